r"""A box moving with constant velocity, with noise that scales with its size.

State ``[cx, cy, w, h, vcx, vcy, vw, vh]`` (centre, size and their rates, derivative-major like
the kinematic models); measurement ``[cx, cy, w, h]``. A pedestrian 400 pixels tall moves and is
mis-detected by more pixels than one 40 pixels tall, so every standard deviation is a fraction
of the box's width (x, w) or height (y, h), as in the Kalman filters of DeepSORT, ByteTrack and
BoT-SORT (``σ_p = 1/20`` of the size per frame for position, as theirs, and ``σ_v = 1/320`` for
velocity, half theirs, at 30 frames/s: with the noise following the frame rate as below, theirs
tracked the 7-14 frames/s sequences worse, see docs/mot.md). Over a gap of ``dt`` frames ``F``
integrates the velocity for ``dt`` and the process noise variances grow by ``dt``.

Those per-frame values describe one physical motion at one frame rate. The noise is a random
walk of the position and of the velocity in time, so at ``r`` times fewer frames a second each
frame's position variance is ``r`` times larger and, the velocity being per frame, its variance
``r³`` times larger; the initial uncertainty of a new track's position (in pixels) stays, and
its velocity's (in pixels per frame) grows by ``r``. :meth:`BoxMotion.at_rate` gives the model
at another frame rate; :class:`~vistrack.tracking.BoxTracker` uses the one at its own.

A detector's box size is noisier than its centre, and its width noisiest: a person's arms and
legs swing in and out of the box, while head and feet fix its height. Against the ground
truth of MOT15 and MOT17 (robust standard deviations, each sequence's bias taken off), the
detected width errs by 0.18 and 0.038 of the width, the centre's x by 0.10 and 0.022 of the
width; the height by 0.087 and 0.025 of the height, the centre's y by 0.039 and 0.014 of the
height. So by default a detection's width has a standard deviation of ``1/10`` of it and its
height ``1/14`` of it, against ``1/20`` for the centre, and the filter follows the jumps of a
detection's size less. (On MOT15 the centre's x errs by more than ``1/20`` too, but a larger
value there, or for the height, tracked worse; see docs/mot.md.)
"""

from __future__ import annotations

import numpy as np

from .._jit import njit
from .._prebuilt import kernel
from .._validate import as_finite, as_number

__all__ = ["BoxMotion", "FRAME_RATES"]

FRAME_RATES = (1e-3, 1e6)
"""The frame rates (frames a second) a motion model is scaled to, and is given at: one frame
in 1,000 s to a million a second. The noise scales with powers of the rate (up to 1.5), so
rates far outside overflow it, or make it 0."""

MAX_SECONDS = 1e9
"""The longest duration a tracker's setting takes (about 32 years): counted in frames at
the highest frame rate (:data:`FRAME_RATES`) it is still a whole number a frame counter
holds (1e308 s overflowed)."""


@kernel
@njit(cache=True)
def _size_scaled(boxes, std, dt):
    """Variances of noise scaled by the size of boxes ``[cx, cy, w, h] (K, 4)``: ``(K, n)``,
    ``(std[c] * s) ** 2 * dt`` for each entry ``c`` of ``std (n,)``, ``s`` the box's width
    (even ``c``) or height (odd ``c``), at least 1e-3. Compiled, as the trackers ask for the
    noise of every track at every frame (numpy's dozen small operations took longer than the
    filter's steps); the same numbers as numpy's ``(std * s) ** 2 * dt``."""
    out = np.empty((boxes.shape[0], std.shape[0]))
    for i in range(boxes.shape[0]):
        for c in range(std.shape[0]):
            s = boxes[i, 2 + c % 2]
            if s < 1e-3:  # (NaN stays NaN)
                s = 1e-3
            v = std[c] * s
            out[i, c] = v * v * dt
    return out


def _box_rows(boxes: np.ndarray) -> np.ndarray:
    """``boxes`` as a C-contiguous float64 ``(K, 4)`` array, checked: the compiled kernel
    reads each row's 4 values unchecked (a (K, 3) array was read past its end, a (4,) one
    failed in numba's typing)."""
    b = np.ascontiguousarray(boxes, dtype=np.float64)
    if b.ndim != 2 or b.shape[1] != 4:
        raise ValueError(f"boxes must have shape (K, 4), rows cx, cy, w, h; got {b.shape}")
    return b


def _frame_rate(value: float) -> float:
    """``value`` as a frame rate within :data:`FRAME_RATES`, or an error naming
    ``frame_rate`` (a string failed in numpy's isfinite, naming nothing)."""
    rate = as_number(value, "frame_rate")
    if not (np.isfinite(rate) and FRAME_RATES[0] <= rate <= FRAME_RATES[1]):
        raise ValueError(f"frame_rate must be a number from {FRAME_RATES[0]:g} to "
                         f"{FRAME_RATES[1]:g} frames/s; got {rate:g}")
    return rate


class BoxMotion:
    r"""Constant velocity of box centre and size with size-scaled noise.

    With :math:`s = (w, h, w, h)` the size of a box ``[cx, cy, w, h]`` (each entry at least
    ``1e-3``), over ``dt`` frames

    .. math::

        F = \begin{pmatrix} I_4 & \Delta t\, I_4 \\ 0 & I_4 \end{pmatrix}, \quad
        Q = \Delta t \operatorname{diag}\big((\sigma_p s)^2, (\sigma_v s)^2\big), \quad
        R = \operatorname{diag}\big((\sigma_m \odot s)^2\big),

    with :math:`\sigma_p` = ``std_pos``, :math:`\sigma_v` = ``std_vel``, :math:`\sigma_m` =
    ``std_meas`` and the squares taken entry by entry; a new track starts at the detected box
    with zero velocity and standard deviations ``init_pos σ_p s`` and ``init_vel σ_v s``.

    Parameters
    ----------
    std_pos, std_vel : float
        Per-frame standard deviations of position and velocity noise, as fractions of the box
        size.
    std_meas : float or sequence of 4 floats
        Standard deviations of a detection's ``cx, cy, w, h`` as fractions of its width (x, w)
        or height (y, h); one number for all four, or one each (default
        ``(1/20, 1/20, 1/10, 1/14)``, see the module).
    init_pos, init_vel : float
        Multipliers of ``std_pos`` and ``std_vel`` for a new track's covariance (its velocity
        is unknown: ``20 × 1/320``, a sixteenth of its size a frame at 30 frames/s).
    frame_rate : float
        The frames per second at which the per-frame ``std_pos``, ``std_vel``, ``init_pos`` and
        ``init_vel`` hold (see the module).

    Attributes
    ----------
    ndim_state, ndim_meas : int
        Sizes of the state and of a measurement: 8 and 4.
    std_meas : (4,) ndarray
        The measurement standard deviations, one per component.

    Raises
    ------
    ValueError
        If a value is not a finite number > 0, or ``std_meas`` is neither one number nor four.

    References
    ----------
    .. [1] N. Wojke, A. Bewley and D. Paulus, "Simple online and realtime tracking with a deep
       association metric" (DeepSORT), ICIP 2017.
    .. [2] Y. Zhang et al., "ByteTrack: multi-object tracking by associating every detection
       box", ECCV 2022.
    .. [3] N. Aharon, R. Orfaig and B.-Z. Bobrovsky, "BoT-SORT: robust associations
       multi-pedestrian tracking", arXiv:2206.14651, 2022.

    Examples
    --------
    >>> m = BoxMotion()
    >>> float(m.F(2.0)[0, 4])
    2.0
    >>> m.R(np.array([[0, 0, 20.0, 28.0]]))[0].diagonal().round(2).tolist()  # cx, cy, w, h
    [1.0, 1.96, 4.0, 4.0]
    >>> slow = m.at_rate(10.0)  # a third of the frames: each frame's velocity noise 3**1.5 larger
    >>> round(slow.std_vel / m.std_vel, 3), round(slow.std_pos / m.std_pos, 3)
    (5.196, 1.732)
    """

    ndim_state, ndim_meas = 8, 4

    def __init__(self, std_pos: float = 1 / 20, std_vel: float = 1 / 320,
                 std_meas: float | tuple[float, float, float, float] = (1 / 20, 1 / 20, 1 / 10,
                                                                        1 / 14),
                 init_pos: float = 2.0, init_vel: float = 20.0, frame_rate: float = 30.0):
        given = np.asarray(std_meas, dtype=object)
        if given.shape not in ((), (4,)):
            raise ValueError(f"std_meas must be one number or 4 (cx, cy, w, h); got {std_meas!r}")
        for name, v in (("std_pos", std_pos), ("std_vel", std_vel), ("init_pos", init_pos),
                        ("init_vel", init_vel), ("frame_rate", frame_rate),
                        *(("std_meas", m) for m in given.ravel())):
            # (True was taken as 1, in std_meas too; "a" failed in float(), naming nothing)
            as_finite(v, name, 0.0, above=True)
        # the rate its values are per frame at: scaled to another (at_rate) from 1e300 they
        # overflowed, from 1e-300 they were 0 ("std_vel must be ... got 0.0")
        _frame_rate(frame_rate)
        meas = given.astype(float)
        self.std_pos, self.std_vel = std_pos, std_vel
        self._std_q = np.repeat(np.array([std_pos, std_vel], dtype=float), 4)
        self.std_meas = np.broadcast_to(meas, (4,)).copy()
        self.init_pos, self.init_vel = init_pos, init_vel
        self.frame_rate = float(frame_rate)

    def _key(self) -> tuple:
        return (type(self), self.std_pos, self.std_vel, tuple(self.std_meas.tolist()),
                self.init_pos, self.init_vel, self.frame_rate)

    def __eq__(self, other: object) -> bool:
        """Equal when of the same class with the same parameters (a configuration read back
        from its TOML equals the one written)."""
        return isinstance(other, BoxMotion) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(std_pos={self.std_pos!r}, std_vel={self.std_vel!r}, "
                f"std_meas={tuple(self.std_meas.tolist())!r}, init_pos={self.init_pos!r}, "
                f"init_vel={self.init_vel!r}, frame_rate={self.frame_rate!r})")

    def at_rate(self, frame_rate: float) -> BoxMotion:
        """The same motion with its per-frame noise at another frame rate (see the module).

        With ``r = self.frame_rate / frame_rate`` (frames ``r`` times further apart),
        ``std_pos`` scales by ``r^(1/2)``, ``std_vel`` by ``r^(3/2)``, ``init_pos`` and
        ``init_vel`` by ``r^(-1/2)`` (so a new track's position uncertainty stays and its
        velocity's grows by ``r``); ``std_meas`` is unchanged.

        Parameters
        ----------
        frame_rate : float
            Frames per second, finite and > 0.

        Returns
        -------
        BoxMotion
            The model at ``frame_rate``; ``self`` when that is its rate already.

        Raises
        ------
        ValueError
            If ``frame_rate`` is not a number in :data:`FRAME_RATES` (0.001 to 10^6).
        TypeError
            If it is no number (a string).

        Examples
        --------
        >>> m = BoxMotion()
        >>> m.at_rate(30.0) is m, m.at_rate(15.0).frame_rate
        (True, 15.0)
        """
        frame_rate = _frame_rate(frame_rate)
        if frame_rate == self.frame_rate:
            return self
        r = self.frame_rate / float(frame_rate)
        return type(self)(std_pos=self.std_pos * r ** 0.5, std_vel=self.std_vel * r ** 1.5,
                          std_meas=tuple(self.std_meas), init_pos=self.init_pos * r ** -0.5,
                          init_vel=self.init_vel * r ** -0.5, frame_rate=frame_rate)

    def F(self, dt: float = 1.0) -> np.ndarray:
        """The constant-velocity transition of the 4 box values, ``[[I, dt I], [0, I]]``.

        Parameters
        ----------
        dt : float
            Time step, in frames.

        Returns
        -------
        (8, 8) ndarray
            ``F(dt)``.

        Examples
        --------
        >>> BoxMotion().F(3.0)[:4, 4:].diagonal().tolist()
        [3.0, 3.0, 3.0, 3.0]
        """
        # (backwards too: the box filter predicts back; NaN and infinity gave such a matrix)
        dt = as_finite(dt, "dt", what="number of frames")
        return np.kron(np.array([[1.0, dt], [0.0, 1.0]]), np.eye(4))

    @staticmethod
    def _scale(boxes: np.ndarray) -> np.ndarray:
        # (K, 4): w, h, w, h of each box (centre x and width scale with w, y and h with h)
        wh = np.maximum(np.asarray(boxes, dtype=float)[:, 2:4], 1e-3)
        return np.concatenate([wh, wh], axis=1)

    def Q_diag(self, boxes: np.ndarray, dt: float = 1.0) -> np.ndarray:
        """The diagonal of the process noise of boxes over ``dt`` (the covariance is diagonal).

        Parameters
        ----------
        boxes : (K, 4) array_like
            Boxes ``[cx, cy, w, h]`` whose sizes scale the noise.
        dt : float
            Time step, in frames (finite, >= 0); the variances are proportional to it.

        Returns
        -------
        (K, 8) ndarray
            ``dt (σ_p s)², dt (σ_v s)²`` per box, ``s = (w, h, w, h)``.

        Examples
        --------
        >>> BoxMotion().Q_diag(np.array([[100, 50, 20.0, 40.0]]))[0, :4].round(4).tolist()
        [1.0, 4.0, 1.0, 4.0]
        """
        # variances proportional to it: -1 gave negative ones; True was taken as 1, and
        # "x" or an array failed in float(), naming nothing
        dt = as_finite(dt, "dt", 0.0, what="number of frames")
        return _size_scaled(_box_rows(boxes), self._std_q, dt)

    def Q(self, boxes: np.ndarray, dt: float = 1.0) -> np.ndarray:
        """Process noise of boxes over ``dt``: :meth:`Q_diag` as diagonal matrices.

        Parameters
        ----------
        boxes : (K, 4) array_like
            Boxes ``[cx, cy, w, h]`` whose sizes scale the noise.
        dt : float
            Time step, in frames.

        Returns
        -------
        (K, 8, 8) ndarray
            Diagonal covariances.

        Examples
        --------
        >>> BoxMotion().Q(np.array([[100, 50, 20.0, 40.0]]), dt=2.0).shape
        (1, 8, 8)
        """
        return self.Q_diag(boxes, dt)[:, :, None] * np.eye(8)

    def R_diag(self, boxes: np.ndarray) -> np.ndarray:
        """The diagonal of the measurement noise of boxes (the covariance is diagonal).

        Parameters
        ----------
        boxes : (K, 4) array_like
            Boxes ``[cx, cy, w, h]`` (detected or predicted) whose sizes scale the noise.

        Returns
        -------
        (K, 4) ndarray
            ``(std_meas s)²`` per box, ``s = (w, h, w, h)``.

        Examples
        --------
        >>> BoxMotion().R_diag(np.array([[100, 50, 20.0, 40.0]])).round(2).tolist()
        [[1.0, 4.0, 4.0, 8.16]]
        """
        return _size_scaled(_box_rows(boxes), self.std_meas, 1.0)

    def R(self, boxes: np.ndarray) -> np.ndarray:
        """Measurement noise of boxes: :meth:`R_diag` as diagonal matrices.

        Parameters
        ----------
        boxes : (K, 4) array_like
            Boxes ``[cx, cy, w, h]`` whose sizes scale the noise.

        Returns
        -------
        (K, 4, 4) ndarray
            Diagonal covariances.

        Examples
        --------
        >>> BoxMotion().R(np.array([[0, 0, 20.0, 28.0]]))[0].diagonal().round(2).tolist()
        [1.0, 1.96, 4.0, 4.0]
        """
        return self.R_diag(boxes)[:, :, None] * np.eye(4)

    def initial(self, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The Gaussian of new tracks started at detected boxes.

        Parameters
        ----------
        boxes : (K, 4) array_like
            Detected boxes ``[cx, cy, w, h]``.

        Returns
        -------
        mean : (K, 8) ndarray
            The boxes, with zero velocity.
        cov : (K, 8, 8) ndarray
            Diagonal, with standard deviations ``init_pos σ_p s`` and ``init_vel σ_v s``,
            ``s = (w, h, w, h)``.

        Examples
        --------
        >>> mean, cov = BoxMotion().initial(np.array([[100, 50, 20.0, 40.0]]))
        >>> mean[0, 4:].tolist(), np.sqrt(cov[0].diagonal()).round(3).tolist()
        ([0.0, 0.0, 0.0, 0.0], [2.0, 4.0, 2.0, 4.0, 1.25, 2.5, 1.25, 2.5])
        """
        b = _box_rows(boxes)
        s = self._scale(b)
        d = np.concatenate([(self.init_pos * self.std_pos * s) ** 2,
                            (self.init_vel * self.std_vel * s) ** 2], axis=1)
        return np.concatenate([b, np.zeros_like(b)], axis=1), d[:, :, None] * np.eye(8)

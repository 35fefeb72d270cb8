r"""Robust online appearance models: the WSL mixture of Jepson, Fleet and El-Maraghi (CVPR 2001;
seed 000, "Jepson, Fleet, and El-Maraghi tracker"), and a region tracker that uses it as its
likelihood.

Each pixel ``x`` of the target's normalised view holds a mixture of three components for its
observation ``d_t(x)``:

- **S**, stable: a Gaussian ``N(d; μ_s, σ_s²)`` whose moments are learnt slowly;
- **W**, wandering: ``N(d; d_{t-1}, σ_w²)``, a two-frame model (the last observation);
- **L**, lost: a uniform density over the data's range (outliers, occluders).

With mixing probabilities ``m = (m_s, m_w, m_l)`` per pixel, the **ownership** of the
observation by component ``i`` is ``o_i = m_i p_i(d_t) / Σ_j m_j p_j(d_t)``. Online EM with a
forgetting factor ``α = 1 - exp(-1/τ)`` then updates, per pixel,

    m_i ← α o_i + (1 - α) m_i,
    M_j ← α o_s d_t^j + (1 - α) M_j  (j = 1, 2),   μ_s = M_1 / m_s,  σ_s² = M_2 / m_s - μ_s²,

so an occluded pixel's data is owned by L (or W) and leaves the stable mean where it was. The
data here are the grey intensities of the normalised view, in ``[0, 1]`` after a light blur;
the paper uses steerable-pyramid phase, which is also robust to lighting: intensity is what
the seeds' SSD trackers compare, and makes the figures readable.

:class:`WSLTracker` moves a box over the image to the translation and scale whose normalised
view is most probable under the mixture (an exhaustive search on the view's pixel grid around
a constant-velocity prediction), then updates the mixture there.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .._validate import as_box, as_finite, as_number, as_scales, as_uint8_image, as_whole
from .base import _HALF, SingleObjectTracker

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["WSLModel", "WSLTracker"]

_LOG_2PI = float(np.log(2 * np.pi))


class WSLModel:
    """The per-pixel stable / wandering / lost mixture, learnt by online EM (see the module).

    Parameters
    ----------
    shape : tuple of int
        Shape of the data (the normalised view, or ``(n,)`` for ``n`` independent signals).
    tau : float
        Time constant of the online EM, in frames: ``α = 1 - exp(-1/τ)``.
    sigma_w : float
        Standard deviation of the wandering component around the last observation.
    sigma_s0, sigma_min : float
        Initial and smallest standard deviation of the stable component (``sigma_s0``
        default: 0.05, or ``sigma_min`` where that is higher).
    m0 : three floats
        Initial mixing probabilities of S, W and L.
    lost_density : float
        The lost component's uniform density (1 for data in ``[0, 1]``).

    Attributes
    ----------
    alpha : float
        The online EM's forgetting factor ``1 - exp(-1/τ)``.
    m : (3, \\*shape) ndarray
        Mixing probabilities of S, W and L per pixel (after :meth:`init`).
    mu_s, var_s : (\\*shape) ndarray
        Mean and variance of the stable component.
    prev : (\\*shape) ndarray
        The last observation, the wandering component's mean.

    Raises
    ------
    ValueError
        If ``shape`` is empty or not positive integers, a scale or ``tau`` is not a finite
        positive number, ``sigma_s0`` is below ``sigma_min``, or ``m0`` is not three finite
        positive numbers.

    References
    ----------
    .. [1] A. D. Jepson, D. J. Fleet and T. F. El-Maraghi, "Robust online appearance models
       for visual tracking", *IEEE Conference on Computer Vision and Pattern Recognition*,
       2001.

    Examples
    --------
    >>> model = WSLModel((1,))
    >>> model.init(np.array([0.5]))
    >>> for _ in range(50):
    ...     _ = model.update(np.array([0.5]))
    >>> float(model.mu_s[0]), bool(model.m[0, 0] > 0.8)
    (0.5, True)
    """

    def __init__(self, shape: tuple[int, ...], *, tau: float = 20.0, sigma_w: float = 0.08,
                 sigma_s0: float | None = None, sigma_min: float = 0.02,
                 m0: tuple[float, float, float] = (0.4, 0.15, 0.45), lost_density: float = 1.0):
        dims = np.atleast_1d(shape)
        if dims.ndim != 1 or dims.dtype.kind not in "iuf" or not (
                np.isfinite(dims).all() and (dims == np.round(dims)).all()):
            raise ValueError(f"shape must be a tuple of integers; got {shape!r}")  # 2.5 was 2
        self.shape = tuple(int(s) for s in dims)
        if not self.shape or min(self.shape) < 1:
            raise ValueError(f"shape must be positive; got {shape!r}")
        if sigma_s0 is None:  # 0.05, or the floor where that is higher
            sigma_s0 = max(0.05, as_number(sigma_min, "sigma_min"))
        for name, v in (("tau", tau), ("sigma_w", sigma_w), ("sigma_s0", sigma_s0),
                        ("sigma_min", sigma_min), ("lost_density", lost_density)):
            # (a string failed in numpy's isfinite, naming nothing)
            if not np.isfinite(as_number(v, name)) or v <= 0:
                raise ValueError(f"{name} must be positive; got {v!r}")
        if sigma_s0 < sigma_min:  # (the stable component started below its own floor)
            raise ValueError(f"sigma_s0 must be at least sigma_min, the stable component's "
                             f"smallest standard deviation; got {sigma_s0!r} below {sigma_min!r}")
        try:  # ("a", 1, 1) was numpy's "could not convert string to float: 'a'"
            m0_arr = np.asarray(m0, dtype=float)
            got = m0_arr.tolist()
        except (TypeError, ValueError):
            m0_arr, got = np.full(1, np.nan), m0
        if m0_arr.shape != (3,) or not (np.isfinite(m0_arr).all() and (m0_arr > 0).all()):
            raise ValueError("m0 must be three finite positive mixing probabilities; got "
                             f"{got!r}")  # NaN and inf gave NaN mixtures
        self.alpha = 1.0 - float(np.exp(-1.0 / tau))
        if self.alpha >= 1.0:
            # (the model kept no memory: a pixel the stable component did not own at all
            # took its moments to 0 / 0, NaN for good, and the tracker's score to -inf)
            raise ValueError(f"tau must be long enough for the model to remember a frame, "
                             f"1 - exp(-1 / tau) < 1 (tau above about 0.027); got {tau!r}")
        self.sigma_w, self.sigma_s0 = float(sigma_w), float(sigma_s0)
        self.sigma_min = float(sigma_min)
        self.m0, self.log_lost = m0_arr / m0_arr.sum(), float(np.log(lost_density))
        self.ready = False

    def _data(self, d: ArrayLike, name: str = "data") -> np.ndarray:
        d = np.asarray(d, dtype=float)
        if d.shape[-len(self.shape):] != self.shape:
            raise ValueError(f"{name} must end in shape {self.shape}; got {d.shape}")
        if not np.isfinite(d).all():  # one NaN made its pixel NaN for good
            i = tuple(int(v) for v in np.argwhere(~np.isfinite(d))[0])
            raise ValueError(f"{name} must be finite; {name}[{', '.join(map(str, i))}] is "
                             f"{float(d[i])}")
        return d

    def init(self, d: ArrayLike) -> None:
        """Start the model on a first observation: ``μ_s = d``, ``σ_s = sigma_s0``.

        The mixing probabilities start at ``m0`` (normalised) and the wandering component's
        mean at ``d``.

        Parameters
        ----------
        d : array_like
            One observation, of the model's ``shape``.

        Raises
        ------
        ValueError
            If ``d`` does not have the model's shape.

        Examples
        --------
        >>> model = WSLModel((2,), m0=(2.0, 1.0, 1.0))
        >>> model.init([0.2, 0.8])
        >>> model.mu_s.tolist(), model.m[:, 0].tolist()
        ([0.2, 0.8], [0.5, 0.25, 0.25])
        """
        d = self._data(d)
        if d.shape != self.shape:
            raise ValueError(f"init takes one observation of shape {self.shape}; got {d.shape}")
        self.m = np.broadcast_to(self.m0[:, None], (3, d.size)).reshape((3,) + self.shape).copy()
        self.mu_s = d.copy()
        self.var_s = np.full(self.shape, self.sigma_s0 ** 2)
        self.M1 = self.m[0] * self.mu_s
        self.M2 = self.m[0] * (self.var_s + self.mu_s ** 2)
        self.prev = d.copy()
        self.ready = True

    def _log_terms(self, d: np.ndarray) -> np.ndarray:
        # log m_i p_i(d), stacked on a new first axis: (3,) + d.shape
        if not self.ready:
            raise RuntimeError("call init(d) before using the model")
        ls = (np.log(self.m[0]) - 0.5 * (_LOG_2PI + np.log(self.var_s))
              - 0.5 * (d - self.mu_s) ** 2 / self.var_s)
        lw = (np.log(self.m[1]) - 0.5 * _LOG_2PI - np.log(self.sigma_w)
              - 0.5 * (d - self.prev) ** 2 / self.sigma_w ** 2)
        ll = np.broadcast_to(np.log(self.m[2]) + self.log_lost, d.shape)
        return np.stack(np.broadcast_arrays(ls, lw, ll))

    def log_likelihood(self, d: ArrayLike) -> np.ndarray:
        """``Σ_x log Σ_i m_i p_i(d(x))`` for each observation in a batch ``(..., *shape)``.

        Parameters
        ----------
        d : (..., \\*shape) array_like
            Observations; the leading dimensions index the batch.

        Returns
        -------
        (...) ndarray
            The log-likelihood of each observation, summed over its pixels.

        Raises
        ------
        ValueError
            If ``d`` does not end in the model's shape.
        RuntimeError
            Before :meth:`init`.

        Examples
        --------
        The observation the model was started on is more likely than one far from it:

        >>> model = WSLModel((2,))
        >>> model.init([0.5, 0.5])
        >>> model.log_likelihood([[0.5, 0.5], [0.5, 0.95]]).round(3)
        array([2.958, 0.681])
        """
        d = self._data(d)
        t = self._log_terms(d)
        top = t.max(axis=0)
        per_pixel = top + np.log(np.exp(t - top).sum(axis=0))
        return per_pixel.reshape(d.shape[:d.ndim - len(self.shape)] + (-1,)).sum(-1)

    def ownership(self, d: ArrayLike) -> np.ndarray:
        """``(3, *shape)``: the ownership probabilities ``o_s, o_w, o_l`` of one observation.

        Parameters
        ----------
        d : (\\*shape) array_like
            One observation.

        Returns
        -------
        (3, \\*shape) ndarray
            ``o_i = m_i p_i(d) / Σ_j m_j p_j(d)`` per pixel; they sum to 1 over the first axis.

        Raises
        ------
        ValueError
            If ``d`` does not end in the model's shape.
        RuntimeError
            Before :meth:`init`.

        Examples
        --------
        A pixel far from its stable mean and from its last value is owned by the lost
        component:

        >>> model = WSLModel((2,))
        >>> model.init([0.5, 0.5])
        >>> model.ownership([0.5, 0.95]).round(2)
        array([[0.73, 0.  ],
               [0.17, 0.  ],
               [0.1 , 1.  ]])
        """
        d = self._data(d)
        t = self._log_terms(d)
        t = np.exp(t - t.max(axis=0))
        return t / t.sum(axis=0)

    def update(self, d: ArrayLike) -> np.ndarray:
        """One step of online EM on observation ``d``; returns its ownerships ``(3, *shape)``.

        The mixing probabilities and the stable component's moments move towards the
        observation by ``alpha``, weighted by the ownerships (see the module); ``σ_s`` is
        floored at ``sigma_min``, and ``d`` becomes the wandering component's mean. A mixing
        probability is floored at ``1e-12`` (``log m`` stays finite); where ``m_s`` is, the
        moments ``M_1``, ``M_2`` are scaled with it, so that a pixel occluded by something
        steady keeps ``μ_s`` and ``σ_s`` for any time and recovers its stable component when
        the target is back. An occluder that flickers is another matter: once ``m_s`` is at
        its floor, a value that happens to fall near ``μ_s`` weighs as much as all the
        stable component's past, and moves it. Over a pixel at 0.5 ± 0.01 occluded by
        uniform noise (the lost component's own model), ``μ_s`` moved by more than 3 ``σ_s``
        in none of 20 draws after 200 frames (``tau`` 20), in 10 after 1,000 and 13 after
        5,000, and ``m_s`` was not back above 0.5 within 1,000 frames in 0, 3 and 9.

        Parameters
        ----------
        d : (\\*shape) array_like
            One observation.

        Returns
        -------
        (3, \\*shape) ndarray
            The ownerships of ``d`` before the update (:meth:`ownership`).

        Raises
        ------
        ValueError
            If ``d`` does not have the model's shape.
        RuntimeError
            Before :meth:`init`.

        Examples
        --------
        An outlier owned by the lost component leaves the stable mean where it was:

        >>> model = WSLModel((2,))
        >>> model.init([0.5, 0.5])
        >>> o = model.update([0.5, 0.95])
        >>> model.mu_s.tolist(), model.m[2].round(3).tolist()
        ([0.5, 0.5], [0.433, 0.477])
        """
        d = self._data(d)
        if d.shape != self.shape:
            raise ValueError(f"update takes one observation of shape {self.shape}; got {d.shape}")
        o = self.ownership(d)
        a = self.alpha
        m = a * o + (1 - a) * self.m
        self.m = np.maximum(m, 1e-12)   # keeps log m finite
        self.m /= self.m.sum(axis=0)
        self.M1 = a * o[0] * d + (1 - a) * self.M1
        self.M2 = a * o[0] * d ** 2 + (1 - a) * self.M2
        floored = m[0] < 1e-12
        if floored.any():
            # the moments follow m_s up to its floor (m_s > 0: (1 - a) times the last one):
            # they decayed on alone, and after a long occlusion μ_s = M1 / m_s fell to 0 and
            # m_s never recovered
            scale = np.where(floored, self.m[0] / m[0], 1.0)
            self.M1 = self.M1 * scale
            self.M2 = self.M2 * scale
        self.mu_s = self.M1 / self.m[0]
        self.var_s = np.maximum(self.M2 / self.m[0] - self.mu_s ** 2, self.sigma_min ** 2)
        self.prev = d.copy()
        return o


def _view_size(w: float, h: float, size: int) -> tuple[int, int, float]:
    """The view's pixels across and down for a box ``w × h``, ``size`` on its long side and
    at least 4 on each, and how many times a view pixel's width its height spans of the
    image: 1 (square pixels) unless a side was raised to 4, for a box longer than
    ``size / 4`` to 1 (one scale on both axes viewed a 3 × 100 box's central 24 rows alone)."""
    s = size / max(w, h)
    vw, vh = int(round(w * s)), int(round(h * s))
    if min(vw, vh) >= 4:
        return vw, vh, 1.0
    vw, vh = max(4, vw), max(4, vh)
    return vw, vh, (h / vh) / (w / vw)


class WSLTracker(SingleObjectTracker):
    """A region tracker whose likelihood is the WSL appearance model (see the module).

    Parameters
    ----------
    size : int
        Pixels on the long side of the normalised view.
    radius : int
        Search radius, in view pixels, around the predicted centre (the constant-velocity
        prediction); of equally likely offsets, the one nearest the prediction is taken.
    scales : tuple of float
        Relative scales tried each frame (of equally likely ones, the nearest 1). The
        default keeps the first box's size: with ``(0.95, 1, 1.05)`` the box shrinks on OTB
        Crossing (38 % success against 70 % at a fixed size), as the model adapts to the
        inner part of the target.
    blur : float
        Gaussian blur (σ, image pixels) before sampling.
    **model
        Passed to :class:`WSLModel`.

    Attributes
    ----------
    model : WSLModel
        The mixture (after the tracker has started).
    ownership : (3, h, w) ndarray
        The ownerships of the view at the last box.
    score : float
        The log-likelihood of the view at the last box (NaN after :meth:`init`).

    Raises
    ------
    ValueError
        If ``size`` is less than 8 or ``radius`` less than 1.

    Notes
    -----
    After each ``update``, ``ownership`` holds the ownerships ``(3, h, w)`` of the view at
    the new box and ``model`` the mixture.

    References
    ----------
    .. [1] A. D. Jepson, D. J. Fleet and T. F. El-Maraghi, "Robust online appearance models
       for visual tracking", *IEEE Conference on Computer Vision and Pattern Recognition*,
       2001.

    Examples
    --------
    A red square moving 3 pixels a frame:

    >>> def image(x):
    ...     im = np.zeros((60, 80, 3), np.uint8); im[20:40, x:x + 20] = (0, 0, 255)
    ...     return im
    >>> t = WSLTracker()
    >>> t.init(image(30), [30, 20, 20, 20])
    >>> [t.update(image(x)).round().tolist()[0] for x in (33, 36, 39)]
    [33.0, 36.0, 39.0]
    >>> t.ownership.shape
    (3, 32, 32)
    """

    def __init__(self, size: int = 32, radius: int = 8, scales: tuple = (1.0,),
                 blur: float = 1.0, **model: Any):
        self.size, self.radius = as_whole(size, "size", 8), as_whole(radius, "radius", 1)
        self.scales = as_scales(scales)
        self.blur, self.model_args = as_finite(blur, "blur", 0.0), model
        WSLModel((1, 1), **model)  # its settings checked now (they failed at init())

    def _prepare(self, image: np.ndarray) -> np.ndarray:
        import cv2

        g = as_uint8_image(image, grey=True).astype(np.float32) / 255.0
        return cv2.GaussianBlur(g, (0, 0), self.blur) if self.blur > 0 else g

    def _sample(self, g: np.ndarray, cx: float, cy: float, scale: float, out_w: int,
                out_h: int) -> np.ndarray:
        """The image around ``(cx, cy)`` (in a box's coordinates, :data:`~.base._HALF`) at
        ``scale`` image pixels per view pixel, as an ``(out_h, out_w)`` array centred there
        (bilinear, edges replicated). Sampled at the box's centre taken as a pixel index, the
        view of a square filling its box was lopsided (its first column 1.0, its last 0.31)."""
        import cv2

        cx, cy = cx - _HALF, cy - _HALF  # the pixels' indices: pixel k's centre at k
        down = scale * self.aspect  # a view pixel's height in the image
        A = np.array([[scale, 0, cx - scale * (out_w - 1) / 2],
                      [0, down, cy - down * (out_h - 1) / 2]], dtype=np.float64)
        return cv2.warpAffine(g, A, (out_w, out_h), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                              borderMode=cv2.BORDER_REPLICATE).astype(float)

    def _start(self, image: np.ndarray, b: np.ndarray) -> None:
        g = self._prepare(image)
        self.vw, self.vh, self.aspect = _view_size(b[2], b[3], self.size)
        self.w, self.h = float(b[2]), float(b[3])
        self.centre = np.array([b[0] + b[2] / 2, b[1] + b[3] / 2])
        self.velocity = np.zeros(2)
        self.model = WSLModel((self.vh, self.vw), **self.model_args)
        view = self._sample(g, self.centre[0], self.centre[1], self.w / self.vw, self.vw,
                            self.vh)
        self.model.init(view)
        self.ownership = self.model.ownership(view)
        self.box = b.copy()
        self.score = float("nan")

    def _follow(self, image: np.ndarray) -> np.ndarray:
        from numpy.lib.stride_tricks import sliding_window_view

        g = self._prepare(image)
        r = self.radius
        pred = self.centre + self.velocity
        # ties go to the least change: the scale nearest 1 first, and the offsets in order of
        # their distance from the prediction (the first maximum, offset (-r, -r), sent the
        # box up and left across a region without texture, and the velocity on further)
        k = np.arange(-r, r + 1)
        near = np.argsort((k[:, None] ** 2 + k[None, :] ** 2).ravel(), kind="stable")
        best = (-np.inf, 0.0, 0.0, 1.0)
        for s in sorted(self.scales, key=lambda v: max(v, 1 / v) if v > 0 else np.inf):
            step = s * self.w / self.vw
            region = self._sample(g, pred[0], pred[1], step, self.vw + 2 * r,
                                  self.vh + 2 * r)
            windows = sliding_window_view(region, (self.vh, self.vw))
            ll = self.model.log_likelihood(windows)
            i, j = np.unravel_index(near[int(np.argmax(ll.ravel()[near]))], ll.shape)
            if ll[i, j] > best[0]:
                best = (float(ll[i, j]), (j - r) * step, (i - r) * step * self.aspect, s)
        self.score, dx, dy, s = best
        H, W = g.shape
        # within the image's extent, [0, W] x [0, H] (a box half outside may start there):
        # [W - 1, H - 1] moved a still box at the right or bottom edge by a pixel
        centre = np.clip(pred + [dx, dy], 0, [W, H])
        self.velocity = centre - self.centre
        self.centre = centre
        self.w, self.h = self.w * s, self.h * s
        view = self._sample(g, self.centre[0], self.centre[1], self.w / self.vw, self.vw,
                            self.vh)
        self.ownership = self.model.update(view)
        self.box = np.array([self.centre[0] - self.w / 2, self.centre[1] - self.h / 2,
                             self.w, self.h])
        return self.box.copy()

    def anchor(self, box: ArrayLike) -> None:
        """Move the region to ``box`` (the view keeps its pixel size; the velocity is kept).

        Parameters
        ----------
        box : (4,) array_like
            The box ``x, y, w, h``.

        Examples
        --------
        >>> t = WSLTracker()
        >>> t.init(np.zeros((60, 80), np.uint8), [30, 20, 20, 20])
        >>> t.anchor([10, 10, 30, 30])
        >>> t.centre.tolist(), t.box.tolist()
        ([25.0, 25.0], [10.0, 10.0, 30.0, 30.0])
        """
        self._need_start("anchor")
        b = as_box(box)
        self.centre = b[:2] + b[2:] / 2
        reshaped = not np.isclose(b[3] / b[2], self.h / self.w, rtol=1e-9, atol=0.0)
        self.w, self.h = float(b[2]), float(b[3])
        if self.aspect != 1.0 or reshaped:
            # the view spans the new box: a view of a side raised to 4, or of square pixels
            # anchored to a box of another shape (its width alone set the scale, and a box
            # twice as tall was seen over its upper half)
            self.aspect = (self.h / self.vh) / (self.w / self.vw)
        self.box = b

r"""Tracker composition: several single-object trackers fused into one estimate (seed 001,
"Tracker composition: color and shape", "Combining trackers ⇒ robustness"; XVision's
composition of primitive trackers).

:class:`Composite` runs its member trackers on each frame, reads each one's box as a
measurement ``z = (cx, cy, log w, log h)`` and fuses them in a Kalman filter whose state is the
centre with its velocity (constant velocity, white acceleration ``q_pos`` px²/frame³) and the
log size (a random walk, ``q_size`` per frame). A member's measurement noise is set by its
``noise``: a standard deviation of the centre as a fraction of the box's size, and one of the
log size. Each frame follows the Hager/Toyama cycle with the prediction shared: every member
is first **anchored** on the composite's predicted box (``anchor(box)`` moves its own state
there), so a member that drifted, or whose window grew over the background, searches from
the composite's estimate; each member's box is then gated, a member whose normalised
innovation squared exceeds the χ² quantile ``p_gate`` (4 degrees of freedom) being rejected
that frame as in the seeds' validation gates; the accepted ones correct the prediction.

A member is anything with ``init(image, box)``, ``update(image) -> box`` and
``anchor(box)``; every tracker in :data:`vistrack.tracking.single.METHODS` except OpenCV's
has ``anchor``. A member that measures the motion from the frame before (``"klt"``'s median
flow, and the one that starts ``"template"``'s search) also has ``anchor_last(box)``, and is
given the composite's estimate of that frame too.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import TYPE_CHECKING, Protocol

import numpy as np

from .._validate import as_finite, is_number
from ..filters import kf_predict, kf_update
from ..models import ConstantVelocity
from ..types import Gaussian
from .base import SingleObjectTracker

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["Composite"]


class _Member(Protocol):
    """What a member of a :class:`Composite` answers: ``init(image, box)``,
    ``update(image) -> box`` and ``anchor(box)``, boxes ``x, y, w, h``."""

    def init(self, image: np.ndarray, box: np.ndarray, /) -> None: ...

    def update(self, image: np.ndarray, /) -> ArrayLike: ...

    def anchor(self, box: np.ndarray, /) -> None: ...

# the first velocity's standard deviation, as a fraction of the box's size a frame
_V0 = 0.5

_H = np.zeros((4, 6))
_H[0, 0] = _H[1, 1] = _H[2, 4] = _H[3, 5] = 1.0


def _measure(box: np.ndarray) -> np.ndarray:
    return np.array([box[0] + box[2] / 2, box[1] + box[3] / 2, np.log(box[2]), np.log(box[3])])


def _box_of(x: np.ndarray) -> np.ndarray:
    w, h = np.exp(x[4]), np.exp(x[5])
    return np.array([x[0] - w / 2, x[1] - h / 2, w, h])


class Composite(SingleObjectTracker):
    """Member trackers fused by a gated Kalman filter (see the module).

    Parameters
    ----------
    members : mapping of name to (tracker, (pos_sd, log_size_sd))
        The trackers and their measurement noise: the centre's standard deviation as a
        fraction of the box's size, and the log size's standard deviation.
    q_pos : float
        White-acceleration density of the centre (px² per frame³, scaled by the box's size
        over 100 px).
    q_size : float
        Random-walk variance of the log size per frame.
    p_gate : float
        Probability of the χ² gate on each member's innovation (4 degrees of freedom).

    Attributes
    ----------
    members : dict of str to tracker
        The member trackers.
    noise : dict of str to (2,) ndarray
        Their ``(pos_sd, log_size_sd)``.
    threshold : float
        The gate: the ``p_gate`` quantile of χ² with 4 degrees of freedom.
    state : Gaussian
        The fused state ``[cx, cy, vx, vy, log w, log h]`` (after the tracker has started).

    Raises
    ------
    ValueError
        If ``members`` is empty, a member's value is not ``(tracker, (pos_sd, log_size_sd))``
        with positive, finite noise, ``q_pos`` or ``q_size`` is negative or not finite, or
        ``p_gate`` is not a number in ``(0, 1)``.
    TypeError
        If ``members`` is not a mapping, or a member lacks ``init``, ``update`` or
        ``anchor``.

    Notes
    -----
    After each ``update``, ``boxes`` holds each member's own box and ``accepted`` whether
    it passed the gate.

    Examples
    --------
    Colour for the centre, a snake's contour for the size (``examples/compose_bag.py``), on
    a red square moving 3 pixels a frame:

    >>> from vistrack.tracking.single import single_tracker
    >>> tracker = Composite({"colour": (single_tracker("meanshift"), (0.1, 1.0)),
    ...                      "shape": (single_tracker("snake"), (0.2, 0.05))})
    >>> def image(x):
    ...     im = np.full((60, 80, 3), (40, 120, 40), np.uint8); im[20:40, x:x + 20] = (0, 0, 255)
    ...     return im
    >>> tracker.init(image(30), [30, 20, 20, 20])
    >>> [tracker.update(image(x)).round().tolist()[0] for x in (33, 36, 39)]
    [32.0, 35.0, 39.0]
    >>> tracker.accepted
    {'colour': True, 'shape': True}
    """

    def __init__(self, members: Mapping[str, tuple[_Member, tuple[float, float]]], *,
                 q_pos: float = 16.0, q_size: float = 1e-3, p_gate: float = 0.999):
        if not isinstance(members, Mapping):  # (a list was "'list' object has no 'items'")
            raise TypeError(f"members must be a mapping of names to (tracker, (pos_sd, "
                            f"log_size_sd)); got {type(members).__name__}")
        if not members:
            raise ValueError("members must name at least one tracker")
        self.members: dict[str, _Member] = {}
        self.noise: dict[str, np.ndarray] = {}
        for name, value in members.items():
            try:
                tracker, (pos_sd, size_sd) = value
            except (TypeError, ValueError):
                raise ValueError(f"members[{name!r}] must be (tracker, (pos_sd, log_size_sd)); "
                                 f"got {value!r}") from None
            for attr in ("init", "update", "anchor"):
                if not callable(getattr(tracker, attr, None)):
                    raise TypeError(f"members[{name!r}] has no {attr}() method")
            if not (is_number(pos_sd) and is_number(size_sd)
                    and 0 < pos_sd < np.inf and 0 < size_sd < np.inf):
                # ("a", 1) was a bare "'<' not supported", (True, 1) taken as 1.0
                raise ValueError(f"members[{name!r}]: noise must be two positive, finite "
                                 f"numbers; got {(pos_sd, size_sd)!r}")
            twin = next((k for k, t in self.members.items() if t is tracker), None)
            if twin is not None:  # (updated twice a frame: a MedianFlow's second saw no motion)
                raise ValueError(f"members[{name!r}] is the tracker of members[{twin!r}]: each "
                                 "member needs a tracker of its own")
            self.members[name] = tracker
            self.noise[name] = np.array([pos_sd, size_sd], float)
        # (a string or None was a bare "'<' not supported", an array numpy's "ambiguous")
        if not (is_number(p_gate) and 0 < p_gate < 1):
            raise ValueError(f"p_gate must be a probability in (0, 1); got {p_gate!r}")
        from scipy.stats import chi2

        # named here: a negative or NaN one failed at the first update, naming q or Q
        self.q_pos = as_finite(q_pos, "q_pos", 0.0)
        self.q_size = as_finite(q_size, "q_size", 0.0)
        self.threshold = float(chi2.ppf(p_gate, 4))

    def _start(self, image: np.ndarray, b: np.ndarray) -> None:
        # all members or none: one refusing the frame left those before it started on it
        # (a template cut from the refused frame) while the composite kept its old state
        saved = {name: copy.deepcopy(t.__dict__) for name, t in self.members.items()}
        try:
            for tracker in self.members.values():
                tracker.init(image, b)
        except BaseException:
            for name, t in self.members.items():
                t.__dict__.clear()
                t.__dict__.update(saved[name])
            raise
        z = _measure(b)
        mean = np.r_[z[:2], 0.0, 0.0, z[2:]]
        cov = np.diag([1.0, 1.0, (_V0 * b[2]) ** 2, (_V0 * b[3]) ** 2, 1e-4, 1e-4])
        self.state = Gaussian(mean, cov)
        self.box = b.copy()
        self.boxes = {name: b.copy() for name in self.members}
        self.accepted = {name: True for name in self.members}

    def _motion(self) -> tuple[np.ndarray, np.ndarray]:
        # the centre: the models' constant velocity over one frame; the log size: a random walk
        cv = ConstantVelocity(dim=2, q=self.q_pos * max(self.box[2], self.box[3]) / 100.0)
        F, Q = np.eye(6), np.zeros((6, 6))
        F[:4, :4], Q[:4, :4] = cv.F(1.0), cv.Q(1.0)
        Q[4, 4] = Q[5, 5] = self.q_size
        return F, Q

    def _follow(self, image: np.ndarray) -> np.ndarray:
        g = kf_predict(self.state, *self._motion())
        size = np.exp(g.mean[4:])
        predicted = _box_of(g.mean)
        for tracker in self.members.values():
            tracker.anchor(predicted)
            # a member that measures motion from the frame before (median flow) starts from
            # the estimate of that frame: anchored on the prediction alone, it added the
            # frame's motion twice and ran ahead of the target
            anchor_last = getattr(tracker, "anchor_last", None)
            if callable(anchor_last):
                anchor_last(self.box)
        # every member is gated against the prediction, then the accepted ones correct it
        accepted = []
        for name, tracker in self.members.items():
            box = np.asarray(tracker.update(image), float)
            if box.shape != (4,):
                # a member's programming error, not a failure: a (1, 4) box was rejected on
                # every frame, and the composite followed its own prediction without a word
                raise ValueError(f"members[{name!r}].update returned shape {box.shape}; "
                                 "expected one box x, y, w, h, (4,)")
            self.boxes[name] = box
            ok = bool(np.isfinite(box).all() and box[2] > 0 and box[3] > 0)
            if ok:
                pos_sd, size_sd = self.noise[name]
                R = np.diag([(pos_sd * size[0]) ** 2, (pos_sd * size[1]) ** 2,
                             size_sd ** 2, size_sd ** 2])
                z = _measure(box)
                v = z - _H @ g.mean
                ok = float(v @ np.linalg.solve(_H @ g.cov @ _H.T + R, v)) <= self.threshold
                if ok:
                    accepted.append((z, R))
            self.accepted[name] = ok
        for z, R in accepted:
            g = kf_update(g, z, _H, R)
        self.state = g
        self.box = _box_of(g.mean)
        return self.box.copy()

r"""Snakes: a closed B-spline contour tracked by radial edge search and a Kalman filter over its
control points (seed 001, "Snakes: basic approach"; Blake and Isard's active contours).

The contour is a periodic uniform cubic B-spline, ``r(s) = U(s) Q`` with ``n`` control points
``Q``; it is sampled at ``m`` points ``r_k = B_k Q`` with unit normals ``ν_k``. Each frame:

1. **predict** the contour's shape (a random walk: it keeps its value, its covariance grows
   by ``q`` per frame and parameter, scaled as the parameter moves the control points);
2. **search radially for edges**: along each normal, within ``±search`` pixels of the
   predicted contour, the strongest change of intensity along the normal (above
   ``min_edge``) is the measured edge point ``p_k``;
3. **solve a least-squares problem for the new state**, as a Kalman update: each found edge
   measures the contour's position along its normal, ``ν_kᵀ B_k Q = ν_kᵀ p_k`` with variance
   ``r`` (:func:`vistrack.filters.kf_update`, all measurements at once). With a flat prior this
   is exactly the least-squares fit of the seeds' slide; the prior keeps the contour where no
   edge is seen.

The state lives in a **shape space** (Blake and Isard, ch. 4): the control points are
``Q = Q₀ + W X``, a template ``Q₀`` (the contour :meth:`Snake.init` was given) moved by a few
parameters ``X``. ``shape="affine"`` (the default) allows the template's translations and
linear maps (6 parameters), ``"euclidean"`` translation, rotation and uniform scale (4), and
``"free"`` every control point on its own (``2n``). An edge measures the contour only along its
normal, so free control points may slide along the contour without any measurement seeing it;
over frames they bunch, the contour folds, and a moving object's contour grows (a square moving
(3, 2) pixels a frame: 11 to 34 pixels too tall after 20 frames, by where it starts, and 165
off after 60). In a shape space the contour keeps the template's form, and 100 edges fix 6
parameters rather than 40. A template needs an area: points on one line cannot become a
contour by a linear map.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .._jit import njit
from .._prebuilt import kernel
from .._validate import (
    as_box,
    as_finite,
    as_flag,
    as_float_array,
    as_uint8_image,
    as_whole,
    is_whole,
)
from ..filters import kf_predict, kf_update
from ..types import Gaussian
from .base import _HALF, SingleObjectTracker, _index_centre

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["Snake", "SnakeTracker", "bspline_matrix"]

_SHAPES = ("affine", "euclidean", "free")


def bspline_matrix(n: int, m: int, derivative: bool = False) -> np.ndarray:
    """``(m, n)``: the periodic uniform cubic B-spline basis at ``m`` equally spaced parameters
    (row ``k`` gives ``r(s_k) = Σ_j B[k, j] Q_j``), or its derivative along ``s``.

    Parameters
    ----------
    n : int
        Control points, at least 4.
    m : int
        Samples, at least 1, at ``s_k = k n / m`` (the parameter runs over ``[0, n)``).
    derivative : bool
        The derivative ``dr/ds`` instead.

    Returns
    -------
    (m, n) ndarray
        The basis: each row has the four weights of the control points around its
        parameter (they sum to 1, and to 0 for the derivative).

    Raises
    ------
    ValueError
        If ``n < 4`` or ``m < 1``, or either is not a whole number.

    Examples
    --------
    >>> B = bspline_matrix(6, 12)
    >>> bool(np.allclose(B.sum(1), 1.0)), bool(np.allclose(bspline_matrix(6, 12, True).sum(1), 0))
    (True, True)
    """
    # (4.5 control points was a bare TypeError in numpy, NaN a cast warning)
    if not (is_whole(n, 4) and is_whole(m, 1)):
        raise ValueError(f"need n >= 4 control points and m >= 1 samples, whole numbers; "
                         f"got n={n!r}, m={m!r}")
    if not (isinstance(derivative, (int, np.integer)) and derivative in (0, 1)):
        derivative = as_flag(derivative, "derivative")  # ("no" gave the derivative's basis)
    n, m = int(n), int(m)
    s = np.arange(m) * n / m
    i = np.floor(s).astype(int)
    t = s - i
    if derivative:
        w = np.stack([-(1 - t) ** 2 / 2, (3 * t ** 2 - 4 * t) / 2, (-3 * t ** 2 + 2 * t + 1) / 2,
                      t ** 2 / 2], axis=1)
    else:
        w = np.stack([(1 - t) ** 3 / 6, (3 * t ** 3 - 6 * t ** 2 + 4) / 6,
                      (-3 * t ** 3 + 3 * t ** 2 + 3 * t + 1) / 6, t ** 3 / 6], axis=1)
    B = np.zeros((m, n))
    for a in range(4):
        np.add.at(B, (np.arange(m), (i - 1 + a) % n), w[:, a])
    return B


@kernel
@njit(cache=True, fastmath=True)
def _radial_search(img, pts, normals, search, min_edge, out, found):
    # along each normal, the offset (from -search to +search, half-pixel steps) of the
    # largest central difference of intensity, if above min_edge
    H, W = img.shape
    steps = 4 * search + 1
    for k in range(pts.shape[0]):
        px, py = pts[k, 0], pts[k, 1]
        nx, ny = normals[k, 0], normals[k, 1]
        best, where = min_edge, 0.0
        found[k] = False
        prev2 = prev1 = 0.0
        for a in range(steps + 2):
            d = -search - 0.5 + a * 0.5
            x, y = px + d * nx, py + d * ny
            # the last row and column's centres too (a sample there was left out, where the
            # first's was taken: an edge between the last two was placed half a pixel off,
            # at half its step)
            if not (W > 1 and H > 1 and 0.0 <= x <= W - 1.0 and 0.0 <= y <= H - 1.0):
                v = np.nan
            else:
                x0, y0 = min(int(x), W - 2), min(int(y), H - 2)
                fx, fy = x - x0, y - y0
                v = ((1.0 - fy) * ((1.0 - fx) * img[y0, x0] + fx * img[y0, x0 + 1])
                     + fy * ((1.0 - fx) * img[y0 + 1, x0] + fx * img[y0 + 1, x0 + 1]))
            if a >= 2 and not (np.isnan(v) or np.isnan(prev2)):
                g = abs(v - prev2)  # over one pixel, centred at d - 0.5
                if g > best:
                    best, where = g, d - 0.5
                    found[k] = True
            prev2, prev1 = prev1, v
        out[k, 0], out[k, 1] = px + where * nx, py + where * ny


class Snake:
    """A closed B-spline contour tracked by radial edge search and a Kalman filter.

    Parameters
    ----------
    n_control : int
        Control points of the spline.
    n_samples : int
        Points where edges are searched for (3 or more: an update needs edges at 3).
    search : int
        Half-length of the radial search, in pixels.
    min_edge : float
        An intensity change over a pixel counts as an edge where it is larger than this.
    q, r : float
        Process variance per frame of each control point coordinate, and the variance of an
        edge's position along its normal (pixels²). In a shape space, ``q`` for a
        translation and ``q / ρ²`` for a linear parameter (``ρ`` the template's RMS distance
        from its centre): a control point's coordinate then moves by ``q`` from the
        translation and by ``q`` again, on average over the control points, from the
        linear map (``2q``; ``q`` for ``"free"``).
    shape : {"affine", "euclidean", "free"}
        The shape space (see the module).

    Attributes
    ----------
    state : Gaussian or None
        The shape parameters' distribution ``X`` (None before :meth:`init`): for
        ``"affine"`` the translation ``tx, ty`` and the linear map's change ``a, b, c, d``
        (``x = tx + c₀ + (1 + a) x₀ + b y₀``, ``y = ty + c₀ + c x₀ + (1 + d) y₀`` about the
        template's centre ``c₀``); for ``"euclidean"`` ``tx, ty, a, b``, read as
        ``x = ... + (1 + a) x₀ − b y₀``, ``y = ... + b x₀ + (1 + a) y₀``; for
        ``"free"`` each control point's own displacement, the ``n`` x coordinates then the
        ``n`` y.
    found : (m,) bool ndarray
        Where :meth:`track` found an edge at the last frame.

    Raises
    ------
    ValueError
        If ``n_control`` is not a whole number >= 4, ``n_samples`` not one >= 3, ``search``
        not one >= 1, ``min_edge`` not a finite number >= 0, ``q`` or ``r`` not a finite number
        > 0 (a TypeError for what is no number), or ``shape`` not one of the three.

    References
    ----------
    .. [1] A. Blake and M. Isard, *Active Contours*, Springer, 1998.

    Examples
    --------
    >>> import cv2
    >>> im = np.zeros((120, 160), np.uint8)
    >>> _ = cv2.circle(im, (80, 60), 30, 255, -1)
    >>> s = Snake(n_control=12, n_samples=60)
    >>> s.init_circle((80, 60), 26)
    >>> for _ in range(5):
    ...     pts = s.track(im)
    >>> r = np.linalg.norm(pts - [80, 60], axis=1)
    >>> bool(abs(r.mean() - 30) < 0.6)
    True
    """

    def __init__(self, n_control: int = 20, n_samples: int = 100, *, search: int = 10,
                 min_edge: float = 20.0, q: float = 4.0, r: float = 1.0,
                 shape: str = "affine"):
        # each named: a search of -1 or a min_edge of NaN gave a snake that never moved, a
        # n_control of 4.7 was cut to 4, and an infinite q failed at the first update
        self.n = as_whole(n_control, "n_control", 4, "control points of a closed B-spline")
        # (1 or 2 were taken, and a snake that needs 3 edges to move never moved)
        self.m = as_whole(n_samples, "n_samples", 3, "samples, 3 or more: an update needs "
                                                     "edges at 3")
        self.B = bspline_matrix(self.n, self.m)
        self.dB = bspline_matrix(self.n, self.m, derivative=True)
        self.search = as_whole(search, "search", 1, "pixels each way along a normal")
        self.min_edge = as_finite(min_edge, "min_edge", 0)
        self.q = as_finite(q, "q", 0, above=True)
        self.r = as_finite(r, "r", 0, above=True)
        if shape not in _SHAPES:
            raise ValueError(f"shape must be one of {', '.join(map(repr, _SHAPES))}; "
                             f"got {shape!r}")
        self.shape = shape
        self.state: Gaussian | None = None
        self.found = np.zeros(self.m, bool)  # (documented, and missing before a frame)
        # set by init (_template): Q₀ stacked x then y, W of Q = Q₀ + W X, each parameter's
        # process variance
        self._base: np.ndarray
        self._W: np.ndarray
        self._qdiag: np.ndarray

    def init(self, control_points: ArrayLike, std: float = 2.0) -> None:
        """Start from control points ``(n, 2)`` with standard deviation ``std`` pixels.

        Parameters
        ----------
        control_points : (n, 2) array_like
            The control points ``x, y``.
        std : float
            Standard deviation, in pixels, of each free control point's coordinates
            (independent), or of the translation in a shape space; each linear parameter's
            is ``std / ρ``, as ``q`` is scaled (see the class).

        Raises
        ------
        ValueError
            If ``control_points`` does not have shape ``(n, 2)``, is not finite, or, in a
            shape space, lies on one line (or one point).

        Examples
        --------
        >>> s = Snake(n_control=4, n_samples=8)
        >>> s.init([[0, 0], [10, 0], [10, 10], [0, 10]])
        >>> s.control_points[1].tolist(), float(s.state.cov[0, 0])
        ([10.0, 0.0], 4.0)
        """
        Q = self._points(control_points)
        std = as_finite(std, "std", 0.0, above=True)
        self._template(Q)
        # std pixels at each control point, as q is
        self.state = Gaussian(np.zeros(len(self._qdiag)),
                              std ** 2 / self.q * np.diag(self._qdiag))

    def _template(self, Q: np.ndarray) -> None:
        # the shape space about the control points Q (n, 2): Q₀, W, and the process noise of
        # each parameter (q for translations and free points, q / ρ² for linear parameters)
        n = self.n
        if self.shape == "free":
            self._base = np.r_[Q[:, 0], Q[:, 1]]
            self._W = np.eye(2 * n)
            self._qdiag = np.full(2 * n, self.q)
            return
        c = Q.mean(0)
        x0, y0 = Q[:, 0] - c[0], Q[:, 1] - c[1]
        rho2 = float((x0 ** 2 + y0 ** 2).mean())
        # (all in one point gave linear parameters whose noise grew 4e12 a frame; on one line,
        # a contour no linear map can thicken)
        spread = np.linalg.eigvalsh(np.cov(np.c_[x0, y0].T, bias=True))
        if not spread[0] > 1e-12 * max(spread[1], 1e-300):
            raise ValueError(f"control_points lie on one line, which shape={self.shape!r} "
                             f"cannot turn into a contour; give points around an area, or "
                             f"shape='free'")
        one, zero = np.ones(n), np.zeros(n)
        cols = [np.r_[one, zero], np.r_[zero, one]]
        if self.shape == "affine":
            cols += [np.r_[x0, zero], np.r_[y0, zero], np.r_[zero, x0], np.r_[zero, y0]]
        else:
            cols += [np.r_[x0, y0], np.r_[-y0, x0]]
        # set only once the points are known to make a contour (the base was set before the
        # check, so a refused init, move_to or anchor left the old map about the new points)
        self._base = np.r_[Q[:, 0], Q[:, 1]]
        self._W = np.stack(cols, axis=1)
        self._qdiag = np.r_[self.q, self.q, np.full(len(cols) - 2, self.q / rho2)]

    def _points(self, control_points: ArrayLike) -> np.ndarray:
        # (booleans and text were read as numbers, complex ones as their real parts, and a
        # masked array's hidden points as data: the package's numeric rules)
        Q = as_float_array(control_points, "control_points", not_boolean="x, y coordinates")
        if Q.shape != (self.n, 2):
            raise ValueError(f"control_points must have shape ({self.n}, 2); got {Q.shape}")
        if not np.isfinite(Q).all():  # a NaN point tracked an all-NaN contour without a word
            k = int(np.flatnonzero(~np.isfinite(Q).all(axis=1))[0])
            raise ValueError(f"control_points must be finite; control_points[{k}] = "
                             f"{Q[k].tolist()}")
        return Q

    def init_circle(self, centre: ArrayLike, radius: float, std: float = 2.0) -> None:
        """Start from the spline closest to a circle (control points on a slightly larger
        circle, as a cubic B-spline lies inside its control polygon).

        Parameters
        ----------
        centre : (2,) array_like
            The circle's centre ``x, y``.
        radius : float
            Its radius, in pixels.
        std : float
            Standard deviation of each control point coordinate, in pixels.

        Raises
        ------
        ValueError
            If ``centre`` is not two finite numbers (None, or one string of a number, is
            one value) or ``radius`` not a finite number > 0.
        TypeError
            If ``centre`` cannot be read as numbers at all (``"ab"``).

        Examples
        --------
        >>> s = Snake(n_control=8, n_samples=16)
        >>> s.init_circle((80, 60), 26)
        >>> r = np.linalg.norm(s.contour() - [80, 60], axis=1)
        >>> round(float(r.min()), 1), round(float(r.max()), 1)
        (26.0, 26.0)
        """
        radius = as_finite(radius, "radius", 0.0, above=True)
        a = 2 * np.pi * np.arange(self.n) / self.n
        # the spline through points on a circle of radius R has radius about R (2 + cos(2π/n))/3
        R = radius * 3 / (2 + np.cos(2 * np.pi / self.n))
        # (one number was a bare IndexError, a third coordinate dropped, NaN named as
        # control_points)
        c = as_float_array(centre, "centre", not_boolean="x and y")  # (True was x = 1)
        if c.shape != (2,) or not np.isfinite(c).all():
            raise ValueError(f"centre must be two finite numbers, x and y; got {centre!r}")
        self.init(np.c_[c[0] + R * np.cos(a), c[1] + R * np.sin(a)], std)

    @property
    def control_points(self) -> np.ndarray:
        """The control points' means ``(n, 2)`` (``x, y``).

        Raises
        ------
        AttributeError
            Before :meth:`init` or :meth:`init_circle`.

        Examples
        --------
        >>> s = Snake(n_control=4, n_samples=8)
        >>> s.init([[0, 0], [10, 0], [10, 10], [0, 10]])
        >>> s.control_points.tolist()
        [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]
        """
        if self.state is None:  # AttributeError, as before this check (and for hasattr)
            raise AttributeError("the snake has no state yet: call init or init_circle first")
        x = self._base + self._W @ self.state.mean
        return np.c_[x[:self.n], x[self.n:]]

    def move_to(self, control_points: ArrayLike) -> None:
        """Put the contour's control points at ``control_points`` (n, 2), keeping the
        state's covariance: the shape space is taken about the new points.

        A translation's variance stays in pixels²; a linear parameter's is relative to the
        template's size, so kept, it grows and shrinks with the contour (moved to twice the
        size, its pixel spread doubles). Carried over exactly in pixels instead (the
        control points' covariance mapped into the new space's parameters), the colour +
        snake composite of the single-object benchmark fell from 96 % to 55 % success on
        VOT15 bag (AUC 72 % to 47 %) and from 62 % to 59 % on OTB Crossing (AUC 49 % to
        53 %).

        Parameters
        ----------
        control_points : (n, 2) array_like
            The control points ``x, y``.

        Raises
        ------
        AttributeError
            Before :meth:`init` or :meth:`init_circle`.
        ValueError
            If ``control_points`` does not have shape ``(n, 2)`` or is not finite.

        Examples
        --------
        >>> s = Snake(n_control=4, n_samples=8)
        >>> s.init([[0, 0], [10, 0], [10, 10], [0, 10]])
        >>> s.move_to([[5, 0], [15, 0], [15, 20], [5, 20]])
        >>> s.control_points.tolist()
        [[5.0, 0.0], [15.0, 0.0], [15.0, 20.0], [5.0, 20.0]]
        """
        g = self.state
        if g is None:
            raise AttributeError("the snake has no state yet: call init or init_circle first")
        Q = self._points(control_points)
        self._template(Q)
        self.state = Gaussian(np.zeros_like(g.mean), g.cov)

    def contour(self) -> np.ndarray:
        """The contour's ``m`` sample points ``(m, 2)``.

        Returns
        -------
        (m, 2) ndarray
            ``r(s_k) = B_k Q`` at the control points' means, ``x, y``.

        Raises
        ------
        AttributeError
            Before :meth:`init` or :meth:`init_circle`.

        Examples
        --------
        >>> s = Snake(n_control=4, n_samples=4)
        >>> s.init([[0, 0], [6, 0], [6, 6], [0, 6]])
        >>> s.contour().tolist()
        [[1.0, 1.0], [5.0, 1.0], [5.0, 5.0], [1.0, 5.0]]
        """
        return self.B @ self.control_points

    def track(self, image: np.ndarray) -> np.ndarray:
        """Track the contour into a new (grey or BGR) frame; returns its sample points.

        Predicts the control points, searches for an edge along each sample's normal, and
        corrects the control points with the edges found (see the module); with fewer than
        3 edges the prediction stands.

        Parameters
        ----------
        image : (H, W) or (H, W, 3) ndarray
            The frame, grey or BGR uint8.

        Returns
        -------
        (m, 2) ndarray
            The contour's sample points after the correction (:meth:`contour`).

        Raises
        ------
        RuntimeError
            Before :meth:`init` or :meth:`init_circle`.

        Examples
        --------
        A circle of radius 26 locks onto a disc of radius 30:

        >>> import cv2
        >>> im = np.zeros((120, 160), np.uint8)
        >>> _ = cv2.circle(im, (80, 60), 30, 255, -1)
        >>> s = Snake(n_control=12, n_samples=60)
        >>> s.init_circle((80, 60), 26)
        >>> for _ in range(5):
        ...     pts = s.track(im)
        >>> pts.shape, int(s.found.sum())
        ((60, 2), 60)
        """
        if self.state is None:
            raise RuntimeError("call init or init_circle first")
        img = as_uint8_image(image, grey=True).astype(np.float32)
        n, m = self.n, self.m
        d = len(self._qdiag)
        g = kf_predict(self.state, np.eye(d), np.diag(self._qdiag))
        Qs = self._base + self._W @ g.mean
        Q = np.c_[Qs[:n], Qs[n:]]
        pts, tang = self.B @ Q, self.dB @ Q
        norm = np.linalg.norm(tang, axis=1, keepdims=True)
        normals = np.c_[tang[:, 1], -tang[:, 0]] / np.maximum(norm, 1e-12)
        edges = np.empty((m, 2))
        found = np.zeros(m, np.bool_)
        _radial_search(img, np.ascontiguousarray(pts), np.ascontiguousarray(normals),
                       self.search, self.min_edge, edges, found)
        if found.sum() >= 3:
            k = np.flatnonzero(found)
            # each edge measures the contour along its normal: ν_kᵀ B_k Q
            H = np.c_[normals[k, 0:1] * self.B[k], normals[k, 1:2] * self.B[k]]
            z = (normals[k] * edges[k]).sum(1) - H @ self._base
            g = kf_update(g, z, H @ self._W, self.r * np.eye(len(k)))
        self.state = g
        self.found = found
        return self.contour()



class SnakeTracker(SingleObjectTracker):
    """A :class:`Snake` as a box tracker: started on the ellipse inscribed in the first box,
    its box is the contour's bounding box; ``anchor(box)`` moves and scales the contour so
    that its bounding box is ``box``.

    In a shape space (the default, affine), the template is the object's outline in the first
    frame: the ellipse, as free control points, fitted to that frame ``settle`` times.

    Parameters
    ----------
    settle : int
        Fits of the free snake to the first frame that make the template (0: the ellipse
        itself); unused with ``shape="free"``.
    **snake
        Passed to :class:`Snake`.

    Attributes
    ----------
    snake : Snake
        The contour.

    Examples
    --------
    A disc of radius 30 around pixel (80, 60), whose centre is at 80.5, 60.5 in a box's
    coordinates (pixel ``k`` spans ``[k, k + 1)``), started from a smaller box:

    >>> import cv2
    >>> im = np.zeros((120, 160, 3), np.uint8)
    >>> _ = cv2.circle(im, (80, 60), 30, (255, 255, 255), -1)
    >>> t = SnakeTracker(n_control=12, n_samples=60)
    >>> t.init(im, [54, 34, 52, 52])
    >>> for _ in range(5):
    ...     box = t.update(im)
    >>> (box[:2] + box[2:] / 2).round(1).tolist(), box[2:].round().tolist()
    ([80.6, 60.6], [60.0, 60.0])
    """

    def __init__(self, settle: int = 10, **snake: Any):
        self.settle = as_whole(settle, "settle", 0, "frames the free snake fits the first frame")
        self.snake = Snake(**snake)

    def _start(self, image: np.ndarray, b: np.ndarray) -> None:
        as_uint8_image(image)  # a frame the updates would refuse is refused at the start
        s = self.snake
        # a cubic B-spline through control points on an ellipse lies inside them: the
        # ratio is (2 + cos(2π/n)) / 3, as in Snake.init_circle
        k = 3 / (2 + np.cos(2 * np.pi / s.n))
        a = 2 * np.pi * np.arange(s.n) / s.n
        c = _index_centre(b)
        Q = np.c_[c[0] + k * b[2] / 2 * np.cos(a), c[1] + k * b[3] / 2 * np.sin(a)]
        try:
            s.init(Q)
        except ValueError:
            # (named the control points, which the caller never gave, and shape='free',
            # which track-one has no option for)
            raise ValueError(f"box {b.tolist()} is too flat for the snake (shape="
                             f"{s.shape!r}): the control points on its ellipse lie on one "
                             "line; give a box around an area") from None
        if s.shape != "free" and self.settle:
            # the template: the object's outline in the first frame, found by the free snake
            free = Snake(s.n, s.m, search=s.search, min_edge=s.min_edge, q=s.q, r=s.r,
                         shape="free")
            free.init(Q)
            for _ in range(self.settle):
                free.track(image)
            s.init(free.control_points)
        self.box = self._bounds()

    def _bounds(self) -> np.ndarray:
        pts = self.snake.contour()
        lo, hi = pts.min(0), pts.max(0)
        return np.r_[lo + _HALF, np.maximum(hi - lo, 1e-6)]

    def _follow(self, image: np.ndarray) -> np.ndarray:
        self.snake.track(image)
        self.box = self._bounds()
        return self.box.copy()

    def anchor(self, box: ArrayLike) -> None:
        """Move and scale the contour (each axis on its own) so that its bounding box is
        ``box``; the covariance is kept.

        Parameters
        ----------
        box : (4,) array_like
            The box ``x, y, w, h``.

        Examples
        --------
        >>> t = SnakeTracker(n_control=8, n_samples=32)
        >>> t.init(np.zeros((120, 160), np.uint8), [50, 30, 60, 60])
        >>> t.anchor([40, 30, 30, 20])
        >>> pts = t.snake.contour()  # (in the pixels' indices: half a pixel before the box's)
        >>> pts.min(0).round(6).tolist(), pts.max(0).round(6).tolist()
        ([39.5, 29.5], [69.5, 49.5])
        """
        self._need_start("anchor")
        b = as_box(box)
        cur = self._bounds()
        s = b[2:] / cur[2:]
        c0, c1 = cur[:2] + cur[2:] / 2, b[:2] + b[2:] / 2
        Q = self.snake.control_points
        try:
            self.snake.move_to(c1 + s * (Q + _HALF - c0) - _HALF)
        except ValueError:
            # (named the control points, which the caller never gave)
            raise ValueError(f"box {b.tolist()} is too flat for the snake (shape="
                             f"{self.snake.shape!r}): the control points moved to it lie on "
                             "one line; give a box around an area") from None
        self.box = b

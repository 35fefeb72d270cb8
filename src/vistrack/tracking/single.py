r"""Single-object trackers: one box, initialised by hand, followed frame to frame.

Every tracker has ``init(image, box)`` and ``update(image) -> box`` (boxes are ``x, y, w, h``
floats, the top-left corner and size), and is chosen by name from :data:`METHODS`:

- ``"klt"``: median flow (Kalal et al., 2010) from the seeds' feature tracking: Shi-Tomasi
  features inside the box are tracked by pyramidal Lucas-Kanade with the forward-backward
  check; the box moves by their median displacement and scales by the median ratio of
  their pairwise distances;
- ``"template"``: the seeds' SSD template tracking with an affine warp (the Hager/Toyama
  cycle: predict, warp, compare, correct), by inverse-compositional Lucas-Kanade of the
  first frame's central patch (:mod:`vistrack.tracking._affine`), started each frame from
  the median-flow motion; the box is the warped first box's bounding box;
- ``"colour"``: mean shift on the back-projection of a hue-saturation-value histogram of
  the target against its surroundings (the object's colour over the background's), with the
  histogram updated online from the tracked box;
- ``"camshift"``: the same back-projection, tracked by OpenCV's CamShift (the window's size
  and orientation from its moments);
- ``"particle"``: CONDENSATION on the same colour model (Pérez et al., 2002): particles of
  ``(cx, cy, log scale)`` diffuse as a random walk, each is weighed by how much more of the
  object's colour its box holds than the ring around it, and they are resampled by
  :func:`vistrack.filters.resample` when the effective sample size falls below half;
- ``"wsl"``: the robust online appearance model of Jepson, Fleet and El-Maraghi
  (:class:`vistrack.tracking.appearance.WSLTracker`): the stable / wandering / lost mixture
  of the view's intensities is the likelihood of an exhaustive translation search;
- ``"meanshift"``: ``"colour"`` with the window's size fixed (the classic mean-shift tracker);
- ``"snake"``: the B-spline snake (:class:`vistrack.tracking.snake.SnakeTracker`) started on
  the ellipse inscribed in the box, its box the contour's bounding box;
- ``"csrt"``, ``"kcf"``: OpenCV contrib's trackers, for comparison.

Every tracker but OpenCV's also has ``anchor(box)``, which moves its state to a box, for
:class:`vistrack.tracking.compose.Composite`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np

from .._registry import Registry
from .._validate import as_box, as_finite, as_scales, as_uint8_image, as_whole, is_whole
from ._affine import prepare_templates, register
from .appearance import WSLTracker
from .base import _HALF, SingleObjectTracker, _index_centre
from .snake import SnakeTracker

if TYPE_CHECKING:
    import cv2
    from numpy.typing import ArrayLike

__all__ = ["METHODS", "single_tracker", "MedianFlow", "TemplateTracker", "ColourTracker",
           "CamShiftTracker", "ColourParticleTracker", "OpenCVTracker"]


class _LKArgs(TypedDict):
    """Keyword arguments of ``cv2.calcOpticalFlowPyrLK``."""

    winSize: tuple[int, int]
    maxLevel: int


def _grey(image: np.ndarray) -> np.ndarray:
    return as_uint8_image(image, grey=True)


def _hsv(image: np.ndarray) -> np.ndarray:
    import cv2

    im = as_uint8_image(image, channels=(1, 3))
    if im.ndim != 3:
        # a grey frame is its value alone (hue and saturation 0), as the same frame in BGR
        # gives: the model is then the brightness's histogram (a grey image read by the
        # command line, three equal channels, was tracked so, and refused as an array)
        im = cv2.cvtColor(im, cv2.COLOR_GRAY2BGR)
    return cv2.cvtColor(im, cv2.COLOR_BGR2HSV)


class MedianFlow(SingleObjectTracker):
    """Median-flow tracking of a box by its features (see the module).

    Parameters
    ----------
    grid : int
        Features are the best Shi-Tomasi corners in the box, up to ``grid²`` (a regular
        ``grid × grid`` of points where the box has too little texture: fewer than 5
        corners).
    fb_max : float
        Forward-backward error (pixels) above which a feature is not used; of the others,
        the better half by that error (but no fewer than 3) moves the box.
    win_size, levels : int
        Lucas-Kanade window (pixels) and pyramid levels above the image.

    References
    ----------
    .. [1] Z. Kalal, K. Mikolajczyk and J. Matas, "Forward-backward error: automatic
       detection of tracking failures", *International Conference on Pattern Recognition*,
       2010.

    Examples
    --------
    A textured scene moving 3 pixels right and 1 down:

    >>> import cv2
    >>> rng = np.random.default_rng(0)
    >>> scene = cv2.GaussianBlur(rng.integers(0, 256, (120, 160), dtype=np.uint8), (0, 0), 2)
    >>> t = MedianFlow()
    >>> t.init(scene, [40, 30, 40, 40])
    >>> t.update(np.roll(scene, (1, 3), axis=(0, 1))).round(1).tolist()
    [43.0, 31.0, 40.0, 40.0]
    """

    def __init__(self, grid: int = 10, fb_max: float = 2.0, win_size: int = 11,
                 levels: int = 3):
        self.grid = as_whole(grid, "grid", 2)
        self.fb_max = as_finite(fb_max, "fb_max", 0.0, above=True)
        win_size, levels = as_whole(win_size, "win_size", 3), as_whole(levels, "levels", 0)
        self.lk = _LKArgs(winSize=(win_size, win_size), maxLevel=levels)

    def _start(self, image: np.ndarray, box: np.ndarray) -> None:
        self.prev = _grey(image)
        self.box = box
        self._shift = np.zeros(2)  # the box's last frame-to-frame displacement

    def motion(self, grey: np.ndarray) -> tuple[np.ndarray, float] | None:
        """Median displacement and scale of the box's features from the previous frame, or
        None when too few are reliable.

        Parameters
        ----------
        grey : (H, W) uint8 ndarray
            The next frame, grey, of the previous frame's size.

        Returns
        -------
        tuple of ((2,) ndarray, float) or None
            The median displacement ``dx, dy`` of the reliable features, and the median
            ratio of their pairwise distances (the scale); None when the box lies outside
            the image or, for a box at least 4 pixels on a side, less than 4 pixels of it
            lies inside, or when fewer than 3 features pass the forward-backward check (of
            those that do, the better half moves the box, and never fewer than 3).

        Examples
        --------
        >>> import cv2
        >>> rng = np.random.default_rng(0)
        >>> scene = cv2.GaussianBlur(rng.integers(0, 256, (120, 160), dtype=np.uint8), (0, 0), 2)
        >>> t = MedianFlow()
        >>> t.init(scene, [40, 30, 40, 40])
        >>> d, s = t.motion(np.roll(scene, (1, 3), axis=(0, 1)))
        >>> d.round(1).tolist(), round(s, 3)
        ([3.0, 1.0], 1.0)
        """
        import cv2

        self._need_start("motion")
        g = np.asarray(grey)
        if g.shape != self.prev.shape or g.dtype != np.uint8:
            # (a BGR frame failed in "too many values to unpack", one of another size or
            # type in OpenCV's assertion)
            raise ValueError(f"grey must be a grey uint8 image of the previous frame's size "
                             f"{self.prev.shape}; got shape {g.shape}, dtype {g.dtype}")
        x, y, w, h = self.box
        H, W = grey.shape
        if min(x + w, W) <= max(x, 0) or min(y + h, H) <= max(y, 0):
            return None  # outside the image
        # the pixels the box covers in the image, at least one in each direction
        x0, y0 = int(max(x, 0)), int(max(y, 0))
        x1, y1 = max(int(min(x + w, W)), x0 + 1), max(int(min(y + h, H)), y0 + 1)
        # a sliver of a box (under 4 pixels of it in the image) has too little of the object
        # to follow; a box under 4 pixels itself is followed where it all lies in the image
        # (a 3x3 box was refused inside the image, and never moved)
        need_x = min(4, max(int(np.floor(x + w)) - int(np.floor(x)), 1))
        need_y = min(4, max(int(np.floor(y + h)) - int(np.floor(y)), 1))
        if x1 - x0 < need_x or y1 - y0 < need_y:
            return None
        mask = np.zeros_like(self.prev)
        mask[y0:y1, x0:x1] = 255
        p0 = cv2.goodFeaturesToTrack(self.prev, self.grid ** 2, 0.01, 2, mask=mask,
                                     blockSize=3)
        if p0 is None or len(p0) < 5:
            # too little texture for 3 features to outlast the better half below (of 4
            # corners, 2 were left, and the box never moved): a regular grid instead
            gx, gy = np.meshgrid(np.linspace(x0, x1 - 1, self.grid),
                                 np.linspace(y0, y1 - 1, self.grid))
            p0 = np.c_[gx.ravel(), gy.ravel()].astype(np.float32).reshape(-1, 1, 2)
        # nextPts=None: OpenCV allocates the output points (OpenCV 5.0's stubs forbid None
        # there, 5.1's allow it: the ignore, and that it may be unused)
        p1, st, _ = cv2.calcOpticalFlowPyrLK(  # type: ignore[call-overload, unused-ignore]
            self.prev, grey, p0, None, **self.lk)
        pb, sb, _ = cv2.calcOpticalFlowPyrLK(  # type: ignore[call-overload, unused-ignore]
            grey, self.prev, p1, None, **self.lk)
        fb = np.linalg.norm((pb - p0).reshape(-1, 2), axis=1)
        ok = st.ravel().astype(bool) & sb.ravel().astype(bool) & (fb <= self.fb_max)
        if ok.sum() < 3:
            return None
        # the better half by forward-backward error, as median flow does, but no fewer than
        # 3 (of 3 or 4 reliable features the half left 2, and the box did not move)
        passed = np.sort(fb[ok])
        ok &= fb <= max(np.median(passed), passed[2])
        a, b = p0.reshape(-1, 2)[ok], p1.reshape(-1, 2)[ok]
        d = np.median(b - a, axis=0)
        i, j = np.triu_indices(len(a), 1)
        da = np.linalg.norm(a[i] - a[j], axis=1)
        db = np.linalg.norm(b[i] - b[j], axis=1)
        good = da > 1e-3
        s = float(np.median(db[good] / da[good])) if good.any() else 1.0
        return d, s

    def _follow(self, image: np.ndarray) -> np.ndarray:
        grey = _grey(image)
        m = self.motion(grey)
        self._shift = np.zeros(2)
        if m is not None:
            d, s = m
            x, y, w, h = self.box
            cx, cy = x + w / 2 + d[0], y + h / 2 + d[1]
            self.box = np.array([cx - s * w / 2, cy - s * h / 2, s * w, s * h])
            self._shift = np.asarray(d, float)
        self.prev = grey
        return self.box.copy()

    def anchor(self, box: ArrayLike) -> None:
        """Move the box so that the next frame's is ``box``, as far as the flow can tell: its
        features are found where ``box`` lay a frame earlier, moved back by the box's last
        displacement, since their motion to the next frame is added to it. (Taken as it
        stood, the motion was counted twice: anchored on a composite's prediction, the box
        ran ahead of a target moving 5 pixels a frame, 110 against 60 after 8 frames.)
        :meth:`anchor_last` gives the earlier frame's box itself.

        Parameters
        ----------
        box : (4,) array_like
            The box ``x, y, w, h`` expected in the next frame.

        Examples
        --------
        >>> t = MedianFlow()
        >>> t.init(np.zeros((60, 80), np.uint8), [10, 10, 20, 20])
        >>> t.anchor([30, 20, 10, 10])   # no motion yet: the box itself
        >>> t.box.tolist()
        [30.0, 20.0, 10.0, 10.0]
        """
        self._need_start("anchor")
        b = as_box(box)
        self.box = np.r_[b[:2] - self._shift, b[2:]]

    def anchor_last(self, box: ArrayLike) -> None:
        """Move the box of the frame last given to ``box``: the next frame's features are
        found in it (a composite's estimate of that frame, so that the flow measures the
        motion from where the target was, not from where the box drifted).

        Parameters
        ----------
        box : (4,) array_like
            The box ``x, y, w, h`` in the frame last given.

        Examples
        --------
        >>> t = MedianFlow()
        >>> t.init(np.zeros((60, 80), np.uint8), [10, 10, 20, 20])
        >>> t.anchor_last([12, 10, 20, 20])
        >>> t.box.tolist()
        [12.0, 10.0, 20.0, 20.0]
        """
        self._need_start("anchor_last")
        self.box = as_box(box)


class TemplateTracker(SingleObjectTracker):
    """Affine template tracking of the first frame's central patch (see the module).

    Parameters
    ----------
    max_residual : float
        RMS difference of normalised intensities above which the registration is not
        trusted and the median-flow motion alone moves the box.
    iters : int
        Iterations of the inverse-compositional registration per frame.

    Attributes
    ----------
    residual : float
        The registration's RMS residual at the last frame; NaN where none ran: before the
        first :meth:`update`, or where no template was cut and the median flow alone
        moves the box (a flat box, or one whose central patch the image's edge cuts to
        nothing).

    References
    ----------
    .. [1] S. Baker and I. Matthews, "Lucas-Kanade 20 years on: a unifying framework",
       *International Journal of Computer Vision* 56(3), 2004.

    Examples
    --------
    A textured scene moving 3 pixels right and 1 down:

    >>> import cv2
    >>> rng = np.random.default_rng(0)
    >>> scene = cv2.GaussianBlur(rng.integers(0, 256, (120, 160), dtype=np.uint8), (0, 0), 2)
    >>> t = TemplateTracker()
    >>> t.init(scene, [40, 30, 40, 40])
    >>> t.update(np.roll(scene, (1, 3), axis=(0, 1))).round(1).tolist()
    [43.0, 31.0, 40.0, 40.0]
    """

    def __init__(self, max_residual: float = 0.6, iters: int = 30):
        # a NaN max_residual turned every registration down (median flow alone), 2.7
        # iterations were 2 and -5 had no bound
        self.max_residual = as_finite(max_residual, "max_residual", 0.0, above=True)
        self.iters = as_whole(iters, "iters", 1)
        self.flow = MedianFlow()

    def _start(self, image: np.ndarray, b: np.ndarray) -> None:
        grey = _grey(image).astype(np.float32)
        self.box0 = b
        # the warp's translation is the centre in the pixels' indices (pixel k's centre at
        # k), half a pixel before the box's (pixel k spans [k, k + 1)): at the box's own,
        # the patch of a box at the right or bottom edge reached past the image, and the
        # template was dropped there (kept at the left and top)
        c = _index_centre(b)[None]
        # the box's central patch, smaller where the image's edge cuts it: its samples, and
        # the pixel around them that its gradients need, lie where the image is sampled
        # (0 <= x < W - 1)
        H, W = grey.shape
        cx, cy = c[0]
        room = min(np.floor(cx), np.ceil(W - 2 - cx), np.floor(cy), np.ceil(H - 2 - cy)) - 1
        self.half = max(3, min(int(min(b[2], b[3]) / 2) - 1, int(room)))
        self.T, self.SD, self.Hinv, ok = prepare_templates(grey, c, self.half)
        self.ok = bool(ok[0])
        self.p = np.zeros((1, 6))
        self.p[0, 4:] = c[0]
        self.flow.init(image, b)
        self.box = b.copy()
        self.residual = float("nan")  # (0, a perfect fit, before any registration ran)

    def _corners(self, p: np.ndarray) -> np.ndarray:
        x, y, w, h = self.box0
        c = np.array([x + w / 2, y + h / 2])
        rel = np.array([[x, y], [x + w, y], [x, y + h], [x + w, y + h]]) - c
        A = np.array([[1 + p[0], p[2]], [p[1], 1 + p[3]]])
        return rel @ A.T + p[4:] + _HALF  # (the translation is in the pixels' indices)

    def _follow(self, image: np.ndarray) -> np.ndarray:
        grey = _grey(image)
        prior = self.flow.update(image)
        if not self.ok:
            self.box = prior
            return prior.copy()
        # predict: the last warp, moved and scaled by the median flow
        p = self.p.copy()
        s = prior[2] / self.box[2] if self.box[2] > 0 else 1.0
        A = np.array([[1 + p[0, 0], p[0, 2]], [p[0, 1], 1 + p[0, 3]]]) * s
        p[0, :4] = [A[0, 0] - 1, A[1, 0], A[0, 1], A[1, 1] - 1]
        p[0, 4:] = _index_centre(prior)
        predicted = p.copy()
        rms = register(grey, self.half, self.T, self.SD, self.Hinv, p, iters=self.iters)
        self.residual = float(rms[0])
        if rms[0] <= self.max_residual:
            self.p = p
            q = self._corners(p[0])
            lo, hi = q.min(0), q.max(0)
            self.box = np.r_[lo, hi - lo]
        else:
            # the median flow's box, and the warp predicted from it, scale included: with
            # the last warp's shape kept, each frame turned down lost its change of scale,
            # and the warp's box drifted from the box reported
            self.box = prior
            self.p = predicted
        self.flow.box = self.box.copy()
        return self.box.copy()

    def anchor(self, box: ArrayLike) -> None:
        """Move the warp so that its box is ``box``: the same shape, shifted and scaled.

        Parameters
        ----------
        box : (4,) array_like
            The box ``x, y, w, h``; the warp is scaled by the square root of the ratio of the
            areas.

        Examples
        --------
        >>> import cv2
        >>> rng = np.random.default_rng(0)
        >>> scene = cv2.GaussianBlur(rng.integers(0, 256, (120, 160), dtype=np.uint8), (0, 0), 2)
        >>> t = TemplateTracker()
        >>> t.init(scene, [40, 30, 40, 40])
        >>> t.anchor([50, 40, 20, 20])
        >>> t.box.tolist()
        [50.0, 40.0, 20.0, 20.0]
        """
        self._need_start("anchor")
        b = as_box(box)
        s = np.sqrt(b[2] * b[3] / (self.box[2] * self.box[3]))
        p = self.p[0]
        A = np.array([[1 + p[0], p[2]], [p[1], 1 + p[3]]]) * s
        p[:4] = [A[0, 0] - 1, A[1, 0], A[0, 1], A[1, 1] - 1]
        self.p[0, 4:] = _index_centre(b)
        self.box = b
        self.flow.anchor(b)

    def anchor_last(self, box: ArrayLike) -> None:
        """The box of the frame last given, for the median flow that starts the warp's search
        (:meth:`MedianFlow.anchor_last`); the warp is :meth:`anchor`'s.

        Parameters
        ----------
        box : (4,) array_like
            The box ``x, y, w, h`` in the frame last given.
        """
        self._need_start("anchor_last")
        self.flow.anchor_last(box)


def _contrast(integral: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Mean of the image inside each box ``(N, 4)`` minus the mean in the ring a quarter of
    its size around it, from the image's integral ``(H + 1, W + 1)``."""
    H, W = integral.shape[0] - 1, integral.shape[1] - 1

    def total(x0, y0, x1, y1):
        x0, x1 = np.clip(np.round(x0), 0, W).astype(int), np.clip(np.round(x1), 0, W).astype(int)
        y0, y1 = np.clip(np.round(y0), 0, H).astype(int), np.clip(np.round(y1), 0, H).astype(int)
        area = (x1 - x0) * (y1 - y0)
        return integral[y1, x1] - integral[y0, x1] - integral[y1, x0] + integral[y0, x0], area

    inner, n_in = total(b[:, 0], b[:, 1], b[:, 0] + b[:, 2], b[:, 1] + b[:, 3])
    mx, my = b[:, 2] / 4, b[:, 3] / 4
    outer, n_out = total(b[:, 0] - mx, b[:, 1] - my, b[:, 0] + b[:, 2] + mx,
                         b[:, 1] + b[:, 3] + my)
    return inner / np.maximum(n_in, 1) - (outer - inner) / np.maximum(n_out - n_in, 1)


def _mean_shift(bp: np.ndarray, box: np.ndarray, iters: int = 20, eps: float = 0.05
                ) -> tuple[float, float]:
    """The mode of the back-projection ``bp`` that mean shift reaches from ``box``: the
    centre of the window of ``box``'s size at the centroid of what it covers, in a box's
    coordinates (pixel ``k`` spans ``[k, k + 1)``), to within ``eps`` pixels or ``iters``
    steps. A pixel the window cuts counts by the share of it inside, at that share's
    centre; what lies outside the image weighs nothing, and the window keeps its size there.

    ``cv2.meanShift`` moved by whole pixels and took the centroid in the pixels' indices
    against the window's ``w / 2``: a window up to 2 pixels left of (or above) its mode did
    not move, so the colour trackers were half a pixel up and to the left of the object on
    average (−0.53, −0.50 px on an exactly drawn disc; they lagged moving right, and not
    moving left). A window wholly outside the image is left where it is.

    Examples
    --------
    A blob cut by the right edge, the window started on it, half outside; a blob of 20
    pixels from x = 40, the window started 2 pixels to its left:

    >>> bp = np.zeros((60, 100), np.uint8); bp[20:40, 88:] = 255
    >>> _mean_shift(bp, np.array([88.0, 20, 20, 20]))
    (94.0, 30.0)
    >>> bp = np.zeros((60, 100), np.uint8); bp[20:40, 40:60] = 255
    >>> [round(v, 1) for v in _mean_shift(bp, np.array([38.0, 20, 20, 20]))]
    [50.0, 30.0]
    """
    x, y, w, h = (float(v) for v in box)
    # a window under a pixel is widened to one about its centre (widened from its corner,
    # a still box 0.5 pixel wide moved 0.25 pixel a frame, with nothing under it too)
    cx, cy = x + w / 2, y + h / 2
    w, h = max(w, 1.0), max(h, 1.0)
    H, W = bp.shape
    for _ in range(iters):
        x0, y0 = cx - w / 2, cy - h / 2
        i0, i1 = max(int(np.floor(x0)), 0), min(int(np.ceil(x0 + w)), W)
        j0, j1 = max(int(np.floor(y0)), 0), min(int(np.ceil(y0 + h)), H)
        if i0 >= i1 or j0 >= j1:
            break  # (wholly outside the image)
        # each column's and row's share inside the window, and that share's centre
        (ax, mx), (ay, my) = _cut(i0, i1, x0, w), _cut(j0, j1, y0, h)
        mass = bp[j0:j1, i0:i1] * ay[:, None] * ax[None, :]
        total = mass.sum()
        if total <= 0:
            break  # (nothing under the window: no direction to move)
        nx, ny = float(mass.sum(0) @ mx / total), float(mass.sum(1) @ my / total)
        step = max(abs(nx - cx), abs(ny - cy))
        cx, cy = nx, ny
        if step < eps:
            break
    return cx, cy


def _cut(k0: int, k1: int, start: float, length: float) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel ``k0 <= k < k1``'s share inside ``[start, start + length)`` (pixel ``k``
    spans ``[k, k + 1)``), and the centre of that share."""
    k = np.arange(k0, k1)
    lo, hi = np.maximum(k, start), np.minimum(k + 1, start + length)
    return np.maximum(hi - lo, 0.0), (lo + hi) / 2


def _colour_cells(hsv: np.ndarray, bins: int) -> np.ndarray:
    """Each pixel's cell of the colour model, a histogram of ``bins`` hue (OpenCV's 8-bit
    hue, 0-179) by ``bins`` saturation by ``bins`` value (0-255), as OpenCV's uniform bins
    cut them (saturation and value alone, before, told a red object on green from its
    background only where they differed in brightness or saturation).

    Examples
    --------
    >>> _colour_cells(np.array([[[0, 0, 0], [179, 255, 255], [90, 128, 64]]], np.uint8),
    ...               12).tolist()
    [[0, 1727, 939]]
    """
    th, ts, tv = _cell_tables(bins)
    return th[hsv[..., 0]] + ts[hsv[..., 1]] + tv[hsv[..., 2]]


@functools.lru_cache(maxsize=8)
def _cell_tables(bins: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each 8-bit hue's, saturation's and value's share of :func:`_colour_cells`' index (a
    table lookup a channel: 5 times as fast as the arithmetic on a whole frame)."""
    x = np.arange(256, dtype=np.int64)
    hue = (np.minimum(x, 179) * bins // 180) * bins * bins
    return hue.astype(np.int32), ((x * bins >> 8) * bins).astype(np.int32), \
        (x * bins >> 8).astype(np.int32)


class ColourTracker(SingleObjectTracker):
    """Mean shift on a colour back-projection, with an online histogram (see the module).

    Frames are BGR, or grey: a grey frame is its brightness alone (hue and saturation 0, as
    the same frame in BGR), and the model that brightness's histogram.

    Parameters
    ----------
    bins : int
        Histogram bins per channel (hue, saturation and value; 12, 1,728 cells in all), 2 to
        64.
    rate : float
        Weight of the current box's histogram in the model each frame (0 keeps the first).
    scales : tuple of float
        Relative sizes tried around the mean-shift position each frame; the one whose box
        best separates the object's colour from the ring around it is kept, and of those
        that separate it equally well the one nearest 1 (``(1.0,)``: a fixed size,
        ``"meanshift"`` in :data:`METHODS`).

    References
    ----------
    .. [1] D. Comaniciu, V. Ramesh and P. Meer, "Real-time tracking of non-rigid objects
       using mean shift", *IEEE Conference on Computer Vision and Pattern Recognition*, 2000.

    Examples
    --------
    A red square moving 3 pixels a frame over green:

    >>> def image(x):
    ...     im = np.full((60, 80, 3), (40, 120, 40), np.uint8); im[20:40, x:x + 20] = (0, 0, 255)
    ...     return im
    >>> t = ColourTracker()
    >>> t.init(image(30), [30, 20, 20, 20])
    >>> [t.update(image(x)).round().tolist()[0] for x in (33, 36, 39)]
    [33.0, 36.0, 39.0]
    """

    def __init__(self, bins: int = 12, rate: float = 0.05, scales: tuple = (0.93, 1.0, 1.07)):
        self.bins = as_whole(bins, "bins", 2)  # 0 failed inside OpenCV's histogram
        if self.bins > 64:  # (bins³ cells: 100 took 8 MB a histogram, 1,000 8 GB)
            raise ValueError(f"bins must be at most 64 a channel (64³ cells); got {bins}")
        self.rate = as_finite(rate, "rate", 0.0, high=1.0)
        self.scales = as_scales(scales)

    def _cells(self, image: np.ndarray) -> np.ndarray:
        """The frame's pixels' cells of the colour model (:func:`_colour_cells`), once a
        frame for the back-projection and the histograms learnt."""
        return _colour_cells(_hsv(image), self.bins)

    def _hist(self, cells: np.ndarray, box: np.ndarray) -> tuple[np.ndarray, np.ndarray]:

        x, y, w, h = np.round(box).astype(int)
        # a side under half a pixel rounded to none, and the model to nothing (every colour
        # then equally likely, the box followed nothing): the pixel under its centre
        if w < 1:
            x, w = int(np.floor(box[0] + box[2] / 2)), 1
        if h < 1:
            y, h = int(np.floor(box[1] + box[3] / 2)), 1
        H, W = cells.shape[:2]
        inner = np.zeros((H, W), np.uint8)
        inner[max(y, 0):max(y + h, 0), max(x, 0):max(x + w, 0)] = 1
        ring = np.zeros((H, W), np.uint8)
        ring[max(y - h, 0):max(y + 2 * h, 0), max(x - w, 0):max(x + 2 * w, 0)] = 1
        ring[inner == 1] = 0
        n = self.bins ** 3
        ht = np.bincount(cells[inner == 1], minlength=n).astype(np.float64)
        hb = np.bincount(cells[ring == 1], minlength=n).astype(np.float64)
        return ht / max(ht.sum(), 1.0), hb / max(hb.sum(), 1.0)

    def _start(self, image: np.ndarray, box: np.ndarray) -> None:
        cells = self._cells(image)  # first: an image refused leaves the tracker as it was
        self.pt, self.pb = self._hist(cells, box)
        self.box = box

    def _backproject(self, cells: np.ndarray) -> np.ndarray:
        # p(object | colour) with equal priors, 0-255

        ratio = (255 * self.pt / (self.pt + self.pb + 1e-12)).astype(np.uint8)
        return ratio[cells]

    def _learn(self, cells: np.ndarray) -> None:
        # the online model: a share `rate` of the tracked box's histograms each frame
        if self.rate > 0:
            pt, pb = self._hist(cells, self.box)
            self.pt = (1 - self.rate) * self.pt + self.rate * pt
            self.pb = (1 - self.rate) * self.pb + self.rate * pb

    def _follow(self, image: np.ndarray) -> np.ndarray:
        import cv2

        cells = self._cells(image)
        bp = self._backproject(cells)
        cx, cy = _mean_shift(bp, self.box)
        w, h = self.box[2], self.box[3]
        # the scale whose box best separates the object's colour from its surroundings:
        # mean back-projection inside minus in the ring around it; of scales that tie, the
        # one nearest 1 (the first, 0.93, shrank the box to nothing on unchanged frames)
        sc = np.array(self.scales)
        sc = sc[np.argsort(np.abs(np.log(sc)), kind="stable"), None]  # 1 first
        boxes = np.c_[cx - sc * w / 2, cy - sc * h / 2, sc * w, sc * h]
        self.box = boxes[int(np.argmax(_contrast(cv2.integral(bp.astype(np.float64)), boxes)))]
        self._learn(cells)
        return self.box.copy()

    def anchor(self, box: ArrayLike) -> None:
        """Move the window to ``box``.

        Parameters
        ----------
        box : (4,) array_like
            The box ``x, y, w, h``.

        Examples
        --------
        >>> t = ColourTracker()
        >>> t.init(np.zeros((60, 80, 3), np.uint8), [30, 20, 20, 20])
        >>> t.anchor([10, 10, 30, 30])
        >>> t.box.tolist()
        [10.0, 10.0, 30.0, 30.0]
        """
        self._need_start("anchor")
        self.box = as_box(box)


_FAR = 2.0 ** 29
"""How far past the image CamShift's window is given to OpenCV (which cuts it to the image)."""


class CamShiftTracker(ColourTracker):
    """OpenCV's CamShift on the colour back-projection of :class:`ColourTracker`.

    The back-projection below one half (pixels more likely background than object) is set
    to 0 first; the box is the bounding box of the ellipse whose axes are CamShift's rotated
    window (the same for a round target at whatever angle its moments leave it).

    Parameters
    ----------
    bins, rate : int, float
        As for :class:`ColourTracker`.
    scales : tuple of float
        Not used: CamShift sizes its window itself.

    References
    ----------
    .. [1] G. R. Bradski, "Computer vision face tracking for use in a perceptual user
       interface", *Intel Technology Journal* Q2, 1998.

    Examples
    --------
    >>> def image(x):
    ...     im = np.full((60, 80, 3), (40, 120, 40), np.uint8); im[20:40, x:x + 20] = (0, 0, 255)
    ...     return im
    >>> t = CamShiftTracker()
    >>> t.init(image(30), [30, 20, 20, 20])
    >>> [t.update(image(x)).round().tolist()[0] for x in (33, 36, 39)]
    [31.0, 35.0, 37.0]
    """

    def _follow(self, image: np.ndarray) -> np.ndarray:
        import cv2

        cells = self._cells(image)
        bp = self._backproject(cells)
        # CamShift sizes its window from the back-projection's mass in it: pixels more
        # likely background than object (below one half) must not count, or the window
        # grows over the background's faint mass
        bp[bp < 128] = 0
        H, W = bp.shape[:2]
        bx, by, bw, bh = self.box
        if bx + bw <= 0 or by + bh <= 0 or bx >= W or by >= H:
            # a window wholly outside the image is left where it is, as ColourTracker's is
            # (OpenCV's mean shift moved an empty window to the image's centre, onto
            # whatever lay there; past int32, its window could not be read)
            self._learn(cells)
            return self.box.copy()
        # the window as OpenCV's ints, cut to within 2^29 pixels of the image (it cuts it to
        # the image itself; past int32, "Can't parse 'window'")
        b = np.round(self.box)  # (each value rounded, as always; then cut)
        lo = np.maximum(b[:2], -_FAR)
        hi = np.minimum(b[:2] + b[2:], _FAR)
        x, y, w, h = (int(v) for v in np.r_[lo, hi - lo])
        crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 20, 0.5)
        rect, _ = cv2.CamShift(bp, (x, y, max(w, 1), max(h, 1)), crit)
        (cx, cy), (rw, rh), angle = rect
        if rw > 1 and rh > 1:
            # the bounding box of the ellipse the window's axes are (OpenCV's 4 standard
            # deviations of the mass along each): its turned rectangle's corners made a
            # round target's box up to 1.41 times too large, by an angle its moments leave
            # arbitrary (a disc of 24 px boxed 33.8 or 23.7 by where it stood within a
            # pixel); cv2.boundingRect's whole pixels, 1-2 more
            a = np.deg2rad(angle)
            ex = np.hypot(rw * np.cos(a), rh * np.sin(a)) / 2
            ey = np.hypot(rw * np.sin(a), rh * np.cos(a)) / 2
            # within the image, as OpenCV's own window is (a window larger than the image,
            # turned, reached 49 pixels past every edge)
            lo = np.maximum([cx - ex, cy - ey], 0.0)
            hi = np.minimum([cx + ex, cy + ey], [W, H])
            if (hi > lo).all():
                self.box = np.r_[lo, hi - lo].astype(float)
        self._learn(cells)
        return self.box.copy()


class ColourParticleTracker(ColourTracker):
    """CONDENSATION with the colour model of :class:`ColourTracker` (see the module).

    Parameters
    ----------
    n_particles : int
        Particles of ``(cx, cy, log scale)``.
    step : float
        Standard deviation of the random walk of the centre per frame, as a fraction of the
        box's size; the log scale walks with a quarter of it.
    sharpness : float
        ``λ`` of the likelihood ``exp(λ · contrast)``, the contrast being the mean
        back-projection (0–1) inside the box minus that in the ring around it.
    rng : numpy.random.Generator, int or None
        Random generator or seed; each start draws afresh from it (an integer seed gives the
        same boxes again).
    **kwargs
        Passed to :class:`ColourTracker` (``bins``, ``rate``).

    References
    ----------
    .. [1] P. Pérez, C. Hue, J. Vermaak and M. Gangnet, "Color-based probabilistic tracking",
       *European Conference on Computer Vision*, 2002.
    .. [2] M. Isard and A. Blake, "CONDENSATION: conditional density propagation for visual
       tracking", *International Journal of Computer Vision* 29(1), 1998.

    Examples
    --------
    >>> def image(x):
    ...     im = np.full((60, 80, 3), (40, 120, 40), np.uint8); im[20:40, x:x + 20] = (0, 0, 255)
    ...     return im
    >>> t = ColourParticleTracker(rng=0)
    >>> t.init(image(30), [30, 20, 20, 20])
    >>> [t.update(image(x)).round().tolist()[0] for x in (33, 36, 39)]
    [33.0, 36.0, 39.0]
    """

    def __init__(self, n_particles: int = 300, step: float = 0.15, sharpness: float = 30.0,
                 rng: np.random.Generator | int | None = 0, **kwargs: Any):
        if "scales" in kwargs:  # (taken and never used: the particles carry the size)
            raise TypeError("ColourParticleTracker takes no scales: its particles' sizes are "
                            "its own (bins and rate go to ColourTracker)")
        super().__init__(**kwargs)
        # an infinite sharpness gave NaN boxes, a NaN step an IndexError
        self.n = as_whole(n_particles, "n_particles", 1)
        # at most 100 box sizes a frame (a step of 1000 overflowed the log scale's walk, and
        # the boxes' sums then failed in an IndexError, the particles moved)
        self.step_size = as_finite(step, "step", 0.0, high=100.0)
        self.sharpness = as_finite(sharpness, "sharpness", 0.0)
        if not (rng is None or isinstance(rng, np.random.Generator) or is_whole(rng, 0)):
            # (True was seed 1; -1, 1.5 or "a" failed at init() in numpy's words)
            raise ValueError(f"rng must be a numpy Generator, a whole-number seed >= 0 or "
                             f"None; got {rng!r}")
        # a seed of 3.0 is seed 3 (numpy's SeedSequence refused the float at init())
        self._seed = rng if rng is None or isinstance(rng, np.random.Generator) else int(rng)

    def _start(self, image: np.ndarray, box: np.ndarray) -> None:
        super()._start(image, box)  # first: an image refused leaves the tracker as it was
        # each start draws afresh from the seed (an integer seed: the same boxes again)
        self.rng = np.random.default_rng(self._seed)
        b = self.box
        self.size = b[2:].copy()
        self.x = np.tile([b[0] + b[2] / 2, b[1] + b[3] / 2, 0.0], (self.n, 1))
        self.w = np.full(self.n, 1.0 / self.n)

    def anchor(self, box: ArrayLike) -> None:
        """Shift and scale the particle cloud so that its mean box is ``box``.

        Parameters
        ----------
        box : (4,) array_like
            The box ``x, y, w, h``.

        Examples
        --------
        >>> t = ColourParticleTracker()
        >>> t.init(np.zeros((60, 80, 3), np.uint8), [30, 20, 20, 20])
        >>> t.anchor([40, 20, 20, 20])
        >>> (t.w @ t.x).round(3).tolist()  # the weighted mean centre and log scale
        [50.0, 30.0, 0.0]
        """
        self._need_start("anchor")
        b = as_box(box)
        m = self.w @ self.x
        self.x[:, :2] += b[:2] + b[2:] / 2 - m[:2]
        # the box's own shape: the particles' sizes are scales of it (the area's root alone
        # was carried, and a cloud anchored at 40 x 10 reported 20 x 20 at the next frame;
        # b[2] b[3] overflowed at 1e200, a NaN box)
        self.size = b[2:].copy()
        self.x[:, 2] -= m[2]
        self.box = b

    def _follow(self, image: np.ndarray) -> np.ndarray:
        import cv2

        from ..filters import resample
        from ..filters.particle import _ess

        cells = self._cells(image)
        bp = self._backproject(cells)
        integral = cv2.integral(bp.astype(np.float64) / 255.0)
        # predict: a random walk in centre and log scale
        sz = self.size * np.exp(self.x[:, 2:3])
        self.x[:, :2] += self.rng.standard_normal((self.n, 2)) * self.step_size * sz
        self.x[:, 2] += self.rng.standard_normal(self.n) * self.step_size / 4
        # sizes from a pixel to four times the image (the log scale's walk is unbounded: a
        # large step overflowed it over a few frames)
        H, W = image.shape[:2]
        np.clip(self.x[:, 2], np.log(1.0 / self.size.min()),
                np.log(4.0 * max(H, W) / self.size.max()), out=self.x[:, 2])
        # weigh
        sz = self.size * np.exp(self.x[:, 2:3])
        boxes = np.c_[self.x[:, :2] - sz / 2, sz]
        contrast = _contrast(integral, boxes)
        logw = np.log(self.w) + self.sharpness * contrast
        w = np.exp(logw - logw.max())
        self.w = w / w.sum()
        m = self.w @ self.x
        s = self.size * np.exp(m[2])
        self.box = np.r_[m[:2] - s / 2, s]
        # resample when the effective sample size is below half
        if _ess(self.w) < 0.5 * self.n:
            idx = resample(self.w, "systematic", rng=self.rng)
            self.x, self.w = self.x[idx], np.full(self.n, 1.0 / self.n)
        self._learn(cells)
        return self.box.copy()


# the least w and h (whole pixels) OpenCV's trackers start on: CSRT fails on 1, KCF on 0
_OPENCV_LEAST = {"csrt": 2, "kcf": 1}


class OpenCVTracker(SingleObjectTracker):
    """OpenCV contrib's CSRT or KCF behind the same interface (for comparison).

    Boxes are rounded to whole pixels when the tracker starts; where OpenCV's tracker
    reports a failure, raises its own error in an update, or reports a box of no width or
    height, the last box is kept. It has no ``anchor``, so it cannot be a member
    of :class:`~vistrack.tracking.compose.Composite`.

    Parameters
    ----------
    kind : {"csrt", "kcf"}
        OpenCV's ``TrackerCSRT`` or ``TrackerKCF``.

    Raises
    ------
    ValueError
        If ``kind`` is neither; from :meth:`init`, if the image is not 8-bit grey or BGR,
        the box's width or height is less than OpenCV's least once rounded (2 pixels for
        CSRT, 1 for KCF), or OpenCV's tracker cannot start on it (CSRT cannot on small boxes
        at the image's right or bottom edge), the message naming the box.

    Examples
    --------
    >>> import cv2
    >>> rng = np.random.default_rng(0)
    >>> scene = cv2.GaussianBlur(rng.integers(0, 256, (120, 160, 3), dtype=np.uint8), (0, 0), 2)
    >>> t = OpenCVTracker("csrt")
    >>> t.init(scene, [40, 30, 40, 40])
    >>> t.update(np.roll(scene, (1, 3), axis=(0, 1))).shape
    (4,)
    >>> t.init(scene, [40, 30, 1.4, 3])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: box (x, y, w, h) = (40, 30, 1.4, 3), whole pixels (40, 30, 1, 3): OpenCV's ...
    """

    def __init__(self, kind: str = "csrt"):
        import cv2

        makers: dict[str, Callable[[], cv2.Tracker]] = {"csrt": cv2.TrackerCSRT.create,
                                                        "kcf": cv2.TrackerKCF.create}
        if kind not in makers:
            raise ValueError(f"kind must be one of {sorted(makers)}; got {kind!r}")
        self.kind, self._make = kind, makers[kind]

    def _image(self, image: np.ndarray) -> np.ndarray:
        import cv2

        im = as_uint8_image(image, channels=(1, 3))
        # KCF on grey frames failed in OpenCV on its second update ("empty matrix")
        return cv2.cvtColor(im, cv2.COLOR_GRAY2BGR) if self.kind == "kcf" and im.ndim == 2 \
            else im

    def _start(self, image: np.ndarray, b: np.ndarray) -> None:
        import cv2

        # OpenCV's own failures on another kind of image read as the box's (CSRT on float
        # pixels: "cannot start there: 'depth' is 6")
        image = self._image(image)
        r = tuple(int(round(v)) for v in b)
        where = (f"box (x, y, w, h) = ({', '.join(f'{v:g}' for v in b)}), whole pixels "
                 f"({', '.join(str(v) for v in r)})")
        least = _OPENCV_LEAST[self.kind]
        if min(r[2:]) < least:
            # smaller, OpenCV's tracker fails inside with an assertion (OpenCV 5.0)
            raise ValueError(f"{where}: OpenCV's {self.kind} needs w and h of at least "
                             f"{least} whole pixel{'s' if least > 1 else ''}")
        tracker = self._make()
        try:
            tracker.init(image, r)
        except cv2.error as e:
            # e.g. CSRT on a small box at the image's right or bottom edge
            reason = str(e).strip().splitlines()[-1].split("error: ", 1)[-1]
            raise ValueError(f"{where}: OpenCV's {self.kind} cannot start there: {reason}") from e
        self._t = tracker
        self.box = b

    def _follow(self, image: np.ndarray) -> np.ndarray:
        import cv2

        try:
            ok, b = self._t.update(self._image(image))
        except cv2.error:
            # (CSRT's window past a small image's edge: OpenCV's assertion in copyMakeBorder,
            # a traceback from track-one) a failure, as OpenCV's own report of one
            ok, b = False, None
        # a box of no size reported as found (KCF's [0, 0, 0, 0] on a 3 x 1 box) is a failure
        # too: it was taken, and written
        if ok and b is not None and b[2] > 0 and b[3] > 0:
            self.box = np.asarray(b, float)
        return self.box.copy()


METHODS: Registry[Callable[[], SingleObjectTracker]] = Registry("single-object method", {
    "klt": MedianFlow,
    "template": TemplateTracker,
    "colour": ColourTracker,
    "camshift": CamShiftTracker,
    "particle": ColourParticleTracker,
    "wsl": WSLTracker,
    "snake": SnakeTracker,
    "meanshift": lambda: ColourTracker(scales=(1.0,)),
    "csrt": lambda: OpenCVTracker("csrt"),
    "kcf": lambda: OpenCVTracker("kcf"),
})
"""Single-object trackers by name."""


def single_tracker(method: str = "template") -> SingleObjectTracker:
    """A single-object tracker by name in :data:`METHODS`.

    Parameters
    ----------
    method : str
        A name in :data:`METHODS` (see the module).

    Returns
    -------
    SingleObjectTracker
        A new tracker, with its default settings.

    Raises
    ------
    ValueError
        If ``method`` is not in :data:`METHODS`.

    Examples
    --------
    >>> type(single_tracker("meanshift")).__name__, single_tracker("meanshift").scales
    ('ColourTracker', (1.0,))
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {sorted(METHODS)}; got {method!r}")
    return METHODS[method]()

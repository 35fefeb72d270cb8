r"""Blobs: the seeds' blob tracker front-end (UCSD CSE 252A, "Example: blob tracker").

From a binary image (a threshold of the frame, or a background model's foreground mask):

1. clean it with morphological opening and closing;
2. find the connected regions (OpenCV's connected components, 8-connected);
3. take each region's moments: area ``m00``, centroid ``(m10, m01) / m00`` and the covariance of
   its pixel coordinates (the central second moments over ``m00``); the covariance's
   eigen-decomposition gives the equivalent ellipse (axes ``2 √λ``, which is the ellipse of
   the same second moments) and its orientation;
4. keep the regions within the size limits, as :class:`Blobs`, and as
   :class:`~vistrack.types.Detections` (points or boxes) for the trackers.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .._jit import njit
from .._prebuilt import kernel
from .._validate import as_flag, as_number, as_whole, bgr_to_grey, is_whole
from ..types import Detections

if TYPE_CHECKING:
    from collections.abc import Iterable

    from numpy.typing import ArrayLike

__all__ = ["Blobs", "BlobDetector", "find_blobs", "threshold"]


@dataclass(frozen=True)
class Blobs:
    """Regions of one frame, as columns: ``centroids (N, 2)`` (x, y), ``covs (N, 2, 2)`` of
    the pixel coordinates, ``areas (N,)`` in pixels, ``boxes (N, 4)`` (``x0, y0, x1, y1``,
    bounding the pixels), and the equivalent ellipses' ``axes (N, 2)`` (semi-major, semi-minor)
    and ``angles (N,)`` (radians, of the major axis from +x towards +y, in [-π/2, π/2)).

    What :func:`find_blobs` returns; ``len()`` is the number of regions.

    Attributes
    ----------
    centroids : (N, 2) ndarray
        Centroids ``x, y`` (pixel centres at integer coordinates).
    covs : (N, 2, 2) ndarray
        Covariances of the regions' pixel coordinates.
    areas : (N,) ndarray
        Pixel counts.
    boxes : (N, 4) ndarray
        Bounding boxes ``x0, y0, x1, y1`` (``x1, y1`` one past the last pixel).
    axes : (N, 2) ndarray
        Semi-axes of the equivalent ellipses, ``2 √λ`` of the covariance's eigenvalues,
        major first.
    angles : (N,) ndarray
        Orientation of the major axis, radians from +x towards +y, in [-π/2, π/2) (an axis
        has no direction: one orientation, one angle).

    Examples
    --------
    >>> m = np.zeros((20, 30), np.uint8)
    >>> m[2:6, 3:13] = 255                     # a 10 x 4 bar
    >>> b = find_blobs(m, open_size=0, close_size=0)
    >>> len(b), b.axes.round(2).tolist(), b.angles.round(2).tolist()
    (1, [[5.74, 2.24]], [0.0])
    """

    centroids: np.ndarray
    covs: np.ndarray
    areas: np.ndarray
    boxes: np.ndarray
    axes: np.ndarray
    angles: np.ndarray

    def __len__(self) -> int:
        return int(self.areas.shape[0])

    def detections(self, kind: str = "boxes") -> Detections:
        """As :class:`~vistrack.types.Detections`: ``"boxes"`` or ``"points"`` (centroids);
        scores are 1.

        The two are in the conventions of their kinds, half a pixel apart: a box's corners
        are pixel edges, ``[x0, y0, x1 + 1, y1 + 1]`` for the pixels ``x0..x1, y0..y1`` (as
        MOTChallenge's and OpenCV's boxes count), and a centroid is a mean of pixel indices,
        pixel centres at whole numbers (as image moments and trackpy count). The centre of a
        symmetric blob's box is its centroid plus ``(0.5, 0.5)``.

        Parameters
        ----------
        kind : {"boxes", "points"}
            Detections of the bounding boxes, or of the centroids.

        Returns
        -------
        Detections
            One per region.

        Raises
        ------
        ValueError
            If ``kind`` is neither.

        Examples
        --------
        >>> m = np.zeros((20, 30), np.uint8)
        >>> m[2:6, 3:13] = 255
        >>> b = find_blobs(m, open_size=0, close_size=0)
        >>> b.detections().boxes.tolist(), b.detections("points").points.tolist()
        ([[3.0, 2.0, 13.0, 6.0]], [[7.5, 3.5]])
        """
        if kind == "boxes":
            return Detections(boxes=self.boxes)
        if kind == "points":
            return Detections(points=self.centroids)
        raise ValueError(f"kind must be 'boxes' or 'points'; got {kind!r}")


def threshold(image: ArrayLike, level: float, above: bool = True) -> np.ndarray:
    """A binary mask (uint8, 255 set) of the pixels above (or below) ``level``; colour images
    are compared in grey.

    Parameters
    ----------
    image : (H, W) or (H, W, C) array_like
        Grey, or BGR (``C`` 3) or BGRA (4), converted to grey; no NaN.
    level : float
        The threshold (strict: pixels equal to it are not set).
    above : bool
        Set the pixels above ``level``; False: those below.

    Returns
    -------
    (H, W) uint8 ndarray
        255 where set, 0 elsewhere.

    Raises
    ------
    ValueError
        If ``image`` has another shape or a NaN pixel (neither above nor below any level),
        or ``level`` is NaN.

    Examples
    --------
    >>> threshold(np.array([[0, 100], [200, 255]], np.uint8), 150)
    array([[  0,   0],
           [255, 255]], dtype=uint8)
    >>> threshold(np.array([[0, 100], [200, 255]], np.uint8), 150, above=False)
    array([[255, 255],
           [  0,   0]], dtype=uint8)
    """
    if np.isnan(as_number(level, "level")):  # (compared false everywhere: an empty mask)
        raise ValueError(f"level must be a number; got {level}")
    im = np.asarray(image)
    if not (im.ndim == 2 or (im.ndim == 3 and im.shape[2] in (1, 3, 4))):
        # (a 1-D image gave a 1-D mask; two channels failed in OpenCV, naming neither)
        raise ValueError(f"image must be (H, W) grey or (H, W, C) with C 1, 3 (BGR) or 4 "
                         f"(BGRA); got shape {im.shape}")
    _check_no_nan(im, "image")  # (a NaN pixel is neither above nor below: dropped unsaid)
    above = as_flag(above, "above")  # ("False" set the pixels above)
    if im.ndim == 3:
        im = bgr_to_grey(im)
    m = im > level if above else im < level
    return m.astype(np.uint8) * 255


def _check_no_nan(im: np.ndarray, name: str) -> None:
    """A float image's first NaN pixel, named (comparisons take it as neither set nor unset)."""
    if im.dtype.kind in "fc" and np.isnan(im).any():
        at = tuple(int(v) for v in np.argwhere(np.isnan(im))[0])
        raise ValueError(f"{name} must have no NaN; {name}[{', '.join(map(str, at))}] is NaN")


@kernel
@njit(cache=True)
def _moments(labels, n):
    # per label (1..n-1): m00, m10, m01, m20, m11, m02 and the pixel bounds
    s = np.zeros((n, 6))
    lo = np.full((n, 2), np.iinfo(np.int64).max)
    hi = np.full((n, 2), -1)
    H, W = labels.shape
    for y in range(H):
        for x in range(W):
            k = labels[y, x]
            if k == 0:
                continue
            s[k, 0] += 1.0
            s[k, 1] += x
            s[k, 2] += y
            s[k, 3] += x * x
            s[k, 4] += x * y
            s[k, 5] += y * y
            lo[k, 0], lo[k, 1] = min(lo[k, 0], x), min(lo[k, 1], y)
            hi[k, 0], hi[k, 1] = max(hi[k, 0], x), max(hi[k, 1], y)
    return s, lo, hi


def find_blobs(mask: ArrayLike, *, min_area: float = 0, max_area: float = np.inf,
               open_size: int = 3, close_size: int = 5) -> Blobs:
    """Connected regions of a binary ``mask`` (non-zero set) and their moments (see the
    module).

    Parameters
    ----------
    mask : (H, W) array
        Binary: non-zero pixels are set (no NaN); one of no rows or columns, as the
        background models give for such a frame, has no regions.
    min_area, max_area : float
        Limits on a region's pixel count (after the clean-up).
    open_size, close_size : int
        Sizes of the elliptical structuring elements of the opening (removes specks) and then
        the closing (joins a body's pieces); 0 skips one.

    Returns
    -------
    Blobs
        The regions kept, 8-connected, in OpenCV's label order.

    Raises
    ------
    ValueError
        If ``mask`` is not 2-D or holds a NaN, or ``min_area`` or ``max_area`` is NaN, or
        ``max_area`` is below ``min_area`` or 1, or ``min_area`` is infinite.

    Examples
    --------
    >>> m = np.zeros((20, 30), np.uint8)
    >>> m[2:6, 3:13] = 255                     # a 10 x 4 bar
    >>> b = find_blobs(m, open_size=0, close_size=0)
    >>> b.centroids.tolist(), b.areas.tolist(), b.boxes.tolist()
    ([[7.5, 3.5]], [40.0], [[3.0, 2.0, 13.0, 6.0]])
    >>> b.covs[0].round(3).tolist()             # (10² - 1) / 12 and (4² - 1) / 12
    [[8.25, 0.0], [0.0, 1.25]]
    """
    import cv2

    m = np.asarray(mask)
    if m.ndim != 2:
        raise ValueError(f"mask must be 2-D (H, W); got shape {m.shape}")
    _check_no_nan(m, "mask")  # (a NaN is non-zero: it was taken as a set pixel)
    for name, limit in (("min_area", min_area), ("max_area", max_area)):
        if np.isnan(as_number(limit, name)):  # (every region was dropped, without a word)
            raise ValueError(f"{name} must be a number of pixels; got {limit}")
    if max_area < min_area:  # (no region can be both: none was found, without a word)
        raise ValueError(f"max_area must be at least min_area; got max_area {max_area} below "
                         f"min_area {min_area}")
    # (no region is so large, or so small: none was found, without a word; BlobDetector
    # refused them)
    if min_area == np.inf:
        raise ValueError("min_area must be finite: no region has an infinite area; got inf")
    if max_area < 1:
        raise ValueError(f"max_area must be at least 1 pixel, a region's least; got "
                         f"{max_area}")
    # (2.7 was cut to 2, and -3 taken as 0)
    open_size = as_whole(open_size, "open_size", 0, "pixels across; 0 skips it")
    close_size = as_whole(close_size, "close_size", 0, "pixels across; 0 skips it")
    m = (m != 0).astype(np.uint8)
    for opening, size in ((True, open_size), (False, close_size)):
        # (an empty mask, of a frame of no rows, which the background models give for
        # one: OpenCV's assertion, naming nothing; it has no regions)
        if size and size > 1 and m.size:
            k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (int(size), int(size)))
            # OpenCV's erode is the erosion by k, its dilate the dilation by k reflected
            # (each anchored at a): the dilation by k itself is dilate by k reflected, at the
            # reflected anchor. morphologyEx anchors both at size // 2 with k as it is, which
            # for an even size is no opening (or closing): every region moved a pixel down
            # and right, and an opening added pixels
            a, b = int(size) // 2, int(size) - 1 - int(size) // 2
            flipped = np.ascontiguousarray(k[::-1, ::-1])
            if opening:
                m = cv2.dilate(cv2.erode(m, k, anchor=(a, a)), flipped, anchor=(b, b))
            else:
                m = cv2.erode(cv2.dilate(m, flipped, anchor=(b, b)), k, anchor=(a, a))
    n, labels = (cv2.connectedComponents(m, connectivity=8, ltype=cv2.CV_32S) if m.size
                 else (1, np.zeros(m.shape, np.int32)))
    s, lo, hi = _moments(labels, n)
    s, lo, hi = s[1:], lo[1:], hi[1:]
    keep = (s[:, 0] >= min_area) & (s[:, 0] <= max_area) & (s[:, 0] > 0)
    s, lo, hi = s[keep], lo[keep], hi[keep]
    area = s[:, 0]
    c = s[:, 1:3] / area[:, None]
    cxx = s[:, 3] / area - c[:, 0] ** 2
    cxy = s[:, 4] / area - c[:, 0] * c[:, 1]
    cyy = s[:, 5] / area - c[:, 1] ** 2
    covs = np.stack([np.stack([cxx, cxy], -1), np.stack([cxy, cyy], -1)], -2)
    lam, vec = np.linalg.eigh(covs) if len(area) else (np.zeros((0, 2)), np.zeros((0, 2, 2)))
    axes = 2.0 * np.sqrt(np.maximum(lam[:, ::-1], 0.0))
    angles = np.arctan2(vec[:, 1, 1], vec[:, 0, 1]) if len(area) else np.zeros(0)
    # the eigenvector's sign is LAPACK's choice: two blobs of one orientation came out a
    # half-turn apart (an ellipse at 30 degrees as -149.8)
    angles = (angles + np.pi / 2) % np.pi - np.pi / 2
    angles[angles >= np.pi / 2] -= np.pi  # (an angle a rounding below -π/2 came out +π/2)
    boxes = np.c_[lo, hi + 1].astype(float)
    return Blobs(c, covs, area, boxes, axes, angles)


class BlobDetector:
    """The seeds' background subtraction and blobs as a detector: each frame's foreground
    mask from a background model (:func:`~vistrack.frontends.background`), cleaned by an
    opening and a closing, and its connected regions as boxes (score 1).

    A background model needs a still camera, and a start: :meth:`initialize` with the first
    frames (their median); without it the selective model collects its first frames (and
    finds nothing in them) before it starts. Every ``check_view`` frames the detector
    measures how far the view moved since its last check
    (:func:`~vistrack.frontends.view_shift`); once the median of its last five checks is
    ``max_shift`` pixels or more, :attr:`view_moves` is true: the camera moves, and the
    blobs follow the image's motion rather than objects (a run says so). Between frames 10
    apart, still cameras shift the estimate by at most 0.0 pixels on PETS09-S2L1 (people
    walking), 1.0 on trackpy's microscopy clip and 0.2 on OTB's Crossing (the median of five
    checks by at most 0.9), where VOT's bag, filmed from the hand, shifts by 28 in median
    (the median of five checks by 21 or more). A textured object that covers a quarter of a
    still frame moves the median of five checks by 1.6 at most; one that covers a third of
    it or more and crosses it for 30 frames or more (a bus passing near the camera) is taken
    for the view; so is a smaller textured one crossing a scene of faint texture while the
    model starts (the corners followed are then the object's alone): ``follow_view=False``
    where the camera is known to be still.

    Where the view moves, the selective model follows it (``follow_view``; MOG2's state is
    OpenCV's own, and cannot be moved): from then on the detector measures the view's shift
    from each frame to the next and moves the model by it in whole pixels
    (:meth:`~vistrack.frontends.SelectiveBackground.move`; the fractions carried to the next
    frame), each part of the scene that comes into view learning from a few frames before
    anything is found there. The frames that start the model tell already whether the view
    moves (the median of their shifts over ``check_view`` frames is ``max_shift`` or
    more), and then the model starts from their median once each is moved onto the last;
    where the view begins to move later, the model is first moved by how far the view moved
    since it began to (the checks that found it moving: while the view moved unfollowed, the
    scene's edges were foreground, which the selective model does not learn, so what it
    learnt of the scene before stays whole). Only a shift of the whole image is followed: a
    view that turns or zooms is not. On the bundled PETS09-S2L1 clip cropped to 560 × 400 from a
    window that moves 1 pixel a frame (docs/frontends.md) the tracks score 31.3 HOTA against
    the ground truth cropped the same way, where the whole still clip's tracks, cropped,
    score 33.2, and the model that does not follow 17.6.

    Parameters
    ----------
    background : str
        The background model's name (``"selective"``, the seeds' running mean and variance
        updated where no object is, or ``"mog2"``).
    min_area : float
        The smallest blob, in pixels.
    open_size, close_size : int
        Structuring elements of the clean-up (:func:`find_blobs`).
    check_view : int
        Frames between two checks of the view's motion (0: none).
    max_shift : float
        The shift, in pixels between two checks (median of the last five), from which the
        view moves.
    follow_view : bool
        Move the selective model with the view once it moves (above); False: only say so
        (:attr:`view_moves`).

    Attributes
    ----------
    model : SelectiveBackground or MOG2Background
        The background model.
    view_shifts : list of float
        How far the view moved between each two checks, in pixels (``inf`` where the corners
        of one could not be followed into the next; a check of a frame without corners adds
        none).
    view_motion : float or None
        The median of the last five :attr:`view_shifts` (None before five checks): how far
        the view moves between two checks, updated at each check; before five checks, where
        the frames that started the model show the view moving, the median of their shifts
        over ``check_view`` frames.
    following_from : int or None
        The frame (counted from 0, the first given to :meth:`detect` since
        :meth:`initialize`) from which the model follows the view; None while it does not.

    Raises
    ------
    ValueError
        If ``background`` is not a name in :data:`~vistrack.frontends.BACKGROUNDS`.

    Examples
    --------
    >>> frames = [np.full((40, 60), 100, np.uint8) for _ in range(5)]
    >>> det = BlobDetector(min_area=20)
    >>> det.initialize(frames)
    >>> person = frames[0].copy(); person[10:30, 20:30] = 250
    >>> det.detect(person).boxes.tolist()
    [[20.0, 10.0, 30.0, 30.0]]
    """

    def __init__(self, background: str = "selective", *, min_area: float = 500.0,
                 open_size: int = 3, close_size: int = 7, check_view: int = 10,
                 max_shift: float = 4.0, follow_view: bool = True):
        from .background import background as make_background

        if not is_whole(check_view, 0):
            raise ValueError(f"check_view must be a whole number >= 0; got {check_view!r}")
        # (None or "4" failed on "'>' not supported", naming neither)
        if not as_number(max_shift, "max_shift") > 0:
            raise ValueError(f"max_shift must be > 0; got {max_shift}")
        # (-5 was taken; the command line refuses it)
        if not 0 <= as_number(min_area, "min_area") < np.inf:
            raise ValueError(f"min_area must be >= 0 and finite; got {min_area}")
        self.model = make_background(background)
        # (checked here, not at the first frame with a blob: -3 was taken)
        self.open_size = as_whole(open_size, "open_size", 0, "pixels across; 0 skips it")
        self.close_size = as_whole(close_size, "close_size", 0, "pixels across; 0 skips it")
        self.min_area = float(min_area)
        self.check_view, self.max_shift = int(check_view), float(max_shift)
        self.follow_view = as_flag(follow_view, "follow_view")  # ("False" was true)
        self._reset()

    def _reset(self) -> None:
        """The view's checks and its following as before any frame (:meth:`initialize`
        starts again from here)."""
        self.view_shifts: list[float] = []
        self.view_motion: float | None = None
        self.following_from: int | None = None
        self._frames = 0
        self._last_check: np.ndarray | None = None
        # following the view: the frame before, the last frame's place (how far the view's
        # content moved since following began) and the whole pixels the model has moved
        self._prev: np.ndarray | None = None
        self._at, self._moved = np.zeros(2), np.zeros(2)
        self._start: tuple[list[np.ndarray], np.ndarray] | None = None
        self._check_moves: list[tuple[float, float]] = []  # each check's dx, dy (NaN: none)

    @property
    def view_moves(self) -> bool:
        """Whether the view moves: :attr:`view_motion`, the median of the last five
        :attr:`view_shifts`, is ``max_shift`` or more.

        Examples
        --------
        >>> import cv2
        >>> rng = np.random.default_rng(0)
        >>> img = cv2.GaussianBlur(rng.integers(0, 255, (240, 320), np.uint8), (0, 0), 3)
        >>> det = BlobDetector(check_view=1)
        >>> det.initialize([img] * 5)
        >>> for f in range(7):  # a pan of 6 pixels a frame
        ...     _ = det.detect(np.roll(img, 6 * f, axis=1))
        >>> det.view_moves, [round(s) for s in det.view_shifts]
        (True, [6, 6, 6, 6, 6, 6])
        """
        return self.view_motion is not None and self.view_motion >= self.max_shift

    def initialize(self, images: Iterable[np.ndarray]) -> None:
        """Start the background model from ``images`` (an iterable of frames).

        Following the view (the class), where the selective model is given more than
        ``check_view`` frames and their shifts over ``check_view`` frames are ``max_shift``
        or more in median, the frames are moved onto the last before their median is taken,
        and the model follows the view from the first frame :meth:`detect` is given (the
        frame after them, or the first of them again, whose place is known). What earlier
        frames told of the view (its checks, its following) is forgotten: a new start.

        Parameters
        ----------
        images : iterable of ndarray
            Frames ``(H, W)`` grey or BGR, uint8: converted to grey, as :meth:`detect` gives
            them to the model.

        Examples
        --------
        >>> det = BlobDetector()
        >>> det.initialize([np.full((40, 60), 100, np.uint8)] * 5)
        >>> det.model.mean.shape
        (40, 60, 1)
        """
        from .._validate import as_uint8_image

        # grey, as detect gives the model its frames: a BGR start made the selective model
        # refuse the first grey frame, and MOG2 start again on it, learning the people there
        # (copies of the caller's own grey frames: the last is kept as the reference of the
        # next, and drawing on it after this call must not change that)
        frames = [_own(as_uint8_image(im, f"images[{k}]", grey=True), im)
                  for k, im in enumerate(images)]
        # all or nothing: no frames, or frames of two sizes, reset the view's checks and
        # then failed in the model, which kept its state (detector and model disagreed)
        self._all_or_nothing(self._initialize, frames)

    def _all_or_nothing(self, call: Any, *args: Any) -> Any:
        """``call(*args)``, the detector's own state (not its model's, which refuses before
        it changes) as it was if it raises: a refused frame was counted, which moved the
        view's checks by a frame."""
        saved = dict(self.__dict__)
        # the lists only grow in a frame (a start makes new ones): their lengths, not copies,
        # which a long video's checks would make a frame's cost grow with its length
        lengths = {k: len(v) for k, v in saved.items() if isinstance(v, list)}
        try:
            return call(*args)
        except BaseException:
            self.__dict__.clear()
            self.__dict__.update(saved)
            for k, n in lengths.items():
                del self.__dict__[k][n:]
            raise

    def _initialize(self, frames: list[np.ndarray]) -> None:
        from .background import VIEW_MIN, SelectiveBackground, view_shift

        self._reset()  # a new start: what earlier frames said of the view no longer holds
        k = self.check_view
        # (frames too small for view_shift: no view to follow, as detect's checks; they
        # failed here with view_shift's error about frames never given to it)
        if not (self.follow_view and isinstance(self.model, SelectiveBackground) and k
                and len(frames) > k and min(frames[0].shape) >= VIEW_MIN):
            self.model.initialize(frames)
            return
        # the view's shift from each frame to the next (small, so followed reliably where
        # a shift over many frames of a repetitive texture is not), NaN where not followed;
        # no corners to follow: no evidence either way, as detect's checks
        steps, evidence = [], []
        for a, b in zip(frames, frames[1:]):
            dx, dy, followed = view_shift(a, b, refine=True)
            steps.append((dx, dy))
            evidence.append(followed == followed)
        d = np.array(steps)
        # steps not followed (a blank or blurred frame, a flash) bridged where the frames
        # either side of them follow one into the other, the frames between placed on the
        # straight line: else the frames before them had no place, and a run that tracks
        # them again found its first frame's place across all the frames (wrongly)
        unfollowed = np.isnan(d[:, 0])
        i = 0
        while i < len(d):
            if not unfollowed[i]:
                i += 1
                continue
            j = i
            while j < len(d) and unfollowed[j]:
                j += 1
            if j > i + 1 and j < len(d):  # frames i and j, with the frames between
                bridge = view_shift(frames[i], frames[j], refine=True)
                if bridge[0] == bridge[0]:
                    d[i:j] = np.array(bridge[:2]) / (j - i)
                    evidence[i:j] = [True] * (j - i)
            i = j
        # the view's motion over each check_view frames: where the median is max_shift or
        # more, the view moves from the start, and the frames are moved onto the last (by
        # the sum of the steps after them) before their median is taken
        checks = [float(np.hypot(*d[i:i + k].sum(axis=0))) if not np.isnan(d[i:i + k]).any()
                  else np.inf for i in range(len(d) - k + 1) if all(evidence[i:i + k])]
        motion = float(np.median(checks)) if checks else 0.0
        if motion < self.max_shift:
            self.model.initialize(frames)
            return
        self.view_motion = motion
        # the frames after the last step not followed, each moved by the steps after it
        lost = np.flatnonzero(np.isnan(d[:, 0]))
        first = int(lost[-1]) + 1 if len(lost) else 0
        # where each of these frames lies against the last: a run tracks from the first of
        # them again, which may lie further from the last than Lucas-Kanade follows
        places = np.vstack([np.cumsum(d[first:][::-1], axis=0)[::-1], np.zeros((1, 2))])
        self.model.initialize(frames[first:], shifts=np.round(places))
        self.following_from, self._prev = 0, frames[-1]  # the model in the last one's pixels
        self._start = (frames[first:], places)

    def detect(self, image: np.ndarray) -> Detections:
        """The blobs of ``image``'s foreground as boxes ``x0, y0, x1, y1``.

        The image is converted to grey, its foreground mask taken (the model learns from it),
        cleaned and its regions of at least ``min_area`` pixels found.

        Parameters
        ----------
        image : (H, W) or (H, W, 3) ndarray
            The frame, grey or BGR uint8.

        Returns
        -------
        Detections
            One box per blob, score 1.

        Examples
        --------
        >>> det = BlobDetector(min_area=20)
        >>> det.initialize([np.full((40, 60), 100, np.uint8)] * 5)
        >>> person = np.full((40, 60, 3), 100, np.uint8); person[10:30, 20:30] = 250
        >>> d = det.detect(person)
        >>> d.boxes.tolist(), d.scores.tolist()
        ([[20.0, 10.0, 30.0, 30.0]], [1.0])
        """
        from .._validate import as_uint8_image

        grey = _own(as_uint8_image(image, grey=True), image)  # kept as the next's reference
        return cast(Detections, self._all_or_nothing(self._detect, grey))

    def _detect(self, grey: np.ndarray) -> Detections:
        from .background import VIEW_MIN, SelectiveBackground, view_shift

        # (frames under view_shift's least size: not checked, no evidence either way; every
        # 10th frame failed with its error, --still-camera or not)
        if self.check_view and self._frames % self.check_view == 0 \
                and min(grey.shape) >= VIEW_MIN:
            if self._last_check is not None and self._last_check.shape == grey.shape:
                dx, dy, followed = view_shift(self._last_check, grey)
                if followed == followed:  # NaN: no corners to follow, no evidence either way
                    # corners found but not followed: the view changed beyond Lucas-Kanade
                    self.view_shifts.append(float(np.hypot(dx, dy)) if dx == dx else np.inf)
                    self._check_moves.append((dx, dy))
                    last = self.view_shifts[-5:]
                    if len(last) == 5:  # once a check, not once a frame
                        self.view_motion = float(np.median(last))
            self._last_check = grey
        if (self.follow_view and isinstance(self.model, SelectiveBackground)
                and self.following_from is None and self.view_moves
                and self.model.mean is not None):
            # from here the model follows the view, first moved by how far the view moved
            # since it began to: what it learnt of the scene before stays in its place
            # (while the view moved unfollowed, the scene's edges were foreground, and the
            # selective model learnt none of them). How far: this frame against the model's
            # own image, from the checks that found the view moving (which miss the part of
            # a check's interval the view moved in before it moved max_shift in one)
            self.following_from, self._prev = self._frames, grey
            moved = [m for m, size in zip(self._check_moves[-5:], self.view_shifts[-5:])
                     if self.max_shift <= size < np.inf]
            total = np.sum(moved, axis=0) if moved else np.zeros(2)
            here = self._against_model(grey, total)
            self._at = here if here[0] == here[0] else np.round(total)
            self._moved = np.round(self._at)
            if self._moved.any():
                self.model.move(int(self._moved[0]), int(self._moved[1]), grey)
        self._frames += 1
        mask = self._followed(grey) if self._prev is not None else self.model.apply(grey)
        return find_blobs(mask, min_area=self.min_area, open_size=self.open_size,
                          close_size=self.close_size).detections("boxes")

    def _followed(self, grey: np.ndarray) -> np.ndarray:
        """The foreground mask of ``grey``, the model first moved to the view's place in it
        (whole pixels; the fraction left to the next frame): the place of the frame before
        plus the view's shift between them (:func:`~vistrack.frontends.view_shift`, refined
        on the frames themselves: small shifts, which Lucas-Kanade follows on any texture,
        where shifts over many frames of a repetitive one are taken for others)."""
        from .background import SelectiveBackground, view_shift

        assert self._prev is not None and isinstance(self.model, SelectiveBackground)
        start, self._start = self._start, None
        if self._prev is not grey and self._prev.shape == grey.shape:  # (else apply says)
            known = [at for f, at in zip(*start) if np.array_equal(f, grey)] if start else []
            if known:
                # one of the frames that started the model: its place is known (the content
                # moves from the last of them back to it)
                self._at = -np.asarray(known[0], float)
            else:
                d = np.array(view_shift(self._prev, grey, refine=True)[:2])
                if d[0] == d[0]:
                    self._at = self._at + d
                else:
                    # the frame before not followed into this one (it or this one blank,
                    # blurred, a flash): this one against the model's own image, which lies
                    # at the place the model was moved to; where that fails too, it is
                    # taken as still (a step lost had been taken as still for good: the
                    # model kept the error and found the scene's edges ever after)
                    here = self._against_model(grey, self._at - self._moved)
                    if here[0] == here[0]:
                        self._at = self._moved + here
            step = np.round(self._at) - self._moved
            if step.any():
                self.model.move(int(step[0]), int(step[1]), grey)
                self._moved += step
        self._prev = grey
        return self.model.apply(grey)

    def _against_model(self, grey: np.ndarray, guess: np.ndarray) -> np.ndarray:
        """How far ``grey``'s content lies from the selective model's image (its mean, in
        the pixels the model was moved to), looked for from ``guess``; NaN where not
        followed (:func:`~vistrack.frontends.view_shift`)."""
        from .background import SelectiveBackground, view_shift

        assert isinstance(self.model, SelectiveBackground) and self.model.mean is not None
        mean = np.clip(np.rint(self.model.mean[..., 0]), 0, 255).astype(np.uint8)
        return np.array(view_shift(mean, grey, refine=True,
                                   guess=(float(guess[0]), float(guess[1])))[:2])


def _own(grey: np.ndarray, image: np.ndarray) -> np.ndarray:
    """``grey``, copied where it is the caller's ``image`` itself (or a view of it)."""
    return grey.copy() if np.shares_memory(grey, image) else grey

"""Detectors: OpenCV's HOG people detector, and the protocol a user's detector follows.

A detector is any object with ``detect(image) -> Detections``; nothing here downloads weights
(HOG's linear SVM ships inside OpenCV).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

import numpy as np

from .._validate import as_finite, as_float_array
from ..types import Detections

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from numpy.typing import ArrayLike

__all__ = ["Detector", "HOGDetector", "nms", "ConfidenceMap", "HOGConfidence",
           "ConfidencePeaks"]


def nms(boxes: np.ndarray, scores: np.ndarray, max_iou: float,
        classes: np.ndarray | None = None) -> np.ndarray:
    """Greedy non-maximum suppression: indices of the boxes ``(N, 4)`` ``x0, y0, x1, y1``
    kept, best score first; a box overlapping a kept one of its class by more than
    ``max_iou`` is dropped (:func:`vistrack.association.non_maximum`, which drops at
    ``max_iou`` or more, with the next float above ``max_iou``).

    Parameters
    ----------
    boxes : (N, 4) ndarray
        Boxes ``x0, y0, x1, y1``.
    scores : (N,) array_like
        Their scores (ties keep the earlier box first).
    max_iou : float
        The largest IoU with a kept box that a box may have and be kept.
    classes : (N,) array_like of int, optional
        Their classes (default one class): boxes of two classes never suppress each other.

    Returns
    -------
    (K,) int ndarray
        Indices of the boxes kept, in decreasing score.

    Examples
    --------
    >>> boxes = np.array([[0, 0, 10, 10], [1, 1, 11, 11], [20, 20, 30, 30.0]])
    >>> nms(boxes, np.array([0.5, 0.9, 0.1]), 0.5)
    array([1, 2])
    """
    from ..association import non_maximum

    order = np.argsort(-np.asarray(scores), kind="stable")
    # (a NaN kept every box, a string failed in numpy's words)
    max_iou = as_finite(max_iou, "max_iou", 0.0, high=1.0)
    keep = non_maximum(boxes, scores, classes, float(np.nextafter(max_iou, np.inf)))
    return order[keep[order]]


# the person inside HOG's 64x128 window, as in the INRIA data its SVM was trained on: 96 pixels
# tall (75 %) and about 32 wide (50 %)
_INNER_W, _INNER_H = 0.5, 0.75


class Detector(Protocol):
    """What :func:`vistrack.pipeline.track_video` needs of a detector: ``detect(image) ->
    Detections``.

    Any object with that method is a detector for :func:`vistrack.pipeline.run` (which calls
    it on each frame's image, :func:`vistrack.pipeline.as_detector`).

    Examples
    --------
    A detector of the bright pixels' bounding box:

    >>> from vistrack.pipeline import as_detector
    >>> from vistrack.types import Frame
    >>> class Bright:
    ...     def detect(self, image):
    ...         y, x = np.nonzero(image > 128)
    ...         return Detections(boxes=np.array([[x.min(), y.min(), x.max() + 1, y.max() + 1]],
    ...                                          float))
    >>> image = np.zeros((40, 60), np.uint8); image[10:20, 5:15] = 255
    >>> as_detector(Bright())(Frame(1, 0.0, image)).boxes.tolist()
    [[5.0, 10.0, 15.0, 20.0]]
    """

    def detect(self, image: np.ndarray) -> Detections:
        """The detections of one image.

        Parameters
        ----------
        image : ndarray
            The frame's image (``(H, W, 3)`` BGR or ``(H, W)`` grey, uint8).

        Returns
        -------
        Detections
            Its detections.

        Examples
        --------
        >>> HOGDetector().detect(np.zeros((128, 96, 3), np.uint8)).boxes.shape
        (0, 4)
        """
        ...


def bgr_or_grey(image: np.ndarray) -> np.ndarray:
    """An 8-bit grey or BGR image for a detector (OpenCV's HOG, an ONNX model's input),
    which takes no other: a BGRA one (a PNG with transparency) without its alpha; anything
    else a ValueError naming ``image`` (OpenCV's assertion named neither)."""
    from .._validate import as_uint8_image

    im = as_uint8_image(image)
    return np.ascontiguousarray(im[..., :3]) if im.ndim == 3 and im.shape[2] == 4 else im


class HOGDetector:
    """Dalal and Triggs' HOG people detector (OpenCV's default people SVM), with non-maximum
    suppression; boxes are the person inside each detection window (its central 50 % of the
    width and 75 % of the height, as in the INRIA data the SVM was trained on), and scores the
    SVM margins squashed to (0, 1) by a logistic.

    Parameters
    ----------
    scale : float
        Step between pyramid levels.
    hit_threshold : float
        SVM margin below which windows are dropped.
    nms_iou : float
        Overlap above which the weaker of two detections is dropped.
    upscale : float
        Enlarge the image first: the detector's window is 64×128 pixels, so people smaller
        than about 50×100 pixels need it (PETS09's are about 30×80).

    Raises
    ------
    ValueError
        If ``upscale`` is not > 0.

    References
    ----------
    .. [1] N. Dalal and B. Triggs, "Histograms of oriented gradients for human detection",
       *IEEE Conference on Computer Vision and Pattern Recognition*, 2005.

    Examples
    --------
    An empty scene has no people:

    >>> len(HOGDetector().detect(np.zeros((128, 96, 3), np.uint8)))
    0
    """

    def __init__(self, scale: float = 1.05, hit_threshold: float = 0.0, nms_iou: float = 0.4,
                 upscale: float = 2.0):
        import cv2

        self._hog = cv2.HOGDescriptor()
        # the detector comes as a float32 array (asarray keeps it; the stubs say Sequence)
        self._hog.setSVMDetector(np.asarray(cv2.HOGDescriptor.getDefaultPeopleDetector()))
        # a scale of 1 or less, a NaN threshold: no detection at all, without a word
        self.scale = as_finite(scale, "scale", 1.0, above=True)
        self.hit_threshold = as_finite(hit_threshold, "hit_threshold")
        self.nms_iou = as_finite(nms_iou, "nms_iou", 0.0, high=1.0)
        # (infinity was taken, and failed allocating 1.4e19 bytes)
        self.upscale = as_finite(upscale, "upscale", 0.0, above=True)

    def detect(self, image: np.ndarray) -> Detections:
        """The people in ``image``.

        Parameters
        ----------
        image : (H, W, 3) or (H, W) ndarray
            The frame, BGR or grey uint8.

        Returns
        -------
        Detections
            Boxes of the people (in the image's pixels), after non-maximum suppression, with
            scores ``1 / (1 + exp(-margin))``; none where the image, upscaled, is smaller than
            the 64x128 window.

        Examples
        --------
        >>> HOGDetector(upscale=1.0).detect(np.zeros((128, 64, 3), np.uint8)).boxes.shape
        (0, 4)
        >>> len(HOGDetector().detect(np.zeros((40, 100, 3), np.uint8)))  # 80x200 upscaled
        0
        """
        import cv2

        im = bgr_or_grey(image)
        if min(im.shape[:2]) * self.upscale < 1:  # (OpenCV's resize to nothing failed)
            return Detections(boxes=np.zeros((0, 4)))
        if self.upscale != 1.0:
            im = cv2.resize(im, None, fx=self.upscale, fy=self.upscale,
                            interpolation=cv2.INTER_LINEAR)
        win_w, win_h = self._hog.winSize
        if im.shape[0] < win_h or im.shape[1] < win_w:
            # no window fits: nobody to find (OpenCV's search crashed the process on such
            # images, 40x100 at the default upscale, or failed an assertion)
            return Detections(boxes=np.zeros((0, 4)))
        rects, weights = self._hog.detectMultiScale(im, hitThreshold=self.hit_threshold,
                                                    winStride=(8, 8), padding=(8, 8),
                                                    scale=self.scale)
        if len(rects) == 0:
            return Detections(boxes=np.zeros((0, 4)))
        w = np.asarray(weights, float).ravel()
        r = np.asarray(rects, float).reshape(-1, 4) / self.upscale
        # the window holds the person with a margin: keep the central part where INRIA's
        # people stand
        mw, mh = (1 - _INNER_W) / 2, (1 - _INNER_H) / 2
        r = r + np.c_[mw * r[:, 2], mh * r[:, 3], -2 * mw * r[:, 2], -2 * mh * r[:, 3]]
        keep = nms(np.c_[r[:, :2], r[:, :2] + r[:, 2:]], w, self.nms_iou)
        return Detections.from_xywh(r[keep], 1.0 / (1.0 + np.exp(-w[keep])))


def _weighed(w: np.ndarray, s: np.ndarray) -> np.ndarray:
    """``w s``, 0 where the weight is 0: a centre on a cell beside a cell of -inf (no person
    there) scored NaN, 0 times -inf."""
    with np.errstate(invalid="ignore"):
        return np.where(w == 0, 0.0, w * s)


class ConfidenceMap:
    """A detector's continuous confidence over positions and sizes: one grid of scores per
    box height (seed 004, "Tracking based on detector confidence").

    Parameters
    ----------
    heights : (L,) float
        The person-box height of each level, in image pixels.
    scores : list of L arrays (ny, nx)
        Scores at box centres ``origin + stride · (j, i)`` of each level (larger: more
        person-like); for HOG, the SVM margin.
    origins : (L, 2) float
        Image position of each level's first cell.
    strides : (L,) or (L, 2) float
        Image pixels between cells of each level: one for both axes, or along x and y (a
        grid computed on an image resized to whole pixels is stretched a little differently
        along each).
    aspect : float
        Box width over height (default: the person inside HOG's window, 32 / 96).

    Raises
    ------
    ValueError
        If the four have not one entry per level (at least one; ``strides`` one or two
        numbers each), or a level's scores are not a 2-D grid of at least 2 x 2, or hold
        NaN (a cell with no score is ``-inf``).
    TypeError
        If any of the four is not numbers (a string, or booleans).

    Examples
    --------
    One level of 5 x 6 cells with a peak of 2 at cell ``(2, 3)``:

    >>> scores = np.zeros((5, 6)); scores[2, 3] = 2.0
    >>> cmap = ConfidenceMap([100.0], [scores], [(10.0, 20.0)], [8.0])
    >>> float(cmap.score(10 + 8 * 3, 20 + 8 * 2, 100)), float(cmap.score(10 + 8 * 2.5, 36, 100))
    (2.0, 1.0)
    """

    def __init__(self, heights: ArrayLike, scores: Sequence[ArrayLike], origins: ArrayLike,
                 strides: ArrayLike,
                 aspect: float = _INNER_W * 64 / (_INNER_H * 128)):
        # (a string or a boolean failed in numpy's words, or was read as 1 and 0)
        self.heights = as_float_array(heights, "heights", not_boolean="numbers > 0").reshape(-1)
        self.scores = [as_float_array(s, f"scores[{k}]", not_boolean="a grid of numbers")
                       for k, s in enumerate(scores)]
        o = as_float_array(origins, "origins", not_boolean="numbers")
        if o.size % 2 or not np.isfinite(o).all():  # a reshape's message named nothing
            raise ValueError(f"origins must be an x and a y per level, finite; got {o.tolist()}")
        self.origins = o.reshape(-1, 2)
        st = as_float_array(strides, "strides", not_boolean="numbers > 0")
        # (L, 2): x and y; one stride per level serves both
        self.strides = (np.repeat(st.reshape(-1, 1), 2, axis=1) if st.ndim <= 1
                        else st if st.ndim == 2 and st.shape[1] == 2 else st.reshape(-1, 1))
        L = len(self.heights)
        if not (len(self.scores) == L == len(self.origins) == len(self.strides)) or L == 0:
            raise ValueError(f"heights, scores, origins and strides must have one entry per "
                             f"level; got {L}, {len(self.scores)}, {len(self.origins)}, "
                             f"{len(self.strides)}")
        for k, s in enumerate(self.scores):
            if s.ndim != 2 or min(s.shape) < 2:  # (the level and its shape went unnamed)
                raise ValueError(f"each level's scores must be a 2-D grid of at least 2 x 2; "
                                 f"scores[{k}] has shape {s.shape}")
        for k, s in enumerate(self.scores):
            # (a NaN grid was taken and gave no detections without a word; -inf is a cell no
            # window was scored at, as HOGConfidence leaves them)
            if np.isnan(s).any():
                i, j = np.argwhere(np.isnan(s))[0]
                raise ValueError(f"scores[{k}] holds NaN (first at row {i}, column {j}); a "
                                 f"cell with no score is -inf")
        # (a stride of (L, 1) failed at score() with an IndexError, a stride of 0 gave -inf
        # everywhere)
        if self.strides.shape != (L, 2) or not (np.isfinite(self.strides).all()
                                                 and (self.strides > 0).all()):
            raise ValueError(f"strides must be one number > 0 per level, or an x and a y per "
                             f"level, shape ({L}, 2); got {st.tolist()}")
        if not (np.isfinite(self.heights).all() and (self.heights > 0).all()):
            raise ValueError(f"heights must be finite and > 0; got {self.heights.tolist()}")
        # (-1 was taken, and detections() failed naming the boxes' widths)
        self.aspect = as_finite(aspect, "aspect", 0.0, above=True)

    def level(self, h: ArrayLike) -> np.ndarray:
        """Index of the level nearest each height (in log height).

        Parameters
        ----------
        h : float or array_like
            Box heights (image pixels).

        Returns
        -------
        int ndarray
            The level of each, of ``h``'s shape; -1 for a NaN height, which has none (it was
            level 0, and scored there).

        Examples
        --------
        >>> cmap = ConfidenceMap([50.0, 100.0], [np.zeros((2, 2))] * 2, [(0, 0)] * 2, [8, 8])
        >>> cmap.level([40, 70, 71, 300, np.nan]).tolist()
        [0, 0, 1, 1, -1]
        """
        h = np.asarray(h, float)
        lev = np.abs(np.log(np.maximum(h, 1e-6))[..., None]
                     - np.log(self.heights)).argmin(-1)
        return np.where(np.isnan(h), -1, lev)

    def score(self, x: ArrayLike, y: ArrayLike, h: ArrayLike,
              outside: float = -np.inf) -> np.ndarray:
        """The score at box centres ``(x, y)`` and heights ``h`` (broadcast together),
        bilinear in position on the level nearest in height; ``outside`` beyond the grid.

        Parameters
        ----------
        x, y : float or array_like
            Box centres (image pixels).
        h : float or array_like
            Box heights; each picks the level nearest in log height (:meth:`level`).
        outside : float
            The score of a centre beyond its level's grid.

        Returns
        -------
        ndarray
            The scores, of the broadcast shape of ``x``, ``y`` and ``h``.

        Examples
        --------
        >>> scores = np.zeros((5, 6)); scores[2, 3] = 2.0
        >>> cmap = ConfidenceMap([100.0], [scores], [(10.0, 20.0)], [8.0])
        >>> cmap.score([34.0, 30.0, 0.0], 36.0, 100.0)
        array([  2.,   1., -inf])
        """
        x, y, h = np.broadcast_arrays(*(np.asarray(v, float) for v in (x, y, h)))
        lev = self.level(h)
        out = np.full(x.shape, outside, float)
        for k, s in enumerate(self.scores):
            sel = lev == k
            if not sel.any():
                continue
            u = (x[sel] - self.origins[k, 0]) / self.strides[k, 0]
            v = (y[sel] - self.origins[k, 1]) / self.strides[k, 1]
            ny, nx = s.shape
            # (a centre on the grid's edge, the cell's own, is inside to within rounding:
            # 1e-9 of a cell; it was -inf where (x - origin) / stride came to 16 + 4e-15)
            e = 1e-9
            ok = (u >= -e) & (u <= nx - 1 + e) & (v >= -e) & (v <= ny - 1 + e)
            j0 = np.clip(np.floor(u).astype(int), 0, nx - 2)
            i0 = np.clip(np.floor(v).astype(int), 0, ny - 2)
            # (within the edge's allowance u - j0 can pass 1 by rounding, and a weight of
            # -2e-16 on a -inf cell gave +inf)
            fu, fv = np.clip(u - j0, 0.0, 1.0), np.clip(v - i0, 0.0, 1.0)
            val = (_weighed(1 - fv, _weighed(1 - fu, s[i0, j0]) + _weighed(fu, s[i0, j0 + 1]))
                   + _weighed(fv, _weighed(1 - fu, s[i0 + 1, j0])
                              + _weighed(fu, s[i0 + 1, j0 + 1])))
            out[sel] = np.where(ok, val, outside)
        return out

    def detections(self, threshold: float = 0.0, nms_iou: float = 0.4) -> Detections:
        """The discrete detections: cells scoring above ``threshold`` that are the largest of
        their 3 x 3 neighbourhood, over all levels, after non-maximum suppression; scores
        squashed to (0, 1) by a logistic.

        Parameters
        ----------
        threshold : float
            The score a peak must exceed.
        nms_iou : float
            Overlap above which the weaker of two detections is dropped.

        Returns
        -------
        Detections
            A box per peak, centred on its cell, the level's height tall and ``aspect`` times
            that wide; scores ``1 / (1 + exp(-score))``.

        Examples
        --------
        >>> scores = np.zeros((5, 6)); scores[2, 3] = 2.0
        >>> cmap = ConfidenceMap([90.0], [scores], [(10.0, 20.0)], [8.0], aspect=0.5)
        >>> d = cmap.detections(threshold=1.0)
        >>> d.xywh.tolist(), d.scores.round(3).tolist()
        ([[11.5, -9.0, 45.0, 90.0]], [0.881])
        """
        threshold = as_finite(threshold, "threshold")  # (a NaN found nothing)
        nms_iou = as_finite(nms_iou, "nms_iou", 0.0, high=1.0)
        boxes, scores = [], []
        for k, s in enumerate(self.scores):
            pad = np.pad(s, 1, constant_values=-np.inf)
            peak = np.ones(s.shape, bool)
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    if di or dj:
                        peak &= s >= pad[1 + di:1 + di + s.shape[0], 1 + dj:1 + dj + s.shape[1]]
            i, j = np.nonzero(peak & (s > threshold))
            h = self.heights[k]
            w = self.aspect * h
            cx = self.origins[k, 0] + self.strides[k, 0] * j
            cy = self.origins[k, 1] + self.strides[k, 1] * i
            boxes.append(np.c_[cx - w / 2, cy - h / 2, np.full(len(i), w), np.full(len(i), h)])
            scores.append(s[i, j])
        b, sc = np.concatenate(boxes), np.concatenate(scores)
        if len(b) == 0:
            return Detections(boxes=np.zeros((0, 4)))
        keep = nms(np.c_[b[:, :2], b[:, :2] + b[:, 2:]], sc, nms_iou)
        return Detections.from_xywh(b[keep], 1.0 / (1.0 + np.exp(-sc[keep])))


class ImageTooSmall(ValueError):
    """An image smaller than every level of a :class:`HOGConfidence` can hold a grid of
    windows in."""


class HOGConfidence:
    """OpenCV's HOG people detector evaluated densely: every window at a stride of 8 pixels on
    an image resized so that a person of each given box height fills the window, giving a
    :class:`ConfidenceMap` of SVM margins.

    Parameters
    ----------
    heights : sequence of float
        Person-box heights (image pixels) of the levels. The defaults, 46 to 121 pixels,
        resize the image by 2.1 to 0.8 (the range of :class:`HOGDetector`'s pyramid on an
        image enlarged twice); on PETS09-S2L1 (people 55 to 150 pixels tall) they gave
        fewer false detections than levels from 55 to 145 (MOTA 65 against 55 with the
        particle filter).

    Raises
    ------
    ValueError
        If ``heights`` is not a non-empty list of positive numbers; called on an image
        smaller than every level can hold 2 x 2 windows in, :class:`ImageTooSmall` (a
        ``ValueError``).
    TypeError
        If ``heights`` is not numbers (a string, or booleans).

    Notes
    -----
    Call it on an image (grey or BGR uint8) for its :class:`ConfidenceMap`: level ``k`` is
    HOG's SVM margin of every window at a stride of 8 pixels of the image resized by
    ``96 / heights[k]``, with ``origins`` and ``strides`` in the original image's pixels. A
    level whose resized image holds fewer than 2 x 2 windows (the tallest people's, in a
    frame under about 170 pixels high) is left out of the map.

    OpenCV searches one level on one thread; the levels run on as many threads as OpenCV
    uses (``cv2.getNumThreads()``, set by ``cv2.setNumThreads``), the largest first, and
    give the same map, bit for bit, on any number (on two cores, 1.9 times one thread's
    speed: ``bench/bench_hog.py``).

    Examples
    --------
    >>> cmap = HOGConfidence()(np.zeros((240, 320, 3), np.uint8))
    >>> cmap.heights.tolist(), cmap.scores[3].shape, cmap.strides[3].tolist()
    ([46.0, 58.0, 75.0, 96.0, 121.0], (15, 33), [8.0, 8.0])
    """

    def __init__(self, heights: ArrayLike = (46, 58, 75, 96, 121)):
        import cv2

        self.heights = as_float_array(heights, "heights", not_boolean="numbers > 0")
        if self.heights.ndim == 1 and len(self.heights) == 0:  # (said "finite and > 0")
            raise ValueError("heights must hold at least one height; got none")
        if self.heights.ndim != 1 or not (
                np.isfinite(self.heights) & (self.heights > 0)).all():
            # (NaN failed at the first image: "cannot convert float NaN to integer")
            raise ValueError(f"heights must be finite and > 0; got {heights!r}")
        self._hog = cv2.HOGDescriptor()
        # the detector comes as a float32 array (asarray keeps it; the stubs say Sequence)
        self._hog.setSVMDetector(np.asarray(cv2.HOGDescriptor.getDefaultPeopleDetector()))

    def __call__(self, image: np.ndarray) -> ConfidenceMap:
        import cv2

        im = bgr_or_grey(image)
        H, W = im.shape[:2]
        levels = []  # (height, resized width, resized height)
        for h in self.heights:
            f = _INNER_H * 128 / h
            sw, sh = int(round(W * f)), int(round(H * f))
            if sw < 64 + 8 or sh < 128 + 8:
                # fewer than 2 x 2 windows fit the resized image: no grid to interpolate
                # (the tallest people's levels of a small frame); the level is left out
                continue
            levels.append((h, sw, sh))
        if not levels:
            raise ImageTooSmall(f"image of {W} x {H} pixels is too small for HOG's levels: "
                                f"the one for people {self.heights.min():g} pixels tall needs "
                                f"{_least_side(72, self.heights.min())} x "
                                f"{_least_side(136, self.heights.min())} or more")

        def margins(level: tuple) -> np.ndarray:
            _, sw, sh = level
            small = cv2.resize(im, (sw, sh), interpolation=cv2.INTER_LINEAR)
            found, w = self._hog.detect(small, hitThreshold=-1e9, winStride=(8, 8),
                                        padding=(0, 0))
            loc = np.asarray(found, float).reshape(-1, 2)
            grid = np.full(((sh - 128) // 8 + 1, (sw - 64) // 8 + 1), -np.inf)
            grid[(loc[:, 1] // 8).astype(int), (loc[:, 0] // 8).astype(int)] = \
                np.asarray(w, float).ravel()
            return grid

        # OpenCV's detect is one thread a call and lets Python's other threads run: the levels
        # (the largest image first) go to as many threads as OpenCV uses (cv2.setNumThreads),
        # each level's margins as they are on one thread
        workers = min(len(levels), max(1, cv2.getNumThreads()))
        if workers > 1:
            from concurrent.futures import ThreadPoolExecutor

            order = sorted(range(len(levels)), key=lambda k: -levels[k][1] * levels[k][2])
            with ThreadPoolExecutor(workers) as pool:
                done = dict(zip(order, pool.map(margins, [levels[k] for k in order])))
            scores = [done[k] for k in range(len(levels))]
        else:
            scores = [margins(level) for level in levels]
        # cell (i, j): the window at (8j, 8i) of the resized image, centred at (8j + 32,
        # 8i + 64), which is ((8j + 32) / fx, (8i + 64) / fy) in the image, by the factors of
        # the resize made (to whole pixels: f itself put the last windows' centres up to 0.4
        # pixel off, and beyond the grid)
        factors = [(sw / W, sh / H) for _, sw, sh in levels]
        return ConfidenceMap(np.array([h for h, _, _ in levels]), scores,
                             [(32 / fx, 64 / fy) for fx, fy in factors],
                             [(8 / fx, 8 / fy) for fx, fy in factors])


def _least_side(pixels: int, height: float) -> int:
    """The least side of an image whose resize for people ``height`` pixels tall is at least
    ``pixels`` across (as :class:`HOGConfidence` rounds it; the ceiling of the exact ratio
    said 66 where 65 served)."""
    f = _INNER_H * 128 / height
    n = max(1, int(np.floor((pixels - 0.5) / f)))
    while int(round(n * f)) < pixels:
        n += 1
    while n > 1 and int(round((n - 1) * f)) >= pixels:
        n -= 1
    return n


class ConfidencePeaks:
    """A detector from a continuous confidence: the peaks of ``confidence(image)`` (a
    :class:`ConfidenceMap`) above ``threshold``, as :meth:`ConfidenceMap.detections` gives
    them.

    Parameters
    ----------
    confidence : callable
        ``image -> ConfidenceMap``, such as :class:`HOGConfidence`.
    threshold : float
        The SVM margin above which a peak is a detection.

    Raises
    ------
    TypeError
        If ``confidence`` is not callable.

    Examples
    --------
    >>> scores = np.zeros((5, 6)); scores[2, 3] = 2.0
    >>> cmap = ConfidenceMap([90.0], [scores], [(10.0, 20.0)], [8.0], aspect=0.5)
    >>> peaks = ConfidencePeaks(lambda image: cmap, threshold=1.0)
    >>> peaks.detect(np.zeros((100, 100), np.uint8)).xywh.tolist()
    [[11.5, -9.0, 45.0, 90.0]]
    """

    def __init__(self, confidence: Callable[[np.ndarray], ConfidenceMap],
                 threshold: float = 0.5):
        if not callable(confidence):
            raise TypeError(f"confidence must be a callable image -> ConfidenceMap; got "
                            f"{type(confidence).__name__}")
        # (a NaN found nothing, without a word)
        self.confidence, self.threshold = confidence, as_finite(threshold, "threshold")

    def detect(self, image: np.ndarray) -> Detections:
        """The peaks of the image's confidence above the threshold.

        Parameters
        ----------
        image : ndarray
            The frame's image, as ``confidence`` takes it.

        Returns
        -------
        Detections
            :meth:`ConfidenceMap.detections` of ``confidence(image)`` above ``threshold``.

        Examples
        --------
        >>> len(ConfidencePeaks(HOGConfidence()).detect(np.zeros((240, 320, 3), np.uint8)))
        0
        """
        try:
            cmap = self.confidence(image)
        except ImageTooSmall:  # as HOGDetector: nothing found in a frame smaller than a person
            return Detections(boxes=np.zeros((0, 4)))
        return cmap.detections(self.threshold)

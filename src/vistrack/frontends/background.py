r"""Background subtraction: the seeds' selective running mean and variance, and OpenCV's MOG2.

:class:`SelectiveBackground` is the model of the seeds (UCSD CSE 252A, "Background image" and
"Segmentation image"), per pixel:

- ``B_0`` is the median of the first ``N`` frames (:meth:`~SelectiveBackground.initialize`);
- the difference ``D_n² = (I_n - B_{n-1})²`` marks a pixel foreground where
  ``D_n² ≥ T σ_{n-1}²``;
- where the pixel is background, the mean and the mean of squares run on,
  ``B_n = (1-α) B_{n-1} + α I_n`` and ``J_n² = (1-α) J_{n-1}² + α I_n²``; elsewhere they keep
  their values (a person standing still is not learnt into the background);
- the variance is ``σ_n² = J_n² - B_n²``.

Two choices the seeds leave open: ``J_0²`` is ``B_0²`` plus a robust variance of the first
``N`` frames, ``(1.4826 · median |I - B_0|)²`` (the median absolute deviation: people who walk
through some of those frames would inflate the plain variance and blind the model where they
walked), and ``σ²`` is floored at ``min_sigma²`` (a pixel that never changed would otherwise
call any change foreground). In colour the test sums over
channels, ``Σ_c D_c² ≥ T Σ_c σ_c²``, which is the seeds' test on grey images.

The selective update has the seeds' blind spot: an object that stands in more than half of the
first ``N`` frames is part of ``B_0``, and when it leaves, the uncovered background is
foreground (a "ghost") that is never learnt, since foreground pixels are not updated. Start
the model on frames where things move, or with more of them.

``freeze=True`` stops learning (the model stays ``B_0``, ``J_0``; pixels that come into
view where the model moves with the view still take their first ``n_new`` frames, having no
model before them); OpenCV's KNN and GSOC
subtractors ignore ``learningRate=0``. Masks are uint8, 255 for foreground, as OpenCV's.

Both models are made for a still camera: where the view moves, every edge of the scene is
foreground and the blobs follow the image's motion rather than objects.
:func:`~vistrack.frontends.view_shift` measures how far the view moved between two frames
(the median motion of corners followed from one to the other), so that a run can say so
(:class:`~vistrack.frontends.BlobDetector` checks it as it goes). The selective model can
follow a view that shifts: :meth:`SelectiveBackground.move` moves it by whole pixels, each
pixel that comes into view learning from its first ``n_new`` frames, and
:meth:`SelectiveBackground.initialize` takes frames of a moving view with their shifts.
MOG2's state is OpenCV's, and cannot be moved.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from .._jit import bind, njit
from .._prebuilt import kernel
from .._registry import Registry
from .._validate import (
    as_finite,
    as_flag,
    as_float_array,
    as_number,
    as_uint8_image,
    as_whole,
    is_whole,
)

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

prange = range  # numba.prange once numba is imported: a parallel loop when compiled
bind(globals(), prange="prange")

__all__ = ["BACKGROUNDS", "MOG2Background", "SelectiveBackground", "background",
           "view_shift"]


@kernel
@njit(cache=True, fastmath=True)
def _selective_grey(img, B, J2, T, min_var, alpha, mask):
    # one thread: it takes 0.14 ms a 640x480 frame, and idle OpenMP threads would spin on the
    # core a video decoder needs. Flat (n,) arrays; branchless, so that the loop vectorises:
    # the learning weight is alpha
    # where the pixel is background and 0 where it is foreground
    # (B + w (I - B) is (1 - w) B + w I)
    for i in range(img.shape[0]):
        v = np.float32(img[i])
        b = B[i]
        d = v - b
        fg = d * d >= T * max(J2[i] - b * b, min_var)
        mask[i] = np.uint8(255) * np.uint8(fg)
        w = np.float32(0.0) if fg else alpha
        B[i] = b + w * d
        J2[i] = J2[i] + w * (v * v - J2[i])


@njit(cache=True, parallel=True, fastmath=True)
def _selective_colour(img, B, J2, T, min_var, alpha, mask):
    # (n, 3) arrays: the test sums over the channels; written out per channel so that the
    # loop vectorises
    for i in prange(img.shape[0]):
        v0, v1, v2 = np.float32(img[i, 0]), np.float32(img[i, 1]), np.float32(img[i, 2])
        b0, b1, b2 = B[i, 0], B[i, 1], B[i, 2]
        d0, d1, d2 = v0 - b0, v1 - b1, v2 - b2
        var = (max(J2[i, 0] - b0 * b0, min_var) + max(J2[i, 1] - b1 * b1, min_var)
               + max(J2[i, 2] - b2 * b2, min_var))
        fg = d0 * d0 + d1 * d1 + d2 * d2 >= T * var
        mask[i] = np.uint8(255) * np.uint8(fg)
        w = np.float32(0.0) if fg else alpha
        B[i, 0], B[i, 1], B[i, 2] = b0 + w * d0, b1 + w * d1, b2 + w * d2
        J2[i, 0] += w * (v0 * v0 - J2[i, 0])
        J2[i, 1] += w * (v1 * v1 - J2[i, 1])
        J2[i, 2] += w * (v2 * v2 - J2[i, 2])


def _moved(a: np.ndarray, dx: int, dy: int, fill: float) -> np.ndarray:
    """``a`` (H, W, ...) with its content moved ``dx`` pixels right and ``dy`` down, the
    pixels it leaves ``fill``."""
    out = np.full_like(a, fill)
    H, W = a.shape[:2]
    if abs(dx) < W and abs(dy) < H:
        out[max(dy, 0):H + min(dy, 0), max(dx, 0):W + min(dx, 0)] = \
            a[max(-dy, 0):H + min(-dy, 0), max(-dx, 0):W + min(-dx, 0)]
    return out


class SelectiveBackground:
    """The seeds' selective running mean/variance background model (see the module).

    Parameters
    ----------
    alpha : float
        Learning rate of the running mean and mean of squares, in (0, 1].
    threshold : float
        ``T``: foreground where ``D² ≥ T σ²`` (25 is five standard deviations).
    n_init : int
        Frames whose median is ``B_0``, when the model initialises itself from the first
        frames given to :meth:`apply`.
    min_sigma : float
        Floor of ``σ``, in grey levels.
    freeze : bool
        Keep the initial model (no learning; but pixels that come into view, :meth:`move`,
        learn their first ``n_new`` frames).
    n_new : int
        For a model that moves with the view (:meth:`move`): the frames a pixel that came
        into view learns from (the mean of each frame that saw it) before it tells
        foreground from background there.

    Attributes
    ----------
    mean : (H, W, C) float32 ndarray or None
        The background ``B`` (None until the model is initialised).
    mean_sq : (H, W, C) float32 ndarray or None
        The running mean of squares ``J²``.

    Raises
    ------
    ValueError
        If ``alpha`` is not in (0, 1], ``threshold`` not > 0, ``n_init`` less than 1,
        ``min_sigma`` not > 0, ``n_new`` not a whole number >= 1, or ``threshold``,
        ``min_sigma²`` or their product 0 or infinite in float32, the model's type.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> frames = [np.clip(100 + rng.normal(0, 2, (40, 60)), 0, 255).astype(np.uint8)
    ...           for _ in range(10)]
    >>> bg = SelectiveBackground(threshold=16).initialize(frames)
    >>> im = frames[0].copy(); im[10:20, 20:30] = 200   # a bright square
    >>> m = bg.apply(im)
    >>> int(m[10:20, 20:30].all()), int(m.sum() // 255)
    (1, 100)
    """

    def __init__(self, alpha: float = 0.02, threshold: float = 25.0, n_init: int = 20,
                 min_sigma: float = 6.0, freeze: bool = False, n_new: int = 3):
        # (None or "25" failed on "'<' not supported", naming no setting)
        if not 0.0 < as_number(alpha, "alpha") <= 1.0:
            raise ValueError(f"alpha must be in (0, 1]; got {alpha}")
        if not 0 < as_number(threshold, "threshold") < np.inf:  # (infinity: nothing found)
            raise ValueError(f"threshold must be > 0 and finite; got {threshold}")
        n_init = as_whole(n_init, "n_init", 1)  # 2.5 was cut to 2, NaN unnamed
        if not is_whole(n_new, 1):
            raise ValueError(f"n_new must be a whole number >= 1; got {n_new!r}")
        if not 0 < as_number(min_sigma, "min_sigma") < np.inf:
            # at 0 a pixel that never changed has σ = 0 and passes D² >= T σ² with D = 0:
            # the whole of a still scene is foreground, and foreground is never learnt; at
            # infinity nothing ever is
            raise ValueError(f"min_sigma must be > 0 and finite (grey levels): at 0 every "
                             f"pixel that never changed is foreground; got {min_sigma}")
        # the model is kept in float32: a value that is 0 or infinite there is as above
        for name, value in (("threshold", threshold), ("min_sigma² (min_sigma squared)",
                                                       float(min_sigma) ** 2)):
            with np.errstate(over="ignore"):
                held = np.float32(value)
            if not 0 < held < np.inf:
                raise ValueError(f"{name} must lie within float32's range (1.4e-45 to "
                                 f"3.4e38), in which the model is kept; got {value:g}")
        with np.errstate(under="ignore", over="ignore"):  # the test's T σ² at the floor
            floor = np.float32(threshold) * np.float32(float(min_sigma) ** 2)
        if not 0 < floor < np.inf:
            raise ValueError(f"threshold × min_sigma² must lie within float32's range (1.4e-45 "
                             f"to 3.4e38), in which the model tests a pixel against T σ²; got "
                             f"{threshold:g} × {float(min_sigma) ** 2:g}")
        self.alpha, self.threshold, self.n_init = float(alpha), float(threshold), int(n_init)
        self.min_sigma, self.n_new = float(min_sigma), int(n_new)
        self.freeze = as_flag(freeze, "freeze")  # ("False" was true)
        self.mean: np.ndarray | None = None  # B (H, W, C) float32
        self.mean_sq: np.ndarray | None = None  # J² (H, W, C) float32
        self._buffer: list[np.ndarray] = []
        # how many frames saw each pixel, where fewer than n_new did (pixels that came into
        # view, move): None where every pixel was seen by all the frames that started it
        self._seen: np.ndarray | None = None

    @staticmethod
    def _as3(image: np.ndarray, name: str = "image") -> np.ndarray:
        im = as_uint8_image(image, name, channels=(1, 3))
        return im[:, :, None] if im.ndim == 2 else im

    def initialize(self, frames: Iterable[np.ndarray],
                   shifts: ArrayLike | None = None) -> SelectiveBackground:
        """``B_0`` = the per-pixel median of ``frames``, ``σ_0`` their median absolute deviation
        from it times 1.4826 (the standard deviation, for Gaussian noise).

        Parameters
        ----------
        frames : iterable of ndarray
            Frames ``(H, W)`` grey or ``(H, W, 3)`` BGR, uint8, all of one size.
        shifts : (N, 2) array_like of int, optional
            For a view that moves: how far each frame's content has moved by the last frame,
            whole pixels ``dx, dy``: what lies at ``(x, y)`` in the frame lies at ``(x + dx,
            y + dy)`` in the last one (the last frame's row ``0, 0``; :meth:`move`'s sense,
            summed over the frames after). Each frame is moved by its row onto the last one's
            pixels, and a pixel takes the median of
            the frames that saw it (the last frame's value where none other did).

        Returns
        -------
        SelectiveBackground
            The model itself, initialised (``J_0² = B_0² + σ_0²``).

        Raises
        ------
        ValueError
            If there are no frames, or ``shifts`` is not one row of two whole numbers for
            each frame, the last ``0, 0``.

        Examples
        --------
        >>> rng = np.random.default_rng(0)
        >>> frames = [np.clip(100 + rng.normal(0, 2, (40, 60)), 0, 255).astype(np.uint8)
        ...           for _ in range(10)]
        >>> bg = SelectiveBackground().initialize(frames)
        >>> bg.mean.shape, round(float(bg.mean.mean()))
        ((40, 60, 1), 100)
        """
        images = [self._as3(f, f"frames[{k}]") for k, f in enumerate(frames)]
        if len(images) == 0:
            raise ValueError("initialize needs at least one frame")
        _one_shape([f.shape for f in images], "frames")
        stack = np.stack(images)
        if shifts is None:
            self.mean = np.median(stack, axis=0).astype(np.float32)
            mad = np.median(np.abs(stack.astype(np.float32) - self.mean), axis=0)
        else:
            d = as_float_array(shifts, "shifts", not_boolean="whole numbers of pixels")
            if d.shape != (len(images), 2):
                raise ValueError(f"shifts must be one row of two whole numbers for each of the "
                                 f"{len(images)} frames; got shape {d.shape}")
            whole = np.isfinite(d) & (d == np.round(d))
            if not whole.all():  # (the right shape was given as the complaint)
                k = int(np.flatnonzero(~whole.all(axis=1))[0])
                raise ValueError(f"shifts must be whole numbers of pixels; shifts[{k}] = "
                                 f"({d[k, 0]:g}, {d[k, 1]:g})")
            if d[-1].any():  # (each row is a shift to the last frame: any other was ignored)
                raise ValueError(f"shifts' last row is the last frame's shift to itself, 0, 0; "
                                 f"got {d[-1, 0]:g}, {d[-1, 1]:g}")
            seen = np.full(stack.shape, np.nan, np.float32)
            for k, (dx, dy) in enumerate(d.astype(np.int64)):
                seen[k] = _moved(stack[k].astype(np.float32), int(dx), int(dy), np.nan)
            seen[-1] = stack[-1]  # the last frame's own pixels: every pixel seen once
            with warnings.catch_warnings():  # (no all-NaN pixel: the last frame sees each)
                warnings.simplefilter("ignore", RuntimeWarning)
                self.mean = np.nanmedian(seen, axis=0).astype(np.float32)
                mad = np.nanmedian(np.abs(seen - self.mean), axis=0)
            count = (~np.isnan(seen[..., 0])).sum(axis=0)
            # seen by fewer than n_new frames: they go on learning as new pixels do
            self._seen = np.minimum(count, self.n_new).astype(np.int32)
            # with too few frames to spread, σ from the floor (as new pixels start)
            mad = np.where(count[..., None] >= 3, mad, np.float32(self.min_sigma / 1.4826))
        var = (1.4826 * mad) ** 2
        # C-ordered: the median keeps the frames' layout, and of column-major frames (as
        # scipy.io.loadmat gives them) apply's flat views were copies, each update lost
        self.mean = np.ascontiguousarray(self.mean)
        self.mean_sq = np.ascontiguousarray(self.mean * self.mean + var, dtype=np.float32)
        self._buffer = []
        if shifts is None:
            self._seen = None
        return self

    def move(self, dx: int, dy: int, image: np.ndarray) -> None:
        """Move the model with the view: the content of the scene moved ``dx, dy`` whole
        pixels (right and down) in the image, so each pixel takes the model of the pixel
        ``dx, dy`` before it. The pixels that come into view start from ``image`` (the
        frame they came into view in: ``B = I``, ``σ = min_sigma``) and then take the mean
        of the first ``n_new`` frames given to :meth:`apply` (this one too, where it is
        given next), finding nothing until then.

        Parameters
        ----------
        dx, dy : int
            The displacement, whole pixels.
        image : (H, W) or (H, W, 3) ndarray
            The frame the model moves to, of the model's size and channels.

        Raises
        ------
        RuntimeError
            If the model is not initialised yet.
        ValueError
            If ``dx`` or ``dy`` is not a whole number, or the image's shape differs from the
            model's.

        Examples
        --------
        >>> bg = SelectiveBackground().initialize([np.arange(12, dtype=np.uint8).reshape(3, 4)])
        >>> bg.move(1, 0, np.full((3, 4), 99, np.uint8))
        >>> bg.mean[..., 0].tolist()
        [[99.0, 0.0, 1.0, 2.0], [99.0, 4.0, 5.0, 6.0], [99.0, 8.0, 9.0, 10.0]]
        """
        if self.mean is None or self.mean_sq is None:
            raise RuntimeError("the model is not initialised yet")
        if not (is_whole(dx) and is_whole(dy)):  # ("a" failed in float(), naming neither)
            raise ValueError(f"dx and dy must be whole numbers of pixels; got {dx!r}, {dy!r}")
        im = self._as3(image)
        if im.shape != self.mean.shape:
            raise ValueError(f"image has shape {im.shape}; the model was built on "
                             f"{self.mean.shape}")
        self.mean = _moved(self.mean, int(dx), int(dy), np.nan)
        self.mean_sq = _moved(self.mean_sq, int(dx), int(dy), np.nan)
        come = np.isnan(self.mean)
        new = im[come].astype(np.float32)  # (those pixels alone, not the whole frame)
        self.mean[come] = new
        self.mean_sq[come] = new ** 2 + np.float32(self.min_sigma ** 2)
        seen = (np.full(im.shape[:2], self.n_new, np.int32) if self._seen is None
                else self._seen)
        # seen by no frame applied yet: they learn from the frames to come before they tell
        # anything apart (apply)
        self._seen = _moved(seen, int(dx), int(dy), 0)

    @property
    def variance(self) -> np.ndarray:
        """``σ² = J² - B²`` (H, W, C), before the floor.

        Raises
        ------
        RuntimeError
            If the model is not initialised yet.

        Examples
        --------
        Frames with noise of standard deviation 2:

        >>> rng = np.random.default_rng(0)
        >>> frames = [np.clip(100 + rng.normal(0, 2, (40, 60)), 0, 255).astype(np.uint8)
        ...           for _ in range(10)]
        >>> bg = SelectiveBackground().initialize(frames)
        >>> bg.variance.shape, round(float(np.sqrt(bg.variance.mean())), 1)
        ((40, 60, 1), 2.0)
        """
        if self.mean is None:
            raise RuntimeError("the model is not initialised yet")
        return self.mean_sq - self.mean * self.mean

    def apply(self, image: np.ndarray) -> np.ndarray:
        """The foreground mask ``(H, W)`` uint8 (255 foreground) of one frame, and the model's
        update. Before the model has ``n_init`` frames (when :meth:`initialize` was not called)
        the frames are collected and the masks are empty.

        Parameters
        ----------
        image : (H, W) or (H, W, 3) ndarray
            The frame, grey or BGR uint8, of the model's size and channels.

        Returns
        -------
        (H, W) uint8 ndarray
            255 where ``D² ≥ T σ²`` (summed over channels), 0 elsewhere.

        Raises
        ------
        ValueError
            If the image's shape differs from the model's.

        Examples
        --------
        Without :meth:`initialize`, the first ``n_init`` frames start the model:

        >>> rng = np.random.default_rng(0)
        >>> frames = [np.clip(100 + rng.normal(0, 2, (40, 60)), 0, 255).astype(np.uint8)
        ...           for _ in range(4)]
        >>> bg = SelectiveBackground(n_init=3, threshold=16)
        >>> [int(bg.apply(f).max()) for f in frames[:3]], bg.mean is None
        ([0, 0, 0], False)
        >>> im = frames[3].copy(); im[10:20, 20:30] = 200
        >>> int(bg.apply(im)[10:20, 20:30].min())
        255
        """
        im = self._as3(image)
        if self.mean is None:
            if self._buffer and im.shape != self._buffer[0].shape:  # named now, not at the stack
                _one_shape([self._buffer[0].shape, im.shape], "image")
            self._buffer.append(im.copy())
            if len(self._buffer) >= self.n_init:
                self.initialize(self._buffer)
            return np.zeros(im.shape[:2], np.uint8)
        assert self.mean_sq is not None  # set together with mean by initialize
        if im.shape != self.mean.shape:
            raise ValueError(f"image has shape {im.shape[:2] + im.shape[2:]}; the model was "
                             f"built on {self.mean.shape}")
        mask = np.empty(im.shape[:2], np.uint8)
        H, W, C = im.shape
        args = (np.float32(self.threshold), np.float32(self.min_sigma ** 2),
                np.float32(0.0 if self.freeze else self.alpha), mask.reshape(-1))
        im = np.ascontiguousarray(im)
        young = None  # the flat indices of the pixels seen by fewer than n_new frames
        if self._seen is not None:
            young = np.flatnonzero(self._seen < self.n_new)
            if len(young):
                before = self.mean.reshape(-1, C)[young]
                before_sq = self.mean_sq.reshape(-1, C)[young]
            else:  # every pixel seen by n_new frames: as a model never moved
                self._seen, young = None, None
        if C == 1:
            _selective_grey(im.reshape(-1), self.mean.reshape(-1), self.mean_sq.reshape(-1),
                            *args)
        else:  # 3 channels (checked by _as3)
            _selective_colour(im.reshape(-1, C), self.mean.reshape(-1, C),
                              self.mean_sq.reshape(-1, C), *args)
        if young is not None and self._seen is not None:
            # pixels seen by fewer than n_new frames (come into view): the mean of every
            # frame that saw them, as yet nothing told apart there (a person who walks in
            # with them is not learnt whole, as taking one frame would)
            seen = self._seen.reshape(-1)
            n = (seen[young] + 1).astype(np.float32)[:, None]
            v = im.reshape(-1, C)[young].astype(np.float32)
            self.mean.reshape(-1, C)[young] = before + (v - before) / n
            self.mean_sq.reshape(-1, C)[young] = before_sq + (v * v - before_sq) / n
            seen[young] += 1
            mask.reshape(-1)[young] = 0
        return mask


class MOG2Background:
    """OpenCV's Gaussian-mixture subtractor (Zivkovic 2004) behind the same interface; shadows
    (marked 127 by OpenCV) count as background.

    Parameters
    ----------
    history : int
        Frames that make the model (OpenCV's ``history``).
    var_threshold : float
        Squared Mahalanobis distance above which a pixel is foreground (OpenCV's
        ``varThreshold``).
    detect_shadows : bool
        Mark shadows (which :meth:`apply` then counts as background).
    freeze : bool
        Stop learning once the model has seen a frame.

    References
    ----------
    .. [1] Z. Zivkovic, "Improved adaptive Gaussian mixture model for background
       subtraction", *International Conference on Pattern Recognition*, 2004.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> frames = [np.clip(100 + rng.normal(0, 2, (40, 60)), 0, 255).astype(np.uint8)
    ...           for _ in range(10)]
    >>> bg = MOG2Background(history=50).initialize(frames)
    >>> im = frames[0].copy(); im[10:20, 20:30] = 200   # a bright square
    >>> m = bg.apply(im)
    >>> int(m[10:20, 20:30].all()), int(m.sum() // 255)
    (1, 100)
    """

    def __init__(self, history: int = 500, var_threshold: float = 16.0,
                 detect_shadows: bool = True, freeze: bool = False):
        import cv2

        # each named (any history and threshold were taken: 0, -5, a NaN)
        history = as_whole(history, "history", 1)
        var_threshold = as_finite(var_threshold, "var_threshold", 0.0, above=True)
        self._settings = (history, var_threshold, as_flag(detect_shadows, "detect_shadows"))
        self._m = cv2.createBackgroundSubtractorMOG2(*self._settings)
        self.freeze = as_flag(freeze, "freeze")
        self._seen = 0
        self._shape: tuple[int, ...] | None = None  # (H, W, C) of the frames learnt from

    def initialize(self, frames: Iterable[np.ndarray]) -> MOG2Background:
        """Start afresh and learn from ``frames`` (each is one step of the mixture's
        learning), as :meth:`SelectiveBackground.initialize` starts its model: what earlier
        frames taught it is forgotten, and frames of another size may start it.

        Parameters
        ----------
        frames : iterable of ndarray
            Frames ``(H, W)`` grey or ``(H, W, 3)`` BGR, uint8.

        Returns
        -------
        MOG2Background
            The model itself.

        Examples
        --------
        >>> bg = MOG2Background().initialize([np.zeros((4, 6), np.uint8)] * 3)
        >>> int(bg.apply(np.zeros((4, 6), np.uint8)).max())
        0
        """
        import cv2

        # (a second start kept the first's mixture and frame size: BlobDetector("mog2")'s
        # initialize, "a new start", refused frames of another size)
        # every frame checked before the new mixture replaces the old one (a frame of
        # another size refused after the first was learnt left a mixture of one frame)
        kept = self._m, self._seen, self._shape
        self._m = cv2.createBackgroundSubtractorMOG2(*self._settings)
        self._seen, self._shape = 0, None
        try:
            for k, f in enumerate(frames):
                self._m.apply(self._same(f, f"frames[{k}]"))
                self._seen += 1
        except BaseException:
            self._m, self._seen, self._shape = kept
            raise
        return self

    def _same(self, image: np.ndarray, name: str = "image") -> np.ndarray:
        # OpenCV starts its mixture afresh on a frame of another size or type, without a word
        # (a frame of zeros of another size, and then nothing was ever foreground again)
        # uint8 as documented: a float frame restarted the mixture too, without a word
        im = as_uint8_image(image, name, channels=(1, 3))
        shape = im.shape if im.ndim == 3 else im.shape + (1,)
        if self._shape is None:
            self._shape = shape
        elif shape != self._shape:
            _one_shape([self._shape, shape], name)
        return im

    def apply(self, image: np.ndarray) -> np.ndarray:
        """The foreground mask ``(H, W)`` uint8 (255 foreground) of one frame, and the model's
        update (none with ``freeze``, after the first frame).

        Parameters
        ----------
        image : (H, W) or (H, W, 3) ndarray
            The frame, grey or BGR uint8.

        Returns
        -------
        (H, W) uint8 ndarray
            255 where OpenCV marks foreground, 0 elsewhere (shadows included).

        Examples
        --------
        >>> bg = MOG2Background()
        >>> bg.apply(np.zeros((4, 6), np.uint8)).shape
        (4, 6)
        """
        # MOG2 honours learningRate=0 (unlike KNN and GSOC), so freezing works after warm-up
        rate = 0.0 if self.freeze and self._seen else -1.0
        m = self._m.apply(self._same(image), learningRate=rate)
        self._seen += 1
        return np.where(m > 200, np.uint8(255), np.uint8(0))


def _one_shape(shapes: list[tuple[int, ...]], name: str) -> None:
    """A ValueError naming ``name`` where the frames' shapes ``(H, W, C)`` differ (numpy's
    "all input arrays must have the same shape" named neither)."""
    first = shapes[0]
    for k, shape in enumerate(shapes[1:], start=1):
        if shape != first:
            what = f"{name}[{k}]" if name == "frames" else name
            raise ValueError(f"{what} is {shape[1]}x{shape[0]} with {shape[2]} channel(s); the "
                             f"model's frames are {first[1]}x{first[0]} with {first[2]}")


BACKGROUNDS: Registry[type] = Registry("background", {"selective": SelectiveBackground,
                                                       "mog2": MOG2Background})
"""Background models by name: ``selective`` (the seeds'), ``mog2`` (OpenCV)."""


def background(name: str = "selective", **kwargs: Any) -> SelectiveBackground | MOG2Background:
    """A background model by name in :data:`BACKGROUNDS`.

    Parameters
    ----------
    name : str
        ``"selective"`` (:class:`SelectiveBackground`) or ``"mog2"``
        (:class:`MOG2Background`).
    **kwargs
        Passed to the model.

    Returns
    -------
    SelectiveBackground or MOG2Background
        A new model.

    Raises
    ------
    ValueError
        If ``name`` is not in :data:`BACKGROUNDS`.

    Examples
    --------
    >>> background("selective", alpha=0.05).alpha
    0.05
    """
    if name not in BACKGROUNDS:
        raise ValueError(f"background must be one of {sorted(BACKGROUNDS)}; got {name!r}")
    return BACKGROUNDS[name](**kwargs)


def _there_and_back(a: np.ndarray, b: np.ndarray, p: np.ndarray, *, levels: int,
                    within: float, guess: np.ndarray | None = None,
                    back: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Points ``p`` (N, 1, 2) of ``a`` followed into ``b`` by pyramidal Lucas-Kanade (from
    ``guess``, or from ``p``) and back into ``a`` (from ``back``, or from where they
    landed): where they landed, and which were followed both ways and came back within
    ``within`` pixels of where they were."""
    import cv2

    def follow(x: np.ndarray, y: np.ndarray, pts: np.ndarray,
               start: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        found, status, _ = cv2.calcOpticalFlowPyrLK(
            x, y, pts, np.empty_like(pts) if start is None else start, winSize=(21, 21),
            maxLevel=levels, flags=0 if start is None else cv2.OPTFLOW_USE_INITIAL_FLOW)
        return found, status

    q, there = follow(a, b, p, guess)
    r, again = follow(b, a, q, back)
    return q, (there[:, 0] == 1) & (again[:, 0] == 1) & (np.hypot(*(r - p)[:, 0].T) < within)


VIEW_MIN = 16
"""The least width and height of the frames :func:`view_shift` compares (pixels)."""


def view_shift(a: np.ndarray, b: np.ndarray, *, width: int = 256, refine: bool = False,
               guess: tuple[float, float] | None = None) -> tuple[float, float, float]:
    """How far the view moved from frame ``a`` to frame ``b``: the median displacement of up
    to 200 corners of ``a`` (Shi-Tomasi) followed into ``b`` by pyramidal Lucas-Kanade and
    back (kept where they come back within a pixel), on copies reduced by a whole factor to
    about ``width`` pixels across, in the frames' pixels.

    The median is the view's motion wherever most corners lie on what stands still: objects
    that move before a still camera do not move it (0.0 pixels between frames 10 apart of
    PETS09-S2L1, people walking), where the phase correlation of the whole image followed
    a textured object covering a sixteenth of a still frame. Translations of a textured
    640 × 480 image (six textures, eight sub-pixel shifts of up to 20 pixels each) are
    found to 0.02 of a pixel at the median and within 0.1 at worst (refined: 0.01 and
    0.1; moved by a cubic warp instead of a bilinear one, 0.04 and 0.07, refined 0.04
    and 0.05).

    Parameters
    ----------
    a, b : (H, W) or (H, W, 3) ndarray
        Two frames of one size, grey or BGR, uint8.
    width : int
        About how many pixels across the reduced copies are (at least 16): fewer is faster
        and coarser.
    refine : bool
        Follow the corners again on the frames themselves, from where the reduced copies
        put them (Lucas-Kanade on two levels, and back within half a pixel), and take their
        median: on copies reduced by 2 or more, sub-pixel estimates lean towards whole
        reduced pixels (a view panned a quarter of a pixel a frame read 0.05 pixel short a
        frame at 640 pixels across, reduced by 2; refined, within 0.02, and shifts over
        10 frames within 0.002). About 1.2 ms more for 640 × 576 frames.
    guess : (float, float), optional
        About how far the view moved (``dx, dy``, pixels): the corners are looked for in
        ``b`` from there, so that a shift further than Lucas-Kanade's reach is found where
        it lies near the guess.

    Returns
    -------
    dx, dy : float
        The displacement of ``b``'s content against ``a``'s, in pixels (positive: to the right
        and down); NaN if fewer than 10 corners were followed (the view changed beyond what
        Lucas-Kanade follows, or there is nothing to follow).
    followed : float
        The share of ``a``'s corners followed into ``b`` and back; NaN if ``a`` has fewer
        than 10 corners (a blank or blurred frame; or a faint scene whose one bright object
        takes Shi-Tomasi's share of the strongest corner above every corner around it).

    Raises
    ------
    ValueError
        If the frames differ in size, either is smaller than 16 pixels on a side,
        ``width`` is not a whole number of at least 16, or ``guess`` is not two finite
        numbers.

    Examples
    --------
    A textured image and the same moved 12 pixels right and 8 up:

    >>> import cv2
    >>> rng = np.random.default_rng(0)
    >>> img = cv2.GaussianBlur(rng.integers(0, 255, (240, 320), np.uint8), (0, 0), 3)
    >>> moved = np.roll(img, (-8, 12), axis=(0, 1))
    >>> dx, dy, followed = view_shift(img, moved)
    >>> round(dx), round(dy), followed > 0.9
    (12, -8, True)

    Moved 90 pixels, further than the corners are followed from where they were; from a
    guess of 80:

    >>> far = np.roll(img, 90, axis=1)
    >>> round(view_shift(img, far)[0]) == 90, round(view_shift(img, far, guess=(80, 0))[0])
    (False, 90)
    """
    import cv2

    a, b = as_uint8_image(a, "a", grey=True), as_uint8_image(b, "b", grey=True)
    if a.shape != b.shape:
        raise ValueError(f"the frames must have one size; got {a.shape[1]}x{a.shape[0]} and "
                         f"{b.shape[1]}x{b.shape[0]}")
    # (a width of 100.0 failed inside OpenCV's resize, and one of NaN was taken)
    width = as_whole(width, "width", 16, "pixels across the reduced copies")
    refine = as_flag(refine, "refine")  # ("no" refined)
    moved = None
    if guess is not None:  # (before the corners: a frame with none returned NaN first)
        try:
            moved = np.asarray(guess, np.float64)
        except (TypeError, ValueError):
            moved = np.full(0, np.nan)
        if moved.shape != (2,) or not np.isfinite(moved).all():
            raise ValueError(f"guess must be two finite numbers, dx and dy; got {guess!r}")
    h, w = a.shape
    if min(h, w) < VIEW_MIN:
        raise ValueError(f"the frames must be at least {VIEW_MIN} pixels on a side; got "
                         f"{w}x{h}")
    s = max(1, min(w // width, h // 16))
    size = (w // s, h // s)
    # the reduction along each axis: s where it divides the size, a little more where not
    # (a 1279-pixel width by 4 is 319 pixels: 4.009 each)
    sx, sy = w / size[0], h / size[1]
    small_a, small_b = (cv2.resize(x, size, interpolation=cv2.INTER_AREA) if s > 1 else x
                        for x in (a, b))
    p = cv2.goodFeaturesToTrack(small_a, 200, 0.01, 7)
    if p is None or len(p) < 10:
        return float("nan"), float("nan"), float("nan")
    if moved is None:
        q, ok = _there_and_back(small_a, small_b, p, levels=3, within=1.0)
    else:
        g = moved.astype(np.float32) / np.array([sx, sy], np.float32)
        q, ok = _there_and_back(small_a, small_b, p, levels=3, within=1.0, guess=p + g,
                                back=p.copy())
    followed = float(ok.mean())
    if ok.sum() < 10:
        return float("nan"), float("nan"), followed
    d = (q - p)[ok, 0]
    dx, dy = float(np.median(d[:, 0]) * sx), float(np.median(d[:, 1]) * sy)
    if refine and s > 1:
        # the corners kept, at the centres of the pixels they stand for, from the estimate
        scale = np.array([sx, sy])
        at = (p[ok] * scale + (scale - 1) / 2).astype(np.float32)
        q1, kept = _there_and_back(a, b, at, levels=1, within=0.5,
                                   guess=at + np.array([dx, dy], np.float32), back=at.copy())
        if kept.sum() >= 10:
            d1 = (q1 - at)[kept, 0]
            dx, dy = float(np.median(d1[:, 0])), float(np.median(d1[:, 1]))
    return dx, dy, followed

r"""Spots: bright (or dark) round features of a known size, for microscopy; the Crocker-Grier
algorithm (J. Colloid Interface Sci. 179, 1996), with trackpy's conventions so that the two
give the same positions.

1. **band-pass**: a Gaussian of ``noise_size`` removes pixel noise, a boxcar of
   ``smoothing_size`` (default ``diameter``) estimates the background (in the image's own
   integer type, as trackpy computes it), which is subtracted;
   values below ``threshold`` become 0; the result is scaled to integers, over the range of
   the image's own integer type (0–65535 for 16 bits), 0–255 for a float image (trackpy's);
2. **local maxima**: pixels equal to the grey dilation over a square inscribed in the circle of
   radius ``separation`` (default ``diameter + 1``; trackpy's square, of side
   ``2 separation / sqrt(2)``), brighter than the ``percentile`` of the image's non-zero
   pixels, and away from the margins;
3. **refine**: the centroid of the band-passed intensity in a disc of radius ``diameter // 2``;
   while it is more than 0.6 pixel off the disc's centre, the disc moves one pixel towards it
   and is measured again (at most ``max_iterations`` measurements, as trackpy counts them:
   ``max_iterations - 1`` moves); ``mass`` is the disc's total band-passed intensity;
4. of each pair of spots closer than ``separation`` the less massive is dropped; so are
   spots with ``mass <= minmass``.

Positions are ``(x, y)`` with the origin at the centre of pixel (0, 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._jit import njit
from .._prebuilt import kernel
from .._validate import as_finite, as_flag, as_number, as_whole, bgr_to_grey, is_whole
from ..types import Detections

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["Spots", "locate"]


@dataclass(frozen=True)
class Spots:
    """Spots of one frame: ``centroids (N, 2)`` (x, y), ``mass (N,)`` (integrated band-passed
    brightness, in the input's grey levels) and ``size (N,)`` (radius of gyration, pixels).

    What :func:`locate` returns; ``len()`` is the number of spots.

    Attributes
    ----------
    centroids : (N, 2) ndarray
        Positions ``x, y``, the origin at the centre of pixel (0, 0).
    mass : (N,) ndarray
        Integrated band-passed brightness, in the input's grey levels.
    size : (N,) ndarray
        Radius of gyration, in pixels.

    Examples
    --------
    >>> s = Spots(np.array([[3.0, 4.0]]), np.array([100.0]), np.array([2.0]))
    >>> len(s), s.detections().points.tolist()
    (1, [[3.0, 4.0]])
    """

    centroids: np.ndarray
    mass: np.ndarray
    size: np.ndarray

    def __len__(self) -> int:
        return int(self.mass.shape[0])

    def detections(self) -> Detections:
        """As point detections (scores 1).

        Returns
        -------
        Detections
            ``points (N, 2)``: the centroids.

        Examples
        --------
        >>> d = Spots(np.array([[3.0, 4.0]]), np.array([100.0]), np.array([2.0])).detections()
        >>> d.points.tolist(), d.scores.tolist()
        ([[3.0, 4.0]], [1.0])
        """
        return Detections(points=self.centroids)


def _disc(r: int) -> np.ndarray:
    y, x = np.ogrid[-r:r + 1, -r:r + 1]
    return ((x / r) ** 2 + (y / r) ** 2 <= 1).astype(np.float64) if r > 0 else np.ones((1, 1))


@kernel
@njit(cache=True)
def _refine(image, coords, r, mask, max_iterations, shift):
    # centre of mass of mask * image around each (row, col) start, moving the disc a pixel at
    # a time towards it while it is more than `shift` off
    H, W = image.shape
    n = coords.shape[0]
    out = np.empty((n, 2))
    mass = np.empty(n)
    rg = np.empty(n)
    for k in range(n):
        cy, cx = coords[k, 0], coords[k, 1]
        py, px = cy, cx  # the disc last measured (where max_iterations runs out, it is the
        # one before the move: its centre of mass, mass and size are reported, as trackpy's)
        my = mx = 0.0
        m = 0.0
        for _ in range(max_iterations):
            py, px = cy, cx
            m = my = mx = 0.0
            for i in range(2 * r + 1):
                for j in range(2 * r + 1):
                    v = mask[i, j] * image[cy - r + i, cx - r + j]
                    m += v
                    my += v * i
                    mx += v * j
            if m > 0:
                my, mx = my / m - r, mx / m - r
            else:
                my = mx = 0.0
            if abs(my) < shift and abs(mx) < shift:
                break
            if my > shift:
                cy += 1
            elif my < -shift:
                cy -= 1
            if mx > shift:
                cx += 1
            elif mx < -shift:
                cx -= 1
            cy = min(max(cy, r), H - 1 - r)
            cx = min(max(cx, r), W - 1 - r)
        # the final disc's mass and radius of gyration
        m = g = 0.0
        for i in range(2 * r + 1):
            for j in range(2 * r + 1):
                v = mask[i, j] * image[py - r + i, px - r + j]
                m += v
                g += v * ((i - r) ** 2 + (j - r) ** 2)
        out[k, 0], out[k, 1] = px + mx, py + my
        mass[k] = m
        rg[k] = np.sqrt(g / m) if m > 0 else 0.0
    return out, mass, rg


def _check_diameter(diameter: int) -> int:
    """``diameter`` as an int, checked: the spots' size in pixels, odd, at least 3.

    Raises
    ------
    ValueError
        If it is not.

    >>> _check_diameter(11)
    11
    """
    # (int() cut 10.5 to 10 and named that, took 9.9 as 9, and failed on NaN naming nothing)
    if not is_whole(diameter, 3) or int(diameter) % 2 == 0:
        raise ValueError(f"diameter must be an odd integer >= 3; got {diameter!r}")
    return int(diameter)


def _inverted(im: np.ndarray) -> np.ndarray:
    """Dark spots made bright: an integer image's values from its type's top, as trackpy's
    (``255 - v`` for 8 bits); a signed image with values below 0 from its own largest value
    instead (``32767 - v`` wrapped round there: a background-subtracted image's dark spots
    became bright rings); a bool image's negation; a float image's from its largest."""
    if im.dtype == bool:
        return ~im
    if im.dtype.kind in "ui" and not (im.dtype.kind == "i" and im.min() < 0):
        return np.iinfo(im.dtype).max - im
    if im.dtype.kind == "i":  # (in its own type, which holds max - min unless it is wide)
        top = int(im.max())
        if top - int(im.min()) > np.iinfo(np.int64).max:  # (int64 would wrap round)
            return float(top) - im.astype(np.float64)
        out = top - im.astype(np.int64)
        return out.astype(im.dtype) if out.max() <= np.iinfo(im.dtype).max else out
    return im.max() - im


def locate(image: ArrayLike, diameter: int, *, minmass: float = 0.0,
           separation: float | None = None, noise_size: float = 1.0,
           smoothing_size: int | None = None, threshold: float | None = None,
           invert: bool = False,
           percentile: float = 64.0, max_iterations: int = 10) -> Spots:
    """Find the spots of a grey image (see the module).

    Parameters
    ----------
    image : (H, W) array
        Grey; colour images are converted.
    diameter : int
        The spots' size in pixels, odd (round up), at least 3.
    minmass : float
        Smallest integrated brightness kept (in the input's grey levels; strictly above it).
    separation : float, optional
        Smallest distance between spots, > 0; default ``diameter + 1``.
    noise_size : float
        Standard deviation of the Gaussian that removes pixel noise, >= 0 (0: none).
    smoothing_size : int, optional
        Side of the boxcar that estimates the background, odd and larger than
        ``noise_size``; default ``diameter``.
    threshold : float, optional
        Band-passed values below it become 0; default 1 grey level for an integer image and
        1/255 for a float one (trackpy's: an image of floats in [0, 1] found no spot at 1).
    invert : bool
        Spots darker than the background: each value taken from the top of an integer
        image's type (as trackpy's), or from the image's largest value where it is a float
        image or holds values below 0.
    percentile : float
        A local maximum must be brighter than this percentile of the band-passed image's
        non-zero pixels.
    max_iterations : int
        Most measurements of the disc in the refinement (>= 0), each but the first after a
        move of one pixel: ``max_iterations - 1`` moves at most, as trackpy counts them. The
        centre of mass of the disc at the local maximum is measured even with 0 (as with 1),
        as trackpy's ``locate`` does.

    Returns
    -------
    Spots
        The spots found.

    Raises
    ------
    ValueError
        If ``image`` is neither ``(H, W)`` nor ``(H, W, C)`` with ``C`` 1, 3 (BGR) or 4
        (BGRA), is empty, holds no real numbers (an object or complex array), or holds NaN
        or infinity,
        ``diameter`` is not an odd integer >= 3, ``noise_size`` is negative, ``separation``
        not > 0, ``smoothing_size`` is not a whole number, is even or not larger than
        ``noise_size``, ``minmass`` or ``threshold`` is not finite (``minmass`` None
        too), ``percentile`` is not in [0, 100], or ``max_iterations`` is not a whole
        number >= 0.
    TypeError
        If ``separation``, ``noise_size``, ``smoothing_size``, ``minmass``, ``threshold``,
        ``percentile`` or ``max_iterations`` is no number (a string, or None but for
        ``minmass``; ``separation`` a pair, one per axis, which is not supported).

    References
    ----------
    .. [1] J. C. Crocker and D. G. Grier, "Methods of digital video microscopy for colloidal
       studies", *Journal of Colloid and Interface Science* 179(1), 1996.

    Examples
    --------
    Two Gaussian spots of standard deviation 2 pixels:

    >>> y, x = np.mgrid[0:64, 0:64]
    >>> im = sum(200 * np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / 8.0)
    ...          for cx, cy in [(20.3, 15.6), (45.0, 40.2)]).astype(np.uint8)
    >>> spots = locate(im, 9)
    >>> spots.centroids.round(1).tolist(), spots.size.round(1).tolist()
    ([[20.3, 15.6], [45.0, 40.2]], [2.0, 2.0])
    """
    from scipy import ndimage

    im = np.asarray(image)
    if im.dtype.kind not in "biuf":
        # (an object or complex array failed deep in the band-pass: "array type dtype('O')
        # not supported")
        raise ValueError(f"image must hold real numbers (integers or floats); got dtype "
                         f"{im.dtype}")
    if im.dtype == np.float16:  # (the band-pass's filters take no half floats)
        im = im.astype(np.float32)
    if im.ndim == 3 and im.shape[2] in (1, 3, 4):  # grey, BGR or BGRA
        im = bgr_to_grey(im)
    if im.ndim != 2:
        # (a one-page stack (1, H, W), as a TIFF reader gives it, was read as BGR: one row
        # of H pixels, and no spot without a word)
        hint = (": a stack of one page? pass image[0]" if im.ndim == 3 and im.shape[0] == 1
                else ": one call a frame for a stack" if im.ndim == 3 else "")
        raise ValueError(f"image must be (H, W), or (H, W, C) with C 1, 3 (BGR) or 4 (BGRA); "
                         f"got shape {im.shape}{hint}")
    if im.size == 0:  # (the band-pass's top failed: "zero-size array to reduction")
        raise ValueError(f"image is empty (shape {im.shape}): no spot can be found in it")
    diameter = _check_diameter(diameter)
    r = diameter // 2
    if isinstance(separation, (tuple, list)) or (
            isinstance(separation, np.ndarray) and separation.ndim > 0):  # (0-d: one number)
        # (trackpy takes one per axis; float() of it said only "not 'tuple'")
        raise TypeError(f"separation must be one number, the same along x and y; got "
                        f"{separation!r}")
    sep = as_finite(diameter + 1 if separation is None else separation, "separation", 0,
                    above=True)
    noise_size = as_number(noise_size, "noise_size")
    if not (np.isfinite(noise_size) and noise_size >= 0):
        raise ValueError(f"noise_size must be a finite number >= 0 (0: no smoothing); got "
                         f"{noise_size}")
    smooth = diameter if smoothing_size is None else as_whole(smoothing_size, "smoothing_size", 1)
    if smooth % 2 == 0 or smooth <= noise_size:
        # (at the default, the diameter: "got None" named no value)
        raise ValueError(f"smoothing_size must be odd and larger than noise_size "
                         f"({noise_size:g}); got {smooth}"
                         + (" (the default, diameter)" if smoothing_size is None else ""))
    for name, value in (("minmass", minmass), ("threshold", threshold)):
        # (NaN: every spot dropped; a minmass of None failed after the whole search)
        if (value is None and name == "minmass") or (
                value is not None and not np.isfinite(as_number(value, name))):
            raise ValueError(f"{name} must be a finite number; got {value}")
    # (None failed in the search, naming no argument; 150 was taken where nothing was lit)
    percentile = as_finite(percentile, "percentile", 0.0, high=100.0)
    # (checked only once a spot was found: a batch failed at the first frame with one)
    max_iterations = as_whole(max_iterations, "max_iterations", 0)
    if im.dtype.kind == "f" and not np.isfinite(im).all():
        # one NaN made the band-pass's top NaN, and every value with it: no spot, no word
        r0, c0 = np.argwhere(~np.isfinite(im))[0]
        raise ValueError(f"image must be finite; image[{r0}, {c0}] = {im[r0, c0]} (a NaN of "
                         "a flat-field division? replace it, e.g. with the image's median)")
    if as_flag(invert, "invert"):
        im = _inverted(im)
    if threshold is None:
        threshold = 1.0 if np.issubdtype(im.dtype, np.integer) else 1.0 / 255
    empty = Spots(np.zeros((0, 2)), np.zeros(0), np.zeros(0))
    # a spot is kept this far from the edges: where no pixel is, there is none (a diameter
    # or separation larger than the image filtered, or built a square of 1.8 TiB, for it)
    margin = max(r, int(sep) // 2 - 1, smooth // 2)
    H, W = im.shape[:2]
    if 2 * margin >= min(H, W):
        return empty
    raw = im.astype(np.float64)
    # 1. band-pass, then integers. As trackpy does, the boxcar of an integer image is
    # taken in its own integer type (each pass rounds)
    import cv2

    if noise_size > 0:
        rad = int(4.0 * noise_size + 0.5)  # the Gaussian truncated at 4 sigma, zero outside
        g = np.exp(-0.5 * np.arange(-rad, rad + 1) ** 2 / noise_size ** 2)
        g /= g.sum()
        # scipy's correlation, rows then columns, zero outside: trackpy's arithmetic to the
        # last bit. OpenCV's separable filter (5 times faster) rounds otherwise, and a value
        # exactly at `threshold` in one is just under it in the other, which moved a few
        # spots of a bright-spot image (invert=False) by up to 1.7 px against trackpy's
        low = ndimage.correlate1d(raw, g, 0, mode="constant")
        low = ndimage.correlate1d(low, g, 1, mode="constant")
    else:  # no smoothing (trackpy's noise_size 0; the Gaussian's weights were NaN)
        low = raw
    back = im.copy()
    for axis in (0, 1):
        ndimage.uniform_filter1d(back, smooth, axis, output=back, mode="nearest")
    bp = low - back.astype(np.float64)
    bp = np.where(bp >= threshold, bp, 0.0)
    # integers as trackpy makes them: the input's own integer type (a 16-bit camera's
    # 0-65535), 0-255 for a float image
    kind = im.dtype if np.issubdtype(im.dtype, np.integer) else np.dtype(np.uint8)
    top = bp.max()
    scale = float(np.iinfo(kind).max) / top if top > 0 else 1.0
    img = scale * bp.clip(min=0.0)
    if kind in (np.uint8, np.uint16, np.int16):
        img = img.astype(kind)
    else:  # OpenCV's dilation takes no wider integers: their values, truncated, as floats
        # (a 64-bit integer's top, 2^63 - 1 as a float, would not fit back into it)
        img = np.floor(img)
    # 2. local maxima
    lit = img[img > 0]
    if lit.size == 0:
        return empty
    floor = np.percentile(lit, percentile)
    # at least 1: below a separation of 0.71 the side was 0, which OpenCV takes as its
    # default 3 x 3 (a square of side 0 dilates nothing, as trackpy's does); at most the
    # side that reaches the whole image from any pixel, as any larger one does (a
    # separation of 1e6 built a square of 1.8 TiB)
    box = min(max(1, int(2 * sep / np.sqrt(2))), 2 * max(H, W) + 1)
    # a flat square's dilation, zero outside the image; for an even side scipy's
    # grey_dilation (trackpy's) reflects the square, so its anchor is (box - 1) // 2
    a = (box - 1) // 2
    dil = cv2.dilate(img, np.ones((box, box), np.uint8), anchor=(a, a),
                     borderType=cv2.BORDER_CONSTANT, borderValue=0)
    rows, cols = np.nonzero((img == dil) & (img > floor))
    ok = (rows >= margin) & (cols >= margin) & (rows <= H - margin - 1) & (cols <= W - margin - 1)
    coords = np.c_[rows[ok], cols[ok]].astype(np.int64)
    if len(coords) == 0:
        return empty
    # 3. refine
    # at least the first disc measured (0 reported the integer maxima themselves)
    moves = max(1, min(max_iterations, 2**62))  # (2**63 overflowed the compiled kernel)
    pos, mass, rg = _refine(img.astype(np.float64), coords, r, _disc(r), moves,
                            0.6)
    # 4. of each pair of spots closer than the separation, the less massive goes (ties: the
    # one whose coordinates over the separation sum less, nearer the origin, as trackpy: the
    # coordinates' own sums, equal where theirs differ in the last bit, kept the other spot
    # of a two-pixel plateau, and its size); then the mass limit
    if len(pos) > 1:
        from scipy.spatial import cKDTree

        scaled = pos / sep
        pairs = cKDTree(scaled).query_pairs(1 - 1e-7, output_type="ndarray")
        if len(pairs):
            a, b = pairs[:, 0], pairs[:, 1]
            drop = np.where(mass[a] > mass[b], b, a)
            tie = mass[a] == mass[b]
            drop[tie] = np.where(scaled[a[tie]].sum(1) > scaled[b[tie]].sum(1), b[tie], a[tie])
            keep = np.ones(len(pos), bool)
            keep[drop] = False
            pos, mass, rg = pos[keep], mass[keep], rg[keep]
    mass = mass / scale
    sel = mass > minmass
    return Spots(pos[sel], mass[sel], rg[sel])

"""Argument checks whose errors name the argument, the expected and the actual shape or value.

Every public function validates user input here, so that a mistake is reported where it was
made (``ValueError: R must have shape (2, 2) or (T=50, 2, 2); got (3, 3)``) instead of
surfacing later as a broadcasting error or a silent NaN.
"""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = [
    "as_box",
    "as_uint8_image",
    "bgr_to_grey",
    "as_float_array",
    "check_finite",
    "check_matrix_stack",
    "check_psd",
    "as_rng",
    "as_measurement_series",
    "check_has_steps",
    "check_prior",
    "check_linear_gaussian",
]


def _fmt_shape(shape: tuple[int, ...]) -> str:
    return "(" + ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def _masked_as_nan(value: np.ma.MaskedArray, name: str) -> np.ndarray:
    """A numpy masked array as a float64 array with NaN at its masked entries (the package's
    missing value), rather than the placeholder values under the mask."""
    try:
        arr = np.ma.getdata(value).astype(np.float64)  # a copy: the caller's data is kept
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name} must be an array of numbers; got {type(value).__name__} of "
                        f"{value.dtype}") from exc
    arr[np.ma.getmaskarray(value)] = np.nan
    return arr


def as_float_array(value: ArrayLike | None, name: str, *,
                   ndim: tuple[int, ...] | None = None,
                   not_boolean: str | None = None) -> np.ndarray:
    """Convert ``value`` to a C-contiguous float64 array, checking its number of dimensions.

    A numpy masked array (``numpy.ma``, pykalman's way of marking missing measurements)
    gives NaN at its masked entries: missing where NaN means missing (measurements), and an
    error naming the entry where values must be finite, instead of the values under the
    mask read as data. With ``not_boolean``, what the values are (``"probabilities"``),
    booleans are refused in those words (:func:`check_not_boolean`) instead of read as 1
    and 0.

    >>> as_float_array([0.5, True], "weights", not_boolean="numbers >= 0")
    Traceback (most recent call last):
    ...
    TypeError: weights must be numbers >= 0; got [0.5, True]
    """
    if not_boolean is not None:
        check_not_boolean(value, name, not_boolean)
    if isinstance(value, np.ma.MaskedArray):
        value = _masked_as_nan(value, name)
    if getattr(getattr(value, "dtype", None), "kind", None) == "c":
        # (numpy cast them to their real parts with a ComplexWarning alone)
        raise TypeError(f"{name} must be real numbers; got complex values "
                        f"({np.asarray(value).dtype})")
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name} must be an array of numbers; got {type(value).__name__}") from exc
    except OverflowError:  # (an int past the largest float: Python's words, naming nothing)
        got = (f"an integer of {value.bit_length()} bits" if isinstance(value, int)
               else f"{value!r:.80}")
        raise ValueError(f"{name} must be numbers a float can hold (up to 1.8e308); got "
                         f"{got}") from None
    if ndim is not None and arr.ndim not in ndim:
        want = " or ".join(f"{d}-D" for d in ndim)
        raise ValueError(f"{name} must be {want}; got shape {_fmt_shape(arr.shape)}")
    if not arr.flags.c_contiguous:  # (np.ascontiguousarray would turn a scalar into 1-D)
        arr = np.ascontiguousarray(arr)
    return arr


def _is_boolean(value: Any) -> bool:
    """Whether ``value`` is a boolean: Python's, numpy's, or a 0-d array of them."""
    return isinstance(value, (bool, np.bool_)) or (
        isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind == "b")


def _is_text(value: Any) -> bool:
    """Whether ``value`` is text: a string, bytes, or an array of them."""
    return isinstance(value, (str, bytes)) or getattr(
        getattr(value, "dtype", None), "kind", None) in ("U", "S")


def check_not_boolean(value: Any, name: str, what: str = "a number or an array of numbers"
                      ) -> None:
    """Raise TypeError where ``value`` is a boolean or text, an array of them, or a list or
    tuple holding one: a flag or a mask passed where numbers belong (numpy reads True as 1),
    or numbers left as text (numpy reads ``"0.5"`` as 0.5).

    >>> check_not_boolean([1.0, True], "dt")
    Traceback (most recent call last):
    ...
    TypeError: dt must be a number or an array of numbers; got [1.0, True]
    >>> check_not_boolean("0.5", "dt")
    Traceback (most recent call last):
    ...
    TypeError: dt must be a number or an array of numbers; got '0.5'
    """
    def bad(v: Any) -> bool:
        return _is_boolean(v) or _is_text(v)

    if bad(value) or getattr(value, "dtype", None) == np.bool_ or (
            isinstance(value, (list, tuple)) and any(
                bad(v) or isinstance(v, (list, tuple)) and any(map(bad, v))
                for v in value)):
        raise TypeError(f"{name} must be {what}; got {value!r:.80}")


def is_number(value: Any) -> bool:
    """Whether ``value`` is one real number, Python's or numpy's (``np.float32(0.5)``), and
    not a boolean, a string, None or an array (where ``0 < value < 1`` raised its own
    error, or took ``True`` for 1)."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not _is_boolean(value)


def is_real(value: Any) -> bool:
    """Whether ``value`` reads as one real number: :func:`is_number`'s, a 0-d numeric array,
    or another number type ``float()`` takes (``Fraction``, ``Decimal``); never a string, a
    boolean or None."""
    if is_number(value):
        return True
    if isinstance(value, (str, bytes)) or value is None or _is_boolean(value) \
            or np.ndim(value) != 0 or getattr(value, "dtype", np.dtype(float)).kind not in "iuf":
        return False
    try:
        float(value)
    except (TypeError, ValueError):
        return False
    return True


def as_number(value: Any, name: str) -> float:
    """``value`` as a float, or a TypeError naming ``name`` (``float()`` names neither). A
    boolean is not a number here (``float(True)`` is 1.0: ``q=True`` was taken as 1); an
    integer past the largest float is infinite (``float()`` raised a bare OverflowError),
    which the caller's range check names."""
    if isinstance(value, (str, bytes)) or _is_boolean(value):
        raise TypeError(f"{name} must be a number; got {value!r}")
    try:
        return float(value)
    except OverflowError:  # an integer past the largest float (10**400): infinite, as named
        return float("inf") if value > 0 else float("-inf")
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a number; got {value!r}") from None


def is_whole(value: Any, minimum: float | None = None) -> bool:
    """Whether ``value`` is a whole number ``>= minimum``: an int, or a float with an
    integral value (Python's or numpy's); not a boolean (``int(True) == True``), a string, NaN
    or infinity (``int()`` of these raised errors that name nothing, or passed)."""
    if isinstance(value, (str, bytes)) or _is_boolean(value):
        return False
    if isinstance(value, (int, np.integer)):  # (float() of 10**400 overflows)
        return bool(minimum is None or value >= minimum)
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        return False
    return math.isfinite(v) and v.is_integer() and (minimum is None or v >= minimum)


def as_whole(value: Any, name: str, minimum: int, what: str = "") -> int:
    """``value`` as an int, or an error naming ``name``: a TypeError for what is no number (a
    string, None), a ValueError for anything else that is not a whole number (a boolean
    too), or is below ``minimum`` (``int()`` would cut 2.5 to 2). ``what`` says what it
    counts (``"frames count from 1"``)."""
    if not (_is_boolean(value) or isinstance(value, (int, np.integer))):
        as_number(value, name)  # (a TypeError for what is no number: a string, None)
    if not is_whole(value, minimum):
        raise ValueError(f"{name} must be a whole number >= {minimum}"
                         f"{f' ({what})' if what else ''}; got {value!r}")
    return int(value)


def as_flag(value: Any, name: str) -> bool:
    """``value`` as a bool: True or False (Python's or numpy's, or a 0-d array of one), or a
    TypeError naming ``name`` (``store_covs="no"`` was true)."""
    if not _is_boolean(value):
        raise TypeError(f"{name} must be True or False; got {value!r}")
    return bool(value)


def as_finite(value: Any, name: str, low: float | None = None, *, above: bool = False,
              high: float | None = None, what: str = "number") -> float:
    """``value`` as a finite float ``>= low`` (``> low`` with ``above``) and ``<= high``, or
    an error naming ``name`` (a NaN setting compared false everywhere and was taken);
    ``what`` it is (``"number of seconds"``)."""
    v = as_number(value, name)
    if not (np.isfinite(v) and (low is None or (v > low if above else v >= low))
            and (high is None or v <= high)):
        limits = [f"{'>' if above else '>='} {low:g}" if low is not None else "",
                  f"<= {high:g}" if high is not None else ""]
        raise ValueError(f"{name} must be a finite {what}{' ' if any(limits) else ''}"
                         f"{' and '.join(x for x in limits if x)}; got {value!r}")
    return v


def as_scales(values: Any, name: str = "scales") -> tuple[float, ...]:
    """``values`` as a tuple of one or more finite numbers > 0 (the relative sizes a
    tracker tries), or a ValueError naming ``name``: a scale of 0 made a box of no size, and
    none kept the prediction for ever."""
    try:  # (1.0 was "'float' object is not iterable", "abc" and None numpy's own words)
        if isinstance(values, (str, bytes)):
            raise TypeError
        scales = tuple(float(as_number(v, name)) for v in values)
    except (TypeError, ValueError):
        scales = ()
    if not scales or not all(np.isfinite(v) and v > 0 for v in scales):
        raise ValueError(f"{name} must be one or more finite positive numbers; got {values!r}")
    return scales


def as_uint8_image(image: ArrayLike, name: str = "image", channels: tuple[int, ...] = (1, 3, 4),
                   grey: bool = False) -> np.ndarray:
    """An 8-bit ``(H, W)`` or ``(H, W, C)`` image, checked; ``grey=True`` converts colour
    (BGR) to grey."""
    im = np.asarray(image)
    if im.dtype != np.uint8 or im.ndim not in (2, 3) or (im.ndim == 3
                                                         and im.shape[2] not in channels):
        raise ValueError(f"{name} must be (H, W) or (H, W, C) uint8 with C in {channels}; got "
                         f"shape {_fmt_shape(im.shape)} {im.dtype}")
    if im.ndim == 3 and (grey or im.shape[2] == 1):
        im = bgr_to_grey(im)  # (one channel: the grey image itself)
    return im


def bgr_to_grey(im: np.ndarray) -> np.ndarray:
    """The grey image of a BGR (or BGRA) ``(H, W, C)`` image of any numeric type: OpenCV's
    conversion where it takes the type (uint8, uint16, float32), otherwise OpenCV's weights
    (0.114 B + 0.587 G + 0.299 R) in float64, rounded back into an integer type (OpenCV
    refuses float64, numpy's own float, and the wider integers). One channel ``(H, W, 1)`` is
    the grey image already (OpenCV's conversion refuses it)."""
    if im.shape[-1] == 1:
        return im[..., 0]
    im = np.ascontiguousarray(im[..., :3])
    if im.dtype in (np.uint8, np.uint16, np.float32):
        import cv2

        return cv2.cvtColor(im, cv2.COLOR_BGR2GRAY)
    g = im.astype(np.float64) @ np.array([0.114, 0.587, 0.299])
    if np.issubdtype(im.dtype, np.integer):
        info = np.iinfo(im.dtype)
        return np.clip(np.rint(g), info.min, info.max).astype(im.dtype)
    return g


def as_rows4(value: ArrayLike, name: str, columns: str) -> np.ndarray:
    """``value`` as float rows ``(N, 4)`` (one row ``(4,)``, or nothing, ``(0,)``, taken as
    such), or a ValueError naming ``name`` and what its ``columns`` are: ``reshape(-1, 4)``
    read a transposed ``(4, N)`` array, or 8 values a row, as other boxes, without a word,
    and an empty ``(3, 0)`` as no rows.

    >>> as_rows4([1, 2, 3, 4], "a", "x0, y0, x1, y1").shape
    (1, 4)
    >>> as_rows4([[1, 2, 3]], "a", "x0, y0, x1, y1")
    Traceback (most recent call last):
    ...
    ValueError: a must be rows (N, 4) of x0, y0, x1, y1; got shape (1, 3)
    >>> as_rows4([], "a", "x0, y0, x1, y1").shape
    (0, 4)
    """
    arr = np.asarray(value, dtype=float)
    if arr.shape in ((0,), (0, 4)):
        return arr.reshape(0, 4)
    if arr.shape[-1:] != (4,) or arr.ndim > 2:
        raise ValueError(f"{name} must be rows (N, 4) of {columns}; got shape {arr.shape}")
    return arr.reshape(-1, 4)


def as_box(box: ArrayLike, name: str = "box") -> np.ndarray:
    """One box ``x, y, w, h`` as 4 finite floats with ``w, h > 0`` within ±2^52 pixels, given
    as 4 numbers or one row of them (``(1, 4)``). A boolean was a coordinate of 1, a complex
    number its real part, and ``[[x, y], [w, h]]`` was flattened into a box."""
    said = f"{name} must be x, y, w, h with w, h > 0"
    if isinstance(box, (str, bytes)):  # ("could not convert string to float", unnamed)
        raise TypeError(f"{said}; got the text {box!r}")
    b = as_float_array(box, name, not_boolean="x, y, w, h: four numbers")
    if b.shape not in ((4,), (1, 4)):
        raise ValueError(f"{said}; got shape {b.shape}")
    b = b.reshape(-1)
    if not np.isfinite(b).all() or b[2] <= 0 or b[3] <= 0:
        raise ValueError(f"{said}; got {b.tolist()}")
    # (as the box trackers' detections: a box of 1e200 crashed OpenCV's warp, the process
    # with it, and areas overflowed to NaN boxes)
    check_in_pixels(b[None], name, got=True)
    return b


MAX_PIXELS = 2.0 ** 52
"""The largest box value (in pixels) the trackers take: beyond it a float no longer holds
every whole pixel, the filters' variances (the squares of the sizes) soon overflow, and so
do the areas of overlaps."""


def check_in_pixels(boxes: np.ndarray, name: str, suffix: str = "", *,
                    got: bool = False) -> None:
    """Raise ``ValueError`` if a row of ``boxes`` (``(N, 4)``) has a value beyond
    :data:`MAX_PIXELS`, naming it (``name[i] = [...]``; ``got [...]`` with ``got``, for one
    box) and then ``suffix``.

    >>> check_in_pixels(np.array([[0, 0, 5, 5], [1e17, 0, 5, 5]]), "boxes")
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: boxes must lie within ±2^52 pixels, ...; boxes[1] = [1e+17, 0.0, 5.0, 5.0]
    """
    if not len(boxes) or not (np.abs(boxes) > MAX_PIXELS).any():
        return  # (NaN is the callers' to name: its max() failed the test, then an IndexError)
    i = int(np.flatnonzero((np.abs(boxes) > MAX_PIXELS).any(axis=1))[0])
    where = "got" if got else f"{name.split()[-1]}[{i}] ="
    raise ValueError(f"{name} must lie within ±2^52 pixels, where a float holds every whole "
                     f"pixel; {where} {boxes[i].tolist()}{suffix}")


def check_finite(arr: np.ndarray, name: str) -> None:
    """Raise ``ValueError`` if ``arr`` has a NaN or an infinite entry, naming the first one."""
    bad = ~np.isfinite(arr)
    if bad.any():
        if np.ndim(arr) == 0:  # (one value was named as "d[] = nan")
            raise ValueError(f"{name} must be finite; got {arr}")
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{name} must be finite; {name}[{', '.join(map(str, idx))}] = {arr[idx]}")


def check_not_infinite(y: np.ndarray, name: str = "y") -> None:
    """Raise ``ValueError`` if a measurement ``y`` has an infinite entry (NaN is a missing
    value), naming the first one: a filter would give NaN means. A few values are checked
    in Python (0.5 us against numpy's 1.9 for two), more with numpy."""
    if any(map(math.isinf, y.flat)) if y.size <= 16 else np.isinf(y).any():
        idx = np.unravel_index(int(np.argmax(np.isinf(y))), y.shape)
        raise ValueError(f"{name} must be finite or NaN (missing); {name}"
                         f"{[int(k) for k in idx]} = {y[idx]}")


def check_matrix_stack(
    value: ArrayLike | None, name: str, rows: int, cols: int, T: int | None = None
) -> np.ndarray:
    """Check a constant matrix ``(rows, cols)`` or a per-step stack ``(T, rows, cols)``.

    Returns a float64 array of shape ``(1, rows, cols)`` or ``(T, rows, cols)``, finite.
    """
    arr = as_float_array(value, name, ndim=(2, 3))
    if arr.ndim == 2:
        arr = arr[None]
    if arr.shape[0] == 0:  # (taken as constant: a model of no steps, failing in numpy later)
        raise ValueError(f"{name} must hold at least one matrix; got shape "
                         f"{_fmt_shape(arr.shape)}")
    ok_rc = arr.shape[1:] == (rows, cols)
    ok_t = arr.shape[0] == 1 or T is None or arr.shape[0] == T
    if not (ok_rc and ok_t):
        want = f"({rows}, {cols})" + (f" or (T={T}, {rows}, {cols})" if T is not None else "")
        got = _fmt_shape(arr.shape if value is None else np.shape(value))
        raise ValueError(f"{name} must have shape {want}; got {got}")
    check_finite(arr, name)
    return arr


def check_symmetric(arr: np.ndarray, name: str) -> np.ndarray:
    """Check that every matrix of a stack ``(..., n, n)`` is symmetric, to a relative
    tolerance of 1e-8 of its largest entry, naming the first entry that is not; returns each
    matrix's scale, that largest entry (1 where all are 0), shaped ``(..., 1, 1)``."""
    # (the largest of no entries, of a (0, 0) matrix, failed in numpy's words)
    scale = np.max(np.abs(arr), axis=(-2, -1), keepdims=True, initial=0.0)
    scale = np.where(scale > 0, scale, 1.0)
    asym = np.abs(arr - np.swapaxes(arr, -1, -2)) > 1e-8 * scale
    if asym.any():
        where = tuple(int(i) for i in np.argwhere(asym)[0])
        raise ValueError(
            f"{name} must be symmetric; {name}{list(where)} = {arr[where]} but its transpose "
            f"entry is {arr[where[:-2] + (where[-1], where[-2])]}"
        )
    return scale


def correlation(S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The correlation matrices ``C = D^-1 S D^-1`` of a stack of covariances ``S (..., n,
    n)``, ``D = diag(S)^(1/2)``, and those standard deviations ``(..., n)`` (0 where a
    variance is 0 or below, whose row and column are then divided by 1): ``S`` without the
    scales of its axes, whose rank and definiteness hold at any units (variances of 1e4 and
    1e-13 beside each other were taken for a singular matrix).

    Examples
    --------
    >>> C, sd = correlation(np.diag([1e4, 1e-12]))
    >>> C.tolist(), sd.tolist()
    ([[1.0, 0.0], [0.0, 1.0]], [100.0, 1e-06])
    """
    sd = np.sqrt(np.clip(np.diagonal(S, axis1=-2, axis2=-1), 0.0, None))
    unit = np.where(sd > 0, sd, 1.0)
    return S / (unit[..., :, None] * unit[..., None, :]), sd


def check_psd(arr: np.ndarray, name: str, *, strict: bool = False) -> None:
    """Check that every matrix of a stack ``(..., n, n)`` is symmetric positive (semi-)definite.

    Symmetry is checked to a relative tolerance of 1e-8 of the largest entry
    (:func:`check_symmetric`). Semi-definiteness is judged by the smallest eigenvalue, to a
    tolerance of 1e-10 of the largest entry, the rounding of a computed covariance of low
    rank (as scipy's ``multivariate_normal`` judges it): a variance below that is named
    (where the eigenvalue alone was given). Definiteness (``strict``, a covariance given,
    such as a measurement's noise) is judged on the correlation matrix
    (:func:`correlation`), whose smallest eigenvalue must be above 1e-10, so that it holds
    at any units (on the matrix itself, ``diag(1e4, 1e-7)`` was refused); a variance of 0
    is named.

    >>> check_psd(np.diag([1e4, 1e-7]), "r", strict=True)
    >>> check_psd(np.diag([1.0, -0.5]), "Q")
    Traceback (most recent call last):
    ...
    ValueError: Q must be positive semi-definite; Q[1, 1] = -0.5, a negative variance
    """
    check_symmetric(arr, name)
    if arr.shape[-1] == 0:  # (no entries to judge: the largest of none failed in numpy's words)
        return
    kind = "positive definite" if strict else "positive semi-definite"
    d = np.diagonal(arr, axis1=-2, axis2=-1)
    top = np.max(np.abs(arr), axis=(-2, -1))
    low = (d <= 0) if strict else (d < -1e-10 * top[..., None])
    if np.any(low):
        where = tuple(int(i) for i in np.argwhere(low)[0])
        loc = f" (matrix {list(where[:-1])})" if where[:-1] else ""
        raise ValueError(f"{name} must be {kind}{loc}; {name}[{where[-1]}, {where[-1]}] = "
                         f"{d[where]:g}, a "
                         + ("variance of 0" if strict and d[where] == 0 else
                            "negative variance"))
    if strict:  # (the eigenvalue named is the one judged)
        eig = np.linalg.eigvalsh(correlation(arr)[0])[..., 0]
        bad, of = eig <= 1e-10, "its correlation matrix's smallest eigenvalue is"
    else:
        eig = np.linalg.eigvalsh(arr)[..., 0]
        bad, of = eig < -1e-10 * top, "its smallest eigenvalue is"
    if np.any(bad):
        which = tuple(int(i) for i in np.argwhere(np.atleast_1d(bad))[0]) if bad.ndim else ()
        loc = f" (matrix {list(which)})" if which else ""
        raise ValueError(f"{name} must be {kind}{loc}; {of} "
                         f"{float(np.atleast_1d(eig)[which if which else 0]):.3g}")


def as_rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    """Normalise ``rng`` (a Generator, a seed or None) to a ``numpy.random.Generator``."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, (int, np.integer)) and not _is_boolean(rng):  # (True: 1)
        if rng is not None and rng < 0:  # (numpy's "expected non-negative integer")
            raise ValueError(f"rng must be a seed >= 0, a numpy Generator or None; got {rng}")
        return np.random.default_rng(rng)
    raise TypeError(f"rng must be a numpy Generator, an int seed or None; got {type(rng).__name__}")


def masked_batch(ys: Any) -> Any:
    """``ys`` as one masked array where it is a list or tuple with a masked series in it, so
    that every series keeps its mask (``np.asarray`` of the list drops them, and the values
    under the masks are read as data); anything else as it is.

    >>> ys = [np.ma.masked_array([1.0, 9e9], mask=[0, 1]), np.array([2.0, 3.0])]
    >>> as_float_array(masked_batch(ys), "ys").tolist()
    [[1.0, nan], [2.0, 3.0]]
    """
    if isinstance(ys, (list, tuple)) and any(isinstance(s, np.ma.MaskedArray) for s in ys):
        try:
            return np.ma.array(ys)
        except (TypeError, ValueError):
            pass  # ragged or not numbers: as_float_array names the argument
    return ys


def check_not_masked(value: Any, name: str, why: str) -> None:
    """Raise ValueError, naming the first masked entry, where ``value`` is a numpy masked
    array with an entry masked: for values that have no missing one (``why``).

    >>> check_not_masked(np.ma.masked_array([1.0, 2.0], mask=[0, 1]), "x0", "a prior has no "
    ...                  "missing value")
    Traceback (most recent call last):
    ...
    ValueError: x0 must not have masked entries (a prior has no missing value); x0[1] is masked
    """
    if isinstance(value, np.ma.MaskedArray) and np.ma.is_masked(value):
        idx = [int(i) for i in np.argwhere(np.ma.getmaskarray(value))[0]]
        raise ValueError(f"{name} must not have masked entries ({why}); {name}{idx} is masked")


def as_measurement_series(ys: ArrayLike, name: str = "ys") -> tuple[np.ndarray, bool]:
    """Measurements ``(T, m)`` or ``(B, T, m)`` as ``(B, T, m)`` float64 (NaN: missing), and
    whether a single series was given; an infinite value is named with its index.

    The masked entries of a numpy masked array (pykalman's convention), or of the masked
    series of a list of them (a batch), are missing: NaN.

    Examples
    --------
    >>> ys = np.ma.masked_array([[0.1], [-999.0], [3.2]], mask=[[0], [1], [0]])
    >>> y, single = as_measurement_series(ys)
    >>> y[0, :, 0], single
    (array([0.1, nan, 3.2]), True)
    """
    y = as_float_array(masked_batch(ys), name, ndim=(2, 3))
    if np.isinf(y).any():
        idx = tuple(int(i) for i in np.argwhere(np.isinf(y))[0])
        raise ValueError(f"{name} must be finite or NaN (missing); {name}{list(idx)} = {y[idx]}")
    single = y.ndim == 2
    return (y[None] if single else y), single


def sum_tolerance(value: Any, n: int) -> float:
    """How far ``n`` probabilities may sum from 1: 1e-9, or the rounding of ``n`` values of
    ``value``'s own floating type where that is coarser (a float32 row ``(0.9, 0.1)``, whose
    sum is 1 in float32, sums to 1 - 2.2e-8 in float64, and was refused).

    >>> sum_tolerance([0.5, 0.5], 2), sum_tolerance(np.float32([0.5, 0.5]), 2) > 2e-7
    (1e-09, True)
    """
    return max(1e-9, n * eps_of(value))


def rescaled_rows(arr: np.ndarray, value: Any) -> np.ndarray:
    """Probabilities ``arr`` (float64, rows along the last axis, checked to sum to 1 within
    :func:`sum_tolerance`) with each row scaled to sum to 1 where ``value``, as given, was
    of a coarser floating type than float64 (its rows sum to 1 only to that type's
    rounding); as they are otherwise.

    >>> rescaled_rows(np.float32([0.9, 0.1]).astype(float), np.float32([0.9, 0.1])).sum()
    np.float64(1.0)
    """
    if eps_of(value) > np.finfo(float).eps:
        return arr / arr.sum(-1, keepdims=True)
    return arr


def as_markov_chain(transition: ArrayLike, mode_probs: ArrayLike | None,
                    k: int) -> tuple[np.ndarray, np.ndarray]:
    """A ``(k, k)`` transition matrix (non-negative, rows summing to 1 within
    :func:`sum_tolerance`) and ``k`` initial mode probabilities (uniform when None), checked
    and returned as float64 copies, each row rescaled as :func:`rescaled_rows` does; each
    error names the argument and, for a negative entry, where it is.

    >>> Pi, mu = as_markov_chain([[0.9, 0.1], [0.2, 0.8]], None, 2)
    >>> Pi.tolist(), mu.tolist()
    ([[0.9, 0.1], [0.2, 0.8]], [0.5, 0.5])
    >>> as_markov_chain([[1.1, -0.1], [0.0, 1.0]], None, 2)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: transition must be a (2, 2) non-negative matrix ...; transition[0, 1] = -0.1
    """
    # (a mask of True and False was read as probabilities 1 and 0)
    Pi = as_float_array(transition, "transition", ndim=(2,), not_boolean="probabilities")
    check_finite(Pi, "transition")
    what = f"transition must be a ({k}, {k}) non-negative matrix whose rows sum to 1"
    if Pi.shape == (k, k) and np.any(Pi < 0):
        i, j = (int(x) for x in np.argwhere(Pi < 0)[0])
        raise ValueError(f"{what}; transition[{i}, {j}] = {Pi[i, j]}")
    if Pi.shape != (k, k) or not np.allclose(Pi.sum(1), 1.0, rtol=0.0,
                                             atol=sum_tolerance(transition, k)):
        raise ValueError(f"{what}; got shape {Pi.shape} and row sums {Pi.sum(1).tolist()}")
    mu = np.full(k, 1.0 / k) if mode_probs is None else as_float_array(
        mode_probs, "mode_probs", ndim=(1,), not_boolean="probabilities")
    check_finite(mu, "mode_probs")  # NaN would pass the checks below (NaN < 0 is False)
    if mu.shape != (k,) or np.any(mu < 0) or abs(mu.sum() - 1.0) > sum_tolerance(mode_probs, k):
        raise ValueError(f"mode_probs must be {k} non-negative numbers summing to 1; "
                         f"got {mu.tolist()}")
    # copies (views of the caller's arrays were kept, and a change after the checks was used
    # unchecked by the switching filters)
    return rescaled_rows(Pi, transition).copy(), rescaled_rows(mu, mode_probs).copy()


def eps_of(values: Any) -> float:
    """The spacing of floats near 1 in ``values``' own precision (float64's for anything
    else: integers, lists, None).

    >>> eps_of(np.float32([0.5])) == 2.0 ** -23, eps_of([0.5]) == 2.0 ** -52
    (True, True)
    """
    dtype = getattr(values, "dtype", None)
    if dtype is not None and np.issubdtype(dtype, np.floating):
        return float(np.finfo(dtype).eps)
    return float(np.finfo(float).eps)


def check_one_step(dt: Any, batch: str = "every estimate of g") -> None:
    """Refuse a ``dt`` of more than one value: a prediction takes one time step for every
    estimate of the batch (numpy's own errors, further on, named neither)."""
    if np.ndim(dt) != 0:
        raise ValueError(f"dt must be one time step, for {batch}; got shape "
                         f"{np.shape(dt)}")


def check_has_steps(y: np.ndarray, name: str = "ys") -> None:
    """Raise ``ValueError`` if a series ``(..., T, m)`` has no step (``T = 0``): a filter has
    nothing to return then, not even a last estimate."""
    if y.ndim >= 2 and y.shape[-2] == 0:
        raise ValueError(f"{name} must have at least one step; got shape {_fmt_shape(y.shape)}")


def check_prior(x0: ArrayLike | None, P0: ArrayLike | None, n: int, *, batch: bool = True,
                space: str = "", series: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A prior mean ``(n,)`` (or ``(B, n)`` when ``batch``) and covariance ``(n, n)`` (or
    ``(B, n, n)``, symmetric positive semi-definite) for a model whose state has ``n``
    entries; each error names the argument
    (``space`` is appended to the expected shape, e.g. " (the largest member's state)"). A
    numpy masked array with a masked entry is refused: a prior has no missing value, nor a
    NaN or an infinite entry. Given the number of ``series`` of the measurements, a prior
    with a batch axis has one entry for all of them or one each (numpy's broadcasting error
    named neither)."""
    for name, value in (("x0", x0), ("P0", P0)):
        if value is None:
            raise ValueError(f"{name} is required (the prior of the first step); got None")
        # (as_float_array would make it NaN, which the filters would carry silently)
        check_not_masked(value, name, "a prior has no missing value")
    x = as_float_array(x0, "x0", ndim=(1, 2) if batch else (1,))
    # a NaN mean went through the extended and ensemble filters as NaN estimates, and
    # an IMM's as "every model gives zero likelihood"
    check_finite(x, "x0")
    if x.shape[-1] != n:
        want = f"({n},)" + (f" or (B, {n})" if batch else "")
        raise ValueError(f"x0 must have shape {want}{space}; got {_fmt_shape(x.shape)}")
    P = as_float_array(P0, "P0", ndim=(2, 3) if batch else (2,))
    if P.shape[-2:] != (n, n):
        want = f"({n}, {n})" + (f" or (B, {n}, {n})" if batch else "")
        raise ValueError(f"P0 must have shape {want}{space}; got {_fmt_shape(P.shape)}")
    check_finite(P, "P0")
    check_psd(P, "P0")  # a particle filter drew its first cloud from -I without a word
    if series is not None:
        for name, a, nd in (("x0", x, 2), ("P0", P, 3)):
            if a.ndim == nd and a.shape[0] not in (1, series):
                raise ValueError(f"{name} must be one for all series or one per series of ys "
                                 f"(B={series}); got {a.shape[0]}")
    return x, P


def check_linear_gaussian(F: ArrayLike, Q: ArrayLike, H: ArrayLike, R: ArrayLike, n: int, m: int,
                          T: int | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A linear-Gaussian model's ``F (n, n)``, ``Q (n, n)``, ``H (m, n)``, ``R (m, m)``, each
    constant or one per step (``T``), checked (``Q`` and ``R`` positive semi-definite).
    Where ``H`` and ``R`` agree on a measurement size other than the series' ``m``, the series
    ``ys`` is the one named."""
    hs, rs = np.shape(H), np.shape(R)
    if len(hs) >= 2 and len(rs) >= 2 and hs[-1] == n and hs[-2] == rs[-1] == rs[-2] != m:
        raise ValueError(f"ys must have {hs[-2]} value{'s' * (hs[-2] != 1)} a step, as H "
                         f"({hs[-2]}, {n}) and R ({hs[-2]}, {hs[-2]}) measure; got {m}")
    F_ = check_matrix_stack(F, "F", n, n, T)
    Q_ = check_matrix_stack(Q, "Q", n, n, T)
    H_ = check_matrix_stack(H, "H", m, n, T)
    R_ = check_matrix_stack(R, "R", m, m, T)
    # each named by its index as given: one matrix's by [i, j] (the stack's leading 0 named
    # Q[0, 0, 1], an index a matrix does not have)
    check_psd(Q_ if np.ndim(Q) == 3 else Q_[0], "Q")
    check_psd(R_ if np.ndim(R) == 3 else R_[0], "R")
    return F_, Q_, H_, R_


def ordinal(k: int) -> str:
    """2nd, 3rd, 11th, 21st (for messages)."""
    end = "th" if 10 <= k % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"{k}{end}"


def decode_text(data: bytes, path: object, what: str, error: type[Exception]) -> str:
    """``data`` as UTF-8 text (a byte-order mark dropped), or ``error`` saying that ``path`` is
    not a text ``what`` file, and at which byte."""
    try:
        # utf-8, and the mark dropped after: utf-8-sig's positions leave the mark's 3 bytes
        # out, so the byte named was 3 before the one that is not UTF-8
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{path} is not a text {what} file (byte {exc.start}: "
                    f"{data[exc.start:exc.start + 1]!r} is not UTF-8)") from None
    text = text.removeprefix("\ufeff")
    if "\x00" in text:
        raise error(f"{path} is not a text {what} file (byte {data.index(0)} is a NUL byte)")
    return text


_NUMBER_TEXT = re.compile(r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
                          r"|inf|infinity|nan)", re.IGNORECASE)
"""A number as a data file writes it and C's ``strtod`` (numpy's text reader) reads it:
ASCII digits, a sign, a point, an exponent; or a word for infinity or NaN."""


def text_number(text: str) -> float:
    """``text`` (stripped) read as a number as numpy's text reader reads it, or ValueError.

    Python's ``float()`` reads more: ``1_0`` as 10 (a digit separator of Python's source) and
    digits of other scripts (``"١٢"`` as 12); a data file's reader took them where
    ``np.loadtxt`` refuses them, so the same file was read one way or the other by where its
    other lines failed."""
    t = text.strip()
    if not _NUMBER_TEXT.fullmatch(t):
        raise ValueError(f"could not convert string to float: {text!r}")
    return float(t)

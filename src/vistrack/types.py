"""Core value types shared by every stage of vistrack."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ._validate import as_rows4

if TYPE_CHECKING:
    from collections.abc import Sequence
    from typing import TypeAlias

    from numpy.typing import ArrayLike

    # what indexes a batch: an integer, a slice, a boolean mask or integer indices, or a
    # tuple of these for several batch dimensions
    _Index: TypeAlias = (int | slice | np.ndarray | Sequence[int]
                         | tuple[int | slice | np.ndarray | Sequence[int], ...])

__all__ = ["Gaussian", "Detections", "Tracks", "Frame", "xyxy_to_xywh"]


@dataclass(frozen=True, slots=True)
class Gaussian:
    r"""A batch of Gaussian densities ``N(mean, cov)``.

    Each member of the batch is the density

    .. math::

        N(x; \mu, P) = (2\pi)^{-n/2} \det(P)^{-1/2}
        \exp\left(-\tfrac12 (x - \mu)' P^{-1} (x - \mu)\right).

    Parameters
    ----------
    mean : (..., n) array_like
        Means; the leading dimensions index the batch (one Gaussian is a batch of one).
        Stored as float64.
    cov : (..., n, n) array_like
        Covariances, with the same leading dimensions as ``mean``. Stored as float64; their
        symmetry and definiteness are not checked here.

    Raises
    ------
    ValueError
        If ``mean`` is a scalar or ``cov`` does not have the shape ``mean.shape + (n,)``.

    Notes
    -----
    Index the batch as an array: ``g[mask]``, ``g[3]``, ``g[:10]`` give Gaussians of the
    selected members; ``len(g)`` is the size of the first batch dimension (a single Gaussian,
    ``mean`` of shape ``(n,)``, has no ``len``). Instances are frozen.

    Examples
    --------
    >>> import numpy as np
    >>> g = Gaussian(np.zeros((3, 2)), np.broadcast_to(np.eye(2), (3, 2, 2)))
    >>> g.batch_shape, g.ndim
    ((3,), 2)
    >>> g[1:].mean.shape, len(g)
    ((2, 2), 3)
    """

    mean: np.ndarray
    cov: np.ndarray

    def __post_init__(self) -> None:
        for name in ("mean", "cov"):
            if getattr(getattr(self, name), "dtype", np.dtype(float)).kind == "c":
                # (cast to its real part with numpy's ComplexWarning alone)
                raise TypeError(f"Gaussian {name} must be real numbers; got complex values")
        mean = np.asarray(self.mean, dtype=np.float64)
        cov = np.asarray(self.cov, dtype=np.float64)
        if mean.ndim < 1:
            raise ValueError(f"Gaussian mean must have shape (..., n); got {mean.shape}")
        n = mean.shape[-1]
        if cov.shape != mean.shape + (n,):
            raise ValueError(
                f"Gaussian cov must have shape mean.shape + (n,) = {mean.shape + (n,)}; "
                f"got {cov.shape}"
            )
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", cov)

    @classmethod
    def _trusted(cls, mean: np.ndarray, cov: np.ndarray) -> Gaussian:
        """Wrap float64 arrays already known to have matching shapes (kernel outputs)."""
        g = object.__new__(cls)
        object.__setattr__(g, "mean", mean)
        object.__setattr__(g, "cov", cov)
        return g

    @property
    def ndim(self) -> int:
        """Dimension ``n`` of the state: the last axis of ``mean``.

        Examples
        --------
        >>> Gaussian(np.zeros(4), np.eye(4)).ndim
        4
        """
        return int(self.mean.shape[-1])

    @property
    def batch_shape(self) -> tuple[int, ...]:
        """The leading (batch) dimensions: ``mean.shape[:-1]``, ``()`` for one Gaussian.

        Examples
        --------
        >>> Gaussian(np.zeros(4), np.eye(4)).batch_shape
        ()
        """
        return tuple(self.mean.shape[:-1])

    def __getitem__(self, index: _Index) -> Gaussian:
        """Index the batch: ``g[mask]``, ``g[3]``, ``g[:10]``."""
        return Gaussian(self.mean[index], self.cov[index])

    def __len__(self) -> int:
        if self.mean.ndim == 1:
            raise TypeError("a single Gaussian (mean of shape (n,)) has no len()")
        return int(self.mean.shape[0])


def xyxy_to_xywh(boxes: np.ndarray) -> np.ndarray:
    """Boxes ``x0, y0, x1, y1`` as ``left, top, width, height`` (MOTChallenge files).

    Parameters
    ----------
    boxes : (N, 4) or (4,) array_like
        Corners ``x0, y0, x1, y1``; any shape with a multiple of 4 values is read as rows of
        four.

    Returns
    -------
    (N, 4) ndarray
        ``x0, y0, x1 - x0, y1 - y0`` as float64.

    Examples
    --------
    >>> xyxy_to_xywh([[10, 20, 40, 60]]).tolist()
    [[10.0, 20.0, 30.0, 40.0]]
    """
    b = as_rows4(boxes, "boxes", "x0, y0, x1, y1")  # (reshape(-1, 4) read any array)
    return np.c_[b[:, :2], b[:, 2:] - b[:, :2]]


def _floats(values: ArrayLike, name: str) -> np.ndarray:
    """``values`` as float64, or a ValueError naming ``name`` where one is not a number (a
    class's name, a word): numpy's "could not convert string to float" named nothing."""
    try:
        return np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        flat = np.asarray(values, dtype=object).ravel()
        for k, v in enumerate(flat):
            try:
                float(v)
            except (TypeError, ValueError):
                raise ValueError(f"{name} must be numbers; {name}[{k}] (flattened) is {v!r}"
                                 + ("; map class names to numbers first" if name == "classes"
                                    else "")) from None
        raise


def _whole_numbers(values: ArrayLike, name: str) -> np.ndarray:
    """``values`` as int64, refusing a value that is not a whole number (a class of 1.7 was
    class 1), not finite, or not within ±(2**53 - 1) (a uint64 of 2**64 - 1 became -1),
    naming it."""
    a = np.asarray(values)
    if a.dtype.kind in "iub":
        big = (a >= 2**53) | (a <= -(2**53))  # compared as integers
        if big.any():
            k = int(np.flatnonzero(big.ravel())[0])
            raise ValueError(f"{name} must be whole numbers within ±(2**53 - 1); {name}[{k}] = "
                             f"{a.ravel()[k].tolist()!r}")
        return a.astype(np.int64, copy=False)
    x = _floats(a, name)
    bad = ~np.isfinite(x) | (x != np.round(x)) | (np.abs(x) >= 2.0 ** 53)
    if bad.any():
        k = int(np.flatnonzero(bad.ravel())[0])
        raise ValueError(f"{name} must be whole numbers; {name}[{k}] = {float(x.ravel()[k])!r}")
    return x.astype(np.int64)


def _box_rows(values: ArrayLike, name: str, *, one: bool = False) -> np.ndarray:
    """``values`` as finite rows of four floats ``(N, 4)``: ``[]`` or ``(0, k)`` as none, and
    with ``one`` a lone ``(4,)`` as one box; each error names ``name`` (and the row)."""
    b = _floats(values, name)
    if (one and b.shape == (4,)) or (b.size == 0 and (b.ndim < 2 or b.shape[0] == 0)):
        b = b.reshape(-1, 4)
    if b.ndim != 2 or b.shape[1] != 4:
        raise ValueError(f"{name} must have shape (N, 4); got {b.shape}")
    if not np.isfinite(b).all():
        i = int(np.flatnonzero(~np.isfinite(b).all(axis=1))[0])
        raise ValueError(f"{name} must be finite; {name}[{i}] = {b[i].tolist()}")
    return b


@dataclass(frozen=True)
class Detections:
    """One frame's detections, as columns: boxes or points, scores and classes.

    Parameters
    ----------
    boxes : (N, 4) array_like, optional
        ``x0, y0, x1, y1`` in pixels (``x1 >= x0``, ``y1 >= y0``, finite).
    points : (N, d) array_like, optional
        Point measurements (blob centres, particles), when there are no boxes. Exactly one of
        ``boxes`` and ``points`` is given.
    scores : (N,) array_like, optional
        Detector confidences; default 1.
    classes : (N,) array_like of int, optional
        Class numbers; default 0. Trackers never give two classes one identity.

    Raises
    ------
    ValueError
        If both or neither of ``boxes`` and ``points`` are given, a box is not finite or has
        ``x1 < x0`` or ``y1 < y0``, or ``scores`` or ``classes`` do not have one value per
        detection.

    Notes
    -----
    Index with a boolean mask, indices or a slice (``dets[dets.scores > 0.5]``), or with one
    integer for the Detections of that one row (``dets[0]``, ``len`` 1, as ``dets[[0]]``);
    ``len(dets)`` is the number of detections. Instances are frozen; the arrays are stored as
    float64 (boxes, points, scores) and int64 (classes).

    Examples
    --------
    >>> d = Detections.from_xywh([[10, 20, 30, 40], [0, 0, 5, 5]], scores=[0.9, 0.3])
    >>> d[d.scores > 0.5].boxes.tolist(), d.centers[0].tolist()
    ([[10.0, 20.0, 40.0, 60.0]], [25.0, 40.0])
    >>> d[-1].boxes.tolist(), d[-1].scores.tolist()
    ([[0.0, 0.0, 5.0, 5.0]], [0.3])
    """

    boxes: np.ndarray | None = None
    points: np.ndarray | None = None
    scores: np.ndarray | None = None
    classes: np.ndarray | None = None

    def __post_init__(self) -> None:
        if (self.boxes is None) == (self.points is None):
            raise ValueError("Detections need boxes or points (one of them)")
        if self.boxes is not None:
            b = _box_rows(self.boxes, "boxes")
            if (b[:, 2] < b[:, 0]).any() or (b[:, 3] < b[:, 1]).any():
                i = int(np.flatnonzero((b[:, 2] < b[:, 0]) | (b[:, 3] < b[:, 1]))[0])
                raise ValueError(f"boxes must be x0, y0, x1, y1 with x1 >= x0 and y1 >= y0; "
                                 f"boxes[{i}] = {b[i].tolist()}")
            object.__setattr__(self, "boxes", b)
            n = len(b)
        else:
            p = np.asarray(self.points, dtype=np.float64)
            if p.ndim != 2:
                # (no points given as [] say no dimension: the tracker's must be matched)
                hint = (" (no points: np.zeros((0, d)), d the points' dimension)"
                        if p.size == 0 else "")
                raise ValueError(f"points must have shape (N, d); got {p.shape}{hint}")
            if not np.isfinite(p).all():  # a tracker would start a track at NaN
                i = int(np.flatnonzero(~np.isfinite(p).all(axis=1))[0])
                raise ValueError(f"points must be finite; points[{i}] = {p[i].tolist()}")
            object.__setattr__(self, "points", p)
            n = len(p)
        for name, default, dtype in (("scores", 1.0, np.float64), ("classes", 0, np.int64)):
            v = getattr(self, name)
            if v is None:
                v = np.full(n, default, dtype)
            elif name == "classes":
                v = _whole_numbers(v, "classes")
            else:
                v = _floats(v, name)
                if not np.isfinite(v).all():  # any real number ranks; inf and NaN do not
                    i = int(np.flatnonzero(~np.isfinite(v.ravel()))[0])
                    bad = float(v.ravel()[i])
                    raise ValueError(f"scores must be finite; scores[{i}] = {bad}" + (
                        " (the logit of a probability of 0 or 1? clip the probabilities "
                        "first)" if np.isinf(bad) else ""))
            if v.shape != (n,):
                raise ValueError(f"{name} must have shape ({n},); got {v.shape}")
            object.__setattr__(self, name, v)

    @classmethod
    def from_xywh(cls, xywh: ArrayLike, scores: ArrayLike | None = None,
                  classes: ArrayLike | None = None) -> Detections:
        """Detections from ``left, top, width, height`` boxes (MOTChallenge files).

        Parameters
        ----------
        xywh : (N, 4) array_like
            ``left, top, width, height`` of each box (widths and heights >= 0).
        scores : (N,) array_like, optional
            Detector confidences; default 1.
        classes : (N,) array_like of int, optional
            Class numbers; default 0.

        Returns
        -------
        Detections
            With ``boxes`` ``x0, y0, x0 + w, y0 + h``.

        Examples
        --------
        >>> Detections.from_xywh([[10, 20, 30, 40]]).boxes.tolist()
        [[10.0, 20.0, 40.0, 60.0]]
        """
        b = _box_rows(xywh, "xywh", one=True)
        bad = np.flatnonzero((b[:, 2] < 0) | (b[:, 3] < 0))
        if len(bad):  # named as given, not as the corners it would make
            raise ValueError(f"xywh must have widths and heights >= 0; xywh[{int(bad[0])}] = "
                             f"{b[bad[0]].tolist()}")
        # the fields are typed as the ndarrays __post_init__ makes of them; it takes array_like
        return cls(boxes=np.c_[b[:, :2], b[:, :2] + b[:, 2:]],
                   scores=scores, classes=classes)  # type: ignore[arg-type]

    @classmethod
    def from_supervision(cls, detections: Any) -> Detections:
        """From a ``supervision.Detections`` (or anything with its ``xyxy``, ``confidence``
        and ``class_id``; supervision is not imported).

        Examples
        --------
        >>> from types import SimpleNamespace
        >>> sv = SimpleNamespace(xyxy=np.array([[10.0, 20, 40, 60]]),
        ...                      confidence=np.array([0.8]), class_id=np.array([2]))
        >>> d = Detections.from_supervision(sv)
        >>> d.boxes.tolist(), d.scores.tolist(), d.classes.tolist()
        ([[10.0, 20.0, 40.0, 60.0]], [0.8], [2])
        """
        xyxy = np.asarray(detections.xyxy, dtype=np.float64)
        if xyxy.size == 0:
            xyxy = xyxy.reshape(0, 4)
        elif xyxy.ndim != 2 or xyxy.shape[1] != 4:  # (a (2, 8) was read as 4 boxes)
            raise ValueError(f"xyxy must have shape (N, 4); got {xyxy.shape}")
        return cls(boxes=xyxy, scores=getattr(detections, "confidence", None),
                   classes=getattr(detections, "class_id", None))

    def to_supervision(self) -> Any:
        """As a ``supervision.Detections`` (``xyxy``, ``confidence``, ``class_id``), for
        supervision's annotators and tools; needs supervision.

        Raises
        ------
        ValueError
            If these are point detections (supervision's are boxes).
        """
        if self.boxes is None:
            raise ValueError("supervision's detections are boxes; these are points")
        try:
            import supervision
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("to_supervision needs supervision (pip install supervision)") \
                from e
        assert self.scores is not None and self.classes is not None  # (__post_init__)
        return supervision.Detections(xyxy=self.boxes.copy(), confidence=self.scores.copy(),
                                      class_id=self.classes.copy())

    @classmethod
    def from_ultralytics(cls, result: Any) -> Detections:
        """From one image's ``ultralytics`` result (``result.boxes`` with ``xyxy``, ``conf``
        and ``cls``, torch tensors or arrays; ultralytics is not imported), or the list of one
        that ``model(image)`` returns. Raises ``TypeError`` for a list of several results, or a
        result without boxes.

        Examples
        --------
        >>> from types import SimpleNamespace
        >>> boxes = SimpleNamespace(xyxy=np.array([[1.0, 2, 3, 4]]), conf=np.array([0.5]),
        ...                         cls=np.array([0.0]))
        >>> Detections.from_ultralytics(SimpleNamespace(boxes=boxes)).classes.tolist()
        [0]
        """
        def array(x: Any) -> np.ndarray:
            for step in ("detach", "cpu", "numpy"):  # a torch tensor
                x = getattr(x, step)() if hasattr(x, step) else x
            return np.asarray(x)

        if isinstance(result, (list, tuple)):
            # what ``model(image)`` returns: one result for each image given
            if len(result) != 1:
                raise TypeError(f"result must be one image's result; got a {type(result).__name__}"
                                f" of {len(result)} (give results[k], one at a time)")
            result = result[0]
        b = getattr(result, "boxes", None)
        if b is None:
            raise TypeError(f"result must be a detection model's result, with boxes; this "
                            f"{type(result).__name__} has none (a classification model's?)")
        xyxy = array(b.xyxy).astype(np.float64)
        if xyxy.size == 0:
            xyxy = xyxy.reshape(0, 4)
        elif xyxy.ndim != 2 or xyxy.shape[1] != 4:  # (a (2, 8) was read as 4 boxes)
            raise ValueError(f"boxes.xyxy must have shape (N, 4); got {xyxy.shape}")
        # the classes as given: Detections names one that is not whole (2.7 was class 2)
        return cls(boxes=xyxy, scores=array(b.conf).astype(np.float64),
                   classes=array(b.cls).astype(np.float64))

    def __len__(self) -> int:
        assert self.scores is not None  # filled in by __post_init__
        return int(self.scores.shape[0])

    def __getitem__(self, index: _Index) -> Detections:
        assert self.scores is not None and self.classes is not None  # set by __post_init__
        if isinstance(index, (int, np.integer)) and not isinstance(index, (bool, np.bool_)):
            # one detection, as a Detections of one row (it raised "boxes must have shape
            # (N, 4); got (4,)")
            index = [int(index)]
        return Detections(
            boxes=None if self.boxes is None else self.boxes[index],
            points=None if self.points is None else self.points[index],
            scores=self.scores[index], classes=self.classes[index])

    @property
    def xywh(self) -> np.ndarray:
        """Boxes as ``left, top, width, height``, ``(N, 4)``.

        Raises ``ValueError`` for point detections, which have no boxes.

        Examples
        --------
        >>> Detections(boxes=[[10, 20, 40, 60]]).xywh.tolist()
        [[10.0, 20.0, 30.0, 40.0]]
        """
        if self.boxes is None:
            raise ValueError("xywh needs box detections; these detections are points")
        return xyxy_to_xywh(self.boxes)

    @property
    def centers(self) -> np.ndarray:
        """Box centres ``(N, 2)``, or the points ``(N, d)`` themselves.

        Examples
        --------
        >>> Detections(boxes=[[10, 20, 40, 60]]).centers.tolist()
        [[25.0, 40.0]]
        >>> Detections(points=[[1.0, 2.0, 3.0]]).centers.tolist()
        [[1.0, 2.0, 3.0]]
        """
        if self.boxes is None:
            assert self.points is not None  # __post_init__ requires boxes or points
            return self.points
        return 0.5 * (self.boxes[:, :2] + self.boxes[:, 2:])


@dataclass(frozen=True)
class Tracks:
    """What a tracker reports for one frame (:class:`~vistrack.tracking.Tracker`): the
    confirmed tracks updated in it (and, for the box trackers, the ones coasting through a
    short miss, at their predictions).

    Boxes are ``x0, y0, x1, y1``, as in :class:`Detections`; :attr:`xywh` converts at the
    edge, for the MOTChallenge files.

    Attributes
    ----------
    ids : (K,) int
        Identities, integers from 1.
    boxes : (K, 4) float or None
        ``x0, y0, x1, y1`` (box trackers), or None for point tracks.
    points : (K, d) float or None
        Positions (point trackers), or None.
    scores, classes : (K,)
        The score and class of the detection each track was last updated with.
    covs : (K, 2, 2) float or None
        The covariance of each track's centre (boxes) or point position, where the tracker
        gives it.

    Examples
    --------
    >>> t = Tracks(ids=np.array([1]), boxes=np.array([[10.0, 20, 40, 80]]), points=None,
    ...            scores=np.array([0.9]), classes=np.array([0]))
    >>> len(t), t.xywh.tolist()
    (1, [[10.0, 20.0, 30.0, 60.0]])
    >>> len(Tracks.empty())
    0
    """

    ids: np.ndarray
    boxes: np.ndarray | None
    points: np.ndarray | None
    scores: np.ndarray
    classes: np.ndarray
    covs: np.ndarray | None = None

    def __post_init__(self) -> None:
        # arrays, one row a track, boxes or points: a caller's own tracker's lists failed in
        # len() ("'list' object has no attribute 'shape'"), and a short column in the writer
        for name in ("ids", "boxes", "points", "scores", "classes", "covs"):
            v = getattr(self, name)
            if v is not None and not isinstance(v, np.ndarray):
                v = np.asarray(v)
                if name == "boxes" and v.size == 0:  # ([] for no tracks, as Detections)
                    v = v.reshape(0, 4)
                object.__setattr__(self, name, v)
        if (self.boxes is None) == (self.points is None):
            raise ValueError("Tracks hold boxes or points: give one of them, the other None")
        if self.ids.ndim != 1:
            raise ValueError(f"ids must be one identity a track, (K,); got shape "
                             f"{self.ids.shape}")
        k = self.ids.shape[0]
        geometry, name = ((self.boxes, "boxes") if self.boxes is not None
                          else (self.points, "points"))
        assert geometry is not None
        if geometry.ndim != 2 or len(geometry) != k or (name == "boxes"
                                                        and geometry.shape[1] != 4):
            raise ValueError(f"{name} must be one row a track, ({k}, "
                             f"{4 if name == 'boxes' else 'd'}); got shape {geometry.shape}")
        for name in ("scores", "classes", "covs"):
            v = getattr(self, name)
            if v is not None and (v.ndim == 0 or len(v) != k):
                raise ValueError(f"{name} must have one row a track ({k}); got shape "
                                 f"{v.shape}")

    def __len__(self) -> int:
        return int(self.ids.shape[0])

    @classmethod
    def empty(cls, boxes: bool = True) -> Tracks:
        """No tracks: box tracks (``boxes (0, 4)``), or point tracks with ``boxes=False``."""
        return cls(ids=np.zeros(0, np.int64), boxes=np.zeros((0, 4)) if boxes else None,
                   points=None if boxes else np.zeros((0, 2)), scores=np.zeros(0),
                   classes=np.zeros(0, np.int64))

    @property
    def xywh(self) -> np.ndarray:
        """Boxes as ``x, y, w, h`` ``(K, 4)`` (top-left corner and size)."""
        if self.boxes is None:
            raise ValueError("xywh needs box tracks; these tracks are points")
        return xyxy_to_xywh(self.boxes)

    @property
    def centers(self) -> np.ndarray:
        """Box centres ``(K, 2)``, or the points ``(K, d)`` themselves (as
        :attr:`Detections.centers`).

        Examples
        --------
        >>> Tracks(ids=np.array([1]), boxes=np.array([[10.0, 20, 40, 60]]), points=None,
        ...        scores=np.ones(1), classes=np.zeros(1)).centers.tolist()
        [[25.0, 40.0]]
        """
        if self.boxes is None:
            assert self.points is not None  # a tracker's tracks are boxes or points
            return self.points
        return 0.5 * (self.boxes[:, :2] + self.boxes[:, 2:])


@dataclass(frozen=True)
class Frame:
    """One frame of a source: ``index`` (from 1, as MOTChallenge counts), ``time`` (seconds
    from the first frame, ``(index - 1) / fps``) and ``image`` (``(H, W, 3)`` BGR or
    ``(H, W)`` grey, uint8; None where only detections are tracked).

    Every tracker's :meth:`~vistrack.tracking.Tracker.step` takes one.

    Examples
    --------
    >>> Frame(3, 2 / 25)
    Frame(index=3, time=0.08)
    """

    index: int
    time: float
    image: np.ndarray | None = field(default=None, repr=False)

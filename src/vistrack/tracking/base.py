r"""One protocol for every tracker: ``step(frame, detections) -> Tracks`` and ``reset()``.

A tracker takes one :class:`~vistrack.types.Frame` at a time (its index, its time in seconds,
its image where there is one) with the frame's :class:`~vistrack.types.Detections`, and
reports the tracks it holds in that frame as :class:`~vistrack.types.Tracks`. Trackers that
need only detections (box and point trackers) read the frame's index; trackers that look at
pixels (the single-object trackers, the detector-confidence particle filter, KLT) read its
image. :func:`vistrack.pipeline.run` drives any of them, and never asks which it has.

Single-object trackers (:class:`SingleObjectTracker`) start from the most confident detection
of the first frame that has one, and follow that object alone from then on.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from .._validate import as_box
from ..types import Detections, Frame, Tracks

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["Tracker", "SingleObjectTracker", "check_start_box", "frame_index", "frame_image"]


@runtime_checkable
class Tracker(Protocol):
    """What every tracker answers: ``step(frame, detections) -> Tracks`` and ``reset()``.

    Any object with these two methods is a tracker for :func:`vistrack.pipeline.run`; the
    protocol is checkable at run time with ``isinstance`` (which looks for the names only, not
    their signatures).

    Examples
    --------
    >>> from vistrack.tracking import BoxTracker, PointTracker
    >>> isinstance(BoxTracker(), Tracker), isinstance(PointTracker(), Tracker)
    (True, True)
    """

    def step(self, frame: Frame, detections: Detections | None = None) -> Tracks:
        """Track one frame; return the tracks reported in it.

        Parameters
        ----------
        frame : Frame
            The frame: its index, its time, and its image where the tracker looks at pixels
            (trackers of detections also take the index alone).
        detections : Detections, optional
            The frame's detections (None: none, or the tracker finds its own objects).

        Returns
        -------
        Tracks
            The tracks the tracker reports in this frame.

        Examples
        --------
        >>> from vistrack.tracking import BoxTracker
        >>> tracker = BoxTracker()
        >>> tracks = tracker.step(Frame(1, 0.0), Detections.from_xywh([[10, 20, 30, 60]], [0.9]))
        >>> tracks.ids.tolist(), tracks.xywh.tolist()
        ([1], [[10.0, 20.0, 30.0, 60.0]])
        """
        ...

    def reset(self) -> None:
        """Forget every track; identities start again from 1.

        Examples
        --------
        >>> from vistrack.tracking import BoxTracker
        >>> tracker = BoxTracker()
        >>> _ = tracker.step(Frame(1, 0.0), Detections.from_xywh([[10, 20, 30, 60]], [0.9]))
        >>> _ = tracker.step(Frame(2, 0.04), Detections.from_xywh([[500, 20, 30, 60]], [0.9]))
        >>> tracker.reset()
        >>> tracker.step(Frame(1, 0.0), Detections.from_xywh([[500, 20, 30, 60]], [0.9])).ids
        array([1])
        """
        ...


class FixedSettings:
    """A tracker whose settings (the names of ``_fixed``) are fixed once it is made: what it
    derives from them when made (a compiled association, a gate's threshold, a track
    table's window) would not follow a later change, so assigning one raises
    AttributeError naming it (a changed ``config`` ran half of it: the compiled association
    kept the old gates while the lifecycle took the new). A subclass sets ``_made`` at the
    end of its ``__init__``.

    Examples
    --------
    >>> from vistrack.tracking import PointTracker
    >>> tr = PointTracker()
    >>> try:
    ...     tr.p_gate = 0.5
    ... except AttributeError as e:
    ...     print(str(e).split(" (")[0] + "; " + str(e).split(": ")[1])
    PointTracker.p_gate is fixed when the tracker is made; make a new PointTracker(p_gate=...)
    """

    _fixed: frozenset[str] = frozenset()

    def __setattr__(self, name: str, value: object) -> None:
        if name in self._fixed and self.__dict__.get("_made", False):
            kind = type(self).__name__
            raise AttributeError(f"{kind}.{name} is fixed when the tracker is made (what it "
                                 f"derives from it would not follow): make a new "
                                 f"{kind}({name}=...)")
        super().__setattr__(name, value)


def frame_index(frame: Frame | int | None, last: int | None) -> int:
    """The index of ``frame`` (a :class:`~vistrack.types.Frame`, or its index; None: the
    one after ``last``, or 1), checked to come after ``last``.

    Parameters
    ----------
    frame : Frame, int or None
        The frame, its index, or None for the one after ``last``.
    last : int or None
        The index of the tracker's previous frame (None: there was none).

    Returns
    -------
    int
        The frame's index.

    Raises
    ------
    TypeError
        If ``frame`` is neither a :class:`~vistrack.types.Frame`, an integer nor None.
    ValueError
        If the index does not come after ``last``.

    Examples
    --------
    >>> frame_index(None, None), frame_index(Frame(7, 0.2), 3), frame_index(5, 4)
    (1, 7, 5)
    """
    if frame is None:
        index = 1 if last is None else last + 1
    elif isinstance(frame, Frame):
        if isinstance(frame.index, (bool, np.bool_)) or not isinstance(frame.index,
                                                                      (int, np.integer)):
            # int() cut 2.5 to 2 and read "4" as 4
            raise TypeError(f"frame.index must be an int; got {frame.index!r}")
        index = int(frame.index)
    elif isinstance(frame, (int, np.integer)) and not isinstance(frame, bool):
        index = int(frame)
    else:
        raise TypeError(f"frame must be a vistrack.types.Frame or its index (an int); got "
                        f"{type(frame).__name__}")
    if last is not None and index <= last:
        raise ValueError(f"frame must increase; got {index} after {last}")
    return index


def frame_image(frame: Frame, who: str) -> np.ndarray:
    """The image of ``frame``, a :class:`~vistrack.types.Frame` with one; ``who`` names the
    tracker in the error.

    Parameters
    ----------
    frame : Frame
        A frame with an image.
    who : str
        The tracker asking, for the message.

    Returns
    -------
    ndarray
        ``frame.image``, as an array.

    Raises
    ------
    TypeError
        If ``frame`` is not a :class:`~vistrack.types.Frame`, or has no image.

    Examples
    --------
    >>> frame_image(Frame(1, 0.0, np.zeros((4, 6), np.uint8)), "mine").shape
    (4, 6)
    >>> frame_image(Frame(1, 0.0), "mine")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    TypeError: mine looks at pixels: frame must be a vistrack.types.Frame with an image; ...
    """
    image = frame.image if isinstance(frame, Frame) else None
    if image is None:
        got = (f"{frame!r}" if isinstance(frame, Frame) else
               f"an array of shape {frame.shape} (wrap it: Frame(index, time, image))"
               if isinstance(frame, np.ndarray) else type(frame).__name__)
        raise TypeError(f"{who} looks at pixels: frame must be a vistrack.types.Frame with an "
                        f"image; got {got}")
    return np.asarray(image)


_HALF = 0.5
"""Half a pixel, between the two ways single-object trackers place a pixel: a box's
coordinates count pixel ``k`` as ``[k, k + 1)``, while the image is sampled (templates
cut, contours fitted, registrations solved) in the pixels' indices, pixel ``k``'s centre
at ``k``. An edge between pixels 49 and 50 is at 50 in the first and 49.5 in the second
(without the half pixel, boxes sat half a pixel up and to the left of the object)."""


def _index_centre(box: np.ndarray) -> np.ndarray:
    """A box's centre in the pixels' indices (:data:`_HALF`)."""
    return box[:2] + box[2:] / 2 - _HALF


def check_start_box(image: np.ndarray, box: np.ndarray, name: str = "box") -> None:
    """Refuse a start box ``x, y, w, h`` with less than half its area inside ``image``, or
    whose size floating point loses: a tracker has no object to learn there (and OpenCV's
    fail inside, others follow nothing).

    Examples
    --------
    >>> image, box = np.zeros((576, 768), np.uint8), np.array([700.0, 10, 200, 40])
    >>> check_start_box(image, box)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: box (x, y, w, h) = (700, 10, 200, 40) has only 34 % of its area inside the ...
    """
    shape = np.shape(image)
    if len(shape) < 2:
        return  # not an image: the tracker's own check names it
    H, W = shape[:2]
    x, y, w, h = (float(v) for v in box)
    where = f"{name} (x, y, w, h) = ({', '.join(f'{v:g}' for v in (x, y, w, h))})"
    if not w * h > 0 or x + w == x or y + h == y:
        # (1e-200 on a side, or a size under a unit of the last place at x = 2^52, divided by an
        # area of 0 in a ZeroDivisionError; a box under a pixel is followed, by the pixels
        # about it)
        raise ValueError(f"{where} has no size a float holds at its place (its area, or "
                         "x + w against x, or y + h against y, rounds to nothing)")
    iw = max(0.0, min(x + w, W) - max(x, 0.0))
    ih = max(0.0, min(y + h, H) - max(y, 0.0))
    inside = iw * ih / (w * h)
    if inside >= 0.5:
        return
    if inside == 0.0:
        raise ValueError(f"{where} lies outside the {W}x{H} image")
    raise ValueError(f"{where} has only {int(100 * inside)} % of its area inside the {W}x{H} "
                     "image; a start box must be at least half inside")


class SingleObjectTracker:
    """The tracker protocol for trackers of one object, on top of ``init(image, box)`` and
    ``update(image) -> box`` (boxes ``x, y, w, h``: the top-left corner and size).

    :meth:`step` starts the tracker at the most confident detection of the first frame that
    has one (the frames before report no track) and from then on follows that object,
    reported as track 1 with score 1; later detections are not used. :meth:`reset` forgets
    it, so the next frame's detections start it again. By hand, :meth:`init` starts it at a
    box and :meth:`update` follows it.

    A tracker implements ``_start(image, box)`` (``box`` validated, ``(4,)`` float) and
    ``_follow(image) -> box``.

    Examples
    --------
    By hand, on a red square that moves 3 pixels to the right:

    >>> from vistrack.tracking.single import single_tracker
    >>> def image(x):
    ...     im = np.zeros((60, 80, 3), np.uint8); im[20:40, x:x + 20] = (0, 0, 255)
    ...     return im
    >>> t = single_tracker("wsl")
    >>> t.init(image(30), [30, 20, 20, 20])
    >>> t.update(image(33)).round().tolist()
    [33.0, 20.0, 20.0, 20.0]
    """

    _started: bool = False
    _shape: tuple[int, ...] = ()

    def _start(self, image: np.ndarray, box: np.ndarray) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _follow(self, image: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _need_start(self, what: str) -> None:
        """A ``RuntimeError`` naming the method ``what`` if the tracker holds no object yet
        (the state it works on is made by :meth:`init`)."""
        if not self._started:
            raise RuntimeError(f"{type(self).__name__}.{what} before init: start it with "
                               "init(image, box) or step(frame, detections)")

    def init(self, image: np.ndarray, box: ArrayLike) -> None:
        """Start following the object in ``box`` (``x, y, w, h``) of ``image``.

        Parameters
        ----------
        image : (H, W, 3) or (H, W) ndarray
            The first frame, BGR or grey uint8 (as the tracker needs).
        box : (4,) array_like
            The object's box ``x, y, w, h``: the top-left corner and size.

        Raises
        ------
        ValueError
            If ``box`` is not four finite numbers with a positive size, or less than half of
            it lies inside ``image`` (the message gives the box, the share inside and the
            image's size).

        Examples
        --------
        >>> from vistrack.tracking.single import single_tracker
        >>> t = single_tracker("colour")
        >>> t.init(np.zeros((60, 80, 3), np.uint8), [30, 20, 20, 20])
        >>> t.started
        True
        >>> t.init(np.zeros((60, 80, 3), np.uint8), [90, 20, 20, 20])
        Traceback (most recent call last):
        ...
        ValueError: box (x, y, w, h) = (90, 20, 20, 20) lies outside the 80x60 image
        """
        b = as_box(box)
        check_start_box(image, b)
        self._start(image, b)
        self._started = True
        self._shape = np.shape(image)  # the frames to come are of its kind (update)

    def update(self, image: np.ndarray) -> np.ndarray:
        """The object's box ``(4,)`` (``x, y, w, h``) in the next ``image``.

        Parameters
        ----------
        image : (H, W, 3) or (H, W) ndarray
            The next frame, of the first frame's kind.

        Returns
        -------
        (4,) ndarray
            The box ``x, y, w, h`` (float).

        Raises
        ------
        RuntimeError
            If the tracker has not been started (:meth:`init` or :meth:`step`).
        ValueError
            If ``image`` differs in shape from the first frame's (its size, or grey against
            colour): the box is in the first frame's pixels, and each tracker would fail
            inside OpenCV, or follow on, in its own way.

        Examples
        --------
        >>> from vistrack.tracking.single import single_tracker
        >>> def image(x):
        ...     im = np.zeros((60, 80, 3), np.uint8); im[20:40, x:x + 20] = (0, 0, 255)
        ...     return im
        >>> t = single_tracker("wsl")
        >>> t.init(image(30), [30, 20, 20, 20])
        >>> [t.update(image(x)).round().tolist()[0] for x in (33, 36)]
        [33.0, 36.0]
        >>> t.update(image(39)[:30])  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        ValueError: image is (30, 80, 3); the tracker started on a (60, 80, 3) image: ...
        """
        self._need_start("update")
        if np.shape(image) != self._shape:
            raise ValueError(f"image is {np.shape(image)}; the tracker started on a "
                             f"{self._shape} image: give it the frames of one video, each "
                             "of the first frame's shape")
        return self._follow(image)

    @property
    def started(self) -> bool:
        """Whether the tracker holds an object (after :meth:`init`, until :meth:`reset`).

        Examples
        --------
        >>> from vistrack.tracking.single import single_tracker
        >>> t = single_tracker("colour")
        >>> t.started
        False
        >>> t.init(np.zeros((60, 80, 3), np.uint8), [30, 20, 20, 20])
        >>> t.started
        True
        """
        return self._started

    def step(self, frame: Frame, detections: Detections | None = None) -> Tracks:
        """Track one frame (see the class); ``frame`` must carry its image.

        Parameters
        ----------
        frame : Frame
            The frame, with its image.
        detections : Detections, optional
            The frame's detections, with boxes; used only until the tracker has started, the
            most confident one (the first, without scores) starting it.

        Returns
        -------
        Tracks
            Nothing before the tracker has started; then one track, identity 1, score 1 and
            class 0, with the object's box ``x0, y0, x1, y1``.

        Raises
        ------
        TypeError
            If ``frame`` has no image, or the detections that would start the tracker have no
            boxes.
        ValueError
            If the detection that starts the tracker is less than half inside the image (see
            :meth:`init`).

        Examples
        --------
        >>> from vistrack.tracking.single import single_tracker
        >>> image = np.zeros((60, 80, 3), np.uint8); image[20:40, 30:50] = (0, 0, 255)
        >>> t = single_tracker("colour")
        >>> t.step(Frame(1, 0.0, image)).ids.tolist()  # no detection yet: nothing to follow
        []
        >>> first = t.step(Frame(2, 0.04, image), Detections.from_xywh([[30, 20, 20, 20]]))
        >>> first.ids.tolist(), first.boxes.tolist()
        ([1], [[30.0, 20.0, 50.0, 40.0]])
        """
        image = frame_image(frame, type(self).__name__)
        if not self._started:
            if detections is None or len(detections) == 0:
                return Tracks.empty()
            if detections.boxes is None:
                raise TypeError("detections must have boxes to start a single-object tracker")
            best = int(np.argmax(detections.scores)) if detections.scores is not None else 0
            box = detections.xywh[best]
            self.init(image, box)
        else:
            box = np.asarray(self.update(image), dtype=float)
        xyxy = np.r_[box[:2], box[:2] + box[2:]][None]
        return Tracks(ids=np.ones(1, np.int64), boxes=xyxy, points=None, scores=np.ones(1),
                      classes=np.zeros(1, np.int64))

    def reset(self) -> None:
        """Forget the object; the next frame with a detection starts the tracker again.

        Examples
        --------
        >>> from vistrack.tracking.single import single_tracker
        >>> t = single_tracker("colour")
        >>> t.init(np.zeros((60, 80, 3), np.uint8), [30, 20, 20, 20])
        >>> t.reset()
        >>> t.started
        False
        """
        self._started = False

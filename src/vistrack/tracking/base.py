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

from typing import Any, Protocol, runtime_checkable

import numpy as np

from .._validate import as_box
from ..types import Detections, Frame, Tracks

__all__ = ["Tracker", "SingleObjectTracker", "frame_index", "frame_image"]


@runtime_checkable
class Tracker(Protocol):
    """What every tracker answers.

    Examples
    --------
    >>> from vistrack.tracking import BoxTracker, PointTracker
    >>> isinstance(BoxTracker(), Tracker), isinstance(PointTracker(), Tracker)
    (True, True)
    """

    def step(self, frame: Frame, detections: Detections | None = None) -> Tracks:
        """Track one frame; return the tracks reported in it."""
        ...

    def reset(self) -> None:
        """Forget every track; identities start again from 1."""
        ...


def frame_index(frame: Frame | int | None, last: int | None) -> int:
    """The index of ``frame`` (a :class:`~vistrack.types.Frame`, or its index; None: the
    one after ``last``, or 1), checked to come after ``last``.

    Examples
    --------
    >>> frame_index(None, None), frame_index(Frame(7, 0.2), 3), frame_index(5, 4)
    (1, 7, 5)
    """
    if frame is None:
        index = 1 if last is None else last + 1
    elif isinstance(frame, Frame):
        index = int(frame.index)
    elif isinstance(frame, (int, np.integer)) and not isinstance(frame, bool):
        index = int(frame)
    else:
        raise TypeError(f"frame must be a vistrack.types.Frame or its index (an int); got "
                        f"{type(frame).__name__}")
    if last is not None and index <= last:
        raise ValueError(f"frame must increase; got {index} after {last}")
    return index


def frame_image(frame: Any, who: str) -> np.ndarray:
    """The image of ``frame``, a :class:`~vistrack.types.Frame` with one; ``who`` names the
    tracker in the error."""
    image = frame.image if isinstance(frame, Frame) else None
    if image is None:
        raise TypeError(f"{who} looks at pixels: frame must be a vistrack.types.Frame with an "
                        f"image; got {frame!r}")
    return np.asarray(image)


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
    """

    _started: bool = False

    def _start(self, image: Any, box: np.ndarray) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _follow(self, image: Any) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def init(self, image: Any, box: Any) -> None:
        """Start following the object in ``box`` (``x, y, w, h``) of ``image``."""
        self._start(image, as_box(box))
        self._started = True

    def update(self, image: Any) -> np.ndarray:
        """The object's box ``(4,)`` (``x, y, w, h``) in the next ``image``."""
        if not self._started:
            raise RuntimeError(f"{type(self).__name__}.update before init: start it with "
                               "init(image, box) or step(frame, detections)")
        return self._follow(image)

    @property
    def started(self) -> bool:
        """Whether the tracker holds an object (after :meth:`init`, until :meth:`reset`)."""
        return self._started

    def step(self, frame: Frame, detections: Detections | None = None) -> Tracks:
        """Track one frame (see the class); ``frame`` must carry its image.

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
        """Forget the object; the next frame with a detection starts the tracker again."""
        self._started = False

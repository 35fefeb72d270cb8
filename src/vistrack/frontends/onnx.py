"""A detector from the user's own ONNX model, run by onnxruntime (``pip install
'vistrack[onnx]'``): YOLO-style and SSD-style outputs, letterboxed input, a class filter and
non-maximum suppression. vistrack ships no weights and downloads none: the model file is
the user's (an ``ultralytics`` ``model.export(format="onnx")``, a YOLOv5 ``export.py``, a
converted SSD, ...).

Output layouts (``layout``; ``"auto"`` tells them apart from the outputs' shapes):

- ``"yolov8"`` (YOLOv8, YOLO11 and later): one output ``(1, 4 + C, N)``: each of the
  ``N`` columns a box centre and size ``cx, cy, w, h`` in the network input's pixels and
  ``C`` class scores. An export transposed to ``(1, N, 4 + C)`` is read too when
  ``layout="yolov8"`` is given.
- ``"yolov5"`` (YOLOv5, YOLOv7): one output ``(1, N, 5 + C)``: ``cx, cy, w, h``, an
  objectness and ``C`` class probabilities; a box's score is the objectness times its best
  class's probability.
- ``"ssd"``: two outputs, boxes ``(1, N, 4)`` as ``x0, y0, x1, y1`` in fractions of the
  network input, and scores ``(1, N, C)`` whose class 0 is the background (the classes
  reported are 1 to ``C - 1``).

A YOLO segmentation model (``yolov8`` or ``yolov5`` layout; ultralytics' ``-seg``
exports) has a second output, the masks' prototypes ``(1, M, h, w)``, and ``M`` mask
coefficients after each box's class scores in the first; vistrack follows boxes, so the
coefficients and the prototypes are left unread (they were read as class scores).

``"auto"``: two outputs are SSD's, unless the second is a segmentation model's prototypes
(four dimensions); one output whose columns are one box a cell of YOLO's
grid at the input's size (strides 8, 16 and 32: 8,400 at 640 × 640) is YOLOv8's, whose rows
are three a cell YOLOv5's; otherwise one with fewer rows than columns is YOLOv8's, and the
rest YOLOv5's (rows of one box a cell with 5 + C columns, YOLOX's or YOLOv6's, are read as
YOLOv5's; a YOLOv8 export transposed to them needs ``layout="yolov8"``). ``"yolov8"`` reads
its output's orientation by the grid too: transposed where its rows are one box a cell.

The image (BGR, as OpenCV and :class:`~vistrack.io.VideoReader` give it; grey is repeated)
is converted to RGB, scaled to the input's size keeping its aspect (letterboxed: padded
with grey 114 on both sides, as YOLO's exporters expect) or stretched (``resize=
"stretch"``, SSD's default), scaled to 0-1 and normalised by ``mean`` and ``std``; the
boxes found are mapped back to the image and clipped to it.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .._validate import as_finite, as_whole, is_number
from ..types import Detections
from .detectors import bgr_or_grey, nms

__all__ = ["ONNXDetector", "LAYOUTS", "letterbox"]

LAYOUTS = ("auto", "yolov8", "yolov5", "ssd")
"""The output layouts :class:`ONNXDetector` reads."""


def letterbox(image: np.ndarray, size: tuple[int, int],
              fill: int = 114) -> tuple[np.ndarray, float, tuple[float, float]]:
    """``image`` scaled by the largest factor ``r`` that fits it in ``size = (height, width)``,
    centred and padded with ``fill``; the factor and the padding ``(left, top)``. The image
    is resized to whole pixels, ``nw = round(w r)`` by ``nh = round(h r)``, so a point
    ``(x, y)`` of the result is ``((x - left) w / nw, (y - top) h / nh)`` in the image (which
    ``(p - (left, top)) / r`` is to within half a pixel of the result).

    Examples
    --------
    >>> out, r, (left, top) = letterbox(np.zeros((64, 128, 3), np.uint8), (64, 64))
    >>> out.shape, r, (left, top), int(out[0, 0, 0]), int(out[32, 32, 0])
    ((64, 64, 3), 0.5, (0.0, 16.0), 114, 0)
    """
    import cv2

    h, w = image.shape[:2]
    H, W = size
    r = min(H / h, W / w)
    # at least a pixel each way: a (4, 8000) image at 640 was 0 rows high (OpenCV's assertion)
    nw, nh = max(1, int(round(w * r))), max(1, int(round(h * r)))
    resized = cv2.resize(image, (nw, nh), interpolation=cv2.INTER_LINEAR) if (nw, nh) != (w, h) \
        else image
    left, top = (W - nw) / 2, (H - nh) / 2
    out = np.full((H, W) + image.shape[2:], fill, dtype=image.dtype)
    x0, y0 = int(round(left - 0.1)), int(round(top - 0.1))
    out[y0:y0 + nh, x0:x0 + nw] = resized
    return out, r, (float(x0), float(y0))


class ONNXDetector:
    """Detections from an ONNX model (see the module): ``detect(image) -> Detections``.

    Parameters
    ----------
    model : str or Path
        The ``.onnx`` file.
    layout : {"auto", "yolov8", "yolov5", "ssd"}
        How to read the outputs (:data:`LAYOUTS`).
    classes : sequence of int, optional
        Keep only these classes (the model's own indices: 0 is a person for COCO-trained
        YOLO models; SSD's start at 1, 0 being the background); default all. A class the
        model has not is refused at the first frame, when its outputs show how many it has.
    min_score : float
        Drop boxes scoring less (0.1 by default: a tracker's second stage uses the low ones).
    nms_iou : float
        Of two boxes of the same class overlapping by more than this, the lower-scoring one is
        dropped.
    input_size : (int, int), optional
        ``(height, width)`` of the network's input when the model leaves it open (640 x 640
        by default); a fixed size in the model must not be contradicted.
    resize : {"letterbox", "stretch"}, optional
        How the image is fitted to the input (default: letterbox for YOLO, stretch for SSD).
    mean, std : sequence of 3 floats
        Per RGB channel, after scaling to 0-1: ``(x - mean) / std`` (default: none).

    Raises
    ------
    ImportError
        If onnxruntime is missing.
    FileNotFoundError
        If ``model`` does not exist.
    ValueError
        If an option is invalid, the model takes no image ``(1, 3, H, W)`` of 32- or 16-bit
        floats (a batch of one), or its outputs fit no layout (naming their shapes).
    TypeError
        If ``classes`` is not a sequence (a bare ``0``).

    Notes
    -----
    Boxes are mapped back to the image and clipped to it; a box wholly outside it (in the
    letterbox's padding) is left out.
    """

    def __init__(self, model: str | Path, *, layout: str = "auto",
                 classes: Sequence[int] | None = None, min_score: float = 0.1,
                 nms_iou: float = 0.45, input_size: tuple[int, int] | None = None,
                 resize: str | None = None, mean: Sequence[float] = (0.0, 0.0, 0.0),
                 std: Sequence[float] = (1.0, 1.0, 1.0)) -> None:
        try:
            import onnxruntime as ort
        except ImportError as e:
            raise ImportError("the onnx front-end needs onnxruntime "
                              "(pip install 'vistrack[onnx]')") from e
        path = Path(model)
        if not path.is_file():
            raise FileNotFoundError(f"{path} does not exist (--frontend onnx:MODEL.onnx)")
        if layout not in LAYOUTS:
            raise ValueError(f"layout must be one of {list(LAYOUTS)}; got {layout!r}")
        if resize not in (None, "letterbox", "stretch"):
            raise ValueError(f"resize must be 'letterbox' or 'stretch'; got {resize!r}")
        # each named ("0.5" and None failed in a comparison, True was 1)
        min_score = as_finite(min_score, "min_score", 0.0, high=1.0)
        nms_iou = as_finite(nms_iou, "nms_iou", 0.0, high=1.0)
        for name, v in (("mean", mean), ("std", std)):
            # (a text was "unknown special directive", one number "has no len()")
            if isinstance(v, (str, bytes)) or np.ndim(v) != 1 or len(v) != 3 \
                    or not all(is_number(x) and np.isfinite(x) for x in v):
                raise ValueError(f"{name} must be 3 finite numbers, one a channel; got {v!r}")
        if not all(s > 0 for s in std):
            raise ValueError(f"std must be above 0 in each channel; got {std!r}")
        options = ort.SessionOptions()
        options.log_severity_level = 3
        try:
            self.session = ort.InferenceSession(str(path), options,
                                                providers=["CPUExecutionProvider"])
        except Exception as e:  # onnxruntime's own error types: a file that is not a model
            raise ValueError(f"{path}: not an ONNX model onnxruntime can run "
                             f"({' '.join(str(e).split())})") from e
        inputs = self.session.get_inputs()
        types = {"tensor(float)": np.float32, "tensor(float16)": np.float16}
        # an (H, W, 3) input, one of integers, or a batch fixed at 2 failed at the first frame
        # in onnxruntime
        if len(inputs) != 1 or len(inputs[0].shape) != 4 or inputs[0].shape[1] not in (
                3, None) and isinstance(inputs[0].shape[1], int) \
                or isinstance(inputs[0].shape[0], int) and inputs[0].shape[0] != 1 \
                or inputs[0].type not in types:
            raise ValueError(f"{path}: the model must take one image (1, 3, H, W) of floats "
                             f"(32 or 16 bits); it takes "
                             f"{[(i.name, i.shape, i.type) for i in inputs]}")
        self._dtype = types[inputs[0].type]
        self.input_name = inputs[0].name
        fixed = [d if isinstance(d, int) else None for d in inputs[0].shape[2:]]
        if input_size is None:
            size = (fixed[0] or 640, fixed[1] or 640)
        else:
            if np.ndim(input_size) != 1 or len(input_size) != 2:
                raise ValueError(f"input_size must be (height, width); got {input_size!r}")
            size = (as_whole(input_size[0], "input_size[0]", 1),
                    as_whole(input_size[1], "input_size[1]", 1))
            if any(f is not None and f != s for f, s in zip(fixed, size)):
                raise ValueError(f"{path}: input_size {size} contradicts the model's input "
                                 f"{tuple(inputs[0].shape)}")
        self.size = size
        self._path = path
        self.layout = layout if layout != "auto" else self._guess_layout(path)
        self.resize = resize or ("stretch" if self.layout == "ssd" else "letterbox")
        if classes is not None and (isinstance(classes, (str, bytes))
                                    or not np.iterable(classes)):
            raise TypeError(f"classes must be a sequence of class indices (e.g. [0]); got "
                            f"{classes!r}")
        if classes is not None:
            # checked against the model's classes at the first frame (_check_classes): a
            # class it has not, or an empty list, kept nothing, and the run blamed the model
            classes = [as_whole(c, "classes", 0, "the model's class indices")
                       for c in classes]
            if not classes:
                raise ValueError("classes must name one class or more (None: every class)")
        self.classes = None if classes is None else np.array(sorted(set(classes)), np.int64)
        self._classes_checked = False
        self.min_score, self.nms_iou = float(min_score), float(nms_iou)
        self.mean = np.asarray(mean, np.float32).reshape(3, 1, 1)
        self.std = np.asarray(std, np.float32).reshape(3, 1, 1)

    def _cells(self) -> int:
        """YOLO's grid cells at the input's size: its strides 8, 16 and 32 (YOLOv8 has one
        box a cell, 8,400 at 640 × 640; YOLOv5 three)."""
        H, W = self.size
        return sum(-(-H // s) * -(-W // s) for s in (8, 16, 32))

    def _yolo_layout(self, rows: int, cols: int) -> str:
        """One output ``(1, rows, cols)``: YOLOv8's where its columns are one box a grid
        cell, YOLOv5's where its rows are three a cell; otherwise by which side is longer (a
        YOLOv8 model of more classes than boxes, 601 classes at 160 pixels, was read as
        YOLOv5's). Rows of one box a cell are not told apart: a transposed YOLOv8 export and
        YOLOX's or YOLOv6's ``(1, N, 5 + C)``, with an objectness, share them."""
        n = self._cells()
        if cols == n and rows != cols:
            return "yolov8"
        if rows == 3 * n:
            return "yolov5"
        return "yolov8" if rows < cols else "yolov5"

    def _transposed(self, rows: int, cols: int) -> bool:
        """Whether a YOLOv8 output ``(rows, cols)`` is the export transposed, ``(N, 4 + C)``."""
        n = self._cells()
        if n in (rows, cols) and rows != cols:
            return rows == n
        return rows > cols

    def _guess_layout(self, path: Path) -> str:
        outs = self.session.get_outputs()
        if len(outs) == 2 and len(outs[1].shape) != 4:
            return "ssd"
        if len(outs) in (1, 2) and len(outs[0].shape) == 3:  # (two: YOLO's with masks)
            rows, cols = outs[0].shape[1:]
            if isinstance(rows, int) and isinstance(cols, int):
                return self._yolo_layout(rows, cols)
            return "auto"  # open dimensions: decided on the first output seen
        raise ValueError(f"{path}: cannot tell the output layout from "
                         f"{[(o.name, o.shape) for o in outs]}; give the layout "
                         f"(one of {list(LAYOUTS[1:])})")

    def _check_classes(self, first: int, n: int) -> None:
        """The class filter against the model's classes ``first .. n - 1`` (SSD's 0 is the
        background), once, at the first frame."""
        if self.classes is not None and (self.classes.min() < first or self.classes.max() >= n):
            bad = [int(c) for c in self.classes if not first <= c < n]
            raise ValueError(f"classes {bad} are not among the model's classes {first} to "
                             f"{n - 1} (--classes; its outputs have {n} class scores"
                             f"{', 0 the background' if first else ''})")
        self._classes_checked = True  # (after: refused again at the next frame, if asked)

    def _input(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The network's input, and the scale and offset ``(4,)`` that map its boxes back."""
        import cv2

        image = bgr_or_grey(image)  # float, 16-bit: OpenCV's error, or pixels past 1
        if min(image.shape[:2]) < 1:
            raise ValueError(f"image has no pixels; got shape {image.shape}")
        if image.ndim == 2:
            image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
        H, W = self.size
        h, w = image.shape[:2]
        if self.resize == "letterbox":
            fitted, r, (left, top) = letterbox(image, (H, W))
            # the resized image's own factors, whole pixels over the image's (r itself put a
            # 1920 x 1081 frame's full box back at 1080 rows, a 3840 x 2163 one's at 2160)
            rx, ry = max(1, round(w * r)) / w, max(1, round(h * r)) / h
            scale, offset = np.array([rx, ry, rx, ry]), np.array([left, top, left, top])
        else:
            fitted = cv2.resize(image, (W, H), interpolation=cv2.INTER_LINEAR)
            scale = np.array([W / w, H / h, W / w, H / h])
            offset = np.zeros(4)
        x = cv2.cvtColor(fitted, cv2.COLOR_BGR2RGB).transpose(2, 0, 1).astype(np.float32)
        x = (x / np.float32(255.0) - self.mean) / self.std
        return x[None].astype(self._dtype), scale, offset

    def _decode(self, outputs: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Boxes ``x0, y0, x1, y1`` in the input's pixels, scores and classes."""
        layout = self.layout
        if layout == "auto":
            rows, cols = np.shape(outputs[0])[1:]
            layout = self.layout = self._yolo_layout(rows, cols)
        if layout == "ssd":
            if len(outputs) != 2:
                raise ValueError(f"an SSD-style model has two outputs (boxes, scores); this "
                                 f"one gave {len(outputs)}")
            boxes, scores = np.asarray(outputs[0])[0], np.asarray(outputs[1])[0]
            if boxes.ndim != 2 or boxes.shape[1] != 4 or scores.ndim != 2 \
                    or len(scores) != len(boxes) or scores.shape[1] < 2:
                raise ValueError(f"SSD-style outputs must be boxes (1, N, 4) and scores (1, N, "
                                 f"C >= 2); got {outputs[0].shape} and {outputs[1].shape}")
            if not self._classes_checked:
                self._check_classes(1, scores.shape[1])
            cls = 1 + np.argmax(scores[:, 1:], axis=1)
            best = scores[np.arange(len(cls)), cls]
            H, W = self.size
            return boxes * np.array([W, H, W, H]), best, cls
        out = np.asarray(outputs[0])
        # a segmentation model's second output is its masks' prototypes (1, M, h, w), and
        # each box's last M values are its mask coefficients: left unread (they were read
        # as class scores, and their largest taken for the box's class)
        masks = np.shape(outputs[1])[1] if len(outputs) == 2 and np.ndim(outputs[1]) == 4 \
            and np.shape(outputs[1])[0] == 1 else 0
        if out.ndim != 3 or out.shape[0] != 1 or len(outputs) != 1 + (masks > 0):
            raise ValueError(f"a YOLO-style model has one output (1, ..., ...), or two for "
                             f"segmentation, the second its masks' prototypes (1, M, h, w); "
                             f"got {[np.shape(o) for o in outputs]}")
        a = out[0]
        with_masks = f" + {masks} mask coefficients" if masks else ""
        if layout == "yolov8":
            if self._transposed(*a.shape):  # an export transposed to (N, 4 + C)
                a = a.T
            a = a.T  # (N, 4 + C + M)
            if a.shape[1] - masks < 5:
                raise ValueError(f"a YOLOv8-style output has 4 + C{with_masks} rows (C >= 1); "
                                 f"got {out.shape}")
            n = a.shape[1] - masks - 4
            if not self._classes_checked:
                self._check_classes(0, n)
            cls = np.argmax(a[:, 4:4 + n], axis=1)
            best = a[np.arange(len(a)), 4 + cls]
        else:
            if a.shape[1] - masks < 6:
                raise ValueError(f"a YOLOv5-style output has 5 + C{with_masks} columns "
                                 f"(C >= 1); got {out.shape}")
            n = a.shape[1] - masks - 5
            if not self._classes_checked:
                self._check_classes(0, n)
            cls = np.argmax(a[:, 5:5 + n], axis=1)
            best = a[:, 4] * a[np.arange(len(a)), 5 + cls]
        c, s = a[:, :2], a[:, 2:4] / 2
        return np.c_[c - s, c + s], best, cls

    def detect(self, image: np.ndarray) -> Detections:
        """The detections in one image (BGR or grey, ``uint8``), in its pixels, best first.

        Raises
        ------
        ValueError
            If the model's outputs do not fit its layout, or a box or score it gives is not
            finite.
        """
        x, scale, offset = self._input(np.asarray(image))
        outputs = self.session.run(None, {self.input_name: x})
        boxes, scores, cls = self._decode(outputs)
        # (a NaN box was named as "boxes must be finite", an infinite score as a logit the user
        # gave, and a NaN score dropped without a word)
        # among the boxes min_score would keep (a NaN score is none it can judge)
        bad = ~(scores < self.min_score) & ~(np.isfinite(boxes).all(1) & np.isfinite(scores))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(f"the model gave {int(bad.sum())} box(es) or score(s) that are not "
                             f"finite (box {i}: {boxes[i].tolist()}, score {float(scores[i])}) "
                             f"for this image ({self._path})")
        keep = scores >= self.min_score
        if self.classes is not None:
            keep &= np.isin(cls, self.classes)
        boxes, scores, cls = boxes[keep].astype(np.float64), scores[keep].astype(np.float64), \
            cls[keep].astype(np.int64)
        if len(boxes):
            kept = nms(boxes, scores, self.nms_iou, cls)  # per class
            boxes, scores, cls = boxes[kept], scores[kept], cls[kept]
        h, w = np.asarray(image).shape[:2]
        boxes = (boxes - offset) / scale
        boxes = np.clip(boxes, 0.0, [w, h, w, h])
        # a box wholly outside the image (in the letterbox's padding) is clipped to no area:
        # not a detection in the image, and one no track could follow
        inside = (boxes[:, 2] > boxes[:, 0]) & (boxes[:, 3] > boxes[:, 1])
        return Detections(boxes=boxes[inside], scores=scores[inside], classes=cls[inside])

    def __repr__(self) -> str:
        classes = None if self.classes is None else self.classes.tolist()
        return (f"ONNXDetector(layout={self.layout!r}, input {self.size[0]}x{self.size[1]}, "
                f"{self.resize}, classes={classes}, min_score={self.min_score}, "
                f"nms_iou={self.nms_iou})")

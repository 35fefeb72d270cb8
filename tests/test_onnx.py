"""The ONNX front-end: small models built here (onnx.helper) that emit known tensors in each
output layout, and the boxes they must give, worked by hand; letterboxing, the class filter,
the score threshold and per-class suppression; and the front-end in a tracking run."""

from pathlib import Path

import numpy as np
import pytest

onnx = pytest.importorskip("onnx")
pytest.importorskip("onnxruntime")

from onnx import TensorProto, helper, numpy_helper  # noqa: E402

from vistrack.frontends.onnx import ONNXDetector, letterbox  # noqa: E402


def constant_model(path: Path, outputs: list[np.ndarray], size=(64, 64),
                   names=("out0", "out1"), batch=1) -> Path:
    """A model taking an image (1, 3, H, W) and returning ``outputs`` whatever the image,
    each plus 0 times the image's mean, so that the input is used."""
    H, W = size
    nodes = [helper.make_node("ReduceMean", ["images"], ["mean"], keepdims=0),
             helper.make_node("Mul", ["mean", "zero"], ["nothing"])]
    inits = [numpy_helper.from_array(np.zeros((), np.float32), "zero")]
    outs = []
    for k, value in enumerate(outputs):
        inits.append(numpy_helper.from_array(value.astype(np.float32), f"value{k}"))
        nodes.append(helper.make_node("Add", [f"value{k}", "nothing"], [names[k]]))
        outs.append(helper.make_tensor_value_info(names[k], TensorProto.FLOAT, value.shape))
    graph = helper.make_graph(
        nodes, "constant", [helper.make_tensor_value_info("images", TensorProto.FLOAT,
                                                          [batch, 3, H, W])], outs, inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.checker.check_model(model)
    onnx.save(model, str(path))
    return path


IMAGE = np.zeros((64, 128, 3), np.uint8)  # 128 wide, 64 high: letterboxed into 64 x 64 at 1/2,
# 16 rows of padding above and below


def to_image(x0, y0, x1, y1):
    """A box in the 64 x 64 input's pixels, in IMAGE's: minus the padding, times 2."""
    return [2 * x0, 2 * (y0 - 16), 2 * x1, 2 * (y1 - 16)]


def test_letterbox_centres_the_scaled_image():
    img = np.arange(64 * 128 * 3, dtype=np.uint8).reshape(64, 128, 3)
    out, r, (left, top) = letterbox(img, (64, 64))
    assert (r, left, top) == (0.5, 0.0, 16.0)
    assert (out[:16] == 114).all() and (out[48:] == 114).all()
    out, r, (left, top) = letterbox(np.zeros((100, 50), np.uint8), (64, 64))
    assert (out.shape, r, left, top) == ((64, 64), 0.64, 16.0, 0.0)


def test_letterboxed_boxes_map_back_by_the_resized_image_s_own_factors(tmp_path):
    """An image of 129 x 65 fits the 64 x 64 input at r = 64/129 as 64 x 32 whole pixels (32.25
    rounded): the box of the whole resized content, (0, 16)-(64, 48) in the input, is the whole
    image, (0, 0)-(129, 65). Mapped back by r on both axes it was 64.5 rows high (a 1920 x 1081
    frame came back 1080 high, a 3840 x 2163 one 2160)."""
    cols = np.array([[32, 32, 64, 32, 0.9]] + [[0, 0, 0, 0, 0]] * 8, np.float32)
    det = ONNXDetector(constant_model(tmp_path / "whole.onnx", [cols.T[None]]))
    d = det.detect(np.zeros((65, 129, 3), np.uint8))
    np.testing.assert_allclose(d.boxes, [[0, 0, 129, 65]], atol=1e-4)


def test_yolov8_layout(tmp_path):
    # (1, 4 + C, N): C = 3 classes, N = 4 boxes, one per column
    cols = np.array([
        # cx, cy, w, h, class scores
        [32, 32, 20, 10, 0.9, 0.1, 0.0],   # class 0 at 0.9
        [33, 32, 20, 10, 0.8, 0.0, 0.0],   # the same place, lower: suppressed
        [33, 32, 20, 10, 0.0, 0.7, 0.0],   # the same place, class 1: kept
        [10, 20, 4, 8, 0.0, 0.0, 0.05],    # below min_score
    ] + [[0, 0, 0, 0, 0, 0, 0]] * 8, np.float32)  # N = 12 columns, more than 4 + C = 7 rows
    model = constant_model(tmp_path / "v8.onnx", [cols.T[None]])
    det = ONNXDetector(model)
    assert det.layout == "yolov8" and det.size == (64, 64) and det.resize == "letterbox"
    d = det.detect(IMAGE)
    np.testing.assert_allclose(d.boxes, [to_image(22, 27, 42, 37), to_image(23, 27, 43, 37)])
    np.testing.assert_allclose(d.scores, [0.9, 0.7], rtol=1e-6)
    assert d.classes.tolist() == [0, 1]
    # only class 1
    d = ONNXDetector(model, classes=[1]).detect(IMAGE)
    assert d.classes.tolist() == [1] and len(d) == 1
    # everything above 0, the lowest too, and no suppression
    d = ONNXDetector(model, min_score=0.01, nms_iou=1.0).detect(IMAGE)
    assert len(d) == 4
    # the same export transposed to (1, N, 4 + C), its layout given
    model_t = constant_model(tmp_path / "v8t.onnx", [cols[None]])
    assert ONNXDetector(model_t).layout == "yolov5"  # as its shape says: N rows > 7 columns
    d = ONNXDetector(model_t, layout="yolov8").detect(IMAGE)
    np.testing.assert_allclose(d.boxes[0], to_image(22, 27, 42, 37))


def test_yolov5_layout(tmp_path):
    # (1, N, 5 + C): objectness times the best class's probability
    rows = np.array([
        [32, 32, 20, 10, 0.5, 0.2, 0.8],   # class 1 at 0.4
        [40, 40, 8, 8, 0.9, 0.9, 0.1],     # class 0 at 0.81
        [20, 20, 8, 8, 0.1, 0.5, 0.5],     # 0.05: below min_score
        [41, 40, 8, 8, 0.9, 0.8, 0.1],     # class 0 at 0.72, overlapping the second: dropped
        [50, 30, 6, 6, 0.3, 0.1, 0.1],     # 0.03
        [5, 5, 4, 4, 0.2, 0.5, 0.0],       # 0.1 (>= min_score), but in the padding: left out
        [60, 60, 4, 4, 0.0, 1.0, 1.0],
        [30, 50, 2, 2, 0.0, 0.0, 0.0],
    ], np.float32)  # 8 rows, 7 columns: rows > columns, so "auto" reads YOLOv5
    model = constant_model(tmp_path / "v5.onnx", [rows[None]])
    det = ONNXDetector(model)
    assert det.layout == "yolov5"
    d = det.detect(IMAGE)
    np.testing.assert_allclose(d.scores, [0.81, 0.4], rtol=1e-6)
    assert d.classes.tolist() == [0, 1]
    np.testing.assert_allclose(d.boxes, [to_image(36, 36, 44, 44), to_image(22, 27, 42, 37)])


def test_ssd_layout(tmp_path):
    # boxes (1, N, 4) x0, y0, x1, y1 as fractions of the input; scores (1, N, C), class 0 the
    # background; the image stretched (not letterboxed) to the input
    boxes = np.array([[0.25, 0.5, 0.5, 1.0], [0.1, 0.1, 0.2, 0.2], [0.0, 0.0, 1.0, 1.0]])
    scores = np.array([[0.1, 0.2, 0.7], [0.9, 0.05, 0.05], [0.5, 0.3, 0.2]])
    model = constant_model(tmp_path / "ssd.onnx", [boxes[None], scores[None]], size=(32, 32))
    det = ONNXDetector(model, min_score=0.25)
    assert det.layout == "ssd" and det.resize == "stretch"
    d = det.detect(IMAGE)  # 128 x 64: x times 128, y times 64
    np.testing.assert_allclose(d.boxes, [[32, 32, 64, 64], [0, 0, 128, 64]])
    np.testing.assert_allclose(d.scores, [0.7, 0.3], rtol=1e-6)
    assert d.classes.tolist() == [2, 1]


def _same_detections(model, layout, want):
    """The model read with ``layout`` given and guessed: ``want``'s boxes, scores, classes."""
    for given in ("auto", layout):
        det = ONNXDetector(model, layout=given)
        assert det.layout == layout
        d = det.detect(IMAGE)
        for field in ("boxes", "scores", "classes"):
            np.testing.assert_array_equal(getattr(d, field), getattr(want, field))


def test_a_segmentation_model_s_mask_coefficients_are_not_read_as_classes(tmp_path):
    """A YOLO segmentation export (ultralytics' -seg) gives a second output, the masks'
    prototypes (1, M, h, w), and M mask coefficients after each box's class scores. "auto"
    took the two outputs for SSD's and refused them; layout="yolov8" read the coefficients as
    class scores (here a coefficient of 5 became a box of "class 3" scoring 5). The oracle is
    the same boxes from the export without masks (the layouts' own tests, worked by hand)."""
    C, M, N = 2, 3, 84  # N: the grid's cells at 64 x 64 (64 + 16 + 4), one box a cell
    v8 = np.zeros((N, 4 + C + M), np.float32)
    v8[0] = [32, 32, 20, 10, 0.9, 0.1, 5.0, -4.0, 2.0]   # class 0 at 0.9
    v8[1] = [10, 40, 8, 8, 0.0, 0.6, 0.0, 7.0, 0.0]      # class 1 at 0.6
    v8[2] = [50, 30, 6, 6, 0.01, 0.02, 9.0, 9.0, 9.0]    # below min_score in its classes
    protos = np.zeros((1, M, 16, 16), np.float32)
    seg = constant_model(tmp_path / "v8seg.onnx", [v8.T[None], protos])
    plain = constant_model(tmp_path / "v8.onnx", [np.ascontiguousarray(v8[:, :4 + C].T)[None]])
    want = ONNXDetector(plain).detect(IMAGE)
    assert want.classes.tolist() == [0, 1]
    np.testing.assert_allclose(want.scores, [0.9, 0.6], rtol=1e-6)
    _same_detections(seg, "yolov8", want)
    # a class past the model's two is refused: the coefficients are not classes
    with pytest.raises(ValueError, match=r"classes \[2\] are not among the model's classes 0 "
                                         r"to 1"):
        ONNXDetector(seg, classes=[2]).detect(IMAGE)
    # YOLOv5's segmentation export: (1, 3 cells, 5 + C + M), an objectness first
    v5 = np.zeros((3 * N, 5 + C + M), np.float32)
    v5[0] = [40, 40, 8, 8, 0.9, 0.9, 0.1, 8.0, 8.0, 8.0]  # class 0 at 0.81
    v5[1] = [20, 30, 8, 8, 0.5, 0.2, 0.8, 0.0, 9.0, 0.0]  # class 1 at 0.4
    seg5 = constant_model(tmp_path / "v5seg.onnx", [v5[None], protos])
    plain5 = constant_model(tmp_path / "v5.onnx", [np.ascontiguousarray(v5[:, :5 + C])[None]])
    want = ONNXDetector(plain5).detect(IMAGE)
    np.testing.assert_allclose(want.scores, [0.81, 0.4], rtol=1e-6)
    _same_detections(seg5, "yolov5", want)
    # a second output that is not prototypes is no YOLO layout's, and says what it takes
    other = constant_model(tmp_path / "odd.onnx", [v8.T[None], np.zeros((1, 5), np.float32)])
    with pytest.raises(ValueError, match=r"or two for segmentation, the second its masks' "
                                         r"prototypes \(1, M, h, w\); got \[\(1, 9, 84\), "
                                         r"\(1, 5\)\]"):
        ONNXDetector(other, layout="yolov8").detect(IMAGE)


def test_the_onnx_detector_checks_what_it_is_given(tmp_path):
    model = constant_model(tmp_path / "m.onnx", [np.zeros((1, 6, 10))])
    with pytest.raises(FileNotFoundError, match="nope.onnx"):
        ONNXDetector(tmp_path / "nope.onnx")
    with pytest.raises(ValueError, match="layout must be one of"):
        ONNXDetector(model, layout="yolov3")
    with pytest.raises(ValueError, match="contradicts the model's input"):
        ONNXDetector(model, input_size=(32, 32))
    bad = tmp_path / "bad.onnx"
    bad.write_bytes(b"not a model")
    with pytest.raises(ValueError, match="bad.onnx: not an ONNX model"):
        ONNXDetector(bad)
    with pytest.raises(ValueError, match="two outputs"):
        ONNXDetector(model, layout="ssd").detect(IMAGE)
    mismatched = constant_model(tmp_path / "two.onnx", [np.zeros((1, 2, 4)),
                                                         np.zeros((1, 3, 2))])
    with pytest.raises(ValueError, match=r"scores \(1, N, C >= 2\); got \(1, 2, 4\) and "
                                         r"\(1, 3, 2\)"):
        ONNXDetector(mismatched).detect(IMAGE)


def _model_taking(path: Path, shape, elem=TensorProto.FLOAT) -> Path:
    """A model whose input is ``shape`` of ``elem`` and whose output is one YOLOv8 column."""
    out = np.zeros((1, 5, 8), np.float32)  # 8 columns, the others scoring 0
    out[0, :, 0] = [32, 32, 8, 8, 0.9]
    nodes = [helper.make_node("Cast", ["images"], ["f"], to=TensorProto.FLOAT),
             helper.make_node("ReduceMean", ["f"], ["mean"], keepdims=0),
             helper.make_node("Mul", ["mean", "zero"], ["nothing"]),
             helper.make_node("Add", ["value", "nothing"], ["out0"])]
    inits = [numpy_helper.from_array(np.zeros((), np.float32), "zero"),
             numpy_helper.from_array(out, "value")]
    graph = helper.make_graph(nodes, "taking", [helper.make_tensor_value_info(
        "images", elem, shape)], [helper.make_tensor_value_info("out0", TensorProto.FLOAT,
                                                                 out.shape)], inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.save(model, str(path))
    return path


def test_what_the_onnx_detector_takes_is_named_before_the_first_frame(tmp_path):
    """Each of these failed at the first frame inside onnxruntime or OpenCV, or gave nothing
    without a word: classes the model has not (a 2-class model with ``classes=[5]``, an SSD
    one with its background 0: "found nothing", blaming the model), an empty or fractional
    class list, an ``input_size`` of 0 or 640.9, an (H, W, 3) input, a float image, an
    empty one. A float16 model now takes its input as float16; a box wholly outside the
    image (in the letterbox's padding) was clipped to a box of no area and kept."""
    two = np.zeros((1, 6, 20), np.float32)
    two[0, :, 0] = [32, 32, 8, 8, 0.9, 0.1]
    model = constant_model(tmp_path / "two.onnx", [two])
    with pytest.raises(ValueError, match=r"classes \[5\] are not among the model's classes 0 "
                                         r"to 1 \(--classes; its outputs have 2 class scores\)"):
        ONNXDetector(model, classes=[0, 5]).detect(IMAGE)
    refusing = ONNXDetector(model, classes=[5])
    for _ in range(2):  # every frame, not the first alone
        with pytest.raises(ValueError, match=r"classes \[5\]"):
            refusing.detect(IMAGE)
    assert len(ONNXDetector(model, classes=[0]).detect(IMAGE)) == 1
    ssd = constant_model(tmp_path / "ssd.onnx", [np.full((1, 5, 4), 0.5, np.float32),
                                                  np.full((1, 5, 3), 0.3, np.float32)])
    with pytest.raises(ValueError, match=r"classes \[0\] are not among the model's classes 1 "
                                         r"to 2 .* 0 the background"):
        ONNXDetector(ssd, classes=[0]).detect(IMAGE)
    for kw, message in (({"classes": []}, "classes must name one class or more"),
                        ({"classes": [0.7]}, "classes must be a whole number >= 0"),
                        ({"classes": [-1]}, "classes must be a whole number >= 0"),
                        ({"input_size": (0, 64)}, r"input_size\[0\] must be a whole number"),
                        ({"input_size": (64.9, 64)}, r"input_size\[0\] must be a whole"),
                        ({"input_size": 64}, r"input_size must be \(height, width\)"),
                        ({"mean": (np.nan, 0, 0)}, "mean must be 3 finite numbers"),
                        # each named: a comparison's TypeError, np.r_'s "unknown special
                        # directive", "has no len()", and True taken as 1, before
                        ({"min_score": "0.5"}, "min_score must be a number"),
                        ({"min_score": None}, "min_score must be a number"),
                        ({"nms_iou": True}, "nms_iou must be a number"),
                        ({"nms_iou": 1.5}, r"nms_iou must be a finite number >= 0 and <= 1"),
                        ({"mean": "abc"}, "mean must be 3 finite numbers, one a channel"),
                        ({"std": 1.0}, "std must be 3 finite numbers, one a channel"),
                        ({"std": (1, 0, 1)}, "std must be above 0 in each channel")):
        with pytest.raises((TypeError, ValueError), match=message):
            ONNXDetector(model, **kw)
    nhwc = _model_taking(tmp_path / "nhwc.onnx", [1, 64, 64, 3])
    with pytest.raises(ValueError, match=r"must take one image \(1, 3, H, W\) of floats"):
        ONNXDetector(nhwc)
    half = ONNXDetector(_model_taking(tmp_path / "half.onnx", [1, 3, 64, 64],
                                      TensorProto.FLOAT16))
    np.testing.assert_allclose(half.detect(IMAGE).boxes, [to_image(28, 28, 36, 36)])
    detector = ONNXDetector(model)
    for image, message in ((IMAGE.astype(np.float64), "image must be"),
                           (IMAGE.astype(np.uint16), "image must be"),
                           (np.zeros((0, 0, 3), np.uint8), "image has no pixels")):
        with pytest.raises(ValueError, match=message):
            detector.detect(image)
    padded = np.zeros((1, 5, 8), np.float32)  # the last 6 columns score 0
    padded[0, :, 0] = [32, 4, 8, 4, 0.9]  # rows 2-6 of the input: its padding (0-15)
    padded[0, :, 1] = [32, 32, 8, 8, 0.8]
    got = ONNXDetector(constant_model(tmp_path / "pad.onnx", [padded])).detect(IMAGE)
    np.testing.assert_allclose(got.boxes, [to_image(28, 28, 36, 36)])
    assert got.scores.tolist() == [pytest.approx(0.8)]


def test_an_onnx_model_as_the_front_end_of_a_tracking_run(tmp_path, capsys):
    from vistrack.cli import main
    from vistrack.data import demo_clip
    from vistrack.io import read_mot
    from vistrack.pipeline import track_video

    # one person-sized box, class 0, and a car (class 2) elsewhere, in every frame; the
    # clip is 768 x 576, letterboxed into 64 x 64 at 1/12 with 8 rows of padding at the top
    cols = np.array([[32, 32, 8, 16, 0.9, 0.0, 0.0], [10, 20, 6, 4, 0.0, 0.0, 0.9]]
                    + [[0.0] * 7] * 10).T[None]  # (1, 4 + 3, 12)
    model = constant_model(tmp_path / "m.onnx", [cols])
    run = track_video(demo_clip().video, tmp_path / "out", frontend=f"onnx:{model}", stop=6,
                      annotate=False, classes=[0])
    t = read_mot(run.out_dir / "tracks.txt")
    assert len(np.unique(t.ids)) == 1 and t.frames.max() == 6
    # x0 = (32 - 4) * 12 = 336, y0 = (32 - 8 - 8) * 12 = 192, 96 wide, 192 high
    np.testing.assert_allclose(t.boxes[-1], [336, 192, 96, 192], atol=0.01)
    assert main(["track", str(demo_clip().video), "--frontend", f"onnx:{model}", "--classes",
                 "0,2", "--onnx-layout", "yolov8", "--stop", "6", "--out-dir",
                 str(tmp_path / "cli"), "--still-camera"]) == 0
    t = read_mot(tmp_path / "cli" / "tracks.txt")
    assert len(np.unique(t.ids)) == 2  # the person and the car
    capsys.readouterr()
    assert main(["track", str(demo_clip().video), "--frontend", "onnx:missing.onnx",
                 "--out-dir", str(tmp_path / "x")]) == 2
    assert "missing.onnx does not exist" in capsys.readouterr().err


def test_classes_on_the_command_line_are_checked(capsys):
    from vistrack.cli import main

    for bad in ("a", "-1", ","):
        with pytest.raises(SystemExit) as e:
            main(["track", "x.mp4", "--out-dir", "o", "--classes", bad])
        assert e.value.code == 2
        assert "--classes" in capsys.readouterr().err


def test_yolo_outputs_are_told_by_the_grid_not_by_their_longer_side(tmp_path):
    """A YOLOv8 model of more classes than boxes (601 classes at 160 pixels: 605 rows, 525
    columns) was read as transposed, or as YOLOv5's, and every detection was lost; a YOLOv5
    model of more classes than boxes was read as YOLOv8's. The grid says which side is the
    boxes: at 64 x 64, strides 8, 16 and 32 give 64 + 16 + 4 = 84 cells, one box each for
    YOLOv8, three for YOLOv5 (oracle: the box worked by hand, class 7 at 0.9)."""
    C = 100
    v8 = np.zeros((4 + C, 84), np.float32)
    v8[:4, 0] = [32, 32, 20, 10]
    v8[4 + 7, 0] = 0.9
    v5 = np.zeros((3 * 84, 5 + 3 * C), np.float32)
    v5[0, :5] = [32, 32, 20, 10, 1.0]
    v5[0, 5 + 7] = 0.9
    for name, out, layout in (("v8", v8, "yolov8"), ("v8t", v8.T, "yolov8"),
                              ("v5", v5, "yolov5")):
        model = constant_model(tmp_path / f"{name}.onnx", [out[None]])
        for given in ("auto", layout):
            det = ONNXDetector(model, layout=given)
            assert det.layout == layout
            d = det.detect(IMAGE)
            np.testing.assert_allclose(d.boxes, [to_image(22, 27, 42, 37)], atol=1e-4)
            assert d.classes.tolist() == [7]
            np.testing.assert_allclose(d.scores, [0.9], rtol=1e-6)
    # YOLOX's and YOLOv6's one box a cell with an objectness, (1, N, 5 + C), stay YOLOv5's:
    # read as a transposed YOLOv8 export, the objectness became class 0's score
    yolox = np.zeros((84, 5 + 20), np.float32)  # as 8,400 x 85 at 640
    yolox[0, :5] = [32, 32, 20, 10, 0.9]
    yolox[0, 5 + 2] = 0.8
    det = ONNXDetector(constant_model(tmp_path / "yolox.onnx", [yolox[None]]))
    assert det.layout == "yolov5"
    d = det.detect(IMAGE)
    assert d.classes.tolist() == [2]
    np.testing.assert_allclose(d.scores, [0.72], rtol=1e-6)


def test_a_model_s_odd_input_or_output_is_named(tmp_path):
    """A batch fixed at 2 was taken and failed at the first frame in onnxruntime; an image of
    (4, 8000) letterboxed to 0 rows (OpenCV's assertion); a NaN box from the model was named
    as "boxes must be finite", an infinite score as a logit the user gave, a NaN score was
    dropped; ``classes=0`` was "'int' object is not iterable"."""
    import re

    cols = np.array([[32, 32, 20, 10, 0.9]] + [[0, 0, 0, 0, 0]] * 8, np.float32)
    with pytest.raises(ValueError, match=re.escape("the model must take one image (1, 3, H, W)")):
        ONNXDetector(constant_model(tmp_path / "b2.onnx", [cols.T[None]], batch=2))
    det = ONNXDetector(constant_model(tmp_path / "ok.onnx", [cols.T[None]]))
    d = det.detect(np.zeros((4, 8000, 3), np.uint8))  # 64 x 0.03 rows: one row
    assert np.isfinite(d.boxes).all()
    out, r, _ = letterbox(np.zeros((4, 8000, 3), np.uint8), (64, 64))
    assert out.shape == (64, 64, 3) and (out[..., 0] == 0).all(1).sum() == 1  # one row
    for k, bad in ((0, np.nan), (4, np.inf), (4, np.nan)):
        c = cols.copy()
        c[0, k] = bad
        model = constant_model(tmp_path / f"bad{k}{bad}.onnx", [c.T[None]])
        with pytest.raises(ValueError, match=re.escape(
                "the model gave 1 box(es) or score(s) that are not finite (box 0: ")
                + f".*for this image \\({re.escape(str(model))}\\)"):
            ONNXDetector(model).detect(IMAGE)
    # below min_score, such a row is one the detector drops anyway: the frame's box stays
    c = cols.copy()
    c[1] = [np.nan, 0, np.inf, 1, 0.0]
    c[2, 4] = -np.inf
    d = ONNXDetector(constant_model(tmp_path / "low.onnx", [c.T[None]])).detect(IMAGE)
    np.testing.assert_allclose(d.scores, [0.9], rtol=1e-6)
    with pytest.raises(TypeError, match=re.escape(
            "classes must be a sequence of class indices (e.g. [0]); got 0")):
        ONNXDetector(constant_model(tmp_path / "c.onnx", [cols.T[None]]), classes=0)

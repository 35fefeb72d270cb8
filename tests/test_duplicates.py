"""A detector without non-maximum suppression: its copies of one object each started a track
of their own. ``nms_iou`` (``--nms-iou``) suppresses them, and a detections file made of such
copies says so in a warning."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from vistrack.association import non_maximum
from vistrack.io import read_mot, write_mot

from .mot_oracles import seq_dir


def _greedy(boxes, scores, classes, min_iou):
    """The textbook loop, one box at a time: the oracle of :func:`non_maximum`."""
    def iou(a, b):
        w = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
        h = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
        inter = w * h
        union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
        return inter / union if union > 0 else 0.0

    order = sorted(range(len(boxes)), key=lambda i: (-scores[i], i))
    keep = [True] * len(boxes)
    for n, i in enumerate(order):
        if not keep[i]:
            continue
        for j in order[n + 1:]:
            if keep[j] and classes[j] == classes[i] and iou(boxes[i], boxes[j]) >= min_iou:
                keep[j] = False
    return keep


@pytest.mark.parametrize("seed", range(20))
def test_non_maximum_is_the_greedy_loop(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 60))
    xy = rng.uniform(0, 100, (n, 2))
    wh = rng.uniform(5, 30, (n, 2))
    boxes = np.c_[xy, xy + wh]
    scores = rng.choice([0.2, 0.5, 0.9], n) if seed % 2 else rng.random(n)  # ties, or none
    classes = rng.integers(0, 2, n)
    for min_iou in (0.3, 0.5, 0.7):
        got = non_maximum(boxes, scores, classes, min_iou).tolist()
        assert got == _greedy(boxes.tolist(), scores.tolist(), classes.tolist(), min_iou)


def test_a_nan_class_is_named():
    """NaN equals no class, its own included: two copies of one box of class NaN were both
    kept, where any class shared suppresses one."""
    box = [[0, 0, 10, 10], [0, 0, 10, 10]]
    assert non_maximum(box, [0.9, 0.8], [1.0, 1.0]).tolist() == [True, False]
    with pytest.raises(ValueError, match=r"classes must be numbers; classes\[0\] is NaN"):
        non_maximum(box, [0.9, 0.8], [np.nan, np.nan])
    with pytest.raises(ValueError, match=r"classes\[1\] is NaN"):
        non_maximum(box, [0.9, 0.8], np.array(["a", np.nan], dtype=object))
    assert non_maximum(box, [0.9, 0.8], np.array(["a", "a"], dtype=object)).tolist() == [
        True, False]  # (names as classes, as before)


def test_exact_copies_are_suppressed_to_the_original_tracks(tmp_path):
    """Each detection repeated with a lower score: suppressed at any ``nms_iou`` below 1, the
    file tracks exactly as the one without the copies; left in, they make tracks of their
    own, and the file's warning says what to do."""
    from vistrack.pipeline import track_sequence

    rows = [(f, -1, 20 + 4 * f + 80 * k, 30, 20, 50, 0.9) for f in range(1, 31) for k in range(3)]
    one = tmp_path / "one.txt"
    one.write_text("".join(",".join(map(str, r)) + "\n" for r in rows))
    two = tmp_path / "two.txt"
    two.write_text("".join(",".join(map(str, r)) + "\n" + ",".join(map(str, r[:6])) + ",0.5\n"
                           for r in rows))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        track_sequence(one, tmp_path / "a.txt", fps=10)
    with pytest.warns(UserWarning, match=re.escape(
            f"{two}: 100% of the detections overlap another of their frame and class at IoU "
            "0.7 or more (at most 3 % in detectors that apply non-maximum suppression): "
            "copies of one object, each of which starts a track of its own; --nms-iou 0.7 "
            "(nms_iou under [tracker] in a --config file) keeps the most confident of each")):
        track_sequence(two, tmp_path / "b.txt", fps=10)
    assert len(set(read_mot(tmp_path / "b.txt").ids.tolist())) > 3  # copies tracked too
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # given nms_iou, no warning
        track_sequence(two, tmp_path / "c.txt", fps=10, nms_iou=0.7)
    assert (tmp_path / "c.txt").read_text() == (tmp_path / "a.txt").read_text()


def test_a_detector_without_suppression_on_a_real_sequence(tmp_path):
    """MOT17-09 with a copy of every detection, moved by 5 % of its size and scaled by 5 %
    (standard deviations), scoring 0.7-1 times as much: HOTA fell from 49.3 to 30.1; with
    ``nms_iou`` 0.7 it scores 49.1. No sequence
    of the shared data has 3 % of its detections overlapping at 0.7 (MOT16-09 with FairMOT's
    the most, 2.4 %), nor MOT20-01's ground truth (3.0 %, a dense crowd); such copies, 96 %."""
    from vistrack.detector_checks import duplicate_share
    from vistrack.evaluation import evaluate_mot
    from vistrack.pipeline import track_sequence

    d = seq_dir("MOT17", "MOT17-09-FRCNN")
    t = read_mot(d / "det" / "det.txt")
    rng = np.random.default_rng(0)
    b = t.boxes.copy()
    b[:, :2] += rng.normal(0, 0.05, (len(t), 2)) * b[:, 2:]
    b[:, 2:] *= np.exp(rng.normal(0, 0.05, (len(t), 2)))
    conf = t.conf * rng.uniform(0.7, 1.0, len(t))
    f = np.r_[t.frames, t.frames]
    o = np.argsort(f, kind="stable")
    dup = tmp_path / "dup.txt"
    write_mot(dup, f[o], np.full(len(f), -1), np.r_[t.boxes, b][o], np.r_[t.conf, conf][o])
    assert duplicate_share(t) < 0.03 and duplicate_share(read_mot(dup)) > 0.9
    gt = read_mot(d / "gt" / "gt.txt")

    def hota(det, **kw):
        out = tmp_path / f"out{len(list(tmp_path.iterdir()))}.txt"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            track_sequence(d, out, detections=det, **kw)
        return evaluate_mot(gt, read_mot(out), 525, benchmark="MOT17").HOTA

    plain, copies, suppressed = hota(None), hota(dup), hota(dup, nms_iou=0.7)
    assert copies < plain - 0.15
    assert suppressed > plain - 0.015


def test_a_video_tracked_from_such_a_file_warns_too(tmp_path):
    """``--frontend detections:FILE`` reads the file as ``vistrack track FILE`` does: the
    same warning, none with ``nms_iou`` set, and then one track for the one disc."""
    from vistrack.pipeline import track_video

    from .test_pipeline import red_disc_clip, write_clip

    frames, truth = red_disc_clip(T=12)
    clip = write_clip(tmp_path / "frames", frames)
    dets = tmp_path / "dets.txt"
    dets.write_text("".join(f"{k + 1},-1,{x:.2f},{y:.2f},{w:.2f},{h:.2f},0.9\n"
                            f"{k + 1},-1,{x + 1:.2f},{y:.2f},{w:.2f},{h:.2f},0.8\n"
                            for k, (x, y, w, h) in enumerate(truth)))
    with pytest.warns(UserWarning, match=re.escape(f"{dets}: 100% of the detections overlap")):
        track_video(clip, tmp_path / "a", frontend=f"detections:{dets}", fps=10,
                    annotate=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = track_video(clip, tmp_path / "b", frontend=f"detections:{dets}", fps=10,
                        annotate=False, nms_iou=0.7)
    assert r.tracks == 1

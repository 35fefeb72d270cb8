"""One tracker protocol and one loop: every tracker answers ``step(frame, detections)`` and
``reset()``, :func:`vistrack.pipeline.run` drives any of them into any sinks, and the
registries name the valid parts."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from vistrack.evaluation.single import success_rate
from vistrack.io import read_mot
from vistrack.io.tracks import BoxesWriter, CSVWriter, MOTWriter, TrackRows
from vistrack.pipeline import FRONTENDS, SINKS, TRACKERS, Registry, as_detector, run, track_video
from vistrack.tracking import (
    METHODS,
    BoxTracker,
    Composite,
    DetectorConfidencePF,
    KLTTracker,
    PointTracker,
    SingleObjectTracker,
    Tracker,
    single_tracker,
)
from vistrack.types import Detections, Frame, Tracks

ROOT = Path(__file__).resolve().parents[1]


def red_disc_clip(T=30, size=(160, 120)):
    """Frames of a red disc moving right on a grey background, and its true boxes (xywh)."""
    W, H = size
    frames, boxes = [], []
    for k in range(T):
        im = np.full((H, W, 3), 120, np.uint8)
        cx, cy, r = 30 + 2 * k, 60, 12
        cv2.circle(im, (cx, cy), r, (30, 30, 220), -1)
        frames.append(Frame(k + 1, k / 25, im))
        boxes.append([cx - r, cy - r, 2 * r, 2 * r])
    return frames, np.array(boxes, float)


def every_tracker():
    """One of each tracker class, ready to step."""
    out = {"BoxTracker": BoxTracker(), "PointTracker": PointTracker(),
           "DetectorConfidencePF": DetectorConfidencePF(gamma=0.0), "KLTTracker": KLTTracker(),
           "Composite": Composite({"colour": (single_tracker("colour"), (4.0, 8.0))})}
    out.update({f"single:{m}": single_tracker(m) for m in METHODS})
    return out


@pytest.mark.parametrize("name", list(every_tracker()))
def test_every_tracker_answers_the_protocol(name):
    """Each tracker is a Tracker, steps through frames with the frame's detections into
    Tracks, and after reset() gives the same tracks again from the same frames."""
    tracker = every_tracker()[name]
    assert isinstance(tracker, Tracker)
    frames, boxes = red_disc_clip(T=8)
    points = name == "PointTracker"

    def dets(k):
        b = boxes[k]
        if points:
            return Detections(points=[b[:2] + b[2:] / 2])
        return Detections.from_xywh([b], [0.9])

    def go():
        out = [tracker.step(f, dets(k)) for k, f in enumerate(frames)]
        assert all(isinstance(t, Tracks) for t in out)
        return out

    first = go()
    tracker.reset()
    again = go()
    for a, b in zip(first, again):
        np.testing.assert_array_equal(a.ids, b.ids)
        np.testing.assert_array_equal(a.boxes if a.boxes is not None else a.points,
                                      b.boxes if b.boxes is not None else b.points)
    if name not in ("KLTTracker",):  # KLT follows its own features, not the disc
        last = first[-1]
        assert len(last) >= 1 and last.ids[0] == 1
        if not points:
            assert last.boxes.shape == (len(last), 4)


def test_single_object_trackers_start_at_the_best_detection_and_follow_it():
    frames, truth = red_disc_clip()
    tr = single_tracker("colour")
    assert not tr.started and len(tr.step(frames[0])) == 0  # nothing to start from
    decoy = np.r_[truth[1, :2] + 50, truth[1, 2:]]
    out = [tr.step(frames[1], Detections.from_xywh([decoy, truth[1]], [0.3, 0.9]))]
    out += [tr.step(f) for f in frames[2:]]
    np.testing.assert_allclose(out[0].xywh[0], truth[1])  # the more confident one
    boxes = np.array([t.xywh[0] for t in out])
    assert success_rate(boxes, truth[1:]) > 0.9
    with pytest.raises(TypeError, match="frame must be a vistrack.types.Frame with an image"):
        tr.step(5)
    with pytest.raises(TypeError, match=r"got an array of shape \(120, 160, 3\) \(wrap it"):
        tr.step(frames[3].image)
    fresh = single_tracker("template")
    with pytest.raises(RuntimeError, match="update before init"):
        fresh.update(frames[0].image)
    assert isinstance(fresh, SingleObjectTracker)


def test_box_and_point_trackers_take_a_frame_or_its_index():
    d = Detections.from_xywh([[10, 20, 30, 60]], [0.9])
    a, b = BoxTracker(), BoxTracker()
    for k in range(1, 4):
        ta, tb = a.step(k, d), b.step(Frame(k, (k - 1) / 30), d)
        np.testing.assert_array_equal(ta.boxes, tb.boxes)
    assert len(a.step(None, None)) == 0 and a.frame == 4  # the next frame; no detections
    with pytest.raises(ValueError, match="frame must increase; got 2 after 4"):
        a.step(2, d)
    with pytest.raises(TypeError, match="frame must be a vistrack.types.Frame or its index"):
        a.step("7", d)


def test_run_feeds_sinks_and_writes_nothing_from_a_failed_run(tmp_path):
    frames, truth = red_disc_clip(T=10)
    boxes = {f.index: Detections.from_xywh([truth[k]], [0.9]) for k, f in enumerate(frames)}
    sinks = [MOTWriter(tmp_path / "t.txt"), CSVWriter(tmp_path / "t.csv"), TrackRows()]
    stats = run(frames, lambda f: boxes[f.index], BoxTracker(), sinks)
    assert stats.frames == 10 and set(stats.seconds) == {"decode", "frontend", "tracker",
                                                         "write", "compile"}
    got = read_mot(tmp_path / "t.txt")
    np.testing.assert_allclose(got.boxes, sinks[2].xywh, atol=0.005)
    assert len(got) == len(sinks[2]) == 10  # confirmed at once in the first frame
    assert ((tmp_path / "t.csv").read_text().splitlines()[0]
            == "frame,id,bb_left,bb_top,bb_width,bb_height,conf,class")

    def broken(f):
        if f.index == 5:
            raise RuntimeError("detector failed at frame 5")
        return boxes[f.index]

    with pytest.raises(RuntimeError, match="frame 5"):
        run(frames, broken, BoxTracker(), [MOTWriter(tmp_path / "partial.txt")])
    assert not (tmp_path / "partial.txt").exists()
    with pytest.raises(TypeError, match=r"sinks\[0\] must have write"):
        run(frames, None, BoxTracker(), [object()])
    with pytest.raises(TypeError, match="tracker must have step"):
        run(frames, None, object())
    # a source of no frames failed in Python's words ("'int' object is not iterable"), and
    # one giving images (or indices) on "has no attribute 'index'"
    with pytest.raises(TypeError, match=re.escape(
            "source must be an iterable of Frame (a VideoReader, a list of Frame); got int")):
        run(5, None, BoxTracker())
    with pytest.raises(TypeError, match=re.escape(
            "source must give Frame objects; its frame 3 is a ndarray")):
        run([*frames[:2], np.zeros((4, 4)), *frames[2:]], None, BoxTracker(),
            [MOTWriter(tmp_path / "part.txt")])
    assert not (tmp_path / "part.txt").exists()


def test_registries_list_the_valid_names():
    assert {"bgsub", "hog", "confidence"} <= set(FRONTENDS)
    assert {"bytetrack", "sort", "dcpf", "single:colour"} <= set(TRACKERS)
    assert set(SINKS) == {"tracks", "csv", "video", "plot"}
    with pytest.raises(ValueError, match=r"tracker must be one of \['bytetrack'"):
        TRACKERS["yolo"]
    with pytest.raises(ValueError, match="must be one of"):
        Registry("sink", {})["x"]


def test_every_registry_the_docs_name_lists_its_names_for_a_wrong_one():
    """docs/conventions.md: parts chosen by name come from registries whose unknown names
    raise a ValueError listing the valid ones; the box-tracker presets, single-object
    methods, background models, resamplers and assigners were plain dicts (KeyError)."""
    from vistrack import association, filters, frontends, tracking

    for registry, kind in ((tracking.TRACKERS, "box-tracker preset"),
                           (tracking.METHODS, "single-object method"),
                           (frontends.BACKGROUNDS, "background"),
                           (filters.RESAMPLERS, "resampler"),
                           (association.ASSIGNERS, "assigner")):
        assert isinstance(registry, Registry)
        with pytest.raises(ValueError) as e:
            registry["nope"]
        assert str(e.value) == f"{kind} must be one of {sorted(registry)}; got 'nope'"


class EveryDetection:
    """A tracker of one's own: each detection is its own track, numbered in order."""

    def __init__(self):
        self.reset()

    def reset(self):
        self.frames = 0

    def step(self, frame, detections=None):
        self.frames += 1
        n = 0 if detections is None else len(detections)
        return Tracks(ids=np.arange(1, n + 1), boxes=detections.boxes if n else np.zeros((0, 4)),
                      points=None, scores=np.ones(n), classes=np.zeros(n, int))


def write_clip(folder, frames):
    folder.mkdir()
    for f in frames:
        cv2.imwrite(str(folder / f"{f.index:06d}.png"), f.image)
    return folder


class TruthDetector:
    """A detector of one's own: frame k's box is ``truth[k - 1]``, scored ``score(k)``; it
    raises KeyboardInterrupt (Ctrl-C) at frame ``stop``."""

    def __init__(self, truth, score=lambda k: 0.9, stop=None):
        self.truth, self.score, self.stop, self.k = truth, score, stop, 0

    def detect(self, image):
        self.k += 1
        if self.k == self.stop:
            raise KeyboardInterrupt
        return Detections.from_xywh([self.truth[self.k - 1]], [self.score(self.k)])


def test_track_video_takes_any_tracker_and_detector(tmp_path):
    """A tracker and a detector of one's own, through track_video: the tracks written are
    the detector's boxes, as the tracker returned them."""
    frames, truth = red_disc_clip(T=12)
    folder = write_clip(tmp_path / "frames", frames)

    mine = EveryDetection()
    run_ = track_video(folder, tmp_path / "out", tracker=mine,
                       frontend=TruthDetector(truth, lambda k: 0.8), fps=25, annotate=False)
    got = read_mot(run_.files["tracks"])
    assert run_.frames == 12 and mine.frames == 12 and run_.config is None
    np.testing.assert_allclose(got.boxes, truth, atol=0.005)
    with pytest.raises(TypeError, match="tracker must be a name in"):
        track_video(folder, tmp_path / "o2", tracker=42, frontend=TruthDetector(truth))


def test_rows_past_the_videos_end_and_ground_truth_with_nothing_to_score_are_named(tmp_path):
    """Detections (``detections:FILE``) and ground truth on frames past a video's last frame
    were dropped without a word, and ground truth with no row on the frames tracked (empty,
    or all of it past the end) gave a MOTA of -2200 % without one. Each is now named; with
    ``stop`` before the end, rows after it are what was asked for, and only those past the
    video's own end are said (they went without a word too)."""
    import warnings

    import cv2

    from vistrack.pipeline import track_video

    folder = tmp_path / "frames"
    folder.mkdir()
    for k in range(5):
        cv2.imwrite(str(folder / f"{k + 1:06d}.png"), np.zeros((60, 80, 3), np.uint8))

    def rows(frames, ident):
        return "".join(f"{f},{ident},{5 + 3 * f},20,20,30,1,1,1\n" for f in frames)

    det, gt = tmp_path / "det.txt", tmp_path / "gt.txt"
    det.write_text(rows(range(1, 8), -1))
    gt.write_text(rows(range(1, 9), 1))
    with pytest.warns(UserWarning) as seen:
        run_ = track_video(folder, tmp_path / "a", frontend=f"detections:{det}", gt=gt,
                           annotate=False, fps=25)
    said = [str(w.message) for w in seen]
    assert f"{det}: 2 rows on frames 6-7, past the video's last frame (5): not tracked" in said
    assert f"{gt}: 3 rows on frames 6-8, past the video's last frame (5): not scored" in said
    assert run_.scores.TP > 0
    with warnings.catch_warnings(record=True) as seen_b:
        warnings.simplefilter("always")
        track_video(folder, tmp_path / "b", frontend=f"detections:{det}", gt=gt, stop=3,
                    annotate=False, fps=25)
    assert sorted(str(w.message) for w in seen_b) == sorted(
        [f"{det}: 2 rows on frames 6-7, past the video's last frame (5): not tracked",
         f"{gt}: 3 rows on frames 6-8, past the video's last frame (5): not scored"])
    # one row, or rows of one frame, past the end: "1 rows on frames 6-6" before
    for frames, said_as in (([1, 2, 6], "1 row on frame 6"), ([1, 6, 6], "2 rows on frame 6")):
        det.write_text(rows(frames[:2], -1) + rows(frames[2:], -1))
        with pytest.warns(UserWarning) as seen_c:
            track_video(folder, tmp_path / said_as, frontend=f"detections:{det}",
                        annotate=False, fps=25)
        assert f"{det}: {said_as}, past the video's last frame (5): not tracked" in \
            [str(w.message) for w in seen_c]
    det.write_text(rows(range(1, 8), -1))
    # stop at a frame whose image is missing: the run stopped at 2, the folder goes on to 5
    # (it said the rows from 3 on lay past the video's last frame, 2)
    (folder / "000003.png").unlink()
    with warnings.catch_warnings(record=True) as seen_c:
        warnings.simplefilter("always")
        track_video(folder, tmp_path / "stop_missing", frontend=f"detections:{det}", gt=gt, stop=3,
                    annotate=False, fps=25)
    said = [str(w.message) for w in seen_c]
    assert any("no image for frame 3" in m for m in said), said
    assert not any("last frame (2)" in m for m in said), said
    (folder / "000003.png").write_bytes((folder / "000002.png").read_bytes())
    empty = tmp_path / "empty.txt"
    empty.write_text("")
    with pytest.warns(UserWarning, match=re.escape(
            f"{empty}: no ground-truth rows on the frames tracked (1-5): every box tracked "
            "counts as a false positive")):
        run_ = track_video(folder, tmp_path / "c", frontend=f"detections:{det}", gt=empty,
                           annotate=False, fps=25)
    assert run_.scores.TP == 0 and run_.scores.FP > 0


def test_a_box_beyond_any_image_is_refused_by_its_line(tmp_path):
    """A corrupt row with a box value of 1e100 crashed the process (the IoU pairs' grid),
    1e308 failed with an OverflowError (the image's size taken from the boxes), and 1e160
    made the tracker's own boxes NaN ("track boxes must be finite", naming nothing). Values
    beyond 2^52 pixels, where a float no longer holds every whole pixel, are refused by
    their line; the tracker refuses them too, by frame. 1e15 is tracked as any box."""
    from vistrack.pipeline import track_sequence
    from vistrack.tracking import BoxTracker
    from vistrack.types import Detections

    rows = "".join(f"{f},-1,{10 + 3 * f},20,20,40,0.9\n" for f in range(1, 11))
    for far in ("1e100", "1e308", "-5e15"):
        det = tmp_path / f"d{far}.txt"
        det.write_text(rows + f"11,-1,{far},20,20,40,0.1\n")
        with pytest.raises(ValueError, match=re.escape(
                f"{det}, line 11: a box ({float(far):g}, 20, 20, 40) beyond 2^52 pixels, where "
                "a float no longer holds every whole pixel: not a box of any image")):
            track_sequence(det, tmp_path / "a.txt", fps=10)
        assert not (tmp_path / "a.txt").exists()
    det = tmp_path / "d15.txt"
    det.write_text(rows + "11,-1,1e15,20,20,40,0.1\n")
    assert track_sequence(det, tmp_path / "b.txt", fps=10).detections == 11
    trk = BoxTracker()
    with pytest.raises(ValueError, match=re.escape(
            "detection boxes must lie within ±2^52 pixels, where a float holds every whole "
            "pixel; boxes[1] = [0.0, 0.0, 1e+160, 1e+160] (frame 1)")):
        trk.step(1, Detections(boxes=[[0, 0, 10, 10], [0, 0, 1e160, 1e160]], scores=[.9, .9]))


def test_an_image_folder_tracked_at_an_assumed_rate_says_so(tmp_path):
    """An image folder has no frame rate, and was tracked at 30 frames/s without a word,
    though the tracker's times (coasting, how long a lost track is kept) and its motion's
    noise follow the rate; run.json did not say which rate was used. The run now says it
    assumed 30, and run.json holds the rate; with fps given nothing is said."""
    import json
    import warnings

    import cv2

    from vistrack.pipeline import track_video

    folder = tmp_path / "frames"
    folder.mkdir()
    for k in range(4):
        cv2.imwrite(str(folder / f"{k + 1:06d}.png"), np.zeros((60, 80, 3), np.uint8))
    with pytest.warns(UserWarning, match=re.escape(
            f"{folder} gives no frame rate (an image folder, or a video whose header has "
            "none): tracked at 30 frames/s (give the true one with --fps, or fps=)")):
        run_ = track_video(folder, tmp_path / "a", annotate=False)
    assert json.loads((run_.out_dir / "run.json").read_text())["frame_rate"] == 30
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # (black frames: the front-end finds nothing in them, and says that)
        warnings.filterwarnings("ignore", message=".*front-end found nothing")
        run_ = track_video(folder, tmp_path / "b", annotate=False, fps=10)
    assert json.loads((run_.out_dir / "run.json").read_text())["frame_rate"] == 10


def test_detections_outside_the_image_are_named(tmp_path):
    """Detections that lie wholly outside the image (in the pixels of another image size,
    or shifted) were tracked and written without a word, against a sequence's seqinfo.ini
    and against a video's frames. From a twentieth of the boxes on, they are named, with the
    first one's line; a few just past the edge (a detector extrapolating people who leave,
    0.2-0.6 % of FairMOT's boxes on MOT16) are not."""
    import warnings

    import cv2

    from vistrack.pipeline import track_sequence, track_video

    seq = tmp_path / "seq"
    (seq / "det").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=40\n"
                                     "imWidth=80\nimHeight=60\n")
    inside = [f"{f},-1,{5 + f},10,10,20,0.9\n" for f in range(1, 41)]
    shifted = [f"{f},-1,{2005 + 2 * f},10,10,20,0.9\n" for f in range(1, 41)]
    det = seq / "det" / "det.txt"
    det.write_text("".join(inside[:39] + shifted[39:]))  # 1 of 40: under a twentieth
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        track_sequence(seq, tmp_path / "a.txt")
    det.write_text("".join(inside[:38] + shifted[38:]))  # 2 of 40
    with pytest.warns(RuntimeWarning, match=re.escape(
            f"{det}, line 39: a box (2083, 10, 10, 20) wholly outside the 80x60 image, and 1 "
            "more of 40: tracked as the others, though nothing of the image is there")):
        track_sequence(seq, tmp_path / "b.txt")
    frames = tmp_path / "frames"
    frames.mkdir()
    for k in range(40):
        cv2.imwrite(str(frames / f"{k + 1:06d}.png"), np.zeros((60, 80, 3), np.uint8))
    with pytest.warns(RuntimeWarning, match=re.escape(
            f"{det}, line 39: a box (2083, 10, 10, 20) wholly outside the 80x60 image")):
        track_video(frames, tmp_path / "v", frontend=f"detections:{det}", annotate=False)


def test_track_video_follows_one_object_by_name(tmp_path):
    """``single:colour``: the first frame's detection starts it; it follows the disc."""
    frames, truth = red_disc_clip(T=20)
    folder = write_clip(tmp_path / "frames", frames)
    det = tmp_path / "det.txt"
    det.write_text(",".join(map(str, [1, -1, *truth[0], 0.9, -1, -1, -1])) + "\n")
    r = track_video(folder, tmp_path / "out", tracker="single:colour",
                    frontend=f"detections:{det}", fps=25, annotate=False)
    got = read_mot(r.files["tracks"])
    assert r.tracks == 1 and len(got) == 20
    assert success_rate(got.boxes, truth) > 0.9


def _own_tracker_case(tmp_path: Path) -> list[str]:
    """A 6-frame clip, its detections, and mytracker.py (``make()`` returns an
    EveryDetection) in ``tmp_path``: ``vistrack track``'s arguments for them."""
    frames, truth = red_disc_clip(T=6)
    folder = write_clip(tmp_path / "frames", frames)
    (tmp_path / "mytracker.py").write_text(
        "from tests.test_pipeline import EveryDetection\n"
        "def make():\n    return EveryDetection()\n")
    det = tmp_path / "det.txt"
    det.write_text("".join(",".join(map(str, [k + 1, -1, *truth[k], 0.9, -1, -1, -1])) + "\n"
                           for k in range(6)))
    return ["track", str(folder), "--tracker", "mytracker:make", "--frontend",
            f"detections:{det}", "--out-dir", str(tmp_path / "out"), "--fps", "25", "--force"]


def test_cli_takes_a_tracker_of_ones_own(tmp_path):
    """``--tracker module:callable``: the CLI makes it and runs it like any other."""
    env = {"PYTHONPATH": f"{tmp_path}:{ROOT}:{ROOT / 'src'}"}
    cmd = [sys.executable, "-m", "vistrack.cli", *_own_tracker_case(tmp_path)]
    r = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "tracked 6 frames: 6 boxes of 1 track;" in r.stdout
    bad = subprocess.run(cmd[:6] + ["nomodule:make"] + cmd[7:], capture_output=True, text=True,
                         env=env, cwd=tmp_path)
    assert bad.returncode == 2
    assert "cannot import make from nomodule" in bad.stderr
    # a module that does not parse: its file and line, on one line (not a traceback)
    (tmp_path / "broken.py").write_text("def make():\n    return (\n")
    bad = subprocess.run(cmd[:6] + ["broken:make"] + cmd[7:], capture_output=True, text=True,
                         env=env, cwd=tmp_path)
    assert bad.returncode == 2
    assert bad.stderr.startswith(f"vistrack track: error: tracker 'broken:make': "
                                 f"{tmp_path / 'broken.py'}:2: ")
    assert bad.stderr.count("\n") == 1
    box_only = subprocess.run(cmd[:6] + ["dcpf", "--high", "0.5"] + cmd[7:],
                              capture_output=True, text=True, env=env, cwd=tmp_path)
    assert box_only.returncode == 2 and "goes with the box trackers" in box_only.stderr


def test_a_tracker_of_ones_own_that_fails_is_named_with_its_frame(tmp_path, capsys,
                                                                    monkeypatch):
    """``--tracker module:callable`` whose step returns something else than Tracks, or raises:
    one line naming the class and the frame (it was a traceback from inside the writers,
    'list' object has no attribute 'ids', and the bare message 'my bug')."""
    from vistrack.cli import main

    argv = _own_tracker_case(tmp_path)
    (tmp_path / "mytracker.py").write_text(
        "from tests.test_pipeline import EveryDetection\n"
        "class Listing(EveryDetection):\n"
        "    def step(self, frame, detections=None):\n"
        "        return list(super().step(frame, detections).ids)\n"
        "class Failing(EveryDetection):\n"
        "    def step(self, frame, detections=None):\n"
        "        if frame.index == 4:\n"
        "            raise ValueError('my bug')\n"
        "        return super().step(frame, detections)\n"
        "def make():\n    return Listing()\n"
        "def failing():\n    return Failing()\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.syspath_prepend(str(ROOT))
    assert main(argv) == 2
    assert capsys.readouterr().err == ("vistrack track: error: mytracker.Listing.step returned "
                                       "a list at frame 1, not Tracks\n")
    assert main([a.replace("mytracker:make", "mytracker:failing") for a in argv]) == 2
    assert capsys.readouterr().err == ("vistrack track: error: my bug (at frame 4, in "
                                       "mytracker.Failing.step)\n")
    assert not (tmp_path / "out").exists()  # nothing written from part of a run


def test_run_notes_the_frame_and_the_stage_an_error_came_from():
    """The library's loop: an exception of the tracker or the detector is raised as it was,
    with a note of the frame and the stage (shown under a traceback)."""
    frames = [Frame(k, (k - 1) / 25) for k in range(1, 6)]
    boxes = lambda f: Detections.from_xywh([[10.0, 20, 30, 60]], [0.9])  # noqa: E731

    def detect(f):
        if f.index == 3:
            raise KeyError("lens cap")
        return boxes(f)

    with pytest.raises(KeyError, match="lens cap") as info:
        run(frames, detect, BoxTracker(), [TrackRows()])
    assert info.value.__notes__ == ["at frame 3, in the front-end"]

    class Late(BoxTracker):
        def step(self, frame, detections=None):
            if frame.index == 5:
                raise ZeroDivisionError("late")
            return super().step(frame, detections)

    with pytest.raises(ZeroDivisionError) as info:
        run(frames, boxes, Late(), [TrackRows()])
    assert info.value.__notes__ == [f"at frame 5, in {__name__}.{Late.__qualname__}.step"]
    with pytest.raises(TypeError, match=r"\.step returned a NoneType at frame 1, not Tracks"):
        run(frames, boxes, type("Nothing", (), {"step": lambda self, f, d: None})(),
            [TrackRows()])


def test_the_console_command_finds_a_tracker_module_in_the_current_folder(tmp_path):
    """``vistrack track ... --tracker mytracker:make`` with mytracker.py in the current
    folder, through the installed console command (whose path holds its own folder, not the
    current one, as ``python -m`` would): found, as a newcomer expects."""
    console = Path(sys.executable).with_name("vistrack")
    if not console.exists():
        pytest.skip(f"no console command beside {sys.executable} (vistrack not installed)")
    env = dict(os.environ, PYTHONPATH=f"{ROOT}:{ROOT / 'src'}")
    r = subprocess.run([str(console), *_own_tracker_case(tmp_path)], capture_output=True,
                       text=True, env=env, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "tracked 6 frames: 6 boxes of 1 track;" in r.stdout


def test_boxes_writer_marks_frames_without_the_object(tmp_path):
    w = BoxesWriter(tmp_path / "b.txt")
    w.write(Frame(1, 0.0), Tracks.empty())
    w.write(Frame(2, 0.04), Tracks(ids=np.ones(1, int), boxes=np.array([[1.0, 2, 4, 6]]),
                                   points=None, scores=np.ones(1), classes=np.zeros(1, int)))
    w.close()
    assert (tmp_path / "b.txt").read_text().splitlines() == ["1,nan,nan,nan,nan",
                                                             "2,1.00,2.00,3.00,4.00"]


def test_a_video_where_nothing_is_tracked_still_writes_every_output(tmp_path):
    """No detections at all: empty tracks files and a plot of the first frame, no error."""
    frames, _ = red_disc_clip(T=5)
    folder = write_clip(tmp_path / "frames", frames)

    class Nothing:
        def detect(self, image):
            return Detections(boxes=np.zeros((0, 4)))

    r = track_video(folder, tmp_path / "out", frontend=Nothing(), fps=25)
    assert r.rows == 0 and r.tracks == 0
    assert all(p.exists() for p in r.files.values())
    assert (tmp_path / "out" / "tracks.txt").read_text() == ""
    assert ((tmp_path / "out" / "tracks.csv").read_text()
            == "frame,id,bb_left,bb_top,bb_width,bb_height,conf,class\n")


def test_a_video_whose_raw_scores_start_no_track_says_so(tmp_path):
    """With raw scores all below the start threshold a video's run wrote no tracks without a
    word, where a detections file tracked alone says so: a detections file through a video
    is checked before it is tracked, a detector's scores after (the highest seen), and the
    same run with the threshold below the scores tracks the disc and says nothing."""
    import warnings

    frames, truth = red_disc_clip(T=8)
    folder = write_clip(tmp_path / "frames", frames)
    rising = lambda k: 0.5 + 0.01 * k  # noqa: E731
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{f + 1},-1,{x:.2f},{y:.2f},{w:.2f},{h:.2f},0.9\n"
                           for f, (x, y, w, h) in enumerate(truth)))
    starts = "(a track starts from a detection scoring at least high and new_track)"
    with pytest.warns(UserWarning, match=re.escape(
            f"{det}: every score lies below high 0.95 (the scores run 0.9 to 0.9), and with raw "
            f"scores (--scores raw) no track can start {starts}: lower --high")):
        r = track_video(folder, tmp_path / "a", frontend=f"detections:{det}", fps=25,
                        annotate=False, scores="raw", high=0.95)
    assert r.rows == 0
    with pytest.warns(UserWarning, match=re.escape(
            f"{folder}: the front-end: every score lies below new_track 0.7 (the scores run "
            f"0.51 to 0.58), and with raw scores (--scores raw) no track can start {starts}: "
            "lower --new-track")):
        r = track_video(folder, tmp_path / "b", frontend=TruthDetector(truth, rising), fps=25,
                        annotate=False,
                        scores="raw", high=0.5, new_track=0.7)
    assert r.rows == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name, frontend in (("c", f"detections:{det}"), ("d", TruthDetector(truth, rising))):
            r = track_video(folder, tmp_path / name, frontend=frontend, fps=25, annotate=False,
                            scores="raw", high=0.5, new_track=0.5)
            assert r.tracks == 1 and r.rows > 0


def test_a_videos_ground_truth_that_looks_unrelated_is_warned_of(tmp_path):
    """Another clip's ground truth scores valid numbers (MOTA -100 here), which vistrack eval
    warns of and a video's --gt did not: the disc's own truth scores 100 without a word, the
    same boxes 300 pixels off are named as unrelated (no box of the tracks meets one)."""
    import warnings

    frames, truth = red_disc_clip(T=8)
    folder = write_clip(tmp_path / "frames", frames)
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{f + 1},-1,{x:.2f},{y:.2f},{w:.2f},{h:.2f},0.9\n"
                           for f, (x, y, w, h) in enumerate(truth)))
    gts = {}
    for name, dx in (("gt.txt", 0), ("far.txt", 300)):
        gts[name] = tmp_path / name
        gts[name].write_text("".join(f"{f + 1},1,{x + dx:.2f},{y:.2f},{w:.2f},{h:.2f},1,1,1\n"
                                     for f, (x, y, w, h) in enumerate(truth)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = track_video(folder, tmp_path / "a", frontend=f"detections:{det}", fps=25,
                        annotate=False, gt=gts["gt.txt"])
    assert r.scores.MOTA == 1.0
    with pytest.warns(UserWarning, match=re.escape(
            f"predictions and ground truth look unrelated: no box of {tmp_path / 'b'}"
            f"/tracks.txt overlaps a box of {gts['far.txt']} by IoU >= 0.5 in any of their 8 "
            "common frames")):
        r = track_video(folder, tmp_path / "b", frontend=f"detections:{det}", fps=25,
                        annotate=False, gt=gts["far.txt"])
    assert r.scores.MOTA == -1.0


def test_a_videos_empty_results_are_warned_of_once(tmp_path):
    """Results with no rows against a --gt that has some: a detector that found something
    but started no track is told by the ground-truth check (the rows of the frames tracked,
    missed); a front-end that found nothing says so itself, and the check says it no
    second time."""
    import warnings

    frames, truth = red_disc_clip(T=8)
    folder = write_clip(tmp_path / "frames", frames)
    gt = tmp_path / "gt.txt"
    gt.write_text("".join(f"{f + 1},1,{x:.2f},{y:.2f},{w:.2f},{h:.2f},1,1,1\n"
                          for f, (x, y, w, h) in enumerate(truth)))

    def said(name, frontend, **kw):
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            r = track_video(folder, tmp_path / name, frontend=frontend, fps=25,
                            annotate=False, gt=gt, **kw)
        assert r.rows == 0
        return [str(w.message) for w in got if issubclass(w.category, UserWarning)]

    # found, but every raw score under the start
    got = said("low", TruthDetector(truth), scores="raw", high=0.95, new_track=0.95)
    assert f"{tmp_path / 'low'}/tracks.txt holds no rows: the 8 rows of {gt} on its frames " \
        "1-8 count as missed (FN) or ignored" in got
    got = said("none", "bgsub", min_area=1e8)
    assert sum("found nothing" in w for w in got) == 1
    assert not any("holds no rows" in w for w in got)


def test_an_interrupted_run_leaves_the_earlier_outputs_as_they_were(tmp_path):
    """Ctrl-C in the middle of a run over an earlier run's folder (``force``): every file of
    the earlier run is still there, byte for byte, and no partial file is left beside it."""
    frames, truth = red_disc_clip(T=12)
    folder = write_clip(tmp_path / "frames", frames)

    out = tmp_path / "out"
    first = track_video(folder, out, frontend=TruthDetector(truth), fps=25)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert sorted(before) == sorted([p.name for p in first.files.values()] + ["run.json"])
    assert len(before) == 5 and all(before.values())
    with pytest.raises(KeyboardInterrupt):
        track_video(folder, out, frontend=TruthDetector(truth, stop=6), fps=25, force=True)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    # into folders that did not exist: they are removed again, and the folder above is empty
    with pytest.raises(KeyboardInterrupt):
        track_video(folder, tmp_path / "new" / "out", frontend=TruthDetector(truth, stop=6), fps=25)
    assert not (tmp_path / "new").exists()


def test_a_run_found_wrong_at_its_end_writes_nothing(tmp_path, monkeypatch):
    """What fails only once the frames are through (a video with no frame to track; results
    that cannot be scored against --gt, a tracker reporting one id twice in a frame; a
    track-one --gt shorter than the video) was found after the outputs were committed: the
    error came with the files written, over an earlier run's with force (docs/errors.md:
    "a run that fails ... leaves no file under a final name"). Now an earlier run's files
    stay byte for byte, and a folder the run made is removed again."""
    from vistrack.pipeline import track_one

    frames, truth = red_disc_clip(T=8)
    folder = write_clip(tmp_path / "frames", frames)

    out = tmp_path / "out"
    track_video(folder, out, frontend=TruthDetector(truth), fps=25)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    empty = tmp_path / "empty.avi"  # a video with a header and no frame
    cv2.VideoWriter(str(empty), cv2.VideoWriter_fourcc(*"MJPG"), 25, (64, 48)).release()
    with pytest.raises(ValueError, match="no frames to track"):
        track_video(empty, out, frontend=TruthDetector(truth), fps=25, force=True)

    class Twice:  # one id twice in every frame
        def reset(self):
            pass

        def step(self, frame, detections=None):
            return Tracks(ids=np.array([1, 1]), boxes=np.array([[1.0, 1, 9, 9], [20, 1, 29, 9]]),
                          points=None, scores=np.ones(2), classes=np.zeros(2, int))

    gt = tmp_path / "gt.txt"
    gt.write_text("".join(f"{k},1,{x:.1f},{y:.1f},{w:.1f},{h:.1f},1,1,1\n"
                          for k, (x, y, w, h) in enumerate(truth, 1)))
    # (found by the sinks at the frame now, where scoring found it at the end)
    with pytest.raises(ValueError, match=re.escape("frame 1: track 1 is given twice")):
        track_video(folder, out, tracker=Twice(), frontend=TruthDetector(truth), fps=25, gt=gt,
                    force=True)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    with pytest.raises(ValueError, match="no frames to track"):
        track_video(empty, tmp_path / "new" / "out", frontend=TruthDetector(truth), fps=25)
    assert not (tmp_path / "new").exists()
    short = tmp_path / "short.txt"
    short.write_text("".join(f"{x},{y},{w},{h}\n" for x, y, w, h in truth[:3]))
    with pytest.raises(ValueError, match="has 3 boxes for 8 frames"):
        track_one(folder, truth[0], tmp_path / "one" / "boxes.txt", gt=short)
    assert not (tmp_path / "one").exists()
    # an image folder counts its frames: refused before a frame is tracked (the whole run
    # came first)
    import vistrack.pipeline

    def tracked(*args, **kwargs):
        raise AssertionError("the frames were tracked")

    with monkeypatch.context() as m:
        m.setattr(vistrack.pipeline, "run", tracked)
        with pytest.raises(ValueError, match="has 3 boxes for 8 frames"):
            track_one(folder, truth[0], tmp_path / "one" / "boxes.txt", gt=short)
        # frame,x,y,w,h lines of other frames are named as such, not by their count
        other = tmp_path / "other.txt"
        other.write_text("".join(f"{200 + k},{x},{y},{w},{h}\n"
                                 for k, (x, y, w, h) in enumerate(truth[:3], 1)))
        with pytest.raises(ValueError, match="lines start at frame 201"):
            track_one(folder, truth[0], tmp_path / "one" / "boxes.txt", gt=other)


def test_the_folder_of_the_images_tracked_is_no_output_folder(tmp_path):
    """out_dir the image folder itself (or a sequence's img1/) put trajectories.png among
    the frames, and the next run read it as one (failing, or with skip_bad_frames numbering
    every image after it a frame early). Refused before anything is written; the sequence
    folder above its img1/ is a fine output folder."""
    frames, truth = red_disc_clip(T=4)
    (tmp_path / "seq").mkdir()
    (tmp_path / "seq" / "seqinfo.ini").write_text("[Sequence]\nimDir=img1\nframeRate=25\n")
    folder = write_clip(tmp_path / "seq" / "img1", frames)
    images = sorted(p.name for p in folder.iterdir())

    def boxes(image):
        return Detections.from_xywh([truth[0]], [0.9])

    for source in (folder, tmp_path / "seq"):
        with pytest.raises(ValueError, match=re.escape(
                f"{folder / 'trajectories.png'} lies in the folder of the images tracked, "
                "among the files the run reads; give another out_dir")):
            track_video(source, folder, frontend=boxes, fps=25)
    assert sorted(p.name for p in folder.iterdir()) == images
    assert track_video(tmp_path / "seq", tmp_path / "seq", frontend=boxes).frames == 4


def test_the_cli_says_an_interrupted_run_in_one_line(tmp_path, monkeypatch, capsys):
    import vistrack.pipeline
    from vistrack.cli import main

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(vistrack.pipeline, "track_video", interrupted)
    out = tmp_path / "out"
    # a first run: nothing there before, nothing left ("earlier outputs are kept" was said)
    assert main(["track", str(tmp_path), "--out-dir", str(out)]) == 130
    assert capsys.readouterr().err == "vistrack track: interrupted; nothing was written\n"
    assert not out.exists()
    # a folder holding files of the user's own, none a run's output: nothing was written
    out.mkdir()
    (out / "notes.md").write_text("mine\n")
    assert main(["track", str(tmp_path), "--out-dir", str(out)]) == 130
    assert capsys.readouterr().err == "vistrack track: interrupted; nothing was written\n"
    (out / "tracks.txt").write_text("an earlier run's\n")
    assert main(["track", str(tmp_path), "--out-dir", str(out), "--force"]) == 130
    err = capsys.readouterr().err
    assert err == "vistrack track: interrupted; earlier outputs are kept\n"
    assert (out / "tracks.txt").read_text() == "an earlier run's\n"
    # a first run stopped after its outputs were renamed into place says so
    fresh = tmp_path / "fresh"

    def written_then_interrupted(video, out_dir, **kwargs):
        Path(out_dir).mkdir()
        (Path(out_dir) / "tracks.txt").write_text("this run's\n")
        raise KeyboardInterrupt

    monkeypatch.setattr(vistrack.pipeline, "track_video", written_then_interrupted)
    assert main(["track", str(tmp_path), "--out-dir", str(fresh)]) == 130
    assert capsys.readouterr().err == ("vistrack track: interrupted; this run's outputs were "
                                       "written\n")


def test_an_interrupt_after_the_outputs_replaced_earlier_ones_says_so(tmp_path, monkeypatch,
                                                                      capsys):
    """Ctrl-C after the run had renamed its outputs over an earlier run's, before its summary
    was printed, said "earlier outputs are kept" of files already replaced (a SIGINT 3.45 s
    into a 3.5 s run did). Oracle: the files' contents after the interrupt, each the run's
    own, for a video run (`--out-dir`) and a detections file (`--out`)."""
    import vistrack.cli as cli
    import vistrack.pipeline

    det = tmp_path / "cam.txt"
    det.write_text("".join(f"{f},-1,{10 + 2 * f},20,30,60,0.9\n" for f in range(1, 11)))
    out = tmp_path / "res.txt"
    out.write_text("an earlier run's\n")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_warn_printed_rate", interrupted)  # the step after the run
    assert cli.main(["track", str(det), "--fps", "10", "--out", str(out), "--force"]) == 130
    assert capsys.readouterr().err == ("vistrack track: interrupted; this run's outputs were "
                                       "written\n")
    assert out.read_text() != "an earlier run's\n" and len(read_mot(out)) > 0
    monkeypatch.undo()
    clip = Path(vistrack.pipeline.__file__).parent / "data" / "pets09-s2l1" / "pets09-s2l1.mp4"
    folder = tmp_path / "v"
    folder.mkdir()
    (folder / "tracks.txt").write_text("an earlier run's\n")
    monkeypatch.setattr(cli, "_print_video_run", interrupted)
    assert cli.main(["track", str(clip), "--out-dir", str(folder), "--stop", "5", "--force",
                     "--quiet"]) == 130
    assert capsys.readouterr().err == ("vistrack track: interrupted; this run's outputs were "
                                       "written\n")
    assert (folder / "tracks.txt").read_text() != "an earlier run's\n"


def test_a_detector_on_a_frame_without_an_image_names_the_frame():
    from vistrack.frontends import BlobDetector

    detect = as_detector(BlobDetector())
    with pytest.raises(ValueError, match=r"frame 3 has no image; the detector BlobDetector"):
        detect(Frame(3, 0.1))


def test_track_rows_equal_the_concatenated_frames():
    """TrackRows keeps its rows in doubling arrays; they equal the frames' rows concatenated,
    the ids' dtype widened as np.concatenate widens it."""
    rng = np.random.default_rng(3)
    rows, blocks = TrackRows(), []
    for f in range(1, 400):
        k = int(rng.integers(0, 9))
        ids = rng.integers(0, 1000, k).astype(np.int32 if f < 200 else np.int64)
        xyxy = rng.uniform(0, 50, (k, 4))
        xyxy[:, 2:] += xyxy[:, :2]
        t = Tracks(ids=ids, boxes=xyxy, points=None, scores=rng.uniform(0, 1, k),
                   classes=np.zeros(k))
        rows.write(Frame(f, f / 25), t)
        blocks.append((np.full(k, f), ids, t.xywh, t.scores))
    assert len(rows) == sum(len(b[0]) for b in blocks)
    np.testing.assert_array_equal(rows.frames, np.concatenate([b[0] for b in blocks]))
    want_ids = np.concatenate([b[1] for b in blocks])
    np.testing.assert_array_equal(rows.ids, want_ids)
    np.testing.assert_array_equal(rows.xywh, np.concatenate([b[2] for b in blocks]))
    np.testing.assert_array_equal(rows.scores, np.concatenate([b[3] for b in blocks]))


def test_a_detections_file_with_boxes_of_no_area_says_so(tmp_path):
    """A box of zero width or height (KITTI-0000-Car's det.txt has one, clipped at the
    image's edge) overlaps no other box, itself in the next frame included, so no track can
    follow it: a confident one that stays put is not reported after its first frame. That
    used to happen without a word; the file's reader now warns, naming the first such box's
    line (its frame in a CSV file, whose columns may lie in any order) and how many more
    there are."""
    import warnings

    from vistrack.pipeline import track_sequence

    # a person walking, and a flat box that stays where it is in every frame
    rows = []
    for f in range(1, 11):
        rows.append(f"{f},-1,{10 + 3 * f},20,30,60,0.9")
        rows.append(f"{f},-1,200,50,{0 if f != 4 else 20},40,0.95")
    det = tmp_path / "det.txt"
    det.write_text("\n".join(rows) + "\n")
    with pytest.warns(RuntimeWarning) as got:  # scores as given: the flat box is confident
        run_ = track_sequence(det, tmp_path / "out.txt", fps=10, scores="raw")
    assert [str(w.message) for w in got] == [
        f"{det}, line 2: a box of zero width (200, 50, 0, 40) and 8 more of zero width or "
        "height: a box with no area overlaps no other, so no track can follow it from frame "
        "to frame"]
    out = read_mot(run_.out)
    # the person is followed through the ten frames; the flat box only in the first frame,
    # where every track is reported at once, and never after
    flat = out.boxes[:, 0] == 200
    assert out.frames[~flat].tolist() == list(range(1, 11)) and out.frames[flat].tolist() == [1]

    csv = tmp_path / "det.csv"
    # (a CSV file's box was named by its frame: its line now, the rows out of frame order)
    csv.write_text("conf,frame,x0,y0,w,h\n0.9,4,5,5,10,10\n0.9,3,5,5,10,0\n")
    names = {"bb_left": "x0", "bb_top": "y0", "bb_width": "w", "bb_height": "h"}
    with pytest.warns(RuntimeWarning, match=rf"^{csv}, line 3: a box of zero height "
                                            r"\(5, 5, 10, 0\): a box with no area"):
        track_sequence(csv, tmp_path / "csv.txt", fps=10, columns=names)

    # --frontend detections:FILE reads the file the same way
    frames, _ = red_disc_clip(T=10)
    clip = write_clip(tmp_path / "frames", frames)
    with pytest.warns(RuntimeWarning, match=rf"^{det}, line 2: a box of zero width"):
        track_video(clip, tmp_path / "video", frontend=f"detections:{det}", fps=10,
                    annotate=False, scores="raw")

    # boxes with area: no warning
    det.write_text("\n".join(r for r in rows if ",0,40," not in r) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        track_sequence(det, tmp_path / "clean.txt", fps=10)


def test_a_detections_file_of_several_classes_is_tracked_class_by_class(tmp_path):
    """The eighth value of a detections file's rows is their class: a track takes detections
    of its own class only, as the box trackers keep classes apart. It used to be dropped, so
    a track followed whatever class came where it was. A file of more than one class also
    says that the MOTChallenge results file does not carry them."""
    import warnings

    from vistrack.pipeline import track_sequence

    # an object of class 1 moving right over frames 1-10, then one of class 2 taking up
    # the same path over frames 11-20
    def rows(classes):
        return "".join(f"{f},-1,{10 + 3 * f},20,20,40,0.9,{classes(f)},-1,-1\n"
                       for f in range(1, 21))

    mixed = tmp_path / "mixed.txt"
    mixed.write_text(rows(lambda f: 1 if f <= 10 else 2))
    with pytest.warns(UserWarning) as got:
        run_ = track_sequence(mixed, tmp_path / "mixed-out.txt", fps=10, scores="raw")
    assert [str(w.message) for w in got] == [
        f"{mixed}: detections of 2 classes (1, 2): each class is tracked apart, no track "
        "taking another's detections; "
        f"{tmp_path / 'mixed-out.txt'}, MOTChallenge's text, has no class column (a .csv or "
        ".parquet results file has one)"]
    out = read_mot(run_.out)
    before = set(out.ids[out.frames <= 10].tolist())
    after = set(out.ids[out.frames >= 12].tolist())
    # class 1's track, then class 2's from its confirmation (frame 12): two identities
    assert len(before) == 1 and len(after) == 1 and before != after
    assert out.frames[out.ids == after.pop()].tolist() == list(range(12, 21))

    # one class (or none, -1): one track follows the path through all twenty frames
    for kind in (lambda f: 1, lambda f: -1):
        one = tmp_path / "one.txt"
        one.write_text(rows(kind))
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            run_ = track_sequence(one, tmp_path / "one-out.txt", fps=10, scores="raw",
                                  force=True)
        out = read_mot(run_.out)
        assert len(set(out.ids.tolist())) == 1 and out.frames.tolist() == list(range(1, 21))

    # --frontend detections:FILE reads the classes the same way
    frames, _ = red_disc_clip(T=20)
    clip = write_clip(tmp_path / "frames", frames)
    with pytest.warns(UserWarning, match=rf"^{mixed}: detections of 2 classes"):
        track_video(clip, tmp_path / "video", frontend=f"detections:{mixed}", fps=10,
                    annotate=False, scores="raw")
    out = read_mot(tmp_path / "video" / "tracks.txt")
    first, second = (set(out.ids[k].tolist()) for k in (out.frames <= 10, out.frames >= 12))
    assert len(first) == 1 and len(second) == 1 and first != second
    # tracks.csv says which class each row's track is: the class of its detections
    pd = pytest.importorskip("pandas")
    csv = pd.read_csv(tmp_path / "video" / "tracks.csv")
    assert list(csv.columns) == ["frame", "id", "bb_left", "bb_top", "bb_width", "bb_height",
                                "conf", "class"]
    assert (csv["class"] == np.where(csv["id"] == first.pop(), 1, 2)).all()
    # the same rows as tracks.txt (class 1's track coasts through frame 11)
    assert sorted(zip(csv["frame"], csv["id"])) == sorted(zip(out.frames, out.ids))
    assert set(csv.loc[csv["frame"] <= 11, "class"]) == {1}


def test_a_videos_tracks_csv_reads_back_as_the_tracks(tmp_path):
    """A video's ``tracks.csv`` was ``frame,id,x,y,w,h,score,class`` with ``x, y`` the box's
    corner, while ``MOTTable.from_pandas`` (and ``vistrack track`` reading a CSV file) takes
    ``x, y`` for its centre, as ``to_pandas`` and trackpy write it: read back, each box was
    half its size off, or refused for want of ``bb_width``. Its columns are now MOTChallenge's
    names, and it reads back as the rows of ``tracks.txt``, written beside it."""
    pd = pytest.importorskip("pandas")
    from vistrack.io import MOTTable

    frames, truth = red_disc_clip(T=12)
    clip = write_clip(tmp_path / "frames", frames)
    dets = tmp_path / "dets.txt"
    dets.write_text("".join(f"{k + 1},-1,{x:.2f},{y:.2f},{w:.2f},{h:.2f},0.9,3\n"
                            for k, (x, y, w, h) in enumerate(truth)))
    track_video(clip, tmp_path / "out", frontend=f"detections:{dets}", fps=10,
                annotate=False, scores="raw")
    txt = read_mot(tmp_path / "out" / "tracks.txt")
    csv = MOTTable.from_pandas(pd.read_csv(tmp_path / "out" / "tracks.csv"))
    assert len(txt) == len(csv) == 12
    assert csv.frames.tolist() == txt.frames.tolist() and csv.ids.tolist() == txt.ids.tolist()
    np.testing.assert_array_equal(csv.boxes, txt.boxes)  # both to 2 decimals
    np.testing.assert_allclose(csv.conf, txt.conf, atol=5e-4)  # 3 decimals against more
    assert set(csv.classes.tolist()) == {3}
    # and the boxes are where the disc was (the filter's, within a pixel or two of it)
    np.testing.assert_allclose(csv.boxes, truth, atol=2.0)


def test_offline_tracks_a_file_with_nothing_to_calibrate_on_as_online(tmp_path):
    """The offline mode calibrates the scores on the whole file first; a file with no
    detection seen to persist or not (none at all, or all on one frame) left it nothing to
    fit, and ``--offline`` stopped with ``no scores to fit``, naming nothing. It now
    calibrates as it goes, as online, and writes what online writes."""
    from vistrack.pipeline import track_sequence
    from vistrack.tracking.calibration import NoOutcomesError, ScoreCalibration

    files = {"empty": "", "one": "1,-1,10,10,50,50,0.9\n",
             "two": "1,-1,10,10,50,50,0.9\n1,-1,100,10,50,50,0.5\n"}
    for name, text in files.items():
        det = tmp_path / f"{name}.txt"
        det.write_text(text)
        on = track_sequence(det, tmp_path / f"{name}-on.txt", fps=10)
        off = track_sequence(det, tmp_path / f"{name}-off.txt", fps=10, offline=True)
        assert on.out.read_text() == off.out.read_text()
        assert off.rows == (0 if name == "empty" else 1)
    with pytest.raises(NoOutcomesError, match="no scores to fit"):
        ScoreCalibration.from_frames([Detections(boxes=np.array([[0.0, 0, 5, 5]]))])
    assert issubclass(NoOutcomesError, ValueError)


def test_boxes_normalised_to_the_image_track_and_are_written_as_in_pixels(tmp_path):
    """A detections file in fractions of the image (YOLO's xywhn) tracks as the same file in
    pixels does (the tracker's noise scales with the boxes), but its results were written to
    2 decimals, a hundredth of the image: KITTI-0004-Car's HOTA fell from 55.9 to 48.3. The
    results now carry the decimals the boxes need (``box_decimals``), online and offline."""
    from vistrack.pipeline import track_sequence

    scale = np.array([1000.0, 500.0, 1000.0, 500.0])
    rng = np.random.default_rng(4)
    rows = []
    for k in range(3):
        start, v = rng.uniform([100, 100], [800, 400]), rng.uniform(-6, 6, 2)
        for f in range(1, 31):
            x, y = (start + v * f + rng.normal(0, 0.7, 2)).tolist()
            rows.append((f, x, y, 30.0 + k, 70.0 + 2 * k, 0.9 - 0.1 * k))
    pixels, unit = tmp_path / "px.txt", tmp_path / "unit.txt"
    pixels.write_text("".join(f"{f},-1,{x!r},{y!r},{w!r},{h!r},{c!r}\n"
                              for f, x, y, w, h, c in rows))
    unit.write_text("".join(
        "{},-1,{!r},{!r},{!r},{!r},{!r}\n".format(f, *(np.array([x, y, w, h]) / scale).tolist(),
                                                  c)
        for f, x, y, w, h, c in rows))
    for offline in (False, True):
        a = read_mot(track_sequence(pixels, tmp_path / f"a{offline}.txt", fps=10,
                                    offline=offline).out)
        b = read_mot(track_sequence(unit, tmp_path / f"b{offline}.txt", fps=10,
                                    offline=offline).out)
        assert len(a) > 60 and (a.frames == b.frames).all() and (a.ids == b.ids).all()
        # each to its last decimal: a hundredth of a pixel, and 0.0001 of the image (4
        # decimals: a thousandth of the boxes' median height, 0.14, or less)
        np.testing.assert_allclose(b.boxes * scale, a.boxes, atol=0.005 + 0.5e-4 * 1000)
        assert len((tmp_path / f"b{offline}.txt").read_text().split(",")[2]) == 6  # 0.xxxx


def test_a_frame_number_far_past_the_rest_is_named_not_tracked_for_ever(tmp_path):
    """A stray frame number of 10^11 (a timestamp in the frame's column) asked
    ``undelivered_frames`` for a count of every frame up to it (745 GiB: a traceback), and the
    tracker would then have stepped through 10^11 frames. The runs of frames without rows
    are found from the frames that have rows, and a detections file alone past
    ``MAX_FRAMES`` is refused, naming the line."""
    from vistrack.detector_checks import undelivered_frames
    from vistrack.pipeline import MAX_FRAMES, track_sequence

    frames = np.r_[np.repeat([1, 2, 4], 6), 10 ** 11]
    assert undelivered_frames(frames).tolist() == [3]
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,20,40,0.9\n2,-1,12,10,20,40,0.9\n"
                   f"{MAX_FRAMES + 1},-1,14,10,20,40,0.9\n")
    with pytest.raises(ValueError, match=rf"^{re.escape(str(det))}, line 3: frame "
                                         rf"{MAX_FRAMES + 1} is beyond the 100,000,000 frames"):
        track_sequence(det, tmp_path / "out.txt", fps=10)
    assert not (tmp_path / "out.txt").exists()


def test_a_stray_frame_far_past_the_rest_is_named_in_a_warning(tmp_path):
    """Below ``MAX_FRAMES`` a stray frame number is tracked up to: rows on frames 1-525 and
    one more on frame 1,000,000 took 2.5 minutes at 30 frames/s without a word. A run of
    frames without rows longer than an hour at the file's rate and than ten times the frames
    that have rows is now named, by the line after it; shorter runs are not."""
    import warnings

    from vistrack.pipeline import track_sequence

    def rows(frames):
        return "".join(f"{f},-1,{10 + 3 * (f % 20)},20,20,40,0.9\n" for f in frames)

    det = tmp_path / "det.txt"
    # at 0.01 frames/s an hour is 36 frames, so the bound is ten times the 20 frames with
    # rows: 200
    det.write_text(rows([*range(1, 20), 221]))
    with pytest.warns(UserWarning, match=re.escape(
            f"{det}, line 20: frame 221's rows come after frames 20-220 without any (201 "
            "frames, 5.6 hours at 0.01 frames/s), where 20 frames have rows: the tracker "
            "steps through all 221 frames up to the last (a mistyped frame "
            "number, or a timestamp where the frame should be?)")):
        track_sequence(det, tmp_path / "a.txt", fps=0.01)
    # the file's first rows after a long run from frame 1 are named the same way
    det.write_text(rows([500, *range(501, 520)]))
    with pytest.warns(UserWarning, match=re.escape(
            f"{det}, line 1: frame 500's rows come after frames 1-499 without any (499 "
            "frames")):
        track_sequence(det, tmp_path / "b.txt", fps=0.01, force=True)
    det.write_text(rows([*range(1, 20), 220]))  # 200 frames between: no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        track_sequence(det, tmp_path / "c.txt", fps=0.01)


def test_ground_truth_given_as_detections_is_named_as_such(tmp_path):
    """Detections carry no identity (-1); ground truth or a tracker's results given as
    detections were tracked without a word, their ignored boxes (conf 0) as detections. A
    file whose every row has an identity now says so; detections do not."""
    import warnings

    from vistrack.pipeline import track_sequence

    gt = tmp_path / "gt.txt"
    gt.write_text("".join(f"{f},{i},{10 + 3 * f + 100 * i},20,20,40,1,1,1\n"
                          for f in range(1, 11) for i in (1, 2)))
    with pytest.warns(UserWarning, match=re.escape(
            f"{gt}: every row has an identity (the second value; detections have -1): ground "
            "truth or tracks rather than detections?")):
        track_sequence(gt, tmp_path / "a.txt", fps=10)
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{f},-1,{10 + 3 * f},20,20,40,0.9\n" for f in range(1, 11)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        track_sequence(det, tmp_path / "b.txt", fps=10)


def test_detections_that_cannot_give_tracks_are_named(tmp_path):
    """Four files tracked without a word though their scores or rows could not be what the
    user meant: six values a row (no score: every detection scored 1, where a CSV file
    without a score column is named), no rows at all (an empty result), raw scores all below
    the new-track threshold (no track can start), and a CSV file whose identity column (not
    "the second value") is filled; and results asked for as JSON, written as MOTChallenge's
    text. Each now says so; a plain detections file says nothing."""
    import warnings

    from vistrack.pipeline import track_sequence

    six = tmp_path / "six.txt"
    six.write_text("".join(f"{f},-1,{10 + 3 * f},20,20,40\n" for f in range(1, 11)))
    with pytest.warns(UserWarning, match=re.escape(
            f"{six}: 6 values a row, no score (MOTChallenge's 7th value, conf): every "
            "detection scores 1")):
        run = track_sequence(six, tmp_path / "a.txt", fps=10)
    assert run.rows == 10
    empty = tmp_path / "empty.txt"
    empty.write_text("")
    with pytest.warns(UserWarning, match=re.escape(
            f"{empty}: no detections: nothing to track, and the results hold no rows")):
        run = track_sequence(empty, tmp_path / "b.txt", fps=10)
    assert run.rows == 0
    for text in ("", "\n  \n"):  # a CSV file with no header either: failed in pandas' words
        blank = tmp_path / "blank.csv"
        blank.write_text(text)
        with pytest.warns(UserWarning, match=re.escape(
                f"{blank}: no detections: nothing to track, and the results hold no rows")):
            run = track_sequence(blank, tmp_path / "b.txt", fps=10, force=True)
        assert run.rows == 0
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{f},-1,{10 + 3 * f},20,20,40,0.9\n" for f in range(1, 11)))
    # new_track or high above every raw score starts no track (high alone wrote 0 boxes
    # without a word), nor offline start_score; offline, a min_track_score that drops every
    # track says so
    starts = "(a track starts from a detection scoring at least high and new_track)"
    for name, kwargs, message in (
            ("c", dict(scores="raw", new_track=2.0),
             f"{det}: every score lies below new_track 2 (the scores run 0.9 to 0.9), and with "
             f"raw scores (--scores raw) no track can start {starts}: lower --new-track"),
            ("c2", dict(scores="raw", high=5.0),
             f"{det}: every score lies below high 5 (the scores run 0.9 to 0.9), and with raw "
             f"scores (--scores raw) no track can start {starts}: lower --high, or calibrate"),
            ("c3", dict(scores="raw", offline=True, start_score=0.95),
             f"{det}: every score lies below start_score 0.95 (the scores run 0.9 to 0.9), and "
             "with raw scores (--scores raw) no track can start (a track starts from a "
             "detection scoring at least high, new_track and start_score): lower "
             "--start-score, or calibrate"),
            ("c4", dict(scores="raw", offline=True, min_track_score=1.0),
             "min_score 1 (min_track_score under [offline] in a --config file, "
             "--min-track-score) drops every one of the 1 confirmed tracks, the highest mean "
             "confidence of a track's detections being 0.9: the results hold no rows")):
        with pytest.warns(UserWarning, match=re.escape(message)):
            run = track_sequence(det, tmp_path / f"{name}.txt", fps=10, **kwargs)
        assert run.rows == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert track_sequence(det, tmp_path / "d.txt", fps=10, scores="raw").rows == 10
        assert track_sequence(det, tmp_path / "e.txt", fps=10).rows == 10
    # a results file named for a format vistrack does not write gets MOTChallenge's text,
    # and says so; .txt and no suffix do not
    with pytest.warns(UserWarning, match=re.escape(
            f"{tmp_path / 'r.json'}: written as MOTChallenge text; .json is not a format "
            "vistrack writes (.txt: MOTChallenge's text, .csv, .parquet)")):
        track_sequence(det, tmp_path / "r.json", fps=10)
    assert (tmp_path / "r.json").read_bytes() == (tmp_path / "e.txt").read_bytes()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        track_sequence(det, tmp_path / "results", fps=10)
    csv = tmp_path / "ids.csv"
    csv.write_text("frame,x1,y1,x2,y2,conf,track\n"
                   + "".join(f"{f},{10 + 3 * f},20,{30 + 3 * f},60,0.9,4\n" for f in range(1, 11)))
    with pytest.warns(UserWarning, match=re.escape(
            f"{csv}: every row has an identity (column 'track'; detections have -1)")):
        track_sequence(csv, tmp_path / "f.txt", fps=10, columns={"id": "track"})


def test_the_results_never_overwrite_the_detections_file(tmp_path):
    """``--out`` naming the detections file itself, with ``--force``, wrote the results over
    the detections: the input was lost. It is refused, and the file left as it was."""
    from vistrack.pipeline import track_sequence

    det = tmp_path / "det.txt"
    det.write_text("".join(f"{f},-1,{10 + 2 * f},10,20,40,0.9\n" for f in range(1, 6)))
    before = det.read_bytes()
    for out in (det, tmp_path / "sub" / ".." / "det.txt"):
        with pytest.raises(ValueError, match=r"is the detections file: the run would write "
                                             r"over it; give another out"):
            track_sequence(det, out, fps=10, force=True)
    seq = tmp_path / "seq"
    (seq / "det").mkdir(parents=True)
    (seq / "det" / "det.txt").write_bytes(before)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=5\n"
                                     "imWidth=100\nimHeight=100\n")
    with pytest.raises(ValueError, match="is the detections file"):
        track_sequence(seq, seq / "det" / "det.txt", force=True)
    assert det.read_bytes() == before == (seq / "det" / "det.txt").read_bytes()
    # nor the sequence's other files: with --force its seqinfo.ini became results (the next
    # run failed on it) and its ground truth was replaced by the tracks without a word;
    # other detections given, its own det.txt is still its own
    (seq / "gt").mkdir()
    (seq / "gt" / "gt.txt").write_text("1,1,10,10,20,40,1,1,1\n")
    files = {p: p.read_bytes() for p in seq.rglob("*") if p.is_file()}
    for out, what in ((seq / "seqinfo.ini", "seqinfo.ini"), (seq / "gt" / "gt.txt", "ground truth"),
                      (seq / "det" / ".." / "det" / "det.txt", "detections file")):
        # (named as Python's argument, out: "--out" was the command line's)
        with pytest.raises(ValueError, match=re.escape(
                f"out {out} is the sequence's {what}: the run would write over it; give "
                "another out")):
            track_sequence(seq, out, detections=det, force=True)
    assert {p: p.read_bytes() for p in seq.rglob("*") if p.is_file()} == files


def _mjpg_video(path, frames, fps=25):
    h, w = frames[0].image.shape[:2]
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, (w, h))
    for f in frames:
        vw.write(f.image)
    vw.release()
    return path


def test_no_output_is_the_runs_own_input(tmp_path):
    """With ``force``, ``track_one(video, out=video)`` wrote its boxes over the video, ``out``
    naming ``gt`` replaced the ground truth by the boxes, and ``track_video`` wrote its
    ``tracks.txt`` over a ``gt`` or a ``detections:FILE`` in the output folder (and its
    ``annotated.mp4`` over the video tracked), or wrote among the frames of an image folder:
    the input was lost. Each is refused before anything is read, by any path to the file
    through folders, and every file keeps its bytes; a link at the output's name is
    replaced, not the file it points to, and is no input."""
    from vistrack.pipeline import track_one

    frames, truth = red_disc_clip(T=6)
    out = tmp_path / "out"
    out.mkdir()
    video = _mjpg_video(out / "annotated.mp4", frames)
    gt = out / "tracks.txt"
    gt.write_text("".join(f"{k},1,{x:.1f},{y:.1f},{w:.1f},{h:.1f},1,1,1\n"
                          for k, (x, y, w, h) in enumerate(truth, 1)))
    boxes = tmp_path / "boxes.txt"
    boxes.write_text("".join(f"{x:.1f},{y:.1f},{w:.1f},{h:.1f}\n" for x, y, w, h in truth))
    os.link(boxes, tmp_path / "hard.txt")
    folder = write_clip(tmp_path / "frames", frames)
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}

    def refused(what, call, *args, **kwargs):
        with pytest.raises(ValueError, match=re.escape(what) + "(: the run would write over it|"
                                             "; give another)"):
            call(*args, **kwargs)

    refused(f"out {video} is the video tracked", track_one, video, truth[0], video, force=True)
    refused(f"out {boxes} is the ground truth (--gt)", track_one, folder, None, boxes,
            gt=boxes, force=True)
    # named before "exists; pass --force", which would have it written over next
    refused(f"out {boxes} is the ground truth (--gt)", track_one, folder, None, boxes, gt=boxes)
    # through a folder that is a link to the input's
    (tmp_path / "via").symlink_to(tmp_path)
    refused(f"out {tmp_path / 'via' / 'boxes.txt'} is the ground truth (--gt)", track_one,
            folder, None, tmp_path / "via" / "boxes.txt", gt=boxes, force=True)
    # among the frames read (an image written over, or one more frame for the next run)
    refused(f"out {folder / '000001.png'} lies in the folder of the images tracked, among "
            "the files the run reads", track_one, folder, truth[0], folder / "000001.png",
            force=True)
    refused(f"out_dir {out}: {gt} is the ground truth (--gt)", track_video, folder, out,
            frontend=TruthDetector(truth), gt=gt, force=True)
    refused(f"out_dir {out}: {gt} is the detections file (--frontend detections:FILE)",
            track_video, folder, out, frontend=f"detections:{gt}", force=True)
    refused(f"out_dir {out}: {video} is the video tracked", track_video, video, out,
            frontend=TruthDetector(truth), force=True)
    # a sequence folder as gt is its gt/gt.txt (here a link to the file written over)
    seq = tmp_path / "seq"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").symlink_to(gt)
    refused(f"out_dir {out}: {gt} is the ground truth (--gt)", track_video, folder, out,
            frontend=TruthDetector(truth), gt=seq, force=True)
    (seq / "gt" / "gt.txt").unlink()
    # a sequence folder's seqinfo.ini and its imDir
    (seq / "seqinfo.ini").write_text("[Sequence]\nimDir=frames\nframeRate=25\n")
    os.symlink(folder, seq / "frames")
    refused(f"out {seq / 'seqinfo.ini'} is the sequence's seqinfo.ini", track_one, seq,
            truth[0], seq / "seqinfo.ini", force=True)
    refused(f"out {seq / 'frames' / 'x.png'} lies in the folder of the images tracked, among "
            "the files the run reads", track_one, seq, truth[0], seq / "frames" / "x.png")
    (seq / "seqinfo.ini").unlink()
    (seq / "frames").unlink()
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()
            and "via" not in p.parts} == before
    # a link at the output's name is replaced, not the file it points to: no input
    (tmp_path / "link.txt").symlink_to(boxes)
    track_one(folder, None, tmp_path / "link.txt", gt=boxes, force=True)
    track_one(folder, None, tmp_path / "hard.txt", gt=boxes, force=True)
    assert not (tmp_path / "link.txt").is_symlink() and boxes.read_bytes() == before[boxes]
    # an output of the same name elsewhere is no input
    with pytest.warns(UserWarning, match="every row has an identity"):
        track_video(folder, tmp_path / "out2", frontend=f"detections:{gt}", gt=gt, fps=25,
                    annotate=False)
    assert (tmp_path / "out2" / "tracks.txt").exists()


def test_the_command_line_refuses_an_output_that_is_an_input_before_reading(tmp_path, capsys):
    """``vistrack track --out-dir`` and ``track-one --out`` name an output that is the run's
    own input before anything is read (the --config file too), and write nothing."""
    from vistrack.cli import main

    frames, truth = red_disc_clip(T=6)
    video = _mjpg_video(tmp_path / "in.avi", frames)
    out = tmp_path / "o"
    out.mkdir()
    (out / "tracks.txt").write_text("1,1,10,10,20,20,1,1,1\n")
    assert main(["track", str(video), "--out-dir", str(out), "--gt", str(out / "tracks.txt"),
                 "--frontend", "hog", "--force"]) == 2
    err = capsys.readouterr().err
    assert err == (f"vistrack track: error: --out-dir {out}: {out / 'tracks.txt'} is the ground "
                   "truth (--gt): the run would write over it; give another --out-dir\n")
    assert main(["track-one", str(video), "--init", "30,30,20,20", "--out", str(video),
                 "--force"]) == 2
    assert capsys.readouterr().err == (f"vistrack track-one: error: --out {video} is the video "
                                       "tracked: the run would write over it; give another "
                                       "--out\n")
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["in.avi", "o", "tracks.txt"]
    # several inputs: one job's outputs may not be another's input (in.avi's video,
    # o/in/annotated.mp4, over the input of that name)
    (out / "in").mkdir()
    other = _mjpg_video(out / "in" / "annotated.mp4", frames)
    kept = other.read_bytes()
    assert main(["track", str(other), str(video), "--out-dir", str(out), "--frontend", "hog",
                 "--force", "--jobs", "1"]) == 2
    err = capsys.readouterr().err
    assert f"{other} is the video tracked: the run would write over it" in err, err
    assert other.read_bytes() == kept


def test_a_video_without_frames_is_named_by_every_front_end_and_track_one(tmp_path):
    """A video with a header and no frame: the background model's start said "initialize
    needs at least one frame" (no file named), and ``track_one`` wrote an empty boxes file
    over an earlier one with force and gave -1e12 frames a second. Each now says the video
    has no frames, and the earlier file keeps its bytes."""
    from vistrack.pipeline import track_one

    empty = tmp_path / "empty.avi"
    cv2.VideoWriter(str(empty), cv2.VideoWriter_fourcc(*"MJPG"), 25, (64, 48)).release()
    for frontend in ("bgsub", "hog"):
        with pytest.raises(ValueError, match=re.escape(f"{empty}: no frames to track")):
            track_video(empty, tmp_path / frontend, frontend=frontend)
        assert not (tmp_path / frontend).exists()
    boxes = tmp_path / "boxes.txt"
    boxes.write_text("1,5.00,10.00,20.00,30.00\n")
    with pytest.raises(ValueError, match=re.escape(f"{empty}: no frames to track")):
        track_one(empty, [5, 10, 20, 30], boxes, force=True)
    assert boxes.read_text() == "1,5.00,10.00,20.00,30.00\n"
    from vistrack.pipeline import SingleRun

    assert SingleRun(boxes, np.zeros((0, 4)), 0.0, None).fps == 0.0


def test_a_header_frame_rate_out_of_range_names_the_video_and_fps(tmp_path):
    """A video header's rate of 10^8 frames/s was named by the motion model, as
    ``frame_rate``, an argument the caller never gave; one of NaN was "fps must be a finite
    number", another. The first names the video and asks for the true rate; the second is
    no rate (30 frames/s, said, as for a header without one)."""
    import struct

    frames, truth = red_disc_clip(T=4)
    video = _mjpg_video(tmp_path / "v.avi", frames, fps=10)
    data = bytearray(video.read_bytes())
    at = data.index(b"strh") + 8 + 20  # the stream header's dwScale, dwRate
    for name, scale, rate in (("huge", 1, 10**8), ("nan", 0, 0)):
        patched = tmp_path / f"{name}.avi"
        d = data.copy()
        d[at:at + 8] = struct.pack("<II", scale, rate)
        patched.write_bytes(bytes(d))
        fps = cv2.VideoCapture(str(patched)).get(cv2.CAP_PROP_FPS)
        if name == "huge":
            assert fps == 1e8
            with pytest.raises(ValueError, match=re.escape(
                    f"{patched}: its header gives 1e+08 frames/s, and the box tracker takes 0.001 "
                    "to 1e+06 (give the true rate with --fps")):
                track_video(patched, tmp_path / "o1", frontend=TruthDetector(truth))
            run = track_video(patched, tmp_path / "o2", frontend=TruthDetector(truth), fps=10,
                              annotate=False)
            assert run.fps > 0 and run.frames == 4
        elif not np.isfinite(fps) or fps <= 0:  # OpenCV's reading of a rate of 0 / 0
            with pytest.warns(UserWarning, match="gives no frame rate"):
                run = track_video(patched, tmp_path / "o3", frontend=TruthDetector(truth),
                                  annotate=False)
            assert run.frames == 4


def test_a_sink_that_fails_to_start_leaves_no_partial_file_of_the_others(tmp_path, monkeypatch):
    """A sink whose constructor fails (the plot's matplotlib import, done up front) left the
    sinks made before it with their partial files, in the user's folder, and kept a folder the
    run had made. Those are removed, and the user's own files kept."""
    import vistrack.viz.plots as plots

    def broken():
        raise ImportError("matplotlib is broken (simulated)")

    monkeypatch.setattr(plots, "_import_agg", broken)
    frames, truth = red_disc_clip(T=4)
    folder = write_clip(tmp_path / "frames", frames)
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine\n")
    for where in (out, tmp_path / "new" / "out"):
        with pytest.raises(ImportError, match="simulated"):
            track_video(folder, where, frontend=TruthDetector(truth), fps=25)
    assert [p.name for p in out.iterdir()] == ["keep.txt"]
    assert not (tmp_path / "new").exists()


def test_a_run_without_a_video_removes_an_earlier_runs_video(tmp_path):
    """``annotate=False`` with ``force`` over an earlier run's folder kept its
    ``annotated.mp4``, which showed other tracks beside the new ones (and the report showed
    it). Without ``force`` it is named as the outputs are; with it, removed as the new
    outputs are written."""
    frames, truth = red_disc_clip(T=4)
    folder = write_clip(tmp_path / "frames", frames)
    out = tmp_path / "out"
    track_video(folder, out, frontend=TruthDetector(truth), fps=25)
    assert (out / "annotated.mp4").exists()
    with pytest.raises(FileExistsError, match="annotated.mp4"):
        track_video(folder, out, frontend=TruthDetector(truth), fps=25, annotate=False)
    assert (out / "annotated.mp4").exists()
    track_video(folder, out, frontend=TruthDetector(truth), fps=25, annotate=False, force=True)
    assert sorted(p.name for p in out.iterdir()) == ["run.json", "tracks.csv", "tracks.txt",
                                                     "trajectories.png"]


def test_a_detection_beyond_the_sequences_frames_is_named_by_its_line(tmp_path):
    """A detection on a frame past seqinfo.ini's seqLength names the first such line, as
    ``vistrack eval`` names a ground-truth row past it."""
    from vistrack.pipeline import track_sequence

    seq = tmp_path / "seq"
    (seq / "det").mkdir(parents=True)
    (seq / "det" / "det.txt").write_text(
        "".join(f"{f},-1,{10 + 2 * f},10,20,40,0.9\n" for f in (1, 2, 7, 3, 9)))
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=5\n"
                                     "imWidth=100\nimHeight=100\n")
    with pytest.raises(ValueError) as e:
        track_sequence(seq, tmp_path / "out.txt")
    assert str(e.value) == (f"{seq / 'det' / 'det.txt'}, line 3: frame 7 is beyond the "
                            f"sequence's 5 frames ({seq / 'seqinfo.ini'})")


def test_a_parquet_results_file_carries_each_tracks_class(tmp_path):
    """A MOTChallenge results file has no class column, so a detections file of several
    classes loses them there; a Parquet results file (the same rows, with
    ``MOTTable.to_pandas``'s columns) carries each row's class, online and offline: that of
    the detections its track follows."""
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    from vistrack.pipeline import track_sequence

    # class 3 moving right along y = 20, class 5 moving left along y = 200, and a gap of
    # frames 8-9 in class 5's detections, which the offline mode fills
    rows = [f"{f},-1,{10 + 3 * f},20,20,40,0.9,3,-1,-1\n" for f in range(1, 21)]
    rows += [f"{f},-1,{300 - 3 * f},200,20,40,0.9,5,-1,-1\n" for f in range(1, 21)
             if f not in (8, 9)]
    det = tmp_path / "two.csv"
    pd.DataFrame([r.split(",")[:8] for r in rows],
                 columns=["frame", "id", "bb_left", "bb_top", "bb_width", "bb_height", "conf",
                          "class"]).astype(float).to_csv(det, index=False)
    for offline in (False, True):
        with pytest.warns(UserWarning, match="detections of 2 classes") as said:
            run_ = track_sequence(det, tmp_path / f"out-{offline}.parquet", fps=10,
                                  scores="raw", offline=offline)
        # (the results file has a class column: the warning says nothing of one missing)
        assert not any("no class column" in str(w.message) for w in said)
        table = pd.read_parquet(run_.out)
        ids = table.groupby("class")["particle"].unique()  # the identity (trackpy's name)
        assert sorted(ids.index) == [3, 5] and all(len(v) == 1 for v in ids)
        # each row's class is its track's, and its boxes are that class's path
        assert (table.loc[table["class"] == 3, "bb_top"] == 20).all()
        assert (table.loc[table["class"] == 5, "bb_top"].round() == 200).all()
        # offline, class 5's gap is filled: both tracks on all 20 frames
        assert not offline or len(table) == 40


def test_a_detector_that_ran_on_every_other_frame_is_tracked_on_its_own_frames(tmp_path):
    """A detector run on every 2nd frame, its rows numbered by the video's frames: the
    frames between are not frames where it found nothing. Stepping through them as such
    dropped every new track before it could be confirmed (a track needs two updates in a
    row), and a person walking across was never reported after the first frame. The run
    now tracks the frames the detector ran on, at half the frame rate, and says so; online,
    each frame between has the tracks' boxes predicted from the frames before it, and
    offline, boxes on the straight line between the smoothed ones: for a person walking at
    a constant velocity, where they are. A video tracked with these detections
    (``--frontend detections:FILE``) is tracked the same way."""
    import warnings

    from vistrack.pipeline import track_sequence

    def truth(f):
        return np.array([10 + 4.0 * f, 20 + 1.0 * f, 30, 60])

    det = tmp_path / "det.txt"
    det.write_text("".join(f"{f},-1,{','.join(f'{v:g}' for v in truth(f))},0.9\n"
                           for f in range(1, 40, 2)))
    with pytest.warns(RuntimeWarning) as got:
        online = track_sequence(det, tmp_path / "on.txt", fps=20, scores="raw")
    assert [str(w.message) for w in got] == [
        f"{det}: detections on every 2nd frame only (frames 1, 3, 5, ...): tracked as a "
        "sequence of those frames at 10 frames/s; the frames between have the tracks' "
        "predicted boxes (score 0)"]
    assert online.derived["detection_stride"] == 2 and online.derived["frame_rate"] == 10
    on = read_mot(online.out)
    # the track from the first frame (a track found in the first frame is reported at
    # once), each frame between the detector's predicted from the ones before it only
    assert on.frames.tolist() == list(range(1, 40)) and set(on.ids.tolist()) == {1}
    between = on.frames % 2 == 0
    assert (on.conf[between] == 0).all() and (on.conf[~between] > 0).all()
    # once the filter has the person's velocity (3 frames), where they are
    np.testing.assert_allclose(on.boxes[5:], [truth(f) for f in on.frames[5:]], atol=1.0)
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        offline = track_sequence(det, tmp_path / "off.txt", fps=20, scores="raw",
                                 offline=True)
    off = read_mot(offline.out)
    assert off.frames.tolist() == list(range(1, 40)) and set(off.ids.tolist()) == {1}
    between = off.frames % 2 == 0
    assert (off.conf[between] == 0).all() and (off.conf[~between] > 0).all()
    # a filled box is halfway between its neighbours (written to 2 decimals), and every
    # box within a pixel of where the person is (the smoother starts from no velocity)
    np.testing.assert_allclose(off.boxes[1:-1][between[1:-1]],
                               (off.boxes[:-2] + off.boxes[2:])[between[1:-1]] / 2, atol=0.011)
    np.testing.assert_allclose(off.boxes, [truth(f) for f in off.frames], atol=1.0)

    # a video from pixels with these detections (--frontend detections:FILE): the box
    # tracker steps through the detector's frames alone there too, and every frame of the
    # video gets the disc's box; another tracker is told that it steps through them all
    frames, boxes = red_disc_clip(T=24)
    clip = write_clip(tmp_path / "frames", frames)
    every2 = tmp_path / "disc.txt"
    every2.write_text("".join(f"{f},-1,{','.join(f'{v:g}' for v in boxes[f - 1])},0.9\n"
                              for f in range(1, 25, 2)))
    with pytest.warns(RuntimeWarning) as got:
        video = track_video(clip, tmp_path / "video", frontend=f"detections:{every2}", fps=25,
                            annotate=False, scores="raw")
    assert [str(w.message) for w in got] == [
        f"{every2}: detections on every 2nd frame only (frames 1, 3, 5, ...): tracked as a "
        "sequence of those frames at 12.5 frames/s; the frames between have the tracks' "
        "predicted boxes (score 0)"]
    assert video.derived["frame_rate"] == 12.5
    rows = read_mot(video.files["tracks"])
    assert rows.frames.tolist() == list(range(1, 25)) and set(rows.ids.tolist()) == {1}
    np.testing.assert_allclose(rows.boxes[5:], boxes[5:], atol=1.0)

    class Count:  # a tracker of one's own
        def step(self, frame, detections):
            return Tracks.empty()

        def reset(self):
            pass

    # a box tracker made by the caller, as an object or by module:callable, keeps the frame
    # rate it was made with
    owns = ((Count(), "Count"), (BoxTracker(frame_rate=25), "BoxTracker"),
            ("vistrack.tracking:BoxTracker", "BoxTracker"))
    for k, (own, name) in enumerate(owns):
        with pytest.warns(RuntimeWarning, match=rf"^{every2}: detections on every 2nd frame "
                                                rf"only: the tracker, {name}, steps through "
                                                r"every frame of the video, each frame "
                                                r"without detections as one where nothing was "
                                                r"found$"):
            track_video(clip, tmp_path / f"own{k}", frontend=f"detections:{every2}", fps=25,
                        annotate=False, tracker=own)


def test_frames_a_detector_did_not_deliver_are_tracked_over(tmp_path):
    """A detector that did not deliver some frames (dropped while busy), its rows numbered by
    the video's frames: a frame without rows amid frames with 5 or more each is not one
    where it found nothing. Stepped through as such, every track missed a frame there: a
    new one was dropped before it could be confirmed, and nothing was reported on the frame
    but what coasts. The run now steps over such frames, and says so: online they get the
    tracks' predicted boxes, offline boxes on the straight line between the smoothed ones;
    six people walking at a constant velocity are where they are on every frame, and a
    seventh, coming in frame 8 just before two frames that were not delivered, is confirmed
    by its second detection, in frame 11. Where fewer than 5 were found around such a
    frame, it is one where nothing was found, as before."""
    import warnings

    from vistrack.pipeline import track_sequence

    def truth(k, f):  # walker k in frame f
        return np.array([10 + 3.0 * f, 20 + 70.0 * k, 30, 60])

    gone = (4, 9, 10, 17)
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{f},-1,{','.join(f'{v:g}' for v in truth(k, f))},0.9\n"
                           for f in range(1, 25) if f not in gone
                           for k in [*range(6), *([7] if f >= 8 else [])]))
    for offline, there in ((False, "given their predicted boxes there"),
                           (True, "filled on the line between the smoothed boxes there")):
        with pytest.warns(RuntimeWarning) as got:
            run = track_sequence(det, tmp_path / f"{offline}.txt", fps=10, scores="raw",
                                 offline=offline)
        assert [str(w.message) for w in got] == [
            f"{det}: 4 frames without detections amid frames with 5 or more each (frames 4, "
            "9, 10, 17): taken as frames the detector did not deliver; the tracks are carried "
            f"across them, and {there} (score 0)"]
        assert run.derived["undelivered_frames"] == 4 and run.derived["frame_rate"] == 10
        t = read_mot(run.out)
        walkers = t.ids <= 6
        assert sorted(set(t.ids.tolist())) == [1, 2, 3, 4, 5, 6, 7]
        assert (np.bincount(t.frames[walkers]) == 6)[1:].all() and t.frames.max() == 24
        not_delivered = np.isin(t.frames, gone)
        assert (t.conf[not_delivered] == 0).all() and (t.conf[~not_delivered] > 0).all()
        # after the first frame (offline, the smoother starts from no velocity)
        late = walkers & (t.frames >= 2)
        want = np.array([truth(i - 1, f) for i, f in zip(t.ids[late], t.frames[late])])
        np.testing.assert_allclose(t.boxes[late], want, atol=1.0)
        # the newcomer: one identity, reported from its confirmation (online) or its first
        # detection (offline, followed back) to the end, the two frames between filled
        assert t.frames[t.ids == 7].tolist() == list(range(11 if not offline else 8, 25))
    # a video from pixels with such detections (--frontend detections:FILE): the disc, and
    # five boxes that stay, in every frame but 9 and 10; the disc's track on every frame
    frames, boxes = red_disc_clip(T=24)
    clip = write_clip(tmp_path / "frames", frames)
    file = tmp_path / "disc.txt"
    file.write_text("".join(
        f"{f},-1,{','.join(f'{v:g}' for v in b)},0.9\n" for f in range(1, 25) if f not in (9, 10)
        for b in [boxes[f - 1], *([100 + 10 * j, 5 + 20 * j, 8, 8] for j in range(5))]))
    with pytest.warns(RuntimeWarning, match=rf"^{file}: 2 frames without detections amid "
                                            r"frames with 5 or more each \(frames 9, 10\)"):
        video = track_video(clip, tmp_path / "video", frontend=f"detections:{file}", fps=25,
                            annotate=False, scores="raw")
    rows = read_mot(video.files["tracks"])
    # rows for frames past the folder's last image, with frames 30 and 31 left out there: only
    # the frames tracked are said to be without detections (frames 9, 10, 30, 31 were, beside
    # "rows on frames 25-40, past the video's last frame (24): not tracked"), for the box
    # trackers and a caller's alike; their tracks are as before
    longer = tmp_path / "longer.txt"
    longer.write_text(file.read_text() + "".join(
        f"{f},-1,{100 + 10 * j},{5 + 20 * j},8,8,0.9\n" for f in range(25, 41)
        if f not in (30, 31) for j in range(6)))
    for tracker, said in (("bytetrack", r" \(frames 9, 10\): taken as frames the detector"),
                          (BoxTracker(frame_rate=25), r": the tracker, BoxTracker, steps")):
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            more = track_video(clip, tmp_path / f"longer{type(tracker).__name__}",
                               frontend=f"detections:{longer}", fps=25, annotate=False,
                               scores="raw", tracker=tracker)
        said_gone = [str(w.message) for w in got if "without detections" in str(w.message)]
        assert len(said_gone) == 1 and re.search(rf"^{longer}: 2 frames without detections "
                                                 rf"amid frames with 5 or more each{said}",
                                                 said_gone[0]), said_gone
        assert any("rows on frames 25-40, past the video's last frame (24): not tracked"
                   in str(w.message) for w in got)
        if tracker == "bytetrack":
            assert read_mot(more.files["tracks"]).boxes.tolist() == rows.boxes.tolist()
    # a tracker made by the caller steps through every frame, and is told so
    with pytest.warns(RuntimeWarning, match=rf"^{file}: 2 frames without detections amid "
                                            r"frames with 5 or more each: the tracker, "
                                            r"BoxTracker, steps through every frame of the "
                                            r"video, each frame without detections as one "
                                            r"where nothing was found$"):
        track_video(clip, tmp_path / "own", frontend=f"detections:{file}", fps=25,
                    annotate=False, tracker=BoxTracker(frame_rate=25))
    # a stray frame number far past the video: its run was listed frame by frame (a
    # MemoryError of 745 GiB) before the tracker stepped the video's frames
    stray = tmp_path / "stray.txt"
    stray.write_text("".join(f"{f},-1,{100 + 10 * j},{5 + 20 * j},8,8,0.9\n"
                             for f in (1, 2, 3, 10 ** 11) for j in range(6)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        own = track_video(clip, tmp_path / "stray", frontend=f"detections:{stray}", fps=25,
                          annotate=False, tracker=BoxTracker(frame_rate=25))
    assert read_mot(own.files["tracks"]).frames.max() <= 24
    first = rows.frames == 1
    disc = rows.ids == rows.ids[first][np.abs(rows.boxes[first] - boxes[0]).sum(1).argmin()]
    np.testing.assert_array_equal(rows.frames[disc], np.arange(1, 25))
    np.testing.assert_allclose(rows.boxes[disc][5:], boxes[5:], atol=1.0)
    # two people a frame: a frame without rows is one where nothing was found
    sparse = tmp_path / "sparse.txt"
    sparse.write_text("".join(f"{f},-1,{','.join(f'{v:g}' for v in truth(k, f))},0.9\n"
                              for f in range(1, 25) if f not in gone for k in range(2)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        run = track_sequence(sparse, tmp_path / "sparse_out.txt", fps=10, scores="raw")
    assert "undelivered_frames" not in run.derived
    # nothing there but a track coasting for 0.1 s (frame 9), as before
    assert 10 not in read_mot(run.out).frames


def test_a_detector_that_dropped_a_fifth_of_its_frames_tracks_as_well_as_with_them(
        tmp_path):
    """MOT17-09 (30 frames/s) with the rows of a fifth of its frames removed at random (as a
    detector dropping frames while busy would leave them): against the ground truth of every
    frame, HOTA within 2 points of the whole file's, online and offline (stepped through as
    frames where nothing was found, it scored 40.1 online against 49.3). KITTI-0001-Car's
    own file has no rows on frames 178-181 while the frames either side have 11 and 12: those
    four are taken as not delivered, and no frame of it else."""
    import warnings

    from vistrack.detector_checks import undelivered_frames
    from vistrack.evaluation import evaluate_mot
    from vistrack.pipeline import track_sequence

    from .mot_oracles import SHARED

    seq = SHARED / "mot17" / "MOT17-09-FRCNN"
    kitti = SHARED / "kitti-tracking" / "KITTI-0001-Car" / "det" / "det.txt"
    if not seq.exists() or not kitti.exists():
        pytest.skip(f"{seq} not found: the shared data is not beside this checkout")
    assert undelivered_frames(read_mot(kitti).frames).tolist() == [178, 179, 180, 181]
    lines = (seq / "det" / "det.txt").read_text().splitlines(keepends=True)
    frames = np.array([int(t.split(",", 1)[0]) for t in lines])
    have = np.unique(frames)
    gone = have[np.random.default_rng(0).random(len(have)) < 0.2]
    det = tmp_path / "det.txt"
    det.write_text("".join(t for t, f in zip(lines, frames) if f not in set(gone.tolist())))
    gt = read_mot(seq / "gt" / "gt.txt")
    for offline in (False, True):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            full = track_sequence(seq, tmp_path / f"full{offline}.txt", offline=offline)
            dropped = track_sequence(seq, tmp_path / f"dropped{offline}.txt", detections=det,
                                     offline=offline)
        assert dropped.derived["undelivered_frames"] > 0.7 * len(gone)
        want = evaluate_mot(gt, read_mot(full.out), 525).HOTA
        got = evaluate_mot(gt, read_mot(dropped.out), 525).HOTA
        assert got > want - 0.02, (offline, got, want)


def test_a_strided_detections_file_tracks_as_the_sequence_of_its_frames(tmp_path):
    """Every 2nd (MOT17-09, 30 frames/s) or 3rd (KITTI-0001, 10 frames/s) frame's
    detections, numbered by the video's frames, give online the same tracks, row for row,
    as the same detections numbered 1, 2, 3, ... at the lower frame rate (the independent
    run the stride stands for), and offline the same rows at those frames; the frames
    between have the tracks' predicted boxes online and boxes filled between the smoothed
    ones offline. The ground truth has people in those frames too: HOTA over every frame
    rises above that of the rows at the detector's frames alone."""
    import warnings

    from vistrack.evaluation import evaluate_mot
    from vistrack.pipeline import track_sequence

    from .mot_oracles import SHARED

    for bench, name, k in (("mot17", "MOT17-09-FRCNN", 2), ("kitti-tracking",
                                                             "KITTI-0001-Car", 3)):
        seq = SHARED / bench / name
        if not seq.exists():
            pytest.skip(f"{seq} not found: the shared data is not beside this checkout")
        a = np.loadtxt(seq / "det" / "det.txt", delimiter=",", ndmin=2)
        keep = a[(a[:, 0] - 1) % k == 0]
        strided = tmp_path / f"{name}.det.txt"
        np.savetxt(strided, keep, delimiter=",", fmt="%.6g")
        info = dict(line.split("=", 1) for line in (seq / "seqinfo.ini").read_text().split()
                    if "=" in line)
        renum = tmp_path / name
        (renum / "det").mkdir(parents=True)
        r = keep.copy()
        r[:, 0] = (r[:, 0] - 1) // k + 1
        np.savetxt(renum / "det" / "det.txt", r, delimiter=",", fmt="%.6g")
        (renum / "seqinfo.ini").write_text(
            f"[Sequence]\nname={name}\nframeRate={float(info['frameRate']) / k}\n"
            f"seqLength={(int(info['seqLength']) - 1) // k + 1}\nimWidth={info['imWidth']}\n"
            f"imHeight={info['imHeight']}\n")
        for offline in (False, True):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                a_run = track_sequence(seq, tmp_path / f"a{offline}.txt", detections=strided,
                                       offline=offline, force=True)
                b_run = track_sequence(renum, tmp_path / f"b{offline}.txt", offline=offline,
                                       force=True)
            got, want = read_mot(a_run.out), read_mot(b_run.out)
            at = (got.frames - 1) % k == 0
            np.testing.assert_array_equal(got.frames[at], (want.frames - 1) * k + 1)
            np.testing.assert_array_equal(got.ids[at], want.ids)
            np.testing.assert_array_equal(got.boxes[at], want.boxes)
            np.testing.assert_array_equal(got.conf[at], want.conf)
            assert (got.conf[~at] == 0).all() and len(np.unique(got.frames[~at])) > 100
            gt = read_mot(seq / "gt" / "gt.txt")
            n = int(info["seqLength"])
            every = evaluate_mot(gt, got, n).HOTA
            alone = evaluate_mot(gt, got[at], n).HOTA
            assert every > alone + 0.05, (name, offline, every, alone)


def test_offline_carries_the_tracks_on_after_a_strided_detectors_last_frame(tmp_path):
    """A detector on every 3rd frame of a 30-frame sequence ran last on frame 28: online,
    frames 29 and 30 have the tracks' predicted boxes; offline had none there, and each
    track seemed to end two frames early. Now it carries on each track of frame 28 as the
    online mode does, its centre along its line and its size by the same factor each frame:
    for a box moving 4 pixels a frame and growing 1 % a frame (the oracle: its true boxes;
    held where it was on frame 28, it would be 4 and 8 pixels off), within 0.3 pixel, closer
    than the online mode's predictions, with score 0. On MOT17-09 (525 frames) from every
    3rd frame's detections, frames 524 and 525 hold the tracks of frame 523."""
    import warnings

    from vistrack.pipeline import track_sequence

    from .mot_oracles import SHARED

    f = np.arange(1, 31)
    w, h = 40 * 1.01 ** f, 80 * 1.01 ** f
    cx, cy = 100 + 4 * f, 200 - 1.5 * f
    true = np.c_[cx - w / 2, cy - h / 2, w, h]
    seq = tmp_path / "seq"
    (seq / "det").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=30\nseqLength=30\n"
                                     "imWidth=640\nimHeight=480\n")
    grid = (f - 1) % 3 == 0
    np.savetxt(seq / "det" / "det.txt", np.c_[f[grid], -np.ones(grid.sum()), true[grid],
                                              np.full(grid.sum(), 0.9)], delimiter=",",
               fmt="%.6f")
    error = {}
    for offline in (False, True):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            got = read_mot(track_sequence(seq, tmp_path / f"o{offline}.txt",
                                          offline=offline).out)
        tail = got.frames > 28
        assert got.frames[tail].tolist() == [29, 30] and (got.conf[tail] == 0).all()
        assert len(np.unique(got.ids)) == 1
        error[offline] = np.abs(got.boxes[tail] - true[28:]).max(axis=1)
    assert (error[True] < 0.3).all() and (error[True] < error[False]).all(), error
    real = SHARED / "mot17" / "MOT17-09-FRCNN"
    if not real.exists():
        pytest.skip(f"{real} not found: the shared data is not beside this checkout")
    a = np.loadtxt(real / "det" / "det.txt", delimiter=",", ndmin=2)
    np.savetxt(tmp_path / "every3.txt", a[(a[:, 0] - 1) % 3 == 0], delimiter=",", fmt="%.6g")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        got = read_mot(track_sequence(real, tmp_path / "real.txt", offline=True,
                                      detections=tmp_path / "every3.txt").out)
    at_523 = sorted(got.ids[got.frames == 523].tolist())
    assert len(at_523) > 3
    for frame in (524, 525):
        assert sorted(got.ids[got.frames == frame].tolist()) == at_523
        assert (got.conf[got.frames == frame] == 0).all()


def test_a_box_of_no_width_is_carried_on_without_nan():
    """After the detector's last frame a track's size grows by the factor of its last frame;
    a width of 0 (a detector's box of no width) gave log(0 / 0), and NaN would have been
    written. It is held at 0, the height still grows by its factor (12 / 11.33 a frame), and
    a track with rows on every detector frame is carried on along its line."""
    from vistrack.pipeline import _fill_between

    F, I = np.array([1, 4, 1, 4]), np.array([1, 1, 2, 2])
    B = np.array([[0.0, 0, 0, 10], [3, 0, 0, 12], [5, 5, 4, 8], [6, 5, 4, 8]])
    f, i, b, c = _fill_between(F, I, B, np.ones(4), 1, 3, np.zeros(0, np.int64), 6)
    assert np.isfinite(b).all() and f.tolist() == [1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6]
    one = b[i == 1]
    assert (one[:, 2] == 0).all()
    np.testing.assert_allclose(one[4:, 3], 12 * (12 / (34 / 3)) ** np.arange(1, 3))
    np.testing.assert_allclose(b[i == 2][4:, 0], [19 / 3, 20 / 3])  # x: 1/3 a frame
    assert (c[f > 4] == 0).all()


def test_progress_that_is_no_stream_is_named(tmp_path):
    """`progress=True` failed with "'bool' object has no attribute 'write'" once the run was
    under way; it is named before anything is written."""
    from vistrack.tracking import BoxTracker

    with pytest.raises(TypeError, match=r"^progress must be a text stream \(sys.stderr, say\) "
                                        r"or None; got bool$"):
        run([Frame(1, 0.0)], None, BoxTracker(), progress=True)


def test_a_det_file_given_from_inside_its_sequence_is_named_by_the_sequence(
        tmp_path, monkeypatch):
    """``vistrack track det/det.txt`` run inside MOT17-02 named the sequence ``det``, and
    wrote ``det.txt`` where TrackEval looks for ``MOT17-02.txt``; ``det.txt`` inside its
    ``det`` folder too. The oracle: the folders the file lies in (``Path.resolve``)."""
    from vistrack.batch import input_label
    from vistrack.io import sequence_name
    from vistrack.pipeline import track_sequence

    seq = tmp_path / "MOT17-02" / "det"
    seq.mkdir(parents=True)
    (seq / "det.txt").write_text("".join(f"{f},-1,{10 + f},20,30,60,0.9\n"
                                         for f in range(1, 6)))
    for where, given in ((seq.parent, "det/det.txt"), (seq, "det.txt"),
                         (seq, "../det/det.txt")):
        monkeypatch.chdir(where)
        want = Path(given).resolve().parent.parent.name
        assert sequence_name(given) == input_label(Path(given)) == want == "MOT17-02"
    monkeypatch.chdir(seq.parent)
    assert sequence_name("other/x.txt") == "x" and sequence_name("det.txt") == "det"
    track_sequence("det/det.txt", tmp_path / "res" / f"{sequence_name('det/det.txt')}.txt",
                   fps=10)
    assert (tmp_path / "res" / "MOT17-02.txt").exists()


def test_a_dotted_folders_run_is_named_by_its_whole_name(tmp_path):
    """``cam1.2024-05-01`` (a folder of images) was named ``cam1`` in run.json, the report's
    title and the score table, where a batch names it ``cam1.2024-05-01``
    (``sequence_name``, the oracle)."""
    import json
    import warnings

    import cv2

    from vistrack.io import sequence_name
    from vistrack.pipeline import track_video

    folder = tmp_path / "cam1.2024-05-01"
    folder.mkdir()
    for k in range(4):
        cv2.imwrite(str(folder / f"{k + 1:06d}.png"), np.zeros((60, 80, 3), np.uint8))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run_ = track_video(folder, tmp_path / "out", annotate=False, fps=10)
    name = json.loads((run_.out_dir / "run.json").read_text())["name"]
    assert name == sequence_name(folder) == "cam1.2024-05-01"


def test_an_interrupt_while_the_outputs_are_renamed_keeps_the_earlier_set(tmp_path,
                                                                          monkeypatch):
    """Each output was renamed into place as its writer closed: Ctrl-C after tracks.txt's
    rename left new tracks beside the earlier run's CSV, video, plot and run.json (whose
    command then described another run). The outputs are renamed together now, run.json
    with them: interrupted anywhere before, the earlier set stays whole, byte for byte (the
    oracle: the files of the earlier run), with no partial file left."""
    from vistrack.pipeline import track_video
    from vistrack.viz.plots import TrajectoryPlot

    clip = Path(__file__).resolve().parents[1] / "src" / "vistrack" / "data" / "pets09-s2l1" \
        / "pets09-s2l1.mp4"
    out = tmp_path / "out"
    track_video(clip, out, stop=12, force=True)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert {"tracks.txt", "tracks.csv", "annotated.mp4", "trajectories.png",
            "run.json"} <= set(before)

    def interrupted(self):
        raise KeyboardInterrupt  # the plot, closed after the tracks, video and CSV

    monkeypatch.setattr(TrajectoryPlot, "close", interrupted)
    with pytest.raises(KeyboardInterrupt):
        track_video(clip, out, stop=12, min_area=150, force=True)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_a_detections_file_s_rows_in_another_order_give_the_same_results(tmp_path):
    """Three people, each found at score 0.9 in every frame: the rows of each frame in the
    file's order and reversed give the same results file, identities included (the tracks
    a frame started were numbered in the rows' order: reversed, the first frame's three
    took 3, 2 and 1)."""
    from vistrack.pipeline import track_sequence

    rows = [(f, k) for f in range(1, 13) for k in range(3)]

    def line(f, k):
        x, y = 40 + 150 * k + 3 * f, 50 + 20 * k
        return f"{f},-1,{x},{y},40,90,0.9,-1,-1,-1\n"

    given, reversed_ = tmp_path / "given.txt", tmp_path / "reversed.txt"
    given.write_text("".join(line(f, k) for f, k in rows))
    reversed_.write_text("".join(line(f, 2 - k) for f, k in rows))
    a = track_sequence(given, tmp_path / "a.txt", fps=10).out.read_text()
    b = track_sequence(reversed_, tmp_path / "b.txt", fps=10).out.read_text()
    assert a == b and len(a.splitlines()) == 36
    assert {line.split(",")[1] for line in a.splitlines()} == {"1", "2", "3"}


@pytest.mark.slow
@pytest.mark.parametrize("bench, name", [("mot17", "MOT17-05-FRCNN"),
                                         ("kitti-tracking", "KITTI-0001-Car")])
def test_tracks_follow_the_image_s_scale_and_ignore_the_rows_order(tmp_path, bench, name):
    """A user's expectations of a box tracker on a real sequence (MOT17-05: 14 frames/s, a
    walking camera; KITTI-0001: a car's camera, 10 frames/s), online and offline:

    - the same video at twice or half its size (every box and the image times 2 or 0.5,
      exact in floating point) gives the same tracks, each box times the same factor: the
      noise, gates, camera shifts and calibration are all relative to the boxes. The results
      file holds hundredths of a pixel, so the boxes agree to the two roundings' 0.005 each,
      the scaled file's 0.005 / k in the given image's pixels;
    - the detections' rows in another order within the file give the same results, row for
      row: the same boxes on the same frames under the same identities (the rows are read
      into an order of their own, by score and box: MOT17's FRCNN rows, sorted by score
      with ties at 1.0 in every frame, had the tracks a frame starts numbered in the file's
      order, and on MOT15's ACF detections, links of equal overlap went another way)."""
    import warnings

    from vistrack.pipeline import track_sequence

    from .mot_oracles import SHARED

    seq = SHARED / bench / name
    if not seq.exists():
        pytest.skip(f"{seq} not found: the shared data is not beside this checkout")
    lines = (seq / "det" / "det.txt").read_text().splitlines()
    info = (seq / "seqinfo.ini").read_text()

    def copy(tag, rows, k=1.0):
        d = tmp_path / tag
        (d / "det").mkdir(parents=True)
        (d / "det" / "det.txt").write_text("".join(r + "\n" for r in rows))
        (d / "seqinfo.ini").write_text(re.sub(
            r"(imWidth|imHeight)=(\d+)", lambda m: f"{m[1]}={int(int(m[2]) * k)}", info))
        return d

    def scaled(k):
        return [",".join(c[:2] + [repr(float(v) * k) for v in c[2:6]] + c[6:])
                for c in (r.split(",") for r in lines)]

    order = np.random.default_rng(0).permutation(len(lines))
    variants = {k: copy(f"x{k}", scaled(k), k) for k in (2.0, 0.5)}
    shuffled = copy("shuffled", [lines[i] for i in order])
    for offline in (False, True):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a lone class, camera notes
            want = read_mot(track_sequence(seq, tmp_path / f"as{offline}.txt",
                                           offline=offline).out)
            for k, d in variants.items():
                got = read_mot(track_sequence(d, tmp_path / f"x{k}{offline}.txt",
                                              offline=offline).out)
                np.testing.assert_array_equal(got.frames, want.frames)
                np.testing.assert_array_equal(got.ids, want.ids)
                np.testing.assert_allclose(got.boxes / k, want.boxes, rtol=0,
                                           atol=0.005 + 0.005 / k + 1e-9)
            got = read_mot(track_sequence(shuffled, tmp_path / f"sh{offline}.txt",
                                          offline=offline).out)
        assert len(got.frames) == len(want.frames) > 1000
        assert (tmp_path / f"sh{offline}.txt").read_text() == \
            (tmp_path / f"as{offline}.txt").read_text()


def test_a_detections_file_that_ends_long_before_the_video_is_warned_of(tmp_path):
    """Detections ending at frame 10 of a 40-frame video left frames 11-40 tracked with no
    detections, without a word. It is said where the file ends a second or more before the
    video, by more frames than its longest run without rows, and by so many that frames as
    often with rows as its own would have left none empty by chance below e^-10; not said:
    a file ending less than a second early (a video a frame longer than its file), or one
    whose rows stop for longer runs inside it (a scene that empties, as KITTI-13's does
    for 14 frames)."""
    import warnings

    import cv2

    from vistrack.pipeline import track_video

    folder = tmp_path / "frames"
    folder.mkdir()
    for k in range(40):
        cv2.imwrite(str(folder / f"{k + 1:06d}.png"), np.zeros((60, 200, 3), np.uint8))
    det = tmp_path / "det.txt"

    def rows(frames):
        return "".join(f"{f},-1,{10 + 50 * i + f},20,20,30,0.9,-1,-1,-1\n"
                       for f in frames for i in range(3))

    det.write_text(rows(range(1, 11)))
    with pytest.warns(UserWarning, match=re.escape(
            f"{det}: no rows after frame 10, where the video runs to frame 40: frames 11-40 "
            "were tracked without detections (100 % of the frames before have some; a file "
            "for a shorter video, or cut short?)")):
        track_video(folder, tmp_path / "a", frontend=f"detections:{det}", annotate=False,
                    fps=10)
    for name, frames in (("short", range(1, 36)),  # 0.5 s early
                         ("gappy", [*range(1, 5), *range(26, 31)])):  # 21 empty inside
        det.write_text(rows(frames))
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            track_video(folder, tmp_path / name, frontend=f"detections:{det}",
                        annotate=False, fps=10)
        assert not any("no rows after" in str(w.message) for w in seen), (name, seen)


@pytest.mark.parametrize("run, max_lost", [(50, 2.0), (55, 2.2), (60, 2.4), (54, 2.2)])
def test_a_run_without_rows_as_long_as_max_lost_is_not_undelivered(tmp_path, run, max_lost):
    """Frames not delivered are runs shorter than max_lost (docs/mot.md, Frame rate); at 25
    frames/s 2.2 s is 55.000000000000007 frames, whose ceiling took a run of exactly 55 for
    shorter. Oracle: the rule in whole frames (run < max_lost x 25)."""
    import warnings

    from vistrack.pipeline import track_sequence

    rows = [f"{f},-1,{100 + 150 * k},100,40,80,0.9" for f in
            [*range(1, 21), *range(21 + run, 21 + run + 20)] for k in range(6)]
    det = tmp_path / "det.txt"
    det.write_text("\n".join(rows) + "\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        track_sequence(det, tmp_path / "out.txt", fps=25.0, max_lost=max_lost)
    said = any("did not deliver" in str(w.message) for w in caught)
    assert said == (run < round(max_lost * 25)), [str(w.message) for w in caught]


def test_a_video_whose_header_disagrees_with_its_ground_truths_sequence_is_warned(tmp_path):
    """PETS09's vtest.avi says 10 frames/s in its header where the sequence is 7 (its
    seqinfo.ini, beside the ground truth given): tracked at 10 without a word. The oracle:
    the two files' own rates, said; none where they agree or ``fps`` is given."""
    import shutil
    import warnings

    from vistrack.pipeline import track_video

    data = ROOT / "src" / "vistrack" / "data" / "pets09-s2l1"
    video = data / "pets09-s2l1.mp4"  # (its header: 7 frames/s)
    for rate, fps, warned in ((10, None, True), (7, None, False), (10, 7.0, False)):
        seq = tmp_path / f"seq{rate}{fps}"
        (seq / "gt").mkdir(parents=True)
        shutil.copy(data / "gt.txt", seq / "gt" / "gt.txt")
        (seq / "seqinfo.ini").write_text(f"[Sequence]\nname=s\nframeRate={rate}\n"
                                         "seqLength=200\nimWidth=768\nimHeight=576\n")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            track_video(video, tmp_path / f"out{rate}{fps}", gt=seq, fps=fps, stop=3,
                        annotate=False)
        said = [str(w.message) for w in caught if "ground truth's sequence" in str(w.message)]
        assert said == ([f"{video}: its header gives 7 frames/s, and the ground truth's "
                         f"sequence 10 ({seq / 'seqinfo.ini'}): tracked at 7 (give the true "
                         "rate with --fps, or fps=)"] if warned else [])


def test_a_csv_file_of_detections_is_named_by_its_lines(tmp_path):
    """A CSV file's rows at fault were named by their frame alone ("big.csv, frame 2: a box
    ... beyond 2^52 pixels"), where a MOTChallenge text file's were named by their lines:
    its columns may lie in any order, so its rows were not looked for. They are now found by
    reading the file again, its columns named as for the run; the line counts blank lines,
    as an editor does. Oracle: the line written."""
    from vistrack.pipeline import track_sequence

    names = {"conf": "score", "frame": "t", "bb_left": "x", "bb_top": "y", "bb_width": "w",
             "bb_height": "h"}
    head = "h,score,w,t,y,x\n"

    def rows(*extra):  # frames 1-3 of a box, then the rows given, each (frame, x, w)
        body = [f"50,0.9,30,{f},10,{10 + f}" for f in (3, 1, 2)]
        return head + "\n".join(body + [f"50,0.8,{w},{f},10,{x}" for f, x, w in extra]) + "\n"

    big = tmp_path / "big.csv"
    big.write_text(rows((2, 1e100, 30)))
    with pytest.raises(ValueError, match=rf"^{big}, line 5: a box \(1e\+100, 10, 30, 50\) "
                                         "beyond 2\\^52 pixels"):
        track_sequence(big, tmp_path / "o.txt", fps=10, columns=names)
    huge = tmp_path / "huge.csv"
    huge.write_text(rows().replace("\n50,0.9,30,1,", "\n\n50,0.9,30,100000000000,"))
    with pytest.raises(ValueError, match=rf"^{huge}, line 4: frame 100000000000 is beyond"):
        track_sequence(huge, tmp_path / "o.txt", fps=10, columns=names)
    far = tmp_path / "far.csv"
    far.write_text(rows((100, 40, 30)))  # (96 frames without rows: 2.7 hours at 0.01/s)
    with pytest.warns(UserWarning, match=rf"^{far}, line 5: frame 100's rows come after"):
        track_sequence(far, tmp_path / "far.txt", fps=0.01, columns=names)
    # the first of two rows of one frame and box is the one named
    twice = tmp_path / "twice.csv"
    twice.write_text(rows((2, 7, 0), (2, 7, 0)))
    with pytest.warns(RuntimeWarning, match=rf"^{twice}, line 5: a box of zero width"):
        track_sequence(twice, tmp_path / "twice.txt", fps=10, columns=names, scores="raw")


def test_run_takes_its_sinks_from_any_iterable_and_names_one_given_alone():
    """A generator of sinks was used up by run's check of them, and its sinks were given no
    row, unsaid; one sink given without a list failed as "'TrackRows' object is not
    iterable". Oracle: the same sink given in a list."""
    from vistrack.io.tracks import TrackRows
    from vistrack.tracking import BoxTracker

    def frames():
        return [Frame(k, k / 10) for k in range(1, 6)]

    def det(frame):
        x = 10.0 + 2 * frame.index
        return Detections(boxes=np.array([[x, 10, x + 20, 50]]), scores=np.array([0.9]))

    listed, made = TrackRows(), TrackRows()
    run(frames(), det, BoxTracker(scores="raw"), [listed])
    run(frames(), det, BoxTracker(scores="raw"), (r for r in [made]))
    assert len(listed) > 0 and made.ids.tolist() == listed.ids.tolist()
    with pytest.raises(TypeError, match=re.escape("sinks must be a sequence of sinks; got one, "
                                                  "a TrackRows: give [sink]")):
        run(frames(), det, BoxTracker(scores="raw"), TrackRows())
    with pytest.raises(TypeError, match="sinks must be a sequence of sinks; got int"):
        run(frames(), det, BoxTracker(scores="raw"), 3)

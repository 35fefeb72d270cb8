"""Scoring positions rather than boxes (``zero_distance``): points such as a microscope's
particles, whose IoU is always 0. The oracle is TrackEval's own metrics run on its own
Euclidean similarity."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from vistrack.cli import main
from vistrack.evaluation import evaluate_files, evaluate_mot, point_similarity, sanity_warnings
from vistrack.io import MOTTable, read_mot

from .mot_oracles import seq_dir
from .test_mot_eval import compare


def _points(frames, ids, xy, path=""):
    """A table of points: rows of width and height 0 at ``xy``."""
    n = len(frames)
    return MOTTable.from_rows(np.c_[frames, ids, xy, np.zeros((n, 2)), np.ones(n),
                                    -np.ones(n), -np.ones(n)] if n else np.zeros((0, 9)), path)


def _walks(seed, n=12, frames=60):
    """``n`` particles on random walks (each present over a stretch of the frames), and
    predictions with every kind of error: positions off by up to about the threshold, rows
    missed, false points, an identity that changes part-way and two that swap."""
    rng = np.random.default_rng(seed)
    rows = []
    for pid in range(1, n + 1):
        a = int(rng.integers(1, frames // 2))
        b = int(rng.integers(a + 5, frames + 1))
        xy = rng.uniform(0, 100, 2) + np.cumsum(rng.normal(0, 1.5, (b - a + 1, 2)), 0)
        rows += [(f, pid, *p) for f, p in zip(range(a, b + 1), xy)]
    gt = np.array(rows, dtype=float)
    keep = rng.random(len(gt)) > 0.1
    pred = gt[keep].copy()
    pred[:, 2:4] += rng.normal(0, 1.2, (len(pred), 2))
    cut = pred[:, 0] > frames / 2
    pred[(pred[:, 1] == 3) & cut, 1] = 99  # a new identity half-way
    one, two = (pred[:, 1] == 5) & cut, (pred[:, 1] == 6) & cut
    pred[one, 1], pred[two, 1] = 6, 5  # two identities swap
    k = len(gt) // 8
    false = np.c_[rng.integers(1, frames + 1, k), 1000 + np.arange(k),
                  rng.uniform(0, 100, (k, 2))]
    pred = np.concatenate([pred, false])
    pred = pred[np.argsort(pred[:, 0], kind="stable")]
    return gt, pred


def _trackeval(gt, pred, n_frames, zero):
    """TrackEval's HOTA, CLEAR and Identity on positions, its similarity its
    ``_calculate_euclidean_similarity`` (arrays of frame, id, x, y)."""
    te = pytest.importorskip("trackeval")
    from trackeval.datasets._base_dataset import _BaseDataset

    ug, up = np.unique(gt[:, 1]), np.unique(pred[:, 1])
    data = {"num_timesteps": n_frames, "num_gt_ids": len(ug), "num_tracker_ids": len(up),
            "num_gt_dets": len(gt), "num_tracker_dets": len(pred),
            "gt_ids": [], "tracker_ids": [], "similarity_scores": []}
    for f in range(1, n_frames + 1):
        g, p = gt[gt[:, 0] == f], pred[pred[:, 0] == f]
        data["gt_ids"].append(np.searchsorted(ug, g[:, 1]))
        data["tracker_ids"].append(np.searchsorted(up, p[:, 1]))
        data["similarity_scores"].append(
            _BaseDataset._calculate_euclidean_similarity(g[:, 2:4], p[:, 2:4], zero))
    return {"HOTA": te.metrics.HOTA().eval_sequence(data),
            "CLEAR": te.metrics.CLEAR().eval_sequence(data),
            "Identity": te.metrics.Identity().eval_sequence(data)}


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("zero", [2.0, 5.0])
def test_points_score_as_trackeval_scores_them(seed, zero):
    """Every count and score of positions by distance equals TrackEval's, run on its own
    Euclidean similarity (the errors of each kind present)."""
    gt, pred = _walks(seed)
    ours = evaluate_mot(_points(gt[:, 0], gt[:, 1], gt[:, 2:4]),
                        _points(pred[:, 0], pred[:, 1], pred[:, 2:4]), 60, zero_distance=zero)
    assert ours.IDSW > 0 and ours.FP > 0 and ours.FN > 0 and 0 < ours.HOTA < 1
    compare(ours, _trackeval(gt, pred, 60, zero))


def test_box_centres_score_as_trackeval_scores_them_on_shared_ground_truth(tmp_path):
    """MOT15's KITTI-17 ground truth and the test suite's noisy predictions of it, scored by
    the distance between the boxes' centres (zero_distance 30 pixels): the same as TrackEval
    given the centres."""
    from .mot_oracles import noisy_predictions

    d = seq_dir("MOT15", "KITTI-17")
    gt = read_mot(d / "gt" / "gt.txt")
    pred = read_mot(noisy_predictions(d / "gt" / "gt.txt", tmp_path / "p.txt", seed=3))
    n = int(max(gt.frames.max(), pred.frames.max()))

    def centres(t):
        return np.c_[t.frames, t.ids, t.boxes[:, :2] + t.boxes[:, 2:] / 2]

    ours = evaluate_mot(gt, pred, n, benchmark="MOT15", zero_distance=30)
    assert ours.IDSW > 0 and ours.FP > 0 and (gt.conf == 0).any()
    # MOT15's convention: ground-truth rows of conf 0 are not scored (the predictions all are)
    compare(ours, _trackeval(centres(gt)[gt.conf != 0], centres(pred), n, 30))


def test_points_need_a_distance_and_a_distance_must_be_one():
    """Points scored by IoU would all be missed (IoU 0): an error naming zero_distance;
    a zero_distance that is not a number > 0 is named; boxes are scored by IoU as before,
    and by their centres with it."""
    gt, pred = _walks(0)
    g, p = _points(gt[:, 0], gt[:, 1], gt[:, 2:4], "gt.csv"), _points(pred[:, 0], pred[:, 1],
                                                                       pred[:, 2:4])
    with pytest.raises(ValueError, match=r"gt.csv: every row is a point \(no width or "
                                         r"height\), which no IoU can score: .*zero_distance="):
        evaluate_mot(g, p)
    for bad in (0, -1, float("nan"), float("inf"), "2", True):
        with pytest.raises(ValueError, match="zero_distance must be a finite number > 0"):
            evaluate_mot(g, p, zero_distance=bad)
    box = MOTTable.from_rows([(1, 1, 0, 0, 10, 10), (2, 1, 30, 0, 10, 10)])
    assert evaluate_mot(box, box).TP == 2
    far = MOTTable.from_rows([(1, 1, 3, 4, 10, 10), (2, 1, 33, 4, 10, 10)])  # centres 5 away
    assert evaluate_mot(box, far).TP == 0  # IoU 0.47
    assert evaluate_mot(box, far, zero_distance=10).TP == 2  # at similarity 0.5
    assert evaluate_mot(box, far, zero_distance=9.9).TP == 0
    np.testing.assert_allclose(point_similarity([[0, 0, 10, 10]], [[3, 4, 10, 10]], 10), 0.5)


def test_positions_near_the_largest_float_are_scored_without_overflow():
    """A finite box whose centre passes the largest float (left 1.7e308, width 1e308) gave a
    NaN similarity, and ``vistrack eval --zero-distance`` stopped in SciPy's assignment
    ("matrix contains invalid numeric entries"), naming nothing. Oracle: the same row is at
    distance 0 from itself (similarity 1); rows 3e308 apart are as far as can be (0)."""
    b = [1.7e308, 0, 1.0e308, 10]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_array_equal(point_similarity([b], [b], 10), [[1.0]])
        np.testing.assert_array_equal(point_similarity([b], [[-1.7e308, 0, 0, 10]], 10), [[0.0]])
        np.testing.assert_array_equal(point_similarity([[1e200, 0, 0, 0]], [[0, 0, 0, 0]],
                                                       1e-300), [[0.0]])
        t = MOTTable.from_rows([(1, 1, *b)])
        c = evaluate_mot(t, t, zero_distance=10)
    assert (c.TP, c.FP, c.FN, c.MOTA) == (1, 0, 0, 1.0)


def test_a_points_csv_reads_as_points_where_asked_and_a_half_box_is_named():
    """trackpy's columns (frame, particle, x, y) read as points, rows of width and height 0,
    where they are to be scored by distance (``points=True``); otherwise they are no box, as
    before (a table's size may be in columns of other names), the error now saying what
    reads them. A box's centre with one of its width and height is refused naming the
    other; corners beside x, y are still the box."""
    rows = {"frame": [1, 2], "particle": [4, 4], "x": [10.5, 11.0], "y": [3.0, 3.5]}
    t = MOTTable.from_pandas(rows, points=True)
    assert t.boxes.tolist() == [[10.5, 3.0, 0.0, 0.0], [11.0, 3.5, 0.0, 0.0]]
    assert t.ids.tolist() == [4, 4]
    with pytest.raises(ValueError, match=r"no box in p.csv: .*; x, y alone are points, scored "
                                         r"by distance with vistrack eval --zero-distance PX"):
        MOTTable.from_pandas(rows, path="p.csv")
    sized = dict(rows, w=[2.0, 2.0], h=[4.0, 4.0])  # a size the reader does not know by name
    with pytest.raises(ValueError, match="no box in p.csv"):
        MOTTable.from_pandas(sized, path="p.csv")
    with pytest.raises(ValueError, match=r"no column 'bb_height' in p.csv \(x, y are a box's "
                                         r"centre with 'bb_width' and 'bb_height', or a point "
                                         r"with neither\)"):
        MOTTable.from_pandas({"frame": [1], "x": [1.0], "y": [1.0], "bb_width": [2.0]},
                             path="p.csv")
    both = MOTTable.from_pandas({"frame": [1], "x": [9.0], "y": [9.0], "x1": [0.0],
                                 "y1": [0.0], "x2": [4.0], "y2": [2.0]})
    assert both.boxes.tolist() == [[0.0, 0.0, 4.0, 2.0]]


def test_ground_truth_files_read_as_before_and_as_csv(tmp_path, capsys):
    """MOTChallenge's text named .csv (no header) is still read as such for ground truth;
    a CSV of boxes with a header is read as ground truth by vistrack eval and by vistrack
    track --gt alike; a detections CSV of x, y alone is still no box to the box trackers."""
    from vistrack.evaluation.files import read_truth
    from vistrack.io import write_mot
    from vistrack.pipeline import track_sequence

    rows = [(f, 1, 10.0 + 2 * f, 20.0, 30.0, 60.0) for f in range(1, 6)]
    text = write_mot(tmp_path / "gt.txt", *zip(*[(f, i, (x, y, w, h))
                                                 for f, i, x, y, w, h in rows]))
    named = tmp_path / "gt_mot.csv"
    named.write_bytes(text.read_bytes())
    table = read_truth(named)
    assert table.boxes.tolist() == read_mot(text).boxes.tolist()
    boxes = tmp_path / "truth.csv"
    boxes.write_text("frame,id,bb_left,bb_top,bb_width,bb_height\n" + "".join(
        f"{f},{i},{x},{y},{w},{h}\n" for f, i, x, y, w, h in rows))
    assert read_truth(boxes).boxes.tolist() == table.boxes.tolist()
    for gt in (named, boxes):
        assert main(["eval", "--gt", str(gt), "--pred", str(text), "--json"]) == 0
        assert '"MOTA": 1.0' in capsys.readouterr().out
    from vistrack.pipeline import _ground_truth

    assert _ground_truth(boxes).boxes.tolist() == table.boxes.tolist()  # (vistrack track --gt)
    det = tmp_path / "pts.csv"
    det.write_text("frame,x,y,conf\n1,10,10,0.9\n2,11,10,0.9\n")
    with pytest.raises(ValueError, match="no box in .*pts.csv"):
        track_sequence(det, tmp_path / "out.txt", fps=10)


def test_vistrack_eval_scores_points_files(tmp_path, capsys):
    """``vistrack eval --gt truth.csv --pred tracks.csv --zero-distance PX``: both files of
    trackpy's columns (the tracks.csv of --frontend spots), scored as evaluate_mot scores
    them; without the option the error names it, and a distance that is not > 0 is refused.
    Predictions far from every point are warned of as unrelated, in the words of points."""
    gt, pred = _walks(1)

    def write(path, rows):
        path.write_text("frame,particle,x,y\n" + "".join(
            f"{int(f)},{int(i)},{float(x)!r},{float(y)!r}\n" for f, i, x, y in rows))
        return path

    truth, tracks = write(tmp_path / "truth.csv", gt), write(tmp_path / "tracks.csv", pred)
    assert main(["eval", "--gt", str(truth), "--pred", str(tracks), "--zero-distance", "4",
                 "--json"]) == 0
    import json

    got = json.loads(capsys.readouterr().out)["truth"]
    want = evaluate_mot(_points(gt[:, 0], gt[:, 1], gt[:, 2:4]),
                        _points(pred[:, 0], pred[:, 1], pred[:, 2:4]), zero_distance=4)
    assert got == json.loads(json.dumps(want.summary()))
    assert main(["eval", "--gt", str(truth), "--pred", str(tracks)]) == 2
    assert "x, y alone are points, scored by distance with vistrack eval --zero-distance PX" \
        in capsys.readouterr().err
    assert main(["eval", "--gt", str(truth), "--pred", str(tracks), "--zero-distance",
                 "0"]) == 2
    assert "--zero-distance must be a finite distance > 0" in capsys.readouterr().err
    far = pred.copy()
    far[:, 2:4] += 500
    res = evaluate_files([("s", truth, write(tmp_path / "far.csv", far), None)],
                         zero_distance=4)
    assert res.warnings == [
        f"predictions and ground truth look unrelated: no position of {tmp_path / 'far.csv'} "
        f"lies within 2 of a position of {truth} in any of their "
        f"{len(np.intersect1d(gt[:, 0], far[:, 0]))} common frames"]
    assert sanity_warnings(_points(gt[:, 0], gt[:, 1], gt[:, 2:4]),
                           _points(pred[:, 0], pred[:, 1], pred[:, 2:4]),
                           zero_distance=4) == []


def test_the_hota_plot_of_points_says_what_its_threshold_is_on():
    """HOTA's α over positions scored by distance is a threshold on ``1 - d / PX``, not on
    an IoU: the plot's axis said IoU whatever was scored."""
    from vistrack.viz.plots import plot_hota_alpha

    gt, pred = _walks(2)
    res = {"s": evaluate_mot(_points(gt[:, 0], gt[:, 1], gt[:, 2:4]),
                             _points(pred[:, 0], pred[:, 1], pred[:, 2:4]), zero_distance=4)}
    assert {ax.get_xlabel() for ax in plot_hota_alpha(res, zero_distance=4).axes} == {
        "localisation threshold α (1 - distance / 4)"}
    assert {ax.get_xlabel() for ax in plot_hota_alpha(res).axes} == {
        "localisation threshold α (IoU)"}


def test_a_box_run_scored_by_distance_says_so_to_its_report(tmp_path):
    """``vistrack track VIDEO --gt GT --zero-distance 40``: the boxes are scored by their
    centres' distance, run.json records the distance, and the report's plots use it (they
    scored by IoU whatever the run had printed)."""
    import json

    from vistrack.data import demo_clip
    from vistrack.report import _gt_plots

    clip = demo_clip()
    run = main(["track", str(clip.video), "--out-dir", str(tmp_path / "o"), "--gt",
                str(clip.gt), "--stop", "20", "--zero-distance", "40", "--report", "--quiet"])
    assert run == 0
    info = json.loads((tmp_path / "o" / "run.json").read_text())
    assert info["zero_distance"] == 40
    gt = read_mot(clip.gt)
    pred = read_mot(tmp_path / "o" / "tracks.txt")
    want = evaluate_mot(gt[gt.frames <= 20], pred, 20, zero_distance=40)
    assert info["scores"] == json.loads(json.dumps(want.summary()))
    assert want.summary() != evaluate_mot(gt[gt.frames <= 20], pred, 20).summary()
    assert len(_gt_plots(tmp_path / "o" / "tracks.txt", "clip", info)) == 2
    assert (tmp_path / "o" / "report.html").stat().st_size > 0


def test_the_similarities_refuse_rows_that_are_not_boxes_and_a_bad_zero_distance():
    """``reshape(-1, 4)`` read a transposed (4, N) array, or a VOT polygon's 8 values a row,
    as other boxes, without a word (the IoU of three boxes with themselves, transposed, was
    not the identity), and an empty (3, 0) or (0, 5) as no boxes; ``point_similarity`` took
    a zero distance of 0 (all 0, numpy's divide warning), -5 (similarities of 1.2) or NaN.
    The oracle for the good cases: the IoU of boxes with themselves is the identity, one
    row (4,) is one box, nothing is nothing."""
    from vistrack.evaluation import box_iou_xywh

    gt = np.array([[0.0, 0, 10, 10], [20, 20, 10, 10], [50, 0, 10, 10]])
    np.testing.assert_array_equal(box_iou_xywh(gt, gt), np.eye(3))
    for fn in (box_iou_xywh, lambda a, b: point_similarity(a, b, 10.0)):
        for a, shape in ((gt.T, "(4, 3)"), ([[0, 0, 1]], "(1, 3)"),
                         ([[0, 0, 4, 0, 4, 2, 0, 2]], "(1, 8)"), (np.zeros((1, 2, 4)),
                                                                 "(1, 2, 4)"),
                         (np.zeros((3, 0)), "(3, 0)"), (np.zeros((0, 5)), "(0, 5)")):
            with pytest.raises(ValueError, match=re.escape(
                    f"a must be rows (N, 4) of left, top, width, height; got shape {shape}")):
                fn(a, gt)
        assert fn(gt[0], gt).shape == (1, 3) and fn([], gt).shape == (0, 3)
        assert fn(gt, np.zeros((0, 4))).shape == (3, 0)
    from vistrack.types import xyxy_to_xywh

    with pytest.raises(ValueError, match=re.escape("boxes must be rows (N, 4) of x0, y0, x1, "
                                                   "y1; got shape (4, 3)")):
        xyxy_to_xywh(gt.T)
    assert xyxy_to_xywh(gt[0]).shape == (1, 4) and xyxy_to_xywh([]).shape == (0, 4)
    for bad in (0, -5, np.nan, np.inf, True):
        with pytest.raises(ValueError, match=re.escape(
                f"zero_distance must be a finite number > 0 (the distance at which a pair's "
                f"similarity falls to 0); got {bad!r}")):
            point_similarity([[0, 0, 0, 0]], [[1, 0, 0, 0]], bad)

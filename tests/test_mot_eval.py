"""CLEAR MOT, IDF1 and HOTA against TrackEval (the official MOTChallenge scorer) and
py-motmetrics, on the real MOT15 and MOT17 ground truth with predictions that carry every kind
of error; and the scores' definitions on small cases worked by hand."""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys

import numpy as np
import pytest

from vistrack.evaluation import ALPHAS, MOTCounts, box_iou_xywh, combine, evaluate_mot
from vistrack.io import MOTTable, read_mot

from .mot_oracles import MOT15, MOT17, n_frames, noisy_predictions, seq_dir, trackeval_scores

CLEAR = {"TP": "CLR_TP", "FN": "CLR_FN", "FP": "CLR_FP", "IDSW": "IDSW", "Frag": "Frag",
         "MT": "MT", "PT": "PT", "ML": "ML"}
IDENTITY = ("IDTP", "IDFN", "IDFP")


def compare(ours: MOTCounts, ref: dict) -> None:
    for k, r in CLEAR.items():
        assert getattr(ours, k) == ref["CLEAR"][r], k
    assert ours.MOTA == pytest.approx(ref["CLEAR"]["MOTA"], abs=1e-12)
    assert ours.MOTP == pytest.approx(ref["CLEAR"]["MOTP"], abs=1e-12)
    for k in IDENTITY:
        assert getattr(ours, k) == ref["Identity"][k], k
    for k in ("IDF1", "IDP", "IDR"):
        assert getattr(ours, k) == pytest.approx(ref["Identity"][k], abs=1e-12), k
    h = ref["HOTA"]
    for k in ("HOTA_TP", "HOTA_FN", "HOTA_FP"):
        np.testing.assert_array_equal(getattr(ours, k), h[k], err_msg=k)
    for k in ("HOTA", "DetA", "AssA", "LocA", "AssRe", "AssPr"):
        np.testing.assert_allclose(getattr(ours, f"{k}_alpha"), h[k], rtol=1e-10, atol=1e-12,
                                   err_msg=k)
    for k in ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr"):
        assert getattr(ours, k) == pytest.approx(float(np.mean(h[k])), rel=1e-10, abs=1e-12), k


def run_against_trackeval(bench, names, tmp_path):
    seqs = {n: seq_dir(bench, n) for n in names}
    preds = {n: noisy_predictions(d / "gt" / "gt.txt", tmp_path / "pred" / f"{n}.txt", seed=i)
             for i, (n, d) in enumerate(seqs.items())}
    ref = trackeval_scores(bench, seqs, preds, tmp_path / "te")
    ours = {n: evaluate_mot(read_mot(d / "gt" / "gt.txt"), read_mot(preds[n]), n_frames(d),
                            benchmark=bench) for n, d in seqs.items()}
    for n in names:
        compare(ours[n], ref[n])
    compare(combine(ours.values()), ref["COMBINED_SEQ"])
    return ours


def test_equals_trackeval_on_mot15(tmp_path):
    ours = run_against_trackeval("MOT15", ["KITTI-17", "ETH-Sunnyday"], tmp_path)
    assert all(c.IDSW > 0 and c.FP > 0 and c.FN > 0 for c in ours.values())


def test_equals_trackeval_on_mot17_with_distractors(tmp_path):
    ours = run_against_trackeval("MOT17", ["MOT17-09-FRCNN", "MOT17-05-FRCNN"], tmp_path)
    d = seq_dir("MOT17", "MOT17-09-FRCNN")
    gt = read_mot(d / "gt" / "gt.txt")
    # the ground truth kept is pedestrians to consider only; the rest are not counted
    assert ours["MOT17-09-FRCNN"].gt_dets == int(np.sum((gt.classes == 1) & (gt.conf != 0)))
    # "auto" picks the MOT17 preprocessing from the classes in the file
    auto = evaluate_mot(gt, read_mot(tmp_path / "pred" / "MOT17-09-FRCNN.txt"), n_frames(d))
    assert auto.summary() == ours["MOT17-09-FRCNN"].summary()


@pytest.mark.slow
@pytest.mark.parametrize("bench", ["MOT15", "MOT17"])
def test_equals_trackeval_on_every_sequence(bench, tmp_path):
    run_against_trackeval(bench, MOT15 if bench == "MOT15" else MOT17, tmp_path)


def table(frames, ids, x, w=10.0):
    n = len(frames)
    return MOTTable(np.asarray(frames), np.asarray(ids),
                    np.c_[np.asarray(x, float), np.zeros(n), np.full(n, w), np.full(n, w)],
                    np.ones(n), -np.ones(n, int), -np.ones(n))


def test_hand_worked_cases():
    # one object over 4 frames; the prediction is right but changes id in frame 3
    gt = table([1, 2, 3, 4], [1, 1, 1, 1], [0, 1, 2, 3])
    c = evaluate_mot(gt, table([1, 2, 3, 4], [7, 7, 8, 8], [0, 1, 2, 3]))
    assert (c.TP, c.FP, c.FN, c.IDSW) == (4, 0, 0, 1)
    assert c.MOTA == 0.75 and c.MOTP == 1.0
    assert (c.IDTP, c.IDFP, c.IDFN) == (2, 2, 2) and c.IDF1 == 0.5
    # every alpha matches all 4 (IoU 1); the association is half: AssA = 2/4 * ... by hand:
    # pairs (1,7) and (1,8) each matched twice: A(c) = 2 / (4 + 2 - 2) = 0.5 for each match
    np.testing.assert_allclose(c.AssA_alpha, 0.5)
    assert c.DetA == 1.0 and c.HOTA == pytest.approx(np.sqrt(0.5))
    # shifted by half a box: IoU = 5*10 / (200 - 50) = 1/3, below 0.5: all missed for CLEAR
    c = evaluate_mot(gt, table([1, 2, 3, 4], [7, 7, 7, 7], np.array([0, 1, 2, 3]) + 5))
    assert (c.TP, c.FP, c.FN) == (0, 4, 4) and c.MOTA == -1.0
    # ... but matched by HOTA at every alpha up to 1/3
    assert np.all(c.HOTA_TP[ALPHAS <= 1 / 3] == 4) and np.all(c.HOTA_TP[ALPHAS > 1 / 3] == 0)
    assert c.LocA_alpha[0] == pytest.approx(1 / 3)


def test_sum_equals_combine():
    """sum() starts from 0; the total must be combine's, field by field, bit for bit."""
    rng = np.random.default_rng(3)
    counts = []
    for k in range(3):
        frames = np.repeat(np.arange(1, 21), 3)
        ids = np.tile([1, 2, 3], 20)
        x = ids * 30.0 + rng.normal(0, 1, len(ids))
        keep = rng.random(len(ids)) < 0.8
        pid = np.where(frames > 10 + k, ids + 10, ids)  # an identity switch halfway
        gt = table(frames, ids, x)
        pred = table(frames[keep], pid[keep], x[keep] + rng.normal(0, 3, keep.sum()))
        counts.append(evaluate_mot(gt, pred))
    for part in (counts[:1], counts[:2], counts):
        total, ref = sum(part), combine(part)
        assert isinstance(total, MOTCounts)
        for f in dataclasses.fields(MOTCounts):
            np.testing.assert_array_equal(getattr(total, f.name), getattr(ref, f.name),
                                          err_msg=f.name)
    assert sum(counts).HOTA == combine(counts).HOTA and sum(counts).IDSW > 0
    with pytest.raises(TypeError):
        1 + counts[0]  # only sum()'s start value 0 is an empty MOTCounts


def test_bad_inputs_are_named():
    gt = table([1, 1], [1, 1], [0, 50])
    with pytest.raises(ValueError, match="id 1 appears more than once in frame 1"):
        evaluate_mot(gt, table([1], [1], [0]))
    with pytest.raises(ValueError, match="frame 9 is beyond the sequence's 4 frames"):
        evaluate_mot(table([1], [1], [0]), table([9], [1], [0]), n_frames=4)
    with pytest.raises(ValueError, match="benchmark must be"):
        evaluate_mot(table([1], [1], [0]), table([1], [1], [0]), benchmark="KITTI")



def test_a_frame_before_the_first_is_named_not_dropped():
    """A table built in Python (read_mot refuses it) with a row of frame 0, as a tracker that
    counts frames from 0 writes: it used to be left out of the scores without a word, and a
    wrong box there scored as perfect."""
    gt = MOTTable.from_rows([(0, 1, 0, 0, 10, 10), (1, 1, 0, 0, 10, 10)])
    good = MOTTable.from_rows([(1, 1, 0, 0, 10, 10)])
    with pytest.raises(ValueError) as e:
        evaluate_mot(gt, good)
    assert str(e.value) == ("ground truth: frame 0 is before the first (MOTChallenge frames "
                            "count from 1)")
    with pytest.raises(ValueError) as e:
        evaluate_mot(good, MOTTable.from_rows([(-2, 1, 500, 0, 10, 10), (1, 1, 0, 0, 10, 10)]))
    assert str(e.value) == ("prediction: frame -2 is before the first (MOTChallenge frames "
                            "count from 1)")
    assert evaluate_mot(good, good).MOTA == 1.0
    # n_frames of NaN was "cannot convert float NaN to integer", 2.5 frame 2
    for n in (np.nan, 2.5, -1):
        with pytest.raises(ValueError, match=f"n_frames must be a whole number >= 0; got {n}"):
            evaluate_mot(good, good, n_frames=n)


def test_two_pairs_of_one_name_are_refused(tmp_path):
    """evaluate_files keys its results by name: a second pair of a name, or a pair named
    COMBINED, would replace a sequence's scores with another's."""
    from vistrack.evaluation import evaluate_files

    g = tmp_path / "gt.txt"
    g.write_text("1,1,0,0,10,10,1,1,1\n")
    with pytest.raises(ValueError) as e:
        evaluate_files([("seq", g, g, None), ("other", g, g, None), (1, g, g, None),
                        ("1", g, g, None)])
    assert str(e.value) == ("pairs[2] and pairs[3] are both named '1': each pair needs a name "
                            "of its own")
    with pytest.raises(ValueError) as e:
        evaluate_files([("seq", g, g, None), ("COMBINED", g, g, None)])
    assert str(e.value) == (f"pairs[1] ({g}) is named 'COMBINED', the name of the sum of "
                            "all: give its sequence another name")
    # one pair alone has no sum: its name is its own (a sequence folder named COMBINED was
    # refused in words about pairs[0])
    alone = evaluate_files([("COMBINED", g, g, None)])
    assert list(alone) == ["COMBINED"] and alone["COMBINED"].MOTA == 1.0
    assert sorted(evaluate_files([("a", g, g, None), ("b", g, g, None)])) == ["COMBINED", "a",
                                                                               "b"]


def test_pairs_of_any_iterable_and_arguments_named(tmp_path):
    """A zip or a generator of pairs is scored as the list is (the checks used it up: an
    empty result, as if there were no pairs); an argument of the wrong kind is named."""
    from vistrack.evaluation import evaluate_files
    from vistrack.evaluation.files import pair_matches

    g = tmp_path / "gt.txt"
    g.write_text("1,1,0,0,10,10,1,1,1\n2,1,1,0,10,10,1,1,1\n")
    listed = evaluate_files([("a", g, g, None), ("b", g, g, None)])
    for pairs in (zip("ab", [g, g], [g, g], [None, None]),
                  ((n, g, g, None) for n in "ab")):
        got = evaluate_files(pairs)
        assert sorted(got) == ["COMBINED", "a", "b"]
        assert got["COMBINED"].TP == listed["COMBINED"].TP == 4
    with pytest.raises(TypeError, match="jobs"):
        evaluate_files([("a", g, g, None)], jobs="2")
    with pytest.raises(ValueError, match=r"jobs must be a whole number >= 1; got 3\.5"):
        evaluate_files([("a", g, g, None)], jobs=3.5)
    with pytest.raises(TypeError, match="n_frames"):
        evaluate_mot(read_mot(g), read_mot(g), "3")
    with pytest.raises(ValueError, match=re.escape("a pair is a (name, gt, results, seqinfo "
                                                   "or None) tuple; pair is ('a', ")):
        pair_matches(("a", g, g))
    with pytest.raises(TypeError, match="MOTCounts"):
        MOTCounts() + 1


def test_a_fractional_class_of_a_table_made_by_hand_is_named_as_it_is():
    """(it was named class 1, which is one)"""
    g = MOTTable.from_rows([(1, 1, 0, 0, 10, 10, 1, 1, 1), (2, 1, 0, 0, 10, 10, 1, 1, 1)])
    table = MOTTable(g.frames, g.ids, g.boxes, g.conf, np.array([1.5, 1.0]), g.visibility, "",
                     9)
    with pytest.raises(ValueError, match=re.escape("ground truth: class 1.5 is not a MOT17 "
                                                   "class (1-13)")):
        evaluate_mot(table, g, benchmark="MOT17")


def motmetrics_summary(gt_path, pred_path):
    if not hasattr(np, "asfarray"):  # py-motmetrics 1.4 still calls np.asfarray (numpy < 2)
        np.asfarray = lambda a, dtype=float: np.asarray(a, dtype=dtype)  # noqa: NPY201 (the shim)
    mm = pytest.importorskip("motmetrics")
    gt = mm.io.loadtxt(str(gt_path), fmt="mot15-2D", min_confidence=1)
    ts = mm.io.loadtxt(str(pred_path), fmt="mot15-2D")
    acc = mm.utils.compare_to_groundtruth(gt, ts, "iou", distth=0.5)
    names = ["idf1", "idp", "idr", "num_false_positives", "num_misses", "num_switches",
             "num_matches"]
    return mm.metrics.create().compute(acc, metrics=names, name="s").iloc[0]


@pytest.mark.parametrize("name", ["KITTI-17", "ETH-Sunnyday", "ADL-Rundle-6"])
def test_identity_scores_equal_py_motmetrics(name, tmp_path):
    """IDF1, IDP and IDR equal py-motmetrics'. Its CLEAR matching prefers each object's last
    pair however long ago, where TrackEval prefers only the previous frame's pairs, so its
    counts may differ a little (on ADL-Rundle-6 here: FP 468 against 470, ID switches 12
    against 24); vistrack follows TrackEval, the official scorer."""
    d = seq_dir("MOT15", name)
    pred = noisy_predictions(d / "gt" / "gt.txt", tmp_path / "p.txt", seed=0)
    ours = evaluate_mot(read_mot(d / "gt" / "gt.txt"), read_mot(pred), n_frames(d))
    ref = motmetrics_summary(d / "gt" / "gt.txt", pred)
    for k in ("IDF1", "IDP", "IDR"):
        assert getattr(ours, k) == pytest.approx(ref[k.lower()], abs=1e-12), k
    assert abs(ours.FP - ref.num_false_positives) <= 0.01 * ours.FP
    assert abs(ours.FN - ref.num_misses) <= 0.01 * ours.FN
    # motmetrics counts a switch as a match of its own: TP = matches + switches
    assert abs(ours.TP - (ref.num_matches + ref.num_switches)) <= 0.01 * ours.TP


@pytest.mark.parametrize("bench,name", [("MOT15", "ADL-Rundle-6"), ("MOT17", "MOT17-09-FRCNN")])
def test_the_matches_frame_by_frame_are_the_counts(bench, name, tmp_path):
    """clear_matches gives the rows behind evaluate_mot's CLEAR counts (themselves equal to
    TrackEval's): matched rows are TP, the others FN, switches IDSW, and MT, PT and ML
    recomputed from the rows as their definitions say (Frag depends also on the frames
    where an object is absent, which the rows do not hold); each match overlaps at IoU
    >= 0.5."""
    from vistrack.evaluation import clear_matches

    d = seq_dir(bench, name)
    gt = read_mot(d / "gt" / "gt.txt")
    pred = read_mot(noisy_predictions(d / "gt" / "gt.txt", tmp_path / "p.txt", seed=1))
    c = evaluate_mot(gt, pred, n_frames(d), benchmark=bench)
    m = clear_matches(gt, pred, n_frames(d), benchmark=bench)
    hit = m.matched
    assert (int(hit.sum()), int((~hit).sum()), int(m.switches.sum())) == (c.TP, c.FN, c.IDSW)
    assert not (m.switches & ~hit).any() and np.all(np.diff(m.frames) >= 0)
    mt = pt = ml = 0
    for obj in np.unique(m.gt_ids):
        ratio = hit[m.gt_ids == obj].mean()
        mt += ratio > 0.8
        pt += 0.2 <= ratio <= 0.8
        ml += ratio < 0.2
    assert (mt, pt, ml) == (c.MT, c.PT, c.ML)
    # each matched pair: the object's box and the track's box that frame overlap enough
    gk = {(f, i): b for f, i, b in zip(gt.frames, gt.ids, gt.boxes)}
    pk = {(f, i): b for f, i, b in zip(pred.frames, pred.ids, pred.boxes)}
    a = np.array([gk[f, g] for f, g in zip(m.frames[hit], m.gt_ids[hit])])
    b = np.array([pk[f, p] for f, p in zip(m.frames[hit], m.pred_ids[hit])])
    iou = np.array([box_iou_xywh(x[None], y[None])[0, 0] for x, y in zip(a, b)])
    assert iou.min() >= 0.5 - 1e-9


def test_unsorted_tables_are_refused():
    gt = table([2, 1], [1, 1], [0, 0])
    with pytest.raises(ValueError, match="rows must be sorted by frame"):
        evaluate_mot(gt, table([1], [1], [0]))


# ------------------------------------------------- huge numbers, long sequences, bad rows


def _exact_iou(a, b):
    """IoU in exact rational arithmetic: no rounding, no overflow."""
    from fractions import Fraction

    (ax, ay, aw, ah), (bx, by, bw, bh) = (map(Fraction, map(float, box)) for box in (a, b))
    iw = max(Fraction(0), min(ax + aw, bx + bw) - max(ax, bx))
    ih = max(Fraction(0), min(ay + ah, by + bh) - max(ay, by))
    union = aw * ah + bw * bh - iw * ih
    return float(iw * ih / union) if union > 0 else 0.0


def test_iou_of_huge_boxes_is_exact_and_in_range():
    """Boxes up to 1e308: the IoU of exact arithmetic (it was NaN once a right edge or an area
    overflowed, and evaluate_mot failed in scipy with "matrix contains invalid numeric
    entries")."""
    import warnings

    rng = np.random.default_rng(5)
    a = np.c_[rng.uniform(-50, 50, (40, 2)), rng.uniform(1, 60, (40, 2))]
    b = a[rng.permutation(40)] + rng.normal(0, 5, (40, 4)) * [1, 1, 0, 0]
    b[:10] = a[:10] + rng.normal(0, 2, (10, 4)) * [1, 1, 0.1, 0.1]  # overlapping pairs
    exact = np.array([[_exact_iou(p, q) for q in b] for p in a])
    small = box_iou_xywh(a, b)
    # rounding in the corners' differences: at most a few ulp of the coordinates (~100)
    np.testing.assert_allclose(small, exact, rtol=0, atol=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow warning either
        for exponent in (400, 900, 1016):  # 2**1016 * 60: near the largest float
            # a power of two scales every sum and product exactly: the same IoU, bit for bit
            iou = box_iou_xywh(np.ldexp(a, exponent), np.ldexp(b, exponent))
            assert (iou == small).all() and (iou[:10].diagonal() > 0).all()
        mixed = [[1e308, 0, 1e308, 10], [0, 0, 1e308, 1e308], [0, 0, 10, 10],
                 [-1e308, 5, 3e307, 1], [-1.1e308, 5.5, 5e307, 2]]
        iou = box_iou_xywh(mixed, mixed)
    exact = np.array([[_exact_iou(p, q) for q in mixed] for p in mixed])
    # (a right edge x + w is rounded, as any sum of floats: a few ulp of x)
    np.testing.assert_allclose(iou, exact, rtol=1e-14, atol=1e-300)
    assert iou[3, 4] > 0.1 and (iou.diagonal() == 1.0).all()


def test_huge_boxes_score_as_their_scaled_down_copies(tmp_path):
    from vistrack.evaluation import evaluate_files

    rng = np.random.default_rng(6)
    frames, ids = np.repeat(np.arange(1, 6), 3), np.tile([1, 2, 3], 5)
    x = ids * 30.0 + rng.normal(0, 1, 15)
    gt, res = table(frames, ids, x), table(frames, np.where(frames > 3, ids + 5, ids),
                                           x + rng.normal(0, 3, 15))
    small = evaluate_mot(gt, res).summary()
    for exponent in (600, 1000):
        def big(t, exponent=exponent):
            return MOTTable(t.frames, t.ids, np.ldexp(t.boxes, exponent), t.conf, t.classes,
                            t.visibility)
        assert evaluate_mot(big(gt), big(res)).summary() == small
    # the case, through the files: a right edge of 2e308 (inf in floats)
    f = _rows(tmp_path / "gt.txt", [(1, 1, "1e308", 0, "1e308", 10, 1, -1, -1, -1)])
    c = evaluate_files([("s", f, f, None)])["s"]
    assert (c.TP, c.FP, c.FN, c.MOTP, c.HOTA) == (1, 0, 0, 1.0, 1.0)


def test_frame_numbers_near_2_to_53_need_no_memory_per_frame():
    """A sequence as long as its last frame number (no seqinfo.ini): the frames without rows
    cost nothing (a table of every frame up to 2**53 was a MemoryError)."""
    last = 2 ** 53
    gt = table([1, 2, last], [1, 1, 1], [0, 1, 5])
    c = evaluate_mot(gt, table([1, 2, last], [4, 4, 4], [0, 1, 5]))
    assert c.frames == last and (c.TP, c.FP, c.FN, c.IDSW) == (3, 0, 0, 0) and c.HOTA == 1.0
    c = evaluate_mot(gt, table([1, 2, last - 1], [4, 4, 4], [0, 1, 5]), n_frames=last)
    assert (c.TP, c.FP, c.FN, c.frames) == (2, 1, 1, last)


def test_ids_far_apart_are_not_taken_for_twins():
    """Ids from -2**52 to 2**52: (frame, id) pairs were once packed into one int64, which
    overflowed and made two different pairs equal."""
    m = 2 ** 52
    t = table([1, 2049, 2049], [-m + 2048, -m, m], [0, 0, 50])
    c = evaluate_mot(t, t)
    assert (c.TP, c.FP, c.FN, c.IDSW) == (3, 0, 0, 0)
    twins = table([1, 2049, 2049, 2049], [-m + 2048, -m, m, -m], [0, 0, 50, 90])
    with pytest.raises(ValueError, match=f"^prediction: id {-m} appears more than once in "
                                         "frame 2049$"):
        evaluate_mot(t, twins)


def test_a_bad_row_found_while_scoring_is_named_by_its_line(tmp_path):
    """An id twice in a frame, a frame past seqinfo.ini's length, a class out of range: the
    file and the line(s), counted as read_mot counts them (blank and comment lines too, in the
    file's order, not the frames')."""
    from vistrack.evaluation import evaluate_files

    gt = tmp_path / "gt.txt"
    gt.write_text("2,1,0,0,10,10,1,1,1\n\n1,1,0,0,10,10,1,1,1\n# a comment\n"
                  "2,2,20,0,10,10,1,1,1\n2,1,5,0,10,10,1,1,1\n")
    ok = _rows(tmp_path / "ok.txt", [(1, 1, 0, 0, 10, 10, 1, 1, 1), (3, 1, 0, 0, 10, 10, 1, 14,
                                                                     1)])
    info = tmp_path / "seqinfo.ini"
    info.write_text("[Sequence]\nname=s\nframeRate=10\nseqLength=2\nimWidth=64\n"
                    "imHeight=48\n")
    with pytest.raises(ValueError) as e:
        evaluate_files([("s", ok, gt, None)], benchmark="MOT15")
    assert str(e.value) == f"{gt}, lines 1 and 6: id 1 appears more than once in frame 2"
    with pytest.raises(ValueError) as e:
        evaluate_files([("s", ok, ok, info)], benchmark="MOT15")
    assert str(e.value) == f"{ok}, line 2: frame 3 is beyond the sequence's 2 frames"
    with pytest.raises(ValueError) as e:
        evaluate_files([("s", ok, ok, None)], benchmark="MOT17")
    assert str(e.value) == f"{ok}, line 2, column 8 (class): class 14 is not a MOT17 class (1-13)"
    half = _rows(tmp_path / "half.txt", [(1, 1, 0, 0, 10, 10, 1, 1, 1), (2, 1, 0, 0, 10, 10, 1,
                                                                       3.5, 1)])
    with pytest.raises(ValueError) as e:  # not truncated to class 3
        evaluate_files([("s", half, half, None)], benchmark="MOT17")
    assert str(e.value) == (f"{half}, line 2, column 8 (class): class 3.5 is not a MOT17 class "
                            "(1-13)")


def test_cli_eval_table_keeps_its_columns_apart(tmp_path, capsys):
    """MOTA of -1300 % and a name shorter than the header: each value still ends under its
    header, with a space before it (-1300.0 and 7-digit counts filled the 7 characters)."""
    import re

    from vistrack.cli import main

    (tmp_path / "s" / "gt").mkdir(parents=True)
    gt = _rows(tmp_path / "s" / "gt" / "gt.txt", [(1, 1, 0, 0, 20, 40, 1, 1, 1)])
    res = _rows(tmp_path / "res.txt", [(1, k, 100 + 30 * k, 0, 20, 40, 1, -1, -1, -1)
                                       for k in range(13)])
    assert main(["eval", "--gt", str(gt), "--pred", str(res)]) == 0
    head, row = capsys.readouterr().out.splitlines()
    cells = dict(zip(head.split(), row.split()))
    assert cells["sequence"] == "s" and cells["MOTA"] == "-1300.0" and cells["FP"] == "13"
    ends = [[m.end() for m in re.finditer(r"\S+", line)] for line in (head, row)]
    assert ends[0][1:] == ends[1][1:] and len(ends[0]) == len(ends[1]) == 17
    # a gt.txt outside a gt folder is its folder's, named after it; a file of another name
    # (KITTI's label_02/0004.txt) after itself
    for name, label in (("gt.txt", "s"), ("flat.txt", "flat")):
        flat = _rows(tmp_path / "s" / name, [(1, 1, 0, 0, 20, 40, 1, 1, 1)])
        assert main(["eval", "--gt", str(flat), "--pred", str(res)]) == 0
        assert capsys.readouterr().out.splitlines()[1].split()[0] == label


# ------------------------------------------------------------------ sanity warnings


def _rows(path, rows):
    path.write_text("".join(",".join(str(v) for v in r) + "\n" for r in rows))
    return path


def test_sanity_warnings_of_unrelated_files(tmp_path):
    from vistrack.evaluation import sanity_warnings

    gt = _rows(tmp_path / "gt.txt", [(f, 1, 10 * f, 0, 20, 40, 1, 1, 1) for f in range(1, 11)])
    g = read_mot(gt)
    assert sanity_warnings(g, read_mot(gt)) == []
    late = read_mot(_rows(tmp_path / "late.txt", [(f, 1, 0, 0, 20, 40, 1, -1, -1, -1)
                                                  for f in (20, 21)]))
    assert sanity_warnings(g, late) == [
        f"predictions and ground truth look unrelated: {late.path} has frames 20-21 and "
        f"{gt} frames 1-10, no frame in common"]
    far = read_mot(_rows(tmp_path / "far.txt", [(f, 1, 900, 900, 20, 40, 1, -1, -1, -1)
                                                for f in range(1, 11)]))
    assert sanity_warnings(g, far) == [
        f"predictions and ground truth look unrelated: no box of {far.path} overlaps a box of "
        f"{gt} by IoU >= 0.5 in any of their 10 common frames"]
    one = read_mot(_rows(tmp_path / "one.txt", [(1, 1, 10, 0, 20, 40, 1, -1, -1, -1)]))
    assert sanity_warnings(g, one) == []
    # 1 box of 11 meets the ground truth: fewer than 10 %
    few = read_mot(_rows(tmp_path / "few.txt", [(1, 1, 10, 0, 20, 40, 1, -1, -1, -1)]
                         + [(f, 2, 900, 900, 20, 40, 1, -1, -1, -1) for f in range(1, 11)]))
    assert sanity_warnings(g, few) == [
        f"predictions and ground truth look unrelated: only 1 of the 11 boxes of {few.path} in "
        f"their 10 common frames overlap a box of {gt} by IoU >= 0.5"]
    # no results at all: every ground-truth row is missed (nothing was said of it, and the
    # zeros looked like scores); no ground truth at all: a sequence without objects
    empty = read_mot(_rows(tmp_path / "empty.txt", []))
    assert sanity_warnings(g, empty) == [
        f"{empty.path} holds no rows: the 10 rows of {gt} on its frames 1-10 count as missed "
        "(FN) or ignored"]
    assert sanity_warnings(g, empty, empty_said=True) == []  # the caller said why
    # an empty ground truth scores every result row as a false positive: said (it was not)
    assert sanity_warnings(empty, far) == [
        f"{empty.path} holds no rows: the 10 rows of {far.path} on its frames 1-10 count as "
        "false positives (FP)"]
    assert sanity_warnings(empty, far, empty_said=True) == []
    assert sanity_warnings(empty, empty) == []


def test_sanity_warnings_on_the_shared_files_and_a_chance_overlap(tmp_path):
    from vistrack.evaluation import sanity_warnings

    d = seq_dir("MOT17", "MOT17-09-FRCNN")
    gt, det = read_mot(d / "gt" / "gt.txt"), read_mot(d / "det" / "det.txt")
    assert sanity_warnings(gt, det) == []  # a detector's boxes meet the ground truth's
    # another sequence's ground truth as results: some boxes meet by chance (0.98 %)
    other = read_mot(seq_dir("MOT17", "MOT17-04-FRCNN") / "gt" / "gt.txt")
    # (MOT17-04's 1,050 frames against MOT17-09's 525: its later rows are said too)
    past, w = sanity_warnings(gt, other)
    assert past.startswith(f"{int((other.frames > 525).sum())} of the {len(other)} rows of "
                           f"{other.path} lie past the last frame of {gt.path} (525)")
    assert w.startswith("predictions and ground truth look unrelated: only ")
    assert w.endswith(f"boxes of {other.path} in their 525 common frames overlap a box of "
                      f"{gt.path} by IoU >= 0.5")


def test_ground_truth_that_looks_like_detections(tmp_path):
    from vistrack.evaluation import evaluate_files, sanity_warnings

    det = _rows(tmp_path / "det.txt", [(1, -1, 0, 0, 20, 40, 0.9, -1, -1, -1),
                                       (1, -1, 50, 0, 20, 40, 0.4, -1, -1, -1)])
    res = _rows(tmp_path / "res.txt", [(1, 1, 0, 0, 20, 40, 0.9, -1, -1, -1),
                                       (1, 2, 50, 0, 20, 40, 0.4, -1, -1, -1)])
    with pytest.raises(ValueError) as e:
        evaluate_files([("s", det, res, None)])
    assert str(e.value) == (f"{det}, lines 1 and 2: id -1 appears more than once in frame 1; "
                            "every id is -1: it looks like a detections file (det.txt), not "
                            "ground truth")
    with pytest.raises(ValueError, match="looks like a detections file .det.txt., not tracking "
                                         "results"):
        evaluate_files([("s", res, det, None)])
    one = _rows(tmp_path / "one.txt", [(1, -1, 0, 0, 20, 40, 0.9, -1, -1, -1)])
    assert sanity_warnings(read_mot(one), read_mot(res)) == [
        f"{one} looks like a detections or results file, not ground truth: every id is -1"]
    r = evaluate_files([("s", res, res, None)])
    assert r.warnings == [
        f"{res} looks like a detections or results file, not ground truth: its column 7 holds "
        "scores (0.9) where ground truth has 0 or 1, and it has no class column"]
    # scored as TrackEval reads such a file: its flags 0.9 and 0.4 as integers are 0, every
    # row ignored, every prediction false (the warning says why)
    assert (r["s"].TP, r["s"].FP) == (0, 2)


def test_mot17_ground_truth_with_a_class_of_none_of_theirs_is_warned_about(tmp_path):
    """Nine columns, classes 1-13 but one 14: --benchmark auto falls back to MOT15's
    convention (no distractors removed), which it now says, naming the row; MOT17 refuses the
    file naming the same row; a file of MOT17 classes only, or of no classes, is not warned."""
    from vistrack.evaluation import evaluate_files

    gt = _rows(tmp_path / "gt.txt", [(1, 1, 10, 20, 30, 60, 1, 1, 1),
                                     (2, 1, 10, 20, 30, 60, 1, 1, 1),
                                     (3, 1, 10, 20, 30, 60, 1, 14, 1)])
    res = _rows(tmp_path / "res.txt", [(1, 1, 10, 20, 30, 60, 1, -1, -1, -1)])
    r = evaluate_files([("s", gt, res, None)])
    assert r.warnings == [
        f"{gt}, line 3: class 14 is not a MOT16/17/20 class (1-13), though most rows have one: "
        "--benchmark auto scores the file as MOT15, without their preprocessing (--benchmark "
        "MOT17 refuses it, naming the row)"]
    with pytest.raises(ValueError, match=re.escape(f"{gt}, line 3, column 8 (class): class 14 "
                                                   "is not a MOT17 class (1-13)")):
        evaluate_files([("s", gt, res, None)], benchmark="MOT17")
    ok = _rows(tmp_path / "ok.txt", [(1, 1, 10, 20, 30, 60, 1, 1, 1),
                                     (2, 1, 10, 20, 30, 60, 1, 7, 1)])
    assert evaluate_files([("s", ok, res, None)]).warnings == []
    with pytest.raises(ValueError, match=r"pairs\[0\] is \("):
        evaluate_files([(ok, res)])


def test_mot17_ground_truth_with_a_class_that_is_not_whole_is_warned_about(tmp_path):
    """One class written 9.5 makes the reader take column 8 for no classes at all, so
    --benchmark auto scores MOT17 ground truth as MOT15 (distractors kept): it says so, naming
    the row, as for a class outside 1-13; MOT17 refuses the file, naming the same row. A
    nine-column file whose classes are all -1 (none) is not warned about."""
    from vistrack.evaluation import evaluate_files

    gt = _rows(tmp_path / "gt.txt", [(1, 1, 10, 20, 30, 60, 1, 1, 1),
                                     (2, 1, 10, 20, 30, 60, 1, 9.5, 1),
                                     (3, 1, 10, 20, 30, 60, 1, 1, 1)])
    res = _rows(tmp_path / "res.txt", [(1, 1, 10, 20, 30, 60, 1, -1, -1, -1)])
    assert evaluate_files([("s", gt, res, None)]).warnings == [
        f"{gt}, line 2: class 9.5 is not a whole number, so no value of column 8 is read as a "
        "class: --benchmark auto scores the file as MOT15, without the preprocessing of "
        "MOT16/17/20 (--benchmark MOT17 refuses it, naming the row)"]
    with pytest.raises(ValueError, match=re.escape(f"{gt}, line 2, column 8 (class)")):
        evaluate_files([("s", gt, res, None)], benchmark="MOT17")
    none = _rows(tmp_path / "none.txt", [(1, 1, 10, 20, 30, 60, 1, -1, 1),
                                         (2, 1, 10, 20, 30, 60, 1, -1, 1)])
    assert evaluate_files([("s", none, res, None)]).warnings == []


def test_iou_is_trackevals_bit_for_bit():
    """The IoU is computed with TrackEval's operations in its order (corners first, areas from
    the corners), so a pair whose IoU is 0.5 in exact arithmetic falls on the same side of the
    threshold and equal pairs rank alike: on boxes with two-decimal coordinates, every value
    equals TrackEval's _calculate_box_ious exactly. Before, areas as w * h differed in the
    last bits, and with every prediction half its object's width (IoU 0.5 exactly) MOTA was
    0.39 against TrackEval's 0.65."""
    te = pytest.importorskip("trackeval")
    rng = np.random.default_rng(11)
    a = np.round(np.c_[rng.uniform(0, 1900, (300, 2)), rng.uniform(5, 300, (300, 2))], 2)
    b = a.copy()
    b[:100, 2] = np.round(a[:100, 2] / 2, 2)  # IoU 1/2 where w is even in cents
    b[100:200, :2] += np.round(rng.normal(0, 20, (100, 2)), 2)
    b[200:] = np.round(np.c_[rng.uniform(0, 1900, (100, 2)), rng.uniform(5, 300, (100, 2))], 2)
    ours = box_iou_xywh(a, b)
    ref = te.datasets._base_dataset._BaseDataset._calculate_box_ious(a, b, box_format="xywh")
    assert (ours == ref).all()
    half = ours[:100, :100].diagonal()
    assert (half >= 0.5 - np.finfo(float).eps).sum() == (ref[:100, :100].diagonal()
                                                         >= 0.5 - np.finfo(float).eps).sum()


def test_cli_eval_prints_the_warnings_on_stderr(tmp_path, capsys):
    from vistrack.cli import main

    gt = _rows(tmp_path / "gt.txt", [(f, 1, 10 * f, 0, 20, 40, 1, 1, 1) for f in range(1, 4)])
    res = _rows(tmp_path / "res.txt", [(f, 1, 500, 0, 20, 40, 1, -1, -1, -1)
                                       for f in range(1, 4)])
    assert main(["eval", "--gt", str(gt), "--pred", str(res)]) == 0
    out = capsys.readouterr()
    assert out.err == (f"vistrack eval: warning: predictions and ground truth look unrelated: "
                       f"no box of {res} overlaps a box of {gt} by IoU >= 0.5 in any of their "
                       "3 common frames\n")
    assert "MOTA" in out.out


def test_the_assignment_is_scipys_without_importing_scipy_optimize():
    """eval's assignment is scipy's ``linear_sum_assignment`` loaded from its extension alone
    (``import scipy.optimize`` costs 0.3 s): in a fresh interpreter, scipy.optimize stays
    unimported, and on tie-heavy integer costs of every shape the pairs are scipy's public
    function's, exactly; with the extension not found, the public import is used."""
    code = """
import sys
import numpy as np
import vistrack.evaluation.mot as m
rng = np.random.default_rng(0)
costs = [rng.integers(0, k, (n, p)).astype(float) for k in (2, 5, 1000)
         for n in range(0, 9) for p in range(0, 9)]
mine = [m.linear_sum_assignment(c) for c in costs]
assert "scipy.optimize" not in sys.modules
from scipy.optimize import linear_sum_assignment
for c, (r, k) in zip(costs, mine):
    R, K = linear_sum_assignment(c)
    assert np.array_equal(r, R) and np.array_equal(k, K) and r.dtype == R.dtype, c
print(len(costs))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["243"]
    fallback = """
import importlib.machinery, sys
import vistrack.evaluation.mot as m
importlib.machinery.EXTENSION_SUFFIXES[:] = []
fn = m._scipy_lsa()
print(fn is sys.modules["scipy.optimize"].linear_sum_assignment)
"""
    out = subprocess.run([sys.executable, "-c", fallback], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True"]


@pytest.mark.parametrize("sep", [",", " ", "\t"])
def test_a_row_found_wrong_while_scoring_is_named_by_its_line_whatever_the_separator(tmp_path,
                                                                                     sep):
    """read_mot reads values separated by spaces or tabs as by commas; the line of a row found
    wrong while scoring was looked up in commas only, so a space-separated file was named
    without its lines."""
    from vistrack.evaluation import evaluate_files

    gt = tmp_path / "gt.txt"
    gt.write_text("# ground truth\n" + "".join(
        sep.join(map(str, (f, 1, 10, 20, 30, 60, 1, 1, 1))) + "\n" for f in (1, 2)))
    res = tmp_path / "res.txt"
    res.write_text("".join(sep.join(map(str, r)) + "\n" for r in (
        (1, 3, 10, 20, 30, 60, 1, -1, -1, -1), (2, 3, 10, 20, 30, 60, 1, -1, -1, -1),
        (2, 3, 40, 20, 30, 60, 1, -1, -1, -1))))
    with pytest.raises(ValueError, match=re.escape(
            f"{res}, lines 2 and 3: id 3 appears more than once in frame 2")):
        evaluate_files([("s", gt, res, None)])


@pytest.mark.parametrize("bench", ["MOT15", "MOT17"])
def test_a_fractional_consider_flag_is_read_as_trackeval_reads_it(bench, tmp_path):
    """TrackEval reads ground truth's column 7 as an integer (``int(0.5)`` is 0: the row is
    ignored); vistrack scored every row whose flag was not exactly 0 (MOTA 1.0 against
    TrackEval's 0.0 on a row of 0.5). The flags 0.5, 0.3, 1.5, -1 and -0.5, against
    TrackEval itself."""
    flags = [0.5, 1, 0.3, 1.5, -1, -0.5, 1]
    gt_rows = [(f, 1, 10 + 3 * f, 20, 30, 60, c, 1, 1) for f, c in enumerate(flags, start=1)]
    gt_rows += [(f, 2, 200, 50, 30, 60, 1, 1, 1) for f in range(1, 8)]
    d = tmp_path / "seq"
    (d / "gt").mkdir(parents=True)
    _rows(d / "gt" / "gt.txt", gt_rows)
    (d / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=7\n"
                                   "imWidth=640\nimHeight=480\n")
    # exact predictions of both, a second identity for the first from frame 4 on
    pred = _rows(tmp_path / "seq.txt", [(f, 7 if f < 4 else 8, 10 + 3 * f, 20, 30, 60, 1, -1, -1,
                                         -1) for f in range(1, 8)]
                 + [(f, 9, 200, 50, 30, 60, 1, -1, -1, -1) for f in range(1, 8)])
    ref = trackeval_scores(bench, {"seq": d}, {"seq": pred}, tmp_path / "te")
    ours = evaluate_mot(read_mot(d / "gt" / "gt.txt"), read_mot(pred), 7, benchmark=bench)
    compare(ours, ref["seq"])
    assert ours.FP == 3  # the rows of 0.5, 0.3 and -0.5: ignored, their predictions false


def test_what_is_not_a_readable_table_is_named(tmp_path):
    """A path, an array or a table built by hand with a NaN box, columns of two lengths or
    a frame of 1.5 failed inside numpy or SciPy's assignment ("'str' object has no attribute
    'frames'", "matrix contains invalid numeric entries"), or scored silently; each is now
    named, with the argument."""
    from vistrack.evaluation.mot import clear_matches

    good = MOTTable.from_rows([(1, 1, 0, 0, 10, 10), (2, 1, 1, 0, 10, 10)])
    path = tmp_path / "gt.txt"
    path.write_text("1,1,0,0,10,10,1,1,1\n")
    for gt, pred, error, message in [
            (str(path), good, TypeError, "gt must be a MOTTable (vistrack.io.read_mot reads a "
             "file; evaluate_files scores files); got str"),
            (good, np.zeros((2, 6)), TypeError, "pred must be a MOTTable (vistrack.io.read_mot "
             "reads a file; evaluate_files scores files); got ndarray"),
            (dataclasses.replace(good, boxes=np.array([[0, 0, 10, 10], [np.nan, 0, 10, 10]])),
             good, ValueError, "gt.boxes[1] is not finite: [nan, 0.0, 10.0, 10.0]"),
            (good, dataclasses.replace(good, ids=np.array([1])), ValueError,
             "pred.ids must be an array of shape (N,) = (2,), as frames; got ndarray of shape "
             "(1,)"),
            (good, dataclasses.replace(good, boxes=np.zeros(4)), ValueError,
             "pred.boxes must be an array of shape (N, 4) = (2, 4); got ndarray of shape (4,)"),
            (dataclasses.replace(good, frames=np.array([1.5, 2])), good, ValueError,
             "gt.frames[0] must be a whole number; got 1.5"),
            # from_rows keeps a negative width (read_mot refuses one) for the scoring to name:
            # it scored IoU 0 (a miss and a false positive) without a word
            (good, MOTTable.from_rows([(1, 1, 30, 40, -30, -40), (2, 1, 1, 0, 10, 10)]),
             ValueError, "pred.boxes[0] has a negative width or height: [30.0, 40.0, -30.0, "
             "-40.0] (x, y, w, h: a box of corners x1, y1, x2, y2?)")]:
        for score in (evaluate_mot, clear_matches):
            with pytest.raises(error, match="^" + re.escape(message) + "$"):
                score(gt, pred)
    assert evaluate_mot(good, good).MOTA == 1.0


def test_a_missing_results_file_is_named_missing_with_columns_given(tmp_path):
    """With columns given (a CSV's names), a results file that is not there was blamed on
    them ("columns name a CSV or Parquet file's columns; ... is read as a MOTChallenge text
    file"); it is named as missing, as without columns."""
    from vistrack.evaluation import evaluate_files

    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,0,0,10,10,1,1,1\n")
    pairs = [("A", gt, tmp_path / "A.txt", None)]
    res = evaluate_files(pairs, keep_going=True, columns={"frame": "t"})
    assert res.errors == {"A": f"FileNotFoundError: {tmp_path / 'A.txt'} does not exist"}
    (tmp_path / "A.txt").write_text("1,1,0,0,10,10,1,-1,-1,-1\n")
    res = evaluate_files(pairs, keep_going=True, columns={"frame": "t"})
    assert res.errors["A"].startswith("ValueError: columns name a CSV or Parquet file's")


def _one_sequence(tmp_path, seqinfo):
    seq = tmp_path / "S"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_text("1,1,0,0,10,10,1,-1,-1,-1\n2,1,0,0,10,10,1,-1,-1,-1\n")
    (seq / "seqinfo.ini").write_text(seqinfo)
    return seq


def test_a_csv_results_file_is_named_without_a_line_read_as_another_format(tmp_path):
    """The line was found by re-reading the CSV as MOTChallenge text, frame and id first:
    with the columns in another order it named another, valid row."""
    from vistrack.evaluation import evaluate_files

    seq = _one_sequence(tmp_path, "[Sequence]\nname=S\nseqLength=3\n")
    pred = tmp_path / "r.csv"
    pred.write_text("id,frame,bb_left,bb_top,bb_width,bb_height\n1,2,0,0,10,10\n"
                    "2,1,0,0,10,10\n2,1,50,0,10,10\n")
    with pytest.raises(ValueError, match=re.escape(f"{pred}: id 2 appears more than once in "
                                                   "frame 1") + "$"):
        evaluate_files([("S", seq / "gt" / "gt.txt", pred, seq / "seqinfo.ini")])
    pred.write_text("id,frame,bb_left,bb_top,bb_width,bb_height\n9,1,0,0,10,10\n1,9,0,0,10,10\n")
    with pytest.raises(ValueError, match=re.escape(f"{pred}: frame 9 is beyond the sequence's "
                                                   "3 frames") + "$"):
        evaluate_files([("S", seq / "gt" / "gt.txt", pred, seq / "seqinfo.ini")])


def test_scoring_needs_only_seq_length_of_seqinfo_as_trackeval_reads_it(tmp_path):
    """TrackEval reads seqLength alone; vistrack eval refused the file for its missing
    frameRate, imWidth and imHeight, which scoring does not use."""
    from vistrack.evaluation import evaluate_files

    short = _one_sequence(tmp_path / "a", "[Sequence]\nname=S\nseqLength=3\n")
    full = _one_sequence(tmp_path / "b", "[Sequence]\nname=S\nseqLength=3\nframeRate=10\n"
                                         "imWidth=100\nimHeight=100\n")
    got = [evaluate_files([("S", s / "gt" / "gt.txt", s / "gt" / "gt.txt", s / "seqinfo.ini")])
           for s in (short, full)]
    for field in dataclasses.fields(got[0]["S"]):
        np.testing.assert_array_equal(getattr(got[0]["S"], field.name),
                                      getattr(got[1]["S"], field.name))
    assert got[0]["S"].TP == 2
    (short / "seqinfo.ini").write_text("[Sequence]\nname=S\n")
    with pytest.raises(ValueError, match="seqinfo.ini: \\[Sequence\\] has no seqLength"):
        evaluate_files([("S", short / "gt" / "gt.txt", short / "gt" / "gt.txt",
                         short / "seqinfo.ini")])


def test_a_bad_benchmark_is_the_call_s_error_with_keep_going_too(tmp_path):
    """With keep_going the benchmark was checked in each worker: every pair failed of it and
    an empty result came back, where the docstring promises a ValueError."""
    from vistrack.evaluation import evaluate_files

    gt = _one_sequence(tmp_path, "[Sequence]\nname=S\nseqLength=3\n") / "gt" / "gt.txt"
    with pytest.raises(ValueError, match="benchmark must be one of 'auto', .*; got 'MOT18'"):
        evaluate_files([("a", gt, gt, None), ("b", gt, gt, None)], benchmark="MOT18",
                       keep_going=True)


@pytest.mark.parametrize("bench", ["MOT15", "MOT17"])
def test_a_sequence_whose_ground_truth_is_all_ignored_scores_as_trackeval(bench, tmp_path):
    """A sequence with no ground truth left to count (every row's flag 0) and predictions:
    TrackEval's MOTA for that sequence is 0 (its CLEAR metric returns before the final
    fields), where (TP - FP - IDSW) / max(1, TP + FN) gave -FP (-5.0 here); summed over
    several such sequences TrackEval's COMBINED is that formula again. Every score, per
    sequence and COMBINED, against TrackEval itself."""
    from vistrack.evaluation import evaluate_files

    seqs, preds = {}, {}
    for name, n_fp in (("a", 5), ("b", 3)):
        d = tmp_path / name
        (d / "gt").mkdir(parents=True)
        _rows(d / "gt" / "gt.txt", [(f, 1, 10 + 3 * f, 20, 30, 60, 0, 1, 1)
                                     for f in range(1, 7)])
        (d / "seqinfo.ini").write_text(f"[Sequence]\nname={name}\nframeRate=10\nseqLength=6\n"
                                       "imWidth=640\nimHeight=480\n")
        seqs[name] = d
        preds[name] = _rows(tmp_path / f"{name}.txt",
                            [(f, 7, 300, 200, 30, 60, 1, -1, -1, -1) for f in range(1, n_fp + 1)])
    ref = trackeval_scores(bench, seqs, preds, tmp_path / "te")
    ours = evaluate_files([(n, d / "gt" / "gt.txt", preds[n], d / "seqinfo.ini")
                           for n, d in seqs.items()], benchmark=bench)
    for name, theirs in (("a", "a"), ("b", "b"), ("COMBINED", "COMBINED_SEQ")):
        compare(ours[name], ref[theirs])
    assert ours["a"].MOTA == 0.0 and ours["COMBINED"].MOTA == -8.0
    assert (ours["a"] + MOTCounts()).MOTA == -5.0  # a sum, as TrackEval's COMBINED


def test_results_of_other_classes_are_refused_as_trackeval_refuses_them(tmp_path):
    """A multi-class tracker's results (class 3 in column 8) were scored as pedestrians on
    MOT17, each car a false positive or a match; TrackEval (the oracle) refuses the file:
    "Evaluation is only valid for pedestrian class". Refused too now, with the file, the line
    and the column; classes -1 and 1 are scored by both, alike; a hand-built table's classes
    of another length are named as its other columns are."""
    from vistrack.evaluation import evaluate_files

    seq = tmp_path / "gt" / "S-1"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_text("".join(f"{f},1,0,0,10,10,1,1,1\n" for f in (1, 2)))
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=S-1\nframeRate=10\nseqLength=2\n"
                                     "imWidth=64\nimHeight=48\nimDir=img1\nimExt=.jpg\n")
    for cls, refused in (("3", True), ("-1", False), ("1", False)):
        pred = tmp_path / f"pred{cls}.txt"
        pred.write_text("1,5,0,0,10,10,0.9,1,-1,-1\n"
                        f"2,5,0,0,10,10,0.9,{cls},-1,-1\n")
        if refused:
            # under MOT15's convention too (it was scored there, the car a pedestrian)
            for bench in ("MOT17", "MOT15"):
                with pytest.raises(ValueError) as e:
                    evaluate_files([("S-1", seq / "gt" / "gt.txt", pred, seq / "seqinfo.ini")],
                                   benchmark=bench)
                assert str(e.value).startswith(f"{pred}, line 2, column 8 (class): class 3: "
                                               f"{bench} scores pedestrians alone")
                with pytest.raises(Exception, match="only valid for pedestrian class"):
                    trackeval_scores(bench, {"S-1": seq}, {"S-1": pred},
                                     tmp_path / f"te{cls}{bench}", raise_errors=True)
        else:
            got = evaluate_files([("S-1", seq / "gt" / "gt.txt", pred, seq / "seqinfo.ini")],
                                 benchmark="MOT17")["S-1"]
            want = trackeval_scores("MOT17", {"S-1": seq}, {"S-1": pred}, tmp_path / f"te{cls}")
            assert got.MOTA == pytest.approx(want["S-1"]["CLEAR"]["MOTA"])
    n = 3
    table = MOTTable(np.arange(1, n + 1), np.ones(n, int), np.c_[np.arange(n) * 1.0,
                     np.zeros(n), np.full(n, 10.0), np.full(n, 10.0)], np.ones(n),
                     np.ones(2, int), -np.ones(n), columns=9)
    with pytest.raises(ValueError, match=re.escape("gt.classes must be an array of shape (N,) "
                                                   "= (3,), as frames")):
        evaluate_mot(table, table)


@pytest.mark.parametrize("extra", ["", ",-1"])  # 8 and 10 values a row
def test_auto_reads_classes_in_ground_truth_of_8_or_10_columns(tmp_path, extra):
    """--benchmark auto took MOT17's convention for 9 values a row alone: with 8 or 10, a
    distractor (class 7) was a person to find (FN 8, MOTA 0.5), where TrackEval reads column
    8 as the class of any row of 8 values or more. The oracle: TrackEval's MOT17 scores."""
    from vistrack.evaluation import evaluate_files

    seq = tmp_path / "gt" / "S-1"
    (seq / "gt").mkdir(parents=True)
    rows = [f"{f},1,0,0,10,10,1,1{',1' if extra else ''}{extra}\n" for f in range(1, 9)]
    rows += [f"{f},2,50,50,10,10,1,7{',1' if extra else ''}{extra}\n" for f in range(1, 9)]
    (seq / "gt" / "gt.txt").write_text("".join(rows))
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=S-1\nframeRate=10\nseqLength=8\n"
                                     "imWidth=64\nimHeight=48\nimDir=img1\nimExt=.jpg\n")
    pred = tmp_path / "pred.txt"
    pred.write_text("".join(f"{f},5,0,0,10,10,0.9,-1,-1,-1\n" for f in range(1, 9)))
    got = evaluate_files([("S-1", seq / "gt" / "gt.txt", pred, seq / "seqinfo.ini")])["S-1"]
    want = trackeval_scores("MOT17", {"S-1": seq}, {"S-1": pred}, tmp_path / "te")["S-1"]
    assert (got.MOTA, got.HOTA, got.IDF1, got.FN) == (1.0, 1.0, 1.0, 0)
    assert got.MOTA == want["CLEAR"]["MOTA"] and got.FN == want["CLEAR"]["CLR_FN"]
    assert got.HOTA == pytest.approx(float(np.mean(want["HOTA"]["HOTA"])))
    # MOT15's ten columns (a world x in column 8, -1 where there is none) stay MOT15's
    mot15 = tmp_path / "gt15.txt"
    mot15.write_text("".join(f"{f},{i},{50 * (i - 1)},0,10,10,1,-1,-1,-1\n"
                             for f in range(1, 9) for i in (1, 2)))
    got = evaluate_files([("S-1", mot15, pred, seq / "seqinfo.ini")])["S-1"]
    assert got.FN == 8  # the second person is one to find


def test_ground_truth_without_conf_is_said_to_count_every_row(tmp_path):
    """A ground-truth file of 6 values a row has no conf, MOTChallenge's mark (0) of the rows
    a benchmark ignores: every row counted, without a word (PETS09-S2L1's FN 941 became
    1,091). Oracle: the same rows with conf 1, which count every row too, and no warning."""
    import warnings

    from vistrack.evaluation.files import read_truth

    six, seven = tmp_path / "g6.txt", tmp_path / "g7.txt"
    six.write_text("1,1,10,10,20,40\n2,1,12,10,20,40\n")
    seven.write_text("1,1,10,10,20,40,1\n2,1,12,10,20,40,1\n")
    with pytest.warns(UserWarning, match=re.escape(
            f"{six}: 6 values a row, no conf (MOTChallenge's 7th value, 0 on the rows a "
            "benchmark ignores): every row is counted")):
        a = read_truth(six)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        b = read_truth(seven)
    assert len(a) == len(b) == 2
    # scored by evaluate_files, in this process or in workers: the warning is the result's,
    # the same either way (a worker's was said on its stderr, or nowhere with Dask)
    from vistrack.evaluation import evaluate_files

    for jobs in (1, 2):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            got = evaluate_files([("a", six, seven, None), ("b", seven, seven, None)],
                                 jobs=jobs)
        assert got.warnings == [f"{six}: 6 values a row, no conf (MOTChallenge's 7th value, "
                                "0 on the rows a benchmark ignores): every row is counted"]
    # a ground-truth CSV file's error calls it one (it was "not a CSV results file")
    bad = tmp_path / "empty.csv"
    bad.write_text("")
    with pytest.raises(Exception, match="not a CSV ground-truth file"):
        read_truth(bad)


def test_results_past_a_short_ground_truth_are_said():
    """A ground truth of the first 100 frames scored results running to 795 with every later
    row a false positive (MOTA -660), without a word; results shorter than the ground
    truth were warned of already. Oracle: the frames themselves; a few rows past the end
    (objects gone before the sequence ends) are not warned of."""
    from vistrack.evaluation.sanity import sanity_warnings

    gt = MOTTable.from_rows([(f, 1, 10, 0, 20, 40, 1, 1, 1.0) for f in range(1, 11)],
                            path="gt.txt")
    long = MOTTable.from_rows([(f, 7, 10, 0, 20, 40) for f in range(1, 41)], path="res.txt")
    assert sanity_warnings(gt, long) == [
        "30 of the 40 rows of res.txt lie past the last frame of gt.txt (10), on frames 11-40: "
        "each counts as a false positive (a ground truth of part of the sequence?)"]
    few = MOTTable.from_rows([(f, 7, 10, 0, 20, 40) for f in range(1, 13)], path="res.txt")
    assert sanity_warnings(gt, few) == []
    # the frames the rows lie on, one of them said as one
    one = MOTTable.from_rows([(f, 7, 10, 0, 20, 40) for f in (9, 10, 19)], path="res.txt")
    assert sanity_warnings(gt, one) == [
        "1 of the 3 rows of res.txt lie past the last frame of gt.txt (10), on frame 19: "
        "each counts as a false positive (a ground truth of part of the sequence?)"]


def test_a_misspelt_column_name_is_raised_once_with_keep_going(tmp_path):
    """keep_going with a misspelt key of columns failed every pair, one by one, as if each
    file were at fault; it is the argument's error, raised once before any file is read."""
    from vistrack.evaluation import evaluate_files

    gt = tmp_path / "gt.txt"
    gt.write_text("1,1,0,0,10,10,1,1,1\n")
    pred = tmp_path / "A.csv"
    pred.write_text("t,id,bb_left,bb_top,bb_width,bb_height\n1,1,0,0,10,10\n")
    pairs = [("A", gt, pred, None), ("B", gt, pred, None)]
    with pytest.raises(ValueError, match=r"columns fram=t: 'fram' is not a column vistrack "
                                         r"reads \(did you mean 'frame'\?\)"):
        evaluate_files(pairs, keep_going=True, columns={"fram": "t"})
    res = evaluate_files(pairs, keep_going=True, columns={"frame": "t"})
    assert res.errors == {} and res["COMBINED"].TP == 2


def test_counts_and_matches_compare_with_equals():
    """`evaluate_mot(g, g) == evaluate_mot(g, g)` and the same of `clear_matches` raised
    numpy's "truth value of an array is ambiguous" (the generated `==` compared array
    fields as one value). Oracle: the same scoring twice is equal, another is not."""
    from vistrack.evaluation import MOTCounts, clear_matches, evaluate_mot

    g = MOTTable.from_rows([(1, 1, 0, 0, 10, 10), (2, 1, 1, 0, 10, 10), (2, 2, 50, 0, 10, 10)])
    p = MOTTable.from_rows([(1, 1, 0, 0, 10, 10), (2, 3, 1, 0, 10, 10)])
    assert evaluate_mot(g, p) == evaluate_mot(g, p)
    assert evaluate_mot(g, p) != evaluate_mot(g, g) and evaluate_mot(g, g) != MOTCounts()
    assert clear_matches(g, p) == clear_matches(g, p)
    assert clear_matches(g, p) != clear_matches(g, g)
    assert evaluate_mot(g, p) != "counts"


def test_hand_built_tables_with_an_infinite_frame_or_ids_that_are_no_whole_numbers():
    """A table built by hand with an infinite frame failed in float()'s bare OverflowError;
    NaN ids escaped the duplicate check (NaN != NaN) and were one object to np.unique
    (MOTA 1.0 and IDF1 0.667 without a word; SciPy's "invalid numeric entries" against
    itself); an id of 1.5, which read_mot and from_rows refuse, was scored as a switch.
    Oracle: from_rows's refusal of the same rows, and the message's own index."""
    from vistrack.evaluation import clear_matches, evaluate_mot

    def table(frames, ids):
        n = len(frames)
        return MOTTable(frames=np.array(frames, float), ids=np.array(ids, float),
                        boxes=np.tile([0.0, 0.0, 10.0, 10.0], (n, 1)), conf=np.ones(n),
                        classes=np.ones(n, np.int64), visibility=np.ones(n))

    g = table([1, 2, 2], [1, 1, 2])
    with pytest.raises(ValueError, match="id must be an integer; got 1.5"):
        MOTTable.from_rows([(1, 1.5, 0, 0, 10, 10)])
    for gt, pred, said in ((g, table([1, 2, np.inf], [1, 1, 2]),
                            "pred.frames[2] must be a whole number; got inf"),
                           (table([1, 2, 2], [1, np.nan, np.nan]), g,
                            "gt.ids[1] must be a whole number; got nan"),
                           (g, table([1, 2, 2], [1, np.nan, 2]),
                            "pred.ids[1] must be a whole number; got nan"),
                           (g, table([1, 2, 2], [1, 1.5, 2]),
                            "pred.ids[1] must be a whole number; got 1.5")):
        for score in (evaluate_mot, clear_matches):
            with pytest.raises(ValueError, match=re.escape(said)):
                score(gt, pred)


def test_a_csv_of_motchallenge_text_names_the_lines_as_a_txt_does(tmp_path):
    """A ground truth of MOTChallenge's text named `.csv` (read as text, without a header)
    lost the line numbers of its errors, which the same rows named `.txt` give. Oracle: the
    `.txt` file's message, its path changed."""
    from vistrack.evaluation import evaluate_files

    ok = tmp_path / "ok.txt"
    ok.write_text("1,1,0,0,10,10,1,1,1\n2,1,0,0,10,10,1,1,1\n")
    rows = "1,1,0,0,10,10,1,1,1\n2,1,0,0,10,10,1,1,1\n2,1,5,0,10,10,1,1,1\n"
    said = {}
    for name in ("gt.txt", "gt.csv"):
        (tmp_path / name).write_text(rows)
        with pytest.raises(ValueError) as e:
            evaluate_files([("s", tmp_path / name, ok, None)])
        said[name] = str(e.value).replace(str(tmp_path / name), "FILE")
    assert said["gt.csv"] == said["gt.txt"] == (
        "FILE, lines 2 and 3: id 1 appears more than once in frame 2")
    (tmp_path / "cls.csv").write_text("1,1,0,0,10,10,1,1,1\n2,1,0,0,10,10,1,14,1\n")
    with pytest.raises(ValueError, match=re.escape(
            "cls.csv, line 2, column 8 (class): class 14 is not a MOT17 class (1-13)")):
        evaluate_files([("s", tmp_path / "cls.csv", ok, None)], benchmark="MOT17")


def test_the_identity_matching_equals_every_matching_tried_and_a_dense_assignment():
    """IDF1's matched detections (IDTP) from the sparse assignment on the pairs that ever
    match: the oracles are every one-to-one matching enumerated, on small cases, and
    scipy's dense assignment of every pair of identities, on larger ones."""
    import itertools

    from scipy.optimize import linear_sum_assignment

    from vistrack.evaluation.mot import most_matched

    rng = np.random.default_rng(5)
    for trial in range(300):
        small = trial < 200
        G, P = (int(rng.integers(1, 5)), int(rng.integers(1, 5))) if small else \
            (int(rng.integers(5, 60)), int(rng.integers(5, 200)))
        n = int(rng.integers(0, 40 if small else 2000))
        keys = rng.integers(0, G, n) * P + rng.integers(0, P, n)
        pot = np.zeros((G, P))
        np.add.at(pot, (keys // P, keys % P), 1)
        if small:  # every matching: each row to a distinct column or to none
            best = max(sum(pot[i, c] for i, c in enumerate(cols) if c is not None)
                       for cols in itertools.product(*[[None, *range(P)]] * G)
                       if len([c for c in cols if c is not None])
                       == len({c for c in cols if c is not None}))
        else:
            r, c = linear_sum_assignment(-pot)
            best = pot[r, c].sum()
        assert most_matched(keys, P) == best


def test_identity_scores_of_very_many_identities_keep_to_their_pairs():
    """A tracker that gives every detection its own identity (120,000 of them beside 2,420
    people) made IDF1 a dense matrix of every pair of identities: 4.7 GB, and a failure to
    allocate at 180,000. Here 20 people a frame over 1,000 frames, each seen for 10 frames
    (2,000 people), every box its own identity (20,000): the scores equal the closed form
    (each person keeps one box of their own: IDTP is the number of people; every box is a
    CLEAR match, and each person switches at every frame after their first) within 100 MB
    of peak allocation, where the dense matrix took 320 MB a copy."""
    import tracemalloc

    slots, frames, life = 20, 1000, 10
    f = np.repeat(np.arange(1, frames + 1), slots)
    k = np.tile(np.arange(slots), frames)
    x = k * 50.0
    people = (f - 1) // life * slots + k + 1
    ones = np.ones_like(x)
    gt = MOTTable.from_rows(np.c_[f, people, x, 0 * x, 20 * ones, 40 * ones, ones, -ones,
                                  -ones, -ones])
    pred = MOTTable.from_rows(np.c_[f, np.arange(1, len(f) + 1), x, 0 * x, 20 * ones,
                                    40 * ones, ones, ones, ones, ones])
    tracemalloc.start()
    s = evaluate_mot(gt, pred, frames, benchmark="MOT15")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    n_people = frames // life * slots
    assert s.IDTP == n_people and s.IDFN == s.IDFP == len(f) - n_people
    assert s.TP == len(f) and s.IDSW == n_people * (life - 1)
    assert peak < 100e6, peak


def test_vistrack_eval_given_odd_but_plain_inputs(tmp_path, capsys, monkeypatch):
    """Four ways `vistrack eval` misread what it was given: a second --gt/--pred pair replaced
    the first, unsaid; `--gt gt.txt` from inside SEQ/gt/ did not read SEQ/seqinfo.ini (a row
    past seqLength scored as a false positive, the sequence named "gt"); --plots said the
    ground truth's warning twice; a ground-truth CSV missing its frame column was told to
    name it with --columns, which names the results' columns only. Oracles: the same files
    given as SEQ/gt/gt.txt from outside, and the warning as evaluate_files returns it."""
    from vistrack.cli import main

    seq = tmp_path / "S"
    (seq / "gt").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=S\nframeRate=10\nseqLength=2\n"
                                     "imWidth=640\nimHeight=480\n")
    (seq / "gt" / "gt.txt").write_text("1,1,10,10,20,40,1,1,1\n2,1,12,10,20,40,1,1,1\n")
    past = tmp_path / "res3.txt"
    past.write_text("1,1,10,10,20,40,1,-1,-1,-1\n3,1,12,10,20,40,1,-1,-1,-1\n")
    said = "frame 3 is beyond the sequence's 2 frames"
    assert main(["eval", "--gt", str(seq / "gt" / "gt.txt"), "--pred", str(past)]) == 2
    assert said in capsys.readouterr().err
    monkeypatch.chdir(seq / "gt")
    assert main(["eval", "--gt", "gt.txt", "--pred", str(past)]) == 2
    assert said in capsys.readouterr().err
    monkeypatch.chdir(tmp_path)
    good = tmp_path / "res.txt"
    good.write_text("1,1,10,10,20,40,1,-1,-1,-1\n")
    with pytest.raises(SystemExit) as e:
        main(["eval", "--gt", str(seq), "--pred", str(good), "--gt", str(seq), "--pred",
              str(past)])
    assert e.value.code == 2
    assert f"--gt is given twice ({seq} and {seq}): one sequence is scored by --gt and " \
           "--pred, several by --gt-dir and --pred-dir" in capsys.readouterr().err
    six = tmp_path / "g6.txt"
    six.write_text("1,1,10,10,20,40\n2,1,12,10,20,40\n")
    assert main(["eval", "--gt", str(six), "--pred", str(good), "--plots",
                 str(tmp_path / "pl")]) == 0
    err = capsys.readouterr().err
    assert err.count("6 values a row, no conf") == 1, err
    csv = tmp_path / "gt.csv"
    csv.write_text("t,id,bb_left,bb_top,bb_width,bb_height\n1,1,10,10,20,40\n")
    assert main(["eval", "--gt", str(csv), "--pred", str(good), "--columns", "frame=t"]) == 2
    err = capsys.readouterr().err
    assert "no column 'frame' (the frame)" in err and "a ground truth is read by its own " \
        "columns' names" in err and "--columns frame=NAME" not in err, err

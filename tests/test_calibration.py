"""Score calibration by persistence: isotonic regression against scipy, invariance to the
score's scale, what it learns on scenes with known truth, and the tracker built on it."""

from __future__ import annotations

import re

import numpy as np
import pytest

from vistrack.association.costs import iou
from vistrack.io import read_mot
from vistrack.tracking import BoxTracker, BoxTrackerConfig
from vistrack.tracking.calibration import (
    ScoreCalibration,
    ScoreCalibrator,
    isotonic_increasing,
    persistence,
)
from vistrack.types import Detections

from .test_tracking import run, scene


def test_isotonic_regression_equals_scipys():
    from scipy.optimize import isotonic_regression

    rng = np.random.default_rng(0)
    for n in (1, 2, 7, 200):
        y, w = rng.normal(size=n), rng.uniform(0.1, 3.0, n)
        np.testing.assert_allclose(isotonic_increasing(y, w),
                                   isotonic_regression(y, weights=w).x, rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="weights must have the shape"):
        isotonic_increasing([1.0, 2.0], [1.0])
    with pytest.raises(ValueError, match="finite and weights finite and > 0"):
        isotonic_increasing([1.0, 2.0], [1.0, 0.0])


def test_isotonic_regression_pools_values_and_weights_near_the_largest_float():
    # each pool's weighted sum overflowed: 1.7e308 pooled with 1.6e308 gave inf, with
    # -1.7e308 NaN, weights of 1e308 NaN, and two of them pooling 1 and 0.5 gave 0 (a finite
    # sum over an infinite weight; scipy's does all of this too); the oracle is scipy's fit
    # of the same problem scaled by powers of two (exact), scaled back
    from scipy.optimize import isotonic_regression

    def oracle(y, w, ky, kw):
        return isotonic_regression(np.ldexp(y, -ky), weights=np.ldexp(w, -kw)).x * 2.0 ** ky

    rng = np.random.default_rng(1)
    cases = [([1.7e308, 1.6e308], [1.0, 1.0]), ([1.7e308, -1.7e308], [1.0, 3.0]),
             ([2.0, 1.0, 0.5], [1e308, 1e308, 1.0]), ([1.0, 0.5], [1e308, 1e308]),
             (rng.uniform(-1.0, 1.0, 50) * 1.7e308, rng.uniform(0.5, 1.0, 50) * 1e307)]
    for y, w in cases:
        y, w = np.asarray(y), np.asarray(w)
        got = isotonic_increasing(y, w)
        np.testing.assert_allclose(got, oracle(y, w, 4, 1030), rtol=1e-12)
        assert (np.diff(got) >= 0).all()
    # where the scaled weights of a pool vanish, it says so rather than give NaN
    with pytest.raises(ValueError, match="weights span too wide a range"):
        isotonic_increasing([3.0, 2.0, 1.7e308, 1.6e308], [5e-324, 5e-324, 1e308, 1e308])


def frames_with_clutter(rng, T=120, scale=lambda s: s):
    """Eight objects moving slowly (they persist), scored 0.5-1, and three clutter boxes a
    frame at random places (they do not), scored 0-0.6; ``scale`` maps every score."""
    p0 = rng.uniform(100, 900, (8, 2))
    v = rng.normal(0, 2, (8, 2))
    out, truth = [], []
    for f in range(T):
        c = p0 + v * f
        obj = np.c_[c - [15, 40], c + [15, 40]]
        xy = rng.uniform(0, 1000, (3, 2))
        clutter = np.c_[xy, xy + [30, 80]]
        s = np.r_[rng.uniform(0.5, 1.0, 8), rng.uniform(0.0, 0.6, 3)]
        out.append(Detections(boxes=np.r_[obj, clutter], scores=scale(s)))
        truth.append(np.r_[np.ones(8, bool), np.zeros(3, bool)])
    return out, truth


def test_persistence_tells_objects_from_clutter():
    """Objects persist (continued from the frame before and into the next), clutter does not;
    the calibrated confidence of an object's score is high, of clutter's low, and the
    threshold at confidence 0.5 falls where the two score ranges meet."""
    frames, truth = frames_with_clutter(np.random.default_rng(1))
    s, p = persistence(frames)
    t = np.concatenate(truth[1:-1])  # the first and last frames give no outcome
    assert len(s) == len(t) and p[t].mean() > 0.99 and p[~t].mean() < 0.05
    cal = ScoreCalibration.fit(s, p)
    assert cal.top_persistence > 0.99
    assert cal(s[t]).mean() > 0.95 and cal(s[~t]).mean() < 0.2
    assert 0.45 < cal.score_at(0.5) < 0.65  # objects from 0.5, clutter up to 0.6
    assert cal.score_at(2.0) == np.inf


@pytest.mark.parametrize("transform", [lambda s: 10 * s, lambda s: np.log(s / (1 - s)),
                                       lambda s: s ** 2, lambda s: np.arctan(50 * s) - 8])
def test_calibration_and_tracks_do_not_depend_on_the_scores_scale(transform):
    """Any strictly increasing transform of every score (x 10, a logit, a square, a squashed
    offset) gives the same confidences, the thresholds move with it, and the tracker's
    tracks are identical, online and with a fixed calibration."""
    rng = np.random.default_rng(2)
    frames, _ = frames_with_clutter(np.random.default_rng(2))
    frames = [Detections(boxes=d.boxes, scores=np.clip(d.scores, 1e-3, 1 - 1e-3))
              for d in frames]
    moved = [Detections(boxes=d.boxes, scores=transform(d.scores)) for d in frames]
    a, b = ScoreCalibration.from_frames(frames), ScoreCalibration.from_frames(moved)
    np.testing.assert_array_equal(a(frames[5].scores), b(moved[5].scores))
    assert b.score_at(0.7) == pytest.approx(transform(a.score_at(0.7)))
    _, dets = scene(rng, clutter=2.0)
    for fixed in (False, True):
        outs = []
        for ds in (dets, [Detections(boxes=d.boxes, scores=transform(np.clip(d.scores, 1e-3,
                                                                               1 - 1e-3)))
                          for d in dets]):
            cal = ScoreCalibration.from_frames(ds) if fixed else None
            tr = BoxTracker(calibration=cal)
            outs.append([tr.step(f, d) for f, d in enumerate(ds, start=1)])
        for x, y in zip(*outs):
            assert np.array_equal(x.ids, y.ids) and np.array_equal(x.boxes, y.boxes)


def test_the_online_calibration_learns_what_the_whole_file_gives():
    """Online, after the last frame, the calibrator holds the outcomes of every frame but the
    first and the last, and of every chain resolved: its map equals the one fitted to the
    whole file. Before any outcome, the first frame's scores are ranked."""
    frames, _ = frames_with_clutter(np.random.default_rng(3))
    cal = ScoreCalibrator(window=None)
    cal.observe(frames[0])
    ranks = cal(frames[0].scores)
    order = np.argsort(frames[0].scores)
    np.testing.assert_allclose(ranks[order], np.arange(1, 12) / 11)
    for d in frames[1:]:
        cal.observe(d)
    full = ScoreCalibration.from_frames(frames)
    last = cal.calibration()
    np.testing.assert_array_equal(last.scores, full.scores)
    np.testing.assert_array_equal(last.confidence, full.confidence)
    assert cal.n == full.n
    flat = ScoreCalibration.from_frames(frames, chain_span=0.0)
    assert flat.n == 11 * (len(frames) - 2)


def test_a_frame_where_nothing_was_found_breaks_the_links_at_the_start_as_anywhere():
    """Derived by hand, frame to frame: a frame without detections is one where nothing was
    found. The detections of the frame after it continue nothing and do not persist, and
    those of the frame before it are continued by nothing, whether the empty frame comes
    first (a sequence whose objects come in later) or in the middle; only the very first
    frame's detections, with nothing seen before them, get no outcome. Online and over the
    whole file alike."""
    frames, truth = frames_with_clutter(np.random.default_rng(3), T=40)
    empty = Detections(boxes=np.zeros((0, 4)))

    def outcomes(seq):
        cal = ScoreCalibrator(window=None, chain_span=0.0)
        for d in seq:
            cal.observe(d)
        return cal.outcomes()

    s0, o0 = outcomes(frames)  # frames 1..38, eleven each
    t = np.array(truth)
    for lead in (1, 5):  # frame 0 gets outcomes too, all 0; the rest as before
        s, o = outcomes([empty] * lead + frames)
        assert len(s) == 11 * 39 and (o[:11] == 0).all()
        np.testing.assert_array_equal(s[:11], frames[0].scores)
        np.testing.assert_array_equal(s[11:], s0)
        np.testing.assert_array_equal(o[11:], o0)
        whole = ScoreCalibration.from_frames([empty] * lead + frames, chain_span=0.0)
        np.testing.assert_array_equal(whole.confidence, ScoreCalibration.fit(s, o).confidence)
    # an empty frame after frame 19: frames 19 and 20 do not persist, the others as before
    s, o = outcomes(frames[:20] + [empty] + frames[20:])
    assert len(s) == 11 * 38
    o = o.reshape(38, 11).astype(bool)
    broken = np.isin(np.arange(1, 39), [19, 20])
    assert not o[broken].any()
    np.testing.assert_array_equal(o[~broken], t[1:39][~broken])


def test_a_detector_that_refills_one_buffer_every_frame_is_calibrated_as_fresh_arrays():
    """A detector that writes each frame's boxes and scores into the same arrays (a real-time
    detector's buffers): the calibrator keeps the previous frame past ``observe``, so it must
    keep its own copy. The oracle is the same frames in fresh arrays, and the truth of the
    scene (clutter at random places seldom persists). Kept as views, every
    box continued itself and the clutter persisted (confidence 1 for its score, through the
    tracker 0.54)."""
    frames, truth = frames_with_clutter(np.random.default_rng(5), T=30)
    fresh, reused = ScoreCalibrator(window=None), ScoreCalibrator(window=None)
    buf_b, buf_s = np.empty((11, 4)), np.empty(11)
    for d in frames:
        fresh.observe(d)
        buf_b[:], buf_s[:] = d.boxes, d.scores
        reused.observe(Detections(boxes=buf_b, scores=buf_s))
    for a, b in zip(fresh.outcomes(), reused.outcomes()):
        np.testing.assert_array_equal(a, b)
    # frame to frame alone: as the whole file's persistence gives, the clutter almost never
    cal = ScoreCalibrator(window=None, chain_span=0.0)
    for d in frames:
        buf_b[:], buf_s[:] = d.boxes, d.scores
        cal.observe(Detections(boxes=buf_b, scores=buf_s))
    for a, b in zip(cal.outcomes(), persistence(frames)):
        np.testing.assert_array_equal(a, b)
    o, t = cal.outcomes()[1].astype(bool), np.concatenate(truth[1:-1])
    assert o[t].all() and o[~t].mean() < 0.05
    np.testing.assert_array_equal(reused([0.1, 0.5, 0.9]), fresh([0.1, 0.5, 0.9]))
    # and through the tracker, whose calibrator sees the caller's arrays
    trackers = BoxTracker("bytetrack"), BoxTracker("bytetrack")
    for f, d in enumerate(frames, 1):
        trackers[0].step(f, d)
        buf_b[:], buf_s[:] = d.boxes, d.scores
        trackers[1].step(f, Detections(boxes=buf_b, scores=buf_s))
    np.testing.assert_array_equal(trackers[1].confidence([0.1, 0.5, 0.9]),
                                  trackers[0].confidence([0.1, 0.5, 0.9]))


def test_sequences_observed_one_after_another_are_linked_as_each_alone():
    """``observe(None)`` ends a sequence: a calibrator that goes on to a second one resolves
    every detection as two calibrators each given one sequence would (the oracle: the
    whole-file outcomes of each, concatenated). The second sequence continues the first's
    scene, whose chains (a second long, 20 frames seen) were all still open at the end: they
    get no outcome, and the second's detections join none of them (they had: the first
    sequence's open detections were resolved by the second's, and its chains went on)."""
    frames, _ = frames_with_clutter(np.random.default_rng(7), T=40)
    a, b = frames[:20], frames[20:]
    cal = ScoreCalibrator(window=None)
    for d in [*a, None, *b, None]:
        cal.observe(d)
    alone = []
    for seq in (a, b):
        one = ScoreCalibrator(window=None)
        for d in [*seq, None]:
            one.observe(d)
        alone.append(one.outcomes())
    want = [np.concatenate(x) for x in zip(*alone)]
    for got, w in zip(cal.outcomes(), want):
        np.testing.assert_array_equal(got, w)


@pytest.mark.parametrize("window", [1, 7, 50, 333])
def test_a_window_holds_the_last_outcomes_of_all(window):
    """With ``window``, after every frame the calibrator holds exactly the last ``window``
    outcomes, in order, of those a calibrator holding all of them has (the oracle), through
    frames of 0 to 11 detections, some resolving more outcomes at once than the window
    holds."""
    rng = np.random.default_rng(window)
    frames, _ = frames_with_clutter(rng)
    frames = [Detections(boxes=d.boxes[keep], scores=d.scores[keep])
              for d in frames + frames[::-1]
              for keep in [rng.random(len(d.boxes)) < rng.uniform(0, 1.5)]]
    every, last = ScoreCalibrator(window=None), ScoreCalibrator(window=window)
    for d in frames:
        every.observe(d)
        last.observe(d)
        s_all, o_all = every.outcomes()
        s, o = last.outcomes()
        np.testing.assert_array_equal(s, s_all[-window:])
        np.testing.assert_array_equal(o, o_all[-window:])
        assert last.n == min(window, every.n)
    assert every.n > 2000


def test_the_calibrations_settings_reach_the_online_calibrator():
    """``calibration_window`` (0: every outcome), ``calibration_top_min`` and
    ``calibration_cap_sigma`` of the tracker's configuration are the calibrator's (the bound
    reaching the fit: the test above); with a window of 50 it holds the last 50 outcomes of
    those a tracker holding all of them has."""
    t = BoxTracker(BoxTrackerConfig(calibration_window=50, calibration_top_min=7,
                                    calibration_cap_sigma=3.0))
    assert (t.calibrator.window, t.calibrator.top_min, t.calibrator.cap_sigma) == (50, 7, 3.0)
    assert BoxTracker(calibration_window=0).calibrator.window is None
    assert BoxTracker(calibration_window=50.0).calibrator.window == 50  # an integral float
    assert BoxTracker().calibrator.window == 20000
    every = BoxTracker(calibration_window=0, calibration_top_min=7, calibration_cap_sigma=3.0)
    for f, d in enumerate(frames_with_clutter(np.random.default_rng(4))[0], start=1):
        t.step(f, d)
        every.step(f, d)
    s, p = every.calibrator.outcomes()
    assert len(s) > 50
    held = t.calibrator.outcomes()
    np.testing.assert_array_equal(held[0], s[-50:])
    np.testing.assert_array_equal(held[1], p[-50:])
    for key, value, match in (("calibration_window", -1, "an integer >= 0"),
                              ("calibration_cap_sigma", 0.0, r"> 0 \(inf: no bound\)"),
                              ("calibration_top_min", 0, "an integer >= 1"),
                              ("calibration_window", np.inf, "an integer")):
        with pytest.raises(ValueError, match=f"{key} must be {match}"):
            BoxTrackerConfig(**{key: value})


def flickering_scene(pan=0.0, T=40):
    """At 10 frames/s: four objects detected in every frame (score 0.9), four detected in two
    frames of three (0.5), one clutter box a frame, each far from every other (0.2); the
    image moves by ``pan`` pixels a frame. Boxes 100 pixels wide."""
    out = []
    for f in range(T):
        x = np.r_[np.arange(4) * 300.0, 1500 + np.arange(4) * 300.0] + pan * f
        seen = np.r_[np.ones(4, bool), np.full(4, f % 3 != 2)]
        x = np.r_[x[seen], 5000 + 500 * f]
        boxes = np.c_[x, np.full(len(x), 100.0), x + 100, np.full(len(x), 300.0)]
        scores = np.r_[np.full(4, 0.9), np.full(int(seen[4:].sum()), 0.5), 0.2]
        out.append(Detections(boxes=boxes, scores=scores))
    return out


@pytest.mark.parametrize("pan", [0.0, 35.0])
def test_chains_across_gaps_count_flickering_objects(pan):
    """Derived by hand: a detection of the flickering objects (seen two frames of three) is
    never continued from the frame before *and* into the next, so it never persists; but it
    lies on a chain across one-frame gaps that spans the sequence. The clutter does neither,
    the steady objects both. So with chains (over 1 s, gaps up to 0.2 s: 2 frames at 10
    frames/s), scores 0.2, 0.5, 0.9 have confidences 0, n / (2n - 2) and 1, where n is the
    number of frames a flickering object is seen in (27 of 40: each of its detections has a
    chain's outcome 1, and all but the first and the last one frame to frame, 0); frame to
    frame alone, 0, 0, 1. With the image moving by 35 pixels a frame, a box 100 wide seen
    again after a frame's gap overlaps its last one at IoU 0.18, under the links' 0.3: the
    chains hold because their last boxes are moved by the image's shift (the median
    displacement of the frame-to-frame links)."""
    frames = flickering_scene(pan)
    T = len(frames)
    n = sum(f % 3 != 2 for f in range(T))
    assert n == 27
    for span, want in ((1.0, [0.0, n / (2 * n - 2), 1.0]), (0.0, [0.0, 0.0, 1.0])):
        cal = ScoreCalibration.from_frames(frames, frame_rate=10.0, chain_span=span)
        assert cal([0.2, 0.5, 0.9]).tolist() == want
    # the outcomes one by one: the objects' chains last once they span 10 frames, and then
    # every detection on them counts; the clutter's end 3 frames after it was seen (the
    # last two frames' are still open)
    online = ScoreCalibrator(frame_rate=10.0, window=None)
    for d in frames:
        online.observe(d)
    s, o = online.outcomes()
    assert np.count_nonzero(s == 0.9) == 4 * (T - 2) + 4 * T and (o[s == 0.9] == 1).all()
    assert np.count_nonzero(s == 0.5) == 4 * (n - 2) + 4 * n
    assert o[s == 0.5].sum() == 4 * n  # the flickering ones: 0 frame to frame
    assert np.count_nonzero(s == 0.2) == (T - 2) + (T - 3) and (o[s == 0.2] == 0).all()


@pytest.mark.parametrize("pan", [0.0, 35.0])
@pytest.mark.parametrize("rate", [10.0, 2.0])
@pytest.mark.parametrize("k", [2, 3, 7])
def test_chains_count_frames_not_calls(pan, rate, k):
    """The flickering scene above at ``rate`` frames/s, and the same frames observed ``k``
    frames apart (``step=k``) by a calibrator at ``k`` times the rate: the same times, so the
    same outcomes, one by one (the oracle: the run at ``rate``, derived by hand above at 10).
    Counting calls, the chains' 1 s spanned ``k`` seconds and their 0.2 s gap was 0.2 ``k``
    s. At 10 frames/s the gap is 2 frames, and ``2 k`` at ``10 k``; at 2 frames/s it is less
    than a frame (0.4), which a chain always bridges (1 frame), and ``k`` frames at ``2 k``,
    a step. The outcomes at 2 frames/s differ from 10's: the flickering objects' chains end
    at their first gap there (frame-to-frame alone then: 0 for them)."""
    frames = flickering_scene(pan)
    one = ScoreCalibrator(frame_rate=rate, window=None)
    apart = ScoreCalibrator(frame_rate=rate * k, window=None)
    for d in frames:
        one.observe(d)
        apart.observe(d, step=k)
        for a, b in zip(one.outcomes(), apart.outcomes()):
            assert a.tolist() == b.tolist()
    s, o = one.outcomes()
    assert o[s == 0.5].sum() == (0 if rate == 2 else 4 * 27)
    assert (o[s == 0.9] == 1).all() and (o[s == 0.2] == 0).all()


def test_a_step_must_be_a_whole_number_of_frames():
    d = Detections(boxes=np.array([[10.0, 10, 40, 80]]), scores=[0.9])
    for bad in (0, -1, 1.5, True, "2", np.nan):
        with pytest.raises(ValueError, match=r"^step must be an integer >= 1 \(frames\); got "):
            ScoreCalibrator().observe(d, step=bad)
    cal = ScoreCalibrator()
    cal.observe(d, step=np.int64(2))
    cal.observe(d, step=2.0)
    assert cal._t == 4


def test_chains_no_longer_referred_to_are_forgotten():
    """A parked car detected in every frame keeps its chain for the whole run, while clutter
    begins a chain a box: the table of chains holds the ones still referred to (by a last
    box or an open detection), not every chain begun since the car's (15,000 here)."""
    rng = np.random.default_rng(9)
    cal = ScoreCalibrator(frame_rate=30.0, window=None)
    for _ in range(3000):
        xy = rng.uniform(0, 4000, (5, 2))
        boxes = np.r_[[[10.0, 10, 50, 100]], np.c_[xy, xy + 40]]
        cal.observe(Detections(boxes=boxes, scores=np.r_[0.9, rng.uniform(0, 0.8, 5)]))
    assert len(cal._first) < 100  # the car's chain and the last 0.2 s of clutter's
    s, o = cal.outcomes()
    assert (o[s == 0.9] == 1).all() and np.count_nonzero(s == 0.9) == 2 * 3000 - 2


def test_the_rank_map_is_the_empirical_distribution_function():
    """``ScoreCalibration.ranks``: each score maps to the fraction of scores at or below it,
    ties included (scipy's weak percentile of score); one below them all takes the lowest
    score's rank, as any map does."""
    from scipy.stats import percentileofscore

    rng = np.random.default_rng(5)
    s = np.round(rng.uniform(-1, 3, 60), 1)  # many ties
    cal = ScoreCalibration.ranks(s)
    q = np.r_[s, 0.05, 9.0]
    want = np.array([percentileofscore(s, x, kind="weak") / 100 for x in q])
    np.testing.assert_allclose(cal(q), want, rtol=0, atol=1e-12)
    assert cal([-2.0]) == np.count_nonzero(s == s.min()) / len(s)
    with pytest.raises(ValueError, match="no scores to rank"):
        ScoreCalibration.ranks([])


@pytest.mark.parametrize("asked_each_frame", [True, False])
def test_before_any_outcome_the_ranks_are_of_every_score_seen(asked_each_frame):
    """Until the first outcome the map is the ranks of the scores seen so far (scipy's weak
    percentile of score over all of them), frame by frame. It was kept from the first frame
    it was asked for (the second frame's detections ranked among the first's alone, [0.5,
    0.5, 1] below), and was built from the latest frame's scores alone, so asking early
    changed later answers."""
    from scipy.stats import percentileofscore

    boxes = np.array([[10.0, 10, 40, 80], [200, 100, 230, 160]])
    frames = [[0.9, 0.4], [0.2, 0.1], [0.35, 0.95]]
    cal, seen = ScoreCalibrator(), []
    for k, scores in enumerate(frames):
        cal.observe(Detections(boxes=boxes + 300 * k, scores=scores))  # nothing persists
        seen += scores
        if asked_each_frame or k == 1:
            q = [0.1, 0.4, 0.9, 0.05]
            # one below every score seen takes the lowest score's rank
            want = [percentileofscore(seen, max(x, min(seen)), kind="weak") / 100 for x in q]
            if k < 2:
                assert cal.n == 0
                np.testing.assert_allclose(cal(q), want, rtol=0, atol=1e-12)
    assert cal.n == 2  # the second frame's two detections are resolved at the third


def test_outcomes_against_the_ranking_beyond_their_noise_are_capped():
    """Closed form: 300 outcomes at score 0 persisting at 0.9 (clutter that recurs in place),
    300 at score 1 at 0.2, 400 at score 2 at 0.8. The plain isotonic fit pools the first two
    (0.55, confidence 0.55 / 0.8); with the cap the first bin, below the top third and 0.7
    above the fit of the bins above it (about 17 standard errors), is taken down to 0.2."""
    s = np.repeat([0.0, 1.0, 2.0], [300, 300, 400])
    p = np.r_[np.arange(300) < 270, np.arange(300) < 60, np.arange(400) < 320].astype(float)
    plain = ScoreCalibration.fit(s, p, cap_sigma=np.inf)
    np.testing.assert_allclose(plain.confidence, [0.55 / 0.8, 0.55 / 0.8, 1.0])
    capped = ScoreCalibration.fit(s, p)
    np.testing.assert_allclose(capped.confidence, [0.25, 0.25, 1.0])
    assert capped.top_persistence == plain.top_persistence == 0.8
    # at 20 standard errors the same outcomes are within the bound: pooled as before
    np.testing.assert_array_equal(ScoreCalibration.fit(s, p, cap_sigma=20).confidence,
                                  plain.confidence)
    with pytest.raises(ValueError, match="cap_sigma must be > 0; got 0"):
        ScoreCalibration.fit(s, p, cap_sigma=0)


def test_the_caps_bins_close_as_soon_as_they_hold_their_outcomes():
    """Closed form: 201 outcomes over five scores (72, 17, 26, 11 and 75 of them, 49, 2, 1,
    1 and 63 persisting), bins of at least 50 from the top: [75], [11 + 26 + 17 = 54 at
    4/54] and [72 at 49/72], the last below the top third and 6.8 standard errors above the
    bin above it, so taken down to 4/54 before the isotonic fit. The bins were first grouped
    by the outcomes above each score in steps of 50, which made them [75] and [126]: the
    low-scoring clutter pooled with the bin above it and nothing was capped (score 1 at 0.50
    instead of 0.09)."""
    counts, hits = np.array([72, 17, 26, 11, 75]), np.array([49, 2, 1, 1, 63])
    s = np.repeat([1.0, 2, 3, 4, 5], counts)
    p = np.concatenate([np.arange(c) < h for c, h in zip(counts, hits)]).astype(float)
    low = 72 * 4 / 54  # score 1's persisting outcomes once capped
    pooled = (low + 2 + 1) / (72 + 17 + 26)  # scores 1-3 (their rates 0.074, 0.12, 0.04)
    top = 63 / 75  # the top 5 % (at least 20 outcomes) are all of score 5
    want = np.r_[[pooled] * 3, 1 / 11, top] / top
    np.testing.assert_allclose(ScoreCalibration.fit(s, p).confidence, want, rtol=1e-12)
    np.testing.assert_allclose(ScoreCalibration.fit(s, p, cap_sigma=np.inf).confidence,
                               np.r_[[53 / 126] * 4, top] / top, rtol=1e-12)


def test_a_dip_within_the_top_third_is_pooled_not_capped():
    """Closed form: 200 outcomes at score 3 persisting at 0.3 (the most confident, large and
    fast), 1,800 at score 2 at 0.9, 2,000 at score 1 at 0.5 and 2,000 at score 0 at 0.2.
    Score 2's bin lies 22 standard errors above the bin above it, but within the top third
    (200 outcomes above it, of 6,000): it is pooled with score 3 (0.84), as the plain fit
    does, and so is the top 5 %'s rate (score 3 and the ties of score 2). Were it capped
    (to 0.3), score 1's bin would be capped too and every score from 1 up would be fully
    confident."""
    s = np.repeat([0.0, 1.0, 2.0, 3.0], [2000, 2000, 1800, 200])
    p = np.r_[np.arange(2000) < 400, np.arange(2000) < 1000, np.arange(1800) < 1620,
              np.arange(200) < 60].astype(float)
    cal = ScoreCalibration.fit(s, p)
    np.testing.assert_allclose(cal.confidence, [0.2 / 0.84, 0.5 / 0.84, 1.0, 1.0])
    np.testing.assert_array_equal(cal.confidence,
                                  ScoreCalibration.fit(s, p, cap_sigma=np.inf).confidence)


@pytest.mark.parametrize("seed", range(5))
def test_outcomes_that_agree_with_the_ranking_fit_as_isotonic(seed):
    """Outcomes whose rate rises with the score, with their noise, and a dip at the very top
    (the most confident persisting less than the next, as large fast objects do): the fit is
    the plain isotonic one, exactly."""
    rng = np.random.default_rng(seed)
    s = rng.uniform(0, 1, 3000)
    rate = np.where(s > 0.9, 0.6, 0.1 + 0.8 * s)
    p = (rng.random(3000) < rate).astype(float)
    np.testing.assert_array_equal(ScoreCalibration.fit(s, p).confidence,
                                  ScoreCalibration.fit(s, p, cap_sigma=np.inf).confidence)


def test_clutter_that_recurs_in_place_at_low_scores_starts_no_track():
    """The objects and passing clutter of ``frames_with_clutter`` (tall boxes), and twelve
    wide boxes that recur in place in 95 % of the frames, scoring below everything (no object
    overlaps one at IoU 0.3). They persist as the objects do: the plain isotonic fit pools
    them with the passing clutter scored above them, which then looks nearly as good as the
    objects, and tracks follow the static boxes through the whole sequence. The capped fit
    rates both no higher than the passing clutter alone: no track of the offline run (the
    whole file's calibration) follows one, and online only the first frames' tracks do, while
    the outcomes are too few to contradict the ranking."""
    rng = np.random.default_rng(2)
    frames, _ = frames_with_clutter(rng, T=150)
    xy = rng.uniform(0, 900, (12, 2))
    spots = np.c_[xy, xy + [80, 40]]
    for f, d in enumerate(frames):
        on = rng.random(12) < 0.95
        frames[f] = Detections(boxes=np.r_[d.boxes, spots[on] + rng.normal(0, 1, (on.sum(), 1))],
                               scores=np.r_[d.scores, rng.uniform(-0.1, 0.0, on.sum())])
    s, p = persistence(frames)
    static = s < 0
    assert p[static].mean() > 0.8 and p[(s >= 0) & (s < 0.5)].mean() < 0.05
    plain = ScoreCalibration.fit(s, p, cap_sigma=np.inf)
    cal = ScoreCalibration.from_frames(frames)
    assert plain(s[static]).min() > 0.7 and plain(np.array([0.25])).item() > 0.7
    assert cal(s[static]).max() <= cal(np.array([0.25])).item() < 0.1
    assert cal(s[s > 0.6]).mean() > 0.9  # objects only

    def on_spots(tracker):
        hits = []
        for f, d in enumerate(frames, start=1):
            n = int((iou(tracker.step(f, d).boxes, spots) >= 0.3).sum())
            hits += [f] * n
        return np.array(hits)

    assert len(on_spots(BoxTracker(calibration=plain))) > 1000
    assert len(on_spots(BoxTracker(calibration=cal))) == 0
    online = on_spots(BoxTracker())
    assert len(online) and online.max() <= 10
    # the bound is a tracker setting, online and (as the pipeline fits it) offline
    unbounded = BoxTrackerConfig(calibration_cap_sigma=np.inf)
    assert len(on_spots(BoxTracker(unbounded))) > 1000
    whole = ScoreCalibration.from_frames(frames, **unbounded.calibration_options(30.0))
    assert whole(s[static]).min() > 0.7
    np.testing.assert_array_equal(
        whole.confidence, ScoreCalibration.from_frames(frames, cap_sigma=np.inf).confidence)


def test_calibration_edge_cases_and_errors():
    """One score for all (nothing to tell apart: full confidence), frames without detections,
    and bad input named."""
    boxes = np.array([[0, 0, 10, 20.0]])
    same = [Detections(boxes=boxes + 2 * f, scores=[1.0]) for f in range(5)]
    cal = ScoreCalibration.from_frames(same)
    assert cal([0.0, 1.0, 7.0]).tolist() == [1.0, 1.0, 1.0]
    gaps = [Detections(boxes=np.zeros((0, 4))) if f % 2 else same[f] for f in range(5)]
    assert ScoreCalibration.from_frames(gaps).n == 1
    with pytest.raises(ValueError, match=r"scores\[1\] is NaN"):
        ScoreCalibration.fit([0.1, np.nan], [1, 0])
    with pytest.raises(ValueError, match="no scores to fit"):
        ScoreCalibration.fit([], [])
    with pytest.raises(ValueError, match=r"top must be in \(0, 1\]"):
        ScoreCalibrator(top=0.0)
    with pytest.raises(ValueError, match="chain_span must be a finite number >= 0; got -1"):
        ScoreCalibrator(chain_span=-1.0)
    with pytest.raises(ValueError, match="chain_gap must be a finite number >= 0; got inf"):
        ScoreCalibrator(chain_gap=np.inf)
    with pytest.raises(ValueError, match="frame_rate must be > 0 and finite; got 0"):
        ScoreCalibrator(frame_rate=0.0)
    for window in (0, 2.5, np.inf):
        with pytest.raises(ValueError,
                           match=f"window must be an integer >= 1 or None; got {window}"):
            ScoreCalibrator(window=window)
    assert ScoreCalibrator(window=50.0).window == 50  # an integral float, as a count
    with pytest.raises(ValueError, match=re.escape(
            "chain_span must be a number of seconds from 0 to 1e+09; got -0.5")):
        BoxTracker(chain_span=-0.5)
    with pytest.raises(ValueError, match="must be increasing"):
        ScoreCalibration([0.2, 0.1], [0.0, 1.0])
    with pytest.raises(ValueError, match="must be increasing"):  # inf - inf was NaN: passed
        ScoreCalibration([np.inf, np.inf], [0.5, 0.5])
    with pytest.raises(ValueError, match=r"scores must be finite; scores\[0\] = nan"):
        BoxTracker().step(1, Detections(boxes=boxes, scores=[np.nan]))
    # a chain gap (or frame rate) of 1e300, finite as checked, overflowed the compiled
    # step's integer frames: it is a gap that never ends a chain
    one = Detections(boxes=np.array([[10.0, 10, 40, 80]]), scores=[0.9])
    for kw in ({"chain_gap": 1e300}, {"frame_rate": 1e300}):
        assert ScoreCalibration.from_frames([one] * 5, **kw)([0.9]).tolist() == [1.0]


def test_scores_above_one_are_calibrated_or_refused():
    """Raw scores of 0-16 (a LiDAR detector's logits): calibrated, they track like scores in
    [0, 1]; as raw scores with the first stage weighing IoU by the score they are refused by
    name, since 1 - IoU x score would go negative."""
    rng = np.random.default_rng(5)
    _, dets = scene(rng)
    wide = [Detections(boxes=d.boxes, scores=16 * d.scores) for d in dets]
    a, b = run(BoxTracker(), dets), run(BoxTracker(), wide)
    assert np.array_equal(a.ids, b.ids) and np.array_equal(a.boxes, b.boxes)
    with pytest.raises(ValueError, match="fuse_score weighs IoU by the score, which must lie"):
        run(BoxTracker(scores="raw", high=8.0, new_track=9.0, low=1.0), wide)
    out = run(BoxTracker(scores="raw", high=8.0, new_track=9.0, low=1.0, fuse_score=False),
              wide)
    assert len(out) > 500


def _transformed(seq, tmp_path, fn, name):
    """``seq`` with every detection score mapped by ``fn`` (the rest of each line as it is,
    the new score in full precision): a sequence folder in tmp_path."""
    import shutil

    d = tmp_path / name / seq.name
    (d / "det").mkdir(parents=True)
    shutil.copy(seq / "seqinfo.ini", d / "seqinfo.ini")
    lines = []
    for line in (seq / "det" / "det.txt").read_text().splitlines():
        cells = line.split(",")
        cells[6] = repr(float(fn(float(cells[6]))))
        lines.append(",".join(cells))
    (d / "det" / "det.txt").write_text("\n".join(lines) + "\n")
    return d


@pytest.mark.parametrize("bench,name,transforms", [
    ("kitti-tracking", "KITTI-0001-Car", {"x10": lambda s: 10 * s, "cube": lambda s: s ** 3,
                                          "arctan": lambda s: np.arctan(s)}),
    ("mot16-fairmot", "MOT16-09", {"logit": lambda s: np.log(s / (1 - s)),
                                   "square": lambda s: s ** 2}),
])
@pytest.mark.parametrize("offline", [False, True])
def test_a_monotone_transform_of_a_real_detectors_scores_changes_no_track(
        tmp_path, bench, name, transforms, offline):
    """PointRCNN's raw scores on a KITTI drive, FairMOT's on a MOT16 sequence: mapped by any
    strictly increasing function, the tracks are the same, online and offline, so HOTA is
    too."""
    from vistrack.evaluation import evaluate_mot
    from vistrack.pipeline import track_sequence

    from .mot_oracles import SHARED

    seq = SHARED / bench / name
    if not (seq / "det" / "det.txt").exists():
        pytest.skip(f"{seq} not found: the shared data is not beside this checkout")
    base = track_sequence(seq, tmp_path / "base.txt", offline=offline)
    ref = read_mot(base.out)
    scores = set()
    for label, fn in transforms.items():
        d = _transformed(seq, tmp_path, fn, label)
        run = track_sequence(d, tmp_path / f"{label}.txt", offline=offline)
        got = read_mot(run.out)
        assert np.array_equal(got.frames, ref.frames) and np.array_equal(got.ids, ref.ids)
        np.testing.assert_array_equal(got.boxes, ref.boxes)
        gt = read_mot(seq / "gt" / "gt.txt")
        scores.add(round(evaluate_mot(gt, got, base.frames).HOTA, 12))
    assert len(scores) == 1 and len(ref) > 1000


def _sequence(folder, frames, fps=2):
    """A MOTChallenge sequence folder of ``frames`` (Detections) at ``fps``."""
    from vistrack.io import write_mot

    (folder / "det").mkdir(parents=True)
    f = np.concatenate([np.full(len(d), k) for k, d in enumerate(frames, start=1)])
    b = np.concatenate([d.xywh for d in frames])
    s = np.concatenate([d.scores for d in frames])
    write_mot(folder / "det" / "det.txt", f, -np.ones(len(f), int), b, s)
    (folder / "seqinfo.ini").write_text(f"[Sequence]\nname={folder.name}\nframeRate={fps}\n"
                                        f"seqLength={len(frames)}\nimWidth=1100\n"
                                        "imHeight=1100\n")
    return folder


def test_a_run_says_when_the_calibration_cannot_tell_scores_apart(tmp_path):
    """Where no detection persists (every box at a new place in every frame), the calibration
    rates every score alike and every detection may start a track: track_sequence warns, the
    command line in one line, and the tracks are still written. Where objects persist (with
    clutter, or alone: then every detection is one), where every score is the same, or with
    raw scores, nothing is said."""
    import subprocess
    import sys
    import warnings

    from vistrack.pipeline import track_sequence

    rng = np.random.default_rng(5)
    moving, _ = frames_with_clutter(rng, T=60)
    jumping = [Detections(boxes=np.c_[xy, xy + [30, 80]], scores=rng.uniform(0, 1, 11))
               for xy in rng.uniform(0, 1000, (60, 11, 2))]
    same = [Detections(boxes=d.boxes, scores=np.ones(len(d))) for d in jumping]
    only = [Detections(boxes=d.boxes[:8], scores=d.scores[:8]) for d in moving]  # all persist

    def said(frames, name, **kw):
        seq = _sequence(tmp_path / name, frames)
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            run = track_sequence(seq, tmp_path / f"{name}.txt", **kw)
        assert run.rows > 0
        return [str(x.message) for x in w if issubclass(x.category, RuntimeWarning)]

    got = said(jumping, "jumping")
    assert len(got) == 1 and got[0].startswith(
        f"{tmp_path / 'jumping'}: every detection counts as confident enough to start a track: "
        "the score calibration finds the least confident persisting from frame to frame nearly "
        "as often as the most confident, which persist at a rate of 0.00 at 2 frames/s; ")
    # offline, the whole file's calibration loosened its links first, and says so
    assert said(jumping, "jumping-offline", offline=True) == [
        got[0].replace("/jumping:", "/jumping-offline:").replace(
            "the score calibration finds", "the score calibration, its links loosened to IoU "
            "0.1, finds")]
    assert said(moving, "moving") == [] and said(same, "same") == [] and said(only, "only") == []
    assert said(jumping, "jumping-raw", scores="raw") == []
    r = subprocess.run([sys.executable, "-m", "vistrack.cli", "track", str(tmp_path / "jumping"),
                        "--out", str(tmp_path / "cli.txt")], capture_output=True, text=True)
    assert r.returncode == 0 and (tmp_path / "cli.txt").stat().st_size > 0
    assert r.stderr == f"vistrack track: warning: {got[0]}\n"


def test_the_warning_also_says_when_every_detection_is_confident_but_not_all_start_tracks():
    """Where the lowest score's confidence reaches ``high`` but not ``new_track``, the first
    association stage takes every detection, clutter too, though not each starts a track: the
    run says so too (KITTI-0004-Car with its detections on every 2nd frame, at 5 frames/s,
    did that without a word, and scored MOTA -85). Above ``new_track`` the warning is the one
    above; under ``high``, or where the most confident persist half the time, none."""
    from vistrack.pipeline import calibration_warning

    def warning(lowest, top_persistence=0.2):
        cal = ScoreCalibration(np.array([0.1, 0.9]), np.array([lowest, 1.0]), n=100,
                               top_persistence=top_persistence)
        return calibration_warning(BoxTracker("bytetrack", frame_rate=5.0, calibration=cal),
                                   "SEQ")

    assert warning(0.65).startswith(  # high 0.6, new_track 0.7
        "SEQ: every detection counts as confident (the first association stage takes them "
        "all): the score calibration finds the least confident persisting from frame to frame "
        "nearly as often as the most confident, which persist at a rate of 0.20 at 5 frames/s")
    assert warning(0.75).startswith("SEQ: every detection counts as confident enough to start "
                                    "a track: ")
    assert warning(0.55) is None and warning(0.65, top_persistence=0.5) is None


def test_the_warning_names_every_class_it_holds_for():
    """With a calibration for each class, every class whose detections all count as confident
    is named, each with its own rate, in the order of the classes; a class whose calibration
    tells its scores apart is not (only the first class was named before)."""
    from vistrack.pipeline import calibration_warning

    def cal(lowest, top_persistence):
        return ScoreCalibration(np.array([0.1, 0.9]), np.array([lowest, 1.0]), n=100,
                                top_persistence=top_persistence)

    def warning(**by_class):
        maps = {int(k[1:]): cal(*v) for k, v in by_class.items()}
        return calibration_warning(BoxTracker("bytetrack", frame_rate=5.0, calibration=maps),
                                   "SEQ")

    both = warning(c7=(0.75, 0.2), c2=(0.65, 0.31), c0=(0.2, 0.1))
    assert both == (
        "SEQ: every detection of class 2 counts as confident (the first association stage "
        "takes them all), its most confident persisting at a rate of 0.31; every detection of "
        "class 7 counts as confident enough to start a track, its most confident persisting at "
        "a rate of 0.20: at 5 frames/s the score calibration finds the least confident of "
        "each persisting from frame to frame nearly as often as the most confident; "
        "thresholds on the scores themselves may track better (--scores raw with --high, "
        "--low and --new-track, for every class)")
    one = warning(c7=(0.75, 0.2), c0=(0.2, 0.1))
    assert one.startswith("SEQ: every detection of class 7 counts as confident enough to "
                          "start a track, its most confident persisting at a rate of 0.20: "
                          "at 5 frames/s the score calibration finds the least confident of "
                          "that class ")
    assert warning(c7=(0.75, 0.6), c0=(0.2, 0.1)) is None


@pytest.mark.parametrize("persisted", [[0, np.nan, 1], [0, 2, 1], [0, -1, 1]])
def test_outcomes_outside_0_1_are_named(persisted):
    """An outcome is 0, 1 or a weight between: NaN and -1 failed with the fit's internal
    "confidence must be non-decreasing", 2 was fitted, and all -1 gave a top persistence of
    -1."""
    from vistrack.tracking.calibration import ScoreCalibration

    with pytest.raises(ValueError, match=r"persisted must hold outcomes in \[0, 1\]; "
                                         r"persisted\[1\] = "):
        ScoreCalibration.fit([0.1, 0.5, 0.9], persisted)


def _class_file(path, dets, scale, cls):
    """``dets`` (one Detections a frame) as a CSV of detections of class ``cls``, each score
    through ``scale``."""
    import pandas as pd

    rows = [(f, *b, scale(s), cls) for f, d in enumerate(dets, start=1)
            for b, s in zip(d.xywh.tolist(), d.scores.tolist())]
    table = pd.DataFrame(rows, columns=["frame", "bb_left", "bb_top", "bb_width", "bb_height",
                                        "conf", "class"])
    table.to_csv(path, index=False)
    return table


def _canonical(table):
    """A results table's rows sorted by frame and box, each track renumbered by its first
    row in that order: equal for the same tracks under other identities."""
    t = table.sort_values(["frame", "bb_left", "bb_top", "bb_width", "bb_height"],
                          kind="stable").reset_index(drop=True)
    first = {}
    ids = [first.setdefault(i, len(first) + 1) for i in t["particle"].tolist()]
    return np.c_[t["frame"], ids, t[["bb_left", "bb_top", "bb_width", "bb_height", "conf"]]]


@pytest.mark.parametrize("offline", [False, True], ids=["online", "offline"])
def test_a_file_of_two_classes_tracks_each_class_as_tracked_alone(tmp_path, offline):
    """A detector of two classes, each scored on a scale of its own (PointRCNN's cars from
    −1 to 16, its pedestrians mostly below 1): one calibration over both rated the class of
    lower scores as clutter (KITTI-0001's pedestrians, tracked in one file with its cars:
    24.2 HOTA online against 49.5 alone). Each class is calibrated apart now, so with the
    camera still (its motion is estimated from every track) the tracks of each class are
    those of its detections tracked alone, boxes and confidences alike, up to identities."""
    import pandas as pd

    from vistrack.config import TrackConfig
    from vistrack.pipeline import track_sequence

    _, cars = scene(np.random.default_rng(21), clutter=3.0)
    _, people = scene(np.random.default_rng(22), clutter=3.0, height=(20, 50))
    assert all(len(d) for d in cars) and all(len(d) for d in people)  # no frame empty alone
    tables = [_class_file(tmp_path / "cars.csv", cars, lambda s: 16 * s - 1, 2),
              _class_file(tmp_path / "people.csv", people, lambda s: s ** 3 / 2, 0)]
    pd.concat(tables).sort_values("frame", kind="stable").to_csv(tmp_path / "both.csv",
                                                                  index=False)
    cfg = TrackConfig.preset("bytetrack").with_values(
        tracker={"camera_motion": False}, offline={"enabled": offline})
    # the image's size given (a file alone is as large as its boxes reach, the two classes'
    # together further than each one's)
    (tmp_path / "seqinfo.ini").write_text("[Sequence]\nname=SCENE\nframeRate=25\n"
                                          "seqLength=150\nimWidth=1000\nimHeight=1000\n")
    out = {}
    for name in ("cars", "people", "both"):
        track_sequence(tmp_path, tmp_path / f"{name}-out.csv", config=cfg,
                       detections=tmp_path / f"{name}.csv")
        out[name] = pd.read_csv(tmp_path / f"{name}-out.csv")
    both = out["both"]
    for name, cls in (("cars", 2), ("people", 0)):
        alone = _canonical(out[name])
        assert len(alone) > 300
        np.testing.assert_array_equal(_canonical(both[both["class"] == cls]), alone)


def test_several_classes_name_the_calibration_each_has():
    """With detections of several classes, a calibration is each class's: asking for the
    tracker's one calibration, its one learner or the confidence of scores without their
    classes says so, naming the classes."""
    tr = BoxTracker()
    d = Detections.from_xywh([[0, 0, 9, 9], [50, 0, 9, 9]], [0.9, 0.2], classes=[2, 0])
    tr.step(1, d)
    for call in (lambda: tr.score_calibration(), lambda: tr.calibrator,
                 lambda: tr.confidence([0.5])):
        with pytest.raises(ValueError, match=r"classes \[0, 2\] has a calibrat"):
            call()
    assert sorted(tr.score_calibrations()) == [0, 2]
    # each class's confidences by its own map: the ranks of its own scores so far
    np.testing.assert_array_equal(tr.confidence([0.9, 0.2], [2, 0]), [1.0, 1.0])
    with pytest.raises(ValueError, match="classes must have one per score; got 1 classes "
                                         "for 2 scores"):
        tr.confidence([0.9, 0.2], [2])


@pytest.mark.parametrize("chain_span", [0.0, 0.3])
def test_frames_without_detections_passed_over_quickly_leave_the_state_as_the_full_step(
        monkeypatch, chain_span):
    """A frame without detections after another, with no chain open, is passed over
    without the compiled step (a class's calibration sees most frames empty in a file of
    many classes): after every frame, the outcomes, the map and every array of the state
    equal those of the full step, over runs of frames with and without detections."""
    import vistrack.tracking.calibration as calibration

    rng = np.random.default_rng(4)
    frames = []
    for f in range(400):
        n = 0 if (f // 23) % 3 == 1 or rng.random() < 0.2 else rng.integers(1, 6)
        xy = rng.uniform(0, 200, (n, 2)) if f % 2 else np.full((n, 2), 50.0) + f * 0.5
        frames.append(Detections(boxes=np.c_[xy, xy + 30], scores=rng.random(n)))
    cals = {}
    for quiet in (True, False):
        monkeypatch.setattr(calibration, "_QUIET", quiet)
        cal = ScoreCalibrator(frame_rate=10.0, chain_span=chain_span, chain_gap=0.2)
        states = []
        for d in frames:
            cal.observe(d)
            m = cal.calibration()
            states.append((cal.outcomes(), m.scores, m.confidence, cal._t, cal._frames,
                           cal._head_box, cal._first, cal._state, cal._open_s, cal._shift,
                           cal._prev[0], cal._prev[4]))
        cals[quiet] = states
    for a, b in zip(cals[True], cals[False]):
        for x, y in zip(a, b):
            if isinstance(x, tuple):
                for u, v in zip(x, y):
                    np.testing.assert_array_equal(u, v)
            else:
                np.testing.assert_array_equal(x, y)
    # the quick way was taken: runs of empty frames after the chains ended
    monkeypatch.setattr(calibration, "_QUIET", True)
    seen = []
    real = calibration._observe

    def counted(*a):
        seen.append(1)
        return real(*a)

    monkeypatch.setattr(calibration, "_observe", counted)
    cal = ScoreCalibrator(frame_rate=10.0, chain_span=chain_span, chain_gap=0.2)
    for d in frames:
        cal.observe(d)
    quick = len(frames) - len(seen)
    assert quick > 50


def test_the_calibrator_before_any_detection_is_the_first_classs():
    """Before any detection the tracker's calibrator is one object, the one the first class
    to come takes, shown every frame before (it was made anew at each access, and what was
    done to it was lost); a fixed map by class must be keyed by the classes as integers
    (``"2"``, as ``--print-config`` writes them, was never looked up)."""
    tr = BoxTracker()
    first = tr.calibrator
    assert tr.calibrator is first
    tr.step(1, Detections(boxes=np.zeros((0, 4))))
    tr.step(2, Detections.from_xywh([[0, 0, 9, 9]], [0.9], classes=[2]))
    assert tr.calibrator is first and tr.calibrators == {2: first}
    cal = ScoreCalibration([0.0], [1.0])
    with pytest.raises(TypeError, match="calibration's keys must be detection classes, "
                                        "integers; got '2'"):
        BoxTracker(calibration={"2": cal})
    assert BoxTracker(calibration={np.int64(2): cal}).calibration == {2: cal}


def test_a_learner_put_in_the_trackers_place_is_the_one_it_learns_with():
    """``tracker.calibrator = learner`` starts the online calibration from what ``learner``
    learnt on other frames of the detector: after a frame, the tracker's confidences are
    those of a copy of the learner shown the same frame (the objects above 0.9, the clutter
    below 0.2), where a tracker left to learn from that frame alone ranks the scores. Where
    nothing is learnt, or each of several classes has its own learner, the assignment is
    refused by name."""
    import copy

    frames = _fast(5)
    learner = ScoreCalibrator(**BoxTracker().config.calibration_options(30.0))
    for d in frames[:-1]:
        learner.observe(d)
    twin = copy.deepcopy(learner)
    tr, fresh = BoxTracker(), BoxTracker()
    tr.calibrator = learner
    assert tr.calibrator is learner
    tr.step(1, frames[-1])
    fresh.step(1, frames[-1])
    twin.observe(frames[-1])
    s = frames[-1].scores
    assert tr.calibrator is learner and tr.calibrators == {0: learner}
    np.testing.assert_array_equal(tr.confidence(s), twin.calibration()(s))
    assert tr.confidence(s)[:8].min() > 0.9 > 0.2 > tr.confidence(s)[8:].max()
    # the fresh tracker, with no outcome yet, ranks the scores (1/16 to 1): the weakest
    # object 0.5625, the strongest clutter 0.5
    np.testing.assert_array_equal(fresh.confidence(s), (np.argsort(np.argsort(s)) + 1) / 16)
    with pytest.raises(TypeError, match="calibrator must be a ScoreCalibrator; got "
                                        "ScoreCalibration"):
        tr.calibrator = twin.calibration()
    with pytest.raises(ValueError, match=r"learns no calibration \(scores='raw'\)"):
        BoxTracker(scores="raw").calibrator = learner
    with pytest.raises(ValueError, match="learns no calibration .a fixed calibration is "):
        BoxTracker(calibration=twin.calibration()).calibrator = learner
    two = BoxTracker()
    two.step(1, Detections.from_xywh([[0, 0, 9, 9], [50, 0, 9, 9]], [0.9, 0.2],
                                     classes=[2, 0]))
    with pytest.raises(ValueError, match=r"classes \[0, 2\] has a calibrator of its own: "
                                         r"calibrators\[class\] = learner"):
        two.calibrator = learner


def _fast(shift, frames=30, seed=0):
    """Eight objects (30 x 80 pixels, scores 0.6-1) moving ``shift`` pixels a frame to the
    right, each on a row of its own, and eight boxes of clutter (scores 0-0.5) at random
    places in every frame. Two boxes of an object one frame apart overlap by IoU
    ``(30 - shift) / (30 + shift)``, the clutter's hardly ever."""
    rng = np.random.default_rng(seed)
    out = []
    for f in range(frames):
        x = 10.0 + shift * f
        obj = np.array([[x, 100.0 * r, x + 30, 100.0 * r + 80] for r in range(8)])
        xy = rng.uniform(0, 1000, (8, 2))
        clutter = np.c_[xy, xy + [30, 80]]
        out.append(Detections(boxes=np.r_[obj, clutter],
                              scores=np.r_[np.linspace(0.6, 1.0, 8), rng.uniform(0, 0.5, 8)]))
    return out


@pytest.mark.parametrize("shift", [5, 18, 22, 27])
def test_the_whole_files_calibration_loosens_its_links_where_objects_move_far(shift):
    """Offline, where the most confident detections do not persist at the overlap the links
    are made at (objects move further between frames than their boxes overlap by 0.3), the
    outcomes are gathered again at 0.2, then 0.1, and the first overlap at which they persist
    is taken: the largest of 0.3, 0.2 and 0.1 at or below the closed-form overlap of an
    object's boxes one frame apart. There the map tells the objects from the clutter, which
    at 0.3 it could not; where even 0.1 is too tight, the loosest is taken, and nothing is
    told apart. ``min_link_iou`` bounds the steps; without it only ``link_iou`` is tried."""
    frames = _fast(shift)
    overlap = (30 - shift) / (30 + shift)  # the oracle: equal boxes moved along x
    tried = [0.3, 0.2, 0.1]
    want = next((v for v in tried if v <= overlap), 0.1)
    cal = ScoreCalibration.from_frames(frames, frame_rate=10.0, min_link_iou=0.1)
    assert cal.link_iou == want
    objects, clutter = cal(np.linspace(0.6, 1.0, 8)), cal(np.linspace(0.0, 0.5, 9))
    if overlap >= 0.1:
        assert cal.top_persistence >= 0.5
        assert objects.min() > 0.9 and clutter.max() < 0.2, (objects, clutter)
    else:  # nothing persists at any overlap tried: nothing to tell apart
        assert cal.top_persistence < 0.5 and (clutter == 1).all()
    tight = ScoreCalibration.from_frames(frames, frame_rate=10.0)
    assert tight.link_iou == 0.3
    if overlap < 0.3:
        assert tight.top_persistence < 0.5 and (tight(np.linspace(0.0, 0.5, 9)) == 1).all()
    bounded = ScoreCalibration.from_frames(frames, frame_rate=10.0, min_link_iou=0.2)
    assert bounded.link_iou == max(want, 0.2)
    assert ScoreCalibration.from_frames(frames, frame_rate=10.0, link_iou=0.3,
                                        min_link_iou=0.5).link_iou == 0.3


def test_offline_runs_say_the_overlap_their_calibration_took(tmp_path):
    """The offline mode fits its calibration at the loosened overlap by default
    (``[offline] calibration_iou_min``, 0.1): on objects whose boxes overlap by 0.25 from one
    frame to the next, ``[derived] calibration_link_iou`` is 0.2, and the run does not warn that
    the scores could not be told apart, as the online run (which links at
    ``calibration_iou``, 0.3) and the offline one with ``calibration_iou_min`` 0.3 do. Where
    the boxes overlap well, nothing changes: the results are those of ``calibration_iou_min``
    0.3, byte for byte."""
    import warnings

    from vistrack.config import OfflineConfig
    from vistrack.pipeline import track_sequence

    seq = _sequence(tmp_path / "fast", _fast(18), fps=10)

    def run(name, **kw):
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            r = track_sequence(seq, tmp_path / f"{name}.txt", **kw)
        return r, [str(x.message) for x in w if "counts as confident" in str(x.message)]

    r, said = run("loose", offline=True)
    assert r.derived["calibration_link_iou"] == 0.2 and said == []
    r, said = run("online")
    assert "calibration_link_iou" not in r.derived and len(said) == 1
    r, said = run("tight", offline=True, calibration_iou_min=0.3)
    assert r.derived["calibration_link_iou"] == 0.3 and len(said) == 1
    slow = _sequence(tmp_path / "slow", _fast(5), fps=10)
    a = track_sequence(slow, tmp_path / "a.txt", offline=True)
    track_sequence(slow, tmp_path / "b.txt", offline=True, calibration_iou_min=0.3)
    assert a.derived["calibration_link_iou"] == 0.3
    assert (tmp_path / "a.txt").read_bytes() == (tmp_path / "b.txt").read_bytes()
    with pytest.raises(ValueError, match=r"calibration_iou_min must be in \(0, 1\]; got 0"):
        OfflineConfig(calibration_iou_min=0)


def test_the_ladder_ends_at_its_least_overlap_and_blend_keeps_it():
    """Steps of 0.1 from ``link_iou`` that fall short of ``min_link_iou`` end at the least
    itself (0.35 to 0.1: 0.25, 0.15, then 0.1), so that the least named is always tried; a
    blended map keeps the overlap its outcomes were gathered at."""
    import vistrack.tracking.calibration as calibration

    tried = []
    outcomes = calibration._outcomes

    def spy(frames, **kw):
        tried.append(kw["link_iou"])
        return outcomes(frames, **kw)

    frames = _fast(27)  # overlap 0.053: nothing persists at any overlap tried
    calibration._outcomes = spy
    try:
        for start, least, want in ((0.35, 0.1, [0.35, 0.25, 0.15, 0.1]),
                                   (0.3, 0.1, [0.3, 0.2, 0.1]), (0.3, 0.05, [0.3, 0.2, 0.1, 0.05]),
                                   (0.3, 0.3, [0.3]), (0.3, None, [0.3])):
            tried.clear()
            cal = ScoreCalibration.from_frames(frames, link_iou=start, min_link_iou=least,
                                               frame_rate=10.0)
            assert tried == want and cal.link_iou == want[-1]
    finally:
        calibration._outcomes = outcomes
    assert cal.blend(0.5, np.array([0.1, 0.9])).link_iou == 0.3
    assert np.isnan(ScoreCalibration.ranks([0.1, 0.9]).link_iou)


def test_each_class_loosens_its_own_links(tmp_path):
    """Offline, with detections of two classes, each class's calibration loosens its links
    on its own: the class whose objects move far links at 0.2, the one whose objects move
    little at 0.3, and ``[derived] calibration_link_iou`` gives both by class."""
    import pandas as pd

    from vistrack.pipeline import track_sequence

    slow = [Detections(boxes=d.boxes + [0, 1000, 0, 1000], scores=d.scores) for d in _fast(5)]
    tables = [_class_file(tmp_path / "fast.csv", _fast(18), lambda s: s, 1),
              _class_file(tmp_path / "slow.csv", slow, lambda s: s, 2)]
    pd.concat(tables).sort_values("frame", kind="stable").to_csv(tmp_path / "both.csv",
                                                                  index=False)
    run = track_sequence(tmp_path / "both.csv", tmp_path / "out.csv", fps=10, offline=True)
    assert run.derived["calibration_link_iou"] == {"1": 0.2, "2": 0.3}


def test_top_min_that_is_no_whole_number_is_named():
    """NaN failed on "cannot convert float NaN to integer", infinity on an OverflowError,
    2.5 was cut to 2."""
    for bad, error in ((np.nan, ValueError), (np.inf, ValueError), (2.5, ValueError),
                       ("20", TypeError)):
        with pytest.raises(error, match="top_min"):
            ScoreCalibrator(top_min=bad)
        with pytest.raises(error, match="top_min"):
            ScoreCalibration.fit([0.1, 0.9], [0, 1], top_min=bad)
    assert ScoreCalibrator(top_min=2.0).top_min == 2


@pytest.mark.parametrize("rate, step, frames", [(12.5, 1, 3), (22.5, 1, 5), (37.5, 1, 8),
                                                (25.0, 2, 6), (2.5, 1, 1), (30.0, 1, 6),
                                                (14.0, 1, 3), (7.0, 1, 1)])
def test_the_chains_gap_is_whole_steps_a_half_up(rate, step, frames):
    """chain_gap 0.2 s in whole steps: Python's round took a half to the even number (2.5
    frames at 12.5 frames/s to 2, 4.5 at 22.5 to 4, but 7.5 at 37.5 to 8; 2.5 steps of 2
    frames at 25 to 2 steps), where coasting and the offline durations round a half up. The
    oracle: floor(0.2 rate / step + 1/2) steps, at least one."""
    from fractions import Fraction
    from math import floor

    want = step * max(1, floor(Fraction("0.2") * Fraction(rate) / step + Fraction(1, 2)))
    assert want == frames
    assert ScoreCalibrator(frame_rate=rate, chain_gap=0.2)._gap_frames(step) == frames


def test_the_top_fraction_is_the_outcomes_own_rate_of_a_whole_count():
    """`top` x n a whole number in reals but not in floats (0.07 x 100 = 7.000000000000001)
    took one outcome more than the top fraction, and where the top fraction reaches below
    the top third its rate was taken from the outcomes after the rank cap lowered them.
    Oracles: the mean of the top outcomes by score, and scipy's isotonic regression."""
    from scipy.optimize import isotonic_regression

    s = np.arange(100.0)
    p = np.zeros(100)
    p[93:] = 1
    p[40:60:2] = 1
    cal = ScoreCalibration.fit(s, p, top=0.07, top_min=1)
    assert cal.top_persistence == p[-7:].mean() == 1.0
    assert cal([50.0])[0] == pytest.approx(isotonic_regression(p).x[50] / p[-7:].mean())
    s = np.arange(600.0)
    p = np.zeros(600)
    p[400:] = np.arange(200) % 2
    p[300:400] = 1
    assert ScoreCalibration.fit(s, p, top=0.5, top_min=1).top_persistence == pytest.approx(
        p[300:].mean())


def test_calibration_settings_that_mean_nothing_are_named():
    """`from_frames(min_link_iou=0, -1 or NaN)` left the links as they were; `blend` clipped
    a weight of 2 or -1 into a map, warned of a division by 0 on no ranked scores and named
    a NaN among them by its place in the union; `score_at(NaN)` said inf ("no score
    reaches it")."""
    fast = [Detections(boxes=np.array([[10.0 + 18 * f, 10, 40 + 18 * f, 80],
                                       [200.0 + 50 * f, 100, 230 + 50 * f, 160]]),
                       scores=np.array([0.9, 0.4])) for f in range(6)]
    for bad in (0.0, -1.0, float("nan"), True):
        with pytest.raises(ValueError, match=re.escape(
                f"min_link_iou must be an overlap > 0, or None; got {bad!r}")):
            ScoreCalibration.from_frames(fast, min_link_iou=bad)
    assert ScoreCalibration.from_frames(fast, min_link_iou=0.1).link_iou == 0.2
    cal = ScoreCalibration([0.4, 0.9], [0.0, 1.0])
    for weight in (2.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match=re.escape(f"weight must be in [0, 1]; got "
                                                       f"{weight!r}")):
            cal.blend(weight, np.array([0.4, 0.9]))
    with pytest.raises(ValueError, match="ranked must hold at least one score"):
        cal.blend(0.5, np.array([]))
    with pytest.raises(ValueError, match=re.escape("ranked must not be NaN; ranked[0] is NaN")):
        cal.blend(0.5, np.array([np.nan, 0.4]))
    assert cal.blend(0.5, np.array([0.4, 0.9])).confidence.tolist() == [0.25, 1.0]
    with pytest.raises(ValueError, match="level must be a confidence, not NaN"):
        ScoreCalibration([0.2, 0.5, 0.8], [0.0, 0.6, 1.0]).score_at(float("nan"))


def test_a_frame_given_as_none_is_a_frame_of_none_in_the_whole_file_fits():
    """``persistence`` and ``ScoreCalibration.from_frames`` take an iterable of frames;
    ``None`` among them was passed on to ``observe``, where it means the sequence has
    ended: the sequence was cut there and the outcomes about the cut lost (none at all on
    five frames). The oracle: ``BoxTracker.step``'s reading of None, a frame of no
    detections."""
    frames, _ = frames_with_clutter(np.random.default_rng(3), T=60)
    empty = Detections(boxes=np.zeros((0, 4)))
    with_none = [None if k in (20, 41) else d for k, d in enumerate(frames)]
    with_empty = [empty if k in (20, 41) else d for k, d in enumerate(frames)]
    for a, b in zip(persistence(with_none), persistence(with_empty)):
        np.testing.assert_array_equal(a, b)
    got, want = (ScoreCalibration.from_frames(f, frame_rate=30.0)
                 for f in (with_none, with_empty))
    np.testing.assert_array_equal(got.confidence, want.confidence)
    np.testing.assert_array_equal(got.scores, want.scores)


@pytest.mark.parametrize("call, message", [
    (lambda s, p: ScoreCalibration.fit(s, p, top=True), "top must be a number; got True"),
    (lambda s, p: ScoreCalibration.fit(s, p, top=None), "top must be a number; got None"),
    (lambda s, p: ScoreCalibration.fit(s, p, cap_sigma="5"),
     "cap_sigma must be a number; got '5'"),
    (lambda s, p: ScoreCalibration.fit(s, p).blend(True, s),
     "weight must be a number; got True"),
    (lambda s, p: ScoreCalibrator(link_iou="0.3"), "link_iou must be a number; got '0.3'"),
    (lambda s, p: ScoreCalibrator(frame_rate=None), "frame_rate must be a number; got None"),
    (lambda s, p: ScoreCalibrator(top=True), "top must be a number; got True"),
    (lambda s, p: ScoreCalibrator(prior=True), "prior must be a number; got True"),
    (lambda s, p: ScoreCalibrator(chain_span=True), "chain_span must be a number; got True"),
])
def test_calibration_settings_that_are_no_numbers_are_named(call, message):
    """``top=True`` was taken as 1, the rate of every outcome (the top's persistence 0.455
    against 0.95, every confidence another); text or None failed in a comparison, naming
    nothing. The rule of the package's numeric checks: a boolean is not a number."""
    s, p = np.linspace(0, 1, 40), np.linspace(0, 1, 40) > 0.3
    with pytest.raises(TypeError, match=re.escape(message)):
        call(s, p)


def test_the_calibration_names_boxes_beyond_the_trackers_range():
    """Boxes past ±2^52 pixels (the tracker refuses them) made every overlap's area
    overflow: no detection persisted, and the calibration took every score as confident,
    without a word."""
    frames, _ = frames_with_clutter(np.random.default_rng(1), T=20)
    far = [Detections(boxes=d.boxes * 1e160, scores=d.scores) for d in frames]
    with pytest.raises(ValueError, match=re.escape("detection boxes must lie within ±2^52 "
                                                   "pixels, where a float holds every whole "
                                                   "pixel; boxes[0] = [")):
        persistence(far)
    cal = ScoreCalibrator()
    with pytest.raises(ValueError, match="must lie within ±2\\^52 pixels"):
        cal.observe(far[0])
    assert cal.n == 0

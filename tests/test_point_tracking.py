"""Point trackers: association methods agree where they must, and recover targets in clutter."""

from __future__ import annotations

import re

import numpy as np
import pytest

from vistrack.tracking import POINT_ASSOCIATIONS, PointTracker
from vistrack.types import Detections


def targets(rng, T=60, clutter=0.0, p_detect=1.0, area=200.0, crossing=True):
    """Four targets at constant velocity (two pairs cross, unless not `crossing`), measured
    with unit noise, missed with probability 1 - p_detect, among Poisson clutter of `clutter`
    per unit area."""
    if crossing:
        p0 = np.array([[20.0, 20.0], [20.0, 180.0], [100.0, 10.0], [180.0, 100.0]])
        v = np.array([[2.5, 2.5], [2.5, -2.5], [0.0, 3.0], [-3.0, 0.2]])
    else:
        p0 = np.array([[10.0, 20.0], [10.0, 220.0], [10.0, 420.0], [10.0, 620.0]])
        v = np.array([[2.5, 0.5], [2.0, -0.5], [3.0, 0.3], [2.8, 0.0]])
    truth, frames = [], []
    for f in range(T):
        x = p0 + v * f
        truth.append(x)
        seen = rng.random(4) < p_detect
        z = x[seen] + rng.normal(0, 1, (seen.sum(), 2))
        k = rng.poisson(clutter * area * area)
        frames.append(np.r_[z, rng.uniform(0, area, (k, 2))])
    return np.array(truth), frames


def run(tracker, frames):
    return [tracker.step(f, Detections(points=z)) for f, z in enumerate(frames, 1)]


def recall_and_ids(truth, outputs, start=5, radius=3.0):
    hits, ids = 0, [set() for _ in range(truth.shape[1])]
    for x, out in zip(truth[start:], outputs[start:]):
        if len(out) == 0:
            continue
        d = np.linalg.norm(x[:, None, :] - out.points[None, :, :], axis=-1)
        for k in range(len(x)):
            j = int(np.argmin(d[k]))
            if d[k, j] < radius:
                hits += 1
                ids[k].add(int(out.ids[j]))
    return hits / (truth.shape[1] * (len(truth) - start)), [len(s) for s in ids]


def test_every_association_agrees_without_clutter():
    """Targets far apart, all detected, no clutter: every gate holds one measurement, so GNN,
    NN and greedy are the same Kalman filter, and PDA and JPDA (with P_D P_G = 1 - 1e-9) equal
    it to 1e-6. (IPDA and JIPDA confirm by existence instead: below.)"""
    truth, frames = targets(np.random.default_rng(0), crossing=False)
    runs = {a: run(PointTracker(a, p_detect=1.0, p_gate=1 - 1e-9, frame_rate=1.0), frames)
            for a in POINT_ASSOCIATIONS if a not in ("ipda", "jipda")}
    ref = runs["gnn"]
    for a, outs in runs.items():
        for o, r in zip(outs, ref):
            assert o.ids.tolist() == r.ids.tolist(), a
            np.testing.assert_allclose(o.points, r.points, rtol=1e-6, atol=1e-6, err_msg=a)
    rec, ids = recall_and_ids(truth, ref)
    assert rec > 0.99 and ids == [1, 1, 1, 1]


@pytest.mark.parametrize("association", ["gnn", "pda", "jpda"])
def test_targets_are_kept_in_clutter(association):
    """Crossing targets among about 4 clutter points a frame, 10 % of detections missed (a
    track is reported only in frames it is updated, so about 0.9 is the most): every target is
    followed within 3 noise standard deviations more than 80 % of the time."""
    truth, frames = targets(np.random.default_rng(1), clutter=1e-4, p_detect=0.9)
    tr = PointTracker(association, p_detect=0.9, clutter_density=1e-4, frame_rate=1.0,
                      init_speed=5.0)
    rec, ids = recall_and_ids(truth, run(tr, frames))
    assert rec > 0.8, (rec, ids)
    if association == "jpda":  # joint probabilities keep the crossing targets apart
        assert sum(ids) <= 8, ids


def test_gnn_leaves_a_poor_pair_unassigned_rather_than_take_two():
    """GNN with the gate as the price of a track or a measurement left unassigned (the
    textbook GNN's non-assignment cost): of two tracks and two measurements, where track A
    sits on measurement 1, track B is near it too and A's only other candidate, measurement
    2, lies at the edge of A's gate, the assignment of least total d^2 - gate is A with 1
    alone, B missed and 2 a new track; taking the most pairs would give A measurement 2 and
    B measurement 1, moving both. Checked against a brute force over the matchings, on the
    tracker's own predicted distances."""
    from itertools import permutations

    from vistrack.filters import kf_predict
    from vistrack.models import ConstantPosition, Position
    from vistrack.types import Gaussian

    tr = PointTracker("gnn", motion=ConstantPosition(dim=2, q=0.01),
                      measurement=Position(dim=2, r=1.0), confirm_hits=1, frame_rate=1.0)
    tr.step(1, Detections(points=[[0.0, 0.0], [3.0, 0.0]]))  # tracks A (id 1) and B (id 2)
    t = tr.tracks
    g = kf_predict(Gaussian(t.mean, t.cov), tr.motion.F(1.0), tr.motion.Q(1.0))
    z = np.array([[1.0, 0.0], [-4.1, 0.0]])
    S = tr.H @ g.cov @ tr.H.T + tr.R
    r = z[None, :, :] - (g.mean @ tr.H.T)[:, None, :]
    d2 = np.einsum("kni,kij,knj->kn", r, np.linalg.inv(S), r)
    gate = tr.threshold
    # every matching of tracks to measurements within the gate (None: unassigned)
    best, most = None, None
    for perm in permutations([0, 1, None, None], 2):
        pairs = [(k, n) for k, n in enumerate(perm) if n is not None]
        if len({n for _, n in pairs}) < len(pairs) or any(d2[k, n] > gate for k, n in pairs):
            continue
        # (each pair's likelihood against a track's one frame after an update: the two
        # tracks' innovations are that one here, so the log-determinants add nothing)
        gain = sum(d2[k, n] + np.linalg.slogdet(S[k])[1] - tr._logdet_ref - gate
                   for k, n in pairs)
        if best is None or gain < best[0]:
            best = (gain, sorted(pairs))
        key = (-len(pairs), sum(d2[k, n] for k, n in pairs))
        if most is None or key < most[0]:
            most = (key, sorted(pairs))
    assert best[1] == [(0, 0)] and most[1] == [(0, 1), (1, 0)]  # the two rules differ here
    out = tr.step(2, Detections(points=z))
    # A (reported) at measurement 1; B missed this frame; measurement 2 a new track, id 3,
    # reported at once (confirm_hits=1: its one update confirms it)
    assert out.ids.tolist() == [1, 3] and np.abs(out.points[0] - z[0]).max() < 0.6
    assert tr.tracks.ids.tolist() == [1, 2, 3]
    assert tr.tracks.last_time.tolist() == [2.0, 1.0, 2.0]
    np.testing.assert_allclose(tr.tracks.mean[2, :2], z[1])


def _particles_like(search=5.0, fps=24.0, **kw):
    """The point tracker the command line's ``particles`` tracker builds."""
    from vistrack.pipeline import Context, _particles

    ctx = Context.__new__(Context)
    ctx.overrides, ctx.options, ctx.fps = {"search_range": search, **kw}, {}, fps
    return _particles(ctx)


def test_gnn_gives_a_particle_to_the_track_whose_prediction_is_the_more_likely():
    """Particle 1 is found in every frame and steps 1.5 px; particle 2, missed for 3 frames,
    lies 2.0 px off. On d² alone the track missed, its gate grown, was the cheaper and took
    particle 1's identity (as trackpy does not: it links the shorter step). Oracle: the two
    tracks' Gaussian likelihoods of the measurement, from their own predictions."""
    from vistrack.filters import kf_predict
    from vistrack.types import Gaussian

    tr = _particles_like()
    frames = [[[10, 10], [13.5, 10]], [[10, 10], [13.5, 10]], [[10, 10]], [[10, 10]],
              [[10, 10]], [[11.5, 10]], [[11.5, 10]]]
    seen = []
    for k, p in enumerate(frames):
        if k == 5:  # the tracks' own predictions and likelihoods of the measurement
            t = tr.tracks
            g = kf_predict(Gaussian(t.mean, t.cov), tr.motion.F(1 / 24), tr.motion.Q(1 / 24))
            S = tr.H @ g.cov @ tr.H.T + tr.R
            r = np.array([11.5, 10.0]) - g.mean @ tr.H.T
            d2 = np.einsum("ki,kij,kj->k", r, np.linalg.inv(S), r)
            lik = np.exp(-0.5 * d2) / np.sqrt(np.linalg.det(2 * np.pi * S))
            assert t.ids.tolist() == [1, 2] and d2[1] < d2[0]  # d² alone: track 2's
            assert lik[0] > lik[1]  # the likelihood: track 1's
        seen.append(tr.step(k, Detections(points=np.array(p, float))).ids.tolist())
    assert seen == [[1, 2], [1, 2], [1], [1], [1], [1], [1]]


def test_a_link_is_never_longer_than_max_distance():
    """A track missed for 3 frames has a gate grown to about √4 times its radius one frame
    after an update; with ``max_distance`` a measurement beyond it starts a new track
    however far the gate has grown (trackpy's search range); without it, the track takes
    it."""
    from vistrack.models import ConstantPosition, Position
    from vistrack.pipeline import PARTICLE_GATE, PARTICLE_NOISE

    base = _particles_like()  # (its settings are fixed once made: built again with the cap)
    for cap, ids in ((None, [1]), (5.0, [2])):
        tr = PointTracker("gnn", motion=ConstantPosition(dim=2, q=base.motion.q),
                          measurement=Position(dim=2, r=PARTICLE_NOISE ** 2),
                          frame_rate=base.frame_rate, confirm_hits=1, max_lost=base.max_lost,
                          p_gate=PARTICLE_GATE, max_distance=cap, report="measurement")
        tr.step(0, Detections(points=[[10.0, 10.0]]))
        out = tr.step(4, Detections(points=[[16.5, 10.0]]))  # 6.5 px, 4 frames on
        assert out.ids.tolist() == ids
    with pytest.raises(ValueError, match="max_distance must be a finite number > 0; got 0.0"):
        PointTracker(max_distance=0.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_particles_tracker_links_no_further_than_its_search_range(seed):
    """520 particles diffusing 0.57 px a frame on each axis in 640 x 424 (as trackpy's
    bulk-water clip's), a tenth of the detections missed, 2 % a frame leaving for a new one
    elsewhere: every link, across missed frames too, is at most the search range (the
    positions are filtered, to within 0.1 px of the measurements), and there are no more
    wrong links, by the simulation's identities, than trackpy's ``link`` makes with the same
    range and memory. The grown gate on d² alone made 98, 55 and 79 against trackpy's 86, 38
    and 69 on these three seeds."""
    pd = pytest.importorskip("pandas")
    trackpy = pytest.importorskip("trackpy")
    rng = np.random.default_rng(seed)
    N, T, size = 520, 50, np.array([640.0, 424.0])
    p, ids, frames = rng.uniform(0, 1, (N, 2)) * size, np.arange(N), []
    for _ in range(T):
        keep = rng.random(N) < 0.9
        frames.append((p[keep].copy(), ids[keep]))
        p = p + rng.normal(0, 0.57, (N, 2))
        new = rng.random(N) < 0.02
        p[new] = rng.uniform(0, 1, (new.sum(), 2)) * size
        ids = ids.copy()
        ids[new] = ids.max() + 1 + np.arange(new.sum())
    tr = _particles_like(search=5.0)
    last: dict[int, tuple[np.ndarray, int]] = {}
    wrong, longest = 0, 0.0
    for k, (z, truth) in enumerate(frames):
        out = tr.step(k, Detections(points=z))
        near = np.argmin(((out.points[:, None] - z[None]) ** 2).sum(-1), axis=1)
        assert np.abs(out.points - z[near]).max() < 0.1
        for i, j in zip(out.ids.tolist(), near):
            if i in last:
                longest = max(longest, float(np.hypot(*(z[j] - last[i][0]))))
                wrong += int(last[i][1] != truth[j])
            last[i] = (z[j], truth[j])
    assert 4.0 < longest <= 5.0
    df = pd.concat([pd.DataFrame({"frame": k, "x": z[:, 0], "y": z[:, 1], "truth": truth})
                    for k, (z, truth) in enumerate(frames)], ignore_index=True)
    trackpy.quiet()
    linked = trackpy.link(df, 5.0, memory=3).sort_values(["particle", "frame"])
    same = linked.particle.values[1:] == linked.particle.values[:-1]
    theirs = int((linked.truth.values[1:] != linked.truth.values[:-1])[same].sum())
    assert wrong <= theirs, (wrong, theirs)


def test_point_tracker_arguments():
    with pytest.raises(ValueError, match="association must be one of"):
        PointTracker("mht")
    tr = PointTracker("gnn")
    with pytest.raises(TypeError, match="with points"):
        tr.step(detections=Detections.from_xywh([[0, 0, 1, 1]]))
    with pytest.raises(ValueError, match="points must have 2 coordinates"):
        tr.step(detections=Detections(points=np.zeros((1, 3))))


def one_target_that_leaves(rng, clutter, T=80, leave=30, area=200.0, p_detect=0.9):
    """One target crossing the area at constant velocity, detected with probability
    p_detect until frame `leave` and gone after it, among Poisson clutter."""
    truth, frames = [], []
    for f in range(T):
        x = np.array([20 + 2.0 * f, 100 + 0.5 * f])
        z = [x + rng.normal(0, 1, 2)] if f < leave and rng.random() < p_detect else []
        k = rng.poisson(clutter * area * area)
        frames.append(np.r_[np.reshape(z, (-1, 2)), rng.uniform(0, area, (k, 2))])
        truth.append(x)
    return np.array(truth), frames


@pytest.mark.parametrize("association", ["ipda", "jipda"])
def test_existence_deletes_tracks_of_clutter_that_pda_keeps(association):
    """About 20 clutter points a frame: PDA and JPDA confirm tracks of clutter (3 frames in a
    row with a point in the gate) and keep them, since some point nearly always falls in a
    gate; so they do the track of a target that has gone. With each track's existence, the
    target is followed while it is there and, once it has gone (frame 30), nothing is
    reported in frames 41-80 but the odd track of clutter: over 5 draws, fewer than 0.1
    boxes a frame, where PDA reports more than 2 (4.5 on these draws, IPDA 0.04)."""
    kw = dict(p_detect=0.9, clutter_density=5e-4, frame_rate=1.0, init_speed=5.0)
    found, after, after_pda = [], 0, 0
    for seed in range(5):
        truth, frames = one_target_that_leaves(np.random.default_rng(seed), 5e-4)
        outs = run(PointTracker(association, **kw), frames)
        found += [len(o) > 0 and bool((np.linalg.norm(o.points - x, axis=1) < 3).any())
                  for x, o in zip(truth[5:30], outs[5:30])]
        after += sum(len(o) for o in outs[40:])
        after_pda += sum(len(o) for o in run(PointTracker("pda", **kw), frames)[40:])
    assert np.mean(found) > 0.8
    assert after < 0.1 * 40 * 5 and after_pda > 2 * 40 * 5, (after, after_pda)


def test_jipda_keeps_crossing_targets_in_clutter_without_false_tracks():
    """The crossing targets of test_targets_are_kept_in_clutter: JIPDA follows each as JPDA
    does, and the tracks that JPDA's count of hits confirms on clutter, or on a target that
    another track already follows (two tracks sharing its detections), lose their existence
    instead: over the 55 frames scored, JPDA reports 48 boxes on no target or beyond one a
    target, JIPDA 1."""
    def false_boxes(outs, truth):
        return sum(int((np.linalg.norm(o.points[:, None] - x[None], axis=-1).min(1)
                        >= 3).sum()) + max(0, len(o) - len(x)) for x, o in
                   zip(truth[5:], outs[5:]) if len(o))

    truth, frames = targets(np.random.default_rng(1), clutter=1e-4, p_detect=0.9)
    kw = dict(p_detect=0.9, clutter_density=1e-4, frame_rate=1.0, init_speed=5.0)
    outs = run(PointTracker("jipda", **kw), frames)
    rec, ids = recall_and_ids(truth, outs)
    assert rec > 0.8 and sum(ids) <= 8, (rec, ids)
    assert false_boxes(outs, truth) <= 2
    assert false_boxes(run(PointTracker("jpda", **kw), frames), truth) > 20


@pytest.mark.parametrize("association", ["ipda", "jipda"])
def test_a_track_certain_to_exist_is_still_lowered_by_its_misses(association):
    """With p_survive 1 a target seen for some frames had its existence rounded to 1, and no
    miss lowered it again: it was never deleted by its existence (only by max_lost). The
    prior is kept at most 1 - 2**-40 now. Oracle: IPDA's closed form for a miss with nothing
    in the gate, the odds of existence times B = 1 - P_D P_G each frame, from that cap."""
    kw = dict(p_detect=0.9, clutter_density=1e-4, p_gate=0.99, frame_rate=1.0, max_lost=1e3,
              p_survive=1.0)
    tr = PointTracker(association, **kw)
    for f in range(1, 31):
        tr.step(f, Detections(points=np.array([[50.0, 50.0]])))
    assert tr.existence[0] > 1.0 - 1e-12  # (1.0 exactly before)
    B = 1.0 - 0.9 * 0.99
    odds = (1.0 - 2.0 ** -40) / 2.0 ** -40
    for k in range(1, 40):
        tr.step(30 + k, Detections(points=np.zeros((0, 2))))
        odds *= B
        want = odds / (1.0 + odds)
        if want < 0.01:  # below delete_existence: deleted
            assert len(tr.tracks) == 0 and k == 15
            break
        # (the complement, 1 - existence, to 1e-4: a probability near 1 holds it to 1e-16
        # absolute, 1e-5 of the 1e-11 left after the first miss, carried on by the odds)
        np.testing.assert_allclose(1.0 - tr.existence, [1.0 - want], rtol=1e-4)
    else:
        raise AssertionError("the track was never deleted by its existence")


def test_existence_settings_are_checked():
    with pytest.raises(ValueError, match="p_survive must be in"):
        PointTracker("ipda", p_survive=0.0)
    with pytest.raises(ValueError, match="delete_existence < init_existence"):
        PointTracker("ipda", init_existence=0.005)
    with pytest.raises(ValueError, match="confirm_existence <= 1"):
        PointTracker("jipda", confirm_existence=1.5)
    from vistrack.association import ipda_weights
    with pytest.raises(ValueError, match="existence must be probabilities"):
        ipda_weights(np.ones((1, 1)), np.ones((1, 1), bool), [1.2])
    with pytest.raises(ValueError, match=r"one probability per track, shape \(2,\)"):
        ipda_weights(np.ones((2, 1)), np.ones((2, 1), bool), [0.5])


@pytest.mark.parametrize("association", POINT_ASSOCIATIONS)
def test_frames_not_stepped_delete_what_stepping_them_would_have(association):
    """A track last updated 4 s before, with max_lost 1 s, took the detection of a frame
    stepped to over a gap and kept its identity; stepping the frames between without
    detections deleted it (BoxTracker deletes such tracks before associating)."""
    def points(*p):
        return Detections(points=np.array(p, float))

    skipped = PointTracker(association, frame_rate=1.0, max_lost=1.0)
    skipped.step(1, points([0.0, 0.0]))
    stepped = PointTracker(association, frame_rate=1.0, max_lost=1.0)
    stepped.step(1, points([0.0, 0.0]))
    for f in (2, 3, 4):
        stepped.step(f, None)
    for tr in (skipped, stepped):
        tr.step(5, points([0.5, 0.0]))
    assert skipped.tracks.ids.tolist() == stepped.tracks.ids.tolist() == [2]
    assert len(skipped.existence) == len(skipped.tracks)
    # within max_lost, the gap is bridged: the track keeps its identity
    near = PointTracker(association, frame_rate=1.0, max_lost=5.0)
    near.step(1, points([0.0, 0.0]))
    assert 1 in near.step(3, points([0.5, 0.0])).ids.tolist() + near.tracks.ids.tolist()


def test_a_track_starts_where_a_measurement_of_another_h_puts_it():
    """With H = 2 [I 0] a track started at z itself, so its predicted measurement was 2 z
    and a still target started a new track every frame (ids 1 to 5)."""
    from vistrack.models import LinearMeasurement

    H = np.hstack([2 * np.eye(2), np.zeros((2, 2))])
    tr = PointTracker("gnn", measurement=LinearMeasurement(H, np.eye(2)), frame_rate=10.0,
                      init_speed=1.0)
    for f in range(1, 6):
        out = tr.step(f, Detections(points=[[100.0, 100.0]]))
    assert out.ids.tolist() == tr.tracks.ids.tolist() == [1]
    np.testing.assert_allclose(tr.tracks.mean[0], np.linalg.pinv(H) @ [100.0, 100.0],
                               atol=1e-6)


@pytest.mark.parametrize("setting,message", [
    ({"max_lost": float("nan")}, "max_lost must be a finite number of seconds >= 0; got nan"),
    ({"max_lost": -1.0}, "max_lost must be a finite number of seconds >= 0; got -1.0"),
    ({"confirm_hits": 2.5}, "confirm_hits must be a whole number >= 1; got 2.5"),
    ({"confirm_hits": 0}, "confirm_hits must be a whole number >= 1; got 0"),
    ({"frame_rate": float("inf")}, "frame_rate must be a finite number > 0; got inf"),
    ({"p_gate": 1.0}, "p_gate must be in (0, 1); got 1.0"),
    ({"init_speed": float("nan")}, "init_speed must be a finite number > 0; got nan"),
    # the detection and clutter model were checked at the second frame, by the weights,
    # and in the nearest-neighbour modes never
    ({"association": "pda", "p_detect": 1.5}, "p_detect must be in (0, 1]; got 1.5"),
    ({"association": "gnn", "p_detect": 0.0}, "p_detect must be in (0, 1]; got 0.0"),
    ({"association": "gnn", "clutter_density": float("nan")},
     "clutter_density must be a finite number > 0 (per unit of measurement space); got nan"),
    ({"association": "jpda", "clutter_density": -1.0},
     "clutter_density must be a finite number > 0 (per unit of measurement space); got -1.0"),
])
def test_point_tracker_settings_out_of_range_are_named(setting, message):
    """A NaN max_lost kept lost tracks for ever, 2.5 hits confirmed at 2, an infinite frame
    rate froze time, p_gate 1 was named as chi2_threshold's p, and a p_detect of 1.5 was
    named at the second frame."""
    with pytest.raises(ValueError, match=re.escape(message)):
        PointTracker(**setting)


def test_point_tracks_run_through_the_pipeline_into_a_video_and_a_plot(tmp_path, monkeypatch):
    """Point tracks go through :func:`vistrack.pipeline.run` into the annotated video (a dot
    and a trail each) and the trajectory plot, whose paths are the tracker's points (it
    took box tracks only: "xywh needs box tracks")."""
    from vistrack.io import VideoReader
    from vistrack.pipeline import run as run_pipeline
    from vistrack.types import Frame
    from vistrack.viz import AnnotatedVideo, TrajectoryPlot, plots

    truth, zs = targets(np.random.default_rng(5), T=20)
    frames = [Frame(k, (k - 1) / 10, np.full((220, 220, 3), 90, np.uint8))
              for k in range(1, 21)]
    given = iter(zs)

    class Kept:  # the tracker's own outputs, as the oracle
        def __init__(self):
            self.rows = []

        def write(self, frame, tracks):
            self.rows += [(frame.index, i, x, y) for i, (x, y) in zip(tracks.ids, tracks.points)]

        def close(self):
            pass

    drawn = {}
    real = plots.plot_trajectories
    monkeypatch.setattr(plots, "plot_trajectories", lambda f, i, c, *a, **k: (
        drawn.update(frames=np.array(f), ids=np.array(i), centres=np.array(c)),
        real(f, i, c, *a, **k))[1])
    kept = Kept()
    stats = run_pipeline(frames, lambda frame: Detections(points=next(given)),
                         PointTracker("gnn", frame_rate=10.0),
                         [kept, AnnotatedVideo(tmp_path / "a.mp4", 10),
                          TrajectoryPlot(tmp_path / "t.png", "points")])
    assert stats.frames == 20 and len(kept.rows) > 40
    want = np.array(kept.rows)
    np.testing.assert_array_equal(drawn["frames"], want[:, 0])
    np.testing.assert_array_equal(drawn["ids"], want[:, 1])
    np.testing.assert_array_equal(drawn["centres"], want[:, 2:])
    assert (tmp_path / "t.png").stat().st_size > 0
    assert sum(1 for _ in VideoReader(tmp_path / "a.mp4")) == 20


def test_track_video_given_a_point_tracker_says_where_point_tracks_go(tmp_path):
    """The results files of :func:`~vistrack.pipeline.track_video` are MOTChallenge's
    boxes: a point tracker's tracks are refused at the first frame that has any, naming the
    sink, the frame and where point tracks can go, and no output is left."""
    from vistrack.io import VideoWriter
    from vistrack.pipeline import track_video

    video = tmp_path / "v.mp4"
    with VideoWriter(video, 10) as w:
        for _ in range(5):
            w.write(np.full((64, 80, 3), 90, np.uint8))
    with pytest.raises(ValueError, match=re.escape(
            "frame 1: MOTWriter(" + str(tmp_path / "out" / "tracks.txt") + ") takes box tracks "
            "(MOTChallenge's rows are boxes), and these tracks are points (a PointTracker's): "
            "run them with vistrack.pipeline.run and sinks that take points")):
        track_video(video, tmp_path / "out", fps=10,
                    frontend=lambda f: Detections(points=[[10.0, 20.0]]),
                    tracker=PointTracker("gnn", frame_rate=10.0, confirm_hits=1))
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


@pytest.mark.parametrize("init_speed", [10.0, 15.3, 20.0, 100.0])
def test_gnn_takes_a_lone_measurement_inside_the_gate_however_uncertain_the_track(init_speed):
    """The price of a pair left unassigned is the gate, and GNN's cost adds ln(|S| / |S₁|):
    a track whose |S| exceeded |S₁| by e^χ² could take no measurement, even one on its
    prediction (d² = 0, inside any gate) with no rival. From ``init_speed`` 15.2 at 1 frame/s
    (S = init² + 2⅓ against S₁ = 2⅓ on each axis, 2 ln(S / S₁) ≥ χ²₂(0.99) = 9.21) a point
    standing still started a new track every frame and was never reported after the first.
    Oracle: the measurement on the prediction, the only one, as ``nn`` and ``greedy`` take
    it; and a point moving 3 a frame, inside the gate from the second frame on."""
    for z in (lambda f: [0.0, 0.0], lambda f: [3.0 * f, 1.0]):
        for assoc in ("gnn", "nn", "greedy"):
            tr = PointTracker(assoc, frame_rate=1.0, init_speed=init_speed, confirm_hits=2)
            ids = [tr.step(f, Detections(points=[z(f)])).ids.tolist() for f in range(1, 8)]
            assert ids == [[1]] * 7, (assoc, ids)
            assert tr.tracks.ids.tolist() == [1]


def test_point_tracker_settings_that_broke_later_are_named_when_it_is_made():
    """Position(dim=3) on a motion in 2 read its third coordinate as the first velocity, and
    a point moving (1, 0, 10) a frame started a new track every frame; init_speed 1e155
    overflowed at the first step after the frame was counted (the frame could not be given
    again); frame_rate 1e-300 gave GNN's price NaN; a probability given as a string was
    float()-ed (p_detect) or failed on "'<' not supported"."""
    from vistrack.models import ConstantVelocity, Position

    with pytest.raises(ValueError, match=re.escape(
            "the measurement measures 3 coordinates of a motion in 2: Position(dim=3) with "
            "ConstantVelocity(dim=2, q=1.0)")):
        PointTracker("gnn", motion=ConstantVelocity(dim=2), measurement=Position(dim=3))
    PointTracker("gnn", motion=ConstantVelocity(dim=3), measurement=Position(dim=2))
    with pytest.raises(ValueError, match="init_speed must be below 1e154"):
        PointTracker(init_speed=1e155)
    tr = PointTracker(init_speed=1e153)
    tr.step(1, Detections(points=[[0.0, 0.0]]))
    assert np.isfinite(tr.tracks.cov).all()
    with pytest.raises(ValueError, match="frame_rate 1e-300 makes a frame's process noise"):
        PointTracker(frame_rate=1e-300)
    for name in ("p_detect", "clutter_density", "p_gate", "p_survive", "init_existence",
                 "confirm_existence", "delete_existence"):
        with pytest.raises(TypeError, match=f"^{name} must be a number; got '0.5'$"):
            PointTracker(**{name: "0.5"})
    from fractions import Fraction

    # numbers of other types, as before: a 0-d array, a fraction
    PointTracker(p_detect=np.array(0.9), clutter_density=Fraction(1, 10000))


def test_gnn_ranks_the_pairs_it_takes_past_the_gate_by_their_likelihood():
    """The pairs GNN's price leaves are taken too, ranked by the same likelihood: a track lost
    for a frame (S = 1029 on each axis at 1 frame/s with init_speed 16; d² 0.87, cost d² +
    ln(|S| / |S₁|) = 13.05) and one found in the frame before (S = 258, d² 2.42, cost 11.83)
    both want (25, 0), each over the gate of 9.21: the second takes it, as the likelihood
    says (on d² alone the lost one did)."""
    tr = PointTracker("gnn", frame_rate=1.0, init_speed=16.0, confirm_hits=1)
    out = [tr.step(f, Detections(points=[p])) for f, p in enumerate(([55.0, 0], [0.0, 0],
                                                                      [25.0, 0]), 1)]
    assert [o.ids.tolist() for o in out] == [[1], [2], [2]]


def test_a_gate_probability_of_another_number_type_is_taken():
    """p_gate=np.array(0.5) or Fraction(1, 2) passed the tracker's own check, and then
    chi2_threshold refused it naming "p", an argument the user never gave; the gate is the
    same as for 0.5 (the oracle: scipy's chi-square quantile)."""
    from fractions import Fraction

    from scipy.stats import chi2

    from vistrack.tracking import PointTracker

    for p in (np.array(0.5), Fraction(1, 2), np.float32(0.5)):
        t = PointTracker("pda", p_gate=p)
        assert t.threshold == pytest.approx(chi2.ppf(0.5, t.m), rel=1e-12)


def test_report_measurement_gives_each_track_the_point_it_was_updated_with():
    """tracks.csv of the particles tracker held the filter's estimates, drawn towards each
    track's past: every step shrank, and the mean squared displacement of particles doing a
    random walk came out low (0.071 px² at lag 1 against the true 0.079). With
    report="measurement" each updated track gives the point it took, as trackpy's link does
    (oracle: the points given, and the walk's own variance)."""
    from vistrack.models import ConstantPosition, Position

    rng = np.random.default_rng(3)
    n, T, sig = 40, 60, 0.2
    start = rng.uniform(0, 2000, (n, 2))  # (far apart: no link is in doubt)
    walk = start + np.cumsum(rng.normal(0, sig, (T, n, 2)), axis=0)
    runs = {}
    for report in ("estimate", "measurement"):
        tr = PointTracker("gnn", motion=ConstantPosition(dim=2, q=4 * sig ** 2),
                          measurement=Position(dim=2, r=0.01), frame_rate=1.0, confirm_hits=1,
                          max_distance=2.0, report=report)
        out = [tr.step(t + 1, Detections(points=walk[t])) for t in range(T)]
        runs[report] = out
    for t, o in enumerate(runs["measurement"]):
        # every particle linked, each its own track (ids in the order of the first frame's
        # points), at the point given
        np.testing.assert_array_equal(o.points[np.argsort(o.ids)], walk[t])
    steps = {k: np.diff(np.stack([o.points[np.argsort(o.ids)] for o in v]), axis=0)
             for k, v in runs.items()}
    msd = {k: float((s ** 2).sum(-1).mean()) for k, s in steps.items()}
    truth = float((np.diff(walk, axis=0) ** 2).sum(-1).mean())
    assert msd["measurement"] == pytest.approx(truth, rel=1e-12)
    assert msd["estimate"] < 0.95 * truth  # (what was written before)
    with pytest.raises(ValueError, match="report='measurement' needs an association that "
                                         "gives each track one measurement"):
        PointTracker("jpda", report="measurement")
    with pytest.raises(ValueError, match="report must be 'estimate' or 'measurement'"):
        PointTracker("gnn", report="located")


def test_a_point_tracker_step_that_fails_changes_nothing():
    """Points of 3 coordinates were taken with no track (the frame counted) and, with
    tracks, named as ``z`` after the frame was counted and a stale track deleted; a track
    lost long enough with an accepted ``init_speed`` (1e153 with ``max_lost`` 100 s at 1
    frame/s) overflowed its variance at frame 15, after the frame was counted, and every
    later frame failed until it was deleted. The oracle: the tracker's state before the
    step, and a twin that never saw the refused step."""
    from vistrack.models import ConstantVelocity

    def state(tr):
        t = tr.tracks
        return (tr.frame, t.ids.tolist(), t.mean.tolist(), t.cov.tolist(), t.state.tolist(),
                t.last_time.tolist(), t.scores.tolist(), tr.existence.tolist())

    tr = PointTracker("gnn", frame_rate=1.0)
    with pytest.raises(ValueError, match=re.escape(
            "points must have 2 coordinates; got shape (0, 3)")):
        tr.step(1, Detections(points=np.zeros((0, 3))))
    assert tr.frame is None
    for assoc in ("gnn", "jpda", "jipda"):
        tr = PointTracker(assoc, frame_rate=1.0, max_lost=2.0)
        tr.step(1, Detections(points=[[0.0, 0.0], [50.0, 50.0]]))
        tr.step(2, Detections(points=[[0.0, 0.0]]))
        before = state(tr)
        with pytest.raises(ValueError, match=re.escape("got shape (0, 3)")):
            tr.step(5, Detections(points=np.zeros((0, 3))))
        assert state(tr) == before
        tr.step(5, Detections(points=np.zeros((0, 2))))  # the frame can be given again

    class Breaks(ConstantVelocity):
        """Process noise that is not finite over exactly 2 s, or over 10 s or more (a
        model's failure)."""

        def Q(self, dt):
            Q = super().Q(dt)
            return np.full_like(Q, np.inf) if dt == 2 or dt >= 10 else Q

    with pytest.raises(ValueError, match=re.escape(
            "max_lost 9.5 makes the process noise of a lost track not finite before it is "
            "deleted")):
        PointTracker("gnn", motion=Breaks(dim=2), frame_rate=1.0, max_lost=9.5)
    tr = PointTracker("gnn", motion=Breaks(dim=2), frame_rate=1.0, max_lost=5)
    twin = PointTracker("gnn", motion=Breaks(dim=2), frame_rate=1.0, max_lost=5)
    for f in (1, 2, 3):
        for x in (tr, twin):
            x.step(f, Detections(points=[[0.0, 0.0], [40.0, 0.0]][:1 if f == 3 else 2]))
    before = state(tr)
    with pytest.raises(ValueError, match="Q"):  # (the tracks predicted over 2 s)
        tr.step(5, Detections(points=[[0.0, 0.0]]))
    assert state(tr) == before
    for f in (4, 5):
        a = tr.step(f, Detections(points=[[0.0, 0.0]]))
        b = twin.step(f, Detections(points=[[0.0, 0.0]]))
        assert a.ids.tolist() == b.ids.tolist() and np.array_equal(a.points, b.points)
    assert state(tr) == state(twin)
    with pytest.raises(ValueError, match=re.escape(
            "init_speed times (max_lost + one frame) must be below 1e154 (past it a lost "
            "track's variance, its square, overflows before the track is deleted); got "
            "1e+153 over 101 s")):
        PointTracker("gnn", frame_rate=1.0, init_speed=1e153, max_lost=100.0)
    tr = PointTracker("gnn", frame_rate=1.0, init_speed=1e152, max_lost=8.0)
    tr.step(1, Detections(points=[[0.0, 0.0]]))
    for f in range(2, 12):  # lost, predicted until deleted: every variance finite
        tr.step(f, None)
        assert np.isfinite(tr.tracks.cov).all()
    assert len(tr.tracks) == 0


def test_cluster_groups_hold_whole_clusters_and_every_pair_once(rng):
    """The groups the PDA family is weighed in: every gated pair in exactly one group, at
    its row and column of the group's block; every track and detection in one group only
    (so whole clusters); groups within their size unless one cluster is larger. Oracle:
    `association.components` on the dense gate (numpy's labelling, or scipy's)."""
    from vistrack.association import components
    from vistrack.tracking.point import _cluster_groups

    K, D = 60, 80
    gate = rng.random((K, D)) < 0.02
    gate[:6, :6] = True  # one cluster of 36 pairs, past a size of 30
    r, c = np.nonzero(gate)
    perm = rng.permutation(len(r))
    r, c = r[perm], c[perm]
    _, tl, dl = components(gate)
    for size in (1, 30, 1 << 16):
        seen = np.zeros(len(r), int)
        track_group, det_group = {}, {}
        for g, (rows, cols, sel, lr, lc) in enumerate(_cluster_groups(r, c, K, size)):
            seen[sel] += 1
            assert np.array_equal(rows[lr], r[sel]) and np.array_equal(cols[lc], c[sel])
            assert np.array_equal(rows, np.unique(r[sel])) and np.array_equal(
                cols, np.unique(c[sel]))
            for t in rows.tolist():
                assert track_group.setdefault(t, g) == g
            for d in cols.tolist():
                assert det_group.setdefault(d, g) == g
            labels = set(tl[rows].tolist())
            if len(rows) * len(cols) > size:
                assert len(labels) == 1  # a single cluster larger than the size
        assert (seen == 1).all()
        # every cluster of the oracle's labelling lies in one group
        for lab in set(tl[r].tolist()):
            assert len({track_group[t] for t in np.flatnonzero(tl == lab).tolist()
                        if t in track_group}) == 1
            assert len({det_group[d] for d in np.flatnonzero(dl == lab).tolist()
                        if d in det_group}) == 1
    assert list(_cluster_groups(np.zeros(0, int), np.zeros(0, int), 5)) == []


@pytest.mark.parametrize("association", ["pda", "jpda", "ipda", "jipda"])
def test_the_pda_family_weighed_by_groups_of_clusters_is_the_whole_problem(association,
                                                                          monkeypatch):
    """The PDA family weighs and corrects a group of whole clusters at a time (8,000 points a
    frame took 8 s and 1.8 GB over three frames as one tracks-by-detections problem, 0.4 s
    and 0.22 GB so). Oracle: the same tracker with every cluster in one group, the dense
    problem of the code before, and with each cluster alone: the same identities every
    frame, the same points, covariances and existences to 1e-12 (the weights' sums run
    over another number of zeros), on a field of 150 moving points with misses, clutter
    and a dense knot of 40 detections."""
    import vistrack.tracking.point as point

    def run(size):
        monkeypatch.setattr(point, "_GROUP_SIZE", size)
        rng = np.random.default_rng(5)
        p = rng.uniform(0, 150, (150, 2))
        v = rng.normal(0, 1.0, (150, 2))
        tr = PointTracker(association, frame_rate=10.0, clutter_density=1e-3)
        out = []
        for f in range(15):
            p = p + v * 0.1 + rng.normal(0, 0.3, p.shape)
            seen = rng.random(len(p)) < 0.85
            Z = np.concatenate([p[seen] + rng.normal(0, 0.5, (seen.sum(), 2)),
                                rng.uniform(0, 150, (20, 2))])
            if f == 7:
                Z = np.concatenate([Z, 75 + rng.normal(0, 1.0, (40, 2))])
            res = tr.step(f, Detections(points=Z))
            out.append((res.ids, res.points, res.covs, tr.existence.copy()))
        return out

    whole, alone, grouped = run(1 << 62), run(1), run(1 << 16)
    for a, b, c in zip(whole, alone, grouped):
        for other in (b, c):
            assert np.array_equal(a[0], other[0])
            for x, y in zip(a[1:], other[1:]):
                np.testing.assert_allclose(y, x, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("association", ["ipda", "jipda"])
def test_a_frame_that_fails_leaves_the_existences_as_they_were(association, monkeypatch):
    """The existences of a frame weighed group by group are written into a new array: a step
    interrupted during the correction (Ctrl-C) put back the array it had already changed,
    and the frame given again counted its evidence twice (a track confirmed a frame early);
    a reference taken before a step was changed by it. Oracle: a twin tracker never
    interrupted, and the array as it was."""
    import vistrack.tracking.point as point

    def pts(f):
        return Detections(points=[[0.1 * f, 0.0]])

    kw = dict(frame_rate=10.0, clutter_density=0.01)
    twin, tr = PointTracker(association, **kw), PointTracker(association, **kw)
    twin.step(1, pts(1))
    tr.step(1, pts(1))
    before = tr.existence
    kept = before.copy()

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(point, "pda_update", interrupted)
        with pytest.raises(KeyboardInterrupt):
            tr.step(2, pts(2))
    assert np.array_equal(tr.existence, kept) and np.array_equal(before, kept)
    for f in (2, 3, 4):
        a, b = twin.step(f, pts(f)), tr.step(f, pts(f))
        assert np.array_equal(a.ids, b.ids)
        np.testing.assert_array_equal(tr.existence, twin.existence)
    assert np.array_equal(before, kept)  # (a normal step wrote a new array too)


@pytest.mark.parametrize("association", ["pda", "jpda", "ipda", "jipda"])
def test_a_likelihood_past_the_float_range_is_named_by_the_frame_s_track(association):
    """A gated pair whose likelihood overflows (3-D, variances of 1e-207: the density at the
    mean passes the largest float) is named by its track and measurement in the frame, as
    the weights name it in the tracks-by-measurements matrix; it was named by its row and
    column in its group's block (lik[0, 0] for track 2's measurement 1)."""
    from vistrack.models import ConstantPosition, Position

    tiny = np.exp(-477.0)
    tr = PointTracker(association, motion=ConstantPosition(dim=3, q=tiny),
                      measurement=Position(dim=3, r=tiny), frame_rate=1.0)
    tr.step(1, Detections(points=[[0.0, 0, 0], [100.0, 0, 0], [200.0, 0, 0]]))
    with pytest.raises(ValueError, match=re.escape(
            "lik must be finite and >= 0 inside the gate; lik[2, 1] = inf")):
        tr.step(2, Detections(points=[[900.0, 0, 0], [200.0, 0, 0]]))


@pytest.mark.parametrize("association", ["pda", "jpda", "ipda", "jipda"])
def test_pda_tracks_report_the_score_of_their_most_probable_detection(association):
    """The PDA family's tracks kept the score of the detection they started from (0.3 in
    every frame below), where ``Tracks.scores`` is the score of the detection a track was
    last updated with. Oracle: one detection in the gate each frame, so the most probable
    one is it, and ``gnn``'s scores on the same frames."""
    frames = [(1, 0.3), (2, 0.9), (3, 0.8), (4, 0.7), (5, 0.6)]

    def scores(method):
        tr = PointTracker(method, frame_rate=1.0, confirm_hits=1)
        return [tr.step(f, Detections(points=[[0.1 * f, 0.0]], scores=[s])).scores.tolist()
                for f, s in frames]

    got, want = scores(association), scores("gnn")
    assert want == [[0.3], [0.9], [0.8], [0.7], [0.6]]
    # (the existence-based filters confirm a track some frames after its start)
    assert [g for g in got if g] == [w for g, w in zip(got, want) if g]
    assert got[-1] == [0.6]


@pytest.mark.parametrize("association", ["gnn", "nn", "jpda"])
def test_points_far_past_the_gates_arithmetic_are_named(association):
    """A point 2e154 from a track overflowed the gate's squared distance in scipy's words
    ("The value of p too large for this dataset"), naming no argument; the tracker is as
    it was before the step."""
    tr = PointTracker(association, frame_rate=1.0)
    tr.step(1, Detections(points=[[0.0, 0.0]]))
    with pytest.raises(ValueError, match=re.escape(
            "points must lie within ±1e150, where the gates' squared distances hold; "
            "points[0] = [2e+154, 0.0]")):
        tr.step(2, Detections(points=[[2e154, 0.0], [0.0, 0.0]]))
    assert tr.frame == 1 and tr.step(2, Detections(points=[[1e150, 0.0]])) is not None

"""Learning a box tracker's noise (vistrack.tracking.fit, vistrack.pipeline.fit_sequences,
vistrack fit): against the parameters simulated data were drawn with."""

import re
from dataclasses import replace

import numpy as np
import pytest
import tomllib

from vistrack.cli import main
from vistrack.config import TrackConfig, read_config
from vistrack.models import BoxMotion
from vistrack.pipeline import fit_sequences, track_sequence
from vistrack.tracking.fit import (
    fit_box_motion,
    matched_series,
    measurement_noise,
    smoothed_residual_share,
)


def _simulate(rng, n_objects, T, std_pos, std_vel, std_meas, size=(40.0, 100.0)):
    """Objects moving as BoxMotion's model says, in units of their first size: the true boxes
    and the detections ``[cx, cy, w, h]``, (n, T, 4) each."""
    F = BoxMotion().F(1.0)
    scale = np.array([size[0], size[1], size[0], size[1]])
    x = np.zeros((n_objects, 8))
    x[:, :4] = [0.0, 0.0, 1.0, 1.0]
    x[:, 4:] = rng.normal(0, 0.01, (n_objects, 4)) * [1, 1, 0.1, 0.1]
    truth = np.empty((n_objects, T, 4))
    for t in range(T):
        truth[:, t] = x[:, :4]
        w = rng.normal(size=(n_objects, 8)) * np.repeat([std_pos, std_vel], 4)
        x = x @ F.T + w * np.tile(x[:, 2:4], 4)  # noise scaled by the current size
    noise = rng.normal(size=truth.shape) * np.asarray(std_meas) * truth[..., [2, 3, 2, 3]]
    origin = rng.uniform(100, 1000, (n_objects, 1, 2))
    truth = truth * scale
    truth[..., :2] += origin
    return truth, truth + noise * scale


def _series(truth, dets):
    return [(np.arange(truth.shape[1]), d, g) for g, d in zip(truth, dets)]


def test_measurement_noise_is_the_detections_spread_about_the_truth():
    rng = np.random.default_rng(1)
    truth, dets = _simulate(rng, 200, 30, 0.002, 0.0005, (0.03, 0.02, 0.06, 0.04))
    got = measurement_noise(_series(truth, dets))
    np.testing.assert_allclose(got, [0.03, 0.02, 0.06, 0.04], rtol=0.05)
    # a detector's bias is not noise
    biased = dets + np.array([4.0, -3.0, 2.0, 5.0])
    np.testing.assert_allclose(measurement_noise(_series(truth, biased)), got, rtol=0.05)


@pytest.mark.parametrize("fps, T", [(30.0, 60), (10.0, 30)])
def test_the_motion_noise_of_simulated_boxes_is_found(fps, T):
    """Drawn at ``fps`` from BoxMotion's model with known noise (its values at 30 frames/s
    converted to ``fps``), the learned values at 30 frames/s are the true ones. 300 objects
    of ``T`` frames, 2 s at 30 frames/s: over 1 s the position noise learned scatters from
    draw to draw by more than the 15 % allowed (0.82, 1.14 and 1.06 of the truth for seeds 2,
    5 and 7), over 2 s by 3 % (0.975 to 1.032 over seeds 2 to 7); at 10 frames/s 3 s (the
    sizes, whose noise is a share of the size, drift too far over longer at that rate)."""
    true = BoxMotion(std_pos=0.004, std_vel=0.001, std_meas=(0.03, 0.02, 0.06, 0.04))
    at = true.at_rate(fps)
    rng = np.random.default_rng(2)
    truth, dets = _simulate(rng, 300, T, at.std_pos, at.std_vel, true.std_meas)
    fit = fit_box_motion([(_series(truth, dets), fps)])
    m = fit.motion
    assert m.frame_rate == 30.0 and fit.per_sequence[0]["converged"]
    assert m.std_pos == pytest.approx(true.std_pos, rel=0.15)
    assert m.std_vel == pytest.approx(true.std_vel, rel=0.15)
    np.testing.assert_allclose(m.std_meas, true.std_meas, rtol=0.05)
    # a new track's uncertainty is the start's, not learned
    start = BoxMotion()
    assert m.init_pos * m.std_pos == pytest.approx(start.init_pos * start.std_pos)
    assert m.init_vel * m.std_vel == pytest.approx(start.init_vel * start.std_vel)


def _dense_loglik(Y, F, Q, H, R, P0):
    """The sum over series of log p(y_1, ..., y_{T-1} | y_0), ``Y`` (B, T, 4), from the joint
    Gaussian of a series' states written out whole (no filter): the first state
    N([y_0, 0], P0), each next ``F x + N(0, Q)``, each detection after the first
    ``H x + N(0, R)``."""
    from scipy.stats import multivariate_normal

    B, T, n = Y.shape[0], Y.shape[1], F.shape[0]
    var, powers = [P0], [np.eye(n)]
    for _ in range(1, T):
        var.append(F @ var[-1] @ F.T + Q)
        powers.append(F @ powers[-1])
    cov = np.zeros((T * n, T * n))
    for s in range(T):
        for t in range(s, T):  # Cov(x_t, x_s) = F^(t-s) Var(x_s)
            block = powers[t - s] @ var[s]
            cov[t * n:(t + 1) * n, s * n:(s + 1) * n] = block
            cov[s * n:(s + 1) * n, t * n:(t + 1) * n] = block.T
    Hb = np.kron(np.eye(T - 1), H)
    m0 = np.concatenate([Y[:, 0], np.zeros((B, n - 4))], axis=1)
    means = np.concatenate([m0 @ powers[t].T for t in range(1, T)], axis=1) @ Hb.T
    S = Hb @ cov[n:, n:] @ Hb.T + np.kron(np.eye(T - 1), R)
    return float(np.sum([multivariate_normal(mu, S).logpdf(y)
                         for mu, y in zip(means, Y[:, 1:].reshape(B, -1))]))


def test_the_learned_motion_noise_is_a_maximum_of_the_likelihood():
    """The likelihood reported, and maximised, is that of each series' detections after its
    first, given the first (the first step's prior, with the measurement noise as its
    spread): the joint Gaussian of the states written out whole gives it too."""
    rng = np.random.default_rng(3)
    truth, dets = _simulate(rng, 100, 30, 0.004, 0.001, (0.03, 0.02, 0.06, 0.04))
    series = _series(truth, dets)
    row = fit_box_motion([(series, 30.0)]).per_sequence[0]
    meas = measurement_noise(series)
    Y = np.stack([d / np.array([np.median(g[:, 2]), np.median(g[:, 3])] * 2)
                  for _, d, g in series])
    F, H, R = BoxMotion().F(1.0), np.eye(4, 8), np.diag(meas ** 2)
    m = BoxMotion()
    P0 = np.diag(np.r_[meas ** 2, np.full(4, (m.init_vel * m.std_vel) ** 2)])

    def loglik(sp, sv):
        Q = np.diag(np.repeat([sp ** 2, sv ** 2], 4))
        return _dense_loglik(Y, F, Q, H, R, P0)

    best = loglik(row["std_pos"], row["std_vel"])
    assert best == pytest.approx(row["loglik"], rel=1e-9)
    assert row["detections"] == Y[..., 0].size
    for f in (0.8, 1.25):
        assert loglik(row["std_pos"] * f, row["std_vel"]) < best
        assert loglik(row["std_pos"], row["std_vel"] * f) < best


def test_matched_series_pairs_each_detection_with_one_object():
    ref = np.array([[0, 0, 10, 20], [12, 0, 10, 20], [0, 0, 10, 20], [12, 0, 10, 20.0]])
    det = np.array([[1, 0, 10, 20], [0, 1, 10, 20], [11, 0, 10, 20.0]])
    out = matched_series([1, 1, 2, 2], [1, 2, 1, 2], ref, [1, 2, 2], det, min_length=1)
    # frame 1: one detection near object 1; frame 2: one each
    assert [f.tolist() for f, _, _ in out] == [[1, 2], [2]]
    assert out[0][1][:, 0].tolist() == [6.0, 5.0] and out[1][1][:, 0].tolist() == [16.0]
    assert matched_series([1, 1, 2, 2], [1, 2, 1, 2], ref, [1, 2, 2], det, min_length=2)[0][
        0].tolist() == [1, 2]
    with pytest.raises(ValueError, match="identity 1 appears twice in frame 1"):
        matched_series([1, 1], [1, 1], ref[:2], [1, 1], det[[0, 2]], min_length=1)
    with pytest.raises(ValueError, match="min_iou"):
        matched_series([1], [1], ref[:1], [1], det[:1], min_iou=0)


def test_matched_series_names_the_frame_an_identity_is_duplicated_in():
    """The frame was looked up by its offset from the first: frame 16 named for a duplicate
    in frame 14 (frames 10, 13, 14, 14, 16), an IndexError for one in frame 50 (frames 10,
    50, 50). Oracle: the frames as given."""
    box, far = [0, 0, 10, 20.0], [100, 100, 10, 20.0]
    for frames, dup in (([10, 13, 14, 14, 16], 14), ([10, 50, 50], 50),
                        ([50, 50, 10], 50), ([3, 3, 7, 7], 3), ([10**6, 5, 10**6], 10**6)):
        # the second box of a frame apart from the first: each matches its own detection
        boxes = np.array([far if f in frames[:k] else box for k, f in enumerate(frames)])
        with pytest.raises(ValueError, match=f"identity 7 appears twice in frame {dup} "
                                             r"\(ref_ids\[\d+\] and ref_ids\[\d+\]\)$"):
            matched_series(frames, [7] * len(frames), boxes, frames, boxes, min_length=2)


def test_matched_series_and_measurement_noise_name_what_does_not_fit():
    """Boxes of another count than their frames were used up to the shorter (3 boxes, 2
    frames: one object of 2 detections, without a word) or failed inside numpy (IndexError,
    "operands could not be broadcast"); frames of 1.9 were cut to 1; ``min_length=0`` and
    an empty list of series failed in numpy's reductions. Each is named."""
    ref = np.array([[0, 0, 10, 20], [1, 0, 10, 20], [2, 0, 10, 20.0]])
    for args, kw, message in [
            (([1, 2, 3], [7, 7, 7], ref, [1, 2], ref), {},
             r"det_boxes must be \(2, 4\), a box \[x, y, w, h\] for each of det_frames; "
             r"got shape \(3, 4\)"),
            (([1, 2, 3], [7, 7, 7], ref, [1, 2, 3, 3], ref), {}, r"det_boxes must be \(4, 4\)"),
            (([1, 2, 3], [7, 7], ref, [1, 2, 3], ref), {},
             r"ref_ids must be \(3,\), one for each of ref_frames; got shape \(2,\)"),
            (([1, 2, 3], [7, 7, 7], ref[:, :2], [1, 2, 3], ref), {},
             r"ref_boxes must be \(3, 4\).*got shape \(3, 2\)"),
            (([1, 2], [7, 8], ref[:2], [1], ref[:1]), {"min_length": 0},
             "min_length must be a whole number >= 1; got 0"),
            (([1.9, 2.9], [7, 7], ref[:2], [1, 2], ref[:2]), {},
             r"ref_frames must be whole numbers; ref_frames\[0\] = 1.9"),
            (([1, 2], [7, 7], ref[:2], [1, np.nan], ref[:2]), {},
             r"det_frames must be whole numbers; det_frames\[1\] = nan")]:
        with pytest.raises(ValueError, match=message):
            matched_series(*args, **kw)
    with pytest.raises(ValueError, match="no matched detections: nothing to learn from"):
        measurement_noise([])
    # what fits is taken as before: frames as floats that are whole, one object of three
    out = matched_series([1.0, 2, 3], [7, 7, 7], ref, [1, 2, 3], ref, min_length=1)
    assert [f.tolist() for f, _, _ in out] == [[1, 2, 3]]


def _sequence(folder, rng, n_objects=12, T=60, fps=15.0, std=(0.003, 0.001),
              meas=(0.04, 0.03, 0.08, 0.05)):
    """A MOTChallenge sequence of simulated people: seqinfo.ini, det/det.txt, gt/gt.txt
    (``std``: the motion noise; a long sequence needs little, or sizes wander below 0;
    ``meas``: the detections' noise, fractions of the width and height)."""
    truth, dets = _simulate(rng, n_objects, T, *std, meas)
    (folder / "det").mkdir(parents=True)
    (folder / "gt").mkdir()
    (folder / "seqinfo.ini").write_text(f"[Sequence]\nname={folder.name}\nframeRate={fps}\n"
                                        f"seqLength={T}\nimWidth=1920\nimHeight=1080\n")
    gt_rows, det_rows = [], []
    for t in range(T):
        for i in range(n_objects):
            g, d = truth[i, t], dets[i, t]
            gt_rows.append(f"{t + 1},{i + 1},{g[0] - g[2] / 2:.2f},{g[1] - g[3] / 2:.2f},"
                           f"{g[2]:.2f},{g[3]:.2f},1,1,1")
            det_rows.append(f"{t + 1},-1,{d[0] - d[2] / 2:.2f},{d[1] - d[3] / 2:.2f},"
                            f"{d[2]:.2f},{d[3]:.2f},{rng.uniform(0.6, 1):.3f}")
    (folder / "gt" / "gt.txt").write_text("\n".join(gt_rows) + "\n")
    (folder / "det" / "det.txt").write_text("\n".join(det_rows) + "\n")
    return folder


def test_fit_sequences_from_ground_truth_and_from_a_first_pass(tmp_path):
    rng = np.random.default_rng(4)
    seqs = [_sequence(tmp_path / f"SIM-{k}", rng) for k in range(2)]
    run = fit_sequences(seqs, gt=True)
    assert run.reference == "ground truth" and len(run.fit.per_sequence) == 2
    np.testing.assert_allclose(run.fit.motion.std_meas, [0.04, 0.03, 0.08, 0.05], rtol=0.2)
    assert set(run.held_out) == {"learned", "given"}
    assert all(0 < v["HOTA"] <= 1 for v in run.held_out.values())
    # simulated with the noise learned: it tracks the held-out sequence better than the
    # defaults (HOTA 0.904 against 0.870), so it is the configuration returned
    assert run.held_out["learned"]["HOTA"] > run.held_out["given"]["HOTA"] + 0.01
    assert run.chosen == "learned" and run.config.motion == run.fit.motion
    first = fit_sequences(seqs)  # the offline mode's tracks as the objects
    assert first.reference == "first pass" and first.held_out is None
    # its smoothed boxes follow the detections partly, which the spread about them is
    # divided for (smoothed_residual_share): the errors here are white, and it comes out as
    # the truth does, 0.04, 0.03, 0.08 and 0.05 (within 20 %, as from the ground truth)
    # (undivided, the spread would be 0.3 to 0.8 of it at 15 frames/s)
    np.testing.assert_allclose(first.fit.motion.std_meas, [0.04, 0.03, 0.08, 0.05], rtol=0.2)
    share = smoothed_residual_share(BoxMotion().at_rate(15.0))
    assert 0.3 < np.sqrt(share).min() and np.sqrt(share).max() < 0.8
    # and nothing checks it: the given configuration, whose measurement noise (0.05, 0.05,
    # 0.1, 0.071) is above every value learned here, is returned as it was
    assert first.chosen == "measurement" and first.config == TrackConfig.preset()
    assert fit_sequences(seqs, gt=True, held_out=False).held_out is None
    nogt = _sequence(tmp_path / "NOGT", rng)
    (nogt / "gt" / "gt.txt").unlink()
    with pytest.raises(FileNotFoundError, match="NOGT/gt/gt.txt does not exist"):
        fit_sequences([tmp_path / "SIM-0", nogt], gt=True)
    with pytest.raises(FileNotFoundError, match="nowhere"):
        fit_sequences([tmp_path / "nowhere"])
    with pytest.raises(ValueError, match="no sequences"):
        fit_sequences([])


@pytest.mark.parametrize("file", ["det/det.txt", "gt/gt.txt"])
def test_fit_gt_refuses_a_frame_past_the_sequences_length_as_track_does(tmp_path, file):
    """`fit --gt` learned from detections and ground truth past seqLength unsaid, where
    `vistrack track` refuses such a detections file, naming its line (the oracle here:
    track_sequence's error on the same detections file)."""
    rng = np.random.default_rng(4)
    seq = _sequence(tmp_path / "SIM", rng, T=60)
    path = seq / file
    rows = path.read_text().splitlines()
    line = len(rows) - 5
    rows[line - 1] = "61" + rows[line - 1][rows[line - 1].index(","):]
    path.write_text("\n".join(rows) + "\n")
    said = f"{path}, line {line}: frame 61 is beyond the sequence's 60 frames"
    if file.startswith("det"):
        with pytest.raises(ValueError, match=re.escape(said)):
            track_sequence(seq, tmp_path / "out.txt")
    with pytest.raises(ValueError, match=re.escape(said)):
        fit_sequences([seq], gt=True, held_out=False)


def test_ctrl_c_in_vistrack_fit_says_what_was_kept(tmp_path, monkeypatch, capsys):
    """`vistrack fit` stopped by Ctrl-C said "interrupted" alone, not whether the --out of an
    earlier run was kept (it is: written whole or not at all)."""
    import vistrack.pipeline as pipeline

    seq = _sequence(tmp_path / "SIM", np.random.default_rng(4))

    def stopped(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(pipeline, "fit_sequences", stopped)
    out = tmp_path / "learned.toml"
    assert main(["fit", str(seq), "--out", str(out)]) == 130
    assert capsys.readouterr().err.strip() == "vistrack fit: interrupted; nothing was written"
    assert not out.exists()
    out.write_text("# earlier\n")
    assert main(["fit", str(seq), "--out", str(out), "--force"]) == 130
    assert capsys.readouterr().err.strip() == ("vistrack fit: interrupted; earlier outputs are "
                                               "kept")
    assert out.read_text() == "# earlier\n"


def test_two_sequence_folders_of_one_name_are_two_sequences(tmp_path):
    """a/S and b/S (the same name in two folders): the held-out check scored them under their
    names, so one replaced the other and `vistrack fit` failed with KeyError: 'COMBINED'."""
    rng = np.random.default_rng(4)
    seqs = [_sequence(tmp_path / k / "SIM", rng) for k in ("a", "b")]
    run = fit_sequences(seqs, gt=True)
    assert len(run.fit.per_sequence) == 2 and set(run.held_out) == {"learned", "given"}
    assert all(0 < v["HOTA"] <= 1 for v in run.held_out.values())


def test_fit_returns_the_learned_motion_only_where_it_tracked_held_out_sequences_better(
        tmp_path, monkeypatch, capsys):
    """The held-out check decides: the learned motion is returned (and written) if the
    sequences it was not learned from scored a higher COMBINED HOTA with it, else the given
    configuration as it was, with the learned values in the file's [derived] table;
    ``keep_learned`` (``--keep-learned``) returns them regardless."""
    import vistrack.pipeline as pipeline

    rng = np.random.default_rng(4)
    seqs = [_sequence(tmp_path / f"SIM-{k}", rng) for k in range(2)]

    def scores(learned, given):
        return lambda *a, **k: {"learned": {"HOTA": learned, "MOTA": 0.5, "IDF1": 0.5},
                                "given": {"HOTA": given, "MOTA": 0.5, "IDF1": 0.5}}

    given = TrackConfig.preset()
    for learned_hota, given_hota, chosen in ((0.4, 0.5, "given"), (0.5, 0.5, "given"),
                                             (0.6, 0.5, "learned")):
        monkeypatch.setattr(pipeline, "_held_out", scores(learned_hota, given_hota))
        run = fit_sequences(seqs, gt=True, config=given)
        assert run.chosen == chosen
        assert run.config == (given if chosen == "given" else
                              replace(given, motion=run.fit.motion))
        kept = fit_sequences(seqs, gt=True, config=given, keep_learned=True)
        assert kept.chosen == "learned" and kept.config.motion == kept.fit.motion
    monkeypatch.setattr(pipeline, "_held_out", scores(0.4, 0.5))
    out = tmp_path / "fit.toml"
    assert main(["fit", *map(str, seqs), "--gt", "--out", str(out), "--quiet"]) == 0
    assert "wrote the given one" in capsys.readouterr().out
    table = tomllib.loads(out.read_text())
    assert "motion" not in table and read_config(out) == given
    assert table["derived"]["written"] == "given"
    np.testing.assert_array_equal(table["derived"]["learned_std_meas"],
                                  run.fit.motion.std_meas)
    assert main(["fit", *map(str, seqs), "--gt", "--out", str(out), "--quiet", "--force",
                 "--keep-learned"]) == 0
    table = tomllib.loads(out.read_text())
    assert table["derived"]["written"] == "learned"
    assert read_config(out).motion == run.fit.motion


def test_vistrack_fit_writes_a_configuration_that_track_reads(tmp_path, capsys):
    rng = np.random.default_rng(5)
    seqs = [str(_sequence(tmp_path / f"SIM-{k}", rng)) for k in range(2)]
    out = tmp_path / "fit.toml"
    assert main(["fit", *seqs, "--gt", "--out", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "learned from the ground truth of 2 of 2 sequences" in text
    assert "std_meas w" in text and "held out" in text and f"wrote {out}" in text
    cfg = read_config(out)
    table = tomllib.loads(out.read_text())
    assert table["derived"]["learned_from"] == "ground truth"
    assert cfg.motion.std_pos == table["motion"]["std_pos"]
    # the file is the configuration vistrack track uses
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    assert main(["track", seqs[0], "--out", str(a), "--config", str(out), "--quiet"]) == 0
    track_sequence(seqs[0], b, config=cfg)
    assert a.read_bytes() == b.read_bytes()
    # an existing file is not overwritten without --force
    assert main(["fit", *seqs, "--out", str(out), "--quiet"]) == 2
    assert "--force" in capsys.readouterr().err
    # without ground truth nothing is held out: the given configuration, the detections
    # straying less than it assumes, the learned values in [derived]
    assert main(["fit", *seqs, "--out", str(out), "--quiet", "--force"]) == 0
    assert "the detections straying no more than it assumes" in capsys.readouterr().out
    table = tomllib.loads(out.read_text())
    assert table["derived"]["written"] == "measurement" and "learned_std_meas" in table[
        "derived"]
    assert "motion" not in table and read_config(out) == TrackConfig.preset()
    # --keep-learned writes them all, said to be unchecked
    assert main(["fit", *seqs, "--out", str(out), "--quiet", "--force", "--keep-learned"]) == 0
    assert "not checked on held-out sequences" in capsys.readouterr().out
    assert tomllib.loads(out.read_text())["derived"]["written"] == "learned"


def test_without_ground_truth_only_a_larger_measurement_noise_is_taken(tmp_path, capsys):
    """Learnt from a first pass, nothing checks the values: the given motion noise is kept,
    and each measurement noise is the larger of the given and the learned one. Detections
    straying 0.15 of the width along x and 0.25 of it in width (the defaults assume 0.05 and
    0.1), and less than the defaults in y and height: cx and w raised to what was learned, cy
    and h as given; a given configuration's motion is kept as it is, at its frame rate."""
    rng = np.random.default_rng(6)
    seqs = [_sequence(tmp_path / f"SIM-{k}", rng, meas=(0.15, 0.02, 0.25, 0.03))
            for k in range(2)]
    run = fit_sequences(seqs)
    learned, got = run.fit.motion.std_meas, run.config.motion
    base = BoxMotion()
    assert run.chosen == "measurement"
    assert learned[0] > base.std_meas[0] and learned[2] > base.std_meas[2]
    assert learned[1] < base.std_meas[1] and learned[3] < base.std_meas[3]
    np.testing.assert_array_equal(got.std_meas, [learned[0], base.std_meas[1], learned[2],
                                                 base.std_meas[3]])
    assert (got.std_pos, got.std_vel, got.init_pos, got.init_vel, got.frame_rate) == (
        base.std_pos, base.std_vel, base.init_pos, base.init_vel, base.frame_rate)
    given = replace(TrackConfig.preset(), motion=BoxMotion(std_pos=0.02, std_vel=0.001,
                                                           std_meas=0.4, frame_rate=10.0))
    mine = fit_sequences(seqs, config=given)
    assert mine.config == given  # 0.4 everywhere: nothing learned is larger
    assert fit_sequences(seqs, keep_learned=True).config.motion == run.fit.motion
    out = tmp_path / "fit.toml"
    assert main(["fit", *map(str, seqs), "--out", str(out), "--quiet"]) == 0
    assert "its measurement noise raised to the learned one for cx, w" in capsys.readouterr(
        ).out
    assert read_config(out).motion == got


def test_fit_out_of_another_suffix_is_written_as_toml_and_said(tmp_path, capsys):
    """``fit --out learned.json`` wrote TOML unsaid, where ``track --out results.json`` warns
    that it writes MOTChallenge's text: said the same way; the file is the configuration."""
    rng = np.random.default_rng(5)
    seqs = [str(_sequence(tmp_path / f"SIM-{k}", rng)) for k in range(2)]
    out = tmp_path / "learned.json"
    assert main(["fit", *seqs, "--out", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert f"vistrack fit: warning: {out}: written as TOML" in err and ".json is not" in err
    assert read_config(out) == TrackConfig.preset()
    for name in ("fit.toml", "fit"):  # TOML's suffix, or none: nothing said
        assert main(["fit", *seqs, "--out", str(tmp_path / name), "--quiet"]) == 0
        assert "warning" not in capsys.readouterr().err


def test_a_sequence_given_twice_is_refused(tmp_path, capsys, monkeypatch):
    """One sequence given twice (or by two paths) was learned from twice and "held out" from
    itself: `fit S S ../x/S --gt` reported three times its objects."""
    rng = np.random.default_rng(6)
    seq = _sequence(tmp_path / "SIM", rng)
    other = _sequence(tmp_path / "SIM-B", rng)
    for given in ([seq, seq], [seq, other, tmp_path / "SIM-B" / ".." / "SIM"]):
        with pytest.raises(ValueError, match="given twice"):
            fit_sequences(given, gt=True)
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "fit.toml"
    assert main(["fit", "SIM", str(seq), "--gt", "--out", str(out), "--quiet"]) == 2
    assert "SIM is given twice" in capsys.readouterr().err and not out.exists()
    # distinct sequences: as before
    assert len(fit_sequences([seq, other], gt=True).fit.per_sequence) == 2


def test_a_file_or_a_folder_of_sequences_given_to_fit(tmp_path, capsys):
    """A file given as a sequence was read as its seqinfo.ini ("not a valid INI file", "byte
    16 is not UTF-8", or ".../seqinfo.ini/det/det.txt does not exist"): named as a file now.
    A folder of sequences, which ``vistrack track`` takes for its sequences, said
    "seqinfo.ini does not exist": ``vistrack fit`` takes it for its sequences too, and
    ``fit_sequences`` names it."""
    rng = np.random.default_rng(7)
    seqs = [_sequence(tmp_path / "bench" / f"SIM-{k}", rng) for k in range(2)]
    out = tmp_path / "fit.toml"
    for f in (seqs[0] / "seqinfo.ini", seqs[0] / "det" / "det.txt"):
        assert main(["fit", str(f), "--gt", "--out", str(out), "--quiet"]) == 2
        assert capsys.readouterr().err == (f"vistrack fit: error: {f} is a file, not a sequence "
                                           "folder (seqinfo.ini, det/det.txt)\n")
    assert not out.exists()
    with pytest.raises(FileNotFoundError, match="is a folder of sequences; give the sequence "
                                                "folders in it"):
        fit_sequences([tmp_path / "bench"], gt=True)
    assert main(["fit", str(tmp_path / "bench"), "--gt", "--out", str(out), "--quiet"]) == 0
    assert "learned from the ground truth of 2 of 2 sequences" in capsys.readouterr().out
    assert read_config(out).motion == fit_sequences(seqs, gt=True).config.motion


def test_fit_gt_checks_every_sequence_first_and_leaves_a_folders_test_sequences_out(
        tmp_path, capsys):
    """A sequence without ground truth failed with --gt after the others were learnt from
    (`vistrack fit ../shared/data/mot15 --gt`: TUD-Campus, the ninth); named alone it is
    refused before anything is learnt, with how many lack one, and in a folder of sequences
    it is left out, said in a warning, as `vistrack eval --gt-dir` leaves it out."""
    rng = np.random.default_rng(5)
    root = tmp_path / "set"
    seqs = [_sequence(root / f"SIM-{k}", rng) for k in range(3)]
    (seqs[1] / "gt" / "gt.txt").unlink()
    with pytest.raises(FileNotFoundError) as e:
        fit_sequences(seqs, gt=True, progress=None)
    assert str(e.value) == (f"{seqs[1] / 'gt' / 'gt.txt'} does not exist (--gt learns from "
                            "each sequence's ground truth): 1 of 3 sequences lacks gt/gt.txt")
    out = tmp_path / "fit.toml"
    assert main(["fit", str(root), "--gt", "--out", str(out), "--quiet", "--no-held-out"]) == 0
    captured = capsys.readouterr()
    assert "vistrack fit: warning: 1 of the 3 sequences has no gt/gt.txt and is left out: " \
        "SIM-1" in captured.err
    assert "learned from the ground truth of 2 of 2 sequences" in captured.out
    assert main(["fit", *map(str, seqs), "--gt", "--out", str(out), "--force"]) == 2
    assert "1 of 3 sequences lacks gt/gt.txt" in capsys.readouterr().err


@pytest.mark.parametrize("fps", [30.0, 7.0])
def test_smoothed_residual_share_is_what_a_smoother_leaves_of_white_noise(fps):
    """Oracle: detections of objects moving at constant velocities (which a constant-velocity
    smoother follows without error), with white errors, smoothed with the model's noise by
    :func:`vistrack.filters.kalman_filter` and :func:`~vistrack.filters.smoothers.rts_smooth`
    (time-varying, from a diffuse start); the residuals' variance over the errors' is the
    steady-state share, per value, within 4 % (40 series of 2,000 frames, the first and last
    100 frames, where the smoother is not in its steady state, left out)."""
    from vistrack.filters import kalman_filter
    from vistrack.filters.smoothers import rts_smooth

    m = BoxMotion().at_rate(fps)
    share = smoothed_residual_share(m)
    rng = np.random.default_rng(7)
    F = np.array([[1.0, 1.0], [0.0, 1.0]])
    B, T = 40, 2000
    for i, r in enumerate(m.std_meas):
        Q = np.diag([m.std_pos ** 2, m.std_vel ** 2])
        truth = rng.normal(0, 1, (B, 1)) + rng.normal(0, 0.01, (B, 1)) * np.arange(T)
        z = truth + rng.normal(0, r, (B, T))
        res = kalman_filter(z[..., None], F=F, Q=Q, H=np.array([[1.0, 0.0]]),
                            R=np.array([[r ** 2]]), x0=np.zeros(2), P0=np.diag([1e4, 1e4]))
        smoothed = rts_smooth(res, F=F, Q=Q).means[..., 0]
        resid = (z - smoothed)[:, 100:-100]
        assert abs(resid.var() / r ** 2 - share[i]) < 0.04 * share[i]
    # the limits: a smoother that follows each detection leaves nothing (the smallest
    # positive float where nothing is left at all: something to divide by), one that
    # averages over many leaves all
    assert smoothed_residual_share(BoxMotion(std_meas=1e-4)).max() < 1e-3
    assert (smoothed_residual_share(BoxMotion(std_meas=1e-9).at_rate(1.0)) > 0).all()
    assert smoothed_residual_share(BoxMotion(std_pos=1e-6, std_vel=1e-7)).min() > 0.99


@pytest.mark.filterwarnings("ignore:.*wholly outside the:RuntimeWarning")  # simulated paths
def test_a_first_pass_on_a_detector_run_every_kth_frame_is_divided_at_its_own_rate(tmp_path):
    """A detector run on every 3rd frame: the first pass tracks (and smooths) at a third of
    the frame rate, and the spread about it is divided for that smoother; it comes out as
    the simulated noise, 0.04, 0.03, 0.08 and 0.05 (within 20 %), as on every frame."""
    rng = np.random.default_rng(8)
    seqs = [_sequence(tmp_path / f"SIM-{k}", rng, T=180, std=(0.001, 0.0003)) for k in range(2)]
    for seq in seqs:
        det = seq / "det" / "det.txt"
        rows = det.read_text().splitlines()
        det.write_text("\n".join(r for r in rows if (int(r.split(",")[0]) - 1) % 3 == 0) + "\n")
    with pytest.warns(RuntimeWarning, match="detections on every 3rd frame only"):
        run = fit_sequences(seqs)
    np.testing.assert_allclose(run.fit.motion.std_meas, [0.04, 0.03, 0.08, 0.05], rtol=0.2)


def test_fit_learns_the_same_from_a_detections_file_in_any_row_order(tmp_path, monkeypatch):
    """Two detections tie for an object (the same box moved one pixel left and right: equal
    overlap with its ground-truth box): which one is its measurement was decided by the
    file's row order. Each frame's rows are taken in their own order (the more confident
    first), so the file's order does not change what is learned."""
    rng = np.random.default_rng(7)
    T, w, h = 40, 40, 100
    x = np.round(100 + np.cumsum(rng.normal(2, 1, T)))
    gt = "".join(f"{t + 1},1,{x[t]:.0f},200,{w},{h},1,1,1\n" for t in range(T))
    # the right-hand box scores more; each is exact in the file (whole pixels)
    rows = [[f"{t + 1},-1,{x[t] + 1:.0f},200,{w},{h},0.9", f"{t + 1},-1,{x[t] - 1:.0f},200,"
             f"{w},{h},0.8"] for t in range(T)]

    def sequence(name, flip):
        d = tmp_path / name
        (d / "det").mkdir(parents=True)
        (d / "gt").mkdir()
        (d / "seqinfo.ini").write_text(f"[Sequence]\nname={name}\nframeRate=10\n"
                                       f"seqLength={T}\nimWidth=1920\nimHeight=1080\n")
        (d / "gt" / "gt.txt").write_text(gt)
        (d / "det" / "det.txt").write_text("".join(
            f"{r[::-1][k] if f else r[k]}\n" for r, f in zip(rows, flip) for k in (0, 1)))
        return d

    flips = rng.random(T) < 0.5  # about half the frames with the 0.8 row first
    a = sequence("A", np.zeros(T, bool))
    b = sequence("B", flips)

    def learned(seq):
        run = fit_sequences([seq], gt=True, held_out=False)
        return run.fit.motion, run.fit.per_sequence[0]["std_meas"]

    want = learned(a)
    assert learned(b) == want
    import vistrack.pipeline as pipeline
    monkeypatch.setattr(pipeline, "in_own_order", lambda t: t)
    assert learned(b) != want  # the file's order decided, without


def test_a_series_that_starts_without_a_detection_learns_as_from_its_first():
    """fit_box_motion took each series' first row as its first detection: a series whose
    first frames have none (padded, as the public API allows) failed on "x0 must be finite".
    Oracle: the same series without those rows."""
    rng = np.random.default_rng(9)
    truth, dets = _simulate(rng, 40, 20, 0.004, 0.001, (0.03, 0.02, 0.06, 0.04))
    series = _series(truth, dets)
    padded = [(np.arange(-3, len(t)), np.r_[np.full((3, 4), np.nan), z],
               np.r_[np.full((3, 4), np.nan), g]) for t, z, g in series]
    a, b = (fit_box_motion([(s, 30.0)]).per_sequence[0] for s in (series, padded))
    assert a == b


def test_fit_prints_the_given_noise_at_30_frames_a_second_and_names_short_objects(
        tmp_path, capsys):
    """A --config whose [motion] frame_rate is 10 had its noise printed at 10 beside the
    learned values at 30, under a footer saying both were at 30 (1.7 and 5.2 times off):
    the oracle is BoxMotion.at_rate(30) of the given model. And objects matched in fewer
    than 10 frames, left out, were reported as "no object was matched in two frames or
    more" where every object was matched in 9."""
    rng = np.random.default_rng(7)
    seq = _sequence(tmp_path / "SIM-0", rng)
    given = BoxMotion(std_pos=0.05, std_vel=0.003125, frame_rate=10.0)
    cfg = tmp_path / "cfg10.toml"
    cfg.write_text("[motion]\nstd_pos = 0.05\nstd_vel = 0.003125\nframe_rate = 10.0\n")
    assert main(["fit", str(seq), "--gt", "--no-held-out", "--config", str(cfg), "--out",
                 str(tmp_path / "o.toml"), "--quiet"]) == 0
    rows = {line.split()[0]: line.split() for line in capsys.readouterr().out.splitlines()
            if line.startswith(("std_pos", "std_vel"))}
    at_30 = given.at_rate(30.0)
    assert float(rows["std_pos"][1]) == pytest.approx(at_30.std_pos, rel=1e-3)
    assert float(rows["std_vel"][1]) == pytest.approx(at_30.std_vel, rel=1e-3)
    short = _sequence(tmp_path / "SIM-9", rng, T=9)
    with pytest.raises(ValueError, match="^no object was matched in 10 frames or more in the "
                                         "sequence: nothing to learn from$"):
        fit_sequences([short], gt=True)


def test_matched_series_names_a_box_that_is_no_number_and_any_identity_twice(tmp_path):
    """A NaN box failed inside iou_pairs, named "a" or "b" by its index in its frame, as
    x0, y0, x1, y1 (and a NaN detection in a frame without reference boxes was taken); an
    identity twice in a frame was named only where both rows were matched, and by no file
    from vistrack fit."""
    ref = np.array([[0, 0, 10, 20], [0, 0, 10, 20.0]])
    det = np.array([[0, 0, 10, 20], [5, 5, 10, 20], [1, 0, 10, 20.0]])
    for r, d, message in ((ref, np.r_[det[:2], [[0, 0, np.nan, 10]]],
                           "det_boxes must be finite; det_boxes[2] = [0.0, 0.0, nan, 10.0]"),
                          (np.r_[ref[:1], [[0, 0, 10, np.nan]]], det,
                           "ref_boxes must be finite; ref_boxes[1] = [0.0, 0.0, 10.0, nan]")):
        with pytest.raises(ValueError, match=re.escape(message)):
            matched_series([1, 2], [1, 1], r, [1, 2, 9], d, min_length=1)
    # identity 3 twice in frame 2, neither row matched by any detection
    far = np.array([[500, 500, 10, 20.0]] * 3)
    with pytest.raises(ValueError, match=re.escape("reference identity 3 appears twice in "
                                                   "frame 2 (ref_ids[1] and ref_ids[2])")):
        matched_series([1, 2, 2], [3, 3, 3], far, [1], det[:1], min_length=1)
    seq = _sequence(tmp_path / "SIM-D", np.random.default_rng(2))
    gt = seq / "gt" / "gt.txt"
    lines = gt.read_text().splitlines()
    gt.write_text("\n".join(lines + [lines[0].replace(",1,1,1", ",1,1,1")]) + "\n")
    with pytest.raises(ValueError, match=re.escape(f"{gt}: reference identity 1 appears twice "
                                                   f"in frame 1")):
        fit_sequences([seq], gt=True)

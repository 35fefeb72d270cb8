"""The simulated crowd's detector (``bench/simulated_crowd.py``): with ``--persistence`` a
person's detection is a two-state Markov chain that keeps the rate of detection and makes
misses last, and 0 draws exactly what the independent draws did."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
crowd = pytest.importorskip("simulated_crowd")


def _rows(people=400, frames=250):
    ids = np.repeat(np.arange(people), frames).astype(float)
    fr = np.tile(np.arange(1, frames + 1), people).astype(float)
    order = np.random.default_rng(0).permutation(len(ids))  # rows in any order
    return ids[order], fr[order]


@pytest.mark.parametrize("p, rho", [(0.5, 0.7), (0.8, 0.5), (0.3, 0.9)])
def test_persistence_keeps_the_rate_and_gives_the_chains_transitions(p, rho):
    """Closed form: the chain's stationary rate is ``p``; found after a find with probability
    ``p + rho (1 - p)``, after a miss ``p (1 - rho)`` (100,000 draws: within 4 standard
    errors; the rate's with the chain's ``(1 + rho) / (1 - rho)`` for its correlation)."""
    ids, fr = _rows()
    u = np.random.default_rng(1).random(len(ids))
    seen = crowd._persist(u, np.full(len(ids), p), ids, fr, rho)
    order = np.lexsort((fr, ids))
    s, i = seen[order], ids[order]
    same = i[1:] == i[:-1]
    after_find, after_miss = s[1:][same & s[:-1]], s[1:][same & ~s[:-1]]
    for got, want, n in ((seen.mean(), p, len(seen) * (1 - rho) / (1 + rho)),
                         (after_find.mean(), p + rho * (1 - p), len(after_find)),
                         (after_miss.mean(), p * (1 - rho), len(after_miss))):
        assert abs(got - want) < 4 * np.sqrt(want * (1 - want) / n)


def test_no_persistence_is_the_independent_draw():
    ids, fr = _rows(20, 30)
    u = np.random.default_rng(2).random(len(ids))
    p = np.random.default_rng(3).random(len(ids))
    assert np.array_equal(crowd._persist(u, p, ids, fr, 0.0), u < p)
    e = np.random.default_rng(4).normal(size=len(ids))
    assert crowd._ar1(e, ids, fr, 0.0) is e


def test_score_noise_is_ar1_with_unit_variance():
    """Closed form: an AR(1) process ``rho x + sqrt(1 - rho^2) e`` keeps variance 1 and has
    lag-1 correlation ``rho`` within each person."""
    ids, fr = _rows()
    e = np.random.default_rng(5).normal(size=len(ids))
    x = crowd._ar1(e, ids, fr, 0.6)
    order = np.lexsort((fr, ids))
    xs, i = x[order], ids[order]
    same = i[1:] == i[:-1]
    assert abs(x.var() - 1) < 0.03
    assert abs(np.corrcoef(xs[1:][same], xs[:-1][same])[0, 1] - 0.6) < 0.01


def test_a_source_of_ones_own_is_simulated_in_its_own_images(tmp_path):
    """``--source DIR``: the detector simulated from another sequence's ground truth, its
    considered pedestrians only, its clutter people-sized in proportion to the image's
    height (60-250 pixels in MOT20-01's 1080 rows), the sequence's frames and seqinfo.ini."""
    from vistrack.io import read_mot

    src = tmp_path / "SEQ"
    (src / "gt").mkdir(parents=True)
    rng = np.random.default_rng(0)
    rows = [f"{f},{i},{100 + 20 * i + f},50,20,60,{int(i != 3)},{1 if i != 4 else 7},"
            f"{rng.uniform(0.2, 1):.2f}\n" for f in range(1, 201) for i in range(1, 6)]
    (src / "gt" / "gt.txt").write_text("".join(rows))
    (src / "seqinfo.ini").write_text("[Sequence]\nname=SEQ\nframeRate=30\nseqLength=200\n"
                                     "imWidth=640\nimHeight=480\n")
    d = crowd.simulate(0, 0.5, 1.0, tmp_path / "out", 0.7, src)
    assert d.name == "SEQ-sim0" and (d / "seqinfo.ini").read_text() == (
        src / "seqinfo.ini").read_text()
    det = read_mot(d / "det" / "det.txt")
    assert det.frames.min() >= 1 and det.frames.max() <= 200
    # each person's detections lie on its path (x moved by 0.05 of 20 px, y by 0.03 of 60,
    # standard deviations): persons 1, 2 and 5 are found in most of the 200 frames, person 3
    # (not considered) and 4 (not a pedestrian) never
    on = [(np.abs(det.boxes[:, 0] - det.frames - (100 + 20 * i)) < 5)
          & (np.abs(det.boxes[:, 1] - 50) < 10) for i in range(1, 6)]
    assert [int(k.sum()) > 60 for k in on] == [True, True, False, False, True]
    assert on[2].sum() == 0 and on[3].sum() == 0
    # the rest is clutter, 15 % as many boxes, 60-250 pixels tall scaled by 480 / 1080
    clutter = det.boxes[~np.any(on, axis=0), 3]
    assert len(clutter) == int(0.15 * (len(det) - len(clutter)))
    assert ((clutter >= 60 * 480 / 1080) & (clutter <= 250 * 480 / 1080)).all()


def test_a_configuration_file_is_tracked_beside_the_defaults(tmp_path):
    """``--config FILE`` adds vistrack's rows with FILE's configuration, ``--set`` put over
    it: FILE holding the defaults (as ``--print-config`` writes them), its rows are the
    defaults', and with ``--set`` those of ``--set`` over the defaults; ``--write`` with it
    exits naming the problem."""
    import re
    import subprocess

    from vistrack.config import TrackConfig, config_toml

    src = tmp_path / "SEQ"
    (src / "gt").mkdir(parents=True)
    (src / "gt" / "gt.txt").write_text("".join(
        f"{f},{i},{100 + 60 * i + f},50,20,60,1,1,0.9\n" for f in range(1, 61)
        for i in range(1, 4)))
    (src / "seqinfo.ini").write_text("[Sequence]\nname=SEQ\nframeRate=30\nseqLength=60\n"
                                     "imWidth=640\nimHeight=480\n")
    cfg = tmp_path / "same.toml"
    cfg.write_text(config_toml(TrackConfig.preset().with_motion()))
    bench = Path(crowd.__file__)

    def rows(*extra):
        r = subprocess.run([sys.executable, str(bench), "--draws", "1", "--no-peers",
                            "--source", str(src), *extra],
                           capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr
        return dict(re.findall(r"^\| \*\*(vistrack[^*]*)\*\* \| (.*) \|$", r.stdout, re.M))

    mine = rows("--config", str(cfg))
    assert mine["vistrack, same.toml"] == mine["vistrack"]
    assert mine["vistrack offline, same.toml"] == mine["vistrack offline"]
    over = rows("--config", str(cfg), "--set", "high=0.9", "--set", "new_track=0.95")
    alone = rows("--set", "high=0.9", "--set", "new_track=0.95")
    assert over["vistrack, same.toml, high=0.9, new_track=0.95"] == alone[
        "vistrack, high=0.9, new_track=0.95"]
    assert over["vistrack offline, same.toml, high=0.9, new_track=0.95"] == alone[
        "vistrack offline, high=0.9, new_track=0.95"]
    r = subprocess.run([sys.executable, str(bench), "--config", str(cfg), "--write",
                        str(tmp_path / "x.md")], capture_output=True, text=True, timeout=600)
    assert r.returncode == 1 and "--config's are printed" in r.stderr


@pytest.mark.parametrize("k", [0.5, 2.5])
def test_box_noise_scales_the_boxes_errors(tmp_path, k):
    """``--box-noise K``: the four standard deviations of the boxes' noise times ``K``
    (closed form: the left edge's error over the width ``0.05 K``, the top's over the height
    ``0.03 K``, the log width's ``0.08 K`` and the log height's ``0.05 K``; one person alone in
    2,000 frames, the spreads robust (1.4826 MADs) to the few clutter boxes near it: within
    10 %)."""
    from vistrack.io import read_mot

    src = tmp_path / "SEQ"
    (src / "gt").mkdir(parents=True)
    (src / "gt" / "gt.txt").write_text("".join(
        f"{f},1,300,200,40,100,1,1,1.0\n" for f in range(1, 2001)))
    (src / "seqinfo.ini").write_text("[Sequence]\nname=SEQ\nframeRate=30\nseqLength=2000\n"
                                     "imWidth=640\nimHeight=480\n")
    det = read_mot(crowd.simulate(0, 0.5, 1.0, tmp_path / f"k{k}", 0.0, src, k)
                   / "det" / "det.txt")
    b = det.boxes
    on = (np.abs(b[:, 0] - 300) < 40) & (np.abs(b[:, 1] - 200) < 60) & (
        np.abs(np.log(b[:, 3] / 100)) < 0.5)
    assert on.sum() > 1800  # found in 95 % of the frames (visibility 1)

    def spread(e):
        return 1.4826 * np.median(np.abs(e - np.median(e)))

    got = [spread((b[on, 0] - 300) / 40), spread((b[on, 1] - 200) / 100),
           spread(np.log(b[on, 2] / 40)), spread(np.log(b[on, 3] / 100))]
    assert np.allclose(got, [0.05 * k, 0.03 * k, 0.08 * k, 0.05 * k], rtol=0.1)


@pytest.mark.parametrize("bad", ["0", "-1", "inf", "nan"])
def test_box_noise_must_be_positive_and_finite(bad):
    import subprocess

    r = subprocess.run([sys.executable, str(Path(crowd.__file__)), "--box-noise", bad],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "--box-noise must be > 0 and finite" in r.stderr

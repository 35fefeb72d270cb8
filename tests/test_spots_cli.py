"""``vistrack track FRAMES --frontend spots``: particles in a microscope's frames, from the
command line, against their known positions and beside trackpy's linking."""

from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from vistrack.cli import main

from .test_spots import FRAMES


def _walk(folder, invert=False, seed=0, hidden=()):
    """20 frames (260 x 200) of 16 Gaussian spots (standard deviation 1.8 pixels, 150 grey
    levels above a background of 20, pixel noise 2), each on a random walk of 0.8 pixels a
    step per axis, starting at least 25 pixels apart; dark on light with ``invert``; the
    first particle left out of the frames (numbered from 1) in ``hidden``. Returns the true
    positions ``(frames, 16, 2)``."""
    rng = np.random.default_rng(seed)
    start = []
    while len(start) < 16:
        p = rng.uniform(30, [230, 170])
        if all(np.hypot(*(p - q)) > 25 for q in start):
            start.append(p)
    truth = np.array(start)[None] + np.cumsum(rng.normal(0, 0.8, (20, 16, 2)), axis=0)
    y, x = np.mgrid[0:200, 0:260]
    folder.mkdir()
    for k, pts in enumerate(truth):
        im = 20 + sum(150 * np.exp(-((x - a) ** 2 + (y - b) ** 2) / (2 * 1.8 ** 2))
                      for i, (a, b) in enumerate(pts) if not (i == 0 and k + 1 in hidden))
        im = np.clip(im + rng.normal(0, 2, im.shape), 0, 255).astype(np.uint8)
        cv2.imwrite(str(folder / f"{k + 1:03d}.png"), 255 - im if invert else im)
    return truth


def _rows(path):
    rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    assert path.read_text().splitlines()[0] == "frame,particle,x,y"
    return rows


def test_spots_from_the_command_line_follow_each_particle(tmp_path, capsys):
    """Each of 16 particles on a random walk is one identity in every frame, at its true
    position to within 0.3 pixel (the spots' own accuracy here: test_spots); the same frames
    dark on light with --invert give the same file; the outputs are points (tracks.csv of
    trackpy's columns, the video, the plot), with no tracks.txt of boxes."""
    truth = _walk(tmp_path / "bright")
    out = tmp_path / "out"
    assert main(["track", str(tmp_path / "bright"), "--out-dir", str(out), "--frontend",
                 "spots", "--diameter", "9", "--minmass", "100", "--fps", "10",
                 "--quiet"]) == 0
    said = capsys.readouterr().out
    assert "tracked 20 frames: 320 positions of 16 particles;" in said
    assert sorted(p.name for p in out.iterdir()) == ["annotated.mp4", "run.json",
                                                     "tracks.csv", "trajectories.png"]
    rows = _rows(out / "tracks.csv")
    assert len(rows) == 320
    ids_of = {}
    for k in range(20):
        r = rows[rows[:, 0] == k + 1]
        d = np.linalg.norm(r[:, None, 2:] - truth[k][None], axis=2)
        nearest = d.argmin(1)
        assert d.min(1).max() < 0.3 and len(set(nearest)) == 16
        for i, t in zip(r[:, 1].astype(int), nearest):
            ids_of.setdefault(int(t), set()).add(i)
    assert all(len(v) == 1 for v in ids_of.values())
    assert len(set.union(*ids_of.values())) == 16
    _walk(tmp_path / "dark", invert=True)
    assert main(["track", str(tmp_path / "dark"), "--out-dir", str(tmp_path / "out2"),
                 "--frontend", "spots", "--diameter", "9", "--minmass", "100", "--invert",
                 "--fps", "10", "--quiet"]) == 0
    assert (tmp_path / "out2" / "tracks.csv").read_bytes() == (out / "tracks.csv").read_bytes()


def test_a_particle_missed_for_two_frames_keeps_its_identity_within_max_lost(tmp_path):
    """A particle not found in frames 8 and 9 is taken back as the same identity by default
    (kept 3 frames, 0.35 s at 10 frames/s); with --max-lost 0.1 (one frame) it comes back
    as a new one. Every other particle is one identity either way."""
    truth = _walk(tmp_path / "frames", hidden=(8, 9))
    ids = {}
    for extra in ([], ["--max-lost", "0.1"]):
        out = tmp_path / f"out{len(extra)}"
        assert main(["track", str(tmp_path / "frames"), "--out-dir", str(out), "--frontend",
                     "spots", "--diameter", "9", "--minmass", "100", "--fps", "10", "--quiet",
                     *extra]) == 0
        rows = _rows(out / "tracks.csv")
        of = {}
        for k in range(20):
            r = rows[rows[:, 0] == k + 1]
            d = np.linalg.norm(r[:, None, 2:] - truth[k][None], axis=2)
            for i, t in zip(r[:, 1].astype(int), d.argmin(1)):
                of.setdefault(int(t), set()).add(i)
        assert all(len(of[t]) == 1 for t in range(1, 16))
        ids[len(extra)] = len(of[0])
    assert ids == {0: 1, 2: 2}


def test_box_settings_go_with_box_trackers_and_max_lost_with_particles(tmp_path, capsys):
    """--max-lost is the particles tracker's too; with dcpf it is refused, for one input as
    for several (where it was taken and ignored)."""
    _walk(tmp_path / "a")
    _walk(tmp_path / "a2", seed=1)
    for inputs in ([tmp_path / "a"], [tmp_path / "a", tmp_path / "a2"]):
        assert main(["track", *map(str, inputs), "--out-dir", str(tmp_path / "o"),
                     "--tracker", "dcpf", "--max-lost", "1"]) == 2
        assert ("--max-lost goes with the box trackers (bytetrack, sort) and particles"
                in capsys.readouterr().err)
        assert main(["track", *map(str, inputs), "--out-dir", str(tmp_path / "o"),
                     "--tracker", "dcpf", "--high", "0.5"]) == 2
        assert "--high goes with the box trackers (bytetrack, sort)\n" in capsys.readouterr().err


def test_a_points_run_over_an_earlier_box_run_replaces_its_tracks(tmp_path, capsys):
    """An earlier run's tracks.txt (boxes) in the output folder stops a points run without
    --force, as any output does, and with it is removed: it would read as this run's."""
    _walk(tmp_path / "frames")
    out = tmp_path / "out"
    out.mkdir()
    (out / "tracks.txt").write_text("1,1,0,0,5,5,1,-1,-1,-1\n")
    args = ["track", str(tmp_path / "frames"), "--out-dir", str(out), "--frontend", "spots",
            "--diameter", "9", "--fps", "10", "--quiet"]
    assert main(args) == 2
    assert "tracks.txt exists; pass --force to overwrite it" in capsys.readouterr().err
    assert main([*args, "--force"]) == 0
    assert not (out / "tracks.txt").exists() and (out / "tracks.csv").exists()


@pytest.mark.parametrize("extra, message", [
    ([], "--frontend spots needs --diameter: the spots' diameter in pixels, odd (round up)"),
    (["--diameter", "8"], "--diameter must be an odd number of pixels >= 3; got 8"),
    (["--diameter", "9", "--minmass", "-1"], "--minmass must be a finite number >= 0; got -1"),
    # (inf meets "> 0" and ">= 0": the words now name the rule it breaks)
    (["--diameter", "9", "--minmass", "inf"], "--minmass must be a finite number >= 0; got inf"),
    (["--diameter", "9", "--search-range", "inf"],
     "--search-range must be a finite number of pixels > 0; got inf"),
    (["--diameter", "9", "--fps", "inf"],
     "--fps must be a finite number > 0 (frames a second); got inf"),
    (["--diameter", "9", "--tracker", "bytetrack"],
     "--frontend spots finds points, and --tracker bytetrack tracks boxes: track spots with "
     "--tracker particles (the default with them)"),
    (["--diameter", "9", "--tracker", "dcpf"], "--tracker dcpf tracks boxes"),
    (["--diameter", "9", "--tracker", "single:csrt"], "--tracker single:csrt tracks boxes"),
    (["--diameter", "9", "--search-range", "3", "--tracker", "sort"],
     "--search-range goes with --tracker particles, not sort"),
    (["--diameter", "9", "--search-range", "0.3"],
     "--search-range must be above 0.53 pixels (the gate of the positions' own noise); got "
     "0.3"),
    (["--diameter", "9", "--max-lost", "-1"],
     "--max-lost must be a finite number of seconds >= 0; got -1"),
    (["--gt", "gt.txt"], "--frontend spots needs --diameter"),  # (the diameter named first)
    (["--diameter", "9", "--still-camera"],
     "--still-camera goes with the box trackers (bytetrack, sort)"),
])
def test_spots_options_are_checked_by_name(tmp_path, monkeypatch, capsys, extra, message):
    """Each mistake is named before anything is written."""
    _walk(tmp_path / "frames")
    (tmp_path / "gt.txt").write_text("1,1,10,10,5,5,1,1,1\n")
    monkeypatch.chdir(tmp_path)
    assert main(["track", "frames", "--out-dir", "out", "--frontend", "spots", "--fps", "10",
                 "--quiet", *extra]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_spots_and_particles_go_together(tmp_path, capsys):
    """Spots' options with another front-end, the particles tracker with a front-end of
    boxes, --out (a sequence's boxes) with spots, and, for several inputs too, a missing
    --diameter or box settings: each named before anything runs. From Python the same
    pairs are refused by track_video."""
    from vistrack.pipeline import track_video

    _walk(tmp_path / "frames")
    _walk(tmp_path / "more", seed=1)
    frames, out = str(tmp_path / "frames"), str(tmp_path / "o")
    for args, message in (
            ([frames, "--out-dir", out, "--frontend", "hog", "--diameter", "9"],
             "--diameter goes with --frontend spots, not --frontend hog"),
            ([frames, "--out-dir", out, "--tracker", "particles", "--frontend", "hog"],
             "--tracker particles links points, and --frontend hog finds boxes: give it "
             "--frontend spots"),
            ([frames, "--out", str(tmp_path / "r.txt"), "--frontend", "spots"],
             "--out (a sequence's detections) goes with the box trackers (bytetrack, sort); "
             "--frontend spots, tracked by particles, goes with --out-dir"),
            ([frames, str(tmp_path / "more"), "--out-dir", out, "--frontend", "spots"],
             "--frontend spots needs --diameter"),
            ([frames, str(tmp_path / "more"), "--out-dir", out, "--frontend", "spots",
              "--diameter", "9", "--tracker", "sort"], "--tracker sort tracks boxes"),
            ([frames, str(tmp_path / "more"), "--out-dir", out, "--frontend", "spots",
              "--diameter", "9", "--config", str(tmp_path / "c.toml")],
             "--config goes with the box trackers (bytetrack, sort)")):
        assert main(["track", *args]) == 2, args
        assert message in capsys.readouterr().err, args
        assert not (tmp_path / "o").exists()
    with pytest.raises(ValueError, match="the spots front-end finds points, and the dcpf "
                                         "tracker tracks boxes"):
        track_video(frames, out, frontend="spots", diameter=9, tracker="dcpf", fps=10)
    with pytest.raises(ValueError, match="the particles tracker links points, and the hog "
                                         "front-end finds boxes"):
        track_video(frames, out, frontend="hog", tracker="particles", fps=10)
    with pytest.raises(ValueError, match="zero_distance scores the tracks against gt: give "
                                         "gt too"):
        track_video(frames, out, frontend="spots", diameter=9, zero_distance=4, fps=10)
    with pytest.raises(ValueError, match="the spots front-end needs the spots' diameter"):
        track_video(frames, out, frontend="spots", fps=10)
    assert not (tmp_path / "o").exists()


def test_a_points_run_is_scored_against_ground_truth_points(tmp_path, capsys):
    """``--gt TRUTH.csv`` (frame, particle, x, y) with spots: the particles are scored by
    distance, by default at the diameter (a match within a particle's radius), or at
    ``--zero-distance``, as vistrack eval scores tracks.csv afterwards; run.json keeps the
    scores. Before, --gt was refused with points. The true walks: every particle found and
    followed (MOTA 1, no switch). ``--zero-distance`` without --gt is refused."""
    import json

    from vistrack.evaluation import evaluate_files

    truth = _walk(tmp_path / "frames")
    gt = tmp_path / "truth.csv"
    gt.write_text("frame,particle,x,y\n" + "".join(
        f"{k + 1},{i + 1},{x!r},{y!r}\n" for k, pts in enumerate(truth.tolist())
        for i, (x, y) in enumerate(pts)))
    for extra, zero in (([], 9.0), (["--zero-distance", "3"], 3.0)):
        out = tmp_path / f"out{zero:g}"
        assert main(["track", str(tmp_path / "frames"), "--out-dir", str(out), "--frontend",
                     "spots", "--diameter", "9", "--minmass", "100", "--fps", "10", "--gt",
                     str(gt), *extra]) == 0
        shown = capsys.readouterr().out.splitlines()
        want = evaluate_files([("frames", gt, out / "tracks.csv", None)], zero_distance=zero)
        scores = want["frames"]
        assert scores.MOTA == 1.0 and scores.IDSW == 0 and scores.TP == truth.shape[0] * 16
        assert shown[-1].split()[:2] == ["frames", f"{100 * scores.HOTA:.1f}"]
        assert json.loads((out / "run.json").read_text())["scores"] == json.loads(
            json.dumps(scores.summary()))
    assert main(["track", str(tmp_path / "frames"), "--out-dir", str(tmp_path / "o2"),
                 "--frontend", "spots", "--diameter", "9", "--zero-distance", "3"]) == 2
    assert "--zero-distance goes with --gt" in capsys.readouterr().err


def test_a_points_run_has_a_report_page(tmp_path, capsys):
    """A particles run's page (--report, or vistrack report on its folder): its counts in
    positions of particles, the scores against --gt and the plots of HOTA over α and the
    timeline, scored by distance as the run was (the distance run.json keeps). Before, the
    page was refused: it showed box tracks only."""
    import json

    from vistrack.evaluation import evaluate_files

    truth = _walk(tmp_path / "frames")
    gt = tmp_path / "truth.csv"
    gt.write_text("frame,particle,x,y\n" + "".join(
        f"{k + 1},{i + 1},{x!r},{y!r}\n" for k, pts in enumerate(truth.tolist())
        for i, (x, y) in enumerate(pts)))
    out = tmp_path / "out"
    assert main(["track", str(tmp_path / "frames"), "--out-dir", str(out), "--frontend",
                 "spots", "--diameter", "9", "--minmass", "100", "--fps", "10", "--gt",
                 str(gt), "--report", "--quiet"]) == 0
    capsys.readouterr()
    page = (out / "report.html").read_text()
    assert "20 frames of" in page and "320 positions of 16 particles" in page
    assert page.count("<img ") == 3  # trajectories, HOTA over α, the timeline
    assert json.loads((out / "run.json").read_text())["zero_distance"] == 9
    scores = evaluate_files([("f", gt, out / "tracks.csv", None)], zero_distance=9)["f"]
    assert f"<td>{100 * scores.HOTA:.1f}</td>" in page
    assert main(["report", str(out), "--force"]) == 0  # (the WebM inside differs run to run)
    again = (out / "report.html").read_text()
    assert "320 positions of 16 particles" in again and again.count("<img ") == 3


def test_bulk_water_from_the_command_line_links_as_trackpy_does(tmp_path, capsys):
    """trackpy's bulk-water clip (50 frames, about 520 particles each) from the command line
    with its defaults (search range half the diameter, a particle kept 3 frames), beside
    trackpy's locate and link (search range 5 px, memory 3) on the same frames: every one of
    trackpy's positions has a particle of ours within 0.5 pixel, and 99.4 % of trackpy's
    trajectories are one identity of ours throughout (measured)."""
    tp = pytest.importorskip("trackpy")
    import pandas as pd
    from scipy.spatial import cKDTree

    files = sorted(FRAMES.glob("*.png"))
    if not files:
        pytest.skip(f"{FRAMES} not found: the shared data is not beside this checkout")
    out = tmp_path / "out"
    assert main(["track", str(FRAMES), "--out-dir", str(out), "--frontend", "spots",
                 "--diameter", "11", "--invert", "--minmass", "20", "--fps", "24",
                 "--quiet"]) == 0
    ours = pd.read_csv(out / "tracks.csv")
    tp.quiet()
    # as the video reader gives the frames: colour, made grey by the spots front-end
    grey = [cv2.cvtColor(cv2.imread(str(f)), cv2.COLOR_BGR2GRAY) for f in files]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        links = tp.link(tp.batch(grey, 11, invert=True, minmass=20), 5, memory=3)
    near, ids_of = [], {}
    for k in range(len(files)):
        o, t = ours[ours.frame == k + 1], links[links.frame == k]
        d, j = cKDTree(o[["x", "y"]].values).query(t[["x", "y"]].values)
        near.append(d < 0.5)
        for pid, i, ok in zip(t.particle.values, o.particle.values[j], d < 0.5):
            if ok:
                ids_of.setdefault(pid, set()).add(int(i))
    assert np.concatenate(near).all()
    assert np.mean([len(v) == 1 for v in ids_of.values()]) > 0.99


def test_spots_that_find_nothing_say_what_was_looked_for(tmp_path, capsys):
    """A mass threshold above every spot's finds nothing: the run says what it looked for
    and what to change, and writes a header-only tracks.csv."""
    _walk(tmp_path / "frames")
    out = tmp_path / "out"
    assert main(["track", str(tmp_path / "frames"), "--out-dir", str(out), "--frontend",
                 "spots", "--diameter", "9", "--minmass", "1e6", "--fps", "10", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert ("the spots front-end found nothing in 20 frames (bright spots of diameter 9 whose "
            "mass is above 1e+06; for dark spots on a light background, --invert, or another "
            "--diameter or --minmass): the results hold no rows") in err
    assert (out / "tracks.csv").read_text() == "frame,particle,x,y\n"

"""The tracker's configuration: TOML written and read back, every `vistrack track` setting,
and bad files and values named."""

from __future__ import annotations

import math
import re
import shutil
import subprocess
import sys
from dataclasses import fields, replace
from pathlib import Path

import numpy as np
import pytest

from vistrack.config import ConfigError, OfflineConfig, TrackConfig, config_toml, read_config
from vistrack.data import demo_clip
from vistrack.io import read_mot, write_mot
from vistrack.io.motchallenge import read_seqinfo
from vistrack.models import BoxMotion
from vistrack.pipeline import resolve_config, track_sequence

from .test_tracking import scene

CLI = [sys.executable, "-m", "vistrack.cli", "track"]


@pytest.fixture(scope="module")
def seq(tmp_path_factory):
    """A MOTChallenge sequence folder of the tests' scene: 150 frames at 25 frames/s, scores
    on a raw scale of 0-16."""
    d = tmp_path_factory.mktemp("seq") / "SCENE"
    (d / "det").mkdir(parents=True)
    _, dets = scene(np.random.default_rng(11), clutter=2.0)
    f = np.concatenate([np.full(len(x), k) for k, x in enumerate(dets, start=1)])
    b = np.concatenate([x.xywh for x in dets])
    s = 16 * np.concatenate([x.scores for x in dets]) - 1
    write_mot(d / "det" / "det.txt", f, -np.ones(len(f), int), b, s)
    (d / "seqinfo.ini").write_text("[Sequence]\nname=SCENE\nimDir=img1\nframeRate=25\n"
                                   "seqLength=150\nimWidth=1000\nimHeight=1000\nimExt=.jpg\n")
    return d


def cli(*args):
    return subprocess.run(CLI + [str(a) for a in args], capture_output=True, text=True)


def test_a_configuration_reads_back_as_written(tmp_path):
    """Every preset, and one with values of every kind changed (a float, an integer, a bool,
    a string, infinity, the motion's four measurement noises, the offline mode), is read back
    equal."""
    changed = TrackConfig.preset("bytetrack").with_values(
        tracker={"high": 0.55, "confirm_hits": 3, "camera_motion": False, "scores": "raw",
                 "new_track": 0.9, "calibration_cap_sigma": math.inf, "calibration_window": 0,
                 "coast_rate": 0.4, "coast_window": 0.5},
        motion={"std_meas": (0.03, 0.04, 0.05, 0.06), "frame_rate": 25.0},
        offline={"enabled": True, "max_gap": 0.75})
    for cfg in (TrackConfig.preset("bytetrack"), TrackConfig.preset("sort"), changed):
        path = tmp_path / "c.toml"
        path.write_text(config_toml(cfg, {"frame_rate": 25.0, "high_score": 3.5}))
        back = read_config(path)
        assert back == cfg
        assert back.name == cfg.name and back.tracker == cfg.tracker
        assert back.offline == cfg.offline
        if cfg.motion is not None:
            for k in ("std_pos", "std_vel", "init_pos", "init_vel", "frame_rate"):
                assert getattr(back.motion, k) == getattr(cfg.motion, k)
            np.testing.assert_array_equal(back.motion.std_meas, cfg.motion.std_meas)


def test_a_partial_file_keeps_the_presets_other_values(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('[tracker]\nname = "sort"\nhigh = 0.4\n\n[offline]\nmax_gap = 2\n')
    cfg = read_config(path)
    assert cfg.name == "sort" and cfg.tracker.high == 0.4 and cfg.offline.max_gap == 2.0
    assert cfg.tracker.confirm_hits == 3 and not cfg.tracker.two_stage  # sort's own
    assert cfg.motion is None  # the front-end's default motion


@pytest.mark.parametrize("text,match", [
    ("[tracker\nhigh = 0.5\n", r"not valid TOML: .*line 1, column 9"),
    ("[trakcer]\nhigh = 0.5\n", "unknown table or key 'trakcer'"),
    ("[tracker]\nhihg = 0.5\n", r"\[tracker\] has no key 'hihg'; did you mean 'high'\? "
                                r"\(keys: assigner"),
    ("[tracker]\nmax_gap = 0.5\n", r"\[tracker\] has no key 'max_gap'; it is a key of "
                                   r"\[offline\] \(keys: assigner"),
    ("[offline]\nzzz = 1\n", r"\[offline\] has no key 'zzz' \(keys: calibration_iou_min, enabled"),
    ("[tracker]\nhigh = \"0.5\"\n", r"\[tracker\] high must be a number; got '0.5'"),
    ("[tracker]\nconfirm_hits = 2.5\n", r"\[tracker\] confirm_hits must be an integer"),
    ("[tracker]\ncalibration_window = -1\n",
     r"\[tracker\] calibration_window must be an integer >= 0"),
    ("[tracker]\ncalibration_cap_sigma = 0\n", r"\[tracker\] calibration_cap_sigma must be > 0"),
    ("[tracker]\ncoast_rate = 1.5\n", r"\[tracker\] coast_rate must be in \[0, 1\]; got 1.5"),
    ("[tracker]\ncoast_window = 0\n",
     r"\[tracker\] coast_window must be a number of seconds > 0 and at most 1e\+09"),
    ("[tracker]\ncamera_motion = 1\n", r"\[tracker\] camera_motion must be true or false"),
    ("[tracker]\nname = \"deepsort\"\n", r"\[tracker\] name must be one of \['bytetrack', "
                                         r"'sort'\]"),
    ("[tracker]\nhigh = 1.5\n",
     r"\[tracker\] high must be in \[0, 1\] \(a calibrated confidence\)"),
    ("[motion]\nstd_meas = [0.1, 0.2]\n", r"std_meas must be a number or a list of 4"),
    ("[motion]\nstd_pos = -1\n", r"\[motion\] std_pos must be a finite number > 0"),
    ("[offline]\nmax_gap = -1\n", r"\[offline\] max_gap must be a finite number >= 0"),
    ("[offline]\nstart_score = 2.0\n",
     r"\[offline\] start_score must be in \[0, 1\] \(a calibrated"),
    ("tracker = 3\n", "tracker must be a table"),
    # a name that is no string ("unhashable type: 'list'", naming neither file nor key), and
    # an integer beyond int64 (read, printed, then an OverflowError in the middle of the run)
    ('[tracker]\nname = ["sort"]\n', r"\[tracker\] name must be one of .*; got \['sort'\]"),
    ("[tracker]\nname = 3\n", r"\[tracker\] name must be one of .*; got 3"),
    ("[tracker]\ncamera_min_matches = 9223372036854775808\n",
     r"\[tracker\] camera_min_matches must be an integer from -9223372036854775808 to "
     r"9223372036854775807; got 9223372036854775808"),
    ("[tracker]\nconfirm_hits = -9223372036854775809\n",
     "confirm_hits must be an integer from"),
    # a check across two keys of a table names the table too (it named none)
    ("[tracker]\nhigh = 0.2\nlow = 0.5\n", r"bad.toml:3: \[tracker\] low must be at most high"),
])
def test_a_bad_file_is_named_with_its_key(tmp_path, text, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=match) as e:
        read_config(path)
    assert str(path) in str(e.value)
    # and with the line that sets the key (the table, for a table that is wrong); TOML's own
    # syntax errors give theirs in its words
    lines = text.splitlines()
    line = (1 if text.startswith(("[trakcer]", "tracker =", "[tracker\n")) else
            3 if "low = 0.5" in text else 2)
    assert len(lines) >= line
    if not text.startswith("[tracker\n"):
        assert str(e.value).startswith(f"{path}:{line}: "), (str(e.value), lines[line - 1])


@pytest.mark.parametrize("text, line, match", [
    # under a header, after comments, blank lines and other tables; a quoted key
    ('# mine\n\n[motion]\nstd_pos = 0.1\n\n[tracker]  # the box tracker\nname = "sort"\n'
     '"high" = 1.5\n', 8, r"\[tracker\] high must be in \[0, 1\]"),
    # a dotted key at the top, and an inline table
    ('offline.enabled = true\noffline.max_gap = -2\n', 2, r"\[offline\] max_gap must be"),
    ('motion = { std_pos = 0.1, std_vel = -1 }\n', 1, r"\[motion\] std_vel must be"),
    # a key of the same name in another table before it is not the one; a table in a table
    ('[tracker]\nmax_lost = 1\n[offline]\nmax_lost = 1\n', 4,
     r"\[offline\] has no key 'max_lost'; it is a key of \[tracker\]"),
    ('[tracker]\nhigh = 0.5\n[offline]\n[tracker.deeper]\nx = 1\n', 4,
     r"\[tracker\] has no key 'deeper'"),
    # a check across keys: the line of the key the message is about
    ('[tracker]\nlow = 0.3\nhigh = 0.2\n', 2, r"\[tracker\] low must be at most high"),
    # an array of tables where a table goes
    ('# mine\n[[tracker]]\nhigh = 0.5\n', 2, r"tracker must be a table \(\[tracker\]\)"),
    # a table misspelt is named with a near one
    ('# mine\n[trackr]\nhigh = 0.5\n', 2, r"unknown table or key 'trackr'; did you mean "
                                             r"\[tracker\]\?"),
    # a line separator in a comment ends no line (it was counted as one, a line too far)
    ('# a\u2028b\n[tracker]\nhigh = 2\n', 3, r"\[tracker\] high must be"),
])
def test_a_bad_key_is_named_by_its_line(tmp_path, text, line, match):
    """The message opens with FILE:LINE where LINE is the line that sets the key (counted
    from 1, as editors count)."""
    path = tmp_path / "c.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError, match=match) as e:
        read_config(path)
    assert str(e.value).startswith(f"{path}:{line}: "), str(e.value)


def test_bad_files_and_values_on_the_command_line(seq, tmp_path):
    missing = cli(seq, "--out", tmp_path / "r.txt", "--config", tmp_path / "none.toml")
    assert missing.returncode == 2 and "none.toml does not exist (--config FILE)" in \
        missing.stderr
    (tmp_path / "s.toml").write_text('[tracker]\nname = "sort"\n')
    r = cli(seq, "--out", tmp_path / "r.txt", "--config", tmp_path / "s.toml", "--tracker",
            "bytetrack")
    assert r.returncode == 2 and "--tracker bytetrack disagrees with [tracker] name" in r.stderr
    r = cli(seq, "--out", tmp_path / "r.txt", "--high", "1.5")
    assert r.returncode == 2 and "--high: high must be in [0, 1]" in r.stderr
    # --low above --high left the second stage no detection, without a word
    r = cli(seq, "--out", tmp_path / "r.txt", "--low", "0.9", "--high", "0.3")
    assert r.returncode == 2 and not (tmp_path / "r.txt").exists()
    assert ("--high, --low: low must be at most high with two_stage (the second stage takes the "
            "detections between them); got low 0.9 above high 0.3") in r.stderr
    # both below the default low (0.3), given together: set together, not --high checked
    # against the default low first (which refused them)
    r = cli(seq, "--out", tmp_path / "hl.txt", "--high", "0.2", "--low", "0.1", "--print-config")
    assert r.returncode == 0, r.stderr
    assert "\nhigh = 0.2\n" in r.stdout and "\nlow = 0.1\n" in r.stdout
    r = cli(seq, "--out", tmp_path / "h.txt", "--high", "0.2")
    assert r.returncode == 2 and "--high: low must be at most high" in r.stderr
    # the one-stage tracker has no second stage: its low is not compared
    r = cli(seq, "--out", tmp_path / "sort.txt", "--tracker", "sort", "--high", "0.4")
    assert r.returncode == 0, r.stderr
    r = cli(seq, "--out", tmp_path / "r.txt", "--offline", "--start-score", "1.5")
    assert r.returncode == 2 and "--start-score: start_score must be in [0, 1]" in r.stderr
    # a track's mean confidence above 1 dropped every track (0 boxes, exit status 0)
    r = cli(seq, "--out", tmp_path / "r.txt", "--offline", "--min-track-score", "2")
    assert r.returncode == 2 and "--min-track-score: min_track_score must be in [0, 1]" in \
        r.stderr and not (tmp_path / "r.txt").exists()
    r = cli(seq, "--out-dir", tmp_path / "v", "--min-track-score", "0.5")
    assert r.returncode == 2 and "--offline, its settings and --detections go with --out" in \
        r.stderr
    r = cli(seq, "--out-dir", tmp_path / "v", "--link-gap", "0")  # a zero is a value given
    assert r.returncode == 2 and "--offline, its settings and --detections go with --out" in \
        r.stderr
    # dcpf reads its own table: a box tracker's file is named, at its line, with the table
    # dcpf reads (it said --config went with the box trackers alone)
    r = cli(seq, "--out-dir", tmp_path / "v", "--tracker", "dcpf", "--config",
            tmp_path / "s.toml")
    assert r.returncode == 2 and (f"{tmp_path / 's.toml'}:1: unknown table or key 'tracker'; "
                                  "it is the box trackers' table (bytetrack, sort), and "
                                  "--tracker dcpf reads [dcpf]") in r.stderr
    r = cli(seq, "--out-dir", tmp_path / "v", "--tracker", "particles", "--config",
            tmp_path / "s.toml")
    assert r.returncode == 2 and \
        "--config goes with the box trackers (bytetrack, sort) and dcpf" in r.stderr
    # raw scores of -1 to 15: refused before tracking, naming the file, the scores' range and
    # the way out on the command line (it named a Python argument and frame 1)
    r = cli(seq, "--out", tmp_path / "r.txt", "--scores", "raw")
    det = read_mot(seq / "det" / "det.txt")
    assert r.returncode == 2 and (
        f"{seq / 'det' / 'det.txt'}: scores from {det.conf.min():.4g} to {det.conf.max():.4g}, "
        "but with raw scores (--scores raw) the first association stage weighs IoU by the "
        "score, which must lie in [0, 1]: calibrate them (--scores calibrated, the default), or "
        "turn the weighing off (fuse_score = false under [tracker] in a --config file") in \
        r.stderr and not (tmp_path / "r.txt").exists()
    (tmp_path / "raw.toml").write_text('[tracker]\nscores = "raw"\nhigh = 5.0\nlow = 1.0\n'
                                       'new_track = 8.0\nfuse_score = false\n')
    r = cli(seq, "--out", tmp_path / "r.txt", "--config", tmp_path / "raw.toml")
    assert r.returncode == 0 and len(read_mot(tmp_path / "r.txt")) > 0, r.stderr


@pytest.mark.parametrize("offline", [False, True])
def test_print_config_read_back_gives_identical_tracks(seq, tmp_path, offline):
    """`--print-config` writes TOML alone to stdout (the summary to stderr), with the values
    derived from the data; read back with `--config` it tracks the sequence identically."""
    flags = ["--offline"] if offline else []
    r = cli(seq, "--out", tmp_path / "a.txt", "--print-config", "--high", "0.5", *flags)
    assert r.returncode == 0, r.stderr
    assert "wrote" in r.stderr and "wrote" not in r.stdout
    (tmp_path / "used.toml").write_text(r.stdout)
    assert "high = 0.5" in r.stdout and "[derived]" in r.stdout
    assert "frame_rate = 25.0" in r.stdout and "new_track_score = " in r.stdout
    assert f"enabled = {'true' if offline else 'false'}" in r.stdout
    r = cli(seq, "--out", tmp_path / "b.txt", "--config", tmp_path / "used.toml")
    assert r.returncode == 0, r.stderr
    a, b = (tmp_path / "a.txt").read_text(), (tmp_path / "b.txt").read_text()
    assert a == b and len(a.splitlines()) > 500
    # the file given to track_sequence's config, as a path or its name (it was taken for a
    # preset's: "tracker must be one of ['bytetrack', 'sort']; got '.../used.toml'")
    from vistrack.pipeline import track_sequence

    for k, config in enumerate((tmp_path / "used.toml", str(tmp_path / "used.toml"))):
        track_sequence(seq, tmp_path / f"api{k}.txt", config=config)
        assert (tmp_path / f"api{k}.txt").read_text() == a


def test_print_config_of_a_run_given_fps_warns_where_read_back_without_it(seq, tmp_path):
    """The frame rate is the input's, not a setting: a file printed by a run given ``--fps``
    and read back without it tracked at the sequence's own rate, other tracks without a
    word. The file records the option ([derived] fps_option); read back without it (or with
    another) the run warns, and with it the tracks are identical."""
    r = cli(seq, "--out", tmp_path / "a.txt", "--print-config", "--fps", "12.5")
    assert r.returncode == 0, r.stderr
    (tmp_path / "used.toml").write_text(r.stdout)
    assert "fps_option = 12.5" in r.stdout and "frame_rate = 12.5" in r.stdout
    warning = (f"vistrack track: warning: {tmp_path / 'used.toml'} was printed by a run given "
               "--fps 12.5 ([derived] fps_option), tracked at 12.5 frames/s; this run tracks "
               "at ")
    r = cli(seq, "--out", tmp_path / "b.txt", "--config", tmp_path / "used.toml")
    own = f"{read_seqinfo(seq).frame_rate:g}"
    assert r.returncode == 0 and warning + f"{own} (its input's frame rate): give --fps " \
        "12.5 for that run's tracks" in r.stderr, r.stderr
    assert (tmp_path / "b.txt").read_text() != (tmp_path / "a.txt").read_text()
    r = cli(seq, "--out", tmp_path / "c.txt", "--config", tmp_path / "used.toml", "--fps", "10")
    assert r.returncode == 0 and warning + "10 (--fps 10)" in r.stderr, r.stderr
    # printed with --fps the input's own rate: read back without it, the same tracks, and
    # nothing to warn of (it warned, from --fps alone)
    r = cli(seq, "--out", tmp_path / "f.txt", "--print-config", "--fps", own)
    (tmp_path / "own.toml").write_text(r.stdout)
    r = cli(seq, "--out", tmp_path / "g.txt", "--config", tmp_path / "own.toml")
    assert r.returncode == 0 and "warning" not in r.stderr, r.stderr
    assert (tmp_path / "g.txt").read_text() == (tmp_path / "f.txt").read_text()
    r = cli(seq, "--out", tmp_path / "d.txt", "--config", tmp_path / "used.toml", "--fps",
            "12.5")
    assert r.returncode == 0 and "warning" not in r.stderr, r.stderr
    assert (tmp_path / "d.txt").read_text() == (tmp_path / "a.txt").read_text()
    # printed without --fps: nothing recorded, nothing to warn of
    r = cli(seq, "--out", tmp_path / "e.txt", "--print-config")
    assert r.returncode == 0 and "fps_option" not in r.stdout


def test_a_config_file_is_read_once_a_command(seq, tmp_path, monkeypatch, capsys):
    """The configuration and the warnings about it (``--still-camera`` where the file sets
    no camera motion, ``--fps`` other than the one it was printed with) come from one read
    of the file: it was read three times, so a file rewritten meanwhile could track with
    one content and warn of another. Counted at the file system (every read of its bytes or
    text)."""
    from pathlib import Path

    from vistrack.cli import main

    file = tmp_path / "used.toml"
    file.write_text("[tracker]\ncamera_motion = false\n[derived]\nfps_option = 12.5\n")
    reads = []
    for name in ("read_bytes", "read_text"):
        real = getattr(Path, name)

        def counted(self, *a, _real=real, **k):
            if self == file:
                reads.append(self)
            return _real(self, *a, **k)

        monkeypatch.setattr(Path, name, counted)
    assert main(["track", str(seq), "--out", str(tmp_path / "a.txt"), "--config", str(file),
                 "--still-camera"]) == 0
    err = capsys.readouterr().err
    assert f"--still-camera changes nothing here: {file} sets camera_motion = false" in err
    assert f"{file} was printed by a run given --fps 12.5" in err
    assert len(reads) == 1


def test_a_bad_config_file_is_named_before_an_existing_out(seq, tmp_path, capsys):
    """A mistake in --config is reported even where --out exists: the run said "pass
    --force" first, and only the run given --force named the file's mistake. Several inputs
    already read the file first."""
    from vistrack.cli import main

    bad = tmp_path / "bad.toml"
    bad.write_text("[tracker]\nhihg = 0.5\n")
    out = tmp_path / "exists.txt"
    out.write_text("1,1,0,0,1,1,1,-1,-1,-1\n")
    assert main(["track", str(seq), "--out", str(out), "--config", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "has no key 'hihg'; did you mean 'high'?" in err and "--force" not in err
    assert out.read_text() == "1,1,0,0,1,1,1,-1,-1,-1\n"


@pytest.mark.parametrize("flags", [[], ["--high", "0.5", "--offline"], ["--tracker", "sort"],
                                   ["--config", "FILE", "--max-lost", "1"]])
def test_print_config_without_input_is_what_a_run_prints(seq, tmp_path, flags):
    """`vistrack track --print-config` without INPUT prints, for the same options, what a run
    of a sequence's detections prints but its [derived] table, and tracks nothing; read back
    with `--config` it tracks as those options do."""
    (tmp_path / "file.toml").write_text('[tracker]\nhigh = 0.55\n[motion]\nstd_pos = 0.04\n')
    flags = [str(tmp_path / "file.toml") if f == "FILE" else f for f in flags]
    (tmp_path / "empty").mkdir()
    alone = subprocess.run(CLI + ["--print-config", *flags], capture_output=True, text=True,
                           cwd=tmp_path / "empty")
    assert alone.returncode == 0 and alone.stderr == "", alone.stderr
    assert list((tmp_path / "empty").iterdir()) == []  # nothing written
    run = cli(seq, "--out", tmp_path / "a.txt", "--print-config", *flags)
    assert run.returncode == 0, run.stderr
    head = run.stdout.split("\n[derived]")[0]
    text, note = alone.stdout.split("\n# a run adds [derived]")
    assert text == head and "vistrack track INPUT --out FILE --print-config" in note
    (tmp_path / "used.toml").write_text(alone.stdout)
    back = cli(seq, "--out", tmp_path / "b.txt", "--config", tmp_path / "used.toml")
    assert back.returncode == 0, back.stderr
    a, b = (tmp_path / "a.txt").read_text(), (tmp_path / "b.txt").read_text()
    assert a == b and len(a.splitlines()) > 500


@pytest.mark.parametrize("flags, message", [
    ([], "the following arguments are required: INPUT"),
    (["--print-config", "--out", "r.txt"],
     "--out goes with INPUT; without one, --print-config prints the configuration the other "
     "options give"),
    (["--print-config", "--frontend", "hog"],
     "--frontend goes with INPUT; without one, --print-config prints the configuration the "
     "other options give"),
    (["--print-config", "--fps", "25"],
     "--fps goes with INPUT; without one, --print-config prints the configuration the other "
     "options give"),
    (["--print-config", "--tracker", "particles"],
     "--print-config goes with the box trackers (bytetrack, sort) and dcpf"),
    (["--print-config", "--tracker", "dcpf", "--high", "0.5"],
     "--high goes with the box trackers (bytetrack, sort)"),
    (["--print-config", "--tracker", "dcpf", "--offline"],  # (it printed dcpf's, unsaid)
     "--offline goes with the box trackers (bytetrack, sort)"),
    (["--print-config", "--high", "2"],
     "--high: high must be in [0, 1] (a calibrated confidence); got 2.0"),
])
def test_print_config_without_input_refuses_what_belongs_to_a_run(tmp_path, flags, message):
    """Without INPUT only the configuration's options are taken: one that belongs to a run
    is named, as is a bad value; nothing is written."""
    r = subprocess.run(CLI + flags, capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.splitlines()[-1] == f"vistrack track: error: {message}"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("offline", [False, True])
def test_a_detections_file_alone_tracks_as_its_sequence_would(seq, tmp_path, offline):
    """A detections file alone, at `--fps`, is tracked as a sequence folder whose
    seqinfo.ini gives that frame rate, the file's last frame and an image as large as its
    boxes reach; a folder without seqinfo.ini, at `--fps`, the same; and `--fps` is put over
    a seqinfo.ini's frameRate."""
    det = read_mot(seq / "det" / "det.txt")
    far = det.boxes[:, :2] + det.boxes[:, 2:]

    def folder(name, rate, info=True):
        d = tmp_path / name
        (d / "det").mkdir(parents=True)
        shutil.copy(seq / "det" / "det.txt", d / "det" / "det.txt")
        if info:
            (d / "seqinfo.ini").write_text(
                f"[Sequence]\nname={name}\nframeRate={rate}\nseqLength={det.frames.max()}\n"
                f"imWidth={math.ceil(far[:, 0].max())}\nimHeight={math.ceil(far[:, 1].max())}\n")
        return d

    flags = ["--offline"] if offline else []
    runs = {"given": [folder("GIVEN", 12.5)],
            "alone": [seq / "det" / "det.txt", "--fps", "12.5"],
            "no seqinfo": [folder("BARE", 25, info=False), "--fps", "12.5"],
            "put over": [folder("OVER", 25), "--fps", "12.5"],
            "25 frames/s": [folder("AT25", 25)]}
    text = {}
    for key, args in runs.items():
        r = cli(*args, "--out", tmp_path / f"{key}.txt", *flags)
        assert r.returncode == 0, (key, r.stderr)
        assert f"over {det.frames.max()} frames from {len(det)} detections" in r.stdout
        text[key] = (tmp_path / f"{key}.txt").read_text()
    assert len(text["given"].splitlines()) > 500
    assert text["alone"] == text["given"] == text["no seqinfo"] == text["put over"]
    # the frame rate is the one given: at 25 frames/s the same file tracks otherwise
    assert text["25 frames/s"] != text["given"]


# every option: its value in the configuration used, and the same tracks as the API's
OPTIONS = [("--scores", "raw", "scores", "raw"), ("--high", "0.7", "high", 0.7),
           ("--low", "0.5", "low", 0.5), ("--new-track", "0.9", "new_track", 0.9),
           ("--min-iou", "0.5", "min_iou", 0.5), ("--confirm-hits", "3", "confirm_hits", 3),
           ("--max-lost", "0.05", "max_lost", 0.05), ("--max-gap", "0.04", "max_gap", 0.04),
           ("--min-track-score", "0.99", "min_track_score", 0.99),
           ("--start-score", "14.5", "start_score", 14.5),
           ("--link-gap", "0", "link_gap", 0.0), ("--still-camera", None, "camera_motion",
                                                  False)]
OFFLINE_KEYS = {f.name for f in fields(OfflineConfig)}
# raw scores of -1 to 15 need thresholds on their scale (raw.toml below holds them too)
RAW = dict(scores="raw", high=12.0, low=2.0, new_track=13.0, fuse_score=False)


@pytest.mark.parametrize("option,value,key,expected", OPTIONS)
def test_each_option_sets_its_value(seq, tmp_path, option, value, key, expected):
    flags = [option] + ([value] if value is not None else [])
    offline = key in OFFLINE_KEYS
    if offline:
        flags.append("--offline")
    # with calibrated scores every track of this scene starts at a confidence of 1: the
    # start's threshold is tried on the raw scores
    raw = key in ("scores", "start_score")
    if raw:
        flags = ([] if key == "scores" else flags) + ["--config", tmp_path / "raw.toml"]
        (tmp_path / "raw.toml").write_text(config_toml(resolve_config(**RAW)))
    r = cli(seq, "--out", tmp_path / "cli.txt", "--print-config", *flags)
    assert r.returncode == 0, r.stderr
    line = f"{key} = " + (f'"{expected}"' if isinstance(expected, str) else
                          str(expected).lower() if isinstance(expected, bool) else
                          repr(expected))
    assert line in r.stdout.splitlines(), (line, r.stdout)
    base = RAW if key == "start_score" else {}
    run = track_sequence(seq, tmp_path / "api.txt", offline=offline,
                         **{**(RAW if raw else {}), key: expected})
    default = track_sequence(seq, tmp_path / "default.txt", offline=offline, **base)
    cli_rows, api_rows = (tmp_path / "cli.txt").read_text(), (tmp_path / "api.txt").read_text()
    assert cli_rows == api_rows
    if key != "link_gap":  # nothing to join in this scene
        assert api_rows != (tmp_path / "default.txt").read_text(), key
    assert run.config.tracker != default.config.tracker or \
        run.config.offline != default.config.offline


def test_resolve_config_puts_values_over_a_preset():
    cfg = resolve_config("sort", offline=True, high=0.4, max_gap=0.5,
                         motion=BoxMotion(std_meas=0.04))
    assert cfg.name == "sort" and cfg.tracker.high == 0.4 and cfg.offline.enabled
    assert cfg.offline.max_gap == 0.5 and float(cfg.motion.std_meas[0]) == 0.04
    assert resolve_config(tracker="sort").name == "sort"
    with pytest.raises(ValueError, match="tracker 'sort' and the configuration's 'bytetrack'"):
        resolve_config(TrackConfig.preset(), tracker="sort")
    with pytest.raises(TypeError, match="hgh"):
        resolve_config(hgh=0.4)
    assert replace(OfflineConfig(), enabled=True).enabled
    with pytest.raises(ValueError, match="enabled must be true or false"):
        OfflineConfig(enabled=1)
    # at 0 any two tracks within link_gap were joined, however far apart
    with pytest.raises(ValueError, match=r"link_iou must be in \(0, 1\] \(at 0 any two tracks"):
        OfflineConfig(link_iou=0.0)
    assert OfflineConfig(link_iou=0.0, link_gap=0.0).link_iou == 0.0  # (no joining)


def test_each_flat_override_names_one_setting():
    """``resolve_config(**overrides)`` puts a name to the tracker's settings or the offline
    mode's: no name may be both (the tracker's calibration IoU was once ``link_iou``, the
    offline joining's too, and an override of it reached the offline mode only)."""
    from vistrack.tracking import BoxTrackerConfig

    tracker = {f.name for f in fields(BoxTrackerConfig)}
    assert not tracker & {f.name for f in fields(OfflineConfig)}
    cfg = resolve_config(calibration_iou=0.5, link_iou=0.4)
    assert cfg.tracker.calibration_iou == 0.5 and cfg.offline.link_iou == 0.4


def test_offline_settings_without_the_offline_mode_say_they_change_nothing(seq, tmp_path):
    """``--max-gap`` or ``--start-score`` without ``--offline`` gave the online tracks, byte
    for byte, without a word; the run now says so. With ``--offline``, or a configuration file
    that turns it on, nothing is said."""
    r = cli(seq, "--out", tmp_path / "a.txt", "--max-gap", "2", "--start-score", "0.9")
    assert r.returncode == 0 and ("vistrack track: warning: --max-gap, --start-score: offline "
                                  "settings, which change nothing without --offline") in r.stderr
    r = cli(seq, "--out", tmp_path / "b.txt", "--max-gap", "2", "--offline")
    assert r.returncode == 0 and "warning" not in r.stderr
    (tmp_path / "off.toml").write_text("[offline]\nenabled = true\n")
    r = cli(seq, "--out", tmp_path / "c.txt", "--max-gap", "2", "--config", tmp_path / "off.toml")
    assert r.returncode == 0 and "warning" not in r.stderr
    assert (tmp_path / "b.txt").read_bytes() == (tmp_path / "c.txt").read_bytes()
    # SORT has one stage: its low threshold is read by nothing
    r = cli(seq, "--out", tmp_path / "s.txt", "--tracker", "sort", "--low", "0.1")
    assert r.returncode == 0 and ("vistrack track: warning: --low: the second association "
                                  "stage's threshold, which changes nothing with a tracker of "
                                  "one stage (sort)") in r.stderr


def test_still_camera_where_the_camera_is_taken_as_still_anyway_says_so(seq, tmp_path):
    """``--still-camera`` with SORT (which estimates no camera motion), with a configuration
    file that turns the camera's motion off, or from pixels with the bgsub front-end and
    MOG2 (a background model that cannot follow the view) gave the same tracks, byte for
    byte, without a word; the run now says so. With the default tracker, which estimates the
    camera's motion (test_cli_still_camera_turns_camera_motion_off), nothing is said."""
    import cv2

    for extra, why in ((["--tracker", "sort"], "--tracker sort does not estimate the camera's "
                        "motion"),
                       (["--config", tmp_path / "still.toml"],
                        f"{tmp_path / 'still.toml'} sets camera_motion = false")):
        (tmp_path / "still.toml").write_text("[tracker]\ncamera_motion = false\n")
        r = cli(seq, "--out", tmp_path / "a.txt", *extra, "--still-camera", "--force")
        assert r.returncode == 0 and (f"vistrack track: warning: --still-camera changes nothing "
                                      f"here: {why}") in r.stderr
        r = cli(seq, "--out", tmp_path / "b.txt", *extra, "--force")
        assert r.returncode == 0 and "warning" not in r.stderr
        assert (tmp_path / "a.txt").read_bytes() == (tmp_path / "b.txt").read_bytes()
    r = cli(seq, "--out", tmp_path / "c.txt", "--still-camera")
    assert r.returncode == 0 and "warning" not in r.stderr
    frames = tmp_path / "frames"
    frames.mkdir()
    for k in range(8):
        img = np.zeros((60, 80, 3), np.uint8)
        img[20:40, 5 + 5 * k:25 + 5 * k] = 255
        cv2.imwrite(str(frames / f"{k + 1:06d}.png"), img)
    # from pixels, the selective background model follows a view that moves unless told
    # the camera is still: the option is heard (a still view's tracks the same); MOG2's
    # model cannot follow one, so there it changes nothing
    for out, extra in (("v1", ["--still-camera"]), ("v2", []),
                       ("v3", ["--background", "mog2", "--still-camera"])):
        r = cli(frames, "--out-dir", tmp_path / out, "--min-area", "50", "--quiet", *extra)
        assert r.returncode == 0, r.stderr
        assert ("--still-camera changes nothing here: the bgsub front-end with --background "
                "mog2 takes the camera as still" in r.stderr) == (out == "v3")
        assert "changes nothing" not in r.stderr or out == "v3"
    assert (tmp_path / "v1" / "tracks.txt").read_bytes() == \
        (tmp_path / "v2" / "tracks.txt").read_bytes()
    # with a tracker or a file that estimates no camera motion, the selective model is still
    # told not to follow the view: the option is not said to change nothing (it was)
    for out, extra in (("v4", ["--tracker", "sort"]),
                       ("v5", ["--config", tmp_path / "still.toml"])):
        r = cli(frames, "--out-dir", tmp_path / out, "--min-area", "50", "--quiet",
                "--still-camera", *extra)
        assert r.returncode == 0 and "changes nothing" not in r.stderr, r.stderr
    r = cli(frames, "--out-dir", tmp_path / "v6", "--min-area", "50", "--quiet",
            "--still-camera", "--tracker", "sort", "--background", "mog2")
    assert r.returncode == 0 and "--still-camera changes nothing here: --tracker sort does " \
        "not estimate the camera's motion" in r.stderr


def test_the_command_lines_defaults_are_the_configurations():
    """The defaults `vistrack track --help` states are the configuration's own (the parser
    does not load the tracker to read them)."""
    from vistrack.cli import _SETTINGS

    cfg = TrackConfig.preset("bytetrack")
    for option, table, key, _, _, _, default in _SETTINGS:
        assert getattr(getattr(cfg, table), key) == default, option
    # and --fps's range is the one the motion model scales to
    from vistrack.cli import _FPS
    from vistrack.models.box import FRAME_RATES

    assert _FPS == FRAME_RATES


def test_video_mode_options_keep_the_front_ends_defaults(tmp_path):
    """From pixels, an option goes over the background front-end's defaults (a still camera);
    a configuration file is used as it is, and reads back to the same tracks."""

    clip = demo_clip().video
    r = cli(clip, "--out-dir", tmp_path / "a", "--stop", "15", "--high", "0.5", "--quiet",
            "--print-config")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert "high = 0.5" in lines and "camera_motion = false" in lines
    assert "frame_rate = 7.0" in lines  # the clip's, in [derived]
    (tmp_path / "used.toml").write_text(r.stdout)
    r = cli(clip, "--out-dir", tmp_path / "b", "--stop", "15", "--quiet", "--config",
            tmp_path / "used.toml")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "a" / "tracks.txt").read_text() == \
        (tmp_path / "b" / "tracks.txt").read_text()


@pytest.mark.parametrize("data, why", [
    (b"\x89PNG\r\n\x1a\n\x00", "(byte 0: b'\\x89' is not UTF-8)"),
    (b"[tracker]\nname = \"s\xe9rt\"\n", "(byte 19: b'\\xe9' is not UTF-8)"),
    (b"[tracker]\n\x00\x00", "(byte 10 is a NUL byte)"),
])
def test_a_binary_or_non_utf8_file_is_named(tmp_path, data, why):
    path = tmp_path / "bad.toml"
    path.write_bytes(data)
    with pytest.raises(ConfigError) as e:
        read_config(path)
    assert str(e.value) == f"{path} is not a text TOML file {why}"
    with pytest.raises(ConfigError, match=re.escape(f"{tmp_path} is not a text TOML file (it "
                                                    "is a folder)")):
        read_config(tmp_path)


def test_a_byte_order_mark_is_dropped_and_deep_nesting_is_named(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf[tracker]\r\nname = \"sort\"\r\n")
    assert read_config(path).name == "sort"
    path.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(ConfigError, match=re.escape(f"{path}: not valid TOML")):
        read_config(path)


def test_an_interrupted_sequence_leaves_no_folder_it_made(seq, tmp_path, monkeypatch):
    """Ctrl-C at frame 50, when rows have been written to the partial file, into folders that
    did not exist: they are removed again, with the partial file."""
    import vistrack.pipeline

    step = vistrack.pipeline.BoxTracker.step

    out = tmp_path / "new" / "deeper" / "tracks.txt"
    seen = []

    def interrupted(self, frame, *args, **kwargs):
        if frame.index == 50:
            seen.extend(p.name for p in out.parent.iterdir())
            raise KeyboardInterrupt
        return step(self, frame, *args, **kwargs)

    monkeypatch.setattr(vistrack.pipeline.BoxTracker, "step", interrupted)
    with pytest.raises(KeyboardInterrupt):
        track_sequence(seq, out)
    assert len(seen) == 1 and re.fullmatch(r"\.tracks\.[0-9a-f]{10}\.partial\.txt", seen[0])
    assert list(tmp_path.iterdir()) == []


def test_numpy_scalars_and_whole_floats_are_written_as_read_config_reads_them(tmp_path):
    # before: `high = np.float64(0.5)`, `camera_motion = False` (not TOML), and an integer
    # setting given as 3.0 written `confirm_hits = 3.0`, which read_config refuses
    cases = [{"tracker": {"confirm_hits": 3.0}}, {"tracker": {"high": np.float64(0.5)}},
             {"tracker": {"camera_motion": np.False_}},
             {"tracker": {"calibration_window": np.int64(100)}},
             {"motion": {"std_pos": np.float64(0.1), "frame_rate": np.float32(25.0)}},
             {"offline": {"max_gap": np.float64(0.5), "enabled": True}}]
    path = tmp_path / "c.toml"
    for values in cases:
        cfg = TrackConfig.preset().with_values(**values)
        text = config_toml(cfg, {"frame_rate": np.float64(30.0), "sequences": np.int64(2)})
        assert "np." not in text and "True" not in text and "False" not in text
        path.write_text(text)
        assert read_config(path) == cfg, values
    assert "confirm_hits = 3\n" in config_toml(TrackConfig.preset().with_values(
        tracker={"confirm_hits": 3.0}))


def test_the_largest_int64_is_read(tmp_path):
    path = tmp_path / "big.toml"
    path.write_text("[tracker]\ncamera_min_matches = 9223372036854775807\n")
    assert read_config(path).tracker.camera_min_matches == 2 ** 63 - 1


def test_offline_scores_on_raw_scores_below_zero_track_as_shifted_ones(seq, tmp_path):
    """With raw scores, the offline mode's min_track_score and start_score had to be >= 0,
    so scores shifted below 0 (a detector's logits) lost every track: 0 boxes whatever the
    setting. Shifting the scores and every threshold by one constant must give the same
    tracks (the oracle)."""
    rows = (seq / "det" / "det.txt").read_text().splitlines()
    shifted = tmp_path / "SHIFTED"
    (shifted / "det").mkdir(parents=True)
    shutil.copy(seq / "seqinfo.ini", shifted / "seqinfo.ini")
    (shifted / "det" / "det.txt").write_text("".join(
        ",".join(c[:6] + [repr(float(c[6]) - 20.0)] + c[7:]) + "\n"
        for c in (r.split(",") for r in rows)))
    out = {}
    for name, folder, d in (("as", seq, 0.0), ("shifted", shifted, -20.0)):
        (tmp_path / f"{name}.toml").write_text(
            f'[tracker]\nscores = "raw"\nfuse_score = false\nhigh = {6 + d}\nlow = {1 + d}\n'
            f"new_track = {8 + d}\n[offline]\nenabled = true\nmin_track_score = {7 + d}\n"
            f"start_score = {9 + d}\n")
        r = cli(folder, "--out", tmp_path / f"{name}.txt", "--config", tmp_path / f"{name}.toml")
        assert r.returncode == 0, r.stderr
        out[name] = [line.split(",")[:6] for line in
                     (tmp_path / f"{name}.txt").read_text().splitlines()]
    assert out["as"] == out["shifted"] and len(out["as"]) > 500
    with pytest.raises(ValueError, match=r"min_track_score must be in \[0, 1\] \(a calibrated"):
        TrackConfig().with_values(offline={"min_track_score": -0.5})


def test_print_config_of_two_classes_gives_each_class_its_thresholds_raw_scores(tmp_path,
                                                                              capsys):
    """With detections of two classes, each calibrated apart, ``--print-config`` gives the
    raw score of each threshold for each class, as TOML tables by class; read back, the
    file tracks identically."""
    import pandas as pd

    from vistrack.cli import main
    from vistrack.config import _toml_loads

    from .test_calibration import _class_file

    _, cars = scene(np.random.default_rng(21), clutter=3.0)
    _, people = scene(np.random.default_rng(22), clutter=3.0, height=(20, 50))
    both = tmp_path / "both.csv"
    pd.concat([_class_file(tmp_path / "c.csv", cars, lambda s: 16 * s - 1, 2),
               _class_file(tmp_path / "p.csv", people, lambda s: s ** 3 / 2, 0)]).to_csv(
        both, index=False)
    assert main(["track", str(both), "--fps", "25", "--out", str(tmp_path / "a.csv"),
                 "--print-config"]) == 0
    text = capsys.readouterr().out
    derived = _toml_loads(text)["derived"]
    assert sorted(derived["high_score"]) == ["0", "2"]
    # each class's threshold on its own scale: the cars' raw scores run from -1 to 15, the
    # people's from 0 to 0.5
    assert 0 < derived["high_score"]["0"] <= 0.5 < derived["high_score"]["2"] <= 15
    assert derived["calibration_outcomes"]["0"] > 0 and derived["calibration_outcomes"]["2"] > 0
    (tmp_path / "used.toml").write_text(text)
    assert main(["track", str(both), "--fps", "25", "--out", str(tmp_path / "b.csv"),
                 "--config", str(tmp_path / "used.toml")]) == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_a_file_leaves_a_still_camera_front_end_its_own_default(tmp_path, capsys):
    """With `--frontend bgsub` (a background model: a still camera) a --config file of
    `[tracker] max_lost = 0.2` alone turned camera-motion compensation back on without a
    word, where `--max-lost 0.2` leaves it off: the same tracks now (oracle: the option's
    run); a file that sets `camera_motion = true` itself keeps it, and is said."""
    from vistrack.cli import main

    clip = demo_clip()
    one = tmp_path / "one.toml"
    one.write_text("[tracker]\nmax_lost = 0.2\n")
    base = ["track", str(clip.video), "--stop", "30", "--quiet"]
    assert main(base + ["--out-dir", str(tmp_path / "opt"), "--max-lost", "0.2"]) == 0
    assert main(base + ["--out-dir", str(tmp_path / "cfg"), "--config", str(one)]) == 0
    assert (tmp_path / "opt" / "tracks.txt").read_text() == \
        (tmp_path / "cfg" / "tracks.txt").read_text()
    on = tmp_path / "on.toml"
    on.write_text("[tracker]\nmax_lost = 0.2\ncamera_motion = true\n")
    capsys.readouterr()
    assert main(["track", str(clip.video), "--stop", "30", "--out-dir", str(tmp_path / "on"),
                 "--config", str(on)]) == 0
    assert (f"{on}: camera_motion = true with the bgsub front-end, which needs a still camera"
            in capsys.readouterr().err)


def test_durations_and_rates_a_run_cannot_count_are_refused_when_read(seq, tmp_path):
    """`--max-lost 1e308`, `--max-gap 1e308` and `[motion] frame_rate = 1e300` passed every
    check and failed in the run with a traceback (OverflowError, status 1); a frame rate of
    1e-300 was named as `std_vel ... got 0.0`, a key the file never set. Now each is refused
    when read, naming the option or the file's key (status 2)."""
    for extra, said in ((["--max-lost", "1e308"], "--max-lost: max_lost must be a number of "
                         "seconds from 0 to 1e+09; got 1e+308"),
                        (["--offline", "--max-gap", "1e308"], "--max-gap: max_gap must be a "
                         "number of seconds from 0 to 1e+09; got 1e+308")):
        r = cli(seq, "--out", tmp_path / "a.txt", *extra)
        assert r.returncode == 2 and said in r.stderr, r.stderr
    for rate in ("1e300", "1e-300"):
        f = tmp_path / f"r{rate}.toml"
        f.write_text(f"[motion]\nframe_rate = {rate}\n")
        r = cli(seq, "--out", tmp_path / "a.txt", "--config", f)
        assert r.returncode == 2 and (f"{f}:2: [motion] frame_rate must be a number from 0.001 "
                                      f"to 1e+06 frames/s; got {float(rate)!r}") in r.stderr, \
            r.stderr


def test_a_start_score_that_changes_nothing_and_a_files_value_are_said(seq, tmp_path):
    """`--start-score` at or below the online start changed nothing offline (0, 0.5 and 0.7
    gave one file), without a word; `low` from a file against `--high` named `--high`
    alone."""
    r = cli(seq, "--out", tmp_path / "a.txt", "--offline", "--start-score", "0.5")
    assert r.returncode == 0 and ("--start-score 0.5 changes nothing: offline, tracks start "
                                  "from the detections the online start takes (high 0.6 and "
                                  "new_track 0.7)") in r.stderr, r.stderr
    # between new_track and high, a track's detection must reach high anyway
    r = cli(seq, "--out", tmp_path / "d.txt", "--offline", "--high", "0.8", "--low", "0.3",
            "--start-score", "0.75")
    assert r.returncode == 0 and "--start-score 0.75 changes nothing" in r.stderr, r.stderr
    r = cli(seq, "--out", tmp_path / "b.txt", "--offline", "--start-score", "0.9")
    assert r.returncode == 0 and "start-score" not in r.stderr, r.stderr
    low = tmp_path / "low.toml"
    low.write_text("[tracker]\nlow = 0.5\n")
    r = cli(seq, "--out", tmp_path / "c.txt", "--config", low, "--high", "0.4")
    # the file's low at its line, with the option that made it wrong
    assert r.returncode == 2 and f"{low}:2: [tracker] low must be at most high" in r.stderr
    assert r.stderr.rstrip().endswith("(with --high 0.4)")


@pytest.mark.parametrize("value, read", [("-5e-1", -0.5), ("-.25E+1", -2.5), ("-0.5", -0.5),
                                         ("-2", -2.0)])
def test_a_negative_threshold_in_exponent_form_is_a_value(value, read, capsys):
    """`--low -5e-1` was argparse's "expected one argument" (it took -5e-1 for an option:
    only integers and decimals counted as negative numbers); any form float() reads is a
    value, as raw scores below 0 need (`--low=-5e-1` worked)."""
    from vistrack.cli import main

    assert main(["track", "--scores", "raw", "--low", value, "--print-config"]) == 0
    out = capsys.readouterr().out
    assert f"\nlow = {read}\n" in out
    with pytest.raises(SystemExit) as ended:
        main(["track", "--low", "-x", "--print-config"])
    assert ended.value.code == 2
    assert capsys.readouterr().err == ("vistrack track: error: argument --low: expected one "
                                       "argument\n")


@pytest.mark.parametrize("rate", [30.0, 25.0, 15.0, 14.0, 12.5, 10.0, 7.5, 7.0, 5.0, 2.5,
                                  25 / 3, 25 / 6, 10 / 6])
def test_offline_durations_are_frames_to_the_nearest_a_half_up(rate):
    """Python's round took a half frame to the even one: ``link_window`` 0.3 s was 4 frames
    at 15 frames/s but 8 at 25, ``max_gap`` 1 s 2 frames at 2.5 frames/s and 12 at 12.5,
    where the box tracker's coasting rounds a half up. The oracle: exact rational
    arithmetic, floor(seconds x rate + 1/2), the durations' decimal values as written."""
    from fractions import Fraction

    cfg = OfflineConfig()
    exact = Fraction(rate).limit_denominator(1000)  # 25/3 as the third it is
    want = {name: math.floor(Fraction(str(getattr(cfg, name))) * exact + Fraction(1, 2))
            for name in ("max_gap", "link_gap", "link_window")}
    want["link_window"] = max(1, want["link_window"])
    assert cfg.frames(rate) == want


def test_offline_durations_need_a_frame_rate():
    """frames(-30) gave negative frame counts, NaN and inf numpy's conversion errors."""
    for bad in (-30.0, 0.0, math.nan, math.inf):
        with pytest.raises(ValueError, match=re.escape(f"frame_rate must be a finite number "
                                                       f"> 0; got {bad!r}")):
            OfflineConfig().frames(bad)


def test_the_options_are_checked_over_the_file_and_name_what_is_theirs(seq, tmp_path):
    """The --config file was checked on its own before the options came over it: a file of
    raw thresholds (high = 3) was refused before --scores raw, one of high = 0.2 before
    --low 0.1 (which the same values as options take); an error from a value of the file
    was blamed on the option alone; a key's text inside a string of several lines named
    that line. Oracles: the same values as options, and the line that sets the key."""
    raw = tmp_path / "raw.toml"
    raw.write_text("[tracker]\nhigh = 3\nlow = 1\nnew_track = 4\nfuse_score = false\n")
    a = tmp_path / "a.txt"
    r = cli(seq, "--out", a, "--config", raw, "--scores", "raw")
    assert r.returncode == 0, r.stderr
    low = tmp_path / "low.toml"
    low.write_text("[tracker]\nhigh = 0.2\n")
    c, d = tmp_path / "c.txt", tmp_path / "d.txt"
    assert cli(seq, "--out", c, "--config", low, "--low", "0.1").returncode == 0
    assert cli(seq, "--out", d, "--high", "0.2", "--low", "0.1").returncode == 0
    assert c.read_bytes() == d.read_bytes()
    bad = tmp_path / "bad.toml"
    bad.write_text("[offline]\nlink_gap = 0\nlink_iou = 0\n")
    r = cli(seq, "--out", c, "--config", bad, "--offline", "--link-gap", "1", "--force")
    assert r.returncode == 2
    assert f"{bad}:3: [offline] link_iou must be in (0, 1]" in r.stderr
    high = tmp_path / "high.toml"
    high.write_text("[tracker]\nhigh = 0.4\n")
    r = cli(seq, "--out", c, "--config", high, "--low", "0.5", "--force")
    assert r.returncode == 2 and f"--low over {high}: low must be at most high" in r.stderr
    r = cli(seq, "--out", c, "--config", raw, "--force")  # (the file alone: its line)
    assert r.returncode == 2 and f"{raw}:2: [tracker] high must be in [0, 1]" in r.stderr
    note = tmp_path / "note.toml"
    note.write_text('[derived]\nnote = """\n[tracker]\nhigh = 1\n"""\n[tracker]\nhigh = 2\n')
    with pytest.raises(ConfigError, match=re.escape(f"{note}:7: [tracker] high must be")):
        read_config(note)


def test_fit_refuses_to_write_over_its_own_config_and_thresholds_are_finite(tmp_path, seq):
    """`vistrack fit --out c.toml --config c.toml --force` replaced its own input, which
    `track` refuses; raw thresholds of -inf or inf were taken from a file where --high
    refuses them. Oracle: track's refusal, and the options' ranges."""
    c = tmp_path / "c.toml"
    c.write_text("[tracker]\nmax_lost = 1.5\n")
    before = c.read_text()
    r = subprocess.run([sys.executable, "-m", "vistrack.cli", "fit", str(seq), "--out",
                        str(c), "--config", str(c), "--force"], capture_output=True, text=True)
    assert r.returncode == 2 and "--config" in r.stderr and c.read_text() == before
    for key in ("high", "low", "new_track"):
        for v in ("inf", "-inf"):
            c.write_text(f'[tracker]\nscores = "raw"\n{key} = {v}\n')
            with pytest.raises(ConfigError, match=re.escape(f"{key} must be a finite number")):
                read_config(c)


def test_a_file_printed_with_still_camera_says_so_when_read_back_without_it(tmp_path):
    """In video mode --still-camera turns the background model's following of the view
    off, a front-end's option the file does not hold: read back without it, the view was
    followed and the tracks differed (736 boxes against 267 on a pan), without a word. The
    file records it in [derived] (as --fps), a run read back without it is warned, and with
    it the tracks are the same. Oracle: the printing run's own tracks."""
    clip = demo_clip().video
    p1, p2 = tmp_path / "p1", tmp_path / "p2"
    r = subprocess.run(CLI + [str(clip), "--out-dir", str(p1), "--still-camera", "--stop", "40",
                              "--print-config"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    toml = tmp_path / "p1.toml"
    toml.write_text(r.stdout)
    assert "still_camera_option = true" in r.stdout
    r = subprocess.run(CLI + [str(clip), "--out-dir", str(p2), "--config", str(toml), "--stop",
                              "40"], capture_output=True, text=True)
    assert "was printed by a run given --still-camera" in r.stderr
    r = subprocess.run(CLI + [str(clip), "--out-dir", str(p2), "--config", str(toml), "--stop",
                              "40", "--still-camera", "--force"], capture_output=True, text=True)
    assert r.returncode == 0 and "was printed by a run given --still-camera" not in r.stderr
    assert (p1 / "tracks.txt").read_bytes() == (p2 / "tracks.txt").read_bytes()


def test_the_second_reading_of_the_configuration_messages(seq, tmp_path):
    """From the second reading: a ''' in a comment after a value made every later line
    "inside a string" (the error lost its line); two options that clash were named as one
    over the file (the file gave neither); an offline start_score of -inf was taken from a
    file where --start-score refuses it. Oracles: the line that sets the key, the options'
    own message without a file, and the option's range."""
    c = tmp_path / "c.toml"
    c.write_text("[tracker]\nscores = \"calibrated\"  # not '''raw\nhigh = 3\n")
    with pytest.raises(ConfigError, match=re.escape(f"{c}:3: [tracker] high must be in")):
        read_config(c)
    c.write_text('[tracker]\nname = "bytetrack"\n')
    with_file = cli(seq, "--out", tmp_path / "a.txt", "--config", c, "--high", "0.5", "--low",
                    "0.6")
    alone = cli(seq, "--out", tmp_path / "a.txt", "--high", "0.5", "--low", "0.6")
    assert with_file.returncode == alone.returncode == 2
    assert "--high, --low: low must be at most high" in alone.stderr
    assert "--high, --low: low must be at most high" in with_file.stderr
    for key in ("start_score", "min_track_score"):
        c.write_text(f"[offline]\n{key} = -inf\n")
        with pytest.raises(ConfigError, match=re.escape(f"[offline] {key} must be a finite "
                                                        "number")):
            read_config(c)


DEMO_CLIP = (Path(__file__).resolve().parents[1] / "src" / "vistrack" / "data" / "pets09-s2l1"
             / "pets09-s2l1.mp4")


def test_dcpf_settings_round_trip_through_print_config_and_config(tmp_path):
    """`--tracker dcpf` had its defaults alone on the command line (`--config` and
    `--print-config` went with the box trackers). Its settings now come from a `[dcpf]`
    table: `--print-config` without INPUT prints the defaults (`DCPFConfig()`'s, the
    oracle), a file changing some is used (the run prints them back, with what it derived),
    and the printed file read back with `--config` gives identical tracks."""
    from vistrack.config import read_dcpf_config
    from vistrack.tracking import DCPFConfig

    r = cli("--print-config", "--tracker", "dcpf")
    assert r.returncode == 0, r.stderr
    (tmp_path / "defaults.toml").write_text(r.stdout)
    assert read_dcpf_config(tmp_path / "defaults.toml") == (DCPFConfig(), {})
    (tmp_path / "mine.toml").write_text("[dcpf]\nn_particles = 60\nmax_lost = 1.0\n")
    r = cli(DEMO_CLIP, "--tracker", "dcpf", "--config", tmp_path / "mine.toml", "--stop", "25",
            "--out-dir", tmp_path / "a", "--print-config")
    assert r.returncode == 0, r.stderr
    (tmp_path / "used.toml").write_text(r.stdout)
    used, derived = read_dcpf_config(tmp_path / "used.toml")
    assert used == DCPFConfig(n_particles=60, max_lost=1.0)
    assert derived["frame_rate"] == 7.0 and derived["scored_detections"] > 0
    assert 0.75 <= derived["top_score"] < 1  # the confidence front end's logistic
    r = cli(DEMO_CLIP, "--tracker", "dcpf", "--config", tmp_path / "used.toml", "--stop", "25",
            "--out-dir", tmp_path / "b")
    assert r.returncode == 0, r.stderr
    a, b = ((tmp_path / d / "tracks.txt").read_text() for d in "ab")
    assert a == b and len(a.splitlines()) > 50
    r = cli(DEMO_CLIP, "--tracker", "dcpf", "--stop", "25", "--out-dir", tmp_path / "c")
    assert (tmp_path / "c" / "tracks.txt").read_text() != a  # the settings changed the run


def test_a_dcpf_file_printed_by_a_run_given_fps_says_so_when_read_back_without_it(tmp_path):
    """The frame rate is the input's, not a setting: a file printed by a run given --fps 2,
    read back without it, tracked at the clip's 7 frames/s and gave other tracks without a
    word (the box trackers' files warn). It warns now, naming the option; with --fps 2 it
    gives the printing run's tracks (the oracle) and says nothing."""
    r = cli(DEMO_CLIP, "--tracker", "dcpf", "--fps", "2", "--stop", "20", "--out-dir",
            tmp_path / "a", "--print-config")
    assert r.returncode == 0, r.stderr
    (tmp_path / "c.toml").write_text(r.stdout)
    assert "fps_option = 2.0" in r.stdout and "frame_rate = 2.0" in r.stdout
    r = cli(DEMO_CLIP, "--tracker", "dcpf", "--config", tmp_path / "c.toml", "--stop", "20",
            "--out-dir", tmp_path / "b")
    assert r.returncode == 0, r.stderr
    assert ("c.toml was printed by a run given --fps 2 ([derived] fps_option), tracked at 2 "
            "frames/s; this run tracks at 7 (its input's frame rate): give --fps 2") in r.stderr
    r = cli(DEMO_CLIP, "--tracker", "dcpf", "--config", tmp_path / "c.toml", "--fps", "2",
            "--stop", "20", "--out-dir", tmp_path / "c")
    assert r.returncode == 0 and "was printed by a run" not in r.stderr
    assert (tmp_path / "c" / "tracks.txt").read_text() == \
        (tmp_path / "a" / "tracks.txt").read_text()


def test_a_dcpf_start_above_every_score_is_said_and_read_from_the_file(tmp_path):
    """A file's `init_score` reaches the tracker: above every score of the clip's detector
    (the confidence front end's, under 1), no target starts, and the run says so with the
    file's value."""
    (tmp_path / "c.toml").write_text("[dcpf]\ninit_score = 0.999\n")
    r = cli(DEMO_CLIP, "--tracker", "dcpf", "--config", tmp_path / "c.toml", "--stop", "10",
            "--out-dir", tmp_path / "o")
    assert r.returncode == 0, r.stderr
    assert "no target started: no detection reached init_score 0.999 (the highest of" in \
        r.stderr
    assert (tmp_path / "o" / "tracks.txt").read_text() == ""
    # several inputs read it too (the file's settings went to the box trackers' checks)
    for name in ("a", "b"):
        shutil.copy(DEMO_CLIP, tmp_path / f"{name}.mp4")
    r = cli(tmp_path / "a.mp4", tmp_path / "b.mp4", "--tracker", "dcpf", "--config",
            tmp_path / "c.toml", "--stop", "5", "--out-dir", tmp_path / "many")
    assert r.returncode == 0, r.stderr
    assert r.stderr.count("no target started: no detection reached init_score 0.999") == 2


@pytest.mark.parametrize("text, message", [
    ("[dcpf]\nbeta = 1.0\nsigma_det = 0\n", "c.toml:3: [dcpf] sigma_det must be a finite "
     "number > 0; got 0.0"),
    ("[dcpf]\ninit_scor = 0.5\n", "c.toml:2: [dcpf] has no key 'init_scor'; did you mean "
     "'init_score'?"),
    ("[dcpf]\nn_particles = \"100\"\n", "c.toml:2: [dcpf] n_particles must be an integer; "
     "got '100'"),
    ("[dcpf]\nmin_score = 3\n", "c.toml:2: [dcpf] min_score must be below the largest "
     "association score"),
    ("[dcpf]\n[motion]\nstd_pos = 1\n", "c.toml:2: unknown table or key 'motion'; it is the "
     "box trackers' table (bytetrack, sort), and --tracker dcpf reads [dcpf]"),
])
def test_a_dcpf_file_at_fault_is_named_at_its_line(tmp_path, text, message):
    (tmp_path / "c.toml").write_text(text)
    r = cli(DEMO_CLIP, "--tracker", "dcpf", "--config", tmp_path / "c.toml", "--stop", "2",
            "--out-dir", tmp_path / "o")
    assert r.returncode == 2 and message in r.stderr, r.stderr
    assert not (tmp_path / "o").exists()
    # and a box tracker given the dcpf table says whose it is
    r = cli(DEMO_CLIP, "--config", tmp_path / "c.toml", "--stop", "2", "--out-dir",
            tmp_path / "o")
    assert r.returncode == 2 and "unknown table or key 'dcpf'; it is --tracker dcpf's table" \
        in r.stderr


def test_configurations_take_numpys_numbers_and_refuse_what_no_file_reads_back():
    """OfflineConfig refused np.int64(2), np.float32(0.5) and np.bool_(True) as no number
    and no flag, where BoxTrackerConfig takes them (kept as Python's own types); TrackConfig
    took a name of no preset, which config_toml wrote into a file read_config refuses, and a
    dict of settings for tracker, which failed in config_toml as an AttributeError. Oracle:
    read_config of config_toml's text gives the configuration back."""
    c = OfflineConfig(enabled=np.bool_(True), max_gap=np.int64(2), link_iou=np.float32(0.5))
    assert (c.enabled, c.max_gap, c.link_iou) == (True, 2, 0.5)
    assert (type(c.enabled), type(c.max_gap), type(c.link_iou)) == (bool, int, float)
    cfg = TrackConfig.preset().with_values(offline={"max_gap": np.int64(3),
                                                    "enabled": np.bool_(True)})
    assert cfg.offline == OfflineConfig(enabled=True, max_gap=3)
    with pytest.raises(ValueError, match=re.escape("max_gap must be a finite number >= 0; "
                                                   "got np.float64(nan)")):
        OfflineConfig(max_gap=np.float64("nan"))
    with pytest.raises(ValueError, match="enabled must be true or false; got 1"):
        OfflineConfig(enabled=1)
    with pytest.raises(ValueError, match=re.escape("name must be one of ['bytetrack', 'sort']; "
                                                   "got 'nope'")):
        TrackConfig(name="nope")
    with pytest.raises(TypeError, match=re.escape("tracker must be a BoxTrackerConfig; got dict "
                                                  "{'high': 0.5}")):
        TrackConfig(tracker={"high": 0.5})
    with pytest.raises(TypeError, match="motion must be a BoxMotion or None; got int 3"):
        TrackConfig(motion=3)
    for made in (TrackConfig(name="sort"), cfg):
        assert read_config(_toml(made)) == made


def _toml(cfg):
    import tempfile

    path = Path(tempfile.mkdtemp()) / "c.toml"
    path.write_text(config_toml(cfg))
    return path

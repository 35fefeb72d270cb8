"""``bench/accuracy_mot.py --stride K``'s inputs: a detector that ran on every K-th frame
(its rows numbered by the video's frames, the ground truth of every frame kept), and the
peers' rows, tracked on the detector's frames numbered 1, 2, ..., written back at the
video's frames; and ``--set NAME=DIR``, a set of one's own."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
acc = pytest.importorskip("accuracy_mot")

from vistrack.detector_checks import detection_stride  # noqa: E402
from vistrack.io import read_mot  # noqa: E402


def _sequence(root: Path) -> Path:
    d = root / "SEQ"
    (d / "det").mkdir(parents=True)
    (d / "gt").mkdir()
    (d / "det" / "det.txt").write_text("".join(
        f"{f},-1,{10 + f},{20 + 80 * j},30,60,0.{5 + j}\n" for f in range(1, 31) for j in range(2)))
    (d / "gt" / "gt.txt").write_text("".join(
        f"{f},1,{10 + f},20,30,60,1,1,1\n" for f in range(1, 31)))
    (d / "seqinfo.ini").write_text("[Sequence]\nname=SEQ\nframeRate=30\nseqLength=30\n"
                                   "imWidth=640\nimHeight=480\n")
    return d


@pytest.mark.parametrize("k", [2, 3])
def test_strided_keeps_every_kth_frames_detections_and_every_frames_truth(tmp_path, k):
    d = _sequence(tmp_path)
    (s,) = acc.strided([d], k, tmp_path / "strided")
    det, full = read_mot(s / "det" / "det.txt"), read_mot(d / "det" / "det.txt")
    keep = (full.frames - 1) % k == 0
    np.testing.assert_array_equal(det.frames, full.frames[keep])
    np.testing.assert_array_equal(det.boxes, full.boxes[keep])
    np.testing.assert_array_equal(det.conf, full.conf[keep])
    assert detection_stride(det.frames) == k
    assert (s / "gt" / "gt.txt").read_text() == (d / "gt" / "gt.txt").read_text()
    assert (s / "seqinfo.ini").read_text() == (d / "seqinfo.ini").read_text()


@pytest.mark.parametrize("k", [2, 3])
def test_renumber_back_inverts_every_kths_numbering(tmp_path, k):
    """Rows on the detector's frames 1, 2, ... (``every_kth``) go back to the video's frames
    1, 1 + k, ...: the ground truth taken through both is the ground truth of those frames."""
    d = _sequence(tmp_path)
    (e,) = acc.every_kth([d], k, tmp_path / "every")
    (tmp_path / "rows").mkdir()
    (tmp_path / "rows" / "SEQ.txt").write_text((e / "gt" / "gt.txt").read_text())
    acc.renumber_back(tmp_path / "rows", tmp_path / "back", k)
    back, gt = read_mot(tmp_path / "back" / "SEQ.txt"), read_mot(d / "gt" / "gt.txt")
    keep = (gt.frames - 1) % k == 0
    np.testing.assert_array_equal(back.frames, gt.frames[keep])
    np.testing.assert_array_equal(back.ids, gt.ids[keep])
    np.testing.assert_array_equal(back.boxes, gt.boxes[keep])


def test_dropped_removes_the_rows_of_a_fraction_of_the_frames_and_keeps_the_rest(tmp_path):
    """``--drop FRAC``: the lines of the frames drawn are gone, every other line is kept as
    it was written, and the ground truth and ``seqinfo.ini`` are as they were."""
    d = _sequence(tmp_path)
    (o,) = acc.dropped([d], 0.3, tmp_path / "dropped")
    lines = (d / "det" / "det.txt").read_text().splitlines(keepends=True)
    kept = (o / "det" / "det.txt").read_text().splitlines(keepends=True)
    gone = sorted({int(t.split(",")[0]) for t in lines} - {int(t.split(",")[0]) for t in kept})
    assert kept == [t for t in lines if int(t.split(",")[0]) not in gone]
    assert 3 <= len(gone) <= 16  # of 30 frames, each with probability 0.3
    assert (o / "gt" / "gt.txt").read_text() == (d / "gt" / "gt.txt").read_text()
    assert (o / "seqinfo.ini").read_text() == (d / "seqinfo.ini").read_text()
    # the same draw each time, and none at 0
    (again,) = acc.dropped([d], 0.3, tmp_path / "again")
    assert (again / "det" / "det.txt").read_text() == (o / "det" / "det.txt").read_text()
    (none,) = acc.dropped([d], 0.0, tmp_path / "none")
    assert (none / "det" / "det.txt").read_text() == (d / "det" / "det.txt").read_text()


def test_a_set_of_ones_own_runs_beside_the_shared_ones(tmp_path):
    """``--set NAME=DIR`` runs the sequence folders in DIR as a set; its vistrack row is
    what ``track_sequence`` and the scorer give on the same folder."""
    import re
    import subprocess

    from vistrack.evaluation import evaluate_files
    from vistrack.pipeline import track_sequence

    d = _sequence(tmp_path / "mine")
    bench = Path(acc.__file__)
    r = subprocess.run([sys.executable, str(bench), "--set", f"mine={tmp_path / 'mine'}",
                        "--no-peers"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert "### mine (1 sequences)" in r.stdout
    hota = float(re.search(r"^\| \*\*vistrack\*\* \| ([\d.]+) \|", r.stdout, re.M).group(1))
    track_sequence(d, tmp_path / "SEQ.txt")
    c = evaluate_files([("SEQ", d / "gt" / "gt.txt", tmp_path / "SEQ.txt",
                         d / "seqinfo.ini")])["SEQ"]
    assert hota == round(100 * c.HOTA, 1)
    # a folder without sequences is named
    (tmp_path / "empty").mkdir()
    r = subprocess.run([sys.executable, str(bench), "--set", f"x={tmp_path / 'empty'}"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 1 and r.stderr.strip().endswith(
        f"--set x={tmp_path / 'empty'}: no sequence folder in {tmp_path / 'empty'} has "
        "seqinfo.ini, det/det.txt and gt/gt.txt")


def test_a_configuration_file_runs_beside_the_defaults(tmp_path):
    """``--config FILE`` adds vistrack's rows with FILE's configuration: each the HOTA that
    ``track_sequence`` with that configuration and the scorer give on the same folder, the
    defaults' rows as without the option, and with ``--jitter`` each seed's HOTA with FILE
    beside the defaults'; ``--write`` with it, or a file with a key that is no setting,
    exits naming the problem."""
    import re
    import subprocess

    from vistrack.config import read_config
    from vistrack.evaluation import evaluate_files
    from vistrack.pipeline import track_sequence

    d = _sequence(tmp_path / "mine")
    cfg = tmp_path / "wide.toml"
    # raw scores above the person's 0.5: only the other object (0.6) is tracked
    cfg.write_text('[tracker]\nscores = "raw"\nhigh = 0.55\nnew_track = 0.55\n'
                   "[motion]\nstd_pos = 0.2\n")
    bench = Path(acc.__file__)
    r = subprocess.run([sys.executable, str(bench), "--set", f"mine={tmp_path / 'mine'}",
                        "--no-peers", "--config", str(cfg), "--jitter", "1"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr

    def row(label):
        return float(re.search(rf"^\| \*\*{re.escape(label)}\*\* \| ([\d.]+) \|", r.stdout,
                               re.M).group(1))

    def hota(**kw):
        out = tmp_path / f"SEQ-{len(list(tmp_path.glob('SEQ-*')))}.txt"
        track_sequence(d, out, **kw)
        return round(100 * evaluate_files([("SEQ", d / "gt" / "gt.txt", out,
                                            d / "seqinfo.ini")])["SEQ"].HOTA, 1)

    assert row("vistrack") == hota()
    assert row("vistrack offline") == hota(offline=True)
    assert row("vistrack (wide.toml)") == hota(config=read_config(cfg))
    assert row("vistrack offline (wide.toml)") == hota(config=read_config(cfg), offline=True)
    assert row("vistrack (wide.toml)") < row("vistrack")
    assert "| sequence | vistrack | offline | (wide.toml) | offline (wide.toml) |" in r.stdout
    # the moved boxes tracked with both: the person is never tracked with FILE's settings
    spread = re.search(r"HOTA ranges ([\d.]+)-([\d.]+)\. With wide\.toml, on the same boxes "
                       r"\(against the defaults'\): seed 1 ([\d.]+) \(([-+][\d.]+)\)\.",
                       r.stdout)
    assert spread is not None, r.stdout
    assert float(spread.group(3)) == 0.0 and float(spread.group(4)) < 0
    r = subprocess.run([sys.executable, str(bench), "--config", str(cfg), "--write",
                        str(tmp_path / "x.md")], capture_output=True, text=True, timeout=600)
    assert r.returncode == 1 and "--config's are printed" in r.stderr
    cfg.write_text("[motion]\nstd_mea = 0.1\n")
    r = subprocess.run([sys.executable, str(bench), "--set", f"mine={tmp_path / 'mine'}",
                        "--config", str(cfg)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 1 and f"{cfg}:2: [motion] has no key 'std_mea'" in r.stderr


def test_goals_check_a_configuration_files_rows_as_the_defaults():
    """The goal lines: online first on HOTA with MOTA and IDF1 within a point, offline first
    on all three, the worst sequence within 5 HOTA of its best peer; a ``--config`` file's
    rows (whatever the file's name) are checked as the defaults', and are no peer."""
    from types import SimpleNamespace as S

    def r(h, m, i, seq):
        return {"COMBINED": S(HOTA=h, MOTA=m, IDF1=i), "A": S(HOTA=seq)}

    res = {"vistrack": r(0.50, 0.40, 0.50, 0.50),
           "vistrack offline": r(0.52, 0.45, 0.55, 0.52),
           "vistrack (my offline.toml)": r(0.49, 0.40, 0.50, 0.40),
           "vistrack offline (my offline.toml)": r(0.53, 0.43, 0.56, 0.53),
           "peer": r(0.48, 0.44, 0.50, 0.46)}
    lines = acc.goals(res)
    assert [ln.split(":")[0] for ln in lines] == [
        "- vistrack", "- vistrack offline", "- vistrack (my offline.toml)",
        "- vistrack offline (my offline.toml)"]
    # online: MOTA 40 within a point of 44? no; offline: MOTA 45 above 44
    assert "MOTA 40.0 vs 44.0 MISSED" in lines[0] and "HOTA 50.0 vs 48.0 ok" in lines[0]
    assert "MISSED" not in lines[1]
    # the file's online row is an online row (HOTA first only), its sequence 6 below
    assert "HOTA 49.0 vs 48.0 ok" in lines[2] and "IDF1 50.0 vs 50.0 ok" in lines[2]
    assert "A -6.0 HOTA against its best peer MISSED" in lines[2]
    # the file's offline row must be first on MOTA too: 43 against 44
    assert "MOTA 43.0 vs 44.0 MISSED" in lines[3]


def test_held_out_set_takes_its_own_detections_file(tmp_path, monkeypatch):
    """``--sets MOT15-ACF``: each sequence of the shared folder that has the set's detections
    file and ground truth, laid out with that file as ``det/det.txt``; a sequence without
    either is left out, and the folder's own ``det.txt`` is not read."""
    data = tmp_path / "data"
    (data / "mot15").mkdir(parents=True)
    a, b, c = (_sequence(tmp_path / n).rename(data / "mot15" / n) for n in ("A", "B", "C"))
    (a / "det" / "det_public_acf.txt").write_text("1,-1,5,6,7,8,42.5\n")
    (b / "det" / "det_public_acf.txt").write_text("1,-1,5,6,7,8,-0.3\n")
    (b / "gt" / "gt.txt").unlink()  # no ground truth: not scored, left out
    monkeypatch.setattr(acc, "DATA", data)
    root = acc.held_out("MOT15-ACF", tmp_path / "out")
    assert [d.name for d in acc.sequences(root)] == ["A"]
    d = root / "A"
    assert (d / "det" / "det.txt").read_text() == "1,-1,5,6,7,8,42.5\n"
    assert (d / "gt" / "gt.txt").read_text() == (a / "gt" / "gt.txt").read_text()
    assert (d / "seqinfo.ini").read_text() == (a / "seqinfo.ini").read_text()
    assert c.exists()


def test_held_out_sets_are_run_by_name_and_written_alone(tmp_path):
    """A held-out set is no default set, and ``--write`` takes it alone."""
    import subprocess

    assert "MOT15-ACF" not in acc.SETS and "MOT15-ACF" in acc.HELD_OUT
    bench = Path(acc.__file__)
    r = subprocess.run([sys.executable, str(bench), "--sets", "MOT15,MOT15-ACF", "--no-peers",
                        "--write", str(tmp_path / "x.md")], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 1 and "--write with MOT15-ACF takes it alone" in r.stderr
    assert not (tmp_path / "x.md").exists()

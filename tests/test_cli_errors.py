"""The command line answers mistakes and signals in one line, with a known exit status, and
before any frame is read: SIGTERM, outputs that cannot be written, numbers out of range,
unknown trackers, a closed pipe, and ``--debug``."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from vistrack.cli import main

ROOT = Path(__file__).resolve().parents[1]
VIDEO = ROOT / "src" / "vistrack" / "data" / "pets09-s2l1" / "pets09-s2l1.mp4"
GT = ROOT / "src" / "vistrack" / "data" / "pets09-s2l1" / "gt.txt"
ENV = {**os.environ, "PYTHONPATH": f"{ROOT / 'src'}"}


def cli(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "vistrack.cli", *map(str, args)],
                          capture_output=True, text=True, env=ENV, cwd=ROOT, **kwargs)


def one_line(capsys, command, message):
    """What main printed: nothing on stdout and exactly one error line on stderr."""
    out, err = capsys.readouterr()
    assert out == ""
    assert err == f"vistrack {command}: error: {message}\n"


@pytest.fixture
def bad_sequence(tmp_path):
    """A MOTChallenge sequence folder whose detections file is malformed: reading it fails,
    so an error about anything else shows that it was never read."""
    seq = tmp_path / "seq"
    (seq / "det").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=5\n"
                                     "imWidth=320\nimHeight=240\n")
    (seq / "det" / "det.txt").write_text("not,a,detection\n")
    return seq


# ------------------------------------------------------------------------------ SIGTERM
def test_sigterm_keeps_the_earlier_outputs_and_says_so_in_one_line(tmp_path):
    """SIGTERM in the middle of a run over an earlier complete run (``--force``): exit 143,
    one line, every earlier file byte for byte as it was and no partial file left."""
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "vistrack.cli", "track", str(VIDEO), "--out-dir", str(out),
           "--force", "--quiet"]
    first = subprocess.run(cmd, capture_output=True, text=True, env=ENV, cwd=ROOT)
    assert first.returncode == 0, first.stderr
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert sorted(before) == ["annotated.mp4", "run.json", "tracks.csv", "tracks.txt",
                              "trajectories.png"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=ENV, cwd=ROOT)
    # the annotated video's partial file appears with the first frame written: the run is
    # then in its loop, with about two seconds to go
    deadline = time.monotonic() + 300
    while not list(out.glob(".annotated.*.partial.mp4")) and proc.poll() is None and \
            time.monotonic() < deadline:
        time.sleep(0.01)
    assert proc.poll() is None, "the run ended before it could be stopped"
    proc.send_signal(signal.SIGTERM)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 143
    assert stderr == "vistrack track: terminated; earlier outputs are kept\n"
    assert stdout == ""
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_a_full_disk_is_one_line_and_keeps_the_earlier_file(tmp_path, capsys, monkeypatch):
    """The disk filling up while the results are written (ENOSPC at a write) printed a
    traceback and exited 1, the status of a bug: one line now, the file named, status 2, the
    earlier results byte for byte and no partial file left (the atomic writing, as before)."""
    import errno

    from vistrack.io.atomic import PartialFile

    dets = tmp_path / "cam.txt"
    dets.write_text("".join(f"{f},-1,{10 + 2 * f},20,30,60,0.9,-1,-1,-1\n" for f in range(1, 41)))
    out = tmp_path / "res.txt"
    out.write_text("earlier\n")

    def full(self, text):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self.part))

    monkeypatch.setattr(PartialFile, "write", full)
    assert main(["track", str(dets), "--fps", "25", "--out", str(out), "--force"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("vistrack track: error: ")
    assert err[0] == f"vistrack track: error: {out}: No space left on device"
    assert out.read_text() == "earlier\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cam.txt", "res.txt"]


def test_main_restores_the_sigterm_handler(tmp_path, capsys):
    old = signal.getsignal(signal.SIGTERM)
    assert main(["track", str(VIDEO), "--out-dir", str(tmp_path), "--min-area", "-1"]) == 2
    assert signal.getsignal(signal.SIGTERM) is old


# --------------------------------------------------------- outputs checked before any work
def test_out_that_is_a_folder_is_refused_even_with_force(bad_sequence, tmp_path, capsys):
    folder = tmp_path / "results"
    folder.mkdir()
    assert main(["track", str(bad_sequence), "--out", str(folder), "--force"]) == 2
    one_line(capsys, "track", f"--out {folder} is a folder, not a file")


def test_out_under_a_file_is_refused(bad_sequence, tmp_path, capsys):
    (tmp_path / "file").write_text("")
    out = tmp_path / "file" / "results.txt"
    assert main(["track", str(bad_sequence), "--out", str(out)]) == 2
    one_line(capsys, "track", f"--out {out}: {tmp_path / 'file'} is a file, not a folder")


def test_an_existing_out_without_force_is_refused_before_reading(bad_sequence, tmp_path,
                                                                 capsys):
    out = tmp_path / "results.txt"
    out.write_text("earlier")
    assert main(["track", str(bad_sequence), "--out", str(out)]) == 2
    one_line(capsys, "track", f"--out {out} exists; pass --force to overwrite it")
    assert out.read_text() == "earlier"


def test_out_dir_that_is_a_file_is_refused(tmp_path, capsys):
    # the output is checked before the video is read (a video that does not exist is
    # named first: test_an_input_that_does_not_exist_is_named_before_an_existing_output)
    (tmp_path / "file").write_text("")
    assert main(["track", str(VIDEO), "--out-dir",
                 str(tmp_path / "file")]) == 2
    one_line(capsys, "track", f"--out-dir {tmp_path / 'file'} is a file, not a folder")
    assert main(["track", str(VIDEO), "--out-dir",
                 str(tmp_path / "file" / "sub")]) == 2
    one_line(capsys, "track", f"--out-dir {tmp_path / 'file' / 'sub'}: {tmp_path / 'file'} "
             "is a file, not a folder")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_out_dir_with_earlier_outputs_needs_force(tmp_path, capsys):
    (tmp_path / "tracks.txt").write_text("earlier")
    assert main(["track", str(VIDEO), "--out-dir", str(tmp_path)]) == 2
    one_line(capsys, "track", f"{tmp_path / 'tracks.txt'} exists; pass --force to overwrite "
             "it")
    (tmp_path / "tracks.csv").mkdir()
    assert main(["track", str(VIDEO), "--out-dir", str(tmp_path),
                 "--force"]) == 2
    one_line(capsys, "track", f"--out-dir {tmp_path}: {tmp_path / 'tracks.csv'} is a folder, "
             "not a file")


def test_an_output_folder_that_cannot_be_written_is_refused(tmp_path, capsys, monkeypatch):
    import vistrack.io.atomic

    monkeypatch.setattr(vistrack.io.atomic.os, "access", lambda path, mode: False)
    assert main(["track", str(VIDEO), "--out-dir",
                 str(tmp_path / "out")]) == 2
    one_line(capsys, "track", f"--out-dir {tmp_path / 'out'}: cannot write in {tmp_path} "
             "(no permission)")
    assert main(["track-one", str(VIDEO), "--init", "1,2,3,4", "--out",
                 str(tmp_path / "boxes.txt")]) == 2
    one_line(capsys, "track-one", f"--out {tmp_path / 'boxes.txt'}: cannot write in "
             f"{tmp_path} (no permission)")
    # on a read-only mount access() fails too: said as such (it said "no permission")
    real = os.statvfs(tmp_path)

    class ReadOnly:
        f_flag = real.f_flag | os.ST_RDONLY

    monkeypatch.setattr(vistrack.io.atomic.os, "statvfs", lambda path: ReadOnly())
    assert main(["track", str(VIDEO), "--out-dir",
                 str(tmp_path / "out")]) == 2
    one_line(capsys, "track", f"--out-dir {tmp_path / 'out'}: cannot write in {tmp_path} "
             "(a read-only file system)")


def test_a_folder_that_refuses_new_files_is_named_not_a_partial_file(tmp_path, capsys,
                                                                     monkeypatch):
    """A folder may refuse new files whatever its permissions say (a read-only mount;
    ``/proc``; root passes every access check): ``--out /proc/x.txt`` failed at the partial
    file, ``/proc/.x.partial.txt: No such file or directory``, a name the user never gave.
    The output is now refused up front, naming the option and the folder; a folder that
    takes files is left as it was."""
    import errno

    import vistrack.io.atomic

    vistrack.io.atomic.check_output(tmp_path / "a.txt")
    assert list(tmp_path.iterdir()) == []  # the file made to find out is gone
    if os.path.isdir("/proc/self"):  # Linux: /proc takes no new files, even from root
        seq = tmp_path / "dets.txt"
        seq.write_text("1,-1,10,10,20,20,0.9,-1,-1,-1\n")
        assert main(["track", str(seq), "--fps", "10", "--out", "/proc/vistrack-x.txt"]) == 2
        # root passes the permissions and fails at the file; another user at the permissions
        why = "No such file or directory" if os.geteuid() == 0 else "no permission"
        one_line(capsys, "track", f"--out /proc/vistrack-x.txt: cannot write in /proc ({why})")

    def read_only(*args, **kwargs):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))

    monkeypatch.setattr(vistrack.io.atomic.tempfile, "mkstemp", read_only)
    assert main(["track", str(VIDEO), "--out-dir",
                 str(tmp_path / "out")]) == 2
    one_line(capsys, "track", f"--out-dir {tmp_path / 'out'}: cannot write in {tmp_path} "
             f"({os.strerror(errno.EROFS)})")


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0,
                    reason="permissions bind a user other than root on POSIX")
def test_a_read_only_folder_is_refused(tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        assert main(["track", str(VIDEO), "--out-dir", str(folder)]) == 2
        one_line(capsys, "track", f"--out-dir {folder}: cannot write in {folder} "
                 "(no permission)")
    finally:
        folder.chmod(0o755)


def test_track_one_checks_its_output_first(tmp_path, capsys):
    (tmp_path / "folder").mkdir()
    missing = VIDEO  # (checked before the video is read)
    assert main(["track-one", str(missing), "--init", "1,2,3,4", "--out",
                 str(tmp_path / "folder"), "--force"]) == 2
    one_line(capsys, "track-one", f"--out {tmp_path / 'folder'} is a folder, not a file")
    (tmp_path / "boxes.txt").write_text("earlier")
    assert main(["track-one", str(missing), "--init", "1,2,3,4", "--out",
                 str(tmp_path / "boxes.txt")]) == 2
    one_line(capsys, "track-one", f"--out {tmp_path / 'boxes.txt'} exists; pass --force to "
             "overwrite it")


# ------------------------------------------------------------- a video given to --out
def test_a_video_given_to_out_says_which_option_goes_with_videos(tmp_path):
    r = cli("track", VIDEO, "--out", tmp_path / "results.txt")
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == (f"vistrack track: error: --out is for a MOTChallenge sequence folder "
                        f"(seqinfo.ini, det/det.txt) or a detections file (.txt, .csv), and "
                        f"{VIDEO} is neither: track a video with --out-dir OUT/\n")
    assert not (tmp_path / "results.txt").exists()


def test_a_text_file_given_to_out_is_not_sent_to_out_dir(tmp_path, capsys):
    """README.md given to --out was told to be tracked as a video with --out-dir, which then
    said it is not a video."""
    notes = tmp_path / "notes.md"
    notes.write_text("# not detections\n")
    assert main(["track", str(notes), "--out", str(tmp_path / "r.txt"), "--fps", "10"]) == 2
    one_line(capsys, "track", f"--out is for a MOTChallenge sequence folder (seqinfo.ini, "
             f"det/det.txt) or a detections file (.txt, .csv), and {notes} is neither (a .md "
             "file)")


def test_gt_with_out_names_the_command_that_scores(tmp_path, capsys):
    """--gt with --out sent a user who wants scores to --out-dir, which tracks from pixels."""
    seq = tmp_path / "seq"
    (seq / "det").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=2\n"
                                     "imWidth=320\nimHeight=240\n")
    (seq / "det" / "det.txt").write_text("1,-1,10,10,20,40,0.9\n")
    out = tmp_path / "r.txt"
    assert main(["track", str(seq), "--out", str(out), "--gt", str(GT)]) == 2
    one_line(capsys, "track", f"--gt goes with --out-dir; score {out} after tracking with "
             f"vistrack eval --gt {GT} --pred {out}")
    assert not out.exists()
    # a video's scores are --out-dir's: no advice to keep --out, which cannot track it
    assert main(["track", str(VIDEO), "--out", str(out), "--gt", str(GT)]) == 2
    one_line(capsys, "track", "--gt goes with --out-dir")


def test_an_image_folder_given_to_out_says_which_option_goes_with_it(tmp_path, capsys):
    """It said the folder's seqinfo.ini did not exist and to pass --fps, and given --fps, that
    det/det.txt did not exist: advice that led away from --out-dir."""
    import cv2
    import numpy as np

    folder = tmp_path / "img"
    folder.mkdir()
    for k in range(3):
        cv2.imwrite(str(folder / f"{k + 1:06d}.jpg"), np.zeros((16, 16, 3), np.uint8))
    for extra in ([], ["--fps", "30"]):
        assert main(["track", str(folder), "--out", str(tmp_path / "r.txt"), *extra]) == 2
        one_line(capsys, "track", "--out is for a MOTChallenge sequence folder (seqinfo.ini, "
                 f"det/det.txt) or a detections file (.txt, .csv), and {folder} is a folder "
                 "of images: track it from its pixels with --out-dir OUT/")
    assert not (tmp_path / "r.txt").exists()


def test_a_file_that_is_not_a_video_is_said_once(tmp_path):
    """FFmpeg's own line ("[mov,mp4,m4a,3gp,3g2,mj2 @ 0x...] moov atom not found") came before
    vistrack's message of the same fault; a log level of the user's own still shows it."""
    bad = tmp_path / "notvideo.mp4"
    bad.write_text("hello\n")
    env = {k: v for k, v in ENV.items() if k != "OPENCV_FFMPEG_LOGLEVEL"}
    r = subprocess.run([sys.executable, "-m", "vistrack", "track", str(bad), "--out-dir",
                        str(tmp_path / "out")], capture_output=True, text=True, env=env)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == f"vistrack track: error: {bad}: OpenCV cannot open it as a video\n"
    r = subprocess.run([sys.executable, "-m", "vistrack", "track", str(bad), "--out-dir",
                        str(tmp_path / "out")], capture_output=True, text=True,
                       env=env | {"OPENCV_FFMPEG_LOGLEVEL": "16"})
    assert "moov atom not found" in r.stdout + r.stderr  # (OpenCV prints it on stdout)


def test_a_detections_file_alone_needs_its_frame_rate_once(tmp_path, capsys, bad_sequence):
    """A detections file alone, or a sequence folder without seqinfo.ini: the frame rate is
    asked for by name before the file is read (it is malformed), and the file is given
    once."""
    det = bad_sequence / "det" / "det.txt"
    out = tmp_path / "results.txt"
    assert main(["track", str(det), "--out", str(out)]) == 2
    one_line(capsys, "track", f"{det} is a detections file alone: give its frame rate with "
             "--fps")
    assert main(["track", str(det), "--out", str(out), "--fps", "10", "--detections",
                 str(det)]) == 2
    one_line(capsys, "track", f"{det} is a detections file, and --detections gives another: "
             "give one")
    (bad_sequence / "seqinfo.ini").unlink()
    assert main(["track", str(bad_sequence), "--out", str(out)]) == 2
    one_line(capsys, "track", f"{bad_sequence / 'seqinfo.ini'} does not exist; pass the frame "
             "rate (--fps) to track the detections without it")
    assert not out.exists()
    # the same from Python, which names the argument too
    from vistrack.pipeline import track_sequence

    with pytest.raises(FileNotFoundError) as e:
        track_sequence(det, out)
    assert str(e.value) == f"{det} is a detections file alone: give its frame rate (fps, --fps)"
    assert not out.exists()
    # a mistyped input is named as given (it was "nothere.txt/det/det.txt does not exist")
    assert main(["track", str(tmp_path / "nothere.txt"), "--out", str(out), "--fps", "10"]) == 2
    one_line(capsys, "track", f"{tmp_path / 'nothere.txt'} does not exist (a sequence folder, "
             "or a detections file)")
    # --detections that does not exist is named with its option, as --gt is (it asked to pass
    # --detections, given; then it named the file alone); a sequence folder without
    # det/det.txt points to the option
    seq = tmp_path / "seq_no_det"
    (seq / "det").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=5\n"
                                     "imWidth=640\nimHeight=480\n")
    assert main(["track", str(seq), "--out", str(out), "--detections",
                 str(tmp_path / "nosuch.txt")]) == 2
    one_line(capsys, "track", f"{tmp_path / 'nosuch.txt'} does not exist (--detections FILE)")
    assert main(["track", str(seq), "--out", str(out)]) == 2
    one_line(capsys, "track", f"{seq / 'det' / 'det.txt'} does not exist (pass --detections "
             "FILE, another file of detections)")
    # a folder that is no sequence at all (neither file) is named as such; it was told its
    # seqinfo.ini did not exist, to pass --fps, and then that its det/det.txt did not
    odd = tmp_path / "notes"
    odd.mkdir()
    (odd / "readme.txt").write_text("hello\n")
    for extra in ([], ["--fps", "10"]):
        assert main(["track", str(odd), "--out", str(out), *extra]) == 2
        one_line(capsys, "track", f"{odd} is not a MOTChallenge sequence (no seqinfo.ini, no "
                 "det/det.txt) nor a folder of them: give a sequence folder or a detections "
                 "file (with --fps), or track its images with --out-dir OUT/ instead of --out")
    # --out and --out-dir together
    assert main(["track", str(seq), "--out", str(out), "--out-dir", str(tmp_path / "o")]) == 2
    one_line(capsys, "track", "give --out RESULTS.txt (a MOTChallenge sequence's detections) "
             "or --out-dir OUT/ (from pixels), not both")
    # --print-config with an input but no output: what it needs, and what it does without INPUT
    assert main(["track", str(seq), "--print-config"]) == 2
    one_line(capsys, "track", "give --out RESULTS.txt (a MOTChallenge sequence's detections) "
             "or --out-dir OUT/ (from pixels); --print-config with INPUT tracks it, to show "
             "what the run derives from it (without INPUT it prints the configuration the "
             "options give)")


# ------------------------------------------------------------------- numbers and names
@pytest.mark.parametrize("option, value, message", [
    ("--min-area", "-1", "--min-area must be a finite number >= 0; got -1"),
    ("--min-area", "nan", "--min-area must be a finite number >= 0; got nan"),
    # (inf is >= 0: "must be a number >= 0; got inf" named a rule it meets)
    ("--min-area", "inf", "--min-area must be a finite number >= 0; got inf"),
    ("--fps", "0", "--fps must be a number from 0.001 to 1e+06 (frames a second); got 0"),
    ("--fps", "inf", "--fps must be a number from 0.001 to 1e+06 (frames a second); got inf"),
    # the motion's noise scales with powers of the rate: 1e-300 overflowed it (a traceback)
    ("--fps", "1e-300", "--fps must be a number from 0.001 to 1e+06 (frames a second); got "
                        "1e-300"),
    ("--fps", "1e300", "--fps must be a number from 0.001 to 1e+06 (frames a second); got "
                       "1e+300"),
    ("--stop", "-3", "--stop must be a frame number >= 1; got -3"),
    ("--high", "nan", "--high must be a finite number; got nan"),
    ("--max-lost", "inf", "--max-lost must be a finite number; got inf"),
])
def test_numbers_out_of_range_are_refused_before_reading(tmp_path, capsys, option, value,
                                                         message):
    # the video does not exist: the number is checked before it is opened
    assert main(["track", str(tmp_path / "missing.mp4"), "--out-dir", str(tmp_path / "out"),
                 option, value]) == 2
    one_line(capsys, "track", message)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("tracker", ["dcpf", "single:colour", "particles"])
def test_trackers_of_any_frame_rate_take_any_fps_above_0(tmp_path, capsys, tracker):
    """--fps 1e7 was refused for every tracker, the box trackers' range, where the others
    take such a rate from a file's header; they take it from --fps too, and 0 is named."""
    missing = tmp_path / "missing.mp4"
    extra = ["--frontend", "spots", "--diameter", "5"] if tracker == "particles" else []
    assert main(["track", str(missing), "--tracker", tracker, "--fps", "1e7", "--out-dir",
                 str(tmp_path / "out"), *extra]) == 2
    err = capsys.readouterr().err
    assert "--fps" not in err and "missing.mp4" in err, err
    assert main(["track", str(missing), "--tracker", tracker, "--fps", "0", "--out-dir",
                 str(tmp_path / "out"), *extra]) == 2
    one_line(capsys, "track", "--fps must be a finite number > 0 (frames a second); got 0")


def test_track_one_takes_a_box_as_otb_writes_it(tmp_path, capsys):
    """--init separated by commas, by the tabs of a line of OTB's groundtruth_rect.txt pasted
    as is, or by spaces: the same box, the same track."""
    outs = []
    for k, init in enumerate(("300,130,40,100", "300\t130\t40\t100", " 300 130, 40 100 ")):
        out = tmp_path / f"b{k}.txt"
        assert main(["track-one", str(VIDEO), "--init", init, "--out", str(out)]) == 0
        outs.append(out.read_bytes())
    assert outs[0] == outs[1] == outs[2] and outs[0].startswith(b"1,300.00,130.00,40.00,100.00\n")
    capsys.readouterr()


def test_columns_name_a_csv_s_columns_from_pixels_and_for_eval(tmp_path, capsys):
    """A CSV of detections with other column names, as --frontend detections:FILE: the error
    said to name them with --columns, which --out-dir then refused ("--offline, its settings
    and --detections go with --out"); and vistrack eval gave the same advice without having
    the option. Both take --columns now: the same rows under other names track and score
    exactly as under MOTChallenge's."""
    from vistrack.io import read_mot

    gt = read_mot(GT)
    g = gt[gt.frames <= 12]
    header = {"std": "frame,id,bb_left,bb_top,bb_width,bb_height,conf",
              "own": "t,tid,l,top,w,h,score"}
    for name, head in header.items():
        (tmp_path / f"{name}.csv").write_text(head + "\n" + "".join(
            f"{f},-1,{x},{y},{w},{h},0.9\n" for f, (x, y, w, h) in zip(g.frames, g.boxes)))
    own = "frame=t,id=tid,bb_left=l,bb_top=top,bb_width=w,bb_height=h,conf=score"
    runs = {}
    for name, extra in (("std", []), ("own", ["--columns", own])):
        out = tmp_path / f"out_{name}"
        assert main(["track", str(VIDEO), "--frontend", f"detections:{tmp_path / name}.csv",
                     "--stop", "12", "--out-dir", str(out), "--quiet"] + extra) == 0
        runs[name] = (out / "tracks.txt").read_bytes()
    assert runs["own"] == runs["std"] and runs["std"]
    capsys.readouterr()
    # the tracks as a CSV of other names, scored with --columns: as the text file
    t = read_mot(tmp_path / "out_std" / "tracks.txt")
    (tmp_path / "res.csv").write_text("t,tid,l,top,w,h\n" + "".join(
        f"{f},{i},{x},{y},{w},{h}\n" for f, i, (x, y, w, h) in zip(t.frames, t.ids, t.boxes)))
    scores = []
    for pred, extra in ((tmp_path / "out_std" / "tracks.txt", []),
                        (tmp_path / "res.csv", ["--columns", own.rsplit(",", 1)[0]])):
        assert main(["eval", "--gt", str(GT), "--pred", str(pred), "--json"] + extra) == 0
        scores.append(json.loads(capsys.readouterr().out)["pets09-s2l1"])
    assert scores[0] == scores[1] and scores[0]["TP"] > 0
    # --plots read the CSV again without --columns: the scores, then "no column 'frame'";
    # the same timeline as the text file's now (the plot's own bytes)
    plots = {}
    for pred, extra in ((tmp_path / "out_std" / "tracks.txt", []),
                        (tmp_path / "res.csv", ["--columns", own.rsplit(",", 1)[0]])):
        folder = tmp_path / f"plots_{pred.suffix[1:]}"
        assert main(["eval", "--gt", str(GT), "--pred", str(pred), "--plots", str(folder)]
                    + extra) == 0
        plots[pred.suffix] = sorted((p.name, p.stat().st_size > 0) for p in folder.iterdir())
    assert plots[".csv"] == plots[".txt"] and len(plots[".txt"]) == 2
    # a space after each comma, as read_mot takes it in a text file: the columns were named
    # " bb_left" and so on, and eval said they were missing
    (tmp_path / "sp.csv").write_text("frame, id, bb_left, bb_top, bb_width, bb_height\n" + "".join(
        f"{f}, {i}, {x}, {y}, {w}, {h}\n" for f, i, (x, y, w, h) in zip(t.frames, t.ids, t.boxes)))
    capsys.readouterr()
    assert main(["eval", "--gt", str(GT), "--pred", str(tmp_path / "sp.csv"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["pets09-s2l1"] == scores[0]
    # a ground-truth file of another name, in a folder of other files, names the row after
    # itself (it was named after the folder: "runs")
    (tmp_path / "runs").mkdir()
    (tmp_path / "runs" / "pets-truth.txt").write_bytes(GT.read_bytes())
    assert main(["eval", "--gt", str(tmp_path / "runs" / "pets-truth.txt"), "--pred",
                 str(tmp_path / "sp.csv"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == {"pets-truth": scores[0]}


def test_eval_of_a_run_stopped_early_says_the_frames_after_count_as_missed(tmp_path, capsys):
    """A run with --stop scored against the whole clip's ground truth: the frames after its
    last count as missed, which the scores alone do not say. Its run.json tells the frames
    tracked; eval names them and counts the ground truth's scored rows after (counted here
    from the file itself, and checked against FN: the whole truth's FN less the FN against
    its rows up to frame 12). The rows the convention ignores (a flag of 0; under MOT17's,
    other classes) were counted as missed too: 1187 where FN had 1086. The whole clip's
    run, or a results file without run.json, says nothing."""
    rows = [line.split(",") for line in GT.read_text().splitlines() if line.strip()]
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{r[0]},-1,{r[2]},{r[3]},{r[4]},{r[5]},0.9\n" for r in rows))
    out = tmp_path / "stopped"
    assert main(["track", str(VIDEO), "--frontend", f"detections:{det}", "--stop", "12",
                 "--out-dir", str(out), "--quiet"]) == 0
    capsys.readouterr()
    last = max(int(r[0]) for r in rows)
    # the bundled truth in MOT15's columns, and the same rows in MOT17's with a distractor
    # class (7) on every fifth identity
    mot17 = tmp_path / "gt17.txt"
    mot17.write_text("".join(f"{','.join(r[:7])},{7 if int(r[1]) % 5 == 0 else 1},1\n"
                             for r in rows))
    for gt, scored in ((GT, lambda r: int(float(r[6])) != 0),
                       (mot17, lambda r: int(float(r[6])) != 0 and int(r[1]) % 5 != 0)):
        after = [r for r in rows if int(r[0]) > 12]
        missed = sum(map(scored, after))
        ignored = len(after) - missed
        assert 0 < missed and 0 < ignored  # (both kinds of row, for the oracle to tell apart)
        assert main(["eval", "--gt", str(gt), "--pred", str(out / "tracks.txt")]) == 0
        err = capsys.readouterr().err
        assert err == (f"vistrack eval: warning: {out / 'tracks.txt'}: its run "
                       f"({out / 'run.json'}) tracked frames 1-12 only, and {gt} runs to "
                       f"frame {last}: its {missed} scored rows after frame 12 count as "
                       f"missed (FN) ({ignored} more are ignored)\n")
        head = tmp_path / f"head-{gt.name}"
        head.write_text("".join(line + "\n" for line in gt.read_text().splitlines()
                                if int(line.split(",")[0]) <= 12))
        fn = []
        for truth in (gt, head):
            assert main(["eval", "--gt", str(truth), "--pred", str(out / "tracks.txt"),
                         "--json"]) == 0
            fn.append(next(iter(json.loads(capsys.readouterr().out).values()))["FN"])
        assert fn[0] - fn[1] == missed
    # rows after the last frame that no convention scores (a flag of 0) change no score:
    # nothing is said ("its 0 scored rows ... count as missed"); one is one row
    quiet = tmp_path / "quiet.txt"
    quiet.write_text("".join(",".join(r[:6] + ["0" if int(r[0]) > 12 else r[6]] + r[7:]) + "\n"
                             for r in rows))
    assert main(["eval", "--gt", str(quiet), "--pred", str(out / "tracks.txt")]) == 0
    assert capsys.readouterr().err == ""
    one = tmp_path / "one.txt"
    first_after = next(k for k, r in enumerate(rows) if int(r[0]) > 12)
    one.write_text("".join(",".join(r[:6] + ["1" if k == first_after else
                                             ("0" if int(r[0]) > 12 else r[6])] + r[7:]) + "\n"
                           for k, r in enumerate(rows)))
    assert main(["eval", "--gt", str(one), "--pred", str(out / "tracks.txt")]) == 0
    assert ": its 1 scored row after frame 12 counts as missed (FN) (" in capsys.readouterr().err
    whole = tmp_path / "whole"
    assert main(["track", str(VIDEO), "--frontend", f"detections:{det}", "--out-dir",
                 str(whole), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["eval", "--gt", str(GT), "--pred", str(whole / "tracks.txt")]) == 0
    assert capsys.readouterr().err == ""
    import shutil

    shutil.copy(out / "tracks.txt", tmp_path / "alone.txt")
    assert main(["eval", "--gt", str(GT), "--pred", str(tmp_path / "alone.txt")]) == 0
    assert capsys.readouterr().err == ""


def test_out_with_a_trailing_slash_is_a_folder_with_one_input_too(tmp_path, capsys,
                                                                   monkeypatch):
    """--out RESULTS/ with several inputs writes RESULTS/NAME.txt; with one input it wrote a
    file named RESULTS (Path drops the slash). It is the folder in both cases."""
    dets = tmp_path / "cam3.txt"
    dets.write_text("".join(f"{f},-1,{10 + 2 * f},20,30,60,0.9,-1,-1,-1\n"
                            for f in range(1, 11)))
    monkeypatch.chdir(tmp_path)
    assert main(["track", str(dets), "--fps", "25", "--out", "res/"]) == 0
    assert capsys.readouterr().out.startswith(f"wrote {Path('res') / 'cam3.txt'}: ")
    assert (tmp_path / "res").is_dir() and (tmp_path / "res" / "cam3.txt").is_file()


def test_out_named_as_a_file_with_several_inputs_is_refused(tmp_path, capsys):
    """--out multi.txt with several inputs (or a folder of sequences) made a folder named
    multi.txt, which looked like one results file: refused, saying --out is a folder there."""
    seqs = []
    for name in ("A", "B"):
        seq = tmp_path / name
        (seq / "det").mkdir(parents=True)
        (seq / "seqinfo.ini").write_text("[Sequence]\nframeRate=25\nseqLength=10\nimWidth=640\n"
                                         "imHeight=480\n")
        (seq / "det" / "det.txt").write_text("".join(f"{f},-1,{10 + 2 * f},20,30,60,0.9\n"
                                                     for f in range(1, 11)))
        seqs.append(str(seq))
    for out in ("multi.txt", "multi.CSV", "multi.parquet"):
        assert main(["track", *seqs, "--out", str(tmp_path / out)]) == 2
        one_line(capsys, "track", f"--out {tmp_path / out} names a file; with 2 inputs --out is "
                 "a folder, each sequence's results NAME.txt in it: give --out RESULTS/")
        assert not (tmp_path / out).exists()
    assert main(["track", *seqs, "--out", str(tmp_path / "res")]) == 0
    assert sorted(p.name for p in (tmp_path / "res").iterdir()) == ["A.txt", "B.txt"]


def test_track_one_starts_from_the_ground_truth_s_first_box_without_init(tmp_path, capsys):
    """OTB's groundtruth_rect.txt counts pixels from 1 and --init from 0: its first line
    pasted as --init started the tracker a pixel off the box it is scored against (IoU 0.86
    on the first frame itself). Without --init, --gt's first box is the start, converted as
    the scoring reads it (read_boxes: 0-based), so the first frame's box is the ground
    truth's exactly; the same for groundtruth_rect.1.txt, OTB's name for a second object,
    which was read 1-based. Neither --init nor --gt: named. A box outside the first frame is
    named as --init."""
    from vistrack.evaluation.single import read_boxes

    for name in ("groundtruth_rect.txt", "groundtruth_rect.1.txt"):
        gt = tmp_path / name
        gt.write_text("".join(f"{301 + k}\t{131}\t40\t100\n" for k in range(200)))
        out = tmp_path / f"{name}.boxes.txt"
        assert main(["track-one", str(VIDEO), "--gt", str(gt), "--out", str(out)]) == 0
        first = read_boxes(out)[0]
        assert first.tolist() == read_boxes(gt)[0].tolist() == [300.0, 130.0, 40.0, 100.0]
    capsys.readouterr()
    assert main(["track-one", str(VIDEO), "--out", str(tmp_path / "b.txt")]) == 2
    one_line(capsys, "track-one", "--init is required: the object's box x,y,w,h in the first "
             "frame (or --gt, whose first box is then the start)")
    assert main(["track-one", str(VIDEO), "--init", "5000,10,20,20", "--out",
                 str(tmp_path / "b.txt")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("vistrack track-one: error: --init (x, y, w, h) = (5000, 10, 20, 20) "
                          "lies outside the "), err
    # the frame, and no front-end: track-one has none (it said "in the front-end")
    assert err.rstrip().endswith("image (at frame 1)"), err
    assert not (tmp_path / "b.txt").exists()
    # without --init, a start outside the frame is --gt's first box (another sequence's
    # ground truth, most likely), and so named: it blamed --init, which was not given
    other = tmp_path / "other.txt"
    other.write_text("5001,11,20,20\n")
    assert main(["track-one", str(VIDEO), "--gt", str(other), "--gt-origin", "0", "--out",
                 str(tmp_path / "b.txt")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"vistrack track-one: error: the start, {other}'s first box (x, y, w, "
                          "h) = (5001, 11, 20, 20) lies outside the "), err
    assert not (tmp_path / "b.txt").exists()


def test_track_one_names_a_missing_gt_as_track_does(tmp_path, capsys):
    """A missing --gt file was said as "FILE: No such file or directory", naming no option
    (vistrack track says "... does not exist (--gt FILE)")."""
    missing = tmp_path / "groundtruth.txt"
    out = tmp_path / "b.txt"
    assert main(["track-one", str(VIDEO), "--gt", str(missing), "--out", str(out)]) == 2
    one_line(capsys, "track-one", f"{missing} does not exist (--gt FILE)")
    assert main(["track", str(VIDEO), "--gt", str(missing), "--out-dir", str(tmp_path / "o")]) == 2
    one_line(capsys, "track", f"{missing} does not exist (--gt FILE)")
    assert main(["track-one", str(VIDEO), "--gt", str(tmp_path), "--out", str(out)]) == 2
    one_line(capsys, "track-one", f"{tmp_path} is a folder, not a file (--gt FILE)")
    assert not out.exists()


@pytest.mark.parametrize("init", ["1,2,3,nan", "1,2,0,4", "1,2,3", "1\t2\t3", "1,,2,3,4"])
def test_track_one_refuses_a_box_that_is_not_one(tmp_path, capsys, init):
    assert main(["track-one", str(VIDEO), "--init", init, "--out",
                 str(tmp_path / "b.txt")]) == 2
    one_line(capsys, "track-one", f"--init must be x,y,w,h (four finite numbers, w and h > 0); "
             f"got {init!r}")


@pytest.mark.parametrize("name", ["bogus", "single:bogus"])
def test_an_unknown_tracker_lists_every_form(tmp_path, capsys, name):
    from vistrack.tracking.single import METHODS

    assert main(["track", str(VIDEO), "--out-dir", str(tmp_path / "out"), "--tracker",
                 name]) == 2
    one_line(capsys, "track", "--tracker must be bytetrack, sort, dcpf, particles, "
             f"single:METHOD (METHOD one of {', '.join(sorted(METHODS))}) or module:callable "
             f"(a tracker of your own); got {name!r}")


# ------------------------------------------------------------- argparse's own errors
@pytest.mark.parametrize("argv, message", [
    (["track", "clip.mp4", "--min-area", "abc"],
     "vistrack track: error: argument --min-area: invalid float value: 'abc'"),
    (["track", "clip.mp4", "--out-dir", "out", "--bogus", "1"],
     "vistrack track: error: unrecognized arguments: --bogus 1"),
    (["track"], "vistrack track: error: the following arguments are required: INPUT"),
    (["track-one", "clip.mp4", "--init", "1,2,3,4"],
     "vistrack track-one: error: the following arguments are required: --out"),
    (["track-one", "clip.mp4", "--out", "b.txt", "--init"],
     "vistrack track-one: error: argument --init: expected one argument"),
    (["eval", "--gt", "gt.txt", "--pred", "res.txt", "--jsn"],
     "vistrack eval: error: unrecognized arguments: --jsn; did you mean --json?"),
    # a misspelt option is told the nearest one, as a misspelt key of a --config file is
    (["track", "seq", "--out", "r.txt", "--hihg", "0.5"],
     "vistrack track: error: unrecognized arguments: --hihg 0.5; did you mean --high?"),
    (["track", "seq", "--out", "r.txt", "--still-camra"],
     "vistrack track: error: unrecognized arguments: --still-camra; did you mean "
     "--still-camera?"),
    (["track", "clip.mp4", "--outdir=out"],
     "vistrack track: error: unrecognized arguments: --outdir=out; did you mean --out-dir?"),
    (["eval", "res.txt", "gt.txt"],
     "vistrack eval: error: unrecognized arguments: res.txt gt.txt; vistrack eval takes its "
     "files as options: --pred RESULTS --gt GROUND_TRUTH, or --pred-dir and --gt-dir"),
    # a missing argument of a few values is told them
    (["demo"], "vistrack demo: error: the following arguments are required: DEMO (kalman or "
     "track)"),
    (["demo", "kalman", "--seeds", "x"],
     "vistrack demo: error: argument --seeds: invalid int value: 'x'"),
    (["demo", "kalman", "--seeds", "0"],
     "vistrack demo: error: --seeds must be from 1 to 1,000,000; got 0"),
    (["--bogus"], "vistrack: error: unrecognized arguments: --bogus"),
    # an option of one value given twice: argparse kept the last, unsaid (the first --out
    # was never written, the first --detections never read)
    (["track", "x", "--out", "a.txt", "--out", "b.txt"],
     "vistrack track: error: --out is given twice (a.txt and b.txt): give it once"),
    (["track", "x", "--out", "a.txt", "--detections", "d1.txt", "--detections", "d2.txt"],
     "vistrack track: error: --detections is given twice (d1.txt and d2.txt): give it once"),
    (["fit", "x", "--out", "a.toml", "--config", "c1.toml", "--config", "c2.toml"],
     "vistrack fit: error: --config is given twice (c1.toml and c2.toml): give it once"),
    (["track-one", "v.mp4", "--init", "1,2,3,4", "--init", "5,6,7,8", "--out", "b.txt"],
     "vistrack track-one: error: --init is given twice (1,2,3,4 and 5,6,7,8): give it once"),
    (["demo", "kalman", "--out", "o1", "--out", "o2"],
     "vistrack demo: error: --out is given twice (o1 and o2): give it once"),
])
def test_argument_errors_are_one_line(capsys, argv, message):
    """An unknown option, a value of the wrong type, a missing argument: argparse's message in
    the command line's one form (argparse printed its usage on a line before), status 2."""
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    out, err = capsys.readouterr()
    assert out == "" and err == message + "\n"


@pytest.mark.parametrize("argv, name", [
    (["track", "", "--out", "a.txt"], "INPUT"),
    (["track", "{seq}", "--out", ""], "--out"),
    (["track", "{video}", "--out-dir", ""], "--out-dir"),
    (["track", "{seq}", "--out", "a.txt", "--detections", ""], "--detections"),
    (["track", "{seq}", "--out", "a.txt", "--config", ""], "--config"),
    (["track", "{video}", "--out-dir", "o", "--gt", ""], "--gt"),
    (["report", ""], "OUT_DIR"),
    (["fit", "", "--out", "f.toml"], "SEQ_DIR"),
    (["fit", "{seq}", "--out", ""], "--out"),
    (["fit", "{seq}", "--out", "f.toml", "--config", ""], "--config"),
    (["track-one", "", "--init", "1,2,3,4", "--out", "b.txt"], "INPUT"),
    (["track-one", "{video}", "--init", "1,2,3,4", "--out", ""], "--out"),
    (["track-one", "{video}", "--init", "1,2,3,4", "--out", "b.txt", "--gt", ""], "--gt"),
    (["eval", "--gt", "", "--pred", "{gt}"], "--gt"),
    (["eval", "--gt", "{gt}", "--pred", ""], "--pred"),
    (["eval", "--gt-dir", "", "--pred-dir", "r"], "--gt-dir"),
    (["eval", "--gt-dir", "g", "--pred-dir", ""], "--pred-dir"),
    (["eval", "--gt", "{gt}", "--pred", "{gt}", "--plots", ""], "--plots"),
    (["demo", "track", "--out", ""], "--out"),
])
def test_an_empty_name_is_refused_and_nothing_is_written_here(tmp_path, capsys, monkeypatch,
                                                             argv, name):
    """An empty file or folder name was the current folder: `report ''` read ./run.json and
    wrote report.html there, `track-one ''` tracked the images there, `demo track --out ''`
    wrote its outputs there, `eval --gt ''` said to give --gt. Each is refused by name, in
    one line, and the current folder stays empty (the oracle)."""
    seq = _sequence(tmp_path / "in" / "seq")
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    argv = [a.format(seq=seq, video=VIDEO, gt=GT) for a in argv]
    with pytest.raises(SystemExit) as e:
        main(argv)
    out, err = capsys.readouterr()
    assert (e.value.code, out) == (2, "")
    assert err == (f"vistrack {argv[0]}: error: argument {name}: an empty name: give a file "
                   "or folder\n")
    assert list(here.iterdir()) == []


@pytest.mark.parametrize("argv, start", [
    (["eval", "--benchmark", "MOT99"],
     "vistrack eval: error: argument --benchmark: invalid choice: 'MOT99' "),
    (["track-one", "clip.mp4", "--init", "1,2,3,4", "--out", "b.txt", "--method", "nope"],
     "vistrack track-one: error: argument --method: invalid choice: 'nope' "),
    (["trak"], "vistrack: error: argument COMMAND: invalid choice: 'trak' "),
])
def test_an_invalid_choice_is_one_line_listing_the_choices(capsys, argv, start):
    with pytest.raises(SystemExit) as e:
        main(argv)
    out, err = capsys.readouterr()
    assert e.value.code == 2 and out == "" and err.startswith(start)
    assert err.count("\n") == 1 and err.endswith(")\n")  # "(choose from ...)"


def test_argument_errors_through_the_console_and_the_usage_with_help():
    r = cli("track", VIDEO, "--min-area", "abc")
    assert (r.returncode, r.stdout) == (2, "")
    assert r.stderr == "vistrack track: error: argument --min-area: invalid float value: 'abc'\n"
    r = cli("track", "--help")
    assert r.returncode == 0 and r.stdout.startswith("usage: vistrack track ")


# ------------------------------------------------------------------------- closed pipe
def test_a_pipe_closed_early_ends_quietly():
    """``vistrack eval --json | head -c 10``: head's ten bytes, and nothing on stderr."""
    cmd = (f"{sys.executable} -m vistrack.cli eval --gt {GT} --pred {GT} --json "
           "| head -c 10")
    r = subprocess.run(["bash", "-o", "pipefail", "-c", cmd], capture_output=True, text=True,
                       env=ENV, cwd=ROOT)
    assert r.stdout == '{\n  "pets0'
    assert r.stderr == ""
    assert r.returncode in (0, 1)  # 1 if head had gone before the JSON was written


def test_a_pipe_closed_before_writing_gives_status_1_and_no_traceback():
    """The reader gone before anything is written (as ``head`` once it has its lines):
    status 1, as the Python documentation's note on SIGPIPE recommends, and no traceback."""
    read, write = os.pipe()
    os.close(read)  # no reader: every write to the pipe fails with EPIPE
    try:
        r = subprocess.run([sys.executable, "-m", "vistrack.cli", "eval", "--gt", str(GT),
                            "--pred", str(GT), "--json"], stdout=write,
                           stderr=subprocess.PIPE, text=True, env=ENV, cwd=ROOT)
    finally:
        os.close(write)
    assert r.stderr == ""
    assert r.returncode == 1


# ---------------------------------------------------------------------- errors, --debug
def test_a_user_error_from_inside_a_run_is_one_line(tmp_path, capsys, monkeypatch):
    import vistrack.pipeline
    from vistrack.io.video import VideoError

    def broken(*args, **kwargs):
        raise VideoError("clip.mp4: cannot decode frame 7")

    monkeypatch.setattr(vistrack.pipeline, "track_video", broken)
    assert main(["track", str(VIDEO), "--out-dir", str(tmp_path / "out")]) == 2
    one_line(capsys, "track", "clip.mp4: cannot decode frame 7")

    def denied(*args, **kwargs):
        raise PermissionError(13, "Permission denied", "/somewhere/tracks.txt")

    monkeypatch.setattr(vistrack.pipeline, "track_video", denied)
    assert main(["track", str(VIDEO), "--out-dir", str(tmp_path / "out")]) == 2
    one_line(capsys, "track", "/somewhere/tracks.txt: Permission denied")


def test_debug_shows_a_user_errors_traceback(tmp_path, capsys):
    out = tmp_path / "boxes.txt"
    out.write_text("earlier")
    argv = ["track-one", str(VIDEO), "--init", "1,2,3,4", "--out", str(out)]
    # the traceback, then the one line; the status a user's mistake has without --debug (it
    # was 1, a bug's)
    for args in (["--debug", *argv], [*argv, "--debug"]):  # after the command too
        assert main(args) == 2
        err = capsys.readouterr().err
        assert "Traceback (most recent call last)" in err and "FileExistsError: --out " in err
        assert err.rstrip().splitlines()[-1].startswith("vistrack track-one: error: --out ")
    r = cli("--debug", *argv)
    assert r.returncode == 2
    assert "Traceback (most recent call last)" in r.stderr


def test_a_bug_always_shows_its_traceback(tmp_path, monkeypatch):
    import vistrack.pipeline

    def bug(*args, **kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr(vistrack.pipeline, "track_video", bug)
    with pytest.raises(RuntimeError, match="a bug"):
        main(["track", str(VIDEO), "--out-dir", str(tmp_path / "out")])


def test_skip_bad_frames_carries_on_past_a_cut_short_jpeg(tmp_path, capsys):
    """An image folder with one JPEG cut in half: an error naming it, or with
    --skip-bad-frames a one-line warning naming it and the other frames tracked."""
    import cv2
    import numpy as np

    from vistrack.io import read_mot

    folder = tmp_path / "img"
    folder.mkdir()
    rng = np.random.default_rng(0)
    for k in range(1, 31):
        img = np.full((120, 160, 3), 90, np.uint8) + rng.integers(0, 5, (120, 160, 3),
                                                                   dtype=np.uint8)
        img[40:80, 4 * k:4 * k + 20] = 230  # a bright box moving right
        cv2.imwrite(str(folder / f"{k:06d}.jpg"), img)
    bad = folder / "000025.jpg"
    bad.write_bytes(bad.read_bytes()[: bad.stat().st_size // 2])
    status = main(["track", str(folder), "--out-dir", str(tmp_path / "a"), "--quiet",
                   "--min-area", "50", "--fps", "10"])
    err = capsys.readouterr().err
    assert status == 2 and "000025.jpg" in err and "cut short" in err
    assert not (tmp_path / "a" / "tracks.txt").exists()
    status = main(["track", str(folder), "--out-dir", str(tmp_path / "b"), "--quiet",
                   "--min-area", "50", "--fps", "10", "--skip-bad-frames"])
    err = capsys.readouterr().err
    assert status == 0
    warned = [line for line in err.splitlines() if "warning" in line]
    assert len(warned) == 1 and warned[0].startswith("vistrack track: warning: ")
    assert "000025.jpg" in warned[0]
    frames = read_mot(tmp_path / "b" / "tracks.txt").frames
    assert 25 not in frames and frames.max() > 25  # the frame after it keeps its number


def test_skip_bad_frames_with_video_files_only_is_refused(tmp_path, capsys):
    """--skip-bad-frames reads image folders; with a video file (or several inputs all video
    files) it would change nothing, and was dropped without a word."""
    import shutil

    from vistrack.data import demo_clip

    clip = tmp_path / "clip.mp4"
    shutil.copy(demo_clip().video, clip)
    out = tmp_path / "out"
    assert main(["track", str(clip), "--out-dir", str(out), "--skip-bad-frames"]) == 2
    assert (f"--skip-bad-frames goes with an image folder (or a sequence folder's img1/); "
            f"{clip} is a video file, decoded as it is") in capsys.readouterr().err
    assert main(["track", str(clip), str(demo_clip().video), "--out-dir", str(out),
                 "--skip-bad-frames"]) == 2
    assert (f"{clip}, {demo_clip().video} are video files, decoded as they are"
            in capsys.readouterr().err)
    assert not out.exists()


def test_a_detections_file_given_to_out_dir_is_refused_naming_out(tmp_path, capsys):
    """``vistrack track det.txt --out-dir OUT`` (a detections file in the mode for pixels):
    OpenCV decoded the text as 243 frames of noise and the run "tracked" them, 0 boxes."""
    assert main(["track", str(GT), "--out-dir", str(tmp_path / "out")]) == 2
    one_line(capsys, "track", f"--out-dir is for a video, image folder or sequence folder from "
             f"pixels, and {GT} is a detections file: track it with --out RESULTS.txt (and its "
             "frame rate, --fps)")
    assert not (tmp_path / "out").exists()


def test_eval_takes_a_sequence_folder_for_its_ground_truth(tmp_path, capsys):
    """``--gt SEQ`` (as vistrack track takes a sequence) scores against SEQ/gt/gt.txt, with
    SEQ/seqinfo.ini; a folder without gt/gt.txt is named."""
    seq = tmp_path / "SEQ-1"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_bytes(GT.read_bytes())
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=SEQ-1\nseqLength=200\nframeRate=7\n"
                                     "imWidth=768\nimHeight=576\n")
    assert main(["eval", "--gt", str(seq / "gt" / "gt.txt"), "--pred", str(GT), "--json"]) == 0
    want = capsys.readouterr().out
    assert main(["eval", "--gt", str(seq), "--pred", str(GT), "--json"]) == 0
    assert capsys.readouterr().out == want and '"SEQ-1"' in want
    assert main(["eval", "--gt", str(tmp_path), "--pred", str(GT)]) == 2
    one_line(capsys, "eval", f"--gt {tmp_path} is a folder without gt/gt.txt: give a "
             "ground-truth file, or a sequence folder that holds gt/gt.txt")


def test_eval_errors_are_one_line_and_debug_shows_them(tmp_path, capsys):
    """A missing file is named with its option (it was "nothere.txt: No such file or
    directory"); a malformed one by its line, and with --debug its traceback."""
    missing = tmp_path / "nothere.txt"
    assert main(["eval", "--gt", str(missing), "--pred", str(GT)]) == 2
    one_line(capsys, "eval", f"--gt {missing} does not exist")
    assert main(["eval", "--gt", str(GT), "--pred", str(missing)]) == 2
    one_line(capsys, "eval", f"--pred {missing} does not exist")
    bad = tmp_path / "bad.txt"
    bad.write_text("1,1,10,10,5,5,1,-1,-1,-1\n2,x,10,10,5,5,1,-1,-1,-1\n")
    assert main(["eval", "--gt", str(GT), "--pred", str(bad)]) == 2
    assert capsys.readouterr().err.startswith(f"vistrack eval: error: {bad}, line 2")
    assert main(["eval", "--debug", "--gt", str(GT), "--pred", str(bad)]) == 2
    assert "MOTFormatError" in capsys.readouterr().err


def test_a_front_end_or_detections_file_that_is_no_file_is_named(tmp_path, capsys):
    """``--frontend detections:`` with no name read ``.`` and said ".: Is a directory",
    ``onnx:`` said ". does not exist"; a folder given as the file, or to ``--detections``,
    was "Is a directory" without the option. Each names the option now, and nothing is
    written."""
    for spec, msg in (("detections:", "--frontend detections:FILE needs a file's name after "
                                      "'detections:'; got 'detections:'"),
                      ("onnx:", "--frontend onnx:MODEL.onnx needs a file's name after 'onnx:'; "
                                "got 'onnx:'"),
                      (f"detections:{tmp_path}",
                       f"{tmp_path} is a folder, not a file (--frontend detections:FILE)"),
                      (f"onnx:{tmp_path}",
                       f"{tmp_path} is a folder, not a file (--frontend onnx:MODEL.onnx)")):
        assert main(["track", str(VIDEO), "--frontend", spec, "--out-dir",
                     str(tmp_path / "o"), "--quiet"]) == 2
        one_line(capsys, "track", msg)
    seq = tmp_path / "seq"
    (seq / "det").mkdir(parents=True)
    (seq / "det" / "det.txt").write_text("1,-1,10,10,20,40,0.9\n")
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=5\n"
                                     "imWidth=100\nimHeight=100\n")
    assert main(["track", str(seq), "--detections", str(tmp_path), "--out",
                 str(tmp_path / "o.txt")]) == 2
    one_line(capsys, "track", f"{tmp_path} is a folder, not a detections file "
             "(--detections FILE)")
    assert not (tmp_path / "o").exists() and not (tmp_path / "o.txt").exists()


def test_eval_refuses_one_pair_beside_folders(tmp_path, capsys):
    """``--gt``/``--pred`` beside ``--gt-dir``/``--pred-dir``: the pair was dropped without
    a word and the folders scored."""
    for extra in (["--gt-dir", str(tmp_path)], ["--pred-dir", str(tmp_path)],
                  ["--gt-dir", str(tmp_path), "--pred-dir", str(tmp_path)]):
        assert main(["eval", "--gt", str(GT), "--pred", str(GT), *extra]) == 2
        one_line(capsys, "eval", "give --gt and --pred, or --gt-dir and --pred-dir, not both")
    assert main(["eval", "--pred", str(GT), "--gt-dir", str(tmp_path),
                 "--pred-dir", str(tmp_path)]) == 2
    one_line(capsys, "eval", "give --gt and --pred, or --gt-dir and --pred-dir, not both")


def test_a_videos_ground_truth_is_checked_before_anything_is_tracked(tmp_path, capsys):
    """``--gt`` with a detections file (every id -1, so an identity twice in a frame) was
    found faulty only by the scoring, after the whole video had been tracked and its outputs
    written; a missing one was named without saying it was --gt's, and a folder was "Is a
    directory". These are refused before any output is made, and a sequence folder's
    gt/gt.txt is read, as vistrack eval --gt reads it."""
    det = tmp_path / "det.txt"
    det.write_text("".join(f"1,-1,{10 + 50 * k},20,20,40,0.9\n" for k in range(3)))
    assert main(["track", str(VIDEO), "--out-dir", str(tmp_path / "a"), "--gt", str(det),
                 "--stop", "3", "--quiet"]) == 2
    one_line(capsys, "track", f"{det}, lines 1 and 2: id -1 appears more than once in frame 1; "
             "every id is -1: it looks like a detections file (det.txt), not ground truth")
    missing = tmp_path / "nope.txt"
    assert main(["track", str(VIDEO), "--out-dir", str(tmp_path / "b"), "--gt", str(missing),
                 "--stop", "3", "--quiet"]) == 2
    one_line(capsys, "track", f"{missing} does not exist (--gt FILE)")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()
    # a folder: a sequence's, whose gt/gt.txt is read (as vistrack eval reads it), or not
    assert main(["track", str(VIDEO), "--out-dir", str(tmp_path / "c"), "--gt", str(tmp_path),
                 "--stop", "3", "--quiet"]) == 2
    one_line(capsys, "track", f"--gt {tmp_path} is a folder without gt/gt.txt: give a "
             "ground-truth file, or a sequence folder that holds gt/gt.txt")
    seq = tmp_path / "seq"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_bytes(GT.read_bytes())
    for name, gt in (("d", seq), ("e", GT)):
        assert main(["track", str(VIDEO), "--out-dir", str(tmp_path / name), "--gt", str(gt),
                     "--stop", "3", "--quiet"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [x for x in out if x.startswith("pets09")] and \
        len({x for x in out if x.startswith("pets09")}) == 1  # the same scores


def test_a_configuration_file_without_a_name_goes_over_the_tracker_given(tmp_path, capsys):
    # before: "--tracker sort disagrees with [tracker] name = "bytetrack"", a name the file
    # does not give
    import tomllib

    from vistrack.config import TrackConfig

    path = tmp_path / "f.toml"
    path.write_text("[tracker]\nhigh = 0.5\n")
    assert main(["track", "--print-config", "--tracker", "sort", "--config", str(path)]) == 0
    table = tomllib.loads(capsys.readouterr().out)["tracker"]
    sort = TrackConfig.preset("sort").tracker
    assert table["name"] == "sort" and table["high"] == 0.5
    assert table["two_stage"] == sort.two_stage and table["low"] == sort.low
    path.write_text('[tracker]\nname = "bytetrack"\n')
    assert main(["track", "--print-config", "--tracker", "sort", "--config", str(path)]) == 2
    assert 'disagrees with [tracker] name = "bytetrack"' in capsys.readouterr().err
    # a value of the file that an option makes invalid: the file is named
    path.write_text('[tracker]\nscores = "raw"\n[offline]\nstart_score = 3.0\n')
    assert main(["track", "--print-config", "--config", str(path), "--scores",
                 "calibrated"]) == 2
    said = capsys.readouterr().err
    assert f"{path}:4: [offline] start_score must be in [0, 1]" in said
    assert said.rstrip().endswith("(with --scores calibrated)")


@pytest.mark.parametrize("flag, value", [("--jobs", "2"), ("--scheduler", "tcp://x:1")])
def test_jobs_and_scheduler_go_with_several_inputs(tmp_path, capsys, flag, value):
    """One input with --jobs went the several inputs' way: --out res.txt made a folder
    res.txt/ holding NAME.txt, where without --jobs it is the file. Refused, as --keep-going
    is, before anything is read or written."""
    dets = tmp_path / "cam3.txt"
    dets.write_text("1,-1,10,20,30,60,0.9,-1,-1,-1\n")
    assert main(["track", str(dets), "--fps", "25", "--out", str(tmp_path / "res.txt"), flag,
                 value]) == 2
    one_line(capsys, "track", f"{flag} goes with several inputs (or a folder of sequences); "
             f"{dets} is one")
    assert not (tmp_path / "res.txt").exists()


def test_eval_names_a_folder_given_for_a_file_and_the_reverse(tmp_path, capsys):
    """`--pred DIR` said "Is a directory", `--pred-dir FILE` looked for FILE/SEQ.txt, and
    `--jobs` with one pair was taken without a word where `--keep-going` was refused."""
    seq = tmp_path / "SEQ"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_text("1,1,0,0,10,10,1,1,1\n")
    res = tmp_path / "res"
    res.mkdir()
    (res / "SEQ.txt").write_text("1,1,0,0,10,10,1,-1,-1,-1\n")
    assert main(["eval", "--gt", str(seq), "--pred", str(res)]) == 2
    one_line(capsys, "eval", f"--pred {res} is a folder, not a results file (a folder of them: "
             f"--gt-dir SETDIR --pred-dir {res})")
    assert main(["eval", "--gt-dir", str(tmp_path), "--pred-dir", str(res / "SEQ.txt")]) == 2
    one_line(capsys, "eval", f"--pred-dir {res / 'SEQ.txt'} is a file, not a folder (one file: "
             "--pred)")
    # a folder that does not exist is named as such (it was named as its first sequence's
    # missing results file), with --keep-going too; and so is a --gt-dir
    for keep in ([], ["--keep-going"]):
        assert main(["eval", "--gt-dir", str(tmp_path), "--pred-dir", str(tmp_path / "no"),
                     *keep]) == 2
        one_line(capsys, "eval", f"--pred-dir {tmp_path / 'no'} does not exist")
    assert main(["eval", "--gt-dir", str(tmp_path / "no"), "--pred-dir", str(res)]) == 2
    one_line(capsys, "eval", f"--gt-dir {tmp_path / 'no'} does not exist")
    # one sequence given as the set: the way to score it is named
    assert main(["eval", "--gt-dir", str(seq), "--pred-dir", str(res)]) == 2
    one_line(capsys, "eval", f"no SEQ/gt/gt.txt under {seq} ({seq} is one sequence: --gt "
             f"{seq} --pred RESULTS.txt)")
    assert main(["eval", "--gt", str(seq), "--pred", str(res / "SEQ.txt"), "--jobs", "2"]) == 2
    one_line(capsys, "eval", "--jobs goes with --gt-dir")
    assert main(["eval", "--gt-dir", str(tmp_path), "--pred-dir", str(res), "--jobs", "1"]) == 0


def _sequence(folder, n_frames=10, seqinfo=True):
    """A sequence folder of ``n_frames`` at 10 frames/s, one detection a frame."""
    (folder / "det").mkdir(parents=True)
    (folder / "det" / "det.txt").write_text("".join(
        f"{f},-1,{10 + 2 * f},20,20,40,0.9,-1,-1,-1\n" for f in range(1, n_frames + 1)))
    if seqinfo:
        (folder / "seqinfo.ini").write_text(
            f"[Sequence]\nname={folder.name}\nframeRate=10\nseqLength={n_frames}\n"
            "imWidth=200\nimHeight=100\n")
    return folder


def test_what_a_batch_or_a_folder_of_results_leaves_out_is_said(tmp_path, capsys):
    """Results that are no sequence's (a misspelt name) and sequences without ground truth
    were left out of `eval --gt-dir` without a word; a folder of sequences left out its
    sub-folders without seqinfo.ini without one ("1 of 1 inputs tracked")."""
    gt_dir, pred_dir = tmp_path / "gt", tmp_path / "pred"
    a = _sequence(gt_dir / "A")
    (a / "gt").mkdir()
    (a / "gt" / "gt.txt").write_text("".join(f"{f},1,{10 + 2 * f},20,20,40,1,1,1\n"
                                             for f in range(1, 11)))
    _sequence(gt_dir / "B")  # no ground truth
    pred_dir.mkdir()
    for name in ("A.txt", "B.txt", "a_typo.txt"):
        (pred_dir / name).write_text((a / "gt" / "gt.txt").read_text())
    assert main(["eval", "--gt-dir", str(gt_dir), "--pred-dir", str(pred_dir)]) == 0
    err = capsys.readouterr().err
    assert (f"vistrack eval: warning: 1 sequence folder of {gt_dir} has no gt/gt.txt and is "
            "left out: B\n") in err
    assert (f"vistrack eval: warning: 2 files of {pred_dir} match no sequence with ground "
            f"truth in {gt_dir} and are not scored: B.txt, a_typo.txt\n") in err
    _sequence(tmp_path / "set" / "C", seqinfo=False)
    _sequence(tmp_path / "set" / "D")
    assert main(["track", str(tmp_path / "set"), "--out", str(tmp_path / "res"), "--jobs", "1",
                 "--quiet"]) == 0
    assert (f"vistrack track: warning: {tmp_path / 'set'}: 1 folder without seqinfo.ini is no "
            "sequence of the set and is left out: C (name it as inputs, with --fps, to track "
            "them)") in capsys.readouterr().err


def test_options_of_one_input_given_to_a_batch_are_refused(tmp_path, capsys):
    """With several inputs, --frontend detections:FILE tracked every input from the one
    file, and --skip-bad-frames with --out was taken and ignored (one input refuses it)."""
    _sequence(tmp_path / "set" / "A")
    _sequence(tmp_path / "set" / "B")
    for k in (1, 2):
        (tmp_path / f"v{k}").mkdir()
    for args, message in (
            (["track", str(tmp_path / "v1"), str(tmp_path / "v2"), "--out-dir",
              str(tmp_path / "o"), "--frontend", "detections:d.txt"],
             "--frontend detections:d.txt goes with one input: a detections file is one "
             "video's"),
            (["track", str(tmp_path / "set"), "--out", str(tmp_path / "r"), "--skip-bad-frames"],
             "--skip-bad-frames goes with --out-dir")):
        assert main(args) == 2
        one_line(capsys, "track", message)


def test_an_image_folder_longer_than_its_sequence_says_so(tmp_path):
    """A sequence's img1/ with more images than seqLength was tracked whole without a word
    (fewer warned)."""
    import re

    import cv2
    import numpy as np

    from vistrack.io import VideoReader

    seq = tmp_path / "S"
    (seq / "img1").mkdir(parents=True)
    for k in range(1, 6):
        cv2.imwrite(str(seq / "img1" / f"{k:06d}.png"), np.zeros((4, 6, 3), np.uint8))
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=S\nimDir=img1\nframeRate=10\n"
                                     "seqLength=3\nimWidth=6\nimHeight=4\nimExt=.png\n")
    with pytest.warns(RuntimeWarning, match=re.escape(
            f"{seq / 'img1'} holds 5 images, but {seq / 'seqinfo.ini'} gives seqLength=3: all "
            "5 are tracked")):
        assert len(list(VideoReader(seq))) == 5


def test_a_sequence_and_its_own_images_or_detections_are_one_input(tmp_path):
    """A batch from pixels given a sequence folder and its own img1/ tracked the same frames
    twice, under two names (their paths differ)."""
    from vistrack.batch import check_distinct

    seq = _sequence(tmp_path / "S")
    (seq / "img1").mkdir()
    for other in (seq / "img1", seq / "det" / "det.txt"):
        with pytest.raises(ValueError, match=f"is given twice .*{other.relative_to(seq)} is "
                                             "the same input"):
            check_distinct([seq, other])
        with pytest.raises(ValueError, match="is given twice"):
            check_distinct([other, seq])
    check_distinct([seq, _sequence(tmp_path / "T")])  # two sequences: two inputs


def test_eval_plots_of_a_sequence_with_a_long_name_and_scores_first(tmp_path, capsys,
                                                                       monkeypatch):
    """A sequence named with 234 characters or more (a legal folder name) failed `eval
    --plots` with a traceback, "File name too long" (the plots' names add to it), and no
    score table; its timeline now goes under a name cut and told apart by a hash of the
    whole. The scores are printed before the plots are drawn: a plot that fails loses none."""
    name = "S" * 240
    gt_dir, pred_dir, plots = tmp_path / "gt", tmp_path / "pred", tmp_path / "plots"
    seq = _sequence(gt_dir / name)
    (seq / "gt").mkdir()
    (seq / "gt" / "gt.txt").write_text("".join(f"{f},1,{10 + 2 * f},20,20,40,1,1,1\n"
                                               for f in range(1, 11)))
    pred_dir.mkdir()
    (pred_dir / f"{name}.txt").write_text((seq / "gt" / "gt.txt").read_text())
    args = ["eval", "--gt-dir", str(gt_dir), "--pred-dir", str(pred_dir), "--plots",
            str(plots), "--jobs", "1"]
    assert main(args) == 0
    out, err = capsys.readouterr()
    assert out.splitlines()[1].startswith(name) and " 100.0 " in out
    timeline = [p.name for p in plots.iterdir() if p.name.startswith("timeline_")]
    assert len(timeline) == 1 and len(timeline[0]) < 160
    assert timeline[0].startswith("timeline_" + "S" * 100) and f"wrote {plots}" in err
    assert main(args + ["--force"]) == 0  # again, over them

    def broken(*a, **k):
        raise RuntimeError("the plot failed")

    monkeypatch.setattr("vistrack.viz.plots.plot_hota_alpha", broken)
    capsys.readouterr()
    with pytest.raises(RuntimeError, match="the plot failed"):
        main(args + ["--force"])
    assert name in capsys.readouterr().out  # the table came first


def test_eval_of_folders_finds_results_whose_suffix_is_upper_case(tmp_path, capsys):
    """MOT17-02.TXT beside its sequence was called missing ("MOT17-02.txt does not exist")
    and was no stray file either; --pred MOT17-02.TXT alone was scored. Found and scored the
    same now (the oracle: the same rows under a lower-case suffix)."""
    rows = "".join(f"{f},1,{10 + f},20,30,60,1,1,1\n" for f in range(1, 11))
    seq = tmp_path / "set" / "SEQ-1" / "gt"
    seq.mkdir(parents=True)
    (seq / "gt.txt").write_text(rows)
    scores = []
    for name in ("SEQ-1.txt", "SEQ-1.TXT"):
        pred = tmp_path / name.replace(".", "_")
        pred.mkdir()
        (pred / name).write_text(rows)
        assert main(["eval", "--gt-dir", str(tmp_path / "set"), "--pred-dir", str(pred),
                     "--json"]) == 0
        cap = capsys.readouterr()
        scores.append(json.loads(cap.out))
        assert "warning" not in cap.err
    assert scores[0] == scores[1] and scores[0]["SEQ-1"]["MOTA"] == 1.0


def test_columns_twice_and_an_out_over_the_config_are_refused(tmp_path, capsys):
    """``--columns frame=t,frame=a`` kept the last pair and read the file by it, the first
    going unread without a word; ``--out`` naming the ``--config`` file the run reads wrote
    the results over it (with ``--force``). Both are refused before anything is read, and
    the configuration keeps its bytes."""
    (tmp_path / "d.csv").write_text("t,a,bb_left,bb_top,bb_width,bb_height,conf\n"
                                    "1,2,10,20,30,40,0.9\n")
    assert main(["track", str(tmp_path / "d.csv"), "--out", str(tmp_path / "o.txt"),
                 "--fps", "10", "--columns", "frame=t,frame=a"]) == 2
    one_line(capsys, "track", "--columns names 'frame' twice (frame=t, frame=a); give each "
                              "of vistrack's columns one of yours")
    seq = _sequence(tmp_path / "seq")
    cfg = tmp_path / "c.toml"
    assert main(["track", "--print-config"]) == 0
    cfg.write_text(capsys.readouterr().out)
    before = cfg.read_bytes()
    assert main(["track", str(seq), "--out", str(cfg), "--config", str(cfg), "--force"]) == 2
    one_line(capsys, "track", f"--out {cfg} is the configuration file (--config): the run "
                              "would write over it; give another --out")
    assert cfg.read_bytes() == before


def test_seqinfo_frame_rate_and_length_are_checked_where_read(tmp_path):
    """``seqinfo.ini``'s frameRate out of range was named by the motion model, without the
    file or the key; its seqLength had no bound (10^12 stepped through empty frames without
    end); and ``--fps`` could not stand in for a frameRate the file lacks, though it is put
    over the file's. The tracks with ``fps`` and no frameRate are those with frameRate
    equal to it."""
    from vistrack.io.motchallenge import MOTFormatError
    from vistrack.pipeline import track_sequence

    seq = _sequence(tmp_path / "seq")
    ini = seq / "seqinfo.ini"
    track_sequence(seq, tmp_path / "ref.txt")
    text = ini.read_text()
    ini.write_text(text.replace("frameRate=10\n", ""))
    track_sequence(seq, tmp_path / "fps.txt", fps=10)
    assert (tmp_path / "fps.txt").read_bytes() == (tmp_path / "ref.txt").read_bytes()
    with pytest.raises(MOTFormatError, match=f"{re.escape(str(ini))}: \\[Sequence\\] has no "
                                             "frameRate"):
        track_sequence(seq, tmp_path / "no.txt")
    ini.write_text(text.replace("frameRate=10", "frameRate=0.0005"))
    with pytest.raises(MOTFormatError, match=re.escape(
            f"{ini}: frameRate must be from 0.001 to 1e+06 frames/s; got 0.0005 (give the "
            "true rate with --fps)")):
        track_sequence(seq, tmp_path / "slow.txt")
    track_sequence(seq, tmp_path / "slow.txt", fps=10)  # --fps over it: tracked
    ini.write_text(text.replace("seqLength=10", "seqLength=1e12"))
    with pytest.raises(MOTFormatError, match=re.escape(
            f"{ini}: seqLength must be at most 100,000,000 frames; got 1,000,000,000,000")):
        track_sequence(seq, tmp_path / "long.txt")


def _red_square_frames(tmp_path):
    """A folder of three 80 x 60 frames, a red 20 x 20 square moving 3 pixels a frame from
    (10, 20)."""
    import cv2
    import numpy as np

    folder = tmp_path / "img"
    folder.mkdir()
    for k in range(3):
        im = np.full((60, 80, 3), (40, 120, 40), np.uint8)
        im[20:40, 10 + 3 * k:30 + 3 * k] = (0, 0, 255)
        cv2.imwrite(str(folder / f"{k + 1:04d}.png"), im)
    return folder


def test_track_one_reads_a_renamed_otb_file_as_it_says_and_names_an_empty_one(tmp_path,
                                                                             capsys):
    """A copy of OTB's groundtruth_rect.txt under another name was read as counting pixels
    from 0 without a word: the start box and the scores moved by a pixel. It is now said,
    and ``--gt-origin`` says which; an empty ground truth was answered "--init is
    required", though a ground truth was given."""
    from vistrack.evaluation.single import read_boxes

    folder = _red_square_frames(tmp_path)
    otb = tmp_path / "groundtruth_rect.txt"
    otb.write_text("".join(f"{11 + 3 * k}\t21\t20\t20\n" for k in range(3)))
    renamed = tmp_path / "object_gt.txt"
    renamed.write_text(otb.read_text())
    assert main(["track-one", str(folder), "--gt", str(otb), "--out", str(tmp_path / "a.txt"),
                 "--quiet"]) == 0
    assert "warning" not in capsys.readouterr().err
    assert main(["track-one", str(folder), "--gt", str(renamed), "--out",
                 str(tmp_path / "b.txt"), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert err == (f"vistrack track-one: warning: {renamed}: its x y w h boxes are read as "
                   "counting pixels from 0, as any such file not named OTB's "
                   "groundtruth_rect.txt (which counts from 1); --gt-origin 1 reads them from "
                   "1, --gt-origin 0 keeps 0 without this warning\n")
    assert read_boxes(tmp_path / "b.txt")[0].tolist() == [11, 21, 20, 20]  # read from 0
    for bad in (2, True, "1"):  # named whatever the file holds (5 values a line here)
        with pytest.raises(ValueError, match=re.escape(f"origin must be 0, 1 or None (by the "
                                                       f"file's name); got {bad!r}")):
            read_boxes(tmp_path / "b.txt", origin=bad)
    assert main(["track-one", str(folder), "--gt", str(renamed), "--gt-origin", "1", "--out",
                 str(tmp_path / "c.txt"), "--quiet"]) == 0
    assert capsys.readouterr().err == ""
    assert (tmp_path / "c.txt").read_text() == (tmp_path / "a.txt").read_text()
    assert main(["track-one", str(folder), "--gt", str(renamed), "--gt-origin", "0", "--out",
                 str(tmp_path / "d.txt"), "--quiet"]) == 0
    assert capsys.readouterr().err == ""
    assert (tmp_path / "d.txt").read_text() == (tmp_path / "b.txt").read_text()
    empty = tmp_path / "empty.txt"
    empty.write_text("")
    assert main(["track-one", str(folder), "--gt", str(empty), "--out",
                 str(tmp_path / "e.txt")]) == 2
    one_line(capsys, "track-one", f"{empty} has no boxes, so no first box to start from: "
             "give --init, or a ground truth with a box for every frame")
    assert main(["track-one", str(folder), "--init", "10,20,20,20", "--gt-origin", "1",
                 "--out", str(tmp_path / "e.txt")]) == 2
    one_line(capsys, "track-one", "--gt-origin says where --gt's boxes count from; give --gt")


def test_the_particles_tracker_on_a_video_names_itself_for_a_missing_diameter(capsys):
    """`--tracker particles` on a video was told that "--frontend spots needs --diameter",
    an option the user never gave."""
    assert main(["track", str(VIDEO), "--tracker", "particles", "--out-dir", "x"]) == 2
    one_line(capsys, "track", "--tracker particles, whose front-end on a video is spots, "
             "needs --diameter: the spots' diameter in pixels, odd (round up)")


def test_track_one_reads_its_ground_truth_once(tmp_path, monkeypatch, capsys):
    """``track-one --gt`` read a file not named OTB's twice, the second time only to see
    whether its lines were ``x y w h`` (whose origin matters); ``read_box_lines`` says how
    many values its lines hold, so the file is read once."""
    import numpy as np

    import vistrack.evaluation.single as single

    folder = _red_square_frames(tmp_path)
    files = {4: "".join(f"{10 + 3 * k} 20 20 20\n" for k in range(3)),
             5: "".join(f"{k + 1},{10 + 3 * k},20,20,20\n" for k in range(3)),
             8: "".join(f"{x},20,{x + 20},20,{x + 20},40,{x},40\n"
                        for x in (10, 13, 16))}
    reads = []
    decode = single.decode_text
    monkeypatch.setattr(single, "decode_text", lambda *a: reads.append(a[1]) or decode(*a))
    for width, text in files.items():
        gt = tmp_path / f"gt{width}.txt"
        gt.write_text(text)
        boxes, got = single.read_box_lines(gt)
        assert got == width and boxes.shape == (3, 4)
        np.testing.assert_allclose(boxes[:, 2:], 21.0 if width == 8 else 20.0)  # (pysot's +1)
        reads.clear()
        assert main(["track-one", str(folder), "--gt", str(gt), "--out",
                     str(tmp_path / f"o{width}.txt"), "--quiet"]) == 0
        assert reads == [gt]
        warned = "its x y w h boxes are read as counting pixels from 0" in \
            capsys.readouterr().err
        assert warned == (width == 4)
    empty = tmp_path / "empty.txt"
    empty.write_text("\n")
    assert single.read_box_lines(empty)[1] == 0


def test_a_missing_detections_file_and_an_eleventh_value_are_named_plainly(bad_sequence,
                                                                            tmp_path):
    """`--detections nothere.txt` said "nothere.txt does not exist", naming no option (--gt
    and the rest name theirs); a row of 12 values said "column 11 (column 11)"."""
    r = cli("track", bad_sequence, "--out", tmp_path / "r.txt", "--detections",
            tmp_path / "no.txt")
    assert r.returncode == 2
    assert f"{tmp_path / 'no.txt'} does not exist (--detections FILE)" in r.stderr
    extra = tmp_path / "extra.txt"
    extra.write_text("1,-1,1,2,3,4,0.9,-1,-1,-1,7,8\n")
    r = cli("track", bad_sequence, "--out", tmp_path / "r.txt", "--detections", extra)
    assert r.returncode == 2
    assert f"{extra}, line 1, column 11: expected at most 10 values, got 12" in r.stderr


def test_a_confirm_hits_beyond_the_frames_is_said(tmp_path):
    """--confirm-hits 100000 on 5 frames of detections wrote the first frame's tracks alone
    (ByteTrack confirms those at once), without a word. Oracle: the file's own frames."""
    seq = tmp_path / "seq"
    (seq / "det").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=5\n"
                                     "imWidth=320\nimHeight=240\n")
    (seq / "det" / "det.txt").write_text(
        "".join(f"{f},-1,{10 + 2 * f},20,20,40,0.9,-1,-1,-1\n" for f in range(1, 6)))
    r = cli("track", seq, "--out", tmp_path / "r.txt", "--confirm-hits", 6)
    assert r.returncode == 0, r.stderr
    assert ("confirm_hits 6 (--confirm-hits) is more than its 5 frames of detections: no track "
            "is confirmed but those started on the first frame") in r.stderr
    r = cli("track", seq, "--out", tmp_path / "s.txt", "--confirm-hits", 5)
    assert "confirm_hits" not in r.stderr


def test_a_columns_pair_without_its_other_half_is_quoted_as_given(bad_sequence, tmp_path):
    """`--columns frame=` was said as "got 'frame'", its "=" lost."""
    for given in ("frame=", "=frame", "frame"):
        r = cli("track", bad_sequence, "--out", tmp_path / "r.txt", "--columns",
                f"id=track,{given}")
        assert r.returncode == 2
        assert f"--columns takes OURS=THEIRS pairs separated by commas; got {given!r}" in \
            r.stderr, r.stderr


def test_an_interrupt_inside_a_compiled_function_is_an_interrupt(capsys):
    """A signal's handler that raised as a compiled (numba) function returned made CPython
    raise SystemError ("returned a result with an exception set"), the interrupt its cause:
    SIGTERM during the front-end's moments printed a traceback and exited 1, in 1 of 15
    runs (the SIGTERM test's rare failure). Oracle: the exit statuses of SIGINT and SIGTERM,
    130 and 143, and a SystemError of another cause still raised."""
    import argparse

    from vistrack.cli import Terminated, _run

    def raises(stop):
        def run(args):
            try:
                raise stop
            except BaseException as e:
                raise SystemError("CPUDispatcher(<function _moments>) returned a result with "
                                  "an exception set") from e
        return run

    for stop, status, how in ((Terminated(), 143, "terminated"),
                              (KeyboardInterrupt(), 130, "interrupted")):
        args = argparse.Namespace(command="eval", func=raises(stop), debug=False)
        assert _run(args) == status
        assert capsys.readouterr().err == f"vistrack eval: {how}\n"
    args = argparse.Namespace(command="eval", func=raises(ValueError("x")), debug=False)
    with pytest.raises(SystemError):
        _run(args)


def test_options_that_mean_nothing_alone_and_a_tracker_that_is_no_callable(tmp_path, capsys,
                                                                           monkeypatch):
    """`eval --force` without --plots and `fit --no-held-out` without --gt were taken and did
    nothing; `--tracker mod:NAME` whose NAME is no callable said "'int' object is not
    callable", naming nothing; an empty ground truth was scored as all false positives
    without a word (an empty results file was warned of)."""
    from vistrack.cli import main

    gt, res = tmp_path / "gt.txt", tmp_path / "res.txt"
    gt.write_text("")
    res.write_text("1,1,0,0,10,10,1,-1,-1,-1\n2,1,0,0,10,10,1,-1,-1,-1\n")
    assert main(["eval", "--gt", str(gt), "--pred", str(res), "--force"]) == 2
    assert capsys.readouterr().err == "vistrack eval: error: --force goes with --plots\n"
    assert main(["eval", "--gt", str(gt), "--pred", str(res)]) == 0
    assert (f"{gt} holds no rows: the 2 rows of {res} on its frames 1-2 count as false "
            "positives (FP)") in capsys.readouterr().err
    assert main(["fit", str(tmp_path), "--out", str(tmp_path / "c.toml"),
                 "--no-held-out"]) == 2
    assert capsys.readouterr().err == "vistrack fit: error: --no-held-out goes with --gt\n"
    (tmp_path / "mymod.py").write_text("notcallable = 3\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert main(["track", str(VIDEO), "--out-dir", str(tmp_path / "o"), "--stop", "2",
                 "--tracker", "mymod:notcallable"]) == 2
    assert capsys.readouterr().err == (
        "vistrack track: error: tracker 'mymod:notcallable': notcallable = 3, not a callable "
        "that makes a tracker\n")


def test_an_input_that_does_not_exist_is_named_before_an_existing_output(tmp_path, capsys):
    """A missing input beside an output that exists said "pass --force"; given --force, the
    next run named the input. The input is named first, in the words a run without the
    output names it (the oracle: the same command with a new output)."""
    out_dir, res = tmp_path / "out", tmp_path / "res.txt"
    out_dir.mkdir()
    (out_dir / "tracks.txt").write_text("an earlier run's\n")
    res.write_text("an earlier run's\n")
    seq = tmp_path / "SEQ"
    (seq / "det").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=SEQ\nframeRate=10\nseqLength=3\n"
                                     "imWidth=100\nimHeight=80\n")
    (seq / "det" / "det.txt").write_text("1,-1,10,10,20,20,0.9,-1,-1,-1\n")
    gone = str(tmp_path / "gone.txt")
    cases = [
        ("track", [str(tmp_path / "missing.mp4")], "--out-dir", out_dir),
        ("track", [str(tmp_path / "missing")], "--out", res),
        ("track", [str(VIDEO), "--gt", gone], "--out-dir", out_dir),
        ("track", [str(VIDEO), "--frontend", f"detections:{gone}"], "--out-dir", out_dir),
        ("track", [str(seq), "--detections", gone], "--out", res),
        ("track", [str(VIDEO), "--frontend", f"onnx:{tmp_path / 'gone.onnx'}"], "--out-dir",
         out_dir),
        ("track-one", [str(tmp_path / "missing.mp4"), "--init", "1,1,5,5"], "--out", res),
        ("track-one", [str(VIDEO), "--gt", gone], "--out", res),
    ]
    for command, argv, flag, existing in cases:
        new = tmp_path / ("new" if flag == "--out-dir" else "new.txt")
        assert main([command, *argv, flag, str(new)]) == 2
        _, want = capsys.readouterr()
        assert "does not exist" in want, want
        assert main([command, *argv, flag, str(existing)]) == 2
        assert capsys.readouterr() == ("", want)
        assert not new.exists()
    assert (out_dir / "tracks.txt").read_text() == res.read_text() == "an earlier run's\n"
    # an option of the other mode is named before the file it names is looked for
    assert main(["track", str(seq), "--out", str(tmp_path / "new.txt"), "--frontend",
                 f"detections:{gone}"]) == 2
    one_line(capsys, "track", "--frontend goes with --out-dir")


def test_one_frame_is_said_as_one(tmp_path, capsys):
    """A folder of one image: `track-one` said "1 boxes; colour 0 frames/s" (no frame was
    followed after the start, so there is no rate), and `track` "found nothing in 1
    frames". Oracle: the count of images given."""
    import cv2
    import numpy as np

    folder = tmp_path / "one"
    folder.mkdir()
    image = np.full((120, 160, 3), 90, np.uint8)
    image[40:80, 60:90] = (20, 40, 200)
    cv2.imwrite(str(folder / "000001.png"), image)
    out = tmp_path / "box.txt"
    assert main(["track-one", str(folder), "--init", "60,40,30,40", "--out", str(out)]) == 0
    assert capsys.readouterr().out == (f"wrote {out}: 1 box; colour started on the first "
                                       "frame, with none after it to follow\n")
    assert len(out.read_text().splitlines()) == 1
    assert main(["track", str(folder), "--out-dir", str(tmp_path / "t"), "--quiet"]) == 0
    assert (f"{folder}: the bgsub front-end found nothing in 1 frame (blobs of 500 pixels"
            in capsys.readouterr().err)


def test_an_existing_output_is_said_in_the_callers_words(tmp_path, capsys):
    """Python callers were told "pass --force" where their option is `force=True`
    (`track_many`'s outcomes, `track_sequence`, `write_boxes`); the command line still says
    `--force`. Oracle: the option each caller has."""
    from vistrack.io.tracks import write_boxes
    from vistrack.pipeline import track_sequence

    det = tmp_path / "cam.txt"
    det.write_text("".join(f"{f},-1,{10 + 2 * f},20,30,60,0.9\n" for f in range(1, 11)))
    out = tmp_path / "res.txt"
    out.write_text("")
    with pytest.raises(FileExistsError, match=re.escape(
            f"out {out} exists; pass force=True to overwrite it")):
        track_sequence(det, out, fps=10)
    with pytest.raises(FileExistsError, match=re.escape(
            f"{out} exists; pass force=True to overwrite it")):
        write_boxes(out, [[1.0, 2.0, 3.0, 4.0]])
    assert main(["track", str(det), "--fps", "10", "--out", str(out)]) == 2
    assert f"--out {out} exists; pass --force to overwrite it" in capsys.readouterr().err


def test_two_inputs_of_one_name_are_told_how_to_be_tracked(tmp_path, capsys):
    """Two image folders both called img (each OTB sequence keeps its frames in img/) would
    write one output; the message said so and nothing more."""
    import cv2
    import numpy as np

    for seq in ("a", "b"):
        (tmp_path / seq / "img").mkdir(parents=True)
        for k in range(2):
            cv2.imwrite(str(tmp_path / seq / "img" / f"{k + 1:04d}.jpg"),
                        np.zeros((20, 30, 3), np.uint8))
    out = tmp_path / "out"
    assert main(["track", str(tmp_path / "a" / "img"), str(tmp_path / "b" / "img"),
                 "--out-dir", str(out), "--fps", "25", "--quiet"]) == 2
    assert capsys.readouterr().err == (
        f"vistrack track: error: {tmp_path / 'a' / 'img'} and {tmp_path / 'b' / 'img'} would "
        f"both write {out / 'img'} (outputs are named after each input): track them one at "
        "a time, each into its own output folder\n")


def test_a_config_files_offline_mode_with_out_dir_is_named_by_the_file(tmp_path, capsys):
    """A --config file whose [offline] table enables the offline mode, given with --out-dir,
    was refused in words about --offline, an option never given; the file is named now (one
    input or several). --offline itself is still named as before."""
    import cv2
    import numpy as np

    from vistrack.data import demo_clip

    clip = demo_clip().video
    assert main(["track", "--print-config", "--offline"]) == 0
    cfg = tmp_path / "c1.toml"
    cfg.write_text(capsys.readouterr().out)
    folders = []
    for k in range(2):
        f = tmp_path / f"imgs{k}"
        f.mkdir()
        cv2.imwrite(str(f / "000001.png"), np.zeros((16, 16, 3), np.uint8))
        folders.append(str(f))
    said = (f"vistrack track: error: {cfg}: [offline] enabled = true goes with --out, a "
            "sequence's detections into a results file (with --out-dir a video is tracked "
            "online: set it false, or give --out)")
    for inputs in ([str(clip)], folders):
        assert main(["track", *inputs, "--out-dir", str(tmp_path / "o"), "--config",
                     str(cfg), "--fps", "10"]) == 2
        assert capsys.readouterr().err.strip() == said
        assert main(["track", *inputs, "--out-dir", str(tmp_path / "o"), "--offline",
                     "--fps", "10"]) == 2
        assert "--offline, its settings and --detections go with --out" in \
            capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_parquet_detections_are_said_not_to_be_read(tmp_path, capsys):
    """A Parquet file of detections (vistrack writes Parquet results) given to --out was sent
    to --out-dir as a video, and given as --detections was "not a text MOTChallenge file"."""
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    dets = tmp_path / "o.parquet"
    pd.DataFrame({"frame": [1], "bb_left": [1.0], "bb_top": [1.0], "bb_width": [3.0],
                  "bb_height": [3.0], "conf": [0.5]}).to_parquet(dets)
    said = "Parquet detections are not read: write them as CSV with a header, " \
           "DataFrame.to_csv, or as MOTChallenge text"
    assert main(["track", str(dets), "--fps", "25", "--out", str(tmp_path / "p.txt")]) == 2
    err = capsys.readouterr().err
    assert f"{dets} is neither ({said})" in err and "--out-dir" not in err.split("neither")[1]
    seq = tmp_path / "seq"
    (seq / "det").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=2\n"
                                     "imWidth=320\nimHeight=240\n")
    (seq / "det" / "det.txt").write_text("1,-1,10,10,20,40,0.9\n")
    assert main(["track", str(seq), "--detections", str(dets), "--out",
                 str(tmp_path / "p.txt")]) == 2
    assert capsys.readouterr().err.strip() == f"vistrack track: error: {dets}: {said}"
    assert not (tmp_path / "p.txt").exists()

"""vistrack report: one self-contained HTML page of a video run, opened in a real browser
(Debian's headless Chromium, which .ci/run installs when missing): no console message, every
image shown, the video decoded, and a screenshot that is not blank."""

import html
import json
import re
import shutil
import subprocess

import numpy as np
import pytest

from vistrack.cli import main
from vistrack.data import demo_clip


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "run"
    clip = demo_clip()
    assert main(["track", str(clip.video), "--gt", str(clip.gt), "--stop", "40", "--out-dir",
                 str(out), "--report"]) == 0
    return out


def test_the_page_holds_the_run(run_dir):
    page = (run_dir / "report.html").read_text()
    info = json.loads((run_dir / "run.json").read_text())
    assert info["command"].startswith("vistrack track ") and "--report" in info["command"]
    assert (info["frames"], info["first_frame"], info["last_frame"]) == (40, 1, 40)
    assert info["scores"]["TP"] > 0
    assert f"<pre>{info['command']}</pre>" in page
    # the score table shows the run's own scores
    assert f"<td>{100 * info['scores']['HOTA']:.1f}</td>" in page
    assert f"<td>{info['scores']['IDSW']}</td>" in page
    # everything inside the page: every source a data: URI
    sources = re.findall(r"""(?:src|href)=['"]([^'"]{0,30})""", page)
    assert sources and all(s.startswith("data:") for s in sources), sources
    assert page.count("<img ") == 3  # trajectories, HOTA over alpha, the timeline
    assert page.count("<video ") == 1


def test_report_command_and_its_errors(run_dir, tmp_path, capsys):
    assert main(["report", str(run_dir)]) == 2
    # the option's words (it said "pass force=True (--force)", Python's argument beside it)
    assert capsys.readouterr().err == (f"vistrack report: error: report {run_dir / 'report.html'}"
                                       " exists; pass --force to overwrite it\n")
    assert main(["report", str(run_dir), "--force"]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {run_dir / 'report.html'}"
    assert main(["report", str(tmp_path)]) == 2
    assert "tracks.txt does not exist" in capsys.readouterr().err
    # a file: it said FILE/tracks.txt does not exist
    (tmp_path / "afile").write_text("")
    assert main(["report", str(tmp_path / "afile")]) == 2
    assert capsys.readouterr().err == (f"vistrack report: error: {tmp_path / 'afile'} is a "
                                       "file: give the folder that vistrack track --out-dir "
                                       "wrote\n")
    # no such folder: it said NOPE/tracks.txt does not exist, as if the folder were there
    assert main(["report", str(tmp_path / "nope")]) == 2
    assert capsys.readouterr().err == (f"vistrack report: error: {tmp_path / 'nope'} does not "
                                       "exist: give the folder that vistrack track --out-dir "
                                       "wrote\n")
    # without run.json: what the folder holds
    bare = tmp_path / "bare"
    bare.mkdir()
    for name in ("tracks.txt", "trajectories.png"):
        shutil.copy(run_dir / name, bare / name)
    assert main(["report", str(bare)]) == 0
    page = (bare / "report.html").read_text()
    assert "<h1>vistrack report: bare</h1>" in page and page.count("<img ") == 1


def test_a_run_over_an_earlier_ones_outputs_removes_its_page(run_dir, tmp_path, capsys):
    """A run with --force replaced every output of an earlier run in the folder but left
    its report.html, which still showed the earlier tracks and scores; without --force the
    list of files in the way left the page out. Both now count it."""
    out = tmp_path / "run"
    shutil.copytree(run_dir, out)
    clip = demo_clip()
    args = ["track", str(clip.video), "--stop", "5", "--out-dir", str(out), "--quiet"]
    assert main(args) == 2
    assert f"{out / 'report.html'} exist; pass --force" in capsys.readouterr().err
    assert main(args + ["--force"]) == 0
    assert not (out / "report.html").exists()
    assert json.loads((out / "run.json").read_text())["frames"] == 5


def _browser() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    pytest.skip("no headless Chromium here (.ci/run installs Debian's chromium package)")


@pytest.mark.slow
def test_the_page_in_a_real_browser(run_dir, tmp_path):
    browser = _browser()
    page = (run_dir / "report.html").resolve().as_uri()
    common = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
              "--enable-logging=stderr", "--v=0", "--virtual-time-budget=15000",
              f"--user-data-dir={tmp_path / 'profile'}"]
    # the video is marked once the browser has decoded its first frame; where the browser's
    # virtual time ran out before that (a test process on each core beside it: the video
    # neither marked playable nor failed: once in four runs of `make test` on 2026-12-02),
    # it is asked again
    for _ in range(3):
        dom = subprocess.run(common + ["--dump-dom", page], capture_output=True, text=True,
                             timeout=180)
        assert dom.returncode == 0, dom.stderr[-2000:]
        states = re.findall(r'data-state="([a-z]+)"', dom.stdout)
        if {"playable", "error"} & set(states):
            break
    console = [line for line in dom.stderr.splitlines() if ":CONSOLE" in line]
    assert not console, console  # no error, no warning, nothing logged by the page
    assert sorted(states) == ["playable", "shown", "shown", "shown"], states
    shot = tmp_path / "shot.png"
    subprocess.run(common + [f"--screenshot={shot}", "--window-size=1280,1400", page],
                   capture_output=True, timeout=180, check=True)
    import cv2

    image = cv2.imread(str(shot))
    assert image is not None and image.shape[:2] == (1400, 1280)
    assert image.std() > 20  # not blank: text, the table, the video's frame
    # the video's frame is drawn: a region of many colours, not the page's white
    colours = len(np.unique(image.reshape(-1, 3) // 32, axis=0))
    assert colours > 50, colours


def test_report_goes_with_one_video(tmp_path, capsys):
    from tests.test_fit import _sequence

    seq = _sequence(tmp_path / "SIM", np.random.default_rng(0), n_objects=2, T=5)
    assert main(["track", str(seq), "--out", str(tmp_path / "t.txt"), "--report"]) == 2
    assert "--report goes with --out-dir" in capsys.readouterr().err
    assert main(["track", str(seq), "--out", str(tmp_path / "t.txt")]) == 0  # without it: fine
    assert main(["track", str(seq), str(seq), "--out-dir", str(tmp_path / "many"),
                 "--report"]) == 2
    assert "--report goes with one input" in capsys.readouterr().err


def test_a_ground_truth_gone_is_said(run_dir, tmp_path):
    moved = tmp_path / "moved"
    shutil.copytree(run_dir, moved)
    (moved / "report.html").unlink()
    info = json.loads((moved / "run.json").read_text())
    info["gt"] = str(tmp_path / "gone" / "gt.txt")
    (moved / "run.json").write_text(json.dumps(info))
    assert main(["report", str(moved)]) == 0
    page = (moved / "report.html").read_text()
    assert "is not there any more" in page and page.count("<img ") == 1  # trajectories only
    assert f"<td>{100 * info['scores']['HOTA']:.1f}</td>" in page  # the scores kept in run.json


def test_a_video_or_plot_gone_is_said(run_dir, tmp_path, capsys):
    """A folder whose annotated.mp4 (or trajectories.png) was removed gets a page that says
    so, and a warning; before, the page left the video out without a word."""
    moved = tmp_path / "moved"
    shutil.copytree(run_dir, moved)
    (moved / "annotated.mp4").unlink()
    assert main(["report", str(moved), "--force"]) == 0
    page = (moved / "report.html").read_text()
    assert "<video" not in page and page.count("<img ") == 3  # trajectories, HOTA, timeline
    assert f"No annotated.mp4 in {moved} when this page was written: no annotated video." in page
    assert f"warning: {moved}: no annotated.mp4: the report has no annotated video" in \
        capsys.readouterr().err
    (moved / "trajectories.png").unlink()
    assert main(["report", str(moved), "--force"]) == 0
    assert ("no annotated.mp4 nor trajectories.png: the report has no annotated video nor "
            "plot of the trajectories") in capsys.readouterr().err
    assert (moved / "report.html").read_text().count("<img ") == 2


def test_a_run_description_that_is_not_an_object_is_named(run_dir, tmp_path, capsys):
    """A run.json holding a JSON list (or number) failed with AttributeError: 'list' object
    has no attribute 'get'."""
    odd = tmp_path / "odd"
    shutil.copytree(run_dir, odd)
    (odd / "run.json").write_text("[1, 2]")
    assert main(["report", str(odd), "--force"]) == 2
    assert capsys.readouterr().err.strip() == (f"vistrack report: error: {odd / 'run.json'}: not "
                                               "a run's description (a JSON list, not an "
                                               "object)")


@pytest.mark.parametrize("patch, said", [
    ({"scores": {"HOTA": 1}}, "its scores have no DetA, AssA, MOTA, ..."),
    ({"fps": "x"}, "fps is 'x'"),
    ({"gt": 5}, "gt is 5"),
    ({"first_frame": "a"}, "first_frame is 'a'"),
])
def test_a_run_description_of_other_fields_is_named(run_dir, tmp_path, capsys, patch, said):
    """A run.json whose fields hold other kinds of value (hand-edited, or another tool's)
    failed with a KeyError's traceback (a score without DetA, status 1) or in Python's words
    naming no file ("Unknown format code 'f'", "invalid literal for int()")."""
    odd = tmp_path / "odd"
    shutil.copytree(run_dir, odd)
    info = json.loads((odd / "run.json").read_text())
    (odd / "run.json").write_text(json.dumps({**info, **patch}))
    assert main(["report", str(odd), "--force"]) == 2
    assert capsys.readouterr().err.strip() == (f"vistrack report: error: {odd / 'run.json'}: not "
                                               f"a run's description ({said})")


def test_a_run_without_a_video_by_choice_is_not_said_to_have_lost_it(tmp_path):
    """track_video(annotate=False) writes no annotated.mp4, and run.json lists what it wrote:
    the page and the command say nothing of a missing video (they did), but a plot removed
    afterwards is still named."""
    import warnings

    from vistrack.pipeline import track_video
    from vistrack.report import write_report

    clip = demo_clip()
    out = tmp_path / "run"
    track_video(clip.video, out, stop=10, annotate=False)
    assert "annotated.mp4" not in json.loads((out / "run.json").read_text())["outputs"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        page = write_report(out).read_text()
    assert "<video" not in page and "No annotated.mp4" not in page
    (out / "trajectories.png").unlink()
    with pytest.warns(RuntimeWarning, match=r"no trajectories.png: the report has no plot"):
        write_report(out, force=True)


def test_a_ground_truth_given_as_its_sequence_folder_is_shown(tmp_path, capsys):
    """--gt SEQ_FOLDER (its gt/gt.txt scored) was stored in run.json as the folder, which the
    page took for a ground truth gone: "is not there any more", without the HOTA-over-alpha
    plot and the timeline. run.json now names the file scored."""
    clip = demo_clip()
    seq = tmp_path / "seq"
    (seq / "gt").mkdir(parents=True)
    shutil.copy(clip.gt, seq / "gt" / "gt.txt")
    out = tmp_path / "run"
    assert main(["track", str(clip.video), "--gt", str(seq), "--stop", "20", "--out-dir",
                 str(out), "--report"]) == 0
    capsys.readouterr()
    assert json.loads((out / "run.json").read_text())["gt"] == str((seq / "gt" / "gt.txt")
                                                                 .resolve())
    page = (out / "report.html").read_text()
    assert "not there any more" not in page and page.count("<img ") == 3


def test_the_run_keeps_its_warnings_and_the_page_lists_them(run_dir, tmp_path, capsys):
    """A run's warnings went to stderr only: a batch of videos printed them interleaved, and
    nothing beside the outputs said that a run had been warned (an assumed frame rate, a
    moving view). run.json now keeps each message as it was shown, and the page lists them;
    a run with nothing to say keeps an empty list and the page has no such section."""
    import cv2

    assert json.loads((run_dir / "run.json").read_text())["warnings"] == []
    assert "<h2>Warnings</h2>" not in (run_dir / "report.html").read_text()

    folder = tmp_path / "frames"  # an image folder: no frame rate to read
    folder.mkdir()
    for k in range(4):
        im = np.zeros((60, 80, 3), np.uint8)
        im[20:40, 10 + 5 * k:30 + 5 * k] = 255
        cv2.imwrite(str(folder / f"{k + 1:06d}.png"), im)
    out = tmp_path / "out"
    capsys.readouterr()
    assert main(["track", str(folder), "--out-dir", str(out), "--report", "--quiet",
                 "--min-area", "50"]) == 0  # (the square's blobs: found)
    printed = [line.removeprefix("vistrack track: warning: ")
               for line in capsys.readouterr().err.splitlines()
               if line.startswith("vistrack track: warning: ")]
    kept = json.loads((out / "run.json").read_text())["warnings"]
    assert kept == printed and len(kept) == 1
    assert kept[0].startswith(f"{folder} gives no frame rate")
    page = (out / "report.html").read_text()
    assert f"<h2>Warnings</h2><ul class='warnings'><li>{html.escape(kept[0])}</li></ul>" in page
    # the command's own warnings too, given before the run (a setting that changes nothing):
    # they were printed and left out of run.json and the page
    assert main(["track", str(folder), "--out-dir", str(out), "--report", "--quiet", "--force",
                 "--min-area", "50", "--tracker", "sort", "--low", "0.2"]) == 0
    printed = [line.removeprefix("vistrack track: warning: ")
               for line in capsys.readouterr().err.splitlines()
               if line.startswith("vistrack track: warning: ")]
    kept = json.loads((out / "run.json").read_text())["warnings"]
    assert kept == printed and len(kept) == 2 and kept[0].startswith("--low: ")
    assert html.escape(kept[0]) in (out / "report.html").read_text()


def test_the_page_says_the_frame_rate_the_run_said(tmp_path, capsys):
    """run.json kept the rate rounded to a tenth and the page rounded it again: a run at
    81.46 frames/s said 81 and its page 82. It is kept whole now, and both round it once."""
    clip = demo_clip()
    out = tmp_path / "run"
    assert main(["track", str(clip.video), "--stop", "12", "--out-dir", str(out),
                 "--report"]) == 0
    said = re.search(r"(\d+) frames/s without writing", capsys.readouterr().out).group(1)
    fps = json.loads((out / "run.json").read_text())["fps"]
    assert f"{fps:.0f}" == said
    assert f"{said} frames/s without writing" in (out / "report.html").read_text()
    assert fps != round(fps, 1)  # the rate as measured, not rounded to a tenth


def test_an_interrupt_while_the_page_is_made_says_the_outputs_were_written(
        tmp_path, monkeypatch, capsys):
    """The page is made (seconds, to re-encode the video) after the run's outputs are in
    place: an interrupt then said "earlier outputs are kept" of outputs already replaced."""
    import vistrack.report

    def stopped(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(vistrack.report, "write_report", stopped)
    out = tmp_path / "run"
    assert main(["track", str(demo_clip().video), "--stop", "5", "--out-dir", str(out),
                 "--report", "--quiet"]) == 130
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("vistrack track: interrupted after this run's outputs were written (")
    assert err.endswith("); the report page was not") and str(out / "tracks.txt") in err
    assert (out / "tracks.txt").exists() and not (out / "report.html").exists()


def test_a_points_runs_folder_is_read_by_its_run_description(tmp_path, capsys):
    """A points run's folder (tracks.csv, no tracks.txt) whose run.json could not be read
    was taken for a box run's: "tracks.txt does not exist", where run.json was the fault;
    without run.json it said the same of a folder holding tracks.csv. Now run.json is read
    first and named, and a folder of tracks.csv alone is a points run's."""
    pts = tmp_path / "pts"
    pts.mkdir()
    (pts / "tracks.csv").write_text("frame,particle,x,y\n1,1,10.0,12.0\n2,1,11.0,12.5\n")
    assert main(["report", str(pts)]) == 0
    assert "<h1>vistrack report: pts</h1>" in (pts / "report.html").read_text()
    capsys.readouterr()  # (its warning: no video nor plot)
    (pts / "run.json").write_text('{"points": true, broken')
    assert main(["report", str(pts), "--force"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"vistrack report: error: {pts / 'run.json'}: not a run's "
                          "description (Expecting property name enclosed in double quotes: "
                          "line 1 column 18")


def test_a_page_that_fails_still_shows_the_runs_files_and_scores(tmp_path, monkeypatch,
                                                                   capsys):
    """The page is made after the run's outputs and scores: when it failed (an OpenCV
    without a WebM encoder), the command ended with the error alone, the files written and
    the scores not shown."""
    import vistrack.report
    from vistrack.io import VideoError

    def fails(*args, **kwargs):
        raise VideoError("annotated.mp4: cannot be re-encoded")

    monkeypatch.setattr(vistrack.report, "_webm", fails)
    out, clip = tmp_path / "run", demo_clip()
    assert main(["track", str(clip.video), "--gt", str(clip.gt), "--stop", "5", "--out-dir",
                 str(out), "--report", "--quiet"]) == 2
    said = capsys.readouterr()
    lines = said.out.splitlines()
    assert [ln.split()[0] for ln in lines[1:5]] == ["tracks", "csv", "video", "plot"]
    assert lines[5].split()[:2] == ["sequence", "HOTA"] and lines[6].startswith("pets09-s2l1")
    assert lines[7] == ("  the files above are written; --report's page is not, for the "
                        "error below")
    assert said.err.strip() == "vistrack track: error: annotated.mp4: cannot be re-encoded"
    assert (out / "tracks.txt").exists() and not (out / "report.html").exists()


def test_a_folder_without_its_run_description_is_said(run_dir, tmp_path, capsys):
    """A run folder whose run.json was removed gave a page without the command, the counts
    and the scores (the run had --gt), without a word, where a missing video is said."""
    moved = tmp_path / "moved"
    shutil.copytree(run_dir, moved)
    (moved / "run.json").unlink()
    assert main(["report", str(moved), "--force"]) == 0
    assert (f"warning: {moved}: no run.json: the report has no command, counts, warnings or "
            "scores of the run, only its files") in capsys.readouterr().err
    assert "<h2>Scores</h2>" not in (moved / "report.html").read_text()


def test_the_folder_of_several_runs_names_them_and_dot_has_a_title(run_dir, tmp_path, capsys,
                                                                   monkeypatch):
    """The folder --out-dir took for several inputs (a folder each) said "tracks.txt does
    not exist: give the folder that vistrack track --out-dir wrote", the very folder given;
    it names the runs inside. `vistrack report .` without run.json titled the page
    "vistrack report: " (the name of ".")."""
    several = tmp_path / "several"
    for name in ("a", "b"):
        shutil.copytree(run_dir, several / name)
    assert main(["report", str(several)]) == 2
    assert capsys.readouterr().err == (
        f"vistrack report: error: {several} holds no run of its own, but runs in folders of "
        f"their own ({several / 'a'}, {several / 'b'}): give one of them\n")
    shutil.rmtree(several / "b")  # (as `vistrack demo track --out OUT` leaves OUT)
    assert main(["report", str(several)]) == 2
    assert capsys.readouterr().err == (
        f"vistrack report: error: {several} holds no run of its own, but the run in "
        f"{several / 'a'}: give that folder\n")
    bare = tmp_path / "bare-dot"
    bare.mkdir()
    shutil.copy(run_dir / "tracks.txt", bare / "tracks.txt")
    monkeypatch.chdir(bare)
    assert main(["report", "."]) == 0
    assert "<h1>vistrack report: bare-dot</h1>" in (bare / "report.html").read_text()


@pytest.mark.parametrize("size, want", [((640, 480), (640, 480)), ((768, 576), (768, 576)),
                                        ((1280, 720), (1280, 720)), ((1920, 1080), (1280, 720)),
                                        ((1080, 1920), (720, 1280)), ((960, 200), (960, 200))])
def test_the_pages_video_is_shrunk_no_further_than_its_labels_read(tmp_path, size, want):
    """Every video was shrunk to 640 pixels across: a 1920 x 1080 one's identity numbers,
    drawn 1.5 times as large as at 720 rows (the annotator's text scale), came out 7 pixels
    tall, a blur, and a 1280 x 720 one's, drawn at scale 1, half their size. Shrunk by that
    scale now, to 720 pixels on the short side, where the labels are as large as drawn on a
    frame of that size. Oracle: the WebM decoded back (its frame size)."""
    import cv2

    from vistrack.report import _webm
    from vistrack.viz.annotate import text_scale

    w, h = size
    path = tmp_path / "v.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 10, (w, h))
    for k in range(3):
        writer.write(np.full((h, w, 3), 60 * k, np.uint8))
    writer.release()
    (tmp_path / "v.webm").write_bytes(_webm(path))
    cap = cv2.VideoCapture(str(tmp_path / "v.webm"))
    ok, frame = cap.read()
    assert ok and (frame.shape[1], frame.shape[0]) == want
    # the labels as large as the annotator's text at scale 1
    assert want[0] / w * text_scale((h, w)) == pytest.approx(1.0, abs=2 / w)


def test_the_pages_counts_say_one_in_the_singular(tmp_path):
    """"1 frames of x.mp4: 1 boxes of 1 tracks" where the command line says "1 frame"."""
    from vistrack.report import write_report

    d = tmp_path / "one"
    d.mkdir()
    (d / "tracks.txt").write_text("1,1,10,10,20,40,1,-1,-1,-1\n")
    info = {"name": "x", "input": "x.mp4", "frames": 1, "rows": 1, "tracks": 1, "fps": 50.0,
            "outputs": ["tracks.txt"]}
    (d / "run.json").write_text(json.dumps(info))
    write_report(d, force=True)
    assert "<p>1 frame of x.mp4: 1 box of 1 track, 50 frames/s" in (d / "report.html").read_text()
    info |= {"frames": 2, "rows": 2, "tracks": 2}
    (d / "run.json").write_text(json.dumps(info))
    write_report(d, force=True)
    assert "<p>2 frames of x.mp4: 2 boxes of 2 tracks, " in (d / "report.html").read_text()


def test_report_names_a_folder_without_tracks_before_its_old_page(tmp_path, capsys):
    """A folder holding an old report.html and no tracks.txt: the command line said "exists;
    pass --force" first, and only with --force that tracks.txt does not exist."""
    (tmp_path / "report.html").write_text("<html></html>")
    assert main(["report", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "tracks.txt does not exist" in err and "--force" not in err


def test_ctrl_c_in_vistrack_report_says_what_was_kept(tmp_path, monkeypatch, capsys):
    """`vistrack report` stopped by Ctrl-C said "interrupted" alone: whether a page was there
    before, and kept, was not said."""
    import vistrack.report

    out = tmp_path / "run"
    assert main(["track", str(demo_clip().video), "--stop", "3", "--out-dir", str(out),
                 "--quiet"]) == 0
    real = vistrack.report.write_report

    def stopped(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(vistrack.report, "write_report", stopped)
    capsys.readouterr()
    assert main(["report", str(out)]) == 130
    assert capsys.readouterr().err.strip() == "vistrack report: interrupted; nothing was written"
    assert not (out / "report.html").exists()
    monkeypatch.setattr(vistrack.report, "write_report", real)
    assert main(["report", str(out)]) == 0
    page = (out / "report.html").read_bytes()
    monkeypatch.setattr(vistrack.report, "write_report", stopped)
    capsys.readouterr()
    assert main(["report", str(out), "--force"]) == 130
    assert capsys.readouterr().err.strip() == ("vistrack report: interrupted; earlier outputs "
                                               "are kept")
    assert (out / "report.html").read_bytes() == page

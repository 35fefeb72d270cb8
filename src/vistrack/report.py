"""One page to look at: ``vistrack report OUT_DIR`` (or ``vistrack track ... --report``)
writes ``OUT_DIR/report.html`` from what ``vistrack track --out-dir OUT_DIR`` wrote.

The page holds everything itself (no file beside it, no network): the command that made the
results, the run's numbers, the scores against the ground truth, the annotated video
(``annotated.mp4`` re-encoded as WebM VP8, which every browser plays, at most 720 pixels
on its short side, where its labels read as drawn), the trajectories and, with ground
truth, HOTA, DetA and AssA over the localisation threshold and the timeline of every
object (:func:`vistrack.viz.plot_timeline`). Images and the video are embedded as
``data:`` URIs. A short script marks the video ``data-state="playable"`` once the browser
has decoded its first frame, or shows a note if it cannot.

``run.json`` (:data:`vistrack.pipeline.RUN_INFO`), which ``vistrack track --out-dir``
writes beside its outputs, says how they
were made (the command, the input, the ground truth, the scores, the warnings the run gave,
which the page lists); without it the page shows what the folder holds.
"""

from __future__ import annotations

import base64
import html
import io
import json
import os
import sys
import tempfile
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from ._pool import counted

__all__ = ["write_report"]

def _webm(video: Path) -> bytes:
    """``video`` re-encoded as WebM (VP8), scaled down by the annotator's text scale
    (:func:`~vistrack.viz.annotate.text_scale`), to 720 pixels on its short side if longer:
    its labels then read as on a frame of that size (shrunk to 640 pixels across, as every
    video was, a 1920 × 1080 one's identity numbers were 7 pixels tall, a blur)."""
    import cv2

    from .io.video import VideoReader
    from .viz.annotate import text_scale

    reader = VideoReader(video)
    w, h = reader.size
    scale = 1.0 / text_scale((h, w))
    size = (max(2, int(round(w * scale / 2)) * 2), max(2, int(round(h * scale / 2)) * 2))
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "video.webm"
        with _stderr_silenced():  # FFmpeg's WebM muxer takes no four-character code, and
            # OpenCV says so on stderr each time, before it falls back to VP8's own
            writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"VP80"), reader.fps,
                                     size)
        if not writer.isOpened():  # pragma: no cover - an OpenCV built without libvpx
            raise ValueError("this OpenCV cannot write WebM (VP8) video")
        for frame in reader:
            image = frame.image
            assert image is not None  # a reader's frames carry their images
            writer.write(cv2.resize(image, size, interpolation=cv2.INTER_AREA)
                         if size != (w, h) else image)
        writer.release()
        return path.read_bytes()


@contextmanager
def _stderr_silenced() -> Iterator[None]:
    """Standard error (the file descriptor, which C code writes to) sent nowhere."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _png(fig: Any) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return buf.getvalue()


def _data(kind: str, data: bytes) -> str:
    return f"data:{kind};base64,{base64.b64encode(data).decode('ascii')}"


def _score_table(scores: dict[str, dict]) -> str:
    from .evaluation.mot import SCORE_COLUMNS

    head = "".join(f"<th>{c}</th>" for c, _ in SCORE_COLUMNS)
    rows = []
    for name, s in scores.items():
        cells = "".join(f"<td>{100 * s[c]:.1f}</td>" if pct else f"<td>{int(s[c])}</td>"
                        for c, pct in SCORE_COLUMNS)
        rows.append(f"<tr><th>{html.escape(name)}</th>{cells}</tr>")
    return (f"<table class='scores'><tr><th>sequence</th>{head}</tr>{''.join(rows)}"
            f"</table>")


def _check_info(info: dict, path: Path) -> None:
    """A ValueError naming ``path`` where a field the page reads holds another kind of value
    (a hand-edited or another tool's ``run.json``: a score without DetA was a KeyError's
    traceback, text for ``fps`` "Unknown format code 'f'", naming nothing)."""
    from .evaluation.mot import SCORE_COLUMNS

    number = (int, float)
    kinds: dict[str, type | tuple[type, ...]] = {
        "name": str, "command": str, "input": str, "vistrack": str, "gt": str,
        "frames": number, "rows": number, "tracks": number, "fps": number,
        "first_frame": int, "last_frame": int, "warnings": list, "outputs": list,
        "scores": dict}
    for key, kind in kinds.items():
        value = info.get(key)
        if value is not None and (not isinstance(value, kind) or isinstance(value, bool)):
            raise ValueError(f"{path}: not a run's description ({key} is {value!r})")
    scores = info.get("scores") or {}
    lost = [c for c, _ in SCORE_COLUMNS if not isinstance(scores.get(c, None), number)]
    if scores and lost:
        raise ValueError(f"{path}: not a run's description (its scores have no "
                         f"{', '.join(lost[:3])}{', ...' if len(lost) > 3 else ''})")


def _gt_plots(tracks: Path, name: str, info: dict) -> list[tuple[str, bytes]]:
    """HOTA over α and the timeline of the run's ``tracks`` (its results file), when its
    ground truth is known and readable."""
    from .evaluation import clear_matches, evaluate_mot
    from .evaluation.files import read_truth
    from .viz.plots import plot_hota_alpha, plot_timeline

    gt_path = info.get("gt")
    if not gt_path or not Path(gt_path).is_file():
        return []
    first, last = int(info.get("first_frame", 1)), int(info.get("last_frame", 0))
    zero = info.get("zero_distance")  # scored by distance (vistrack track --zero-distance)
    # the run's own results: MOTChallenge's text, or a points run's tracks.csv
    gt, pred = (read_truth(p, points=zero is not None) for p in (gt_path, tracks))
    if last <= 0:
        last = int(pred.frames.max()) if len(pred) else 0
    g = gt[(gt.frames >= first) & (gt.frames <= last)]
    return [("HOTA, DetA and AssA over the localisation threshold α",
             _png(plot_hota_alpha({name: evaluate_mot(g, pred, last, zero_distance=zero)},
                                  zero_distance=zero))),
            ("Every object over time, coloured by the predicted identity that covers it",
             _png(plot_timeline(clear_matches(g, pred, last, zero_distance=zero),
                                title=name)))]


_STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1240px; color: #222;
       padding: 0 1em; }
h1 { font-size: 1.4em; } h2 { font-size: 1.1em; margin-top: 1.6em; }
pre { background: #f4f4f4; padding: 0.7em; overflow-x: auto; }
table.scores { border-collapse: collapse; font-variant-numeric: tabular-nums; }
table.scores td, table.scores th { border-bottom: 1px solid #ddd; padding: 0.2em 0.5em;
                                   text-align: right; }
img, video { max-width: 100%; border: 1px solid #ccc; }
.note, ul.warnings { color: #a00; }
"""

_SCRIPT = """
for (const v of document.querySelectorAll('video')) {
  v.addEventListener('loadeddata', () => { v.dataset.state = 'playable'; });
  v.addEventListener('error', () => {
    v.dataset.state = 'error';
    document.getElementById('video-note').hidden = false;
  });
}
for (const img of document.querySelectorAll('img')) {
  const mark = () => { img.dataset.state = img.naturalWidth > 0 ? 'shown' : 'error'; };
  if (img.complete) { mark(); } else {
    img.addEventListener('load', mark);
    img.addEventListener('error', mark);
  }
}
"""


def write_report(out_dir: str | Path, *, force: bool = False) -> Path:
    """Write ``out_dir/report.html`` (see the module) and return its path.

    Parameters
    ----------
    out_dir : str or Path
        A folder written by ``vistrack track --out-dir`` (:func:`vistrack.pipeline.track_video`):
        ``tracks.txt`` at least (``tracks.csv`` for a points run, ``run.json`` saying so);
        ``annotated.mp4``, ``trajectories.png`` and ``run.json`` when there.
    force : bool
        Replace an existing ``report.html``.

    Raises
    ------
    NotADirectoryError
        If ``out_dir`` is a file.
    FileNotFoundError
        If ``out_dir`` has no ``tracks.txt`` (a points run, no ``tracks.csv``).
    FileExistsError
        If ``report.html`` exists and ``force`` is False.
    ValueError
        If ``run.json`` cannot be read, naming it.
    vistrack.io.VideoError
        If the video cannot be read, naming it.

    Warns
    -----
    RuntimeWarning
        If ``annotated.mp4`` or ``trajectories.png`` is not there though the run wrote it
        (``run.json``'s ``outputs``; the page says so too).
    """
    from .io.atomic import check_output, replacing
    from .pipeline import REPORT, RUN_INFO, SINK_FILES

    out_dir = Path(out_dir)
    target = out_dir / REPORT
    if out_dir.is_file():
        raise NotADirectoryError(f"{out_dir} is a file: give the folder that vistrack track "
                                 "--out-dir wrote")
    if not out_dir.is_dir():  # (it said "nope/tracks.txt does not exist")
        raise FileNotFoundError(f"{out_dir} does not exist: give the folder that vistrack "
                                "track --out-dir wrote")
    # run.json is read first: it says which tracks file the run wrote (a particles run's
    # points are in tracks.csv), and one that cannot be read was taken for a box run's,
    # whose missing tracks.txt was then the error
    info: dict = {}
    run_info = out_dir / RUN_INFO
    if run_info.is_file():
        try:
            info = json.loads(run_info.read_text())
        except ValueError as e:
            raise ValueError(f"{run_info}: not a run's description ({e})") from e
        if not isinstance(info, dict):
            raise ValueError(f"{run_info}: not a run's description (a JSON "
                             f"{type(info).__name__}, not an object)")
        _check_info(info, run_info)
    # without run.json: a folder of tracks.csv alone is a points run's
    points = bool(info.get("points", False)) if run_info.is_file() else (
        not (out_dir / SINK_FILES["tracks"]).is_file()
        and (out_dir / SINK_FILES["csv"]).is_file())
    tracks = out_dir / SINK_FILES["csv" if points else "tracks"]
    if not tracks.is_file():
        # a run of several inputs (or `vistrack demo track`) writes a folder for each: the
        # folder given to --out-dir holds them, and "give the folder --out-dir wrote" sent
        # the user back to it
        runs = sorted(str(d) for d in out_dir.iterdir() if d.is_dir() and (
            (d / RUN_INFO).is_file() or (d / SINK_FILES["tracks"]).is_file()
            or (d / SINK_FILES["csv"]).is_file())) if out_dir.is_dir() else []
        if runs:
            inside = ", ".join(runs[:3]) + (f" and {len(runs) - 3} more" if len(runs) > 3
                                             else "")
            raise FileNotFoundError(f"{out_dir} holds no run of its own, but "
                                    + (f"the run in {inside}: give that folder"
                                       if len(runs) == 1 else
                                       f"runs in folders of their own ({inside}): give one of "
                                       "them"))
        raise FileNotFoundError(f"{tracks} does not exist: give the folder that vistrack "
                                "track --out-dir wrote")
    # (`vistrack report` checks it first, in its option's words)
    check_output(target, force=force, name="report", option="force=True")
    if not run_info.is_file():
        # (the page was written without the command, the counts and the scores, unsaid, as a
        # missing video or plot is said)
        warnings.warn(f"{out_dir}: no {RUN_INFO}: the report has no command, counts, warnings "
                      "or scores of the run, only its files", RuntimeWarning, stacklevel=2)
    name = info.get("name") or out_dir.resolve().name  # ("." has no name of its own)
    parts = [f"<h1>vistrack report: {html.escape(name)}</h1>"]
    if info.get("command"):
        parts.append(f"<p>Made by</p><pre>{html.escape(info['command'])}</pre>")
    if info.get("frames"):
        n_rows, n_tracks = info.get("rows", 0), info.get("tracks", 0)
        parts.append(  # (in the singular for one: "1 frames of" was said)
            f"<p>{counted(info['frames'], 'frame')} of "
            f"{html.escape(str(info.get('input', '')))}: "
            f"{counted(n_rows, 'position') if points else counted(n_rows, 'box', 'boxes')} of "
            f"{counted(n_tracks, 'particle' if points else 'track')}, "
            f"{info.get('fps', 0):.0f} frames/s without writing; vistrack "
            f"{html.escape(str(info.get('vistrack', '')))}.</p>")
    said = info.get("warnings")
    if isinstance(said, list) and said:  # what the run warned of, beside its numbers
        parts.append("<h2>Warnings</h2><ul class='warnings'>"
                     + "".join(f"<li>{html.escape(str(m))}</li>" for m in said) + "</ul>")
    if info.get("scores"):
        gt = html.escape(str(info.get("gt", "")))
        parts.append(f"<h2>Scores</h2><p>Against {gt}, over the frames tracked.</p>"
                     + _score_table({name: info["scores"]}))
    video = out_dir / SINK_FILES["video"]
    if video.is_file():
        parts.append("<h2>Annotated video</h2>"
                     f"<video controls loop muted autoplay preload='auto' "
                     f"src='{_data('video/webm', _webm(video))}'></video>"
                     "<p id='video-note' class='note' hidden>This browser cannot play the "
                     "video (WebM, VP8): annotated.mp4 beside this page is the same.</p>")
    plot = out_dir / SINK_FILES["plot"]
    # the ones the run wrote (run.json's outputs; a run with annotate=False made no video)
    made = info.get("outputs")
    absent = [f.name for f in (video, plot)
              if not f.is_file() and (not isinstance(made, list) or f.name in made)]
    shown = {video.name: "annotated video", plot.name: "plot of the trajectories"}
    if absent:
        # removed, or never written (a run stopped before its end): said, not left out
        what, lost = " nor ".join(absent), " nor ".join(shown[a] for a in absent)
        warnings.warn(f"{out_dir}: no {what}: the report has no {lost}", RuntimeWarning,
                      stacklevel=2)
        parts.append(f"<p class='note'>No {html.escape(what)} in {html.escape(str(out_dir))} "
                     f"when this page was written: no {lost}.</p>")
    figures = ([("Trajectories", plot.read_bytes())] if plot.is_file() else [])
    figures += _gt_plots(tracks, name, info)
    if info.get("gt") and not Path(info["gt"]).is_file():
        parts.append(f"<p class='note'>The ground truth, {html.escape(info['gt'])}, is not "
                     "there any more: no plot of HOTA over α nor timeline.</p>")
    for title, png in figures:
        parts.append(f"<h2>{html.escape(title)}</h2><img alt='{html.escape(title)}' "
                     f"src='{_data('image/png', png)}'>")
    page = ("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
            f"<title>vistrack report: {html.escape(name)}</title><style>{_STYLE}</style>"
            f"</head><body>{''.join(parts)}<script>{_SCRIPT}</script></body></html>\n")
    with replacing(target) as part:
        part.write_text(page, encoding="utf-8")
    return target

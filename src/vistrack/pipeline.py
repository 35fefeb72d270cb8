"""Where the stages meet: detections from a file, a tracker, results and scores.

``track_sequence`` runs a tracker over a MOTChallenge sequence folder; ``evaluate_files`` scores
results files against ground truth. The command line (:mod:`vistrack.cli`) calls these.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .evaluation.mot import MOTCounts, combine, evaluate_mot
from .io.motchallenge import read_mot, read_seqinfo, write_mot
from .tracking.box import BoxTracker
from .tracking.offline import smooth
from .types import Detections

__all__ = ["track_sequence", "TrackRun", "evaluate_files"]


@dataclass(frozen=True)
class TrackRun:
    """What :func:`track_sequence` did: the results file, frames, tracks and tracker time."""

    out: Path
    frames: int
    detections: int
    rows: int
    tracks: int
    seconds: float

    @property
    def fps(self) -> float:
        return self.frames / max(self.seconds, 1e-12)


def _progress(done: int, total: int, label: str, stream: Any) -> None:
    if stream is None:
        return
    width = 30
    k = int(width * done / max(total, 1))
    stream.write(f"\r{label} [{'#' * k}{'.' * (width - k)}] {done}/{total}")
    if done == total:
        stream.write("\n")
    stream.flush()


def track_sequence(seq_dir: str | Path, out: str | Path, *, detections: str | Path | None = None,
                   tracker: str = "bytetrack", offline: bool = False, max_gap: float = 0.5,
                   force: bool = False, progress: Any = None,
                   **overrides: Any) -> TrackRun:
    """Track a MOTChallenge sequence folder and write a results file.

    Parameters
    ----------
    seq_dir
        A folder with ``seqinfo.ini`` and ``det/det.txt``.
    out
        The results file to write (not overwritten unless ``force``).
    detections
        Another detections file (default ``seq_dir/det/det.txt``).
    tracker
        A name in :data:`vistrack.tracking.TRACKERS`.
    offline
        Smooth the finished tracks and fill gaps of up to ``max_gap`` seconds
        (:func:`vistrack.tracking.smooth`).
    progress
        A stream for a progress bar (the command line passes stderr on a terminal), or None.
    """
    seq_dir = Path(seq_dir)
    info = read_seqinfo(seq_dir)
    det_path = Path(detections) if detections is not None else seq_dir / "det" / "det.txt"
    if not det_path.exists():
        raise FileNotFoundError(f"{det_path} does not exist (pass --detections FILE)")
    out = Path(out)
    if out.exists() and not force:
        raise FileExistsError(f"{out} exists; pass --force to overwrite it")
    dets = read_mot(det_path)
    if len(dets) and dets.frames.max() > info.seq_length:
        raise ValueError(f"{det_path}: frame {int(dets.frames.max())} is beyond the "
                         f"sequence's {info.seq_length} frames ({seq_dir / 'seqinfo.ini'})")
    trk = BoxTracker(tracker, frame_rate=info.frame_rate, record=offline, **overrides)
    slices = dets.frame_slices(info.seq_length)
    xyxy = np.c_[dets.boxes[:, :2], dets.boxes[:, :2] + dets.boxes[:, 2:]]
    frames, ids, boxes, scores = [], [], [], []
    every = max(1, info.seq_length // 50)
    seconds = 0.0
    for f in range(1, info.seq_length + 1):
        s = slices[f - 1]
        d = Detections(boxes=xyxy[s], scores=dets.conf[s])
        t0 = time.perf_counter()
        res = trk.step(d, frame=f)
        seconds += time.perf_counter() - t0
        if len(res):
            frames.append(np.full(len(res), f))
            ids.append(res.ids)
            boxes.append(res.xywh)
            scores.append(res.scores)
        if f % every == 0 or f == info.seq_length:
            _progress(f, info.seq_length, info.name, progress)
    cat = (lambda a, shape: np.concatenate(a) if a else np.zeros(shape))
    F, I = cat(frames, (0,)).astype(int), cat(ids, (0,)).astype(int)
    B, S = cat(boxes, (0, 4)), cat(scores, (0,))
    if offline:
        t0 = time.perf_counter()
        sm = smooth(trk, max_gap=int(round(max_gap * info.frame_rate)))
        seconds += time.perf_counter() - t0
        F, I, B, S = sm.frames, sm.ids, sm.xywh, np.where(sm.filled, 0.0, sm.scores)
    write_mot(out, F, I, B, S, force=True)
    return TrackRun(out, info.seq_length, len(dets), len(F), len(np.unique(I)), seconds)


def evaluate_files(pairs: list[tuple[str, Path, Path, Path | None]], *,
                   benchmark: str = "auto") -> dict[str, MOTCounts]:
    """Score ``(name, gt, results, seqinfo-or-None)`` pairs; adds ``"COMBINED"`` when there are
    several."""
    out: dict[str, MOTCounts] = {}
    for name, gt, pred, info in pairs:
        n = read_seqinfo(info).seq_length if info is not None else None
        out[str(name)] = evaluate_mot(read_mot(gt), read_mot(pred), n, benchmark=benchmark)
    if len(out) > 1:
        out["COMBINED"] = combine(out.values())
    return out

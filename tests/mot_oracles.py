"""Shared helpers for the MOT tests: the data in ../shared, predictions made from ground truth
with known kinds of error, and the reference scorers (TrackEval, py-motmetrics) run on files."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from vistrack.io import read_mot, read_seqinfo, write_mot

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
MOT15 = ["ADL-Rundle-6", "ADL-Rundle-8", "ETH-Bahnhof", "ETH-Pedcross2", "ETH-Sunnyday",
         "KITTI-13", "KITTI-17", "PETS09-S2L1", "Venice-2"]
MOT17 = [f"MOT17-{k:02d}-FRCNN" for k in (2, 4, 5, 9, 10, 11, 13)]


def seq_dir(bench: str, name: str) -> Path:
    d = SHARED / bench.lower() / name
    if not (d / "gt" / "gt.txt").exists():
        pytest.skip(f"{d} not found: the shared MOTChallenge data is not beside this checkout")
    return d


def noisy_predictions(gt_path: Path, out: Path, seed: int) -> Path:
    """Predictions from ground truth with every kind of error the scores count: missed boxes,
    jittered boxes (IoU spread around the thresholds), false positives, identity switches and
    swaps, boxes on ignored and distractor objects, and frames with no predictions."""
    rng = np.random.default_rng(seed)
    gt = read_mot(gt_path)
    keep = rng.random(len(gt)) > 0.12
    t = gt[keep]
    frames, ids, boxes = t.frames.copy(), t.ids.copy(), t.boxes.copy()
    wh = boxes[:, 2:4]
    boxes[:, :2] += rng.normal(0, 0.08, (len(t), 2)) * wh
    boxes[:, 2:4] *= np.exp(rng.normal(0, 0.08, (len(t), 2)))
    # identity errors: some objects change id from a random frame on; some pairs swap
    for obj in rng.choice(np.unique(ids), size=max(1, len(np.unique(ids)) // 4), replace=False):
        rows = np.flatnonzero(ids == obj)
        cut = rows[rng.integers(len(rows))]
        ids[rows[frames[rows] >= frames[cut]]] = obj + 10_000
    last = int(frames.max())
    drop_frames = rng.choice(np.arange(1, last + 1), size=max(1, last // 50), replace=False)
    ok = ~np.isin(frames, drop_frames)
    frames, ids, boxes = frames[ok], ids[ok], boxes[ok]
    # false positives: random boxes of the sizes seen, in random frames
    n_fp = len(frames) // 10
    fp_boxes = boxes[rng.integers(len(boxes), size=n_fp)].copy()
    fp_boxes[:, :2] += rng.normal(0, 3.0, (n_fp, 2)) * fp_boxes[:, 2:4]
    fp_frames = rng.integers(1, last + 1, size=n_fp)
    fp_ids = 100_000 + np.arange(n_fp)
    frames = np.concatenate([frames, fp_frames])
    ids = np.concatenate([ids, fp_ids])
    boxes = np.concatenate([boxes, fp_boxes])
    conf = rng.random(len(frames))
    return write_mot(out, frames, ids, boxes, conf, force=True)


def trackeval_scores(bench: str, seqs: dict[str, Path], preds: dict[str, Path], tmp: Path,
                     raise_errors: bool = False):
    """TrackEval's MotChallenge2DBox results, per sequence and COMBINED, on these files (its
    errors raised with ``raise_errors``, which TrackEval otherwise logs and leaves out)."""
    te = pytest.importorskip("trackeval")
    gt_root, tr_root = tmp / "gt", tmp / "trackers"
    for name, d in seqs.items():
        (gt_root / name / "gt").mkdir(parents=True, exist_ok=True)
        shutil.copy(d / "gt" / "gt.txt", gt_root / name / "gt" / "gt.txt")
        shutil.copy(d / "seqinfo.ini", gt_root / name / "seqinfo.ini")
        (tr_root / "vt" / "data").mkdir(parents=True, exist_ok=True)
        shutil.copy(preds[name], tr_root / "vt" / "data" / f"{name}.txt")
    seqmap = tmp / "seqmap.txt"
    seqmap.write_text("name\n" + "\n".join(seqs) + "\n")
    ev = te.Evaluator.get_default_eval_config()
    ev.update(USE_PARALLEL=False, PRINT_RESULTS=False, PRINT_CONFIG=False, TIME_PROGRESS=False,
              OUTPUT_SUMMARY=False, OUTPUT_DETAILED=False, PLOT_CURVES=False,
              DISPLAY_LESS_PROGRESS=True, OUTPUT_EMPTY_CLASSES=False,
              BREAK_ON_ERROR=raise_errors, RETURN_ON_ERROR=False, LOG_ON_ERROR=None)
    ds = te.datasets.MotChallenge2DBox.get_default_dataset_config()
    ds.update(GT_FOLDER=str(gt_root), TRACKERS_FOLDER=str(tr_root), BENCHMARK=bench,
              SPLIT_TO_EVAL="train", TRACKERS_TO_EVAL=["vt"], SEQMAP_FILE=str(seqmap),
              SKIP_SPLIT_FOL=True, PRINT_CONFIG=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res, _ = te.Evaluator(ev).evaluate(
            [te.datasets.MotChallenge2DBox(ds)],
            [te.metrics.HOTA(), te.metrics.CLEAR(), te.metrics.Identity()])
    return {k: v["pedestrian"] for k, v in res["MotChallenge2DBox"]["vt"].items()}


def n_frames(d: Path) -> int:
    return read_seqinfo(d).seq_length

"""Scoring speed and memory: vistrack's scorer beside TrackEval, the official MOTChallenge
scorer, on the four sets of ``accuracy_mot.py`` (vistrack's own tracks of them) and on a
generated long sequence with many identities; CLEAR MOT, identity and HOTA per sequence and
COMBINED, the same scores from both.

    python bench/bench_eval.py [--sets MOT15,MOT17,MOT16-FairMOT,KITTI] [--repeats 3]
                               [--write docs/benchmarks.md]

Each scorer reads the ground truth and the results from their files and scores every
sequence of the set in one call, in this process (TrackEval on one core, as vistrack's
scorer runs); medians of ``--repeats`` rounds, each scorer in turn, after an untimed run
of each. The conventions are ``accuracy_mot.py``'s: MOT15 and KITTI under MOT15's, MOT17
and MOT16 under their own (distractors removed). Before the times are reported, every
sequence's HOTA, MOTA and IDF1 are checked to agree with TrackEval's to 1e-9. The peak of
memory each scorer allocates is measured in one more run of each under tracemalloc.
"""

from __future__ import annotations

import argparse
import platform
import shutil
import statistics
import sys
import tempfile
import time
import tracemalloc
import warnings
from pathlib import Path

import accuracy_mot as acc  # bench/ is on the path of its scripts
import numpy as np

from vistrack.evaluation import evaluate_files
from vistrack.io import write_mot
from vistrack.pipeline import track_sequence

from _common import optional  # noqa: E402
from _markdown import publish  # noqa: E402

CONVENTION = {"MOT15": "MOT15", "MOT17": "MOT17", "MOT16-FairMOT": "MOT16", "KITTI": "MOT15"}


LONG = "long, generated"


def long_sequence(root: Path, n_frames: int) -> Path:
    """A long sequence with many identities that never meet: ``n_frames`` frames of 40
    objects each (1920 x 1080), a new set of 40 every 40 frames (as many objects as frames),
    predicted with 2 pixels of noise under a new identity every 13 frames (about 4 times as
    many); MOTChallenge's layout in ``root`` (``gt/gt.txt``, ``seqinfo.ini``, the results in
    ``results.txt``)."""
    rng = np.random.default_rng(0)
    frames, ids, boxes = [], [], []
    for k, start in enumerate(range(1, n_frames + 1, 40)):
        x, y = rng.uniform(0, 1800, 40), rng.uniform(0, 900, 40)
        v = rng.normal(0, 2, (40, 2))
        for f in range(start, min(start + 40, n_frames + 1)):
            frames.append(np.full(40, f))
            ids.append(k * 40 + np.arange(1, 41))
            boxes.append(np.c_[x + v[:, 0] * (f - start), y + v[:, 1] * (f - start),
                               np.full(40, 40.0), np.full(40, 100.0)])
    f, i, b = np.concatenate(frames), np.concatenate(ids), np.concatenate(boxes)
    (root / "gt").mkdir(parents=True)
    (root / "seqinfo.ini").write_text("[Sequence]\nname=long\nimDir=img1\nframeRate=30\n"
                                      f"seqLength={n_frames}\nimWidth=1920\nimHeight=1080\n"
                                      "imExt=.jpg\n")
    write_mot(root / "gt" / "gt.txt", f, i, b, np.ones(len(f)))
    pred = np.unique(i * 1000 + (f - 1) // 13, return_inverse=True)[1] + 1
    write_mot(root / "results.txt", f, pred, b + rng.normal(0, 2, b.shape), np.ones(len(f)))
    return root


def traced_peak(fn) -> float:
    """The peak of memory that ``fn()`` allocates, in MB, as tracemalloc sees it (numpy's
    arrays included)."""
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def trackeval_layout(seqs: list[Path], results: Path, root: Path) -> dict:
    """TrackEval's folders for these sequences and results; its dataset configuration."""
    gt_root, tr_root = root / "gt", root / "trackers" / "vistrack" / "data"
    tr_root.mkdir(parents=True)
    for d in seqs:
        (gt_root / d.name / "gt").mkdir(parents=True)
        shutil.copy(d / "gt" / "gt.txt", gt_root / d.name / "gt" / "gt.txt")
        shutil.copy(d / "seqinfo.ini", gt_root / d.name / "seqinfo.ini")
        shutil.copy(results / f"{d.name}.txt", tr_root / f"{d.name}.txt")
    seqmap = root / "seqmap.txt"
    seqmap.write_text("name\n" + "\n".join(d.name for d in seqs) + "\n")
    return dict(GT_FOLDER=str(gt_root), TRACKERS_FOLDER=str(root / "trackers"),
                SPLIT_TO_EVAL="train", TRACKERS_TO_EVAL=["vistrack"], SEQMAP_FILE=str(seqmap),
                SKIP_SPLIT_FOL=True, PRINT_CONFIG=False)


def run_trackeval(te, dataset: dict, benchmark: str) -> dict:
    ev = te.Evaluator.get_default_eval_config()
    ev.update(USE_PARALLEL=False, PRINT_RESULTS=False, PRINT_CONFIG=False, TIME_PROGRESS=False,
              OUTPUT_SUMMARY=False, OUTPUT_DETAILED=False, PLOT_CURVES=False,
              DISPLAY_LESS_PROGRESS=True, OUTPUT_EMPTY_CLASSES=False)
    ds = te.datasets.MotChallenge2DBox.get_default_dataset_config()
    ds.update(dataset, BENCHMARK=benchmark)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res, _ = te.Evaluator(ev).evaluate(
            [te.datasets.MotChallenge2DBox(ds)],
            [te.metrics.HOTA(), te.metrics.CLEAR(), te.metrics.Identity()])
    return {k: v["pedestrian"] for k, v in res["MotChallenge2DBox"]["vistrack"].items()}


def interleaved(runs: dict, repeats: int) -> tuple[dict, dict]:
    """Each run once untimed, then ``repeats`` rounds of every run in turn (so that a busy
    spell of the machine slows both scorers alike): the median seconds and the last result
    of each."""
    res = {k: f() for k, f in runs.items()}
    times: dict = {k: [] for k in runs}
    for _ in range(repeats):
        for k, f in runs.items():
            t = time.perf_counter()
            res[k] = f()
            times[k].append(time.perf_counter() - t)
    return {k: statistics.median(v) for k, v in times.items()}, res


def check_equal(ours: dict, ref: dict, name: str) -> None:
    for seq, c in ours.items():
        r = ref["COMBINED_SEQ" if seq == "COMBINED" else seq]
        for mine, theirs in ((c.HOTA, float(np.mean(r["HOTA"]["HOTA"]))),
                             (c.MOTA, r["CLEAR"]["MOTA"]), (c.IDF1, r["Identity"]["IDF1"])):
            if abs(mine - theirs) > 1e-9:
                sys.exit(f"{name} {seq}: vistrack {mine!r} against TrackEval {theirs!r}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sets", default=",".join(acc.SETS))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--long-frames", type=int, default=1200,
                    help="frames (and objects) of the generated long sequence")
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    if not acc.DATA.exists():
        sys.exit(f"{acc.DATA} not found: the shared data must be beside this checkout")
    names = [s.strip() for s in args.sets.split(",")]
    bad = [s for s in names if s not in acc.SETS]
    if bad:
        sys.exit(f"unknown set {bad[0]!r}; sets: {', '.join(acc.SETS)}")
    te = optional("trackeval")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name in names + [LONG]:
            if name == LONG:
                seqs = [long_sequence(tmp / "long" / "long", args.long_frames)]
                out = tmp / "long" / "results"
                out.mkdir()
                (seqs[0] / "results.txt").rename(out / "long.txt")
            else:
                seqs, out = acc.sequences(name), tmp / name / "results"
                for d in seqs:
                    track_sequence(d, out / f"{d.name}.txt", force=True)
            bench = CONVENTION.get(name, "MOT15")
            files = [(d.name, d / "gt" / "gt.txt", out / f"{d.name}.txt", d / "seqinfo.ini")
                     for d in seqs]
            runs = {"vistrack": lambda: evaluate_files(files, benchmark=bench)}
            if te is not None:
                dataset = trackeval_layout(seqs, out, tmp / name / "trackeval")
                runs["TrackEval"] = lambda: run_trackeval(te, dataset, bench)
            times, res = interleaved(runs, args.repeats)
            peaks = {k: traced_peak(f) for k, f in runs.items()}
            ours = res["vistrack"]
            gt_boxes = sum(c.gt_dets for k, c in ours.items() if k != "COMBINED")
            if te is not None:
                check_equal(ours, res["TrackEval"], name)
            rows.append((name, len(seqs), gt_boxes, times, peaks))
            if name == LONG:
                long = ours["long"]
            print(f"{name}: " + ", ".join(f"{k} {v:.3f} s, {peaks[k]:.0f} MB"
                                          for k, v in times.items()), file=sys.stderr)
    table = ["| set | sequences | ground-truth boxes scored | vistrack s | TrackEval s | "
             "TrackEval, times vistrack's | vistrack MB | TrackEval MB |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for name, n, boxes, t, mb in rows:
        a, b = t["vistrack"], t.get("TrackEval")
        table.append(f"| {name} | {n} | {boxes:,} | {a:.2f} | "
                     + ("- | - |" if b is None else f"{b:.2f} | {b / a:.1f} |")
                     + f" {mb['vistrack']:.0f} | "
                     + ("- |" if b is None else f"{mb['TrackEval']:.0f} |"))
    cmd = "python bench/bench_eval.py" + (f" --repeats {args.repeats}" if args.repeats != 3
                                          else "")
    section = "\n".join([
        "## Scoring",
        "",
        f"Measured with `{cmd}` (Python {platform.python_version()}, numpy {np.__version__}, "
        f"{platform.machine()}, one core, {time.strftime('%Y-%m-%d')}): every sequence of the "
        "set scored in one call, its files read, CLEAR MOT, identity and HOTA per sequence and "
        "COMBINED; vistrack's own tracks of the set (its defaults, online), and a generated "
        f"long sequence with many identities ({long.frames:,} frames of 40 objects, "
        f"{long.gt_ids:,} objects, {long.pred_ids:,} predicted identities; see the script); "
        "medians of "
        f"{args.repeats} rounds, each scorer in turn, after an untimed run of each. HOTA, "
        "MOTA and IDF1 equal TrackEval's to 1e-9 on every sequence (checked before the times "
        "are reported). MB: the peak of memory each scorer allocates, in a run of its own "
        "under tracemalloc (numpy's arrays included).",
        "",
        *table,
        ""])
    publish(section, args.write)


if __name__ == "__main__":
    main()

"""Multi-object tracker speed, tracker stage only: vistrack beside the trackers a user would pick
instead (roboflow's `trackers` ByteTrack and SORT, motpy, norfair), in one run, on the same
detections.

    python bench/bench_tracking.py [--quick] [--write docs/benchmarks.md]

1. MOT17-04 FRCNN public detections (1,050 frames, about 27 boxes a frame): frames per second,
   and HOTA / MOTA / IDF1 of each result (vistrack's scorer, equal to TrackEval).
2. Scaling: simulated frames with 100 ... 10,000 boxes moving at constant velocity on a large
   image, milliseconds per frame (median over the frames after the first few).
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from vistrack.evaluation import evaluate_mot
from vistrack.io import MOTTable, read_mot, read_seqinfo
from vistrack.tracking import BoxTracker
from vistrack.types import Detections

from _common import optional  # noqa: E402  (bench/ is on the path of its scripts)
from _markdown import publish  # noqa: E402

SEQ = Path(__file__).resolve().parents[2] / "shared" / "data" / "mot17" / "MOT17-04-FRCNN"


# ------------------------------------------------------------------ one runner per library
# each takes frames of (xyxy (N, 4), scores (N,)) and returns, per frame, (ids, xyxy), and the
# seconds of each of the tracker's own calls; it stops early after `budget` seconds
def run_vistrack(name):
    def run(frames, fps, budget=np.inf, image_size=None):
        tr = BoxTracker(name, frame_rate=fps, image_size=image_size)
        out, sec = [], []
        for f, (b, s) in enumerate(frames, 1):
            d = Detections(boxes=b, scores=s)
            t = time.perf_counter()
            r = tr.step(f, d)
            sec.append(time.perf_counter() - t)
            out.append((r.ids, r.boxes))
            if sum(sec) > budget:
                break
        return out, sec
    return run


def run_trackers(kind):
    import supervision as sv
    import trackers

    def run(frames, fps, budget=np.inf):
        tr = (trackers.ByteTrackTracker(frame_rate=fps) if kind == "bytetrack"
              else trackers.SORTTracker(frame_rate=fps))
        out, sec = [], []
        for b, s in frames:
            d = sv.Detections(xyxy=b.astype(np.float32), confidence=s.astype(np.float32),
                              class_id=np.zeros(len(b), int))
            t = time.perf_counter()
            r = tr.update(d)
            sec.append(time.perf_counter() - t)
            ok = r.tracker_id >= 0 if r.tracker_id is not None else np.zeros(0, bool)
            out.append((r.tracker_id[ok], r.xyxy[ok]))
            if sum(sec) > budget:
                break
        return out, sec
    return run


def run_motpy(frames, fps, budget=np.inf):
    import motpy

    tr = motpy.MultiObjectTracker(dt=1.0 / fps)
    out, sec = [], []
    for b, s in frames:
        dets = [motpy.Detection(box=x, score=float(c)) for x, c in zip(b, s)]
        t = time.perf_counter()
        tracks = tr.step(detections=dets)
        sec.append(time.perf_counter() - t)
        ids = {}
        out.append((np.array([ids.setdefault(k.id, hash(k.id) % 10**9) for k in tracks], int),
                    np.array([k.box for k in tracks]).reshape(-1, 4)))
        if sum(sec) > budget:
            break
    return out, sec


def run_norfair(frames, fps, budget=np.inf):
    import norfair

    tr = norfair.Tracker(distance_function="iou", distance_threshold=0.7)
    out, sec = [], []
    for b, s in frames:
        dets = [norfair.Detection(points=x.reshape(2, 2), scores=np.array([c, c]))
                for x, c in zip(b, s)]
        t = time.perf_counter()
        objs = tr.update(dets)
        sec.append(time.perf_counter() - t)
        out.append((np.array([o.id for o in objs], int),
                    np.array([o.estimate.ravel() for o in objs]).reshape(-1, 4)))
        if sum(sec) > budget:
            break
    return out, sec


def runners():
    out = {"vistrack bytetrack": run_vistrack("bytetrack"), "vistrack sort": run_vistrack("sort")}
    if optional("trackers") is not None:
        out["trackers ByteTrack"] = run_trackers("bytetrack")
        out["trackers SORT"] = run_trackers("sort")
    if optional("motpy") is not None:
        out["motpy"] = run_motpy
    if optional("norfair") is not None:
        out["norfair (IoU)"] = run_norfair
    return out


def to_table(result):
    rows = [(f, i, *b[:2], *(b[2:] - b[:2])) for f, (ids, boxes) in enumerate(result, 1)
            for i, b in zip(ids, boxes)]
    a = np.array(rows, dtype=float).reshape(-1, 6)
    return MOTTable(a[:, 0].astype(int), a[:, 1].astype(int), a[:, 2:6], np.ones(len(a)),
                    -np.ones(len(a), int), -np.ones(len(a)), columns=10)


def mot17_rows(repeats):
    dets = read_mot(SEQ / "det" / "det.txt")
    info = read_seqinfo(SEQ)
    gt = read_mot(SEQ / "gt" / "gt.txt")
    xyxy = np.c_[dets.boxes[:, :2], dets.boxes[:, :2] + dets.boxes[:, 2:]]
    frames = [(xyxy[s], dets.conf[s]) for s in dets.frame_slices(info.seq_length)]
    rows = []
    for name, run in runners().items():
        secs, res = [], None
        ours = name.startswith("vistrack")
        kw = {"image_size": (info.im_width, info.im_height)} if ours else {}  # as the CLI
        for _ in range(repeats if ours else 1):
            res, sec = run(frames, info.frame_rate, **kw)
            secs.append(sum(sec))
        c = evaluate_mot(gt, to_table(res), info.seq_length, benchmark="MOT17")
        rows.append((name, len(frames) / min(secs), c.HOTA, c.MOTA, c.IDF1))
        print(f"  {name}: {rows[-1][1]:.0f} fps", file=sys.stderr)
    return rows


def scene(n, T, rng):
    """n boxes of 20-60 pixels moving at constant velocity on a square image sized for about
    the density of MOT17-04, detected with noise; scores 0.9-1, so that every tracker starts
    a track on every box."""
    side = 60.0 * np.sqrt(n) * 3
    p = rng.uniform(0, side, (n, 2))
    v = rng.normal(0, 2, (n, 2))
    wh = rng.uniform(20, 60, (n, 2))
    frames = []
    for _ in range(T):
        p = p + v
        c = p + rng.normal(0, 1, (n, 2))
        frames.append((np.c_[c - wh / 2, c + wh / 2], rng.uniform(0.9, 1.0, n)))
    return frames


def scaling_rows(sizes, budget_s):
    rows = []
    rng = np.random.default_rng(0)
    run_all = runners()
    for n in sizes:
        frames = scene(n, 20, rng)
        for name, run in run_all.items():
            prev = [r for r in rows if r[1] == name]
            if prev and (prev[-1][3] == "not run"
                         or prev[-1][2] / 1e3 * (n / prev[-1][0]) ** 2 > budget_s):
                # one frame alone would take longer than the budget (quadratic growth)
                rows.append((n, name, float("nan"), "not run"))
                continue
            t0 = time.perf_counter()
            _, sec = run(frames, 30.0, budget_s)
            per = statistics.median(sec[3:]) if len(sec) > 3 else statistics.median(sec)
            note = "" if len(sec) == len(frames) else f"{len(sec)} frames"
            rows.append((n, name, per * 1e3, note))
            print(f"  {n} boxes, {name}: {per * 1e3:.1f} ms/frame "
                  f"({time.perf_counter() - t0:.1f} s)", file=sys.stderr)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="up to 1,000 boxes")
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    parts = []
    if SEQ.exists():
        print("MOT17-04 ...", file=sys.stderr)
        rows = mot17_rows(3)
        ref = rows[0][1]
        t = ["**MOT17-04 FRCNN, tracker stage**", "",
             "| tracker | frames/s | times slower than vistrack bytetrack | HOTA | MOTA | IDF1 |",
             "|---|---:|---:|---:|---:|---:|"]
        t += [f"| {n} | {fps:.0f} | {ref / fps:.2g} | {100 * h:.1f} | {100 * m:.1f} | "
              f"{100 * i:.1f} |" for n, fps, h, m, i in rows]
        parts.append("\n".join(t))
    else:
        print(f"{SEQ} not found: MOT17-04 skipped", file=sys.stderr)
    sizes = (100, 1000) if args.quick else (100, 1000, 2000, 5000, 10_000)
    print("scaling ...", file=sys.stderr)
    rows = scaling_rows(sizes, budget_s=60.0)
    names = list(dict.fromkeys(r[1] for r in rows))
    t = ["**Scaling, simulated boxes, ms per frame**", "",
         "| tracker | " + " | ".join(f"{n:,}" for n in sizes) + " |",
         "|---|" + "---:|" * len(sizes)]
    for name in names:
        cells = []
        for n in sizes:
            r = [x for x in rows if x[0] == n and x[1] == name]
            if r and r[0][3] == "not run":
                cells.append("not run (over a minute a frame)")
            else:
                cells.append("" if not r else f"{r[0][2]:.3g}"
                             + (f" ({r[0][3]})" if r[0][3] else ""))
        t.append(f"| {name} | " + " | ".join(cells) + " |")
    parts.append("\n".join(t))
    env = (f"Python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}, "
           f"one core, {time.strftime('%Y-%m-%d')}")
    cmd = "python bench/bench_tracking.py" + (" --quick" if args.quick else "")
    section = (f"## Multi-object tracking\n\nMeasured with `{cmd}` ({env}). Time in the "
               f"trackers' own update calls only.\n\n" + "\n\n".join(parts) + "\n")
    publish(section, args.write)


if __name__ == "__main__":
    main()

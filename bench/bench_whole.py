"""Whole process, 1,000 boxes a frame: ``vistrack track SEQ_DIR --out FILE`` beside the script a
user would write instead with roboflow's ``trackers`` (SORT), on the same detections.

    python bench/bench_whole.py [--runs N] [--write MD]

A MOTChallenge sequence is generated in a temporary folder (fixed seed): 150 frames of about
1,000 boxes of 20-60 pixels moving at constant velocity with a little noise on a 4000x4000
image, a few appearing and disappearing, scores 0.5-1 (``det/det.txt``, ``seqinfo.ini``). Each
command is a fresh Python process (interpreter start, imports, reading det.txt, tracking,
writing the results); after one untimed run of each (numba's caches filled), the two run in
turn ``--runs`` times. Figures are medians: wall-clock seconds, CPU seconds (user + system of
the child), milliseconds a frame of the whole process, and the peer's time over vistrack's.
For vistrack, where a run's time goes: interpreter start, imports, reading det.txt, the first
frame (where the kernels are loaded), the other frames, writing; and the tracker stage's
figure ``vistrack track`` prints itself.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from vistrack.io import write_mot

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_startup import PEER_SORT  # noqa: E402  (trackers' SORT, as a user would script it)

from _markdown import replace_section  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
VT = str(Path(PY).parent / "vistrack")
FRAMES, BOXES, SIDE, FPS = 150, 1000, 4000, 25
GOAL_MS, GOAL_RATIO = 3.0, 40.0

# vistrack's steps of `vistrack track SEQ_DIR --out FILE`, one process, each timed (as
# pipeline.track_sequence, with the CLI's default tracker); prints seconds as key=value
VT_PARTS = """
import time
t0 = time.perf_counter()
import sys
from pathlib import Path
import numpy as np
import vistrack.cli, vistrack.config, vistrack.io.atomic, vistrack.pipeline
from vistrack.io import read_mot, read_seqinfo
from vistrack.io.tracks import MOTWriter
from vistrack.tracking import BoxTracker
from vistrack.types import Detections, Frame
t1 = time.perf_counter()
seq = Path(sys.argv[1])
info = read_seqinfo(seq)
d = read_mot(seq / "det" / "det.txt")
xyxy = np.c_[d.boxes[:, :2], d.boxes[:, :2] + d.boxes[:, 2:]]
per_frame = [Detections(boxes=xyxy[s], scores=d.conf[s])
             for s in d.frame_slices(info.seq_length)]
t2 = time.perf_counter()
tr = BoxTracker("bytetrack", frame_rate=info.frame_rate,
                image_size=(info.im_width, info.im_height))
out = MOTWriter(sys.argv[2])
step, write = [], 0.0
for f in range(1, info.seq_length + 1):
    t = time.perf_counter()
    r = tr.step(Frame(f, (f - 1) / info.frame_rate), per_frame[f - 1])
    u = time.perf_counter()
    out.write(Frame(f, (f - 1) / info.frame_rate), r)
    write += time.perf_counter() - u
    step.append(u - t)
t = time.perf_counter()
out.close()
write += time.perf_counter() - t
print(f"imports={t1 - t0} read={t2 - t1} first={step[0]} others={sum(step[1:])} "
      f"write={write}")
"""


def make_sequence(seq: Path, seed: int = 0) -> int:
    """Write ``seq``/det/det.txt and ``seq``/seqinfo.ini; returns the rows of det.txt."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(100, SIDE - 100, (BOXES, 2))
    v = rng.normal(0, 1.5, (BOXES, 2))
    wh = rng.uniform(20, 60, (BOXES, 2))
    first = np.ones(BOXES, int)
    last = np.full(BOXES, FRAMES)
    late, early = rng.choice(BOXES, (2, 40), replace=False)  # a few appear, a few go
    first[late] = rng.integers(2, FRAMES // 2, len(late))
    last[early] = rng.integers(FRAMES // 2, FRAMES, len(early))
    frames, boxes, scores = [], [], []
    for f in range(1, FRAMES + 1):
        c = p + v * f + rng.normal(0, 1, (BOXES, 2))
        b = np.c_[c - wh / 2, wh]
        keep = ((first <= f) & (f <= last) & (b[:, 0] >= 0) & (b[:, 1] >= 0)
                & (b[:, 0] + b[:, 2] <= SIDE) & (b[:, 1] + b[:, 3] <= SIDE))
        frames.append(np.full(keep.sum(), f))
        boxes.append(b[keep])
        scores.append(rng.uniform(0.5, 1.0, keep.sum()))
    f = np.concatenate(frames)
    write_mot(seq / "det" / "det.txt", f, -np.ones(len(f), int), np.concatenate(boxes),
              np.concatenate(scores))
    (seq / "seqinfo.ini").write_text(
        f"[Sequence]\nname={seq.name}\nimDir=img1\nframeRate={FPS}\nseqLength={FRAMES}\n"
        f"imWidth={SIDE}\nimHeight={SIDE}\nimExt=.jpg\n")
    return len(f)


def timed(cmd: list[str], env: dict[str, str]) -> tuple[float, float, str]:
    """Wall seconds, CPU seconds (user + system of the child) and the output (stdout and
    stderr) of one run; exits on a failed run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=ROOT)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode:
        sys.stderr.write(p.stdout[-1000:] + p.stderr[-2000:])
        raise SystemExit(f"failed ({p.returncode}): {' '.join(cmd)}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, p.stdout + p.stderr


def tracker_ms(output: str) -> float:
    """The tracker stage's milliseconds a frame, from vistrack track's summary line
    ("... tracker N frames/s", or "ms a frame: ..., tracker X, ...")."""
    m = re.search(r"ms a frame:[^)]*tracker ([0-9.]+)", output)
    if m:
        return float(m.group(1))
    m = re.search(r"tracker ([0-9.]+) frames/s", output)
    return 1e3 / float(m.group(1)) if m else float("nan")


def import_ms(stderr: str) -> float:
    """Milliseconds of all imports of a run under ``-X importtime``: the sum of the top-level
    lines' cumulative times (an import inside a function counts once, at top level)."""
    total = 0
    for line in stderr.splitlines():
        m = re.match(r"import time:\s+\d+ \|\s+(\d+) \| (\S.*)$", line)
        if m:  # a nested import's name is indented, so does not match "| \S"
            total += int(m.group(1))
    return total / 1e3


def rows_of(path: Path) -> int:
    with open(path, "rb") as fh:
        return sum(1 for line in fh if line.strip())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=5, help="timed runs of each (default 5)")
    ap.add_argument("--write", metavar="MD", help="write the section into this markdown file")
    args = ap.parse_args(argv)

    work = Path(tempfile.mkdtemp(prefix="vt-whole-"))
    try:
        seq = work / "SIM-1000"
        n_det = make_sequence(seq)
        det = seq / "det" / "det.txt"
        env = dict(os.environ, NUMBA_CACHE_DIR=str(work / "numba"),
                   VISTRACK_CACHE_DIR=str(work / "kernels"))
        vt_out, peer_out = work / "vistrack.txt", work / "peer.txt"
        vt_cmd = [VT, "track", str(seq), "--out", str(vt_out), "--force"]
        probe = subprocess.run([PY, "-c", "import trackers, supervision"], env=env,
                               capture_output=True, text=True)
        peer_cmd = None
        if probe.returncode == 0:
            script = work / "peer_sort.py"
            script.write_text(PEER_SORT)
            peer_cmd = [PY, str(script), str(det), str(peer_out), str(FPS)]
        else:
            print("trackers is not importable: vistrack alone ("
                  + (probe.stderr.strip().splitlines() or ["?"])[-1] + ")", file=sys.stderr)
        print(f"{FRAMES} frames, {n_det:,} detections ({n_det / FRAMES:.0f} a frame), "
              f"{SIDE}x{SIDE}; {args.runs} runs each, interleaved, after one untimed run",
              file=sys.stderr)

        timed(vt_cmd, env)  # untimed: fills numba's caches
        if peer_cmd:
            timed(peer_cmd, env)
        vt, peer = [], []
        for k in range(args.runs):
            vt.append(timed(vt_cmd, env))
            print(f"  run {k + 1}: vistrack {vt[-1][0]:.2f} s", end="", file=sys.stderr,
                  flush=True)
            if peer_cmd:
                peer.append(timed(peer_cmd, env))
                print(f", trackers SORT {peer[-1][0]:.2f} s", end="", file=sys.stderr)
            print(file=sys.stderr, flush=True)

        # where vistrack's time goes
        start = [timed([PY, "-c", "pass"], env)[0] for _ in range(args.runs)]
        (work / "parts.py").write_text(VT_PARTS)
        parts_cmd = [PY, str(work / "parts.py"), str(seq), str(work / "parts.txt")]
        runs = [dict((k, float(v)) for k, v in (kv.split("=") for kv in
                                                timed(parts_cmd, env)[2].split()))
                for _ in range(args.runs)]
        it = timed([PY, "-X", "importtime", "-m", "vistrack.cli"] + vt_cmd[1:], env)[2]
        vt_rows, peer_rows = rows_of(vt_out), (rows_of(peer_out) if peer_cmd else 0)
    finally:
        shutil.rmtree(work, ignore_errors=True)

    med = statistics.median
    vt_wall, vt_cpu = med(r[0] for r in vt), med(r[1] for r in vt)
    trk = med(tracker_ms(r[2]) for r in vt)
    t_start, t_it = med(start) * 1e3, import_ms(it)
    numba_in = re.search(r"\| numba$", it, re.M) is not None
    part = {k: med(r[k] for r in runs) * 1e3 for k in runs[0]}
    results = [("`vistrack track SEQ_DIR --out FILE --force`", vt_wall, vt_cpu, vt_rows)]
    if peer:
        results.append(("`trackers` SORT script (peer)", med(r[0] for r in peer),
                        med(r[1] for r in peer), peer_rows))
    ratio = results[1][1] / vt_wall if peer else float("nan")
    cpu_ratio = results[1][2] / vt_cpu if peer else float("nan")

    print(f"\n{'command':45s} {'wall s':>7s} {'CPU s':>7s} {'ms/frame':>9s} {'x vistrack':>10s}"
          f" {'rows out':>9s}")
    for name, wall, cpu, rows in results:
        print(f"{name.replace('`', ''):45s} {wall:7.2f} {cpu:7.2f} {wall * 1e3 / FRAMES:9.2f} "
              f"{wall / vt_wall:10.1f} {rows:9,d}")
    n = FRAMES - 1
    parts = [("interpreter start (`python -c pass`)", t_start, ""),
             ("imports of `vistrack.cli`, `.config`, `.io.atomic`, `.pipeline`", part["imports"],
              ""),
             ("reading seqinfo.ini and det.txt, boxes by frame", part["read"], ""),
             ("tracker, first frame (the kernels loaded)", part["first"], ""),
             (f"tracker, the other {n} frames", part["others"],
              f"{part['others'] / n:.2f} a frame"),
             ("writing the results (`MOTWriter`)", part["write"], ""),
             ("sum of these", t_start + sum(part.values()), ""),
             ("whole process, `vistrack track` (above)", vt_wall * 1e3, ""),
             ("imports, one `vistrack track` run under `-X importtime` (top-level "
              "cumulative)", t_it,
              "numba imported" if numba_in else "numba not imported (the kernels compiled "
              "at install serve every call)"),
             ("tracker stage as `vistrack track` prints it (all frames)", trk * FRAMES, "")]
    print("\nvistrack, where the time goes (medians):")
    for name, ms, note in parts:
        print(f"  {name.replace('`', ''):88s} {ms:6.0f} ms {ms / FRAMES:6.2f} ms/frame"
              + (f" ({note})" if note else ""))

    ms_frame = vt_wall * 1e3 / FRAMES
    ok_ms = ms_frame <= GOAL_MS
    ok_ratio = ratio >= GOAL_RATIO if peer else None
    verdict = (f"{'met' if ok_ms else 'not met'}: {ms_frame:.2f} ms a frame"
               + (f"; {'met' if ok_ratio else 'not met'}: {ratio:.1f}x" if peer else
                  "; the ratio not measured (`trackers` not importable)"))
    print(f"\nGoal: <= {GOAL_MS:g} ms a frame whole process, >= {GOAL_RATIO:g}x trackers SORT's "
          f"whole process in the same run. {verdict.replace('`', '')}")

    if args.write:
        env_text = (f"{platform.python_implementation()} {platform.python_version()}, numpy "
                    f"{np.__version__}, {platform.machine()}, {os.cpu_count()} cores, "
                    f"{time.strftime('%Y-%m-%d')}")
        lines = [
            "## Whole process, 1,000 boxes a frame",
            "",
            f"Measured with `python bench/bench_whole.py --runs {args.runs}` ({env_text}). "
            f"A generated MOTChallenge sequence: {FRAMES} frames, {n_det:,} detections "
            f"({n_det / FRAMES:.0f} a frame) of 20-60 pixels moving at constant velocity on a "
            f"{SIDE}x{SIDE} image, scores 0.5-1. Each command is a fresh process (interpreter "
            "start, imports, reading det.txt, tracking, writing the results), run "
            f"{args.runs} times in turn with the other after one untimed run of each; medians. "
            "CPU: user + system seconds of the process.",
            "",
            "| command | wall s | CPU s | ms a frame, whole process | wall, times vistrack's |",
            "|---|---:|---:|---:|---:|",
        ]
        lines += [f"| {name} | {wall:.2f} | {cpu:.2f} | {wall * 1e3 / FRAMES:.2f} | "
                  f"{wall / vt_wall:.1f} |" for name, wall, cpu, _ in results]
        if not peer:
            lines += ["", "`trackers` is not importable here: vistrack alone."]
        else:
            lines += ["", f"CPU, times vistrack's: {cpu_ratio:.1f}."]
        lines += ["", "Where vistrack's whole process goes: a script doing `vistrack track`'s "
                  "steps in one process, each timed (medians of as many runs), beside the "
                  "whole command and what it reports itself.", "",
                  f"| part | ms | ms a frame ({FRAMES} frames) | note |",
                  "|---|---:|---:|---|"]
        lines += [f"| {name} | {ms:.0f} | {ms / FRAMES:.2f} | {note} |"
                  for name, ms, note in parts]
        lines += ["", f"Goal: ≤ {GOAL_MS:g} ms a frame whole process, ≥ {GOAL_RATIO:g}× "
                  f"`trackers` SORT's whole process in the same run. {verdict}."]
        replace_section(args.write, "\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Reading and writing MOTChallenge files: vistrack's read_mot and write_mot beside what a user
would use instead (numpy's loadtxt and savetxt, pandas' read_csv and to_csv, motmetrics' loader),
in one run, on the same files.

    python bench/bench_mot_io.py [--rows N] [--repeat N] [--write MD]

Files: MOT17-04's gt.txt (108,005 rows of 9 values, sorted by id, not by frame) and det.txt
(28,406 rows of 7), when ../shared/data is beside the repository, and a results file of
``--rows`` rows (default 1,000,000; 100 boxes a frame, written by write_mot). Each figure is
the median wall-clock time of ``--repeat`` rounds (default 5), each running every reader (and
then every writer) once in turn, so that other work on the machine weighs on all alike (a
reader or writer that has taken 30 s is not run again), the file in the page cache; rows/s
is rows / that time, and also rows / the median CPU time. "before" is, for reading,
read_mot's careful reader alone (numpy's loadtxt, then line by line where it fails: what
read_mot was before it read plain files itself) and, for writing, write_mot's previous code
(Python's %-format, a block of rows at a time), run here beside the rest.
"""

from __future__ import annotations

import argparse
import functools
import itertools
import os
import platform
import shutil
import statistics
import sys
import tempfile
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from vistrack.io import MOTTable, read_mot, write_mot
from vistrack.io.motchallenge import _read_careful

from _common import optional  # noqa: E402  (bench/ is on the path of its scripts)
from _markdown import publish  # noqa: E402

SEQ = Path(__file__).resolve().parents[2] / "shared" / "data" / "mot17" / "MOT17-04-FRCNN"
BUDGET_S = 30.0
ROW = "%d,%d,%.2f,%.2f,%.2f,%.2f,%.4g,-1,-1,-1"


def medians(jobs: list[Callable[[], object]], repeat: int) -> list[tuple[float, float, int]]:
    """Median wall-clock and CPU seconds of each job, and its calls: ``repeat`` rounds, each
    calling every job once in turn (so that other work on the machine weighs on all alike); a
    job that has taken BUDGET_S is not called again."""
    wall: list[list[float]] = [[] for _ in jobs]
    cpu: list[list[float]] = [[] for _ in jobs]
    for _ in range(repeat):
        for k, fn in enumerate(jobs):
            if sum(wall[k]) < BUDGET_S:
                t, c = time.perf_counter(), time.process_time()
                fn()
                wall[k].append(time.perf_counter() - t)
                cpu[k].append(time.process_time() - c)
    return [(statistics.median(w), statistics.median(c), len(w)) for w, c in zip(wall, cpu)]


def names(width: int) -> list[str]:
    """The MOTChallenge column names of a file of ``width`` values."""
    tail = ["class", "visibility"] if width == 9 else ["x", "y", "z"]
    return (["frame", "id", "bb_left", "bb_top", "bb_width", "bb_height", "conf"] + tail)[:width]


def readers() -> list[tuple[str, Callable[[Path, int], object]]]:
    def before(p: Path, w: int) -> MOTTable:
        return MOTTable.from_rows(_read_careful(str(p), p.read_bytes()), str(p))

    out: list[tuple[str, Callable[[Path, int], object]]] = [
        ("vistrack read_mot", lambda p, w: read_mot(p)),
        ("vistrack read_mot before (loadtxt, then line by line)", before),
        ("numpy loadtxt(delimiter=',')", lambda p, w: np.loadtxt(p, delimiter=",", ndmin=2)),
    ]
    pd = optional("pandas")
    if pd is not None:
        out.append(("pandas read_csv(header=None, names=MOT columns)",
                    lambda p, w: pd.read_csv(p, header=None, names=names(w))))
    mm = optional("motmetrics")
    if mm is not None:
        out.append(("motmetrics io.loadtxt(fmt='mot15-2D')",
                    lambda p, w: mm.io.loadtxt(str(p), fmt="mot15-2D")))
    return out


def results(n: int, seed: int = 0) -> tuple[np.ndarray, ...]:
    """``n`` results rows, 100 boxes a frame: frames, ids, boxes, scores."""
    rng = np.random.default_rng(seed)
    f = np.repeat(np.arange(1, n // 100 + 2), 100)[:n]
    i = np.tile(np.arange(1, 101), n // 100 + 1)[:n]
    b = np.c_[rng.uniform(0, 1900, (n, 2)), rng.uniform(5, 300, (n, 2))]
    return f, i, b, rng.uniform(0, 1, n)


def write_mot_before(path: Path, f, i, b, c) -> None:
    """write_mot as it was: rows sorted by frame and id, then Python's %-format of a block of
    65,536 rows at a time."""
    order = np.lexsort((i, f))
    f, i, b, c = f[order], i[order], b[order], c[order]
    with open(path, "w") as out:
        for s in range(0, len(f), 65536):
            e = min(s + 65536, len(f))
            cells = zip(f[s:e].tolist(), i[s:e].tolist(), *b[s:e].T.tolist(), c[s:e].tolist())
            out.write(((ROW + "\n") * (e - s)) % tuple(itertools.chain.from_iterable(cells)))


def writers(f, i, b, c) -> list[tuple[str, Callable[[Path], object]]]:
    rows = np.c_[f, i, b, c]
    out: list[tuple[str, Callable[[Path], object]]] = [
        ("vistrack write_mot", lambda p: write_mot(p, f, i, b, c, force=True)),
        ("vistrack write_mot before (%-format, a block of rows at a time)",
         lambda p: write_mot_before(p, f, i, b, c)),
        (f"numpy savetxt(fmt='{ROW}')", lambda p: np.savetxt(p, rows, fmt=ROW)),
    ]
    pd = optional("pandas")
    if pd is not None:
        df = pd.DataFrame(rows, columns=names(7)).astype({"frame": int, "id": int})
        df["x"] = df["y"] = df["z"] = -1
        out.append(("pandas to_csv(float_format='%.2f')",
                    lambda p: df.to_csv(p, header=False, index=False, float_format="%.2f")))
    return out


def table(head: str, files: list[tuple[str, Path | None, int, int]],
          rows: list[tuple[str, list[tuple[float, float]]]]) -> list[str]:
    """Per file: milliseconds, M rows/s, and M rows/s of CPU time (rows / CPU seconds: less
    sensitive to other work on the machine); and how many times vistrack's (the first row's)
    time each takes on the last file."""
    cols = " | ".join(f"{name} ({n:,} rows): ms | M rows/s | M rows/s, CPU"
                      for name, _, n, _ in files)
    t = [f"| {head} | {cols} | times vistrack's time ({files[-1][0]}) |",
         "|---|" + "---:|---:|---:|" * len(files) + "---:|"]
    ref = rows[0][1][-1][0]
    for name, secs in rows:
        cells = " | ".join(f"{1e3 * s:,.0f} | {n / s / 1e6:.2f} | {n / c / 1e6:.2f}"
                           for (s, c), (_, _, n, _) in zip(secs, files))
        t.append(f"| {name} | {cells} | {secs[-1][0] / ref:.2g} |")
    return t


def rate(files: list[tuple[str, Path | None, int, int]], secs: list[tuple[float, float]],
         k: int) -> str:
    """The M rows/s on each file (wall clock: k = 0, CPU: k = 1), lowest to highest."""
    r = sorted(n / s[k] / 1e6 for (_, _, n, _), s in zip(files, secs))
    return f"{r[0]:.2f}" if len(r) == 1 else f"{r[0]:.2f} to {r[-1]:.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rows", type=int, default=1_000_000, help="rows of the results file")
    ap.add_argument("--repeat", type=int, default=5, help="runs of each (median)")
    ap.add_argument("--write", metavar="MD", help="write the section into this markdown file")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    load = os.getloadavg()[0]
    work = Path(tempfile.mkdtemp(prefix="vt-motio-"))
    try:
        f, i, b, c = results(args.rows)
        big = write_mot(work / "results.txt", f, i, b, c)
        files: list[tuple[str, Path | None, int, int]] = []
        for name in ("gt", "det"):
            p = SEQ / name / f"{name}.txt"
            if p.exists():
                t = read_mot(p)
                files.append((f"MOT17-04 {name}.txt", p, len(t), t.columns))
            else:
                print(f"  ({p} not found: skipped)", file=sys.stderr)
        files.append(("results", big, args.rows, 10))

        rd = readers()
        for _, fn in rd:
            fn(files[0][1], files[0][3])  # once before timing: first-call costs are not reading
        jobs = [(name, fname, n, functools.partial(fn, p, w))
                for name, fn in rd for fname, p, n, w in files]
        got = medians([j[3] for j in jobs], args.repeat)
        read_rows = [(name, [(s, cpu) for (nm, _, _, _), (s, cpu, _) in zip(jobs, got)
                             if nm == name])
                     for name, _ in rd]
        for (name, fname, n, _), (s, cpu, runs) in zip(jobs, got):
            print(f"{name:55s} {fname:18s} {1e3 * s:9.1f} ms  {n / s / 1e6:6.2f} M rows/s "
                  f"({n / cpu / 1e6:6.2f} CPU; {runs} runs)", flush=True)

        wr = writers(f, i, b, c)
        outs = [work / f"written-{k}.txt" for k in range(len(wr))]
        got = medians([functools.partial(fn, out) for (_, fn), out in zip(wr, outs)], args.repeat)
        write_rows = [(name, [(s, cpu)]) for (name, _), (s, cpu, _) in zip(wr, got)]
        written = [out.read_bytes() for out in outs]
        for (name, _), (s, cpu, runs) in zip(wr, got):
            print(f"{name:55s} {'results':18s} {1e3 * s:9.1f} ms  {args.rows / s / 1e6:6.2f} M "
                  f"rows/s ({args.rows / cpu / 1e6:6.2f} CPU; {runs} runs)", flush=True)

        # read_mot gives what its careful reader gives, and write_mot what it wrote before
        same_read = all(
            all(np.array_equal(getattr(a, k), getattr(z, k)) for k in ("frames", "ids", "boxes",
                                                                       "conf", "classes",
                                                                       "visibility"))
            for a, z in ((read_mot(p), readers()[1][1](p, w)) for _, p, _, w in files))
        same_write = written[0] == written[1]
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"same arrays read: {same_read}; same bytes written: {same_write}", file=sys.stderr)
    same = {True: "the same", False: "NOT the same"}

    versions = ", ".join(f"{m} {getattr(optional(m), '__version__', '?')}"
                         for m in ("numpy", "pandas", "motmetrics") if optional(m) is not None)
    cmd = "python bench/bench_mot_io.py" + ("" if args.rows == 1_000_000 else
                                            f" --rows {args.rows}") + (
        "" if args.repeat == 5 else f" --repeat {args.repeat}")
    lines = [
        "## MOTChallenge files: reading and writing",
        "",
        f"Measured with `{cmd}` (Python {platform.python_version()}, {versions}, "
        f"{os.cpu_count()} cores, load average {load:.1f} at the start, "
        f"{time.strftime('%Y-%m-%d')}). Median of {args.repeat} rounds, each running every "
        f"reader (then writer) once in turn (one that has taken {BUDGET_S:.0f} s is not run "
        "again), the file in the page cache: wall-clock "
        "milliseconds and rows a second, and rows a second of the process's CPU time. read_mot "
        "returns the rows checked and sorted by frame; the others parse only. \"before\" is "
        "read_mot's careful reader alone, what read_mot was until it read plain files itself, "
        "and write_mot's previous code, Python's %-format of a block of rows at a time. In "
        f"this run read_mot gave {same[same_read]} arrays as the careful reader on every "
        f"file, and write_mot {same[same_write]} bytes as before.",
        "",
        "**Reading**",
        "",
        *table("reader", files, read_rows),
        "",
        f"**Writing** ({args.rows:,} results rows, `{ROW}` a row; pandas with %.2f for every "
        "float)",
        "",
        *table("writer", [("results", None, args.rows, 10)], write_rows),
        "",
        "Goal: reading and writing at >= 2 M rows/s. In this run, M rows a second of CPU "
        f"time: read_mot {rate(files, read_rows[0][1], 1)} (before: "
        f"{rate(files, read_rows[1][1], 1)}), write_mot {rate(files[-1:], write_rows[0][1], 1)} "
        f"(before: {rate(files[-1:], write_rows[1][1], 1)}); of wall-clock time: read_mot "
        f"{rate(files, read_rows[0][1], 0)}, write_mot {rate(files[-1:], write_rows[0][1], 0)}.",
        "",
    ]
    section = "\n".join(lines)
    publish(section, args.write)


if __name__ == "__main__":
    main()

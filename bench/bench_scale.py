"""Many sequences, one command: ``vistrack track BENCH... --out DIR --jobs N`` beside a shell
loop and ``xargs -P N`` of one ``vistrack track`` a sequence (what a user would script
instead), on every sequence of the shared data's four sets.

Each command is run ``--runs`` times in turn with the others, after one untimed run of each;
medians of the wall time; the outputs of every command are checked to be identical to the
serial loop's. Writes a section of docs/benchmarks.md with ``--write``.

    python bench/bench_scale.py --runs 3 --write docs/benchmarks.md
"""

from __future__ import annotations

import argparse
import filecmp
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _markdown import replace_section  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
SETS = ("mot15", "mot17", "mot16-fairmot", "kitti-tracking")
PY = sys.executable
VT = str(Path(PY).parent / "vistrack")


def sequences() -> list[Path]:
    return sorted((p for s in SETS for p in (DATA / s).iterdir()
                   if (p / "seqinfo.ini").exists() and (p / "det" / "det.txt").exists()),
                  key=lambda p: p.name)


def timed(cmd: str | list[str], shell: bool = False) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, shell=shell, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    return time.perf_counter() - t


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3, help="timed runs of each (default 3)")
    ap.add_argument("--write", metavar="MD", help="write the section into this markdown file")
    args = ap.parse_args(argv)
    if not DATA.is_dir():
        print(f"skipped: {DATA} is absent (the shared data sits beside the repository)",
              file=sys.stderr)
        return 0
    seqs = sequences()
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    work = Path(tempfile.mkdtemp(prefix="vt-scale-"))
    try:
        lines = work / "seqs.txt"
        lines.write_text("".join(f"{p}\n" for p in seqs))
        dirs = {k: work / k for k in ("loop", "xargs", "jobs1", "jobsN")}
        commands = {
            "loop": (f"while read s; do {VT} track \"$s\" --out {dirs['loop']}/$(basename "
                     f"\"$s\").txt --force --quiet; done < {lines}", True),
            "xargs": (f"xargs -P {cores} -I@ sh -c '{VT} track @ --out {dirs['xargs']}/"
                      f"$(basename @).txt --force --quiet' < {lines}", True),
            "jobs1": ([VT, "track", *map(str, seqs), "--out", str(dirs["jobs1"]), "--jobs",
                       "1", "--force", "--quiet"], False),
            "jobsN": ([VT, "track", *map(str, seqs), "--out", str(dirs["jobsN"]), "--jobs",
                       str(cores), "--force", "--quiet"], False),
        }
        for d in dirs.values():
            d.mkdir()
        names = {"loop": "a shell loop, one `vistrack track` a sequence",
                 "xargs": f"`xargs -P {cores}`, one `vistrack track` a sequence",
                 "jobs1": "`vistrack track SEQ... --out DIR --jobs 1`",
                 "jobsN": f"`vistrack track SEQ... --out DIR --jobs {cores}`"}
        for cmd, shell in commands.values():  # untimed: fills the caches
            timed(cmd, shell)
        times: dict[str, list[float]] = {k: [] for k in commands}
        for r in range(args.runs):
            for k, (cmd, shell) in commands.items():
                times[k].append(timed(cmd, shell))
            print(f"run {r + 1}: " + ", ".join(f"{k} {v[-1]:.2f} s" for k, v in times.items()),
                  file=sys.stderr)
        same = all(filecmp.cmp(dirs["loop"] / f"{p.name}.txt", d / f"{p.name}.txt",
                               shallow=False) for p in seqs for d in dirs.values())
    finally:
        shutil.rmtree(work, ignore_errors=True)
    med = {k: statistics.median(v) for k, v in times.items()}
    rows = [(names[k], med[k], med["loop"] / med[k]) for k in commands]
    print(f"{len(seqs)} sequences, {cores} cores; outputs identical: {same}")
    for name, t, ratio in rows:
        print(f"  {name.replace('`', ''):58s} {t:6.2f} s  {ratio:5.2f}x the loop")
    if args.write:
        env = (f"CPython {platform.python_version()}, {platform.machine()}, {cores} cores, "
               f"{time.strftime('%Y-%m-%d')}")
        text = [
            "## Many sequences, one command",
            "",
            f"Measured with `python bench/bench_scale.py --runs {args.runs}` ({env}): every "
            f"sequence of the shared data's four sets ({len(seqs)} sequences: MOT15, MOT17, "
            "MOT16-FairMOT, KITTI), tracked online from their detections; each command run "
            f"{args.runs} times in turn with the others after one untimed run of each; medians "
            "of the wall time. The outputs of every command are identical to the loop's: "
            f"{'yes' if same else 'NO'}.",
            "",
            "| command | wall s | times faster than the loop |",
            "|---|---:|---:|",
            *[f"| {name} | {t:.2f} | {ratio:.2f} |" for name, t, ratio in rows],
        ]
        replace_section(args.write, "\n".join(text) + "\n")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())

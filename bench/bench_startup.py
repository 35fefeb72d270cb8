"""Start-up and first-run time of each entry point, whole process, cold and warm.

    python bench/bench_startup.py [--cold N] [--warm N] [--only NAME ...] [--write MD]

"Cold" is a fresh install's first run: every cache vistrack and numba use (``NUMBA_CACHE_DIR``,
``VISTRACK_CACHE_DIR``) points at a new empty temporary folder, so every compiled kernel the
command needs is compiled in that run. "Warm" is the same command again with those caches
filled. Each figure is the median of the runs (wall-clock seconds and CPU seconds of the
process and its children). Beside vistrack: roboflow's ``trackers`` (SORT), what a user would
pick instead, whole process on the same detections, when it is installed.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
CLIP = ROOT / "src" / "vistrack" / "data" / "pets09-s2l1" / "pets09-s2l1.mp4"
GT = ROOT / "src" / "vistrack" / "data" / "pets09-s2l1" / "gt.txt"
SEQ = SHARED / "mot17" / "MOT17-04-FRCNN"
OTB = SHARED / "otb-crossing" / "Crossing"

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _markdown import replace_section  # noqa: E402

BIN = Path(sys.executable).parent
VT = str(BIN / "vistrack")
PY = sys.executable

# trackers' SORT over a MOTChallenge detection file, whole process, as a user would script it
PEER_SORT = """
import sys, numpy as np, supervision as sv
from trackers import SORTTracker
det = np.loadtxt(sys.argv[1], delimiter=",", ndmin=2)
tr = SORTTracker(frame_rate=float(sys.argv[3]))
rows = []
for f in range(1, int(det[:, 0].max()) + 1):
    d = det[det[:, 0] == f]
    xyxy = np.c_[d[:, 2:4], d[:, 2:4] + d[:, 4:6]]
    out = tr.update(sv.Detections(xyxy=xyxy, confidence=d[:, 6]))
    for (x0, y0, x1, y1), i in zip(out.xyxy, out.tracker_id):
        if i >= 0:
            rows.append(f"{f},{i},{x0:.2f},{y0:.2f},{x1 - x0:.2f},{y1 - y0:.2f},1,-1,-1,-1")
open(sys.argv[2], "w").write("\\n".join(rows) + "\\n")
"""


def entries(out: Path, examples: Path) -> list[tuple[str, list[str], bool]]:
    """(name, command, needs shared data) for each entry point."""
    e = [
        ("import vistrack", [PY, "-c", "import vistrack"], False),
        ("vistrack --help", [VT, "--help"], False),
        ("vistrack track (bundled clip)", [VT, "track", str(CLIP), "--out-dir", str(out / "clip"),
                                           "--force"], False),
        ("vistrack eval (bundled clip's gt against itself)",
         [VT, "eval", "--gt", str(GT), "--pred", str(GT)], False),
        ("vistrack demo kalman", [VT, "demo", "kalman", "--out", str(out / "demo")], False),
        ("vistrack track SEQ_DIR (MOT17-04)", [VT, "track", str(SEQ), "--out",
                                               str(out / "mot17-04.txt"), "--force"], True),
        ("vistrack track SEQ_DIR --offline (MOT17-04)",
         [VT, "track", str(SEQ), "--offline", "--out", str(out / "mot17-04-offline.txt"),
          "--force"], True),
        ("vistrack track-one (OTB Crossing)",
         [VT, "track-one", str(OTB / "img"), "--init", "205,151,17,50", "--out",
          str(out / "crossing.txt"), "--force"], True),
        ("examples/filter_and_smooth.py", [PY, str(ROOT / "examples" / "filter_and_smooth.py")],
         False),
        ("examples/nonlinear_figures.py",
         [PY, str(ROOT / "examples" / "nonlinear_figures.py"), str(out / "figures")], False),
    ]
    # the examples that write their figures beside themselves run from a copy (see main)
    for name, shared in [("kalman_seed_figures", False), ("compose_bag", True),
                         ("snake_bag", True), ("mm_pets09", True), ("dcpf_pets09", True),
                         ("wsl_pets09", True)]:
        e.append((f"examples/{name}.py", [PY, str(examples / f"{name}.py")], shared))
    return e


def _copy_examples(work: Path) -> Path:
    """A copy of examples/ under ``work``, so that their figures go there; its
    ``../../shared`` is the shared data, as for the repository's own."""
    copy = work / "tree" / "repo" / "examples"
    shutil.copytree(ROOT / "examples", copy, ignore=shutil.ignore_patterns("*.png"))
    (copy / "figures").mkdir(exist_ok=True)
    if SHARED.exists():
        (work / "tree" / "shared").symlink_to(SHARED.parent)
    return copy


def timed(cmd: list[str], env: dict[str, str]) -> tuple[float, float, int]:
    """Wall seconds, CPU seconds (user + system of the process and its children) and the exit
    status of one run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    p = subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, cwd=ROOT)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode:
        sys.stderr.write(p.stderr.decode(errors="replace")[-2000:])
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, p.returncode


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cold", type=int, default=1, help="cold runs per entry (default 1)")
    ap.add_argument("--warm", type=int, default=3, help="warm runs per entry (default 3)")
    ap.add_argument("--only", nargs="*", default=None,
                    help="entries whose name contains one of these strings")
    ap.add_argument("--write", metavar="MD", help="write the section into this markdown file")
    ap.add_argument("--jit", action="store_true",
                    help="also time each cold run without the kernels compiled at install "
                         "(VISTRACK_PREBUILT=0): everything compiled on first use")
    args = ap.parse_args(argv)

    work = Path(tempfile.mkdtemp(prefix="vt-startup-"))
    out = work / "out"
    rows = []
    examples = _copy_examples(work)
    from vistrack import _prebuilt

    print(_prebuilt.status(), file=sys.stderr)
    try:
        for name, cmd, shared in entries(out, examples):
            if args.only and not any(s in name for s in args.only):
                continue
            if shared and not SHARED.exists():
                print(f"  skip {name}: ../shared/data is not beside the repository",
                      file=sys.stderr)
                continue
            cold, jit, warm = [], [], []
            for k in range(args.cold):
                env = dict(os.environ, NUMBA_CACHE_DIR=str(work / f"numba-{name}-{k}"),
                           VISTRACK_CACHE_DIR=str(work / f"kernels-{name}-{k}"))
                cold.append(timed(cmd, env))
                if args.jit:  # the same without the kernels compiled at install
                    env = dict(env, VISTRACK_PREBUILT="0",
                               NUMBA_CACHE_DIR=str(work / f"numba-jit-{name}-{k}"),
                               VISTRACK_CACHE_DIR=str(work / f"kernels-jit-{name}-{k}"))
                    jit.append(timed(cmd, env))
            env = dict(os.environ, NUMBA_CACHE_DIR=str(work / "numba-warm"),
                       VISTRACK_CACHE_DIR=str(work / "kernels-warm"))
            timed(cmd, env)  # fill the caches
            for _ in range(args.warm):
                warm.append(timed(cmd, env))
            if any(c[2] for c in cold + jit + warm):
                print(f"  {name}: a run failed", file=sys.stderr)
            nan = float("nan")
            row = (name, statistics.median(c[0] for c in cold) if cold else nan,
                   statistics.median(c[1] for c in cold) if cold else nan,
                   statistics.median(w[0] for w in warm), statistics.median(w[1] for w in warm),
                   statistics.median(c[0] for c in jit) if jit else nan)
            rows.append(row)
            print(f"{name:45s} cold {row[1]:7.2f} s ({row[2]:6.2f} s CPU)   "
                  f"warm {row[3]:6.2f} s ({row[4]:5.2f} s CPU)"
                  + (f"   cold, compiled on first use {row[5]:7.2f} s" if jit else ""),
                  flush=True)
        peer = []
        if SHARED.exists() and (not args.only or any("trackers" in s for s in args.only)):
            env = dict(os.environ)
            probe = subprocess.run([PY, "-c", "import trackers, supervision"], env=env,
                                   capture_output=True)
            if probe.returncode == 0:
                script = work / "peer_sort.py"
                script.write_text(PEER_SORT)
                cmd = [PY, str(script), str(SEQ / "det" / "det.txt"), str(out / "peer.txt"),
                       "30"]
                (out).mkdir(parents=True, exist_ok=True)
                imp = [timed([PY, "-c", "import trackers"], env) for _ in range(args.warm)]
                runs = [timed(cmd, env) for _ in range(args.warm)]
                peer = [("import trackers", statistics.median(r[0] for r in imp),
                         statistics.median(r[1] for r in imp)),
                        ("trackers SORT script (MOT17-04)", statistics.median(r[0] for r in runs),
                         statistics.median(r[1] for r in runs))]
                for p in peer:
                    print(f"{p[0]:45s} {'':29s}warm {p[1]:6.2f} s ({p[2]:5.2f} s CPU)")
            else:
                print("  (trackers not installed: no peer rows)", file=sys.stderr)
    finally:
        shutil.rmtree(work, ignore_errors=True)

    if args.write:
        lines = [
            "## Start-up and first run",
            "",
            f"Measured with `python bench/bench_startup.py --cold {args.cold} --warm "
            f"{args.warm}{' --jit' if args.jit else ''}` ({platform.python_implementation()} "
            f"{platform.python_version()}, {os.cpu_count()} cores; {_prebuilt.status()}). "
            "Whole process, median of the runs; cold: every cache emptied (a fresh install's "
            "first run), warm: the same command again"
            + ("; compiled on first use: cold without the kernels compiled at install "
               "(`VISTRACK_PREBUILT=0`), as before they were." if args.jit else "."),
            "",
            "| command | cold s | cold CPU s | warm s | warm CPU s |"
            + (" cold, compiled on first use, s |" if args.jit else ""),
            "|---|---:|---:|---:|---:|" + ("---:|" if args.jit else ""),
        ]
        lines += [f"| {r[0]} | {r[1]:.2f} | {r[2]:.2f} | {r[3]:.2f} | {r[4]:.2f} |"
                  + (f" {r[5]:.2f} |" if args.jit else "") for r in rows]
        lines += [f"| {p[0]} (peer) | | | {p[1]:.2f} | {p[2]:.2f} |" + (" |" if args.jit else "")
                  for p in peer]
        replace_section(args.write, "\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

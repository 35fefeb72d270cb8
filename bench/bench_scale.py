"""Many sequences, one command: ``vistrack track BENCH... --out DIR --jobs N`` beside a shell
loop and ``xargs -P N`` of one ``vistrack track`` a sequence (what a user would script
instead), on every sequence of the shared data's four sets, and ``--jobs 1`` against ``--jobs
N`` on MOT15 and MOT17 alone. Then the cost of a job on the process pool and on a Dask
``LocalCluster`` (no-op jobs), and a batched Kalman filter over a million series on a Dask
cluster of 1 and N worker processes against one process filtering the same chunks in a loop
(the data generated where it is filtered), in 10 chunks (the goals' setting) and in 50.

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


def sequences(sets: tuple[str, ...] = SETS) -> list[Path]:
    return sorted((p for s in sets for p in (DATA / s).iterdir()
                   if (p / "seqinfo.ini").exists() and (p / "det" / "det.txt").exists()),
                  key=lambda p: p.name)


def timed(cmd: str | list[str], shell: bool = False) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, shell=shell, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    return time.perf_counter() - t


def _noop(x: object) -> object:
    return x


def pool_cost(workers: int, n: int) -> float:
    """Seconds a job of the process pool ``vistrack track`` uses (``--jobs``), over ``n``
    jobs that send a job's description and get an outcome back, pool start excluded."""
    from vistrack.batch import Job, Outcome, process_pool

    job = Job(Path("/data/MOT17-04-FRCNN"), Path("/out/MOT17-04-FRCNN.txt"), "detections",
              {"offline": False})
    back = Outcome(job.input, job.out, True, 1050, 47_557, 83, 0.4)
    with process_pool(workers) as pool:
        t = time.perf_counter()
        for f in [pool.submit(_noop, (job, back)) for _ in range(n)]:
            f.result()
        return (time.perf_counter() - t) / n


# a Dask worker runs its tasks in a thread; glibc gives each thread an arena of its own, from
# which a chunk's large arrays are mapped and unmapped afresh (a page fault for every page
# touched, about a tenth of the filter's time here); one arena, as in a process of one thread,
# reuses them
ONE_ARENA = {"MALLOC_ARENA_MAX": "1"}


def local_cluster(workers: int, env: dict[str, str] | None = None):
    """A Dask cluster of ``workers`` processes, one thread each, on localhost with no
    dashboard; one BLAS thread a worker, without the nanny's MALLOC_TRIM_THRESHOLD_ (``env``:
    more of the workers' environment, by default one malloc arena) and without Dask's
    profiler."""
    import dask
    import distributed

    one = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    env = ONE_ARENA if env is None else env
    # Dask's statistical profiler samples each worker's thread every 10 ms (the frames walked
    # under the GIL): off, as on a cluster that runs numeric tasks and is not being profiled
    with dask.config.set({"distributed.nanny.pre-spawn-environ": {**one, **env},
                          "distributed.worker.profile.enabled": False}):
        return distributed.LocalCluster(n_workers=workers, threads_per_worker=1,
                                        processes=True, dashboard_address=None)


def dask_cost(client, n: int) -> float:
    """Seconds a no-op task takes through the cluster's scheduler, over ``n`` tasks."""
    t = time.perf_counter()
    client.gather(client.map(_noop, range(n), pure=False))
    return (time.perf_counter() - t) / n



def _model() -> dict:
    import numpy as np

    F = np.block([[np.eye(2), np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])
    return dict(F=F, Q=0.01 * np.eye(4), H=np.eye(2, 4), R=np.eye(2), x0=np.zeros(4),
                P0=np.eye(4))


def measurements(seed: int, k: int, T: int):
    """A chunk of ``k`` random walks of ``T`` steps in the plane, from its own seed."""
    import numpy as np

    return np.random.default_rng(seed).normal(size=(k, T, 2)).cumsum(axis=1)


def filter_loop(B: int, T: int, chunk: int) -> float:
    """One process: each chunk of series generated and filtered in turn (what the cluster
    does, without it); the sum of the log-likelihoods."""
    import vistrack as vt

    total = 0.0
    for i, a in enumerate(range(0, B, chunk)):
        ys = measurements(i, min(chunk, B - a), T)
        total += float(vt.kalman_filter(ys, **_model(), store_covs=False).loglik.sum())
    return total


def _measurements_block(seed, B: int, chunk: int, T: int):
    i = int(seed[0])
    return measurements(i, min(chunk, B - i * chunk), T)


def filter_dask(client, B: int, T: int, chunk: int) -> float:
    """The same on the cluster: each chunk generated by the same function (a block of
    ``map_blocks``, which Dask fuses with the filter into one task a chunk) and filtered on a
    worker, the log-likelihoods summed there; the total."""
    import dask.array as da

    import vistrack as vt

    sizes = tuple(min(chunk, B - a) for a in range(0, B, chunk))
    ys = da.arange(len(sizes), chunks=1).map_blocks(
        _measurements_block, B, chunk, T, new_axis=[1, 2], chunks=(sizes, (T,), (2,)),
        dtype=float)
    res = vt.kalman_filter(ys, **_model(), store_covs=False)
    return float(client.compute(res.loglik.sum()).result())


def track_commands(seqs: list[Path], cores: int, runs: int, work: Path,
                   kinds: tuple[str, ...]) -> tuple[dict[str, float], dict[str, str], bool]:
    """Median wall seconds of each command of ``kinds`` on ``seqs``, their names, and
    whether every command's outputs are identical to the first's."""
    lines = work / "seqs.txt"
    lines.write_text("".join(f"{p}\n" for p in seqs))
    dirs = {k: work / k for k in kinds}
    everything = {
        "loop": (f"while read s; do {VT} track \"$s\" --out {dirs.get('loop')}/$(basename "
                 f"\"$s\").txt --force --quiet; done < {lines}", True),
        "xargs": (f"xargs -P {cores} -I@ sh -c '{VT} track @ --out {dirs.get('xargs')}/"
                  f"$(basename @).txt --force --quiet' < {lines}", True),
        "jobs1": ([VT, "track", *map(str, seqs), "--out", str(dirs.get("jobs1")), "--jobs",
                   "1", "--force", "--quiet"], False),
        "jobsN": ([VT, "track", *map(str, seqs), "--out", str(dirs.get("jobsN")), "--jobs",
                   str(cores), "--force", "--quiet"], False),
    }
    commands = {k: everything[k] for k in kinds}
    for d in dirs.values():
        d.mkdir()
    names = {"loop": "a shell loop, one `vistrack track` a sequence",
             "xargs": f"`xargs -P {cores}`, one `vistrack track` a sequence",
             "jobs1": "`vistrack track SEQ... --out DIR --jobs 1`",
             "jobsN": f"`vistrack track SEQ... --out DIR --jobs {cores}`"}
    for cmd, shell in commands.values():  # untimed: fills the caches
        timed(cmd, shell)
    times: dict[str, list[float]] = {k: [] for k in commands}
    for r in range(runs):
        for k, (cmd, shell) in commands.items():
            times[k].append(timed(cmd, shell))
        print(f"run {r + 1}: " + ", ".join(f"{k} {v[-1]:.2f} s" for k, v in times.items()),
              file=sys.stderr)
    first = dirs[kinds[0]]
    same = all(filecmp.cmp(first / f"{p.name}.txt", d / f"{p.name}.txt", shallow=False)
               for p in seqs for d in dirs.values())
    return ({k: statistics.median(v) for k, v in times.items()},
            {k: names[k] for k in kinds}, same)


def dask_part(cores: int, runs: int, B: int, T: int, chunks: tuple[int, ...]) -> dict:
    """The no-op job costs, and the batched filter in chunks of each size of ``chunks`` on 1
    and ``cores`` Dask workers against the loop in this process; medians over ``runs``."""
    import distributed
    import numpy as np

    out: dict = {"pool": statistics.median(pool_cost(cores, 2000) for _ in range(runs))}
    loop: dict[int, list[float]] = {c: [] for c in chunks}
    on: dict[tuple[int, int], list[float]] = {(w, c): [] for w in (1, cores) for c in chunks}
    rate: list[float] = []
    sums: dict[int, list[float]] = {c: [] for c in chunks}  # the log-likelihoods' totals
    loop_sums: dict[int, list[float]] = {c: [] for c in chunks}
    for workers in (1, cores):
        t0 = time.perf_counter()
        with local_cluster(workers) as cluster, distributed.Client(cluster) as client:
            start = time.perf_counter() - t0
            client.run(lambda: __import__("vistrack").kalman_filter)  # imports on the workers
            if workers == cores:
                out["start"] = start
                dask_cost(client, 200)
                rate = [dask_cost(client, 5000) for _ in range(runs)]
            for chunk in chunks:
                filter_dask(client, chunk, T, chunk)  # untimed: a first chunk on each
                for r in range(runs):
                    t = time.perf_counter()
                    sums[chunk].append(filter_dask(client, B, T, chunk))
                    on[workers, chunk].append(time.perf_counter() - t)
                    if workers == 1:  # the loop in turn with the cluster of one
                        t = time.perf_counter()
                        loop_sums[chunk].append(filter_loop(B, T, chunk))
                        loop[chunk].append(time.perf_counter() - t)
                    print(f"chunks of {chunk:,}, dask {workers} worker(s), run {r + 1}: "
                          f"{on[workers, chunk][-1]:.2f} s"
                          + (f", loop {loop[chunk][-1]:.2f} s" if workers == 1 else ""),
                          file=sys.stderr)
    out["filter"] = {c: dict(loop=statistics.median(loop[c]), one=statistics.median(on[1, c]),
                             many=statistics.median(on[cores, c])) for c in chunks}
    # each size of chunk its own data (a chunk's measurements come from its index)
    out.update(task=statistics.median(rate),
               same=all(np.allclose(sums[c] + loop_sums[c], loop_sums[c][0], rtol=1e-12, atol=0)
                        for c in chunks))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3, help="timed runs of each (default 3)")
    ap.add_argument("--series", type=int, default=1_000_000,
                    help="series of the batched filter on Dask (default 1,000,000)")
    ap.add_argument("--write", metavar="MD", help="write the section into this markdown file")
    args = ap.parse_args(argv)
    if not DATA.is_dir():
        print(f"skipped: {DATA} is absent (the shared data sits beside the repository)",
              file=sys.stderr)
        return 0
    seqs, mot = sequences(), sequences(("mot15", "mot17"))
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    work = Path(tempfile.mkdtemp(prefix="vt-scale-"))
    try:
        (work / "all").mkdir()
        (work / "mot").mkdir()
        med, names, same = track_commands(seqs, cores, args.runs, work / "all",
                                          ("loop", "xargs", "jobs1", "jobsN"))
        med_mot, _, same_mot = track_commands(mot, cores, args.runs, work / "mot",
                                              ("jobs1", "jobsN"))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    # ten chunks (the setting of the goals: 100,000 series, 160 MB of measurements a chunk
    # at the default size), and fifty, which one process filters faster
    T, chunks = 100, (args.series // 10, args.series // 50)
    try:
        dk = dask_part(cores, args.runs, args.series, T, chunks)
    except ImportError as e:
        print(f"Dask part skipped: {e} (pip install 'vistrack[dask]')", file=sys.stderr)
        dk = None
    rows = [(names[k], med[k], med["loop"] / med[k]) for k in med]
    print(f"{len(seqs)} sequences, {cores} cores; outputs identical: {same}")
    for name, t, ratio in rows:
        print(f"  {name.replace('`', ''):58s} {t:6.2f} s  {ratio:5.2f}x the loop")
    mot_ratio = med_mot["jobs1"] / med_mot["jobsN"]
    print(f"MOT15 + MOT17 ({len(mot)} sequences): --jobs 1 {med_mot['jobs1']:.2f} s, --jobs "
          f"{cores} {med_mot['jobsN']:.2f} s: {mot_ratio:.2f}x; identical: {same_mot}")
    if dk:
        print(f"no-op job: process pool {dk['pool'] * 1e3:.3f} ms, Dask {dk['task'] * 1e3:.3f} ms "
              f"({1 / dk['task']:.0f} tasks/s); cluster start {dk['start']:.2f} s")
        for c, f in dk["filter"].items():
            print(f"filter {args.series:,} x {T} in chunks of {c:,}: loop {f['loop']:.2f} s, "
                  f"Dask 1 worker {f['one']:.2f} s ({f['loop'] / f['one']:.2f}x), {cores} "
                  f"workers {f['many']:.2f} s ({f['loop'] / f['many']:.2f}x)")
        print(f"same sums: {dk['same']}")
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
            "",
            f"MOT15 and MOT17 alone ({len(mot)} sequences): `--jobs 1` {med_mot['jobs1']:.2f} s, "
            f"`--jobs {cores}` {med_mot['jobsN']:.2f} s, {mot_ratio:.2f} times faster (outputs "
            f"identical: {'yes' if same_mot else 'NO'}).",
        ]
        if dk:
            text += [
                "",
                f"A job's own cost, over no-op jobs ({cores} workers; medians of "
                f"{args.runs}): {dk['pool'] * 1e3:.3f} ms on the process pool of `--jobs` "
                f"(a job's description out, its outcome back), {dk['task'] * 1e3:.2f} ms "
                f"through a Dask `LocalCluster`'s scheduler ({1 / dk['task']:,.0f} tasks a "
                f"second; the cluster started in {dk['start']:.1f} s).",
                "",
                f"A Kalman filter (constant velocity, 2-D positions) over {args.series:,} "
                f"series of {T} steps in {len(chunks)} sizes of chunk, each chunk's "
                "measurements generated by the same function where it is filtered, the "
                "log-likelihoods summed (for each size, the same total, to 1e-12, in every run "
                "and every way: "
                f"{'yes' if dk['same'] else 'NO'}):",
                "",
                "The cluster's workers: one thread each, one BLAS thread, one malloc arena "
                "(`MALLOC_ARENA_MAX=1`), and no `MALLOC_TRIM_THRESHOLD_` from the nanny, set "
                "through `distributed.nanny.pre-spawn-environ`; Dask's profiler off "
                "(`distributed.worker.profile.enabled: false`).",
                "",
                "| chunks | where | wall s | against one process |",
                "|---|---|---:|---:|",
            ]
            for c, f in dk["filter"].items():
                n = -(-args.series // c)
                text += [
                    f"| {n} of {c:,} | one process, the chunks in a loop | {f['loop']:.2f} | "
                    "1.00 |",
                    f"|  | Dask `LocalCluster`, 1 worker process | {f['one']:.2f} | "
                    f"{f['loop'] / f['one']:.2f} |",
                    f"|  | Dask `LocalCluster`, {cores} worker processes | {f['many']:.2f} | "
                    f"{f['loop'] / f['many']:.2f} |",
                ]
        replace_section(args.write, "\n".join(text) + "\n")
    return 0 if same and same_mot else 1


if __name__ == "__main__":
    raise SystemExit(main())

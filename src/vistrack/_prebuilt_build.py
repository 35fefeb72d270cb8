"""Build :mod:`vistrack._kernels`, the kernels compiled ahead of time (:mod:`vistrack._prebuilt`).

``python -m vistrack._prebuilt_build record``
    runs what vistrack's commands run (the bundled clip tracked online and offline, the same
    detections as a MOTChallenge sequence, ``vistrack demo kalman``, a filter and a smoother on
    a short series, the seeds' linear models in 1-D and 2-D) and writes to ``_prebuilt.json``
    every kernel wrapped by :func:`vistrack._prebuilt.kernel` and the argument types it was
    compiled for.
``python -m vistrack._prebuilt_build build [--inplace | --out FILE] [--jobs N] [--numba-cache DIR]``
    compiles them into the extension (``setup.py`` does this when pip installs vistrack;
    ``make`` when the sources changed), in parts compiled at once by processes of their own,
    one module a part (``--jobs``, default the processors, at most 4). ``--if-stale`` skips a
    build that is current; ``--numba-cache`` keeps numba's own compilations of the kernels,
    which the build makes first, for other processes to load (``make`` keeps them in
    ``build/numba-cache`` for the test suite).

Each exported function forwards to the numba function itself, so that numba compiles the
kernel with its own options (``fastmath``, ``error_model``) exactly as on first use, and the
module targets this machine's processor, as numba does: the results are those of the kernels
compiled on first use.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import importlib
import io
import json
import os
import runpy
import secrets
import shutil
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from . import _prebuilt
from ._prebuilt import BUILD_INFO, PACKAGE, SIGNATURES, decode, encode

__all__ = ["record", "build", "copy_numba_cache", "main"]


def _resolve(key: str) -> Any:
    """The numba function named by a key of ``_prebuilt.json``."""
    module, _, name = key.partition(":")
    mod = importlib.import_module(module)
    if name.endswith(")"):
        factory, _, args = name.partition("(")
        obj = getattr(mod, factory)(*ast.literal_eval(f"({args[:-1]},)"))
    else:
        obj = getattr(mod, name)
    return obj.jit if isinstance(obj, _prebuilt.Kernel) else obj


@contextlib.contextmanager
def _quiet_cwd() -> Iterator[Path]:
    old = Path.cwd()
    with tempfile.TemporaryDirectory() as d:
        os.chdir(d)
        try:
            yield Path(d)
        finally:
            os.chdir(old)


def _workloads(root: Path) -> None:
    """Run what vistrack's commands run, on data that ships with it (see the module)."""
    import numpy as np

    import vistrack as vt
    from vistrack.cli import main as cli
    from vistrack.data import demo_clip
    from vistrack.io.motchallenge import read_mot

    clip, gt, _ = demo_clip()
    sink = io.StringIO()
    with _quiet_cwd() as d, contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
        cli(["track", str(clip), "--out-dir", str(d / "a"), "--force"])
        cli(["track", str(clip), "--out-dir", str(d / "b"), "--force", "--offline"])
        # the clip's ground truth as a detector's output: a MOTChallenge sequence
        seq = d / "seq"
        (seq / "det").mkdir(parents=True)
        t = read_mot(gt)
        rows = [f"{f},-1,{x:.2f},{y:.2f},{w:.2f},{h:.2f},{0.5 + 0.5 * (i % 2):.2f},-1,-1,-1"
                for i, (f, (x, y, w, h)) in enumerate(zip(t.frames, t.boxes))]
        (seq / "det" / "det.txt").write_text("\n".join(rows) + "\n")
        (seq / "seqinfo.ini").write_text(
            "[Sequence]\nname=seq\nframeRate=7\nseqLength=795\nimWidth=768\nimHeight=576\n")
        cli(["track", str(seq), "--out", str(d / "c.txt"), "--force"])
        cli(["track", str(seq), "--out", str(d / "d.txt"), "--force", "--offline"])
        cli(["demo", "kalman", "--out", str(d / "demo")])
        # a filter and a smoother on a short series (examples/filter_and_smooth.py)
        cv, pos = vt.ConstantVelocity(dim=2, q=0.5), vt.Position(dim=2, r=4.0)
        _, ys = vt.simulate.simulate(cv, pos, 7, x0=[0, 0, 2, 1], dt=np.ones(6), rng=0)
        ys[5, 1] = np.nan
        kf = vt.KalmanFilter(cv, pos)
        kf.filter(ys, dt=np.ones(6))
        kf.smooth(ys, dt=np.ones(6))
        # the seeds' linear models in one and two dimensions (drifting points, constant
        # velocity, constant acceleration, periodic motion), smoothed (the smoother runs the
        # filter's kernel with the filter's types): compiled on first use, each state size took
        # up to 8 s
        for kind, dim in ((vt.ConstantPosition, 1), (vt.ConstantPosition, 2),
                          (vt.ConstantVelocity, 1), (vt.ConstantAcceleration, 1),
                          (vt.ConstantAcceleration, 2), (vt.Periodic, 1)):
            model, meas = kind(dim=dim), vt.Position(dim=dim)
            _, series = vt.simulate.simulate(model, meas, 5, x0=np.zeros(model.ndim_state),
                                             rng=0)
            vt.KalmanFilter(model, meas).smooth(series)
        # a batch whose series miss different steps: each its own covariances
        two = np.stack([ys, ys])
        two[1, 2, 0] = np.nan
        kf.filter(two, dt=np.ones(6))
        # the pairing the offline linking does from Python
        boxes = np.column_stack([t.boxes[:, :2], t.boxes[:, :2] + t.boxes[:, 2:]])[:200]
        r, c, v = vt.association.iou_pairs(boxes, boxes + 1.0, 0.3)
        vt.association.gnn_sparse(r, c, 1.0 - v, (len(boxes), len(boxes)))
        _more_workloads(root, clip, d, ys, cv, pos)


def _more_workloads(root: Path, clip: Path, d: Path, ys: Any, cv: Any, pos: Any) -> None:
    """The single-object trackers, the detector-confidence particle filter, the nonlinear
    filters, the IMM, particle resampling, the pooled EM and the spot finder (the examples'
    kernels)."""
    import cv2
    import numpy as np

    import vistrack as vt
    from vistrack.cli import main as cli
    from vistrack.filters import ExtendedKalmanFilter, IMMFilter

    cap = cv2.VideoCapture(str(clip))
    folder = d / "frames"
    folder.mkdir()
    for k in range(8):
        ok, frame = cap.read()
        if ok:
            cv2.imwrite(str(folder / f"{k:04d}.png"), frame)
    cap.release()
    for method in ("colour", "meanshift", "particle", "template", "klt", "snake"):
        cli(["track-one", str(folder), "--init", "40,95,30,80", "--method", method,
             "--out", str(d / f"one-{method}.txt")])
    cli(["track", str(clip), "--tracker", "dcpf", "--stop", "3", "--out-dir", str(d / "e")])
    # the multiple-model example: an IMM of extended Kalman filters
    P = ExtendedKalmanFilter(vt.ConstantPosition(dim=2, q=1.0), vt.Position(dim=2, r=4.0))
    PV = ExtendedKalmanFilter(vt.ConstantVelocity(dim=2, q=400.0), vt.Position(dim=2, r=4.0))
    imm = IMMFilter([P, PV], [[0.95, 0.05], [0.05, 0.95]])
    imm.filter(np.nan_to_num(ys), x0=np.r_[0.0, 0, 0, 0], P0=np.diag([25, 25, 400, 400.0]),
               dt=1 / 7)
    # the nonlinear filters, particles and resampling
    from vistrack.filters import (
        EnsembleKalmanFilter,
        ParticleFilter,
        UnscentedKalmanFilter,
    )
    from vistrack.models import CoordinatedTurn, RangeBearing

    ct, rb = CoordinatedTurn(q=0.1), RangeBearing(r_range=1.0, r_bearing=1e-3, ndim_state=5)
    xs, zs = vt.simulate.simulate(ct, rb, 20, x0=[100.0, 100, 1, 0, 0.05], rng=0)
    x0, P0 = xs[0], np.eye(5)
    for f in (ExtendedKalmanFilter(ct, rb), UnscentedKalmanFilter(ct, rb),
              EnsembleKalmanFilter(ct, rb, n_members=50, rng=0)):
        f.filter(zs, x0=x0, P0=P0)
    # the UKF's steps one at a time (the filter above runs them in one compiled call)
    from vistrack.filters import ukf_predict, ukf_update

    ukf_update(ukf_predict(vt.Gaussian(x0, P0), ct), zs[1], rb)
    # a batch whose prior has a singular member: its sigma points from the compiled factor
    UnscentedKalmanFilter(ct, rb).filter(np.stack([zs, zs]), x0=x0,
                                         P0=np.stack([P0, np.diag([1.0, 1, 1, 1, 0])]))
    for method in ("multinomial", "stratified", "systematic", "residual"):
        ParticleFilter(ct, rb, n_particles=200, resampling=method, rng=0).filter(
            zs, x0=x0, P0=P0)
    runpy.run_path(str(root / "examples" / "nonlinear_figures.py"))["main"](d / "figures")
    # the Kalman filter's steps, one state and a batch, chained as a user chains them
    # (OnlineFilter's kernel is left to compile on first use: a call of a few microseconds,
    # which the ahead-of-time build's dispatch would slow by about 2)
    from vistrack.filters import kf_predict, kf_step, kf_update

    F, Q, H, R = cv.F(1.0), cv.Q(1.0), pos.H(4), pos.R()
    for g in (vt.Gaussian(np.zeros(4), np.eye(4)),
              vt.Gaussian(np.zeros((3, 4)), np.tile(np.eye(4), (3, 1, 1)))):
        y = np.ones(g.mean.shape[:-1] + (2,))
        for _ in range(2):
            g = kf_update(kf_predict(g, F, Q), y, H, R)
            g = kf_step(g, y, F, Q, H, R)
    # EM on a batch of series that share their covariances: the compiled E-step, and the
    # general one's smoother of shared gains (F learned)
    batch = np.stack([np.nan_to_num(ys), np.nan_to_num(ys) + 1.0])
    for learn in (("Q", "R"), ("F", "Q")):
        vt.filters.em(batch, F=F, Q=Q, H=H, R=R, x0=np.zeros(4), P0=np.eye(4), learn=learn,
                      max_iter=2)
    img = np.zeros((64, 64))
    img[20:23, 30:33] = 50.0
    vt.frontends.locate(img, diameter=5)


def record(root: Path) -> dict[str, list[Any]]:
    """Run :func:`_workloads` and return each wrapped kernel's argument types (encoded) that
    Python called it with, in the order they were compiled. A kernel that another compiled
    function also calls is compiled for that caller's types too, when the caller is compiled
    rather than loaded from numba's cache; those are left out, so that the record does not
    depend on what the cache held (a build for them would serve no call), and so is a call
    with an argument :func:`._prebuilt._argument` does not know (no build serves it).

    Numba must compile every call: with the build in use, the calls it serves would never
    reach numba and would be missing (``main`` turns it off; a RuntimeError here)."""
    if _prebuilt._load() is not None:
        raise RuntimeError("record needs numba to compile every kernel, and the kernels built "
                           "ahead of time are in use: run it with VISTRACK_PREBUILT=0")
    called: dict[str, set[Any]] = {}
    original = _prebuilt.Kernel.__call__

    def spy(self: _prebuilt.Kernel, *args: Any) -> Any:
        key = [_prebuilt._argument(a) for a in args]
        seen = called.setdefault(self.key, set())
        if all(k is not None for k in key):
            seen.add(_prebuilt._frozen([_prebuilt._encoded(k) for k in key]))
        return original(self, *args)

    _prebuilt.Kernel.__call__ = spy  # type: ignore[method-assign]
    try:
        _workloads(root)
    finally:
        _prebuilt.Kernel.__call__ = original  # type: ignore[method-assign]
    out: dict[str, list[Any]] = {}
    for key, k in sorted(_prebuilt._REGISTRY.items()):
        if key not in called:
            continue
        sigs = []
        for args in k.jit.nopython_signatures:
            encoded = [encode(t) for t in args.args]
            if _prebuilt._frozen(encoded) not in called[key]:
                continue  # (a callee's types may be literals, which no Python call has)
            if tuple(decode(e) for e in encoded) != tuple(args.args):
                raise TypeError(f"{key}: {args.args} does not survive encoding")
            sigs.append(encoded)
        if sigs:
            out[key] = sigs
    return out


def _forwarder(target: Any, n: int) -> Any:
    """``def f(a0, ..., a{n-1}): return target(a0, ..., a{n-1})``, for export."""
    names = ", ".join(f"a{i}" for i in range(n))
    scope: dict[str, Any] = {"target": target}
    exec(f"def forward({names}):\n    return target({names})\n", scope)  # noqa: S102
    return scope["forward"]


@contextlib.contextmanager
def _own_temporary_folder(parent: Path, prefix: str = ".kernels-tmp-") -> Iterator[Path]:
    """A new folder in ``parent`` (its name starting ``prefix``), the temporary folder of
    this process (``tempfile``) and of the processes it starts (``TMPDIR``) inside the block;
    removed with what it holds after (the test suite's too: ``conftest.py``)."""
    folder = Path(tempfile.mkdtemp(prefix=prefix, dir=parent))
    saved, saved_env = tempfile.tempdir, os.environ.get("TMPDIR")
    tempfile.tempdir = os.environ["TMPDIR"] = str(folder)
    try:
        yield folder
    finally:
        tempfile.tempdir = saved
        if saved_env is None:
            os.environ.pop("TMPDIR", None)
        else:
            os.environ["TMPDIR"] = saved_env
        shutil.rmtree(folder, ignore_errors=True)


def build(out_dir: Path, filename: str | None = None, verbose: bool = False,
          jobs: int | None = None, numba_cache: Path | None = None) -> Path:
    """Compile every kernel of ``_prebuilt.json`` into ``out_dir``: the extension, in ``jobs``
    parts compiled at once in processes of their own (default: the processors this process may
    use, at most 4), one module a part (``_kernels``, ``_kernels_1``, ...), and their build
    information; returns the first part's path. All are written under temporary names and
    renamed into place when complete, the build information last (a running vistrack keeps
    the files it opened).

    To build a kernel, numba first compiles it as on first use, into the numba cache of its
    part's process. With ``numba_cache``, those caches are kept there (replacing what it
    held), with the sources' hash in its file ``sources``: a process that sets
    ``NUMBA_CACHE_DIR`` to a copy of it (:func:`copy_numba_cache`) loads these compilations
    instead of compiling them again (the test suite's processes do)."""
    # the sources as they are imported here, before they are compiled
    info: dict[str, Any] = dict(_prebuilt.machine(), sources=_prebuilt.source_hash())
    spec = json.loads(SIGNATURES.read_text(encoding="utf-8"))["kernels"]
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    jobs = max(1, min(jobs or cpus or 1, 4, len(spec)))
    out_dir.mkdir(parents=True, exist_ok=True)
    # numba's check for a C compiler, made once in each process that builds, leaves a folder of
    # its test files in the temporary folder (numba.pycc.platform._gentmpfile): this build's
    # temporary files, and its parts' processes', go to a folder of its own, removed after
    with _own_temporary_folder(out_dir):
        first = filename or Path(_cc(EXTENSION_NAME).output_file).name
        modules = [EXTENSION_NAME] + [f"{EXTENSION_NAME}_{i}" for i in range(1, jobs)]
        files = _prebuilt.part_files(first, modules)
        # every build its exported name; then the kernels dealt to the parts by module, the
        # modules with the most builds first, each to the part with the fewest builds so far. A
        # kernel's callees are compiled again in every part that calls them, so the box tracker's
        # modules, which share their association kernels, go to one part together.
        items, n = {}, 0
        units: dict[str, list[Any]] = {}
        for key, sigs in spec.items():
            items[key] = [(encoded, f"k{n + i}") for i, encoded in enumerate(sigs)]
            n += len(sigs)
            module = key.partition(":")[0]
            unit = "tracking" if module.startswith(_SHARING) else module
            units.setdefault(unit, []).append((key, items[key]))
        parts: list[list[Any]] = [[] for _ in modules]
        for unit in sorted(units, key=lambda u: -sum(len(b) for _, b in units[u])):
            min(parts, key=lambda p: sum(len(b) for _, b in p)).extend(units[unit])
        info["build_id"] = secrets.randbits(62)
        tmp = Path(tempfile.mkdtemp(prefix=".kernels-", dir=out_dir))
        try:
            jobs_spec = [dict(dir=str(tmp), module=m, file=f, kernels=p, cpu=info["cpu"],
                              build_id=info["build_id"], verbose=verbose)
                         for m, f, p in zip(modules, files, parts)]
            if len(jobs_spec) == 1 and numba_cache is None:
                _build_part(jobs_spec[0])
            else:
                _run_parts(jobs_spec, tmp)
            if numba_cache is not None:
                shutil.rmtree(numba_cache, ignore_errors=True)
                for i in range(len(jobs_spec)):
                    copy_numba_cache(tmp / f"numba{i}", numba_cache)
                (numba_cache / "sources").write_text(info["sources"] + "\n", encoding="utf-8")
            info["parts"] = modules
            info["kernels"] = {key: [[e, name if m == EXTENSION_NAME else f"{m}.{name}"]
                                     for e, name in builds]
                               for m, p in zip(modules, parts) for key, builds in p}
            (tmp / BUILD_INFO).write_text(json.dumps(info, indent=1) + "\n", encoding="utf-8")
            for f in files:
                os.replace(tmp / f, out_dir / f)
            os.replace(tmp / BUILD_INFO, out_dir / BUILD_INFO)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    return out_dir / first


def copy_numba_cache(src: Path, dest: Path) -> int:
    """Copy numba's cache of each function in ``src`` (a ``NUMBA_CACHE_DIR``) into ``dest``,
    its index and code files together, where ``dest`` has none for the function or an older
    index (whose code files are removed first, so that the index copied names only its own);
    returns the number of functions copied. numba checks each index against its source file's
    contents when it loads it."""
    import glob

    n = 0
    for index in sorted(src.rglob("*.nbi")):
        target = dest / index.relative_to(src)
        if target.exists() and target.stat().st_mtime >= index.stat().st_mtime:
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        code = glob.escape(index.name[: -len(".nbi")]) + ".*.nbc"
        for old in target.parent.glob(code):
            old.unlink()
        for data in index.parent.glob(code):
            shutil.copy2(data, target.parent / data.name)
        shutil.copy2(index, target)
        n += 1
    return n


_SHARING = ("vistrack.association.", "vistrack.tracking.", "vistrack.models.box")


def _cc(module: str) -> Any:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # numba.pycc's pending deprecation
        from numba.pycc import CC
    return CC(module)


def _build_part(job: dict[str, Any]) -> None:
    """Compile one part of the extension (a job of :func:`build`) into ``job["dir"]``."""
    cc = _cc(job["module"])
    cc.output_dir = job["dir"]
    cc.output_file = job["file"]
    cc.verbose = job["verbose"]
    cc.target_cpu = job["cpu"]
    # the module and its build information name the same build
    scope: dict[str, Any] = {}
    exec(f"def build_id():\n    return {job['build_id']}\n", scope)  # noqa: S102
    cc.export("build_id", "int64()")(scope["build_id"])
    for key, builds in job["kernels"]:
        jit = _resolve(key)
        for encoded, name in builds:
            args = tuple(decode(e) for e in encoded)
            if args not in jit.overloads:
                jit.compile(args)
            cc.export(name, jit.overloads[args].signature)(_forwarder(jit, len(args)))
    cc.compile()


def _run_parts(jobs: list[dict[str, Any]], tmp: Path) -> None:
    """Each job of :func:`build` in a process of its own, all at once, each with an empty
    numba cache of its own (numba compiles from source, and no two processes write one
    cache); raises if one fails, with its output."""
    import subprocess

    procs = []
    for i, job in enumerate(jobs):
        (tmp / f"part{i}.json").write_text(json.dumps(job), encoding="utf-8")
        (tmp / f"numba{i}").mkdir()
        env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp / f"numba{i}"),
                   PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "vistrack._prebuilt_build", "part", str(tmp / f"part{i}.json")],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True))
    failed = []
    for job, proc in zip(jobs, procs):
        out, _ = proc.communicate()
        if proc.returncode:
            failed.append(f"{job['module']} (exit status {proc.returncode}):\n{out[-2000:]}")
    if failed:
        raise RuntimeError("compiling the kernels failed: " + "\n".join(failed))


EXTENSION_NAME = _prebuilt.EXTENSION.rpartition(".")[2]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m vistrack._prebuilt_build", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("record", help="run the workloads, write _prebuilt.json")
    r.add_argument("--root", type=Path, default=PACKAGE.parent.parent,
                   help="the source tree with examples/ (default: this package's)")
    b = sub.add_parser("build", help="compile the extension")
    where = b.add_mutually_exclusive_group(required=True)
    where.add_argument("--inplace", action="store_true", help="beside this package's sources")
    where.add_argument("--out", type=Path,
                       help=f"the extension's file (its folder gets {BUILD_INFO})")
    b.add_argument("--if-stale", action="store_true",
                   help="do nothing if the extension in place is current")
    b.add_argument("--verbose", action="store_true")
    b.add_argument("--jobs", type=int, default=None,
                   help="parts compiled at once (default: the processors, at most 4)")
    b.add_argument("--numba-cache", type=Path, default=None,
                   help="keep numba's compilations of the kernels in this folder")
    part = sub.add_parser("part", help="compile one part (run by build)")
    part.add_argument("job", type=Path)
    a = p.parse_args(argv)
    if a.command == "part":
        _build_part(json.loads(a.job.read_text(encoding="utf-8")))
        return 0
    if a.command == "record":
        os.environ["VISTRACK_PREBUILT"] = "0"  # numba compiles every call (see record)
        kernels = record(a.root)
        text = json.dumps({"kernels": kernels}, indent=1) + "\n"
        SIGNATURES.write_text(text, encoding="utf-8")
        print(f"{SIGNATURES}: {sum(map(len, kernels.values()))} builds of {len(kernels)} "
              "kernels")
        return 0
    out_dir, filename = (PACKAGE, None) if a.inplace else (a.out.parent, a.out.name)
    if a.if_stale:
        info, why = _prebuilt.built(out_dir)
        if info is not None and not why:
            print(f"{out_dir / BUILD_INFO}: current")
            return 0
    t = time.perf_counter()
    with tempfile.TemporaryDirectory() as cache:
        os.environ["NUMBA_CACHE_DIR"] = cache  # build from source, not from a cache
        path = build(out_dir, filename, verbose=a.verbose, jobs=a.jobs,
                     numba_cache=a.numba_cache)
    print(f"built {path} in {time.perf_counter() - t:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

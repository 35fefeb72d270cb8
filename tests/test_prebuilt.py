"""The kernels compiled ahead of time: in use, complete for vistrack's commands, and equal to
numba's compilation on first use."""

import ast
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from numba import njit
from numba.core import types

from tests.conftest import seed_numba_cache
from vistrack import _prebuilt

ROOT = Path(__file__).resolve().parent.parent


def test_the_kernels_compiled_ahead_of_time_are_in_use():
    # `make test` builds them (setup.py on install, `make kernels` after a change)
    assert _prebuilt.status().startswith("ahead-of-time kernels in use"), _prebuilt.status()


@pytest.mark.slow
def test_vistracks_commands_compile_nothing_on_a_first_run(tmp_path):
    """With numba's and vistrack's caches empty, the workloads of ``_prebuilt_build`` (the
    bundled clip tracked online and offline and by the detector-confidence particle filter, a
    MOTChallenge sequence online and offline, `demo kalman`, `track-one` by each of vistrack's
    methods, the filters, smoothers, particle filters and spot finder of the examples) compile
    only what cannot be compiled ahead of time: the template tracker's multi-threaded
    kernels."""
    script = textwrap.dedent("""
        import sys
        from pathlib import Path
        from numba.core import event
        from vistrack import _prebuilt_build

        depth, compiled = [0], []
        class Listener(event.Listener):
            def on_start(self, ev):
                if depth[0] == 0:
                    d = ev.data["dispatcher"]
                    compiled.append((d.py_func.__module__, d.py_func.__qualname__,
                                     bool(d.targetoptions.get("parallel"))))
                depth[0] += 1
            def on_end(self, ev):
                depth[0] -= 1
        event.register("numba:compile", Listener())
        _prebuilt_build._workloads(Path(sys.argv[1]))
        print(repr(sorted(set(compiled))))
    """)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               VISTRACK_CACHE_DIR=str(tmp_path / "kernels"))
    out = subprocess.run([sys.executable, "-c", script, str(ROOT)], env=env, check=True,
                         capture_output=True, text=True).stdout
    compiled = ast.literal_eval(out.strip().splitlines()[-1])
    for module, name, parallel in compiled:
        assert parallel, (module, name)


def test_the_seeds_linear_models_filter_and_smooth_without_numba_on_a_first_use(tmp_path):
    """A user's first script with the seeds' models (a drifting point, constant velocity and
    acceleration, periodic motion; 1-D and 2-D), each filtered and smoothed, waited up to 8 s for
    numba to compile the one-series filter and the smoother of its state size. With empty
    caches it now runs on the kernels built ahead of time: numba is never imported, so nothing
    can have been compiled. The filter's answer is the closed form of the 1-D drifting point
    (a scalar Kalman recursion written out)."""
    script = textwrap.dedent("""
        import sys
        import numpy as np
        import vistrack as vt
        for kind, dim in ((vt.ConstantPosition, 1), (vt.ConstantPosition, 2),
                          (vt.ConstantVelocity, 1), (vt.ConstantVelocity, 2),
                          (vt.ConstantAcceleration, 1), (vt.ConstantAcceleration, 2),
                          (vt.Periodic, 1), (vt.Periodic, 2)):
            model, meas = kind(dim=dim), vt.Position(dim=dim, r=0.5)
            _, ys = vt.simulate.simulate(model, meas, 20, x0=np.zeros(model.ndim_state), rng=1)
            vt.KalmanFilter(model, meas).smooth(ys)
        ys = np.array([[1.0], [0.5], [2.0]])
        means = vt.KalmanFilter(vt.ConstantPosition(dim=1, q=0.3),
                                vt.Position(dim=1, r=0.5)).filter(ys, x0=[0.0], P0=[[2.0]]).means
        print(repr(means.ravel().tolist()), "numba" in sys.modules)
    """)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               VISTRACK_CACHE_DIR=str(tmp_path / "kernels"))
    out = subprocess.run([sys.executable, "-c", script], env=env, check=True,
                         capture_output=True, text=True).stdout.strip().rsplit(" ", 1)
    x, P, want = 0.0, 2.0, []
    for t, y in enumerate((1.0, 0.5, 2.0)):
        P += 0.3 * (t > 0)  # ConstantPosition's Q(1) = q; no prediction before the first
        k = P / (P + 0.5)
        x, P = x + k * (y - x), (1 - k) * P
        want.append(x)
    np.testing.assert_allclose(ast.literal_eval(out[0]), want, rtol=1e-14)
    assert out[1] == "False"


@pytest.mark.slow
def test_each_build_equals_numbas_compilation_on_first_use(tmp_path):
    """Every kernel call of the workloads, repeated with the numba function itself: the same
    results and the same changes to the arguments, to the bit. Compared in a process of its
    own, as on a first use: nothing the test process compiled or cached before (other tests'
    signatures, under pytest-xdist another order of them) enters the comparison. numba's
    cache holds only what the build itself compiled as on first use, from these sources,
    before it compiled the same code ahead of time (``build/numba-cache``, when the build
    kept it; the comparison is the same without, and numba compiles everything here)."""
    seed_numba_cache(tmp_path / "numba")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               VISTRACK_CACHE_DIR=str(tmp_path / "kernels"))
    compared = _in_a_process("compare_builds_with_numba", env)
    spec = json.loads(_prebuilt.SIGNATURES.read_text())["kernels"]
    # every build was used and compared at least once
    assert int(compared) >= sum(map(len, spec.values()))


def _in_a_process(function: str, env: dict) -> str:
    """The last line ``function()`` of this module prints in a Python process of its own with
    the environment ``env`` (a first use: nothing this process compiled or cached enters)."""
    r = subprocess.run([sys.executable, "-c", f"from tests.test_prebuilt import {function} "
                        "as f; print(f())"], cwd=ROOT, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    return r.stdout.strip().splitlines()[-1]


def compare_builds_with_numba() -> int:
    """The comparison of the test above, in this process: the number of calls compared."""
    from vistrack import _prebuilt_build

    calls: dict = {}
    original = _prebuilt.Kernel.__call__

    def spy(self, *args):
        if len(calls.setdefault(self.key, [])) < 3:
            calls[self.key].append(_copy(args))
        return original(self, *args)

    _prebuilt.Kernel.__call__ = spy
    try:
        _prebuilt_build._workloads(ROOT)
    finally:
        _prebuilt.Kernel.__call__ = original
    spec = json.loads(_prebuilt.SIGNATURES.read_text())["kernels"]
    assert set(calls) >= set(spec), set(spec) - set(calls)
    checked = 0
    for key, arg_lists in calls.items():
        k = _prebuilt._REGISTRY[key]
        for args in arg_lists:
            aot = k._resolve(tuple(_prebuilt._argument(a) for a in args))
            if aot is None:
                continue
            a_args, j_args = _copy(args), _copy(args)
            a_out, j_out = aot(*a_args), k.jit(*j_args)
            _assert_identical(a_out, j_out, key)
            _assert_identical(a_args, j_args, key)
            checked += 1
    return checked


@pytest.mark.slow
def test_the_kalman_kernels_give_the_same_bits_whatever_numba_compiled_before(tmp_path):
    """The Kalman update, filter, smoother and EM kernels, compiled by numba in one process from
    an empty cache, compiled after another process compiled and cached the Cholesky solves they
    call, and built ahead of time: the same bits. (With fused multiply-add allowed, the first two
    differed in the update and EM: the kernel that loaded the solves from the cache could not
    inline them.)"""

    def bits(cache, prebuilt="0"):
        env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / cache),
                   VISTRACK_CACHE_DIR=str(tmp_path / "kernels"), VISTRACK_PREBUILT=prebuilt)
        return ast.literal_eval(_in_a_process("kalman_bits", env))

    solves = textwrap.dedent("""
        import numpy as np
        from vistrack.filters._kernels import chol_solve
        chol_solve(np.zeros((3, 3)), np.eye(3), np.ones((3, 2)), 3, 2)
    """)
    subprocess.run([sys.executable, "-c", solves], cwd=ROOT, check=True,
                   env=dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "solves first")))
    after_solves = bits("solves first")
    # the kernels built ahead of time are numba's compilation from an empty cache, call for
    # call (test_each_build_equals_numbas_compilation_on_first_use): where they are in use
    # they stand for it, and the kernels are compiled from an empty cache once, not twice
    if _prebuilt.status().startswith("ahead-of-time kernels in use"):
        assert after_solves == bits("ahead of time", prebuilt="1")
    else:
        assert after_solves == bits("fresh")


@pytest.mark.slow
def test_the_affine_registration_gives_the_same_bits_compiled_or_loaded(tmp_path):
    """The template and KLT trackers' multi-threaded registration (compiled on first use, not
    ahead of time): the process that compiles it and the next, which loads it from numba's
    cache, give the same bits. With fastmath=True they differed."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               VISTRACK_CACHE_DIR=str(tmp_path / "kernels"))
    assert _in_a_process("registration_bits", env) == _in_a_process("registration_bits", env)


def registration_bits() -> str:
    """A digest of the affine registration of 40 features on a fixed image (the test above)."""
    import hashlib

    from vistrack.tracking import _affine

    rng = np.random.default_rng(0)
    img = (rng.random((120, 160)) * 255 + np.add.outer(np.arange(120), np.arange(160)))
    img = img.astype(np.float32)
    c = rng.uniform(20, 100, size=(40, 2))
    T, SD, Hinv, _ = _affine.prepare_templates(img, c, 7)
    p = np.zeros((40, 6))
    p[:, 4:] = c + rng.normal(0, 0.7, (40, 2))
    rms = _affine.register(img, 7, T, SD, Hinv, p)
    return hashlib.sha256(p.tobytes() + rms.tobytes()).hexdigest()[:16]


def kalman_bits() -> dict[str, str]:
    """Digests of the outputs of the Kalman kernels on fixed data (the test above, in a process
    of its own)."""
    import hashlib

    import vistrack as vt
    from vistrack.filters import _kernels

    rng = np.random.default_rng(0)

    def digest(*arrays):
        return hashlib.sha256(b"".join(np.ascontiguousarray(a).tobytes()
                                       for a in arrays)).hexdigest()[:16]

    out = {}
    for n, m, B in [(4, 2, 3), (4, 2, 20), (6, 3, 2)]:  # one at a time, in chunks; 6 states
        G = rng.normal(size=(B, n, n))
        P = G @ G.transpose(0, 2, 1) + 0.1 * np.eye(n)
        x, y = rng.normal(size=(B, n)), rng.normal(size=(B, m))
        H, R = np.eye(m, n), np.diag(rng.uniform(0.1, 2.0, m))
        out[f"update {n}x{m}x{B}"] = digest(*_kernels.update_batch_py(x, P, y, H, R)[1:])
    cv, pos = vt.ConstantVelocity(dim=2, q=0.3), vt.Position(dim=2, r=0.7)
    model = dict(F=cv.F(1.0), Q=cv.Q(1.0), H=pos.H(4), R=pos.R())
    ys = rng.normal(size=(3, 60, 2)).cumsum(1)
    res = vt.filters.kalman_filter(ys, **model, x0=np.zeros(4), P0=np.eye(4))
    out["filter"] = digest(res.means, res.covs, res.loglik)
    sm = vt.filters.rts_smooth(res, F=model["F"], Q=model["Q"])
    out["smoother"] = digest(sm.means, sm.covs)
    fit = vt.filters.em(ys, **model, x0=np.zeros(4), P0=np.eye(4), max_iter=5)
    out["em"] = digest(fit.Q, fit.R)
    return out


def _copy(x):
    if isinstance(x, np.ndarray):
        c = x.copy()
        c.flags.writeable = x.flags.writeable
        return c
    if isinstance(x, tuple):
        return tuple(_copy(v) for v in x)
    return x


def _assert_identical(a, b, key):
    if isinstance(a, tuple):
        assert isinstance(b, tuple) and len(a) == len(b), key
        for u, v in zip(a, b):
            _assert_identical(u, v, key)
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, key
        assert np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"), key
    else:
        assert a == b or (a != a and b != b), key


def test_other_argument_types_go_to_numba():
    @njit
    def add(a, x):
        a += x
        return a.sum()

    k = _prebuilt.Kernel(add, "tests:add")
    signature = [_prebuilt.encode(types.Array(types.float64, 1, "C")),
                 _prebuilt.encode(types.float64)]
    k._builds = {_prebuilt._frozen(signature): lambda *a: "built"}
    assert k(np.zeros(3), 1.0) == "built"
    # other dtypes, layouts and scalar types: numba's own dispatch (read-only arrays: below)
    assert k(np.zeros(3, np.float32), 1.0) == 3.0
    assert k(np.zeros(6)[::2], 1.0) == 3.0
    assert k(np.zeros(3), 1) == 3.0
    assert k(np.zeros((2, 2)), 1.0) == 4.0
    ro = np.zeros(3)
    ro.flags.writeable = False

    def resolve(*args):
        return k._resolve(tuple(_prebuilt._argument(a) for a in args))

    assert resolve(ro, 1.0) is None and resolve(np.zeros(3), 1.0) is not None
    assert resolve(np.zeros(3), None) is None  # a type the quick check does not know


def test_read_only_arrays_run_the_build_on_copies():
    """A read-only array (a broadcast view, an array its owner made read-only) is not a type the
    kernels are built for: numba compiled the kernel again for it at its first call (the
    Kalman update given a broadcast measurement, 17 s). A kernel does not write to an argument
    it is given read-only, so the build runs on a writeable C-ordered copy, and numba compiles
    nothing. Oracles: the build's answer on the values, and the same bits as the writeable
    array's on the Kalman update."""
    @njit
    def total(a, x):
        return a.sum() * x

    k = _prebuilt.Kernel(total, "tests:total")
    signature = [_prebuilt.encode(types.Array(types.float64, 1, "C")),
                 _prebuilt.encode(types.float64)]
    given = []
    k._builds = {_prebuilt._frozen(signature): lambda a, x: given.append(a.copy()) or -1.0}
    ro = np.arange(3.0)
    ro.flags.writeable = False
    assert k(ro, 2.0) == -1.0 and k(np.broadcast_to(np.array([5.0, 6.0]), (2,)), 1.0) == -1.0
    assert k(np.broadcast_to(7.0, (3,)), 1.0) == -1.0  # (strided: a stride of 0)
    assert [g.tolist() for g in given] == [[0.0, 1.0, 2.0], [5.0, 6.0], [7.0, 7.0, 7.0]]
    assert total.signatures == []
    ro32 = np.arange(3.0, dtype=np.float32)
    ro32.flags.writeable = False
    assert k(ro32, 2.0) == 6.0 and len(total.signatures) == 1  # no build for float32 either

    if not _prebuilt.status().startswith("ahead-of-time kernels in use"):
        return
    import vistrack as vt
    from vistrack.filters import _kernels, kf_update

    g = vt.Gaussian(np.tile([1.0, 2.0, 0.5, -1.0], (3, 1)), np.tile(np.eye(4), (3, 1, 1)))
    H, R = np.eye(2, 4), np.broadcast_to(0.5 * np.eye(2), (2, 2))
    y = np.broadcast_to(np.array([1.5, 1.0]), (3, 2))
    before = list(_kernels.update_batch.signatures)
    got, want = kf_update(g, y, H, R), kf_update(g, y.copy(), H, R.copy())
    assert _kernels.update_batch.signatures == before
    assert got.mean.tobytes() == want.mean.tobytes() and got.cov.tobytes() == want.cov.tobytes()


def _unaligned(n):
    raw = np.zeros(8 * n + 1, np.uint8)
    a = raw[1:].view(np.float64)
    assert not a.flags.aligned
    return a


def _argument_examples():
    ro = np.arange(6.0).reshape(2, 3)
    ro.flags.writeable = False
    rec = np.dtype([("a", "<f8"), ("b", "<i4")])
    packed = np.zeros(3, rec)
    aligned = np.zeros(3, np.dtype([("a", "<f8"), ("b", "<i4")], align=True))
    return [np.zeros(3), np.zeros((2, 3)), np.zeros((2, 3), order="F"), np.zeros((4, 4))[::2],
            np.zeros((3, 1)), np.zeros((1, 3), order="F"), np.zeros(()), ro, _unaligned(3),
            *(np.zeros(2, d) for d in (np.float32, np.int64, np.int32, np.int8, np.uint8,
                                       np.uint64, np.bool_, np.complex128, np.complex64)),
            packed, aligned, packed[["a"]], 1.5, 7, -(2 ** 62), 2 ** 63 - 1, True, False,
            np.float64(2.0), np.float32(2.0), np.int64(3), np.int32(3), np.uint8(3),
            np.bool_(True), np.complex128(1j), (1.0, 2.0), (np.zeros(2), 3, True),
            ((1.0, 2), np.zeros((2, 2)))]


@pytest.mark.parametrize("value", _argument_examples(), ids=lambda v: type(v).__name__)
def test_the_quick_argument_types_are_numbas(value):
    """Read without numba, an argument's type is numba's own (its JSON encoding equal to that
    of numba's typeof), so that the ahead-of-time build is called exactly when numba's
    dispatch would have chosen the same compilation."""
    from numba import typeof
    from numba.core.typing.typeof import Purpose

    key = _prebuilt._argument(value)
    assert key is not None
    assert _prebuilt._encoded(key) == _prebuilt.encode(typeof(value, Purpose.argument))


@pytest.mark.parametrize("value", [None, "s", [1.0], {"a": 1}, 2 ** 63, -(2 ** 63), 1j,
                                   np.zeros(2, ">f8"), np.zeros(2, np.float16),
                                   np.zeros(2, "M8[s]"), np.ma.zeros(2), (1.0, None)],
                         ids=repr)
def test_arguments_the_quick_check_does_not_know_find_no_build(value):
    # left to numba (which may type them, or refuse them), never matched to a build
    key = _prebuilt._argument(value)
    assert key is None or _prebuilt._encoded(key)[1] is None


def test_signatures_recorded_anew_make_a_build_stale(tmp_path, monkeypatch):
    """``_prebuilt.json`` recorded anew (a kernel's arguments of another type) left the
    extension in place current for ``make kernels``' ``--if-stale``, which built nothing: the
    new signature was compiled on first use. The recorded signatures are part of the
    sources' hash."""
    info = dict(_prebuilt.machine(), sources=_prebuilt.source_hash(), kernels={})
    (tmp_path / _prebuilt.BUILD_INFO).write_text(json.dumps(info))
    assert _prebuilt.built(tmp_path)[1] == ""
    other = tmp_path / "_prebuilt.json"
    other.write_bytes(_prebuilt.SIGNATURES.read_bytes() + b" ")
    monkeypatch.setattr(_prebuilt, "SIGNATURES", other)
    assert _prebuilt.built(tmp_path)[1].startswith("built from other sources")


def test_a_build_for_other_sources_or_another_machine_is_not_used(tmp_path, monkeypatch):
    assert _prebuilt.built(tmp_path) == (None, "not built")
    info = dict(_prebuilt.machine(), sources=_prebuilt.source_hash(), kernels={})
    assert info["host"] == _prebuilt.host() != ""
    (tmp_path / _prebuilt.BUILD_INFO).write_text(json.dumps(info))
    assert _prebuilt.built(tmp_path)[1] == ""
    for field, value in [("sources", "0" * 64), ("numba", "0.1"), ("cpu", "i386"),
                         ("features", "-sse2")]:
        # the processor and numba are checked with numba's own answers where the quick
        # check (the operating system's description of both) does not match the build's
        changed = dict(info, **{field: value})
        del changed["host"]
        (tmp_path / _prebuilt.BUILD_INFO).write_text(json.dumps(changed))
        assert _prebuilt.built(tmp_path)[1], field
        changed["host"] = "0" * 64
        (tmp_path / _prebuilt.BUILD_INFO).write_text(json.dumps(changed))
        assert _prebuilt.built(tmp_path)[1], field
    (tmp_path / _prebuilt.BUILD_INFO).write_text(json.dumps(dict(info, host="0" * 64)))
    assert _prebuilt.built(tmp_path)[1] == ""  # another quick answer: numba's agree
    # where the quick check matches, numba is not asked (nor imported)
    monkeypatch.setattr(_prebuilt, "machine", lambda: pytest.fail("numba was asked"))
    (tmp_path / _prebuilt.BUILD_INFO).write_text(json.dumps(info))
    assert _prebuilt.built(tmp_path)[1] == ""
    (tmp_path / _prebuilt.BUILD_INFO).write_text("{")
    assert _prebuilt.built(tmp_path)[1].startswith("build information unreadable")


def test_a_command_served_by_the_build_does_not_import_numba(tmp_path):
    """``vistrack track`` on a MOTChallenge sequence (online and offline) and on the bundled
    clip, and ``vistrack eval``, with the ahead-of-time build in use: numba (0.12-0.2 s to
    import) is never imported."""
    seq = tmp_path / "SEQ"
    (seq / "det").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=SEQ\nframeRate=10\nseqLength=30\n"
                                     "imWidth=640\nimHeight=480\n")
    rows = []
    for f in range(1, 31):
        for i in range(3):
            rows.append(f"{f},-1,{50 + 100 * i + 2 * f},{80 + 20 * i},40,90,0.{9 - i},-1,-1,-1")
    (seq / "det" / "det.txt").write_text("\n".join(rows) + "\n")
    script = textwrap.dedent("""
        import sys
        from vistrack.cli import main
        for argv in sys.argv[1:]:
            assert main(argv.split("|")) == 0, argv
        print("numba imported:", "numba" in sys.modules)
    """)
    clip = ROOT / "src" / "vistrack" / "data" / "pets09-s2l1" / "pets09-s2l1.mp4"
    commands = [f"track|{seq}|--out|{tmp_path / 'a.txt'}",
                f"track|{seq}|--offline|--out|{tmp_path / 'b.txt'}",
                f"eval|--gt|{tmp_path / 'a.txt'}|--pred|{tmp_path / 'b.txt'}",
                f"track|{clip}|--out-dir|{tmp_path / 'clip'}|--stop|40"]
    out = subprocess.run([sys.executable, "-c", script, *commands], check=True,
                         capture_output=True, text=True, cwd=tmp_path).stdout
    assert out.strip().splitlines()[-1] == "numba imported: False"


def test_the_record_keeps_only_the_types_python_called_a_kernel_with(monkeypatch, tmp_path):
    """A kernel that another compiled function calls is compiled for the caller's types too
    (when the caller is compiled, not loaded from numba's cache), literals among them, which
    have no encoding: ``record`` leaves those out, and a kernel no Python call reached, so
    that the record does not depend on what numba's cache held."""
    from vistrack import _prebuilt_build

    @njit
    def inner(x):
        return x * 2.0

    @njit
    def outer(x):
        return inner(x) + inner(3)  # compiles inner for float64 and the literal 3 (callee)

    @njit
    def never(x):
        return x

    monkeypatch.setattr(_prebuilt, "_REGISTRY", {})
    if _prebuilt._load() is not None:  # the build in use: record refuses
        with pytest.raises(RuntimeError, match="run it with VISTRACK_PREBUILT=0"):
            _prebuilt_build.record(tmp_path)
    monkeypatch.setattr(_prebuilt, "_load", lambda: None)
    k = _prebuilt.kernel(inner, key="tests:inner")
    _prebuilt.kernel(never, key="tests:never")
    never(np.zeros(2))  # compiled, but not through its kernel

    def workloads(root):
        assert outer(1.5) == 9.0
        k(np.arange(3.0))
        k(np.zeros((2, 2)))
        k(np.arange(4.0).view(np.ma.MaskedArray))  # a type no build serves (numba decides)

    monkeypatch.setattr(_prebuilt_build, "_workloads", workloads)
    recorded = _prebuilt_build.record(tmp_path)
    assert len(inner.nopython_signatures) == 4  # the callee's two, and Python's two
    arrays = [[_prebuilt.encode(types.Array(types.float64, n, "C"))] for n in (1, 2)]
    assert recorded == {"tests:inner": arrays}


def test_a_ukf_batch_with_a_singular_member_does_not_import_numba():
    """The sigma points of a batch member with no Cholesky factor by LAPACK come from the
    compiled factor, called from Python: served by the build, as the one-Gaussian path's
    calls are (it compiled with numba, about a second, on a build that otherwise never
    imports it)."""
    script = textwrap.dedent("""
        import sys
        import numpy as np
        import vistrack as vt
        from vistrack.filters import UnscentedKalmanFilter
        ukf = UnscentedKalmanFilter(vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1))
        ys = np.stack([np.arange(5.0), -np.arange(5.0)])[..., None]
        P0 = np.stack([np.eye(2), np.ones((2, 2))])  # the second: two states equal
        assert np.isfinite(ukf.filter(ys, x0=[0.0, 0.0], P0=P0).means).all()
        print("numba imported:", "numba" in sys.modules)
    """)
    out = subprocess.run([sys.executable, "-c", script], check=True, capture_output=True,
                         text=True).stdout
    assert out.strip().splitlines()[-1] == "numba imported: False"


def test_the_argument_types_survive_json():
    from numba.np.numpy_support import from_dtype

    from vistrack.tracking.box import _ASSOCIATION

    samples = [types.float64, types.int64, types.boolean, types.int8,
               types.Array(types.float64, 3, "C"), types.Array(types.int32, 2, "A"),
               types.Array(types.float64, 2, "C", readonly=True),
               types.Array(from_dtype(_ASSOCIATION), 1, "C"),
               types.UniTuple(types.int64, 2), types.Tuple((types.float64, types.int64))]
    for t in samples:
        assert _prebuilt.decode(json.loads(json.dumps(_prebuilt.encode(t)))) == t
    spec = json.loads(_prebuilt.SIGNATURES.read_text())["kernels"]
    for sigs in spec.values():
        for sig in sigs:
            assert [_prebuilt.encode(_prebuilt.decode(e)) for e in sig] == sig
    with pytest.raises(TypeError, match="no ahead-of-time build"):
        _prebuilt.encode(types.unicode_type)


def test_an_extension_and_build_information_of_two_builds_are_not_used(tmp_path, monkeypatch):
    import types as pytypes

    info = dict(_prebuilt.machine(), sources=_prebuilt.source_hash(), kernels={}, build_id=7)
    (tmp_path / _prebuilt.BUILD_INFO).write_text(json.dumps(info))
    fake = pytypes.ModuleType(_prebuilt.EXTENSION)
    fake.__file__ = str(tmp_path / "_kernels.so")
    monkeypatch.setattr(_prebuilt.importlib, "import_module", lambda name: fake)
    monkeypatch.setattr(_prebuilt, "_state", {})
    fake.build_id = lambda: 8
    assert _prebuilt._load() is None and "another build" in _prebuilt.status()
    monkeypatch.setattr(_prebuilt, "_state", {})
    fake.build_id = lambda: 7
    assert _prebuilt._load() == (fake, info)
    monkeypatch.setattr(_prebuilt, "_state", {})
    monkeypatch.setenv("VISTRACK_PREBUILT", "0")
    assert _prebuilt._load() is None and "VISTRACK_PREBUILT=0" in _prebuilt.status()


def test_a_build_in_parts_is_used_only_with_every_part_of_the_same_build(tmp_path,
                                                                          monkeypatch):
    """The kernels compiled in parallel come in one module a part; a part missing, or one
    of another build, and none is used."""
    import types as pytypes

    info = dict(_prebuilt.machine(), sources=_prebuilt.source_hash(), build_id=7,
                parts=["_kernels", "_kernels_1"],
                kernels={"tests:add": [[[_prebuilt.encode(types.float64)], "_kernels_1.k0"]]})
    (tmp_path / _prebuilt.BUILD_INFO).write_text(json.dumps(info))
    modules = {}
    for name in info["parts"]:
        m = modules[f"vistrack.{name}"] = pytypes.ModuleType(f"vistrack.{name}")
        m.__file__ = str(tmp_path / f"{name}.so")
        m.build_id = lambda: 7

    real = _prebuilt.importlib.import_module

    def import_module(name, *args):
        if name.startswith("vistrack._kernels"):
            if name not in modules:
                raise ImportError(f"No module named {name!r}")
            return modules[name]
        return real(name, *args)

    monkeypatch.setattr(_prebuilt.importlib, "import_module", import_module)
    modules["vistrack._kernels_1"].k0 = lambda x: ("part 1", x)
    monkeypatch.setattr(_prebuilt, "_state", {})
    assert _prebuilt._load() == (modules["vistrack._kernels"], info)
    k = _prebuilt.Kernel(njit(lambda x: x), "tests:add")
    assert k(2.0) == ("part 1", 2.0) and k(2) == 2  # a float built in part 1; an int: numba
    modules["vistrack._kernels_1"].build_id = lambda: 8
    monkeypatch.setattr(_prebuilt, "_state", {})
    assert _prebuilt._load() is None and "another build" in _prebuilt.status()
    del modules["vistrack._kernels_1"]
    monkeypatch.setattr(_prebuilt, "_state", {})
    assert _prebuilt._load() is None
    assert "part _kernels_1 not built" in _prebuilt.status()


def test_copied_numba_caches_load_each_signature_with_its_own_code(tmp_path):
    """numba's cache of a function copied into another cache directory (as the build's
    compilations are copied for the tests): the copy loads each signature's own code, and
    where the destination held an older cache of the same function for other signatures,
    those are compiled again rather than loaded with another signature's code."""
    from vistrack._prebuilt_build import copy_numba_cache

    (tmp_path / "mod.py").write_text(textwrap.dedent("""
        import sys
        import numpy as np
        from numba import njit

        @njit(cache=True)
        def f(x):
            return x * 2 + 1

        if __name__ == "__main__":
            args = {"int": 3, "float": 3.5, "complex": 1j, "array": np.arange(3.0)}
            got = [f(args[k]) for k in sys.argv[1:]]
            print(repr([np.asarray(g).tolist() for g in got]), f.stats.cache_hits.total(),
                  f.stats.cache_misses.total())
    """))

    def run(cache, *kinds):
        r = subprocess.run([sys.executable, str(tmp_path / "mod.py"), *kinds], cwd=tmp_path,
                           env=dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / cache)),
                           capture_output=True, text=True, check=True)
        values, hits, misses = r.stdout.rsplit(" ", 2)
        return ast.literal_eval(values), int(hits), int(misses)

    want = {"int": 7, "float": 8.0, "complex": 1 + 2j, "array": [1.0, 3.0, 5.0]}
    # an older cache of f for two other signatures in the destination
    assert run("dest", "complex", "array") == ([want["complex"], want["array"]], 0, 2)
    assert run("dest", "complex", "array")[1:] == (2, 0)
    os.utime(next((tmp_path / "dest").rglob("*.nbi")), (1, 1))  # made long before
    assert run("src", "int", "float") == ([want["int"], want["float"]], 0, 2)
    assert copy_numba_cache(tmp_path / "src", tmp_path / "dest") == 1
    assert copy_numba_cache(tmp_path / "src", tmp_path / "dest") == 0  # now as new as the copy
    assert run("dest", "int", "float") == ([want["int"], want["float"]], 2, 0)
    # the destination's own signatures compiled again, with their own results
    assert run("dest", "complex", "array", "int") == (
        [want["complex"], want["array"], want["int"]], 1, 2)


@pytest.mark.slow
def test_a_build_leaves_nothing_in_the_temporary_folder(tmp_path):
    """A build, in one process or in parts, leaves the temporary folder as it found it
    (numba's check for a C compiler leaves a folder there in each process that runs it) and
    its own folders in the output folder removed; two small kernels are built, in one part
    and in two."""
    spec = {key: json.loads(_prebuilt.SIGNATURES.read_text())["kernels"][key]
            for key in ("vistrack.models.box:_size_scaled", "vistrack.tracking.calibration:_pava")}
    (tmp_path / "spec.json").write_text(json.dumps({"kernels": spec}))
    temp = tmp_path / "temp"
    temp.mkdir()
    code = textwrap.dedent(f"""
        from pathlib import Path
        from vistrack import _prebuilt_build as b
        b.SIGNATURES = Path({str(tmp_path / 'spec.json')!r})
        for jobs in (1, 2):
            b.build(Path({str(tmp_path)!r}) / f"out{{jobs}}", jobs=jobs)
    """)
    env = dict(os.environ, TMPDIR=str(temp), NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               VISTRACK_PREBUILT="0")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert sorted(p.name for p in temp.iterdir()) == []
    for jobs in (1, 2):
        built = sorted(p.name for p in (tmp_path / f"out{jobs}").iterdir())
        assert len(built) == jobs + 1 and _prebuilt.BUILD_INFO in built, built

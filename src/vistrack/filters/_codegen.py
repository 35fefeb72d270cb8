"""Batch Kalman kernels generated for the structure of one model. Private.

The per-series batch filter spends its time on small matrix products whose shapes and zero
patterns are fixed by the model: a constant-velocity ``F`` is mostly zeros and ones, and a
position ``H`` only selects. :func:`batch_kernel` writes, for one pattern of zeros and ones in
``F``, ``Q``, ``H`` and ``R``, the filter as straight-line scalar code: every product by a
structural zero is gone, every product by a structural one is a copy, and the covariance is
held as its upper triangle. The other entries are read at run time (per step when they vary),
so one kernel serves every noise level and every ``dt`` but 1 (whose entries are ones).

The series of a chunk are the innermost loop, so LLVM turns each straight-line block into SIMD
code over series. Three things keep it so: the work arrays are rows of one flat array at
constant offsets (separate arrays might alias, and LLVM gives up on the run-time checks for
that many), divisions follow numpy's error model (Python's raises on zero, a branch that stops
vectorisation), and the log-determinant is accumulated as a product, with a log only when the
product leaves [1e-100, 1e100] (a call to ``log`` would not vectorise). The prediction and the
update are two loops rather than one: smaller blocks spill fewer registers, and measured faster.

The equations are those of :mod:`vistrack.filters._kernels`: Cholesky factor of the innovation
covariance ``S``, gains by triangular solves, the Joseph form evaluated as ``AP - W K'``, and
missing components decoupled in ``S`` so that their gain is zero. A dense ``F`` and ``H`` give
the generic kernel for that state and measurement size. As in the one-series kernel, constant
matrices and fully observed steps lead to a steady state: once two fully observed steps leave
every covariance of a chunk unchanged to 8 ulp (each entry of its own scale, the square root of
the product of its two variances), only the means are computed, until a step with a missing
component.

The source of each kernel is written to a file in the user's cache directory
(``$VISTRACK_CACHE_DIR``, else ``$XDG_CACHE_HOME/vistrack/kernels`` or
``~/.cache/vistrack/kernels``) and imported from there, so numba caches its machine code like
that of any other module: a pattern costs its compilation (seconds) once per machine. Since
numba unpickles what it finds there, a folder is used only if it is a directory (not a symbolic
link) owned by the user and not writable by others, below folders that no one else could
replace it in (as ssh's StrictModes: each is owned by the user or root, and not writable by
group or others unless it has the sticky bit, as ``/tmp``); it is created with mode 0o700, and
so are the folders missing above it. An unsafe folder is refused with a warning (then
``vistrack-kernels-{uid}`` in the temporary directory, under the same rule, else a new private
folder for the process, else no cache at all).
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import importlib.util
import math
import os
import shutil
import stat
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

CH = 128  # series per chunk
MAX_N, MAX_M = 6, 3  # larger models: the code, and its compilation time, grow as n² m
# Below this many series-steps the loop kernel of _kernels is used: a new pattern costs some
# seconds of compilation once per machine, which only a large batch repays.
MIN_STEPS = 100_000


def worth_it(n: int, m: int, steps: int) -> bool:
    """Whether a batch of ``steps`` series-steps of this size runs a generated kernel."""
    return n <= MAX_N and m <= MAX_M and steps >= MIN_STEPS


def entry_codes(a: np.ndarray) -> tuple:
    """Per entry of a stack ``(T, r, c)``: 0 if it is zero at every step, 1 if it is one at
    every step, else 2."""
    zero = (a == 0.0).all(axis=0)
    one = (a == 1.0).all(axis=0)
    codes = np.where(zero, 0, np.where(one, 1, 2))
    return tuple(tuple(int(v) for v in row) for row in codes)


def _term(code: int, coef: str, var: str) -> str | None:
    if code == 0:
        return None
    return var if code == 1 else f"{coef} * {var}"


def _sum(terms, empty: str = "0.0") -> str:
    terms = [t for t in terms if t is not None]
    return " + ".join(terms) if terms else empty


def _p(i: int, k: int, name: str = "p") -> str:
    return f"{name}{min(i, k)}_{max(i, k)}"


def _tri(n: int):
    return [(i, k) for i in range(n) for k in range(i, n)]


class _Layout:
    """Where the kernel's work rows live: rows of ``CH`` series (one per ``j``) at constant
    offsets in one flat array ``W``, since separate arrays might alias as far as LLVM knows, and
    it will not emit run-time checks for that many, so it would not vectorise; rows of one
    array need no check. ``w("X", 2)`` is the source of row 2 of the mean ``X`` at series
    ``j``, ``w("Y", "k")`` the row a generated variable ``k`` picks, ``w("LL")`` a single row.

    The rows: the mean ``X`` (``n``), the covariance's upper triangle ``PP``, the prediction
    ``XP`` and ``PPP``, the measurement ``Y`` (``m``), the running log-determinant ``D``, a
    step's ``DS``, the log-likelihood ``LL``, and the steady state's gain and factor ``KL``."""

    def __init__(self, n: int, m: int):
        nt = n * (n + 1) // 2
        self.offsets, o = {}, 0
        for name, nrows in (("X", n), ("PP", nt), ("XP", n), ("PPP", nt), ("Y", m), ("D", 1),
                            ("DS", 1), ("LL", 1), ("KL", n * m + m * (m + 1) // 2)):
            self.offsets[name], o = o, o + nrows

    def __call__(self, name: str, row: int | str | None = None) -> str:
        base = self.offsets[name] * CH
        if row is None:
            return f"W[{base} + j]"
        if isinstance(row, int):
            return f"W[{base + row * CH} + j]"
        return f"W[{base} + ({row}) * {CH} + j]"


def _load(n: int, x: str, p: str, X: str, P: str, w: _Layout) -> list[str]:
    """Read a mean from rows ``X`` into scalars ``x0..`` and an upper triangle from rows ``P``
    into ``p0_0..``."""
    return ([f"{x}{i} = {w(X, i)}" for i in range(n)]
            + [f"{p}{i}_{k} = {w(P, a)}" for a, (i, k) in enumerate(_tri(n))])


def _predict(n, cf, cq, w: _Layout) -> list[str]:
    """Straight-line prediction of one series: reads ``X, PP``, writes ``XP, PPP`` at ``j``."""
    tri = _tri(n)
    L = _load(n, "x", "p", "X", "PP", w)
    for i in range(n):
        L.append(f"{w('XP', i)} = " + _sum(_term(cf[i][l], f"f{i}_{l}", f"x{l}") for l in range(n)))
    for i in range(n):
        for k in range(n):
            fp = _sum(_term(cf[i][l], f"f{i}_{l}", _p(l, k)) for l in range(n))
            L.append(f"fp{i}_{k} = {fp}")
    for a, (i, k) in enumerate(tri):
        terms = [_term(cf[k][l], f"f{k}_{l}", f"fp{i}_{l}") for l in range(n)]
        if cq[i][k]:
            terms.append(f"q{i}_{k}" if cq[i][k] == 2 else "1.0")
        L.append(f"{w('PPP', a)} = " + _sum(terms))
    return L


def _update(n, m, ch, cr, w: _Layout) -> list[str]:
    """Straight-line update of one series: reads ``XP, PPP, Y`` (NaN = missing), writes
    ``X, PP``, the innovation log-density without its log-determinant to ``LL`` and the
    determinant of the Cholesky factor of ``S`` to ``DS``, at ``j``."""
    tri = _tri(n)
    L = _load(n, "xp", "pp", "XP", "PPP", w)
    # innovation e = y - H xp, U = Pp H', S = H U + R
    for k in range(m):
        L.append(f"y{k} = {w('Y', k)}")
        hx = _sum(_term(ch[k][i], f"h{k}_{i}", f"xp{i}") for i in range(n))
        L.append(f"o{k} = 0.0 if math.isnan(y{k}) else 1.0")
        L.append(f"e{k} = (y{k} - ({hx})) if o{k} == 1.0 else 0.0")
    for i in range(n):
        for k in range(m):
            u = _sum(_term(ch[k][l], f"h{k}_{l}", _p(i, l, "pp")) for l in range(n))
            L.append(f"u{i}_{k} = o{k} * ({u})")
    for k, k2 in _tri(m):
        terms = [_term(ch[k][i], f"h{k}_{i}", f"u{i}_{k2}") for i in range(n)]
        if cr[k][k2]:
            terms.append(f"r{k}_{k2}" if cr[k][k2] == 2 else "1.0")
        s = _sum(terms)
        s = f"o{k} * ({s}) + (1.0 - o{k})" if k == k2 else f"o{k} * o{k2} * ({s})"
        L.append(f"s{k}_{k2} = {s}")
    # Cholesky S = L L' (a non-positive pivot is counted and replaced by one)
    for k in range(m):
        d = f"s{k}_{k}" + "".join(f" - l{k}_{p} * l{k}_{p}" for p in range(k))
        L.append(f"d{k} = {d}")
        L.append(f"nbad += not d{k} > 0.0")
        L.append(f"l{k}_{k} = math.sqrt(d{k}) if d{k} > 0.0 else 1.0")
        L.append(f"il{k} = 1.0 / l{k}_{k}")
        for k2 in range(k + 1, m):
            v = f"s{k}_{k2}" + "".join(f" - l{k2}_{p} * l{k}_{p}" for p in range(k))
            L.append(f"l{k2}_{k} = ({v}) * il{k}")
    # gains K = U S^-1 by forward and back substitution, and the whitened innovation
    for i in range(n):
        for k in range(m):
            v = f"u{i}_{k}" + "".join(f" - l{k}_{p} * z{i}_{p}" for p in range(k))
            L.append(f"z{i}_{k} = ({v}) * il{k}")
        for k in range(m - 1, -1, -1):
            v = f"z{i}_{k}" + "".join(f" - l{p}_{k} * k{i}_{p}" for p in range(k + 1, m))
            L.append(f"k{i}_{k} = ({v}) * il{k}")
    for k in range(m):
        v = f"e{k}" + "".join(f" - l{k}_{p} * w{p}" for p in range(k))
        L.append(f"w{k} = ({v}) * il{k}")
    nobs = " + ".join(f"o{k}" for k in range(m))
    L.append(f"{w('LL')} -= 0.5 * (" + " + ".join(f"w{k} * w{k}" for k in range(m))
             + f") + HALF_LOG2PI * ({nobs})")
    L.append(f"{w('DS')} = " + " * ".join(f"l{k}_{k}" for k in range(m)))
    for i in range(n):
        L.append(f"{w('X', i)} = xp{i} + " + _sum(f"k{i}_{k} * e{k}" for k in range(m)))
    # Joseph form (I - K H) Pp (I - K H)' + K R K' = AP - W K' with AP = Pp - K U',
    # W = AP H' - K R
    for i in range(n):
        for l in range(n):
            L.append(f"ap{i}_{l} = {_p(i, l, 'pp')} - ("
                     + _sum(f"k{i}_{k} * u{l}_{k}" for k in range(m)) + ")")
    for i in range(n):
        for k in range(m):
            ha = _sum(_term(ch[k][l], f"h{k}_{l}", f"ap{i}_{l}") for l in range(n))
            rk = _sum(_term(cr[k2][k], f"r{k2}_{k}", f"k{i}_{k2}") for k2 in range(m))
            L.append(f"wk{i}_{k} = {ha} - ({rk})")
    # count the entries of P that moved by more than 8 ulp of their own scale, sqrt(P_ii
    # P_ll) of the last step's P, since the last step (NaN counts as moved: against the
    # largest variance, a small one still converging was frozen far from its limit), and
    # keep the gain and the factor of S for a steady state
    for a, (i, l) in enumerate(tri):
        if i == l:
            L.append(f"sd{i} = math.sqrt(abs({w('PP', a)}))")
    for a, (i, l) in enumerate(tri):
        L.append(f"pn = ap{i}_{l} - (" + _sum(f"wk{i}_{k} * k{l}_{k}" for k in range(m)) + ")")
        L.append(f"nmoved += not abs(pn - {w('PP', a)}) <= 8.0 * EPS * sd{i} * sd{l}")
        L.append(f"{w('PP', a)} = pn")
    for i in range(n):
        for k in range(m):
            L.append(f"{w('KL', i * m + k)} = k{i}_{k}")
    for a, (k, p) in enumerate(_lower(m)):
        L.append(f"{w('KL', n * m + a)} = " + (f"il{k}" if k == p else f"l{k}_{p}"))
    return L


def _lower(m: int):
    return [(k, p) for k in range(m) for p in range(k + 1)]


def _steady(n, m, cf, ch, w: _Layout) -> list[str]:
    """The steady-state step of one series: ``P``, the gain and ``S`` are those of the last
    step (kept in ``KL``), so only the mean moves. Reads ``X, Y``, writes ``X, XP, LL``."""
    L = []
    for i in range(n):
        L.append(f"x{i} = {w('X', i)}")
    for i in range(n):
        L.append(f"xp{i} = " + _sum(_term(cf[i][l], f"f{i}_{l}", f"x{l}") for l in range(n)))
        L.append(f"{w('XP', i)} = xp{i}")
    for k in range(m):
        hx = _sum(_term(ch[k][i], f"h{k}_{i}", f"xp{i}") for i in range(n))
        L.append(f"e{k} = {w('Y', k)} - ({hx})")
    for a, (k, p) in enumerate(_lower(m)):
        L.append(f"{'il' if k == p else 'l'}{k}{'' if k == p else f'_{p}'} = {w('KL', n * m + a)}")
    for k in range(m):
        v = f"e{k}" + "".join(f" - l{k}_{p} * w{p}" for p in range(k))
        L.append(f"w{k} = ({v}) * il{k}")
    L.append(f"{w('LL')} -= 0.5 * (" + " + ".join(f"w{k} * w{k}" for k in range(m))
             + f") + HALF_LOG2PI * {float(m)}")
    for i in range(n):
        L.append(f"{w('X', i)} = xp{i} + " + _sum(f"{w('KL', i * m + k)} * e{k}" for k in range(m)))
    return L


def source(n: int, m: int, cf, cq, ch, cr) -> str:
    """The Python source of the kernel for this pattern (see :func:`batch_kernel`)."""
    tri = _tri(n)
    nt = len(tri)
    w = _Layout(n, m)

    def loads(codes, name, arr, idx, rows, cols, upper=False):
        out = []
        for i in range(rows):
            for k in range(i if upper else 0, cols):
                if codes[i][k] == 2:
                    out.append(f"{name}{i}_{k} = {arr}[{idx}, {i}, {k}]")
        return out

    def loop(body, ind):
        pad = " " * ind
        return [f"{pad}for j in range(c):"] + [pad + "    " + s for s in body]

    src = [
        "import math",
        "import numpy as np",
        "from numba import njit",
        "",
        f"HALF_LOG2PI = {0.5 * math.log(2.0 * math.pi)!r}",
        f"EPS = {float(np.finfo(np.float64).eps)!r}",
        "",
        "",
        "@njit(cache=True, error_model='numpy', fastmath={'contract', 'arcp', 'nsz'})",
        "def kernel(ys, F, Q, H, R, x_init, P_init, means, covs, pmeans, pcovs, loglik, last_P,"
        " store_covs):",
        "    B, T, m = ys.shape",
        f"    W = np.empty({(2 * n + 2 * nt + m + 3 + n * m + m * (m + 1) // 2) * CH})",
        "    bad_t = -1",
        "    constant = max(F.shape[0], Q.shape[0], H.shape[0], R.shape[0]) == 1",
        f"    for b0 in range(0, B, {CH}):",
        f"        c = min({CH}, B - b0)",
        "        for j in range(c):",
        "            bx = b0 + j if x_init.shape[0] > 1 else 0",
        "            bp = b0 + j if P_init.shape[0] > 1 else 0",
    ]
    src += [f"            {w('X', i)} = x_init[bx, {i}]" for i in range(n)]
    src += [f"            {w('PP', a)} = P_init[bp, {i}, {k}]" for a, (i, k) in enumerate(tri)]
    src += [
        f"            {w('LL')} = 0.0",
        f"            {w('D')} = 1.0",
        "        steady = False",
        "        full_before = False",
        "        for t in range(T):",
        "            tf = t if F.shape[0] > 1 else 0",
        "            tq = t if Q.shape[0] > 1 else 0",
        "            th = t if H.shape[0] > 1 else 0",
        "            tr = t if R.shape[0] > 1 else 0",
    ]
    src += ["            " + s for s in loads(cf, "f", "F", "tf", n, n)]
    src += ["            " + s for s in loads(cq, "q", "Q", "tq", n, n, upper=True)]
    src += ["            " + s for s in loads(ch, "h", "H", "th", m, n)]
    src += ["            " + s for s in loads(cr, "r", "R", "tr", m, m)]
    src += [
        "            nnan = 0",
        "            for k in range(m):",
        "                for j in range(c):",
        "                    v = ys[b0 + j, t, k]",
        f"                    {w('Y', 'k')} = v",
        "                    nnan += v != v",
        "            nbad = 0",
        "            nmoved = 0",
        "            if steady and nnan == 0:",
    ]
    src += loop(_steady(n, m, cf, ch, w), 16)
    src += [
        "            else:",
        "                if t == 0:  # no prediction before the first step",
        "                    for j in range(c):",
    ]
    src += [f"                        {w('XP', i)} = {w('X', i)}" for i in range(n)]
    src += [f"                        {w('PPP', a)} = {w('PP', a)}" for a in range(nt)]
    src += ["                else:"]
    src += loop(_predict(n, cf, cq, w), 20)
    src += loop(_update(n, m, ch, cr, w), 16)
    src += [
        "                # steady state: two fully observed steps with constant matrices that",
        "                # left every P of the chunk unchanged to 8 ulp (P does not depend on y)",
        "                steady = (constant and t > 0 and nnan == 0 and full_before",
        "                          and nmoved == 0 and nbad == 0)",
        "                full_before = nnan == 0",
        "            if nbad and bad_t < 0:",
        "                bad_t = t",
        "            # log det L summed as a running product D of the per-step products DS, one",
        "            # log per series when D leaves [1e-100, 1e100] (or DS is extreme); at the end",
        "            nout = 0",
        "            for j in range(c):",
        f"                d = {w('D')} * {w('DS')}",
        "                nout += not (1e-100 < d < 1e100)",
        "            if nout == 0 and t < T - 1:",
        "                for j in range(c):",
        f"                    {w('D')} *= {w('DS')}",
        "            else:",
        "                for j in range(c):",
        f"                    d = {w('D')} * {w('DS')}",
        "                    if 1e-100 < d < 1e100:",
        f"                        {w('D')} = d",
        "                    else:",
        f"                        {w('LL')} -= math.log({w('D')}) + math.log({w('DS')})",
        f"                        {w('D')} = 1.0",
        "                    if t == T - 1:",
        f"                        {w('LL')} -= math.log({w('D')})",
        "            for j in range(c):",
        f"                for i in range({n}):",
        f"                    means[b0 + j, t, i] = {w('X', 'i')}",
        "            if store_covs:",
        "                for j in range(c):",
        f"                    for i in range({n}):",
        f"                        pmeans[b0 + j, t, i] = {w('XP', 'i')}",
    ]
    for a, (i, k) in enumerate(tri):
        src.append(f"                    covs[b0 + j, t, {i}, {k}] = {w('PP', a)}")
        src.append(f"                    pcovs[b0 + j, t, {i}, {k}] = {w('PPP', a)}")
        if i != k:
            src.append(f"                    covs[b0 + j, t, {k}, {i}] = {w('PP', a)}")
            src.append(f"                    pcovs[b0 + j, t, {k}, {i}] = {w('PPP', a)}")
    src += ["        for j in range(c):", f"            loglik[b0 + j] = {w('LL')}"]
    for a, (i, k) in enumerate(tri):
        src.append(f"            last_P[b0 + j, {i}, {k}] = {w('PP', a)}")
        if i != k:
            src.append(f"            last_P[b0 + j, {k}, {i}] = {w('PP', a)}")
    src += ["    return bad_t", ""]
    return "\n".join(src)


def _cache_dir() -> Path:
    base = os.environ.get("VISTRACK_CACHE_DIR")
    if base:
        return Path(base)
    xdg = os.environ.get("XDG_CACHE_HOME")
    root = Path(xdg) if xdg else Path.home() / ".cache"
    return root / "vistrack" / "kernels"


def _uid() -> int | None:
    return os.getuid() if hasattr(os, "getuid") else None


def _unsafe_parents(d: Path) -> str | None:
    """Why a folder above ``d`` would let someone else replace ``d`` (or what holds it), or
    None: as ssh's StrictModes, each existing folder above it must be owned by this user or
    root, and not writable by group or others unless it has the sticky bit (as ``/tmp``,
    where only an entry's owner may rename or delete it). The folders above ``d`` as written
    and above its real path (symbolic links resolved) are checked, nearest first. Not on
    systems without POSIX owners (Windows)."""
    uid = _uid()
    if uid is None:
        return None
    seen = set()
    for path in (Path(os.path.abspath(d)), Path(os.path.realpath(d))):
        for parent in path.parents:
            if parent in seen:
                continue
            seen.add(parent)
            try:
                st = os.stat(parent)
            except (FileNotFoundError, NotADirectoryError):  # made below, mode 0o700
                continue
            if st.st_uid not in (uid, 0):
                return (f"{parent}, a folder above it, belongs to user id {st.st_uid}, neither "
                        f"this user ({uid}) nor root; set VISTRACK_CACHE_DIR to a folder of "
                        "your own")
            if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH) and not st.st_mode & stat.S_ISVTX:
                return (f"others may write to {parent}, a folder above it (mode "
                        f"{stat.S_IMODE(st.st_mode):#o}, no sticky bit), and put another folder "
                        f"in its place; 'chmod go-w {parent}' makes it safe")
    return None


def _unsafe(d: Path) -> str | None:
    """Why the kernel folder ``d`` must not be used, or None if it is safe.

    numba unpickles what it finds beside a kernel's source, so the folder must be a real
    directory (not a symbolic link) that only this user can write to: owned by them, with no
    group or other write permission, below folders that no one else could replace it in
    (:func:`_unsafe_parents`, checked before anything is created). A missing folder is created
    with mode 0o700, as are the missing folders above it. An ``OSError`` (the folder cannot be
    created) propagates."""
    why = _unsafe_parents(d)
    if why is not None:
        return why
    if not os.path.lexists(d):
        for parent in reversed(d.parents):
            if not os.path.lexists(parent):
                try:
                    parent.mkdir(mode=0o700)
                except FileExistsError:  # made meanwhile: the checks below see it
                    pass
        try:
            d.mkdir(mode=0o700)
        except FileExistsError:  # created meanwhile, by this user or another: check it below
            pass
    st = os.lstat(d)
    if stat.S_ISLNK(st.st_mode):
        return "it is a symbolic link"
    if not stat.S_ISDIR(st.st_mode):
        return "it is not a directory"
    uid = _uid()
    if uid is not None and st.st_uid != uid:
        return f"it belongs to user id {st.st_uid}, not to this user ({uid})"
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return f"others may write to it (mode {stat.S_IMODE(st.st_mode):#o})"
    return None


_PRIVATE_DIR: list[Path] = []  # this process's own temporary folder, made when first needed


def _private_dir() -> Path:
    """A fresh folder (mode 0o700) for this process only, removed when it exits."""
    if not _PRIVATE_DIR:
        d = Path(tempfile.mkdtemp(prefix="vistrack-kernels-"))
        atexit.register(shutil.rmtree, d, ignore_errors=True)
        _PRIVATE_DIR.append(d)
    return _PRIVATE_DIR[0]


def _write(path: Path, src: str) -> None:
    """Write ``src`` to ``path`` through a temporary file of a name unique to this call (so
    neither concurrent processes nor threads share one), replaced atomically: a reader never
    sees half a file."""
    with tempfile.NamedTemporaryFile("w", dir=path.parent, prefix=f"{path.stem}.",
                                     suffix=".tmp", delete=False, encoding="utf-8") as f:
        f.write(src)
    try:
        os.replace(f.name, path)
    except OSError:
        Path(f.name).unlink(missing_ok=True)
        raise


def _source_file(name: str, src: str) -> Path | None:
    """The file holding ``src`` in the first usable kernel folder: the cache directory, else
    ``vistrack-kernels-{uid}`` in the temporary directory, else a fresh folder for this process.
    A folder that is unsafe (see :func:`_unsafe`) is refused with a warning; one that cannot be
    written is passed over. None if no folder can be written, or the temporary directory is
    below a folder others could replace it in (the kernels then compile without a cache)."""
    user = _uid() if _uid() is not None else "user"
    shared = [_cache_dir(), Path(tempfile.gettempdir()) / f"vistrack-kernels-{user}"]
    for i, d in enumerate(shared + [None]):
        try:
            if d is None:
                if not _PRIVATE_DIR:
                    # the fresh folder is made in the temporary directory: the folders above it
                    # must be safe too (the temporary directory itself may be /tmp)
                    why = _unsafe_parents(Path(tempfile.gettempdir()) / "vistrack-kernels-")
                    if why is not None:
                        warnings.warn(f"vistrack does not make a kernel folder in "
                                      f"{tempfile.gettempdir()}: {why}; it compiles the kernels "
                                      "without a cache instead", RuntimeWarning, stacklevel=4)
                        return None
                d = _private_dir()
            else:
                why = _unsafe(d)
                if why is not None:
                    warnings.warn(
                        f"vistrack does not use the kernel folder {d}: {why}; "
                        + ("it tries " + str(shared[i + 1]) if i + 1 < len(shared)
                           else "it uses a new temporary folder for this process instead"),
                        RuntimeWarning, stacklevel=4)
                    continue
            p = d / f"{name}.py"
            # compared as bytes: a file damaged into bytes that are not UTF-8 raised
            # UnicodeDecodeError (not an OSError) and stopped the filter; it is rewritten
            if not p.exists() or p.read_bytes() != src.encode("utf-8"):
                _write(p, src)
            return p
        except OSError:
            continue
    return None


@functools.cache
def batch_kernel(n: int, m: int, cf: tuple, cq: tuple, ch: tuple, cr: tuple):
    """The compiled kernel for state size ``n``, measurement size ``m`` and the entry codes
    (see :func:`entry_codes`) of ``F``, ``Q``, ``H``, ``R``.

    ``kernel(ys, F, Q, H, R, x0, P0, means, covs, pmeans, pcovs, loglik, last_P, store_covs)``
    has the arguments and result of :func:`vistrack.filters._kernels.kf_batch` without the gains.
    """
    return load(f"vistrack_kf_{n}_{m}", source(n, m, cf, cq, ch, cr)).kernel


def load(prefix: str, src: str):
    """Import generated source ``src`` as a module, from a file in the cache directory named by
    ``prefix`` and the source's hash (so a changed generator never meets a stale cache), so
    that numba caches the machine code of its ``cache=True`` functions."""
    name = f"{prefix}_{hashlib.sha1(src.encode()).hexdigest()[:16]}"
    path = _source_file(name, src)
    if path is None:  # no writable directory: compile without a cache
        module = type(sys)(name)
        exec(compile(src.replace("cache=True", "cache=False"), name, "exec"), module.__dict__)
        return module
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot load the generated kernel module {path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


Ref = tuple[str, str]
"""A module-level numba function's module and name, as a generated kernel imports it."""


def jit_ref(fn) -> Ref | None:
    """Module and name of a module-level numba function, or None."""
    py = getattr(fn, "py_func", None)
    if py is None or "<locals>" in py.__qualname__:
        return None
    return py.__module__, py.__name__


_HASHES: dict[tuple, str] = {}


def source_hash(*modules: str) -> str:
    """A hash of the source files of ``modules``: part of the generated kernel's source, so
    that numba's cache of it (which tracks its own file only) is rebuilt when a function it
    inlines changes, and part of the key its callers keep the kernel under, so that a
    module changed and reloaded in the same process (a notebook's) gets a kernel of its new
    functions (the old one gave the old model's estimates). Read once per file's version
    (its path, time of change and size)."""
    files = []
    for name in modules:
        spec = importlib.util.find_spec(name)
        if spec is None or not spec.origin:
            continue
        try:
            st = os.stat(spec.origin)
        except OSError:  # (built in, or no file)
            continue
        files.append((spec.origin, st.st_mtime_ns, st.st_size))
    key = tuple(files)
    got = _HASHES.get(key)
    if got is None:
        h = hashlib.sha1()
        for origin, _, _ in files:
            h.update(Path(origin).read_bytes())
        got = _HASHES[key] = h.hexdigest()[:16]
    return got


def generated_kernel(template: str, prefix: str, key: str, modules: tuple[str, ...],
                     **fields: object):
    """The ``run`` function of the source ``template`` formatted with ``fields`` and
    ``depends``, the :func:`source_hash` of ``modules`` (the modules its functions come
    from), loaded by :func:`load` under ``prefix`` and wrapped for calls from Python (and
    its build ahead of time) as ``key`` (:func:`vistrack._prebuilt.kernel`). Kept per
    source hash: a module changed and reloaded gets a kernel of its new functions."""
    return _generated(template, prefix, key, source_hash(*modules),
                      tuple(sorted(fields.items())))


@functools.cache
def _generated(template: str, prefix: str, key: str, depends: str, fields: tuple):
    from .._prebuilt import kernel

    return kernel(load(prefix, template.format(depends=depends, **dict(fields))).run, key)

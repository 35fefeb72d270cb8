"""Kernels compiled when vistrack is installed, so that a first run does not wait for numba.

vistrack's kernels are numba functions. Compiled on first use, the ones a ``vistrack track``
needs take about 30 s on two cores; so installing vistrack from source also compiles, ahead
of time, the kernels its commands call from Python, for the argument types they call them with,
into the extension module :mod:`vistrack._kernels` (``setup.py``; the list of kernels and types
is ``_prebuilt.json``, written by ``python -m vistrack._prebuilt_build record``), compiled in
parts in parallel, one module a part (``_kernels``, ``_kernels_1``, ...).

A :class:`Kernel` stands where Python calls such a numba function. It calls the ahead-of-time
build when the arguments have exactly the numba types it was built for, and numba's dispatcher
otherwise, which compiles (or loads from its cache) as before. Both are numba's compilation of
the same source for the same types and the same processor, so their results are the same; the
extension is used only if it was built

- from the package's current source (a hash of every ``.py`` file in it),
- by the numba version now installed,
- for this machine's processor (its name and features, as numba targets them).

Otherwise, or if it is missing (no C compiler when installing, ``VISTRACK_PREBUILT=0``),
everything is compiled on first use, as before: slower to start, the same results.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import json
import os
import platform
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["Kernel", "kernel", "status", "built", "source_hash"]

EXTENSION = "vistrack._kernels"
"""The extension module the kernels are compiled into."""

PACKAGE = Path(__file__).resolve().parent
SIGNATURES = PACKAGE / "_prebuilt.json"
"""The kernels to build and their argument types (``_prebuilt_build record`` writes it)."""

BUILD_INFO = "_kernels.json"
"""Beside the extension: what it was built from and for (see :func:`_build_info`)."""

_REGISTRY: dict[str, Kernel] = {}
_MISSING = object()
_state: dict[str, Any] = {}


def source_hash() -> str:
    """A hash of every ``.py`` file in the package (paths and contents) and of the kernels'
    recorded signatures (:data:`SIGNATURES`, the builds made): compiled code is current only
    if this has not changed since it was built (a signature recorded anew went unbuilt by
    ``make kernels``, which found the extension current)."""
    h = hashlib.sha256()
    for path in [*sorted(PACKAGE.rglob("*.py")), SIGNATURES]:
        h.update(path.name.encode() if path == SIGNATURES
                 else path.relative_to(PACKAGE).as_posix().encode())
        h.update(b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def machine() -> dict[str, str]:
    """The numba version and the processor numba compiles for here (imports numba), and
    :func:`host`."""
    import llvmlite.binding as llvm
    import numba

    return {"numba": numba.__version__, "cpu": llvm.get_host_cpu_name(),
            "features": llvm.get_host_cpu_features().flatten(), "host": host()}


def host() -> str:
    """A hash of what :func:`machine` depends on, read without importing numba or llvmlite
    (0.15-0.2 s): the processor as the operating system reports it (its model and feature
    flags, from which LLVM's host features are derived) and numba's installed version file.
    "" where that cannot be read (not Linux), and then :func:`machine` decides."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            cpu = f.read().partition("\n\n")[0]  # the first processor's lines
        spec = importlib.util.find_spec("numba")
        version = Path(spec.origin or "").with_name("_version.py").read_bytes()  # type: ignore
    except (OSError, AttributeError, ValueError, ImportError):
        return ""
    lines = [line for line in cpu.splitlines()
             if line.split(":")[0].strip() in ("vendor_id", "cpu family", "model", "model name",
                                               "stepping", "flags")]
    if not lines:
        return ""
    h = hashlib.sha256("\n".join([platform.machine(), *lines]).encode())
    h.update(version)
    return h.hexdigest()


def _stale(info: dict[str, Any]) -> str:
    """Why the build described by ``info`` may not be used here ("" if it may)."""
    if info.get("sources") != source_hash():
        return "built from other sources (rebuild: pip install, or make)"
    quick = host()
    if quick and info.get("host") == quick:
        return ""  # the same processor and numba as the build's, by the quick check
    here = machine()
    if any(info.get(k) != v for k, v in here.items() if k != "host"):
        return "built for another numba version or processor"
    return ""


def part_files(first: str, parts: list[str]) -> list[str]:
    """The file of each part (module names, the first ``_kernels``) of a build whose first
    part's file is ``first`` (``_kernels.cpython-311-x86_64-linux-gnu.so``: ``_kernels_1.cp...``
    for part ``_kernels_1``)."""
    name = EXTENSION.rpartition(".")[2]
    return [first.replace(name, part, 1) for part in parts]


def built(directory: Path = PACKAGE) -> tuple[dict[str, Any] | None, str]:
    """The build information in ``directory`` and why it may not be used ("" if it may),
    without importing the extension."""
    path = directory / BUILD_INFO
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None, "not built"
    except (OSError, ValueError) as e:
        return None, f"build information unreadable ({path}: {e})"
    return info, _stale(info)


def _load() -> tuple[Any, dict[str, Any]] | None:
    """The extension and its build information, if it exists and may be used here (see the
    module); None otherwise, with the reason in :func:`status`."""
    if "loaded" in _state:
        return _state["loaded"]
    loaded, why = None, ""
    if os.environ.get("VISTRACK_PREBUILT", "1") == "0":
        why = "turned off (VISTRACK_PREBUILT=0)"
    else:
        try:
            module = importlib.import_module(EXTENSION)
        except ImportError as e:
            why = f"not built ({e})"
        else:
            info, why = built(Path(module.__file__ or "").parent)
            if info is not None and not why:
                # the kernels were compiled in parts, in parallel: the other parts' modules
                parts = {}
                for name in info.get("parts", [])[1:]:
                    try:
                        parts[name] = importlib.import_module(f"{PACKAGE.name}.{name}")
                    except ImportError as e:
                        why = f"part {name} not built ({e})"
                        break
                else:
                    for m in [module, *parts.values()]:
                        if getattr(m, "build_id", lambda: None)() != info.get("build_id"):
                            why = f"{BUILD_INFO} describes another build than {m.__file__}"
                            break
                    else:
                        loaded = (module, info)
                        _state["parts"] = parts
    _state["loaded"], _state["why"] = loaded, why
    return loaded


def status() -> str:
    """One line: are the ahead-of-time kernels in use, and if not, why."""
    loaded = _load()
    if loaded is None:
        return f"ahead-of-time kernels not used: {_state['why']}"
    n = sum(len(v) for v in loaded[1]["kernels"].values())
    return f"ahead-of-time kernels in use: {n} builds of {len(loaded[1]['kernels'])} kernels"


class Kernel:
    """A numba function called from Python: the ahead-of-time build for the argument types it
    was built for, numba's dispatcher (``jit``) for any other.

    Parameters
    ----------
    jit : numba dispatcher
        The ``@njit`` function.
    key : str
        Its name in ``_prebuilt.json``: ``module:name``, or ``module:factory(args)`` for a
        kernel made by a factory.
    """

    __slots__ = ("jit", "key", "_table", "_builds")

    def __init__(self, jit: Any, key: str) -> None:
        self.jit = jit
        self.key = key
        self._table: dict[tuple[Any, ...], Callable[..., Any] | None] = {}
        self._builds: dict[Any, Callable[..., Any]] | None = None

    def __call__(self, *args: Any) -> Any:
        key = tuple([_argument(a) for a in args])
        fn = self._table.get(key, _MISSING)
        if fn is _MISSING:
            fn = self._resolve(key) or self._through_copies(args, key)
            if len(self._table) < 64:
                self._table[key] = fn
        return (fn or self.jit)(*args)  # type: ignore[operator]

    def _resolve(self, key: tuple[Any, ...]) -> Callable[..., Any] | None:
        """The ahead-of-time build for arguments of these :func:`_argument` types, if there
        is one."""
        if self._builds is None:
            self._builds = {}
            loaded = _load()
            if loaded is not None:
                module, info = loaded
                for encoded, name in info["kernels"].get(self.key, []):
                    part, _, fn = name.rpartition(".")  # "kN" in the first part, "part.kN"
                    self._builds[_frozen(encoded)] = getattr(
                        _state["parts"][part] if part else module, fn)
        if not self._builds or any(k is None for k in key):
            return None  # a type this check does not know: numba decides
        return self._builds.get(_frozen([_encoded(k) for k in key]))

    def _through_copies(self, args: tuple[Any, ...],
                        key: tuple[Any, ...]) -> Callable[..., Any] | None:
        """The build for writeable C-ordered copies of the read-only arrays among ``args`` (a
        broadcast view, an array its owner made read-only), if there is one: numba would compile
        the kernel again for their types, seconds at the first call (the Kalman update's, 17
        s), and a kernel does not write to an argument it is given read-only (numba refuses
        such code). None if no array is read-only or the copies' types have no build either."""
        at = tuple(i for i, a in enumerate(args) if type(a) is np.ndarray
                   and not a.flags.writeable)
        if not at:
            return None
        plain = list(key)
        for i in at:
            plain[i] = _argument(np.empty(args[i].shape, args[i].dtype))  # (a copy's type)
        build = self._resolve(tuple(plain))
        if build is None:
            return None

        def on_copies(*given: Any) -> Any:
            a = list(given)
            for i in at:
                a[i] = np.array(a[i], order="C")
            return build(*a)

        return on_copies

    def __repr__(self) -> str:
        return f"Kernel({self.key})"


def kernel(jit: Any, key: str | None = None) -> Kernel:
    """Wrap the numba function ``jit`` for calls from Python (see :class:`Kernel`); ``key``
    names a kernel made by a factory, ``"module:factory(args)"``."""
    if key is None:
        key = f"{jit.py_func.__module__}:{jit.py_func.__qualname__}"
    k = _REGISTRY.get(key)
    if k is None or k.jit is not jit:
        k = _REGISTRY[key] = Kernel(jit, key)
    return k


# -- argument types to and from JSON -------------------------------------------------------

_INT64 = sys.maxsize > 2 ** 32  # numba types a Python int as intp: int64 on 64-bit builds


def _argument(a: Any) -> Any:
    """What numba's type of ``a`` as an argument depends on, read without numba: a hashable
    key, which :func:`_encoded` turns into the JSON of :func:`encode`; None for a value this
    does not know (then numba types it). The same keys as numba's ``typeof`` (its encoding is
    equal, tests/test_prebuilt.py)."""
    t = type(a)
    if t is np.ndarray:
        # C-contiguous, Fortran-contiguous and writeable: numpy's flag bits 0x1, 0x2, 0x400
        # (numba's type does not depend on the data's alignment)
        return (a.dtype, a.ndim, a.flags.num & 0x403)
    if t is float:
        return "float64"
    if t is bool:
        return "bool"
    if t is int:
        return "int64" if _INT64 and a.bit_length() < 64 else None
    if t is tuple:
        items = tuple([_argument(x) for x in a])
        return None if None in items else ("tuple", items)
    if isinstance(a, np.generic) and t in _SCALARS:
        return _SCALARS[t]
    return None


_SCALARS = {t: np.dtype(t).name for t in (np.float64, np.float32, np.int64, np.int32, np.int16,
                                          np.int8, np.uint64, np.uint32, np.uint16, np.uint8,
                                          np.bool_, np.complex128, np.complex64)}


def _dtype(d: np.dtype) -> Any:
    """A dtype as :func:`encode` writes its numba type; None if numba has no such type or this
    does not know it."""
    if d.fields is not None:
        names = list(d.names or ())
        return ["record", names, [d.fields[n][0].str for n in names],
                [d.fields[n][1] for n in names], d.itemsize, bool(d.isalignedstruct)]
    if d.isnative and d.name in _SCALARS.values():
        return d.name
    return None


def _encoded(k: Any) -> Any:
    """The JSON of :func:`encode` for an :func:`_argument` key."""
    if isinstance(k, str):
        return k
    if k[0] == "tuple":
        return ["tuple", [_encoded(x) for x in k[1]]]
    dtype, ndim, flags = k
    layout = "C" if flags & 0x1 else "F" if flags & 0x2 else "A"
    readonly = not flags & 0x400
    # numba's array type is aligned unless its dtype is a record without C alignment
    aligned = dtype.fields is None or bool(dtype.isalignedstruct)
    return ["array", _dtype(dtype), ndim, layout, bool(readonly), aligned]


def _frozen(e: Any) -> Any:
    """JSON lists as tuples, to be a dictionary's key."""
    return tuple(_frozen(x) for x in e) if isinstance(e, list) else e


def encode(t: Any) -> Any:
    """A numba argument type as JSON (arrays, records, scalars and tuples of them); raises
    TypeError for any other type."""
    from numba.core import types
    from numba.np.numpy_support import as_dtype

    if isinstance(t, types.Array):
        return ["array", encode(t.dtype), t.ndim, t.layout, bool(not t.mutable), bool(t.aligned)]
    if isinstance(t, types.Record):
        d = as_dtype(t)
        fields: dict[str, Any] = dict(d.fields or {})
        return ["record", list(d.names or ()), [fields[n][0].str for n in d.names or ()],
                [fields[n][1] for n in d.names or ()], d.itemsize, bool(t.aligned)]
    if isinstance(t, types.BaseTuple):
        return ["tuple", [encode(x) for x in getattr(t, "types")]]  # noqa: B009
    if isinstance(t, (types.Boolean, types.Integer, types.Float, types.Complex)):
        return str(t)
    raise TypeError(f"no ahead-of-time build for arguments of type {t}")


def decode(e: Any) -> Any:
    """The numba type :func:`encode` wrote."""
    import numpy as np
    from numba.core import types
    from numba.np.numpy_support import from_dtype

    if isinstance(e, str):
        return getattr(types, e)
    kind = e[0]
    if kind == "array":
        _, dtype, ndim, layout, readonly, aligned = e
        return types.Array(decode(dtype), ndim, layout, readonly=readonly, aligned=aligned)
    if kind == "record":
        _, names, formats, offsets, itemsize, aligned = e
        return from_dtype(np.dtype({"names": names, "formats": formats, "offsets": offsets,
                                    "itemsize": itemsize, "aligned": aligned}))
    if kind == "tuple":
        return types.BaseTuple.from_types([decode(x) for x in e[1]])
    raise ValueError(f"unknown type {e!r} in {SIGNATURES}")

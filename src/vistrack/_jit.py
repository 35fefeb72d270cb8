"""numba's decorators, imported only when something is compiled.

Importing numba takes 0.12-0.2 s, more than the rest of ``vistrack track``'s imports together,
yet a command whose kernels were compiled when vistrack was installed (:mod:`vistrack._prebuilt`)
never calls numba. So vistrack's modules decorate with :func:`njit` and :func:`intrinsic` from
here, which keep the Python function and the options and make numba's dispatcher (or intrinsic)
the first time it is needed: the first call not served by the ahead-of-time build, an
attribute of numba's object (``.signatures``, ``.overloads``, ...), or numba typing a function
that calls this one (:attr:`Lazy._numba_type_`, the hook numba's ``typeof`` asks any object for).
From then on each call is the dispatcher's, so results are numba's own.

:func:`on_import` runs a function once numba is imported (by vistrack or anyone).
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable
from typing import Any

__all__ = ["njit", "intrinsic", "Lazy", "on_import", "cancel", "bind", "numba_imported"]

_lock = threading.RLock()
_hooks: list[Callable[[], None]] = []


def numba_imported() -> bool:
    """Whether numba has been imported in this process."""
    return "numba" in sys.modules


def _numba() -> Any:
    import numba

    if _hooks:
        with _lock:
            hooks, _hooks[:] = list(_hooks), []
        for hook in hooks:
            hook()
    return numba


def on_import(hook: Callable[[], None]) -> None:
    """Call ``hook()`` once numba is imported: now if it is, otherwise when one of this module's
    objects first needs it (numba imported by anyone else is noticed then too)."""
    if numba_imported():
        hook()
    else:
        with _lock:
            _hooks.append(hook)


def cancel(hook: Callable[[], None]) -> None:
    """Forget a hook given to :func:`on_import` that has not run yet."""
    with _lock:
        if hook in _hooks:
            _hooks.remove(hook)


class Lazy:
    """A numba object made on first need: see the module. ``py_func`` is the Python function,
    ``real`` numba's object (made by this access)."""

    __slots__ = ("py_func", "_make", "_real", "__dict__")

    def __init__(self, py_func: Callable[..., Any], make: Callable[[Any], Any]) -> None:
        self.py_func = py_func
        self._make = make
        self._real: Any = None
        # what functools.wraps copies, for help() and the documentation
        for name in ("__module__", "__name__", "__qualname__", "__doc__"):
            try:
                setattr(self, name, getattr(py_func, name))
            except AttributeError:  # pragma: no cover - every function has them
                pass
        self.__wrapped__ = py_func

    @property
    def real(self) -> Any:
        real = self._real
        if real is None:
            with _lock:
                if self._real is None:
                    self._real = self._make(_numba())
                real = self._real
        return real

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self.real(*args, **kwargs)

    @property
    def _numba_type_(self) -> Any:
        # numba's typeof asks for this: a compiled function calling this one is typed (and
        # lowered) as calling numba's object, whose type numba's typing context knows
        # (an intrinsic's, unlike a dispatcher's, only by the object itself)
        from numba.core.registry import cpu_target

        real = self.real
        context = cpu_target.typing_context
        context.refresh()  # an intrinsic made since numba last looked is registered then
        return context.resolve_value_type(real)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.real, name)

    def __repr__(self) -> str:
        state = "compiled on first use" if self._real is None else repr(self._real)
        return f"<lazy numba function {self.__qualname__}: {state}>"


def njit(*args: Any, **options: Any) -> Any:
    """``numba.njit``, made on first need: ``@njit``, ``@njit(cache=True, ...)``; a signature
    given as the first argument compiles eagerly, as numba's does, so it imports numba now."""
    if args and callable(args[0]) and not options and len(args) == 1:
        return _lazy(args[0], {})
    if args:
        return _numba().njit(*args, **options)
    return lambda fn: _lazy(fn, options)


def _lazy(fn: Callable[..., Any], options: dict[str, Any]) -> Any:
    return _made(fn, lambda numba: numba.njit(**options)(fn))


def intrinsic(fn: Callable[..., Any]) -> Any:
    """``numba.extending.intrinsic``, made on first need (see :func:`njit`)."""

    def make(numba: Any) -> Any:
        from numba.extending import intrinsic as numbas

        return numbas(fn)

    return _made(fn, make)


def _made(fn: Callable[..., Any], make: Callable[[Any], Any]) -> Any:
    """numba's object ``make(numba)`` now if numba is imported, else a :class:`Lazy`."""
    return make(_numba()) if numba_imported() else Lazy(fn, make)


def bind(namespace: dict[str, Any], **names: str) -> None:
    """Once numba is imported, set each ``namespace[name]`` to ``numba.<attribute>``: a
    module's globals that its compiled functions use by name, as ``prange`` (until then the
    module's own stand-in, ``range``, which is what ``prange`` means in Python)."""

    def hook() -> None:
        import numba

        for name, attribute in names.items():
            namespace[name] = getattr(numba, attribute)

    on_import(hook)

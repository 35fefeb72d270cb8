"""Process pools for many jobs: workers with one BLAS and OpenMP thread each, forked where
that is safe and spawned otherwise.

Shared by :mod:`vistrack.batch` (sequences and videos tracked in parallel) and
:mod:`vistrack.evaluation.files` (results files scored in parallel): the scoring gets its pool
here, not from :mod:`vistrack.batch`, which imports the pipeline, which imports the scoring.
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from concurrent.futures import ProcessPoolExecutor

# concurrent.futures' process pool imports multiprocessing (12-18 ms): imported where a pool is
# made, so that `vistrack track` with one input does not pay for it

__all__ = ["process_pool", "one_thread_here", "default_jobs", "one_line", "message"]

_BLAS_THREADS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
_ONE_THREAD = (*_BLAS_THREADS, "NUMBA_NUM_THREADS")



def frames_text(first: int, last: int) -> str:
    """``frame 4``, or ``frames 4-9``: the frames from ``first`` to ``last``.

    Examples
    --------
    >>> frames_text(6, 6), frames_text(6, 7)
    ('frame 6', 'frames 6-7')
    """
    return f"frame {first}" if first == last else f"frames {first}-{last}"


def counted(count: int, one: str, many: str | None = None) -> str:
    """``count`` and the word, in the singular for 1 (``1 track``, ``2 tracks``, ``1 box``,
    ``2 boxes`` with ``many``).

    Examples
    --------
    >>> counted(1, "box", "boxes"), counted(3, "frame")
    ('1 box', '3 frames')
    """
    return f"{count} {one if count == 1 else many or one + 's'}"

def message(exc: BaseException) -> str:
    """An exception's message on one line; an OS error as ``FILE: what went wrong``, and the
    notes of where it was raised (:func:`vistrack.pipeline.run` adds them) after it.

    Examples
    --------
    >>> message(FileNotFoundError(2, "No such file or directory", "a.txt"))
    'a.txt: No such file or directory'
    >>> message(ValueError("two\\nlines"))
    'two lines'
    >>> message(OSError(28, "No space left on device", "out/.res.000a1b2c3d.partial.txt"))
    'out/res.txt: No space left on device'
    >>> message(OSError(9, "Bad file descriptor", 999))
    '[Errno 9] Bad file descriptor: 999'
    """
    if isinstance(exc, OSError) and exc.strerror and isinstance(exc.filename, str):
        from .io.atomic import final_path

        # an output's partial file is named by the output (a name the user gave); a file
        # descriptor or bytes for a name (os.stat(999)) is said as Python says it (a
        # TypeError hid the error)
        text = f"{final_path(exc.filename)}: {exc.strerror}"
    else:
        text = str(exc) or type(exc).__name__
    notes = getattr(exc, "__notes__", None)  # where it was raised (pipeline.run adds them)
    if isinstance(notes, list) and notes:
        text = f"{text} ({'; '.join(map(str, notes))})"
    return " ".join(line.strip() for line in text.splitlines())


def one_line(e: BaseException) -> str:
    """An error as one line: ``TypeName: its message`` (:func:`message`: with the file an OS
    error names and the notes of where it was raised; white space collapsed)."""
    return f"{type(e).__name__}: {' '.join(message(e).split())}"


def process_pool(workers: int, imports: Sequence[str] = ()) -> ProcessPoolExecutor:
    """A pool of ``workers`` processes, each with one BLAS and OpenMP thread unless the
    environment sets them.

    On Linux, when this process has one thread, the workers are forked from it after it has
    imported ``imports`` (what the jobs run), so that each starts with them loaded, as a
    forked process safely can when no other thread holds a lock. Otherwise (another thread
    running, such as a BLAS pool started with more than one thread; not Linux) they are
    spawned: fresh processes that import what they need. A forked worker is then made like a
    fresh one: SIGTERM acts as Python's default once the job's partial files are removed
    (:func:`_on_sigterm`, in a spawned worker too; or stays ignored if this process ignores
    it), and no compile watch of this process's (:mod:`vistrack._compile`) goes on in it;
    warnings print as this process prints them. Ctrl-C (unless ignored here) stops the job a
    worker runs, as in any process, and is left to the pool between jobs: raised while a
    worker waited on the pool's queues, it could leave a queue's lock held, and the pool hung
    (about 1 in 30 batches given Ctrl-C), or, ending its other workers at once, left their
    outputs under partial names (1-4 in 30).
    """
    import importlib
    import multiprocessing
    import signal
    import sys
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    class _Jobs(ProcessPoolExecutor):
        """Each job run by :func:`_in_job`."""

        def submit(self, fn: Any, /, *args: Any, **kwargs: Any) -> Any:
            return super().submit(_in_job, fn, *args, **kwargs)

    if getattr(multiprocessing.current_process(), "_inheriting", False):
        # a spawned worker importing the script that started it, whose top level asks for a
        # pool again: its workers would be forked (it has one thread) and run the jobs again
        raise RuntimeError(_UNGUARDED)
    fork = sys.platform.startswith("linux") and _one_thread()
    if fork:
        for name in imports:  # before the environment below: this process's own threads
            importlib.import_module(name)
        fork = _one_thread()
    saved = {k: os.environ.get(k) for k in _ONE_THREAD}
    try:
        for k in _ONE_THREAD:
            os.environ.setdefault(k, "1")
        if fork:  # a fresh process's handlers: Python's, or ignored as here
            ign = {s: signal.getsignal(s) == signal.SIG_IGN for s in (signal.SIGINT,
                                                                     signal.SIGTERM)}
            pool = _Jobs(
                workers, mp_context=multiprocessing.get_context("fork"), initializer=_as_fresh,
                initargs=(signal.SIG_IGN if ign[signal.SIGINT] else _on_sigint,
                          signal.SIG_IGN if ign[signal.SIGTERM] else _on_sigterm))
        else:
            pool = _Jobs(workers, mp_context=multiprocessing.get_context("spawn"),
                         initializer=_as_spawned)
        # the processes start at the first submission: start them now, with this environment
        try:
            for f in [pool.submit(os.getpid) for _ in range(workers)]:
                f.result()
        except BrokenProcessPool as e:
            pool.shutdown(wait=True, cancel_futures=True)
            raise RuntimeError("the pool's worker processes ended as they started (their "
                               f"errors are above); {_UNGUARDED}") from e
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return pool


_UNGUARDED = ("a script that starts a process pool (track_many, evaluate_files with jobs) must "
              "guard its top level with `if __name__ == \"__main__\":`, since each spawned "
              "worker imports the script")


def one_thread_here() -> None:
    """Give this process one BLAS and OpenMP thread, as its workers have (unless the
    environment sets them), for a process that only hands out jobs, so that it stays
    single-threaded and :func:`process_pool` can fork its workers. It acts only before numpy
    is first imported: a numpy loaded already keeps the threads it started, and then the
    environment is left as it is."""
    import sys

    if "numpy" not in sys.modules:
        for k in _BLAS_THREADS:
            os.environ.setdefault(k, "1")


def _one_thread(wait: float = 0.02) -> bool:
    """Whether this process has one thread. A thread Python has joined (an earlier pool's)
    can stay in the system's list for a moment after: while Python runs no other thread,
    wait up to ``wait`` seconds for it to go."""
    import threading

    deadline = time.monotonic() + wait
    while (n := _threads()) > 1 and threading.active_count() == 1 \
            and time.monotonic() < deadline:
        time.sleep(0.001)
    return n == 1


def _threads() -> int:
    """This process's threads (Linux's ``/proc/self/stat``; 0 where it cannot be read)."""
    try:
        with open("/proc/self/stat", "rb") as f:
            return int(f.read().rsplit(b")", 1)[1].split()[17])
    except (OSError, ValueError, IndexError):
        return 0


_busy = False  # in a worker: a job of the pool's runs (_in_job)


def _on_sigint(signum: int, frame: Any) -> None:
    """A worker's Ctrl-C: KeyboardInterrupt in the job under way; none between jobs."""
    if _busy:
        raise KeyboardInterrupt


def stop_workers(pool: Any) -> None:
    """Ctrl-C to each worker process of ``pool`` (a process pool of :func:`process_pool`):
    for a stop the workers did not take themselves (SIGTERM sent to this process alone, as
    ``kill PID`` or ``docker stop`` sends it), so that the jobs under way stop, their
    outputs not written (they ran to their end: an hour of video each)."""
    import signal

    for proc in list(getattr(pool, "_processes", {}).values()):
        try:
            os.kill(proc.pid, signal.SIGINT)
        except (ProcessLookupError, PermissionError):
            pass


def _in_job(fn: Any, *args: Any, **kwargs: Any) -> Any:
    """Run a job in a worker, Ctrl-C taken while it runs (:func:`_on_sigint`)."""
    global _busy
    _busy = True
    try:
        return fn(*args, **kwargs)
    finally:
        _busy = False


def _as_spawned() -> None:
    """In a spawned worker: Ctrl-C as :func:`_on_sigint` and SIGTERM as :func:`_on_sigterm`
    (unless ignored)."""
    import signal

    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _on_sigint)
    if signal.getsignal(signal.SIGTERM) == signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _on_sigterm)


def _on_sigterm(signum: int, frame: Any) -> None:
    """SIGTERM in a worker: the partial files of its job removed, then the default action
    (the process ends, as a fresh one would, and the pool sees it die; in a compiled call
    that runs on, once it returns). ``timeout``, ``kill -TERM -PGID`` and a service
    manager's stop send it to every process of the group: each worker's outputs under
    partial names stayed until a later run wrote them. Nothing is imported here: a job
    whose imports the signal came into (a spawned worker's first) has named no partial
    file, and an import in the handler ran into them (a partly imported numpy)."""
    import signal
    import sys

    remove = getattr(sys.modules.get("vistrack.io.atomic"), "remove_partials", None)
    if remove is not None:
        remove()
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    os.kill(os.getpid(), signal.SIGTERM)


def _as_fresh(sigint: Any, sigterm: Any) -> None:
    """In a forked worker: what a fresh process would have. The handlers of Ctrl-C and
    SIGTERM given (the parent's own, such as the command line's SIGTERM, are its own), and
    no compile watch or partial files of the parent's (:func:`_on_sigterm` removes a
    worker's own)."""
    import signal
    import sys

    from . import _compile

    signal.signal(signal.SIGINT, sigint)
    signal.signal(signal.SIGTERM, sigterm)
    _compile.forget()
    # the parent's partial files are its own: a worker's SIGTERM removed them under it (one
    # worker's death has the pool send SIGTERM to the others)
    atomic = sys.modules.get("vistrack.io.atomic")
    if atomic is not None:
        atomic.forget_partials()


def default_jobs() -> int:
    """The cores this process may use."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)  # pragma: no cover - macOS, Windows


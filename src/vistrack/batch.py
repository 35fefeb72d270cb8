"""Many inputs, one call: sequences, benchmark folders and videos tracked in parallel.

:func:`track_many` runs :func:`~vistrack.pipeline.track_sequence` (a sequence's detections)
or :func:`~vistrack.pipeline.track_video` (from pixels) on every input, each in a job of its
own, on a pool of processes (by default one for each core this process may use) or on any
``concurrent.futures``-style executor the caller brings (``executor.submit(fn, *args)``
returning a future): a thread pool, a process pool of its own, or a Dask client's
``client.get_executor()``. vistrack never starts a cluster.

- Each job's results are those of tracking that input alone (the trackers are
  deterministic), written by the worker that computed them, under a partial name renamed
  into place when complete (:mod:`vistrack.io.atomic`).
- A job that fails is reported with its error, one line, and the others go on
  (``keep_going``), or no new job starts after the first failure.
- On the pool it owns, a worker that dies (killed, out of memory) breaks the pool; the jobs
  it ended are run again on a new pool, each alone when several were (which one's worker
  died is not known), and the others not started after them. A job is failed once its
  worker has died ``retries + 1`` times with it running alone, so a job that kills its
  worker each time fails alone, not those beside it. What they wrote is replaced whole, so
  outputs are complete and the same as a run without the failure.
- On a pool or an executor, the largest inputs (by the bytes of their detections file, video
  or images) start first, so that a large one does not start last and run alone; outcomes
  are reported in the inputs' order all the same.
- Each worker uses one thread for BLAS and OpenMP (more threads than cores per worker made a
  batched numpy filter several times slower), unless the environment says otherwise.
"""

from __future__ import annotations

import contextlib
import os
import time
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ._pool import (
    counted,
    default_jobs,
    one_line,
    one_thread_here,
    process_pool,
    stop_workers,
)

if TYPE_CHECKING:
    from concurrent.futures import Executor, Future
    from typing import TextIO

__all__ = ["Job", "Outcome", "is_benchmark", "expand_inputs", "check_distinct", "plan",
           "track_many", "run_jobs", "progress_lines", "process_pool", "one_thread_here"]

_PIPELINE = f"{__package__}.pipeline"  # what the jobs run (_run)


def _is_sequence(path: Path) -> bool:
    return path.is_dir() and (path / "seqinfo.ini").is_file()


def is_benchmark(path: Path) -> bool:
    """Whether ``path`` is a folder of sequence folders (and not a sequence itself)."""
    try:
        return (path.is_dir() and not _is_sequence(path)
                and any(_is_sequence(p) for p in path.iterdir()))
    except OSError:
        return False


def expand_inputs(inputs: Iterable[str | Path], *, reads: str = "both") -> list[Path]:
    """The inputs, each benchmark folder (a folder of sequence folders, each with
    ``seqinfo.ini``) replaced by its sequences, sorted by name; other inputs as given. A
    benchmark folder's sub-folders that hold detections or images but no ``seqinfo.ini`` are
    left out with a warning naming them (given alone, with ``--fps``, they are tracked).
    ``reads`` is what is read of a sequence, for :func:`check_distinct`.

    Raises
    ------
    FileNotFoundError
        If an input does not exist.
    ValueError
        If an input appears twice.
    """
    given = [Path(item) for item in inputs]
    check_distinct(given, reads=reads)  # (a folder given twice was named by its first one)
    out: list[Path] = []
    within: list[Path | None] = []  # each input's folder of sequences, if it came from one
    for item in given:
        path = Path(item)
        if not path.exists():
            raise FileNotFoundError(f"{path} does not exist")
        if is_benchmark(path):
            members = sorted((p for p in path.iterdir() if _is_sequence(p)),
                             key=lambda p: p.name)
            out.extend(members)
            within.extend([path] * len(members))
            left = sorted(p.name for p in path.iterdir() if p.is_dir() and not _is_sequence(p)
                          and ((p / "det" / "det.txt").is_file() or (p / "img1").is_dir()))
            if left:  # (the count said "1 of 1 inputs tracked" without them)
                warnings.warn(f"{path}: {len(left)} folder{'s' * (len(left) > 1)} without "
                              f"seqinfo.ini {'are' if len(left) > 1 else 'is'} no sequence of "
                              f"the set and {'are' if len(left) > 1 else 'is'} left out: "
                              f"{', '.join(left)} (name {'them' if len(left) > 1 else 'it'} "
                              "as inputs, with --fps, to track them)", UserWarning,
                              stacklevel=2)
        else:
            out.append(path)
            within.append(None)
    check_distinct(out, within, reads=reads)
    return out


def check_distinct(paths: Iterable[str | Path],
                   within: Sequence[Path | None] | None = None, *,
                   reads: str = "both") -> None:
    """Check that no two of ``paths`` resolve to the same file or folder, a sequence folder
    counting as what is read of it too (a sequence and its own ``img1/`` are the same frames,
    tracked twice under two names): its detections file and its images' folder (``reads``
    ``"both"``), or the one read, ``"detections"`` or ``"pixels"`` (MOT17's three detectors'
    sequences share one folder of images through links: tracked from their detections they
    are three inputs, and were refused as one given three times). ``within`` gives, for each
    path, the folder of sequences it was found in (or None), which the error names: each was
    given once, one of them as a member of that folder.

    Raises
    ------
    ValueError
        If a path is given twice (two spellings of one path count as one).

    Examples
    --------
    >>> check_distinct(["a", "b"])
    >>> check_distinct(["a", "./a"])
    Traceback (most recent call last):
    ...
    ValueError: a is given twice (as a too)
    """
    if reads not in ("both", "detections", "pixels"):
        raise ValueError(f"reads must be 'both', 'detections' or 'pixels'; got {reads!r}")
    seen: dict[Path, tuple[Path, str, Path | None]] = {}  # what each path is, how, and where
    given = [Path(p) for p in paths]
    if within is not None and len(within) != len(given):
        raise ValueError(f"within must give a folder (or None) for each of the {len(given)} "
                         f"paths; got {len(within)}")
    for p, folder in zip(given, within if within is not None else [None] * len(given)):
        own = {p.resolve(): ""}
        if _is_sequence(p):  # what is read of it: as if given alone
            parts = ([_image_dir(p)] if reads != "detections" else []) + (
                ["det/det.txt"] if reads != "pixels" else [])
            for part in parts:
                own[(p / part).resolve()] = f"{p}/{part}"
        for key, via in own.items():
            if key in seen:
                other, via_other, folder_other = seen[key]
                why = via or via_other
                found = folder or folder_other  # (not both: each folder is given once)
                raise ValueError(f"{p} is given twice (as {other} too"
                                 + (f": {why} is the same input" if why else "")
                                 + (f"; one of them found in the folder of sequences {found}"
                                    if found else "") + ")")
        seen.update({key: (p, via, folder) for key, via in own.items()})


def _image_dir(sequence: Path) -> str:
    """The images' folder a sequence's ``seqinfo.ini`` names (``imDir``; img1 where it names
    none or cannot be read: the reader says what is wrong with it)."""
    from .io.motchallenge import _sequence_section

    try:
        return _sequence_section(sequence)[1].get("imDir", "img1") or "img1"
    except (OSError, ValueError):  # MOTFormatError is one
        return "img1"


@dataclass(frozen=True)
class Job:
    """One input to track: ``kind`` ``"detections"`` (a sequence's detections into the
    results file ``out``) or ``"pixels"`` (a video, image folder or sequence folder from its
    images into the folder ``out``), with the keyword arguments of
    :func:`~vistrack.pipeline.track_sequence` or :func:`~vistrack.pipeline.track_video`."""

    input: Path
    out: Path
    kind: str
    options: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Outcome:
    """How a :class:`Job` went: ``ok``, or ``error`` (one line: the exception's type and
    message); frames, rows and tracks written; seconds of the whole job; ``attempts`` (more
    than 1 if a worker died under it); ``replaced_rate``, an input from pixels' own frame rate
    that ``fps`` was put over (:attr:`~vistrack.pipeline.VideoRun.replaced_rate`)."""

    input: Path
    out: Path
    ok: bool
    frames: int = 0
    rows: int = 0
    tracks: int = 0
    seconds: float = 0.0
    error: str = ""
    attempts: int = 1
    replaced_rate: tuple[str, float] | None = None


def input_label(path: Path) -> str:
    """An input as progress lines and the command line's table name it: its name, a path
    whose name says nothing (``.``, ``..``) as given, and MOTChallenge's ``SEQ/det/det.txt``
    as ``SEQ`` (as its results are named; several such files were each "det.txt").

    Examples
    --------
    >>> input_label(Path("KITTI-13/det/det.txt")), input_label(Path("clip.mp4"))
    ('KITTI-13', 'clip.mp4')
    """
    from .io.motchallenge import _det_file_sequence

    if path.name in ("", ".", ".."):
        return str(path)
    return _det_file_sequence(path) or path.name


def plan(inputs: Iterable[str | Path], out: str | Path, *, kind: str = "detections",
         **options: Any) -> list[Job]:
    """The jobs of :func:`track_many`: each input (benchmark folders expanded,
    :func:`expand_inputs`) to ``out/NAME.txt`` (``"detections"``) or ``out/NAME/``
    (``"pixels"``; a video's name without its suffix).

    With ``"detections"``, an input may also be a detections file alone (``.txt``, ``.csv``),
    or a folder with ``det/det.txt`` and no ``seqinfo.ini``, given the frame rate ``fps``
    (:func:`~vistrack.pipeline.track_sequence`); its results are named as
    :func:`~vistrack.io.motchallenge.sequence_name` names it (``SEQ.txt`` for
    ``SEQ/det/det.txt``).

    Raises
    ------
    ValueError
        If ``kind`` is unknown, with ``"detections"`` an input is not a sequence folder (or,
        given ``fps``, a detections file or a folder with ``det/det.txt``) or a setting's
        value is invalid, two inputs would write to the same place, an input resolves to
        no name to name its outputs after (the root folder), or a file of one input's own
        (``detections``, ``gt``, a ``frontend`` of ``detections:FILE``) is given with
        several inputs.
    TypeError
        With ``"detections"``, if an option is no setting of ``track_sequence``.
    """
    if kind not in ("detections", "pixels"):
        raise ValueError(f"kind must be 'detections' or 'pixels'; got {kind!r}")
    from .io.motchallenge import DETECTION_SUFFIXES, sequence_name

    if kind == "detections":
        # the configuration every job would make, made once here: an unknown option or a bad
        # value is named before any job runs, not once for each input
        import inspect

        from .pipeline import check_fps, resolve_config, track_sequence

        # track_sequence's own options (detections, fps, ...), read from the two signatures
        # rather than listed again here
        run = set(inspect.signature(track_sequence).parameters) - set(
            inspect.signature(resolve_config).parameters)
        resolve_config(**{k: v for k, v in options.items() if k not in run})
        check_fps(options.get("fps"))  # (a bad one failed each job on its own)
    elif options.get("fps") is not None:  # (the same, read from pixels)
        from .io.video import check_rate

        check_rate(options["fps"])

    out = Path(out)
    jobs = []
    for path in expand_inputs(inputs, reads=kind):
        if kind == "detections":
            alone = path.is_file() and path.suffix.lower() in DETECTION_SUFFIXES
            if alone and options.get("fps") is None:
                raise ValueError(f"{path} is a detections file alone: give its frame rate "
                                 "(fps, --fps)")
            if not (alone or _is_sequence(path) or (options.get("fps") is not None and (
                    path / "det" / "det.txt").is_file())):
                raise ValueError(f"{path} is not a MOTChallenge sequence folder (seqinfo.ini, "
                                 "det/det.txt), a detections file (.txt, .csv) nor a folder of "
                                 "sequences")
            target = out / f"{sequence_name(path)}.txt"
        else:  # a video's name without its suffix, a folder's name
            target = out / sequence_name(path)
        jobs.append(Job(path, target, kind, dict(options)))
    if len(jobs) > 1:
        # a file of one input's own, given for all: every sequence was tracked from the one
        # detections file and its results written under its own name (the command line
        # refuses --detections, --gt and --frontend detections:FILE with several inputs)
        own = [k for k in ("detections", "gt") if options.get(k) is not None]
        frontend = options.get("frontend")
        if isinstance(frontend, str) and frontend.startswith("detections:"):
            own.append("frontend")
        if own:
            raise ValueError(f"{own[0]}={options[own[0]]!r} is one input's file, and there "
                             f"are {len(jobs)} inputs: give it with one input (each sequence "
                             "folder holds its own)")
    names: dict[Path, Path] = {}
    for job in jobs:
        if job.out in names:
            # (and said no way out: OTB's sequences each keep their frames in img/)
            raise ValueError(f"{names[job.out]} and {job.input} would both write {job.out} "
                             f"(outputs are named after each input): track them one at a "
                             f"time, each into its own output folder")
        names[job.out] = job.input
    return jobs


def _run(job: Job) -> Outcome:
    """Run one job (in a worker): its outcome, an error caught as one line."""
    from .pipeline import track_sequence, track_video

    t0 = time.perf_counter()
    try:
        if job.kind == "detections":
            run: Any = track_sequence(job.input, job.out, **job.options)
        else:
            run = track_video(job.input, job.out, **job.options)
    except (Exception, SystemExit) as e:  # noqa: BLE001 - reported, the other jobs go on
        # (a sys.exit in a user's tracker or a library ended the whole batch, status 0 and
        # no table)
        return Outcome(job.input, job.out, False, seconds=time.perf_counter() - t0,
                       error=one_line(e) if isinstance(e, Exception)
                       else f"SystemExit: sys.exit({e.code!r}) in the job")
    return Outcome(job.input, job.out, True, frames=run.frames, rows=run.rows,
                   tracks=run.tracks, seconds=time.perf_counter() - t0,
                   replaced_rate=run.replaced_rate)



def _absolute(job: Job) -> Job:
    """``job`` with its input, its output and the options that are paths absolute, as a
    worker of an executor's (Dask's), whose working folder is its own, must be given them:
    relative ones were found, or written, in the worker's folder (an input refused, or
    results written elsewhere while the table said "ok")."""
    def anywhere(key: str, value: Any) -> Any:
        if isinstance(value, os.PathLike):
            return Path(value).absolute()
        if not isinstance(value, str):
            return value
        if key in _PATH_OPTIONS:
            return str(Path(value).absolute())
        kind, colon, path = value.partition(":")
        if key == "frontend" and colon and kind in ("detections", "onnx") and path:
            return f"{kind}:{Path(path).absolute()}"
        return value

    return replace(job, input=job.input.absolute(), out=job.out.absolute(),
                   options={k: anywhere(k, v) for k, v in job.options.items()})


_PATH_OPTIONS = ("detections", "gt", "config")
"""The options of :func:`~vistrack.pipeline.track_sequence` and
:func:`~vistrack.pipeline.track_video` that name a file when given as text (and the
front-ends ``detections:FILE`` and ``onnx:MODEL``)."""


def _size(job: Job) -> int:
    """Bytes of what ``job`` reads, an estimate of its work: the detections file, the video,
    or the images of its folder (``img1/`` of a MOTChallenge sequence); 0 if unreadable."""
    path = job.input
    try:
        if job.kind == "detections" and not path.is_file():
            return Path(job.options.get("detections") or path / "det" / "det.txt").stat().st_size
        if path.is_file():
            return path.stat().st_size
        folder = path / "img1" if (path / "img1").is_dir() else path
        return sum(e.stat().st_size for e in os.scandir(folder) if e.is_file())
    except OSError:
        return 0


def _largest_first(jobs: Sequence[Job], indices: Iterable[int]) -> list[int]:
    """``indices`` of ``jobs``, the largest jobs (:func:`_size`) first, ties in order."""
    return sorted(indices, key=lambda i: -_size(jobs[i]))


def run_jobs(jobs: Sequence[Job], *, workers: int | None = None,
             executor: Executor | None = None, keep_going: bool = True, retries: int = 2,
             on_done: Callable[[Outcome, int, int], None] | None = None) -> list[Outcome]:
    """Run ``jobs`` (see the module); their outcomes in the order of ``jobs``.

    Parameters
    ----------
    jobs : sequence of Job
        What to run.
    workers : int, optional
        Processes of the pool made here (default: the cores this process may use; 1: every
        job in this process, one after the other). Ignored with ``executor``.
    executor : concurrent.futures.Executor, optional
        Where to run the jobs instead (anything with ``submit(fn, *args) -> future``); its
        own failures are reported as the jobs' errors, not retried here.
    keep_going : bool
        After a job fails, run the others (True), or start no new job (False: the jobs not
        started are reported as not run). An ``executor`` is given every job at once, and
        those it has started by the time the failure is seen run to their end (a thread
        pool of one starts the next job as the failed one ends).
    retries : int
        Times a job whose worker died while it ran alone is run again, on a new pool (the
        pool made here only); a death beside other jobs is followed by a run alone.
    on_done : callable, optional
        Called with each outcome as it comes, the number done and the number of jobs.

    Returns
    -------
    list of Outcome
    """
    from concurrent.futures import FIRST_COMPLETED, wait
    from concurrent.futures.process import BrokenProcessPool

    if workers is not None:  # (-1 was the pool's "max_workers must be greater than 0")
        workers = _count(workers, "workers")
    n = len(jobs)
    outcomes: dict[int, Outcome] = {}
    attempts = dict.fromkeys(range(n), 0)
    # the output folders this run makes: one a failed job leaves empty is removed (a worker
    # that died left it behind)
    new = {i for i, job in enumerate(jobs) if not os.path.lexists(job.out)}

    def done(i: int, outcome: Outcome) -> None:
        # (an executor's job ran with its paths absolute: said as planned)
        outcomes[i] = replace(outcome, input=jobs[i].input, out=jobs[i].out,
                              attempts=attempts[i])
        if on_done is not None:
            on_done(outcomes[i], len(outcomes), n)

    def failed(i: int, error: str) -> None:
        if i in new:
            with contextlib.suppress(OSError):  # (not a folder, not empty, or gone)
                os.rmdir(jobs[i].out)
        done(i, Outcome(jobs[i].input, jobs[i].out, False, error=error))

    def stopped() -> bool:
        return not keep_going and any(not o.ok for o in outcomes.values())

    def report_finished(running: dict[Future, int]) -> None:
        # stopped by Ctrl-C or a signal while waiting: the jobs that had finished are said
        # (their outputs are whole) before it goes on; they were lost unsaid. Those the
        # signal stopped in their workers failed of it (numba's "SystemError: ... returned a
        # result with an exception set"): not said as failures of their own
        for f, i in running.items():
            if i not in outcomes and f.done() and not f.cancelled() and f.exception() is None \
                    and f.result().ok:
                done(i, f.result())

    if executor is None and (workers or default_jobs()) == 1:
        for i, job in enumerate(jobs):
            if stopped():
                break
            attempts[i] += 1
            done(i, _run(job))
    elif executor is not None:
        futures = {}
        for i in _largest_first(jobs, range(n)):
            attempts[i] += 1
            futures[executor.submit(_run, _absolute(jobs[i]))] = i
        try:
            for f in _as_done(futures, stopped):
                i = futures[f]
                try:
                    done(i, f.result())
                except Exception as e:  # noqa: BLE001 - the executor's own failure
                    failed(i, f"{type(e).__name__}: {e}")
        except BaseException:
            report_finished(futures)
            raise
    else:
        size = workers or default_jobs()
        pending = _largest_first(jobs, range(n))
        # the jobs under way when a worker died, which took the pool down with them: which
        # one's worker it was is not known, so each is run again alone, on a pool of one,
        # and only a death alone counts against a job (every job beside one that killed its
        # worker each time was failed as if it had killed its own)
        suspects: list[int] = []
        deaths, alone_deaths = dict.fromkeys(range(n), 0), dict.fromkeys(range(n), 0)
        while (pending or suspects) and not stopped():
            alone = bool(suspects)
            width = 1 if alone else size
            queue = list(suspects if alone else pending)
            pool = process_pool(min(width, len(queue)), imports=(_PIPELINE,))
            running: dict[Future, int] = {}
            died: list[int] = []
            broken = False
            try:
                while (queue or running) and not broken:
                    # one job a worker handed to the pool, the rest waiting here: a stop (a
                    # failure, a signal) leaves them unstarted. (Twice as many were handed
                    # over, and those the pool had queued ran after the stop)
                    while queue and len(running) < width and not stopped():
                        i = queue.pop(0)
                        try:
                            f = pool.submit(_run, jobs[i])
                        except BrokenProcessPool:
                            queue.insert(0, i)
                            broken = True
                            break
                        attempts[i] += 1
                        running[f] = i
                    if not running:
                        break
                    finished, _ = wait(running, return_when=FIRST_COMPLETED)
                    for f in finished:
                        i = running.pop(f)
                        try:
                            done(i, f.result())
                        except BrokenProcessPool:
                            died.append(i)
                            broken = True
                        except Exception as e:  # noqa: BLE001 - a job that cannot be sent
                            failed(i, f"{type(e).__name__}: {e}")
                if broken:  # the other jobs under way end with the pool
                    wait(running)
                    for f, i in running.items():
                        error = f.exception()
                        if error is None:
                            done(i, f.result())
                        elif isinstance(error, BrokenProcessPool):
                            died.append(i)
                        else:
                            failed(i, f"{type(error).__name__}: {error}")
            except BaseException as exc:
                # the jobs under way end first (their workers take the signal too: each
                # stops, its output not written, or has just finished and written it whole),
                # then those finished are said. SIGTERM sent to this process alone reached no
                # worker: they are stopped as by Ctrl-C (they ran every job to its end)
                if type(exc).__name__ == "Terminated":
                    stop_workers(pool)
                pool.shutdown(wait=True, cancel_futures=True)
                report_finished(running)
                raise
            finally:
                pool.shutdown(wait=True, cancel_futures=True)
            unstarted = queue if broken else []
            for i in died:
                deaths[i] += 1
            if len(died) > 1:  # died together: not counted; each run again alone
                again = died
            else:
                again = []
                for i in died:
                    alone_deaths[i] += 1
                    if alone_deaths[i] > retries:
                        failed(i, f"its worker died {deaths[i]} times")
                    else:
                        again.append(i)
            if alone:
                suspects = _largest_first(jobs, again + unstarted)
            elif len(died) > 1:
                suspects, pending = _largest_first(jobs, again), _largest_first(jobs, unstarted)
            else:
                pending = _largest_first(jobs, again + unstarted)
    return [outcomes.get(i, Outcome(job.input, job.out, False, attempts=0,
                                    error="not run (another input failed first)"))
            for i, job in enumerate(jobs)]


def _count(value: Any, name: str) -> int:
    """A number of processes, checked (imported here: numpy, which the check imports, may
    start its BLAS threads, and a process with more than one thread spawns its workers
    rather than forking them)."""
    from ._validate import as_whole

    return as_whole(value, name, 1, "processes")


def _as_done(futures: dict[Future, int], stopped: Callable[[], bool]) -> Iterable[Future]:
    """The futures as they finish; once ``stopped()``, the ones not started are cancelled."""
    from concurrent.futures import FIRST_COMPLETED, wait

    left = set(futures)
    while left:
        finished, left = wait(left, return_when=FIRST_COMPLETED)
        yield from finished
        if stopped():
            left = {f for f in left if not f.cancel()}


def track_many(inputs: Iterable[str | Path], out: str | Path, *, kind: str = "detections",
               jobs: int | None = None, executor: Executor | None = None,
               keep_going: bool = True, retries: int = 2, progress: TextIO | None = None,
               **options: Any) -> list[Outcome]:
    """Track every input, in parallel (see the module).

    Parameters
    ----------
    inputs : iterable of str or Path
        Sequence folders, benchmark folders (folders of sequences) and, with ``kind``
        ``"pixels"``, videos and image folders.
    out : str or Path
        The folder written: ``out/NAME.txt`` for each sequence's results (``"detections"``),
        ``out/NAME/`` for each input's outputs (``"pixels"``).
    kind : {"detections", "pixels"}
        Track each sequence's detections (:func:`~vistrack.pipeline.track_sequence`), or
        each input from its images (:func:`~vistrack.pipeline.track_video`).
    jobs, executor, keep_going, retries
        As :func:`run_jobs` (``jobs`` is its ``workers``).
    progress : TextIO, optional
        Where to write a line as each input is done.
    **options
        Keyword arguments of ``track_sequence`` or ``track_video`` (``config``, ``force``,
        ``offline``, ``frontend``, ...), the same for every input.

    Returns
    -------
    list of Outcome
        One for each input, in order.

    Examples
    --------
    >>> import tempfile
    >>> root = Path(tempfile.mkdtemp())
    >>> for name in ("A", "B"):
    ...     seq = root / "bench" / name
    ...     (seq / "det").mkdir(parents=True)
    ...     _ = (seq / "seqinfo.ini").write_text(f"[Sequence]\\nname={name}\\nframeRate=10\\n"
    ...                                          "seqLength=3\\nimWidth=320\\nimHeight=240\\n")
    ...     _ = (seq / "det" / "det.txt").write_text(
    ...         "".join(f"{f},-1,{10 + 5 * f},20,30,60,0.9\\n" for f in range(1, 4)))
    >>> [(o.input.name, o.ok, o.rows) for o in track_many([root / "bench"], root / "out",
    ...                                                    jobs=1)]
    [('A', True, 3), ('B', True, 3)]
    """
    if jobs is not None:  # (0 was taken as every core, which --jobs refuses)
        jobs = _count(jobs, "jobs")
    planned = plan(inputs, out, kind=kind, **options)
    try:
        return run_jobs(planned, workers=jobs, executor=executor, keep_going=keep_going,
                        retries=retries, on_done=progress_lines(progress, len(planned)))
    finally:
        if progress is not None and getattr(progress, "isatty", lambda: False)():
            # the bar cleared: it stayed where inputs were left unrun after a failure, or
            # an interrupt came, and the caller's next words ran on after it
            progress.write("\r\x1b[K")
            progress.flush()


def progress_lines(stream: TextIO | None,
                   total: int | None = None) -> Callable[[Outcome, int, int], None] | None:
    """An ``on_done`` for :func:`run_jobs` writing ``[k/n] NAME: ...`` to ``stream`` as each
    job is done (None: nothing). On a terminal, a bar under those lines shows how many inputs
    are done, how many failed, the time so far and an estimate of the time left; it is drawn
    at once, for ``total`` inputs, if given, and cleared when the last input is done."""
    if stream is None:
        return None
    bar = bool(getattr(stream, "isatty", lambda: False)())
    t0 = time.monotonic()
    failed = 0

    def draw(k: int, n: int) -> None:
        width = 24
        full = width * k // n if n else width
        elapsed = time.monotonic() - t0
        left = f", about {elapsed / k * (n - k):.0f} s left" if 0 < k < n else ""
        bad = f", {failed} failed" if failed else ""
        stream.write(f"[{'#' * full}{'-' * (width - full)}] {k}/{n} inputs{bad}, "
                     f"{elapsed:.0f} s{left}")
        stream.flush()

    def report(o: Outcome, k: int, n: int) -> None:
        nonlocal failed
        failed += not o.ok
        what = (f"{counted(o.frames, 'frame')}, {counted(o.tracks, 'track')}, "
                f"{o.seconds:.1f} s" if o.ok else
                f"failed: {o.error}")
        line = f"[{k}/{n}] {input_label(o.input)}: {what}"
        if not bar:
            # one write for the line and its newline: print's two let a worker's warning,
            # written to the same stderr unbuffered (python -u), fall between them
            stream.write(line + "\n")
            stream.flush()
            return
        stream.write(f"\r\x1b[K{line}\n")  # the bar's line cleared, the line, the bar again
        if k < n:
            draw(k, n)
        else:
            stream.flush()

    if bar and total:
        draw(0, total)
    return report

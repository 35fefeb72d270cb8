"""Outputs written whole or not at all: each is written under a partial name beside it and
renamed over the real name only when complete, so that an interrupted or failed run leaves
the file of an earlier run as it was."""

from __future__ import annotations

import contextlib
import contextvars
import errno
import itertools
import os
import re
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any

__all__ = ["partial_path", "replacing", "open_replacing", "PartialFile", "check_output",
           "check_place", "check_not_input", "Input", "made_folder", "together",
           "remove_on_commit", "staging"]


_NAME_MAX = 255
"""The longest file name (bytes) most file systems take."""


def hidden_path(path: str | os.PathLike, tail: str) -> Path:
    """A hidden name beside ``path``, ``.{stem}.{token}.{tail}``, its token new at each call
    (this process's id in 6 hex digits, then 4 of a count this process keeps, from a random
    start): two runs (or two writers) given the same output never share one, and one left by
    a writer that died (SIGKILL, a worker killed) is removed when another completes the
    output (:func:`commit_partial`). A stem too long for the file system with the rest is
    cut, a hash of it kept (the name fits in 255 bytes).

    Examples
    --------
    >>> names = {hidden_path("out/tracks.txt", "partial.txt") for _ in range(16**4)}
    >>> len(names)  # a process's 65,536 names in a row all differ
    65536
    """
    p = Path(path)
    return p.with_name(f"{_hidden_prefix(p, tail)}{os.getpid() % 16**6:06x}"
                       f"{next(_COUNT) % 16**4:04x}.{tail}")


_COUNT = itertools.count(int.from_bytes(os.urandom(2), "big"))
"""The count that :func:`hidden_path`'s tokens end in, from a random start (another process,
or one given the same id later, starts elsewhere; ``os.urandom``, where ``secrets`` costs 3
ms an import on every command's start). Four random hex digits at each call repeated one
another about 8 times in 1,000 names of one process, and two writers of one output in one
process could meet; ``next`` on a count is atomic, so threads never share a value."""


def _hidden_prefix(p: Path, tail: str) -> str:
    """``.{stem}.`` of :func:`hidden_path`'s names for ``p`` and ``tail``, the stem cut to
    fit (its hash kept) where the whole name would pass 255 bytes."""
    stem = p.stem
    room = _NAME_MAX - len(f"..{'0' * _TOKEN}.{tail}".encode())
    if len(stem.encode()) > room:
        import hashlib

        digest = hashlib.sha1(stem.encode()).hexdigest()[:8]
        stem = stem.encode()[:max(room - 9, 0)].decode(errors="ignore") + "~" + digest
    return f".{stem}."


_TOKEN = 10
"""The length of a hidden name's token: the writer's process id (6 hex digits) and 4 random
hex digits."""


_GROUP: contextvars.ContextVar[list[tuple[Path | None, Path]] | None] = contextvars.ContextVar(
    "vistrack_atomic_group", default=None)


@contextlib.contextmanager
def together() -> Iterator[None]:
    """Outputs completed inside the block (:func:`commit_partial`, so every writer of this
    module) are renamed into place together when it ends normally, with Ctrl-C and SIGTERM
    held off while they are; when it raises, none is, their partial files are removed, and
    the earlier outputs stay as they were, every one. A run's files then describe one run:
    they were renamed one at a time as each closed, and Ctrl-C between two left new tracks
    beside an earlier run's video, plot and ``run.json``. Inside another such block, the
    outer one renames them.

    Examples
    --------
    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> _ = (out / "a.txt").write_text("earlier"); _ = (out / "b.txt").write_text("earlier")
    >>> try:
    ...     with together():
    ...         with replacing(out / "a.txt") as part:
    ...             _ = part.write_text("new")
    ...         raise KeyboardInterrupt  # before b.txt was written
    ... except KeyboardInterrupt:
    ...     pass
    >>> [(p.name, p.read_text()) for p in sorted(out.iterdir())]
    [('a.txt', 'earlier'), ('b.txt', 'earlier')]
    """
    if _GROUP.get() is not None:
        yield
        return
    pending: list[tuple[Path | None, Path]] = []
    token = _GROUP.set(pending)
    try:
        yield
    except BaseException:
        for part, _ in pending:
            if part is not None:
                part.unlink(missing_ok=True)
        raise
    finally:
        _GROUP.reset(token)
    _apply(pending)


def remove_on_commit(path: str | os.PathLike) -> None:
    """Remove ``path`` (if there) where the outputs of :func:`together`'s block are renamed
    into place, or now outside such a block: a file that would describe an earlier run."""
    group = _GROUP.get()
    if group is None:
        Path(path).unlink(missing_ok=True)
    else:
        group.append((None, Path(path)))


def _apply(pending: list[tuple[Path | None, Path]]) -> None:
    """The renames (and removals) of a group, with SIGINT and SIGTERM held off (delivered
    after) where this is the main thread; a rename that fails removes the partial files not
    yet renamed.

    They are held off by handlers of Python's that note them, for Python runs every signal's
    handler in the main thread whichever thread the system hands it to: a mask of this
    thread's (``pthread_sigmask``) left the signal to the process's other threads (decoding,
    numba's), and Ctrl-C between two renames left new tracks beside an earlier run's video."""
    import signal
    import threading

    held: list[int] = []
    saved: dict[int, Any] = {}
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            old = signal.getsignal(sig)
            if old is not None:  # (a handler set outside Python cannot be put back)
                saved[sig] = old
                signal.signal(sig, lambda number, _frame: held.append(number))
    try:
        for k, (part, path) in enumerate(pending):
            try:
                if part is None:
                    path.unlink(missing_ok=True)
                else:
                    _rename(part, path)
            except BaseException:
                for rest, _ in pending[k:]:
                    if rest is not None:
                        rest.unlink(missing_ok=True)
                raise
    finally:
        for number, handler in saved.items():
            signal.signal(number, handler)
        if held:  # delivered now, to the handlers put back (over a rename's error too)
            signal.raise_signal(held[0])


def commit_partial(part: Path, path: Path) -> None:
    """Rename the complete partial file ``part`` over ``path`` (inside :func:`together`'s
    block, when the block ends), then remove the partial files (:func:`partial_path`) of
    ``path`` that writers which died left (their process no longer exists: killed before it
    could remove its own), as the shared partial name used to be overwritten by the next
    run."""
    group = _GROUP.get()
    if group is not None:
        group.append((part, path))
        return
    _rename(part, path)


def _rename(part: Path, path: Path) -> None:
    """:func:`commit_partial`'s rename and sweep."""
    import glob

    os.replace(part, path)
    _NAMED.discard(part)
    for tail in (f"partial{path.suffix}", STAGING_TAIL):
        prefix = _hidden_prefix(path, tail)
        for other in path.parent.glob(f"{glob.escape(prefix)}*.{glob.escape(tail)}"):
            token = other.name[len(prefix):-len(tail) - 1]
            if len(token) != _TOKEN or not re.fullmatch(r"[0-9a-f]+", token):
                continue
            pid = int(token[:6], 16)
            if pid != os.getpid() % 16**6 and not _alive(pid):
                other.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    """Whether a process ``pid`` exists (one of another user's counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


def final_path(path: str | os.PathLike) -> str:
    """The output a partial file (:func:`partial_path`) is written for, or ``path`` as given
    when it is no partial file, or one whose stem was cut to fit.

    Examples
    --------
    >>> final_path("out/.tracks.00a1b2c3d4.partial.txt"), final_path("out/tracks.txt")
    ('out/tracks.txt', 'out/tracks.txt')
    """
    p = Path(path)
    m = re.fullmatch(r"\.(.+)\.[0-9a-f]{10}\.partial(\.[^.]*)?", p.name)
    if m is None or "~" in m.group(1):
        return str(path)
    return str(p.with_name(m.group(1) + (m.group(2) or "")))


def partial_path(path: str | os.PathLike) -> Path:
    """Where ``path`` is written until it is complete: a hidden name in the same folder with
    the same suffix (a video writer picks its container by the suffix),
    ``.{stem}.{token}.partial{suffix}``, new at each call (two runs writing one output each
    write their own and the last rename wins, where a shared one mixed their rows), and
    within 255 bytes however long ``path``'s name (:func:`hidden_path`).

    Examples
    --------
    >>> a, b = partial_path("out/tracks.txt"), partial_path("out/tracks.txt")
    >>> a.parent.name, a.name.startswith(".tracks."), a.name.endswith(".partial.txt"), a != b
    ('out', True, True, True)
    >>> len(partial_path("r" * 251 + ".txt").name.encode())
    255
    """
    p = Path(path)
    part = hidden_path(p, f"partial{p.suffix}")
    if len(_NAMED) >= 1024:  # (those given up without a rename: the files no longer there)
        _NAMED.difference_update([q for q in _NAMED if not q.exists()])
    _NAMED.add(part)
    return part


_NAMED: set[Path] = set()
"""The partial and staging files this process has named and not yet renamed over their
outputs or removed."""

_MADE: list[list[Path]] = []
"""The folders made for the blocks under way (:func:`made_folder`, :func:`replacing`), each
block's outermost first: a block that ends by SIGTERM's default action in a worker cannot
remove them (:func:`remove_partials` does)."""


STAGING_TAIL = "rows.txt"
"""The tail of :func:`staging`'s hidden names."""


@contextlib.contextmanager
def staging(path: str | os.PathLike) -> Iterator[Path]:
    """A hidden file beside ``path`` (:func:`hidden_path`, tail :data:`STAGING_TAIL`) for the
    writer of ``path`` to build it from: removed when the block ends, however it ends; by
    :func:`remove_partials` when a worker is stopped with SIGTERM inside the block; and, left
    by a writer that died, when another completes ``path`` (:func:`commit_partial`).

    Examples
    --------
    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp()) / "tracks.csv"
    >>> with staging(out) as rows:
    ...     _ = rows.write_text("1,1,0,0,1,1,1,-1,-1,-1\\n")
    ...     rows.name.startswith(".tracks.") and rows.name.endswith(".rows.txt")
    True
    >>> rows.exists()
    False
    """
    part = hidden_path(path, STAGING_TAIL)
    _NAMED.add(part)
    try:
        yield part
    finally:
        part.unlink(missing_ok=True)
        _NAMED.discard(part)


def forget_partials() -> None:
    """Forget the partial files named so far, and the folders made for blocks under way: in
    a forked process, they are its parent's."""
    _NAMED.clear()
    _MADE.clear()


def remove_partials() -> None:
    """Remove the partial and staging files this process has named that are still there:
    what a job stopped by SIGTERM in a worker leaves (the default action ends the process at
    once, and its partial files stayed until a later run wrote the same outputs); then the
    folders made for the blocks under way, where empty."""
    for part in list(_NAMED):
        try:
            part.unlink()
        except OSError:  # (never made, already renamed, or a folder)
            pass
    _NAMED.clear()
    # and the folders made for them, where empty now (a batch terminated by SIGTERM left
    # its inputs' new folders, empty, after saying "nothing was written")
    for made in reversed(_MADE):
        _remove_empty(made)


def _make_folder(path: Path) -> list[Path]:
    """Make the folder ``path`` and its missing parents; the folders made, outermost first."""
    made, p = [], path
    while not p.exists() and p != p.parent:
        made.append(p)
        p = p.parent
    path.mkdir(parents=True, exist_ok=True)
    return made[::-1]


def _forget(made: list[Path]) -> None:
    """Take a block's folders off :data:`_MADE` (that list object, not an equal one)."""
    for k in range(len(_MADE) - 1, -1, -1):
        if _MADE[k] is made:
            del _MADE[k]
            return


def _remove_empty(made: list[Path]) -> None:
    """Remove the folders ``made`` (outermost first) that are empty, innermost first."""
    for p in reversed(made):
        try:
            p.rmdir()
        except OSError:  # not empty (something else was written there), or gone
            return


@contextlib.contextmanager
def made_folder(path: str | os.PathLike) -> Iterator[Path]:
    """Make the folder ``path`` (and its missing parents) for the block; if the block raises
    (an error, Ctrl-C), remove again those it made that are still empty, so that a failed run
    leaves no trace where there was nothing.

    Examples
    --------
    >>> import tempfile
    >>> root = Path(tempfile.mkdtemp())
    >>> try:
    ...     with made_folder(root / "out" / "run1") as out:
    ...         raise KeyboardInterrupt
    ... except KeyboardInterrupt:
    ...     pass
    >>> sorted(root.iterdir())
    []
    >>> with made_folder(root / "out") as out:
    ...     _ = (out / "a.txt").write_text("done")
    >>> sorted(p.name for p in out.iterdir())
    ['a.txt']
    """
    p = Path(path)
    made = _make_folder(p)
    _MADE.append(made)
    try:
        yield p
    except BaseException:
        _remove_empty(made)
        raise
    finally:
        _forget(made)


@contextlib.contextmanager
def replacing(path: str | os.PathLike) -> Iterator[Path]:
    """Yield the partial name of ``path`` (its folder made); when the block ends normally,
    rename it over ``path``; when it raises (an error, Ctrl-C), remove it.

    Examples
    --------
    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp()) / "a.txt"
    >>> _ = out.write_text("earlier")
    >>> try:
    ...     with replacing(out) as part:
    ...         _ = part.write_text("half")
    ...         raise KeyboardInterrupt
    ... except KeyboardInterrupt:
    ...     pass
    >>> out.read_text(), sorted(p.name for p in out.parent.iterdir())
    ('earlier', ['a.txt'])
    """
    p = Path(path)
    check_place(p)
    part = partial_path(p)
    made = _make_folder(p.parent)
    _MADE.append(made)
    try:
        # a buffered write's error (a full disk) names the file, as PartialFile's do: it
        # reached the command line as "[Errno 28] No space left on device", no file named
        with _naming(part):
            yield part
        commit_partial(part, p)  # (failing, as over a folder: the partial file removed too)
    except BaseException:
        part.unlink(missing_ok=True)
        _remove_empty(made)
        raise
    finally:
        _forget(made)


@contextlib.contextmanager
def open_replacing(path: str | os.PathLike) -> Iterator[IO[str]]:
    """A text file to write ``path`` with, that replaces it only once closed complete
    (:func:`replacing`)."""
    with replacing(path) as part, open(part, "w") as fh:
        yield fh


class PartialFile:
    """A text file written piece by piece, as a run goes, under the partial name of ``path``
    (:func:`partial_path`): :meth:`commit` renames it over ``path`` once complete,
    :meth:`abort` removes it. Nothing is made on disk before the first :meth:`write` (or
    :meth:`commit`, which writes an empty file).

    Parameters
    ----------
    path : str or os.PathLike
        The file's final name (its folder is made when the file is opened).

    Examples
    --------
    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp()) / "a.txt"
    >>> _ = out.write_text("earlier")
    >>> f = PartialFile(out)
    >>> f.write("new ")
    >>> f.write("rows")
    >>> out.read_text(), f.part.exists()   # the earlier file stays until the commit
    ('earlier', True)
    >>> f.commit()
    >>> out.read_text(), f.part.exists()
    ('new rows', False)
    >>> g = PartialFile(out)
    >>> g.write("half")
    >>> g.abort()
    >>> out.read_text(), sorted(p.name for p in out.parent.iterdir())
    ('new rows', ['a.txt'])
    """

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        check_place(self.path)
        self.part = partial_path(self.path)
        self._fh: IO[str] | None = None
        self._ended = False  # committed or given up

    def _open(self) -> IO[str]:
        if self._ended:
            # (a write after commit began an untracked partial file, and a second commit
            # replaced the output with the later rows alone)
            raise ValueError(f"{self.path}: the file is committed or given up: no more can be "
                             "written to it")
        if self._fh is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._fh = open(self.part, "w")  # closed by commit or abort
        return self._fh

    def write(self, text: str) -> None:
        """Append ``text`` to the partial file (opened, and its folder made, at the first
        call)."""
        with self._naming():
            self._open().write(text)

    def _naming(self) -> contextlib.AbstractContextManager:
        """An OS error of a write or flush (a full disk) with the partial file's name, which
        a buffered write leaves out ("[Errno 28] No space left on device" named no file)."""
        return _naming(self.part)

    def read(self) -> str:
        """Everything written so far (the partial file read back)."""
        with self._naming():
            self._open().flush()
        return self.part.read_text()

    def truncate(self) -> None:
        """Start the partial file over, empty."""
        fh = self._open()
        fh.seek(0)
        fh.truncate()

    def commit(self) -> None:
        """Close the partial file and rename it over ``path`` (an empty file if nothing was
        written); on failure (a full disk at the last flush) remove it, leaving ``path`` as
        it was."""
        try:
            with self._naming():
                self._open().close()
            commit_partial(self.part, self.path)
        except BaseException:
            self.abort()
            raise
        finally:
            self._fh = None
            self._ended = True

    def abort(self) -> None:
        """Give the file up: close and remove the partial file; ``path`` is left as it was.
        Harmless when nothing was written, or called twice."""
        fh, self._fh = self._fh, None
        self._ended = True
        try:
            if fh is not None:
                fh.close()
        except OSError:  # the flush of a file being given up (a full disk)
            pass
        finally:
            self.part.unlink(missing_ok=True)
            _NAMED.discard(self.part)


@contextlib.contextmanager
def _naming(path: Path) -> Iterator[None]:
    """Give an OS error raised inside without a file name (a buffered write's) ``path``."""
    try:
        yield
    except OSError as e:
        if e.filename is None and e.strerror:
            raise OSError(e.errno, e.strerror, str(path)) from e
        raise


def check_output(path: str | os.PathLike, *, force: bool = False, name: str = "out",
                 folder: bool = False, option: str | None = None) -> None:
    """Raise, before any work is done, if ``path`` cannot be written: a file (or with
    ``folder``, a folder to write files in) that is a folder (a file), lies under a file,
    lies in a folder that cannot be written, or (a file) exists and ``force`` is False.

    ``name`` names the argument or option in the messages, and ``option`` how to overwrite
    an existing file (by default ``--force`` where ``name`` is an option, ``--out``, and
    ``force=True`` where it is Python's argument, :func:`force_option`).

    Raises
    ------
    IsADirectoryError, NotADirectoryError
        As :func:`check_place`: ``path`` is where no file (with ``folder``, no folder) can
        be, or a folder above it is a file.
    FileExistsError
        If ``path`` is to be a file, exists and ``force`` is False.
    PermissionError
        If the nearest existing folder at or above where ``path`` is written cannot be
        written in: its permissions say so, or a file cannot be made there (``/proc``, a
        read-only mount).

    Examples
    --------
    >>> import tempfile
    >>> tmp = Path(tempfile.mkdtemp())
    >>> check_output(tmp / "new" / "a.txt")  # folders are made when written
    >>> check_output(tmp, name="--out")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    IsADirectoryError: --out ... is a folder, not a file
    >>> _ = (tmp / "f").write_text("")
    >>> check_output(tmp / "f" / "a.txt", name="--out")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    NotADirectoryError: --out .../f/a.txt: .../f is a file, not a folder
    >>> check_output(tmp / "f", name="--out")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    FileExistsError: --out .../f exists; pass --force to overwrite it
    >>> check_output(tmp / "f")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    FileExistsError: out .../f exists; pass force=True to overwrite it
    >>> check_output(tmp / "f", name="--out-dir", folder=True)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    NotADirectoryError: --out-dir .../f is a file, not a folder
    """
    p = Path(path)
    here = check_place(p, name=name, folder=folder)
    if not os.access(here, os.W_OK | os.X_OK):
        why = "no permission"
        try:  # access() fails on a read-only mount too, whatever the permissions say
            if os.statvfs(here).f_flag & os.ST_RDONLY:
                why = "a read-only file system"
        except (OSError, AttributeError):  # (no statvfs on Windows)
            pass
        raise PermissionError(f"{name} {p}: cannot write in {here} ({why})")
    # a folder may refuse new files whatever its permissions say (/proc, /sys, a read-only
    # mount; root passes every access check): a file made and removed there tells, where a
    # failure at the partial file's name, later, named a file the user never gave
    try:
        fd, probe = tempfile.mkstemp(prefix=".vistrack-", suffix=".probe", dir=here)
    except OSError as e:
        raise PermissionError(f"{name} {p}: cannot write in {here} "
                              f"({e.strerror or type(e).__name__})") from e
    os.close(fd)
    os.unlink(probe)
    if not folder and p.exists() and not force:
        raise FileExistsError(f"{name} {p} exists; pass {option or force_option(name)} to "
                              "overwrite it")


def check_place(path: str | os.PathLike, *, name: str | None = None,
                folder: bool = False) -> Path:
    """Raise if ``path`` cannot be where a file (with ``folder``, a folder) is written: it is
    an existing folder (file), or a folder above it is a file. Returns the nearest existing
    folder at or above where the file is written. ``name``, where given, names the argument
    before the path in the messages. Nothing is made or written (:func:`check_output` checks
    besides that the folder can be written in and what exists).

    Every writer checks this before its work (:func:`replacing`, :class:`PartialFile`):
    a folder given as the file was found only at the rename, after the whole file was
    written, in words naming the partial file (``Is a directory: '.nd.00436f4e82.partial'
    -> 'nd'``), and a file above the path as ``[Errno 17] File exists``.

    Raises
    ------
    IsADirectoryError
        If ``path`` is to be a file and is an existing folder.
    NotADirectoryError
        If ``path`` is to be a folder and is an existing file, or a folder above it is a
        file.
    OSError
        ``ENAMETOOLONG``, if a name of ``path`` still to be made is longer than the file
        system takes there (``PC_NAME_MAX``, 255 bytes where it does not say).

    Examples
    --------
    >>> import tempfile
    >>> tmp = Path(tempfile.mkdtemp())
    >>> check_place(tmp / "new" / "a.txt") == tmp
    True
    >>> check_place(tmp)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    IsADirectoryError: ... is a folder, not a file
    """
    p = Path(path)
    label = f"{name} {p}" if name else str(p)
    if folder:
        if p.exists() and not p.is_dir():
            raise NotADirectoryError(f"{label} is a file, not a folder")
    elif p.is_dir():
        raise IsADirectoryError(f"{label} is a folder, not a file")
    # the nearest existing folder at or above where the file is written
    here = p if folder else p.parent
    while not here.exists() and here != here.parent:
        here = here.parent
    if here.exists() and not here.is_dir():
        raise NotADirectoryError(f"{label}: {here} is a file, not a folder")
    # each name to be made below it within what the file system takes there: past an
    # existing folder the name was refused by its stat, but below one still to be made it
    # was found only when written (a batch ran its other inputs first)
    try:
        longest = os.pathconf(here, "PC_NAME_MAX")
    except (OSError, ValueError):
        longest = 255
    q = p
    while q != here and q != q.parent:
        if len(os.fsencode(q.name)) > longest:
            raise OSError(errno.ENAMETOOLONG, os.strerror(errno.ENAMETOOLONG), str(p))
        q = q.parent
    return here


def force_option(name: str) -> str:
    """How to say "overwrite" to whoever named an output ``name``: ``--force`` to the command
    line (an option's name, ``--out``), ``force=True`` to Python (an argument's, ``out``;
    a Python caller was told to pass ``--force``)."""
    return "--force" if name.startswith("--") else "force=True"


Input = tuple[str, str | os.PathLike | None] | tuple[str, str | os.PathLike | None,
                                                     tuple[str, ...]]
"""What a run reads, for :func:`check_not_input`: ``(what, file)``, or ``(what, folder,
suffixes)``, a folder whose files of those suffixes it reads (the images of a video)."""


def check_not_input(outputs: Iterable[str | os.PathLike], inputs: Iterable[Input], *,
                    name: str = "out", given: str | os.PathLike | None = None) -> None:
    """Raise, before any work is done, if an output would be written where one of the run's
    inputs lies, which ``force`` would replace with what was read from it: at an input file
    (by any path to it: through a folder that is a link, or ``new/../in.txt``), or directly
    in an input folder under a name it reads (an image among a video's frames).

    An output is renamed into place when written, which replaces a link at its name rather
    than the file the link points to: an output that is a link (symbolic or hard) to an
    input is no input.

    ``inputs`` are ``(what, file)`` pairs, or ``(what, folder, suffixes)``, ``what`` naming
    the input in the message (None paths, paths that do not exist, and a folder given as a
    file, are skipped); ``name`` names the option, whose value
    ``given`` is a folder the ``outputs`` are written in (default: each output is the
    option's value itself).

    Raises
    ------
    ValueError
        If an output is an input, or lies in an input folder.

    Examples
    --------
    >>> import tempfile
    >>> gt = Path(tempfile.mkdtemp()) / "gt.txt"
    >>> _ = gt.write_text("1,1,0,0,5,5,1,1,1\\n")
    >>> check_not_input([gt.parent / "tracks.txt"], [("the ground truth (--gt)", gt)])
    >>> check_not_input([gt], [("the video", None), ("the ground truth (--gt)", gt)],
    ...                 name="--out")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: --out .../gt.txt is the ground truth (--gt): the run would write over it; give \
another --out
    """
    read = []
    for what, src, *among in inputs:
        if src is None:
            continue
        p = Path(src)
        if (p.is_dir() and among) or (p.is_file() and not among):
            read.append((what, p.resolve(), tuple(among[0]) if among else None))
    for out in map(Path, outputs):
        parent = out.parent.resolve()  # (the output's own name is not followed: it is replaced)
        at = parent / out.name
        for what, src, suffixes in read:
            where = f"{name} {out}" if given is None else f"{name} {given}: {out}"
            if suffixes is not None:
                if parent == src and out.suffix.lower() in suffixes:
                    raise ValueError(f"{where} lies in {what}, among the files the run "
                                     f"reads; give another {name}")
                continue
            # the same name, or the same file under the name in another case (a file system
            # that ignores case; a hard link of another name is another name, replaced alone)
            if at == src or (parent == src.parent and at.name.casefold() == src.name.casefold()
                             and at.exists() and not at.is_symlink()
                             and os.path.samefile(at, src)):
                raise ValueError(f"{where} is {what}: the run would write over it; give "
                                 f"another {name}")

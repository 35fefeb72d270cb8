"""Outputs written whole or not at all: each is written under a partial name beside it and
renamed over the real name only when complete, so that an interrupted or failed run leaves
the file of an earlier run as it was."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path
from typing import IO

__all__ = ["partial_path", "replacing", "open_replacing", "check_output"]


def partial_path(path: str | os.PathLike) -> Path:
    """Where ``path`` is written until it is complete: a hidden name in the same folder with
    the same suffix (a video writer picks its container by the suffix)."""
    p = Path(path)
    return p.with_name(f".{p.stem}.partial{p.suffix}")


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
    part = partial_path(p)
    p.parent.mkdir(parents=True, exist_ok=True)
    try:
        yield part
    except BaseException:
        part.unlink(missing_ok=True)
        raise
    os.replace(part, p)


@contextlib.contextmanager
def open_replacing(path: str | os.PathLike) -> Iterator[IO[str]]:
    """A text file to write ``path`` with, that replaces it only once closed complete
    (:func:`replacing`)."""
    with replacing(path) as part, open(part, "w") as fh:
        yield fh


def check_output(path: str | os.PathLike, *, force: bool = False, name: str = "out",
                 folder: bool = False) -> None:
    """Raise, before any work is done, if ``path`` cannot be written: a file (or with
    ``folder``, a folder to write files in) that is a folder (a file), lies under a file,
    lies in a folder that cannot be written, or (a file) exists and ``force`` is False.

    ``name`` names the argument or option in the messages.

    Raises
    ------
    IsADirectoryError
        If ``path`` is to be a file and is an existing folder.
    NotADirectoryError
        If ``path`` is to be a folder and is an existing file, or a folder above it is a
        file.
    FileExistsError
        If ``path`` is to be a file, exists and ``force`` is False.
    PermissionError
        If the nearest existing folder at or above where ``path`` is written cannot be
        written in.

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
    >>> check_output(tmp / "f", name="--out-dir", folder=True)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    NotADirectoryError: --out-dir .../f is a file, not a folder
    """
    p = Path(path)
    if folder:
        if p.exists() and not p.is_dir():
            raise NotADirectoryError(f"{name} {p} is a file, not a folder")
    elif p.is_dir():
        raise IsADirectoryError(f"{name} {p} is a folder, not a file")
    # the nearest existing folder at or above where the file is written
    here = p if folder else p.parent
    while not here.exists() and here != here.parent:
        here = here.parent
    if here.exists() and not here.is_dir():
        raise NotADirectoryError(f"{name} {p}: {here} is a file, not a folder")
    if not os.access(here, os.W_OK | os.X_OK):
        raise PermissionError(f"{name} {p}: cannot write in {here} (no permission)")
    if not folder and p.exists() and not force:
        raise FileExistsError(f"{name} {p} exists; pass --force to overwrite it")

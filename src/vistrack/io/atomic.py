"""Outputs written whole or not at all: each is written under a partial name beside it and
renamed over the real name only when complete, so that an interrupted or failed run leaves
the file of an earlier run as it was."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path
from typing import IO

__all__ = ["partial_path", "replacing", "open_replacing"]


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

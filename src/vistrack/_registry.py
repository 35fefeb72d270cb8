"""Parts chosen by name: :class:`Registry` (re-exported as :class:`vistrack.pipeline.Registry`)."""

from __future__ import annotations

from typing import Generic, TypeVar

__all__ = ["Registry"]

T = TypeVar("T")


class Registry(dict[str, T], Generic[T]):
    """Parts by name: a ``dict`` whose missing names raise a ``ValueError`` that lists the
    valid ones.

    Parameters
    ----------
    kind : str
        What the parts are, for the message (``"frontend"``, ``"tracker"``, ``"sink"``).
    items : dict of str to part
        The parts by name.

    Examples
    --------
    >>> r = Registry("colour", {"red": 1, "blue": 2})
    >>> r["red"]
    1
    >>> r["green"]
    Traceback (most recent call last):
    ...
    ValueError: colour must be one of ['blue', 'red']; got 'green'
    """

    def __init__(self, kind: str, items: dict[str, T]):
        super().__init__(items)
        self.kind = kind

    def __missing__(self, name: str) -> T:
        raise ValueError(f"{self.kind} must be one of {sorted(self)}; got {name!r}")

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

    A name that is no string is no name of the registry, in either use (``["red"] in r``
    and ``r[["red"]]`` said "unhashable type: 'list'"):

    >>> ["red"] in r
    False
    >>> r[["red"]]
    Traceback (most recent call last):
    ...
    ValueError: colour must be one of ['blue', 'red']; got ['red']
    """

    def __init__(self, kind: str, items: dict[str, T]):
        super().__init__(items)
        self.kind = kind

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and super().__contains__(name)

    def __getitem__(self, name: str) -> T:
        if not isinstance(name, str):
            return self.__missing__(name)
        return super().__getitem__(name)

    def __missing__(self, name: str) -> T:
        raise ValueError(f"{self.kind} must be one of {sorted(self)}; got {name!r}")

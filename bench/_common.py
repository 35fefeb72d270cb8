"""Helpers shared by the benchmark scripts."""

from __future__ import annotations

import sys


def optional(name: str):
    """The module ``name``, or None (with a note on stderr) when it does not import."""
    try:
        return __import__(name)
    except Exception as exc:  # noqa: BLE001 - any import failure means "not available"
        print(f"  ({name} not available: {exc})", file=sys.stderr)
        return None

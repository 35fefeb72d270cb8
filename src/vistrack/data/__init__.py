"""Data that ships with vistrack, inside the package (a ``pip install`` carries it): the demo
clip that ``vistrack demo track`` and ``make run`` track.

``pets09-s2l1/``: frames 1-200 of PETS09-S2L1 (OpenCV's sample video ``vtest.avi``, 768x576,
7 frames/s) and their MOT15 ground truth; ``PROVENANCE.md`` beside them gives their origin
and licences.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

__all__ = ["Clip", "demo_clip"]


class Clip(NamedTuple):
    """A bundled clip's files: the video, its ground truth (MOTChallenge rows) and where
    they come from."""

    video: Path
    gt: Path
    provenance: Path


def demo_clip() -> Clip:
    """The demo clip, PETS09-S2L1 frames 1-200, as files on disk.

    Raises
    ------
    FileNotFoundError
        If an installation lost one of its files, naming it.

    Examples
    --------
    >>> clip = demo_clip()
    >>> clip.video.name, clip.gt.name
    ('pets09-s2l1.mp4', 'gt.txt')
    """
    root = Path(__file__).resolve().parent / "pets09-s2l1"
    clip = Clip(root / "pets09-s2l1.mp4", root / "gt.txt", root / "PROVENANCE.md")
    for path in clip:
        if not path.is_file():
            raise FileNotFoundError(f"vistrack's demo clip has no {path}: reinstall vistrack "
                                    "(its wheel carries the clip)")
    return clip

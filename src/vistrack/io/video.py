"""Frames in and out: :class:`VideoReader` over a video file, an image folder or a MOTChallenge
``img1/``, and :class:`VideoWriter` for MP4.

Frames stream one at a time (memory stays bounded however long the video), each as a
:class:`Frame` with its index (from 1, as MOTChallenge counts) and time in seconds. OpenCV
decodes. A file that stops decoding before the frame count its header gives yields the
frames read and warns with the frame index where reading stopped; a file OpenCV cannot open at
all raises :class:`VideoError` naming it. In an image folder, an image that does not decode, a
JPEG cut short (its data end before its end-of-image marker; data after the marker, which many
cameras append, are fine) and an image of another size than the first raise
:class:`VideoError` naming the file, or are skipped with a warning naming it
(``skip_bad=True``).
"""

from __future__ import annotations

import math
import os
import re
import warnings
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validate import as_finite, as_flag, as_number, as_whole, bgr_to_grey, is_real, ordinal
from ..types import Frame

if TYPE_CHECKING:
    import cv2

__all__ = ["Frame", "VideoError", "VideoReader", "VideoWriter", "IMAGE_SUFFIXES"]

IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff")

# a JPEG's markers: FF, then a code other than 00 and FF (FF FF: a fill byte before the
# marker); in entropy-coded data, FF 00 is a data byte FF and FF D0-D7 a restart marker, which
# the data go on after. (Without repetition, so that re scans at about 1 GB/s.)
_JPEG_MARKER = re.compile(rb"\xff[\x01-\xfe]")
_JPEG_SCAN_END = re.compile(rb"\xff[\x01-\xcf\xd8-\xfe]")


def _jpeg_end(data: bytes) -> int | None:
    """Where the JPEG image that ``data`` starts with ends: the offset just past its
    end-of-image marker (FF D9), or None if the data end first (cut short, or corrupt).

    The segments are walked as a decoder reads them (each marker's length, and the
    entropy-coded data after a start of scan up to the next marker), so an FF D9 inside a
    thumbnail or metadata is not taken for the image's end, and whatever follows the end
    (cameras append metadata, other images, even videos) is not looked at.

    Examples
    --------
    Start of image, an APP1 segment that holds FF D9, a scan whose data hold a byte FF
    (FF 00) and a restart marker, and the end of image:

    >>> jpeg = bytes.fromhex("ffd8 ffe1 0006 ffd9 0000 ffda 0002 12ff0034 ffd0 56 ffd9")
    >>> len(jpeg), _jpeg_end(jpeg), _jpeg_end(jpeg + b"appended"), _jpeg_end(jpeg[:-2])
    (23, 23, 23, None)
    """
    pos = 2  # past the start-of-image marker FF D8
    while True:
        # the next marker: fill bytes FF before it, and bytes that are not one (libjpeg warns
        # of "extraneous bytes"), are skipped as libjpeg skips them
        m = _JPEG_MARKER.search(data, pos)
        if m is None:
            return None
        code, pos = data[m.end() - 1], m.end()
        if code == 0xD9:  # end of image
            return pos
        if code in (0x01, 0xD8) or 0xD0 <= code <= 0xD7:  # markers without a length
            continue
        if pos + 2 > len(data) or (length := int.from_bytes(data[pos:pos + 2], "big")) < 2:
            return None
        pos += length
        if pos > len(data):
            return None
        if code == 0xDA:  # start of scan: entropy-coded data up to the next marker
            m = _JPEG_SCAN_END.search(data, pos)
            if m is None:
                return None
            pos = m.start()


class _Note(str):
    """A warning :meth:`VideoReader._frames` hands to the caller's thread, in order."""


class VideoError(OSError):
    """A video or image that cannot be read or written.

    An ``OSError``; :class:`VideoReader` and :class:`VideoWriter` raise it, naming the file.

    Examples
    --------
    >>> import tempfile
    >>> try:
    ...     VideoReader(tempfile.mkdtemp())
    ... except VideoError as e:
    ...     print(str(e).split(" ", 1)[1])
    holds no images (.jpg, .jpeg, .png, .bmp, .tif, .tiff)
    """


def _cv2():
    try:
        import cv2
    except ImportError as e:  # pragma: no cover - a core dependency
        raise ImportError("vistrack.io.video needs OpenCV: pip install "
                          "opencv-contrib-python-headless") from e
    return cv2


_SHORT_WARNED: set[Path] = set()
_GAP_WARNED: set[Path] = set()
"""Image folders whose missing frame numbers were warned about (once a process)."""

_TEXT_SUFFIXES = (".txt", ".csv", ".tsv", ".json", ".toml", ".ini", ".md")
"""Files that are text: refused as videos."""


def _natural(path: Path) -> tuple:
    """A sort key of a file's name with its numbers as numbers: ``2.png`` before ``10.png``,
    as ``000002.png`` before ``000010.png`` (the name itself breaks ties: ``1.png``,
    ``01.png``)."""
    parts = re.split(r"(\d+)", path.name)
    return tuple(int(t) if k % 2 else t for k, t in enumerate(parts)), path.name


def _numbered(files: list[Path], as_named: bool = False) -> list[int] | None:
    """Each image's frame index from the last number in its name, counted from the first
    image's number as 1 (``000001.jpg`` and ``000000.png`` alike start at frame 1), or, with
    ``as_named`` (a MOTChallenge sequence), from the first image's own number (at least 1),
    when every name has a number, the numbers increase in name order, and they skip no more
    numbers than there are images (a dropped frame is an exception; names that are
    timestamps skip many between every two; a MOTChallenge sequence's names are its frame
    numbers, however many they skip); else None (then the images are numbered by position).

    >>> _numbered([Path("000001.jpg"), Path("000002.jpg"), Path("000004.jpg")])
    [1, 2, 4]
    >>> _numbered([Path("000002.jpg"), Path("000003.jpg")], as_named=True)
    [2, 3]
    >>> _numbered([Path("cam_0.png"), Path("cam_1.png")]), _numbered([Path("a.png")])
    ([1, 2], None)
    >>> _numbered([Path("t1690000000000.jpg"), Path("t1690000000033.jpg")]) is None
    True
    """
    numbers = []
    for path in files:
        found = re.findall(r"\d+", path.stem)
        if not found:
            return None
        numbers.append(int(found[-1]))
    # (a MOTChallenge sequence's names are its frame numbers, gaps or not: frames 1-3 and
    # 20-22 were numbered 1-6 by position)
    if any(b <= a for a, b in zip(numbers, numbers[1:])) \
            or (not as_named and numbers[-1] - numbers[0] + 1 > 2 * len(numbers)):
        return None
    first = max(1, numbers[0]) if as_named else 1
    return [n - numbers[0] + first for n in numbers]


def _unnumbered_why(files: list[Path]) -> str | None:
    """Why images that are mostly numbered are numbered by position instead: a name without
    a number among numbered ones (``notes.png``), or two names of one number, or numbers
    that go back in name order (``000003 (copy).jpg`` beside ``000003.jpg``), or numbers that
    step by one same amount of 2 or more (a folder thinned to every k-th frame, whose
    detections and ground truth number the frames between too); None where no name has a
    number, or the numbers only skip too many, unevenly (timestamps), as intended. Runs of
    numbers one apart with a gap between them longer than the folder's count of images are
    frames missing, or timestamps: said too.

    >>> _unnumbered_why([Path("000001.jpg"), Path("000002.jpg")]) is None
    True
    >>> _unnumbered_why([Path("000001.jpg"), Path("000001.png"), Path("000002.jpg")])
    '000001.jpg and 000001.png both give frame 1'
    >>> _unnumbered_why([Path("000001.jpg"), Path("000004.jpg"), Path("000007.jpg")])
    'the names step by 3 (000001.jpg, 000004.jpg, ...): every 3rd frame, or timestamps'
    >>> print(_unnumbered_why([Path(f"{k:06d}.jpg") for k in (1, 2, 3, 20, 21, 22)]))
    the names run from 1 to 22, over twice the folder's 6 images, mostly one apart (the longest gap 16 numbers, between 000003.jpg and 000020.jpg): frames missing, or timestamps
    """  # noqa: E501
    numbers = [re.findall(r"\d+", p.stem) for p in files]
    if not any(numbers):
        return None
    for path, found in zip(files, numbers):
        if not found:
            return f"{path.name} has no number"
    values = [int(f[-1]) for f in numbers]
    for k in range(1, len(values)):
        if values[k] == values[k - 1]:
            return (f"{files[k - 1].name} and {files[k].name} both give frame "
                    f"{values[k] - values[0] + 1}")
        if values[k] < values[k - 1]:
            return f"{files[k].name} comes after {files[k - 1].name} but numbers an earlier frame"
    steps = {b - a for a, b in zip(values, values[1:])}
    if len(values) >= 3 and len(steps) == 1 and (step := steps.pop()) > 1:
        # numbered by place, frame 2 is the name's frame 1 + step: said, as a thinned
        # folder's detections number the frames between too (it went without a word)
        return (f"the names step by {step} ({files[0].name}, {files[1].name}, ...): every "
                f"{ordinal(step)} frame, or timestamps")
    ones = sum(b - a == 1 for a, b in zip(values, values[1:]))
    if ones >= len(values) // 2 and values[-1] - values[0] + 1 > 2 * len(values):
        # runs of frames one apart with a long gap between: frames missing, not timestamps
        # (which skip many between every two), numbered by place without a word before
        k = max(range(1, len(values)), key=lambda i: values[i] - values[i - 1])
        return (f"the names run from {values[0]} to {values[-1]}, over twice the folder's "
                f"{len(values)} images, mostly one apart (the longest gap "
                f"{values[k] - values[k - 1] - 1} numbers, between {files[k - 1].name} and "
                f"{files[k].name}): frames missing, or timestamps")
    return None


def _missing(index: list[int], limit: int = 5) -> tuple[int, str]:
    """How many frame numbers between the first and the last of ``index`` (increasing) have
    no image, and the first ``limit`` of them as text.

    >>> _missing([1, 2, 4, 8])
    (4, '3, 5, 6, 7')
    """
    gaps = [(a + 1, b - 1) for a, b in zip(index, index[1:]) if b > a + 1]
    n = sum(hi - lo + 1 for lo, hi in gaps)
    first: list[str] = []
    for lo, hi in gaps:
        first += [str(k) for k in range(lo, min(hi, lo + limit) + 1)]
        if len(first) >= limit:
            break
    return n, ", ".join(first[:limit]) + (", ..." if n > limit else "")


def _pages(path: Path) -> int:
    """The pages of a TIFF file (1 for any other image, or one OpenCV cannot count)."""
    if path.suffix.lower() not in (".tif", ".tiff"):
        return 1
    try:
        return int(_cv2().imcount(str(path)))
    except Exception:  # noqa: BLE001  (a corrupt file is named where it is decoded)
        return 1


def _stack_error(path: Path, pages: int) -> VideoError:
    # (its first page alone was read, as one frame, and the rest dropped without a word)
    return VideoError(f"{path} is a TIFF of {pages} pages (a stack): one image a file is read, "
                      "so its other pages would be lost; save the pages as numbered images "
                      "in a folder and give the folder")


def _holds_images(folder: Path) -> bool:
    """Whether ``folder`` is a folder with an image in it (False if it cannot be listed)."""
    try:
        return folder.is_dir() and any(p.suffix.lower() in IMAGE_SUFFIXES
                                       for p in folder.iterdir())
    except OSError:
        return False


def _sequence_section(info: Path) -> Mapping[str, str]:
    """The ``[Sequence]`` section of ``seqinfo.ini`` as :class:`VideoReader` reads it (empty
    without one), or a :class:`VideoError` naming the file and line as
    :func:`~vistrack.io.read_seqinfo` names them (configparser's and the decoder's own words
    before, without the line where the detections' reading named it)."""
    from .motchallenge import MOTFormatError
    from .motchallenge import _sequence_section as section

    try:
        return section(info, required=False)[1]
    except MOTFormatError as exc:
        raise VideoError(str(exc)) from None


def _frame_rate(info: Path, seq: Mapping[str, str], given: float | None) -> float | None:
    """``frameRate`` of a sequence's ``[Sequence]`` section ``seq`` (None without one), or a
    :class:`VideoError` naming the file and line where it is no number, or where it is no
    finite number > 0 and no frame rate is ``given`` to replace it."""
    if "frameRate" not in seq:
        return None
    from .motchallenge import _ini_line

    try:
        rate = float(seq["frameRate"])
    except ValueError:  # (Python's "could not convert string to float" before, no line)
        raise VideoError(f"{_ini_line(info, 'frameRate')}: frameRate = "
                         f"{seq['frameRate']!r} is not a number") from None
    if given is None and not (np.isfinite(rate) and rate > 0):
        # 0 fell back to 30 frames/s without a word, as no frame rate at all; the frame
        # rate given (fps, --fps) overrides it
        raise VideoError(f"{_ini_line(info, 'frameRate')}: frameRate must be a finite number "
                         f"> 0; got {seq['frameRate']}")
    return rate


def images_of(folder: str | os.PathLike) -> Path:
    """The folder :class:`VideoReader` reads a folder's images from: a sequence folder's
    ``imDir`` (``img1`` by default), or the folder itself.

    Raises
    ------
    VideoError
        If the sequence's ``seqinfo.ini`` cannot be read.
    """
    folder = Path(folder)
    info = folder / "seqinfo.ini"
    return folder / _sequence_section(info).get("imDir", "img1") if info.exists() else folder


def check_rate(fps: Any) -> None:
    """``fps`` a frame rate a video is read at: a finite number > 0 (a ValueError naming it)."""
    # (text met numpy's "ufunc 'isfinite' not supported"; True was 1 frame a second)
    if not (is_real(fps) and math.isfinite(float(fps)) and float(fps) > 0):
        raise ValueError(f"fps must be a finite number > 0; got {fps}")


class VideoReader:
    """Frames of a video file, an image folder, or a MOTChallenge sequence folder (its
    ``img1/``, with the frame rate of its ``seqinfo.ini``).

    Parameters
    ----------
    source : str or Path
        A video file, a folder of images (read in name order, numbers as numbers: ``2.png``
        before ``10.png``), or a MOTChallenge sequence folder. An image is the frame the
        last number in its name gives, counted from the first image's as 1 (``000001.jpg``
        and ``000000.png`` are both frame 1; in a MOTChallenge sequence the number itself,
        so one whose ``000001.jpg`` is missing starts at frame 2, warned), so a number with
        no image is a missing frame
        (warned, once) and the frames after it keep their numbers, as detections and ground
        truth number them; where a name has no number, or the numbers do not increase in
        name order, or they skip more numbers than there are images (timestamps), the
        images are numbered by position. A text file (``.txt``, ``.csv``, ...) is refused.
    fps : float, optional
        Frames per second; default the sequence's ``seqinfo.ini``, else the container's header,
        else 30 (image folders). Give it when the header is wrong.
    grey : bool
        Yield ``(H, W)`` grey frames instead of BGR.
    start, stop : int, optional
        The first and last frame index to yield (from 1, inclusive). A video is sought to
        ``start`` where OpenCV seeks exactly (MP4, MOV, MKV, WebM, AVI); others (MPEG
        program and transport streams, a stream without a frame count) are read through to
        it.
    prefetch : int
        Decode up to this many frames ahead in a background thread (OpenCV releases the GIL
        while it decodes), so that decoding overlaps the caller's work; 0 decodes in the
        caller's thread. Memory holds at most ``prefetch`` frames more.
    skip_bad : bool
        Image folders: skip an image that does not decode, a JPEG cut short, or an image of
        another size than the first readable one, with a ``RuntimeWarning`` naming the file,
        instead of raising :class:`VideoError`. The frames after keep their indices, so a
        skipped image is a missing index; ``len()`` still counts it.

    Attributes
    ----------
    fps : float
        The frame rate used.
    fps_from : str or None
        What gave it: ``"fps"`` (the argument), ``"seqinfo.ini"``, ``"the header"``; None
        where nothing did (an image folder), and it is 30.
    own_fps, own_fps_from : float or None, str or None
        The frame rate the source itself gives and what gives it (``"seqinfo.ini"``,
        ``"the header"``), whether or not ``fps`` was put over it; None, None where it gives
        none (an image folder) or none that is a rate (a frameRate of 0).
    size : (width, height)
        The frames' size (of the header, for video files).
    frame_count : int
        Frames in the source: the header's count, for video files (0 where it gives none, as
        a raw stream such as ``.mjpeg``, or where OpenCV only estimates it, as for Matroska
        and WebM; the frames are read to the file's end all the same); for image folders
        the last image's frame, missing frames included.
    image_folder : Path or None
        The folder the images are read from (a sequence folder's ``img1/``); None for a
        video file.

    Raises
    ------
    FileNotFoundError
        If ``source`` (or the image folder its ``seqinfo.ini`` names) does not exist.
    VideoError
        If ``source`` is a text file, OpenCV cannot open the video, the folder holds no
        images, its ``seqinfo.ini`` is
        not a text INI file, a TIFF given or in the folder has several pages (a stack, even
        with ``skip_bad``), or (while iterating, unless ``skip_bad``) an image is
        unreadable, cut short or of another size than the first, naming the file.
    ValueError
        If ``start`` is less than 1, ``prefetch`` negative, or the frame rate not a finite
        number > 0.

    Warns
    -----
    RuntimeWarning
        If a sequence folder's images are fewer than its ``seqinfo.ini``'s ``seqLength``
        (once a process for a folder): those there are read. If an image folder's numbered
        names skip a number (once a process for a folder): those frames are missing. If a
        folder's images are 16-bit (PNG, TIFF): each is scaled to 8 bits by the depth (8,
        10, 12, 14 or 16 bits) that holds the largest value of up to ten images spread over
        the folder (a 12-bit camera's values divided by 16), where ``cv2.imread`` divides by
        256 and leaves such images near black; and, while iterating, at the first image with
        values above that depth, which are clipped.

    Examples
    --------
    >>> import tempfile, cv2
    >>> d = Path(tempfile.mkdtemp())
    >>> for k in range(3):
    ...     _ = cv2.imwrite(str(d / f"{k:06d}.png"), np.full((4, 6, 3), 40 * k, np.uint8))
    >>> r = VideoReader(d, fps=10)
    >>> len(r), r.size, [(f.index, f.time, int(f.image[0, 0, 0])) for f in r]
    (3, (6, 4), [(1, 0.0, 0), (2, 0.1, 40), (3, 0.2, 80)])
    """

    def __init__(self, source: str | Path, *, fps: float | None = None, grey: bool = False,
                 start: int = 1, stop: int | None = None, prefetch: int = 0,
                 skip_bad: bool = False):
        src = Path(source)
        if not src.exists():
            raise FileNotFoundError(f"{src} does not exist")
        _opencv_name(src)
        # ("False" and "no" were true: grey frames, bad frames skipped)
        self.source, self.grey = src, as_flag(grey, "grey")
        # whole numbers: int() cut 2.7 to 2 (a frame early) and named nothing for "x"
        self.start = as_whole(start, "start", 1, "frames count from 1")
        # (before the start: "no frames to track")
        self.stop = None if stop is None else as_whole(
            stop, "stop", self.start, f"the last frame read, from start = {self.start}")
        self.prefetch = as_whole(prefetch, "prefetch", 0, "frames decoded ahead")
        if fps is not None:
            fps = as_number(fps, "fps")
        self.skip_bad = as_flag(skip_bad, "skip_bad")
        self._files: list[Path] | None = None
        # a folder's 16-bit images: their depth in bits, and how many were clipped above it
        self._bits: int | None = None
        self._clipped = 0
        seq_fps, seq_length = None, None
        in_sequence = False
        if src.is_dir():
            info = src / "seqinfo.ini"
            if info.exists():
                in_sequence = True
                seq = _sequence_section(info)
                seq_fps = _frame_rate(info, seq, fps)
                length = str(seq.get("seqLength", "")).strip()
                seq_length = int(length) if length.isdigit() else None  # for a warning
                src = src / seq.get("imDir", "img1")
                if not src.is_dir():
                    raise FileNotFoundError(f"{src} does not exist ({info} names it)")
            self._files = sorted((p for p in src.iterdir()
                                  if p.suffix.lower() in IMAGE_SUFFIXES), key=_natural)
            for path in self._files:
                _opencv_name(path)
            if not self._files:
                # an OTB or VOT sequence's folder holds its images in a folder of its own
                inner = sorted(d.name for d in src.iterdir() if _holds_images(d))
                where = (f"; its folder{'s' if len(inner) > 1 else ''} "
                         f"{', '.join(inner)} hold{'' if len(inner) > 1 else 's'} images: give "
                         f"{'one' if len(inner) > 1 else 'it'}" if inner else "")
                raise VideoError(f"{src} holds no images ({', '.join(IMAGE_SUFFIXES)}){where}")
            if seq_length is not None and len(self._files) != seq_length \
                    and src not in _SHORT_WARNED:
                # a sequence shipped with its first frames only (MOT17's in the shared data),
                # or a folder with more images than its sequence (tracked all the same, where
                # --out refuses detections past seqLength, naming the line); said once a
                # process (a front-end may open the folder again for its start)
                _SHORT_WARNED.add(src)
                few = len(self._files) < seq_length
                warnings.warn(f"{src} holds {len(self._files)} images, but {info} gives "
                              f"seqLength={seq_length}: "
                              + (f"only those {len(self._files)} are tracked" if few else
                                 f"all {len(self._files)} are tracked"),
                              RuntimeWarning, stacklevel=2)
            first = None
            for path in self._files:
                im, why = self._decode(path)
                if im is not None:
                    first = im
                    self._first = path
                    break
                if not self.skip_bad:
                    raise VideoError(f"{path}: {why}")
            if first is None:
                raise VideoError(f"{src} holds no readable images (every one fails to decode)")
            self._depth(first)
            self.size = (first.shape[1], first.shape[0])
            # a MOTChallenge sequence numbers its images as its frames (000001.jpg is frame 1):
            # one whose first images are missing starts later, where its detections and
            # ground truth put it (counted from the first image present, every frame was one
            # too low, and nothing said so)
            numbered = _numbered(self._files, as_named=in_sequence)
            start = numbered[0] if numbered is not None else 1
            self._index = numbered or list(range(1, len(self._files) + 1))
            self.frame_count = self._index[-1]
            said = src in _GAP_WARNED
            if start > 1 and not said:
                _GAP_WARNED.add(src)
                warnings.warn(f"{src}: no image for frame"
                              f"{f's 1-{start - 1}' if start > 2 else ' 1'}: the sequence "
                              f"starts at {self._files[0].name}, frame {start}, as "
                              f"{info.name} and its files number it",
                              RuntimeWarning, stacklevel=2)
            if numbered is not None and numbered[-1] - start + 1 > len(self._files) \
                    and not said:
                # a frame dropped from a folder: its number is a missing frame, and the
                # images after it keep the frames their names give, as detections and ground
                # truth number them (said after a late start too: it was one or the other)
                _GAP_WARNED.add(src)
                n, which = _missing(numbered)
                what = f"frame {which}" if n == 1 else f"{n} frames ({which})"
                warnings.warn(f"{src}: no image for {what}, numbering the images by their "
                              f"names from {self._files[0].name} as frame {start}: "
                              f"{'that frame is' if n == 1 else 'those frames are'} missing, "
                              "and the images after a gap keep the frames their names give",
                              RuntimeWarning, stacklevel=2)
            named = (int(re.findall(r"\d+", self._files[0].stem)[-1])
                     if numbered is not None and not in_sequence else 1)
            if named > 1 and src not in _GAP_WARNED:
                # (a folder cut from a longer one, whose detections or ground truth number its
                # frames as its names do, was numbered from 1 unsaid: every frame off by as
                # many)
                _GAP_WARNED.add(src)
                warnings.warn(f"{src}: {self._files[0].name} is frame 1: a folder of images "
                              f"counts its frames from its first image, whose name gives "
                              f"{named}; detections and ground truth must count from it too "
                              "(in a MOTChallenge sequence folder, with seqinfo.ini, the "
                              "names' numbers are the frames)", RuntimeWarning, stacklevel=2)
            unnumbered = _unnumbered_why(self._files) if numbered is None else None
            if unnumbered and src not in _GAP_WARNED:
                # images whose names give frames, but not one each: numbered by position,
                # so that detections and ground truth numbered by name no longer match
                _GAP_WARNED.add(src)
                warnings.warn(f"{src}: {unnumbered}: the {len(self._files)} images are "
                              f"numbered by their place in name order instead (frames 1-"
                              f"{len(self._files)}), not by the frames their names give",
                              RuntimeWarning, stacklevel=2)
            header_fps = None
        else:
            if src.suffix.lower() in _TEXT_SUFFIXES:
                # FFmpeg opens text too, as frames of its characters drawn
                raise VideoError(f"{src} is a {src.suffix} file, not a video: OpenCV would "
                                 "decode its text as frames of noise")
            pages = _pages(src)
            if pages > 1:
                raise _stack_error(src, pages)
            cv2 = _cv2()
            cap = cv2.VideoCapture(str(src))
            if not cap.isOpened():
                raise VideoError(f"{src}: OpenCV cannot open it as a video")
            self.size = (int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)),
                         int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))
            # a raw stream (.mjpeg) or a recording never finalised has no count, or
            # one that is negative or absurd: then 0, unknown, and the frames are read to
            # their end all the same
            count = cap.get(cv2.CAP_PROP_FRAME_COUNT)
            self.frame_count = int(count) if 0 < count < 2**31 else 0
            # Matroska (and WebM) holds no count: OpenCV's is its duration times its rate
            # (85 for a whole file of 60 whose times start at 1 s), which said "truncated" of
            # a whole file; kept as no count, and only to bound a seek
            self._seek_count = self.frame_count
            if src.suffix.lower() in _ESTIMATED_COUNT:
                self.frame_count = 0
            header_fps = cap.get(cv2.CAP_PROP_FPS) or None
            cap.release()
        # the folder the images are read from (a sequence's img1/), None for a video file
        self.image_folder: Path | None = self._files[0].parent if self._files else None
        # the rate the source gives, where fps is put over it too (the run says so)
        own: tuple[float | None, str | None] = next(
            ((float(r), f) for r, f in ((seq_fps, "seqinfo.ini"), (header_fps, "the header"))
             if r is not None and np.isfinite(r) and r > 0), (None, None))
        self.own_fps, self.own_fps_from = own
        # where the rate comes from: None where nothing gives one (an image folder, a
        # header's rate of 0, NaN or below 0, which was refused as "fps must be ...", an
        # argument not given), and it is 30
        self.fps_from = "fps" if fps is not None else self.own_fps_from
        fps = fps if fps is not None else self.own_fps or 30.0
        check_rate(fps)
        self.fps = float(fps)

    def __len__(self) -> int:
        """Frames to yield: the images present for a folder; from the header's count for
        video files (the file may hold fewer: reading then stops with a warning; or more,
        which are read too); 0 where the header gives no count (nor a Matroska or WebM file,
        whose count is an estimate) and no ``stop`` is given."""
        if self._files is not None:  # the images present (a frame without one is none)
            stop = self.frame_count if self.stop is None else self.stop
            return sum(1 for k in self._index if self.start <= k <= stop)
        if self.frame_count == 0:
            return 0 if self.stop is None else max(0, self.stop - self.start + 1)
        stop = self.frame_count if self.stop is None else min(self.stop, self.frame_count)
        return max(0, stop - self.start + 1)

    def _load(self, path: Path) -> tuple[np.ndarray | None, str]:
        """The image, 8 bits a channel, or None and why not (:meth:`_decode`,
        :meth:`_to_8bit`)."""
        im, why = self._decode(path)
        if im is None:
            return None, why
        im = self._to_8bit(im)
        return (bgr_to_grey(im) if self.grey else im), ""

    def _depth(self, first: np.ndarray) -> None:
        """The bits of a folder's 16-bit images (``first``, the first readable one, as
        decoded), from the largest value of up to ten images spread over the folder, and the
        note that says so."""
        assert self._files is not None
        picks = np.unique(np.linspace(0, len(self._files) - 1, 10).round().astype(int))
        # the first image's depth, and the others' (a folder whose first image is 8-bit and
        # later ones 16-bit had those divided by 256, 12-bit values of 1600 read as 6)
        top, seen = (int(first.max()), 1) if first.dtype == np.uint16 else (0, 0)
        for k in picks[1:]:
            if not seen and not _may_be_deep(self._files[k]):
                continue  # (an 8-bit folder: no image decoded twice)
            im, _ = self._decode(self._files[k])
            if im is not None and im.dtype == np.uint16:
                top, seen = max(top, int(im.max())), seen + 1
        if not seen:
            return
        # the depth a camera delivers (8, 10, 12, 14 or 16 bits) that holds them: a dark
        # first image alone would have set too few bits, and the later ones clipped to white
        self._bits = min(16, max(8, top.bit_length() + top.bit_length() % 2))
        scale = f"divided by {1 << (self._bits - 8)}" if self._bits > 8 else "as they are"
        warnings.warn(f"{self.source}: 16-bit images (values up to {top} in {seen} of them, "
                      f"spread over the folder): read as {self._bits}-bit and scaled to 8 "
                      f"bits (values {scale}); values above {(1 << self._bits) - 1} in other "
                      "images are clipped to white", RuntimeWarning, stacklevel=3)

    def _to_8bit(self, im: np.ndarray) -> np.ndarray:
        """An image of 8 bits a channel (:meth:`_decode` gives 8 or 16): 16-bit ones scaled
        down by the folder's depth to the nearest level (:meth:`_depth`; clipped above it,
        counted in ``_clipped``)."""
        if im.dtype == np.uint8:
            return im
        bits = self._bits if self._bits is not None else 16
        top = (1 << bits) - 1
        if bits < 16 and im.max() > top:
            self._clipped += 1
            im = np.minimum(im, top)
        shift = bits - 8
        if shift == 0:
            return im.astype(np.uint8)
        # to the nearest level, in 32 bits (65535 + 128 wraps around in 16), then the clip
        # (65535 rounds up to 256)
        wide = im.astype(np.uint32) + (1 << (shift - 1))
        return np.minimum(wide >> shift, 255).astype(np.uint8)

    def _decode(self, path: Path) -> tuple[np.ndarray | None, str]:
        """The image, 8-bit, or 16-bit where the file is unsigned 16-bit (PNG, TIFF), or None
        and why not. Other depths (signed, floating point) are read as ``cv2.imread``
        reads them, at 8 bits.

        A JPEG is read once: its bytes are checked for the image's end-of-image marker (data
        after it are fine) and decoded from memory, as ``cv2.imread`` decodes the file."""
        cv2 = _cv2()
        # colour even for a grey reader (:meth:`_load` converts): OpenCV's own grey decoding
        # (a JPEG's luma, a PNG's rounding) differs by a level from the BGR image converted,
        # as a frame given in colour is converted, in half the pixels of a colour PNG
        plain = cv2.IMREAD_COLOR
        flags = plain | cv2.IMREAD_ANYDEPTH
        unreadable = "not a readable image (OpenCV cannot decode it: corrupt or truncated)"
        try:  # a file that cannot be read at all (a broken link, an I/O error) says so, and
            # is skipped as one that does not decode (it raised, or was called corrupt)
            data = path.read_bytes() if path.suffix.lower() in (".jpg", ".jpeg") else b""
            if not data and not path.is_file():
                raise FileNotFoundError(2, "No such file or directory", str(path))
        except OSError as e:
            return None, f"not a readable image: the file cannot be read ({e.strerror or e})"
        if path.suffix.lower() not in (".jpg", ".jpeg"):
            pages = _pages(path)
            if pages > 1:
                raise _stack_error(path, pages)
            tiff = path.suffix.lower() in (".tif", ".tiff")
            im = _quietly(cv2.imread, str(path), flags) if tiff else cv2.imread(str(path), flags)
            if tiff and (im is None or im.dtype.kind == "f"):
                # OpenCV decodes a TIFF of floating-point samples in their own depth only (it
                # was called corrupt, grey or colour): 0 to 1 read as 8 bits, as a float image
                # is by convention
                raw = im if im is not None else _quietly(cv2.imread, str(path),
                                                         cv2.IMREAD_UNCHANGED)
                if raw is not None and raw.dtype.kind == "f":
                    return _float_as_8bit(raw)
            if im is not None and im.dtype not in (np.uint8, np.uint16):
                im = cv2.imread(str(path), plain)
            return (None, unreadable) if im is None else (im, "")
        if data[:2] == b"\xff\xd8" and _jpeg_end(data) is None:
            return None, (f"a JPEG cut short (its {len(data)} bytes end before its end-of-image "
                          "marker FF D9): truncated or corrupt")
        try:
            im = cv2.imdecode(np.frombuffer(data, np.uint8), flags) if data else None
        except cv2.error:
            im = None
        return (None, unreadable) if im is None else (im, "")

    def _image(self, path: Path) -> np.ndarray | _Note:
        """The image of one file, or (``skip_bad``) the note that it was skipped."""
        im, why = self._load(path)
        if im is not None and (im.shape[1], im.shape[0]) != self.size:
            why = (f"image is {im.shape[1]}x{im.shape[0]}, but {self._first.name}, the first "
                   f"image, is {self.size[0]}x{self.size[1]} (a folder's images must have one "
                   "size)")
            im = None
        if im is None:
            if not self.skip_bad:
                raise VideoError(f"{path}: {why}")
            return _Note(f"{path}: {why}; skipped")
        return im

    def _frame(self, index: int, image: np.ndarray) -> Frame:
        return Frame(index, (index - 1) / self.fps, image)

    def __iter__(self) -> Iterator[Frame]:
        if self.prefetch == 0:
            for f in self._frames():
                if isinstance(f, _Note):
                    warnings.warn(f, RuntimeWarning, stacklevel=2)
                else:
                    yield f
            return
        import queue
        import threading

        q: queue.Queue = queue.Queue(maxsize=self.prefetch)
        stop = threading.Event()
        end = object()

        def hand(item: object) -> bool:
            # to the caller, unless it has stopped reading (then nothing takes from the
            # queue: a put that waits for room would wait for ever, and the caller's join
            # with it)
            while not stop.is_set():
                try:
                    q.put(item, timeout=0.1)
                    return True
                except queue.Full:
                    continue
            return False

        def work() -> None:
            # what goes wrong is handed to the caller's thread, in order: the notes of a
            # truncated file or a skipped image (warned there, not here: the warnings machinery
            # is not thread-safe) and the error
            try:
                for f in self._frames():
                    if not hand(f):
                        return
                hand((end, None))
            except BaseException as exc:
                hand((end, exc))

        t = threading.Thread(target=work, name="vistrack-video-reader", daemon=True)
        t.start()
        try:
            while True:
                item = q.get()
                if isinstance(item, tuple) and item[0] is end:
                    if item[1] is not None:
                        raise item[1]
                    return
                if isinstance(item, _Note):
                    warnings.warn(item, RuntimeWarning, stacklevel=2)
                else:
                    yield item
        finally:
            stop.set()
            t.join()

    def _frames(self) -> Iterator[Frame | _Note]:
        # the frames, and a note where none lies at or after a start past the first frame
        # (a start past the end yielded nothing, without a word)
        read = False
        for item in self._read_frames():
            read = read or not isinstance(item, _Note)
            yield item
        last = (max(self._index, default=0) if self._files is not None
                else self.frame_count or None)
        if not read and self.start > 1 and (last is None or self.start > last):
            what = "folder's images end" if self._files is not None else "video ends"
            yield _Note(f"{self.source}: no frame from start = {self.start} on: the {what} "
                        "before it")

    def _read_frames(self) -> Iterator[Frame | _Note]:
        # frames in order, and the notes of a file that stops early or an image skipped
        last = self.frame_count if self.stop is None else min(self.stop, self.frame_count)
        if self._files is not None:
            for k, path in zip(self._index, self._files):
                if k < self.start:
                    continue
                if k > last:
                    return
                clipped = self._clipped
                im = self._image(path)
                yield im if isinstance(im, _Note) else self._frame(k, im)
                if clipped == 0 and self._clipped:
                    bits = self._bits or 16  # set where anything is clipped
                    yield _Note(f"{path}: values above {(1 << bits) - 1}, the folder's "
                                f"{bits}-bit depth, clipped to white (here and in any later "
                                "image that has them)")
            return
        cv2 = _cv2()
        cap = cv2.VideoCapture(str(self.source))
        try:
            # a stream without a count may accept a seek and not move, and a transport or
            # program stream (.ts, .mts, .mpg) lands on another frame than it reports (H.264
            # in .ts: frame 31 for any start from 2 to 30): those are read through
            # too; so is a start past the header's count, where a seek lands on the last
            # frame counted (a header of 10 for 20 frames gave frame 11 as frame 15, and on,
            # without a word), and any seek that does not land where it was sent
            if self.start > 1:
                # the frame before the start, or the last the header counts (a start past
                # it: read on from there), where a seek lands where it was sent
                at = 0
                if self._seek_count > 0 and self.source.suffix.lower() in _SEEKABLE:
                    at = min(self.start - 1, self._seek_count - 1)
                    if at and not (cap.set(cv2.CAP_PROP_POS_FRAMES, at)
                                   and cap.get(cv2.CAP_PROP_POS_FRAMES) == at
                                   and _at_its_time(cap, at, self.own_fps, self.source)):
                        at = 0
                if at == 0 and cap.get(cv2.CAP_PROP_POS_FRAMES) != 0:  # (moved: from the first)
                    cap.release()
                    cap = cv2.VideoCapture(str(self.source))
                for j in range(at + 1, self.start):
                    if not cap.grab():
                        if j <= last:  # (as a read that stops: said)
                            yield _Note(f"{self.source}: reading stopped at frame {j} of the "
                                        f"{self.frame_count} its header gives (truncated or "
                                        "corrupt)")
                        return
            # to the end of the file, whatever its header's count (a frame past it is read
            # too), or to stop
            k = self.start
            while self.stop is None or k <= self.stop:
                ok, im = cap.read()
                if not ok or im is None:
                    if k <= last:
                        yield _Note(f"{self.source}: reading stopped at frame {k} of the "
                                    f"{self.frame_count} its header gives (truncated or "
                                    "corrupt)")
                    return
                if self.grey:
                    im = bgr_to_grey(im)
                yield self._frame(k, im)
                k += 1
        finally:
            cap.release()


def _quietly(read: Any, *args: Any) -> Any:
    """``read(*args)`` with OpenCV's log silenced (its decoders' errors and warnings, which
    a fallback after them makes misleading)."""
    from cv2.utils import logging as cv_log

    level = cv_log.getLogLevel()
    cv_log.setLogLevel(cv_log.LOG_LEVEL_SILENT)
    try:
        return read(*args)
    finally:
        cv_log.setLogLevel(level)


def _float_as_8bit(raw: np.ndarray) -> tuple[np.ndarray | None, str]:
    """A floating-point image (a TIFF's samples) as 8-bit BGR: values from 0 to 1 times 255,
    rounded; or None and why, where they lie outside (their scale unknown)."""
    cv2 = _cv2()
    if not (np.isfinite(raw).all() and raw.min() >= 0 and raw.max() <= 1):
        return None, (f"floating-point samples from {float(np.nanmin(raw)):g} to "
                      f"{float(np.nanmax(raw)):g}, which are read from 0 to 1 only: write the "
                      "frames as 8- or 16-bit images, or scaled to 0-1")
    im = np.round(raw.astype(np.float64) * 255).astype(np.uint8)
    if im.ndim == 2 or im.shape[2] == 1:
        return cv2.cvtColor(im, cv2.COLOR_GRAY2BGR), ""
    return (cv2.cvtColor(im, cv2.COLOR_BGRA2BGR) if im.shape[2] == 4 else im[..., :3]), ""


def _may_be_deep(path: Path) -> bool:
    """Whether an image may hold 16 bits a channel: a TIFF, or a PNG whose header says so
    (its bit depth, byte 24; read without decoding it). JPEGs and 8-bit PNGs do not."""
    suffix = path.suffix.lower()
    if suffix in (".tif", ".tiff"):
        return True
    if suffix != ".png":
        return False
    try:
        with open(path, "rb") as f:
            head = f.read(25)
    except OSError:
        return False
    return len(head) == 25 and head[:8] == b"\x89PNG\r\n\x1a\n" and head[24] == 16


def _opencv_name(path: Path, name: str | None = None) -> None:
    """Refuse a path that is not UTF-8 text (bytes a file system holds, which Python keeps
    as surrogates): OpenCV's readers and writer take such a name and end the process
    (a segmentation fault, status 139, no word, partial files left)."""
    try:
        os.fsencode(path).decode("utf-8")
    except UnicodeDecodeError:
        raise VideoError(f"{str(name or path)!r}: the name is not UTF-8 text, which OpenCV "
                         "cannot open (it stops the process): rename it") from None


_SEEKABLE = frozenset({".mp4", ".m4v", ".mov", ".mkv", ".webm", ".avi"})
"""Containers whose frame index OpenCV seeks to exactly (each checked against a reading
through, frame by frame), where their frames come at a constant rate (:func:`_at_its_time`);
a video of another is read through to its start."""

_ESTIMATED_COUNT = frozenset({".mkv", ".webm"})
"""Containers whose frame count OpenCV estimates from the duration (Matroska holds none)."""


def _at_its_time(cap: Any, at: int, fps: float | None, source: Path) -> bool:
    """Whether a capture sent to frame ``at`` (``CAP_PROP_POS_FRAMES``) lies at the time a
    constant rate puts it, against frame 1's (B-frames in an AVI put every frame one or two
    frames late), within half a frame: a seek in a video of variable rate (a phone's)
    reports the frame sent to and lands on another (frame 30 of one whose second half is 5
    times slower showed frame 49), which a reading through does not."""
    import cv2

    if not fps:
        return False
    step = 1000.0 / fps
    probe = cv2.VideoCapture(str(source))
    try:
        if not (probe.set(cv2.CAP_PROP_POS_FRAMES, 1)
                and probe.get(cv2.CAP_PROP_POS_FRAMES) == 1):
            return False
        first = probe.get(cv2.CAP_PROP_POS_MSEC)
    finally:
        probe.release()
    off = cap.get(cv2.CAP_PROP_POS_MSEC) - (at - 1) * step - first
    return bool(abs(off) <= 0.5 * step)


def _mp4_rate(fps: float, pixels: int) -> float:
    """``fps``, or the nearest rate an MP4 of ``pixels`` pixels a frame holds where it holds
    no such rate.

    OpenCV writes a rate as the fraction ``round(fps 10^k) / 10^k`` within 0.001 of it,
    reduced, and MPEG-4 holds a time base whose denominator is at most 65,535 (and not 0):
    29.97 frames a second (2997/100) is held, 12345.678 (6172839/500) and 100000 are not,
    nor 0.001 (0 at a thousandth's precision). And OpenCV sets the bit rate to the pixels a
    second, rounded: where that is 0 (a 16x16 image at 0.0019 frames a second, 4x4 at 0.01)
    libavcodec aborts the process at the first frame. Such rates get the nearest whole rate
    up to 65,535 at or above ``1 / pixels``, or below 1 frame a second the nearest whole
    number of seconds a frame up to 500.

    >>> _mp4_rate(29.97, 768 * 576), _mp4_rate(1e5, 768 * 576), _mp4_rate(12345.678, 64)
    (29.97, 65535.0, 12346.0)
    >>> _mp4_rate(0.001, 768 * 576), _mp4_rate(0.01, 16), _mp4_rate(0.01, 4)
    (0.002, 0.0625, 0.25)
    """
    lo = 1.0 / max(pixels, 1)
    base = 1
    rate = int(fps + 0.5)
    while abs(rate / base - fps) > 0.001 and base < 10**9:
        base *= 10
        rate = int(fps * base + 0.5)
    if fps >= lo and 0 < rate // math.gcd(rate, base) <= 65535:
        return fps
    f = max(fps, lo)
    if f >= 1:
        return float(min(max(round(f), 1), 65535))
    return 1.0 / min(max(math.floor(1.0 / f), 1), 500)


class VideoWriter:
    """Write frames to an MP4 file (``mp4v``), as a context manager.

    Parameters
    ----------
    path : str or Path
        The file to write; its folder is created (at the first frame).
    fps : float
        Frames per second; a rate an MP4 cannot hold (100000, 12345.678) is written as the
        nearest one it can, with a warning.
    size : (width, height), optional
        Default: the first frame's.
    name : str or Path, optional
        What messages call the file (default ``path``: a partial file's final name).

    The file is written at ``path`` as the frames come: a run stopped midway leaves the
    frames written so far there. :class:`~vistrack.viz.AnnotatedVideo` writes to a partial
    file and renames it over its path when complete.

    Attributes
    ----------
    frames : int
        Frames written so far.

    Raises
    ------
    ValueError
        If ``fps`` is not a finite number > 0, ``size`` not two whole numbers >= 1, or
        ``path`` (``name``, where given) ends in an image's suffix (``.png``, ``.jpg``).

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "a.mp4"
    >>> with VideoWriter(p, fps=10) as w:
    ...     for k in range(5):
    ...         w.write(np.full((32, 48, 3), 50 * k, np.uint8))
    >>> r = VideoReader(p)
    >>> len(r), r.size, r.fps
    (5, (48, 32), 10.0)
    """

    def __init__(self, path: str | Path, fps: float, size: tuple[int, int] | None = None, *,
                 name: str | Path | None = None):
        fps = as_finite(fps, "fps", 0.0, above=True)
        if size is not None:
            # (64.5 met OpenCV's overload error, (0, 0) "cannot write an MP4 here", (64,) an
            # IndexError)
            try:
                w, h = size
            except (TypeError, ValueError):
                raise ValueError(f"size must be (width, height); got {size!r}") from None
            size = (as_whole(w, "size's width", 1, "pixels"),
                    as_whole(h, "size's height", 1, "pixels"))
        self.path, self.fps, self.size = Path(path), fps, size
        self.name = str(path if name is None else name)
        suffix = Path(self.name).suffix.lower()
        if suffix in IMAGE_SUFFIXES + (".gif", ".webp"):
            # (OpenCV's image-sequence writer took it: every frame after the first failed to
            # write under the one name, unsaid, and the file held no frame a reader decodes)
            raise ValueError(f"path {self.name}: {suffix} is an image's suffix; VideoWriter "
                             "writes a video (.mp4)")
        self._w: cv2.VideoWriter | None = None
        self._closed = False
        self.frames = 0

    def _open(self, size: tuple[int, int]) -> None:
        cv2 = _cv2()
        _opencv_name(self.path, self.name)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        play = _mp4_rate(self.fps, size[0] * size[1])
        if play != self.fps:
            warnings.warn(f"{self.name}: plays at {play:g} frames a second, the nearest rate "
                          f"an MP4 holds to {self.fps:g}", UserWarning, stacklevel=3)
            self.fps = play
        # MP4 (mp4v) holds even sizes only: OpenCV's encoder cut an odd width's last column
        # and an odd height's last row; such frames are padded by one instead (write)
        even = (size[0] + size[0] % 2, size[1] + size[1] % 2)
        w = cv2.VideoWriter(str(self.path), cv2.VideoWriter_fourcc(*"mp4v"), self.fps, even)
        if not w.isOpened():
            # (kept before this was refused: the next frame found a writer unopened and no
            # size, an AssertionError, and close() said nothing of a video never written)
            w.release()
            raise VideoError(f"{self.name}: OpenCV cannot write an MP4 here")
        self._w = w
        self.size = size

    def write(self, image: np.ndarray) -> None:
        """Append a ``(H, W, 3)`` BGR or ``(H, W)`` grey uint8 frame of the writer's size.

        The first frame opens the file (at ``size``, or the frame's own size). MP4 holds even
        sizes only: a frame of odd width or height is written with its last column or row
        repeated once, so the video is a pixel wider or taller and loses none of it (OpenCV's
        encoder cut them).

        Parameters
        ----------
        image : (H, W, 3) or (H, W) uint8 ndarray
            The frame; grey frames are written as BGR.

        Raises
        ------
        ValueError
            If ``image`` is not such an array, has no pixels, or its size is not the video's.
        VideoError
            If OpenCV cannot open the file for writing (the writer is left as it was: a
            frame given again tries again).

        Examples
        --------
        >>> import tempfile
        >>> w = VideoWriter(Path(tempfile.mkdtemp()) / "grey.mp4", fps=25)
        >>> w.write(np.zeros((16, 16), np.uint8))
        >>> w.frames, w.size
        (1, (16, 16))
        >>> w.close()
        """
        if self._closed:  # (a new file was begun over the closed one's frames)
            raise ValueError(f"{self.name}: write after close: the video is finished, with "
                             f"{self.frames} frames")
        im = np.asarray(image)
        if im.dtype != np.uint8 or im.ndim not in (2, 3) or (im.ndim == 3 and im.shape[2] != 3):
            raise ValueError(f"{self.name}: frame {self.frames + 1}: image must be (H, W) or "
                             f"(H, W, 3) uint8; got {im.shape} {im.dtype}")
        size = (im.shape[1], im.shape[0])
        if 0 in size:  # (OpenCV "cannot write an MP4 here", the file blamed for the frame)
            raise ValueError(f"{self.name}: frame {self.frames + 1} has no pixels: its shape is "
                             f"{im.shape}")
        if self.size is not None and size != self.size:
            # (before the file is begun: a first frame refused replaced an existing video
            # with an empty, unreadable one)
            raise ValueError(f"{self.name}: frame {self.frames + 1} is {size[0]}x{size[1]}; the "
                             f"video is {self.size[0]}x{self.size[1]}")
        if self._w is None:
            self._open(self.size or size)
        assert self._w is not None and self.size is not None  # both set by _open
        if im.ndim == 2:
            im = np.repeat(im[:, :, None], 3, axis=2)
        if size[0] % 2 or size[1] % 2:  # the last column or row repeated (see _open)
            im = np.pad(im, ((0, size[1] % 2), (0, size[0] % 2), (0, 0)), mode="edge")
        self._w.write(np.ascontiguousarray(im))
        self.frames += 1

    def abandon(self) -> None:
        """Release the file without checking it (a run that failed, whose file is removed):
        a check there would put its own error in the failure's place."""
        self._closed = True
        if self._w is not None:
            self._w.release()
            self._w = None

    def close(self) -> None:
        """Finish the file (nothing is written if no frame was); closing twice is harmless.

        Raises
        ------
        VideoError
            If the file does not hold every frame written (OpenCV's writer does not say
            when a write fails: a full disk, or a limit on a file's size).

        Examples
        --------
        >>> import tempfile
        >>> w = VideoWriter(Path(tempfile.mkdtemp()) / "a.mp4", fps=25)
        >>> w.write(np.zeros((16, 16, 3), np.uint8))
        >>> w.close(); w.close()
        >>> len(VideoReader(w.path))
        1
        """
        self._closed = True
        if self._w is not None:
            self._w.release()
            self._w = None
            # OpenCV's writer says nothing of a write that failed (a full disk, a limit on a
            # file's size): a video cut short, without its index, was taken for complete and
            # replaced a good one. Its frames are counted back from the file's own index,
            # where an MP4 keeps an exact count (other containers' counts are estimates)
            if self.path.suffix.lower() not in (".mp4", ".m4v", ".mov"):
                return
            cap = _cv2().VideoCapture(str(self.path))
            got = int(cap.get(_cv2().CAP_PROP_FRAME_COUNT)) if cap.isOpened() else 0
            cap.release()
            if got != self.frames:
                raise VideoError(f"{self.name}: the video file holds {got} of the "
                                 f"{self.frames} frames written to it: the disk is full, or "
                                 "a limit on a file's size was reached")

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

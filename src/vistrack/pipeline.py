"""Where the stages meet: one loop, source → detector → tracker → sinks.

:func:`run` is the loop: for each :class:`~vistrack.types.Frame` of a source, the detector
gives its :class:`~vistrack.types.Detections`, the tracker (any
:class:`~vistrack.tracking.Tracker`) its :class:`~vistrack.types.Tracks`, and every sink
(:class:`~vistrack.io.tracks.Sink`) takes them. It never asks which parts it has.

The parts are chosen by name from registries that list the valid names when one is wrong:
:data:`FRONTENDS` (frames to detections), :data:`TRACKERS` (box trackers' presets, the
detector-confidence particle filter, the single-object trackers, or ``module:callable``,
any tracker of your own) and :data:`SINKS` (the files of a run). :func:`track_sequence`,
:func:`track_video` and :func:`track_one` assemble them for the command line
(:mod:`vistrack.cli`) and call :func:`run`;
:func:`vistrack.evaluation.evaluate_files` scores results files.
"""

from __future__ import annotations

import importlib
import itertools
import math
import os
import re
import threading
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field, fields, replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _compile
from ._memory import PeriodicRelease
from ._pool import counted, frames_text
from ._registry import Registry
from ._validate import MAX_PIXELS
from .config import OfflineConfig, TrackConfig
from .detector_checks import (
    detector_grid,
    first_box,
    ordinal,
    row_line,
    stride_warning,
    undelivered_frames,
    undelivered_text,
    undelivered_warning,
    warn_classes,
    warn_duplicates,
    warn_long_silence,
    warn_no_area,
    warn_outside,
)
from .evaluation.mot import MOTCounts, check_zero_distance, considered, evaluate_mot
from .evaluation.sanity import sanity_warnings
from .io.atomic import (
    Input,
    check_not_input,
    check_output,
    force_option,
    made_folder,
    remove_on_commit,
    staging,
    together,
)
from .io.motchallenge import (
    DETECTION_SUFFIXES,
    PARQUET_DETECTIONS,
    MOTFormatError,
    MOTTable,
    SeqInfo,
    _ground_truth_file,
    box_decimals,
    need_parquet,
    read_mot,
    read_seqinfo,
    sequence_name,
    write_mot,
)
from .io.tracks import BoxesWriter, CSVWriter, MOTWriter, PointsCSVWriter, Sink
from .models.box import FRAME_RATES, BoxMotion
from .tracking.base import Tracker, check_start_box
from .tracking.box import BoxTracker, BoxTrackerConfig
from .tracking.calibration import TOP_PERSISTS, NoOutcomesError, ScoreCalibration
from .tracking.offline import SmoothedTracks, smooth
from .types import Detections, Frame, Tracks

if TYPE_CHECKING:
    from typing import TextIO

    from numpy.typing import ArrayLike

    from .frontends.detectors import ConfidenceMap, Detector
    from .io.video import VideoReader
    from .tracking.fit import MotionFit, Series

__all__ = ["run", "LoopStats", "Context", "Registry", "FRONTENDS", "TRACKERS", "SINKS",
           "as_detector", "make_tracker", "track_sequence", "TrackRun", "resolve_config",
           "derived_values", "calibration_warning", "start_warning", "track_video",
           "VideoRun", "track_one", "SingleRun", "video_outputs", "RUN_INFO", "fit_sequences",
           "FitRun"]


@dataclass(frozen=True)
class TrackRun:
    """What :func:`track_sequence` did: the results file, frames, tracks, tracker time, the
    configuration used and the values derived from the data (:func:`derived_values`).

    Attributes
    ----------
    out : Path
        The results file written.
    frames : int
        Frames in the sequence.
    detections : int
        Rows of the detections file.
    rows : int
        Rows written.
    tracks : int
        Distinct identities written.
    seconds : float
        Seconds spent tracking (with the offline mode's calibration and smoothing).
    config : TrackConfig or None
        The configuration used (its motion filled in).
    derived : dict or None
        :func:`derived_values` of the tracker, with ``detection_stride`` where the detections lie on
        every k-th frame only (:func:`~vistrack.detector_checks.detection_stride`; the tracker's
        ``frame_rate`` is then the sequence's divided by k), and ``undelivered_frames``, their
        number, where frames without detections lie amid frames with many
        (:func:`~vistrack.detector_checks.undelivered_frames`).
    replaced_rate : (str, float) or None
        Where ``fps`` was put over the frame rate of the sequence's ``seqinfo.ini``:
        ``("seqinfo.ini", its frameRate)``; None otherwise.

    Examples
    --------
    >>> run = TrackRun(Path("out.txt"), frames=100, detections=900, rows=800, tracks=12,
    ...                seconds=0.5)
    >>> run.fps
    200.0
    """

    out: Path
    frames: int
    detections: int
    rows: int
    tracks: int
    seconds: float
    config: TrackConfig | None = None
    derived: dict | None = None
    replaced_rate: tuple[str, float] | None = None

    @property
    def fps(self) -> float:
        """Frames tracked per second of tracking.

        Examples
        --------
        >>> TrackRun(Path("out.txt"), 100, 900, 800, 12, 0.25).fps
        400.0
        """
        return self.frames / max(self.seconds, 1e-12)


def _progress(done: int, total: int, label: str, stream: TextIO | None) -> None:
    if stream is None:
        return
    width = 30
    k = int(width * done / max(total, 1))
    stream.write(f"\r{label} [{'#' * k}{'.' * (width - k)}] {done}/{total}")
    if done == total:
        stream.write("\n")
    stream.flush()


_OFFLINE_KEYS = {f.name for f in fields(OfflineConfig)}
_TRACKER_KEYS = {f.name for f in fields(BoxTrackerConfig)}


def resolve_config(config: TrackConfig | str | os.PathLike | None = None, *,
                   tracker: str | None = None,
                   offline: bool | None = None, **overrides: Any) -> TrackConfig:
    """The configuration of a run: ``config`` (a :class:`~vistrack.config.TrackConfig` or a
    preset's name; default the ``tracker`` preset, else ``bytetrack``), with ``offline`` and
    ``overrides`` (fields of the tracker's or the offline mode's settings, or ``motion``, a
    :class:`~vistrack.models.BoxMotion`) put over it.

    Parameters
    ----------
    config : TrackConfig, str, path or None
        The configuration, a preset's name in :data:`vistrack.tracking.TRACKERS`, or a
        configuration file (a path, or a name ending in ``.toml``), as ``vistrack track
        --config FILE`` takes it (:func:`~vistrack.config.read_config`, over the ``tracker``
        preset where given).
    tracker : str, optional
        A preset's name; it must agree with ``config`` when both are given.
    offline : bool, optional
        Turn the offline mode on or off (None: as ``config`` has it).
    **overrides
        Fields of :class:`~vistrack.tracking.BoxTrackerConfig` or
        :class:`~vistrack.config.OfflineConfig`, or ``motion``; None values are left alone.

    Returns
    -------
    TrackConfig
        The configuration of the run.

    Raises
    ------
    ValueError
        If ``tracker`` and ``config`` disagree, a preset is unknown, or a value is invalid.
    TypeError
        If an override names no field.

    Examples
    --------
    >>> cfg = resolve_config("sort", high=0.5, max_gap=2.0)
    >>> cfg.name, cfg.tracker.high, cfg.offline.max_gap, cfg.offline.enabled
    ('sort', 0.5, 2.0, False)
    >>> resolve_config(offline=True).offline.enabled
    True
    """
    from .tracking.box import TRACKERS as BOX_PRESETS

    if isinstance(config, os.PathLike) or (isinstance(config, str)
                                           and config not in BOX_PRESETS
                                           and (config.lower().endswith(".toml")
                                                or os.sep in config or "/" in config)):
        # a configuration file, as `vistrack track --config FILE` takes (it was taken for a
        # preset's name: "tracker must be one of ['bytetrack', 'sort']; got 'used.toml'")
        from .config import read_config

        config = read_config(config, TrackConfig.preset(tracker) if tracker else None)
    if isinstance(config, str) or config is None:
        if isinstance(config, str) and tracker is not None and tracker != config:
            raise ValueError(f"tracker {tracker!r} and config {config!r} disagree")
        config = TrackConfig.preset(config if isinstance(config, str) else tracker or
                                    "bytetrack")
    elif tracker is not None and tracker != config.name:
        raise ValueError(f"tracker {tracker!r} and the configuration's {config.name!r} "
                         "disagree; give one")
    motion = overrides.pop("motion", None)
    unknown = sorted(set(overrides) - _OFFLINE_KEYS - _TRACKER_KEYS)
    if unknown:  # named here: the dataclass would say it of its __init__
        raise TypeError(f"{unknown[0]} is no setting of the box tracker or the offline mode "
                        f"(those are {', '.join(sorted(_TRACKER_KEYS | _OFFLINE_KEYS))}, and "
                        "motion)")
    off = {k: overrides.pop(k) for k in list(overrides) if k in _OFFLINE_KEYS}
    if offline is not None:
        off["enabled"] = bool(offline)
    config = config.with_values(tracker=overrides, offline=off)
    return replace(config, motion=motion) if motion is not None else config


def derived_values(trk: BoxTracker) -> dict:
    """What a box tracker derived from the data it has tracked: its frame rate, its motion's
    per-frame noise at that rate, and with calibrated scores the raw score at which each
    threshold's confidence is reached (:meth:`ScoreCalibration.score_at`), with what the
    calibration was fitted to.

    Parameters
    ----------
    trk : BoxTracker
        A box tracker (that has tracked a sequence, for the calibration's values).

    Returns
    -------
    dict
        ``frame_rate``, ``image_size`` (when the tracker has one), ``std_pos_per_frame`` and
        ``std_vel_per_frame``; with calibrated scores also ``calibration`` (``"whole file"``
        or ``"online, at the last frame"``), ``calibration_outcomes``,
        ``calibration_top_persistence`` (when fitted to outcomes), ``calibration_link_iou``
        (the overlap a whole file's calibration linked detections at, offline) and
        ``high_score``, ``low_score`` and ``new_track_score`` (for the threshold tracks
        started at: offline, the offline mode's ``start_score`` where it is above
        ``new_track``); where the detections are of several classes, each class calibrated
        apart, these are dicts by class (the class as a string).

    Examples
    --------
    >>> trk = BoxTracker("sort", frame_rate=25.0, scores="raw")
    >>> sorted(derived_values(trk))
    ['frame_rate', 'std_pos_per_frame', 'std_vel_per_frame']
    """
    c, m = trk.config, trk.motion
    out: dict = {"frame_rate": trk.frame_rate}
    if trk.image_size is not None:
        out["image_size"] = [int(v) for v in trk.image_size]
    out.update({"std_pos_per_frame": float(m.std_pos), "std_vel_per_frame": float(m.std_vel)})
    maps = trk.score_calibrations()
    if maps:
        out["calibration"] = "whole file" if trk.calibration is not None else \
            "online, at the last frame"
        if isinstance(trk.calibration, dict) and trk.calibrators:  # a class with nothing
            # to fit in the whole file learnt online
            online = ", ".join(str(k) for k in sorted(trk.calibrators))
            out["calibration"] = f"whole file; online, at the last frame, for class {online}"

        def each(value: Callable[[ScoreCalibration], Any], fitted: bool = False) -> Any:
            # one class: its value; several: a dict by class
            got = {str(k): value(cal) for k, cal in sorted(maps.items())
                   if cal.n or not fitted}
            return next(iter(got.values())) if len(maps) == 1 else got

        out["calibration_outcomes"] = each(lambda cal: cal.n)
        if any(cal.n for cal in maps.values()):
            out["calibration_top_persistence"] = each(
                lambda cal: round(cal.top_persistence, 6), fitted=True)
        links = {str(k): cal.link_iou for k, cal in sorted(maps.items())
                 if np.isfinite(cal.link_iou)}
        if links:  # the whole file's overlap (offline: loosened where nothing persists;
            # not [tracker] calibration_iou, the setting it starts from)
            out["calibration_link_iou"] = (next(iter(links.values())) if len(maps) == 1
                                           else links)
        for name in ("high", "low", "new_track"):
            out[f"{name}_score"] = each(partial(ScoreCalibration.score_at,
                                                level=getattr(c, name)))
    return out


def start_warning(trk: Any, name: str) -> str | None:
    """Why a detector-confidence particle filter's run started no target, as a warning, or
    None: its ``init_score`` (0.75 by default, for the confidence front end's scores in
    (0, 1)) lies above every detection's score (a detector of another scale, or a setting
    above this detector's).

    Parameters
    ----------
    trk : DetectorConfidencePF
        A tracker that has tracked a sequence (other trackers: None).
    name : str
        What to call the sequence in the message.

    Returns
    -------
    str or None

    Examples
    --------
    >>> from vistrack.tracking import DetectorConfidencePF
    >>> trk = DetectorConfidencePF(gamma=0.0, eta=0.0)
    >>> image = np.zeros((240, 320, 3), np.uint8)
    >>> for f in range(1, 6):
    ...     _ = trk.step(Frame(f, (f - 1) / 30, image), Detections(boxes=[[100, 50, 140, 130]],
    ...                                                         scores=[0.004]))
    >>> print(start_warning(trk, "SEQ"))  # doctest: +NORMALIZE_WHITESPACE
    SEQ: no target started: no detection reached init_score 0.75 (the highest of 5 scored
    0.004); set init_score below the detector's scores (a --config file's [dcpf]
    init_score, or DetectorConfidencePF(init_score=...)): its default, 0.75, is for the
    confidence front end's scores in (0, 1)
    """
    from .tracking.dcpf import DCPFConfig, DetectorConfidencePF

    if not isinstance(trk, DetectorConfidencePF) or not trk.n_scored:
        return None
    cfg = trk.config
    if trk.top_score >= cfg.init_score:
        return None
    seen = ("the only detection" if trk.n_scored == 1 else
            f"the highest of {trk.n_scored:,}")
    return (f"{name}: no target started: no detection reached init_score {cfg.init_score:g} "
            f"({seen} scored {trk.top_score:.3g}); set init_score below the detector's "
            "scores (a --config file's [dcpf] init_score, or "
            f"DetectorConfidencePF(init_score=...)): its default, {DCPFConfig.init_score:g}, "
            "is for the confidence front end's scores in (0, 1)")


def _run_derived(trk: Any) -> dict | None:
    """What a run's tracker derived from the data (``VideoRun.derived``): a box tracker's
    :func:`derived_values`; the detector-confidence particle filter's frame rate and the
    detections' scores it saw (how many, and the highest); None for other trackers."""
    from .tracking.dcpf import DetectorConfidencePF

    if isinstance(trk, BoxTracker):
        return derived_values(trk)
    if isinstance(trk, DetectorConfidencePF):
        out: dict = {"frame_rate": trk.frame_rate, "scored_detections": trk.n_scored}
        if trk.n_scored:
            out["top_score"] = trk.top_score
        return out
    return None


def _warn_calibration(trk: BoxTracker, name: str) -> None:
    """:func:`calibration_warning` as a ``RuntimeWarning`` of the run that called for it (of
    :func:`track_sequence`'s or :func:`track_video`'s caller)."""
    warning = calibration_warning(trk, name)
    if warning is not None:
        warnings.warn(warning, RuntimeWarning, stacklevel=3)


def calibration_warning(trk: BoxTracker, name: str) -> str | None:
    """Why a box tracker's calibrated scores could not be told apart, as a warning, or None.

    The score calibration (:mod:`vistrack.tracking.calibration`) rates a detection by how
    nearly detections of its score persist from frame to frame, and lie on chains that last,
    as the detector's most confident ones do. Where even the least confident detections do
    that nearly as well as the most confident ones (the confidence of the lowest score seen
    reaches ``high``) while the most confident themselves persist less than half the time,
    nothing tells objects from clutter, and every detection counts as confident, clutter
    too: the first association stage takes them all, and where the lowest reaches
    ``new_track`` as well, each starts a track. That happens where hardly anything persists:
    at a low frame rate, objects move too far between frames for their boxes to overlap.
    (Where every detection persists, all are objects, and taking each as confident is
    right.)

    Parameters
    ----------
    trk : BoxTracker
        A box tracker that has tracked a sequence.
    name : str
        What to call the sequence in the message.

    Returns
    -------
    str or None
        The message, naming each class it holds for where the detections are of several
        (each class has a calibration of its own), and the overlap a whole file's calibration
        loosened its links to (offline, :meth:`ScoreCalibration.from_frames`) where it did;
        None with raw scores, before the
        calibration has outcomes, when all scores are equal (nothing to tell apart), when the
        lowest score stays under ``high``, or when the most confident detections persist half
        the time or more.

    Examples
    --------
    >>> trk = BoxTracker("bytetrack", frame_rate=2.0)
    >>> rng = np.random.default_rng(0)
    >>> for f in range(40):  # boxes anywhere in every frame: none persists
    ...     xy = rng.uniform(0, 900, (5, 2))
    ...     _ = trk.step(f + 1, Detections(boxes=np.c_[xy, xy + 40], scores=rng.random(5)))
    >>> print(calibration_warning(trk, "SEQ"))  # doctest: +ELLIPSIS
    SEQ: every detection counts as confident ...
    """
    c = trk.config
    if c.scores != "calibrated":
        return None
    maps = trk.score_calibrations()
    found = []  # (class, what it counts as, its most confident detections' persistence,
    # the overlap its links were loosened to offline, or None)
    for k, cal in sorted(maps.items()):
        if cal.n == 0 or len(cal.scores) < 2:
            continue
        if cal.confidence[0] < c.high or cal.top_persistence >= TOP_PERSISTS:
            continue
        loose = cal.link_iou if cal.link_iou < c.calibration_iou else None  # (NaN: online)
        found.append((k, "confident enough to start a track" if cal.confidence[0] >= c.new_track
                      else "confident (the first association stage takes them all)",
                      cal.top_persistence, loose))
    if not found:
        return None
    raw = "thresholds on the scores themselves may track better (--scores raw with --high, " \
          "--low and --new-track"
    if len(maps) == 1:
        _, what, rate, loose = found[0]
        links = "" if loose is None else f", its links loosened to IoU {loose:g},"
        return (f"{name}: every detection counts as {what}: the score calibration{links} finds "
                f"the least confident persisting from frame to frame nearly as often as the "
                f"most confident, which persist at a rate of {rate:.2f} at "
                f"{trk.frame_rate:.3g} frames/s; {raw})")
    # every class it holds for, each with its own rate
    each = "; ".join(f"every detection of class {k} counts as {what}, its most confident "
                     f"persisting at a rate of {rate:.2f}"
                     + ("" if loose is None else f" with links loosened to IoU {loose:g}")
                     for k, what, rate, loose in found)
    return (f"{name}: {each}: at {trk.frame_rate:.3g} frames/s the score calibration finds the "
            f"least confident of {'that class' if len(found) == 1 else 'each'} persisting from "
            f"frame to frame nearly as often as the most confident; {raw}, for every class)")


# -------------------------------------------------------------------------------- the loop
FrameDetector = Callable[[Frame], Detections]
"""A detector as the loop sees it: one frame to its detections."""


@dataclass(frozen=True)
class LoopStats:
    """What :func:`run` did: the frames it went through, and the seconds spent in each stage
    (``decode``: waiting for the source, ``frontend``, ``tracker``, ``write``: the sinks), and
    compiling kernels (``compile``: counted while the command line watches numba, and left out
    of the stages).

    Attributes
    ----------
    frames : int
        Frames the loop went through.
    seconds : dict of str to float
        Seconds in each stage: ``decode``, ``frontend``, ``tracker``, ``write`` and
        ``compile``.
    last : int
        The index of the last frame it went through (0: none); frames missing from the
        source (an image folder's gaps, images skipped) make it more than the first index
        plus ``frames - 1``.

    Examples
    --------
    >>> from vistrack.tracking import BoxTracker
    >>> stats = run([Frame(1, 0.0), Frame(2, 0.04)], None, BoxTracker())
    >>> stats.frames, sorted(stats.seconds)
    (2, ['compile', 'decode', 'frontend', 'tracker', 'write'])
    """

    frames: int
    seconds: dict
    last: int = 0


def as_detector(detector: Detector | Callable[[Frame], Detections | None] | None
                ) -> Callable[[Frame], Detections | None] | None:
    """A detector as a function of the frame: an object with ``detect(image) ->
    Detections`` (:class:`~vistrack.frontends.Detector`) is called on the frame's image, a
    callable ``frame -> Detections`` is used as it is, and None stays None (the tracker
    finds its own objects).

    Parameters
    ----------
    detector : detector, callable or None
        An object with ``detect(image)``, a callable of the frame, or None.

    Returns
    -------
    callable or None
        ``frame -> Detections``, or None.

    Raises
    ------
    TypeError
        If ``detector`` is none of these.

    Examples
    --------
    >>> from vistrack.frontends import BlobDetector
    >>> callable(as_detector(BlobDetector())), as_detector(None)
    (True, None)
    """
    if detector is None:
        return None
    detect = getattr(detector, "detect", None)
    if callable(detect):
        what = f"the detector {type(detector).__name__}"
        return lambda frame: detect(_image(frame, what))
    if callable(detector):
        return detector
    raise TypeError(f"detector must be an object with detect(image) -> Detections, a callable "
                    f"frame -> Detections, or None; got {type(detector).__name__}")


def run(source: Iterable[Frame], detector: Detector | Callable[[Frame], Detections | None] | None,
        tracker: Tracker, sinks: Iterable[Sink] = (), *, progress: TextIO | None = None,
        total: int | None = None, label: str = "",
        check: Callable[[LoopStats], None] | None = None,
        detector_label: str | None = "the front-end") -> LoopStats:
    """The pipeline's one loop: every frame of ``source`` through ``detector``, ``tracker``
    and ``sinks``.

    Parameters
    ----------
    source : iterable of Frame
        The frames, in order (a :class:`~vistrack.io.VideoReader`, or frames without images
        where only detections are tracked).
    detector : detector, callable or None
        Each frame's detections (:func:`as_detector`).
    tracker : Tracker
        Anything with ``step(frame, detections) -> Tracks``
        (:class:`~vistrack.tracking.Tracker`).
    sinks : iterable of Sink
        Each takes every frame's tracks (``write(frame, tracks)``) and is closed when the
        source ends. If the loop fails, sinks with an ``abort()`` are aborted instead, and
        none is closed: no results file is written from part of a run. If a sink fails to
        close, it and the sinks after it are aborted.
    progress : stream, optional
        Where to draw a progress bar (of ``total`` frames, named ``label``).
    check : callable, optional
        Called with the loop's :class:`LoopStats` once the source has ended, before the
        sinks are closed: if it raises, the sinks are aborted as for a failed loop, so a run
        found wrong at its end (no frame, results that cannot be scored) writes nothing.
    detector_label : str or None
        What the detector is called in the note added to its errors ("at frame 7, in the
        front-end"); None for the frame alone (the detector is the caller's own, such as a
        single-object run's start box).

    Returns
    -------
    LoopStats
        The frames and the seconds of each stage.

    Raises
    ------
    TypeError
        Before any frame: if ``source`` is not iterable, or ``tracker``, a sink or
        ``progress`` is not of the kind described; at a frame: if ``source`` gives one that
        is not a :class:`~vistrack.types.Frame`, or the tracker returns no ``Tracks``.

    Notes
    -----
    Every 10 s of a run, and once more at the end of one that lasted that long, the memory
    the C library holds free is given back to the system
    (``vistrack._memory.PeriodicRelease``), so that an hour of video does not leave the
    process tens of MB larger with freed frame buffers.

    Examples
    --------
    >>> from vistrack.io.tracks import TrackRows
    >>> from vistrack.tracking import BoxTracker
    >>> frames = [Frame(k, (k - 1) / 25) for k in range(1, 4)]
    >>> boxes = lambda f: Detections.from_xywh([[10.0 + 4 * f.index, 20, 30, 60]], [0.9])
    >>> rows = TrackRows()
    >>> run(frames, boxes, BoxTracker(), [rows]).frames
    3
    >>> rows.frames.tolist(), rows.ids.tolist()
    ([1, 2, 3], [1, 1, 1])
    """
    detect = as_detector(detector)
    try:
        frames = iter(source)
    except TypeError:  # ("'int' object is not iterable", naming no argument)
        raise TypeError(f"source must be an iterable of Frame (a VideoReader, a list of "
                        f"Frame); got {type(source).__name__}") from None
    if not callable(getattr(tracker, "step", None)):
        raise TypeError(f"tracker must have step(frame, detections) -> Tracks; got "
                        f"{type(tracker).__name__}")
    if progress is not None and not callable(getattr(progress, "write", None)):
        # (progress=True: "'bool' object has no attribute 'write'", after the first frames)
        raise TypeError(f"progress must be a text stream (sys.stderr, say) or None; got "
                        f"{type(progress).__name__}")
    if isinstance(sinks, Sink):  # (one sink: "'TrackRows' object is not iterable")
        raise TypeError(f"sinks must be a sequence of sinks; got one, a "
                        f"{type(sinks).__name__}: give [sink]")
    try:
        # a list of them, once: a generator was used up by the check below, and its sinks
        # were given no row, unsaid
        sinks = list(sinks)
    except TypeError:
        raise TypeError(f"sinks must be a sequence of sinks; got {type(sinks).__name__}"
                        ) from None
    for k, sink in enumerate(sinks):
        if not isinstance(sink, Sink):
            raise TypeError(f"sinks[{k}] must have write(frame, tracks) and close(); got "
                            f"{type(sink).__name__}")
    sec = dict.fromkeys(("decode", "frontend", "tracker", "write", "compile"), 0.0)
    n = last = 0
    every = max(1, (total or 0) // 50)
    release = PeriodicRelease()  # freed frame buffers back to the system, on long runs
    t0, c0 = time.perf_counter(), _compile.seconds()
    try:
        for frame in frames:
            if not isinstance(frame, Frame):
                # (an image or an index failed on "has no attribute 'index'")
                raise TypeError(f"source must give Frame objects; its frame {n + 1} is a "
                                f"{type(frame).__name__}")
            t1, c1 = time.perf_counter(), _compile.seconds()
            sec["decode"] += (t1 - t0) - (c1 - c0)
            try:
                d = detect(frame) if detect is not None else None
            except Exception as exc:
                _add_note(exc, f"at frame {frame.index}" if detector_label is None
                          else f"at frame {frame.index}, in {detector_label}")
                raise
            t2, c2 = time.perf_counter(), _compile.seconds()
            try:
                tracks = tracker.step(frame, d)
            except Exception as exc:
                _add_note(exc, f"at frame {frame.index}, in {_qualname(tracker)}.step")
                raise
            if not isinstance(tracks, Tracks):
                raise TypeError(f"{_qualname(tracker)}.step returned a {type(tracks).__name__} "
                                f"at frame {frame.index}, not Tracks")
            t3, c3 = time.perf_counter(), _compile.seconds()
            sec["frontend"] += (t2 - t1) - (c2 - c1)
            sec["tracker"] += (t3 - t2) - (c3 - c2)
            for sink in sinks:
                sink.write(frame, tracks)
            n += 1
            last = frame.index
            if total and (n % every == 0 or n == total):
                _progress(n, total, label, progress)
            release()
            t0, c0 = time.perf_counter(), _compile.seconds()
            sec["write"] += (t0 - t3) - (c0 - c3)
            sec["compile"] += c0 - c1
        if check is not None:
            check(LoopStats(n, sec, last))
    except BaseException:
        _abort(sinks)
        raise
    t0 = time.perf_counter()
    for k, sink in enumerate(sinks):
        try:
            sink.close()
        except BaseException:
            _abort(sinks[k:])  # the files not yet complete are given up
            raise
    release.end()
    sec["write"] += time.perf_counter() - t0
    return LoopStats(n, sec, last)


def _qualname(obj: object) -> str:
    """``module.Class`` of an object, as a user would find it in their code."""
    kind = type(obj)
    return f"{kind.__module__}.{kind.__qualname__}"


def _add_note(exc: BaseException, note: str) -> None:
    """Where ``exc`` was raised, as a note (``BaseException.add_note`` from Python 3.11;
    the same ``__notes__`` list before): shown under a traceback, and after the message in
    the command line's one-line errors."""
    if hasattr(exc, "add_note"):
        exc.add_note(note)
    else:  # Python 3.10
        exc.__notes__ = [*getattr(exc, "__notes__", ()), note]  # type: ignore[attr-defined]


def _abort(sinks: Sequence[Sink]) -> None:
    """Call ``abort()`` on the sinks that have one (harmless on one that failed to close)."""
    for sink in sinks:
        abort = getattr(sink, "abort", None)
        if callable(abort):
            abort()


# ---------------------------------------------------------------------------- registries
class _OncePerImage:
    """A confidence ``image -> ConfidenceMap`` evaluated once per image, so that a detector
    and a tracker asking for the same frame's map share it."""

    def __init__(self, confidence: Callable[[np.ndarray], ConfidenceMap]):
        if not callable(confidence):
            raise TypeError(f"confidence must be a callable image -> ConfidenceMap; got "
                            f"{type(confidence).__name__}")
        self.confidence = confidence
        self._last: tuple[np.ndarray, ConfidenceMap] | None = None

    def __call__(self, image: np.ndarray) -> ConfidenceMap:
        if self._last is None or self._last[0] is not image:
            self._last = (image, self.confidence(image))
        return self._last[1]


@dataclass
class Context:
    """What the parts of a run are made from: the source's frame rate and image size, the
    video reader (a background model starts from its first frames), the run's box-tracker
    configuration and settings, and the options of the front-ends.

    Attributes
    ----------
    fps : float
        Frames per second of the source.
    image_size : (width, height) or None
    reader : VideoReader or None
    config : TrackConfig or None
        A box tracker's whole configuration, used as it is.
    overrides : dict
        Settings of the tracker (fields of its configuration).
    options : dict
        Front-end options: ``background``, ``min_area``, ``n_init`` (``bgsub``),
        ``det_threshold`` (``confidence``), ``confidence`` (a callable ``image ->
        ConfidenceMap``; default :class:`~vistrack.frontends.HOGConfidence`).
    resolved : TrackConfig or None
        The configuration a box tracker was made with (set by its maker).
    points : bool
        Whether the run's tracker gives point tracks (its entry's in :data:`TRACKERS`): the
        CSV sink then writes ``frame,particle,x,y``.

    Examples
    --------
    >>> ctx = Context(fps=25.0, overrides={"high": 0.5})
    >>> tracker, frontend = make_tracker("sort", ctx)
    >>> frontend, ctx.resolved.name, ctx.resolved.tracker.high
    ('bgsub', 'sort', 0.5)
    """

    fps: float
    image_size: tuple[int, int] | None = None
    reader: VideoReader | None = None
    config: TrackConfig | None = None
    overrides: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)
    resolved: TrackConfig | None = None
    points: bool = False
    _confidence: _OncePerImage | None = field(default=None, init=False, repr=False)

    @property
    def confidence(self) -> Callable[[np.ndarray], ConfidenceMap]:
        """The run's detector confidence (one per run, once per image).

        ``options["confidence"]``, or a :class:`~vistrack.frontends.HOGConfidence`, made at
        the first call and kept; it evaluates each image once, however many parts ask.

        Examples
        --------
        >>> calls = []
        >>> ctx = Context(fps=25.0, options={"confidence": lambda image: calls.append(1)})
        >>> image = np.zeros((4, 4), np.uint8)
        >>> _ = ctx.confidence(image), ctx.confidence(image)
        >>> len(calls)
        1
        """
        if self._confidence is None:
            conf = self.options.get("confidence")
            if conf is None:
                from .frontends.detectors import HOGConfidence

                conf = HOGConfidence()
            self._confidence = _OncePerImage(conf)
        return self._confidence


def _image(frame: Frame, what: str) -> np.ndarray:
    """The frame's image, or a ValueError naming the frame and the front-end that needs it."""
    if frame.image is None:
        raise ValueError(f"frame {frame.index} has no image; {what} needs the video's frames "
                         f"(for detections read from a file, use --frontend detections:FILE)")
    return frame.image


def _bgsub(ctx: Context) -> FrameDetector:
    from .frontends.blobs import BlobDetector
    from .io.video import VideoReader

    opt, reader = ctx.options, ctx.reader
    det = BlobDetector(opt.get("background", "selective"), min_area=opt.get("min_area", 500.0),
                       follow_view=opt.get("follow_view", True))
    if reader is not None:
        n_init = int(opt.get("n_init", 20))
        with warnings.catch_warnings():
            # the run reads these frames again, and says then what is wrong with them (an
            # image skipped, a file that stops early): not twice
            warnings.filterwarnings("ignore", message=re.escape(str(reader.source)),
                                    category=RuntimeWarning)
            frames = (_image(f, "the background model") for f in VideoReader(
                reader.source, fps=reader.fps, grey=True, start=reader.start,
                stop=reader.start + n_init - 1, skip_bad=reader.skip_bad))
            first = next(frames, None)
            if first is None:  # (as the run says it: not "initialize needs at least one frame")
                raise ValueError(f"{reader.source}: no frames to track")
            det.initialize(itertools.chain([first], frames))
    source = reader.source if reader is not None else "the frames"
    said = False

    def detect(frame: Frame) -> Detections:
        nonlocal said
        found = det.detect(_image(frame, "the background model"))
        if not said and det.view_moves:
            said = True
            shift = det.view_motion
            assert shift is not None  # set once the view moves
            # inf: most checks found no corner of one frame in the next
            how = (f"by {shift:.0f} pixels every {det.check_view} frames, in median"
                   if math.isfinite(shift) else
                   f"further than corners can be followed over {det.check_view} frames, in "
                   "most checks")
            moves = f"{source}: the view moves ({how}; found by frame {frame.index})"
            if det.following_from is not None:
                warnings.warn(
                    f"{moves}: the background model follows it, as a shift of the whole "
                    "image (not a view that turns or zooms), and learns each part of the "
                    "scene as it comes into view; a detector (--frontend hog, or "
                    "onnx:MODEL.onnx) needs no still camera", RuntimeWarning, stacklevel=2)
            else:
                why, instead = (("it is taken as still (--still-camera, or follow_view=False)",
                                 "without --still-camera the background model follows it")
                                if not det.follow_view else
                                ("MOG2's background model cannot follow it",
                                 "the selective model (--background selective, the default) "
                                 "follows it"))
                warnings.warn(
                    f"{moves}: {why}, and the blobs follow the image's motion rather than "
                    f"objects; {instead}, and a detector (--frontend hog, or onnx:MODEL.onnx) "
                    "needs no still camera", RuntimeWarning, stacklevel=2)
        return found

    return detect


def _hog(ctx: Context) -> FrameDetector:
    from .frontends.detectors import HOGDetector

    hog = HOGDetector()
    return lambda frame: hog.detect(_image(frame, "the HOG detector"))


def _confidence_peaks(ctx: Context) -> FrameDetector:
    from .frontends.detectors import ConfidencePeaks

    peaks = ConfidencePeaks(ctx.confidence, ctx.options.get("det_threshold", 0.5))
    return lambda frame: peaks.detect(_image(frame, "the confidence peaks"))


def _onnx(path: str | Path, ctx: Context) -> FrameDetector:
    from .frontends.onnx import ONNXDetector

    det = ONNXDetector(path, layout=ctx.options.get("onnx_layout", "auto"),
                       classes=ctx.options.get("classes"))
    return lambda frame: det.detect(_image(frame, "the ONNX model"))


def _spots(ctx: Context) -> FrameDetector:
    from .frontends.spots import _check_diameter, locate

    opt = ctx.options
    if opt.get("diameter") is None:
        raise ValueError("the spots front-end needs the spots' diameter in pixels, odd "
                         "(diameter=, --diameter): the size of feature it looks for")
    diameter, minmass = _check_diameter(opt["diameter"]), float(opt.get("minmass", 0.0))
    invert = bool(opt.get("invert", False))
    if not (math.isfinite(minmass) and minmass >= 0):
        raise ValueError(f"minmass must be a finite number >= 0; got {opt['minmass']}")
    return lambda frame: locate(_image(frame, "the spots front-end"), diameter,
                                minmass=minmass, invert=invert).detections()


MAX_FRAMES = 10 ** 8
"""The last frame a detections file without a sequence folder is tracked up to (39 days at
30 frames/s): the tracker steps through every frame to its last, and a frame number that is a
timestamp would keep it going for years."""

def _warn_detections_end(grid: _FileDetections, last: int, fps: float) -> None:
    """Warn where a detections file ends before the video's last frame, ``last``, by a
    second or more, by more of its detector's frames than the longest run without rows
    inside the file, and by so many that frames as often with rows as the file's before
    would have left none of them empty by chance below e^-10: the file is more likely one
    for a shorter video, or cut short (the frames after it were tracked without a word). A
    scene that empties at its end, or a video a frame longer than its file, is not said."""
    frames = np.unique(grid.dets.frames)
    end = int(frames[-1])
    tail = (last - end) // grid.stride  # the detector's frames after its last row
    if last - end < fps or tail < 1:
        return
    on_grid = (frames - grid.first) // grid.stride  # the grid frames with rows, 0 first
    longest = int(np.max(np.diff(np.r_[-1, on_grid]) - 1))  # empty grid frames in a row
    share = len(on_grid) / (on_grid[-1] + 1)  # of the grid frames to the end, with rows
    if tail > longest and (share == 1.0 or tail * math.log1p(-share) < -10.0):
        warnings.warn(f"{grid.path}: no rows after frame {end}, where the video runs to frame "
                      f"{last}: frames {end + 1}-{last} were tracked without detections "
                      f"({100 * share:.3g} % of the frames before have some; a file for a "
                      "shorter video, or cut short?)", UserWarning, stacklevel=3)


class _FileDetections:
    """The ``detections:FILE`` front-end: each frame's rows of a detections file, up to the file's
    last frame (none after it: a video may run past its header's count, or give none); ``stride``
    and ``first`` are :func:`~vistrack.detector_checks.detection_stride`'s and the first frame of
    its grid (:func:`track_video` steps a box tracker through those frames alone)."""

    def __init__(self, path: Path, dets: MOTTable,
                 columns: dict[str, str] | None = None) -> None:
        self.path, self.dets, self.columns = path, dets, columns
        self.slices = dets.frame_slices()
        self.first, self.stride = detector_grid(dets.frames)

    def __call__(self, frame: Frame) -> Detections:
        s = self.slices[frame.index - 1] if frame.index <= len(self.slices) else slice(0, 0)
        return Detections.from_xywh(self.dets.boxes[s], self.dets.conf[s], self.dets.classes[s])


def _detections_file(path: str | Path, ctx: Context) -> FrameDetector:
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path} does not exist (--frontend detections:FILE)")
    # MOTChallenge's text, or CSV with a header (its columns named by columns=, --columns)
    columns = ctx.options.get("columns")
    dets = read_detections(path, columns, stacklevel=3)
    return _FileDetections(path, dets, columns)


@dataclass(frozen=True)
class Frontend:
    """A front-end in :data:`FRONTENDS`: ``make(context) -> (frame -> Detections)``, and
    whether it needs a still camera (then the box trackers do not compensate camera
    motion, unless their configuration is given whole)."""

    make: Callable[[Context], FrameDetector]
    still_camera: bool = False
    help: str = ""


FRONTENDS: Registry[Frontend] = Registry("frontend", {
    "bgsub": Frontend(_bgsub, still_camera=True, help="the seeds' background model, then "
                      "blobs (frontends.BlobDetector)"),
    "hog": Frontend(_hog, help="OpenCV's HOG people detector"),
    "confidence": Frontend(_confidence_peaks, help="the peaks of the detector's confidence "
                           "map (HOG's by default) above det_threshold"),
    "spots": Frontend(_spots, help="round spots of a given diameter, bright or dark "
                      "(microscopy; frontends.spots.locate, Crocker and Grier's, trackpy's)"),
})
"""Front-ends by name; also ``"detections:FILE"``, a MOTChallenge detections file, and
``"onnx:MODEL.onnx"``, the user's own ONNX detector
(:class:`~vistrack.frontends.onnx.ONNXDetector`)."""

FRONTEND_OPTIONS = {"background": "bgsub", "min_area": "bgsub", "n_init": "bgsub",
                    "follow_view": "bgsub",
                    "det_threshold": "confidence", "classes": "onnx:MODEL.onnx",
                    "onnx_layout": "onnx:MODEL.onnx", "columns": "detections:FILE",
                    "diameter": "spots", "minmass": "spots", "invert": "spots"}
"""The front-ends' own options (:func:`track_video`'s arguments) and the front-end that reads
each; given with another front-end, one would change nothing, so it is refused."""


def unread_frontend_option(frontend: object, options: dict) -> tuple[str, str] | None:
    """The first option given (not None) in ``options`` that ``frontend`` does not read, and
    the front-end that does (:data:`FRONTEND_OPTIONS`); None if it reads them all.

    Examples
    --------
    >>> unread_frontend_option("hog", {"min_area": 100, "classes": None})
    ('min_area', 'bgsub')
    >>> unread_frontend_option("onnx:model.onnx", {"classes": [0], "onnx_layout": "auto"})
    """
    for key, owner in FRONTEND_OPTIONS.items():
        if options.get(key) is None:
            continue
        prefix = owner.split(":", 1)[0] + ":" if ":" in owner else None
        if not isinstance(frontend, str) or not (
                frontend.startswith(prefix) if prefix else frontend == owner):
            return key, owner
    return None


_FILE_FRONTENDS: dict[str, tuple[str, str, Callable[[str | Path, Context], FrameDetector]]] = {
    "detections": ("detections:FILE", "detections file", _detections_file),
    "onnx": ("onnx:MODEL.onnx", "model", _onnx)}
"""The front-ends named with a file, ``KIND:FILE``: their form, what the file is, and what
makes them (:func:`_frontend`; :func:`input_files` lists the file among a run's inputs)."""


def _frontend(name: str | Detector | Callable[[Frame], Detections | None] | None,
              ctx: Context) -> Callable[[Frame], Detections | None]:
    """A front-end by name (:data:`FRONTENDS`, or ``detections:FILE``), or a detector of
    your own (:func:`as_detector`)."""
    if isinstance(name, str):
        for kind, (form, _, make) in _FILE_FRONTENDS.items():
            if name.startswith(kind + ":"):
                path = name.split(":", 1)[1]
                # ("" read as ".", a folder, which was "Is a directory" or "does not exist")
                if not path:
                    raise ValueError(f"--frontend {form} needs a file's name after "
                                     f"'{kind}:'; got {name!r}")
                if Path(path).is_dir():
                    raise ValueError(f"{path} is a folder, not a file (--frontend {form})")
                return make(path, ctx)
        if name not in FRONTENDS:
            raise ValueError(f"--frontend must be {', '.join(sorted(FRONTENDS))}, "
                             f"detections:FILE or onnx:MODEL.onnx; got {name!r}")
        return FRONTENDS[name].make(ctx)
    detect = as_detector(name) if name is not None else None
    if detect is None:
        raise TypeError("frontend must be a name or a detector, not None")
    return detect


def _box_tracker(preset: str) -> Callable[[Context], Tracker]:
    def make(ctx: Context) -> Tracker:
        over = dict(ctx.overrides)
        motion = over.pop("motion", None)
        cfg = resolve_config(ctx.config if ctx.config is not None else preset, **over)
        if motion is not None or cfg.motion is None:
            cfg = replace(cfg, motion=motion or BoxMotion())
        if cfg.offline.enabled:
            raise ValueError("the offline mode goes with a sequence's detections (track "
                             "--out), not with a video")
        ctx.resolved = cfg
        return BoxTracker(cfg.tracker, motion=cfg.motion, frame_rate=ctx.fps,
                          image_size=ctx.image_size)
    return make


def _dcpf(ctx: Context) -> Tracker:
    from .tracking.dcpf import DetectorConfidencePF

    return DetectorConfidencePF(confidence=ctx.confidence, frame_rate=ctx.fps, **ctx.overrides)


PARTICLE_GATE = 0.999
"""The gate probability of the ``particles`` tracker: its ``search_range`` is the radius of
this quantile of a track's innovation, one frame after an update, and the farthest a link
reaches from the track's predicted position (``PointTracker(max_distance=)``) however far
the gate grows while a particle is missed."""


def _particles(ctx: Context) -> Tracker:
    from .association.gating import chi2_threshold
    from .models import ConstantPosition, Position
    from .tracking import PointTracker

    over = dict(ctx.overrides)
    search = over.pop("search_range", None)
    if search is None:
        diameter = ctx.options.get("diameter")
        if diameter is None:
            raise ValueError("the particles tracker needs search_range (--search-range, the "
                             "farthest a particle moves between frames, in pixels), or the "
                             "spots' diameter to take half of it")
        search = diameter / 2
    search = float(search)
    max_lost = float(over.pop("max_lost", 3.5 / ctx.fps))
    if over:
        raise ValueError(f"the particles tracker's settings are search_range and max_lost; got "
                         f"{sorted(over)}")
    floor = min_search_range()
    if not (math.isfinite(search) and search > floor):
        raise ValueError(f"search_range must be a finite number of pixels above {floor:.2f} "
                         f"(the gate of the positions' own noise); got {search:g}")
    # one frame after an update the innovation's variance per axis is r + q / fps + r, and
    # the gate's radius sqrt(chi2 (2 r + step)); the floor is that of step 0
    step = (search ** 2 - floor ** 2) / chi2_threshold(2, PARTICLE_GATE)
    return PointTracker("gnn", motion=ConstantPosition(dim=2, q=step * ctx.fps),
                        measurement=Position(dim=2, r=PARTICLE_NOISE ** 2), frame_rate=ctx.fps,
                        confirm_hits=1, max_lost=max_lost, p_gate=PARTICLE_GATE,
                        max_distance=search, report="measurement")


PARTICLE_NOISE = 0.1
"""The ``particles`` tracker's measurement noise, pixels (standard deviation per axis): the
spots' positions, to about a tenth of a pixel."""


def min_search_range() -> float:
    """The least ``search_range`` of the ``particles`` tracker, pixels: the gate of the
    positions' own noise alone (a particle that does not move), below which the search range
    would leave the particle's step a negative variance.

    >>> round(min_search_range(), 2)
    0.53
    """
    from .association.gating import chi2_threshold

    return math.sqrt(2 * PARTICLE_NOISE ** 2 * chi2_threshold(2, PARTICLE_GATE))


def _single(method: str) -> Callable[[Context], Tracker]:
    def make(ctx: Context) -> Tracker:
        from .tracking.single import single_tracker

        if ctx.overrides:
            raise ValueError(f"the single-object tracker {method!r} takes no settings; got "
                             f"{sorted(ctx.overrides)}")
        return single_tracker(method)
    return make


@dataclass(frozen=True)
class TrackerEntry:
    """A tracker in :data:`TRACKERS`: ``make(context) -> Tracker``, the front-end it goes
    with by default, whether its configuration is a box tracker's, and whether its tracks
    are points (then :func:`track_video` writes no ``tracks.txt``)."""

    make: Callable[[Context], Tracker]
    frontend: str = "bgsub"
    box_config: bool = False
    help: str = ""
    points: bool = False


def _trackers() -> Registry[TrackerEntry]:
    from .tracking.box import TRACKERS as BOX_PRESETS
    from .tracking.single import METHODS

    items = {name: TrackerEntry(_box_tracker(name), box_config=True,
                                help="box tracker (tracking.BoxTracker)")
             for name in BOX_PRESETS}
    items["dcpf"] = TrackerEntry(_dcpf, frontend="confidence",
                                 help="detector-confidence particle filter")
    items["particles"] = TrackerEntry(_particles, frontend="spots", points=True,
                                      help="drifting points linked frame to frame "
                                      "(microscopy; tracking.PointTracker)")
    for name in METHODS:
        items[f"single:{name}"] = TrackerEntry(_single(name), help="one object, started at "
                                               "the first frame's most confident detection")
    return Registry("tracker", items)


TRACKERS: Registry[TrackerEntry] = _trackers()
"""Trackers by name for :func:`track_video` (``vistrack track --tracker``): the box trackers'
presets (:data:`vistrack.tracking.TRACKERS`), ``"dcpf"``, ``"particles"`` (points) and
``"single:METHOD"`` (a
single-object tracker, :data:`vistrack.tracking.METHODS`); also ``"module:callable"``, a
callable of yours that returns a :class:`~vistrack.tracking.Tracker`."""


def default_frontend(tracker: object) -> str:
    """The front-end a tracker goes with when none is given: its entry's in :data:`TRACKERS`
    (``confidence`` for ``dcpf``), else ``bgsub``.

    >>> default_frontend("dcpf"), default_frontend("bytetrack")
    ('confidence', 'bgsub')
    """
    return TRACKERS[tracker].frontend if isinstance(tracker, str) and tracker in TRACKERS \
        else "bgsub"


def points_problem(tracker: object, frontend: object, *, cli: bool = False) -> str:
    """What is wrong with a tracker and a front-end together where one is of points and the
    other of boxes, "" if nothing: in the arguments' words, or the command line's (``cli``),
    which checks the same before anything runs. A tracker or a front-end that is an object
    of yours is not checked.

    >>> points_problem("bytetrack", "spots", cli=True)[:60]
    '--frontend spots finds points, and --tracker bytetrack track'
    >>> points_problem("particles", "hog")[:58]
    'the particles tracker links points, and the hog front-end '
    >>> points_problem("particles", "spots"), points_problem("bytetrack", "hog")
    ('', '')
    """
    if not (isinstance(tracker, str) and tracker in TRACKERS):
        return ""
    points = TRACKERS[tracker].points
    trk = f"--tracker {tracker}" if cli else f"the {tracker} tracker"
    if frontend == "spots" and not points:
        return ((f"--frontend spots finds points, and {trk} tracks boxes: track spots with "
                 "--tracker particles") if cli else
                (f"the spots front-end finds points, and {trk} tracks boxes: track spots "
                 "with the particles tracker")) + " (the default with them)"
    if points and isinstance(frontend, str) and frontend != "spots":
        return (f"{trk} links points, and --frontend {frontend} finds boxes: give it "
                "--frontend spots" if cli else
                f"{trk} links points, and the {frontend} front-end finds boxes: give it the "
                "spots front-end (or a detector of your own that finds points)")
    return ""


def make_tracker(tracker: str | Tracker, ctx: Context) -> tuple[Tracker, str]:
    """A tracker and its default front-end: ``tracker`` by name in :data:`TRACKERS`, as
    ``"module:callable"`` (the callable is called with no arguments), or a tracker object
    (any :class:`~vistrack.tracking.Tracker`, whose default front-end is ``bgsub``).

    Parameters
    ----------
    tracker : str or Tracker
        A name in :data:`TRACKERS`, ``"module:callable"``, or a tracker.
    ctx : Context
        What a named tracker is made from (its ``overrides`` are the tracker's settings).

    Returns
    -------
    tracker : Tracker
        The tracker.
    frontend : str
        The name of its default front-end in :data:`FRONTENDS`.

    Raises
    ------
    ValueError
        If the name is not in :data:`TRACKERS` (the message lists them), the callable
        cannot be imported, a single-object tracker is given settings, or a setting's value
        is invalid.
    TypeError
        If ``tracker`` (or what the callable made) has no ``step``, or a setting names no
        field of the tracker's configuration.

    Examples
    --------
    >>> tracker, frontend = make_tracker("dcpf", Context(fps=25.0))
    >>> type(tracker).__name__, frontend
    ('DetectorConfidencePF', 'confidence')
    >>> type(make_tracker("single:colour", Context(fps=25.0))[0]).__name__
    'ColourTracker'
    """
    if not isinstance(tracker, str):
        if not callable(getattr(tracker, "step", None)):
            raise TypeError(f"tracker must be a name in {sorted(TRACKERS)}, 'module:callable' "
                            f"or an object with step(frame, detections) -> Tracks; got "
                            f"{type(tracker).__name__}")
        return tracker, default_frontend(tracker)
    if tracker in TRACKERS:
        return TRACKERS[tracker].make(ctx), default_frontend(tracker)
    if ":" in tracker and not tracker.startswith("single:"):
        module, _, name = tracker.partition(":")
        try:
            maker = getattr(importlib.import_module(module), name)
        except (ImportError, AttributeError) as exc:
            raise ValueError(f"tracker {tracker!r}: cannot import {name} from {module} "
                             f"({exc})") from exc
        except SyntaxError as exc:  # the module's file and line, in the one-line form
            raise ValueError(f"tracker {tracker!r}: {exc.filename}:{exc.lineno}: {exc.msg}"
                             ) from exc
        if not callable(maker):  # ("'int' object is not callable", naming nothing)
            raise TypeError(f"tracker {tracker!r}: {name} = {maker!r:.40}, not a callable "
                            "that makes a tracker")
        made = maker()
        if not callable(getattr(made, "step", None)):
            raise TypeError(f"tracker {tracker!r} made a {type(made).__name__}, which has no "
                            "step(frame, detections) -> Tracks")
        return made, default_frontend(tracker)
    return TRACKERS[tracker].make(ctx), ""  # raises, listing the names


# ------------------------------------------------------------------------------- sinks
SINKS: Registry[Callable[[Path, Context, str], Sink]] = Registry("sink", {
    "tracks": lambda path, ctx, name: MOTWriter(path),
    "csv": lambda path, ctx, name: PointsCSVWriter(path) if ctx.points else CSVWriter(path),
    "video": lambda path, ctx, name: _annotated_video(path, ctx.fps),
    "plot": lambda path, ctx, name: _trajectory_plot(path, name),
})
"""The outputs of :func:`track_video` by name: ``make(path, context, source name) -> Sink``."""

SINK_FILES = {"tracks": "tracks.txt", "csv": "tracks.csv", "video": "annotated.mp4",
              "plot": "trajectories.png"}
"""Each sink's file in the output folder."""


def _annotated_video(path: Path, fps: float) -> Sink:
    from .viz.annotate import AnnotatedVideo

    return AnnotatedVideo(path, fps)


def _trajectory_plot(path: Path, name: str) -> Sink:
    from .viz.plots import TrajectoryPlot

    return TrajectoryPlot(path, name)


def _blank(path: Path) -> bool:
    """Whether the file holds nothing but white space (a few KiB read at most)."""
    with open(path, "rb") as fh:
        head = fh.read(4097)
    return len(head) <= 4096 and not head.strip()


def read_detections(path: str | Path, columns: dict[str, str] | None = None,
                    stacklevel: int = 1, *, classless: str | Path | None = None) -> MOTTable:
    """A detections file: MOTChallenge's format, or a ``.csv`` file with a header whose
    columns ``columns`` names (:meth:`~vistrack.io.MOTTable.from_pandas`); ``stacklevel``
    is that of its warnings of boxes of no area and of classes, from the caller;
    ``classless``, a results file without a class column that the warning of several
    classes then names.

    Raises
    ------
    ValueError
        If ``columns`` is given for a MOTChallenge file, the CSV file lacks a column, or the
        file is Parquet (not read as detections).

    Warns
    -----
    UserWarning
        If the CSV file has no score column (``conf``, or the name ``columns`` gives it):
        every detection then scores 1. The warning names the columns not read, one of which
        may hold the scores under another name. If the file holds more than one class:
        each is tracked apart (and ``classless`` has no class column).
    RuntimeWarning
        If a box has zero width or height, naming the first one's line (its frame in a CSV
        file): such a box overlaps no other, so no track can follow it.
    """
    path = Path(path)
    if path.suffix.lower() == ".parquet":  # (read as text: "not a text MOTChallenge file")
        raise ValueError(f"{path}: {PARQUET_DETECTIONS}")
    if path.suffix.lower() != ".csv":
        if columns:
            raise ValueError(f"columns name a CSV file's columns; {path} is read as a "
                             "MOTChallenge file (its name does not end in .csv)")
        table = read_mot(path)
        if len(table) and table.columns < 7:
            warnings.warn(f"{path}: {table.columns} values a row, no score (MOTChallenge's "
                          "7th value, conf): every detection scores 1", UserWarning,
                          stacklevel=stacklevel + 1)
        who = "the second value"
    elif _blank(path):
        # no header and no row: no detections, as an empty text file is (pandas' "No
        # columns to parse from file" was an error)
        table, who = MOTTable.from_rows([]), "the identity"
    else:
        from .io.motchallenge import _COLUMNS, _read_csv

        df = _read_csv(path, "a CSV file of detections")
        table = MOTTable.from_pandas(df, columns, path=str(path))
        names = dict(columns or {})
        conf = names.get("conf", "conf")
        if conf not in df.columns:
            used = {names.get(c, c) for c in _COLUMNS}
            unread = [str(c) for c in df.columns if c not in used]
            warnings.warn(f"{path}: no column {conf!r}: every detection scores 1"
                          + (f" (columns not read: {', '.join(unread)}; name the score's "
                             "column: --columns conf=NAME, or columns={'conf': NAME})"
                             if unread else ""), UserWarning, stacklevel=stacklevel + 1)
        who = next((f"column {names.get(c, c)!r}" for c in ("particle", "id")
                    if names.get(c, c) in df.columns), "the identity")
    if not len(table):
        warnings.warn(f"{path}: no detections: nothing to track, and the results hold no rows",
                      UserWarning, stacklevel=stacklevel + 1)
    far = (np.abs(table.boxes) > MAX_PIXELS).any(axis=1)
    if far.any():
        # a corrupt row: refused here, by its line, rather than by the tracker at its frame
        where, box = first_box(table, int(np.argmax(far)), path, columns)
        raise ValueError(f"{where}: a box ({box}) beyond 2^52 pixels, where a float no longer "
                         "holds every whole pixel: not a box of any image (a corrupt row?)")
    if len(table) and (table.ids >= 0).all():
        # detections carry no identity (-1); a file whose every row has one is ground truth
        # or a tracker's results, whose ignored boxes (conf 0) would be tracked as detections
        warnings.warn(f"{path}: every row has an identity ({who}; detections have "
                      "-1): ground truth or tracks rather than detections? The identities are "
                      "not used, and each row is tracked as a detection scoring its conf",
                      UserWarning, stacklevel=stacklevel + 1)
    warn_no_area(table, path, stacklevel + 1, columns)
    warn_classes(table, path, stacklevel + 1,
                 None if classless is None else Path(classless))
    return in_own_order(table)


def in_own_order(table: MOTTable) -> MOTTable:
    """``table``'s rows, each frame's in an order of their own rather than the file's: the
    most confident first, equal scores by their boxes (left, top, width, height) and then
    their classes. The tracker breaks exact ties (two links of equal overlap, the score
    calibration's and the tracks') by the detections' positions in a frame, and numbers the
    tracks a frame starts in that order: the same rows in another order gave other
    identities, and where links tied, other tracks. Detectors write their rows by score
    (every frame of the four benchmark sets is), so in most files only equal scores move.

    Examples
    --------
    >>> t = MOTTable.from_rows([(1, -1, 5, 0, 4, 9, 0.5), (1, -1, 0, 0, 4, 9, 0.5),
    ...                         (1, -1, 0, 0, 4, 4, 0.9), (2, -1, 0, 0, 1, 1, 0.1)])
    >>> o = in_own_order(t)
    >>> o.boxes[:, 0].tolist(), o.conf.tolist()
    ([0.0, 0.0, 5.0, 0.0], [0.9, 0.5, 0.5, 0.1])
    """
    f, c, b = table.frames, table.conf, table.boxes
    if bool(((f[1:] > f[:-1]) | ((f[1:] == f[:-1]) & (c[1:] < c[:-1]))).all()):
        return table  # by frame, and each frame's by score with no two equal: in order
    order = np.lexsort((table.classes, b[:, 3], b[:, 2], b[:, 1], b[:, 0], -c, f))
    return table if bool((order == np.arange(len(order))).all()) else table[order]


def track_sequence(seq_dir: str | Path, out: str | Path, *, detections: str | Path | None = None,
                   columns: dict[str, str] | None = None,
                   config: TrackConfig | str | os.PathLike | None = None,
                   tracker: str | None = None,
                   offline: bool | None = None, fps: float | None = None, force: bool = False,
                   progress: TextIO | None = None, **overrides: object) -> TrackRun:
    """Track a MOTChallenge sequence folder, or a detections file alone, and write a results
    file.

    Parameters
    ----------
    seq_dir : str or Path
        A folder with ``seqinfo.ini`` and ``det/det.txt``; or a detections file (``.txt``,
        MOTChallenge's format, or ``.csv``) with no sequence folder, tracked at ``fps`` over
        its frames up to the last one it has, in an image as large as its boxes reach.
    out : str or Path
        The results file to write (not overwritten unless ``force``): MOTChallenge's text,
        or Parquet if its name ends in ``.parquet`` (needs pandas and pyarrow), CSV with a
        header if in ``.csv`` (needs pandas): the same rows, with the columns of
        :meth:`~vistrack.io.MOTTable.to_pandas` and each track's class.
    detections : str or Path, optional
        Another detections file (default ``seq_dir/det/det.txt``): MOTChallenge's format, or
        a CSV file with a header (``.csv``; read by pandas, its columns as
        :meth:`~vistrack.io.MOTTable.from_pandas` takes them). Its classes (the eighth
        value of a MOTChallenge file's rows, a CSV file's ``class``; -1 where there is none)
        are tracked apart; a MOTChallenge results file has no class column (a Parquet one
        has: each row its track's class), and a file of more than one class says so in a
        ``UserWarning``.
        Where its rows lie on every k-th frame only
        (:func:`~vistrack.detector_checks.detection_stride`: a detector run on every k-th frame),
        the tracker steps through those frames alone, at the frame rate divided by k, and a
        ``RuntimeWarning`` says so; each frame between gets the reported tracks' boxes as predicted
        from the frames before it (:meth:`~vistrack.tracking.BoxTracker.boxes_ahead`), offline boxes
        on the straight line between the smoothed ones (after the detector's last frame, carried on
        along it), both with score 0. Frames without rows whose
        neighbours on the detector's frames have 5 or more each
        (:func:`~vistrack.detector_checks.undelivered_frames`, runs shorter than ``max_lost``) are
        taken as frames the detector did not deliver and treated the same way: the tracker steps
        over them, and a ``RuntimeWarning`` says so.
    columns : dict, optional
        A CSV file's column names, ``{ours: theirs}`` (:meth:`~vistrack.io.MOTTable.from_pandas`).
    fps : float, optional
        The frame rate (frames a second): needed where there is no ``seqinfo.ini``, and put
        over its ``frameRate`` where there is.
    config, tracker, offline, overrides
        The configuration (:func:`resolve_config`): a
        :class:`~vistrack.config.TrackConfig`, a preset's name in
        :data:`vistrack.tracking.TRACKERS` or a configuration file (as ``--config FILE``),
        and values put over it.
        Offline, tracks start only at detections scoring the offline mode's
        ``start_score`` or more (where it is above ``new_track``), the finished tracks are
        smoothed, gaps filled, tracks of weak detections dropped, tracks followed back
        through the detections left over and joined across gaps
        (:func:`vistrack.tracking.smooth`), and calibrated scores are calibrated on the whole
        file.
    force : bool
        Overwrite ``out``.
    progress
        A stream for a progress bar (the command line passes stderr on a terminal), or None.

    Returns
    -------
    TrackRun
        The file written, counts, the tracker's seconds, the configuration and the values
        derived from the data.

    Raises
    ------
    FileNotFoundError
        If the detections file does not exist, or ``seqinfo.ini`` does not and ``fps`` is
        not given.
    FileExistsError
        If ``out`` exists and ``force`` is False.
    IsADirectoryError, NotADirectoryError, PermissionError
        If ``out`` cannot be written (:func:`vistrack.io.atomic.check_output`); checked
        first, before anything is read.
    ValueError
        If ``seq_dir`` is a file other than a detections file (a video: :func:`track_video`)
        or is one and ``detections`` is given too, ``fps`` is not a number from 0.001 to
        10^6 (:data:`vistrack.models.box.FRAME_RATES`), scores lie
        outside ``[0, 1]`` with raw scores weighing the first stage's IoU, a detections
        file alone runs past frame :data:`MAX_FRAMES` (naming its line), ``out`` is
        the detections file (even with ``force``: the results would overwrite it), the
        detections run past the sequence's last frame, or the configuration is invalid.
    MOTFormatError
        If a file is malformed, or ``seqinfo.ini``'s ``frameRate`` (without ``fps``, which
        also stands in for one it lacks) is not from 0.001 to 10^6 or its ``seqLength``
        is beyond :data:`MAX_FRAMES`.
    ImportError
        If ``out`` is Parquet and pandas or pyarrow is missing, or CSV and pandas is.

    Examples
    --------
    A sequence of five frames with one detection each:

    >>> import tempfile
    >>> seq = Path(tempfile.mkdtemp())
    >>> _ = (seq / "seqinfo.ini").write_text("[Sequence]\\nname=demo\\nframeRate=10\\n"
    ...                                      "seqLength=5\\nimWidth=320\\nimHeight=240\\n")
    >>> (seq / "det").mkdir()
    >>> _ = (seq / "det" / "det.txt").write_text(
    ...     "".join(f"{f},-1,{10 + 5 * f},20,30,60,0.9\\n" for f in range(1, 6)))
    >>> result = track_sequence(seq, seq / "tracks.txt")
    >>> result.frames, result.rows, result.tracks, result.config.name
    (5, 5, 1, 'bytetrack')
    >>> (seq / "tracks.txt").read_text().splitlines()[0]
    '1,1,15.00,20.00,30.00,60.00,0.9,-1,-1,-1'

    The same detections file alone, at 10 frames a second:

    >>> track_sequence(seq / "det" / "det.txt", seq / "alone.txt", fps=10).rows
    5
    """
    out = Path(out)
    # (named first: "exists; pass --force" would have the input overwritten next; as
    # Python's argument, out: the command line checks --out itself first)
    check_not_input([out], sequence_inputs(seq_dir, detections), name="out")
    check_output(out, force=force)
    table_kind = _results_format(out)
    cfg = resolve_config(config, tracker=tracker, offline=offline, **overrides)
    src = _read_sequence(Path(seq_dir), out, detections, columns, fps)
    dets, info = src.dets, src.info
    _check_detections(src, cfg.tracker, cfg.offline)
    slices = dets.frame_slices(info.seq_length)
    xyxy = np.c_[dets.boxes[:, :2], dets.boxes[:, :2] + dets.boxes[:, 2:]]
    # the detector's own frames: every frame, or every stride-th one, where the frames
    # between are not ones where it found nothing; the tracker runs on that timeline, at
    # frame_rate / stride (_OnDetectorFrames)
    first, stride = detector_grid(dets.frames)
    rate = info.frame_rate / stride

    def frame_detections(k: int) -> Detections:
        # frame k's (from 1), made when asked for: memory does not grow with the frames
        s = slices[k - 1]
        return Detections(boxes=xyxy[s], scores=dets.conf[s], classes=dets.classes[s])

    seconds = 0.0
    calibration = None
    tc, oc = cfg.tracker, cfg.offline
    if oc.enabled and tc.scores == "calibrated":
        # offline, the scores are calibrated on the whole file (see tracking.calibration)
        calibration, seconds = _timed(_whole_file_calibration, (
            frame_detections(k) for k in range(first, info.seq_length + 1, stride)), tc, rate,
            oc.calibration_iou_min)
    if oc.enabled and oc.start_score > tc.new_track:
        tc = replace(tc, new_track=oc.start_score)
    trk = BoxTracker(tc, motion=cfg.motion, frame_rate=rate, record=oc.enabled,
                     image_size=(info.im_width, info.im_height) if info.im_width > 0 else None,
                     calibration=calibration)
    frames = (Frame(f, (f - 1) / info.frame_rate) for f in range(1, info.seq_length + 1))
    # online, the rows go to the file as they come; offline, the tracker records its tracks,
    # which are smoothed at the end and written then. Parquet and CSV: the same rows,
    # written as text beside it under a hidden name first
    with made_folder(out.parent), (staging(out) if table_kind
                                   else nullcontext(out)) as text:
        # boxes in pixels to MOTChallenge's hundredth; in smaller units (normalised to the
        # image) to a thousandth of their typical height
        decimals = box_decimals(dets.boxes[:, 3])
        writer = None if oc.enabled else MOTWriter(text, decimals)
        stepper, skip = _on_detector_frames(trk, src.det_path, dets.frames, first, stride,
                                            oc.enabled)
        stats = run(frames, lambda frame: frame_detections(frame.index), stepper,
                    [writer] if writer is not None else [], progress=progress,
                    total=info.seq_length, label=info.name)
        seconds += stats.seconds["tracker"]
        classes_of: Callable[[Any], np.ndarray]  # each track's class, by identity
        if writer is not None:
            n_rows, n_tracks = len(writer), len(writer.identities)
            classes_of = writer.classes_of
        else:
            sm, sec = _timed(smooth, trk, min_score=oc.min_track_score,
                             extend_iou=oc.extend_iou if oc.extend_iou > 0 else None,
                             link_iou=oc.link_iou, **oc.frames(rate))
            seconds += sec
            n_rows, n_tracks, classes_of = _write_smoothed(sm, text, decimals, first, stride,
                                                           skip, info.seq_length)
        if table_kind:
            _write_table(text, out, table_kind, classes_of)
    _warn_calibration(trk, src.label)
    derived = derived_values(trk)
    if stride > 1:
        derived["detection_stride"] = stride
    if len(skip):
        derived["undelivered_frames"] = len(skip)
    return TrackRun(out, info.seq_length, len(dets), n_rows, n_tracks, seconds,
                    cfg.with_motion(), derived, src.replaced_rate)


# the stages of track_sequence: the results' format, the input read and checked, the whole
# file's calibration (offline), the smoothed tracks written, the table beside the text
def _results_format(out: Path) -> str | None:
    """``"parquet"`` or ``"csv"`` for a results file of that suffix (the text's rows as
    :meth:`~vistrack.io.MOTTable.to_pandas` names them, with a header; raises ImportError
    before anything is read when what writes it is missing), None for MOTChallenge's text."""
    kind = {".parquet": "parquet", ".csv": "csv"}.get(out.suffix.lower())
    if kind is None and out.suffix.lower() not in ("", ".txt"):
        # results.json holding MOTChallenge's text would be read as JSON, and fail
        warnings.warn(f"{out}: written as MOTChallenge text; {out.suffix} is not a format "
                      "vistrack writes (.txt: MOTChallenge's text, .csv, .parquet)",
                      UserWarning, stacklevel=3)
    if kind == "parquet":
        need_parquet()
    elif kind == "csv":
        from .io.motchallenge import _pandas

        _pandas("a CSV results file")
    return kind


@dataclass(frozen=True)
class _SequenceInput:
    """What :func:`track_sequence` tracks: the detections file, the sequence's facts and
    its rows; ``label`` names the input in warnings (the sequence folder, or the file
    alone); ``replaced_rate``, :attr:`TrackRun.replaced_rate`."""

    det_path: Path
    label: str
    info: SeqInfo
    dets: MOTTable
    replaced_rate: tuple[str, float] | None = None


def _a_frame_rate(x: Any) -> bool:
    """Whether ``x`` is a frame rate the box tracker's motion model scales to
    (:data:`~vistrack.models.box.FRAME_RATES`)."""
    try:
        return not isinstance(x, bool) and FRAME_RATES[0] <= float(x) <= FRAME_RATES[1]
    except (TypeError, ValueError):
        return False


def check_fps(fps: Any) -> None:
    """``fps`` None, or a frame rate :func:`track_sequence` takes (a ValueError naming it)."""
    if fps is not None and not _a_frame_rate(fps):
        raise ValueError(f"fps must be a number from {FRAME_RATES[0]:g} to "
                         f"{FRAME_RATES[1]:g} (frames a second); got {fps!r}")


def _read_sequence(seq_dir: Path, out: Path, detections: str | Path | None,
                   columns: dict[str, str] | None, fps: float | None) -> _SequenceInput:
    """The detections of a sequence folder, or of a detections file alone, read and checked
    against the sequence (:func:`track_sequence`'s errors; its warnings name the caller of
    :func:`track_sequence`)."""
    check_fps(fps)
    if not seq_dir.exists():  # not "SEQ/det/det.txt does not exist" for a mistyped SEQ
        raise FileNotFoundError(f"{seq_dir} does not exist (a sequence folder, or a "
                                "detections file)")
    alone = seq_dir.is_file()
    if alone:
        if seq_dir.suffix.lower() not in DETECTION_SUFFIXES:
            raise ValueError(f"seq_dir {seq_dir} is a file but not a detections file "
                             f"({', '.join(DETECTION_SUFFIXES)}); a MOTChallenge sequence is "
                             "a folder (seqinfo.ini, det/det.txt), and a video is tracked by "
                             "track_video")
        if detections is not None:
            raise ValueError(f"seq_dir {seq_dir} is a detections file and detections is "
                             f"{detections}: give one")
        det_path = seq_dir
    else:
        det_path = Path(detections) if detections is not None else seq_dir / "det" / "det.txt"
    ini = None if alone else seq_dir / "seqinfo.ini"
    has_info = ini is not None and ini.exists()
    if not alone and not has_info and detections is None and not det_path.exists():
        # not "SEQ/seqinfo.ini does not exist; pass --fps", then "SEQ/det/det.txt does not
        # exist", for a folder that is no sequence at all
        raise FileNotFoundError(
            f"{seq_dir} is not a MOTChallenge sequence (no seqinfo.ini, no det/det.txt) nor a "
            "folder of them: give a sequence folder or a detections file (with --fps), or "
            "track its images with --out-dir OUT/ instead of --out")
    if not has_info and fps is None:
        raise FileNotFoundError(
            f"{seq_dir} is a detections file alone: give its frame rate (fps, --fps)" if alone
            else f"{ini} does not exist; pass the frame rate (--fps) to track the detections "
            "without it")
    # (--fps stands in for a frameRate the file lacks: it is put over the file's anyway)
    info = read_seqinfo(seq_dir, frame_rate=fps) if has_info else None
    if info is not None:
        if fps is None and not _a_frame_rate(info.frame_rate):
            # (named by the motion model later, without the file or the key)
            raise MOTFormatError(f"{ini}: frameRate must be from {FRAME_RATES[0]:g} to "
                                 f"{FRAME_RATES[1]:g} frames/s; got {info.frame_rate:g} "
                                 "(give the true rate with --fps)")
        if info.seq_length > MAX_FRAMES:
            # tracked frame by frame up to its last frame: 10^12 would never end
            raise MOTFormatError(f"{ini}: seqLength must be at most {MAX_FRAMES:,} frames; "
                                 f"got {info.seq_length:,}")
    replaced: tuple[str, float] | None = None  # seqinfo.ini's frameRate, where fps is put over
    if not det_path.exists():
        raise FileNotFoundError(
            f"{det_path} does not exist" + (" (--detections FILE)" if detections is not None
                                            else "" if alone else
                                            " (pass --detections FILE, another file of "
                                            "detections)"))
    if det_path.is_dir():
        raise ValueError(f"{det_path} is a folder, not a detections file"
                         + (" (--detections FILE)" if detections is not None else ""))
    # the warnings' stacklevels (here and in _check_detections) name track_sequence's caller
    dets = read_detections(det_path, columns, stacklevel=3,
                           classless=None if out.suffix.lower() in (".csv", ".parquet")
                           else out)
    if info is None:
        assert fps is not None  # refused above without seqinfo.ini
        if len(dets) and dets.frames.max() > MAX_FRAMES:
            # tracked frame by frame up to its last frame: 10^11 would never end
            f = int(dets.frames.max())
            line = row_line(det_path, f, columns=columns)
            raise ValueError(f"{det_path}" + (f", line {line}" if line is not None else "")
                             + f": frame {f} is beyond the {MAX_FRAMES:,} frames a detections "
                             "file is tracked over (a timestamp or another column where the "
                             "frame should be?)")
        warn_long_silence(dets, det_path, float(fps), stacklevel=3, columns=columns)
        info = SeqInfo.from_detections(det_path if alone else seq_dir, dets, float(fps))
    else:
        if fps is not None:
            if not math.isclose(info.frame_rate, float(fps)):
                replaced = ("seqinfo.ini", info.frame_rate)
            info = replace(info, frame_rate=float(fps))
        _check_within_length(det_path, dets, info.seq_length, ini, columns)
        warn_outside(dets, det_path, (info.im_width, info.im_height), stacklevel=3,
                     columns=columns)
    return _SequenceInput(det_path, str(det_path if alone else seq_dir), info, dets, replaced)


def _check_within_length(path: Path, table: MOTTable, n: int, ini: Path | None,
                        columns: dict[str, str] | None = None) -> None:
    """Refuse a row of ``table`` (read from ``path``) past the sequence's ``n`` frames (its
    ``seqLength``, in ``ini``), naming the file, the line of the first frame beyond and
    ``ini``."""
    if len(table) and table.frames.max() > n:
        f = int(table.frames[table.frames > n].min())  # the first frame beyond, its line
        line = row_line(path, f, columns=columns)
        raise ValueError(f"{path}" + (f", line {line}" if line is not None else "")
                         + f": frame {f} is beyond the sequence's {n} frames ({ini})")


def _check_detections(src: _SequenceInput, tc: BoxTrackerConfig, oc: OfflineConfig) -> None:
    """Warn of duplicate boxes where the tracker does no suppression of its own, and of raw
    scores that all lie below the threshold a track starts at (the highest of ``high``,
    ``new_track`` and, offline, ``start_score``); refuse scores outside [0, 1] where raw
    scores weigh the first stage's IoU."""
    dets = src.dets
    if tc.nms_iou >= 1:
        warn_duplicates(dets, src.det_path, stacklevel=3)
    if len(dets):
        _warn_no_start(src.det_path, dets.conf, tc, oc.start_score if oc.enabled else None,
                       stacklevel=3)
        frames = int(dets.frames.max() - dets.frames.min()) + 1
        if 1 < frames < tc.confirm_hits:  # (on one frame every track starts on the first)
            # (--confirm-hits 100000 wrote the tracks of the first frame alone, unsaid)
            warnings.warn(f"{src.det_path}: confirm_hits {tc.confirm_hits} (--confirm-hits) "
                          f"is more than its {frames} frames of detections: no track is "
                          "confirmed but those started on the first frame", UserWarning,
                          stacklevel=3)
    if tc.scores == "raw" and tc.fuse_score and len(dets) and not (
            (dets.conf >= 0) & (dets.conf <= 1)).all():
        raise ValueError(f"{src.det_path}: scores from {dets.conf.min():.4g} to "
                         f"{dets.conf.max():.4g}, but with raw scores (--scores raw) the first "
                         "association stage weighs IoU by the score, which must lie in [0, 1]: "
                         "calibrate them (--scores calibrated, the default), or turn the "
                         "weighing off (fuse_score = false under [tracker] in a --config file; "
                         "fuse_score=False in Python)")


def _warn_no_start(label: object, scores: np.ndarray, tc: BoxTrackerConfig,
                   start_score: float | None, stacklevel: int) -> None:
    """Warn where, with raw scores, every one of ``scores`` lies below the threshold a track
    starts at: the highest of ``high``, ``new_track`` and, offline, ``start_score`` (``--high
    5`` alone wrote 0 boxes without a word). ``stacklevel`` is the caller's own."""
    starts = [("high", tc.high), ("new_track", tc.new_track)]
    if start_score is not None:
        starts.append(("start_score", start_score))
    name, start = max(starts, key=lambda t: t[1])
    if tc.scores != "raw" or not len(scores) or scores.max() >= start:
        return
    option = "--" + name.replace("_", "-")
    names = ", ".join(n for n, _ in starts[:-1]) + f" and {starts[-1][0]}"
    warnings.warn(f"{label}: every score lies below {name} {start:g} (the scores run "
                  f"{scores.min():.4g} to {scores.max():.4g}), and with raw scores (--scores "
                  "raw) no track can start (a track starts from a detection scoring at least "
                  f"{names}): lower {option}, or calibrate the scores (--scores calibrated, "
                  "the default)", UserWarning, stacklevel=stacklevel + 1)


def _timed(fn: Callable[..., Any], *args: Any, **kwargs: Any) -> tuple[Any, float]:
    """``fn(*args, **kwargs)`` and the seconds it took, less any spent compiling kernels."""
    t0, c0 = time.perf_counter(), _compile.seconds()
    result = fn(*args, **kwargs)
    return result, (time.perf_counter() - t0) - (_compile.seconds() - c0)


def _whole_file_calibration(frames: Iterable[Detections], tc: BoxTrackerConfig, rate: float,
                            min_iou: float | None = None
                            ) -> ScoreCalibration | dict[int, ScoreCalibration] | None:
    """The score calibration fitted to every frame's detections (offline), or, where they
    are of several classes, one fitted to each class's detections alone, by class (a class
    with nothing to fit left out), its links loosened down to ``min_iou`` where the most
    confident detections do not persist (:meth:`ScoreCalibration.from_frames`). None where
    no detection is seen to persist or not (no detections, or all on one frame): nothing to
    fit, so the tracker calibrates as it goes, as online (a class left out, the same)."""
    frames = list(frames)
    classes = np.unique(np.concatenate([d.classes for d in frames] or [np.zeros(0)]))
    options = dict(tc.calibration_options(rate), min_link_iou=min_iou)
    if len(classes) <= 1:
        try:
            return ScoreCalibration.from_frames(frames, **options)
        except NoOutcomesError:
            return None
    out = {}
    for k in classes.tolist():
        try:
            out[int(k)] = ScoreCalibration.from_frames(
                [d[d.classes == k] for d in frames], **options)
        except NoOutcomesError:
            pass
    return out or None


def _write_smoothed(sm: SmoothedTracks, text: Path, decimals: int, first: int, stride: int,
                    skip: np.ndarray, last: int) -> tuple[int, int, Callable[[Any], np.ndarray]]:
    """The offline mode's end: the smoothed tracks (:func:`~vistrack.tracking.smooth`),
    numbered by the sequence's frames (the frames between a detector's filled, and those after
    its last up to ``last``, the sequence's), written to ``text``; returns the rows, the
    tracks and each track's class by identity."""
    F, I, xywh = first + (sm.frames - 1) * stride, sm.ids, sm.xywh
    conf = np.where(sm.filled, 0.0, sm.scores)
    if stride > 1 or len(skip):
        F, I, xywh, conf = _fill_between(F, I, xywh, conf, first, stride, skip, last)
    write_mot(text, F, I, xywh, conf, force=True, decimals=decimals)
    known, at = np.unique(sm.ids, return_index=True)
    return len(F), len(np.unique(I)), lambda ids: sm.classes[at][np.searchsorted(known, ids)]


def _write_table(text: Path, out: Path, kind: str,
                 classes_of: Callable[[Any], np.ndarray]) -> None:
    """The rows of ``text`` as Parquet or CSV at ``out``: the text has no class column;
    Parquet's and CSV's have, each row its track's."""
    table = read_mot(text)
    table = replace(table, classes=classes_of(table.ids).astype(np.int64))
    if kind == "parquet":
        table.to_parquet(out)
    else:
        table.to_csv(out)



class _OnDetectorFrames:
    """A box tracker stepped through the frames a detector delivered alone, every ``stride``-th
    from ``first`` but those in ``skip`` (:func:`~vistrack.detector_checks.undelivered_frames`;
    the tracker's frame rate the video's divided by ``stride``; its frame ``i`` the video's
    ``first + (i - 1) * stride``): at each frame between, the tracks it reported last, at
    their boxes predicted that far ahead (:meth:`BoxTracker.boxes_ahead`), with score 0;
    before ``first``, none."""

    def __init__(self, tracker: BoxTracker, first: int, stride: int,
                 skip: ArrayLike = ()) -> None:
        self.tracker, self.first, self.stride = tracker, first, stride
        self.skip = frozenset(np.asarray(skip, dtype=np.int64).tolist())
        self._last, self._at = Tracks.empty(), first

    def step(self, frame: Frame, detections: Detections | None = None) -> Tracks:
        j = frame.index - self.first
        if j < 0:
            return Tracks.empty()
        i, ahead = divmod(j, self.stride)
        if ahead == 0:
            if frame.index not in self.skip:
                self._last, self._at = self.tracker.step(
                    Frame(i + 1, i / self.tracker.frame_rate, frame.image), detections
                ), frame.index
                return self._last
            self.tracker.pass_over()
        t = self._last
        return Tracks(ids=t.ids, boxes=self.tracker.boxes_ahead(
            t.ids, (frame.index - self._at) / self.stride), points=None,
            scores=np.zeros(len(t)), classes=t.classes)

    def reset(self) -> None:
        self.tracker.reset()
        self._last, self._at = Tracks.empty(), self.first


def _on_detector_frames(trk: BoxTracker, path: str | Path, frames: np.ndarray, first: int,
                        stride: int, offline: bool, last: int | None = None
                        ) -> tuple[Tracker, np.ndarray]:
    """What steps ``trk`` (made at the detector's rate) through a detections file's frames, and the
    frames the detector did not deliver (:func:`~vistrack.detector_checks.undelivered_frames`, runs
    a lost track outlives: shorter than ``max_lost``): ``trk`` itself where it ran on every frame
    and delivered them all, else :class:`_OnDetectorFrames`; a ``RuntimeWarning`` says which
    frames it steps over, up to ``last``, the last frame tracked where it is known."""
    # (frames, to rounding: 2.2 s at 25 frames/s is 55.000000000000007, whose ceiling took
    # a run of 55 frames, exactly max_lost, for shorter than it)
    span = trk.config.max_lost * trk.frame_rate
    if abs(span - round(span)) <= 1e-9 * max(1.0, span):
        span = float(round(span))
    longest = max(0, math.ceil(span) - 1)
    skip = undelivered_frames(frames, first, stride, longest)
    if stride > 1:
        warnings.warn(stride_warning(path, first, stride, trk.frame_rate, offline),
                      RuntimeWarning, stacklevel=3)
    shown = skip if last is None else skip[skip <= last]
    if len(shown):
        warnings.warn(undelivered_warning(path, shown, offline), RuntimeWarning, stacklevel=3)
    if stride == 1 and not len(skip):
        return trk, skip
    return _OnDetectorFrames(trk, first, stride, skip), skip


def _fill_between(frames: np.ndarray, ids: np.ndarray, xywh: np.ndarray, conf: np.ndarray,
                  first: int, stride: int, skip: np.ndarray, last: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rows for the frames between two rows of a track with no frame the tracker stepped
    on between them (the detector's frames, every ``stride``-th from ``first``, but those
    in ``skip``), on the straight line between the two; and for the frames after the last
    one the tracker stepped on, up to ``last``, a row for each track it reported there: its
    centre carried on along the line from its row before, as the online mode predicts it,
    its size by the same factor each frame (a size of 0 held; a track of one row: its box as
    it is). All with score 0, as the offline mode's filled rows; sorted by frame and id."""
    o = np.lexsort((frames, ids))
    F, I, B, C = frames[o], ids[o], xywh[o], conf[o]
    # stepped[f]: the frames up to f the tracker stepped on
    end = int(F.max()) + 1 if len(F) else 1
    on = np.zeros(end + 1, np.int64)
    on[first:end + 1:stride] = 1
    on[skip[skip <= end]] = 0
    stepped = np.cumsum(on)
    gap = F[1:] - F[:-1]
    k = np.flatnonzero((I[1:] == I[:-1]) & (gap > 1)
                       & (stepped[F[1:] - 1] == stepped[F[:-1]]))
    n = gap[k] - 1  # frames to fill between each pair
    at = np.repeat(k, n)
    step = np.arange(len(at)) - np.repeat(np.cumsum(n) - n, n) + 1  # 1..n each
    w = (step / np.repeat(gap[k], n))[:, None]  # fractions of the way
    nF, nI = F[at] + step, I[at]
    nB = B[at] * (1 - w) + B[at + 1] * w
    F, I = np.r_[F, nF], np.r_[I, nI]
    B, C = np.r_[B, nB], np.r_[C, np.zeros(len(nF))]
    # the frames after the detector's last (fewer than stride): each track there carried on
    o = np.lexsort((F, I))
    F, I, B, C = F[o], I[o], B[o], C[o]
    end = first + (last - first) // stride * stride
    ends = np.flatnonzero(F == end) if last > end else np.zeros(0, np.int64)
    before = np.maximum(ends - 1, 0)
    before = np.where((ends > 0) & (I[before] == I[ends]), before, ends)
    # the centre on its line, the size by the same factor each frame (so never below 0)
    centre, size = B[:, :2] + B[:, 2:] / 2, B[:, 2:]
    dt = np.maximum(F[ends] - F[before], 1)[:, None]
    velocity = (centre[ends] - centre[before]) / dt
    with np.errstate(divide="ignore", invalid="ignore"):  # a size of 0 (or less): held
        growth = np.log(size[ends] / size[before]) / dt
    growth[~np.isfinite(growth)] = 0.0
    ahead = np.tile(np.arange(1, last - end + 1), len(ends))[:, None]  # 1.. each
    at = np.repeat(ends, last - end) if len(ends) else ends
    tc = centre[at] + np.repeat(velocity, last - end, axis=0) * ahead
    ts = size[at] * np.exp(np.repeat(growth, last - end, axis=0) * ahead)
    F, I = np.r_[F, F[at] + ahead[:, 0]], np.r_[I, I[at]]
    B, C = np.r_[B, np.c_[tc - ts / 2, ts]], np.r_[C, np.zeros(len(at))]
    o = np.lexsort((I, F))
    return F[o], I[o], B[o], C[o]


# --------------------------------------------------------------------------------- fit
@dataclass(frozen=True)
class FitRun:
    """What :func:`fit_sequences` learned and how it tracked.

    Attributes
    ----------
    config : TrackConfig
        The configuration to track with: the one given with the learned box motion, or the
        one given as it was when the learned motion did not track the held-out sequences
        better, or, learnt from a first pass, the one given with each measurement noise
        raised to the learned one where that is larger (``chosen``).
    fit : MotionFit
        The learned noise, and each sequence's values.
    reference : str
        What the objects were: ``"ground truth"`` or ``"first pass"`` (the confident tracks
        of the offline mode with the configuration given).
    held_out : dict or None
        With ground truth and two sequences or more: COMBINED ``HOTA``, ``MOTA`` and ``IDF1``
        (fractions) of each sequence tracked online with the values learned from the
        others (``"learned"``) and with the configuration given (``"given"``); None
        otherwise.
    chosen : str
        Which motion ``config`` has: ``"learned"``; ``"given"`` when the held-out
        sequences' HOTA was not higher with the learned values; ``"measurement"`` when learnt
        from a first pass (nothing to check it against): the given motion with each
        measurement noise the larger of the given and the learned one.
    """

    config: TrackConfig
    fit: MotionFit
    reference: str
    held_out: dict | None = None
    chosen: str = "learned"


def _gt_reference(seq: Path, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows of ``seq``'s ground truth that scoring considers, refusing a frame past the
    sequence's ``n`` frames."""
    gt = read_mot(seq / "gt" / "gt.txt")
    _check_within_length(seq / "gt" / "gt.txt", gt, n, seq / "seqinfo.ini")
    # the rows the scoring considers (0: to ignore), as TrackEval reads the flag
    keep = considered(gt.conf) if gt.conf is not None else np.ones(len(gt), bool)
    return gt.frames[keep], gt.ids[keep], gt.boxes[keep]


_MIN_MATCHED = 10
"""The least number of detections matched to an object for :func:`fit_sequences` to learn
from it (:func:`~vistrack.tracking.fit.matched_series`' ``min_length``)."""


def fit_sequences(seq_dirs: Sequence[str | Path], *, gt: bool = False,
                  config: TrackConfig | str | None = None, held_out: bool = True,
                  keep_learned: bool = False, progress: TextIO | None = None) -> FitRun:
    """Learn a box tracker's motion and measurement noise from MOTChallenge sequences
    (:mod:`vistrack.tracking.fit`): from each sequence's ground truth (``gt``), otherwise
    from the confident tracks of a first pass (the offline mode), and the detections.

    Parameters
    ----------
    seq_dirs : sequence of str or Path
        Sequence folders (``seqinfo.ini``, ``det/det.txt``; ``gt/gt.txt`` with ``gt``).
    gt : bool
        Learn from the ground truth's objects (rows of confidence 0 ignored, as in scoring).
    config : TrackConfig or str, optional
        The configuration to start from and to compare with (default: the default one).
    held_out : bool
        With ``gt`` and two sequences or more: also track each sequence with the values
        learned from the others and with ``config``, and score both (``FitRun.held_out``);
        unless ``keep_learned``, the learned motion is returned only if it scored the
        higher COMBINED HOTA, else ``config`` as given. The likeliest noise for the
        detections is not always the one that tracks best (docs/mot.md): a learned value
        is kept only where it tracked sequences it was not learned from better.
    keep_learned : bool
        Return the learned motion whatever the held-out sequences scored; without ``gt``,
        all of it.
    progress : TextIO, optional
        Where to report each sequence.

    Returns
    -------
    FitRun

    Notes
    -----
    Without ``gt`` nothing scores what was learned, and the first pass's tracks are no
    truth: smoothed through the detections, they follow their errors in part. The spread
    measured about them is divided for what the smoother takes of white errors
    (:func:`~vistrack.tracking.fit.smoothed_residual_share`, at the rate the first pass ran:
    the detector's own frames), but errors that persist from frame to frame it follows as
    motion (MOT17's ``cx``: 0.012 of the width from a first pass, 0.027 from the ground
    truth); where objects move about as jumpily as the model's noise allows, the residuals
    hold their motion too and the division overstates (people and cars move far more
    smoothly); the rows the steady-state smoother does not describe (a track's ends, the
    boxes followed back or filled offline) are few, and the spread is robust (a median
    absolute deviation). And the motion noise of maximum likelihood tracks worse than the
    defaults' (docs/mot.md). Tracked with everything learnt from a first pass (before the
    division), each of the four sets of docs/mot.md lost 0.75 to 2.4 HOTA online. So,
    unless ``keep_learned``, the motion returned keeps ``config``'s motion noise and raises
    each measurement noise to the learned one only where that is larger: a detector whose
    boxes visibly stray more than ``config`` assumes. On MOT17, MOT16 with FairMOT and KITTI
    that is ``config`` itself, on MOT15 the width's noise 0.103 instead of 0.1 (HOTA within
    0.05 either way); on a simulated detector whose boxes err 2.5 times as much as
    ``bench/simulated_crowd.py``'s it gained 4.0 HOTA online and 4.8 offline.

    Raises
    ------
    FileNotFoundError
        If a sequence lacks ``det/det.txt``, or ``gt/gt.txt`` with ``gt``, or is a folder of
        sequences (``vistrack fit`` takes one for its sequences).
    ValueError
        If no sequences are given, a sequence is given twice (two paths of one folder) or is
        a file, or no object is matched in 10 frames or more (shorter ones are left out).
    """
    import tempfile

    from .batch import check_distinct
    from .tracking.fit import fit_box_motion, matched_series

    seqs = [Path(d) for d in seq_dirs]
    if not seqs:
        raise ValueError("no sequences to learn from")
    # one sequence given twice would be learned from twice, and held out from itself
    check_distinct(seqs, reads="detections")  # (their images are not read)
    cfg = resolve_config(config)
    start = cfg.motion if cfg.motion is not None else BoxMotion()
    series: list[tuple[list[Series], float]] = []
    smoothers: list[BoxMotion] = []
    for seq in seqs:  # before anything is learnt (a file was read as its seqinfo.ini)
        if seq.is_file():
            raise ValueError(f"{seq} is a file, not a sequence folder (seqinfo.ini, "
                             "det/det.txt)")
        if seq.is_dir() and not (seq / "seqinfo.ini").exists() and any(
                (p / "seqinfo.ini").exists() for p in seq.iterdir() if p.is_dir()):
            raise FileNotFoundError(f"{seq / 'seqinfo.ini'} does not exist: {seq} is a "
                                    "folder of sequences; give the sequence folders in it")
    # every file each sequence needs, before anything is learnt: a folder whose last
    # sequence had no ground truth failed after learning from the others
    for need, why in ((Path("det") / "det.txt", ""),
                      *(((Path("gt") / "gt.txt",
                          " (--gt learns from each sequence's ground truth)"),) if gt else ())):
        missing = [seq / need for seq in seqs if not (seq / need).exists()]
        if missing:
            more = f" and {len(missing) - 1} more" if len(missing) > 1 else ""
            raise FileNotFoundError(f"{missing[0]}{more} do{'es' if not more else ''} not "
                                    f"exist{why}: {len(missing)} of {len(seqs)} sequences "
                                    f"lack{'s' if len(missing) == 1 else ''} "
                                    f"{need.as_posix()}")
    with tempfile.TemporaryDirectory(prefix="vistrack-fit-") as tmp:
        for seq in seqs:
            info = read_seqinfo(seq)
            det_path = seq / "det" / "det.txt"  # (checked above, with gt/gt.txt)
            # (track refuses a frame past seqLength, naming its line; fit --gt learned from
            # one unsaid, matched to ground truth past the sequence's end)
            dets = in_own_order(read_mot(det_path))
            _check_within_length(det_path, dets, info.seq_length, seq / "seqinfo.ini")
            if gt:
                ref = _gt_reference(seq, info.seq_length)
            else:
                first = Path(tmp) / f"{len(series)}.txt"
                run = track_sequence(seq, first, config=replace(
                    cfg, offline=replace(cfg.offline, enabled=True)))
                t = read_mot(first)
                ref = (t.frames, t.ids, t.boxes)
                # its smoother ran on the detector's own frames: every stride-th
                stride = (run.derived or {}).get("detection_stride", 1)
                smoothers.append(start.at_rate(info.frame_rate / stride))
            try:
                s = matched_series(*ref, dets.frames, dets.boxes, min_length=_MIN_MATCHED)
            except ValueError as e:  # (an identity twice in a frame named no file)
                where = seq / "gt" / "gt.txt" if gt else f"{seq.name}'s first pass"
                raise ValueError(f"{where}: {e}") from None
            series.append((s, info.frame_rate))
            if progress is not None:
                n = sum(int(np.isfinite(z[:, 0]).sum()) for _, z, _ in s)
                print(f"{info.name}: {len(s)} objects, {n} matched detections",
                      file=progress, flush=True)
        if not any(len(s) for s, _ in series):
            # (fit_box_motion's own words said two frames, where matched_series keeps the
            # objects matched in 10 or more: 50 objects of 9 frames each were "none")
            raise ValueError(f"no object was matched in {_MIN_MATCHED} frames or more in "
                             f"{'the sequence' if len(seqs) == 1 else 'any sequence'}: "
                             "nothing to learn from")
        learned = fit_box_motion(series, start=start, smoothed_by=None if gt else smoothers)
        scores = None
        if gt and held_out and len(seqs) > 1:
            scores = _held_out(seqs, cfg, start, learned.per_sequence, Path(tmp), progress)
    if not gt and not keep_learned:
        # nothing to check the values against: the given motion, its measurement noise
        # raised where the detections stray more (see Notes)
        motion = _measurement_raised(start, learned.motion)
        return FitRun(cfg if motion == start else replace(cfg, motion=motion), learned,
                      "first pass", None, "measurement")
    chosen = ("given" if scores is not None and not keep_learned
              and not scores["learned"]["HOTA"] > scores["given"]["HOTA"] else "learned")
    return FitRun(replace(cfg, motion=learned.motion) if chosen == "learned" else cfg, learned,
                  "ground truth" if gt else "first pass", scores, chosen)


def _measurement_raised(given: BoxMotion, learned: BoxMotion) -> BoxMotion:
    """``given`` with each measurement noise the larger of its own and ``learned``'s (the
    measurement noise is a fraction of the box's size at any frame rate)."""
    return BoxMotion(std_pos=given.std_pos, std_vel=given.std_vel,
                     std_meas=tuple(np.maximum(given.std_meas, learned.std_meas).tolist()),
                     init_pos=given.init_pos, init_vel=given.init_vel,
                     frame_rate=given.frame_rate)


def _held_out(seqs: list[Path], cfg: TrackConfig, start: BoxMotion, rows: list[dict],
              tmp: Path, progress: TextIO | None) -> dict:
    """Each sequence tracked online with the values learned from the other sequences (their
    ``rows`` of :attr:`MotionFit.per_sequence`, over ``start``), and with ``cfg``; COMBINED
    scores of both."""
    from .evaluation.files import evaluate_files
    from .tracking.fit import median_motion

    online = replace(cfg, offline=replace(cfg.offline, enabled=False))
    out = {}
    for mode in ("learned", "given"):
        for k, seq in enumerate(seqs):
            config = online
            others = [r for r in rows if r["sequence"] != k]
            if mode == "learned" and others:  # (else nothing was learned without it)
                config = replace(online, motion=median_motion(others, start))
            track_sequence(seq, tmp / mode / f"{k}.txt", config=config)
        # named by position: two folders of one name (a/S, b/S) are two sequences
        c = evaluate_files([(str(k), seq / "gt" / "gt.txt", tmp / mode / f"{k}.txt",
                             seq / "seqinfo.ini") for k, seq in enumerate(seqs)])["COMBINED"]
        out[mode] = {"HOTA": float(c.HOTA), "MOTA": float(c.MOTA), "IDF1": float(c.IDF1)}
        if progress is not None:
            print(f"held out, {mode}: HOTA {100 * c.HOTA:.1f}", file=progress, flush=True)
    return out


# ------------------------------------------------------------------------------- video
@dataclass(frozen=True)
class VideoRun:
    """What :func:`track_video` wrote and measured: the output files, frames, tracks, the
    seconds spent in each stage (``decode``, ``frontend``, ``tracker``, ``write``), the
    scores against ground truth (None without it), and for a box tracker the configuration
    used and the values derived from the data.

    Attributes
    ----------
    out_dir : Path
        The output folder.
    files : dict of str to Path
        The file of each sink written (:data:`SINKS`).
    frames : int
        Frames tracked.
    rows : int
        Rows of tracks written.
    tracks : int
        Distinct identities.
    seconds : dict of str to float
        Seconds in each stage (:class:`LoopStats`).
    scores : MOTCounts or None
        The scores against the ground truth.
    config : TrackConfig or None
        A box tracker's configuration.
    derived : dict or None
        :func:`derived_values` of a box tracker; of the detector-confidence particle
        filter (``dcpf``), its ``frame_rate``, ``scored_detections`` and ``top_score``.
    first, last : int
        The first and the last frame tracked (0: ``first + frames - 1``); frames missing
        from the source between them are not counted in ``frames``.
    replaced_rate : (str, float) or None
        Where ``fps`` was put over another frame rate that the source gives: what gives it
        (``"the header"``, ``"seqinfo.ini"``) and that rate; None otherwise.

    Examples
    --------
    >>> run = VideoRun(Path("out"), {}, 100, 800, 12, {"decode": 0.5, "frontend": 1.0,
    ...                "tracker": 0.5, "write": 3.0}, None)
    >>> run.fps
    50.0
    """

    out_dir: Path
    files: dict
    frames: int
    rows: int
    tracks: int
    seconds: dict
    scores: MOTCounts | None
    config: TrackConfig | None = None
    derived: dict | None = None
    first: int = 1
    last: int = 0
    replaced_rate: tuple[str, float] | None = None

    @property
    def fps(self) -> float:
        """Frames per second of decode, front-end and tracker together (compiling left out).

        Examples
        --------
        >>> VideoRun(Path("out"), {}, 10, 0, 0, {"decode": 0.1, "tracker": 0.1,
        ...          "write": 5.0}, None).fps
        50.0
        """
        s = sum(v for k, v in self.seconds.items() if k not in ("write", "compile"))
        return self.frames / max(s, 1e-12)


RUN_INFO = "run.json"
"""The file :func:`track_video` writes beside its outputs to say how they were made (the
command, the input, the ground truth, the frames, the scores, the warnings), which
:func:`vistrack.report.write_report` reads."""

REPORT = "report.html"
"""The page :func:`vistrack.report.write_report` writes beside a run's outputs; a run that
replaces the outputs (``force``) removes an earlier run's, which would describe other
tracks."""


def input_files(video: str | Path | None, *, gt: str | Path | None = None,
                frontend: object = None, config: str | Path | None = None
                ) -> list[Input]:
    """The files a run of :func:`track_video` or :func:`track_one` reads, each with what a
    message calls it (None where not given): no output may be one of them
    (:func:`~vistrack.io.atomic.check_not_input`). ``gt`` is a file or a sequence folder
    (its ``gt/gt.txt``); ``frontend`` a front-end's name (``detections:FILE`` and
    ``onnx:MODEL.onnx`` read a file); ``config`` the configuration file read. A video that
    is a folder reads the images of its folder (a sequence's ``imDir``, and its
    ``seqinfo.ini``): no output may be an image there.

    Examples
    --------
    >>> [(what, str(p)) for what, p in input_files("in.avi", frontend="detections:d.txt")
    ...  if p is not None]
    [('the video tracked', 'in.avi'), ('the detections file (--frontend detections:FILE)', \
'd.txt')]
    """
    from .io.video import IMAGE_SUFFIXES, VideoError, images_of

    gt_file = None
    if gt is not None:
        try:
            gt_file = _ground_truth_file(gt)
        except ValueError:  # (a folder without gt/gt.txt: the run names it, reading it)
            pass

    read: list[Input] = []
    if video is not None and Path(video).is_dir():
        # the images (a sequence folder's imDir/), and the sequence's seqinfo.ini
        v = Path(video)
        if (v / "seqinfo.ini").is_file():
            read.append(("the sequence's seqinfo.ini", v / "seqinfo.ini"))
        try:
            images = images_of(v)
        except VideoError:  # (the reader names what is wrong with the file)
            images = v / "img1"
        read.append(("the folder of the images tracked", images, IMAGE_SUFFIXES))
    else:
        read.append(("the video tracked", None if video is None else Path(video)))
    read += [("the ground truth (--gt)", gt_file),
             ("the configuration file (--config)", None if config is None else Path(config))]
    if isinstance(frontend, str):
        for kind, (form, what, _) in _FILE_FRONTENDS.items():
            if frontend.startswith(kind + ":") and frontend != kind + ":":
                read.append((f"the {what} (--frontend {form})", Path(frontend.split(":", 1)[1])))
    return read


def sequence_inputs(seq_dir: str | Path, detections: str | Path | None = None
                    ) -> list[tuple[str, Path | None]]:
    """The files :func:`track_sequence` reads, each with what a message calls it, which its
    results may not be (:func:`~vistrack.io.atomic.check_not_input`): the detections file
    (``seq_dir`` itself, ``detections``, or the sequence's ``det/det.txt``), and a sequence
    folder's ``seqinfo.ini``, ``gt/gt.txt`` and ``det/det.txt``.

    Examples
    --------
    >>> [(what, str(p)) for what, p in sequence_inputs("dets.txt")]
    [('the detections file', 'dets.txt')]
    """
    seq = Path(seq_dir)
    if not seq.is_dir():
        return [("the detections file", seq)]
    return [("the detections file", Path(detections) if detections is not None
             else seq / "det" / "det.txt"),
            ("the sequence's seqinfo.ini", seq / "seqinfo.ini"),
            ("the sequence's ground truth", seq / "gt" / "gt.txt"),
            ("the sequence's detections file", seq / "det" / "det.txt")]


def video_outputs(out_dir: str | Path, *, annotate: bool = True, force: bool = False,
                  name: str = "out_dir", points: bool = False,
                  inputs: Sequence[Input] = ()) -> dict[str, Path]:
    """The file of each sink :func:`track_video` writes in ``out_dir``, checked before any
    work is done: ``out_dir`` is a folder or can be made one, can be written in, its
    outputs (``run.json`` too, which is not a sink's, and an earlier run's ``report.html``)
    are not folders, exist only if ``force``, and are none of the run's ``inputs``
    (:func:`input_files`), which ``force`` would write over.

    ``name`` names the argument or option in the messages. With ``points`` (a tracker of
    point tracks, whose rows are no boxes) there is no ``tracks.txt``, and without
    ``annotate`` no ``annotated.mp4``; an earlier run's is checked as the outputs are, and
    removed when the run's outputs are written.

    Raises
    ------
    NotADirectoryError
        If ``out_dir`` or a folder above it is a file.
    IsADirectoryError
        If an output's name is a folder.
    PermissionError
        If the output folder (or the nearest existing one above it) cannot be written in.
    FileExistsError
        If an output exists and ``force`` is False.
    ValueError
        If an output is one of ``inputs``.

    Examples
    --------
    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp()) / "out"
    >>> sorted(p.name for p in video_outputs(out, annotate=False).values())
    ['tracks.csv', 'tracks.txt', 'trajectories.png']
    """
    out_dir = Path(out_dir)
    check_output(out_dir, name=name, folder=True)
    files = {key: out_dir / SINK_FILES[key] for key in SINKS
             if (annotate or key != "video") and not (points and key == "tracks")}
    # and how they were made, and the page that showed an earlier run's (and its tracks.txt,
    # where these tracks are points, and its video, where none is made)
    written = [*files.values(), out_dir / RUN_INFO, out_dir / REPORT,
               *[out_dir / SINK_FILES[key] for key in ("tracks", "video") if key not in files]]
    for p in written:
        if p.is_dir():
            raise IsADirectoryError(f"{name} {out_dir}: {p} is a folder, not a file")
    # (named first: "exist; pass --force" would have the input overwritten next)
    check_not_input(written, inputs, name=name, given=out_dir)
    there = [str(p) for p in written if p.exists()]
    if there and not force:
        raise FileExistsError(f"{', '.join(there)} exist{'s' if len(there) == 1 else ''}; "
                              f"pass {force_option(name)} to overwrite "
                              + ("it" if len(there) == 1 else "them"))
    return files


def track_video(video: str | Path, out_dir: str | Path, *,
                frontend: str | Detector | Callable[[Frame], Detections | None] | None = None,
                fps: float | None = None, tracker: str | Tracker | None = None,
                gt: str | Path | None = None, background: str | None = None,
                min_area: float | None = None, n_init: int | None = None,
                follow_view: bool | None = None, stop: int | None = None,
                skip_bad_frames: bool = False,
                annotate: bool = True, force: bool = False, progress: TextIO | None = None,
                confidence: Callable[[np.ndarray], ConfidenceMap] | None = None,
                det_threshold: float | None = None, classes: Sequence[int] | None = None,
                onnx_layout: str | None = None, config: TrackConfig | None = None,
                command: str | None = None, columns: dict[str, str] | None = None,
                diameter: int | None = None, minmass: float | None = None,
                invert: bool | None = None, zero_distance: float | None = None,
                **overrides: object) -> VideoRun:
    """Track a video (a file, an image folder or a MOTChallenge sequence folder) from pixels.

    Writes into ``out_dir`` (:data:`SINKS`): ``tracks.txt`` (MOTChallenge results),
    ``tracks.csv``, ``annotated.mp4`` (boxes, identities, trails and 2-sigma ellipses of the
    centres) and ``trajectories.png``, and ``run.json`` (how they were made, which
    :mod:`vistrack.report` reads); scores against ``gt`` (a MOTChallenge ground-truth file)
    when given. A tracker of points (``particles``) writes no ``tracks.txt``: its
    ``tracks.csv`` holds ``frame,particle,x,y`` (:class:`~vistrack.io.PointsCSVWriter`).

    Parameters
    ----------
    video : str or Path
        A video file, an image folder or a MOTChallenge sequence folder.
    out_dir : str or Path
        The output folder (made if needed; its files are not overwritten unless ``force``).
    frontend : str or detector, optional
        A name in :data:`FRONTENDS`: ``"bgsub"`` (the seeds' background model, then blobs),
        ``"hog"`` (OpenCV's people detector), ``"confidence"`` (the peaks of the detector's
        confidence map above ``det_threshold``), ``"spots"`` (round spots of ``diameter``
        pixels, microscopy: :func:`~vistrack.frontends.spots.locate`);
        ``"detections:FILE"`` (a MOTChallenge
        detections file, or CSV; where its rows lie on every k-th frame only, a box tracker
        steps through those frames alone, at the frame rate divided by k, and each frame
        between gets its tracks' predicted boxes, as in :func:`track_sequence`);
        ``"onnx:MODEL.onnx"`` (your own ONNX detector, YOLO- or SSD-style,
        run by onnxruntime: :class:`~vistrack.frontends.onnx.ONNXDetector`); or a detector
        of your own: any object with ``detect(image) ->
        Detections`` (:class:`vistrack.frontends.detectors.Detector`). Default: the
        tracker's (``bgsub``; ``confidence`` for ``dcpf``, ``spots`` for ``particles``).
    tracker : str or Tracker, optional
        A name in :data:`TRACKERS`: a box tracker's preset (``"bytetrack"``, ``"sort"``;
        ``overrides`` are fields of its configuration), ``"dcpf"`` (the detector-confidence
        particle filter; ``overrides`` are fields of its
        :class:`~vistrack.tracking.dcpf.DCPFConfig`), ``"particles"`` (drifting points,
        linked by global nearest neighbour; ``overrides`` ``search_range``, the radius of a
        track's gate one frame after an update in pixels and the farthest a link reaches
        from its predicted position, default
        half ``diameter``, and
        ``max_lost``, seconds, default 3.5 frames), ``"single:METHOD"`` (one object,
        from the first frame's most confident detection); ``"module:callable"``; or any
        tracker object (:class:`~vistrack.tracking.Tracker`). Default: ``"particles"`` with
        the ``spots`` front-end, else ``"bytetrack"``.
    gt : str or Path, optional
        A MOTChallenge ground-truth file, scored over the frames tracked (or a CSV or Parquet
        file with a header; for points, ``frame, particle, x, y``).
    zero_distance : float, optional
        With ``gt``: score positions by distance rather than boxes by IoU
        (:func:`~vistrack.evaluation.evaluate_mot`; a match lies within half of it). Points
        are always scored so, by default at the spots' ``diameter``: a match within a
        particle's radius.
    confidence, det_threshold : callable, float
        The detector's continuous confidence, a callable ``image -> ConfidenceMap`` (default
        :class:`vistrack.frontends.detectors.HOGConfidence`), for ``dcpf`` and the
        ``confidence`` front-end, and the SVM margin above which its peaks are detections
        (``confidence`` only; default 0.5).
    command : str, optional
        The command line that asked for this run, kept in ``run.json`` (written beside the
        outputs: the command, the input, the ground truth, the frames, the scores, and the
        messages of the warnings the run gave), which ``vistrack report`` reads.
    classes, onnx_layout : sequence of int, str
        For ``onnx:MODEL`` only: the model's classes kept (default all) and its output layout
        (:data:`~vistrack.frontends.onnx.LAYOUTS`; default ``"auto"``, told from the
        outputs).
    columns : dict, optional
        For ``detections:FILE`` only: the names of a CSV file's columns, ``{ours: theirs}``
        (:func:`read_detections`; ``--columns`` on the command line).
    fps : float, optional
        The true frame rate, when the container's header is wrong.
    diameter, minmass, invert : int, float, bool
        For ``spots`` only: the spots' diameter in pixels, odd (needed), the least mass kept
        (default 0), and whether the spots are darker than the background
        (:func:`~vistrack.frontends.spots.locate`).
    background, min_area, n_init, follow_view : str, float, int, bool
        For ``bgsub`` only: the background model's name (default ``"selective"``), the
        smallest blob in pixels (500), the frames whose median starts the model (20), and
        whether the selective model follows a view that moves (default True; False: the
        camera is still, and a view found moving is only said to move:
        :class:`~vistrack.frontends.BlobDetector`). The background model takes the view as
        still, moving itself where the view moves, so with ``bgsub`` the box tracker's
        ``camera_motion`` is off unless passed. A front-end's own option given with another
        front-end would change nothing, and is refused (:data:`FRONTEND_OPTIONS`).
    stop : int, optional
        The last frame to track (default: all).
    skip_bad_frames : bool
        In an image folder, skip an image that cannot be read (or is cut short, or of another
        size) with a ``RuntimeWarning`` naming it, instead of stopping with a
        :class:`~vistrack.io.VideoError`; the frames after it keep their numbers.
    annotate : bool
        Also write ``annotated.mp4``.
    force : bool
        Overwrite the output files.
    progress
        A stream for a progress bar, or None.
    config : TrackConfig, optional
        The whole configuration of a box tracker (:class:`~vistrack.config.TrackConfig`), used
        as it is: the ``bgsub`` front-end's default (no camera motion) is not put over it.
        ``overrides`` then change its tracker's settings.

    **overrides
        Settings of the tracker (fields of its configuration).

    Returns
    -------
    VideoRun
        The files written, counts, seconds per stage and the scores.

    Raises
    ------
    FileExistsError
        If an output file exists and ``force`` is False.
    IsADirectoryError, NotADirectoryError, PermissionError
        If an output cannot be written (:func:`video_outputs`); checked first, before
        anything is read.
    FileNotFoundError
        If the video, the ground truth or a detections file does not exist.
    ValueError
        If the video has no frames to track, ``config`` goes with a tracker that is not a
        box tracker, a front-end's option is given with another front-end, or a name or a
        setting is invalid.
    TypeError
        If ``confidence`` is not callable, or the tracker or front-end is not one.

    Examples
    --------
    Five frames of an image folder, with their detections from a MOTChallenge file:

    >>> import tempfile, cv2
    >>> folder = Path(tempfile.mkdtemp())
    >>> for k in range(5):
    ...     _ = cv2.imwrite(str(folder / f"{k + 1:06d}.png"), np.zeros((60, 80, 3), np.uint8))
    >>> dets = folder / "det.txt"
    >>> _ = dets.write_text("".join(f"{f},-1,{5 + 5 * f},20,20,20,0.9\\n" for f in range(1, 6)))
    >>> result = track_video(folder, folder / "out", frontend=f"detections:{dets}",
    ...                      annotate=False)
    >>> result.frames, result.rows, result.tracks, sorted(result.files)
    (5, 5, 1, ['csv', 'plot', 'tracks'])
    """
    from .io.video import VideoReader

    with _shown_warnings() as said:  # kept in run.json, each still shown as it comes
        if tracker is None:  # spots are points: the tracker of points goes with them
            tracker = "particles" if frontend == "spots" else "bytetrack"
        name = default_frontend(tracker) if frontend is None else frontend
        options = {"background": background, "min_area": min_area, "n_init": n_init,
                   "follow_view": follow_view, "det_threshold": det_threshold,
                   "classes": classes, "onnx_layout": onnx_layout, "columns": columns,
                   "diameter": diameter, "minmass": minmass, "invert": invert}
        unread = unread_frontend_option(name, options)
        if unread is not None:
            what = repr(name) if isinstance(name, str) else f"a {type(name).__name__}"
            raise ValueError(f"{unread[0]} goes with the {unread[1]!r} front-end; the front-end "
                             f"here, {what}, does not read it")
        points = isinstance(tracker, str) and tracker in TRACKERS and TRACKERS[tracker].points
        problem = points_problem(tracker, name)
        if problem:
            raise ValueError(problem)
        if zero_distance is not None and gt is None:
            raise ValueError("zero_distance scores the tracks against gt: give gt too")
        if points and gt is not None and zero_distance is None and diameter is not None:
            zero_distance = float(diameter)  # a match within the particle's radius
        if zero_distance is not None:
            zero_distance = check_zero_distance(zero_distance)
        files = video_outputs(out_dir, annotate=annotate, force=force, points=points,
                              inputs=input_files(video, gt=gt, frontend=name))
        out_dir = Path(out_dir)
        gt_table = _ground_truth(gt, zero_distance) if gt is not None else None
        if confidence is not None and not callable(confidence):
            raise TypeError(f"confidence must be a callable image -> ConfidenceMap; got "
                            f"{type(confidence).__name__}")
        reader = VideoReader(video, fps=fps, stop=stop, prefetch=8, skip_bad=skip_bad_frames)
        if reader.image_folder is not None and out_dir.resolve() == reader.image_folder.resolve():
            # the outputs among the frames: the next run reads trajectories.png as one (and fails,
            # or with skip_bad_frames numbers every image after it a frame early)
            raise ValueError(f"{out_dir} is the folder of the images being tracked: the outputs "
                             "would be read as frames by the next run; write them to another "
                             "folder (--out-dir)")
        if reader.fps_from is None:
            # the tracker's times (coasting, how long a lost track is kept) and its motion's
            # noise follow the rate
            warnings.warn(f"{video} gives no frame rate (an image folder, or a video whose "
                          f"header has none): tracked at {reader.fps:g} frames/s (give the true "
                          "one with --fps, or fps=)", UserWarning, stacklevel=2)
        elif gt is not None and reader.fps_from != "fps":
            disagree = _gt_rate_disagrees(video, reader.fps, reader.fps_from, gt)
            if disagree:
                warnings.warn(disagree, UserWarning, stacklevel=2)
        # the options not given are left to the front-ends' own defaults
        ctx = Context(reader.fps, reader.size, reader, config, dict(overrides),
                      {k: v for k, v in options.items() if v is not None}
                      | {"confidence": confidence}, points=points)
        box = isinstance(tracker, str) and tracker in TRACKERS and TRACKERS[tracker].box_config
        if box and reader.fps_from not in (None, "fps") and not _a_frame_rate(reader.fps):
            # (named by the motion model later, as frame_rate, without the file; the other
            # trackers take any rate)
            raise ValueError(f"{video}: its {reader.fps_from.removeprefix('the ')} gives "
                             f"{reader.fps:g} frames/s, and the box tracker takes "
                             f"{FRAME_RATES[0]:g} to {FRAME_RATES[1]:g} (give the true rate "
                             "with --fps, or fps=)")
        if config is not None and not box:
            raise ValueError(f"config is a box tracker's configuration; tracker {tracker!r} is "
                             "not a box tracker")
        if box and config is None and isinstance(name, str) and name in FRONTENDS \
                and FRONTENDS[name].still_camera:
            # a background model works only with a still camera: nothing to compensate, and
            # blobs that split and merge would read as small shifts of the camera
            ctx.overrides.setdefault("camera_motion", False)
        detect = _frontend(name, ctx)
        # a detector run on every k-th frame: a box tracker by name steps through its frames
        # alone, at the video's frame rate / k (as track_sequence), and over the frames it did
        # not deliver; any other tracker, or one made by the caller, keeps its rate and every
        # frame
        grid = detect if isinstance(detect, _FileDetections) else None
        # the last frame tracked, where known before the run: an image folder's last image
        # (a video's header may count fewer frames than it holds) or the stop; the frames of
        # a detections file past it are not said to be frames without detections (they are
        # said to be past the video's end, after the run)
        known_end = min((k for k in (reader.stop, reader.frame_count if
                                     reader.image_folder is not None else None) if k),
                        default=None)
        if grid is not None:
            warn_outside(grid.dets, grid.path, reader.size, stacklevel=2, columns=grid.columns)
        if box and grid is not None:
            at_rate = replace(ctx, fps=ctx.fps / grid.stride)
            trk, _ = make_tracker(tracker, at_rate)
            assert isinstance(trk, BoxTracker)  # a box preset's
            ctx.resolved = at_rate.resolved
            if trk.config.nms_iou >= 1:  # as track_sequence warns, with the tracker's setting
                warn_duplicates(grid.dets, grid.path, stacklevel=2)
            stepper, _ = _on_detector_frames(trk, grid.path, grid.dets.frames, grid.first,
                                             grid.stride, offline=False, last=known_end)
        else:
            trk, _ = make_tracker(tracker, ctx)
            stepper = trk
            if grid is not None:
                # what the file's frames are that this tracker steps through as found nothing
                # runs up to an hour (a longer silence is no frame the detector dropped; a
                # stray frame number of 10^11 listed its run frame by frame: 745 GiB)
                skip = (undelivered_frames(grid.dets.frames,
                                           max_run=math.ceil(3600 * ctx.fps))
                        if grid.stride == 1 else np.zeros(0, np.int64))
                if known_end is not None:
                    skip = skip[skip <= known_end]
                gaps = (f"detections on every {ordinal(grid.stride)} frame only"
                        if grid.stride > 1 else undelivered_text(skip) if len(skip) else "")
                if gaps:
                    warnings.warn(f"{grid.path}: {gaps}: the tracker, {type(trk).__name__}, steps "
                                  "through every frame of the video, each frame without "
                                  "detections as one where nothing was found", RuntimeWarning,
                                  stacklevel=2)
        if grid is not None and isinstance(trk, BoxTracker) and len(grid.dets):
            _warn_no_start(grid.path, grid.dets.conf, trk.config, None, stacklevel=2)
        scored: list[MOTCounts] = []

        def check(stats: LoopStats) -> None:
            # what can still fail is found before the sinks are closed: a failed run writes
            # nothing, and with force an earlier run's files stay as they were
            if stats.frames == 0:
                raise ValueError(f"{video}: no frames to track")
            if gt_table is not None:  # scored over the frames tracked
                g = gt_table[(gt_table.frames >= reader.start) & (gt_table.frames <= stats.last)]
                if not len(g):
                    warnings.warn(f"{gt}: no ground-truth rows on the frames tracked "
                                  f"({reader.start}-{stats.last}): every box tracked counts as a "
                                  "false positive", UserWarning, stacklevel=4)
                tracks = sinks["csv" if points else "tracks"]
                assert isinstance(tracks, (MOTWriter, PointsCSVWriter))
                written = tracks.written()
                scored.append(evaluate_mot(g, written, stats.last, benchmark="auto",
                                           zero_distance=zero_distance))
                # as vistrack eval warns: another sequence's ground truth scores valid numbers
                # (results left empty by a front-end that found nothing: the run says so
                # itself, after the loop)
                for message in sanity_warnings(g, written,
                                               empty_said=found_nothing() or not len(g),
                                               zero_distance=zero_distance):
                    warnings.warn(message, UserWarning, stacklevel=4)

        found = 0  # what a front-end from pixels found (a detections file is checked as read)
        top, bottom = -np.inf, np.inf  # and the highest and lowest of its scores
        call = as_detector(detect)
        if grid is None and call is not None:
            inner = call

            def counting(frame: Frame) -> Detections | None:
                nonlocal found, top, bottom
                d = inner(frame)
                if d is not None and len(d):
                    found += len(d)
                    assert d.scores is not None  # Detections fills them (1) where not given
                    top = max(top, float(d.scores.max()))
                    bottom = min(bottom, float(d.scores.min()))
                return d

            call = counting

        def found_nothing() -> bool:  # a front-end from pixels that found nothing (said below)
            return grid is None and call is not None and not found

        # the folder removed again, if made here, when the run fails; the outputs renamed
        # into place together, run.json with them, once all are complete (Ctrl-C between
        # two left new tracks beside an earlier run's video, plot and run.json)
        with made_folder(out_dir), together():
            sinks: dict[str, Sink] = {}
            try:
                for key, path in files.items():
                    sinks[key] = SINKS[key](path, ctx, reader.source.name)
            except BaseException:  # the partial files of those made (and the folder made)
                _abort(list(sinks.values()))
                raise
            stats = run(reader, call, stepper, list(sinks.values()), progress=progress,
                        total=len(reader), label=reader.source.name, check=check)
            n = stats.frames
            if found_nothing():
                # an empty result said nothing: tracks, video and plot written, none with a box
                what = f"the {name} front-end" if isinstance(name, str) else "the front-end"
                hint = ""
                if name == "bgsub":
                    hint = (f" (blobs of {ctx.options.get('min_area', 500.0):g} pixels or "
                            "more where a frame differs from the background model; to find "
                            "more, try a smaller --min-area, --background mog2, or a "
                            "detector: --frontend hog)")
                elif name == "spots":
                    hint = (f" ({'dark' if invert else 'bright'} spots of diameter {diameter} "
                            f"whose mass is above {minmass or 0:g}; "
                            + ("spots brighter than the background need no --invert"
                               if invert else "for dark spots on a light background, --invert")
                            + ", or another --diameter or --minmass)")
                warnings.warn(f"{video}: {what} found nothing in {counted(n, 'frame')}{hint}: the "
                              "results hold no rows", UserWarning, stacklevel=2)
            elif grid is None and found and isinstance(trk, BoxTracker):
                # a detector's raw scores all below the start: its boxes were found and dropped
                what = f"the {name} front-end" if isinstance(name, str) else "the front-end"
                _warn_no_start(f"{video}: {what}", np.array([bottom, top]), trk.config, None,
                               stacklevel=2)
            rows = sinks["csv" if points else "tracks"]
            assert isinstance(rows, (MOTWriter, PointsCSVWriter))
            last = stats.last
            # the video ended before stop (not --stop's own end, nor a missing image at it: a
            # folder without its frame 5 stopped at 5 warned of "rows past the video's last
            # frame (4)")
            ended = stop is None or (reader.frame_count < stop if reader.frame_count
                                     else last < stop)
            # rows past the video's last frame were for nothing; rows past --stop are what was
            # asked for, and not said, but with --stop the rows past the video's own end are
            # said still (they went without a word)
            end = last if ended else (reader.frame_count or None)
            for table, what, label in ((grid.dets if grid is not None else None, "not tracked",
                                        grid.path if grid is not None else None),
                                       (gt_table, "not scored", gt)):
                if end is not None and table is not None and len(table) and \
                        table.frames[-1] > end:
                    past = table.frames[table.frames > end]
                    on = f"{counted(len(past), 'row')} on {frames_text(past[0], past[-1])}"
                    warnings.warn(f"{label}: {on}, "
                                  f"past the video's last frame ({end}): {what}", UserWarning,
                                  stacklevel=2)
            if grid is not None and len(grid.dets) and last is not None:
                _warn_detections_end(grid, last, reader.fps)
            scores = scored[0] if scored else None
            n_tracks = len(rows.identities)
            if isinstance(trk, BoxTracker):
                _warn_calibration(trk, str(video))
            started = start_warning(trk, str(video))
            if started is not None:
                warnings.warn(started, RuntimeWarning, stacklevel=2)
            result = VideoRun(out_dir, files, n, len(rows), n_tracks, stats.seconds, scores,
                              ctx.resolved if isinstance(trk, BoxTracker) else None,
                              _run_derived(trk),
                              reader.start, stats.last, _replaced_rate(reader))
            _write_run_info(result, video, gt, command, reader.fps, said, points=points,
                            zero_distance=zero_distance)
            # an earlier run's page would show other tracks beside these outputs (a new one, if
            # asked for, is written from run.json after this)
            remove_on_commit(out_dir / REPORT)
            if points:  # an earlier run's box tracks would read as this run's
                remove_on_commit(out_dir / SINK_FILES["tracks"])
            if not annotate:  # and its video would show other tracks (the report showed it)
                remove_on_commit(out_dir / SINK_FILES["video"])
            return result


def _replaced_rate(reader: VideoReader) -> tuple[str, float] | None:
    """What gives the frame rate that ``fps`` was put over, and that rate
    (:attr:`VideoRun.replaced_rate`); None where the source gives none, or the same."""
    own = reader.own_fps
    if reader.fps_from != "fps" or own is None or math.isclose(own, reader.fps):
        return None
    return str(reader.own_fps_from), own


def _gt_rate_disagrees(video: str | Path, fps: float, fps_from: str,
                       gt: str | Path) -> str | None:
    """Where the ground truth lies in a MOTChallenge sequence (``SEQ/gt/gt.txt``) whose
    ``seqinfo.ini`` gives another frame rate than the video's own (``fps_from``, its header),
    a warning saying both; None where they agree, or there is no such file to read. (A video
    whose header is wrong, as PETS09's vtest.avi says 10 frames/s for 7, was tracked at its
    header's rate without a word beside the sequence's own file.)"""
    from .io.motchallenge import _ground_truth_file

    try:
        truth = _ground_truth_file(gt)
    except ValueError:
        return None
    ini = truth.parent.parent / "seqinfo.ini"
    if truth.parent.name != "gt" or not ini.is_file():
        return None
    try:
        rate = read_seqinfo(ini.parent).frame_rate
    except (OSError, ValueError):  # (a seqinfo.ini of its own faults: the ground truth's
        return None                # file is what is read; nothing to compare)
    if math.isclose(rate, fps, rel_tol=1e-6):
        return None
    return (f"{video}: its {fps_from.removeprefix('the ')} gives {fps:g} frames/s, and the "
            f"ground truth's sequence {rate:g} ({ini}): tracked at {fps:g} (give the true rate "
            "with --fps, or fps=)")


def _ground_truth(gt: str | Path, zero_distance: float | None = None) -> MOTTable:
    """The ground truth to score a video's tracks against (a file, or a sequence folder's
    ``gt/gt.txt``), read and checked before anything is tracked: a missing file is named as
    ``--gt``'s, and the faults the scoring would find after the whole video (an identity
    twice in a frame, a detections file given as ground truth) are found now. A CSV or
    Parquet file is read as ``vistrack eval`` reads one (:func:`~vistrack.evaluation.files.
    read_truth`), x, y alone as points where they are scored by distance
    (``zero_distance``)."""
    from .evaluation.files import read_truth

    try:
        table = read_truth(_ground_truth_file(gt), points=zero_distance is not None)
    except FileNotFoundError:
        raise FileNotFoundError(f"{gt} does not exist (--gt FILE)") from None
    evaluate_mot(table, MOTTable.from_rows(np.zeros((0, 6)), str(gt)), benchmark="auto",
                 zero_distance=zero_distance)
    return table


@contextmanager
def _shown_warnings() -> Iterator[list[str]]:
    """The messages of the warnings shown while inside, in the order shown, by this thread:
    each is still shown as it comes (by whatever shows warnings outside: the command line's
    one line, a test's recorder), and kept. Warnings that the filters hide or turn into
    errors are not kept.

    Runs in threads of one process (a thread pool given to
    :func:`~vistrack.batch.track_many`) keep their own: ``warnings.catch_warnings``, which
    this used, swaps the process's one ``showwarning`` and is not safe in threads, so every
    run's ``run.json`` listed every other's warnings, and a swapped hook could be left
    behind. One hook is put in while any thread keeps warnings, and taken out after the
    last.

    Examples
    --------
    >>> with warnings.catch_warnings(record=True):
    ...     with _shown_warnings() as said:
    ...         warnings.warn("a.txt: no detections", UserWarning)
    >>> said
    ['a.txt: no detections']
    """
    global _KEEPING
    said: list[str] = []
    with _KEEP_LOCK:
        if _KEEPING == 0:
            _SHOWN["show"] = warnings.showwarning
            warnings.showwarning = _keep_shown
        _KEEPING += 1
    kept = getattr(_KEPT, "lists", [])
    _KEPT.lists = [*kept, said]
    try:
        yield said
    finally:
        _KEPT.lists = kept
        with _KEEP_LOCK:
            _KEEPING -= 1
            if _KEEPING == 0 and warnings.showwarning is _keep_shown:
                warnings.showwarning = _SHOWN.pop("show")


_KEPT = threading.local()  # each thread's lists of kept messages, outermost first
_KEEP_LOCK = threading.Lock()
_KEEPING = 0  # the blocks of _shown_warnings open, in every thread
_SHOWN: dict[str, Any] = {}  # what showed warnings before the first block opened


def _keep_shown(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                file: Any = None, line: str | None = None) -> None:
    """``warnings.showwarning`` while :func:`_shown_warnings` blocks are open: the message
    kept in each of the calling thread's open blocks, then shown as before them."""
    for said in getattr(_KEPT, "lists", ()):
        said.append(str(message))
    _SHOWN["show"](message, category, filename, lineno, file, line)


def _write_run_info(run: VideoRun, video: str | Path, gt: str | Path | None,
                    command: str | None, frame_rate: float, said: Sequence[str] = (), *,
                    points: bool = False, zero_distance: float | None = None) -> None:
    """``run.json`` beside a run's outputs: how they were made (:mod:`vistrack.report`;
    ``fps`` the frames tracked a second, ``frame_rate`` the video's, ``warnings`` the
    messages of the warnings the run gave, ``said``; ``points`` where the tracks are points,
    which have no ``tracks.txt``)."""
    import json

    from . import __version__
    from .io.atomic import replacing

    info = {"command": command, "vistrack": __version__, "name": sequence_name(video),
            "input": str(Path(video).resolve()),
            # the file scored (a sequence folder's gt/gt.txt), which the report reads
            "gt": str(Path(_ground_truth_file(gt)).resolve()) if gt is not None else None,
            "first_frame": run.first, "last_frame": run.last or run.first + run.frames - 1,
            "frames": run.frames, "rows": run.rows, "tracks": run.tracks,
            # unrounded: the report rounds it once, as the run's line did (81.46 was kept as
            # 81.5, and the page said 82 where the run had said 81)
            "fps": run.fps, "frame_rate": frame_rate,
            "scores": run.scores.summary() if run.scores is not None else None,
            "outputs": sorted(f.name for f in run.files.values()),
            "warnings": list(said), "points": points,
            # how the scores were taken (None: boxes by IoU), for the report's plots
            "zero_distance": zero_distance}
    with replacing(run.out_dir / RUN_INFO) as part:
        part.write_text(json.dumps(info, indent=2) + "\n")


def _keep_warnings(out_dir: str | Path, said: Sequence[str], *, before: bool = False) -> None:
    """``run.json``'s ``warnings`` (:func:`_write_run_info`) made ``said``: the warnings of the
    whole command, those it gave before the run (a setting that changes nothing) with the
    run's own, in the order shown; with ``before``, ``said`` are the command's alone, put
    before the run's own (a run in a worker of a batch, which kept its own)."""
    import json

    from .io.atomic import replacing

    path = Path(out_dir) / RUN_INFO
    info = json.loads(path.read_text(encoding="utf-8"))
    want = list(said) + (list(info.get("warnings", [])) if before else [])
    if info.get("warnings") != want:
        info["warnings"] = want
        with replacing(path) as part:
            part.write_text(json.dumps(info, indent=2) + "\n")


# -------------------------------------------------------------------- one object, by hand
@dataclass(frozen=True)
class SingleRun:
    """What :func:`track_one` did: the boxes file, the boxes ``(T, 4)``, the tracker's
    seconds, and the scores against ground truth (``success``, ``auc``, ``precision``; None
    without it).

    Attributes
    ----------
    out : Path
        The boxes file written.
    boxes : (T, 4) ndarray
        The box ``x, y, w, h`` in each frame (the first is ``init``).
    seconds : float
        Seconds spent in the tracker.
    scores : dict of str to float or None
        ``success``, ``auc`` and ``precision`` against the ground truth.

    Examples
    --------
    >>> SingleRun(Path("boxes.txt"), np.zeros((11, 4)), 0.5, None).fps
    20.0
    """

    out: Path
    boxes: np.ndarray
    seconds: float
    scores: dict | None

    @property
    def fps(self) -> float:
        """Frames followed per second of tracking (the first frame, where the tracker
        starts, not counted).

        Examples
        --------
        >>> SingleRun(Path("boxes.txt"), np.zeros((5, 4)), 0.1, None).fps
        40.0
        """
        return max(len(self.boxes) - 1, 0) / max(self.seconds, 1e-12)


def track_one(source: str | Path, init: ArrayLike | None, out: str | Path, *,
              method: str = "colour", gt: str | Path | None = None, force: bool = False,
              progress: TextIO | None = None, init_name: str = "init",
              gt_origin: int | None = None) -> SingleRun:
    """Follow one object from its box ``init`` (``x, y, w, h`` in the first frame) through a
    video or image folder, and write ``frame,x,y,w,h`` lines (frames from 1) to ``out``.

    ``method`` is a name in :data:`vistrack.tracking.single.METHODS`; ``gt`` a ground-truth
    file (OTB ``groundtruth_rect.txt``, VOT ``groundtruth.txt`` or a boxes file) to score
    against. The loop is :func:`run`'s: the first frame's detection is ``init``, which starts
    the tracker (:class:`~vistrack.tracking.SingleObjectTracker`).

    Parameters
    ----------
    source : str or Path
        A video file or an image folder.
    init : (4,) array_like or None
        The object's box ``x, y, w, h`` in the first frame, in 0-based pixels (the top-left
        pixel's corner at 0, 0; OTB's files count from 1); None: ``gt``'s first box (read
        by :func:`~vistrack.evaluation.single.read_boxes`, 0-based).
    out : str or Path
        The boxes file to write (not overwritten unless ``force``).
    method : str
        A name in :data:`vistrack.tracking.single.METHODS`.
    gt : str or Path, optional
        A ground-truth file, with a box for every frame tracked.
    force : bool
        Overwrite ``out``.
    progress
        A stream for a progress bar, or None.
    init_name : str
        What an error about the start box calls it (``--init`` on the command line).
    gt_origin : {0, 1}, optional
        Where ``gt``'s ``x y w h`` lines count pixels from (``origin`` of
        :func:`~vistrack.evaluation.single.read_boxes`); None: by its name, 1 for OTB's
        ``groundtruth_rect.txt``, else 0, with a warning where the two differ (a copy of
        OTB's file renamed moved the start box and the scores by a pixel, without a word).

    Returns
    -------
    SingleRun
        The file written, the boxes, the tracker's seconds and the scores.

    Raises
    ------
    FileExistsError
        If ``out`` exists and ``force`` is False.
    IsADirectoryError, NotADirectoryError, PermissionError
        If ``out`` cannot be written (:func:`vistrack.io.atomic.check_output`); checked
        first, before anything is read.
    ValueError
        If ``method`` is unknown, ``init`` is not a box, is less than half inside the first
        frame, or is None without ``gt``, ``gt`` has fewer boxes than frames, ``out`` is the
        video or ``gt`` (:func:`~vistrack.io.atomic.check_not_input`), or the video has no
        frames.

    Examples
    --------
    A red square moving 5 pixels a frame over green:

    >>> import tempfile, cv2
    >>> folder = Path(tempfile.mkdtemp())
    >>> for k in range(4):
    ...     im = np.full((60, 80, 3), (40, 120, 40), np.uint8)
    ...     im[20:40, 10 + 5 * k:30 + 5 * k] = (0, 0, 255)
    ...     _ = cv2.imwrite(str(folder / f"{k + 1:06d}.png"), im)
    >>> result = track_one(folder, [10, 20, 20, 20], folder / "boxes.txt", method="wsl")
    >>> result.boxes[:, 0].round().tolist()
    [10.0, 15.0, 20.0, 25.0]
    >>> (folder / "boxes.txt").read_text().splitlines()[1]
    '2,15.00,20.00,20.00,20.00'
    """
    from ._validate import as_box
    from .evaluation.single import (
        _read_box_rows,
        boxes_origin,
        precision,
        success_curve,
        success_rate,
    )
    from .io.video import VideoReader
    from .tracking.single import single_tracker

    out = Path(out)
    check_not_input([out], input_files(source, gt=gt), name="out")
    check_output(out, force=force)
    tracker = single_tracker(method)
    truth, gt_first = None, None
    if gt is not None:
        try:
            truth, width, gt_first = _read_box_rows(gt, origin=gt_origin)
        except FileNotFoundError:  # (named as the track command names it)
            raise FileNotFoundError(f"{gt} does not exist (--gt FILE)") from None
        except IsADirectoryError:
            raise IsADirectoryError(f"{gt} is a folder, not a file (--gt FILE)") from None
        if gt_origin is not None and width not in (0, 4):
            # (taken, and changing nothing: polygons and frame,x,y,w,h lines have no origin
            # to choose)
            what = "polygons" if width == 8 else "frame,x,y,w,h lines"
            raise ValueError(f"gt_origin (--gt-origin) applies to x y w h lines; {gt} holds "
                             f"{what}")
        # x y w h lines (the only ones whose origin matters: read from 1 they differ) under a
        # name that is not OTB's: read from 0, and said so
        if gt_origin is None and not boxes_origin(gt) and width == 4:
            warnings.warn(f"{gt}: its x y w h boxes are read as counting pixels from 0, as "
                          "any such file not named OTB's groundtruth_rect.txt (which counts "
                          "from 1); --gt-origin 1 reads them from 1, --gt-origin 0 keeps 0 "
                          "without this warning", RuntimeWarning, stacklevel=2)
    if init is None:
        if truth is None:
            raise ValueError(f"{init_name} is required: the object's box in the first frame "
                             "(or a ground truth, whose first box is then the start)")
        if not len(truth):
            raise ValueError(f"{gt} has no boxes, so no first box to start from: give "
                             f"{init_name}, or a ground truth with a box for every frame")
        init = truth[0]
        # an error about the start box is about the ground truth's first box: one of another
        # sequence, most likely (it blamed --init, which was not given)
        init_name = f"the start, {gt}'s first box"
    start = Detections.from_xywh(as_box(init, init_name)[None])
    reader = VideoReader(source, prefetch=4)
    first = reader.start
    if truth is not None and gt_first is not None and gt_first not in (first, first - 1):
        # frame,x,y,w,h lines number their frames: of frames 201-320, they were scored as
        # the video's 1-120 without a word (numbered from 0 for frames from 1: taken)
        raise ValueError(f"{gt}'s frame,x,y,w,h lines start at frame {gt_first}; the video's "
                         f"frames start at {first}: a ground truth of other frames (its line "
                         "k is scored against the video's k-th frame; lines numbered from "
                         f"{first - 1} or {first} are taken)")
    if truth is not None and reader._files is not None and len(truth) < len(reader):
        # an image folder counts its frames exactly: refused before tracking them (checked
        # after the run, it cost the whole run first); a video's header may count wrong,
        # and is checked against the frames read (check, below)
        raise ValueError(f"{gt} has {counted(len(truth), 'box', 'boxes')} for "
                         f"{counted(len(reader), 'frame')}")

    def detect(frame: Frame) -> Detections | None:
        if frame.index != first:
            return None
        if frame.image is not None:  # named as the caller gave it
            check_start_box(frame.image, start.xywh[0], init_name)
        return start

    writer = BoxesWriter(out)

    def check(stats: LoopStats) -> None:  # before the file is written (run's check)
        if stats.frames == 0:  # (an empty file was written, and "-1e12 frames/s" said)
            raise ValueError(f"{source}: no frames to track")
        if truth is not None and len(truth) < len(writer.boxes):
            raise ValueError(f"{gt} has {counted(len(truth), 'box', 'boxes')} for "
                             f"{counted(len(writer.boxes), 'frame')}")

    with made_folder(out.parent):  # removed again, if made here, when the run fails
        stats = run(reader, detect, tracker, [writer], progress=progress, total=len(reader),
                    label=reader.source.name, check=check, detector_label=None)
    b = writer.boxes
    scores = None
    if truth is not None:
        if len(truth) > len(b):  # a ground truth of another, longer sequence?
            warnings.warn(f"{gt} has {counted(len(truth), 'box', 'boxes')} for "
                          f"{counted(len(b), 'frame')}: the last "
                          f"{len(truth) - len(b)} are not scored", UserWarning, stacklevel=2)
        t = truth[:len(b)]
        scores = {"success": success_rate(b, t), "auc": success_curve(b, t)[2],
                  "precision": precision(b, t)}
    return SingleRun(out, b, stats.seconds["tracker"], scores)

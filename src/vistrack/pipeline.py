"""Where the stages meet: detections from a file, a tracker, results and scores.

``track_sequence`` runs a tracker over a MOTChallenge sequence folder; ``evaluate_files`` scores
results files against ground truth. The command line (:mod:`vistrack.cli`) calls these.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from .config import OfflineConfig, TrackConfig
from .evaluation.mot import MOTCounts, combine, evaluate_mot
from .io.motchallenge import read_mot, read_seqinfo, write_mot
from .models.box import BoxMotion
from .tracking.box import BoxTracker
from .tracking.calibration import ScoreCalibration
from .tracking.lifecycle import Tracks
from .tracking.offline import smooth
from .types import Detections

__all__ = ["track_sequence", "TrackRun", "resolve_config", "derived_values", "evaluate_files",
           "track_video", "VideoRun", "FRONTENDS", "track_one", "SingleRun"]


@dataclass(frozen=True)
class TrackRun:
    """What :func:`track_sequence` did: the results file, frames, tracks, tracker time, the
    configuration used and the values derived from the data (:func:`derived_values`)."""

    out: Path
    frames: int
    detections: int
    rows: int
    tracks: int
    seconds: float
    config: TrackConfig | None = None
    derived: dict | None = None

    @property
    def fps(self) -> float:
        return self.frames / max(self.seconds, 1e-12)


def _progress(done: int, total: int, label: str, stream: Any) -> None:
    if stream is None:
        return
    width = 30
    k = int(width * done / max(total, 1))
    stream.write(f"\r{label} [{'#' * k}{'.' * (width - k)}] {done}/{total}")
    if done == total:
        stream.write("\n")
    stream.flush()


_OFFLINE_KEYS = {f.name for f in fields(OfflineConfig)}


def resolve_config(config: TrackConfig | str | None = None, *, tracker: str | None = None,
                   offline: bool | None = None, **overrides: Any) -> TrackConfig:
    """The configuration of a run: ``config`` (a :class:`~vistrack.config.TrackConfig` or a
    preset's name; default the ``tracker`` preset, else ``bytetrack``), with ``offline`` and
    ``overrides`` (fields of the tracker's or the offline mode's settings, or ``motion``, a
    :class:`~vistrack.models.BoxMotion`) put over it."""
    if isinstance(config, str) or config is None:
        if isinstance(config, str) and tracker is not None and tracker != config:
            raise ValueError(f"tracker {tracker!r} and config {config!r} disagree")
        config = TrackConfig.preset(config if isinstance(config, str) else tracker or
                                    "bytetrack")
    elif tracker is not None and tracker != config.name:
        raise ValueError(f"tracker {tracker!r} and the configuration's {config.name!r} "
                         "disagree; give one")
    motion = overrides.pop("motion", None)
    off = {k: overrides.pop(k) for k in list(overrides) if k in _OFFLINE_KEYS}
    if offline is not None:
        off["enabled"] = bool(offline)
    config = config.with_values(tracker=overrides, offline=off)
    return replace(config, motion=motion) if motion is not None else config


def derived_values(trk: BoxTracker) -> dict:
    """What a box tracker derived from the data it has tracked: its frame rate, its motion's
    per-frame noise at that rate, and with calibrated scores the raw score at which each
    threshold's confidence is reached (:meth:`ScoreCalibration.score_at`), with what the
    calibration was fitted to."""
    c, m = trk.config, trk.motion
    out: dict = {"frame_rate": trk.frame_rate}
    if trk.image_size is not None:
        out["image_size"] = [int(v) for v in trk.image_size]
    out.update({"std_pos_per_frame": float(m.std_pos), "std_vel_per_frame": float(m.std_vel)})
    cal = trk.score_calibration()
    if cal is not None:
        out["calibration"] = "whole file" if trk.calibration is not None else \
            "online, at the last frame"
        out["calibration_outcomes"] = cal.n
        if cal.n:
            out["calibration_top_persistence"] = round(cal.top_persistence, 6)
        for name in ("high", "low", "new_track"):
            out[f"{name}_score"] = cal.score_at(getattr(c, name))
    return out


def track_sequence(seq_dir: str | Path, out: str | Path, *, detections: str | Path | None = None,
                   config: TrackConfig | str | None = None, tracker: str | None = None,
                   offline: bool | None = None, force: bool = False, progress: Any = None,
                   **overrides: Any) -> TrackRun:
    """Track a MOTChallenge sequence folder and write a results file.

    Parameters
    ----------
    seq_dir
        A folder with ``seqinfo.ini`` and ``det/det.txt``.
    out
        The results file to write (not overwritten unless ``force``).
    detections
        Another detections file (default ``seq_dir/det/det.txt``).
    config, tracker, offline, overrides
        The configuration (:func:`resolve_config`): a
        :class:`~vistrack.config.TrackConfig` or a preset's name in
        :data:`vistrack.tracking.TRACKERS`, and values put over it.
        Offline, the finished tracks are smoothed, gaps filled, tracks of weak detections
        dropped, tracks followed back through the detections left over and joined across
        gaps (:func:`vistrack.tracking.smooth`), and calibrated scores are calibrated on the
        whole file.
    progress
        A stream for a progress bar (the command line passes stderr on a terminal), or None.
    """
    cfg = resolve_config(config, tracker=tracker, offline=offline, **overrides)
    seq_dir = Path(seq_dir)
    info = read_seqinfo(seq_dir)
    det_path = Path(detections) if detections is not None else seq_dir / "det" / "det.txt"
    if not det_path.exists():
        raise FileNotFoundError(f"{det_path} does not exist (pass --detections FILE)")
    out = Path(out)
    if out.exists() and not force:
        raise FileExistsError(f"{out} exists; pass --force to overwrite it")
    dets = read_mot(det_path)
    if len(dets) and dets.frames.max() > info.seq_length:
        raise ValueError(f"{det_path}: frame {int(dets.frames.max())} is beyond the "
                         f"sequence's {info.seq_length} frames ({seq_dir / 'seqinfo.ini'})")
    slices = dets.frame_slices(info.seq_length)
    xyxy = np.c_[dets.boxes[:, :2], dets.boxes[:, :2] + dets.boxes[:, 2:]]
    per_frame = [Detections(boxes=xyxy[s], scores=dets.conf[s]) for s in slices]
    seconds = 0.0
    calibration = None
    tc, oc = cfg.tracker, cfg.offline
    if oc.enabled and tc.scores == "calibrated":
        # offline, the scores are calibrated on the whole file (see tracking.calibration)
        t0 = time.perf_counter()
        calibration = ScoreCalibration.from_frames(per_frame, link_iou=tc.link_iou,
                                                   top=tc.calibration_top)
        seconds += time.perf_counter() - t0
    trk = BoxTracker(tc, motion=cfg.motion, frame_rate=info.frame_rate, record=oc.enabled,
                     image_size=(info.im_width, info.im_height), calibration=calibration)
    frames, ids, boxes, scores = [], [], [], []
    every = max(1, info.seq_length // 50)
    for f in range(1, info.seq_length + 1):
        d = per_frame[f - 1]
        t0 = time.perf_counter()
        res = trk.step(d, frame=f)
        seconds += time.perf_counter() - t0
        if len(res):
            frames.append(np.full(len(res), f))
            ids.append(res.ids)
            boxes.append(res.xywh)
            scores.append(res.scores)
        if f % every == 0 or f == info.seq_length:
            _progress(f, info.seq_length, info.name, progress)

    def cat(a: list, shape: tuple) -> np.ndarray:
        return np.concatenate(a) if a else np.zeros(shape)

    F, I = cat(frames, (0,)).astype(int), cat(ids, (0,)).astype(int)
    B, S = cat(boxes, (0, 4)), cat(scores, (0,))
    if oc.enabled:
        t0 = time.perf_counter()
        fps = info.frame_rate
        sm = smooth(trk, max_gap=int(round(oc.max_gap * fps)), min_score=oc.min_track_score,
                    extend_iou=oc.extend_iou if oc.extend_iou > 0 else None,
                    link_gap=int(round(oc.link_gap * fps)), link_iou=oc.link_iou,
                    link_window=max(1, round(oc.link_window * fps)))
        seconds += time.perf_counter() - t0
        F, I, B, S = sm.frames, sm.ids, sm.xywh, np.where(sm.filled, 0.0, sm.scores)
    write_mot(out, F, I, B, S, force=True)
    used = cfg if cfg.motion is not None else replace(cfg, motion=BoxMotion())
    return TrackRun(out, info.seq_length, len(dets), len(F), len(np.unique(I)), seconds,
                    used, derived_values(trk))


def evaluate_files(pairs: list[tuple[str, Path, Path, Path | None]], *,
                   benchmark: str = "auto") -> dict[str, MOTCounts]:
    """Score ``(name, gt, results, seqinfo-or-None)`` pairs; adds ``"COMBINED"`` when there are
    several."""
    out: dict[str, MOTCounts] = {}
    for name, gt, pred, info in pairs:
        n = read_seqinfo(info).seq_length if info is not None else None
        out[str(name)] = evaluate_mot(read_mot(gt), read_mot(pred), n, benchmark=benchmark)
    if len(out) > 1:
        out["COMBINED"] = combine(out.values())
    return out


# ------------------------------------------------------------------------------- video
FRONTENDS = ("bgsub", "hog", "detections:FILE")
"""Front-ends of :func:`track_video` by name."""


@dataclass(frozen=True)
class VideoRun:
    """What :func:`track_video` wrote and measured: the output files, frames, tracks, the
    seconds spent in each stage (``decode``, ``frontend``, ``tracker``, ``write``), the
    scores against ground truth (None without it), and for a box tracker the configuration
    used and the values derived from the data."""

    out_dir: Path
    files: dict
    frames: int
    rows: int
    tracks: int
    seconds: dict
    scores: MOTCounts | None
    config: TrackConfig | None = None
    derived: dict | None = None

    @property
    def fps(self) -> float:
        """Frames per second of decode, front-end and tracker together."""
        s = sum(v for k, v in self.seconds.items() if k != "write")
        return self.frames / max(s, 1e-12)


def _frontend(name: Any, reader: Any, *, background: str, min_area: float, n_init: int):
    """The per-frame function ``image -> Detections`` of a front-end, by name, or of a
    detector (any object with ``detect(image) -> Detections``)."""
    if not isinstance(name, str):
        if not callable(getattr(name, "detect", None)):
            raise TypeError(f"frontend must be a name in {list(FRONTENDS)} or an object with "
                            f"detect(image) -> Detections; got {type(name).__name__}")
        return lambda image, index: name.detect(image)

    from ._validate import as_uint8_image
    from .frontends import background as make_background
    from .frontends import find_blobs
    from .io.video import VideoReader

    if name == "bgsub":
        bg = make_background(background)
        bg.initialize(f.image for f in VideoReader(reader.source, fps=reader.fps, grey=True,
                                                   start=reader.start,
                                                   stop=reader.start + n_init - 1))

        def detect(image: np.ndarray, index: int) -> Detections:
            mask = bg.apply(as_uint8_image(image, grey=True))
            return find_blobs(mask, min_area=min_area, open_size=3,
                              close_size=7).detections("boxes")
        return detect
    if name == "hog":
        from .frontends.detectors import HOGDetector

        hog = HOGDetector()
        return lambda image, index: hog.detect(image)
    if name.startswith("detections:"):
        path = Path(name.split(":", 1)[1])
        if not path.exists():
            raise FileNotFoundError(f"{path} does not exist (--frontend detections:FILE)")
        dets = read_mot(path)
        n = max(int(dets.frames.max()) if len(dets) else 0, reader.start + len(reader))
        slices = dets.frame_slices(n)
        return lambda image, index: Detections.from_xywh(dets.boxes[slices[index - 1]],
                                                         dets.conf[slices[index - 1]])
    raise ValueError(f"frontend must be one of {list(FRONTENDS)}; got {name!r}")


def track_video(video: str | Path, out_dir: str | Path, *, frontend: Any = None,
                fps: float | None = None, tracker: str = "bytetrack",
                gt: str | Path | None = None, background: str = "selective",
                min_area: float = 500.0, n_init: int = 20, stop: int | None = None,
                annotate: bool = True, force: bool = False, progress: Any = None,
                confidence: Any = None, det_threshold: float = 0.5,
                config: TrackConfig | None = None, **overrides: Any) -> VideoRun:
    """Track a video (a file, an image folder or a MOTChallenge sequence folder) from pixels.

    Writes into ``out_dir``: ``tracks.txt`` (MOTChallenge results), ``tracks.csv``,
    ``annotated.mp4`` (boxes, identities, trails and 2-sigma ellipses of the centres) and
    ``trajectories.png``; scores against ``gt`` (a MOTChallenge ground-truth file) when given.

    Parameters
    ----------
    frontend
        ``"bgsub"`` (the default of the box trackers: the seeds' background model, then
        blobs), ``"hog"`` (OpenCV's people detector; with ``tracker="dcpf"``, the default,
        the peaks of the confidence map above ``det_threshold``), ``"detections:FILE"`` (a
        MOTChallenge detections file), or a detector of your own: any object with
        ``detect(image) -> Detections`` (:class:`vistrack.frontends.detectors.Detector`).
    tracker
        A box tracker's name (:data:`vistrack.tracking.TRACKERS`: ``"bytetrack"``,
        ``"sort"``), or ``"dcpf"``, the detector-confidence particle filter
        (:class:`vistrack.tracking.dcpf.DetectorConfidencePF`; ``overrides`` are then
        fields of its :class:`~vistrack.tracking.dcpf.DCPFConfig`).
    confidence, det_threshold
        For ``"dcpf"``: the detector's continuous confidence, a callable ``image ->
        ConfidenceMap`` (default :class:`vistrack.frontends.detectors.HOGConfidence`), and
        the SVM margin above which its peaks are detections.
    fps
        The true frame rate, when the container's header is wrong.
    background, min_area, n_init
        For ``bgsub``: the background model's name, the smallest blob in pixels, and the
        frames whose median starts the model. A background model needs a still camera, so
        with ``bgsub`` the box tracker's ``camera_motion`` is off unless passed.
    stop
        The last frame to track (default: all).
    config
        The whole configuration of a box tracker (:class:`~vistrack.config.TrackConfig`), used
        as it is: the ``bgsub`` front-end's default (no camera motion) is not put over it.
        ``overrides`` then change its tracker's settings.
    """
    import cv2

    from .io.video import VideoReader, VideoWriter
    from .viz.annotate import Annotator
    from .viz.plots import plot_trajectories

    out_dir = Path(out_dir)
    files = {"tracks": out_dir / "tracks.txt", "csv": out_dir / "tracks.csv",
             "video": out_dir / "annotated.mp4", "plot": out_dir / "trajectories.png"}
    if not annotate:
        del files["video"]
    there = [str(p) for p in files.values() if p.exists()]
    if there and not force:
        raise FileExistsError(f"{', '.join(there)} exist; pass --force to overwrite them")
    gt_table = read_mot(gt) if gt is not None else None
    reader = VideoReader(video, fps=fps, stop=stop, prefetch=8)
    if tracker == "dcpf":
        from .frontends.detectors import HOGConfidence
        from .tracking.dcpf import DetectorConfidencePF

        conf_of = HOGConfidence() if confidence is None else confidence
        if not callable(conf_of):
            raise TypeError(f"confidence must be a callable image -> ConfidenceMap; got "
                            f"{type(conf_of).__name__}")
        own = frontend in (None, "hog")
        detect_other = None if own else _frontend(frontend, reader, background=background,
                                                  min_area=min_area, n_init=n_init)
        dcpf = DetectorConfidencePF(**overrides)

        def detect(image: np.ndarray, index: int) -> Any:
            # the frame's detections and confidence map (the particle filter's classifiers
            # also read the image)
            cmap = conf_of(image)
            if own:
                return cmap.detections(det_threshold), cmap, image
            assert detect_other is not None  # made above when the frontend is not HOG's own
            return detect_other(image, index), cmap, image

        def step(d: Any, index: int) -> Tracks:
            return dcpf.update(d[2], d[0], d[1])
    else:
        frontend = "bgsub" if frontend is None else frontend
        detect = _frontend(frontend, reader, background=background, min_area=min_area,
                           n_init=n_init)
        if config is not None and config.offline.enabled:
            raise ValueError("the offline mode goes with a sequence's detections (track "
                             "--out), not with a video")
        if frontend == "bgsub" and config is None:
            # a background model works only with a still camera: nothing to compensate, and
            # blobs that split and merge would read as small shifts of the camera
            overrides.setdefault("camera_motion", False)
        motion = overrides.pop("motion", None)
        cfg = resolve_config(config if config is not None else tracker, **overrides)
        if motion is not None or cfg.motion is None:
            cfg = replace(cfg, motion=motion or BoxMotion())
        box_tracker = BoxTracker(cfg.tracker, motion=cfg.motion, frame_rate=reader.fps,
                                 image_size=reader.size)

        def step(d: Any, index: int) -> Tracks:
            return box_tracker.step(d, frame=index)
    out_dir.mkdir(parents=True, exist_ok=True)
    writer = VideoWriter(files["video"], reader.fps) if annotate else None
    ann = Annotator()
    sec = dict.fromkeys(("decode", "frontend", "tracker", "write"), 0.0)
    rows, first_image, n = [], None, 0
    every = max(1, len(reader) // 50)
    t0 = time.perf_counter()
    try:
        for frame in reader:
            t1 = time.perf_counter()
            sec["decode"] += t1 - t0
            d = detect(frame.image, frame.index)
            t2 = time.perf_counter()
            res = step(d, frame.index)
            t3 = time.perf_counter()
            sec["frontend"] += t2 - t1
            sec["tracker"] += t3 - t2
            rows += [(frame.index, i, *b, s) for i, b, s in zip(res.ids, res.xywh, res.scores)]
            if first_image is None:
                first_image = frame.image
            if writer is not None:
                writer.write(ann.draw(frame.image, res, label=f"frame {frame.index}"))
            n += 1
            if n % every == 0 or n == len(reader):
                _progress(n, len(reader), reader.source.name, progress)
            t0 = time.perf_counter()
            sec["write"] += t0 - t3
    finally:
        if writer is not None:
            writer.close()
    if n == 0:
        raise ValueError(f"{video}: no frames to track")
    assert first_image is not None  # kept at the first of the n frames
    a = np.array(rows, dtype=float).reshape(-1, 7)
    F, I = a[:, 0].astype(int), a[:, 1].astype(int)
    write_mot(files["tracks"], F, I, a[:, 2:6], a[:, 6], force=True)
    with open(files["csv"], "w") as fh:
        fh.write("frame,id,x,y,w,h,score\n")
        for r in a:
            fh.write(f"{int(r[0])},{int(r[1])},{r[2]:.2f},{r[3]:.2f},{r[4]:.2f},{r[5]:.2f},"
                     f"{r[6]:.3f}\n")
    plot_trajectories(F, I, a[:, 2:4] + a[:, 4:6] / 2,
                      cv2.cvtColor(first_image, cv2.COLOR_BGR2RGB) if first_image.ndim == 3
                      else first_image, files["plot"],
                      title=f"{reader.source.name}: {len(np.unique(I))} tracks, {n} frames")
    scores = None
    if gt_table is not None:  # scored over the frames tracked
        last = reader.start + n - 1
        g = gt_table[(gt_table.frames >= reader.start) & (gt_table.frames <= last)]
        scores = evaluate_mot(g, read_mot(files["tracks"]), last, benchmark="auto")
    if tracker == "dcpf":
        return VideoRun(out_dir, files, n, len(a), len(np.unique(I)), sec, scores)
    return VideoRun(out_dir, files, n, len(a), len(np.unique(I)), sec, scores, cfg,
                    derived_values(box_tracker))


# -------------------------------------------------------------------- one object, by hand
@dataclass(frozen=True)
class SingleRun:
    """What :func:`track_one` did: the boxes file, the boxes ``(T, 4)``, the tracker's
    seconds, and the scores against ground truth (``success``, ``auc``, ``precision``; None
    without it)."""

    out: Path
    boxes: np.ndarray
    seconds: float
    scores: dict | None

    @property
    def fps(self) -> float:
        return (len(self.boxes) - 1) / max(self.seconds, 1e-12)


def track_one(source: str | Path, init: Any, out: str | Path, *, method: str = "colour",
              gt: str | Path | None = None, force: bool = False,
              progress: Any = None) -> SingleRun:
    """Follow one object from its box ``init`` (``x, y, w, h`` in the first frame) through a
    video or image folder, and write ``frame,x,y,w,h`` lines (frames from 1) to ``out``.

    ``method`` is a name in :data:`vistrack.frontends.single.METHODS`; ``gt`` a ground-truth
    file (OTB ``groundtruth_rect.txt``, VOT ``groundtruth.txt`` or a boxes file) to score
    against.
    """
    from .evaluation.single import precision, read_boxes, success_curve, success_rate, write_boxes
    from .frontends.single import single_tracker
    from .io.video import VideoReader

    out = Path(out)
    if out.exists() and not force:
        raise FileExistsError(f"{out} exists; pass --force to overwrite it")
    tracker = single_tracker(method)
    truth = read_boxes(gt) if gt is not None else None
    reader = VideoReader(source, prefetch=4)
    boxes, sec = [], 0.0
    for k, frame in enumerate(reader):
        t0 = time.perf_counter()
        if k == 0:
            tracker.init(frame.image, init)
            boxes.append(np.asarray(init, dtype=float))
        else:
            boxes.append(tracker.update(frame.image))
            sec += time.perf_counter() - t0
        if (k + 1) % 20 == 0 or k + 1 == len(reader):
            _progress(k + 1, len(reader), reader.source.name, progress)
    b = np.array(boxes).reshape(-1, 4)
    write_boxes(out, b, force=True)
    scores = None
    if truth is not None:
        if len(truth) < len(b):
            raise ValueError(f"{gt} has {len(truth)} boxes for {len(b)} frames")
        t = truth[:len(b)]
        scores = {"success": success_rate(b, t), "auc": success_curve(b, t)[2],
                  "precision": precision(b, t)}
    return SingleRun(out, b, sec, scores)

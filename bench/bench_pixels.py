"""From pixels: background models beside OpenCV's, and the whole chain on PETS09-S2L1 beside
a baseline a user would assemble from OpenCV and PyPI, in one run.

    python bench/bench_pixels.py [--write docs/benchmarks.md]

1. Background subtraction per frame at 640x480 (PETS09-S2L1 frames resized), grey and colour:
   vistrack's selective running mean/variance against OpenCV's MOG2 and KNN. Feature
   tracking with 500 features: vistrack's KLT against OpenCV's lk_track.py sample loop.
2. PETS09-S2L1 (`../shared/data/opencv-vtest/vtest.avi`, 795 frames, 7 frames/s), end to end:
   decode, background, blobs, tracker; HOTA / MOTA / IDF1 against the MOT15 ground truth.
   vistrack: the selective model, `frontends.BlobDetector`, `bytetrack`. Baseline: MOG2,
   morphology, `cv2.connectedComponentsWithStats`, and `trackers`' SORT (vistrack's `sort`
   when `trackers` is not installed). Frames per second are of the whole loop, decode
   included (in a second thread, as `vistrack track` does), the median of three runs after
   a warm-up.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from vistrack.evaluation import evaluate_mot
from vistrack.frontends import BlobDetector, SelectiveBackground
from vistrack.io import MOTTable, VideoReader, read_mot
from vistrack.tracking import BoxTracker
from vistrack.types import Detections

from _common import optional, per_frame  # noqa: E402  (bench/ is on the path of its scripts)
from _markdown import publish  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
VIDEO = DATA / "opencv-vtest" / "vtest.avi"
GT = DATA / "mot15" / "PETS09-S2L1" / "gt" / "gt.txt"
FPS = 7.0  # MOTChallenge's rate for PETS09-S2L1 (the AVI header says 10)
SIZE = (768, 576)  # vtest.avi's frames


def background_rows():
    frames = [cv2.resize(f.image, (640, 480), interpolation=cv2.INTER_AREA)
              for f in VideoReader(VIDEO, stop=120)]
    rows = []
    for kind in ("grey", "colour"):
        fr = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames] if kind == "grey" else frames
        sel = SelectiveBackground().initialize(fr[:20])
        mog = cv2.createBackgroundSubtractorMOG2()
        knn = cv2.createBackgroundSubtractorKNN()
        for m in (mog, knn):
            for f in fr[:20]:
                m.apply(f)
        sel.apply(fr[0])
        ours = per_frame(sel.apply, fr[20:])
        rows.append((kind, ours, per_frame(mog.apply, fr[20:]), per_frame(knn.apply, fr[20:])))
        print(f"  {kind}: selective {ours:.2f} ms", file=sys.stderr)
    return rows


def klt_rows(n_features=500):
    """ms a frame of feature tracking at 640x480 (PETS09 frames resized): vistrack's KLT with
    and without the affine check, and OpenCV's lk_track.py sample loop (pyramidal LK with a
    forward-backward check, new features every 5 frames), the same number of features."""
    from vistrack.tracking.klt import KLTTracker

    grey = [cv2.cvtColor(cv2.resize(f.image, (640, 480), interpolation=cv2.INTER_AREA),
                         cv2.COLOR_BGR2GRAY) for f in VideoReader(VIDEO, stop=150)]

    def opencv_sample():
        tracks, prev = [], None
        lk = dict(winSize=(15, 15), maxLevel=2,
                  criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 0.03))

        def step(g):
            nonlocal tracks, prev
            if prev is not None and tracks:
                p0 = np.float32(tracks).reshape(-1, 1, 2)
                p1, _, _ = cv2.calcOpticalFlowPyrLK(prev, g, p0, None, **lk)
                p0r, _, _ = cv2.calcOpticalFlowPyrLK(g, prev, p1, None, **lk)
                good = np.abs(p0 - p0r).reshape(-1, 2).max(-1) < 1
                tracks = [tuple(p) for p, ok in zip(p1.reshape(-1, 2), good) if ok]
            step.n += 1
            if step.n % 5 == 1 and len(tracks) < n_features:
                mask = np.full(g.shape, 255, np.uint8)
                for x, y in np.int32(tracks):
                    cv2.circle(mask, (int(x), int(y)), 7, 0, -1)
                p = cv2.goodFeaturesToTrack(g, n_features - len(tracks), 0.01, 7, mask=mask,
                                            blockSize=7)
                if p is not None:
                    tracks += [tuple(q) for q in p.reshape(-1, 2)]
            prev = g
        step.n = 0
        return step

    rows = []
    for name, make in (("vistrack KLT, affine check on", lambda: KLTTracker(n_features).track),
                       ("vistrack KLT, affine check off",
                        lambda: KLTTracker(n_features, affine_check=False).track),
                       ("OpenCV lk_track.py loop", opencv_sample)):
        step = make()
        for g in grey[:10]:
            step(g)
        ms = per_frame(step, grey[10:], repeats=1)
        rows.append((name, ms))
        print(f"  {name}: {ms:.2f} ms", file=sys.stderr)
    return rows


def run_chain(make, stop=None):
    """(results rows, seconds) of one pass over the video, decode included: frames are decoded
    (to grey) a few ahead in a second thread, as `vistrack track` reads them. `make()` gives
    detect(image) -> (xyxy, scores) and track(xyxy, scores, frame) -> (ids, xyxy)."""
    detect, track = make()
    rows = []
    t = time.perf_counter()
    for f in VideoReader(VIDEO, fps=FPS, grey=True, stop=stop, prefetch=8):
        ids, boxes = track(*detect(f.image), f.index)
        rows += [(f.index, i, b[0], b[1], b[2] - b[0], b[3] - b[1]) for i, b in zip(ids, boxes)]
    return rows, time.perf_counter() - t


def vistrack_chain(init):
    def make():
        blobs = BlobDetector(min_area=500)  # the CLI's bgsub front-end
        blobs.initialize(init)
        tr = BoxTracker("bytetrack", frame_rate=FPS, camera_motion=False,  # as the CLI's bgsub
                        image_size=SIZE)

        def detect(grey):
            d = blobs.detect(grey)
            return d.boxes, d.scores

        def track(boxes, scores, k):
            r = tr.step(k, Detections(boxes=boxes, scores=scores))
            return r.ids, r.boxes
        return detect, track
    return make


def baseline_chain(init):
    trackers = optional("trackers")

    def make():
        mog = cv2.createBackgroundSubtractorMOG2()
        for f in init:
            mog.apply(f)
        k3 = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
        k7 = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (7, 7))

        def detect(grey):
            m = (mog.apply(grey) > 200).astype(np.uint8)
            m = cv2.morphologyEx(cv2.morphologyEx(m, cv2.MORPH_OPEN, k3), cv2.MORPH_CLOSE, k7)
            n, _, stats, _ = cv2.connectedComponentsWithStats(m, connectivity=8)
            s = stats[1:][stats[1:, cv2.CC_STAT_AREA] >= 500]
            xyxy = np.c_[s[:, 0], s[:, 1], s[:, 0] + s[:, 2], s[:, 1] + s[:, 3]].astype(float)
            return xyxy, np.ones(len(s))

        if trackers is not None:
            import supervision as sv

            tr = trackers.SORTTracker(frame_rate=FPS)

            def track(boxes, scores, k):
                r = tr.update(sv.Detections(xyxy=boxes.astype(np.float32),
                                            confidence=scores.astype(np.float32),
                                            class_id=np.zeros(len(boxes), int)))
                ok = r.tracker_id >= 0 if r.tracker_id is not None else np.zeros(0, bool)
                return r.tracker_id[ok], r.xyxy[ok]
        else:
            tr = BoxTracker("sort", frame_rate=FPS)

            def track(boxes, scores, k):
                r = tr.step(k, Detections(boxes=boxes, scores=scores))
                return r.ids, r.boxes
        return detect, track
    return make, "trackers SORT" if trackers is not None else "vistrack sort"


def chain_rows():
    t = time.perf_counter()
    n = sum(1 for _ in VideoReader(VIDEO, fps=FPS, grey=True))
    decode_ms = (time.perf_counter() - t) / n * 1e3
    init = [f.image for f in VideoReader(VIDEO, grey=True, stop=20)]
    gt = read_mot(GT)
    base_make, base_tracker = baseline_chain(init)
    rows = []
    for name, make in (("vistrack: selective background, blobs, bytetrack", vistrack_chain(init)),
                       (f"baseline: MOG2, connected components, {base_tracker}", base_make)):
        run_chain(make, stop=30)  # warm-up (compiled code loaded)
        secs, res = [], None
        for _ in range(3):
            res, sec = run_chain(make)
            secs.append(sec)
        a = np.array(res, dtype=float).reshape(-1, 6)
        pred = MOTTable(a[:, 0].astype(int), a[:, 1].astype(int), a[:, 2:6], np.ones(len(a)),
                        -np.ones(len(a), int), -np.ones(len(a)), columns=10)
        c = evaluate_mot(gt, pred, n, benchmark="MOT15")
        ms = statistics.median(secs) / n * 1e3
        rows.append((name, 1e3 / ms, ms, c.HOTA, c.MOTA, c.IDF1))
        print(f"  {name}: {1e3 / ms:.0f} fps, HOTA {100 * c.HOTA:.1f}", file=sys.stderr)
    return rows, decode_ms


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    if not VIDEO.exists() or not GT.exists():
        sys.exit(f"{VIDEO} or {GT} not found: the shared data must be beside this checkout")
    bg = background_rows()
    t = ["**Background subtraction, 640×480, ms a frame**", "",
         "| frames | vistrack selective | OpenCV MOG2 | OpenCV KNN | MOG2 / selective |",
         "|---|---:|---:|---:|---:|"]
    t += [f"| {k} | {a:.2f} | {b:.2f} | {c:.2f} | {b / a:.0f} |" for k, a, b, c in bg]
    kl = klt_rows()
    k = ["**Feature tracking, 500 features, 640×480, ms a frame**", "",
         "| tracker | ms a frame | frames/s |", "|---|---:|---:|"]
    k += [f"| {n} | {m:.2f} | {1e3 / m:.0f} |" for n, m in kl]
    chain, decode = chain_rows()
    u = ["**PETS09-S2L1 from pixels, 795 frames, end to end**", "",
         "| chain | frames/s | ms a frame | HOTA | MOTA | IDF1 |", "|---|---:|---:|---:|---:|---:|"]
    u += [f"| {n} | {f:.0f} | {m:.2f} | {100 * h:.1f} | {100 * a:.1f} | {100 * i:.1f} |"
          for n, f, m, h, a, i in chain]
    env = (f"Python {platform.python_version()}, numpy {np.__version__}, OpenCV "
           f"{cv2.__version__}, {platform.machine()}, {time.strftime('%Y-%m-%d')}")
    section = (f"## From pixels\n\nMeasured with `python bench/bench_pixels.py` ({env}).\n\n"
               + "\n".join(t) + "\n\n" + "\n".join(k) + "\n\n" + "\n".join(u) + "\n\n"
               + f"Decoding alone (to grey, "
               f"in one thread) takes {decode:.2f} ms a frame; both chains read the video "
               f"through `VideoReader(prefetch=8)`, which decodes in a second thread while "
               f"the frame before is processed, and their times are of the whole loop.\n")
    publish(section, args.write)


if __name__ == "__main__":
    main()

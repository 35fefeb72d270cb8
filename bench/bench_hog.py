"""HOG's dense confidence (the detector-confidence particle filter's front-end) beside the
loop a user would write with OpenCV, in one run, on the bundled PETS09-S2L1 clip.

    python bench/bench_hog.py [--frames 40] [--write docs/benchmarks.md]

Each frame (768 x 576) is searched at the five levels of ``HOGConfidence`` (people 46 to 121
pixels tall): the image resized so that such a person fills OpenCV's 64 x 128 window, and
the default people SVM's margin of every window at a stride of 8 pixels
(``cv2.HOGDescriptor.detect``). vistrack: ``HOGConfidence`` as it runs (the levels on as
many threads as OpenCV uses), and with OpenCV set to one thread. OpenCV: the same resizes and
searches, one level after another, as a script would. Every map is checked equal, bit for
bit, to the script's margins. The median of three passes over the frames, ms a frame.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import cv2
import numpy as np

from vistrack.data import demo_clip
from vistrack.frontends import HOGConfidence
from vistrack.io import VideoReader

from _common import per_frame  # noqa: E402  (bench/ is on the path of its scripts)
from _markdown import publish  # noqa: E402


def opencv_loop(heights):
    """The margins of every window at each level, one level after another, as a script
    using OpenCV alone computes them: ``image -> [grid of margins per level]``."""
    hog = cv2.HOGDescriptor()
    hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())

    def margins(image):
        H, W = image.shape[:2]
        grids = []
        for h in heights:
            sw, sh = round(W * (96 / h)), round(H * (96 / h))
            loc, w = hog.detect(cv2.resize(image, (sw, sh)), hitThreshold=-1e9,
                                winStride=(8, 8), padding=(0, 0))
            grid = np.full(((sh - 128) // 8 + 1, (sw - 64) // 8 + 1), -np.inf)
            loc = np.asarray(loc).reshape(-1, 2) // 8
            grid[loc[:, 1], loc[:, 0]] = np.asarray(w, float).ravel()
            grids.append(grid)
        return grids

    return margins


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=40, help="frames of the clip (default 40)")
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    frames = [f.image for f in VideoReader(demo_clip().video, stop=args.frames)]
    hog = HOGConfidence()
    script = opencv_loop(hog.heights)
    for f in frames:  # the same margins, to the bit
        ours, theirs = hog(f).scores, script(f)
        assert len(ours) == len(theirs) and all(
            np.array_equal(a, b) for a, b in zip(ours, theirs)), "the maps differ"
    threads = cv2.getNumThreads()
    hog(frames[0])  # (each front-end's first call untimed)
    rows = [(f"vistrack `HOGConfidence` ({threads} threads, OpenCV's)", per_frame(hog, frames))]
    cv2.setNumThreads(1)
    try:
        rows.append(("vistrack `HOGConfidence`, OpenCV set to 1 thread", per_frame(hog, frames)))
    finally:
        cv2.setNumThreads(threads)
    script(frames[0])
    rows.append(("OpenCV: the levels one after another (a script's loop)",
                 per_frame(script, frames)))
    for name, ms in rows:
        print(f"  {name}: {ms:.1f} ms", file=sys.stderr)
    base = rows[-1][1]
    t = ["| front-end | ms a frame | frames/s | the script's time / this |",
         "|---|---:|---:|---:|"]
    t += [f"| {n} | {m:.1f} | {1e3 / m:.1f} | {base / m:.2f} |" for n, m in rows]
    env = (f"Python {platform.python_version()}, numpy {np.__version__}, OpenCV "
           f"{cv2.__version__}, {platform.machine()}, {os.cpu_count()} cores, "
           f"{time.strftime('%Y-%m-%d')}")
    section = (f"## HOG's dense confidence\n\nMeasured with `python bench/bench_hog.py` ({env}): "
               f"the first {len(frames)} frames of the bundled PETS09-S2L1 clip (768 × 576), "
               f"the five levels of people 46 to 121 pixels tall, the margin of every window "
               f"at a stride of 8 pixels; every map equal, bit for bit, to the script's.\n\n"
               + "\n".join(t) + "\n")
    publish(section, args.write)


if __name__ == "__main__":
    main()

"""Particles in a microscope's video: spots (Crocker-Grier, as trackpy's `locate`) linked by
the point tracker with the drifting-points model, through the pipeline's one loop into an
annotated video, a trajectory plot and a CSV of trackpy's columns (`io.PointsCSVWriter`).
`vistrack track FRAMES --out-dir OUT --frontend spots --diameter 11 --invert --minmass 20`
does the same from the command line, with the `particles` tracker's own settings.

    python examples/spots_bulk_water.py [FRAMES] [OUT]

FRAMES is trackpy's bulk-water clip by default (50 PNG frames, 640x424, about 520 particles
a frame, in the shared data beside this checkout); OUT is `out/bulk-water/`. The settings
are `bench/bench_microscopy.py`'s: spots of 11 pixels, dark on a light background, mass
above 20; a particle's position wanders by about a pixel a frame at 24 frames/s, measured to
a tenth of a pixel, and a track is kept through 3 missed frames, as trackpy's
`link(search_range=5, memory=3)` there. The frames come as the video reader gives them, in
colour, and `locate` makes them grey; the benchmark reads them grey with OpenCV, whose grey
levels differ by up to 1, which moves spots near the mass threshold: 2,018 identities here
against its 2,222, 473 against 475 of them followed 25 frames or more.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from vistrack.frontends.spots import locate
from vistrack.io import PointsCSVWriter, VideoReader
from vistrack.models import ConstantPosition, Position
from vistrack.pipeline import run
from vistrack.tracking import PointTracker
from vistrack.viz import AnnotatedVideo, TrajectoryPlot

FRAMES = Path(__file__).resolve().parents[2] / "shared" / "data" / "trackpy-bulk-water" / "frames"
FPS = 24.0


def main() -> None:
    frames = Path(sys.argv[1]) if len(sys.argv) > 1 else FRAMES
    if not frames.is_dir():
        sys.exit(f"{frames} is not a folder of frames (the shared data must be beside this "
                 "checkout for the default)")
    out = Path(sys.argv[2] if len(sys.argv) > 2 else "out/bulk-water")
    out.mkdir(parents=True, exist_ok=True)
    # each particle at its located position, as trackpy links them (the filter's estimate
    # is drawn towards the track's past, which shrinks every step)
    tracker = PointTracker("gnn", motion=ConstantPosition(dim=2, q=FPS),  # 1 px² a frame
                           measurement=Position(dim=2, r=0.01), frame_rate=FPS,
                           confirm_hits=1, max_lost=3.5 / FPS, p_gate=0.999,
                           report="measurement")

    def spots(frame):
        return locate(frame.image, 11, invert=True, minmass=20).detections()

    stats = run(VideoReader(frames, fps=FPS), spots, tracker,
                [PointsCSVWriter(out / "tracks.csv"), AnnotatedVideo(out / "annotated.mp4", FPS),
                 TrajectoryPlot(out / "trajectories.png", "bulk water")])
    rows = np.loadtxt(out / "tracks.csv", delimiter=",", skiprows=1, ndmin=2)
    lengths = np.bincount(rows[:, 1].astype(int))
    print(f"{stats.frames} frames: {len(rows)} positions of {np.count_nonzero(lengths)} "
          f"particles, {np.count_nonzero(lengths >= 25)} of them followed 25 frames or more")
    for name in ("tracks.csv", "annotated.mp4", "trajectories.png"):
        print(f"  {out / name}")


if __name__ == "__main__":
    main()

"""trackpy's particles, located and linked, written as a CSV file of its columns: a reference
to score vistrack's particle tracks against (``vistrack eval --zero-distance``).

    python examples/trackpy_links.py FRAMES OUT.csv [--diameter 11] [--minmass 20]
        [--no-invert] [--search-range 5] [--memory 3]

FRAMES is a folder of images (or a video), read as ``vistrack track`` reads it
(``vistrack.io.VideoReader``: images in natural order, each numbered by its name, a missing
one a missing frame) and made grey as its spots front-end makes it. OUT.csv holds
``frame,particle,x,y``, each frame the number vistrack gives it (trackpy's count from 0
along the images it is given). The defaults are those of trackpy's walkthrough of its
bulk-water clip, the settings ``bench/bench_microscopy.py`` runs it with. Needs trackpy (in
vistrack's ``test`` extra).
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import cv2
import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("frames", type=Path, help="a folder of images, or a video")
    ap.add_argument("out", type=Path, help="the CSV file to write")
    ap.add_argument("--diameter", type=int, default=11, help="the spots' diameter, odd")
    ap.add_argument("--minmass", type=float, default=20.0, help="the least integrated brightness")
    ap.add_argument("--invert", action=argparse.BooleanOptionalAction, default=True,
                    help="dark spots on a light background (the default, as the clip's)")
    ap.add_argument("--search-range", type=float, default=5.0,
                    help="the farthest a particle moves between frames, pixels")
    ap.add_argument("--memory", type=int, default=3,
                    help="frames a particle may go unseen and keep its identity")
    args = ap.parse_args()
    import trackpy as tp

    from vistrack.io import VideoReader

    tp.quiet()
    frames = list(VideoReader(args.frames))
    numbers = np.array([f.index for f in frames])
    # grey as the spots front-end makes it: decoded in colour, then OpenCV's conversion
    grey = [cv2.cvtColor(f.image, cv2.COLOR_BGR2GRAY) if f.image.ndim == 3 else f.image
            for f in frames]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (pandas' future warnings inside trackpy)
        found = tp.batch(grey, args.diameter, invert=args.invert, minmass=args.minmass)
        links = tp.link(found, args.search_range, memory=args.memory)
    out = links[["frame", "particle", "x", "y"]].sort_values(["frame", "particle"])
    out = out.assign(frame=numbers[out["frame"].to_numpy()])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    out.to_csv(args.out, index=False, float_format="%.3f")
    print(f"{len(frames)} frames: {len(out)} positions of {out['particle'].nunique()} "
          f"trajectories, written to {args.out}")


if __name__ == "__main__":
    main()

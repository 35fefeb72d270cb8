"""trackpy's particles, located and linked, written as a CSV file of its columns: a reference
to score vistrack's particle tracks against (``vistrack eval --zero-distance``).

    python examples/trackpy_links.py FRAMES OUT.csv [--diameter 11] [--minmass 20]
        [--no-invert] [--search-range 5] [--memory 3]

FRAMES is a folder of images. OUT.csv holds ``frame,particle,x,y``, its frames counted from
1 as vistrack's are (trackpy's count from 0). The defaults are those of trackpy's
walkthrough of its bulk-water clip, the settings ``bench/bench_microscopy.py`` runs it with.
Needs trackpy (in vistrack's ``test`` extra).
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import cv2


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("frames", type=Path, help="a folder of images")
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

    tp.quiet()
    files = sorted(p for p in args.frames.iterdir()
                   if p.suffix.lower() in (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp"))
    if not files:
        raise SystemExit(f"{args.frames} holds no images")
    # grey as vistrack's reader makes it: decoded in colour, then converted
    grey = [cv2.cvtColor(cv2.imread(str(f)), cv2.COLOR_BGR2GRAY) for f in files]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (pandas' future warnings inside trackpy)
        found = tp.batch(grey, args.diameter, invert=args.invert, minmass=args.minmass)
        links = tp.link(found, args.search_range, memory=args.memory)
    out = links[["frame", "particle", "x", "y"]].sort_values(["frame", "particle"])
    out = out.assign(frame=out["frame"] + 1)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    out.to_csv(args.out, index=False, float_format="%.3f")
    print(f"{len(files)} frames: {len(out)} positions of {out['particle'].nunique()} "
          f"trajectories, written to {args.out}")


if __name__ == "__main__":
    main()

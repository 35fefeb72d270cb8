"""The ``vistrack`` command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from . import __version__

DEMOS = ("kalman",)


def _demo(args: argparse.Namespace) -> int:
    from .demo import run_kalman_demo

    print(run_kalman_demo(args.out, n_seeds=args.seeds))
    return 0


def _track(args: argparse.Namespace) -> int:
    from .pipeline import track_sequence

    try:
        run = track_sequence(args.seq_dir, args.out, detections=args.detections,
                             tracker=args.tracker, offline=args.offline, force=args.force,
                             progress=sys.stderr if sys.stderr.isatty() and not args.quiet
                             else None)
    except (FileNotFoundError, FileExistsError, ValueError) as exc:
        print(f"vistrack track: error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {run.out}: {run.rows} boxes of {run.tracks} tracks over {run.frames} frames "
          f"from {run.detections} detections; tracker {run.fps:.0f} frames/s")
    return 0


_COLUMNS = (("HOTA", 1), ("DetA", 1), ("AssA", 1), ("MOTA", 1), ("MOTP", 1), ("IDF1", 1),
            ("IDP", 1), ("IDR", 1), ("TP", 0), ("FP", 0), ("FN", 0), ("IDSW", 0), ("Frag", 0),
            ("MT", 0), ("PT", 0), ("ML", 0))


def _eval(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from .pipeline import evaluate_files

    pairs = []
    if args.gt_dir or args.pred_dir:
        if not (args.gt_dir and args.pred_dir):
            print("vistrack eval: error: --gt-dir and --pred-dir go together", file=sys.stderr)
            return 2
        for seq in sorted(p for p in Path(args.gt_dir).iterdir() if (p / "gt" / "gt.txt").exists()):
            pred = Path(args.pred_dir) / f"{seq.name}.txt"
            if not pred.exists():
                print(f"vistrack eval: error: no results for {seq.name}: {pred} does not exist",
                      file=sys.stderr)
                return 2
            info = seq / "seqinfo.ini"
            pairs.append((seq.name, seq / "gt" / "gt.txt", pred, info if info.exists() else None))
        if not pairs:
            print(f"vistrack eval: error: no SEQ/gt/gt.txt under {args.gt_dir}", file=sys.stderr)
            return 2
    elif args.gt and args.pred:
        gt = Path(args.gt)
        info = gt.parent.parent / "seqinfo.ini"
        pairs.append((gt.parent.parent.name or "sequence", gt, Path(args.pred),
                      info if info.exists() else None))
    else:
        print("vistrack eval: error: give --gt and --pred, or --gt-dir and --pred-dir",
              file=sys.stderr)
        return 2
    try:
        res = evaluate_files(pairs, benchmark=args.benchmark)
    except (FileNotFoundError, ValueError) as exc:
        print(f"vistrack eval: error: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps({k: v.summary() for k, v in res.items()}, indent=2))
        return 0
    width = max(len(k) for k in res) + 2
    print("".join([f"{'sequence':<{width}}"] + [f"{c:>7}" for c, _ in _COLUMNS]))
    for name, c in res.items():
        s = c.summary()
        cells = [f"{100 * s[k]:7.1f}" if pct else f"{s[k]:7d}" for k, pct in _COLUMNS]
        print("".join([f"{name:<{width}}"] + cells))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="vistrack", description="Visual object tracking: filters, trackers, scores."
    )
    parser.add_argument("--version", action="version", version=f"vistrack {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo = sub.add_parser(
        "demo", help="remake the lecture figures from real runs",
        description="Run a demo and write its figures. 'kalman': the 1-D filter, the "
        "forward-backward smoother and the 2-D constant-velocity example.",
    )
    demo.add_argument("name", choices=DEMOS, help="which demo")
    demo.add_argument("--out", default="out", help="folder for the figures (default: out)")
    demo.add_argument("--seeds", type=int, default=1000,
                      help="simulated runs for the error statistics (default: 1000)")
    demo.set_defaults(func=_demo)
    from .tracking import TRACKERS

    track = sub.add_parser(
        "track", help="track the detections of a MOTChallenge sequence",
        description="Track a MOTChallenge sequence folder (seqinfo.ini, det/det.txt) and write "
        "a MOTChallenge results file.")
    track.add_argument("seq_dir", help="sequence folder")
    track.add_argument("--detections", help="detections file (default SEQ_DIR/det/det.txt)")
    track.add_argument("--tracker", default="bytetrack", choices=sorted(TRACKERS),
                       help="tracker (default: bytetrack)")
    track.add_argument("--offline", action="store_true",
                       help="smooth finished tracks and fill gaps of up to 0.5 s")
    track.add_argument("--out", required=True, help="results file to write")
    track.add_argument("--force", action="store_true", help="overwrite an existing results file")
    track.add_argument("--quiet", action="store_true",
                       help="no progress bar (shown on a terminal only)")
    track.set_defaults(func=_track)
    ev = sub.add_parser(
        "eval", help="score results against ground truth (HOTA, CLEAR MOT, IDF1)",
        description="Score MOTChallenge results as TrackEval does: HOTA, DetA, AssA, MOTA, "
        "MOTP, IDF1 and the counts, per sequence and combined.")
    ev.add_argument("--gt", help="ground-truth file (SEQ/gt/gt.txt; seqinfo.ini is read beside)")
    ev.add_argument("--pred", help="results file")
    ev.add_argument("--gt-dir", help="folder of sequences SEQ/gt/gt.txt")
    ev.add_argument("--pred-dir", help="folder of results SEQ.txt")
    ev.add_argument("--benchmark", default="auto", choices=("auto", "MOT15", "MOT16", "MOT17",
                                                           "MOT20"),
                    help="preprocessing of the ground truth (default: auto, from its columns)")
    ev.add_argument("--json", action="store_true", help="print JSON instead of a table")
    ev.set_defaults(func=_eval)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "func"):
        parser.print_help()
        return 2
    if getattr(args, "seeds", 1) < 1:
        parser.error(f"--seeds must be >= 1; got {args.seeds}")
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())

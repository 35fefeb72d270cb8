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

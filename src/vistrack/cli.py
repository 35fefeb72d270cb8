"""The ``vistrack`` command line."""

from __future__ import annotations

import argparse
import errno
import functools
import math
import os
import re
import signal
import sys
import threading
import time
import traceback
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

from . import __version__, _compile
from ._pool import counted as _n

if TYPE_CHECKING:
    from typing import TextIO

    from .batch import Job
    from .config import TrackConfig
    from .pipeline import TrackRun, VideoRun
    from .tracking.dcpf import DCPFConfig

DEMOS = ("kalman", "track")

_FRONTEND_OPTIONS = ("frontend", "stop", "min_area", "background", "classes", "onnx_layout",
                     "diameter", "minmass", "invert")
"""``vistrack track``'s options of the front-end, for video mode only (None when not given):
passed on to ``track_video`` as they are."""


class Terminated(BaseException):
    """SIGTERM, raised in the main thread while :func:`main` runs, so that a run stops as on
    Ctrl-C: partial outputs removed, earlier ones kept (a ``BaseException``, as
    ``KeyboardInterrupt``, so that no ``except Exception`` takes it for an error)."""


def _terminate(signum: int, frame: object) -> None:
    raise Terminated


def _fail(command: str, text: str) -> int:
    """Print a user's mistake in one line and return the exit status 2."""
    print(f"vistrack {command}: error: {text}", file=sys.stderr)
    return 2


def _user_errors() -> tuple[type[BaseException], ...]:
    """The exceptions that say what a user gave is wrong (printed in one line, without
    ``--debug``): ``ValueError`` (``MOTFormatError`` and ``ConfigError`` are ones),
    ``TypeError``, the file errors, and ``VideoError`` (looked up only if
    ``vistrack.io.video`` was imported, which is the only way one can have been raised)."""
    errors: list[type[BaseException]] = [
        ValueError, TypeError, FileNotFoundError, FileExistsError, PermissionError,
        IsADirectoryError, NotADirectoryError]
    video = sys.modules.get("vistrack.io.video")
    if video is not None:
        errors.append(video.VideoError)
    return tuple(errors)


def _message(exc: BaseException) -> str:
    """An exception's message on one line (:func:`vistrack._pool.message`: an OS error as
    ``FILE: what went wrong``, with the notes of where it was raised)."""
    from ._pool import message

    return message(exc)


class _Parser(argparse.ArgumentParser):
    """argparse's parser with its errors in the command line's one form: one line
    ``vistrack COMMAND: error: MESSAGE`` and exit status 2, where argparse prints its usage and
    then the error. ``--help`` shows the usage."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # a value that is a negative number in any form float() reads, not argparse's
        # integers and decimals alone: "--low -5e-1" was "expected one argument"
        self._negative_number_matcher = re.compile(
            r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-inf(inity)?$", re.IGNORECASE)

    def error(self, message: str) -> NoReturn:
        required = "the following arguments are required: "
        if message.startswith(required):  # with the values a missing argument may take
            named = {a.metavar or a.dest: a.choices for a in self._actions
                     if not a.option_strings and a.choices}
            message = required + ", ".join(
                f"{name} ({' or '.join(map(str, named[name]))})" if name in named else name
                for name in message[len(required):].split(", "))
        self.exit(2, f"{self.prog}: error: {_message(ValueError(message))}\n")


def _option_hint(parser: argparse.ArgumentParser, extra: Sequence[str]) -> str:
    """``"; did you mean --high?"`` for the first unknown option in ``extra`` that is close
    to one of ``parser``'s (as a misspelt key of a ``--config`` file is told), else ""."""
    import difflib

    known = [o for a in parser._actions for o in a.option_strings if o.startswith("--")]
    for arg in extra:
        if arg.startswith("--"):
            close = difflib.get_close_matches(arg.split("=", 1)[0], known, n=1, cutoff=0.75)
            if close:
                return f"; did you mean {close[0]}?"
    return ""


def _command_parser(parser: argparse.ArgumentParser, command: str | None
                    ) -> argparse.ArgumentParser:
    """The parser of ``command`` (``vistrack track``), or ``parser`` itself."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction) and command in action.choices:
            return action.choices[command]
    return parser


def _command_line(argv: Sequence[str]) -> str:
    """``vistrack ARGS...`` as a shell would read it back."""
    import shlex

    return shlex.join(["vistrack", *argv])


def _path(value: str) -> str:
    """A file or folder argument: any name but the empty one, which meant the current folder
    (`report ''` read ./run.json, `track-one ''` tracked the images there, `demo track --out
    ''` wrote there, `eval --gt ''` was taken as no --gt)."""
    if value == "":
        raise argparse.ArgumentTypeError("an empty name: give a file or folder")
    return value


class _Once(argparse.Action):
    """An option that takes one value: given twice, it is an error naming both (argparse
    keeps the last: `eval --gt A --pred a --gt B --pred b` scored B alone, `track --out
    a.txt --out b.txt` wrote b.txt alone, unsaid)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:
        given = vars(namespace).setdefault("_given_once", {})
        if self.dest in given:
            hint = (": one sequence is scored by --gt and --pred, several by --gt-dir and "
                    "--pred-dir" if parser.prog.endswith(" eval") else ": give it once")
            parser.error(f"{option_string} is given twice ({given[self.dest]} and {values})"
                         f"{hint}")
        given[self.dest] = values
        setattr(namespace, self.dest, values)


def _report(args: argparse.Namespace) -> int:
    from .io.atomic import check_output
    from .pipeline import REPORT
    from .report import write_report

    args.outputs_to = [(Path(args.out_dir) / REPORT, False)]  # (what Ctrl-C says it kept)
    args.had_outputs = _had_outputs(*args.outputs_to[0])
    try:
        page = write_report(args.out_dir, force=args.force)
        args.run_written = True
        print(f"wrote {page}")
    except FileExistsError:
        # the page, found after the run folder's own faults: said in the option's words
        # (write_report's are Python's; it said "pass force=True (--force)")
        check_output(Path(args.out_dir) / REPORT, force=args.force, name="report",
                     option="--force")
        raise
    return 0


def _class_list(text: str) -> list[int]:
    """``--classes 0,2``: class numbers separated by commas."""
    try:
        values = [int(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"class numbers separated by commas, e.g. 0,2; got "
                                         f"{text!r}") from None
    if not values or min(values) < 0:
        raise argparse.ArgumentTypeError(f"class numbers 0 or more, separated by commas; got "
                                         f"{text!r}")
    return values


def _demo(args: argparse.Namespace) -> int:
    from .io.atomic import check_output

    # the folder given, named as the option given (a file there was "afile: File exists",
    # or "--out-dir afile/pets09-s2l1", an option the user never gave)
    check_output(args.out, name="--out", folder=True)
    if args.name == "track":  # the main job on the clip that ships with vistrack
        from .data import demo_clip

        # and the run's folder in it, named as --out's too (a file there was named as
        # --out-dir, the option the demo gives its track run)
        check_output(Path(args.out) / "pets09-s2l1", name="--out", folder=True)

        clip = demo_clip()
        argv = ["track", str(clip.video), "--gt", str(clip.gt), "--out-dir",
                str(Path(args.out) / "pets09-s2l1")] + (["--force"] if args.force else [])
        track = _parser().parse_args(argv)
        track.command_line = getattr(args, "command_line", None)
        try:
            return int(track.func(track))
        finally:  # what the run kept, for Ctrl-C's line (it said "interrupted" alone)
            for name in ("outputs_to", "had_outputs", "run_written", "outputs_written"):
                if hasattr(track, name):
                    setattr(args, name, getattr(track, name))
    from .demo import run_kalman_demo

    # what Ctrl-C says it kept (the figures are replaced as one set)
    args.outputs_to = [(Path(args.out) / n, False)
                       for n in ("kalman_1d.png", "smoothing_1d.png", "kalman_2d.png")]
    args.had_outputs = any(_had_outputs(*o) for o in args.outputs_to)
    summary = run_kalman_demo(args.out, n_seeds=1000 if args.seeds is None else args.seeds,
                              force=args.force)
    args.run_written = True
    print(summary)
    return 0


# the error for the offline mode, its settings or --detections given with --out-dir, from the
# options or from --config's file
_OFFLINE_NEEDS_OUT = ("--offline, its settings and --detections go with --out, a "
                      "sequence's detections into a results file (with --out-dir a video is "
                      "tracked online, its detections read from a file with --frontend "
                      "detections:FILE)")

def _offline_needs_out(args: argparse.Namespace, given: bool = False) -> str:
    """Why the offline mode cannot run with --out-dir: said of --offline (or its settings,
    ``given``), or of the --config file whose [offline] table enables it (it was said of
    --offline, an option never given)."""
    if getattr(args, "offline", False) or given or getattr(args, "config", None) is None:
        return _OFFLINE_NEEDS_OUT
    return (f"{args.config}: [offline] enabled = true goes with --out, a sequence's detections "
            "into a results file (with --out-dir a video is tracked online: set it false, or "
            "give --out)")


# command-line options that set the box tracker's configuration: (option, table, key, type,
# metavar, help, the default as the help says it); vistrack.config is not imported to build the
# parser (it loads the compiled tracker), and a test checks these defaults against it
_SETTINGS = (
    ("scores", "tracker", "scores", str, None, "what the thresholds apply to", "calibrated"),
    ("high", "tracker", "high", float, "X", "confident detections: the first association stage",
     0.6),
    ("low", "tracker", "low", float, "X", "the lowest used at all", 0.3),
    ("new_track", "tracker", "new_track", float, "X", "the lowest that starts a track", 0.7),
    ("min_iou", "tracker", "min_iou", float, "X",
     "the first stage's gate, on IoU times the confidence", 0.2),
    ("confirm_hits", "tracker", "confirm_hits", int, "N", "updates in a row that confirm a track",
     2),
    ("max_lost", "tracker", "max_lost", float, "SECONDS", "how long a lost track is kept", 2.0),
    ("nms_iou", "tracker", "nms_iou", float, "X",
     "drop a detection overlapping a more confident one of its frame at IoU X or more "
     "(non-maximum suppression, for a detector that applies none; 1: none dropped, 0: any "
     "that overlaps)", 1.0),
    ("max_gap", "offline", "max_gap", float, "SECONDS", "offline: the longest gap filled", 1.0),
    ("min_track_score", "offline", "min_track_score", float, "X",
     "offline: the lowest mean confidence of a track's detections kept", 0.75),
    ("start_score", "offline", "start_score", float, "X",
     "offline: the lowest confidence that starts a track, if above --high and "
     "--new-track", 0.8),
    ("link_gap", "offline", "link_gap", float, "SECONDS",
     "offline: join tracks up to this far apart (0: never)", 2.0),
)


def _config_file(args: argparse.Namespace) -> tuple[TrackConfig, dict[str, Any]]:
    """--config's configuration (a file without ``[tracker] name`` over --tracker's preset)
    and its ``[derived]`` table, read once a command: the configuration, and the warnings
    about what it makes of the other options, all come from the same read of the file."""
    from .config import TrackConfig, _read_config_file

    memo = getattr(args, "config_file_read", None)
    if memo is None:
        base = TrackConfig.preset(args.tracker) if args.tracker is not None else None
        # the setting options over the file's values, checked together (each option is put
        # over --config, as its help says: checked alone, the file's high = 0.2 was refused
        # before --low 0.1 came over it)
        over: dict[str, dict[str, Any]] = {}
        names: dict[tuple[str, str], str] = {}
        for option, table, key, *_ in _SETTINGS:
            value = getattr(args, option, None)
            if value is not None:
                over.setdefault(table, {})[key] = value
                names[(table, key)] = "--" + option.replace("_", "-")
        memo = args.config_file_read = _read_config_file(args.config, base, over, names)
    return memo[:2]


def _config_file_keys(args: argparse.Namespace) -> dict[str, frozenset[str]]:
    """The keys --config's file sets in each table, from the same read (:func:`_config_file`)."""
    _config_file(args)
    return args.config_file_read[2]


def _box_config(args: argparse.Namespace):
    """The box tracker's configuration from --tracker, --config and the setting options
    (in that order, each over the one before), or an error message."""
    from .config import TrackConfig

    if args.config is not None:
        cfg = _config_file(args)[0]
        if args.tracker is not None and args.tracker != cfg.name:
            return None, (f"--tracker {args.tracker} disagrees with [tracker] name = "
                          f"\"{cfg.name}\" in {args.config}")
    else:
        cfg = TrackConfig.preset(args.tracker or "bytetrack")
    # the options given, set together: one checked against another's default first would
    # refuse --high 0.2 --low 0.1 (low 0.3 above high 0.2)
    given = [(option, table, key, getattr(args, option)) for option, table, key, *_ in _SETTINGS
             if getattr(args, option) is not None]
    tables: dict[str, dict[str, object]] = {}
    for _, table, key, value in given:
        tables.setdefault(table, {})[key] = value
    try:
        cfg = cfg.with_values(**tables)
    except ValueError as exc:
        # name the options the message is about (low and high: both), or else all given
        named = [option for option, _, key, _ in given if re.search(rf"\b{key}\b", str(exc))]
        names = named or [option for option, *_ in given]
        # a value the message is about that no option gave comes from the file (low from
        # the file against --high named --high alone)
        keys = {key for _, key, _ in (m[1:4] for m in _SETTINGS)}
        given_keys = {key for _, _, key, _ in given}
        from_file = not named or any(re.search(rf"\b{k}\b", str(exc)) for k in keys - given_keys)
        where = f" over {args.config}" if args.config is not None and from_file else ""
        return None, f"{', '.join('--' + n.replace('_', '-') for n in names)}{where}: {exc}"
    if args.still_camera:
        cfg = cfg.with_values(tracker={"camera_motion": False})
    if args.offline:
        cfg = cfg.with_values(offline={"enabled": True})
    return cfg, None


def _dcpf_config(args: argparse.Namespace):
    """The detector-confidence particle filter's settings (``--tracker dcpf``): --config's
    ``[dcpf]`` table over the defaults (its ``[derived]`` table kept as
    ``args.dcpf_file_derived``), or the defaults; or an error message."""
    from .config import ConfigError, read_dcpf_config
    from .tracking.dcpf import DCPFConfig

    if args.config is None:
        return DCPFConfig(), None
    try:
        cfg, args.dcpf_file_derived = read_dcpf_config(args.config)
    except (ConfigError, FileNotFoundError) as exc:
        return None, str(exc)
    return cfg, None


def _tracker_problem(name: str) -> str | None:
    """Why ``--tracker name`` names no tracker, listing the valid names, or None."""
    from .pipeline import TRACKERS

    module, colon, attr = name.partition(":")
    if name in TRACKERS or (colon and module != "single" and module and attr):
        return None
    boxes = [k for k, entry in TRACKERS.items() if entry.box_config]
    others = [k for k in TRACKERS if k not in boxes and not k.startswith("single:")]
    methods = [k.split(":", 1)[1] for k in TRACKERS if k.startswith("single:")]
    return (f"--tracker must be {', '.join(sorted(boxes) + sorted(others))}, single:METHOD "
            f"(METHOD one of {', '.join(sorted(methods))}) or module:callable (a tracker of "
            f"your own); got {name!r}")


# the frame rates the motion model scales to: vistrack.models.box.FRAME_RATES (not imported
# to check the options; a test checks the two agree)
_FPS = (1e-3, 1e6)


def _number_problem(args: argparse.Namespace, box: bool = True) -> str | None:
    """The first numeric option whose value is out of its range, as a message, or None.
    ``--fps`` lies within the box trackers' rates for a box tracker (``box``); the other
    trackers take any rate above 0, as they take a file's (1e7 was refused)."""
    fps = ((lambda v: _FPS[0] <= v <= _FPS[1],
            f"a number from {_FPS[0]:g} to {_FPS[1]:g} (frames a second)") if box else
           (lambda v: 0 < v < math.inf, "a finite number > 0 (frames a second)"))
    checks = (("fps", *fps),
              ("stop", lambda v: v >= 1, "a frame number >= 1"),
              ("min_area", lambda v: math.isfinite(v) and v >= 0, "a finite number >= 0"),
              ("diameter", lambda v: v >= 3 and v % 2 == 1, "an odd number of pixels >= 3"),
              ("minmass", lambda v: math.isfinite(v) and v >= 0, "a finite number >= 0"),
              ("search_range", lambda v: math.isfinite(v) and v > 0,
               "a finite number of pixels > 0"),
              ("zero_distance", lambda v: math.isfinite(v) and v > 0,
               "a finite distance > 0 (where a pair counts for nothing)"))
    for option, ok, what in checks:
        value = getattr(args, option, None)
        if value is not None and not ok(value):
            return f"--{option.replace('_', '-')} must be {what}; got {value:g}"
    for option, _, _, kind, *_ in _SETTINGS:
        value = getattr(args, option, None)
        if kind is float and value is not None and not math.isfinite(value):
            return f"--{option.replace('_', '-')} must be a finite number; got {value:g}"
    return None


def _tracker_and_numbers(args: argparse.Namespace) -> tuple[str, bool, str]:
    """``vistrack track``'s tracker name, whether it is a box tracker, and what is wrong with
    the numbers given or the tracker's name ("" if nothing)."""
    from .tracking.box import TRACKERS as BOX_PRESETS

    # spots are points: the tracker of points goes with them
    name = args.tracker or ("particles" if args.frontend == "spots" else "bytetrack")
    box = name in BOX_PRESETS
    problem = _number_problem(args, box) or ("" if box else _tracker_problem(name) or "")
    if not problem and getattr(args, "search_range", None) is not None and name != "particles":
        problem = f"--search-range goes with --tracker particles, not {name}"
    return name, box, problem


def _box_settings_given(args: argparse.Namespace, name: str) -> list[str]:
    """The box trackers' setting options given (``max_lost`` is the particles' too)."""
    return [o for o, *_ in _SETTINGS if getattr(args, o) is not None
            and not (o == "max_lost" and _points(name))]


def _box_setting_problem(option: str) -> str:
    """``--option goes with the box trackers (...)``, and the particles tracker for
    ``--max-lost``."""
    return (f"--{option.replace('_', '-')} goes with {_box_trackers()}"
            + (" and particles" if option == "max_lost" else
               " and dcpf" if option in ("config", "print_config") else ""))


def _points(name: str) -> bool:
    """Whether ``--tracker name`` gives point tracks (no ``tracks.txt``)."""
    from .pipeline import TRACKERS

    return name in TRACKERS and TRACKERS[name].points


def _box_trackers() -> str:
    """The box trackers' names, for messages: ``"the box trackers (bytetrack, sort)"``."""
    from .tracking.box import TRACKERS as BOX_PRESETS

    return f"the box trackers ({', '.join(sorted(BOX_PRESETS))})"


# `vistrack track`'s options that belong to a run, refused without INPUT (the configuration
# options alone may then be given, to --print-config)
_RUN_OPTIONS = ("out", "out_dir", "jobs", "scheduler", "keep_going", "detections", "columns",
                "fps", "gt", "zero_distance", "skip_bad_frames", "report",
                "force") + _FRONTEND_OPTIONS


def _print_config(args: argparse.Namespace) -> int:
    """`vistrack track --print-config` without INPUT: the configuration that --tracker,
    --config and the settings give, as a run of a sequence's detections (--out) uses it, with
    no [derived] table (nothing is tracked)."""
    from .config import config_toml

    def fail(text: str) -> int:
        return _fail("track", text)

    for flag in _RUN_OPTIONS:
        if getattr(args, flag) not in (None, False):
            return fail(f"--{flag.replace('_', '-')} goes with INPUT; without one, "
                        "--print-config prints the configuration the other options give")
    name, box, problem = _tracker_and_numbers(args)
    if problem:
        return fail(problem)
    if name == "dcpf":
        from .config import dcpf_toml

        given = _box_settings_given(args, name) + [f for f in ("still_camera", "offline")
                                                    if getattr(args, f)]
        if given:
            return fail(_box_setting_problem(given[0]))
        dcfg, problem = _dcpf_config(args)
        if problem:
            return fail(problem)
        sys.stdout.write(dcpf_toml(dcfg))
        print("\n# a run adds [derived], what it derives from its data (the frame rate, the "
              "detections' scores):\n# vistrack track VIDEO --tracker dcpf --out-dir OUT "
              "--print-config")
        return 0
    if not box:
        return fail(f"--print-config goes with {_box_trackers()} and dcpf")
    cfg, problem = _box_config(args)
    if problem:
        return fail(problem)
    assert cfg is not None  # a box tracker's
    sys.stdout.write(config_toml(cfg.with_motion()))
    print("\n# a run adds [derived], what it derives from its data (the frame rate, the image "
          "size, the raw score\n# at each threshold): vistrack track INPUT --out FILE "
          "--print-config")
    return 0


def _track(args: argparse.Namespace) -> int:
    from .batch import is_benchmark

    if not args.input:
        if not args.print_config:  # as argparse says it: INPUT is needed but for that
            raise SystemExit(_fail("track", "the following arguments are required: INPUT"))
        return _print_config(args)
    # the offline mode's settings given: they go with --out, and need --offline to count
    offline_given = [o for o, table, *_ in _SETTINGS
                     if table == "offline" and getattr(args, o) is not None]
    if ":" in (args.tracker or "") and not args.tracker.startswith("single:") \
            and getattr(args, "own_process", False) and "" not in sys.path \
            and os.getcwd() not in sys.path:
        # --tracker module:callable finds a module of the current folder, as `python -m`
        # would (a console script's path has its own folder instead; a program calling main
        # keeps its own path); workers inherit it
        sys.path.insert(0, os.getcwd())
    if len(args.input) > 1 or is_benchmark(Path(args.input[0])):
        return _track_many(args, offline_given)

    from .config import config_toml
    from .io.atomic import check_output
    from .pipeline import (
        VideoRun,
        _keep_warnings,
        _shown_warnings,
        track_sequence,
        track_video,
    )

    def fail(text: str) -> int:
        return _fail("track", text)

    if args.keep_going:
        return fail("--keep-going goes with several inputs")
    for flag in ("jobs", "scheduler"):
        # one input took the several inputs' way: --out res.txt made a folder res.txt/
        if getattr(args, flag) is not None:
            return fail(f"--{flag} goes with several inputs (or a folder of sequences); "
                        f"{args.input[0]} is one")
    args.input = args.input[0]
    if (args.out is None) == (args.out_dir is None):
        return fail("give --out RESULTS.txt (a MOTChallenge sequence's detections) or "
                    "--out-dir OUT/ (from pixels)"
                    + (", not both" if args.out is not None else "")
                    + ("; --print-config with INPUT tracks it, to show what the run derives "
                       "from it (without INPUT it prints the configuration the options give)"
                       if args.print_config and args.out is None else ""))
    if args.out is not None and args.out.endswith(("/", os.sep)):
        # a folder, as with several inputs: RESULTS/NAME.txt (Path dropped the slash, and
        # one input wrote a file named RESULTS)
        from .io.motchallenge import sequence_name

        args.out = str(Path(args.out) / f"{sequence_name(args.input)}.txt")
    name, box, problem = _tracker_and_numbers(args)
    if problem:
        return fail(problem)
    progress = sys.stderr if sys.stderr.isatty() and not args.quiet else None
    cfg = None
    if box:  # before the outputs, as with several inputs: a bad --config is named even
        # where --out exists (which said "pass --force", and the next run named the file)
        cfg, problem = _box_config(args)
        if problem:
            return fail(problem)
    dcfg = None
    if name == "dcpf" and args.out is None:
        dcfg, problem = _dcpf_config(args)
        if problem:
            return fail(problem)
    problem = _outputs_problem(args, name, box, offline_given)
    if problem:
        return fail(problem)
    # with --print-config, stdout holds the configuration alone (the summary goes to stderr)
    report = sys.stderr if args.print_config else sys.stdout
    run: TrackRun | VideoRun
    with _shown_warnings() as said:  # the command's warnings, kept in run.json with the run's
        if box:
            _warn_unused_settings(args, cfg, offline_given, rate=False)
        if args.out is not None:
            columns, problem = _columns(args.columns)
            if problem:
                return fail(problem)
            run = track_sequence(args.input, args.out, detections=args.detections,
                                 columns=columns, config=cfg, fps=args.fps, force=args.force,
                                 progress=progress)
            # the outputs are in place: an interrupt from here on said "earlier outputs are
            # kept" of outputs this run had replaced
            args.run_written = True
        else:
            if cfg is not None and cfg.offline.enabled:
                return fail(_offline_needs_out(args))
            problem = _frontend_problem(args, name)
            if problem:
                return fail(problem)
            if args.report:  # before anything runs: a report that cannot be written fails now
                check_output(Path(args.out_dir) / "report.html", force=args.force,
                             name="--report")
            run = track_video(args.input, args.out_dir, fps=args.fps, gt=args.gt,
                              force=args.force, progress=progress,
                              **_video_options(args, name, box, cfg or dcfg))
            args.run_written = True  # (as above)
        if box:
            _warn_printed_rate(args, run)
        elif dcfg is not None and args.config is not None:
            _warn_printed_rate(args, run, args.dcpf_file_derived)
    if isinstance(run, VideoRun):
        # run.json (and the report, from it) keeps the command's warnings too: one about a
        # setting that changes nothing came before the run, and was left out
        _keep_warnings(run.out_dir, said)
        _print_video_run(args, run, report)
    else:
        print(f"wrote {run.out}: {_n(run.rows, 'box', 'boxes')} of {_n(run.tracks, 'track')} "
              f"over {_n(run.frames, 'frame')} from {_n(run.detections, 'detection')}; tracker "
              f"{run.fps:.0f} frames/s{_fps_words(args, run)}", file=report)
    if args.print_config and dcfg is not None:  # --tracker dcpf's
        from .config import dcpf_toml

        derived = dict(run.derived or {})
        if args.fps is not None:  # the input's rate, no setting: said on reading back
            derived["fps_option"] = float(args.fps)
        sys.stdout.write(dcpf_toml(dcfg, derived))
    elif args.print_config:
        assert run.config is not None  # a box tracker's run (others refuse --print-config)
        derived = dict(run.derived or {})
        if args.fps is not None:  # the frame rate is the input's, not the configuration's:
            # a file read back with --config warns where the run is given another
            derived["fps_option"] = float(args.fps)
        if args.still_camera and _follows_view(args):
            # the background model's following of the view is the front-end's, not the
            # tracker's: read back without --still-camera the view was followed, and the
            # tracks differed (736 boxes against 267), without a word
            derived["still_camera_option"] = True
        sys.stdout.write(config_toml(run.config, derived))
    return 0


def _fps_words(args: argparse.Namespace, run: TrackRun | VideoRun) -> str:
    """The end of one input's summary where ``--fps`` was put over the input's own frame
    rate (``run.replaced_rate``), naming that rate and what gave it; "" otherwise."""
    if run.replaced_rate is None:
        return ""
    source, own = run.replaced_rate
    where = (f"{Path(args.input) / 'seqinfo.ini'}'s frameRate" if source == "seqinfo.ini"
             else f"the rate of {args.input}'s header,")
    return f"; tracked at --fps {args.fps:g} frames/s, over {where} {own:g}"


_RATE_SOURCES = {"seqinfo.ini": "the frameRate of seqinfo.ini",
                 "the header": "the rate of the video's header"}
"""What gave an input's own frame rate (:attr:`~vistrack.pipeline.VideoRun.replaced_rate`),
as several inputs' summary names it."""


def _outputs_problem(args: argparse.Namespace, name: str, box: bool,
                     offline_given: list[str]) -> str:
    """What is wrong with one input's ``--out`` or ``--out-dir`` and the options that go with
    either, "" if nothing; checked before anything is read or computed, so that a run that
    cannot write its outputs fails now (raises as :func:`~vistrack.io.atomic.check_output`
    and :func:`~vistrack.pipeline.video_outputs` do)."""
    from .io.atomic import check_not_input, check_output
    from .io.motchallenge import DETECTION_SUFFIXES, PARQUET_DETECTIONS
    from .io.video import _TEXT_SUFFIXES, _holds_images
    from .pipeline import input_files, sequence_inputs, video_outputs

    setting_flags = _box_settings_given(args, name)
    if not box:
        # (dcpf reads its own table of --config, and prints it)
        given = setting_flags + [f for f in ("still_camera", "config", "print_config")
                                 if getattr(args, f)
                                 and not (name == "dcpf" and f != "still_camera")]
        if given:
            return _box_setting_problem(given[0])
        if args.out is not None:
            what = (f"--tracker {name}" if args.tracker is not None
                    else f"--frontend {args.frontend}, tracked by {name},")
            return (f"--out (a sequence's detections) goes with {_box_trackers()}; "
                    f"{what} goes with --out-dir")
    if args.zero_distance is not None and args.gt is None:
        return "--zero-distance goes with --gt (it says how the tracks are scored against it)"
    if args.out is not None:
        folder = Path(args.input)
        sequence = folder.is_dir() and ((folder / "seqinfo.ini").exists()
                                        or (folder / "det" / "det.txt").exists())
        if args.gt is not None:
            # a user who wants a detections source's scores was sent to --out-dir, which
            # tracks from pixels; a video's or an image folder's are --out-dir's
            detections = args.detections is not None or sequence or (
                folder.is_file() and folder.suffix.lower() in DETECTION_SUFFIXES)
            return "--gt goes with --out-dir" + (
                f"; score {args.out} after tracking with vistrack eval --gt {args.gt} --pred "
                f"{args.out}" if detections else "")
        for flag in _FRONTEND_OPTIONS:
            if getattr(args, flag) is not None:
                return f"--{flag.replace('_', '-')} goes with --out-dir"
        for flag in ("skip_bad_frames", "report"):
            if getattr(args, flag):
                return f"--{flag.replace('_', '-')} goes with --out-dir"
        if folder.is_dir() and args.detections is None and not sequence \
                and _holds_images(folder):
            # (it said seqinfo.ini was missing, then, given --fps, det/det.txt)
            return (f"--out is for a MOTChallenge sequence folder (seqinfo.ini, det/det.txt) "
                    f"or a detections file (.txt, .csv), and {args.input} is a folder of "
                    "images: track it from its pixels with --out-dir OUT/")
        if Path(args.input).is_file():
            suffix = Path(args.input).suffix.lower()
            if suffix not in DETECTION_SUFFIXES:
                # (a text file is no video either: --out-dir OUT/ then said it was not one)
                return (f"--out is for a MOTChallenge sequence folder (seqinfo.ini, "
                        f"det/det.txt) or a detections file (.txt, .csv), and "
                        f"{args.input} is neither" + (
                            f" (a {suffix} file)" if suffix in _TEXT_SUFFIXES
                            else f" ({PARQUET_DETECTIONS})" if suffix == ".parquet"
                            else ": track a video with --out-dir OUT/"))
            if args.detections is not None:
                return (f"{args.input} is a detections file, and --detections gives "
                        "another: give one")
            if args.fps is None:
                return (f"{args.input} is a detections file alone: give its frame rate "
                        "with --fps")
        missing = _missing_input(args)
        if missing:
            return missing
        # (--force wrote the results over the configuration the run read, or the sequence's
        # own files; named before "exists; pass --force")
        check_not_input([args.out], sequence_inputs(args.input, args.detections)
                        + input_files(None, config=args.config), name="--out")
        check_output(args.out, force=args.force, name="--out")
        if str(args.out).lower().endswith(".parquet"):
            from .io.motchallenge import need_parquet

            try:
                need_parquet()
            except ImportError as e:
                return f"--out {args.out}: {e}"
    elif Path(args.input).is_file() and Path(args.input).suffix.lower() in DETECTION_SUFFIXES:
        # OpenCV would decode the text as frames of noise and the run would "track" them
        return (f"--out-dir is for a video, image folder or sequence folder from pixels, and "
                f"{args.input} is a detections file: track it with --out RESULTS.txt "
                "(and its frame rate, --fps)")
    else:
        offline_flags = [f for f in ("offline", "detections") if getattr(args, f)]
        if offline_flags or offline_given:
            return _OFFLINE_NEEDS_OUT
        _, problem = _columns(args.columns)  # for --frontend detections:FILE
        if problem:
            return problem
        if args.skip_bad_frames and Path(args.input).is_file():
            return _skip_bad_frames_problem([args.input])
        missing = _missing_input(args)
        if missing:
            return missing
        video_outputs(args.out_dir, force=args.force, name="--out-dir",
                      points=_points(name),
                      inputs=input_files(args.input, gt=args.gt, frontend=args.frontend,
                                         config=args.config))
    # what a stop says it kept: the outputs there before the run (looked at when it stopped,
    # an unrelated file in --out-dir, or a file this run wrote, was taken for one)
    args.outputs_to = [(args.out if args.out is not None else args.out_dir, args.out is None)]
    args.had_outputs = _had_outputs(*args.outputs_to[0])
    return ""


def _missing_input(args: argparse.Namespace) -> str:
    """The first of one input's files (INPUT, ``--gt``, ``--detections``, ``--frontend
    detections:FILE`` or ``onnx:MODEL``) that does not exist, in the words the run would name
    it in, "" if none: named before an existing output's "pass --force" (which, given, named
    the input next), after the options that do not go with the run's mode."""
    frontend = args.frontend or ""
    kind, _, file = frontend.partition(":")
    return _first_missing(
        (args.input, " (a sequence folder, or a detections file)" if args.out is not None
         else ""),
        (args.gt, " (--gt FILE)"), (args.detections, " (--detections FILE)"),
        (file if kind in ("detections", "onnx") else None,
         f" (--frontend {kind}:{'FILE' if kind == 'detections' else 'MODEL'})"))


def _first_missing(*given: tuple[str | None, str]) -> str:
    """``"PATH does not exist WHAT"`` for the first ``(PATH, WHAT)`` given whose path does
    not exist (None and "": not given), "" if none."""
    for path, what in given:
        if path and not Path(path).exists():
            return f"{path} does not exist{what}"
    return ""


def _had_outputs(out: str | Path, folder: bool) -> bool:
    """Whether an output of a run to ``out`` (a results file, or a folder of a video's
    outputs) is there before it runs: what a stopped run says it kept."""
    from .pipeline import REPORT, RUN_INFO, SINK_FILES

    p = Path(out)
    if not folder:
        return p.exists()
    return any((p / name).exists() for name in (*SINK_FILES.values(), RUN_INFO, REPORT))


def _skip_bad_frames_problem(videos: Sequence[str]) -> str:
    """--skip-bad-frames given with video files only, where it would change nothing."""
    which = (f"{videos[0]} is a video file, decoded as it is" if len(videos) == 1
             else f"{', '.join(map(str, videos))} are video files, decoded as they are")
    return f"--skip-bad-frames goes with an image folder (or a sequence folder's img1/); {which}"


def _warn_unused_settings(args: argparse.Namespace, cfg: TrackConfig | None,
                          offline_given: list[str], rate: bool = True) -> None:
    """Warn of settings given that the configuration makes change nothing: the offline
    mode's without --offline, --low with a tracker of one stage online, --start-score at or
    below the start online, --still-camera where the camera's motion is not estimated
    anyway; and (``rate``) of a --config file printed by a run given another --fps."""
    if cfg is None:
        return
    start = max(cfg.tracker.high, cfg.tracker.new_track)  # (a new track's detection: both)
    if cfg.offline.enabled and args.start_score is not None \
            and cfg.offline.start_score <= start:
        # (the offline start is taken only above the tracker's: 0, 0.5, 0.7 gave one file)
        warnings.warn(f"--start-score {args.start_score:g} changes nothing: offline, tracks "
                      "start from the detections the online start takes (high "
                      f"{cfg.tracker.high:g} and new_track {cfg.tracker.new_track:g}) or, "
                      "above them, from --start-score's", UserWarning, stacklevel=1)
    if offline_given and not cfg.offline.enabled:
        named = ", ".join("--" + o.replace("_", "-") for o in offline_given)
        warnings.warn(f"{named}: offline settings, which change nothing without --offline",
                      UserWarning, stacklevel=1)
    if args.low is not None and not cfg.tracker.two_stage and not cfg.offline.enabled:
        # offline, low is also the least score of a detection a track is followed back
        # through: it was said to change nothing there too
        warnings.warn("--low: the second association stage's threshold, which changes "
                      f"nothing with a tracker of one stage ({cfg.name}) online (offline, "
                      "it is also the least score a track is followed back through)",
                      UserWarning, stacklevel=1)
    why = _still_already(args) if args.still_camera else None
    if why:
        warnings.warn(f"--still-camera changes nothing here: {why}", UserWarning, stacklevel=1)
    if args.config is not None and _config_file(args)[1].get("still_camera_option") is True \
            and not args.still_camera and _follows_view(args):
        warnings.warn(f"{args.config} was printed by a run given --still-camera ([derived] "
                      "still_camera_option): the background model's following of the view "
                      "is the front-end's, not a setting of the file; give --still-camera "
                      "for that run's tracks", UserWarning, stacklevel=1)
    printed = _printed_fps(_config_file(args)[1]) if args.config is not None and rate \
        else None
    if printed is not None and printed != args.fps:
        # the frame rate is no setting: --config does not set it, and a file printed by a
        # run given --fps tracked another way without a word
        warnings.warn(f"{args.config} was printed by a run given --fps {printed:g} ([derived] "
                      f"fps_option); this run is given "
                      + (f"--fps {args.fps:g}" if args.fps is not None
                         else "no --fps (its input's frame rate)")
                      + f": give --fps {printed:g} for that run's tracks", UserWarning,
                      stacklevel=1)


def _warn_printed_rate(args: argparse.Namespace, run: TrackRun | VideoRun,
                       derived: dict[str, Any] | None = None) -> None:
    """After one input's run: warn where its --config file was printed by a run given
    --fps whose tracker ran at another rate than this one's (``[derived] frame_rate``): the
    frame rate is no setting, and the file alone does not give that run's tracks. (Said
    before the run from --fps alone, it warned where this input's own rate is the one
    printed, and the tracks were the same.) ``derived``: the file's ``[derived]`` table
    (a box tracker's file's, read here, by default)."""
    if args.config is None or run.derived is None:
        return
    derived = _config_file(args)[1] if derived is None else derived
    printed, then = _printed_fps(derived), derived.get("frame_rate")
    now = run.derived.get("frame_rate")
    if printed is None or printed == args.fps or now is None:
        return
    # the rate that run's tracker ran at ([derived] frame_rate; the option's, without it)
    then = float(then) if isinstance(then, (int, float)) and not isinstance(then, bool) \
        else printed
    if then == float(now):
        return
    warnings.warn(f"{args.config} was printed by a run given --fps {printed:g} ([derived] "
                  f"fps_option), tracked at {then:g} frames/s; this run tracks at "
                  f"{float(now):g}"
                  + (f" (--fps {args.fps:g})" if args.fps is not None
                     else " (its input's frame rate)")
                  + f": give --fps {printed:g} for that run's tracks", UserWarning,
                  stacklevel=1)


def _printed_fps(derived: dict[str, Any]) -> float | None:
    """The ``--fps`` of the run that printed a configuration file, from its ``[derived]``
    table (``fps_option``), or None (not given)."""
    value = derived.get("fps_option")
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) \
        else None


def _dask_client(address: str) -> Any:
    """A client of the Dask scheduler at ``address`` (``--scheduler``), or a ValueError
    naming the address where none answers within 10 s: Dask's own error came as a traceback
    of 55 lines after 30 s, with the status of a bug (1)."""
    import logging

    from distributed import Client

    log = logging.getLogger("distributed")
    level = log.level
    log.setLevel(logging.CRITICAL)  # its retries' tracebacks: said in one line below
    try:
        return Client(address, set_as_default=False, timeout=10)
    except (OSError, TimeoutError) as e:
        raise ValueError(f"--scheduler {address}: no Dask scheduler answers there "
                         f"({' '.join(str(e).split())})") from None
    finally:
        log.setLevel(level)


def _follows_view(args: argparse.Namespace) -> bool:
    """Whether this run's front-end, from pixels, follows a view that moves unless
    ``--still-camera`` (the selective background model's)."""
    from .pipeline import FRONTENDS, default_frontend

    front = args.frontend or default_frontend(args.tracker or "bytetrack")
    return args.out_dir is not None and front in FRONTENDS and FRONTENDS[front].still_camera \
        and args.background != "mog2"


def _still_already(args: argparse.Namespace) -> str | None:
    """Why ``--still-camera`` changes nothing here, or None: the configuration file or the
    tracker estimates no camera motion, or the front-end, from pixels, takes the camera as
    still and cannot follow a view that moves (``bgsub`` with MOG2). The selective model
    follows a view that moves unless ``--still-camera``, whatever the tracker: with it, the
    option always changes something."""
    from .config import TrackConfig
    from .pipeline import FRONTENDS, default_frontend

    name = args.tracker or "bytetrack"
    front = args.frontend or default_frontend(name)
    # the selective background model follows a view that moves, unless --still-camera: there
    # it changes something, whatever the tracker; MOG2's state cannot be moved
    still_front = args.out_dir is not None and front in FRONTENDS and \
        FRONTENDS[front].still_camera
    if still_front and args.background != "mog2":
        return None
    if args.config is not None:
        if not _config_file(args)[0].tracker.camera_motion:
            return f"{args.config} sets camera_motion = false"
    elif not TrackConfig.preset(name).tracker.camera_motion:
        return f"--tracker {name} does not estimate the camera's motion"
    if still_front:
        return f"the {front} front-end with --background mog2 takes the camera as still"
    return None


def _columns(text: str | None) -> tuple[dict[str, str] | None, str]:
    """``--columns OURS=THEIRS,...`` as ``{ours: theirs}`` (None when not given), and what is
    wrong with it ("" if nothing)."""
    if not text:
        return None, ""
    written = [p for p in text.split(",") if p.strip()]
    pairs = [p.split("=", 1) for p in written]
    # the pair as written ('frame=' was said as 'frame')
    bad = [g for g, p in zip(written, pairs) if len(p) != 2 or not p[0].strip()
           or not p[1].strip()]
    if bad:
        return None, f"--columns takes OURS=THEIRS pairs separated by commas; got {bad[0]!r}"
    ours = [a.strip() for a, _ in pairs]
    twice = next((a for k, a in enumerate(ours) if a in ours[:k]), None)
    if twice is not None:  # (the dict kept the last, and the first went unread)
        given = ", ".join(f"{twice}={b.strip()}" for a, b in pairs if a.strip() == twice)
        return None, (f"--columns names {twice!r} twice ({given}); give each of vistrack's "
                      "columns one of yours")
    return {a.strip(): b.strip() for a, b in pairs}, ""


def _print_video_run(args: argparse.Namespace, run: VideoRun, report: TextIO) -> None:
    """A run from pixels in a few lines: counts and time a frame by stage, the files (and
    the report page, with --report, written here), the scores against --gt."""
    sec = dict(run.seconds)
    compiling = sec.pop("compile", 0.0)
    ms = ", ".join(f"{k} {1e3 * v / run.frames:.2f}" for k, v in sec.items())
    rows = (f"{_n(run.rows, 'position')} of {_n(run.tracks, 'particle')}"
            if _points(_tracker_and_numbers(args)[0]) else
            f"{_n(run.rows, 'box', 'boxes')} of {_n(run.tracks, 'track')}")
    print(f"tracked {_n(run.frames, 'frame')}: {rows}; "
          f"{run.fps:.0f} frames/s without writing (ms a frame: {ms})"
          + (f"; compiling took {compiling:.1f} s" if compiling >= 0.05 else "")
          + _fps_words(args, run), file=report)
    failed: Exception | None = None
    if args.report:
        from .report import write_report

        # the run's outputs are in place: an interrupt while the page is made (seconds, to
        # re-encode the video) said "earlier outputs are kept" of outputs already replaced
        args.outputs_written = list(run.files.values())
        try:
            run.files["report"] = write_report(args.out_dir, force=True)
        except Exception as e:  # noqa: BLE001  (raised below, after the run's own results)
            # (a page that failed, as with an OpenCV without a WebM encoder, hid the files
            # written and the scores: the command ended with the error alone)
            failed = e
    for key, path in run.files.items():
        print(f"  {key:<7} {path}", file=report)
    if run.scores is not None:
        from .io.motchallenge import sequence_name

        _table({sequence_name(args.input): run.scores}, report)  # (a dotted folder's whole name)
    if failed is not None:
        print("  the files above are written; --report's page is not, for the error below",
              file=report)
        raise failed


def _frontend_problem(args: argparse.Namespace, name: str) -> str:
    """What is wrong with a front-end's own option given with another front-end (it would
    change nothing), for --out-dir; "" if nothing."""
    from .pipeline import default_frontend, unread_frontend_option

    frontend = args.frontend or default_frontend(name)
    unread = unread_frontend_option(frontend, {k: getattr(args, k, None)
                                               for k in _FRONTEND_OPTIONS + ("columns",)})
    if unread is not None:
        here = (f"--frontend {frontend}" if args.frontend
                else f"the default front-end of --tracker {name}, {frontend}")
        return f"--{unread[0].replace('_', '-')} goes with --frontend {unread[1]}, not {here}"
    return _points_problem(args, name, frontend)


def _points_problem(args: argparse.Namespace, name: str, frontend: str) -> str:
    """What is wrong with spots or the particles tracker as given ("" if nothing): checked
    before anything is read, for one input or many, in the command line's words."""
    from .pipeline import min_search_range, points_problem

    problem = points_problem(name, frontend, cli=True)
    if problem:
        return problem
    if frontend == "spots" and args.diameter is None:
        # (--tracker particles alone was told of --frontend spots, which the user never gave)
        which = ("--frontend spots" if args.frontend
                 else f"--tracker {name}, whose front-end on a video is spots,")
        return f"{which} needs --diameter: the spots' diameter in pixels, odd (round up)"
    if not _points(name):
        return ""
    floor = min_search_range()
    if args.search_range is not None and not args.search_range > floor:
        return (f"--search-range must be above {floor:.2f} pixels (the gate of the positions' "
                f"own noise); got {args.search_range:g}")
    if args.max_lost is not None and not (math.isfinite(args.max_lost) and args.max_lost >= 0):
        return f"--max-lost must be a finite number of seconds >= 0; got {args.max_lost:g}"
    return ""


def _video_options(args: argparse.Namespace, name: str, box: bool,
                   cfg: TrackConfig | DCPFConfig | None) -> dict:
    """``track_video``'s keyword arguments from ``vistrack track``'s options, for one input or
    many: the front-end's, and the tracker's configuration, a file used as it is, or the
    options given over the front-end's defaults (bgsub: a still camera); ``dcpf``'s
    settings as its fields."""
    from dataclasses import fields

    from .pipeline import FRONTENDS, default_frontend
    from .tracking.dcpf import DCPFConfig

    options = {k: getattr(args, k) for k in _FRONTEND_OPTIONS if getattr(args, k) is not None}
    columns, _ = _columns(getattr(args, "columns", None))  # checked before, with its message
    if columns is not None:  # a CSV file's columns, for --frontend detections:FILE
        options["columns"] = columns
    options.update(tracker=name, skip_bad_frames=args.skip_bad_frames,
                   command=getattr(args, "command_line", None))
    if args.search_range is not None:  # the particles tracker's (checked before)
        options["search_range"] = args.search_range
    if args.zero_distance is not None:  # (with --gt, one input)
        options["zero_distance"] = args.zero_distance
    if _points(name) and args.max_lost is not None:  # the particles tracker's too
        options["max_lost"] = args.max_lost
    front = args.frontend or default_frontend(name)
    if args.still_camera and front in FRONTENDS and FRONTENDS[front].still_camera:
        options["follow_view"] = False  # the background model: the view is not followed
    if isinstance(cfg, DCPFConfig):  # --tracker dcpf's settings, as its overrides
        options.update({f.name: getattr(cfg, f.name) for f in fields(cfg)})
    elif args.config is not None or not box:
        if cfg is not None and box and front in FRONTENDS and FRONTENDS[front].still_camera \
                and cfg.tracker.camera_motion:
            # a front-end that needs a still camera turns the compensation off, as without a
            # file: where the file leaves camera_motion out, as there; where it sets it, said
            # (a file of [tracker] max_lost alone turned it on without a word)
            if "camera_motion" not in _config_file_keys(args)["tracker"]:
                cfg = cfg.with_values(tracker={"camera_motion": False})
            else:
                warnings.warn(f"{args.config}: camera_motion = true with the {front} "
                              "front-end, which needs a still camera (it follows a moving "
                              "view itself): the tracker compensates camera motion too; set "
                              "camera_motion = false, or leave it out, for the front-end's "
                              "default", UserWarning, stacklevel=2)
        if cfg is not None:
            options["config"] = cfg
    else:
        options.update({key: getattr(args, option) for option, table, key, *_ in _SETTINGS
                        if table == "tracker" and getattr(args, option) is not None})
        if args.still_camera:
            options["camera_motion"] = False
    return options


def _track_many(args: argparse.Namespace, offline_given: list[str]) -> int:
    """``vistrack track`` on several inputs (vistrack.batch): in parallel, a line as each is
    done, a table at the end; exit status 1 if any failed. ``offline_given``: the offline
    mode's settings given, refused with ``--out-dir`` and said to change nothing without
    ``--offline``, as for one input."""
    from .batch import Outcome, input_label, one_thread_here, plan, progress_lines, run_jobs

    if args.own_process:
        one_thread_here()  # before numpy: this process hands out the inputs, its workers track
    from .io.atomic import check_not_input, check_output
    from .pipeline import input_files, sequence_inputs, video_outputs

    def fail(text: str) -> int:
        return _fail("track", text)

    def progress(n: int) -> Callable[[Outcome, int, int], None] | None:
        return progress_lines(None if args.quiet else sys.stderr, n)

    def clear_bar() -> None:
        # a batch that stopped before its last input (not run, Ctrl-C) left the bar, and
        # the table was printed on its line; cleared (a bar already cleared is an empty line)
        if not args.quiet and sys.stderr.isatty():
            sys.stderr.write("\r\x1b[K")
            sys.stderr.flush()

    if (args.out is None) == (args.out_dir is None):
        return fail("give --out RESULTS/ (each sequence's detections, NAME.txt each) or "
                    "--out-dir OUT/ (from pixels, NAME/ each)")
    if args.out is not None and Path(args.out).suffix.lower() in (".txt", ".csv", ".parquet") \
            and not Path(args.out).is_dir() and not args.out.endswith(("/", os.sep)):
        # (a folder of that name was made, which looked like one results file)
        many = (f"{len(args.input)} inputs" if len(args.input) > 1 else
                f"{args.input[0]}, a folder of sequences,")
        return fail(f"--out {args.out} names a file; with {many} --out is a folder, each "
                    "sequence's results NAME.txt in it: give --out RESULTS/")
    if args.jobs is not None and args.jobs < 1:
        return fail(f"--jobs must be 1 or more; got {args.jobs}")
    for flag in ("print_config", "gt", "zero_distance", "detections", "columns"):
        if getattr(args, flag):
            return fail(f"--{flag.replace('_', '-')} goes with one input")
    if (args.frontend or "").startswith("detections:"):
        # (every input was tracked from the one file)
        return fail(f"--frontend {args.frontend} goes with one input: a detections file is "
                    "one video's")
    if args.report:
        return fail("--report goes with one input (vistrack report NAME/ makes an input's "
                    "page afterwards)")
    name, box, problem = _tracker_and_numbers(args)
    if problem:
        return fail(problem)
    given = _box_settings_given(args, name) + [f for f in ("still_camera", "config")
                                                if getattr(args, f)
                                                and not (name == "dcpf" and f == "config")]
    if not box and given:  # as for one input (they were taken and ignored)
        return fail(_box_setting_problem(given[0]))
    cfg = None
    if box:
        cfg, problem = _box_config(args)
        if problem:
            return fail(problem)
    dcfg = None
    if name == "dcpf" and args.out is None:
        dcfg, problem = _dcpf_config(args)
        if problem:
            return fail(problem)
    options: dict = {"force": args.force}
    if args.out is not None:
        if not box:
            return fail(f"--out (sequences' detections) goes with {_box_trackers()}")
        for flag in _FRONTEND_OPTIONS:
            if getattr(args, flag) is not None:
                return fail(f"--{flag.replace('_', '-')} goes with --out-dir")
        if args.skip_bad_frames:  # (taken and ignored, where one input refuses it)
            return fail("--skip-bad-frames goes with --out-dir")
        kind, out, options["config"] = "detections", args.out, cfg
    else:
        if (cfg is not None and cfg.offline.enabled) or offline_given:
            return fail(_offline_needs_out(args, bool(offline_given)))
        if args.skip_bad_frames and all(Path(i).is_file() for i in args.input):
            return fail(_skip_bad_frames_problem(args.input))
        problem = _frontend_problem(args, name)
        if problem:
            return fail(problem)
        kind, out = "pixels", args.out_dir
        options.update(_video_options(args, name, box, cfg or dcfg))
    if args.fps is not None:  # every input's frame rate, put over any it gives
        options["fps"] = args.fps
    from .pipeline import _keep_warnings, _shown_warnings

    with _shown_warnings() as said:  # kept in each input's run.json, as for one input
        _warn_unused_settings(args, cfg, offline_given)
    jobs = plan(args.input, out, kind=kind, **options)
    # every job's inputs: one job's outputs may not be another's input either
    read = [r for job in jobs for r in (sequence_inputs(job.input) if kind == "detections"
                                        else input_files(job.input))]
    read += input_files(None, config=args.config)
    for job in jobs:  # before anything runs: a job that cannot write fails now
        if kind == "detections":
            check_not_input([job.out], read, name="--out")
            check_output(job.out, force=args.force, name="--out")
        else:
            video_outputs(job.out, force=args.force, name="--out-dir", points=_points(name),
                          inputs=read)
    args.had_outputs = any(_had_outputs(job.out, kind != "detections") for job in jobs)
    if args.scheduler is not None:
        if args.jobs is not None:
            return fail("--jobs goes with the local pool; the cluster has its own workers")
        try:
            client = _dask_client(args.scheduler)
        except ImportError:
            return fail("--scheduler needs Dask's distributed (pip install 'vistrack[dask]')")
        with client:
            try:
                outcomes = run_jobs(jobs, executor=client.get_executor(),
                                    keep_going=args.keep_going, on_done=progress(len(jobs)))
            finally:
                clear_bar()
    else:
        t0 = time.time()
        try:
            outcomes = run_jobs(jobs, workers=args.jobs, keep_going=args.keep_going,
                                on_done=progress(len(jobs)))
        except (KeyboardInterrupt, Terminated):
            clear_bar()
            written = _written_since(jobs, t0)
            print(f"vistrack track: {len(written)} of {len(jobs)} inputs written before it "
                  f"stopped{': ' if written else ''}{', '.join(written)}", file=sys.stderr)
            args.batch_written = written
            raise
        clear_bar()
    if kind == "pixels" and said:
        # run.json (and the report, from it) keeps the command's warnings before the run's
        # own, as for one input: with several inputs they were left out
        for o in outcomes:
            if o.ok:
                try:
                    _keep_warnings(o.out, said, before=True)
                except OSError:  # (a cluster's outputs out of reach here: printed above)
                    pass
    names = [input_label(o.input) for o in outcomes]
    width = max(len("input"), *map(len, names))  # (names shorter than the header: misaligned)
    # ("not run" is 7 wide: in a column of 6 it moved the rest of its row by one)
    print(f"{'input':{width}s}  status   frames  tracks  seconds  output")
    for o, input_name in zip(outcomes, names):
        status = "ok" if o.ok else ("failed" if o.attempts else "not run")
        print(f"{input_name:{width}s}  {status:7s}  {o.frames:6d}  {o.tracks:6d}  "
              f"{o.seconds:7.1f}  {o.out if o.ok else o.error}")
    bad = [o for o in outcomes if not o.ok]
    print(f"{len(outcomes) - len(bad)} of {len(outcomes)} inputs tracked"
          + (f"; {len(bad)} not" if bad else ""))
    over = {source: ", ".join(f"{n} {o.replaced_rate[1]:g}" for o, n in zip(outcomes, names)
                              if o.ok and o.replaced_rate and o.replaced_rate[0] == source)
            for source in _RATE_SOURCES}
    if any(over.values()):
        print(f"tracked at --fps {args.fps:g} frames/s, over "
              + "; over ".join(f"{_RATE_SOURCES[k]}: {v}" for k, v in over.items() if v))
    return 1 if bad else 0


def _written_since(jobs: Sequence[Job], t0: float) -> list[str]:
    """The names of the jobs whose outputs were written at ``t0`` (a time) or after: each is
    written whole or not at all, and the workers stop with an interrupted run, one perhaps
    writing its file as the signal came, without a line said of it. A job from pixels
    counts by its tracks file, ``tracks.txt`` or, from a point tracker, ``tracks.csv`` (its
    written inputs were counted as none)."""
    from .pipeline import SINK_FILES

    def mtime(job: Job) -> float:
        files = ([job.out] if job.kind == "detections" else
                 [job.out / SINK_FILES[k] for k in ("tracks", "csv")])
        return max((f.stat().st_mtime for f in files if f.exists()), default=-math.inf)

    return [j.out.name for j in jobs if mtime(j) >= t0 - 0.05]


def _fit(args: argparse.Namespace) -> int:
    from .batch import expand_inputs
    from .config import TrackConfig, config_toml, read_config
    from .io.atomic import check_not_input, check_output, open_replacing
    from .pipeline import fit_sequences, sequence_inputs

    if args.no_held_out and not args.gt:  # (accepted, and meant nothing)
        return _fail("fit", "--no-held-out goes with --gt")
    # a folder of sequences: its sequences, as track's (their detections are what is read)
    inputs = expand_inputs(args.inputs, reads="detections")
    # (--force wrote the configuration over a sequence's detections, or its ground truth)
    # (and over its own --config: fit --out c.toml --config c.toml --force replaced it, where
    # track refuses the same)
    check_not_input([args.out], [r for s in inputs for r in sequence_inputs(s)]
                    + ([("--config", args.config)] if args.config is not None else []),
                    name="--out")
    check_output(args.out, force=args.force, name="--out")
    args.outputs_to = [(args.out, False)]  # (what Ctrl-C says it kept)
    args.had_outputs = _had_outputs(args.out, False)
    if Path(args.out).suffix.lower() not in ("", ".toml"):
        # (fit --out learned.json wrote TOML unsaid, where track --out results.json warns)
        warnings.warn(f"{args.out}: written as TOML, the configuration's format (read back "
                      f"with --config); {Path(args.out).suffix} is not a format vistrack fit "
                      "writes", UserWarning, stacklevel=2)
    cfg = read_config(args.config) if args.config is not None else TrackConfig.preset()
    progress = sys.stderr if not args.quiet else None
    if args.gt:
        # a folder's sequences without ground truth (a set's test sequences) are left out,
        # as `vistrack eval --gt-dir` leaves them; a sequence named alone must have one
        named = {Path(i).resolve() for i in args.inputs}
        left = [s for s in inputs if Path(s).resolve() not in named
                and not (Path(s) / "gt" / "gt.txt").exists()]
        if left and len(left) < len(inputs):
            one = len(left) == 1
            warnings.warn(f"{len(left)} of the {len(inputs)} sequences {'has' if one else 'have'}"
                          f" no gt/gt.txt and {'is' if one else 'are'} left out: "
                          f"{', '.join(Path(s).name for s in left)}",
                          UserWarning, stacklevel=2)
            inputs = [s for s in inputs if s not in left]
    run = fit_sequences(inputs, gt=args.gt, config=cfg, held_out=not args.no_held_out,
                        keep_learned=args.keep_learned, progress=progress)
    rows = run.fit.per_sequence
    from .models.box import BoxMotion

    # at 30 frames/s, as the learned values and the footer say (a [motion] frame_rate of 10
    # printed the given noise at 10, beside the learned at 30: off by 1.7 and 5.2 times)
    given = (cfg.motion if cfg.motion is not None else BoxMotion()).at_rate(30.0)
    learned = run.fit.motion
    n_obj, n_det = sum(r["objects"] for r in rows), sum(r["detections"] for r in rows)
    print(f"learned from the {run.reference} of {len(rows)} of {len(inputs)} sequences: "
          f"{n_obj} objects, {n_det} matched detections")
    print(f"{'value':14s} {'given':>9s} {'learned':>9s}   each sequence (min to max)")
    values = [("std_pos", given.std_pos, learned.std_pos, [r["std_pos"] for r in rows]),
              ("std_vel", given.std_vel, learned.std_vel, [r["std_vel"] for r in rows])]
    values += [(f"std_meas {c}", given.std_meas[i], learned.std_meas[i],
                [r["std_meas"][i] for r in rows]) for i, c in enumerate(("cx", "cy", "w", "h"))]
    for name, a, b, each in values:
        print(f"{name:14s} {a:9.4g} {b:9.4g}   {min(each):.4g} to {max(each):.4g}")
    print("(fractions of the box's size; std_pos and std_vel per frame at 30 frames/s)")
    derived: dict = {"learned_from": run.reference, "sequences": len(rows),
                     "objects": n_obj, "detections": n_det}
    if run.held_out is not None:
        print("held out: each sequence tracked online with the values learned from the others,"
              " and with the given configuration (COMBINED)")
        print(f"{'':14s} {'HOTA':>6s} {'MOTA':>6s} {'IDF1':>6s}")
        for mode in ("given", "learned"):
            h = run.held_out[mode]
            print(f"{mode:14s} {100 * h['HOTA']:6.1f} {100 * h['MOTA']:6.1f} "
                  f"{100 * h['IDF1']:6.1f}")
            derived.update({f"held_out_{mode}_{k.lower()}": round(v, 6) for k, v in h.items()})
        if run.chosen == "given":
            print("the learned values did not track the held-out sequences better than the "
                  "given configuration (HOTA): wrote the given one, the learned values in its "
                  "[derived] table (--keep-learned writes them)")
        elif run.held_out["learned"]["HOTA"] <= run.held_out["given"]["HOTA"]:
            print("the learned values did not track the held-out sequences better than the "
                  "given configuration (HOTA): wrote them all the same (--keep-learned)")
    elif run.chosen == "measurement":
        raised = [c for c, a, b in zip(("cx", "cy", "w", "h"), given.std_meas,
                                       learned.std_meas) if b > a]
        print("without a ground truth nothing checks the learned values, and a first pass's "
              "tracks follow their detections in part: wrote the given configuration, "
              + (f"its measurement noise raised to the learned one for {', '.join(raised)}"
                 if raised else "the detections straying no more than it assumes")
              + "; the learned values in its [derived] table (--keep-learned writes them)")
    else:
        print("not checked on held-out sequences (that needs --gt, two sequences or more, and "
              "no --no-held-out): wrote the learned values")
    derived["written"] = run.chosen
    if run.chosen in ("given", "measurement"):
        derived.update({f"learned_{k}": (list(map(float, getattr(learned, k))) if k == "std_meas"
                                         else float(getattr(learned, k)))
                        for k in ("std_pos", "std_vel", "std_meas")})
    with open_replacing(args.out) as fh:
        fh.write(config_toml(run.config, derived))
    args.run_written = True
    print(f"wrote {args.out} (vistrack track SEQ_DIR --out RESULTS.txt --config {args.out})")
    return 0


def _track_one(args: argparse.Namespace) -> int:
    from .io.atomic import check_not_input, check_output
    from .pipeline import input_files, track_one

    init: list[float] | None = None
    if args.gt_origin is not None and args.gt is None:
        return _fail("track-one", "--gt-origin says where --gt's boxes count from; give --gt")
    if args.init is None and args.gt is None:
        return _fail("track-one", "--init is required: the object's box x,y,w,h in the first "
                     "frame (or --gt, whose first box is then the start)")
    try:
        if args.init is not None:  # commas, or the tabs or spaces of a line of a boxes file
            init = [float(v) for v in re.split(r"\s*,\s*|\s+", args.init.strip())]
            if len(init) != 4 or not all(math.isfinite(v) for v in init) or min(init[2:]) <= 0:
                raise ValueError
    except ValueError:
        return _fail("track-one", f"--init must be x,y,w,h (four finite numbers, w and h "
                     f"> 0); got {args.init!r}")
    # inputs that do not exist, named before an existing output's "pass --force" (which,
    # given, named the input next)
    missing = _first_missing((args.input, ""), (args.gt, " (--gt FILE)"))
    if missing:
        return _fail("track-one", missing)
    # before anything is read or computed: a run that would write over what it reads, or
    # cannot write, fails now
    check_not_input([args.out], input_files(args.input, gt=args.gt), name="--out")
    check_output(args.out, force=args.force, name="--out")
    args.outputs_to = [(args.out, False)]
    args.had_outputs = _had_outputs(args.out, False)
    run = track_one(args.input, init, args.out, method=args.method, gt=args.gt,
                    force=args.force, progress=sys.stderr if sys.stderr.isatty()
                    and not args.quiet else None, init_name="--init", gt_origin=args.gt_origin)
    # (one frame is the start alone: no frame followed, no rate; it said "0 frames/s")
    rate = (f"{args.method} {run.fps:.0f} frames/s" if len(run.boxes) > 1 else
            f"{args.method} started on the first frame, with none after it to follow")
    print(f"wrote {run.out}: {_n(len(run.boxes), 'box', 'boxes')}; {rate}")
    if run.scores is not None:
        s = run.scores
        print(f"success rate (IoU > 0.5) {100 * s['success']:.1f} %, AUC {100 * s['auc']:.1f} %, "
              f"precision (20 px) {100 * s['precision']:.1f} %")
    return 0


def _partial_runs(pairs: list[tuple[str, Path, Path, Path | None]],
                  failed: dict[str, str], points: bool = False,
                  benchmark: str = "auto") -> list[str]:
    """Warnings for results a run of vistrack wrote over part of the frames only (its
    ``run.json`` beside them; ``--stop``, or a video shorter than its ground truth): the
    ground truth's scored rows after its last frame count as missed (the rows ``benchmark``
    ignores were counted too: 1187 missed where FN had 1086 of them)."""
    import json

    from .evaluation.files import read_truth
    from .evaluation.mot import scored_truth
    from .pipeline import RUN_INFO

    out = []
    for name, gt, pred, _ in pairs:
        info = Path(pred).parent / RUN_INFO
        if name in failed or not info.is_file():
            continue
        try:
            run = json.loads(info.read_text(encoding="utf-8"))
            last = int(run["last_frame"])
            if Path(pred).name not in run["outputs"]:
                continue
        except (OSError, ValueError, KeyError, TypeError):
            continue  # not a run's own file: nothing to tell from it
        with warnings.catch_warnings():  # (said already, by the scoring's read of it)
            warnings.simplefilter("ignore")
            truth = read_truth(gt, points=points)
        after = truth.frames > last
        missed = int((after & scored_truth(truth, benchmark)).sum())
        if missed:  # (rows the convention ignores alone change no score: nothing to say)
            ignored = int(after.sum()) - missed
            more = f" ({ignored} more {'is' if ignored == 1 else 'are'} ignored)" if ignored else ""
            out.append(f"{pred}: its run ({info}) tracked frames {run.get('first_frame', 1)}-"
                       f"{last} only, and {gt} runs to frame {truth.frames[-1]}: its "
                       f"{_n(missed, 'scored row')} after frame {last} "
                       f"{'counts' if missed == 1 else 'count'} as missed (FN){more}")
    return out


def _eval(args: argparse.Namespace) -> int:
    import json

    from ._pool import default_jobs, one_thread_here

    jobs = default_jobs() if args.jobs is None else args.jobs
    if jobs > 1 and args.gt_dir and args.scheduler is None and args.own_process:
        one_thread_here()  # before numpy: the sequences are scored by the workers
    from .evaluation import evaluate_files

    pairs = []
    if args.force and not args.plots:  # (it overwrites plots alone: it did nothing)
        return _fail("eval", "--force goes with --plots")
    if (args.gt_dir or args.pred_dir) and (args.gt or args.pred):
        # (the one pair was dropped without a word, and the folders scored)
        return _fail("eval", "give --gt and --pred, or --gt-dir and --pred-dir, not both")
    if args.gt_dir or args.pred_dir:
        if not (args.gt_dir and args.pred_dir):
            return _fail("eval", "--gt-dir and --pred-dir go together")
        for flag in ("gt_dir", "pred_dir"):  # (a file's name became a folder of results)
            if not Path(getattr(args, flag)).exists():  # (a missing --pred-dir was named
                # as its first sequence's missing file)
                return _fail("eval", f"--{flag.replace('_', '-')} {getattr(args, flag)} does "
                             "not exist")
            if Path(getattr(args, flag)).is_file():
                single = "--gt" if flag == "gt_dir" else "--pred"
                return _fail("eval", f"--{flag.replace('_', '-')} {getattr(args, flag)} is a "
                             f"file, not a folder (one file: {single})")
        # SEQ.txt, or the .parquet or .csv file vistrack track --out writes, the suffix in
        # any case (MOT17-02.TXT was called missing, and left out of the stray files too)
        results: dict[str, list[Path]] = {}
        if Path(args.pred_dir).is_dir():
            for q in sorted(Path(args.pred_dir).iterdir()):
                if q.is_file() and q.suffix.lower() in (".txt", ".parquet", ".csv"):
                    results.setdefault(q.stem, []).append(q)
        for seq in sorted(p for p in Path(args.gt_dir).iterdir() if (p / "gt" / "gt.txt").exists()):
            found = results.get(seq.name, [])
            if len(found) > 1:
                return _fail("eval", f"results for {seq.name} in more than one file: "
                             f"{', '.join(map(str, found))}; keep one")
            pred = found[0] if found else Path(args.pred_dir) / f"{seq.name}.txt"
            if not pred.exists() and not args.keep_going:
                return _fail("eval", f"no results for {seq.name}: {pred} does not exist")
            info = seq / "seqinfo.ini"
            pairs.append((seq.name, seq / "gt" / "gt.txt", pred, info if info.exists() else None))
        if not pairs:
            hint = (f" ({args.gt_dir} is one sequence: --gt {args.gt_dir} --pred RESULTS.txt)"
                    if (Path(args.gt_dir) / "gt" / "gt.txt").is_file() else "")
            return _fail("eval", f"no SEQ/gt/gt.txt under {args.gt_dir}{hint}")
        # what is left out is said: sequences without ground truth (a set's test sequences),
        # and results that are no sequence's (a misspelt name), which were never scored
        left = sorted(p.name for p in Path(args.gt_dir).iterdir() if p.is_dir()
                      and not (p / "gt" / "gt.txt").exists() and any(
                          (p / q).exists() for q in ("seqinfo.ini", "det", "img1", "gt")))
        if left:
            print(f"vistrack eval: warning: {len(left)} sequence folder"
                  f"{'s' * (len(left) > 1)} of {args.gt_dir} {'have' if len(left) > 1 else 'has'}"
                  f" no gt/gt.txt and {'are' if len(left) > 1 else 'is'} left out: "
                  f"{', '.join(left)}", file=sys.stderr)
        scored = {name for name, *_ in pairs}
        stray = sorted(p.name for p in Path(args.pred_dir).iterdir() if p.is_file()
                       and p.suffix.lower() in (".txt", ".parquet", ".csv")
                       and p.stem not in scored)
        if stray:
            print(f"vistrack eval: warning: {len(stray)} file{'s' * (len(stray) > 1)} of "
                  f"{args.pred_dir} {'match' if len(stray) > 1 else 'matches'} no sequence "
                  f"with ground truth in {args.gt_dir} and {'are' if len(stray) > 1 else 'is'}"
                  f" not scored: {', '.join(stray)}", file=sys.stderr)
    elif args.gt and args.pred:
        for flag in ("keep_going", "scheduler", "jobs"):
            if getattr(args, flag) is not None and getattr(args, flag) is not False:
                return _fail("eval", f"--{flag.replace('_', '-')} goes with --gt-dir")
        if Path(args.pred).is_dir():  # ("Is a directory")
            return _fail("eval", f"--pred {args.pred} is a folder, not a results file (a "
                         "folder of them: --gt-dir SETDIR --pred-dir " f"{args.pred})")
        for flag in ("gt", "pred"):  # ("nope.txt: No such file or directory", no option)
            if not Path(getattr(args, flag)).exists():
                return _fail("eval", f"--{flag} {getattr(args, flag)} does not exist")
        from .io.motchallenge import _ground_truth_file

        try:  # a sequence folder's gt/gt.txt, as vistrack track takes the folder
            gt = _ground_truth_file(args.gt)
        except ValueError as exc:
            return _fail("eval", str(exc))
        # SEQ/gt/gt.txt, or a ground-truth file beside its seqinfo.ini (SEQ/gt.txt), named
        # after SEQ; any other file after itself (runs/MOT17-09.txt, not "runs"). Its folders
        # as an absolute path (gt.txt given from inside SEQ/gt/ has the parent ".": its
        # seqinfo.ini was not read, and a row past seqLength was scored)
        where = Path(os.path.normpath(gt.absolute()))
        seq = where.parent.parent if where.parent.name == "gt" else where.parent
        info = seq / "seqinfo.ini"
        own = where.parent.name == "gt" or gt.name == "gt.txt" or info.exists()
        pairs.append(((seq.resolve().name if own else gt.stem) or "sequence", gt,
                      Path(args.pred), info if info.exists() else None))
    else:
        return _fail("eval", "give --gt and --pred, or --gt-dir and --pred-dir")
    # a missing or malformed file is a user's mistake: main prints it in one line
    if args.jobs is not None and args.jobs < 1:
        return _fail("eval", f"--jobs must be 1 or more; got {args.jobs}")
    columns, problem = _columns(args.columns)
    if problem:
        return _fail("eval", problem)
    out_of_range = _number_problem(args)  # (--zero-distance, as vistrack track checks it)
    if out_of_range:
        return _fail("eval", out_of_range)
    zero = args.zero_distance
    if args.scheduler is not None and args.jobs is not None:
        return _fail("eval", "--jobs goes with the local pool; the cluster has its own workers")
    plots = [] if args.plots is None else [Path(args.plots) / "hota_alpha.png"] + [
        Path(args.plots) / f"timeline_{_file_name(name)}.png" for name, *_ in pairs]
    if plots:
        from .io.atomic import check_output

        for path in plots:
            check_output(path, force=args.force, name="--plots")
    if args.scheduler is not None:
        try:
            client = _dask_client(args.scheduler)
        except ImportError:
            return _fail("eval", "--scheduler needs Dask's distributed (pip install "
                         "'vistrack[dask]')")
        with client:
            res = evaluate_files(pairs, benchmark=args.benchmark,
                                 executor=client.get_executor(), keep_going=args.keep_going,
                                 columns=columns, zero_distance=zero)
    else:
        res = evaluate_files(pairs, benchmark=args.benchmark, jobs=jobs,
                             keep_going=args.keep_going, columns=columns, zero_distance=zero)
    for warning in res.warnings + _partial_runs(pairs, res.errors, zero is not None,
                                                 args.benchmark):
        print(f"vistrack eval: warning: {warning}", file=sys.stderr)
    for name, error in res.errors.items():
        print(f"vistrack eval: error: {name}: {error}", file=sys.stderr)
    if res.errors:
        print(f"vistrack eval: {len(pairs) - len(res.errors)} of {len(pairs)} sequences scored; "
              f"{len(res.errors)} not", file=sys.stderr)
    status = 1 if res.errors else 0
    if not res:  # nothing scored
        if args.json:
            print("{}")
        return status
    # the scores first: a plot that cannot be drawn or written loses none of them
    if args.json:
        print(json.dumps({k: v.summary() for k, v in res.items()}, indent=2))
    else:
        _table(res)
    sys.stdout.flush()
    if plots:
        from .evaluation.files import pair_matches
        from .io.atomic import made_folder, replacing, together
        from .viz.plots import plot_hota_alpha, plot_timeline

        written = plots[:1] + [path for pair, path in zip(pairs, plots[1:])
                               if pair[0] not in res.errors]
        # the plots as one set, as a run's outputs: one that failed (a full disk) left the
        # plots written before it under their final names, in a folder the run had made
        with made_folder(plots[0].parent), together():
            with replacing(plots[0]) as part:
                plot_hota_alpha(res, part, zero_distance=zero)
            for pair, path in zip(pairs, plots[1:]):
                if pair[0] not in res.errors:
                    with replacing(path) as part, warnings.catch_warnings():
                        # (the files' warnings were said by the scoring: not twice)
                        warnings.simplefilter("ignore")
                        plot_timeline(pair_matches(pair, args.benchmark, columns, zero),
                                      part, title=pair[0])
        for path in written:
            print(f"wrote {path}", file=sys.stderr)
    return status


def _file_name(name: str, limit: int = 120) -> str:
    """``name`` as part of a file's name: as it is, or, past ``limit`` characters, cut and
    told apart by a hash of the whole (a file's name holds 255 bytes, and the plots' names
    add to the sequence's; a name of 234 characters failed with "File name too long")."""
    if len(name.encode()) <= limit:
        return name
    import hashlib

    digest = hashlib.sha1(name.encode()).hexdigest()[:10]
    cut = name.encode()[:limit - 11].decode(errors="ignore")
    return f"{cut}-{digest}"


def _table(res: dict, stream=None) -> None:
    """The scores as a table: a column of 7 characters per score, wider where a value needs it
    (MOTA -1200.0, a count of millions), so that a space always parts two values; the names'
    column as wide as its header or its longest name, and two spaces."""
    from .evaluation.mot import SCORE_COLUMNS

    stream = sys.stdout if stream is None else stream
    width = max(len(k) for k in ["sequence", *res]) + 2
    rows = [[f"{100 * s[k]:.1f}" if pct else f"{s[k]:d}" for k, pct in SCORE_COLUMNS]
            for s in (c.summary() for c in res.values())]
    widths = [max([7] + [len(r[j]) + 1 for r in rows]) for j in range(len(SCORE_COLUMNS))]
    print("".join([f"{'sequence':<{width}}"] + [f"{c:>{w}}" for (c, _), w in
                                                 zip(SCORE_COLUMNS, widths)]), file=stream)
    for name, cells in zip(res, rows):
        print("".join([f"{name:<{width}}"] + [f"{v:>{w}}" for v, w in zip(cells, widths)]),
              file=stream)


def _runs(command: argparse.ArgumentParser, func: Callable[[argparse.Namespace], int],
          debug_help: str) -> None:
    """End a command's parser: its own ``--debug`` (so that it may come after the command's
    name; vistrack's applies when it is not given) and the function that runs it."""
    command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                         help=debug_help)
    command.set_defaults(func=func)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="vistrack", description="Visual object tracking: filters, trackers, scores."
    )
    parser.add_argument("--version", action="version", version=f"vistrack {__version__}")
    debug_help = ("show the traceback of a user's mistake found while running too (a bug's "
                  "is always shown; a bad option is one line either way)")
    parser.add_argument("--debug", action="store_true", help=debug_help)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo = sub.add_parser(
        "demo", help="track the bundled clip, or remake the lecture figures from real runs",
        description="Run a demo and write what it makes. 'track': the main job on the clip "
        "that ships with vistrack (PETS09-S2L1, frames 1-200, with its ground truth): tracks, "
        "scores, an annotated video and a plot in OUT/pets09-s2l1/, as `vistrack track "
        "CLIP --gt GT --out-dir OUT/pets09-s2l1` writes them. 'kalman': the 1-D filter, the "
        "forward-backward smoother and the 2-D constant-velocity example's figures in OUT.",
    )
    demo.add_argument("name", choices=DEMOS, metavar="DEMO",
                      help=f"which demo: {' or '.join(DEMOS)}")
    demo.add_argument("--out", action=_Once, type=_path, default="out", metavar="OUT",
                      help="folder for what the demo writes (default: out)")
    demo.add_argument("--force", action="store_true",
                      help="replace the results of an earlier run")
    demo.add_argument("--seeds", type=int,
                      help="kalman: simulated runs for the error statistics, 1 to 1,000,000 "
                      "(default: 1000)")
    _runs(demo, _demo, debug_help)
    track = sub.add_parser(
        "track", help="track a MOTChallenge sequence's detections, or a video from pixels",
        description="With --out: track a MOTChallenge sequence folder's detections "
        "(seqinfo.ini, det/det.txt), or a detections file alone (.txt or .csv, with --fps), "
        "and write a results file. With --out-dir: track a video "
        "file, image folder or sequence folder from pixels and write tracks.txt, tracks.csv, "
        "annotated.mp4 and trajectories.png (and scores, given --gt).")
    track.add_argument("input", metavar="INPUT", nargs="*", type=_path,
                       help="MOTChallenge sequence folder or detections file (--out), or "
                       "video (--out-dir); "
                       "several, or a folder of sequences, are tracked in parallel; none "
                       "with --print-config: print the configuration the options give")
    track.add_argument("--out", action=_Once, type=_path,
                       help="results file to write (detections mode); with several inputs, or "
                       "ending in /, the folder of their results, NAME.txt each")
    track.add_argument("--out-dir", action=_Once, type=_path,
                       help="folder for the outputs (video mode); with several inputs, a folder "
                       "NAME/ each inside it")
    track.add_argument("--jobs", type=int, metavar="N",
                       help="several inputs: processes tracking at once (default: the cores "
                       "this process may use; 1: one after the other, in this process)")
    track.add_argument("--scheduler", metavar="ADDRESS",
                       help="several inputs: run them on the running Dask cluster whose "
                       "scheduler is at ADDRESS (tcp://host:8786), each worker with vistrack "
                       "installed and the inputs and outputs on a filesystem it shares "
                       "(needs vistrack[dask])")
    track.add_argument("--keep-going", action="store_true",
                       help="several inputs: after one fails, track the others (default: "
                       "start no new one)")
    track.add_argument("--detections", action=_Once, type=_path,
                       help="detections file (default INPUT/det/det.txt): MOTChallenge's format, "
                       "or CSV with a header (.csv); a detector run on "
                       "every k-th frame only (rows on frames 1, 1 + k, ...) is tracked on "
                       "its own frames, the frames between given the tracks' predicted "
                       "(offline: filled) boxes")
    track.add_argument("--columns", metavar="OURS=THEIRS,...",
                       help="a CSV file's column names: frame, id (or particle), bb_left, "
                       "bb_top, bb_width, bb_height (or x, y: the centre; or the corners "
                       "x1, y1, x2, y2), conf, class "
                       "(e.g. frame=t,bb_width=w,bb_height=h,conf=score)")
    track.add_argument("--tracker", metavar="NAME",
                       help="tracker: bytetrack (default) or sort; in video mode also dcpf "
                       "(the detector-confidence particle filter on HOG's confidence map, "
                       "about 9 frames/s), particles (drifting points, the default with "
                       "--frontend spots; writes tracks.csv of frame,particle,x,y, no "
                       "tracks.txt), single:METHOD (one object, from the first frame's "
                       "most confident detection; METHOD as track-one's), or "
                       "module:callable, a tracker of your own (a callable returning an "
                       "object with step(frame, detections) -> Tracks and reset())")
    track.add_argument("--offline", action="store_true",
                       help="start tracks only at confident detections (--start-score), "
                       "smooth finished tracks, fill their gaps, drop tracks of weak "
                       "detections, follow tracks back through unused detections and join "
                       "tracks across gaps; scores are calibrated on the whole file (--out)")
    track.add_argument("--still-camera", action="store_true",
                       help="the camera does not move: no camera-motion compensation (on by "
                       "default in bytetrack, except with the bgsub front-end, whose "
                       "background model follows a view that moves unless this is given)")
    box = track.add_argument_group(
        "box tracker settings", "The thresholds apply to calibrated confidences in [0, 1] "
        "(how nearly detections of a score persist from frame to frame, and lie on chains "
        "of detections that last, as the detector's best do; learnt from the detections, so "
        "any score scale works), or with --scores "
        "raw to the scores themselves. Each option is put over --config, and the file over "
        "its preset ([tracker] name, which --tracker must then agree with). The defaults "
        "below are bytetrack's; --print-config --tracker NAME shows another preset's.")
    box.add_argument("--config", action=_Once, type=_path, metavar="FILE",
                     help="the whole tracker configuration, TOML (as --print-config writes): "
                     "a box tracker's [tracker], [motion] and [offline] tables, or "
                     "--tracker dcpf's [dcpf] table")
    box.add_argument("--print-config", action="store_true",
                     help="print the configuration used, with the values derived from the "
                     "data (raw score of each threshold, frame rate), as TOML to stdout; "
                     "the summary goes to stderr. Without INPUT: print the configuration "
                     "the options give, and track nothing")
    for option, _, _, kind, metavar, text, default in _SETTINGS:
        # (the particles tracker's max_lost: 3.5 frames)
        more = "; particles: 3.5 frames" if option == "max_lost" else ""
        box.add_argument("--" + option.replace("_", "-"), type=kind, metavar=metavar,
                         choices=("calibrated", "raw") if option == "scores" else None,
                         help=f"{text} (default {default:g}{more})" if kind is not str else
                         f"{text} (default {default})")
    track.add_argument("--frontend", help="video mode: bgsub (default; background model and "
                       "blobs), hog (OpenCV's people detector), confidence (the peaks of "
                       "HOG's confidence map; the default of dcpf), spots (round spots of "
                       "--diameter, microscopy; the default of particles), detections:FILE "
                       "(MOTChallenge's format, or CSV with a header; as --detections, a "
                       "detector run on every k-th frame is tracked on its own frames), or "
                       "onnx:MODEL.onnx (your own YOLO- or SSD-style detector; pip install "
                       "'vistrack[onnx]')")
    track.add_argument("--classes", type=_class_list, metavar="LIST",
                       help="video mode, onnx: the model's classes to keep, e.g. 0 (a COCO "
                       "model's people) or 0,2 (default: all)")
    track.add_argument("--onnx-layout", choices=("auto", "yolov8", "yolov5", "ssd"),
                       help="video mode, onnx: the model's output layout (default: auto, told "
                       "from the outputs' shapes)")
    track.add_argument("--fps", type=float, help="the true frame rate: video mode, for an "
                       "image folder or when the file's header is wrong; --out, for a "
                       "detections file alone or a sequence without seqinfo.ini (put over the "
                       "rate an input gives, where it gives one; with several inputs, every "
                       "input's)")
    track.add_argument("--gt", action=_Once, type=_path,
                       help="video mode, one input: MOTChallenge ground truth to score against "
                       "(or a .csv or .parquet file with a header; for points, "
                       "frame, particle, x, y)")
    track.add_argument("--zero-distance", type=float, metavar="PX",
                       help="with --gt: score positions by distance rather than boxes by "
                       "IoU, a match within PX/2 (as vistrack eval --zero-distance); points "
                       "(--frontend spots) are always scored so, by default at --diameter")
    track.add_argument("--stop", type=int,
                       help="video mode: the last frame to track (the background model "
                            "still starts from the first 20 frames, as a whole run's)")
    track.add_argument("--skip-bad-frames", action="store_true",
                       help="image folders: skip an unreadable, cut-short or differently sized "
                            "image with a warning naming it (default: stop with an error)")
    track.add_argument("--background", choices=("selective", "mog2"),
                       help="video mode, bgsub: the background model (default: selective, the "
                       "seeds' running mean and variance)")
    track.add_argument("--min-area", type=float,
                       help="video mode, bgsub: the smallest blob, in pixels (default: 500)")
    track.add_argument("--diameter", type=int, metavar="PX",
                       help="video mode, spots: the spots' diameter in pixels, odd (round "
                       "up); needed")
    track.add_argument("--minmass", type=float, metavar="X",
                       help="video mode, spots: the least integrated brightness of a spot, "
                       "in grey levels (default: 0)")
    track.add_argument("--invert", action="store_const", const=True,
                       help="video mode, spots: spots darker than the background")
    track.add_argument("--search-range", type=float, metavar="PX",
                       help="--tracker particles: the farthest a particle moves between "
                       "frames, in pixels: the radius of its gate one frame after it was "
                       "found (the gate grows while it is missed), and the farthest a link "
                       "reaches from where the particle is predicted (default: half "
                       "--diameter); its --max-lost is 3.5 frames by default")
    track.add_argument("--report", action="store_true",
                       help="video mode, one input: also write OUT/report.html, one page "
                       "with the command, the scores, the annotated video and the plots (as "
                       "vistrack report OUT writes it)")
    track.add_argument("--force", action="store_true", help="overwrite existing outputs")
    track.add_argument("--quiet", action="store_true",
                       help="no progress bar (shown on a terminal only)")
    _runs(track, _track, debug_help)
    rep = sub.add_parser(
        "report", help="one HTML page of a video run: the command, scores, video and plots",
        description="Write OUT_DIR/report.html from what `vistrack track VIDEO --out-dir "
        "OUT_DIR` wrote: the command that made it, the run's numbers, the scores against the "
        "ground truth, the annotated video (as WebM) and the trajectories, and with ground "
        "truth HOTA over α and each object's timeline. The page holds everything itself: it "
        "can be mailed or opened anywhere.")
    rep.add_argument("out_dir", metavar="OUT_DIR", type=_path,
                     help="a folder written by vistrack track --out-dir")
    rep.add_argument("--force", action="store_true", help="overwrite an existing report.html")
    _runs(rep, _report, debug_help)
    fit = sub.add_parser(
        "fit", help="learn a box tracker's motion and measurement noise from sequences",
        description="Learn the box motion's noise (std_pos, std_vel) and each value's "
        "measurement noise (std_meas: cx, cy, w, h) from MOTChallenge sequences: the "
        "detections matched to each object of the ground truth (--gt) or of a first pass's "
        "confident tracks (the offline mode), against those objects' boxes; the motion noise "
        "of maximum likelihood. Writes the configuration (TOML) that vistrack track --config "
        "reads, and prints the learned values beside the given ones. With --gt and two "
        "sequences or more, also tracks each sequence with the values learned from the "
        "others and with the given configuration, scores both, and writes the learned "
        "values only if they scored the higher HOTA (else the given configuration). Without "
        "--gt nothing is scored: it writes the given configuration with each measurement "
        "noise raised to the learned one where that is larger (a detector whose boxes stray "
        "more than the configuration assumes).")
    fit.add_argument("inputs", metavar="SEQ_DIR", nargs="+", type=_path,
                     help="MOTChallenge sequence folders (seqinfo.ini, det/det.txt), or a "
                     "folder of them")
    fit.add_argument("--out", action=_Once, type=_path, required=True,
                     help="configuration file to write (TOML)")
    fit.add_argument("--gt", action="store_true",
                     help="learn from each sequence's ground truth (SEQ_DIR/gt/gt.txt)")
    fit.add_argument("--config", action=_Once, type=_path, metavar="FILE",
                     help="the configuration to start from and compare with (default: the "
                     "default one)")
    fit.add_argument("--no-held-out", action="store_true",
                     help="with --gt: do not track and score the held-out sequences (the "
                     "learned values are written unchecked)")
    fit.add_argument("--keep-learned", action="store_true",
                     help="write the learned values even if they tracked the held-out "
                     "sequences no better than the given configuration (without --gt: all "
                     "of them, the motion noise too)")
    fit.add_argument("--force", action="store_true", help="overwrite an existing --out")
    fit.add_argument("--quiet", action="store_true", help="no report of each sequence")
    _runs(fit, _fit, debug_help)
    one = sub.add_parser(
        "track-one", help="follow one object from a box drawn on the first frame",
        description="Follow one object through a video or image folder from its box in the "
        "first frame; write frame,x,y,w,h lines (frames from 1).")
    one.add_argument("input", metavar="INPUT", type=_path, help="video file or image folder")
    one.add_argument("--init", action=_Once,
                     help="the first frame's box: x,y,w,h in 0-based pixels (or separated by "
                     "tabs or spaces; OTB's groundtruth_rect.txt counts from 1: subtract 1 from "
                     "x and y, or leave --init out and give --gt, whose first box is then the "
                     "start); a negative x as --init=-5,10,20,20")
    one.add_argument("--method", default="colour",
                     choices=("colour", "meanshift", "camshift", "particle", "template", "klt",
                              "wsl", "snake", "csrt", "kcf"),
                     help="colour (default: mean shift on a colour model learnt online, "
                     "with scale), meanshift (the same, fixed size), camshift, particle "
                     "(CONDENSATION on the colour model), template (affine SSD), klt (median "
                     "flow), wsl (robust online appearance model), snake (B-spline contour), "
                     "or OpenCV's csrt and kcf for comparison")
    one.add_argument("--out", action=_Once, type=_path, required=True, help="boxes file to write")
    one.add_argument("--gt", action=_Once, type=_path,
                     help="ground truth (OTB groundtruth_rect.txt, VOT groundtruth.txt or a boxes"
                     " file) to score against")
    one.add_argument("--gt-origin", type=int, choices=(0, 1), default=None,
                     help="where --gt's x y w h lines count pixels from: 1 (OTB's) or 0; "
                     "default by its name, 1 for groundtruth_rect.txt, else 0 with a warning")
    one.add_argument("--force", action="store_true", help="overwrite an existing boxes file")
    one.add_argument("--quiet", action="store_true", help="no progress bar")
    _runs(one, _track_one, debug_help)
    ev = sub.add_parser(
        "eval", help="score results against ground truth (HOTA, CLEAR MOT, IDF1)",
        description="Score MOTChallenge results as TrackEval does: HOTA, DetA, AssA, MOTA, "
        "MOTP, IDF1 and the counts, per sequence and combined.")
    ev.add_argument("--gt", action=_Once, type=_path,
                    help="ground-truth file (SEQ/gt/gt.txt; seqinfo.ini is read beside), or "
                    "the sequence folder SEQ holding it; or a .csv or .parquet file, read by "
                    "its columns' names (for points: frame, particle, x, y)")
    ev.add_argument("--pred", action=_Once, type=_path,
                    help="results file: MOTChallenge's text, or the .parquet or .csv file "
                    "vistrack track --out writes (or the tracks.csv of points that "
                    "--frontend spots writes)")
    ev.add_argument("--gt-dir", type=_path, help="folder of sequences SEQ/gt/gt.txt")
    ev.add_argument("--columns", metavar="OURS=THEIRS,...",
                    help="the results' column names in a .csv or .parquet file: frame, id, "
                    "bb_left, bb_top, bb_width, bb_height (or x, y: the centre; or the corners "
                    "x1, y1, x2, y2), conf (e.g. frame=t,id=tid,bb_width=w,bb_height=h)")
    ev.add_argument("--plots", action=_Once, type=_path, metavar="DIR",
                    help="also draw HOTA, DetA and AssA over the localisation threshold α, "
                    "each sequence and COMBINED, into DIR/hota_alpha.png, and each "
                    "sequence's objects over time, coloured by the predicted identity that "
                    "covers them, switches marked, into DIR/timeline_SEQ.png (a name over "
                    "120 bytes cut, with a hash of the whole)")
    ev.add_argument("--force", action="store_true", help="overwrite existing plots")
    ev.add_argument("--jobs", type=int, metavar="N",
                    help="with --gt-dir: sequences scored at once, each in a process of its "
                    "own (default: one for each core)")
    ev.add_argument("--keep-going", action="store_true",
                    help="with --gt-dir: a sequence whose files are missing or cannot be read "
                    "is named with its error and left out, the others are scored (COMBINED "
                    "over them), and the exit status is 1")
    ev.add_argument("--scheduler", metavar="ADDRESS",
                    help="with --gt-dir: score the sequences on the running Dask cluster whose "
                    "scheduler is at ADDRESS (tcp://host:8786), each worker with vistrack "
                    "installed and the files on a filesystem it shares (needs vistrack[dask])")
    ev.add_argument("--pred-dir", type=_path,
                    help="folder of results SEQ.txt (or SEQ.parquet, SEQ.csv)")
    ev.add_argument("--benchmark", default="auto", choices=("auto", "MOT15", "MOT16", "MOT17",
                                                           "MOT20"),
                    help="preprocessing of the ground truth (default: auto, MOT17's where "
                         "column 8 holds MOT16/17/20 classes in every row, MOT15's otherwise; "
                         "MOT20's classes are MOT17's, so give MOT20 for its sequences, whose "
                         "predictions on class 6, a non-motorised vehicle, it ignores)")
    ev.add_argument("--zero-distance", type=float, metavar="PX",
                    help="score positions rather than boxes (points, such as particles; or "
                    "boxes' centres): a pair's similarity 1 - distance / PX, at least 0, in "
                    "place of the IoU (TrackEval's for points): a match lies within PX/2")
    ev.add_argument("--json", action="store_true", help="print JSON instead of a table")
    _runs(ev, _eval, debug_help)
    return parser


def _one_line_warnings(command: str) -> Callable[..., None]:
    """``warnings.showwarning`` for the command line: ``vistrack COMMAND: warning: MESSAGE``."""

    def show(message: Warning | str, category: type[Warning], *rest: object,
             **kw: object) -> None:
        # one write for the line and its newline (print makes two): the workers of a batch
        # share stderr, and unbuffered (python -u) another's line fell between them
        sys.stderr.write(f"vistrack {command}: warning: {message}\n")
        sys.stderr.flush()

    return show


@functools.cache
def _parser() -> argparse.ArgumentParser:
    """The command line's parser, built once a process: parsing leaves it as it is, and
    building it (every command's options, each help text looked up by gettext) takes a few
    milliseconds that a program calling :func:`main` again and again would pay each time."""
    return build_parser()


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return its exit status.

    A user's mistake (:func:`_user_errors`) prints one line ``vistrack COMMAND: error:
    MESSAGE`` and returns 2 (with ``--debug``, its traceback instead); any other exception
    is a bug and shows its traceback. A mistake in the arguments themselves (an unknown
    option, a value of the wrong type, a missing argument) prints the same one line and
    exits 2 (``SystemExit``, as argparse does). Ctrl-C returns 130 and SIGTERM 143, each with one
    line (outputs are written whole or not at all: earlier ones are kept). When stdout is a
    pipe closed early (``vistrack eval --json | head -1``), the rest of the output is
    dropped quietly and the status is 1, as Python's documentation recommends.
    """
    parser = _parser()
    args, extra = parser.parse_known_args(argv)
    command = _command_parser(parser, getattr(args, "command", None))
    if extra:  # said by the command's parser (parse_args would say it as vistrack's)
        hint = ""
        if getattr(args, "command", None) == "eval" and not any(a.startswith("-") for a in extra):
            hint = ("; vistrack eval takes its files as options: --pred RESULTS --gt "
                    "GROUND_TRUTH, or --pred-dir and --gt-dir")
        else:
            hint = _option_hint(command, extra)
        command.error(f"unrecognized arguments: {' '.join(extra)}{hint}")
    if not hasattr(args, "func"):
        parser.print_help()
        return 2
    seeds = getattr(args, "seeds", None)
    if seeds is not None and not 1 <= seeds <= 1_000_000:
        # (10**10 ran out of memory after the figures were written; 10**20 failed in numpy's
        # words): demo.MAX_SEEDS, not imported for an error of the command line
        command.error(f"--seeds must be from 1 to 1,000,000; got {seeds}")
    if seeds is not None and getattr(args, "name", None) == "track":
        command.error("--seeds goes with 'vistrack demo kalman' (the error statistics' runs); "
                      "'track' takes none")
    args.command_line = _command_line(sys.argv[1:] if argv is None else argv)
    # the command is this process's own (vistrack's entry point), not a call from a program
    # whose environment it must leave alone (batch.one_thread_here)
    args.own_process = argv is None
    if args.own_process:
        # FFmpeg's own log lines (OpenCV's video reading: "[mov,mp4,... @ 0x...] moov atom
        # not found") came before vistrack's message of the same fault: one line is said of
        # each. Set before OpenCV first opens a video; a value of the user's own is kept
        os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
    # SIGTERM stops a run as Ctrl-C does, for as long as main runs (signal handlers can be
    # set in the main thread only)
    old = (signal.signal(signal.SIGTERM, _terminate)
           if threading.current_thread() is threading.main_thread() else None)
    try:
        return _dispatch(args)
    finally:
        if old is not None:
            signal.signal(signal.SIGTERM, old)


def _dispatch(args: argparse.Namespace) -> int:
    """Run the command with each warning printed as one line, as an error is
    (``vistrack track: warning: FILE: ...; skipped``)."""
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warnings(args.command)
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    """Run the command, turning an interrupt, a closed pipe or a user's mistake into one line
    and an exit status."""
    try:
        if args.command in ("track", "track-one", "demo"):
            # a first run compiles the kernels: say so once, and leave it out of the rates
            # (which demo kalman does not print)
            rates = not (args.command == "demo" and getattr(args, "name", None) == "kalman")
            with _compile.watch(None if getattr(args, "quiet", False) else sys.stderr,
                                rates=rates):
                status = args.func(args)
        else:
            status = args.func(args)
        sys.stdout.flush()  # a closed pipe shows here, not at exit
        return status
    except (KeyboardInterrupt, Terminated) as exc:
        return _stopped(args, exc)
    except SystemError as exc:
        # a signal's handler that raised as a compiled (numba) function returned: CPython
        # raises SystemError, "returned a result with an exception set", the interrupt its
        # cause (a traceback and status 1, 1 SIGTERM in 15 during the front-end's moments)
        if isinstance(exc.__cause__, (KeyboardInterrupt, Terminated)):
            return _stopped(args, exc.__cause__)
        raise
    except BrokenPipeError:
        # https://docs.python.org/3/library/signal.html#note-on-sigpipe: the reader has
        # gone; send the rest of stdout (and the flush at exit) to devnull
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except (OSError, ValueError):  # stdout is not a file (a test's capture)
            pass
        return 1
    except _user_errors() as exc:
        if args.debug:  # the traceback, and still a user's mistake's status (2, not 1)
            traceback.print_exc()
        return _fail(args.command, _message(exc))
    except OSError as exc:
        # the machine refusing an output (a full disk, a quota, a file size limit, a name too
        # long) is no bug: one line, as a user's mistake, the earlier outputs kept
        if exc.errno not in _REFUSED_WRITES:
            raise
        if args.debug:
            traceback.print_exc()
        return _fail(args.command, _message(exc))


def _stopped(args: argparse.Namespace, exc: BaseException) -> int:
    """Ctrl-C's or SIGTERM's one line and exit status."""
    # tracks, boxes, video and plot are written under partial names and renamed only when
    # complete (vistrack.io.atomic): what an earlier run wrote is still there
    kept = ""
    if getattr(args, "run_written", False):
        # stopped after the run's outputs were renamed into place (over earlier ones or not)
        kept = "; this run's outputs were written"
    elif getattr(args, "had_outputs", False):
        kept = "; earlier outputs are kept"
    elif any(_had_outputs(*o) for o in getattr(args, "outputs_to", ())):
        # a first run stopped after its outputs were renamed into place
        kept = "; this run's outputs were written"
    elif hasattr(args, "had_outputs") and not getattr(args, "batch_written", None):
        # a first run ("earlier outputs are kept" was said of none); a batch that wrote some
        # inputs has named them in the line before
        kept = "; nothing was written"
    written = getattr(args, "outputs_written", None)
    if written:  # (stopped while --report's page was made)
        kept = (f" after this run's outputs were written ({', '.join(map(str, written))}); "
                "the report page was not")
    how = "interrupted" if isinstance(exc, KeyboardInterrupt) else "terminated"
    print(f"vistrack {args.command}: {how}{kept}", file=sys.stderr)
    return 130 if isinstance(exc, KeyboardInterrupt) else 128 + signal.SIGTERM


_REFUSED_WRITES = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS, errno.ENAMETOOLONG}
"""The errors of a write the machine refuses (:func:`_run` says them in one line)."""


if __name__ == "__main__":
    sys.exit(main())

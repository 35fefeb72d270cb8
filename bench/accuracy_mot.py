"""Tracking accuracy on four sets of public detections, vistrack (online and offline) beside
the trackers a user would pick instead, each with its packaged defaults, scored the same way
(vistrack's scorer, which equals TrackEval; COMBINED and per sequence).

    python bench/accuracy_mot.py [--sets MOT15,MOT17,MOT16-FairMOT,KITTI] [--no-peers]
                                 [--boxmot-python PY] [--jitter SEEDS] [--every K]
                                 [--stride K] [--drop FRAC] [--config FILE]
                                 [--write docs/mot.md]
    python bench/accuracy_mot.py --set NAME=DIR [--set NAME=DIR ...] [options above]

Sets (``../shared/data``): MOT15 train with SORT's Faster R-CNN detections, MOT17 train with
the FRCNN detections, MOT16 train with FairMOT's detections (scores 0.5-0.99), and KITTI
tracking drives 0000-0010 with PointRCNN's raw scores (-0.85 to 16). One configuration,
vistrack's defaults, for every set and sequence.

Peers, in this run: roboflow ``trackers`` (SORT, ByteTrack, OC-SORT, BoT-SORT without camera
motion compensation, which needs the images), in this interpreter; boxmot (BoT-SORT without
ReID or camera motion compensation, ByteTrack, OC-SORT) in an interpreter of its own
(``--boxmot-python``, default ``.venv-boxmot/bin/python``; ``make bench-peers`` makes it),
since it pins ``filterpy<2`` and ``opencv-python<5``. boxmot refuses scores outside [0, 1]:
PointRCNN's raw scores are clipped to [0, 1] for it, which scored higher than passing them
through the logistic function (KITTI HOTA of its OC-SORT 58.6 against 56.3).

``--sets MOT15-ACF`` runs a set held out from the defaults' choice: MOT15's official public
detections, from the ACF detector, on the five training sequences that have them and ground
truth, scores unbounded (about -0.8 to 139). No setting was chosen on it; it is run by name
only, and written to a section of its own.

``--every K`` tracks every set at a K-th of its frame rate: each sequence's every K-th frame
(1, 1 + K, ...; detections and ground truth), renumbered, with ``frameRate`` divided by K. No
setting was chosen at those rates; the COMBINED tables go to a section of their own.

``--stride K`` gives every set a detector that ran on every K-th frame only: each
sequence's detections on frames 1, 1 + K, ... alone, numbered as the video's frames, scored
against the ground truth of every frame. vistrack reads the file as it is (it finds the stride
and tracks the detector's frames, predicting the tracks' boxes on the frames between online,
filling them offline); each peer is given the detector's frames alone, numbered 1, 2, ...,
at the frame rate divided by K (as ``--every K``), and its rows are written back at the
video's frames: the most a user of it gets without writing more.

``--drop FRAC`` gives every set a detector that did not deliver a fraction FRAC of the frames
it ran on (as one dropping frames while busy does): each sequence's detections with the rows
of that fraction of its frames with rows removed, the frames drawn at random (seed 0, one draw
per sequence), scored against the ground truth of every frame. vistrack and the peers read
the file as it is: no renumbering gives the peers the frames the detector delivered at their
own times.

``--set NAME=DIR`` adds a set of your own: the sequence folders in DIR, each laid out as
MOTChallenge's (``seqinfo.ini``, ``det/det.txt``, ``gt/gt.txt``), scored with TrackEval's
conventions as the others are (MOT16/17/20's where the ground truth has classes, MOT15's
where its class column is -1). Given alone, it runs that set only; ``--sets`` names the
shared ones to run beside it. Tables of such sets are printed, not written to the docs.

``--jitter N`` also runs vistrack's online default N more times with every detection box
moved by up to 0.05 pixel (uniform, seeds 1..N), and reports the spread of COMBINED HOTA: how
much of a difference between two settings is noise.

``--config FILE`` adds vistrack's rows (online and offline) with the configuration in FILE, a
TOML file as ``vistrack track --config`` reads (``vistrack track --print-config`` writes one
to start from), beside the defaults' on the same detections: a setting compared against the
defaults on every set. Their goals are checked as the defaults' are, the per-sequence tables
get their columns, and with ``--jitter`` each seed's boxes are tracked with both and the
difference in online COMBINED HOTA is reported per seed. Such tables are printed, not
written to the docs.
"""

from __future__ import annotations

import argparse
import platform
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from vistrack.config import ConfigError, TrackConfig, read_config
from vistrack.detector_checks import ordinal
from vistrack.evaluation import evaluate_files
from vistrack.io import read_mot, read_seqinfo, write_mot
from vistrack.pipeline import track_sequence

from _markdown import replace_section  # noqa: E402  (bench/ is on the path of its scripts)

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
SETS = {"MOT15": "mot15", "MOT17": "mot17", "MOT16-FairMOT": "mot16-fairmot",
        "KITTI": "kitti-tracking"}
HELD_OUT = {"MOT15-ACF": ("mot15", "det_public_acf.txt")}
"""Shared sets no setting was chosen on, run by name only (``--sets MOT15-ACF``): the folder
in ``../shared/data`` and the detections file beside ``det.txt`` in each sequence's ``det/``.
MOT15-ACF is MOT15's official public detections, from the ACF detector, on the five
sequences that have them and ground truth: another detector on MOT15's scenes, its scores
unbounded (about -0.8 to 139)."""
VISTRACK = ("vistrack", "vistrack offline")


def is_vistrack(label: str) -> bool:
    """A row of vistrack's: the defaults' (:data:`VISTRACK`) or a ``--config`` file's."""
    return label.split(" (")[0] in VISTRACK


def config_given(path: Path | None, write: str | None) -> TrackConfig | None:
    """The configuration of ``--config FILE`` (None without it), or an exit naming the
    problem: a file that is missing or not a configuration, or ``--write`` beside it (the docs
    hold the defaults' rows)."""
    if path is None:
        return None
    if write:
        sys.exit("--write takes no --config: --config's are printed, never written to the docs")
    try:
        return read_config(path)
    except (OSError, ConfigError) as exc:
        sys.exit(str(exc))


def sequences(root: str | Path) -> list[Path]:
    """The sequence folders with the frame rate, detections and ground truth in ``root``, a
    folder, or a shared set by name (:data:`SETS`)."""
    root = DATA / SETS[root] if isinstance(root, str) else root
    return sorted(p for p in root.iterdir()
                  if (p / "seqinfo.ini").exists() and (p / "gt" / "gt.txt").exists()
                  and (p / "det" / "det.txt").exists())


def held_out(name: str, root: Path) -> Path:
    """The held-out set ``name`` (:data:`HELD_OUT`) laid out as the others are, under
    ``root``: each of its sequences that has the set's detections file and ground truth, with
    that file as ``det/det.txt``, the ground truth and ``seqinfo.ini`` as they are."""
    folder, det = HELD_OUT[name]
    for d in sorted((DATA / folder).iterdir()):
        if (d / "det" / det).exists() and (d / "gt" / "gt.txt").exists():
            shutil.copy(d / "det" / det, _beside(d, root / d.name))
    return root


def own_sets(given: list[str]) -> dict[str, Path]:
    """``--set NAME=DIR`` options as ``{NAME: DIR}``, each DIR holding one sequence folder
    or more; exits naming the option that is wrong."""
    out: dict[str, Path] = {}
    for g in given:
        name, eq, folder = g.partition("=")
        name = name.strip()
        if not eq or not name or not folder:
            sys.exit(f"--set {g}: expected NAME=DIR")
        if name in SETS or name in HELD_OUT or name in out:
            sys.exit(f"--set {g}: {name!r} names a set already")
        root = Path(folder).expanduser()
        if not root.is_dir():
            sys.exit(f"--set {g}: {root} is not a folder")
        if not sequences(root):
            sys.exit(f"--set {g}: no sequence folder in {root} has seqinfo.ini, det/det.txt "
                     "and gt/gt.txt")
        out[name] = root
    return out


def score(seqs: list[Path], results: Path) -> dict:
    """Each sequence's scores by name, and ``"COMBINED"`` (a set of one sequence: its own)."""
    res = evaluate_files([(d.name, d / "gt" / "gt.txt", results / f"{d.name}.txt",
                           d / "seqinfo.ini") for d in seqs])
    return res if "COMBINED" in res else {**res, "COMBINED": res[seqs[0].name]}


def every_kth(seqs: list[Path], k: int, root: Path) -> list[Path]:
    """The sequences at a ``k``-th of their frame rate, written under ``root`` with the same
    names: frames 1, 1 + k, ... of the detections and the ground truth, numbered 1, 2, ...,
    and ``frameRate`` / k, ``seqLength`` the frames kept, in ``seqinfo.ini``."""
    out = []
    for d in seqs:
        o = root / d.name
        for sub in ("det/det.txt", "gt/gt.txt"):
            rows = np.loadtxt(d / sub, delimiter=",", ndmin=2)
            rows = rows[(rows[:, 0] - 1) % k == 0]
            rows[:, 0] = (rows[:, 0] - 1) // k + 1
            (o / sub).parent.mkdir(parents=True, exist_ok=True)
            np.savetxt(o / sub, rows, delimiter=",", fmt="%.10g")
        info = read_seqinfo(d)
        lines = []
        for line in (d / "seqinfo.ini").read_text().splitlines():
            key = line.split("=", 1)[0].strip().lower()
            if key == "framerate":
                line = f"frameRate={info.frame_rate / k:.10g}"
            elif key == "seqlength":
                line = f"seqLength={(info.seq_length - 1) // k + 1}"
            lines.append(line)
        (o / "seqinfo.ini").write_text("\n".join(lines) + "\n")
        out.append(o)
    return out


def _beside(d: Path, o: Path) -> Path:
    """``o``, a copy of the sequence ``d``'s ground truth and ``seqinfo.ini``, ready for
    detections of its own: the path of its ``det.txt``, to write."""
    (o / "det").mkdir(parents=True, exist_ok=True)
    (o / "gt").mkdir(parents=True, exist_ok=True)
    shutil.copy(d / "gt" / "gt.txt", o / "gt" / "gt.txt")
    shutil.copy(d / "seqinfo.ini", o / "seqinfo.ini")
    return o / "det" / "det.txt"


def strided(seqs: list[Path], k: int, root: Path) -> list[Path]:
    """The sequences with a detector that ran on every ``k``-th frame, written under ``root``
    with the same names: the detections of frames 1, 1 + k, ... alone, numbered as before;
    the ground truth and ``seqinfo.ini`` as they are."""
    out = []
    for d in seqs:
        rows = np.loadtxt(d / "det" / "det.txt", delimiter=",", ndmin=2)
        np.savetxt(_beside(d, root / d.name), rows[(rows[:, 0] - 1) % k == 0], delimiter=",",
                   fmt="%.10g")
        out.append(root / d.name)
    return out


def dropped(seqs: list[Path], frac: float, root: Path, seed: int = 0) -> list[Path]:
    """The sequences with a detector that did not deliver ``frac`` of its frames, written
    under ``root`` with the same names: ``det.txt``'s lines as they are, but those of the
    frames drawn (each frame with rows, with probability ``frac``; seed ``seed`` and the
    sequence's place in ``seqs``); the ground truth and ``seqinfo.ini`` as they are."""
    out = []
    for i, d in enumerate(seqs):
        lines = (d / "det" / "det.txt").read_text().splitlines(keepends=True)
        frames = np.array([int(float(t.split(",", 1)[0])) for t in lines], dtype=np.int64)
        have = np.unique(frames)
        gone = have[np.random.default_rng([seed, i]).random(len(have)) < frac]
        keep = ~np.isin(frames, gone)
        _beside(d, root / d.name).write_text("".join(t for t, k in zip(lines, keep) if k))
        out.append(root / d.name)
    return out


def renumber_back(src: Path, dst: Path, k: int) -> None:
    """Every results file in ``src`` written to ``dst`` with its frame ``i`` as the video's
    frame ``1 + (i - 1) k`` (the inverse of :func:`every_kth`'s numbering)."""
    dst.mkdir(parents=True, exist_ok=True)
    for f in src.glob("*.txt"):
        t = read_mot(f)
        write_mot(dst / f.name, 1 + (t.frames - 1) * k, t.ids, t.boxes, t.conf, force=True)


# ----------------------------------------------------------------------------- runners
def run_vistrack(seqs: list[Path], out: Path, offline: bool, jitter: int = 0,
                 config: TrackConfig | None = None) -> float:
    """Track every sequence into ``out`` (with ``config``, else the defaults); returns the
    frames per second of the tracker."""
    frames, sec = 0, 0.0
    for d in seqs:
        det = None
        if jitter:
            rng = np.random.default_rng(jitter)
            t = read_mot(d / "det" / "det.txt")
            j = rng.uniform(-0.05, 0.05, t.boxes.shape)
            j[:, 2:] = np.maximum(j[:, 2:], -t.boxes[:, 2:])
            det = out / f"{d.name}.det.txt"
            out.mkdir(parents=True, exist_ok=True)
            write_mot(det, t.frames, t.ids, t.boxes + j, t.conf, force=True)
        r = track_sequence(d, out / f"{d.name}.txt", detections=det, config=config,
                           offline=offline, force=True)
        frames, sec = frames + r.frames, sec + r.seconds
    return frames / max(sec, 1e-9)


def trackers_peers() -> dict:
    """roboflow ``trackers``' trackers by name, each a factory of the frame rate."""
    try:
        import trackers
    except Exception as exc:  # noqa: BLE001
        print(f"  (trackers not available: {exc})", file=sys.stderr)
        return {}
    return {"trackers SORT": lambda fps: trackers.SORTTracker(frame_rate=fps),
            "trackers ByteTrack": lambda fps: trackers.ByteTrackTracker(frame_rate=fps),
            "trackers OC-SORT": lambda fps: trackers.OCSORTTracker(frame_rate=fps),
            "trackers BoT-SORT": lambda fps: trackers.BoTSORTTracker(frame_rate=fps,
                                                                     enable_cmc=False)}


def run_trackers(make, seqs: list[Path], out: Path) -> float:
    import supervision as sv

    out.mkdir(parents=True, exist_ok=True)
    frames, sec = 0, 0.0
    for d in seqs:
        info, det = read_seqinfo(d), read_mot(d / "det" / "det.txt")
        tr = make(info.frame_rate)
        rows = []
        for f, s in enumerate(det.frame_slices(info.seq_length), start=1):
            b = det.boxes[s]
            dets = sv.Detections(xyxy=np.c_[b[:, :2], b[:, :2] + b[:, 2:]].astype(np.float32),
                                 confidence=det.conf[s].astype(np.float32),
                                 class_id=np.zeros(len(b), int))
            t0 = time.perf_counter()
            r = tr.update(dets)
            sec += time.perf_counter() - t0
            ok = r.tracker_id >= 0
            rows += [(f, i, x0, y0, x1 - x0, y1 - y0) for i, (x0, y0, x1, y1) in
                     zip(r.tracker_id[ok], r.xyxy[ok])]
        frames += info.seq_length
        a = np.array(rows, float).reshape(-1, 6)
        write_mot(out / f"{d.name}.txt", a[:, 0].astype(int), a[:, 1].astype(int), a[:, 2:6],
                  force=True)
    return frames / max(sec, 1e-9)


def run_boxmot(python: Path, seqs: list[Path], out: Path) -> dict:
    """boxmot's trackers in their own interpreter: {name: frames per second}."""
    cmd = [str(python), str(Path(__file__).with_name("peers_boxmot.py")), str(out),
           *map(str, seqs)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        tail = r.stderr.strip().splitlines()[-1] if r.stderr.strip() else "no output"
        print(f"  (boxmot failed: {tail})", file=sys.stderr)
        return {}
    fps: dict = {}
    for line in r.stdout.splitlines():
        name, _seq, f = line.split("\t")
        fps.setdefault(name, []).append(float(f))
    return {k: float(np.median(v)) for k, v in fps.items()}


# ------------------------------------------------------------------------------ tables
def fmt(c) -> str:
    return (f"{100 * c.HOTA:.1f} | {100 * c.MOTA:.1f} | {100 * c.IDF1:.1f} | {100 * c.DetA:.1f} "
            f"| {100 * c.AssA:.1f} | {c.IDSW} | {c.FP} | {c.FN}")


HEAD = ("| tracker | HOTA | MOTA | IDF1 | DetA | AssA | IDSW | FP | FN | frames/s |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")


def combined_table(res: dict, fps: dict) -> str:
    rows = [HEAD]
    for name, r in res.items():
        c = r["COMBINED"]
        bold = "**" if is_vistrack(name) else ""
        rows.append(f"| {bold}{name}{bold} | {fmt(c)} | {fps.get(name, float('nan')):.0f} |")
    return "\n".join(rows)


def goals(res: dict) -> list[str]:
    """The issue's goals on one set: online first on HOTA with MOTA and IDF1 within a point
    of the best peer (or above), offline first on all three, and no sequence more than 5 HOTA
    below the best peer on it."""
    peers = {k: v for k, v in res.items() if not is_vistrack(k)}
    if not peers:
        return []
    best = {m: max(getattr(r["COMBINED"], m) for r in peers.values())
            for m in ("HOTA", "MOTA", "IDF1")}
    out = []
    for name in (k for k in res if is_vistrack(k)):
        offline = name.split(" (")[0] == "vistrack offline"
        first_on = ("HOTA", "MOTA", "IDF1") if offline else ("HOTA",)
        c = res[name]["COMBINED"]
        checks = []
        for m in ("HOTA", "MOTA", "IDF1"):
            v, b = 100 * getattr(c, m), 100 * best[m]
            ok = v > b if m in first_on else v >= b - 1.0
            checks.append(f"{m} {v:.1f} vs {b:.1f} {'ok' if ok else 'MISSED'}")
        worst = min(((100 * (r.HOTA - max(p[s].HOTA for p in peers.values())), s)
                     for s, r in res[name].items() if s != "COMBINED"))
        checks.append(f"worst sequence {worst[1]} {worst[0]:+.1f} HOTA against its best peer "
                      f"{'ok' if worst[0] >= -5 else 'MISSED'}")
        out.append(f"- {name}: " + "; ".join(checks))
    return out


def per_sequence(res: dict) -> str:
    peers = [k for k in res if not is_vistrack(k)]
    ours = [*VISTRACK, *(k for k in res if is_vistrack(k) and k not in VISTRACK)]
    head = "| " + " | ".join(
        ["sequence", "vistrack", "offline", *(v.replace("vistrack ", "") for v in ours[2:]),
         "best peer (HOTA)",
         *(p.replace("trackers ", "t. ").replace("boxmot ", "b. ") for p in peers)]) + " |"
    rows = [head, "|---" * (2 + len(ours) + len(peers)) + "|"]
    seqs = [s for s in next(iter(res.values())) if s != "COMBINED"]
    for s in seqs:
        cells = [f"{100 * res[v][s].HOTA:.1f} / {100 * res[v][s].MOTA:.1f} / "
                 f"{100 * res[v][s].IDF1:.1f}" if v in res else "" for v in ours]
        best = max(peers, key=lambda p: res[p][s].HOTA) if peers else None
        cells.append(f"{100 * res[best][s].HOTA:.1f} ({best})" if best else "")
        cells += [f"{100 * res[p][s].HOTA:.1f}" for p in peers]
        rows.append(f"| {s} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sets", default=None, help="the shared sets to run, of "
                    f"{', '.join(SETS)} (all of them, unless --set is given), or "
                    f"{', '.join(HELD_OUT)} (held out: by name only)")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=DIR", dest="own",
                    help="a set of your own: MOTChallenge sequence folders in DIR")
    ap.add_argument("--no-peers", action="store_true")
    ap.add_argument("--boxmot-python", type=Path, default=ROOT / ".venv-boxmot" / "bin" /
                    "python")
    ap.add_argument("--jitter", type=int, default=0, metavar="SEEDS")
    ap.add_argument("--every", type=int, default=1, metavar="K")
    ap.add_argument("--stride", type=int, default=1, metavar="K")
    ap.add_argument("--drop", type=float, default=0.0, metavar="FRAC")
    ap.add_argument("--config", type=Path, metavar="FILE",
                    help="vistrack's rows with this configuration too (TOML, as vistrack "
                         "track --config reads)")
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    own = own_sets(args.own)
    given = args.sets if args.sets is not None else "" if own else ",".join(SETS)
    names = [s.strip() for s in given.split(",") if s.strip()]
    bad = [s for s in names if s not in SETS and s not in HELD_OUT]
    if bad:
        sys.exit(f"unknown set {bad[0]!r}; sets: {', '.join([*SETS, *HELD_OUT])} (and your "
                 "own: --set NAME=DIR)")
    held = [s for s in names if s in HELD_OUT]
    if held and args.write and (len(held) < len(names) or own or args.every > 1
                                or args.stride > 1 or args.drop):
        sys.exit(f"--write with {held[0]} takes it alone, at its own frame rate: its tables "
                 "have a section of their own")
    if names and not DATA.exists():
        sys.exit(f"{DATA} not found: the shared data must be beside this checkout")
    if own and args.write:
        sys.exit("--write takes the shared sets' tables alone; --set's are printed")
    config = config_given(args.config, args.write)
    mine = () if config is None else tuple(f"{v} ({args.config.name})" for v in VISTRACK)
    if args.every < 1 or args.stride < 1 or (args.every > 1 and args.stride > 1):
        sys.exit(f"--every and --stride must be at least 1, and one of them 1; got "
                 f"{args.every} and {args.stride}")
    if not 0 <= args.drop < 1 or (args.drop and (args.every > 1 or args.stride > 1)):
        sys.exit(f"--drop must be at least 0 and below 1, and goes alone; got {args.drop}")
    warnings.filterwarnings("ignore")
    peers = {} if args.no_peers else trackers_peers()
    boxmot = None if args.no_peers else args.boxmot_python
    if boxmot is not None and not boxmot.exists():
        print(f"  (boxmot skipped: {boxmot} does not exist; make bench-peers makes it)",
              file=sys.stderr)
        boxmot = None
    parts, notes = [], []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        roots = {**{n: DATA / SETS[n] if n in SETS else held_out(n, tmp / "held-out" / n)
                    for n in names}, **own}
        for name, root in roots.items():
            seqs = peer_seqs = sequences(root)
            if args.every > 1:
                seqs = peer_seqs = every_kth(seqs, args.every, tmp / "every" / name)
            peer_out = tmp / name
            if args.stride > 1:
                # the peers get the detector's frames alone (see the module)
                peer_seqs = every_kth(seqs, args.stride, tmp / "peers-in" / name)
                seqs = strided(seqs, args.stride, tmp / "strided" / name)
                peer_out = tmp / "peers-out" / name
            if args.drop:
                seqs = peer_seqs = dropped(seqs, args.drop, tmp / "dropped" / name)
            res, fps = {}, {}
            for label, offline, cfg in (*zip(VISTRACK, (False, True), (None, None)),
                                        *zip(mine, (False, True), (config, config))):
                fps[label] = run_vistrack(seqs, tmp / name / label, offline, config=cfg)
                res[label] = score(seqs, tmp / name / label)
            done = []
            for label, make in peers.items():
                fps[label] = run_trackers(make, peer_seqs, peer_out / label)
                done.append(label)
            if boxmot is not None:
                for label, f in run_boxmot(boxmot, peer_seqs, peer_out).items():
                    fps[label] = f
                    done.append(label)
            for label in done:
                if args.stride > 1:
                    renumber_back(peer_out / label, tmp / name / label, args.stride)
                res[label] = score(seqs, tmp / name / label)
            spread = ""
            if args.jitter:
                h = [100 * res["vistrack"]["COMBINED"].HOTA]
                diffs = []
                for seed in range(1, args.jitter + 1):
                    run_vistrack(seqs, tmp / name / f"jitter{seed}", False, jitter=seed)
                    h.append(100 * score(seqs, tmp / name / f"jitter{seed}")["COMBINED"].HOTA)
                    if config is not None:
                        run_vistrack(seqs, tmp / name / f"jitter{seed}-config", False,
                                     jitter=seed, config=config)
                        c = score(seqs, tmp / name / f"jitter{seed}-config")["COMBINED"]
                        hota = 100 * c.HOTA
                        diffs.append(f"seed {seed} {hota:.2f} ({hota - h[-1]:+.2f})")
                spread = (f"\n\nWith every box moved by up to 0.05 pixel ({args.jitter} seeds), "
                          f"vistrack's online COMBINED HOTA ranges {min(h):.2f}-{max(h):.2f}.")
                if diffs:
                    spread += (f" With {args.config.name}, on the same boxes (against the "
                               f"defaults'): {', '.join(diffs)}.")
            g = goals(res)
            title = (f"{name}, every {ordinal(args.every)} frame" if args.every > 1 else
                     f"{name}, detections on every {ordinal(args.stride)} frame"
                     if args.stride > 1 else
                     f"{name}, {args.drop:.0%} of the frames not delivered" if args.drop
                     else name)
            part = (f"### {title} ({len(seqs)} sequences)\n\n{combined_table(res, fps)}"
                    + ("\n\nGoals:\n\n" + "\n".join(g) if g else "") + spread)
            if args.every == 1 and args.stride == 1 and not args.drop:
                # otherwise the COMBINED tables alone
                part += ("\n\nHOTA / MOTA / IDF1 per sequence (peers: HOTA):\n\n"
                         f"{per_sequence(res)}")
            parts.append(part + "\n")
            print(parts[-1], flush=True)
    env = (f"Python {platform.python_version()}, numpy {np.__version__}, "
           f"{time.strftime('%Y-%m-%d')}")
    cmd = ("python bench/accuracy_mot.py" + (f" --sets {','.join(held)}" if held else "")
           + (f" --jitter {args.jitter}" if args.jitter else ""))
    if held:
        section = ("## A detector no setting was chosen on: MOT15's ACF detections\n\n"
                   f"Measured with `{cmd}` ({env}): MOT15's official public detections, from "
                   "the ACF detector, on the five training sequences that have them and "
                   "ground truth (`det/det_public_acf.txt` in `../shared/data/mot15`), its "
                   "scores unbounded (about -0.8 to 139); otherwise as above. The peers are "
                   "given the raw scores, as a user would give them (boxmot's clipped to [0, "
                   "1], which it requires: almost every one becomes 1). frames/s is the "
                   "tracker alone.\n\n" + "\n".join(parts))
    elif args.drop:
        cmd += f" --drop {args.drop:g}"
        section = (f"## A detector that drops frames: the four sets\n\nMeasured with `{cmd}` "
                   f"({env}): each sequence's detections without the rows of {args.drop:.0%} "
                   "of its frames with rows, drawn at random (seed 0), scored against the "
                   "ground truth of every frame. vistrack and the peers read the file as it "
                   "is. frames/s is the tracker alone.\n\n" + "\n".join(parts))
    elif args.stride > 1:
        cmd += f" --stride {args.stride}"
        k = ordinal(args.stride)
        section = (f"## A detector run on every {k} frame: the four sets\n\nMeasured with "
                   f"`{cmd}` ({env}): each sequence's detections on every {k} frame alone "
                   f"(frames 1, {1 + args.stride}, {1 + 2 * args.stride}, ...), numbered as "
                   "the video's frames, scored against the "
                   "ground truth of every frame. vistrack reads the file as it is; each peer is "
                   f"given the detector's frames alone, at the frame rate divided by "
                   f"{args.stride}, its rows written back at the video's frames. frames/s is "
                   "the tracker alone, over the video's frames for vistrack and the "
                   "detector's for the peers.\n\n" + "\n".join(parts))
    elif args.every > 1:
        cmd += f" --every {args.every}"
        section = (f"## Every {ordinal(args.every)} frame: the four sets at a lower frame "
                   f"rate\n\nMeasured with `{cmd}` ({env}): each sequence's every "
                   f"{ordinal(args.every)} frame (detections and ground truth), its frame rate "
                   f"divided by {args.every}, a rate no setting was chosen at; otherwise as "
                   "above. frames/s is the tracker alone.\n\n" + "\n".join(parts))
    else:
        section = ("## Accuracy on four sets, beside the peers\n\n"
                   f"Measured with `{cmd}` ({env}); vistrack's defaults, "
                   "the peers' packaged defaults, the frame rate from `seqinfo.ini`, "
                   "TrackEval's conventions (MOT15's for KITTI: ground-truth rows with conf 0 "
                   "are ignored). frames/s is the tracker alone, the median over sequences for "
                   "boxmot.\n\n" + "\n".join(parts) + "\n".join(notes))
    if args.write:
        replace_section(args.write, section)


if __name__ == "__main__":
    main()

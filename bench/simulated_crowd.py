"""A crowd that no setting was tuned on: MOT20-01's ground truth (429 frames at 25 frames/s,
1920x1080, 36-55 people a frame, half of each seen on average) with detections simulated from
it, vistrack beside the peers of ``accuracy_mot.py``, scored the same way (COMBINED over the
draws).

    python bench/simulated_crowd.py [--draws 3] [--persistence RHO] [--box-noise K]
                                    [--set KEY=VALUE ...] [--config FILE] [--source DIR ...]
                                    [--no-peers] [--boxmot-python PY] [--write docs/mot.md]

The four sets of ``accuracy_mot.py`` are what vistrack's defaults were chosen on; this one is
a check that a setting does not only fit them. The detector is simulated, one draw per seed:

- each pedestrian of the ground truth (class 1, flagged to be considered) is detected with
  probability ``0.2 + 0.75 v``, ``v`` its visibility, its box moved by 5 % of its width and
  3 % of its height (standard deviations) and its width and height scaled by ``exp`` of 8 %
  and 5 %;
- its score is ``lo + (hi - lo) * sigmoid(3 (v - 0.4) + N(0, 1))``: the less of a person is
  seen, the lower the score, with much overlap;
- clutter: 15 % as many boxes again, of people's sizes (60-250 pixels tall in MOT20-01's
  1080 rows, in proportion to the image's height elsewhere), anywhere, in any frame, scoring
  ``lo + (hi - lo) * sigmoid(N(-1.5, 1))``;
- three score scales, one per draw in turn: ``(lo, hi)`` = (0.3, 0.9) as FairMOT's on new
  scenes, (0.5, 1.0) as a detector thresholded at 0.5, and (-2, 9) as raw logits (passed to
  the peers as they are, as ``accuracy_mot.py`` passes PointRCNN's; boxmot clips them).

By default each frame's detections are drawn independently: a half-hidden person is missed in
one frame and found in the next as often as not. A real detector's misses last (the person
stays hidden, the image changes little from frame to frame): ``--persistence RHO`` makes each
person's detection a two-state Markov chain with the same rate of detection, found in the next
frame with probability ``p + RHO (1 - p)`` when found in this one and ``p (1 - RHO)`` when
not, and the score's noise an AR(1) process with correlation ``RHO`` over the person's
detections (0: the independent draws, the same as without the option).

``--box-noise K`` multiplies the four standard deviations of the boxes' noise by ``K``: a
detector that places its boxes less well (or better) than the one above, whose errors no
setting of vistrack's box filter was chosen for.

``--source DIR`` (repeatable) simulates the same detector on other scenes instead: MOT16,
MOT17 or MOT20 sequence folders whose ground truth has classes and visibility (MOT17's
``../shared/data/mot17/MOT17-*``, moving cameras among them), each draw covering them all.

``--set KEY=VALUE`` (repeatable) adds a row of vistrack with those settings over its defaults
(fields of ``BoxTrackerConfig`` or ``OfflineConfig``), online and offline, to compare a
setting against the defaults on the same draws. ``--config FILE`` adds the rows of the
configuration in FILE (a TOML file as ``vistrack track --config`` reads, the box motion's
``[motion]`` included), and ``--set`` then goes over it instead of over the defaults; such
rows are printed, not written to the docs.
"""

from __future__ import annotations

import argparse
import json
import platform
import shutil
import sys
import tempfile
import time
import warnings
from pathlib import Path

import accuracy_mot as acc  # bench/ is on the path of its scripts
import numpy as np

from vistrack.io import read_seqinfo, write_mot
from vistrack.pipeline import track_sequence

from _markdown import publish  # noqa: E402

SOURCE = acc.DATA / "mot20" / "MOT20-01"
SCALES = ((0.3, 0.9), (0.5, 1.0), (-2.0, 9.0))


def _persist(u: np.ndarray, p: np.ndarray, ids: np.ndarray, frames: np.ndarray,
             rho: float) -> np.ndarray:
    """Which rows are detected: row k (a person ``ids[k]`` in frame ``frames[k]``) when
    ``u[k]`` is below its chance, ``p[k]`` for a person's first row and after a frame it was
    missed ``p (1 - rho)``, after a frame it was found ``p + rho (1 - p)`` (``rho`` 0:
    ``u < p``, independent)."""
    seen = u < p
    if rho == 0:
        return seen
    prev = {}  # person -> (frame, found)
    for k in np.lexsort((frames, ids)):
        last = prev.get(ids[k])
        q = p[k]
        if last is not None and last[0] == frames[k] - 1:
            q = p[k] + rho * (1 - p[k]) if last[1] else p[k] * (1 - rho)
        seen[k] = u[k] < q
        prev[ids[k]] = (frames[k], seen[k])
    return seen


def _ar1(e: np.ndarray, ids: np.ndarray, frames: np.ndarray, rho: float) -> np.ndarray:
    """Standard normal noise ``e`` made an AR(1) process with correlation ``rho`` over each
    person's rows in frame order (``rho`` 0: ``e`` itself)."""
    if rho == 0:
        return e
    out = e.copy()
    order = np.lexsort((frames, ids))
    for a, b in zip(order[:-1], order[1:]):
        if ids[a] == ids[b]:
            out[b] = rho * out[a] + np.sqrt(1 - rho ** 2) * e[b]
    return out


def simulate(seed: int, lo: float, hi: float, root: Path, persistence: float = 0.0,
             source: Path = SOURCE, box_noise: float = 1.0) -> Path:
    """One draw of detections for ``source`` (MOT20-01; a MOT16/17/20 sequence folder with
    ground truth) into ``root/NAME-sim{seed}`` (MOTChallenge layout: ``det/det.txt``,
    ``gt/gt.txt``, ``seqinfo.ini``), with misses and score noise correlated from frame to
    frame by ``persistence`` and the boxes' noise times ``box_noise`` (see the module);
    returns the folder."""
    rng = np.random.default_rng(seed)
    gt = np.loadtxt(source / "gt" / "gt.txt", delimiter=",", ndmin=2)
    gt = gt[(gt[:, 6] != 0) & (gt[:, 7] == 1)]
    seen = _persist(rng.random(len(gt)), 0.2 + 0.75 * gt[:, 8], gt[:, 1], gt[:, 0],
                    persistence)
    f, b, v = gt[seen, 0].astype(int), gt[seen, 2:6].copy(), gt[seen, 8]
    n = len(f)
    w, h = b[:, 2].copy(), b[:, 3].copy()
    b[:, 0] += rng.normal(0, 0.05 * box_noise, n) * w
    b[:, 1] += rng.normal(0, 0.03 * box_noise, n) * h
    b[:, 2] *= np.exp(rng.normal(0, 0.08 * box_noise, n))
    b[:, 3] *= np.exp(rng.normal(0, 0.05 * box_noise, n))
    e = _ar1(rng.normal(0, 1.0, n), gt[seen, 1], f, persistence)
    s = lo + (hi - lo) / (1 + np.exp(-(3 * (v - 0.4) + e)))
    info = read_seqinfo(source)
    k = int(0.15 * n)
    cf = rng.integers(1, info.seq_length + 1, k)
    ch = rng.uniform(60, 250, k) * info.im_height / 1080  # MOT20-01's people, in its images
    cw = ch * rng.uniform(0.3, 0.5, k)
    cb = np.stack([rng.uniform(0, info.im_width - cw), rng.uniform(0, info.im_height - ch), cw,
                   ch], 1)
    cs = lo + (hi - lo) / (1 + np.exp(-rng.normal(-1.5, 1.0, k)))
    frames, boxes, scores = np.r_[f, cf], np.r_[b, cb], np.r_[s, cs]
    order = np.argsort(frames, kind="stable")
    d = root / f"{source.name}-sim{seed}"
    (d / "det").mkdir(parents=True)
    (d / "gt").mkdir()
    shutil.copy(source / "seqinfo.ini", d)
    shutil.copy(source / "gt" / "gt.txt", d / "gt")
    write_mot(d / "det" / "det.txt", frames[order], np.full(len(order), -1), boxes[order],
              scores[order])
    return d


def parse_set(text: str) -> tuple[str, object]:
    key, _, value = text.partition("=")
    if not key or not value:
        raise argparse.ArgumentTypeError(f"--set takes KEY=VALUE; got {text!r}")
    try:
        return key, json.loads(value)
    except json.JSONDecodeError:
        return key, value


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--draws", type=int, default=3, help="simulated draws (seeds 0..N-1)")
    ap.add_argument("--persistence", type=float, default=0.0, metavar="RHO",
                    help="correlation of a person's detection and score from frame to frame, "
                         "in [0, 1) (default 0: independent)")
    ap.add_argument("--box-noise", type=float, default=1.0, metavar="K",
                    help="the boxes' noise (the four standard deviations) times K, > 0 "
                         "(default 1): a detector that places its boxes less well")
    ap.add_argument("--set", type=parse_set, action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--config", type=Path, metavar="FILE",
                    help="vistrack's rows with this configuration too (TOML, as vistrack "
                         "track --config reads); --set goes over it")
    ap.add_argument("--source", type=Path, action="append", default=[], metavar="DIR",
                    help="a MOT16/17/20 sequence folder with ground truth (visibility) to "
                         "simulate from instead of MOT20-01 (repeatable: each draw covers "
                         "them all)")
    ap.add_argument("--no-peers", action="store_true")
    ap.add_argument("--boxmot-python", type=Path,
                    default=acc.ROOT / ".venv-boxmot" / "bin" / "python")
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    if not 0 <= args.persistence < 1:
        ap.error(f"--persistence must be in [0, 1); got {args.persistence}")
    if not 0 < args.box_noise < np.inf:
        ap.error(f"--box-noise must be > 0 and finite; got {args.box_noise}")
    sources = args.source or [SOURCE]
    for src in sources:
        if not (src / "gt" / "gt.txt").exists() or not (src / "seqinfo.ini").exists():
            sys.exit(f"{src}: no gt/gt.txt and seqinfo.ini" + (
                ": the shared data must be beside this checkout" if src == SOURCE else ""))
    config = acc.config_given(args.config, args.write)
    warnings.filterwarnings("ignore")
    over = dict(args.set)
    runs = {"vistrack": (None, {}, False), "vistrack offline": (None, {}, True)}
    tag = ", ".join(([args.config.name] if config is not None else [])
                    + [f"{k}={v}" for k, v in over.items()])
    if tag:
        runs |= {f"vistrack, {tag}": (config, over, False),
                 f"vistrack offline, {tag}": (config, over, True)}
    peers = {} if args.no_peers else acc.trackers_peers()
    boxmot = None if args.no_peers or not args.boxmot_python.exists() else args.boxmot_python
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        seqs = [simulate(i, *SCALES[i % len(SCALES)], tmp / "data", args.persistence, src,
                         args.box_noise)
                for i in range(args.draws) for src in sources]
        res = {}
        for label, (cfg, kw, offline) in runs.items():
            out = tmp / "out" / label
            for d in seqs:
                track_sequence(d, out / f"{d.name}.txt", config=cfg, offline=offline,
                               force=True, **kw)
            res[label] = acc.score(seqs, out)
        for label, make in peers.items():
            acc.run_trackers(make, seqs, tmp / "out" / label)
            res[label] = acc.score(seqs, tmp / "out" / label)
        if boxmot is not None:
            for label in acc.run_boxmot(boxmot, seqs, tmp / "out"):
                res[label] = acc.score(seqs, tmp / "out" / label)
    rows = ["| tracker | HOTA | MOTA | IDF1 | DetA | AssA | IDSW | FP | FN |",
            "|---" + "|---:" * 8 + "|"]
    for label, r in res.items():
        bold = "**" if label.startswith("vistrack") else ""
        c = r["COMBINED"] if "COMBINED" in r else r[seqs[0].name]  # one draw: no COMBINED row
        rows.append(f"| {bold}{label}{bold} | {acc.fmt(c)} |")
    draws = ["HOTA per draw (scores " + ", ".join(
        f"{SCALES[i % len(SCALES)][0]:g} to {SCALES[i % len(SCALES)][1]:g}"
        for i in range(args.draws)) + "):", "",
        "| tracker | " + " | ".join(d.name for d in seqs) + " |",
        "|---" * (len(seqs) + 1) + "|"]
    for label, r in res.items():
        draws.append(f"| {label} | " + " | ".join(f"{100 * r[d.name].HOTA:.1f}" for d in seqs)
                     + " |")
    cmd = "python bench/simulated_crowd.py" + (f" --draws {args.draws}" if args.draws != 3
                                               else "")
    cmd += f" --persistence {args.persistence:g}" if args.persistence else ""
    cmd += f" --box-noise {args.box_noise:g}" if args.box_noise != 1 else ""
    cmd += "".join(f" --set {k}={json.dumps(v)}" for k, v in over.items())
    cmd += "".join(f" --source {src}" for src in args.source)
    who = ", ".join(src.name for src in sources)
    lasting = (f" Here a person's misses last (`--persistence {args.persistence:g}`: found "
               "again after a miss, or missed again after a find, less often than the rate "
               "alone would have it), as a real detector's do." if args.persistence else "")
    section = "\n".join([
        ("## A simulated detector on other scenes" if args.source else "## A simulated crowd")
        + (" whose misses last" if args.persistence else "")
        + (f", its boxes {args.box_noise:g} times as noisy" if args.box_noise != 1 else ""),
        "",
        f"Measured with `{cmd}` (Python {platform.python_version()}, "
        f"{time.strftime('%Y-%m-%d')}): {who}'s ground truth with detections simulated from "
        "it (see the script: detection and score fall with a person's visibility, clutter at "
        "low scores, three score scales), "
        + ("a detector that none of vistrack's settings was chosen on (on scenes some were)."
           if args.source else "a crowd that none of vistrack's settings was chosen on.")
        + f"{lasting} COMBINED over the draws:",
        "",
        *rows,
        "",
        *draws,
        ""])
    publish(section, args.write)


if __name__ == "__main__":
    main()

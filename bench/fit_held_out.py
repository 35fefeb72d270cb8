"""Is `vistrack fit` useful for tracking? Each sequence of a set tracked with the configuration
`vistrack fit --gt` wrote from the other sequences of its set, against the defaults.

    python bench/fit_held_out.py [--sets MOT15,MOT17,MOT16-FairMOT,KITTI] [--jobs N]
                                 [--write docs/mot.md]

Leave one out, nested: for each sequence, `vistrack.pipeline.fit_sequences` learns
from the others (their ground truth), runs its own held-out check among them (each tracked
with the values learned from the rest, and with the defaults) and returns the learned motion
only if that check scored it higher; the sequence left out, which took no part in any of it,
is then tracked online with what it returned. Also shown: the learned values whatever the
check says (`keep_learned`), each sequence tracked with those learned from the others.
COMBINED HOTA / MOTA / IDF1 over each set, scored as `bench/accuracy_mot.py` scores.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from accuracy_mot import SETS, score, sequences  # noqa: E402

from _markdown import replace_section  # noqa: E402

HEADING = "## `vistrack fit` on sequences it did not learn from"


def _fold(seqs: list[Path], k: int, out: Path) -> tuple[str, str]:
    """Sequence ``k`` tracked with what fit learned from the others: the fit's choice, and
    the learned values kept whatever the check said; returns the choice and the name."""
    from vistrack.config import TrackConfig
    from vistrack.pipeline import fit_sequences, track_sequence

    others = [s for i, s in enumerate(seqs) if i != k]
    run = fit_sequences(others, gt=True)
    online = replace(TrackConfig.preset(), offline=replace(TrackConfig.preset().offline,
                                                           enabled=False))
    track_sequence(seqs[k], out / "chosen" / f"{seqs[k].name}.txt",
                   config=replace(online, motion=run.config.motion), force=True)
    track_sequence(seqs[k], out / "learned" / f"{seqs[k].name}.txt",
                   config=replace(online, motion=run.fit.motion), force=True)
    track_sequence(seqs[k], out / "defaults" / f"{seqs[k].name}.txt", config=online,
                   force=True)
    return run.chosen, seqs[k].name


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sets", default=",".join(SETS))
    ap.add_argument("--jobs", type=int, default=2, help="folds at once (default 2)")
    ap.add_argument("--write", metavar="MD", help="write the section into this markdown file")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp, ProcessPoolExecutor(args.jobs) as pool:
        for name in args.sets.split(","):
            seqs = sequences(name)
            out = Path(tmp) / name
            for d in ("chosen", "learned", "defaults"):
                (out / d).mkdir(parents=True)
            folds = list(pool.map(_fold, [seqs] * len(seqs), range(len(seqs)),
                                  [out] * len(seqs)))
            learned = [n for c, n in folds if c == "learned"]
            res = {d: score(seqs, out / d)["COMBINED"] for d in ("defaults", "learned", "chosen")}
            fmt = {d: f"{100 * c.HOTA:.1f} / {100 * c.MOTA:.1f} / {100 * c.IDF1:.1f}"
                   for d, c in res.items()}
            rows.append((name, fmt["defaults"], fmt["learned"], fmt["chosen"],
                         f"{len(learned)} of {len(seqs)}" + (f" ({', '.join(learned)})"
                                                             if learned else "")))
            print(f"{name}: defaults {fmt['defaults']}, learned {fmt['learned']}, fit's choice "
                  f"{fmt['chosen']}; learned kept for {rows[-1][4]}", flush=True)
    table = ("| set | defaults | learned, held out | `vistrack fit`'s choice, held out | "
             "folds where fit kept the learned values |\n|---|---|---|---|---|\n"
             + "\n".join("| " + " | ".join(r) + " |" for r in rows) + "\n")
    print(table)
    if args.write:
        replace_section(args.write, HEADING + "\n\n"
                        "Measured with `python bench/fit_held_out.py` (COMBINED HOTA / MOTA / "
                        "IDF1, online). " + " ".join(__doc__.split("\n\n")[2].split()) + "\n\n"
                        + table)


if __name__ == "__main__":
    main()

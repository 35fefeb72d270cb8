"""The clutter that stays (``bench/static_clutter.py``): the boxes added recur in place, in
nine frames of ten, scoring no higher than the file's lowest detection, and the file's own
detections are kept as they were."""

import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from vistrack.io import read_mot, write_mot

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
static = pytest.importorskip("static_clutter")


@pytest.mark.parametrize("lo", [0.3, 0.0, -1.0])
def test_boxes_that_stay_score_no_higher_than_the_lowest(tmp_path, lo):
    src = tmp_path / "SEQ"
    (src / "det").mkdir(parents=True)
    (src / "gt").mkdir()
    (src / "seqinfo.ini").write_text("[Sequence]\nname=SEQ\nimDir=img1\nframeRate=25\n"
                                     "seqLength=400\nimWidth=640\nimHeight=480\nimExt=.jpg\n")
    rng = np.random.default_rng(0)
    frames = np.repeat(np.arange(1, 401), 3)
    boxes = np.c_[rng.uniform(0, 500, (1200, 2)), rng.uniform(20, 80, (1200, 2))]
    conf = np.round(rng.uniform(lo, lo + 0.7, 1200), 2)  # as written: the lowest is lo
    conf[0] = lo
    write_mot(src / "det" / "det.txt", frames, np.full(1200, -1), boxes, conf)
    (src / "gt" / "gt.txt").write_text("1,1,10,10,20,40,1,1,1\n")
    out = static.add_clutter(src, 4, tmp_path / "out")
    assert (out / "gt" / "gt.txt").read_text() == (src / "gt" / "gt.txt").read_text()
    got, own = read_mot(out / "det" / "det.txt"), read_mot(src / "det" / "det.txt")
    # the file's own rows, as written, each found once among the rows out
    rows = Counter(zip(own.frames.tolist(), map(tuple, own.boxes.tolist()), own.conf.tolist()))
    added = np.ones(len(got.conf), bool)
    for k, key in enumerate(zip(got.frames.tolist(), map(tuple, got.boxes.tolist()),
                                got.conf.tolist())):
        if rows[key]:
            rows[key] -= 1
            added[k] = False
    assert sum(rows.values()) == 0 and (~added).sum() == 1200
    # up to half the lowest score's magnitude below it (0.5 where it is 0)
    assert (got.conf[added] <= lo).all() and (got.conf[added] > lo - (abs(lo) / 2 or 0.5)).all()
    # about 0.9 of 4 boxes a frame (binomial, 1,600 draws: within 4 standard errors)
    assert abs(added.sum() / 1600 - 0.9) < 4 * np.sqrt(0.09 / 1600)
    # four places, each box within a few pixels of its place, of a size of the file's own
    wh = got.boxes[added, 2:]
    sizes = np.unique(wh, axis=0)
    assert len(sizes) == 4 and all((own.boxes[:, 2:] == s).all(1).any() for s in sizes)
    for s in sizes:
        xy = got.boxes[added][(wh == s).all(1), :2]
        assert np.abs(xy - np.median(xy, 0)).max() < 12  # 2 pixels' noise, 6 standard deviations
    assert np.all(np.diff(got.frames) >= 0)  # in frame order

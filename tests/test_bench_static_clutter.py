"""The clutter that stays (``bench/static_clutter.py``): the boxes added recur in place, in
nine frames of ten, scoring below every detection of the file, and the file's own
detections are kept as they were."""

import sys
from pathlib import Path

import numpy as np
import pytest

from vistrack.io import read_mot, write_mot

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
static = pytest.importorskip("static_clutter")


def test_boxes_that_stay_are_added_below_every_score(tmp_path):
    src = tmp_path / "SEQ"
    (src / "det").mkdir(parents=True)
    (src / "gt").mkdir()
    (src / "seqinfo.ini").write_text("[Sequence]\nname=SEQ\nimDir=img1\nframeRate=25\n"
                                     "seqLength=400\nimWidth=640\nimHeight=480\nimExt=.jpg\n")
    rng = np.random.default_rng(0)
    frames = np.repeat(np.arange(1, 401), 3)
    boxes = np.c_[rng.uniform(0, 500, (1200, 2)), rng.uniform(20, 80, (1200, 2))]
    conf = np.round(rng.uniform(0.3, 1.0, 1200), 2)  # as written: the lowest is 0.3
    conf[0] = 0.3
    write_mot(src / "det" / "det.txt", frames, np.full(1200, -1), boxes, conf)
    (src / "gt" / "gt.txt").write_text("1,1,10,10,20,40,1,1,1\n")
    out = static.add_clutter(src, 4, tmp_path / "out")
    assert (out / "gt" / "gt.txt").read_text() == (src / "gt" / "gt.txt").read_text()
    got = read_mot(out / "det" / "det.txt")
    added = got.conf < 0.3
    assert (~added).sum() == 1200 and np.array_equal(np.sort(got.conf[~added]), np.sort(conf))
    assert (got.conf[added] >= 0.15).all()
    # about 0.9 of 4 boxes a frame (binomial, 1,600 draws: within 4 standard errors)
    assert abs(added.sum() / 1600 - 0.9) < 4 * np.sqrt(0.09 / 1600)
    # four places, each box within a few pixels of its place, of a size of the file's own
    wh = got.boxes[added, 2:]
    sizes = np.unique(wh, axis=0)
    own = read_mot(src / "det" / "det.txt").boxes[:, 2:]  # as written, to 2 decimals
    assert len(sizes) == 4 and all((own == s).all(1).any() for s in sizes)
    for s in sizes:
        xy = got.boxes[added][(wh == s).all(1), :2]
        assert np.abs(xy - np.median(xy, 0)).max() < 12  # 2 pixels' noise, 6 standard deviations
    assert np.all(np.diff(got.frames) >= 0)  # in frame order

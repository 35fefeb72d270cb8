"""The annotated video's colours and trails: identities far apart in colour (measured with
scikit-image's CIEDE2000, an independent colour-difference formula), and a trail drawn only
while its track is in the frame."""

import itertools

import numpy as np
import pytest

from vistrack.types import Tracks
from vistrack.viz import Annotator, id_colour
from vistrack.viz.annotate import PALETTE_SIZE


def _min_delta_e(ids):
    color = pytest.importorskip("skimage.color")
    bgr = np.array([id_colour(i) for i in ids], dtype=float) / 255
    lab = color.rgb2lab(bgr[None, :, ::-1])[0]
    return min(color.deltaE_ciede2000(lab[a], lab[b])
               for a, b in itertools.combinations(range(len(ids)), 2))


def test_identities_get_colours_far_apart():
    assert _min_delta_e(range(1, 31)) > 10  # golden-ratio HSV hues: 1.0 (ids 2, 10, 15: 4.5)
    assert _min_delta_e(range(1, PALETTE_SIZE + 1)) > 6
    assert len({id_colour(i) for i in range(1, PALETTE_SIZE + 1)}) == PALETTE_SIZE
    assert id_colour(5) == id_colour(5 + PALETTE_SIZE) and id_colour(0) == id_colour(PALETTE_SIZE)
    # bright enough to see on a dark frame, and not white
    for i in range(1, PALETTE_SIZE + 1):
        assert 120 <= max(id_colour(i)) and min(id_colour(i)) < 200


def _box_track(i, x):
    return Tracks(ids=np.array([i]), boxes=np.array([[x, 40, x + 20, 80.0]]), points=None,
                  scores=np.ones(1), classes=np.zeros(1))


def test_a_trail_ends_with_its_track():
    ann = Annotator(trail=30)
    empty = Tracks(ids=np.zeros(0, int), boxes=np.zeros((0, 4)), points=None,
                   scores=np.zeros(0), classes=np.zeros(0))
    black = np.zeros((120, 200, 3), np.uint8)
    for x in range(10, 60, 5):  # a track moving right: its trail lies behind its box
        out = ann.draw(black, _box_track(7, float(x)))
    colour = np.array(id_colour(7))
    trail_pixel = out[60, 35]  # on the trail, left of the last box
    assert (np.abs(trail_pixel.astype(int) - colour) < 60).all()
    gone = ann.draw(black, empty)  # the track is gone: nothing of it is drawn
    assert gone.max() == 0
    back = ann.draw(black, _box_track(7, 60.0))  # it returns: its trail goes on
    assert (np.abs(back[60, 35].astype(int) - colour) < 60).all()


def test_hota_over_alpha_is_drawn_from_the_scores(tmp_path, capsys):
    from tests.test_fit import _sequence
    from vistrack.cli import main
    from vistrack.evaluation import evaluate_files
    from vistrack.evaluation.mot import ALPHAS
    from vistrack.pipeline import track_sequence
    from vistrack.viz import plot_hota_alpha

    rng = np.random.default_rng(2)
    seqs = [_sequence(tmp_path / f"S{k}", rng) for k in range(2)]
    for s in seqs:
        track_sequence(s, tmp_path / "res" / f"{s.name}.txt")
    pairs = [(s.name, s / "gt" / "gt.txt", tmp_path / "res" / f"{s.name}.txt",
              s / "seqinfo.ini") for s in seqs]
    res = evaluate_files(pairs)
    fig = plot_hota_alpha(res)
    for ax, metric in zip(fig.axes, ("HOTA", "DetA", "AssA")):
        assert [line.get_label() for line in ax.lines] == ["S0", "S1", "COMBINED"]
        for line, name in zip(ax.lines, ("S0", "S1", "COMBINED")):
            np.testing.assert_array_equal(line.get_xdata(), ALPHAS)
            np.testing.assert_allclose(line.get_ydata(),
                                       100 * getattr(res[name], f"{metric}_alpha"))
    # the mean over α is the score itself
    np.testing.assert_allclose(fig.axes[0].lines[2].get_ydata().mean(), 100 * res["COMBINED"].HOTA)
    args = ["eval", "--gt-dir", str(tmp_path), "--pred-dir", str(tmp_path / "res"), "--plots",
            str(tmp_path / "plots")]
    assert main(args) == 0
    assert (tmp_path / "plots" / "hota_alpha.png").read_bytes()[:4] == b"\x89PNG"
    capsys.readouterr()
    assert main(args) == 2 and "--force" in capsys.readouterr().err
    assert main(args + ["--force"]) == 0

"""The annotated video's colours and trails: identities far apart in colour (measured with
scikit-image's CIEDE2000, an independent colour-difference formula), and a trail drawn only
while its track is in the frame."""

import itertools
import re
import warnings

import numpy as np
import pytest

from vistrack.types import Frame, Tracks
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


def _point_track(i, x, y=60.0):
    return Tracks(ids=np.array([i]), boxes=None, points=np.array([[x, y]]),
                  scores=np.ones(1), classes=np.zeros(1))


def test_a_trail_is_its_last_centres_however_often_it_wraps():
    """A trail is an identity's last ``trail`` centres, oldest first, as one anti-aliased
    line (kept in a ring whose last centres are one slice): a point on a zigzag, drawn with
    a trail of 7 after 2 to 53 frames (before, at and past each wrap of the ring), gives
    exactly OpenCV's line through those centres and the dot. An identity unseen for longer
    than the trail starts a new one; a trail of less than 0 frames is refused."""
    import cv2

    black = np.zeros((120, 200, 3), np.uint8)
    path = [(10.0 + 3 * k, 60.0 + (12 if k % 2 else -12) + 0.4 * k) for k in range(53)]
    colour = id_colour(3)
    for frames in (2, 6, 7, 8, 13, 14, 15, 22, 53):
        ann = Annotator(trail=7, labels=False)
        for x, y in path[:frames]:
            out = ann.draw(black, _point_track(3, x, y))
        want = black.copy()
        last = np.round(np.array(path[max(0, frames - 7):frames])).astype(np.int32)
        cv2.polylines(want, [last.reshape(-1, 1, 2)], False, colour, 2, cv2.LINE_AA)
        cv2.circle(want, tuple(int(v) for v in last[-1]), 3, colour, -1)
        np.testing.assert_array_equal(out, want, err_msg=f"after {frames} frames")
    ann = Annotator(trail=4)
    for x in range(10):
        ann.draw(black, _point_track(2, float(x)))
    empty = Tracks(ids=np.zeros(0, int), boxes=None, points=np.zeros((0, 2)),
                   scores=np.zeros(0), classes=np.zeros(0))
    for _ in range(5):  # unseen for longer than the trail: forgotten
        ann.draw(black, empty)
    out = ann.draw(black, _point_track(2, 60.0))
    assert not out[60, :50].any()  # no line back to x 9
    with pytest.raises(ValueError, match="trail must be a number of frames >= 0; got -1"):
        Annotator(trail=-1)


def test_a_long_trail_holds_what_it_was_given_and_trail_can_change():
    """A trail of 100 is its last 100 centres past the ring's first sizes (it starts small and
    grows as the trail does, so that a long trail asked for costs memory only as it fills);
    ``trail`` changed between frames applies to every trail from the next frame: each keeps
    its last centres up to the new length (it failed with an IndexError)."""
    import cv2

    black = np.zeros((200, 400, 3), np.uint8)
    path = [(5.0 + 3 * k, 100.0 + (20 if k % 2 else -20) + 0.3 * k) for k in range(120)]
    colour = id_colour(4)

    def want(points):
        out = black.copy()
        pts = np.round(np.array(points)).astype(np.int32)
        cv2.polylines(out, [pts.reshape(-1, 1, 2)], False, colour, 2, cv2.LINE_AA)
        cv2.circle(out, tuple(int(v) for v in pts[-1]), 3, colour, -1)
        return out

    ann = Annotator(trail=100, labels=False)
    for k, (x, y) in enumerate(path):
        out = ann.draw(black, _point_track(4, x, y))
        if k + 1 in (31, 33, 64, 65, 99, 100, 101, 120):
            np.testing.assert_array_equal(out, want(path[max(0, k - 99):k + 1]), err_msg=k)
    assert ann._buf.shape[1] == 200  # (the ring reached the trail: 2 x 100 centres a slot)
    ann = Annotator(trail=5, labels=False)
    for x, y in path[:10]:
        ann.draw(black, _point_track(4, x, y))
    ann.trail = 20  # the 5 centres kept, then up to 20
    for k in range(10, 30):
        out = ann.draw(black, _point_track(4, *path[k]))
        np.testing.assert_array_equal(out, want(path[max(5, k - 19):k + 1]), err_msg=k)
    ann.trail = 3
    out = ann.draw(black, _point_track(4, *path[30]))
    np.testing.assert_array_equal(out, want(path[28:31]))
    ann.trail = -2
    with pytest.raises(ValueError, match="trail must be a number of frames >= 0; got -2"):
        ann.draw(black, _point_track(4, *path[31]))


def test_labels_and_lines_grow_with_a_large_image():
    """On a 4K frame (2880 rows: 4 times 720) the frame label, the identity's number and the
    box's line are 4 times as large as on a PAL frame (576 rows); before, they kept their PAL
    size and were hard to read on a 4000x3000 image."""

    def extents(h, w, scale):
        tracks = Tracks(ids=np.array([7]), boxes=np.array([[w / 2, h / 2, w / 2 + 60 * scale,
                                                            h / 2 + 150 * scale]]),
                        points=None, scores=np.ones(1), classes=np.zeros(1))
        out = Annotator().draw(np.full((h, w, 3), 128, np.uint8), tracks, label="frame 101")
        dark = np.flatnonzero((out[:, 6 * scale] == 0).all(axis=1))  # the label's black box
        row = out[h // 2 + 75 * scale, w // 2 - 20 * scale: w // 2 + 20 * scale]
        line = int((row != 128).any(axis=1).sum())  # the box's left side, across
        number = np.flatnonzero((out[: h // 2, w // 2: w // 2 + 60 * scale] != 128).any(axis=2)
                                .any(axis=1))  # the identity's number, above the box
        return dark.max() - dark.min() + 1, line, number.max() - number.min() + 1

    (label, line, number), (label4, line4, number4) = extents(576, 768, 1), extents(2880, 3840, 4)
    assert 3.4 <= label4 / label <= 4.6 and 3.4 <= number4 / number <= 4.6
    # a line of thickness t covers t + 1 pixels across: 2 -> 3, 8 -> 9
    assert (line, line4) == (3, 9)


def test_an_identity_is_numbered_inside_the_image_and_off_the_frame_label():
    """A box reaching past the image's top-left corner: its number was drawn at the box's
    left edge, off the image (a sliver of it showed); now whole, inside the image, at the
    box's top. Under the frame's label, a box's number went over the label; now below it."""
    import cv2

    grey = np.full((120, 160, 3), 128, np.uint8)

    def draw(box, label=None):
        t = Tracks(ids=np.array([5]), boxes=np.array([box], float), points=None,
                   scores=np.ones(1), classes=np.zeros(1))
        return Annotator().draw(grey, t, label=label)

    # the box's own lines lie off the image but for its right and bottom sides, far away:
    # what is drawn in the corner is the number (its colour, and its black outline)
    out = draw([-15, -10, 120, 100])
    corner = out[:25, :25]
    assert (corner == id_colour(5)).all(axis=2).any() and (corner < 40).all(axis=2).any()
    # a box just below the label: its number, above it, went over the label; now the rows
    # of the label are as drawn without the track, and the number is inside the box
    _, base = cv2.getTextSize("frame 2", cv2.FONT_HERSHEY_SIMPLEX, 0.6, 1)
    bottom = 22 + base + 2  # the label's black box ends here
    empty = Tracks(ids=np.zeros(0, int), boxes=np.zeros((0, 4)), points=None,
                   scores=np.zeros(0), classes=np.zeros(0))
    alone = Annotator().draw(grey, empty, label="frame 2")
    out = draw([6, bottom + 3, 60, 100], label="frame 2")
    np.testing.assert_array_equal(out[:bottom + 1], alone[:bottom + 1])
    assert (out[bottom + 5:bottom + 30, 8:30] == id_colour(5)).all(axis=2).any()
    # a point's number there was drawn under the label, hidden but for a sliver: now
    # below it, as a box's; the label's rows as drawn without the track, but for the dot
    dot = Tracks(ids=np.array([7]), boxes=None, points=np.array([[30.0, bottom + 2]]),
                 scores=np.ones(1), classes=np.zeros(1))
    out = Annotator().draw(grey, dot, label="frame 2")
    differ = (out[:bottom + 1] != alone[:bottom + 1]).any(axis=2)
    assert not differ[:, 40:].any()  # (the number's columns, right of the dot)
    assert (out[bottom + 1:bottom + 30, 34:60] == id_colour(7)).all(axis=2).any()


def test_tracks_drawn_over_the_frame_label_leave_its_text_whole():
    """The frame label was drawn first and a crowd's points and trails over it ("frame 26"
    read "frame 2o"); its box still goes under the tracks, its text over them now. Oracle:
    the label's white strokes as drawn with no track."""
    import cv2

    grey = np.full((120, 160, 3), 128, np.uint8)
    empty = Tracks(ids=np.zeros(0, int), boxes=np.zeros((0, 4)), points=None,
                   scores=np.zeros(0), classes=np.zeros(0))
    alone = Annotator().draw(grey, empty, label="frame 26")
    (w, h), base = cv2.getTextSize("frame 26", cv2.FONT_HERSHEY_SIMPLEX, 0.6, 1)
    strokes = (alone[22 - h:22 + base, 8:8 + w] > 200).all(axis=2)
    assert strokes.sum() > 50
    # points along the label's row, and a box whose side crosses it
    xs = np.arange(4, 8 + w, 6.0)
    points = Tracks(ids=np.arange(1, len(xs) + 1), boxes=None,
                    points=np.c_[xs, np.full(len(xs), 18.0)], scores=np.ones(len(xs)),
                    classes=np.zeros(len(xs)))
    boxed = Tracks(ids=np.array([3]), boxes=np.array([[20.0, -5, 60, 80]]), points=None,
                   scores=np.ones(1), classes=np.zeros(1))
    for tracks in (points, boxed):
        out = Annotator(labels=False).draw(grey, tracks, label="frame 26")
        text = out[22 - h:22 + base, 8:8 + w]
        assert (text[strokes] > 200).all()
        assert (out != alone).any(axis=2)[:22 + base, :8 + w].any()  # the tracks are drawn


def test_boxes_not_finite_are_left_out_and_far_ones_drawn_as_near_ones():
    """A NaN or infinite box made OpenCV fail ("Can't parse 'pt1'"), and the annotated video
    with it; so did one beyond OpenCV's integers (x = -3e9). The first are left out (the
    frame as without them), the last drawn as the same box reaching just off the image."""
    def draw(*boxes):
        b = np.array(boxes, float)
        t = Tracks(ids=np.arange(1, len(b) + 1), boxes=b, points=None, scores=np.ones(len(b)),
                   classes=np.zeros(len(b)))
        return Annotator().draw(np.zeros((60, 80, 3), np.uint8), t)

    fine = [20.0, 10, 50, 40]
    alone = draw(fine)
    for bad in ([np.nan, 1, 5, 5], [0, 0, np.inf, 5]):
        # the bad box is track 1 and the fine one track 2: drawn as track 2 alone would be
        t = Tracks(ids=np.array([1, 2]), boxes=np.array([bad, fine]), points=None,
                   scores=np.ones(2), classes=np.zeros(2))
        want = Annotator().draw(np.zeros((60, 80, 3), np.uint8),
                                Tracks(ids=np.array([2]), boxes=np.array([fine]), points=None,
                                       scores=np.ones(1), classes=np.zeros(1)))
        assert (Annotator().draw(np.zeros((60, 80, 3), np.uint8), t) == want).all()
    assert alone.any()
    np.testing.assert_array_equal(draw([-3e9, 10, 40, 30]), draw([-100, 10, 40, 30]))


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
    for name in ("hota_alpha.png", "timeline_S0.png", "timeline_S1.png"):
        assert (tmp_path / "plots" / name).read_bytes()[:4] == b"\x89PNG"
    capsys.readouterr()
    assert main(args) == 2 and "--force" in capsys.readouterr().err
    assert main(args + ["--force"]) == 0
    # past 20 sequences (a whole MOT17 training split) the legend was left out, without a
    # word: it says now what the thin lines are, and which is COMBINED
    many = {f"S{k:02d}": res["S0"] for k in range(21)} | {"COMBINED": res["COMBINED"]}
    legend = plot_hota_alpha(many).axes[-1].get_legend()
    assert [t.get_text() for t in legend.get_texts()] == ["21 sequences (named up to 20)",
                                                          "COMBINED"]
    # 20 and COMBINED: COMBINED was counted among the 20, and none was named ("20
    # sequences (named up to 20)")
    twenty = {f"S{k:02d}": res["S0"] for k in range(20)} | {"COMBINED": res["COMBINED"]}
    legend = plot_hota_alpha(twenty).axes[-1].get_legend()
    assert [t.get_text() for t in legend.get_texts()] == [*list(twenty)]
    # the first ten curves are of ten hues, not pairs told apart by lightness alone (the
    # first two were dark and light blue, 9 degrees apart): hues read back from the lines
    # (matplotlib's HSV), neighbours of colour (not grey) at least 30 degrees apart
    from matplotlib.colors import rgb_to_hsv

    hsv = [rgb_to_hsv(np.array(line.get_color()[:3]))
           for line in plot_hota_alpha(twenty).axes[0].lines[:10]]
    for (h1, s1, _), (h2, s2, _) in zip(hsv, hsv[1:]):
        if min(s1, s2) > 0.2:
            assert min(abs(h1 - h2), 1 - abs(h1 - h2)) >= 30 / 360
    # a sequence named with a leading "_" is named too (matplotlib leaves such labels out of
    # a legend it collects: a curve was drawn without its name)
    legend = plot_hota_alpha({"_night": res["S0"], "day": res["S1"],
                              "COMBINED": res["COMBINED"]}).axes[-1].get_legend()
    assert [t.get_text() for t in legend.get_texts()] == ["_night", "day", "COMBINED"]


def test_the_timeline_draws_each_objects_matches(tmp_path):
    from vistrack.evaluation import clear_matches, evaluate_mot
    from vistrack.io import MOTTable
    from vistrack.viz import id_colour, plot_timeline

    # object 1 covered by track 7 for frames 1-3, missed at 4, by track 8 at 5-6 (a switch);
    # object 2 appears at frame 3, covered by track 9 throughout
    rows = [(f, 1, 10 * f, 0, 10, 10) for f in range(1, 7)]
    rows += [(f, 2, 200, 50, 10, 10) for f in range(3, 7)]
    gt = MOTTable.from_rows(rows)
    pred = MOTTable.from_rows([(f, 7 if f < 4 else 8, 10 * f, 0, 10, 10)
                               for f in (1, 2, 3, 5, 6)]
                              + [(f, 9, 200, 50, 10, 10) for f in range(3, 7)])
    m = clear_matches(gt, pred)
    assert m.gt_ids.tolist() == [1, 1, 1, 2, 1, 2, 1, 2, 1, 2]
    assert m.pred_ids.tolist() == [7, 7, 7, 9, -1, 9, 8, 9, 8, 9]
    assert m.switches.tolist() == [False] * 6 + [True] + [False] * 3
    c = evaluate_mot(gt, pred)
    assert (c.TP, c.FN, c.IDSW) == (9, 1, 1)
    ax = plot_timeline(m, tmp_path / "t.png", title="S").axes[0]
    assert ax.get_title() == "S: 2 objects, 1 identity switch"
    runs = ax.collections[0]
    # object 1: 7 over frames 1-3, missed at 4, 8 over 5-6; object 2: 9 over 3-6
    spans = sorted((round(p.vertices[:, 1].mean()), p.vertices[0, 0], p.vertices[1, 0])
                   for p in runs.get_paths())
    assert spans == [(0, 0.5, 3.5), (0, 3.5, 4.5), (0, 4.5, 6.5), (1, 2.5, 6.5)]
    colours = {(round(p.vertices[:, 1].mean()), p.vertices[0, 0]): tuple(c[:3])
               for p, c in zip(runs.get_paths(), runs.get_facecolors())}
    b, g, r = id_colour(8)
    assert np.allclose(colours[(0, 4.5)], (r / 255, g / 255, b / 255))
    assert np.allclose(colours[(0, 3.5)], (0.85, 0.85, 0.85))  # missed
    marks = ax.collections[1].get_offsets()
    assert marks.tolist() == [[5.0, 0.0]]  # the switch, on object 1's row
    assert (tmp_path / "t.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("pid", [-1, -5])
def test_a_track_numbered_minus_one_or_below_is_drawn_as_matched(tmp_path, pid):
    """A results file whose track is numbered -1 (or -5) scores it as any track (TP 3), but
    ``clear_matches`` gave -1 for it, read as a miss, and ``vistrack eval --plots`` drew the
    whole object light grey, "missed". ``Matches.matched`` tells them apart; the timeline
    draws the track's colour, and a miss beside it in grey."""
    from vistrack.evaluation import clear_matches, evaluate_mot
    from vistrack.io import MOTTable
    from vistrack.viz import id_colour, plot_timeline

    gt = MOTTable.from_rows([(f, 1, 10 * f, 0, 30, 40) for f in (1, 2, 3, 4)])
    pred = MOTTable.from_rows([(f, pid, 10 * f, 0, 30, 40) for f in (1, 2, 3)])
    c, m = evaluate_mot(gt, pred), clear_matches(gt, pred)
    assert (c.TP, c.FN) == (3, 1)
    assert m.matched.tolist() == [True, True, True, False]
    assert m.pred_ids[m.matched].tolist() == [pid] * 3
    runs = plot_timeline(m).axes[0].collections[0]
    b, g, r = id_colour(pid)
    assert np.allclose(runs.get_facecolors()[:, :3], [(r / 255, g / 255, b / 255),
                                                      (0.85, 0.85, 0.85)])
    assert [p.vertices[0, 0] for p in runs.get_paths()] == [0.5, 3.5]


@pytest.mark.parametrize("field, value", [
    ("matched", np.array([True, False])), ("switches", np.zeros(4, bool)),
    ("pred_ids", np.array([[7], [8], [8]])), ("frames", np.array(1))])
def test_matches_built_by_hand_with_fields_of_other_lengths_are_named(field, value):
    """A ``Matches`` built by hand with ``matched`` of the wrong length failed later, in the
    timeline, with numpy's IndexError; each field is checked against ``frames`` as it is
    made."""
    from vistrack.evaluation import Matches

    fields = dict(frames=np.array([1, 2, 3]), gt_ids=np.array([5, 5, 5]),
                  pred_ids=np.array([7, 8, 8]), switches=np.array([False, True, False]),
                  matched=np.array([True, True, True]))
    Matches(**fields)  # the same fields, each of length 3: accepted
    fields[field] = value
    with pytest.raises(ValueError, match=rf"Matches\.{field} must have shape \(N,\)"):
        Matches(**fields)


def test_the_timeline_of_a_ground_truth_with_nothing_to_score(tmp_path):
    """Ground truth with no box to score (empty, all ignored, or starting after the frames
    tracked): `vistrack eval --plots` and `track --report` failed in the timeline with an
    IndexError; it is drawn empty."""
    from vistrack.evaluation import clear_matches
    from vistrack.io import MOTTable
    from vistrack.viz import plot_timeline

    pred = MOTTable.from_rows([(1, 7, 0, 0, 10, 10)])
    m = clear_matches(MOTTable.from_rows([]), pred)
    assert len(m.frames) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # matplotlib's singular limits among them
        fig = plot_timeline(m, tmp_path / "t.png", title="S")
    assert (tmp_path / "t.png").stat().st_size > 0
    assert fig.axes[0].get_title() == "S: 0 objects, 0 identity switches"
    assert len(fig.axes[0].collections[0].get_paths()) == 0
    # no frame ticks (the frame locator put -0.04 to 0.04 back over set_xticks([])), and the
    # y label inside the figure (it was cut to "ground-truth objec" at 176 pixels high)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == []
    span = ax.yaxis.label.get_window_extent(fig.canvas.get_renderer())
    assert 0 <= span.y0 and span.y1 <= fig.bbox.height


def test_names_are_drawn_as_written_and_whole_frames_counted(tmp_path):
    """A sequence or video named with ``$`` was read by matplotlib as mathematics: ``a$b$c``
    titled with an italic b, and ``p$^$q`` failed to draw (``vistrack track`` and ``eval
    --plots`` then exited 2, with no plot, run.json or score table); a long name pushed the
    title's counts and the legend out of the figure; a score of 0 or 100 lay hidden under
    the axes' frame; a short timeline's frames were ticked 0.25, 0.5, ..."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from vistrack.evaluation import clear_matches, evaluate_mot
    from vistrack.io import MOTTable
    from vistrack.viz import plot_hota_alpha, plot_timeline
    from vistrack.viz.plots import TrajectoryPlot

    gt = MOTTable.from_rows([(1, 1, 0, 0, 10, 10), (2, 1, 1, 0, 10, 10)])
    m = clear_matches(gt, gt)
    for name in ("a$b$c", "p$^$q"):
        fig = plot_timeline(m, tmp_path / "t.png", title=name)
        title = fig.axes[0].title
        FigureCanvasAgg(fig).draw()
        # drawn as written: the text matplotlib lays out is the name, not mathematics
        assert title._preprocess_math(title.get_text()) == (
            f"{name}: 1 object, 0 identity switches", False)
    long = "L" * 120
    fig = plot_timeline(m, title=long)
    assert fig.axes[0].get_title() == "L" * 29 + "…" + "L" * 30 + ": 1 object, 0 identity switches"
    FigureCanvasAgg(fig).draw()
    bbox = fig.axes[0].title.get_window_extent()
    assert bbox.x0 >= 0 and bbox.x1 <= fig.bbox.x1  # the counts inside the figure
    ticks = fig.axes[0].get_xticks()
    assert np.array_equal(ticks, np.round(ticks))  # frames are whole
    res = {long: evaluate_mot(gt, gt), "COMBINED": evaluate_mot(gt, gt)}
    fig = plot_hota_alpha(res, tmp_path / "h.png")
    assert all(not line.get_clip_on() for ax in fig.axes for line in ax.lines)  # 100 shown
    legend = fig.axes[-1].get_legend()
    FigureCanvasAgg(fig).draw()
    assert legend.get_window_extent().x1 <= fig.bbox.x1
    assert not legend.get_window_extent().overlaps(fig.axes[-1].get_window_extent())
    plot = TrajectoryPlot(tmp_path / "p.png", "p$^$q.mp4")
    plot.write(Frame(1, 0.0), Tracks(ids=np.array([1]), boxes=np.array([[0, 0, 4, 4.0]]),
                                     points=None, scores=np.ones(1), classes=np.zeros(1)))
    plot.close()
    assert (tmp_path / "p.png").stat().st_size > 0
    assert matplotlib.rcParams["text.usetex"] is False


def _points(n, rng, h, w):
    return Tracks(ids=np.arange(1, n + 1), boxes=None,
                  points=np.c_[rng.uniform(0, w - 1, n), rng.uniform(0, h - 1, n)],
                  scores=np.ones(n), classes=np.zeros(n))


def test_identity_numbers_are_left_out_where_they_would_hide_the_frame():
    """Hundreds of particles in a microscope's frame (500 on 640x424, as in trackpy's
    bulk-water clip): their numbers covered most of the image. By default a frame's numbers
    are drawn only where they cover at most a tenth of it; ``labels`` forces either way."""
    rng = np.random.default_rng(3)
    grey = np.full((424, 640, 3), 128, np.uint8)
    dense = _points(500, rng, 424, 640)
    auto = Annotator().draw(grey, dense)
    plain = Annotator(labels=False).draw(grey, dense)
    numbered = Annotator(labels=True).draw(grey, dense)
    np.testing.assert_array_equal(auto, plain)
    # the numbers, forced, change much of the frame: that is what the default spares
    assert (numbered != plain).any(axis=2).mean() > 0.1
    # the dots are drawn either way: a point no other comes near (another's dot, of radius
    # 3, could cover it) has its track's colour
    d = np.hypot(*(dense.points[:, None] - dense.points[None]).transpose(2, 0, 1))
    alone = np.sort(d, axis=1)[:, 1] > 8
    assert alone.sum() > 100
    for i, (x, y) in zip(dense.ids[alone], dense.points[alone]):
        assert (plain[int(round(y)), int(round(x))] == id_colour(i)).all()
    sparse = _points(8, rng, 576, 768)  # PETS09's people: numbered, as before
    pal = np.full((576, 768, 3), 128, np.uint8)
    with_numbers = Annotator(labels=True).draw(pal, sparse)
    np.testing.assert_array_equal(Annotator().draw(pal, sparse), with_numbers)
    assert (with_numbers != Annotator(labels=False).draw(pal, sparse)).any()


def test_identity_numbers_left_out_come_back_only_well_below_the_line():
    """Near the line, frame by frame the count of tracks crosses it: the numbers came and
    went. Once left out (the numbers would cover more than a tenth of the frame), they
    come back only where they would cover a twentieth or less."""
    rng = np.random.default_rng(8)
    grey = np.full((424, 640, 3), 128, np.uint8)
    sizes = [20, 100, 50, 100, 50, 20, 50]  # tracks a frame: numbers over 3 %, 15 %, 7 %

    def numbered(ann, n):
        t = _points(n, rng, 424, 640)
        return not np.array_equal(ann.draw(grey, t), Annotator(labels=False).draw(grey, t))

    ann = Annotator(trail=1)
    got = [numbered(ann, n) for n in sizes]
    # 50 tracks' numbers cover less than a tenth, more than a twentieth: drawn only while
    # they were drawn in the frame before
    fresh = Annotator(trail=1)
    assert numbered(fresh, 50)
    assert got == [True, False, False, False, False, True, True]


def test_each_tracks_ellipse_is_its_covariances_closed_form():
    """The 2-sigma ellipse of a covariance ``R(θ) diag(a², b²) R(θ)'`` has semi-axes 2a and
    2b along θ: every pixel drawn away from a track's dot lies on that curve (within a
    pixel), for three tracks of one frame at other angles and sizes; a track whose
    covariance is not finite gets its dot and no ellipse."""
    specs = [(1, (80.0, 60.0), 10.0, 3.0, 30.0), (2, (200.0, 60.0), 6.0, 6.0, 0.0),
             (3, (80.0, 150.0), 12.0, 2.0, -65.0)]
    covs, points = [], []
    for _, centre, a, b, deg in specs:
        t = np.radians(deg)
        rot = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
        covs.append(rot @ np.diag([a * a, b * b]) @ rot.T)
        points.append(centre)
    covs.append(np.full((2, 2), np.nan))
    points.append((200.0, 150.0))
    tracks = Tracks(ids=np.array([1, 2, 3, 4]), boxes=None, points=np.array(points),
                    scores=np.ones(4), classes=np.zeros(4), covs=np.array(covs))
    out = Annotator(labels=False).draw(np.zeros((220, 280, 3), np.uint8), tracks)
    ys, xs = np.mgrid[0:220, 0:280]
    # each track's quarter of the image; the ellipses are drawn anti-aliased, so a pixel of
    # the curve is one at half its colour's brightness or more
    bright = out.max(axis=2).astype(float)
    for i, (cx, cy), a, b, deg in specs:
        near = (np.abs(xs - cx) < 70) & (np.abs(ys - cy) < 45)
        mine = near & (bright >= max(id_colour(i)) / 2) & (np.hypot(xs - cx, ys - cy) > 4)
        t = np.radians(deg)
        u = (xs - cx) * np.cos(t) + (ys - cy) * np.sin(t)
        v = -(xs - cx) * np.sin(t) + (ys - cy) * np.cos(t)
        # the distance from the ellipse along the normal, about |F| / |grad F| for
        # F = u² / A² + v² / B² - 1
        A, B = 2 * a, 2 * b
        f = u ** 2 / A ** 2 + v ** 2 / B ** 2 - 1
        grad = 2 * np.hypot(u / A ** 2, v / B ** 2)
        assert mine.sum() > 2 * (A + B)  # drawn all round
        assert (np.abs(f[mine]) / grad[mine]).max() < 1.0
    lone = (np.abs(xs - 200) < 70) & (np.abs(ys - 150) < 45) & (bright > 0)
    assert lone.sum() > 0 and (np.hypot(xs[lone] - 200, ys[lone] - 150) <= 4).all()


def test_a_box_or_point_wholly_off_the_image_has_no_number():
    """The number of a box wholly past an edge was pulled inside, and stood at the edge over
    nothing: such boxes and points are now drawn as without their number (the frame as with
    the on-image tracks alone), while one partly inside keeps its number."""
    img = np.full((120, 160, 3), 90, np.uint8)

    def draw(ids, boxes=None, points=None):
        n = len(ids)
        t = Tracks(ids=np.array(ids), boxes=None if boxes is None else np.array(boxes, float),
                   points=None if points is None else np.array(points, float),
                   scores=np.ones(n), classes=np.zeros(n))
        return Annotator().draw(img, t)

    inside = [[40, 40, 70, 80]]
    for off in ([200, 30, 240, 60], [20, -80, 50, -20], [-60, 50, -10, 90], [30, 130, 60, 170]):
        np.testing.assert_array_equal(draw([1, 2], inside + [off]), draw([1], inside))
    for off in ([175.0, 50.0], [-10.0, 50.0], [60.0, 130.0]):  # (its dot, too, off it)
        np.testing.assert_array_equal(draw([1, 2], points=[[50.0, 50.0], off]),
                                      draw([1], points=[[50.0, 50.0]]))
    # a box whose right edge is drawn in column 0 is on the image: numbered
    edge = draw([1, 2], inside + [[-30, 50, 0, 90]])
    assert not (edge == draw([1], inside)).all()
    part = draw([1, 2], inside + [[-30, 50, 20, 90]])
    assert not (part == draw([1, 2], inside + [[-30, 50, 0, 90]])).all()  # its number there
    assert (part[:, :25] == id_colour(2)).all(axis=2).any()


def test_an_annotated_frame_of_another_size_is_named_by_its_own_number(tmp_path):
    """The writer counted the frames it had written: frame 103 of another size was called
    "frame 3"; the video's own label says "frame 103"."""
    from vistrack.viz.annotate import AnnotatedVideo

    v = AnnotatedVideo(tmp_path / "a.mp4", fps=10)
    for k in (101, 102):
        v.write(Frame(k, 0.0, np.zeros((48, 64, 3), np.uint8)), Tracks.empty())
    with pytest.raises(ValueError, match=re.escape(
            f"{tmp_path / 'a.mp4'}: frame 103 is 64x50; the video is 64x48")):
        v.write(Frame(103, 0.0, np.zeros((50, 64, 3), np.uint8)), Tracks.empty())
    v.abort()


def test_the_trajectory_plot_names_what_it_cannot_show(tmp_path):
    """A track whose last centre was NaN lost its end dot and label (a track of one finite
    centre vanished, still counted in the title); a third centre beside two frames was
    dropped; one centre at x = 1e5 made the frame a strip; a uint16 RGB background of 300
    wrapped to 44 where matplotlib clips it to 255. Oracle: the finite rows' own plot, the
    image's extent, matplotlib's clipping."""
    from vistrack.viz import plot_trajectories

    fr, ids = [1, 2, 3, 1, 2, 3], [1, 1, 1, 2, 2, 2]
    c = [[10, 10], [20, 20], [30, 30], [40, 40], [60, 50], [np.nan, np.nan]]
    with pytest.warns(RuntimeWarning, match=re.escape(
            "1 of the 6 centres are not finite (NaN or infinite boxes): left out of the plot")):
        fig = plot_trajectories(fr, ids, c, path=tmp_path / "a.png")
    dots = fig.axes[0].collections[1].get_offsets().tolist()
    assert dots == [[30.0, 30.0], [60.0, 50.0]]
    assert [t.get_text() for t in fig.axes[0].texts] == ["1", "2"]
    with pytest.raises(ValueError, match=re.escape(
            "frames, ids and centres must be one row each, centres (N, 2); got 2 frames, 2 "
            "ids and centres of shape (3, 2)")):
        plot_trajectories([1, 2], [1, 1], [[0, 0], [1, 1], [2, 2]])
    bg = np.zeros((576, 768, 3), np.uint8)
    with pytest.warns(RuntimeWarning, match=re.escape(
            "1 of the 4 centres lie more than the image's size (768 x 576) outside it")):
        fig = plot_trajectories([1, 2, 1, 2], [1, 1, 2, 2],
                                [[100, 100], [120, 110], [300, 300], [1e5, 300]], bg,
                                tmp_path / "b.png")
    assert fig.axes[0].get_xlim() == (-0.5, 767.5)
    assert fig.axes[0].get_ylim() == (575.5, -0.5)
    fig = plot_trajectories([1, 2], [1, 1], [[-50, 10], [100, 700]], bg, tmp_path / "c.png")
    assert fig.axes[0].get_xlim() == (-50, 767.5) and fig.axes[0].get_ylim() == (700, -0.5)
    import matplotlib.image

    plot_trajectories([1, 2], [1, 1], [[10, 10], [20, 20]], np.full((40, 60, 3), 300, np.uint16),
                      tmp_path / "d.png")
    centre = matplotlib.image.imread(tmp_path / "d.png")
    h, w = centre.shape[:2]
    light = centre[h // 2 - 5:h // 2 + 5, w // 2 + 40:w // 2 + 50, :3]
    # 255 under the figure's white at alpha 0.45: white; 44 (wrapped) was a grey of about 160
    assert light.min() > 0.95


def test_no_box_covers_a_number_and_a_narrow_frame_shows_its_label_whole():
    """Each track's box and number were drawn together, so a box drawn later covered an
    earlier track's number (10 of the 22 stroke pixels of "9" took track 19's colour); the
    frame label ran past a narrow frame's edge ("frame 100" read "frame 10" 80 pixels wide);
    a float identity was labelled "3.0". Oracles: the number drawn alone, the label drawn
    on a frame wide enough for it (its ink the same share of its box), and the writers'
    whole numbers."""
    import cv2

    grey = np.full((1400, 1200, 3), 128, np.uint8)  # (large: numbers of thick strokes)

    def tracks(ids, boxes):
        return Tracks(ids=np.array(ids), boxes=np.array(boxes, float), points=None,
                      scores=np.ones(len(ids)), classes=np.zeros(len(ids)))

    nine = [300, 400, 600, 1000]
    alone = Annotator(labels=True).draw(grey, tracks([9], [nine]))
    ink = (alone == id_colour(9)).all(axis=2)
    ink[380:] = False  # (the number above the box; not the box)
    assert ink.sum() > 20
    rows = np.flatnonzero(ink.any(axis=1))
    across = int(rows.mean())  # track 19's top edge through the middle of the number
    both = Annotator(labels=True).draw(grey, tracks([9, 19], [nine, [280, across, 550, 900]]))
    assert (both[ink] == id_colour(9)).all()
    for W, label in ((80, "frame 100"), (64, "frame 7"), (96, "frame 1234")):
        out = Annotator().draw(np.full((60, W, 3), 128, np.uint8), Tracks.empty(), label=label)
        white = (out > 200).all(axis=2)
        cols = np.flatnonzero(white.any(axis=0))
        assert cols.max() < W - 1  # whole: no stroke reaches the edge
        wide = Annotator().draw(np.full((60, 400, 3), 128, np.uint8), Tracks.empty(),
                                label=label)
        (w, h), _ = cv2.getTextSize(label, cv2.FONT_HERSHEY_SIMPLEX, 0.6, 1)
        full = (wide > 200).all(axis=2).sum() / (w * h)
        span = cols.max() - cols.min() + 1
        assert white.sum() / (span * span * h / w) > 0.5 * full  # (its ink, not cut away)
    floats = Annotator(labels=True).draw(grey, tracks([3.0, 12.0], [[20, 30, 50, 80],
                                                                    [70, 30, 100, 80]]))
    ints = Annotator(labels=True).draw(grey, tracks([3, 12], [[20, 30, 50, 80],
                                                              [70, 30, 100, 80]]))
    assert np.array_equal(floats, ints)


def test_float_identities_past_2_53_keep_their_own_labels():
    """From the second reading: float identities were turned to int64 to be labelled as
    whole numbers, and 1e20 became -9223372036854775808 (as did 2**63). Oracle: the
    labels drawn from the floats themselves, as before, where no int64 holds them."""
    grey = np.full((100, 140, 3), 128, np.uint8)

    def draw(ids):
        return Annotator(labels=True).draw(grey, Tracks(
            ids=np.array(ids), boxes=np.array([[20, 30, 50, 80.0], [80, 30, 110, 80]]),
            points=None, scores=np.ones(2), classes=np.zeros(2)))

    assert not np.array_equal(draw([1e20, 3.0]), draw([2.0**63, 3.0]))


def test_hota_alpha_curves_on_the_frame_are_seen():
    """A curve at exactly 100 % (or 0 %) lies on the axes' frame, which was drawn over it:
    a perfect sequence's colour had no pixel inside the panels, only in the legend. Oracle:
    the rendered figure's pixels of the curve's colour inside each panel's box."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import to_rgb

    from vistrack.evaluation.mot import evaluate_mot
    from vistrack.io.motchallenge import MOTTable
    from vistrack.viz import plot_hota_alpha

    gt = MOTTable.from_rows([(1, 1, 0, 0, 10, 20), (2, 1, 1, 0, 10, 20)])
    off = MOTTable.from_rows([(1, 1, 1, 1, 10, 20), (2, 1, 2, 0, 10, 20)])
    fig = plot_hota_alpha({"perfect": evaluate_mot(gt, gt), "other": evaluate_mot(gt, off)})
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    image = np.asarray(canvas.buffer_rgba())[..., :3].astype(int)
    height = image.shape[0]
    for name in ("perfect", "other"):
        line = next(line for line in fig.axes[0].lines if line.get_label() == name)
        colour = np.round(255 * np.array(to_rgb(line.get_color()))).astype(int)
        near = (np.abs(image - colour).max(axis=-1) <= 8)
        for ax in fig.axes:
            box = ax.get_window_extent()
            rows = slice(int(height - box.y1) - 2, int(height - box.y0) + 3)
            cols = slice(int(box.x0) - 2, int(box.x1) + 3)
            assert near[rows, cols].sum() > 50, (name, ax.get_title())

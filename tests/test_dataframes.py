"""Tracks as pandas DataFrames, named as trackpy names particles' columns, and back."""

import importlib.util
import re
import sys

import numpy as np
import pytest

from vistrack.io import read_mot, write_mot
from vistrack.io.motchallenge import MOTTable

pd = pytest.importorskip("pandas")


def _table(tmp_path):
    rng = np.random.default_rng(0)
    frames = np.repeat(np.arange(1, 21), 3)
    ids = np.tile([1, 2, 3], 20)
    keep = ~((ids == 3) & (frames > 4))  # identity 3 lives 4 frames only
    boxes = np.c_[rng.uniform(0, 500, (60, 2)), rng.uniform(5, 50, (60, 2))]
    path = tmp_path / "tracks.txt"
    write_mot(path, frames[keep], ids[keep], boxes[keep], rng.uniform(0, 1, 60)[keep])
    return read_mot(path)


def test_a_table_goes_to_a_dataframe_and_back_unchanged(tmp_path):
    t = _table(tmp_path)
    df = t.to_pandas()
    assert list(df.columns[:4]) == ["frame", "particle", "x", "y"]
    np.testing.assert_array_equal(df["x"], t.boxes[:, 0] + t.boxes[:, 2] / 2)
    back = MOTTable.from_pandas(df)
    for f in ("frames", "ids", "boxes", "conf", "classes", "visibility"):
        np.testing.assert_array_equal(getattr(back, f), getattr(t, f), err_msg=f)


def test_trackpy_reads_vistracks_tracks_as_its_own(tmp_path):
    trackpy = pytest.importorskip("trackpy")
    t = _table(tmp_path)
    df = t.to_pandas()
    # trackpy's filter_stubs keeps particles seen in at least 5 frames: identities 1 and 2
    kept = trackpy.filter_stubs(df, threshold=5)
    assert sorted(set(kept["particle"])) == [1, 2]
    # its drift is the mean displacement of the particles seen in consecutive frames
    drift = trackpy.compute_drift(df[df["particle"] < 3])
    c = t.boxes[:, :2] + t.boxes[:, 2:] / 2

    def at(f, i):
        return c[(t.frames == f) & (t.ids == i)][0]

    steps = [np.mean([at(f + 1, i) - at(f, i) for i in (1, 2)], axis=0) for f in range(1, 20)]
    want = np.cumsum(steps, axis=0)  # frames 2 to 20, against frame 1
    assert drift.index.tolist() == list(range(2, 21))
    np.testing.assert_allclose(drift[["x", "y"]].values, want, atol=1e-9)


def test_other_column_names_and_missing_columns():
    rows = pd.DataFrame({"t": [2, 1], "track": [4, 4], "cx": [15.0, 12.0], "cy": [30.0, 30.0],
                         "w": [10.0, 10.0], "h": [20.0, 20.0]})
    names = {"frame": "t", "particle": "track", "x": "cx", "y": "cy", "bb_width": "w",
             "bb_height": "h"}
    t = MOTTable.from_pandas(rows, columns=names, path="mine.csv")
    assert t.frames.tolist() == [1, 2] and t.boxes[:, 0].tolist() == [7.0, 10.0]
    # the columns named go before those read by their own names, where a file has both: the
    # particle and bb_left, bb_top columns were read over --columns id=..., x=..., y=...
    both = rows.assign(particle=[8, 9], bb_left=[0.0, 0.0], bb_top=[0.0, 0.0])
    named = {"frame": "t", "id": "track", "x": "cx", "y": "cy", "bb_width": "w",
             "bb_height": "h"}
    t = MOTTable.from_pandas(both, columns=named)
    assert t.ids.tolist() == [4, 4] and t.boxes[:, :2].tolist() == [[7.0, 20.0], [10.0, 20.0]]
    corners = pd.DataFrame({"frame": [1], "bb_left": [0.0], "bb_top": [0.0], "x": [0.0],
                            "y": [0.0], "bb_width": [1.0], "bb_height": [1.0], "a": [10.0],
                            "b": [20.0], "c": [30.0], "d": [60.0]})
    t = MOTTable.from_pandas(corners, columns={"x1": "a", "y1": "b", "x2": "c", "y2": "d"})
    assert t.boxes.tolist() == [[10.0, 20.0, 20.0, 40.0]]
    # and without columns, the file's own names in their order, as before
    own = both.rename(columns={"t": "frame", "w": "bb_width", "h": "bb_height"})
    t = MOTTable.from_pandas(own)
    assert t.ids.tolist() == [9, 8] and t.boxes[:, :2].tolist() == [[0.0, 0.0], [0.0, 0.0]]
    assert t.conf.tolist() == [1.0, 1.0]
    no_width = {k: v for k, v in names.items() if k != "bb_width"}
    # the centre with a height and no width: the width is named alone (it was "no box", the
    # columns of the first form listed), and the file's own columns are listed
    with pytest.raises(ValueError, match=re.escape(
            "no column 'bb_width' in mine.csv (x, y are a box's centre with 'bb_width' and 'h', "
            "or a point with neither); columns: ['cx', 'cy', 'h', 't', 'track']")):
        MOTTable.from_pandas(rows.drop(columns="w"), columns=no_width, path="mine.csv")
    # no box in any form: the forms and the file's columns (they were not listed)
    with pytest.raises(ValueError, match=re.escape(
            "or the corners 'x1', 'y1', 'x2', 'y2'); columns: ['h', 't', 'track', 'w'] "
            "(name yours: --columns bb_left=NAME,..., or columns={'bb_left': NAME, ...})")):
        MOTTable.from_pandas(rows.drop(columns=["cx", "cy"]), path="mine.csv",
                             columns={"frame": "t", "particle": "track", "bb_width": "w",
                                      "bb_height": "h"})
    with pytest.raises(ValueError, match=re.escape(
            "no column 'bb_width' in mine.csv; columns: ['h', 'l', 't', 'top', 'track']")):
        MOTTable.from_pandas(rows.drop(columns=["w", "cx"]).rename(columns={"cy": "top"})
                             .assign(l=1.0), path="mine.csv",
                             columns={"frame": "t", "particle": "track", "bb_left": "l",
                                      "bb_top": "top", "bb_height": "h"})
    # a name in columns that is not ours, or not the table's, was ignored: the column then
    # went unread (a class column under a mistyped name: every row class -1)
    with pytest.raises(ValueError, match=re.escape(
            "columns bb_widht=w: 'bb_widht' is not a column vistrack reads (did you mean "
            "'bb_width'?); those are frame, particle, id, bb_left")):
        MOTTable.from_pandas(rows, columns=names | {"bb_widht": "w"}, path="mine.csv")
    with pytest.raises(ValueError, match=re.escape(
            "columns bb_width=w: no column 'w' in mine.csv; columns: ['cx', 'cy', 'h', 't', "
            "'track']")):
        MOTTable.from_pandas(rows.drop(columns="w"), columns=names, path="mine.csv")
    with pytest.raises(ValueError, match=re.escape(
            "no column 'frame' (the frame); columns: ['cx', 'cy', 'h', 't', 'track', 'w'] "
            "(name the frame's column: --columns frame=NAME, or columns={'frame': NAME})")):
        MOTTable.from_pandas(rows)
    # a column named as the frame's in another case is suggested
    with pytest.raises(ValueError, match=re.escape(
            "(did you mean 'Frame'? name the frame's column: --columns frame=NAME")):
        MOTTable.from_pandas(rows.rename(columns={"t": "Frame"}))
    assert len(MOTTable.from_pandas(rows.iloc[:0], columns=names)) == 0


@pytest.mark.parametrize("column, values, message", [
    ("t", [1.5, 2], "row 1 after the header, column 't' (frame): frame must be an integer "
                    ">= 1 (frames count from 1, as MOTChallenge's do); got 1.5"),
    ("t", [1, 0], "row 2 after the header, column 't' (frame): frame must be an integer >= 1"),
    ("track", [4, 4.5], "row 2 after the header, column 'track' (particle): id must be an "
                        "integer; got 4.5"),
    ("w", [10, -1], "row 2 after the header, column 'w' (bb_width): width must be >= 0; got -1"),
    ("h", [np.nan, 20], "row 1 after the header, column 'h' (bb_height): not a finite number: "
                        "nan (an empty cell, or NaN)"),
    ("cx", [1, np.inf], "row 2 after the header, column 'cx' (x): not a finite number: inf"),
    ("score", [0.9, "high"], "row 2 after the header, column 'score' (conf): not a number: "
                             "'high'"),
    ("kind", [1, 2.5], "row 2 after the header, column 'kind' (class): class must be an "
                       "integer; got 2.5"),
])
def test_a_bad_value_is_named_by_row_and_column(column, values, message):
    """What read_mot refuses in a text file, from_pandas refuses in a table (a CSV file of
    detections), naming the row and the column: before, a frame 0 was dropped unseen, a
    negative width or an empty cell stopped the run with a message naming neither. A
    fraction in the class column, read as no class (-1) before, is refused too: in a text
    file the eighth value may be something else (MOT15's world x), in a column named as the
    class it is not."""
    from vistrack.io import MOTFormatError

    rows = pd.DataFrame({"t": [1, 2], "track": [4, 4], "cx": [15.0, 12.0], "cy": [30.0, 30.0],
                         "w": [10.0, 10.0], "h": [20.0, 20.0], "score": [0.9, 0.8],
                         "kind": [1, 1]})
    names = {"frame": "t", "particle": "track", "x": "cx", "y": "cy", "bb_width": "w",
             "bb_height": "h", "conf": "score", "class": "kind"}
    with pytest.raises(MOTFormatError) as e:
        MOTTable.from_pandas(rows.assign(**{column: values}), columns=names, path="mine.csv")
    assert str(e.value).startswith(f"mine.csv, {message}")


def test_a_box_by_its_corners():
    """``x1, y1, x2, y2`` (supervision's and YOLO's ``xyxy``) read as the box ``x1, y1,
    x2 - x1, y2 - y1``; a far corner before the near one is named by row and column."""
    from vistrack.io import MOTFormatError

    rows = pd.DataFrame({"frame": [1, 2], "xmin": [10.0, 12.5], "y1": [20.0, 21.0],
                         "xmax": [30.0, 40.0], "y2": [60.0, 81.0], "conf": [0.9, 0.8]})
    t = MOTTable.from_pandas(rows, columns={"x1": "xmin", "x2": "xmax"})
    assert t.boxes.tolist() == [[10.0, 20.0, 20.0, 40.0], [12.5, 21.0, 27.5, 60.0]]
    assert t.conf.tolist() == [0.9, 0.8]
    with pytest.raises(MOTFormatError) as e:
        MOTTable.from_pandas(rows.assign(y2=[60.0, 20.0]), columns={"x1": "xmin", "x2": "xmax"},
                             path="mine.csv")
    assert str(e.value) == ("mine.csv, row 2 after the header, column 'y2': the box's far "
                            "corner must not lie before its near one; y1 = 21, y2 = 20")
    with pytest.raises(ValueError, match=re.escape(
            "or the corners 'x1', 'y1', 'x2', 'y2'); columns: ['conf', 'frame', 'xmax', "
            "'xmin', 'y1'] (name yours")):
        MOTTable.from_pandas(rows.drop(columns="y2"))


def test_detections_from_a_csv_file_of_corners_and_a_score_of_another_name(tmp_path, capsys):
    """A YOLO-style CSV file (corners, ``confidence``, ``class_id``) tracks as the same
    detections in MOTChallenge's format do; without its score named, the run says that every
    detection scores 1 and which columns it did not read."""
    from tests.test_fit import _sequence
    from vistrack.cli import main

    seq = _sequence(tmp_path / "SIM", np.random.default_rng(3))
    det = read_mot(seq / "det" / "det.txt")
    b = det.boxes
    pd.DataFrame({"frame": det.frames, "x1": b[:, 0], "y1": b[:, 1], "x2": b[:, 0] + b[:, 2],
                  "y2": b[:, 1] + b[:, 3], "confidence": det.conf,
                  "class_id": np.zeros(len(b), int)}).to_csv(tmp_path / "yolo.csv", index=False)
    a, c = tmp_path / "a.txt", tmp_path / "c.txt"
    assert main(["track", str(seq), "--out", str(a), "--quiet"]) == 0
    assert main(["track", str(seq), "--out", str(c), "--detections", str(tmp_path / "yolo.csv"),
                 "--columns", "conf=confidence", "--quiet"]) == 0
    ta, tc = read_mot(a), read_mot(c)
    assert (ta.ids == tc.ids).all() and np.allclose(ta.boxes, tc.boxes, atol=0.011)
    capsys.readouterr()
    assert main(["track", str(seq), "--out", str(c), "--force", "--detections",
                 str(tmp_path / "yolo.csv"), "--quiet"]) == 0
    assert (f"vistrack track: warning: {tmp_path / 'yolo.csv'}: no column 'conf': every "
            "detection scores 1 (columns not read: confidence, class_id; name the score's "
            "column: --columns conf=NAME, or columns={'conf': NAME})") in capsys.readouterr().err


def test_detections_from_a_csv_file_with_its_own_column_names(tmp_path, capsys):
    from tests.test_fit import _sequence
    from vistrack.cli import main

    seq = _sequence(tmp_path / "SIM", np.random.default_rng(3))
    det = read_mot(seq / "det" / "det.txt")
    b = det.boxes
    pd.DataFrame({"t": det.frames, "cx": b[:, 0] + b[:, 2] / 2, "cy": b[:, 1] + b[:, 3] / 2,
                  "w": b[:, 2], "h": b[:, 3], "score": det.conf}).to_csv(
        tmp_path / "dets.csv", index=False)
    a, c = tmp_path / "a.txt", tmp_path / "c.txt"
    assert main(["track", str(seq), "--out", str(a), "--quiet"]) == 0
    assert main(["track", str(seq), "--out", str(c), "--detections", str(tmp_path / "dets.csv"),
                 "--columns", "frame=t,x=cx,y=cy,bb_width=w,bb_height=h,conf=score",
                 "--quiet"]) == 0
    ta, tc = read_mot(a), read_mot(c)
    assert (ta.ids == tc.ids).all() and np.allclose(ta.boxes, tc.boxes, atol=0.011)
    capsys.readouterr()
    # column names go with a CSV file only
    assert main(["track", str(seq), "--out", str(c), "--force", "--columns", "frame=t",
                 "--quiet"]) == 2
    assert "columns name a CSV file's columns" in capsys.readouterr().err
    assert main(["track", str(seq), "--out", str(c), "--force", "--detections",
                 str(tmp_path / "dets.csv"), "--columns", "frame", "--quiet"]) == 2
    assert "OURS=THEIRS" in capsys.readouterr().err
    # a CSV file counting frames from 0: refused, naming the row (its rows of frame 0 were
    # left out unseen before)
    zero = tmp_path / "zero.csv"
    zero.write_text("frame,bb_left,bb_top,bb_width,bb_height,conf\n0,10,10,20,20,0.9\n"
                    "1,11,10,20,20,0.9\n")
    assert main(["track", str(zero), "--out", str(tmp_path / "z.txt"), "--fps", "10",
                 "--quiet"]) == 2
    assert capsys.readouterr().err.strip() == (
        f"vistrack track: error: {zero}, line 2, column 'frame': frame must "
        "be an integer >= 1 (frames count from 1, as MOTChallenge's do); got 0")
    assert not (tmp_path / "z.txt").exists()


def test_a_csv_file_pandas_cannot_read_is_named(tmp_path):
    """pandas' own errors (a row of more values than the header) came out
    without the file's name: ``Error tokenizing data. C error: Expected 5 fields in line 3,
    saw 6``. A row of more values, or of fewer (which pandas fills with NaN, then named as
    an empty cell of another column), is named by its line and its count against the
    header's, blank lines counted as the file's lines."""
    from vistrack.io.motchallenge import MOTFormatError
    from vistrack.pipeline import track_sequence

    path = tmp_path / "dets.csv"
    head = "frame,bb_left,bb_top,bb_width,bb_height"
    for text, message in [
        (f"{head}\n1,2,3,4,5\n1,2,3,4,5,6\n", ", line 3: 6 values where the header has 5"),
        (f"{head}\n1,2,3,4,5\n\n2,2,3\n", ", line 4: 3 values where the header has 5"),
        # every row one value longer than the header: pandas takes the first column for the
        # index and reads the rest shifted by one column, no value missing (it was tracked
        # so, frame 100 at left 200, and nothing said)
        (f"{head},conf\n1,100,200,50,120,0.9,1\n2,102,200,50,120,0.9,1\n",
         ", line 2: 7 values where the header has 6"),
        # the same where the first values count 0, 1, 2, ...: pandas' index is then a
        # range, like its own, and the rows were read shifted without a word (frames 1, 2,
        # 3 from the second column)
        (f"{head},conf\n0,1,100,200,50,120,0.9\n1,2,102,200,50,120,0.9\n"
         "2,3,104,200,50,120,0.9\n", ", line 2: 7 values where the header has 6"),
        # a column named twice in the header: pandas read the second as 'conf.1', which
        # nothing read, without a word
        (f"{head},conf,conf\n1,1,2,3,4,0.9,0.1\n",
         ", line 1: the header names column 'conf' twice; name each column once"),
        # a blank line before the header (pandas skips it): a short row was named as an
        # empty cell of another column, "row 1 after the header"
        (f"\n{head}\n2,2,3\n", ", line 3: 3 values where the header has 5"),
        # an empty cell in a row of the header's length is named by its column and its line
        # (blank lines, lines of spaces and a quoted value's line break counted as the
        # file's lines; it was "row 2 after the header", two lines off here)
        (f"{head},note\n1,2,3,4,5,\"two\nlines\"\n  \n\n2,2,,4,5,x\n",
         ", line 6, column 'bb_top': not a finite number: nan"),
        # a line of spaces is skipped by the row check as pandas skips it, not a row of one
        # value
        (f"{head}\n1,2,3,4,5\n   \n2,2,3\n", ", line 4: 3 values where the header has 5"),
        # a line of a quoted empty value, or of a no-break space, is a row of one value to
        # pandas, not a blank line (it was skipped, and the next row named instead)
        (f"{head}\n1,2,3,4,5\n\"\"\n2,2,3,4,5\n", ", line 3: 1 values where the header has 5"),
        (f"{head}\n1,2,3,4,5\n\xa0\n2,2,3,4,5\n", ", line 3: 1 values where the header has 5"),
        # spaces after a separator are skipped, as pandas skips them: the quoted line break
        # after ', ' is one value's (the bad value was named a line early)
        (f"{head},note\n1, 2, 3, 4, 5, \"a\nb\"\n2, 2, bad, 4, 5, x\n",
         ", line 4, column 'bb_top': not a number: 'bad'"),
        # (an empty file, pandas' "No columns to parse from file" before, is a file of no
        # detections: test_pipeline's test_detections_that_cannot_give_tracks_are_named)
    ]:
        path.write_text(text)
        with pytest.raises(MOTFormatError, match=re.escape(f"{path}{message}")):
            track_sequence(path, tmp_path / "out.txt", fps=10)
    # a blank line before the header, and a quoted value holding the separator after ', ':
    # read, as pandas reads it (the row check, counting spaces as values, refused it)
    path.write_text(f"\n{head},conf,note\n1, 2, 3, 4, 5, 0.9, \"a, b\"\n"
                    "2, 2, 3, 4, 5, 0.9,\n")
    assert track_sequence(path, tmp_path / "ok.txt", fps=10).detections == 2


def test_a_csv_file_separated_by_tabs_or_semicolons_reads_as_with_commas(tmp_path):
    """A spreadsheet's export separates its values by tabs, or by semicolons with decimal
    commas: its header was read as one column, and the file refused (``no column 'frame'
    ... columns: ['frame\\tid\\t...']``). Where the header has no comma, the values are
    split at tabs or semicolons, and the file tracks as the same rows with commas do."""
    pytest.importorskip("pandas")
    from vistrack.pipeline import track_sequence

    rows = [(f, -1, 10.5 + 3 * f, 20, 30, 60, 0.9) for f in range(1, 11)]
    head = ["frame", "id", "bb_left", "bb_top", "bb_width", "bb_height", "conf"]

    def write(name, sep, decimal=".", before=""):
        path = tmp_path / name
        path.write_text(before + "\n".join([sep.join(head)] + [
            sep.join(str(v).replace(".", decimal) for v in r) for r in rows]) + "\n")
        return path

    comma = track_sequence(write("a.csv", ","), tmp_path / "a.txt", fps=10)
    assert comma.rows == 10
    # a blank line before the header, as pandas skips it: the separator was taken from the
    # blank line ("line 3: 1 values where the header has 7" for a semicolon file)
    for name, sep, decimal, before in (("t.csv", "\t", ".", ""), ("s.csv", ";", ".", ""),
                                       ("d.csv", ";", ",", ""), ("b.csv", ";", ",", "\n"),
                                       ("bt.csv", "\t", ".", " \n")):
        track_sequence(write(name, sep, decimal, before), tmp_path / f"{name}.txt", fps=10)
        assert (tmp_path / f"{name}.txt").read_text() == (tmp_path / "a.txt").read_text()


def test_detections_to_and_from_supervision_and_ultralytics():
    sv = pytest.importorskip("supervision")
    from types import SimpleNamespace

    from vistrack.types import Detections

    theirs = sv.Detections(xyxy=np.array([[10.0, 20, 40, 60], [5, 5, 9, 30]]),
                           confidence=np.array([0.9, 0.2]), class_id=np.array([0, 3]))
    ours = Detections.from_supervision(theirs)
    assert ours.boxes.tolist() == theirs.xyxy.tolist() and ours.classes.tolist() == [0, 3]
    back = ours.to_supervision()
    assert isinstance(back, sv.Detections) and len(back) == 2
    np.testing.assert_array_equal(back.xyxy, theirs.xyxy)
    np.testing.assert_array_equal(back.confidence, theirs.confidence)
    np.testing.assert_array_equal(back.class_id, theirs.class_id)
    # supervision without scores or classes: ours default to 1 and 0
    plain = Detections.from_supervision(sv.Detections(xyxy=theirs.xyxy))
    assert plain.scores.tolist() == [1.0, 1.0] and plain.classes.tolist() == [0, 0]
    with pytest.raises(ValueError, match="points"):
        Detections(points=np.zeros((1, 2))).to_supervision()

    class Tensor:  # what ultralytics holds: torch tensors, detached and moved to the CPU
        def __init__(self, a):
            self.a = a

        def detach(self):
            return self

        def cpu(self):
            return self

        def numpy(self):
            return self.a

    result = SimpleNamespace(boxes=SimpleNamespace(xyxy=Tensor(theirs.xyxy.astype(np.float32)),
                                                   conf=Tensor(np.array([0.9, 0.2], np.float32)),
                                                   cls=Tensor(np.array([0.0, 3.0], np.float32))))
    d = Detections.from_ultralytics(result)
    assert d.boxes.tolist() == theirs.xyxy.tolist() and d.classes.tolist() == [0, 3]
    np.testing.assert_allclose(d.scores, [0.9, 0.2], rtol=1e-6)
    # the list of one that model(image) returns is taken as its result; a list of several,
    # or a result without boxes (a classification model's), is named
    listed = Detections.from_ultralytics([result])
    assert listed.boxes.tolist() == d.boxes.tolist() and listed.scores.tolist() == d.scores.tolist()
    with pytest.raises(TypeError, match=r"result must be one image's result; got a list of 2 "):
        Detections.from_ultralytics([result, result])
    with pytest.raises(TypeError, match="result must be a detection model's result, with boxes"):
        Detections.from_ultralytics(SimpleNamespace(boxes=None))
    # a (2, 8) array was read as 4 boxes and class 2.7 as 2, where from_supervision and
    # Detections refuse them (the oracle: their words)
    bad = SimpleNamespace(xyxy=np.arange(16.0).reshape(2, 8), conf=np.full(2, 0.5),
                          cls=np.zeros(2))
    with pytest.raises(ValueError, match=re.escape("boxes.xyxy must have shape (N, 4); got "
                                                   "(2, 8)")):
        Detections.from_ultralytics(SimpleNamespace(boxes=bad))
    with pytest.raises(ValueError, match=re.escape("xyxy must have shape (N, 4); got (2, 8)")):
        Detections.from_supervision(SimpleNamespace(xyxy=bad.xyxy, confidence=bad.conf,
                                                    class_id=bad.cls))
    odd = SimpleNamespace(xyxy=np.array([[0.0, 0, 1, 1]]), conf=np.ones(1), cls=np.array([2.7]))
    with pytest.raises(ValueError, match=re.escape("classes must be whole numbers; classes[0] "
                                                   "= 2.7")):
        Detections.from_ultralytics(SimpleNamespace(boxes=odd))
    none = SimpleNamespace(xyxy=np.zeros((0, 4)), conf=np.zeros(0), cls=np.zeros(0))
    assert len(Detections.from_ultralytics(SimpleNamespace(boxes=none))) == 0


def test_tracks_written_as_parquet_are_the_text_files_rows(tmp_path):
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    from tests.test_fit import _sequence
    from vistrack.cli import main
    from vistrack.io import MOTTable, read_mot
    from vistrack.pipeline import track_sequence

    seq = _sequence(tmp_path / "SIM", np.random.default_rng(3), n_objects=6, T=40)
    for offline in (False, True):
        txt = track_sequence(seq, tmp_path / f"t{offline}.txt", offline=offline)
        pq = track_sequence(seq, tmp_path / f"t{offline}.parquet", offline=offline)
        assert (pq.rows, pq.tracks) == (txt.rows, txt.tracks) and pq.rows > 0
        df = pd.read_parquet(pq.out)
        want = read_mot(txt.out)
        pd.testing.assert_frame_equal(df, want.to_pandas())
        back = MOTTable.from_pandas(df)
        assert np.array_equal(back.boxes, want.boxes) and np.array_equal(back.ids, want.ids)
    # nothing left beside it but the two outputs of each mode and the sequence
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "SIM", "tFalse.parquet", "tFalse.txt", "tTrue.parquet", "tTrue.txt"]
    assert main(["track", str(seq), "--out", str(tmp_path / "cli.parquet")]) == 0
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "cli.parquet"),
                                  read_mot(tmp_path / "tFalse.txt").to_pandas())


def test_tracks_written_as_csv_have_a_header_and_read_back_as_detections(tmp_path, capsys):
    """``--out tracks.csv`` wrote MOTChallenge's text, headerless, under a .csv name, which
    ``vistrack track`` could not read back (a .csv file needs a header); it is now the
    Parquet file's rows as CSV, read back by ``from_pandas`` and as detections."""
    pd = pytest.importorskip("pandas")
    from tests.test_fit import _sequence
    from vistrack.evaluation import evaluate_files
    from vistrack.io import MOTTable, read_mot
    from vistrack.pipeline import track_sequence

    seq = _sequence(tmp_path / "SIM", np.random.default_rng(3), n_objects=6, T=40)
    for offline in (False, True):
        txt = track_sequence(seq, tmp_path / f"t{offline}.txt", offline=offline)
        csv = track_sequence(seq, tmp_path / f"t{offline}.csv", offline=offline)
        assert (csv.rows, csv.tracks) == (txt.rows, txt.tracks) and csv.rows > 0
        want = read_mot(txt.out)
        df = pd.read_csv(csv.out)
        assert list(df.columns) == list(want.to_pandas().columns)
        back = MOTTable.from_pandas(df)
        assert np.array_equal(back.boxes, want.boxes) and np.array_equal(back.ids, want.ids)
        # the centre as the box's decimals give it (0.01 of a pixel at most: a half of 0.01
        # is 0.005), not left + width / 2's binary noise (118.86999999999999)
        text = [line.split(",")[2:4] for line in csv.out.read_text().splitlines()[1:]]
        assert max(len(v.partition(".")[2]) for row in text for v in row) <= 3
        np.testing.assert_allclose(df[["x", "y"]].to_numpy(),
                                   want.boxes[:, :2] + want.boxes[:, 2:] / 2, rtol=1e-14)
        # and as the detections of another run: each box where the text file has it
        again = track_sequence(csv.out, tmp_path / f"again{offline}.txt", fps=10)
        assert again.detections == len(want)
        # vistrack eval scores it as the text file (and the Parquet one)
        scores = [evaluate_files([("s", seq / "gt" / "gt.txt", out, seq / "seqinfo.ini")])
                  ["s"] for out in (txt.out, csv.out)]
        if importlib.util.find_spec("pyarrow") is not None:
            pq = track_sequence(seq, tmp_path / f"t{offline}.parquet", offline=offline)
            scores.append(evaluate_files([("s", seq / "gt" / "gt.txt", pq.out,
                                           seq / "seqinfo.ini")])["s"])
        assert all(s.summary() == scores[0].summary() for s in scores) and scores[0].TP > 0
    # vistrack eval --pred-dir finds SEQ.csv (or SEQ.parquet) where there is no SEQ.txt, and
    # refuses two files for one sequence
    import json

    from vistrack.cli import main

    res = tmp_path / "res"
    res.mkdir()
    (res / "SIM.csv").write_bytes((tmp_path / "tFalse.csv").read_bytes())
    assert main(["eval", "--gt-dir", str(tmp_path), "--pred-dir", str(res), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["SIM"]["HOTA"] == evaluate_files(
        [("s", seq / "gt" / "gt.txt", tmp_path / "tFalse.txt", seq / "seqinfo.ini")]
    )["s"].summary()["HOTA"]
    (res / "SIM.txt").write_bytes((tmp_path / "tFalse.txt").read_bytes())
    assert main(["eval", "--gt-dir", str(tmp_path), "--pred-dir", str(res)]) == 2
    assert "results for SIM in more than one file" in capsys.readouterr().err


def test_parquet_without_pyarrow_is_a_clear_error(tmp_path, monkeypatch, capsys):
    from tests.test_fit import _sequence
    from vistrack.cli import main
    from vistrack.pipeline import track_sequence

    seq = _sequence(tmp_path / "SIM", np.random.default_rng(3), n_objects=2, T=5)
    monkeypatch.setitem(sys.modules, "pyarrow", None)  # import pyarrow raises ImportError
    with pytest.raises(ImportError, match="pyarrow is missing"):
        track_sequence(seq, tmp_path / "t.parquet")
    assert main(["track", str(seq), "--out", str(tmp_path / "t.parquet")]) == 2
    err = capsys.readouterr().err
    assert "pyarrow is missing" in err and "vistrack[parquet]" in err
    assert not (tmp_path / "t.parquet").exists()


def test_columns_given_as_the_command_lines_text_are_named():
    """`columns="frame=t"` (the command line's --columns form) failed with "dictionary
    update sequence element #0 has length 1; 2 is required", naming nothing."""
    from vistrack.io import MOTTable

    with pytest.raises(TypeError, match=r"^columns must be a dict \{ours: theirs\}, such as "
                       r"\{'frame': 't'\}; got the text 'frame=t' \(the command line's "
                       r"--columns OURS=THEIRS,\.\.\. form\)$"):
        MOTTable.from_pandas({"t": [1]}, "frame=t")


def test_supervision_boxes_of_another_shape_are_named():
    """An xyxy of shape (2, 8) became 4 boxes without a word, and one of shape (3,) failed
    with numpy's "cannot reshape array of size 3 into shape (4)"."""
    from types import SimpleNamespace

    from vistrack.types import Detections

    for shape in ((2, 8), (3,)):
        with pytest.raises(ValueError, match=rf"^xyxy must have shape \(N, 4\); got "
                                             rf"{re.escape(str(shape))}$"):
            Detections.from_supervision(SimpleNamespace(xyxy=np.zeros(shape)))
    assert len(Detections.from_supervision(SimpleNamespace(xyxy=np.zeros((0,))))) == 0


def test_detections_of_words_name_the_column():
    """A class's name, a word for a score or a box: numpy's "could not convert string to
    float" named no column."""
    from vistrack.types import Detections

    box = np.zeros((1, 4))
    for kw, message in (({"classes": ["person"]}, "classes must be numbers; classes[0] "
                         "(flattened) is 'person'; map class names to numbers first"),
                        ({"scores": ["high"]}, "scores must be numbers; scores[0] (flattened) "
                         "is 'high'")):
        with pytest.raises(ValueError, match="^" + re.escape(message) + "$"):
            Detections(boxes=box, **kw)
    with pytest.raises(ValueError, match=r"^boxes must be numbers; boxes\[1\] \(flattened\) "
                                         r"is 'a'$"):
        Detections(boxes=[[0, "a", 1, 1]])
    assert Detections(boxes=box, scores=["0.5"], classes=["2"]).classes.tolist() == [2]


def test_detections_refuse_scores_that_are_no_real_number_and_classes_that_would_wrap():
    """An infinite score was tracked and written to results read_mot then refused; a NaN one
    failed only at the tracker's step; a uint64 class of 2**64 - 1 became -1."""
    from vistrack.types import Detections

    box = np.zeros((2, 4))
    with pytest.raises(ValueError, match=re.escape(
            "scores must be finite; scores[1] = inf (the logit of a probability of 0 or 1? "
            "clip the probabilities first)")):
        Detections(boxes=box, scores=[0.5, np.inf])
    for scores in ([np.nan, 1.0], [None, 1.0]):
        with pytest.raises(ValueError, match=re.escape("scores must be finite; scores[0] = nan")
                           + "$"):
            Detections(boxes=box, scores=scores)
    with pytest.raises(ValueError, match=re.escape(
            "classes must be whole numbers within ±(2**53 - 1); classes[0] = "
            "18446744073709551615")):
        Detections(boxes=box, classes=np.array([2**64 - 1, 1], np.uint64))
    assert Detections(boxes=box, scores=[-5.0, 1e9]).scores.tolist() == [-5.0, 1e9]


def test_a_semicolon_csv_whose_first_rows_are_whole_numbers_reads_its_decimal_commas(tmp_path):
    """The decimal comma was looked for in the first row alone: a file whose first row held
    whole numbers was read with decimal points, and '10,5' two rows on was refused. pandas,
    told the dialect, reads it."""
    import pandas as pd

    from vistrack.io.motchallenge import _read_csv

    p = tmp_path / "semi.csv"
    p.write_text("frame;id;bb_left;bb_top;bb_width;bb_height;conf\n1;1;10;20;30;40;1\n"
                 "2;1;10,5;20,25;30;40;0,5\n")
    np.testing.assert_array_equal(_read_csv(p, "a CSV file").to_numpy(),
                                  pd.read_csv(p, sep=";", decimal=",").to_numpy())
    assert _read_csv(p, "a CSV file").to_numpy()[1, 2:4].tolist() == [10.5, 20.25]


def test_corners_named_without_their_far_corner_are_named():
    """A table read by corners named in `columns` (x1=x, y1=y) without x2 and y2 was told
    "no column 'h'", a column it lists, where the far corner is what is missing (it read the
    x, y mapped as x1, y1 as a centre). Oracle: the columns given."""
    from vistrack.io import MOTTable

    rows = {"t": [1], "x": [1.0], "y": [2.0], "w": [3.0], "h": [4.0], "score": [0.5]}
    with pytest.raises(ValueError) as e:
        MOTTable.from_pandas(rows, columns={"frame": "t", "x1": "x", "y1": "y", "bb_width": "w",
                                            "bb_height": "h", "conf": "score"}, path="d.csv")
    assert str(e.value) == ("no column 'x2' or 'y2' in d.csv (a box by its corners needs all "
                            "four, 'x', 'y', 'x2', 'y2'); columns: ['h', 'score', 't', 'w', "
                            "'x', 'y']")
    whole = {"t": [1], "a": [1.0], "b": [2.0], "c": [4.0], "d": [7.0]}
    t = MOTTable.from_pandas(whole, columns={"frame": "t", "x1": "a", "y1": "b", "x2": "c",
                                             "y2": "d"})
    assert t.boxes.tolist() == [[1.0, 2.0, 3.0, 5.0]]


def test_one_column_named_for_two_of_ours_is_refused(tmp_path, capsys):
    """`--columns bb_left=x,bb_top=x` read one column as both, unsaid (boxes on the diagonal,
    warned of as outside the image at best). Oracle: the names given."""
    from vistrack.cli import main
    from vistrack.io import MOTTable

    rows = {"frame": [1], "x": [1.0], "y": [2.0], "w": [3.0], "h": [4.0]}
    said = "columns bb_left=x and bb_top=x: one column, 'x', named for two of ours"
    with pytest.raises(ValueError, match=re.escape(said)):
        MOTTable.from_pandas(rows, columns={"bb_left": "x", "bb_top": "x", "bb_width": "w",
                                            "bb_height": "h"})
    csv = tmp_path / "d.csv"
    csv.write_text("frame,x,y,w,h\n1,1,2,3,4\n")
    assert main(["track", str(csv), "--fps", "10", "--out", str(tmp_path / "r.txt"),
                 "--columns", "bb_left=x,bb_top=x,bb_width=w,bb_height=h"]) == 2
    assert said in capsys.readouterr().err

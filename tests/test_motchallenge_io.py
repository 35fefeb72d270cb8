"""MOTChallenge files: every format in ../shared reads, rows are sorted, bad rows are named."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from vistrack.io import MOTFormatError, MOTTable, read_mot, read_seqinfo, write_mot
from vistrack.io.motchallenge import _write_sorted

from .mot_oracles import MOT15, MOT17, seq_dir


def test_reads_the_shared_files():
    d = seq_dir("MOT17", "MOT17-09-FRCNN")
    gt = read_mot(d / "gt" / "gt.txt")
    raw = np.loadtxt(d / "gt" / "gt.txt", delimiter=",")
    assert len(gt) == len(raw) and gt.columns == 9
    assert set(np.unique(gt.classes)) <= set(range(1, 14)) and (gt.visibility <= 1).all()
    assert np.all(np.diff(gt.frames) >= 0)  # MOT17 gt is sorted by id, not by frame
    # the rows of one frame are the file's rows of that frame, in file order
    f = raw[raw[:, 0] == 100]
    np.testing.assert_array_equal(gt.ids[gt.frame_slices()[99]], f[:, 1])
    info = read_seqinfo(d)
    assert (info.name, info.frame_rate, info.seq_length) == ("MOT17-09-FRCNN", 30.0, 525)
    for name in MOT15:
        t = read_mot(seq_dir("MOT15", name) / "det" / "det.txt")
        assert len(t) > 0 and t.columns == 10 and (t.ids == -1).all()
    for name in MOT17:
        assert len(read_mot(seq_dir("MOT17", name) / "det" / "det.txt")) > 0


def test_frame_slices_are_found_when_asked_for():
    """Each frame's rows, against a scan of the frame column, for frames with rows, frames
    without and frames past the last; a file whose frame numbers lie 10^12 apart costs no
    memory for the frames between (a list of slices would need tens of terabytes)."""
    from vistrack.io.motchallenge import MOTTable

    rng = np.random.default_rng(3)
    frames = np.sort(rng.choice([1, 2, 2, 5, 5, 5, 9, 30], size=40))
    t = MOTTable.from_rows([(f, k, 0, 0, 5, 5) for k, f in enumerate(frames)])
    s = t.frame_slices(35)
    assert len(s) == 35 and len(t.frame_slices()) == 30
    for f in range(1, 36):
        np.testing.assert_array_equal(t.ids[s[f - 1]], np.flatnonzero(frames == f))
    assert s[-1] == s[34] and s[2:4] == [s[2], s[3]] and list(s)[4] == s[4]
    with pytest.raises(IndexError, match="frame 36 is outside frames 1-35"):
        s[35]
    far = MOTTable.from_rows([(1, 1, 0, 0, 5, 5), (10**12, 2, 0, 0, 5, 5)])
    sl = far.frame_slices()
    assert len(sl) == 10**12 and far.ids[sl[10**12 - 1]].tolist() == [2]
    assert far.ids[sl[5 * 10**11]].tolist() == []


@pytest.mark.parametrize("text, where", [
    ("1,1,10,10,5,5,1\n2,1,10,x,5,5,1\n", "line 2, column 4 (top): not a number: 'x'"),
    ("1,1,10,10,5,5,1\n\n3,1,10,10,-5,5,1\n", "line 3, column 5 (width): width must be >= 0"),
    ("1,1,10,10,5\n", "line 1, column 6 (height): expected at least 6"),
    ("0,1,10,10,5,5,1\n", "line 1, column 1 (frame): frame must be an integer >= 1"),
    ("1,1,10,10,5,5,1\n2,1,10,10,5,5,1,3\n", "line 2, column 8 (class): 8 values where"),
    ("1,1.5,10,10,5,5,1\n", "line 1, column 2 (id): id must be an integer"),
    ("1,1,nan,10,5,5,1\n", "line 1, column 3 (left): not a finite number"),
])
def test_bad_rows_are_named(tmp_path, text, where):
    p = tmp_path / "gt.txt"
    p.write_text(text)
    with pytest.raises(MOTFormatError, match=re.escape(f"gt.txt, {where}")):
        read_mot(p)


@pytest.mark.parametrize("field", ["1_0", "\u0661\u0662", "\uff11"])
def test_numbers_pythons_float_reads_and_numpy_refuses_are_named(tmp_path, field):
    """A value np.loadtxt refuses sent the file to the line-by-line reader, whose float() read
    ``1_0`` as 10 and Arabic-Indic or full-width digits as numbers: the file was read, or
    refused, by whether its other lines were plain. Oracle: numpy's text reader, which refuses
    each field."""
    with pytest.raises(ValueError):
        np.loadtxt([f"1,1,{field},10,5,5,1"], delimiter=",")
    p = tmp_path / "gt.txt"
    p.write_text(f"1,1,10,10,5,5,1\n2,1,{field},10,5,5,1\n", encoding="utf-8")
    with pytest.raises(MOTFormatError, match=re.escape(
            f"gt.txt, line 2, column 3 (left): not a number: {field!r}")):
        read_mot(p)
    ini = tmp_path / "seqinfo.ini"
    for key in ("frameRate", "seqLength"):
        values = {"frameRate": "25", "seqLength": "600", key: field.replace("1_0", "3_0")}
        ini.write_text("[Sequence]\n" + "".join(f"{k}={v}\n" for k, v in values.items())
                       + "imWidth=640\nimHeight=480\n", encoding="utf-8")
        with pytest.raises(MOTFormatError, match="is not a number"):
            read_seqinfo(ini)


def test_write_then_read_and_no_overwrite(tmp_path):
    p = tmp_path / "out" / "res.txt"
    write_mot(p, [2, 1, 1], [5, 9, 3], [[1, 2, 3, 4], [5, 6, 7, 8], [0.5, 0, 1, 1]], [0.5, 1, 1])
    t = read_mot(p)
    assert t.frames.tolist() == [1, 1, 2] and t.ids.tolist() == [3, 9, 5]
    np.testing.assert_allclose(t.boxes[0], [0.5, 0, 1, 1])
    with pytest.raises(FileExistsError, match="res.txt exists; pass force=True"):
        write_mot(p, [1], [1], [[0, 0, 1, 1]])
    write_mot(p, [1], [1], [[0, 0, 1, 1]], force=True)
    assert len(read_mot(p)) == 1
    (tmp_path / "s").mkdir()
    (tmp_path / "s" / "seqinfo.ini").write_text("[Sequence]\nname=s\nframeRate=abc\n")
    # the line, and the words of the file's reader ("is not float" before, and no line)
    with pytest.raises(MOTFormatError, match=re.escape(
            f"{tmp_path / 's' / 'seqinfo.ini'}:3: frameRate = 'abc' is not a number")):
        read_seqinfo(tmp_path / "s")
    (tmp_path / "s" / "seqinfo.ini").write_text(
        "; made by hand\n[Other]\nseqLength = 4\n[Sequence]\nname=s\nframeRate=25\n"
        "SEQLENGTH : 2.5\n")
    with pytest.raises(MOTFormatError, match=re.escape(
            f"{tmp_path / 's' / 'seqinfo.ini'}:7: seqLength must be a whole number; got 2.5")):
        read_seqinfo(tmp_path / "s")
    (tmp_path / "s" / "seqinfo.ini").write_text("[Sequence]\nname=s\nseqLength=3\n")
    with pytest.raises(MOTFormatError, match=re.escape(
            "[Sequence] has no frameRate; give the rate (vistrack track --fps, read_seqinfo's "
            "frame_rate)")):
        read_seqinfo(tmp_path / "s")


def test_write_mot_text_equals_python_formatting_row_by_row(tmp_path):
    """The block writer gives, byte for byte, each row formatted on its own with str.format."""
    rng = np.random.default_rng(5)
    n = 70_000  # more than one block
    F, I = rng.integers(1, 500, n), rng.integers(-1, 3000, n)
    B = rng.uniform(-50, 2000, (n, 4))
    S = rng.uniform(-1, 17, n)
    B[:4] = [[-0.0, 0.125, 0.375, 1.005], [2.675, 1e-9, -1e-9, 1e15], [0, 0, 0, 0],
             [np.inf, -np.inf, np.nan, 5]]
    S[:6] = [1.0, 1e-5, 123456.0, -0.85, np.nan, 0.99995]
    # the formatting (write_mot refuses negative widths and row 4: read_mot would refuse them)
    path = _write_sorted(tmp_path / "r.txt", F, I, B, S)
    order = np.lexsort((I, F))
    want = "".join(f"{F[k]},{I[k]},{B[k, 0]:.2f},{B[k, 1]:.2f},{B[k, 2]:.2f},{B[k, 3]:.2f},"
                   f"{S[k]:.4g},-1,-1,-1\n" for k in order)
    assert path.read_text() == want


def test_a_byte_order_mark_and_crlf_read_as_plain_text(tmp_path):
    rows = "170,1,10,10,5,5,1\n171,2,1,2,3,4,0\n"
    plain, bom, crlf = tmp_path / "plain.txt", tmp_path / "bom.txt", tmp_path / "crlf.txt"
    plain.write_bytes(rows.encode())
    bom.write_bytes(b"\xef\xbb\xbf" + rows.encode())
    crlf.write_bytes(b"\xef\xbb\xbf" + rows.replace("\n", "\r\n").encode())
    want = read_mot(plain)
    for p in (bom, crlf):
        got = read_mot(p)
        np.testing.assert_array_equal(got.frames, want.frames)
        np.testing.assert_array_equal(got.ids, want.ids)
        np.testing.assert_array_equal(got.boxes, want.boxes)
        np.testing.assert_array_equal(got.conf, want.conf)
    # a bad row after a BOM is still named by its line
    bom.write_bytes(b"\xef\xbb\xbf1,1,10,10,5,5,1\r\n2,1,x,10,5,5,1\r\n")
    with pytest.raises(MOTFormatError, match=re.escape("bom.txt, line 2, column 3 (left): "
                                                       "not a number: 'x'")):
        read_mot(bom)


def test_values_separated_by_spaces_or_tabs_or_ending_in_a_separator(tmp_path):
    """As TrackEval and py-motmetrics read them: a line without a comma splits at spaces or
    tabs, and a separator ending a line is ignored; each file gives the comma file's table."""
    rows = ["170,1,10.5,10,5,5,0.9,-1,-1,-1", "171,2,1,2,3,4,0,-1,-1,-1", "3,7,-4,2.25,3,4,1,1,1,1"]
    want = tmp_path / "plain.txt"
    want.write_text("\n".join(rows) + "\n")
    want_t = read_mot(want)
    variants = {
        "spaces": [r.replace(",", " ") for r in rows],
        "tabs": [r.replace(",", "\t") for r in rows],
        "aligned": ["  ".join(f"{v:>6}" for v in r.split(",")) + "  " for r in rows],
        "trailing": [r + "," for r in rows],
        "comma_space": [r.replace(",", ", ") for r in rows],
        "mixed": [rows[0], rows[1].replace(",", " "), rows[2] + ","],
    }
    for name, lines in variants.items():
        p = tmp_path / f"{name}.txt"
        p.write_text("\n".join(lines) + "\n")
        got = read_mot(p)
        for col in ("frames", "ids", "boxes", "conf"):
            np.testing.assert_array_equal(getattr(got, col), getattr(want_t, col), err_msg=name)
    p = tmp_path / "bad.txt"
    p.write_text("1 1 10 10 5 5 1\n2\t1\t10\tx\t5\t5\t1\n3 1 10 10 5\n")
    with pytest.raises(MOTFormatError, match=re.escape("bad.txt, line 2, column 4 (top): not a "
                                                       "number: 'x'")):
        read_mot(p)
    p.write_text("1 1 10 10 5\n")
    with pytest.raises(MOTFormatError, match=re.escape(
            "line 1, column 6 (height): expected at least 6 values (separated by commas, or "
            "by spaces or tabs), got 5")):
        read_mot(p)


def test_a_header_line_is_named_as_one(tmp_path):
    p = tmp_path / "det.txt"
    p.write_text("frame,id,x,y,w,h,score\n1,-1,10,10,5,5,0.9\n")
    with pytest.raises(MOTFormatError, match=re.escape(
            "det.txt, line 1, column 1 (frame): not a number: 'frame' (a header line? "
            "MOTChallenge files have none; a .csv file's header names its columns)")):
        read_mot(p)
    p.write_text("1,-1,10,10,5,5,0.9\n2,-1,10,10,5,5,high\n")  # not a header: no hint
    with pytest.raises(MOTFormatError, match=r"column 7 \(conf\): not a number: 'high'$"):
        read_mot(p)


@pytest.mark.parametrize("data, why", [
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "(byte 0: b'\\x89' is not UTF-8)"),
    (b"1,1,10,10,5,5,1\n2,1,10,10,\xe9,5,1\n", "(byte 26: b'\\xe9' is not UTF-8)"),
    (b"\x00" * 64, "(byte 0 is a NUL byte)"),
    (b"1,1,10,10,5,5,1\n\x00\x00", "(byte 16 is a NUL byte)"),
])
def test_binary_or_non_utf8_files_are_named(tmp_path, data, why):
    p = tmp_path / "gt.txt"
    p.write_bytes(data)
    with pytest.raises(MOTFormatError) as e:
        read_mot(p)
    assert str(e.value) == f"{p} is not a text MOTChallenge file {why}"
    s = tmp_path / "seqinfo.ini"
    s.write_bytes(data)
    with pytest.raises(MOTFormatError) as e:
        read_seqinfo(tmp_path)
    assert str(e.value) == f"{s} is not a text seqinfo.ini file {why}"


def test_huge_frames_and_ids_are_refused(tmp_path):
    p = tmp_path / "gt.txt"
    p.write_text("1,1,10,10,5,5,1\n1e300,1,10,10,5,5,1\n")
    with pytest.raises(MOTFormatError, match=re.escape(
            "gt.txt, line 2, column 1 (frame): frame must be below 2**53; got 1e+300")):
        read_mot(p)
    p.write_text("1,-1e20,10,10,5,5,1\n")
    with pytest.raises(MOTFormatError, match=re.escape(
            "gt.txt, line 1, column 2 (id): id must lie within ±(2**53 - 1); got -1e+20")):
        read_mot(p)


@pytest.mark.parametrize("body, match", [
    ("[Sequence]\nname=50%\nframeRate=25\nseqLength=3\nimWidth=640\nimHeight=480\n", None),
    ("[Sequence]\nframeRate=inf\nseqLength=3\nimWidth=640\nimHeight=480\n",
     ":2: frameRate must be a finite number > 0; got inf"),
    ("[Sequence]\nframeRate=25\nframeRate=30\n",
     ", line 3: not a valid INI file: 'framerate' appears twice in [Sequence]"),
    ("frameRate=25\n", ", line 1: not a valid INI file: no [section] header before 'frameRate=25'"),
    ("[Sequence]\nframeRate=25\n[Sequence]\n",
     ", line 3: not a valid INI file: [Sequence] appears twice"),
    ("[Sequence]\nframeRate=25\njunk line\n",
     ", line 3: not a valid INI file: not 'key = value': 'junk line'"),
])
def test_seqinfo_oddities(tmp_path, body, match):
    """A bad INI file is named with its line, in one line of text (configparser's own messages
    span several)."""
    p = tmp_path / "seqinfo.ini"
    p.write_bytes(b"\xef\xbb\xbf" + body.encode())
    if match is None:
        assert read_seqinfo(p).name == "50%"  # no interpolation; the BOM is dropped
    else:
        with pytest.raises(MOTFormatError) as e:
            read_seqinfo(p)
        sep = "" if match.startswith((",", ":")) else ": "
        assert str(e.value) == f"{p}{sep}{match}"


def test_seqinfo_counts_written_as_floats_are_read(tmp_path):
    """seqLength, imWidth and imHeight are counts: written 600.0 or 6e2 (a finite number > 0,
    as the contract asks, and whole), they were refused as "not int", where frameRate=1e1 was
    read; a count that is not whole is named."""
    p = tmp_path / "seqinfo.ini"
    p.write_text("[Sequence]\nframeRate=1e1\nseqLength=6e2\nimWidth=1920.0\nimHeight=1080\n")
    info = read_seqinfo(p)
    assert (info.frame_rate, info.seq_length, info.im_width, info.im_height) == (10.0, 600, 1920,
                                                                                1080)
    assert all(type(v) is int for v in (info.seq_length, info.im_width, info.im_height))
    p.write_text("[Sequence]\nframeRate=10\nseqLength=600.5\nimWidth=1920\nimHeight=1080\n")
    with pytest.raises(MOTFormatError) as e:
        read_seqinfo(p)
    assert str(e.value) == f"{p}:3: seqLength must be a whole number; got 600.5"


@pytest.mark.parametrize("before", ["; page\fbreak\n", "; a\u2028b\n", "name=Caf\x85e\n"])
def test_a_seqinfo_value_is_named_by_its_line_as_editors_count_them(tmp_path, before):
    """Lines were counted with str.splitlines, which also breaks at a form feed, NEL and
    U+2028: a bad value after one was named a line too far. Oracle: the lines split at \\n."""
    p = tmp_path / "seqinfo.ini"
    text = f"[Sequence]\n{before}frameRate=25\nseqLength=abc\nimWidth=640\nimHeight=480\n"
    p.write_text(text, encoding="utf-8")
    line = text.split("\n").index("seqLength=abc") + 1
    with pytest.raises(MOTFormatError) as e:
        read_seqinfo(p)
    assert str(e.value) == f"{p}:{line}: seqLength = 'abc' is not a number"


@pytest.mark.parametrize("rate, error, message", [
    (-5, ValueError, "frame_rate must be a finite number > 0; got -5"),
    (0, ValueError, "frame_rate must be a finite number > 0; got 0"),
    (float("nan"), ValueError, "frame_rate must be a finite number > 0; got nan"),
    (True, TypeError, "frame_rate must be a number; got True"),
    ("abc", TypeError, "frame_rate must be a number; got 'abc'"),
])
def test_read_seqinfo_names_a_frame_rate_given_that_is_no_rate(tmp_path, rate, error, message):
    """The rate given for a file without frameRate was taken as it came (-5, 0, NaN, True as
    1.0), or failed in float()'s words ("could not convert string to float"), where the same
    value in the file is named."""
    p = tmp_path / "seqinfo.ini"
    p.write_text("[Sequence]\nname=S\nseqLength=3\nimWidth=640\nimHeight=480\n")
    with pytest.raises(error, match=re.escape(message)):
        read_seqinfo(p, frame_rate=rate)
    assert read_seqinfo(p, frame_rate=12.5).frame_rate == 12.5


def test_a_class_column_that_holds_no_class(tmp_path):
    """Column 8 is the class of MOT16/17/20 ground truth and a world x in MOT15's (and in
    MOTChallenge's detections files): a column with a value that is not an integer (3.5,
    1e30) holds no class, and every row's is -1, whole numbers among them too (a world x of
    2 was class 2, and its detection was tracked apart from the rest); read without a numpy
    warning. A column of integers is one of classes."""
    p = tmp_path / "gt.txt"
    p.write_text("1,1,10,10,5,5,1,3.5,1\n1,2,10,10,5,5,1,1e30,1\n2,2,10,10,5,5,1,2,1\n"
                 "2,3,10,10,5,5,1,-9007199254740992,1\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_mot(p).classes.tolist() == [-1, -1, -1, -1]
    p.write_text("1,1,10,10,5,5,1,7,1\n2,2,10,10,5,5,1,2,1\n2,3,10,10,5,5,1,-9007199254740991,1\n")
    assert read_mot(p).classes.tolist() == [7, 2, -(2 ** 53 - 1)]
    # ETH-Bahnhof's ground truth holds world coordinates there, none a whole number; one
    # made whole is no class either
    lines = (seq_dir("MOT15", "ETH-Bahnhof") / "gt" / "gt.txt").read_text().splitlines()
    cells = lines[0].split(",")
    cells[7] = "3"
    p.write_text("\n".join([",".join(cells), *lines[1:]]) + "\n")
    assert set(read_mot(p).classes.tolist()) == {-1}


def test_a_world_y_is_no_visibility(tmp_path):
    """MOT15's ground truth holds world x, y, z in columns 8-10: x was known for no class,
    but y was read as the visibility (3.3 to 143 on ETH-Bahnhof, -16 to 7.7 on
    PETS09-S2L1) and written as one by to_csv. -1 now, as where absent; MOT17's visibility
    is read as its file holds it (oracle: numpy's loadtxt of the column)."""
    for name in ("ETH-Bahnhof", "PETS09-S2L1"):
        gt = seq_dir("MOT15", name) / "gt" / "gt.txt"
        table = read_mot(gt)
        assert set(table.visibility.tolist()) == {-1.0}
        assert np.ptp(np.loadtxt(gt, delimiter=",")[:, 8]) > 1  # (a world y, not a share)
    gt = seq_dir("MOT17", "MOT17-09-FRCNN") / "gt" / "gt.txt"
    rows = np.loadtxt(gt, delimiter=",")
    rows = rows[np.argsort(rows[:, 0], kind="stable")]
    np.testing.assert_array_equal(read_mot(gt).visibility, rows[:, 8])
    # a world x of whole numbers beside a world y: no class is told from it, but the y is
    # no share, so no visibility either; shares and -1 are visibilities
    p = tmp_path / "gt.txt"
    p.write_text("1,1,10,10,5,5,1,3,12.5,0\n2,1,10,10,5,5,1,4,-3.25,0\n")
    assert read_mot(p).visibility.tolist() == [-1.0, -1.0]
    p.write_text("1,1,10,10,5,5,1,1,0.25\n2,1,10,10,5,5,1,1,-1\n3,1,10,10,5,5,1,1,1\n")
    assert read_mot(p).visibility.tolist() == [0.25, -1.0, 1.0]


@pytest.mark.parametrize("row, message", [
    ((1.7, 1, 0, 0, 1, 1), "row 1, value 1 (frame): frame must be an integer; got 1.7"),
    ((1, 2.7, 0, 0, 1, 1), "row 1, value 2 (id): id must be an integer; got 2.7"),
    ((1e30, 1, 0, 0, 1, 1),
     "row 1, value 1 (frame): frame must lie within ±(2**53 - 1); got 1e+30"),
    ((np.nan, 1, 0, 0, 1, 1), "row 1, value 1 (frame): not a finite number; got nan"),
    ((1, 1, np.nan, 0, 10, 10), "row 1, value 3 (left): not a finite number; got nan"),
    ((1, 1, 0, 0, 10, 10, np.inf), "row 1, value 7 (conf): not a finite number; got inf"),
])
def test_rows_a_table_cannot_hold_are_named(row, message):
    """MOTTable.from_rows made frame 1.7 frame 1 and ids 2.7 and 2.2 one id (then "id 2
    appears more than once"), a frame of NaN or 1e30 frame -2**63, and a NaN box reached
    scipy's "matrix contains invalid numeric entries" in evaluate_mot. Each is named by its
    row and value; a frame of 0 is kept, for evaluate_mot to name."""
    with pytest.raises(ValueError) as e:
        MOTTable.from_rows([(1, 1, 0, 0, 1, 1, 1)[:len(row)], row], path="mine")
    assert str(e.value) == "mine, " + message.replace("row 1", "row 2")
    assert MOTTable.from_rows([(0, 1, 0, 0, 1, 1)]).frames.tolist() == [0]


def test_rows_not_given_as_a_list_of_rows_are_named():
    """A single row not in a list: 12 values were cut into two rows without a word, and 7
    failed in a reshape's words ("cannot reshape array of size 7"). No rows at all is an
    empty table, as before."""
    for flat in ([1, 1, 0, 0, 1, 1, 1], list(range(1, 13))):
        with pytest.raises(ValueError, match=re.escape(
                f"rows must be a list of rows, (N, w); got shape ({len(flat)},) (one row: "
                "[row])")):
            MOTTable.from_rows(flat)
        assert MOTTable.from_rows([flat]).columns == len(flat)
    with pytest.raises(ValueError, match=re.escape("got shape (2, 1, 6)")):
        MOTTable.from_rows(np.ones((2, 1, 6)))
    assert len(MOTTable.from_rows([])) == len(MOTTable.from_rows(np.zeros((0, 9)))) == 0


# the lines around a bad row: every kind of line that holds no row, and rows
FILLER = {
    "comment": "# frame,id,left,top,width,height,conf",
    "comment_no_comma": "# produced by my detector",
    "hash_alone": "#",
    "blank": "",
    "row": "5,-1,10,10,20,20,0.9",
    "row_with_comment": "6,-1,10,10,20,20,0.9 # a note, with a comma",
    "row_hash_glued": "7,-1,10,10,20,20,0.9#note",
}


@pytest.mark.parametrize("before", [
    ["comment", "row", "row"],
    ["comment_no_comma", "row"],
    ["comment", "comment", "blank", "row", "hash_alone", "row_with_comment"],
    ["row", "comment", "row_hash_glued", "blank", "comment_no_comma"],
    ["row_with_comment", "row_with_comment", "comment"],
])
@pytest.mark.parametrize("bad, message", [
    ("9,-1,10,10,-20,20,0.9", "column 5 (width): width must be >= 0; got -20"),
    ("9,-1,10,10,20,-3,0.9", "column 6 (height): height must be >= 0; got -3"),
    ("0,-1,10,10,20,20,0.9", "column 1 (frame): frame must be an integer >= 1"),
    ("9,1.5,10,10,20,20,0.9", "column 2 (id): id must be an integer; got 1.5"),
    # rows numpy's reader refuses, read line by line: a comment there is one too
    ("9,-1,10,10,20,20,nan", "column 7 (conf): not a finite number: 'nan'"),
    ("9,-1,10,x,20,20,0.9", "column 4 (top): not a number: 'x'"),
])
def test_a_bad_row_after_comment_lines_is_named_by_its_line(tmp_path, before, bad, message):
    """np.loadtxt drops '#' comments (to the end of a line) and lines left empty; the line
    named for a bad row counted only the lines that were not blank, so every line after a
    comment line was one too early ("det.txt, line 3" for the row on line 4), and a file
    read line by line (numpy's reader refused a row) named the comment line itself ("got 2:
    '# header'"). The line is the file's: its position among all the file's lines."""
    lines = [FILLER[k] for k in before] + [bad] + [FILLER["row"], FILLER["comment"]]
    want = lines.index(bad) + 1
    for sep in (",", " "):  # commas; spaces (a comment with a comma or without before them)
        text = "\n".join(line.replace(",", sep) if not line.startswith("#") else line
                         for line in lines) + "\n"
        p = tmp_path / "det.txt"
        p.write_text(text)
        with pytest.raises(MOTFormatError) as e:
            read_mot(p)
        assert str(e.value).startswith(f"{p}, line {want}, {message}"), (sep, str(e.value))
        assert text.splitlines()[want - 1].split("#")[0].strip() == bad.replace(",", sep)


@pytest.mark.parametrize("char", ["\f", "\x0b", "\x1c", "\x85", "\u2028"])
def test_a_bad_row_is_named_by_its_line_as_editors_count_them(tmp_path, char):
    """Lines are broken at \\n, \\r\\n or \\r alone, as editors, ``wc -l`` and numpy's reader
    count them: Python's ``splitlines`` also breaks at a form feed and six others, and a
    comment holding one put the line named for a bad row one past it ("line 4" for the row
    on line 3), in ``read_mot`` and in the scoring's messages alike."""
    from vistrack.evaluation.mot import _lines_of

    p = tmp_path / "gt.txt"
    p.write_text(f"1,1,10,10,20,20,1\n# page{char}break\n2,1,10,10,20,-3,1\n", encoding="utf-8")
    assert len(p.read_bytes().split(b"\n")) - 1 == 3
    with pytest.raises(MOTFormatError) as e:
        read_mot(p)
    assert str(e.value) == f"{p}, line 3, column 6 (height): height must be >= 0; got -3"
    assert _lines_of(str(p), lambda row: row[0] == 2) == [3]
    crlf = tmp_path / "crlf.txt"  # \r\n and a lone \r: one line break each, as before
    crlf.write_bytes(b"1,1,10,10,20,20,1\r\n# note\r2,1,10,10,20,-3,1\r\n")
    with pytest.raises(MOTFormatError, match=", line 3, column 6"):
        read_mot(crlf)


@pytest.mark.parametrize("text", ids=["comment", "comma_comment", "noted", "trailing",
                                   "indented"], argvalues=[
    "# frame id left top width height\n{rows}",  # a comment without a comma, rows with
    "# frame,id,left,top,width,height\n{spaced}",  # a comment with commas, rows without
    "{rows_noted}\n# end\n",  # a comment ending each row
    "# only a comment\n\n{rows_trailing}",  # a separator ending each row: read line by line
    "{spaced}\n   # indented comment\n",
])
def test_comment_lines_read_as_numpy_reads_them(tmp_path, text):
    """A comment line before the rows chose the separator (a comment without a comma before
    rows with commas: every row one value), and the rows numpy's reader refused were read line
    by line, where a comment was refused ("got 2: '# header'"): each file reads as its rows
    alone do, to the bit."""
    rows = ["3,7,-4.5,2.25,3,4,0.912345678901", "1,2,10.1,20,30,40.75,1", "2,-1,0,0,5,5,0.5"]
    p, clean = tmp_path / "gt.txt", tmp_path / "clean.txt"
    clean.write_text("\n".join(rows) + "\n")
    want = read_mot(clean)
    p.write_text(text.format(rows="\n".join(rows), spaced="\n".join(r.replace(",", " ")
                                                                     for r in rows),
                             rows_noted="\n".join(f"{r} # row {k}" for k, r in enumerate(rows)),
                             rows_trailing="\n".join(r + "," for r in rows)))
    got = read_mot(p)
    for col in ("frames", "ids", "boxes", "conf", "classes", "visibility"):
        a, b = getattr(got, col), getattr(want, col)
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), col
    assert got.columns == want.columns
    p.write_text("# nothing but comments\n#\n\n")
    assert len(read_mot(p)) == 0
    # a '#' inside a row cuts it short, as numpy's reader cuts it, and the message says so
    p.write_text(f"{rows[0]}\n1,2,10#1,20,30,40,1\n")
    with pytest.raises(MOTFormatError) as e:
        read_mot(p)
    assert str(e.value) == (f"{p}, line 2, column 4 (top): expected at least 6 values "
                            "(separated by commas, or by spaces or tabs), got 3: "
                            "'1,2,10#1,20,30,40,1' ('#' starts a comment, to the end of the "
                            "line)")


HEADER = "frame,id,bb_left,bb_top,bb_width,bb_height,conf\n"


@pytest.mark.parametrize("data, bad", ids=["latin1_header", "latin1_deep", "bom_latin1",
                                            "utf16", "utf16le", "utf16be"], argvalues=[
    # cp1252 / Latin-1 (Excel's "CSV"): a column's name, a value deep in the file (pandas
    # counted its position from the start of the piece it decoded)
    (b"frame,bb_left,bb_top,bb_width,bb_height,conf,Gr\xf6\xdfe\n1,10,10,20,20,0.9,1\n", b"\xf6"),
    ((HEADER + "1,-1,10,10,20,20,0.9\n" * 20_000).encode() + b"2,-1,10,10,20,20,0.9\xb5\n",
     b"\xb5"),
    # after a UTF-8 byte-order mark, counted
    (b"\xef\xbb\xbf" + HEADER.encode() + b"1,-1,10,10,20,20,0.9\xe9\n", b"\xe9"),
    # UTF-16 (Excel's "Unicode Text"), its byte-order mark first; without one, NUL bytes
    (("\ufeff" + HEADER + "1,-1,10,10,20,20,0.9\n").encode("utf-16-le"), b"\xff"),
    ((HEADER + "1,-1,10,10,20,20,0.9\n").encode("utf-16-le"), b"\x00"),
    ((HEADER + "1,-1,10,10,20,20,0.9\n").encode("utf-16-be"), b"\x00"),
])
def test_a_csv_file_that_is_not_utf8_is_named_with_the_byte(tmp_path, data, bad):
    """pandas' UnicodeDecodeError passed through: "error: 'utf-8' codec can't decode byte
    0xf6 in position 2" named no file, and its position was not the file's. The file is
    named, and its first byte that is not UTF-8 (or a NUL byte), by its offset in the file,
    as read_mot names a text file's."""
    from vistrack.evaluation.files import _read_results
    from vistrack.pipeline import read_detections

    p = tmp_path / "dets.csv"
    p.write_bytes(data)
    k = data.index(bad)
    why = f"byte {k} is a NUL byte" if bad == b"\x00" else f"byte {k}: {bad!r} is not UTF-8"
    utf16 = " (it looks like UTF-16 text)" if b"\x00" in data else ""
    for read in (read_detections, _read_results):
        with pytest.raises(MOTFormatError) as e:
            read(p)
        assert str(e.value) == f"{p} is not a text CSV file ({why}); save it as UTF-8{utf16}"


def test_a_headerless_csv_file_is_named_as_one(tmp_path):
    """A MOTChallenge text file saved as .csv had its first row read as the header: "no column
    'frame' (the frame) in dets.csv; columns: ['-1', '-1.1', ..., '0.995474', '1', ...]
    (name the frame's column: --columns frame=NAME ...)". Said to have no header instead;
    whatever separates the values; its first row still no one's data."""
    from vistrack.evaluation.files import _read_results
    from vistrack.pipeline import read_detections

    rows = ["1,-1,649.441,231.502,44.417,86.13,0.995474,-1,-1,-1",
            "1,-1,252.783,207.732,35.813,96.641,0.991175,-1,-1,-1",
            "2,-1,647,230.5,44,86,0.99,-1,-1,-1"]
    variants = {"comma": rows, "tab": [r.replace(",", "\t") for r in rows],
                "semicolon": [r.replace(",", ";") for r in rows],
                "decimal_comma": [r.replace(",", ";").replace(".", ",") for r in rows]}
    for name, lines in variants.items():
        p = tmp_path / f"{name}.csv"
        p.write_text("\n".join(lines) + "\n")
        want = (f"{p}: no header: its first line holds numbers, not the columns' names (a "
                "MOTChallenge text file? name it .txt to read it as one; or add a header line "
                "naming the columns, as 'frame,id,bb_left,bb_top,bb_width,bb_height,conf')")
        for read in (read_detections, lambda p: read_detections(p, {"frame": "t"}),
                     _read_results):
            with pytest.raises(MOTFormatError) as e:
                read(p)
            assert str(e.value) == want, name
    # named .txt, it is one
    p = tmp_path / "dets.txt"
    p.write_text("\n".join(rows) + "\n")
    assert read_mot(p).frames.tolist() == [1, 1, 2]
    # numbered columns: pandas' own header (0 ... n - 1), or numbers named in columns
    seven = [r[:r.index(",-1,-1,-1")] for r in rows]
    p = tmp_path / "numbered.csv"
    p.write_text("0,1,2,3,4,5,6\n" + "\n".join(seven) + "\n")
    assert read_detections(p, {"frame": "0", "id": "1", "bb_left": "2", "bb_top": "3",
                               "bb_width": "4", "bb_height": "5",
                               "conf": "6"}).frames.tolist() == [1, 1, 2]
    with pytest.raises(ValueError, match=re.escape("no column 'frame' (the frame)")):
        read_detections(p)
    p = tmp_path / "named.csv"
    p.write_text("\n".join(seven) + "\n")
    t = read_detections(p, {"frame": "1", "id": "-1", "bb_left": "649.441",
                            "bb_top": "231.502", "bb_width": "44.417", "bb_height": "86.13",
                            "conf": "0.995474"})
    assert t.boxes.tolist() == [[252.783, 207.732, 35.813, 96.641], [647, 230.5, 44, 86]]
    # a DataFrame's numbered columns are not a file's first line
    pd = pytest.importorskip("pandas")
    with pytest.raises(ValueError, match=re.escape("no column 'frame' (the frame)")):
        MOTTable.from_pandas(pd.DataFrame(np.ones((2, 6))))


def test_a_text_file_after_a_byte_order_mark_names_the_byte_that_is_not_utf8(tmp_path):
    """The byte named counts from the file's start: decoded as utf-8-sig, the positions left
    the mark's 3 bytes out, and the message named a byte 3 before the bad one."""
    import re

    from vistrack.io import read_mot

    data = "\ufeff1,-1,10,20,30,40,0.9\n2,-1,10,20,30,40,0.9\n".encode() + b"3,-1,1\xf6,2,3,4,1\n"
    path = tmp_path / "bom.txt"
    path.write_bytes(data)
    at = data.index(bytes([0xF6]))
    with pytest.raises(ValueError, match=re.escape(
            f"bom.txt is not a text MOTChallenge file (byte {at}: b'\\xf6' is not UTF-8)")):
        read_mot(path)


def test_a_text_file_of_semicolons_is_pointed_to_csv(tmp_path):
    """A CSV file of semicolons named .txt was "expected at least 6 values, got 1" alone;
    the message says what the semicolons suggest, and the same file named .csv reads."""
    rows = "frame;id;bb_left;bb_top;bb_width;bb_height;conf\n1;-1;10;20;30;40;0.9\n"
    (tmp_path / "d.txt").write_text(rows)
    with pytest.raises(MOTFormatError, match=r"got 1: .* \(values separated by ';': a CSV "
                                             r"file\? name it \.csv to read it as one\)"):
        read_mot(tmp_path / "d.txt")
    (tmp_path / "d.csv").write_text(rows)
    from vistrack.pipeline import read_detections

    assert read_detections(tmp_path / "d.csv").boxes.tolist() == [[10.0, 20.0, 30.0, 40.0]]
    # a .csv of semicolons without its header was told to be named .csv, which it was: it is
    # told to name its columns, and with that header it reads
    from vistrack.evaluation.files import read_truth

    (tmp_path / "gt.csv").write_text(rows.partition("\n")[2])
    with pytest.raises(MOTFormatError, match=r"got 1: .* \(values separated by ';': a CSV file "
                                             r"of semicolons is read by its header, a first "
                                             r"line naming its columns: frame;id;bb_left;"):
        read_truth(tmp_path / "gt.csv")
    (tmp_path / "gt.csv").write_text(rows)
    assert read_truth(tmp_path / "gt.csv").boxes.tolist() == [[10.0, 20.0, 30.0, 40.0]]
    (tmp_path / "plain.txt").write_text("1 -1 10 20\n")  # no semicolon: no such hint
    with pytest.raises(MOTFormatError, match=r"got 4: '1 -1 10 20'$"):
        read_mot(tmp_path / "plain.txt")


def test_messages_show_every_digit_and_named_columns_are_read_as_named(tmp_path):
    """A value was shown to six digits (`frame must be an integer ...; got 123456` for
    123456.5); a column named `visibility` holding 40 or 1.0000001 was read by the text
    file's rule as a world y and became -1 in every row (written so by `to_csv`); columns
    of True and False were ids of 1 and 0; a `seqinfo.ini` whose header carries a comment
    (`[Sequence] ; MOT`) lost its error's line, and a `seqLength` past 2**53 was changed
    by a float (12345678901234567 read as ...568, where configparser and `int()` keep it).
    Oracle: the files' own text."""
    from vistrack.io.motchallenge import _read_csv

    p = tmp_path / "f.txt"
    p.write_text("123456.5,1,1,2,3,4,1\n")
    with pytest.raises(MOTFormatError, match=re.escape("frame must be an integer >= 1 "
                                                       "(frames count from 1, as MOTChallenge's"
                                                       " do); got 123456.5")):
        read_mot(p)
    with pytest.raises(MOTFormatError, match=re.escape("id must be an integer; got 2.5")):
        MOTTable.from_rows([(1, 2.5, 0, 0, 1, 1)])
    for text, said in (("0.5\n2,1,0,0,10,10,1,1,1.0000001", "line 3, column 'visibility': "
                        "visibility must be a share from 0 to 1 (-1: not given); got "
                        "1.0000001"),
                       ("40\n2,1,0,0,10,10,1,1,100", "line 2, column 'visibility': visibility"
                        " must be a share from 0 to 1 (-1: not given); got 40")):
        c = tmp_path / "v.csv"
        c.write_text("frame,id,bb_left,bb_top,bb_width,bb_height,conf,class,visibility\n"
                     f"1,1,0,0,10,10,1,1,{text}\n")
        with pytest.raises(MOTFormatError, match=re.escape(said)):
            MOTTable.from_pandas(_read_csv(c, "x"), path=str(c))
    c.write_text("frame,id,bb_left,bb_top,bb_width,bb_height,conf,class,visibility\n"
                 "1,1,0,0,10,10,1,1,0.5\n2,1,0,0,10,10,1,1,-1\n")
    assert MOTTable.from_pandas(_read_csv(c, "x"), path=str(c)).visibility.tolist() == [0.5, -1]
    c.write_text("frame,id,bb_left,bb_top,bb_width,bb_height,conf\n1,True,1,2,3,4,False\n")
    with pytest.raises(MOTFormatError, match=re.escape("line 2, column 'id': not a number: "
                                                       "True")):
        MOTTable.from_pandas(_read_csv(c, "x"), path=str(c))
    seq = tmp_path / "s"
    seq.mkdir()
    (seq / "seqinfo.ini").write_text("[Sequence] ; MOT\nname=S\nframeRate=25\nseqLength=3.5\n")
    with pytest.raises(MOTFormatError, match=re.escape(
            f"{seq / 'seqinfo.ini'}:4: seqLength must be a whole number; got 3.5")):
        read_seqinfo(seq)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=S\nframeRate=25\n"
                                     "seqLength=12345678901234567\nimWidth=640\nimHeight=480\n")
    assert read_seqinfo(seq).seq_length == 12345678901234567


def test_write_mot_and_from_rows_name_what_is_no_number(tmp_path):
    """Ids of Python's big integers, or None, failed with "'int' object has no attribute
    'tolist'"; ragged boxes, or a conf of text, failed in numpy's words naming neither
    argument (from_rows too). Oracle: the argument and the entry named."""
    out = tmp_path / "a.txt"
    for ids, said in (([2**70], "ids[0] = 1180591620717411303424 is not within ±(2**53 - 1)"),
                      ([None], "ids[0] = None is not a whole number"),
                      (["7"], "ids[0] = '7' is not a whole number")):
        with pytest.raises(ValueError, match=re.escape(said)):
            write_mot(out, [1], ids, [[0, 0, 1, 1]])
    with pytest.raises(TypeError, match="^boxes must be an array of numbers"):
        write_mot(out, [1, 2], [1, 1], [[0, 0, 1, 1], [0, 0, 1]])
    with pytest.raises(TypeError, match="^conf must be an array of numbers"):
        write_mot(out, [1], [1], [[0, 0, 1, 1]], ["high"])
    with pytest.raises(TypeError, match="^rows must be an array of numbers"):
        MOTTable.from_rows([(1, 1, 0, 0, 1, 1), (2, 1, 0, 0, 1)])
    assert not out.exists()
    write_mot(out, np.array([1], object), np.array([2**40], object), [[0, 0, 1, 1]])
    assert read_mot(out).ids.tolist() == [2**40]


def test_the_second_reading_of_the_track_files(tmp_path):
    """From the second reading: a seqLength of 400 digits failed in a bare OverflowError
    (the check of a whole number took a float of it); a ground truth's conf column of True
    and False, a flag, was refused with the booleans of other columns; a class of 1234567
    was shown as 1.23457e+06; BoxesWriter wrote a frame of 2.5 as its line 2, and one of
    2**53 + 1 as lines of NaN without end. Oracles: the file's own text, and the sinks'
    rule for frames."""
    from vistrack.evaluation import evaluate_mot
    from vistrack.io.motchallenge import _read_csv
    from vistrack.io.tracks import BoxesWriter
    from vistrack.types import Frame, Tracks

    seq = tmp_path / "s"
    seq.mkdir()
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=S\nframeRate=25\nseqLength=1"
                                     + "0" * 400 + "\n")
    with pytest.raises(MOTFormatError, match=re.escape(":4: seqLength must be a finite "
                                                       "number > 0")):
        read_seqinfo(seq)
    c = tmp_path / "gt.csv"
    c.write_text("frame,id,bb_left,bb_top,bb_width,bb_height,conf\n1,1,0,0,10,10,True\n"
                 "1,2,50,0,10,10,False\n")
    gt = MOTTable.from_pandas(_read_csv(c, "x"), path=str(c))
    assert gt.conf.tolist() == [1.0, 0.0]
    g = MOTTable.from_rows([(1, 1, 0, 0, 10, 10, 1, 1234567)])
    with pytest.raises(ValueError, match=re.escape("class 1234567 is not a MOT17 class")):
        evaluate_mot(g, g, benchmark="MOT17")
    box = Tracks(ids=np.array([1]), boxes=np.array([[0.0, 0, 2, 3]]), points=None,
                 scores=np.ones(1), classes=np.zeros(1))
    for index, said in ((2.5, "frame 2.5: a frame's index must be a whole number"),
                        (2**53 + 1, "must lie within ±(2**53 - 1)")):
        b = BoxesWriter(tmp_path / "b.txt")
        b.write(Frame(1, 0.0), box)
        with pytest.raises(ValueError, match=re.escape(said)):
            b.write(Frame(index, 0.0), box)
        assert len(b.boxes) == 1
        b.abort()


def test_a_folder_or_a_file_above_the_output_is_named_before_anything_is_written(tmp_path):
    """``write_mot`` given a folder told the caller to pass ``force=True``; with it, the whole
    file was written and the rename failed naming the partial file
    (``'.nd.00436f4e82.partial' -> 'nd'``); under a file, ``force=True`` raised the
    ``FileExistsError`` that means "exists, without force". The writers that take no
    ``force`` (``to_csv``, ``MOTWriter``, ``write_boxes``) failed the same way. Oracle: the
    messages ``check_output`` gives the command line's ``--out``, with the argument's name,
    and no file left behind."""
    from vistrack.io.tracks import CSVWriter, MOTWriter, write_boxes

    folder = tmp_path / "nd"
    folder.mkdir()
    (tmp_path / "f.txt").write_text("")
    under = tmp_path / "f.txt" / "y.txt"
    row = ([1], [1], [[0, 0, 1, 1]])
    for force in (False, True):
        with pytest.raises(IsADirectoryError, match=re.escape(
                f"path {folder} is a folder, not a file")):
            write_mot(folder, *row, force=force)
        with pytest.raises(NotADirectoryError, match=re.escape(
                f"path {under}: {tmp_path / 'f.txt'} is a file, not a folder")):
            write_mot(under, *row, force=force)
        with pytest.raises(IsADirectoryError, match=re.escape(f"{folder} is a folder")):
            write_boxes(folder, [[1.0, 2.0, 3.0, 4.0]], force=force)
    table = MOTTable.from_rows([(1, 1, 0, 0, 10, 20)])
    for call in (table.to_csv, MOTWriter, CSVWriter):
        with pytest.raises(IsADirectoryError, match=re.escape(f"{folder} is a folder, not a "
                                                              "file")):
            call(folder)
        with pytest.raises(NotADirectoryError, match=re.escape(
                f"{under}: {tmp_path / 'f.txt'} is a file, not a folder")):
            call(under)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.txt", "nd"]
    assert list(folder.iterdir()) == []


def test_frame_slices_name_a_length_that_would_leave_rows_out():
    """``frame_slices(2)`` of a table with rows in frame 3 left them in no slice, unsaid;
    2.7 was cut to 2, -1 gave no frame and the text '3' was read. Oracle: ``evaluate_mot``'s
    own check of its ``n_frames``."""
    t = MOTTable.from_rows([(1, 1, 0, 0, 10, 20), (3, 1, 5, 5, 10, 20), (3, 2, 1, 1, 3, 3)])
    with pytest.raises(ValueError, match=re.escape(
            "MOTTable: frame 3 is beyond n_frames = 2 (2 rows past it)")):
        t.frame_slices(2)
    for bad, error in ((2.7, ValueError), (-1, ValueError), (float("nan"), ValueError),
                       ("3", TypeError), (True, ValueError)):
        with pytest.raises(error, match="n_frames must be"):
            t.frame_slices(bad)
    assert [len(t.ids[s]) for s in t.frame_slices(3.0)] == [1, 0, 2]
    assert len(MOTTable.from_rows(np.zeros((0, 6))).frame_slices(0)) == 0

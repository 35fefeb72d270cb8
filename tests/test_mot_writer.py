"""write_mot formats whole columns with numpy: its text must be, byte for byte, Python's
%-format of each row (`%d,%d,%.2f,%.2f,%.2f,%.2f,%.4g,-1,-1,-1`), on every kind of value."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vistrack.io import MOTWriter, read_mot, write_mot
from vistrack.io.motchallenge import _write_sorted
from vistrack.types import Frame, Tracks

ROW = "%d,%d,%.2f,%.2f,%.2f,%.2f,%.4g,-1,-1,-1\n"


def percent_format(f, i, b, c) -> bytes:
    """Each row with Python's %-format, sorted by frame and id (stably) as write_mot sorts."""
    order = np.lexsort((i, f))
    return "".join(ROW % (int(f[k]), int(i[k]), *map(float, b[k]), float(c[k]))
                   for k in order).encode()


def values(rng: np.random.Generator, n: int) -> np.ndarray:
    """Values of every kind: any magnitude, ties and near-ties of the rounding (multiples of 1/8
    and of 0.005, their neighbours), decimals as files hold them, scores in [0, 1], and zeros,
    NaN, infinities, the %.4g exponent switches."""
    kind = rng.integers(0, 9, n)
    v = rng.uniform(-1, 1, n) * 10.0 ** rng.uniform(-12, 16, n)
    v = np.where(kind == 0, np.round(rng.uniform(-3000, 3000, n) * 8) / 8, v)
    v = np.where(kind == 1, np.round(rng.uniform(-3000, 3000, n) * 200) / 200, v)
    v = np.where(kind == 2, np.round(rng.uniform(-1e4, 1e4, n), int(rng.integers(0, 6))), v)
    v = np.where(kind == 3, rng.choice(
        [0.0, -0.0, np.nan, np.inf, -np.inf, 1e-4, 9.9995e-5, 1e-5, 2.5e-5, 1.5e-4, 0.99995,
         9999.4, 9999.5, 9999.6, 99995.0, 1e11, 1e13, 5e-324, 1.7976931348623157e308], n), v)
    v = np.where(kind == 4, rng.uniform(0, 1, n), v)
    v = np.where(kind == 5, np.round(rng.uniform(0, 1, n), 4), v)
    v = np.where(kind == 6, np.nextafter(np.round(rng.uniform(-1e3, 1e3, n), 3),
                                         rng.choice([-np.inf, np.inf], n)), v)
    return np.where(kind == 7, rng.uniform(-50, 2000, n), v)


@pytest.mark.parametrize("seed", range(12))
def test_write_mot_is_the_percent_format_byte_for_byte(tmp_path, seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 40_000))
    f = rng.integers(-10 ** int(rng.integers(1, 19)), 10 ** int(rng.integers(1, 19)), n)
    f[rng.random(n) < 0.005] = np.iinfo(np.int64).min
    i = rng.integers(-5, 10 ** int(rng.integers(1, 16)), n)
    b, c = values(rng, 4 * n).reshape(n, 4), values(rng, n)
    # the formatting of any values (write_mot refuses the rows read_mot would refuse; its
    # valid rows are tested below)
    path = _write_sorted(tmp_path / "r.txt", f, i, b, c)
    assert path.read_bytes() == percent_format(f, i, b, c)
    ok = (f >= 1) & np.isfinite(b).all(axis=1) & (b[:, 2:] >= 0).all(axis=1) & np.isfinite(c)
    ok &= (f < 2**53) & (np.abs(i) < 2**53)  # read_mot's bound on frames and ids
    valid = write_mot(tmp_path / "v.txt", f[ok], i[ok], b[ok], c[ok])
    assert valid.read_bytes() == percent_format(f[ok], i[ok], b[ok], c[ok])


@pytest.mark.parametrize("seed", range(4))
def test_mot_writer_is_the_percent_format_byte_for_byte(tmp_path, seed):
    """MOTWriter formats a frame of many rows as write_mot does, a few rows with %: either
    way each frame's text is the %-format of its rows (sorted by id), on every kind of value."""
    rng = np.random.default_rng(100 + seed)
    writer, want = MOTWriter(tmp_path / "w.txt"), []
    for frame in range(1, 9):
        n = 3000 if frame == 1 else int(rng.choice([0, 1, 5, 255, 256, 257, 3000]))
        ids = rng.permutation(np.unique(rng.integers(0, 10 ** int(rng.integers(4, 15)), n)))
        n = len(ids)
        b, c = values(rng, 4 * n).reshape(n, 4), values(rng, n)
        ok = np.isfinite(b).all(axis=1) & (np.abs(b) < 1e15).all(axis=1)
        # the rows the writer takes, those read_mot reads back (finite, w and h >= 0; it
        # refuses the others, tests/test_track_sinks.py)
        ok &= (b[:, 2:] >= 0).all(axis=1) & np.isfinite(c)
        ids, b, c = ids[ok], b[ok], c[ok]  # boxes as Tracks holds them: finite corners
        tracks = Tracks(ids=ids, boxes=np.c_[b[:, :2], b[:, :2] + b[:, 2:]], points=None,
                        scores=c, classes=np.zeros(len(ids)))
        writer.write(Frame(frame, 0.0), tracks)
        xywh = tracks.xywh
        want.append(percent_format(np.full(len(ids), frame), ids, xywh, c))
    writer.close()
    assert (tmp_path / "w.txt").read_bytes() == b"".join(want)


def test_write_mot_typical_results_then_read_back(tmp_path):
    """A tracker's results (boxes in pixels, scores in [0, 1]) more than one block long, and
    read_mot reads the file back to the rounded values."""
    rng = np.random.default_rng(7)
    n = 50_000
    f, i = np.repeat(np.arange(1, 501), 100), np.tile(np.arange(1, 101), 500)
    b = np.c_[rng.uniform(-20, 1920, (n, 2)), rng.uniform(1, 400, (n, 2))]
    c = rng.uniform(0, 1, n)
    path = write_mot(tmp_path / "r.txt", f, i, b, c)
    assert path.read_bytes() == percent_format(f, i, b, c)
    t = read_mot(path)
    np.testing.assert_array_equal(t.boxes, np.array([float(f"{x:.2f}") for x in b.ravel()])
                                  .reshape(n, 4))
    np.testing.assert_array_equal(t.conf, [float(f"{x:.4g}") for x in c])


@settings(max_examples=500, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(rows=st.lists(st.tuples(
    st.integers(-2 ** 63, 2 ** 63 - 1), st.integers(-2 ** 63, 2 ** 63 - 1),
    *[st.floats(allow_nan=True, allow_infinity=True, width=64)] * 5), min_size=1, max_size=40))
def test_write_mot_hypothesis_floats(tmp_path_factory, rows):
    """Any int64 frames and ids and any doubles (subnormal, huge, -0.0, NaN), formatted as
    write_mot formats its rows."""
    a = list(zip(*rows))
    f, i = np.array(a[0], dtype=np.int64), np.array(a[1], dtype=np.int64)
    b, c = np.array(a[2:6], dtype=float).T, np.array(a[6], dtype=float)
    path = _write_sorted(tmp_path_factory.getbasetemp() / "hyp.txt", f, i, b, c)
    assert path.read_bytes() == percent_format(f, i, b, c)


@pytest.mark.parametrize("frames, ids, boxes, conf, message", [
    ([0, 2], [1, 1], [[0, 0, 1, 1]] * 2, None,
     "frames[0] = 0: MOTChallenge frames count from 1"),
    ([1, 2.7], [1, 1], [[0, 0, 1, 1]] * 2, None, "frames[1] = 2.7 is not a whole number"),
    ([1, np.nan], [1, 1], [[0, 0, 1, 1]] * 2, None, "frames[1] = nan is not a whole number"),
    ([1, 2], [1, 1.9], [[0, 0, 1, 1]] * 2, None, "ids[1] = 1.9 is not a whole number"),
    ([1, 2], [1, 1], [[0, 0, 1, 1], [np.inf, 0, 1, 1]], None,
     "boxes[1] = [inf, 0.0, 1.0, 1.0] is not finite"),
    ([1, 2], [1, 1], [[0, 0, -5, 1], [0, 0, 1, 1]], None,
     "boxes[0] = [0.0, 0.0, -5.0, 1.0] has a negative width or height"),
    ([1, 2], [1, 1], [[0, 0, 1, 1]] * 2, [np.nan, 1], "conf[0] = nan is not finite"),
    ([1], [1], [[0, 0, 1, 1, 1]], None, "boxes must have shape (N, 4); got (1, 5)"),
    # an id of 2**64 - 1 (uint64) was written as -1, a detection's; frame 2**62 was written
    # into a file read_mot refused
    ([1], np.array([2**64 - 1], np.uint64), [[0, 0, 1, 1]], None,
     "ids[0] = 18446744073709551615 is not within ±(2**53 - 1), which read_mot refuses"),
    ([2**62], [1], [[0, 0, 1, 1]], None,
     "frames[0] = 4611686018427387904 is not within ±(2**53 - 1), which read_mot refuses"),
    ([1.0e17], [1], [[0, 0, 1, 1]], None,
     "frames[0] = 1e+17 is not within ±(2**53 - 1), which read_mot refuses"),
    # 2**53 + 1 was let through (as a float it is 2**53) and read back as 2**53: two
    # identities one
    ([1, 1], np.array([2**53 - 1, 2**53 + 1]), [[0, 0, 1, 1]] * 2, None,
     "ids[1] = 9007199254740993 is not within ±(2**53 - 1), which read_mot refuses"),
])
def test_write_mot_refuses_what_read_mot_would_refuse(tmp_path, frames, ids, boxes, conf,
                                                      message):
    """Each of these was written (frame 2.7 as 2, id 1.9 as 1, a NaN box as 'nan') into a
    file read_mot then refused, or read back as other numbers; now nothing is written."""
    path = tmp_path / "res.txt"
    with pytest.raises(ValueError) as e:
        write_mot(path, frames, ids, boxes, conf)
    assert str(e.value) == message
    assert not path.exists()


def test_write_mot_takes_whole_floats_and_one_row_as_four_numbers(tmp_path):
    """Frames and ids as floats that are whole numbers (a table read with pandas), and one
    box given as four numbers, are written as read_mot reads them back."""
    path = write_mot(tmp_path / "a.txt", np.array([2.0, 1.0]), np.array([7.0, 3.0]),
                     [[0, 0, 10, 20], [1, 2, 3, 4]], [0.5, 0.25])
    t = read_mot(path)
    assert t.frames.tolist() == [1, 2] and t.ids.tolist() == [3, 7]
    one = read_mot(write_mot(tmp_path / "b.txt", [4], [1], [1.5, 2, 3, 4]))
    assert one.boxes.tolist() == [[1.5, 2.0, 3.0, 4.0]] and one.frames.tolist() == [4]


def test_written_holds_the_rows_in_the_order_the_closed_file_will(tmp_path):
    """written() is "the rows as the file will hold them". With a frame written twice it
    gave that frame's two writes one after the other, each sorted by id, where close()
    sorts the whole file by frame and id. Oracle: the closed file read back."""
    writer = MOTWriter(tmp_path / "w.txt")

    def tracks(ids):
        n = len(ids)
        boxes = np.c_[np.arange(n), np.zeros(n), np.arange(n) + 5.0, np.full(n, 5.0)]
        return Tracks(ids=np.array(ids), boxes=boxes, points=None, scores=np.ones(n),
                      classes=np.zeros(n))

    writer.write(Frame(2, 0.1), tracks([7, 3]))
    writer.write(Frame(1, 0.0), tracks([4]))
    writer.write(Frame(2, 0.1), tracks([5, 1]))
    seen = writer.written()
    writer.close()
    closed = read_mot(tmp_path / "w.txt")
    assert closed.frames.tolist() == [1, 2, 2, 2, 2] and closed.ids.tolist() == [4, 1, 3, 5, 7]
    assert seen.frames.tolist() == closed.frames.tolist()
    assert seen.ids.tolist() == closed.ids.tolist()
    np.testing.assert_array_equal(seen.boxes, closed.boxes)

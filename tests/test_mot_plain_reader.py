"""read_mot's plain-file reader (eight bytes at a time) against the careful one (numpy's loadtxt,
then line by line): on every file either it declines, or it gives the same values to the bit,
and read_mot gives the same table or the same message as the careful reader alone."""

from __future__ import annotations

import random

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vistrack.io import MOTFormatError, MOTTable, read_mot
from vistrack.io.motchallenge import _parse_lines, _parse_plain, _read_careful, _row_lines

from .conftest import SHARED
from .test_fuzz_inputs import KINDS, damage

COLUMNS = ("frames", "ids", "boxes", "conf", "classes", "visibility")


def outcome(read, path) -> tuple:
    """The table ``read(path)`` gives (every array's dtype, shape and bytes) or its message."""
    try:
        t = read(path)
    except MOTFormatError as e:
        return ("error", str(e))
    return ("table", t.columns, t.path) + tuple(
        (getattr(t, k).dtype.str, getattr(t, k).shape, getattr(t, k).tobytes()) for k in COLUMNS)


def careful(path) -> MOTTable:
    """read_mot without the plain-file reader."""
    p = str(path)
    with open(p, "rb") as fh:
        return MOTTable.from_rows(_read_careful(p, fh.read()), p)


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def check(path, data: bytes) -> bool:
    """read_mot and the careful reader agree on ``data``; whether the plain reader read it."""
    path.write_bytes(data)
    plain = _parse_plain(data)
    if plain is not None:
        # what it read is what numpy's reader reads, to the bit (-0.0 included)
        text = data.decode("utf-8-sig")
        assert same_bits(plain, _parse_lines(str(path), text, text.splitlines())), data[:200]
    assert outcome(read_mot, path) == outcome(careful, path), data[:200]
    return plain is not None


# ------------------------------------------------------------------------ chosen fields

ROW = "7,3,10.5,20,30.25,40,0.9"

# each replaces the left value (column 3) of the second row
FIELDS = [
    "5", "-5", "0", "-0", "-0.0", "007", "-007.50", ".5", "-.5", "5.", "-5.", "0.125",
    "12345678", "-12345678", "1234567.8", ".1234567", "123456789", "1234567.89",
    "12345678.1234567", "-12345678.1234567", ".123456789012345", "1234567890123456",
    "9007199254740993", "12345678901234567890", "0.1234567890123456789", "1e5", "1E5", "-1e-5",
    "2.6772e-05", "1e+2", "1e308", "1e309", "1e-400", "4.9e-324",
    # what the careful reader refuses, or reads otherwise
    "", "-", ".", "-.", "--1", "1-", "1.2.3", "..5", "nan", "-nan", "inf", "-inf", "NaN",
    "0x10", "+1", " 1", "1 ", "\t1", "1_0", "1e", "e5", "1e5.5", "#", "1#2", '"1"', "١",
    "\x0b", "\x0c", "\x1c", "\x85", "\u2028", "\r", "\x00", "1,", ",1",
]


@pytest.mark.parametrize("field", FIELDS)
def test_one_field_as_the_careful_reader_reads_it(tmp_path, field):
    data = f"{ROW}\n7,4,{field},20,30,40,0.8\n{ROW}\n".encode()
    check(tmp_path / "gt.txt", data)


@pytest.mark.parametrize("text, plain", [
    (f"{ROW}\n{ROW}\n", True),
    (f"{ROW}\n{ROW}", True),  # no end of line at the end
    (f"{ROW}\n{ROW}\n\n\n", True),
    (f"\ufeff{ROW}\r\n{ROW}\r\n", True),
    (f"{ROW}\r\n{ROW}\n", True),  # mixed line ends
    (f"{ROW}\r\n{ROW}\r\n\r\n", True),
    (f"{ROW}\r{ROW}\r", False),  # old Mac line ends
    (f"{ROW}\n\n{ROW}\n", False),  # a blank line between rows
    (f"\n{ROW}\n", False),
    (f"{ROW}\n \n", False),
    (f"{ROW}\n{ROW},1\n", False),  # a row wider than the others
    (f"{ROW},1\n{ROW}\n", False),
    (f"{ROW},\n{ROW},\n", False),  # trailing commas
    ("1,1,1,1,1\n", False),  # 5 values
    ("1,1,1,1,1,1,1,1,1,1,1\n", False),  # 11
    (f"# a comment\n{ROW}\n", False),
    (f"{ROW} # a comment\n", False),
    (f"\ufeff\ufeff{ROW}\n", False),
    (f"{ROW}\n\x1a", False),
    ("", False),
    ("\n\n", False),
    ("\ufeff", False),
    ("0,1,1,1,1,1\n", True),  # read, then refused by the checks (frame 0)
    ("1,1,1,1,-1,1\n", True),  # width -1
    ("1,1.5,1,1,1,1\n", True),
    ("1e300,1,1,1,1,1\n", True),
])
def test_files_as_the_careful_reader_reads_them(tmp_path, text, plain):
    assert check(tmp_path / "gt.txt", text.encode()) == plain


def test_long_files_take_the_plain_reader_block_after_block(tmp_path):
    """Blocks end at line ends; a line longer than a block; fields of 9 to 17 bytes (read after
    the last block) in every block; an odd field deep in the file."""
    r = random.Random(3)
    rows = [f"{r.randrange(1, 900)},{r.randrange(-1, 300)},{r.uniform(-50, 2000):.3f},"
            f"{r.uniform(0, 1000):.2f},{r.uniform(0, 500):.1f},{r.randrange(0, 800)},"
            f"{r.random():.6f},-1,-1,-1" for _ in range(30_000)]
    for k in range(0, len(rows), 97):
        x = f"{r.uniform(-1e3, 1e3):.{r.randrange(6, 13)}f}"
        rows[k] = rows[k].replace(",-1,-1,-1", f",-1,{x},-1")
    rows[12_345] = rows[12_345].replace(",-1,-1,-1", ",-1,-1," + "0" * 70_000 + "1")
    assert check(tmp_path / "gt.txt", "\n".join(rows).encode())
    for junk in ("12345678x", "1234567.8.9", "-123456789012345678"):
        odd = rows[:20_000] + [rows[20_000].replace(",-1,", f",{junk},", 1)] + rows[20_001:]
        assert check(tmp_path / "gt.txt", "\n".join(odd).encode()) == (junk[0] == "-")
    rows[29_000] = rows[29_000].replace(",-1,", ",+1,", 1)
    assert not check(tmp_path / "gt.txt", "\n".join(rows).encode())
    rows[29_000] = rows[29_000].replace(",+1,", ",1e0,", 1)
    assert check(tmp_path / "gt.txt", "\n".join(rows).encode())
    # more than 1 field in 64 for Python's float(): the careful reader reads the file
    odd = [row.replace(",-1,-1,-1", ",-1,-1,1e0") for row in rows]
    assert not check(tmp_path / "gt.txt", "\n".join(odd).encode())


def test_the_shared_files_read_as_the_careful_reader_reads_them():
    """Every det.txt and gt.txt beside this checkout (MOT15, MOT16, MOT17, MOT20, KITTI) is read
    by the plain reader, to the careful reader's bits, and so with CRLF line ends or a
    byte-order mark."""
    files = sorted((SHARED / "data").rglob("det.txt")) + sorted((SHARED / "data").rglob("gt.txt"))
    if not files:
        pytest.skip(f"no MOTChallenge files under {SHARED / 'data'}")
    for p in files:
        data = p.read_bytes()
        assert outcome(read_mot, p) == outcome(careful, p), p
        plain, text = _parse_plain(data), data.decode("utf-8-sig")
        assert plain is not None, p
        assert same_bits(plain, _parse_lines(str(p), text, text.splitlines())), p
        for variant in (data.replace(b"\n", b"\r\n"), b"\xef\xbb\xbf" + data):
            v = _parse_plain(variant)
            assert v is not None and same_bits(v, plain), p


# ---------------------------------------------------------------------------- fuzzing

def _number(r: random.Random) -> str:
    kind = r.randrange(10)
    if kind < 3:
        return str(r.randrange(-20, 3000))
    if kind < 6:
        return f"{r.uniform(-1e4, 1e4):.{r.randrange(7)}f}"
    if kind == 6:
        return repr(r.uniform(-1e5, 1e5))  # up to 17 digits
    if kind == 7:
        return f"{r.uniform(-1, 1) * 10 ** r.randrange(-8, 9):.{r.randrange(1, 9)}g}"
    if kind == 8:
        return r.choice(["-0", "0.", ".5", "-.25", "007", "1e5", "-0.0", "1.0e-3"])
    return "".join(r.choice("0123456789") for _ in range(r.randrange(1, 20))) + r.choice(
        ["", ".", "." + "".join(r.choice("0123456789") for _ in range(r.randrange(1, 12)))])


def mot_text(seed: int) -> str:
    """Rows of one width with values of every kind, as tracker outputs and datasets write them,
    frames and ids integers mostly."""
    r = random.Random(seed)
    width = r.randrange(6, 11)
    rows = []
    for _ in range(r.randrange(1, 12)):
        head = [str(r.randrange(1, 60)), str(r.randrange(-1, 30))] if r.random() < 0.9 else [
            _number(r), _number(r)]
        rows.append(",".join(head + [_number(r) for _ in range(width - 2)]))
    return "\n".join(rows) + r.choice(["", "\n", "\n\n"])


# lines that hold no row, or a row with a comment
NOT_ROWS = ["", "  ", "\t", "#", "# a comment", "# frame,id,left,top", "  # indented, comma",
            "#1,1,1,1,1,1"]


@pytest.mark.parametrize("seed", range(200))
def test_each_row_is_on_the_line_messages_name(tmp_path, seed):
    """The careful reader's row i is on line _row_lines(lines)[i], the line its messages name,
    whichever of its parsers (numpy's reader, or line by line) read the file: blank lines,
    comment lines and comments hold no row. The oracle: each of those lines read alone gives
    that row, to the bit, and they are as many as the rows."""
    r = random.Random(seed)
    lines = mot_text(seed).splitlines()
    for _ in range(r.randrange(1, 5)):
        lines.insert(r.randrange(len(lines) + 1), r.choice(NOT_ROWS))
    k = r.randrange(len(lines))
    if lines[k].strip() and not lines[k].lstrip().startswith("#"):
        lines[k] += r.choice([" # note", "#", "# x,y", ","])  # a comment, or a trailing comma
    if r.random() < 0.3:
        lines = [line.replace(",", " ") for line in lines]
    text = "\n".join(lines) + "\n"
    try:
        a = _parse_lines("gt.txt", text, lines)
    except MOTFormatError:
        return
    where = _row_lines(lines)
    assert len(where) == len(a), text
    for i, n in enumerate(where):
        alone = _parse_lines("gt.txt", lines[n - 1], [lines[n - 1]])
        assert same_bits(alone[0], a[i]), (text, n)


FUZZ = settings(max_examples=1500, derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow])


@pytest.mark.slow
@FUZZ
@given(kinds=st.lists(st.sampled_from(KINDS), max_size=3), seed=st.integers(0, 2 ** 32 - 1))
def test_fuzz_plain_and_careful_readers_agree(tmp_path_factory, kinds, seed):
    """Valid files (plain numbers, exponents, 17 digits, -0, '.5', '5.') with none, one or more
    kinds of damage (junk, a dropped comma, NaN, a byte-order mark, CRLF, truncation, a blank or
    doubled line, a stray byte): the same table or the same message."""
    path = tmp_path_factory.getbasetemp() / "plain-fuzz.txt"
    r = random.Random(seed)
    for k in ([], kinds, r.sample(KINDS, r.randrange(1, 4))):
        s = r.randrange(2 ** 32)
        check(path, damage(mot_text(s), k, s))

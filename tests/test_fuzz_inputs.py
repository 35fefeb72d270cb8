"""Fuzzing the text readers with Hypothesis: random bytes, and valid-looking files with random
damage (a field replaced by junk, a comma dropped, NaN, a byte-order mark, CRLF, truncation).
Each reader either returns a valid result or raises its documented error naming the file (and
the line, for a bad row): never another exception. Derandomized, so every run tries the same
cases; 12,000 per reader."""

from __future__ import annotations

import random
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vistrack.config import ConfigError, TrackConfig, config_toml, read_config
from vistrack.io import MOTFormatError, read_mot, read_seqinfo

# about 24 s on an idle 2-CPU machine (50-100 s when it is loaded): more than the ~20 s a test
# outside the slow set may take
pytestmark = pytest.mark.slow

# each example checks PER inputs (the drawn one and PER - 1 more from its seed), which cuts
# Hypothesis' overhead per input: 2 tests x 2,000 examples x 3 = 12,000 inputs per reader
EXAMPLES, PER = 2000, 3
FUZZ = settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz")
    return {k: d / k for k in ("gt.txt", "seqinfo.ini", "track.toml")}


# ------------------------------------------------------------------------------ damage
# Hypothesis draws the kinds of damage and a seed; the details come from random.Random(seed),
# which is much faster than drawing each from Hypothesis (thousands of cases in seconds)

JUNK = ["", "x", "nan", "NaN", "inf", "-inf", "1e999", "--1", "1,,2", "0x10", "\ufeff", "\x00",
        "é", "1e308", "-0", "9" * 30, "1_0", " ", "\t", "\r", "#", '"1"', "1.5.2", "١", "[",
        "]", "=", '"', "'", "{", "\\", "%", "%(x)s", "\u2028", "\x0c"]
KINDS = ["junk", "comma", "nan", "bom", "crlf", "cut", "blank", "dup", "byte"]


def _junk(r: random.Random) -> str:
    if r.random() < 0.8:
        return r.choice(JUNK)
    return "".join(chr(r.choice([r.randrange(32, 127), r.randrange(0, 0x3000)]))
                   for _ in range(r.randrange(1, 6)))


def damage(text: str, kinds: list[str], seed: int) -> bytes:
    """``text`` with the damage of ``kinds``, as bytes."""
    r = random.Random(seed)
    for kind in kinds:
        if kind == "junk" and text:  # a field or a stretch replaced by junk
            i = r.randrange(len(text))
            text = text[:i] + _junk(r) + text[min(len(text), i + r.randrange(9)):]
        elif kind == "comma" and "," in text:
            i = r.choice([m.start() for m in re.finditer(",", text)])
            text = text[:i] + text[i + 1:]
        elif kind == "nan":
            text = text.replace(r.choice("1052="), r.choice(["nan", "inf", "-nan"]), 1)
        elif kind == "bom":
            text = "\ufeff" + text
        elif kind == "crlf":
            text = text.replace("\n", "\r\n")
        elif kind == "cut":
            text = text[: r.randrange(len(text) + 1)]
        elif kind == "blank":
            lines = text.split("\n")
            lines.insert(r.randrange(len(lines) + 1), r.choice(["", " ", "\t"]))
            text = "\n".join(lines)
        elif kind == "dup":
            lines = text.split("\n")
            k = r.randrange(len(lines))
            lines.insert(k, lines[k])
            text = "\n".join(lines)
    data = text.encode("utf-8")
    if "byte" in kinds:  # a stray non-UTF-8 or NUL byte
        i = r.randrange(len(data) + 1)
        data = data[:i] + r.choice([b"\xff", b"\x00", b"\xe9", b"\xc3"]) + data[i:]
    return data


DAMAGE = st.lists(st.sampled_from(KINDS), max_size=3)
SEED = st.integers(0, 2 ** 32 - 1)


def more_bytes(data: bytes, seed: int) -> list[bytes]:
    """``data`` and PER - 1 random byte strings from ``seed``: mostly printable, some not."""
    r = random.Random(seed)
    out = [data]
    for _ in range(PER - 1):
        n = r.randrange(300)
        out.append(r.randbytes(n) if r.random() < 0.5 else
                   bytes(r.choice(b"0123456789,.-\n\r =[]\"#e\xff\x00") for _ in range(n)))
    return out


def variants(kinds: list[str], seed: int) -> list[tuple[list[str], int]]:
    """The drawn damage, and PER - 1 more random ones from ``seed``."""
    r = random.Random(seed)
    return [(kinds, seed)] + [(r.sample(KINDS, r.randrange(4)), r.randrange(2 ** 32))
                              for _ in range(PER - 1)]


def _number(r: random.Random) -> str:
    return str(r.randrange(-5, 2000)) if r.random() < 0.5 else f"{r.uniform(-1e4, 1e4):.2f}"


def mot_text(seed: int) -> str:
    r = random.Random(seed)
    width = r.randrange(6, 11)
    rows = [",".join([str(r.randrange(1, 51)), str(r.randrange(-1, 21))]
                     + [_number(r) for _ in range(width - 2)]) for _ in range(r.randrange(7))]
    return "\n".join(rows) + ("\n" if r.random() < 0.5 else "")


# ------------------------------------------------------------------------- properties


def _lines(data: bytes) -> int:
    return len(data.decode("utf-8-sig", errors="replace").splitlines())


def check_mot(path, data: bytes) -> None:
    path.write_bytes(data)
    try:
        t = read_mot(path)
    except MOTFormatError as e:
        msg = str(e)
        if msg.startswith(f"{path} is not a text MOTChallenge file ("):
            return
        m = re.match(re.escape(str(path)) + r", line (\d+), column (\d+) \(", msg)
        assert m, msg
        assert 1 <= int(m[1]) <= _lines(data) and 1 <= int(m[2]) <= 11, msg
        return
    assert 6 <= t.columns <= 10 or len(t) == 0
    assert (t.frames >= 1).all() and (np.diff(t.frames) >= 0).all()
    assert np.isfinite(t.boxes).all() and (t.boxes[:, 2:] >= 0).all()
    assert np.isfinite(t.conf).all() and t.path == str(path)


def check_seqinfo(path, data: bytes) -> None:
    path.write_bytes(data)
    try:
        info = read_seqinfo(path)
    except MOTFormatError as e:
        assert str(e).startswith(str(path)), str(e)
        return
    assert 0 < info.frame_rate < np.inf and info.seq_length > 0
    assert info.im_width > 0 and info.im_height > 0


def check_config(path, data: bytes) -> None:
    path.write_bytes(data)
    try:
        cfg = read_config(path)
    except ConfigError as e:
        assert str(e).startswith(str(path)), str(e)
        return
    assert isinstance(cfg, TrackConfig)


# --------------------------------------------------------------------------------- mot


@FUZZ
@given(data=st.binary(max_size=300), seed=SEED)
def test_read_mot_random_bytes(files, data, seed):
    for d in more_bytes(data, seed):
        check_mot(files["gt.txt"], d)


@FUZZ
@given(kinds=DAMAGE, seed=SEED)
def test_read_mot_damaged_rows(files, kinds, seed):
    for k, s in variants(kinds, seed):
        check_mot(files["gt.txt"], damage(mot_text(s), k, s))


# ----------------------------------------------------------------------------- seqinfo

INI_KEYS = ["name", "imDir", "frameRate", "seqLength", "imWidth", "imHeight", "imExt"]


INI_VALUES = {"name": "MOT17-04", "imDir": "img1", "frameRate": "30", "seqLength": "1050",
              "imWidth": "1920", "imHeight": "1080", "imExt": ".jpg"}


def seqinfo_text(seed: int) -> str:
    r = random.Random(seed)
    lines = ["[Sequence]"] if r.random() < 0.9 else []
    for key in r.sample(INI_KEYS, len(INI_KEYS)):
        if r.random() < 0.85:
            value = INI_VALUES[key] if r.random() < 0.75 else r.choice([_junk(r), _number(r)])
            lines.append(f"{key}{r.choice(['=', ' = ', ':', ''])}{value}")
    return "\n".join(lines) + "\n"


@FUZZ
@given(data=st.binary(max_size=300), seed=SEED)
def test_read_seqinfo_random_bytes(files, data, seed):
    for d in more_bytes(data, seed):
        check_seqinfo(files["seqinfo.ini"], d)


@FUZZ
@given(kinds=DAMAGE, seed=SEED)
def test_read_seqinfo_damaged(files, kinds, seed):
    for k, s in variants(kinds, seed):
        check_seqinfo(files["seqinfo.ini"], damage(seqinfo_text(s), k, s))


# ------------------------------------------------------------------------------ config

TOML = [config_toml(TrackConfig.preset(name).with_values(motion={"std_pos": 0.1}),
                    {"frame_rate": 30.0}) for name in ("sort", "bytetrack")]
# the table lines and a few of each table's, so damage lands on them often
SHORT = ['[tracker]\nname = "sort"\nhigh = 0.6\n[offline]\nenabled = true\nmax_gap = 1.0\n',
         "[motion]\nstd_pos = 0.05\nstd_meas = [0.1, 0.1, 0.2, 0.2]\n"]


TEXTS = TOML + SHORT


@FUZZ
@given(data=st.binary(max_size=300), seed=SEED)
def test_read_config_random_bytes(files, data, seed):
    for d in more_bytes(data, seed):
        check_config(files["track.toml"], d)


@FUZZ
@given(text=st.sampled_from(TOML + SHORT), kinds=DAMAGE, seed=SEED)
def test_read_config_damaged(files, text, kinds, seed):
    for k, s in variants(kinds, seed):
        check_config(files["track.toml"], damage(TEXTS[s % len(TEXTS)] if s != seed else text,
                                                 k, s))

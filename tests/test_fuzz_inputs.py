"""Fuzzing the text readers and ``vistrack eval`` with Hypothesis: random bytes, and
valid-looking files with random damage (a field replaced by junk, a comma dropped, NaN, a
byte-order mark, CRLF, truncation; for eval also ids twice in a frame, huge numbers, results of
another sequence ...). Each reader either returns a valid result or raises its documented error
naming the file (and the line, for a bad row): never another exception; eval scores in range or
does the same. Derandomized, so every run tries the same cases; 12,000 per reader, 10,000 for
eval."""

from __future__ import annotations

import random
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vistrack.config import ConfigError, TrackConfig, config_toml, read_config
from vistrack.io import MOTFormatError, read_mot, read_seq_length, read_seqinfo

# about 24 s for the readers and 30 s for eval on an idle 2-CPU machine (two to four times that
# when it is loaded): more than the ~20 s a test outside the slow set may take
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
        m = re.match(re.escape(str(path)) + r", line (\d+), column (\d+)[ :(]", msg)
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


# -------------------------------------------------------------------------------- eval
# vistrack eval (evaluation.evaluate_files, and through the command line): a ground-truth file,
# a results file and maybe a seqinfo.ini, each random bytes or a valid-looking file with random
# damage: an id twice in a frame, a negative size, NaN, huge numbers, an empty file, ids all -1,
# classes out of range, results of another sequence, a sequence shorter than the files, and the
# readers' damage above. Each pair either scores, with every score finite and in its range, or
# raises ValueError (MOTFormatError is one) naming one of the files, and the line of a bad row.
# (500 random-bytes + 1,250 damaged + 750 command-line examples) x 4 = 10,000 cases.

EVAL_PER = 4
EVAL_BYTES = settings(FUZZ, max_examples=500)
EVAL = settings(FUZZ, max_examples=1250)
EVAL_CLI = settings(FUZZ, max_examples=750)
EVAL_KINDS = ["dupid", "negsize", "nan", "huge", "empty", "det", "class", "bigframe", "bigid",
              "columns", "text"]
HUGE = ["1e308", "-1e308", "1.7976931348623157e308", "1e300", "-1e300", "4e153", "1e200",
        "9007199254740992", "-9007199254740992", "9007199254740993", "1e16", "2e9", "-0",
        "123456789012345678901234567890"]
BENCHMARKS = ["auto", "auto", "auto", "MOT15", "MOT16", "MOT17", "MOT20"]
FRACTIONS = ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr", "MOTP", "IDF1",
             "IDP", "IDR")


@pytest.fixture(scope="module")
def eval_files(tmp_path_factory):
    """seq/gt/gt.txt, seq/seqinfo.ini (beside the gt/ folder, where vistrack eval looks) and
    res.txt, shared by every case."""
    d = tmp_path_factory.mktemp("eval")
    (d / "seq" / "gt").mkdir(parents=True)
    return d / "seq" / "gt" / "gt.txt", d / "res.txt", d / "seq" / "seqinfo.ini"


def _cell(r: random.Random, v: float) -> str:
    return str(int(v)) if v == int(v) and r.random() < 0.5 else f"{v:.2f}"


def eval_rows(seed: int) -> tuple[list[list[str]], list[list[str]], int]:
    """Ground-truth rows (MOT15's 10 values, or MOT17's 9) and result rows of one short made-up
    sequence, cells as text, and its length."""
    r = random.Random(seed)
    frames, mot15 = r.randrange(1, 5), r.random() < 0.4
    gt, res = [], []
    for obj in range(1, r.randrange(0, 5) + 1):
        x, y, vx = r.uniform(-20, 300), r.uniform(-20, 200), r.uniform(-15, 15)
        w = r.uniform(5, 60) if r.random() > 0.05 else r.choice([0.0, r.uniform(1, 5)])
        h = r.uniform(10, 120)
        pid = obj + r.choice([0, 0, 50])
        # MOT17: mostly pedestrians, some distractors (their matches are dropped) and others
        cls, consider = r.choice([1, 1, 1, 1, 1, 1, 2, 3, 7, 8, 12]), r.random() < 0.9
        for f in range(1, frames + 1):
            if r.random() < 0.15:
                continue
            box = [x + vx * f, y, w, h]
            tail = (["1", "-1", "-1", "-1"] if mot15 else
                    [str(int(consider or r.random() < 0.2)), str(cls), f"{r.random():.2f}"])
            gt.append([str(f), str(obj)] + [_cell(r, v) for v in box] + tail)
            if r.random() < 0.85:
                if r.random() < 0.1:
                    pid += 100  # an identity switch
                jit = [v + r.gauss(0, 0.05) * s for v, s in zip(box, [w, h, w, h])]
                res.append([str(f), str(pid)] + [_cell(r, v) for v in jit]
                           + [f"{r.random():.3f}", "-1", "-1", "-1"])
    for k in range(r.randrange(3)):  # false positives
        res.append([str(r.randrange(1, frames + 1)), str(500 + k)]
                   + [_cell(r, r.uniform(0, 300)) for _ in range(2)]
                   + [_cell(r, r.uniform(1, 80)) for _ in range(2)] + ["0.5", "-1", "-1", "-1"])
    if r.random() < 0.1:  # results of another sequence: other frames, or boxes elsewhere
        shift = r.choice([(frames, 0.0), (0, 1000.0)])
        res = [[str(int(c[0]) + shift[0]), c[1], _cell(r, float(c[2]) + shift[1])] + c[3:]
               for c in res]
    for rows in (gt, res):
        if r.random() < 0.3:
            r.shuffle(rows)  # read_mot sorts them
    return gt, res, frames


def damage_rows(rows: list[list[str]], kinds: list[str], seed: int) -> bytes:
    """The rows with the damage of ``kinds``, as the bytes of a file."""
    r = random.Random(seed)
    rows = [list(c) for c in rows]
    for kind in kinds:
        k = r.randrange(len(rows)) if rows else None
        if kind == "dupid" and rows:  # the same id twice in a frame
            twin = list(rows[k])
            if np.isfinite(x := float(twin[2])):  # (an earlier damage may have made it NaN)
                twin[2] = f"{x + r.uniform(-5, 5):.2f}"
            rows.insert(r.randrange(len(rows) + 1), twin)
        elif kind == "negsize" and rows and len(rows[k]) > 5:  # (not a row "columns" cut)
            rows[k][r.choice([4, 5])] = r.choice(["-1", "-0.01", "-0", "-1e308"])
        elif kind == "nan" and rows:
            rows[k][r.randrange(len(rows[k]))] = r.choice(["nan", "NaN", "inf", "-inf"])
        elif kind == "huge" and rows:
            # not in the class column (8) beyond int64: read_mot (vistrack.io.motchallenge)
            # casts it to int64 unchecked, a wrong class and a RuntimeWarning
            j = r.randrange(len(rows[k]))
            rows[k][j] = r.choice(HUGE if j != 7 else [h for h in HUGE if abs(float(h)) < 2**63])
        elif kind == "empty":
            rows = []
        elif kind == "det":  # a detections file: every id -1
            for c in rows:
                c[1] = "-1"
        elif kind == "class" and rows and len(rows[k]) > 7:
            rows[k][7] = r.choice(["-1", "0", "14", "99", "1000000", "2.5"])
        elif kind == "bigframe" and rows:
            rows[k][0] = r.choice(["9007199254740992", "1000000000", "100000", "5"])
        elif kind == "bigid" and rows:
            for c in r.sample(rows, r.randrange(1, len(rows) + 1)):
                c[1] = r.choice(["4503599627370496", "-4503599627370496", "9007199254740992",
                                 "-9007199254740991", "2048"])
        elif kind == "columns" and rows:  # a row of another width
            rows[k] = rows[k][:r.randrange(4, 11)] + ["1"] * r.randrange(2)
    text = "".join(",".join(c) + "\n" for c in rows) if r.random() < 0.9 else \
        "\n".join(",".join(c) for c in rows)
    if "text" in kinds:  # the readers' damage: junk, a dropped comma, a BOM, CRLF, a cut ...
        return damage(text, r.sample(KINDS, r.randrange(1, 4)), r.randrange(2 ** 32))
    return text.encode()


def seqinfo_for(frames: int, seed: int) -> bytes | None:
    """seqinfo.ini for a sequence of ``frames`` frames: none, right, too short, or damaged."""
    r = random.Random(seed)
    x = r.random()
    if x < 0.4:
        return None
    length = frames if x < 0.85 else r.choice([max(1, frames - 1), frames + 3, 1])
    text = (f"[Sequence]\nname=seq\nimDir=img1\nframeRate=30\nseqLength={length}\n"
            "imWidth=640\nimHeight=480\nimExt=.jpg\n")
    if r.random() < 0.05:
        return damage(text, r.sample(KINDS, r.randrange(1, 4)), r.randrange(2 ** 32))
    return text.encode()


def eval_case(seed: int, gt_kinds: list[str], res_kinds: list[str]):
    """The bytes of ground truth, results and seqinfo.ini (or None), and the benchmark."""
    r = random.Random(seed)
    gt, res, frames = eval_rows(seed)
    return (damage_rows(gt, gt_kinds, r.randrange(2 ** 32)),
            damage_rows(res, res_kinds, r.randrange(2 ** 32)),
            seqinfo_for(frames, r.randrange(2 ** 32)), r.choice(BENCHMARKS))


def eval_variants(seed: int, gt_kinds: list[str], res_kinds: list[str]):
    """The drawn case and EVAL_PER - 1 more from ``seed`` (each file damaged half the time),
    each with whether it is undamaged."""
    r = random.Random(seed)
    out = [(*eval_case(seed, gt_kinds, res_kinds), not (gt_kinds or res_kinds))]
    for _ in range(EVAL_PER - 1):
        kinds = [r.sample(EVAL_KINDS, r.randrange(1, 3)) if r.random() < 0.5 else []
                 for _ in range(2)]
        out.append((*eval_case(r.randrange(2 ** 32), *kinds), not (kinds[0] or kinds[1])))
    return out


def _row(data: bytes, line: int) -> list[float]:
    """The numbers of line ``line`` (from 1) of a MOTChallenge file, read independently."""
    text = data.decode("utf-8-sig").splitlines()[line - 1]
    return [float(c) for c in text.split("#", 1)[0].split(",")]


def check_eval_error(msg: str, files: dict) -> None:
    """``msg`` names one of ``files`` (path: its bytes) first, then the line(s) of a bad row;
    the lines named hold the rows the message speaks of."""
    path = next((p for p in files if msg.startswith(str(p))), None)
    assert path is not None, msg
    rest = msg[len(str(path)):]
    m = re.match(r", lines? (\d+)(?: and (\d+))?", rest)
    lines = [int(k) for k in m.groups() if k] if m else []
    data = files[path]
    assert all(1 <= k <= _lines(data) for k in lines), msg
    dup = re.search(r": id (-?\d+) appears more than once in frame (\d+)", rest)
    if dup:
        assert len(lines) == 2 and lines[0] < lines[1], msg
        for k in lines:
            assert _row(data, k)[:2] == [float(dup[2]), float(dup[1])], msg
    beyond = re.search(r": frame (\d+) is beyond the sequence's (\d+) frames", rest)
    if beyond:
        assert len(lines) == 1 and _row(data, lines[0])[0] == float(beyond[1]), msg
        assert int(beyond[1]) > int(beyond[2]), msg
    cls = re.search(r": class (\S+) is not a MOT\d\d class", rest)
    if cls:  # the line of a class out of range, or a file without classes (6-7 values a row)
        if lines:  # the value as written, every digit
            assert len(lines) == 1 and _row(data, lines[0])[7] == float(cls[1]), msg
        else:
            assert read_mot(path).columns <= 7 and cls[1] == "-1", msg


def check_scores(s: dict, gt_rows: int, res_rows: int, frames: int) -> None:
    """``s`` (MOTCounts.summary) holds finite scores in their ranges and counts that add up."""
    for k in FRACTIONS:
        assert 0.0 <= s[k] <= 1.0, (k, s[k])
    assert np.isfinite(s["MOTA"]) and s["MOTA"] <= 1.0
    assert all(v >= 0 for k, v in s.items() if isinstance(v, int))
    assert s["TP"] + s["FN"] == s["gt_dets"] <= gt_rows
    assert s["TP"] + s["FP"] == s["pred_dets"] <= res_rows
    assert s["IDTP"] + s["IDFN"] == s["gt_dets"] and s["IDTP"] + s["IDFP"] == s["pred_dets"]
    assert s["MT"] + s["PT"] + s["ML"] == s["gt_ids"] and s["IDSW"] <= s["TP"]
    assert s["frames"] == frames


def run_eval(paths, gt: bytes, res: bytes, info: bytes | None, benchmark: str) -> None:
    from vistrack.evaluation import evaluate_files

    gt_path, res_path, info_path = paths
    gt_path.write_bytes(gt)
    res_path.write_bytes(res)
    if info is not None:
        info_path.write_bytes(info)
    try:
        out = evaluate_files([("seq", gt_path, res_path, None if info is None else info_path)],
                             benchmark=benchmark)
    except ValueError as e:  # MOTFormatError is one
        check_eval_error(str(e), {gt_path: gt, res_path: res, info_path: info})
        return
    g, p = read_mot(gt_path), read_mot(res_path)
    frames = (read_seq_length(info_path) if info is not None else
              int(max([0, *g.frames[-1:], *p.frames[-1:]])))
    c = out["seq"]
    check_scores(c.summary(), len(g), len(p), frames)
    assert (c.HOTA_TP + c.HOTA_FN == c.gt_dets).all() and (c.HOTA_TP + c.HOTA_FP ==
                                                           c.pred_dets).all()
    assert (np.diff(c.HOTA_TP) <= 0).all()  # fewer matches at a higher IoU threshold
    for w in out.warnings:
        assert "\n" not in w and (str(gt_path) in w or str(res_path) in w), w


@EVAL_BYTES
@given(data=st.binary(max_size=300), which=st.sampled_from(["gt", "res", "info"]), seed=SEED)
def test_eval_random_bytes(eval_files, data, which, seed):
    """One of the three files random bytes, the others valid (from ``seed``)."""
    r = random.Random(seed)
    for k, junk in enumerate(more_bytes(data, seed) + [r.randbytes(r.randrange(200))]):
        gt, res, info, bench = eval_case(r.randrange(2 ** 32), [], [])
        part = which if k == 0 else r.choice(["gt", "res", "info"])
        gt, res = (junk if part == "gt" else gt), (junk if part == "res" else res)
        run_eval(eval_files, gt, res, junk if part == "info" else info, bench)


def scaled(data: bytes, exponent: int) -> bytes:
    """A MOTChallenge file with every box (left, top, width, height) times 2**exponent: the
    same boxes to IoU, exactly (a power of two), in numbers up to about 1e300."""
    rows = [line.split(",") for line in data.decode().splitlines() if line.strip()]
    return "".join(",".join(c[:2] + [repr(float(v) * 2.0 ** exponent) for v in c[2:6]] + c[6:])
                   + "\n" for c in rows).encode()


@EVAL
@given(gt_kinds=st.lists(st.sampled_from(EVAL_KINDS), max_size=2),
       res_kinds=st.lists(st.sampled_from(EVAL_KINDS), max_size=2), seed=SEED)
def test_eval_damaged(eval_files, gt_kinds, res_kinds, seed):
    """Valid-looking files with random damage. An undamaged pair is also scored with its boxes
    scaled by 2**k up to 1e300 (the same scores, exactly), and its ground truth against itself
    (every box of positive area matched)."""
    from vistrack.evaluation import evaluate_files

    gt_path, res_path, info_path = eval_files
    r = random.Random(seed)
    for gt, res, info, bench, whole in eval_variants(seed, gt_kinds, res_kinds):
        run_eval(eval_files, gt, res, info, bench)
        if not (whole and gt and res):
            continue
        try:  # scored without seqinfo.ini (which may be short), under this benchmark
            before = evaluate_files([("seq", gt_path, res_path, None)], benchmark=bench)
        except ValueError as e:  # MOT15 ground truth under --benchmark MOT17
            assert "is not a MOT" in str(e), str(e)
            continue
        k = r.randrange(400, 990)
        gt_path.write_bytes(scaled(gt, k))
        res_path.write_bytes(scaled(res, k))
        after = evaluate_files([("seq", gt_path, res_path, None)], benchmark=bench)
        assert after["seq"].summary() == before["seq"].summary()
        assert after.warnings == before.warnings
        rows = [c.split(",") for c in gt.decode().splitlines() if c.strip()]
        if len(rows[0]) == 10 and bench in ("auto", "MOT15"):  # MOT15 ground truth, conf 1
            gt_path.write_bytes(gt)
            itself = evaluate_files([("seq", gt_path, gt_path, None)], benchmark=bench)["seq"]
            boxes = sum(float(c[4]) * float(c[5]) > 0 for c in rows)
            assert (itself.TP, itself.FP, itself.FN, itself.IDSW) == (
                boxes, len(rows) - boxes, len(rows) - boxes, 0)


@EVAL_CLI
@given(gt_kinds=st.lists(st.sampled_from(EVAL_KINDS), max_size=2),
       res_kinds=st.lists(st.sampled_from(EVAL_KINDS), max_size=2), seed=SEED)
def test_eval_command_line(eval_files, gt_kinds, res_kinds, seed):
    """``vistrack eval --gt seq/gt/gt.txt --pred res.txt`` (seqinfo.ini read beside): status 0
    with the table or JSON on stdout and one-line warnings, or status 2 with one line
    ``vistrack eval: error: FILE...`` and nothing on stdout."""
    import contextlib
    import io
    import json

    from vistrack.cli import main

    gt_path, res_path, info_path = eval_files
    r = random.Random(seed)
    for *files, bench, _ in eval_variants(seed, gt_kinds, res_kinds):
        if r.random() < 0.1:
            files[r.randrange(3)] = r.randbytes(r.randrange(100))
        gt, res, info = files
        gt_path.write_bytes(gt)
        res_path.write_bytes(res)
        info_path.unlink(missing_ok=True)
        if info is not None:
            info_path.write_bytes(info)
        as_json = r.random() < 0.5
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main(["eval", "--gt", str(gt_path), "--pred", str(res_path),
                           "--benchmark", bench] + ["--json"] * as_json)
        out, err = out.getvalue(), err.getvalue()
        if status == 2:
            assert out == ""
            assert err.count("\n") == 1 and err.endswith("\n"), err
            assert re.match("vistrack eval: error: (" + "|".join(
                re.escape(str(p)) for p in eval_files) + ")", err), err
            continue
        assert status == 0, (status, err)
        assert all(line.startswith("vistrack eval: warning: ") for line in err.splitlines())
        if as_json:
            s = json.loads(out)["seq"]
            assert len(s) == 29 and all(np.isfinite(v) for v in s.values())
            g, p = read_mot(gt_path), read_mot(res_path)
            frames = (read_seq_length(info_path) if info is not None else
                      int(max([0, *g.frames[-1:], *p.frames[-1:]])))
            check_scores(s, len(g), len(p), frames)
        else:
            head, row = out.splitlines()
            assert head.split()[:4] == ["sequence", "HOTA", "DetA", "AssA"]
            assert row.split()[0] == "seq" and len(row.split()) == len(head.split())
            # each value ends under its header (the columns are apart and aligned)
            ends = [[m.end() for m in re.finditer(r"\S+", line)][1:] for line in (head, row)]
            assert ends[0] == ends[1], out

"""The command lines shown in README.md and docs/ print what the docs say they print.

Each fenced block, without a language or marked ``text`` or ``console``, whose first line
starts with ``$ `` is a transcript: every ``$`` line is run with a shell, from a folder laid
out as the project's root (``src/``, ``examples/``, ``bench/`` and ``../shared``) with an
``out/`` in it, as the README's first command leaves one, and what it writes to stdout and
stderr is compared with the lines shown under it. Times are the one thing left out:
frames/s, the milliseconds a frame, a batch's seconds, and the note a first run gives when
it compiles. Lines are compared as a multiset (a batch's pool finishes its inputs in any
order); where the docs elide lines with ``...``, the lines shown must each be printed.
Blocks that cannot run as written are listed in ``NOT_RUN`` with the reason. README's
``python`` blocks run in order in one namespace, each printing the output shown under it.
"""

import os
import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from .conftest import SHARED, need

ROOT = Path(__file__).resolve().parents[1]
FILES = ("README.md", "docs/mot.md", "docs/scaling.md", "docs/frontends.md")

NOT_RUN = {
    "vistrack track video.mp4 --frontend onnx:yolo11n.onnx":
        "the user's own video and ONNX model, neither shipped",
    "vistrack track KITTI-0004-Car-every-6th":
        "a sequence folder the section builds in prose",
    "vistrack track dup09.txt":
        "a detections file the section builds in prose",
    "mkdir myset":
        "a benchmark: its tables are measurements, times included",
    "cat centre.toml":
        "a benchmark: its tables are measurements, times included",
    "vistrack eval --gt-dir ../shared/data/mot17 --pred-dir out/mot17":
        "a results folder made by hand, with a malformed line 12",
}

# blocks that read a folder of the shared data under another name, as the prose says
LINKED = {"vistrack track KITTI-0004-Car --scores raw":
          ("KITTI-0004-Car", "data/kitti-tracking/KITTI-0004-Car")}

TIMES = (
    (re.compile(r"\d[\d.,]* frames/s"), "N frames/s"),
    (re.compile(r"\(ms a frame:[^)]*\)"), "(ms a frame: N)"),
    # a batch's progress lines: the order of completion, and the seconds each took
    (re.compile(r"^\[\d+/(\d+)\] (.*), \d+(\.\d+)? s$"), r"[i/\1] \2, N s"),
    # a batch's table: input, status, frames, tracks, seconds, output
    (re.compile(r"^(\S+ +\S+ +\d+ +\d+ +)\d+\.\d( +\S)"), r"\1N\2"),
    # kernels compiled on first use, where the ahead-of-time build did not serve the call
    (re.compile(r"; compiling took \d+(\.\d+)? s"), ""),
)
# said once where a first run compiles kernels: the machine's state, not the docs'
COMPILING = re.compile(r": compiling its kernels for this machine, once ")


def normalise(line):
    for pattern, repl in TIMES:
        line = pattern.sub(repl, line)
    return " ".join(line.split())


def transcripts(path):
    """``(line, [(command, [expected lines])])`` for each transcript block of ``path``."""
    lines = path.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        if not lines[i].lstrip().startswith("```"):
            i += 1
            continue
        plain = lines[i].strip()[3:] in ("", "text", "console")
        j = i + 1
        while lines[j].strip() != "```":
            j += 1
        body = lines[i + 1:j]
        if plain and body and body[0].startswith("$ "):
            steps = []
            for text in body:
                if text.startswith("$ "):
                    steps.append((text[2:], []))
                else:
                    steps[-1][1].append(text)
            yield i + 1, steps
        i = j + 1


BLOCKS = [(f"{name}:{line}", steps) for name in FILES
          for line, steps in transcripts(ROOT / name)]


def reason_not_run(steps):
    return next((why for start, why in NOT_RUN.items() if steps[0][0].startswith(start)), None)


def test_every_block_not_run_is_still_in_the_docs():
    firsts = [steps[0][0] for _, steps in BLOCKS]
    stale = [start for start in (*NOT_RUN, *LINKED)
             if not any(f.startswith(start) for f in firsts)]
    assert not stale, f"NOT_RUN or LINKED names blocks no longer in {FILES}: {stale}"
    assert len(BLOCKS) - sum(reason_not_run(s) is not None for _, s in BLOCKS) >= 15


@pytest.mark.slow
@pytest.mark.parametrize("where,steps", BLOCKS, ids=[w for w, _ in BLOCKS])
def test_transcript(where, steps, tmp_path):
    why = reason_not_run(steps)
    if why:
        pytest.skip(f"{where} is not run: {why}")
    if any("../shared" in cmd for cmd, _ in steps):
        need(SHARED)
    root = tmp_path / "root"
    (root / "out").mkdir(parents=True)
    (tmp_path / "shared").symlink_to(SHARED)
    for name in ("src", "examples", "bench"):
        (root / name).symlink_to(ROOT / name)
    for start, (name, target) in LINKED.items():
        if steps[0][0].startswith(start):
            (root / name).symlink_to(need(SHARED / target))
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    for cmd, want in steps:
        run = subprocess.run(cmd, shell=True, cwd=root, env=env, capture_output=True,
                             text=True, timeout=300)
        got = Counter(normalise(x) for x in (run.stdout + run.stderr).splitlines()
                      if not COMPILING.search(x))
        shown = Counter(normalise(x) for x in want if x != "...")
        missing, extra = shown - got, got - shown
        if "..." in want:
            extra = Counter()
        assert not missing and not extra, (
            f"{where}: `$ {cmd}` printed\n{run.stdout}{run.stderr}\n"
            f"lines shown in the docs but not printed: {list(missing)}\n"
            f"lines printed but not shown: {list(extra)}")


def python_blocks(path):
    """``(line, code, shown)`` for each ``python`` block of ``path``, ``shown`` the lines of
    a plain block right after it (its printed output), or None."""
    lines = path.read_text(encoding="utf-8").splitlines()
    fences = [k for k, text in enumerate(lines) if text.lstrip().startswith("```")]
    blocks = list(zip(fences[::2], fences[1::2]))
    for (a, b), after in zip(blocks, [*blocks[1:], None]):
        if lines[a].strip() != "```python":
            continue
        shown = None
        if after is not None and lines[after[0]].strip() == "```" and \
                not "\n".join(lines[b + 1:after[0]]).strip():
            body = lines[after[0] + 1:after[1]]
            shown = None if body and body[0].startswith("$ ") else body
        yield a + 1, "\n".join(lines[a + 1:b]), shown


PYTHON_NOT_RUN = {"from ultralytics import YOLO": "the user's own model and video"}


@pytest.mark.slow
def test_the_readme_python_blocks_run_in_order_and_print_what_is_shown(tmp_path, monkeypatch):
    """README's Python blocks, run one after the other in one namespace as a reader pastes
    them (a block used a name no block defined: NameError), each printing the output block
    shown under it."""
    import contextlib
    import io

    (tmp_path / "out").mkdir()
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    ran = 0
    for line, code, shown in python_blocks(ROOT / "README.md"):
        if any(code.startswith(start) for start in PYTHON_NOT_RUN):
            continue
        printed = io.StringIO()
        with contextlib.redirect_stdout(printed):
            exec(compile(code, f"README.md:{line}", "exec"), namespace)  # noqa: S102
        ran += 1
        if shown is not None:
            assert [normalise(x) for x in printed.getvalue().splitlines()] == \
                [normalise(x) for x in shown], f"README.md:{line} printed {printed.getvalue()}"
    assert ran >= 4

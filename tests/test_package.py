"""What a pip-only user gets: the demo clip as package data, `vistrack demo track`, and a
wheel that carries both and runs the demo from any folder."""

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from vistrack.cli import main
from vistrack.data import demo_clip

ROOT = Path(__file__).resolve().parents[1]


def test_demo_track_is_vistrack_track_on_the_bundled_clip(tmp_path, capsys):
    clip = demo_clip()
    assert clip.video.parent == ROOT / "src" / "vistrack" / "data" / "pets09-s2l1"
    assert main(["demo", "track", "--out", str(tmp_path / "demo")]) == 0
    shown = capsys.readouterr().out
    assert f"tracks  {tmp_path / 'demo' / 'pets09-s2l1' / 'tracks.txt'}" in shown
    assert "pets09-s2l1     " in shown  # the scores against the bundled ground truth
    assert main(["track", str(clip.video), "--gt", str(clip.gt), "--out-dir",
                 str(tmp_path / "track")]) == 0
    for name in ("tracks.txt", "tracks.csv"):
        assert (tmp_path / "demo" / "pets09-s2l1" / name).read_bytes() == \
            (tmp_path / "track" / name).read_bytes()
    # a second run refuses to replace the first's results, and --force replaces them
    assert main(["demo", "track", "--out", str(tmp_path / "demo")]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["demo", "track", "--out", str(tmp_path / "demo"), "--force"]) == 0


@pytest.mark.slow
def test_a_wheel_carries_the_clip_and_runs_the_demo_from_another_folder(tmp_path):
    # the sources as a clean checkout has them, with the kernels `make` compiled beside them
    src = tmp_path / "src-tree"
    src.mkdir()
    for name in ("pyproject.toml", "setup.py", "README.md", "LICENSE"):
        shutil.copy2(ROOT / name, src / name)
    shutil.copytree(ROOT / "src", src / "src",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    dist = tmp_path / "dist"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                    "--no-index", "-q", "-w", str(dist), str(src)], check=True)
    (wheel,) = dist.glob("vistrack-*.whl")
    # a fresh environment with the wheel alone; its dependencies seen from this one's
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    subprocess.run([sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python"),
                    "install", "--no-deps", "--no-index", "-q", str(wheel)], check=True)
    site = subprocess.run([venv / "bin" / "python", "-c",
                           "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          check=True, capture_output=True, text=True).stdout.strip()
    # appended after the wheel's site-packages; this environment's own vistrack (an editable
    # install, found through a .pth file there) is not seen, as .pth files in it are not read
    Path(site, "dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR")}
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "numba-cache")  # empty: nothing compiled before
    where = subprocess.run([venv / "bin" / "python", "-c",
                            "import vistrack; print(vistrack.__file__)"], cwd=elsewhere,
                           env=env, check=True, capture_output=True, text=True).stdout.strip()
    assert Path(where).is_relative_to(site), where
    run = subprocess.run([venv / "bin" / "vistrack", "demo", "track", "--out", "out"],
                         cwd=elsewhere, env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert "compiling" not in run.stderr  # the wheel carries the kernels compiled by make
    assert "pets09-s2l1     " in run.stdout
    mine = tmp_path / "mine"
    assert main(["demo", "track", "--out", str(mine)]) == 0
    for name in ("tracks.txt", "tracks.csv"):
        assert (elsewhere / "out" / "pets09-s2l1" / name).read_bytes() == \
            (mine / "pets09-s2l1" / name).read_bytes()


def test_python_m_vistrack_is_the_command():
    """``python -m vistrack`` runs the ``vistrack`` command (it said "No module named
    vistrack.__main__"): the same version, and a user's mistake's status and message."""
    import vistrack

    r = subprocess.run([sys.executable, "-m", "vistrack", "--version"], capture_output=True,
                       text=True)
    assert r.returncode == 0 and r.stdout.strip() == f"vistrack {vistrack.__version__}"
    r = subprocess.run([sys.executable, "-m", "vistrack", "track", "no-such-file.txt", "--out",
                        "x.txt"], capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.startswith("vistrack track: ")

"""The `vistrack demo kalman` command and the seeds' 2-D example statistics."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from vistrack.cli import main
from vistrack.demo import MURPHY, MURPHY_P0, MURPHY_T, MURPHY_X0, murphy_errors

filterpy_kalman = pytest.importorskip("filterpy.kalman")


def test_demo_writes_the_figures(tmp_path, capsys):
    assert main(["demo", "kalman", "--out", str(tmp_path), "--seeds", "20"]) == 0
    out = capsys.readouterr().out
    for name in ("kalman_1d.png", "smoothing_1d.png", "kalman_2d.png"):
        png = (tmp_path / name).read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
        assert name in out
    assert "mean over 20 seeds" in out
    # the peers' line is stored, and said so (it read as computed beside any --seeds); the
    # slide's run is placed by percentile only among 100 seeds or more (of one seed it was
    # "the 100th / 100th percentile")
    assert "FilterPy and pykalman, 1000 seeds, measured once:" in out
    assert "percentile" not in out and "placed among ours from 100 seeds on" in out


def test_demo_kalman_keeps_earlier_figures_without_force(tmp_path, capsys):
    """A second run replaced the figures without a word, where ``demo track`` (and every
    other command) asks for --force; --seeds given to 'track' was taken and ignored."""
    assert main(["demo", "kalman", "--out", str(tmp_path), "--seeds", "1"]) == 0
    assert "mean over 1 seed:        filtered" in capsys.readouterr().out
    before = {p.name: p.stat().st_mtime_ns for p in tmp_path.glob("*.png")}
    assert main(["demo", "kalman", "--out", str(tmp_path), "--seeds", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("vistrack demo: error: ") and err.rstrip().endswith(
        f"{tmp_path / 'kalman_2d.png'} exist; pass --force to overwrite them")
    assert {p.name: p.stat().st_mtime_ns for p in tmp_path.glob("*.png")} == before
    assert main(["demo", "kalman", "--out", str(tmp_path), "--seeds", "1", "--force"]) == 0
    with pytest.raises(SystemExit):
        main(["demo", "track", "--out", str(tmp_path), "--seeds", "5"])
    assert "--seeds goes with 'vistrack demo kalman'" in capsys.readouterr().err


def test_cli_rejects_bad_arguments(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "nosuchdemo"])
    assert "invalid choice: 'nosuchdemo'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["demo", "kalman", "--seeds", "0"])
    assert "--seeds must be from 1 to 1,000,000; got 0" in capsys.readouterr().err


@pytest.mark.parametrize("seeds", ["1000001", "10000000000", "100000000000000000000"])
def test_demo_kalman_refuses_more_seeds_than_it_runs_before_writing(tmp_path, capsys, seeds):
    """`--seeds 10000000000` ran out of memory (a traceback) after writing the figures, and
    `--seeds 1e20` as digits failed in numpy's words; both are named now, nothing written."""
    with pytest.raises(SystemExit) as e:
        main(["demo", "kalman", "--out", str(tmp_path / "o"), "--seeds", seeds])
    assert e.value.code == 2
    assert f"--seeds must be from 1 to 1,000,000; got {seeds}" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
    with pytest.raises(ValueError, match="n_seeds must be at most 1,000,000"):
        murphy_errors(int(seeds))


def test_demo_kalman_writes_no_figure_when_its_statistics_fail(tmp_path, monkeypatch):
    """The statistics (the long part) ran after the three figures were written: a failure or
    Ctrl-C there left them, new, beside a run that said it failed."""
    import vistrack.demo as demo

    def fail(n_seeds):
        raise MemoryError

    monkeypatch.setattr(demo, "murphy_errors", fail)
    with pytest.raises(MemoryError):
        demo.run_kalman_demo(tmp_path / "o", n_seeds=10)
    assert not (tmp_path / "o").exists()


def test_murphy_errors_in_batches_match_the_published_means(monkeypatch):
    """More runs than one batch are drawn and filtered batch by batch (memory stays that of a
    batch: 10**10 runs ran out of it); the means still agree with FilterPy's and pykalman's
    over 1000 seeds (4.30 and 2.93) within 4 standard errors, and every run is its own."""
    import vistrack.demo as demo

    monkeypatch.setattr(demo, "_CHUNK", 300)
    st = demo.murphy_errors(1000, seed=5)
    assert st.n_seeds == 1000 and st.filtered.shape == st.smoothed.shape == (1000,)
    assert len(np.unique(st.filtered)) == 1000
    assert abs(st.mean_filtered - 4.30) < 4 * st.filtered.std() / np.sqrt(1000)
    assert abs(st.mean_smoothed - 2.93) < 4 * st.smoothed.std() / np.sqrt(1000)
    with pytest.raises(ValueError, match="n_seeds must be a whole number >= 1"):
        demo.murphy_errors(0)


def test_demo_out_that_is_a_file_is_named_as_out(tmp_path, capsys):
    """``--out FILE`` said "FILE: File exists" (kalman) or named ``--out-dir FILE/pets09-s2l1``
    (track), an option the user never gave."""
    afile = tmp_path / "afile"
    afile.write_text("")
    for name in ("kalman", "track"):
        assert main(["demo", name, "--out", str(afile)]) == 2
        assert capsys.readouterr().err == (f"vistrack demo: error: --out {afile} is a file, not "
                                           "a folder\n")
    # and a file where the track demo's run folder goes (named as --out-dir, still)
    folder = tmp_path / "dfile"
    folder.mkdir()
    (folder / "pets09-s2l1").write_text("x\n")
    assert main(["demo", "track", "--out", str(folder)]) == 2
    assert capsys.readouterr().err == (f"vistrack demo: error: --out {folder / 'pets09-s2l1'} "
                                       "is a file, not a folder\n")


def test_console_script_runs():
    r = subprocess.run([sys.executable, "-m", "vistrack.cli", "--version"], capture_output=True,
                       text=True)
    assert r.returncode == 0 and r.stdout.startswith("vistrack ")


def test_the_version_has_one_source():
    """The installed metadata's version is ``vistrack.__version__`` (pyproject reads it)."""
    from importlib.metadata import version

    import vistrack

    assert version("vistrack") == vistrack.__version__
    assert 'dynamic = ["version"]' in (Path(__file__).resolve().parents[1] /
                                       "pyproject.toml").read_text()


def test_murphy_errors_equal_filterpy_per_run_and_match_published_means():
    st = murphy_errors(1000, seed=0)
    # per run: FilterPy's filter on the same simulated tracks gives the same error (first 20 runs)
    from vistrack.simulate import simulate_lgssm

    xs, ys = simulate_lgssm(MURPHY_T, F=MURPHY.F, Q=MURPHY.Q, H=MURPHY.H, R=MURPHY.R,
                            x0=MURPHY_X0, n_series=1000, rng=0)
    for b in range(20):
        kf = filterpy_kalman.KalmanFilter(dim_x=4, dim_z=2)
        kf.F, kf.Q, kf.H, kf.R = MURPHY.F, MURPHY.Q, MURPHY.H, MURPHY.R
        kf.x, kf.P = MURPHY_X0.copy(), MURPHY_P0.copy()
        est = []
        for t in range(MURPHY_T):
            if t:
                kf.predict()
            kf.update(ys[b, t])
            est.append(kf.x[:2].copy())
        err = np.sqrt(((np.array(est) - xs[b, :, :2]) ** 2).sum())
        assert st.filtered[b] == pytest.approx(err, rel=1e-10)
    # over 1000 seeds FilterPy and pykalman average 4.30 filtered and 2.93 smoothed: our means,
    # from independent random draws, must agree within 4 standard errors
    se_f = st.filtered.std() / np.sqrt(1000)
    se_s = st.smoothed.std() / np.sqrt(1000)
    assert abs(st.mean_filtered - 4.30) < 4 * se_f
    assert abs(st.mean_smoothed - 2.93) < 4 * se_s
    assert st.ratio == pytest.approx(1.47, abs=0.05)


def test_import_stays_light():
    """`import vistrack` must not pull in matplotlib or scipy.stats (~60 MB and ~1 s each):
    the CLI and library users pay for them only when they plot or ask for chi-square bands."""
    code = ("import sys, vistrack; "
            "print(sorted(m for m in ('matplotlib', 'scipy.stats') if m in sys.modules))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip() == "[]"


def test_nonlinear_example_figures(tmp_path):
    import runpy

    example = runpy.run_path(str(Path(__file__).parents[1] / "examples" / "nonlinear_figures.py"))
    paths = example["main"](tmp_path)
    assert [p.name for p in paths] == ["particle_cloud.png", "p_vs_pv.png", "ekf_ukf_pf.png"]
    for p in paths:
        png = p.read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000


def test_nonlinear_example_help_writes_nothing(tmp_path):
    """``--help`` was taken as the output folder: it made ``--help/`` and wrote the figures
    there."""
    script = Path(__file__).parents[1] / "examples" / "nonlinear_figures.py"
    r = subprocess.run([sys.executable, str(script), "--help"], capture_output=True, text=True,
                       cwd=tmp_path)
    assert r.returncode == 0 and r.stdout.startswith("usage: nonlinear_figures.py")
    assert "out_dir" in r.stdout and list(tmp_path.iterdir()) == []


def test_a_figure_interrupted_while_saved_leaves_the_earlier_one(tmp_path, capsys,
                                                                  monkeypatch):
    """The figures were saved in place: Ctrl-C while kalman_2d.png was written left 124 bytes
    that no viewer opens, where a complete figure had been. Saved whole or not at all now:
    the earlier figures byte for byte, no partial file left."""
    from matplotlib.figure import Figure

    assert main(["demo", "kalman", "--out", str(tmp_path), "--seeds", "1"]) == 0
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    save = Figure.savefig

    def cut(self, fname, *args, **kwargs):
        Path(fname).write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 116)  # the first bytes
        raise KeyboardInterrupt

    monkeypatch.setattr(Figure, "savefig", cut)
    assert main(["demo", "kalman", "--out", str(tmp_path), "--seeds", "1", "--force"]) == 130
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    monkeypatch.setattr(Figure, "savefig", save)


def test_ctrl_c_in_a_demo_says_what_was_kept(tmp_path, capsys, monkeypatch):
    """`vistrack demo` stopped by Ctrl-C said "interrupted" alone, where `track` says whether
    earlier outputs were kept; and the three figures were replaced one at a time, so Ctrl-C
    between two left new figures beside an earlier run's. Now they are one set."""
    import vistrack.demo as demo
    import vistrack.pipeline as pipeline

    def stop(*args, **kwargs):
        raise KeyboardInterrupt

    out = tmp_path / "o"
    real = demo.murphy_2d
    monkeypatch.setattr(demo, "murphy_2d", stop)  # the third figure
    assert main(["demo", "kalman", "--out", str(out), "--seeds", "1"]) == 130
    assert capsys.readouterr().err.strip() == "vistrack demo: interrupted; nothing was written"
    assert not out.exists()
    monkeypatch.setattr(demo, "murphy_2d", real)
    assert main(["demo", "kalman", "--out", str(out), "--seeds", "1"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert sorted(before) == ["kalman_1d.png", "kalman_2d.png", "smoothing_1d.png"]
    capsys.readouterr()
    monkeypatch.setattr(demo, "murphy_2d", stop)
    from vistrack.io.atomic import replacing

    def other(fig, path):  # a figure of other bytes, saved as _save saves (whole or not)
        with replacing(path) as part:
            part.write_bytes(b"new")

    monkeypatch.setattr(demo, "_save", other)
    assert main(["demo", "kalman", "--out", str(out), "--seeds", "1", "--force"]) == 130
    assert capsys.readouterr().err.strip() == "vistrack demo: interrupted; earlier outputs are kept"
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    monkeypatch.setattr(pipeline, "track_video", stop)
    assert main(["demo", "track", "--out", str(tmp_path / "t")]) == 130
    assert capsys.readouterr().err.strip().endswith("vistrack demo: interrupted; nothing was "
                                                    "written")

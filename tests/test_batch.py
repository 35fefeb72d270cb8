"""Many inputs at once (vistrack.batch, vistrack track with several inputs): the results of
each input alone, failures reported without stopping the others, and a worker killed in the
middle of a job run again to the same outputs."""

import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from tests.test_fit import _sequence
from vistrack.batch import check_distinct, expand_inputs, plan, run_jobs, track_many
from vistrack.cli import main
from vistrack.data import demo_clip
from vistrack.pipeline import track_sequence


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    """A benchmark folder of three simulated sequences."""
    root = tmp_path_factory.mktemp("bench")
    rng = np.random.default_rng(7)
    for k, T in enumerate((60, 90, 40)):
        _sequence(root / f"SIM-{k}", rng, n_objects=8, T=T)
    return root


def _alone(seq: Path, out: Path) -> bytes:
    track_sequence(seq, out, force=True)
    return out.read_bytes()


def test_each_input_gives_what_it_gives_alone(bench, tmp_path):
    outcomes = track_many([bench], tmp_path / "out", jobs=2)
    assert [o.input.name for o in outcomes] == ["SIM-0", "SIM-1", "SIM-2"]
    for o in outcomes:
        assert o.ok and o.attempts == 1 and o.out == tmp_path / "out" / f"{o.input.name}.txt"
        assert o.out.read_bytes() == _alone(o.input, tmp_path / f"{o.input.name}.txt")
    # any executor: the same files
    with ThreadPoolExecutor(2) as pool:
        again = track_many([bench], tmp_path / "threads", executor=pool)
    assert [o.out.read_bytes() for o in again] == [o.out.read_bytes() for o in outcomes]
    # options go to every input: offline
    off = track_many([bench / "SIM-1"], tmp_path / "off", jobs=1, offline=True)
    track_sequence(bench / "SIM-1", tmp_path / "off-alone.txt", offline=True)
    assert off[0].out.read_bytes() == (tmp_path / "off-alone.txt").read_bytes()


def test_the_largest_inputs_start_first_and_outcomes_keep_the_inputs_order(bench, tmp_path):
    """SIM-1 (90 frames) has the largest detections file, then SIM-0 (60), then SIM-2 (40):
    submitted in that order, so that the largest does not start last; the outcomes are in
    the inputs' order."""
    sizes = {d.name: (d / "det" / "det.txt").stat().st_size for d in bench.iterdir()}
    assert sizes["SIM-1"] > sizes["SIM-0"] > sizes["SIM-2"]
    submitted = []

    class Recording(ThreadPoolExecutor):
        def submit(self, fn, *args, **kwargs):
            submitted.append(args[0].input.name)
            return super().submit(fn, *args, **kwargs)

    with Recording(1) as pool:
        outcomes = track_many([bench], tmp_path / "out", executor=pool)
    assert submitted == ["SIM-1", "SIM-0", "SIM-2"]
    assert [o.input.name for o in outcomes] == ["SIM-0", "SIM-1", "SIM-2"]


def test_inputs_finished_before_an_interrupt_are_reported(tmp_path, monkeypatch):
    """Ctrl-C while waiting for the jobs: the ones already finished (their outputs whole)
    are reported, a line each, before the interrupt goes on; they went unsaid, the table
    never printed, and a user could not tell which outputs were written. Oracle: two jobs,
    the first finished, the second not, and the wait interrupted."""
    import concurrent.futures
    from concurrent.futures import Future

    from vistrack.batch import Job, Outcome, run_jobs

    jobs = [Job(tmp_path / name, tmp_path / f"{name}.txt", "detections") for name in "AB"]
    futures = []

    class Frozen:  # the first job done, the second never
        def submit(self, fn, job):
            f = Future()
            if job.input.name == "A":
                f.set_result(Outcome(job.input, job.out, True, frames=3, tracks=1))
            futures.append(f)
            return f

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(concurrent.futures, "wait", interrupted)
    said = []
    with pytest.raises(KeyboardInterrupt):
        run_jobs(jobs, executor=Frozen(), on_done=lambda o, k, n: said.append((o.input.name,
                                                                            o.ok, k, n)))
    assert said == [("A", True, 1, 2)]


def test_an_interrupted_batch_names_the_outputs_it_wrote(bench, tmp_path, monkeypatch, capsys):
    """Ctrl-C during ``vistrack track A B C --out DIR``: the command names the inputs whose
    outputs this run wrote (each whole: written under a partial name and renamed), those a
    worker wrote as the signal came included, and not an earlier run's files. Before, it
    said "interrupted" alone. Oracle: a run that writes SIM-0's results, then is
    interrupted; SIM-1's results are an earlier run's."""
    import vistrack.batch

    out = tmp_path / "res"
    out.mkdir()
    (out / "SIM-1.txt").write_text("an earlier run's\n")
    old = time.time() - 60
    os.utime(out / "SIM-1.txt", (old, old))

    def interrupted(jobs, **kwargs):
        (out / "SIM-0.txt").write_text("this run's\n")
        raise KeyboardInterrupt

    monkeypatch.setattr(vistrack.batch, "run_jobs", interrupted)
    assert main(["track", str(bench), "--out", str(out), "--force"]) == 130
    assert capsys.readouterr().err.splitlines()[-2:] == [
        "vistrack track: 1 of 3 inputs written before it stopped: SIM-0.txt",
        "vistrack track: interrupted; earlier outputs are kept"]
    # a first run: what it wrote is named, and no earlier outputs are said to be kept
    first = tmp_path / "first"

    def interrupted_first(jobs, **kwargs):
        first.mkdir()
        (first / "SIM-0.txt").write_text("this run's\n")
        raise KeyboardInterrupt

    monkeypatch.setattr(vistrack.batch, "run_jobs", interrupted_first)
    assert main(["track", str(bench), "--out", str(first)]) == 130
    assert capsys.readouterr().err.splitlines()[-2:] == [
        "vistrack track: 1 of 3 inputs written before it stopped: SIM-0.txt",
        "vistrack track: interrupted"]


def _broken(tmp_path: Path, bench: Path) -> Path:
    bad = tmp_path / "BAD"
    (bad / "det").mkdir(parents=True)
    (bad / "seqinfo.ini").write_text((bench / "SIM-0" / "seqinfo.ini").read_text())
    (bad / "det" / "det.txt").write_text("1,-1,10,20,30,40,0.9\n2,-1,10,20,x,40,0.9\n")
    return bad


def test_a_failing_input_is_reported_and_the_others_finish(bench, tmp_path):
    bad = _broken(tmp_path, bench)
    inputs = [bench / "SIM-0", bad, bench / "SIM-1"]
    outcomes = track_many(inputs, tmp_path / "out", jobs=2)
    assert [o.ok for o in outcomes] == [True, False, True]
    assert "det.txt" in outcomes[1].error and "line 2" in outcomes[1].error
    assert not (tmp_path / "out" / "BAD.txt").exists()
    # without keep_going, no input starts after the failure
    stop = track_many(inputs, tmp_path / "stop", jobs=1, keep_going=False)
    assert [(o.ok, o.attempts) for o in stop] == [(True, 1), (False, 1), (False, 0)]
    assert stop[2].error.startswith("not run")


def _failing_or_slow(job):
    """A stand-in for a worker's job: the input named BAD fails at once, the others take a
    second (module level, so that forked workers find it)."""
    import vistrack.batch as batch

    if job.input.name == "BAD":
        return batch.Outcome(job.input, job.out, False, error="ValueError: bad")
    time.sleep(1.0)
    return batch.Outcome(job.input, job.out, True)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forked workers (Linux)")
def test_without_keep_going_no_input_starts_after_the_first_failure(tmp_path, monkeypatch):
    """With two workers, four inputs were handed to the pool at once: the first, failing at
    once, stopped nothing, since the pool ran those it held (both started after the
    failure). One input a worker is handed over now: the failing one and the one beside it
    start, the other two not (attempts 0, "not run")."""
    import vistrack.batch as batch

    monkeypatch.setattr(batch, "_run", _failing_or_slow)  # (the forked workers' too)
    jobs = [batch.Job(tmp_path / name, tmp_path / f"{name}.txt", "detections")
            for name in ("BAD", "A", "B", "C")]
    stop = batch.run_jobs(jobs, workers=2, keep_going=False)
    assert [(o.ok, o.attempts) for o in stop] == [(False, 1), (True, 1), (False, 0),
                                                   (False, 0)]
    # (not "an earlier input failed": the one that failed may come later in the inputs)
    assert all(o.error == "not run (another input failed first)" for o in stop[2:])


def _children(parent: int) -> dict[int, bytes]:
    """The processes whose parent is ``parent``, with their command lines."""
    out = {}
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == parent:
            out[int(pid)] = cmd
    return out


def _pool_workers() -> list[int]:
    """This process's children that are spawned process-pool workers."""
    return [pid for pid, cmd in _children(os.getpid()).items() if b"spawn_main" in cmd]


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="finds the workers in /proc (Linux)")
def test_a_worker_killed_mid_job_is_replaced_and_the_outputs_are_complete(tmp_path):
    rng = np.random.default_rng(8)
    seqs = [_sequence(tmp_path / "in" / f"LONG-{k}", rng, n_objects=400, T=150,
                      std=(0.002, 0.00005)) for k in range(3)]
    out = tmp_path / "out"
    killed: list[int] = []

    def killer():
        # once a job is writing its results, kill one worker
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not killed:
            if out.exists() and any(p.name.startswith(".") for p in out.iterdir()):
                workers = _pool_workers()
                if workers:
                    os.kill(workers[0], signal.SIGKILL)
                    killed.append(workers[0])
            time.sleep(0.01)

    thread = threading.Thread(target=killer)
    thread.start()
    outcomes = run_jobs(plan(seqs, out), workers=2)
    killed.append(0)  # (stops the thread if it saw nothing)
    thread.join()
    killed.pop()
    assert killed, "no worker was seen running a job"
    assert all(o.ok for o in outcomes), [o.error for o in outcomes]
    assert max(o.attempts for o in outcomes) == 2
    for o in outcomes:
        assert o.out.read_bytes() == _alone(o.input, tmp_path / f"{o.input.name}.txt")
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no partial file left


class _KillsItsWorker:
    """A tracker that tracks nothing, and kills its own process (as a crash or the
    out-of-memory killer would) on a frame 170 pixels wide."""

    def step(self, frame, detections=None):
        from vistrack.types import Tracks

        if frame.image is not None and frame.image.shape[1] == 170:
            os.kill(os.getpid(), signal.SIGKILL)
        time.sleep(0.5)  # (the others run while it dies: the pool breaks under them)
        return Tracks.empty()


def kills_its_worker():
    return _KillsItsWorker()


def test_a_job_that_kills_its_worker_fails_alone(tmp_path):
    """A job whose worker dies each time took the pool down with the jobs beside it, and
    each death was counted against every one of them: after three, all were failed ("its
    worker died 3 times"), though each of the others runs alone. Those that died together
    run again alone now, and only a death alone counts."""
    from tests.test_pipeline import red_disc_clip, write_clip

    inputs = [write_clip(tmp_path / name, red_disc_clip(T=4, size=(width, 120))[0])
              for name, width in (("good-a", 160), ("good-b", 160), ("good-c", 160),
                                  ("poison", 170))]
    jobs = plan(inputs, tmp_path / "out", kind="pixels", fps=10, annotate=False,
                tracker="tests.test_batch:kills_its_worker")
    outcomes = {o.input.name: o for o in run_jobs(jobs, workers=3)}
    assert not outcomes["poison"].ok
    # its deaths in all: three alone (retries=2), and once beside two of the others (the
    # largest input, it starts first, with two of them; each takes 2 s)
    assert outcomes["poison"].error == "its worker died 4 times"
    assert outcomes["poison"].attempts == 4
    # its output folder, made by its dead worker and left empty, is gone (it stayed)
    assert not outcomes["poison"].out.exists()
    assert sorted(o.attempts for n, o in outcomes.items() if n != "poison") == [1, 2, 2]
    for name in ("good-a", "good-b", "good-c"):
        assert outcomes[name].ok, outcomes[name].error
        assert outcomes[name].attempts <= 2  # (once alone, if it died beside the poison)
        assert (outcomes[name].out / "tracks.txt").read_bytes() == b""  # nothing tracked


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers are forked on Linux")
def test_the_command_forks_its_workers_and_one_terminated_mid_job_is_replaced(tmp_path):
    """`vistrack track` with several inputs keeps to one thread until its workers start, so
    that they are forked from it (its imports inherited, not done again in each); a forked
    worker sent SIGTERM dies as a spawned one would (not through the command's own SIGTERM
    handler), and its job runs again: every output whole, as each input alone gives it."""
    rng = np.random.default_rng(9)
    seqs = [_sequence(tmp_path / "in" / f"LONG-{k}", rng, n_objects=400, T=150,
                      std=(0.002, 0.00005)) for k in range(3)]
    out = tmp_path / "out"
    cmd = [str(Path(sys.executable).parent / "vistrack"), "track", *map(str, seqs), "--out",
           str(out), "--jobs", "2", "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    workers: dict[int, bytes] = {}
    deadline = time.monotonic() + 120
    while not workers and proc.poll() is None and time.monotonic() < deadline:
        if out.exists() and any(p.name.startswith(".") for p in out.iterdir()):
            workers = _children(proc.pid)
            parent = Path(f"/proc/{proc.pid}/cmdline").read_bytes()
            if workers:
                os.kill(min(workers), signal.SIGTERM)
        time.sleep(0.01)
    stdout, stderr = proc.communicate(timeout=120)
    assert workers, "no worker was seen running a job"
    # forked: a worker's command line is the command's own (a spawned one's is spawn_main)
    assert all(c == parent for c in workers.values())
    assert proc.returncode == 0, stderr
    assert "3 of 3 inputs tracked" in stdout
    for seq in seqs:
        assert (out / f"{seq.name}.txt").read_bytes() == _alone(seq, tmp_path / f"{seq.name}.txt")
    assert not [p for p in out.iterdir() if p.name.startswith(".")]


HOW = """import multiprocessing, signal, sys

from vistrack import _compile


def how():
    return (multiprocessing.get_start_method(), "vistrack.pipeline" in sys.modules,
            signal.getsignal(signal.SIGINT) == signal.SIG_IGN, len(_compile._watches))
"""

POOLS = """import signal, sys, threading
sys.path.insert(0, sys.argv[1])
from how import how
from vistrack import _compile
from vistrack.batch import process_pool

def show():
    with process_pool(1, imports=("vistrack.pipeline",)) as pool:
        print(*pool.submit(how).result())

if __name__ == "__main__":
    with _compile.watch(None):  # a command's watch of numba's compilations
        show()
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        show()
        signal.signal(signal.SIGINT, signal.default_int_handler)
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    show()
    stop.set()
    other.join()
"""


CTRL_C = """import os, signal, sys, threading, time
from vistrack._pool import process_pool

def interrupted():
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(5)
    return "not interrupted"

def check():
    with process_pool(1) as pool:
        pid = pool.submit(os.getpid).result()
        os.kill(pid, signal.SIGINT)  # between jobs: the worker waits on the pool's queue
        time.sleep(0.3)
        alive = pool.submit(os.getpid).result() == pid
        try:
            got = pool.submit(interrupted).result()
        except KeyboardInterrupt:
            got = "KeyboardInterrupt"
        print(alive, got, pool.submit(os.getpid).result() == pid)

if __name__ == "__main__":
    check()  # forked
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    check()  # spawned
    stop.set()
    other.join()
"""


def test_a_worker_takes_ctrl_c_in_a_job_and_not_between_jobs(tmp_path):
    """Ctrl-C stops the job a worker runs (KeyboardInterrupt, its outputs unwound), and is
    left to the pool between jobs: raised while the worker waited on the pool's queue, it
    ended the worker (the pool broken), could leave the queue's lock held (a batch hung on
    Ctrl-C about once in 30), and the pool then ended its other workers at once, leaving
    their outputs under partial names. Forked and spawned workers alike."""
    (tmp_path / "ctrl_c.py").write_text(CTRL_C)
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1",
               PYTHONPATH=str(Path(__file__).parents[1] / "src"))
    r = subprocess.run([sys.executable, str(tmp_path / "ctrl_c.py")], env=env,
                       capture_output=True, text=True, timeout=120)
    assert r.stdout.splitlines() == ["True KeyboardInterrupt True"] * 2, r.stderr


def test_a_single_threaded_process_forks_its_workers_and_one_with_other_threads_spawns(
        tmp_path):
    """With one thread (BLAS given one), the workers are forked after the jobs' module is
    imported, and start with it; Ctrl-C stays ignored if this process ignores it, and the
    parent's compile watch is not theirs. With another thread running (a fork could copy a
    lock it holds), they are spawned and import what they need."""
    (tmp_path / "how.py").write_text(HOW)
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    r = subprocess.run([sys.executable, "-c", POOLS, str(tmp_path)], env=env,
                       capture_output=True, text=True, check=True)
    assert r.stdout.splitlines() == ["fork True False 0", "fork True True 0",
                                     "spawn False False 0"]


SCRIPT = """import sys
from vistrack.batch import track_many

{guard}outcomes = track_many([sys.argv[1]], sys.argv[2], jobs=2)
{indent}print(*(o.ok for o in outcomes))
"""


@pytest.mark.parametrize("guarded", [False, True], ids=["unguarded", "guarded"])
def test_a_script_without_a_main_guard_is_refused_before_any_job_runs(bench, tmp_path,
                                                                     guarded):
    """A script whose top level calls track_many without ``if __name__ == "__main__":``:
    its spawned workers (it imported numpy, whose BLAS threads rule out a fork) import the
    script, whose top level asks for a pool again. Refused there, in each worker, and in the
    script, naming the guard: before, each worker tracked every input in a pool of its own and
    the script's own jobs then failed on the files they had written. Guarded, it runs once."""
    script = tmp_path / "many.py"
    script.write_text(SCRIPT.format(guard='if __name__ == "__main__":\n    ' if guarded else "",
                                    indent="    " if guarded else ""))
    env = dict(os.environ, OMP_NUM_THREADS="2", OPENBLAS_NUM_THREADS="2")  # BLAS threads
    r = subprocess.run([sys.executable, str(script), str(bench), str(tmp_path / "out")],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    if guarded:
        assert (r.returncode, r.stdout) == (0, "True True True\n"), r.stderr[-2000:]
        return
    assert r.returncode == 1 and r.stdout == ""
    last = r.stderr.strip().splitlines()[-1]
    assert last == ("RuntimeError: the pool's worker processes ended as they started (their "
                    "errors are above); a script that starts a process pool (track_many, "
                    "evaluate_files with jobs) must guard its top level with `if __name__ == "
                    '"__main__":`, since each spawned worker imports the script')
    assert not (tmp_path / "out").exists()


def test_the_command_line_does_not_start_numpy_before_it_knows_the_command():
    """Importing vistrack (and its command line) leaves numpy, and the BLAS threads it starts,
    to the command: one that hands its inputs to workers gives itself one thread first."""
    code = "import sys, vistrack.cli; print('numpy' in sys.modules)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip() == "False"


def test_inputs_expand_and_are_checked(bench, tmp_path):
    assert [p.name for p in expand_inputs([bench])] == ["SIM-0", "SIM-1", "SIM-2"]
    # each path given once, one of them inside a folder of sequences: the error names that
    # folder (it named the same path twice, "SIM-1 is given twice (as SIM-1 too)")
    for inputs, first, second in (([bench, bench / "SIM-1"], "SIM-1", "SIM-1"),
                                  ([bench / "SIM-1", bench], "SIM-1", "SIM-1")):
        with pytest.raises(ValueError) as e:
            expand_inputs(inputs)
        assert str(e.value) == (f"{bench / second} is given twice (as {bench / first} too; one "
                                f"of them found in the folder of sequences {bench})")
    with pytest.raises(ValueError) as e:
        expand_inputs([bench / "SIM-1", bench / "SIM-1"])
    assert "folder of sequences" not in str(e.value)
    with pytest.raises(ValueError) as e:  # (it was named by its first sequence)
        expand_inputs([bench, bench])
    assert str(e.value) == f"{bench} is given twice (as {bench} too)"
    with pytest.raises(ValueError, match="within must give a folder .* each of the 2 paths"):
        check_distinct([bench / "SIM-0", bench / "SIM-0"], [None])
    with pytest.raises(FileNotFoundError, match="nowhere"):
        expand_inputs([tmp_path / "nowhere"])
    video = tmp_path / "clip.mp4"
    video.write_bytes(b"")
    with pytest.raises(ValueError, match="not a MOTChallenge sequence folder"):
        plan([video], tmp_path / "out")
    assert plan([video], tmp_path / "out", kind="pixels")[0].out == tmp_path / "out" / "clip"
    with pytest.raises(ValueError, match="kind"):
        plan([video], tmp_path, kind="pictures")


def test_one_inputs_own_file_is_refused_with_several_inputs(bench, tmp_path):
    """track_many(several, detections=FILE) tracked every sequence from the one file and
    wrote each result under its own sequence's name (the command line refuses --detections
    with several inputs). Refused before any job, as a ground truth or a detections front-end
    of one video for several; with one input each is taken, and a shared ONNX model too."""
    det = bench / "SIM-1" / "det" / "det.txt"
    seqs = [bench / "SIM-0", bench / "SIM-1"]
    with pytest.raises(ValueError, match=re.escape(
            f"detections={det!r} is one input's file, and there are 2 inputs: give it with "
            "one input")):
        plan(seqs, tmp_path / "out", detections=det)
    with pytest.raises(ValueError, match="detections=.* 3 inputs"):
        track_many([bench], tmp_path / "out", detections=det)
    assert not (tmp_path / "out").exists()
    assert plan(seqs[:1], tmp_path / "out", detections=det)[0].options["detections"] == det
    videos = [tmp_path / "a.mp4", tmp_path / "b.mp4"]
    for v in videos:
        v.write_bytes(b"")
    for option in ({"gt": tmp_path / "gt.txt"}, {"frontend": "detections:d.txt"}):
        with pytest.raises(ValueError, match="is one input's file, and there are 2 inputs"):
            plan(videos, tmp_path / "out", kind="pixels", **option)
        assert len(plan(videos[:1], tmp_path / "out", kind="pixels", **option)) == 1
    assert len(plan(videos, tmp_path / "out", kind="pixels", frontend="onnx:m.onnx")) == 2


def test_vistrack_track_with_several_inputs(bench, tmp_path, capsys):
    out = tmp_path / "results"
    assert main(["track", str(bench), "--out", str(out), "--jobs", "2", "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "3 of 3 inputs tracked" in text
    assert (out / "SIM-2.txt").read_bytes() == _alone(bench / "SIM-2", tmp_path / "a.txt")
    # names shorter than the header ("A" under "input"): the columns were shifted
    short = tmp_path / "short"
    short.mkdir()
    for name in ("A", "B"):
        shutil.copytree(bench / "SIM-0", short / name)
    assert main(["track", str(short), "--out", str(tmp_path / "r3"), "--quiet"]) == 0
    rows = [r for r in capsys.readouterr().out.splitlines() if r.split()[:1] in
            (["input"], ["A"], ["B"])]
    assert len(rows) == 3 and len({r.index(" ok") + 1 if " ok" in r else r.index("status")
                                   for r in rows}) == 1, rows
    # outputs are not overwritten without --force, before anything runs
    assert main(["track", str(bench), "--out", str(out), "--quiet"]) == 2
    assert "--force" in capsys.readouterr().err
    bad = _broken(tmp_path, bench)
    status = main(["track", str(bench / "SIM-0"), str(bad), "--out", str(tmp_path / "r2"),
                   "--keep-going", "--jobs", "1", "--quiet"])
    text = capsys.readouterr().out
    assert status == 1 and "1 of 2 inputs tracked; 1 not" in text and "failed" in text
    assert main(["track", str(bench), "--out", str(out), "--gt", "x", "--quiet"]) == 2
    assert "--gt goes with one input" in capsys.readouterr().err


def test_several_inputs_say_which_settings_change_nothing(bench, tmp_path, capsys):
    """As with one input: the offline mode's settings without ``--offline``, and ``--low``
    with a tracker of one stage, are said to change nothing, and with ``--out-dir`` the
    offline settings are refused. With several inputs they were dropped without a word."""
    for argv, said in (
            (["--out", str(tmp_path / "a"), "--max-gap", "2"],
             "vistrack track: warning: --max-gap: offline settings, which change nothing "
             "without --offline"),
            (["--out", str(tmp_path / "b"), "--tracker", "sort", "--low", "0.2"],
             "vistrack track: warning: --low: the second association stage's threshold, which "
             "changes nothing with a tracker of one stage (sort) online (offline, it is also "
             "the least score a track is followed back through)")):
        assert main(["track", str(bench), *argv, "--jobs", "1", "--quiet"]) == 0
        cap = capsys.readouterr()
        assert said in cap.err and "3 of 3 inputs tracked" in cap.out
    # offline, --low sets which detections a track is followed back through: nothing is said
    assert main(["track", str(bench), "--out", str(tmp_path / "b2"), "--tracker", "sort",
                 "--low", "0.2", "--offline", "--jobs", "1", "--quiet"]) == 0
    assert "warning" not in capsys.readouterr().err
    # with the offline mode on, its settings count: nothing is said
    assert main(["track", str(bench), "--out", str(tmp_path / "c"), "--max-gap", "2",
                 "--offline", "--jobs", "1", "--quiet"]) == 0
    assert "warning" not in capsys.readouterr().err
    import shutil

    clip = tmp_path / "clip.mp4"
    shutil.copy(demo_clip().video, clip)
    for flag in (["--max-gap", "2"], ["--offline"]):
        assert main(["track", str(clip), str(demo_clip().video), "--out-dir",
                     str(tmp_path / "d"), *flag, "--quiet"]) == 2
        assert ("--offline, its settings and --detections go with --out"
                in capsys.readouterr().err)
    assert not (tmp_path / "d").exists()


def test_detections_files_alone_at_the_frame_rate_given(bench, tmp_path, capsys):
    """Several detections files alone (and a folder without seqinfo.ini) at `--fps`: each
    result is what tracking that file alone gives, named after its sequence; without the
    frame rate they are refused before anything runs."""
    bare = tmp_path / "BARE"
    (bare / "det").mkdir(parents=True)
    (bare / "det" / "det.txt").write_bytes((bench / "SIM-1" / "det" / "det.txt").read_bytes())
    (tmp_path / "cam.txt").write_bytes((bench / "SIM-2" / "det" / "det.txt").read_bytes())
    inputs = [bench / "SIM-0" / "det" / "det.txt", bare, tmp_path / "cam.txt"]
    out = tmp_path / "results"
    assert main(["track", *map(str, inputs), "--out", str(out), "--fps", "12", "--jobs",
                 "2", "--quiet"]) == 0
    said = capsys.readouterr().out
    assert "3 of 3 inputs tracked" in said
    # the table names SEQ/det/det.txt after its sequence, as its results (every such file
    # was "det.txt")
    assert [line.split()[0] for line in said.splitlines()[1:4]] == ["SIM-0", "BARE", "cam.txt"]
    assert sorted(p.name for p in out.iterdir()) == ["BARE.txt", "SIM-0.txt", "cam.txt"]
    for name, path in zip(("SIM-0", "BARE", "cam"), inputs):
        track_sequence(path, tmp_path / "alone.txt", fps=12, force=True)
        assert (out / f"{name}.txt").read_bytes() == (tmp_path / "alone.txt").read_bytes()
    assert main(["track", *map(str, inputs), "--out", str(tmp_path / "r2")]) == 2
    assert (f"{inputs[0]} is a detections file alone: give its frame rate (fps, --fps)"
            in capsys.readouterr().err)
    assert not (tmp_path / "r2").exists()
    with pytest.raises(ValueError, match="is not a MOTChallenge sequence folder"):
        plan([bare], tmp_path / "r3")


def test_the_summary_says_where_fps_was_put_over_seqinfo(bench, tmp_path, capsys):
    """``--fps`` is put over a sequence's own ``frameRate`` (15 here): the summary says so,
    for one input on its line and for several in a line naming each sequence and its own
    rate; a detections file alone has none to put it over, and the same rate says nothing."""
    seq = bench / "SIM-0"
    assert main(["track", str(seq), "--out", str(tmp_path / "a.txt"), "--fps", "10"]) == 0
    assert capsys.readouterr().out.rstrip().endswith(
        f"; tracked at --fps 10 frames/s, over {seq / 'seqinfo.ini'}'s frameRate 15")
    for fps in ([], ["--fps", "15"]):
        assert main(["track", str(seq), "--out", str(tmp_path / "a.txt"), "--force",
                     *fps]) == 0
        assert "tracked at" not in capsys.readouterr().out
    inputs = [bench / "SIM-1", seq / "det" / "det.txt", bench / "SIM-2"]
    assert main(["track", *map(str, inputs), "--out", str(tmp_path / "r"), "--fps", "12.5",
                 "--quiet"]) == 0
    assert capsys.readouterr().out.splitlines()[-2:] == [
        "3 of 3 inputs tracked",
        "tracked at --fps 12.5 frames/s, over the frameRate of seqinfo.ini: SIM-1 15, SIM-2 15"]
    assert main(["track", *map(str, inputs), "--out", str(tmp_path / "s"), "--fps", "15",
                 "--quiet"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "3 of 3 inputs tracked"


def test_scoring_many_pairs_at_once_gives_the_same_scores(bench, tmp_path, capsys):
    from vistrack.evaluation import evaluate_files

    outcomes = track_many([bench], tmp_path / "out", jobs=1)
    pairs = [(o.input.name, o.input / "gt" / "gt.txt", o.out, o.input / "seqinfo.ini")
             for o in outcomes]
    serial = evaluate_files(pairs)
    with ThreadPoolExecutor(2) as pool:
        threads = evaluate_files(pairs, executor=pool)
    processes = evaluate_files(pairs, jobs=2)
    for name in serial:
        for other in (threads, processes):
            a, b = vars(serial[name]), vars(other[name])
            assert a.keys() == b.keys()
            assert all(np.array_equal(a[k], b[k]) for k in a), name
    with pytest.raises(ValueError, match="jobs"):
        evaluate_files(pairs, jobs=0)
    # vistrack eval scores the sequences on a process each by default: the same table
    tables = []
    for jobs in ([], ["--jobs", "1"]):
        assert main(["eval", "--gt-dir", str(bench), "--pred-dir", str(tmp_path / "out"),
                     "--json", *jobs]) == 0
        tables.append(capsys.readouterr().out)
    assert tables[0] == tables[1] and '"SIM-2"' in tables[0]


def test_scoring_keeps_going_past_a_sequence_it_cannot_read(bench, tmp_path, capsys):
    import json

    from vistrack.evaluation import evaluate_files

    out = tmp_path / "out"
    track_many([bench], out, jobs=1)
    (out / "SIM-1.txt").write_text("1,1,10,20,30,40,1,-1,-1,-1\n2,1,10,x,30,40,1,-1,-1,-1\n")
    pairs = [(s.name, s / "gt" / "gt.txt", out / f"{s.name}.txt", s / "seqinfo.ini")
             for s in sorted(bench.iterdir())]
    good = evaluate_files([pairs[0], pairs[2]])
    threads = ThreadPoolExecutor(2)
    for where in (dict(jobs=1), dict(jobs=2), dict(executor=threads)):
        res = evaluate_files(pairs, keep_going=True, **where)
        assert sorted(res) == ["COMBINED", "SIM-0", "SIM-2"]
        assert list(res.errors) == ["SIM-1"] and "SIM-1.txt" in res.errors["SIM-1"]
        assert "line 2" in res.errors["SIM-1"]
        # COMBINED over the sequences scored: as if the one left out were not there
        a, b = vars(res["COMBINED"]), vars(good["COMBINED"])
        assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in b)
    threads.shutdown()
    with pytest.raises(Exception, match="line 2"):
        evaluate_files(pairs, keep_going=False)
    # the command: one line for the sequence left out, the others' table, exit status 1
    args = ["eval", "--gt-dir", str(bench), "--pred-dir", str(out), "--json"]
    assert main(args) == 2  # without --keep-going, the error alone
    assert "SIM-1.txt" in capsys.readouterr().err
    assert main([*args, "--keep-going"]) == 1
    cap = capsys.readouterr()
    assert sorted(json.loads(cap.out)) == ["COMBINED", "SIM-0", "SIM-2"]
    assert "vistrack eval: error: SIM-1: " in cap.err and "2 of 3 sequences scored" in cap.err
    # the command as a user runs it: the sequences scored by forked workers, the same output
    run = subprocess.run([str(Path(sys.executable).parent / "vistrack"), *args, "--keep-going"],
                         capture_output=True, text=True)
    assert (run.returncode, run.stdout, run.stderr) == (1, cap.out, cap.err)
    one = ["eval", "--gt", str(bench / "SIM-0" / "gt" / "gt.txt"), "--pred",
           str(out / "SIM-0.txt"), "--keep-going"]
    assert main(one) == 2 and "--keep-going goes with --gt-dir" in capsys.readouterr().err
    # a missing results file is one more error, not a stop
    (out / "SIM-2.txt").unlink()
    assert main([*args, "--keep-going"]) == 1
    cap = capsys.readouterr()
    assert sorted(json.loads(cap.out)) == ["SIM-0"]
    assert "SIM-2: FileNotFoundError" in cap.err and "1 of 3 sequences scored" in cap.err
    (out / "SIM-0.txt").unlink()  # nothing to score: still JSON
    assert main([*args, "--keep-going"]) == 1
    assert json.loads(capsys.readouterr().out) == {}


def _two_clips(folder):
    """Two copies of the bundled clip, ``folder/a.mp4`` and ``folder/b.mp4``."""
    import shutil

    a, b = folder / "a.mp4", folder / "b.mp4"
    for copy in (a, b):
        shutil.copy(demo_clip().video, copy)
    return a, b


def test_several_videos_from_pixels(tmp_path, capsys):
    from vistrack.pipeline import track_video

    a, b = _two_clips(tmp_path)
    out = tmp_path / "out"
    assert main(["track", str(a), str(b), "--out-dir", str(out), "--stop", "20", "--jobs",
                 "2", "--still-camera", "--quiet"]) == 0
    assert "2 of 2 inputs tracked" in capsys.readouterr().out
    track_video(a, tmp_path / "alone", stop=20, camera_motion=False)
    for name in ("a", "b"):
        for f in ("tracks.txt", "tracks.csv"):
            assert (out / name / f).read_bytes() == (tmp_path / "alone" / f).read_bytes()
        assert (out / name / "annotated.mp4").stat().st_size > 0


def _image_folder(video, folder, frames):
    """The first ``frames`` frames of ``video`` as PNG images in ``folder``, which gives no
    frame rate."""
    import cv2

    folder.mkdir(parents=True)
    cap = cv2.VideoCapture(str(video))
    for k in range(frames):
        ok, image = cap.read()
        assert ok
        cv2.imwrite(str(folder / f"{k + 1:06d}.png"), image)
    cap.release()
    return folder


def test_several_inputs_from_pixels_take_one_frame_rate(tmp_path, capsys):
    """Image folders give no frame rate, and each run says to give the true one with
    ``--fps``; with several inputs ``--fps`` was refused, so they could only be tracked at
    an assumed 30 frames/s. Now, as with ``--out``, it is every input's rate, put over any
    an input gives (the clip's header says 7): each input is tracked as it is alone at that
    rate, and a line after the table names each input whose own rate was replaced."""
    import json

    from vistrack.io import VideoReader
    from vistrack.pipeline import track_video

    clip, _ = _two_clips(tmp_path)
    assert VideoReader(clip).own_fps == 7  # the header's, what the last line names
    folders = [_image_folder(clip, tmp_path / name, 12) for name in ("f1", "f2")]
    out = tmp_path / "out"
    assert main(["track", str(folders[0]), str(folders[1]), str(clip), "--out-dir", str(out),
                 "--fps", "10", "--stop", "12", "--still-camera", "--quiet"]) == 0
    assert capsys.readouterr().out.splitlines()[-2:] == [
        "3 of 3 inputs tracked",
        "tracked at --fps 10 frames/s, over the rate of the video's header: a.mp4 7"]
    for name, source in (("f1", folders[0]), ("a", clip)):
        alone = track_video(source, tmp_path / f"alone-{name}", fps=10, stop=12,
                            camera_motion=False, annotate=False)
        assert json.loads((out / name / "run.json").read_text())["frame_rate"] == 10
        assert (out / name / "tracks.txt").read_bytes() == \
            (alone.out_dir / "tracks.txt").read_bytes()
    # at the assumed 30 frames/s the tracks differ: the rate was the option's
    with pytest.warns(UserWarning, match="gives no frame rate"):
        at30 = track_video(folders[0], tmp_path / "at30", stop=12, camera_motion=False,
                           annotate=False)
    assert (at30.out_dir / "tracks.txt").read_bytes() != (out / "f1" / "tracks.txt").read_bytes()
    # the folders alone, or the clip at its own rate: nothing was replaced, nothing said
    assert main(["track", str(folders[0]), str(clip), "--out-dir", str(out), "--fps", "7",
                 "--stop", "12", "--force", "--quiet"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "2 of 2 inputs tracked"


def test_one_input_from_pixels_says_which_rate_fps_was_put_over(tmp_path, capsys):
    """``--fps`` over a video's header rate, or over the frameRate of an image sequence's
    seqinfo.ini, was taken without a word, where a detections run names the frameRate it
    replaced. The summary's first line now ends naming it; the same rate, or a folder that
    gives none, says nothing. ``VideoReader.own_fps`` is the rate the source gives."""
    from vistrack.io import VideoReader

    clip, _ = _two_clips(tmp_path)
    seq = tmp_path / "SEQ"
    _image_folder(clip, seq / "img1", 8)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=SEQ\nimDir=img1\nframeRate=25\n"
                                     "seqLength=8\nimWidth=768\nimHeight=576\n")
    bare = _image_folder(clip, tmp_path / "bare", 8)
    for source, own, where in ((clip, 7, "the header"), (seq, 25, "seqinfo.ini"),
                               (bare, None, None)):
        assert (VideoReader(source).own_fps, VideoReader(source).own_fps_from) == (own, where)
        assert (VideoReader(source, fps=12).own_fps, VideoReader(source, fps=12).fps) == (own, 12)
    words = {clip: f"; tracked at --fps 12 frames/s, over the rate of {clip}'s header, 7",
             seq: f"; tracked at --fps 12 frames/s, over {seq / 'seqinfo.ini'}'s frameRate 25",
             bare: ""}
    for source, end in words.items():
        assert main(["track", str(source), "--out-dir", str(tmp_path / "o"), "--fps", "12",
                     "--stop", "8", "--force"]) == 0
        first = capsys.readouterr().out.splitlines()[0]
        assert first.endswith(end) if end else "tracked at --fps" not in first
    for source, own in ((clip, "7"), (seq, "25")):  # the same rate as its own
        assert main(["track", str(source), "--out-dir", str(tmp_path / "o"), "--fps", own,
                     "--stop", "8", "--force"]) == 0
        assert "tracked at --fps" not in capsys.readouterr().out


@pytest.mark.skipif(sys.platform == "win32", reason="SIGTERM to one process (POSIX)")
def test_sigterm_to_the_batch_alone_stops_its_workers(tmp_path):
    """``kill PID`` (or ``docker stop``) signals the command's own process, not its workers:
    it waited for them, and they ran the jobs under way and the queued ones to their end
    (every input written, 6 s after the signal for short clips; an hour for long videos).
    The workers are stopped as by Ctrl-C now: status 143 at once, the inputs under way not
    written (nothing of them left, not even a partial file), the others not started."""
    import shutil
    import signal
    import time

    clips = []
    for name in "abcd":
        shutil.copy(demo_clip().video, tmp_path / f"{name}.mp4")
        clips.append(str(tmp_path / f"{name}.mp4"))
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).parents[1] / "src"))
    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", "track", *clips,
                             "--out-dir", str(out), "--jobs", "2", "--quiet"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not list(out.glob("*/.*.partial.*")) and proc.poll() is None and \
            time.monotonic() < deadline:  # the workers write their first frames' rows
        time.sleep(0.01)
    assert proc.poll() is None, "the batch ended before it could be stopped"
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 143, stderr
    assert time.monotonic() - t0 < 10, stderr  # (0.2 s here; 3.5 s before, 3 written)
    assert "terminated" in stderr and "0 of 4 inputs written" in stderr
    assert not list(out.glob("*/*")), stderr  # nothing written, nothing partial


def test_a_job_that_cannot_be_sent_to_a_worker_is_reported(bench, tmp_path):
    # a front-end defined here cannot be pickled to the pool's processes
    jobs = plan([bench / "SIM-0"], tmp_path / "out", offline=False)
    jobs.append(type(jobs[0])(bench / "SIM-1", tmp_path / "out" / "SIM-1.txt", "detections",
                              {"config": lambda: None}))
    outcomes = run_jobs(jobs, workers=2)
    assert outcomes[0].ok and not outcomes[1].ok
    assert "pickle" in outcomes[1].error.lower()


def test_the_progress_bar_on_a_terminal_and_lines_elsewhere(tmp_path):
    import io

    from vistrack.batch import Outcome, progress_lines

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    done = [Outcome(Path("A"), tmp_path / "A.txt", True, 10, 30, 3, 0.2),
            Outcome(Path("B"), tmp_path / "B.txt", False, error="ValueError: bad"),
            Outcome(Path("C"), tmp_path / "C.txt", True, 5, 9, 2, 0.1),
            Outcome(Path("D"), tmp_path / "D.txt", True, 1, 1, 1, 0.1)]  # ("1 frames")
    term = Terminal()
    report = progress_lines(term, 3)
    assert term.getvalue() == "[------------------------] 0/3 inputs, 0 s"
    for k, o in enumerate(done[:3], 1):
        report(o, k, 3)
    shown = term.getvalue().split("\r\x1b[K")  # each line clears the bar's line first
    assert shown[1] == ("[1/3] A: 10 frames, 3 tracks, 0.2 s\n"
                        "[########----------------] 1/3 inputs, 0 s, about 0 s left")
    assert shown[2].startswith("[2/3] B: failed: ValueError: bad\n"
                               "[################--------] 2/3 inputs, 1 failed, ")
    assert shown[3] == "[3/3] C: 5 frames, 2 tracks, 0.1 s\n"  # the bar gone at the end
    plain = io.StringIO()  # a log file: the lines only
    report = progress_lines(plain, 3)
    for k, o in enumerate(done[:3], 1):
        report(o, k, 3)
    report(done[3], 4, 4)
    assert plain.getvalue().splitlines() == [
        "[1/3] A: 10 frames, 3 tracks, 0.2 s", "[2/3] B: failed: ValueError: bad",
        "[3/3] C: 5 frames, 2 tracks, 0.1 s", "[4/4] D: 1 frame, 1 track, 0.1 s"]
    assert progress_lines(None, 3) is None


def test_each_progress_and_warning_line_is_one_write(tmp_path, monkeypatch):
    """A batch's workers share stderr with the process handing out the inputs. print wrote
    a line and its newline in two writes, and unbuffered (python -u) a worker's warning fell
    between them: "... from frame to frame[15/20] KITTI-0010-Car: ..." and an empty line.
    Each line is now one write, which a pipe keeps whole (under 4,096 bytes)."""
    import io
    import sys
    import warnings

    from vistrack.batch import Outcome, progress_lines
    from vistrack.cli import _one_line_warnings

    class Writes(io.StringIO):
        def __init__(self):
            super().__init__()
            self.calls = []

        def write(self, text):
            self.calls.append(text)
            return super().write(text)

    out = Writes()
    report = progress_lines(out, 2)
    report(Outcome(Path("A"), tmp_path / "A.txt", True, 10, 30, 3, 0.2), 1, 2)
    report(Outcome(Path("B"), tmp_path / "B.txt", False, error="ValueError: bad"), 2, 2)
    assert out.calls == ["[1/2] A: 10 frames, 3 tracks, 0.2 s\n",
                         "[2/2] B: failed: ValueError: bad\n"]
    err = Writes()
    monkeypatch.setattr(sys, "stderr", err)
    show = _one_line_warnings("track")
    show(UserWarning("a box of zero width"), UserWarning, "f.py", 1)
    with warnings.catch_warnings():
        warnings.showwarning = show
        warnings.simplefilter("always")
        warnings.warn("frames taken as not delivered", stacklevel=1)
    assert err.calls == ["vistrack track: warning: a box of zero width\n",
                         "vistrack track: warning: frames taken as not delivered\n"]


@pytest.mark.parametrize("option, error, message", [
    ("bogus", TypeError, "bogus is no setting of the box tracker or the offline mode (those "
                         "are assigner, "),
    ("high", ValueError, "high must be in [0, 1] (a calibrated confidence); got 1.5"),
])
def test_options_are_checked_once_before_any_job(bench, tmp_path, option, error, message):
    """An unknown option or a bad value is named once, before any job runs or anything is
    written; before, every input failed with the same error in its outcome. The name is
    vistrack's, not the dataclass __init__'s."""
    value = 1.5 if option == "high" else 3
    with pytest.raises(error) as e:
        track_many([bench], tmp_path / "out", jobs=1, **{option: value})
    assert str(e.value).startswith(message)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("fps", [-1, 0, "abc", float("nan")])
def test_a_bad_frame_rate_is_named_before_any_job(bench, tmp_path, fps):
    """A frame rate no tracker takes failed every input on its own, each outcome saying
    the same, where plan's other settings are named once before any job. Oracle:
    track_sequence's own message."""
    with pytest.raises(ValueError) as alone:
        track_sequence(bench / "SIM-0" / "det" / "det.txt", tmp_path / "a.txt", fps=fps)
    with pytest.raises(ValueError) as e:
        track_many([bench / "SIM-0" / "det" / "det.txt", bench / "SIM-1" / "det" / "det.txt"],
                   tmp_path / "out", jobs=1, fps=fps)
    assert str(e.value) == str(alone.value)
    assert str(e.value).startswith("fps must be a number from 0.001 to 1e+06")
    assert not (tmp_path / "out").exists()
    # from pixels: the video reader's words, once, before any job
    with pytest.raises(ValueError, match=re.escape(f"fps must be a finite number > 0; got "
                                                   f"{fps}")):
        plan([bench / "SIM-0", bench / "SIM-1"], tmp_path / "out", kind="pixels", fps=fps)


def test_an_input_of_dot_or_dot_dot_is_named_from_the_folder_it_resolves_to(
        bench, tmp_path, monkeypatch, capsys):
    # "." and ".." name nothing: the outputs are named from the folder they resolve to, and
    # stay inside the output folder (before: out/.txt, and out/.. wrote into out's parent)
    monkeypatch.chdir(bench / "SIM-0")
    out = tmp_path / "many"
    assert main(["track", ".", "../SIM-1", "--out", str(out), "--jobs", "1", "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["SIM-0.txt", "SIM-1.txt"]
    assert (out / "SIM-0.txt").read_bytes() == _alone(bench / "SIM-0", tmp_path / "a.txt")
    assert "SIM-0.txt" in capsys.readouterr().out
    assert plan(["."], out)[0].out == out / "SIM-0.txt"
    monkeypatch.chdir(bench / "SIM-0" / "det")
    assert plan([".."], out)[0].out == out / "SIM-0.txt"
    assert plan(["../."], out, kind="pixels")[0].out == out / "SIM-0"
    # (a benchmark folder given as ".." is its sequences, as given by name)
    assert [j.out.name for j in plan(["../.."], out)] == ["SIM-0.txt", "SIM-1.txt",
                                                          "SIM-2.txt"]
    (tmp_path / "frames" / "inner").mkdir(parents=True)
    monkeypatch.chdir(tmp_path / "frames" / "inner")
    assert plan([".."], out, kind="pixels")[0].out == out / "frames"
    # one input, --out FOLDER/ names it the same way
    monkeypatch.chdir(bench / "SIM-2")
    assert main(["track", ".", "--out", f"{tmp_path / 'one'}/", "--quiet"]) == 0
    assert [p.name for p in (tmp_path / "one").iterdir()] == ["SIM-2.txt"]
    # a path that resolves to no name (the root folder) is refused, named
    with pytest.raises(ValueError, match="'?/'? has no name"):
        plan(["/"], out, kind="pixels")


def test_existing_outputs_of_several_videos_are_refused_before_any_runs(tmp_path, capsys):
    a, b = _two_clips(tmp_path)
    out = tmp_path / "out"
    (out / "b").mkdir(parents=True)
    (out / "b" / "tracks.txt").write_text("an earlier result\n")
    # before: a was tracked and written, then b failed (FileExistsError, exit 1)
    assert main(["track", str(a), str(b), "--out-dir", str(out), "--stop", "5", "--jobs",
                 "1", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "tracks.txt" in err and "--force" in err
    assert sorted(p.name for p in out.iterdir()) == ["b"]
    assert (out / "b" / "tracks.txt").read_text() == "an earlier result\n"


def test_an_inputs_error_keeps_where_it_was_raised_and_which_file():
    """In a batch's table an error lost the note of where it was raised (``at frame 3, in
    Bad.step``), which one input's message gives, and a full disk named no file."""
    from vistrack._pool import one_line

    e = ValueError("cannot follow these boxes")
    e.add_note("at frame 3, in badtrk.Bad.step")
    assert one_line(e) == ("ValueError: cannot follow these boxes (at frame 3, in "
                           "badtrk.Bad.step)")
    full = OSError(28, "No space left on device", "out/.A.0123456789.partial.txt")
    assert one_line(full) == "OSError: out/A.txt: No space left on device"
    assert one_line(ValueError("two\n  lines")) == "ValueError: two lines"


def test_a_batchs_counts_of_processes_are_named(bench, tmp_path):
    """``jobs=-1`` failed in the pool ("max_workers must be greater than 0") and ``jobs=0``
    was taken as every core, which ``--jobs 0`` refuses."""
    for jobs in (-1, 0, 1.5):
        with pytest.raises(ValueError, match=re.escape(
                f"jobs must be a whole number >= 1 (processes); got {jobs}")):
            track_many([bench / "SIM-0"], tmp_path / "out", jobs=jobs)
    with pytest.raises(ValueError, match=re.escape("workers must be a whole number >= 1 "
                                                   "(processes); got 0")):
        run_jobs(plan([bench / "SIM-0"], tmp_path / "out"), workers=0)
    assert not (tmp_path / "out").exists()


def test_an_interrupted_batch_counts_a_point_trackers_outputs_as_written(tmp_path):
    """A point tracker writes ``tracks.csv`` and no ``tracks.txt``: an interrupted batch of
    them said "0 of 2 inputs written" where one was."""
    import time

    from vistrack.batch import Job
    from vistrack.cli import _written_since

    t0 = time.time()
    jobs = [Job(Path(f"in{k}"), tmp_path / f"out{k}", "pixels") for k in range(3)]
    jobs.append(Job(Path("seq"), tmp_path / "seq.txt", "detections"))
    (tmp_path / "out0").mkdir()
    (tmp_path / "out0" / "tracks.csv").write_text("frame,id,x,y\n")  # points
    (tmp_path / "out1").mkdir()
    (tmp_path / "out1" / "tracks.txt").write_text("")  # boxes
    (tmp_path / "seq.txt").write_text("")
    assert _written_since(jobs, t0) == ["out0", "out1", "seq.txt"]
    assert _written_since(jobs, t0 + 60) == []


def test_a_batch_stopped_early_on_a_terminal_clears_its_progress_bar(
        bench, tmp_path, monkeypatch, capsys):
    """Without ``--keep-going`` the inputs after a failure are not run, the bar was never
    cleared and the table was printed on its line."""
    import io

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    term = Terminal()
    monkeypatch.setattr(sys, "stderr", term)
    bad = _broken(tmp_path, bench)
    status = main(["track", str(bench / "SIM-0"), str(bad), str(bench / "SIM-1"),
                   "--out", str(tmp_path / "out"), "--jobs", "1"])
    assert status == 1
    assert term.getvalue().endswith("\r\x1b[K")  # the bar's line cleared
    out = capsys.readouterr().out
    assert out.startswith("input ") and "not run" in out
    # the numbers end where their headers do ("not run", 7 wide in a column of 6, moved
    # its row's numbers one to the right)
    lines = out.splitlines()
    header, rows = lines[0], lines[1:4]
    want = [header.index(h) + len(h) for h in ("frames", "tracks", "seconds")]
    for row in rows:
        m = re.search(r" (\d+) +(\d+) +(\d+\.\d) ", row)
        assert m and [m.end(k) for k in (1, 2, 3)] == want, (header, row)
    assert sum("not run" in row for row in rows) == 1


def test_each_inputs_run_json_keeps_the_commands_warnings(tmp_path, capsys):
    """A setting that changes nothing is said once, before the run; one input's
    ``run.json`` kept that warning, several inputs' did not (nor their report pages)."""
    import json
    import shutil

    clip = tmp_path / "clip.mp4"
    shutil.copy(demo_clip().video, clip)
    out = tmp_path / "many"
    assert main(["track", str(clip), str(demo_clip().video), "--out-dir", str(out),
                 "--tracker", "sort", "--low", "0.2", "--stop", "5", "--jobs", "1",
                 "--quiet"]) == 0
    said = [line for line in capsys.readouterr().err.splitlines() if "--low" in line]
    assert len(said) == 1
    for name in ("clip", demo_clip().video.stem):
        kept = json.loads((out / name / "run.json").read_text())["warnings"]
        assert kept[0].startswith("--low: the second association stage's threshold") \
            and kept[0] in said[0]


TERMINATED = """import os, signal, sys, threading
from concurrent.futures.process import BrokenProcessPool
from vistrack._pool import process_pool
from vistrack.io.atomic import PartialFile

def half_written(out):
    f = PartialFile(out)
    f.write("1,1,10,20,30,40,1,-1,-1,-1\\n")
    f.read()  # (flushed: the partial file is on disk)
    os.kill(os.getpid(), signal.SIGTERM)  # as timeout or kill -TERM -PGID sends it
    return "not terminated"

def check(folder):
    with process_pool(1) as pool:
        try:
            got = pool.submit(half_written, os.path.join(folder, "res.txt")).result()
        except BrokenProcessPool:
            got = "died"
    print(got, sorted(os.listdir(folder)))

def theirs_kept(folder):
    # a partial file of this process's, open while a forked worker dies of SIGTERM (as the
    # pool sends its other workers when one dies): the worker's own are removed, not it
    mine = PartialFile(os.path.join(folder, "mine.txt"))
    mine.write("kept\\n")
    mine.read()
    with process_pool(1) as pool:
        try:
            pool.submit(half_written, os.path.join(folder, "res.txt")).result()
        except BrokenProcessPool:
            pass
    mine.commit()
    print(sorted(os.listdir(folder)))

if __name__ == "__main__":
    theirs_kept(sys.argv[3])
    check(sys.argv[1])  # forked
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    check(sys.argv[2])  # spawned
    stop.set()
    other.join()
"""


def test_a_worker_sent_sigterm_removes_its_partial_files_and_dies(tmp_path):
    """SIGTERM sent to the whole process group (``timeout``, ``kill -TERM -PGID``, a service
    manager's stop) ended a worker at once, its outputs left under partial names until a
    later run wrote the same outputs (and ``vistrack eval --pred-dir`` listed them). The
    worker still dies of it, as the pool expects (its job run again elsewhere), forked or
    spawned, but removes them first."""
    (tmp_path / "terminated.py").write_text(TERMINATED)
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1",
               PYTHONPATH=str(Path(__file__).parents[1] / "src"))
    for name in ("forked", "spawned", "parent"):
        (tmp_path / name).mkdir()
    r = subprocess.run([sys.executable, str(tmp_path / "terminated.py"),
                        str(tmp_path / "forked"), str(tmp_path / "spawned"),
                        str(tmp_path / "parent")], env=env,
                       capture_output=True, text=True, timeout=120)
    assert r.stdout.splitlines() == ["['mine.txt']", "died []", "died []"], r.stderr
    assert (tmp_path / "parent" / "mine.txt").read_text() == "kept\n"


MADE = """import os, signal, sys
from concurrent.futures.process import BrokenProcessPool
from vistrack._pool import process_pool
from vistrack.io.atomic import made_folder, replacing

def half_written(out):
    with made_folder(os.path.dirname(out)), replacing(out) as part:
        with open(part, "w") as f:
            f.write("1,1,10,20,30,40,1,-1,-1,-1\\n")
        os.kill(os.getpid(), signal.SIGTERM)  # as timeout or kill -TERM -PGID sends it
    return "not terminated"

if __name__ == "__main__":
    root = sys.argv[1]
    # the parent's own folder, made for a block under way (empty while the worker dies): its
    # forked worker must leave it
    with made_folder(os.path.join(root, "mine")):
        with process_pool(1) as pool:
            try:
                got = pool.submit(half_written,
                                  os.path.join(root, "new", "deep", "res.txt")).result()
            except BrokenProcessPool:
                got = "died"
        print(got, sorted(os.listdir(root)))
"""


def test_a_worker_sent_sigterm_removes_the_folders_it_made(tmp_path):
    """SIGTERM sent to a batch's process group (``timeout 1 vistrack track ... --jobs 2``)
    left each worker's new output folders behind, empty, after the command said "nothing was
    written": the worker's partial files were removed, but the folders made for them stayed
    (their removal is in blocks that SIGTERM's default action never finishes). Oracle: the
    folder's listing; the parent's own folder, made for a block still under way, stays."""
    (tmp_path / "made.py").write_text(MADE)
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1",
               PYTHONPATH=str(Path(__file__).parents[1] / "src"))
    r = subprocess.run([sys.executable, str(tmp_path / "made.py"), str(tmp_path)], env=env,
                       capture_output=True, text=True, timeout=120)
    assert r.stdout.splitlines() == ["died ['made.py', 'mine']"], (r.stdout, r.stderr)


STAGED = """import os, signal, sys
from concurrent.futures.process import BrokenProcessPool
import vistrack.pipeline as pipeline
from vistrack._pool import process_pool

def stopped(text, out, kind, classes_of):
    # the rows are in the staging file beside the CSV: stopped before the CSV is written
    assert os.path.exists(text)
    os.kill(os.getpid(), signal.SIGTERM)  # as timeout or kill -TERM -PGID sends it

def track(det, out):
    pipeline._write_table = stopped
    pipeline.track_sequence(det, out, fps=10)
    return "not terminated"

if __name__ == "__main__":
    folder = sys.argv[1]
    with process_pool(1) as pool:
        try:
            got = pool.submit(track, os.path.join(folder, "det.txt"),
                              os.path.join(folder, "res.csv")).result()
        except BrokenProcessPool:
            got = "died"
    print(got, sorted(os.listdir(folder)))
"""


def test_a_worker_sent_sigterm_removes_a_csv_outputs_staging_file(tmp_path):
    """A CSV or Parquet output is built from its rows written as text beside it under a
    hidden name first; a worker stopped by SIGTERM while it was there left
    ``.res.TOKEN.rows.txt`` behind (the worker's partial files were removed, not it)."""
    (tmp_path / "staged.py").write_text(STAGED)
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "det.txt").write_text("".join(
        f"{f},-1,{10 + 2 * f},20,30,60,0.9,-1,-1,-1\n" for f in range(1, 21)))
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1",
               PYTHONPATH=str(Path(__file__).parents[1] / "src"))
    r = subprocess.run([sys.executable, str(tmp_path / "staged.py"), str(tmp_path / "run")],
                       env=env, capture_output=True, text=True, timeout=120)
    assert r.stdout.splitlines() == ["died ['det.txt']"], r.stderr


def _in_its_own_folder(folder):
    os.chdir(folder)


def test_an_executors_workers_in_another_folder_find_the_inputs_and_write_where_planned(
        bench, tmp_path, monkeypatch):
    """A Dask worker's working folder is its own: relative inputs were looked for there
    (refused), and relative outputs written there while the table said "ok". Its jobs are
    given absolute paths; the outcomes say the paths as planned. Oracle: the same inputs
    tracked alone. The same for vistrack eval's pairs."""
    from concurrent.futures import ProcessPoolExecutor

    from vistrack.evaluation import evaluate_files

    here, elsewhere = tmp_path / "here", tmp_path / "elsewhere"
    here.mkdir()
    elsewhere.mkdir()
    shutil.copytree(bench / "SIM-0", here / "SIM-0")
    monkeypatch.chdir(here)
    with ProcessPoolExecutor(1, initializer=_in_its_own_folder,
                             initargs=(str(elsewhere),)) as pool:
        (outcome,) = run_jobs(plan([Path("SIM-0")], Path("out"), offline=False), executor=pool)
        assert outcome.ok, outcome.error
        assert outcome.input == Path("SIM-0") and outcome.out == Path("out/SIM-0.txt")
        assert (here / "out" / "SIM-0.txt").read_bytes() == _alone(
            here / "SIM-0", tmp_path / "alone.txt")
        assert not list(elsewhere.iterdir())
        # an option naming a file as text, as the command line gives it
        (again,) = run_jobs(plan([Path("SIM-0")], Path("out2"), offline=False,
                                 detections="SIM-0/det/det.txt"), executor=pool)
        assert again.ok, again.error
        assert (here / "out2" / "SIM-0.txt").read_bytes() == (here / "out" / "SIM-0.txt"
                                                                ).read_bytes()
        gt = Path("SIM-0/gt/gt.txt")
        scores = evaluate_files([("s", gt, Path("out/SIM-0.txt"), None)], executor=pool)
        assert scores["s"].TP == evaluate_files([("s", gt, Path("out/SIM-0.txt"), None)])[
            "s"].TP > 0


def exits_in_a_job():
    """A tracker whose making calls sys.exit(0), as a library might."""
    sys.exit(0)


def test_a_job_that_calls_sys_exit_is_reported_and_the_others_run(tmp_path):
    """SystemExit is no Exception: a sys.exit in one job ended the whole batch, status 0
    and no table, the inputs after it not run."""
    from tests.test_pipeline import red_disc_clip, write_clip

    inputs = [write_clip(tmp_path / name, red_disc_clip(T=3)[0]) for name in ("a", "b")]
    jobs = plan(inputs[:1], tmp_path / "out", kind="pixels", fps=10, annotate=False,
                tracker="tests.test_batch:exits_in_a_job") + plan(
        inputs[1:], tmp_path / "out", kind="pixels", fps=10, annotate=False)
    bad, good = run_jobs(jobs, workers=1)
    assert not bad.ok and bad.error == "SystemExit: sys.exit(0) in the job"
    assert good.ok, good.error


def test_several_inputs_take_an_out_folder_named_like_a_file_given_with_a_slash(bench, tmp_path):
    """--out res.csv/ is a folder, as --help says of a name ending in /, and as one input
    takes it; with several inputs it was refused as a file's name."""
    out = tmp_path / "res.csv"
    assert main(["track", str(bench / "SIM-0"), str(bench / "SIM-1"), "--out", f"{out}/",
                 "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["SIM-0.txt", "SIM-1.txt"]


class _DiesAfterMakingItsFolder:
    """An executor whose worker makes the job's output folder and dies."""

    def submit(self, fn, job):
        from concurrent.futures import Future

        Path(job.out).mkdir(exist_ok=True)
        f = Future()
        f.set_exception(RuntimeError("worker lost"))
        return f


def test_a_failed_jobs_empty_new_folder_is_removed_and_an_old_one_kept(tmp_path):
    """A job whose worker died left the output folder it had made, empty. The folder this
    run made is removed; one that was there before the run (an earlier run's) is kept."""
    from vistrack.batch import Job

    old = tmp_path / "old"
    old.mkdir()
    jobs = [Job(tmp_path / "a.mp4", tmp_path / "new", "pixels"), Job(tmp_path / "b.mp4", old,
                                                                       "pixels")]
    outcomes = run_jobs(jobs, executor=_DiesAfterMakingItsFolder())
    assert [o.error for o in outcomes] == ["RuntimeError: worker lost"] * 2
    assert not (tmp_path / "new").exists() and old.is_dir()


def test_track_many_clears_its_bar_when_inputs_are_left_unrun(tmp_path, monkeypatch):
    """Without keep_going, the inputs after a failure are not run, so the bar never reached
    its last input and stayed on the terminal: the caller's next words ran on after
    "about 0 s left". Oracle: the text ends with the bar's line cleared."""
    import io

    import vistrack.batch as batch

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr(batch, "_run", _failing_or_slow)
    monkeypatch.setattr(batch, "plan", lambda inputs, out, **_: [
        batch.Job(tmp_path / name, tmp_path / f"{name}.txt", "detections")
        for name in ("BAD", "A", "B")])
    term = Terminal()
    outcomes = track_many(["x"], tmp_path, jobs=1, keep_going=False, progress=term)
    assert [o.attempts for o in outcomes] == [1, 0, 0]
    text = term.getvalue()
    assert text.endswith("\r\x1b[K")
    assert "inputs" not in text.rsplit("\r\x1b[K", 2)[-1]


def test_runs_in_threads_keep_their_own_warnings():
    """Each run keeps the warnings it gave for its run.json: in a thread pool every run's
    run.json listed every other run's (warnings.catch_warnings swaps the process's one
    showwarning, and is not safe in threads), and a swapped hook could be left in after the
    runs. Oracle: the warnings each thread gave, and the hook there before."""
    import warnings

    from vistrack.pipeline import _shown_warnings

    before = warnings.showwarning
    barrier = threading.Barrier(3)
    kept: dict[int, list[str]] = {}

    def run(k: int) -> None:
        with _shown_warnings() as said:
            for step in range(20):
                barrier.wait()  # the three threads warn step by step, interleaved
                warnings.warn(f"run {k}: step {step}", UserWarning, stacklevel=1)
            with _shown_warnings() as inner:  # a block inside keeps its own too
                warnings.warn(f"run {k}: inner", UserWarning, stacklevel=1)
        kept[k] = said + ["|"] + inner

    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        recorder = warnings.showwarning
        threads = [threading.Thread(target=run, args=(k,)) for k in range(3)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        hook = warnings.showwarning
    for k in range(3):
        own = [f"run {k}: step {step}" for step in range(20)] + [f"run {k}: inner"]
        assert kept[k] == own + ["|", f"run {k}: inner"], kept[k]
    assert len(shown) == 63  # each still shown as it came
    assert hook is recorder and warnings.showwarning is before  # the hooks put back


def test_sequences_sharing_one_image_folder_are_distinct_inputs_of_their_detections(tmp_path):
    """MOT17's sequences of three detectors share one folder of images through links: given
    together (a folder of them) to `vistrack track --out` or `vistrack fit`, which read their
    detections alone, they were refused as one input given twice. Tracked from pixels they
    are still one input given twice. Oracle: each sequence tracked alone."""
    from vistrack.pipeline import fit_sequences

    rng = np.random.default_rng(5)
    share = tmp_path / "share"
    a = _sequence(share / "SIM-FRCNN", rng)
    b = _sequence(share / "SIM-DPM", rng)
    (a / "img1").mkdir()
    (b / "img1").symlink_to(a / "img1", target_is_directory=True)
    assert expand_inputs([share], reads="detections") == [b, a]
    with pytest.raises(ValueError, match="is the same input"):
        expand_inputs([share], reads="pixels")
    with pytest.raises(ValueError, match="is the same input"):
        check_distinct([a, b])  # (both read: as before)
    assert main(["track", str(share), "--out", str(tmp_path / "out") + "/", "--quiet"]) == 0
    for seq in (a, b):
        assert (tmp_path / "out" / f"{seq.name}.txt").read_bytes() == _alone(
            seq, tmp_path / f"{seq.name}-alone.txt")
    assert len(fit_sequences([a, b], gt=True, held_out=False).fit.per_sequence) == 2


def test_an_output_name_too_long_for_a_folder_still_to_be_made_is_named_first(tmp_path,
                                                                               capsys):
    """Outputs are checked before any frame is read: a name longer than the file system
    takes was refused by its stat where its folder existed, but below a folder still to be
    made it was found only when written, the other inputs of the batch tracked first
    (status 1). Oracle: the file system's own refusal of the name (ENAMETOOLONG)."""
    import errno

    from vistrack.io.atomic import check_place

    rng = np.random.default_rng(6)
    long = "S" * 253
    bench = tmp_path / "bench"
    _sequence(bench / "SIM-A", rng, n_objects=2, T=12)
    _sequence(bench / long, rng, n_objects=2, T=12)
    with pytest.raises(OSError) as e:
        (tmp_path / f"{long}.txt").write_text("")
    assert e.value.errno == errno.ENAMETOOLONG
    for where in (tmp_path / "new" / f"{long}.txt", tmp_path / "new" / (long + "SSS") / "a.txt"):
        with pytest.raises(OSError) as e:
            check_place(where)
        assert e.value.errno == errno.ENAMETOOLONG and e.value.filename == str(where)
    assert check_place(tmp_path / "new" / ("S" * 251 + ".txt")) == tmp_path
    out = tmp_path / "out"
    assert main(["track", str(bench), "--out", f"{out}/"]) == 2
    assert capsys.readouterr().err.strip() == (f"vistrack track: error: {out / long}.txt: File "
                                               "name too long")
    assert not out.exists()

"""The writers of tracks stream: MOTChallenge results, CSV and boxes go to a partial file as
the frames come, in the same bytes as the whole file formatted at once, hold no rows in
memory, and leave no file under the final name until the run is complete."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

from vistrack.cli import main
from vistrack.io import PartialFile, box_decimals, partial_path, replacing, write_mot
from vistrack.io.motchallenge import _write_sorted
from vistrack.io.tracks import BoxesWriter, CSVWriter, MOTWriter, TrackRows, write_boxes
from vistrack.pipeline import run, track_sequence
from vistrack.tracking import BoxTracker
from vistrack.types import Detections, Frame, Tracks

from .heap import heap_meter


def random_tracks(rng, n_frames, *, max_rows=8, id_pool=60):
    """Frames 1..n of box tracks with random ids (int32 or int64), boxes and scores, and some
    awkward values (negative zero, halves that round either way, huge and tiny negative
    scores)."""
    out = []
    for f in range(1, n_frames + 1):
        k = int(rng.integers(0, max_rows + 1))
        ids = rng.choice(id_pool, k, replace=False).astype(np.int32 if f % 2 else np.int64)
        xyxy = rng.uniform(-20, 900, (k, 4))
        xyxy[:, 2:] = xyxy[:, :2] + rng.uniform(0, 200, (k, 2))
        scores = rng.uniform(-1, 17, k)
        if k and f % 7 == 0:
            xyxy[0] = [-0.0, 0.125, 2.675, 1.005]
            scores[0] = [-1e-300, 0.99995, 1e-5, 123456.0][f % 4]
        out.append((Frame(f, (f - 1) / 25), Tracks(ids=ids, boxes=xyxy, points=None,
                                                   scores=scores,
                                                   classes=ids % 3 - 1)))  # a track's own
    return out


def rows_of(frames):
    """Every row (frame, id, x, y, w, h, score, class) in the order written, from the boxes."""
    rows = []
    for frame, t in frames:
        b = np.asarray(t.boxes, float)
        for i, (x0, y0, x1, y1), s, c in zip(t.ids.tolist(), b.tolist(), t.scores.tolist(),
                                             t.classes.tolist()):
            rows.append((frame.index, i, x0, y0, x1 - x0, y1 - y0, s, c))
    return rows


def mot_text(rows, decimals=2):
    """The results file formatted at once, row by row with str.format: sorted by frame, then
    id, rows of equal keys in the order written."""
    rows = sorted(rows, key=lambda r: (r[0], r[1]))
    d = decimals
    return "".join(f"{f},{i},{x:.{d}f},{y:.{d}f},{w:.{d}f},{h:.{d}f},{s:.4g},-1,-1,-1\n"
                   for f, i, x, y, w, h, s, _ in rows)


def csv_text(rows):
    return "frame,id,bb_left,bb_top,bb_width,bb_height,conf,class\n" + "".join(
        f"{f},{i},{x:.2f},{y:.2f},{w:.2f},{h:.2f},{s:.3f},{c}\n"
        for f, i, x, y, w, h, s, c in rows)


def test_mot_and_csv_writers_write_the_same_bytes_as_the_whole_file_at_once(tmp_path):
    frames = random_tracks(np.random.default_rng(7), 3000)
    rows = rows_of(frames)
    mot, csv = MOTWriter(tmp_path / "t.txt"), CSVWriter(tmp_path / "t.csv")
    kept = TrackRows()
    for frame, t in frames:
        for sink in (mot, csv, kept):
            sink.write(frame, t)
    mot.close()
    csv.close()
    assert (tmp_path / "t.txt").read_text() == mot_text(rows)
    assert (tmp_path / "t.csv").read_text() == csv_text(rows)
    # and what write_mot's formatting makes of the rows kept in memory
    _write_sorted(tmp_path / "all.txt", np.asarray(kept.frames, np.int64),
                  np.asarray(kept.ids, np.int64), kept.xywh, kept.scores)
    assert (tmp_path / "t.txt").read_bytes() == (tmp_path / "all.txt").read_bytes()
    assert len(mot) == len(csv) == len(rows) > 10_000
    assert mot.identities.tolist() == sorted({r[1] for r in rows})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["all.txt", "t.csv", "t.txt"]


@pytest.mark.parametrize("decimals", [0, 5, 12])
def test_boxes_in_other_units_are_written_with_more_decimals(tmp_path, decimals):
    """Boxes normalised to the image (YOLO's xywhn: 0.13 tall) lost nearly everything to
    MOTChallenge's 2 decimals; the writers take the decimals, streamed or whole, the same
    bytes as str.format's."""
    frames = random_tracks(np.random.default_rng(11), 200)
    for _, t in frames:
        t.boxes[:] = t.boxes / 997.0  # small, and not round in any base
    rows = rows_of(frames)
    mot, kept = MOTWriter(tmp_path / "t.txt", decimals), TrackRows()
    for frame, t in frames:
        mot.write(frame, t)
        kept.write(frame, t)
    mot.close()
    assert (tmp_path / "t.txt").read_text() == mot_text(rows, decimals)
    write_mot(tmp_path / "w.txt", kept.frames, kept.ids, kept.xywh, kept.scores,
              decimals=decimals)
    assert (tmp_path / "w.txt").read_text() == mot_text(rows, decimals)
    with pytest.raises(ValueError, match="decimals must be an integer in 0-12; got 13"):
        MOTWriter(tmp_path / "x.txt", 13)
    with pytest.raises(ValueError, match="decimals must be an integer in 0-12; got 2.5"):
        write_mot(tmp_path / "x.txt", [1], [1], [[0, 0, 1, 1]], decimals=2.5)
    assert box_decimals([0.13] * 3) == 4 and box_decimals([10.0]) == 2
    assert box_decimals([9.0]) == 3 and box_decimals([np.nan, 0.0]) == 2


def test_frames_out_of_order_are_sorted_when_the_file_is_closed(tmp_path):
    frames = random_tracks(np.random.default_rng(8), 300)
    order = np.random.default_rng(9).permutation(len(frames))
    shuffled = [frames[k] for k in order] + frames[:20]  # and some frames twice
    mot = MOTWriter(tmp_path / "t.txt")
    for frame, t in shuffled:
        mot.write(frame, t)
    mot.close()
    assert (tmp_path / "t.txt").read_text() == mot_text(rows_of(shuffled))


def test_the_writers_hold_no_rows_and_write_as_the_frames_come(tmp_path):
    """20,000 frames of 6 rows: the memory the process holds (:func:`heap_meter`) stays where
    it was after the first 1,000 frames (a TrackRows, which keeps the rows, grows by megabytes
    under the same measure), and the rows are on disk under the partial name, none under the
    final one."""
    pool = random_tracks(np.random.default_rng(10), 50, max_rows=6, id_pool=6)
    pool = [t for _, t in pool if len(t) == 6]
    assert pool

    def growth(sinks, n=20_000, settle=1_000):
        held, done = heap_meter()
        try:
            for f in range(1, n + 1):
                for sink in sinks:
                    sink.write(Frame(f, f / 25), pool[f % len(pool)])
                if f == settle:
                    start = held()
            return held() - start
        finally:
            done()

    mot, csv = MOTWriter(tmp_path / "t.txt"), CSVWriter(tmp_path / "t.csv")
    boxes = BoxesWriter(tmp_path / "b.txt")
    streamed = growth([mot, csv])
    kept = growth([TrackRows()])
    assert len(mot) == len(csv) == 120_000
    assert streamed < 64 * 1024, streamed
    assert kept > 3 * 2**20, kept  # the measure sees rows that are kept
    # the boxes writer keeps one box a frame (32 bytes), as an array, and nothing else
    assert growth([boxes]) < 20_000 * 32 * 2.5
    for path in (tmp_path / "t.txt", tmp_path / "t.csv", tmp_path / "b.txt"):
        assert not path.exists()
        [part] = _partials(path)
        assert part.stat().st_size > 100_000  # all but the buffer's last bytes
    mot.close()
    csv.close()
    boxes.close()
    assert len((tmp_path / "t.txt").read_text().splitlines()) == 120_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.txt", "t.csv", "t.txt"]


def test_the_boxes_writer_writes_what_write_boxes_writes(tmp_path):
    rng = np.random.default_rng(11)
    w, want = BoxesWriter(tmp_path / "b.txt"), []
    for f in range(1, 400):
        if rng.uniform() < 0.2:
            w.write(Frame(f, 0.0), Tracks.empty())
            want.append([np.nan] * 4)
            continue
        xyxy = rng.uniform(-10, 500, (2, 4))
        xyxy[:, 2:] += xyxy[:, :2]
        w.write(Frame(f, 0.0), Tracks(ids=np.array([1, 2]), boxes=xyxy, points=None,
                                      scores=np.ones(2), classes=np.zeros(2, int)))
        want.append([xyxy[0, 0], xyxy[0, 1], xyxy[0, 2] - xyxy[0, 0], xyxy[0, 3] - xyxy[0, 1]])
    w.close()
    write_boxes(tmp_path / "want.txt", want)
    assert (tmp_path / "b.txt").read_bytes() == (tmp_path / "want.txt").read_bytes()
    np.testing.assert_array_equal(w.boxes, np.array(want))


@pytest.mark.parametrize("shape", [(3, 8), (4, 2), (3, 2), (4,), (2, 4, 1)])
def test_write_boxes_refuses_what_is_not_one_box_a_frame(tmp_path, shape):
    """A VOT polygon's (T, 8) corners, or (T, 2) centres, were reshaped into other boxes and
    written without a word (and (3, 2) failed inside numpy's reshape)."""
    with pytest.raises(ValueError, match=re.escape("boxes must be")):
        write_boxes(tmp_path / "b.txt", np.ones(shape))
    assert not (tmp_path / "b.txt").exists()
    write_boxes(tmp_path / "none.txt", np.zeros((0, 4)))
    assert (tmp_path / "none.txt").read_text() == ""


def truth_detector(frames, stop=None):
    """Detections of three boxes moving apart, one call a frame; KeyboardInterrupt (Ctrl-C)
    in frame ``stop``."""

    def detect(frame):
        if frame.index == stop:
            raise KeyboardInterrupt
        f = frame.index
        return Detections.from_xywh([[10 + 3 * f, 20, 30, 60], [200 - 2 * f, 40, 30, 60],
                                     [100, 100 + f, 40, 40]], [0.9, 0.8, 0.95])

    return detect


def test_an_interrupted_run_leaves_no_file_under_a_final_name(tmp_path):
    frames = [Frame(k, (k - 1) / 25) for k in range(1, 31)]
    names = ["t.txt", "t.csv", "b.txt"]

    def sinks(folder):
        return [MOTWriter(folder / "t.txt"), CSVWriter(folder / "t.csv"),
                BoxesWriter(folder / "b.txt")]

    # nothing there before: nothing there after, not even a partial file
    fresh = tmp_path / "fresh"
    seen = []

    def look(frame):  # in the middle of the run: partial files, no final names
        if frame.index == 12:
            seen.append(sorted(p.name for p in fresh.iterdir()))
        return truth_detector(frames, stop=20)(frame)

    with pytest.raises(KeyboardInterrupt):
        run(frames, look, BoxTracker(), sinks(fresh))
    assert len(seen) == 1 and len(seen[0]) == len(names)
    for n in names:  # one partial file each, under a hidden name of its own
        stem, suffix = n.split(".")
        assert sum(bool(re.fullmatch(rf"\.{stem}\.[0-9a-f]{{10}}\.partial\.{suffix}", m))
                   for m in seen[0]) == 1
    assert list(fresh.iterdir()) == []

    # an earlier run's files stay byte for byte
    earlier = tmp_path / "earlier"
    run(frames, truth_detector(frames), BoxTracker(), sinks(earlier))
    before = {p.name: p.read_bytes() for p in earlier.iterdir()}
    assert sorted(before) == sorted(names) and all(before.values())
    with pytest.raises(KeyboardInterrupt):
        run(frames, truth_detector(frames, stop=20), BoxTracker(), sinks(earlier))
    assert {p.name: p.read_bytes() for p in earlier.iterdir()} == before


def test_a_sink_that_fails_to_close_aborts_the_sinks_after_it(tmp_path):
    frames = [Frame(k, (k - 1) / 25) for k in range(1, 11)]

    class Broken:
        def write(self, frame, tracks):
            pass

        def close(self):
            raise OSError("no space left on device")

    sinks = [MOTWriter(tmp_path / "a.txt"), Broken(), CSVWriter(tmp_path / "c.csv")]
    with pytest.raises(OSError, match="no space left"):
        run(frames, truth_detector(frames), BoxTracker(), sinks)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]  # closed before the failure


def test_a_partial_file_that_cannot_be_renamed_is_removed(tmp_path):
    f = PartialFile(tmp_path / "t.txt")
    f.write("rows\n")
    # the final name taken by a folder after the file was opened (a folder there before is
    # refused when it is made: test_motchallenge_io)
    (tmp_path / "t.txt").mkdir()
    with pytest.raises(OSError):
        f.commit()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.txt"]
    assert (tmp_path / "t.txt").is_dir()


def test_replacing_removes_its_partial_file_when_the_rename_fails(tmp_path):
    """As a PartialFile does (above): the rename over a folder failed and left the partial
    file behind, for write_mot, tables, plots and the report."""
    (tmp_path / "res.txt").mkdir()
    (tmp_path / "res.txt" / "k").write_text("x")
    with pytest.raises(OSError):
        write_mot(tmp_path / "res.txt", [1], [1], [[0, 0, 1, 1]], force=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["res.txt"]
    with pytest.raises(OSError), replacing(tmp_path / "new.txt") as part:
        part.write_text("rows")
        (tmp_path / "new.txt").mkdir()  # taken by a folder while written
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new.txt", "res.txt"]


def test_two_writers_of_one_path_each_write_their_own_partial_file(tmp_path):
    """Two runs (or writers) given the same output shared one partial file: each truncated it
    and wrote at its own offset, and the first to finish renamed the mixture into place (a
    NUL byte at 162,200; a row of 12 values). Each now writes its own, and the file is one
    writer's whole output, the last to finish; a name too long for the partial name's
    additions is cut to fit, with a hash (an OSError after the whole run before)."""
    from vistrack.io import read_mot

    out = tmp_path / "same.txt"
    a, b = MOTWriter(out), MOTWriter(out)
    rows = [Tracks(ids=np.array([i]), boxes=np.array([[0, 0, 10, 10.0]]) + i, points=None,
                   scores=np.ones(1), classes=np.zeros(1)) for i in range(1, 3000)]
    for f, t in enumerate(rows, 1):
        a.write(Frame(f, f / 25), t)
        if f > 1500:  # the second starts halfway
            b.write(Frame(f, f / 25), t)
    assert len(list(tmp_path.glob(".same.*.partial.txt"))) == 2
    a.close()
    assert len(read_mot(out)) == 2999
    b.close()
    got = read_mot(out)
    assert len(got) == 1499 and got.frames.min() == 1501
    assert sorted(p.name for p in tmp_path.iterdir()) == ["same.txt"]
    # a writer killed (SIGKILL) leaves its partial file: the next to complete the output
    # removes it, as the shared name used to be overwritten; a live writer's stays
    import subprocess
    import sys

    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    dead = tmp_path / f".same.{int(gone.stdout) % 16**6:06x}beef.partial.txt"
    live = tmp_path / f".same.{os.getppid() % 16**6:06x}beef.partial.txt"
    dead.write_text("half")
    live.write_text("half")
    write_mot(out, [1], [1], [[0, 0, 1, 1]], force=True)
    assert not dead.exists() and live.exists()
    live.unlink()
    long = tmp_path / ("r" * 251 + ".txt")  # 255 bytes: the longest name the folder takes
    write_mot(long, [1], [1], [[0, 0, 1, 1]])
    assert read_mot(long).ids.tolist() == [1]
    part = partial_path(long)
    assert len(part.name.encode()) <= 255 and part.parent == tmp_path


def test_track_sequence_online_writes_what_the_rows_kept_in_memory_give(tmp_path):
    """The online results of a sequence, written as the frames come, equal write_mot of the
    same tracker's rows kept in memory; the counts are the file's."""
    seq = tmp_path / "seq"
    (seq / "det").mkdir(parents=True)
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=seq\nframeRate=10\nseqLength=60\n"
                                     "imWidth=640\nimHeight=480\n")
    rng = np.random.default_rng(12)
    lines = []
    for f in range(1, 61):
        for k in range(4):
            if rng.uniform() < 0.9:
                x, y = 20 + 100 * k + 2 * f + rng.normal(0, 1), 50 + 30 * k + rng.normal(0, 1)
                lines.append(f"{f},-1,{x:.2f},{y:.2f},40,80,{rng.uniform(0.3, 1):.3f}\n")
    (seq / "det" / "det.txt").write_text("".join(lines))
    r = track_sequence(seq, tmp_path / "online.txt")

    from vistrack.io import read_mot

    dets = read_mot(seq / "det" / "det.txt")
    slices = dets.frame_slices(60)
    xyxy = np.c_[dets.boxes[:, :2], dets.boxes[:, :2] + dets.boxes[:, 2:]]
    rows = TrackRows()
    trk = BoxTracker(r.config.tracker, motion=r.config.motion, frame_rate=10.0,
                     image_size=(640, 480))
    run([Frame(f, (f - 1) / 10) for f in range(1, 61)],
        lambda fr: Detections(boxes=xyxy[slices[fr.index - 1]], scores=dets.conf[
            slices[fr.index - 1]]), trk, [rows])
    write_mot(tmp_path / "want.txt", rows.frames, rows.ids, rows.xywh, rows.scores)
    assert (tmp_path / "online.txt").read_bytes() == (tmp_path / "want.txt").read_bytes()
    assert r.rows == len(rows) > 100 and r.tracks == len(np.unique(rows.ids)) >= 4
    assert not _partials(tmp_path / "online.txt")
    assert isinstance(r.out, Path)


def test_the_trajectory_plot_draws_the_rows_it_was_given(tmp_path):
    """The plot keeps each row's frame, identity and centre only; its PNG is byte for byte
    the figure of the rows' centres computed here from the boxes."""
    from vistrack.viz import TrajectoryPlot, plot_trajectories

    frames = random_tracks(np.random.default_rng(13), 120, id_pool=12)
    image = np.random.default_rng(14).integers(0, 255, (120, 160, 3), dtype=np.uint8)
    plot = TrajectoryPlot(tmp_path / "t.png", "demo")
    for frame, t in frames:
        plot.write(Frame(frame.index, frame.time, image), t)
    plot.close()
    rows = np.array([r[:6] for r in rows_of(frames)])
    ids = rows[:, 1].astype(int)
    plot_trajectories(rows[:, 0].astype(int), ids, rows[:, 2:4] + rows[:, 4:6] / 2,
                      image[..., ::-1], tmp_path / "want.png",
                      title=f"demo: {len(set(ids.tolist()))} tracks, 120 frames")
    assert (tmp_path / "t.png").read_bytes() == (tmp_path / "want.png").read_bytes()


def test_a_nameless_trajectory_plot_titles_its_counts_alone(tmp_path):
    """Without a name the title is the counts, the same PNG as the figure titled so: it
    read ": 2 tracks, 3 frames" before; one track of one frame is "1 track, 1 frame"."""
    from vistrack.viz import TrajectoryPlot, plot_trajectories

    plot = TrajectoryPlot(tmp_path / "t.png")
    boxes = np.array([[0, 0, 4, 4.0], [10, 10, 12, 12]])  # x1, y1, x2, y2
    for f in range(1, 4):
        plot.write(Frame(f, 0.0), Tracks(ids=np.array([1, 2]), boxes=boxes + f, points=None,
                                         scores=np.ones(2), classes=np.zeros(2)))
    plot.close()
    centres = np.concatenate([((boxes + f)[:, :2] + (boxes + f)[:, 2:]) / 2 for f in range(1, 4)])
    plot_trajectories(np.repeat([1, 2, 3], 2), np.tile([1, 2], 3), centres, None,
                      tmp_path / "want.png", title="2 tracks, 3 frames")
    assert (tmp_path / "t.png").read_bytes() == (tmp_path / "want.png").read_bytes()
    one = TrajectoryPlot(tmp_path / "o.png", "x")  # one of each: no plural
    one.write(Frame(1, 0.0), Tracks(ids=np.array([1]), boxes=boxes[:1], points=None,
                                    scores=np.ones(1), classes=np.zeros(1)))
    one.close()
    plot_trajectories(np.array([1]), np.array([1]), np.array([[2.0, 2]]), None,
                      tmp_path / "want1.png", title="x: 1 track, 1 frame")
    assert (tmp_path / "o.png").read_bytes() == (tmp_path / "want1.png").read_bytes()


def test_the_trajectory_plot_draws_all_tracks_in_two_artists(tmp_path):
    """Each track's centres in frame order (rows given in any order), its end dot at its last
    centre, both in the identity's colour of the annotated video (``id_colour``, BGR there),
    labelled with the identity at the dot up to 100 tracks; beyond, as many artists for 300
    tracks as for 101, so that an hour of video draws in bounded memory."""
    from vistrack.viz import plot_trajectories
    from vistrack.viz.annotate import id_colour

    rng = np.random.default_rng(5)
    children = []
    for n in (3, 101, 300):
        lens = rng.integers(1, 30, n)
        ids = np.repeat(rng.permutation(np.arange(10, 10 + 7 * n, 7)), lens)
        frames = np.concatenate([rng.integers(1, 500) + np.arange(k) for k in lens])
        c = rng.uniform(0, 100, (len(ids), 2))
        shuffle = rng.permutation(len(ids))
        fig = plot_trajectories(frames[shuffle], ids[shuffle], c[shuffle],
                                path=tmp_path / f"{n}.png")
        ax = fig.axes[0]
        paths, dots = ax.collections
        want = [c[ids == i][np.argsort(frames[ids == i])] for i in np.unique(ids)]
        assert len(paths.get_segments()) == n
        for got, w in zip(paths.get_segments(), want, strict=True):
            assert np.array_equal(got, w)
        assert np.array_equal(dots.get_offsets(), [w[-1] for w in want])
        rgba = np.c_[[np.array(id_colour(i)[::-1]) / 255 for i in np.unique(ids)], np.ones(n)]
        assert np.allclose(paths.get_colors(), rgba, atol=1e-12)
        assert np.allclose(dots.get_facecolors(), rgba, atol=1e-12)
        labels = [(t.get_text(), t.xy) for t in ax.texts]
        if n <= 100:
            assert labels == [(str(i), tuple(w[-1])) for i, w in zip(np.unique(ids), want)]
        else:
            assert labels == []
        children.append(len(ax.get_children()))
    assert children[1] == children[2] and children[0] == children[1] + 3


@pytest.mark.parametrize("background", [False, True])
def test_labels_of_tracks_that_end_together_do_not_cover_one_another(tmp_path, background):
    """Ten tracks ending within 3 pixels of one another (identities of one to three digits):
    every label, drawn, lies clear of the others (matplotlib's own extents of the rendered
    text), each still annotating its track's last centre; they were all drawn up and to the
    right of their dots, over one another (the bundled clip's 1, 6 and 11)."""
    from vistrack.viz import plot_trajectories

    rng = np.random.default_rng(2)
    ends = 300 + rng.uniform(-1.5, 1.5, (10, 2))
    ids = np.array([1, 6, 11, 7, 100, 23, 5, 42, 9, 310])
    frames = np.tile([1, 2], 10)
    c = np.stack([ends - [40, 20], ends], axis=1).reshape(-1, 2)
    image = np.full((576, 768, 3), 200, np.uint8) if background else None
    fig = plot_trajectories(frames, np.repeat(ids, 2), c, image, tmp_path / "p.png")
    ax = fig.axes[0]
    fig.canvas.draw()
    boxes = [t.get_window_extent() for t in ax.texts]
    assert sorted(t.get_text() for t in ax.texts) == sorted(map(str, ids))
    for t in ax.texts:
        assert np.allclose(t.xy, ends[list(ids).index(int(t.get_text()))])
    for a in range(len(boxes)):
        for b in range(a):
            assert not boxes[a].overlaps(boxes[b]), (ax.texts[a].get_text(),
                                                     ax.texts[b].get_text())


def test_labels_of_tracks_that_end_at_the_images_edge_stay_inside_it(tmp_path):
    """Tracks that end at the image's right edge, its top, its top-right corner and its
    bottom-left one: each label, drawn (matplotlib's extent of the rendered text), lies
    inside the axes, still annotating its track's last centre, and clear of the others; the
    label of a track ending at the right edge went across the frame (the bundled clip's 9)."""
    from vistrack.viz import plot_trajectories

    ends = np.array([[767.0, 300.0], [400.0, 0.5], [767.0, 0.5], [0.5, 575.0], [766.0, 320.0]])
    ids = np.array([9, 12, 310, 4, 77])
    frames = np.tile([1, 2], len(ids))
    c = np.stack([ends + [-30, 30] * np.sign(ends - [384, 288]) * -1, ends], axis=1
                 ).reshape(-1, 2)
    image = np.full((576, 768, 3), 200, np.uint8)
    fig = plot_trajectories(frames, np.repeat(ids, 2), c, image, tmp_path / "p.png")
    ax = fig.axes[0]
    fig.canvas.draw()
    frame = ax.get_window_extent()
    boxes = [t.get_window_extent() for t in ax.texts]
    assert sorted(t.get_text() for t in ax.texts) == sorted(map(str, ids))
    for t, box in zip(ax.texts, boxes):
        assert np.allclose(t.xy, ends[list(ids).index(int(t.get_text()))])
        assert (frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0
                and box.y1 <= frame.y1), (t.get_text(), box, frame)
    for a in range(len(boxes)):
        for b in range(a):
            assert not boxes[a].overlaps(boxes[b]), (ax.texts[a].get_text(),
                                                     ax.texts[b].get_text())


@pytest.mark.parametrize("grey", [False, True])
def test_a_saved_plots_background_is_what_matplotlib_draws(tmp_path, grey):
    """Saved, the background is put under the drawing instead of being drawn by matplotlib;
    the PNG is the one matplotlib draws from the figure returned (the image shown there),
    but for the resampling filter at the image's edges. Grey images are stretched over their
    range as imshow's colour map does (here 60-180)."""
    import cv2

    from vistrack.viz import plot_trajectories

    rng = np.random.default_rng(8)
    image = cv2.GaussianBlur(rng.integers(0, 255, (300, 400, 3), dtype=np.uint8), (0, 0), 3)
    cv2.rectangle(image, (50, 40), (120, 200), (200, 30, 30), -1)
    if grey:
        image = (60 + image[..., 0] / 255 * 120).astype(np.float64)
    ids = np.repeat([1, 2, 3], 20)
    frames = np.tile(np.arange(20), 3)
    c = rng.uniform(0, 300, (60, 2))
    fig = plot_trajectories(frames, ids, c, image, tmp_path / "saved.png", title="t")
    assert fig.axes[0].images[0].get_visible()
    fig.savefig(tmp_path / "matplotlib.png", dpi=100)
    got = cv2.imread(str(tmp_path / "saved.png"), cv2.IMREAD_UNCHANGED).astype(int)
    want = cv2.imread(str(tmp_path / "matplotlib.png"), cv2.IMREAD_UNCHANGED).astype(int)
    assert got.shape == want.shape == (700, 900, 4)
    diff = np.abs(got - want).max(axis=2)
    assert diff.mean() < 0.5 and np.percentile(diff, 99) <= 6, (diff.mean(), diff.max())


def test_a_saved_plot_draws_a_frame_in_a_few_mb(tmp_path):
    """A 768x576 frame under the paths: matplotlib's own drawing of it allocated 37 MB
    (resampled in floating point), at the end of a run; saved, the plot allocates under
    12 MB (tracemalloc, which numpy's arrays report to)."""
    import tracemalloc

    from vistrack.viz import plot_trajectories

    rng = np.random.default_rng(9)
    image = rng.integers(0, 255, (576, 768, 3), dtype=np.uint8)
    args = (np.tile(np.arange(50), 20), np.repeat(np.arange(20), 50),
            rng.uniform(0, 576, (1000, 2)), image)
    plot_trajectories(*args, tmp_path / "warm.png")  # fonts and caches loaded once
    tracemalloc.start()
    plot_trajectories(*args, tmp_path / "p.png")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 12 * 2 ** 20, peak / 2 ** 20


def test_a_saved_trajectory_plot_leaves_pyplot_alone(tmp_path):
    """Saved to a file, the plot is drawn without pyplot: in a fresh interpreter pyplot is not
    imported and the backend is not switched (a notebook's stays as it was); TrajectoryPlot
    imports what it draws with when made, before any frame."""
    code = f"""
import sys
import matplotlib
backend = matplotlib.rcParams._get_backend_or_none()
from vistrack.viz import TrajectoryPlot, plot_trajectories
plot = TrajectoryPlot({str(tmp_path / "t.png")!r})
assert "matplotlib.figure" in sys.modules
plot_trajectories([1, 2], [1, 1], [[0, 0], [1, 1]], path={str(tmp_path / "p.png")!r})
assert "matplotlib.pyplot" not in sys.modules
assert matplotlib.rcParams._get_backend_or_none() == backend
print("ok")
"""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout == "ok\n", out.stderr


def test_replacing_removes_the_folders_it_made_when_interrupted(tmp_path):
    """An interrupted write under folders that did not exist leaves neither file nor folder;
    a folder that existed, or that holds something else, stays."""
    from vistrack.io.atomic import replacing

    with pytest.raises(KeyboardInterrupt), replacing(tmp_path / "a" / "b" / "x.txt") as part:
        part.write_text("half")
        raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "keep.txt").write_text("other")
    with pytest.raises(KeyboardInterrupt), replacing(tmp_path / "a" / "b" / "x.txt") as part:
        raise KeyboardInterrupt
    assert [p.name for p in (tmp_path / "a").iterdir()] == ["keep.txt"]


@pytest.mark.parametrize("frame,ids,box,score,message", [
    (0, [1], [0.0, 0.0, 1.0, 1.0], 1.0, "frame 0: MOTChallenge frames count from 1"),
    (1, [1], [np.nan, 0.0, 1.0, 1.0], 1.0, "frame 1, track 1: box (x, y, w, h) [nan, 0.0, "),
    (1, [1.7], [0.0, 0.0, 1.0, 1.0], 1.0, "frame 1: ids[0] = 1.7 is not a whole number"),
    # a tracker's class NaN was written as -9223372036854775808, 2.7 as 2
    (1, [1], [0.0, 0.0, 1.0, 1.0], (1.0, np.nan), "frame 1: classes[0] = nan is not a whole "
                                                  "number"),
    (1, [1], [0.0, 0.0, 1.0, 1.0], (1.0, 2.7), "frame 1: classes[0] = 2.7 is not a whole "
                                               "number"),
    (1, [1], [0.0, 0.0, 1.0, 1.0], np.inf, "frame 1, track 1: box (x, y, w, h) [0.0, 0.0, 1.0,"
                                           " 1.0], score inf: a row read_mot refuses"),
])
@pytest.mark.parametrize("sink", [MOTWriter, CSVWriter])
def test_the_file_sinks_refuse_rows_read_mot_would_refuse(tmp_path, sink, frame, ids, box,
                                                          score, message):
    """The sinks wrote frame 0, NaN boxes and infinite scores, which read_mot then refused
    (as write_mot refuses them), and wrote track 1.7 as track 1."""
    x0, y0, w, h = box
    score, cls = score if isinstance(score, tuple) else (score, 0)
    tracks = Tracks(ids=np.asarray(ids), boxes=np.array([[x0, y0, x0 + w, y0 + h]]),
                    points=None, scores=np.array([score]), classes=np.array([cls]))
    out = sink(tmp_path / ("t.txt" if sink is MOTWriter else "t.csv"))
    with pytest.raises(ValueError, match="^" + re.escape(message)):
        out.write(Frame(frame, 0.0), tracks)


@pytest.mark.parametrize("kind", ["mot", "csv", "points"])
def test_the_file_sinks_refuse_a_track_given_twice_in_a_frame(tmp_path, kind):
    """The sinks wrote track 3 twice in frame 2, in one call or in two calls for the frame,
    and the file was refused only when scored (evaluate_mot names the two lines: the oracle
    of what a results file may hold). A frame after it may hold track 3 again, and a frame
    given again later (out of order) adds its own tracks."""
    from vistrack.evaluation import evaluate_mot
    from vistrack.io import PointsCSVWriter, read_mot

    def tracks(ids):
        n = len(ids)
        xy = np.arange(2.0 * n).reshape(n, 2) * 10
        if kind == "points":
            return Tracks(ids=np.array(ids), boxes=None, points=xy, scores=np.ones(n),
                          classes=np.zeros(n))
        return Tracks(ids=np.array(ids), boxes=np.c_[xy, xy + 5], points=None,
                      scores=np.ones(n), classes=np.zeros(n))

    path = tmp_path / ("t.txt" if kind == "mot" else "t.csv")
    # what the sinks wrote: a file evaluate_mot refuses
    write_mot(tmp_path / "old.txt", [2, 2], [3, 3], [[0, 0, 5, 5], [10, 10, 5, 5]])
    with pytest.raises(ValueError, match="id 3 appears more than once in frame 2"):
        evaluate_mot(read_mot(tmp_path / "old.txt"), read_mot(tmp_path / "old.txt"))
    sink = {"mot": MOTWriter, "csv": CSVWriter, "points": PointsCSVWriter}[kind](path)
    said = "frame 2: track 3 is given twice (a track is one row a frame"
    with pytest.raises(ValueError, match=re.escape(said)):
        sink.write(Frame(2, 0.0), tracks([3, 5, 3]))
    sink.write(Frame(2, 0.0), tracks([3, 5]))
    with pytest.raises(ValueError, match=re.escape(said)):
        sink.write(Frame(2, 0.0), tracks([7, 3]))
    sink.write(Frame(2, 0.0), tracks([7]))
    sink.write(Frame(3, 0.0), tracks([3]))
    sink.write(Frame(2, 0.0), tracks([8]))  # (frame 2's earlier tracks are not kept)
    assert len(sink) == 5 and sink.identities.tolist() == [3, 5, 7, 8]
    sink.close()
    if kind == "mot":
        t = read_mot(path)
        assert list(zip(t.frames.tolist(), t.ids.tolist())) == [(2, 3), (2, 5), (2, 7), (2, 8),
                                                                 (3, 3)]


def test_the_points_sink_takes_no_tracks_of_either_kind(tmp_path):
    """PointsCSVWriter refused Tracks.empty() (whose default is box tracks) as box tracks: a
    frame without tracks is nothing to write, whatever their kind."""
    from vistrack.io import PointsCSVWriter

    sink = PointsCSVWriter(tmp_path / "p.csv")
    sink.write(Frame(1, 0.0), Tracks.empty())
    sink.write(Frame(2, 0.0), Tracks.empty(boxes=False))
    with pytest.raises(ValueError, match="takes point tracks; these are boxes"):
        sink.write(Frame(3, 0.0), Tracks(ids=np.array([1]), boxes=np.array([[0.0, 0, 2, 2]]),
                                         points=None, scores=np.ones(1), classes=np.zeros(1)))
    with pytest.raises(ValueError, match="frames count from 1"):
        sink.write(Frame(0, 0.0), Tracks.empty())
    sink.close()
    assert (tmp_path / "p.csv").read_text() == "frame,particle,x,y\n" and len(sink) == 0


def test_track_rows_refuse_an_id_that_is_not_whole():
    """TrackRows took ids 1.2 and 1.7 as track 1 both (two tracks merged, no word), where the
    file sinks name them (the test above); whole ids of any numeric type are taken."""
    tracks = Tracks(ids=np.array([1.2, 1.7]), boxes=np.array([[0, 0, 10, 10.0], [50, 50, 60, 60]]),
                    points=None, scores=np.array([0.9, 0.8]), classes=np.zeros(2))
    rows = TrackRows()
    with pytest.raises(ValueError, match=re.escape("frame 3: ids[0] = 1.2 is not a whole number")):
        rows.write(Frame(3, 0.0), tracks)
    assert len(rows) == 0
    rows.write(Frame(3, 0.0), Tracks(ids=np.array([4.0, 9.0]), boxes=tracks.boxes, points=None,
                                     scores=tracks.scores, classes=tracks.classes))
    assert rows.ids.tolist() == [4, 9] and rows.frames.tolist() == [3, 3]


def _partials(path):
    """The partial files of ``path`` on disk (their names carry a token of their own)."""
    path = Path(path)
    return sorted(path.parent.glob(f".{path.stem}.*.partial{path.suffix}"))


def test_a_full_disk_is_named_by_the_output_it_stopped(tmp_path, monkeypatch):
    """A buffered write's "No space left on device" named no file: ``vistrack track: error:
    [Errno 28] No space left on device``, and in a batch's table the same. The partial file's
    name is given, which the command line turns into the output's."""
    import vistrack.io.atomic as atomic
    from vistrack.cli import _message

    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full here to fill a disk with")
    real_open = open
    monkeypatch.setattr(atomic, "open", lambda path, mode: real_open("/dev/full", mode),
                        raising=False)  # a full disk
    out = tmp_path / "res.txt"
    for last in ("write", "commit"):
        f = PartialFile(out)
        with pytest.raises(OSError) as e:
            if last == "write":
                for _ in range(100):  # past the write buffer
                    f.write("1,1,10,20,30,40,1,-1,-1,-1\n" * 100)
            else:
                f.write("1,1,10,20,30,40,1,-1,-1,-1\n")  # in the buffer: the last flush
                f.commit()
        f.abort()
        assert e.value.errno == 28 and _message(e.value) == f"{out}: No space left on device"
        assert list(tmp_path.iterdir()) == []


def test_a_processs_hidden_names_never_repeat_even_from_threads():
    """A partial name's token was the process id and 4 random hex digits: 1,000 names in one
    process repeated one another about 8 times, so two writers of one output in one process
    (two threads) could write one partial file. The 4 digits now count: 65,536 names in a
    row, from 8 threads at once, all differ."""
    from concurrent.futures import ThreadPoolExecutor

    from vistrack.io.atomic import final_path, hidden_path

    def names(_):
        return [hidden_path("out/tracks.txt", "partial.txt") for _ in range(16**4 // 8)]

    with ThreadPoolExecutor(8) as pool:
        got = [p for batch in pool.map(names, range(8)) for p in batch]
    assert len(got) == len(set(got)) == 16**4
    assert {final_path(p) for p in got} == {"out/tracks.txt"}


def test_a_dead_writers_staging_file_is_removed_when_the_output_is_complete(tmp_path):
    """A CSV's rows are staged as text beside it (``.res.TOKEN.rows.txt``); one left by a
    writer that died is removed when another completes the CSV, as its partial files are,
    and a live writer's stays. The staging file is gone when its block ends, however it
    ends."""
    import subprocess
    import sys

    from vistrack.io.atomic import _NAMED, staging

    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    out = tmp_path / "res.csv"
    dead = tmp_path / f".res.{int(gone.stdout) % 16**6:06x}beef.rows.txt"
    live = tmp_path / f".res.{os.getppid() % 16**6:06x}beef.rows.txt"
    dead.write_text("half")
    live.write_text("half")
    t = Tracks(ids=np.array([1]), boxes=np.array([[0, 0, 10, 10.0]]), points=None,
               scores=np.ones(1), classes=np.zeros(1))
    w = CSVWriter(out)
    w.write(Frame(1, 0.0), t)
    w.close()
    assert not dead.exists() and live.exists()
    live.unlink()
    with pytest.raises(KeyboardInterrupt), staging(out) as rows:
        rows.write_text("1,1,0,0,1,1,1,-1,-1,-1\n")
        assert rows in _NAMED
        raise KeyboardInterrupt
    assert rows not in _NAMED
    assert sorted(p.name for p in tmp_path.iterdir()) == ["res.csv"]


def test_a_video_cut_short_by_a_failed_write_is_named_and_replaces_nothing(tmp_path):
    """OpenCV's writer says nothing of a write that fails: under a limit on a file's size
    (as a full disk, or FAT32's 4 GiB), the annotated video was cut short without its index,
    unreadable, and replaced an earlier complete one, the run saying it wrote it. Oracle:
    the operating system's limit on the file's size (RLIMIT_FSIZE) in a child process;
    the file's own frame count; the earlier video byte for byte."""
    import subprocess
    import sys

    script = tmp_path / "w.py"
    script.write_text(
        "import resource, sys, numpy as np\n"
        "from vistrack.io.video import VideoWriter, VideoError\n"
        "from vistrack.viz.annotate import AnnotatedVideo\n"
        "from vistrack.types import Frame, Tracks\n"
        "rng = np.random.default_rng(0)\n"
        "resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, resource.RLIM_INFINITY))\n"
        "video = AnnotatedVideo(sys.argv[1], fps=10)\n"
        "for k in range(1, 61):\n"
        "    video.write(Frame(k, 0.0, rng.integers(0, 256, (240, 320, 3), np.uint8)),\n"
        "                Tracks.empty())\n"
        "try:\n"
        "    video.close()\n"
        "except VideoError as e:\n"
        "    video.abort()\n"
        "    print(e)\n")
    out = tmp_path / "a.mp4"
    out.write_bytes(b"an earlier complete video")
    r = subprocess.run([sys.executable, str(script), str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert re.fullmatch(rf"{re.escape(str(out))}: the video file holds \d+ of the 60 frames "
                        r"written to it: the disk is full, or a limit on a file's size was "
                        r"reached\n", r.stdout), r.stdout
    assert out.read_bytes() == b"an earlier complete video"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4", "w.py"]


def test_a_video_writer_names_a_frame_of_no_pixels_and_stays_whole(tmp_path, monkeypatch):
    """A frame of shape (0, 0, 3) was blamed on the file ("OpenCV cannot write an MP4 here"),
    and the writer kept the unopened OpenCV writer: the next, good frame failed with a bare
    AssertionError and close() reported nothing of a video never written. A writer that
    OpenCV cannot open is left as it was: a frame given again tries again. Oracle: the
    frames read back."""
    import cv2

    from vistrack.io.video import VideoError, VideoReader, VideoWriter

    w = VideoWriter(tmp_path / "z.mp4", fps=10)
    for shape in ((0, 0, 3), (0, 10, 3), (10, 0)):
        with pytest.raises(ValueError, match=re.escape(
                f"z.mp4: frame 1 has no pixels: its shape is {shape}")):
            w.write(np.zeros(shape, np.uint8))
    real = cv2.VideoWriter

    class Unopened:
        def __init__(self, *args):
            pass

        def isOpened(self):
            return False

        def release(self):
            pass

    monkeypatch.setattr(cv2, "VideoWriter", Unopened)
    with pytest.raises(VideoError, match="cannot write an MP4 here"):
        w.write(np.zeros((16, 16, 3), np.uint8))
    monkeypatch.setattr(cv2, "VideoWriter", real)
    for k in range(3):
        w.write(np.full((16, 16, 3), 40 * k, np.uint8))
    w.close()
    frames = list(VideoReader(tmp_path / "z.mp4"))
    means = [float(f.image.mean()) for f in frames]
    assert len(frames) == 3 and frames[0].image.shape == (16, 16, 3)
    assert means[0] < means[1] < means[2], means  # the three frames, in order


@pytest.mark.parametrize("name", ["grey", "skip_bad"])
def test_a_video_readers_flags_are_true_or_false(tmp_path, name):
    """grey="False" and skip_bad="no" were taken as true (bool() of a string): grey frames,
    bad frames skipped."""
    from vistrack.io.video import VideoReader, VideoWriter

    w = VideoWriter(tmp_path / "a.mp4", fps=10)
    w.write(np.zeros((16, 16, 3), np.uint8))
    w.close()
    for value in ("False", "no", 1):
        with pytest.raises(TypeError, match=f"{name} must be True or False; got {value!r}"):
            VideoReader(tmp_path / "a.mp4", **{name: value})
    assert getattr(VideoReader(tmp_path / "a.mp4", **{name: np.bool_(True)}), name) is True


def test_a_complete_video_of_another_container_closes(tmp_path):
    """The frames are counted back only where the container keeps an exact count (MP4):
    an MKV's estimate from its rate ("holds 12 of the 10 frames" at 12345.678 frames/s)
    failed complete videos. Oracle: each frame read back."""
    import warnings

    from vistrack.io.video import VideoReader, VideoWriter

    for name in ("a.mkv", "b.mp4"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # (the nearest rate an MP4 holds)
            w = VideoWriter(tmp_path / name, fps=12345.678)
            for k in range(10):
                w.write(np.full((16, 16, 3), 20 * k, np.uint8))
            w.close()
        assert sum(1 for _ in VideoReader(tmp_path / name, fps=25)) == 10


def test_a_held_interrupt_wins_over_a_failed_rename(tmp_path):
    """A Ctrl-C held during the group's renames was dropped where a rename then failed (the
    OSError alone escaped); the interrupt is delivered over it."""
    import signal

    from vistrack.io import atomic
    from vistrack.io.atomic import replacing, together

    rename, calls = atomic._rename, []

    def failing(part, path):
        calls.append(path.name)
        if len(calls) == 1:
            os.kill(os.getpid(), signal.SIGINT)
            rename(part, path)
            return
        raise OSError(28, "No space left on device", str(path))

    atomic._rename = failing
    try:
        with pytest.raises(KeyboardInterrupt):
            with together():
                for n in ("a.txt", "b.txt"):
                    with replacing(tmp_path / n) as part:
                        part.write_text("new")
    finally:
        atomic._rename = rename
    assert calls == ["a.txt", "b.txt"]


def test_a_video_writer_refuses_frames_after_close(tmp_path):
    """A write after close began a new file over the closed one's frames: 15 counted, the
    last 5 in the file."""
    from vistrack.io.video import VideoReader, VideoWriter

    w = VideoWriter(tmp_path / "v.mp4", fps=10)
    for _ in range(10):
        w.write(np.zeros((16, 16, 3), np.uint8))
    w.close()
    with pytest.raises(ValueError, match=re.escape("v.mp4: write after close: the video is "
                                                   "finished, with 10 frames")):
        w.write(np.zeros((16, 16, 3), np.uint8))
    assert len(VideoReader(tmp_path / "v.mp4")) == 10


def test_ctrl_c_from_another_thread_waits_for_the_groups_renames(tmp_path):
    """The group's renames held SIGINT off with a mask of the main thread's alone: the system
    handed the signal to another thread (decoding's, numba's), Python raised it in the main
    thread between two renames, and new tracks stood beside an earlier run's other files.
    Oracle: the files' contents after a SIGINT sent from another thread during the second of
    three renames: all new, and the KeyboardInterrupt after them."""
    import signal
    import threading

    from vistrack.io import atomic
    from vistrack.io.atomic import replacing, together

    names = ["a.txt", "b.txt", "c.txt"]
    for n in names:
        (tmp_path / n).write_text("earlier")
    rename, calls = atomic._rename, []

    def slow(part, path):
        calls.append(path.name)
        if len(calls) == 2:
            sender = threading.Thread(target=os.kill, args=(os.getpid(), signal.SIGINT))
            sender.start()
            sender.join()
            for _ in range(100):  # a Python handler runs between bytecodes: give it some
                sum(range(100))
        rename(part, path)

    atomic._rename = slow
    try:
        with pytest.raises(KeyboardInterrupt):
            with together():
                for n in names:
                    with replacing(tmp_path / n) as part:
                        part.write_text("new")
    finally:
        atomic._rename = rename
    assert calls == names
    assert [(tmp_path / n).read_text() for n in names] == ["new"] * 3
    assert sorted(p.name for p in tmp_path.iterdir()) == names


def test_a_video_given_up_is_released_without_its_check(tmp_path):
    """SIGTERM between a frame's write and its count left the writer a frame short of the
    file; given up after the failure, the video's check raised its own error in place of
    the interrupt (status 2) and left the partial file behind. Oracle: the folder, empty
    of partial files, and abort raising nothing."""
    from vistrack.types import Frame, Tracks
    from vistrack.viz.annotate import AnnotatedVideo

    video = AnnotatedVideo(tmp_path / "a.mp4", fps=10)
    for k in range(1, 4):
        video.write(Frame(k, 0.0, np.zeros((24, 32, 3), np.uint8)), Tracks.empty())
    video._writer.frames -= 1  # as a signal between the write and its count leaves it
    video.abort()
    assert list(tmp_path.iterdir()) == []


def test_a_committed_partial_file_takes_no_more_rows(tmp_path):
    """A write after commit began a new, untracked partial file, and a second commit
    replaced the output with the later rows alone ('row1\\nrow2\\n' became 'row3\\n')."""
    f = PartialFile(tmp_path / "r.txt")
    f.write("row1\\nrow2\\n")
    f.commit()
    for late in (lambda: f.write("row3\\n"), f.commit):
        with pytest.raises(ValueError, match=re.escape(
                f"{tmp_path / 'r.txt'}: the file is committed or given up: no more can be "
                "written to it")):
            late()
    assert (tmp_path / "r.txt").read_text() == "row1\\nrow2\\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.txt"]
    g = PartialFile(tmp_path / "s.txt")
    g.write("x")
    g.abort()
    g.abort()  # twice: harmless, as documented
    with pytest.raises(ValueError, match="committed or given up"):
        g.write("y")


def test_a_video_writers_size_and_an_os_errors_odd_name_are_named():
    """VideoWriter(size=...) took (64.5, 48) to OpenCV's overload error, (0, 0) to "cannot
    write an MP4 here" and (64,) to an IndexError; message() of an OSError whose file is a
    descriptor (os.stat(999)) raised a TypeError that hid the error."""
    from vistrack._pool import message
    from vistrack.io.video import VideoWriter

    for size, said in (((64.5, 48), "size's width must be a whole number >= 1 (pixels); got "
                        "64.5"), ((0, 0), "size's width must be a whole number >= 1 (pixels); "
                        "got 0"), ((64,), "size must be (width, height); got (64,)")):
        with pytest.raises(ValueError, match=re.escape(said)):
            VideoWriter("x.mp4", 10, size)
    try:
        os.stat(999)
    except OSError as e:
        assert message(e) == "[Errno 9] Bad file descriptor: 999"


def test_the_sinks_name_a_frame_that_is_no_whole_number_and_points_they_cannot_write(tmp_path):
    """A frame of 2.7 was written as frame 2 by every sink (ids of 1.7 were refused), one of
    2**53 + 1 written where read_mot refuses it; PointsCSVWriter failed on points of three
    coordinates in a %-format's words; BoxesWriter refused point tracks in Tracks.xywh's
    words, naming neither the frame nor the sink, after keeping the frame as its first.
    Oracle: write_mot's refusal of the same values, and what read_mot reads back."""
    from vistrack.io import PointsCSVWriter

    box = Tracks(ids=np.array([1]), boxes=np.array([[0.0, 0, 2, 3]]), points=None,
                 scores=np.ones(1), classes=np.zeros(1))
    for sink in (lambda: MOTWriter(tmp_path / "m.txt"), lambda: CSVWriter(tmp_path / "c.csv"),
                 TrackRows):
        for index, said in ((2.7, "frame 2.7: a frame's index must be a whole number"),
                            (2**53 + 1, "frame 9007199254740993: a frame's index must lie "
                                        "within ±(2**53 - 1)")):
            s = sink()
            with pytest.raises(ValueError, match=re.escape(said)):
                s.write(Frame(index, 0.0), box)
            s.abort() if hasattr(s, "abort") else None
    with pytest.raises(ValueError, match="not within"):
        write_mot(tmp_path / "w.txt", [2**53 + 1], [1], [[0, 0, 1, 1]])
    w = MOTWriter(tmp_path / "ok.txt")
    w.write(Frame(np.int64(3), 0.0), box)
    w.close()
    from vistrack.io import read_mot

    assert read_mot(tmp_path / "ok.txt").frames.tolist() == [3]
    pts = PointsCSVWriter(tmp_path / "p.csv")
    with pytest.raises(ValueError, match=re.escape(
            "frame 1: PointsCSVWriter(" + str(tmp_path / "p.csv") + ") writes points of two "
            "coordinates, x and y; got shape (1, 3)")):
        pts.write(Frame(1, 0.0), Tracks(ids=np.array([1]), boxes=None,
                                        points=np.array([[1.0, 2.0, 3.0]]), scores=np.ones(1),
                                        classes=np.zeros(1)))
    pts.abort()
    b = BoxesWriter(tmp_path / "b.txt")
    points = Tracks(ids=np.array([1]), boxes=None, points=np.array([[1.0, 2.0]]),
                    scores=np.ones(1), classes=np.zeros(1))
    with pytest.raises(ValueError, match=re.escape(
            f"frame 4: BoxesWriter({tmp_path / 'b.txt'}) takes box tracks")):
        b.write(Frame(4, 0.0), points)
    b.write(Frame(6, 0.0), box)  # the refused frame 4 is not its first
    assert len(b.boxes) == 1
    b.abort()


def _under_size_limit(tmp_path, limit, argv):
    """``vistrack`` run in a child process whose files may not grow past ``limit`` bytes
    (RLIMIT_FSIZE, as a full disk): its status and stderr."""
    import subprocess
    import sys

    script = tmp_path / "limited.py"
    script.write_text(
        "import resource, sys\n"
        f"resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, resource.RLIM_INFINITY))\n"
        "from vistrack.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n")
    r = subprocess.run([sys.executable, str(script), *map(str, argv)], capture_output=True,
                       text=True, cwd=tmp_path)
    return r.returncode, r.stderr


def test_a_refused_write_of_offline_tracks_or_of_plots_names_the_output(tmp_path):
    """The offline mode's tracks (written sorted, through one buffered file) and `eval`'s
    plots met a full disk as "[Errno 27] File too large", no file named, where the online
    tracks said "res.txt: File too large"; and the plots were renamed one by one, so a
    failure at the second left the first under its final name, in a folder the run had
    made. Oracle: the operating system's limit on a file's size (RLIMIT_FSIZE) in a child
    process; the folder's listing before and after."""
    box = lambda f, k: f"{10 + 40 * k + f},{20 + k},30,60"
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{f},-1,{box(f, k)},0.9\n" for f in range(1, 301)
                           for k in range(1, 9)))
    (tmp_path / "res.txt").write_text("earlier\n")
    status, err = _under_size_limit(tmp_path, 20_000, [
        "track", det, "--fps", "25", "--offline", "--out", "res.txt", "--force"])
    assert status == 2 and err.strip() == "vistrack track: error: res.txt: File too large"
    assert (tmp_path / "res.txt").read_text() == "earlier\n"
    # eval's plots under a limit between their sizes: the smaller fits, the larger does not
    # (here the timeline, written second: the HOTA plot is written whole first)
    gt, pred = tmp_path / "gt.txt", tmp_path / "pred.txt"
    gt.write_text("".join(f"{f},{k},{box(f, k)},1,1,1\n" for f in range(1, 301)
                          for k in range(1, 9)))
    # an identity switch every 3 frames, and misses: a timeline of many colours
    pred.write_text("".join(f"{f},{k + 8 * (f // 3)},{box(f, k)},1,-1,-1,-1\n"
                            for f in range(1, 301) for k in range(1, 9) if (f * k) % 7))
    assert main(["eval", "--gt", str(gt), "--pred", str(pred), "--plots",
                 str(tmp_path / "sizes")]) == 0
    sizes = sorted((p.stat().st_size, p.name) for p in (tmp_path / "sizes").iterdir())
    assert len(sizes) == 2 and sizes[0][0] < sizes[1][0], sizes
    before = sorted(p.name for p in tmp_path.iterdir())
    status, err = _under_size_limit(tmp_path, (sizes[0][0] + sizes[1][0]) // 2, [
        "eval", "--gt", gt, "--pred", pred, "--plots", tmp_path / "plq"])
    last = err.strip().splitlines()[-1]
    assert status == 2 and re.fullmatch(
        rf"vistrack eval: error: {re.escape(str(tmp_path / 'plq'))}/\S+\.png: File too large",
        last), err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # no plq/, no plot

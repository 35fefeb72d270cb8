"""The detector-confidence particle filter: the confidence map's geometry against OpenCV's
HOG and bilinear interpolation, and tracking two crossing people whose detections are missing
half the time."""

from __future__ import annotations

import re
from decimal import Decimal
from fractions import Fraction

import numpy as np
import pytest

from vistrack.evaluation.mot import evaluate_mot
from vistrack.frontends.detectors import ConfidenceMap, HOGConfidence
from vistrack.io.motchallenge import MOTTable
from vistrack.tracking.dcpf import DCPFConfig, DetectorConfidencePF
from vistrack.types import Detections


def test_confidence_map_is_bilinear_and_picks_the_nearest_height():
    y, x = np.mgrid[0:20, 0:30].astype(float)
    plane = lambda a, b, c: a * x + b * y + c          # noqa: E731
    cm = ConfidenceMap([50, 100], [plane(1, 2, 3), plane(-1, 0.5, 0)], [(10, 20), (0, 0)],
                       [4, 8])
    rng = np.random.default_rng(1)
    px, py = rng.uniform(10, 10 + 4 * 29, 100), rng.uniform(20, 20 + 4 * 19, 100)
    u, v = (px - 10) / 4, (py - 20) / 4
    np.testing.assert_allclose(cm.score(px, py, 60), u + 2 * v + 3, rtol=1e-12)
    u, v = px / 8, py / 8
    np.testing.assert_allclose(cm.score(px, py, 80), -u + 0.5 * v, rtol=1e-12)
    assert cm.score(-5, 30, 50, outside=-7.0) == -7.0
    with pytest.raises(ValueError, match="one entry per level"):
        ConfidenceMap([50, 100], [plane(1, 2, 3)], [(0, 0)], [4])


def test_confidence_map_peaks_are_the_detections():
    y, x = np.mgrid[0:40, 0:60].astype(float)
    s = -3 + 4 * np.exp(-((x - 20) ** 2 + (y - 10) ** 2) / 4) \
        + 3 * np.exp(-((x - 45) ** 2 + (y - 30) ** 2) / 4)
    cm = ConfidenceMap([80], [s], [(0, 0)], [2], aspect=0.5)
    d = cm.detections(threshold=-0.5)
    np.testing.assert_allclose(np.sort(d.centers[:, 0]), [40, 90])
    np.testing.assert_allclose(d.xywh[:, 2:], [[40, 80], [40, 80]])
    np.testing.assert_allclose(np.sort(d.scores), 1 / (1 + np.exp(-np.array([0.0, 1.0]))))


def test_hog_confidence_cells_are_opencv_hog_windows():
    """Each cell's score is the SVM margin OpenCV's HOG gives the window it names, at the
    image position the map gives it."""
    import cv2

    rng = np.random.default_rng(2)
    img = cv2.GaussianBlur(rng.integers(0, 255, (240, 200, 3), dtype=np.uint8), (0, 0), 2)
    cv2.rectangle(img, (80, 60), (110, 170), (20, 20, 20), -1)
    cv2.circle(img, (95, 50), 12, (20, 20, 20), -1)
    hog = HOGConfidence(heights=(120,))
    cm = hog(img)
    f = 0.75 * 128 / 120
    sw, sh = int(round(200 * f)), int(round(240 * f))
    small = cv2.resize(img, (sw, sh))
    ref = cv2.HOGDescriptor()
    ref.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    loc, w = ref.detect(small, hitThreshold=-1e9, winStride=(8, 8), padding=(0, 0))
    loc, w = np.asarray(loc, float).reshape(-1, 2), np.asarray(w, float).ravel()
    # each window's centre in the image, by the factors of the resize made (to whole
    # pixels: 160 / 200 and 192 / 240 here)
    centres = (loc + [32, 64]) * [200 / sw, 240 / sh]
    np.testing.assert_allclose(cm.score(centres[:, 0], centres[:, 1], 120), w, rtol=1e-5,
                               atol=1e-5)


def test_hog_confidence_maps_every_window_by_the_resize_made():
    """Each level's image is resized to whole pixels, so by factors a little off the nominal
    one (PETS09's 768 x 576 at the level of people 121 pixels tall: 609 / 768 = 0.79297
    along x, 0.79388 nominal); the grid mapped back by the nominal factor put the last
    windows' centres up to 0.4 pixel off, beyond its edge: the score at the true centre of 327
    windows of a level was -inf, others off by up to 0.13 of a margin. Every window's true
    centre (OpenCV's window in the resized image, mapped back by the resize made) now scores
    its own margin, at every level."""
    import cv2

    rng = np.random.default_rng(5)
    img = cv2.GaussianBlur(rng.integers(0, 255, (576, 768, 3), dtype=np.uint8), (0, 0), 2)
    hog = HOGConfidence()
    cm = hog(img)
    ref = cv2.HOGDescriptor()
    ref.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    for h in cm.heights:
        f = 96 / h
        sw, sh = int(round(768 * f)), int(round(576 * f))
        loc, w = ref.detect(cv2.resize(img, (sw, sh)), hitThreshold=-1e9, winStride=(8, 8),
                            padding=(0, 0))
        centres = (np.asarray(loc, float).reshape(-1, 2) + [32, 64]) * [768 / sw, 576 / sh]
        got = cm.score(centres[:, 0], centres[:, 1], h)
        assert np.isfinite(got).all(), h
        np.testing.assert_allclose(got, np.asarray(w, float).ravel(), rtol=1e-5, atol=1e-5)
    # a map of one stride per level is the map of the same stride along both axes
    s = np.arange(30.0).reshape(5, 6)
    one, two = (ConfidenceMap([90.0], [s], [(10.0, 20.0)], st) for st in ([8.0], [[8.0, 8.0]]))
    x, y = np.array([10.0, 23.0, 41.5, 50.0]), np.array([20.0, 31.0, 50.0, 52.0])
    np.testing.assert_array_equal(one.score(x, y, 90), two.score(x, y, 90))
    across = ConfidenceMap([90.0], [s], [(10.0, 20.0)], [[4.0, 8.0]])
    assert across.score(10 + 4 * 3, 20 + 8 * 2, 90) == s[2, 3]


def test_hog_confidence_scores_its_levels_on_opencvs_threads_to_the_same_bits():
    """OpenCV's HOG search is one thread a call, so the levels of a frame ran one after the
    other (184 ms a frame of the bundled clip here, 104 ms on two threads). They run on as many
    threads as OpenCV uses (``cv2.setNumThreads``), and each level's grid is OpenCV's margin
    of each window, bit for bit, as on one thread."""
    import threading

    import cv2

    from vistrack.data import demo_clip
    from vistrack.io import VideoReader

    clip = demo_clip()
    img = next(iter(VideoReader(clip.video))).image

    class Spy:  # OpenCV's detector, noting the thread of each call
        def __init__(self, hog):
            self.hog, self.threads = hog, set()

        def detect(self, *args, **kwargs):
            self.threads.add(threading.get_ident())
            return self.hog.detect(*args, **kwargs)

    ref = cv2.HOGDescriptor()
    ref.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    before = cv2.getNumThreads()
    maps = {}
    try:
        for n in (1, 2):
            cv2.setNumThreads(n)
            hog = HOGConfidence()
            hog._hog = spy = Spy(hog._hog)
            maps[n] = hog(img)
            assert len(spy.threads) == min(n, cv2.getNumThreads()), n
        # levels given in any order (searched the largest image first) keep their order
        mixed = HOGConfidence(heights=(121, 46, 75))(img)
    finally:
        cv2.setNumThreads(before)
    assert mixed.heights.tolist() == [121, 46, 75]
    for h, grid in zip(mixed.heights, mixed.scores):
        np.testing.assert_array_equal(grid, maps[1].scores[maps[1].heights.tolist().index(h)])
    for h, grid, other in zip(maps[2].heights, maps[2].scores, maps[1].scores):
        np.testing.assert_array_equal(grid, other)
        f = 96 / h
        sw, sh = int(round(768 * f)), int(round(576 * f))
        loc, w = ref.detect(cv2.resize(img, (sw, sh)), hitThreshold=-1e9, winStride=(8, 8),
                            padding=(0, 0))
        loc = np.asarray(loc).reshape(-1, 2) // 8
        np.testing.assert_array_equal(grid[loc[:, 1], loc[:, 0]], np.asarray(w, float).ravel())
        assert len(loc) == grid.size  # every cell is one of OpenCV's windows
    assert maps[1].heights.tolist() == maps[2].heights.tolist() == [46, 58, 75, 96, 121]


def test_hog_confidence_on_small_frames_leaves_out_the_levels_that_do_not_fit():
    """A 160 x 120 frame holds fewer than 2 x 2 windows at the tallest people's level (121
    pixels: the frame resized to 119 rows, under one 128-row window): that level was kept, as
    a grid of one row or clamped to the window's size (its cells then mapped to the wrong
    place), and the map refused it ("each level's scores must be a 2-D grid"). It is left
    out; the levels kept are the ones whose every cell is OpenCV's window, as above; on a
    frame too small for any level the peaks are none, as HOGDetector finds nobody there."""
    import cv2

    from vistrack.frontends.detectors import ConfidencePeaks, HOGDetector, ImageTooSmall

    rng = np.random.default_rng(4)
    img = cv2.GaussianBlur(rng.integers(0, 255, (160, 120, 3), dtype=np.uint8), (0, 0), 2)
    hog = HOGConfidence()
    cm = hog(img)
    fits = [h for h in hog.heights
            if round(120 * 96 / h) >= 72 and round(160 * 96 / h) >= 136]
    assert cm.heights.tolist() == fits == [46.0, 58.0, 75.0, 96.0]
    ref = cv2.HOGDescriptor()
    ref.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    for h in fits:
        f = 96 / h
        sw, sh = int(round(120 * f)), int(round(160 * f))
        small = cv2.resize(img, (sw, sh))
        loc, w = ref.detect(small, hitThreshold=-1e9, winStride=(8, 8), padding=(0, 0))
        centres = (np.asarray(loc, float).reshape(-1, 2) + [32, 64]) * [120 / sw, 160 / sh]
        np.testing.assert_allclose(cm.score(centres[:, 0], centres[:, 1], h),
                                   np.asarray(w, float).ravel(), rtol=1e-5, atol=1e-5)
    tiny = np.zeros((30, 30, 3), np.uint8)
    with pytest.raises(ImageTooSmall, match="image of 30 x 30 pixels is too small"):
        hog(tiny)
    assert len(ConfidencePeaks(hog).detect(tiny)) == len(HOGDetector().detect(tiny)) == 0


def crossing_scene(T=60, miss=0.5, seed=0):
    """Two people (20 x 50 boxes), red and blue, crossing paths on a grey ground; each is
    detected with probability ``1 - miss``; the confidence map has a peak of margin 2 on a
    detected person and 0.3 (below the detection threshold) on a missed one, 10 pixels wide
    (a fifth of the height, as HOG's response on PETS09)."""
    import cv2

    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:60, 0:80] * 4.0
    frames, dets, maps, gt = [], [], [], []
    for t in range(T):
        img = np.full((240, 320, 3), 128, np.uint8)
        centres = [(40 + 4 * t, 120.0), (276 - 4 * t, 128.0)]
        boxes, score = [], np.full(xx.shape, -3.0)
        for k, ((cx, cy), colour) in enumerate(zip(centres, [(0, 0, 200), (200, 0, 0)])):
            cv2.rectangle(img, (int(cx - 10), int(cy - 25)), (int(cx + 10), int(cy + 25)),
                          colour, -1)
            gt.append((t + 1, k + 1, cx - 10, cy - 25, 20, 50))
            seen = rng.random() >= miss
            peak = 2.0 if seen else 0.3
            score = np.maximum(score, -3 + (peak + 3) * np.exp(
                -((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * 10.0 ** 2)))
            if seen:
                boxes.append([cx - 10 + rng.normal(0, 1), cy - 25 + rng.normal(0, 1), 20, 50])
        frames.append(img)
        dets.append(Detections.from_xywh(np.array(boxes).reshape(-1, 4),
                                         np.full(len(boxes), 0.95)))
        maps.append(ConfidenceMap([50], [score], [(0, 0)], [4], aspect=0.4))
    return frames, dets, maps, MOTTable.from_rows(gt)


def score(scene, **config):
    frames, dets, maps, gt = scene
    tracker = DetectorConfidencePF(rng=0, frame_rate=10, max_lost=0.55, **config)
    rows = []
    for t, (img, d, m) in enumerate(zip(frames, dets, maps), 1):
        out = tracker.update(img, d, m if tracker.config.gamma > 0 else None)
        rows += [(t, i, *b) for i, b in zip(out.ids, out.xywh)]
    return evaluate_mot(gt, MOTTable.from_rows(rows), len(frames), benchmark="MOT15")


def test_detector_confidence_carries_the_targets_through_missed_detections():
    scene = crossing_scene()
    full, det_only = score(scene), score(scene, gamma=0.0, eta=0.0)
    # missed detections: the Det filter reports a target only when detected; the
    # confidence term keeps it reported (and in place) in between
    assert full.FN < 0.5 * det_only.FN
    assert full.MOTA > det_only.MOTA + 0.2
    assert full.IDSW == 0 and full.MOTP > 0.75


def test_each_target_classifier_tells_its_person_from_the_other():
    """Detected every frame for 20 frames (before they meet), each target's online
    classifier scores its own person's box high and the other person's low. The scene's
    people move 4 pixels a frame, 0.8 of their height a second at 10 frames/s (a brisk
    walk; at 30 they would run at 2.4 heights a second)."""
    from vistrack.tracking.dcpf import ColourFeatures

    frames, dets, maps, gt = crossing_scene(miss=0.0)
    tracker = DetectorConfidencePF(rng=0, gamma=0.0, frame_rate=10)
    for t in range(20):
        tracker.update(frames[t], dets[t])
    truth = gt.boxes[gt.frames == 21]
    c = tracker._classify(ColourFeatures(frames[20])(truth)[None], slice(None))
    # target k started on person k (the red one is on the left, and first)
    order = np.argsort(tracker.particles[:, :, 0].mean(1))
    assert c[order[0], 0] > 0.9 and c[order[0], 1] < 0.1
    assert c[order[1], 1] > 0.9 and c[order[1], 0] < 0.1


def test_configuration_is_checked():
    with pytest.raises(ValueError, match="beta must be >= 0"):
        DCPFConfig(beta=-1)
    with pytest.raises(ValueError, match="at least one"):
        DCPFConfig(beta=0, gamma=0, eta=0)
    for alpha in (np.inf, -1.0):  # a weight: inf made every association score inf or NaN
        with pytest.raises(ValueError, match="alpha must be a finite number >= 0"):
            DCPFConfig(alpha=alpha)
    tracker = DetectorConfidencePF()
    with pytest.raises(ValueError, match="needs the detector.s confidence"):
        tracker.update(np.zeros((10, 10, 3), np.uint8), Detections.from_xywh(np.zeros((0, 4))))


def test_track_video_runs_the_particle_filter_on_a_users_confidence(tmp_path):
    """``track_video(tracker="dcpf")`` with a user-supplied confidence callable: the
    detections are the map's peaks, and the written tracks score as the tracker does."""
    import cv2

    from vistrack.io import write_mot
    from vistrack.pipeline import track_video

    frames, dets, maps, gt = crossing_scene(miss=0.3, seed=4)
    folder = tmp_path / "frames"
    folder.mkdir()
    for t, f in enumerate(frames, 1):
        cv2.imwrite(str(folder / f"{t:06d}.png"), f)
    write_mot(tmp_path / "gt.txt", gt.frames, gt.ids, gt.boxes)
    calls = iter(maps)
    run = track_video(folder, tmp_path / "out", tracker="dcpf", fps=10,
                      confidence=lambda image: next(calls), gt=tmp_path / "gt.txt",
                      max_lost=0.55)
    assert run.frames == len(frames) and run.tracks >= 2
    assert run.scores.MOTA > 0.6 and run.scores.IDSW == 0
    with pytest.raises(TypeError, match="confidence must be a callable"):
        track_video(folder, tmp_path / "o2", tracker="dcpf", confidence=3)


def test_the_scores_seen_and_why_no_target_started():
    """A detector whose scores all lie under ``init_score`` starts no target: the tracker
    keeps the highest score it has seen (the oracle: numpy's maximum of the scores given),
    and :func:`~vistrack.pipeline.start_warning` says so; with the scores as they are, or
    one reaching ``init_score``, it says nothing (it was silent either way)."""
    from vistrack.pipeline import start_warning
    from vistrack.types import Frame

    frames, dets, maps, _ = crossing_scene(miss=0.3, seed=4)
    rng = np.random.default_rng(0)
    scores = [rng.uniform(0.8, 0.99, len(d)) for d in dets]
    every = np.concatenate(scores)
    for scale, starts in ((1.0, True), (1 / 200, False)):
        calls = iter(maps)
        trk = DetectorConfidencePF(confidence=lambda image, c=calls: next(c), frame_rate=10)
        reported = 0
        for t, (img, d, sc) in enumerate(zip(frames, dets, scores), 1):
            out = trk.step(Frame(t, (t - 1) / 10, img),
                           Detections.from_xywh(d.xywh, sc * scale))
            reported += len(out)
        assert trk.n_scored == len(every)
        assert trk.top_score == every.max() * scale
        assert (reported > 0) == starts
        said = start_warning(trk, "SEQ")
        assert (said is None) == starts
    assert said == (f"SEQ: no target started: no detection reached init_score 0.75 (the "
                    f"highest of {len(every)} scored {every.max() / 200:.3g}); set init_score "
                    "below the detector's scores (a --config file's [dcpf] init_score, or "
                    "DetectorConfidencePF(init_score=...)): its default, 0.75, is for the "
                    "confidence front end's scores in (0, 1)")
    trk.reset()
    assert trk.n_scored == 0 and trk.top_score == -np.inf and start_warning(trk, "S") is None


def test_track_video_says_when_a_weaker_detector_starts_no_target(tmp_path):
    """The confidence front end's peaks of a detector whose margins are half the scene's
    (1.0 at a person: a score of 0.731 after the logistic, under ``init_score`` 0.75) start
    no target; the run says so, with the highest score (the oracle: the logistic of the
    largest margin above the threshold)."""
    import cv2

    from vistrack.pipeline import track_video

    frames, _, maps, _ = crossing_scene(miss=0.3, seed=4)
    folder = tmp_path / "frames"
    folder.mkdir()
    for t, f in enumerate(frames, 1):
        cv2.imwrite(str(folder / f"{t:06d}.png"), f)
    weak = [ConfidenceMap([50], [m.scores[0] * 0.5], [(0, 0)], [4], aspect=0.4) for m in maps]
    top = 1.0 / (1.0 + np.exp(-max(float(m.scores[0].max()) for m in weak)))
    calls = iter(weak)
    with pytest.warns(RuntimeWarning, match=re.escape(
            "no target started: no detection reached init_score 0.75 (the highest of ")
            + r"\d+" + re.escape(f" scored {top:.3g})")):
        run = track_video(folder, tmp_path / "out", tracker="dcpf", fps=10,
                          confidence=lambda image: next(calls))
    assert run.tracks == 0


@pytest.mark.slow
def test_pets09_clip_terms_of_the_observation_model():
    """The bundled PETS09-S2L1 clip (200 frames) from pixels, against MOT15's annotations:
    every configuration tracks (MOTA about 0.5 on this clip), and the whole model switches
    identities less often than the detections alone and keeps them better (IDF1; on the
    whole sequence 15 against 20 switches, IDF1 74.6 against 66.3, docs/advanced.md)."""
    from pathlib import Path

    from vistrack.io import VideoReader, read_mot

    demo = Path(__file__).resolve().parents[1] / "src" / "vistrack" / "data" / "pets09-s2l1"
    gt = read_mot(demo / "gt.txt")
    gt = gt[gt.frames <= 200]
    hog = HOGConfidence()
    frames, maps = [], []
    for f in VideoReader(demo / "pets09-s2l1.mp4"):
        frames.append(f.image)
        maps.append(hog(f.image))

    def mot(**config):
        tracker = DetectorConfidencePF(rng=0, frame_rate=7, **config)
        rows = []
        for t, (img, m) in enumerate(zip(frames, maps), 1):
            out = tracker.update(img, m.detections(0.5), m)
            rows += [(t, i, *b) for i, b in zip(out.ids, out.xywh)]
        return evaluate_mot(gt, MOTTable.from_rows(rows), 200)

    full, det_conf, det = mot(), mot(eta=0.0), mot(gamma=0.0, eta=0.0)
    assert min(full.MOTA, det_conf.MOTA, det.MOTA) > 0.45
    assert full.IDSW < det.IDSW and full.IDF1 > det.IDF1 + 0.05


@pytest.mark.parametrize("gap", [5, 8, 10])
def test_detections_alone_keep_a_target_through_a_gap_shorter_than_max_lost(gap):
    """With the detection term alone (no confidence map, no classifier) a person missed for 8
    frames at 7 frames/s always came back under a new identity, though ``max_lost`` is 1.5 s
    (10.5 frames): the association scored a detection by a fixed kernel over the particles,
    whose cloud spreads while unsupported, so the score at the person's own position fell
    below ``min_score``. Scored by the cloud's predictive density (its spread added to the
    detection's noise), the person walking on at the predicted place is found again, on
    every seed, until ``max_lost``; after it the target has ended (the lifecycle's rule,
    as the box tracker's, the oracle)."""
    from vistrack.types import Frame

    im = np.full((300, 600, 3), 128, np.uint8)
    for seed in range(5):
        trk = DetectorConfidencePF(rng=seed, gamma=0.0, eta=0.0, frame_rate=7)
        ids = set()
        for t in range(1, 40):
            out = trk.step(Frame(t, (t - 1) / 7, im), _walker(t, seen=not 15 <= t < 15 + gap))
            ids |= set(out.ids.tolist())
        assert ids == {1}, (seed, ids)
    trk = DetectorConfidencePF(rng=0, gamma=0.0, eta=0.0, frame_rate=7)
    ids = set()
    for t in range(1, 40):  # missed for 12 frames (1.7 s): a new identity after
        out = trk.step(Frame(t, (t - 1) / 7, im), _walker(t, seen=not 15 <= t < 27))
        ids |= set(out.ids.tolist())
    assert ids == {1, 2}


def test_colour_features_count_each_boxs_pixels_in_a_reused_buffer():
    """Each box's histogram, from the integral images, equals its pixels counted directly
    (hue-saturation bins of the half-size frame); a buffer passed frame after frame is
    written in place and gives the same features as a new one, and one of another shape is
    not used."""
    import cv2

    from vistrack.tracking.dcpf import ColourFeatures

    rng = np.random.default_rng(3)
    frames = [rng.integers(0, 256, (60, 80, 3), dtype=np.uint8) for _ in range(2)]
    boxes = np.array([[0, 0, 80, 60], [10, 6, 30, 20], [51, 33, 17, 9], [70, 50, 40, 40]])
    buffer = ColourFeatures(frames[0]).integral
    for image in frames:
        f = ColourFeatures(image, out=buffer)
        assert f.integral is buffer
        hsv = cv2.cvtColor(cv2.resize(image, None, fx=0.5, fy=0.5,
                                      interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2HSV)
        b = (hsv[..., 0].astype(int) * 8 // 180) * 4 + hsv[..., 1].astype(int) * 4 // 256
        want = []
        for x, y, w, h in boxes / 2:
            x0, y0 = int(np.clip(round(x), 0, 40)), int(np.clip(round(y), 0, 30))
            x1, y1 = int(np.clip(round(x + w), 0, 40)), int(np.clip(round(y + h), 0, 30))
            counts = np.bincount(b[y0:y1, x0:x1].ravel(), minlength=32).astype(float)
            want.append(np.sqrt(counts / max(counts.sum(), 1.0)))
        np.testing.assert_allclose(f(boxes), want, rtol=1e-12)
        np.testing.assert_array_equal(f(boxes), ColourFeatures(image)(boxes))
    other = ColourFeatures(frames[0], out=np.zeros((32, 5, 5), np.int32))
    assert other.integral.shape == buffer.shape


def test_the_younger_target_ends_after_more_than_merge_time_of_overlap():
    """"Overlapping for more than merge_time seconds": the timer added 1/frame_rate a frame
    and compared with <= merge_time, so at 10 frames/s and merge_time=0.3 the younger
    ended after exactly 3 frames of overlap (0.1 + 0.1 + 0.1 > 0.3), and at 5 frames/s and
    0.6 after exactly 0.6 s. Oracle: the frames in a row in which the two confirmed
    targets' boxes overlap by more than merge_iou, counted from the boxes, against the first
    k with k / frame_rate > merge_time in exact fractions."""
    from fractions import Fraction

    from vistrack.association import iou
    from vistrack.tracking.lifecycle import TENTATIVE

    im = np.zeros((240, 320, 3), np.uint8)
    cases = [(10, "0.3"), (10, "0.35"), (10, "0.25"), (7, Fraction(3, 7)), (5, "0.6"),
             (30, "0.1"), (25, "0.2")]
    for frame_rate, merge_time in cases:
        exact = Fraction(merge_time)
        trk = DetectorConfidencePF(frame_rate=frame_rate, gamma=0.0, eta=0.0,
                                   merge_time=float(exact), max_lost=100.0, rng=0)
        run, ended = 0, None
        for t in range(60):
            bx = max(100.0, 130.0 - 2 * t)  # the second walks onto the first, and stays
            det = Detections(boxes=np.array([[100.0, 60, 124, 120], [bx + 1, 60, bx + 25, 120]]),
                             scores=np.full(2, 0.9))
            before = len(trk.ids)
            trk.update(im, det)
            if before == 2 and len(trk.ids) == 1:
                ended = run + 1  # this frame overlapped too (or the timer had restarted)
                break
            if len(trk.ids) == 2:
                b = trk.tracks.mean
                xyxy = np.c_[b[:, :2], b[:, :2] + b[:, 2:]]
                over = iou(xyxy, xyxy)[0, 1] > 0.5 and (trk.tracks.state != TENTATIVE).all()
                run = run + 1 if over else 0
        want = next(k for k in range(1, 100) if Fraction(k, frame_rate) > exact)
        assert ended == want, (frame_rate, merge_time, ended, want)
        assert trk.ids.tolist() == [1]  # the younger ended, not the older


def test_every_setting_is_checked_and_named():
    """sigma_det=0 was taken (NaN detection terms: nothing was ever associated), a NaN
    sigma_pos or size_rate was an IndexError in update(), n_particles=2.5 a TypeError, and
    n_particles=1 with confirm=0 one message for four settings."""
    cases = [({"n_particles": 2.5}, "n_particles must be a whole number >= 2; got 2.5"),
             ({"n_particles": 1}, "n_particles must be a whole number >= 2; got 1"),
             ({"confirm": 0}, "confirm must be a whole number >= 1; got 0"),
             ({"epochs": 1.5}, "epochs must be a whole number >= 0; got 1.5"),
             ({"epochs": True}, "epochs must be a whole number >= 0; got True"),
             ({"noise_rate": 0.0}, "noise_rate must be a finite number > 0 (frames a second); "
                                   "got 0.0"),
             # the score reaches 0.5 + alpha at most without the classifier, 1 + alpha with it
             ({"alpha": 0.0, "eta": 0.0}, "min_score must be below the largest association "
              "score, 0.5 (the classifier off: eta 0) + alpha = 0.5; got 0.6 (no detection "
              "would ever be associated)"),
             ({"alpha": 0.2, "min_score": 1.2}, "min_score must be below the largest "
              "association score, 1 + alpha = 1.2; got 1.2"),
             # 0.5 + alpha is met only by a detection exactly at the particles' mean
             ({"alpha": 1.0, "eta": 0.0, "min_score": 1.5}, "min_score must be below the "
              "largest association score, 0.5 (the classifier off: eta 0) + alpha = 1.5; "
              "got 1.5 (only a detection exactly at a target's predicted centre would be "
              "associated)"),
             ({"sigma_det": 0.0}, "sigma_det must be a finite number > 0; got 0.0"),
             ({"sigma_det": -0.1}, "sigma_det must be a finite number > 0; got -0.1"),
             ({"sigma_det": np.inf}, "sigma_det must be a finite number > 0; got inf"),
             ({"sigma_pos": np.nan}, "sigma_pos must be a number (not NaN); got nan"),
             ({"sigma_vel": -0.02}, "sigma_vel must be a finite number >= 0; got -0.02"),
             ({"size_rate": np.nan}, "size_rate must be a number (not NaN); got nan"),
             ({"size_rate": 1.5}, "size_rate must be in [0, 1]"),
             ({"learning_rate": np.inf}, "learning_rate must be a finite number >= 0; got inf"),
             ({"gamma": np.inf}, "gamma must be finite; got inf"),
             ({"max_lost": -1.0}, "max_lost must be >= 0; got -1.0"),
             ({"merge_time": np.nan}, "merge_time must be a number (not NaN); got nan"),
             # taken before: two people who never met lost their identities every merge_time,
             # or a new identity every frame was started and none reported
             ({"merge_iou": -1.0}, "merge_iou must be in [0, 1]; got -1.0"),
             ({"max_overlap": -0.5}, "max_overlap must be in [0, 1]; got -0.5"),
             ({"min_confidence": 2.0}, "min_confidence must be in [0, 1]; got 2.0"),
             ({"gate_heights": -1.0},
              "gate_heights must be a finite number > 0 (box heights); got -1.0"),
             ({"init_score": np.inf}, "init_score must be finite; got inf")]
    for kw, msg in cases:
        with pytest.raises(ValueError, match=re.escape(msg)):
            DCPFConfig(**kw)
        with pytest.raises(ValueError, match=re.escape(msg)):
            DetectorConfidencePF(**({"gamma": 0.0} | kw))
    # what is no number is a TypeError, as for every other setting of the package
    for kw, msg in (({"alpha": "1"}, "alpha must be a number; got '1'"),
                    ({"beta": None}, "beta must be a number; got None"),
                    ({"gamma": True}, "gamma must be a number; got True"),
                    ({"n_particles": "100"}, "n_particles must be a number; got '100'")):
        with pytest.raises(TypeError, match=re.escape(msg)):
            DCPFConfig(**kw)
    assert DCPFConfig(alpha=0.0, eta=0.0, min_score=0.5).min_score == 0.5  # reachable
    # (an alpha too small to add to 0.5: every gated detection still scores 0.5)
    assert DCPFConfig(alpha=1e-17, eta=0.0, min_score=0.5).min_score == 0.5
    # an integer past the largest float is infinite (a bare OverflowError before), and named
    # where a finite number is asked for
    assert DCPFConfig(max_lost=10 ** 400).max_lost == np.inf
    with pytest.raises(ValueError, match=re.escape("sigma_det must be a finite number > 0; "
                                                   "got inf")):
        DCPFConfig(sigma_det=10 ** 400)
    # any real number is stored as a float: a Decimal failed in isnan without naming the
    # setting, and a 0-d array was stored as an array
    exact = DCPFConfig(alpha=Decimal("0.5"), sigma_pos=Fraction(1, 25),
                       min_score=np.array(0.7), beta=np.float32(2.0), gamma=1)
    assert (exact.alpha, exact.sigma_pos, exact.min_score, exact.beta, exact.gamma) \
        == (0.5, 0.04, 0.7, 2.0, 1.0)
    assert all(type(v) is float for v in (exact.alpha, exact.sigma_pos, exact.min_score,
                                          exact.beta, exact.gamma))
    with pytest.raises(ValueError, match=re.escape("alpha must be a number (not NaN); got nan")):
        DCPFConfig(alpha=Decimal("NaN"))
    with pytest.raises(TypeError, match=re.escape("sigma_vel must be a number; got 1j")):
        DCPFConfig(sigma_vel=1j)
    # integral values of other types are the integers; the defaults are what they were
    cfg = DCPFConfig(n_particles=50.0, confirm=np.int64(1), epochs=0)
    assert (cfg.n_particles, cfg.confirm, cfg.epochs) == (50, 1, 0)
    assert all(type(v) is int for v in (cfg.n_particles, cfg.confirm, cfg.epochs))
    im = np.zeros((120, 160, 3), np.uint8)
    det = Detections(boxes=np.array([[50.0, 30, 74, 90]]), scores=np.array([0.9]))
    trk = DetectorConfidencePF(cfg, gamma=0.0)
    for _ in range(3):
        out = trk.update(im, det)
    assert trk.particles.shape == (1, 50, 4) and len(out) == 1
    np.testing.assert_allclose(out.boxes[0], det.boxes[0], atol=3.0)


def test_detections_of_no_area_are_left_out_once_said():
    """A detection of no height started a target every frame (its height ratio 0/0, with
    numpy's "invalid value" warnings), one of no width was confirmed and reported as a
    track of no width."""
    import warnings

    from vistrack.types import Frame

    image = np.zeros((200, 300, 3), np.uint8)
    boxes = [[50, 50, 50, 90], [100, 50, 140, 150], [200, 50, 200, 150]]  # x0, y0, x1, y1
    tracker = DetectorConfidencePF(rng=0, gamma=0.0, eta=0.0)
    alone = DetectorConfidencePF(rng=0, gamma=0.0, eta=0.0)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        for f in range(1, 6):
            frame = Frame(f, (f - 1) / 7, image)
            out = tracker.step(frame, Detections(boxes=boxes, scores=[0.9] * 3))
            ref = alone.step(frame, Detections(boxes=boxes[1:2], scores=[0.9]))
    assert [str(w.message) for w in said] == [
        "frame 1: 2 detection(s) of no width or height left out (a box with no area can be "
        "no target's); said once"]
    assert tracker.tracks.ids.tolist() == [1]
    np.testing.assert_array_equal(out.boxes, ref.boxes)  # as if they were not there


@pytest.mark.parametrize("change,message", [
    ({"strides": [[8.0]]}, "strides must be one number > 0 per level, or an x and a y per "
                           "level, shape (1, 2); got [[8.0]]"),
    ({"strides": [0.0]}, "strides must be one number > 0 per level"),
    ({"origins": [[0.0, 0.0, 0.0]]}, "origins must be an x and a y per level, finite"),
    ({"heights": [0.0]}, "heights must be finite and > 0; got [0.0]"),
])
def test_a_confidence_map_names_its_strides_origins_and_heights(change, message):
    """A (L, 1) stride failed at score() with an IndexError, three origins at a reshape, and
    a stride of 0 scored -inf everywhere without a word."""
    args = {"heights": [100.0], "scores": [np.zeros((5, 6))], "origins": [(10.0, 20.0)],
            "strides": [8.0]} | change
    with pytest.raises(ValueError, match=re.escape(message)):
        ConfidenceMap(**args)


@pytest.mark.parametrize("make,error,message", [
    (lambda: ConfidenceMap("a", [np.zeros((3, 3))], [(0, 0)], [8]), TypeError,
     "heights must be numbers > 0; got 'a'"),
    (lambda: ConfidenceMap([90], [np.zeros((3, 3))], [("a", 0)], [8]), TypeError,
     "origins must be numbers; got [('a', 0)]"),
    (lambda: ConfidenceMap([90], [np.zeros((3, 3))], [(0, 0)], [True]), TypeError,
     "strides must be numbers > 0; got [True]"),
    (lambda: ConfidenceMap([90], ["ab"], [(0, 0)], [8]), TypeError,
     "scores[0] must be a grid of numbers; got 'ab'"),
    (lambda: ConfidenceMap([90, 60], [np.zeros((3, 3)), np.where(np.eye(3) > 0, np.nan, 0.0)],
                           [(0, 0)] * 2, [8, 8]), ValueError,
     "scores[1] holds NaN (first at row 0, column 0); a cell with no score is -inf"),
    (lambda: HOGConfidence(heights="abc"), TypeError,
     "heights must be numbers > 0; got 'abc'"),
    (lambda: HOGConfidence(heights=[True, 2]), TypeError,
     "heights must be numbers > 0; got [True, 2]"),
])
def test_a_confidence_map_and_hog_name_values_that_are_not_numbers(make, error, message):
    """Strings failed in numpy's words ("could not convert string to float"), booleans were
    read as 1, and a grid of NaN scores was taken and found nobody without a word."""
    with pytest.raises(error, match=re.escape(message)):
        make()


def test_a_confidence_map_takes_minus_infinity_as_a_cell_with_no_score():
    """-inf is what HOGConfidence leaves where no window was scored; it stays accepted."""
    s = np.zeros((4, 4))
    s[0, 0] = -np.inf
    s[2, 2] = 3.0
    cm = ConfidenceMap([80], [s], [(0, 0)], [8])
    assert float(cm.score(16, 16, 80)) == 3.0


def _walker(t, seen=True):
    """One person walking right, 2 pixels a frame; no detection where ``seen`` is False."""
    if not seen:
        return Detections(boxes=np.zeros((0, 4)))
    cx = 60 + 2 * t
    return Detections(boxes=np.array([[cx - 12, 100, cx + 12, 160.0]]), scores=np.array([0.9]))


def test_step_follows_the_frames_own_index_and_time():
    """step() counted its calls, not the frames: a target was kept across a gap of 13.9 s
    (frames 3 to 100 at 7 frames/s) against max_lost 1.5 s, and a frame before the last was
    taken. The frames' own indices now (as the box trackers take them, the oracle): the
    target ends over the gap, and a frame going back is refused; confirm=1 reports a target
    in the frame it starts (its first frame was lost)."""
    from vistrack.tracking import BoxTracker
    from vistrack.types import Frame

    im = np.full((300, 600, 3), 128, np.uint8)
    trk = DetectorConfidencePF(rng=0, gamma=0.0, eta=0.0, frame_rate=7, confirm=1)
    box = BoxTracker(frame_rate=7)
    outs = [trk.step(Frame(t, (t - 1) / 7, im), _walker(t)).ids.tolist() for t in (1, 2, 3)]
    assert outs == [[1], [1], [1]]
    trk.step(Frame(100, 99 / 7, im), _walker(100, seen=False))
    assert len(trk.ids) == 0  # lost for 13.9 s: ended
    for t in (1, 2, 3):
        box.step(Frame(t, (t - 1) / 7), _walker(t))
    box.step(Frame(100, 99 / 7), _walker(100, seen=False))
    assert len(box.tracks.ids) == 0  # the same rule
    with pytest.raises(ValueError, match="frame"):
        trk.step(Frame(50, 49 / 7, im), _walker(50))


@pytest.mark.parametrize("gap", [13, 18, 30])
def test_a_gap_in_the_frames_longer_than_max_lost_ends_a_target_found_after_it(gap):
    """Frames 11 to 10 + ``gap`` left out (images skipped) at 7 frames/s, max_lost 1.5 s
    (10.5 frames), the person detected before and after: the target was predicted across
    the gap and took the detection after it before the lifecycle looked, so it kept its
    identity (on every seed over gaps of 1.9 to 4.3 s). The oracles: the same frames stepped
    one by one without detections, and the box tracker given the gap; both start a new
    identity for the person after it."""
    from vistrack.tracking import BoxTracker
    from vistrack.types import Frame

    im = np.full((300, 600, 3), 128, np.uint8)
    after = 11 + gap
    for seed in range(5):
        skipped = DetectorConfidencePF(rng=seed, gamma=0.0, eta=0.0, frame_rate=7)
        stepped = DetectorConfidencePF(rng=seed, gamma=0.0, eta=0.0, frame_rate=7)
        for t in range(1, 11):
            skipped.step(Frame(t, (t - 1) / 7, im), _walker(t))
        for t in range(1, after):
            stepped.step(Frame(t, (t - 1) / 7, im), _walker(t, seen=t <= 10))
        for trk in (skipped, stepped):
            for t in (after, after + 1):
                out = trk.step(Frame(t, (t - 1) / 7, im), _walker(t))
            assert trk.ids.tolist() == [2] and out.ids.tolist() == [2], (seed, trk.ids)
    box = BoxTracker(frame_rate=7, max_lost=1.5)
    for t in list(range(1, 11)) + [after, after + 1]:
        out = box.step(Frame(t, (t - 1) / 7), _walker(t))
    assert out.ids.tolist() == [2]


def test_frame_zero_is_a_frame_and_a_confidence_is_a_map():
    """Frame 0 stepped was read as no frame before, so frame 0 could be stepped again (three
    times: one frame confirmed a target on its own) and frame -2 after it was refused in
    seconds, by the track table; a confidence callable returning an array was taken, and
    failed a frame later in numpy's words. The box tracker's words are the oracle."""
    from vistrack.frontends.detectors import ImageTooSmall
    from vistrack.types import Frame

    im = np.full((300, 600, 3), 128, np.uint8)
    trk = DetectorConfidencePF(rng=0, gamma=0.0, eta=0.0)
    trk.step(Frame(0, 0.0, im), _walker(1))
    for again in (0, -2):
        with pytest.raises(ValueError, match=f"^frame must increase; got {again} after 0$"):
            trk.step(Frame(again, 0.0, im), _walker(1))
    trk = DetectorConfidencePF(rng=0, eta=0.0, confidence=lambda image: np.zeros((60, 80)))
    with pytest.raises(TypeError, match="^confidence must be a callable image -> "
                                        "ConfidenceMap; it returned ndarray$"):
        trk.step(Frame(1, 0.0, im), _walker(1))
    # refused by update() too, before anything changes: the frame and the targets stay
    cmap = ConfidenceMap([60.0], [np.zeros((3, 3))], [(0.0, 0.0)], [100.0])
    trk = DetectorConfidencePF(rng=0, eta=0.0, frame_rate=7)
    for t in range(1, 11):
        trk.update(im, _walker(t), cmap)
    with pytest.raises(TypeError, match="^confidence must be a ConfidenceMap; got ndarray$"):
        trk.update(im, _walker(11), np.zeros((60, 80)))
    with pytest.raises(ValueError, match="needs the detector's confidence"):
        trk.step(Frame(30, 29 / 7, im), _walker(30))
    assert trk.frame == 10 and trk.ids.tolist() == [1]
    # the maps' own words: a level named with its shape, no heights, the least image
    with pytest.raises(ValueError, match=re.escape("scores[1] has shape (1, 5)")):
        ConfidenceMap([60.0, 80.0], [np.zeros((3, 3)), np.zeros((1, 5))], [(0, 0)] * 2,
                      [4.0] * 2)
    with pytest.raises(ValueError, match="^heights must hold at least one height; got none$"):
        HOGConfidence([])
    hog = HOGConfidence([46.0])
    assert hog(np.zeros((65, 35), np.uint8)).heights.tolist() == [46.0]  # it fits
    for shape in ((65, 34), (64, 35)):
        with pytest.raises(ImageTooSmall, match="needs 35 x 65 or more"):
            hog(np.zeros(shape, np.uint8))


def test_a_confidence_map_giving_nan_is_named():
    """NaN scores from a user's confidence map failed inside resample ("weights must be
    finite and >= 0"), of weights the user never gave."""
    class Broken(ConfidenceMap):
        def score(self, *args, **kwargs):
            return np.full(np.shape(args[0]), np.nan)

    im = np.full((120, 160, 3), 128, np.uint8)
    cmap = ConfidenceMap([64.0], [np.zeros((10, 12))], [(0.0, 0.0)], [16.0])
    broken = Broken([64.0], [np.zeros((10, 12))], [(0.0, 0.0)], [16.0])
    trk = DetectorConfidencePF(rng=0, eta=0.0)
    det = Detections(boxes=np.array([[50.0, 30, 74, 90]]), scores=np.array([0.9]))
    trk.update(im, det, cmap)
    with pytest.raises(ValueError, match=r"frame 2: the confidence map \(Broken\) gave a "
                                         "score that is not a number"):
        trk.update(im, det, broken)


def test_a_refused_frame_leaves_the_tracker_as_it_was():
    """A frame refused partway (point detections, a grey image with the colour term, a map
    giving NaN after a gap of frames) had taken the frame and moved the particles (and ended
    targets over a gap): the same frame given again was refused as one that does not increase.
    Oracle: a twin tracker of the same seed that never saw the refused frame gives the same
    tracks, particle for particle."""
    from vistrack.types import Frame

    class Broken(ConfidenceMap):
        def score(self, *args, **kwargs):
            return np.full(np.shape(args[0]), np.nan)

    im = np.full((240, 320, 3), 128, np.uint8)
    cmap = ConfidenceMap([64.0], [np.zeros((10, 12))], [(0.0, 0.0)], [16.0])
    broken = Broken([64.0], [np.zeros((10, 12))], [(0.0, 0.0)], [16.0])

    def det(t):
        return Detections(boxes=np.array([[50.0 + 4 * t, 30, 74 + 4 * t, 90]]),
                          scores=np.array([0.9]))

    def pair(**kw):
        return [DetectorConfidencePF(rng=3, confirm=1, max_lost=0.2, **kw) for _ in range(2)]

    # gamma 0 (no map) and the colour term: point detections, then a grey image
    a, b = pair(gamma=0.0)
    for t in (1, 2):
        assert a.step(Frame(t, t / 30, im), det(t)).ids.tolist() == \
            b.step(Frame(t, t / 30, im), det(t)).ids.tolist()
    with pytest.raises(TypeError, match="detections must be vistrack.Detections with boxes"):
        a.step(Frame(3, 0.1, im), Detections(points=np.array([[1.0, 2.0]])))
    with pytest.raises(ValueError, match="image must be a BGR frame"):
        a.step(Frame(3, 0.1, im[..., 0]), det(3))
    for t in (3, 4):
        ta, tb = a.step(Frame(t, t / 30, im), det(t)), b.step(Frame(t, t / 30, im), det(t))
        assert ta.ids.tolist() == tb.ids.tolist() and np.array_equal(ta.boxes, tb.boxes)
    assert np.array_equal(a.particles, b.particles)
    # the map giving NaN after a gap of two frames (the particles moved over it first)
    a, b = pair()
    a.update(im, det(1), cmap, _index=1)
    b.update(im, det(1), cmap, _index=1)
    with pytest.raises(ValueError, match="gave a score that is not a number"):
        a.update(im, Detections(boxes=np.zeros((0, 4))), broken, _index=3)
    assert a.frame == 1 and len(a.ids) == 1
    ta = a.update(im, det(3), cmap, _index=3)
    tb = b.update(im, det(3), cmap, _index=3)
    assert ta.ids.tolist() == tb.ids.tolist() and np.array_equal(a.particles, b.particles)


def _walk(trk, frames, speed=6.0, detected=lambda t: True, fps=10.0):
    """Step ``trk`` through ``frames`` (indices) of a person 60 pixels tall walking right at
    ``speed`` pixels a frame; the detection given where ``detected(t)``."""
    from vistrack.types import Frame

    im = np.zeros((240, 640, 3), np.uint8)
    for t in frames:
        box = np.array([[20.0 + speed * t, 80, 44 + speed * t, 140]])
        det = Detections(boxes=box, scores=[0.9]) if detected(t) else None
        trk.step(Frame(t, t / fps, im), det)


def test_a_gap_of_frames_moves_the_targets_as_far():
    """A gap in the frame indices (frames skipped as unreadable) counts as time for
    ``max_lost``, but the particles moved one frame's worth: after frames 1-20 of a walker
    at 6 pixels a frame and then frame 28, the cloud had moved 6.5 pixels where constant
    velocity moves it 8 frames' worth. Oracle: the cloud's mean moves by ``k`` times its mean
    velocity (no detection: every weight equal, the resampling keeps each particle), and
    the velocity's spread grows as over ``k`` frames stepped one by one."""
    cfg = dict(gamma=0.0, eta=0.0, sigma_pos=0.0, n_particles=4000, frame_rate=10.0, rng=1)
    trk = DetectorConfidencePF(**cfg)
    _walk(trk, range(1, 21))
    p0 = trk.particles[0].copy()
    _walk(trk, [28], detected=lambda t: False)
    p1 = trk.particles[0]
    u = p0[:, 2:].mean(0)
    assert u[0] > 3.0  # (the cloud's velocity follows the walker's, 6)
    np.testing.assert_allclose(p1[:, :2].mean(0), p0[:, :2].mean(0) + 8 * u, atol=0.05)
    # the velocity's variance grew by 8 frames' (sigma_vel h)^2 r^3, r = 7/10
    h = trk.size[0, 1]
    grew = p1[:, 2:].var(0) - p0[:, 2:].var(0)
    np.testing.assert_allclose(grew, 8 * (0.02 * h) ** 2 * 0.7 ** 3, rtol=0.1)
    assert trk.ids.tolist() == [1]


@pytest.mark.parametrize("fps", [7.0, 30.0])
def test_a_gap_of_frames_spreads_the_cloud_as_the_frames_stepped_one_by_one(fps):
    """Across a gap of ``k`` frames the centre's noise was ``k`` frames' own, but left out how
    far each frame's velocity noise moved the centre in the frames after it: after a gap of
    1 s the centre's spread was 0.18 heights where the frames stepped one by one spread it
    0.26 (7 frames/s) and 0.28 (30). Closed form: one target started by one detection, no
    detection after it, so every weight is equal and the systematic resampling keeps each
    particle in its place; each particle's noise over the gap, ``x1 - x0 - k u0`` and
    ``u1 - u0``, then has the covariance of ``k`` steps of ``x += u + e_x, u += e_u``:
    ``Var e_x = k a + b (k-1) k (2k-1) / 6``, ``Var e_u = k b``, ``Cov = b k (k-1) / 2``,
    with ``a = r (sigma_pos h)²``, ``b = r³ (sigma_vel h)²``, ``r = 7 / fps``."""
    def one(gap):
        trk = DetectorConfidencePF(gamma=0.0, eta=0.0, confirm=1, n_particles=20000,
                                   frame_rate=fps, max_lost=5.0, rng=3)
        _walk(trk, [0], speed=0.0, fps=fps)
        p0 = trk.particles[0].copy()
        _walk(trk, [n] if gap else range(1, n + 1), speed=0.0, detected=lambda t: False,
              fps=fps)
        return p0, trk.particles[0], trk.size[0, 1]

    n = k = int(round(fps))  # one second
    p0, p1, h = one(gap=True)
    r = 7.0 / fps
    a, b = r * (0.04 * h) ** 2, r ** 3 * (0.02 * h) ** 2
    for axis in (0, 1):
        e = np.stack([p1[:, axis] - p0[:, axis] - k * p0[:, 2 + axis],
                      p1[:, 2 + axis] - p0[:, 2 + axis]])
        want = [[k * a + b * (k - 1) * k * (2 * k - 1) / 6, b * k * (k - 1) / 2],
                [b * k * (k - 1) / 2, k * b]]
        np.testing.assert_allclose(np.cov(e), want, rtol=0.05, err_msg=str(axis))
    # and the cloud as a whole as the frames stepped one by one (another draw)
    s0, s1, _ = one(gap=False)
    np.testing.assert_allclose(p1.var(0), s1.var(0), rtol=0.06)


def test_the_motion_noise_is_the_same_in_a_second_at_any_frame_rate():
    """``sigma_pos`` and ``sigma_vel`` were per frame whatever the frame rate, so at 30
    frames/s a target's velocity spread 9 times as far in a second as at PETS09's 7, where
    they were chosen, and a person missed for 1 s (under ``max_lost``) came back under a
    new identity. Closed form: one target started by one detection (``confirm`` 1), no
    detection after it, so every weight is equal and the resampling keeps each particle;
    its velocity in pixels a second then has the variance ``(sigma_vel h)² (7² + 7³ t)``
    after ``t`` seconds at any rate (a start spread of ``sigma_vel h`` a frame at 7 frames/s,
    a random walk of ``(sigma_vel h)²`` a frame there), and its centre, without velocity
    noise, ``(sigma_pos h)² (1 + 7 t)``."""
    h = 60.0
    for fps in (7.0, 10.0, 30.0):
        trk = DetectorConfidencePF(gamma=0.0, eta=0.0, confirm=1, n_particles=20000,
                                   frame_rate=fps, max_lost=5.0, rng=2)
        n = int(round(fps))  # one second
        _walk(trk, range(n + 1), speed=0.0, detected=lambda t: t == 0, fps=fps)
        v = trk.particles[0, :, 2:] * fps
        np.testing.assert_allclose(v.var(0), (0.02 * h) ** 2 * (49 + 343), rtol=0.05,
                                   err_msg=str(fps))
        still = DetectorConfidencePF(gamma=0.0, eta=0.0, confirm=1, n_particles=20000,
                                     sigma_vel=0.0, frame_rate=fps, max_lost=5.0, rng=2)
        _walk(still, range(n + 1), speed=0.0, detected=lambda t: t == 0, fps=fps)
        np.testing.assert_allclose(still.particles[0, :, :2].var(0), (0.04 * h) ** 2 * 8,
                                   rtol=0.05, err_msg=str(fps))


@pytest.mark.parametrize("fps", [7.0, 30.0])
def test_a_person_missed_for_a_second_keeps_their_identity_at_any_frame_rate(fps):
    """A person walking 0.5 heights a second, missed for 1 s (``max_lost`` 1.5 s), with the
    detection term alone: at 30 frames/s the per-frame noise spread the cloud so far that
    the person came back under a new identity in 3 of 5 seeds; at 7 frames/s none did."""
    for seed in range(5):
        trk = DetectorConfidencePF(gamma=0.0, eta=0.0, frame_rate=fps, rng=seed)
        n = int(round(4 * fps))
        _walk(trk, range(n), speed=30.0 / fps, fps=fps,
                detected=lambda t: not (1.5 * fps <= t < 2.5 * fps))
        assert trk.ids.tolist() == [1], (fps, seed)


def test_the_younger_target_ends_after_merge_time_across_gaps_of_frames():
    """The merge timer added ``1 / frame_rate`` a step: with every 5th frame stepped at 10
    frames/s, two targets on one person overlapped for 3 s (``merge_time`` 0.5 s) and
    both stayed. Oracle: the overlap's time from the frames' indices, 0.5 s a step, each
    step counting the time since the one before, as a frame counts 1 / frame_rate."""
    from vistrack.types import Frame

    im = np.zeros((240, 320, 3), np.uint8)
    trk = DetectorConfidencePF(frame_rate=10, gamma=0.0, eta=0.0, max_lost=100.0, rng=0)
    held = []
    for t in range(1, 40, 5):  # two people 14 pixels apart (IoU 0.26), then on one place
        gap = 14.0 if t < 10 else 3.0
        det = Detections(boxes=np.array([[100.0, 60, 124, 120], [100 + gap, 60, 124 + gap, 120]]),
                         scores=np.full(2, 0.9))
        trk.step(Frame(t, t / 10, im), det)
        held.append(trk.ids.tolist())
    # frames 1 and 6 confirm both; 11 overlaps (0.5 s since 6, not more); 16 ends the younger
    assert held[:3] == [[1, 2]] * 3 and held[3:] == [[1]] * 5, held


def test_two_detections_of_one_person_start_one_target():
    """``max_overlap`` was checked against the targets only, so two detections of one
    person in one frame (IoU 0.82; a detection file has no suppression) started two
    targets, both reported. The stronger starts one; one apart from it starts its own."""
    im = np.zeros((240, 320, 3), np.uint8)
    trk = DetectorConfidencePF(gamma=0.0, eta=0.0, rng=0)
    boxes = np.array([[100.0, 60, 124, 120], [101.0, 61, 125, 121], [200.0, 60, 224, 120]])
    for _ in range(3):
        out = trk.update(im, Detections(boxes=boxes, scores=[0.8, 0.9, 0.85]))
    assert trk.ids.tolist() == [1, 2] and len(out) == 2
    np.testing.assert_allclose(out.boxes[0], boxes[1], atol=1.0)  # from the stronger


def test_a_target_keeps_to_its_detections_class():
    """Trackers never give two classes one identity (`Detections`): a box of class 7 took
    the target of a class-3 box at its place, and every target was reported as class 0. Two
    overlapping boxes of two classes start two targets (one person by a car)."""
    im = np.zeros((240, 320, 3), np.uint8)
    trk = DetectorConfidencePF(gamma=0.0, eta=0.0, rng=0)
    box = np.array([[100.0, 60, 124, 120]])
    seen = {}
    for t in range(8):
        cls = [3] if t < 4 else [7]
        out = trk.update(im, Detections(boxes=box, scores=[0.9], classes=cls))
        for i, c in zip(out.ids.tolist(), out.classes.tolist()):
            seen.setdefault(i, set()).add(c)
            assert c == cls[0]
    assert len(seen) == 2 and all(len(c) == 1 for c in seen.values())
    both = DetectorConfidencePF(gamma=0.0, eta=0.0, rng=0)
    for _ in range(3):
        out = both.update(im, Detections(boxes=np.r_[box, box + 1.0], scores=[0.9, 0.8],
                                         classes=[3, 7]))
    assert sorted(out.classes.tolist()) == [3, 7] and len(set(out.ids.tolist())) == 2


def test_the_colour_classifier_names_a_grey_frame():
    with pytest.raises(ValueError, match=re.escape("image must be a BGR frame (H, W, 3) for the "
                                                   "colour features")):
        DetectorConfidencePF(gamma=0.0, rng=0).update(np.zeros((240, 320), np.uint8),
                                                      Detections(boxes=np.zeros((0, 4))))


def test_no_confidence_map_is_computed_without_its_term():
    """With ``gamma`` 0 nothing reads the detector's confidence, but :meth:`step` computed
    it every frame (a dense HOG map, 0.1 s a frame, for nothing)."""
    from vistrack.types import Frame

    calls = []
    im = np.zeros((120, 160, 3), np.uint8)
    trk = DetectorConfidencePF(gamma=0.0, confidence=lambda image: calls.append(1))
    for t in range(4):
        trk.step(Frame(t, t / 30, im), Detections(boxes=np.array([[50.0, 30, 74, 90]]),
                                                  scores=[0.9]))
    assert calls == [] and trk.ids.tolist() == [1]


def test_the_particles_weights_are_the_observation_model():
    """The weights given to the resampling against the seed's observation model computed
    by hand, each term with a weight of its own: ``1e-6 + β exp(-|p - d*|² / 2 (σ_det h)²)``
    for the target the detection was associated with, plus ``γ d_c(p) p_o`` everywhere,
    ``p_o = 1 / (1 + k)`` for the ``k`` other targets overlapping at IoU > 0.2, ``d_c`` the
    logistic of a plane's confidence (bilinear interpolation is exact on it)."""
    import vistrack.tracking.dcpf as dcpf
    from vistrack.association import iou

    captured = []
    resample = dcpf.resample

    def spy(w, *a, **kw):
        captured.append(np.array(w))
        return resample(w, *a, **kw)

    im = np.full((240, 320, 3), 128, np.uint8)
    y, x = np.mgrid[0:40, 0:50] * 8.0
    cmap = ConfidenceMap([60.0], [0.02 * x - 0.01 * y], [(0.0, 0.0)], [8.0])
    trk = DetectorConfidencePF(rng=0, eta=0.0, sigma_pos=0.0, sigma_vel=0.0, frame_rate=10,
                               beta=1.3, gamma=0.7, sigma_det=0.2, max_overlap=1.0)
    boxes = np.array([[100.0, 60, 24, 60], [110.0, 62, 24, 60], [250.0, 100, 24, 60]])
    trk.update(im, Detections.from_xywh(boxes, np.full(3, 0.9)), cmap)
    trk.particles[..., :2] += np.random.default_rng(1).normal(0, 5, (3, 100, 2))
    trk.particles[..., 2:] = 0.0
    P, size = trk.particles[..., :2].copy(), trk.size.copy()
    d = np.array([[103.0, 61, 24, 60]])
    dcpf.resample = spy
    try:
        trk.update(im, Detections.from_xywh(d, np.array([0.9])), cmap)
    finally:
        dcpf.resample = resample
    c = P.mean(1)
    xyxy = np.c_[c - size / 2, c + size / 2]
    ov = iou(xyxy, xyxy)
    np.fill_diagonal(ov, 0.0)
    p_o = 1.0 / (1.0 + (ov > 0.2).sum(1))
    assert p_o.tolist() == [0.5, 0.5, 1.0]
    want = 1e-6 + 0.7 / (1 + np.exp(-(0.02 * P[..., 0] - 0.01 * P[..., 1]))) * p_o[:, None]
    centre = d[0, :2] + d[0, 2:] / 2
    want[0] += 1.3 * np.exp(-0.5 * ((P[0] - centre) ** 2).sum(-1) / (0.2 * size[0, 1]) ** 2)
    np.testing.assert_allclose(captured[0], want / want.sum(1, keepdims=True), rtol=1e-9)


def test_a_detection_of_another_height_is_not_associated():
    """The gate takes a detection whose height is within a factor 1.5 of the target's: one
    1.6 times as tall, on the target's centre, starts no update of it (the target goes
    unsupported and a tentative target starts from it), one 1.4 times as tall updates it."""
    im = np.zeros((240, 320, 3), np.uint8)
    for factor, updated in ((1.4, True), (1.6, False)):
        trk = DetectorConfidencePF(gamma=0.0, eta=0.0, rng=0, max_overlap=1.0)
        for _ in range(3):
            trk.update(im, Detections.from_xywh(np.array([[100.0, 60, 24, 60]]), [0.9]))
        h = 60 * factor
        out = trk.update(im, Detections.from_xywh(np.array([[100.0, 90 - h / 2, 24, h]]),
                                                  [0.9]))
        assert (out.ids.tolist() == [1]) is updated, factor
        assert len(trk.ids) == (1 if updated else 2), factor


def test_a_nan_height_has_no_level_and_a_cell_beside_minus_inf_keeps_its_score():
    """level(nan) was level 0, so a NaN height scored on the first level; and a centre on a
    cell whose neighbour is -inf scored NaN (its zero weight times -inf). The oracle: the
    cells' own values, and `outside` where no level applies."""
    grid = np.array([[1.0, 2.0, -np.inf], [3.0, 4.0, 5.0]])
    cm = ConfidenceMap([50.0, 100.0], [grid, grid], [(0.0, 0.0)] * 2, [10.0, 10.0])
    assert cm.level([np.nan, 50.0, 100.0]).tolist() == [-1, 0, 1]
    assert cm.score(0.0, 0.0, np.nan, outside=-7.0) == -7.0
    # on cell (0, 1), beside the -inf at (0, 2): its own 2; on (1, 2) below it: 5
    np.testing.assert_array_equal(cm.score([10.0, 20.0, 15.0], [0.0, 10.0, 10.0], 50.0),
                                  [2.0, 5.0, 4.5])
    # between the -inf cell and another, a person can be nowhere there: -inf, not NaN
    assert cm.score(15.0, 0.0, 50.0) == -np.inf


def test_a_centre_on_the_grids_edge_by_rounding_keeps_its_cells_score():
    """Within the edge's allowance of 1e-9 of a cell, (x - origin) / stride can pass the
    last column by rounding (1.0000000000000002 here): the weight of the -inf column beside
    it came to -2e-16, and the score to +inf. It is the last column's own, 2."""
    grid = np.array([[-np.inf, 2.0], [-np.inf, 2.0]])
    cm = ConfidenceMap([50.0], [grid], [(0.1, 0.0)], [0.7])
    assert (0.8 - 0.1) / 0.7 > 1.0  # (the rounding this is about)
    assert cm.score(0.8, 0.0, 50.0) == 2.0


def test_a_step_before_the_last_update_is_refused_by_its_frame():
    """step(Frame(3)) after update() had moved the tracker to frame 4 was refused by the
    track table, "time must not go back: 0.1 after ... 0.133", in seconds, after the
    tracker had taken frame 3 as its own; it is refused by its frame, before anything
    changes."""
    from vistrack.types import Detections, Frame

    img = np.zeros((120, 160, 3), np.uint8)
    tr = DetectorConfidencePF(DCPFConfig(gamma=0.0), frame_rate=30)
    tr.step(Frame(1, 0.0, img), Detections(boxes=np.zeros((0, 4))))
    for _ in range(3):
        tr.update(img, Detections(boxes=np.zeros((0, 4))))
    assert tr.frame == 4
    with pytest.raises(ValueError, match=r"^frame must increase; got 3 after 4$"):
        tr.step(Frame(3, 0.0, img), Detections(boxes=np.zeros((0, 4))))
    assert tr.frame == 4
    tr.step(Frame(5, 0.0, img), Detections(boxes=np.zeros((0, 4))))  # the next is taken
    assert tr.frame == 5


def test_the_tracker_names_a_config_or_rng_it_cannot_take():
    """A config that is no DCPFConfig (a dict of settings, a file's path) failed in reset,
    "'dict' object has no attribute 'n_particles'"; a bad rng in numpy's SeedSequence words
    at reset, and True was taken as the seed 1. Each is named when the tracker is made."""
    from vistrack.tracking.dcpf import DetectorConfidencePF

    for config in ({"beta": 1.0}, "dcpf.toml"):
        with pytest.raises(TypeError, match=r"^config must be a DCPFConfig \(DCPFConfig\("
                                            r"\*\*settings\), or vistrack\.config\."
                                            r"read_dcpf_config\(path\) for a file\); got "):
            DetectorConfidencePF(config, gamma=0.0)
    for rng, kind in (("a", TypeError), (1.5, TypeError), (True, TypeError), (-1, ValueError)):
        with pytest.raises(kind, match=r"^rng must be "):
            DetectorConfidencePF(rng=rng, gamma=0.0)
    for rng in (None, 3, np.random.default_rng(1)):  # what it takes
        DetectorConfidencePF(rng=rng, gamma=0.0)

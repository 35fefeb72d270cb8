"""KLT feature tracking: sub-pixel motion with known truth, large motions, the affine check
against the first frame, affine registration of a known warp, and a static camera."""

from __future__ import annotations

import re

import cv2
import numpy as np
import pytest

from vistrack.tracking._affine import prepare_templates, register
from vistrack.tracking.klt import KLTTracker

from .conftest import SHARED


def texture(rng, shape=(240, 320), blur=2.0):
    im = rng.uniform(0, 255, shape).astype(np.float32)
    return cv2.GaussianBlur(im, (0, 0), blur)


def shifted(im, dx, dy):
    M = np.float32([[1, 0, dx], [0, 1, dy]])
    return np.clip(cv2.warpAffine(im, M, im.shape[::-1], flags=cv2.INTER_CUBIC,
                                  borderMode=cv2.BORDER_REFLECT), 0, 255).astype(np.uint8)


def test_features_follow_a_known_subpixel_motion():
    rng = np.random.default_rng(0)
    base = texture(rng)
    klt = KLTTracker(200)
    f0 = klt.track(shifted(base, 0, 0))
    start = dict(zip(f0.ids.tolist(), f0.points))
    v = np.array([1.3, -0.7])
    for k in range(1, 11):
        f = klt.track(shifted(base, *(k * v)))
    assert f.ages.max() == 10
    old = np.isin(f.ids, list(start))
    assert old.sum() > 0.9 * len(start)  # nearly all survive every check
    err = np.array([p - start[i] - 10 * v for i, p in zip(f.ids[old], f.points[old])])
    inner = np.all((f.points[old] > 20) & (f.points[old] < [300, 220]), axis=1)
    assert np.median(np.abs(err[inner])) < 0.05 and np.abs(err[inner]).max() < 0.3
    # topped up whenever a fifth is gone
    assert f.residuals[old].max() < 0.3 and len(f) >= 160


def test_a_frame_of_another_size_is_refused_with_or_without_features():
    """The contract (``ValueError`` on a frame whose size differs from the previous one's)
    holds after a frame with no features too, where the check was skipped and the new size
    taken in silence; after ``reset`` any size starts afresh."""
    rng = np.random.default_rng(0)
    small = shifted(texture(rng, (30, 40)), 0, 0)
    for first in (np.zeros((60, 80), np.uint8), shifted(texture(rng, (60, 80)), 0, 0)):
        klt = KLTTracker(20)
        assert (len(klt.track(first)) > 0) == (first.max() > 0)
        with pytest.raises(ValueError, match="image is 40x30; the previous frame was 80x60"):
            klt.track(small)
        klt.reset()
        assert len(klt.track(small)) > 0


def test_large_motions_are_found_by_discrete_search():
    """Without a pyramid, Lucas-Kanade loses a 9-pixel jump; the NCC search finds it."""
    rng = np.random.default_rng(1)
    base = texture(rng, blur=1.5)
    kept = {}
    for radius in (0, 24):
        klt = KLTTracker(150, levels=0, search_radius=radius)
        ids0 = set(klt.track(shifted(base, 0, 0)).ids.tolist())
        f = klt.track(shifted(base, 9, -6))
        kept[radius] = len(ids0 & set(f.ids.tolist())) / len(ids0)
    assert kept[0] < 0.3 and kept[24] > 0.8


def test_the_search_keeps_no_hidden_feature_on_a_look_alike():
    """A still scene where each of ten features has its whole patch covered by a white square
    in the next frame: nothing moved, so a hidden feature kept anywhere but where it was is
    wrong. The discrete search finds a look-alike within 24 px for some, and the backward
    check started those from where they were, so they came back there whatever the search
    had matched: 8 of 100 were kept, 10-30 px off. Searched for back from its new place, a
    feature must be found where it was: the search keeps none that Lucas-Kanade alone
    (``search_radius=0``) drops, and every feature not covered stays within a pixel."""
    kept = {0: set(), 24: set()}
    for seed in range(10):
        rng = np.random.default_rng(seed)
        base = cv2.GaussianBlur(rng.normal(size=(240, 320)), (0, 0), 2.5)
        first = np.clip(np.rint(128 + base / base.std() * 40), 0, 255).astype(np.uint8)
        for radius in kept:
            klt = KLTTracker(max_features=200, search_radius=radius)
            f0 = klt.track(first)
            hidden = [k for k, (x, y) in enumerate(f0.points)
                      if 40 < x < 280 and 40 < y < 200][:10]
            second = first.copy()
            for k in hidden:
                x, y = f0.points[k].astype(int)
                second[y - 6:y + 7, x - 6:x + 7] = 255
            f1 = klt.track(second)
            where = dict(zip(f1.ids.tolist(), f1.points))
            kept[radius] |= {(seed, int(f0.ids[k])) for k in hidden if f0.ids[k] in where}
            near = [np.hypot(*(where[i] - p)) for k, (i, p) in enumerate(zip(f0.ids, f0.points))
                    if k not in hidden and i in where]
            assert len(near) > 100 and max(near) <= 1.0, (seed, radius, max(near))
    assert kept[24] <= kept[0] and len(kept[0]) <= 2, kept


def test_affine_check_against_the_first_frame_stops_slow_drift():
    """A patch of the scene fades into other content, 4 % a frame: each frame looks like
    the last (Lucas-Kanade and the forward-backward check keep the features), but against
    the frame where the features were first seen the patch no longer matches, and the
    affine check ends them; elsewhere features live on."""
    rng = np.random.default_rng(2)
    a, b = texture(rng), texture(rng)
    region = (slice(60, 180), slice(40, 150))
    survivors = {}
    for check in (False, True):
        klt = KLTTracker(300, affine_check=check)
        f = klt.track(a.astype(np.uint8))
        inside = {i for i, (x, y) in zip(f.ids.tolist(), f.points)
                  if 50 <= x < 140 and 70 <= y < 170}
        outside = set(f.ids.tolist()) - inside
        for k in range(1, 26):
            im = a.copy()
            w = min(1.0, 0.04 * k)
            im[region] = (1 - w) * a[region] + w * b[region]
            f = klt.track(im.astype(np.uint8))
        now = set(f.ids.tolist())
        survivors[check] = (len(inside & now) / len(inside), len(outside & now) / len(outside))
    assert survivors[False][0] > 0.5  # frame to frame, the fading patch passes
    assert survivors[True][0] < 0.1  # against the first frame, it does not
    assert survivors[True][1] > 0.9  # the rest of the scene is kept


def test_affine_registration_recovers_a_known_warp():
    rng = np.random.default_rng(3)
    img = texture(rng)
    c = np.array([[120.0, 110.0]])
    A, d = np.array([[1.06, 0.04], [-0.03, 0.95]]), np.array([2.4, -1.7])
    M = np.c_[A, d + c[0] - A @ c[0]]  # the warp about the patch centre
    img2 = cv2.warpAffine(img, M, img.shape[::-1], flags=cv2.INTER_CUBIC)
    img2 = 0.8 * img2 + 20  # and a change of contrast and brightness
    T, SD, Hinv, ok = prepare_templates(img, c, 7)
    p = np.zeros((1, 6))
    p[0, 4:] = c[0]
    rms = register(img2, 7, T, SD, Hinv, p, iters=50, eps=1e-4)
    assert ok[0] and rms[0] < 0.05
    # where the patch's corners land, by the estimated and the true warp: within 0.1 pixel
    corners = np.array([[-7, -7], [7, -7], [-7, 7], [7, 7]], float)
    Ae = np.array([[1 + p[0, 0], p[0, 2]], [p[0, 1], 1 + p[0, 3]]])
    est = corners @ Ae.T + p[0, 4:]
    true = corners @ A.T + c[0] + d
    assert np.abs(est - true).max() < 0.1
    flat = prepare_templates(np.full((50, 50), 7.0), np.array([[25.0, 25.0]]), 5)[3]
    assert not flat[0]  # a flat patch cannot be registered


def test_static_camera_features_stay_put_on_pets09():
    """Real frames (PETS09-S2L1, a fixed camera): features off the people do not move."""
    from vistrack.io import VideoReader, read_mot

    video = SHARED / "data" / "opencv-vtest" / "vtest.avi"
    gt_path = SHARED / "data" / "mot15" / "PETS09-S2L1" / "gt" / "gt.txt"
    if not video.exists() or not gt_path.exists():
        pytest.skip(f"{video} not found: the shared data is not beside this checkout")
    gt = read_mot(gt_path)
    klt = KLTTracker(300)
    frames = list(VideoReader(video, grey=True, stop=12))
    start = klt.track(frames[0].image)
    first = dict(zip(start.ids.tolist(), start.points))
    for fr in frames[1:]:
        f = klt.track(fr.image)
    people = gt.boxes[gt.frames <= 12]
    moved = []
    for i, p in zip(f.ids.tolist(), f.points):
        if i not in first:
            continue
        q = first[i]
        on_person = ((q[0] >= people[:, 0] - 10) & (q[0] <= people[:, 0] + people[:, 2] + 10)
                     & (q[1] >= people[:, 1] - 10)
                     & (q[1] <= people[:, 1] + people[:, 3] + 10)).any()
        if not on_person:
            moved.append(np.linalg.norm(p - q))
    assert len(moved) > 150 and np.median(moved) < 0.1 and np.percentile(moved, 95) < 0.5


def _scene(seed=0, shape=(240, 320)):
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.integers(0, 256, shape).astype(np.uint8), (0, 0), 2)


def test_drawing_on_a_grey_frame_after_tracking_changes_nothing():
    """The tracker kept the caller's grey frame itself as its reference: circles drawn on it
    to show the features ended 868 of them over five frames of a 1-pixel pan. The same
    features with and without drawing (the oracle: the run that does not draw)."""
    scene = _scene()
    runs = []
    for draw in (False, True):
        klt, out = KLTTracker(max_features=200), []
        for k in range(6):
            f = np.roll(scene, k, axis=1).copy()
            feats = klt.track(f)
            out.append((feats.ids.tolist(), feats.points.tolist(), feats.terminated))
            if draw:
                for x, y in feats.points:
                    cv2.circle(f, (int(round(x)), int(round(y))), 3, 255, 1)
        runs.append(out)
    assert runs[0] == runs[1] and sum(t for *_, t in runs[0]) == 0


def _ncc(a, pa, b, pb, half):
    """Normalised cross-correlation of the patches at sub-pixel places (OpenCV's bilinear
    sampling, independent of vistrack's)."""
    size = (2 * half + 1, 2 * half + 1)
    out = []
    for (xa, ya), (xb, yb) in zip(pa, pb):
        u = cv2.getRectSubPix(a, size, (float(xa), float(ya))).ravel() - 0.0
        v = cv2.getRectSubPix(b, size, (float(xb), float(yb))).ravel() - 0.0
        u, v = u - u.mean(), v - v.mean()
        out.append(float(u @ v / np.sqrt((u @ u) * (v @ v))))
    return np.array(out)


def test_a_feature_the_search_found_meets_min_ncc_too():
    """A feature the discrete search found was kept at a correlation of 0.7 at its integer
    place, whatever ``min_ncc``, and never checked at its refined place: with ``min_ncc``
    0.95 two were kept at 0.73. Every feature kept correlates with its last patch by at least
    ``min_ncc`` (measured with OpenCV's sampling)."""
    rng = np.random.default_rng(0)
    scene = _scene()
    noisy = lambda im: np.clip(im + rng.normal(0, 12, im.shape), 0, 255).astype(np.uint8)  # noqa: E731
    a, b = noisy(scene), noisy(np.roll(scene, 2, axis=1))
    for min_ncc in (0.95, 0.8):
        klt = KLTTracker(max_features=200, min_ncc=min_ncc, affine_check=False)
        f0, f1 = klt.track(a), klt.track(b)
        kept = np.isin(f0.ids, f1.ids)
        n = int(kept.sum())
        ncc = _ncc(a.astype(np.float32), f0.points[kept], b.astype(np.float32),
                   f1.points[:n], 5)
        assert (ncc >= min_ncc - 1e-4).all(), ncc.min()


def test_features_start_inside_the_image_and_reach_max_features():
    """The features were asked of OpenCV to exactly the number missing, and those too near
    the border for their patch were dropped after: on vtest.avi 483 of 500 started, and the
    count stayed short until a fifth was gone. Without the affine check the border's
    features were kept, then ended by the correlation check with nothing moved (500, then
    486 on the same frame again). Oracle: OpenCV's own corners of the frame, far more than
    500 of them inside the border."""
    frame = cv2.cvtColor(_vtest_frame(), cv2.COLOR_BGR2GRAY)
    H, W = frame.shape
    for check in (True, False):
        klt = KLTTracker(500, affine_check=check)
        first = klt.track(frame)
        assert len(first) == 500
        m = klt.half + 1  # the patch and the pixel around it inside the image
        assert (first.points >= m).all() and (first.points <= [W - m - 2, H - m - 2]).all()
        again = klt.track(frame)
        assert again.terminated == 0 and len(again) == 500


def test_top_ups_take_corners_of_the_share_of_the_frames_best():
    """``quality`` is a share of the frame's strongest corner, but OpenCV takes it of the
    strongest its mask leaves: with the features kept hidden, each top-up took weaker
    corners (to 0.0057 of the frame's best for 0.01). Oracle: OpenCV's minimum eigenvalues
    of the whole frame, at every feature started on vtest.avi's first frames."""
    klt = KLTTracker(1000, quality=0.01)
    seen: set = set()
    for frame in _vtest_frames(4):
        frame = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        f = klt.track(frame)
        new = ~np.isin(f.ids, list(seen))
        seen.update(f.ids.tolist())
        if new.any():
            eig = cv2.cornerMinEigenVal(frame, klt.block_size)
            x, y = np.round(f.points[new]).astype(int).T
            assert eig[y, x].min() >= 0.01 * eig.max() * (1 - 1e-6)
    assert len(seen) > len(f)  # topped up on the way


def _vtest_frames(n):
    from .conftest import need

    path = need(SHARED / "data" / "opencv-vtest" / "vtest.avi")
    reader = cv2.VideoCapture(str(path))
    frames = [reader.read()[1] for _ in range(n)]
    reader.release()
    assert all(f is not None for f in frames)
    return frames


def _vtest_frame():
    return _vtest_frames(1)[0]


def test_a_min_ncc_of_minus_one_is_refused():
    """A patch that leaves its image, or is flat, scores -1: at ``min_ncc`` -1 such features
    passed the correlation check."""
    with pytest.raises(ValueError, match=r"min_ncc must be a finite number > -1 and <= 1; "
                                         r"got -1"):
        KLTTracker(min_ncc=-1)


@pytest.mark.parametrize("min_distance", [7.0, 10.9])
def test_new_features_keep_min_distance_from_those_kept(min_distance):
    """New features were kept from the old ones by circles drawn in whole pixels about
    rounded points: a corner 9.54 px from a kept feature started with min_distance 10.9
    (6.56 with 7). Oracle: every pair's distance, new to kept, over several top-ups."""
    rng = np.random.default_rng(4)
    base = texture(rng)
    klt = KLTTracker(max_features=2000, min_distance=min_distance)
    seen = klt.track(shifted(base, 0, 0))
    topped = 0
    for k in range(1, 8):
        kept = set(seen.ids.tolist())
        f = klt.track(shifted(base, 0.5 * k, 0.3 * k))
        new = ~np.isin(f.ids, list(kept))
        if new.any() and (~new).any():
            topped += 1
            d = np.linalg.norm(f.points[new][:, None] - f.points[~new][None], axis=2)
            # the kept features' positions are this frame's; new ones were kept from where
            # the kept ones were found this frame
            assert d.min() >= min_distance, d.min()
        seen = f
    assert topped >= 1


def test_a_top_up_reaches_max_features_where_the_image_has_the_corners():
    """The exact min_distance test dropped corners OpenCV had counted against the top-up's
    quota: the features stayed short of max_features (on vtest.avi 5 of 150 frames at 500,
    against 14 before it). Oracle: a textured frame with corners to spare, shifted so that a
    fifth of the features leave: the top-up brings them back to max_features."""
    rng = np.random.default_rng(6)
    base = texture(rng, (240, 320), blur=1.5)
    other = texture(rng, (240, 320), blur=1.5)
    for md in (7.0, 10.9):
        klt = KLTTracker(max_features=150, min_distance=md)
        assert len(klt.track(shifted(base, 0, 0))) == 150
        # the left part of the view replaced: its features fail, a top-up follows
        cut = base.copy()
        cut[:, :120] = other[:, :120]
        f = klt.track(shifted(cut, 0, 0))
        assert f.terminated >= 30 and len(f) == 150, (md, f.terminated, len(f))


def test_patches_are_compared_inside_each_image_by_its_own_size():
    """patch_ncc checked b's patch against a's size: a patch of a large b outside a small
    a's bounds scored -1 (and a small b was read past its end). Oracle: the same pixels
    copied, NCC 1, and a patch outside b, -1."""
    from vistrack.tracking._affine import patch_ncc

    rng = np.random.default_rng(5)
    a = rng.uniform(0, 255, (20, 20)).astype(np.float32)
    b = np.zeros((200, 200), np.float32)
    b[95:106, 95:106] = a[5:16, 5:16]
    assert patch_ncc(a, np.array([[10.0, 10.0]]), b, np.array([[100.0, 100.0]]), 5)[0] == \
        pytest.approx(1.0)
    assert patch_ncc(b, np.array([[100.0, 100.0]]), a, np.array([[10.0, 10.0]]), 5)[0] == \
        pytest.approx(1.0)
    assert patch_ncc(b, np.array([[100.0, 100.0]]), a, np.array([[100.0, 100.0]]), 5)[0] == -1


def test_a_frame_too_small_for_any_patch_is_refused():
    """With half=100 on a 160 x 120 frame no feature can be found, frame after frame, and
    none was, without a word (half=0 is refused for that reason). Oracle: the corner mask's
    own extent, which is empty below 2 half + 4 pixels."""
    rng = np.random.default_rng(0)
    frame = shifted(texture(rng, (120, 160)), 0, 0)
    with pytest.raises(ValueError, match=re.escape(
            "image is 160x120: a feature's patch of half=100 and the pixel around it need "
            "204 pixels across and down")):
        KLTTracker(half=100).track(frame)
    with pytest.raises(ValueError, match="need 124 pixels"):
        KLTTracker(half=60).track(frame)
    assert len(KLTTracker(half=58).track(frame)) > 0  # 120 = 2 x 58 + 4: it fits


@pytest.mark.parametrize("name, value, most", [
    ("min_distance", 3e9, "2**20"), ("max_features", 2**30, "2**20"), ("levels", 2**31, "2**20"),
    ("half", 2**31, "2**20"), ("search_radius", 2**31, "2**20"),
    ("win_size", 100_000, "4096 pixels"), ("block_size", 2**31, "4096 pixels")])
def test_sizes_past_what_opencv_holds_are_named(name, value, most):
    """OpenCV takes these as C ints: ``min_distance=3e9`` crashed the process (a
    segmentation fault in goodFeaturesToTrack, at the first frame), the others failed in
    OpenCV's overload error naming none, and a window of 100,000 pixels in its failure to
    allocate 40 GB. Refused at construction, named; the largest taken tracks."""
    with pytest.raises(ValueError, match=re.escape(f"{name} must be at most {most}")):
        KLTTracker(**{name: value})
    if name in ("win_size", "block_size", "min_distance"):
        rng = np.random.default_rng(0)
        scene = cv2.GaussianBlur(rng.integers(0, 256, (60, 80), dtype=np.uint8), (0, 0), 2)
        klt = KLTTracker(**{name: 4095 if name == "block_size" else
                            4096 if name == "win_size" else 2**20})
        klt.track(scene)
        klt.track(np.roll(scene, 1, axis=1))

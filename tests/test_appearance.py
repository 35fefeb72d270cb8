"""The WSL appearance model: its ownerships against scipy's densities, online EM against the
exponentially weighted moments it must equal on clean data, persistence through outliers,
and a region tracker through synthetic and real occlusions."""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.stats import norm

from vistrack.tracking.appearance import WSLModel, WSLTracker

from .conftest import SHARED, need


def test_ownership_is_bayes_rule_on_the_three_densities():
    rng = np.random.default_rng(0)
    model = WSLModel((5, 4), sigma_w=0.1)
    model.init(rng.random((5, 4)))
    for _ in range(3):
        model.update(rng.random((5, 4)))
    d = rng.random((5, 4))
    p = np.stack([model.m[0] * norm.pdf(d, model.mu_s, np.sqrt(model.var_s)),
                  model.m[1] * norm.pdf(d, model.prev, 0.1),
                  model.m[2] * np.ones_like(d)])
    np.testing.assert_allclose(model.ownership(d), p / p.sum(0), rtol=1e-12)
    batch = rng.random((7, 5, 4))
    expect = np.log(np.stack([model.m[0] * norm.pdf(batch, model.mu_s, np.sqrt(model.var_s)),
                              model.m[1] * norm.pdf(batch, model.prev, 0.1),
                              model.m[2] * np.ones_like(batch)]).sum(0)).sum((1, 2))
    np.testing.assert_allclose(model.log_likelihood(batch), expect, rtol=1e-12)


def test_online_em_equals_the_exponentially_weighted_moments_when_s_owns_everything():
    """With a tiny lost density and a very broad wandering density, S owns (nearly) every
    observation, and online EM reduces to moments weighted by α = 1 - exp(-1/τ) times the
    ownership."""
    rng = np.random.default_rng(1)
    d = 0.4 + 0.03 * rng.normal(size=300)
    model = WSLModel((1,), tau=15.0, sigma_w=10.0, lost_density=1e-12, sigma_s0=0.03,
                     sigma_min=1e-6, m0=(0.98, 0.01, 0.01))
    model.init(d[:1])
    a = 1 - np.exp(-1 / 15.0)
    m, M1, M2 = 0.98, 0.98 * d[0], 0.98 * (0.03 ** 2 + d[0] ** 2)
    for x in d[1:]:
        o = model.update(x[None])
        o = o[0, 0]
        assert o > 0.95
        m, M1, M2 = a * o + (1 - a) * m, a * o * x + (1 - a) * M1, a * o * x * x + (1 - a) * M2
    np.testing.assert_allclose(model.mu_s[0], M1 / m, rtol=1e-5)
    np.testing.assert_allclose(model.var_s[0], M2 / m - (M1 / m) ** 2, rtol=1e-3)
    assert abs(np.sqrt(model.var_s[0]) - 0.03) < 0.01


def test_stable_mean_holds_through_a_burst_of_outliers():
    """The seed's Figure 2: 90 % Gaussian, 10 % uniform noise around a constant, then 15
    frames of pure outliers."""
    rng = np.random.default_rng(2)
    n, truth = 400, 0.6
    outlier = rng.random(n) < 0.1
    outlier[300:315] = True
    d = np.where(outlier, rng.random(n), truth + rng.normal(0, 0.02, n))
    model = WSLModel((1,))
    model.init(np.array([truth]))
    mu, m_l = [], []
    for x in d:
        model.update(x[None])
        mu.append(model.mu_s[0])
        m_l.append(model.m[2, 0])
    mu, m_l = np.array(mu), np.array(m_l)
    assert np.abs(mu[50:300] - truth).max() < 0.02
    assert np.abs(mu[300:315] - truth).max() < 0.03         # the outliers leave μ_s in place
    assert m_l[314] > m_l[299] + 0.2                        # and the lost component takes them
    assert np.abs(mu[-1] - truth) < 0.02


def test_model_arguments_are_checked():
    with pytest.raises(ValueError, match="tau"):
        WSLModel((3,), tau=0)
    with pytest.raises(ValueError, match="m0"):
        WSLModel((3,), m0=(1, 0, 0))
    model = WSLModel((3, 2))
    with pytest.raises(RuntimeError, match="init"):
        model.ownership(np.zeros((3, 2)))
    with pytest.raises(ValueError, match=r"shape \(3, 2\)"):
        model.init(np.zeros((2, 3)))
    # one NaN made its pixel, and every log-likelihood after it, NaN for good
    with pytest.raises(ValueError, match=r"data must be finite; data\[1, 0\] is inf"):
        model.init([[0.5, 0.5], [np.inf, 0.5], [0.5, 0.5]])
    model.init(np.full((3, 2), 0.5))
    with pytest.raises(ValueError, match=r"data must be finite; data\[2, 1\] is nan"):
        model.update([[0.5, 0.5], [0.5, 0.5], [0.5, np.nan]])
    assert np.isfinite(model.log_likelihood(np.full((3, 2), 0.5)))


def textured_scene(T=40, occlude=range(15, 25), seed=3):
    """A textured 30 x 40 target moving 2.5 px/frame right and 1 px/frame down over a textured
    background; a flat grey bar covers its left half in the ``occlude`` frames."""
    import cv2

    rng = np.random.default_rng(seed)
    bg = cv2.GaussianBlur(rng.integers(0, 255, (200, 260)).astype(np.float32), (0, 0), 2)
    tex = cv2.GaussianBlur(rng.integers(0, 255, (40, 30)).astype(np.float32), (0, 0), 1.5)
    tex = (tex - tex.mean()) * 3 + 128
    frames, boxes, bars = [], [], []
    for t in range(T):
        x, y = 40 + 2.5 * t, 50 + 1.0 * t
        img = bg.copy()
        xi, yi = int(round(x)), int(round(y))
        img[yi:yi + 40, xi:xi + 30] = tex
        bar = None
        if t in occlude:
            bar = (xi, yi - 10, 15, 60)
            img[yi - 10:yi + 50, xi:xi + 15] = 90
        frames.append(np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8))
        boxes.append([xi, yi, 30, 40])
        bars.append(bar)
    return frames, np.array(boxes, float), bars


def test_tracker_follows_a_target_through_an_occlusion_and_ownership_drops_there():
    frames, boxes, bars = textured_scene()
    tr = WSLTracker(size=32, radius=6)
    tr.init(frames[0], boxes[0])
    covered, visible = [], []
    for t in range(1, len(frames)):
        box = tr.update(frames[t])
        err = np.abs((box[:2] + box[2:] / 2) - (boxes[t, :2] + boxes[t, 2:] / 2)).max()
        assert err <= 1.5, (t, err)
        o = tr.ownership
        covered.append(o[0][:, : tr.vw // 2 - 1].mean())     # the bar's half of the view
        visible.append(o[0][:, tr.vw // 2 + 2:].mean())
        if bars[t] is not None:
            # the bar is new data: L owns it in its first frame, W (the last frame) after
            first = bars[t - 1] is None
            owner = o[2] if first else o[1]
            assert owner[:, : tr.vw // 2 - 1].mean() > 0.45, t
    covered, visible = np.array(covered), np.array(visible)
    before, during, after = slice(9, 14), slice(14, 24), slice(25, 39)
    assert covered[before].min() > 0.8 and covered[during].max() < 0.4
    assert visible[during].min() > 0.8
    assert covered[after].min() > 0.7
    # the stable mean kept the occluded half's texture: it matches the unoccluded target
    import cv2

    clean = tr._sample(cv2.GaussianBlur(frames[-1].astype(np.float32) / 255, (0, 0), 1.0),
                       *tr.centre, tr.w / tr.vw, tr.vw, tr.vh)
    half = slice(1, tr.vw // 2 - 1)
    assert np.abs(tr.model.mu_s[2:-2, half] - clean[2:-2, half]).mean() < 0.03


@pytest.mark.slow
def test_pets09_person_held_through_an_occlusion_by_another():
    """PETS09-S2L1: person 12 stands while person 13 walks in front of her (frames 157-164).
    The tracked box stays on the annotation, and where person 13's annotated box covers the
    view, the stable component owns less of the data than elsewhere."""
    from vistrack.evaluation import box_iou_xywh
    from vistrack.io import VideoReader, read_mot

    video = need(SHARED / "data" / "opencv-vtest" / "vtest.avi")
    gt = read_mot(need(SHARED / "data" / "mot15" / "PETS09-S2L1" / "gt" / "gt.txt"))
    box_of = {i: {int(f): b for f, b in zip(gt[gt.ids == i].frames, gt[gt.ids == i].boxes)}
              for i in (12, 13)}
    tr, inside, outside = WSLTracker(), [], []
    for frame in VideoReader(video, start=150, stop=185):
        if frame.index == 150:
            tr.init(frame.image, box_of[12][150])
            continue
        box = tr.update(frame.image)
        assert box_iou_xywh(box[None], box_of[12][frame.index][None])[0, 0] > 0.5
        occ = box_of[13].get(frame.index)
        if occ is None:
            continue
        step = tr.w / tr.vw
        x = tr.centre[0] + step * (np.arange(tr.vw) - (tr.vw - 1) / 2)
        y = tr.centre[1] + step * (np.arange(tr.vh) - (tr.vh - 1) / 2)
        mask = (((y >= occ[1]) & (y <= occ[1] + occ[3]))[:, None]
                & ((x >= occ[0]) & (x <= occ[0] + occ[2]))[None, :])
        if mask.mean() > 0.2:
            inside.append(tr.ownership[0][mask].mean())
            outside.append(tr.ownership[0][~mask].mean())
    assert len(inside) >= 4
    assert np.mean(inside) < np.mean(outside) - 0.1


def test_a_long_occlusion_leaves_the_stable_component_where_it_was():
    """120 frames of an occluder (τ = 2): m_s reaches its floor of 1e-12 and stays there, but
    the moments M1, M2 decayed on alone, so μ_s = M1 / m_s fell to 0.000 (a value never
    observed) and the stable component never recovered (m_s = 1e-12 100 frames after the
    target was back). Oracle: the same online EM written in μ_s and E_s[d²] (the weighted
    means of the data S owned, which cannot underflow), with scipy's densities."""
    model = WSLModel((1,), tau=2.0)
    model.init([0.5])
    a = model.alpha
    m, mu, s2, prev = model.m[:, 0].copy(), 0.5, 0.05 ** 2 + 0.25, 0.5
    data = [0.5] * 20 + [0.9] * 120 + [0.5] * 100
    m_s = []
    for d in data:
        model.update([d])
        var = max(s2 - mu * mu, 0.02 ** 2)
        p = m * np.array([norm.pdf(d, mu, np.sqrt(var)), norm.pdf(d, prev, 0.08), 1.0])
        o = p / p.sum()
        raw = a * o + (1 - a) * m
        mu = (a * o[0] * d + (1 - a) * m[0] * mu) / raw[0]
        s2 = (a * o[0] * d * d + (1 - a) * m[0] * s2) / raw[0]
        m = np.maximum(raw, 1e-12)
        m /= m.sum()
        prev = d
        np.testing.assert_allclose(model.mu_s[0], mu, rtol=1e-9)
        np.testing.assert_allclose(model.var_s[0], max(s2 - mu * mu, 0.02 ** 2), rtol=1e-9)
        np.testing.assert_allclose(model.m[:, 0], m, rtol=1e-9, atol=1e-15)
        m_s.append(model.m[0, 0])
    assert m_s[139] == pytest.approx(1e-12)                  # the occluder took the pixel
    assert abs(model.mu_s[0] - 0.5) < 1e-9                    # and left μ_s where it was
    assert min(i for i in range(140, 240) if m_s[i] > 0.5) - 139 <= 25  # back in 21 frames
    assert m_s[-1] > 0.99


def test_mixing_probabilities_and_shape_must_be_finite_and_integral():
    """m0 of NaN or inf passed `(m0 <= 0).any()` and gave NaN likelihoods; a shape of 2.5
    was cut to 2."""
    for m0 in [(np.nan, 0.15, 0.45), (np.inf, 0.15, 0.45), (0.4, 0.15, -np.inf)]:
        with pytest.raises(ValueError, match=r"m0 must be three finite positive mixing "
                                             r"probabilities; got \["):
            WSLModel((2,), m0=m0)
    with pytest.raises(ValueError, match=r"shape must be a tuple of integers; got \(2.5,\)"):
        WSLModel((2.5,))
    assert WSLModel((2.0, np.int64(3))).shape == (2, 3)       # integral values are taken
    model = WSLModel((2,), m0=(2.0, 1.0, 1.0))
    model.init([0.5, 0.5])
    assert np.isfinite(model.log_likelihood([0.5, 0.5]))


def _uniform_object():
    """A 320x240 frame with a large uniform red object, and a 40-pixel box well inside it:
    every window of the search has the same likelihood."""
    im = np.full((240, 320, 3), 128, np.uint8)
    im[60:180, 80:240] = (0, 0, 200)
    return im, np.array([140.0, 100.0, 40.0, 40.0])


def test_equally_likely_windows_keep_the_predicted_box():
    """Where every candidate window is as likely as every other (no texture), the box is the
    prediction. np.argmax took the first window, offset (-r, -r), and the constant-velocity
    prediction added that jump again: the same frame repeated gave [130, 90], [110, 70],
    [83.8, 60], ... against [140, 100] every frame. With scales (0.95, 1, 1.05) the first
    scale, 0.95, won the tie too and the box shrank. Oracle: the documented contract (of
    equally likely offsets the one nearest the prediction; of scales the one nearest 1)."""
    im, box = _uniform_object()
    for scales in [(1.0,), (0.95, 1.0, 1.05)]:
        tr = WSLTracker(scales=scales)
        tr.init(im, box)
        for _ in range(6):
            np.testing.assert_array_equal(tr.update(im), box)
        assert tr.velocity.tolist() == [0.0, 0.0]


def test_without_texture_the_box_goes_on_at_its_velocity():
    """A textured target moving (3, 1) pixels a frame, then frames without texture: the box
    goes on at its last velocity (the prediction, nearest of the equally likely windows),
    not to the first window of the search. Oracle: constant velocity in closed form (a
    32-pixel box: one view pixel is one image pixel, so the search lands on whole pixels)."""
    rng = np.random.default_rng(4)
    tex = (rng.random((32, 32)) * 255).astype(np.uint8)
    tr = WSLTracker(blur=0.0)
    frames = []
    for k in range(6):
        im = np.full((240, 320), 128, np.uint8)
        im[100 + k:132 + k, 100 + 3 * k:132 + 3 * k] = tex
        frames.append(im)
    tr.init(frames[0], [100, 100, 32, 32])
    for k in range(1, 6):
        np.testing.assert_allclose(tr.update(frames[k]), [100 + 3 * k, 100 + k, 32, 32],
                                   atol=1e-9)
    flat = np.full((240, 320), 128, np.uint8)
    for k in range(6, 10):
        np.testing.assert_allclose(tr.update(flat), [100 + 3 * k, 100 + k, 32, 32], atol=1e-9)


def test_a_wsl_trackers_model_settings_are_checked_when_it_is_made():
    """WSLTracker(tau=-1) and WSLTracker(bogus=3) were taken, and failed at init(), on the
    first frame: refused when the tracker is made, as WSLModel refuses them; a setting that
    is no number is a TypeError naming it."""
    for kw, error in (({"tau": -1}, ValueError), ({"bogus": 3}, TypeError),
                      # (a string failed in numpy's isfinite, naming nothing)
                      ({"lost_density": "x"}, TypeError)):
        with pytest.raises(error) as want:
            WSLModel((8, 8), **kw)
        with pytest.raises(error) as got:
            WSLTracker(**kw)
        assert str(got.value) == str(want.value)


def test_the_view_of_a_square_filling_its_box_is_symmetric():
    """The view was sampled at the box's centre taken as a pixel index, half a pixel right
    and down of the box's centre in the pixels' indices (the package's rule, base._HALF):
    the view of a bright square exactly filling its box had a first column of 1.0 and a
    last of 0.31. Now it is the same either way along each axis (the oracle: the square's
    own symmetry)."""
    img = np.zeros((100, 100), np.uint8)
    img[40:60, 30:50] = 255
    tr = WSLTracker(size=32, blur=0)
    tr.init(img, np.array([30.0, 40.0, 20.0, 20.0]))
    view = tr._sample(tr._prepare(img), *tr.centre, tr.w / tr.vw, tr.vw, tr.vh)
    np.testing.assert_allclose(view, view[:, ::-1], atol=1e-9)
    np.testing.assert_allclose(view, view[::-1, :], atol=1e-9)


def test_settings_that_are_no_numbers_are_named():
    """("a", 1, 1) was numpy's "could not convert string to float"; scales=1.0 "'float'
    object is not iterable"; "abc" and [1, None] numpy's or Python's own words."""
    with pytest.raises(ValueError, match=re.escape("m0 must be three finite positive mixing "
                                                   "probabilities; got ('a', 1, 1)")):
        WSLModel((3,), m0=("a", 1, 1))
    for scales in (1.0, "abc", [1, None]):
        with pytest.raises(ValueError, match=re.escape("scales must be one or more finite "
                                                       f"positive numbers; got {scales!r}")):
            WSLTracker(scales=scales)


@pytest.mark.parametrize("w, h", [(3, 100), (100, 3), (4, 60), (60, 2)])
def test_the_view_of_a_long_thin_box_spans_the_box(w, h):
    """The view has at least 4 pixels a side, but one scale served both axes: a 3 x 100
    box was viewed over its central 24 rows alone (the mean of a box bright only at its ends
    0.0 against 0.6), a 100 x 3 one over 12.5 rows. Oracle: the box's own pixels, whose mean
    the view's (bilinear, the view's pixels evenly over the box) must match, and a bar of
    that shape moving 2 pixels a frame along its short side."""
    img = np.zeros((240, 240), np.uint8)
    x, y = 60, 60
    region = img[y:y + h, x:x + w]
    # bright at both ends of the long side only: a fifth of the box at each end
    if h > w:
        region[: h // 5], region[h - h // 5:] = 250, 250
    else:
        region[:, : w // 5], region[:, w - w // 5:] = 250, 250
    t = WSLTracker(blur=0.0)
    t.init(img, [x, y, w, h])
    g = t._prepare(img)
    view = t._sample(g, *t.centre, t.w / t.vw, t.vw, t.vh)
    assert view.mean() == pytest.approx(g[y:y + h, x:x + w].mean(), rel=0.15)
    # a bar of the box's shape, moving across its short side
    bar = lambda k: np.pad(np.full((h, w), 200, np.uint8),  # noqa: E731
                           ((y + (2 * k if w > h else 0), 240 - h - y - (2 * k if w > h else 0)),
                            (x + (2 * k if h > w else 0), 240 - w - x - (2 * k if h > w else 0))),
                           constant_values=20)
    t = WSLTracker()
    t.init(bar(0), [x, y, w, h])
    for k in range(1, 6):
        box = t.update(bar(k))
    want = [x + (10 if h > w else 0), y + (10 if w > h else 0)]
    assert np.abs(box[:2] - want).max() <= 1.0, (box, want)


def test_anchored_to_a_box_of_another_shape_the_view_spans_it():
    """A view of square pixels anchored to a box of another shape was scaled by the box's
    width alone: anchored from 20 x 20 to 20 x 40 it spanned 20 x 20, the box's upper half
    (a view of a side raised to 4 was rescaled, and spanned its box). The oracle: the view's
    rows span the box's height, and its mean is the box's own pixels'; the same shape
    anchored again keeps its square pixels."""
    img = np.zeros((120, 120), np.uint8)
    img[70:90, 50:70] = 250  # the lower half of the 20 x 40 box at (50, 50)
    t = WSLTracker(blur=0.0)
    t.init(img, [50, 50, 20, 20])
    t.anchor([50, 50, 10, 10])  # the same shape: square pixels kept
    assert t.aspect == 1.0
    t.anchor([50, 50, 20, 40])
    assert t.aspect * (t.w / t.vw) * t.vh == pytest.approx(40.0)
    g = t._prepare(img)
    view = t._sample(g, *t.centre, t.w / t.vw, t.vw, t.vh)
    assert view.mean() == pytest.approx(g[50:90, 50:70].mean(), rel=0.1)


def test_a_forgetting_time_too_short_to_remember_a_frame_is_refused():
    """``tau`` 0.02 frames made the update's weight 1 - exp(-1 / tau) exactly 1: a pixel the
    stable component did not own at all took its moments to 0 / 0, NaN for good, and the
    tracker's score to -inf, without a word. The shortest tau accepted keeps finite
    moments through the same data (the equations' oracle: m = o at a weight of 1)."""
    for tau in (0.02, 0.026):
        with pytest.raises(ValueError, match=re.escape(f"tau must be long enough for the "
                                                       f"model to remember a frame, 1 - exp(-1 "
                                                       f"/ tau) < 1 (tau above about 0.027); "
                                                       f"got {tau!r}")):
            WSLModel((1,), tau=tau)
    m = WSLModel((1,), tau=0.0275)
    m.init([0.05])
    m.update([0.05])
    m.update([0.98])
    assert np.isfinite(m.mu_s).all() and np.isfinite(m.var_s).all()


def test_a_start_below_the_stable_components_floor_is_refused():
    """sigma_s0 below sigma_min started the stable component under its own floor (the first
    update then raised it)."""
    with pytest.raises(ValueError, match=r"sigma_s0 must be at least sigma_min.*0\.01 below 0\.02"):
        WSLModel((4, 4), sigma_s0=0.01, sigma_min=0.02)
    m = WSLModel((4, 4), sigma_s0=0.02, sigma_min=0.02)  # equal: the floor itself
    m.init(np.full((4, 4), 0.5))
    np.testing.assert_array_equal(m.var_s, np.full((4, 4), 0.02**2))
    # the floor raised alone: the default start follows it (0.05 below 0.1 is not refused)
    m = WSLModel((4, 4), sigma_min=0.1)
    m.init(np.full((4, 4), 0.5))
    np.testing.assert_array_equal(m.var_s, np.full((4, 4), 0.1**2))
    assert WSLModel((4, 4)).sigma_s0 == 0.05

"""Tracker composition: the fusion against the information form of the Kalman update, the
gate, and colour + shape on a synthetic scene where each alone fails."""

from __future__ import annotations

import re

import numpy as np
import pytest

from vistrack.evaluation.single import overlaps
from vistrack.tracking.compose import Composite
from vistrack.tracking.single import single_tracker


class Fixed:
    """A member that reports given boxes and records where it is anchored."""

    def __init__(self, boxes):
        self.boxes, self.k, self.anchored = [np.asarray(b, float) for b in boxes], 0, []

    def init(self, image, box):
        pass

    def update(self, image):
        self.k += 1
        return self.boxes[self.k - 1]

    def anchor(self, box):
        self.anchored.append(np.asarray(box, float))


def information_fusion(x, P, zs, Rs):
    """The posterior of a Gaussian prior and independent linear measurements, in information
    form: P⁻¹ = P₀⁻¹ + Σ Hᵀ R⁻¹ H, x = P (P₀⁻¹ x₀ + Σ Hᵀ R⁻¹ z)."""
    H = np.zeros((4, 6))
    H[0, 0] = H[1, 1] = H[2, 4] = H[3, 5] = 1
    info, vec = np.linalg.inv(P), np.linalg.inv(P) @ x
    for z, R in zip(zs, Rs):
        info = info + H.T @ np.linalg.inv(R) @ H
        vec = vec + H.T @ np.linalg.inv(R) @ z
    return np.linalg.solve(info, vec)


def z_of(b):
    return np.array([b[0] + b[2] / 2, b[1] + b[3] / 2, np.log(b[2]), np.log(b[3])])


def test_fusion_is_the_information_weighted_combination_and_the_gate_rejects():
    first = np.array([100.0, 50.0, 40.0, 80.0])
    a = Fixed([[104, 52, 40, 80]])
    b = Fixed([[101, 49, 44, 84]])
    far = Fixed([[300, 300, 40, 80]])
    comp = Composite({"a": (a, (0.1, 1.0)), "b": (b, (0.3, 0.05)), "far": (far, (0.1, 0.1))},
                     q_pos=4.0, q_size=1e-3)
    comp.init(None, first)
    x0, P0 = comp.state.mean.copy(), comp.state.cov.copy()
    F, Q = comp._motion()
    box = comp.update(None)
    assert comp.accepted == {"a": True, "b": True, "far": False}
    xp, Pp = F @ x0, F @ P0 @ F.T + Q
    w, h = np.exp(xp[4:])

    def R(pos, size):
        return np.diag([(pos * w) ** 2, (pos * h) ** 2, size ** 2, size ** 2])

    x = information_fusion(xp, Pp, [z_of(a.boxes[0]), z_of(b.boxes[0])],
                           [R(0.1, 1.0), R(0.3, 0.05)])
    np.testing.assert_allclose(comp.state.mean, x, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(box, [x[0] - np.exp(x[4]) / 2, x[1] - np.exp(x[5]) / 2,
                                     np.exp(x[4]), np.exp(x[5])], rtol=1e-12)
    # every member, the one rejected too, started the frame from the predicted box
    pred = [xp[0] - w / 2, xp[1] - h / 2, w, h]
    for m in (a, b, far):
        np.testing.assert_allclose(m.anchored[-1], pred)


def test_members_are_checked():
    with pytest.raises(ValueError, match="at least one"):
        Composite({})
    class NoAnchor:
        def init(self, image, box): ...

        def update(self, image): ...

    with pytest.raises(TypeError, match=r"members\['x'\] has no anchor"):
        Composite({"x": (NoAnchor(), (0.1, 0.1))})
    with pytest.raises(ValueError, match=r"members\['x'\] must be"):
        Composite({"x": Fixed([])})
    with pytest.raises(ValueError, match="gate"):
        Composite({"x": (Fixed([]), (0.1, 0.1))}, p_gate=1.0)
    # a string or None was a bare "'<' not supported", an array numpy's "ambiguous"
    for p in ("0.99", None, np.array([0.9, 0.9])):
        with pytest.raises(ValueError, match=re.escape("p_gate must be a probability in (0, 1); "
                                                       f"got {p!r}")):
            Composite({"x": (Fixed([]), (0.1, 0.1))}, p_gate=p)
    with pytest.raises(TypeError, match="members must be a mapping of names to"):
        Composite([("x", (Fixed([]), (0.1, 0.1)))])
    # each failed at the first update, naming q, Q or R, not the setting
    for kw, message in (({"q_pos": -16.0}, "q_pos must be a finite number >= 0; got -16.0"),
                        ({"q_size": np.nan}, "q_size must be a finite number >= 0; got nan")):
        with pytest.raises(ValueError, match=re.escape(message)):
            Composite({"x": (Fixed([]), (0.1, 0.1))}, **kw)
    for noise in ((np.inf, 1.0), ("a", 1), (True, 1)):  # ("a" a bare TypeError, True 1.0)
        with pytest.raises(ValueError, match=re.escape(
                f"members['x']: noise must be two positive, finite numbers; got {noise!r}")):
            Composite({"x": (Fixed([]), noise)})


def growing_ellipse_scene(T=30, seed=0):
    """A red ellipse on a grey-green ground, moving 11 px a frame and growing from 18 x 14 to
    41 x 32 px semi-axes; ``(frames, boxes)``."""
    import cv2

    rng = np.random.default_rng(seed)
    frames, boxes = [], []
    for t in range(T):
        cx, cy, a = 40 + 11 * t, 120 + 2 * t, 18 + 0.8 * t
        b = 0.78 * a
        img = np.empty((260, 420, 3), np.float64)
        img[:] = (110, 125, 110)
        cv2.ellipse(img, (int(round(cx * 16)), int(round(cy * 16))),
                    (int(round(a * 16)), int(round(b * 16))), 0, 0, 360, (40, 40, 200), -1,
                    cv2.LINE_AA, 4)
        img += rng.normal(0, 4, img.shape)
        frames.append(np.clip(img, 0, 255).astype(np.uint8))
        boxes.append([cx - a, cy - b, 2 * a, 2 * b])
    return frames, np.array(boxes)


def test_colour_and_shape_hold_where_colour_and_the_free_snake_fail():
    """Mean shift keeps its window's size as the ellipse doubles; the free snake's radial
    search (10 px) cannot follow 11 px a frame; composed, colour gives the centre and the
    snake the size. The snake in its affine shape space (the default) follows alone: the
    edges within reach place all six of its parameters."""
    from vistrack.tracking.snake import SnakeTracker

    frames, truth = growing_ellipse_scene()

    def run(tracker):
        tracker.init(frames[0], truth[0])
        return np.array([truth[0]] + [tracker.update(f) for f in frames[1:]])

    colour = overlaps(run(single_tracker("meanshift")), truth)
    assert colour[-5:].max() < 0.5          # the right place, the first size
    free = overlaps(run(SnakeTracker(shape="free")), truth)
    assert free[-5:].max() < 0.3            # lost
    assert overlaps(run(single_tracker("snake")), truth).min() > 0.7
    for shape in (SnakeTracker(shape="free"), single_tracker("snake")):
        both = overlaps(run(Composite({"colour": (single_tracker("meanshift"), (0.1, 1.0)),
                                       "shape": (shape, (0.2, 0.05))})), truth)
        assert both.min() > 0.75


@pytest.mark.parametrize("method", ["colour", "meanshift", "camshift", "particle", "template",
                                    "klt", "wsl", "snake"])
def test_anchor_moves_each_tracker_to_the_box(method):
    """The target jumps 60 px, beyond every tracker's reach; anchored on its new box, each
    tracker finds it there."""
    frames, truth = growing_ellipse_scene(T=2)
    jumped = frames[0].copy()
    jumped[:, 60:] = frames[0][:, :-60]
    jumped[:, :60] = frames[0][:, :60].mean((0, 1)).astype(np.uint8)
    moved = truth[0] + [60, 0, 0, 0]
    tracker = single_tracker(method)
    tracker.init(frames[0], truth[0])
    tracker.anchor(moved)
    box = tracker.update(jumped)
    assert overlaps(box[None], moved[None])[0] > 0.7


@pytest.mark.parametrize(("method", "speed"), [("klt", 5), ("klt", 8), ("template", 8)])
def test_a_member_that_measures_motion_follows_a_constant_velocity_target(method, speed):
    """A textured square moving ``speed`` pixels a frame (the truth known): a composite of
    one median-flow (or template) member stays within a pixel of it, as the member alone
    does. Anchored on the prediction alone, the member added each frame's motion twice: the
    klt composite ran to 110 where the square was at 60, and the template one was lost at 8
    pixels a frame."""
    import cv2

    rng = np.random.default_rng(1)
    tex = cv2.normalize(cv2.GaussianBlur(rng.integers(0, 256, (30, 30, 3)).astype(np.float32),
                                         (0, 0), 1.5), None, 0, 255,
                        cv2.NORM_MINMAX).astype(np.uint8)

    def image(x):
        im = np.full((200, 400, 3), (40, 120, 40), np.uint8)
        im[80:110, x:x + 30] = tex
        return im

    alone = single_tracker(method)
    alone.init(image(20), [20, 80, 30, 30])
    comp = Composite({method: (single_tracker(method), (0.1, 0.1))})
    comp.init(image(20), [20, 80, 30, 30])
    for k in range(1, 12):
        x = 20 + speed * k
        assert abs(alone.update(image(x))[0] - x) < 0.5
        assert abs(comp.update(image(x))[0] - x) < 1.0


def test_a_member_box_of_another_shape_is_named():
    """A member whose `update` returns (1, 4) (or a box and a score) was rejected on every
    frame as if it had failed, and the composite followed its own prediction without a
    word; a NaN box is still a failure."""
    img = np.zeros((60, 80, 3), np.uint8)
    c = Composite({"a": (Fixed([[[32.0, 20, 10, 10]]]), (0.1, 0.1))})
    c.init(img, np.array([30.0, 20, 10, 10]))
    with pytest.raises(ValueError, match=re.escape(
            "members['a'].update returned shape (1, 4); expected one box x, y, w, h, (4,)")):
        c.update(img)
    c = Composite({"a": (Fixed([[np.nan] * 4]), (0.1, 0.1))})
    c.init(img, np.array([30.0, 20, 10, 10]))
    c.update(img)
    assert c.accepted == {"a": False}
    # a box of no width is a failure too, said in a plain bool (np.False_ before)
    c = Composite({"a": (Fixed([[32.0, 20, 0, 10]]), (0.1, 0.1))})
    c.init(img, np.array([30.0, 20, 10, 10]))
    c.update(img)
    assert c.accepted == {"a": False} and type(c.accepted["a"]) is bool


def _scene(x=30):
    im = np.full((60, 80, 3), (40, 120, 40), np.uint8)
    im[20:40, x:x + 20] = (0, 0, 255)
    return im


def test_a_refused_start_leaves_every_member_as_it_was():
    """A frame refused by the colour member (BGRA, which the template member takes) left
    the template member started on it (its box and template cut from the refused frame)
    while the composite kept its old state: all members start, or none does."""
    template, colour = single_tracker("template"), single_tracker("colour")
    c = Composite({"t": (template, (4.0, 0.1)), "c": (colour, (4.0, 0.1))})
    c.init(_scene(), [30, 20, 20, 20])
    before = {k: v.copy() if isinstance(v, np.ndarray) else v
              for k, v in template.__dict__.items()}
    bgra = np.zeros((60, 80, 4), np.uint8)
    with pytest.raises(ValueError, match=r"C in \(1, 3\); got shape \(60, 80, 4\)"):
        c.init(bgra, [5, 5, 30, 30])
    for k, v in before.items():
        got = template.__dict__[k]
        if isinstance(v, np.ndarray):
            np.testing.assert_array_equal(got, v)
    np.testing.assert_array_equal(template.box, [30, 20, 20, 20])
    # the oracle: a composite never given the refused frame gives the same boxes after
    fresh = Composite({"t": (single_tracker("template"), (4.0, 0.1)),
                       "c": (single_tracker("colour"), (4.0, 0.1))})
    fresh.init(_scene(), [30, 20, 20, 20])
    for x in (33, 36):
        np.testing.assert_array_equal(c.update(_scene(x)), fresh.update(_scene(x)))


def test_one_tracker_listed_twice_is_refused():
    """One instance under two names was updated twice a frame (a MedianFlow's second
    update saw no motion and counted the first's box twice)."""
    ms = single_tracker("meanshift")
    with pytest.raises(ValueError, match=r"members\['b'\] is the tracker of members\['a'\]"):
        Composite({"a": (ms, (4.0, 0.1)), "b": (ms, (4.0, 0.1))})

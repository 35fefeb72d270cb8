"""Snakes: the B-spline basis against scipy, and contours tracking shapes with known
boundaries."""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.interpolate import BSpline

from vistrack.tracking.snake import Snake, bspline_matrix


def test_bspline_basis_equals_scipy():
    """The periodic uniform cubic B-spline and its derivative, against scipy's BSpline on
    the periodically extended control points."""
    rng = np.random.default_rng(0)
    for n, m in ((4, 9), (7, 21), (20, 100)):
        Q = rng.normal(size=(n, 2))
        s = np.arange(m) * n / m
        spl = BSpline(np.arange(-3, n + 4, dtype=float), Q[(np.arange(n + 3) - 1) % n], 3)
        np.testing.assert_allclose(bspline_matrix(n, m) @ Q, spl(s), atol=1e-12)
        np.testing.assert_allclose(bspline_matrix(n, m, derivative=True) @ Q,
                                   spl.derivative()(s), atol=1e-12)
    with pytest.raises(ValueError, match="n >= 4"):
        bspline_matrix(3, 10)


def ellipse_frame(cx, cy, a, b, angle, shape=(240, 320), rng=None):
    """A filled ellipse rendered exactly: each pixel's coverage from 4 x 4 sub-samples
    (pixel (i, j) covers [j - 0.5, j + 0.5] x [i - 0.5, i + 0.5])."""
    sub = (np.arange(4) + 0.5) / 4 - 0.5
    y, x = np.mgrid[0:shape[0], 0:shape[1]].astype(float)
    t = np.radians(angle)
    cover = np.zeros(shape)
    for dy in sub:
        for dx in sub:
            u = (x + dx - cx) * np.cos(t) + (y + dy - cy) * np.sin(t)
            v = -(x + dx - cx) * np.sin(t) + (y + dy - cy) * np.cos(t)
            cover += (u / a) ** 2 + (v / b) ** 2 <= 1
    im = 60 + 140 * cover / 16
    if rng is not None:
        im = im + rng.normal(0, 4, shape)
    return np.clip(np.round(im), 0, 255).astype(np.uint8)


def distance_to_ellipse(pts, cx, cy, a, b, angle):
    # |implicit radius - 1| scaled by the local radius: a close approximation of the distance
    t = np.radians(angle)
    d = pts - [cx, cy]
    u = d[:, 0] * np.cos(t) + d[:, 1] * np.sin(t)
    v = -d[:, 0] * np.sin(t) + d[:, 1] * np.cos(t)
    rho = np.sqrt((u / a) ** 2 + (v / b) ** 2)
    return np.abs(rho - 1) * np.hypot(u, v) / np.maximum(rho, 1e-9)


def test_snake_follows_a_moving_turning_ellipse():
    """An ellipse drifts 2 px a frame, grows and turns, on noise: the contour stays on its
    boundary (mean distance < 0.5 px in every frame)."""
    rng = np.random.default_rng(1)
    s = Snake()
    s.init_circle((100, 120), 30)
    for k in range(40):
        geo = (100 + 2 * k, 120 + np.sin(k / 6) * 10, 40 + k * 0.3, 25, 10 + 2 * k)
        pts = s.track(ellipse_frame(*geo, rng=rng))
        if k >= 5:  # after it has locked on
            assert distance_to_ellipse(pts, *geo).mean() < 0.5
    assert s.found.mean() > 0.9


def test_without_edges_the_contour_holds_its_prediction():
    s = Snake(n_control=12, n_samples=60)
    s.init_circle((80, 60), 20)
    before = s.contour().copy()
    after = s.track(np.full((120, 160), 90, np.uint8))  # a blank frame: no edge anywhere
    assert not s.found.any()
    np.testing.assert_allclose(after, before)
    with pytest.raises(ValueError, match="control_points must have shape \\(12, 2\\)"):
        s.init(np.zeros((5, 2)))


def test_a_snake_started_from_nan_or_a_zero_radius_is_named():
    """A NaN centre or control point tracked an all-NaN contour without an error; a NaN std
    failed in the Kalman update as "H P H' + R is not positive definite"."""
    import re

    s = Snake(n_control=8, n_samples=16)
    with pytest.raises(ValueError, match=re.escape("centre must be two finite numbers, x and "
                                                   "y; got (nan, 60)")):
        s.init_circle((np.nan, 60), 26)
    # one number was a bare IndexError, and a third coordinate was dropped without a word
    for centre in (5, (40, 30, 99)):
        with pytest.raises(ValueError, match=re.escape(f"centre must be two finite numbers, "
                                                       f"x and y; got {centre!r}")):
            s.init_circle(centre, 10)
    with pytest.raises(ValueError, match=re.escape("control_points must be finite; "
                                                   "control_points[0] = [nan, 60.0]")):
        s.init(np.c_[[np.nan, 70, 80, 70, 60, 50, 40, 50], [60, 50, 60, 70, 80, 70, 60, 50]])
    # the B-spline basis of 4.5 control points was a bare TypeError in numpy
    from vistrack.tracking.snake import bspline_matrix
    for n, m in ((4.5, 8), (6, 2.5), (np.nan, 8), (3, 8)):
        with pytest.raises(ValueError, match=re.escape(
                f"need n >= 4 control points and m >= 1 samples, whole numbers; got n={n}, "
                f"m={m}")):
            bspline_matrix(n, m)
    np.testing.assert_array_equal(bspline_matrix(6.0, 12.0), bspline_matrix(6, 12))
    with pytest.raises(ValueError, match="std must be a finite number > 0; got nan"):
        s.init_circle((80, 60), 26, std=np.nan)
    with pytest.raises(ValueError, match="radius must be a finite number > 0; got 0"):
        s.init_circle((80, 60), 0)


@pytest.mark.parametrize("setting, message", [
    (dict(search=-1), "search must be a whole number >= 1 (pixels each way along a normal); "
                      "got -1"),
    (dict(min_edge=np.nan), "min_edge must be a finite number >= 0; got nan"),
    (dict(n_control=4.7), "n_control must be a whole number >= 4 (control points of a closed "
                          "B-spline); got 4.7"),
    (dict(n_control=3), "n_control must be a whole number >= 4"),
    (dict(q=np.inf), "q must be a finite number > 0; got inf"),
    (dict(r=0), "r must be a finite number > 0; got 0"),
    (dict(shape="similarity"), "shape must be one of 'affine', 'euclidean', 'free'; got "
                               "'similarity'"),
])
def test_a_snakes_settings_are_named_when_it_is_made(setting, message):
    """A search of -1 or a min_edge of NaN gave a snake that never moved, n_control 4.7 was
    cut to 4, 3 was named as ``n``, and an infinite q failed at the first update naming
    ``Q``; each is now named by the tracker's own setting when it is made, as the other
    trackers' are."""
    from vistrack.tracking.snake import SnakeTracker

    for make in (Snake, SnakeTracker):
        with pytest.raises(ValueError, match="^" + re.escape(message)):
            make(**setting)


def _disc(H, W, cx, cy, r, ss=16):
    """A disc's coverage of each pixel, by 16 x 16 samples a pixel (pixel k spans [k, k + 1),
    a box's coordinates)."""
    ys, xs = (np.arange(H * ss) + 0.5) / ss, (np.arange(W * ss) + 0.5) / ss
    inside = (xs[None] - cx) ** 2 + (ys[:, None] - cy) ** 2 <= r * r
    return inside.astype(float).reshape(H, ss, W, ss).mean((1, 3))


@pytest.mark.parametrize("cx,cy", [(80.0, 60.0), (80.5, 60.25)])
def test_the_snakes_box_is_the_objects_not_half_a_pixel_before_it(cx, cy):
    """The contour lies in the pixels' indices (pixel k's centre at k) and its bounding box
    was reported as a box's coordinates (pixel k spans [k, k + 1)): half a pixel up and to
    the left of the object. Oracle: a disc drawn by its exact coverage of each pixel, its
    box ``cx - r, cy - r, 2r, 2r``, the snake started on that box and given the frame
    again."""
    from vistrack.tracking.snake import SnakeTracker

    im = (_disc(120, 160, cx, cy, 30.0) * 255).round().astype(np.uint8)
    t = SnakeTracker()
    t.init(im, [cx - 30, cy - 30, 60, 60])
    for _ in range(10):
        box = t.update(im)
    np.testing.assert_allclose(box[:2] + box[2:] / 2, [cx, cy], atol=0.05)
    np.testing.assert_allclose(box[2:], [60, 60], atol=0.3)
    t.anchor([40, 30, 30, 20])  # and a box given is the contour's box
    np.testing.assert_allclose(t._bounds(), [40, 30, 30, 20], atol=1e-9)


def _square(x, y, size=(480, 480)):
    im = np.full(size, 30, np.uint8)
    im[y:y + 20, x:x + 20] = 220
    return im


@pytest.mark.parametrize("shape", ["affine", "euclidean"])
@pytest.mark.parametrize("v", [(3, 0), (0, 3), (3, 2), (-3, 2), (3, 3), (-2, -3)])
def test_a_shape_space_snake_keeps_a_moving_squares_box(shape, v):
    """Free control points slide along the contour unseen by the edges (each measures only
    along its normal): on a 20 px square moving (3, 2) px a frame the free snake's box was 11
    to 34 px too tall after 20 frames (by where it started) and 165 px off after 60. In a
    shape space, with the template fitted to the first frame, every side of the box stays
    within one frame's motion of the square's (oracle: the square drawn; a random walk lags
    a moving object by less than its step) over 60 frames, whichever way it moves, and it
    does not drift: the last 20 frames err by at most half a pixel more than the 20 before
    (the free snake: 60 px more)."""
    from vistrack.tracking.snake import SnakeTracker

    x0, y0 = 200 - 40 * np.sign(v[0]), 200 - 40 * np.sign(v[1])
    t = SnakeTracker(n_control=12, n_samples=60, shape=shape)
    t.init(_square(x0, y0), [x0, y0, 20, 20])
    err = [np.abs(t.update(_square(x0 + v[0] * k, y0 + v[1] * k))
                  - [x0 + v[0] * k, y0 + v[1] * k, 20, 20]).max() for k in range(1, 61)]
    assert max(err) < np.hypot(*v)
    assert max(err[40:]) < max(err[20:40]) + 0.5


def test_the_shape_spaces_are_the_maps_they_name():
    """``Q = Q₀ + W X``: the affine parameters move the template's control points by
    ``x = tx + c + (1 + a) x₀ + b y₀``, ``y = ty + c + c' x₀ + (1 + d) y₀`` about its centre,
    the Euclidean ones by a rotation and scale, the free ones each point by its own (oracle:
    the maps written out)."""
    rng = np.random.default_rng(3)
    Q0 = rng.normal(50, 10, (8, 2))
    c = Q0.mean(0)
    p0 = Q0 - c
    X = rng.normal(0, 0.1, 6) * [10, 10, 1, 1, 1, 1]
    tx, ty, a, b, cc, d = X
    from vistrack.types import Gaussian
    for shape, want in (
            ("affine", np.c_[tx + c[0] + (1 + a) * p0[:, 0] + b * p0[:, 1],
                             ty + c[1] + cc * p0[:, 0] + (1 + d) * p0[:, 1]]),
            ("euclidean", np.c_[tx + c[0] + (1 + a) * p0[:, 0] - b * p0[:, 1],
                                ty + c[1] + b * p0[:, 0] + (1 + a) * p0[:, 1]]),
            ("free", None)):
        s = Snake(n_control=8, n_samples=16, shape=shape)
        s.init(Q0)
        np.testing.assert_allclose(s.control_points, Q0, atol=1e-12)
        dim = {"affine": 6, "euclidean": 4, "free": 16}[shape]
        assert s.state.mean.shape == (dim,)
        x = X[:dim] if shape != "free" else np.r_[X[0].repeat(4), X[2].repeat(4),
                                                  X[1].repeat(4), X[3].repeat(4)]
        if shape == "free":
            want = Q0 + np.c_[x[:8], x[8:]]
        s.state = Gaussian(x, s.state.cov)
        np.testing.assert_allclose(s.control_points, want, atol=1e-12)
        np.testing.assert_allclose(s.contour(), bspline_matrix(8, 16) @ want, atol=1e-12)
        # move_to takes the template about the points given, the covariance kept
        P = s.state.cov.copy()
        s.move_to(Q0 + 5)
        np.testing.assert_allclose(s.control_points, Q0 + 5, atol=1e-12)
        np.testing.assert_array_equal(s.state.cov, P)
        assert not s.state.mean.any()


def test_process_noise_is_the_documented_variance_in_every_shape_space():
    """``q`` is each control point's variance per frame for free points and translations,
    and ``q / ρ²`` for a linear parameter (``ρ²`` the template's mean squared distance from
    its centre), so that the linear part's noise moves each coordinate by ``q`` on average
    (oracle: the mean over the coordinates of the prediction's variance, ``W P Wᵀ``, after
    a blank frame, from a start of ``std``² per coordinate, in closed form)."""
    blank = np.full((120, 160), 90, np.uint8)
    for shape in ("affine", "euclidean", "free"):
        s = Snake(n_control=12, n_samples=60, q=4.0, shape=shape)
        s.init_circle((80, 60), 20, std=1.0)
        s.track(blank)
        var = np.einsum("ij,jk,ik->i", s._W, s.state.cov, s._W)
        # translation alone: q + std² at every coordinate; the linear parameters add as
        # much again on average (each coordinate's two terms: x₀² and y₀², over ρ²)
        lin = var.mean() - (4.0 + 1.0)
        assert lin == pytest.approx(0.0 if shape == "free" else 4.0 + 1.0, rel=1e-9, abs=1e-9)


def test_the_trackers_settle_is_named():
    from vistrack.tracking.snake import SnakeTracker

    with pytest.raises(ValueError, match=re.escape(
            "settle must be a whole number >= 0 (frames the free snake fits the first "
            "frame); got -1")):
        SnakeTracker(settle=-1)


@pytest.mark.parametrize("shape", ["affine", "euclidean"])
def test_a_template_on_one_line_is_named(shape):
    """Control points all in one place gave linear parameters whose noise grew by 4e12 a
    frame, and on one line a contour no linear map thickens; a shape space names them."""
    s = Snake(n_control=6, n_samples=12, shape=shape)
    msg = re.escape(f"control_points lie on one line, which shape={shape!r} cannot turn into "
                    f"a contour; give points around an area, or shape='free'")
    for Q in (np.full((6, 2), 40.0), np.c_[np.arange(6.0), 2 * np.arange(6.0) + 1]):
        with pytest.raises(ValueError, match=msg):
            s.init(Q)
    Snake(n_control=6, n_samples=12, shape="free").init(np.full((6, 2), 40.0))


def test_a_refused_move_leaves_the_snake_as_it_was():
    """The shape space's base was set before the check that the points make a contour, so
    a refused init, move_to or anchor left the old map about the new, flat points: the
    tracker followed a flat line after its error, and anchor's error named control points
    its caller never gave. The oracle: the contour before the refused call."""
    from vistrack.tracking.snake import SnakeTracker

    img = np.zeros((120, 160), np.uint8)
    img[40:90, 60:110] = 200
    t = SnakeTracker(n_control=8, n_samples=32)
    t.init(img, [50, 30, 60, 60])
    before = t.snake.contour().copy()
    box = t.box.copy()
    with pytest.raises(ValueError, match=re.escape("box [50.0, 60.0, 60.0, 1e-07] is too flat "
                                                   "for the snake (shape='affine'): the control "
                                                   "points moved to it lie on one line")):
        t.anchor([50, 60, 60, 1e-7])
    flat = np.c_[np.linspace(0, 10, 8), np.zeros(8)]
    for call in (lambda: t.snake.move_to(flat), lambda: t.snake.init(flat)):
        with pytest.raises(ValueError, match="control_points lie on one line"):
            call()
    np.testing.assert_array_equal(t.snake.contour(), before)
    np.testing.assert_array_equal(t.box, box)


def test_an_edge_at_the_last_row_or_column_is_found_as_at_the_first():
    """Samples on the last pixel centres were left out where the first's were taken: an
    edge between the last two columns or rows was placed half a pixel inside, at half its
    step (a 30-level step, under twice min_edge, was missed there alone). The oracle: the
    edges drawn at 0.5 and 58.5, found alike on all four sides."""
    img = np.full((60, 60), 100, np.uint8)
    img[:, 0] = img[:, -1] = img[0, :] = img[-1, :] = 130  # steps of 30 at 0.5 and 58.5
    from vistrack.tracking.snake import _radial_search

    pts = np.array([[1.5, 30.0], [57.5, 30.0], [30.0, 1.5], [30.0, 57.5]])
    normals = np.array([[-1.0, 0], [1, 0], [0, -1], [0, 1]])
    found, ok = np.zeros((4, 2)), np.zeros(4, bool)
    _radial_search(img.astype(np.float32), pts, normals, 3, 20.0, found, ok)
    assert ok.all()
    np.testing.assert_allclose(found, [[0.5, 30], [58.5, 30], [30, 0.5], [30, 58.5]])


def test_a_snake_needs_three_samples_and_names_its_arguments():
    """n_samples 1 or 2 was taken, and a snake whose update needs edges at 3 never moved;
    bspline_matrix said "got n=6" for the string '6', and took derivative="no" as true;
    ``found``, documented, did not exist before a frame; min_edge is strict, as said."""
    for m in (1, 2):
        with pytest.raises(ValueError, match=r"^n_samples must be a whole number >= 3"):
            Snake(n_control=8, n_samples=m)
    with pytest.raises(ValueError, match=re.escape("got n='6', m=5")):
        bspline_matrix("6", 5)
    with pytest.raises(TypeError, match="derivative"):
        bspline_matrix(6, 5, derivative="no")
    s = Snake(n_control=8, n_samples=16)
    assert s.found.tolist() == [False] * 16
    np.testing.assert_allclose(bspline_matrix(6, 5, derivative=True).sum(1), 0, atol=1e-15)
    # 1 and 0 as before
    np.testing.assert_array_equal(bspline_matrix(6, 5, derivative=1),
                                  bspline_matrix(6, 5, derivative=True))
    np.testing.assert_array_equal(bspline_matrix(6, 5, derivative=0), bspline_matrix(6, 5))


@pytest.mark.parametrize("call, error, said", [
    (lambda s: s.init([[True, False]] * 8), TypeError, "control_points must be x, y"),
    (lambda s: s.init([["10", "0"]] * 8), TypeError, "control_points must be x, y"),
    (lambda s: s.init(np.full((8, 2), 1 + 1j)), TypeError, "control_points must be real"),
    (lambda s: s.init(np.ma.masked_array(np.arange(16.0).reshape(8, 2),
                                         mask=np.eye(8, 2, dtype=bool))),
     ValueError, "control_points must be finite; control_points[0] = [nan, 1.0]"),
    (lambda s: s.init_circle((True, 60), 26), TypeError, "centre must be x and y"),
])
def test_control_points_that_are_no_coordinates_are_named(call, error, said):
    """Booleans and text were read as numbers (a 1 x 1 square of 0s and 1s), complex
    points as their real parts, a masked array's hidden points as data, and a centre of
    True as x = 1: the package's numeric rules, each named."""
    with pytest.raises(error, match=re.escape(said)):
        call(Snake(n_control=8, n_samples=16))

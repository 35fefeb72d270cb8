"""Motion and measurement models against closed forms and a Van Loan matrix-exponential oracle."""

import re

import numpy as np
import pytest
from scipy.linalg import expm

from vistrack.filters import kalman_filter
from vistrack.models import (
    BoxMotion,
    ConstantAcceleration,
    ConstantPosition,
    ConstantVelocity,
    LinearGaussian,
    LinearMeasurement,
    LinearMotion,
    Periodic,
    Position,
    SwitchingLinearSystem,
)


def van_loan(A, G, q, dt):
    """Exact discretisation of dx = A x dt + G dw, E[dw dw'] = q dt (Van Loan, 1978)."""
    n = A.shape[0]
    M = np.zeros((2 * n, 2 * n))
    M[:n, :n] = -A
    M[:n, n:] = G @ G.T * q
    M[n:, n:] = A.T
    E = expm(M * dt)
    F = E[n:, n:].T
    return F, F @ E[:n, n:]


def integrator(order, dim):
    k = order + 1
    A1 = np.eye(k, k, 1)
    G1 = np.zeros((k, 1))
    G1[-1] = 1
    return np.kron(A1, np.eye(dim)), np.kron(G1, np.eye(dim))


@pytest.mark.parametrize("cls,order",
                         [(ConstantPosition, 0), (ConstantVelocity, 1), (ConstantAcceleration, 2)])
@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("dt", [0.04, 1.0, 2.5])
def test_kinematic_models_equal_van_loan(cls, order, dim, dt):
    model = cls(dim=dim, q=0.7)
    A, G = integrator(order, dim)
    F, Q = van_loan(A, G, 0.7, dt)
    np.testing.assert_allclose(model.F(dt), F, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(model.Q(dt), Q, rtol=1e-9, atol=1e-14)
    assert model.ndim_state == dim * (order + 1)


@pytest.mark.parametrize("omega", [0.5, 1.0, 3.0])
@pytest.mark.parametrize("dt", [0.1, 1.3])
def test_periodic_exact_equals_van_loan(omega, dt):
    model = Periodic(dim=1, omega=omega, q=0.3)
    A = np.array([[0.0, 1.0], [-(omega**2), 0.0]])
    F, Q = van_loan(A, np.array([[0.0], [1.0]]), 0.3, dt)
    np.testing.assert_allclose(model.F(dt), F, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(model.Q(dt), Q, rtol=1e-9, atol=1e-14)


def periodic_van_loan_q(omega, q, dt):
    A = np.array([[0.0, 1.0], [-(omega**2), 0.0]])
    return van_loan(A, np.array([[0.0], [1.0]]), q, dt)[1]


@pytest.mark.parametrize("omega,dt", [(1e-8, 1.0), (1e-5, 1.0), (1e-3, 2.0), (0.05, 1.0),
                                      (1.0, 1e-7), (1.0, 1e-4), (3.0, 0.01), (1.0, 0.1),
                                      (1.0, 0.49), (1.0, 0.51)])
def test_periodic_q_is_exact_where_omega_dt_is_small(omega, dt):
    """Q11 = q/ω² (dt/2 - sin(2ωdt)/(4ω)) cancelled for small ω dt: 0 instead of 1/3 at
    ω = 1e-8, dt = 1, and Q not positive semi-definite (smallest eigenvalue -0.207), which
    kalman_filter refused. Oracle: Van Loan's matrix exponential, directly and (accurate for
    any dt) at dt = 1 and frequency ω dt, scaled back: Q(dt; ω) = dt D Q(1; ω dt) D with
    D = diag(dt, 1)."""
    Q = Periodic(dim=1, omega=omega, q=0.7).Q(dt)
    D = np.diag([dt, 1.0])
    np.testing.assert_allclose(Q, dt * D @ periodic_van_loan_q(omega * dt, 0.7, 1.0) @ D,
                               rtol=1e-12, atol=0)
    np.testing.assert_allclose(Q, periodic_van_loan_q(omega, 0.7, dt), rtol=1e-12, atol=0)
    np.linalg.cholesky(Q)  # positive definite for dt > 0
    kalman_filter(np.zeros((3, 1)), F=Periodic(omega=omega).F(dt), Q=Q, H=[[1.0, 0.0]],
                  R=[[1.0]], x0=[0.0, 0.0], P0=np.eye(2))


def test_periodic_q_tends_to_constant_velocity_as_omega_tends_to_zero():
    """As ω → 0 the oscillator is a free particle: Q → q [[dt³/3, dt²/2], [dt²/2, dt]], to
    within O((ω dt)²) = 1e-16 at ω = 1e-8; the frequency need not be representable squared
    or cubed (ω = 1e-200)."""
    for omega in (1e-8, 1e-200):
        for dt in (1e-6, 0.3, 1.0, 40.0):
            np.testing.assert_allclose(Periodic(dim=2, omega=omega, q=0.7).Q(dt),
                                       ConstantVelocity(dim=2, q=0.7).Q(dt), rtol=1e-12,
                                       atol=0)


def test_periodic_f_tends_to_constant_velocity_for_any_small_omega():
    """F's sin(ω dt)/ω lost the step where ω dt is subnormal: 0 instead of 0.3 at
    ω = 5e-324 and dt = 0.3 (ω dt rounds to 0), 0.2999 at ω = 1e-320. Oracle: the free
    particle's F = [[1, dt], [0, 1]], which the oscillator tends to as ω → 0 (each entry
    within (ω dt)² max(dt, 1) of it, below rounding but at ω = 1e-8), and, for ω dt from
    1e-3 to 3, Van Loan's matrix exponential."""
    for omega in (5e-324, 1e-320, 1e-310, 1e-200, 1e-8):
        for dt in (1e-6, 0.3, 1.0, 40.0):
            np.testing.assert_allclose(Periodic(dim=2, omega=omega).F(dt),
                                       ConstantVelocity(dim=2).F(dt), rtol=1e-15,
                                       atol=(omega * max(dt, 1.0)) ** 2 * max(dt, 1.0))
    for omega, dt in ((1e-3, 1.0), (0.5, 1.9), (1.0, 0.999), (1.0, 1.001), (3.0, 1.0)):
        A = np.array([[0.0, 1.0], [-(omega**2), 0.0]])
        np.testing.assert_allclose(Periodic(dim=1, omega=omega).F(dt),
                                   van_loan(A, np.array([[0.0], [1.0]]), 1.0, dt)[0],
                                   rtol=1e-13, atol=1e-15)


def test_periodic_q_of_mixed_steps_is_each_steps():
    """A dt array with steps on both sides of the series' range (2 ω dt < 1 and >= 1) gives
    each step's matrix; its entries are continuous across the switch (at 2 ω dt = 1, the
    closed form is still exact to a few rounding errors)."""
    p = Periodic(dim=1, omega=1.0, q=0.7)
    dts = np.array([0.0, 1e-6, np.nextafter(0.5, 0.0), 0.5, 2.0])
    np.testing.assert_array_equal(p.Q(dts), np.stack([p.Q(d) for d in dts]))
    np.testing.assert_array_equal(p.Q(0.0), np.zeros((2, 2)))
    np.testing.assert_allclose(p.Q(dts[2]), p.Q(dts[3]), rtol=1e-14)
    for d in dts[1:]:
        np.testing.assert_allclose(p.Q(d), periodic_van_loan_q(1.0, 0.7, d), rtol=1e-12, atol=0)


def test_seed_euler_matrices():
    # the slides: periodic u_i = [[1, dt], [-dt, 1]] u_{i-1}; constant acceleration without dt²/2
    np.testing.assert_array_equal(Periodic(discretisation="euler").F(0.1), [[1, 0.1], [-0.1, 1]])
    np.testing.assert_array_equal(
        ConstantAcceleration(dim=1, discretisation="euler").F(0.5),
        [[1, 0.5, 0], [0, 1, 0.5], [0, 0, 1]],
    )
    # forward Euler of the oscillator gains energy every step; the exact one keeps it
    Fe, Fx = Periodic(discretisation="euler").F(0.1), Periodic().F(0.1)
    ue = ux = np.array([1.0, 0.0])
    for _ in range(100):
        ue, ux = Fe @ ue, Fx @ ux
    assert np.hypot(*ux) == pytest.approx(1.0, abs=1e-12)
    assert np.hypot(*ue) == pytest.approx((1 + 0.01) ** 50, rel=1e-9)


def test_dt_array_gives_stacks():
    cv = ConstantVelocity(dim=2, q=0.2)
    dts = np.array([0.5, 1.0, 3.0])
    np.testing.assert_array_equal(cv.F(dts), np.stack([cv.F(d) for d in dts]))
    np.testing.assert_array_equal(cv.Q(dts), np.stack([cv.Q(d) for d in dts]))
    p = Periodic(dim=2)
    assert p.F(dts).shape == (3, 4, 4)


def test_state_layout_matches_seed_2d_example():
    F = ConstantVelocity(dim=2).F(1.0)
    np.testing.assert_array_equal(F, [[1, 0, 1, 0], [0, 1, 0, 1], [0, 0, 1, 0], [0, 0, 0, 1]])
    np.testing.assert_array_equal(Position(dim=2).H(4), np.eye(2, 4))


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda: ConstantVelocity(dim=4), "dim must be 1, 2 or 3; got 4"),
        (lambda: ConstantVelocity(q=-1), "q must be a finite number >= 0"),
        (lambda: ConstantVelocity().F(-0.1), "dt must be finite and >= 0"),
        (lambda: ConstantVelocity().F(np.nan), "dt must be finite"),
        (lambda: Periodic(omega=0), "omega must be a finite number > 0"),
        (lambda: BoxMotion(std_meas=(0.05, 0.05)), r"std_meas must be one number or 4 \(cx, cy"),
        (lambda: BoxMotion(std_meas=(0.05, 0.05, 0.0, 0.05)),
         "std_meas must be a finite number > 0; got 0.0$"),
        (lambda: BoxMotion(frame_rate=0), "frame_rate must be a finite number > 0"),
        (lambda: BoxMotion().at_rate(np.inf), r"frame_rate must be a number from 0.001 to "
                                               r"1e\+06 frames/s; got inf"),
        (lambda: BoxMotion().at_rate(1e-300), "frame_rate must be a number from 0.001"),
        # (NaN and infinity gave such a matrix; a boolean setting was taken as 1)
        (lambda: BoxMotion().F(np.inf), "dt must be a finite number of frames; got inf"),
        (lambda: BoxMotion().F(np.nan), "dt must be a finite number of frames; got nan"),
        (lambda: ConstantAcceleration(discretisation="rk4"), "discretisation must be"),
        (lambda: Position(dim=2, r=0.0), "r must be a finite variance > 0"),
        (lambda: Position(dim=2, r=np.eye(3)), r"r must have shape \(2, 2\)"),
        (lambda: Position(dim=2, r=[[1, 2], [2, 1]]), "r must be positive definite"),
        (lambda: Position(dim=3).H(2), "needs a state of at least 3"),
        (lambda: LinearMotion(np.eye(2), -np.eye(2)), "Q must be positive semi-definite"),
        (lambda: LinearMotion(np.eye(2), [[1, 0.5], [0, 1]]), "Q must be symmetric"),
        (lambda: LinearMotion([[1, np.nan], [0, 1]], np.eye(2)), r"F must be finite; F\[0, 0, 1\]"),
        (lambda: LinearMotion(np.eye(2), np.eye(3)), r"Q must have shape \(2, 2\)"),
        (lambda: LinearMotion(np.eye(2), np.eye(2)).F(0.5), "discrete-time model"),
        (lambda: LinearMeasurement(np.eye(2, 4), np.eye(3)), r"R must have shape \(2, 2\)"),
        (lambda: LinearGaussian(np.eye(4), np.eye(4), np.eye(2, 3), np.eye(2)), "H has 3 columns"),
        (lambda: LinearGaussian(np.stack([np.eye(2)] * 5), np.eye(2), np.stack([np.eye(2)] * 4),
                                np.eye(2)),
         "disagree on the number of steps"),
    ],
)
def test_bad_model_arguments_name_the_argument(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_linear_gaussian_time_varying():
    T = 6
    F = np.stack([np.eye(2) * (1 + 0.1 * t) for t in range(T)])
    model = LinearGaussian(F, np.eye(2), np.eye(1, 2), np.eye(1))
    assert model.n_steps == T
    assert model.F.shape == (T, 2, 2)
    assert model.H.shape == (1, 2)


def test_a_stack_of_one_matrix_is_the_constant_as_kalman_filter_takes_it():
    """F of shape (1, n, n) beside an H of 5 steps: kalman_filter takes the one F for every
    step, where LinearGaussian said "per-step matrices disagree on the number of steps:
    [1, 5]"; its filter now gives kalman_filter's answer on the same matrices."""
    from vistrack.filters import kalman_filter

    rng = np.random.default_rng(2)
    F, Q = np.array([[[1.0, 1.0], [0.0, 1.0]]]), 0.1 * np.eye(2)
    H, R = rng.normal(size=(5, 1, 2)), np.ones((1, 1, 1))
    model = LinearGaussian(F, Q, H, R)
    assert model.n_steps == 5
    ys = rng.normal(size=(5, 1))
    want = kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=np.zeros(2), P0=np.eye(2))
    got = kalman_filter(ys, F=model.F, Q=model.Q, H=model.H, R=model.R, x0=np.zeros(2),
                        P0=np.eye(2))
    np.testing.assert_allclose(got.means, want.means, rtol=1e-12)
    assert LinearMotion(F, np.stack([Q] * 3)).n_steps == 3
    assert LinearMotion(F, Q).n_steps is None


def test_box_measurement_noise_per_value():
    """R is diagonal with each value's standard deviation times the box's width (cx, w) or
    height (cy, h); one number sets all four."""
    boxes = np.array([[50.0, 60.0, 20.0, 40.0], [0.0, 0.0, 10.0, 30.0]])
    m = BoxMotion(std_meas=(0.1, 0.2, 0.3, 0.4))
    expected = (np.array([0.1, 0.2, 0.3, 0.4]) * boxes[:, [2, 3, 2, 3]]) ** 2
    np.testing.assert_allclose(m.R_diag(boxes), expected)
    np.testing.assert_allclose(m.R(boxes), expected[:, :, None] * np.eye(4))
    np.testing.assert_allclose(BoxMotion(std_meas=0.1).R_diag(boxes),
                               (0.1 * boxes[:, [2, 3, 2, 3]]) ** 2)


def test_box_noise_is_the_size_scaled_formula_bit_for_bit():
    """The compiled Q_diag and R_diag give numpy's ``(std * s) ** 2 * dt`` exactly, ``s`` the
    width (x, w) or height (y, h) at least 1e-3, on views and lists too; NaN sizes give NaN."""
    rng = np.random.default_rng(1)
    mean = np.c_[rng.uniform(-100, 1000, (300, 2)), rng.uniform(-1, 400, (300, 2)),
                 rng.normal(0, 5, (300, 4))]
    mean[:4, 2:4] = [[0.0, 1e-4], [1e-3, -5.0], [np.nan, 3.0], [2.0, np.inf]]
    boxes = mean[:, :4]  # a view, as the tracker passes
    for m in (BoxMotion(), BoxMotion().at_rate(7.0), BoxMotion(std_meas=0.07)):
        s = np.tile(np.maximum(boxes[:, 2:4], 1e-3), 2)
        for dt in (1.0, 3.0, 0.5, 1 / 3):
            want = np.concatenate([(m.std_pos * s) ** 2, (m.std_vel * s) ** 2], axis=1) * dt
            assert np.array_equal(m.Q_diag(boxes, dt), want, equal_nan=True)
        assert np.array_equal(m.R_diag(boxes), (m.std_meas * s) ** 2, equal_nan=True)
        assert np.array_equal(m.R_diag(boxes[:5].tolist()), m.R_diag(boxes[:5]),
                              equal_nan=True)
    assert BoxMotion().Q_diag(np.zeros((0, 4))).shape == (0, 8)


@pytest.mark.parametrize("rate", [7.0, 10.0, 14.0, 60.0])
def test_box_motion_at_another_frame_rate_is_the_same_motion_in_time(rate):
    """The noise is a random walk of the position and of the velocity in time: over one
    second, the position variance added, and the velocity variance in pixels per second, are
    the same at any frame rate; a new track's position and velocity (pixels per second)
    start as uncertain; F is the same per frame."""
    box = np.array([[100.0, 200.0, 40.0, 90.0]])
    ref, m = BoxMotion(), BoxMotion().at_rate(rate)
    assert ref.at_rate(30.0) is ref and m.frame_rate == rate
    q_ref, q = ref.Q_diag(box, 30.0), m.Q_diag(box, rate)  # one second of frames
    np.testing.assert_allclose(q[:, :4], q_ref[:, :4])
    np.testing.assert_allclose(q[:, 4:] * rate ** 2, q_ref[:, 4:] * 30.0 ** 2)
    d_ref = np.diagonal(ref.initial(box)[1], axis1=1, axis2=2)
    d = np.diagonal(m.initial(box)[1], axis1=1, axis2=2)
    np.testing.assert_allclose(d[:, :4], d_ref[:, :4])
    np.testing.assert_allclose(d[:, 4:] * rate ** 2, d_ref[:, 4:] * 30.0 ** 2)
    np.testing.assert_array_equal(m.F(2.0), ref.F(2.0))
    np.testing.assert_array_equal(m.R_diag(box), ref.R_diag(box))


@pytest.mark.slow
@pytest.mark.parametrize("bench", ["mot15", "mot17"])
def test_detected_sizes_are_noisier_than_centres(bench):
    """The premise of BoxMotion's default, against ground truth: a detection's width errs by
    more, as a fraction of the width, than its centre's x does, and than its height does as
    a fraction of the height; the height errs by more than the centre's y."""
    from vistrack.association import iou
    from vistrack.io import read_mot

    from .conftest import SHARED, need

    root = need(SHARED / "data" / bench)
    xyxy = (lambda b: np.c_[b[:, :2], b[:, :2] + b[:, 2:]])
    errors = []
    for d in sorted(p for p in root.iterdir() if (p / "gt" / "gt.txt").exists()):
        gt, det = read_mot(d / "gt" / "gt.txt"), read_mot(d / "det" / "det.txt")
        keep = gt.conf != 0
        if bench == "mot17":
            keep &= gt.classes == 1  # pedestrians
        rel = []
        for f in np.unique(det.frames):
            g = gt.boxes[keep & (gt.frames == f)]
            p = det.boxes[(det.frames == f) & (det.conf >= 0.8)]
            if len(g) and len(p):
                ov = iou(xyxy(p), xyxy(g))
                ok = ov.max(axis=1) > 0.5
                p, q = p[ok], g[ov.argmax(axis=1)[ok]]
                centre = (p[:, :2] + p[:, 2:] / 2 - q[:, :2] - q[:, 2:] / 2) / q[:, 2:]
                rel.append(np.c_[centre, p[:, 2:] / q[:, 2:] - 1.0])
        rel = np.concatenate(rel)
        errors.append(rel - np.median(rel, axis=0))  # the sequence's bias is not noise
    cx, cy, w, h = 1.4826 * np.median(np.abs(np.concatenate(errors)), axis=0)
    # measured: MOT15 0.10, 0.039, 0.18, 0.087; MOT17 0.022, 0.014, 0.038, 0.025
    assert w > 1.4 * h and w > 1.4 * cx and h > 1.4 * cy, (cx, cy, w, h)


def test_box_motion_names_boxes_of_the_wrong_shape_and_a_negative_dt():
    """The compiled noise kernel reads 4 values a row unchecked: (2, 3) boxes were read past
    the array's end, a (4,) box failed in numba's typing; a negative dt gave negative
    variances."""
    from vistrack.models import BoxMotion

    m = BoxMotion()
    for bad in (np.ones((2, 3)), np.ones(4), np.ones((1, 5))):
        for call in (m.Q_diag, m.R_diag, m.initial):
            with pytest.raises(ValueError, match=r"boxes must have shape \(K, 4\)"):
                call(bad)
    with pytest.raises(ValueError, match="dt must be a finite number of frames >= 0; got -1"):
        m.Q_diag(np.ones((1, 4)), dt=-1)
    box = np.array([[100, 50, 20.0, 40.0]])
    np.testing.assert_allclose(m.Q_diag(box, dt=2.0), 2 * m.Q_diag(box))
    # a setting of another kind is named (True was taken as 1; a string rate failed in
    # numpy's isfinite)
    with pytest.raises(TypeError, match="std_pos must be a number; got True"):
        BoxMotion(std_pos=True)
    for bad in ("10", None):
        with pytest.raises(TypeError, match=f"frame_rate must be a number; got {bad!r}"):
            m.at_rate(bad)


def test_nonlinear_filters_name_a_linear_model_of_per_step_matrices():
    """A LinearMotion or LinearMeasurement with matrices per step (T, ...) went into the
    adapters of the nonlinear filters as one matrix: f of a (1, n) state came back (1, 1, n),
    h failed in matmul, R was taken for one covariance. Named now, with where they go."""
    from vistrack.models import LinearMeasurement, LinearMotion
    from vistrack.models.adapters import MeasurementFunctions, MotionFunctions

    with pytest.raises(ValueError, match=r"motion has per-step matrices \(3 steps\)"):
        MotionFunctions(LinearMotion(np.stack([np.eye(1), 2 * np.eye(1), 3 * np.eye(1)]),
                                     np.eye(1)))
    with pytest.raises(ValueError, match=r"measurement has per-step matrices \(3 steps\)"):
        MeasurementFunctions(LinearMeasurement(np.ones((3, 1, 2)), np.eye(1)), 2)
    MotionFunctions(LinearMotion(np.eye(2), np.eye(2)))  # constant ones, as before
    MeasurementFunctions(LinearMeasurement(np.ones((1, 2)), np.eye(1)), 2)


@pytest.mark.parametrize("model", [ConstantVelocity(dim=2), ConstantAcceleration(dim=1),
                                   Periodic(omega=0.7)])
def test_f_with_a_time_step_for_each_state_is_each_state_propagated_alone(model):
    """With dt an array, F(dt) is a stack and ``x @ F.T`` transposed the stack's three axes:
    a (2, 2, 2) answer for two states of a 1-D constant velocity, and no error for three
    states against two time steps."""
    rng = np.random.default_rng(0)
    n = model.ndim_state
    x, dt = rng.normal(size=(3, n)), np.array([0.5, 1.0, 2.5])
    want = np.stack([model.F(d) @ xi for xi, d in zip(x, dt)])  # the oracle: one at a time
    np.testing.assert_allclose(model.f(x, dt), want, rtol=0, atol=1e-12)
    np.testing.assert_allclose(model.f(x[0], dt), [model.F(d) @ x[0] for d in dt], atol=1e-12)
    with pytest.raises(ValueError, match=r"x must have one state for each of the 3 time steps"):
        model.f(rng.normal(size=(2, n)), dt)


@pytest.mark.parametrize("call,exc,match", [
    (lambda: ConstantVelocity(q="a"), TypeError, "q must be a number; got 'a'"),
    (lambda: Periodic(omega="a"), TypeError, "omega must be a number; got 'a'"),
    (lambda: ConstantVelocity(dim="2"), ValueError, "dim must be 1, 2 or 3; got '2'"),
    (lambda: SwitchingLinearSystem([ConstantVelocity(dim=1)], Position(dim=1), [[1.0]]).sample(
        -1, x0=[0.0, 0.0], rng=0), ValueError,
     "T must be a whole number >= 0 (a number of steps); got -1"),
])
def test_arguments_that_float_or_numpy_named_no_further_are_named(call, exc, match):
    """float()'s "could not convert string to float", numpy's "negative dimensions are not
    allowed", and a dim of '2' shown as 2."""
    with pytest.raises(exc, match=re.escape(match)):
        call()


def test_psd_sqrt_is_the_principal_root_whatever_basis_lapack_returns():
    """``psd_sqrt`` is the principal square root, which is unique: scipy's ``sqrtm`` of a
    positive definite matrix, ``v v' / |v|`` of a rank-one ``v v'``, ``2 I`` of ``4 I``. Where
    eigenvalues repeat, the eigenvectors LAPACK returns are any basis of their space, and
    vary with the processor; the root must not. Its rows are checked against the same matrix
    given in a rotated basis (``U S U'``, whose root is ``U A U'``), and a seeded simulation's
    measurement noise of ``R = 4 I`` is 2 times the generator's standard normals."""
    from scipy.linalg import sqrtm

    from vistrack.models import psd_sqrt
    from vistrack.simulate import simulate_lgssm

    rng = np.random.default_rng(0)
    Q = ConstantVelocity(dim=2, q=0.5).Q(0.7)  # the x and y blocks: repeated eigenvalues
    M = rng.normal(size=(4, 4))
    for S in (Q, np.eye(3) * 4.0, M @ M.T):
        A = psd_sqrt(S)
        np.testing.assert_allclose(A, A.T, rtol=0, atol=1e-14 * np.abs(S).max())
        np.testing.assert_allclose(A, sqrtm(S).real, rtol=0, atol=1e-10 * np.abs(S).max())
        U = np.linalg.qr(rng.normal(size=S.shape))[0]
        np.testing.assert_allclose(psd_sqrt(U @ S @ U.T), U @ A @ U.T, rtol=0,
                                   atol=1e-10 * np.abs(S).max())
    np.testing.assert_array_equal(psd_sqrt(np.eye(3) * 4.0), np.eye(3) * 2.0)
    v = np.array([1.0, -2.0, 0.5])
    np.testing.assert_allclose(psd_sqrt(np.outer(v, v)), np.outer(v, v) / np.linalg.norm(v),
                               rtol=0, atol=1e-12)
    stack = np.stack([Q, 2 * Q])
    np.testing.assert_allclose(psd_sqrt(stack)[1], np.sqrt(2) * psd_sqrt(Q), rtol=0, atol=1e-12)
    # each step draws the state's noise (none at the first), then the measurement's
    n, T = 2, 50
    xs, ys = simulate_lgssm(T, F=np.eye(n), Q=np.zeros((n, n)), H=np.eye(n),
                            R=4.0 * np.eye(n), x0=np.zeros(n), rng=3)
    np.testing.assert_array_equal(xs, 0.0)
    gen = np.random.default_rng(3)
    want = []
    for t in range(T):
        if t > 0:
            gen.standard_normal((1, n))  # the state's noise, times a zero root
        want.append(2.0 * gen.standard_normal((1, n))[0])
    np.testing.assert_array_equal(ys, np.array(want))


def test_psd_sqrt_keeps_the_noise_of_a_matrix_of_scales_far_apart():
    """A constant-acceleration ``Q`` at ``dt`` 1e-4 (seconds at 10 kHz) has a least
    eigenvalue under the eigendecomposition's rounding of its largest, which the root took
    as 0: the position's sampled variance was 35/36 of ``Q``'s, and at ``dt`` 1e-5 4.7 times
    it on one axis. Oracle: ``A A' = Q`` to rounding, and a seeded simulation's position
    noise against ``Q``'s variance. A matrix whose scales are near one another keeps its
    symmetric root, bit for bit."""
    from vistrack.models import ConstantAcceleration, psd_sqrt
    from vistrack.models.adapters import _principal_root

    for dt in (3e-4, 1e-4, 1e-5):
        Q = ConstantAcceleration(dim=2, q=1.0).Q(dt)
        A = psd_sqrt(Q)
        d = np.sqrt(np.diag(Q))  # each entry against its variances' scale
        np.testing.assert_allclose((A @ A.T) / np.outer(d, d), Q / np.outer(d, d), rtol=0,
                                   atol=1e-9)
    Q = ConstantAcceleration(dim=1, q=1.0).Q(1e-4)
    e = np.random.default_rng(0).standard_normal((400_000, 3)) @ psd_sqrt(Q).T
    assert abs(e[:, 0].var() / Q[0, 0] - 1) < 0.01  # (0.972 before)
    S = np.diag([1e-20, 1.0, 1e20])
    np.testing.assert_allclose(psd_sqrt(S), np.diag([1e-10, 1.0, 1e10]), rtol=1e-15)
    for S in (ConstantAcceleration(dim=2, q=0.5).Q(0.1), np.eye(3) * 4.0,
              np.array([[4.0, 0.0], [0.0, 0.0]])):
        np.testing.assert_array_equal(psd_sqrt(S), _principal_root(*np.linalg.eigh(S)))


@pytest.mark.parametrize("S, message", [
    (np.diag([1.0, -1.0]), "S must be positive semi-definite; S[1, 1] = -1, a negative variance"),
    (np.array([[1.0, 2.0], [2.0, 1.0]]),
     "S must be positive semi-definite; its smallest eigenvalue is -1"),
    (np.array([[1.0, 2.0], [0.0, 1.0]]),
     "S must be symmetric; S[0, 1] = 2.0 but its transpose entry is 0.0"),
    (np.zeros((2, 3)), "S must be square matrices (..., n, n); got shape (2, 3)"),
    (np.array([[np.nan, 0.0], [0.0, 1.0]]), "S must be finite"),
    (np.stack([np.eye(2), np.diag([1.0, -2.0])]),
     "S must be positive semi-definite (matrix [1]); S[1, 1] = -2, a negative variance"),
    (np.stack([np.eye(2), np.array([[1.0, 2.0], [2.0, 1.0]])]),
     "S must be positive semi-definite (matrix [1]); its smallest eigenvalue is -1"),
])
def test_psd_sqrt_refuses_what_has_no_root(S, message):
    """``psd_sqrt`` took any square matrix: ``diag(1, -1)`` gave the root of ``diag(1, 0)``
    (its square is not ``S``), a triangular matrix the root of another (``eigh`` reads one
    triangle), and a (2, 3) array failed in numpy's words. Oracle: ``check_psd``'s rule (no
    eigenvalue below -1e-10 of the largest entry); a semi-definite matrix whose least
    eigenvalue is negative by rounding still has its root, ``A A' = S``. The words are
    ``check_psd``'s, as every covariance's check in the package."""
    from vistrack.models import psd_sqrt

    with pytest.raises(ValueError, match=re.escape(message)):
        psd_sqrt(S)
    U = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    S = U @ np.diag([-1e-12, 1.0, 4.0]) @ U.T  # negative within 1e-10 of the largest entry
    A = psd_sqrt(S)
    np.testing.assert_allclose(A @ A.T, S, rtol=0, atol=1e-11)


def test_psd_sqrt_of_matrices_of_no_entries_is_theirs():
    """The root of a (0, 0) matrix, or of a stack of them, failed in numpy's words ("zero-size
    array to reduction operation maximum"); it is the matrix of no entries itself (A A' = S
    holds vacuously, as scipy's sqrtm gives), and the checks of symmetry and definiteness
    find nothing to refuse in it."""
    from scipy.linalg import sqrtm

    from vistrack._validate import check_psd, check_symmetric
    from vistrack.models import psd_sqrt

    assert sqrtm(np.zeros((0, 0))).shape == (0, 0)
    for shape in ((0, 0), (3, 0, 0)):
        S = np.zeros(shape)
        A = psd_sqrt(S)
        assert A.shape == shape and A is not S
        check_psd(S, "S")
        check_psd(S, "S", strict=True)
        assert check_symmetric(S, "S").shape == shape[:-2] + (1, 1)


def test_model_settings_that_were_cut_or_wrong_are_named():
    """`MotionFunctions.f` with a `dt` for each state reversed the three axes of the F stack
    (states of the wrong shape and values, no error; the model's own `f` is the oracle);
    `NonlinearMotion`'s and `NonlinearMeasurement`'s `ndim_state` 2.5 was cut to 2 and an
    angle index 0.5 to 0; `BoxMotion.Q_diag(dt=True)`, `std_meas` holding True and
    `GrowthMeasurement(r=True)` were taken as 1; strings and arrays failed in numpy's words;
    `Periodic.Q` overflowed for a large `omega`; a switching system with per-step models
    failed in `sample`; `matched_series`' `min_iou` of no number failed on "'<'"."""
    from vistrack.models import (
        BoxMotion,
        GrowthMeasurement,
        LinearMotion,
        NonlinearMeasurement,
        NonlinearMotion,
        Periodic,
        Position,
    )
    from vistrack.models.adapters import MotionFunctions
    from vistrack.models.switching import SwitchingLinearSystem

    cv = ConstantVelocity(dim=1)
    X, dt = np.array([[0.0, 1.0], [0.0, 2.0]]), np.array([1.0, 3.0])
    np.testing.assert_array_equal(MotionFunctions(cv).f(X, dt, 0.0), cv.f(X, dt))
    np.testing.assert_array_equal(MotionFunctions(cv).f(X, 2.0, 0.0), cv.f(X, 2.0))
    with pytest.raises(ValueError, match=re.escape(
            "x must be states of size 4, shape (..., 4); got shape (3,)")):
        ConstantVelocity(dim=2).f(np.zeros(3))
    for call, exc, msg in (
            (lambda: NonlinearMotion(lambda x, dt, t: x, np.eye(2), ndim_state=2.5),
             ValueError, "ndim_state must be a whole number >= 1; got 2.5"),
            (lambda: NonlinearMotion(lambda x, dt, t: x, np.eye(2), ndim_state=0),
             ValueError, "ndim_state must be a whole number >= 1; got 0"),
            (lambda: NonlinearMeasurement(lambda x: x, np.eye(1), ndim_state=2.5),
             ValueError, "ndim_state must be a whole number >= 1; got 2.5"),
            (lambda: NonlinearMeasurement(lambda x: x, np.eye(1), 2, angles=(0.5,)),
             ValueError, "angles must be a whole number >= 0; got 0.5"),
            (lambda: BoxMotion().Q_diag(np.array([[0, 0, 10.0, 10.0]]), dt=True),
             TypeError, "dt must be a number; got True"),
            (lambda: BoxMotion().Q_diag(np.array([[0, 0, 10.0, 10.0]]), dt="x"),
             TypeError, "dt must be a number; got 'x'"),
            (lambda: BoxMotion(std_meas=(True, 0.1, 0.1, 0.1)),
             TypeError, "std_meas must be a number; got True"),
            (lambda: BoxMotion(std_meas="a"), TypeError, "std_meas must be a number; got 'a'"),
            (lambda: GrowthMeasurement(r=True), TypeError, "r must be a number; got True"),
            (lambda: GrowthMeasurement(r="a"), TypeError, "r must be a number; got 'a'")):
        with pytest.raises(exc, match=re.escape(msg)):
            call()
    assert BoxMotion(std_meas=(0.1, 0.1, 0.2, 0.3)).std_meas.tolist() == [0.1, 0.1, 0.2, 0.3]
    # the closed form, as numpy computes it: q / ω² (d/2 - sin(2ωd)/(4ω)), ...
    Q = Periodic(omega=1e160, q=1.0).Q(1.0)
    assert np.isfinite(Q).all() and Q[1, 1] == pytest.approx(0.5, rel=1e-12)
    assert Q[0, 0] == pytest.approx(0.5e-320, rel=1e-2)
    np.testing.assert_array_equal(Periodic(omega=2.0, q=0.3).Q(0.7),
                                  Periodic(omega=2.0, q=0.3).Q(0.7))
    steps = LinearMotion(np.stack([np.eye(2)] * 3), np.stack([np.eye(2)] * 3))
    with pytest.raises(ValueError, match=re.escape(
            "motions[1] has per-step matrices (3 steps); a switching system takes one model "
            "of each kind for every step")):
        SwitchingLinearSystem([cv, steps], Position(dim=1), [[0.9, 0.1], [0.1, 0.9]])
    with pytest.raises(ValueError, match=re.escape(
            "this LinearMeasurement's H has 3 columns; the motion model's state has 2")):
        from vistrack.models import LinearMeasurement
        SwitchingLinearSystem([cv], LinearMeasurement(np.eye(3), np.eye(3)), [[1.0]])
    from vistrack.tracking.fit import matched_series
    with pytest.raises(TypeError, match=re.escape("min_iou must be a number; got 'a'")):
        matched_series(np.zeros(0), np.zeros(0), np.zeros((0, 4)), np.zeros(0),
                       np.zeros((0, 4)), min_iou="a")


def test_a_linear_motion_keeps_its_own_matrices():
    """LinearMotion kept the caller's arrays: a Q changed after its check (made not positive
    semi-definite) was used as it was, and so was one changed through the matrix Q() gave."""
    from vistrack.models import LinearMotion

    F, Q = np.eye(2), 0.1 * np.eye(2)
    m = LinearMotion(F, Q)
    Q[0, 0] = -5.0
    F[0, 1] = 3.0
    np.testing.assert_array_equal(m.Q(), 0.1 * np.eye(2))
    np.testing.assert_array_equal(m.F(), np.eye(2))
    m.Q()[1, 1] = -3.0  # a copy: the model's own stays
    m.F()[0, 0] = 2.0
    np.testing.assert_array_equal(m.Q(), 0.1 * np.eye(2))
    np.testing.assert_array_equal(m.F(), np.eye(2))


def test_a_range_bearing_sensor_must_be_finite():
    """A NaN sensor position gave NaN ranges and bearings, without a word."""
    from vistrack.models import RangeBearing

    with pytest.raises(ValueError, match=re.escape("sensor must be finite; sensor[0] = nan")):
        RangeBearing(sensor=(np.nan, 0.0))


def test_nonlinear_motion_and_range_bearing_keep_their_own_arrays():
    """NonlinearMotion kept a view of the caller's Q and RangeBearing one of its sensor
    position: changed after their checks (Q not positive semi-definite, the sensor NaN), the
    model gave them as changed. The oracle: the values given at construction."""
    from vistrack.models import NonlinearMotion, RangeBearing

    Q = 0.1 * np.eye(2)
    m = NonlinearMotion(lambda x, dt, t: x, Q, 2)
    Q[0, 0] = -5.0
    np.testing.assert_array_equal(m.Q(), 0.1 * np.eye(2))
    sensor = np.zeros(2)
    rb = RangeBearing(sensor=sensor)
    sensor[:] = np.nan
    np.testing.assert_allclose(rb.h([3.0, 4.0, 0.0, 0.0]), [5.0, np.arctan2(4.0, 3.0)])


def test_switching_samples_refuse_a_noise_matrix_the_filters_refuse():
    """A mode's Q of a model of the caller's own, NaN or with a negative variance, was drawn
    as no noise at all, or without that variance, where the filters refuse it; an R likewise.
    Both named now as the filters name them (MotionFunctions' check)."""
    class Still:
        ndim_state = 2

        def __init__(self, Q):
            self._Q = np.asarray(Q, float)

        def F(self, dt=1.0):
            return np.eye(2)

        def Q(self, dt=1.0):
            return self._Q

    meas = Position(dim=1)
    for Q, message in (([[np.nan, 0.0], [0.0, 1.0]], "motions[1].Q(1) must be finite; "
                                                        "motions[1].Q(1)[0, 0] = nan"),
                       (np.diag([-4.0, 9.0]), "motions[1].Q(1) must be positive "
                                              "semi-definite; motions[1].Q(1)[0, 0] = -4, a "
                                              "negative variance")):
        slds = SwitchingLinearSystem([Still(np.eye(2)), Still(Q)], meas, [[0.5, 0.5]] * 2)
        with pytest.raises(ValueError, match=re.escape(message)):
            slds.sample(4, x0=[0.0, 0.0], rng=0)

    class BadR:
        ndim_meas = 1

        def H(self, n):
            return np.eye(1, n)

        def R(self):
            return np.array([[-1.0]])

    slds = SwitchingLinearSystem([Still(np.eye(2))], BadR(), [[1.0]])
    with pytest.raises(ValueError, match=re.escape("measurement.R() must be positive "
                                                   "semi-definite")):
        slds.sample(4, x0=[0.0, 0.0], rng=0)
    # a good system still draws, the first state exactly x0
    zs, xs, ys = SwitchingLinearSystem([Still(np.eye(2))], meas, [[1.0]]).sample(
        3, x0=[1.0, 2.0], rng=0)
    assert xs[0].tolist() == [1.0, 2.0] and ys.shape == (3, 1)


def test_the_growth_model_and_numerical_jacobian_name_bad_arguments():
    """The growth model's functions broadcast a state of another size into a result of the
    wrong shape (x of shape (2,) against t of shape (2,): a (2, 2) array); eps 0 gave a NaN
    Jacobian with a RuntimeWarning alone. The oracle for the good cases: the formulas."""
    from vistrack.models import GrowthMeasurement, GrowthMotion, numerical_jacobian

    gm, gh = GrowthMotion(), GrowthMeasurement()
    for call, model in ((lambda: gm.f(np.array([1.0, 2.0]), t=np.array([0.0, 1.0])),
                         "GrowthMotion"),
                        (lambda: gm.jacobian(np.array([1.0, 2.0, 3.0])), "GrowthMotion"),
                        (lambda: gh.h(np.array([1.0, 2.0])), "GrowthMeasurement"),
                        (lambda: gh.jacobian(np.float64(2.0)), "GrowthMeasurement")):
        with pytest.raises(ValueError, match=rf"^x must be {model} states of 1 entry "
                                             r"\(last axis\); got shape"):
            call()
    x = np.array([[1.0], [2.0]])
    np.testing.assert_allclose(gm.f(x, t=0.0), x / 2 + 25 * x / (1 + x * x) + 8)
    np.testing.assert_allclose(gh.jacobian(x), (x / 10)[..., None])
    for eps in (0.0, -1e-6, np.nan, np.inf):
        with pytest.raises(ValueError, match=r"^eps must be a finite step > 0; got "):
            numerical_jacobian(lambda v: v ** 2, np.array([3.0]), eps=eps)
    np.testing.assert_allclose(numerical_jacobian(lambda v: v ** 2, np.array([3.0])), [[6.0]],
                               rtol=1e-8)


def test_linear_models_check_their_arguments_as_the_others_do():
    """LinearMotion.F(True) was a step of 1 where ConstantVelocity's refuses it, and its f of
    a state of another size met numpy's bare matmul error; Position(r=True) was a variance of
    1 and Position().H(2.5) met numpy's "cannot be interpreted as an integer"."""
    lm = LinearMotion(np.eye(2), np.eye(2))
    with pytest.raises(TypeError, match=r"^dt must be a number or an array of numbers; "
                                        r"got True"):
        lm.F(True)
    with pytest.raises(ValueError, match=re.escape("x must be states of size 2, shape "
                                                   "(..., 2); got shape (3,)")):
        lm.f(np.zeros(3))
    np.testing.assert_array_equal(lm.f(np.ones((4, 2))), np.ones((4, 2)))
    with pytest.raises(TypeError, match=r"^r must be a variance or a covariance matrix; "
                                        r"got True"):
        Position(r=True)
    with pytest.raises(ValueError, match=re.escape("Position(dim=2) needs a state of at least "
                                                   "2 entries, a whole number; got "
                                                   "ndim_state=2.5")):
        Position().H(2.5)
    np.testing.assert_array_equal(Position(dim=1).H(np.int64(3)), [[1.0, 0.0, 0.0]])


def test_a_boolean_dt_is_refused():
    """F(True) was the step of 1: a flag passed where a time step belongs."""
    for model in (ConstantVelocity(), Periodic()):
        for bad in (True, np.bool_(False), np.array([1.0, 2.0]) > 1, [1.0, True]):
            with pytest.raises(TypeError, match=r"dt must be a number or an array of numbers"):
                model.F(bad)
    np.testing.assert_array_equal(ConstantVelocity(dim=1).F(1), [[1.0, 1.0], [0.0, 1.0]])


def test_periodic_euler_names_an_overflowing_step():
    """omega 1e160 with the Euler step: -omega² dt raised Python's OverflowError,
    "Numerical result out of range", naming neither omega nor dt."""
    with pytest.raises(ValueError, match=r"Euler step overflows.*omega=1e\+160, dt=0\.5"):
        Periodic(omega=1e160, discretisation="euler").F(0.5)
    # the largest omega whose square is finite still gives the seeds' matrix [[1, dt], [-ω² dt, 1]]
    w = 1e154
    np.testing.assert_array_equal(Periodic(omega=w, discretisation="euler").F(0.5),
                                  [[1.0, 0.5], [-w * w * 0.5, 1.0]])


def test_a_switching_system_keeps_its_own_transition_and_mode_probabilities():
    """Views of the caller's transition and mode_probs were kept: changed after the checks
    (a row of 3 and -2), the switching particle filter used them unchecked. The oracle: the
    values given at construction."""
    Pi, mu = np.array([[0.95, 0.05], [0.2, 0.8]]), np.array([0.5, 0.5])
    slds = SwitchingLinearSystem([ConstantVelocity(dim=1, q=0.01), ConstantVelocity(dim=1)],
                                 Position(dim=1), Pi, mode_probs=mu)
    Pi[0] = [3.0, -2.0]
    mu[:] = [2.0, -1.0]
    np.testing.assert_array_equal(slds.transition, [[0.95, 0.05], [0.2, 0.8]])
    np.testing.assert_array_equal(slds.mode_probs, [0.5, 0.5])


@pytest.mark.parametrize("dt", ["0.5", b"1", np.array(["1.0"]), [1.0, "2"], None])
def test_a_time_step_of_text_or_none_is_refused(dt):
    """Text was read as a step (``F("0.5")`` was the step of 0.5) and None was said as "got
    nan"; both are refused, as ``q`` refuses text, and the shared step check of the filters
    with them."""
    from vistrack.filters._nonlinear import step_times

    for model in (ConstantVelocity(dim=1), Periodic(omega=1.0),
                  LinearMotion(np.eye(2), np.eye(2))):
        with pytest.raises(TypeError, match="dt must be a number or an array of numbers; got"):
            model.F(dt)
        with pytest.raises(TypeError, match="dt must be a number or an array of numbers; got"):
            model.Q(dt)
    if dt is not None:  # (None is step_times' "not given")
        with pytest.raises(TypeError, match="dt must be a number or an array of numbers"):
            step_times(dt, None, 3)


def test_a_time_step_past_the_largest_float_is_named():
    """An integer past the largest float failed in Python's words (OverflowError: int too
    large to convert to float), naming nothing; a step whose F or Q overflows gave inf."""
    with pytest.raises(ValueError, match="dt must be numbers a float can hold .*1329 bits"):
        ConstantVelocity(dim=1).F(10**400)
    with pytest.raises(ValueError, match=r"ConstantVelocity's Q\(dt\) is past the largest "
                                         r"float at dt=1e\+155, q=1: too long a step or too "
                                         "large a noise"):
        ConstantVelocity(dim=1).Q(1e155)
    with pytest.raises(ValueError, match=r"ConstantVelocity's Q\(dt\) .* at dt=10, q=1e\+308"):
        ConstantVelocity(dim=1, q=1e308).Q(10.0)
    with pytest.raises(ValueError, match=r"ConstantAcceleration's F\(dt\) is past"):
        ConstantAcceleration(dim=1).F(1e200)
    with pytest.raises(ValueError, match=r"Periodic's Q\(dt\) is past the largest float at "
                                         r"dt=10, q=1e\+308"):
        Periodic(omega=1.0, q=1e308).Q(10.0)
    # entries within the range whose powers of dt are not (dt^3 of 1e103, dt^2 of 1.5e154),
    # and no noise at all (0 x inf was NaN): the closed forms, exact in fractions
    from fractions import Fraction as Fr

    np.testing.assert_allclose(ConstantVelocity(dim=1, q=1e-20).Q(1e103), [
        [float(Fr(1e-20) * Fr(1e103) ** 3 / 3), float(Fr(1e-20) * Fr(1e103) ** 2 / 2)],
        [float(Fr(1e-20) * Fr(1e103) ** 2 / 2), float(Fr(1e-20) * Fr(1e103))]], rtol=1e-15)
    assert ConstantAcceleration(dim=1).F(1.5e154)[0, 2] == pytest.approx(
        float(Fr(1.5e154) ** 2 / 2), rel=1e-15)
    assert (ConstantVelocity(dim=1, q=0.0).Q(1e103) == 0).all()
    # the closed forms at a step well inside the range: computed as before, to the bit
    np.testing.assert_array_equal(ConstantVelocity(dim=1, q=1.0).Q(1e100), [
        [1.0 * 1e100**3 / 3, 1.0 * 1e100**2 / 2], [1.0 * 1e100**2 / 2, 1.0 * 1e100 / 1]])


def test_periodic_noise_at_a_phase_past_the_largest_float():
    """At ω 1e308 and dt 1, 2 ω dt overflowed and Q was NaN, where its closed form
    ``q (dt/2 + sin(2ωdt) / 4ω)`` is 0.5 to within 2.5e-309 and the position's entries
    within 1e-616 of 0; a phase ω dt past the largest float itself (F and Q NaN) is named."""
    Q = Periodic(omega=1e308, q=1.0).Q(1.0)
    np.testing.assert_allclose(Q, [[0.0, 0.0], [0.0, 0.5]], rtol=0, atol=1e-300)
    for call in (lambda m: m.F(1e10), lambda m: m.Q(1e10)):
        with pytest.raises(ValueError, match="Periodic's phase omega dt is past the largest "
                                             "float at omega=1e\\+300, dt=1e\\+10"):
            call(Periodic(omega=1e300))


def test_an_empty_stack_of_matrices_is_refused():
    """A stack of no matrices was taken as a constant model ("steps=constant", n_steps 0)
    and failed later in numpy's words; a 0 x 0 model failed in the covariance check's."""
    for F, Q, name in ((np.zeros((0, 2, 2)), np.eye(2), "F"), (np.eye(2), np.zeros((0, 2, 2)),
                                                               "Q")):
        with pytest.raises(ValueError, match=re.escape(
                f"{name} must hold at least one matrix; got shape (0, 2, 2)")):
            LinearMotion(F, Q)
    with pytest.raises(ValueError, match="F must hold at least one matrix"):
        LinearGaussian(np.zeros((0, 2, 2)), np.eye(2), np.eye(2), np.eye(2))
    with pytest.raises(ValueError, match=re.escape("F must be at least 1 x 1")):
        LinearMotion(np.zeros((0, 0)), np.zeros((0, 0)))


def test_a_switching_system_refuses_a_motion_whose_noise_needs_the_state():
    """BoxMotion's ``Q(boxes, dt)`` passed the check of a linear motion model (it is
    callable) and failed at ``sample`` naming ``boxes``, which the caller never gave."""
    with pytest.raises(TypeError, match=r"motions\[0\] must be a linear motion model whose "
                                        r"Q\(dt\) takes the time step alone; BoxMotion's"):
        SwitchingLinearSystem([BoxMotion(), BoxMotion()],
                              LinearMeasurement(np.eye(4, 8), np.eye(4)), [[0.9, 0.1],
                                                                          [0.1, 0.9]])


def test_probabilities_stored_as_float32_are_taken():
    """A float32 switching matrix whose rows sum to 1 in float32 sums to 1 - 2.2e-8 in
    float64, and was refused at the absolute 1e-9; the tolerance is now the input's own
    rounding, and each row scaled to sum to 1. The filter then equals the one given the
    float32 values in float64, each row scaled to sum to 1 (the oracle), and a row that is
    off is still refused."""
    from vistrack.filters import IMMFilter

    cv = [ConstantVelocity(dim=1, q=0.1), ConstantVelocity(dim=1, q=2.0)]
    Pi32, mu32 = np.float32([[0.9, 0.1], [0.3, 0.7]]), np.float32([0.1, 0.9])
    assert (Pi32.sum(1, dtype=np.float32) == 1).all() and mu32.sum(dtype=np.float32) == 1
    slds = SwitchingLinearSystem(cv, Position(dim=1), Pi32, mode_probs=mu32)
    Pi64, mu64 = Pi32.astype(float), mu32.astype(float)
    same = SwitchingLinearSystem(cv, Position(dim=1), Pi64 / Pi64.sum(1, keepdims=True),
                                 mode_probs=mu64 / mu64.sum())
    ys = np.array([[0.0], [1.1], [1.9], [3.2]])
    a = IMMFilter.from_system(slds).filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    b = IMMFilter.from_system(same).filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    np.testing.assert_array_equal(a.means, b.means)
    np.testing.assert_array_equal(a.mode_probs, b.mode_probs)
    with pytest.raises(ValueError, match="rows sum to 1; got shape"):
        IMMFilter([vt_kf(c) for c in cv], np.float32([[0.9, 0.2], [0.3, 0.7]]))
    with pytest.raises(ValueError, match="whose rows sum to 1"):
        SwitchingLinearSystem(cv, Position(dim=1), np.float32([[0.9, 0.2], [0.3, 0.7]]))


def vt_kf(motion):
    """A Kalman filter of ``motion`` measuring its position."""
    from vistrack.filters import KalmanFilter

    return KalmanFilter(motion, Position(dim=1))

"""Errors that name the argument: no measurement steps, a prior of the wrong size, and a
particle filter's user likelihood that returns NaN or the wrong number of values."""

import re

import numpy as np
import pytest

import vistrack as vt
from vistrack.evaluation.filtering import chi2_band
from vistrack.filters import (
    EnsembleKalmanFilter,
    ExtendedKalmanFilter,
    FilterResult,
    IMMFilter,
    KalmanFilter,
    ParticleFilter,
    SwitchingParticleFilter,
    UnscentedKalmanFilter,
    kalman_filter,
    rts_smooth,
)
from vistrack.filters.enkf import Ensemble
from vistrack.frontends.background import SelectiveBackground
from vistrack.frontends.blobs import BlobDetector
from vistrack.models import SwitchingLinearSystem
from vistrack.simulate import simulate_lgssm
from vistrack.tracking.calibration import ScoreCalibrator
from vistrack.tracking.dcpf import DCPFConfig

CV, POS = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1, r=1.0)
MATS = dict(F=np.array([[1.0, 1.0], [0.0, 1.0]]), Q=0.01 * np.eye(2), H=np.array([[1.0, 0.0]]),
            R=[[0.25]])
SLDS = SwitchingLinearSystem([vt.ConstantVelocity(dim=1, q=0.01),
                              vt.ConstantVelocity(dim=1, q=4.0)], POS, [[0.9, 0.1], [0.2, 0.8]])


def _imm():
    return IMMFilter([KalmanFilter(CV, POS), KalmanFilter(vt.ConstantVelocity(dim=1, q=4.0), POS)],
                     [[0.9, 0.1], [0.1, 0.9]])


# every sequence filter, called with ys, x0 and P0
FILTERS = {
    "kalman_filter": lambda ys, x0, P0: kalman_filter(ys, **MATS, x0=x0, P0=P0),
    "KalmanFilter.filter": lambda ys, x0, P0: KalmanFilter(CV, POS).filter(ys, x0=x0, P0=P0),
    "KalmanFilter.smooth": lambda ys, x0, P0: KalmanFilter(CV, POS).smooth(ys, x0=x0, P0=P0),
    "ExtendedKalmanFilter": lambda ys, x0, P0: ExtendedKalmanFilter(CV, POS).filter(
        ys, x0=x0, P0=P0),
    "UnscentedKalmanFilter": lambda ys, x0, P0: UnscentedKalmanFilter(CV, POS).filter(
        ys, x0=x0, P0=P0),
    "EnsembleKalmanFilter": lambda ys, x0, P0: EnsembleKalmanFilter(CV, POS, rng=0).filter(
        ys, x0=x0, P0=P0),
    "ParticleFilter": lambda ys, x0, P0: ParticleFilter(CV, POS, rng=0).filter(
        ys, x0=x0, P0=P0),
    "ParticleFilter (numpy path)": lambda ys, x0, P0: ParticleFilter(CV, POS, rng=0).filter(
        ys, x0=x0, P0=P0, modes=True),
    "IMMFilter": lambda ys, x0, P0: _imm().filter(ys, x0=x0, P0=P0),
    "SwitchingParticleFilter": lambda ys, x0, P0: SwitchingParticleFilter(SLDS, rng=0).filter(
        ys, x0=x0, P0=P0),
}
BATCHED = {"kalman_filter", "KalmanFilter.filter", "KalmanFilter.smooth", "ExtendedKalmanFilter",
           "UnscentedKalmanFilter", "EnsembleKalmanFilter", "IMMFilter"}


@pytest.mark.parametrize("name", sorted(FILTERS))
def test_no_step_is_refused_naming_ys(name):
    with pytest.raises(ValueError, match=re.escape(
            "ys must have at least one step; got shape (0, 1)") + "$"):
        FILTERS[name](np.empty((0, 1)), [0.0, 1.0], np.eye(2))
    if name in BATCHED:
        with pytest.raises(ValueError, match=re.escape(
                "ys must have at least one step; got shape (3, 0, 1)") + "$"):
            FILTERS[name](np.empty((3, 0, 1)), [0.0, 1.0], np.eye(2))


def test_no_step_is_refused_by_the_default_prior():
    kf = KalmanFilter(CV, POS)
    for call in (kf.filter, kf.smooth, kf.default_prior):
        with pytest.raises(ValueError, match=re.escape(
                "ys must have at least one step; got shape (0, 1)") + "$"):
            call(np.empty((0, 1)))


def test_rts_smooth_refuses_a_result_without_steps():
    res = FilterResult(np.empty((0, 2)), np.empty((0, 2, 2)), None, None, np.asarray(0.0),
                       vt.Gaussian(np.zeros(2), np.eye(2)))
    with pytest.raises(ValueError, match=re.escape(
            "result.means must have at least one step; got shape (0, 2)") + "$"):
        rts_smooth(res, F=MATS["F"], Q=MATS["Q"])


@pytest.mark.parametrize("name", sorted(FILTERS))
def test_a_prior_mean_of_the_wrong_length_names_x0(name):
    if name.startswith("kalman") or name.startswith("KalmanFilter"):
        want = "x0 must have shape (2,) or (B=1, 2) to match P0 and F; got (3,)"
    elif name in BATCHED:
        want = "x0 must have shape (2,) or (B, 2)"
        want += " (the largest member's state)" if name == "IMMFilter" else ""
        want += "; got (3,)"
    else:
        want = "x0 must have shape (2,); got (3,)"
    with pytest.raises(ValueError, match=re.escape(want) + "$"):
        FILTERS[name](np.zeros((4, 1)), [0.0, 1.0, 2.0], np.eye(2))


@pytest.mark.parametrize("name", sorted(FILTERS))
def test_a_prior_covariance_of_the_wrong_size_names_P0(name):
    with pytest.raises(ValueError, match=r"^P0 must have shape \(2, 2\)"):
        FILTERS[name](np.zeros((4, 1)), [0.0, 1.0], np.eye(3))


def test_a_missing_prior_is_named():
    with pytest.raises(ValueError, match=re.escape(
            "P0 is required (the prior of the first step); got None") + "$"):
        ParticleFilter(CV, POS, rng=0).filter(np.zeros((3, 1)), x0=[0.0, 1.0])


def test_a_likelihood_returning_nan_is_a_value_error_naming_the_step():
    calls = [0]

    def loglik(y, x):
        calls[0] += 1
        out = -0.5 * (y[0] - x[:, 0]) ** 2
        if calls[0] == 3:
            out[:7] = np.nan
        return out

    pf = ParticleFilter(CV, loglik, n_particles=1000, rng=0)
    with pytest.raises(ValueError, match=re.escape(
            "likelihood returned NaN for 7 of 1000 particles at step 2 (measurement [2.0]); it "
            "must return log p(y | x) for each particle, finite or -inf where y is impossible")
            + "$"):
        pf.filter(np.arange(5.0)[:, None], x0=[0.0, 1.0], P0=np.eye(2))


@pytest.mark.parametrize("shape", [(999,), (1000, 1), ()])
def test_a_likelihood_returning_the_wrong_number_of_values_is_named(shape):
    pf = ParticleFilter(CV, lambda y, x: np.zeros(shape), n_particles=1000, rng=0)
    with pytest.raises(ValueError, match=re.escape(
            f"likelihood must return (N,) = (1000,) log-likelihoods, one per particle; got "
            f"shape {shape} at step 0") + "$"):
        pf.filter(np.arange(5.0)[:, None], x0=[0.0, 1.0], P0=np.eye(2))


def test_a_likelihood_of_minus_infinity_everywhere_is_still_degeneracy():
    from vistrack.filters import ParticleDegeneracyError

    pf = ParticleFilter(CV, lambda y, x: np.full(len(x), -np.inf), n_particles=50, rng=0)
    with pytest.raises(ParticleDegeneracyError, match="zero likelihood at step 0"):
        pf.filter(np.zeros((3, 1)), x0=[0.0, 1.0], P0=np.eye(2))


@pytest.mark.parametrize("make, message", [
    (lambda: vt.Detections(points=[[1.0, 2.0], [np.nan, 1.0]]),
     "points must be finite; points[1] = [nan, 1.0]"),
    (lambda: vt.Detections(boxes=[[0, 0, 1, 1], [0, np.inf, 1, 1]]),
     "boxes must be finite; boxes[1] = [0.0, inf, 1.0, 1.0]"),
    (lambda: vt.Detections.from_xywh([[10, 10, 20, 40], [10, 10, -40, 80]]),
     "xywh must have widths and heights >= 0; xywh[1] = [10.0, 10.0, -40.0, 80.0]"),
    # a class of 1.7 was class 1, NaN failed in numpy's cast; boxes of shape (5, 0) were
    # no detections at all; xywh of 3 values failed in numpy's reshape, and a non-finite one
    # was named as the corners it made
    (lambda: vt.Detections(boxes=[[0, 0, 1, 1], [0, 0, 2, 2]], classes=[1, 1.7]),
     "classes must be whole numbers; classes[1] = 1.7"),
    (lambda: vt.Detections(boxes=[[0, 0, 1, 1]], classes=[np.nan]),
     "classes must be whole numbers; classes[0] = nan"),
    (lambda: vt.Detections(boxes=np.zeros((5, 0))), "boxes must have shape (N, 4); got (5, 0)"),
    # (points=[] says no dimension, where boxes=[] is boxes of 4 values: said how to give none)
    (lambda: vt.Detections(points=[]), "points must have shape (N, d); got (0,) (no points: "
                                       "np.zeros((0, d)), d the points' dimension)"),
    (lambda: vt.Detections.from_xywh([1, 2, 3]), "xywh must have shape (N, 4); got (3,)"),
    (lambda: vt.Detections.from_xywh([[1, 2, np.inf, 4]]),
     "xywh must be finite; xywh[0] = [1.0, 2.0, inf, 4.0]"),
])
def test_detections_name_the_row_that_is_not_a_box_or_a_point(make, message):
    """A NaN point was taken (a point tracker then started a track at NaN, and every later
    step failed in scipy's k-d tree); a bad box is named by its row; a negative width is
    named as given, not as the corners it makes."""
    with pytest.raises(ValueError) as e:
        make()
    assert str(e.value) == message


@pytest.mark.parametrize("name", sorted(FILTERS))
def test_every_filter_names_ys_of_another_width_and_its_infinite_step(name):
    """The IMM named ``y`` (one step's) where ``ys`` had two values a step; the particle
    filter took an infinite measurement for a lost target, and the EKF, UKF and EnKF named
    the step's ``y[0]`` instead of the series' ``ys[1, 0]``."""
    with pytest.raises(ValueError, match=r"^ys must have (1 |shape \(T, 1\)).*got (2|\(4, 2\))$"):
        FILTERS[name](np.zeros((4, 2)), [0.0, 1.0], np.eye(2))
    with pytest.raises(ValueError, match=re.escape(
            "ys must be finite or NaN (missing); ys[1, 0] = inf") + "$"):
        FILTERS[name](np.array([[0.0], [np.inf], [1.0]]), [0.0, 1.0], np.eye(2))


@pytest.mark.parametrize("name", sorted(FILTERS))
def test_every_filter_takes_a_singular_prior(name):
    """A prior known exactly along a direction is positive semi-definite, as the prior check
    accepts; the EnKF could not sample its ensemble from it."""
    P0 = np.array([[1.0, 1.0], [1.0, 1.0]])
    res = FILTERS[name](np.array([[0.0], [1.0], [2.0]]), [0.0, 1.0], P0)
    assert np.isfinite(res.means).all()


def test_an_ensemble_drawn_from_a_singular_covariance_has_that_covariance():
    cov = np.array([[4.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 0.0]])  # rank 1
    mean, got = Ensemble.sample([1.0, 2.0, 3.0], cov, 40_000, rng=0).moments()
    np.testing.assert_allclose(got, cov, atol=0.08)
    np.testing.assert_allclose(mean, [1.0, 2.0, 3.0], atol=0.03)
    with pytest.raises(ValueError, match="cov must be positive semi-definite"):
        Ensemble.sample([0.0, 0.0], -np.eye(2), 10, rng=0)
    # a NaN covariance passed Cholesky's factorisation, and drew NaN members without a word
    with pytest.raises(ValueError, match=re.escape("cov must be finite; cov[0, 1] = nan")):
        Ensemble.sample([0.0, 0.0], [[1.0, np.nan], [np.nan, 1.0]], 10, rng=0)
    with pytest.raises(ValueError, match=re.escape("mean must be finite; mean[1] = inf")):
        Ensemble.sample([0.0, np.inf], np.eye(2), 10, rng=0)


# booleans and non-finite values where a whole number or a number is asked for: int(True) ==
# True and float(True) == 1.0, so True passed as 1; int(NaN) and int(inf) raised errors that
# name nothing
WHOLE_CASES = [
    (lambda v: vt.ConstantVelocity(dim=v), "dim must be 1, 2 or 3"),
    (lambda v: vt.Position(dim=v), "dim must be 1, 2 or 3"),
    (lambda v: simulate_lgssm(v, **MATS, x0=[0.0, 1.0], rng=0), "T must be a positive integer"),
    (lambda v: EnsembleKalmanFilter(CV, POS, n_members=v), "n_members must be"),
    (lambda v: Ensemble.sample([0.0], [[1.0]], v, rng=0), "n_members must be"),
    (lambda v: SelectiveBackground(n_new=v), "n_new must be"),
    (lambda v: BlobDetector(check_view=v), "check_view must be"),
    (lambda v: ScoreCalibrator(window=v), "window must be"),
    (lambda v: DCPFConfig(n_particles=v), "n_particles must be"),
    (lambda v: chi2_band(v), "dof must be a whole number >= 1"),
]


@pytest.mark.parametrize("value", [True, np.bool_(True), np.array(True), np.nan, np.inf, 2.5])
@pytest.mark.parametrize("case", range(len(WHOLE_CASES)))
def test_whole_number_settings_refuse_booleans_and_non_finite(case, value):
    make, message = WHOLE_CASES[case]
    with pytest.raises(ValueError, match=f"{re.escape(message)}.*got {re.escape(repr(value))}"):
        make(value)


def test_whole_number_settings_take_integral_floats_and_numpy_integers():
    # (what was taken before stays taken)
    assert vt.ConstantVelocity(dim=2.0).dim == 2
    assert vt.ConstantVelocity(dim=np.int64(3)).dim == 3
    # an integer too large for a float is whole, and named where it is out of range (float()
    # of it overflowed, naming nothing)
    with pytest.raises(ValueError, match="dim must be 1, 2 or 3"):
        vt.ConstantVelocity(dim=10**400)
    xs, _ = simulate_lgssm(np.float64(4.0), **MATS, x0=[0.0, 1.0], rng=0)
    assert xs.shape == (4, 2)


@pytest.mark.parametrize("value", [True, False, np.bool_(True)])
def test_a_boolean_is_not_a_number(value):
    with pytest.raises(TypeError, match=f"q must be a number; got {re.escape(repr(value))}"):
        vt.ConstantVelocity(dim=1, q=value)


@pytest.mark.parametrize("value", ["no", 0, 1, None])
def test_store_covs_must_be_true_or_false(value):
    ys = np.zeros((3, 1))
    said = f"store_covs must be True or False; got {re.escape(repr(value))}"
    with pytest.raises(TypeError, match=said):
        kalman_filter(ys, **MATS, x0=[0.0, 1.0], P0=np.eye(2), store_covs=value)
    with pytest.raises(TypeError, match="store_covs must be True or False"):
        KalmanFilter(CV, POS).filter(ys, store_covs=value)
    # numpy's bools are bools: False stores no covariances
    assert kalman_filter(ys, **MATS, x0=[0.0, 1.0], P0=np.eye(2),
                         store_covs=np.bool_(False)).covs is None

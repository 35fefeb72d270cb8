"""simulate() checks its arguments as simulate_lgssm does, with a nonlinear model too."""

import numpy as np
import pytest

from vistrack.models import ConstantVelocity, Position, growth_model
from vistrack.simulate import simulate

LINEAR = (ConstantVelocity(dim=1, q=1.0), Position(dim=1))
NONLINEAR = growth_model()


@pytest.mark.parametrize("bad, match", [
    ({"T": 2.5}, "T must be a positive integer; got 2.5"),
    ({"T": 0}, "T must be a positive integer; got 0"),
    ({"n_series": 0}, "n_series must be a whole number >= 1; got 0"),
    # taken as 2 series, NaN states, NaN states after the first step (the nonlinear path)
    ({"n_series": 2.7}, "n_series must be a whole number >= 1; got 2.7"),
    ({"P0": "nan"}, r"P0 must be finite; P0\[0, 0\] = nan"),
    ({"dt": [1.0, np.nan]}, "dt must be finite and >= 0; got nan"),
    ({"P0": "negative"}, "P0 must be positive semi-definite"),
    ({"P0": "wrong shape"}, r"P0 must have shape"),
    ({"x0": "nan"}, r"x0 must be finite; x0\[0\] = nan"),
])
@pytest.mark.parametrize("models", [LINEAR, NONLINEAR], ids=["linear", "nonlinear"])
def test_both_paths_refuse_the_same_bad_arguments(models, bad, match):
    # before, the nonlinear path took T=2.5 as 2 steps, T=0 and n_series=0 as empty
    # series, a P0 not positive semi-definite, and x0 NaN (NaN series)
    n = 2 if models is LINEAR else 1
    kwargs = {"T": 3, "x0": np.full(n, 0.1), "P0": None, "n_series": None}
    kwargs.update(bad)
    if isinstance(kwargs["P0"], str) and kwargs["P0"] == "nan":
        kwargs["P0"] = np.full((n, n), np.nan)
    elif kwargs["P0"] == "negative":
        kwargs["P0"] = np.diag([-1.0] + [1.0] * (n - 1))
    elif kwargs["P0"] == "wrong shape":
        kwargs["P0"] = np.eye(n + 1)
    if isinstance(kwargs["x0"], str):
        kwargs["x0"] = np.full(n, np.nan)
    T = kwargs.pop("T")
    with pytest.raises(ValueError, match=match):
        simulate(*models, T, rng=0, **kwargs)


def test_valid_nonlinear_draws_are_unchanged():
    # the checks consume no random numbers: the draws are those of the generator alone
    xs, ys = simulate(*NONLINEAR, 20, x0=[0.1], P0=[[0.5]], n_series=3, rng=0)
    again, _ = simulate(*NONLINEAR, 20.0, x0=[0.1], P0=[[0.5]], n_series=3, rng=0)
    assert xs.shape == (3, 20, 1) and ys.shape == (3, 20, 1)
    np.testing.assert_array_equal(xs, again)
    gen = np.random.default_rng(0)
    np.testing.assert_array_equal(xs[:, 0, 0], 0.1 + np.sqrt(0.5) * gen.standard_normal(3))


def test_an_initial_state_of_the_wrong_size_is_named_alone():
    """`simulate`'s linear path named a P0 never given (the identity it built) and offered a
    (B, n) x0 that it then refused: it names x0 and the one shape it takes."""
    import re

    from vistrack.models import ConstantVelocity, Position
    from vistrack.simulate import simulate

    with pytest.raises(ValueError, match=re.escape(
            "x0 must have shape (2,), the motion's state; got (3,)")):
        simulate(ConstantVelocity(dim=1, q=0.1), Position(dim=1), 3, x0=[0, 1, 2], rng=0)
    xs, _ = simulate(ConstantVelocity(dim=1, q=0.1), Position(dim=1), 3, x0=[0, 1], rng=0)
    assert xs.shape == (3, 2)

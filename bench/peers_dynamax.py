"""Time dynamax's EM (``LinearGaussianSSM.fit_em``) on measurements saved by bench_em.py.

    PYTHON_WITH_DYNAMAX bench/peers_dynamax.py PROBLEM.npz ITERATIONS REPEATS

``PROBLEM.npz`` holds ``ys`` ``(B, T, m)`` and the model to start from: ``F``, ``Q``, ``H``,
``R``, ``x0``, ``P0``. Prints one JSON object: ``first`` (seconds of the first call, which
traces and compiles), ``median`` (of ``REPEATS`` more calls), ``fixed`` (the median call of one
iteration: what a call costs besides its iterations), ``loglik`` (the last iteration's log
probability) and ``first_nan`` (the first iteration whose log probability is NaN, or null).

dynamax learns every parameter of its model at once (``F``, ``H``, their biases, ``Q``,
``R`` and the prior): its M-step takes all of them or none. Runs in an interpreter of its
own, since it needs jax (``make bench-peers`` makes ``.venv-dynamax``); it does not import
vistrack.
"""

from __future__ import annotations

import json
import statistics
import sys
import time

import numpy as np


def main() -> None:
    path, iters, reps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    import jax
    import jax.numpy as jnp
    from dynamax.linear_gaussian_ssm import LinearGaussianSSM

    jax.config.update("jax_enable_x64", True)  # float64, as vistrack and the other peers
    d = np.load(path)
    ys = jnp.asarray(d["ys"])
    n, m = d["F"].shape[0], d["H"].shape[0]
    model = LinearGaussianSSM(n, m)
    params, props = model.initialize(
        jax.random.PRNGKey(0), initial_mean=jnp.asarray(d["x0"]),
        initial_covariance=jnp.asarray(d["P0"]), dynamics_weights=jnp.asarray(d["F"]),
        dynamics_covariance=jnp.asarray(d["Q"]), emission_weights=jnp.asarray(d["H"]),
        emission_covariance=jnp.asarray(d["R"]))

    def fit(k: int):
        t = time.perf_counter()
        _, lps = model.fit_em(params, props, ys, num_iters=k, verbose=False)
        lps = np.asarray(lps.block_until_ready())
        return time.perf_counter() - t, lps

    first, lps = fit(iters)
    times = [fit(iters)[0] for _ in range(reps)]
    fixed = statistics.median(fit(1)[0] for _ in range(reps))
    nan = np.flatnonzero(np.isnan(lps))
    print(json.dumps(dict(first=first, median=statistics.median(times), fixed=fixed,
                          loglik=float(lps[-1]), first_nan=int(nan[0]) if len(nan) else None)))


if __name__ == "__main__":
    main()

"""Learning Q and R from measurements: vistrack's EM beside the libraries a user would pick.

    python bench/bench_em.py [--quick] [--dynamax-python PY] [--write docs/benchmarks.md]

The problem: a 2-D constant-velocity model (4 states), 2-D positions, T = 1,000 steps, the
true white-noise-acceleration q = 0.5 and R = 4 I, every fit started from q = 1, R = I (the
prior x0 = 0, P0 = 10 I known). vistrack learns the structured model (the factor q of the
white-noise-acceleration Q, R's diagonal: `Q_form="scaled"`, `R_form="diag"`) and, beside
pykalman and simdkalman, which learn every entry, the full Q and R. statsmodels maximises the
likelihood over (q, r_x, r_y) with L-BFGS. dynamax's EM (`fit_em`) learns every parameter
(F, H, their biases, Q, R and the prior: all or none), in float64, in an interpreter of its
own (`--dynamax-python`, default `.venv-dynamax/bin/python`; `make bench-peers` makes
it), since it needs jax. One process, one core; each time is the median of the repeats after
a warm-up run; a peer too slow for 50 iterations is timed on fewer and its time given per 50
(said in the table).
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import warnings

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import vistrack as vt  # noqa: E402
from vistrack.filters import em, mle  # noqa: E402
from vistrack.simulate import simulate_lgssm  # noqa: E402

from _common import median_time, optional  # noqa: E402  (bench/ is on the path of its scripts)
from _markdown import publish  # noqa: E402

CV, POS = vt.ConstantVelocity(dim=2, q=0.5), vt.Position(dim=2, r=4.0)
F, Q_TRUE, H, R_TRUE = CV.F(1.0), CV.Q(1.0), POS.H(4), POS.R()
Q1 = Q_TRUE / 0.5  # q = 1: the start, and the shape whose factor is learned
X0, P0 = np.zeros(4), 10.0 * np.eye(4)
T = 1000


def _ratio(r: float) -> str:
    """A ratio for the table: one decimal below 10 (statsmodels' 1.45 was printed 1)."""
    return f"{r:.1f}" if r < 10 else f"{r:.0f}"


def data(B: int) -> np.ndarray:
    ys = [simulate_lgssm(T, F=F, Q=Q_TRUE, H=H, R=R_TRUE, x0=X0, P0=P0, rng=s)[1]
          for s in range(B)]
    return ys[0] if B == 1 else np.stack(ys)


def vistrack_fit(ys, iters, structured=True, tol=-np.inf):
    return em(ys, F=F, Q=Q1 if structured else np.eye(4), H=H, R=np.eye(2), x0=X0, P0=P0,
              learn=("Q", "R"), Q_form="scaled" if structured else "full",
              R_form="diag" if structured else "full", tol=tol, max_iter=iters)


def statsmodels_fit(ys):
    from statsmodels.tsa.statespace.mlemodel import MLEModel

    class WhiteNoiseAcceleration(MLEModel):
        def __init__(self, endog):
            super().__init__(endog, k_states=4, k_posdef=4)
            self["design"], self["transition"], self["selection"] = H, F, np.eye(4)
            self.initialize_known(X0, P0)

        @property
        def start_params(self):
            return np.ones(3)

        @property
        def param_names(self):
            return ["q", "r_x", "r_y"]

        def transform_params(self, u):
            return u ** 2

        def untransform_params(self, c):
            return np.sqrt(c)

        def update(self, params, **kwargs):
            params = super().update(params, **kwargs)
            self["state_cov"] = params[0] * Q1
            self["obs_cov"] = np.diag(params[1:])

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return WhiteNoiseAcceleration(ys).fit(method="lbfgs", disp=False, maxiter=500)


def _simd_prior(B: int) -> dict:
    """x0 and P0 in simdkalman's shapes, one per series."""
    return dict(initial_value=np.tile(X0, (B, 1))[..., None],
                initial_covariance=np.tile(P0, (B, 1, 1)))


def dynamax_fit(python: str, ys: np.ndarray, iters: int, reps: int) -> dict | None:
    """dynamax's EM on ``ys (B, T, 2)`` from the same start, run by ``peers_dynamax.py`` in the
    interpreter ``python``: its JSON (seconds of the first call and the median call, what a
    call of one iteration costs, the last log probability, the first NaN), or None."""
    import json

    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "problem.npz")
        np.savez(path, ys=ys if ys.ndim == 3 else ys[None], F=F, Q=Q1, H=H, R=np.eye(2), x0=X0,
                 P0=P0)
        r = subprocess.run([python, os.path.join(os.path.dirname(__file__), "peers_dynamax.py"),
                            path, str(iters), str(reps)], capture_output=True, text=True)
    if r.returncode != 0:
        tail = r.stderr.strip().splitlines()[-1] if r.stderr.strip() else "no output"
        print(f"  (dynamax failed: {tail})", file=sys.stderr)
        return None
    return json.loads(r.stdout.strip().splitlines()[-1])


def _dynamax_note(res: dict) -> str:
    nan = (f"log probability NaN from iteration {res['first_nan']}"
           if res["first_nan"] is not None else "no NaN")
    return (f"every parameter learned; {res['fixed']:.2f} s of a call is tracing and "
            f"compiling (a call of one iteration), again on every call; first call "
            f"{res['first']:.2f} s; {nan}")


def cold_first_call(prebuilt: bool = True) -> float:
    """Seconds for a fresh process, numba's and vistrack's caches empty, to import vistrack
    and run 50 iterations on one series; with the kernels compiled at install, or not
    (``VISTRACK_PREBUILT=0``: compiled on first use)."""
    code = ("import time; t = time.perf_counter(); import sys; sys.path.insert(0, 'bench'); "
            "import bench_em as b; b.vistrack_fit(b.data(1), 50); "
            "print(time.perf_counter() - t)")
    with tempfile.TemporaryDirectory() as d:
        env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(d, "numba"),
                   VISTRACK_CACHE_DIR=os.path.join(d, "kernels"),
                   VISTRACK_PREBUILT="1" if prebuilt else "0")
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, check=True, cwd=os.path.dirname(os.path.dirname(
                               os.path.abspath(__file__))))
    return float(r.stdout.split()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="fewer repeats")
    ap.add_argument("--write", metavar="MD", help="write the results into this markdown file")
    ap.add_argument("--dynamax-python", default=os.path.join(
        os.path.dirname(os.path.dirname(os.path.abspath(__file__))), ".venv-dynamax", "bin",
        "python"), help="an interpreter with dynamax (default .venv-dynamax/bin/python)")
    args = ap.parse_args()
    dx_python = args.dynamax_python if os.path.exists(args.dynamax_python) else None
    if dx_python is None:
        print(f"  (dynamax skipped: {args.dynamax_python} does not exist; make bench-peers "
              "makes it)", file=sys.stderr)
    reps = 2 if args.quick else 5
    one, batch = data(1), data(100)
    rows: list[tuple[str, str, str, str, str]] = []  # what, library, seconds, ratio, note

    t_struct, fit = median_time(lambda: vistrack_fit(one, 50), reps)
    t_full, fit_full = median_time(lambda: vistrack_fit(one, 50, structured=False), reps)
    base = t_struct
    rows.append(("one series, 50 iterations", "vistrack, q and R's diagonal", f"{t_struct:.3f}",
                 "1.0", f"q {fit.q:.3f}, R {np.diag(fit.R).round(2).tolist()}"))
    rows.append(("", "vistrack, full Q and R", f"{t_full:.3f}", f"{t_full / base:.1f}", ""))
    pk = optional("pykalman")
    if pk is not None:
        n = 2

        def pk_fit():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return pk.KalmanFilter(
                    transition_matrices=F, observation_matrices=H, transition_covariance=np.eye(4),
                    observation_covariance=np.eye(2), initial_state_mean=X0,
                    initial_state_covariance=P0,
                    em_vars=["transition_covariance", "observation_covariance"]).em(one, n_iter=n)

        t, kf = median_time(pk_fit, 1)
        same = vistrack_fit(one, n, structured=False)
        diff = max(float(np.max(np.abs(same.Q - kf.transition_covariance))),
                   float(np.max(np.abs(same.R - kf.observation_covariance))))
        rows.append(("", "pykalman EM (full Q, R)", f"{t * 50 / n:.1f}",
                     _ratio(t * 50 / n / base),
                     f"{n} iterations timed; its Q and R equal vistrack's full fit after them "
                     f"to {diff:.0e}"))
    sk = optional("simdkalman")
    if sk is not None:
        n = 2
        kf = sk.KalmanFilter(state_transition=F, process_noise=np.eye(4), observation_model=H,
                             observation_noise=np.eye(2))
        t, _ = median_time(lambda: kf.em(one[None], n_iter=n, **_simd_prior(1)), 1)
        rows.append(("", "simdkalman EM (full Q, R)", f"{t * 50 / n:.1f}",
                     _ratio(t * 50 / n / base), f"{n} iterations timed"))
    dx_one = dynamax_fit(dx_python, one, 50, reps) if dx_python else None
    if dx_one is not None:
        rows.append(("", "dynamax EM (`fit_em`)", f"{dx_one['median']:.2f}",
                     _ratio(dx_one['median'] / base), _dynamax_note(dx_one)))
    t_sm = None
    res = None
    if optional("statsmodels") is not None:
        t_sm, res = median_time(lambda: statsmodels_fit(one), max(1, reps // 2))
        rows.append(("", "statsmodels MLE (L-BFGS on q, r_x, r_y)", f"{t_sm:.2f}",
                     _ratio(t_sm / base), f"to its optimum, log-likelihood {res.llf:.2f}"))
    # EM to convergence against statsmodels' maximum
    t_conv, conv = median_time(lambda: vistrack_fit(one, 5000, tol=1e-6), reps)
    gap = f", {res.llf - conv.loglik[-1]:+.4f} nats from statsmodels' maximum" if res else ""
    rows.append(("one series, to the maximum", "vistrack EM (tol 1e-6), q and R's diagonal",
                 f"{t_conv:.3f}", f"{t_conv / t_sm:.2f} of statsmodels'" if t_sm else "",
                 f"{conv.iterations} iterations, log-likelihood {conv.loglik[-1]:.2f}{gap}"))
    t_ml, ml = median_time(lambda: mle(one, F=F, Q=Q1, H=H, R=np.eye(2), x0=X0, P0=P0), reps)
    gap = f", {res.llf - ml.loglik[-1]:+.4f} nats from statsmodels' maximum" if res else ""
    rows.append(("", "vistrack ML (L-BFGS, exact gradient, standard errors)", f"{t_ml:.3f}",
                 f"{t_ml / t_sm:.2f} of statsmodels'" if t_sm else "",
                 f"{ml.iterations} iterations, q {ml.q:.3f} ± {ml.stderr['q']:.3f}, "
                 f"log-likelihood {ml.loglik[-1]:.2f}{gap}"))

    t_b, fb = median_time(lambda: vistrack_fit(batch, 50), max(1, reps // 2))
    rows.append(("100 series pooled, 50 iterations", "vistrack, q and R's diagonal",
                 f"{t_b:.2f}", "1.0",
                 f"q {fb.q:.3f}, R {np.diag(fb.R).round(3).tolist()}"))
    dx_batch = dynamax_fit(dx_python, batch, 50, max(1, reps // 2)) if dx_python else None
    if dx_batch is not None:
        rows.append(("", "dynamax EM (`fit_em`)", f"{dx_batch['median']:.2f}",
                     f"{dx_batch['median'] / t_b:.1f}", _dynamax_note(dx_batch)))
    if sk is not None:
        kf = sk.KalmanFilter(state_transition=F, process_noise=np.eye(4), observation_model=H,
                             observation_noise=np.eye(2))
        t, _ = median_time(lambda: kf.em(batch, n_iter=1, **_simd_prior(len(batch))), 1)
        rows.append(("", "simdkalman EM (100 separate fits)", f"{t * 50:.1f}",
                     _ratio(t * 50 / t_b), "1 iteration timed"))
    t_bm, bm = median_time(lambda: mle(batch, F=F, Q=Q1, H=H, R=np.eye(2), x0=X0, P0=P0),
                           max(1, reps // 2))
    rows.append(("100 series pooled, to the maximum", "vistrack ML (L-BFGS)", f"{t_bm:.2f}",
                 f"{t_bm / t_b:.2f}", f"{bm.iterations} iterations, q {bm.q:.3f} ± "
                 f"{bm.stderr['q']:.3f}, R {bm.r.round(3).tolist()} ± "
                 f"{bm.stderr['r'].round(3).tolist()}"))
    cold, jit = cold_first_call(), cold_first_call(prebuilt=False)
    rows.append(("first call, caches empty", "vistrack (import and 50 iterations)",
                 f"{cold:.1f}", "", f"a fresh process; {jit:.1f} s with the kernels compiled "
                 "on first use instead of at install"))

    def met(ok: bool) -> str:
        return "met" if ok else "not met"

    goals = [f"- one series, 50 iterations ≤ 0.1 s: {t_struct:.3f} s, {met(t_struct <= 0.1)}"]
    if res is not None:
        gaps = (res.llf - conv.loglik[-1], res.llf - ml.loglik[-1])
        goals.append(f"- at statsmodels' maximum within 0.01 nats: EM {gaps[0]:+.4f}, ML "
                     f"{gaps[1]:+.4f}, {met(max(map(abs, gaps)) <= 0.01)}")
        goals.append(f"- ≥ 50× the fastest peer end to end: statsmodels reaches the maximum in "
                     f"{t_sm:.3f} s, vistrack's maximum likelihood in {t_ml:.3f} s "
                     f"({t_sm / t_ml:.1f}×), {met(t_sm / t_ml >= 50)}")
    if dx_one is not None:
        r1 = dx_one["median"] / t_struct
        goals.append(f"- one series, 50 iterations, ≥ 50× dynamax's EM: {r1:.0f}×, "
                     f"{met(r1 >= 50)}")
    dx = (f"{dx_batch['median'] / t_b:.1f}× dynamax's {dx_batch['median']:.2f} s, "
          f"{met(dx_batch['median'] / t_b >= 7)}" if dx_batch is not None
          else "against dynamax: not measured (not installed here)")
    goals.append(f"- 100 series pooled, 50 iterations ≤ 2 s: {t_b:.2f} s, {met(t_b <= 2)}; "
                 f"≥ 7× dynamax: {dx}")
    goals.append(f"- on the batch, q within 5 % of 0.5 and R's diagonal within 3 % of 4 (at the "
                 f"maximum): q {bm.q:.3f}, R {bm.r.round(3).tolist()}, "
                 f"{met(abs(bm.q / 0.5 - 1) <= 0.05 and bool(np.all(abs(bm.r / 4 - 1) <= 0.03)))}")
    goals.append(f"- first call with empty caches ≤ 20 s: {cold:.1f} s, {met(cold <= 20)}")

    head = ("| problem | library | seconds | times vistrack's | note |\n"
            "|---|---|---:|---:|---|\n")
    table = head + "\n".join("| " + " | ".join(r) + " |" for r in rows) + "\n"
    cmd = "python bench/bench_em.py" + (" --quick" if args.quick else "")
    section = (f"## Learning Q and R (EM)\n\nMeasured with `{cmd}` (CPython "
               f"{platform.python_version()}, numpy {np.__version__}, one thread). "
               f"{__doc__.split(chr(10) + chr(10), 2)[2].strip()}\n\n{table}\nGoals:\n\n"
               + "\n".join(goals) + "\n")
    publish(section, args.write)


if __name__ == "__main__":
    main()

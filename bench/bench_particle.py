"""Particle filter and UKF speed: vistrack beside the libraries a user would pick instead.

    python bench/bench_particle.py [--quick] [--write docs/benchmarks.md]

Particle filter: the univariate growth model (q = 10, r = 1), 100 steps, systematic resampling
every step, N = 1,000 and N = 100,000, one core. Every implementation runs in this process on
the same measurements; the table gives the median time per step of a few runs and the RMSE of
the filtered mean against the simulated states. UKF and EKF: 2-D coordinated turn with
range-bearing measurements, one predict + update per call; the EKF's means are checked against
FilterPy's (its `ExtendedKalmanFilter` given the model's f, Jacobians and residual) before the
times are reported. EnKF: the same problem with 100 and 1,000 members beside FilterPy's
`EnsembleKalmanFilter`, each with its RMSE over four seeds. IMM: two constant-velocity
Kalman filters beside FilterPy's `IMMEstimator`, checked equal likewise.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
import warnings

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import vistrack as vt  # noqa: E402
from vistrack.filters import (  # noqa: E402
    ExtendedKalmanFilter,
    ParticleFilter,
    UnscentedKalmanFilter,
    ekf_predict,
    ekf_update,
    ukf_predict,
    ukf_update,
)

from _common import median_time, optional  # noqa: E402  (bench/ is on the path of its scripts)
from _markdown import publish  # noqa: E402

T = 100


def growth_f(x, t):
    return x / 2 + 25 * x / (1 + x * x) + 8 * np.cos(1.2 * t)


def numpy_sir(ys, N, rng, resample_fn=None):
    """A plain-numpy bootstrap filter: what a user writes by hand."""
    x = rng.normal(0.0, np.sqrt(5.0), N)
    means = np.empty(len(ys))
    for t, y in enumerate(ys[:, 0]):
        if t > 0:
            x = growth_f(x, t) + rng.normal(0.0, np.sqrt(10.0), N)
        logw = -0.5 * (y - x * x / 20) ** 2
        w = np.exp(logw - logw.max())
        w /= w.sum()
        means[t] = w @ x
        if resample_fn is None:
            idx = np.searchsorted(np.cumsum(w), (rng.random() + np.arange(N)) / N)
            x = x[np.minimum(idx, N - 1)]
        else:
            x = x[resample_fn(w)]
    return means


def numba_sir(ys, N, seed):
    """A plain numba bootstrap filter, what a numba user writes (compiled on first use)."""
    from numba import njit

    global _numba_sir
    if "_numba_sir" not in globals():
        @njit(cache=True)
        def run(ys, N, seed):
            np.random.seed(seed)
            T = ys.shape[0]
            x = np.sqrt(5.0) * np.random.standard_normal(N)
            w, cw, xn, means = np.empty(N), np.empty(N), np.empty(N), np.empty(T)
            for t in range(T):
                if t > 0:
                    c = 8 * np.cos(1.2 * t)
                    for i in range(N):
                        v = x[i]
                        x[i] = (v / 2 + 25 * v / (1 + v * v) + c
                                + np.sqrt(10.0) * np.random.standard_normal())
                top = -np.inf
                for i in range(N):
                    d = ys[t] - x[i] * x[i] / 20
                    w[i] = -0.5 * d * d
                    top = max(top, w[i])
                s = 0.0
                for i in range(N):
                    w[i] = np.exp(w[i] - top)
                    s += w[i]
                m, c = 0.0, 0.0
                for i in range(N):
                    w[i] /= s
                    m += w[i] * x[i]
                    c += w[i]
                    cw[i] = c
                means[t] = m
                u0, j = np.random.random(), 0
                for k in range(N):  # systematic resampling
                    while j < N - 1 and cw[j] < (k + u0) / N:
                        j += 1
                    xn[k] = x[j]
                x, xn = xn, x
            return means

        _numba_sir = run
    return _numba_sir(ys, N, seed)


def particle_rows(rows, repeats, sizes):
    motion, meas = vt.models.growth_model()
    xs, ys = vt.simulate.simulate(motion, meas, T, x0=[0.1], rng=1)
    truth = xs[:, 0]

    def rmse(m):
        return float(np.sqrt(np.mean((np.asarray(m) - truth) ** 2)))

    fp = optional("filterpy.monte_carlo")
    pfl = optional("pfilter")
    prt = optional("particles")
    for N in sizes:
        label = f"particle filter, growth model, N = {N:,}"
        pf = ParticleFilter(motion, meas, n_particles=N, ess_threshold=1.0, rng=2)
        sec, res = median_time(lambda: pf.filter(ys, x0=[0.0], P0=[[5.0]]), repeats)
        rows.append((label, "vistrack ParticleFilter", sec / T * 1e3, rmse(res.means[:, 0])))
        rng = np.random.default_rng(3)
        sec, m = median_time(lambda: numpy_sir(ys, N, rng), repeats)
        rows.append((label, "plain numpy SIR", sec / T * 1e3, rmse(m)))
        numba_sir(ys[:, 0], 10, 0)  # compile outside the timing
        sec, m = median_time(lambda: numba_sir(ys[:, 0], N, 3), repeats)
        rows.append((label, "plain numba SIR", sec / T * 1e3, rmse(m)))
        if fp is not None:
            from filterpy.monte_carlo import systematic_resample

            sec, m = median_time(lambda: numpy_sir(ys, N, rng, systematic_resample), 1)
            rows.append((label, "numpy + FilterPy systematic_resample", sec / T * 1e3, rmse(m)))
        if pfl is not None:
            def run_pfilter():
                f = pfl.ParticleFilter(
                    prior_fn=lambda n: np.random.normal(0, np.sqrt(5.0), (n, 1)),
                    observe_fn=lambda x, **kw: x ** 2 / 20,
                    n_particles=N,
                    dynamics_fn=lambda x, t=0, **kw: growth_f(x, t),
                    noise_fn=lambda x, **kw: x + np.random.normal(0, np.sqrt(10.0), x.shape),
                    weight_fn=lambda x, y, **kw: np.exp(-0.5 * ((x - y) ** 2).sum(1)),
                    resample_proportion=0.0,
                    resample_fn=pfl.systematic_resample,
                )
                out = []
                for t in range(T):
                    f.update(ys[t][None], t=t)
                    out.append(f.mean_state[0])
                return out

            np.random.seed(4)
            sec, m = median_time(run_pfilter, 1)
            rows.append((label, "pfilter (systematic_resample)", sec / T * 1e3, rmse(m)))
        if prt is not None:
            from particles import distributions as dists
            from particles import state_space_models as ssm
            from particles.collectors import Moments

            class Growth(ssm.StateSpaceModel):
                def PX0(self):
                    return dists.Normal(loc=0.0, scale=np.sqrt(5.0))

                def PX(self, t, xp):
                    return dists.Normal(loc=growth_f(xp, t), scale=np.sqrt(10.0))

                def PY(self, t, xp, x):
                    return dists.Normal(loc=x ** 2 / 20, scale=1.0)

            def run_particles():
                fk = ssm.Bootstrap(ssm=Growth(), data=ys[:, 0])
                alg = prt.SMC(fk=fk, N=N, resampling="systematic", ESSrmin=1.0,
                              collect=[Moments()], store_history=False)
                alg.run()
                return [s["mean"] for s in alg.summaries.moments]

            sec, m = median_time(run_particles, 1)
            rows.append((label, "particles (SMC, systematic)", sec / T * 1e3, rmse(m)))


def _turn(states=False):
    """The UKF's and EKF's problem: a coordinated turn seen by range and bearing, 200
    steps, and the first step's prior (and the simulated states, with ``states``)."""
    motion, meas = vt.models.CoordinatedTurn(q=0.05, q_turn=1e-3), vt.models.RangeBearing(
        1.0, 1e-3, ndim_state=5)
    xs, zs = vt.simulate.simulate(motion, meas, 200, x0=[-20.0, 8.0, 0.0, -0.8, 0.01], rng=5)
    x0, P0 = np.array([-20.0, 8.0, 0.0, -0.8, 0.01]), np.diag([4.0, 4.0, 0.5, 0.5, 1e-3])
    return (motion, meas, zs, x0, P0) + ((xs,) if states else ())


def _vistrack_rows(rows, repeats, label, name, predict, update, flt):
    """vistrack's functions (``name_predict`` + ``name_update``, a Gaussian each call) and
    its filter ``flt`` on :func:`_turn`'s problem, per step."""
    motion, meas, zs, x0, P0 = _turn()

    def functional():
        g = update(vt.Gaussian(x0, P0), zs[0], meas)  # (x0, P0: the first step's prior)
        for z in zs[1:]:
            g = update(predict(g, motion), z, meas)

    sec, _ = median_time(functional, repeats)
    rows.append((label, f"vistrack {name}_predict + {name}_update", sec / len(zs) * 1e3, None))
    sec, _ = median_time(lambda: flt.filter(zs, x0=x0, P0=P0), repeats)
    rows.append((label, f"vistrack {type(flt).__name__}.filter, per step",
                 sec / len(zs) * 1e3, None))


def ukf_rows(rows, repeats):
    motion, meas, zs, x0, P0 = _turn()
    label = "UKF, coordinated turn + range-bearing, one predict + update"
    _vistrack_rows(rows, repeats, label, "ukf", ukf_predict, ukf_update,
                   UnscentedKalmanFilter(motion, meas))
    if optional("filterpy") is not None:
        from filterpy.kalman import MerweScaledSigmaPoints
        from filterpy.kalman import UnscentedKalmanFilter as FPU

        def filterpy_run():
            kf = FPU(dim_x=5, dim_z=2, dt=1.0, points=MerweScaledSigmaPoints(5, 1e-3, 2.0, 0.0),
                     fx=lambda x, dt: motion.f(x, dt), hx=meas.h, residual_z=meas.residual,
                     z_mean_fn=meas.mean)
            kf.x, kf.P, kf.Q, kf.R = x0.copy(), P0.copy(), motion.Q(1.0), meas.R()
            for k, z in enumerate(zs):
                if k:  # (the first step's prior is x0, P0, as vistrack's filter takes it)
                    kf.predict()
                kf.update(z)

        sec, _ = median_time(filterpy_run, repeats)
        rows.append((label, "FilterPy UnscentedKalmanFilter", sec / len(zs) * 1e3, None))


def ekf_rows(rows, repeats):
    """The UKF's problem through the EKF: vistrack's functions and filter, and FilterPy's
    ExtendedKalmanFilter (its predict_x given the model's f, its F the model's Jacobian)."""
    motion, meas, zs, x0, P0 = _turn()
    label = "EKF, coordinated turn + range-bearing, one predict + update"
    flt = ExtendedKalmanFilter(motion, meas)
    _vistrack_rows(rows, repeats, label, "ekf", ekf_predict, ekf_update, flt)
    if optional("filterpy") is not None:
        from filterpy.kalman import ExtendedKalmanFilter as FPE

        class Turn(FPE):
            def predict_x(self, u=0):
                self.x = motion.f(self.x, 1.0)

        def filterpy_run():
            kf = Turn(dim_x=5, dim_z=2)
            kf.x, kf.P, kf.Q, kf.R = x0.copy(), P0.copy(), motion.Q(1.0), meas.R()
            means = []
            for k, z in enumerate(zs):
                if k:  # (the first step's prior is x0, P0, as vistrack's filter takes it)
                    kf.F = motion.jacobian(kf.x, 1.0)
                    kf.predict()
                kf.update(z, meas.jacobian, meas.h, residual=meas.residual)
                means.append(kf.x.copy())
            return np.array(means)

        gap = np.abs(filterpy_run() - flt.filter(zs, x0=x0, P0=P0).means).max()
        if not gap < 1e-9:
            raise SystemExit(f"the EKFs disagree: vistrack's means and FilterPy's differ by {gap}")
        sec, _ = median_time(filterpy_run, repeats)
        rows.append((label, "FilterPy ExtendedKalmanFilter", sec / len(zs) * 1e3, None))


def enkf_rows(rows, repeats, sizes):
    """The UKF's problem through the stochastic EnKF of ``N`` members: vistrack's
    `EnsembleKalmanFilter.filter` and FilterPy's `EnsembleKalmanFilter`. The draws differ, so
    the two are compared by the RMSE of the filtered positions against the simulated states
    over four seeds. FilterPy takes no residual: its ``hx`` gives each member's bearing
    within half a turn of the step's measured one, which makes ``z - hx`` the wrapped residual
    vistrack's model gives (the bearing crosses ±π on this track)."""
    from vistrack.filters import EnsembleKalmanFilter

    motion, meas, zs, x0, P0, xs = _turn(states=True)

    def rmse(means):
        return float(np.sqrt(np.mean(np.sum((means[:, :2] - xs[:, :2]) ** 2, axis=1))))

    for N in sizes:
        label = (f"EnKF, coordinated turn + range-bearing, N = {N:,} members, "
                 "one predict + update")
        seeds = range(5)
        flts = [EnsembleKalmanFilter(motion, meas, N, rng=s) for s in seeds]
        sec, _ = median_time(lambda: flts[0].filter(zs, x0=x0, P0=P0), repeats)
        err = np.mean([rmse(f.filter(zs, x0=x0, P0=P0).means) for f in flts[1:]])
        rows.append((label, "vistrack EnsembleKalmanFilter.filter, per step",
                     sec / len(zs) * 1e3, err))
        if optional("filterpy") is None:
            continue
        from filterpy.kalman import EnsembleKalmanFilter as FPEn

        def filterpy_run(seed):
            np.random.seed(seed)  # (FilterPy draws from numpy's global generator)
            ref = [0.0]

            def hx(x):
                r, b = meas.h(x)
                return np.array([r, ref[0] + (b - ref[0] + np.pi) % (2 * np.pi) - np.pi])

            kf = FPEn(x=x0.copy(), P=P0.copy(), dim_z=2, dt=1.0, N=N, hx=hx,
                      fx=lambda x, dt: motion.f(x, dt))
            kf.Q, kf.R = motion.Q(1.0), meas.R()
            means = []
            for k, z in enumerate(zs):
                if k:  # (the first step's prior is x0, P0, as vistrack's filter takes it)
                    kf.predict()
                ref[0] = z[1]
                kf.update(z)
                means.append(kf.x.copy())
            return np.array(means)

        sec, _ = median_time(lambda: filterpy_run(0), max(1, repeats if N <= 100 else 1))
        err = np.mean([rmse(filterpy_run(s)) for s in seeds[1:]])
        rows.append((label, "FilterPy EnsembleKalmanFilter", sec / len(zs) * 1e3, err))


def imm_rows(rows, repeats):
    """An IMM of two constant-velocity Kalman filters (2-D, q = 0.01 and 10, positions seen
    with unit noise, switching 3 % a step) on a random walk of 500 steps: vistrack's
    `IMMFilter` of `KalmanFilter` members, and FilterPy's `IMMEstimator` of its
    `KalmanFilter`s given the same matrices; the combined means are checked equal to 1e-9
    before the times are reported."""
    from vistrack.filters import IMMFilter, KalmanFilter

    rng = np.random.default_rng(0)
    T = 500
    ys = np.cumsum(rng.normal(0, 1, (T, 2)), 0)
    slow, fast = vt.ConstantVelocity(dim=2, q=0.01), vt.ConstantVelocity(dim=2, q=10.0)
    pos = vt.Position(dim=2, r=1.0)
    Pi = np.array([[0.97, 0.03], [0.03, 0.97]])
    x0, P0 = np.zeros(4), np.eye(4) * 10.0
    label = "IMM of two Kalman filters (2-D constant velocity), one step"
    imm = IMMFilter([KalmanFilter(slow, pos), KalmanFilter(fast, pos)], Pi)
    sec, res = median_time(lambda: imm.filter(ys, x0=x0, P0=P0), repeats)
    rows.append((label, "vistrack IMMFilter.filter", sec / T * 1e3, None))
    if optional("filterpy") is not None:
        from filterpy.kalman import IMMEstimator
        from filterpy.kalman import KalmanFilter as FPK

        def filterpy_run():
            members = []
            for model in (slow, fast):
                k = FPK(dim_x=4, dim_z=2)
                k.F, k.Q, k.H, k.R = model.F(1.0), model.Q(1.0), pos.H(4), pos.R()
                k.x, k.P = x0.copy(), P0.copy()
                members.append(k)
            # (FilterPy weighs the first measurement by mu Π: the mu that makes it uniform)
            est = IMMEstimator(members, np.linalg.solve(Pi.T, [0.5, 0.5]), Pi)
            out = []
            for k, y in enumerate(ys):
                if k:
                    est.predict()
                est.update(y)
                out.append(est.x.copy())
            return np.array(out)

        sec, theirs = median_time(filterpy_run, repeats)
        gap = np.abs(theirs - res.means).max()
        if not gap < 1e-9:
            raise SystemExit(f"the IMMs disagree: vistrack's means and FilterPy's differ by {gap}")
        rows.append((label, "FilterPy IMMEstimator", sec / T * 1e3, None))


def to_markdown(rows):
    out, current = [], None
    for label, lib, ms, rmse in rows:
        if label != current:
            current, ref = label, ms
            out += ["", f"**{label}**", "",
                    "| library | ms/step | times slower than vistrack | RMSE |",
                    "|---|---:|---:|---:|"]
        r = "" if rmse is None else f"{rmse:.2f}"
        out.append(f"| {lib} | {ms:.3g} | {ms / ref:.2g} | {r} |")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="N = 1,000 only")
    ap.add_argument("--write", metavar="MD",
                    help="replace the particle-filter section of this file")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    rows = []
    print("particle filter ...", file=sys.stderr)
    particle_rows(rows, 7, (1000,) if args.quick else (1000, 100_000))
    print("UKF ...", file=sys.stderr)
    ukf_rows(rows, 5)
    print("EKF ...", file=sys.stderr)
    ekf_rows(rows, 5)
    print("EnKF ...", file=sys.stderr)
    enkf_rows(rows, 5, (100,) if args.quick else (100, 1000))
    print("IMM ...", file=sys.stderr)
    imm_rows(rows, 5)
    import numba

    env = (f"Python {platform.python_version()}, numpy {np.__version__}, "
           f"numba {numba.__version__}, "
           f"{platform.machine()}, one core, {time.strftime('%Y-%m-%d')}")
    cmd = "python bench/bench_particle.py" + (" --quick" if args.quick else "")
    section = (f"## Particle filter and UKF\n\nMeasured with `{cmd}` ({env}). RMSE: of the "
               f"filtered mean against the simulated states.\n{to_markdown(rows)}\n")
    publish(section, args.write)


if __name__ == "__main__":
    main()

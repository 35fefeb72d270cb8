"""Kalman filter and smoother speed: vistrack beside the libraries a user would pick instead.

    python bench/bench_kalman.py [--quick] [--write docs/benchmarks.md]

Model everywhere: 2-D constant velocity (4 states), 2-D position measurements, float64, one core.
Every library runs in this one process on the same data; each number is the median of several
repeats, and ratios are against vistrack on the same row. Results of a slow library on a long
problem are measured on a shorter one and given per step (said in the table).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
import warnings

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import vistrack as vt  # noqa: E402

from _common import optional  # noqa: E402  (bench/ is on the path of its scripts)
from _markdown import publish  # noqa: E402

F = vt.ConstantVelocity(dim=2).F(1.0)
Q = 0.1 * np.eye(4)
H = np.eye(2, 4)
R = np.eye(2)
X0 = np.zeros(4)
P0 = 10.0 * np.eye(4)


def median_time(fn, repeats: int) -> float:
    fn()  # warm-up (compilation, caches)
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


# ---------------------------------------------------------------- per-step from Python
def per_step(rows, repeats):
    steps = 2000
    z = np.ones(2)

    def vistrack_step():
        g = vt.Gaussian(X0, P0)
        for _ in range(steps):
            g = vt.kf_update(vt.kf_predict(g, F, Q), z, H, R)

    def vistrack_fused():
        g = vt.Gaussian(X0, P0)
        for _ in range(steps):
            g = vt.kf_step(g, z, F, Q, H, R)

    def vistrack_online():
        f = vt.KalmanFilter(vt.LinearMotion(F, Q), vt.LinearMeasurement(H, R)).online(X0, P0)
        for _ in range(steps):
            f.step(z)

    rows.append(("one predict + update from Python", "vistrack OnlineFilter.step",
                 median_time(vistrack_online, repeats) / steps * 1e6, "µs/step"))
    rows.append(("one predict + update from Python", "vistrack kf_step",
                 median_time(vistrack_fused, repeats) / steps * 1e6, "µs/step"))
    rows.append(("one predict + update from Python", "vistrack kf_predict + kf_update",
                 median_time(vistrack_step, repeats) / steps * 1e6, "µs/step"))
    n_tracks = 100
    zs = np.ones((n_tracks, 2))

    def vistrack_tracks():
        g = vt.Gaussian(np.tile(X0, (n_tracks, 1)), np.tile(P0, (n_tracks, 1, 1)))
        for _ in range(steps // 10):
            g = vt.kf_update(vt.kf_predict(g, F, Q), zs, H, R)

    rows.append(("one predict + update from Python",
                 f"vistrack kf_predict + kf_update on {n_tracks} tracks at once, per track",
                 median_time(vistrack_tracks, repeats) / (steps // 10) / n_tracks * 1e6,
                 "µs/step"))
    fk = optional("filterpy.kalman")
    if fk is not None:
        import filterpy.kalman as fk

        def filterpy_step():
            kf = fk.KalmanFilter(dim_x=4, dim_z=2)
            kf.F, kf.Q, kf.H, kf.R, kf.x, kf.P = F, Q, H, R, X0.copy(), P0.copy()
            for _ in range(steps):
                kf.predict()
                kf.update(z)

        rows.append(("one predict + update from Python", "FilterPy",
                     median_time(filterpy_step, repeats) / steps * 1e6, "µs/step"))
    cv2 = optional("cv2")
    if cv2 is not None:
        zz = np.ones((2, 1))

        def opencv_step():
            k = cv2.KalmanFilter(4, 2, 0, cv2.CV_64F)
            k.transitionMatrix, k.measurementMatrix = F.copy(), H.copy()
            k.processNoiseCov, k.measurementNoiseCov = Q.copy(), R.copy()
            k.statePost, k.errorCovPost = X0.reshape(4, 1).copy(), P0.copy()
            for _ in range(steps):
                k.predict()
                k.correct(zz)

        rows.append(("one predict + update from Python", "OpenCV cv2.KalmanFilter",
                     median_time(opencv_step, repeats) / steps * 1e6, "µs/step"))
    pk = optional("pykalman")
    if pk is not None:
        kfp = pk.KalmanFilter(transition_matrices=F, observation_matrices=H,
                              transition_covariance=Q, observation_covariance=R)
        n_pk = 200

        def pykalman_step():
            m, P = X0, P0
            for _ in range(n_pk):
                m, P = kfp.filter_update(m, P, z)

        rows.append(("one predict + update from Python", "pykalman (filter_update)",
                     median_time(pykalman_step, repeats) / n_pk * 1e6, "µs/step"))


# ---------------------------------------------------------------- one long series
def one_series(rows, repeats, T):
    rng = np.random.default_rng(0)
    ys = rng.normal(size=(T, 2)).cumsum(0)
    label = f"one series, whole-sequence filter (T={T:,})"
    t = median_time(lambda: vt.kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=X0, P0=P0), repeats)
    rows.append((label, "vistrack", t / T * 1e6, "µs/step"))
    t = median_time(
        lambda: vt.kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=X0, P0=P0, store_covs=False), repeats)
    rows.append((label, "vistrack, store_covs=False (means only)", t / T * 1e6, "µs/step"))
    label2 = f"filter + RTS smoother, one series (T={T:,})"

    def vt_both():
        res = vt.kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=X0, P0=P0)
        vt.rts_smooth(res, F=F, Q=Q)

    rows.append((label2, "vistrack", median_time(vt_both, repeats), "s"))
    short = min(T, 10_000)
    ys_s = ys[:short]
    scale = T / short
    if optional("filterpy") is not None:
        import filterpy.kalman as fk

        kf = fk.KalmanFilter(dim_x=4, dim_z=2)
        kf.F, kf.Q, kf.H, kf.R = F, Q, H, R

        def fp_filter():
            kf.x, kf.P = X0.copy(), P0.copy()
            ms, Ps = np.empty((short, 4)), np.empty((short, 4, 4))
            for i, y in enumerate(ys_s):
                if i:
                    kf.predict()
                kf.update(y)
                ms[i], Ps[i] = kf.x, kf.P
            return ms, Ps

        rows.append((label, "FilterPy (predict/update loop)",
                     median_time(fp_filter, 1) / short * 1e6, "µs/step"))

        def fp_both():
            ms, Ps = fp_filter()
            kf.rts_smoother(ms, Ps)

        rows.append((label2, f"FilterPy (loop + rts_smoother; T={short:,}, ×{scale:g})",
                     median_time(fp_both, 1) * scale, "s"))
    pk = optional("pykalman")
    if pk is not None:
        n_pk = min(T, 2000)
        kfp = pk.KalmanFilter(transition_matrices=F, observation_matrices=H,
                              transition_covariance=Q, observation_covariance=R,
                              initial_state_mean=X0, initial_state_covariance=P0)
        rows.append((label, f"pykalman (T={n_pk:,})",
                     median_time(lambda: kfp.filter(ys[:n_pk]), 1) / n_pk * 1e6, "µs/step"))
        rows.append((label2, f"pykalman (smooth; T={n_pk:,}, ×{T / n_pk:g})",
                     median_time(lambda: kfp.smooth(ys[:n_pk]), 1) * T / n_pk, "s"))
    sk = optional("simdkalman")
    if sk is not None:
        kfs = sk.KalmanFilter(state_transition=F, process_noise=Q, observation_model=H,
                              observation_noise=R)
        y3 = ys[None]
        rows.append((label, "simdkalman", median_time(
            lambda: kfs.compute(y3, 0, initial_value=X0, initial_covariance=P0, filtered=True,
                                smoothed=False), repeats) / T * 1e6, "µs/step"))
        rows.append((label2, "simdkalman", median_time(
            lambda: kfs.compute(y3, 0, initial_value=X0, initial_covariance=P0, filtered=True,
                                smoothed=True), repeats), "s"))
    if optional("statsmodels") is not None:
        from statsmodels.tsa.statespace.kalman_smoother import KalmanSmoother

        def sm_run(smooth):
            ks = KalmanSmoother(k_endog=2, k_states=4)
            ks.bind(ys.copy())
            ks["design"], ks["obs_cov"], ks["transition"] = H, R, F
            ks["selection"], ks["state_cov"] = np.eye(4), Q
            ks.initialize_known(X0, P0)
            return ks.smooth() if smooth else ks.filter()

        rows.append((label, "statsmodels",
                     median_time(lambda: sm_run(False), repeats) / T * 1e6, "µs/step"))
        rows.append((label2, "statsmodels", median_time(lambda: sm_run(True), repeats), "s"))


# ---------------------------------------------------------------- a batch of series
def batch(rows, repeats, B, T):
    rng = np.random.default_rng(1)
    ys = rng.normal(size=(B, T, 2)).cumsum(1)
    label = f"batch of {B:,} series × {T} steps"
    P0b = P0 * (1.0 + rng.random(B))[:, None, None]  # a different prior for every series
    steps = B * T

    def vt_shared():
        return vt.kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=X0, P0=P0, store_covs=False)

    def vt_general():
        return vt.kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=X0, P0=P0b, store_covs=False)

    rows.append((label, "vistrack, shared covariances (same P0 and missing pattern)",
                 steps / median_time(vt_shared, repeats) / 1e6, "M steps/s"))
    rows.append((label, "vistrack, one covariance per series "
                        "(generated kernel; steady state after ~40 steps)",
                 steps / median_time(vt_general, repeats) / 1e6, "M steps/s"))
    Fd = np.eye(4) + 0.1 * rng.normal(size=(4, 4))  # a dense model: no zeros to skip
    Ad = rng.normal(size=(4, 4))
    Qd, Hd = Ad @ Ad.T / 4 + 0.1 * np.eye(4), rng.normal(size=(2, 4))
    rows.append((label, "vistrack, one covariance per series, dense F and H (generated kernel)",
                 steps / median_time(lambda: vt.kalman_filter(
                     ys, F=Fd, Q=Qd, H=Hd, R=R, x0=X0, P0=P0b, store_covs=False), repeats) / 1e6,
                 "M steps/s"))
    # the loop kernel that serves models too large for generated code (n > 6 or m > 3)
    from vistrack.filters import _codegen

    min_steps, _codegen.MIN_STEPS = _codegen.MIN_STEPS, 1 << 62
    try:
        rows.append((label, "vistrack, one covariance per series, loop kernel (any size)",
                     steps / median_time(lambda: vt.kalman_filter(
                         ys, F=F, Q=Q, H=H, R=R, x0=X0, P0=P0b, store_covs=False), repeats)
                     / 1e6, "M steps/s"))
        rows.append((label, "vistrack, loop kernel, dense F and H",
                     steps / median_time(lambda: vt.kalman_filter(
                         ys, F=Fd, Q=Qd, H=Hd, R=R, x0=X0, P0=P0b, store_covs=False), repeats)
                     / 1e6, "M steps/s"))
    finally:
        _codegen.MIN_STEPS = min_steps
    ys_m = ys.copy()
    ys_m[rng.random((B, T)) < 0.05] = np.nan  # different missing steps per series
    rows.append((label, "vistrack, 5 % missing steps, different per series "
                        "(generated kernel, never steady)",
                 steps / median_time(lambda: vt.kalman_filter(
                     ys_m, F=F, Q=Q, H=H, R=R, x0=X0, P0=P0, store_covs=False), repeats) / 1e6,
                 "M steps/s"))
    sk = optional("simdkalman")
    if sk is not None:
        kfs = sk.KalmanFilter(state_transition=F, process_noise=Q, observation_model=H,
                              observation_noise=R)
        rows.append((label, "simdkalman", steps / median_time(
            lambda: kfs.compute(ys, 0, initial_value=X0, initial_covariance=P0, filtered=True,
                                smoothed=False), repeats) / 1e6, "M steps/s"))
    if optional("filterpy") is not None:
        import filterpy.kalman as fk

        nb = 20
        kf = fk.KalmanFilter(dim_x=4, dim_z=2)
        kf.F, kf.Q, kf.H, kf.R = F, Q, H, R

        def fp_loop():
            for b in range(nb):
                kf.x, kf.P = X0.copy(), P0.copy()
                for i in range(T):
                    if i:
                        kf.predict()
                    kf.update(ys[b, i])

        rows.append((label, f"FilterPy loop ({nb} series)",
                     nb * T / median_time(fp_loop, 1) / 1e6, "M steps/s"))


def to_markdown(rows) -> str:
    """One table per task, in order of first appearance; ratios against the task's first
    vistrack row (how many times slower than it)."""
    out = []
    for task in dict.fromkeys(r[0] for r in rows):
        group = [r for r in rows if r[0] == task]
        unit = group[0][3]
        ref = next(v for _, lib, v, _ in group if lib.startswith("vistrack"))
        out += ["", f"**{task}**", "", f"| library | {unit} | times slower than vistrack |",
                "|---|---:|---:|"]
        for _, lib, value, _ in group:
            ratio = value / ref if unit != "M steps/s" else ref / value
            out.append(f"| {lib} | {value:.3g} | {ratio:.2g} |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="small sizes, for a smoke run")
    ap.add_argument("--write", metavar="MD",
                    help="replace the Kalman section of this markdown file")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    repeats = 3 if args.quick else 5
    rows: list = []
    print("per-step ...", file=sys.stderr)
    per_step(rows, repeats)
    print("one series ...", file=sys.stderr)
    one_series(rows, repeats, 10_000 if args.quick else 100_000)
    print("batch ...", file=sys.stderr)
    batch(rows, repeats, 1000 if args.quick else 10_000, 100 if args.quick else 500)
    import numba

    env = (f"Python {platform.python_version()}, numpy {np.__version__}, "
           f"numba {numba.__version__}, "
           f"{platform.machine()}, {os.cpu_count()} cores (one used), "
           f"{time.strftime('%Y-%m-%d')}")
    table = to_markdown(rows)
    cmd = "python bench/bench_kalman.py" + (" --quick" if args.quick else "")
    section = (f"## Kalman filter and smoother\n\nMeasured with `{cmd}` ({env}). "
               "The last column: how many times slower than the first vistrack row of the table.\n"
               f"{table}\n")
    publish(section, args.write)


if __name__ == "__main__":
    main()

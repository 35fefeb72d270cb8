"""Figures of the nonlinear and multiple-model filters, from real runs of vistrack.

    python examples/nonlinear_figures.py            # writes examples/figures/*.png
    python examples/nonlinear_figures.py OUT_DIR    # writes OUT_DIR/*.png

- particle_cloud.png: one step of the particle filter on the growth model (seed 004 "Particle
  Filtering": resample, predict, spread, weight), and the cloud over 60 steps with the truth.
- p_vs_pv.png: the seed's multiple-model example (seed 000 "Multiple model filters", "MM
  estimate", "No lag", "Smooth when still"): a target that stands, walks and stands, tracked
  by a position model P, a position-velocity model PV and their IMM, with the model
  probabilities.
- ekf_ukf_pf.png: EKF, UKF and particle filter on the growth model, whose measurement x²/20
  hides the sign of x.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

import vistrack as vt
from vistrack.filters import (
    ExtendedKalmanFilter,
    IMMFilter,
    ParticleFilter,
    UnscentedKalmanFilter,
    resample,
)


def particle_cloud(out: Path, seed: int = 3) -> Path:
    motion, meas = vt.models.growth_model()
    xs, ys = vt.simulate.simulate(motion, meas, 60, x0=[0.1], rng=seed)
    N, t = 400, 21
    pf = ParticleFilter(motion, meas, n_particles=N, rng=seed)
    before = pf.filter(ys[:t], x0=[0.0], P0=[[5.0]])
    rng = np.random.default_rng(seed)
    x0 = before.particles[resample(before.weights, "systematic", rng=rng), 0]
    drift = motion.f(x0[:, None], 1.0, float(t))[:, 0]
    spread = drift + rng.normal(scale=np.sqrt(motion.q), size=N)
    logw = -0.5 * (ys[t, 0] - spread**2 / 20) ** 2
    w = np.exp(logw - logw.max())
    w /= w.sum()

    fig = Figure(figsize=(12, 7.5), layout="constrained")
    top = fig.subfigures(2, 1, height_ratios=[1, 1.1])
    axs = top[0].subplots(1, 4, sharex=True)
    jitter = rng.uniform(-0.4, 0.4, N)
    # the first panel is the cloud at step t - 1, the others step t: each with its own truth
    panels = [(x0, None, f"resampled cloud at step {t - 1}", t - 1),
              (drift, None, f"predict to step {t}: x/2 + 25x/(1+x²) + 8cos(1.2t)", t),
              (spread, None, "spread: + N(0, 10)", t),
              (spread, w, f"weight: p(y={ys[t, 0]:.1f} | x)", t)]
    for ax, (p, wt, title, step) in zip(axs, panels):
        size = 8 if wt is None else 2 + 600 * wt
        ax.scatter(p, jitter, s=size, alpha=0.5, color="C0" if wt is None else "C3", lw=0)
        ax.axvline(xs[step, 0], color="k", lw=1, ls="--", label="true state at that step")
        ax.set_title(title, fontsize=9)
        ax.set_yticks([])
        ax.set_xlabel("x")
    axs[0].legend(fontsize=8, loc="upper left")
    res = ParticleFilter(motion, meas, n_particles=2000, rng=seed).filter(
        ys, x0=[0.0], P0=[[5.0]], modes=True)
    ax = top[1].subplots()
    # density of the cloud over time, from the weighted mean and covariance is not enough
    # (the posterior is bimodal): rerun and histogram the particles step by step
    grid = np.linspace(-25, 25, 101)
    dens = np.zeros((len(grid) - 1, len(ys)))
    pf2 = ParticleFilter(motion, meas, n_particles=2000, rng=seed)
    for k in range(1, len(ys) + 1):
        r = pf2.filter(ys[:k], x0=[0.0], P0=[[5.0]])
        dens[:, k - 1] = np.histogram(r.particles[:, 0], grid, weights=r.weights)[0]
    ax.imshow(dens, origin="lower", aspect="auto", cmap="Greys",
              extent=(-0.5, len(ys) - 0.5, grid[0], grid[-1]), vmax=0.25)
    ax.plot(xs[:, 0], "k-", lw=1.5, label="true state")
    ax.plot(res.means[:, 0], "C0.", ms=4, label="weighted mean")
    ax.plot(res.modes[:, 0], "C3x", ms=4, label="mode (mean of the tallest peak)")
    ax.set_xlabel("step")
    ax.set_ylabel("x")
    ax.set_title("the cloud over time (grey: particle density)", fontsize=10)
    ax.legend(fontsize=8, loc="upper right", ncols=3)
    path = out / "particle_cloud.png"
    fig.savefig(path, dpi=110)
    return path


def p_vs_pv(out: Path, seed: int = 0) -> Path:
    v = np.r_[np.zeros(40), np.full(40, 0.5), np.zeros(40)]
    x = np.cumsum(v)
    ys = (x + np.random.default_rng(seed).normal(scale=np.sqrt(0.05), size=len(x)))[:, None]
    P = ExtendedKalmanFilter(vt.ConstantPosition(dim=1, q=1e-4), vt.Position(dim=1, r=0.05))
    PV = ExtendedKalmanFilter(vt.ConstantVelocity(dim=1, q=0.05), vt.Position(dim=1, r=0.05))
    res = IMMFilter([P, PV], [[0.95, 0.05], [0.05, 0.95]]).filter(ys, x0=[0.0, 0.0], P0=np.eye(2))
    fig = Figure(figsize=(10, 6.5), layout="constrained")
    a, b = fig.subplots(2, 1, sharex=True, height_ratios=[2, 1])
    a.plot(ys[:, 0], "kx", ms=3, label="measurements")
    a.plot(x, "k-", lw=1, label="true position")
    a.plot(res.member_means[0][:, 0], "C1-", lw=1, label="P model alone: lags when walking")
    a.plot(res.member_means[1][:, 0], "C2-", lw=1, label="PV model alone: jitters when still")
    a.plot(res.means[:, 0], "C0-", lw=2, label="multiple-model estimate")
    a.set_ylabel("position")
    a.legend(fontsize=8)
    a.set_title("stand, walk, stand: P vs PV (seed 000, after Welch and Bishop)", fontsize=10)
    b.plot(res.mode_probs[:, 0], "C1-", label="P(P model)")
    b.plot(res.mode_probs[:, 1], "C2-", label="P(PV model)")
    b.set_ylim(-0.02, 1.02)
    b.set_xlabel("step")
    b.set_ylabel("model probability")
    b.legend(fontsize=8)
    path = out / "p_vs_pv.png"
    fig.savefig(path, dpi=110)
    return path


def ekf_ukf_pf(out: Path, seed: int = 3) -> Path:
    motion, meas = vt.models.growth_model()
    xs, ys = vt.simulate.simulate(motion, meas, 60, x0=[0.1], rng=seed)
    prior = dict(x0=[0.0], P0=[[5.0]])
    runs = {
        "EKF": ExtendedKalmanFilter(motion, meas).filter(ys, **prior).means[:, 0],
        "UKF": UnscentedKalmanFilter(motion, meas,
                                     points=vt.filters.MerweScaledSigmaPoints(1.0, 2.0, 2.0)
                                     ).filter(ys, **prior).means[:, 0],
        "particle filter (N = 2,000)": ParticleFilter(motion, meas, 2000, rng=seed).filter(
            ys, **prior).means[:, 0],
    }
    fig = Figure(figsize=(10, 4.5), layout="constrained")
    ax = fig.subplots()
    ax.plot(xs[:, 0], "k-", lw=2, label="true state")
    for (name, m), style in zip(runs.items(), ("C1--", "C2-.", "C0-")):
        rmse = np.sqrt(np.mean((m - xs[:, 0]) ** 2))
        ax.plot(m, style, lw=1.2, label=f"{name}: RMSE {rmse:.1f}")
    ax.set_xlabel("step")
    ax.set_ylabel("x")
    ax.set_title("growth model: y = x²/20 + noise hides the sign of x", fontsize=10)
    ax.legend(fontsize=8)
    path = out / "ekf_ukf_pf.png"
    fig.savefig(path, dpi=110)
    return path


def main(out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    return [particle_cloud(out), p_vs_pv(out), ekf_ukf_pf(out)]


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("out_dir", nargs="?", type=Path, default=Path(__file__).parent / "figures",
                        help="the folder the figures are written to (default: examples/figures)")
    for p in main(parser.parse_args().out_dir):
        print("wrote", p)

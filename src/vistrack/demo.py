"""The seeds' Kalman-filter figures, remade from real runs of vistrack.

- :func:`constant_velocity_1d`: 1-D constant velocity, "o state, x measurement, * predicted,
  + corrected, 3σ bars" (seed ``000``/``002``);
- :func:`smoothing_1d`: forward, backward and combined estimates of the two-filter smoother;
- :func:`murphy_2d`: the 2-D constant-velocity example from Kevin Murphy's toolbox (seed ``000``),
  with uncertainty ellipses, and its error statistics over many seeds.

``vistrack demo kalman`` runs them all and writes the PNGs.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .filters import kalman_filter, rts_smooth, two_filter_smooth
from .models import ConstantVelocity, LinearGaussian, Position
from .simulate import simulate, simulate_lgssm

__all__ = ["constant_velocity_1d", "smoothing_1d", "murphy_2d", "MurphyStats", "run_kalman_demo"]

# the 1-D example: constant velocity, position measured
_CV1 = ConstantVelocity(dim=1, q=0.05)
_POS1 = Position(dim=1, r=1.0)
_X0 = np.array([0.0, 1.0])
_P0 = np.diag([4.0, 1.0])


def _figure(ncols: int = 1, *, width: float = 6.4, height: float = 4.2):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width * ncols, height), layout="constrained")
    return fig, fig.subplots(1, ncols, squeeze=False)[0]


def _sample_1d(T: int, seed: int):
    return simulate(_CV1, _POS1, T, x0=_X0, rng=seed)


def constant_velocity_1d(path: str | Path, *, T: int = 20, seed: int = 2) -> Path:
    """Filter a simulated 1-D constant-velocity track and draw the seeds' figure."""
    from .viz.plots import plot_estimates_1d

    xs, ys = _sample_1d(T, seed)
    F, Q, H, R = _CV1.F(1.0), _CV1.Q(1.0), _POS1.H(2), _POS1.R()
    res = kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=_X0, P0=_P0)
    # store_covs=True (the default) keeps every covariance and prediction
    assert res.pred_means is not None and res.pred_covs is not None and res.covs is not None
    fig, (ax,) = _figure()
    t = np.arange(T)
    plot_estimates_1d(
        ax, t, truth=xs[:, 0], measurements=ys[:, 0],
        pred_mean=res.pred_means[:, 0], pred_std=np.sqrt(res.pred_covs[:, 0, 0]),
        mean=res.means[:, 0], std=np.sqrt(res.covs[:, 0, 0]),
        title="Kalman filter, 1-D constant velocity (bars: 3 standard deviations)",
    )
    path = Path(path)
    _save(fig, path)
    return path


def _moments(Lam: np.ndarray, eta: np.ndarray, cond_max: float = 1e8):
    """Mean and covariance from information form, NaN where ``Λ`` is (near) singular."""
    T, n = eta.shape
    mean = np.full((T, n), np.nan)
    cov = np.full((T, n, n), np.nan)
    for t in range(T):
        if np.linalg.cond(Lam[t]) < cond_max:
            cov[t] = np.linalg.inv(Lam[t])
            mean[t] = cov[t] @ eta[t]
    return mean, cov


def smoothing_1d(path: str | Path, *, T: int = 20, seed: int = 2) -> Path:
    """The seeds' forward, backward and combined (two-filter) estimates, in three panels."""
    from .viz.plots import plot_estimates_1d

    xs, ys = _sample_1d(T, seed)
    F, Q, H, R = _CV1.F(1.0), _CV1.Q(1.0), _POS1.H(2), _POS1.R()
    sm = two_filter_smooth(ys, F=F, Q=Q, H=H, R=R, x0=_X0, P0=_P0)
    fwd = sm.filtered
    # two_filter_smooth keeps the backward information and all of the forward filter's arrays
    assert sm.backward_info is not None and sm.backward_info_vec is not None
    assert fwd.pred_means is not None and fwd.pred_covs is not None and fwd.covs is not None
    # backward filter: its prediction (without y_t) and its correction (with y_t), in moments
    Lp, ep = sm.backward_info, sm.backward_info_vec
    HtRi = H.T @ np.linalg.inv(R)
    Lc = Lp + HtRi @ H
    ec = ep + ys @ HtRi.T
    bp_mean, bp_cov = _moments(Lp, ep)
    bc_mean, bc_cov = _moments(Lc, ec)
    t = np.arange(T)
    fig, axes = _figure(3, width=5.2)
    common = dict(truth=xs[:, 0], measurements=ys[:, 0])
    plot_estimates_1d(axes[0], t, **common, pred_mean=fwd.pred_means[:, 0],
                      pred_std=np.sqrt(fwd.pred_covs[:, 0, 0]), mean=fwd.means[:, 0],
                      std=np.sqrt(fwd.covs[:, 0, 0]), title="Forward estimates")
    plot_estimates_1d(axes[1], t, **common, pred_mean=bp_mean[:, 0],
                      pred_std=np.sqrt(bp_cov[:, 0, 0]), mean=bc_mean[:, 0],
                      std=np.sqrt(bc_cov[:, 0, 0]), title="Backward estimates")
    plot_estimates_1d(axes[2], t, **common, mean=sm.means[:, 0], std=np.sqrt(sm.covs[:, 0, 0]),
                      title="Combined forward-backward estimates", mean_label="smoothed")
    # every 3σ bar inside (the first prediction's, from the prior, reached past the
    # measurements' range and lost its end cap)
    bars = [(fwd.pred_means, fwd.pred_covs), (fwd.means, fwd.covs), (bp_mean, bp_cov),
            (bc_mean, bc_cov), (sm.means, sm.covs)]
    ends = [m[:, 0] + k * 3 * np.sqrt(c[:, 0, 0]) for m, c in bars for k in (-1, 1)]
    lo = min(np.nanmin(ys) - 4, *(np.nanmin(e) - 0.5 for e in ends))
    hi = max(np.nanmax(ys) + 4, *(np.nanmax(e) + 0.5 for e in ends))
    for ax in axes:
        ax.set_ylim(lo, hi)
        ax.set_xlim(-0.6, T - 0.4)  # one range for the three (the backward's stopped short)
        ax.set_title(ax.get_title() + " (bars: 3σ)")
    path = Path(path)
    _save(fig, path)
    return path


# Kevin Murphy's 2-D constant-velocity demo, as in seed 000
MURPHY = LinearGaussian(
    F=np.array([[1, 0, 1, 0], [0, 1, 0, 1], [0, 0, 1, 0], [0, 0, 0, 1.0]]),
    Q=0.1 * np.eye(4),
    H=np.eye(2, 4),
    R=np.eye(2),
)
MURPHY_X0 = np.array([10.0, 10.0, 1.0, 0.0])
MURPHY_P0 = 10.0 * np.eye(4)
MURPHY_T = 15


@dataclass(frozen=True)
class MurphyStats:
    """The toolbox demo's error, ``sqrt(Σ_t Σ_{x,y} (estimate - truth)²)``, over ``n_seeds``
    runs."""

    n_seeds: int
    filtered: np.ndarray  # (n_seeds,)
    smoothed: np.ndarray  # (n_seeds,)

    @property
    def mean_filtered(self) -> float:
        return float(self.filtered.mean())

    @property
    def mean_smoothed(self) -> float:
        return float(self.smoothed.mean())

    @property
    def ratio(self) -> float:
        return self.mean_filtered / self.mean_smoothed

    def percentile_of(self, filtered: float, smoothed: float) -> tuple[float, float]:
        """Where a single run's errors sit in our distribution, in percent."""
        return (float(100 * np.mean(self.filtered < filtered)),
                float(100 * np.mean(self.smoothed < smoothed)))


def _murphy_run(seed: int | np.random.Generator, n_series: int | None = None):
    """Simulate the 2-D example, filter and RTS-smooth it; ``(xs, ys, filtered, smoothed)``."""
    m = MURPHY
    xs, ys = simulate_lgssm(MURPHY_T, F=m.F, Q=m.Q, H=m.H, R=m.R, x0=MURPHY_X0,
                            n_series=n_series, rng=seed)
    res = kalman_filter(ys, F=m.F, Q=m.Q, H=m.H, R=m.R, x0=MURPHY_X0, P0=MURPHY_P0)
    return xs, ys, res, rts_smooth(res, F=m.F, Q=m.Q)


def _toolbox_error(est: np.ndarray, xs: np.ndarray) -> np.ndarray:
    """The toolbox demo's "MSE": sqrt of the squared position errors summed over x, y and steps."""
    return np.sqrt(((est[..., :2] - xs[..., :2]) ** 2).sum(axis=(-2, -1)))


MAX_SEEDS = 1_000_000
"""The most runs :func:`murphy_errors` takes (about two minutes; 10**10 ran out of memory)."""

_CHUNK = 10_000
"""The runs filtered as one batch (about 90 MB): more are drawn and filtered in batches of
this many, one random generator for them all."""


def murphy_errors(n_seeds: int = 1000, *, seed: int = 0) -> MurphyStats:
    """Run the 2-D example on ``n_seeds`` simulated tracks (1 to :data:`MAX_SEEDS`) in
    batches: filter and RTS-smooth. Up to 10,000 runs are one batch, drawn from ``seed``
    alone; more take their batches from one generator of ``seed``, so memory stays that of
    one batch (8 KB a run)."""
    from ._validate import as_whole

    n = as_whole(n_seeds, "n_seeds", 1)
    if n > MAX_SEEDS:
        raise ValueError(f"n_seeds must be at most {MAX_SEEDS:,}; got {n:,}")
    if n <= _CHUNK:
        xs, _, res, sm = _murphy_run(seed, n)
        return MurphyStats(n, _toolbox_error(res.means, xs), _toolbox_error(sm.means, xs))
    rng = np.random.default_rng(seed)
    filtered, smoothed = np.empty(n), np.empty(n)
    for a in range(0, n, _CHUNK):
        b = min(n, a + _CHUNK)
        xs, _, res, sm = _murphy_run(rng, b - a)
        filtered[a:b], smoothed[a:b] = _toolbox_error(res.means, xs), _toolbox_error(sm.means, xs)
    return MurphyStats(n, filtered, smoothed)


def murphy_2d(path: str | Path, *, seed: int = 8) -> tuple[Path, float, float]:
    """Draw one run of the 2-D example: filtered and smoothed estimates with 1σ ellipses.

    Returns the path and that run's filtered and smoothed errors.
    """
    from .viz.plots import plot_track_2d

    xs, ys, res, sm = _murphy_run(seed)
    ef, es = float(_toolbox_error(res.means, xs)), float(_toolbox_error(sm.means, xs))
    fig, axes = _figure(2, width=3.6, height=5.6)
    plot_track_2d(axes[0], truth=xs, measurements=ys, means=res.means, covs=res.covs,
                  label="filtered", color="tab:red", title=f"Filtered (error {ef:.2f})")
    plot_track_2d(axes[1], truth=xs, measurements=ys, means=sm.means, covs=sm.covs,
                  label="smoothed", color="tab:blue", title=f"Smoothed (error {es:.2f})")
    lims = [(min(a.get_xlim()[0] for a in axes), max(a.get_xlim()[1] for a in axes)),
            (min(a.get_ylim()[0] for a in axes), max(a.get_ylim()[1] for a in axes))]
    for a in axes:
        a.set_xlim(*lims[0])
        a.set_ylim(*lims[1])
        # below the axes: inside, the legend sat on measurements
        a.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncols=3, fontsize=8)
        a.set_title(a.get_title() + ", 1σ ellipses", fontsize=10)
    path = Path(path)
    _save(fig, path)
    return path, ef, es


def _save(fig: Any, path: Path) -> None:
    """Save the figure whole or not at all (:func:`~vistrack.io.atomic.replacing`): it was
    written in place, and Ctrl-C while it was written left a figure of 124 bytes where an
    earlier, complete one had been."""
    from .io.atomic import replacing

    with replacing(path) as part:
        fig.savefig(part, dpi=110, format=path.suffix.lstrip(".") or "png")


_PERCENTILE_SEEDS = 100
"""The fewest seeds among which the demo places the slide's run by percentile."""


def run_kalman_demo(out_dir: str | Path, *, n_seeds: int = 1000, force: bool = False) -> str:
    """Write the three figures into ``out_dir`` and return a text summary; figures there
    already are replaced only with ``force`` (else a FileExistsError naming them). The
    statistics over ``n_seeds`` runs (:func:`murphy_errors`) are computed first, and the
    figures replace earlier ones as one set (:func:`~vistrack.io.atomic.together`): a
    failure or Ctrl-C leaves every earlier figure as it was, or none written."""
    out = Path(out_dir)
    names = ("kalman_1d.png", "smoothing_1d.png", "kalman_2d.png")
    there = [str(out / n) for n in names if (out / n).exists()]
    if there and not force:
        raise FileExistsError(f"{', '.join(there)} exist; pass --force to overwrite them")
    from .io.atomic import made_folder, together

    st = murphy_errors(n_seeds)
    # the three as one set: stopped between two, new figures stood beside an earlier run's
    with made_folder(out), together():
        p1 = constant_velocity_1d(out / names[0])
        p2 = smoothing_1d(out / names[1])
        p3, ef, es = murphy_2d(out / names[2])
    pf, ps = st.percentile_of(4.9, 3.2)
    mean = f"vistrack, mean over {st.n_seeds} seed{'s' if st.n_seeds != 1 else ''}:"
    lines = [
        f"wrote {p1}",
        f"wrote {p2}",
        f"wrote {p3}",
        "",
        "2-D constant-velocity example (seed 000, Murphy's toolbox): error = sqrt(sum of squared",
        "position errors over x, y and all 15 steps)",
        f"  this figure's run:                 filtered {ef:.2f}   smoothed {es:.2f}",
        f"  {mean:<35}filtered {st.mean_filtered:.2f}   "
        f"smoothed {st.mean_smoothed:.2f}   ratio {st.ratio:.2f}",
        # (stored: measured once with both, over their own 1000 draws; it read as computed
        # beside any --seeds)
        "  FilterPy and pykalman, 1000 seeds, measured once: filtered 4.30   smoothed 2.93   "
        "ratio 1.47",
        # (a percentile of one seed is its rank among one: 100th, said as a finding)
        f"  the slide's run (4.9 / 3.2) sits at our {pf:.0f}th / {ps:.0f}th percentile"
        if st.n_seeds >= _PERCENTILE_SEEDS else
        f"  (the slide's run is placed among ours from {_PERCENTILE_SEEDS} seeds on)",
    ]
    return "\n".join(lines)

"""Exact JPDA association probabilities: vistrack against pyehm (Maskell's EHM2, C++).

    python bench/bench_jpda.py

Both compute every track's marginal probability of each gated detection and of none, over
every feasible joint event, exactly. Two kinds of problem:

- dense clusters: T tracks and D detections, every detection in every track's gate (the
  worst case for both: the events number 1,441,729 at 8 x 8 and 1.4e11 at 12 x 12);
- scenes: 30 or 300 targets, as many clutter points and 2-D measurements, gated at
  chi-square 9.21 (99 %), as a point tracker's frame is, with the targets packed in a
  smaller or a larger area (more or fewer of them share detections).

Each problem is solved by ``vistrack.association.jpda_weights`` and by
``pyehm.core.EHM2.run`` in turn; milliseconds a call, medians, and the largest difference
between the two answers. pyehm is in the ``bench`` extra.
"""

from __future__ import annotations

import sys

import numpy as np

from vistrack.association import jpda_weights, likelihoods

from _common import median_time, optional

PD, LAM, PG = 0.9, 1e-3, 0.99


def dense(rng, T, D):
    return rng.uniform(0.5, 1.5, (T, D)) * 1e-3, np.ones((T, D), bool)


def scene(rng, side, T=30, clutter=30):
    """T targets uniform in a square of ``side``, each measured with probability PD (unit
    noise), and ``clutter`` points uniform in it; unit predicted covariance plus noise."""
    x = rng.uniform(0, side, (T, 2))
    seen = rng.random(T) < PD
    z = np.r_[x[seen] + rng.normal(0, 1, (int(seen.sum()), 2)),
              rng.uniform(0, side, (clutter, 2))]
    S = np.broadcast_to(2.0 * np.eye(2), (T, 2, 2))
    lik = likelihoods(x, S, z)
    d2 = np.einsum("tdi,tij,tdj->td", z[None] - x[:, None],
                   np.linalg.inv(S), z[None] - x[:, None])
    return lik, d2 < 9.21


def largest_cluster(gate):
    from vistrack.association.assign import components

    _, lt, ld = components(gate)
    sizes = [(int((lt == c).sum()), int((ld == c).sum())) for c in np.unique(lt)]
    return max(sizes, key=lambda s: min(s))


def main() -> None:
    pyehm = optional("pyehm.core")
    if pyehm is None:
        sys.exit("pyehm is needed for the side by side: pip install -e '.[bench]'")
    ehm = pyehm.core.EHM2()
    rng = np.random.default_rng(0)
    problems = [(f"dense {T} x {D}", *dense(rng, T, D), 7 if T < 12 else 3)
                for T, D in [(4, 4), (6, 6), (8, 8), (10, 10), (12, 12), (20, 4)]]
    for side, n in ((60, 30), (120, 30), (200, 300), (400, 300)):
        lik, gate = scene(rng, side, n, n)
        t, d = largest_cluster(gate)
        problems.append((f"{n} targets, {side} x {side} (largest cluster {t} x {d})", lik,
                         gate, 7))
    print("| problem | vistrack ms | pyehm EHM2 ms | pyehm / vistrack | largest difference |")
    print("|---|---|---|---|---|")
    for name, lik, gate, reps in problems:
        G = np.where(gate, PD * lik / LAM, 0.0)
        B = 1.0 - PD * PG
        v = np.c_[np.ones(len(G)), gate].astype(np.uint8)
        L = np.c_[np.full(len(G), B), G]
        tv, (beta, beta0) = median_time(
            lambda: jpda_weights(lik, gate, p_detect=PD, clutter_density=LAM, p_gate=PG,
                                 max_exact=12), reps)
        te, a = median_time(lambda: ehm.run(v, L), reps)
        diff = max(float(np.abs(a[:, 1:] - beta).max()), float(np.abs(a[:, 0] - beta0).max()))
        print(f"| {name} | {tv * 1e3:.2f} | {te * 1e3:.2f} | {te / tv:.2f} | "
              f"{diff:.1e} |")
        assert diff < 1e-12, (name, diff)  # two exact sums: they differ by rounding


if __name__ == "__main__":
    main()

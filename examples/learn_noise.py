"""Learn a Kalman filter's noise from its measurements: q and R of a constant-velocity target
seen at irregular times with gaps, by maximum likelihood and by EM, and what that buys the
smoother against a guess ten times off."""

import numpy as np

import vistrack as vt

rng = np.random.default_rng(0)
dts = rng.uniform(0.1, 1.0, size=999)                              # irregular sampling
truth = vt.KalmanFilter(vt.ConstantVelocity(dim=2, q=0.5), vt.Position(dim=2, r=4.0))
xs, ys = vt.simulate.simulate(truth.motion, truth.measurement, 1000, x0=[0, 0, 1, 1], dt=dts,
                              rng=1)
ys[rng.random(1000) < 0.1] = np.nan                                # 10 % of the steps missed

guess = vt.KalmanFilter(vt.ConstantVelocity(dim=2, q=5.0), vt.Position(dim=2, r=0.4))
kf, fit = guess.fit(ys, dt=dts)                                    # maximum likelihood
print(f"q = {kf.motion.q:.3f} +/- {fit.stderr['q']:.3f} (true 0.5)")
print("R diagonal =", kf.measurement.R().diagonal().round(2), "+/-",
      fit.stderr["r"].round(2), "(true 4)")
print(f"log-likelihood {fit.loglik[0]:.1f} -> {fit.loglik[-1]:.1f} in {fit.iterations} "
      "iterations (L-BFGS, then Newton)")
kf_em, fit_em = guess.fit(ys, dt=dts, method="em", tol=1e-8, max_iter=2000)
print(f"EM: q = {kf_em.motion.q:.3f}, R diagonal = {kf_em.measurement.R().diagonal().round(2)}"
      f" after {fit_em.iterations} iterations")
for name, f in (("guessed noise", guess), ("learned noise", kf)):
    sm = f.smooth(ys, dt=dts)
    print(f"smoothed position RMSE, {name}: "
          f"{vt.evaluation.rmse(sm.means[:, :2], xs[:, :2]):.2f}")

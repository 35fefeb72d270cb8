"""Filter and smooth a 2-D track with dropped frames and a missing coordinate."""

import numpy as np

import vistrack as vt

cv, pos = vt.ConstantVelocity(dim=2, q=0.5), vt.Position(dim=2, r=4.0)
times = np.array([0.0, 1.0, 2.0, 5.0, 6.0, 7.0, 8.0])            # frames 3 and 4 were dropped
xs, ys = vt.simulate.simulate(cv, pos, len(times), x0=[0, 0, 2, 1], dt=np.diff(times), rng=0)
ys[5, 1] = np.nan                                                 # y coordinate missing at t=7

kf = vt.KalmanFilter(cv, pos)
filtered = kf.filter(ys, dt=np.diff(times))
smoothed = kf.smooth(ys, dt=np.diff(times))
print("filtered RMSE", vt.evaluation.rmse(filtered.means[:, :2], xs[:, :2]).round(2))
print("smoothed RMSE", vt.evaluation.rmse(smoothed.means[:, :2], xs[:, :2]).round(2))
print("velocity at t=8:", smoothed.means[-1, 2:].round(2), "+/-",
      np.sqrt(np.diag(smoothed.covs[-1])[2:]).round(2))

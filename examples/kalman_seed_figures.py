"""Remake the seeds' Kalman-filter figures from real runs of vistrack.

    python examples/kalman_seed_figures.py          # writes examples/figures/*.png

- kalman_1d.png: 1-D constant velocity; o state, x measurement, * prediction, + correction,
  3-sigma bars (seed 000 "The Kalman filter in 1D", seed 002 "Constant velocity model").
- smoothing_1d.png: forward, backward and combined estimates of the two-filter smoother
  (seed 000 "Smoothing").
- kalman_2d.png: the 2-D constant-velocity example of Kevin Murphy's toolbox with 1-sigma
  ellipses, filtered and RTS-smoothed (seed 000).
"""

from pathlib import Path

from vistrack.demo import run_kalman_demo

if __name__ == "__main__":
    print(run_kalman_demo(Path(__file__).parent / "figures", n_seeds=1000))

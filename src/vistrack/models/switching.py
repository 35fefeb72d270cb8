r"""Switching linear dynamic systems (seed 004, "Even More Extensions"):

.. math::
    z_t \sim \pi_{z_{t-1}}, \qquad x_t = A^{(z_t)} x_{t-1} + e_t, \quad
    e_t \sim N(0, \Sigma^{(z_t)}), \qquad y_t = C x_t + w_t, \quad w_t \sim N(0, R),

"a set of k dynamic models :math:`A^{(1)}, \dots, A^{(k)}`, each of which describes a
different dynamic behaviour; a hidden variable :math:`z_t` determines which model is active".
Estimate it with :class:`~vistrack.filters.IMMFilter`
(:meth:`IMMFilter.from_system <vistrack.filters.IMMFilter.from_system>`) or
the Rao-Blackwellised particle filter
:class:`~vistrack.filters.SwitchingParticleFilter`, which samples mode sequences and keeps an
exact Kalman filter per sample.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .._validate import (
    as_float_array,
    as_markov_chain,
    as_rng,
    as_whole,
    check_finite,
    check_prior,
)
from .adapters import _check_noise_matrix, psd_sqrt
from .measurement import MeasurementModel
from .motion import MotionModel

__all__ = ["SwitchingLinearSystem"]




class SwitchingLinearSystem:
    r"""A switching linear dynamic system: ``k`` linear motion models of one state size, a
    Markov switching matrix and one linear measurement model.

    .. math::

        z_t \sim \Pi_{z_{t-1}, \cdot}, \qquad
        x_t = F^{(z_t)} x_{t-1} + e_t, \quad e_t \sim N(0, Q^{(z_t)}), \qquad
        y_t = H x_t + w_t, \quad w_t \sim N(0, R).

    Parameters
    ----------
    motions : sequence of motion models
        Linear motion models (``F(dt)``, ``Q(dt)``, ``ndim_state``), all of state size ``n``.
    measurement : measurement model
        A linear measurement model (``H(n)``, ``R()``).
    transition : (k, k) array_like
        ``transition[i, j] = P(z_t = j | z_{t-1} = i)``; non-negative, rows sum to one (to
        1e-9, or to the rounding of the array's own floating type where that is coarser: a
        float32 matrix's rows are then scaled to sum to one).
    mode_probs : (k,) array_like, optional
        Distribution of the first mode (default uniform); as ``transition``'s rows.

    Attributes
    ----------
    motions : list
        The ``k`` motion models.
    measurement : measurement model
        The measurement model.
    transition : (k, k) ndarray
        The switching matrix ``Π``.
    mode_probs : (k,) ndarray
        The first mode's distribution.
    ndim_state : int
        Size ``n`` of the state.

    Raises
    ------
    ValueError
        If there are no motions, they differ in state size, a model has per-step matrices,
        the measurement's ``H`` does not take the motions' states, ``transition`` is not a finite
        non-negative ``(k, k)`` matrix whose rows sum to one, or ``mode_probs`` is not ``k``
        finite non-negative numbers summing to one (a NaN or infinite entry is named).
    TypeError
        If a motion is not a linear motion model (``F``, ``Q``; ``Q(1.0)`` must take the
        step alone, not a state as ``BoxMotion``'s) or the measurement not a linear
        measurement model (``H``, ``R``).

    References
    ----------
    .. [1] K. P. Murphy, "Switching Kalman filters", technical report, 1998.

    Examples
    --------
    A target that is mostly still and sometimes moves:

    >>> import vistrack as vt
    >>> slds = SwitchingLinearSystem(
    ...     [vt.ConstantVelocity(dim=1, q=0.01), vt.ConstantVelocity(dim=1, q=4.0)],
    ...     vt.Position(dim=1), [[0.95, 0.05], [0.2, 0.8]])
    >>> slds
    SwitchingLinearSystem(k=2, ndim_state=2)
    >>> slds.mode_probs
    array([0.5, 0.5])
    """

    def __init__(self, motions: Sequence[MotionModel], measurement: MeasurementModel,
                 transition: ArrayLike, mode_probs: ArrayLike | None = None):
        self.motions = list(motions)
        k = len(self.motions)
        if k < 1:
            raise ValueError("motions must hold at least one model")
        # linear models alone: a nonlinear one was taken, and failed at sample() or in the
        # filters with "'CoordinatedTurn' object has no attribute 'F'"
        for i, m in enumerate(self.motions):
            if not (callable(getattr(m, "F", None)) and callable(getattr(m, "Q", None))):
                raise TypeError(f"motions[{i}] must be a linear motion model, with F(dt) and "
                                f"Q(dt); got {type(m).__name__}")
            # a Q of the state as well (BoxMotion's Q(boxes, dt)) was taken, and failed at
            # sample() or in the filters naming boxes, which the caller never gave
            try:
                m.Q(1.0)
            except (TypeError, ValueError) as exc:
                raise TypeError(f"motions[{i}] must be a linear motion model whose Q(dt) takes "
                                f"the time step alone; {type(m).__name__}'s Q(1.0) failed: "
                                f"{exc}") from None
        if not (callable(getattr(measurement, "H", None))
                and callable(getattr(measurement, "R", None))):
            raise TypeError(f"measurement must be a linear measurement model, with H(n) and R(); "
                            f"got {type(measurement).__name__}")
        sizes = {int(m.ndim_state) for m in self.motions}
        if len(sizes) != 1:
            raise ValueError(f"motions must share one state size; got sizes {sorted(sizes)}")
        self.ndim_state = sizes.pop()
        # one F, Q, H and R for every step: a per-step stack (LinearMotion and
        # LinearMeasurement take one) failed in sample, in numpy's words
        for name, model in (*((f"motions[{i}]", m) for i, m in enumerate(self.motions)),
                            ("measurement", measurement)):
            steps = getattr(model, "n_steps", None)
            if steps is not None:
                raise ValueError(f"{name} has per-step matrices ({steps} steps); a switching "
                                 "system takes one model of each kind for every step")
        H = np.asarray(measurement.H(self.ndim_state))
        if H.ndim != 2 or H.shape[1] != self.ndim_state:
            raise ValueError(f"measurement must measure states of size {self.ndim_state}, as "
                             f"the motions give them; its H is {H.shape}")
        self.measurement = measurement
        self.transition, self.mode_probs = as_markov_chain(transition, mode_probs, k)

    def __repr__(self) -> str:
        return f"SwitchingLinearSystem(k={len(self.motions)}, ndim_state={self.ndim_state})"

    def sample(self, T: int, *, x0: ArrayLike, P0: ArrayLike | None = None, dt: float = 1.0,
               rng: np.random.Generator | int | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Draw a sequence of modes, states and measurements.

        The first mode is drawn from ``mode_probs`` and the first state is ``x0`` (or a draw
        from ``N(x0, P0)``); each later step first switches mode, then moves with that mode's
        dynamics. Every state is measured.

        Parameters
        ----------
        T : int
            Number of steps.
        x0 : (n,) array_like
            Mean of the first state.
        P0 : (n, n) array_like, optional
            Covariance of the first state; the first state is exactly ``x0`` if None.
        dt : float
            Time step of the motion models.
        rng : numpy.random.Generator, int or None
            Random generator or seed.

        Returns
        -------
        zs : (T,) ndarray of int64
            Mode of each step.
        xs : (T, n) ndarray
            States.
        ys : (T, m) ndarray
            Measurements.

        Raises
        ------
        ValueError
            If ``x0`` does not have shape ``(n,)`` or is not finite, ``dt`` is not one
            number, or a mode's ``Q(dt)`` or the measurement's ``R()`` is not a finite
            symmetric positive semi-definite matrix of its size.

        Examples
        --------
        >>> import vistrack as vt
        >>> slds = SwitchingLinearSystem(
        ...     [vt.ConstantVelocity(dim=1, q=0.01), vt.ConstantVelocity(dim=1, q=4.0)],
        ...     vt.Position(dim=1), [[0.95, 0.05], [0.2, 0.8]])
        >>> zs, xs, ys = slds.sample(50, x0=[0.0, 1.0], rng=0)
        >>> zs.shape, xs.shape, ys.shape
        ((50,), (50, 2), (50, 1))
        """
        T = as_whole(T, "T", 0, "a number of steps")
        gen = as_rng(rng)
        n = self.ndim_state
        H, R = np.asarray(self.measurement.H(n)), np.asarray(self.measurement.R())
        x = as_float_array(x0, "x0", ndim=(1,)).copy()
        if x.shape != (n,):
            raise ValueError(f"x0 must have shape ({n},); got {x.shape}")
        check_finite(x, "x0")  # (without P0, NaN states and measurements, unsaid)
        if np.ndim(dt) != 0:  # (a stack of F met numpy's broadcast error)
            raise ValueError(f"dt must be one time step, the same for every step; got shape "
                             f"{np.shape(dt)}")
        # noise drawn by the principal roots, the same on every machine (psd_sqrt)
        if P0 is not None:
            x, P0_ = check_prior(x, P0, n, batch=False)  # shape, finite, semi-definite
            x = x + psd_sqrt(P0_) @ gen.standard_normal(n)
        k = len(self.motions)
        Fs = [m.F(dt) for m in self.motions]  # each mode's, once: dt is the same every step
        Qs = [np.asarray(m.Q(dt), dtype=float) for m in self.motions]
        # checked as the filters check them (a model of the caller's own with a NaN or a
        # negative variance was drawn without noise, or without that variance, unsaid)
        for i, Q in enumerate(Qs):
            _check_noise_matrix(Q, n, f"motions[{i}].Q({float(dt):g})")
        _check_noise_matrix(R, H.shape[0], "measurement.R()")
        roots = [psd_sqrt(Q) for Q in Qs]
        zs, xs = np.empty(T, np.int64), np.empty((T, n))
        z = gen.choice(k, p=self.mode_probs)
        for t in range(T):
            if t > 0:
                z = gen.choice(k, p=self.transition[z])
                x = Fs[z] @ x + roots[z] @ gen.standard_normal(n)
            zs[t], xs[t] = z, x
        ys = xs @ H.T + gen.standard_normal((T, len(R))) @ psd_sqrt(R).T
        return zs, xs, ys

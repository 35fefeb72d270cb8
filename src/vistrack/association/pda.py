r"""Probabilistic data association: PDA for one track, JPDA for tracks that share measurements.

Rather than choosing one measurement, a track is corrected with every gated measurement,
weighted by the probability that it is the track's (seed 003, "probabilistic data
association"; Bar-Shalom and Tse, 1975). With detection probability :math:`P_D`, gate
probability :math:`P_G`, clutter of spatial density :math:`\lambda` and the likelihood
:math:`\ell_{j} = N(z_j; \hat z, S)`:

.. math::
    \beta_j = \frac{P_D \ell_j / \lambda}{1 - P_D P_G + \sum_k P_D \ell_k / \lambda}, \qquad
    \beta_0 = \frac{1 - P_D P_G}{1 - P_D P_G + \sum_k P_D \ell_k / \lambda}

(:math:`\beta_0`: no measurement is the track's). The update
(:func:`vistrack.filters.pda_update`) uses the combined innovation
:math:`\nu = \sum_j \beta_j \nu_j` and adds the spread of the innovations to the covariance:

.. math::
    P = \beta_0 P^- + (1 - \beta_0)(P^- - K S K') + K \Big(\sum_j \beta_j \nu_j \nu_j' - \nu \nu'
    \Big) K'.

**JPDA** (Fortmann, Bar-Shalom and Scheffe, 1983) computes the :math:`\beta` of tracks that
compete for measurements jointly: over every feasible joint event (each measurement to at most
one track, each track at most one measurement, within the gates), with probability
proportional to :math:`\prod_{(t,j)} P_D \ell_{tj} / \lambda \prod_{t \text{ missed}} (1 - P_D
P_G)`. The gated problem is split into independent clusters. A cluster's marginals are
exact: in closed form for one or two tracks, event by event for a small cluster of more
(the clusters and these in one compiled call), and otherwise summed over the subsets of its
smaller side rather than over its events (a cost of :math:`T D 2^{\min(T, D)}`), when that
side has at most ``max_exact`` tracks or measurements and the sum costs at most four times
a ``max_exact`` square's; a larger cluster gets Fitzgerald's "cheap JPDA" approximation
(1985),
:math:`\beta_{tj} = G_{tj} / (\sum_k G_{tk} + \sum_s G_{sj} - G_{tj} + B)` with
:math:`G_{tj} = P_D \ell_{tj} / \lambda` and :math:`B = 1 - P_D P_G`.
"""

from __future__ import annotations

import contextlib
import functools
import math

import numpy as np
from numpy.typing import ArrayLike

from .._jit import njit
from .._validate import as_float_array, as_number, as_whole
from .costs import _innovations, cholesky_innovations

__all__ = ["pda_weights", "jpda_weights", "ipda_weights", "jipda_weights", "likelihoods"]


def likelihoods(z_pred: ArrayLike, S: ArrayLike, Z: ArrayLike) -> np.ndarray:
    r"""Gaussian likelihood of every detection under every track's predicted measurement.

    .. math:: \ell_{tj} = N(z_j; \hat z_t, S_t) = (2\pi)^{-m/2} \det(S_t)^{-1/2}
              \exp\left(-\tfrac12 (z_j - \hat z_t)' S_t^{-1} (z_j - \hat z_t)\right)

    Parameters
    ----------
    z_pred : (T, m) array_like
        Predicted measurements :math:`\hat z_t`.
    S : (T, m, m) array_like
        Innovation covariances, positive definite.
    Z : (D, m) array_like
        Detections.

    Returns
    -------
    (T, D) ndarray
        The likelihoods; ``(T, 0)`` when there are no detections.

    Raises
    ------
    ValueError
        If ``S`` is not ``(T, m, m)`` or ``Z`` not ``(D, m)``, an ``S_t`` is not symmetric and
        positive definite, or a ``z_pred`` is not finite (as
        :func:`~vistrack.association.mahalanobis`).

    Examples
    --------
    >>> likelihoods(np.zeros((1, 2)), np.eye(2)[None], np.array([[0.0, 0.0], [1.0, 0.0]]))
    array([[0.15915494, 0.09653235]])
    """
    zp, S, Z = _innovations(z_pred, S, Z, "Z")
    T, m = zp.shape
    if Z.size == 0 or T == 0:
        return np.zeros((T, len(Z) if Z.size else 0))
    L = cholesky_innovations(S)
    r = Z[None, :, :] - zp[:, None, :]
    w = np.linalg.solve(L, np.swapaxes(r, 1, 2))
    d2 = (w * w).sum(1)
    logdet = 2 * np.log(np.diagonal(L, axis1=1, axis2=2)).sum(1)
    return np.exp(-0.5 * d2 - 0.5 * logdet[:, None] - 0.5 * m * np.log(2 * np.pi))


def _lik_gate(lik: ArrayLike, gate: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``lik`` as floats and ``gate`` as bools, both ``(T, D)``; a likelihood inside the gate
    must be a finite number >= 0 (a NaN detection's is NaN: outside every gate that
    :func:`~vistrack.association.chi2_gate` draws, refused inside one). The pairs of
    likelihood 0 are taken out of the gate: no event may hold them."""
    # (complex ones lost their imaginary parts)
    lik = as_float_array(lik, "lik", not_boolean="likelihoods, numbers >= 0")
    if lik.ndim != 2:
        raise ValueError(f"lik must have shape (T, D), tracks by detections; got shape "
                         f"{lik.shape}")
    gate = np.asarray(gate)
    if gate.shape != lik.shape:
        raise ValueError(f"gate must have the shape of lik, {lik.shape}; got {gate.shape}")
    if gate.dtype != bool:
        # (a gate of 0.5 or NaN would be taken as inside)
        with np.errstate(invalid="ignore"):
            odd = ~((gate == 0) | (gate == 1))
        if odd.any():
            t, j = (int(i) for i in np.argwhere(odd)[0])
            raise ValueError(f"gate must hold True / False (or 1 / 0); gate[{t}, {j}] = "
                             f"{gate[t, j]!r}")
    gate = gate.astype(bool)
    rows, cols = np.nonzero(gate)
    check_pair_likelihoods(rows, cols, lik[rows, cols])
    return lik, gate & (lik > 0)


def check_pair_likelihoods(rows: np.ndarray, cols: np.ndarray, lik: np.ndarray) -> None:
    """Raise the ValueError that names the first gated pair, in the order of the rows and
    then the columns, whose likelihood ``lik[k]`` (of pair ``rows[k], cols[k]``) is not a
    finite number >= 0 (a NaN detection's is NaN, refused inside a gate); the weights' own
    check, for pairs a caller holds without the dense matrix."""
    bad = ~(np.isfinite(lik) & (lik >= 0))
    if bad.any():
        k = np.flatnonzero(bad)
        k = k[np.lexsort((cols[k], rows[k]))[0]]
        raise ValueError(f"lik must be finite and >= 0 inside the gate; "
                         f"lik[{int(rows[k])}, {int(cols[k])}] = {lik[k]}")


def _check(p_detect: float, clutter_density: float, p_gate: float
           ) -> tuple[float, float, float]:
    """The three as floats, each checked (a boolean was taken as 1, a clutter density of
    1 among them; a string or an array met Python's or numpy's error, naming none)."""
    p_detect, clutter_density, p_gate = (as_number(v, k) for v, k in (
        (p_detect, "p_detect"), (clutter_density, "clutter_density"), (p_gate, "p_gate")))
    if not 0.0 < p_detect <= 1.0:
        raise ValueError(f"p_detect must be in (0, 1]; got {p_detect}")
    if not 0 < clutter_density < math.inf:
        raise ValueError(f"clutter_density must be a finite number > 0 (per unit of "
                         f"measurement space); "
                         f"got {clutter_density}")
    if not 0.0 < p_gate <= 1.0:
        raise ValueError(f"p_gate must be in (0, 1]; got {p_gate}")
    return p_detect, clutter_density, p_gate


def _weights(w: float | np.ndarray, lik: np.ndarray, gate: np.ndarray, clutter_density: float
             ) -> tuple[np.ndarray, np.ndarray]:
    """The weights ``G = w lik / clutter_density`` inside the gates (0 outside), ``w`` being
    ``P_D`` (or a column of ``eps_t P_D``), and each track's scale ``c (T,)`` they are
    multiplied by: 1, but for a track whose weights, or their sum, pass the largest float
    (inf, and then NaN probabilities, or 0), ``clutter_density 1e300 / max_j lik_tj``, which
    takes its largest weight to ``w`` 1e300 (not to ``w``: its miss, ``B c``, fell to a
    subnormal number of few digits, whose ratios between tracks the joint events weigh). Every
    event's weight is a product with one factor per track, each of a track's factors (its
    detections', a miss, not being there) scaled alike, and the probabilities ratios of
    such sums: a factor per track cancels (but in Fitzgerald's cheap JPDA, whose sums mix
    the tracks: :func:`_joint` takes the scales there), and the caller scales the track's
    other factors by ``c``."""
    with np.errstate(over="ignore"):  # (an overflow is what is rescaled here)
        G = np.where(gate, w * lik / clutter_density, 0.0)
    c = np.ones(len(G))
    with np.errstate(over="ignore"):
        over = ~np.isfinite(G.sum(axis=1))
    if over.any():
        top = np.where(gate[over], lik[over], 0.0).max(axis=1)
        c[over] = clutter_density * (_LARGE / top)
        ww = np.broadcast_to(w, lik.shape)[over] if np.ndim(w) else w
        # (the likelihoods outside the gate taken out first: one of 1e300 there overflowed
        # in the product, which np.where then dropped, with a RuntimeWarning all the same)
        G[over] = ww * (np.where(gate[over], lik[over], 0.0) / top[:, None]) * _LARGE
    return G, c


_LARGE = 1e300
"""A rescaled track's largest weight over ``P_D`` (:func:`_weights`): room below the largest
float for a few thousand such weights summed."""


def pda_weights(lik: ArrayLike, gate: ArrayLike, *, p_detect: float = 0.9,
                clutter_density: float = 1e-4, p_gate: float = 0.99
                ) -> tuple[np.ndarray, np.ndarray]:
    r"""PDA association probabilities of each track on its own.

    With :math:`G_{j} = P_D \ell_{j} / \lambda` for the gated detections and
    :math:`B = 1 - P_D P_G`,

    .. math:: \beta_j = \frac{G_j}{B + \sum_k G_k}, \qquad \beta_0 = \frac{B}{B + \sum_k G_k}.

    Parameters
    ----------
    lik : (T, D) array_like
        Likelihoods :math:`\ell_{tj}` (:func:`likelihoods`).
    gate : (T, D) array_like of bool
        The detections in each track's gate.
    p_detect : float
        Detection probability :math:`P_D`, in (0, 1].
    clutter_density : float
        Spatial density :math:`\lambda > 0` of false detections, per unit of measurement
        space.
    p_gate : float
        Probability :math:`P_G` that the track's detection falls in its gate, in (0, 1].

    Returns
    -------
    beta : (T, D) ndarray
        Probability that detection ``j`` is track ``t``'s; 0 outside the gate.
    beta0 : (T,) ndarray
        Probability that no detection is the track's. Each row of ``beta`` and its ``beta0``
        sum to one (with :math:`P_D P_G = 1` and no detection in the gate, ``beta0`` is 1:
        the limit as :math:`P_G \to 1`).

    Raises
    ------
    ValueError
        If a probability or the density is out of range, ``gate`` does not have the shape of
        ``lik`` or holds other than True / False (1 / 0), or a likelihood inside the gate is
        not a finite number >= 0.

    See Also
    --------
    jpda_weights : The probabilities of tracks that compete for detections, jointly.

    References
    ----------
    .. [1] Y. Bar-Shalom and E. Tse, "Tracking in a cluttered environment with probabilistic
       data association", *Automatica* 11(5), 1975.

    Examples
    --------
    >>> b, b0 = pda_weights(np.array([[0.02, 0.01]]), np.array([[True, True]]),
    ...                     p_detect=0.9, clutter_density=0.01, p_gate=1.0)
    >>> (b.round(3).tolist(), round(float(b0[0]), 3))    # G = 1.8, 0.9; B = 0.1
    ([[0.643, 0.321]], 0.036)
    """
    p_detect, clutter_density, p_gate = _check(p_detect, clutter_density, p_gate)
    lik, gate = _lik_gate(lik, gate)
    G, c = _weights(p_detect, lik, gate, clutter_density)
    return _pda(G, (1.0 - p_detect * p_gate) * c)


def _pda(G: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """PDA's weights of tracks each on its own, from their weights ``G (T, D)`` (0 outside
    the gates) and misses ``B (T,)``: :func:`pda_weights`, and a track alone in its JPDA
    cluster."""
    den = B + G.sum(1)
    # P_D P_G = 1 and nothing in the gate: a detection certain to be there is not; the track
    # is left as it is (beta0 = 1), as jpda_weights leaves a track with none in its gate
    none = den == 0
    den[none] = 1.0
    return G / den[:, None], np.where(none, 1.0, B / den)


@functools.lru_cache(maxsize=16)
def _subsets_cached(K: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    n = 1 << K
    bit = (np.arange(n)[None, :] >> np.arange(K)[:, None]) & 1 == 1  # (K, n)
    off = np.array([np.flatnonzero(~b) for b in bit], dtype=np.intp).reshape(K, n // 2)
    on = off | (1 << np.arange(K))[:, None]
    for x in (bit, off, on):
        x.setflags(write=False)  # shared by every call
    return bit, off, on


def _subsets(K: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The subsets of ``K`` columns as bit masks ``0 .. 2**K - 1``: ``bit (K, 2**K)``, whether
    each subset holds each column, and for each column ``k`` the subsets without it,
    ``off[k]``, and the same with it, ``on[k]`` (``(K, 2**(K-1))`` each). Kept for the
    sizes of most clusters; a larger one (a ``max_exact`` raised past 12) is made anew."""
    return _subsets_cached(K) if K <= 12 else _subsets_cached.__wrapped__(K)


def _matchings(G: np.ndarray, a: np.ndarray, c: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The probabilities of every matching of the rows and columns of ``G``, summed over
    subsets of the columns.

    A matching (each row to at most one column and each column to at most one row, on pairs
    where ``G > 0``) weighs its pairs' ``G`` times ``a[i]`` for each row and ``c[k]`` for each
    column it leaves unmatched. With the rows taken in turn, ``F[i][U]`` is the weight of
    the ways rows ``0..i-1`` take exactly the columns ``U``, and ``R[U]`` that of the ways
    the rows from ``i`` on can take columns outside ``U``, the columns left over included;
    the weight of the matchings that pair ``(i, k)`` is ``G[i, k] F[i][U] R[U + k]`` summed
    over the ``U`` without ``k``, and row ``i``'s outcomes (a column each, or none) add up to
    the total. The cost grows as ``rows x columns x 2**columns``, not as the number of
    matchings (1,441,729 for 8 x 8). ``F`` and ``R`` are scaled to a largest entry of 1 at
    each row, which each row's probabilities, taken over its own total, do not see: a
    product of hundreds of ``a`` (a cluster of many tracks and few detections) underflowed.

    Where a ``c`` is 0, only the matchings that leave the fewest such columns unmatched are
    counted (rather than none, where every matching leaves one): the limit as those ``c``
    vanish. Every ``a`` must be > 0.

    Returns the probabilities of the pairs ``(I, K)``, and of each row and each column left
    unmatched.

    Where a product could fall below what a float holds (weights spanning about 1e280 or
    more along the rows, where a partial sum would be lost and with it, perhaps, every event
    it leads to), the cluster is summed again in logarithms (:func:`_matchings_log`)."""
    I, K = G.shape
    n = 1 << K
    bit, off, on = _subsets(K)
    F = np.zeros((I + 1, n))
    F[0, 0] = 1.0
    # each row's smallest factor (its a, or a pair's G) times a lower bound on the positive
    # entries of the scaled partial sums it multiplies is the least a term can be: kept
    # above _TINY, no product underflows (the bound is carried from row to row, and the
    # entries themselves looked at where it falls too low)
    lo = np.minimum(a, np.where(G > 0, G, np.inf).min(1))
    floor: float = 1.0
    # a lower bound on each F[i]'s positive entries, which the backward pass multiplies by
    # R's (a product of the two fell below what a float holds, unguarded, and a huge G
    # times it gave a track's pairs 0: every detection in its gate lost)
    floors = np.ones(I + 1)
    for i in range(I):
        if lo[i] * floor < _TINY:
            return _matchings_log(G, a, c)
        # row i takes column k (in nz) on top of every subset without it: all such columns
        # at once, each subset's ways summed by bincount
        nz = np.flatnonzero(G[i])
        f = a[i] * F[i]
        if len(nz):
            f += np.bincount(on[nz].ravel(), (G[i, nz, None] * F[i][off[nz]]).ravel(), n)
        top = f.max()  # (> 0: leaving row i unmatched is always possible)
        if not math.isfinite(top):
            return _matchings_log(G, a, c)
        F[i + 1] = f / top
        floor = lo[i] * floor / top
        if floor < _TINY:  # (scaled, an entry may have fallen below what a float holds)
            kept_min = _least_kept(f, F[i + 1])
            if kept_min is None:
                return _matchings_log(G, a, c)
            floor = kept_min
        floors[i + 1] = floor
    zero = c == 0
    level = (~bit[zero]).sum(0)  # the columns of c = 0 each subset leaves unmatched
    left = np.prod(np.where(bit, 1.0, np.where(zero, 1.0, c)[:, None]), axis=0)
    kept = level == level[F[I] > 0].min()
    R = np.where(kept, left, 0.0)
    top = R.max()
    if not (math.isfinite(top) and R[kept].min() >= _TINY * top):  # (none underflowed)
        return _matchings_log(G, a, c)
    R /= top
    floor = R[kept].min()
    whole = F[I] @ R
    if not whole >= _TINY:  # (a sum of products of scaled entries: 1 at most)
        return _matchings_log(G, a, c)
    col0 = (F[I][off] * R[off]).sum(1) / whole
    pair, row0 = np.zeros((I, K)), np.zeros(I)
    for i in range(I - 1, -1, -1):
        # G R, F R and G F R (a, a F R) each kept above _TINY
        if lo[i] * floor < _TINY or min(lo[i], 1.0) * floors[i] * floor < _TINY:
            return _matchings_log(G, a, c)
        row0[i] = a[i] * (F[i] @ R)
        below = a[i] * R
        nz = np.flatnonzero(G[i])
        if len(nz):
            up = R[on[nz]]
            pair[i, nz] = G[i, nz] * (F[i][off[nz]] * up).sum(1)
            below += np.bincount(off[nz].ravel(), (G[i, nz, None] * up).ravel(), n)
        total = row0[i] + pair[i].sum()
        top = below.max()
        if not (total >= _TINY and math.isfinite(total) and math.isfinite(top)):
            return _matchings_log(G, a, c)
        row0[i] /= total
        pair[i] /= total
        R = below / top
        floor = lo[i] * floor / top
        if floor < _TINY:
            kept_min = _least_kept(below, R)
            if kept_min is None:
                return _matchings_log(G, a, c)
            floor = kept_min
    return pair, row0, col0


def _least_kept(raw: np.ndarray, scaled: np.ndarray) -> float | None:
    """The least positive entry of ``scaled`` (``raw`` over its largest), or None where a
    positive entry of ``raw`` scaled below :data:`_TINY` (to 0, or losing digits)."""
    pos = raw > 0
    least = scaled[pos].min()
    return float(least) if least >= _TINY else None


_TINY = 1e-280
"""The least a product (or a row's total) in :func:`_matchings` may be before it sums the
cluster in logarithms instead: 28 orders of magnitude above the smallest normal float, so
that no term it keeps loses digits, and the terms it may lose (a product of two scaled
entries below the smallest float, at most ``2**K`` of them) add up to less than 1e-23 of
its row's total."""


def _logsumexp_into(idx: np.ndarray, vals: np.ndarray, n: int) -> np.ndarray:
    """``out[j] = log(sum(exp(vals[idx == j])))`` for ``j < n`` (``-inf`` where none)."""
    top = np.full(n, -np.inf)
    np.maximum.at(top, idx, vals)
    shift = np.where(np.isfinite(top), top, 0.0)
    with np.errstate(divide="ignore"):
        return shift + np.log(np.bincount(idx, np.exp(vals - shift[idx]), n))


def _lse(x: np.ndarray, axis: int | None = None) -> np.ndarray:
    """``log(sum(exp(x)))`` along ``axis`` (``-inf`` for an empty or all ``-inf`` sum)."""
    top = np.max(x, axis=axis, keepdims=True, initial=-np.inf)
    shift = np.where(np.isfinite(top), top, 0.0)
    with np.errstate(divide="ignore"):
        out = shift + np.log(np.sum(np.exp(x - shift), axis=axis, keepdims=True))
    return out.reshape(())[()] if axis is None else np.squeeze(out, axis)


def _matchings_log(G: np.ndarray, a: np.ndarray, c: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_matchings` in logarithms: the same sums, each entry held to rounding whatever
    the span of the weights (a few times slower)."""
    I, K = G.shape
    n = 1 << K
    bit, off, on = _subsets(K)
    with np.errstate(divide="ignore"):
        lG, la = np.log(G), np.log(a)
        lc = np.log(np.where(c == 0, 1.0, c))
    F = np.full((I + 1, n), -np.inf)
    F[0, 0] = 0.0
    every = np.arange(n)
    for i in range(I):
        nz = np.flatnonzero(G[i])
        idx = np.concatenate([every, on[nz].ravel()])
        vals = np.concatenate([la[i] + F[i], (lG[i, nz, None] + F[i][off[nz]]).ravel()])
        f = _logsumexp_into(idx, vals, n)
        F[i + 1] = f - f.max()
    zero = c == 0
    level = (~bit[zero]).sum(0)
    left = np.where(bit, 0.0, lc[:, None]).sum(0)
    R = np.where(level == level[np.isfinite(F[I])].min(), left, -np.inf)
    R -= R.max()
    col0 = np.exp(_lse(F[I][off] + R[off], axis=1) - _lse(F[I] + R))
    pair, row0 = np.zeros((I, K)), np.zeros(I)
    for i in range(I - 1, -1, -1):
        nz = np.flatnonzero(G[i])
        l0 = la[i] + _lse(F[i] + R)
        lp = lG[i, nz] + _lse(F[i][off[nz]] + R[on[nz]], axis=1)
        total = _lse(np.concatenate([[l0], lp]))
        row0[i] = np.exp(l0 - total)
        pair[i, nz] = np.exp(lp - total)
        idx = np.concatenate([every, off[nz].ravel()])
        vals = np.concatenate([la[i] + R, (lG[i, nz, None] + R[on[nz]]).ravel()])
        below = _logsumexp_into(idx, vals, n)
        R = below - below.max()
    return pair, row0, col0


def _by_tracks(T: int, D: int, B: np.ndarray) -> bool:
    """Whether :func:`_exact` sums over subsets of the tracks (else of the detections): the
    smaller side, but always the tracks where a miss can weigh 0."""
    return T <= D or not bool((B > 0).all())


def _work(rows: int, K: int) -> int:
    """About what :func:`_matchings` costs, in numpy's element operations: a step of
    ``2**K`` entries for each row and column, each step's call worth about 1,500."""
    return rows * K * ((1 << K) + 1500)


def _exact_is_affordable(T: int, D: int, B: np.ndarray, max_exact: int) -> bool:
    """Whether :func:`_exact` computes a cluster of ``T`` tracks and ``D`` detections: the
    side it sums over has at most ``max_exact``, and its work (:func:`_work`) is at most
    four times a ``max_exact`` x ``max_exact`` cluster's (with 12, about 20 ms): a dozen
    tracks among hundreds of clutter points, or a few among thousands, took a second or
    more."""
    K, rows = (T, D) if _by_tracks(T, D, B) else (D, T)
    m = min(max_exact, 40)  # (a max_exact of 2**40 or more: no bound on the work, at once)
    return K <= max_exact and _work(rows, K) <= 4 * _work(m, m)


# a cluster of three tracks or more with at most this many (events x tracks) is summed
# event by event (:func:`_clusters`), the others by subsets of their smaller side
# (:func:`_exact`): 3 tracks among 5 detections (136 events) take 0.02 ms walked against
# 0.3 ms by subsets in numpy, 5 among 6 (4,051 events) 0.12 against 0.35, 6 among 6 (13,327)
# about as long either way
_ENUMERATED = 20_000
_NORMAL = float(np.finfo(np.float64).tiny)
"""The smallest normal float: a pair's miss weight below it, against its track's largest
weight, has lost digits (:func:`_clusters`). (Named ``_TINY`` too, it replaced
:data:`_TINY`'s margin of 1e-280 in :func:`_matchings` with its own.)"""


def _exact(G: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Marginal association probabilities over every feasible joint event, exactly, for a
    cluster :func:`_clusters` leaves: summed over the subsets of the smaller side
    (:func:`_matchings`), so its cost grows as ``T x D x 2**min(T, D)``. An event weighs its
    pairs' product times ``B[t]`` for each track ``t`` it misses; where ``B[t]`` is 0 (P_D
    P_G = 1: certain to be detected, in its gate), the limit as it vanishes: the events that
    miss the fewest of those tracks."""
    T, D = G.shape
    if _by_tracks(T, D, B):
        pair, _, beta0 = _matchings(G.T, np.ones(D), B)
        return pair.T, beta0
    return _matchings(G, B, np.ones(D))[:2]


@njit(cache=True, error_model="numpy")
def _clusters(G, B, max_exact, enumerated, beta, beta0, label_t, label_d, left):
    """The clusters of the gated problem ``G (T, D)`` (0 outside the gates), and the
    marginals of the most common, in one compiled call: ``beta`` and ``beta0`` of

    - a track alone in its cluster: PDA's closed form;
    - a cluster of two tracks (both ``B`` > 0, and ``max_exact`` at least its smaller side
      or 2): the closed form of positive sums. With ``S1``, ``S2`` the sums of each track's
      weights over the cluster's detections and ``X2j`` the sum of track 2's over the
      detections other than ``j``, the events weigh ``Z = B1 B2 + B2 S1 + B1 S2 + sum_j G1j
      X2j`` in all (both missed, one takes a detection, each takes another); track 1 takes
      ``j`` in ``G1j (B2 + X2j)`` of it and is missed in ``B1 (B2 + S2)``. Nothing cancels
      (``X2j`` is summed, not ``S2 - G2j``), and each track's weights and ``B`` are divided by
      their largest first (an event has one factor of each track's), so that none overflows;
    - a cluster of three tracks or more, every ``B`` > 0, that :func:`_exact_is_affordable`
      and whose events times tracks number at most ``enumerated``: every event in turn (a
      depth-first walk over each track's miss and gated detections, no detection twice),
      weighed in logarithms and scaled to the largest (a first walk finds it: weights of
      1e200 overflowed a product).

    Writes each track's cluster into ``label_t`` (-1: nothing in its gate) and each
    detection's into ``label_d`` (-1: in no gate), and marks in ``left`` the clusters left
    to :func:`_joint` (a ``B`` of 0, too many events, or beyond ``max_exact``); returns the
    number of clusters."""
    T, D = G.shape
    parent = np.arange(T + D)
    for t in range(T):
        for d in range(D):
            if G[t, d] > 0:
                a = t
                while parent[a] != a:
                    parent[a] = parent[parent[a]]
                    a = parent[a]
                b = T + d
                while parent[b] != b:
                    parent[b] = parent[parent[b]]
                    b = parent[b]
                if a != b:
                    parent[max(a, b)] = min(a, b)
    # clusters numbered by their first track; only tracks with a pair are in one
    root_label = np.full(T + D, -1)
    n = 0
    has = np.zeros(T, np.bool_)
    for t in range(T):
        for d in range(D):
            if G[t, d] > 0:
                has[t] = True
                break
    for t in range(T):
        if not has[t]:
            label_t[t] = -1
            continue
        r = t
        while parent[r] != r:
            r = parent[r]
        if root_label[r] < 0:
            root_label[r] = n
            n += 1
        label_t[t] = root_label[r]
    for d in range(D):
        r = T + d
        while parent[r] != r:
            r = parent[r]
        label_d[d] = root_label[r]  # (-1: a detection in no gate is its own root)
    # each cluster's tracks and detections, in order (compressed rows)
    nt, nd = np.zeros(n + 1, np.int64), np.zeros(n + 1, np.int64)
    for t in range(T):
        if label_t[t] >= 0:
            nt[label_t[t] + 1] += 1
    for d in range(D):
        if label_d[d] >= 0:
            nd[label_d[d] + 1] += 1
    nt, nd = np.cumsum(nt), np.cumsum(nd)
    ti, di = np.empty(nt[n], np.int64), np.empty(nd[n], np.int64)
    ft, fd = nt[:n].copy(), nd[:n].copy()
    for t in range(T):
        if label_t[t] >= 0:
            ti[ft[label_t[t]]] = t
            ft[label_t[t]] += 1
    for d in range(D):
        if label_d[d] >= 0:
            di[fd[label_d[d]]] = d
            fd[label_d[d]] += 1
    m = min(max_exact, 40)
    bound = 4 * m * m * ((1 << m) + 1500)  # :func:`_exact_is_affordable`'s
    for c in range(n):
        left[c] = False
        tr, de = ti[nt[c]:nt[c + 1]], di[nd[c]:nd[c + 1]]
        kt, kd = len(tr), len(de)
        if kt == 1:
            t = tr[0]
            den = B[t]
            for j in de:
                den += G[t, j]
            if den == 0:  # P_D P_G = 1 and weights that underflowed: left as it is
                beta0[t] = 1.0
            else:
                for j in de:
                    beta[t, j] = G[t, j] / den
                beta0[t] = B[t] / den
            continue
        positive = True
        for t in tr:
            if not B[t] > 0:
                positive = False
        if kt == 2:
            if not positive or min(kd, 2) > max_exact:
                left[c] = True
                continue
            t1, t2 = tr[0], tr[1]
            s1, s2 = B[t1], B[t2]
            for j in de:
                s1 = max(s1, G[t1, j])
                s2 = max(s2, G[t2, j])
            W1, W2 = np.empty(kd), np.empty(kd)
            for k in range(kd):
                W1[k], W2[k] = G[t1, de[k]] / s1, G[t2, de[k]] / s2
            B1, B2 = B[t1] / s1, B[t2] / s2
            if B1 < _NORMAL or B2 < _NORMAL:
                # a miss below the smallest normal float against the track's largest weight
                # keeps a few digits, or none: the events' ratios hinge on it (2/3 came out
                # 0.667 for 0.75), so such a pair is weighed in logarithms with the rest
                left[c] = True
                continue
            X1, X2 = np.zeros(kd), np.zeros(kd)  # each entry's row sum without it
            a1 = a2 = 0.0
            for k in range(kd):
                X1[k], X2[k] = a1, a2
                a1 += W1[k]
                a2 += W2[k]
            a1 = a2 = 0.0
            for k in range(kd - 1, -1, -1):
                X1[k] += a1
                X2[k] += a2
                a1 += W1[k]
                a2 += W2[k]
            S1, S2, cross = 0.0, 0.0, 0.0
            for k in range(kd):
                S1 += W1[k]
                S2 += W2[k]
                cross += W1[k] * X2[k]
            Z = B1 * B2 + B2 * S1 + B1 * S2 + cross
            for k in range(kd):
                beta[t1, de[k]] = W1[k] * (B2 + X2[k]) / Z
                beta[t2, de[k]] = W2[k] * (B1 + X1[k]) / Z
            beta0[t1] = B1 * (B2 + S2) / Z
            beta0[t2] = B2 * (B1 + S1) / Z
            continue
        K, rows = min(kt, kd), max(kt, kd)
        events, perm = 0.0, 1.0  # sum over k of C(kt, k) P(kd, k), until past the bound
        comb = 1.0
        for k in range(min(kt, kd) + 1):
            events += comb * perm
            comb = comb * (kt - k) / (k + 1)
            perm = perm * (kd - k)
        if (not positive or K > max_exact or rows * K * ((1 << K) + 1500) > bound
                or kt * events > enumerated):
            left[c] = True
            continue
        lw = np.empty((kt, kd + 1))  # log weights: the cluster's detections, then the miss
        for a in range(kt):
            for k in range(kd):
                g = G[tr[a], de[k]]
                lw[a, k] = np.log(g) if g > 0 else -np.inf
            lw[a, kd] = np.log(B[tr[a]])
        choice = np.empty(kt, np.int64)
        used = np.zeros(kd, np.bool_)
        acc = np.zeros(kt + 1)
        mass = np.zeros((kt, kd + 1))
        top, total = -np.inf, 0.0
        for walk in range(2):  # the largest weight, then the sums scaled by it
            choice[:] = -2
            a = 0
            while a >= 0:
                k = choice[a]
                if 0 <= k < kd:
                    used[k] = False
                if k == -2:
                    k = kd  # the miss first
                else:
                    k = 0 if k == kd else k + 1
                    while k < kd and (used[k] or lw[a, k] == -np.inf):
                        k += 1
                    if k >= kd:
                        choice[a] = -2
                        a -= 1
                        continue
                choice[a] = k
                if k < kd:
                    used[k] = True
                v = acc[a] + lw[a, k]
                if a < kt - 1:
                    acc[a + 1] = v
                    a += 1
                elif walk == 0:
                    top = max(top, v)
                else:
                    w = np.exp(v - top)
                    total += w
                    for b in range(kt):
                        mass[b, choice[b]] += w
        for a in range(kt):
            for k in range(kd):
                beta[tr[a], de[k]] = mass[a, k] / total
            beta0[tr[a]] = mass[a, kd] / total
    return n


def _joint(G: np.ndarray, B: np.ndarray, gate: np.ndarray, max_exact: int,
           scale: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The joint association probabilities of :func:`jpda_weights`, with ``G (T, D)`` (0
    outside the gates) and each track's weight of a miss ``B (T,)``: the clusters and the
    most common of them in :func:`_clusters`, the rest here. ``scale (T,)``: each track's
    factors were multiplied by it (:func:`_weights`); the exact sums do not see it, and
    Fitzgerald's cheap JPDA, whose sums mix the tracks, takes it out in logarithms.

    Raises a ValueError where the weights of a rescaled track span more than a float holds
    (against its miss, the events' products underflow), rather than give NaN or
    probabilities that do not sum to 1."""
    max_exact = as_whole(max_exact, "max_exact", 0)
    T, D = G.shape
    beta, beta0 = np.zeros((T, D)), np.ones(T)
    if T == 0:
        return beta, np.zeros(0)
    # a pair whose weight underflows to 0 (or a track whose existence is 0) can be in no
    # event that counts: in no cluster either (with P_D P_G = 1 a lone track's PDA form
    # was 0 / 0)
    G = np.where(gate & (G > 0), G, 0.0)
    if not G.any():
        return beta, beta0
    lt, ld = np.empty(T, np.int64), np.empty(D, np.int64)
    left = np.empty(T, np.bool_)  # (at most one cluster per track)
    n = _clusters(G, np.ascontiguousarray(B, dtype=float), min(max_exact, 2**62), _ENUMERATED,
                  beta, beta0, lt, ld, left)
    for c in np.flatnonzero(left[:n]):
        ti, di = np.flatnonzero(lt == c), np.flatnonzero(ld == c)
        g = G[np.ix_(ti, di)]
        if _exact_is_affordable(len(ti), len(di), B[ti], max_exact):
            b, b0 = _exact(g, B[ti])
        else:  # Fitzgerald's cheap JPDA
            with np.errstate(over="ignore"):
                den = g.sum(1)[:, None] + g.sum(0)[None, :] - g + B[ti, None]
            if (scale is not None and (scale[ti] != 1).any()) or not np.isfinite(den).all():
                # the tracks' scales taken out, or sums past the largest float: in logarithms
                b, b0 = _cheap_in_logs(g, B[ti], np.ones(len(ti)) if scale is None
                                       else scale[ti])
            else:
                b = g / den
                b0 = np.clip(1.0 - b.sum(1), 0.0, 1.0)
                s = b.sum(1) + b0
                b, b0 = b / s[:, None], b0 / s
        beta[np.ix_(ti, di)] = b
        beta0[ti] = b0
    if scale is not None and (scale != 1).any():
        total = beta.sum(1) + beta0
        bad = ~np.isfinite(total) | (np.abs(total - 1) > 1e-9)
        if bad.any():
            _too_wide(int(np.flatnonzero(bad)[0]), G, B, scale)
    return beta, beta0


def _too_wide(t: int, G: np.ndarray, B: np.ndarray, scale: np.ndarray | None) -> None:
    """Raise the ValueError that names track ``t``'s weights as spanning more than a float
    holds (their scale ``scale`` taken out, in logarithms)."""
    c = 1.0 if scale is None else scale[t]
    with np.errstate(divide="ignore"):  # (in logarithms: past the largest float)
        top = np.log10(G[t].max()) - np.log10(c)
        miss = np.log10(B[t]) - np.log10(c)
    reach = f"about 1e{top:.0f}" if np.isfinite(top) else "more than 1e308"
    raise ValueError(
        f"the association weights of track {t} span more than a float holds: its "
        f"likelihoods over clutter_density reach {reach} against a miss weight of "
        f"{10 ** miss if np.isfinite(miss) else 0:.3g}, and the joint events' products "
        "underflow; the likelihoods (or clutter_density) are in units of another scale?")


def _quiet_if(scale: np.ndarray) -> contextlib.AbstractContextManager:
    """numpy's warnings off where a track was rescaled (:func:`_weights`): a product that
    underflows is found, and named, by :func:`_joint` after the sums."""
    if (scale != 1).any():
        return np.errstate(invalid="ignore", divide="ignore", under="ignore")
    return contextlib.nullcontext()


def _cheap_in_logs(g: np.ndarray, B: np.ndarray, scale: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Fitzgerald's cheap JPDA, ``G_tj / (S_t + S_j - G_tj + B_t)``, on a cluster whose
    tracks' factors were each multiplied by ``scale`` (one past the largest float): in
    logarithms, the scales taken out (the column sums ``S_j`` mix the tracks)."""
    with np.errstate(divide="ignore"):
        lg = np.log(g) - np.log(scale)[:, None]  # -inf outside the gates
        lb = np.log(B) - np.log(scale)
    row = np.logaddexp.reduce(lg, axis=1)
    col = np.logaddexp.reduce(lg, axis=0)
    big = np.logaddexp(np.logaddexp(row[:, None], col[None, :]), lb[:, None])
    # minus G_tj, which both sums hold: at most half of them, so nothing cancels
    with np.errstate(divide="ignore", invalid="ignore"):
        den = big + np.log1p(-np.exp(lg - big))
        b = np.where(g > 0, np.exp(lg - den), 0.0)
    b0 = np.clip(1.0 - b.sum(1), 0.0, 1.0)
    s = b.sum(1) + b0
    return b / s[:, None], b0 / s


def jpda_weights(lik: ArrayLike, gate: ArrayLike, *, p_detect: float = 0.9,
                 clutter_density: float = 1e-4, p_gate: float = 0.99,
                 max_exact: int = 12) -> tuple[np.ndarray, np.ndarray]:
    r"""JPDA association probabilities: tracks that share detections, weighed jointly.

    Over every feasible joint event (each detection to at most one track, each track at most
    one detection, within the gates), with probability proportional to

    .. math:: \prod_{(t, j)} \frac{P_D \ell_{tj}}{\lambda}
              \prod_{t \text{ missed}} (1 - P_D P_G),

    :math:`\beta_{tj}` is the probability of the events that give detection ``j`` to track
    ``t``. The gated problem is split into independent clusters (:func:`components`). A
    cluster whose tracks or whose detections number at most ``max_exact`` is computed
    exactly (a cluster of two tracks by a closed form, whatever its detections; a small one
    of more, up to a few thousand events, event by event; a larger one by the subsets of
    that side, the weight of the ways the
    detections seen so far can take exactly a given set of tracks (or the tracks a given set
    of detections), at a cost of :math:`T D 2^{\min(T, D)}` rather than the number of events
    (1,441,729 for 8 tracks and 8 detections all in one another's gates)). A cluster beyond
    that, or one of three tracks or more whose sum would cost more than four times a dense
    ``max_exact`` x ``max_exact`` cluster's (a dozen tracks among hundreds of clutter
    points), gets Fitzgerald's cheap JPDA (1985),
    :math:`\beta_{tj} = G_{tj} / (\sum_k G_{tk} + \sum_s G_{sj} - G_{tj} + B)` with
    :math:`\beta_{t0} = \max(0, 1 - \sum_j \beta_{tj})`, each track's row then normalised to
    sum to one.

    Parameters
    ----------
    lik : (T, D) array_like
        Likelihoods :math:`\ell_{tj}` (:func:`likelihoods`).
    gate : (T, D) array_like of bool
        The detections in each track's gate (pairs of zero likelihood are left out too).
    p_detect : float
        Detection probability :math:`P_D`, in (0, 1].
    clutter_density : float
        Spatial density :math:`\lambda` of false detections, > 0.
    p_gate : float
        Gate probability :math:`P_G`, in (0, 1].
    max_exact : int
        A cluster is computed exactly when its tracks or its detections number at most this
        (its tracks, where :math:`P_D P_G = 1`), and, for three tracks or more, its cost is
        at most four times a dense ``max_exact`` x ``max_exact`` cluster's; the cost doubles
        with each one more on the smaller side (a dense 12 x 12 cluster about 5 ms, 16 x 16
        about 0.1 s). 0: every cluster of more than one track gets the cheap JPDA.

    Returns
    -------
    beta : (T, D) ndarray
        Marginal probability that detection ``j`` is track ``t``'s; 0 outside the gate.
    beta0 : (T,) ndarray
        Probability that no detection is the track's (1 for a track with none in its gate).
        With :math:`P_D P_G = 1`, where every event that misses a track weighs 0, the limit
        as :math:`P_G \to 1`: the events that miss the fewest tracks.

    Raises
    ------
    ValueError
        If a probability or the density is out of range, ``gate`` does not have the shape of
        ``lik`` or holds other than True / False (1 / 0), or a likelihood inside the gate is
        not a finite number >= 0.

    References
    ----------
    .. [1] T. E. Fortmann, Y. Bar-Shalom and M. Scheffe, "Sonar tracking of multiple targets
       using joint probabilistic data association", *IEEE Journal of Oceanic Engineering*
       8(3), 1983.

    Examples
    --------
    Two tracks; the first also sees the second's detection:

    >>> b, b0 = jpda_weights(np.array([[0.02, 0.01], [0.0, 0.02]]),
    ...                      np.array([[True, True], [False, True]]),
    ...                      p_detect=0.9, clutter_density=0.01, p_gate=1.0)
    >>> b.round(3), b0.round(3)
    (array([[0.924, 0.024],
           [0.   , 0.924]]), array([0.051, 0.076]))
    """
    p_detect, clutter_density, p_gate = _check(p_detect, clutter_density, p_gate)
    lik, gate = _lik_gate(lik, gate)
    G, c = _weights(p_detect, lik, gate, clutter_density)
    with _quiet_if(c):
        return _joint(G, (1.0 - p_detect * p_gate) * c, gate, max_exact, c)


def _existence(existence: ArrayLike, T: int) -> np.ndarray:
    eps = as_float_array(existence, "existence", not_boolean="probabilities")  # ([True] was 1)
    if eps.shape != (T,):
        raise ValueError(f"existence must have one probability per track, shape ({T},); "
                         f"got shape {eps.shape}")
    bad = ~((eps >= 0.0) & (eps <= 1.0))
    if bad.any():
        raise ValueError(f"existence must be probabilities in [0, 1]; got {eps[bad][0]} "
                         f"(track {int(np.flatnonzero(bad)[0])})")
    return eps


def _given_existence(beta: np.ndarray, beta0: np.ndarray, eps: np.ndarray, B: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """From the probabilities of each track's events, where missing a track means it was
    missed (``eps B``) or is not there (``1 - eps``): the posterior existence, and the
    association probabilities given that the track exists."""
    miss = 1.0 - eps * (1.0 - B)  # the weight of "no detection is the track's"
    with np.errstate(invalid="ignore", divide="ignore"):
        missed = np.where(miss > 0, beta0 * (eps * B) / miss, 0.0)
    post = beta.sum(1) + missed
    # no evidence can make a track certain not to be there exist: one whose every event
    # weighs 0 given it exists (P_D P_G = 1 and nothing in its gate) keeps its estimate
    none = post <= 0
    post[none] = 1.0
    b, b0 = beta / post[:, None], np.where(none, 1.0, missed / post)
    post[none] = 0.0
    return b, b0, np.minimum(post, 1.0)


def ipda_weights(lik: ArrayLike, gate: ArrayLike, existence: ArrayLike, *,
                 p_detect: float = 0.9, clutter_density: float = 1e-4, p_gate: float = 0.99
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Integrated PDA: each track's association probabilities and its probability of existence.

    A track of clutter (started from a false detection, or left behind by a target that has
    gone) is never missed by PDA in clutter: some false detection usually falls in its gate.
    IPDA (Mušicki, Evans and Stanković, 1994) carries each track's probability
    :math:`\varepsilon` that its target exists; with
    :math:`G_j = P_D \ell_j / \lambda` and :math:`B = 1 - P_D P_G`, the frame's evidence
    multiplies the odds of existence by :math:`\Lambda = B + \sum_j G_j`:

    .. math:: \varepsilon = \frac{\Lambda \varepsilon^-}{1 - \varepsilon^- + \Lambda
              \varepsilon^-},

    where :math:`\varepsilon^-` is the prior of the frame (the last posterior times the
    chance of surviving the time between). Clutter alone gives :math:`\Lambda` a mean of 1
    and a negative mean logarithm, so the existence of a track of clutter falls. Given that
    the target exists, the association probabilities are PDA's (:func:`pda_weights`).

    Parameters
    ----------
    lik : (T, D) array_like
        Likelihoods :math:`\ell_{tj}` (:func:`likelihoods`).
    gate : (T, D) array_like of bool
        The detections in each track's gate.
    existence : (T,) array_like
        Each track's prior probability of existence :math:`\varepsilon^-`, in [0, 1].
    p_detect, clutter_density, p_gate : float
        As for :func:`pda_weights`.

    Returns
    -------
    beta : (T, D) ndarray
        Probability that detection ``j`` is track ``t``'s, given the track exists.
    beta0 : (T,) ndarray
        Probability that no detection is the track's, given it exists.
    existence : (T,) ndarray
        Posterior probability of existence. (With :math:`P_D P_G = 1`, a track with nothing in
        its gate cannot exist: 0; if its prior was 1, its association is left as it is,
        ``beta0`` 1.)

    Raises
    ------
    ValueError
        If a probability or the density is out of range, ``gate`` does not have the shape of
        ``lik`` or holds other than True / False (1 / 0), a likelihood inside the gate is
        not a finite number >= 0, or ``existence`` does not have one probability in [0, 1]
        per track.

    See Also
    --------
    jipda_weights : The same for tracks that compete for detections, jointly.

    References
    ----------
    .. [1] D. Mušicki, R. Evans and S. Stanković, "Integrated probabilistic data association",
       *IEEE Transactions on Automatic Control* 39(6), 1994.

    Examples
    --------
    One detection near the track and one far from it, in the gate; then nothing in the gate:

    >>> b, b0, e = ipda_weights(np.array([[0.02, 0.001]]), np.array([[True, True]]), [0.5],
    ...                         p_detect=0.9, clutter_density=0.01, p_gate=1.0)
    >>> b.round(3).tolist(), round(float(b0[0]), 3), round(float(e[0]), 3)  # odds x 1.99
    ([[0.905, 0.045]], 0.05, 0.666)
    >>> round(float(ipda_weights(np.zeros((1, 0)), np.zeros((1, 0), bool), [0.5],
    ...                          p_detect=0.9, p_gate=1.0)[2][0]), 3)      # odds x 0.1
    0.091
    """
    p_detect, clutter_density, p_gate = _check(p_detect, clutter_density, p_gate)
    lik, gate = _lik_gate(lik, gate)
    eps = _existence(existence, len(lik))
    G, c = _weights(p_detect, lik, gate, clutter_density)
    B = 1.0 - p_detect * p_gate
    # the single track's events: not there (1 - eps), missed (eps B), detection j (eps G_j),
    # each scaled by c
    den = (1.0 - eps) * c + eps * (B * c + G.sum(1))
    with np.errstate(invalid="ignore", divide="ignore"):
        beta = np.where(den[:, None] > 0, eps[:, None] * G / den[:, None], 0.0)
        beta0 = np.where(den > 0, (1.0 - eps * (1.0 - B)) * c / den, 1.0)
    return _given_existence(beta, beta0, eps, B)


def jipda_weights(lik: ArrayLike, gate: ArrayLike, existence: ArrayLike, *,
                  p_detect: float = 0.9, clutter_density: float = 1e-4, p_gate: float = 0.99,
                  max_exact: int = 12) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Joint integrated PDA: JPDA over tracks that may not exist.

    Each track of a joint event either is not there (weight :math:`1 - \varepsilon_t`), is
    there and missed (:math:`\varepsilon_t B`) or is there and takes detection ``j``
    (:math:`\varepsilon_t G_{tj}`, :math:`G_{tj} = P_D \ell_{tj} / \lambda`); not being
    there and being missed both leave it without a detection, so the joint events are
    JPDA's (:func:`jpda_weights`) with :math:`G_{tj}` weighed by :math:`\varepsilon_t` and a
    miss by :math:`1 - \varepsilon_t P_D P_G`: JPDA with detection probability
    :math:`\varepsilon_t P_D` (Mušicki and Evans, 2004). The posterior existence is the
    probability of the events where the track takes a detection, plus the share
    :math:`\varepsilon_t B / (1 - \varepsilon_t P_D P_G)` of those where it takes none. A
    lone track gets :func:`ipda_weights`' values. A cluster that :func:`jpda_weights`
    would not compute exactly (``max_exact``) gets Fitzgerald's cheap JPDA on these
    weights.

    Parameters
    ----------
    lik, gate, existence, p_detect, clutter_density, p_gate
        As for :func:`ipda_weights`.
    max_exact : int
        As for :func:`jpda_weights`.

    Returns
    -------
    beta, beta0, existence : ndarray
        As for :func:`ipda_weights`: the association probabilities given each track exists,
        and the posterior existence. With :math:`P_D P_G = 1`, a track exists only in the
        events where it takes a detection, so one whose prior is 1 has the posterior
        existence of those events (the limit as the prior tends to 1): two such tracks with
        one detection between them split it, each existing with the probability that the
        detection is its own. :func:`jpda_weights` takes the other limit,
        :math:`P_G \to 1` at a prior of 1, where both tracks exist and one is missed.

    Raises
    ------
    ValueError
        As for :func:`ipda_weights`.

    References
    ----------
    .. [1] D. Mušicki and R. Evans, "Joint integrated probabilistic data association:
       JIPDA", *IEEE Transactions on Aerospace and Electronic Systems* 40(3), 2004.

    Examples
    --------
    Two tracks share a detection; the second, less likely to exist, gets less of it:

    >>> b, b0, e = jipda_weights(np.array([[0.02], [0.02]]), np.ones((2, 1), bool),
    ...                          [0.9, 0.3], p_detect=0.9, clutter_density=0.01,
    ...                          p_gate=1.0)
    >>> b.round(3).ravel().tolist(), e.round(3).tolist()
    ([0.912, 0.654], [0.911, 0.11])
    """
    p_detect, clutter_density, p_gate = _check(p_detect, clutter_density, p_gate)
    lik, gate = _lik_gate(lik, gate)
    eps = _existence(existence, len(lik))
    G, c = _weights((eps * p_detect)[:, None], lik, gate, clutter_density)
    with _quiet_if(c):
        beta, beta0 = _joint(G, (1.0 - eps * p_detect * p_gate) * c, gate, max_exact, c)
    return _given_existence(beta, beta0, eps, 1.0 - p_detect * p_gate)

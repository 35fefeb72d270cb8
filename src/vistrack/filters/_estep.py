"""EM's E-step (:mod:`vistrack.filters.learn`) in one compiled pass, for the common case.

When ``F``, ``Q``, ``H`` and ``R`` are constant, every series has the same prior covariance and
each step is measured in full or not at all, the same steps in every series, then every series
shares one sequence of covariances, gains and smoother gains. :func:`estep_shared` computes that
sequence once, the filter's and the smoother's, and stops computing it while it stays at its
steady state (a stretch of measured steps over which the covariances no longer change, to a
few units in the last place: each step there reads the last computed step's, by index). It
then runs each series' means forward and back, a block of series at a time, and returns only
what the M-step needs: the log-likelihood, the expected outer products of the process noise
``sum E[w_t w_t']`` (``w_t = x_t - F x_{t-1}``) and of the measurement noise ``sum E[v_t
v_t']`` (``v_t = y_t - H x_t``), both summed over the steps and series, and the first step's
smoothed means and covariance. The process noise's sum is taken term by term, not as ``S11 -
F S10' - S10 F' + F S00 F'`` from sums of outer products of states, whose terms grow with the
state's distance from the origin and cancel.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from .._prebuilt import kernel
from ._kernels import _FM, _LOG2PI, CH, back_solve, chol_factor, copy_mat, forward_solve

__all__ = ["estep_shared", "work_layout", "NOT_POSITIVE", "WORK_TOO_SMALL"]

NOT_POSITIVE = -2.0
"""``out[1]`` when a predicted covariance is singular: the smoother's gain needs its inverse
(the caller then takes the general path, which says where)."""

WORK_TOO_SMALL = -3.0
"""``out[1]`` when the work space given is smaller than :func:`work_layout`'s size (nothing
computed)."""

_TINY = 4.0 * float(np.finfo(np.float64).eps)


@njit(cache=True)
def _close(A, B):
    """True when the covariances ``A`` and ``B`` differ by at most a few units in the last
    place of each entry's own scale, ``sqrt(A_ii A_jj)`` (the bound on ``|A_ij|``). Against
    the largest entry, a state whose variance is 1e-10 of another's was taken as settled
    while it still changed (Q learned 20 % off at a ratio of 1e14)."""
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            if abs(A[i, j] - B[i, j]) > _TINY * math.sqrt(abs(A[i, i] * A[j, j])):
                return False
    return True


@njit(cache=True, fastmath=_FM)
def _covariances(meas, F, Q, H, R, P0, Pp, Pf, K, L, logdet, same, src):
    """The filter's covariances of one series: predicted ``Pp`` and corrected ``Pf`` ``(T, n,
    n)``, gains ``K (T, n, m)``, the Cholesky factors ``L`` of the innovation covariances and
    half their log-determinants, of each step ``t`` at index ``src[t]``: ``t`` where
    computed, the step before's index where step ``t`` is the step before again at the
    steady state (``same[t]`` True; nothing is written for it). Returns the first step whose
    innovation covariance is not positive definite, or -1."""
    T, n, m = K.shape
    FP = np.empty((n, n))
    HP = np.empty((m, n))
    S = np.empty((m, m))
    IKH = np.empty((n, n))
    M = np.empty((n, n))
    steady = False
    for t in range(T):
        if steady and meas[t]:  # at the steady state: step t is step t - 1 again
            src[t] = src[t - 1]
            same[t] = True
            continue
        same[t] = False
        src[t] = t
        steady = False
        if t == 0:
            for i in range(n):
                for j in range(n):
                    Pp[0, i, j] = P0[i, j]
        else:
            for i in range(n):
                for j in range(n):
                    s = 0.0
                    for l in range(n):
                        f = F[i, l]
                        if f != 0.0:
                            s += f * Pf[src[t - 1], l, j]
                    FP[i, j] = s
            for i in range(n):
                for j in range(i, n):
                    s = Q[i, j]
                    for l in range(n):
                        f = F[j, l]
                        if f != 0.0:
                            s += FP[i, l] * f
                    Pp[t, i, j] = s
                    Pp[t, j, i] = s
        if not meas[t]:
            copy_mat(Pf[t], Pp[t])
            for i in range(n):
                for k in range(m):
                    K[t, i, k] = 0.0
            logdet[t] = 0.0
            continue
        for k in range(m):
            for j in range(n):
                s = 0.0
                for i in range(n):
                    h = H[k, i]
                    if h != 0.0:
                        s += h * Pp[t, i, j]
                HP[k, j] = s
        for k in range(m):
            for q in range(k, m):
                s = R[k, q]
                for i in range(n):
                    h = H[q, i]
                    if h != 0.0:
                        s += HP[k, i] * h
                S[k, q] = s
                S[q, k] = s
        if not chol_factor(L[t], S, m):
            return t
        ld = 0.0
        for k in range(m):
            ld += math.log(L[t, k, k])
        logdet[t] = ld
        forward_solve(L[t], HP, m, n)  # HP becomes S^-1 H Pp = K'
        back_solve(L[t], HP, m, n)
        for i in range(n):
            for k in range(m):
                K[t, i, k] = HP[k, i]
        # Joseph form: (I - K H) Pp (I - K H)' + K R K'
        for i in range(n):
            for j in range(n):
                s = 1.0 if i == j else 0.0
                for k in range(m):
                    s -= K[t, i, k] * H[k, j]
                IKH[i, j] = s
        for i in range(n):
            for j in range(n):
                s = 0.0
                for l in range(n):
                    s += IKH[i, l] * Pp[t, l, j]
                M[i, j] = s
        for i in range(n):
            for j in range(i, n):
                s = 0.0
                for l in range(n):
                    s += M[i, l] * IKH[j, l]
                for k in range(m):
                    kr = 0.0
                    for q in range(m):
                        kr += K[t, i, q] * R[q, k]
                    s += kr * K[t, j, k]
                Pf[t, i, j] = s
                Pf[t, j, i] = s
        if t > 0 and meas[t - 1]:
            u = src[t - 1]
            steady = _close(Pf[t], Pf[u]) and _close(Pp[t], Pp[u])
    return -1


@njit(cache=True, fastmath=_FM)
def _add_hph(H, P, HP, v, V):
    """``v = H P H'`` (``HP`` scratch ``(m, n)``), added to ``V``."""
    m, n = HP.shape
    for k in range(m):
        for j in range(n):
            s = 0.0
            for i in range(n):
                h = H[k, i]
                if h != 0.0:
                    s += h * P[i, j]
            HP[k, j] = s
    for k in range(m):
        for q in range(m):
            s = 0.0
            for i in range(n):
                h = H[q, i]
                if h != 0.0:
                    s += HP[k, i] * h
            v[k, q] = s
            V[k, q] += s


@njit(cache=True, fastmath=_FM)
def _smoothed_covariances(meas, F, Q, H, Pp, Pf, same, src, X, xsrc, A, V, Ps0):
    """The smoother's covariances of one series, backwards from the filter's (at ``src``, see
    :func:`_covariances`), with the transposed gains ``X_t = Pp_{t+1}^-1 F Pf_t`` of each
    transition at ``X[xsrc[t]]`` (``X (T - 1, n, n)``, written where computed); adds to
    ``A (n, n)`` each transition's part of ``E[w_t w_t']`` that is not from the means, ``Ps_t -
    F C_t' - C_t F' + F Ps_{t-1} F'`` (``C_t = Ps_t X_{t-1}``, the lag-one covariance), and to
    ``V (m, m)`` each measured step's ``H Ps_t H'``, per series; writes the first step's
    ``Ps0``. Both covariances are computed as sums of positive semi-definite terms (see the
    loop), which keep a small variance beside a large one. Returns False if a predicted
    covariance is singular."""
    T, n, _ = Pp.shape
    m = H.shape[0]
    Ps = Pf[src[T - 1]].copy()
    Pn = np.empty((n, n))
    Lp = np.empty((n, n))
    D = np.empty((n, n))
    DX = np.empty((n, n))
    C = np.empty((n, n))
    FC = np.empty((n, n))
    FPs = np.empty((n, n))
    HP = np.empty((m, n))
    a = np.zeros((n, n))  # the last transition's term, and the last step's
    v = np.zeros((m, m))

    if meas[T - 1]:
        _add_hph(H, Ps, HP, v, V)
    steady = False
    repeats = 0  # steps at the steady state since a and v were last added
    for t in range(T - 2, -1, -1):
        if steady and same[t + 1] and same[t + 2]:  # t + 2 < T: same[T - 1] implies steady
            xsrc[t] = xsrc[t + 1]
            repeats += 1
            continue
        if repeats:
            _add_repeats(a, v, repeats, A, V)
            repeats = 0
        steady = False
        xsrc[t] = t
        ft, pt = src[t], src[t + 1]
        # X_t = Pp_{t+1}^-1 F Pf_t
        for i in range(n):
            for j in range(n):
                s = 0.0
                for l in range(n):
                    f = F[i, l]
                    if f != 0.0:
                        s += f * Pf[ft, l, j]
                X[t, i, j] = s
        if not chol_factor(Lp, Pp[pt], n):
            return False
        forward_solve(Lp, X[t], n, n)
        back_solve(Lp, X[t], n, n)
        # Ps_t = Pf_t + X_t' (Ps_{t+1} - Pp_{t+1}) X_t, as the sum of semi-definite terms
        # (I - X' F) Pf (I - X' F)' + X' (Q + Ps_{t+1}) X (rts_smooth's form: the difference
        # lost a variance of 1e-8 beside one of 1e8, which the steady state then repeated)
        for i in range(n):
            for j in range(n):
                s = 1.0 if i == j else 0.0
                for l in range(n):
                    f = F[l, j]
                    if f != 0.0:
                        s -= X[t, l, i] * f
                D[i, j] = s  # I - X' F
                C[i, j] = Q[i, j] + Ps[i, j]
        for i in range(n):
            for j in range(n):
                s = 0.0
                s2 = 0.0
                for l in range(n):
                    s += D[i, l] * Pf[ft, l, j]
                    s2 += X[t, l, i] * C[l, j]
                DX[i, j] = s  # (I - X' F) Pf
                FC[i, j] = s2  # X' (Q + Ps)
        for i in range(n):
            for j in range(i, n):
                s = 0.0
                for l in range(n):
                    s += DX[i, l] * D[j, l] + FC[i, l] * X[t, l, j]
                Pn[i, j] = s
                Pn[j, i] = s
        # the transition t -> t + 1: Cov(w_t | y), w_t = x_{t+1} - F x_t, equal to Ps_{t+1} -
        # F C' - C F' + F Ps_t F' (C = Ps_{t+1} X_t) but as the sum of semi-definite terms
        # (I - K) Q (I - K)' + K (F Pf F' + Ps_{t+1}) K', K = Q Pp^-1 (w_t given x_{t+1} and
        # the measurements to t, then x_{t+1}'s smoothed spread)
        for i in range(n):
            for j in range(n):
                C[i, j] = Q[i, j]
        forward_solve(Lp, C, n, n)
        back_solve(Lp, C, n, n)  # C = Pp^-1 Q = K'
        for i in range(n):
            for j in range(n):
                s = 0.0
                for l in range(n):
                    f = F[i, l]
                    if f != 0.0:
                        s += f * Pf[ft, l, j]
                FC[i, j] = s  # F Pf
        for i in range(n):
            for j in range(i, n):
                s = 0.0
                for l in range(n):
                    f = F[j, l]
                    if f != 0.0:
                        s += FC[i, l] * f
                FPs[i, j] = s + Ps[i, j]  # F Pf F' + Ps
                FPs[j, i] = FPs[i, j]
        for i in range(n):
            for j in range(n):
                D[i, j] = (1.0 if i == j else 0.0) - C[j, i]  # I - K
        for i in range(n):
            for j in range(n):
                s = 0.0
                s2 = 0.0
                for l in range(n):
                    s += D[i, l] * Q[l, j]
                    s2 += C[l, i] * FPs[l, j]
                DX[i, j] = s  # (I - K) Q
                FC[i, j] = s2  # K (F Pf F' + Ps)
        for i in range(n):
            for j in range(i, n):
                s = 0.0
                for l in range(n):
                    s += DX[i, l] * D[j, l] + FC[i, l] * C[l, j]
                a[i, j] = s
                a[j, i] = s
        for i in range(n):
            for j in range(n):
                A[i, j] += a[i, j]
        if same[t + 1] and same[t + 2] and _close(Pn, Ps):  # same[T] is False
            steady = True
        for i in range(n):
            for j in range(n):
                Ps[i, j] = Pn[i, j]
        if meas[t]:
            _add_hph(H, Ps, HP, v, V)
    _add_repeats(a, v, repeats, A, V)
    for i in range(n):
        for j in range(n):
            Ps0[i, j] = Ps[i, j]
    return True


@njit(cache=True, fastmath=_FM)
def _add_repeats(a, v, repeats, A, V):
    """``A += repeats a``, ``V += repeats v``: the terms of ``repeats`` steps at the steady
    state, each a copy of the last computed (at the steady state every step is measured)."""
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            A[i, j] += repeats * a[i, j]
    for k in range(v.shape[0]):
        for q in range(v.shape[1]):
            V[k, q] += repeats * v[k, q]


@njit(cache=True)
def work_layout(T, n, m, B):
    """The work space of :func:`estep_shared` for ``B`` series of ``T`` steps, ``n`` states and
    ``m`` measured values: ``(size, rows, means, gap)``, its floats, the rows of series in a
    block of the means' pass (:data:`CH` series at most, 8 more: see :func:`estep_shared`),
    the floats of each of that pass's two arrays of means ``(T, n, rows)``, and the floats
    between them. (From Python, ``work_layout.py_func``, which calls nothing compiled.)"""
    rows = min(CH, B) + 8
    means = T * n * rows
    gap = ((2048 - 8 * means) % 4096) // 8
    size = 2 * T * n * n + T * n * m + T * m * m + T + max(T - 1, 1) * n * n + 2 * means + gap
    return size, rows, means, gap


@kernel
@njit(cache=True, fastmath=_FM)
def estep_shared(yt, F, Q, H, R, x0, P0, A, V, ms0, Ps0, work, out):
    """The E-step of series ``ys (B, T, m)`` that share their covariances (see the module),
    from the prior ``x0 (1 or B, n)``, ``P0 (n, n)``: writes ``A (n, n) = sum E[w_t w_t']``
    over the transitions and series, ``V (m, m) = sum E[v_t v_t']`` over the measured steps
    and series, the smoothed first means ``ms0 (B, n)`` and covariance ``Ps0 (n, n)``, and
    ``out = [log-likelihood, status]``: status -1 when done, the step whose innovation
    covariance is not positive definite, :data:`NOT_POSITIVE` or :data:`WORK_TOO_SMALL`.

    ``work`` holds the large arrays, at least :func:`work_layout`'s size: EM calls this once an
    iteration, and arrays allocated afresh at each call cost as much again in a process that
    has not yet freed memory of that size (the allocator maps new pages for them)."""
    T, m, B = yt.shape
    n = F.shape[0]
    need, Wr, size, pad = work_layout(T, n, m, B)
    if work.shape[0] < need:
        out[1] = WORK_TOO_SMALL
        return
    meas = np.empty(T, np.bool_)
    for t in range(T):
        meas[t] = not math.isnan(yt[t, 0, 0])
    o = 0
    Pp = work[o:o + T * n * n].reshape((T, n, n))
    o += T * n * n
    Pf = work[o:o + T * n * n].reshape((T, n, n))
    o += T * n * n
    K = work[o:o + T * n * m].reshape((T, n, m))
    o += T * n * m
    L = work[o:o + T * m * m].reshape((T, m, m))  # (read on and below the diagonal only)
    o += T * m * m
    logdet = work[o:o + T]
    o += T
    X = work[o:o + max(T - 1, 1) * n * n].reshape((max(T - 1, 1), n, n))
    o += max(T - 1, 1) * n * n
    same = np.zeros(T + 1, np.bool_)  # same[T] False: no step after the last
    src = np.empty(T, np.int64)
    xsrc = np.empty(max(T - 1, 1), np.int64)
    A[:] = 0.0
    V[:] = 0.0
    out[0] = 0.0
    bad = _covariances(meas, F, Q, H, R, P0, Pp, Pf, K, L, logdet, same[:T], src)
    if bad >= 0:
        out[1] = bad
        return
    if not _smoothed_covariances(meas, F, Q, H, Pp, Pf, same, src, X, xsrc, A, V, Ps0):
        out[1] = NOT_POSITIVE
        return
    for i in range(n):  # the covariances' parts stand for every series
        for j in range(n):
            A[i, j] *= B
    for k in range(m):
        for q in range(m):
            V[k, q] *= B
    const = 0.0
    for t in range(T):
        if meas[t]:
            const -= logdet[src[t]] + 0.5 * m * _LOG2PI
    ll_total = B * const

    W = min(CH, B)
    # Each row of series is 64 bytes longer than the series: the processor stalls a load
    # whose address matches a pending store's in its last 12 bits, which rows of 128 series
    # (1 KiB) and page-aligned arrays would bring about at every step (3 to 4 times slower,
    # measured). The predicted means lie 2 KiB off a multiple of 4 KiB from the corrected.
    xf = work[o:o + size].reshape((T, n, Wr))  # each block's corrected and predicted means
    o += size + pad
    xp = work[o:o + size].reshape((T, n, Wr))
    x = np.empty((n, Wr))
    s = np.empty((n, Wr))
    sn = np.empty((n, Wr))
    d = np.empty((n, Wr))
    e = np.empty((m, Wr))
    w = np.empty((m, Wr))
    ll = np.empty(Wr)
    Aw = np.empty((n, n, Wr))  # sums kept per series, so that the loops over series vectorise
    Vw = np.empty((m, m, Wr))
    for b0 in range(0, B, W):
        c = min(W, B - b0)
        for j in range(c):
            bx = b0 + j if x0.shape[0] > 1 else 0
            for i in range(n):
                x[i, j] = x0[bx, i]
            ll[j] = 0.0
        Aw[:] = 0.0
        Vw[:] = 0.0
        # forward: the filter's means
        for t in range(T):
            if t == 0:
                for i in range(n):
                    for j in range(c):
                        xp[0, i, j] = x[i, j]
            else:
                for i in range(n):
                    for j in range(c):
                        xp[t, i, j] = 0.0
                    for l in range(n):
                        f = F[i, l]
                        if f != 0.0:
                            for j in range(c):
                                xp[t, i, j] += f * xf[t - 1, l, j]
            if not meas[t]:
                for i in range(n):
                    for j in range(c):
                        xf[t, i, j] = xp[t, i, j]
                continue
            for k in range(m):
                for j in range(c):
                    e[k, j] = yt[t, k, b0 + j]
                for i in range(n):
                    h = H[k, i]
                    if h != 0.0:
                        for j in range(c):
                            e[k, j] -= h * xp[t, i, j]
            lt = src[t]
            for k in range(m):  # the innovation whitened: L w = e
                for j in range(c):
                    w[k, j] = e[k, j]
                for q in range(k):
                    lkq = L[lt, k, q]
                    if lkq != 0.0:
                        for j in range(c):
                            w[k, j] -= lkq * w[q, j]
                inv = 1.0 / L[lt, k, k]
                for j in range(c):
                    w[k, j] *= inv
                    ll[j] -= 0.5 * w[k, j] * w[k, j]
            for i in range(n):
                for j in range(c):
                    xf[t, i, j] = xp[t, i, j]
                for k in range(m):
                    g = K[lt, i, k]
                    if g != 0.0:
                        for j in range(c):
                            xf[t, i, j] += g * e[k, j]
        # backward: the smoother's means, and the noises' outer products from them
        for i in range(n):
            for j in range(c):
                s[i, j] = xf[T - 1, i, j]
        for t in range(T - 1, -1, -1):
            if t < T - 1:
                xt = xsrc[t]
                for i in range(n):
                    for j in range(c):
                        sn[i, j] = xf[t, i, j]
                    for k in range(n):
                        g = X[xt, k, i]
                        if g != 0.0:
                            for j in range(c):
                                sn[i, j] += g * (s[k, j] - xp[t + 1, k, j])
                for i in range(n):  # w_{t+1} = x_{t+1} - F x_t
                    for j in range(c):
                        d[i, j] = s[i, j]
                    for l in range(n):
                        f = F[i, l]
                        if f != 0.0:
                            for j in range(c):
                                d[i, j] -= f * sn[l, j]
                for i in range(n):
                    for k in range(i, n):
                        for j in range(c):
                            Aw[i, k, j] += d[i, j] * d[k, j]
                for i in range(n):
                    for j in range(c):
                        s[i, j] = sn[i, j]
            if meas[t]:
                for k in range(m):
                    for j in range(c):
                        e[k, j] = yt[t, k, b0 + j]
                    for i in range(n):
                        h = H[k, i]
                        if h != 0.0:
                            for j in range(c):
                                e[k, j] -= h * s[i, j]
                for k in range(m):
                    for q in range(k, m):
                        for j in range(c):
                            Vw[k, q, j] += e[k, j] * e[q, j]
        for j in range(c):
            for i in range(n):
                ms0[b0 + j, i] = s[i, j]
            ll_total += ll[j]
        for i in range(n):
            for k in range(i, n):
                acc = 0.0
                for j in range(c):
                    acc += Aw[i, k, j]
                A[i, k] += acc
                if k != i:
                    A[k, i] += acc
        for k in range(m):
            for q in range(k, m):
                acc = 0.0
                for j in range(c):
                    acc += Vw[k, q, j]
                V[k, q] += acc
                if q != k:
                    V[q, k] += acc
    out[0] = ll_total
    out[1] = -1.0

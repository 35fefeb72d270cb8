"""Compiled Kalman kernels (numba). Private: the public API is in :mod:`vistrack.filters.kalman`.

Layout. The batched kernels work on a chunk of ``CH`` series at a time in structure-of-arrays form
(``x[i, j]`` is entry ``i`` of series ``j``), with the series index as the innermost loop, so that
LLVM turns every matrix operation into SIMD code over series. Entries of ``F`` and ``H`` that are
zero are skipped by a scalar test outside that loop: the constant-position, -velocity,
-acceleration and periodic models, whose ``F`` is mostly zeros, and position measurements, whose
``H`` is a selection, get their sparsity exploited by this one kernel.

Missing measurement components (NaN) are handled exactly and without a branch per series: a
missing component ``k`` gets a zero innovation, a zero column ``k`` in ``P H'`` and a unit,
decoupled row and column in ``S``. Its Kalman-gain column is then zero, and the update equals the
update with the observed components only.

Covariance updates use the Joseph form ``(I - K H) P (I - K H)' + K R K'``, computed on the upper
triangle and mirrored, so covariances stay symmetric and positive semi-definite; gains come from
Cholesky solves, never an explicit inverse.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

CH = 64  # series per chunk
_LOG2PI = math.log(2.0 * math.pi)
_FM = {"contract", "arcp", "nsz", "reassoc"}  # fast-math without assuming "no NaN"


@njit(cache=True, fastmath=_FM)
def predict_chunk(F, Q, tf, tq, x, P, xp, Pp, FP, c):
    """``xp = F x``, ``Pp = F P F' + Q`` for ``c`` series in SoA layout (``x (n, CH)``,
    ``P (n, n, CH)``), skipping the zero entries of ``F``; ``FP`` is scratch."""
    n = x.shape[0]
    for i in range(n):
        for j in range(c):
            xp[i, j] = 0.0
        for k in range(n):
            for j in range(c):
                FP[i, k, j] = 0.0
        for l in range(n):
            f = F[tf, i, l]
            if f != 0.0:
                for j in range(c):
                    xp[i, j] += f * x[l, j]
                for k in range(n):
                    for j in range(c):
                        FP[i, k, j] += f * P[l, k, j]
    for i in range(n):
        for k in range(i, n):
            q = Q[tq, i, k]
            for j in range(c):
                Pp[i, k, j] = q
            for l in range(n):
                f = F[tf, k, l]
                if f != 0.0:
                    for j in range(c):
                        Pp[i, k, j] += FP[i, l, j] * f
            if k != i:
                for j in range(c):
                    Pp[k, i, j] = Pp[i, k, j]


@njit(cache=True, fastmath=_FM)
def predict_batch(mean, cov, F, Q, out_mean, out_cov):
    """Predict a batch of Gaussians ``mean (B, n)``, ``cov (B, n, n)`` with ``F, Q (1, n, n)``."""
    B, n = mean.shape
    x = np.empty((n, CH))
    P = np.empty((n, n, CH))
    xp = np.empty((n, CH))
    Pp = np.empty((n, n, CH))
    FP = np.empty((n, n, CH))
    for b0 in range(0, B, CH):
        c = min(CH, B - b0)
        for j in range(c):
            for i in range(n):
                x[i, j] = mean[b0 + j, i]
                for k in range(n):
                    P[i, k, j] = cov[b0 + j, i, k]
        predict_chunk(F, Q, 0, 0, x, P, xp, Pp, FP, c)
        for j in range(c):
            for i in range(n):
                out_mean[b0 + j, i] = xp[i, j]
                for k in range(n):
                    out_cov[b0 + j, i, k] = Pp[i, k, j]


@njit(cache=True, fastmath=_FM)
def kf_batch(
    ys, F, Q, H, R, x0, P0, means, covs, pmeans, pcovs, loglik, last_P, gains, chol, store_covs
):
    """Filter ``B`` series ``ys (B, T, m)``; see :func:`vistrack.filters.kalman_filter`.

    ``F, Q (TF, n, n)``, ``H (TH, m, n)``, ``R (TR, m, m)`` with each leading size 1 or T.
    ``x0 (B0, n)``, ``P0 (BP, n, n)`` with B0, BP in {1, B}. Writes ``means``, ``pmeans``
    ``(B, T, n)``, ``loglik (B,)``, ``last_P (B, n, n)`` and, when ``store_covs``, ``covs`` and
    ``pcovs (B, T, n, n)``. When ``gains`` has ``T`` rows (used with ``B == 1``) it also writes
    the Kalman gains ``(T, n, m)`` and the Cholesky factors of ``S`` ``(T, m, m)`` into ``chol``.
    Returns the first step whose innovation covariance is not positive definite, or -1.
    """
    B, T, m = ys.shape
    n = x0.shape[1]
    want_gains = gains.shape[0] == T
    x = np.empty((n, CH))
    xp = np.empty((n, CH))
    P = np.empty((n, n, CH))
    Pp = np.empty((n, n, CH))
    FP = np.empty((n, n, CH))
    A = np.empty((n, n, CH))
    AP = np.empty((n, n, CH))
    U = np.empty((n, m, CH))
    K = np.empty((n, m, CH))
    S = np.empty((m, m, CH))
    e = np.empty((m, CH))
    wv = np.empty((m, CH))
    obs = np.empty((m, CH))
    ll = np.empty(CH)
    nobs = np.empty(CH)
    bad_t = -1
    for b0 in range(0, B, CH):
        c = min(CH, B - b0)
        for j in range(c):
            bx = b0 + j if x0.shape[0] > 1 else 0
            bp = b0 + j if P0.shape[0] > 1 else 0
            for i in range(n):
                x[i, j] = x0[bx, i]
                for k in range(n):
                    P[i, k, j] = P0[bp, i, k]
            ll[j] = 0.0
        for t in range(T):
            # ---- predict: xp = F x, Pp = F P F' + Q (none before the first step) ----
            if t == 0:
                for i in range(n):
                    for j in range(c):
                        xp[i, j] = x[i, j]
                    for k in range(n):
                        for j in range(c):
                            Pp[i, k, j] = P[i, k, j]
            else:
                predict_chunk(F, Q, t if F.shape[0] > 1 else 0, t if Q.shape[0] > 1 else 0,
                              x, P, xp, Pp, FP, c)
            for i in range(n):
                for j in range(c):
                    pmeans[b0 + j, t, i] = xp[i, j]
                if store_covs:
                    for k in range(n):
                        for j in range(c):
                            pcovs[b0 + j, t, i, k] = Pp[i, k, j]
            # ---- update ----
            th = t if H.shape[0] > 1 else 0
            tr = t if R.shape[0] > 1 else 0
            for j in range(c):
                nobs[j] = 0.0
            for k in range(m):
                for j in range(c):
                    yv = ys[b0 + j, t, k]
                    o = 0.0 if math.isnan(yv) else 1.0
                    obs[k, j] = o
                    nobs[j] += o
                    e[k, j] = yv if o == 1.0 else 0.0
                for i in range(n):
                    h = H[th, k, i]
                    if h != 0.0:
                        for j in range(c):
                            e[k, j] -= obs[k, j] * h * xp[i, j]
            any_obs = False
            for j in range(c):
                if nobs[j] > 0.0:
                    any_obs = True
            if any_obs:
                # U = Pp H' (n x m), masked; S = H U + R, decoupled on missing components
                for i in range(n):
                    for k in range(m):
                        for j in range(c):
                            U[i, k, j] = 0.0
                        for l in range(n):
                            h = H[th, k, l]
                            if h != 0.0:
                                for j in range(c):
                                    U[i, k, j] += Pp[i, l, j] * h
                        for j in range(c):
                            U[i, k, j] *= obs[k, j]
                for k in range(m):
                    for k2 in range(k, m):
                        r = R[tr, k, k2]
                        for j in range(c):
                            S[k, k2, j] = r
                        for i in range(n):
                            h = H[th, k, i]
                            if h != 0.0:
                                for j in range(c):
                                    S[k, k2, j] += h * U[i, k2, j]
                        for j in range(c):
                            both = obs[k, j] * obs[k2, j]
                            S[k, k2, j] = both * S[k, k2, j] + (1.0 - both) * (k == k2)
                            S[k2, k, j] = S[k, k2, j]
                # Cholesky S = L L' in place (lower triangle of S)
                for k in range(m):
                    for j in range(c):
                        d = S[k, k, j]
                        for p in range(k):
                            d -= S[k, p, j] * S[k, p, j]
                        if not d > 0.0:
                            if bad_t < 0 or t < bad_t:
                                bad_t = t
                            d = 1.0
                        S[k, k, j] = math.sqrt(d)
                    for k2 in range(k + 1, m):
                        for j in range(c):
                            s = S[k2, k, j]
                            for p in range(k):
                                s -= S[k2, p, j] * S[k, p, j]
                            S[k2, k, j] = s / S[k, k, j]
                # K = U S^-1: solve L z = U[i]' then L' K[i]' = z, per state row i
                for i in range(n):
                    for k in range(m):
                        for j in range(c):
                            s = U[i, k, j]
                            for p in range(k):
                                s -= S[k, p, j] * K[i, p, j]
                            K[i, k, j] = s / S[k, k, j]
                    for k in range(m - 1, -1, -1):
                        for j in range(c):
                            s = K[i, k, j]
                            for p in range(k + 1, m):
                                s -= S[p, k, j] * K[i, p, j]
                            K[i, k, j] = s / S[k, k, j]
                # log-likelihood of the innovation: whiten w = L^-1 e (missing: e = 0, L_kk = 1)
                for k in range(m):
                    for j in range(c):
                        s = e[k, j]
                        for p in range(k):
                            s -= S[k, p, j] * wv[p, j]
                        w = s / S[k, k, j]
                        wv[k, j] = w
                        ll[j] -= 0.5 * w * w + math.log(S[k, k, j])
                for j in range(c):
                    ll[j] -= 0.5 * nobs[j] * _LOG2PI
                # mean
                for i in range(n):
                    for j in range(c):
                        s = xp[i, j]
                        for k in range(m):
                            s += K[i, k, j] * e[k, j]
                        x[i, j] = s
                # Joseph form: A = I - K H; P = A Pp A' + K R K'
                for i in range(n):
                    for l in range(n):
                        for j in range(c):
                            A[i, l, j] = 1.0 if i == l else 0.0
                    for k in range(m):
                        for l in range(n):
                            h = H[th, k, l]
                            if h != 0.0:
                                for j in range(c):
                                    A[i, l, j] -= K[i, k, j] * h
                for i in range(n):
                    for l in range(n):
                        for j in range(c):
                            AP[i, l, j] = 0.0
                        for r in range(n):
                            for j in range(c):
                                AP[i, l, j] += A[i, r, j] * Pp[r, l, j]
                for i in range(n):
                    for l in range(i, n):
                        for j in range(c):
                            s = 0.0
                            for r in range(n):
                                s += AP[i, r, j] * A[l, r, j]
                            P[i, l, j] = s
                        for k in range(m):
                            for k2 in range(m):
                                r = R[tr, k, k2]
                                if r != 0.0:
                                    for j in range(c):
                                        P[i, l, j] += K[i, k, j] * r * K[l, k2, j]
                        if l != i:
                            for j in range(c):
                                P[l, i, j] = P[i, l, j]
                if want_gains:
                    for i in range(n):
                        for k in range(m):
                            gains[t, i, k] = K[i, k, 0]
                    for k in range(m):
                        for k2 in range(m):
                            chol[t, k, k2] = S[k, k2, 0] if k2 <= k else 0.0
            else:
                for i in range(n):
                    for j in range(c):
                        x[i, j] = xp[i, j]
                    for k in range(n):
                        for j in range(c):
                            P[i, k, j] = Pp[i, k, j]
                if want_gains:
                    for i in range(n):
                        for k in range(m):
                            gains[t, i, k] = 0.0
                    for k in range(m):
                        for k2 in range(m):
                            chol[t, k, k2] = 1.0 if k == k2 else 0.0
            for i in range(n):
                for j in range(c):
                    means[b0 + j, t, i] = x[i, j]
                if store_covs:
                    for k in range(n):
                        for j in range(c):
                            covs[b0 + j, t, i, k] = P[i, k, j]
        for j in range(c):
            loglik[b0 + j] = ll[j]
            for i in range(n):
                for k in range(n):
                    last_P[b0 + j, i, k] = P[i, k, j]
    return bad_t


@njit(cache=True, fastmath=_FM)
def kf_means_shared(ys, F, H, x0, gains, chol, means, pmeans, loglik):
    """Mean recursion for series that share their covariances and gains.

    ``gains (T, n, m)`` and ``chol (T, m, m)`` come from :func:`kf_batch` run on one series with
    the shared missing-data pattern; missing components have zero gain columns and unit rows in
    ``chol``. Each series costs ``F x``, ``H x``, ``K e`` and a triangular solve per step.
    """
    B, T, m = ys.shape
    n = x0.shape[1]
    x = np.empty((n, CH))
    xp = np.empty((n, CH))
    e = np.empty((m, CH))
    w = np.empty((m, CH))
    ll = np.empty(CH)
    # the part of the log-likelihood that does not depend on y
    const = 0.0
    for t in range(T):
        for k in range(m):
            yv = ys[0, t, k]
            if not math.isnan(yv):
                const -= math.log(chol[t, k, k]) + 0.5 * _LOG2PI
    for b0 in range(0, B, CH):
        c = min(CH, B - b0)
        for j in range(c):
            bx = b0 + j if x0.shape[0] > 1 else 0
            for i in range(n):
                x[i, j] = x0[bx, i]
            ll[j] = const
        for t in range(T):
            if t == 0:
                for i in range(n):
                    for j in range(c):
                        xp[i, j] = x[i, j]
            else:
                tf = t if F.shape[0] > 1 else 0
                for i in range(n):
                    for j in range(c):
                        xp[i, j] = 0.0
                    for l in range(n):
                        f = F[tf, i, l]
                        if f != 0.0:
                            for j in range(c):
                                xp[i, j] += f * x[l, j]
            th = t if H.shape[0] > 1 else 0
            for k in range(m):
                observed = not math.isnan(ys[0, t, k])
                if observed:
                    for j in range(c):
                        e[k, j] = ys[b0 + j, t, k]
                    for i in range(n):
                        h = H[th, k, i]
                        if h != 0.0:
                            for j in range(c):
                                e[k, j] -= h * xp[i, j]
                else:
                    for j in range(c):
                        e[k, j] = 0.0
            for k in range(m):
                lkk = chol[t, k, k]
                for j in range(c):
                    s = e[k, j]
                    for p in range(k):
                        s -= chol[t, k, p] * w[p, j]
                    w[k, j] = s / lkk
                    ll[j] -= 0.5 * w[k, j] * w[k, j]
            for i in range(n):
                for j in range(c):
                    pmeans[b0 + j, t, i] = xp[i, j]
                for j in range(c):
                    s = xp[i, j]
                    for k in range(m):
                        s += gains[t, i, k] * e[k, j]
                    x[i, j] = s
                    means[b0 + j, t, i] = s
        for j in range(c):
            loglik[b0 + j] = ll[j]

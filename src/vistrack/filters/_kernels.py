"""Compiled Kalman kernels (numba). Private: the public API is in :mod:`vistrack.filters.kalman`.

Three families, one set of equations:

- **Batches** (:func:`kf_batch`, :func:`kf_means_shared`, :func:`predict_batch`,
  :func:`update_batch`) work on a chunk of ``CH`` series at a time in structure-of-arrays form
  (``x[i, j]`` is entry ``i`` of series ``j``), with the series index as the innermost loop, so
  that LLVM turns every matrix operation into SIMD code over series. Entries of ``F`` and ``H``
  that are zero are skipped by a scalar test outside that loop, so the sparse kinematic models
  and selection-type measurements cost less. Missing components (NaN) are handled without a
  branch per series: a missing component gets a zero innovation, a zero column in ``P H'`` and a
  unit, decoupled row and column in ``S``, so its gain column is zero and the update equals the
  update with the observed components only.
- **One Gaussian at a time** (:func:`predict_one`, :func:`update_one`, used by the one-series
  filter :func:`single_kernel`, the RTS smoother, small per-call batches and
  :func:`online_kernel`), which update with the observed components only. The one-series and
  online kernels are compiled per state and measurement size, so their loops unroll.

Covariance updates use the Joseph form ``(I - K H) P (I - K H)' + K R K'``, evaluated as
``AP - W K'`` with ``AP = P - K (H P)`` and ``W = AP H' - K R`` (the same matrix for any gain),
on the upper triangle and mirrored, so covariances stay exactly symmetric; gains come from
Cholesky solves, never an explicit inverse.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .._jit import njit
from .._prebuilt import kernel

SMALL_B = 8  # per-call kernels use the scalar path below this batch size
CH = 128  # series per chunk (measured best of 16-256 on the 10,000 x 500 CV batch)
_LOG2PI = math.log(2.0 * math.pi)
_EPS = float(np.finfo(np.float64).eps)
# The one fast-math flag that changes no value but the sign of a zero. With fused multiply-add
# allowed ("contract"), results depended on numba's cache: a kernel compiled in the same process
# as the solves it calls can inline them, one that loads them from the cache cannot, and the
# two round differently (94 % instead of 95 % in examples/compose_bag.py after other commands
# had filled the cache). Reciprocals in place of divisions ("arcp") are left out for the same
# reason: what the compiler may rewrite should not depend on what it can see.
_FM = {"nsz"}


@njit(cache=True)
def _views(buf, o, shape):
    size = 1
    for d in shape:
        size *= d
    return buf[o:o + size].reshape(shape), o + size


@njit(cache=True)
def scratch(n, m, cc):
    """The SoA work arrays of :func:`update_chunk` and :func:`predict_chunk` for ``cc`` series,
    carved from one allocation: ``x, xp, P, Pp, FP, AP, W, U, K, S, e, wv, yv, obs, nobs, ll``."""
    buf = np.empty(cc * (5 * n * n + 2 * n + 3 * n * m + m * m + 4 * m + 2))
    o = 0
    x, o = _views(buf, o, (n, cc))
    xp, o = _views(buf, o, (n, cc))
    P, o = _views(buf, o, (n, n, cc))
    Pp, o = _views(buf, o, (n, n, cc))
    FP, o = _views(buf, o, (n, n, cc))
    AP, o = _views(buf, o, (n, n, cc))
    W, o = _views(buf, o, (n, m, cc))
    U, o = _views(buf, o, (n, m, cc))
    K, o = _views(buf, o, (n, m, cc))
    S, o = _views(buf, o, (m, m, cc))
    e, o = _views(buf, o, (m, cc))
    wv, o = _views(buf, o, (m, cc))
    yv, o = _views(buf, o, (m, cc))
    obs, o = _views(buf, o, (m, cc))
    nobs = buf[o:o + cc]
    ll = buf[o + cc:o + 2 * cc]
    return x, xp, P, Pp, FP, AP, W, U, K, S, e, wv, yv, obs, nobs, ll


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
def predict_batch(mean_in, cov_in, F2, Q2):
    """Predict a batch of Gaussians ``mean (..., n)``, ``cov (..., n, n)`` with ``F, Q (n, n)``.

    Returns ``(code, mean, cov)`` shaped like the inputs; ``code`` is -1, or 1 if ``F`` is not
    finite, 2 if ``Q`` is not, 3 if ``Q`` is not symmetric, 8 if a variance of ``Q`` is
    negative or a correlation beyond ±1, 13 or 14 if the mean or the covariance is not
    finite.
    """
    n = F2.shape[0]
    F = F2.reshape((1, n, n))
    Q = Q2.reshape((1, n, n))
    out_mean = np.empty_like(mean_in)
    out_cov = np.empty_like(cov_in)
    code = check_matrices(F, Q, 1e-8) or check_gaussians(mean_in, cov_in)
    if code:
        return code, out_mean, out_cov
    mean = mean_in.reshape((-1, n))
    cov = cov_in.reshape((-1, n, n))
    om = out_mean.reshape((-1, n))
    oc = out_cov.reshape((-1, n, n))
    B = mean.shape[0]
    if B < SMALL_B:
        FP = np.empty((n, n))
        for b in range(B):
            predict_one(F, Q, 0, 0, mean[b], cov[b], om[b], oc[b], FP, n)
        return -1, out_mean, out_cov
    cc = min(B, CH)
    x, xp, P, Pp, FP = scratch(n, 0, cc)[:5]
    for b0 in range(0, B, cc):
        c = min(cc, B - b0)
        for j in range(c):
            for i in range(n):
                x[i, j] = mean[b0 + j, i]
                for k in range(n):
                    P[i, k, j] = cov[b0 + j, i, k]
        predict_chunk(F, Q, 0, 0, x, P, xp, Pp, FP, c)
        for j in range(c):
            for i in range(n):
                om[b0 + j, i] = xp[i, j]
                for k in range(n):
                    oc[b0 + j, i, k] = Pp[i, k, j]
    return -1, out_mean, out_cov


predict_batch_py = kernel(predict_batch)
""":func:`predict_batch` for calls from Python (compiled code calls the numba function)."""


@njit(cache=True, fastmath=_FM)
def update_chunk(H, R, th, tr, yv, xp, Pp, x, P, AP, W, U, K, S, e, wv, obs, nobs, ll, c):
    """Correct ``c`` predicted series (SoA ``xp (n, CH)``, ``Pp (n, n, CH)``) with ``yv (m, CH)``
    (NaN = missing) into ``x``, ``P``; adds the innovation log-density to ``ll``.

    Leaves the gains in ``K (n, m, CH)`` and the Cholesky factor of ``S`` in the lower triangle
    of ``S (m, m, CH)`` (zero gain, unit factor on missing components). The other arrays are
    scratch. Returns True if some ``S`` was not positive definite.
    """
    n = xp.shape[0]
    m = yv.shape[0]
    bad = False
    for j in range(c):
        nobs[j] = 0.0
    for k in range(m):
        for j in range(c):
            v = yv[k, j]
            o = 0.0 if math.isnan(v) else 1.0
            obs[k, j] = o
            nobs[j] += o
            e[k, j] = v if o == 1.0 else 0.0
        for i in range(n):
            h = H[th, k, i]
            if h != 0.0:
                for j in range(c):
                    e[k, j] -= obs[k, j] * h * xp[i, j]
    any_obs = False
    for j in range(c):
        if nobs[j] > 0.0:
            any_obs = True
    if not any_obs:
        for i in range(n):
            for j in range(c):
                x[i, j] = xp[i, j]
            for k in range(n):
                for j in range(c):
                    P[i, k, j] = Pp[i, k, j]
            for k in range(m):
                for j in range(c):
                    K[i, k, j] = 0.0
        for k in range(m):
            for k2 in range(m):
                for j in range(c):
                    S[k, k2, j] = 1.0 if k == k2 else 0.0
        return False
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
    # Cholesky S = L L' in place (lower triangle of S); the series loop j is innermost in every
    # nest below, so that each statement becomes SIMD code over series
    for k in range(m):
        for p in range(k):
            for j in range(c):
                S[k, k, j] -= S[k, p, j] * S[k, p, j]
        nbad = 0.0
        for j in range(c):
            d = S[k, k, j]
            nbad += 0.0 if d > 0.0 else 1.0  # (NaN counts as bad)
            S[k, k, j] = math.sqrt(d) if d > 0.0 else 1.0
        if nbad > 0.0:
            bad = True
        for k2 in range(k + 1, m):
            for p in range(k):
                for j in range(c):
                    S[k2, k, j] -= S[k2, p, j] * S[k, p, j]
            for j in range(c):
                S[k2, k, j] /= S[k, k, j]
    # K = U S^-1: per state row i, solve L z = U[i]' then L' K[i]' = z
    for i in range(n):
        for k in range(m):
            for j in range(c):
                K[i, k, j] = U[i, k, j]
            for p in range(k):
                for j in range(c):
                    K[i, k, j] -= S[k, p, j] * K[i, p, j]
            for j in range(c):
                K[i, k, j] /= S[k, k, j]
        for k in range(m - 1, -1, -1):
            for p in range(k + 1, m):
                for j in range(c):
                    K[i, k, j] -= S[p, k, j] * K[i, p, j]
            for j in range(c):
                K[i, k, j] /= S[k, k, j]
    # log N(e; 0, S) = -0.5 |L^-1 e|^2 - log det L - 0.5 k log 2π (missing: e = 0, L_kk = 1)
    for j in range(c):
        ll[j] -= 0.5 * nobs[j] * _LOG2PI
        wv[0, j] = 1.0  # scratch: product of the diagonal of L, for one log per series
    for k in range(m):
        for j in range(c):
            obs[k, j] = e[k, j]  # obs is free now: it holds the whitened innovation
        for p in range(k):
            for j in range(c):
                obs[k, j] -= S[k, p, j] * obs[p, j]
        for j in range(c):
            w = obs[k, j] / S[k, k, j]
            obs[k, j] = w
            ll[j] -= 0.5 * w * w
            wv[0, j] *= S[k, k, j]
    for j in range(c):
        ll[j] -= math.log(wv[0, j])
    # mean: x = xp + K e
    for i in range(n):
        for j in range(c):
            x[i, j] = xp[i, j]
        for k in range(m):
            for j in range(c):
                x[i, j] += K[i, k, j] * e[k, j]
    # Joseph form (I - K H) Pp (I - K H)' + K R K', evaluated as P = AP - W K' with
    # AP = (I - K H) Pp = Pp - K U' and W = AP H' - K R: the same matrix for any K (so an
    # inexact gain still costs only second order), in n²m + n·nnz(H) + nm² + n²m/2 operations
    for i in range(n):
        for l in range(n):
            for j in range(c):
                AP[i, l, j] = Pp[i, l, j]
            for k in range(m):
                for j in range(c):
                    AP[i, l, j] -= K[i, k, j] * U[l, k, j]
    for i in range(n):
        for k in range(m):
            for j in range(c):
                W[i, k, j] = 0.0
            for l in range(n):
                h = H[th, k, l]
                if h != 0.0:
                    for j in range(c):
                        W[i, k, j] += AP[i, l, j] * h
            for k2 in range(m):
                r = R[tr, k2, k]
                if r != 0.0:
                    for j in range(c):
                        W[i, k, j] -= K[i, k2, j] * r
    for i in range(n):
        for l in range(i, n):
            for j in range(c):
                P[i, l, j] = AP[i, l, j]
            for k in range(m):
                for j in range(c):
                    P[i, l, j] -= W[i, k, j] * K[l, k, j]
            if l != i:
                for j in range(c):
                    P[l, i, j] = P[i, l, j]
    return bad


@njit(cache=True)
def all_finite(a):
    """Whether every entry of the array ``a`` is finite."""
    for v in a.ravel():
        if not math.isfinite(v):
            return False
    return True


@njit(cache=True)
def check_gaussians(mean, cov):
    """0 if every entry of ``mean`` and ``cov`` is finite, 13 if one of ``mean`` is not, 14
    if one of ``cov`` is not (a NaN Gaussian's update gave NaN means without a word; checked
    here, where it costs a pass over the batch, not in Python, where it cost a step's half)."""
    return 0 if all_finite(mean) and all_finite(cov) else 13 if not all_finite(mean) else 14


@njit(cache=True)
def symmetric_within(A, rel_tol):
    """Whether the square matrix ``A`` is symmetric to ``rel_tol`` of its largest entry (of
    1 where all are 0), as :func:`vistrack._validate.check_symmetric` judges: of each
    entry's own size, an off-diagonal entry near 0 that rounding made differ from its
    transpose by 1e-17 refused a rotated isotropic R."""
    big = 0.0
    for v in A.ravel():
        big = max(big, abs(v))
    tol = rel_tol * (big if big > 0.0 else 1.0)
    n = A.shape[0]
    for i in range(n):
        for k in range(i + 1, n):
            if abs(A[i, k] - A[k, i]) > tol:
                return False
    return True


@njit(cache=True)
def check_matrices(F, Q, sym_tol):
    """0 if ``F`` and ``Q`` (``(1, n, n)`` / ``(1, r, r)``) are finite and ``Q`` symmetric with
    variances >= 0 and correlations within ±1; 1 if ``F`` has a non-finite entry, 2 if ``Q``
    has, 3 if ``Q`` is not symmetric, 8 if a variance or a correlation is not."""
    if not all_finite(F):
        return 1
    if not all_finite(Q):
        return 2
    r = Q.shape[1]
    if not symmetric_within(Q[0], sym_tol):
        return 3
    # what semi-definiteness asks of each variance and each pair: no variance below 0, no
    # covariance beyond the product of the standard deviations (the full test costs more
    # than a step; kalman_filter makes it)
    top = 0.0
    for i in range(r):
        top = max(top, abs(Q[0, i, i]))
    for i in range(r):
        if Q[0, i, i] < -sym_tol * top:
            return 8
        for k in range(i + 1, r):
            if Q[0, i, k] ** 2 > Q[0, i, i] * Q[0, k, k] * (1.0 + sym_tol) + (sym_tol * top) ** 2:
                return 8
    return 0


@njit(cache=True, fastmath=_FM)
def update_batch(mean_in, cov_in, y_in, H2, R2):
    """Correct a batch ``mean (..., n)``, ``cov (..., n, n)`` with ``y (..., m)``; ``H (m, n)``,
    ``R (m, m)``. Returns ``(code, mean, cov, loglik)`` shaped like the inputs; ``code`` is -1, or
    1 ``H`` not finite, 2 ``R`` not finite, 3 ``R`` not symmetric, 4 ``S`` not positive definite,
    8 a variance of ``R`` negative or a correlation beyond ±1.
    """
    m, n = H2.shape
    H = H2.reshape((1, m, n))
    R = R2.reshape((1, m, m))
    out_mean = np.empty_like(mean_in)
    out_cov = np.empty_like(cov_in)
    ll_out = np.empty(y_in.shape[:-1])
    code = check_matrices(H, R, 1e-8) or check_gaussians(mean_in, cov_in)
    if code:
        return code, out_mean, out_cov, ll_out
    mean = mean_in.reshape((-1, n))
    cov = cov_in.reshape((-1, n, n))
    y = y_in.reshape((-1, m))
    out_m = out_mean.reshape((-1, n))
    out_c = out_cov.reshape((-1, n, n))
    ll = ll_out.reshape(-1)
    B = mean.shape[0]
    if B < SMALL_B:
        idx, e, Ut, KT, S, L, AP, W, _ = one_scratch(n, m)
        bad = False
        for b in range(B):
            ok, ll[b] = update_one(H, R, 0, 0, y[b], mean[b], cov[b], out_m[b], out_c[b],
                                   idx, e, Ut, KT, S, L, AP, W, n, m)
            bad = bad or not ok
        return (4 if bad else -1), out_mean, out_cov, ll_out
    cc = min(B, CH)
    x, xp, P, Pp, _, AP, W, U, K, S, e, wv, yv, obs, nobs, llc = scratch(n, m, cc)
    bad = False
    for b0 in range(0, B, cc):
        c = min(cc, B - b0)
        for j in range(c):
            llc[j] = 0.0
            for i in range(n):
                xp[i, j] = mean[b0 + j, i]
                for k in range(n):
                    Pp[i, k, j] = cov[b0 + j, i, k]
            for k in range(m):
                yv[k, j] = y[b0 + j, k]
        if update_chunk(H, R, 0, 0, yv, xp, Pp, x, P, AP, W, U, K, S, e, wv, obs, nobs, llc, c):
            bad = True
        for j in range(c):
            ll[b0 + j] = llc[j]
            for i in range(n):
                out_m[b0 + j, i] = x[i, j]
                for k in range(n):
                    out_c[b0 + j, i, k] = P[i, k, j]
    return (4 if bad else -1), out_mean, out_cov, ll_out


update_batch_py = kernel(update_batch)
""":func:`update_batch` for calls from Python (compiled code calls the numba function)."""


@kernel
@njit(cache=True, fastmath=_FM)
def kf_batch(
    ys, F, Q, H, R, x0, P0, means, covs, pmeans, pcovs, loglik, last_P, gains, chol, store_covs
):
    """Filter ``B`` series ``ys (B, T, m)``; see :func:`vistrack.filters.kalman_filter`.

    ``F, Q (TF, n, n)``, ``H (TH, m, n)``, ``R (TR, m, m)`` with each leading size 1 or T.
    ``x0 (B0, n)``, ``P0 (BP, n, n)`` with B0, BP in {1, B}. Writes ``means``, ``pmeans``
    ``(B, T, n)``, ``loglik (B,)``, ``last_P (B, n, n)`` and, when ``store_covs``, ``pmeans``,
    ``covs`` and ``pcovs (B, T, n, n)``. When ``gains`` has ``T`` rows (used with ``B == 1``)
    it also writes the Kalman gains ``(T, n, m)`` and the Cholesky factors of ``S``
    ``(T, m, m)`` into ``chol``.
    Returns the first step whose innovation covariance is not positive definite, or -1.
    """
    B, T, m = ys.shape
    n = x0.shape[1]
    want_gains = gains.shape[0] == T
    x, xp, P, Pp, FP, AP, W, U, K, S, e, wv, yv, obs, nobs, ll = scratch(n, m, CH)
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
            if store_covs:
                for i in range(n):
                    for j in range(c):
                        pmeans[b0 + j, t, i] = xp[i, j]
                    for k in range(n):
                        for j in range(c):
                            pcovs[b0 + j, t, i, k] = Pp[i, k, j]
            # ---- update ----
            for k in range(m):
                for j in range(c):
                    yv[k, j] = ys[b0 + j, t, k]
            th = t if H.shape[0] > 1 else 0
            tr = t if R.shape[0] > 1 else 0
            if update_chunk(H, R, th, tr, yv, xp, Pp, x, P, AP, W, U, K, S, e, wv, obs, nobs, ll,
                            c):
                if bad_t < 0:
                    bad_t = t
            if want_gains:
                for i in range(n):
                    for k in range(m):
                        gains[t, i, k] = K[i, k, 0]
                for k in range(m):
                    for k2 in range(m):
                        chol[t, k, k2] = S[k, k2, 0] if k2 <= k else 0.0
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


@kernel
@njit(cache=True, fastmath=_FM)
def kf_means_shared(ys, F, H, x0, gains, chol, means, pmeans, loglik, store_pred):
    """Mean recursion for series that share their covariances and gains.

    ``gains (T, n, m)`` and ``chol (T, m, m)`` come from :func:`kf_batch` run on one series with
    the shared missing-data pattern; missing components have zero gain columns and unit rows in
    ``chol``. Each series costs ``F x``, ``H x``, ``K e`` and a triangular solve per step.
    ``pmeans`` is written only when ``store_pred``.
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
                for j in range(c):
                    w[k, j] = e[k, j]
                for p in range(k):
                    lkp = chol[t, k, p]
                    if lkp != 0.0:
                        for j in range(c):
                            w[k, j] -= lkp * w[p, j]
                inv = 1.0 / chol[t, k, k]
                for j in range(c):
                    w[k, j] *= inv
                    ll[j] -= 0.5 * w[k, j] * w[k, j]
            for i in range(n):
                if store_pred:
                    for j in range(c):
                        pmeans[b0 + j, t, i] = xp[i, j]
                for j in range(c):
                    x[i, j] = xp[i, j]
                for k in range(m):
                    g = gains[t, i, k]
                    if g != 0.0:
                        for j in range(c):
                            x[i, j] += g * e[k, j]
                for j in range(c):
                    means[b0 + j, t, i] = x[i, j]
        for j in range(c):
            loglik[b0 + j] = ll[j]


# ------------------------------------------------------------------------------------------------
# Scalar kernels for one Gaussian at a time. With a single series the SoA loops above have length
# one and cost more in loop overhead than in arithmetic; these run the same equations on plain
# (n,) / (n, n) arrays, updating with the observed components only.


@njit(cache=True)
def copy_vec(dst, src):
    """``dst[:] = src`` for two vectors of one length, as a loop. numba compiles an array's
    slice assignment with the message of its shape check, 2-5 s the first time in a process:
    the kernels copy with these instead."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@njit(cache=True)
def copy_mat(dst, src):
    """``dst[:, :] = src`` for two matrices of one shape, as loops (see :func:`copy_vec`)."""
    for i in range(src.shape[0]):
        for k in range(src.shape[1]):
            dst[i, k] = src[i, k]


@njit(cache=True)
def chol_factor(L, A, n):
    """Factor ``A = L L'`` (``A`` is ``n x n``; the lower triangle of ``L`` is written, the upper
    left as it was). Returns False if ``A`` is not positive definite."""
    for i in range(n):
        d = A[i, i]
        for p in range(i):
            d -= L[i, p] * L[i, p]
        if not d > 0.0:
            return False
        L[i, i] = math.sqrt(d)
        for r in range(i + 1, n):
            s = A[r, i]
            for p in range(i):
                s -= L[r, p] * L[i, p]
            L[r, i] = s / L[i, i]
    return True


@njit(cache=True)
def forward_solve(L, B, n, k):
    """Solve ``L X = B`` in place for ``B`` of ``n x k``, ``L`` the lower triangle of a factor
    from :func:`chol_factor`."""
    for c in range(k):
        for i in range(n):
            s = B[i, c]
            for p in range(i):
                s -= L[i, p] * B[p, c]
            B[i, c] = s / L[i, i]


@njit(cache=True)
def back_solve(L, B, n, k):
    """Solve ``L' X = B`` in place for ``B`` of ``n x k`` (see :func:`forward_solve`)."""
    for c in range(k):
        for i in range(n - 1, -1, -1):
            s = B[i, c]
            for p in range(i + 1, n):
                s -= L[p, i] * B[p, c]
            B[i, c] = s / L[i, i]


@njit(cache=True)
def chol_solve(L, A, B, n, k):
    """Factor ``A = L L'`` (``A`` is ``n x n``, the lower triangle of ``L`` is written) and solve
    ``A X = B`` in place for ``B`` of ``n x k``. Returns False if ``A`` is not positive definite."""
    if not chol_factor(L, A, n):
        return False
    forward_solve(L, B, n, k)
    back_solve(L, B, n, k)
    return True


@njit(cache=True, fastmath=_FM)
def predict_one(F, Q, tf, tq, x, P, xp, Pp, FP, n):
    """``xp = F x``, ``FP = F P``, ``Pp = F P F' + Q`` for one Gaussian, skipping zeros of ``F``.

    ``n`` is the state size: a caller that passes a compile-time constant (see
    :func:`single_kernel`) gets the loops unrolled."""
    for i in range(n):
        xp[i] = 0.0
        for k in range(n):
            FP[i, k] = 0.0
        for l in range(n):
            f = F[tf, i, l]
            if f != 0.0:
                xp[i] += f * x[l]
                for k in range(n):
                    FP[i, k] += f * P[l, k]
    for i in range(n):
        for k in range(i, n):
            s = Q[tq, i, k]
            for l in range(n):
                f = F[tf, k, l]
                if f != 0.0:
                    s += FP[i, l] * f
            Pp[i, k] = s
            Pp[k, i] = s


@njit(cache=True, fastmath=_FM)
def update_one(H, R, th, tr, y, xp, Pp, x, P, idx, e, Ut, KT, S, L, AP, W, n, m):
    """Correct one predicted Gaussian ``xp, Pp`` with ``y (m,)`` (NaN = missing) into ``x, P``.

    Uses the observed components only (``Ut = H_o Pp``, ``S = H_o Pp H_o' + R_oo``, gain from
    ``S K' = Ut`` by :func:`chol_solve`); the Joseph form is evaluated as in
    :func:`update_chunk`. Zeros of ``H`` are skipped. Returns ``(ok, loglik)``; ``ok`` is False
    if ``S`` is not positive definite. ``n``, ``m`` as in :func:`predict_one`.
    """
    ko = 0
    for k in range(m):
        if not math.isnan(y[k]):
            idx[ko] = k
            ko += 1
    if ko == 0:
        for i in range(n):
            x[i] = xp[i]
            for k in range(n):
                P[i, k] = Pp[i, k]
        return True, 0.0
    for a in range(ko):
        k = idx[a]
        e[a] = y[k]
        for l in range(n):
            Ut[a, l] = 0.0
        for i in range(n):
            h = H[th, k, i]
            if h != 0.0:
                e[a] -= h * xp[i]
                for l in range(n):
                    Ut[a, l] += h * Pp[i, l]
    for a in range(ko):
        for b in range(a, ko):
            s = R[tr, idx[a], idx[b]]
            for i in range(n):
                h = H[th, idx[a], i]
                if h != 0.0:
                    s += h * Ut[b, i]
            S[a, b] = s
            S[b, a] = s
        for l in range(n):
            KT[a, l] = Ut[a, l]
    if not chol_solve(L, S, KT, ko, n):
        return False, 0.0
    ll = -0.5 * ko * _LOG2PI
    det_l = 1.0
    for a in range(ko):  # whitened innovation L^-1 e, into S's first column (S is spent)
        s = e[a]
        for p in range(a):
            s -= L[a, p] * S[p, 0]
        S[a, 0] = s / L[a, a]
        ll -= 0.5 * S[a, 0] * S[a, 0]
        det_l *= L[a, a]
    ll -= math.log(det_l)
    for i in range(n):
        s = xp[i]
        for a in range(ko):
            s += KT[a, i] * e[a]
        x[i] = s
    for i in range(n):
        for l in range(n):
            s = Pp[i, l]
            for a in range(ko):
                s -= KT[a, i] * Ut[a, l]
            AP[i, l] = s
    for i in range(n):
        for a in range(ko):
            s = 0.0
            for l in range(n):
                h = H[th, idx[a], l]
                if h != 0.0:
                    s += AP[i, l] * h
            for b in range(ko):
                s -= KT[b, i] * R[tr, idx[b], idx[a]]
            W[i, a] = s
    for i in range(n):
        for l in range(i, n):
            s = AP[i, l]
            for a in range(ko):
                s -= W[i, a] * KT[a, l]
            P[i, l] = s
            P[l, i] = s
    return True, ll


@kernel
@njit(cache=True, fastmath=_FM)
def step_batch(mean_in, cov_in, y_in, F2, Q2, H2, R2):
    """Predict with ``F, Q`` then correct with ``y, H, R``, for a batch of Gaussians of any batch
    shape. Returns ``(code, mean, cov, loglik)``; codes as :func:`predict_batch` (1-3, 8) and
    :func:`update_batch` (5-7 and 12 for H/R, 4 for S)."""
    code, pm, pc = predict_batch(mean_in, cov_in, F2, Q2)
    if code >= 0:
        return code, pm, pc, np.empty(y_in.shape[:-1])
    code, m, c, ll = update_batch(pm, pc, y_in, H2, R2)
    if code >= 0 and code not in (4, 13, 14):
        code += 4
    return code, m, c, ll


@njit(cache=True)
def load_state(x0, P0, b, x, P):
    """Copy series ``b``'s prior ``x0[b]``, ``P0[b]`` into ``x``, ``P`` (the generated
    nonlinear filters' start of a series)."""
    n = x.shape[0]
    for i in range(n):
        x[i] = x0[b, i]
        for k in range(n):
            P[i, k] = P0[b, i, k]


@njit(cache=True)
def keep_state(x, P, means, covs, b, t):
    """Write ``x``, ``P`` into ``means[b, t]``, ``covs[b, t]``; whether every value is
    finite (the generated nonlinear filters' record of a step)."""
    n = x.shape[0]
    ok = True
    for i in range(n):
        means[b, t, i] = x[i]
        ok = ok and abs(x[i]) < np.inf
        for k in range(n):
            covs[b, t, i, k] = P[i, k]
            ok = ok and abs(P[i, k]) < np.inf
    return ok


@njit(cache=True)
def observed(y):
    """How many components of the measurement ``y`` are not NaN."""
    seen = 0
    for v in y:
        if not math.isnan(v):
            seen += 1
    return seen


@njit(cache=True)
def one_scratch(n, m):
    """Work arrays of :func:`update_one` and :func:`predict_one`:
    ``idx, e, Ut, KT, S, L, AP, W, FP``."""
    return (np.empty(m, dtype=np.int64), np.empty(m), np.empty((m, n)), np.empty((m, n)),
            np.empty((m, m)), np.empty((m, m)), np.empty((n, n)), np.empty((n, m)),
            np.empty((n, n)))


def online_layout(n, m):
    """Offsets in the one buffer of :func:`online_kernel`: state ``x (n,)``, ``P (n, n)``; model
    ``F, Q (n, n)``, ``H (m, n)``, ``R (m, m)``; then work space. Returns (offsets, size)."""
    sizes = [("x", n), ("P", n * n), ("F", n * n), ("Q", n * n), ("H", m * n), ("R", m * m),
             ("work", 3 * n * n + 3 * n * m + 2 * m * m + m + n)]
    offsets, o = {}, 0
    for name, size in sizes:
        offsets[name] = o
        o += size
    return offsets, o


@functools.cache
def online_kernel(n, m):
    """The in-place predict/correct of :class:`vistrack.filters.OnlineFilter`, compiled for state
    size ``n`` and measurement size ``m`` as constants (see :func:`single_kernel`).

    The kernel takes ``(buf, y, idx, do_predict, do_update)``: ``buf`` holds the state, the model
    and the work space as laid out by :func:`online_layout`, and ``idx`` is an int64 work array of
    ``m`` entries; three arrays, because numba's call overhead grows with each array argument.
    It returns ``(code, loglik)``: code -1 on success, 4 if ``S`` is not positive definite, 8 if
    ``y`` has an infinite entry. On failure the state is left as it was.
    """

    @njit(cache=True, fastmath=_FM)
    def step(buf, y, idx, do_predict, do_update):
        x, o = _views(buf, 0, (n,))
        P, o = _views(buf, o, (n, n))
        F, o = _views(buf, o, (1, n, n))
        Q, o = _views(buf, o, (1, n, n))
        H, o = _views(buf, o, (1, m, n))
        R, o = _views(buf, o, (1, m, m))
        xp, o = _views(buf, o, (n,))
        Pp, o = _views(buf, o, (n, n))
        FP, o = _views(buf, o, (n, n))
        AP, o = _views(buf, o, (n, n))
        e, o = _views(buf, o, (m,))
        Ut, o = _views(buf, o, (m, n))
        KT, o = _views(buf, o, (m, n))
        W, o = _views(buf, o, (n, m))
        S, o = _views(buf, o, (m, m))
        L, o = _views(buf, o, (m, m))
        if do_update:
            for k in range(m):
                if math.isinf(y[k]):
                    return 8, 0.0
        if do_predict:
            predict_one(F, Q, 0, 0, x, P, xp, Pp, FP, n)
        else:
            copy_vec(xp, x)
            copy_mat(Pp, P)
        if not do_update:
            copy_vec(x, xp)
            copy_mat(P, Pp)
            return -1, 0.0
        ok, ll = update_one(H, R, 0, 0, y, xp, Pp, x, P, idx, e, Ut, KT, S, L, AP, W, n, m)
        return (-1 if ok else 4), ll

    return step


@functools.cache
def single_kernel(n, m):
    """The one-series filter for state size ``n`` and measurement size ``m``, compiled with both
    as constants (numba treats a closure's variables as such), so that the small matrix loops
    unroll: about a third faster than with run-time sizes. Each size compiles once per machine
    and is then loaded from numba's cache.

    With constant matrices, the covariance recursion converges to its steady state (the seeds'
    "Riccati" values) within tens of steps. Once two consecutive fully observed steps leave P and
    the predicted P unchanged to within 8 ulp, each entry of its own scale
    ``sqrt(P_ii P_kk)``, P, the gain and S are frozen and
    each step costs only the mean recursion: the recursion is contractive there, so the results
    stay within rounding of the full computation. A step with a missing component leaves the
    steady state until it converges again.

    The kernel takes ``ys (T, m), F, Q, H, R, x0 (n,), P0 (n, n), means, covs, pmeans, pcovs,
    last_P, store_covs`` (as :func:`kf_batch` for one series) and returns ``(bad_t, loglik)``.
    """

    @njit(cache=True, fastmath=_FM)
    def kf_single(ys, F, Q, H, R, x0, P0, means, covs, pmeans, pcovs, last_P, store_covs):
        T = ys.shape[0]
        idx, e, Ut, KT, S, L, AP, W, FP = one_scratch(n, m)
        # the steady state's whitened innovation, (m,): it went into W's first column, (n, m),
        # which a measurement longer than the state (m > n) overran, corrupting the heap
        white = np.empty(m)
        x = x0.copy()
        P = P0.copy()
        xp = np.empty(n)
        Pp = np.empty((n, n))
        P_last = np.full((n, n), np.nan)  # posterior covariance of the previous full update
        Pp_last = np.full((n, n), np.nan)
        constant = F.shape[0] == 1 and Q.shape[0] == 1 and H.shape[0] == 1 and R.shape[0] == 1
        steady = False
        ll_const = 0.0
        total = 0.0
        for t in range(T):
            observed = 0
            for k in range(m):
                if not math.isnan(ys[t, k]):
                    observed += 1
            if steady and observed == m:
                # Steady state: the previous two updates left P and Pp bitwise unchanged, and
                # neither depends on y, so this step's P, Pp, gain and S are those again. Only
                # the mean moves: xp = F x, x = xp + K (y - H xp).
                for i in range(n):
                    s = 0.0
                    for l in range(n):
                        f = F[0, i, l]
                        if f != 0.0:
                            s += f * x[l]
                    xp[i] = s
                for a in range(m):
                    s = ys[t, a]
                    for i in range(n):
                        h = H[0, a, i]
                        if h != 0.0:
                            s -= h * xp[i]
                    e[a] = s
                ll = ll_const
                for a in range(m):  # the whitened innovation
                    s = e[a]
                    for p in range(a):
                        s -= L[a, p] * white[p]
                    white[a] = s / L[a, a]
                    ll -= 0.5 * white[a] * white[a]
                total += ll
                for i in range(n):
                    s = xp[i]
                    for a in range(m):
                        s += KT[a, i] * e[a]
                    x[i] = s
            else:
                if t == 0:
                    copy_vec(xp, x)
                    copy_mat(Pp, P)
                else:
                    predict_one(F, Q, t if F.shape[0] > 1 else 0, t if Q.shape[0] > 1 else 0,
                                x, P, xp, Pp, FP, n)
                ok, ll = update_one(H, R, t if H.shape[0] > 1 else 0, t if R.shape[0] > 1 else 0,
                                    ys[t], xp, Pp, x, P, idx, e, Ut, KT, S, L, AP, W, n, m)
                if not ok:
                    return t, total
                total += ll
                if constant and observed == m and t > 0:
                    # converged: P and Pp within a few ulp of the last step's (the recursion
                    # can end in a cycle of last-bit changes rather than an exact fixed point),
                    # each entry against its own scale sqrt(P_ii P_kk): against the largest
                    # variance, a small one still converging was frozen far from its limit
                    same = True
                    for i in range(n):
                        for k in range(n):
                            tol = 8.0 * _EPS * math.sqrt(abs(P[i, i] * P[k, k]))
                            tolp = 8.0 * _EPS * math.sqrt(abs(Pp[i, i] * Pp[k, k]))
                            # written so that NaN (no previous step) counts as a change
                            if not (abs(P[i, k] - P_last[i, k]) <= tol
                                    and abs(Pp[i, k] - Pp_last[i, k]) <= tolp):
                                same = False
                    if same:
                        steady = True
                        ll_const = -0.5 * m * _LOG2PI
                        for a in range(m):
                            ll_const -= math.log(L[a, a])
                    else:
                        copy_mat(P_last, P)
                        copy_mat(Pp_last, Pp)
                else:
                    steady = False
                    P_last[:, :] = np.nan
            for i in range(n):  # explicit loops: numba's slice assignment costs more here
                means[t, i] = x[i]
                if store_covs:
                    pmeans[t, i] = xp[i]
                    for k in range(n):
                        pcovs[t, i, k] = Pp[i, k]
                        covs[t, i, k] = P[i, k]
        copy_mat(last_P, P)
        return -1, total

    return kernel(kf_single, f"{__name__}:single_kernel({n!r}, {m!r})")

"""Affine registration of image patches by inverse-compositional Lucas-Kanade (Baker and
Matthews, 2004), batched over patches and compiled: the KLT's consistency check and the
template tracker share it.

A patch is a template ``T`` of ``(h, w)`` pixels with its centre at the origin of template
coordinates ``x``; the warp ``W(x; p) = A x + d`` with ``A = [[1 + p0, p2], [p1, 1 + p3]]`` and
``d = (p4, p5)`` maps it into the image. Each iteration warps the image at the template's
pixels (bilinear), compares it with the template, solves for the increment ``Δp`` with the
template's own gradients and Hessian (computed once), and composes ``W ← W ∘ W(Δp)⁻¹``.
Intensities are compared after removing each patch's mean and scaling by its standard
deviation, so a change of brightness and contrast is not a mismatch.
"""

from __future__ import annotations

import numpy as np

from .._jit import bind, njit
from .._prebuilt import kernel

prange = range  # numba.prange once numba is imported: a parallel loop when compiled
bind(globals(), prange="prange")

__all__ = ["prepare_templates", "register"]


@njit(cache=True, fastmath=True)
def _bilinear(img, x, y):
    H, W = img.shape
    if not (0.0 <= x < W - 1.0 and 0.0 <= y < H - 1.0):
        return np.nan
    x0, y0 = int(x), int(y)
    ax, ay = x - x0, y - y0
    return ((1.0 - ay) * ((1.0 - ax) * img[y0, x0] + ax * img[y0, x0 + 1])
            + ay * ((1.0 - ax) * img[y0 + 1, x0] + ax * img[y0 + 1, x0 + 1]))


@kernel
@njit(cache=True)
def _prepare(img, centres, half, T, SD, Hinv, ok):
    # cut the templates (normalised), their steepest-descent images and inverse Hessians
    K = centres.shape[0]
    h = 2 * half + 1
    for k in range(K):
        cx, cy = centres[k, 0], centres[k, 1]
        ok[k] = True
        for i in range(-half - 1, half + 2):
            for j in range(-half - 1, half + 2):
                if np.isnan(_bilinear(img, cx + j, cy + i)):
                    ok[k] = False
        if not ok[k]:
            continue
        patch = np.empty((h + 2, h + 2))
        for i in range(h + 2):
            for j in range(h + 2):
                patch[i, j] = _bilinear(img, cx + j - half - 1, cy + i - half - 1)
        inner = patch[1:-1, 1:-1]
        m, s = inner.mean(), inner.std()
        if s < 1e-6:
            ok[k] = False
            continue
        patch = (patch - m) / s
        Hm = np.zeros((6, 6))
        n = 0
        for i in range(h):
            for j in range(h):
                gx = 0.5 * (patch[i + 1, j + 2] - patch[i + 1, j])
                gy = 0.5 * (patch[i + 2, j + 1] - patch[i, j + 1])
                x, y = j - half, i - half
                sd = (gx * x, gy * x, gx * y, gy * y, gx, gy)
                T[k, n] = patch[i + 1, j + 1]
                for a in range(6):
                    SD[k, n, a] = sd[a]
                n += 1
        for a in range(6):
            for b in range(6):
                acc = 0.0
                for q in range(n):
                    acc += SD[k, q, a] * SD[k, q, b]
                Hm[a, b] = acc
        if np.linalg.cond(Hm) > 1e12:
            ok[k] = False
            continue
        inv = np.linalg.inv(Hm)
        for a in range(inv.shape[0]):  # loops: see filters._kernels.copy_vec
            for b in range(inv.shape[1]):
                Hinv[k, a, b] = inv[a, b]


def prepare_templates(image: np.ndarray, centres: np.ndarray, half: int):
    """Templates ``(K, (2 half + 1)²)`` of a grey ``image`` around ``centres (K, 2)`` (x, y),
    normalised, with their steepest-descent images ``(K, n, 6)``, inverse Hessians
    ``(K, 6, 6)`` and a mask of the usable ones (inside the image, textured)."""
    img = np.ascontiguousarray(image, dtype=np.float32)
    c = np.ascontiguousarray(centres, dtype=np.float64).reshape(-1, 2)
    n = (2 * half + 1) ** 2
    K = len(c)
    T, SD = np.zeros((K, n)), np.zeros((K, n, 6))
    Hinv, ok = np.zeros((K, 6, 6)), np.zeros(K, np.bool_)
    _prepare(img, c, int(half), T, SD, Hinv, ok)
    return T, SD, Hinv, ok


# fast-math without "no NaN", "no inf" and approximate functions: with fastmath=True, the
# registration loaded from numba's cache gave other bits than in the process that compiled it
# (about three quarters of the values of a 40-feature test, up to 7e-14 apart); these flags
# give the compiling process's bits either way (tests/test_prebuilt.py)
@njit(cache=True, parallel=True, fastmath={"reassoc", "contract", "arcp", "nsz"})
def _register(img, half, T, SD, Hinv, p, iters, eps, rms):
    K = p.shape[0]
    H, W = img.shape
    h = 2 * half + 1
    n = h * h
    for k in prange(K):
        warped = np.empty(n)
        b = np.empty(6)
        rms[k] = np.inf
        it = 0
        while True:
            a00, a10, a01, a11 = 1.0 + p[k, 0], p[k, 1], p[k, 2], 1.0 + p[k, 3]
            dx, dy = p[k, 4], p[k, 5]
            # the warped patch is a parallelogram: inside the image if its corners are, so
            # the pixels need no checks
            inside = True
            for cy in (-half, half):
                for cx in (-half, half):
                    u, v = a00 * cx + a01 * cy + dx, a10 * cx + a11 * cy + dy
                    if not (0.0 <= u < W - 1.0 and 0.0 <= v < H - 1.0):
                        inside = False
            if not inside:
                rms[k] = np.inf
                break
            q = 0
            s1 = s2 = 0.0
            for i in range(h):
                y = i - half
                u0, v0 = a01 * y + dx - a00 * half, a11 * y + dy - a10 * half
                for j in range(h):
                    u, v = u0 + a00 * j, v0 + a10 * j
                    x0, y0 = int(u), int(v)
                    fx, fy = u - x0, v - y0
                    val = ((1.0 - fy) * ((1.0 - fx) * img[y0, x0] + fx * img[y0, x0 + 1])
                           + fy * ((1.0 - fx) * img[y0 + 1, x0] + fx * img[y0 + 1, x0 + 1]))
                    warped[q] = val
                    s1 += val
                    s2 += val * val
                    q += 1
            m = s1 / n
            var = s2 / n - m * m
            if var < 1e-12:
                rms[k] = np.inf
                break
            inv_s = 1.0 / np.sqrt(var)
            e2 = 0.0
            b0 = b1 = b2 = b3 = b4 = b5 = 0.0
            for q in range(n):
                e = (warped[q] - m) * inv_s - T[k, q]
                e2 += e * e
                b0 += SD[k, q, 0] * e
                b1 += SD[k, q, 1] * e
                b2 += SD[k, q, 2] * e
                b3 += SD[k, q, 3] * e
                b4 += SD[k, q, 4] * e
                b5 += SD[k, q, 5] * e
            b[0], b[1], b[2], b[3], b[4], b[5] = b0, b1, b2, b3, b4, b5
            rms[k] = np.sqrt(e2 / n)
            if it == iters:
                break
            dp = Hinv[k] @ b
            # W <- W o W(dp)^-1, as 3x3 matrices
            i00, i01, i10, i11 = 1.0 + dp[0], dp[2], dp[1], 1.0 + dp[3]
            det = i00 * i11 - i01 * i10
            if abs(det) < 1e-12:
                rms[k] = np.inf
                break
            j00, j01, j10, j11 = i11 / det, -i01 / det, -i10 / det, i00 / det
            jx = -(j00 * dp[4] + j01 * dp[5])
            jy = -(j10 * dp[4] + j11 * dp[5])
            n00 = a00 * j00 + a01 * j10
            n01 = a00 * j01 + a01 * j11
            n10 = a10 * j00 + a11 * j10
            n11 = a10 * j01 + a11 * j11
            nx = a00 * jx + a01 * jy + dx
            ny = a10 * jx + a11 * jy + dy
            p[k, 0], p[k, 1], p[k, 2], p[k, 3] = n00 - 1.0, n10, n01, n11 - 1.0
            p[k, 4], p[k, 5] = nx, ny
            # converged when the step moves no pixel of the patch by more than eps; the
            # residual just measured is then that of the final warp, to within it
            move = (abs(dp[0]) + abs(dp[1]) + abs(dp[2]) + abs(dp[3])) * half \
                + abs(dp[4]) + abs(dp[5])
            if move < eps:
                break
            it += 1


def register(image: np.ndarray, half: int, T: np.ndarray, SD: np.ndarray, Hinv: np.ndarray,
             p: np.ndarray, iters: int = 10, eps: float = 0.01) -> np.ndarray:
    """Refine the affine warps ``p (K, 6)`` (in place) of the templates into the grey
    ``image``; returns each patch's RMS residual of normalised intensities (``inf`` when the
    warp leaves the image or the patch is flat)."""
    img = np.ascontiguousarray(image, dtype=np.float32)
    rms = np.empty(len(p))
    _register(img, int(half), T, SD, Hinv, p, int(iters), float(eps), rms)
    return rms


@njit(cache=True, parallel=True, fastmath=True)
def _ncc(a, pa, b, pb, half, out):
    H, W = a.shape
    Hb, Wb = b.shape  # (each patch against its own image: b's was checked against a's size)
    n = (2 * half + 1) ** 2
    for k in prange(pa.shape[0]):
        ax, ay, bx, by = pa[k, 0] - half, pa[k, 1] - half, pb[k, 0] - half, pb[k, 1] - half
        # both patches inside their images (checked once, not per pixel)
        if not (0.0 <= ax and ax + 2 * half < W - 1.0 and 0.0 <= ay and ay + 2 * half < H - 1.0
                and 0.0 <= bx and bx + 2 * half < Wb - 1.0 and 0.0 <= by
                and by + 2 * half < Hb - 1.0):
            out[k] = -1.0
            continue
        iax, iay, ibx, iby = int(ax), int(ay), int(bx), int(by)
        fax, fay, fbx, fby = ax - iax, ay - iay, bx - ibx, by - iby
        su = sv = suu = svv = suv = 0.0
        for i in range(2 * half + 1):
            for j in range(2 * half + 1):
                u = ((1.0 - fay) * ((1.0 - fax) * a[iay + i, iax + j]
                                    + fax * a[iay + i, iax + j + 1])
                     + fay * ((1.0 - fax) * a[iay + i + 1, iax + j]
                              + fax * a[iay + i + 1, iax + j + 1]))
                v = ((1.0 - fby) * ((1.0 - fbx) * b[iby + i, ibx + j]
                                    + fbx * b[iby + i, ibx + j + 1])
                     + fby * ((1.0 - fbx) * b[iby + i + 1, ibx + j]
                              + fbx * b[iby + i + 1, ibx + j + 1]))
                su += u
                sv += v
                suu += u * u
                svv += v * v
                suv += u * v
        cu = suu - su * su / n
        cv = svv - sv * sv / n
        out[k] = (suv - su * sv / n) / np.sqrt(cu * cv) if cu > 1e-9 and cv > 1e-9 else -1.0


def patch_ncc(a: np.ndarray, pa: np.ndarray, b: np.ndarray, pb: np.ndarray,
              half: int) -> np.ndarray:
    """Normalised cross-correlation of the ``(2 half + 1)²`` patches of grey image ``a`` at
    ``pa (K, 2)`` and ``b`` at ``pb`` (bilinear; -1 where a patch leaves its image or is
    flat)."""
    out = np.empty(len(pa))
    _ncc(np.ascontiguousarray(a, dtype=np.float32), np.ascontiguousarray(pa, dtype=np.float64),
         np.ascontiguousarray(b, dtype=np.float32), np.ascontiguousarray(pb, dtype=np.float64),
         int(half), out)
    return out

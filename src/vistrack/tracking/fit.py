r"""Learn a box tracker's noise from tracks: the motion's and each value's measurement noise.

A box tracker's Kalman filter (:class:`~vistrack.models.BoxMotion`) needs how fast boxes
wander and how much a detector's boxes err, each as a fraction of the box's size. Given
reference tracks (ground truth, or the confident tracks of a first pass), each reference
object's detections make one series of measurements ``[cx, cy, w, h]``:

1. :func:`matched_series` matches, frame by frame, the detections to the reference boxes
   (one-to-one, by global nearest neighbour on IoU ≥ ``min_iou``) and keeps the objects
   detected ``min_length`` times or more, frames without a match left missing;
2. :func:`measurement_noise` takes the detections' noise from their differences to the
   reference boxes, as fractions of the box's size;
3. :func:`fit_box_motion` divides each object's series by its median width (``cx``, ``w``)
   and height (``cy``, ``h``), so that all are in units of the box's size as the model's
   noise is, and finds the position and velocity noise of maximum likelihood with that
   measurement noise, over the objects of a sequence, at the sequence's frame rate.

The motion noise is converted to the model's reference rate of 30 frames/s
(:meth:`~vistrack.models.BoxMotion.at_rate`); the measurement noise, one value for each of
``cx, cy, w, h``, does not depend on the rate. Over several sequences
:func:`fit_box_motion` takes the median of their values.

Without ground truth the reference boxes are the first pass's smoothed estimates, which
follow the detections partly: each detection's residual about them keeps only a share of its
error's variance (:func:`smoothed_residual_share`, 0.1 to 0.65 for the default model at 7 to
30 frames/s), so :func:`fit_box_motion` given ``smoothed_by`` divides the measured spread
by the square root of that share. For white errors on objects that move much more smoothly
than the model's noise allows (people and cars do), that recovers the truth (a simulated
detector on MOT17's scenes, ``cx`` 0.128 of the width from a first pass against 0.138 from
the ground truth, 0.077 undivided); a detector's errors that persist from frame to frame are
followed by the smoother as motion and stay understated (MOT17's ``cx`` 0.012 from a first
pass against 0.027 from the ground truth).

This is the model that makes the detections most likely. It is not the one that tracks best:
on the four sets of docs/mot.md, values learned from the other sequences of a set tracked
each sequence worse than the defaults on MOT17, as did values chosen by tracking score
(docs/mot.md, "What was tried"). :func:`vistrack.pipeline.fit_sequences` therefore checks
learned values against the given configuration on held-out sequences when it can (with a
ground truth), and returns them only where they tracked those better; from a first pass,
with nothing to check against, it returns the given configuration with each measurement
noise raised to the learned one where that is larger.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

from .._validate import as_number, as_whole
from ..association.assign import gnn_sparse
from ..association.costs import iou_pairs
from ..models.box import BoxMotion
from ..types import _whole_numbers

Series = tuple[np.ndarray, np.ndarray, np.ndarray]
"""One object's frames, detections and reference boxes (:func:`matched_series`)."""

__all__ = ["MotionFit", "matched_series", "measurement_noise", "smoothed_residual_share",
           "fit_box_motion",
           "median_motion"]


def _xyxy(boxes: np.ndarray) -> np.ndarray:
    return np.c_[boxes[:, :2], boxes[:, :2] + boxes[:, 2:]]


def _whole(values: ArrayLike, name: str) -> np.ndarray:
    """``values`` as a 1-D int64 array, or a ValueError naming ``name`` (frames and
    identities of 1.9 were cut to 1)."""
    a = _whole_numbers(values, name)
    if a.ndim != 1:
        raise ValueError(f"{name} must be 1-D; got shape {a.shape}")
    return a


def matched_series(ref_frames: np.ndarray, ref_ids: np.ndarray, ref_boxes: np.ndarray,
                   det_frames: np.ndarray, det_boxes: np.ndarray, *, min_iou: float = 0.5,
                   min_length: int = 10) -> list[Series]:
    """The detections of each reference object, frame by frame.

    Parameters
    ----------
    ref_frames, ref_ids : (N,) array_like of int
        The reference boxes' frames and identities.
    ref_boxes, det_boxes : (N, 4), (M, 4) array_like
        Reference and detected boxes ``[x, y, w, h]`` (MOTChallenge's left, top, width,
        height).
    det_frames : (M,) array_like of int
        The detections' frames.
    min_iou : float
        The least IoU at which a detection is an object's.
    min_length : int
        The least number of matched detections an object needs to be kept.

    Returns
    -------
    list of (frames, measurements, reference)
        For each kept object, in the order of its identity: ``frames (T,)`` from its first
        to its last matched frame, ``measurements (T, 4)``, the matched detections
        ``[cx, cy, w, h]``, and ``reference (T, 4)``, the reference boxes they matched, both
        NaN in frames without a match.

    Examples
    --------
    >>> ref = np.array([[0, 0, 10, 20], [1, 0, 10, 20], [2, 0, 10, 20.0]])
    >>> det = np.array([[0, 0, 10, 20], [2.5, 0, 10, 20.0], [50, 50, 5, 5]])
    >>> [(f.tolist(), z[:, 0].tolist(), g[:, 0].tolist()) for f, z, g in matched_series(
    ...     [1, 2, 3], [7, 7, 7], ref, [1, 3, 3], det, min_length=2)]
    [([1, 2, 3], [5.0, nan, 7.5], [5.0, nan, 7.0])]
    """
    rf, ri = _whole(ref_frames, "ref_frames"), _whole(ref_ids, "ref_ids")
    df = _whole(det_frames, "det_frames")
    rb, db = np.asarray(ref_boxes, np.float64), np.asarray(det_boxes, np.float64)
    for name, boxes, n, of in (("ref_boxes", rb, len(rf), "ref_frames"),
                               ("det_boxes", db, len(df), "det_frames")):
        if boxes.ndim != 2 or boxes.shape[1] != 4 or len(boxes) != n:
            raise ValueError(f"{name} must be ({n}, 4), a box [x, y, w, h] for each of "
                             f"{of}; got shape {boxes.shape}")
        bad = ~np.isfinite(boxes).all(axis=1)
        if bad.any():
            # (named as iou_pairs' "a" or "b", by its index in its frame, as x0, y0, x1, y1;
            # and a NaN detection in a frame without reference boxes was taken)
            k = int(np.flatnonzero(bad)[0])
            raise ValueError(f"{name} must be finite; {name}[{k}] = {boxes[k].tolist()}")
    if len(ri) != len(rf):
        raise ValueError(f"ref_ids must be ({len(rf)},), one for each of ref_frames; got "
                         f"shape {ri.shape}")
    if not 0 < as_number(min_iou, "min_iou") <= 1:  # ("a" failed on "'<' not supported")
        raise ValueError(f"min_iou must be in (0, 1]; got {min_iou}")
    min_length = as_whole(min_length, "min_length", 1)
    match = np.full(len(rf), -1)
    r_order, d_order = np.argsort(rf, kind="stable"), np.argsort(df, kind="stable")
    r_frames, d_frames = rf[r_order], df[d_order]
    for f in np.intersect1d(r_frames, d_frames):
        gi = r_order[np.searchsorted(r_frames, f):np.searchsorted(r_frames, f, "right")]
        di = d_order[np.searchsorted(d_frames, f):np.searchsorted(d_frames, f, "right")]
        r, c, v = iou_pairs(_xyxy(rb[gi]), _xyxy(db[di]), min_iou)
        rows, cols = gnn_sparse(r, c, 1.0 - v, (len(gi), len(di)))
        match[gi[rows]] = di[cols]
    out = []
    # an identity twice in a frame, whether or not either row was matched (only a pair both
    # matched was named): named by the first such frame and both rows' indices
    key = np.lexsort((ri, rf))
    twice = np.flatnonzero((np.diff(rf[key]) == 0) & (np.diff(ri[key]) == 0))
    if len(twice):
        a, b = sorted((int(key[twice[0]]), int(key[twice[0] + 1])))
        raise ValueError(f"reference identity {ri[a]} appears twice in frame {rf[a]} "
                         f"(ref_ids[{a}] and ref_ids[{b}])")
    for i in np.unique(ri):
        rows = np.flatnonzero((ri == i) & (match >= 0))
        if len(rows) < min_length:
            continue
        frames = rf[rows]
        t = np.arange(frames.min(), frames.max() + 1)
        z, ref = np.full((len(t), 4), np.nan), np.full((len(t), 4), np.nan)
        b, g = db[match[rows]], rb[rows]
        z[frames - t[0]] = np.c_[b[:, :2] + b[:, 2:] / 2, b[:, 2:]]
        ref[frames - t[0]] = np.c_[g[:, :2] + g[:, 2:] / 2, g[:, 2:]]
        out.append((t, z, ref))
    return out


@dataclass(frozen=True)
class MotionFit:
    """What :func:`fit_box_motion` learned.

    Attributes
    ----------
    motion : BoxMotion
        The learned noise at 30 frames/s, a new track's uncertainty ``start``'s
        (:func:`median_motion`).
    per_sequence : list of dict
        For each sequence given with an object detected twice or more: its ``sequence``
        (index in the list given), ``frame_rate``, ``objects``, ``detections``, ``std_pos``
        and ``std_vel`` (at 30 frames/s), ``std_meas`` (4 values), ``iterations``,
        ``converged`` and the final ``loglik``.
    """

    motion: BoxMotion
    per_sequence: list[dict]


def measurement_noise(series: list[Series]) -> np.ndarray:
    """The detections' noise: robust standard deviations of ``measurement − reference`` for
    ``cx, cy, w, h``, as fractions of the reference's width (``cx``, ``w``) or height (``cy``,
    ``h``), about their median (a detector's bias is not noise); 1.4826 times the median
    absolute deviation.

    Examples
    --------
    >>> t = np.arange(4)
    >>> ref = np.tile([50.0, 50, 10, 20], (4, 1))
    >>> z = ref + np.array([[1.0, 0, 0, 0], [-1, 0, 0, 0], [1, 0, 0, 0], [-1, 0, 0, 0]])
    >>> measurement_noise([(t, z, ref)]).round(4).tolist()  # cx errs by 1 of a width of 10
    [0.1483, 0.0, 0.0, 0.0]
    """
    if not len(series):
        raise ValueError("no matched detections: nothing to learn from (series is empty)")
    e = np.concatenate([(z - g) / g[:, [2, 3, 2, 3]] for _, z, g in series])
    e = e[np.isfinite(e).all(axis=1)]
    if not len(e):
        raise ValueError("no matched detections: nothing to learn from")
    return 1.4826 * np.median(np.abs(e - np.median(e, axis=0)), axis=0)


def smoothed_residual_share(motion: BoxMotion) -> np.ndarray:
    r"""The share of a white detection error's variance left in the detection's residual
    about the fixed-interval (Rauch-Tung-Striebel) smoother of ``motion``, in steady state,
    for ``cx, cy, w, h``.

    Each value is a constant-velocity axis (position noise ``std_pos``, velocity noise
    ``std_vel`` a frame at ``motion``'s frame rate, measurement noise ``std_meas``, all in
    units of the box's size). In steady state the smoother is linear and time-invariant: its
    estimate at frame 0 is :math:`\hat x_0 = \sum_j w_j z_{-j}`, and the residual of a
    detection whose error :math:`v_0` is white with variance :math:`\sigma^2` keeps

    .. math:: \operatorname{Var}(v_0 - \sum_j w_j v_{-j}) = \sigma^2 \Big((1 - w_0)^2
              + \sum_{j \ne 0} w_j^2\Big)

    of it. The object's own motion is left out: it adds to a residual where the object moves
    as jumpily as the model's noise allows, and hardly at all where it moves much more
    smoothly, as people and cars do (the likeliest position noise for their detections is
    near 0, docs/mot.md), or at a constant velocity, which the smoother follows exactly. The
    weights
    are the smoother's response to one detection, from the filter's steady-state prior
    (the discrete algebraic Riccati equation), forward and back until they fall below
    ``1e-12`` of the first.

    Parameters
    ----------
    motion : BoxMotion
        The model the smoother used, at the frame rate it ran at.

    Returns
    -------
    (4,) ndarray
        The shares, in ``(0, 1]``: small where the smoother follows each detection closely
        (a large position noise against the measurement noise; at least the smallest
        positive float), near 1 where it averages over many. Cached for each model.

    Examples
    --------
    The default model follows a box's centre closely, its width less:

    >>> smoothed_residual_share(BoxMotion()).round(3).tolist()
    [0.373, 0.373, 0.642, 0.522]
    >>> smoothed_residual_share(BoxMotion().at_rate(7.0)).round(3).tolist()[0]
    0.104
    """
    return _residual_share(motion).copy()


@lru_cache(maxsize=64)
def _residual_share(motion: BoxMotion) -> np.ndarray:
    from scipy.linalg import solve_discrete_are

    F = np.array([[1.0, 1.0], [0.0, 1.0]])
    H = np.array([[1.0, 0.0]])
    Q = np.diag([motion.std_pos ** 2, motion.std_vel ** 2])
    out = np.empty(4)
    for i, r in enumerate(motion.std_meas):
        R = np.array([[r ** 2]])
        P = solve_discrete_are(F.T, H.T, Q, R)  # the prior's covariance
        K = P @ H.T / (P[0, 0] + r ** 2)  # (2, 1)
        Pf = P - K @ H @ P  # the corrected covariance
        C = Pf @ F.T @ np.linalg.inv(P)  # the smoother's gain
        A = (np.eye(2) - K @ H) @ F  # the filter's own dynamics
        # one detection at frame 0: the filter's estimates after it, x_t = A^t K
        xs = [K[:, 0]]
        while abs(xs[-1]).max() > 1e-12 * abs(xs[0]).max() and len(xs) < 100_000:
            xs.append(A @ xs[-1])
        # back from the last: x̂_t = x_t + C (x̂_{t+1} - F x_t); before frame 0 the filter
        # has not seen it (x_t = 0), so x̂_t = C x̂_{t+1}
        smoothed = xs[-1]
        after = [smoothed[0]]
        for x in reversed(xs[:-1]):
            smoothed = x + C @ (smoothed - F @ x)
            after.append(smoothed[0])
        w0 = after.pop()  # frame 0's own weight
        before: list[float] = []
        while abs(smoothed).max() > 1e-12 * abs(w0) and len(before) < 100_000:
            smoothed = C @ smoothed
            before.append(smoothed[0])
        out[i] = (1.0 - w0) ** 2 + float(np.sum(np.square(after)) + np.sum(np.square(before)))
    # a smoother that passes each detection through (a measurement noise negligible beside
    # the motion's) leaves nothing to divide by: the smallest share a float holds instead
    return np.clip(out, np.finfo(float).tiny, 1.0)


def fit_box_motion(sequences: list[tuple[list[Series], float]], *,
                   start: BoxMotion | None = None,
                   smoothed_by: Sequence[BoxMotion] | None = None) -> MotionFit:
    """Learn :class:`~vistrack.models.BoxMotion`'s noise from the series of
    :func:`matched_series` (see the module).

    The measurement noise is :func:`measurement_noise`, the detections against the
    reference boxes. The motion noise, ``std_pos`` and ``std_vel``, maximises the
    likelihood of the detections (the Kalman filter's, :func:`vistrack.filters.kalman_filter`)
    with that measurement noise: the best of a grid over their logarithms, then Nelder-Mead,
    each between ``e^-12`` and 1 of the size a frame. (EM, :func:`vistrack.filters.em`,
    learning the measurement noise as well, explains more and more of the detections'
    jitter as motion and drives the measurement noise towards zero: on MOT17-09, ``cx``'s
    from 0.009 of the width after 25 iterations to 0.004 after 300, still falling, where the
    ground truth says 0.019. With the measurement noise fixed it creeps: after 200
    iterations the position noise was still 0.013 of the size, where the maximum is near 0.)

    Parameters
    ----------
    sequences : list of (series, frame_rate)
        For each sequence, its objects' series and its frames per second.
    start : BoxMotion, optional
        The model the search starts from and whose ``init_pos`` and ``init_vel`` are kept
        (default: ``BoxMotion()``).
    smoothed_by : sequence of BoxMotion, optional
        The reference boxes are estimates smoothed through the detections (a first pass):
        for each sequence, the model its smoother ran with, at the frame rate it ran at (a
        detector run on every k-th frame: the sequence's rate over k). Each value's measured
        spread is divided by the square root of :func:`smoothed_residual_share` of it.
        Default: the reference boxes are the truth.

    Returns
    -------
    MotionFit

    Raises
    ------
    ValueError
        If no sequence has an object matched in two frames or more.
    """
    from scipy.optimize import minimize

    from ..filters.kalman import kalman_filter

    start = start if start is not None else BoxMotion()
    if smoothed_by is not None and len(smoothed_by) != len(sequences):
        raise ValueError(f"smoothed_by must have one model for each of the "
                         f"{len(sequences)} sequences; got {len(smoothed_by)}")
    F = BoxMotion().F(1.0)
    H = np.eye(4, 8)
    rows = []
    for index, (series, fps) in enumerate(sequences):
        series = [x for x in series if np.isfinite(x[1][:, 0]).sum() >= 2]
        if not series:
            continue
        meas = measurement_noise(series)
        if smoothed_by is not None:
            meas = meas / np.sqrt(smoothed_residual_share(smoothed_by[index]))
        meas = np.maximum(meas, 1e-6)
        m = start.at_rate(fps)
        T = max(len(t) for t, _, _ in series)
        Y = np.full((len(series), T, 4), np.nan)
        for k, (_, z, g) in enumerate(series):
            w, h = np.nanmedian(g[:, 2]), np.nanmedian(g[:, 3])
            first = int(np.flatnonzero(np.isfinite(z[:, 0]))[0])  # (matched_series': 0)
            Y[k, :len(z) - first] = z[first:] / np.array([w, h, w, h])
        detections = int(np.isfinite(Y[..., 0]).sum())
        # each series from its first detection, which is the first step's prior mean, with
        # the measurement noise as its spread: the likelihood is that of the later
        # detections given it, not of the first detection twice
        x0 = np.c_[Y[:, 0], np.zeros((len(Y), 4))]
        Y[:, 0] = np.nan
        P0 = np.diag(np.r_[meas ** 2, np.full(4, (m.init_vel * m.std_vel) ** 2)])
        R = np.diag(meas ** 2)

        def minus_loglik(log_std: np.ndarray, Y: np.ndarray = Y, R: np.ndarray = R,
                         x0: np.ndarray = x0, P0: np.ndarray = P0) -> float:
            Q = np.diag(np.repeat(np.exp(2.0 * log_std), 4))
            return -float(np.sum(kalman_filter(Y, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0,
                                               store_covs=False).loglik))

        # the likelihood is flat where a noise is negligible: a gradient method started at
        # the defaults can run to the bound of one noise and stop there, so the search
        # starts from the best of a grid over both (9 x 9, 1e-4 to 0.3 and 1e-5 to 0.1 of
        # the size a frame) and polishes with Nelder-Mead
        grid = [(a, b) for a in np.linspace(np.log(1e-4), np.log(0.3), 9)
                for b in np.linspace(np.log(1e-5), np.log(0.1), 9)]
        x_start = min(grid, key=lambda p: minus_loglik(np.array(p)))
        best = minimize(minus_loglik, np.array(x_start), method="Nelder-Mead",
                        bounds=[(-12.0, 0.0), (-12.0, 0.0)],
                        options=dict(xatol=1e-3, fatol=1e-3, maxiter=400))
        std_pos, std_vel = np.exp(best.x)
        at_30 = BoxMotion(std_pos=float(std_pos), std_vel=float(std_vel),
                          frame_rate=fps).at_rate(30.0)
        rows.append(dict(sequence=index, frame_rate=float(fps), objects=len(Y),
                         detections=detections,
                         std_pos=at_30.std_pos, std_vel=at_30.std_vel,
                         std_meas=[float(x) for x in meas], iterations=int(best.nit),
                         converged=bool(best.success), loglik=float(-best.fun)))
    if not rows:
        raise ValueError("no object was matched in two frames or more: nothing to learn from")
    return MotionFit(median_motion(rows, start), rows)


def median_motion(per_sequence: list[dict], start: BoxMotion) -> BoxMotion:
    """The median of sequences' values (:attr:`MotionFit.per_sequence`), at 30 frames/s.

    A new track's uncertainty is not learned: it stays ``start``'s (``init_pos σ_p`` and
    ``init_vel σ_v``, the multipliers rescaled to the learned ``σ_p`` and ``σ_v``), so a
    learned position noise near zero does not pin a new track to its first box."""
    s30 = start.at_rate(30.0)
    std_pos = float(np.median([r["std_pos"] for r in per_sequence]))
    std_vel = float(np.median([r["std_vel"] for r in per_sequence]))
    cx, cy, w, h = (float(x) for x in np.median([r["std_meas"] for r in per_sequence], axis=0))
    return BoxMotion(std_pos=std_pos, std_vel=std_vel, std_meas=(cx, cy, w, h),
                     init_pos=s30.init_pos * s30.std_pos / std_pos,
                     init_vel=s30.init_vel * s30.std_vel / std_vel, frame_rate=30.0)

r"""Detector scores calibrated by the detections themselves.

Every detector scores on its own scale: probabilities from 0.5 up (a detector thresholded at
0.5), raw logits from −1 to 16 (a LiDAR detector), a constant 1. A fixed threshold fitted to
one is wrong for the next: above every score of another, or below its clutter. What all have
in common is that a real object is detected again and again, where most clutter is not. So
the calibration asks two things of each detection, each one outcome of 0 or 1:

- does it **persist** from frame to frame: does it continue a detection of the previous
  frame and is it continued in the next (boxes of one class linked frame to frame
  one-to-one, by global nearest neighbour on IoU ≥ ``link_iou``)?
- does it lie on a **chain** that lasts: detections linked the same way, but across gaps of
  up to ``chain_gap`` seconds, the chain's last box moved by the image's shift since it was
  seen (the median displacement of the frame-to-frame links), spanning ``chain_span``
  seconds or more? A person half hidden in a crowd is detected in some frames and not in
  others, so few of their detections persist from frame to frame, but they lie on long
  chains. Clutter that recurs where it was lies on chains too, so chains alone would take
  it for objects. The frame-to-frame outcome is known one frame later; a chain's once it
  spans ``chain_span`` (1 for every detection on it, and for those that join it later) or
  once it has gone ``chain_gap`` without a detection (0 for all of them).

The two outcomes weigh the same: each detection contributes both. Then

- ``P(outcome | score)`` is estimated by isotonic regression: the non-decreasing function of
  the score closest to the outcomes in least squares (pool-adjacent-violators, over the
  distinct scores weighted by their counts);
- but where the outcomes contradict the detector's own ranking beyond their noise, the
  ranking is trusted: false positives that recur in place (a poster, a reflection) persist
  as an object does, mostly at low scores, and pooled with the detections scored above them
  they would raise the confidence of every score in between. So the outcomes are grouped,
  from the top score down, into bins of at least 2 % of them (and at least 50), and a bin
  below the top third of the outcomes whose rate exceeds the isotonic fit of the bins above
  it by more than ``cap_sigma`` (5) standard errors (the two rates' difference, with their
  pooled rate's binomial variance) is taken down to that fit before the regression. Outcomes
  that agree with the ranking, or disagree within their noise, are fitted as they are. The
  outcomes are not independent (a chain's detections share one), so 5 binomial standard
  errors are fewer true ones; and near a rate of 0 the normal approximation makes the bound
  narrower than it reads. Within the top third, a dip (the most confident detections
  persisting less than the next: large, near objects that move fast against their size) is
  motion, not clutter, and is pooled;
- it is divided by the rate of the detector's most confident detections (the top ``top``
  fraction of the outcomes by score, 5 %, and at least 20 of them), since objects themselves
  persist less where they move fast against their size or the frame rate is low, and
  clipped to 1.

The result, the **calibrated confidence** ``c(score)`` in ``[0, 1]``, says how nearly a
detection of that score behaves like the detector's best ones. It depends on the order of the
scores only, so any strictly increasing transform of all scores (× 10, a logit, a square)
leaves it, and every threshold on it, exactly unchanged.

:class:`ScoreCalibration` is a fitted map; :meth:`ScoreCalibration.from_frames` fits one to a
whole sequence (the offline mode). :class:`ScoreCalibrator` learns it online from the frames
seen so far. Until its first outcome (the second frame's, known once the third is seen; or
the second frame's chains, where ``chain_span`` is one frame or less) the confidence is the
rank of each score among those seen, so the first frames trust their best-scored detections
most; with ``prior`` > 0 the rank keeps a weight after that
(``c = w c_data + (1 - w) rank``, ``w = n / (n + prior)`` for ``n`` outcomes; 0 by default,
which tracked best on the four sets of docs/mot.md).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from .._jit import njit
from .._prebuilt import kernel
from .._validate import as_number, as_whole, check_in_pixels, is_number, is_whole
from ..association.assign import gnn_pairs
from ..association.costs import iou_pairs_same_class
from ..types import Detections
from .lifecycle import nearest_whole

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["NoOutcomesError", "ScoreCalibration", "ScoreCalibrator", "TOP_PERSISTS",
           "isotonic_increasing", "persistence"]


@kernel
@njit(cache=True)
def _pava(y, w):
    # pool adjacent violators: the non-decreasing fit to y with weights w (w > 0)
    n = y.shape[0]
    val, wt, size = np.empty(n), np.empty(n), np.empty(n, np.int64)
    k = 0
    for i in range(n):
        val[k], wt[k], size[k] = y[i], w[i], 1
        while k > 0 and val[k - 1] > val[k]:
            tot = wt[k - 1] + wt[k]
            val[k - 1] = (val[k - 1] * wt[k - 1] + val[k] * wt[k]) / tot
            wt[k - 1] = tot
            size[k - 1] += size[k]
            k -= 1
        k += 1
    out = np.empty(n)
    i = 0
    for b in range(k):
        for _ in range(size[b]):
            out[i] = val[b]
            i += 1
    return out


def isotonic_increasing(y: ArrayLike, weights: ArrayLike | None = None) -> np.ndarray:
    r"""The non-decreasing sequence closest to ``y`` in weighted least squares (isotonic
    regression by pool-adjacent-violators).

    .. math:: \hat y = \arg\min_{z_1 \le z_2 \le \dots \le z_N} \sum_i w_i (y_i - z_i)^2

    Parameters
    ----------
    y : (N,) array_like
        The values, in order (flattened), finite.
    weights : (N,) array_like, optional
        Their weights, finite and > 0; default all 1.

    Returns
    -------
    (N,) ndarray
        The fit: each run of values that violates the order is replaced by its weighted
        mean.

    Raises
    ------
    ValueError
        If ``weights`` does not have the shape of ``y``, or a value or weight is not finite,
        or a weight is not > 0, or, where a pool's sums would overflow, weights pooled
        with each other alone are all under about 2^-1074 of ``N`` times the largest (they
        vanish when the weights are scaled to keep the sums finite; under 2^-1022 of it,
        they lose digits).

    Examples
    --------
    >>> isotonic_increasing([1.0, 3.0, 2.0, 4.0]).tolist()
    [1.0, 2.5, 2.5, 4.0]
    """
    y = np.ascontiguousarray(y, dtype=np.float64).ravel()
    w = np.ones_like(y) if weights is None else np.ascontiguousarray(weights, np.float64).ravel()
    if w.shape != y.shape:
        raise ValueError(f"weights must have the shape of y {y.shape}; got {w.shape}")
    if not (np.isfinite(y).all() and np.isfinite(w).all() and (w > 0).all()):
        raise ValueError("y must be finite and weights finite and > 0")
    if not len(y):
        return y.copy()
    if np.isfinite(w.sum()):  # (a pool's weight is then finite: none overflows)
        fit = _pava(y, w)
        if np.isfinite(fit).all():
            return fit
    # a pool's weighted sum overflowed (values or weights near the largest float gave inf
    # or NaN; weights whose sum overflows gave a finite value over an infinite weight, 0):
    # again with the values halved and the weights scaled so that they add up to at most
    # 1, both by powers of two, which leave every product and quotient as it was (weights
    # under about 2^-1022 of that scale lose digits, and under 2^-1074 vanish: two such
    # pooled first give NaN)
    scale = math.ldexp(1.0, -(math.frexp(float(w.max()))[1] + math.frexp(len(w))[1]))
    try:
        fit = _pava(y * 0.5, w * scale) * 2.0
    except ZeroDivisionError:  # (the compiled pool's 0 / 0)
        fit = np.array([np.nan])
    if not np.isfinite(fit).all():
        raise ValueError("weights span too wide a range to pool (adjacent weights under "
                         "2^-1074 of the largest, times the number of values)")
    return fit


@njit(cache=True)
def _link(prev, prev_cls, cur, cur_cls, min_iou):
    # one-to-one links (GNN on 1 - IoU) between two frames' boxes of the same class
    rows, cols, ov, _ = iou_pairs_same_class(prev, prev_cls, cur, cur_cls, min_iou)
    return gnn_pairs(rows, cols, 1.0 - ov, prev.shape[0], cur.shape[0])


@njit(cache=True)
def _chain_step(t, gap, step, span, shift, head_box, head_cls, head_t, head_shift, head_chain,
                first, state, open_s, open_chain, boxes, cls, s, min_iou):
    # one frame of ScoreCalibrator's chains (see _observe): returns the new heads, the
    # chains' first frames and states by chain number, the detections still open, and the
    # scores and outcomes resolved in this frame
    H, N, C = head_box.shape[0], boxes.shape[0], first.shape[0]
    state = state.copy()
    keep = np.empty(H, np.bool_)
    for i in range(H):
        keep[i] = t - head_t[i] <= gap
        if not keep[i] and state[head_chain[i]] == 0:
            state[head_chain[i]] = -1  # ended short of the span
    kept = np.flatnonzero(keep)
    K = kept.shape[0]
    moved = np.empty((K, 4))
    kcls = np.empty(K, np.int64)
    age = np.empty(K)
    for j in range(K):
        i = kept[j]
        for a in range(4):
            moved[j, a] = head_box[i, a] + shift[a % 2] - head_shift[i, a % 2]
        kcls[j] = head_cls[i]
        age[j] = (t - head_t[i]) / step  # in steps of the frames observed
    ids = np.full(N, -1, np.int64)
    taken = np.zeros(K, np.bool_)
    if K > 0 and N > 0:
        # one-to-one links (GNN) on 1 - IoU plus 0.01 a step (this frame's, in frames)
        # since the chain was last extended (the most recent chain wins a tie)
        rows, cols, ov, _ = iou_pairs_same_class(moved, kcls, boxes, cls, min_iou)
        r, c = gnn_pairs(rows, cols, 1.0 - ov + 0.01 * age[rows], K, N)
        for m in range(r.shape[0]):
            ids[c[m]] = head_chain[kept[r[m]]]
            taken[r[m]] = True
    n_new = 0
    for j in range(N):
        if ids[j] < 0:
            n_new += 1
    first2 = np.empty(C + n_new, np.int64)
    state2 = np.empty(C + n_new, np.int8)
    for i in range(C):  # a loop: a slice assignment costs numba a compilation of its error path
        first2[i] = first[i]
        state2[i] = state[i]
    k = C
    for j in range(N):
        if ids[j] < 0:
            ids[j] = k
            first2[k] = t
            state2[k] = 0
            k += 1
        elif state2[ids[j]] == 0 and t - first2[ids[j]] >= span - 1e-9:
            state2[ids[j]] = 1  # lasted: every detection on it counts
    # the open detections whose chain is now resolved give their outcomes
    P = open_s.shape[0]
    all_s = np.concatenate((open_s, s))
    all_c = np.concatenate((open_chain, ids))
    n_done = 0
    for j in range(P + N):
        if state2[all_c[j]] != 0:
            n_done += 1
    out_s, out_p = np.empty(n_done), np.empty(n_done)
    still_s, still_c = np.empty(P + N - n_done), np.empty(P + N - n_done, np.int64)
    d = 0
    o = 0
    for j in range(P + N):
        st = state2[all_c[j]]
        if st != 0:
            out_s[d] = all_s[j]
            out_p[d] = 1.0 if st > 0 else 0.0
            d += 1
        else:
            still_s[o] = all_s[j]
            still_c[o] = all_c[j]
            o += 1
    # the heads: the chains not extended (and not ended), then this frame's detections
    n_keep = 0
    for j in range(K):
        if not taken[j]:
            n_keep += 1
    M = n_keep + N
    hb, hc, ht = np.empty((M, 4)), np.empty(M, np.int64), np.empty(M, np.int64)
    hs, hid = np.empty((M, 2)), np.empty(M, np.int64)
    m = 0
    for j in range(K):
        if not taken[j]:
            i = kept[j]
            for a in range(4):  # loops: see the chains' first frames above
                hb[m, a] = head_box[i, a]
            hc[m], ht[m], hid[m] = head_cls[i], head_t[i], head_chain[i]
            hs[m, 0], hs[m, 1] = head_shift[i, 0], head_shift[i, 1]
            m += 1
    for j in range(N):
        for a in range(4):
            hb[m, a] = boxes[j, a]
        hc[m], ht[m], hid[m] = cls[j], t, ids[j]
        hs[m, 0], hs[m, 1] = shift[0], shift[1]
        m += 1
    # once more than half the table's chains are no longer referred to (by a head or an open
    # detection), keep only the others, renumbered from 0 in order: a chain that lasts for
    # hours does not keep every chain begun after it
    C2 = first2.shape[0]
    alive = np.zeros(C2, np.bool_)
    for j in range(M):
        alive[hid[j]] = True
    for j in range(o):
        alive[still_c[j]] = True
    n_alive = 0
    for j in range(C2):
        if alive[j]:
            n_alive += 1
    if C2 >= 64 and C2 > 2 * n_alive:
        new_id = np.full(C2, -1, np.int64)
        first3, state3 = np.empty(n_alive, np.int64), np.empty(n_alive, np.int8)
        k = 0
        for j in range(C2):
            if alive[j]:
                new_id[j], first3[k], state3[k] = k, first2[j], state2[j]
                k += 1
        for j in range(M):
            hid[j] = new_id[hid[j]]
        for j in range(o):
            still_c[j] = new_id[still_c[j]]
        first2, state2 = first3, state3
    return hb, hc, ht, hs, hid, first2, state2, still_s, still_c, out_s, out_p


@kernel
@njit(cache=True)
def _observe(prev_box, prev_cls, boxes, cls, s, link_iou, shift, chains, t, gap, step, span,
             head_box, head_cls, head_t, head_shift, head_chain, first, state, open_s,
             open_chain):
    # one frame of ScoreCalibrator.observe in one compiled call: the frame-to-frame links
    # to the previous frame's detections (which of those are continued, which of these
    # continue one), the image's shift summed (the links' median displacement, with chains
    # and 3 links or more), and, with chains, _chain_step
    P, N = prev_box.shape[0], boxes.shape[0]
    fwd, back = np.zeros(P, np.bool_), np.zeros(N, np.bool_)
    shift = shift.copy()
    if P > 0 and N > 0:
        r, c = _link(prev_box, prev_cls, boxes, cls, link_iou)
        n = r.shape[0]
        for k in range(n):
            fwd[r[k]] = True
            back[c[k]] = True
        if chains and n >= 3:
            d = np.empty(n)
            for a in range(2):
                for k in range(n):
                    d[k] = (boxes[c[k], a] + boxes[c[k], a + 2] - prev_box[r[k], a]
                            - prev_box[r[k], a + 2]) / 2
                shift[a] = shift[a] + np.median(d)
    if chains:
        (head_box, head_cls, head_t, head_shift, head_chain, first, state, open_s, open_chain,
         out_s, out_p) = _chain_step(t, gap, step, span, shift, head_box, head_cls, head_t,
                                     head_shift, head_chain, first, state, open_s, open_chain,
                                     boxes, cls, s, link_iou)
    else:
        out_s, out_p = np.zeros(0), np.zeros(0)
    return (fwd, back, shift, head_box, head_cls, head_t, head_shift, head_chain, first, state,
            open_s, open_chain, out_s, out_p)


def _rank_capped(hits: np.ndarray, counts: np.ndarray, cap_sigma: float) -> np.ndarray:
    """``hits`` (outcomes of 1 per distinct score, in increasing order of score) with each bin
    below the top third that contradicts the fit of the bins above it beyond ``cap_sigma``
    standard errors taken down to that fit (see the module)."""
    n = counts.sum()
    size = max(50.0, 0.02 * n)
    # bins from the top: consecutive distinct scores, each bin closed as soon as it holds
    # `size` outcomes
    rc = counts[::-1]
    cum = np.cumsum(rc)
    above = cum - rc  # outcomes scoring above each distinct score, from the top
    starts = [0]  # start (from the top) of each bin
    while True:
        end = int(np.searchsorted(cum, above[starts[-1]] + size)) + 1  # past the bin
        if end >= len(rc):
            break
        starts.append(end)
    if cum[-1] - above[starts[-1]] < size and len(starts) > 1:
        starts.pop()  # the bottom's remainder joins the bin above it
    if len(starts) < 2:
        return hits
    rh = hits[::-1]
    bin_h = np.add.reduceat(rh, starts).tolist()
    bin_c = np.add.reduceat(rc, starts).tolist()
    bin_above = above[starts].tolist()
    scale = [1.0] * len(starts)
    # the fit of the bins above, as blocks of equal rate (pooled, so the lowest block holds
    # every outcome at its rate), from the top: [hits, outcomes]
    stack: list[list[float]] = []
    for b, (h, c) in enumerate(zip(bin_h, bin_c)):
        if stack and bin_above[b] >= n / 3:
            up_h, up_c = stack[-1]
            if h * up_c > up_h * c:  # the bin's rate above the fit of the bins above it
                pooled = (h + up_h) / (c + up_c)
                se = math.sqrt(pooled * (1.0 - pooled) * (1.0 / c + 1.0 / up_c))
                if h / c - up_h / up_c > cap_sigma * se:
                    scale[b] = (up_h / up_c) / (h / c)
                    stack[-1][1] += c  # taken down to the block's rate: part of it
                    stack[-1][0] += c * up_h / up_c
                    continue
        stack.append([h, c])
        while len(stack) > 1 and stack[-1][0] * stack[-2][1] >= stack[-2][0] * stack[-1][1]:
            bh, bc = stack.pop()
            stack[-1][0] += bh
            stack[-1][1] += bc
    if all(f == 1.0 for f in scale):
        return hits
    return (rh * np.repeat(scale, np.diff(starts + [len(rc)])))[::-1]


def _scores(scores: ArrayLike, name: str = "scores") -> np.ndarray:
    s = np.asarray(scores, dtype=np.float64).ravel()
    bad = np.flatnonzero(np.isnan(s))
    if len(bad):
        raise ValueError(f"{name} must not be NaN; {name}[{int(bad[0])}] is NaN")
    return s


def persistence(frames: Iterable[Detections], link_iou: float = 0.3
                ) -> tuple[np.ndarray, np.ndarray]:
    """The scores of every detection of the frames but the first and the last (which lack a
    neighbour), and whether each persists (it continues a detection of the previous frame and
    is continued in the next; see the module): ``(scores, persisted)``, in the order of the
    frames and of the detections within them.

    Parameters
    ----------
    frames : iterable of Detections
        One frame's detections each, with boxes, in order (None: a frame where nothing was
        found, as :meth:`BoxTracker.step <vistrack.tracking.BoxTracker.step>` reads it).
    link_iou : float
        The IoU at which a detection continues one of the previous frame (boxes of one class,
        linked one-to-one by global nearest neighbour).

    Returns
    -------
    scores : (M,) ndarray
        The detections' scores.
    persisted : (M,) bool ndarray
        Whether each persists.

    Examples
    --------
    An object that stays (score 0.9) and clutter that jumps (score 0.4), over four frames:

    >>> frames = [Detections(boxes=np.array([[10.0, 10, 40, 80], [200 + 50 * f, 100,
    ...                                      230 + 50 * f, 160]]), scores=np.array([0.9, 0.4]))
    ...           for f in range(4)]
    >>> scores, persisted = persistence(frames)
    >>> scores.tolist(), persisted.tolist()
    ([0.9, 0.4, 0.9, 0.4], [True, False, True, False])
    """
    s, p = _outcomes(frames, link_iou=link_iou, chain_span=0.0)
    return s, p.astype(bool)


def _outcomes(frames: Iterable[Detections], **calibrator: Any) -> tuple[np.ndarray, np.ndarray]:
    # every outcome of a whole sequence (ScoreCalibrator.outcomes after its last frame)
    cal = ScoreCalibrator(window=None, **calibrator)
    for d in frames:
        # None: a frame of none, as BoxTracker.step reads it (observe's None, the end, cut
        # the sequence there, each side's outcomes lost at the cut)
        cal.observe(_NONE if d is None else d)
    cal.observe(None)  # the last frame has no next frame: its detections do not persist
    return cal.outcomes()


_NONE = Detections(boxes=np.zeros((0, 4)))
"""A frame of no detections."""


TOP_PERSISTS = 0.5
"""The rate below which the detector's most confident detections are said not to persist
(``ScoreCalibration.top_persistence``): at a lower one, outcomes tell objects from clutter no
longer. :meth:`ScoreCalibration.from_frames` then loosens its links (``min_link_iou``), and
:func:`vistrack.pipeline.calibration_warning` warns where every detection counts as
confident."""


_QUIET = True
"""Whether :meth:`ScoreCalibrator.observe` passes over a frame without detections quickly
where the one before held none and no chain is open (the same state as the full step; a
test compares the two)."""


class NoOutcomesError(ValueError):
    """No outcome to fit a calibration to: no scores at all, or, over a whole sequence, no
    detection that was seen to persist or not (:meth:`ScoreCalibration.from_frames`)."""


class ScoreCalibration:
    """A fitted map from a detector's scores to calibrated confidences in ``[0, 1]`` (see the
    module). Call it on scores; :meth:`score_at` is the lowest score with a given confidence.

    Parameters
    ----------
    scores : (M,) float
        The distinct scores, increasing.
    confidence : (M,) float
        Their confidences, non-decreasing, in ``[0, 1]``. A score between two of them takes
        the lower one's confidence, a score below all of them the lowest, one above all the
        highest.
    n : int
        How many outcomes the map was fitted to (0: none; the rank prior alone).
    top_persistence : float
        The rate of the top outcomes (by score) that the data part was divided by.
    link_iou : float
        The IoU at which the outcomes linked detections (:meth:`from_frames`; NaN where the
        map was not fitted to frames).

    Attributes
    ----------
    scores, confidence : (M,) ndarray
        The map's points, as given.
    n, top_persistence, link_iou : int, float, float
        As given.

    Raises
    ------
    ValueError
        If ``scores`` and ``confidence`` differ in length or are empty, the scores are not
        increasing (or one is NaN), or the confidences are not non-decreasing in ``[0, 1]``.

    Examples
    --------
    >>> s = [0.2, 0.3, 0.6, 0.7, 0.8, 0.9]
    >>> cal = ScoreCalibration.fit(s, [0, 0, 1, 0, 1, 1], top=1 / 3, top_min=2)
    >>> cal([0.25, 0.65, 0.95]).tolist()
    [0.0, 0.5, 1.0]
    >>> cal.score_at(0.5), cal.score_at(0.9)
    (0.6, 0.8)
    """

    def __init__(self, scores: ArrayLike, confidence: ArrayLike, *, n: int = 0,
                 top_persistence: float = float("nan"), link_iou: float = float("nan")):
        s = np.asarray(scores, dtype=np.float64).ravel()
        c = np.asarray(confidence, dtype=np.float64).ravel()
        if s.shape != c.shape or len(s) == 0:
            raise ValueError(f"scores and confidence must have one equal, non-zero length; got "
                             f"{s.shape} and {c.shape}")
        with np.errstate(invalid="ignore"):  # inf - inf is NaN: not increasing
            rising = bool((np.diff(s) > 0).all())
        if np.isnan(s).any() or not rising:
            raise ValueError("scores must be increasing (distinct) and not NaN")
        if not ((c >= 0) & (c <= 1)).all() or (np.diff(c) < 0).any():
            raise ValueError("confidence must be non-decreasing, in [0, 1]")
        self.scores, self.confidence = s, c
        self.n, self.top_persistence = int(n), float(top_persistence)
        self.link_iou = float(link_iou)

    @classmethod
    def fit(cls, scores: ArrayLike, persisted: ArrayLike, *, top: float = 0.05,
            top_min: int = 20, cap_sigma: float = 5.0) -> ScoreCalibration:
        """Fit to scores and their outcomes (see the module): full confidence is the rate of
        the ``top`` fraction of the outcomes by score, and of at least
        ``top_min`` of them (a small sample's top fraction is a handful).

        Parameters
        ----------
        scores : (N,) array_like
            The detections' scores (not NaN).
        persisted : (N,) array_like
            Each outcome: whether the detection persisted, or its chain lasted (bool, or 0
            and 1).
        top : float
            The fraction of the outcomes, by score, whose rate is full confidence,
            in ``(0, 1]``; ties at its edge are included.
        top_min : int
            The least number of detections it is taken over (all of them if there are
            fewer).
        cap_sigma : float
            How many standard errors a bin of outcomes below the top third may lie above the
            fit of the bins scored above it before it is taken down to that fit (see the
            module); ``inf``: the plain isotonic fit.

        Returns
        -------
        ScoreCalibration
            On the distinct scores: the isotonic fit of the outcomes (bins that contradict
            the ranking taken down first) over the top outcomes' rate, clipped to 1 (all 1
            when none of the top outcomes is 1).

        Raises
        ------
        ValueError
            If ``top`` is not in ``(0, 1]``, ``cap_sigma`` is not > 0, the shapes differ,
            a score is NaN, or an outcome is not in [0, 1]; :class:`NoOutcomesError` (a
            ``ValueError``) if there are no scores.

        Examples
        --------
        >>> cal = ScoreCalibration.fit([0.1, 0.2, 0.8, 0.9], [0, 1, 1, 1], top=0.5, top_min=2)
        >>> cal.confidence.tolist(), cal.top_persistence
        ([0.0, 1.0, 1.0, 1.0], 1.0)
        """
        # (True was taken as 1, every confidence then another; text or None failed in a
        # comparison, naming nothing)
        top, cap_sigma = as_number(top, "top"), as_number(cap_sigma, "cap_sigma")
        if not 0 < top <= 1:
            raise ValueError(f"top must be in (0, 1]; got {top}")
        if not cap_sigma > 0:
            raise ValueError(f"cap_sigma must be > 0; got {cap_sigma}")
        top_min = as_whole(top_min, "top_min", 1)
        s = _scores(scores)
        p = np.asarray(persisted, dtype=np.float64).ravel()
        if p.shape != s.shape:
            raise ValueError(f"persisted must have the shape of scores {s.shape}; got {p.shape}")
        bad = ~((p >= 0) & (p <= 1))  # NaN too: an outcome is 0, 1 or a weight between
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(f"persisted must hold outcomes in [0, 1]; persisted[{i}] = {p[i]}")
        if len(s) == 0:
            raise NoOutcomesError("no scores to fit")
        u, inv, counts = np.unique(s, return_inverse=True, return_counts=True)
        hits = outcomes = np.bincount(inv, weights=p, minlength=len(u))
        if np.isfinite(cap_sigma):
            hits = _rank_capped(hits, counts, cap_sigma)
        fit = _pava(hits / counts, counts.astype(np.float64))
        # the rate of the top fraction by score (ties at its edge included), of the outcomes
        # themselves (the cap's, where the top reaches below the top third, lowered it); a
        # fraction of a whole count taken as that count (0.07 x 100 is 7.000000000000001,
        # and took 8)
        above = np.cumsum(counts[::-1])[::-1]  # detections scoring >= u[k]
        need = min(len(s), max(math.ceil(round(top * len(s), 9)), top_min))
        k = int(np.flatnonzero(above >= need)[-1])
        a = outcomes[k:].sum() / counts[k:].sum()
        if a <= 0:
            conf = np.ones(len(u))  # nothing persists: no evidence to tell scores apart
        else:
            conf = np.minimum(fit / a, 1.0)
        return cls(u, conf, n=len(s), top_persistence=a)

    @classmethod
    def from_frames(cls, frames: Iterable[Detections], *, link_iou: float = 0.3,
                    top: float = 0.05, top_min: int = 20, cap_sigma: float = 5.0,
                    frame_rate: float = 30.0, chain_span: float = 1.0,
                    chain_gap: float = 0.2, min_link_iou: float | None = None
                    ) -> ScoreCalibration:
        """Fit to a whole sequence of frames (the offline mode).

        The outcomes a :class:`ScoreCalibrator` holds after the last frame (frame-to-frame
        persistence and chains), then :meth:`fit`.

        With ``min_link_iou`` below ``link_iou``, the overlap that links detections is
        loosened where the detector's most confident detections persist less than half the
        time (``top_persistence`` under :data:`TOP_PERSISTS`): their objects then move too
        far between frames, against their size, for their boxes to overlap by ``link_iou``
        (a low frame rate, fast motion), and the outcomes no longer tell objects from
        clutter. The outcomes are gathered again at overlaps 0.1 lower, down to
        ``min_link_iou`` (the last step shorter where it falls between two), and the first at
        which the most confident persist half the time or more is taken (the loosest where
        none does). Where they do at ``link_iou``, nothing changes.

        Parameters
        ----------
        frames : iterable of Detections
            Every frame's detections, with boxes, in order (None: a frame of none).
        link_iou : float
            The IoU at which a detection continues one of the previous frame.
        top, top_min, cap_sigma : float, int, float
            The fraction of the outcomes, by score, whose rate is full confidence, the least
            number of them, and the bound on outcomes that contradict the detector's ranking
            (:meth:`fit`).
        frame_rate, chain_span, chain_gap : float
            Frames a second, and the chains' span and gap in seconds (see
            :class:`ScoreCalibrator`).
        min_link_iou : float, optional
            The loosest overlap tried, > 0 (None, or ``link_iou`` or more: ``link_iou``
            alone).

        Returns
        -------
        ScoreCalibration
            The fitted map; its ``link_iou`` is the overlap its outcomes were gathered at.

        Raises
        ------
        NoOutcomesError
            If no outcome is resolved: the frames but the first and the last hold no
            detections, and no chain has lasted or ended (a ``ValueError``).
        ValueError
            If ``min_link_iou`` is not an overlap > 0 (nor None).

        Examples
        --------
        An object that stays (score 0.9) and clutter that jumps (score 0.4):

        >>> frames = [Detections(boxes=np.array([[10.0, 10, 40, 80], [200 + 50 * f, 100,
        ...                                      230 + 50 * f, 160]]), scores=np.array([0.9, 0.4]))
        ...           for f in range(6)]
        >>> cal = ScoreCalibration.from_frames(frames)
        >>> cal([0.4, 0.9]).tolist(), cal.score_at(0.5), cal.link_iou
        ([0.0, 1.0], 0.9, 0.3)

        The object moving 0.6 of its width a frame (its boxes overlap by 0.4 / 1.6 = 0.25),
        the clutter as before: at 0.3 nothing persists, and nothing tells the two apart; at
        0.2 the object persists:

        >>> fast = [Detections(boxes=np.array([[10.0 + 18 * f, 10, 40 + 18 * f, 80],
        ...                                    [200 + 50 * f, 100, 230 + 50 * f, 160]]),
        ...                    scores=np.array([0.9, 0.4])) for f in range(6)]
        >>> cal = ScoreCalibration.from_frames(fast)
        >>> cal([0.4, 0.9]).tolist(), cal.top_persistence
        ([1.0, 1.0], 0.0)
        >>> cal = ScoreCalibration.from_frames(fast, min_link_iou=0.1)
        >>> cal([0.4, 0.9]).tolist(), cal.link_iou
        ([0.0, 1.0], 0.2)
        """
        if min_link_iou is not None and not (is_number(min_link_iou) and min_link_iou > 0):
            # (0, a negative one or NaN left the links as they were, without a word)
            raise ValueError(f"min_link_iou must be an overlap > 0, or None; got "
                             f"{min_link_iou!r}")
        ious = [float(link_iou)]
        if min_link_iou is not None and min_link_iou < link_iou:
            # 0.1 lower each time (rounded: 0.3 - 0.1 - 0.1 falls short of 0.1), and the
            # least itself last where it falls between two steps (0.35: 0.25, 0.15, 0.1)
            while round(ious[-1] - 0.1, 10) >= min_link_iou:
                ious.append(round(ious[-1] - 0.1, 10))
            if ious[-1] > min_link_iou:
                ious.append(float(min_link_iou))
            frames = list(frames)  # gone over once for each overlap tried
        for iou in ious:
            s, p = _outcomes(frames, link_iou=iou, frame_rate=frame_rate,
                             chain_span=chain_span, chain_gap=chain_gap)
            cal = cls.fit(s, p, top=top, top_min=top_min, cap_sigma=cap_sigma)
            cal.link_iou = iou
            if cal.top_persistence >= TOP_PERSISTS:
                break
        return cal

    def __call__(self, scores: ArrayLike) -> np.ndarray:
        s = _scores(scores)
        # the last of the map's scores at or below each (side="right": at most len - 1)
        k = np.searchsorted(self.scores, s, side="right") - 1
        return self.confidence[np.maximum(k, 0)]

    def score_at(self, level: float) -> float:
        """The lowest of the map's scores whose confidence is at least ``level`` (``inf`` if
        none is); scores below the map's first take its first confidence, so a score lower
        than the one returned may map to ``level`` or more too.

        Parameters
        ----------
        level : float
            A confidence.

        Returns
        -------
        float
            The lowest of the map's scores with at least that confidence, or ``inf``.

        Raises
        ------
        ValueError
            If ``level`` is NaN.

        Examples
        --------
        >>> cal = ScoreCalibration([0.2, 0.5, 0.8], [0.0, 0.6, 1.0])
        >>> cal.score_at(0.5), cal.score_at(1.0), cal.score_at(1.5)
        (0.5, 0.8, inf)
        """
        if math.isnan(level):  # (no confidence is >= NaN: it said inf, "none reaches it")
            raise ValueError("level must be a confidence, not NaN")
        k = np.flatnonzero(self.confidence >= level)
        return float(self.scores[k[0]]) if len(k) else float("inf")

    @classmethod
    def ranks(cls, scores: ArrayLike) -> ScoreCalibration:
        """The map of each score to its rank among ``scores``: the fraction of them at or
        below it (their empirical distribution function; nothing fitted).

        Parameters
        ----------
        scores : (N,) array_like
            Scores (not NaN).

        Returns
        -------
        ScoreCalibration
            On the distinct scores, with ``n = 0``.

        Raises
        ------
        ValueError
            If there are no scores, or one is NaN.

        Examples
        --------
        >>> ScoreCalibration.ranks([0.1, 0.5, 0.5, 0.9]).confidence.tolist()
        [0.25, 0.75, 1.0]
        """
        r = np.sort(_scores(scores))
        if len(r) == 0:
            raise ValueError("no scores to rank")
        u = np.unique(r)
        return cls(u, np.searchsorted(r, u, side="right") / len(r))

    def blend(self, weight: float, ranked: np.ndarray) -> ScoreCalibration:
        """``weight`` × this map + (1 − ``weight``) × the empirical distribution function of
        ``ranked`` (scores), on the union of both's scores.

        Parameters
        ----------
        weight : float
            The weight of this map, in ``[0, 1]``.
        ranked : (R,) ndarray
            The scores whose ranks are the prior; at least one.

        Returns
        -------
        ScoreCalibration
            The blend, clipped to ``[0, 1]``, with this map's ``n``, ``top_persistence`` and
            ``link_iou``.

        Raises
        ------
        ValueError
            If ``weight`` is not in ``[0, 1]``, or ``ranked`` is empty or holds NaN.

        Examples
        --------
        >>> cal = ScoreCalibration([0.4, 0.9], [0.0, 1.0])
        >>> cal.blend(0.5, np.array([0.4, 0.9])).confidence.tolist()
        [0.25, 1.0]
        """
        weight = as_number(weight, "weight")  # (True was a weight of 1)
        if not 0 <= weight <= 1:  # (2 or -1 were clipped into a map, NaN too)
            raise ValueError(f"weight must be in [0, 1]; got {weight!r}")
        r = np.sort(_scores(ranked, "ranked"))
        if not len(r):  # (numpy's division by 0 warned, then the map was named)
            raise ValueError("ranked must hold at least one score")
        u = np.union1d(self.scores, r)
        cdf = np.searchsorted(r, u, side="right") / len(r)
        c = weight * self(u) + (1.0 - weight) * cdf
        return ScoreCalibration(u, np.clip(c, 0.0, 1.0), n=self.n,
                                top_persistence=self.top_persistence, link_iou=self.link_iou)

    def __repr__(self) -> str:
        return (f"ScoreCalibration({len(self.scores)} scores {self.scores[0]:.4g} .. "
                f"{self.scores[-1]:.4g}, fitted to {self.n} detections)")


class ScoreCalibrator:
    """Learns a :class:`ScoreCalibration` online, from the frames seen so far (see the
    module).

    Parameters
    ----------
    link_iou : float
        The IoU at which a detection continues one of the previous frame (or a chain).
    top : float
        The fraction of the outcomes, by score, whose rate is full confidence.
    top_min : int
        The least number of outcomes that rate is taken over.
    cap_sigma : float
        The bound on outcomes that contradict the detector's ranking, in standard errors
        (``inf``: none; :meth:`ScoreCalibration.fit`).
    prior : float
        How many outcomes weigh as much as the rank prior.
    window : int or None
        Keep the last ``window`` outcomes (None: all), so the map follows a scene that changes.
    frame_rate : float
        Frames a second, for the chains' times.
    chain_span, chain_gap : float
        Seconds: a chain that spans ``chain_span`` or more lasts, and a chain ends when
        ``chain_gap`` has gone by without a detection on it (at least one frame). With
        ``chain_span`` 0 there are no chains: frame-to-frame persistence alone.

    Call :meth:`observe` once a frame, then the calibrator itself on that frame's scores:
    ``calibrator(scores)`` is :meth:`calibration` applied to them.

    Raises
    ------
    ValueError
        If ``link_iou`` or ``top`` is not in ``(0, 1]``, ``prior``, ``chain_span`` or
        ``chain_gap`` is negative or not finite, ``frame_rate`` is not > 0 and finite,
        ``cap_sigma`` is not > 0, ``window`` is not an integer >= 1, or ``top_min`` is less
        than 1.

    Examples
    --------
    An object that stays (score 0.9) and clutter that jumps (0.4), at one frame a second,
    with chains that last over 2 s and end after 1 s without a detection. Until the third
    frame, the ranks of the scores seen. There, the second frame's detections are resolved
    frame to frame, the object's chain lasts (its three detections count), and the first
    clutter box's chain ends (it does not); in the fourth, one outcome frame to frame each,
    the object's new detection on its lasting chain, and the second clutter box's chain:

    >>> cal = ScoreCalibrator(frame_rate=1.0, chain_span=2.0, chain_gap=1.0)
    >>> for f in range(4):
    ...     boxes = np.array([[10.0, 10, 40, 80], [200 + 50 * f, 100, 230 + 50 * f, 160]])
    ...     cal.observe(Detections(boxes=boxes, scores=np.array([0.9, 0.4])))
    ...     print(cal.n, cal([0.4, 0.9]).tolist())
    0 [0.5, 1.0]
    0 [0.5, 1.0]
    6 [0.0, 1.0]
    10 [0.0, 1.0]
    """

    def __init__(self, *, link_iou: float = 0.3, top: float = 0.05, top_min: int = 20,
                 cap_sigma: float = 5.0, prior: float = 0.0, window: int | None = 20000,
                 frame_rate: float = 30.0, chain_span: float = 1.0, chain_gap: float = 0.2):
        # (True was taken as 1; text or None failed in a comparison, naming nothing)
        link_iou, top, cap_sigma, prior, frame_rate, chain_span, chain_gap = (
            as_number(v, name) for v, name in (
                (link_iou, "link_iou"), (top, "top"), (cap_sigma, "cap_sigma"),
                (prior, "prior"), (frame_rate, "frame_rate"), (chain_span, "chain_span"),
                (chain_gap, "chain_gap")))
        if not 0 < link_iou <= 1:
            raise ValueError(f"link_iou must be in (0, 1]; got {link_iou}")
        if not 0 < top <= 1:
            raise ValueError(f"top must be in (0, 1]; got {top}")
        if not cap_sigma > 0:
            raise ValueError(f"cap_sigma must be > 0; got {cap_sigma}")
        top_min = as_whole(top_min, "top_min", 1)  # (NaN: "cannot convert", 2.5 cut to 2)
        for name, v in (("prior", prior), ("chain_span", chain_span), ("chain_gap", chain_gap)):
            if not 0 <= v < np.inf:
                raise ValueError(f"{name} must be a finite number >= 0; got {v}")
        if not 0 < frame_rate < np.inf:
            raise ValueError(f"frame_rate must be > 0 and finite; got {frame_rate}")
        if window is not None and not is_whole(window, 1):
            raise ValueError(f"window must be an integer >= 1 or None; got {window!r}")
        self.link_iou, self.top, self.prior = float(link_iou), float(top), float(prior)
        self.window = None if window is None else int(window)  # it slices the store
        self.top_min, self.cap_sigma = int(top_min), float(cap_sigma)
        self.frame_rate, self.chain_span, self.chain_gap = float(frame_rate), \
            float(chain_span), float(chain_gap)
        # in frames: a chain lasts once its last frame is this far after its first, and takes
        # a detection up to this many frames after its last
        self._span = self.chain_span * self.frame_rate
        self.reset()

    def _gap_frames(self, step: int) -> int:
        """The chains' gap in frames, where this frame comes ``step`` frames after the one
        before: ``chain_gap`` rounded to a whole number of such steps, at least one (the
        previous frame's detections always continue a chain), so that a detector delivering
        every ``step``-th frame at ``step`` times the rate links as one delivering every frame
        at the rate; with ``step`` 1, ``chain_gap`` rounded to whole frames."""
        # (held within int64, which the compiled step takes: a gap of 1e300 s is for ever); a
        # half step rounded up, as coasting and the offline durations round (Python's round
        # took 2.5 steps to 2 and 7.5 to 8)
        steps = nearest_whole(min(self.chain_gap * self.frame_rate / step, 2.0**62 / step))
        return step * max(1, steps)

    def reset(self) -> None:
        """Forget everything seen.

        Examples
        --------
        >>> cal = ScoreCalibrator()
        >>> for f in range(3):
        ...     cal.observe(Detections(boxes=np.array([[10.0, 10, 40, 80]]), scores=[0.9]))
        >>> cal.n, (cal.reset(), cal.n)[1]
        (1, 0)
        """
        # the outcomes held are _store[:, _lo:_hi] (scores, outcomes), appended at _hi
        self._store, self._lo, self._hi = np.zeros((2, 1024)), 0, 0
        self._prev: tuple | None = None  # boxes, classes, scores, linked back, first frame
        self._new_since_fit = 0
        self._fit_n = -1
        self._cal: ScoreCalibration | None = None
        # before the first outcome: every score seen, ranked by the map (refreshed each frame)
        self._early: list[np.ndarray] = []
        self._frames, self._fit_frames = 0, -1
        # the chains: the next frame's time in frames (the last one's plus 1), the image's
        # shift summed over the frames, each chain's last box (``_head_*``: box, class, frame,
        # the summed shift then, chain), each chain's first frame and state (0 open, 1 lasted,
        # -1 ended short) by chain number (renumbered as chains are forgotten), and the
        # detections whose chain is still open (score, chain)
        self._t = 0
        self._shift = np.zeros(2)
        self._end_chains()

    def _end_chains(self) -> None:
        # no chain any more: nothing for the next detections to join (see reset)
        self._head_box, self._head_cls = np.zeros((0, 4)), np.zeros(0, np.int64)
        self._head_t, self._head_shift = np.zeros(0, np.int64), np.zeros((0, 2))
        self._head_chain = np.zeros(0, np.int64)
        self._first, self._state = np.zeros(0, np.int64), np.zeros(0, np.int8)
        self._open_s, self._open_chain = np.zeros(0), np.zeros(0, np.int64)

    @property
    def n(self) -> int:
        """How many outcomes are held (at most ``window``): two for a detection whose
        chain is resolved and whose next frame has been seen.

        Examples
        --------
        >>> cal = ScoreCalibrator(chain_span=0.0)
        >>> for f in range(4):
        ...     cal.observe(Detections(boxes=np.array([[10.0, 10, 40, 80]]), scores=[0.9]))
        >>> cal.n  # frames 2 and 3: the first and the last frame seen have no outcome yet
        2
        """
        return len(self._buf_s)

    def outcomes(self) -> tuple[np.ndarray, np.ndarray]:
        """The outcomes held, in the order they were resolved: ``(scores, outcomes)``, each
        outcome 0 or 1 (see the module).

        Returns
        -------
        scores, outcomes : (n,) ndarray
            Copies.

        Examples
        --------
        >>> cal = ScoreCalibrator(chain_span=0.0)
        >>> for f in range(3):
        ...     cal.observe(Detections(boxes=np.array([[10.0, 10, 40, 80]]), scores=[0.9]))
        >>> cal.outcomes()
        (array([0.9]), array([1.]))
        """
        return self._buf_s.copy(), self._buf_p.copy()

    def observe(self, detections: Detections | None, step: int = 1) -> None:
        """Take one frame's detections (None: the sequence has ended): link them to the
        previous frame's, which are then resolved, and to the chains.

        Parameters
        ----------
        detections : Detections or None
            The frame's detections, with boxes (none: a frame where nothing was found, whose
            next frame's detections then continue nothing); None after the last frame (its
            detections then get no frame-to-frame outcome, having no next frame, and chains
            still open none; the detections of frames observed after it join none of this
            sequence's chains, as in a sequence of their own).
        step : int
            Frames since the frame observed before (1: the next one; more where frame
            numbers were left out, as :meth:`BoxTracker.step
            <vistrack.tracking.BoxTracker.step>` is given them): the chains' span and gap
            are times, so they count the frames, not the calls. The frame-to-frame links
            still run from the frame observed before, and a chain always takes a detection
            of that frame, however long the step.

        Raises
        ------
        TypeError
            If the detections have no boxes.
        ValueError
            If a score is NaN, a box lies beyond ±2^52 pixels, or ``step`` is not an integer
            >= 1.

        Examples
        --------
        >>> cal = ScoreCalibrator(chain_span=0.0)
        >>> for f in range(3):
        ...     cal.observe(Detections(boxes=np.array([[10.0, 10, 40, 80]]), scores=[0.9]))
        >>> cal.n
        1
        """
        if detections is None:
            # the last frame's detections get no frame-to-frame outcome (no next frame), and
            # chains still open none: a sequence observed after this starts on its own, its
            # detections continuing no chain of this one
            self._prev = None
            self._end_chains()
            return
        if detections.boxes is None:
            raise TypeError("detections must have boxes")
        if not is_whole(step, 1):  # (not a boolean either)
            raise ValueError(f"step must be an integer >= 1 (frames); got {step!r}")
        step = int(step)
        # copies: the frame is kept past this call (the previous frame, the first frames'
        # scores), and a detector that refills one buffer every frame would otherwise change
        # it under us (each box then continued itself, and clutter persisted)
        boxes = np.array(detections.boxes, dtype=np.float64, order="C")
        # (areas past the float range made every overlap NaN: nothing persisted, and the
        # calibration took every score as confident; BoxTracker.step refuses them too)
        check_in_pixels(boxes, "detection boxes")
        cls = np.array(detections.classes, order="C")
        s = _scores(detections.scores).copy()  # type: ignore[arg-type]  # set by __post_init__
        # the previous frame: its boxes, classes, scores, which of them continued one of the
        # frame before it, and whether it was the first (none, at the first frame: no links)
        if self._prev is None:
            pb, pc, ps, pl, prev_first = np.zeros((0, 4)), cls[:0], s[:0], np.zeros(0, bool), True
        else:
            pb, pc, ps, pl, prev_first = self._prev
        chains = self.chain_span > 0
        if _QUIET and not len(s) and not len(pb) and self._prev is not None and not (
                len(self._head_box) or len(self._open_s)):
            # a frame without detections after another, no chain open: nothing to link,
            # resolve or end (the chains' table, every chain in it ended, is as the step
            # before left it), only the time goes on (a detector of many classes shows each
            # class's calibration every frame, most of them holding none of it)
            if chains:
                self._t += step
            self._prev = (boxes, cls, s, np.zeros(0, bool), False)
            self._frames += 1
            if self._hi > self._lo:
                self._early = []
            return
        (linked_fwd, linked_back, self._shift, self._head_box, self._head_cls, self._head_t,
         self._head_shift, self._head_chain, self._first, self._state, self._open_s,
         self._open_chain, out_s, out_p) = _observe(
            pb, pc, boxes, cls, s, self.link_iou, self._shift, chains, self._t + step - 1,
            self._gap_frames(step), step, self._span, self._head_box, self._head_cls,
            self._head_t, self._head_shift, self._head_chain, self._first, self._state,
            self._open_s, self._open_chain)
        if not prev_first:
            # the previous frame's detections persist if linked both ways (the first frame's
            # have no frame before them, the last frame's none after: no outcome)
            self._push(ps, (pl & linked_fwd).astype(np.float64))
        if chains:
            self._t += step
            self._push(out_s, out_p)
        # a frame without detections is one where nothing was found, at the start as
        # anywhere: the detections of the next continue nothing, and do not persist (only
        # the very first frame's, with nothing seen before them, get no outcome; taking the
        # first frame with detections as the first instead is in docs/mot.md, What was tried)
        self._prev = (boxes, cls, s, linked_back, self._prev is None)
        self._frames += 1
        if self._hi > self._lo:
            self._early = []
        elif len(s):
            self._early.append(s)

    @property
    def _buf_s(self) -> np.ndarray:
        return self._store[0, self._lo:self._hi]

    @property
    def _buf_p(self) -> np.ndarray:
        return self._store[1, self._lo:self._hi]

    def _push(self, s: np.ndarray, p: np.ndarray) -> None:
        """Append outcomes, keeping the last ``window``: into the store's free end, which is
        made by moving the outcomes kept to its front (growing it where they do not fit
        twice), so that each outcome is copied a bounded number of times on average."""
        n = len(s)
        if n == 0:
            return
        if self._hi + n > self._store.shape[1]:
            held = self._hi - self._lo
            keep = held if self.window is None else min(held, max(self.window - n, 0))
            store = self._store
            if 2 * (keep + n) > store.shape[1]:
                store = np.empty((2, 2 * (keep + n)))
            store[:, :keep] = self._store[:, self._hi - keep:self._hi]
            self._store, self._lo, self._hi = store, 0, keep
        self._store[0, self._hi:self._hi + n] = s
        self._store[1, self._hi:self._hi + n] = p
        self._hi += n
        if self.window is not None and self._hi - self._lo > self.window:
            self._lo = self._hi - self.window
        self._new_since_fit += n

    def calibration(self) -> ScoreCalibration:
        """The map learnt so far: refitted when the outcomes held have grown by a tenth (or
        by ``window / 10``) since the last fit, blended with the rank prior.

        Before any outcome, the ranks of the scores seen (:meth:`ScoreCalibration.ranks`);
        with nothing seen, confidence 1 for every score.

        Returns
        -------
        ScoreCalibration
            The map.

        Examples
        --------
        >>> ScoreCalibrator().calibration()([0.1, 5.0]).tolist()
        [1.0, 1.0]
        """
        pending = self._prev[2] if self._prev is not None else np.zeros(0)
        n = self.n
        stale = (self._cal is None or self._new_since_fit >= max(1, 0.1 * max(self._fit_n, 1))
                 or (self._fit_n < self.prior and len(pending))
                 or (n == 0 and self._frames != self._fit_frames))
        if not stale:
            assert self._cal is not None  # stale when nothing was fitted yet
            return self._cal
        ranked = np.concatenate([self._buf_s, pending] if n else [np.zeros(0), *self._early])
        if len(ranked) == 0:
            return ScoreCalibration([0.0], [1.0])  # nothing seen: nothing to tell apart
        w = n / (n + self.prior) if n + self.prior > 0 else 1.0
        if n:
            cal = ScoreCalibration.fit(self._buf_s, self._buf_p, top=self.top,
                                       top_min=self.top_min, cap_sigma=self.cap_sigma)
            cal = cal.blend(w, ranked) if w < 1 else cal
        else:
            cal = ScoreCalibration.ranks(ranked)
        self._cal, self._fit_n, self._new_since_fit = cal, n, 0
        self._fit_frames = self._frames
        return cal

    def __call__(self, scores: ArrayLike) -> np.ndarray:
        return self.calibration()(scores)

r"""Assignment of detections to tracks, chosen by name from :data:`ASSIGNERS`.

Every assigner takes a cost matrix ``(T, D)`` and a boolean gate of allowed pairs of the same
shape, and returns ``(rows, cols)``: the pairs assigned, each track and each detection at most
once (except ``"nn"``).

- ``"gnn"``: global nearest neighbour, the assignment of the most pairs, and among those the
  least total cost (scipy's ``linear_sum_assignment``, Crouse 2016). The gated graph is split
  into connected components first and each is solved on its own: the same answer, at the cost
  of the components' sizes rather than the whole problem's (10,000 objects stay cheap);
- ``"greedy"``: pairs in order of increasing cost, each taken if both ends are free;
- ``"nn"``: each track takes its nearest allowed detection (the seeds' nearest neighbour); two
  tracks may take the same detection.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["ASSIGNERS", "assign", "gnn", "greedy", "nearest_neighbour", "components"]

_EMPTY = (np.zeros(0, np.int64), np.zeros(0, np.int64))


def _check(cost: np.ndarray, gate: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    cost = np.asarray(cost, dtype=float)
    if cost.ndim != 2:
        raise ValueError(f"cost must be 2-D (tracks, detections); got shape {cost.shape}")
    gate = np.isfinite(cost) if gate is None else np.asarray(gate, dtype=bool) & np.isfinite(cost)
    if gate.shape != cost.shape:
        raise ValueError(f"gate must have the shape of cost {cost.shape}; got {gate.shape}")
    return cost, gate


def components(gate: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    """Connected components of the bipartite graph of allowed pairs: ``(k, track_label (T,),
    detection_label (D,))``; unconnected tracks and detections get labels of their own."""
    T, D = gate.shape
    r, c = np.nonzero(gate)
    g = coo_matrix((np.ones(len(r)), (r, T + c)), shape=(T + D, T + D))
    k, labels = connected_components(g, directed=False)
    return k, labels[:T], labels[T:]


def _lsa(cost: np.ndarray, gate: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # a disallowed pair costs more than any set of allowed ones, so the solution has the
    # most allowed pairs and, among those, the least cost
    span = float(np.ptp(cost[gate])) if gate.any() else 0.0
    big = (span + 1.0) * (min(cost.shape) + 1) + float(np.abs(cost[gate]).max(initial=0.0))
    c = np.where(gate, cost, big)
    r, k = linear_sum_assignment(c)
    ok = gate[r, k]
    return r[ok], k[ok]


def gnn(cost: np.ndarray, gate: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Global nearest neighbour by connected components (see the module)."""
    cost, gate = _check(cost, gate)
    if not gate.any():
        return _EMPTY
    r_all, c_all = np.nonzero(gate)
    if len(r_all) == gate.shape[0] * gate.shape[1] or min(gate.shape) <= 2:
        return _lsa(cost, gate)
    k, lt, ld = components(gate)
    order_t, order_d = np.argsort(lt, kind="stable"), np.argsort(ld, kind="stable")
    st = np.searchsorted(lt[order_t], np.arange(k + 1))
    sd = np.searchsorted(ld[order_d], np.arange(k + 1))
    rows, cols = [], []
    for j in np.unique(lt[r_all]):
        ti, di = order_t[st[j]:st[j + 1]], order_d[sd[j]:sd[j + 1]]
        if len(ti) == 1 or len(di) == 1:  # one side alone: its cheapest allowed partner
            sub = np.where(gate[np.ix_(ti, di)], cost[np.ix_(ti, di)], np.inf)
            a = np.unravel_index(np.argmin(sub), sub.shape)
            rows.append(ti[a[0]:a[0] + 1])
            cols.append(di[a[1]:a[1] + 1])
            continue
        r, c = _lsa(cost[np.ix_(ti, di)], gate[np.ix_(ti, di)])
        rows.append(ti[r])
        cols.append(di[c])
    return np.concatenate(rows).astype(np.int64), np.concatenate(cols).astype(np.int64)


def greedy(cost: np.ndarray, gate: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Pairs by increasing cost, each taken when both ends are still free."""
    cost, gate = _check(cost, gate)
    r, c = np.nonzero(gate)
    order = np.argsort(cost[r, c], kind="stable")
    used_t, used_d = np.zeros(cost.shape[0], bool), np.zeros(cost.shape[1], bool)
    rows, cols = [], []
    for i in order:
        a, b = r[i], c[i]
        if not used_t[a] and not used_d[b]:
            used_t[a] = used_d[b] = True
            rows.append(a)
            cols.append(b)
    return np.array(rows, np.int64), np.array(cols, np.int64)


def nearest_neighbour(cost: np.ndarray,
                      gate: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each track's cheapest allowed detection (detections may be shared)."""
    cost, gate = _check(cost, gate)
    if cost.shape[1] == 0:
        return _EMPTY
    c = np.where(gate, cost, np.inf)
    best = np.argmin(c, axis=1)
    rows = np.flatnonzero(np.isfinite(c[np.arange(len(c)), best]))
    return rows.astype(np.int64), best[rows].astype(np.int64)


ASSIGNERS: dict[str, Callable] = {"gnn": gnn, "greedy": greedy, "nn": nearest_neighbour}
"""Assigners by name: ``f(cost (T, D), gate (T, D)) -> (rows, cols)``."""


def assign(cost: np.ndarray, gate: np.ndarray | None = None,
           method: str = "gnn") -> tuple[np.ndarray, np.ndarray]:
    """Assign by ``method``, a name in :data:`ASSIGNERS`.

    Examples
    --------
    >>> cost = np.array([[1.0, 2.0], [1.5, 9.0]])
    >>> [a.tolist() for a in assign(cost)]          # 2 + 1.5 beats 1 + 9
    [[0, 1], [1, 0]]
    >>> [a.tolist() for a in assign(cost, method="greedy")]
    [[0, 1], [0, 1]]
    """
    if method not in ASSIGNERS:
        raise ValueError(f"method must be one of {sorted(ASSIGNERS)}; got {method!r}")
    return ASSIGNERS[method](cost, gate)

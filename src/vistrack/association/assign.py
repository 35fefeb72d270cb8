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
from numba import njit

__all__ = ["ASSIGNERS", "assign", "gnn", "gnn_sparse", "greedy", "nearest_neighbour", "components"]

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
    r, c = np.nonzero(gate)
    return gnn_sparse(r, c, cost[r, c], cost.shape)


@njit(cache=True)
def _local_indices(rr, rc, starts, ends, T, D):
    # for pairs grouped by component: each pair's row and column index within its component,
    # and each component's numbers of rows and columns
    rmap, cmap = np.full(T, -1), np.full(D, -1)
    ir, ic = np.empty(rr.shape[0], np.int64), np.empty(rr.shape[0], np.int64)
    nr, nc = np.zeros(starts.shape[0], np.int64), np.zeros(starts.shape[0], np.int64)
    for k in range(starts.shape[0]):
        for p in range(starts[k], ends[k]):
            if rmap[rr[p]] < 0:
                rmap[rr[p]] = nr[k]
                nr[k] += 1
            if cmap[rc[p]] < 0:
                cmap[rc[p]] = nc[k]
                nc[k] += 1
            ir[p], ic[p] = rmap[rr[p]], cmap[rc[p]]
        for p in range(starts[k], ends[k]):
            rmap[rr[p]], cmap[rc[p]] = -1, -1
    return ir, ic, nr, nc


def _solve_groups(rr: np.ndarray, rc: np.ndarray, cc: np.ndarray, starts: np.ndarray,
                  ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One dense assignment per group of pairs ``starts[k]:ends[k]`` (over that group's tracks
    and detections)."""
    ir, ic, nr, nc = _local_indices(rr, rc, starts, ends, int(rr.max()) + 1, int(rc.max()) + 1)
    out_r, out_c = [], []
    for k in range(len(starts)):
        a, b = starts[k], ends[k]
        cost = np.zeros((nr[k], nc[k]))
        gate = np.zeros((nr[k], nc[k]), bool)
        cost[ir[a:b], ic[a:b]], gate[ir[a:b], ic[a:b]] = cc[a:b], True
        r, c = _lsa(cost, gate)
        ur, uc = np.empty(nr[k], np.int64), np.empty(nc[k], np.int64)
        ur[ir[a:b]], uc[ic[a:b]] = rr[a:b], rc[a:b]
        out_r.append(ur[r])
        out_c.append(uc[c])
    return np.concatenate(out_r), np.concatenate(out_c)


@njit(cache=True)
def _pair_components(rows, cols, T):
    # union-find over tracks 0..T-1 and detections T..: the component of each pair
    parent = np.arange(T + (cols.max() + 1 if cols.shape[0] else 0))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for k in range(rows.shape[0]):
        a, b = find(rows[k]), find(T + cols[k])
        if a != b:
            parent[max(a, b)] = min(a, b)
    out = np.empty(rows.shape[0], np.int64)
    for k in range(rows.shape[0]):
        out[k] = find(rows[k])
    return out


def gnn_sparse(rows: np.ndarray, cols: np.ndarray, cost: np.ndarray,
               shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """:func:`gnn` on the allowed pairs only (``rows``, ``cols`` and their ``cost``), for
    problems too large for a dense matrix: the same answer as ``gnn`` on the dense problem.

    Examples
    --------
    >>> r, c = gnn_sparse(np.array([0, 0, 1]), np.array([0, 1, 0]), np.array([1.0, 2.0, 1.5]),
    ...                   (2, 2))
    >>> r.tolist(), c.tolist()
    ([0, 1], [1, 0])
    """
    rows, cols = np.asarray(rows, np.int64), np.asarray(cols, np.int64)
    cost = np.asarray(cost, dtype=float)
    T, D = shape
    if len(rows) == 0:
        return _EMPTY
    row_deg = np.bincount(rows, minlength=T)
    col_deg = np.bincount(cols, minlength=D)
    alone = (row_deg[rows] == 1) & (col_deg[cols] == 1)
    out_r, out_c = [rows[alone]], [cols[alone]]
    rest = ~alone
    if rest.any():
        rr, rc, cc = rows[rest], cols[rest], cost[rest]
        if len(rr) <= 256:  # small: one assignment over every component at once
            starts, ends = np.zeros(1, np.int64), np.full(1, len(rr))
        else:  # one per connected component
            lab = _pair_components(rr, rc, T)
            order = np.argsort(lab, kind="stable")
            rr, rc, cc, lab = rr[order], rc[order], cc[order], lab[order]
            edges = np.flatnonzero(np.diff(lab)) + 1
            starts, ends = np.r_[0, edges], np.r_[edges, len(lab)]
        r, c = _solve_groups(rr, rc, cc, starts, ends)
        out_r.append(r)
        out_c.append(c)
    return np.concatenate(out_r).astype(np.int64), np.concatenate(out_c).astype(np.int64)


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

r"""Assignment of detections to tracks, chosen by name from :data:`ASSIGNERS`.

Every assigner takes a cost matrix ``(T, D)`` and a boolean gate of allowed pairs of the same
shape, and returns ``(rows, cols)``: the pairs assigned, each track and each detection at most
once (except ``"nn"``).

- ``"gnn"``: global nearest neighbour, the assignment of the most pairs, and among those the
  least total cost (Crouse's shortest augmenting path, 2016, the algorithm of scipy's
  ``linear_sum_assignment``, compiled as :func:`lsa`). The gated graph is split into connected
  components first and each is solved on its own: the same answer, at the cost of the
  components' sizes rather than the whole problem's (10,000 objects stay cheap). With a
  ``limit`` (:func:`gnn`, :func:`gnn_sparse`), leaving a track and a detection unassigned
  costs ``limit``, so a pair is assigned only where that lowers the total: in a crowd, two
  poor pairs no longer outweigh one good one (what ByteTrack's ``lapjv(..., cost_limit)``
  does);
- ``"greedy"``: pairs in order of increasing cost, each taken if both ends are free;
- ``"nn"``: each track takes its nearest allowed detection (the seeds' nearest neighbour); two
  tracks may take the same detection.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._jit import njit
from .._prebuilt import kernel
from .._registry import Registry
from .._validate import as_float_array, is_real, is_whole

__all__ = ["ASSIGNERS", "assign", "gnn", "gnn_pairs", "gnn_pairs_limited", "gnn_sparse",
           "greedy", "greedy_pairs", "lsa", "lsa_kernel", "nearest_neighbour", "nearest_pairs",
           "components"]

_EMPTY = (np.zeros(0, np.int64), np.zeros(0, np.int64))


def _check(cost: np.ndarray, gate: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    # (complex costs lost their imaginary parts; True and False were costs 1 and 0)
    cost = as_float_array(cost, "cost", not_boolean="numbers")
    if cost.ndim != 2:
        raise ValueError(f"cost must be 2-D (tracks, detections); got shape {cost.shape}")
    if gate is None:
        return cost, np.isfinite(cost)
    gate = _as_mask(gate)
    if gate.shape != cost.shape:  # before combining: (1, D) would broadcast without a word
        raise ValueError(f"gate must have the shape of cost {cost.shape}; got {gate.shape}")
    return cost, gate & np.isfinite(cost)


def _as_mask(gate: ArrayLike) -> np.ndarray:
    """``gate`` as booleans, each entry True/False or 1/0 (a NaN or 0.2 was cast to True: a
    pair allowed that was meant not to be)."""
    given = np.asarray(gate)
    if given.dtype != bool:
        flat = given.reshape(-1)
        try:
            odd = np.flatnonzero((flat != 0) & (flat != 1))
        except TypeError:
            odd = np.zeros(1, np.int64)
        if odd.size:
            at = tuple(int(v) for v in np.unravel_index(odd[0], given.shape))
            v = flat[odd[0]]  # (None has no .item(): an AttributeError from this check)
            raise ValueError(f"gate must be True/False (or 1/0) for each pair; gate"
                             f"{list(at)} is {v.item() if hasattr(v, 'item') else v!r}")
    return given.astype(bool)


def _check_limit(limit: float | None) -> None:
    """A ValueError unless ``limit`` (:func:`gnn`'s, :func:`gnn_sparse`'s) is None or a finite
    number."""
    if limit is not None and not (is_real(limit) and np.isfinite(float(limit))):
        raise ValueError(f"limit must be a finite number or None; got {limit!r}")


def components(gate: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    """Connected components of the bipartite graph of allowed track-detection pairs.

    Parameters
    ----------
    gate : (T, D) array_like of bool
        The allowed pairs: the edges of the graph.

    Returns
    -------
    k : int
        Number of components.
    track_label : (T,) ndarray of int
        Component of each track, in ``0 .. k-1``.
    detection_label : (D,) ndarray of int
        Component of each detection; unconnected tracks and detections get labels of their
        own.

    Examples
    --------
    >>> gate = np.array([[True, False, False], [True, False, False], [False, False, True]])
    >>> k, tl, dl = components(gate)
    >>> k, tl.tolist(), dl.tolist()     # {t0, t1, d0}, {t2, d2}, {d1}
    (3, [0, 0, 1], [0, 2, 1])
    """
    gate = _as_mask(gate)  # array_like, as documented (a list had no shape; NaN was True)
    if gate.ndim != 2:
        raise ValueError(f"gate must be a 2-D mask, tracks by detections; got shape "
                         f"{gate.shape}")
    T, D = gate.shape
    r, c = np.nonzero(gate)
    c = c + T  # the graph's nodes: tracks 0..T-1, detections T..T+D-1
    # each node labelled by the least node it reaches, spread along the edges (and each label
    # replaced by its own label, which halves the paths): a few rounds of numpy's in a
    # frame of scattered clusters, three to four times faster than scipy's graph, which
    # a long chain of clusters is left to
    label = np.arange(T + D)
    for _ in range(8):
        least = np.minimum(label[r], label[c])
        new = label.copy()
        np.minimum.at(new, r, least)
        np.minimum.at(new, c, least)
        new = new[new]
        if (new == label).all():
            # the least node of each component, in order: scipy's labels (each component
            # numbered in the order of its first node)
            roots, labels = np.unique(label, return_inverse=True)
            return len(roots), labels[:T], labels[T:]
        label = new
    # scipy.sparse here, not at the top: importing it takes 0.25-0.4 s, which the box
    # trackers (their own union-find, compiled) and vistrack track do not need
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    g = coo_matrix((np.ones(len(r)), (r, c)), shape=(T + D, T + D))
    k, labels = connected_components(g, directed=False)
    return k, labels[:T], labels[T:]


def gnn(cost: np.ndarray, gate: np.ndarray | None = None,
        limit: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    r"""Global nearest neighbour: the most allowed pairs, and among those the least cost; or,
    with a ``limit``, the pairs of least total cost counting ``limit`` for each track and
    detection left unassigned together.

    Without ``limit``: over the matchings ``A`` of allowed pairs (each track and each
    detection at most once) of the largest size, the one that minimises

    .. math:: \sum_{(i, j) \in A} c_{ij}.

    With ``limit`` :math:`L`: over all matchings of allowed pairs with :math:`c_{ij} < L`, the
    one that minimises

    .. math:: \sum_{(i, j) \in A} (c_{ij} - L),

    the cost of the assignment when each unassigned track and each unassigned detection costs
    :math:`L / 2` (the extended matrix of ByteTrack's ``lapjv(..., cost_limit=L)``). An
    assignment may then leave a track and a detection that could be paired unpaired: where
    one good pair competes with two poor ones (a person missed next to a person detected),
    the most pairs would take the two poor ones and pass identities between neighbours.

    The gated graph is split into connected components (:func:`components`), each solved
    by :func:`lsa`; pairs whose track and detection have no other candidate are taken at
    once.

    Parameters
    ----------
    cost : (T, D) array_like
        Cost of each pair; non-finite costs are never assigned.
    gate : (T, D) array_like of bool, optional
        The allowed pairs; default every pair of finite cost.
    limit : float, optional
        The cost of leaving a track and a detection unassigned; pairs costing ``limit`` or
        more are never assigned. Default: none, the most pairs are assigned.

    Returns
    -------
    rows, cols : (K,) ndarray of int64
        The assigned pairs ``(rows[k], cols[k])``.

    Raises
    ------
    ValueError
        If ``cost`` is not 2-D, ``gate`` does not have its shape or holds values other than
        True/False (1/0), or ``limit`` is given and not a finite number.

    See Also
    --------
    gnn_sparse : The same on a list of allowed pairs.

    References
    ----------
    .. [1] D. F. Crouse, "On implementing 2D rectangular assignment algorithms", *IEEE
       Transactions on Aerospace and Electronic Systems* 52(4), 2016.

    Examples
    --------
    >>> cost = np.array([[1.0, 2.0], [1.5, 9.0]])
    >>> [a.tolist() for a in gnn(cost)]           # 2 + 1.5 beats 1 + 9
    [[0, 1], [1, 0]]
    >>> [a.tolist() for a in gnn(cost, gate=[[True, False], [True, False]])]
    [[0], [0]]
    >>> crowd = np.array([[0.2, 0.7], [0.7, 9.0]])  # one good pair, or two poor ones
    >>> [a.tolist() for a in gnn(crowd)], [a.tolist() for a in gnn(crowd, limit=0.8)]
    ([[0, 1], [1, 0]], [[0], [0]])
    """
    cost, gate = _check(cost, gate)
    _check_limit(limit)
    r, c = np.nonzero(gate)  # (each pair once, finite, in range: gnn_sparse's checks)
    T, D = cost.shape
    return _gnn_sparse(r, c, cost[r, c], T, D, limit=limit)


def lsa(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The least-cost assignment of a dense cost matrix, compiled.

    Crouse's shortest augmenting path (2016), the algorithm of scipy's
    ``linear_sum_assignment``, step for step (ties are broken the same way), checked; other
    compiled kernels call :func:`lsa_kernel`, the same without the checks.

    Parameters
    ----------
    cost : (n, m) array_like
        Costs; ``+inf`` forbids a pair.

    Returns
    -------
    rows, cols : (min(n, m),) ndarray of int64
        The assigned pairs, sorted by row.

    Raises
    ------
    ValueError
        If ``cost`` is not 2-D, holds NaN or ``-inf`` (naming the first such entry), or the
        problem is infeasible: no ``min(n, m)`` pairs of finite cost (as scipy says).

    References
    ----------
    .. [1] D. F. Crouse, "On implementing 2D rectangular assignment algorithms", *IEEE
       Transactions on Aerospace and Electronic Systems* 52(4), 2016.

    Examples
    --------
    >>> r, c = lsa(np.array([[4.0, 1.0, 3.0], [2.0, 0.0, 5.0]]))
    >>> r.tolist(), c.tolist()
    ([0, 1], [1, 0])
    """
    # (complex costs lost their imaginary parts; True and False were costs 1 and 0)
    arr = as_float_array(cost, "cost", not_boolean="numbers")
    if arr.ndim != 2:
        raise ValueError(f"cost must be a 2-D matrix; got shape {arr.shape}")
    arr = np.ascontiguousarray(arr)
    bad = np.isnan(arr) | (arr == -np.inf)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise ValueError(f"cost[{i}, {j}] is {arr[i, j]}: costs must be numbers or +inf (a "
                         "pair not allowed)")
    return lsa_kernel(arr)


@njit(cache=True)
def lsa_kernel(cost):
    """:func:`lsa` compiled, for other kernels: ``cost`` a float64 matrix without NaN or
    ``-inf``, not checked.

    Examples
    --------
    >>> r, c = lsa_kernel(np.array([[4.0, 1.0, 3.0], [2.0, 0.0, 5.0]]))
    >>> r.tolist(), c.tolist()
    ([0, 1], [1, 0])
    """
    transpose = cost.shape[0] > cost.shape[1]
    c = cost.T.copy() if transpose else cost
    nr, nc = c.shape
    u, v = np.zeros(nr), np.zeros(nc)
    spc = np.empty(nc)
    path = np.full(nc, -1)
    col4row, row4col = np.full(nr, -1), np.full(nc, -1)
    SR, SC = np.zeros(nr, np.bool_), np.zeros(nc, np.bool_)
    remaining = np.empty(nc, np.int64)
    for cur in range(nr):
        # Dijkstra from row `cur` over reduced costs, to the nearest unassigned column
        min_val = 0.0
        for it in range(nc):
            remaining[it] = nc - it - 1
        n_rem = nc
        SR[:], SC[:] = False, False
        spc[:] = np.inf
        sink, i = -1, cur
        while sink == -1:
            index, lowest = -1, np.inf
            SR[i] = True
            for it in range(n_rem):
                j = remaining[it]
                r = min_val + c[i, j] - u[i] - v[j]
                if r < spc[j]:
                    path[j] = i
                    spc[j] = r
                if spc[j] < lowest or (spc[j] == lowest and row4col[j] == -1):
                    lowest = spc[j]
                    index = it
            min_val = lowest
            if min_val == np.inf:  # only with infinite costs, which callers never pass
                raise ValueError("cost matrix is infeasible")
            j = remaining[index]
            if row4col[j] == -1:
                sink = j
            else:
                i = row4col[j]
            SC[j] = True
            n_rem -= 1
            remaining[index] = remaining[n_rem]
        # update the dual variables and augment along the path
        u[cur] += min_val
        for i in range(nr):
            if SR[i] and i != cur:
                u[i] += min_val - spc[col4row[i]]
        for j in range(nc):
            if SC[j]:
                v[j] -= min_val - spc[j]
        j = sink
        while True:
            i = path[j]
            row4col[j] = i
            col4row[i], j = j, col4row[i]
            if i == cur:
                break
    if transpose:
        order = np.argsort(col4row)
        return col4row[order], order.astype(np.int64)
    return np.arange(nr), col4row


@njit(cache=True)
def _gated_lsa(cost, gate):
    # a disallowed pair costs more than any set of allowed ones, so the solution has the
    # most allowed pairs and, among those, the least cost
    lo, hi, top, any_ok = np.inf, -np.inf, 0.0, False
    for i in range(cost.shape[0]):
        for j in range(cost.shape[1]):
            if gate[i, j]:
                any_ok = True
                lo, hi = min(lo, cost[i, j]), max(hi, cost[i, j])
                top = max(top, abs(cost[i, j]))
    if not any_ok:
        return np.empty(0, np.int64), np.empty(0, np.int64)
    size = min(cost.shape[0], cost.shape[1]) + 1
    big = (hi - lo + 1.0) * size + top
    if not np.isfinite((big + top) * size * 2.0) or 0.0 < top < 2.0 ** -30:
        # costs near the largest float: the same problem scaled into [-1, 1] (the penalty
        # overflowed to inf, and a component with a disallowed pair was called infeasible;
        # or, of costs close together, the solver's sums of a few did: fewer pairs, or a
        # worse total, than the problem scaled down has); and costs far below the penalty's
        # 1 (1e-16 and less: the solver's sums beside it lost their differences, and took a
        # worse total)
        cost = cost / top
        big = 3.0 * size + 1.0
    c = np.where(gate, cost, big)
    r, k = lsa_kernel(c)
    n = 0
    for p in range(r.shape[0]):
        if gate[r[p], k[p]]:
            r[n], k[n] = r[p], k[p]
            n += 1
    return r[:n], k[:n]


@njit(cache=True)
def _limited_lsa(cost, gate):
    # costs relative to leaving the pair unassigned: a disallowed pair costs 0, as much as
    # leaving it, so the least-cost full assignment takes the allowed pairs of least total
    # (negative) cost, and the pairs that gain nothing are dropped
    top = 0.0
    for i in range(cost.shape[0]):
        for j in range(cost.shape[1]):
            if gate[i, j]:
                top = max(top, abs(cost[i, j]))
    c = np.where(gate, cost, 0.0)
    if not np.isfinite((top + 1.0) * (min(cost.shape[0], cost.shape[1]) + 1) * 2.0):
        # costs near the largest float: the same problem scaled into [-1, 0] (as
        # _gated_lsa's; the solver's sums overflowed to -inf, and it paired wrongly); a
        # gain too small to survive the scaling kept below 0, the least gain there is (it
        # became 0, as much as leaving the pair, and a pair nothing contested was dropped)
        c = c / top
        for i in range(cost.shape[0]):
            for j in range(cost.shape[1]):
                if gate[i, j] and cost[i, j] < 0.0 and c[i, j] == 0.0:
                    c[i, j] = -5e-324
    r, k = lsa_kernel(c)
    n = 0
    for p in range(r.shape[0]):
        if gate[r[p], k[p]] and cost[r[p], k[p]] < 0.0:
            r[n], k[n] = r[p], k[p]
            n += 1
    return r[:n], k[:n]


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


@njit(cache=True)
def gnn_pairs(rows, cols, cost, T, D):
    """The compiled core of :func:`gnn_sparse`, for arguments already checked.

    Pairs whose track and detection have no other candidate are taken at once; the others are
    split into connected components, each solved by :func:`lsa`.

    Parameters
    ----------
    rows, cols : (P,) ndarray of int64
        The allowed pairs, tracks in ``0 .. T-1`` and detections in ``0 .. D-1``.
    cost : (P,) ndarray of float64
        Their finite costs.
    T, D : int
        Numbers of tracks and detections.

    Returns
    -------
    rows, cols : (K,) ndarray of int64
        The assigned pairs.

    Examples
    --------
    >>> r, c = gnn_pairs(np.array([0, 0, 1]), np.array([0, 1, 0]), np.array([1.0, 2.0, 1.5]),
    ...                  2, 2)
    >>> r.tolist(), c.tolist()
    ([0, 1], [1, 0])
    """
    return _gnn_pairs(rows, cols, cost, T, D, False)


@njit(cache=True)
def gnn_pairs_limited(rows, cols, cost, T, D):
    """The compiled core of :func:`gnn_sparse` with a ``limit``, for arguments already checked:
    ``cost`` is each pair's cost minus the limit; of the pairs of negative cost, those of
    least total cost are taken (see :func:`gnn`).

    Examples
    --------
    >>> r, c = gnn_pairs_limited(np.array([0, 0, 1]), np.array([0, 1, 0]),
    ...                          np.array([-0.6, -0.1, -0.1]), 2, 2)
    >>> r.tolist(), c.tolist()
    ([0], [0])
    """
    return _gnn_pairs(rows, cols, cost, T, D, True)


@njit(cache=True)
def _gnn_pairs(rows, cols, cost, T, D, limited):
    # gnn_pairs, or with limited gnn_pairs_limited
    if limited:  # a pair that gains nothing is as good as none
        worth = cost < 0.0
        if not worth.all():
            rows, cols, cost = rows[worth], cols[worth], cost[worth]
    n = rows.shape[0]
    out_r, out_c = np.empty(n, np.int64), np.empty(n, np.int64)
    if n == 0:
        return out_r, out_c
    row_deg, col_deg = np.zeros(T, np.int64), np.zeros(D, np.int64)
    for p in range(n):
        row_deg[rows[p]] += 1
        col_deg[cols[p]] += 1
    m, rest = 0, np.empty(n, np.int64)
    n_rest = 0
    for p in range(n):
        if row_deg[rows[p]] == 1 and col_deg[cols[p]] == 1:
            out_r[m], out_c[m] = rows[p], cols[p]
            m += 1
        else:
            rest[n_rest] = p
            n_rest += 1
    if n_rest == 0:
        return out_r[:m], out_c[:m]
    rest = rest[:n_rest]
    rr, rc = rows[rest], cols[rest]
    lab = _pair_components(rr, rc, T)
    order = rest[np.argsort(lab, kind="mergesort")]
    lab = np.sort(lab)
    rmap, cmap = np.full(T, -1), np.full(D, -1)
    ur, uc = np.empty(n_rest, np.int64), np.empty(n_rest, np.int64)
    a = 0
    while a < n_rest:
        b = a
        while b < n_rest and lab[b] == lab[a]:
            b += 1
        # the component's tracks and detections, numbered in order of first appearance
        nr = nc = 0
        for q in range(a, b):
            p = order[q]
            if rmap[rows[p]] < 0:
                rmap[rows[p]] = nr
                ur[nr] = rows[p]
                nr += 1
            if cmap[cols[p]] < 0:
                cmap[cols[p]] = nc
                uc[nc] = cols[p]
                nc += 1
        sub = np.zeros((nr, nc))
        gate = np.zeros((nr, nc), np.bool_)
        for q in range(a, b):
            p = order[q]
            sub[rmap[rows[p]], cmap[cols[p]]] = cost[p]
            gate[rmap[rows[p]], cmap[cols[p]]] = True
        r, k = _limited_lsa(sub, gate) if limited else _gated_lsa(sub, gate)
        for q in range(r.shape[0]):
            out_r[m], out_c[m] = ur[r[q]], uc[k[q]]
            m += 1
        for q in range(a, b):
            p = order[q]
            rmap[rows[p]], cmap[cols[p]] = -1, -1
        a = b
    return out_r[:m], out_c[:m]


gnn_pairs_py = kernel(gnn_pairs)
""":func:`gnn_pairs` for calls from Python (compiled code calls the numba function)."""
gnn_pairs_limited_py = kernel(gnn_pairs_limited)
""":func:`gnn_pairs_limited` for calls from Python."""


def _pair_problem(rows: Any, cols: Any, cost: Any, shape: Any
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int]:
    """``rows``, ``cols`` and ``cost`` of the listed pairs of a problem of ``shape`` (tracks,
    detections; None: as large as the indices), checked: whole-number indices inside it, the
    three 1-D of one length, the costs numbers; as ``int64``, ``int64`` and ``float64``, and
    the shape."""
    for name, idx in (("rows", rows), ("cols", cols)):
        # (0.7 was cut to 0, True was 1, NaN met "cannot convert float NaN to integer")
        a = np.asarray(idx)
        if a.dtype.kind not in "iu" and not (a.dtype.kind == "f" and a.size == 0):
            whole = a.dtype.kind == "f" and bool(np.all(np.isfinite(a) & (a == np.round(a))))
            if not whole:
                raise ValueError(f"{name} must be whole numbers, indices; got "
                                 f"{a.ravel()[:5].tolist()}{' ...' if a.size > 5 else ''}")
    rows, cols = np.ascontiguousarray(rows, np.int64), np.ascontiguousarray(cols, np.int64)
    cost = np.ascontiguousarray(as_float_array(cost, "cost", not_boolean="numbers"))
    if not rows.shape == cols.shape == cost.shape or rows.ndim != 1:
        raise ValueError(f"rows, cols and cost must be 1-D of one length; got shapes "
                         f"{rows.shape}, {cols.shape} and {cost.shape}")
    if shape is None:  # as large as the indices
        for name, idx in (("rows", rows), ("cols", cols)):
            if len(idx) and idx.min() < 0:
                p = int(np.argmax(idx < 0))
                raise ValueError(f"{name} must be indices >= 0; {name}[{p}] is {int(idx[p])}")
        shape = (int(rows.max()) + 1 if len(rows) else 0,
                 int(cols.max()) + 1 if len(cols) else 0)
    if isinstance(shape, (int, np.integer)) or not hasattr(shape, "__len__"):
        raise ValueError(f"shape must be two whole numbers >= 0 (tracks, detections); got "
                         f"{shape!r}")
    if len(shape) != 2 or not all(is_whole(x, 0) for x in shape):  # (2.7 was cut to 2)
        raise ValueError(f"shape must be two whole numbers >= 0 (tracks, detections); got "
                         f"{tuple(shape)!r}")
    T, D = (int(x) for x in shape)
    for name, idx, n in (("rows", rows, T), ("cols", cols, D)):
        out = (idx < 0) | (idx >= n)
        if out.any():
            p = int(np.flatnonzero(out)[0])
            raise ValueError(f"rows and cols must index a ({T}, {D}) problem; {name}[{p}] is "
                             f"{int(idx[p])}")
    return rows, cols, cost, T, D


def gnn_sparse(rows: np.ndarray, cols: np.ndarray, cost: np.ndarray,
               shape: tuple[int, int], limit: float | None = None,
               ) -> tuple[np.ndarray, np.ndarray]:
    """Global nearest neighbour on a list of allowed pairs.

    :func:`gnn` on the allowed pairs only (``rows``, ``cols`` and their ``cost``), for
    problems too large for a dense matrix: the same answer as ``gnn`` on the dense problem,
    with or without ``limit`` (the cost of leaving a track and a detection unassigned).

    Parameters
    ----------
    rows, cols : (P,) array_like of int
        The allowed pairs: track ``rows[p]`` with detection ``cols[p]``.
    cost : (P,) array_like
        The cost of each pair, finite.
    shape : (int, int)
        ``(T, D)``, the numbers of tracks and detections.
    limit : float, optional
        The cost of leaving a track and a detection unassigned (:func:`gnn`); pairs costing
        ``limit`` or more are never assigned. Default: none, the most pairs are assigned.

    Returns
    -------
    rows, cols : (K,) ndarray of int64
        The assigned pairs.

    Raises
    ------
    ValueError
        If the three arrays are not 1-D of one length, ``shape`` is not two whole numbers
        >= 0, an index is outside it, a pair is listed twice, a cost is not finite, or
        ``limit`` is given and not a finite number (each named).

    Examples
    --------
    >>> r, c = gnn_sparse(np.array([0, 0, 1]), np.array([0, 1, 0]), np.array([1.0, 2.0, 1.5]),
    ...                   (2, 2))
    >>> r.tolist(), c.tolist()
    ([0, 1], [1, 0])
    """
    rows, cols, cost, T, D = _pair_problem(rows, cols, cost, shape)
    _check_limit(limit)  # (with no pair too: NaN or "x" went unsaid where none was allowed)
    if len(rows) == 0:
        return _EMPTY
    finite = np.isfinite(cost)
    if not finite.all():
        p = int(np.flatnonzero(~finite)[0])
        raise ValueError(f"cost must be finite on every pair; cost[{p}] is {cost[p]}")
    # each pair once: a second listing overwrote the first's cost, so the answer hung on
    # their order
    key = np.sort(rows * max(D, 1) + cols)
    twice = np.flatnonzero(key[1:] == key[:-1])
    if twice.size:
        k = int(key[twice[0]])
        raise ValueError(f"rows and cols must list each pair once; ({k // max(D, 1)}, "
                         f"{k % max(D, 1)}) is listed twice")
    return _gnn_sparse(rows, cols, cost, T, D, limit)


def _gnn_sparse(rows: np.ndarray, cols: np.ndarray, cost: np.ndarray, T: int, D: int,
                limit: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`gnn_sparse` without its checks, for the package's own callers, whose pairs are
    one each of finite cost within ``(T, D)`` by construction (from a gate's nonzero
    entries or an overlap's pairs): the checks cost a frame of the box tracker's numpy path
    about a tenth."""
    if len(rows) == 0:
        return _EMPTY
    rows, cols = np.ascontiguousarray(rows, np.int64), np.ascontiguousarray(cols, np.int64)
    cost = np.ascontiguousarray(cost, dtype=float)
    if limit is None:
        return gnn_pairs_py(rows, cols, cost, T, D)
    with np.errstate(over="ignore"):  # (said below, without numpy's warning)
        gain = cost - float(limit)
    if not np.isfinite(gain).all():
        # a cost and a limit of opposite signs near the largest float: the difference of
        # the halves, which cannot overflow (-inf made the solver's problem NaN, and it
        # called it infeasible or paired wrongly)
        gain = cost * 0.5 - float(limit) * 0.5
    return gnn_pairs_limited_py(rows, cols, gain, T, D)


def greedy(cost: np.ndarray, gate: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Greedy assignment: pairs by increasing cost, each taken when both ends are still free.

    Not optimal (see the example). Ties are taken in the row-major order of the matrix.

    Parameters
    ----------
    cost : (T, D) array_like
        Cost of each pair; non-finite costs are never assigned.
    gate : (T, D) array_like of bool, optional
        The allowed pairs; default every pair of finite cost.

    Returns
    -------
    rows, cols : (K,) ndarray of int64
        The assigned pairs, in the order they were taken (increasing cost).

    Raises
    ------
    ValueError
        If ``cost`` is not 2-D or ``gate`` does not have its shape.

    Examples
    --------
    >>> [a.tolist() for a in greedy(np.array([[1.0, 2.0], [1.5, 9.0]]))]   # 1 + 9
    [[0, 1], [0, 1]]
    """
    cost, gate = _check(cost, gate)
    r, c = np.nonzero(gate)
    return greedy_pairs(r, c, cost[r, c], cost.shape)


def greedy_pairs(rows: np.ndarray, cols: np.ndarray, cost: np.ndarray,
                 shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """:func:`greedy` on the allowed pairs alone, ``rows``, ``cols`` and their ``cost``
    listed in row-major order (as ``np.nonzero`` lists them; ties are taken in that order),
    of a problem of ``shape``: without the dense matrices, which at 8,000 points a frame
    took a gigabyte.

    >>> greedy_pairs(np.array([0, 0, 1]), np.array([0, 1, 0]), np.array([1.0, 2.0, 0.5]),
    ...              (2, 2))
    (array([1, 0]), array([0, 1]))
    """
    # (a negative index was taken, -1 as the last column, which it then blocked; one past
    # the end raised a bare IndexError)
    rows, cols, cost, T, D = _pair_problem(rows, cols, cost, shape)
    ok = np.isfinite(cost)  # (never assigned: -inf sorted first, and was taken)
    rows, cols, cost = rows[ok], cols[ok], cost[ok]
    order = np.argsort(cost, kind="stable")
    used_t, used_d = bytearray(T), bytearray(D)
    taken_r, taken_c = [], []
    for a, b in zip(rows[order].tolist(), cols[order].tolist()):  # (Python's ints: quicker)
        if not used_t[a] and not used_d[b]:
            used_t[a] = used_d[b] = 1
            taken_r.append(a)
            taken_c.append(b)
    return np.array(taken_r, np.int64), np.array(taken_c, np.int64)


def nearest_neighbour(cost: np.ndarray,
                      gate: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each track's cheapest allowed detection; detections may be shared (the seeds' nearest
    neighbour).

    Parameters
    ----------
    cost : (T, D) array_like
        Cost of each pair; non-finite costs are never assigned.
    gate : (T, D) array_like of bool, optional
        The allowed pairs; default every pair of finite cost.

    Returns
    -------
    rows, cols : (K,) ndarray of int64
        The tracks that have an allowed detection, in order, and their detection.

    Raises
    ------
    ValueError
        If ``cost`` is not 2-D or ``gate`` does not have its shape.

    Examples
    --------
    >>> [a.tolist() for a in nearest_neighbour(np.array([[1.0, 2.0], [1.5, 9.0]]))]
    [[0, 1], [0, 0]]
    """
    cost, gate = _check(cost, gate)
    if cost.shape[1] == 0:
        return _EMPTY
    # (a row's argmin, the lowest column of those tied: nearest_pairs' rule on every pair,
    # without sorting them all)
    c = np.where(gate, cost, np.inf)
    best = np.argmin(c, axis=1)
    rows = np.flatnonzero(np.isfinite(c[np.arange(len(c)), best]))
    return rows.astype(np.int64), best[rows].astype(np.int64)


def nearest_pairs(rows: np.ndarray, cols: np.ndarray, cost: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`nearest_neighbour` on the allowed pairs alone (``rows``, ``cols`` and their
    ``cost``, in any order): each row's cheapest pair of finite cost, the lowest column of
    those tied, rows in order; without the dense matrices.

    >>> nearest_pairs(np.array([1, 0, 0]), np.array([0, 1, 0]), np.array([0.5, 2.0, 2.0]))
    (array([0, 1]), array([0, 0]))
    """
    rows, cols, cost, _, _ = _pair_problem(rows, cols, cost, None)
    ok = np.isfinite(cost)
    r, c, k = rows[ok], cols[ok], cost[ok]
    order = np.lexsort((c, k, r))  # by row, then cost, then column
    r, c = r[order], c[order]
    first = np.r_[True, r[1:] != r[:-1]] if len(r) else np.zeros(0, bool)
    return r[first].astype(np.int64), c[first].astype(np.int64)


ASSIGNERS: Registry[Callable] = Registry("assigner", {"gnn": gnn, "greedy": greedy,
                                                   "nn": nearest_neighbour})
"""Assigners by name: ``f(cost (T, D), gate (T, D)) -> (rows, cols)``."""


def assign(cost: np.ndarray, gate: np.ndarray | None = None,
           method: str = "gnn") -> tuple[np.ndarray, np.ndarray]:
    """Assign detections to tracks by ``method``, a name in :data:`ASSIGNERS`.

    Parameters
    ----------
    cost : (T, D) array_like
        Cost of each track-detection pair; non-finite costs are never assigned.
    gate : (T, D) array_like of bool, optional
        The allowed pairs; default every pair of finite cost.
    method : {'gnn', 'greedy', 'nn'}
        :func:`gnn`, :func:`greedy` or :func:`nearest_neighbour`.

    Returns
    -------
    rows, cols : (K,) ndarray of int64
        The assigned pairs ``(rows[k], cols[k])``.

    Raises
    ------
    ValueError
        If ``method`` is not a name in :data:`ASSIGNERS`, or as the assigner raises.

    Examples
    --------
    >>> cost = np.array([[1.0, 2.0], [1.5, 9.0]])
    >>> [a.tolist() for a in assign(cost)]          # 2 + 1.5 beats 1 + 9
    [[0, 1], [1, 0]]
    >>> [a.tolist() for a in assign(cost, method="greedy")]
    [[0, 1], [0, 1]]
    """
    if method not in ASSIGNERS:  # (a Registry: ["gnn"] is in none)
        raise ValueError(f"method must be one of {sorted(ASSIGNERS)}; got {method!r}")
    return ASSIGNERS[method](cost, gate)

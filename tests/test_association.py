"""Association: costs against independent computations, assignment against brute force."""

from __future__ import annotations

import itertools
import re

import numpy as np
import pytest

from vistrack.association import (
    assign,
    chi2_gate,
    components,
    euclidean,
    giou,
    gnn,
    iou,
    mahalanobis,
    paired_iou,
)


def cells(x):
    return {(i, j) for i in range(int(x[0]), int(x[2])) for j in range(int(x[1]), int(x[3]))}


def raster_iou(a, b):
    """IoU of integer boxes by counting unit cells."""
    A, B = cells(a), cells(b)
    return len(A & B) / len(A | B) if A | B else 0.0


def test_iou_and_giou_against_rasterised_boxes():
    rng = np.random.default_rng(0)
    lo = rng.integers(0, 12, (40, 2))
    boxes = np.c_[lo, lo + rng.integers(0, 8, (40, 2))].astype(float)
    got = iou(boxes[:20], boxes[20:])
    want = np.array([[raster_iou(a, b) for b in boxes[20:]] for a in boxes[:20]])
    np.testing.assert_allclose(got, want, atol=1e-12)
    # GIoU = IoU - (hull - union) / hull, the hull counted by cells too
    g = giou(boxes[:20], boxes[20:])
    for i in range(20):
        for j in range(20):
            a, b = boxes[i], boxes[20 + j]
            hull = cells(np.r_[np.minimum(a[:2], b[:2]), np.maximum(a[2:], b[2:])])
            A, B = cells(a), cells(b)
            if hull:
                want_g = raster_iou(a, b) - (len(hull) - len(A | B)) / len(hull)
                assert g[i, j] == pytest.approx(want_g, abs=1e-12)
    assert np.all(g <= got + 1e-12) and np.all(g >= -1)
    # row by row: box k of one set against box k of the other
    np.testing.assert_allclose(paired_iou(boxes[:20], boxes[20:]),
                               [raster_iou(a, b) for a, b in zip(boxes[:20], boxes[20:])],
                               atol=1e-12)
    with pytest.raises(ValueError, match="same shape"):
        paired_iou(boxes[:3], boxes[:2])


def test_mahalanobis_and_gate():
    rng = np.random.default_rng(1)
    A = rng.normal(size=(5, 3, 3))
    S = A @ A.transpose(0, 2, 1) + np.eye(3)
    zp, z = rng.normal(size=(5, 3)), rng.normal(size=(7, 3))
    want = np.array([[(zz - p) @ np.linalg.inv(s) @ (zz - p) for zz in z] for p, s in zip(zp, S)])
    np.testing.assert_allclose(mahalanobis(zp, S, z), want, rtol=1e-10)
    assert chi2_gate(np.array([[9.20, 9.22]]), 2).tolist() == [[True, False]]  # chi2(2) 99 %
    np.testing.assert_allclose(euclidean([[0, 0]], [[3, 4]]), [[5.0]])
    with pytest.raises(ValueError, match=r"^a must be points, \(N, d\) or one \(d,\); got "
                       r"shape \(2, 3, 2\)$"):  # before: "must have the same point size"
        euclidean(np.zeros((2, 3, 2)), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="same point size"):
        euclidean(np.zeros((2, 3)), np.zeros((2, 2)))
    with pytest.raises(ValueError, match=r"S must have shape \(5, 3, 3\)"):
        mahalanobis(zp, S[:2], z)


def brute_force(cost, gate):
    """The most allowed pairs, then the least cost, over every assignment."""
    T, D = cost.shape
    best = (-1, np.inf)
    for perm in itertools.permutations(range(max(T, D)), min(T, D)):
        pairs = [(i, j) for i, j in zip(range(T), perm) if j < D] if T <= D else \
                [(i, j) for j, i in zip(range(D), perm) if i < T]
        ok = [(i, j) for i, j in pairs if gate[i, j]]
        key = (len(ok), sum(cost[i, j] for i, j in ok))
        if key[0] > best[0] or (key[0] == best[0] and key[1] < best[1] - 1e-12):
            best = key
    return best


@pytest.mark.parametrize("seed", range(30))
def test_gnn_equals_brute_force(seed):
    rng = np.random.default_rng(seed)
    T, D = rng.integers(1, 6, 2)
    cost = rng.uniform(-1, 5, (T, D))
    gate = rng.random((T, D)) < 0.6
    r, c = gnn(cost, gate)
    assert len(set(r)) == len(r) and len(set(c)) == len(c) and gate[r, c].all()
    n, total = brute_force(cost, gate)
    assert len(r) == n and cost[r, c].sum() == pytest.approx(total, abs=1e-9)


def brute_force_limited(cost, gate, limit):
    """The least total of cost - limit over every matching of allowed pairs (any size)."""
    T, D = cost.shape
    pairs = [(i, j) for i in range(T) for j in range(D) if gate[i, j] and cost[i, j] < limit]
    best = 0.0
    for k in range(1, min(T, D) + 1):
        for chosen in itertools.combinations(pairs, k):
            if len({i for i, _ in chosen}) == k and len({j for _, j in chosen}) == k:
                best = min(best, sum(cost[i, j] - limit for i, j in chosen))
    return best


@pytest.mark.parametrize("seed", range(30))
def test_gnn_with_a_limit_equals_brute_force(seed):
    """With ``limit``, the pairs of least total ``cost - limit``, any number of them."""
    rng = np.random.default_rng(100 + seed)
    T, D = rng.integers(1, 6, 2)
    cost = rng.uniform(0, 1, (T, D))
    gate = rng.random((T, D)) < 0.7
    limit = rng.uniform(0.3, 1.0)
    r, c = gnn(cost, gate, limit=limit)
    assert len(set(r)) == len(r) and len(set(c)) == len(c) and gate[r, c].all()
    assert (cost[r, c] < limit).all()
    assert (cost[r, c] - limit).sum() == pytest.approx(brute_force_limited(cost, gate, limit),
                                                       abs=1e-9)


@pytest.mark.parametrize("seed", range(40))
def test_gnn_with_a_limit_near_the_largest_float_equals_brute_force(seed):
    """Costs and a limit near 1.7e308: the pairs of the same problem scaled down by 2^1000
    (exact), by brute force. The solver's sums overflowed to -inf, and it paired wrongly
    (4 of 300 such problems)."""
    rng = np.random.default_rng(700 + seed)
    T, D = rng.integers(2, 5, 2)
    cost = rng.random((T, D)) * 1.7e308
    limit = float(rng.uniform(0.3, 1.05) * 1.7e308)
    gate = np.ones((T, D), bool)
    r, c = gnn(cost, limit=limit)
    scale = 2.0 ** -1000
    small, L = cost * scale, limit * scale
    assert (small[r, c] - L).sum() == pytest.approx(brute_force_limited(small, gate, L),
                                                    rel=1e-12)


def _exact_best_limited(cost, gate, limit):
    """The least total of cost - limit over every matching of allowed pairs, in exact
    fractions (floats overflow at these magnitudes)."""
    from fractions import Fraction

    T, D = cost.shape
    pairs = [(i, j) for i in range(T) for j in range(D) if gate[i, j] and cost[i, j] < limit]
    best = Fraction(0)
    for k in range(1, min(T, D) + 1):
        for chosen in itertools.combinations(pairs, k):
            if len({i for i, _ in chosen}) == k and len({j for _, j in chosen}) == k:
                best = min(best, sum(Fraction(cost[i, j]) - Fraction(limit)
                                     for i, j in chosen))
    return best


@pytest.mark.parametrize("seed", range(40))
def test_gnn_with_a_limit_over_the_whole_float_range_equals_brute_force(seed):
    """Costs and a limit of either sign up to 1.7e308, where cost - limit overflows to
    -inf (the solver called such a problem infeasible, or paired wrongly), and gains from
    1e-300 to 1e308 side by side (a tiny gain nothing contests was scaled to 0 and
    dropped): the pairs of least exact total, within rounding of the total."""
    from fractions import Fraction

    rng = np.random.default_rng(900 + seed)
    T, D = rng.integers(1, 5, 2)
    if seed % 2:
        cost = (rng.random((T, D)) * 2 - 1) * 1.7e308
        limit = float((rng.random() * 2 - 1) * 1.7e308)
    else:
        cost = -rng.random((T, D)) * rng.choice([1.7e308, 1e308, 1e300, 1.0, 1e-300], (T, D))
        limit = 0.0
    gate = rng.random((T, D)) < 0.7
    r, c = gnn(np.where(gate, cost, np.inf), gate, limit=limit)
    assert len(set(r)) == len(r) and len(set(c)) == len(c) and gate[r, c].all()
    got = sum((Fraction(cost[i, j]) - Fraction(limit) for i, j in zip(r, c)), Fraction(0))
    best = _exact_best_limited(cost, gate, limit)
    assert got == best or abs(float((got - best) / best)) < 1e-12


def test_a_gain_too_small_to_scale_is_still_taken():
    """A pair worth 1.2e-302 that no other track wants, beside gains of 1e307: taken (it
    was scaled to 0, as much as leaving it, and dropped)."""
    inf = np.inf
    cost = np.array([[inf, -9.5e-301, inf], [-0.46, -8e307, -1.5e298],
                     [inf, -4.6e-301, -4.7e298], [-1.2e-302, -6.3e297, -6.2e-311]])
    r, c = gnn(cost, limit=0.0)
    assert sorted(zip(r.tolist(), c.tolist())) == [(1, 1), (2, 2), (3, 0)]


def test_gnn_with_a_limit_equals_the_extended_assignment():
    """``limit`` is ByteTrack's ``lapjv(cost, cost_limit=limit)``: the square problem whose
    every track and detection may go to a dummy at ``limit / 2``, solved by scipy."""
    from scipy.optimize import linear_sum_assignment

    from vistrack.association import gnn_sparse, iou_pairs

    rng = np.random.default_rng(21)
    for n, m in [(60, 50), (40, 70), (1, 3)]:
        centres = rng.uniform(0, 200, (max(n, m), 2))  # a crowd: people side by side
        size = rng.uniform(20, 40, (max(n, m), 2))
        a = np.c_[centres[:n] - size[:n] / 2, centres[:n] + size[:n] / 2]
        moved = centres[:m] + rng.normal(0, 6, (m, 2))
        b = np.c_[moved - size[:m] / 2, moved + size[:m] / 2]
        cost = 1.0 - iou(a, b)
        limit = 0.8
        big = np.full((n + m, n + m), 0.0)
        big[:n, :m] = np.where(cost < limit, cost, 1e6)
        big[:n, m:] = np.where(np.eye(n, dtype=bool), limit / 2, 1e6)
        big[n:, :m] = np.where(np.eye(m, dtype=bool), limit / 2, 1e6)
        R, C = linear_sum_assignment(big)
        real = (R < n) & (C < m)
        want = (cost[R[real], C[real]] - limit).sum()
        r, c = gnn(cost, limit=limit)
        assert (cost[r, c] - limit).sum() == pytest.approx(want, abs=1e-9)
        # the most pairs, without a limit, take more pairs at a worse total
        r0, c0 = gnn(cost, cost < limit)
        assert len(r0) >= len(r) and (cost[r0, c0] - limit).sum() >= want - 1e-9
        # the sparse form, on the pairs that overlap at all
        pr, pc, pv = iou_pairs(a, b, 0.0)
        sr, sc = gnn_sparse(pr, pc, 1.0 - pv, (n, m), limit=limit)
        assert sorted(zip(sr.tolist(), sc.tolist())) == sorted(zip(r.tolist(), c.tolist()))


def test_a_limit_keeps_one_good_pair_over_two_poor_ones():
    """Person 1 detected, person 0 missed, a stranger's box beside person 1: the most pairs
    give track 0 person 1's box and track 1 the stranger's."""
    from vistrack.association import gnn_sparse

    cost = np.array([[0.7, np.inf], [0.1, 0.75]])   # rows: tracks 0, 1; columns: boxes 1, 2
    assert [a.tolist() for a in gnn(cost)] == [[0, 1], [0, 1]]
    assert [a.tolist() for a in gnn(cost, limit=0.8)] == [[1], [0]]
    assert [a.tolist() for a in gnn(cost, limit=0.72)] == [[1], [0]]
    # a pair at the limit gains nothing and is not taken
    assert [a.tolist() for a in gnn(np.array([[0.8]]), limit=0.8)] == [[], []]
    with pytest.raises(ValueError, match="limit must be a finite number or None; got inf"):
        gnn_sparse([0], [0], [0.5], (1, 1), limit=np.inf)


def test_components_are_scipys_connected_components_labels_and_all():
    """Random gates of every density, and long chains whose nodes come in a random order
    (which the labels spread along the edges take too many rounds for: scipy's graph
    does those), against scipy.sparse.csgraph.connected_components: the same number, and
    the same label for each track and detection (components numbered by their first node)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    def scipys(gate):
        T, D = gate.shape
        r, c = np.nonzero(gate)
        k, lab = connected_components(coo_matrix((np.ones(len(r)), (r, T + c)),
                                                 shape=(T + D, T + D)), directed=False)
        return k, lab[:T], lab[T:]

    rng = np.random.default_rng(0)
    gates = [rng.random(rng.integers(0, 40, 2)) < rng.uniform(0, 0.25) for _ in range(1500)]
    for n in (10, 200, 1000):
        chain = np.zeros((n, n), bool)
        t, d = rng.permutation(n), rng.permutation(n)
        chain[t, d] = chain[t[1:], d[:-1]] = True
        gates.append(chain)
    for gate in gates:
        k, lt, ld = components(gate)
        want = scipys(gate)
        assert k == want[0]
        np.testing.assert_array_equal(lt, want[1])
        np.testing.assert_array_equal(ld, want[2])


def test_components_give_the_whole_problems_answer_for_many_objects():
    """10,000 objects on a line, gated to their neighbours: solving each connected component
    alone gives the same number of pairs and total cost as one assignment over all."""
    from scipy.optimize import linear_sum_assignment

    rng = np.random.default_rng(2)
    x = np.sort(rng.uniform(0, 20_000, 10_000))
    z = x + rng.normal(0, 0.5, x.size)
    z = z[rng.permutation(z.size)][: 9_500]  # some missed
    d = np.abs(x[:, None] - z[None, :])
    gate = d < 3.0
    r, c = gnn(d, gate)
    k, lt, ld = components(gate)
    assert k > 1000
    big = np.where(gate, d, 1e6)
    R, C = linear_sum_assignment(big)
    ok = gate[R, C]
    assert len(r) == ok.sum()
    assert d[r, c].sum() == pytest.approx(d[R[ok], C[ok]].sum(), rel=1e-12)


def test_greedy_and_nearest_neighbour():
    cost = np.array([[1.0, 2.0], [1.5, 9.0]])
    assert [a.tolist() for a in assign(cost, method="greedy")] == [[0, 1], [0, 1]]
    r, c = assign(cost, method="nn")
    assert r.tolist() == [0, 1] and c.tolist() == [0, 0]  # both take detection 0
    r, c = assign(cost, np.array([[False, True], [False, False]]))
    assert r.tolist() == [0] and c.tolist() == [1]
    with pytest.raises(ValueError, match=r"method must be one of \['gnn', 'greedy', 'nn'\]"):
        assign(cost, method="hungarian")
    with pytest.raises(ValueError, match=r"method must be one of .*got \['gnn'\]"):
        assign(cost, method=["gnn"])  # (was "unhashable type: 'list'")
    assert [len(a) for a in assign(np.zeros((3, 0)))] == [0, 0]


def test_a_gate_of_another_shape_is_named():
    """A gate of another shape than the cost: (3, 2) failed with numpy's "operands could not
    be broadcast", and (1, 2) was broadcast to every track without a word. Both are named."""
    from vistrack.association import gnn

    cost = np.array([[1.0, 2.0], [1.5, 9.0]])
    for shape in ((3, 2), (1, 2), (2,)):
        with pytest.raises(ValueError, match=re.escape(
                f"gate must have the shape of cost (2, 2); got {shape}")):
            gnn(cost, gate=np.ones(shape, bool))


def test_suppression_names_scores_or_classes_of_another_length():
    """non_maximum and overlapping_pairs with too few classes failed with an IndexError deep
    inside, and with too few scores with numpy's "all keys need to be the same shape"."""
    from vistrack.association import non_maximum, overlapping_pairs

    boxes = [[0, 0, 10, 10], [1, 0, 11, 10], [20, 0, 30, 10]]
    with pytest.raises(ValueError, match=re.escape("classes must have one value a box (3); "
                                                   "got 1")):
        overlapping_pairs(boxes, [0])
    with pytest.raises(ValueError, match=re.escape("classes must have one value a box (3); "
                                                   "got 2")):
        non_maximum(boxes, [0.8, 0.9, 0.5], classes=[0, 1])
    with pytest.raises(ValueError, match=re.escape("scores must have one value a box (3); "
                                                   "got 2")):
        non_maximum(boxes, [0.8, 0.9])
    assert non_maximum(boxes, [0.8, 0.9, 0.5], classes=[0, 0, 1]).tolist() == [False, True, True]
    # boxes of another width were re-cut into (N, 4): (2, 8) as four boxes, (4, 3) as three
    for shape in ((2, 8), (4, 3)):
        with pytest.raises(ValueError, match=re.escape(
                f"boxes must have shape (N, 4) (x0, y0, x1, y1); got {shape}")):
            non_maximum(np.zeros(shape), [0.9] * (np.prod(shape) // 4))
    assert non_maximum([], []).tolist() == []


def test_non_maximum_at_zero_drops_boxes_that_overlap_at_all_and_keeps_those_that_touch():
    """As its docstring says: boxes that do not overlap never suppress each other, so at
    min_iou 0 two boxes sharing an edge (IoU 0, by hand) are both kept and any overlap
    (IoU 25 / 175 here) drops the weaker. Oracle: the greedy rule worked by hand."""
    from vistrack.association import iou, non_maximum

    boxes = np.array([[0, 0, 10, 10], [5, 5, 15, 15], [10, 0, 20, 10], [100, 100, 110, 110.]])
    assert iou(boxes[:1], boxes[1:3]).tolist() == [[25 / 175, 0.0]]
    assert non_maximum(boxes, [0.9, 0.8, 0.7, 0.6], min_iou=0.0).tolist() == [
        True, False, True, True]
    assert non_maximum(boxes, [0.9, 0.8, 0.7, 0.6], min_iou=0.15).tolist() == [True] * 4


def test_sparse_pairs_and_assignment_equal_the_dense_ones():
    from vistrack.association import gnn_sparse, iou_pairs

    rng = np.random.default_rng(5)
    for n, m in [(200, 180), (1, 5), (30, 0)]:
        lo = rng.uniform(0, 600, (n, 2))
        a = np.c_[lo, lo + rng.uniform(5, 60, (n, 2))]
        lo = rng.uniform(0, 600, (m, 2))
        b = np.c_[lo, lo + rng.uniform(5, 60, (m, 2))]
        dense = iou(a, b)
        for th in (0.0, 0.3):
            r, c, v = iou_pairs(a, b, th)
            want = np.argwhere(dense > 0) if th == 0 else np.argwhere(dense >= th)
            assert sorted(zip(r.tolist(), c.tolist())) == sorted(map(tuple, want.tolist()))
            np.testing.assert_allclose(v, dense[r, c], rtol=1e-12)
        r, c, v = iou_pairs(a, b, 0.01)
        sr, sc = gnn_sparse(r, c, 1 - v, (n, m))
        gate = dense >= 0.01
        dr, dc = gnn(1 - dense, gate)
        assert len(sr) == len(dr)
        assert (1 - dense[sr, sc]).sum() == pytest.approx((1 - dense[dr, dc]).sum(), abs=1e-9)


def test_iou_pairs_with_far_apart_boxes():
    from vistrack.association import iou_pairs

    a = np.array([[0, 0, 10, 10], [1e9, 1e9, 1e9 + 10, 1e9 + 10]], float)
    b = np.array([[5, 5, 15, 15], [1e9 + 5, 1e9, 1e9 + 15, 1e9 + 10], [-1e9, 0, -1e9 + 1, 1]])
    r, c, v = iou_pairs(a, b)
    np.testing.assert_allclose(v, iou(a, b)[r, c])
    assert sorted(zip(r.tolist(), c.tolist())) == [(0, 0), (1, 1)]


def test_iou_pairs_with_a_box_beyond_any_image():
    """One box far from the rest along one axis (x at 1e20, 1e100 or -1e307; a detector's
    garbage row) coarsened the grid alike on both axes until the other had less than one
    cell, and the first so many that its count overflowed: 1e20 asked for tens of gigabytes
    (MemoryError) and 1e100 crashed the process. The pairs are now the brute force's, and the
    far box pairs with nothing."""
    from vistrack.association import iou_pairs

    rng = np.random.default_rng(3)
    lo = rng.uniform(0, 600, (40, 2))
    near = np.c_[lo, lo + rng.uniform(20, 60, (40, 2))]
    for far in (1e15, 1e20, 1e100, -1e307, 1e307):
        box = np.array([[far, 10.0, far + 30, 60.0]])
        # the same far box on the other side of x = 0 (y as it is: boxes whose far corner
        # lies before the near one are refused)
        mirrored = np.c_[-box[:, 2], box[:, 1], -box[:, 0], box[:, 3]]
        for a, b in ((near, np.r_[near, box]), (np.r_[near, box], near),
                     (np.r_[box, near], np.r_[near, box, mirrored])):
            r, c, v = iou_pairs(a, b, 0.1)
            with np.errstate(invalid="ignore"):
                dense = iou(a, b)
            want = np.argwhere(dense >= 0.1)
            assert sorted(zip(r.tolist(), c.tolist())) == sorted(map(tuple, want.tolist()))
            np.testing.assert_allclose(v, dense[r, c], rtol=1e-12)


def test_compiled_lsa_equals_scipy_pair_for_pair():
    """vistrack's compiled shortest augmenting path gives scipy's assignment exactly, ties
    included (integer costs), for wide, tall and square matrices."""
    from scipy.optimize import linear_sum_assignment

    from vistrack.association import lsa

    rng = np.random.default_rng(11)
    for k in range(600):
        n, m = rng.integers(1, 10, 2)
        cost = rng.uniform(-3, 5, (n, m))
        if k % 2:
            cost = np.round(cost)
        r, c = lsa(cost)
        R, C = linear_sum_assignment(cost)
        assert r.tolist() == R.tolist() and c.tolist() == C.tolist()
    r, c = lsa(np.zeros((0, 3)))
    assert len(r) == len(c) == 0


def test_compiled_lsa_takes_what_scipy_takes_and_refuses_what_it_refuses():
    """Lists, integers, a transposed view and +inf (a pair not allowed) give scipy's pairs;
    NaN, -inf, a 1-D cost and an infeasible one are refused by name. Before, a list raised
    numba's TypingError and NaN gave an assignment."""
    from scipy.optimize import linear_sum_assignment

    from vistrack.association import lsa

    big = np.arange(12.0).reshape(3, 4) % 5
    for cost in ([[1.0, 2.0], [3.0, 0.5]], [[1, 2, 9], [3, 0, 1]], big.T,
                 [[np.inf, 1.0], [2.0, np.inf]]):
        r, c = lsa(cost)
        R, C = linear_sum_assignment(np.asarray(cost, float))
        assert r.tolist() == R.tolist() and c.tolist() == C.tolist()
    for cost, msg in (([[0.0, np.nan], [1.0, 2.0]], r"cost\[0, 1\] is nan: costs must be "
                       r"numbers or \+inf \(a pair not allowed\)"),
                      ([[1.0, 2.0], [-np.inf, 0.0]], r"cost\[1, 0\] is -inf"),
                      ([1.0, 2.0], r"cost must be a 2-D matrix; got shape \(2,\)"),
                      (5.0, r"cost must be a 2-D matrix; got shape \(\)"),
                      ([[np.inf, np.inf], [1.0, 2.0]], "cost matrix is infeasible")):
        with pytest.raises(ValueError, match=msg):
            lsa(cost)


def test_the_compiled_assignment_is_callable_from_a_kernel():
    """lsa_kernel, lsa without its checks, is what a user's numba kernel calls (lsa itself is
    a Python function)."""
    from numba import njit

    from vistrack.association import lsa, lsa_kernel

    @njit
    def total(c):
        r, k = lsa_kernel(c)
        return c[r, k].sum()

    cost = np.random.default_rng(5).uniform(0, 1, (6, 4))
    r, c = lsa(cost)
    assert total(cost) == pytest.approx(cost[r, c].sum())


def test_sparse_assignment_checks_its_arguments():
    from vistrack.association import gnn_sparse

    with pytest.raises(ValueError, match="must index a \\(2, 2\\) problem"):
        gnn_sparse([0, 2], [0, 1], [1.0, 1.0], (2, 2))
    with pytest.raises(ValueError, match="1-D of one length"):
        gnn_sparse([0, 1], [0], [1.0, 1.0], (2, 2))
    with pytest.raises(ValueError, match="finite"):
        gnn_sparse([0, 1], [0, 1], [1.0, np.nan], (2, 2))


@pytest.mark.parametrize("m", [0, -1, 2.7, True, "2", None, 10**400])
def test_the_gate_names_degrees_of_freedom_that_are_not_a_whole_number_from_1(m):
    """0 and -1 gave a NaN threshold, so a gate that kept nothing; 2.7 was taken as 2;
    10**400 failed in scipy's words (an OverflowError naming nothing)."""
    with pytest.raises(ValueError, match=re.escape(
            "m must be a whole number of degrees of freedom from 1 to 2**53")):
        chi2_gate(np.zeros((1, 1)), m)


def test_the_gate_takes_a_probability_as_it_takes_degrees_of_freedom():
    """``m=np.array(2)`` was taken and ``p=np.array(0.99)`` refused as no number; the
    oracle, scipy's quantile."""
    from scipy.stats import chi2

    from vistrack.association.gating import chi2_threshold

    assert chi2_threshold(np.array(2), np.array(0.99)) == chi2.ppf(0.99, 2)


@pytest.mark.parametrize("scores, error", [
    (["0.8", "0.9"], TypeError), ([True, False], TypeError), ([0.8 + 1j, 0.9], TypeError)])
def test_suppression_names_scores_that_are_no_numbers(scores, error):
    """Text and booleans were read as numbers, complex scores lost their imaginary parts
    with a warning alone: named, as every numeric argument of the package is."""
    from vistrack.association.costs import non_maximum

    with pytest.raises(error, match="scores must be"):
        non_maximum([[0, 0, 10, 10], [1, 0, 11, 10]], scores)


def test_the_gate_threshold_is_scipys_quantile():
    from scipy.stats import chi2

    from vistrack.association import chi2_threshold

    for m in (1, 2, 3.0, np.int64(4)):
        assert chi2_threshold(m, 0.95) == pytest.approx(chi2.ppf(0.95, int(m)), rel=1e-12)


def test_iou_pairs_of_one_class_are_the_dense_pairs_of_one_class():
    """Against the dense IoU matrix masked by class (the oracle); classes of another length
    than the boxes are refused (they were read past their end: 3,281 pairs for none)."""
    from vistrack.association import iou, iou_pairs_same_class

    rng = np.random.default_rng(0)
    xy = rng.random((300, 2)) * 100
    a = np.hstack([xy, xy + rng.uniform(2, 10, (300, 2))])
    b = a[rng.permutation(300)] + rng.normal(0, 1, (300, 4))
    b[:, 2:] = np.maximum(b[:, 2:], b[:, :2] + 0.5)
    ac, bc = rng.integers(0, 3, 300), rng.integers(0, 3, 300)
    r, c, v, ok = iou_pairs_same_class(a, ac, b, bc, 0.3)
    dense = iou(a, b)
    want = np.argwhere((dense >= 0.3) & (dense > 0) & (ac[:, None] == bc[None]))
    order = np.lexsort((c, r))  # by row, as documented; within a row in the grid's order
    assert ok and np.all(np.diff(r) >= 0) and np.array_equal(np.c_[r, c][order], want)
    np.testing.assert_allclose(v, dense[r, c], rtol=1e-12)
    for bad in (np.zeros(0, np.int64), np.zeros(10, np.int64)):
        with pytest.raises(ValueError, match="a_cls must hold one class per box of a"):
            iou_pairs_same_class(a, bad, b, bc, 0.3)
        with pytest.raises(ValueError, match="b_cls must hold one class per box of b"):
            iou_pairs_same_class(a, ac, b, bad, 0.3)


def test_an_innovation_covariance_that_is_not_one_is_named_by_every_distance():
    """A NaN ``S`` gave NaN distances (numpy's Cholesky factor of NaN is NaN, no error: the
    track then took no detection, silently), and an indefinite ``S`` negative distances in
    the sparse gate (its largest eigenvalue alone was checked), where the dense distance
    refuses it: each refused, naming the track."""
    from vistrack.association import likelihoods, mahalanobis
    from vistrack.association.costs import mahalanobis_pairs

    zp, z = np.zeros((2, 2)), np.array([[0.0, 3.0], [1.0, 0.0]])
    nan = np.array([np.eye(2), [[np.nan, 0.0], [0.0, 1.0]]])
    for f in (mahalanobis, likelihoods, lambda a, S, b: mahalanobis_pairs(a, S, b, 9.21)):
        with pytest.raises(ValueError, match=r"S must be finite and positive definite for "
                                             r"every track; S\[1\] is not finite"):
            f(zp, nan, z)
    indefinite = np.array([np.eye(2), np.diag([4.0, -1.0])])
    with pytest.raises(ValueError, match=r"S\[1\] is not"):
        mahalanobis(zp, indefinite, z)
    with pytest.raises(ValueError, match=r"S must be positive definite for every track; "
                                         r"S\[1\] is not"):
        mahalanobis_pairs(zp, indefinite, z, 9.21)
    # a positive definite S: the sparse pairs are the dense distances within the gate
    S = np.array([np.eye(2), np.diag([4.0, 1.0])])
    r, c, d2 = mahalanobis_pairs(zp, S, z, 9.21)
    dense = mahalanobis(zp, S, z)
    want = np.argwhere(dense <= 9.21)
    order = np.lexsort((c, r))
    assert np.array_equal(np.c_[r, c][order], want)
    np.testing.assert_allclose(d2[order], dense[dense <= 9.21], rtol=1e-12)


def test_giou_refuses_an_inverted_box_and_components_take_a_list():
    """GIoU of a box whose corners are swapped was 400 (its negative area and hull), outside
    its [-1, 1]; ``components`` of a list of lists (array_like, as documented) raised
    AttributeError."""
    from vistrack.association import components, giou

    with pytest.raises(ValueError, match=re.escape("b[0] = [10.0, 10.0, -10.0, -10.0] is not a "
                                                   "box x0, y0, x1, y1 with x0 <= x1")):
        giou([[0, 0, 1, 1]], [[10, 10, -10, -10]])
    # a point is still a box: IoU 0, and the hull is the unit box itself (0 - 0 / 1)
    assert giou([[0, 0, 1, 1]], [[0, 0, 0, 0]]).tolist() == [[0.0]]
    gate = [[True, False, False], [True, False, False], [False, False, True]]
    k, tl, dl = components(gate)
    want = components(np.array(gate))
    assert k == want[0] == 3 and tl.tolist() == want[1].tolist() and dl.tolist() == \
        want[2].tolist()
    with pytest.raises(ValueError, match=r"gate must be a 2-D mask, tracks by detections"):
        components([True, False])


def test_gnn_with_costs_near_the_largest_float_is_the_scaled_problem():
    """Costs of 5e307 made the penalty for disallowed pairs overflow to inf, and a component
    that must hold such a pair was called infeasible; the answer is that of the same costs
    scaled down (assignment is invariant to a positive scale), checked here against brute
    force over every matching."""
    from vistrack.association import gnn

    rng = np.random.default_rng(3)
    for scale in (1e300, 5e307, 1.7e308):
        for _ in range(20):
            unit = rng.uniform(-1, 1, (3, 4))
            gate = rng.random((3, 4)) < 0.6
            gate[0, 0] = True
            r, c = gnn(unit * scale, gate)
            # brute force on the unit costs: most pairs, then least cost
            best = None
            for cols in itertools.permutations(range(4), 3):
                pairs = [(i, j) for i, j in enumerate(cols) if gate[i, j]]
                key = (-len(pairs), sum(unit[i, j] for i, j in pairs))
                if best is None or key < best[0]:
                    best = (key, pairs)
            got = sorted(zip(r.tolist(), c.tolist()))
            assert len(got) == -best[0][0]
            assert sum(unit[i, j] for i, j in got) == pytest.approx(best[0][1], abs=1e-12)
    # rows 0 and 1 may take column 0 alone: one of them is left over (a disallowed pair in
    # the full assignment); row 1 takes it, at cost 0 against 5e307
    gate = np.array([[1, 0, 0], [1, 0, 0], [1, 1, 1]], bool)
    r, c = gnn(np.array([[5e307, 0, 0], [0.0, 0, 0], [0.0, 0, 0]]), gate)
    assert r.tolist() == [1, 2] and c[0] == 0 and c[1] in (1, 2)


def test_pairs_listed_twice_bad_gates_and_limits_are_named():
    """`gnn_sparse` took a pair listed twice, the later cost overwriting the earlier, so the
    answer hung on their order (oracle: no dense problem has two costs for one pair);
    `limit` was checked only where a pair was allowed; a gate of NaN or 0.2 was cast to
    True; an index or cost out of range was named without its place; a shape of 2.7 cut."""
    from vistrack.association import gnn, gnn_sparse, greedy

    rows, cols = np.array([0, 0, 0, 1, 1]), np.array([0, 0, 1, 0, 1])
    for cost in ([1.0, 100, 60, 50, 60], [100.0, 1, 60, 50, 60]):
        with pytest.raises(ValueError, match=re.escape(
                "rows and cols must list each pair once; (0, 0) is listed twice")):
            gnn_sparse(rows, cols, np.array(cost), (2, 2))
    for call in (lambda: gnn(np.full((2, 2), np.inf), limit=np.nan),
                 lambda: gnn(np.ones((2, 2)), limit=np.nan),
                 lambda: gnn_sparse([], [], [], (2, 2), limit=np.nan)):
        with pytest.raises(ValueError, match=re.escape(
                "limit must be a finite number or None; got nan")):
            call()
    with pytest.raises(ValueError, match=re.escape(
            "limit must be a finite number or None; got 'x'")):
        gnn_sparse([], [], [], (2, 2), limit="x")
    for f, gate, bad in ((gnn, [[np.nan, 0]], "nan"), (greedy, [[0.2, 0]], "0.2")):
        with pytest.raises(ValueError, match=re.escape(
                f"gate must be True/False (or 1/0) for each pair; gate[0, 0] is {bad}")):
            f(np.array([[1.0, 2.0]]), gate=gate)
    # 1/0 and booleans as before
    assert [a.tolist() for a in gnn(np.array([[1.0, 2.0]]), gate=[[0, 1]])] == [[0], [1]]
    with pytest.raises(ValueError, match=re.escape(
            "rows and cols must index a (2, 2) problem; cols[1] is -1")):
        gnn_sparse([0, 1], [0, -1], [1.0, 2.0], (2, 2))
    with pytest.raises(ValueError, match=re.escape(
            "cost must be finite on every pair; cost[1] is nan")):
        gnn_sparse([0, 1], [0, 1], [1.0, np.nan], (2, 2))
    with pytest.raises(ValueError, match=re.escape(
            "shape must be two whole numbers >= 0 (tracks, detections); got (2.7, 3)")):
        gnn_sparse([0], [0], [1.0], (2.7, 3))


def test_boxes_and_detections_that_cannot_be_measured_are_named():
    """A NaN box overlapped nothing (IoU 0, GIoU 0, ranked above a real far box) where
    `iou_pairs` named it; a (3, 0) array of boxes or a (5, 0) one of detections was taken
    for none, their rows dropped; `mahalanobis_pairs` took a threshold of NaN or -1 (no
    pair), and failed on a NaN detection in scipy's words; `non_maximum` sorted a NaN score
    last."""
    from vistrack.association import giou, iou, mahalanobis, non_maximum
    from vistrack.association.costs import mahalanobis_pairs

    nan_box, box = [[0, 0, np.nan, 2]], [[0, 0, 2, 2]]
    for f in (iou, giou):
        with pytest.raises(ValueError, match=re.escape(
                "a must be finite boxes; a[0] = [0.0, 0.0, nan, 2.0]")):
            f(nan_box, box)
    with pytest.raises(ValueError, match=re.escape(
            "a must have shape (N, 4) (x0, y0, x1, y1); got (3, 0)")):
        iou(np.zeros((3, 0)), box)
    assert iou([], box).shape == (0, 1) and iou(np.zeros((0, 4)), box).shape == (0, 1)
    S = np.eye(2)[None]
    with pytest.raises(ValueError, match=re.escape("z must have shape (D, 2); got (5, 0)")):
        mahalanobis([[0.0, 0.0]], S, np.zeros((5, 0)))
    assert mahalanobis([[0.0, 0.0]], S, []).shape == (1, 0)
    for t in (np.nan, -1):
        with pytest.raises(ValueError, match=re.escape(
                f"threshold must be a squared distance >= 0 (inf: no gate); got {t!r}")):
            mahalanobis_pairs([[0.0, 0.0]], S, [[1.0, 0.0]], threshold=t)
    r, c, d2 = mahalanobis_pairs([[0.0, 0.0]], S, [[1.0, 1.0], [5.0, 5.0]], np.inf)  # no gate
    assert c.tolist() == [0, 1] and d2.tolist() == [2.0, 50.0]
    assert iou(np.zeros((0, 0)), box).shape == (0, 1)
    with pytest.raises(ValueError, match=re.escape("z must be finite; z[0] = [nan, 0.0]")):
        mahalanobis_pairs([[0.0, 0.0]], S, [[np.nan, 0.0], [1.0, 0.0]], threshold=4.0)
    with pytest.raises(ValueError, match=re.escape("scores must be numbers; scores[1] is NaN")):
        non_maximum([[0, 0, 10, 10], [1, 0, 11, 10]], [0.8, np.nan])


def test_inverted_boxes_and_a_bad_min_iou_are_named_by_every_box_function():
    """A box whose far corner lies before its near one overlapped nothing, itself included
    (IoU 0, and two such boxes, the same, both survived non_maximum), as giou refused;
    min_iou NaN gave no pair and turned non_maximum off, True was 1."""
    from vistrack.association import iou_pairs, non_maximum, overlapping_pairs

    flipped = [[2.0, 2.0, 0.0, 0.0]]
    for call in (lambda: iou(flipped, flipped), lambda: paired_iou(flipped, flipped),
                 lambda: iou_pairs(flipped, flipped), lambda: overlapping_pairs(flipped),
                 lambda: non_maximum(flipped * 2, [1.0, 2.0]), lambda: giou(flipped, flipped)):
        with pytest.raises(ValueError, match=r"\[0\] = \[2\.0, 2\.0, 0\.0, 0\.0\] is not a box "
                                             r"x0, y0, x1, y1 with x0 <= x1"):
            call()
    box = [[0.0, 0.0, 2.0, 2.0]]
    for bad in (np.nan, np.inf):
        with pytest.raises(ValueError, match=r"min_iou must be a finite number"):
            iou_pairs(box, box, bad)
        with pytest.raises(ValueError, match=r"min_iou must be a finite number"):
            non_maximum(box * 2, [1.0, 2.0], min_iou=bad)
    with pytest.raises(TypeError, match=r"min_iou must be a number; got True"):
        iou_pairs(box, box, True)
    # a box of no size is still a box; identical boxes overlap fully (the oracle: IoU 1)
    assert iou([[1.0, 1.0, 1.0, 3.0]], box).tolist() == [[0.0]]
    assert non_maximum(box * 2, [1.0, 2.0]).tolist() == [False, True]


def test_costs_gates_and_indices_are_numbers_as_given():
    """Complex costs and squared distances lost their imaginary parts with numpy's warning
    alone; booleans were costs 1 and 0; gnn_sparse cut an index of 0.7 to 0 and took True
    for 1; a gate entry of None met an AttributeError from the check; components() took a
    NaN in its mask for True."""
    from vistrack.association import gnn_sparse, lsa

    for call in (lambda: gnn(np.array([[1 + 5j, 2.0]])), lambda: lsa(np.array([[1 + 5j, 2.0]])),
                 lambda: chi2_gate(np.array([[1 + 3j]]), 2),
                 lambda: mahalanobis(np.zeros((1, 2)), np.eye(2)[None],
                                     np.array([[1j, 0.0]]))):
        with pytest.raises(TypeError, match=r"must be real numbers; got complex"):
            call()
    for call in (lambda: gnn([[True, False]]), lambda: lsa([[True, False]]),
                 lambda: chi2_gate([[True, False]], 2)):
        with pytest.raises(TypeError, match=r"must be (numbers|squared distances)"):
            call()
    with pytest.raises(ValueError, match=r"rows must be whole numbers, indices; got \[0\.7\]"):
        gnn_sparse([0.7], [0], [1.0], (1, 1))
    with pytest.raises(ValueError, match=r"rows must be whole numbers, indices; got \[True\]"):
        gnn_sparse([True], [0], [1.0], (2, 1))
    with pytest.raises(ValueError, match=r"shape must be two whole numbers >= 0.*got 3"):
        gnn_sparse([0], [0], [1.0], 3)
    r, c = gnn_sparse([1.0, 0.0], [0, 0], [1.0, 2.0], (2, 1))  # whole floats are indices
    assert (r.tolist(), c.tolist()) == ([1], [0])
    with pytest.raises(ValueError, match=r"gate must be True/False \(or 1/0\) for each pair; "
                                         r"gate\[0, 0\] is None"):
        gnn(np.ones((1, 2)), [[None, 1]])
    with pytest.raises(ValueError, match=r"gate\[0, 1\] is nan"):
        components(np.array([[1.0, np.nan]]))


def test_none_given_as_a_bare_list_is_none_for_every_distance():
    """A frame of no tracks or no detections given as ``[]`` (or an array built from an
    empty list, shape ``(0,)``): ``euclidean([], [])`` was one phantom pair at distance 0,
    which ``gnn`` assigned, and ``euclidean(points, [])`` refused the shapes as of another
    point size; ``mahalanobis`` took ``z_pred`` and ``S`` of shape (0,) for one track of no
    measurement and refused ``S`` as not (1, 0, 0). The oracle: ``iou``'s own contract, a
    bare ``[]`` is no box, and scipy's ``cdist`` on the ``(0, d)`` arrays."""
    from scipy.spatial.distance import cdist

    pts = np.array([[0.0, 0.0], [3.0, 4.0]])
    assert iou([], []).shape == (0, 0)
    for a, b in (([], []), (pts, []), ([], pts)):
        want = cdist(np.reshape(a, (-1, 2)), np.reshape(b, (-1, 2)))
        got = euclidean(a, b)
        assert got.shape == want.shape
        assert [r.tolist() for r in gnn(got)] == [[], []]
    no_tracks = np.array([t for t in []])  # shape (0,), as a loop over no tracks builds it
    from vistrack.association.costs import mahalanobis_pairs

    # and with no detections either, given bare or as (0, 2) (numpy's "zero-size array to
    # reduction operation" where the second reading found it)
    for zp, S, z, D in ((no_tracks, no_tracks, pts, 2), (no_tracks, no_tracks, [], 0),
                        (no_tracks, no_tracks, np.zeros((0, 2)), 0),
                        (np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros((0, 2)), 0)):
        assert mahalanobis(zp, S, z).shape == (0, D)
        r, c, d2 = mahalanobis_pairs(zp, S, z, 9.21)
        assert len(r) == len(c) == len(d2) == 0
    with pytest.raises(ValueError, match=re.escape("z must have shape (D, 2); got (1, 3)")):
        mahalanobis(np.zeros((0, 2)), np.zeros((0, 2, 2)), [[1.0, 2.0, 3.0]])


def test_euclidean_between_points_whose_squares_overflow_is_hypot():
    """Points 5e200 apart: the squares overflowed and the distance was inf; the oracle is
    ``math.hypot`` (as scipy's ``cdist`` gives inf here too)."""
    import math

    got = euclidean([[0.0, 0.0], [1.0, 1.0]], [[3e200, 4e200], [4.0, 5.0]])
    assert got[0, 0] == pytest.approx(math.hypot(3e200, 4e200), rel=1e-15)
    assert got[1, 1] == 5.0 and got[0, 1] == pytest.approx(math.hypot(4.0, 5.0))
    assert np.isinf(euclidean([[0.0]], [[np.inf]])[0, 0])  # (an infinite point stays so)


@pytest.mark.parametrize("seed", range(20))
def test_gnn_with_costs_near_the_largest_float_close_together_is_the_scaled_problem(seed):
    """Costs of 9e307 within a few thousandths of each other: the penalty for a disallowed
    pair stayed finite, so the problem was not scaled, but the solver's sums overflowed and
    it gave one pair where three were allowed (163 of 3,000 such problems), or a worse
    total. The oracle: brute force over every matching of the same problem scaled down
    by 2^-1000 (exact)."""
    rng = np.random.default_rng(4000 + seed)
    T, D = rng.integers(2, 5, 2)
    unit = rng.uniform(0.997, 1.0, (T, D))
    gate = rng.random((T, D)) < 0.6
    gate[0, 0] = True
    cost = unit * 9e307
    for g in (gate, np.ones((T, D), bool)):
        r, c = gnn(cost, g)
        assert len(set(r)) == len(r) and len(set(c)) == len(c) and g[r, c].all()
        n, total = brute_force(cost * 2.0 ** -1000, g)
        assert len(r) == n
        assert (cost[r, c] * 2.0 ** -1000).sum() == pytest.approx(total, rel=1e-12)


def test_gnn_near_the_largest_float_finds_the_whole_matching():
    """The reading's case: three pairs allowed, (0, 2), (1, 0), (2, 1); one was given."""
    unit = np.array([[0.997, 1.0, 0.999], [0.999, 0.999, 1.0], [0.999, 0.997, 0.998]])
    gate = np.array([[1, 1, 1], [1, 0, 0], [0, 1, 0]], bool)
    r, c = gnn(unit * 1e308, gate)
    assert sorted(zip(r.tolist(), c.tolist())) == [(0, 2), (1, 0), (2, 1)]


def test_boxes_whose_area_a_float_cannot_hold_are_named():
    """Two identical boxes of side 1e160 (area inf) or 1e-170 (area 0) overlapped at IoU 0,
    GIoU NaN, and both survived ``non_maximum``; IoU is the same at every scale, so the
    oracle is 1, which these boxes cannot give: refused, named."""
    from vistrack.association.costs import non_maximum

    for side in (1e160, 1e-170):
        box = [[0.0, 0.0, side, side]]
        for f in (iou, giou, lambda a, b: non_maximum(a + b, [1.0, 0.5])):
            with pytest.raises(ValueError, match="0] = \\[0.0, 0.0, .* is a box whose area a "
                                                 "float cannot hold"):
                f(box, box)
    with pytest.raises(ValueError, match=re.escape(
            "b[0] = [0.0, 0.0, 1e+160, 1e+160] is a box whose area a float cannot hold "
            "(1e+160 x 1e+160); scale the boxes")):
        iou([[0, 0, 1, 1]], [[0, 0, 1e160, 1e160]])
    np.testing.assert_array_equal(iou([[0, 0, 1e150, 1e150]], [[0, 0, 1e150, 1e150]]), [[1.0]])


def test_giou_of_boxes_whose_hull_overflows_is_its_limit():
    """A unit box and one at 1e200: their hull's area overflows, and GIoU was NaN (inf minus
    the union, over inf). In exact fractions it is -(1 - 2/hull), -1 to a float."""
    from fractions import Fraction

    a, b = [[0.0, 0.0, 1.0, 1.0]], [[1e200, 1e200, 1e200 + 1, 1e200 + 1]]
    hull = Fraction(1e200 + 1) ** 2
    assert giou(a, b)[0, 0] == float(-(1 - 2 / hull)) == -1.0
    assert giou(a, [[0.0, 0.0, 1.0, 1.0], [2.0, 0.0, 3.0, 1.0]]).tolist() == [[1.0, -1 / 3]]


@pytest.mark.parametrize("seed", range(20))
def test_greedy_and_nearest_on_pairs_equal_their_definitions(seed):
    """The pair forms (which the point tracker uses: the dense matrices took a gigabyte at
    8,000 points a frame) against the rules written out: greedy takes pairs by increasing
    cost, ties in row-major order, each where both ends are free; nearest neighbour gives
    each row its cheapest allowed column, the lowest of those tied. Costs from a few
    values, so that ties are common; the pairs listed in a random order for nearest."""
    from vistrack.association.assign import greedy, greedy_pairs, nearest_neighbour, nearest_pairs

    rng = np.random.default_rng(seed)
    T, D = rng.integers(0, 7, 2)
    cost = rng.integers(0, 4, (T, D)).astype(float)
    gate = rng.random((T, D)) < 0.6
    r, c = np.nonzero(gate)
    # greedy, by its definition
    pairs = sorted(zip(r.tolist(), c.tolist()), key=lambda p: cost[p])  # (stable)
    used_r, used_c, want = set(), set(), []
    for i, j in pairs:
        if i not in used_r and j not in used_c:
            used_r.add(i)
            used_c.add(j)
            want.append((i, j))
    got = greedy_pairs(r, c, cost[r, c], (T, D))
    assert list(zip(got[0].tolist(), got[1].tolist())) == want
    # a pair of infinite cost (either sign) is never taken, and takes nothing from the
    # others (-inf sorted first, and ended the loop before any pair was taken)
    if len(r):
        k = np.r_[cost[r, c], np.inf, -np.inf]
        got = greedy_pairs(np.r_[r, 0, 0], np.r_[c, 0, 0], k, (max(T, 1), max(D, 1)))
        assert list(zip(got[0].tolist(), got[1].tolist())) == want
    assert [list(a) for a in greedy(cost, gate)] == [list(a) for a in got]
    # nearest, by its definition, from the pairs in any order
    want_nn = [(i, min((cost[i, j], j) for j in range(D) if gate[i, j])[1])
               for i in range(T) if gate[i].any()]
    shuffle = rng.permutation(len(r))
    got = nearest_pairs(r[shuffle], c[shuffle], cost[r, c][shuffle])
    assert list(zip(got[0].tolist(), got[1].tolist())) == want_nn
    assert [a.tolist() for a in nearest_neighbour(cost, gate)] == [a.tolist() for a in got]


def test_gnn_of_tiny_costs_takes_the_least_total():
    """The least-cost assignment does not change when every cost is scaled by the same
    positive number; below 1e-16 a gated problem's penalty for a disallowed pair, of an
    absolute 1 beside costs that small, swallowed their differences in the solver's sums,
    and a worse total was taken (-5 where -6 is least). Oracle: scipy's assignment with the
    disallowed pairs priced above any set of allowed ones, scaled alike."""
    from scipy.optimize import linear_sum_assignment

    from vistrack.association import gnn, gnn_sparse

    C = np.array([[-2.0, 2.0, 2.0, -3.0], [1.0, -2.0, -2.0, 0.0], [-2.0, -1.0, -3.0, -2.0]])
    gate = np.array([[0, 1, 1, 1], [0, 0, 1, 0], [0, 0, 1, 0]], bool)
    r0, c0 = linear_sum_assignment(np.where(gate, C, 1e6))
    keep = gate[r0, c0]
    want = sorted(zip(r0[keep].tolist(), c0[keep].tolist()))
    assert want == [(0, 3), (2, 2)]
    for s in (1.0, 1e-15, 1e-16, 1e-20, 1e-300):
        r, c = gnn(C * s, gate)
        assert sorted(zip(r.tolist(), c.tolist())) == want, s
        i, j = np.nonzero(gate)
        r, c = gnn_sparse(i, j, C[i, j] * s, C.shape)
        assert sorted(zip(r.tolist(), c.tolist())) == want, s
    rng = np.random.default_rng(1)
    for _ in range(300):  # random gated problems, each at a tiny scale
        C = rng.integers(-3, 4, size=(4, 5)).astype(float)
        gate = rng.random((4, 5)) < 0.5
        if not gate.any():
            continue
        r0, c0 = linear_sum_assignment(np.where(gate, C, 1e6))
        keep = gate[r0, c0]
        r, c = gnn(C * 1e-200, gate)
        assert len(r) == keep.sum() and C[r, c].sum() == C[r0[keep], c0[keep]].sum()


def test_the_pairs_assigners_name_an_index_outside_the_problem():
    """greedy_pairs took a negative index (-1 as the last column, which it then blocked, so
    track 1 lost its only detection) and met one past the end with a bare IndexError;
    nearest_pairs took a negative one. Each is named now, as gnn_sparse names it."""
    from vistrack.association import greedy_pairs, nearest_pairs

    with pytest.raises(ValueError, match=r"^rows and cols must index a \(2, 2\) problem; "
                                         r"cols\[0\] is -1$"):
        greedy_pairs(np.array([0, 1]), np.array([-1, 1]), np.array([1.0, 2.0]), (2, 2))
    with pytest.raises(ValueError, match=r"^rows and cols must index a \(2, 2\) problem; "
                                         r"cols\[1\] is 5$"):
        greedy_pairs([0, 1], [0, 5], [1.0, 2.0], (2, 2))
    with pytest.raises(ValueError, match=r"^cols must be indices >= 0; cols\[0\] is -2$"):
        nearest_pairs(np.array([0]), np.array([-2]), np.array([1.0]))
    # lists are taken as arrays (their .tolist() failed in numpy's words)
    assert [a.tolist() for a in greedy_pairs([0, 1], [1, 0], [1.0, 2.0], (2, 2))] == [[0, 1],
                                                                                      [1, 0]]


def test_tiny_distances_and_boxes_keep_their_digits_or_are_named():
    """``euclidean`` squared the differences, and below 1e-154 the squares underflowed: two
    points 3e-170 and 1e-170 from the origin were both 0 from it, and the nearest taken was
    the farther. A box of side 2.3e-162 has an area below the smallest normal float, of a
    digit or none: two such boxes overlapping by half had IoU 1, and ``non_maximum`` dropped
    the second. Oracles: ``math.hypot``; the same boxes scaled by 1e161 (IoU 1/3)."""
    import math

    from vistrack.association import euclidean, iou, nearest_neighbour, non_maximum

    d = euclidean([[0.0, 0.0]], [[3e-170, 0.0], [1e-170, 0.0], [3e-160, 4e-160]])
    np.testing.assert_allclose(d[0], [3e-170, 1e-170, math.hypot(3e-160, 4e-160)],
                               rtol=1e-15)
    assert nearest_neighbour(d[:, :2])[1].tolist() == [1]
    np.testing.assert_array_equal(euclidean([[1.0, 2.0]], [[1.0, 2.0]]), [[0.0]])
    scaled = np.array([[0, 0, 2.3, 2.3], [1.15, 0, 3.45, 2.3]])
    np.testing.assert_allclose(iou(scaled, scaled)[0, 1], 1 / 3, rtol=1e-12)
    tiny = scaled * 1e-162
    with pytest.raises(ValueError, match=re.escape("is a box whose area a float cannot hold")):
        iou(tiny, tiny)
    with pytest.raises(ValueError, match="a float cannot hold"):
        non_maximum(tiny, [0.9, 0.8], 0.5)

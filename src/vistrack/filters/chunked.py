"""Batches larger than memory: :func:`~vistrack.filters.kalman_filter`,
:func:`~vistrack.filters.rts_smooth` and :func:`~vistrack.filters.em` on a Dask array chunked
along the batch axis.

Given measurements ``ys`` as a Dask array ``(B, T, m)``, :func:`kalman_filter` returns a
:class:`~vistrack.filters.FilterResult` of Dask arrays, nothing computed yet: each chunk of
series is filtered by the in-memory filter as one batch, when (and where) the result is
computed, so a Dask cluster filters chunks on its workers and no machine holds the whole
batch. The result of each chunk is exactly the in-memory filter's result for that chunk's
series; :func:`rts_smooth` smooths such a result chunk by chunk the same way.

- The chunks run along the batch axis only (time and the measurement are rechunked whole).
- The model (``F``, ``Q``, ``H``, ``R``) is shared by all series (per-step matrices allowed);
  the prior ``x0``, ``P0`` is shared, or one per series as an array with the batch axis
  first (numpy or Dask), cut as ``ys`` is.
- :func:`em` pooled runs each iteration's E-step on every chunk and adds the chunks' sums
  (a few ``(T, n, n)`` arrays a chunk); one fit per series (``pooled=False``) is lazy, as the
  filter is.
- Dask is imported here only (``pip install vistrack[dask]``); ``import vistrack`` does not
  import it.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validate import as_float_array
from ..types import Gaussian
from .kalman import _is_dask

if TYPE_CHECKING:
    from .kalman import FilterResult
    from .learn import FitResult
    from .smoothers import SmoothResult

__all__ = ["kalman_filter", "rts_smooth", "em"]


def _batch_blocks(ys: Any) -> tuple[Any, list[tuple[int, int]]]:
    if ys.ndim != 3:
        raise ValueError(f"ys as a Dask array must have shape (B, T, m); got {ys.shape}")
    if any(np.isnan(c) for axis in ys.chunks for c in axis):
        # (a boolean selection's unknown sizes: "cannot convert float NaN to integer")
        raise ValueError("ys has chunks of unknown size (a boolean selection's): call "
                         "ys.compute_chunk_sizes() first")
    ys = _whole_after_batch(ys)
    edges = np.cumsum((0,) + ys.chunks[0])
    return ys, [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]


def _whole_after_batch(a: Any, batch: tuple[int, ...] | None = None) -> Any:
    """``a`` in one chunk along every axis but the first (chunked as ``batch`` along it, if
    given); ``a`` itself when it is so already (a rechunk to the same chunks would still copy
    every block)."""
    want = (batch or a.chunks[0],) + tuple((d,) for d in a.shape[1:])
    return a if a.chunks == want else a.rechunk(want)


def _block(y: Any) -> np.ndarray:
    """One chunk of ``ys`` as floats, a masked entry (a masked Dask array's blocks) as NaN,
    missing, as the filters in memory read it: ``np.asarray`` kept the values under the mask
    and filtered them as measurements."""
    return as_float_array(y, "ys")


def _one_for_all(p: Any, ndim_shared: int) -> Any:
    """A prior with a batch axis of one, ``(1, n)`` or ``(1, n, n)``, as the one for every
    series (as the in-memory filter takes it); any other as given."""
    return p[0] if np.ndim(p) == ndim_shared + 1 and np.shape(p)[0] == 1 else p


def _per_series(p: Any, B: int, ndim_shared: int, name: str) -> Any:
    """A prior shared by all series (None), or one per series (its batch-first array)."""
    if np.ndim(p) == ndim_shared:
        return None
    if np.ndim(p) != ndim_shared + 1 or np.shape(p)[0] != B:
        raise ValueError(f"{name} must be shared by the series or have the batch axis first "
                         f"(B = {B}); got shape {np.shape(p)}")
    return p


def _chunk_filter(y: np.ndarray, x0: Any, P0: Any, model: dict, store_covs: bool,
                  first: int = 0) -> tuple:
    from .kalman import kalman_filter as in_memory

    y = _block(y)
    inf = np.isinf(y)
    if inf.any():  # named by its place in the batch (the chunk's own was named: ys[1, ...])
        b, t, k = (int(v) for v in np.argwhere(inf)[0])
        raise ValueError(f"ys must be finite or NaN (missing); ys[{first + b}, {t}, {k}] = "
                         f"{y[b, t, k]}")
    try:
        r = in_memory(y, x0=np.asarray(x0), P0=np.asarray(P0), store_covs=store_covs, **model)
    except ValueError as e:  # (its indices and B are the chunk's: said so)
        if first == 0 and len(y) == 0:
            raise
        raise ValueError(f"{e} (in the chunk of ys's series {first}-{first + len(y) - 1}: "
                         "indices and B there count within the chunk)") from None
    # the last state is a view of the means: copied, so that a result that needs only it
    # does not keep every chunk's means alive (a covariance shared by the chunk's series
    # stays one matrix, seen by every series, as in memory)
    cov = r.last.cov
    # (a chunk of no series, as a selection leaves: cov[0] was an IndexError)
    cov = (np.broadcast_to(cov[0].copy(), cov.shape)
           if cov.ndim == 3 and cov.strides[0] == 0 and len(cov) else np.array(cov))
    return (r.means, r.covs, r.pred_means, r.pred_covs, r.loglik, np.array(r.last.mean), cov)


def _one(block: Any) -> np.ndarray:
    """The block itself, from the nested lists in which ``blockwise(..., concatenate=False)``
    passes the one block of each axis summed over (concatenating would copy it)."""
    while isinstance(block, list):
        (block,) = block
    return block


def _block_filter(y: Any, first: Any, *per_series: Any, x0: Any, P0: Any, given: tuple,
                  model: dict, store_covs: bool) -> tuple:
    """:func:`_chunk_filter` on one block (``first``: its series' places in the batch), the
    priors given per series (``given``) among the blocks after it."""
    blocks = {name: _one(b) for name, b in zip(given, per_series)}
    places = np.asarray(_one(first)).reshape(-1)
    return _chunk_filter(_one(y), blocks.get("x0", x0), blocks.get("P0", P0), model,
                         store_covs, int(places[0]) if len(places) else 0)


def _pick(block: tuple, i: int) -> np.ndarray:
    return block[i]


def _fields(packed: Any, tails: list[tuple[int, ...] | None]) -> list[Any]:
    """The arrays packed per block as tuples in ``packed`` (one block per batch chunk), each
    with the shape ``tail`` after the batch axis (None: not there). Each field is one task a
    block that Dask's array optimisation fuses with the block's other steps."""
    out: list[Any] = []
    for i, tail in enumerate(tails):
        if tail is None:
            out.append(None)
            continue
        out.append(packed.map_blocks(_pick, i, dtype=np.float64,
                                     chunks=(packed.chunks[0],) + tuple((d,) for d in tail),
                                     new_axis=list(range(1, len(tail) + 1)),
                                     meta=np.empty((0,) * (len(tail) + 1))))
    return out


def kalman_filter(ys: Any, *, F: Any, Q: Any, H: Any, R: Any, x0: Any, P0: Any,
                  store_covs: bool = True) -> FilterResult:
    """:func:`vistrack.filters.kalman_filter` on a Dask array ``(B, T, m)``, lazily, chunk by
    chunk along the batch axis (see the module).

    Returns
    -------
    FilterResult
        Its arrays are Dask arrays with ``ys``'s batch chunks; ``shared_covs`` is False (a
        chunk's series may share covariances, the batch as a whole is not checked).

    Raises
    ------
    ValueError
        If ``ys`` is not 3-D, or a prior has a batch axis of another length.
    """
    import dask.array as da

    from .._validate import as_flag
    from .kalman import FilterResult

    store_covs = as_flag(store_covs, "store_covs")
    ys, _ = _batch_blocks(ys)
    B, T, _ = ys.shape
    x0, P0 = _one_for_all(x0, 1), _one_for_all(P0, 2)
    x0s, P0s = _per_series(x0, B, 1, "x0"), _per_series(P0, B, 2, "P0")
    n = int(np.shape(x0)[-1])
    model = dict(F=np.asarray(F), Q=np.asarray(Q), H=np.asarray(H), R=np.asarray(R))
    if model["F"].ndim >= 2 and model["F"].shape[-1] != n:
        # at once, with the batch's B (a chunk's B and shape were named when it ran)
        want = model["F"].shape[-1]
        raise ValueError(f"x0 must have shape ({want},) or (B={B}, {want}), F's state size; "
                         f"got {np.shape(x0)}")
    if not (_is_dask(x0) or _is_dask(P0)):
        # the in-memory filter's checks, at once and with the batch's indices (a chunk named
        # its own, within the chunk, when it ran)
        from .kalman import _prior

        _prior(x0, P0, B, model["F"].shape[-1] if model["F"].ndim >= 2 else None)
    # each series' place in the batch, chunked as ys: a block's first is its chunk's offset
    places = da.from_array(np.arange(B, dtype=np.int64), chunks=(ys.chunks[0],))
    args: list[Any] = [ys, "btm", places, "b"]
    given: list[str] = []
    for name, prior, index in (("x0", x0s, "bi"), ("P0", P0s, "bij")):
        if prior is not None:
            prior = da.asarray(prior)
            args += [_whole_after_batch(prior, ys.chunks[0]), index]
            given.append(name)
    packed = da.blockwise(_block_filter, "b", *args, dtype=object, concatenate=False,
                          meta=np.empty((0,), dtype=object), x0=None if x0s is not None
                          else np.asarray(x0), P0=None if P0s is not None else np.asarray(P0),
                          given=tuple(given), model=model, store_covs=store_covs)
    means, covs, pmeans, pcovs, loglik, last_m, last_P = _fields(packed, [
        (T, n), (T, n, n) if store_covs else None, (T, n) if store_covs else None,
        (T, n, n) if store_covs else None, (), (n,), (n, n)])
    return FilterResult(means=means, covs=covs, pred_means=pmeans, pred_covs=pcovs,
                        loglik=loglik, last=Gaussian._trusted(last_m, last_P),
                        shared_covs=False)


def _block_smooth(*parts: np.ndarray, model: dict) -> tuple:
    from .kalman import FilterResult
    from .smoothers import rts_smooth as in_memory

    means, covs, pmeans, pcovs, loglik, last_m, last_P = (np.asarray(_one(p)) for p in parts)
    r = FilterResult(means, covs, pmeans, pcovs, loglik, Gaussian(last_m, last_P))
    s = in_memory(r, **model)
    return s.means, s.covs


def rts_smooth(result: FilterResult, *, F: Any, Q: Any) -> SmoothResult:
    """:func:`vistrack.filters.rts_smooth` on a :class:`FilterResult` of Dask arrays (from
    :func:`kalman_filter` here, with ``store_covs``), lazily, chunk by chunk.

    Raises
    ------
    ValueError
        If the result was filtered without its covariances.
    """
    import dask.array as da

    from .smoothers import SmoothResult

    if result.covs is None or result.pred_covs is None or result.pred_means is None:
        raise ValueError("rts_smooth needs the covariances: filter with store_covs=True")
    arrays: list[Any] = [result.means, result.covs, result.pred_means, result.pred_covs,
                         result.loglik, result.last.mean, result.last.cov]
    chunks = arrays[0].chunks[0]
    args: list[Any] = []
    for a, index in zip(arrays, ("bti", "btij", "bti", "btij", "b", "bi", "bij")):
        args += [_whole_after_batch(a, chunks), index]
    packed = da.blockwise(_block_smooth, "b", *args, dtype=object, concatenate=False,
                          meta=np.empty((0,), dtype=object),
                          model=dict(F=np.asarray(F), Q=np.asarray(Q)))
    _, T, n = result.means.shape
    means, covs = _fields(packed, [(T, n), (T, n, n)])
    return SmoothResult(means, covs, result)


def _chunk_summary(y: Any, first: int) -> dict:
    """What :func:`em` checks of a chunk before its first E-step, and how many of its series
    measured something at each step."""
    from .learn import _Observed

    y = _block(y)
    o = _Observed(y)
    bad = np.argwhere(np.isinf(y))
    inf = None if not len(bad) else ((int(bad[0][0]) + first,) + tuple(int(i) for i in bad[0][1:]),
                                     float(y[tuple(bad[0])]))
    return dict(measured=o.measured, partial=o.has_partial, count=o.count,
                move_count=o.move_count, inf=inf)


def _chunk_sums(y: Any, x0: Any, P0: Any, p: dict, learn: tuple[str, ...],
                H: np.ndarray | None, Fn: np.ndarray | None = None) -> dict:
    """One chunk's E-step under the model ``p`` (its prior ``x0``, ``P0``): the
    log-likelihood and the sums of the M-step for ``learn``, summed over the chunk's series;
    given ``H``, only the expected ``v v'`` of ``R``'s M-step under that ``H``; given ``Fn``
    (the transitions' ``F``, :func:`~vistrack.filters.learn._transitions`), only the expected
    ``w w'`` of ``Q``'s under it. ``Q``'s sums are added term by
    term under a known ``F`` (the model's, where ``F`` is not learned), never from
    ``transition_sums``, whose terms grow with the state's distance from the origin and
    cancel (see :mod:`vistrack.filters.learn`)."""
    from .learn import _EStep, _Observed, _shared_x0_sums, _transitions

    y = _block(y)
    p = dict(p, x0=np.asarray(x0), P0=np.asarray(P0))
    e = _EStep(_Observed(y), p)
    if H is not None:
        return {"V": e.vv(H)}
    if Fn is not None:
        return {"A": e.process_noise_sums(Fn)}
    out: dict[str, Any] = {"ll": e.ll}
    if "F" in learn:
        out["S"] = e.transition_sums()
    elif "Q" in learn:
        out["A"] = e.process_noise_sums(_transitions(p["F"], y.shape[1]))
    if "H" in learn:
        out["H"] = e.H_sums()
    elif "R" in learn:
        out["V"] = e.vv(p["H"])
    if {"x0", "P0"} & set(learn):
        # over the series measured at some step: one never measured says nothing of the
        # prior (learn._prior_step)
        seen = e.o.seen
        ms, Ps, _, _ = e.smoothed
        # (the chunk's x0 of every series, beside the measured ones' means: (1, n) against
        # (2, n) broadcast, a wrong P0 without a word, or numpy's broadcast error)
        d = ms[seen, 0] - (p["x0"][seen] if p["x0"].ndim == 2 else p["x0"][None])
        P = Ps[0, 0] * seen.sum() if len(Ps) == 1 else Ps[seen, 0].sum(axis=0)
        out["d"], out["dd"], out["P"], out["n"] = d.sum(axis=0), d.T @ d, P, int(seen.sum())
        if p["P0"].ndim == 3:
            out["W"], out["Wm"], out["N"] = _shared_x0_sums(p["P0"][seen], ms[seen, 0])
    return out


def _add(parts: list) -> Any:
    """The sum of the chunks' sums (dicts of arrays, tuples of arrays and floats)."""
    first = parts[0]
    if isinstance(first, dict):
        return {k: _add([q[k] for q in parts]) for k in first}
    if isinstance(first, tuple):
        return tuple(_add([q[i] for q in parts]) for i in range(len(first)))
    total = first
    for q in parts[1:]:
        total = total + q
    return total


class _Summed:
    """An E-step over every chunk (the interface of :class:`vistrack.filters.learn._EStep`):
    the chunks' log-likelihoods and sums, computed where the chunks are and added here."""

    def __init__(self, chunks: list, p: dict, learn: tuple[str, ...], count: np.ndarray,
                 move_count: np.ndarray) -> None:
        self.chunks, self.p, self.count, self.move_count = chunks, p, count, move_count
        self.sums = self._pass(learn, None)
        self.ll = float(self.sums["ll"])

    def _pass(self, learn: tuple[str, ...], H: np.ndarray | None,
              Fn: np.ndarray | None = None) -> dict:
        """:func:`_chunk_sums` of every chunk, computed where the chunks are, added. Each
        chunk has its prior: this iteration's where shared (``p``'s, which the M-step may
        have changed), else the chunk's part of the one given per series."""
        import dask

        x0, P0 = self.p["x0"], self.p["P0"]
        model = {k: v for k, v in self.p.items() if k not in ("x0", "P0")}
        parts = dask.compute(*[
            dask.delayed(_chunk_sums)(y, c0 if x0 is None else x0, cP if P0 is None else P0,
                                      model, learn, H, Fn)
            for y, c0, cP in self.chunks])
        return _add(list(parts))

    def transition_sums(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.sums["S"]

    def process_noise_sums(self, Fn: np.ndarray) -> np.ndarray:
        if "A" in self.sums:  # summed under the model's F, not learned
            return self.sums["A"]
        # F learned: a second pass, with this iteration's F (the terms of the transition
        # sums would cancel far from the origin), as R's with a new H
        return self._pass((), None, Fn)["A"]

    def H_sums(self) -> tuple[np.ndarray, np.ndarray]:
        return self.sums["H"]

    def vv(self, H: np.ndarray) -> np.ndarray:
        if "V" in self.sums:  # computed with the model's H, not learned
            return self.sums["V"]
        return self._pass((), H)["V"]  # H learned: a second pass, with this iteration's H

    def R_count(self) -> np.ndarray:
        return self.count

    def Q_count(self) -> np.ndarray:
        return self.move_count

    def prior(self, learn: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
        from .learn import _shared_x0

        s, B = self.sums, self.sums["n"]  # (the series measured at some step)
        c, P0 = self.p["x0"], self.p["P0"]
        x0 = c
        if "x0" in learn:  # (a shared x0: checked by em)
            x0 = _shared_x0(s["W"], s["Wm"], s["N"], c) if "W" in s else c + s["d"] / B
        if "P0" in learn:  # sum (m - x0)(m - x0)' from the sums around the old x0
            dd = s["dd"]
            if "x0" in learn:
                delta = c - x0
                dd = (dd + np.outer(s["d"], delta) + np.outer(delta, s["d"])
                      + B * np.outer(delta, delta))
            P0 = (s["P"] + dd) / B
        return x0, P0


def _chunk_em(y: Any, x0: Any, P0: Any, p: dict, learn: tuple[str, ...], Q_form: str,
              R_form: str, tol: float, max_iter: int, first: int = 0) -> tuple:
    """One fit per series of a chunk whose first series is ``first`` of the batch, as
    :func:`vistrack.filters.em` with ``pooled=False`` fits them in memory; ``loglik`` padded
    with NaN to ``max_iter + 1``."""
    from .learn import _fit_each

    p = dict(p, x0=np.asarray(x0), P0=np.asarray(P0))
    f = _fit_each(_block(y), p, learn, Q_form, R_form, tol, max_iter, None, first)
    ll = np.full((f.loglik.shape[0], max_iter + 1), np.nan)
    ll[:, :f.loglik.shape[1]] = f.loglik
    return (f.F, f.Q, f.H, f.R, f.x0, f.P0, np.asarray(f.q, dtype=np.float64),
            np.asarray(f.r, dtype=np.float64), ll, np.asarray(f.iterations, dtype=np.int64),
            np.asarray(f.converged, dtype=bool))


def em(ys: Any, *, F: Any, Q: Any, H: Any, R: Any, x0: Any, P0: Any, learn: tuple[str, ...],
       Q_form: str, R_form: str, pooled: bool, tol: float, max_iter: int,
       progress: Any) -> FitResult:
    """:func:`vistrack.filters.em` on a Dask array ``(B, T, m)`` chunked along the batch
    axis (``learn``, the forms, ``tol`` and ``max_iter`` already checked).

    Pooled, each iteration runs the E-step on every chunk where the chunk is (one
    ``dask.compute``; two when ``H`` and ``R``, or ``F`` and ``Q``, are both learned: the
    second under the new ``H`` or ``F``) and adds the chunks' sums:
    only the sums, a few ``(T, n, n)`` arrays a chunk, travel, and the parameters returned
    are numpy arrays. The measurements are read (or generated) again at each iteration:
    ``ys.persist()`` first where the cluster can hold them. The sums are added in another
    order than in memory, so the fit equals the in-memory one to rounding, not to the bit.

    With ``pooled=False`` the result is lazy: a :class:`FitResult` of Dask arrays with a
    batch axis, each chunk's series fitted one by one where the chunk is, exactly as in
    memory (``loglik`` padded with NaN to ``max_iter + 1`` iterations). What :func:`em`
    refuses of the model alone is refused here at once; what it refuses of a series' data
    (a component it never measures, with ``H`` learned) when that series' chunk is
    computed.

    Raises
    ------
    ValueError
        As :func:`vistrack.filters.em`, and pooled, if a prior learned is given per series
        (learn it shared, or per series with ``pooled=False``); with ``pooled=False`` and a
        ``progress`` stream (each chunk is fitted where it is computed).
    """
    import dask

    from .._validate import check_linear_gaussian, check_prior
    from .learn import _check_em, _check_steps, _fit, _state_size

    ys, spans = _batch_blocks(ys)
    B, T, m = ys.shape
    if T == 0:
        raise ValueError(f"ys must have at least one step; got shape {ys.shape}")
    _check_steps(T, learn)
    # the prior's state size, where x0 and P0 agree on one, as em in memory: a 3 x 3 F for a
    # 2-state prior is named as F, not Q
    n = _state_size(np.shape(F)[-1] if np.ndim(F) >= 2 else 0, x0, P0)
    check_linear_gaussian(F, Q, H, R, n, m, T)
    x0, P0 = (x0 if _is_dask(x0) else np.asarray(x0, dtype=np.float64),
              P0 if _is_dask(P0) else np.asarray(P0, dtype=np.float64))
    x0, P0 = _one_for_all(x0, 1), _one_for_all(P0, 2)
    x0s, P0s = _per_series(x0, B, 1, "x0"), _per_series(P0, B, 2, "P0")
    # a prior shared by every series is small: computed here (a Dask one, learned, came
    # back as Dask, its graph one iteration longer at each, and numpy's eigh met it)
    if x0s is None and _is_dask(x0):
        x0 = np.asarray(x0.compute(), dtype=np.float64)
    if P0s is None and _is_dask(P0):
        P0 = np.asarray(P0.compute(), dtype=np.float64)
    if np.shape(x0)[-1] != n or np.shape(P0)[-2:] != (n, n):
        raise ValueError(f"x0 must have shape ({n},) or (B, {n}) and P0 ({n}, {n}) or "
                         f"(B, {n}, {n}); got {np.shape(x0)} and {np.shape(P0)}")
    if not (_is_dask(x0) or _is_dask(P0)):
        # em's checks in memory, at once and with the batch's indices: a chunk's E-step
        # named a series by its place in the chunk, and only once computed
        check_prior(x0, P0, n, series=B)
    p = {k: np.asarray(v, dtype=np.float64) for k, v in (("F", F), ("Q", Q), ("H", H),
                                                           ("R", R))}
    blocks = ys.to_delayed().ravel()
    chunks = [(y, x0 if x0s is None else x0s[a:b], P0 if P0s is None else P0s[a:b])
              for y, (a, b) in zip(blocks, spans)]
    if not pooled:
        if progress is not None:
            raise ValueError("progress is not available with pooled=False on a Dask array: "
                             "each chunk is fitted where it is computed")
        # the model's own faults now (as if every component were measured at every step);
        # a series' data are checked where its chunk is fitted
        _check_em(np.ones(m, bool), False, dict(p, x0=x0, P0=P0), learn, Q_form, R_form)
        return _lazy_fits(chunks, spans, p, learn, Q_form, R_form, tol, max_iter, n, m, T)
    for name, prior in (("x0", x0s), ("P0", P0s)):
        if name in learn and prior is not None:
            raise ValueError(f"learning {name} pooled on a Dask array needs one {name} for all "
                             f"series; got one per series (learn it per series with "
                             f"pooled=False)")
    summary = dask.compute(*[dask.delayed(_chunk_summary)(y, a)
                             for y, (a, _) in zip(blocks, spans)])
    for s in summary:
        if s["inf"] is not None:
            idx, value = s["inf"]
            raise ValueError(f"ys must be finite or NaN (missing); ys{list(idx)} = {value}")
    measured = np.any([s["measured"] for s in summary], axis=0)
    if not measured.any():
        raise ValueError("ys has no measurement: every value is NaN")
    partial = any(s["partial"] for s in summary)
    count = _add([s["count"] for s in summary])
    move_count = _add([s["move_count"] for s in summary])
    _check_em(measured, partial, dict(p, x0=x0, P0=P0), learn, Q_form, R_form)
    # a prior given per series stays with the chunks (None here: see _Summed._pass)
    p0: dict[str, Any] = dict(p, x0=x0 if x0s is None else None, P0=P0 if P0s is None else None)

    def estep(params: dict, now: tuple[str, ...]) -> _Summed:
        return _Summed(chunks, params, now, count, move_count)

    fit = _fit(estep, T, p0, learn, Q_form, R_form, tol, max_iter, progress)
    # a prior given per series and not learned is returned as given
    return replace(fit, x0=fit.x0 if x0s is None else x0s, P0=fit.P0 if P0s is None else P0s)


def _lazy_fits(chunks: list, spans: list, p: dict, learn: tuple[str, ...], Q_form: str,
               R_form: str, tol: float, max_iter: int, n: int, m: int, T: int) -> FitResult:
    """``em(..., pooled=False)`` on the chunks, lazily: a :class:`FitResult` of Dask arrays."""
    import dask
    import dask.array as da

    from .learn import FitResult

    def shape(name: str, form: str = "full") -> tuple[int, ...]:
        given = p[name].shape
        return given[-2:] if name in learn and form != "scaled" else given

    per_fit = [shape("F"), shape("Q", Q_form), shape("H"), shape("R", R_form), (n,), (n, n),
               (), (), (max_iter + 1,), (), ()]
    dtypes = [np.float64] * 9 + [np.int64, bool]
    fields: list[list[Any]] = [[] for _ in per_fit]
    for (y, x0, P0), (a, b) in zip(chunks, spans):
        out = dask.delayed(_chunk_em, nout=len(per_fit))(y, x0, P0, p, learn, Q_form, R_form,
                                                         tol, max_iter, a)
        for i, (s, dt) in enumerate(zip(per_fit, dtypes)):
            fields[i].append(da.from_delayed(out[i], (b - a,) + s, dtype=dt))
    F, Q, H, R, x0, P0, q, r, ll, its, conv = (da.concatenate(f) for f in fields)
    return FitResult(F=F, Q=Q, H=H, R=R, x0=x0, P0=P0, q=q, r=r, loglik=ll, iterations=its,
                     converged=conv)

"""Batches larger than memory: :func:`~vistrack.filters.kalman_filter` and
:func:`~vistrack.filters.rts_smooth` on a Dask array chunked along the batch axis.

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
- Dask is imported here only (``pip install vistrack[dask]``); ``import vistrack`` does not
  import it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..types import Gaussian

if TYPE_CHECKING:
    from .kalman import FilterResult
    from .smoothers import SmoothResult

__all__ = ["kalman_filter", "rts_smooth"]


def _batch_blocks(ys: Any) -> tuple[Any, list[tuple[int, int]]]:
    if ys.ndim != 3:
        raise ValueError(f"ys as a Dask array must have shape (B, T, m); got {ys.shape}")
    ys = ys.rechunk({1: -1, 2: -1})
    edges = np.cumsum((0,) + ys.chunks[0])
    return ys, [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]


def _per_series(p: Any, B: int, ndim_shared: int, name: str) -> Any:
    """A prior shared by all series (None), or one per series (its batch-first array)."""
    if np.ndim(p) == ndim_shared:
        return None
    if np.ndim(p) != ndim_shared + 1 or np.shape(p)[0] != B:
        raise ValueError(f"{name} must be shared by the series or have the batch axis first "
                         f"(B = {B}); got shape {np.shape(p)}")
    return p


def _chunk_filter(y: np.ndarray, x0: Any, P0: Any, model: dict, store_covs: bool) -> tuple:
    from .kalman import kalman_filter as in_memory

    r = in_memory(np.asarray(y), x0=np.asarray(x0), P0=np.asarray(P0), store_covs=store_covs,
                  **model)
    # the last state is a view of the means: copied, so that a result that needs only it
    # does not keep every chunk's means alive
    return (r.means, r.covs, r.pred_means, r.pred_covs, r.loglik, np.array(r.last.mean),
            np.array(r.last.cov))


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
    import dask
    import dask.array as da

    from .kalman import FilterResult

    ys, spans = _batch_blocks(ys)
    B, T, _ = ys.shape
    x0s, P0s = _per_series(x0, B, 1, "x0"), _per_series(P0, B, 2, "P0")
    n = int(np.shape(x0)[-1])
    model = dict(F=np.asarray(F), Q=np.asarray(Q), H=np.asarray(H), R=np.asarray(R))
    fields: list[list[Any]] = [[] for _ in range(7)]
    for block, (a, b) in zip(ys.to_delayed().ravel(), spans):
        k = b - a
        out = dask.delayed(_chunk_filter, nout=7)(
            block, x0 if x0s is None else x0s[a:b], P0 if P0s is None else P0s[a:b],
            model, store_covs)
        shapes = [(k, T, n), (k, T, n, n) if store_covs else None,
                  (k, T, n) if store_covs else None, (k, T, n, n) if store_covs else None,
                  (k,), (k, n), (k, n, n)]
        for i, shape in enumerate(shapes):
            if shape is not None:
                fields[i].append(da.from_delayed(out[i], shape, dtype=np.float64))
    cat: list[Any] = [da.concatenate(f, axis=0) if f else None for f in fields]
    return FilterResult(means=cat[0], covs=cat[1], pred_means=cat[2], pred_covs=cat[3],
                        loglik=cat[4], last=Gaussian._trusted(cat[5], cat[6]),
                        shared_covs=False)


def _chunk_smooth(parts: tuple, model: dict) -> tuple:
    from .kalman import FilterResult
    from .smoothers import rts_smooth as in_memory

    means, covs, pmeans, pcovs, loglik, last_m, last_P = (np.asarray(p) for p in parts)
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
    import dask
    import dask.array as da

    from .smoothers import SmoothResult

    if result.covs is None or result.pred_covs is None or result.pred_means is None:
        raise ValueError("rts_smooth needs the covariances: filter with store_covs=True")
    arrays: list[Any] = [result.means, result.covs, result.pred_means, result.pred_covs,
                         result.loglik, result.last.mean, result.last.cov]
    chunks = arrays[0].chunks[0]
    arrays = [a.rechunk({0: chunks, **{i: -1 for i in range(1, a.ndim)}}) for a in arrays]
    blocks = [a.to_delayed().reshape(len(chunks), -1)[:, 0] for a in arrays]
    model = dict(F=np.asarray(F), Q=np.asarray(Q))
    means, covs = [], []
    _, T, n = result.means.shape
    for k, parts in zip(chunks, zip(*blocks)):
        out = dask.delayed(_chunk_smooth, nout=2)(parts, model)
        means.append(da.from_delayed(out[0], (k, T, n), dtype=np.float64))
        covs.append(da.from_delayed(out[1], (k, T, n, n), dtype=np.float64))
    return SmoothResult(da.concatenate(means), da.concatenate(covs), result)

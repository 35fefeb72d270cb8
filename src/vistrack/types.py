"""Core value types shared by every stage of vistrack."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Gaussian"]


@dataclass(frozen=True, slots=True)
class Gaussian:
    """A batch of Gaussian densities ``N(mean, cov)``.

    Parameters
    ----------
    mean : ndarray, shape (..., n)
        Means; the leading dimensions index the batch (one Gaussian is a batch of one).
    cov : ndarray, shape (..., n, n)
        Covariances, with the same leading dimensions as ``mean``.

    Examples
    --------
    >>> import numpy as np
    >>> g = Gaussian(np.zeros((3, 2)), np.broadcast_to(np.eye(2), (3, 2, 2)))
    >>> g.batch_shape, g.ndim
    ((3,), 2)
    """

    mean: np.ndarray
    cov: np.ndarray

    def __post_init__(self) -> None:
        mean = np.asarray(self.mean, dtype=np.float64)
        cov = np.asarray(self.cov, dtype=np.float64)
        if mean.ndim < 1:
            raise ValueError(f"Gaussian mean must have shape (..., n); got {mean.shape}")
        n = mean.shape[-1]
        if cov.shape != mean.shape + (n,):
            raise ValueError(
                f"Gaussian cov must have shape mean.shape + (n,) = {mean.shape + (n,)}; "
                f"got {cov.shape}"
            )
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", cov)

    @classmethod
    def _trusted(cls, mean: np.ndarray, cov: np.ndarray) -> "Gaussian":
        """Wrap float64 arrays already known to have matching shapes (kernel outputs)."""
        g = object.__new__(cls)
        object.__setattr__(g, "mean", mean)
        object.__setattr__(g, "cov", cov)
        return g

    @property
    def ndim(self) -> int:
        """Dimension ``n`` of the state."""
        return int(self.mean.shape[-1])

    @property
    def batch_shape(self) -> tuple[int, ...]:
        """The leading (batch) dimensions."""
        return tuple(self.mean.shape[:-1])

    def __getitem__(self, index: object) -> "Gaussian":
        """Index the batch: ``g[mask]``, ``g[3]``, ``g[:10]``."""
        return Gaussian(self.mean[index], self.cov[index])

    def __len__(self) -> int:
        if self.mean.ndim == 1:
            raise TypeError("a single Gaussian (mean of shape (n,)) has no len()")
        return int(self.mean.shape[0])

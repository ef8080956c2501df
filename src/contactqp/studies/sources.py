r"""Sources of gap fields: sample ``k`` of a study, the same whoever computes it.

Gaussian gap fields (:class:`GaussianGapField`) have the squared-exponential covariance

.. math::

    C(x, x') = \sigma^2 \exp\!\Big(-\frac{\|x - x'\|^2}{2 \ell^2}\Big)

(amplitude :math:`\sigma`, correlation length :math:`\ell`); sample ``k`` is
``mean + L z_k`` with ``L L^T = C`` and ``z_k`` standard normal drawn from
``SeedSequence(seed, spawn_key=(k,))``. :class:`GapSamples` gives the rows of an array,
:func:`load_gap_samples` those of a file.

A source has ``n_available`` (None: unbounded), ``realisations(indices)`` (shape
``(len(indices), m)``, m) and ``describe()`` (what identifies it in a store).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..core.model import MAX_MAGNITUDE, finite_array
from ..errors import FileFormatError, InvalidInputError
from .fingerprint import digest
from .threads import single_threaded_blas

__all__ = ["GapSamples", "GaussianGapField", "load_gap_samples"]


class GaussianGapField:
    """Gaussian random gap fields with squared-exponential covariance (see the module notes).

    Parameters
    ----------
    coordinates : array_like, shape (m, d)
        Position of each gap (m).
    amplitude : float
        Standard deviation ``sigma`` (m), >= 0.
    correlation_length : float
        ``ell`` (m), > 0.
    mean : float or array_like, shape (m,)
        Nominal gap field (m).
    seed : int
        Root of the per-sample seed sequences.
    """

    def __init__(
        self,
        coordinates: ArrayLike,
        amplitude: float,
        correlation_length: float,
        mean: ArrayLike = 0.0,
        seed: int = 0,
    ) -> None:
        self.coordinates = finite_array(coordinates, "coordinates", 2)
        m = len(self.coordinates)
        if not (np.isfinite(amplitude) and 0 <= amplitude <= MAX_MAGNITUDE):
            raise InvalidInputError(
                f"amplitude must be >= 0 and at most {MAX_MAGNITUDE:g} m, got {amplitude!r}"
            )
        if not (np.isfinite(correlation_length) and 0 < correlation_length <= MAX_MAGNITUDE):
            raise InvalidInputError(
                f"correlation_length must be > 0 and at most "
                f"{MAX_MAGNITUDE:g} m, got {correlation_length!r}"
            )
        self.amplitude, self.correlation_length = float(amplitude), float(correlation_length)
        self.mean = np.broadcast_to(finite_array(np.atleast_1d(mean), "mean", 1), (m,)).copy()
        if isinstance(seed, bool) or int(seed) != seed or seed < 0:
            raise InvalidInputError(f"seed must be an integer >= 0, got {seed!r}")
        self.seed = int(seed)
        self._factor: np.ndarray | None = None

    @property
    def n_available(self) -> None:
        """None: any number of samples."""
        return None

    @property
    def covariance(self) -> np.ndarray:
        """``C`` (m^2), shape (m, m)."""
        diff = self.coordinates[:, None, :] - self.coordinates[None, :, :]
        squared = np.einsum("ijk,ijk->ij", diff, diff)
        return self.amplitude**2 * np.exp(-squared / (2.0 * self.correlation_length**2))

    def _square_root(self) -> np.ndarray:
        """``L`` with ``L L^T = C``, from the eigenvectors (``C`` is often numerically singular).

        The eigenvectors of clustered eigenvalues change with the BLAS threads (measured: 1e-6
        of sigma on the riveting grid), so ``L`` is computed on one thread, and once: pickling
        (to workers, a Dask cluster) carries it, so every worker draws the same fields.
        """
        if self._factor is None:
            with single_threaded_blas():
                values, vectors = np.linalg.eigh(self.covariance)
            self._factor = np.ascontiguousarray(vectors * np.sqrt(np.clip(values, 0.0, None)))
        return self._factor

    def __getstate__(self):
        self._square_root()
        return self.__dict__

    def realisations(self, indices: Iterable[int]) -> np.ndarray:
        """Gap fields of the samples ``indices`` (m), shape (len(indices), m).

        Each sample is drawn and transformed on its own, so sample ``k`` is bitwise the same in
        any batch: a product of the batch with ``L`` lets BLAS choose another kernel and
        summation order for another batch size (measured: 1 ulp, 5e-20 m, between ``[k]``
        alone and inside a batch of 2 or more).
        """
        factor = self._square_root()
        indices = list(indices)
        fields = np.empty((len(indices), len(self.mean)))
        for row, k in zip(fields, indices, strict=True):
            stream = np.random.SeedSequence(self.seed, spawn_key=(int(k),))
            row[:] = self.mean + _fixed_order_product(
                factor, np.random.default_rng(stream).standard_normal(len(self.mean))
            )
        return fields

    def describe(self) -> dict:
        return {
            "type": "gaussian",
            "amplitude": self.amplitude,
            "correlation_length": self.correlation_length,
            "seed": self.seed,
            "digest": digest(self.coordinates, self.mean),
        }


def _fixed_order_product(matrix: np.ndarray, vector: np.ndarray, rows: int = 256) -> np.ndarray:
    """``matrix @ vector`` summed in an order fixed by the shapes alone.

    Each entry is numpy's pairwise sum of one row's products, independent of BLAS (its
    kernel, threads and the alignment of the arrays); blocks of ``rows`` bound the temporary.
    """
    out = np.empty(len(matrix))
    for start in range(0, len(matrix), rows):
        block = matrix[start : start + rows]
        np.add.reduce(block * vector, axis=1, out=out[start : start + rows])
    return out


class GapSamples:
    """Gap fields given as an array, one realisation per row (m), shape (N, m)."""

    def __init__(self, samples: ArrayLike) -> None:
        self.samples = finite_array(samples, "gap samples", 2)

    @property
    def n_available(self) -> int:
        """Number of realisations ``N``."""
        return len(self.samples)

    def realisations(self, indices: Iterable[int]) -> np.ndarray:
        """Rows ``indices``, shape (len(indices), m)."""
        return self.samples[np.asarray(indices, dtype=int)]

    def describe(self) -> dict:
        return {"type": "array", "shape": list(self.samples.shape), "digest": digest(self.samples)}


def load_gap_samples(path: str | os.PathLike[str]) -> GapSamples:
    """Realisations from a file: ``.npy``, ``.npz`` (its only array), or ``.csv`` / ``.txt``
    (comma-separated, one row per sample).

    Values in metres, shape (N, m). A missing, truncated or corrupt file is a one-line
    :class:`~contactqp.errors.FileFormatError`.
    """
    from ..io.arrays import read_csv_array, read_numpy_array

    path = Path(path)
    if not path.is_file():
        raise FileFormatError(f"{path}: gap samples file not found")
    if path.suffix not in (".npy", ".npz", ".csv", ".txt"):
        raise FileFormatError(f"{path}: gap samples must be .npy, .npz or .csv (or .txt)")
    data = read_numpy_array(path) if path.suffix in (".npy", ".npz") else read_csv_array(path)
    try:
        return GapSamples(data)
    except InvalidInputError as exc:
        raise FileFormatError(f"{path}: {exc}") from None

"""The seam through which methods reach ``W``: products, diagonals, blocks, factorisations.

A method asks its matrix only for what it needs:

* ``W @ x`` (one vector or the columns of a 2-D array),
* the diagonal, or the ``d x d`` blocks on the diagonal (one per contact),
* dense blocks ``W[rows][:, cols]`` on index sets (the normal block, a free set),
* the Cholesky factor of a principal block (:meth:`Operator.cholesky`), cached on the operator
  so that a check and the method that needs the factor share one factorisation,
* ``shape``;

and, where the operator's physics gives them (an FFT half-space does), two aids of iterative
methods: :meth:`Operator.coarsening` (the same body on a coarser lattice, for a start from a
coarse solve) and :meth:`Operator.preconditioner` (an approximate inverse of its principal
blocks). Both are None by default, and a method runs without them.

:func:`as_operator` wraps a numpy array (:class:`DenseOperator`) or a scipy.sparse matrix
(:class:`SparseOperator`) and passes an :class:`Operator` through unchanged, so a method written
against this interface accepts either, and an operator that never forms its matrix (an FFT
half-space, the Schur complement of a sparse stiffness) by subclassing :class:`Operator` and
implementing the three abstract methods. Methods whose algorithm is built on the stored entries
(sparsity patterns, matrices handed to an external QP backend) ask for :attr:`Operator.matrix`,
which such an operator refuses with :class:`~contactqp.errors.UnsupportedProblemError`.
"""

from __future__ import annotations

import functools
import sys
from abc import ABC, abstractmethod
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InvalidInputError, NotPositiveDefiniteError, UnsupportedProblemError

if TYPE_CHECKING:
    import scipy.sparse as sp
    from typing_extensions import TypeIs

__all__ = [
    "BlockFactor",
    "Coarsening",
    "DenseOperator",
    "Operator",
    "PSD_SHIFT",
    "SparseOperator",
    "SymmetricDenseOperator",
    "as_operator",
    "is_sparse",
    "symmetric_product",
]

#: Diagonal shift, relative to the unit diagonal of the Jacobi-scaled matrix, accepted as
#: rounding of a positive semidefinite matrix. Matrices written with 6 significant digits
#: (Siconos text files) are perturbed by ~5e-7 per entry; the scaled granular-flow file has
#: eigenvalues down to -2.7e-6.
PSD_SHIFT = 1e-5
#: Uniform shift, relative to the largest diagonal entry, that lets a singular (semidefinite)
#: block be factored.
SINGULAR_SHIFT = 1e-11
_FACTORS_KEPT = 2


def is_sparse(value: object) -> TypeIs[sp.sparray | sp.spmatrix]:
    """``scipy.sparse.issparse(value)``, without importing scipy.sparse.

    No value is a sparse matrix or array before :mod:`scipy.sparse` is imported, so the dense
    path never pays for that import (a third of a second); scipy.sparse and scipy.linalg are
    imported by the functions that use them.
    """
    sparse = sys.modules.get("scipy.sparse")
    return sparse is not None and sparse.issparse(value)


@dataclass(frozen=True)
class BlockFactor:
    """Lower Cholesky factor ``L L^T = W[index][:, index] + diag(shift)`` of a principal block.

    Attributes
    ----------
    index : numpy.ndarray of int
        The block's indices, increasing.
    lower : numpy.ndarray, shape (k, k)
        ``L``; read only, shared by everyone who asked for this block.
    uniform, relative : float
        The diagonal shift is ``uniform + relative * W_ii``: both 0 for a definite block,
        ``uniform`` alone (:data:`SINGULAR_SHIFT` of the largest diagonal entry) for a singular
        one, and ``relative`` = :data:`PSD_SHIFT` for one that is semidefinite only to
        rounding. A method bordering the factor with more indices adds the same shift to them.
    """

    index: np.ndarray
    lower: np.ndarray
    uniform: float = 0.0
    relative: float = 0.0

    @property
    def shifted(self) -> bool:
        """True when the block was shifted to be factored."""
        return self.uniform > 0 or self.relative > 0

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve the (shifted) block's system for ``rhs`` (shape (k,) or (k, j))."""
        import scipy.linalg

        return scipy.linalg.cho_solve((self.lower.T, False), rhs, check_finite=False)


def _indices(selection, n: int):
    """``selection`` (None: all, a slice, a bool mask or integer indices) as a slice or an int
    array."""
    if selection is None:
        return slice(None)
    if isinstance(selection, slice):
        return selection
    index = np.asarray(selection)
    if index.dtype == bool:
        return np.flatnonzero(index)
    return index.astype(np.intp, copy=False)


def _everything(selection) -> bool:
    return isinstance(selection, slice) and selection == slice(None)


def _cholesky(block: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor of the lower triangle of ``block``, in place when ``block`` is
    C-contiguous: ``block.T`` is then the same memory in LAPACK's column order, whose upper
    triangle holds ``block``'s lower one, and its upper factor ``U`` is ``L^T`` (no copy)."""
    import scipy.linalg

    return scipy.linalg.cholesky(block.T, lower=False, overwrite_a=True, check_finite=False).T


@dataclass(frozen=True)
class Coarsening:
    """``W`` of the same body on a coarser lattice, and the maps between the two lattices.

    Attributes
    ----------
    operator : Operator
        The coarse ``W``.
    restrict : callable
        Values at the fine points (a separation, m), shape (n,), to the coarse points: their
        mean over the points merged into each.
    prolong : callable
        Forces at the coarse points (N) to the fine points: each shared evenly among the
        points merged into it, so the total is kept.
    """

    operator: Operator
    restrict: Callable[[np.ndarray], np.ndarray]
    prolong: Callable[[np.ndarray], np.ndarray]


class Operator(ABC):
    """``W`` as a method sees it (see the module notes); subclasses implement three methods.

    Attributes
    ----------
    shape : tuple of int
        ``(n, n)``.
    """

    shape: tuple[int, int]

    def __init__(self, shape):
        self.shape = (int(shape[0]), int(shape[1]))
        self._factors: OrderedDict[bytes, BlockFactor] = OrderedDict()

    @abstractmethod
    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        """``W @ x`` for ``x`` of shape (n,) or (n, k), as an ndarray of the same shape."""

    @abstractmethod
    def diagonal(self) -> np.ndarray:
        """The diagonal of ``W``, shape (n,)."""

    @abstractmethod
    def block(self, rows=None, cols=None) -> np.ndarray:
        """Dense ``W[rows][:, cols]``; each selection is None (all), a slice, a bool mask or
        indices (then in their order)."""

    @property
    def matrix(self) -> np.ndarray | sp.csr_matrix | sp.csr_array:
        """The explicit matrix, for methods built on its stored entries.

        Raises
        ------
        UnsupportedProblemError
            For an operator that does not form its matrix.
        """
        raise UnsupportedProblemError(
            f"this method needs W as an explicit matrix; {type(self).__name__} does not form one"
        )

    def diagonal_blocks(self, size: int) -> np.ndarray:
        """The ``size x size`` blocks on the diagonal (one per contact), shape (n / size, s, s)."""
        count = self.shape[0] // size
        return (
            np.stack(
                [
                    self.block(
                        np.arange(i * size, (i + 1) * size), np.arange(i * size, (i + 1) * size)
                    )
                    for i in range(count)
                ]
            )
            if count
            else np.zeros((0, size, size))
        )

    def coarsening(self) -> Coarsening | None:
        """The same body on a coarser lattice, or None (the default: no lattice known)."""
        return None

    def preconditioner(self) -> Callable[[np.ndarray, np.ndarray], np.ndarray] | None:
        """``M(x, on)``: a symmetric positive definite approximation of
        ``W[on][:, on]^-1 x[on]`` for a vector ``x`` and a boolean mask ``on`` (its entries off
        ``on`` are not used), or None (the default: none known)."""
        return None

    def cholesky(self, index) -> BlockFactor:
        """The Cholesky factor of the principal block on ``index`` (cached: shared by callers).

        A block that is not numerically definite is factored with a shift (see
        :class:`BlockFactor`): first :data:`SINGULAR_SHIFT` times the largest diagonal entry
        (a semidefinite block), then, if the Jacobi-scaled block plus :data:`PSD_SHIFT` ``I``
        has a factor, that shift (semidefinite to rounding). The last factors made are kept.

        Parameters
        ----------
        index : array_like of int or bool mask
            The block's indices (sorted into increasing order).

        Raises
        ------
        NotPositiveDefiniteError
            If the block is not positive semidefinite even to :data:`PSD_SHIFT`: a negative
            diagonal entry, or no factor of the Jacobi-scaled block plus that shift.
        """
        index = np.sort(np.asarray(_indices(index, self.shape[0])))
        key = index.tobytes()
        factor = self._factors.get(key)
        if factor is None:
            factor = self._factorise(index)
            self._factors[key] = factor
            if len(self._factors) > _FACTORS_KEPT:
                self._factors.popitem(last=False)
        else:
            self._factors.move_to_end(key)
        return factor

    def singular_shift(self) -> float:
        """:data:`SINGULAR_SHIFT` times the largest diagonal entry (the tiny finite number if
        none is positive)."""
        return SINGULAR_SHIFT * max(
            float(np.max(self.diagonal(), initial=0.0)), np.finfo(float).tiny
        )

    def _factorise(self, index: np.ndarray) -> BlockFactor:
        try:  # factored in place: the block is fetched again if it is not definite
            return BlockFactor(index, _cholesky(self.block(index, index)))
        except np.linalg.LinAlgError:
            pass
        block = self.block(index, index)
        diagonal = block.diagonal().copy()
        uniform = self.singular_shift()
        try:
            shifted = block.copy()
            shifted[np.diag_indices_from(shifted)] += uniform
            return BlockFactor(index, _cholesky(shifted), uniform)
        except np.linalg.LinAlgError:
            pass
        where = (
            f"the {index.size}x{index.size} principal block on indices "
            f"{_describe(index)} is not positive semidefinite"
        )
        if np.any(diagonal < 0):
            i = int(np.argmin(diagonal))
            raise NotPositiveDefiniteError(
                f"{where}: diagonal entry {int(index[i])} is {diagonal[i]:.3g} < 0"
            )
        zero = diagonal == 0
        if np.any(block[zero]):
            raise NotPositiveDefiniteError(
                f"{where}: a row with a zero diagonal entry has nonzero off-diagonal entries"
            )
        scale = 1.0 / np.sqrt(np.where(zero, 1.0, diagonal))
        scaled = scale[:, None] * block * scale[None, :]
        scaled[np.diag_indices_from(scaled)] += PSD_SHIFT
        failure = NotPositiveDefiniteError(
            f"{where}: the Cholesky factorisation of its Jacobi-scaled form + {PSD_SHIFT:g} I fails"
        )
        try:
            _cholesky(scaled)
            block[np.diag_indices_from(block)] += uniform + PSD_SHIFT * diagonal
            return BlockFactor(index, _cholesky(block), uniform, PSD_SHIFT)
        except np.linalg.LinAlgError:
            raise failure from None


_RUN_LENGTH = 8  # mean length of the runs of consecutive indices worth one gather each


def _runs(index: np.ndarray, n: int) -> list[tuple[int, int, int]] | None:
    """``(first, stop, position)`` for each run of consecutive increasing indices of ``index``
    (``index[position : position + stop - first] == range(first, stop)``), or None when the
    runs are short on average (then one gather of the whole selection is cheaper) or ``index``
    is not increasing within ``[0, n)``."""
    if index.size < 2 * _RUN_LENGTH or index[0] < 0 or index[-1] >= n:
        return None
    steps = np.diff(index)
    if np.any(steps <= 0):
        return None
    breaks = np.flatnonzero(steps != 1) + 1
    if (breaks.size + 1) * _RUN_LENGTH > index.size:
        return None
    positions = np.concatenate(([0], breaks))
    lengths = np.diff(np.concatenate((positions, [index.size])))
    firsts = index[positions]
    return list(zip(firsts.tolist(), (firsts + lengths).tolist(), positions.tolist(), strict=True))


def _describe(index: np.ndarray) -> str:
    shown = ", ".join(str(int(i)) for i in index[:4])
    return f"[{shown}{', ...' if index.size > 4 else ''}]"


class DenseOperator(Operator):
    """A dense numpy array (not copied)."""

    def __init__(self, matrix: np.ndarray):
        super().__init__(matrix.shape)
        self._matrix = matrix

    @property
    def matrix(self) -> np.ndarray:
        return self._matrix

    def __matmul__(self, x):
        return self._matrix @ x

    def diagonal(self):
        return np.diag(self._matrix)

    def block(self, rows=None, cols=None):
        rows, cols = _indices(rows, self.shape[0]), _indices(cols, self.shape[1])
        W = self._matrix
        if isinstance(rows, slice):
            return W[rows, cols] if isinstance(cols, slice) else W[rows].take(cols, axis=1)
        if isinstance(cols, slice):
            return W.take(rows, axis=0)[:, cols]
        runs = _runs(rows, self.shape[0])
        if (  # row runs gathered straight into place ("clip" never clips: cols are in range)
            runs is not None
            and W.flags.c_contiguous
            and cols.size
            and 0 <= cols.min()
            and cols.max() < self.shape[1]
        ):
            out = np.empty((rows.size, cols.size), dtype=W.dtype)
            for first, stop, at in runs:
                W[first:stop].take(cols, axis=1, out=out[at : at + stop - first], mode="clip")
            return out
        if cols.size < rows.size:  # the smaller selection first
            return W.take(cols, axis=1).take(rows, axis=0)
        return W.take(rows, axis=0).take(cols, axis=1)

    def diagonal_blocks(self, size):
        count = self.shape[0] // size
        idx = np.arange(count)
        return self._matrix.reshape(count, size, count, size)[idx, :, idx, :].copy()


class SymmetricDenseOperator(DenseOperator):
    """A dense ``float64`` array known to be exactly symmetric (not copied).

    A vector product reads one triangle only (BLAS ``dsymv`` on the array's transpose, which is
    the same matrix in column order): about half the memory traffic of a general product, for
    the same sums up to rounding. Products with several columns are general ones.
    """

    def __init__(self, matrix: np.ndarray):
        if (
            matrix.dtype != np.float64
            or matrix.ndim != 2
            or matrix.shape[0] != matrix.shape[1]
            or not matrix.flags.c_contiguous
        ):
            raise InvalidInputError("a symmetric operator takes a square C-ordered float64 array")
        super().__init__(matrix)

    def __matmul__(self, x):
        return symmetric_product(self._matrix, x)


def symmetric_product(matrix: np.ndarray, x) -> np.ndarray:
    """``matrix @ x`` for an exactly symmetric ``matrix``; a vector product of a C- or
    F-ordered ``float64`` one reads one triangle only (BLAS ``dsymv``), the same sums up to
    rounding at half the memory traffic."""
    x = np.asarray(x)
    if x.ndim == 1 and x.dtype == np.float64 and matrix.dtype == np.float64 and matrix.ndim == 2:
        if matrix.flags.c_contiguous:  # its transpose is the same matrix in column order
            return _symv()(1.0, matrix.T, x)
        if matrix.flags.f_contiguous:
            return _symv()(1.0, matrix, x)
    return matrix @ x


@functools.cache
def _symv() -> Callable[..., np.ndarray]:
    """BLAS ``dsymv`` (importing scipy.linalg on first use)."""
    from scipy.linalg.blas import dsymv

    return dsymv


class SparseOperator(Operator):
    """A scipy.sparse matrix or array, held in CSR form (not copied when it is CSR already)."""

    def __init__(self, matrix):
        super().__init__(matrix.shape)
        self._matrix = matrix if matrix.format == "csr" else matrix.tocsr()

    @property
    def matrix(self) -> sp.csr_matrix | sp.csr_array:
        return self._matrix

    def __matmul__(self, x):
        return np.asarray(self._matrix @ x)

    def diagonal(self):
        return np.asarray(self._matrix.diagonal(), dtype=float)

    def block(self, rows=None, cols=None):
        rows, cols = _indices(rows, self.shape[0]), _indices(cols, self.shape[1])
        W = self._matrix
        picked = W if _everything(rows) else W[rows]
        return (picked if _everything(cols) else picked[:, cols]).toarray()


def as_operator(W) -> Operator:
    """``W`` as an :class:`Operator`: an operator itself, or a dense or sparse matrix wrapped.

    Raises
    ------
    InvalidInputError
        If ``W`` is not a square 2-D real matrix (a ``scipy.sparse.linalg.LinearOperator`` is
        not: subclass :class:`Operator` to give its blocks).
    """
    if isinstance(W, Operator):
        return W
    operator: Operator
    if is_sparse(W):
        operator = SparseOperator(W)
    else:
        try:
            array = np.asarray(W, dtype=float)
        except (TypeError, ValueError):
            raise InvalidInputError(
                f"W must be a real matrix or an Operator, got {type(W).__name__}"
            ) from None
        if type(array) is not np.ndarray:  # e.g. numpy.matrix
            array = array.view(np.ndarray)
        if array.ndim != 2:
            raise InvalidInputError(f"W must be a 2-D matrix, got shape {array.shape}")
        operator = DenseOperator(array)
    if operator.shape[0] != operator.shape[1]:
        raise InvalidInputError(f"W must be square, got shape {operator.shape}")
    return operator

"""Compliance and Delassus operators of a sparse stiffness, applied without forming ``R``.

For a stiffness ``K`` (n x n, fixations applied: fixed freedoms removed, as
:func:`~contactqp.compliance.condensation.condense` and
:meth:`ElasticModel.free_stiffness <contactqp.compliance.fem.ElasticModel.free_stiffness>` give it)
and a sparse ``A`` (m x n), the Delassus operator is

.. math::

    W = A K^{-1} A^T,

and the compliance of chosen freedoms ``c`` is the case ``A = I[c, :]``, ``W = (K^{-1})[c, c]``
(the flexibility ``R`` that :func:`~contactqp.compliance.condensation.condense` forms). Neither
operator forms ``W``: ``K`` is factorised once, at construction, and each product ``W x`` is
one pair of triangular solves with that factor between the scatter ``A^T x`` (for the
compliance: ``x`` written into a zero vector at ``c``) and the gather ``A z`` (``z[c]``). The
factorisation (``factorizer``) is MKL Pardiso's sparse Cholesky when MKL is installed (the
``sparse`` extra; ``PardisoCholesky`` of the private ``_pardiso`` module: METIS
nested-dissection ordering, ``L`` only), else
:func:`~contactqp.compliance.condensation.factorize` (SuperLU in symmetric mode, a minimum-degree
ordering, no pivoting); both with the checks of ``factorize`` for singular and indefinite
stiffnesses.

Cost, with ``T`` the time of one pair of triangular solves (about ``4 nnz(L)`` flops):

* a product ``W x``: ``T`` (``k T`` for ``k`` columns, solved together);
* :meth:`~SparseDelassusOperator.diagonal`: ``m T`` (``m`` unit loads, solved in batches of
  bounded memory; the work of forming ``W`` without keeping it), cached;
* :meth:`~SparseDelassusOperator.block`: ``min(|rows|, |cols|) T`` (``W`` is symmetric), the last
  blocks asked for cached;
* :meth:`~SparseDelassusOperator.diagonal_blocks`: ``m T``, cached.

The factoriser was chosen by measurement: the clamped tetrahedral slab of
``benchmarks/bench_sparse_fe.py`` at 202,248 freedoms (11,236 contact nodes), one thread, CPU
seconds of the factorisation, then of one solve, and the process's peak memory (scikit-fem's
assembly alone peaks at 2.34 GB):

==================================================  =======  =======  =========  =======
factoriser                                          factor   solve    nnz        peak
==================================================  =======  =======  =========  =======
MKL Pardiso (``mkl`` wheel, through ctypes), METIS  8.1 s    0.11 s   101 M (L)  2.34 GB
SuperLU on a METIS ordering (pymetis)               30 s     0.21 s   190 M      2.74 GB
CHOLMOD of the ``cholespy`` wheel (reference BLAS)  73 s     0.16 s   n/a        2.34 GB
Pardiso, partial solve (contact freedoms last)      45 s     0.06 s   214 M (L)  3.30 GB*
SuperLU, minimum degree: the fallback               240 s    1.5 s**  516 M      11.6 GB
==================================================  =======  =======  =========  =======

SuperLU in symmetric mode; (*) in a process that also held the full factor; (**) wall-clock,
session 8, on a loaded machine (``benchmarks/README.md``).

Pardiso is called directly rather than through pypardiso, whose every solve hashes the matrix
and copies its indices (0.25 s a solve here). At 30,258 freedoms: Pardiso 0.62 s, SuperLU on
METIS 1.8 s, SuperLU minimum degree 5.2 s, QDLDL (AMD ordering, not supernodal) 16.6 s. A
matrix-free product, CG with pyamg's smoothed-aggregation preconditioner (rigid-body modes as
its near null space) to a residual of 1e-12, took 19 iterations and 1.2 s a product at 202,248
freedoms (setup 2.0 s), ten times a Pardiso solve. scikit-sparse (CHOLMOD) has no wheel for this
platform, and the only python-mumps wheel for Python 3.11 is built against numpy 1.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike

from ..core.model import SYMMETRY_RTOL
from ..core.operators import Operator, _everything, _indices
from ..errors import InvalidInputError
from ._pardiso import PardisoCholesky, pardiso_installed
from .condensation import (
    SINGULAR_PIVOT_RTOL,
    _checked_freedoms,
    _checked_stiffness,
    _checked_symmetric,
    factorize,
)

__all__ = ["FACTORIZERS", "SOLVE_BATCH_BYTES", "SparseComplianceOperator", "SparseDelassusOperator"]

#: The accepted names of the ``factorizer`` argument.
FACTORIZERS = ("pardiso", "superlu")

#: Memory (bytes) of one batch of right-hand sides solved together (diagonals and blocks).
SOLVE_BATCH_BYTES = 64 * 2**20
_BLOCKS_KEPT = 2


class SparseDelassusOperator(Operator):
    """``W = A K^-1 A^T`` through one sparse factorisation of ``K`` (see the module notes).

    Parameters
    ----------
    stiffness : sparse or array_like, shape (n, n)
        Symmetric positive definite stiffness with the fixations applied (N/m).
    constraints : sparse or array_like, shape (m, n)
        ``A``: row ``i`` maps the freedoms' displacements to the ``i``-th contact quantity (a
        normal ``n^T u`` at a node, a tangent, a relative displacement of two nodes).
    labels : sequence of str, optional
        Names of the ``n`` freedoms, for the errors of the factorisation.
    pivot_rtol, symmetry_rtol : float
        See :func:`~contactqp.compliance.condensation.factorize`.
    factorizer : {None, "pardiso", "superlu"}
        The factorisation of ``K`` (see the module notes): MKL Pardiso's Cholesky (the
        ``sparse`` extra) or SuperLU; None: Pardiso when MKL is installed, else SuperLU.

    Attributes
    ----------
    shape : tuple of int
        ``(m, m)``.
    factorizer : str
        The factorisation used, ``"pardiso"`` or ``"superlu"``.
    factor_nnz : int
        Stored entries of the factor (Pardiso: ``L``, about 8 bytes each; SuperLU: ``L`` and
        ``U``, about 12 bytes each).

    Raises
    ------
    RigidBodyModeError, NotPositiveDefiniteError
        From the factorisation: ``K`` singular (not enough fixations) or indefinite.
    InvalidInputError
        ``K`` not square, not finite or not symmetric; ``A`` not a finite (m, n) matrix with
        ``m >= 1``; an unknown ``factorizer``.
    MissingDependencyError
        ``factorizer="pardiso"`` and MKL is not installed.
    """

    def __init__(
        self,
        stiffness,
        constraints,
        *,
        labels: Sequence[str] | None = None,
        pivot_rtol: float = SINGULAR_PIVOT_RTOL,
        symmetry_rtol: float = SYMMETRY_RTOL,
        factorizer: str | None = None,
    ) -> None:
        K = _checked_stiffness(stiffness)
        n = K.shape[0]
        A = sp.csr_matrix(constraints, dtype=float) if constraints is not None else None
        if A is None or A.ndim != 2 or A.shape[1] != n or A.shape[0] == 0:
            shape = None if A is None else A.shape
            raise InvalidInputError(
                f"constraints must be a matrix of shape (m, {n}) with m >= 1, got {shape}"
            )
        if not np.all(np.isfinite(A.data)):
            raise InvalidInputError("constraints contain NaN or inf")
        self._setup(K, A.shape[0], labels, pivot_rtol, symmetry_rtol, factorizer)
        self._A, self._AT = A, A.T.tocsc()

    def _setup(
        self, K, m: int, labels, pivot_rtol: float, symmetry_rtol: float, factorizer
    ) -> None:
        if factorizer is None:
            factorizer = "pardiso" if pardiso_installed() else "superlu"
        if factorizer not in FACTORIZERS:
            raise InvalidInputError(
                f'factorizer must be None, "pardiso" or "superlu", got {factorizer!r}'
            )
        super().__init__((m, m))
        self._n = K.shape[0]
        self._lu: PardisoCholesky | spla.SuperLU
        if factorizer == "pardiso":
            K, _ = _checked_symmetric(K, labels, symmetry_rtol)
            self._lu = PardisoCholesky(K, labels=labels, pivot_rtol=pivot_rtol)
        else:
            self._lu = factorize(
                K, labels=labels, pivot_rtol=pivot_rtol, symmetry_rtol=symmetry_rtol
            )
        self.factorizer = factorizer
        self.factor_nnz = int(self._lu.nnz)
        self._diagonal: np.ndarray | None = None
        self._diagonal_blocks: dict[int, np.ndarray] = {}
        self._blocks: OrderedDict[bytes, np.ndarray] = OrderedDict()

    # the three maps every product goes through; the compliance overrides them with indexing
    def _scatter(self, x: np.ndarray) -> np.ndarray:
        """``A^T x`` (n,) or (n, k)."""
        return np.asarray(self._AT @ x)

    def _gather(self, z: np.ndarray, rows=slice(None)) -> np.ndarray:
        """``(A z)[rows]``."""
        return np.asarray((self._A if _everything(rows) else self._A[rows]) @ z)

    def _unit_loads(self, cols: np.ndarray) -> np.ndarray:
        """``A^T[:, cols]`` as a dense (n, |cols|) array."""
        return self._AT[:, cols].toarray()

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if x.shape[:1] != (self.shape[1],) or x.ndim > 2:
            raise InvalidInputError(
                f"operand must have shape ({self.shape[1]},) or ({self.shape[1]}, k), got {x.shape}"
            )
        return self._gather(self._lu.solve(self._scatter(x)))

    def _batch(self) -> int:
        return max(1, SOLVE_BATCH_BYTES // (8 * self._n))

    def _columns(self, cols: np.ndarray, rows) -> np.ndarray:
        """``W[rows][:, cols]``: the unit loads on ``cols`` solved in batches."""
        out = np.empty((self._row_count(rows), cols.size))
        step = self._batch()
        for start in range(0, cols.size, step):
            chosen = cols[start : start + step]
            out[:, start : start + step] = self._gather(
                self._lu.solve(self._unit_loads(chosen)), rows
            )
        return out

    def _row_count(self, rows) -> int:
        return self.shape[0] if isinstance(rows, slice) else int(np.asarray(rows).size)

    def diagonal(self) -> np.ndarray:
        """The diagonal of ``W``, shape (m,): ``m`` solves in batches (cached).

        Returns a copy; the cached diagonal stays unchanged.
        """
        if self._diagonal is None:
            self._diagonal = self.diagonal_blocks(1).reshape(-1)
        return self._diagonal.copy()

    def diagonal_blocks(self, size: int) -> np.ndarray:
        """The ``size x size`` blocks on the diagonal, shape (m / size, size, size): ``m``
        solves in batches (cached by ``size``)."""
        if size < 1 or self.shape[0] % size:
            raise InvalidInputError(
                f"size must be a positive divisor of {self.shape[0]}, got {size!r}"
            )
        cached = self._diagonal_blocks.get(size)
        if cached is None:
            count = self.shape[0] // size
            cached = np.empty((count, size, size))
            per_batch = max(1, self._batch() // size)
            for first in range(0, count, per_batch):
                contacts = np.arange(first, min(count, first + per_batch))
                index = (contacts[:, None] * size + np.arange(size)).ravel()
                columns = self._columns(index, index)  # (k size, k size)
                k = contacts.size
                blocks = columns.reshape(k, size, k, size)
                cached[contacts] = blocks[np.arange(k), :, np.arange(k), :]
            self._diagonal_blocks[size] = cached
        return cached.copy()

    def block(self, rows=None, cols=None) -> np.ndarray:
        """Dense ``W[rows][:, cols]`` (see :meth:`Operator.block
        <contactqp.core.operators.Operator.block>`): ``min(|rows|, |cols|)`` solves; the last
        blocks asked for are cached."""
        m = self.shape[0]
        r, c = _indices(rows, m), _indices(cols, m)
        r_index = np.arange(m)[r] if isinstance(r, slice) else r
        c_index = np.arange(m)[c] if isinstance(c, slice) else c
        for index in (r_index, c_index):
            if index.size and (index.min() < 0 or index.max() >= m):
                raise InvalidInputError(f"block indices must lie in 0..{m - 1}")
        key = b"%d:" % r_index.size + r_index.tobytes() + c_index.tobytes()
        cached = self._blocks.get(key)
        if cached is not None:
            self._blocks.move_to_end(key)
            return cached.copy()
        if c_index.size <= r_index.size:
            block = self._columns(c_index, r_index)
        else:  # W is symmetric: solve for the smaller selection
            block = self._columns(r_index, c_index).T.copy()
        self._blocks[key] = block
        if len(self._blocks) > _BLOCKS_KEPT:
            self._blocks.popitem(last=False)
        return block.copy()


class SparseComplianceOperator(SparseDelassusOperator):
    """``W = (K^-1)[c, c]``: the compliance of freedoms ``c`` of a sparse stiffness, never formed.

    The operator of the flexibility that
    :func:`~contactqp.compliance.condensation.condense` returns for the same stiffness and
    freedoms; products scatter ``x`` into a zero vector at ``c``, solve, and gather ``z[c]``
    (see the module notes for the costs).

    Parameters
    ----------
    stiffness : sparse or array_like, shape (n, n)
        Symmetric positive definite stiffness with the fixations applied (N/m).
    freedoms : array_like of int, shape (m,)
        Indices ``c`` of the chosen freedoms in ``stiffness``, distinct.
    labels, pivot_rtol, symmetry_rtol, factorizer
        See :class:`SparseDelassusOperator`.

    Attributes
    ----------
    freedoms : numpy.ndarray of int, shape (m,)
        ``c``.
    """

    def __init__(
        self,
        stiffness,
        freedoms: ArrayLike,
        *,
        labels: Sequence[str] | None = None,
        pivot_rtol: float = SINGULAR_PIVOT_RTOL,
        symmetry_rtol: float = SYMMETRY_RTOL,
        factorizer: str | None = None,
    ) -> None:
        K = _checked_stiffness(stiffness)
        self.freedoms = _checked_freedoms(freedoms, K.shape[0]).astype(np.intp)
        self._setup(K, self.freedoms.size, labels, pivot_rtol, symmetry_rtol, factorizer)

    @classmethod
    def of_model(
        cls,
        model,
        nodes,
        *,
        components: Sequence[int] | None = None,
        factorizer: str | None = None,
    ):
        """The compliance of nodes of an :class:`~contactqp.compliance.fem.ElasticModel`.

        The operator of the flexibility
        :meth:`ElasticModel.reduced_model <contactqp.compliance.fem.ElasticModel.reduced_model>`
        forms, in the same order (node by node, then by component).

        Parameters
        ----------
        model : ElasticModel
        nodes : array_like of int, shape (k,), or NodeSelection
            Distinct mesh node indices.
        components : sequence of int, optional
            Directions kept at every node (0 = x, 1 = y, 2 = z); all by default.
        factorizer : {None, "pardiso", "superlu"}
            See :class:`SparseDelassusOperator`.

        Raises
        ------
        InvalidInputError
            Nodes or components out of range or repeated, or a chosen freedom that is fixed.
        """
        ids = np.asarray(getattr(nodes, "nodes", nodes))
        dim, count = model.dim, model.n_nodes
        if (
            ids.ndim != 1
            or ids.size == 0
            or not np.issubdtype(ids.dtype, np.integer)
            or ids.min() < 0
            or ids.max() >= count
            or np.unique(ids).size != ids.size
        ):
            raise InvalidInputError(f"nodes must be distinct indices in 0..{count - 1}")
        axes = np.arange(dim) if components is None else np.atleast_1d(np.asarray(components))
        if (
            axes.ndim != 1
            or axes.size == 0
            or not np.issubdtype(axes.dtype, np.integer)
            or axes.min() < 0
            or axes.max() >= dim
            or np.unique(axes).size != axes.size
        ):
            raise InvalidInputError(
                f"components must be distinct directions in 0..{dim - 1}, got {components!r}"
            )
        chosen = model.basis.nodal_dofs[axes][:, ids].T.ravel()
        free, K = model.free_stiffness()
        position = np.full(model.basis.N, -1)
        position[free] = np.arange(free.size)
        held = chosen[position[chosen] < 0]
        if held.size:
            raise InvalidInputError(
                f"nodes: freedom {int(held[0])} is fixed and has no flexibility"
            )
        return cls(K, position[chosen], factorizer=factorizer)

    def _scatter(self, x: np.ndarray) -> np.ndarray:
        z = np.zeros((self._n,) + x.shape[1:])
        z[self.freedoms] = x
        return z

    def _gather(self, z: np.ndarray, rows=slice(None)) -> np.ndarray:
        return z[self.freedoms[rows]]

    def _unit_loads(self, cols: np.ndarray) -> np.ndarray:
        z = np.zeros((self._n, cols.size))
        z[self.freedoms[cols], np.arange(cols.size)] = 1.0
        return z

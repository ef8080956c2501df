"""Solves with principal blocks ``W_FF`` of one dense SPD matrix, re-using a Cholesky factor.

An active-set method solves ``W_FF x = r`` for a sequence of free sets ``F`` that differ by a few
indices from one step to the next. Factoring each block costs ``|F|^3 / 3``. Here one *base*
block ``W_BB = L L^T`` is factored and a nearby ``F = (B \\ D) ∪ A`` is solved through it:

* the added indices ``A`` border the factor, ``C = L^{-1} W_BA`` and
  ``S = W_AA - C^T C = L_S L_S^T``, giving the factor :math:`\\mathcal{L} = [[L, 0], [C^T, L_S]]`
  of ``W`` on ``B ∪ A``;
* the dropped indices ``D`` are held at zero by multipliers ``s``: with
  ``V = \\mathcal{L}^{-1} E_D`` and ``y = \\mathcal{L}^{-1} r``, ``s = -(V^T V)^{-1} V^T y`` and
  ``x = \\mathcal{L}^{-T} (y + V s)``.

That costs about ``|B|^2 (|A| + |D|) + |B| (|A|^2 + |D|^2) + (|A|^3 + |D|^3) / 3``. Once the updates
made since the base was factored would cost more in all than factoring ``W_FF`` (``|F|^3 / 3``),
``W_FF`` is factored and becomes the base: a free set that drifts far from the base cannot make
every step expensive. Base blocks are factored by the operator
(:meth:`~contactqp.core.operators.Operator.cholesky`, which also validates them): a block that is
not numerically positive definite (``W`` only semidefinite) is factored with a diagonal shift, and
the same shift is added to the indices that border it.
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

from ..core.operators import BlockFactor, Operator, as_operator

__all__ = ["FreeBlockSolver"]

_PLANS_KEPT = 6


def _cholesky(block: np.ndarray) -> np.ndarray:
    import scipy.linalg

    return scipy.linalg.cholesky(block, lower=True, overwrite_a=True, check_finite=False)


def _forward(L, rhs):
    import scipy.linalg

    return scipy.linalg.solve_triangular(L, rhs, lower=True, check_finite=False)


def _backward(L, rhs):
    import scipy.linalg

    return scipy.linalg.solve_triangular(L, rhs, lower=True, trans="T", check_finite=False)


def _units(n: int, positions: np.ndarray) -> np.ndarray:
    """The columns ``e_p`` of the ``n x n`` identity, ``p`` in ``positions``."""
    unit = np.zeros((n, positions.size))
    unit[positions, np.arange(positions.size)] = 1.0
    return unit


class _SolvedColumns:
    """Columns ``L^{-1} M[:, j]`` solved once per base factor ``L``, keyed by ``j``: free sets
    near one base border and drop mostly the same indices, and each column is independent of the
    others solved with it."""

    def __init__(self, keys: int):
        self.slot = np.full(keys, -1, dtype=np.intp)
        self.columns = np.empty((0, 0))

    def get(self, keys: np.ndarray, solve) -> np.ndarray:
        """The columns of ``keys``; ``solve(missing)`` gives those not solved yet (then kept)."""
        missing = keys[self.slot[keys] < 0]
        if missing.size:
            solved = solve(missing)
            self.slot[missing] = self.columns.shape[1] + np.arange(missing.size)
            self.columns = solved if self.columns.size == 0 else np.hstack([self.columns, solved])
        return self.columns[:, self.slot[keys]]


class _Plan:
    """How to solve with one free set: the base factor, its border and the dropped rows."""

    def __init__(self, L, positions, C=None, L_S=None, V=None, L_G=None):
        self.L, self.positions = L, positions
        self.C, self.L_S, self.V, self.L_G = C, L_S, V, L_G
        self.size = L.shape[0] + (0 if C is None else C.shape[1])

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        import scipy.linalg

        n_base = self.L.shape[0]
        extended = np.zeros(self.size)
        extended[self.positions] = rhs
        y = _forward(self.L, extended[:n_base])
        if self.C is not None:
            y = np.concatenate([y, _forward(self.L_S, extended[n_base:] - self.C.T @ y)])
        if self.V is not None:
            multipliers = scipy.linalg.cho_solve(
                (self.L_G, True), -(self.V.T @ y), check_finite=False
            )
            y = y + self.V @ multipliers
        if self.C is not None:
            z_added = _backward(self.L_S, y[n_base:])
            z = np.concatenate([_backward(self.L, y[:n_base] - self.C @ z_added), z_added])
        else:
            z = _backward(self.L, y)
        return z[self.positions]


class FreeBlockSolver:
    """Solve ``W[F, F] x = r`` for boolean masks ``F``, re-using factorisations.

    Parameters
    ----------
    matrix : ndarray, shape (n, n), or Operator
        Symmetric positive (semi)definite ``W`` (:func:`~contactqp.core.operators.as_operator`);
        not copied, not modified.

    Raises
    ------
    NotPositiveDefiniteError
        From :meth:`solve`, if a free block is not positive semidefinite
        (:meth:`~contactqp.core.operators.Operator.cholesky`).

    Attributes
    ----------
    factorizations : int
        Cholesky factorisations of a base block (updates and re-used plans excluded).
    updates : int
        Free sets solved through the base factor by bordering and dropping rows.
    """

    def __init__(self, matrix: np.ndarray | Operator):
        self.matrix = as_operator(matrix)
        self.diagonal = self.matrix.diagonal()
        self.base: np.ndarray | None = None
        self.base_index = np.empty(0, dtype=np.intp)
        self.base_factor: BlockFactor | None = None
        self.plans: OrderedDict[bytes, _Plan] = OrderedDict()
        self.update_cost = 0.0  # flops spent on updates since the base was factored
        self.bordered = _SolvedColumns(0)  # L^{-1} W[base, j], by index j of W
        self.held = _SolvedColumns(0)  # L^{-1} e_p, by position p in the base
        self.factorizations = 0
        self.updates = 0

    def solve(self, free: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """Solve with the block of free set ``free`` (bool, shape (n,)); ``rhs`` in its order."""
        key = np.packbits(free).tobytes()
        plan = self.plans.get(key)
        if plan is None:
            plan = self._plan(free)
            self.plans[key] = plan
            if len(self.plans) > _PLANS_KEPT:
                self.plans.popitem(last=False)
        else:
            self.plans.move_to_end(key)
        return plan.solve(rhs)

    def _plan(self, free: np.ndarray) -> _Plan:
        if self.base is not None:
            added = np.flatnonzero(free & ~self.base)
            dropped = np.flatnonzero(self.base[self.base_index] & ~free[self.base_index])
            n_free, n_base = int(np.count_nonzero(free)), self.base_index.size
            a, d = added.size, dropped.size
            cost = n_base**2 * (a + d) + n_base * (a * a + d * d) + (a**3 + d**3) / 3
            if self.update_cost + cost <= n_free**3 / 3:
                plan = self._updated_plan(free, added, dropped)
                if plan is not None:
                    self.update_cost += cost
                    return plan
        return self._refactored_plan(free)

    def _refactored_plan(self, free: np.ndarray) -> _Plan:
        index = np.flatnonzero(free)
        factor = self.matrix.cholesky(index)
        self.factorizations += 1
        self.base, self.base_index, self.base_factor = free.copy(), index, factor
        self.update_cost = 0.0
        self.bordered = _SolvedColumns(free.size)
        self.held = _SolvedColumns(index.size)
        self.plans.clear()
        return _Plan(factor.lower, np.arange(index.size))

    def _updated_plan(self, free, added, dropped) -> _Plan | None:
        """The plan through the base factor, or None when a bordered block is not definite."""
        factor, base_index = self.base_factor, self.base_index
        assert factor is not None, "updates are planned only once a base is factored"
        L = factor.lower
        C = L_S = V = L_G = None
        try:
            if added.size:
                C = self.bordered.get(
                    added, lambda j: _forward(L, self.matrix.block(base_index, j))
                )
                schur = self.matrix.block(added, added) - C.T @ C
                if factor.shifted:
                    schur[np.diag_indices_from(schur)] += (
                        factor.uniform + factor.relative * self.diagonal[added]
                    )
                L_S = _cholesky(schur)
            if dropped.size:
                V = self.held.get(dropped, lambda p: _forward(L, _units(base_index.size, p)))
                if C is not None:
                    V = np.vstack([V, -_forward(L_S, C.T @ V)])
                L_G = _cholesky(V.T @ V)
        except np.linalg.LinAlgError:
            return None
        extended_index = np.concatenate([base_index, added])
        order = np.argsort(extended_index, kind="stable")
        kept = free[extended_index[order]]
        self.updates += 1
        return _Plan(L, order[kept], C, L_S, V, L_G)

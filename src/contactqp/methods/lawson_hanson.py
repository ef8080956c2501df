"""Lawson and Hanson's active-set method for ``min 1/2 x^T S x - q^T x, x >= 0``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["NonnegativeQPSolution", "solve_nonnegative_qp"]


@dataclass(frozen=True)
class NonnegativeQPSolution:
    """Outcome of :func:`solve_nonnegative_qp`.

    Attributes
    ----------
    x : ndarray, shape (n,)
        The minimiser (>= 0), or the last iterate when not converged.
    converged : bool
        No entry of ``q - S x`` off the passive set exceeds the tolerance.
    iterations : int
        Outer steps (contacts added).
    factorizations : int
        Cholesky factorisations of passive blocks (a bordering is not one).
    """

    x: np.ndarray
    converged: bool
    iterations: int
    factorizations: int


def solve_nonnegative_qp(S, q, x0=None, tol: float = 1e-10, max_iter: int | None = None):
    """``min 1/2 x^T S x - q^T x, x >= 0`` by Lawson and Hanson's active-set method.

    The passive set ``P`` (``x_P > 0``) grows by the contact of largest ``q - S x`` (the most
    interpenetrating one) at each outer step; ``x_P = S_PP^-1 q_P`` with a Cholesky factor of
    ``S_PP`` bordered at each addition (refactored after a removal, which the inner loop makes
    when ``x_P`` would leave the orthant). A warm start keeps the support of ``x0`` less the
    contacts whose ``x_P`` comes out non-positive, dropped all at once until none does (any
    passive set with ``x_P > 0`` optimal on it is a valid start of the outer loop).
    Suited to problems whose solution has few positive entries (most contacts open): each step
    costs a bordering of a small factor, where the primal-dual active set of
    :func:`~contactqp.methods.box_qp.solve_box_qp` may take many steps on a strongly coupled
    ``S`` (plates). ``max_iter`` defaults to ``3 len(q)``.
    Returns a :class:`NonnegativeQPSolution`.

    References: C. L. Lawson, R. J. Hanson, Solving Least Squares Problems, ch. 23 (1974).
    """
    import scipy.linalg

    if max_iter is None:
        max_iter = 3 * len(q)
    x = np.zeros(len(q))
    passive = [] if x0 is None else np.flatnonzero(x0 > 0).tolist()
    threshold = tol * max(float(np.max(np.abs(q))), np.finfo(float).tiny)
    factorizations = 0

    def factor(indices):
        nonlocal factorizations
        factorizations += 1
        return np.linalg.cholesky(S[np.ix_(indices, indices)]) if indices else np.zeros((0, 0))

    def solve(L, rhs):  # LAPACK directly: scipy's wrappers cost more than these small solves
        return scipy.linalg.lapack.dpotrs(L, rhs, lower=1)[0]

    L = factor(passive)
    while passive:  # warm start: keep the part of the support the solution on it keeps positive
        z = solve(L, q[passive])
        if np.all(z > 0):
            break
        passive = [i for i, value in zip(passive, z, strict=True) if value > 0]
        L = factor(passive)
    x[:] = 0.0
    if passive:
        x[passive] = z
    for iteration in range(1, max_iter + 1):
        while passive:  # x_P = argmin on P, keeping x_P > 0
            z = solve(L, q[passive])
            if np.all(z > 0):
                x[passive] = z
                break
            current = x[passive]
            blocked = np.flatnonzero(z <= 0)
            ratios = current[blocked] / (current[blocked] - z[blocked])
            step = current + float(np.min(ratios)) * (z - current)
            step[blocked[np.argmin(ratios)]] = 0.0
            x[passive] = np.maximum(step, 0.0)
            passive = [i for i in passive if x[i] > 0]
            L = factor(passive)
        gradient = q - x[passive] @ S[passive] if passive else q.copy()  # S symmetric: rows
        gradient[passive] = -np.inf
        j = int(np.argmax(gradient))
        if gradient[j] <= threshold:
            return NonnegativeQPSolution(x, True, iteration, factorizations)
        border = (
            scipy.linalg.lapack.dtrtrs(L, S[passive, j], lower=1)[0] if passive else np.zeros(0)
        )
        pivot = S[j, j] - border @ border
        if not pivot > 0:
            return NonnegativeQPSolution(x, False, iteration, factorizations)
        k = len(passive)
        grown = np.zeros((k + 1, k + 1))
        grown[:k, :k], grown[k, :k], grown[k, k] = L, border, np.sqrt(pivot)
        L = grown
        passive.append(j)
    return NonnegativeQPSolution(x, False, max_iter, factorizations)

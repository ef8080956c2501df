r"""Proximal-point outer loop for the local Coulomb problem ``u = W r + q`` with a singular ``W``.

Rigid multibody problems have far more contact unknowns than body freedoms: ``W = H M^-1 H^T``
is very singular, and with a large friction coefficient many contacts sit at the tip of the
cone. There the semismooth Newton steps of :mod:`contactqp.methods.coulomb` can stall. The
proximal-point method (Rockafellar 1976; the FC3D_PROX solver of Siconos) solves instead a
sequence of problems with the positive definite operator

.. math::

    u = (W + \rho D)\, r + (q - \rho D\, r_k), \qquad D = \mathrm{diag}(\text{contact scale}),

from ``r_k``, the last outer iterate; its solution ``x`` gives ``r_{k+1} = r_k + 1.5 (x - r_k)``
(over-relaxed; Eckstein and Bertsekas 1992). At a fixed point the velocity is exactly
``W r + q``: the problem as given. Each inner problem is solved by a Newton run (the caller's
runner, coulomb's ``_Newton``) from ``r_k`` to a tenth of the current
outer error, and when that run fails, by a Levenberg-Marquardt run from its best point. The
weight ``rho`` (relative to ``D``, from 1) adapts to the inner runs: times 0.3 when an inner
problem is solved in at most 3 iterations, down to 1e-4 (so that ``W + rho D`` stays well
conditioned: the inner problems are then solved in one or two steps each), times 3 when it
takes more than 10, times 10 when it is not solved (Siconos's FC3D_PROX also raises its weight
tenfold then, and lowers it with the outer error); after a failure ``rho`` stays above 3 times
the weight that failed (without that floor it swung between failing and easy weights on one of
20 perturbed starts, and stopped at 6e-8).

Measured from ``r = 0`` with 1000 inner iterations on the walls of rigid boxes of
``tests/multibody_problems.py`` where the default route's Newton, Levenberg-Marquardt and
Gauss-Seidel rounds fail (9 walls of 140 to 360 contacts): 7 converge to 1e-8
(the other two reach 8e-8 and 1.3e-8), and all of 13 walls the rounds solve; Siconos's rule
(``rho = 5 e`` after a solved inner problem), or lowering ``rho`` tenfold down to 1e-10
without relaxation, converged on 4 of the 9 (the inner problems are then as hard as the given
one). A test that stops the loop when its best error has not halved in 30 to 100 outer
iterations cut off 1 to 3 of the 7 (the error plateaus, then falls): the loop runs to its
budget. From the point where the rounds stopped, 6 of the 9 converged (before the floor)
(:func:`~contactqp.methods.coulomb.solve_coulomb` therefore starts its proximal stage from
zero).

Where ``W`` is dense and of low rank (rigid bodies: at most 6 per body, far below the contact
unknowns), :func:`low_rank_factor` finds ``G`` with ``W = G G^T`` once (the caller passes it),
and each inner Newton step is solved through it (the Woodbury identity on
``A + B (G G^T + rho D)``: ``2 m k^2`` flops for rank ``k``, against ``2 m^3 / 3`` for the LU
of the block), with the same steps to rounding. On a wall of 48 boxes (1,080 unknowns, rank
288) the 182 inner iterations took 1.3 s against 5.3 s; on one of 80 boxes (1,824 unknowns,
rank 480) 2,000 took 46 s against 151 s (both with one BLAS thread).

Convergence and the best point are decided by the caller's ``measure`` of the problem as
given, never by the inner problems' errors.

References
----------
R. T. Rockafellar, "Monotone operators and the proximal point algorithm", SIAM J. Control
Optim. 14 (1976). J. Eckstein, D. P. Bertsekas, "On the Douglas-Rachford splitting method and
the proximal point algorithm for maximal monotone operators", Math. Program. 55 (1992).
V. Acary, M. Bremond, O. Huber, "On solving contact problems with Coulomb
friction: formulations and numerical comparisons", INRIA RR-9118 (2018).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..core.local_problem import cone_residual
from ..core.operators import is_sparse

__all__ = [
    "proximal_point",
    "low_rank_factor",
    "RHO_START",
    "RHO_MIN",
    "RHO_MAX",
    "INNER_ITERATIONS",
]

RHO_START = 1.0  # first weight of the proximal term, relative to the contacts' diagonal scale
RHO_MIN, RHO_MAX = 1e-4, 1e6  # range of rho: W + rho D stays positive definite
INNER_ITERATIONS = 50  # largest number of iterations of one inner Newton (or LM) run
INNER_SHARE = 0.1  # inner tolerance: this share of the current outer error (and >= tol / 10)
FAST, SLOW = 3, 10  # inner problems solved in at most FAST (more than SLOW) iterations
LOWER, RAISE, FAIL = 0.3, 3.0, 10.0  # rho's factors then, and when an inner problem fails
# (RAISE times the failed rho is then rho's floor)
RELAX = 1.5  # over-relaxation of the outer step (Eckstein and Bertsekas 1992)
LOW_RANK_MIN = 500  # unknowns of a dense W from which its rank is looked for (below, the
# Woodbury steps measured no faster than the LU: 336 unknowns of rank 96, 0.12 s against 0.06 s)
LOW_RANK_SHARE = 1 / 3  # rank at most this share of the unknowns: steps through the factor


def low_rank_factor(W) -> np.ndarray | None:
    """``G`` (m x k) with ``W = G G^T`` to rounding, for a dense symmetric positive
    semidefinite ``W`` of rank ``k <= LOW_RANK_SHARE m`` (rigid bodies: ``W = H M^-1 H^T`` has
    the rank of the bodies' freedoms), else None (also for a sparse ``W``, one of fewer than
    LOW_RANK_MIN rows, or one not symmetric to 1e-14 of its largest entry).

    LAPACK's Cholesky with complete pivoting (``dpstrf``) stops at the rank, where the largest
    diagonal entry left is below ``m`` ulps of the largest: the entries left out are then below
    that too (``W`` semidefinite), at a cost of about ``m^2 k`` flops.
    """
    if is_sparse(W) or W.shape[0] < LOW_RANK_MIN:
        return None
    from scipy.linalg import lapack

    W = np.asarray(W, dtype=float)
    size = float(np.abs(W).max(initial=0.0))
    if size == 0.0 or float(np.abs(W - W.T).max()) > 1e-14 * size:
        return None
    factor, pivots, rank, info = lapack.dpstrf(np.array(W, order="F"), lower=1, tol=-1.0)
    if info < 0 or rank > LOW_RANK_SHARE * W.shape[0]:
        return None
    G = np.empty((W.shape[0], rank))
    G[pivots - 1] = np.tril(factor[:, :rank])
    return G


def _regularised(W, weights: np.ndarray):  # -> the type of W
    """``W + diag(weights)``, dense or sparse as ``W``."""
    if is_sparse(W):
        import scipy.sparse as sp

        return sp.csr_matrix(W + sp.diags(weights))  # type: ignore[operator]
    out = np.array(W, dtype=float, copy=True)
    out[np.diag_indices_from(out)] += weights
    return out


def proximal_point(
    W,
    q: np.ndarray,
    mu: np.ndarray,
    dim: int,
    r: np.ndarray,
    tol: float,
    max_iter: int,
    measure: Callable[[np.ndarray, np.ndarray], tuple[float, float]],
    newton: Callable,
    *,
    low_rank: np.ndarray | None = None,
) -> tuple[np.ndarray, float, int, str]:
    """Proximal-point iterations on the FCLIB problem ``(W, q, mu)`` (no cohesion) from ``r``.

    Parameters
    ----------
    W : numpy.ndarray or scipy.sparse.csr_matrix, shape (m, m)
        Positive semidefinite (not checked).
    q : numpy.ndarray, shape (m,)
    mu : numpy.ndarray, shape (n_contacts,)
    dim : int
    r : numpy.ndarray, shape (m,)
        Start.
    tol : float
        Target of ``measure``'s error.
    max_iter : int
        Budget of inner Newton iterations.
    measure : callable
        ``measure(r, u) -> (residual, error)`` of the problem as given (``u = W r + q``): the
        only test of convergence and of the best point.
    newton : callable
        ``newton(W, q, mu, dim, measure, low_rank)``: a runner of Newton iterations on the
        problem ``(W, q, mu)`` (coulomb's ``_Newton``; ``low_rank`` is None, or ``(G, weights)``
        with ``W = G G^T + diag(weights)`` when ``low_rank`` is given here), whose
        ``run(r, tol, max_iter, adaptive) -> (r, error, iterations, reason)`` brings
        ``measure``'s error to ``tol`` and whose ``with_q(q, measure)`` is the same runner on
        another ``q`` (the factorisation's ordering kept).
    low_rank : numpy.ndarray, optional
        ``G`` with ``W = G G^T`` (:func:`low_rank_factor`): the inner steps are solved through
        it; None, through the LU of their blocks.

    Returns
    -------
    r : numpy.ndarray
        The best point (lowest error).
    error : float
        Its error by ``measure``.
    iterations : int
        Inner Newton iterations spent.
    reason : str
        ``"converged"`` or ``"iteration limit"``, with the outer count.
    """
    nc = mu.shape[0]
    diag = np.asarray(W.diagonal(), dtype=float).reshape(nc, dim).mean(axis=1)
    scale = np.repeat(np.where(diag > 0, diag, 1.0), dim)
    rho = RHO_START
    error = measure(r, W @ r + q)[1]
    best = (r, error)
    iterations = outer = 0
    runner = None  # the inner problems' Newton runner for the current rho
    floor = RHO_MIN  # raised above a rho whose inner problem failed
    while error > tol and iterations < max_iter:
        if runner is None:  # a new rho: a new inner operator
            weights = rho * scale
            factor = None if low_rank is None else (low_rank, weights)
            runner = newton(_regularised(W, weights), q, mu, dim, measure, factor)
        q_k = q - weights * r

        def inner_measure(x, u, q_k=q_k):
            return cone_residual(q_k, mu, dim, x, u, x)

        inner = runner.with_q(q_k, inner_measure)
        inner_tol = max(INNER_SHARE * error, 0.1 * tol)
        x, inner_error, k = r, math.inf, 0
        for adaptive in (False, True):  # Newton, then Levenberg-Marquardt from its best point
            budget = min(INNER_ITERATIONS, max_iter - iterations - k)
            if budget < 1:
                break
            x, inner_error, more, _ = inner.run(x, inner_tol, budget, adaptive)
            k += max(more, 1)
            if inner_error <= inner_tol:
                break
        iterations += k
        outer += 1
        new = measure(x, W @ x + q)[1]
        if new < best[1]:
            best = (x, new)
        if inner_error > inner_tol:  # inner problem too hard: a stronger proximal term
            floor = min(RAISE * rho, RHO_MAX)
            rho, runner = min(FAIL * rho, RHO_MAX), None
            if new >= error:  # and no progress: from r again
                continue
        elif k <= FAST and rho > floor:  # an easy inner problem: closer to the given one
            rho, runner = max(LOWER * rho, floor), None
        elif k > SLOW and rho < RHO_MAX:
            rho, runner = min(RAISE * rho, RHO_MAX), None
        r = r + RELAX * (x - r)
        error = measure(r, W @ r + q)[1]
        if error < best[1]:
            best = (r, error)
    reason = "converged" if best[1] <= tol else "iteration limit"
    return best[0], best[1], iterations, f"{reason} after {outer} outer it."

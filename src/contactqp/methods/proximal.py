r"""Proximal-point outer loop for the local Coulomb problem ``u = W r + q`` with a singular ``W``.

Rigid multibody problems have far more contact unknowns than body freedoms: ``W = H M^-1 H^T``
is very singular, and with a large friction coefficient many contacts sit at the tip of the
cone. There the semismooth Newton steps of :mod:`contactqp.methods.coulomb` can stall. The
proximal-point method (Rockafellar 1976; the FC3D_PROX solver of Siconos) solves instead a
sequence of problems with the positive definite operator

.. math::

    u = (W + \rho D)\, r + (q - \rho D\, r_k), \qquad D = \mathrm{diag}(\text{contact scale}),

from ``r_k``, the last outer iterate; its solution is ``r_{k+1}``. At a fixed point
``r_{k+1} = r_k`` the velocity is exactly ``W r + q``: the problem as given. Each inner problem
is solved by a Newton run (the caller's, given as ``newton(W, q) -> runner``) to a tolerance a
tenth of the current outer error, and when that run fails, by a Levenberg-Marquardt run from
its best point. The weight ``rho`` adapts to the inner runs (as in Siconos's FC3D_PROX):
divided by 10 when an inner problem is solved in at most 10 iterations (the inner problems
are then nearly the given one and converge as fast), multiplied by 10 when it is not solved.

Measured on the walls of rigid boxes of ``tests/multibody_problems.py`` (13 problems: the
stage's inputs where the default route's rounds had failed, 16 to 360 contacts, 600 inner
iterations): the Levenberg-Marquardt inner runs rescued a problem the Newton runs alone left
at 1.6e-6; a weight tied to the outer error (``rho = 5 e``, Siconos's current rule) did no
better than the rule above (4 of 13 converged each, from the stalled points); a cold start
``r = 0`` converged on 8 of 13 (9 with 1500 iterations) where the stalled point converged on
4 (:func:`~contactqp.methods.coulomb.solve_coulomb` therefore starts its proximal stage from
zero).

Convergence is decided by the caller's ``measure`` of the problem as given, never by the inner
problems' errors.

References
----------
R. T. Rockafellar, "Monotone operators and the proximal point algorithm", SIAM J. Control
Optim. 14 (1976). V. Acary, M. Bremond, O. Huber, "On solving contact problems with Coulomb
friction: formulations and numerical comparisons", INRIA RR-9118 (2018).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from ..core.local_problem import LocalProblem, natural_map_residual

__all__ = ["proximal_point", "RHO_START", "RHO_MIN", "RHO_MAX", "INNER_ITERATIONS"]

RHO_START = 1.0  # first weight of the proximal term, relative to the contacts' diagonal scale
RHO_MIN, RHO_MAX = 1e-10, 1e6  # range of rho
INNER_ITERATIONS = 50  # largest number of Newton iterations of one inner problem
INNER_SHARE = 0.1  # inner tolerance: this share of the current outer error (and >= tol / 10)
FAST = 10  # an inner run of at most this many iterations lowers rho
LM_INNER = True  # an inner Newton run that fails is followed by a Levenberg-Marquardt run
STALL = 30  # the loop stops when its best error has not halved in this many outer iterations


def _regularised(W, weights: np.ndarray):  # -> the type of W
    """``W + diag(weights)``, dense or sparse as ``W``."""
    if sp.issparse(W):
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
) -> tuple[np.ndarray, float, int, str]:
    """Proximal-point iterations on the FCLIB problem ``(W, q, mu)`` from ``r``.

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
        ``measure(r, u) -> (residual, error)`` of the problem as given (``u = W r + q``).
    newton : callable
        ``newton(W, q, mu, dim, measure)`` returns a runner whose
        ``run(r, tol, max_iter, adaptive) -> (r, error, iterations, reason)`` solves the inner
        problem ``(W, q, mu)`` to ``measure``'s error ``tol``
        (:class:`contactqp.methods.coulomb._Newton`).

    Returns
    -------
    r : numpy.ndarray
        The best point (lowest error).
    error : float
    iterations : int
        Inner Newton iterations spent.
    reason : str
        ``"converged"``, ``"stalled"`` or ``"iteration limit"``, with the outer count.
    """
    nc = mu.shape[0]
    diag = np.asarray(W.diagonal(), dtype=float).reshape(nc, dim).mean(axis=1)
    scale = np.repeat(np.where(diag > 0, diag, 1.0), dim)
    rho = RHO_START
    error = measure(r, W @ r + q)[1]
    best = (r, error)
    errors = [error]
    iterations = outer = 0
    inner: LocalProblem | None = None  # the inner problem of the current rho
    weights = rho * scale
    while error > tol and iterations < max_iter:
        if len(errors) > STALL and min(errors[-STALL:]) > 0.5 * min(errors[:-STALL]):
            return best[0], best[1], iterations, f"stalled after {outer} outer it."
        if inner is None:  # a new rho: a new inner operator
            weights = rho * scale
            inner = LocalProblem(_regularised(W, weights), q, mu, dim)
        sub = inner.with_q(q - weights * r)

        def sub_measure(x, u, sub=sub):
            return natural_map_residual(sub, x, u)

        runner = newton(sub.W, sub.q, mu, dim, sub_measure)
        inner_tol = max(INNER_SHARE * error, 0.1 * tol)
        x, inner_error, k = r, math.inf, 0
        for adaptive in (False, True) if LM_INNER else (False,):  # Newton, then LM from its best
            budget = min(INNER_ITERATIONS, max_iter - iterations - k)
            if budget < 1:
                break
            x, inner_error, more, _ = runner.run(x, inner_tol, budget, adaptive)
            k += max(more, 1)
            if inner_error <= inner_tol:
                break
        iterations += k
        outer += 1
        new = measure(x, W @ x + q)[1]
        if inner_error > inner_tol:  # inner problem too hard: a stronger proximal term
            rho = min(10.0 * rho, RHO_MAX)
            inner = None
            if new >= error:
                errors.append(error)
                continue
        elif k <= FAST and rho > RHO_MIN:  # an easy inner problem: closer to the given one
            rho = max(0.1 * rho, RHO_MIN)
            inner = None
        r, error = x, new
        errors.append(error)
        if error < best[1]:
            best = (r, error)
    reason = "converged" if best[1] <= tol else "iteration limit"
    return best[0], best[1], iterations, f"{reason} after {outer} outer it."

"""A second route to a :class:`~contactqp.core.surface.SurfaceProblem`: the box QP's active set.

At a fixed approach ``delta`` the forces solve the bound-constrained QP
``min 1/2 r^T W r + r^T (s - delta 1)``, ``r >= 0``, which
:func:`~contactqp.methods.box_qp.solve_box_qp` (primal-dual active set, Cholesky factors of free
blocks) solves exactly. At a fixed load the approach is found by a safeguarded Newton iteration
on the load ``L(delta) = sum r(delta)``: increasing, and linear while the contact set stays
the same, with slope ``1^T W_CC^{-1} 1`` on the contact ``C``; the root is bracketed by the
approach at which no point touches, ``min s``, and ``min s + max diag(W) P``, at which one
point alone would carry the load (``|W_ij| <= max diag(W)`` for a positive definite ``W``).

It factors blocks of ``W`` (:meth:`~contactqp.core.operators.Operator.block`): a cross-check for
problems of a few thousand points, independent of the conjugate gradients of
:mod:`~contactqp.methods.constrained_cg`.
"""

from __future__ import annotations

import time

import numpy as np

from ..core.model import iteration_cap, positive_tolerance, warm_start
from ..core.surface import SurfaceProblem, SurfaceResult
from .box_qp import FREE, solve_box_qp

__all__ = ["solve_surface_active_set"]

#: Largest number of Newton steps on the approach (fixed load).
_NEWTON_STEPS = 100


def solve_surface_active_set(
    problem: SurfaceProblem, *, r0=None, tol: float = 1e-10, max_iter: int = 500
) -> SurfaceResult:
    """Solve a :class:`~contactqp.core.surface.SurfaceProblem` by the box QP's active set.

    Parameters
    ----------
    problem : SurfaceProblem
    r0 : array_like, shape (m,), optional
        Warm start: forces of a nearby problem (N); their support is the first active set.
    tol : float
        Relative natural residual of each box QP, and the load balance ``|sum r - P| / P``
        at a fixed load.
    max_iter : int
        Largest number of box-QP iterations of each solve.

    Returns
    -------
    SurfaceResult
        ``iterations`` counts the box-QP iterations of every solve; ``info["newton"]`` the
        Newton steps on the approach (fixed load).

    Raises
    ------
    InvalidInputError
        ``tol`` not a finite number > 0, ``max_iter`` not an integer >= 1, or ``r0`` not a
        finite array of shape (m,).
    """
    tol = positive_tolerance(tol)
    max_iter = iteration_cap(max_iter)
    start = time.perf_counter()
    W, s = problem.compliance, problem.separation
    r = None if r0 is None else np.maximum(warm_start(r0, problem.size), 0.0)
    iterations = 0

    def forces_at(approach: float, guess):
        nonlocal iterations
        solution = solve_box_qp(
            W, s - approach, lower=0.0, x0=guess, tol=tol, max_iter=max_iter, check_finite=False
        )
        iterations += solution.iterations
        return solution

    if problem.approach is not None:
        solution = forces_at(problem.approach, r)
        return problem.make_result(
            solution.x,
            problem.approach,
            method="surface-active-set",
            converged=solution.converged,
            message=solution.message,
            iterations=iterations,
            seconds=time.perf_counter() - start,
        )
    load = problem.load
    assert load is not None
    low = float(np.min(s))
    high = low + float(np.max(W.diagonal())) * load
    approach = high
    if r is not None and np.any(r > 0):  # the warm start's mean gap on its support
        guess = float(np.mean((s + W @ r)[r > 0]))
        approach = guess if low < guess < high else high
    converged, message = False, "Newton on the approach did not converge"
    steps, solved = 0, high
    for steps in range(1, _NEWTON_STEPS + 1):
        solution = forces_at(approach, r)
        r, solved = solution.x, approach
        if not solution.converged:
            message = solution.message
            break
        excess = float(np.sum(r)) - load
        if abs(excess) <= tol * load:
            converged, message = True, f"converged: {steps} Newton steps on the approach"
            break
        if excess > 0:
            high = approach
        else:
            low = approach
        free = np.flatnonzero(solution.state == FREE)
        slope = float(np.sum(W.cholesky(free).solve(np.ones(free.size)))) if free.size else 0.0
        trial = approach - excess / slope if slope > 0 else np.nan
        approach = trial if low < trial < high else 0.5 * (low + high)
    assert r is not None
    return problem.make_result(
        r,
        solved,
        method="surface-active-set",
        converged=converged,
        message=message,
        iterations=iterations,
        seconds=time.perf_counter() - start,
        info={"newton": steps},
    )

"""Methods for a :class:`~contactqp.core.fastened.FastenedProblem`: the non-negative QP on ``S``.

``min 1/2 x^T S x - x^T q, x >= 0`` on the contact rows, the fastener multipliers eliminated
(see :mod:`contactqp.core.fastened`): Lawson and Hanson's active set (the default), the
project's box-QP solver (:func:`~contactqp.methods.active_set.solve_active_set` on a fastened
problem) or scipy's NNLS (an independent route).
"""

from __future__ import annotations

import time

import numpy as np

from ..core.fastened import FastenedProblem
from ..core.model import positive_tolerance
from ..core.result import FastenedResult
from ..errors import InvalidInputError
from .box_qp import solve_box_qp
from .lawson_hanson import solve_nonnegative_qp

__all__ = ["solve_lawson_hanson", "solve_nnls", "solve_fastened_box_qp"]


def _checked(problem) -> FastenedProblem:
    if not isinstance(problem, FastenedProblem):
        raise InvalidInputError(f"problem must be a FastenedProblem, got {type(problem).__name__}")
    return problem


def _result(
    problem: FastenedProblem,
    name: str,
    forces,
    converged: bool,
    message: str,
    nit: int,
    factorizations: int,
    start: float,
) -> FastenedResult:
    return problem.make_result(
        forces,
        method=name,
        converged=converged,
        message=message,
        iterations=nit,
        seconds=time.perf_counter() - start,
        info={"factorizations": factorizations},
    )


def solve_lawson_hanson(problem: FastenedProblem, *, r0=None, tol: float = 1e-10) -> FastenedResult:
    """Lawson and Hanson's active set on ``S``, one contact at a time, from the support of ``r0``.

    Parameters
    ----------
    problem : FastenedProblem
    r0 : array_like, shape (m,), optional
        Warm start, e.g. :attr:`~contactqp.core.result.FastenedResult.multipliers`.
    tol : float
        Relative tolerance on ``q - S x`` (relative to ``max|q|``).
    """
    start = time.perf_counter()
    problem = _checked(problem)
    positive_tolerance(tol)
    q = problem.contact_rhs()
    solution = solve_nonnegative_qp(
        problem.schur, q, problem.contact_start(r0), tol, max_iter=3 * len(q)
    )
    forces, converged = solution.x, solution.converged
    nit, factorizations = solution.iterations, solution.factorizations
    message = f"Lawson-Hanson {'converged' if converged else 'did not converge'}"
    return _result(problem, "lawson-hanson", forces, converged, message, nit, factorizations, start)


def solve_fastened_box_qp(
    problem: FastenedProblem, *, r0=None, tol: float = 1e-10, max_iter: int = 500
) -> FastenedResult:
    """The project's primal-dual box-QP solver on ``S``, warm started from ``r0``."""
    start = time.perf_counter()
    problem = _checked(problem)
    solution = solve_box_qp(
        problem.schur,
        -problem.contact_rhs(),
        lower=0.0,
        x0=problem.contact_start(r0),
        tol=tol,
        max_iter=max_iter,
        check_finite=False,
    )
    return _result(
        problem,
        "active-set",
        solution.x,
        solution.converged,
        solution.message,
        solution.iterations,
        solution.factorizations,
        start,
    )


def solve_nnls(problem: FastenedProblem) -> FastenedResult:
    """:func:`scipy.optimize.nnls` on ``min ||L^T x - L^-1 q||`` with ``S = L L^T`` (cold)."""
    import scipy.linalg
    from scipy.optimize import nnls

    start = time.perf_counter()
    problem = _checked(problem)
    q = problem.contact_rhs()
    lower = problem.schur_cholesky()
    target = scipy.linalg.solve_triangular(lower, q, lower=True, check_finite=False)
    try:
        forces, _ = nnls(lower.T, target)
        converged, message = True, "nnls converged (iterations not reported)"
    except RuntimeError as exc:  # iteration limit
        forces, converged, message = np.zeros(len(q)), False, f"nnls: {exc}"
    return _result(problem, "nnls", forces, converged, message, 0, 1, start)

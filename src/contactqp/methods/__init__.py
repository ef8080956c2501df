"""Solvers for frictionless contact and the registry that names them."""

from __future__ import annotations

from ..errors import InvalidInputError
from .active_set import solve_active_set
from .box_qp import BoxQPSolution, solve_box_qp
from .qp import solve_qp

__all__ = ["SOLVERS", "solve", "solve_active_set", "solve_qp", "solve_box_qp", "BoxQPSolution"]

#: Solver names accepted by :func:`solve` and the CLI.
SOLVERS = {"active-set": solve_active_set, "qp": solve_qp}


def solve(problem, solver: str = "active-set", **options):
    """Solve a :class:`~contactqp.ContactProblem` with the named solver.

    Parameters
    ----------
    problem : ContactProblem
    solver : {"active-set", "qp"}
        ``"active-set"`` (default): the project's dual solver. ``"qp"``: the primal QP through
        qpsolvers; choose its backend with ``backend=``.
    **options
        Passed to the solver.

    Returns
    -------
    ContactResult
    """
    try:
        method = SOLVERS[solver]
    except KeyError:
        raise InvalidInputError(
            f"unknown solver {solver!r}; choose one of {', '.join(SOLVERS)}"
        ) from None
    return method(problem, **options)

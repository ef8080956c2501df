"""The default solver: primal-dual active set on the dual, never inverting ``R``."""

from __future__ import annotations

import time

import numpy as np

from ..errors import InvalidInputError
from .box_qp import solve_box_qp

__all__ = ["solve_active_set", "cold_start"]


def cold_start(W, b):
    """A first guess of the contact forces whose support is close to the contact zone.

    Each interpenetration ``b_i > 0`` is shared over the row of ``W``, so that the first free
    block is smaller than the whole overlap; only the first active set depends on it.
    """
    return np.maximum(b, 0.0) / np.abs(W).sum(axis=1)


def solve_active_set(problem, *, forces0=None, tol: float = 1e-10, max_iter: int = 500):
    """Solve a frictionless :class:`~contactqp.ContactProblem` on its dual.

    Parameters
    ----------
    problem : ContactProblem
    forces0 : array_like, shape (n_constraints,), optional
        Warm start: contact forces of a nearby problem (their support is the first active set).
    tol : float
        Relative natural-residual tolerance of :func:`~contactqp.solvers.box_qp.solve_box_qp`.
    max_iter : int

    Returns
    -------
    ContactResult
    """
    if forces0 is not None and np.shape(forces0) != (problem.n_constraints,):
        raise InvalidInputError(
            f"forces0 must have shape ({problem.n_constraints},), got {np.shape(forces0)}"
        )
    start = time.perf_counter()
    dual = problem.dual()
    if forces0 is None:
        forces0 = cold_start(dual.W, dual.b)
    solution = solve_box_qp(dual.W, -dual.b, lower=0.0, x0=forces0, tol=tol, max_iter=max_iter)
    forces = solution.x
    displacements = dual.displacements(forces)
    elapsed = time.perf_counter() - start
    return problem.make_result(
        displacements, forces, solver="active-set", converged=solution.converged,
        message=solution.message, nit=solution.iterations, wall_time=elapsed,
        info={"factorizations": solution.factorizations, "residual": solution.residual},
    )

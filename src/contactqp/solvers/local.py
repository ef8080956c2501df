"""Local FCLIB problems ``u = W r + q`` solved by the project's own active-set method.

This version solves the frictionless case (every ``mu`` zero): the cones reduce to rays, the
tangential reactions vanish and the normal part is the bound-constrained QP
``min 1/2 r_N^T W_NN r_N + q_N^T r_N, r_N >= 0``. Problems with friction raise
:class:`~contactqp.errors.UnsupportedProblemError`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..errors import UnsupportedProblemError
from ..local import LocalProblem, natural_map_error
from .box_qp import solve_box_qp

__all__ = ["LocalSolution", "solve_local"]


@dataclass(frozen=True)
class LocalSolution:
    """Reactions ``r`` and velocities/gaps ``u`` of a local problem, with the natural-map error."""

    r: np.ndarray
    u: np.ndarray
    error: float
    converged: bool
    iterations: int
    seconds: float
    message: str


def _polish(problem, W_nn, q_n, normal, start, steps: int = 10):
    """Active-set Newton steps on the file's own (possibly slightly unsymmetric) ``W``.

    FCLIB matrices written with few digits are unsymmetric at 1e-5..1e-3; the QP solved on the
    symmetric part then misses the true complementarity problem by that much. A few primal-dual
    active set steps on the unsymmetric normal block (least squares where it is singular) remove
    that error; the best point by natural-map error is kept.
    """
    def error_of(x):
        r = np.zeros(problem.W.shape[0])
        r[normal] = x
        return natural_map_error(problem, r)

    best, best_error = start, error_of(start)
    x = start
    for _ in range(steps):
        w = W_nn @ x + q_n
        active = x - w / np.mean(np.abs(np.diag(W_nn)) + 1e-300) > 0
        x = np.zeros_like(x)
        if active.any():
            x[active] = np.linalg.lstsq(W_nn[np.ix_(active, active)], -q_n[active], rcond=None)[0]
        x = np.maximum(x, 0.0)
        error = error_of(x)
        if error < best_error:
            best, best_error = x, error
        elif error >= best_error:
            break
    return best


def solve_local(problem: LocalProblem, *, tol: float = 1e-8, max_iter: int = 500) -> LocalSolution:
    """Solve a frictionless local problem to natural-map error ``tol``.

    Parameters
    ----------
    problem : LocalProblem
    tol : float
        Target of :func:`~contactqp.local.natural_map_error`; ``converged`` is True only when the
        error, computed independently of the solver, is at most ``tol``.
    max_iter : int

    Raises
    ------
    UnsupportedProblemError
        When some ``mu`` is positive (friction is not supported yet).
    """
    frictional = int(np.count_nonzero(problem.mu))
    if frictional:
        raise UnsupportedProblemError(
            f"friction not supported yet: mu > 0 on {frictional} of {problem.n_contacts} contacts"
        )
    start = time.perf_counter()
    normal = np.arange(problem.n_contacts) * problem.dim
    W = problem.W
    W_nn = W[normal][:, normal]
    W_nn = np.asarray(W_nn.toarray() if hasattr(W_nn, "toarray") else W_nn, dtype=float)
    q_n = problem.q[normal]
    solution = solve_box_qp(0.5 * (W_nn + W_nn.T), q_n, lower=0.0,
                            tol=min(tol, 1e-10) * 1e-2, max_iter=max_iter)
    reactions = _polish(problem, W_nn, q_n, normal, solution.x)
    r = np.zeros(problem.W.shape[0])
    r[normal] = reactions
    u = np.asarray(W @ r).reshape(-1) + problem.q
    seconds = time.perf_counter() - start
    error = natural_map_error(problem, r, u)
    return LocalSolution(r=r, u=u, error=float(error), converged=bool(error <= tol),
                         iterations=solution.iterations, seconds=seconds, message=solution.message)

"""Local FCLIB problems ``u = W r + q`` solved by the project's own methods.

With friction (some ``mu > 0``) :func:`solve_local` calls
:func:`~contactqp.methods.coulomb.solve_coulomb`. Without (every ``mu`` zero) the cones reduce to
rays, the tangential reactions vanish and the normal part is the bound-constrained QP
``min 1/2 r_N^T W_NN r_N + q_N^T r_N, r_N >= 0``, solved by the own box-QP solver.

:func:`solve_global` solves a global problem through its condensed form and certifies the answer
on the global equations as written (:meth:`~contactqp.core.local_problem.GlobalProblem.certify`).
Every solution carries its :class:`~contactqp.core.local_problem.AccuracyLimits`: how far rounding (the
conditioning of ``M``) and the data's written digits limit its error.
"""

from __future__ import annotations

import time

import numpy as np

from ..core.certificate import LocalCertificate
from ..core.local_problem import (
    AccuracyLimits,
    GlobalProblem,
    LocalProblem,
    accuracy_limits,
    check_positive_semidefinite,
    contact_status,
    natural_map_error,
)
from ..core.result import NOT_CONVERGED, SUCCESS, LocalResult
from .box_qp import solve_box_qp

__all__ = ["local_result", "solve_global", "solve_local"]


def local_result(problem: LocalProblem, r, u, *, converged: bool, error: float, tol: float,
                 iterations: int, seconds: float, message: str, method: str,
                 limits: AccuracyLimits | None = None, equilibrium: float | None = None,
                 v: np.ndarray | None = None) -> LocalResult:
    """The :class:`~contactqp.core.result.LocalResult` of reactions ``r`` and velocities ``u``
    (shape (m,)) of ``problem``, with the contact status computed from them.

    ``error`` (natural-map), ``equilibrium``, ``limits`` and ``tol`` make its certificate;
    ``converged`` is the method's verdict (status 0, else 1).
    """
    r = np.asarray(r, dtype=float)
    u = np.asarray(u, dtype=float)
    certificate = LocalCertificate(
        natural_map=float(error), equilibrium=equilibrium, tol=float(tol),
        limits=AccuracyLimits(0.0, 0.0) if limits is None else limits)
    return LocalResult(
        displacements=u, forces=r, nodal_forces=r, gaps=u[::problem.dim],
        contact_status=contact_status(problem, r, u), energy=float("nan"),
        success=bool(converged), status=SUCCESS if converged else NOT_CONVERGED,
        message=message, iterations=int(iterations), seconds=float(seconds), method=method,
        certificate=certificate, v=v)


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

    if start.size == 0:
        return start
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
        if error >= best_error:
            break
        best, best_error = x, error
    return best


def solve_local(problem: LocalProblem, *, tol: float = 1e-8,
                 max_iter: int | None = None) -> LocalResult:
    """Solve a local problem to natural-map error ``tol``.

    Parameters
    ----------
    problem : LocalProblem
    tol : float
        Target of :func:`~contactqp.core.local_problem.natural_map_error`; ``success`` is True
        only when the error, computed independently of the solver, is at most ``tol``.
    max_iter : int, optional
        Cap on all the iterations of the route: the box-QP solver (default 500) or, with
        friction, every Newton run and Gauss-Seidel sweep of
        :func:`~contactqp.methods.coulomb.solve_coulomb` together (default its ``MAX_ITER``).

    Raises
    ------
    NotPositiveDefiniteError
        If ``W`` is not positive semidefinite
        (:func:`~contactqp.core.local_problem.check_positive_semidefinite`).
    """
    if np.any(problem.mu > 0):
        from .coulomb import MAX_ITER, solve_coulomb

        return solve_coulomb(problem, tol=tol, max_iter=MAX_ITER if max_iter is None else max_iter)
    start = time.perf_counter()
    check_positive_semidefinite(problem.W)
    normal = np.arange(problem.n_contacts) * problem.dim
    W = problem.W
    W_nn = W[normal][:, normal]
    W_nn = np.asarray(W_nn.toarray() if hasattr(W_nn, "toarray") else W_nn, dtype=float)
    q_n = problem.q[normal]
    solution = solve_box_qp(0.5 * (W_nn + W_nn.T), q_n, lower=0.0, tol=min(tol, 1e-10) * 1e-2,
                            max_iter=500 if max_iter is None else max_iter)
    reactions = _polish(problem, W_nn, q_n, normal, solution.x)
    r = np.zeros(problem.W.shape[0])
    r[normal] = reactions
    return finish(problem, r, tol, solution.iterations, start, solution.message,
                  method="active-set")


def finish(problem: LocalProblem, r, tol: float, iterations: int, start: float,
           detail: str, *, method: str, per_contact: bool = False) -> LocalResult:
    """The :class:`~contactqp.core.result.LocalResult` of reactions ``r``, checked by the
    natural-map error.

    ``u``, the error, the verdict and the contact status are computed here from ``r`` alone,
    independently of the solver; ``start`` is the solver's ``time.perf_counter()`` at entry and
    ``detail`` its account of the iterations, put in the message beside the verdict and error.
    ``per_contact`` chooses the error (:func:`~contactqp.core.local_problem.natural_map_error`).
    """
    u = np.asarray(problem.W @ r).reshape(-1) + problem.q
    error = natural_map_error(problem, r, u, per_contact=per_contact)
    converged = bool(error <= tol)
    verdict = "converged" if converged else f"not converged to {tol:g}"
    limits = accuracy_limits(problem, r, u)
    return local_result(
        problem, r, u, converged=converged, error=error, tol=tol, iterations=iterations,
        seconds=time.perf_counter() - start, method=method, limits=limits,
        message=_with_limits(f"{verdict}: {detail}; natural-map error {error:.2e}"
                             + (" (largest of the problem's and each contact's)"
                                if per_contact else ""), limits, tol))


def _with_limits(message: str, limits: AccuracyLimits, tol: float) -> str:
    notes = limits.describe(tol)
    return f"{message}; {notes}" if notes else message


def solve_global(problem: GlobalProblem, *, tol: float = 1e-8,
                 max_iter: int | None = None) -> LocalResult:
    """Solve a global problem ``M v = H r + f, u = H^T v + w`` as given, certified on it.

    The problem is condensed (:meth:`~contactqp.core.local_problem.GlobalProblem.condense`, ``W`` not
    symmetrised) and solved by :func:`solve_local`; the reactions are then judged on the written
    equations by :meth:`~contactqp.core.local_problem.GlobalProblem.certify`: ``v`` solves ``M v = H r + f``,
    ``u = H^T v + w``, and the certificate's natural-map error is that of ``(r, u)``.

    Parameters
    ----------
    problem : GlobalProblem
    tol : float
        ``success`` is True when the certified natural-map error and the relative
        equilibrium residual are both at most ``tol``.
    max_iter : int
        As :func:`solve_local`.

    Returns
    -------
    LocalResult
        With ``v``, and the certificate's ``equilibrium``; its ``limits`` give the attainable
        error set by the conditioning of ``M`` and the limit set by the data's digits, and the
        message names any above ``tol``.

    Raises
    ------
    NotPositiveDefiniteError
        If ``M`` is singular or the condensed ``W`` is not positive semidefinite.
    """
    start = time.perf_counter()
    local = solve_local(problem.condense(), tol=tol, max_iter=max_iter)
    r = local.forces
    certificate = problem.certify(r)
    error, equilibrium = certificate.error, certificate.equilibrium
    converged = bool(error <= tol and equilibrium <= tol)
    verdict = "converged" if converged else f"not converged to {tol:g}"
    message = (f"{verdict} on the global equations as written: natural-map error {error:.2e}, "
               f"equilibrium residual {equilibrium:.1e} (condensed problem: {local.message})")
    return local_result(
        problem.condense(), r, certificate.u, converged=converged, error=error, tol=tol,
        iterations=local.iterations, seconds=time.perf_counter() - start, method=local.method,
        message=_with_limits(message, certificate.limits, tol), limits=certificate.limits,
        equilibrium=equilibrium, v=certificate.v)

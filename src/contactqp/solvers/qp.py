"""The method's primal QP on displacements, through a generic backend of qpsolvers."""

from __future__ import annotations

import time
import warnings

import numpy as np
import scipy.sparse

from ..errors import InvalidInputError
from ..optional import require

__all__ = ["solve_qp", "available_backends", "backend_options", "DEFAULT_BACKEND"]

DEFAULT_BACKEND = "clarabel"

#: Tight tolerances per backend, so that answers are comparable with the own solver's.
_TIGHT = {
    "clarabel": {"tol_gap_abs": 1e-12, "tol_gap_rel": 1e-12, "tol_feas": 1e-12,
                 "tol_ktratio": 1e-10, "max_iter": 500},
    "piqp": {"eps_abs": 1e-11, "eps_rel": 1e-11, "max_iter": 500},
    "proxqp": {"eps_abs": 1e-11, "eps_rel": 0.0},
    "osqp": {"eps_abs": 1e-10, "eps_rel": 1e-10, "max_iter": 200000, "polishing": True},
    "daqp": {},
    "quadprog": {},
    "cvxopt": {"abstol": 1e-12, "reltol": 1e-12, "feastol": 1e-12},
    "highs": {},
}


def _qpsolvers(purpose: str = "the 'qp' solver"):
    return require("qpsolvers", purpose, "qp")


def available_backends() -> list[str]:
    """Names of the qpsolvers backends installed here."""
    return sorted(_qpsolvers().available_solvers)


def backend_options(backend: str) -> dict:
    """The tight tolerance settings contactqp passes to ``backend``."""
    return dict(_TIGHT.get(backend, {}))


def solve_qp(problem, *, backend: str = DEFAULT_BACKEND, **options):
    """Solve the primal QP ``min 1/2 U^T K U - P^T U, A U <= Delta`` with a qpsolvers backend.

    Parameters
    ----------
    problem : ContactProblem
    backend : str
        A name from :func:`available_backends`.
    **options
        Passed to the backend, over contactqp's tight defaults (:func:`backend_options`).

    Returns
    -------
    ContactResult
        Contact forces are the backend's multipliers of ``A U <= Delta``.
    """
    qpsolvers = _qpsolvers()
    if backend not in qpsolvers.available_solvers:
        raise InvalidInputError(
            f"qp backend {backend!r} is not installed; available: {', '.join(available_backends())}"
        )
    start = time.perf_counter()
    # scaled unknowns U = s_u V and multipliers lambda = s_f z keep the backend's tolerances
    # meaningful in SI units (stiffnesses of 1e6..1e9 N/m)
    K = problem.model.stiffness
    stiffness_scale = float(np.max(np.diag(K)))
    force_scale = float(np.max(np.abs(problem.loads), initial=0.0)) or 1.0
    length_scale = force_scale / stiffness_scale
    A = problem.constraints.matrix
    K_scaled = K / stiffness_scale
    if backend in qpsolvers.sparse_solvers:
        K_scaled, G = scipy.sparse.csc_matrix(K_scaled), A.tocsc()
    else:
        G = A.toarray()
    qp = qpsolvers.Problem(P=K_scaled, q=-problem.loads / force_scale, G=G,
                           h=problem.constraints.gaps / length_scale)
    settings = backend_options(backend)
    settings.update(options)
    with warnings.catch_warnings(record=True) as said:  # a backend's warnings go in the message
        warnings.simplefilter("always")
        solution = qpsolvers.solve_problem(qp, solver=backend, **settings)
    elapsed = time.perf_counter() - start
    found = solution.x is not None and solution.z is not None and solution.found is not False
    U = length_scale * solution.x if found else np.full(problem.model.n_freedoms, np.nan)
    forces = (force_scale * np.maximum(solution.z, 0.0) if found
              else np.full(problem.n_constraints, np.nan))
    message = "backend found a solution" if found else "backend found no solution"
    notes = list(dict.fromkeys(" ".join(str(w.message).split()) for w in said))
    return problem.make_result(
        U, forces, solver=f"qp:{backend}", converged=bool(found),
        message=f"{message} ({'; '.join(notes)})" if notes else message,
        nit=int(getattr(solution, "extras", {}).get("iter", 0) or 0), wall_time=elapsed,
    )

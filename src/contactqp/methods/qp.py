"""The method's primal QP on displacements, through a generic backend of qpsolvers."""

from __future__ import annotations

import os
import sys
import tempfile
import time
import warnings
from contextlib import contextmanager

import numpy as np

from ..errors import InvalidInputError, SolverError
from ..optional import require, require_backend

__all__ = [
    "solve_qp",
    "available_backends",
    "backend_options",
    "refused_setting",
    "installed_backend",
    "run_backend",
    "DEFAULT_BACKEND",
]

DEFAULT_BACKEND = "clarabel"

#: Tight tolerances per backend, so that answers are comparable with the own solver's.
_TIGHT = {
    "clarabel": {
        "tol_gap_abs": 1e-12,
        "tol_gap_rel": 1e-12,
        "tol_feas": 1e-12,
        "tol_ktratio": 1e-10,
        "max_iter": 500,
    },
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


def installed_backend(backend: str, purpose: str = "the 'qp' solver"):
    """qpsolvers, once ``backend`` is known to be one of its installed backends.

    Raises
    ------
    MissingDependencyError
        qpsolvers is not installed.
    InvalidInputError
        ``backend`` is not installed (the message lists those that are).
    """
    qpsolvers = _qpsolvers(purpose)
    require_backend(backend, qpsolvers.available_solvers)
    return qpsolvers


def run_backend(qpsolvers, problem, backend: str, settings: dict, what: str, *, chosen=()):
    """``qpsolvers.solve_problem`` of ``problem`` with ``settings``.

    ``what`` names the problem in the messages (``"the contact QP"``), ``chosen`` the keys of
    ``settings`` that the caller chose (the others are contactqp's defaults).

    Raises
    ------
    InvalidInputError
        The backend raises and refuses one of the ``chosen`` settings
        (:func:`refused_setting`): bad input.
    SolverError
        The backend raises otherwise: it found no answer.
    """
    try:
        return qpsolvers.solve_problem(problem, solver=backend, **settings)
    except Exception as exc:
        for key in chosen:
            reason = refused_setting(backend, key, settings[key])
            if reason:
                raise InvalidInputError(
                    f"backend {backend!r} refuses {key} = {settings[key]!r} ({reason})"
                ) from exc
        raise SolverError(
            f"qp backend {backend!r} failed on {what}: {type(exc).__name__}: "
            f"{' '.join(str(exc).split())}"
        ) from exc


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
        Contact forces are the backend's multipliers of ``A U <= Delta``. ``converged`` is
        False when the backend returns a point without claiming it solves the QP (an
        iteration cap, an inexact status): the point is the result, its message says so.

    Raises
    ------
    InvalidInputError
        ``backend`` is not installed, or refuses one of ``options``.
    SolverError
        The backend raised, or returned no point or a non-finite one.
    """
    import scipy.sparse

    qpsolvers = installed_backend(backend)
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
    qp = qpsolvers.Problem(
        P=K_scaled, q=-problem.loads / force_scale, G=G, h=problem.constraints.gaps / length_scale
    )
    settings = backend_options(backend)
    settings.update(options)
    with warnings.catch_warnings(record=True) as said:  # a backend's warnings go in the message
        warnings.simplefilter("always")
        solution = run_backend(qpsolvers, qp, backend, settings, "the contact QP", chosen=options)
    elapsed = time.perf_counter() - start
    notes = list(dict.fromkeys(" ".join(str(w.message).split()) for w in said))
    z = np.zeros(0) if solution.z is None and problem.n_constraints == 0 else solution.z
    if not all(v is not None and np.all(np.isfinite(v)) for v in (solution.x, z)):
        raise SolverError(
            f"qp backend {backend!r} found no solution of the contact QP"
            + (f" ({'; '.join(notes)})" if notes else "")
        )
    found = solution.found is not False
    U = length_scale * np.asarray(solution.x)
    forces = force_scale * np.maximum(np.asarray(z), 0.0)
    message = (
        "backend found a solution"
        if found
        else "backend stopped without claiming a solution; its last point is returned"
    )
    return problem.make_result(
        U,
        forces,
        method=f"qp:{backend}",
        converged=bool(found),
        message=f"{message} ({'; '.join(notes)})" if notes else message,
        iterations=int(getattr(solution, "extras", {}).get("iter", 0) or 0),
        seconds=elapsed,
    )


def refused_setting(backend: str, key: str, value) -> str | None:
    """Why the installed qpsolvers ``backend`` refuses the setting ``key = value``, or None.

    Backends check their settings only when they run, so the setting (over contactqp's
    defaults, :func:`backend_options`) is tried on a QP of one variable. The reason is what the
    backend raises or prints (from C code), or a warning naming ``key`` (piqp warns of unknown
    names only when verbose).
    """
    import scipy.sparse

    qpsolvers = _qpsolvers()
    sparse = backend in qpsolvers.sparse_solvers
    one = scipy.sparse.csc_matrix(np.ones((1, 1))) if sparse else np.ones((1, 1))
    probe = qpsolvers.Problem(P=one, q=np.zeros(1), G=one, h=np.ones(1))
    settings = {**backend_options(backend), key: value}
    for verbose in (False, True):
        with _captured_output() as printed, warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                qpsolvers.solve_problem(probe, solver=backend, **{"verbose": verbose, **settings})
                raised = None
            except Exception as exc:
                raised = f"{type(exc).__name__}: {exc}"
        if raised:
            said = [line for line in printed[0].splitlines() if "error" in line.lower()]
            return " ".join((said[0] if said else raised).split())
        named = [str(warning.message) for warning in caught if key in str(warning.message)]
        if named:
            return " ".join(named[0].split())
    return None


@contextmanager
def _captured_output():
    """Capture what C code writes to file descriptors 1 and 2 into the list yielded."""
    sys.stdout.flush()
    sys.stderr.flush()
    text = [""]
    with tempfile.TemporaryFile() as sink:
        saved = [os.dup(fd) for fd in (1, 2)]
        try:
            for fd in (1, 2):
                os.dup2(sink.fileno(), fd)
            yield text
        finally:
            for fd, copy in zip((1, 2), saved, strict=True):
                os.dup2(copy, fd)
                os.close(copy)
            sink.seek(0)
            text[0] = sink.read().decode(errors="replace").strip()

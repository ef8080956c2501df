"""``coulomb-batch``: a :class:`~contactqp.core.local_batch.LocalBatch` solved in one compiled
loop.

Each problem runs the first Newton run :func:`~contactqp.methods.coulomb.solve_coulomb` runs on
it alone, in C (:func:`~contactqp.kernels.compiled.small_newton`). The few problems where that
run stops short (on the ill-conditioned one-contact problems of a wide draw, about 1 in 400)
are solved again from their start by the compiled Gauss-Seidel route of their dimension
(:func:`~contactqp.methods.spatial.solve_spatial`,
:func:`~contactqp.methods.planar.solve_planar`, whose local solver is exact on one contact) with
the iterations left, and these hand their own stalls to
:func:`~contactqp.methods.coulomb.solve_coulomb`. Every problem is then certified in one
compiled pass (:func:`~contactqp.kernels.compiled.small_certificate`): ``u = W r + q``, the
natural-map error and the contact status from ``r`` and the problem's own data. Without the
compiled kernels each problem is solved by :func:`~contactqp.methods.coulomb.solve_coulomb`.
"""

from __future__ import annotations

import time

import numpy as np

from .. import kernels
from ..core.local_batch import LocalBatch, LocalBatchResult
from ..core.local_problem import CONTACT_FLOOR, check_positive_semidefinite, small_semidefinite
from ..core.model import iteration_cap, positive_tolerance, real_array
from ..errors import InvalidInputError
from .coulomb import MAX_ITER, RUN_ITERATIONS, solve_coulomb
from .planar import solve_planar
from .spatial import solve_spatial

__all__ = ["solve_coulomb_batch"]


def _start(batch: LocalBatch, r0) -> np.ndarray:
    """The starts, shape (P, m): zero, or ``r0`` checked."""
    shape = batch.q.shape
    if r0 is None:
        return np.zeros(shape)
    start = np.array(real_array(r0, "r0"), dtype=float, order="C")
    if start.shape != shape:
        raise InvalidInputError(f"r0 must have shape {shape}, got {start.shape}")
    if not np.all(np.isfinite(start)):
        raise InvalidInputError("r0 contains NaN or inf")
    return start


def solve_coulomb_batch(
    batch: LocalBatch,
    *,
    r0=None,
    tol: float = 1e-8,
    max_iter: int = MAX_ITER,
    check_psd: bool = True,
    per_contact: bool = False,
) -> LocalBatchResult:
    """Solve every problem of ``batch`` to natural-map error ``tol``.

    The options are those of :func:`~contactqp.methods.coulomb.solve_coulomb`, for every
    problem: the same iterations, the same answers (to rounding), the same verdicts as
    solving each problem alone with :func:`~contactqp.solve`.

    Parameters
    ----------
    batch : LocalBatch
    r0 : array_like, shape (P, m), optional
        Warm starts; zero when not given.
    tol : float
    max_iter : int
    check_psd : bool
        Check that every ``W[p]`` is positive semidefinite (a compiled Cholesky test each; a
        failure is confirmed by
        :func:`~contactqp.core.local_problem.check_positive_semidefinite` and raised naming
        the problem).
    per_contact : bool

    Returns
    -------
    LocalBatchResult

    Raises
    ------
    InvalidInputError
        On a bad option or ``r0``.
    NotPositiveDefiniteError
        If some ``W[p]`` is not positive semidefinite.
    """
    start = time.perf_counter()
    if not isinstance(batch, LocalBatch):
        raise InvalidInputError(f"batch must be a LocalBatch, got {type(batch).__name__}")
    tol = positive_tolerance(tol)
    max_iter = iteration_cap(max_iter)
    x = _start(batch, r0)
    W, q, mu = batch.W, batch.q, batch.mu
    P, m = q.shape
    if kernels.small_newton is None or kernels.small_certificate is None:
        return _one_by_one(batch, x, tol, max_iter, check_psd, per_contact, start)
    if check_psd:
        for p in np.flatnonzero(~small_semidefinite(W)):
            check_positive_semidefinite(W[p], name=f"W[{p}]")  # raises with the reason
    shift = np.zeros((P, m))  # no cohesion
    counts = np.empty(P, dtype=np.intp)
    reasons = np.empty(P, dtype=np.intp)
    errors = np.empty(P)
    kernels.small_newton(
        W,
        q,
        mu,
        shift,
        x,
        tol,
        min(RUN_ITERATIONS, max_iter),
        per_contact,
        CONTACT_FLOOR,
        counts,
        reasons,
        errors,
    )
    messages = {}
    sweeps = solve_spatial if batch.dim == 3 else solve_planar
    for p in np.flatnonzero((reasons != 0) & (counts < max_iter)):
        # Newton stopped short: the sweeps from the start, with the iterations left
        alone = sweeps(
            batch.problem(int(p)),
            r0=None if r0 is None else np.asarray(r0, dtype=float)[p],
            tol=tol,
            max_iter=max_iter - int(counts[p]),
            check_psd=False,
            per_contact=per_contact,
        )
        x[p] = alone.forces
        messages[int(p)] = f"newton {counts[p]} iterations (stopped short), then {alone.message}"
        counts[p] += alone.iterations
    u = np.empty((P, m))
    measures = np.empty((P, 4))
    status = np.empty((P, batch.n_contacts), dtype=np.intp)
    kernels.small_certificate(
        W, q, mu, shift, x, per_contact, CONTACT_FLOOR, 1e-6, u, measures, status
    )
    error = measures[:, 0].copy()
    return LocalBatchResult(
        forces=x,
        displacements=u,
        error=error,
        success=error <= tol,
        iterations=counts.astype(np.int64),
        contact_status=status.astype(np.int64),
        tol=tol,
        seconds=time.perf_counter() - start,
        method="coulomb-batch",
        messages=messages,
    )


def _one_by_one(batch, x, tol, max_iter, check_psd, per_contact, start) -> LocalBatchResult:
    """Every problem by :func:`~contactqp.methods.coulomb.solve_coulomb` (no compiled kernels)."""
    P, m = x.shape
    u = np.empty((P, m))
    error = np.empty(P)
    counts = np.empty(P, dtype=np.int64)
    status = np.empty((P, batch.n_contacts), dtype=np.int64)
    messages = {}
    for p in range(P):
        if check_psd:  # the check of the compiled route, naming the problem
            check_positive_semidefinite(batch.W[p], name=f"W[{p}]")
        alone = solve_coulomb(
            batch.problem(p),
            r0=x[p],
            tol=tol,
            max_iter=max_iter,
            check_psd=False,
            per_contact=per_contact,
        )
        x[p], u[p], counts[p], status[p] = (
            alone.forces,
            alone.displacements,
            alone.iterations,
            alone.contact_status,
        )
        error[p] = alone.certificate.natural_map
        messages[p] = alone.message
    return LocalBatchResult(
        forces=x,
        displacements=u,
        error=error,
        success=error <= tol,
        iterations=counts,
        contact_status=status,
        tol=tol,
        seconds=time.perf_counter() - start,
        method="coulomb-batch",
        messages=messages,
    )

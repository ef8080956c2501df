"""The compiled Gauss-Seidel routes' shared driver: one kernel call, its result, Newton on a stall.

:mod:`~contactqp.methods.planar` (2-D, exact local solver) and
:mod:`~contactqp.methods.spatial` (3-D, local solver by cases) each run their whole solve in one
compiled call (:func:`~contactqp.kernels.compiled.planar_solve`,
:func:`~contactqp.kernels.compiled.spatial_solve`): ``W`` read once into contact blocks, the
sweeps, and the certificate from the final ``r`` and ``W`` as given. :func:`compiled_sweeps`
makes that call and its :class:`~contactqp.core.result.LocalResult`; when the sweeps stop short
(a stall, or their budget spent with iterations left), :func:`newton_after` hands the problem
to :func:`~contactqp.methods.coulomb.solve_coulomb` from the caller's start.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..core.local_problem import (
    CONTACT_FLOOR,
    STATUS_RTOL,
    LocalProblem,
    limits_from_norms,
)
from ..core.model import iteration_cap, positive_tolerance, warm_start
from ..core.operators import PSD_SHIFT
from ..core.result import LocalResult
from ..errors import InvalidInputError
from .coulomb import solve_coulomb
from .local_global import local_result

__all__ = ["checked_start", "compiled_sweeps", "kernel_arrays", "newton_after"]

_NO_ROWS = np.empty((0, 0))
_NO_INDEX = np.empty(0, dtype=np.int64)
_NO_DATA = np.empty(0)


def kernel_arrays(
    W: Any, index: type = np.int64
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(dense, indptr, indices, data)`` as the kernels take them: a dense ``W``
    (C-contiguous), or the CSR arrays of a sparse one, its indices of type ``index``
    (:func:`~contactqp.kernels.planar_gauss_seidel`: int64; the solve kernels: intp)."""
    if isinstance(W, np.ndarray):
        return np.ascontiguousarray(W, dtype=float), _NO_INDEX, _NO_INDEX, _NO_DATA
    import scipy.sparse as sp

    csr = sp.csr_matrix(W)
    return (
        _NO_ROWS,
        np.ascontiguousarray(csr.indptr, dtype=index),
        np.ascontiguousarray(csr.indices, dtype=index),
        np.ascontiguousarray(csr.data, dtype=float),
    )


def checked_start(problem, dim: int, method: str, r0, tol, max_iter) -> np.ndarray:
    """The start of a sweeps route (``r0``, or zero), once the checks both routes make pass:
    ``problem`` a :class:`~contactqp.core.local_problem.LocalProblem` of dimension ``dim``,
    ``tol`` and ``max_iter`` valid (the common case tested first, as coulomb does).

    Raises
    ------
    InvalidInputError
        Naming what is wrong.
    """
    if not isinstance(problem, LocalProblem):
        raise InvalidInputError(f"problem must be a LocalProblem, got {type(problem).__name__}")
    if problem.dim != dim:
        raise InvalidInputError(
            f"the {method} method solves {dim}-D problems, got dim {problem.dim}"
        )
    if not (type(tol) is float and 0.0 < tol < math.inf):
        positive_tolerance(tol)
    if not (type(max_iter) is int and max_iter >= 1):
        iteration_cap(max_iter)
    m = problem.q.shape[0]
    return np.zeros(m) if r0 is None else warm_start(r0, m)


def compiled_sweeps(
    problem: LocalProblem,
    kernel: Callable[..., tuple[int, int]],
    reasons: tuple[str, ...],
    method: str,
    bad_block: Callable[[int], None],
    r: np.ndarray,
    tol: float,
    budget: int,
    first: int,
    max_iter: int,
    check_psd: bool,
    per_contact: bool,
    start: float,
) -> tuple[LocalResult | None, int, float]:
    """The sweeps and the certificate in one call of ``kernel`` from ``r`` (overwritten), at
    most ``budget`` sweeps, the error evaluated after each of the ``first``.

    ``reasons`` names the kernel's codes; ``bad_block(contact)`` raises
    :class:`~contactqp.errors.NotPositiveDefiniteError` for the contact whose diagonal block
    failed the kernel's test (``check_psd``). Returns ``(result, sweeps, error)``: the result
    is None when the sweeps stopped short of ``tol`` (stalled, or ``budget`` spent) with
    iterations left for Newton; ``error`` is the natural-map error where they stopped.
    """
    nc = problem.n_contacts
    u = np.empty(r.shape[0])
    status = np.empty(nc, dtype=np.intp)
    measures = np.empty(4)
    sweeps, code = kernel(
        *kernel_arrays(problem.W, np.intp),
        problem.q,  # C-contiguous, as validated
        np.ascontiguousarray(problem.mu),  # a view of the caller's array, perhaps strided
        problem.apex_shift if np.count_nonzero(problem.law.cohesion) else _NO_DATA,  # empty: none
        r,
        u,
        status,
        measures,
        tol,
        budget,
        first,
        check_psd,
        PSD_SHIFT,
        True,
        per_contact,
        CONTACT_FLOOR,
        STATUS_RTOL,
    )
    reason = reasons[code]
    if reason == "diagonal block not semidefinite":  # sweeps is then the contact's index
        bad_block(sweeps)
    error, product, size_q, scale = measures.tolist()
    if reason != "converged" and sweeps < max_iter:
        return None, sweeps, error
    limits = limits_from_norms(product, size_q, scale, problem.digits)
    converged = error <= tol
    verdict = "converged" if converged else f"not converged to {tol:g}"
    message = (
        f"{verdict}: gauss-seidel {sweeps} sweeps"
        + ("" if reason == "converged" else " (budget spent)")
        + f"; natural-map error {error:.2e}"
        + (" (largest of the problem's and each contact's)" if per_contact else "")
    )
    notes = limits.describe(tol) if max(limits.rounding, limits.data) > tol else ""
    result = local_result(
        problem,
        r,
        u,
        converged=bool(converged),
        error=error,
        tol=tol,
        iterations=sweeps,
        seconds=time.perf_counter() - start,
        message=f"{message}; {notes}" if notes else message,
        method=method,
        limits=limits,
        contact_status=status,
    )
    return result, sweeps, error


def newton_after(
    problem: LocalProblem,
    r0,
    given: np.ndarray,
    tol: float,
    max_iter: int,
    check_psd: bool,
    per_contact: bool,
    start: float,
    sweeps: int,
    error: float,
) -> LocalResult:
    """The stalled sweeps' hand-over: :func:`~contactqp.methods.coulomb.solve_coulomb` from
    the caller's start (``given``; none when ``r0`` is None), ``sweeps`` and the natural-map
    ``error`` where they stopped in its message, ``sweeps`` in its iterations."""
    newton = solve_coulomb(
        problem,
        r0=None if r0 is None else given,
        tol=tol,
        max_iter=max_iter - sweeps,
        check_psd=check_psd,  # what Newton factors: all of W or its candidate sets' blocks
        per_contact=per_contact,
    )
    return dataclasses.replace(
        newton,
        iterations=newton.iterations + sweeps,
        seconds=time.perf_counter() - start,
        message=f"gauss-seidel {sweeps} sweeps (stalled; error {error:.1e}), then {newton.message}",
    )

"""The default solver: primal-dual active set on the dual, never inverting ``R``."""

from __future__ import annotations

import time

import numpy as np

from .. import kernels
from ..core.fastened import FastenedProblem
from ..core.model import iteration_cap, positive_tolerance, warm_start
from ..core.operators import DenseOperator, SymmetricDenseOperator, as_operator
from .box_qp import solve_box_qp
from .fastened import solve_fastened_box_qp

__all__ = ["solve_active_set", "cold_start"]

_ROW_CHUNK = 256


def cold_start(W, b):
    """A first guess of the contact forces whose support is close to the contact zone.

    Each interpenetration ``b_i > 0`` is shared over the row of ``W`` (a matrix or an
    :class:`~contactqp.core.operators.Operator`), so that the first free block is smaller than
    the whole overlap; only the first active set depends on it. Only the rows with ``b_i > 0``
    are read (the guess is zero elsewhere); a dense ``W``'s in one pass
    (:func:`~contactqp.kernels.abs_row_sums`), with no temporary of its size.
    """
    W = as_operator(W)
    b = np.asarray(b, dtype=float)
    overlap = np.flatnonzero(b > 0.0)
    sums = np.empty(overlap.size)
    matrix = W.matrix if isinstance(W, DenseOperator) else None
    if matrix is not None and matrix.dtype == np.float64 and matrix.flags.c_contiguous:
        kernels.abs_row_sums(matrix, overlap.astype(np.int64, copy=False), sums)
    else:
        for start in range(0, overlap.size, _ROW_CHUNK):  # |W| by row blocks
            rows = overlap[start : start + _ROW_CHUNK]
            sums[start : start + rows.size] = np.abs(W.block(rows, None)).sum(axis=1)
    guess = np.zeros(b.size)
    guess[overlap] = b[overlap] / sums
    return guess


def _operator(W):
    """``W`` as an operator; a dense C-ordered ``float64`` one as a symmetric operator (the dual's
    ``W`` is exactly symmetric, :class:`~contactqp.core.problem.DualForm`): its vector products
    read one triangle."""
    if (
        isinstance(W, np.ndarray)
        and W.dtype == np.float64
        and W.flags.c_contiguous
        and W.ndim == 2
        and W.shape[0] == W.shape[1]
    ):
        return SymmetricDenseOperator(W)
    return as_operator(W)


def solve_active_set(problem, *, r0=None, tol: float = 1e-10, max_iter: int = 500):
    """Solve a frictionless :class:`~contactqp.ContactProblem` on its dual.

    On a :class:`~contactqp.core.fastened.FastenedProblem`, the same solver runs on the reduced
    QP (:func:`~contactqp.methods.fastened.solve_fastened_box_qp`).

    Parameters
    ----------
    problem : ContactProblem or FastenedProblem
    r0 : array_like, shape (n_constraints,), optional
        Warm start: contact forces of a nearby problem (their support is the first active set).
    tol : float
        Relative natural-residual tolerance of :func:`~contactqp.methods.box_qp.solve_box_qp`.
    max_iter : int
        Largest number of iterations (both phases of the box-QP solver together).

    Returns
    -------
    ContactResult

    Raises
    ------
    InvalidInputError
        ``tol`` not a finite number > 0, ``max_iter`` not an integer >= 1, or ``r0`` of the
        wrong shape.
    """
    positive_tolerance(tol)
    iteration_cap(max_iter)
    if isinstance(problem, FastenedProblem):
        return solve_fastened_box_qp(problem, r0=r0, tol=tol, max_iter=max_iter)
    if r0 is not None:
        r0 = warm_start(r0, problem.n_constraints)
    start = time.perf_counter()
    dual = problem.dual()
    W = _operator(dual.W)
    if r0 is None:
        r0 = cold_start(W, dual.b)
    with np.errstate(over="ignore", invalid="ignore"):  # the certificate judges non-finite x
        solution = solve_box_qp(
            W, -dual.b, lower=0.0, x0=r0, tol=tol, max_iter=max_iter, check_finite=False
        )  # W: validated model
    forces = solution.x
    # the solver's gradient W x - b gives W x: no product with R for the displacements
    displacements = dual.displacements(forces, W_forces=solution.gradient + dual.b)
    elapsed = time.perf_counter() - start
    return problem.make_result(
        displacements,
        forces,
        method="active-set",
        converged=solution.converged,
        message=solution.message,
        iterations=solution.iterations,
        seconds=elapsed,
        info={
            "factorizations": solution.factorizations,
            "updates": solution.updates,
            "residual": solution.residual,
        },
    )

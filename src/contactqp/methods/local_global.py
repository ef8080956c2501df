"""Local FCLIB problems ``u = W r + q`` solved by the project's own methods.

The answer to a local problem (:class:`~contactqp.core.result.LocalResult`, built by
:func:`local_result` and :func:`finish`, shared by the local methods). Without friction
(every ``mu`` zero) the cones reduce to rays, the tangential reactions vanish and the normal
part is the bound-constrained QP
``min 1/2 r_N^T W_NN r_N + q_N^T r_N, r_N >= 0``, solved by the own box-QP solver
(:func:`solve_frictionless`).

A global problem is solved through its condensed form and the answer certified on the global
equations as written (:func:`certify_global`,
:meth:`~contactqp.core.local_problem.GlobalProblem.certify`; of a small one, in the compiled
route's one call, :func:`compiled_global_result`).
Every solution carries its :class:`~contactqp.core.local_problem.AccuracyLimits`: how far
rounding (the conditioning of ``M``) and the data's written digits limit its error.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..core.certificate import LocalCertificate
from ..core.local_problem import (
    AccuracyLimits,
    GlobalProblem,
    LocalProblem,
    accuracy_limits,
    certify_small,
    check_diagonal,
    column_products,
    contact_status_unchecked,
    limits_from_norms,
    natural_map_error,
    natural_map_residual,
)
from ..core.model import warm_start
from ..core.operators import SymmetricDenseOperator, as_operator, is_sparse
from ..core.result import NOT_CONVERGED, SUCCESS, LocalResult
from ..errors import InvalidInputError, NotPositiveDefiniteError
from .active_set import cold_start
from .box_qp import solve_box_qp

#: Machine epsilon (the rounding of :func:`~contactqp.core.local_problem.limits_from_norms`)
_EPS = float(np.finfo(float).eps)

__all__ = [
    "certified_result",
    "certify_global",
    "compiled_global_result",
    "finish",
    "local_result",
    "solve_frictionless",
]


def local_result(
    problem: LocalProblem | GlobalProblem,
    r,
    u,
    *,
    converged: bool,
    error: float,
    tol: float,
    iterations: int,
    seconds: float,
    message: str,
    method: str,
    limits: AccuracyLimits | None = None,
    equilibrium: float | None = None,
    v: np.ndarray | None = None,
    contact_status: np.ndarray | None = None,
) -> LocalResult:
    """The :class:`~contactqp.core.result.LocalResult` of reactions ``r`` and velocities ``u``
    (shape (m,)) of ``problem``, with the contact status computed from them (unless given:
    ``contact_status``, as :func:`~contactqp.core.local_problem.contact_status_unchecked`
    computes it).

    ``error`` (natural-map), ``equilibrium``, ``limits`` and ``tol`` make its certificate;
    ``converged`` is the method's verdict (status 0, else 1). A global ``problem`` needs its
    ``contact_status`` given (it is computed on the condensed problem).
    """
    r = np.asarray(r, dtype=float)
    u = np.asarray(u, dtype=float)
    certificate = LocalCertificate(
        natural_map=float(error),
        equilibrium=equilibrium,
        tol=float(tol),
        limits=AccuracyLimits(0.0, 0.0) if limits is None else limits,
    )
    return LocalResult(
        displacements=u,
        forces=r,
        nodal_forces=r,
        gaps=u[:: problem.dim],
        contact_status=(contact_status if contact_status is not None else _status(problem, r, u)),
        energy=float("nan"),
        success=bool(converged),
        status=SUCCESS if converged else NOT_CONVERGED,
        message=message,
        iterations=int(iterations),
        seconds=float(seconds),
        method=method,
        certificate=certificate,
        v=v,
    )


def _status(problem: LocalProblem | GlobalProblem, r, u) -> np.ndarray:
    if not isinstance(problem, LocalProblem):
        raise InvalidInputError("the contact status of a global problem must be given")
    return contact_status_unchecked(problem, r, u)


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


def _sparse_normal_columns(W: Any, dim: int) -> tuple[Any, np.ndarray]:
    """``(W[:, N], W_NN)`` of a sparse ``W``, ``N`` the normal components: the CSR columns
    :func:`finish` reads ``W r`` and ``|W| |r|`` from, and a dense copy of the normal block.

    The frictionless route's reactions are zero off the normal components, so these columns
    give all it needs of ``W``: the normal block, ``W r`` and ``|W| |r|``.
    """
    matrix: Any = as_operator(W).matrix
    columns = matrix[:, np.arange(matrix.shape[1] // dim) * dim]
    return columns, columns[::dim].toarray()


def _is_symmetric(A: np.ndarray, block: int = 128) -> bool:
    """``A == A^T`` exactly, compared by strips (no full-size temporary; stops at a difference)."""
    n = A.shape[0]
    return all(
        np.array_equal(A[i : i + block, i:], A[i:, i : i + block].T) for i in range(0, n, block)
    )


#: Entries of a block of rows (512 kB, in cache) by which the dense normal block is copied,
#: tested and summed, and ``W``'s tangential rows read.
_BLOCK_ENTRIES = 1 << 16


def _dense_normal_block(W: np.ndarray, dim: int) -> tuple[np.ndarray, bool, np.ndarray]:
    """``(W_NN, symmetric, s)`` of a dense ``W`` in one pass over its normal rows.

    ``W_NN`` is a contiguous copy of the normal block, ``symmetric`` whether ``W_NN == W_NN^T``
    exactly and ``s`` the row sums of ``|W_NN|``. Each block of rows is copied, summed and
    compared with the rows copied before it (``A[i:j, :j] == A[:j, i:j]^T``, which covers
    every pair) while it is in cache.
    """
    n = W.shape[0] // dim
    W_nn = np.empty((n, n))
    row_sums = np.empty(n)
    rows = max(1, _BLOCK_ENTRIES // max(1, n))
    scratch = np.empty((min(rows, n), n))
    symmetric = True
    for start in range(0, n, rows):
        stop = min(start + rows, n)
        block = W_nn[start:stop]
        block[...] = W[start * dim : stop * dim : dim, ::dim]
        np.abs(block, out=scratch[: stop - start]).sum(axis=1, out=row_sums[start:stop])
        symmetric = symmetric and np.array_equal(block[:, :stop], W_nn[:stop, start:stop].T)
    return W_nn, symmetric, row_sums


def _dense_normal_products(
    W: np.ndarray, W_nn: np.ndarray, x: np.ndarray, dim: int
) -> tuple[np.ndarray, np.ndarray]:
    """``(W r, |W| |r|)`` of the ``r`` that is ``x`` on the normal components and zero off
    them, exactly (the terms left out are zero), ``|W| |r|`` on the normal rows only (zero on
    the tangential ones, which a frictionless certificate does not depend on:
    :attr:`~contactqp.core.local_problem.LocalProblem.certified_rows`).

    Only the columns from the first to the last nonzero entry of ``x`` are read: the normal
    rows from the copy ``W_nn`` (the same numbers as ``W``'s), the tangential rows from ``W``
    in place, by blocks of rows that stay in cache.
    """
    m = W.shape[0]
    product, magnitude = np.zeros(m), np.zeros(m)
    loaded = np.flatnonzero(x)
    if loaded.size == 0:
        return product, magnitude
    first, last = int(loaded[0]), int(loaded[-1]) + 1
    xs = x[first:last]
    ax = np.abs(xs)
    spread = np.zeros((last - first) * dim)  # x on W's columns first * dim ... last * dim
    spread[::dim] = xs
    span = slice(first * dim, last * dim)
    rows = max(1, _BLOCK_ENTRIES // spread.size)
    scratch = np.empty((rows, xs.size))
    for start in range(0, W_nn.shape[0], rows):
        stop = min(start + rows, W_nn.shape[0])
        part = W_nn[start:stop, first:last]
        product[start * dim : stop * dim : dim] = part @ xs
        absolute = np.abs(part, out=scratch[: stop - start])
        magnitude[start * dim : stop * dim : dim] = absolute @ ax
        for k in range(1, dim):  # the tangential rows of these contacts: u_T only
            part = W[start * dim + k : stop * dim : dim, span]
            product[start * dim + k : stop * dim : dim] = part @ spread
    return product, magnitude


def solve_frictionless(
    problem: LocalProblem,
    *,
    r0=None,
    tol: float = 1e-8,
    max_iter: int | None = None,
    check_psd: bool = True,
    per_contact: bool = False,
) -> LocalResult:
    """Solve a local problem with ``mu = 0`` on every contact to natural-map error ``tol``.

    The cones are rays, the tangential reactions vanish and the normal part is the
    bound-constrained QP ``min 1/2 r_N^T W_NN r_N + q_N^T r_N, r_N >= 0``, solved by the own
    box-QP solver; :func:`~contactqp.solve` takes this route for every kind with ``mu = 0``
    everywhere when the default method is asked for.

    Parameters
    ----------
    problem : LocalProblem
        Every ``mu`` zero.
    r0 : array_like, shape (m,), optional
        Warm start (reactions); only the normal components are used.
    tol : float
        Target of :func:`~contactqp.core.local_problem.natural_map_error`; ``success`` is True
        only when the error, computed independently of the solver, is at most ``tol``.
    max_iter : int, optional
        Cap on the box-QP iterations (default 500).
    check_psd : bool
        Check the diagonal of ``W``'s normal block; every free block the box-QP solver factors
        is validated whatever this says.
    per_contact : bool
        Measure the natural map on every contact's own scale too.

    Raises
    ------
    InvalidInputError
        Some ``mu`` positive, or ``r0`` of the wrong shape.
    NotPositiveDefiniteError
        Only the normal block ``W_NN`` is solved on, and it is validated at no extra cost: its
        diagonal (:func:`~contactqp.core.local_problem.check_diagonal`), and each free block
        the box-QP solver factors (:meth:`~contactqp.core.operators.Operator.cholesky`). An
        indefinite part of ``W_NN`` that no free block reaches (contacts that stay open) is not
        looked for: the answer is then judged, like every answer, by the natural-map error on
        the whole ``W``.
    """
    if np.any(problem.mu > 0):
        raise InvalidInputError("the frictionless route needs mu = 0 on every contact")
    start = time.perf_counter()
    normal = np.arange(problem.n_contacts) * problem.dim
    dense = not is_sparse(problem.W)
    if dense:
        W_dense = np.asarray(problem.W)
        W_nn, symmetric, row_sums = _dense_normal_block(W_dense, problem.dim)
    else:
        normal_columns, W_nn = _sparse_normal_columns(problem.W, problem.dim)
        symmetric = _is_symmetric(W_nn)
    W_sym = W_nn if symmetric else 0.5 * (W_nn + W_nn.T)
    if check_psd:
        check_diagonal(W_sym, "W's normal block")
    q_n = problem.q[normal]
    if r0 is None:
        with np.errstate(divide="ignore", invalid="ignore"):  # a zero row of W_NN: start at 0
            guess = (
                np.maximum(-q_n, 0.0) / row_sums  # cold_start's, from the sums of the pass
                if dense and symmetric
                else cold_start(W_sym, -q_n)
            )
            first = np.nan_to_num(guess, nan=0.0, posinf=0.0)
    else:
        first = np.maximum(warm_start(r0, problem.W.shape[0])[normal], 0.0)
    try:  # the box-QP's own factorisations of free blocks validate them
        solution = solve_box_qp(
            SymmetricDenseOperator(W_sym) if dense else W_sym,  # W_sym == W_sym.T exactly
            q_n,
            lower=0.0,
            x0=first,
            tol=min(tol, 1e-10) * 1e-2,
            max_iter=500 if max_iter is None else max_iter,
            check_finite=False,
        )  # W: validated by LocalProblem
    except NotPositiveDefiniteError as exc:
        raise NotPositiveDefiniteError(f"W's normal block: {exc}") from None
    # a symmetric W_NN: the QP's minimiser solves the complementarity problem, nothing to polish
    reactions = solution.x if symmetric else _polish(problem, W_nn, q_n, normal, solution.x)
    r = np.zeros(problem.W.shape[0])
    r[normal] = reactions
    if dense:  # W r and |W| |r| of the given W, over the columns where r is not zero
        products = _dense_normal_products(W_dense, W_nn, reactions, problem.dim)
    else:
        products = column_products(normal_columns, reactions)
    return finish(
        problem,
        r,
        tol,
        solution.iterations,
        start,
        solution.message,
        method="normal-qp",
        per_contact=per_contact,
        products=products,
    )


def finish(
    problem: LocalProblem,
    r,
    tol: float,
    iterations: int,
    start: float,
    detail: str,
    *,
    method: str,
    per_contact: bool = False,
    products: tuple[np.ndarray, np.ndarray] | None = None,
) -> LocalResult:
    """The :class:`~contactqp.core.result.LocalResult` of reactions ``r``, checked by the
    natural-map error.

    ``u``, the error, the verdict and the contact status are computed here from ``r`` alone,
    independently of the solver; ``start`` is the solver's ``time.perf_counter()`` at entry and
    ``detail`` its account of the iterations, put in the message beside the verdict and error.
    ``per_contact`` chooses the error (:func:`~contactqp.core.local_problem.natural_map_error`).
    ``products = (W r, |W| |r|)``, when the caller has read them from the given ``W`` (over
    the columns where ``r`` is not zero), saves reading ``W`` again.
    """
    r = np.asarray(r, dtype=float)
    status = None
    if products is None and problem.small is not None:  # in one compiled pass
        u, error, limits, status = certify_small(problem, r, per_contact=per_contact)
    else:
        if products is None:
            u = np.asarray(problem.W @ r).reshape(-1) + problem.q
            limits = accuracy_limits(problem, r, u)
        else:
            product, magnitude = products
            u = product + problem.q
            limits = accuracy_limits(problem, r, u, magnitude=magnitude)
        error = natural_map_residual(problem, r, u, per_contact=per_contact)[1]
    return certified_result(
        problem, r, u, error, limits, status, tol, iterations, start, detail, method, per_contact
    )


def certified_result(
    problem: LocalProblem,
    r: np.ndarray,
    u: np.ndarray,
    error: float,
    limits: AccuracyLimits,
    status: np.ndarray | None,
    tol: float,
    iterations: int,
    start: float,
    detail: str,
    method: str,
    per_contact: bool,
) -> LocalResult:
    """:func:`finish`'s result of a certificate computed already: ``u = W r + q``, the
    natural-map ``error``, its ``limits`` and the contact ``status`` codes (None: computed
    here), all of the given ``r``."""
    converged = bool(error <= tol)
    verdict = "converged" if converged else f"not converged to {tol:g}"
    return local_result(
        problem,
        r,
        u,
        converged=converged,
        error=error,
        tol=tol,
        iterations=iterations,
        seconds=time.perf_counter() - start,
        method=method,
        limits=limits,
        contact_status=status,
        message=_with_limits(
            f"{verdict}: {detail}; natural-map error {error:.2e}"
            + (" (largest of the problem's and each contact's)" if per_contact else ""),
            limits,
            tol,
        ),
    )


def _with_limits(message: str, limits: AccuracyLimits, tol: float) -> str:
    if limits.rounding <= tol and limits.data <= tol:  # no note (describe's test)
        return message
    notes = limits.describe(tol)
    return f"{message}; {notes}" if notes else message


def certify_global(
    problem: GlobalProblem,
    local: LocalResult,
    tol: float,
    start: float,
    *,
    factor=None,
    condensed: LocalProblem | None = None,
) -> LocalResult:
    """The solution ``local`` of ``problem.condense()`` judged on the global equations as written.

    ``v`` solves ``M v = H r + f`` (``M`` as given), ``u = H^T v + w``, and the certificate's
    natural-map error is that of ``(r, u)``
    (:meth:`~contactqp.core.local_problem.GlobalProblem.certify`); ``success`` when it and
    the relative equilibrium residual are both at most ``tol``. Its ``limits`` give the attainable
    error set by the conditioning of ``M`` and the limit set by the data's digits, and the
    message names any above ``tol``. ``start`` is the ``time.perf_counter()`` of the solve.
    ``factor`` and ``condensed``: the factorisation of ``M`` and the local problem it gave, when
    the caller made them (:func:`contactqp.methods.global_route.condense`).
    """
    r = local.forces
    certificate = problem.certify(r, factor=factor, local=condensed)
    error, equilibrium = certificate.error, certificate.equilibrium
    converged = bool(error <= tol and equilibrium <= tol)
    verdict = "converged" if converged else f"not converged to {tol:g}"
    message = (
        f"{verdict} on the global equations as written: natural-map error {error:.2e}, "
        f"equilibrium residual {equilibrium:.1e} (condensed problem: {local.message})"
    )
    return local_result(
        problem.condense() if condensed is None else condensed,
        r,
        certificate.u,
        converged=converged,
        error=error,
        tol=tol,
        iterations=local.iterations,
        seconds=time.perf_counter() - start,
        method=local.method,
        message=_with_limits(message, certificate.limits, tol),
        limits=certificate.limits,
        equilibrium=equilibrium,
        v=certificate.v,
    )


def compiled_global_result(
    problem: GlobalProblem,
    r: np.ndarray,
    u: np.ndarray,
    v: np.ndarray,
    status: np.ndarray,
    measures: np.ndarray,
    tol: float,
    per_contact: bool,
    start: float,
    *,
    iterations: int | None = None,
    detail: str | None = None,
) -> LocalResult:
    """The :class:`~contactqp.core.result.LocalResult` of the compiled small global route
    (:func:`contactqp.methods.global_route.solve_compiled`), from what
    :func:`~contactqp.kernels.compiled.global_small` computed: the same fields, verdict and
    message as :func:`certify_global` gives the general route's answer.

    ``measures`` holds the figures named by
    :data:`~contactqp.kernels.compiled.GLOBAL_MEASURES`; ``status`` the contact status.
    ``iterations`` and ``detail`` (how the condensed problem was solved), when given, replace
    what ``measures`` says of the solve (a certificate computed apart from it).
    """
    (
        error,
        equilibrium,
        rounding,
        data,
        condition,
        local_error,
        local_product,
        local_size_q,
        local_scale,
        measured_iterations,
        groups,
        _,
    ) = measures.tolist()
    k = int(measured_iterations if iterations is None else iterations)
    limits = AccuracyLimits(
        rounding=rounding, data=data, condition=condition, digits=dict(problem.digits)
    )
    if detail is None:
        detail = f"newton {k} it. (converged)"
        if groups > 1:
            detail += f" on {int(groups)} groups of contacts that W does not couple"
    local_verdict = "converged" if local_error <= tol else f"not converged to {tol:g}"
    local_message = f"{local_verdict}: {detail}; natural-map error {local_error:.2e}" + (
        " (largest of the problem's and each contact's)" if per_contact else ""
    )
    if _EPS * (local_product + local_size_q) > tol * (local_scale or 1.0):  # a note (finish's)
        local_limits = limits_from_norms(local_product, local_size_q, local_scale, {}, (0.0, 0.0))
        local_message = _with_limits(local_message, local_limits, tol)
    converged = bool(error <= tol and equilibrium <= tol)
    verdict = "converged" if converged else f"not converged to {tol:g}"
    message = (
        f"{verdict} on the global equations as written: natural-map error {error:.2e}, "
        f"equilibrium residual {equilibrium:.1e} (condensed problem: {local_message})"
    )
    return local_result(
        problem,
        r,
        u,
        converged=converged,
        error=error,
        tol=tol,
        iterations=k,
        seconds=time.perf_counter() - start,
        method="coulomb",
        message=_with_limits(message, limits, tol),
        limits=limits,
        equilibrium=equilibrium,
        v=v,
        contact_status=status,
    )

r"""Coulomb friction on the local form ``u = W r + q``: semismooth Newton, Gauss-Seidel fallback.

Formulation (Alart and Curnier 1991). For each contact, with ``rho_i > 0``,

.. math::

    \Phi_N = r_N - \max(0,\ r_N - \rho u_N), \qquad
    \Phi_T = r_T - P_{B(0,\ \mu \max(0, r_N - \rho u_N))}(r_T - \rho u_T),

and ``Phi(r) = 0`` (with ``u = W r + q``) is exactly the Coulomb law of
:class:`~contactqp.core.local_problem.LocalProblem`. ``Phi`` is piecewise smooth; a generalised
Jacobian is ``A + B W`` with ``A = dPhi/dr`` and ``B = dPhi/du`` block diagonal (one ``dim x dim``
block per contact, computed with ``Phi`` by one compiled loop over the contacts,
:mod:`contactqp.kernels`; ``rho_i`` = 1 / mean diagonal of ``W_ii``).
A released contact's step is simply ``-Phi``: each Newton step factors only the block of the other
contacts, with LAPACK (``numpy.linalg.solve``: dense ``W``, or sparse ``W`` that
:func:`~contactqp.core.local_problem.better_dense` prefers dense) or SuperLU
(``scipy.sparse.linalg.splu``: the matrix is assembled on ``W``'s stored blocks straight into CSC
storage, in a minimum-degree order computed once).

Safeguards, for the singular ``W`` of rigid multibody problems (more contact unknowns than body
freedoms):

* the Newton matrix is regularised as ``A + B (W + eta D)``, ``D`` the mean diagonal of each
  contact block, ``eta = min(1e-2, e)`` with ``e`` the current natural-map error (it vanishes at
  the solution, so convergence stays fast);
* a full step is taken when it lowers the absolute natural-map residual (the numerator of the error,
  :func:`~contactqp.core.local_problem.natural_map_residual`, which unlike the ratio cannot fall by
  letting ``r`` grow); otherwise a non-monotone Armijo line search on the merit ``1/2 ||Phi||^2``
  (the reference is the largest merit of the last 5 iterations; Grippo, Lampariello and Lucidi
  1986), because the merit has kinks where contacts change status;
* a run stops when its best error has not halved in 20 iterations; a Levenberg-Marquardt run
  (``eta`` adapted to the success of full steps) then continues from the best point;
* if that fails too, 100 nonsmooth Gauss-Seidel sweeps (:mod:`contactqp.methods.pgs`) and both
  Newton runs again, in at most 3 rounds (one only on a dense ``W`` of low rank,
  :func:`~contactqp.methods.proximal.low_rank_factor`: rigid bodies, where the later rounds
  were not seen to converge where the first had not);
* if every round failed, proximal-point iterations (:mod:`contactqp.methods.proximal`: Newton
  runs on ``W + rho D``, up to 1000 inner iterations) from a cold start ``r = 0`` (on walls of
  rigid boxes where the rounds failed, it converged from there on 7 of 9, from where the
  rounds stopped on 6). The better of the two points is kept.

Each stage that stops short of ``tol`` says in the message the error it reached.

Convergence is decided only by :func:`~contactqp.core.local_problem.natural_map_error` (<= ``tol``),
never by the solver's own residual. Cohesion is handled by translating each cone to its apex
(:attr:`~contactqp.core.local_problem.LocalProblem.apex_shift`): ``r~ = r + s`` solves the FCLIB
problem with ``q~ = q - W s``.

References
----------
P. Alart, A. Curnier, "A mixed formulation for frictional contact problems prone to Newton like
solution methods", CMAME 92 (1991). V. Acary, M. Bremond, O. Huber, "On solving contact problems
with Coulomb friction: formulations and numerical comparisons", INRIA RR-9118 (2018).
"""

from __future__ import annotations

import copy
import math
import time
import warnings
from dataclasses import dataclass

import numpy as np

from .. import kernels
from ..core.local_problem import (
    CONTACT_FLOOR,
    STATUS_RTOL,
    LocalProblem,
    better_dense,
    check_positive_semidefinite,
    column_products,
    limits_from_norms,
    natural_map_residual,
)
from ..core.model import iteration_cap, positive_tolerance, warm_start
from ..core.operators import Operator, is_sparse
from ..errors import InvalidInputError
from .local_global import certified_result, finish
from .pgs import GaussSeidel
from .proximal import low_rank_factor, proximal_point

__all__ = [
    "solve_coulomb",
    "solve_proximal",
    "PROXIMAL_MAX_ITER",
    "solve_on_candidates",
    "CandidateSolution",
    "alart_curnier",
]

REGULARISATION = 1e-2  # largest eta of the Newton matrix A + B (W + eta D); LM start
LM_MIN, LM_MAX, LM_TRIES = 1e-12, 1e6, 3  # Levenberg-Marquardt range of eta, tries per step
MEMORY = 5  # iterations looked back by the non-monotone line search (twice that for LM)
ARMIJO = 1e-4  # sufficient-decrease constant
MAX_HALVINGS = 30  # line search gives up below a step of 2**-30
STALL = 20  # a Newton run stops when its best error has not halved in this many iterations
PGS_SWEEPS = 100  # Gauss-Seidel sweeps before each later round
ROUNDS = 3  # rounds of (Gauss-Seidel,) Newton, Levenberg-Marquardt Newton
RUN_ITERATIONS = 100  # largest number of iterations of one Newton (or LM) run
PROXIMAL_ITERATIONS = 1000  # largest number of inner Newton iterations of the proximal stage
PROXIMAL_MAX_ITER = 2000  # default budget of :func:`solve_proximal` (inner Newton iterations)
#: Default total budget: what all the stages can spend (3 rounds of two runs, 2 x 100 sweeps,
#: the proximal stage's 1000 inner iterations).
MAX_ITER = 2 * ROUNDS * RUN_ITERATIONS + (ROUNDS - 1) * PGS_SWEEPS + PROXIMAL_ITERATIONS
PIVOT_THRESHOLD = 0.1  # SuperLU keeps a diagonal pivot down to this share of its column's max
_NO_JACOBIAN = np.empty((0, 3, 3))  # tells kernels.alart_curnier_rows to skip the Jacobian
ACTIVE_SET_MIN = 64  # contacts from which a dense problem is solved on its candidate set
ACTIVE_SET_GROWTH = 8  # fewest violators added to the candidate set at once


def alart_curnier(R, U, mu, rho, jacobian: bool = False):
    """Alart-Curnier function of every contact, and optionally its generalised Jacobian blocks.

    Parameters
    ----------
    R, U : numpy.ndarray, shape (n_contacts, dim)
        Reactions and velocities, normal component first.
    mu, rho : numpy.ndarray, shape (n_contacts,)
        Friction coefficients and the (positive) augmentation parameters.
    jacobian : bool
        Also return ``A = dPhi/dr`` and ``B = dPhi/du``.

    Returns
    -------
    Phi : numpy.ndarray, shape (n_contacts, dim)
    A, B : numpy.ndarray, shape (n_contacts, dim, dim)
        Only with ``jacobian=True``.
    """
    Phi = np.empty_like(R)
    if not jacobian:
        kernels.alart_curnier_rows(R, U, mu, rho, Phi, _NO_JACOBIAN, _NO_JACOBIAN)
        return Phi
    A, B = np.empty(R.shape + R.shape[1:]), np.empty(R.shape + R.shape[1:])
    kernels.alart_curnier_rows(R, U, mu, rho, Phi, A, B)
    return Phi, A, B


class _Newton:
    """Semismooth Newton iterations on the Alart-Curnier function of ``(W, q, mu)``.

    ``W`` is a dense array, or a sparse matrix that
    :func:`~contactqp.core.local_problem.better_dense` leaves sparse. ``low_rank``, for a dense
    ``W``, is ``(G, weights)`` with ``W = G G^T + diag(weights)`` to rounding, ``G`` of few
    columns and ``weights > 0`` (the proximal stage's operators): the steps are then solved
    through ``G`` (:meth:`_low_rank_solve`).
    """

    def __init__(self, W, q, mu, dim, measure, low_rank=None):
        self.W, self.q, self.mu, self.d = W, q, mu, dim
        self.low_rank = low_rank
        self.nc = mu.shape[0]
        self.sparse = is_sparse(W)
        diag = np.asarray(W.diagonal(), dtype=float).reshape(self.nc, dim).mean(axis=1)
        self.scale = np.where(diag > 0, diag, 1.0)  # D: per-contact diagonal scale of W
        self.rho = 1.0 / self.scale
        self.measure = measure
        if self.sparse:
            self._block_structure()

    def _block_structure(self):
        """Blocks of ``W`` (diagonal blocks always stored) and their order in CSC storage.

        ``A + B W`` has the block pattern of ``W`` plus the diagonal: each Newton step computes
        ``B_c W_cj`` (plus ``A_c``) on the stored blocks straight into CSC order
        (:func:`~contactqp.kernels.sparse_newton_matrix`).
        The unknowns are renumbered once by SuperLU's minimum-degree ordering of that pattern,
        so that each step's factorisation keeps the natural order (no new ordering per step).
        """
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        nc, d, m = self.nc, self.d, self.W.shape[0]
        coo = sp.coo_matrix(self.W)
        block = np.arange(nc).repeat(d * d)
        local = np.tile(np.arange(d * d), nc)
        rows = np.concatenate([coo.row, block * d + local // d])
        cols = np.concatenate([coo.col, block * d + local % d])
        values = np.concatenate([coo.data, np.zeros(nc * d * d)])
        blocks = sp.csr_matrix((values, (rows, cols)), shape=(m, m)).tobsr(blocksize=(d, d))
        blocks.sort_indices()
        self.W_blocks = blocks.data
        self.block_row = np.repeat(np.arange(nc, dtype=np.int64), np.diff(blocks.indptr))
        self.block_col = blocks.indices.astype(np.int64)
        positions = sp.bsr_matrix(
            (
                np.arange(1.0, blocks.data.size + 1).reshape(blocks.data.shape),
                blocks.indices,
                blocks.indptr,
            ),
            shape=(m, m),
        ).tocsc()
        pattern = positions.copy()
        pattern.data[:] = 1.0
        pattern.setdiag(float(m))  # diagonally dominant: only the ordering is wanted here
        self.order = np.argsort(splu(pattern, permc_spec="MMD_AT_PLUS_A").perm_c)
        positions = positions[self.order][:, self.order].tocsc()
        positions.sort_indices()
        block, element = np.divmod(positions.data.astype(np.int64) - 1, d * d)
        self.csc_entries = np.column_stack([block, *np.divmod(element, d)])  # (block, row, col)
        self.csc_indices = positions.indices.astype(np.int64)
        self.csc_indptr = positions.indptr.astype(np.int64)

    def with_q(self, q, measure) -> _Newton:
        """The same runner on ``(W, q, mu)`` with another ``q`` and ``measure`` (``W``'s
        block structure and ordering shared)."""
        twin = copy.copy(self)
        twin.q, twin.measure = q, measure
        return twin

    def residual(self, r):
        u = self.W @ r + self.q
        Phi = alart_curnier(
            r.reshape(self.nc, self.d), u.reshape(self.nc, self.d), self.mu, self.rho
        )
        return u, Phi.reshape(-1)

    def direction(self, r, u, eta):
        """Solve ``(A + B (W + eta D)) dr = -Phi``; None if the matrix is singular.

        A released contact (``r_N - rho u_N <= 0`` with a nonzero tangential trial) has
        ``B_c = 0`` (hence ``A_c = I``): its step is ``-Phi_c`` outright. Its coupling to the
        other contacts moves to the right-hand side, and only their block of ``A + B W`` is
        factored (most contacts are open in a typical problem).
        """
        nc, d = self.nc, self.d
        Phi, A, B = alart_curnier(r.reshape(nc, d), u.reshape(nc, d), self.mu, self.rho, True)
        A += (eta * self.scale)[:, None, None] * B
        kept = B.reshape(nc, d * d).any(axis=1)
        step = -Phi.reshape(-1)
        if not kept.any():
            return step
        rhs = step.copy()
        if not kept.all():
            coupling = self.W @ np.where(np.repeat(kept, d), 0.0, step)  # W (released steps)
            rhs -= np.matmul(B, coupling.reshape(nc, d, 1)).reshape(-1)
        if self.low_rank is not None and self._low_rank_solve(A, B, kept, rhs, step):
            return step
        solve = self._sparse_solve if self.sparse else self._dense_solve
        if not solve(A, B, kept, rhs, step):
            return None
        return step if np.all(np.isfinite(step)) else None

    def _dense_solve(self, A, B, kept, rhs, step) -> bool:
        """Write the kept contacts' rows of the step (LAPACK on their block); False if singular."""
        d = self.d
        kept = np.flatnonzero(kept)
        n_kept = kept.size
        if n_kept == self.nc:
            rows, W_kept = slice(None), self.W
        else:
            rows = (kept[:, None] * d + np.arange(d)).reshape(-1)
            W_kept = self.W[np.ix_(rows, rows)]
        J = np.matmul(B[kept], W_kept.reshape(n_kept, d, n_kept * d)).reshape(n_kept * d, -1)
        idx = np.arange(n_kept)
        J.reshape(n_kept, d, n_kept, d)[idx, :, idx, :] += A[kept]
        try:
            step[rows] = np.linalg.solve(J, rhs[rows])
        except np.linalg.LinAlgError:  # exactly singular
            return False
        return True

    def _low_rank_solve(self, A, B, kept, rhs, step) -> bool:
        """The kept contacts' rows of the step through ``W = G G^T + diag(w)`` (Woodbury).

        On the kept rows ``A + B W = T + (B G) G^T`` with ``T = A + B diag(w)`` block diagonal,
        so ``x = T^-1 b - Y (I + G^T Y)^-1 G^T T^-1 b``, ``Y = T^-1 B G``: ``2 m k^2`` flops for
        ``k`` columns of ``G``, against ``2 m^3 / 3`` for the LU of the block. False (the LU
        then) when a block of ``T`` or the small matrix is singular, or the step not finite.
        """
        G, weights = self.low_rank
        d = self.d
        kept = np.flatnonzero(kept)
        n_kept, k = kept.size, G.shape[1]
        rows = (kept[:, None] * d + np.arange(d)).reshape(-1)
        G_kept = G[rows]
        B_kept = B[kept]
        try:
            T_inverse = np.linalg.inv(A[kept] + B_kept * weights[rows].reshape(n_kept, 1, d))
            Y = np.matmul(T_inverse, np.matmul(B_kept, G_kept.reshape(n_kept, d, k)))
            Y = Y.reshape(n_kept * d, k)
            y = np.matmul(T_inverse, rhs[rows].reshape(n_kept, d, 1)).reshape(-1)
            small = G_kept.T @ Y
            small[np.diag_indices_from(small)] += 1.0
            x = y - Y @ np.linalg.solve(small, G_kept.T @ y)
        except np.linalg.LinAlgError:
            return False
        if not np.all(np.isfinite(x)):
            return False
        step[rows] = x
        return True

    def _sparse_solve(self, A, B, kept, rhs, step) -> bool:
        """The kept contacts' rows of the step by SuperLU on their block; False if singular."""
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        kept_unknowns = np.repeat(kept, self.d)[self.order]  # in the factorisation's order
        renumber = np.cumsum(kept_unknowns, dtype=np.int64) - 1
        renumber[~kept_unknowns] = -1
        n = int(kept_unknowns.sum())
        data = np.empty(self.csc_indices.size)
        indices = np.empty_like(self.csc_indices)
        indptr = np.empty(n + 1, dtype=self.csc_indptr.dtype)
        count = kernels.sparse_newton_matrix(
            A,
            B,
            self.W_blocks,
            self.block_row,
            self.block_col,
            self.csc_entries,
            self.csc_indptr,
            self.csc_indices,
            renumber,
            data,
            indices,
            indptr,
        )
        J = sp.csc_matrix((data[:count], indices[:count], indptr), shape=(n, n))
        rows = self.order[kept_unknowns]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a near-singular factor shows as a non-finite step
            try:
                lu = splu(J, permc_spec="NATURAL", diag_pivot_thresh=PIVOT_THRESHOLD)
            except RuntimeError:  # exactly singular
                return False
            step[rows] = lu.solve(rhs[rows])
        return True

    def line_search(self, r, step, residual, reference, merit, tries=MAX_HALVINGS):
        """Backtrack from a full step; return ``(r, u, Phi, measures)`` or None if it fails.

        The full step is taken when it lowers ``residual``, the natural-map residual of ``r``
        (the merit ``1/2 ||Phi||^2`` can rise where that falls: it weighs reactions and
        velocities differently); any step when it meets the non-monotone Armijo condition.
        ``measures`` is ``(residual, relative error)`` of the new point.
        """
        t = 1.0
        for _ in range(tries):
            trial = r + t * step
            u, Phi = self.residual(trial)
            measures = self.measure(trial, u)
            if 0.5 * float(Phi @ Phi) <= reference - ARMIJO * t * merit or (
                t == 1.0 and measures[0] < residual
            ):
                return trial, u, Phi, measures
            t *= 0.5
        return None

    def run(self, r, tol, max_iter, adaptive):
        """Iterate from ``r``; return ``(best r, its error, iterations, reason)``.

        ``adaptive=False``: ``eta = min(1e-2, error)`` and a line search on each direction.
        ``adaptive=True`` (Levenberg-Marquardt): ``eta`` is divided by 10 after a full step
        is accepted and multiplied by 10 (new factorisation) when it is not, up to 3 times
        before the line search takes over; a longer non-monotone memory.
        A run stops early when its best error has not halved in the last 20 iterations.
        """
        memory = 2 * MEMORY if adaptive else MEMORY
        eta = REGULARISATION
        u, Phi = self.residual(r)
        residual, error = self.measure(r, u)
        best = (r, error)
        history, errors = [], [error]
        for k in range(max_iter):
            if error <= tol:
                return r, error, k, "converged"
            if len(errors) > STALL and min(errors[-STALL:]) > 0.5 * min(errors[:-STALL]):
                return best[0], best[1], k, "stalled"
            merit = 0.5 * float(Phi @ Phi)
            history.append(merit)
            reference = max(history[-memory:])
            found = None
            if adaptive:
                for _ in range(LM_TRIES):
                    step = self.direction(r, u, eta)
                    if step is not None:
                        found = self.line_search(r, step, residual, reference, merit, tries=1)
                        if found:
                            eta = max(0.1 * eta, LM_MIN)
                            break
                    eta = min(10.0 * eta, LM_MAX)
            else:
                step = self.direction(r, u, min(REGULARISATION, error))
            if step is None:
                return best[0], best[1], k, "singular Newton matrix"
            found = found or self.line_search(r, step, residual, reference, merit)
            if found is None:
                return best[0], best[1], k, "line search failed"
            r, u, Phi, (residual, error) = found
            errors.append(error)
            if error < best[1]:
                best = (r, error)
        return best[0], best[1], max_iter, "iteration limit"


def _rounds(W, q, mu, d, r, tol, max_iter, measure, first=None, proximal=True):
    """Newton, Levenberg-Marquardt, then (Gauss-Seidel, both Newton runs) up to 3 rounds on
    the FCLIB problem ``(W, q, mu)`` from ``r``, then, only if they all failed, proximal-point
    iterations from ``r = 0`` (:func:`~contactqp.methods.proximal.proximal_point`);
    ``(r, iterations, stages)``. With the proximal stage and a ``W`` of low rank
    (:func:`~contactqp.methods.proximal.low_rank_factor`), a failed first round goes to it
    directly.

    ``measure(r, u)`` is ``(residual, error)``, the convergence test (error <= ``tol``).
    ``first``: what the first Newton run returned when it was run already (by the compiled
    small-problem route), ``(r, error, iterations, reason)``. ``proximal=False``: without
    the proximal stage (a candidate set's subproblem: when it fails, the whole problem is
    solved next, and only its failure is the route's).
    """
    newton = _Newton(W, q, mu, d, measure)
    gauss_seidel = None
    factor = None  # W's low-rank factor, looked for once the first round has failed
    error, iterations, stages = math.inf, 0, []
    for round_ in range(ROUNDS):
        if round_:
            gauss_seidel = gauss_seidel or GaussSeidel(W, q, mu, d)
            sweeps = min(PGS_SWEEPS, max_iter - iterations)
            for sweep in range(1, sweeps + 1):
                r = gauss_seidel.sweep(r)
                if (sweep % 10 == 0 or sweep == sweeps) and (
                    error := measure(r, W @ r + q)[1]
                ) <= tol:
                    break
            iterations += sweep
            stages.append(f"gauss-seidel {sweep} sweeps ({_reached(error, tol)})")
        for adaptive in (False, True):
            if iterations >= max_iter:
                break
            budget = min(RUN_ITERATIONS, max_iter - iterations)
            if first is not None and not round_ and not adaptive:
                r, error, k, reason = first
            else:
                r, error, k, reason = newton.run(r, tol, budget, adaptive)
            iterations += k
            name = "levenberg-marquardt" if adaptive else "newton"
            stages.append(f"{name} {k} it. ({_reached(error, tol, reason)})")
            if error <= tol:
                break
        if error <= tol:
            break
        if iterations >= max_iter:
            stages.append(f"max_iter = {max_iter} reached")
            break
        if not round_ and proximal:
            factor = low_rank_factor(W)
            if factor is not None:
                # a dense W of low rank (rigid bodies) whose first round failed: on the walls
                # of tests/multibody_problems.py of 500 unknowns and more the later rounds
                # never converged where the first had not, and cost the proximal stage's
                # time again
                stages.append("no more rounds (W of low rank)")
                break
    if proximal and error > tol and iterations < max_iter:
        # the last stage: proximal-point iterations from a cold start (the point where the
        # Newton runs stalled attracts them too, measured on the walls of rigid boxes of
        # tests/multibody_problems.py); the better of the two points is kept
        budget = min(PROXIMAL_ITERATIONS, max_iter - iterations)
        cold = np.zeros_like(r)
        x, new, k, reason = proximal_point(
            W, q, mu, d, cold, tol, budget, measure, _Newton, low_rank=factor
        )  # the stage runs only after a failed first round, which looked for the factor
        iterations += k
        stages.append(f"proximal from r = 0 {k} it. ({_reached(new, tol, reason)})")
        if new < error:  # error: that of r, the best point of the last run
            r = x
    return r, iterations, stages


def _reached(error: float, tol: float, reason: str = "") -> str:
    """A stage's account: ``reason`` and, when the stage stopped short of ``tol``, its error."""
    if error <= tol:
        return reason or "converged"
    return f"{reason}; error {error:.1e}" if reason else f"error {error:.1e}"


def _entries(W, rows, cols) -> np.ndarray:
    """Dense ``W[rows][:, cols]`` of a dense ``W`` or an :class:`Operator`."""
    if isinstance(W, Operator):
        return W.block(rows, cols)
    return W[np.ix_(rows, cols)]


def _active_set(W, q, mu, d, r, tol, max_iter, per_contact, look_ahead=False, check_psd=False):
    """Solve on the contacts that can close; ``(r, iterations, stages, index)``.

    The FCLIB problem ``(W, q, mu)`` (dense ``W``, or an :class:`Operator` read only on the
    blocks asked for) is solved on a candidate set ``C`` of
    contacts (those of the warm start ``r`` that carry force), the others held open at
    ``r = 0``. An open contact satisfies the law exactly when its normal gap
    ``u_N = W_NC r_C + q_N`` is not negative, which one product with the columns of ``C``
    checks; the violators are added (the most violated first, at most as many as ``C``
    holds, and at least :data:`ACTIVE_SET_GROWTH`) and ``C`` is solved again from its last
    solution. The subproblem's error (relative to its own, smaller scale) bounds the whole
    problem's, so a converged ``C`` without violators solves the whole problem.
    ``index`` is the components of ``C`` (``r`` is zero elsewhere), or None when a
    subproblem did not converge or ``C`` grew past half of the contacts: the caller then
    solves the whole problem from ``r``. ``look_ahead``: the open contacts that the warm
    start itself closes join ``C`` before its first solve (a warm start from a nearby
    problem's answer then usually needs one solve, not two). ``check_psd``: each candidate
    set's block of ``W`` is checked positive semidefinite before it is solved on.
    """
    nc = mu.shape[0]
    normal = np.arange(nc) * d
    R = r.reshape(nc, d)
    candidate = np.flatnonzero(np.any(R != 0.0, axis=1))
    if look_ahead and candidate.size:
        candidate = _with_violators(W, q, d, r, candidate, normal)
    iterations, stages = 0, []
    while True:
        rows = (candidate[:, None] * d + np.arange(d)).reshape(-1)
        if candidate.size:
            sub_W, sub_q, sub_mu = _entries(W, rows, rows), q[rows], mu[candidate]
            if check_psd:
                check_positive_semidefinite(sub_W, "W (its block of the candidate contacts)")
            sub = LocalProblem(sub_W, sub_q, sub_mu, d)

            def measure(r_sub, u_sub, sub=sub):
                return natural_map_residual(sub, r_sub, u_sub, per_contact=per_contact)

            r_sub, k, more = _rounds(
                sub_W,
                sub_q,
                sub_mu,
                d,
                r[rows],
                tol,
                max_iter - iterations,
                measure,
                proximal=False,
            )
            iterations += k
            stages.append(f"{candidate.size} contacts: " + ", ".join(more))
            r[rows] = r_sub
            if measure(r_sub, sub_W @ r_sub + sub_q)[1] > tol:
                return r, iterations, stages, None
        grown = _with_violators(W, q, d, r, candidate, normal)
        if grown.size == candidate.size:
            return r, iterations, stages, rows
        candidate = grown
        if 2 * candidate.size > nc or iterations >= max_iter:
            return r, iterations, stages, None


def _with_violators(W, q, d, r, candidate, normal) -> np.ndarray:
    """``candidate`` with the open contacts outside it that ``r`` (zero outside it) makes
    penetrate: the most violated first, at most as many as it holds and at least
    :data:`ACTIVE_SET_GROWTH`."""
    nc = normal.size
    rows = (candidate[:, None] * d + np.arange(d)).reshape(-1)
    outside = np.setdiff1d(np.arange(nc), candidate, assume_unique=True)
    gaps = _entries(W, normal[outside], rows) @ r[rows] + q[normal[outside]]
    violated = np.flatnonzero(gaps < 0.0)
    if violated.size > max(ACTIVE_SET_GROWTH, candidate.size):
        closing = -gaps[violated] / W.diagonal()[normal[outside[violated]]]
        keep = max(ACTIVE_SET_GROWTH, candidate.size)
        violated = violated[np.argpartition(-closing, keep)[:keep]]
    return np.union1d(candidate, outside[violated]) if violated.size else candidate


@dataclass(frozen=True)
class CandidateSolution:
    """What :func:`solve_on_candidates` found: reactions, iterations, an account of them."""

    forces: np.ndarray
    iterations: int
    message: str


def solve_on_candidates(
    W: Operator,
    q,
    mu,
    dim: int,
    *,
    r0=None,
    tol: float = 1e-8,
    max_iter: int = MAX_ITER,
    per_contact: bool = False,
    look_ahead: bool = False,
) -> CandidateSolution | None:
    """The FCLIB problem ``(W, q, mu)`` without cohesion, by the candidate-set path of
    :func:`solve_coulomb` on an operator too large to form (only the candidates' blocks and
    the open contacts' normal rows are read).

    Returns None when the candidate set gives up (a subproblem not converged, or the set grew
    past half of the contacts): the caller then solves the whole problem (:func:`solve_coulomb`).
    Otherwise the natural-map error of the last candidate set, at most ``tol``, bounds the
    whole problem's (every contact outside is open with a nonnegative gap); ``W`` is taken as
    positive semidefinite (not checked), e.g. a Schur complement of a validated ``H R H^T``.
    ``look_ahead``: the open contacts that ``r0`` closes join the first candidate set (for a
    warm start from a nearby problem's answer: one candidate solve instead of two, usually;
    the answer then differs from the default's within ``tol``).
    """
    q = np.asarray(q, dtype=float).reshape(-1)
    mu = np.asarray(mu, dtype=float).reshape(-1)
    r = np.zeros(q.shape[0]) if r0 is None else warm_start(r0, q.shape[0])
    r, iterations, stages, index = _active_set(
        W, q, mu, dim, r, tol, max_iter, per_contact, look_ahead=look_ahead
    )
    if index is None:
        return None
    return CandidateSolution(
        r, iterations, "converged on a candidate set (no open contact closes): " + ", ".join(stages)
    )


def _check_options(problem, r0, tol, max_iter):
    if not isinstance(problem, LocalProblem):
        raise InvalidInputError(f"problem must be a LocalProblem, got {type(problem).__name__}")
    if not (type(tol) is float and 0.0 < tol < math.inf):  # the common case without numbers' ABCs
        positive_tolerance(tol)
    if not (type(max_iter) is int and max_iter >= 1):
        iteration_cap(max_iter)
    m = problem.q.shape[0]
    if r0 is None:
        return np.zeros(m)
    return np.array(warm_start(r0, m))  # a copy: the solvers write in it


def _working_W(problem: LocalProblem, check_psd: bool):
    """``W`` as the Newton steps read it (dense where
    :func:`~contactqp.core.local_problem.better_dense` prefers), checked semidefinite once
    per problem and its ``with_q`` twins when ``check_psd``."""
    W = problem.W  # a float ndarray or CSR, as validated
    if is_sparse(W) and better_dense(W):
        W = W.toarray()  # once, for the PSD check, the Newton steps and Gauss-Seidel
    if check_psd:
        problem.check_semidefinite()
    return W


def _apex_form(problem: LocalProblem, W, per_contact: bool):
    """``(shift, q, measure)``: the problem seen from its cones' apexes (``r~ = r + shift``
    solves ``(W, q, mu)`` without cohesion) and the convergence test of ``r~``, the
    natural-map residual and relative error of ``r~ - shift`` on the problem as given."""
    shift = problem.apex_shift
    q = problem.q - W @ shift if np.any(shift) else problem.q

    def measure(r_apex, u):
        return natural_map_residual(problem, r_apex - shift, u, per_contact=per_contact)

    return shift, q, measure


def solve_proximal(
    problem: LocalProblem,
    *,
    r0=None,
    tol: float = 1e-8,
    max_iter: int = PROXIMAL_MAX_ITER,
    check_psd: bool = True,
    per_contact: bool = False,
):
    """Solve a local Coulomb problem by proximal-point iterations alone
    (:func:`~contactqp.methods.proximal.proximal_point` around this module's Newton runs).

    The last stage of :func:`solve_coulomb`, for problems whose ``W`` is very singular (rigid
    multibody problems: far more contact unknowns than body freedoms, large friction). The
    parameters, result and exceptions are those of :func:`solve_coulomb`; ``max_iter`` is the
    budget of inner Newton iterations.
    """
    start = time.perf_counter()
    r = _check_options(problem, r0, tol, max_iter)
    W = _working_W(problem, check_psd)
    shift, q, measure = _apex_form(problem, W, per_contact)
    r, _, iterations, reason = proximal_point(
        W,
        q,
        problem.mu,
        problem.dim,
        r + shift,
        tol,
        max_iter,
        measure,
        _Newton,
        low_rank=low_rank_factor(W),
    )
    return finish(
        problem,
        r - shift,
        tol,
        iterations,
        start,
        f"proximal {iterations} it. ({reason})",
        method="proximal",
        per_contact=per_contact,
    )


def solve_coulomb(
    problem: LocalProblem,
    *,
    r0=None,
    tol: float = 1e-8,
    max_iter: int = MAX_ITER,
    check_psd: bool = True,
    per_contact: bool = False,
):
    """Solve a local Coulomb (Mohr-Coulomb) problem to natural-map error ``tol``.

    Semismooth Newton on the Alart-Curnier formulation with a non-monotone line search, and
    nonsmooth Gauss-Seidel sweeps when Newton stalls (see the module notes). Works for 2D and
    3D, dense or sparse ``W``, any ``mu >= 0`` and cohesion.

    Parameters
    ----------
    problem : LocalProblem
    r0 : array_like, shape (m,), optional
        Warm start (reactions); zero when not given.
    tol : float
        Target of :func:`~contactqp.core.local_problem.natural_map_error` (relative; it adds
        reactions and velocities, so give a problem whose ``W`` is O(1), e.g.
        :attr:`~contactqp.core.problem.FrictionStep.fclib`, not one in newtons and metres).
    max_iter : int
        Total budget of Newton iterations and Gauss-Seidel sweeps over all stages (the
        reported ``iterations`` never exceed it). A round is a Newton run then a
        Levenberg-Marquardt run, each of at most 100 iterations; at most 3 rounds, the later
        two each after up to 100 Gauss-Seidel sweeps; then, if all failed, up to 1000 inner
        Newton iterations of proximal-point iterations. The default, 1800, is what every
        stage can spend.
    check_psd : bool
        Check that ``W`` is positive semidefinite (one factorisation). A dense problem of at
        least :data:`ACTIVE_SET_MIN` contacts solved on candidate sets has the blocks of ``W``
        it is solved on checked, all of ``W`` only when it is solved on the whole (the check
        of all of ``W`` cost three times the solve at 2,304 contacts). Callers whose ``W`` is
        ``H R H^T`` of a validated model may skip it.
    per_contact : bool
        Converge to ``tol`` on every contact's own scale too
        (``natural_map_error(..., per_contact=True)``): one contact with a wide gap then does
        not loosen the test for the others. The FCLIB measure is the default.

    Returns
    -------
    LocalResult
        ``success`` is True exactly when the independently computed natural-map error is at
        most ``tol``; otherwise the forces are the best point found and ``message`` says where
        each stage stopped and the error it reached. ``iterations`` counts Newton iterations
        plus Gauss-Seidel sweeps.
        ``contact_status`` gives open / stick / slip per contact.

    Raises
    ------
    InvalidInputError
        On a bad ``tol``, ``max_iter`` or ``r0``.
    NotPositiveDefiniteError
        If ``W`` is not positive semidefinite
        (:func:`~contactqp.core.local_problem.check_positive_semidefinite`).
    """
    start = time.perf_counter()
    r = _check_options(problem, r0, tol, max_iter)
    small_W = problem.small_W
    if small_W is not None:
        if check_psd:
            problem.check_semidefinite()  # once per problem and its with_q twins
        return _solve_small(problem, small_W, r, tol, max_iter, per_contact, start)
    W, d, mu = _working_W(problem, False), problem.dim, problem.mu
    on_candidates = isinstance(W, np.ndarray) and problem.n_contacts >= ACTIVE_SET_MIN
    if check_psd and not on_candidates:
        problem.check_semidefinite()
    shift, q, measure = _apex_form(problem, W, per_contact)
    r = r + shift
    loaded = None  # the components outside which the answer is zero, when known
    if on_candidates:  # each candidate set's block of W checked, all of W only if solved on
        r, iterations, stages, index = _active_set(
            W, q, mu, d, r, tol, max_iter, per_contact, check_psd=check_psd
        )
        if index is not None:  # r is zero outside index, the apex shifts' normals aside
            shifted = np.flatnonzero(shift)
            loaded = np.union1d(index, shifted) if shifted.size else index
        else:  # the reduction gave up: the whole problem from where it stopped
            if check_psd:
                problem.check_semidefinite()
            r, k, more = _rounds(W, q, mu, d, r, tol, max_iter - iterations, measure)
            iterations += k
            stages += ["whole problem:"] + more
    else:
        r, iterations, stages = _rounds(W, q, mu, d, r, tol, max_iter, measure)
    reactions = r - shift
    # W r and |W| |r| for the certificate, read over the loaded columns only (the other terms
    # are zero)
    products = None if loaded is None else column_products(W, reactions[loaded], loaded)
    return finish(
        problem,
        reactions,
        tol,
        iterations,
        start,
        ", ".join(stages),
        method="coulomb",
        per_contact=per_contact,
        products=products,
    )


def _solve_small(
    problem: LocalProblem,
    W: np.ndarray,
    r: np.ndarray,
    tol: float,
    max_iter: int,
    per_contact: bool,
    start: float,
):
    """:func:`solve_coulomb` of a small problem from ``r`` (``W``: :attr:`LocalProblem.small_W`):
    its first Newton run and the certificate of its answer in one compiled call
    (:func:`~contactqp.kernels.compiled.small_solve`, the iterations of ``_Newton.run``); the
    later stages, where that run does not converge, as on any problem."""
    m, nc = r.shape[0], problem.n_contacts
    u = np.empty(m)
    status = np.empty(nc, dtype=np.intp)
    assert kernels.small_solve is not None  # small_W exists only with the kernels
    k, code, run_error, error, product, size_q, scale = kernels.small_solve(
        W,
        problem.q,  # C-contiguous, as validated
        problem.mu,
        problem.law.cohesion,
        r,
        tol,
        min(RUN_ITERATIONS, max_iter),
        per_contact,
        CONTACT_FLOOR,
        STATUS_RTOL,
        u,
        status,
    )
    reason = kernels.SMALL_REASONS[code]
    if reason == "converged":
        limits = limits_from_norms(product, size_q, scale, problem.digits)
        detail = f"newton {k} it. (converged)"
        return certified_result(
            problem, r, u, error, limits, status, tol, k, start, detail, "coulomb", per_contact
        )
    # the Levenberg-Marquardt run and the later rounds, from where this one stopped
    shift, q_apex, measure = _apex_form(problem, W, per_contact)
    first = (r + shift, run_error, k, reason)
    r_apex, iterations, stages = _rounds(
        W, q_apex, problem.mu, problem.dim, r + shift, tol, max_iter, measure, first=first
    )
    return finish(
        problem,
        r_apex - shift,
        tol,
        iterations,
        start,
        ", ".join(stages),
        method="coulomb",
        per_contact=per_contact,
    )

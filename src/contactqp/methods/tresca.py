r"""Coulomb friction on a local problem as a fixed point of Tresca problems solved by Clarabel.

With the friction bound of each contact frozen at ``s_i`` the law becomes Tresca's, and for a
symmetric ``W`` the local problem is the convex second-order cone program

.. math::

    \min_r \tfrac12 r^T W r + q^T r \quad \text{s.t.} \quad
    r_{N,i} \ge 0, \quad \|r_{T,i}\| \le s_i ,

whose optimality conditions are exactly those of the Coulomb problem at ``s_i = mu_i r_N,i``
(``u_N >= 0`` complementary to ``r_N``, sliding opposite to ``r_T`` on the bound, sticking
inside). Updating ``s = mu r_N`` and solving again is the Tresca fixed point; it converges for
small ``mu`` (where the Coulomb solution is unique) and is a classical reference route
[1]_, [2]_; the cone programs are solved by Clarabel [3]_.
A slightly unsymmetric ``W`` (e.g. FCLIB files written with few digits) is split into its
symmetric part, kept in the cone program, and its skew part, moved to the right-hand side with
the previous reactions, so that a fixed point solves the problem with the given ``W``. Cohesion
(:class:`~contactqp.core.local_problem.LocalProblem`) is handled by measuring reactions from the
cone apex.

An interior-point solution is accurate to about 1e-9 relative, which leaves a 3-D fixed point
stalling near a natural-map error of 1e-8; each cone program's answer is therefore polished by
a few semismooth Newton steps on the Tresca natural map (the active set is right by then), which
reach rounding.

References
----------
.. [1] P. D. Panagiotopoulos, "A nonlinear programming approach to the unilateral contact-, and
   friction-boundary value problem in the theory of elasticity", Ing. Arch. 44, 421-432, 1975.
.. [2] V. Acary, M. Brémond, O. Huber, "On solving contact problems with Coulomb friction:
   formulations and numerical comparisons", INRIA RR-9118, 2018 (the TFP family).
.. [3] P. J. Goulart, Y. Chen, "Clarabel: an interior-point solver for conic programs with
   quadratic objectives", arXiv:2405.12762, 2024.
"""

from __future__ import annotations

import time
import warnings
from typing import TYPE_CHECKING, TypeAlias

import numpy as np

from ..core.local_problem import LocalProblem, natural_map_error
from ..core.model import iteration_cap, positive_tolerance, warm_start
from ..core.operators import as_operator
from ..core.result import LocalResult
from ..errors import InvalidInputError, SolverError
from ..optional import require
from .local_global import local_result

if TYPE_CHECKING:
    import scipy.sparse as sp

__all__ = ["solve_tresca_fixed_point"]

#: Clarabel tolerances on the scaled cone program (O(1) data); the Newton polish does the rest.
_CLARABEL_TOL = 1e-9
#: A bound below this fraction of the largest one is treated as zero (tangential force fixed at 0).
_ZERO_BOUND_RTOL = 1e-12
#: The fixed point stops as stalled after this many iterations without halving its best error.
_PATIENCE = 4


def check_fixed_point_arguments(problem, tol, max_iter, r0):
    """Validate the arguments common to the fixed-point routes; return ``r0`` (array or None)."""
    if not isinstance(problem, LocalProblem):
        raise InvalidInputError(f"problem must be a LocalProblem, got {type(problem).__name__}")
    positive_tolerance(tol, below_one=True)
    iteration_cap(max_iter)
    if r0 is None:
        return None
    return warm_start(r0, problem.dim * problem.n_contacts)


_Matrix: TypeAlias = "np.ndarray | sp.csr_matrix | sp.csr_array"


def _split_skew(W: _Matrix) -> tuple[_Matrix, _Matrix | None]:
    """``(W - S, S)``, ``S = (W - W^T) / 2`` stored as ``W`` is; ``(W, None)`` when ``S = 0``."""
    if isinstance(W, np.ndarray):
        skew = 0.5 * (W - W.T)
        return (W, None) if np.count_nonzero(skew) == 0 else (W - skew, skew)
    # CSR already (W.T is CSC, a difference takes W's format): tocsr() is a no-op for the stubs
    sparse_skew = (0.5 * (W - W.T)).tocsr()
    if sparse_skew.count_nonzero() == 0:
        return W, None
    return (W - sparse_skew).tocsr(), sparse_skew


class FixedPointData:
    """What the fixed-point routes need from a problem, computed once.

    Reactions are measured from the cone apex, ``r' = r + apex_shift`` (so that a Mohr-Coulomb
    problem with cohesion becomes a Coulomb one, ``u = W r' + q'``), and ``W`` is split into its
    symmetric part (for the sub-problems) and its skew part (iterated on, None if zero).

    Attributes
    ----------
    W_sym : ndarray or csr_matrix, shape (m, m)
    skew : ndarray or csr_matrix or None, shape (m, m)
    q : ndarray, shape (m,)
        ``q - W apex_shift``.
    shift : ndarray, shape (m,)
        :attr:`~contactqp.core.local_problem.LocalProblem.apex_shift`.
    w, f : float
        Compliance scale (largest diagonal of ``W``) and initial force scale: the sub-problems
        solve for ``r' / f`` with ``W / w`` and ``q / (f w)``, data on which the backends'
        absolute tolerances mean the same thing on every problem. ``f`` is ``max|q'| / w``;
        :func:`run_fixed_point` starts from it and, for its own run only, replaces it by the
        largest reaction of its first iterate when that is below 1 % of it: a contact far
        from its obstacle (large ``q_i``, no force) would otherwise leave the others' forces a
        small fraction of ``f``, resolved only to the backend's tolerance times ``f``.
        (Scaling up as well, when the reactions exceed ``f``, made the fixed point stall
        earlier on rigid multibody FCLIB files.) Nothing here changes after construction, so
        one instance may serve several runs.
    dim, n_contacts : int
    """

    def __init__(self, problem: LocalProblem):
        W = as_operator(problem.W).matrix  # the cone programs are built on the stored entries
        self.W_sym, self.skew = _split_skew(W)
        self.shift = problem.apex_shift
        self.q = problem.q - np.asarray(W @ self.shift).ravel()
        diagonal = np.abs(self.W_sym.diagonal())
        self.w = float(diagonal.max()) if diagonal.size and diagonal.max() > 0 else 1.0
        self.f = float(np.max(np.abs(self.q), initial=0.0)) / self.w or 1.0
        self.dim, self.n_contacts = problem.dim, problem.n_contacts


def run_fixed_point(
    problem, data, tresca, *, tol, max_iter, r0, exact, method: str, per_contact=False
):
    """Iterate ``s = mu r'_N`` over a Tresca sub-solver; the loop shared by the fixed-point routes.

    Parameters
    ----------
    problem : LocalProblem
    data : FixedPointData
    tresca : callable
        ``tresca(q, s, f) -> r'``: reactions from the apex (shape (m,)) of the Tresca problem
        with ``data.W_sym``, right-hand side ``q`` (shape (m,)) and friction bounds ``s``
        (shape (nc,)), solved on the force scale ``f`` (see :class:`FixedPointData`).
    tol : float
    max_iter : int
        Largest number of sub-problems solved (the first one solved again on the reactions' own
        scale counts too); the reported ``iterations``.
    r0 : ndarray or None
        Starting reactions; None starts from the frictionless bounds ``s = 0``.
    exact : bool
        True when the sub-problem's cone is the Coulomb disc: convergence is then a natural-map
        error at most ``tol``. False (polygonal cones) when it is the fixed point itself: the
        relative change of ``r'`` between two iterations at most ``tol`` (or the exact-cone
        error, when no polygon constraint binds; with a singular ``W`` the reactions need not
        settle while the velocities do).
    method : str
        The route's name, recorded in the result.
    per_contact : bool
        Measure the natural map on each contact's own scale too
        (:func:`~contactqp.core.local_problem.natural_map_error`).

    Returns
    -------
    LocalResult
        The best iterate by natural-map error when ``exact``, the last one otherwise; the
        certificate's ``natural_map`` is always the error against the exact cones, and
        ``success`` the route's convergence.
    """
    start_time = time.perf_counter()
    d = problem.dim
    r = np.zeros(problem.q.shape[0]) if r0 is None else r0 + data.shift
    best = (np.inf, r)
    message, converged, stalled = "", False, 0
    reference = np.inf  # the error at the last halving
    solved = 0  # sub-problems solved: at most max_iter
    scale = data.f  # this run's force scale (data is not changed)
    while solved < max_iter:
        s = problem.mu * np.maximum(r[::d], 0.0)
        q = data.q if data.skew is None else data.q + np.asarray(data.skew @ r).ravel()
        previous, r = r, tresca(q, s, scale)
        solved += 1
        if solved == 1 and solved < max_iter:
            rescaled = _rescaled(scale, r)
            if rescaled != scale:
                scale = rescaled
                r = tresca(q, s, scale)  # the first sub-problem again, on the reactions' scale
                solved += 1
        error = natural_map_error(problem, r - data.shift, per_contact=per_contact)
        if exact:
            # stalled: no halving of the error since `reference` for _PATIENCE iterations (a
            # fixed point contracting at a rate in (0.5, 1) halves it every few iterations)
            if error < 0.5 * reference:
                reference, stalled = error, 0
            else:
                stalled += 1
            if error < best[0]:
                best = (error, r)
            if error <= tol:
                converged, message = True, f"natural-map error {error:.2e} <= tol"
                break
            if stalled >= _PATIENCE:
                message = f"stalled at natural-map error {best[0]:.2e}"
                break
        else:
            best = (error, r)
            change = np.linalg.norm(r - previous) / max(np.linalg.norm(r), np.finfo(float).tiny)
            if change <= tol or error <= tol:
                converged = True
                message = (
                    f"fixed point reached (relative change {change:.1e}); natural-map "
                    f"error against the exact cones {error:.2e}"
                )
                break
    if not message:
        message = f"max_iter = {max_iter} reached, natural-map error {best[0]:.2e}"
    error, r = best
    r = r - data.shift
    u = np.asarray(problem.W @ r).ravel() + problem.q
    return local_result(
        problem,
        r,
        u,
        converged=converged,
        error=error,
        tol=tol,
        iterations=solved,
        seconds=time.perf_counter() - start_time,
        message=message,
        method=method,
    )


def _rescaled(scale: float, r) -> float:
    """The largest reaction of ``r`` if that is below 1 % of the force scale ``scale``, else
    ``scale``."""
    force = float(np.max(np.abs(r), initial=0.0))
    return force if 0.0 < force < 0.01 * scale else scale


def free_unknowns(s, d):
    """The unknowns left free by the bounds ``s`` (shape (nc,)): tangential ones need ``s > 0``.

    Returns
    -------
    keep : ndarray of int
        Indices of the free unknowns in ``r`` (normal ones always, tangential ones of sliding
        contacts).
    sliding : ndarray of bool, shape (nc,)
        Contacts whose bound is positive (above ``1e-12`` times the largest).
    normal : ndarray of int, shape (nc,)
        Position of each normal unknown in ``r[keep]``.
    tangent : ndarray of int, shape (sliding.sum(), d - 1)
        Position of the tangential unknowns of the sliding contacts in ``r[keep]``.
    """
    nc = s.size
    sliding = s > _ZERO_BOUND_RTOL * max(float(s.max(initial=0.0)), np.finfo(float).tiny)
    free = np.zeros((nc, d), dtype=bool)
    free[:, 0] = True
    free[sliding, 1:] = True
    keep = np.flatnonzero(free.ravel())
    position = np.full(nc * d, -1)
    position[keep] = np.arange(keep.size)
    return keep, sliding, position[::d], position.reshape(nc, d)[sliding, 1:]


def _project(z, s, d):
    """Projection on ``{x_N >= 0, ||x_T|| <= s}`` per contact and its (generalised) Jacobian."""
    import scipy.sparse as sp

    Z = z.reshape(-1, d)
    nc = Z.shape[0]
    norm = np.linalg.norm(Z[:, 1:], axis=1)
    outside = norm > s
    factor = np.where(outside, s / np.where(outside, norm, 1.0), 1.0)
    projected = Z.copy()
    projected[:, 0] = np.maximum(Z[:, 0], 0.0)
    projected[:, 1:] *= factor[:, None]
    blocks = np.zeros((nc, d, d))
    blocks[:, 0, 0] = Z[:, 0] > 0.0
    direction = Z[:, 1:] / np.where(norm > 0.0, norm, 1.0)[:, None]
    radial = direction[:, :, None] * direction[:, None, :]
    blocks[:, 1:, 1:] = factor[:, None, None] * (np.eye(d - 1) - outside[:, None, None] * radial)
    return projected.ravel(), sp.block_diag(blocks, format="csr")


def polish(W, c, s, x, d, steps: int = 6):
    """Semismooth Newton steps on the Tresca natural map ``x - P_C(x - (W x + c))``.

    Interior-point solutions are accurate to about 1e-9 relative; from there the active set is
    identified and two or three Newton steps reach rounding. The best point is kept.

    Parameters
    ----------
    W : ndarray or sparse matrix, shape (m, m)
        Symmetric part of the (scaled) Delassus operator.
    c : ndarray, shape (m,)
    s : ndarray, shape (nc,)
        Friction bounds (disc radii; in 2-D the segment ``|x_T| <= s``).
    x : ndarray, shape (m,)
        Start, e.g. an interior-point solution.
    d : int
        2 or 3.
    """
    import scipy.sparse as sp
    from scipy.sparse.linalg import MatrixRankWarning, spsolve

    m = x.size
    dense = not sp.issparse(W)

    def residual(x):
        projected, jacobian = _project(x - (W @ x + c), s, d)
        return x - projected, jacobian

    F, D = residual(x)
    best = np.linalg.norm(F)
    for _ in range(steps):
        if best == 0.0:
            break
        if dense:
            J = np.eye(m) - D @ (np.eye(m) - W)
        else:
            J = sp.identity(m, format="csc") - sp.csc_matrix(D @ (sp.identity(m) - W))
        try:
            with warnings.catch_warnings():  # singular J (rigid bodies): a NaN step, below
                warnings.simplefilter("ignore", MatrixRankWarning)
                step = np.linalg.solve(J, -F) if dense else spsolve(J, -F)
        except np.linalg.LinAlgError:
            break
        if not np.all(np.isfinite(step)):
            break
        candidate = x + step
        F_new, D_new = residual(candidate)
        if not np.linalg.norm(F_new) < best:
            break
        x, F, D, best = candidate, F_new, D_new, np.linalg.norm(F_new)
    return x


class _ClarabelTresca:
    """The Tresca cone program with Clarabel, on the contacts' free unknowns (scaled).

    Tangential unknowns of contacts whose bound is zero are removed (they are zero), so that
    every second-order cone left has an interior.
    """

    def __init__(self, data: FixedPointData):
        import scipy.sparse as sp

        self._clarabel = require("clarabel", "the Tresca fixed point", "qp")
        self.w = data.w
        self.W = data.W_sym / self.w  # scaled, full (for the polish)
        self.P = sp.triu(sp.csc_matrix(self.W), format="csc")
        self.d, self.nc = data.dim, data.n_contacts
        settings = self._clarabel.DefaultSettings()
        settings.verbose = False
        settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = _CLARABEL_TOL
        settings.tol_ktratio = 1e-9
        settings.max_iter = 200
        self.settings = settings

    def __call__(self, q, s, f):
        import scipy.sparse as sp

        clarabel = self._clarabel
        d, nc = self.d, self.nc
        m = d * nc
        keep, sliding, normal, tangent = free_unknowns(s, d)
        n_slide = tangent.shape[0]
        # rows: -x_N <= 0 (nonnegative cone), then per sliding contact (s_i, x_T) in the SOC
        rows = np.concatenate(
            [np.arange(nc), nc + (d * np.arange(n_slide)[:, None] + np.arange(1, d)).ravel()]
        )
        cols = np.concatenate([normal, tangent.ravel()])
        A = sp.csc_matrix((-np.ones(rows.size), (rows, cols)), shape=(nc + d * n_slide, keep.size))
        b = np.zeros(nc + d * n_slide)
        b[nc::d] = s[sliding] / f
        clarabel = self._clarabel
        cones = [clarabel.NonnegativeConeT(nc)] + [clarabel.SecondOrderConeT(d)] * n_slide
        P = self.P[keep][:, keep]
        solver = clarabel.DefaultSolver(P, q[keep] / (f * self.w), A, b, cones, self.settings)
        try:
            solution = solver.solve()
        except Exception as exc:
            raise SolverError(
                f"Clarabel failed on the Tresca cone program: {type(exc).__name__}: {exc}"
            ) from exc
        x = np.zeros(m)
        x[keep] = np.asarray(solution.x)
        if not np.all(np.isfinite(x)):
            raise SolverError(
                f"Clarabel found no solution of the Tresca cone program (status {solution.status})"
            )
        return f * polish(self.W, q / (f * self.w), s / f, x, d)


def solve_tresca_fixed_point(
    problem: LocalProblem,
    *,
    r0=None,
    tol: float = 1e-8,
    max_iter: int = 50,
    per_contact: bool = False,
) -> LocalResult:
    """Solve a local Coulomb problem by a fixed point on Tresca cone programs (Clarabel).

    Each iteration solves the Tresca problem with the bounds ``s_i = mu_i r_N,i`` of the
    previous reactions as a second-order cone program with Clarabel (``NonnegativeConeT`` for
    the normal reactions, one ``SecondOrderConeT`` per contact with a positive bound), the data
    scaled: reactions in units of ``max|q| / max diag W``, or of the first iterate's largest
    reaction when that is below 1 % of it (:class:`FixedPointData`).

    Parameters
    ----------
    problem : LocalProblem
        2-D or 3-D; ``W`` symmetric positive semidefinite, or nearly so (its skew part is
        treated by the outer iteration, see the module notes).
    tol : float
        Target natural-map error
        (:func:`~contactqp.core.local_problem.natural_map_error`), in (0, 1).
    max_iter : int
        Largest number of cone programs solved.
    r0 : array_like, shape (m,), optional
        Starting reactions (N): the first bounds are ``mu r0_N``. By default the first
        sub-problem is frictionless (``s = 0``).
    per_contact : bool
        Converge on every contact's own scale too
        (``natural_map_error(..., per_contact=True)``); the FCLIB measure is the default.

    Returns
    -------
    LocalResult
        The iterate of least natural-map error; ``success`` when it is at most ``tol``. The
        loop also stops when the error has not halved in 4 iterations: the fixed point does not
        contract (large ``mu``, or a singular ``W`` as in rigid multibody problems).

    Raises
    ------
    InvalidInputError
        ``problem`` is not a LocalProblem, ``tol`` not in (0, 1), ``max_iter`` not a positive
        integer or ``r0`` of the wrong shape.
    SolverError
        Clarabel raises, or returns a non-finite point, on one of the cone programs.
    MissingDependencyError
        Clarabel is not installed.
    """
    start = check_fixed_point_arguments(problem, tol, max_iter, r0)
    data = FixedPointData(problem)
    return run_fixed_point(
        problem,
        data,
        _ClarabelTresca(data),
        tol=tol,
        max_iter=max_iter,
        r0=start,
        exact=True,
        per_contact=per_contact,
        method="tresca",
    )

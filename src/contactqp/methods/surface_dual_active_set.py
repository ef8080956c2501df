"""A dual active-set method for surface problems whose ``W`` is reached by products only.

The forces ``r >= 0`` of a :class:`~contactqp.core.surface.SurfaceProblem` minimise
``1/2 r^T W r + r^T (s - delta 1)`` (and carry ``sum r = P`` at a fixed load). The primal-dual
active set strategy [HIK2002]_ guesses the contact set ``C``, solves the equality problem on it,

.. math::

    W_{CC}\\, r_C = \\delta\\,\\mathbf{1} - s_C, \\qquad r_{\\bar C} = 0
    \\qquad \\big(\\text{and } \\mathbf{1}^T r_C = P \\text{ at a fixed load}\\big),

(``delta`` unknown at a fixed load) and moves to ``{i in C: r_i > 0} U {i not in C: g_i < 0}``
until the set repeats. Each equality problem is solved by conjugate gradients on ``W_CC``
(projected onto ``sum r_C = P`` at a fixed load, the approach being the multiplier of that
constraint), warm started from the last forces, so every step costs only products ``W x`` (one
pair of triangular solves for
:class:`~contactqp.compliance.sparse_compliance.SparseComplianceOperator`): no block of ``W`` is
formed or factored, unlike ``surface-active-set``, and the iterates are those of a dense
primal-dual active set up to the CG tolerance. The first set is the rigid interference
``{s_i < delta}`` (at a fixed load, at the mean gap of the load spread evenly), or the warm
start's support.

A set met twice (the strategy may cycle on a ``W`` that is not an M-matrix) stops the method
with ``converged = False`` and says so; the answer is certified like every other.

References
----------
.. [HIK2002] M. Hintermüller, K. Ito, K. Kunisch, "The primal-dual active set strategy as a
   semismooth Newton method", SIAM J. Optim. 13(3), 2002.
"""

from __future__ import annotations

import time

import numpy as np

from ..core.model import iteration_cap, positive_tolerance, warm_start
from ..core.surface import SurfaceProblem, SurfaceResult

__all__ = ["solve_dual_active_set", "MAX_CG"]

#: Default budget of conjugate-gradient iterations of each equality problem.
MAX_CG = 2000


def _length(problem: SurfaceProblem, u: np.ndarray, approach: float) -> float:
    """The certificate's length scale (see :func:`~contactqp.core.surface.certify_surface`)."""
    return max(
        float(np.max(np.abs(u))),
        abs(approach - float(np.min(problem.separation))),
        np.finfo(float).tiny,
    )


def _equality_cg(problem, contact, r, approach, tol, max_cg):
    """Conjugate gradients on ``W_CC r_C = delta - s_C`` (projected on ``sum r_C = P`` at a
    fixed load), from ``r``; returns ``(r, W r, approach, iterations, converged)``."""
    W, s = problem.compliance, problem.separation
    fixed_load = problem.load is not None
    r = np.where(contact, r, 0.0)
    if fixed_load:
        total = float(np.sum(r))
        r = r + (problem.load - total) / np.count_nonzero(contact) * contact
    u = W @ r
    direction = np.zeros_like(r)
    previous = 1.0
    for iteration in range(max_cg + 1):
        g = s + u
        if fixed_load:
            approach = float(np.mean(g[contact]))
        gc = np.where(contact, g - approach, 0.0)
        length = _length(problem, u, approach)
        if float(np.max(np.abs(gc))) <= tol * length:
            return r, u, approach, iteration, True
        if iteration == max_cg:
            break
        G = float(gc @ gc)
        direction = gc + (G / previous) * direction if iteration else gc
        previous = G
        q = W @ direction  # direction sums to 0 on the contact at a fixed load: P is kept
        curvature = float(direction @ q)
        if not curvature > 0.0:
            break
        step = G / curvature
        r = r - step * direction
        if iteration % 50 == 49:  # the recurrence drifts: refresh the displacements
            u = W @ r
        else:
            u = u - step * q
    return r, u, approach, max_cg, False


def solve_dual_active_set(
    problem: SurfaceProblem,
    *,
    r0=None,
    tol: float = 1e-10,
    max_iter: int = 100,
    max_cg: int = MAX_CG,
) -> SurfaceResult:
    """Solve a :class:`~contactqp.core.surface.SurfaceProblem` by a primal-dual active set with
    conjugate-gradient equality solves (products of ``W`` only).

    Parameters
    ----------
    problem : SurfaceProblem
    r0 : array_like, shape (m,), optional
        Warm start: forces of a nearby problem (N); their support is the first contact set.
    tol : float
        Largest gap on the contact (each equality solve's stopping test) and penetration off
        it, relative to the certificate's length scale.
    max_iter : int
        Largest number of active-set changes.
    max_cg : int
        Largest number of conjugate-gradient iterations of each equality problem.

    Returns
    -------
    SurfaceResult
        ``iterations`` counts the active sets; ``info["cg"]`` the conjugate-gradient
        iterations of all of them (each one product ``W x``, plus one per set).

    Raises
    ------
    InvalidInputError
        ``tol`` not a finite number > 0, ``max_iter`` or ``max_cg`` not an integer >= 1, or
        ``r0`` not a finite array of shape (m,).
    """
    tol = positive_tolerance(tol)
    max_iter = iteration_cap(max_iter)
    max_cg = iteration_cap(max_cg, "max_cg")
    start = time.perf_counter()
    W, s = problem.compliance, problem.separation
    fixed_load = problem.load is not None
    r = np.zeros(problem.size)
    if problem.approach is not None:
        approach = problem.approach
    else:  # the load spread evenly: its mean gap is the approach of a first flat guess
        assert problem.load is not None
        approach = float(np.mean(s + W @ np.full(problem.size, problem.load / problem.size)))
    contact = s < approach
    if r0 is not None:
        guess = np.maximum(warm_start(r0, problem.size), 0.0)
        if np.any(guess > 0):
            r, contact = guess, guess > 0
    if not np.any(contact):
        if not fixed_load:  # the indenter does not reach the surface
            return problem.make_result(
                np.zeros(problem.size),
                approach,
                method="dual-active-set",
                converged=True,
                message="no point touches the indenter",
                iterations=0,
                seconds=time.perf_counter() - start,
                info={"cg": 0},
            )
        contact = s <= np.min(s)
    seen: set[bytes] = set()
    cg_total, converged, iterations = 0, False, 0
    message = f"reached max_iter = {max_iter} active sets"
    u = W @ r
    while iterations < max_iter:
        iterations += 1
        key = np.packbits(contact).tobytes()
        if key in seen:
            message = f"the active set cycled after {iterations - 1} sets"
            break
        seen.add(key)
        r, u, approach, count, solved = _equality_cg(problem, contact, r, approach, tol, max_cg)
        cg_total += count
        if not solved:
            message = f"the equality solve of set {iterations} did not converge in {max_cg} steps"
            break
        g = s - approach + u
        length = _length(problem, u, approach)
        new = (contact & (r > 0.0)) | (~contact & (g < -tol * length))
        if np.array_equal(new, contact):
            converged = True
            message = f"converged: {iterations} active sets, {cg_total} CG iterations"
            break
        contact = new
        if not np.any(contact):
            if not fixed_load:
                r = np.zeros_like(r)
                converged, message = True, "no point touches the indenter"
                break
            contact = s <= np.min(s)
    return problem.make_result(
        np.maximum(r, 0.0),
        approach,
        method="dual-active-set",
        converged=converged,
        message=message,
        iterations=iterations,
        seconds=time.perf_counter() - start,
        info={"cg": cg_total},
    )

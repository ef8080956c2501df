"""Polonsky and Keer's constrained conjugate gradient for a surface problem.

The forces ``r >= 0`` minimise the complementary energy

.. math::

    \\Pi(r) = \\tfrac12 r^T W r + r^T (s - \\delta\\,\\mathbf{1}), \\qquad r \\ge 0
    \\quad \\big(\\textstyle\\sum_i r_i = P \\text{ at a fixed load}\\big),

whose gradient is the gap ``g = s - delta + W r``. Polonsky and Keer's method [PK1999]_ runs
conjugate gradients on the points in contact (``r_i > 0``), projects the forces onto
``r >= 0`` after each step, restarts the conjugation whenever points that penetrate
(``r_i = 0``, ``g_i < 0``) join the contact, and, at a fixed load, measures the gaps from their
mean over the contact (that mean is the approach ``delta``, the multiplier of the load) and
rescales the forces to the load after each step. At a fixed approach the same iteration runs
without the mean and the rescaling.

Each iteration costs one product with ``W``, the search direction's, and a few passes over the
vectors; the displacements ``W r`` follow the forces along the step, and are computed afresh
(a second product) only when the projection or the points joining the contact move the forces
off that line, and before the answer is judged. ``W`` is reached through
:class:`~contactqp.core.operators.Operator` products only (an FFT half-space never forms it).
The iteration stops when the gaps vanish on the contact and no free point penetrates, to
``tol`` times the length scale of the certificate (:func:`~contactqp.core.surface.certify_surface`),
which then passes at the same tolerance: that criterion is stricter than the relative change of
the forces of [PK1999]_.

Two aids, used when the operator offers them (an FFT half-space does,
:meth:`~contactqp.core.operators.Operator.coarsening` and
:meth:`~contactqp.core.operators.Operator.preconditioner`), cut the iterations, which otherwise
grow as the square root of the cells across the contact (the condition number of ``W`` on it):

* ``precondition``: the search direction is the gap preconditioned by an approximate inverse of
  ``W`` on the contact (for the half-space the inverse periodic kernel ``E* |q| / 2``, the
  preconditioner of Vollebregt's conjugate gradient [V2014]_), projected onto the forces of
  zero sum at a fixed load: preconditioned conjugate gradients on each contact set.
* ``multilevel``: without a warm start, the problem is first solved on the coarser lattices
  (cells merged 2 x 2, the separation averaged over them; to ``1e-4``), coarsest first, each
  answer, its forces shared evenly among the merged cells, starting the next finer solve
  (a nested iteration). The finest solve then starts with its contact nearly found.

Measured on Hertz's problem (one thread, tol ``1e-8``): from 64 x 64 to 1024 x 1024 cells the
iterations of the finest solve go from 27, 36, 48, 63, 85 without the aids to 9 to 12 with
both, and at 1024 x 1024 the time from 29 s to 2.3 s (``benchmarks/bench_scale.py``). On a
periodic rough surface of 512 x 512 cells at 11 % contact: 131 iterations without the aids, 39
preconditioned, 30 with both.

References
----------
.. [PK1999] I. A. Polonsky, L. M. Keer, "A new numerical method for solving rough contact
   problems based on the multi-level multi-summation and conjugate gradient techniques",
   Wear 231(2), 206-219, 1999.
.. [V2014] E. A. H. Vollebregt, "A new solver for the elastic normal contact problem using
   conjugate gradients, deflation, and an FFT-based preconditioner", Journal of
   Computational Physics 257, 333-351, 2014.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..core.model import iteration_cap, positive_tolerance, true_or_false, warm_start
from ..core.surface import SurfaceProblem, SurfaceResult

__all__ = ["solve_constrained_cg", "MAX_ITER", "COARSE_TOL"]

#: Default budget of iterations.
MAX_ITER = 5000
#: Tolerance of the coarse solves of ``multilevel`` (only a start of the next finer one).
COARSE_TOL = 1e-4
_TINY = np.finfo(float).tiny


def _start(problem: SurfaceProblem, r0) -> tuple[np.ndarray, np.ndarray]:
    """``(r, W r)``: the first forces, inside the constraints, and their displacements."""
    W, s = problem.compliance, problem.separation
    if r0 is not None:
        r = np.maximum(warm_start(r0, problem.size), 0.0)
        if problem.load is not None and np.sum(r) > 0:
            r *= problem.load / np.sum(r)
            return r, W @ r
        if problem.load is None and np.any(r > 0):
            return r, W @ r
    if problem.load is not None:  # the load spread evenly (Polonsky and Keer's start)
        r = np.full(problem.size, problem.load / problem.size)
        return r, W @ r
    # fixed approach: the interference max(delta - s, 0), scaled to the least energy along it
    assert problem.approach is not None
    v = np.maximum(problem.approach - s, 0.0)
    if not np.any(v > 0):
        return v, np.zeros_like(v)  # the indenter does not reach the surface
    Wv = W @ v
    c = float(v @ v) / float(v @ Wv)
    return c * v, c * Wv


@dataclass
class _Run:
    """The end of one constrained CG run."""

    forces: np.ndarray
    approach: float
    converged: bool
    message: str
    iterations: int
    residual: float
    products: int


def _iterate(problem: SurfaceProblem, r0, tol: float, max_iter: int, preconditioner) -> _Run:
    """Constrained (preconditioned) conjugate gradients from ``r0`` (see the module notes)."""
    W, s = problem.compliance, problem.separation
    load, fixed_load = problem.load, problem.load is not None
    with np.errstate(over="ignore", invalid="ignore"):  # the certificate judges non-finite r
        r, u = _start(problem, r0)
        products = 1 if np.any(r) else 0  # the start's (none when nothing touches)
        fresh = True  # u is the product W r (not updated from the previous step's)
        direction = np.zeros_like(r)
        previous, conjugate = 1.0, False
        approach = 0.0 if problem.approach is None else problem.approach
        lowest = float(np.min(s))
        converged, iterations, residual = False, 0, np.inf
        message = f"reached max_iter = {max_iter} iterations"
        while True:
            contact = r > 0.0
            on = contact.astype(float)  # 1 on the contact, 0 off it
            count = float(np.sum(on))
            g = s + u
            if fixed_load:
                approach = float(g @ on) / count
            g -= approach
            length = max(float(np.max(u)), -float(np.min(u)), abs(approach - lowest), _TINY)
            gc = g * on
            residual = max(float(np.max(gc)), -float(np.min(gc)), -float(np.min(g))) / length
            if residual <= tol:
                if not fresh:  # judge the forces by their own product, not the updated one
                    u, fresh = W @ r, True
                    products += 1
                    continue
                converged = True
                message = f"converged in {iterations} iterations (residual {residual:.1e})"
                break
            if not np.isfinite(residual):
                message = f"diverged after {iterations} iterations (non-finite gaps)"
                break
            if iterations >= max_iter:
                break
            iterations += 1
            if preconditioner is None:
                z = gc
            else:  # M g on the contact, of zero sum at a fixed load
                z = preconditioner(gc, contact) * on
                if fixed_load:
                    z -= on * (float(z @ on) / count)
            G = float(gc @ z)
            if conjugate:  # t = z + (G / G_old) t_old on the contact, 0 off it
                direction *= G / previous
                direction += z
                direction *= on
                if not float(gc @ direction) > 0.0:  # lost to rounding: restart
                    direction = z.copy()
            else:
                direction = z.copy()
            previous = G
            q = W @ direction
            products += 1
            curvature = float(q @ direction)  # the direction is 0 off the contact
            if fixed_load:  # q less its mean on the contact
                curvature -= float(q @ on) / count * float(np.sum(direction))
            if not curvature > 0.0:
                message = (
                    f"stopped after {iterations} iterations: no descent along the search "
                    f"direction (curvature {curvature:.2e}; is W positive definite?)"
                )
                break
            step = float(gc @ direction) / curvature
            r -= step * direction
            moved = float(np.min(r)) < 0.0
            joining = (r <= 0.0) & (g < 0.0)  # penetrating points without force
            conjugate = not np.any(joining)
            if moved or not conjugate:  # the projection takes r off the line, and W r with it
                np.maximum(r, 0.0, out=r)
                r[joining] -= step * g[joining]
            scale = 1.0
            if fixed_load:
                assert load is not None
                scale = load / float(np.sum(r))
                r *= scale
            if moved or not conjugate:
                u, fresh = W @ r, True
                products += 1
            else:  # r stayed on the line: so did its product (one product this step)
                u -= step * q
                u *= scale
                fresh = False
    return _Run(r, approach, converged, message, iterations, residual, products)


def _coarse_start(problem: SurfaceProblem, max_iter: int, precondition: bool, levels: list):
    """Forces for ``problem`` from the solves on its coarser lattices (None: no coarser one);
    each level's cells, iterations and products are appended to ``levels``, coarsest first."""
    coarsened = problem.coarsened()
    if coarsened is None:
        return None
    coarse, coarsening = coarsened
    start = _coarse_start(coarse, max_iter, precondition, levels)
    M = coarse.compliance.preconditioner() if precondition else None
    run = _iterate(coarse, start, COARSE_TOL, max_iter, M)
    levels.append({"points": coarse.size, "iterations": run.iterations, "products": run.products})
    if not np.any(run.forces > 0) or not np.all(np.isfinite(run.forces)):
        return None  # no use as a start
    return coarsening.prolong(run.forces)


def solve_constrained_cg(
    problem: SurfaceProblem,
    *,
    r0=None,
    tol: float = 1e-10,
    max_iter: int = MAX_ITER,
    precondition: bool = True,
    multilevel: bool = True,
) -> SurfaceResult:
    """Solve a :class:`~contactqp.core.surface.SurfaceProblem` by constrained conjugate
    gradients (Polonsky and Keer, 1999), at its fixed load or fixed approach.

    Parameters
    ----------
    problem : SurfaceProblem
    r0 : array_like, shape (m,), optional
        Warm start: forces of a nearby problem (N); negative entries are clipped and, at a
        fixed load, the rest scaled to the load. Default: the multilevel start if the
        operator has coarser lattices, else the load spread evenly (fixed load), or the
        interference ``max(delta - s, 0)`` scaled to the least energy (fixed approach).
    tol : float
        Largest gap on the contact and penetration off it, relative to the certificate's
        length scale (the largest surface displacement, or the indenter's interference).
    max_iter : int
        Largest number of iterations of each solve.
    precondition : bool
        Precondition the search directions by the operator's approximate inverse, when it
        has one (see the module notes).
    multilevel : bool
        Without ``r0``, start from the solves on the operator's coarser lattices, when it has
        them (see the module notes).

    Returns
    -------
    SurfaceResult
        Certified through one more product ``W r``. ``info`` holds the finest solve's
        ``residual`` and ``products``, ``preconditioned``, and ``levels``: the coarse solves'
        points, iterations and products, coarsest first.

    Raises
    ------
    InvalidInputError
        ``tol`` not a finite number > 0, ``max_iter`` not an integer >= 1, ``r0`` not a
        finite array of shape (m,), or ``precondition`` or ``multilevel`` not a bool.
    """
    tol = positive_tolerance(tol)
    max_iter = iteration_cap(max_iter)
    precondition = true_or_false(precondition, "precondition")
    multilevel = true_or_false(multilevel, "multilevel")
    start = time.perf_counter()
    levels: list[dict] = []
    if r0 is None and multilevel:
        r0 = _coarse_start(problem, max_iter, precondition, levels)
    M = problem.compliance.preconditioner() if precondition else None
    run = _iterate(problem, r0, tol, max_iter, M)
    return problem.make_result(
        run.forces,
        run.approach,
        method="constrained-cg",
        converged=run.converged,
        message=run.message,
        iterations=run.iterations,
        seconds=time.perf_counter() - start,
        info={  # the certificate's product not counted
            "residual": run.residual,
            "products": run.products,
            "preconditioned": M is not None,
            "levels": levels,
        },
    )

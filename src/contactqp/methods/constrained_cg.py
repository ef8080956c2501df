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

References
----------
.. [PK1999] I. A. Polonsky, L. M. Keer, "A new numerical method for solving rough contact
   problems based on the multi-level multi-summation and conjugate gradient techniques",
   Wear 231(2), 206-219, 1999.
"""

from __future__ import annotations

import time

import numpy as np

from ..core.model import iteration_cap, positive_tolerance, warm_start
from ..core.surface import SurfaceProblem, SurfaceResult

__all__ = ["solve_constrained_cg", "MAX_ITER"]

#: Default budget of iterations.
MAX_ITER = 5000


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


def solve_constrained_cg(
    problem: SurfaceProblem, *, r0=None, tol: float = 1e-10, max_iter: int = MAX_ITER
) -> SurfaceResult:
    """Solve a :class:`~contactqp.core.surface.SurfaceProblem` by constrained conjugate
    gradients [PK1999]_, at its fixed load or fixed approach.

    Parameters
    ----------
    problem : SurfaceProblem
    r0 : array_like, shape (m,), optional
        Warm start: forces of a nearby problem (N); negative entries are clipped and, at a
        fixed load, the rest scaled to the load. Default: the load spread evenly (fixed load),
        or the interference ``max(delta - s, 0)`` scaled to the least energy (fixed approach).
    tol : float
        Largest gap on the contact and penetration off it, relative to the certificate's
        length scale (the largest surface displacement, or the indenter's interference).
    max_iter : int
        Largest number of iterations.

    Returns
    -------
    SurfaceResult
        Certified through one more product ``W r``.

    Raises
    ------
    InvalidInputError
        ``tol`` not a finite number > 0, ``max_iter`` not an integer >= 1, or ``r0`` not a
        finite array of shape (m,).
    """
    tol = positive_tolerance(tol)
    max_iter = iteration_cap(max_iter)
    start = time.perf_counter()
    W, s = problem.compliance, problem.separation
    load, fixed_load = problem.load, problem.load is not None
    with np.errstate(over="ignore", invalid="ignore"):  # the certificate judges non-finite r
        r, u = _start(problem, r0)
        fresh = True  # u is the product W r (not updated from the previous step's)
        direction = np.zeros_like(r)
        previous, conjugate = 1.0, False
        approach = 0.0 if problem.approach is None else problem.approach
        lowest = float(np.min(s))
        converged, iterations, residual = False, 0, np.inf
        message = f"reached max_iter = {max_iter} iterations"
        while True:
            contact = r > 0.0
            g = s + u
            if fixed_load:
                approach = float(np.mean(g[contact]))
            g -= approach
            length = max(float(np.max(np.abs(u))), abs(approach - lowest), np.finfo(float).tiny)
            gc = np.where(contact, g, 0.0)
            residual = max(float(np.max(np.abs(gc))), float(np.max(-g, initial=0.0))) / length
            if residual <= tol:
                if not fresh:  # judge the forces by their own product, not the updated one
                    u, fresh = W @ r, True
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
            G = float(gc @ gc)
            if conjugate:  # t = g + (G / G_old) t_old on the contact, 0 off it
                direction = np.where(contact, gc + (G / previous) * direction, 0.0)
            else:
                direction = gc
            previous = G
            q = W @ direction
            projected = q - np.mean(q[contact]) if fixed_load else q
            curvature = float(np.where(contact, projected, 0.0) @ direction)
            if not curvature > 0.0:
                message = (
                    f"stopped after {iterations} iterations: no descent along the search "
                    f"direction (curvature {curvature:.2e}; is W positive definite?)"
                )
                break
            step = float(gc @ direction) / curvature
            r = r - step * direction
            joining = (r <= 0.0) & (g < 0.0)  # penetrating points without force
            conjugate = not np.any(joining)
            moved = not conjugate or bool(np.any(r < 0.0))
            if moved:  # the projection takes r off the line, and its product with it
                r = np.maximum(r, 0.0)
                r[joining] -= step * g[joining]
            scale = 1.0
            if fixed_load:
                assert load is not None
                scale = load / float(np.sum(r))
                r *= scale
            if moved:
                u, fresh = W @ r, True
            else:  # r stayed on the line: so did its product (one product this step)
                u, fresh = scale * (u - step * q), False
    return problem.make_result(
        r,
        approach,
        method="constrained-cg",
        converged=converged,
        message=message,
        iterations=iterations,
        seconds=time.perf_counter() - start,
        info={"residual": residual},
    )

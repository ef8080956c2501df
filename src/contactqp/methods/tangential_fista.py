"""Partial slip through operator products: an accelerated projected gradient on the discs.

With the normal forces ``p`` of the frictionless problem (solved first by
:func:`~contactqp.methods.constrained_cg.solve_constrained_cg`), the tangential forces ``t``
of a :class:`~contactqp.core.sliding_surface.SlidingSurfaceProblem` minimise

.. math::

    \\Pi(t) = \\tfrac12 t^T W_{TT}\\, t - \\delta_T \\cdot \\textstyle\\sum_i t_i,
    \\qquad |t_i| \\le \\mu_i p_i,

whose gradient is the slip ``w = W_TT t - delta_T``; its optimality conditions are the stick
and slip law of the problem (Tresca's problem with the bound ``mu p``, exact Coulomb when the
normal and tangential problems decouple).

Method: FISTA (Beck and Teboulle's accelerated projected gradient [BT2009]_) with the adaptive
restart of O'Donoghue and Candes [OC2015]_, the projection being onto each point's disc, the
step ``1 / L`` with ``L`` the largest eigenvalue of ``W_TT`` on the points in contact (Lanczos,
:func:`scipy.sparse.linalg.eigsh`, a few dozen products, once per problem; a sequence of shifts
reuses it). Why this and not Polonsky and Keer's conjugate gradient of the normal problem: on
discs the bound is curved, so a conjugate step along a slipping point's circle leaves the
disc at every iteration and the conjugation restarts every step; the accelerated projected
gradient converges for any convex set at the rate ``O(sqrt(kappa) log(1/eps))`` (linear with
the restart), with one product per iteration (the displacements of the extrapolated point are
the same combination of the last two products). Every product is through the operator.

The iteration stops when the projected slip vanishes at the current forces: inside a disc the
slip, on its bound the slip's part that is not directed against the force (with the outward
radial part when the slip points outward), relative to the certificate's length scale, below
``tol``.

References
----------
.. [BT2009] A. Beck, M. Teboulle, "A fast iterative shrinkage-thresholding algorithm for linear
   inverse problems", SIAM J. Imaging Sci. 2(1), 183-202, 2009.
.. [OC2015] B. O'Donoghue, E. Candes, "Adaptive restart for accelerated gradient schemes",
   Found. Comput. Math. 15, 715-732, 2015.
"""

from __future__ import annotations

import time
from collections.abc import Iterable

import numpy as np
from scipy.sparse.linalg import LinearOperator, eigsh

from ..core.model import iteration_cap, positive_tolerance, warm_start
from ..core.sliding_surface import SlidingSurfaceProblem, SlidingSurfaceResult
from ..core.surface import SurfaceProblem
from ..errors import InvalidInputError, UnsupportedProblemError
from .constrained_cg import solve_constrained_cg

__all__ = ["solve_tangential_fista", "shear_history", "MAX_ITER", "COUPLING_RTOL"]

#: Default budget of iterations.
MAX_ITER = 20000
#: The compliance couples the normal and tangential problems when the tangential displacements
#: of the normal forces exceed this fraction of their normal displacements.
COUPLING_RTOL = 1e-12
_TINY = np.finfo(float).tiny


def _project(t: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """Each row of ``t`` (m, 2) projected on its disc of radius ``bound``."""
    size = np.hypot(t[:, 0], t[:, 1])
    scale = np.where(size > bound, bound / np.maximum(size, _TINY), 1.0)
    return t * scale[:, None]


def _project_sum(
    z: np.ndarray, bound: np.ndarray, force: np.ndarray, on: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(t, lam)``: the projection of ``z`` (m, 2) on the discs ``|t_i| <= bound_i`` with
    ``sum t = force``, ``t_i = P_i(z_i + lam)`` on the points ``on`` (0 elsewhere), the 2-D
    multiplier ``lam`` by damped Newton on the monotone ``sum_i P_i(z_i + lam) = force``."""
    zc, b = z[on], bound[on]
    lam = (force - zc.sum(axis=0)) / zc.shape[0]
    scale = max(float(np.hypot(*force)), float(b.sum()))
    for _ in range(100):
        v = zc + lam
        size = np.hypot(v[:, 0], v[:, 1])
        miss = _project(v, b).sum(axis=0) - force
        norm = float(np.hypot(*miss))
        if norm <= 1e-14 * scale:
            break
        edge = size > b
        c = b[edge] / size[edge]
        n = v[edge] / size[edge, None]
        jacobian = np.eye(2) * (np.count_nonzero(~edge) + c.sum())
        jacobian -= np.einsum("i,ij,ik->jk", c, n, n)
        try:
            step = np.linalg.solve(jacobian, miss)
        except np.linalg.LinAlgError:  # every point at its bound, the sum not turning
            step = miss / max(float(np.count_nonzero(~edge)), 1.0)
        a = 1.0
        while a > 1e-10:  # backtrack on |sum - force|
            trial = _project(zc + lam - a * step, b).sum(axis=0) - force
            if float(np.hypot(*trial)) < norm:
                break
            a *= 0.5
        lam = lam - a * step
    t = np.zeros_like(z)
    t[on] = _project(zc + lam, b)
    return t, lam


def _projected_slip(t: np.ndarray, w: np.ndarray, bound: np.ndarray, on: np.ndarray) -> float:
    """Largest norm of the slip that violates the law at ``t``: ``w`` inside a disc, on its
    bound ``w`` less its radial part when that part points inward against the force."""
    size = np.hypot(t[:, 0], t[:, 1])
    edge = on & (size >= bound * (1.0 - 1e-12))
    n = t / np.maximum(size, _TINY)[:, None]
    radial = np.einsum("ij,ij->i", w, n)
    g = w.copy()
    blocked = edge & (radial < 0.0)  # the slip opposes the force: only its turning is wrong
    g[blocked] -= radial[blocked, None] * n[blocked]
    g[~on] = 0.0
    return float(np.max(np.hypot(g[:, 0], g[:, 1]), initial=0.0))


def _lipschitz(apply, cells: np.ndarray) -> tuple[float, int]:
    """Largest eigenvalue of ``W_TT`` on the ``cells`` in contact (times 1.02), and the
    products it took."""
    k = 2 * cells.size
    count = [0]

    def matvec(x):
        count[0] += 1
        t = np.zeros((apply.size, 2))
        t[cells] = np.reshape(x, (-1, 2))
        return apply(t)[cells].ravel()

    if k <= 2:
        x = np.ones(k)
        return 1.02 * float(x @ matvec(x)) / float(x @ x), count[0]
    op = LinearOperator((k, k), matvec=matvec, dtype=float)
    value = eigsh(op, k=1, which="LA", tol=1e-4, ncv=min(k, 20), return_eigenvectors=False)
    return 1.02 * float(value[0]), count[0]


class _Tangential:
    """``t (m, 2) -> (W_TT t) (m, 2)`` through the full operator."""

    def __init__(self, problem: SlidingSurfaceProblem):
        self.W = problem.compliance
        self.size = problem.size
        self.products = 0

    def __call__(self, t: np.ndarray) -> np.ndarray:
        f = np.zeros((self.size, 3))
        f[:, :2] = t
        self.products += 1
        return np.asarray(self.W @ f.ravel()).reshape(-1, 3)[:, :2]


def solve_tangential_fista(
    problem: SlidingSurfaceProblem,
    *,
    r0=None,
    p0=None,
    tol: float = 1e-10,
    max_iter: int = MAX_ITER,
    lipschitz: float | None = None,
) -> SlidingSurfaceResult:
    """Solve a :class:`~contactqp.core.sliding_surface.SlidingSurfaceProblem`: the normal
    problem by constrained conjugate gradients, then the tangential one by FISTA on the discs.

    Parameters
    ----------
    problem : SlidingSurfaceProblem
    r0 : array_like, shape (m, 2) or (2 m,), optional
        Warm start of the tangential forces (N), e.g. those of the previous, smaller shift
        (projected on the discs). Default: zero (the unsheared state).
    p0 : array_like, shape (m,), optional
        Warm start of the normal forces (N).
    tol : float
        Largest projected slip (see the module notes) and largest gap of the normal solve,
        relative to the length scale of the certificate.
    max_iter : int
        Largest number of FISTA iterations.
    lipschitz : float, optional
        ``L`` (m/N), an upper bound of ``W_TT``'s largest eigenvalue on the contact; default:
        computed (Lanczos). ``info["lipschitz"]`` of a result on the same contact can be
        passed on.

    Returns
    -------
    SlidingSurfaceResult
        Certified through one more product ``W f``.

    Raises
    ------
    UnsupportedProblemError
        The compliance couples the normal and tangential problems (the tangential displacement
        of the normal forces exceeds :data:`COUPLING_RTOL` of their normal displacement).
    InvalidInputError
        Bad ``tol``, ``max_iter``, ``lipschitz`` or warm starts; a full compliance whose normal
        block is not the surface's compliance.
    """
    tol = positive_tolerance(tol)
    max_iter = iteration_cap(max_iter)
    if lipschitz is not None:
        lipschitz = positive_tolerance(lipschitz, "lipschitz")
    start = time.perf_counter()
    m = problem.size
    normal = solve_constrained_cg(problem.surface, r0=p0, tol=tol)
    p, approach = normal.forces, normal.approach
    apply = _Tangential(problem)
    with np.errstate(over="ignore", invalid="ignore"):
        check = np.asarray(problem.compliance @ problem.full_forces(np.zeros((m, 2)), p))
        apply.products += 1
        check = check.reshape(-1, 3)
        sink = float(np.max(np.abs(check[:, 2]), initial=0.0))
        if float(np.max(np.abs(check[:, :2]), initial=0.0)) > COUPLING_RTOL * sink:
            raise UnsupportedProblemError(
                "the compliance couples the normal and tangential problems (the normal forces "
                "move the surface tangentially); use an uncoupled compliance "
                "(HalfSpaceOperator(..., coupling=False): elastically similar bodies)"
            )
        mismatch = float(np.max(np.abs(check[:, 2] + normal.displacements), initial=0.0))
        if mismatch > 1e-9 * max(sink, _TINY):
            raise InvalidInputError(
                "compliance: its normal (zz) entries are not the surface problem's compliance "
                f"(normal displacements differ by {mismatch / max(sink, _TINY):.1e} relative)"
            )
    bound = problem.mu * np.maximum(p, 0.0)
    on = bound > 0.0
    cells = np.flatnonzero(on)
    force = problem.force
    if force is not None and not float(np.hypot(*force)) < float(np.sum(bound)):
        raise InvalidInputError(
            f"force: |Q| = {float(np.hypot(*force)):.6g} N is not below the friction limit "
            f"sum mu p = {float(np.sum(bound)):.6g} N (gross sliding has no fixed shift)"
        )
    delta = np.zeros(2) if problem.shift is None else problem.shift
    lowest = float(np.min(problem.surface.separation))
    base = max(float(np.max(np.abs(normal.displacements), initial=0.0)), abs(approach - lowest))
    t = np.zeros((m, 2))
    if r0 is not None:
        t = warm_start(np.ravel(r0), 2 * m).reshape(m, 2)
    if force is None:
        t = _project(t, bound)
    else:
        t, lam = _project_sum(t, bound, force, on)
    iterations, converged, residual = 0, False, np.inf
    message = f"reached max_iter = {max_iter} iterations"
    info: dict = {"normal_iterations": normal.iterations}
    if not normal.success:
        message = f"the normal problem failed: {normal.message}"
    elif cells.size == 0:  # nothing in contact carries friction: no tangential force
        t[:] = 0.0
        converged, message = True, "no point carries friction: no tangential force"
    else:
        if lipschitz is None:
            lipschitz, spent = _lipschitz(apply, cells)
            apply.products += spent
        step = 1.0 / lipschitz
        u = apply(t)
        y, uy, theta = t.copy(), u.copy(), 1.0
        with np.errstate(over="ignore", invalid="ignore"):
            while True:
                if force is not None:  # the shift: the displacement of the sticking points
                    size = np.hypot(t[:, 0], t[:, 1])
                    inside = on & (size < bound * (1.0 - 1e-9))
                    delta = u[inside].mean(axis=0) if np.any(inside) else lam / step
                w = u - delta
                length = max(base, float(np.hypot(*delta)), _TINY)
                residual = _projected_slip(t, w, bound, on) / length
                if residual <= tol:
                    converged = True
                    message = f"converged in {iterations} iterations (residual {residual:.1e})"
                    break
                if not np.isfinite(residual):
                    message = f"diverged after {iterations} iterations (non-finite slips)"
                    break
                if iterations >= max_iter:
                    break
                iterations += 1
                if force is None:
                    t_new = _project(y - step * (uy - delta), bound)
                    t_new[~on] = 0.0
                else:
                    t_new, lam = _project_sum(y - step * uy, bound, force, on)
                u_new = apply(t_new)
                if float(np.sum((y - t_new) * (t_new - t))) > 0.0:  # restart (gradient test)
                    theta, beta = 1.0, 0.0
                else:
                    theta_new = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * theta * theta))
                    beta, theta = (theta - 1.0) / theta_new, theta_new
                y = t_new + beta * (t_new - t)
                uy = u_new + beta * (u_new - u)
                t, u = t_new, u_new
        info["lipschitz"] = lipschitz
    info.update(residual=residual, products=apply.products, normal_products=normal.info["products"])
    return problem.make_result(
        t,
        p,
        approach,
        delta,
        method="tangential-fista",
        converged=converged,
        message=message,
        iterations=iterations,
        seconds=time.perf_counter() - start,
        info=info,
    )


def shear_history(
    surface: SurfaceProblem,
    compliance,
    mu,
    shifts: Iterable,
    **options,
) -> list[SlidingSurfaceResult]:
    """Press, then shear monotonically: one :class:`SlidingSurfaceProblem` per shift.

    Each shift is measured from the unsheared state and the shifts must grow along one fixed
    direction (a monotonic, proportional shear: each point's slip keeps its direction, so the
    answer at each shift is the one-step answer of the module notes). Each solve is
    warm-started from the previous one's forces and reuses its ``lipschitz``.

    Parameters
    ----------
    surface, compliance, mu
        As :class:`SlidingSurfaceProblem`.
    shifts : iterable of array_like, shape (2,)
        The shifts ``(delta_x, delta_y)`` (m), growing along one direction.
    **options
        Options of :func:`solve_tangential_fista` (``tol``, ``max_iter``).

    Returns
    -------
    list of SlidingSurfaceResult

    Raises
    ------
    InvalidInputError
        Shifts that are not parallel to the first nonzero one and growing.
    """
    results: list[SlidingSurfaceResult] = []
    direction: np.ndarray | None = None
    previous = 0.0
    r0 = p0 = lipschitz = None
    for shift in shifts:
        problem = SlidingSurfaceProblem(surface, compliance, mu, shift=shift)
        delta = np.asarray(problem.shift)
        size = float(np.hypot(delta[0], delta[1]))
        if direction is None and size > 0.0:
            direction = delta / size
        if size > 0.0:
            assert direction is not None
            along = float(delta @ direction)
            across = abs(float(delta[0] * direction[1] - delta[1] * direction[0]))
            if across > 1e-12 * size or along < previous:
                raise InvalidInputError(
                    f"shifts must grow along one direction (a monotonic shear), got {shift!r} "
                    f"after a shift of {previous!r} m along {tuple(direction)!r}"
                )
            previous = along
        result = solve_tangential_fista(problem, r0=r0, p0=p0, lipschitz=lipschitz, **options)
        results.append(result)
        r0, p0 = result.forces[:, 1:], result.forces[:, 0]
        lipschitz = result.info.get("lipschitz", lipschitz)
    return results

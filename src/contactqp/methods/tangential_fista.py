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

Coupling: with a coupled compliance (the ``(1 - 2 nu)`` terms of a rigid indenter on one
elastic body) the normal forces ``p`` add the tangential displacements ``W_Tz (-p)`` to the
slip, and the tangential forces add ``-(W_zT t)`` to the gaps. The two problems are then solved
in turn, each warm-started from its previous answer (a block Gauss-Seidel on the two fields,
the Panagiotopoulos process of Kalker's algorithms [K1990]_): the normal problem with the
separation ``s - W_zT t`` of the last tangential forces, then the tangential one with the
bound ``mu p`` and the slip offset of the new ``p``, until the
normal displacements of the tangential forces change by less than ``tol`` of the length scale
between two rounds (each round's tangential solve is converged at its own ``p``, so the answer
then meets both laws to ``tol``). The certificate judges the coupled problem through the full
product. Measured on a steel half-space (``nu = 0.3``, ``mu = 0.3``): 9 to 10 rounds.

Multilevel start: without warm starts, when both compliances have coarser lattices
(:meth:`~contactqp.core.operators.Operator.coarsening`: an FFT half-space of an even number
of cells), the problem is first solved on cells merged 2 x 2 (the separation and ``mu``
averaged, the same load and shift or force; to :data:`COARSE_TOL`), coarsest first, and its
forces, shared among the merged cells, start the finer solve. Measured on Cattaneo-Mindlin
(``Q = mu P / 2``, tol ``1e-10``): 337 FISTA iterations from the unsheared state at 128 x 128,
216 from the coarse start; at 256 x 256, 1,702 against 298 (41 s against 8.5 s).

The iteration stops when the projected slip vanishes at the current forces: inside a disc the
slip, on its bound the slip's part that is not directed against the force (with the outward
radial part when the slip points outward), relative to the certificate's length scale, below
``tol``; the test is made every :data:`CHECK_EVERY` iterations.

References
----------
.. [BT2009] A. Beck, M. Teboulle, "A fast iterative shrinkage-thresholding algorithm for linear
   inverse problems", SIAM J. Imaging Sci. 2(1), 183-202, 2009.
.. [OC2015] B. O'Donoghue, E. Candes, "Adaptive restart for accelerated gradient schemes",
   Found. Comput. Math. 15, 715-732, 2015.
.. [K1990] J. J. Kalker, *Three-dimensional elastic bodies in rolling contact*, Kluwer, 1990.
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from ..core.model import iteration_cap, positive_tolerance, true_or_false, warm_start
from ..core.sliding_surface import SlidingSurfaceProblem, SlidingSurfaceResult
from ..core.surface import SurfaceProblem
from ..errors import InvalidInputError
from .constrained_cg import solve_constrained_cg

__all__ = [
    "solve_tangential_fista",
    "shear_history",
    "MAX_ITER",
    "MAX_OUTER",
    "COUPLING_RTOL",
    "COARSE_TOL",
]

#: Default budget of iterations.
MAX_ITER = 20000
#: Default budget of rounds (normal, then tangential solve) of a coupled problem.
MAX_OUTER = 50
#: Tolerance of the coarse solves of the multilevel start (only a start of the finer one).
COARSE_TOL = 1e-8
#: The stopping test (about the cost of a product's transforms) is made every this many
#: iterations.
CHECK_EVERY = 4
#: The compliance couples the normal and tangential problems when the tangential displacements
#: of the normal forces exceed this fraction of their normal displacements.
COUPLING_RTOL = 1e-12
_TINY = np.finfo(float).tiny


def _project(t: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """Each row of ``t`` (m, 2) projected on its disc of radius ``bound``."""
    size = np.hypot(t[:, 0], t[:, 1])
    scale = np.divide(bound, size, out=np.ones_like(size), where=size > bound)
    return t * scale[:, None]


def _project_sum(
    z: np.ndarray,
    bound: np.ndarray,
    force: np.ndarray,
    on: np.ndarray,
    lam0: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``(t, lam)``: the projection of ``z`` (m, 2) on the discs ``|t_i| <= bound_i`` with
    ``sum t = force``, ``t_i = P_i(z_i + lam)`` on the points ``on`` (0 elsewhere), the 2-D
    multiplier ``lam`` by damped Newton on the monotone ``sum_i P_i(z_i + lam) = force``,
    from ``lam0`` (the previous iteration's) or the mean shift that meets the force."""
    zc, b = z[on], bound[on]
    lam = (force - zc.sum(axis=0)) / zc.shape[0] if lam0 is None else lam0.copy()
    scale = max(float(np.hypot(*force)), float(b.sum()))
    v = zc + lam
    projected = _project(v, b)
    miss = projected.sum(axis=0) - force
    norm = float(np.hypot(*miss))
    for _ in range(100):
        if norm <= 1e-14 * scale:
            break
        size = np.hypot(v[:, 0], v[:, 1])
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
        while True:  # backtrack on |sum - force|; the last trial is kept
            v = zc + (lam - a * step)
            projected = _project(v, b)
            trial = projected.sum(axis=0) - force
            if float(np.hypot(*trial)) < norm or a <= 1e-10:
                break
            a *= 0.5
        lam = lam - a * step
        miss, norm = trial, float(np.hypot(*trial))
    t = np.zeros_like(z)
    t[on] = projected
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
    from scipy.sparse.linalg import LinearOperator, eigsh

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
    start = np.random.default_rng(0).uniform(0.5, 1.5, k)  # ARPACK's own start is random
    value = eigsh(
        op, k=1, which="LA", tol=1e-4, ncv=min(k, 20), v0=start, return_eigenvectors=False
    )
    return 1.02 * float(value[0]), count[0]


class _Tangential:
    """Products of the full operator: ``t (m, 2) -> (W_TT t) (m, 2)`` for the iteration, and
    the cross terms of a coupled compliance."""

    def __init__(self, problem: SlidingSurfaceProblem):
        self.W = problem.compliance
        self.size = problem.size
        self.products = 0

    def full(self, t: np.ndarray, p: np.ndarray | None = None) -> np.ndarray:
        """``W f`` (m, 3) of tangential forces ``t`` (m, 2) and normal forces ``p`` (m,)."""
        f = np.zeros((self.size, 3))
        f[:, :2] = t
        if p is not None:
            f[:, 2] = -p
        self.products += 1
        return np.asarray(self.W @ f.ravel()).reshape(-1, 3)

    def __call__(self, t: np.ndarray) -> np.ndarray:
        return self.full(t)[:, :2]


def _normal_offsets(apply: _Tangential, p: np.ndarray, sink: np.ndarray) -> np.ndarray:
    """The tangential displacements (m, 2) of the normal forces ``p``: zeros for an uncoupled
    compliance (below :data:`COUPLING_RTOL` of their normal displacements ``sink``, the surface
    problem's ``W p``), checked against ``sink``."""
    with np.errstate(over="ignore", invalid="ignore"):
        check = apply.full(np.zeros((apply.size, 2)), p)
    largest = max(float(np.max(np.abs(check[:, 2]), initial=0.0)), _TINY)
    mismatch = float(np.max(np.abs(check[:, 2] + sink), initial=0.0))
    if mismatch > 1e-9 * largest:
        raise InvalidInputError(
            "compliance: its normal (zz) entries are not the surface problem's compliance "
            f"(normal displacements differ by {mismatch / largest:.1e} relative)"
        )
    if float(np.max(np.abs(check[:, :2]), initial=0.0)) <= COUPLING_RTOL * largest:
        return np.zeros((apply.size, 2))
    return check[:, :2].copy()


@dataclass
class _Run:
    """The state of one FISTA run on the discs at fixed normal forces."""

    t: np.ndarray
    delta: np.ndarray
    iterations: int = 0
    converged: bool = False
    residual: float = np.inf
    message: str = ""


def _fista(apply, t, bound, on, offset, force, delta, lam, step, tol, max_iter, base) -> _Run:
    """FISTA with adaptive restart on the discs ``|t_i| <= bound_i`` (see the module notes):
    the slip is ``W_TT t + offset - delta``, ``offset`` the tangential displacements of the
    normal forces (zero without coupling); at a fixed ``force`` the shift ``delta`` is the mean
    displacement of the sticking points and ``lam`` the multiplier of the force."""
    run = _Run(t, delta, message=f"reached max_iter = {max_iter} iterations")
    offset_given = bool(np.any(offset))

    def slip_of(forces: np.ndarray) -> np.ndarray:  # W_TT t + offset
        return apply(forces) + offset if offset_given else apply(forces)

    u = slip_of(t)
    y, uy, theta = t.copy(), u.copy(), 1.0
    with np.errstate(over="ignore", invalid="ignore"):
        while True:
            if run.iterations % CHECK_EVERY == 0 or run.iterations >= max_iter:
                if force is not None:  # the shift: the displacement of the sticking points
                    size = np.hypot(t[:, 0], t[:, 1])
                    inside = on & (size < bound * (1.0 - 1e-9))
                    delta = u[inside].mean(axis=0) if np.any(inside) else lam / step
                length = max(base, float(np.hypot(*delta)), _TINY)
                run.residual = _projected_slip(t, u - delta, bound, on) / length
                run.t, run.delta = t, delta
                if run.residual <= tol:
                    run.converged = True
                    run.message = (
                        f"converged in {run.iterations} iterations (residual {run.residual:.1e})"
                    )
                    return run
                if not np.isfinite(run.residual):
                    run.message = f"diverged after {run.iterations} iterations (non-finite slips)"
                    return run
                if run.iterations >= max_iter:
                    return run
            run.iterations += 1
            if force is None:
                t_new = _project(y - step * (uy - delta), bound)
                t_new[~on] = 0.0
            else:
                t_new, lam = _project_sum(y - step * uy, bound, force, on, lam)
            u_new = slip_of(t_new)
            step_t = t_new - t
            y -= t_new
            if float(np.vdot(y, step_t)) > 0.0:  # restart (gradient test)
                theta, beta = 1.0, 0.0
            else:
                theta_new = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * theta * theta))
                beta, theta = (theta - 1.0) / theta_new, theta_new
            y = step_t  # y = t_new + beta (t_new - t), and uy the same of u
            y *= beta
            y += t_new
            uy = u_new - u
            uy *= beta
            uy += u_new
            t, u = t_new, u_new


def _coarse_start(problem: SlidingSurfaceProblem, max_iter: int, max_outer: int, levels: list):
    """``(t, p)`` for ``problem`` from the solve on its coarser lattices, or None (no coarser
    lattice, or a coarse solve that gives no usable forces); each level's points and
    iterations are appended to ``levels``, coarsest first."""
    pressed, full = problem.surface.coarsened(), problem.compliance.coarsening()
    if pressed is None or full is None:
        return None
    surface, normal = pressed
    try:
        coarse = SlidingSurfaceProblem(
            surface,
            full.operator,
            normal.restrict(problem.mu),
            shift=problem.shift,
            force=problem.force,
        )
        result = _solve(coarse, None, None, COARSE_TOL, max_iter, None, max_outer, True, levels)
    except InvalidInputError:  # e.g. a force past the coarse pressure's friction limit
        return None
    levels.append({"points": coarse.size, "iterations": result.iterations})
    forces = result.forces
    if not np.all(np.isfinite(forces)) or not np.any(forces[:, 0] > 0):
        return None
    f = full.prolong(np.column_stack([forces[:, 1:], forces[:, 0]]).ravel()).reshape(-1, 3)
    return f[:, :2], f[:, 2]


def solve_tangential_fista(
    problem: SlidingSurfaceProblem,
    *,
    r0=None,
    p0=None,
    tol: float = 1e-10,
    max_iter: int = MAX_ITER,
    lipschitz: float | None = None,
    max_outer: int = MAX_OUTER,
    multilevel: bool = True,
) -> SlidingSurfaceResult:
    """Solve a :class:`~contactqp.core.sliding_surface.SlidingSurfaceProblem`: the normal
    problem by constrained conjugate gradients, then the tangential one by FISTA on the discs;
    with a coupled compliance, the two in turn until the coupling settles (see the module
    notes).

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
        relative to the length scale of the certificate; with coupling, also the largest
        change of the normal displacements the tangential forces cause between two rounds.
    max_iter : int
        Largest number of FISTA iterations (over all rounds).
    lipschitz : float, optional
        ``L`` (m/N), an upper bound of ``W_TT``'s largest eigenvalue on the contact; default:
        computed (Lanczos), and again when a round of a coupled problem brings new points into
        contact. ``info["lipschitz"]`` of a result on the same contact can be passed on.
    max_outer : int
        Largest number of rounds (normal solve, then tangential) of a coupled problem.
    multilevel : bool
        Without ``r0`` and ``p0``, start from the solves on the compliances' coarser
        lattices, when they have them (see the module notes).

    Returns
    -------
    SlidingSurfaceResult
        Certified through one more product ``W f``; ``info["rounds"]`` holds the rounds,
        ``info["levels"]`` the coarse solves' points and iterations, coarsest first.

    Raises
    ------
    InvalidInputError
        Bad ``tol``, ``max_iter``, ``max_outer``, ``lipschitz`` or warm starts; a full
        compliance whose normal block is not the surface's compliance; a fixed force not below
        the friction limit of the frictionless pressure.
    """
    tol = positive_tolerance(tol)
    max_iter = iteration_cap(max_iter)
    max_outer = iteration_cap(max_outer, "max_outer")
    given_lipschitz = None if lipschitz is None else positive_tolerance(lipschitz, "lipschitz")
    multilevel = true_or_false(multilevel, "multilevel")
    return _solve(problem, r0, p0, tol, max_iter, given_lipschitz, max_outer, multilevel, [])


def _solve(
    problem: SlidingSurfaceProblem,
    r0,
    p0,
    tol: float,
    max_iter: int,
    given_lipschitz: float | None,
    max_outer: int,
    multilevel: bool,
    levels: list,
) -> SlidingSurfaceResult:
    """:func:`solve_tangential_fista` on checked options; the coarse solves append to
    ``levels``."""
    start = time.perf_counter()
    m = problem.size
    surface = problem.surface
    if multilevel and r0 is None and p0 is None and not np.any(problem.previous_slips):
        nested = _coarse_start(problem, max_iter, max_outer, levels)
        if nested is not None:
            r0, p0 = nested
    normal = solve_constrained_cg(surface, r0=p0, tol=tol)
    p, approach = normal.forces, normal.approach
    apply = _Tangential(problem)
    offset = _normal_offsets(apply, p, normal.displacements)
    coupled = bool(np.any(offset))
    # the law acts on this increment's slip: the previous state's is taken off
    offset = offset - problem.previous_slips
    force = problem.force
    bound = problem.mu * np.maximum(p, 0.0)
    if force is not None and not float(np.hypot(*force)) < float(np.sum(bound)):
        raise InvalidInputError(
            f"force: |Q| = {float(np.hypot(*force)):.6g} N is not below the friction limit "
            f"sum mu p = {float(np.sum(bound)):.6g} N (gross sliding has no fixed shift)"
        )
    t = np.zeros((m, 2))
    if r0 is not None:
        t = warm_start(np.ravel(r0), 2 * m).reshape(m, 2)
    delta = np.zeros(2) if problem.shift is None else problem.shift
    lowest = float(np.min(surface.separation))
    info: dict = {
        "normal_iterations": normal.iterations,
        "normal_products": 0,
        "rounds": 0,
        "levels": levels,
    }
    lipschitz, measured_on = given_lipschitz, np.zeros(m, dtype=bool)
    sink = np.zeros(m)  # the normal displacements of the tangential forces (coupled only)
    iterations, converged, residual, message = 0, False, np.inf, ""
    for rounds in range(1, max_outer + 1):
        info["rounds"] = rounds
        info["normal_products"] += normal.info["products"]
        bound = problem.mu * np.maximum(p, 0.0)
        on = bound > 0.0
        base = max(float(np.max(np.abs(normal.displacements), initial=0.0)), abs(approach - lowest))
        lam = np.zeros(2)
        if force is None:
            t = _project(t, bound)
        elif float(np.hypot(*force)) < float(np.sum(bound)):
            t, lam = _project_sum(t, bound, force, on)
        else:  # the coupling moved the pressure: the force is past its friction limit
            converged = False
            message = f"round {rounds}: |Q| is past the friction limit sum mu p of the pressure"
            break
        if not normal.success:
            converged, message = False, f"the normal problem failed: {normal.message}"
            break
        if not np.any(on):  # nothing in contact carries friction: no tangential force
            t[:] = 0.0
            converged, message = True, "no point carries friction: no tangential force"
            break
        if given_lipschitz is None and np.any(on & ~measured_on):
            lipschitz, spent = _lipschitz(apply, np.flatnonzero(on))
            apply.products += spent
            measured_on = on
        assert lipschitz is not None
        run = _fista(
            apply,
            t,
            bound,
            on,
            offset,
            force,
            delta,
            lam,
            1.0 / lipschitz,
            tol,
            max_iter - iterations,
            base,
        )
        t, delta, residual, message = run.t, run.delta, run.residual, run.message
        iterations += run.iterations
        converged = run.converged
        if not (coupled and converged):
            break
        # the normal displacements of the new tangential forces: settled, or the next round
        new_sink = -apply.full(t)[:, 2]
        length = max(base, float(np.hypot(*delta)), _TINY)
        change = float(np.max(np.abs(new_sink - sink))) / length
        sink = new_sink
        if change <= tol:
            message = f"{message}; coupling settled in {rounds} rounds (change {change:.1e})"
            break
        if rounds == max_outer:
            converged = False
            message = (
                f"the normal-tangential coupling did not settle in max_outer = {max_outer} "
                f"rounds (change {change:.1e})"
            )
            break
        pressed = SurfaceProblem(
            surface.compliance,
            surface.separation + sink,
            load=surface.load,
            approach=surface.approach,
            certificate_tol=surface.certificate_tol,
        )
        normal = solve_constrained_cg(pressed, r0=p, tol=tol)
        p, approach = normal.forces, normal.approach
        info["normal_iterations"] += normal.iterations
        offset = _normal_offsets(apply, p, normal.displacements) - problem.previous_slips
    if lipschitz is not None:
        info["lipschitz"] = lipschitz
    info.update(residual=residual, products=apply.products, coupled=coupled)
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
    """A load history of shifts: one :class:`SlidingSurfaceProblem` per shift, each an
    increment from the state the one before left (its ``previous``).

    The first shift is one increment from the unloaded state (a zero first shift presses
    without shear: with a coupled compliance, Spence's frictional indentation); the next ones
    may go any way, back included (an unloading, a reversed shear): Coulomb's law acts on each
    increment's slip (see :mod:`contactqp.core.sliding_surface`). Each solve is warm-started
    from the previous one's forces and reuses its ``lipschitz``.

    Parameters
    ----------
    surface, compliance, mu
        As :class:`SlidingSurfaceProblem`.
    shifts : iterable of array_like, shape (2,)
        The shifts ``(delta_x, delta_y)`` (m), measured from the unloaded state.
    **options
        Options of :func:`solve_tangential_fista` (``tol``, ``max_iter``).

    Returns
    -------
    list of SlidingSurfaceResult
    """
    results: list[SlidingSurfaceResult] = []
    previous: SlidingSurfaceResult | None = None
    r0 = p0 = lipschitz = None
    for shift in shifts:
        problem = SlidingSurfaceProblem(surface, compliance, mu, shift=shift, previous=previous)
        result = solve_tangential_fista(problem, r0=r0, p0=p0, lipschitz=lipschitz, **options)
        results.append(result)
        previous = result
        r0, p0 = result.forces[:, 1:], result.forces[:, 0]
        lipschitz = result.info.get("lipschitz", lipschitz)
    return results

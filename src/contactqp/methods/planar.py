r"""2-D Coulomb friction on the local form ``u = W r + q``: Gauss-Seidel with an exact local solver.

In the plane a Coulomb cone ``{|r_T| <= mu r_N}`` is two half-planes, and one contact's problem
``u_i = W_ii r_i + b_i`` (``b_i = q_i + sum_{j != i} W_ij r_j``, the others held) has a closed-form
solution: exactly one of four cases holds for a positive definite ``W_ii``,

* open: ``r_i = 0`` when ``b_iN >= 0``;
* stick: ``u_i = 0``, ``r_i = -W_ii^{-1} b_i`` when it lies inside the cone;
* slip along either edge ``s = +1, -1``: ``r_i = r_N (1, -s mu_i)``, ``u_iN = 0`` (one linear
  equation for ``r_N >= 0``) and ``s u_iT >= 0``.

The first case that holds is taken (:func:`~contactqp.kernels.planar_gauss_seidel`, compiled).
Sweeps over the contacts in order are the nonsmooth block Gauss-Seidel method (Siconos'
``fc2d_nsgs`` with its exact local solver); on the files of small and medium 2-D problems it
reaches 1e-8 in tens of sweeps, each sweep one pass over ``W``'s stored entries.

With the compiled kernels the whole solve is one call
(:func:`~contactqp.kernels.compiled.planar_solve`): ``W`` is read once into its 2x2 contact
blocks (those holding a nonzero entry), the sweeps run on them, and the certificate (``u``,
the natural-map error, the accuracy limits' norms, the contact status) is computed in the same
call from the final ``r`` and ``W`` as given; no Python runs between sweeps. Evaluating the
error costs about a sweep, so it is evaluated at the cold start when that is ``r = 0``
(``u = q``: an open problem takes no sweep), after the first :data:`COMPILED_FIRST` sweeps,
then when the relative change of a sweep, scaled by the ratio of error to change at the last
evaluation, says ``tol`` may be met, and at least every ``PLANAR_EVERY`` (10) sweeps of the
kernel. On the 89-contact shared file this stops at the first sweep that meets ``tol`` (59)
after 7 evaluations.

Gauss-Seidel converges linearly, and slowly on the singular ``W`` of large rigid granular
problems. Without the compiled kernels the sweeps are driven from Python
(:func:`~contactqp.kernels.planar_gauss_seidel`, the oracle of the compiled solve): the
natural-map error (the convergence test) is computed after each of the first :data:`FIRST`
sweeps, then every :data:`EVERY`; from the third of these on, the sweeps stop when the rate of
the last two would not reach ``tol`` within :data:`SWEEPS` sweeps (a stall). The compiled solve
applies the same test to the rate over at least ``PLANAR_SPAN`` (20) sweeps.
The semismooth Newton method of :mod:`contactqp.methods.coulomb` then solves the problem from
the caller's start (not from the sweeps' point: on the rounded granular file that start makes
Newton stall), so that a stall costs a few dozen sweeps. Convergence is judged, as for
every local method, by the natural-map error of the final ``r`` computed from ``W`` as given
(:func:`~contactqp.methods.local_global.finish`, or the compiled solve's certificate).
"""

from __future__ import annotations

import functools
import time

import numpy as np

from .. import kernels
from ..core.local_problem import (
    LocalProblem,
    natural_map_residual,
)
from ..core.operators import PSD_SHIFT
from ..core.result import LocalResult
from ..errors import NotPositiveDefiniteError
from .coulomb import MAX_ITER
from .local_global import finish
from .sweeps import checked_start, compiled_sweeps, kernel_arrays, newton_after

__all__ = [
    "solve_planar",
    "check_contact_blocks",
    "SWEEPS",
    "EVERY",
    "FIRST",
    "COMPILED_FIRST",
    "ROUTE_MAX_CONTACTS",
]

SWEEPS = 200  #: largest number of Gauss-Seidel sweeps before Newton takes over
EVERY = 10  #: sweeps between two evaluations of the natural-map error (the first few: each)
FIRST = 4  #: sweeps after each of which the error is evaluated (small problems converge there)
#: Sweeps after each of which the compiled route evaluates the error; after them it evaluates it
#: when the change of a sweep, scaled by the ratio of error to change measured at the last
#: evaluation, says ``tol`` may be met (and at least every ``PLANAR_EVERY`` sweeps of
#: :func:`~contactqp.kernels.compiled.planar_solve`).
COMPILED_FIRST = 1
#: Most contacts of a 2-D problem that :func:`contactqp.solve` sends to the planar route when no
#: method is named; larger ones go to the coulomb method directly. Gauss-Seidel's rate falls
#: with the size of a rigid granular assembly: on the shared 2,020-contact granular file its
#: sweeps would need thousands of iterations (Siconos' NSGS does not converge in 10,000), and
#: the stall test there costs 34 sweeps (a few per cent of Newton's time) before Newton solves it.
ROUTE_MAX_CONTACTS = 1000


def check_contact_blocks(blocks: np.ndarray) -> None:
    """Raise unless each contact's 2x2 diagonal block of ``W`` has a semidefinite symmetric part.

    ``blocks[i] = (a, b, c, d)``, contact ``i``'s block ``[[a, b], [c, d]]``
    (:func:`~contactqp.kernels.planar_blocks`). What the local solver needs of ``W``, and a
    necessary condition for ``W`` to be positive semidefinite: with the Jacobi scaling and the
    shift of :func:`~contactqp.core.local_problem.check_positive_semidefinite`, a block passes
    when ``a, d >= 0`` and ``((b + c) / 2)^2 <= (1 + PSD_SHIFT)^2 a d`` (so a zero diagonal
    entry has a zero symmetric coupling).

    Raises
    ------
    NotPositiveDefiniteError
        Naming the first contact whose block fails.
    """
    a, b, c, d = blocks.T
    coupling = 0.5 * (b + c)
    bad = (a < 0) | (d < 0) | (coupling * coupling > (1.0 + PSD_SHIFT) ** 2 * a * d)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise NotPositiveDefiniteError(
            f"W is not positive semidefinite: the symmetric part of contact {i}'s diagonal "
            f"block [[{a[i]:.3g}, {b[i]:.3g}], [{c[i]:.3g}, {d[i]:.3g}]] is not"
        )


def _sweeps(
    arrays: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    q,
    mu,
    r,
    tol,
    budget,
    measure,
):
    """Sweep from ``r`` (in place) until ``measure`` meets ``tol``, a stall or ``budget``.

    The kernel's own test is the FCLIB error of ``r``; ``measure(r, u)``, when given, is
    ``(residual, error)`` of the method's test where that differs (``per_contact``, or
    cohesion: ``r`` is then measured from the apex), and the kernel's is tightened
    tenfold (up to twice) when it is met but ``measure`` is not. Returns
    ``(sweeps, converged)``.
    """
    u = np.empty_like(q)
    done, target = 0, tol
    for first in (True, False, False, False):
        if done >= budget:
            break
        count, every = (min(FIRST, budget - done), 1) if first else (budget - done, EVERY)
        sweeps, error = kernels.planar_gauss_seidel(
            *arrays, q, mu, r, u, target, count, every, not first
        )
        done += sweeps
        if error <= target:
            if measure is None or measure(r, u)[1] <= tol:
                return done, True
            if not first:
                target *= 0.1
        elif not first:  # stalled or out of sweeps
            return done, False
    return done, False


def solve_planar(
    problem: LocalProblem,
    *,
    r0=None,
    tol: float = 1e-8,
    max_iter: int = MAX_ITER,
    check_psd: bool = True,
    per_contact: bool = False,
) -> LocalResult:
    """Solve a 2-D local Coulomb (Mohr-Coulomb) problem to natural-map error ``tol``.

    Gauss-Seidel sweeps with the exact 2-D local solver (see the module notes); when they
    stall, :func:`~contactqp.methods.coulomb.solve_coulomb` from ``r0``.

    Parameters
    ----------
    problem : LocalProblem
        ``dim == 2``.
    r0 : array_like, shape (m,), optional
        Warm start (reactions); zero when not given.
    tol : float
        Target of :func:`~contactqp.core.local_problem.natural_map_error`.
    max_iter : int
        Budget of Gauss-Seidel sweeps (at most :data:`SWEEPS` of them) and, after a stall,
        Newton iterations and sweeps of :func:`~contactqp.methods.coulomb.solve_coulomb`.
    check_psd : bool
        Check that each contact's diagonal block of ``W`` is positive semidefinite
        (:func:`check_contact_blocks`, what the sweeps rely on: a read of three diagonals);
        when Newton takes over, it checks what it solves on (all of ``W``, or the blocks of
        its candidate sets: see :func:`~contactqp.methods.coulomb.solve_coulomb`). A full
        factorisation would cost several times the sweeps on the files of small 2-D problems;
        the answer is judged by its natural-map error on ``W`` as given either way.
    per_contact : bool
        Converge to ``tol`` on every contact's own scale too.

    Returns
    -------
    LocalResult
        ``method`` is ``"planar"`` when the sweeps converged, else ``"coulomb"`` (the message
        then says how many sweeps ran first); ``iterations`` counts sweeps plus the Newton
        route's iterations.

    Raises
    ------
    InvalidInputError
        A problem of dimension 3, or a bad ``tol``, ``max_iter`` or ``r0``.
    NotPositiveDefiniteError
        If ``W`` is not positive semidefinite.
    """
    start = time.perf_counter()
    given = checked_start(problem, 2, "planar", r0, tol, max_iter)
    budget = min(SWEEPS, max_iter)
    if kernels.planar_solve is not None:
        result, sweeps, error = compiled_sweeps(
            problem,
            kernels.planar_solve,
            kernels.PLANAR_REASONS,
            "planar",
            functools.partial(_bad_block, problem=problem),
            given.copy(),
            tol,
            budget,
            COMPILED_FIRST,
            max_iter,
            check_psd,
            per_contact,
            start,
        )
        if result is not None:
            return result
        return newton_after(
            problem, r0, given, tol, max_iter, check_psd, per_contact, start, sweeps, error
        )
    arrays = kernel_arrays(problem.W)
    blocks = np.empty((problem.n_contacts, 4))
    kernels.planar_blocks(*arrays, blocks)
    if check_psd:
        check_contact_blocks(blocks)
    W, shift = problem.W, problem.apex_shift
    shifted = bool(np.any(shift))
    q = problem.q - np.asarray(W @ shift).ravel() if shifted else problem.q

    def measure(r_apex, u):
        return natural_map_residual(problem, r_apex - shift, u, per_contact=per_contact)

    r = given + shift
    sweeps, converged = _sweeps(
        (*arrays, blocks),
        q,
        problem.mu,
        r,
        tol,
        min(SWEEPS, max_iter),
        measure if per_contact or shifted else None,  # else the kernel's test is the FCLIB one
    )
    if converged or sweeps >= max_iter:
        detail = f"gauss-seidel {sweeps} sweeps" + ("" if converged else " (budget spent)")
        reactions = r - shift
        product, magnitude = np.empty_like(r), np.empty_like(r)  # W r and |W| |r|, read once
        kernels.row_products(*arrays, reactions, product, magnitude)
        return finish(
            problem,
            reactions,
            tol,
            sweeps,
            start,
            detail,
            method="planar",
            per_contact=per_contact,
            products=(product, magnitude),
        )
    error = measure(r, np.asarray(W @ r).ravel() + q)[1]  # where the sweeps stopped
    return newton_after(
        problem, r0, given, tol, max_iter, check_psd, per_contact, start, sweeps, error
    )


def _bad_block(contact: int, problem: LocalProblem) -> None:
    """Raise for ``contact``, whose diagonal block failed the compiled solve's test."""
    blocks = np.empty((problem.n_contacts, 4))
    kernels.planar_blocks(*kernel_arrays(problem.W), blocks)
    check_contact_blocks(blocks)  # raises, naming the block and its entries
    raise NotPositiveDefiniteError(  # a block of duplicate entries, which the kernel sums
        f"W is not positive semidefinite: the symmetric part of contact {contact}'s "
        f"diagonal block (its duplicate entries summed) is not"
    )

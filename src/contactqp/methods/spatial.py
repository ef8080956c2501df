r"""3-D Coulomb friction on the local form ``u = W r + q``: Gauss-Seidel, local problems by cases.

Contact ``i``'s problem ``u_i = W_ii r_i + b_i`` (``b_i = q_i + sum_{j != i} W_ij r_j``, the
others held) is solved by its cases, in order (:func:`~contactqp.kernels.compiled.spatial_solve`,
compiled):

* open: ``r_i = 0`` when ``b_iN >= 0`` (then ``u_i = b_i`` lies in the dual cone);
* without friction (``mu_i = 0``): ``r_i = (-b_iN / W_iNN, 0, 0)``;
* stick: ``r_i = -W_ii^{-1} b_i`` when it lies in the cone (then ``u_i = 0``);
* otherwise it slips: coulomb's semismooth Newton run (:mod:`~contactqp.methods.coulomb`) on
  the one-contact problem, from the contact's last reactions, to a natural-map error of 1e-13.

Sweeps over the contacts in order are the nonsmooth block Gauss-Seidel method (Siconos'
``fc3d_nsgs``; Jourdan, Alart and Jean 1998). Where the contacts interact little, as in the
small FCLIB files of one or a few bodies, the first sweep already solves the problem (a few
microseconds); the medium files of a few dozen bodies take tens of sweeps. The whole solve is one
compiled call, with the error evaluations and the stall test of the planar route
(:mod:`~contactqp.methods.planar`) and the certificate from the final ``r`` and ``W`` as given.

Gauss-Seidel converges linearly, and slowly on the singular ``W`` of large rigid assemblies
(Siconos' NSGS takes thousands of sweeps on the shared Capsules files). When the sweeps'
rate would not reach ``tol`` within :data:`SWEEPS` sweeps, the semismooth Newton method of
:func:`~contactqp.methods.coulomb.solve_coulomb` solves the problem from the caller's start
(:func:`~contactqp.methods.sweeps.newton_after`). Without the compiled kernels the method is
that Newton route alone.
"""

from __future__ import annotations

import functools
import time

import numpy as np

from .. import kernels
from ..core.local_problem import LocalProblem, check_positive_semidefinite
from ..core.operators import PSD_SHIFT, is_sparse
from ..core.result import LocalResult
from ..errors import NotPositiveDefiniteError
from .coulomb import MAX_ITER, solve_coulomb
from .sweeps import checked_start, compiled_sweeps, newton_after

__all__ = ["solve_spatial", "SWEEPS", "FIRST", "ROUTE_MAX_CONTACTS"]

SWEEPS = 200  #: largest number of Gauss-Seidel sweeps before Newton takes over
FIRST = 1  #: sweeps after each of which the error is evaluated (then as the planar route)
#: Most contacts of a 3-D problem that :func:`contactqp.solve` sends to this route when no
#: method is named; larger ones go to the coulomb method directly. On the shared FCLIB files
#: the sweeps converge up to 107 contacts (Confeti, 22 sweeps), and stall from 216 (the
#: Capsules files, spheres-in-a-box, Spheres-i099), where the stall test's 30 to 60 sweeps
#: would cost a fifth of Newton's time.
ROUTE_MAX_CONTACTS = 150


def _bad_block(contact: int, problem: LocalProblem) -> None:
    """Raise for ``contact``, whose diagonal block failed the compiled solve's test: the
    message of :func:`~contactqp.core.local_problem.check_positive_semidefinite` on it."""
    rows = slice(3 * contact, 3 * contact + 3)
    block = problem.W[rows, rows]
    block = np.asarray(block.toarray() if is_sparse(block) else block)  # duplicates summed
    name = f"W's diagonal block of contact {contact}"
    check_positive_semidefinite(block, name)  # raises, saying what fails
    raise NotPositiveDefiniteError(  # a block at the edge of the test, which the kernel failed
        f"{name} is not positive semidefinite: the Cholesky factorisation of its Jacobi-scaled "
        f"symmetric part + {PSD_SHIFT:g} I fails"
    )


def solve_spatial(
    problem: LocalProblem,
    *,
    r0=None,
    tol: float = 1e-8,
    max_iter: int = MAX_ITER,
    check_psd: bool = True,
    per_contact: bool = False,
) -> LocalResult:
    """Solve a 3-D local Coulomb (Mohr-Coulomb) problem to natural-map error ``tol``.

    Gauss-Seidel sweeps with the local solver by cases (see the module notes); when they
    stall, :func:`~contactqp.methods.coulomb.solve_coulomb` from ``r0``.

    Parameters
    ----------
    problem : LocalProblem
        ``dim == 3``.
    r0 : array_like, shape (m,), optional
        Warm start (reactions); zero when not given.
    tol : float
        Target of :func:`~contactqp.core.local_problem.natural_map_error`.
    max_iter : int
        Budget of Gauss-Seidel sweeps (at most :data:`SWEEPS` of them) and, after a stall,
        Newton iterations and sweeps of :func:`~contactqp.methods.coulomb.solve_coulomb`.
    check_psd : bool
        Check that each contact's diagonal block of ``W`` is positive semidefinite (what the
        sweeps rely on); when Newton takes over, it checks what it solves on (all of ``W``,
        or the blocks of its candidate sets: see :func:`~contactqp.methods.coulomb.solve_coulomb`).
        The answer is judged by its natural-map error on ``W`` as given either way.
    per_contact : bool
        Converge to ``tol`` on every contact's own scale too.

    Returns
    -------
    LocalResult
        ``method`` is ``"spatial"`` when the sweeps converged, else ``"coulomb"`` (the message
        then says how many sweeps ran first); ``iterations`` counts sweeps plus the Newton
        route's iterations.

    Raises
    ------
    InvalidInputError
        A problem of dimension 2, or a bad ``tol``, ``max_iter`` or ``r0``.
    NotPositiveDefiniteError
        If a diagonal block of ``W`` (or, after a stall, ``W``) is not positive semidefinite.
    """
    start = time.perf_counter()
    given = checked_start(problem, 3, "spatial", r0, tol, max_iter)
    if kernels.spatial_solve is None:
        return solve_coulomb(
            problem, r0=r0, tol=tol, max_iter=max_iter, check_psd=check_psd, per_contact=per_contact
        )
    result, sweeps, error = compiled_sweeps(
        problem,
        kernels.spatial_solve,
        kernels.SPATIAL_REASONS,
        "spatial",
        functools.partial(_bad_block, problem=problem),
        given.copy(),
        tol,
        min(SWEEPS, max_iter),
        FIRST,
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

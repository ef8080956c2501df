r"""Coulomb friction with polygonal cones: a fixed point of Tresca quadratic programs (qpsolvers).

The linearised friction law replaces the disc ``||r_T|| <= s`` of each contact by the inscribed
regular polygon of ``facets`` sides,

.. math::

    n_k \cdot r_T \le s \cos\frac{\pi}{F}, \qquad
    n_k = (\cos\tfrac{2\pi k}{F}, \sin\tfrac{2\pi k}{F}), \quad k = 0, \dots, F - 1,

so that with the bounds ``s_i = mu_i r_N,i`` frozen each step is a convex quadratic program with
linear constraints, solved by any :mod:`qpsolvers` backend; ``s`` is then updated as in
:func:`~contactqp.methods.tresca.solve_tresca_fixed_point`. The polygon's vertices lie on the
circle and its sides at the distance ``s cos(pi / F)`` from the centre: the admissible tangential
force is reduced by the factor ``1 - cos(pi / F)`` across the middle of a side (7.6 % for
``F = 8``, 1.9 % for 16, 0.5 % for 32) and not at all at a vertex, and a sliding force may point
up to ``pi / F`` away from the direction opposite to the slip. The answer therefore solves the
polygonal problem, not the Coulomb one: its natural-map error against the exact cones is
reported, and is of the order of ``mu (1 - cos(pi / F))`` on sliding contacts.

In 2-D the tangential space is a line and the Coulomb "disc" is the segment ``|r_T| <= s``: the
two facets ``+-r_T <= s`` are the cone itself, so the 2-D route is exact (``facets`` is then not
used) and its error reaches ``tol`` like the Tresca route's (each QP answer is polished by the
same Newton steps).

The frozen-bound fixed point is used rather than the polyhedral cone
``n_k . r_T <= mu cos(pi / F) r_N`` in a single quadratic program: that program's optimality
conditions make the normal velocity ``u_N`` take a share of the slip (an associated, dilatant
law), which is not Coulomb friction.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..core.friction import polygon_normals
from ..core.local_problem import LocalProblem
from ..core.result import LocalResult
from ..errors import SolverError
from .qp import backend_options, installed_backend, run_backend
from .tresca import (
    FixedPointData,
    check_fixed_point_arguments,
    free_unknowns,
    polish,
    run_fixed_point,
)

__all__ = ["solve_polygonal"]


class _PolygonalTresca:
    """Tresca problem with polygonal discs as a qpsolvers problem (scaled like the SOCP)."""

    def __init__(self, data: FixedPointData, facets: int, backend: str, options: dict):
        import scipy.sparse as sp

        self.qpsolvers = installed_backend(backend, "the polygonal cone")
        self.backend = backend
        self.options = {**backend_options(backend), **options}
        self.chosen = tuple(options)
        self.w = data.w
        self.sparse = backend in self.qpsolvers.sparse_solvers
        P = self.W = data.W_sym / self.w
        self.P: sp.csc_matrix | np.ndarray
        if self.sparse:
            self.P = sp.csc_matrix(P)
        else:
            self.P = P if isinstance(P, np.ndarray) else P.toarray()
        self.d, self.nc = data.dim, data.n_contacts
        self.normals = polygon_normals(facets) if self.d == 3 else None
        self.inradius = np.cos(np.pi / facets)

    def __call__(self, q, s, f):
        import scipy.sparse as sp

        d, nc = self.d, self.nc
        keep, sliding, normal, tangent = free_unknowns(s, d)
        bound = s[sliding] / f
        lower = np.full(keep.size, -np.inf)
        lower[normal] = 0.0
        G: sp.csc_matrix | None = None
        h: np.ndarray | None = None
        if d == 2:  # the exact segment |x_T| <= s as two facets
            G = sp.csc_matrix(
                (
                    np.repeat([1.0, -1.0], bound.size),
                    (np.arange(2 * bound.size), np.tile(tangent[:, 0], 2)),
                ),
                shape=(2 * bound.size, keep.size),
            )
            h = np.tile(bound, 2)
        elif bound.size:
            assert self.normals is not None, "a 3-D problem has its facet normals"
            sides = self.normals.shape[0]
            rows = np.arange(bound.size * sides)
            G = sp.csc_matrix(
                (
                    np.tile(self.normals, (bound.size, 1)).ravel(),
                    (np.repeat(rows, 2), np.repeat(tangent, sides, axis=0).ravel()),
                ),
                shape=(rows.size, keep.size),
            )
            h = self.inradius * np.repeat(bound, sides)
        G_backend = G.toarray() if G is not None and not self.sparse else G
        P = self.P[keep][:, keep] if self.sparse else self.P[np.ix_(keep, keep)]
        problem = self.qpsolvers.Problem(P, q[keep] / (f * self.w), G_backend, h, lb=lower)
        with warnings.catch_warnings():
            # An inexact status (e.g. Clarabel's "AlmostSolved" at the tight tolerances) is
            # judged by the outer loop, which measures every iterate itself.
            warnings.simplefilter("ignore", UserWarning)
            x = run_backend(
                self.qpsolvers,
                problem,
                self.backend,
                self.options,
                "the polygonal Tresca problem",
                chosen=self.chosen,
            ).x
        if x is None or not np.all(np.isfinite(x)):
            raise SolverError(
                f"backend {self.backend!r} found no solution of the polygonal Tresca problem "
                f"(is W positive semidefinite?)"
            )
        x = np.asarray(x)
        if d == 3 and G is not None:
            x = _polish_active_set(P, q[keep] / (f * self.w), G, h, normal, x)
        r = np.zeros(d * nc)
        r[keep] = x
        if d == 2:  # the segment is the Coulomb disc of 2-D: polish as the Tresca route does
            r = polish(self.W, q / (f * self.w), s / f, r, d)
        return f * r


#: A constraint whose slack is below this fraction of the solution's scale is taken as active.
_ACTIVE_RTOL = 1e-7


def _polish_active_set(P, c, G, h, normal, x):
    """``x`` refined by one exact KKT solve on the interior-point answer's active set.

    The polygonal Tresca problem ``min 1/2 x^T P x + c^T x, G x <= h, x_normal >= 0`` has linear
    constraints: with the binding facets and normal bounds known, its solution is that of a
    linear system. The interior-point answer is accurate to about 1e-9 relative, which left the
    outer fixed point cycling at that level (relative change 2e-10 against a tol of 1e-10 on a
    3-D hex block, 50 iterations without converging); the solve brings each answer to rounding.
    The refined point is kept only if it is feasible and its multipliers are >= 0 (the active
    set was right); otherwise ``x`` is returned.
    """
    import scipy.sparse as sp
    from scipy.sparse.linalg import splu

    G = sp.csr_matrix(G)
    scale = max(
        float(np.max(np.abs(x), initial=0.0)),
        float(np.max(np.abs(h), initial=0.0)),
        np.finfo(float).tiny,
    )
    tiny = _ACTIVE_RTOL * scale
    facets = np.flatnonzero(h - G @ x <= tiny)
    bounds = normal[x[normal] <= tiny]
    n = x.size
    C = sp.vstack(
        [
            G[facets],
            sp.csr_matrix(
                (-np.ones(bounds.size), (np.arange(bounds.size), bounds)), shape=(bounds.size, n)
            ),
        ]
    ).tocsc()
    kkt = sp.bmat([[sp.csc_matrix(P), C.T], [C, None]], format="csc")
    rhs = np.concatenate([-c, h[facets], np.zeros(bounds.size)])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a singular system shows as a non-finite answer
            solution = splu(kkt).solve(rhs)
    except RuntimeError:  # exactly singular (degenerate active set)
        return x
    refined, multipliers = solution[:n], solution[n:]
    feasible = (
        np.all(np.isfinite(solution))
        and np.all(G @ refined <= h + tiny)
        and np.all(refined[normal] >= -tiny)
        and np.all(multipliers >= -tiny)
    )
    return refined if feasible else x


def solve_polygonal(
    problem: LocalProblem,
    *,
    r0=None,
    facets: int = 8,
    backend: str = "clarabel",
    tol: float = 1e-8,
    max_iter: int = 50,
    per_contact: bool = False,
    **options,
) -> LocalResult:
    """Solve a local problem with polygonal friction cones by a fixed point of QPs (qpsolvers).

    Parameters
    ----------
    problem : LocalProblem
        ``W`` symmetric positive semidefinite, or nearly so (the skew part is iterated on).
    facets : int
        Sides of the inscribed polygon replacing each friction disc in 3-D, >= 3. Checked but
        not used in 2-D, where the two facets ``+-r_T <= mu r_N`` are the exact cone.
    backend : str
        A :mod:`qpsolvers` backend (see :func:`~contactqp.methods.qp.available_backends`),
        run with contactqp's tight tolerances (:func:`~contactqp.methods.qp.backend_options`).
    tol : float
        In (0, 1). Convergence: the natural-map error is at most ``tol`` (always so in 2-D,
        exact cone), or in 3-D the relative change of the reactions between two iterations is.
    max_iter : int
        Largest number of quadratic programs solved.
    r0 : array_like, shape (m,), optional
        Starting reactions (N); default: a frictionless first step.
    per_contact : bool
        Measure the natural map on every contact's own scale too
        (``natural_map_error(..., per_contact=True)``); the FCLIB measure is the default.
    **options
        Passed to the backend over the tight defaults.

    Returns
    -------
    LocalResult
        The certificate's ``natural_map`` is the error against the exact Coulomb cones (it
        does not reach ``tol`` in 3-D: see the module notes); ``message`` states it.

    Raises
    ------
    InvalidInputError
        Bad ``problem``, ``tol``, ``max_iter``, ``r0``, ``facets < 3`` (or not an integer), an
        unknown backend or a setting the backend refuses.
    SolverError
        The backend raises, or finds no solution of one of the quadratic programs.
    MissingDependencyError
        qpsolvers is not installed.
    """
    polygon_normals(facets)
    start = check_fixed_point_arguments(problem, tol, max_iter, r0)
    data = FixedPointData(problem)
    return run_fixed_point(
        problem,
        data,
        _PolygonalTresca(data, facets, backend, options),
        tol=tol,
        max_iter=max_iter,
        r0=start,
        exact=problem.dim == 2,
        per_contact=per_contact,
        method="polygonal",
    )

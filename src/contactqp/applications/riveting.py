r"""Assembly of two thin plates by fasteners (riveting): gaps, contact and fastener forces.

Model
-----
Two plates lie one over the other (``lower`` and ``upper``), their facing surfaces separated
by an initial gap field (part deviations). Both are held by the assembly jig along the same
edges (by default the short edges ``x = 0`` and ``x = length``, simply supported: ``w = 0``).
Each plate is a Kirchhoff plate in bending, assembled with scikit-fem's Morley triangles on the
structured mesh of :func:`~contactqp.compliance.fem.plate`,

.. math::

    a(w, v) = \int \frac{E t^3}{12 (1 + \nu)} \Big(\nabla^2 w
        + \frac{\nu}{1 - \nu} \operatorname{tr}(\nabla^2 w) I\Big) : \nabla^2 v \, dx ,

and condensed (:func:`~contactqp.compliance.condensation.condense`) to the out-of-plane
deflection ``w`` of a grid of contact nodes. Only the out-of-plane freedom is kept: the gaps
are normal to the plates and the membrane (in-plane) response of a flat plate does not couple
with it in the linear theory, so the contact is **frictionless** (friction on the interface
would need the in-plane slip of the surfaces, which this plate model does not give).

The reduced model has ``2 k`` nodes with one freedom each (``k`` contact pairs): nodes
``0 .. k-1`` on the lower plate, ``k .. 2k-1`` on the upper one, pair ``i = (i, k + i)`` with
direction ``+z`` (:class:`~contactqp.core.contact.NodePairs`): ``w_lower - w_upper <= gap``.

Fasteners
---------
A fastener imposes closure: at its pair the gap is brought to zero and held there (a bilateral
constraint). Its multiplier ``lambda_f`` is free in sign: ``lambda_f >= 0`` is a contact
compression at the fastener, ``lambda_f < 0`` a tension ``-lambda_f`` carried by the fastener.
The dual QP is the frictionless one (:class:`~contactqp.core.problem.DualForm`) with the lower bound
of the fastener rows lifted to ``-inf``; :class:`FastenerClosure` eliminates the fastener
multipliers (a Schur complement) and solves the remaining non-negative QP by Lawson and
Hanson's active-set method (or the project's box-QP solver, or scipy's NNLS). The answer is
returned as a certified :class:`~contactqp.core.result.ContactResult` of the contact problem in which
the fastener tensions are external loads, and the closure of each fastener is checked
separately. Fasteners are installed one after another (:meth:`RivetingModel.fasten`), each an
increment warm-started from the previous one; without friction the final state does not depend
on the order (a test checks it), the intermediate states do.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path

import numpy as np
import scipy.linalg

from ..studies.batch import GapVariation
from ..core.contact import NodePairs
from ..errors import InvalidInputError
from ..io.export import PointMesh
from ..core.model import ReducedModel, finite_array
from ..core.problem import ContactProblem
from ..core.result import ContactResult
from ..methods import solve_box_qp
from ..methods.lawson_hanson import solve_nonnegative_qp

__all__ = ["Plate", "Assembly", "RivetingModel", "FastenedResult", "FasteningSequence",
           "FasteningCase", "FastenerClosure", "plate_flexibility", "solve_fastened",
           "STATUS_LABELS",
           "result_mesh", "plot_status"]

#: Pair status codes of :attr:`FastenedResult.status`, by index.
STATUS_LABELS = ("open", "contact", "fastener")

_EDGES = ("left", "right", "bottom", "top")


@dataclass(frozen=True)
class Plate:
    """A thin isotropic plate ``[0, length] x [0, width]`` (m) of uniform ``thickness`` (m).

    Defaults: 200 x 100 x 2 mm aluminium (``E = 70 GPa``, ``nu = 0.33``).
    """

    length: float = 0.200
    width: float = 0.100
    thickness: float = 0.002
    young: float = 70e9
    poisson: float = 0.33

    @property
    def rigidity(self) -> float:
        """Flexural rigidity ``D = E t^3 / (12 (1 - nu^2))`` (N m)."""
        return self.young * self.thickness ** 3 / (12.0 * (1.0 - self.poisson ** 2))


def plate_flexibility(plate: Plate, points, cells, supports=("left", "right")) -> np.ndarray:
    """Out-of-plane flexibility of points of a Kirchhoff plate (Morley elements, condensed).

    Parameters
    ----------
    plate : Plate
    points : array_like, shape (k, 2)
        Positions (m) of the computational nodes; each must be a vertex of the mesh.
    cells : (int, int)
        Mesh cells along ``x`` and ``y`` (each split into two triangles).
    supports : sequence of {"left", "right", "bottom", "top"}
        Simply supported edges (``w = 0``; rotations free): ``x = 0``, ``x = length``,
        ``y = 0``, ``y = width``.

    Returns
    -------
    ndarray, shape (k, k)
        ``R[i, j]``: deflection (m) of point ``i`` under a unit force (N) at point ``j``.
    """
    from ..compliance.fem import plate as plate_mesh  # raises MissingDependencyError without skfem

    import skfem
    from scipy.spatial import cKDTree
    from skfem.helpers import dd, ddot, eye, trace

    bad = [s for s in supports if s not in _EDGES]
    if bad or not supports:
        raise InvalidInputError(f"supports must be edges among {', '.join(_EDGES)}, got "
                                f"{supports!r}")
    mesh = plate_mesh(plate.length, plate.width, *cells, cell="tri")
    basis = skfem.Basis(mesh, skfem.ElementTriMorley())
    scale = plate.young * plate.thickness ** 3 / (12.0 * (1.0 + plate.poisson))
    ratio = plate.poisson / (1.0 - plate.poisson)

    @skfem.BilinearForm
    def bending(u, v, _):
        curvature = dd(u)
        return scale * ddot(curvature + ratio * eye(trace(curvature), 2), dd(v))

    K = skfem.asm(bending, basis).tocsr()
    held = np.unique(np.concatenate([basis.get_dofs(edge).nodal["u"] for edge in supports]))
    wanted = finite_array(points, "points", 2)
    distance, vertex = cKDTree(mesh.p.T).query(wanted)
    if np.max(distance) > 1e-9 * plate.length:
        raise InvalidInputError(f"point {int(np.argmax(distance))} is not a mesh vertex")
    freedoms = basis.nodal_dofs[0, vertex]
    if np.any(np.isin(freedoms, held)):
        raise InvalidInputError("a point lies on a supported edge: it has no flexibility")
    free = np.setdiff1d(np.arange(basis.N), held)
    from ..compliance.condensation import condense

    return condense(K[free][:, free], np.searchsorted(free, freedoms))


@lru_cache(maxsize=4)
def _cached_flexibility(plate: Plate, points: tuple, cells: tuple, supports: tuple) -> np.ndarray:
    return plate_flexibility(plate, np.array(points), cells, supports)


def _axis(count: int, length: float, low_held: bool, high_held: bool, refine: int):
    """Contact positions along one side (held edges excluded) and the mesh cells along it."""
    intervals = count - 1 + low_held + high_held
    spacing = length / intervals
    return (low_held + np.arange(count)) * spacing, refine * intervals


@dataclass(frozen=True)
class Assembly:
    """Definition of a riveted assembly of two plates; :meth:`build` makes the reduced model.

    Parameters
    ----------
    lower, upper : Plate
        The two parts (same outline).
    grid : (int, int)
        Contact node pairs along ``x`` and ``y``: a regular grid over the plate, supported edges
        excluded (25 x 21 = 525 pairs by default).
    supports : tuple of str
        Jig supports, simply supported edges of both plates (see :func:`plate_flexibility`).
    fasteners : tuple of (int, int), optional
        Grid indices ``(i, j)`` (along ``x``, along ``y``) of the fasteners, in fastening order;
        by default a row along the middle of the width, every fourth column from the third.
    refine : int
        Mesh cells between neighbouring contact nodes.
    """

    lower: Plate = Plate()
    upper: Plate = Plate()
    grid: tuple = (25, 21)
    supports: tuple = ("left", "right")
    fasteners: tuple | None = None
    refine: int = 2

    def fastener_cells(self) -> tuple:
        """The fasteners' grid indices (the default row when none were given)."""
        if self.fasteners is not None:
            return tuple(tuple(int(v) for v in f) for f in self.fasteners)
        nx, ny = self.grid
        return tuple((i, ny // 2) for i in range(2, nx - 2, 4))

    def build(self) -> "RivetingModel":
        """Assemble and condense both plates (seconds for the default grid; cached)."""
        if (self.lower.length, self.lower.width) != (self.upper.length, self.upper.width):
            raise InvalidInputError("lower and upper plates must have the same length and width")
        nx, ny = (int(n) for n in self.grid)
        if nx < 1 or ny < 1 or int(self.refine) < 1:
            raise InvalidInputError(f"grid and refine must be positive, got {self.grid}, "
                                    f"{self.refine}")
        held = set(self.supports)
        xs, cx = _axis(nx, self.lower.length, "left" in held, "right" in held, self.refine)
        ys, cy = _axis(ny, self.lower.width, "bottom" in held, "top" in held, self.refine)
        gx, gy = np.meshgrid(xs, ys)  # pair i + nx j at (xs[i], ys[j])
        points = np.column_stack([gx.ravel(), gy.ravel()])
        key = (tuple(map(tuple, points)), (cx, cy), tuple(self.supports))
        blocks = [_cached_flexibility(plate, *key) for plate in (self.lower, self.upper)]
        fasteners = []
        for i, j in self.fastener_cells():
            if not (0 <= i < nx and 0 <= j < ny):
                raise InvalidInputError(f"fastener ({i}, {j}) is outside the {nx} x {ny} grid")
            fasteners.append(i + nx * j)
        if len(set(fasteners)) != len(fasteners):
            raise InvalidInputError("two fasteners share a contact pair")
        model = ReducedModel(flexibility=scipy.linalg.block_diag(*blocks), dofs_per_node=1,
                             coordinates=np.vstack([points, points]))
        return RivetingModel(self, model, points, np.array(fasteners, dtype=int))


class RivetingModel:
    """The reduced model of an :class:`Assembly`: contact pairs, fasteners, problems.

    Attributes
    ----------
    assembly : Assembly
    model : ReducedModel
        ``2 k`` nodes, one freedom (``w``, m) each: lower plate first.
    points : ndarray, shape (k, 2)
        Position of each contact pair (m).
    fasteners : ndarray of int, shape (f,)
        Pair index of each fastener, in fastening order.
    """

    def __init__(self, assembly: Assembly, model: ReducedModel, points, fasteners):
        self.assembly, self.model = assembly, model
        self.points, self.fasteners = points, fasteners

    @property
    def n_pairs(self) -> int:
        """Number of contact pairs ``k``."""
        return len(self.points)

    @cached_property
    def base_problem(self) -> ContactProblem:
        """The contact problem with zero gaps; its dual is assembled once and shared."""
        k = self.n_pairs
        pairs = np.column_stack([np.arange(k), k + np.arange(k)])
        problem = ContactProblem(self.model, np.zeros(2 * k), [NodePairs(pairs, np.zeros(k))])
        problem.dual()
        return problem

    def problem(self, gaps) -> ContactProblem:
        """The contact problem for an initial gap field ``gaps`` (m, shape (k,))."""
        return self.base_problem.variant(gaps=gaps)

    @property
    def thickness(self) -> float:
        """The thinner plate's thickness (m): the scale of a plausible gap or overlap."""
        return min(self.assembly.lower.thickness, self.assembly.upper.thickness)

    def check_gaps(self, gaps, what: str = "gaps") -> np.ndarray:
        """``gaps`` (m) as a finite array of shape (k,); an overlap (negative gap) deeper than
        the thinner plate is physically absurd and refused.

        Raises
        ------
        InvalidInputError
            Wrong shape, NaN or inf, or an overlap beyond the plate thickness; ``what`` names
            the input in the message.
        """
        gaps = finite_array(gaps, what, 1)
        if gaps.shape != (self.n_pairs,):
            raise InvalidInputError(f"{what} must have {self.n_pairs} values, got {gaps.size}")
        deepest = float(gaps.min())
        if deepest < -self.thickness:
            raise InvalidInputError(
                f"{what}: an overlap of {-deepest * 1e3:.4g} mm is deeper than the "
                f"{self.thickness * 1e3:.4g} mm plates (a negative gap is interference)")
        return gaps

    def fasten(self, gaps, order=None, *, method: str = "lawson-hanson",
               tol: float = 1e-10) -> "FasteningSequence":
        """Install the fasteners one after another on the gap field ``gaps`` (m, shape (k,)).

        Parameters
        ----------
        gaps : array_like, shape (k,)
            Initial gaps (m), negative for interference.
        order : sequence of int, optional
            Positions in :attr:`fasteners` in installation order (default: as listed).
        method, tol
            See :meth:`FastenerClosure.solve`; each step is warm started from the previous one
            (except with ``method="nnls"``).

        Returns
        -------
        FasteningSequence
            One result per fastener installed.
        """
        order = np.arange(len(self.fasteners)) if order is None else np.asarray(order, dtype=int)
        if sorted(order.tolist()) != list(range(len(self.fasteners))):
            raise InvalidInputError(f"order must be a permutation of 0..{len(self.fasteners) - 1}")
        problem = self.problem(self.check_gaps(gaps))
        steps, forces = [], None
        for count in range(1, len(order) + 1):
            step = solve_fastened(problem, self.fasteners[order[:count]], method=method,
                                  forces0=forces, tol=tol)
            forces = step.multipliers
            steps.append(step)
        return FasteningSequence(steps, order)


@dataclass
class FastenedResult:
    """The state after some fasteners are installed.

    Attributes
    ----------
    contact : ContactResult
        Certified result of the contact problem with the fastener tensions as loads: ``gaps``
        (final, m), ``forces`` (contact compression per pair, N), ``x`` (deflections, m).
    fasteners : ndarray of int, shape (f,)
        Pairs closed by a fastener.
    fastener_forces : ndarray, shape (f,)
        Tension of each fastener (N, >= 0).
    closure : float
        Largest ``|gap|`` at the fasteners (m): zero up to round-off when the closure holds.
    success : bool
        Converged, certificate passed and closure within the certificate's tolerance.
    multipliers : ndarray, shape (k,)
        The dual solution: contact forces, minus the tension at fasteners (warm starts).
    """

    contact: ContactResult
    fasteners: np.ndarray
    fastener_forces: np.ndarray
    closure: float
    success: bool
    multipliers: np.ndarray

    @property
    def status(self) -> np.ndarray:
        """Status code per pair (index into :data:`STATUS_LABELS`): open, contact, fastener."""
        codes = self.contact.closed.astype(int)
        codes[self.fasteners] = 2
        return codes


@dataclass
class FasteningSequence:
    """The states after each fastener of a sequence; ``steps[-1]`` is the assembled state."""

    steps: list
    order: np.ndarray

    @property
    def final(self) -> FastenedResult:
        """The state with every fastener installed."""
        return self.steps[-1]

    @property
    def success(self) -> bool:
        """True when every step succeeded."""
        return all(step.success for step in self.steps)


class FastenerClosure:
    r"""The dual of a contact problem with some rows closed by fasteners, reduced once.

    The fastener multipliers ``lambda_f`` are free in sign, so they are eliminated: with
    ``W`` split into fastener (``f``) and contact (``c``) blocks and ``q = A R P - Delta``,

    .. math::

        \lambda_f = W_{ff}^{-1} (q_f - W_{fc} \lambda_c), \qquad
        \min_{\lambda_c \ge 0} \tfrac12 \lambda_c^T S \lambda_c
            - \lambda_c^T (q_c - W_{cf} W_{ff}^{-1} q_f),
        \quad S = W_{cc} - W_{cf} W_{ff}^{-1} W_{fc},

    a frictionless contact dual whose Delassus operator ``S`` (a Schur complement, positive
    definite) is that of the assembly with the fasteners closed. ``S`` depends on the fasteners
    only, so a variation study reduces once and solves every sample on it.

    Parameters
    ----------
    problem : ContactProblem
        Node pairs; ``fasteners`` index its constraint rows.
    fasteners : array_like of int, shape (f,)
        Rows whose gap the fasteners close to zero.
    """

    def __init__(self, problem: ContactProblem, fasteners):
        rows = np.asarray(fasteners, dtype=int).reshape(-1)
        m = problem.n_constraints
        if rows.size == 0 or rows.min() < 0 or rows.max() >= m or np.unique(rows).size != rows.size:
            raise InvalidInputError(f"fasteners must be distinct rows in 0..{m - 1}, at least one")
        self.problem, self.fasteners = problem, rows
        self.contacts = np.setdiff1d(np.arange(m), rows)
        W = problem.dual().W
        self._factor = scipy.linalg.cho_factor(W[np.ix_(rows, rows)])
        self._coupling = W[np.ix_(rows, self.contacts)]
        self._eliminated = scipy.linalg.cho_solve(self._factor, self._coupling)
        self.schur = W[np.ix_(self.contacts, self.contacts)] - self._coupling.T @ self._eliminated
        self._schur_factor = None

    def _nnls(self, q):
        """``(forces, converged, message, iterations, factorizations)`` by NNLS."""
        from scipy.optimize import nnls

        if self._schur_factor is None:
            self._schur_factor = np.linalg.cholesky(self.schur)
        lower = self._schur_factor
        target = scipy.linalg.solve_triangular(lower, q, lower=True, check_finite=False)
        try:
            forces, _ = nnls(lower.T, target)
        except RuntimeError as exc:  # iteration limit
            return np.zeros(len(q)), False, f"nnls: {exc}", 0, 1
        return forces, True, "nnls converged (iterations not reported)", 0, 1

    def solve(self, gaps=None, *, method: str = "lawson-hanson", forces0=None,
              tol: float = 1e-10) -> "FastenedResult":
        """Solve for the initial ``gaps`` (m, shape (m,); default: the problem's).

        Parameters
        ----------
        gaps : array_like, shape (m,), optional
        method : {"lawson-hanson", "active-set", "nnls"}
            ``"lawson-hanson"`` (default): Lawson and Hanson's active-set method on ``S``
            directly, adding one contact at a time, warm started from the support of
            ``forces0``. ``"active-set"``: the project's primal-dual box-QP solver
            (:func:`~contactqp.methods.solve_box_qp`) on ``S``, warm started from ``forces0``.
            ``"nnls"``: :func:`scipy.optimize.nnls` (Lawson and Hanson too, cold) on
            ``min ||L^T lambda_c - L^-1 q||`` with ``S = L L^T``: an independent route.
        forces0 : array_like, shape (m,), optional
            Warm start, e.g. :attr:`FastenedResult.multipliers`.
        tol : float
            Relative tolerance of ``"lawson-hanson"`` (on ``q - S lambda``, relative to
            ``max|q|``) and of ``"active-set"`` (its natural residual).
        """
        start = time.perf_counter()
        problem = self.problem if gaps is None else self.problem.variant(gaps=gaps)
        dual = problem.dual()
        rows, contacts = self.fasteners, self.contacts
        q_rows = dual.b[rows]
        q = dual.b[contacts] - self._eliminated.T @ q_rows
        x0 = None if forces0 is None else np.maximum(np.asarray(forces0, float)[contacts], 0)
        if method == "lawson-hanson":
            forces, converged, nit, factorizations = solve_nonnegative_qp(
                self.schur, q, x0, tol, max_iter=3 * len(q))
            message = f"Lawson-Hanson {'converged' if converged else 'did not converge'}"
        elif method == "nnls":
            forces, converged, message, nit, factorizations = self._nnls(q)
        elif method == "active-set":
            solution = solve_box_qp(self.schur, -q, lower=0.0, x0=x0, tol=tol, check_finite=False)
            forces, converged, message = solution.x, solution.converged, solution.message
            nit, factorizations = solution.iterations, solution.factorizations
        else:
            raise InvalidInputError(f"method must be 'lawson-hanson', 'active-set' or 'nnls', "
                                    f"got {method!r}")
        multipliers = np.empty(problem.n_constraints)
        multipliers[contacts] = forces
        multipliers[rows] = scipy.linalg.cho_solve(self._factor, q_rows - self._coupling @ forces)
        tension = np.maximum(-multipliers[rows], 0.0)
        compression = np.maximum(multipliers, 0.0)
        A = problem.constraints.matrix
        pulled = problem.variant(loads=problem.loads + A[rows].T @ tension)
        contact = pulled.make_result(
            dual.displacements(multipliers), compression, solver=f"{method} (fastened)",
            converged=converged, message=message, nit=nit, wall_time=time.perf_counter() - start,
            info={"factorizations": factorizations, "method": method})
        closure = float(np.max(np.abs(contact.gaps[rows])))
        scale = max(float(np.max(np.abs(problem.constraints.gaps))),
                    float(np.max(np.abs(contact.x))), np.finfo(float).tiny)
        return FastenedResult(contact, rows, tension, closure,
                              bool(contact.success and closure <= contact.certificate.tol * scale),
                              multipliers)


def solve_fastened(problem: ContactProblem, fasteners, *, method: str = "lawson-hanson",
                   forces0=None, tol: float = 1e-10) -> FastenedResult:
    """Solve a frictionless contact problem whose ``fasteners`` rows are closed (bilateral).

    One call of :class:`FastenerClosure`; see there for the parameters.
    """
    return FastenerClosure(problem, fasteners).solve(method=method, forces0=forces0, tol=tol)


class FasteningCase(GapVariation):
    """A riveted assembly, every fastener installed: a case of :func:`~contactqp.studies.batch.run_batch`.

    Each sample is solved by :meth:`FastenerClosure.solve` (``method``, ``tol``) with all the
    fasteners at once (without friction the final state does not depend on the order), warm
    started from the previous sample (except with ``method="nnls"``). Records add ``fastener_force``
    (tension per fastener, N) to those of :class:`~contactqp.studies.batch.GapVariation`.
    """

    def __init__(self, model: RivetingModel, method: str = "lawson-hanson", tol: float = 1e-10):
        super().__init__(model.base_problem, method=method, tol=tol)
        self.fasteners = model.fasteners
        self.closure = FastenerClosure(model.base_problem, model.fasteners)

    def fields(self) -> dict:
        return {**super().fields(), "fastener_force": ((len(self.fasteners),), "f8")}

    def solve_sample(self, gaps, warm):
        state = self.closure.solve(gaps, forces0=warm, **self.options)
        record = self._record(state.contact)
        record["fastener_force"] = state.fastener_forces
        record["success"] = state.success
        return record, state.multipliers

    def warm_start(self, record) -> np.ndarray:
        warm = np.array(record["force"], dtype=float)
        warm[self.fasteners] -= record["fastener_force"]
        return warm

    def describe(self) -> dict:
        return {**super().describe(), "fasteners": self.fasteners.tolist()}


def result_mesh(model: RivetingModel, state: FastenedResult, initial_gaps) -> PointMesh:
    """Both contact grids as quadrilateral surfaces with the fastened state, for
    :func:`~contactqp.io.export.write_vtu` (``write_vtu(path, *result_mesh(...))``).

    The lower grid at ``z = 0``, the upper one at ``z = thickness`` of the lower plate (for
    display). Point data: ``displacement`` (``w`` along ``z``, m), ``contact_force`` (N, on the
    node, along ``z``), ``initial_gap`` and ``gap`` (m), ``status`` (codes of
    :data:`STATUS_LABELS`), ``fastener_force`` (N, zero away from fasteners).
    """
    nx, ny = model.assembly.grid
    k = model.n_pairs
    ids = np.arange(k).reshape(ny, nx)
    quads = np.column_stack([ids[:-1, :-1].ravel(), ids[:-1, 1:].ravel(), ids[1:, 1:].ravel(),
                             ids[1:, :-1].ravel()])
    z = model.assembly.lower.thickness
    points = np.vstack([np.column_stack([model.points, np.zeros(k)]),
                        np.column_stack([model.points, np.full(k, z)])])
    w = state.contact.x
    tension = np.zeros(k)
    tension[state.fasteners] = state.fastener_forces
    force = state.contact.forces

    def both(values):
        return np.concatenate([values, values])

    data = {
        "displacement": np.column_stack([np.zeros((2 * k, 2)), w]),
        "contact_force": np.column_stack([np.zeros((2 * k, 2)), np.concatenate([-force, force])]),
        "initial_gap": both(np.asarray(initial_gaps, dtype=float)),
        "gap": both(state.contact.gaps), "status": both(state.status),
        "fastener_force": both(tension),
    }
    return PointMesh(points, [("quad", np.vstack([quads, quads + k]))], data)


def plot_status(model: RivetingModel, state: FastenedResult, initial_gaps, path) -> Path:
    """Maps of the initial and residual gaps (mm) and of the pair status, the fasteners marked
    (drawn by :func:`contactqp.io.plot.plot_point_maps`)."""
    from ..io.plot import plot_point_maps

    panels = [(np.asarray(initial_gaps) * 1e3, "initial gap (mm)", "viridis"),
              (state.contact.gaps * 1e3, "residual gap (mm)", "viridis"),
              (state.status, "status: " + " / ".join(STATUS_LABELS), "coolwarm")]
    return plot_point_maps(model.points, panels, path, marked=model.points[state.fasteners],
                           marked_label="fasteners")

"""The rod over an obstacle, the method's second application.

A straight rod along ``x`` from 0 to ``length``, clamped at its right end (``x = length``: both
displacements and the rotation held), free at its left end, lies above a rigid straight obstacle.
The gap measured along ``y`` grows linearly from ``gap_free`` under the free end to ``gap_clamped``
under the clamp (1 mm and 5 mm by default), so a force pushing the rod down (``fy < 0``) makes its
free end touch first. The obstacle being a straight line, the non-penetration of a point is exact
in the small displacements: ``n . u <= gap cos(theta)``, ``n`` the obstacle's unit normal pointing
down and ``theta`` its slope angle. The normal has an axial component, so contact forces compress
the rod and ``ux`` is small but not zero.

Published data: length 40 mm, E = 1e12 Pa, circular cross-section A = 0.2 mm^2 (I = A^2 / (4 pi)),
8 computational nodes with ``x`` and ``y`` freedoms. Poisson's ratio (0.3) does not enter
Euler-Bernoulli theory (no shear deformation) and is not a parameter.

Two solutions are compared:

- reduced: the flexibility ``R`` of the computational nodes by static condensation of the
  frame's stiffness, contacts at the computational nodes, the project's own dual active-set solver;
- reference: the primal QP ``min 1/2 u^T K u - f^T u`` on every freedom of the finite-element mesh
  with contacts at mesh nodes, solved by the interior-point solver Clarabel (through qpsolvers) on
  the sparse ``K`` and polished by one exact solve of the KKT system on Clarabel's active set.
  With contacts at the computational nodes only the reduced model is exact; with contacts at every
  mesh node the deviation measures what the reduced model misses between its nodes.

Why the default loads keep the contact at the free end: on a straight obstacle, a rod loaded by
forces that all push towards it touches at one place only (between two contact points its bending
moment would be concave and the rod would cross the obstacle), and an interior contact point is a
point of tangency whose position moves continuously with the loads, so it generally falls between
computational nodes. The free end is the only place where a contact is a node for a whole range of
loads. The default loads close the free end and leave every other node open;
``max_penetration`` of a comparison reports any crossing between nodes that would invalidate this.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike

from ..compliance.beam import Frame2D
from ..core.contact import GapObstacle
from ..core.model import ReducedModel
from ..core.problem import ContactProblem
from ..core.result import ContactResult
from ..core.status import ContactStatus
from ..errors import InvalidInputError, ReferenceSolveError
from ..io import export
from ..methods import solve
from ..optional import require

__all__ = [
    "Rod",
    "RodLoad",
    "RodLoadCase",
    "FullSolution",
    "CaseComparison",
    "DEFAULT_CASES",
    "ReferenceSolveError",
    "solve_reduced",
    "solve_full",
    "compare",
    "deviations",
    "as_record",
    "result_mesh",
    "plot_rod",
    "ABSOLUTE_BELOW",
    "MAX_ELEMENTS",
]

#: Reference values below this fraction of a case's largest displacement get absolute deviations.
ABSOLUTE_BELOW = 1e-6

#: Finest mesh offered. The frame's bending stiffness has a condition number growing like the
#: fourth power of the element count: at 1600 elements round-off reaches 1e-4 of the answer
#: (the same-node deviation, zero in exact arithmetic, is 6e-3 %; 7e-8 % at 80), and from about
#: 2400 the stiffness is singular to working precision (the condensation refuses it).
MAX_ELEMENTS = 1600


@dataclass(frozen=True)
class RodLoad:
    """A force on the rod at ``x`` (m, a computational node): ``fx``, ``fy`` in newtons."""

    x: float
    fx: float
    fy: float


@dataclass(frozen=True)
class RodLoadCase:
    """A named set of forces applied together."""

    name: str
    loads: tuple[RodLoad, ...]


#: One force at 10 mm, and three forces growing towards the clamp; both close the free end only.
DEFAULT_CASES = (
    RodLoadCase("one force", (RodLoad(0.010, 0.0, -1.0),)),
    RodLoadCase(
        "several forces",
        (RodLoad(0.010, 0.0, -0.3), RodLoad(0.020, 0.0, -0.6), RodLoad(0.030, 0.0, -0.9)),
    ),
)


@dataclass(frozen=True)
class Rod:
    """The rod, its obstacle and its computational nodes (SI units).

    Parameters
    ----------
    length : float
        Rod length (m).
    young : float
        Young's modulus (Pa).
    area : float
        Cross-section area (m^2); the second moment is that of a circle, ``A^2 / (4 pi)``.
    gap_free, gap_clamped : float
        Gap along ``y`` between rod and obstacle under the free (left) end and under the clamped
        (right) end (m); linear in between.
    nodes : tuple of float
        ``x`` of the computational nodes (m); each must be a mesh node and not the clamp.
    n_elements : int
        Frame elements of the finite-element mesh (equal lengths), at most
        :data:`MAX_ELEMENTS`.
    """

    length: float = 0.04
    young: float = 1e12
    area: float = 0.2e-6
    gap_free: float = 1e-3
    gap_clamped: float = 5e-3
    nodes: tuple = tuple(0.005 * k for k in range(8))
    n_elements: int = 80

    def __post_init__(self):
        for name in ("length", "young", "area", "gap_free", "gap_clamped"):
            value = getattr(self, name)
            if (
                isinstance(value, bool)
                or not isinstance(value, numbers.Real)
                or not math.isfinite(value)
                or value <= 0
            ):
                raise InvalidInputError(f"{name} must be finite and > 0, got {value}")
        self.node_indices  # noqa: B018  (validates nodes and n_elements)

    @property
    def inertia(self) -> float:
        """Second moment of area of the circular section, ``A^2 / (4 pi)`` (m^4)."""
        return self.area**2 / (4 * np.pi)

    @cached_property
    def frame(self) -> Frame2D:
        """The finite-element model: ``n_elements`` frame elements, right end clamped."""
        return Frame2D.straight(
            self.length, self.n_elements, self.young, self.area, self.inertia, fixed={-1: "xyr"}
        )

    @cached_property
    def node_indices(self) -> np.ndarray:
        """Mesh indices of the computational nodes."""
        if (
            isinstance(self.n_elements, bool)
            or not isinstance(self.n_elements, numbers.Real)
            or int(self.n_elements) != self.n_elements
            or self.n_elements < 1
        ):
            raise InvalidInputError(
                f"n_elements must be a whole number >= 1, got {self.n_elements!r}"
            )
        if self.n_elements > MAX_ELEMENTS:
            raise InvalidInputError(
                f"n_elements must be at most {MAX_ELEMENTS}, got {self.n_elements}: the frame's "
                f"stiffness is ill-conditioned like n_elements^4 (round-off reaches 1e-4 of the "
                f"answer at {MAX_ELEMENTS}, and it is singular to working precision from about "
                f"2400)"
            )
        try:
            x = np.asarray(self.nodes, dtype=float)
        except (TypeError, ValueError):
            x = np.array([np.nan])
        if x.ndim != 1 or x.size == 0 or not np.all(np.isfinite(x)):
            raise InvalidInputError(f"nodes must be a non-empty list of x values, got {self.nodes}")
        step = self.length / self.n_elements
        index = np.rint(x / step).astype(int)
        off = np.abs(index * step - x) > 1e-9 * self.length
        if np.any(off) or np.any(index < 0) or np.any(index >= self.n_elements):
            bad = x[off | (index < 0) | (index >= self.n_elements)][0]
            raise InvalidInputError(
                f"computational node x = {bad:g} m is not a free mesh node of the "
                f"{self.n_elements} elements on [0, {self.length:g}) m"
            )
        if np.unique(index).size != index.size:
            raise InvalidInputError("nodes contains repeated positions")
        return index

    @property
    def slope(self) -> float:
        """Slope of the obstacle's gap along ``x``, ``(gap_clamped - gap_free) / length``."""
        return (self.gap_clamped - self.gap_free) / self.length

    @property
    def normal(self) -> np.ndarray:
        """Unit normal of the obstacle pointing from the rod into it, shape (2,)."""
        return np.array([-self.slope, -1.0]) / np.hypot(1.0, self.slope)

    def gap(self, x: ArrayLike) -> np.ndarray:
        """Initial gap along ``y`` under the points ``x`` (m)."""
        return self.gap_free + self.slope * np.asarray(x, dtype=float)

    def normal_gap(self, x: ArrayLike) -> np.ndarray:
        """Initial distance from the points ``x`` to the obstacle, along :attr:`normal` (m)."""
        return self.gap(x) / np.hypot(1.0, self.slope)

    def mesh_loads(self, case: RodLoadCase) -> np.ndarray:
        """Load vector of the free freedoms of :attr:`frame`; forces sit on computational nodes."""
        rows = []
        for load in case.loads:
            hit = np.flatnonzero(np.isclose(self.nodes, load.x, rtol=0, atol=1e-9 * self.length))
            if hit.size == 0:
                raise InvalidInputError(
                    f"load case {case.name!r}: force at x = {load.x:g} m is not on a computational "
                    f"node ({', '.join(f'{x:g}' for x in self.nodes)})"
                )
            rows.append((int(self.node_indices[hit[0]]), load.fx, load.fy))
        return self.frame.load_vector(rows)

    @cached_property
    def reduced_model(self) -> ReducedModel:
        """Reduced model of the computational nodes (``ux``, ``uy``) by static condensation."""
        flexibility = self.frame.compliance(self.node_indices, "xy")
        coordinates = self.frame.coordinates[self.node_indices]
        return ReducedModel(flexibility=flexibility, dofs_per_node=2, coordinates=coordinates)

    @property
    def mesh_contact_nodes(self) -> np.ndarray:
        """Every mesh node but the clamped one."""
        return np.arange(self.n_elements)


def solve_reduced(rod: Rod, case: RodLoadCase, solver: str = "active-set") -> ContactResult:
    """Contact on the reduced model, certified.

    The result's ``seconds`` cover the assembly of the contact problem and its solve; the
    condensation (done once per rod, :attr:`Rod.reduced_model`) is not included.
    """
    model = rod.reduced_model
    loads = rod.mesh_loads(case)
    frame = rod.frame
    P = np.array([loads[frame.index(int(k), c)] for k in rod.node_indices for c in ("ux", "uy")])
    start = time.perf_counter()
    x = rod.frame.coordinates[rod.node_indices, 0]
    problem = ContactProblem(
        model, P, [GapObstacle(range(model.n_nodes), rod.normal_gap(x), rod.normal)]
    )
    result = solve(problem, solver)
    return dataclasses.replace(result, seconds=time.perf_counter() - start)


@dataclass(frozen=True)
class FullSolution:
    """A finite-element contact solution on the whole mesh.

    Attributes
    ----------
    displacements : ndarray, shape (n_mesh_nodes, 3)
        ``ux``, ``uy`` (m) and ``rz`` (rad) of every mesh node.
    contact_nodes : ndarray of int, shape (k,)
        Mesh nodes that were allowed to touch.
    forces : ndarray, shape (k,)
        Contact force of each of them along the obstacle's normal (N, >= 0).
    seconds : float
        Time of the contact solve (constraints, Clarabel, polish).
    """

    displacements: np.ndarray
    contact_nodes: np.ndarray
    forces: np.ndarray
    seconds: float


def solve_full(rod: Rod, case: RodLoadCase, contact: str = "mesh") -> FullSolution:
    """Reference contact solution on the finite-element mesh, independent of the reduced model.

    Parameters
    ----------
    rod : Rod
    case : RodLoadCase
    contact : {"mesh", "nodes"}
        Contacts at every mesh node (but the clamp), or at the computational nodes only.

    Notes
    -----
    The QP is scaled by the stiffness diagonal (``u = l D v``, ``D = diag(K)^{-1/2}``, ``l`` the
    largest gap) because the rod's freedoms differ by ten orders of magnitude in stiffness and an
    interior-point method's tolerances are absolute. The interior-point answer is then polished:
    its active set starts Lawson and Hanson's exact active-set method on the contacts' dual
    (``K`` factored once by sparse LU), which corrects it where the interior-point method
    stopped short (fine meshes), and the result is verified (forces >= 0, no penetration) to
    1e-9.

    Raises
    ------
    ReferenceSolveError
        Clarabel fails or the polished solution violates a contact condition.
    """
    qpsolvers = require("qpsolvers", "the reference solve", "qp")
    require("clarabel", "the reference solve", "qp")
    from ..methods.qp import backend_options

    if contact not in ("mesh", "nodes"):
        raise InvalidInputError(f"contact must be 'mesh' or 'nodes', got {contact!r}")
    frame = rod.frame
    K = frame.stiffness()
    d = 1.0 / np.sqrt(K.diagonal())
    Ks = (sp.diags(d) @ K @ sp.diags(d)).tocsc()
    f = rod.mesh_loads(case)
    nodes = rod.mesh_contact_nodes if contact == "mesh" else rod.node_indices
    start = time.perf_counter()
    columns = np.array([[frame.index(int(k), "ux"), frame.index(int(k), "uy")] for k in nodes])
    n = d.size
    G = sp.csr_matrix(
        (np.tile(rod.normal, len(nodes)), columns.ravel(), np.arange(0, 2 * len(nodes) + 1, 2)),
        shape=(len(nodes), n),
    )
    h = rod.normal_gap(frame.coordinates[nodes, 0])
    scale = float(h.max())
    Gs, fs, hs = (G @ sp.diags(d)).tocsc(), d * f / scale, h / scale
    qp = qpsolvers.Problem(Ks, -fs, Gs, hs)
    with warnings.catch_warnings():  # an inexact status is corrected by the polish, verified
        warnings.simplefilter("ignore", UserWarning)
        answer = qpsolvers.solve_problem(qp, solver="clarabel", **backend_options("clarabel"))
    if answer.x is None or answer.z is None:
        raise ReferenceSolveError(f"load case {case.name!r}: Clarabel found no solution")
    # contact forces (z * scale) above 1e-8 of the largest load are active; no load, no contact
    largest = np.max(np.abs(f), initial=0.0)
    active = (
        np.asarray(answer.z) * scale > 1e-8 * largest
        if largest > 0
        else np.zeros(len(nodes), dtype=bool)
    )
    v, z = _active_set_polish(Ks, Gs, fs, hs, active, case.name)
    forces = z * scale
    penetration = np.max(Gs @ v - hs, initial=0.0)
    if penetration > 1e-9 or np.min(z, initial=0.0) < -1e-9 * np.max(np.abs(z), initial=0.0):
        raise ReferenceSolveError(
            f"load case {case.name!r}: the polished reference violates contact (penetration "
            f"{penetration * scale:.3g} m, least force {np.min(z, initial=0.0) * scale:.3g} N)"
        )
    seconds = time.perf_counter() - start
    full = np.zeros(3 * frame.n_nodes)
    full[frame.free] = scale * d * v
    return FullSolution(full.reshape(-1, 3), np.asarray(nodes), forces, seconds)


#: Columns of ``K^-1 G^T`` computed at once by the reference's polish.
_COLUMN_BLOCK = 256


def _active_set_polish(K, G, f, h, active, name):
    """The reference's exact solution, from the interior-point answer's active set.

    On the contacts' dual, ``min 1/2 z^T W z - z^T (G K^-1 f - h), z >= 0`` with
    ``W = G K^-1 G^T`` (from one sparse LU of ``K``), Lawson and Hanson's active-set method
    (finite, monotone: it cannot cycle) starts from the interior-point answer's active set
    ``active`` (bool per contact). On fine meshes the interior-point method stops short
    (``AlmostSolved``, ``InsufficientProgress``: the frame's stiffness has a condition number
    growing like the fourth power of the element count) and that set may be empty or wrong; a
    single KKT solve on it then violated contact. The data are scaled (unit stiffness diagonal,
    gaps of order one).

    Returns
    -------
    v, z : ndarray
        Scaled displacements and contact forces.
    """
    from ..methods.lawson_hanson import solve_nonnegative_qp

    try:
        lu = spla.splu(K.tocsc())
    except RuntimeError as exc:  # SuperLU: exactly singular
        raise ReferenceSolveError(
            f"load case {name!r}: the mesh's stiffness is singular ({exc})"
        ) from None
    Gt = G.T.tocsc()
    influence = np.empty(Gt.shape)
    for start in range(0, Gt.shape[1], _COLUMN_BLOCK):
        influence[:, start : start + _COLUMN_BLOCK] = lu.solve(
            Gt[:, start : start + _COLUMN_BLOCK].toarray()
        )
    W = np.asarray(G @ influence)
    free = lu.solve(f)
    solution = solve_nonnegative_qp(0.5 * (W + W.T), G @ free - h, x0=active.astype(float))
    z = solution.x
    if not solution.converged:
        raise ReferenceSolveError(
            f"load case {name!r}: the reference's active-set polish did not converge"
        )
    return free - influence @ z, z


def deviations(
    values: ArrayLike, reference: ArrayLike, floor: float
) -> tuple[np.ndarray, np.ndarray]:
    """Relative deviations in percent, or absolute ones (same unit) where ``|reference| <= floor``.

    Returns
    -------
    eps : ndarray
        ``100 |values - reference| / |reference|``, or ``|values - reference|`` where absolute.
    absolute : ndarray of bool
        Where the deviation is absolute.
    """
    values, reference = np.asarray(values, dtype=float), np.asarray(reference, dtype=float)
    difference = np.abs(values - reference)
    absolute = np.abs(reference) <= floor
    eps = np.where(
        absolute, difference, 100.0 * difference / np.where(absolute, 1.0, np.abs(reference))
    )
    return eps, absolute


@dataclass
class CaseComparison:
    """Reduced solution of one load case against its two finite-element references.

    Attributes
    ----------
    case : RodLoadCase
    reduced : ContactResult
        On the computational nodes; ``x`` holds ``(ux, uy)`` node by node.
    same_nodes : FullSolution
        Reference with contacts at the computational nodes only (variant a).
    reference : FullSolution
        Reference with contacts at every mesh node (variant b), the one the table compares with.
    eps_x, eps_y : ndarray, shape (n_nodes,)
        Deviations from ``reference`` in percent, or in metres where ``absolute_x`` /
        ``absolute_y``.
    absolute_x, absolute_y : ndarray of bool
        Reference values below ``ABSOLUTE_BELOW`` times the case's largest displacement.
    max_eps : float
        Largest relative deviation (percent) from ``reference``.
    max_eps_same_nodes : float
        Largest relative deviation (percent) from ``same_nodes``.
    t_reduced, t_full : float
        Seconds of the reduced solve and of the full-mesh contact solve.
    max_penetration : float
        Largest crossing of the obstacle by the rod between computational nodes (m), when the
        reduced contact forces are applied to the full mesh.
    recovered : ndarray, shape (n_mesh_nodes, 3)
        That full-mesh displacement of the reduced solution.
    """

    case: RodLoadCase
    reduced: ContactResult
    same_nodes: FullSolution
    reference: FullSolution
    eps_x: np.ndarray
    eps_y: np.ndarray
    absolute_x: np.ndarray
    absolute_y: np.ndarray
    max_eps: float
    max_eps_same_nodes: float
    t_reduced: float
    t_full: float
    max_penetration: float
    recovered: np.ndarray = field(repr=False)


def _node_deviations(U, reference):
    """``deviations`` of ``ux`` and ``uy`` (shape (n, 2) each) and the largest relative one."""
    floor = ABSOLUTE_BELOW * np.max(np.abs(reference))
    eps, absolute = deviations(U, reference, floor)
    return eps, absolute, float(np.max(eps[~absolute], initial=0.0))


def _compare_case(rod: Rod, case: RodLoadCase, solver: str, repeat: int) -> CaseComparison:
    runs = [solve_reduced(rod, case, solver) for _ in range(repeat)]
    reduced, t_reduced = runs[0], min(run.seconds for run in runs)
    same_nodes = solve_full(rod, case, contact="nodes")
    references = [solve_full(rod, case, contact="mesh") for _ in range(repeat)]
    reference = references[0]
    U = reduced.displacements.reshape(-1, 2)
    eps, absolute, max_eps = _node_deviations(U, reference.displacements[rod.node_indices, :2])
    max_eps_same_nodes = _node_deviations(U, same_nodes.displacements[rod.node_indices, :2])[2]
    frame = rod.frame
    contact = np.zeros(frame.free.size)
    for k, force in zip(rod.node_indices, reduced.forces, strict=True):
        for component, n in zip(("ux", "uy"), rod.normal, strict=True):
            contact[frame.index(int(k), component)] -= force * n
    recovered = frame.displacements(rod.mesh_loads(case) + contact)
    mesh = rod.mesh_contact_nodes
    crossing = recovered[mesh, :2] @ rod.normal - rod.normal_gap(frame.coordinates[mesh, 0])
    return CaseComparison(
        case=case,
        reduced=reduced,
        same_nodes=same_nodes,
        reference=reference,
        eps_x=eps[:, 0],
        eps_y=eps[:, 1],
        absolute_x=absolute[:, 0],
        absolute_y=absolute[:, 1],
        max_eps=max_eps,
        max_eps_same_nodes=max_eps_same_nodes,
        t_reduced=t_reduced,
        t_full=min(r.seconds for r in references),
        max_penetration=float(max(np.max(crossing), 0.0)),
        recovered=recovered,
    )


def compare(
    rod: Rod | None = None,
    cases: Sequence[RodLoadCase] = DEFAULT_CASES,
    solver: str = "active-set",
    repeat: int = 3,
) -> list[CaseComparison]:
    """The method's table: reduced solutions against full finite-element contact solutions.

    Parameters
    ----------
    rod : Rod, optional
        The published rod by default.
    cases : sequence of RodLoadCase
    solver : str
        Solver of the reduced problem (see :func:`contactqp.solve`).
    repeat : int
        Each timed solve runs this many times; the times reported are the shortest.

    Returns
    -------
    list of CaseComparison
    """
    rod = Rod() if rod is None else rod
    if int(repeat) != repeat or repeat < 1:
        raise InvalidInputError(f"repeat must be a whole number >= 1, got {repeat}")
    return [_compare_case(rod, case, solver, int(repeat)) for case in cases]


def as_record(rod: Rod, comparisons: Sequence[CaseComparison]) -> dict:
    """The comparison as plain JSON-ready data, in SI units (m, N, s).

    ``gap`` is the initial gap along ``y``; ``eps_x`` and ``eps_y`` are percentages, except where
    ``eps_x_absolute`` / ``eps_y_absolute`` say they are absolute deviations in metres.
    """
    x = rod.frame.coordinates[rod.node_indices, 0]
    cases = []
    for c in comparisons:
        U = c.reduced.displacements.reshape(-1, 2)
        ref = c.reference.displacements[rod.node_indices, :2]
        nodes = [
            {
                "x": float(x[i]),
                "gap": float(rod.gap(x[i])),
                "ux": float(U[i, 0]),
                "uy": float(U[i, 1]),
                "ux_ref": float(ref[i, 0]),
                "uy_ref": float(ref[i, 1]),
                "eps_x": float(c.eps_x[i]),
                "eps_y": float(c.eps_y[i]),
                "eps_x_absolute": bool(c.absolute_x[i]),
                "eps_y_absolute": bool(c.absolute_y[i]),
                "force": float(c.reduced.forces[i]),
                "closed": bool(c.reduced.contact_status[i] == ContactStatus.CLOSED),
            }
            for i in range(len(x))
        ]
        touching = c.reference.forces > 0
        cases.append(
            {
                "name": c.case.name,
                "loads": [{"x": load.x, "fx": load.fx, "fy": load.fy} for load in c.case.loads],
                "nodes": nodes,
                "max_eps": c.max_eps,
                "max_eps_same_nodes": c.max_eps_same_nodes,
                "t_reduced": c.t_reduced,
                "t_full": c.t_full,
                "max_penetration": c.max_penetration,
                "reference_contacts": [
                    {"x": float(rod.frame.coordinates[k, 0]), "force": float(f)}
                    for k, f in zip(
                        c.reference.contact_nodes[touching],
                        c.reference.forces[touching],
                        strict=True,
                    )
                ],
                "success": c.reduced.success,
                "status": c.reduced.status,
                "message": c.reduced.message,
            }
        )
    return {
        "clamped_end": "right",
        "rod": {
            "length": rod.length,
            "young": rod.young,
            "area": rod.area,
            "inertia": rod.inertia,
            "gap_free": rod.gap_free,
            "gap_clamped": rod.gap_clamped,
            "n_elements": rod.n_elements,
        },
        "cases": cases,
    }


def result_mesh(rod: Rod, comparisons: Sequence[CaseComparison]) -> export.PointMesh:
    """The mesh and every case's solutions, for :func:`~contactqp.io.export.write_vtu`
    (``write_vtu(path, *result_mesh(rod, comparisons))``).

    Line cells, points at the mesh nodes (``z = 0``). Point data: ``gap`` (initial, along ``y``,
    m) and, per case (name with spaces as underscores), ``<case>_displacement`` (reference, m),
    ``<case>_displacement_reduced`` (the reduced contact forces applied to the full mesh, m),
    ``<case>_contact_force`` and ``<case>_contact_force_reduced`` (force on the rod, N).
    """
    frame = rod.frame
    n = frame.n_nodes
    data = {"gap": rod.gap(frame.coordinates[:, 0])}

    def vectors(nodes, forces):
        field3 = np.zeros((n, 3))
        field3[nodes, :2] = -np.outer(forces, rod.normal)
        return field3

    for c in comparisons:
        slug = c.case.name.replace(" ", "_")
        data[f"{slug}_displacement"] = np.column_stack(
            [c.reference.displacements[:, :2], np.zeros(n)]
        )
        data[f"{slug}_displacement_reduced"] = np.column_stack([c.recovered[:, :2], np.zeros(n)])
        data[f"{slug}_contact_force"] = vectors(c.reference.contact_nodes, c.reference.forces)
        data[f"{slug}_contact_force_reduced"] = vectors(rod.node_indices, c.reduced.forces)
    return export.PointMesh(frame.coordinates, [("line", frame.elements)], data)


def plot_rod(rod: Rod, comparisons: Sequence[CaseComparison], path: str | os.PathLike[str]) -> Path:
    """The rod deformed over its obstacle, one panel per load case (drawn by
    :func:`contactqp.io.plot.plot_deflections`, true scale, mm).

    Drawn: the reference deflection on the mesh (line), the reduced solution at the
    computational nodes (markers), the applied forces and the reduced contact forces (arrows,
    labelled in N).
    """
    from ..io.plot import DeflectionCase, plot_deflections

    x = rod.frame.coordinates[:, 0]
    nodes = rod.node_indices
    cases = []
    for c in comparisons:
        U = c.reduced.displacements.reshape(-1, 2)
        at_nodes = np.column_stack([x[nodes] + U[:, 0], U[:, 1]])
        loads = [
            (
                np.array(
                    [load.x, c.reference.displacements[int(np.argmin(np.abs(x - load.x))), 1]]
                ),
                np.array([0.0, load.fy]),
            )
            for load in c.case.loads
        ]
        contacts = [
            (at_nodes[i], -c.reduced.forces[i] * rod.normal)
            for i in np.flatnonzero(c.reduced.forces > 0)
        ]
        cases.append(
            DeflectionCase(
                title=f"{c.case.name}: largest deviation {c.max_eps:.2g} %",
                deformed=rod.frame.coordinates[:, :2] + c.reference.displacements[:, :2],
                nodes=at_nodes,
                loads=loads,
                contacts=contacts,
            )
        )
    return plot_deflections(
        x,
        -rod.gap(x),
        cases,
        path,
        clamp=0.25 * rod.gap_clamped,
        xlabel="x (mm), clamped at the right end",
    )

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
of the fastener rows lifted to ``-inf``: a :class:`~contactqp.core.fastened.FastenedProblem`,
which eliminates the fastener multipliers (a Schur complement); :func:`~contactqp.solve` solves
the remaining non-negative QP by Lawson and Hanson's active-set method (or the project's box-QP
solver, or scipy's NNLS, see :mod:`contactqp.methods.fastened`). The answer is a
:class:`~contactqp.core.fastened.FastenedResult` holding a certified
:class:`~contactqp.core.result.ContactResult` of the contact problem in which the fastener
tensions are external loads, the closure of each fastener checked separately. Fasteners are
installed one after another (:meth:`RivetingModel.fasten`), each an increment warm-started
from the previous one; without friction the final state does not depend
on the order (a test checks it), the intermediate states do.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from ..core.fastened import FastenedProblem
from ..core.model import ReducedModel, finite_array
from ..core.problem import ContactProblem
from ..core.result import FastenedResult
from ..errors import InvalidInputError
from ..io.export import PointMesh
from ..methods import solve
from ..methods.registry import get_method
from ..studies.cases import GapVariation
from .assembly import Part, StackedModel, StackedParts

__all__ = [
    "Assembly",
    "RivetingModel",
    "FasteningSequence",
    "FasteningCase",
    "plate_flexibility",
    "result_mesh",
    "plot_status",
]

_EDGES = ("left", "right", "bottom", "top")


def plate_flexibility(
    plate: Part,
    points: ArrayLike,
    cells: tuple[int, int],
    supports: Sequence[str] = ("left", "right"),
) -> np.ndarray:
    """Out-of-plane flexibility of points of a Kirchhoff plate (Morley elements, condensed).

    Parameters
    ----------
    plate : Part
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
    import skfem
    from scipy.spatial import cKDTree
    from skfem.helpers import dd, ddot, eye, trace

    from ..compliance.fem import plate as plate_mesh  # raises MissingDependencyError without skfem

    bad = [s for s in supports if s not in _EDGES]
    if bad or not supports:
        raise InvalidInputError(
            f"supports must be edges among {', '.join(_EDGES)}, got {supports!r}"
        )
    mesh = plate_mesh(plate.length, plate.width, *cells, cell="tri")
    basis = skfem.Basis(mesh, skfem.ElementTriMorley())
    scale = plate.young * plate.thickness**3 / (12.0 * (1.0 + plate.poisson))
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


def _axis(count: int, length: float, low_held: bool, high_held: bool, refine: int):
    """Contact positions along one side (held edges excluded) and the mesh cells along it."""
    intervals = count - 1 + low_held + high_held
    spacing = length / intervals
    return (low_held + np.arange(count)) * spacing, refine * intervals


@dataclass(frozen=True)
class Assembly(StackedParts):
    """Definition of a riveted assembly of two plates; :meth:`build` makes the reduced model.

    Parameters
    ----------
    lower, upper : Part
        The two plates (same outline).
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

    @cached_property
    def _layout(self) -> tuple:
        """``(points, cells)``: pair positions (m, shape (k, 2)) and mesh cells along x, y."""
        self.check_outline()
        nx, ny = (int(n) for n in self.grid)
        if nx < 1 or ny < 1 or int(self.refine) < 1:
            raise InvalidInputError(
                f"grid and refine must be positive, got {self.grid}, {self.refine}"
            )
        held = set(self.supports)
        xs, cx = _axis(nx, self.lower.length, "left" in held, "right" in held, self.refine)
        ys, cy = _axis(ny, self.lower.width, "bottom" in held, "top" in held, self.refine)
        gx, gy = np.meshgrid(xs, ys)  # pair i + nx j at (xs[i], ys[j])
        return np.column_stack([gx.ravel(), gy.ravel()]), (cx, cy)

    @cached_property
    def flexibilities(self) -> tuple:
        """``(R_lower, R_upper)``: each plate's flexibility at the pairs (m/N, shape (k, k)).

        Computed once per assembly (seconds for the default grid), once for both plates when
        they are equal; kept on this object, which is immutable.
        """
        points, cells = self._layout
        lower = plate_flexibility(self.lower, points, cells, self.supports)
        upper = (
            lower
            if self.upper == self.lower
            else plate_flexibility(self.upper, points, cells, self.supports)
        )
        for block in (lower, upper):
            block.setflags(write=False)
        return lower, upper

    def build(self) -> RivetingModel:
        """The reduced model of both plates (their flexibilities: :attr:`flexibilities`)."""
        points, _ = self._layout
        blocks = self.flexibilities
        nx, ny = (int(n) for n in self.grid)
        fasteners = []
        for i, j in self.fastener_cells():
            if not (0 <= i < nx and 0 <= j < ny):
                raise InvalidInputError(f"fastener ({i}, {j}) is outside the {nx} x {ny} grid")
            fasteners.append(i + nx * j)
        if len(set(fasteners)) != len(fasteners):
            raise InvalidInputError("two fasteners share a contact pair")
        model = ReducedModel(
            flexibility=scipy.linalg.block_diag(*blocks),
            dofs_per_node=1,
            coordinates=np.vstack([points, points]),
        )
        return RivetingModel(self, model, points.copy(), np.array(fasteners, dtype=int))


class RivetingModel(StackedModel):
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
        super().__init__(assembly, model, points, assembly.grid)
        self.fasteners = fasteners

    @cached_property
    def base_problem(self) -> ContactProblem:
        """The contact problem with zero gaps; its dual is assembled once and shared."""
        problem = ContactProblem(
            self.model, np.zeros(2 * self.n_pairs), [self.node_pairs(np.zeros(self.n_pairs))]
        )
        problem.dual()
        return problem

    def problem(self, gaps: ArrayLike) -> ContactProblem:
        """The contact problem for an initial gap field ``gaps`` (m, shape (k,))."""
        return self.base_problem.variant(gaps=gaps)

    def fasten(
        self,
        gaps: ArrayLike,
        order: Sequence[int] | None = None,
        *,
        method: str = "lawson-hanson",
        tol: float = 1e-10,
    ) -> FasteningSequence:
        """Install the fasteners one after another on the gap field ``gaps`` (m, shape (k,)).

        Parameters
        ----------
        gaps : array_like, shape (k,)
            Initial gaps (m), negative for interference.
        order : sequence of int, optional
            Positions in :attr:`fasteners` in installation order (default: as listed).
        method : str
            A method for fastened problems (``"lawson-hanson"``, ``"active-set"``, ``"nnls"``,
            see :func:`~contactqp.solve`); each step is warm started from the previous one
            (except with ``"nnls"``).
        tol : float
            The method's tolerance (``"nnls"`` has none).

        Returns
        -------
        FasteningSequence
            One result per fastener installed.
        """
        n_fasteners = len(self.fasteners)
        sequence = np.arange(n_fasteners) if order is None else np.asarray(order, dtype=int)
        if sorted(sequence.tolist()) != list(range(n_fasteners)):
            raise InvalidInputError(f"order must be a permutation of 0..{len(self.fasteners) - 1}")
        problem = self.problem(self.check_gaps(gaps))
        steps, forces = [], None
        for count in range(1, len(sequence) + 1):
            fastened = FastenedProblem(problem, self.fasteners[sequence[:count]])
            step = solve(fastened, method, **_fastening_options(method, tol, forces))
            forces = step.multipliers
            steps.append(step)
        return FasteningSequence(steps, sequence)


def _fastening_options(method: str, tol: float, r0) -> dict:
    """``tol`` and the warm start ``r0`` for the fastened ``method``, where it takes them."""
    taken = get_method(method, FastenedProblem.kind).option_names
    return {name: value for name, value in (("tol", tol), ("r0", r0)) if name in taken}


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


class FasteningCase(GapVariation):
    """A riveted assembly, every fastener installed: a case of
    :func:`~contactqp.studies.batch.run_batch`.

    Each sample is a :class:`~contactqp.core.fastened.FastenedProblem` (its Schur complement
    reduced once for all samples) solved by :func:`~contactqp.solve` (``method``, ``tol``) with
    all the fasteners at once (without friction the final state does not depend on the order), warm
    started from the previous sample (except with ``method="nnls"``). Records add ``fastener_force``
    (tension per fastener, N) to those of :class:`~contactqp.studies.cases.GapVariation`.
    """

    def __init__(self, model: RivetingModel, method: str = "lawson-hanson", tol: float = 1e-10):
        super().__init__(model.base_problem, method=method, tol=tol)
        self.fasteners = model.fasteners
        self.fastened = FastenedProblem(model.base_problem, model.fasteners)

    def fields(self) -> dict:
        return {**super().fields(), "fastener_force": ((len(self.fasteners),), "f8")}

    def solve_sample(self, gaps, warm):
        options = dict(self.options)
        method = options.pop("method")
        state = solve(
            self.fastened.variant(gaps=gaps),
            method,
            **_fastening_options(method, options.pop("tol"), warm),
            **options,
        )
        record = self._record(state)
        record["fastener_force"] = state.fastener_forces
        record["success"] = state.success
        return record, state.multipliers

    def warm_start(self, record) -> np.ndarray:
        warm = np.array(record["force"], dtype=float)
        warm[self.fasteners] -= record["fastener_force"]
        return warm

    def describe(self) -> dict:
        return {**super().describe(), "fasteners": self.fasteners.tolist()}


def result_mesh(model: RivetingModel, state: FastenedResult, initial_gaps: ArrayLike) -> PointMesh:
    """Both contact grids as quadrilateral surfaces with the fastened state, for
    :func:`~contactqp.io.export.write_vtu` (``write_vtu(path, *result_mesh(...))``).

    The lower grid at ``z = 0``, the upper one at ``z = thickness`` of the lower plate (for
    display). Point data: ``displacement`` (``w`` along ``z``, m), ``contact_force`` (N, on the
    node, along ``z``), ``initial_gap`` and ``gap`` (m), ``status`` (codes of
    :data:`~contactqp.core.status.STATUS_LABELS`: open, closed, fastened), ``fastener_force``
    (N, zero away from fasteners).
    """
    nx, ny = model.grid
    k = model.n_pairs
    ids = np.arange(k).reshape(ny, nx)
    quads = np.column_stack(
        [ids[:-1, :-1].ravel(), ids[:-1, 1:].ravel(), ids[1:, 1:].ravel(), ids[1:, :-1].ravel()]
    )
    z = model.assembly.lower.thickness
    points = np.vstack(
        [
            np.column_stack([model.points, np.zeros(k)]),
            np.column_stack([model.points, np.full(k, z)]),
        ]
    )
    w = state.displacements
    tension = np.zeros(k)
    tension[state.fasteners] = state.fastener_forces
    force = state.forces

    def both(values):
        return np.concatenate([values, values])

    data = {
        "displacement": np.column_stack([np.zeros((2 * k, 2)), w]),
        "contact_force": np.column_stack([np.zeros((2 * k, 2)), np.concatenate([-force, force])]),
        "initial_gap": both(np.asarray(initial_gaps, dtype=float)),
        "gap": both(state.gaps),
        "status": both(state.contact_status),
        "fastener_force": both(tension),
    }
    return PointMesh(points, [("quad", np.vstack([quads, quads + k]))], data)


def plot_status(
    model: RivetingModel,
    state: FastenedResult,
    initial_gaps: ArrayLike,
    path: str | os.PathLike[str],
) -> Path:
    """Maps of the initial and residual gaps (mm) and of the pair status (categorical, with a
    legend), the fasteners marked (drawn by :func:`contactqp.io.plot.plot_point_maps`)."""
    from ..io.plot import STATUS_COLOURS, plot_point_maps

    panels = [
        (np.asarray(initial_gaps) * 1e3, "initial gap (mm)", "viridis"),
        (state.gaps * 1e3, "residual gap (mm)", "viridis"),
        (np.array(state.status_labels, dtype=str), "status", STATUS_COLOURS),
    ]
    return plot_point_maps(
        model.points, panels, path, marked=model.points[state.fasteners], marked_label="fasteners"
    )

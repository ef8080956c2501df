r"""Fastening two thin parts with friction on their interface, the state carried over.

:mod:`contactqp.applications.riveting` models the parts as Kirchhoff plates, out-of-plane only,
so their interface cannot slip. Here each part is a coarse 3-D elastic block
(:class:`~contactqp.compliance.fem.ElasticModel`), so the facing surfaces move in-plane when the
parts bend: a fastener pulling the parts together makes the interface slip where friction lets
it, and what the next fastener finds depends on what the previous ones did.

Model
-----
The ``lower`` part occupies ``[0, L] x [0, B] x [0, t_l]``, the ``upper`` one lies on it,
``t_l <= z <= t_l + t_u``. Both are **clamped at their short end faces** (``x = 0`` and
``x = L``, every component), the assembly jig of :mod:`contactqp.applications.riveting`: this
removes every rigid-body mode of each part with the fixations ``ElasticModel.fix`` offers, and an
in-plane load on the upper part can then be carried by its own clamps and, through friction, by
the lower part, which is the load sharing the fastening sequence decides. (Soft springs holding
the upper part would need springs added to its condensed stiffness, which the finite-element
models do not offer.)

Each part is meshed with one layer of hexahedral cells, each split into quadratic (10-node)
tetrahedra (``block(..., cell="tet")``, ``order=2``). Quadratic hexahedra would do as well but
scikit-fem assembles their 81 x 81 element matrices slowly (2 to 12 s per part here); linear
hexahedra lock in bending (a clamped 2 mm strip under pressure deflects 0.28 of beam theory on
a 20 x 8 x 2 mesh). With the default 10 x 4 cells the midspan deflection of such a strip is 0.84
of beam theory, 0.89 on a mesh twice as fine (plate effect): the coarse model is some 6 %
stiff in bending. The parts differ in thickness by default: two identical parts clamped by
equal and opposite forces deform as mirror images across the interface, whose surfaces then
move alike and never slip.

Each part is condensed (``ElasticModel.reduced_model``) to the three displacement components
of the interface vertices that are not clamped: a grid of ``k`` pairs. The reduced model has
``2 k`` nodes (lower part first, then upper), its flexibility block diagonal. Pair ``i`` is
``(i, k + i)`` with the direction ``+z`` (:class:`~contactqp.core.contact.NodePairs`), so
``u_N = gap_i + w_upper - w_lower`` and the tangents are ``x`` and ``y``; the tangential
displacement of a pair is that of the lower node relative to the upper one, and the tangential
force is the one on the lower part.

Loads
-----
A fastener at pair ``i`` is a clamping force ``F`` (N): ``+F e_z`` on the lower node,
``-F e_z`` on the upper one. Fasteners are installed one after another, each a load increment;
then, optionally, an in-plane shear ``T`` (N, along ``x``, shared equally by the upper part's
interface nodes) is applied and removed in increments. The whole is one load history solved by
:func:`~contactqp.methods.history.solve_history` (each step solved by
:func:`~contactqp.solve` from the previous result), so the friction
law acts on each step's slip increment.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from ..core.contact import NodePairs
from ..core.history import linear_path
from ..core.model import ReducedModel
from ..core.problem import FrictionalProblem
from ..core.result import FrictionalResult
from ..errors import InvalidInputError
from ..methods import solve_history
from .assembly import Part, StackedModel, StackedParts

__all__ = ["FrictionAssembly", "FrictionRivetingModel", "FasteningStep"]

#: Freedoms per contact node: ``u_x, u_y, u_z``.
_DOFS = 3


@dataclass(frozen=True)
class FrictionAssembly(StackedParts):
    """Two parts, one on the other; :meth:`build` meshes, clamps and condenses them.

    Parameters
    ----------
    lower, upper : Part
        The parts (same length and width); by default 100 x 40 mm aluminium, 2 mm and 1.2 mm
        thick.
    cells : (int, int)
        Cells along ``x`` and ``y`` (one through the thickness), each of quadratic tetrahedra
        (see the module notes). The contact
        pairs are the interface vertices off the clamped ends: ``(cells[0] - 1) x (cells[1]
        + 1)`` pairs (9 x 5 = 45 by default).
    """

    lower: Part = Part(length=0.100, width=0.040)
    upper: Part = Part(length=0.100, width=0.040, thickness=0.0012)
    cells: tuple = (10, 4)

    def build(self) -> FrictionRivetingModel:
        """Mesh, clamp and condense both parts (about a second for the default cells)."""
        from ..compliance.fem import ElasticModel, block  # needs scikit-fem

        self.check_outline()
        nx, ny = (int(n) for n in self.cells)
        if nx < 2 or ny < 1:
            raise InvalidInputError(f"cells must be at least (2, 1), got {self.cells}")
        xs = np.linspace(0.0, self.lower.length, nx + 1)[1:-1]
        ys = np.linspace(0.0, self.lower.width, ny + 1)
        gx, gy = np.meshgrid(xs, ys)  # pair i + (nx - 1) j at (xs[i], ys[j])
        points = np.column_stack([gx.ravel(), gy.ravel()])
        parts, blocks, coordinates = [], [], []
        for part, face, base in (
            (self.lower, "top", 0.0),
            (self.upper, "bottom", self.lower.thickness),
        ):
            body = ElasticModel(
                block(part.length, part.width, part.thickness, nx, ny, 1, cell="tet"),
                part.young,
                part.poisson,
                order=2,
            )
            body.fix("left").fix("right")
            height = part.thickness if face == "top" else 0.0
            nodes = body.select_nodes(
                np.column_stack([points, np.full(len(points), height)]), where=face
            ).nodes
            reduced = body.reduced_model(nodes)
            assert reduced.coordinates is not None  # a mesh's reduced model has its nodes'
            parts.append((body, nodes))
            blocks.append(reduced.flexibility)
            coordinates.append(reduced.coordinates + [0.0, 0.0, base])
        model = ReducedModel(
            flexibility=scipy.linalg.block_diag(*blocks),
            dofs_per_node=_DOFS,
            coordinates=np.vstack(coordinates),
        )
        return FrictionRivetingModel(self, model, points, parts)


@dataclass(frozen=True)
class FasteningStep:
    """The state after one step of a fastening sequence (or of the shear load after it).

    Attributes
    ----------
    label : str
        What the step did, e.g. ``"fastener (3, 2)"`` or ``"shear 100 N"``.
    result : FrictionalResult
        The certified step: per pair (lower node first), ``gaps`` (m), ``forces`` (normal,
        then the friction force on the lower part along ``x`` and ``y``, N),
        ``contact_status`` (open, stick, slip), ``slip`` (lower part relative to upper, m) and
        ``dissipation`` (J).
    """

    label: str
    result: FrictionalResult


class FrictionRivetingModel(StackedModel):
    """The reduced model of a :class:`FrictionAssembly`: pairs, loads, fastening sequences.

    Attributes
    ----------
    assembly : FrictionAssembly
    model : ReducedModel
        ``2 k`` nodes with ``u_x, u_y, u_z`` (m) each: the lower part's interface first.
    points : ndarray, shape (k, 2)
        In-plane position of each pair (m).
    parts : list of (ElasticModel, ndarray)
        For the lower and upper part: the clamped finite-element body and the mesh nodes of its
        interface, in pair order (for full analyses that check the reduction).
    """

    def __init__(self, assembly: FrictionAssembly, model: ReducedModel, points, parts):
        nx, ny = assembly.cells
        super().__init__(assembly, model, points, (int(nx) - 1, int(ny) + 1))
        self.parts = parts

    def obstacles(self, gaps: ArrayLike) -> list[NodePairs]:
        """The interface as :class:`NodePairs` for initial gaps ``gaps`` (m, shape (k,))."""
        return [self.node_pairs(gaps)]

    def clamp_loads(self, pairs: Sequence[int], force: float) -> np.ndarray:
        """Loads (N, shape (n_freedoms,)) of fasteners clamping ``pairs`` with ``force`` (N).

        ``+force`` along ``z`` on each pair's lower node, ``-force`` on its upper node.
        """
        loads = np.zeros(self.model.n_freedoms)
        lower = np.asarray(pairs, dtype=int)
        loads[_DOFS * lower + 2] += force
        loads[_DOFS * (self.n_pairs + lower) + 2] -= force
        return loads

    def shear_loads(self, force: float) -> np.ndarray:
        """Loads (N, shape (n_freedoms,)): ``force`` along ``x`` shared by the upper nodes."""
        loads = np.zeros(self.model.n_freedoms)
        loads[_DOFS * np.arange(self.n_pairs, 2 * self.n_pairs)] = force / self.n_pairs
        return loads

    def fasten(
        self,
        gaps: ArrayLike,
        fasteners: Sequence[tuple[int, int]],
        mu: ArrayLike,
        *,
        clamp: float = 500.0,
        shear: float = 0.0,
        shear_steps: int = 2,
        facets: int | None = None,
        **options: Any,
    ) -> list[FasteningStep]:
        """Install ``fasteners`` in order, then apply and remove ``shear``; every step's state.

        Parameters
        ----------
        gaps : array_like, shape (k,)
            Initial gap of each pair (m), negative for interference.
        fasteners : sequence of (int, int)
            Grid positions (along ``x``, along ``y``; see :meth:`pair`) in installation order.
        mu : float or array_like, shape (k,)
            Friction coefficient of the interface, >= 0.
        clamp : float
            Clamping force of each fastener (N).
        shear : float
            In-plane load on the upper part after fastening (N, along ``x``; see
            :meth:`shear_loads`); 0 for the fastening sequence alone.
        shear_steps : int
            Increments to apply the shear, and as many to remove it.
        facets : int, optional
            Polygonal friction cone (see :class:`FrictionalProblem`).
        **options
            Passed to :func:`~contactqp.methods.history.solve_history` (``method``,
            ``tol``, ...).

        Returns
        -------
        list of FasteningStep
            One per fastener, then ``2 shear_steps`` when ``shear`` is not zero. Check each
            ``step.result.success``.
        """
        positions = [tuple(int(v) for v in f) for f in fasteners]
        pairs = [self.pair(i, j) for i, j in positions]
        if not pairs or len(set(pairs)) != len(pairs):
            raise InvalidInputError("fasteners must name at least one pair, each at most once")
        if not (np.isfinite(clamp) and clamp > 0):
            raise InvalidInputError(f"clamp must be a positive force (N), got {clamp!r}")
        history = [self.clamp_loads(pairs[:n], clamp) for n in range(1, len(pairs) + 1)]
        labels = [f"fastener {f}" for f in positions]
        if shear:
            fastened = history[-1]
            history.extend(
                linear_path([fastened, fastened + self.shear_loads(shear), fastened], shear_steps)[
                    1:
                ]
            )
            fractions = (
                np.concatenate([np.arange(1, shear_steps + 1), np.arange(shear_steps - 1, -1, -1)])
                / shear_steps
            )
            labels.extend(f"shear {shear * f:g} N" for f in fractions)
        problem = FrictionalProblem(self.model, history[0], self.obstacles(gaps), mu, facets=facets)
        steps = solve_history(problem, np.array(history), **options).steps
        return [FasteningStep(label, step) for label, step in zip(labels, steps, strict=True)]

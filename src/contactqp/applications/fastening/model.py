"""Parts, interfaces and fasteners of an assembly, and the assembly's reduced model.

An :class:`Assembly` puts its parts' reduced models side by side (a block-diagonal flexibility,
or stiffness when every part holds one) and numbers their nodes part after part. Each interface
pair ``i`` joins a node of its ``first`` part to one of its ``second`` part; its unit normal
``n_i`` points from the first towards the second, and its gap is

    g_i = g0_i + n_i . (u_second - u_first)        (m; g < 0 is interference)

with tangents :func:`~contactqp.core.contact.tangent_basis` of the normals. The parts' models
have 3 freedoms per node (``u_x, u_y, u_z``), or 1: then each node's freedom is its displacement
along the normal of its pair (out-of-plane only), and the interface cannot slip, so friction is
refused.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from functools import cached_property
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from ...core.contact import NodePairs, tangent_basis
from ...core.friction import polygon_normals
from ...core.model import MAX_MAGNITUDE, ReducedModel, finite_array, real_array
from ...core.problem import ContactProblem, FrictionalProblem
from ...errors import InvalidInputError
from .parts import FASTENER_KINDS, SHEARS, AssemblyPart, Fastener, InterfacePairs
from .sequence import run_sequence
from .stage import AssemblySequence

__all__ = ["Assembly", "UNIT_RTOL"]

#: A pair normal is unit when its length is 1 within this tolerance.
UNIT_RTOL = 1e-6


def _name(value: object, what: str) -> str:
    if not isinstance(value, str) or not value:
        raise InvalidInputError(f"{what} must be a non-empty string, got {value!r}")
    return value


def _integers(value: ArrayLike, what: str, shape_text: str) -> np.ndarray:
    array = np.asarray(value)
    if array.size and not np.issubdtype(array.dtype, np.integer):
        if not (np.issubdtype(array.dtype, np.floating) and np.all(array == np.round(array))):
            raise InvalidInputError(f"{what} must be integers ({shape_text}), got {array.dtype}")
    return array.astype(int)


def _real(value: object) -> float | None:
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    return None


class Assembly:
    """Parts joined by interface pairs and fasteners, with friction on the interface.

    Parameters
    ----------
    parts : sequence of AssemblyPart
        Distinct names; every model with 3 freedoms per node, or every model with 1.
    interfaces : sequence of InterfacePairs
        Their pairs, concatenated in order, are the assembly's pairs ``0 .. k-1``.
    fasteners : sequence of Fastener
        At distinct pairs; :meth:`sequence` installs them in a given order.
    mu : float or array_like, shape (k,)
        Friction coefficient of each pair, >= 0 (needs 3 freedoms per node where > 0).
    facets : int, optional
        Polygonal friction cones of ``facets`` sides (None: the exact cone).

    Attributes
    ----------
    parts, interfaces, fasteners : tuple
    model : ReducedModel
        The parts' models side by side, nodes numbered part after part.
    pairs : ndarray of int, shape (k, 2)
        Each pair's first and second node in :attr:`model`.
    points, normals : ndarray, shape (k, 3)
        Pair positions (mean of the two nodes, m) and unit normals.
    mu : ndarray, shape (k,)
    facets : int or None
    dofs_per_node : int
        1 or 3.

    Raises
    ------
    InvalidInputError
        A bad part, interface, fastener, ``mu`` or ``facets``; the message names it.
    """

    def __init__(
        self,
        parts: Sequence[AssemblyPart],
        interfaces: Sequence[InterfacePairs],
        fasteners: Sequence[Fastener] = (),
        *,
        mu: ArrayLike = 0.0,
        facets: int | None = None,
    ) -> None:
        self.parts = self._checked_parts(parts)
        self._index = {part.name: i for i, part in enumerate(self.parts)}
        counts = [part.model.n_nodes for part in self.parts]
        self.node_offsets = np.concatenate(([0], np.cumsum(counts))).astype(int)
        self.dofs_per_node = int(self.parts[0].model.dofs_per_node[0])
        self.interfaces = tuple(interfaces)
        self.pairs, self.normals = self._checked_interfaces(self.interfaces)
        coordinates = np.vstack([part.coordinates for part in self.parts])
        self.points = 0.5 * (coordinates[self.pairs[:, 0]] + coordinates[self.pairs[:, 1]])
        self.tangents = tangent_basis(self.normals)
        self.fasteners = self._checked_fasteners(fasteners)
        self.mu = self._checked_mu(mu)
        if facets is not None:
            polygon_normals(facets)  # refuses a bad count
            facets = int(facets)
        self.facets = facets
        self.model = self._side_by_side(coordinates)
        self._links_cache: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        #: What the stages of every sequence share (linked models, reduced operators), by
        #: the links' structure and the contacts (filled by the sequences).
        self.operators: dict = {}

    # ------------------------------------------------------------------ validation

    @staticmethod
    def _checked_parts(parts: Sequence[AssemblyPart]) -> tuple[AssemblyPart, ...]:
        listed = tuple(parts) if not isinstance(parts, AssemblyPart) else (parts,)
        if not listed:
            raise InvalidInputError("an assembly needs at least one part")
        seen: set[str] = set()
        for position, part in enumerate(listed):
            if not isinstance(part, AssemblyPart):
                raise InvalidInputError(
                    f"parts[{position}] is a {type(part).__name__}, not an AssemblyPart"
                )
            name = _name(part.name, f"parts[{position}].name")
            if name in seen:
                raise InvalidInputError(f"two parts are named {name!r}")
            seen.add(name)
            if not isinstance(part.model, ReducedModel):
                raise InvalidInputError(
                    f"part {name!r}: model must be a ReducedModel, got {type(part.model).__name__}"
                )
            counts = set(part.model.dofs_per_node.tolist())
            if len(counts) != 1 or counts & {2}:
                raise InvalidInputError(
                    f"part {name!r}: its reduced model must have 3 freedoms per node (u_x, u_y, "
                    f"u_z) or 1 (out-of-plane), got {sorted(counts)}"
                )
            coordinates = finite_array(part.coordinates, f"part {name!r} coordinates", 2)
            if coordinates.shape != (part.model.n_nodes, 3):
                raise InvalidInputError(
                    f"part {name!r}: coordinates must have shape ({part.model.n_nodes}, 3), one "
                    f"row per node of its model, got {coordinates.shape}"
                )
        per_node = {int(part.model.dofs_per_node[0]) for part in listed}
        if len(per_node) > 1:
            raise InvalidInputError(
                "the parts' reduced models must all have 3 freedoms per node or all 1, got "
                + ", ".join(f"{p.name}: {int(p.model.dofs_per_node[0])}" for p in listed)
            )
        return listed

    def _part(self, name: object, what: str) -> int:
        if not isinstance(name, str) or name not in self._index:
            raise InvalidInputError(
                f"{what} names an unknown part {name!r}; parts: {', '.join(self._index)}"
            )
        return self._index[name]

    def _checked_interfaces(
        self, interfaces: tuple[InterfacePairs, ...]
    ) -> tuple[np.ndarray, np.ndarray]:
        if not interfaces:
            raise InvalidInputError("an assembly needs at least one interface")
        pairs, normals = [], []
        for position, interface in enumerate(interfaces):
            what = f"interfaces[{position}]"
            if not isinstance(interface, InterfacePairs):
                raise InvalidInputError(
                    f"{what} is a {type(interface).__name__}, not InterfacePairs"
                )
            first = self._part(interface.first, f"{what}.first")
            second = self._part(interface.second, f"{what}.second")
            nodes = _integers(interface.nodes, f"{what}.nodes", "shape (k, 2)")
            if nodes.ndim != 2 or nodes.shape[1] != 2 or nodes.shape[0] == 0:
                raise InvalidInputError(
                    f"{what}.nodes must have shape (k, 2) with k >= 1, got {nodes.shape}"
                )
            for column, part in ((0, first), (1, second)):
                n_nodes = self.parts[part].model.n_nodes
                bad = np.flatnonzero((nodes[:, column] < 0) | (nodes[:, column] >= n_nodes))
                if bad.size:
                    raise InvalidInputError(
                        f"{what}.nodes[{bad[0]}] has node {nodes[bad[0], column]} of part "
                        f"{self.parts[part].name!r}, outside 0..{n_nodes - 1}"
                    )
            unit = finite_array(interface.normals, f"{what}.normals", 2)
            if unit.shape != (len(nodes), 3):
                raise InvalidInputError(
                    f"{what}.normals must have shape ({len(nodes)}, 3), got {unit.shape}"
                )
            lengths = np.linalg.norm(unit, axis=1)
            off = np.flatnonzero(np.abs(lengths - 1.0) > UNIT_RTOL)
            if off.size:
                raise InvalidInputError(
                    f"{what}.normals[{off[0]}] is not a unit vector (length {lengths[off[0]]:.6g})"
                )
            pairs.append(
                np.column_stack(
                    [
                        self.node_offsets[first] + nodes[:, 0],
                        self.node_offsets[second] + nodes[:, 1],
                    ]
                )
            )
            normals.append(unit / lengths[:, None])
        joined = np.vstack(pairs)
        same = np.flatnonzero(joined[:, 0] == joined[:, 1])
        if same.size:
            raise InvalidInputError(f"pair {same[0]} joins a node to itself")
        keys = np.sort(joined, axis=1)
        _, first_seen, counts = np.unique(keys, axis=0, return_index=True, return_counts=True)
        if np.any(counts > 1):
            twice = keys[first_seen[np.argmax(counts > 1)]]
            repeats = np.flatnonzero(np.all(keys == twice, axis=1))
            raise InvalidInputError(
                f"pairs {repeats[0]} and {repeats[1]} join the same two nodes (assembly nodes "
                f"{twice[0]} and {twice[1]}): give each pair once"
            )
        return joined, np.vstack(normals)

    def _checked_fasteners(self, fasteners: Sequence[Fastener]) -> tuple[Fastener, ...]:
        listed = tuple(fasteners) if not isinstance(fasteners, Fastener) else (fasteners,)
        seen: dict[int, int] = {}
        k = self.n_pairs
        for position, fastener in enumerate(listed):
            what = f"fastener {position}"
            if not isinstance(fastener, Fastener):
                raise InvalidInputError(f"{what} is a {type(fastener).__name__}, not a Fastener")
            pair = fastener.pair
            if isinstance(pair, bool) or not isinstance(pair, numbers.Integral):
                raise InvalidInputError(f"{what}: pair must be an integer, got {pair!r}")
            if not 0 <= int(pair) < k:
                raise InvalidInputError(f"{what}: pair {pair} is outside 0..{k - 1}")
            if int(pair) in seen:
                raise InvalidInputError(
                    f"{what}: pair {pair} already has fastener {seen[int(pair)]}"
                )
            seen[int(pair)] = position
            if fastener.kind not in FASTENER_KINDS:
                raise InvalidInputError(
                    f"{what}: kind must be one of {', '.join(FASTENER_KINDS)}, got "
                    f"{fastener.kind!r}"
                )
            if fastener.shear not in SHEARS:
                raise InvalidInputError(
                    f"{what}: shear must be one of {', '.join(SHEARS)}, got {fastener.shear!r}"
                )
            force, stiffness = _real(fastener.force), _real(fastener.stiffness)
            if force is None or not math.isfinite(force) or abs(force) > MAX_MAGNITUDE:
                raise InvalidInputError(
                    f"{what}: force must be a finite number (N), got {fastener.force!r}"
                )
            if fastener.kind == "clamp":
                if stiffness is None or not (math.isfinite(stiffness) and stiffness > 0):
                    raise InvalidInputError(
                        f"{what}: a clamp needs a finite positive axial stiffness (N/m), got "
                        f"{fastener.stiffness!r}"
                    )
            elif stiffness != math.inf or force != 0.0:
                raise InvalidInputError(
                    f"{what}: a closure is rigid and imposes the gap, not a force: leave force 0 "
                    f"and stiffness inf (got {fastener.force!r}, {fastener.stiffness!r}), or "
                    f"use kind 'clamp'"
                )
            if fastener.shear == "bonded" and self.dofs_per_node == 1:
                raise InvalidInputError(
                    f"{what}: shear 'bonded' needs in-plane freedoms, which the parts' reduced "
                    f"models (1 freedom per node) do not have: use shear 'free'"
                )
            if not isinstance(fastener.label, str):
                raise InvalidInputError(f"{what}: label must be a string, got {fastener.label!r}")
        return listed

    def _checked_mu(self, mu: ArrayLike) -> np.ndarray:
        values = finite_array(np.atleast_1d(real_array(mu, "mu")), "mu", 1)
        if values.size == 1:
            values = np.full(self.n_pairs, values[0])
        if values.shape != (self.n_pairs,):
            raise InvalidInputError(
                f"mu must be a scalar or hold one value per pair ({self.n_pairs}), got shape "
                f"{values.shape}"
            )
        if np.any(values < 0):
            raise InvalidInputError(
                f"mu must be >= 0, got {values.min():g} at pair {int(np.argmin(values))}"
            )
        if self.dofs_per_node == 1 and np.any(values > 0):
            raise InvalidInputError(
                f"mu > 0 (pair {int(np.argmax(values > 0))}) needs tangential slip, but the "
                f"parts' reduced models have no in-plane freedoms (1 freedom per node), so the "
                f"interface cannot slip: give mu = 0 or models with u_x, u_y, u_z"
            )
        return values

    def _side_by_side(self, coordinates: np.ndarray) -> ReducedModel:
        """The parts' matrices block-diagonal: stiffnesses when every part holds one, else
        flexibilities (each symmetrised: an inverse carries round-off asymmetry)."""
        models = [part.model for part in self.parts]
        stiff = all(model.given == "stiffness" for model in models)
        blocks = [model.stiffness if stiff else model.flexibility for model in models]
        matrix = scipy.linalg.block_diag(*(0.5 * (block + block.T) for block in blocks))
        if stiff:
            return ReducedModel(
                stiffness=matrix, dofs_per_node=self.dofs_per_node, coordinates=coordinates
            )
        return ReducedModel(
            flexibility=matrix, dofs_per_node=self.dofs_per_node, coordinates=coordinates
        )

    # ------------------------------------------------------------------ geometry and loads

    @property
    def n_pairs(self) -> int:
        """Number of interface pairs ``k``."""
        return int(len(self.pairs))

    @property
    def n_freedoms(self) -> int:
        """Freedoms of :attr:`model`."""
        return self.model.n_freedoms

    @property
    def frictional(self) -> bool:
        """True when ``mu > 0`` on some pair."""
        return bool(np.any(self.mu > 0))

    def node_freedoms(self, node: int) -> np.ndarray:
        """Indices of the freedoms of assembly node ``node`` in :attr:`model`."""
        return self.model.freedoms(int(node))

    def directions(self) -> np.ndarray:
        """The :class:`~contactqp.core.contact.NodePairs` direction of each pair: its normal,
        or ``[1]`` for 1-freedom nodes (each freedom is along its pair's normal)."""
        if self.dofs_per_node == 1:
            return np.ones((self.n_pairs, 1))
        return self.normals

    def node_pairs(self, gaps: ArrayLike, pairs: ArrayLike | None = None) -> NodePairs:
        """The pairs ``pairs`` (all by default) as :class:`NodePairs` on initial gaps ``gaps``."""
        chosen = np.arange(self.n_pairs) if pairs is None else np.asarray(pairs, dtype=int)
        return NodePairs(self.pairs[chosen], gaps, self.directions()[chosen])

    def load_vector(self, part: str, nodes: ArrayLike, force: ArrayLike) -> np.ndarray:
        """Loads (N, shape (n_freedoms,)): the total ``force`` shared equally by ``nodes``.

        Parameters
        ----------
        part : str
            A part name.
        nodes : array_like of int
            Nodes of that part (indices into its model).
        force : array_like, shape (3,)
            Total force (N). For 1-freedom models: a number (along the nodes' freedom), or a
            3-vector projected on the pairs' normal when they all share one.
        """
        index = self._part(part, "load_vector part")
        chosen = _integers(np.atleast_1d(nodes), "nodes", "node indices").reshape(-1)
        n_nodes = self.parts[index].model.n_nodes
        if chosen.size == 0 or np.any((chosen < 0) | (chosen >= n_nodes)):
            raise InvalidInputError(
                f"nodes must be at least one node of part {part!r}, in 0..{n_nodes - 1}"
            )
        total = finite_array(np.atleast_1d(real_array(force, "force")), "force", 1)
        if self.dofs_per_node == 1:
            total = self._along_freedom(total)
        elif total.shape != (3,):
            raise InvalidInputError(f"force must have shape (3,), got {total.shape}")
        loads = np.zeros(self.n_freedoms)
        for node in self.node_offsets[index] + chosen:
            loads[self.node_freedoms(node)] += total / chosen.size
        return loads

    def _along_freedom(self, force: np.ndarray) -> np.ndarray:
        if force.shape == (1,):
            return force
        if force.shape != (3,):
            raise InvalidInputError(f"force must be a number or have shape (3,), got {force.shape}")
        if not np.allclose(self.normals, self.normals[0], rtol=0, atol=UNIT_RTOL):
            raise InvalidInputError(
                "a 3-D force on 1-freedom models needs one normal for all pairs; give the force "
                "along the freedom as a number"
            )
        return np.array([force @ self.normals[0]])

    # ------------------------------------------------------------------ shared problems

    def fastener_links(self, position: int) -> tuple[np.ndarray, np.ndarray]:
        """``(E, R E)`` of fastener ``position``: its link directions in the pair frame (axial
        ``n``, then ``t1, t2`` when bonded), each the relative displacement of the second node
        minus the first, and the displacements they cause; computed once and kept."""
        cached = self._links_cache.get(position)
        if cached is not None:
            return cached
        fastener = self.fasteners[position]
        a, b = self.pairs[fastener.pair]
        if self.dofs_per_node == 1:
            vectors = np.ones((1, 1))
        elif fastener.shear == "free":
            vectors = self.normals[fastener.pair][None, :]
        else:
            vectors = np.vstack([self.normals[fastener.pair], self.tangents[fastener.pair]])
        columns = np.zeros((self.n_freedoms, len(vectors)))
        columns[self.node_freedoms(b)] = vectors.T
        columns[self.node_freedoms(a)] = -vectors.T
        if self.model.given == "flexibility":  # R E = (E^T R)^T: the rows of the two nodes
            touched = np.concatenate([self.node_freedoms(a), self.node_freedoms(b)])
            influence = np.ascontiguousarray(
                (columns[touched].T @ self.model.flexibility[touched]).T
            )
        else:
            influence = np.asarray(self.model.displacements(columns)).reshape(columns.shape)
        for array in (columns, influence):
            array.setflags(write=False)
        self._links_cache[position] = (columns, influence)
        return columns, influence

    @cached_property
    def base_problem(self) -> ContactProblem | FrictionalProblem:
        """All pairs on zero gaps, no loads, its contact operator assembled once and shared by
        every stage of every sequence (:meth:`FrictionalProblem.restricted`)."""
        pairs = [self.node_pairs(np.zeros(self.n_pairs))]
        zero = np.zeros(self.n_freedoms)
        if self.frictional:
            frictional = FrictionalProblem(self.model, zero, pairs, self.mu, facets=self.facets)
            frictional.local()
            return frictional
        frictionless = ContactProblem(self.model, zero, pairs)
        frictionless.dual()
        return frictionless

    def sequence(
        self,
        gaps: ArrayLike,
        *,
        order: Sequence[int] | None = None,
        load_steps: Sequence[tuple[str, ArrayLike]] = (),
        method: str | None = None,
        r0: Any = None,
        **options: Any,
    ) -> AssemblySequence:
        """Install the fasteners one by one, then apply each load step; every stage's state.

        Parameters
        ----------
        gaps : array_like, shape (k,)
            Initial gap of each pair (m), negative for interference.
        order : sequence of int, optional
            Positions in :attr:`fasteners`, distinct, in installation order (default: as
            listed; a subset installs only those).
        load_steps : sequence of (str, array_like)
            ``(label, loads)``: total external loads (N, shape (n_freedoms,)) after fastening,
            e.g. a shear load and its removal (see :meth:`load_vector`).
        method : str, optional
            With friction, a method for frictional problems (see :func:`~contactqp.solve`;
            default ``coulomb``, ``polygonal`` with facets). Without: ``"lawson-hanson"``
            (default) or ``"active-set"`` on the reduced non-negative QP.
        r0 : array_like or AssemblySequence, optional
            Warm start of the first stage (per pair: normal forces (k,), or local forces
            (k, d)), or a sequence (e.g. the nominal one) whose stage ``i`` warm starts stage
            ``i``. By default each stage starts from the previous one.
        **options
            The method's options (``tol``, ``max_iter``, ...).

        Returns
        -------
        AssemblySequence
            Every stage, failed ones included (check :attr:`AssemblySequence.success`).
        """
        return run_sequence(self, gaps, order, load_steps, method, r0, options)

    def __repr__(self) -> str:
        return (
            f"Assembly({len(self.parts)} parts, {self.n_pairs} pairs, {len(self.fasteners)} "
            f"fasteners, {self.dofs_per_node} freedom(s) per node, "
            f"{'mu > 0' if self.frictional else 'frictionless'})"
        )

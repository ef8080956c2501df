"""Unilateral constraints ``A U <= Delta``: rigid obstacles and node-to-node pairs, local frames.

Each constraint row measures the displacement of a node (or the relative displacement of two
nodes) along a unit direction pointing towards the obstacle (or the other body); ``Delta`` is the
initial gap along that direction, in metres. Small displacements are assumed: the directions do not
rotate and the gaps are linear in the displacements.

For friction, :func:`local_frames` completes each direction ``n`` with an orthonormal tangent basis
and builds the operator ``H`` of the local (FCLIB) coordinates: per contact the normal row ``-n``
(so that ``u_N = Delta + (H U)_N`` is the gap opening) and one row per tangent ``t`` (the slip of
the node, or of the first node relative to the second, along ``t``).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, TypeAlias, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidInputError
from .model import MAX_MAGNITUDE, ReducedModel, real_array

if TYPE_CHECKING:
    import scipy.sparse

__all__ = [
    "Constraints",
    "PlaneObstacle",
    "GapObstacle",
    "ProfileObstacle",
    "NodePairs",
    "assemble_constraints",
    "LocalFrames",
    "local_frames",
    "tangent_basis",
    "Obstacle",
    "ConstraintRow",
]

#: One constraint row: ``(node, freedoms, coefficients, gap, label)``; the row reads
#: ``coefficients . U[freedoms] <= gap``.
ConstraintRow: TypeAlias = tuple[int, np.ndarray, np.ndarray, float, str]


@runtime_checkable
class Obstacle(Protocol):
    """What :func:`assemble_constraints` accepts: anything that lists its constraint rows."""

    def rows(self, model: ReducedModel) -> list[ConstraintRow]:
        """Constraint rows as ``(node, freedoms, coefficients, gap, label)`` tuples."""
        ...


@dataclass(frozen=True)
class Constraints:
    """Assembled non-penetration constraints ``A U <= gaps``.

    Attributes
    ----------
    matrix : scipy.sparse.csr_matrix, shape (m, n_freedoms)
    gaps : ndarray, shape (m,)
        Initial gaps in metres (negative: initial interference).
    nodes : ndarray of int, shape (m,)
        The node of each row (the first node for a pair).
    labels : list of str
        A readable description of each row.
    """

    matrix: scipy.sparse.csr_matrix
    gaps: np.ndarray
    nodes: np.ndarray
    labels: list[str] = field(default_factory=list)

    @property
    def n_constraints(self) -> int:
        """Number of rows ``m``."""
        return len(self.gaps)


def _unit_directions(directions: ArrayLike, count: int, name: str) -> np.ndarray:
    dirs = real_array(directions, name)
    if dirs.ndim == 1:
        dirs = np.tile(dirs, (count, 1))
    if dirs.ndim != 2 or dirs.shape[0] != count or dirs.shape[1] not in (1, 2, 3):
        raise InvalidInputError(
            f"{name} must have shape (d,) or ({count}, d) with d in 1..3, "
            f"got {np.shape(directions)}"
        )
    if not np.all(np.isfinite(dirs)):
        raise InvalidInputError(f"{name} contains NaN or inf")
    norms = np.linalg.norm(dirs, axis=1)
    if np.any(norms == 0.0):
        raise InvalidInputError(f"{name} has a zero vector at row {int(np.argmin(norms))}")
    return dirs / norms[:, None]


def _node_indices(model: ReducedModel, nodes: ArrayLike | None, name: str) -> np.ndarray:
    if nodes is None:
        return np.arange(model.n_nodes)
    idx = np.asarray(nodes).reshape(-1)
    if idx.size and not np.issubdtype(idx.dtype, np.integer):
        raise InvalidInputError(f"{name} must be node indices (integers), got dtype {idx.dtype}")
    idx = idx.astype(int)
    bad = idx[(idx < 0) | (idx >= model.n_nodes)]
    if bad.size:
        raise InvalidInputError(f"{name} has node {bad[0]} outside 0..{model.n_nodes - 1}")
    return idx


def _node_freedoms(model: ReducedModel, node: int, direction: np.ndarray, name: str) -> np.ndarray:
    dofs = model.freedoms(node)
    if len(dofs) != len(direction):
        raise InvalidInputError(
            f"{name}: node {node} has {len(dofs)} freedoms but the direction has {len(direction)} "
            "components"
        )
    return dofs


@dataclass(frozen=True)
class _RowBlock:
    """Constraint rows of one width ``w``, as arrays: row ``i`` reads
    ``coefficients[i] . U[freedoms[i]] <= gaps[i]`` (what :class:`ConstraintRow` holds, for
    many rows without a Python object per row)."""

    nodes: np.ndarray  # (k,) int
    freedoms: np.ndarray  # (k, w) int
    coefficients: np.ndarray  # (k, w)
    gaps: np.ndarray  # (k,)
    labels: list[str]

    def rows(self) -> list[ConstraintRow]:
        """The rows as :data:`ConstraintRow` tuples."""
        return [
            (int(k), f, c, float(g), label)
            for k, f, c, g, label in zip(
                self.nodes, self.freedoms, self.coefficients, self.gaps, self.labels, strict=True
            )
        ]


def _node_block(
    model: ReducedModel,
    nodes: np.ndarray,
    gaps: np.ndarray,
    directions: np.ndarray,
    name: str,
    label: str,
) -> _RowBlock:
    """One constraint row per node: its freedoms, the direction, the gap.

    ``directions`` is one unit vector for all nodes, shape (d,), or one per node, shape (k, d).
    """
    d = int(np.shape(directions)[-1])
    directions = np.broadcast_to(np.asarray(directions, dtype=float), (len(nodes), d))
    counts = model.dofs_per_node[nodes]
    wrong = np.flatnonzero(counts != d)
    if wrong.size:
        raise InvalidInputError(
            f"{name}: node {nodes[wrong[0]]} has {counts[wrong[0]]} freedoms but the direction "
            f"has {d} components"
        )
    return _RowBlock(
        nodes=nodes.astype(int, copy=False),
        freedoms=model.offsets[nodes][:, None] + np.arange(d),
        coefficients=directions,
        gaps=np.asarray(gaps, dtype=float).reshape(-1),
        labels=[f"node {k}{label}" for k in nodes.tolist()],
    )


def _coordinates(model: ReducedModel, name: str) -> np.ndarray:
    if model.coordinates is None:
        raise InvalidInputError(f"{name} needs node coordinates: give coordinates to the model")
    return model.coordinates


@dataclass
class GapObstacle:
    """A rigid obstacle given by an initial gap and a direction for each listed node.

    Parameters
    ----------
    nodes : sequence of int
    gaps : array_like, shape (len(nodes),)
        Initial gaps (m) along the directions.
    directions : array_like, shape (d,) or (len(nodes), d)
        Directions from each node towards the obstacle; normalised. For nodes with one freedom,
        ``[1.0]`` (default) or ``[-1.0]``.
    """

    nodes: ArrayLike
    gaps: ArrayLike
    directions: ArrayLike = (1.0,)

    def rows(self, model: ReducedModel) -> list[ConstraintRow]:
        """Constraint rows as ``(node, freedoms, coefficients, gap, label)`` tuples."""
        return self._row_block(model).rows()

    def _row_block(self, model: ReducedModel) -> _RowBlock:
        nodes = _node_indices(model, self.nodes, "GapObstacle.nodes")
        gaps = real_array(self.gaps, "GapObstacle.gaps").reshape(-1)
        if gaps.shape != nodes.shape:
            raise InvalidInputError(
                f"GapObstacle.gaps has {gaps.size} values for {nodes.size} nodes"
            )
        if not np.all(np.isfinite(gaps)):
            raise InvalidInputError("GapObstacle.gaps contains NaN or inf")
        dirs = _unit_directions(self.directions, len(nodes), "GapObstacle.directions")
        return _node_block(model, nodes, gaps, dirs, "GapObstacle", "")


@dataclass
class PlaneObstacle:
    """A rigid plane (a line in 2-D, a point in 1-D) that the nodes must not cross.

    Parameters
    ----------
    point : array_like, shape (d,)
        A point of the plane, in the coordinates of the model (m).
    normal : array_like, shape (d,)
        Direction from the body towards the plane; normalised.
    nodes : sequence of int, optional
        Nodes that may touch the plane (default: all).
    """

    point: ArrayLike
    normal: ArrayLike
    nodes: ArrayLike | None = None

    def rows(self, model: ReducedModel) -> list[ConstraintRow]:
        """Constraint rows as ``(node, freedoms, coefficients, gap, label)`` tuples."""
        return self._row_block(model).rows()

    def _row_block(self, model: ReducedModel) -> _RowBlock:
        coords = _coordinates(model, "PlaneObstacle")
        nodes = _node_indices(model, self.nodes, "PlaneObstacle.nodes")
        normal = _unit_directions(self.normal, 1, "PlaneObstacle.normal")[0]
        point = real_array(self.point, "PlaneObstacle.point").reshape(-1)
        if point.shape != normal.shape or coords.shape[1] != len(normal):
            raise InvalidInputError(
                f"PlaneObstacle: point {point.shape}, normal {normal.shape} and coordinates "
                f"(d={coords.shape[1]}) must share one dimension"
            )
        gaps = (point - coords[nodes]) @ normal
        return _node_block(model, nodes, gaps, normal, "PlaneObstacle", " / plane")


@dataclass
class ProfileObstacle:
    """A rigid obstacle whose surface is a function of the node coordinates.

    Parameters
    ----------
    profile : callable
        ``profile(coordinates) -> positions``: for node coordinates of shape (k, d), the position of
        the obstacle surface along ``direction`` (m) facing each node.
    direction : array_like, shape (d,)
        Direction from the body towards the obstacle; the gap of a node at ``x`` is
        ``profile(x) - x . direction``.
    nodes : sequence of int, optional
        Nodes that may touch the obstacle (default: all).
    """

    profile: Callable[[np.ndarray], np.ndarray]
    direction: ArrayLike
    nodes: ArrayLike | None = None

    def rows(self, model: ReducedModel) -> list[ConstraintRow]:
        """Constraint rows as ``(node, freedoms, coefficients, gap, label)`` tuples."""
        return self._row_block(model).rows()

    def _row_block(self, model: ReducedModel) -> _RowBlock:
        coords = _coordinates(model, "ProfileObstacle")
        nodes = _node_indices(model, self.nodes, "ProfileObstacle.nodes")
        direction = _unit_directions(self.direction, 1, "ProfileObstacle.direction")[0]
        if coords.shape[1] != len(direction):
            raise InvalidInputError(
                f"ProfileObstacle.direction has {len(direction)} components, "
                f"coordinates {coords.shape[1]}"
            )
        surface = real_array(self.profile(coords[nodes]), "ProfileObstacle.profile").reshape(-1)
        if surface.shape != nodes.shape or not np.all(np.isfinite(surface)):
            raise InvalidInputError(
                f"ProfileObstacle.profile must return {nodes.size} finite "
                f"values, got shape {surface.shape}"
            )
        gaps = surface - coords[nodes] @ direction
        return _node_block(model, nodes, gaps, direction, "ProfileObstacle", " / profile")


@dataclass
class NodePairs:
    """Node-to-node contact between two bodies of one model.

    The constraint of a pair ``(a, b)`` is ``(u_a - u_b) . n <= gap`` with ``n`` the direction from
    ``a`` towards ``b``: the gap closes when ``a`` moves towards ``b`` or ``b`` towards ``a``.

    Parameters
    ----------
    pairs : array_like of int, shape (k, 2)
    gaps : array_like, shape (k,)
        Initial gaps (m).
    directions : array_like, shape (d,) or (k, d)
        Directions from the first node towards the second; normalised.
    """

    pairs: ArrayLike
    gaps: ArrayLike
    directions: ArrayLike = (1.0,)

    def rows(self, model: ReducedModel) -> list[ConstraintRow]:
        """Constraint rows as ``(node, freedoms, coefficients, gap, label)`` tuples."""
        pairs = np.asarray(self.pairs)
        if pairs.ndim != 2 or pairs.shape[1] != 2:
            raise InvalidInputError(f"NodePairs.pairs must have shape (k, 2), got {pairs.shape}")
        first = _node_indices(model, pairs[:, 0], "NodePairs.pairs")
        second = _node_indices(model, pairs[:, 1], "NodePairs.pairs")
        if np.any(first == second):
            raise InvalidInputError("NodePairs.pairs pairs a node with itself")
        gaps = real_array(self.gaps, "NodePairs.gaps").reshape(-1)
        if gaps.shape != first.shape or not np.all(np.isfinite(gaps)):
            raise InvalidInputError(
                f"NodePairs.gaps must hold {first.size} finite values, got shape {gaps.shape}"
            )
        dirs = _unit_directions(self.directions, len(first), "NodePairs.directions")
        rows: list[ConstraintRow] = []
        for a, b, g, d in zip(first, second, gaps, dirs, strict=True):
            dofs = np.concatenate(
                [_node_freedoms(model, a, d, "NodePairs"), _node_freedoms(model, b, d, "NodePairs")]
            )
            rows.append((int(a), dofs, np.concatenate([d, -d]), float(g), f"pair {a}-{b}"))
        return rows


def assemble_constraints(
    model: ReducedModel, obstacles: Obstacle | Iterable[Obstacle]
) -> Constraints:
    """Stack the rows of every obstacle and pair into ``A U <= Delta``.

    Parameters
    ----------
    model : ReducedModel
    obstacles : GapObstacle, PlaneObstacle, ProfileObstacle or NodePairs, or a sequence of them

    Returns
    -------
    Constraints

    Raises
    ------
    InvalidInputError
        Something that is not an obstacle, no constraint at all, a gap beyond
        :data:`~contactqp.core.model.MAX_MAGNITUDE`, or a duplicate: one node (or pair) constrained
        twice along the same direction, which makes the Delassus operator singular. A node may
        meet several obstacles along different directions (a corner, or a slot between two
        walls with opposite normals).
    """
    import scipy.sparse

    blocks = [
        block for obstacle in _obstacle_list(obstacles) for block in _row_blocks(obstacle, model)
    ]
    gaps = np.concatenate([block.gaps for block in blocks]) if blocks else np.zeros(0)
    if not gaps.size:
        raise InvalidInputError("obstacles define no constraint: give at least one node")
    labels = [label for block in blocks for label in block.labels]
    if np.max(np.abs(gaps)) > MAX_MAGNITUDE:
        worst = int(np.argmax(np.abs(gaps)))
        raise InvalidInputError(
            f"the gap of {labels[worst]} is {gaps[worst]:.3g} m, beyond "
            f"{MAX_MAGNITUDE:g}: rescale the units"
        )
    _refuse_duplicates(blocks, labels)
    widths = np.concatenate([np.full(b.gaps.size, b.freedoms.shape[1]) for b in blocks])
    indptr = np.concatenate(([0], np.cumsum(widths)))
    indices = np.concatenate([block.freedoms.ravel() for block in blocks])
    data = np.concatenate([block.coefficients.ravel() for block in blocks])
    matrix = scipy.sparse.csr_matrix((data, indices, indptr), shape=(gaps.size, model.n_freedoms))
    return Constraints(
        matrix=matrix,
        gaps=gaps,
        nodes=np.concatenate([block.nodes for block in blocks]).astype(int, copy=False),
        labels=labels,
    )


def _row_blocks(obstacle: Obstacle, model: ReducedModel) -> list[_RowBlock]:
    """The rows of ``obstacle`` as blocks: the built-in obstacles' own, else its
    :meth:`~Obstacle.rows`, consecutive rows of one width in one block."""
    own = getattr(obstacle, "_row_block", None)
    if own is not None:
        return [own(model)]
    blocks = []
    for _, group in itertools.groupby(obstacle.rows(model), key=lambda row: len(row[1])):
        rows = list(group)
        blocks.append(
            _RowBlock(
                nodes=np.array([row[0] for row in rows], dtype=int),
                freedoms=np.array([row[1] for row in rows], dtype=np.intp),
                coefficients=np.array([row[2] for row in rows], dtype=float),
                gaps=np.array([row[3] for row in rows], dtype=float),
                labels=[row[4] for row in rows],
            )
        )
    return blocks


def _obstacle_list(obstacles: Obstacle | Iterable[Obstacle]) -> list[Obstacle]:
    """``obstacles`` as a list of objects with ``rows``: one obstacle alone is accepted."""
    if isinstance(obstacles, Obstacle):
        return [obstacles]
    try:
        listed = list(obstacles)
    except TypeError:
        raise InvalidInputError(
            f"obstacles must be an obstacle or a sequence of obstacles, got "
            f"{type(obstacles).__name__}"
        ) from None
    for position, obstacle in enumerate(listed):
        if not isinstance(obstacle, Obstacle):
            raise InvalidInputError(
                f"obstacles[{position}] is a {type(obstacle).__name__}, not an obstacle "
                f"(GapObstacle, PlaneObstacle, ProfileObstacle or NodePairs)"
            )
    return listed


#: Rows whose unit coefficient vectors on the same freedoms agree to this many decimals are one
#: constraint given twice.
_DUPLICATE_DECIMALS = 9


def _refuse_duplicates(blocks: list[_RowBlock], labels: list[str]) -> None:
    """Raise if two rows constrain the same freedoms along the same direction.

    Rows are compared by width, vectorised: each row's freedoms sorted, with its unit
    coefficients rounded to :data:`_DUPLICATE_DECIMALS`.
    """
    by_width: dict[int, list[tuple[np.ndarray, _RowBlock]]] = {}
    offset = 0
    for block in blocks:
        count = block.gaps.size
        by_width.setdefault(block.freedoms.shape[1], []).append(
            (np.arange(offset, offset + count), block)
        )
        offset += count
    for parts in by_width.values():
        positions = np.concatenate([where for where, _ in parts])
        dofs = np.concatenate([block.freedoms for _, block in parts]).astype(float)
        coefficients = np.concatenate([block.coefficients for _, block in parts])
        order = np.argsort(dofs, axis=1, kind="stable")
        dofs = np.take_along_axis(dofs, order, axis=1)
        unit = np.take_along_axis(coefficients, order, axis=1)
        unit = np.round(unit / np.linalg.norm(unit, axis=1, keepdims=True), _DUPLICATE_DECIMALS)
        keys = np.hstack([dofs, unit + 0.0])  # + 0.0: -0.0 and 0.0 are one direction
        _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
        if np.all(counts == 1):
            continue
        twice = np.flatnonzero(counts[inverse.ravel()] > 1)
        group = inverse.ravel()[twice[0]]
        first, second = (positions[i] for i in twice[inverse.ravel()[twice] == group][:2])
        label = labels[second]
        raise InvalidInputError(
            f"{label} is constrained twice along the same direction (constraints {first} "
            f"and {second}, '{labels[first]}' and '{label}'): the contact operator would "
            f"be singular; give each node and direction once (keep the smaller gap)"
        )


def tangent_basis(normals: ArrayLike) -> np.ndarray:
    """Deterministic orthonormal tangents completing unit normals.

    2-D: ``t = (-n_y, n_x)`` (the normal turned by +90 degrees). 3-D: the branchless basis of
    Duff et al. (2017), with ``t_1 x t_2 = n``; the frame is continuous except across ``n_z = 0``.
    In 1-D there is no tangent.

    Parameters
    ----------
    normals : array_like, shape (k, d)
        Unit vectors, ``d`` in 1..3.

    Returns
    -------
    ndarray, shape (k, d - 1, d)

    References
    ----------
    T. Duff et al., "Building an orthonormal basis, revisited", JCGT 6(1), 2017.
    """
    n = np.asarray(normals, dtype=float)
    d = n.shape[1]
    if d == 1:
        return np.zeros((len(n), 0, 1))
    if d == 2:
        return np.stack([-n[:, 1], n[:, 0]], axis=1)[:, None, :]
    x, y, z = n.T
    s = np.where(z >= 0.0, 1.0, -1.0)
    a = -1.0 / (s + z)
    b = x * y * a
    t1 = np.stack([1.0 + s * x * x * a, s * b, -s * x], axis=1)
    t2 = np.stack([b, s + y * y * a, -y], axis=1)
    return np.stack([t1, t2], axis=1)


@dataclass(frozen=True)
class LocalFrames:
    """Local contact frames and the operator to local coordinates.

    Attributes
    ----------
    normals : ndarray, shape (k, d)
        Unit direction of each contact towards the obstacle (the constraint's direction).
    tangents : ndarray, shape (k, d - 1, d)
        Orthonormal tangents, from :func:`tangent_basis`.
    operator : scipy.sparse.csr_matrix, shape (d * k, n_freedoms)
        ``H``: rows ``-n, t_1[, t_2]`` per contact. Local displacements are ``H U`` and the
        contact forces on the body ``H^T r`` (``r_N >= 0`` compressive, ``r_T`` the tangential
        force on the body, or on the first node of a pair).
    """

    normals: np.ndarray
    tangents: np.ndarray
    operator: scipy.sparse.csr_matrix

    @property
    def dim(self) -> int:
        """Size ``d`` of each contact block."""
        return int(self.normals.shape[1])


def local_frames(model: ReducedModel, constraints: Constraints) -> LocalFrames:
    """Frames and ``H`` for constraints whose nodes all have the same number of freedoms.

    Every row of ``A`` must be made of node blocks ``+n`` (its own node) or ``-n`` (the other
    node of a pair), as built by the obstacles of this module.

    Raises
    ------
    InvalidInputError
        The contact nodes have different numbers of freedoms, or a row is not made of ``+-n``
        blocks.
    """
    import scipy.sparse

    A = constraints.matrix
    counts = model.dofs_per_node[constraints.nodes]
    if np.any(counts != counts[0]):
        raise InvalidInputError(
            "local frames need contact nodes with one number of freedoms, got "
            f"{sorted(set(counts.tolist()))}"
        )
    d, m = int(counts[0]), constraints.n_constraints
    own = model.offsets[constraints.nodes][:, None] + np.arange(d)
    normals = np.asarray(A[np.repeat(np.arange(m), d), own.ravel()]).reshape(m, d)
    # freedom -> (node, component) incidence: block sign s_ik = (A row i on node k) . n_i
    node_of = np.searchsorted(model.offsets, np.arange(model.n_freedoms), side="right") - 1
    component = np.arange(model.n_freedoms) - model.offsets[node_of]
    coo = A.tocoo()
    inside = component[coo.col] < d
    if not np.all(inside):
        raise InvalidInputError(
            f"constraint row {coo.row[~inside][0]} touches a node with more than {d} freedoms"
        )
    comp = component[coo.col]
    signs = scipy.sparse.coo_matrix(
        (coo.data * normals[coo.row, comp], (coo.row, node_of[coo.col])), shape=(m, model.n_nodes)
    ).tocsr()
    signed = signs[coo.row, node_of[coo.col]].A1
    if not (
        np.allclose(np.abs(signs.data[signs.data != 0]), 1.0)
        and np.allclose(coo.data, signed * normals[coo.row, comp])
    ):
        raise InvalidInputError("a constraint row is not made of node blocks +-n: no local frame")
    tangents = tangent_basis(normals)
    rows = [-A]
    for j in range(d - 1):
        rows.append(
            scipy.sparse.csr_matrix(
                (signed * tangents[coo.row, j, comp], (coo.row, coo.col)), shape=A.shape
            )
        )
    # interleave: local row i*d + c is row i of block c
    order = (np.arange(d)[None, :] * m + np.arange(m)[:, None]).ravel()
    operator = scipy.sparse.vstack(rows).tocsr()[order]
    return LocalFrames(normals=normals, tangents=tangents, operator=operator)

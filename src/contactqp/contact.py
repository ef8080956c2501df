"""Unilateral constraints ``A U <= Delta``: rigid obstacles and node-to-node pairs.

Each constraint row measures the displacement of a node (or the relative displacement of two
nodes) along a unit direction pointing towards the obstacle (or the other body); ``Delta`` is the
initial gap along that direction, in metres. Small displacements are assumed: the directions do not
rotate and the gaps are linear in the displacements.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np
import scipy.sparse

from .errors import InvalidInputError
from .model import ReducedModel

__all__ = [
    "Constraints",
    "PlaneObstacle",
    "GapObstacle",
    "ProfileObstacle",
    "NodePairs",
    "assemble_constraints",
]


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
    labels: list = field(default_factory=list)

    @property
    def n_constraints(self) -> int:
        """Number of rows ``m``."""
        return len(self.gaps)


def _unit_directions(directions, count: int, name: str) -> np.ndarray:
    dirs = np.asarray(directions, dtype=float)
    if dirs.ndim == 1:
        dirs = np.tile(dirs, (count, 1))
    if dirs.ndim != 2 or dirs.shape[0] != count or dirs.shape[1] not in (1, 2, 3):
        raise InvalidInputError(
            f"{name} must have shape (d,) or ({count}, d) with d in 1..3, got {np.shape(directions)}"
        )
    if not np.all(np.isfinite(dirs)):
        raise InvalidInputError(f"{name} contains NaN or inf")
    norms = np.linalg.norm(dirs, axis=1)
    if np.any(norms == 0.0):
        raise InvalidInputError(f"{name} has a zero vector at row {int(np.argmin(norms))}")
    return dirs / norms[:, None]


def _node_indices(model: ReducedModel, nodes, name: str) -> np.ndarray:
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


def _node_rows(model: ReducedModel, nodes, gaps, directions, name: str, label: str):
    """One constraint row per node: ``(node, freedoms, direction, gap, label)``.

    ``directions`` is one unit vector for all nodes, shape (d,), or one per node, shape (k, d).
    """
    directions = np.broadcast_to(directions, (len(nodes), np.shape(directions)[-1]))
    return [(int(k), _node_freedoms(model, k, d, name), d, float(g), f"node {k}{label}")
            for k, g, d in zip(nodes, gaps, directions)]


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

    nodes: Sequence[int]
    gaps: Sequence[float]
    directions: Sequence = (1.0,)

    def rows(self, model: ReducedModel):
        """Constraint rows as ``(node, freedoms, coefficients, gap, label)`` tuples."""
        nodes = _node_indices(model, self.nodes, "GapObstacle.nodes")
        gaps = np.asarray(self.gaps, dtype=float).reshape(-1)
        if gaps.shape != nodes.shape:
            raise InvalidInputError(
                f"GapObstacle.gaps has {gaps.size} values for {nodes.size} nodes"
            )
        if not np.all(np.isfinite(gaps)):
            raise InvalidInputError("GapObstacle.gaps contains NaN or inf")
        dirs = _unit_directions(self.directions, len(nodes), "GapObstacle.directions")
        return _node_rows(model, nodes, gaps, dirs, "GapObstacle", "")


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

    point: Sequence[float]
    normal: Sequence[float]
    nodes: Sequence[int] | None = None

    def rows(self, model: ReducedModel):
        """Constraint rows as ``(node, freedoms, coefficients, gap, label)`` tuples."""
        coords = _coordinates(model, "PlaneObstacle")
        nodes = _node_indices(model, self.nodes, "PlaneObstacle.nodes")
        normal = _unit_directions(self.normal, 1, "PlaneObstacle.normal")[0]
        point = np.asarray(self.point, dtype=float).reshape(-1)
        if point.shape != normal.shape or coords.shape[1] != len(normal):
            raise InvalidInputError(
                f"PlaneObstacle: point {point.shape}, normal {normal.shape} and coordinates "
                f"(d={coords.shape[1]}) must share one dimension"
            )
        gaps = (point - coords[nodes]) @ normal
        return _node_rows(model, nodes, gaps, normal, "PlaneObstacle", " / plane")


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
    direction: Sequence[float]
    nodes: Sequence[int] | None = None

    def rows(self, model: ReducedModel):
        """Constraint rows as ``(node, freedoms, coefficients, gap, label)`` tuples."""
        coords = _coordinates(model, "ProfileObstacle")
        nodes = _node_indices(model, self.nodes, "ProfileObstacle.nodes")
        direction = _unit_directions(self.direction, 1, "ProfileObstacle.direction")[0]
        if coords.shape[1] != len(direction):
            raise InvalidInputError(
                f"ProfileObstacle.direction has {len(direction)} components, coordinates {coords.shape[1]}"
            )
        surface = np.asarray(self.profile(coords[nodes]), dtype=float).reshape(-1)
        if surface.shape != nodes.shape or not np.all(np.isfinite(surface)):
            raise InvalidInputError(
                f"ProfileObstacle.profile must return {nodes.size} finite values, got shape {surface.shape}"
            )
        gaps = surface - coords[nodes] @ direction
        return _node_rows(model, nodes, gaps, direction, "ProfileObstacle", " / profile")


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

    pairs: Sequence[Sequence[int]]
    gaps: Sequence[float]
    directions: Sequence = (1.0,)

    def rows(self, model: ReducedModel):
        """Constraint rows as ``(node, freedoms, coefficients, gap, label)`` tuples."""
        pairs = np.asarray(self.pairs)
        if pairs.ndim != 2 or pairs.shape[1] != 2:
            raise InvalidInputError(f"NodePairs.pairs must have shape (k, 2), got {pairs.shape}")
        first = _node_indices(model, pairs[:, 0], "NodePairs.pairs")
        second = _node_indices(model, pairs[:, 1], "NodePairs.pairs")
        if np.any(first == second):
            raise InvalidInputError("NodePairs.pairs pairs a node with itself")
        gaps = np.asarray(self.gaps, dtype=float).reshape(-1)
        if gaps.shape != first.shape or not np.all(np.isfinite(gaps)):
            raise InvalidInputError(
                f"NodePairs.gaps must hold {first.size} finite values, got shape {gaps.shape}"
            )
        dirs = _unit_directions(self.directions, len(first), "NodePairs.directions")
        rows = []
        for a, b, g, d in zip(first, second, gaps, dirs):
            dofs = np.concatenate([_node_freedoms(model, a, d, "NodePairs"),
                                   _node_freedoms(model, b, d, "NodePairs")])
            rows.append((int(a), dofs, np.concatenate([d, -d]), float(g), f"pair {a}-{b}"))
        return rows


def assemble_constraints(model: ReducedModel, obstacles) -> Constraints:
    """Stack the rows of every obstacle and pair into ``A U <= Delta``.

    Parameters
    ----------
    model : ReducedModel
    obstacles : sequence of GapObstacle, PlaneObstacle, ProfileObstacle or NodePairs

    Returns
    -------
    Constraints
    """
    rows = [row for obstacle in obstacles for row in obstacle.rows(model)]
    if not rows:
        raise InvalidInputError("obstacles define no constraint: give at least one node")
    indptr = np.cumsum([0] + [len(r[1]) for r in rows])
    indices = np.concatenate([r[1] for r in rows])
    data = np.concatenate([r[2] for r in rows])
    matrix = scipy.sparse.csr_matrix((data, indices, indptr), shape=(len(rows), model.n_freedoms))
    return Constraints(
        matrix=matrix,
        gaps=np.array([r[3] for r in rows]),
        nodes=np.array([r[0] for r in rows], dtype=int),
        labels=[r[4] for r in rows],
    )

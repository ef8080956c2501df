"""Plane Euler-Bernoulli frames: rods and beams with axial and bending stiffness.

Each node carries three freedoms, ``ux`` and ``uy`` (m) and the rotation ``rz`` (rad); each
element is the classical two-node frame element (linear axial, cubic Hermite bending), whose nodal
displacements are exact for loads applied at the nodes. The stiffness is assembled as a sparse
matrix; the flexibility of chosen nodes follows by static condensation
(:func:`~contactqp.compliance.condensation.condense`).

References
----------
J. S. Przemieniecki, *Theory of Matrix Structural Analysis*, McGraw-Hill, 1968, ch. 5.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable, Mapping, Sequence

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ..core.model import finite_array
from ..errors import InvalidInputError
from .condensation import condense, factorize

__all__ = ["Frame2D", "frame_element_stiffness", "COMPONENTS"]

#: Freedom names of a node, in their order in the global vectors.
COMPONENTS = ("ux", "uy", "rz")
_LETTERS = {"x": 0, "y": 1, "r": 2}


def frame_element_stiffness(
    start: ArrayLike, end: ArrayLike, young: float, area: float, inertia: float
) -> np.ndarray:
    """Stiffness of one plane frame element in global coordinates.

    Parameters
    ----------
    start, end : array_like, shape (2,)
        Node coordinates (m).
    young : float
        Young's modulus ``E`` (Pa).
    area : float
        Cross-section area ``A`` (m^2).
    inertia : float
        Second moment of area ``I`` (m^4).

    Returns
    -------
    ndarray, shape (6, 6)
        For the freedoms ``(ux, uy, rz)`` of ``start`` then of ``end`` (N/m, N, N m).
    """
    delta = np.asarray(end, dtype=float) - np.asarray(start, dtype=float)
    length = float(np.hypot(*delta))
    c, s = delta / length
    a = young * area / length
    b = young * inertia / length**3
    L = length
    local = np.array(
        [
            [a, 0, 0, -a, 0, 0],
            [0, 12 * b, 6 * b * L, 0, -12 * b, 6 * b * L],
            [0, 6 * b * L, 4 * b * L**2, 0, -6 * b * L, 2 * b * L**2],
            [-a, 0, 0, a, 0, 0],
            [0, -12 * b, -6 * b * L, 0, 12 * b, -6 * b * L],
            [0, 6 * b * L, 2 * b * L**2, 0, -6 * b * L, 4 * b * L**2],
        ]
    )
    rotation = np.zeros((6, 6))
    block = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    rotation[:3, :3] = rotation[3:, 3:] = block
    return rotation.T @ local @ rotation


def _positive(value: ArrayLike, name: str, count: int) -> np.ndarray:
    """``value`` as ``count`` positive finite floats (one value is repeated)."""
    try:
        array = np.broadcast_to(np.asarray(value, dtype=float), (count,))
    except (TypeError, ValueError):
        array = None
    if array is None or not np.all(np.isfinite(array)) or np.any(array <= 0):
        raise InvalidInputError(
            f"{name} must be one positive finite value or {count} of them (one per element), "
            f"got {np.shape(value) or value}"
        )
    return array


def _node_number(node: object, n_nodes: int, what: str = "node") -> int:
    """``node`` as a whole index in ``-n_nodes..n_nodes - 1``; InvalidInputError otherwise."""
    if (
        isinstance(node, (bool, np.bool_))
        or not isinstance(node, numbers.Real)
        or not float(node).is_integer()
    ):
        raise InvalidInputError(f"{what} must be a whole node index, got {node!r}")
    index = int(float(node))
    if not -n_nodes <= index < n_nodes:
        raise InvalidInputError(f"{what} {node} outside the {n_nodes} nodes")
    return index


class Frame2D:
    """A plane frame of Euler-Bernoulli elements with fixations.

    Parameters
    ----------
    coordinates : array_like, shape (n_nodes, 2)
        Node positions (m).
    elements : array_like of int, shape (n_elements, 2)
        The two nodes of each element.
    young, area, inertia : float or array_like, shape (n_elements,)
        ``E`` (Pa), ``A`` (m^2) and ``I`` (m^4), per element or for all.
    fixed : mapping of int to str
        ``{node: letters}``: the freedoms held at zero, ``"x"``, ``"y"`` and ``"r"`` (rotation);
        ``"xyr"`` clamps the node. Negative node indices count from the end.

    Raises
    ------
    InvalidInputError
        Wrong shapes, non-positive properties, zero-length elements or unknown fixations.
    """

    def __init__(
        self,
        coordinates: ArrayLike,
        elements: ArrayLike,
        young: ArrayLike,
        area: ArrayLike,
        inertia: ArrayLike,
        fixed: Mapping[int, str] | None = None,
    ) -> None:
        coords = finite_array(coordinates, "coordinates", 2)
        if coords.shape[1] != 2 or coords.shape[0] < 2:
            raise InvalidInputError(f"coordinates must have shape (n >= 2, 2), got {coords.shape}")
        conn = np.asarray(elements)
        if (
            conn.ndim != 2
            or conn.shape[1] != 2
            or conn.shape[0] == 0
            or not np.issubdtype(conn.dtype, np.integer)
        ):
            raise InvalidInputError(
                f"elements must be integer node pairs of shape (m, 2), got {conn.shape}"
            )
        if conn.min() < 0 or conn.max() >= len(coords):
            raise InvalidInputError(f"elements refer to nodes outside 0..{len(coords) - 1}")
        lengths = np.linalg.norm(coords[conn[:, 1]] - coords[conn[:, 0]], axis=1)
        if np.any(lengths == 0.0):
            raise InvalidInputError(f"element {int(np.argmin(lengths))} has zero length")
        self.coordinates = coords
        self.elements = conn.astype(int)
        self.young = _positive(young, "young", len(conn))
        self.area = _positive(area, "area", len(conn))
        self.inertia = _positive(inertia, "inertia", len(conn))
        held: list[int] = []
        for node, letters in dict(fixed or {}).items():
            _node_number(node, len(coords), "fixed node")
            if not isinstance(letters, str) or not letters or set(letters) - set(_LETTERS):
                raise InvalidInputError(
                    f"fixed[{node}] must be letters among 'x', 'y', 'r', got {letters!r}"
                )
            held += [3 * (int(node) % len(coords)) + _LETTERS[c] for c in letters]
        self.fixed = np.unique(np.array(held, dtype=int))
        self.free = np.setdiff1d(np.arange(3 * len(coords)), self.fixed)
        self._position = np.full(3 * len(coords), -1)
        self._position[self.free] = np.arange(self.free.size)

    @classmethod
    def straight(
        cls,
        length: float,
        n_elements: int,
        young: ArrayLike,
        area: ArrayLike,
        inertia: ArrayLike,
        fixed: Mapping[int, str] | None = None,
    ) -> Frame2D:
        """A straight rod along ``x`` from 0 to ``length`` (m), in equal elements."""
        if (
            not isinstance(length, numbers.Real)
            or not isinstance(n_elements, numbers.Real)
            or not (np.isfinite(length) and length > 0)
            or int(n_elements) != n_elements
            or n_elements < 1
        ):
            raise InvalidInputError(
                f"length must be > 0 and n_elements a whole number >= 1, got {length}, {n_elements}"
            )
        x = np.linspace(0.0, length, int(n_elements) + 1)
        nodes = np.column_stack([x, np.zeros_like(x)])
        elements = np.column_stack([np.arange(n_elements), np.arange(1, n_elements + 1)])
        return cls(nodes, elements, young, area, inertia, fixed)

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return len(self.coordinates)

    @property
    def labels(self) -> list[str]:
        """Names of the free freedoms, e.g. ``"node 3 uy"``."""
        return [f"node {k // 3} {COMPONENTS[k % 3]}" for k in self.free]

    def index(self, node: int, component: str) -> int:
        """Position of a freedom (``"ux"``, ``"uy"`` or ``"rz"``) in the free vectors."""
        return self._free_position(node, component)

    def _free_position(self, node: object, component: str) -> int:
        """:meth:`index` of a node not yet known to be a whole number (refused if it is not)."""
        if component not in COMPONENTS:
            raise InvalidInputError(f"component must be one of {COMPONENTS}, got {component!r}")
        number = _node_number(node, self.n_nodes)
        if number < 0:
            raise InvalidInputError(f"node {number} outside 0..{self.n_nodes - 1}")
        position = int(self._position[3 * number + COMPONENTS.index(component)])
        if position < 0:
            raise InvalidInputError(f"node {number} {component} is fixed")
        return position

    def full_stiffness(self) -> sp.csr_matrix:
        """Stiffness of all ``3 n_nodes`` freedoms, fixations ignored (singular), shape (3n, 3n)."""
        blocks = [
            frame_element_stiffness(self.coordinates[a], self.coordinates[b], young, area, inertia)
            for (a, b), young, area, inertia in zip(
                self.elements, self.young, self.area, self.inertia, strict=True
            )
        ]
        dofs = (3 * self.elements[:, :, None] + np.arange(3)).reshape(-1, 6)
        rows = np.repeat(dofs, 6, axis=1).ravel()
        cols = np.tile(dofs, (1, 6)).ravel()
        n = 3 * self.n_nodes
        return sp.csr_matrix((np.ravel(blocks), (rows, cols)), shape=(n, n))

    def stiffness(self) -> sp.csc_matrix:
        """Stiffness of the free freedoms, shape (n_free, n_free), in the order of :attr:`free`."""
        return self.full_stiffness()[self.free][:, self.free].tocsc()

    def load_vector(self, loads: Iterable[Sequence[float]]) -> np.ndarray:
        """Free-freedom load vector from ``[(node, fx, fy), ...]`` or ``(node, fx, fy, mz)`` rows.

        Forces in N, moments in N m; loads on fixed freedoms are rejected.
        """
        vector = np.zeros(self.free.size)
        for row in loads:
            node: object = None
            values: list[float] = []
            try:
                node, *values = row
                finite = bool(np.all(np.isfinite(np.asarray(values, dtype=float))))
            except (TypeError, ValueError):
                finite = False
            if len(values) not in (2, 3) or not finite:
                raise InvalidInputError(
                    f"a load must be (node, fx, fy) or (node, fx, fy, mz) with finite values, "
                    f"got {row!r}"
                )
            for component, value in zip(COMPONENTS, values, strict=False):  # mz is optional
                if value != 0.0:
                    vector[self._free_position(node, component)] += value
        return vector

    def displacements(self, load_vector: ArrayLike) -> np.ndarray:
        """Nodal displacements ``(ux, uy, rz)``, shape (n_nodes, 3), under a free-freedom load.

        Fixed freedoms are zero.

        Raises
        ------
        InvalidInputError
            ``load_vector`` is not ``n_free`` finite values.
        RigidBodyModeError
            The fixations leave the frame free to move (see
            :func:`~contactqp.compliance.condensation.factorize`).
        """
        loads = np.asarray(load_vector, dtype=float)
        if loads.shape != (self.free.size,) or not np.all(np.isfinite(loads)):
            raise InvalidInputError(
                f"load_vector must be {self.free.size} finite values (one per "
                f"free freedom), got shape {loads.shape}"
            )
        full = np.zeros(3 * self.n_nodes)
        full[self.free] = factorize(self.stiffness(), labels=self.labels).solve(loads)
        return full.reshape(-1, 3)

    def compliance(self, nodes: Iterable[int], components: str = "xy") -> np.ndarray:
        """Flexibility of ``components`` (letters ``x``, ``y``, ``r``) of ``nodes``, node by node.

        Returns
        -------
        ndarray, shape (len(nodes) * len(components), same)
            In m/N, rad/(N m) and their mixed units, from static condensation of
            :meth:`stiffness` (:func:`~contactqp.compliance.condensation.condense`, whose pivot
            test is relative to each freedom's own diagonal, so the ten decades between the
            stiffness of translations and rotations need no scaling).

        Raises
        ------
        RigidBodyModeError
            The fixations leave the frame free to move.
        """
        if not components or set(components) - set(_LETTERS):
            raise InvalidInputError(
                f"components must be letters among 'x', 'y', 'r', got {components!r}"
            )
        freedoms = np.array(
            [self.index(k, COMPONENTS[_LETTERS[c]]) for k in nodes for c in components], dtype=int
        )
        return condense(self.stiffness(), freedoms, labels=self.labels)

    def __repr__(self) -> str:
        return (
            f"Frame2D({self.n_nodes} nodes, {len(self.elements)} elements, "
            f"{self.free.size} free freedoms)"
        )

"""What an assembly file gives: :class:`AssemblyInput`, ready to build the assembly."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import InvalidInputError
from ..fastening import Assembly, AssemblyPart, Fastener, InterfacePairs
from .gaps import InterpolationError
from .pairing import UnmatchedNodes
from .parts import PartInput

__all__ = ["AssemblyInput", "load_vector"]


@dataclass(frozen=True)
class AssemblyInput:
    """An assembly file, read: parts, pairs, gaps, fasteners, friction, loads, solver (SI).

    Attributes
    ----------
    name : str
    path : Path
        The assembly file.
    parts : tuple of PartInput
    interfaces : tuple of InterfacePairs
    unmatched : tuple of UnmatchedNodes
        Nodes proximity pairing left without a partner (``describe()`` gives a line each).
    gaps : ndarray, shape (k,)
        Nominal gap of every pair (m), interfaces concatenated in order.
    variation : GapSource or None
        Gap fields of the variation study (``realisations(indices)``), or None.
    variation_description : str
        One line saying where the variation comes from ("" without one).
    interpolation_error : InterpolationError or None
        Leave-one-out error of the interpolated gaps (None when they were not interpolated).
    fasteners : tuple of Fastener
        In installation order.
    mu : ndarray, shape (k,)
    facets : int or None
        Facets of the polygonal cone; None for the exact cone.
    load_steps : tuple of (str, ndarray)
        ``(label, total load over the assembly's freedoms, N)`` after fastening, in order.
    shim_tolerance : float or None
        Gaps above it (m) need a shim.
    method : str
        The solver method (the registry's default for the kind when none is named).
    kind : str
        The problem kind the method was checked against.
    options : dict
        The method's options from ``[solver]``.
    """

    name: str
    path: Path
    parts: tuple[PartInput, ...]
    interfaces: tuple[InterfacePairs, ...]
    unmatched: tuple[UnmatchedNodes, ...]
    gaps: np.ndarray
    variation: Any
    variation_description: str
    interpolation_error: InterpolationError | None
    fasteners: tuple[Fastener, ...]
    mu: np.ndarray
    facets: int | None
    load_steps: tuple[tuple[str, np.ndarray], ...]
    shim_tolerance: float | None
    method: str
    kind: str
    options: dict = field(default_factory=dict)

    @property
    def n_pairs(self) -> int:
        """Pairs over all interfaces."""
        return int(self.gaps.size)

    @property
    def points(self) -> np.ndarray:
        """``(k, 3)`` pair positions (m): the mean of each pair's two nodes."""
        return pair_points(self.parts, self.interfaces)

    def part(self, name: str) -> PartInput:
        """The part called ``name``."""
        for part in self.parts:
            if part.name == name:
                return part
        raise InvalidInputError(f"no part named {name!r}")

    def to_assembly(self) -> Assembly:
        """The :class:`~contactqp.applications.fastening.Assembly` of this input."""
        parts = [AssemblyPart(p.name, p.model, p.coordinates) for p in self.parts]
        return Assembly(parts, self.interfaces, self.fasteners, mu=self.mu, facets=self.facets)


def pair_points(parts, interfaces) -> np.ndarray:
    """``(k, 3)`` mean position of each pair's two nodes (m)."""
    by_name = {part.name: part for part in parts}
    blocks = [
        0.5
        * (
            by_name[i.first].coordinates[i.nodes[:, 0]]
            + by_name[i.second].coordinates[i.nodes[:, 1]]
        )
        for i in interfaces
    ]
    return np.vstack(blocks) if blocks else np.zeros((0, 3))


def load_vector(parts, part: str, nodes, force) -> np.ndarray:
    """The total ``force`` (N, shape (3,)) shared equally by ``nodes`` of ``part``, over the
    assembly's freedoms (the parts' freedoms concatenated in part order, node by node).

    A node with 3 freedoms takes ``(F_x, F_y, F_z)``, one with 2 ``(F_x, F_y)``, one with 1
    (a plate's deflection) ``F_z``; a force component a node has no freedom for is refused.
    The same layout as :meth:`contactqp.applications.fastening.Assembly.load_vector` (the
    file's load steps are read before the assembly is built).
    """
    offsets, start = {}, 0
    for item in parts:
        offsets[item.name] = start
        start += item.model.n_freedoms
    owner = next(p for p in parts if p.name == part)
    force = np.asarray(force, dtype=float)
    nodes = np.asarray(nodes, dtype=int)
    share = force / len(nodes)
    vector = np.zeros(start)
    for node in nodes:
        count = int(owner.model.dofs_per_node[node])
        axes = {3: [0, 1, 2], 2: [0, 1], 1: [2]}[count]
        dropped = np.delete(share, axes)
        if np.any(dropped != 0.0):
            raise InvalidInputError(
                f"node {node} of part '{part}' has {count} freedom(s): it takes no force "
                "along the other axes"
            )
        first = offsets[part] + int(owner.model.offsets[node])
        vector[first : first + count] += share[axes]
    return vector

"""Two thin parts stacked for fastening: the part, the assembly and its reduced model.

Shared by :mod:`~contactqp.applications.riveting` (Kirchhoff plates, out-of-plane only) and
:mod:`~contactqp.applications.riveting_friction` (3-D elastic blocks). The ``upper`` part lies
on the ``lower`` one, same outline; their facing surfaces meet over a grid of ``k`` contact
pairs. The reduced model has ``2 k`` nodes: ``0 .. k-1`` on the lower part, ``k .. 2k-1`` on the
upper one; pair ``i`` is ``(i, k + i)`` with the direction ``+z``
(:class:`~contactqp.core.contact.NodePairs`), and pair ``i + nx j`` is at grid position
``(i, j)`` (along ``x``, along ``y``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..core.contact import NodePairs
from ..core.model import ReducedModel, finite_array
from ..errors import InvalidInputError

__all__ = ["Part", "StackedParts", "StackedModel"]


@dataclass(frozen=True)
class Part:
    """A thin isotropic part ``[0, length] x [0, width] x [0, thickness]`` (m).

    Defaults: a 200 x 100 x 2 mm aluminium plate (``E = 70 GPa`` in Pa, ``nu = 0.33``).
    """

    length: float = 0.200
    width: float = 0.100
    thickness: float = 0.002
    young: float = 70e9
    poisson: float = 0.33

    @property
    def rigidity(self) -> float:
        """Flexural rigidity ``D = E t^3 / (12 (1 - nu^2))`` (N m)."""
        return self.young * self.thickness**3 / (12.0 * (1.0 - self.poisson**2))


@dataclass(frozen=True)
class StackedParts:
    """Two parts of the same outline, ``upper`` lying on ``lower``: the base of an assembly."""

    lower: Part = Part()
    upper: Part = Part()

    def check_outline(self) -> None:
        """Raise :class:`~contactqp.errors.InvalidInputError` unless both parts have the same
        length and width."""
        if (self.lower.length, self.lower.width) != (self.upper.length, self.upper.width):
            raise InvalidInputError("lower and upper parts must have the same length and width")

    @property
    def thickness(self) -> float:
        """The thinner part's thickness (m): the scale of a plausible gap or overlap."""
        return min(self.lower.thickness, self.upper.thickness)


class StackedModel:
    """The reduced model of two stacked parts over a grid of contact pairs (module notes).

    Attributes
    ----------
    assembly : StackedParts
    model : ReducedModel
        ``2 k`` nodes, lower part first; the last freedom of a node is ``u_z`` (m).
    points : ndarray, shape (k, 2)
        In-plane position of each pair (m).
    """

    def __init__(self, assembly: StackedParts, model: ReducedModel, points, grid: tuple[int, int]):
        self.assembly, self.model, self.points = assembly, model, points
        self._grid = (int(grid[0]), int(grid[1]))
        if self._grid[0] * self._grid[1] != len(points):
            raise InvalidInputError(f"a {grid} grid does not hold {len(points)} pairs")

    @property
    def n_pairs(self) -> int:
        """Number of contact pairs ``k``."""
        return len(self.points)

    @property
    def grid(self) -> tuple[int, int]:
        """Pairs along ``x`` and ``y``."""
        return self._grid

    def pair(self, i: int, j: int) -> int:
        """Index of the pair at grid position ``(i, j)`` (along ``x``, along ``y``)."""
        nx, ny = self.grid
        if not (0 <= i < nx and 0 <= j < ny):
            raise InvalidInputError(f"pair ({i}, {j}) is outside the {nx} x {ny} grid")
        return int(i) + nx * int(j)

    @property
    def thickness(self) -> float:
        """The thinner part's thickness (m): the scale of a plausible gap or overlap."""
        return self.assembly.thickness

    def check_gaps(self, gaps: ArrayLike, what: str = "gaps") -> np.ndarray:
        """``gaps`` (m) as a finite array of shape (k,); an overlap (negative gap) deeper than
        the thinner part is physically absurd and refused.

        Raises
        ------
        InvalidInputError
            Wrong shape, NaN or inf, or an overlap beyond the part thickness; ``what`` names
            the input in the message.
        """
        gaps = finite_array(gaps, what, 1)
        if gaps.shape != (self.n_pairs,):
            raise InvalidInputError(f"{what} must have {self.n_pairs} values, got {gaps.size}")
        deepest = float(gaps.min())
        if deepest < -self.thickness:
            raise InvalidInputError(
                f"{what}: an overlap of {-deepest * 1e3:.4g} mm is deeper than the "
                f"{self.thickness * 1e3:.4g} mm plates (a negative gap is interference)"
            )
        return gaps

    def node_pairs(self, gaps: ArrayLike) -> NodePairs:
        """The interface as :class:`NodePairs` for initial gaps ``gaps`` (m, shape (k,))."""
        k = self.n_pairs
        direction = np.eye(int(self.model.dofs_per_node[0]))[-1]  # u_z, the node's last
        return NodePairs(
            np.column_stack([np.arange(k), k + np.arange(k)]), self.check_gaps(gaps), direction
        )

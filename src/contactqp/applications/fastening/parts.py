"""The data an assembly is made of: parts, interface pairs and fasteners.

Units SI (m, N). See :class:`~contactqp.applications.fastening.model.Assembly` for how they
join.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core.model import ReducedModel

__all__ = ["AssemblyPart", "InterfacePairs", "Fastener", "FASTENER_KINDS", "SHEARS"]

#: Fastener kinds: ``"closure"`` (a rigid normal link closing the gap) and ``"clamp"`` (a
#: preload with an axial stiffness).
FASTENER_KINDS = ("closure", "clamp")

#: Tangential behaviour of a fastener: ``"bonded"`` (relative tangential motion frozen at
#: installation) or ``"free"`` (no tangential link).
SHEARS = ("bonded", "free")


@dataclass(frozen=True)
class AssemblyPart:
    """One part: its reduced model and the coordinates of every node of it.

    Attributes
    ----------
    name : str
    model : ReducedModel
        The part's own reduced model (flexibility or stiffness), 1 or 3 freedoms per node.
    coordinates : ndarray, shape (n_nodes, 3)
        Position of each node of ``model`` (m).
    """

    name: str
    model: ReducedModel
    coordinates: np.ndarray


@dataclass(frozen=True)
class InterfacePairs:
    """Node pairs between two parts.

    Attributes
    ----------
    first, second : str
        Part names.
    nodes : ndarray of int, shape (k, 2)
        Node of ``first``, node of ``second`` (indices into each part's model).
    normals : ndarray, shape (k, 3)
        Unit normals from ``first`` towards ``second``.
    """

    first: str
    second: str
    nodes: np.ndarray
    normals: np.ndarray


@dataclass(frozen=True)
class Fastener:
    """A fastener at one interface pair (a link between its two nodes, in the pair frame).

    Attributes
    ----------
    pair : int
        Global pair index (the interfaces' pairs concatenated in order).
    kind : str
        ``"closure"``: the gap is closed to 0 and held (a rigid normal link). ``"clamp"``:
        tightened to the preload ``force`` (it pulls with exactly that in the stage that
        installs it), then an axial spring of ``stiffness`` about that state; where it presses
        the parts together their pair bears (gap 0, a compression >= 0) instead of
        penetrating.
    force : float
        Clamp preload (N), > 0 pulling the parts together; 0 for a closure.
    stiffness : float
        Axial stiffness of a clamp (N/m, finite and > 0); inf for a closure.
    shear : str
        ``"bonded"``: the relative tangential motion of the pair is frozen at installation;
        ``"free"``: no tangential link (the only choice for 1-freedom models).
    label : str
        A name for the stage that installs it (default ``"fastener <position>"``).
    """

    pair: int
    kind: str = "closure"
    force: float = 0.0
    stiffness: float = math.inf
    shear: str = "bonded"
    label: str = ""

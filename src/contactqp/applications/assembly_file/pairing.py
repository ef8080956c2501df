"""Node pairs of an interface: given, or found by proximity; and the pairs' normals.

Proximity pairing (:func:`pair_by_proximity`) puts both parts' nodes in KD-trees
(:class:`scipy.spatial.cKDTree`), takes every candidate pair within the tolerance and keeps them
closest first, each node in at most one pair. Nodes left over are reported
(:class:`UnmatchedNodes`), not refused.

Geometric normals (:func:`geometric_normals`) are fitted to the first part's nodes: at each
pair, the plane through its first node and its nearest neighbours among the first part's nodes
(least squares: the singular vector of the smallest singular value of the centred
neighbourhood), oriented towards the second part (``n . (c_2 - c_1) > 0``, ``c`` the bodies'
centres).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

__all__ = [
    "UnmatchedNodes",
    "pair_by_proximity",
    "pair_distances",
    "geometric_normals",
    "NEIGHBOURS",
]

#: Nodes of the first part (itself included) each geometric normal is fitted to.
NEIGHBOURS = 8
#: Examples of unmatched nodes a report shows.
_EXAMPLES = 5


@dataclass(frozen=True)
class UnmatchedNodes:
    """The nodes of one part that proximity pairing left without a partner.

    Attributes
    ----------
    interface : int
        The interface (from 0, in file order).
    part : str
    nodes : ndarray of int
        Node indices (into the part's model).
    n_nodes : int
        The part's node count.
    """

    interface: int
    part: str
    nodes: np.ndarray
    n_nodes: int

    def describe(self) -> str:
        """One line: ``"interfaces[0]: 3 of 40 nodes of 'upper' unmatched (e.g. 0, 5, 9)"``."""
        shown = ", ".join(str(n) for n in self.nodes[:_EXAMPLES])
        more = ", ..." if self.nodes.size > _EXAMPLES else ""
        return (
            f"interfaces[{self.interface}]: {self.nodes.size} of {self.n_nodes} nodes of "
            f"'{self.part}' unmatched (e.g. {shown}{more})"
        )


def pair_by_proximity(
    first: np.ndarray, second: np.ndarray, tolerance: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One-to-one pairs of points of ``first`` and ``second`` at most ``tolerance`` apart.

    Parameters
    ----------
    first, second : ndarray, shape (n1, 3), (n2, 3)
    tolerance : float
        Largest distance of a pair (m).

    Returns
    -------
    pairs : ndarray of int, shape (k, 2)
        ``(node of first, node of second)``, sorted by the first node.
    unmatched_first, unmatched_second : ndarray of int
        Nodes left without a partner.
    """
    candidates = cKDTree(first).sparse_distance_matrix(
        cKDTree(second), tolerance, output_type="ndarray"
    )
    order = np.lexsort((candidates["j"], candidates["i"], candidates["v"]))
    used_first = np.zeros(len(first), dtype=bool)
    used_second = np.zeros(len(second), dtype=bool)
    pairs = []
    for i, j in zip(candidates["i"][order], candidates["j"][order], strict=True):
        if not (used_first[i] or used_second[j]):
            used_first[i] = used_second[j] = True
            pairs.append((int(i), int(j)))
    result = np.array(sorted(pairs), dtype=int).reshape(-1, 2)
    return result, np.flatnonzero(~used_first), np.flatnonzero(~used_second)


def pair_distances(first: np.ndarray, second: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Distance (m) between the two nodes of each pair."""
    return np.linalg.norm(second[pairs[:, 1]] - first[pairs[:, 0]], axis=1)


def geometric_normals(
    first: np.ndarray, nodes: np.ndarray, towards: np.ndarray
) -> tuple[np.ndarray, str]:
    """Unit normals of the first part's surface at ``nodes``, oriented along ``towards``.

    Parameters
    ----------
    first : ndarray, shape (n, 3)
        The first part's node coordinates.
    nodes : ndarray of int, shape (k,)
        The pairs' first nodes.
    towards : ndarray, shape (3,)
        ``c_2 - c_1``: from the first body's centre to the second's.

    Returns
    -------
    normals : ndarray, shape (k, 3)
    problem : str
        Empty, or why the normals could not be made (too few nodes, a neighbourhood on a line,
        a normal perpendicular to ``towards``).
    """
    if len(first) < 3:
        return np.zeros((len(nodes), 3)), "the first part has fewer than 3 nodes to fit a plane"
    count = min(NEIGHBOURS, len(first))
    _, neighbours = cKDTree(first).query(first[nodes], k=count)
    patches = first[neighbours] - first[neighbours].mean(axis=1, keepdims=True)
    _, singular, vt = np.linalg.svd(patches)
    normals = vt[:, 2, :]
    size = singular[:, 0]
    flat = singular[:, 1] <= 1e-6 * size
    if np.any(flat):
        pair = int(np.argmax(flat))
        return normals, f"the nodes around pair {pair} lie on a line: no plane to fit"
    distance = float(np.linalg.norm(towards))
    side = normals @ towards
    unclear = np.abs(side) <= 1e-6 * max(distance, 1e-300)
    if distance == 0.0 or np.any(unclear):
        pair = int(np.argmax(unclear))
        return normals, (
            f"cannot orient the normal of pair {pair}: the parts' centres do not tell which "
            "side the second part is on"
        )
    return normals * np.sign(side)[:, None], ""

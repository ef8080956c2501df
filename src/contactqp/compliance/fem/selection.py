"""Selectors: which nodes (and which freedoms) of a mesh a fixation or a choice of nodes means.

A selector is one of

* a boundary name: a named boundary of the mesh (``"left"``, a Gmsh physical group, ...) or
  ``"boundary"`` for the whole boundary;
* a :class:`Box`;
* a callable ``f(x) -> mask`` taking coordinates of shape (dim, m) (scikit-fem's convention:
  ``x[0]`` is ``x``) and returning m booleans;
* an integer array of mesh node (vertex) indices;
* a tuple of the above: the points satisfying all of them (e.g. ``("top", Box(...))``).

A selector picks mesh nodes (vertices) and, for quadratic elements, the freedoms at edge and face
mid-points too: a boundary name takes every freedom of its facets, a box or a callable every
freedom located inside, node indices only the freedoms of those nodes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeAlias, TypeGuard

import numpy as np
from numpy.typing import ArrayLike

from ...core.model import finite_array
from ...errors import InvalidInputError

if TYPE_CHECKING:
    import skfem

__all__ = ["Box", "Selector", "boundary_facets", "node_mask", "dof_mask"]

#: What a fixation or a choice of nodes takes (see the module's documentation): a boundary name,
#: a :class:`Box`, a predicate of coordinates, node indices, or a tuple of them (all must hold).
Selector: TypeAlias = "str | Box | Callable[[np.ndarray], Any] | ArrayLike | tuple[Selector, ...]"


@dataclass(frozen=True, init=False, eq=False)
class Box:
    """The closed axis-aligned box ``lower <= x <= upper`` (m).

    The box is widened by ``1e-9`` times its largest corner coordinate (at least ``1e-9`` m) so
    that nodes computed with round-off on its faces belong to it.

    Parameters
    ----------
    lower, upper : array_like, shape (dim,)
        Opposite corners; ``lower == upper`` along an axis selects a plane (a face of a block).
    """

    lower: np.ndarray
    upper: np.ndarray

    def __init__(self, lower: ArrayLike, upper: ArrayLike) -> None:
        low, high = finite_array(lower, "lower", 1), finite_array(upper, "upper", 1)
        if low.shape != high.shape or low.size not in (2, 3) or np.any(low > high):
            raise InvalidInputError(
                f"Box needs lower <= upper of 2 or 3 coordinates, got {low} and {high}"
            )
        object.__setattr__(self, "lower", low)
        object.__setattr__(self, "upper", high)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """Mask of the points ``x`` (shape (dim, m)) inside the box."""
        if x.shape[0] != self.lower.size:
            raise InvalidInputError(
                f"Box has {self.lower.size} coordinates but the mesh is {x.shape[0]}-D"
            )
        tol = 1e-9 * max(1.0, float(np.max(np.abs(np.concatenate([self.lower, self.upper])))))
        inside = (x >= self.lower[:, None] - tol) & (x <= self.upper[:, None] + tol)
        return np.all(inside, axis=0)


def boundary_facets(mesh: skfem.Mesh, name: str, argument: str) -> np.ndarray:
    """Facet indices of the boundary ``name`` (``"boundary"``: all); errors name ``argument``."""
    if name == "boundary":
        return mesh.boundary_facets()
    if not mesh.boundaries or name not in mesh.boundaries:
        known = ", ".join(sorted(mesh.boundaries or {})) or "none"
        raise InvalidInputError(
            f"{argument}: the mesh has no boundary named {name!r} "
            f"(named boundaries: {known}; or 'boundary')"
        )
    return np.asarray(mesh.boundaries[name])


def _predicate_mask(
    function: Callable[[np.ndarray], Any], x: np.ndarray, argument: str
) -> np.ndarray:
    mask = np.asarray(function(x))
    if mask.shape != (x.shape[1],) or mask.dtype != bool:
        raise InvalidInputError(
            f"{argument}: a selector function must return {x.shape[1]} "
            f"booleans for coordinates of shape {x.shape}, got "
            f"{mask.dtype} of shape {mask.shape}"
        )
    return mask


def _node_ids(selector: Selector, n_nodes: int, argument: str) -> np.ndarray:
    ids = np.asarray(selector)
    if ids.ndim != 1 or not (np.issubdtype(ids.dtype, np.integer) or ids.size == 0):
        raise InvalidInputError(
            f"{argument} must be a boundary name, a Box, a function, a tuple "
            f"of them or a 1-D array of node indices, got {selector!r}"
        )
    if ids.size and (ids.min() < 0 or ids.max() >= n_nodes):
        raise InvalidInputError(
            f"{argument}: node indices must lie in 0..{n_nodes - 1}, got {ids.min()}..{ids.max()}"
        )
    return ids.astype(int)


def _is_intersection(selector: Selector) -> TypeGuard[tuple[Selector, ...]]:
    return isinstance(selector, tuple) and not all(
        isinstance(s, (int, np.integer)) for s in selector
    )


def node_mask(selector: Selector, mesh: skfem.Mesh, argument: str = "selector") -> np.ndarray:
    """Mask of the mesh nodes (vertices) that ``selector`` picks, shape (n_nodes,)."""
    if _is_intersection(selector):
        return np.logical_and.reduce([node_mask(s, mesh, argument) for s in selector])
    mask = np.zeros(mesh.p.shape[1], dtype=bool)
    if isinstance(selector, str):
        mask[np.unique(mesh.facets[:, boundary_facets(mesh, selector, argument)])] = True
    elif callable(selector):
        mask = _predicate_mask(selector, mesh.p, argument)
    else:
        mask[_node_ids(selector, mask.size, argument)] = True
    return mask


def dof_mask(selector: Selector, basis: skfem.Basis, argument: str = "selector") -> np.ndarray:
    """Mask of the freedoms of a vector ``basis`` that ``selector`` picks, shape (basis.N,)."""
    if _is_intersection(selector):
        return np.logical_and.reduce([dof_mask(s, basis, argument) for s in selector])
    mask = np.zeros(basis.N, dtype=bool)
    if isinstance(selector, str):
        mask[basis.get_dofs(boundary_facets(basis.mesh, selector, argument)).all()] = True
    elif callable(selector):
        mask = _predicate_mask(selector, basis.doflocs, argument)
    else:
        ids = _node_ids(selector, basis.mesh.p.shape[1], argument)
        mask[basis.nodal_dofs[:, ids].ravel()] = True
    return mask

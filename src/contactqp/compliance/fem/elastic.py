"""Linear elastic bodies: assembly, fixations, full analyses and condensed reduced models.

The body is isotropic (Young's modulus ``E``, Poisson's ratio ``nu``); in 2D it is a slice of
thickness ``t`` in plane strain (``eps_zz = 0``) or in plane stress (``sigma_zz = 0``). The
stiffness is scikit-fem's weak form ``int sigma(u) : eps(v) dx`` with the Lamé parameters

.. math::

    \\lambda = \\frac{E \\nu}{(1 + \\nu)(1 - 2 \\nu)}, \\qquad \\mu = \\frac{E}{2 (1 + \\nu)},

except in plane stress, where eliminating ``eps_zz`` replaces ``lambda`` by

.. math::

    \\lambda^* = \\frac{2 \\lambda \\mu}{\\lambda + 2 \\mu} = \\frac{E \\nu}{1 - \\nu^2}.

2D stiffnesses are multiplied by ``t``, so that loads are forces (N), not forces per unit
thickness.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping, Sequence
from typing import NamedTuple, overload

import numpy as np
import scipy.sparse as sp
import skfem
from numpy.typing import ArrayLike
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from skfem.models.elasticity import lame_parameters, linear_elasticity

from ...core.model import ReducedModel, finite_array
from ...errors import InvalidInputError, RigidBodyModeError, UnsupportedProblemError
from ..condensation import condense, factorize
from .meshes import SUPPORTED_MESHES, straight_sided
from .rigid import free_rigid_motions
from .selection import Selector, boundary_facets, dof_mask, node_mask

__all__ = ["ElasticModel", "NodeSelection", "elastic_compliance"]

#: scikit-fem elements by mesh type and order.
_ELEMENTS = {
    "tri": (skfem.ElementTriP1, skfem.ElementTriP2),
    "quad": (skfem.ElementQuad1, skfem.ElementQuad2),
    "tet": (skfem.ElementTetP1, skfem.ElementTetP2),
    "hex": (skfem.ElementHex1, skfem.ElementHex2),
}
_AXES = "xyz"


class NodeSelection(NamedTuple):
    """Mesh nodes picked by :meth:`ElasticModel.select_nodes`.

    Attributes
    ----------
    nodes : ndarray of int, shape (k,)
        Mesh node (vertex) indices.
    distances : ndarray, shape (k,)
        Distance (m) from each requested point to its node; zeros for nodes picked by a selector.
    """

    nodes: np.ndarray
    distances: np.ndarray


def _real(value: object) -> float | None:
    """``value`` as a float if it is a real number (not a bool), else None."""
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    return None


def _positive(value: object, name: str, unit: str) -> float:
    number = _real(value)
    if number is None or not (np.isfinite(number) and number > 0):
        raise InvalidInputError(f"{name} must be a positive finite number ({unit}), got {value!r}")
    return number


class _FreedomLabels(Sequence[str]):
    """Names of the free freedoms, built only for the one an error message needs."""

    def __init__(self, model: ElasticModel, free: np.ndarray) -> None:
        self._model, self._free = model, free

    def __len__(self) -> int:
        return self._free.size

    @overload
    def __getitem__(self, index: int) -> str: ...
    @overload
    def __getitem__(self, index: slice) -> Sequence[str]: ...

    def __getitem__(self, index: int | slice) -> str | Sequence[str]:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        return self._model._freedom_name(int(self._free[index]))


class ElasticModel:
    """A linear elastic body meshed by scikit-fem, with fixations.

    Parameters
    ----------
    mesh : skfem.Mesh
        Triangles or quadrilaterals (2D), tetrahedra or hexahedra (3D), in metres; see
        :mod:`contactqp.compliance.fem.meshes`.
    young : float
        Young's modulus ``E`` (Pa).
    poisson : float
        Poisson's ratio ``nu``, ``-1 < nu < 0.5``.
    plane : {"stress", "strain"}, optional
        Required for a 2D mesh, refused for a 3D one.
    thickness : float, optional
        Thickness of a 2D body (m), 1 by default; refused in 3D.
    order : {1, 2}
        Polynomial order of the elements (2 avoids the locking of linear elements in bending).

    Notes
    -----
    Freedoms are the displacement components at the mesh's vertices ("nodes") and, for
    ``order=2``, at edge (and face) mid-points. A mesh of second-order cells (6-node triangles,
    10-node tetrahedra, ...) is taken with straight edges, its vertices only: ask ``order=2`` for
    quadratic elements. Nodes used by no cell (points of a CAD geometry left in a mesh file) are
    removed. ``model.mesh`` is the mesh as used, to which node indices refer.
    """

    def __init__(
        self,
        mesh: skfem.Mesh,
        young: float,
        poisson: float,
        *,
        plane: str | None = None,
        thickness: float | None = None,
        order: int = 1,
    ) -> None:
        cell = next(
            (name for name, kind in SUPPORTED_MESHES.items() if isinstance(mesh, kind)), None
        )
        if cell is None:
            raise UnsupportedProblemError(
                f"mesh must be a scikit-fem triangle, quadrilateral, tetrahedron or hexahedron "
                f"mesh, got {type(mesh).__name__}"
            )
        mesh = straight_sided(mesh, cell)
        if np.unique(mesh.t).size < mesh.p.shape[1]:
            mesh = mesh.remove_unused_nodes()
        self.mesh, self.dim = mesh, mesh.p.shape[0]
        self.young = _positive(young, "young", "Pa")
        ratio = _real(poisson)
        if ratio is None or not -1 < ratio < 0.5:
            raise InvalidInputError(f"poisson must lie in (-1, 0.5), got {poisson!r}")
        self.poisson = ratio
        if self.dim == 2:
            if plane not in ("stress", "strain"):
                raise InvalidInputError(
                    f"plane must be 'stress' or 'strain' for a 2D mesh, got {plane!r}"
                )
            self.thickness = 1.0 if thickness is None else _positive(thickness, "thickness", "m")
        else:
            if plane is not None or thickness is not None:
                raise InvalidInputError(
                    "plane and thickness apply to 2D meshes only; this mesh is 3D"
                )
            self.thickness = 1.0
        self.plane = plane
        if order not in (1, 2):
            raise InvalidInputError(f"order must be 1 or 2, got {order!r}")
        self.order = order
        self.basis = skfem.Basis(mesh, skfem.ElementVector(_ELEMENTS[cell][order - 1]()))
        self._component = np.empty(self.basis.N, dtype=int)
        for axis, indices in enumerate(self.basis.split_indices()):
            self._component[indices] = axis
        self._fixed = np.zeros(self.basis.N, dtype=bool)
        self._stiffness: sp.csr_matrix | None = None
        self._free_stiffness: tuple[np.ndarray, sp.csc_matrix] | None = None

    @property
    def lame(self) -> tuple[float, float]:
        """Lamé parameters ``(lambda, mu)`` (Pa), ``lambda*`` in plane stress."""
        lam, mu = lame_parameters(self.young, self.poisson)
        if self.plane == "stress":
            lam = 2 * lam * mu / (lam + 2 * mu)
        return lam, mu

    @property
    def n_nodes(self) -> int:
        """Number of mesh nodes (vertices)."""
        return self.mesh.p.shape[1]

    @property
    def stiffness(self) -> sp.csr_matrix:
        """Assembled stiffness of every freedom before fixation, shape (N, N), N/m."""
        if self._stiffness is None:
            form = linear_elasticity(*self.lame)
            self._stiffness = (skfem.asm(form, self.basis) * self.thickness).tocsr()
        return self._stiffness

    @property
    def fixed(self) -> np.ndarray:
        """Indices of the fixed freedoms."""
        return np.flatnonzero(self._fixed)

    def fix(self, selector: Selector, components: Sequence[int] | None = None) -> ElasticModel:
        """Clamp the freedoms that ``selector`` picks (zero displacement).

        Parameters
        ----------
        selector
            See :mod:`contactqp.compliance.fem.selection`, e.g. ``"left"``,
            ``Box((0, 0), (0, 1))`` or ``lambda x: x[0] == 0``.
        components : sequence of int, optional
            Directions fixed (0 = x, 1 = y, 2 = z); all by default. ``components=[0]`` on a face
            normal to ``x`` is a symmetry (roller) condition.

        Returns
        -------
        ElasticModel
            ``self``, so that fixations chain.
        """
        axes = self._components(components, "components")
        picked = dof_mask(selector, self.basis, "selector") & np.isin(self._component, axes)
        if not picked.any():
            raise InvalidInputError(f"selector {selector!r} picks no freedom to fix")
        self._fixed |= picked
        self._free_stiffness = None
        return self

    def select_nodes(
        self, points: ArrayLike | None = None, *, where: Selector | None = None
    ) -> NodeSelection:
        """Mesh nodes nearest to ``points``, or all the nodes ``where`` picks.

        Parameters
        ----------
        points : array_like, shape (k, dim), optional
            Wanted locations (m) of computational nodes.
        where : selector, optional
            Restricts the candidates (e.g. ``"top"``: nodes of that face); every node when
            omitted.

        Returns
        -------
        NodeSelection
            The nodes, in the order of ``points`` (else by index), and the distances from the
            points to them (m).

        Raises
        ------
        InvalidInputError
            No candidate node, or two points sharing their nearest node.
        """
        ids = np.arange(self.n_nodes)
        if where is not None:
            ids = np.flatnonzero(node_mask(where, self.mesh, "where"))
        if ids.size == 0:
            raise InvalidInputError(f"where={where!r} picks no node of the mesh")
        if points is None:
            return NodeSelection(ids, np.zeros(ids.size))
        wanted = finite_array(points, "points", 2)
        if wanted.shape[1] != self.dim:
            raise InvalidInputError(f"points must have shape (k, {self.dim}), got {wanted.shape}")
        distances, nearest = cKDTree(self.mesh.p[:, ids].T).query(wanted)
        nodes = ids[nearest]
        unique, counts = np.unique(nodes, return_counts=True)
        if np.any(counts > 1):
            node = unique[np.argmax(counts > 1)]
            which = np.flatnonzero(nodes == node)
            raise InvalidInputError(
                f"points {which.tolist()} share their nearest node {node}: "
                "refine the mesh or move the points apart"
            )
        return NodeSelection(nodes, np.asarray(distances))

    def solve(
        self, loads: ArrayLike | None = None, *, tractions: Mapping[str, ArrayLike] | None = None
    ) -> np.ndarray:
        """One full analysis: nodal displacements under loads (factorises at every call).

        Parameters
        ----------
        loads : array_like, shape (n_nodes, dim), optional
            Force on every mesh node (N). Forces on fixed freedoms go straight to the supports.
        tractions : dict, optional
            ``{boundary name: traction}``: a uniform surface traction, shape (dim,), in Pa, on
            the facets of each named boundary (distributed consistently over the freedoms,
            mid-side ones included). In 2D it acts over the thickness.

        Returns
        -------
        ndarray, shape (n_nodes, dim)
            Displacements of the mesh nodes (m).
        """
        if loads is None and not tractions:
            raise InvalidInputError("give loads or tractions")
        vector = np.zeros(self.basis.N)
        if loads is not None:
            forces = finite_array(loads, "loads", 2)
            if forces.shape != (self.n_nodes, self.dim):
                raise InvalidInputError(
                    f"loads must have shape ({self.n_nodes}, {self.dim}), got {forces.shape}"
                )
            vector[self.basis.nodal_dofs] = forces.T
        if tractions is not None and not isinstance(tractions, dict):
            raise InvalidInputError(
                f"tractions must be a dict {{boundary name: traction}}, got "
                f"{type(tractions).__name__}"
            )
        for name, traction in (tractions or {}).items():
            vector += self._traction_load(name, traction)
        free, K = self.free_stiffness()
        displacement = np.zeros(self.basis.N)
        displacement[free] = factorize(K, labels=_FreedomLabels(self, free)).solve(vector[free])
        return displacement[self.basis.nodal_dofs].T

    def _traction_load(self, name: object, traction: ArrayLike) -> np.ndarray:
        """Consistent load vector (N), shape (N,), of a uniform traction on a named boundary."""
        if not isinstance(name, str):
            raise InvalidInputError(f"tractions keys must be boundary names, got {name!r}")
        value = finite_array(traction, f"tractions[{name!r}]", 1)
        if value.shape != (self.dim,):
            raise InvalidInputError(
                f"tractions[{name!r}] must have shape ({self.dim},), got {value.shape}"
            )
        facets = skfem.FacetBasis(
            self.mesh, self.basis.elem, facets=boundary_facets(self.mesh, name, "tractions")
        )

        @skfem.LinearForm
        def work(v: skfem.DiscreteField, _: skfem.DiscreteField) -> skfem.DiscreteField:
            return sum(value[axis] * v[axis] for axis in range(self.dim))

        return skfem.asm(work, facets) * self.thickness

    def reduced_model(
        self, nodes: ArrayLike | NodeSelection, *, components: Sequence[int] | None = None
    ) -> ReducedModel:
        """Flexibility of computational nodes by static condensation.

        Parameters
        ----------
        nodes : array_like of int, shape (k,), or NodeSelection
            Mesh node indices, e.g. from :meth:`select_nodes`.
        components : sequence of int, optional
            Directions kept at every node (0 = x, 1 = y, 2 = z); all by default. Keeping only the
            normal of a flat contact face gives one freedom per node.

        Returns
        -------
        ReducedModel
            ``R[i, j]`` (m/N): displacement of freedom ``i`` under a unit force on freedom ``j``,
            freedoms ordered node by node, then by component; coordinates of the nodes (m).
        """
        if isinstance(nodes, NodeSelection):
            nodes = nodes.nodes
        ids = np.asarray(nodes)
        if ids.ndim != 1 or ids.size == 0 or not np.issubdtype(ids.dtype, np.integer):
            raise InvalidInputError(
                f"nodes must be a non-empty 1-D array of node indices, got {nodes!r}"
            )
        if ids.min() < 0 or ids.max() >= self.n_nodes or np.unique(ids).size != ids.size:
            raise InvalidInputError(f"nodes must be distinct indices in 0..{self.n_nodes - 1}")
        axes = self._components(components, "components")
        freedoms = self.basis.nodal_dofs[axes][:, ids].T.ravel()
        held = freedoms[self._fixed[freedoms]]
        if held.size:
            raise InvalidInputError(
                f"nodes: {self._freedom_name(held[0])} is fixed and has no flexibility"
            )
        free, K = self.free_stiffness()
        position = np.full(self.basis.N, -1)
        position[free] = np.arange(free.size)
        R = condense(K, position[freedoms], labels=_FreedomLabels(self, free))
        return ReducedModel(
            flexibility=R, dofs_per_node=len(axes), coordinates=self.mesh.p[:, ids].T
        )

    def _components(self, components: Sequence[int] | None, name: str) -> np.ndarray:
        if components is None:
            return np.arange(self.dim)
        axes = np.atleast_1d(np.asarray(components))
        if (
            axes.ndim != 1
            or axes.size == 0
            or not np.issubdtype(axes.dtype, np.integer)
            or axes.min() < 0
            or axes.max() >= self.dim
            or np.unique(axes).size != axes.size
        ):
            raise InvalidInputError(
                f"{name} must be distinct directions in 0..{self.dim - 1}, got {components!r}"
            )
        return axes

    def _freedom_name(self, freedom: int) -> str:
        where = ", ".join(f"{c:.4g}" for c in self.basis.doflocs[:, freedom])
        node = np.flatnonzero(self.basis.nodal_dofs == freedom)
        owner = f"node {node[0] % self.n_nodes}" if node.size else "mid-side point"
        return f"u_{_AXES[self._component[freedom]]} of {owner} at ({where})"

    def free_stiffness(self) -> tuple[np.ndarray, sp.csc_matrix]:
        """The stiffness with the fixations applied, after checking that every body is held.

        Returns
        -------
        free : ndarray of int, shape (m,)
            Indices of the free freedoms among all ``N`` (nodal ones are ``basis.nodal_dofs``).
        stiffness : scipy.sparse.csc_matrix, shape (m, m)
            Their stiffness (N/m), as :func:`~contactqp.compliance.condensation.condense` takes.

        Raises
        ------
        RigidBodyModeError
            A connected part of the mesh is not held; the message names its free motions.
        """
        if self._free_stiffness is None:
            self._check_held()
            free = np.flatnonzero(~self._fixed)
            self._free_stiffness = free, self.stiffness[free][:, free].tocsc()
        return self._free_stiffness

    def _check_held(self) -> None:
        """Raise RigidBodyModeError naming the motions a connected body is free to make."""
        mesh = self.mesh
        cells = mesh.t.shape[1]
        incidence = sp.csr_matrix(
            (
                np.ones(mesh.t.size),
                (np.repeat(np.arange(cells), mesh.t.shape[0]), mesh.t.T.ravel()),
            ),
            shape=(cells, self.n_nodes),
        )
        count, part_of_node = connected_components(incidence.T @ incidence, directed=False)
        part_of_dof = np.full(self.basis.N, -1)
        part_of_dof[self.basis.element_dofs] = part_of_node[mesh.t[0]][None, :]
        for part in range(count):
            points = mesh.p[:, part_of_node == part]
            centre = points.mean(axis=1)
            scale = float(np.max(np.ptp(points, axis=1)))
            held = np.flatnonzero(self._fixed & (part_of_dof == part))
            free = free_rigid_motions(
                self.basis.doflocs[:, held], self._component[held], centre, scale
            )
            if free:
                body = (
                    "the body"
                    if count == 1
                    else (f"the part of the mesh around ({', '.join(f'{c:.4g}' for c in centre)})")
                )
                raise RigidBodyModeError(
                    f"not enough fixations: {body} has rigid-body modes "
                    f"({', '.join(free)}); fix more freedoms"
                )


def elastic_compliance(
    mesh: skfem.Mesh,
    young: float,
    poisson: float,
    fixed: Selector,
    points: ArrayLike,
    *,
    plane: str | None = None,
    thickness: float | None = None,
    order: int = 1,
    where: Selector | None = None,
    components: Sequence[int] | None = None,
) -> ReducedModel:
    """Reduced model of an elastic body at the mesh nodes nearest to ``points``, in one call.

    Parameters
    ----------
    mesh, young, poisson, plane, thickness, order
        See :class:`ElasticModel`.
    fixed : selector
        Clamped part (every component), e.g. ``"left"``; use :class:`ElasticModel` for more.
    points : array_like, shape (k, dim)
        Wanted computational nodes (m); see :meth:`ElasticModel.select_nodes` (and ``where``).
    components : sequence of int, optional
        See :meth:`ElasticModel.reduced_model`.

    Returns
    -------
    ReducedModel
    """
    model = ElasticModel(mesh, young, poisson, plane=plane, thickness=thickness, order=order)
    model.fix(fixed)
    return model.reduced_model(model.select_nodes(points, where=where), components=components)

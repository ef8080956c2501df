"""Meshes: structured rectangles and boxes with named faces, and meshes read from files.

The generated meshes start at the origin and carry the named boundaries ``"left"`` and
``"right"`` (``x = 0`` and ``x = length``), ``"bottom"`` and ``"top"`` (the lowest and highest
``y`` in 2D, ``z`` in 3D) and, in 3D, ``"front"`` and ``"back"`` (``y = 0`` and ``y = width``).
"""

from __future__ import annotations

import numbers
import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import skfem

from ...errors import FileFormatError, InvalidInputError, UnsupportedProblemError
from ...optional import require

if TYPE_CHECKING:
    import meshio

__all__ = ["plate", "block", "bar", "read_mesh", "straight_sided", "SUPPORTED_MESHES"]

#: Mesh types of scikit-fem that the elastic models accept, by cell name.
SUPPORTED_MESHES = {
    "tri": skfem.MeshTri,
    "quad": skfem.MeshQuad,
    "tet": skfem.MeshTet,
    "hex": skfem.MeshHex,
}
_CELLS_2D, _CELLS_3D = ("tri", "quad"), ("tet", "hex")


def _length(value: object, name: str) -> float:
    number = None
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        number = float(value)
    if number is None or not (np.isfinite(number) and number > 0):
        raise InvalidInputError(f"{name} must be a positive finite length in metres, got {value!r}")
    return number


def _count(value: object, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise InvalidInputError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _cell(cell: str, allowed: tuple[str, ...]) -> type[skfem.Mesh]:
    if cell not in allowed:
        raise InvalidInputError(f"cell must be one of {', '.join(allowed)}, got {cell!r}")
    return SUPPORTED_MESHES[cell]


def _faces(extents: tuple[float, ...]) -> dict[str, Callable[[np.ndarray], np.ndarray]]:
    """Boundary predicates of the box ``[0, extents]`` (2 or 3 extents)."""
    tol = 1e-9 * max(extents)
    axes = (
        [("left", "right"), ("bottom", "top")]
        if len(extents) == 2
        else [("left", "right"), ("front", "back"), ("bottom", "top")]
    )
    faces = {}
    for axis, ((low, high), extent) in enumerate(zip(axes, extents, strict=True)):
        faces[low] = _plane(axis, 0.0, tol)
        faces[high] = _plane(axis, extent, tol)
    return faces


def _plane(axis: int, at: float, tol: float) -> Callable[[np.ndarray], np.ndarray]:
    """Predicate of the points (coordinates by row) within ``tol`` of the plane ``x[axis] = at``."""
    return lambda x: np.abs(x[axis] - at) < tol


def plate(length: float, width: float, nx: int, ny: int, *, cell: str = "quad") -> skfem.Mesh:
    """Rectangle ``[0, length] x [0, width]`` split into ``nx`` by ``ny`` cells.

    Parameters
    ----------
    length, width : float
        Sides along ``x`` and ``y`` (m).
    nx, ny : int
        Cells along ``x`` and ``y``; ``cell="tri"`` splits each into two triangles.
    cell : {"quad", "tri"}

    Returns
    -------
    skfem.Mesh
        With the boundaries ``left``, ``right``, ``bottom``, ``top``.
    """
    extents = (_length(length, "length"), _length(width, "width"))
    counts = (_count(nx, "nx"), _count(ny, "ny"))
    mesh_type = _cell(cell, _CELLS_2D)
    axes = [np.linspace(0.0, e, n + 1) for e, n in zip(extents, counts, strict=True)]
    return mesh_type.init_tensor(*axes).with_boundaries(_faces(extents))


def block(
    length: float, width: float, height: float, nx: int, ny: int, nz: int, *, cell: str = "hex"
) -> skfem.Mesh:
    """Box ``[0, length] x [0, width] x [0, height]`` split into ``nx * ny * nz`` cells.

    Parameters
    ----------
    length, width, height : float
        Sides along ``x``, ``y`` and ``z`` (m).
    nx, ny, nz : int
        Cells along each axis; ``cell="tet"`` splits each hexahedron into tetrahedra.
    cell : {"hex", "tet"}

    Returns
    -------
    skfem.Mesh
        With the boundaries ``left``, ``right``, ``front``, ``back``, ``bottom``, ``top``.
    """
    extents = (_length(length, "length"), _length(width, "width"), _length(height, "height"))
    counts = (_count(nx, "nx"), _count(ny, "ny"), _count(nz, "nz"))
    mesh_type = _cell(cell, _CELLS_3D)
    axes = [np.linspace(0.0, e, n + 1) for e, n in zip(extents, counts, strict=True)]
    return mesh_type.init_tensor(*axes).with_boundaries(_faces(extents))


def bar(
    length: float,
    height: float,
    width: float | None = None,
    *,
    across: int = 2,
    cell: str | None = None,
) -> skfem.Mesh:
    """A bar along ``x`` meshed with nearly cubic cells: a :func:`plate` or a :func:`block`.

    Parameters
    ----------
    length : float
        Length along ``x`` (m).
    height : float
        Depth of the section: along ``y`` in 2D, along ``z`` in 3D (m).
    width : float, optional
        Width of the section along ``y`` (m); gives a 3D bar when given.
    across : int
        Cells across the height; the other counts follow from the cells' aspect ratio (>= 1).
    cell : str, optional
        ``"quad"`` (default) or ``"tri"`` in 2D, ``"hex"`` (default) or ``"tet"`` in 3D.
    """
    size = _length(height, "height") / _count(across, "across")
    along = max(1, round(_length(length, "length") / size))
    if width is None:
        return plate(length, height, along, across, cell=cell or "quad")
    return block(
        length,
        width,
        height,
        along,
        max(1, round(_length(width, "width") / size)),
        across,
        cell=cell or "hex",
    )


def straight_sided(mesh: skfem.Mesh, cell: str) -> skfem.Mesh:
    """The mesh with first-order geometry: second-order cells lose their mid-side nodes.

    Parameters
    ----------
    mesh : skfem.Mesh
        A mesh of the type ``SUPPORTED_MESHES[cell]`` or of its second-order subtype
        (``MeshTri2``, ``MeshTet2``, ... read from 6-node triangles, 10-node tetrahedra, ...).
    cell : str
        A key of :data:`SUPPORTED_MESHES`.

    Returns
    -------
    skfem.Mesh
        ``mesh`` itself when it is first order; otherwise the mesh of its vertices and cells, with
        its named boundaries and subdomains (edges become straight).
    """
    linear = SUPPORTED_MESHES[cell]
    if type(mesh) is linear:
        return mesh
    return linear(
        mesh.p[:, : mesh.nvertices],
        mesh.t,
        _boundaries=mesh._boundaries,
        _subdomains=mesh._subdomains,
    )


def read_mesh(source: str | os.PathLike[str] | meshio.Mesh) -> skfem.Mesh:
    """A mesh read by meshio from a file, or converted from a ``meshio.Mesh``.

    The cells of the highest dimension make the mesh (triangles, quadrilaterals, tetrahedra or
    hexahedra, first or second order); named cell sets of lower dimension (Gmsh physical groups,
    for example) become named boundaries usable as selectors.

    Parameters
    ----------
    source : str, pathlib.Path or meshio.Mesh
        Any file format meshio reads (``.msh``, ``.vtu``, ``.inp``, ``.med``, ...).

    Returns
    -------
    skfem.Mesh

    Raises
    ------
    FileFormatError
        Missing or unreadable file.
    UnsupportedProblemError
        A mesh of lines only, or of cells the elastic models do not support.
    """
    meshio = require("meshio", "reading meshes", "fem")
    from_meshio = require("skfem.io.meshio", "reading meshes", "fem", "scikit-fem").from_meshio

    if not isinstance(source, meshio.Mesh):
        try:
            path = Path(source)
        except TypeError:
            raise FileFormatError(
                f"a mesh must be a file path or a meshio.Mesh, got {type(source).__name__}"
            ) from None
        if not path.is_file():
            raise FileFormatError(f"mesh file {str(path)!r} does not exist")
        try:
            source = meshio.read(path)
        except (Exception, SystemExit) as exc:  # meshio's legacy VTK reader exits on bad headers
            raise FileFormatError(
                f"mesh file {str(path)!r} could not be read by meshio: {exc}"
            ) from None
    try:
        mesh = from_meshio(source)
    except Exception as exc:
        raise FileFormatError(f"meshio mesh could not be converted: {exc}") from None
    if not isinstance(mesh, tuple(SUPPORTED_MESHES.values())):
        raise UnsupportedProblemError(
            f"mesh of type {type(mesh).__name__} is not supported: give triangles, "
            "quadrilaterals, tetrahedra or hexahedra"
        )
    return mesh

"""The parts of an assembly file: a reduced model and node coordinates from each ``[parts.NAME]``.

A part's compliance comes from a matrix file (the importers of
:mod:`contactqp.compliance.importers`), from a mesh condensed by the embedded finite elements
(:mod:`contactqp.compliance.fem`), or from the built-in Kirchhoff plate of
:mod:`contactqp.applications.riveting`. Every model is converted to SI units.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...compliance.importers import READERS
from ...core.model import ReducedModel
from ...errors import ContactError, InvalidInputError
from ...io.problem_file.messages import Where, as_table, check_keys, counted, describe
from .schema import BOX_KEYS, FIX_KEYS, GENERATOR_KEYS, PART_KEYS, PART_TYPES
from .values import (
    Units,
    array,
    choice,
    file_path,
    integer,
    number,
    read_columns,
    require_columns,
    string,
    vector,
)

__all__ = ["PartInput", "read_part"]

#: File keys of a matrix part and the reader arguments they become.
_SELECTION = {
    "kind": "kind",
    "matrix": "name",
    "nodes": "nodes",
    "components": "components",
    "freedoms": "freedoms",
    "fixed": "fixed",
    "dofs_per_node": "dofs_per_node",
}
_FACES = ("left", "right", "front", "back", "bottom", "top")


@dataclass(frozen=True)
class PartInput:
    """One part as read: its reduced model and where its nodes are.

    Attributes
    ----------
    name : str
    model : ReducedModel
        SI units (m/N or N/m).
    coordinates : ndarray, shape (n_nodes, 3)
        Node positions (m), one row per node of ``model``.
    centroid : ndarray, shape (3,)
        The body's centre (m): of its mesh for a mesh part, of its nodes otherwise; orients
        geometric normals.
    fe_model : ElasticModel or None
        The finite-element model of a mesh part (for full analyses), else None.
    mesh_nodes : ndarray of int or None
        The mesh node of each model node of a mesh part, else None.
    """

    name: str
    model: ReducedModel
    coordinates: np.ndarray
    centroid: np.ndarray
    fe_model: Any = None
    mesh_nodes: np.ndarray | None = None


def read_part(where: Where, name: str, table, units: Units) -> PartInput:
    """The part ``[parts.name]``."""
    key = f"parts.{name}"
    table = as_table(where, table, key)
    if "type" not in table:
        raise where.error(f"{key}.type", f"missing: give one of {', '.join(PART_TYPES)}")
    kind = choice(where, table["type"], f"{key}.type", PART_TYPES)
    check_keys(where, table, PART_KEYS[kind], key)
    reader = {"matrix": _matrix_part, "mesh": _mesh_part, "plate": _plate_part}[kind]
    return reader(where, name, key, table, units)


def _in_si(model: ReducedModel, units: Units, coordinates: np.ndarray) -> ReducedModel:
    """``model`` (file units) as an SI model with ``coordinates``."""
    if model.given == "flexibility":
        scale = units.length / units.force
        return ReducedModel(
            flexibility=model.flexibility * scale,
            dofs_per_node=model.dofs_per_node,
            coordinates=coordinates,
        )
    return ReducedModel(
        stiffness=model.stiffness * units.stiffness,
        dofs_per_node=model.dofs_per_node,
        coordinates=coordinates,
    )


def _reader_for(where: Where, path, key: str):
    name = path.name.lower()
    for endings, reader in READERS.items():
        if name.endswith(endings):
            return reader
    known = ", ".join(ending for endings in READERS for ending in endings)
    raise where.error(key, f"cannot tell the format of '{path.name}' from its extension ({known})")


def _selection_value(where: Where, file_key: str, value, key: str):
    """A selection key's TOML value as the reader takes it (lists stay lists)."""
    if file_key in ("kind", "matrix"):
        return string(where, value, key)
    if file_key == "dofs_per_node" and isinstance(value, int) and not isinstance(value, bool):
        return value
    if not isinstance(value, list):
        raise where.error(key, f"must be an array, got {describe(value)}")
    return value


def _matrix_part(where: Where, name: str, key: str, table: dict, units: Units) -> PartInput:
    if "compliance" not in table:
        raise where.error(f"{key}.compliance", "missing: give the matrix file")
    path = file_path(where, table["compliance"], f"{key}.compliance")
    reader = _reader_for(where, path, f"{key}.compliance")
    accepted = set(inspect.signature(reader).parameters)
    selection = {}
    for file_key, argument in _SELECTION.items():
        if file_key not in table:
            continue
        if argument not in accepted:
            takes = sorted(k for k, a in _SELECTION.items() if a in accepted)
            raise where.error(
                f"{key}.{file_key}",
                f"not taken by {reader.__name__} ('{path.name}'); it takes "
                f"{', '.join(takes) or 'no selection'}",
            )
        selection[argument] = _selection_value(
            where, file_key, table[file_key], f"{key}.{file_key}"
        )
    try:
        inspect.signature(reader).bind(path, **selection)
        model = reader(path, **selection)
    except TypeError as exc:
        raise where.error(f"{key}.compliance", f"{reader.__name__}: {exc}") from None
    except ContactError as exc:
        message = str(exc).removeprefix(f"{path}: ")
        raise where.rewrap(f"{key}.compliance", type(exc)(message)) from None
    if "coordinates" not in table:
        raise where.error(
            f"{key}.coordinates", "missing: give the nodes' coordinates (a CSV node, x, y, z)"
        )
    labels = selection.get("nodes")
    coordinates = _node_coordinates(
        where, table["coordinates"], f"{key}.coordinates", model, labels, units
    )
    model = _in_si(model, units, coordinates)
    return PartInput(name, model, coordinates, coordinates.mean(axis=0))


def _node_coordinates(
    where: Where, value, key: str, model: ReducedModel, labels, units: Units
) -> np.ndarray:
    """``(n_nodes, 3)`` coordinates (m) of the model's nodes: an inline array in model order, or
    a CSV ``node, x, y, z`` (node: the number ``nodes`` names, else the index from 0)."""
    n = model.n_nodes
    if not isinstance(value, str):
        coordinates = array(where, value, key, 2) * units.length
        if coordinates.shape != (n, 3):
            raise where.error(
                key, f"must have shape ({n}, 3) (one row x, y, z per node), got {coordinates.shape}"
            )
        return coordinates
    columns, _ = read_columns(where, value, key, ("x", "y", "z"), units)
    require_columns(where, columns, key, ("node", "x", "y", "z"))
    numbers = columns["node"]
    if np.any(numbers != np.round(numbers)):
        raise where.error(key, "the node column must hold whole numbers")
    row_of = {}
    for row, label in enumerate(numbers.astype(int).tolist()):
        if label in row_of:
            raise where.error(key, f"node {label} appears twice")
        row_of[label] = row
    wanted = [int(v) for v in labels] if labels is not None else list(range(n))
    if len(wanted) != n:
        raise where.error(key, f"the model has {counted(n, 'node')}, nodes names {len(wanted)}")
    missing = [label for label in wanted if label not in row_of]
    if missing:
        raise where.error(
            key, f"has no row for node {missing[0]} ({counted(len(missing), 'node')} missing)"
        )
    rows = [row_of[label] for label in wanted]
    return np.column_stack([columns[axis][rows] for axis in "xyz"])


def _box(where: Where, value, key: str, units: Units):
    from ...compliance.fem import Box

    table = as_table(where, value, key)
    check_keys(where, table, BOX_KEYS, key)
    corners = []
    for corner in BOX_KEYS:
        if corner not in table:
            raise where.error(f"{key}.{corner}", "missing: give [x, y, z]")
        corners.append(vector(where, table[corner], f"{key}.{corner}", 3, units.length))
    if np.any(corners[0] > corners[1]):
        raise where.error(key, "lower must not exceed upper along any axis")
    return Box(*corners)


def _selector(where: Where, value, key: str, mesh, units: Units):
    """A face name of the mesh or a box table."""
    if isinstance(value, str):
        names = sorted(mesh.boundaries or {})
        if value != "boundary" and value not in names:
            raise where.error(
                key,
                f"the mesh has no face named '{value}' (faces: {', '.join(names) or 'none'}; "
                "or 'boundary')",
            )
        return value
    if isinstance(value, dict):
        return _box(where, value, key, units)
    raise where.error(key, f"must be a face name or a box table, got {describe(value)}")


def _mesh(where: Where, value, key: str, units: Units):
    from ...compliance.fem import block, read_mesh

    if isinstance(value, str):
        path = file_path(where, value, key)
        try:
            mesh = read_mesh(path)
        except ContactError as exc:
            raise where.rewrap(key, exc) from None
        return mesh.scaled(units.length) if units.length != 1.0 else mesh
    table = as_table(where, value, key)
    check_keys(where, table, GENERATOR_KEYS, key)
    if "block" not in table:
        raise where.error(f"{key}.block", "missing: give [length, width, height]")
    size = vector(where, table["block"], f"{key}.block", 3, units.length)
    cells = array(where, table.get("cells", [4, 4, 2]), f"{key}.cells", 1, integer=True)
    if cells.size != 3 or np.any(cells < 1):
        raise where.error(f"{key}.cells", "must be 3 positive integers")
    cell = choice(where, table.get("cell", "hex"), f"{key}.cell", ("hex", "tet"))
    origin = vector(where, table.get("origin", [0.0, 0.0, 0.0]), f"{key}.origin", 3, units.length)
    for axis, extent in zip("xyz", size, strict=True):
        if extent <= 0:
            raise where.error(f"{key}.block", f"the {axis} extent must be positive")
    mesh = block(*size, *(int(c) for c in cells), cell=cell)
    return mesh.translated(origin) if np.any(origin) else mesh


def _mesh_part(where: Where, name: str, key: str, table: dict, units: Units) -> PartInput:
    from ...compliance.fem import ElasticModel

    for required in ("mesh", "young", "poisson", "fix", "interface"):
        if required not in table:
            raise where.error(f"{key}.{required}", "missing")
    mesh = _mesh(where, table["mesh"], f"{key}.mesh", units)
    if mesh.p.shape[0] != 3:
        raise where.error(f"{key}.mesh", f"must be a 3-D mesh, got a {mesh.p.shape[0]}-D one")
    young = number(where, table["young"], f"{key}.young", positive=True, scale=units.pressure)
    poisson = number(where, table["poisson"], f"{key}.poisson")
    if not -1.0 < poisson < 0.5:
        raise where.error(f"{key}.poisson", f"must lie in (-1, 0.5), got {poisson}")
    order = integer(where, table.get("order", 1), f"{key}.order")
    if order not in (1, 2):
        raise where.error(f"{key}.order", f"must be 1 or 2, got {order}")
    body = ElasticModel(mesh, young, poisson, order=order)
    fixations = table["fix"]
    if not isinstance(fixations, list) or not fixations:
        raise where.error(f"{key}.fix", "must be a non-empty array of { at = ... } tables")
    for number_, fixation in enumerate(fixations):
        fix_key = f"{key}.fix[{number_}]"
        fixation = as_table(where, fixation, fix_key)
        check_keys(where, fixation, FIX_KEYS, fix_key)
        if "at" not in fixation:
            raise where.error(f"{fix_key}.at", "missing: give a face name or a box")
        selector = _selector(where, fixation["at"], f"{fix_key}.at", mesh, units)
        components = None
        if "components" in fixation:
            components = array(
                where, fixation["components"], f"{fix_key}.components", 1, integer=True
            )
            if components.size == 0 or np.any((components < 0) | (components > 2)):
                raise where.error(f"{fix_key}.components", "must be directions among 0, 1, 2")
        try:
            body.fix(selector, None if components is None else components.tolist())
        except InvalidInputError as exc:
            raise where.rewrap(fix_key, exc) from None
    selector = _selector(where, table["interface"], f"{key}.interface", mesh, units)
    try:
        nodes = body.select_nodes(where=selector).nodes
        model = body.reduced_model(nodes)
    except InvalidInputError as exc:
        failing = "fix" if "fix" in str(exc) or "rigid" in str(exc) else "interface"
        raise where.rewrap(f"{key}.{failing}", exc) from None
    coordinates = np.asarray(mesh.p[:, nodes].T, dtype=float)
    return PartInput(name, model, coordinates, mesh.p.mean(axis=1), body, np.asarray(nodes))


def _plate_part(where: Where, name: str, key: str, table: dict, units: Units) -> PartInput:
    from ..assembly import Part
    from ..riveting import Assembly

    defaults = Part()
    lengths = {}
    for dimension in ("length", "width", "thickness"):
        if dimension in table:
            lengths[dimension] = number(
                where, table[dimension], f"{key}.{dimension}", positive=True, scale=units.length
            )
        else:
            lengths[dimension] = getattr(defaults, dimension)
    young = (
        number(where, table["young"], f"{key}.young", positive=True, scale=units.pressure)
        if "young" in table
        else defaults.young
    )
    poisson = number(where, table.get("poisson", defaults.poisson), f"{key}.poisson")
    if not -1.0 < poisson < 0.5:
        raise where.error(f"{key}.poisson", f"must lie in (-1, 0.5), got {poisson}")
    grid = array(where, table.get("grid", [25, 21]), f"{key}.grid", 1, integer=True)
    if grid.size != 2 or np.any(grid < 1):
        raise where.error(f"{key}.grid", "must be 2 positive integers [along x, along y]")
    supports = table.get("supports", ["left", "right"])
    if (
        not isinstance(supports, list)
        or not supports
        or any(s not in _FACES[:2] + _FACES[4:] for s in supports)
    ):
        raise where.error(
            f"{key}.supports", "must be a non-empty array of edges among left, right, bottom, top"
        )
    refine = integer(where, table.get("refine", 2), f"{key}.refine", minimum=1)
    origin = vector(where, table.get("origin", [0.0, 0.0, 0.0]), f"{key}.origin", 3, units.length)
    part = Part(young=young, poisson=poisson, **lengths)
    try:
        plates = Assembly(
            lower=part,
            upper=part,
            grid=(int(grid[0]), int(grid[1])),
            supports=tuple(supports),
            fasteners=(),
            refine=refine,
        )
        flexibility = plates.flexibilities[0]
        points = plates.build().points
    except InvalidInputError as exc:
        raise where.rewrap(key, exc) from None
    coordinates = np.column_stack([points, np.zeros(len(points))]) + origin
    model = ReducedModel(flexibility=flexibility, dofs_per_node=1, coordinates=coordinates)
    return PartInput(name, model, coordinates, coordinates.mean(axis=0))

"""Parsing a problem file: TOML text to a :class:`ProblemSpec` (a problem and how to solve it).

Every table is checked against its keys (:mod:`~contactqp.io.problem_file.schema`), every value
against its type, shape and range; each error is one line naming the file and the key
(:mod:`.messages`).
"""

from __future__ import annotations

import math
import os
import tomllib
import warnings
from pathlib import Path

import numpy as np

from ...core.contact import GapObstacle, NodePairs, Obstacle, PlaneObstacle, assemble_constraints
from ...core.friction import FrictionLaw
from ...core.history import linear_path
from ...core.model import ReducedModel
from ...core.problem import ContactProblem, FrictionalProblem
from ...errors import FileFormatError, InvalidInputError
from ...methods.registry import get_method
from .messages import Where, as_table, check_keys, counted, describe, one_line
from .options import route_options, solver_options, solver_section
from .schema import (
    FRICTION_KEYS,
    FRICTION_LAW_KEYS,
    LOAD_ENTRY_KEYS,
    LOADING_KEYS,
    LOADS_KEYS,
    MODEL_KEYS,
    OBSTACLE_KEYS,
    OBSTACLE_TYPES,
    TOP_KEYS,
)
from .spec import ProblemSpec
from .values import array, is_file_ref, option, per_contact

__all__ = ["load_problem_file"]


def _matrix(where: Where, model: dict) -> tuple[str, np.ndarray, str]:
    given = [name for name in ("flexibility", "stiffness") if name in model]
    if len(given) != 1:
        found = "both" if given else "neither"
        raise where.error(
            "[model]", f"give exactly one of flexibility and stiffness ({found} given)"
        )
    which = given[0]
    key = f"[model].{which}"
    value = model[which]
    matrix = array(where, value, key, 2)
    label = key
    if isinstance(value, str):
        label = f"{key} ('{value}')"
    elif isinstance(value, dict):
        label = f"{key} ('{value['file']}')"
    if matrix.shape[0] != matrix.shape[1] or matrix.size == 0:
        raise where.error(label, f"must be a non-empty square matrix, got shape {matrix.shape}")
    return which, matrix, label


def _dofs_per_node(where: Where, value, n_freedoms: int):
    key = "[model].dofs_per_node"
    if isinstance(value, int) and not isinstance(value, bool):
        if value not in (1, 2, 3):
            raise where.error(key, f"must be 1, 2 or 3, got {value}")
        if n_freedoms % value:
            raise where.error(
                key, f"the matrix has {n_freedoms} freedoms, not a multiple of {value}"
            )
        return value, n_freedoms // value
    if not (
        isinstance(value, list)
        and value
        and all(isinstance(v, int) and not isinstance(v, bool) for v in value)
    ):
        raise where.error(key, f"must be an integer or a list of integers, got {describe(value)}")
    if any(v not in (1, 2, 3) for v in value):
        raise where.error(key, "every entry must be 1, 2 or 3")
    if sum(value) != n_freedoms:
        raise where.error(key, f"sums to {sum(value)} freedoms, the matrix has {n_freedoms}")
    return list(value), len(value)


def _build_model(where: Where, doc: dict) -> ReducedModel:
    if "model" not in doc:
        raise where.error("[model]", "missing: give the flexibility or stiffness matrix")
    model = as_table(where, doc["model"], "[model]")
    check_keys(where, model, MODEL_KEYS, "[model]")
    which, matrix, label = _matrix(where, model)
    dofs, n_nodes = _dofs_per_node(where, model.get("dofs_per_node", 1), matrix.shape[0])
    coordinates = None
    if "coordinates" in model:
        coordinates = array(where, model["coordinates"], "[model].coordinates", 2)
        if coordinates.shape[0] != n_nodes:
            raise where.error(
                "[model].coordinates",
                f"has {counted(coordinates.shape[0], 'row')}, the model has "
                f"{counted(n_nodes, 'node')}",
            )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            flexibility, stiffness = (matrix, None) if which == "flexibility" else (None, matrix)
            built = ReducedModel(
                flexibility, stiffness, dofs_per_node=dofs, coordinates=coordinates
            )
        except InvalidInputError as exc:
            raise where.rewrap(label, exc) from None
    for warning in caught:
        warnings.warn(
            one_line(f"{where.path}: {label}: {warning.message}"), warning.category, stacklevel=3
        )
    return built


def _loads(where: Where, doc: dict, model: ReducedModel) -> np.ndarray:
    if "loads" not in doc:
        raise where.error("[loads]", "missing: give values = [...] or entries = [...]")
    loads = as_table(where, doc["loads"], "[loads]")
    check_keys(where, loads, LOADS_KEYS, "[loads]")
    given = [name for name in LOADS_KEYS if name in loads]
    if len(given) != 1:
        found = "both" if given else "neither"
        raise where.error("[loads]", f"give exactly one of values and entries ({found} given)")
    n = model.n_freedoms
    if "values" in loads:
        values = array(where, loads["values"], "[loads].values", 1)
        if values.size != n:
            raise where.error(
                "[loads].values",
                f"has {counted(values.size, 'entry', 'entries')}, the model has "
                f"{counted(n, 'freedom')}",
            )
        return values
    entries = loads["entries"]
    if not isinstance(entries, list):
        raise where.error("[loads].entries", f"must be an array of tables, got {describe(entries)}")
    P = np.zeros(n)
    seen: dict[int, int] = {}
    for number, entry in enumerate(entries, start=1):
        key = f"[loads].entries #{number}"
        entry = as_table(where, entry, key)
        check_keys(where, entry, LOAD_ENTRY_KEYS, key)
        value = entry.get("value")
        if not (
            isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
        ):
            raise where.error(key, f"value must be a finite number, got {describe(value)}")
        for name in ("freedom", "node", "component"):
            item = entry.get(name)
            if item is not None and (not isinstance(item, int) or isinstance(item, bool)):
                raise where.error(key, f"{name} must be an integer, got {describe(item)}")
        if "freedom" in entry:
            if "node" in entry or "component" in entry:
                raise where.error(key, "give freedom, or node with component, not both")
            freedom = entry["freedom"]
            if not 0 <= freedom < n:
                raise where.error(
                    key,
                    f"freedom {freedom} is outside 0..{n - 1} (the model has "
                    f"{counted(n, 'freedom')})",
                )
        elif "node" in entry:
            node, component = entry["node"], entry.get("component", 0)
            if not 0 <= node < model.n_nodes:
                raise where.error(
                    key,
                    f"node {node} is outside 0..{model.n_nodes - 1} (the model has "
                    f"{counted(model.n_nodes, 'node')})",
                )
            count = int(model.dofs_per_node[node])
            if not 0 <= component < count:
                raise where.error(
                    key,
                    f"component {component} is outside 0..{count - 1} (node {node} has "
                    f"{counted(count, 'freedom')})",
                )
            freedom = int(model.offsets[node]) + component
        else:
            raise where.error(key, "give freedom, or node (with component), for the value")
        if freedom in seen:
            raise where.error(key, f"freedom {freedom} is already loaded by entry #{seen[freedom]}")
        seen[freedom] = number
        P[freedom] = float(value)
    return P


def _nodes(where: Where, value, key: str, model: ReducedModel) -> np.ndarray:
    nodes = array(where, value, key, 1, integer=True)
    if nodes.size == 0:
        raise where.error(key, "is empty")
    bad = nodes[(nodes < 0) | (nodes >= model.n_nodes)]
    if bad.size:
        raise where.error(
            key,
            f"node {bad[0]} is outside 0..{model.n_nodes - 1} (the model has "
            f"{counted(model.n_nodes, 'node')})",
        )
    return nodes


def _directions(where: Where, table: dict, key: str, count: int):
    if "direction" in table and "directions" in table:
        raise where.error(key, "give direction or directions, not both")
    if "directions" in table:
        dirs = array(where, table["directions"], f"{key}.directions", 2)
        if dirs.shape[0] != count:
            raise where.error(
                f"{key}.directions",
                f"has {counted(dirs.shape[0], 'row')}, expected {count} (one per contact)",
            )
        return dirs
    if "direction" in table:
        return array(where, table["direction"], f"{key}.direction", 1)
    return np.array([1.0])


def _require(where: Where, table: dict, names, key: str, kind: str) -> None:
    for name in names:
        if name not in table:
            raise where.error(key, f"a {kind} obstacle needs '{name}'")


def _gaps(where: Where, value, key: str, count: int, what: str) -> np.ndarray:
    gaps = array(where, value, key, 1)
    if gaps.size != count:
        raise where.error(key, f"has {counted(gaps.size, 'value')} for {counted(count, what)}")
    return gaps


def _obstacle(where: Where, table, number: int, model: ReducedModel):
    key = f"[[obstacle]] #{number}"
    table = as_table(where, table, key)
    kind = table.get("type")
    if kind is None:
        raise where.error(
            key,
            f"missing 'type' (expected {', '.join(OBSTACLE_TYPES[:-1])} or {OBSTACLE_TYPES[-1]})",
        )
    if kind == "profile":
        raise where.error(
            key,
            "type 'profile' cannot be given in a file (its profile is a Python function); "
            'tabulate the gaps and use type = "gaps", or build a ProfileObstacle in Python',
        )
    if kind not in OBSTACLE_TYPES:
        raise where.error(
            key,
            f"unknown type {kind!r} (expected {', '.join(OBSTACLE_TYPES[:-1])} or "
            f"{OBSTACLE_TYPES[-1]})",
        )
    check_keys(where, table, OBSTACLE_KEYS[kind], key)
    if kind == "gaps":
        _require(where, table, ("nodes", "gaps"), key, kind)
        nodes = _nodes(where, table["nodes"], f"{key}.nodes", model)
        gaps = _gaps(where, table["gaps"], f"{key}.gaps", nodes.size, "node")
        dirs = _directions(where, table, key, nodes.size)
        obstacle: Obstacle = GapObstacle(nodes.tolist(), gaps, dirs)
    elif kind == "plane":
        _require(where, table, ("point", "normal"), key, kind)
        if model.coordinates is None:
            raise where.error(key, "a plane obstacle needs [model].coordinates")
        point = array(where, table["point"], f"{key}.point", 1)
        normal = array(where, table["normal"], f"{key}.normal", 1)
        nodes = None
        if "nodes" in table:
            nodes = _nodes(where, table["nodes"], f"{key}.nodes", model).tolist()
        obstacle = PlaneObstacle(point, normal, nodes)
    else:
        _require(where, table, ("pairs", "gaps"), key, kind)
        pairs = array(where, table["pairs"], f"{key}.pairs", 2, integer=True)
        if pairs.shape[1] != 2 or pairs.shape[0] == 0:
            raise where.error(
                f"{key}.pairs", f"must be a list of [a, b] pairs, got shape {pairs.shape}"
            )
        _nodes(where, pairs.reshape(-1).tolist(), f"{key}.pairs", model)
        gaps = _gaps(where, table["gaps"], f"{key}.gaps", pairs.shape[0], "pair")
        dirs = _directions(where, table, key, pairs.shape[0])
        obstacle = NodePairs(pairs.tolist(), gaps, dirs)
    try:
        obstacle.rows(model)  # the library's own checks, attributed to this obstacle
    except InvalidInputError as exc:
        raise where.rewrap(f"{key} ({kind})", exc) from None
    return obstacle


def _obstacles(where: Where, doc: dict, model: ReducedModel) -> list:
    if "obstacle" not in doc:
        raise where.error("[[obstacle]]", "missing: give at least one [[obstacle]] table")
    tables = doc["obstacle"]
    if isinstance(tables, dict):
        raise where.error(
            "[[obstacle]]",
            "write [[obstacle]] (an array of tables, double brackets), not [obstacle]",
        )
    if not isinstance(tables, list) or not tables:
        raise where.error("[[obstacle]]", "give at least one [[obstacle]] table")
    return [_obstacle(where, table, number, model) for number, table in enumerate(tables, 1)]


def _one_freedom_contacts(where: Where, model: ReducedModel, obstacles) -> None:
    """Raise when a contact node has one freedom (no tangent, so no friction)."""
    for number, obstacle in enumerate(obstacles, 1):
        for row in obstacle.rows(model):
            node = row[0]
            if model.dofs_per_node[node] == 1:
                raise where.error(
                    "[friction]",
                    f"friction needs contact nodes with 2 or 3 freedoms (a tangent), but node "
                    f"{node} of [[obstacle]] #{number} has 1 ([model].dofs_per_node)",
                )


def _friction(
    where: Where, table, model: ReducedModel, loads: np.ndarray, obstacles, certificate_tol: float
) -> tuple[FrictionalProblem, str, dict]:
    """The frictional problem of ``[friction]``, its route and the route's options."""
    table = as_table(where, table, "[friction]")
    if "mu" not in table:
        raise where.error("[friction]", "missing 'mu' (the friction coefficient, >= 0)")
    _one_freedom_contacts(where, model, obstacles)
    n_contacts = assemble_constraints(model, obstacles).n_constraints
    given = {}
    for name in FRICTION_LAW_KEYS:  # each key checked by the law, in turn, to name it
        if name in table:
            key = f"[friction].{name}"
            value = table[name]
            given[name] = value if name == "facets" else per_contact(where, value, key)
            try:
                law = FrictionLaw(**given, n_contacts=n_contacts)
            except InvalidInputError as exc:
                raise where.rewrap(key, exc) from None
    route = table.get("solver")
    if route is not None and not isinstance(route, str):
        raise where.error("[friction].solver", f"must be a string, got {describe(route)}")
    kind = "frictional" if law.facets is None else "frictional-polygonal"
    try:
        route = get_method(route, kind).name
        named, extra = solver_options(route, kind)
    except InvalidInputError as exc:
        raise where.rewrap("[friction].solver", exc) from None
    options = route_options(
        where, table, "[friction]", f"friction solver '{route}'", named, extra, FRICTION_KEYS
    )
    try:
        problem = FrictionalProblem(
            model,
            loads,
            obstacles,
            law.mu,
            law.cohesion,
            law.facets,
            certificate_tol=certificate_tol,
        )
    except InvalidInputError as exc:
        raise where.rewrap("[friction]", exc) from None
    return problem, route, options


def _points(where: Where, value, n: int) -> np.ndarray:
    """``[loading].points``: a matrix, a file holding one, or a list of vectors and files."""
    key = "[loading].points"
    if isinstance(value, list) and any(is_file_ref(item) for item in value):
        rows = [array(where, item, f"{key} #{number}", 1) for number, item in enumerate(value, 1)]
        for number, row in enumerate(rows, 1):
            if row.size != n:
                raise where.error(
                    f"{key} #{number}",
                    f"has {counted(row.size, 'value')}, the model has {counted(n, 'freedom')}",
                )
        return np.array(rows)
    points = array(where, value, key, 2)
    if points.shape[1] != n or points.shape[0] == 0:
        raise where.error(
            key, f"must have rows of {n} values (one per freedom), got shape {points.shape}"
        )
    return points


def _loading(
    where: Where, table, loads: np.ndarray | None, n: int
) -> tuple[np.ndarray, np.ndarray | None]:
    """``(history, factors)`` of ``[loading]``: loads of each step (K, n) and, for
    ``factors``, each step's multiple of ``loads`` (K,), else None."""
    table = as_table(where, table, "[loading]")
    check_keys(where, table, LOADING_KEYS, "[loading]")
    given = [name for name in ("factors", "points") if name in table]
    if len(given) != 1:
        found = "both" if given else "neither"
        raise where.error("[loading]", f"give exactly one of factors and points ({found} given)")
    steps = option(where, "steps", table.get("steps", 1), 1, "[loading].steps")
    if "factors" in table:
        factors = array(where, table["factors"], "[loading].factors", 1)
        if factors.size == 0:
            raise where.error("[loading].factors", "is empty")
        turning = factors[:, None]
    else:
        if loads is not None:
            raise where.error(
                "[loading].points",
                "give the loads here or in [loads], not both (factors = [...] scales [loads])",
            )
        turning = _points(where, table["points"], n)
    try:
        path = linear_path(turning, steps)
    except InvalidInputError as exc:
        raise where.rewrap("[loading].steps", exc) from None
    if "factors" in table:
        return path * loads, path[:, 0]
    return path, None


def load_problem_file(path: str | os.PathLike[str]) -> ProblemSpec:
    """Read a TOML problem file and assemble its problem (schema: ``docs/problem-files.md``).

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file. Matrix and array files it names are looked for relative to its directory.

    Returns
    -------
    ProblemSpec

    Raises
    ------
    FileFormatError
        The TOML file or a file it names is missing or unreadable, or the TOML is malformed.
    InvalidInputError
        Any content error: unknown key, wrong type or length, NaN or inf, unknown obstacle type
        or solver, a friction law or load history that does not fit the model. Errors of the
        model or problem (e.g. :class:`NotPositiveDefiniteError`) keep their class. Every
        message is one line naming the file and the key.
    """
    path = Path(path)
    where = Where(path)
    try:
        with open(path, encoding="utf-8-sig", newline="") as handle:  # -sig: skip a BOM
            doc = tomllib.loads(handle.read())
    except FileNotFoundError:
        raise where.error("", "problem file not found", FileFormatError) from None
    except IsADirectoryError:
        raise where.error("", "is a directory, not a problem file", FileFormatError) from None
    except tomllib.TOMLDecodeError as exc:
        raise where.error("", f"malformed TOML: {exc}", FileFormatError) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise where.error("", f"cannot read the problem file: {exc}", FileFormatError) from None
    check_keys(where, doc, TOP_KEYS, "top level")
    name = doc.get("name", path.stem)
    if not isinstance(name, str):
        raise where.error("name", f"must be a string, got {describe(name)}")
    frictional = "friction" in doc
    if "loading" in doc and not frictional:
        raise where.error(
            "[loading]",
            "a load history needs [friction] (without friction the "
            "answer does not depend on the load path)",
        )
    solver, options, certificate_tol = solver_section(where, doc, frictional)
    model = _build_model(where, doc)
    loading = as_table(where, doc.get("loading", {}), "[loading]")
    history: np.ndarray | None
    factors: np.ndarray | None
    if "points" in loading and "loads" not in doc:  # the history's first step is the load
        obstacles = _obstacles(where, doc, model)
        history, factors = _loading(where, loading, None, model.n_freedoms)
        loads = history[0]
    else:
        loads = _loads(where, doc, model)
        obstacles = _obstacles(where, doc, model)
        history, factors = None, None
        if "loading" in doc:
            history, factors = _loading(where, loading, loads, model.n_freedoms)
    problem: ContactProblem | FrictionalProblem
    if frictional:
        problem, solver, options = _friction(
            where, doc["friction"], model, loads, obstacles, certificate_tol
        )
    else:
        try:
            problem = ContactProblem(model, loads, obstacles, certificate_tol=certificate_tol)
        except InvalidInputError as exc:
            raise where.rewrap("problem", exc) from None
    return ProblemSpec(
        problem=problem,
        solver=solver,
        options=options,
        name=name,
        path=path,
        history=history,
        factors=factors,
    )

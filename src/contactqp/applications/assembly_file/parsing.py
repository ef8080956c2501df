"""Reading an assembly file: TOML to an :class:`~.result.AssemblyInput`.

Every table is checked against its keys
(:mod:`~contactqp.applications.assembly_file.schema`) and every value against its type, shape and
range; each error is one line that starts with the file and names the key
(:class:`contactqp.io.problem_file.messages.Where`). The file is only read, never written.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np

from ...errors import ContactError, FileFormatError, InvalidInputError
from ...io.problem_file.messages import Where, as_table, check_keys, counted, describe
from ...io.problem_file.options import route_options, solver_options
from ...methods.registry import default_method
from ..fastening import Fastener, InterfacePairs
from .gaps import Cloud
from .pairing import UnmatchedNodes, geometric_normals, pair_by_proximity, pair_distances
from .parts import PartInput, _box, read_part
from .result import AssemblyInput, load_vector, pair_points
from .schema import (
    CRITERIA_KEYS,
    FASTENER_KEYS,
    FASTENING_KEYS,
    FRICTION_KEYS,
    GAPS_KEYS,
    INTERFACE_KEYS,
    INTERPOLANTS,
    LOAD_KEYS,
    SOLVER_KEYS,
    TOP_KEYS,
    VARIATION_KEYS,
    VARIATION_TYPES,
)
from .values import (
    Units,
    array,
    boolean,
    choice,
    file_path,
    integer,
    is_file_ref,
    number,
    read_columns,
    require_columns,
    string,
    units_section,
    vector,
)

__all__ = ["read_assembly_file"]


def read_assembly_file(path: str | Path) -> AssemblyInput:
    """Read an assembly file (schema: ``docs/assembly-files.md``).

    Parameters
    ----------
    path : str or Path
        The TOML file; relative paths inside it are relative to its directory.

    Returns
    -------
    AssemblyInput

    Raises
    ------
    FileFormatError
        A missing file, invalid TOML, or a missing or unreadable file it names.
    InvalidInputError
        Any other bad input; the message names the file and the key.
    """
    path = Path(path)
    if not path.is_file():
        raise FileFormatError(f"{path}: assembly file not found")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise FileFormatError(f"{path}: not valid TOML: {exc}") from None
    where = Where(path)
    check_keys(where, doc, TOP_KEYS, "top level")
    name = string(where, doc["name"], "name") if "name" in doc else path.stem
    units = units_section(where, doc)
    parts = _parts(where, doc, units)
    interfaces, unmatched = _interfaces(where, doc, parts, units)
    points = pair_points(parts, interfaces)
    gaps, interpolation, cloud = _gaps(where, doc, points, units)
    variation, description = _variation(where, doc, points, gaps, cloud, units)
    freedoms = _pair_freedoms(parts, interfaces)
    fasteners = _fasteners(where, doc, points, freedoms, units)
    mu, facets = _friction(where, doc, freedoms)
    steps = _loads(where, doc, parts, units)
    shim = _criteria(where, doc, units)
    kind = (
        "fastened"
        if not np.any(mu)
        else "frictional"
        if facets is None
        else ("frictional-polygonal")
    )
    method, options = _solver(where, doc, kind)
    return AssemblyInput(
        name=name,
        path=path,
        parts=parts,
        interfaces=interfaces,
        unmatched=unmatched,
        gaps=gaps,
        variation=variation,
        variation_description=description,
        interpolation_error=interpolation,
        fasteners=fasteners,
        mu=mu,
        facets=facets,
        load_steps=steps,
        shim_tolerance=shim,
        method=method,
        kind=kind,
        options=options,
    )


def _parts(where: Where, doc: dict, units: Units) -> tuple[PartInput, ...]:
    if "parts" not in doc:
        raise where.error("parts", "missing: give two or more [parts.NAME] tables")
    table = as_table(where, doc["parts"], "parts")
    if len(table) < 2:
        raise where.error("parts", f"needs two or more parts, got {len(table)}")
    return tuple(read_part(where, name, value, units) for name, value in table.items())


def _tables(where: Where, doc: dict, key: str) -> list[dict]:
    """The array of tables ``[[key]]`` (empty when absent)."""
    value = doc.get(key, [])
    if not isinstance(value, list):
        raise where.error(key, f"must be an array of tables [[{key}]], got {describe(value)}")
    return [as_table(where, item, f"{key}[{i}]") for i, item in enumerate(value)]


def _part_name(where: Where, table: dict, key: str, parts) -> PartInput:
    if key.rsplit(".", 1)[-1] not in table:
        raise where.error(key, "missing: name a part")
    name = table[key.rsplit(".", 1)[-1]]
    for part in parts:
        if part.name == name:
            return part
    names = ", ".join(part.name for part in parts)
    raise where.error(key, f"no part named {describe(name)} (parts: {names})")


def _interfaces(where: Where, doc: dict, parts, units: Units):
    tables = _tables(where, doc, "interfaces")
    if not tables:
        raise where.error("interfaces", "missing: give one or more [[interfaces]]")
    interfaces, unmatched = [], []
    for number_, table in enumerate(tables):
        key = f"interfaces[{number_}]"
        check_keys(where, table, INTERFACE_KEYS, key)
        first = _part_name(where, table, f"{key}.first", parts)
        second = _part_name(where, table, f"{key}.second", parts)
        if first.name == second.name:
            raise where.error(f"{key}.second", "must differ from first")
        tolerance = None
        if "tolerance" in table:
            tolerance = number(
                where, table["tolerance"], f"{key}.tolerance", positive=True, scale=units.length
            )
        if "pairs" in table:
            pairs = _explicit_pairs(where, table["pairs"], f"{key}.pairs", first, second)
            if tolerance is not None:
                distance = pair_distances(first.coordinates, second.coordinates, pairs)
                far = np.flatnonzero(distance > tolerance)
                if far.size:
                    raise where.error(
                        f"{key}.pairs",
                        f"pair {far[0]} ({pairs[far[0], 0]}, {pairs[far[0], 1]}) is "
                        f"{distance[far[0]]:.4g} m apart, beyond the tolerance {tolerance:.4g} m"
                        f" ({counted(far.size, 'pair')} beyond it)",
                    )
        elif tolerance is not None:
            pairs, alone_first, alone_second = pair_by_proximity(
                first.coordinates, second.coordinates, tolerance
            )
            if pairs.size == 0:
                raise where.error(
                    f"{key}.tolerance",
                    f"no node of '{first.name}' lies within {tolerance:.4g} m of a node of "
                    f"'{second.name}'",
                )
            for part, alone in ((first, alone_first), (second, alone_second)):
                if alone.size:
                    unmatched.append(UnmatchedNodes(number_, part.name, alone, part.model.n_nodes))
        else:
            raise where.error(key, "give pairs, or a tolerance to pair nodes by proximity")
        normals = _normals(
            where, table.get("normal", "geometry"), f"{key}.normal", first, second, pairs
        )
        interfaces.append(InterfacePairs(first.name, second.name, pairs, normals))
    return tuple(interfaces), tuple(unmatched)


def _explicit_pairs(where: Where, value, key: str, first: PartInput, second: PartInput):
    pairs = array(where, value, key, 2, integer=True)
    if pairs.shape[1] != 2 or pairs.shape[0] == 0:
        raise where.error(key, f"must be rows (node of first, node of second), got {pairs.shape}")
    for column, part in enumerate((first, second)):
        nodes = pairs[:, column]
        bad = np.flatnonzero((nodes < 0) | (nodes >= part.model.n_nodes))
        if bad.size:
            raise where.error(
                key,
                f"pair {bad[0]}: node {nodes[bad[0]]} is outside 0..{part.model.n_nodes - 1} "
                f"('{part.name}' has {counted(part.model.n_nodes, 'node')})",
            )
        unique, counts = np.unique(nodes, return_counts=True)
        if np.any(counts > 1):
            raise where.error(
                key, f"node {unique[counts > 1][0]} of '{part.name}' is in more than one pair"
            )
    return pairs


def _unit_rows(where: Where, rows: np.ndarray, key: str) -> np.ndarray:
    length = np.linalg.norm(rows, axis=1)
    if np.any(length == 0.0):
        raise where.error(key, f"normal {int(np.argmax(length == 0.0))} is zero")
    return rows / length[:, None]


def _normals(where: Where, value, key: str, first: PartInput, second: PartInput, pairs):
    k = len(pairs)
    if value == "geometry":
        normals, problem = geometric_normals(
            first.coordinates, pairs[:, 0], second.centroid - first.centroid
        )
        if problem:
            raise where.error(key, f"{problem}; give normal = [x, y, z]")
        return normals
    if isinstance(value, list) and value and not isinstance(value[0], list):
        one = vector(where, value, key, 3)
        return np.repeat(_unit_rows(where, one[None, :], key), k, axis=0)
    if not (is_file_ref(value) or isinstance(value, list)):
        raise where.error(
            key, f'must be "geometry", [x, y, z] or one row per pair, got {describe(value)}'
        )
    rows = array(where, value, key, 2)
    if rows.shape != (k, 3):
        raise where.error(key, f"must have shape ({k}, 3) (one row per pair), got {rows.shape}")
    return _unit_rows(where, rows, key)


def _gaps(where: Where, doc: dict, points: np.ndarray, units: Units):
    """``(gaps, interpolation error or None, (cloud, interpolant, extrapolate) or None)``."""
    table = as_table(where, doc.get("gaps", {}), "gaps")
    check_keys(where, table, GAPS_KEYS, "gaps")
    k = len(points)
    interpolant = choice(
        where, table.get("interpolant", "linear"), "gaps.interpolant", INTERPOLANTS
    )
    extrapolate = boolean(where, table.get("extrapolate", False), "gaps.extrapolate")
    settings = (interpolant, extrapolate)
    if "nominal" in table and "cloud" in table:
        raise where.error("gaps", "give nominal or cloud, not both")
    if "cloud" in table:
        columns, _ = read_columns(
            where, table["cloud"], "gaps.cloud", ("x", "y", "z", "gap"), units
        )
        require_columns(where, columns, "gaps.cloud", ("x", "y", "gap"))
        cloud = _cloud(where, columns, "gaps.cloud", points, extrapolate)
        gaps = cloud.interpolate(columns["gap"], points, interpolant)
        error = cloud.leave_one_out(columns["gap"], interpolant)
        return gaps, error, (cloud, *settings)
    value = table.get("nominal", 0.0)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return np.full(k, number(where, value, "gaps.nominal", scale=units.length)), None, None
    gaps = array(where, value, "gaps.nominal", 1) * units.length
    if gaps.size != k:
        raise where.error(
            "gaps.nominal",
            f"has {counted(gaps.size, 'value')}, the interfaces have {counted(k, 'pair')}",
        )
    return gaps, None, None


def _cloud(where: Where, columns: dict, key: str, points: np.ndarray, extrapolate: bool):
    names = ("x", "y", "z") if "z" in columns else ("x", "y")
    try:
        cloud = Cloud(np.column_stack([columns[name] for name in names]))
    except InvalidInputError as exc:
        raise where.rewrap(key, exc) from None
    outside = cloud.outside(points)
    if outside.size and not extrapolate:
        raise where.error(
            key,
            f"{counted(outside.size, 'pair')} outside the measured points' hull (e.g. pair "
            f"{outside[0]} at {np.round(points[outside[0]], 6).tolist()} m); measure there, or "
            "set gaps.extrapolate = true",
        )
    return cloud


def _variation(where: Where, doc: dict, points, gaps, cloud, units: Units):
    from ...studies import GaussianGapField, load_gap_samples
    from ...studies.sources import GapSamples

    if "variation" not in doc:
        return None, ""
    table = as_table(where, doc["variation"], "variation")
    if "type" not in table:
        raise where.error("variation.type", f"missing: give one of {', '.join(VARIATION_TYPES)}")
    kind = choice(where, table["type"], "variation.type", VARIATION_TYPES)
    check_keys(where, table, VARIATION_KEYS[kind], "variation")
    k = len(points)
    if kind == "random":
        for required in ("amplitude", "correlation_length"):
            if required not in table:
                raise where.error(f"variation.{required}", "missing")
        amplitude = number(
            where, table["amplitude"], "variation.amplitude", nonnegative=True, scale=units.length
        )
        length = number(
            where,
            table["correlation_length"],
            "variation.correlation_length",
            positive=True,
            scale=units.length,
        )
        seed = integer(where, table.get("seed", 0), "variation.seed", minimum=0)
        source = GaussianGapField(points, amplitude, length, mean=gaps, seed=seed)
        return source, (
            f"random field around the nominal gaps: amplitude {amplitude:.4g} m, correlation "
            f"length {length:.4g} m, seed {seed}"
        )
    if "file" not in table:
        raise where.error("variation.file", "missing")
    if kind == "samples":
        path = file_path(where, table["file"], "variation.file")
        try:
            samples = load_gap_samples(path).samples * units.length
        except ContactError as exc:
            message = str(exc).removeprefix(f"{path}: ")
            raise where.rewrap("variation.file", type(exc)(message)) from None
        if samples.shape[1] != k:
            raise where.error(
                "variation.file",
                f"rows have {samples.shape[1]} gaps, the interfaces have {counted(k, 'pair')}",
            )
        return GapSamples(samples), f"{len(samples)} gap realisations from '{table['file']}'"
    columns, _ = read_columns(where, table["file"], "variation.file", ("*",), units)
    require_columns(where, columns, "variation.file", ("x", "y"))
    measured = [name for name in columns if name not in ("x", "y", "z")]
    if not measured:
        raise where.error("variation.file", "has no gap column (one per measured assembly)")
    interpolant, extrapolate = cloud[1:] if cloud else ("linear", False)
    shape = _cloud(where, columns, "variation.file", points, extrapolate)
    samples = np.array([shape.interpolate(columns[c], points, interpolant) for c in measured])
    return GapSamples(samples), (
        f"{len(measured)} measured assemblies from '{table['file']}' ({interpolant} interpolation)"
    )


def _pair_freedoms(parts, interfaces) -> np.ndarray:
    """The fewest freedoms of each pair's two nodes, shape (k,)."""
    by_name = {part.name: part for part in parts}
    blocks = [
        np.minimum(
            by_name[i.first].model.dofs_per_node[i.nodes[:, 0]],
            by_name[i.second].model.dofs_per_node[i.nodes[:, 1]],
        )
        for i in interfaces
    ]
    return np.concatenate(blocks)


def _fasteners(where: Where, doc: dict, points, freedoms, units: Units):
    tables = _tables(where, doc, "fasteners")
    setting = as_table(where, doc.get("fastening", {}), "fastening")
    check_keys(where, setting, FASTENING_KEYS, "fastening")
    tolerance = None
    if "tolerance" in setting:
        tolerance = number(
            where, setting["tolerance"], "fastening.tolerance", positive=True, scale=units.length
        )
    from scipy.spatial import cKDTree

    trees: dict[int, cKDTree] = {}
    fasteners: list[Fastener] = []
    used: dict[int, int] = {}
    for index, table in enumerate(tables):
        key = f"fasteners[{index}]"
        check_keys(where, table, FASTENER_KEYS, key)
        if ("position" in table) == ("pair" in table):
            raise where.error(key, "give position or pair (exactly one)")
        if "pair" in table:
            pair = integer(where, table["pair"], f"{key}.pair", minimum=0)
            if pair >= len(points):
                raise where.error(
                    f"{key}.pair",
                    f"is outside 0..{len(points) - 1} (there are {counted(len(points), 'pair')})",
                )
        else:
            position = vector(where, table["position"], f"{key}.position", (2, 3), units.length)
            if tolerance is None:
                raise where.error(
                    "fastening.tolerance", "missing: fasteners given by position need it"
                )
            dim = position.size
            if dim not in trees:
                trees[dim] = cKDTree(points[:, :dim])
            distance, nearest = trees[dim].query(position)
            pair = int(nearest)
            if distance > tolerance:
                raise where.error(
                    f"{key}.position",
                    f"the nearest pair ({pair}) is {distance:.4g} m away, beyond "
                    f"fastening.tolerance = {tolerance:.4g} m",
                )
        if pair in used:
            raise where.error(key, f"pair {pair} already has fasteners[{used[pair]}]")
        used[pair] = index
        kind = choice(where, table.get("kind", "closure"), f"{key}.kind", ("closure", "clamp"))
        force, stiffness = 0.0, math.inf
        if kind == "closure":
            for extra in ("force", "stiffness"):
                if extra in table:
                    raise where.error(f"{key}.{extra}", 'only a clamp has one (kind = "clamp")')
        else:
            for required in ("force", "stiffness"):
                if required not in table:
                    raise where.error(f"{key}.{required}", "missing: a clamp needs it")
            force = number(
                where, table["force"], f"{key}.force", nonnegative=True, scale=units.force
            )
            stiffness = number(
                where, table["stiffness"], f"{key}.stiffness", positive=True, scale=units.stiffness
            )
        in_plane = freedoms[pair] == 3
        shear = choice(
            where,
            table.get("shear", "bonded" if in_plane else "free"),
            f"{key}.shear",
            ("bonded", "free"),
        )
        if shear == "bonded" and not in_plane:
            raise where.error(
                f"{key}.shear",
                f"pair {pair}'s nodes have no in-plane freedoms in the reduced model: only "
                '"free" applies',
            )
        label = (
            string(where, table["label"], f"{key}.label")
            if "label" in table
            else f"fastener {index} (pair {pair})"
        )
        fasteners.append(Fastener(pair, kind, force, stiffness, shear, label))
    if "order" in setting:
        return tuple(fasteners[i] for i in _order(where, setting["order"], fasteners))
    return tuple(fasteners)


def _order(where: Where, value, fasteners) -> list[int]:
    key = "fastening.order"
    if not isinstance(value, list):
        raise where.error(
            key, f"must be an array of fastener indices or labels, got {describe(value)}"
        )
    labels = {f.label: i for i, f in enumerate(fasteners)}
    order = []
    for item in value:
        if isinstance(item, str):
            if item not in labels:
                raise where.error(key, f"no fastener labelled {item!r}")
            order.append(labels[item])
        elif isinstance(item, int) and not isinstance(item, bool):
            if not 0 <= item < len(fasteners):
                raise where.error(key, f"fastener {item} is outside 0..{len(fasteners) - 1}")
            order.append(item)
        else:
            raise where.error(key, f"entries must be indices or labels, got {describe(item)}")
    if sorted(order) != list(range(len(fasteners))):
        missing = sorted(set(range(len(fasteners))) - set(order))
        twice = sorted({i for i in order if order.count(i) > 1})
        problem = f"lists fastener {twice[0]} twice" if twice else (f"misses fastener {missing[0]}")
        raise where.error(key, f"must list every fastener once: it {problem}")
    return order


def _friction(where: Where, doc: dict, freedoms) -> tuple[np.ndarray, int | None]:
    k = len(freedoms)
    table = as_table(where, doc.get("friction", {}), "friction")
    check_keys(where, table, FRICTION_KEYS, "friction")
    value = table.get("mu", 0.0)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        mu = np.full(k, number(where, value, "friction.mu", nonnegative=True))
    else:
        mu = array(where, value, "friction.mu", 1)
        if mu.size != k:
            raise where.error(
                "friction.mu",
                f"has {counted(mu.size, 'value')}, the interfaces have {counted(k, 'pair')}",
            )
        if np.any(mu < 0):
            raise where.error("friction.mu", f"must be >= 0 (pair {int(np.argmax(mu < 0))})")
    lacking = np.flatnonzero((mu > 0) & (freedoms < 3))
    if lacking.size:
        raise where.error(
            "friction.mu",
            f"pair {lacking[0]}'s nodes have no in-plane freedoms in the reduced model "
            f"({counted(lacking.size, 'pair')} with mu > 0 lack them): friction needs "
            "3 freedoms per node",
        )
    cone = choice(where, table.get("cone", "exact"), "friction.cone", ("exact", "polygonal"))
    facets = None
    if cone == "polygonal":
        facets = integer(where, table.get("facets", 8), "friction.facets", minimum=3)
    elif "facets" in table:
        raise where.error("friction.facets", 'applies to cone = "polygonal" only')
    return mu, facets


def _loads(where: Where, doc: dict, parts, units: Units):
    steps, base = [], None
    for index, table in enumerate(_tables(where, doc, "loads")):
        key = f"loads[{index}]"
        check_keys(where, table, LOAD_KEYS, key)
        part = _part_name(where, table, f"{key}.part", parts)
        if "nodes" in table and "box" in table:
            raise where.error(key, "give nodes or box, not both")
        if "nodes" in table:
            nodes = array(where, table["nodes"], f"{key}.nodes", 1, integer=True)
            bad = nodes[(nodes < 0) | (nodes >= part.model.n_nodes)]
            if nodes.size == 0 or bad.size:
                raise where.error(
                    f"{key}.nodes", f"must be nodes of '{part.name}' in 0..{part.model.n_nodes - 1}"
                )
        elif "box" in table:
            box = _box(where, table["box"], f"{key}.box", units)
            nodes = np.flatnonzero(box(part.coordinates.T))
            if nodes.size == 0:
                raise where.error(f"{key}.box", f"holds no node of '{part.name}'")
        else:
            nodes = np.arange(part.model.n_nodes)
        if "force" not in table:
            raise where.error(f"{key}.force", "missing: give [Fx, Fy, Fz]")
        force = vector(where, table["force"], f"{key}.force", 3, units.force)
        count = integer(where, table.get("steps", 1), f"{key}.steps", minimum=1)
        remove = boolean(where, table.get("remove", True), f"{key}.remove")
        label = (
            string(where, table["label"], f"{key}.label") if "label" in table else (f"load {index}")
        )
        try:
            total = load_vector(parts, part.name, nodes, force)
        except InvalidInputError as exc:
            raise where.rewrap(f"{key}.force", exc) from None
        if base is None:
            base = np.zeros_like(total)
        for step in range(1, count + 1):
            name = label if count == 1 else f"{label} {step}/{count}"
            steps.append((name, base + total * step / count))
        if remove:
            for step in range(1, count + 1):
                name = f"{label} removed" if count == 1 else f"{label} removed {step}/{count}"
                steps.append((name, base + total * (1 - step / count)))
        else:
            base = base + total
    return tuple(steps)


def _criteria(where: Where, doc: dict, units: Units) -> float | None:
    table = as_table(where, doc.get("criteria", {}), "criteria")
    check_keys(where, table, CRITERIA_KEYS, "criteria")
    if "shim_tolerance" not in table:
        return None
    return number(
        where,
        table["shim_tolerance"],
        "criteria.shim_tolerance",
        nonnegative=True,
        scale=units.length,
    )


def _solver(where: Where, doc: dict, kind: str) -> tuple[str, dict]:
    table = as_table(where, doc.get("solver", {}), "[solver]")
    method = table.get("method", default_method(kind))
    if not isinstance(method, str):
        raise where.error("[solver].method", f"must be a string, got {describe(method)}")
    try:
        named, extra = solver_options(method, kind)
    except InvalidInputError as exc:
        raise where.rewrap("[solver].method", exc) from None
    options = route_options(
        where, table, "[solver]", f"method '{method}'", named, extra, SOLVER_KEYS
    )
    return method, options

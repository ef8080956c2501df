"""Problem files: a frictionless contact problem described in TOML, and its results written out.

This is what ``contactqp solve PROBLEM.toml`` reads (:func:`load_problem_file`) and writes
(:func:`write_results`).

The schema
----------
A problem file has five top-level entries, ``name``, ``[model]``, ``[loads]``, ``[[obstacle]]``
and ``[solver]``; nothing else is accepted. Every table rejects keys it does not know, so that a
typo (``flexibilty``, ``gap``, ``max_iters``) is an error and never a silently ignored setting.
Units are SI (metres, newtons): the file stores numbers, the physics decides their units, and the
results come back in the same units. Node and freedom indices count from 0; freedoms are ordered
node by node. Numbered entries in messages (``[[obstacle]] #2``, ``[loads].entries #3``) count
from 1, in the order they appear in the file.

**Arrays.** Every array-valued key takes either an inline TOML array (``[1.0, 2.0]``,
``[[1, 0], [0, 1]]``) or a *file reference*: a path string (``"R.csv"``) or an inline table
``{ file = "model.npz", key = "R" }``. Relative paths are relative to the directory of the TOML
file. Readable formats, chosen by the file's extension or by ``format = "..."`` in the table:

* ``.csv``, ``.txt``, ``.dat`` (``format = "csv"``): numbers separated by commas, or by spaces
  or tabs when the file has no comma; ``#`` starts a comment; no header row.
* ``.npz`` (``format = "npz"``): the array named by ``key``, or the only array in the archive; an
  archive written by :func:`scipy.sparse.save_npz` is read as a (densified) sparse matrix.
* ``.npy`` (``format = "npy"``): the stored array.
* ``.mtx``, ``.mtx.gz`` (``format = "mtx"``): MatrixMarket, through :func:`scipy.io.mmread`,
  dense or sparse (densified), ``symmetric`` storage included.
* ``.op4`` (``format = "op4"``): NASTRAN OUTPUT4, ASCII or binary, the matrix named by ``key``
  (e.g. ``{ file = "model.op4", key = "KAA" }``) or the only one in the file; needs pyNastran
  (:func:`contactqp.compliance.importers.op4_matrix`). ANSYS ``.full`` files and DMIG cards need
  a choice of nodes: read them with :mod:`contactqp.compliance.importers`.

A vector may be stored as one row or one column. Inline arrays and files must hold finite numbers
(TOML accepts ``nan`` and ``inf``; this schema does not).

**[model]** (required): the reduced model, :class:`~contactqp.ReducedModel`.

=================  ===========================================================================
``flexibility``    ``R`` (m/N), array, shape (n, n). Give exactly one of ``flexibility``
``stiffness``      and ``stiffness`` (``K``, N/m).
``dofs_per_node``  Integer 1, 2 or 3, or one integer per node (default 1).
``coordinates``    Array, shape (n_nodes, d), metres. Needed by ``plane`` obstacles.
=================  ===========================================================================

**[loads]** (required): the external forces ``P`` (N), by exactly one of

* ``values``: array of ``n`` numbers, one per freedom;
* ``entries``: an array of inline tables, the unlisted freedoms being unloaded. Each entry has a
  ``value`` and either ``freedom`` (global index) or ``node`` with ``component`` (default 0).
  A freedom may be listed once.

**[[obstacle]]** (one or more): unilateral constraints, by ``type``:

* ``type = "gaps"`` (:class:`~contactqp.GapObstacle`): ``nodes`` (required), ``gaps`` (m, one
  per node, required), and ``direction`` (one vector for every node) or ``directions`` (one row
  per node); default ``direction = [1.0]``.
* ``type = "plane"`` (:class:`~contactqp.PlaneObstacle`): ``point`` and ``normal`` (required;
  the normal points from the body towards the plane), ``nodes`` (default: every node). Needs
  ``[model].coordinates``.
* ``type = "pairs"`` (:class:`~contactqp.NodePairs`): ``pairs`` (array of ``[a, b]``, required),
  ``gaps`` (m, required), ``direction`` or ``directions`` from ``a`` towards ``b`` (default
  ``[1.0]``).

A :class:`~contactqp.ProfileObstacle` cannot be written in a file, because its profile is a
Python function: tabulate the gaps and use ``type = "gaps"``, or build the problem in Python.

**[solver]** (optional): how to solve it.

=====================  ======================================================================
``name``               A name from :data:`contactqp.SOLVERS`: ``"active-set"`` (default) or
                       ``"qp"``.
``certificate_tol``    Largest relative residual the certificate accepts (default 1e-7).
other keys             Keyword options of the chosen solver, checked against its signature:
                       ``tol`` and ``max_iter`` for ``"active-set"``, ``backend`` for ``"qp"``.
[solver.backend_options]
                       Only for solvers that pass extra settings on (``"qp"``): a table given
                       verbatim to the qpsolvers backend, under the backend's own names (e.g.
                       ``eps_abs`` for piqp). These names are checked by the backend when it
                       runs, not here, and some backends ignore unknown ones.
=====================  ======================================================================

Numeric solver options must be finite; ``tol``, ``max_iter`` and any ``*_tol`` must be positive.

Example
-------
A plate held by two 2-freedom nodes, pressed on a rigid floor and on a second part::

    name = "plate on floor"                  # optional; default: the file's stem

    [model]
    flexibility = "R.csv"                    # or stiffness = { file = "K.npz", key = "K" }
    dofs_per_node = 2                        # or [2, 2, 2]
    coordinates = [[0.0, 0.0], [0.01, 0.0], [0.01, 0.002]]   # m; or "xyz.csv"

    [loads]                                  # N
    entries = [
        { node = 2, component = 1, value = -500.0 },
        { freedom = 0, value = 20.0 },
    ]                                        # or values = [0.0, ...] (6 numbers), or "P.csv"

    [[obstacle]]
    type = "plane"
    point = [0.0, -0.0001]                   # m
    normal = [0.0, -1.0]
    nodes = [0, 1]

    [[obstacle]]
    type = "gaps"
    nodes = [2]
    gaps = [0.0002]                          # m; or gaps = "gaps.csv"
    direction = [1.0, 0.0]                   # or directions = [[1.0, 0.0]]

    [[obstacle]]
    type = "pairs"
    pairs = [[0, 2]]
    gaps = [0.002]
    direction = [0.0, 1.0]

    [solver]
    name = "qp"
    backend = "clarabel"
    certificate_tol = 1e-7

    [solver.backend_options]
    max_iter = 200

Errors
------
Every problem with a file raises :class:`~contactqp.errors.InvalidInputError`, or its subclass
:class:`~contactqp.errors.FileFormatError` for a missing or unreadable file and malformed TOML,
with a one-line message that starts with the TOML file's path and names the key, e.g.
``problem.toml: [model].flexibility: file 'R.csv' not found (looked for /data/R.csv)``. Errors
of :class:`~contactqp.ReducedModel` and :class:`~contactqp.ContactProblem` (a matrix that is not
positive definite, a direction with the wrong number of components, ...) are raised again with
the key as a prefix and their class kept (e.g.
:class:`~contactqp.errors.NotPositiveDefiniteError`).
"""

from __future__ import annotations

import csv
import difflib
import inspect
import json
import math
import os
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..contact import GapObstacle, NodePairs, PlaneObstacle
from ..errors import FileFormatError, InvalidInputError
from ..model import ReducedModel
from ..problem import ContactProblem
from ..result import CERTIFICATE_TOL, ContactResult
from ..solvers import SOLVERS, solve

__all__ = [
    "ProblemSpec",
    "load_problem_file",
    "write_results",
    "read_array",
    "ARRAY_FORMATS",
    "OBSTACLE_TYPES",
    "RESULT_FILES",
]

#: Array file formats and the file name endings that select them.
ARRAY_FORMATS = {
    "csv": (".csv", ".txt", ".dat"),
    "npz": (".npz",),
    "npy": (".npy",),
    "mtx": (".mtx", ".mtx.gz"),
    "op4": (".op4",),
}

#: Obstacle types a problem file may use.
OBSTACLE_TYPES = ("gaps", "plane", "pairs")

#: The files :func:`write_results` writes, in order.
RESULT_FILES = ("displacements.csv", "contacts.csv", "result.npz", "summary.json")

_TOP_KEYS = ("name", "model", "loads", "obstacle", "solver")
_MODEL_KEYS = ("flexibility", "stiffness", "dofs_per_node", "coordinates")
_LOADS_KEYS = ("values", "entries")
_FILE_REF_KEYS = ("file", "key", "format")
_OBSTACLE_KEYS = {
    "gaps": ("type", "nodes", "gaps", "direction", "directions"),
    "plane": ("type", "point", "normal", "nodes"),
    "pairs": ("type", "pairs", "gaps", "direction", "directions"),
}
_SCIPY_SPARSE_NPZ = {"format", "shape", "data"}


# --------------------------------------------------------------------------------------------
# Messages


def _one_line(text) -> str:
    """Collapse a message to one line."""
    return "; ".join(part.strip() for part in str(text).splitlines() if part.strip())


class _Where:
    """Prefixes messages with the TOML file and raises the errors of one problem file."""

    def __init__(self, path: Path):
        self.path = path
        self.base = path.parent

    def error(self, key: str, message: str, cls=InvalidInputError) -> Exception:
        """An exception of class ``cls`` whose message names the file and ``key``."""
        message = str(message)
        if not key:
            text = f"{self.path}: {message}"
        elif message.startswith("has "):  # reads as a sentence: "[loads].values has 4 entries"
            text = f"{self.path}: {key} {message}"
        else:
            text = f"{self.path}: {key}: {message}"
        return cls(_one_line(text))

    def rewrap(self, key: str, exc: Exception) -> Exception:
        """``exc`` raised again with ``key`` as a prefix, keeping its class."""
        message = _one_line(f"{self.path}: {key}: {exc}")
        try:
            return type(exc)(message)
        except Exception:  # an exception class with an unusual constructor
            return InvalidInputError(message)


def _close_match(name: str, allowed) -> str:
    guesses = difflib.get_close_matches(name, list(allowed), n=1)
    return f"; did you mean '{guesses[0]}'?" if guesses else ""


def _check_keys(where: _Where, table: dict, allowed, key: str) -> None:
    for name in table:
        if name not in allowed:
            raise where.error(
                key, f"unknown key '{name}' (allowed: {', '.join(sorted(allowed))})"
                f"{_close_match(name, allowed)}"
            )


def _table(where: _Where, value, key: str) -> dict:
    if not isinstance(value, dict):
        raise where.error(key, f"must be a table, got {_describe(value)}")
    return value


def _describe(value) -> str:
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, (int, float)):
        return f"the number {value!r}"
    if isinstance(value, list):
        return f"an array of {len(value)} entries"
    if isinstance(value, dict):
        return "a table"
    return f"a {type(value).__name__}"


def _count(n: int, word: str, plural: str | None = None) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {plural or word + 's'}"


# --------------------------------------------------------------------------------------------
# Arrays: inline or read from files


def _format_of(path: Path, fmt: str | None) -> str:
    if fmt is not None:
        if fmt not in ARRAY_FORMATS:
            raise InvalidInputError(
                f"unknown format {fmt!r} (expected {', '.join(ARRAY_FORMATS)})"
            )
        return fmt
    name = path.name.lower()
    for candidate, endings in ARRAY_FORMATS.items():
        if name.endswith(endings):
            return candidate
    known = ", ".join(e for endings in ARRAY_FORMATS.values() for e in endings)
    raise FileFormatError(
        f"cannot tell the format of '{path.name}' from its extension (known: {known}); "
        "give it with { file = ..., format = \"csv\" }"
    )


def _read_csv(path: Path) -> np.ndarray:
    with open(path, encoding="utf-8-sig") as handle:
        text = handle.read()
    body = "\n".join(line.split("#", 1)[0] for line in text.splitlines())
    if not body.strip():
        raise FileFormatError("the file holds no numbers")
    delimiter = "," if "," in body else None
    try:
        return np.loadtxt(body.splitlines(), delimiter=delimiter, ndmin=2, dtype=float)
    except ValueError as exc:
        raise FileFormatError(f"not a table of numbers: {exc}") from None


def _read_npz(path: Path, key: str | None) -> np.ndarray:
    with np.load(path, allow_pickle=False) as data:
        names = list(data.files)
        if key is None and _SCIPY_SPARSE_NPZ <= set(names):
            import scipy.sparse

            return scipy.sparse.load_npz(path).toarray()
        if key is None:
            if len(names) != 1:
                raise InvalidInputError(
                    f"the archive holds {len(names)} arrays ({', '.join(names) or 'none'}); "
                    "choose one with { file = ..., key = \"...\" }"
                )
            key = names[0]
        if key not in names:
            raise InvalidInputError(
                f"the archive has no array {key!r} (it holds {', '.join(names) or 'none'})"
            )
        return data[key]


def _read_mtx(path: Path) -> np.ndarray:
    import scipy.io

    matrix = scipy.io.mmread(str(path))
    return matrix.toarray() if hasattr(matrix, "toarray") else np.asarray(matrix)


def read_array(path, key: str | None = None, format: str | None = None) -> np.ndarray:
    """Read a numeric array from a CSV, NPY, NPZ, MatrixMarket or OP4 file.

    Parameters
    ----------
    path : str or os.PathLike
        The file. Its format comes from its extension (see :data:`ARRAY_FORMATS`) unless given.
    key : str, optional
        The array to take from an ``.npz`` archive (default: its only array; an archive written
        by :func:`scipy.sparse.save_npz` is read as one sparse matrix), or the matrix to take
        from an ``.op4`` file (default: its only matrix).
    format : {"csv", "npz", "npy", "mtx", "op4"}, optional
        Overrides the extension.

    Returns
    -------
    ndarray of float
        Dense; a CSV file always gives a 2-D array, sparse matrices are densified. The values are
        not checked for NaN or inf here.

    Raises
    ------
    FileFormatError
        The file is missing or unreadable, or its content is not numeric.
    InvalidInputError
        ``key`` is missing from the archive, or given for a format without keys.
    """
    path = Path(path)
    fmt = _format_of(path, format)
    if key is not None and fmt not in ("npz", "op4"):
        raise InvalidInputError(f"key {key!r} applies only to .npz and .op4 files, not to {fmt} "
                                "files")
    if not path.exists():
        raise FileFormatError(f"file '{path}' not found")
    if not path.is_file():
        raise FileFormatError(f"'{path}' is not a file")
    try:
        if fmt == "csv":
            array = _read_csv(path)
        elif fmt == "npz":
            array = _read_npz(path, key)
        elif fmt == "npy":
            array = np.load(path, allow_pickle=False)
        elif fmt == "op4":
            from ..compliance.importers import op4_matrix

            array = op4_matrix(path, key)
            array = array.toarray() if hasattr(array, "toarray") else array
        else:
            array = _read_mtx(path)
    except InvalidInputError:
        raise
    except (OSError, ValueError, EOFError, UnicodeDecodeError) as exc:
        raise FileFormatError(f"cannot read {fmt} file: {_one_line(exc)}") from None
    array = np.asarray(array)
    if np.iscomplexobj(array):
        raise FileFormatError("the file holds complex numbers; a real array is needed")
    if not (np.issubdtype(array.dtype, np.number) or array.dtype == bool):
        raise FileFormatError(f"the file holds {array.dtype} values, not numbers")
    return array.astype(float)


def _is_file_ref(value) -> bool:
    return isinstance(value, str) or (isinstance(value, dict) and "file" in value)


def _load_ref(where: _Where, value, key: str) -> tuple[np.ndarray, str]:
    """Read a file reference; return the array and the key label naming the file."""
    if isinstance(value, str):
        name, npz_key, fmt = value, None, None
    else:
        _check_keys(where, value, _FILE_REF_KEYS, key)
        name, npz_key, fmt = value["file"], value.get("key"), value.get("format")
        for sub, item in (("file", name), ("key", npz_key), ("format", fmt)):
            if item is not None and not isinstance(item, str):
                raise where.error(f"{key}.{sub}", f"must be a string, got {_describe(item)}")
    if not name:
        raise where.error(key, "the file name is empty")
    label = f"{key} ('{name}')"
    path = Path(name).expanduser()
    if not path.is_absolute():
        path = where.base / path
    if not path.exists():
        raise where.error(key, f"file '{name}' not found (looked for {os.path.abspath(path)})",
                          FileFormatError)
    try:
        return read_array(path, npz_key, fmt), label
    except InvalidInputError as exc:
        raise where.rewrap(label, exc) from None


def _numeric_leaves(value, integer: bool = False) -> bool:
    if isinstance(value, list):
        return all(_numeric_leaves(item, integer) for item in value)
    kinds = int if integer else (int, float)
    return isinstance(value, kinds) and not isinstance(value, bool)


def _inline(where: _Where, value, key: str) -> np.ndarray:
    if not isinstance(value, list):
        raise where.error(
            key, f"must be an array of numbers or a file reference, got {_describe(value)}"
        )
    if not _numeric_leaves(value):
        raise where.error(key, "must hold numbers only (no strings, booleans or tables)")
    try:
        return np.array(value, dtype=float)
    except ValueError:
        raise where.error(key, "rows have different lengths") from None


def _array(where: _Where, value, key: str, ndim: int, integer: bool = False) -> np.ndarray:
    """An inline array or a file reference as a finite array with ``ndim`` dimensions.

    A vector (``ndim == 1``) read from a file may be stored as one row or one column. With
    ``integer`` the values must be whole numbers and an ``int`` array is returned.
    """
    label = key
    if _is_file_ref(value):
        array, label = _load_ref(where, value, key)
        if ndim == 1 and array.ndim == 2 and 1 in array.shape:
            array = array.reshape(-1)
        elif ndim == 2 and array.ndim == 1 and array.size == 1:
            array = array.reshape(1, 1)
    else:
        if integer and _numeric_leaves(value) and not _numeric_leaves(value, integer=True):
            raise where.error(key, "must hold integers (indices count from 0)")
        array = _inline(where, value, key)
    if array.ndim != ndim:
        shape = "a list of numbers" if ndim == 1 else "an array of rows"
        raise where.error(label, f"must be {shape} ({ndim}-D), got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        bad = np.argwhere(~np.isfinite(array))[0]
        position = ", ".join(str(i) for i in bad)
        raise where.error(
            label, f"contains NaN or inf (first at index [{position}], counting from 0)"
        )
    if integer:
        if np.any(array != np.round(array)):
            raise where.error(label, "must hold integers (indices count from 0)")
        return array.astype(int)
    return array


# --------------------------------------------------------------------------------------------
# Sections


def _matrix(where: _Where, model: dict) -> tuple[str, np.ndarray, str]:
    given = [name for name in ("flexibility", "stiffness") if name in model]
    if len(given) != 1:
        found = "both" if given else "neither"
        raise where.error("[model]", f"give exactly one of flexibility and stiffness ({found} given)")
    which = given[0]
    key = f"[model].{which}"
    value = model[which]
    matrix = _array(where, value, key, 2)
    label = key
    if isinstance(value, str):
        label = f"{key} ('{value}')"
    elif isinstance(value, dict):
        label = f"{key} ('{value['file']}')"
    if matrix.shape[0] != matrix.shape[1] or matrix.size == 0:
        raise where.error(label, f"must be a non-empty square matrix, got shape {matrix.shape}")
    return which, matrix, label


def _dofs_per_node(where: _Where, value, n_freedoms: int):
    key = "[model].dofs_per_node"
    if isinstance(value, int) and not isinstance(value, bool):
        if value not in (1, 2, 3):
            raise where.error(key, f"must be 1, 2 or 3, got {value}")
        if n_freedoms % value:
            raise where.error(
                key, f"the matrix has {n_freedoms} freedoms, not a multiple of {value}"
            )
        return value, n_freedoms // value
    if not (isinstance(value, list) and value
            and all(isinstance(v, int) and not isinstance(v, bool) for v in value)):
        raise where.error(key, f"must be an integer or a list of integers, got {_describe(value)}")
    if any(v not in (1, 2, 3) for v in value):
        raise where.error(key, "every entry must be 1, 2 or 3")
    if sum(value) != n_freedoms:
        raise where.error(
            key, f"sums to {sum(value)} freedoms, the matrix has {n_freedoms}"
        )
    return list(value), len(value)


def _build_model(where: _Where, doc: dict) -> ReducedModel:
    if "model" not in doc:
        raise where.error("[model]", "missing: give the flexibility or stiffness matrix")
    model = _table(where, doc["model"], "[model]")
    _check_keys(where, model, _MODEL_KEYS, "[model]")
    which, matrix, label = _matrix(where, model)
    dofs, n_nodes = _dofs_per_node(where, model.get("dofs_per_node", 1), matrix.shape[0])
    coordinates = None
    if "coordinates" in model:
        coordinates = _array(where, model["coordinates"], "[model].coordinates", 2)
        if coordinates.shape[0] != n_nodes:
            raise where.error(
                "[model].coordinates",
                f"has {_count(coordinates.shape[0], 'row')}, the model has "
                f"{_count(n_nodes, 'node')}",
            )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            built = ReducedModel(**{which: matrix}, dofs_per_node=dofs, coordinates=coordinates)
        except InvalidInputError as exc:
            raise where.rewrap(label, exc) from None
    for warning in caught:
        warnings.warn(_one_line(f"{where.path}: {label}: {warning.message}"), warning.category,
                      stacklevel=3)
    return built


def _loads(where: _Where, doc: dict, model: ReducedModel) -> np.ndarray:
    if "loads" not in doc:
        raise where.error("[loads]", "missing: give values = [...] or entries = [...]")
    loads = _table(where, doc["loads"], "[loads]")
    _check_keys(where, loads, _LOADS_KEYS, "[loads]")
    given = [name for name in _LOADS_KEYS if name in loads]
    if len(given) != 1:
        found = "both" if given else "neither"
        raise where.error("[loads]", f"give exactly one of values and entries ({found} given)")
    n = model.n_freedoms
    if "values" in loads:
        values = _array(where, loads["values"], "[loads].values", 1)
        if values.size != n:
            raise where.error(
                "[loads].values",
                f"has {_count(values.size, 'entry', 'entries')}, the model has "
                f"{_count(n, 'freedom')}",
            )
        return values
    entries = loads["entries"]
    if not isinstance(entries, list):
        raise where.error("[loads].entries", f"must be an array of tables, got {_describe(entries)}")
    P = np.zeros(n)
    seen: dict[int, int] = {}
    for number, entry in enumerate(entries, start=1):
        key = f"[loads].entries #{number}"
        entry = _table(where, entry, key)
        _check_keys(where, entry, ("value", "freedom", "node", "component"), key)
        value = entry.get("value")
        if not (isinstance(value, (int, float)) and not isinstance(value, bool)
                and math.isfinite(value)):
            raise where.error(key, f"value must be a finite number, got {_describe(value)}")
        for name in ("freedom", "node", "component"):
            item = entry.get(name)
            if item is not None and (not isinstance(item, int) or isinstance(item, bool)):
                raise where.error(key, f"{name} must be an integer, got {_describe(item)}")
        if "freedom" in entry:
            if "node" in entry or "component" in entry:
                raise where.error(key, "give freedom, or node with component, not both")
            freedom = entry["freedom"]
            if not 0 <= freedom < n:
                raise where.error(
                    key, f"freedom {freedom} is outside 0..{n - 1} (the model has "
                    f"{_count(n, 'freedom')})"
                )
        elif "node" in entry:
            node, component = entry["node"], entry.get("component", 0)
            if not 0 <= node < model.n_nodes:
                raise where.error(
                    key, f"node {node} is outside 0..{model.n_nodes - 1} (the model has "
                    f"{_count(model.n_nodes, 'node')})"
                )
            count = int(model.dofs_per_node[node])
            if not 0 <= component < count:
                raise where.error(
                    key, f"component {component} is outside 0..{count - 1} (node {node} has "
                    f"{_count(count, 'freedom')})"
                )
            freedom = int(model.offsets[node]) + component
        else:
            raise where.error(key, "give freedom, or node (with component), for the value")
        if freedom in seen:
            raise where.error(key, f"freedom {freedom} is already loaded by entry #{seen[freedom]}")
        seen[freedom] = number
        P[freedom] = float(value)
    return P


def _nodes(where: _Where, value, key: str, model: ReducedModel) -> np.ndarray:
    nodes = _array(where, value, key, 1, integer=True)
    if nodes.size == 0:
        raise where.error(key, "is empty")
    bad = nodes[(nodes < 0) | (nodes >= model.n_nodes)]
    if bad.size:
        raise where.error(
            key, f"node {bad[0]} is outside 0..{model.n_nodes - 1} (the model has "
            f"{_count(model.n_nodes, 'node')})"
        )
    return nodes


def _directions(where: _Where, table: dict, key: str, count: int):
    if "direction" in table and "directions" in table:
        raise where.error(key, "give direction or directions, not both")
    if "directions" in table:
        dirs = _array(where, table["directions"], f"{key}.directions", 2)
        if dirs.shape[0] != count:
            raise where.error(
                f"{key}.directions",
                f"has {_count(dirs.shape[0], 'row')}, expected {count} (one per contact)",
            )
        return dirs
    if "direction" in table:
        return _array(where, table["direction"], f"{key}.direction", 1)
    return np.array([1.0])


def _require(where: _Where, table: dict, names, key: str, kind: str) -> None:
    for name in names:
        if name not in table:
            raise where.error(key, f"a {kind} obstacle needs '{name}'")


def _gaps(where: _Where, value, key: str, count: int, what: str) -> np.ndarray:
    gaps = _array(where, value, key, 1)
    if gaps.size != count:
        raise where.error(key, f"has {_count(gaps.size, 'value')} for {_count(count, what)}")
    return gaps


def _obstacle(where: _Where, table, number: int, model: ReducedModel):
    key = f"[[obstacle]] #{number}"
    table = _table(where, table, key)
    kind = table.get("type")
    if kind is None:
        raise where.error(key, f"missing 'type' (expected {', '.join(OBSTACLE_TYPES[:-1])} or "
                               f"{OBSTACLE_TYPES[-1]})")
    if kind == "profile":
        raise where.error(
            key, "type 'profile' cannot be given in a file (its profile is a Python function); "
            "tabulate the gaps and use type = \"gaps\", or build a ProfileObstacle in Python"
        )
    if kind not in OBSTACLE_TYPES:
        raise where.error(
            key, f"unknown type {kind!r} (expected {', '.join(OBSTACLE_TYPES[:-1])} or "
            f"{OBSTACLE_TYPES[-1]})"
        )
    _check_keys(where, table, _OBSTACLE_KEYS[kind], key)
    if kind == "gaps":
        _require(where, table, ("nodes", "gaps"), key, kind)
        nodes = _nodes(where, table["nodes"], f"{key}.nodes", model)
        gaps = _gaps(where, table["gaps"], f"{key}.gaps", nodes.size, "node")
        dirs = _directions(where, table, key, nodes.size)
        obstacle = GapObstacle(nodes.tolist(), gaps, dirs)
    elif kind == "plane":
        _require(where, table, ("point", "normal"), key, kind)
        if model.coordinates is None:
            raise where.error(key, "a plane obstacle needs [model].coordinates")
        point = _array(where, table["point"], f"{key}.point", 1)
        normal = _array(where, table["normal"], f"{key}.normal", 1)
        nodes = None
        if "nodes" in table:
            nodes = _nodes(where, table["nodes"], f"{key}.nodes", model).tolist()
        obstacle = PlaneObstacle(point, normal, nodes)
    else:
        _require(where, table, ("pairs", "gaps"), key, kind)
        pairs = _array(where, table["pairs"], f"{key}.pairs", 2, integer=True)
        if pairs.shape[1] != 2 or pairs.shape[0] == 0:
            raise where.error(f"{key}.pairs", f"must be a list of [a, b] pairs, got shape "
                                              f"{pairs.shape}")
        _nodes(where, pairs.reshape(-1).tolist(), f"{key}.pairs", model)
        gaps = _gaps(where, table["gaps"], f"{key}.gaps", pairs.shape[0], "pair")
        dirs = _directions(where, table, key, pairs.shape[0])
        obstacle = NodePairs(pairs.tolist(), gaps, dirs)
    try:
        obstacle.rows(model)  # the library's own checks, attributed to this obstacle
    except InvalidInputError as exc:
        raise where.rewrap(f"{key} ({kind})", exc) from None
    return obstacle


def _obstacles(where: _Where, doc: dict, model: ReducedModel) -> list:
    if "obstacle" not in doc:
        raise where.error("[[obstacle]]", "missing: give at least one [[obstacle]] table")
    tables = doc["obstacle"]
    if isinstance(tables, dict):
        raise where.error("[[obstacle]]", "write [[obstacle]] (an array of tables, double "
                                          "brackets), not [obstacle]")
    if not isinstance(tables, list) or not tables:
        raise where.error("[[obstacle]]", "give at least one [[obstacle]] table")
    return [_obstacle(where, table, number, model) for number, table in enumerate(tables, 1)]


def _solver_parameters(method) -> tuple[dict, bool]:
    """Keyword options of a solver function and whether it passes extra ones on."""
    named, extra = {}, False
    for index, parameter in enumerate(inspect.signature(method).parameters.values()):
        if index == 0:
            continue  # the problem
        if parameter.kind is inspect.Parameter.VAR_KEYWORD:
            extra = True
        elif parameter.kind in (inspect.Parameter.KEYWORD_ONLY,
                                inspect.Parameter.POSITIONAL_OR_KEYWORD):
            named[parameter.name] = parameter.default
    return named, extra


def _option(where: _Where, name: str, value, default, key: str):
    if isinstance(value, dict):
        raise where.error(key, "must be a value, not a table")
    kind = None
    if isinstance(default, bool):
        ok, kind = isinstance(value, bool), "true or false"
    elif isinstance(default, int):
        ok, kind = isinstance(value, int) and not isinstance(value, bool), "an integer"
    elif isinstance(default, float):
        ok, kind = isinstance(value, (int, float)) and not isinstance(value, bool), "a number"
        value = float(value) if ok else value
    elif isinstance(default, str):
        ok, kind = isinstance(value, str), "a string"
    else:
        ok = True
    if not ok:
        raise where.error(key, f"must be {kind} (default {default!r}), got {_describe(value)}")
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if not math.isfinite(value):
            raise where.error(key, f"must be finite, got {value}")
        if (name in ("tol", "max_iter") or name.endswith("_tol")) and value <= 0:
            raise where.error(key, f"must be positive, got {value}")
    return value


def _solver(where: _Where, doc: dict) -> tuple[str, dict, float]:
    table = _table(where, doc.get("solver", {}), "[solver]")
    name = table.get("name", "active-set")
    if name not in SOLVERS:
        expected = ", ".join(SOLVERS)
        raise where.error("[solver].name", f"unknown solver {name!r} (expected one of {expected})")
    named, extra = _solver_parameters(SOLVERS[name])
    allowed = {"name", "certificate_tol", *named}
    if extra:
        allowed.add("backend_options")
    for key in table:
        if key not in allowed:
            hint = _close_match(key, allowed)
            if extra:
                hint += "; backend settings go in [solver.backend_options]"
            raise where.error(
                f"[solver].{key}",
                f"not an option of solver '{name}' (allowed: {', '.join(sorted(allowed))}){hint}",
            )
    certificate_tol = _option(where, "certificate_tol", table.get("certificate_tol",
                                                                  CERTIFICATE_TOL),
                              CERTIFICATE_TOL, "[solver].certificate_tol")
    options = {key: _option(where, key, table[key], named[key], f"[solver].{key}")
               for key in table if key in named}
    if "backend_options" in table:
        backend = _table(where, table["backend_options"], "[solver.backend_options]")
        for key, value in backend.items():
            if isinstance(value, (dict, list)) or (isinstance(value, float)
                                                   and not math.isfinite(value)):
                raise where.error(f"[solver.backend_options].{key}",
                                  f"must be a finite number, a string or a boolean, got "
                                  f"{_describe(value)}")
            if key in named or key in options:
                raise where.error(f"[solver.backend_options].{key}",
                                  f"is an option of solver '{name}': set it in [solver]")
            options[key] = value
    return name, options, certificate_tol


# --------------------------------------------------------------------------------------------
# Public API


@dataclass
class ProblemSpec:
    """A contact problem read from a file, with the solver it asks for.

    Attributes
    ----------
    problem : ContactProblem
        The assembled problem (loads in N, lengths in m, as in the file).
    solver : str
        A name from :data:`contactqp.SOLVERS`.
    options : dict
        Keyword options for the solver, ready for ``solve(problem, solver, **options)``.
    name : str
        The problem's name (the file's stem when the file gives none).
    path : pathlib.Path or None
        The TOML file, as given to :func:`load_problem_file`.
    """

    problem: ContactProblem
    solver: str = "active-set"
    options: dict = field(default_factory=dict)
    name: str = ""
    path: Path | None = None

    def solve(self) -> ContactResult:
        """Solve :attr:`problem` with :attr:`solver` and :attr:`options`.

        Returns
        -------
        ContactResult
        """
        return solve(self.problem, solver=self.solver, **self.options)


def load_problem_file(path) -> ProblemSpec:
    """Read a TOML problem file (schema in the module docstring) and assemble its problem.

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
        or solver. Errors of the model or problem (e.g. :class:`NotPositiveDefiniteError`) keep
        their class. Every message is one line naming the file and the key.
    """
    path = Path(path)
    where = _Where(path)
    try:
        with open(path, "rb") as handle:
            doc = tomllib.load(handle)
    except FileNotFoundError:
        raise where.error("", "problem file not found", FileFormatError) from None
    except IsADirectoryError:
        raise where.error("", "is a directory, not a problem file", FileFormatError) from None
    except tomllib.TOMLDecodeError as exc:
        raise where.error("", f"malformed TOML: {exc}", FileFormatError) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise where.error("", f"cannot read the problem file: {exc}", FileFormatError) from None
    _check_keys(where, doc, _TOP_KEYS, "top level")
    name = doc.get("name", path.stem)
    if not isinstance(name, str):
        raise where.error("name", f"must be a string, got {_describe(name)}")
    solver, options, certificate_tol = _solver(where, doc)
    model = _build_model(where, doc)
    loads = _loads(where, doc, model)
    obstacles = _obstacles(where, doc, model)
    try:
        problem = ContactProblem(model, loads, obstacles, certificate_tol=certificate_tol)
    except InvalidInputError as exc:
        raise where.rewrap("problem", exc) from None
    return ProblemSpec(problem=problem, solver=solver, options=options, name=name, path=path)


def _float_text(value) -> str:
    return repr(float(value))  # the shortest text that reads back to the same float


def _json_ready(value):
    if isinstance(value, dict):
        return {str(k): _json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return _json_ready(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if value is None or isinstance(value, str):
        return value
    return str(value)


def write_results(spec: ProblemSpec, result: ContactResult, out_dir) -> list[Path]:
    """Write a solved problem's results to a directory.

    Files written (see :data:`RESULT_FILES`):

    * ``displacements.csv``: columns ``node, freedom, u``, one row per freedom; ``freedom`` is
      the global freedom index, ``u`` the displacement (m).
    * ``contacts.csv``: columns ``row, node, label, gap0, gap, force, status``, one row per
      constraint: initial gap and final gap (m), contact force (N), ``closed`` or ``open``.
    * ``result.npz``: arrays ``x`` (m), ``forces`` (N), ``nodal_forces`` (N), ``gaps`` (m) and
      ``closed`` (bool), as in :class:`~contactqp.ContactResult`.
    * ``summary.json``: ``name``, ``problem`` (absolute path of the problem file), ``solver``,
      ``options`` and ``result`` (:meth:`ContactResult.summary`); NaN and inf are written as
      ``null``.

    Floats are written in their shortest exact form (:func:`repr`), so they read back exactly.

    Parameters
    ----------
    spec : ProblemSpec
    result : ContactResult
        The answer to ``spec.problem``.
    out_dir : str or os.PathLike
        Created, with its parents, when missing; files in it are overwritten.

    Returns
    -------
    list of pathlib.Path
        The files written, in the order above.

    Raises
    ------
    InvalidInputError
        ``result`` does not have the shapes of ``spec.problem``.
    FileFormatError
        The directory or a file cannot be written.
    """
    problem = spec.problem
    model, constraints = problem.model, problem.constraints
    if np.shape(result.x) != (model.n_freedoms,) or np.shape(result.forces) != (
            constraints.n_constraints,):
        raise InvalidInputError(
            f"result has {np.size(result.x)} displacements and {np.size(result.forces)} forces; "
            f"the problem has {model.n_freedoms} freedoms and {constraints.n_constraints} "
            "constraints"
        )
    out = Path(out_dir)
    paths = [out / name for name in RESULT_FILES]
    try:
        out.mkdir(parents=True, exist_ok=True)
        with open(paths[0], "w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle, lineterminator="\n")
            writer.writerow(["node", "freedom", "u"])
            for node in range(model.n_nodes):
                for freedom in model.freedoms(node):
                    writer.writerow([node, int(freedom), _float_text(result.x[freedom])])
        with open(paths[1], "w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle, lineterminator="\n")
            writer.writerow(["row", "node", "label", "gap0", "gap", "force", "status"])
            labels = result.status_labels
            for row in range(constraints.n_constraints):
                writer.writerow([row, int(constraints.nodes[row]), constraints.labels[row],
                                 _float_text(constraints.gaps[row]),
                                 _float_text(result.gaps[row]),
                                 _float_text(result.forces[row]), labels[row]])
        with open(paths[2], "wb") as handle:
            np.savez(handle, x=np.asarray(result.x, dtype=float),
                     forces=np.asarray(result.forces, dtype=float),
                     nodal_forces=np.asarray(result.nodal_forces, dtype=float),
                     gaps=np.asarray(result.gaps, dtype=float),
                     closed=np.asarray(result.closed, dtype=bool))
        summary = {
            "name": spec.name,
            "problem": os.path.abspath(spec.path) if spec.path is not None else None,
            "solver": spec.solver,
            "options": spec.options,
            "result": result.summary(),
        }
        with open(paths[3], "w", encoding="utf-8") as handle:
            json.dump(_json_ready(summary), handle, indent=2, allow_nan=False)
            handle.write("\n")
    except OSError as exc:
        raise FileFormatError(_one_line(f"cannot write results to '{out}': {exc}")) from None
    return paths

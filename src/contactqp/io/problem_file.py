"""Problem files: a contact problem described in TOML, and its results written out.

This is what ``contactqp solve PROBLEM.toml`` reads (:func:`load_problem_file`) and writes
(:func:`write_results`): a frictionless problem, a problem with friction, or a problem with
friction along a load history.

The schema
----------
A problem file has seven top-level entries, ``name``, ``[model]``, ``[loads]``, ``[[obstacle]]``,
``[friction]``, ``[loading]`` and ``[solver]``; nothing else is accepted. Every table rejects keys
it does not know, so that a typo (``flexibilty``, ``gap``, ``max_iters``) is an error and never a
silently ignored setting. Units are SI (metres, newtons): the file stores numbers, the physics
decides their units, and the results come back in the same units. Node and freedom indices count
from 0; freedoms are ordered node by node. Numbered entries in messages (``[[obstacle]] #2``,
``[loads].entries #3``) count from 1, in the order they appear in the file.

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

**[loads]** (required, unless ``[loading].points`` gives the loads): the external forces ``P``
(N), by exactly one of

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

The *contacts* are the rows of all obstacles: the ``[[obstacle]]`` tables in file order, each
one's nodes (or pairs) in order; they are numbered from 0 in results.

**[friction]** (optional): Coulomb (Mohr-Coulomb) friction at every contact, solved by
:class:`~contactqp.FrictionalProblem` from rest. Without this table the problem is frictionless.
Friction needs contact nodes with 2 freedoms (2-D) or 3 (3-D), the same number at every contact.

=============  ===========================================================================
``mu``         Friction coefficient, >= 0 (required): a number, or one per contact (array or
               file, in contact order).
``cohesion``   Cohesion ``c`` (N), >= 0, a number or one per contact (default 0): the friction
               set is ``|r_T| <= mu r_N + c``; a contact with ``c > 0`` needs ``mu > 0`` and
               no initial gap (a bonded interface, see :class:`~contactqp.FrictionalProblem`).
``facets``     Integer >= 3: each friction disc becomes the inscribed regular polygon of that
               many sides, the method's linear cone (in 2-D the cone is linear already).
``solver``     ``"coulomb"`` (default: exact cone, semismooth Newton), ``"tresca"`` (exact
               cone, Tresca fixed point) or ``"polygonal"`` (the default, and the only
               choice, when ``facets`` is given).
``tol``        Solver tolerance (default 1e-10): natural-map error, or the fixed-point change
               of ``"polygonal"``.
other keys     Keyword options of the chosen route, checked against its signature:
               ``max_iter`` for every route, ``backend`` for ``"polygonal"``.
[friction.backend_options]
               ``"polygonal"`` only: settings for its qpsolvers backend, as in ``[solver]``.
=============  ===========================================================================

Local frames: a contact's normal is its obstacle's direction (towards the obstacle, or from the
first node of a pair towards the second); the tangent is the normal turned by +90 degrees in 2-D
(``(n_x, n_y) -> (-n_y, n_x)``), the two tangents of :func:`~contactqp.core.contact.tangent_basis`
in 3-D. Tangential forces (on the body, or on the first node of a pair) and slips are given
along these tangents. With ``[friction]``, ``[solver]`` holds ``certificate_tol`` only: a
``[solver].name`` (a frictionless solver) is an error, the route is ``[friction].solver``.

**[loading]** (optional, needs ``[friction]``): a load history, solved by
:func:`~contactqp.core.history.solve_history` from rest, step by step, the friction state carried
over. Its turning points are given by exactly one of

=============  ===========================================================================
``factors``    Multiples of ``[loads]``, e.g. ``[0, 1, -1, 1]`` (array or file, >= 1 number).
``points``     Full load vectors (N), replacing ``[loads]`` (give one or the other): an array
               of rows of ``n`` numbers, a file holding such a matrix, or an array whose
               entries are vectors or file references (one turning point each).
``steps``      Equal increments from each turning point to the next (integer >= 1, default 1).
=============  ===========================================================================

Step 0 is the first turning point, then ``steps`` increments lead to each next one:
``1 + steps (j - 1)`` steps for ``j`` turning points, numbered from 0 in the results; at most
100000 (:data:`contactqp.core.history.MAX_STEPS`: each step is a full solve whose result is kept).

**[solver]** (optional): how to solve a frictionless problem (with ``[friction]``: only
``certificate_tol``).

=====================  ======================================================================
``name``               A name from :data:`contactqp.SOLVERS`: ``"active-set"`` (default) or
                       ``"qp"``.
``certificate_tol``    Largest relative residual the certificate accepts (default 1e-7).
other keys             Keyword options of the chosen solver, checked against its signature:
                       ``tol`` and ``max_iter`` for ``"active-set"``, ``backend`` for ``"qp"``.
[solver.backend_options]
                       Only for solvers that pass extra settings on (``"qp"``): a table given
                       verbatim to the qpsolvers backend, under the backend's own names (e.g.
                       ``eps_abs`` for piqp), checked when the file is read (below).
=====================  ======================================================================

Numeric solver options must be finite; ``tol``, ``max_iter`` and any ``*_tol`` must be positive,
backend settings named ``tol_*`` or ``eps_*`` >= 0. A backend setting the backend refuses (an
unknown name, a value of the wrong type or range) is an error naming its key when the file is
read: each is tried on a QP of one variable.

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

The same plate with friction (no ``[solver].name`` then), its loads cycled twice::

    [friction]
    mu = [0.3, 0.3, 0.2, 0.5]                # one per contact: nodes 0, 1 (plane), 2, pair 0-2
    cohesion = 0.0                           # N
    solver = "coulomb"                       # or facets = 8 (polygonal)
    tol = 1e-10

    [loading]
    factors = [0.0, 1.0, -1.0, 1.0, -1.0]    # times [loads]; or points = [[...], ...]
    steps = 10                               # 41 steps: 0, 0.1, ..., 1, 0.8, ..., -1, ...

Results
-------
:func:`write_results` writes, into one directory, floats in their shortest exact form
(:func:`repr`, so they read back exactly):

* ``displacements.csv``: ``node, freedom, u``, one row per freedom: the global freedom index
  and its displacement (m).
* ``contacts.csv``, one row per contact. Frictionless: ``row, node, label, gap0, gap, force,
  status``: initial and final gap (m), contact force (N), ``closed`` or ``open``. With friction:
  ``row, node, label, gap0, gap, normal_force, tangential_force, slip, tangential_displacement,
  dissipated, status`` (in 3-D each tangential column twice, suffixed ``_1`` and ``_2``): gaps
  (m), compressive normal force (N), tangential force on the body along the tangent(s) (N),
  slip of the step along the tangent(s) (m), total tangential displacement (m), energy
  dissipated by friction in the step (J), ``open``, ``stick`` or ``slip``.
* ``result.npz``: frictionless, ``x`` (m), ``forces`` (N), ``nodal_forces`` (N), ``gaps`` (m),
  ``closed`` (bool), as in :class:`~contactqp.ContactResult`. With friction, the fields of
  :class:`~contactqp.core.result.FrictionalResult`: ``x`` (m, shape (n,)), ``forces`` (N, (k, d),
  normal first), ``nodal_forces`` (N, (n,)), ``gaps`` (m, (k,)), ``slip`` and
  ``tangential_displacements`` (m, (k, d - 1)), ``contact_status`` (int, (k,): 0 open,
  1 stick, 2 slip), ``dissipation`` (J, (k,)), with the frames ``normals`` ((k, d)) and
  ``tangents`` ((k, d - 1, d)).
* ``summary.json``: ``name``, ``problem`` (absolute path of the problem file), ``solver``,
  ``options``, ``friction`` (with friction: ``mu`` and ``cohesion`` per contact, ``facets``)
  and ``result`` (:meth:`ProblemSpec.summary`); NaN and inf are written as ``null``.

For a load history, ``displacements.csv`` and ``contacts.csv`` start with a ``step`` column
and hold every step; the arrays of ``result.npz`` gain a leading step axis (K, ...) and it adds
``loads`` (N, (K, n)), ``success`` (bool, (K,)) and, for ``factors``, ``factors`` ((K,));
``steps.csv`` (written last) has one row per step: ``step, factor, open, stick, slip,
dissipated, cumulative_dissipated, iterations, certificate_worst, success`` (``factor`` empty
for ``points``; energies in J).

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

import difflib
import inspect
import json
import math
import os
import tomllib
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.contact import GapObstacle, NodePairs, PlaneObstacle, assemble_constraints
from ..errors import FileFormatError, InvalidInputError
from ..core.friction import STATUS_LABELS, FrictionLaw
from ..core.history import HistoryResult, linear_path, solve_history
from ..core.model import ReducedModel
from ..core.problem import ContactProblem, FrictionalProblem, friction_route
from ..core.result import CERTIFICATE_TOL, ContactResult, FrictionalResult
from ..methods import SOLVERS, solve
from .arrays import read_csv_array, read_numpy_array
from .export import write_rows

__all__ = [
    "ProblemSpec",
    "load_problem_file",
    "write_results",
    "read_array",
    "ARRAY_FORMATS",
    "OBSTACLE_TYPES",
    "RESULT_FILES",
    "HISTORY_FILES",
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

#: The files :func:`write_results` writes for a load history, in order.
HISTORY_FILES = RESULT_FILES + ("steps.csv",)

_TOP_KEYS = ("name", "model", "loads", "obstacle", "friction", "loading", "solver")
_FRICTION_LAW_KEYS = ("mu", "cohesion", "facets")
_LOADING_KEYS = ("factors", "points", "steps")
_MODEL_KEYS = ("flexibility", "stiffness", "dofs_per_node", "coordinates")
_LOADS_KEYS = ("values", "entries")
_FILE_REF_KEYS = ("file", "key", "format")
_OBSTACLE_KEYS = {
    "gaps": ("type", "nodes", "gaps", "direction", "directions"),
    "plane": ("type", "point", "normal", "nodes"),
    "pairs": ("type", "pairs", "gaps", "direction", "directions"),
}


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
            array = read_csv_array(path)
        elif fmt in ("npz", "npy"):
            array = read_numpy_array(path, key)
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
        # the readers start their messages with the path, which the label already names
        message = str(exc).removeprefix(f"{path}: ")
        raise where.rewrap(label, type(exc)(message)) from None


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
    positive = name in ("tol", "max_iter") or name.endswith("_tol")
    nonnegative = name.startswith(("tol_", "eps_"))  # backends' tolerances
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if (positive or nonnegative) and not number:
        raise where.error(key, f"must be a number, got {_describe(value)}")
    if number:
        if not math.isfinite(value):
            raise where.error(key, f"must be finite, got {value}")
        if positive and value <= 0:
            raise where.error(key, f"must be positive, got {value}")
        if nonnegative and value < 0:
            raise where.error(key, f"must be >= 0, got {value}")
    return value


def _route_options(where: _Where, table: dict, section: str, route: str, named: dict,
                   extra: bool, reserved) -> dict:
    """The solver options in ``table`` (its keys beyond ``reserved``), checked against ``named``
    (name: default); ``[section.backend_options]`` when the solver passes extra ones on."""
    allowed = {*reserved, *named}
    if extra:
        allowed.add("backend_options")
    for key in table:
        if key not in allowed:
            hint = _close_match(key, allowed)
            if extra:
                hint += f"; backend settings go in [{section[1:-1]}.backend_options]"
            raise where.error(
                f"{section}.{key}",
                f"not an option of {route} (allowed: {', '.join(sorted(allowed))}){hint}",
            )
    options = {key: _option(where, key, table[key], named[key], f"{section}.{key}")
               for key in table if key in named}
    if "backend_options" in table:
        sub = f"[{section[1:-1]}.backend_options]"
        backend = _table(where, table["backend_options"], sub)
        for key, value in backend.items():
            if isinstance(value, (dict, list)) or (isinstance(value, float)
                                                   and not math.isfinite(value)):
                raise where.error(f"{sub}.{key}",
                                  f"must be a finite number, a string or a boolean, got "
                                  f"{_describe(value)}")
            if key in named or key in options:
                raise where.error(f"{sub}.{key}", f"is an option of {route}: set it in {section}")
            _option(where, key, value, None, f"{sub}.{key}")
            options[key] = value
    if "backend" in named:
        _check_backend(where, section, options.get("backend", named["backend"]),
                       {key: options[key] for key in table.get("backend_options", {})})
    return options


def _check_backend(where: _Where, section: str, backend, settings: dict) -> None:
    """Raise, naming the key, when the qpsolvers ``backend`` is not installed or refuses one of
    ``settings`` (see :func:`~contactqp.methods.qp.refused_setting`)."""
    from ..methods.qp import installed_backend, refused_setting

    try:
        installed_backend(backend)
    except InvalidInputError as exc:
        raise where.error(f"{section}.backend", str(exc)) from None
    for key, value in settings.items():
        reason = refused_setting(backend, key, value)
        if reason:
            raise where.error(f"[{section[1:-1]}.backend_options].{key}",
                              f"backend '{backend}' refuses {key} = {value!r} ({reason})")


def _solver(where: _Where, doc: dict, frictional: bool) -> tuple[str, dict, float]:
    table = _table(where, doc.get("solver", {}), "[solver]")
    certificate_tol = _option(where, "certificate_tol", table.get("certificate_tol",
                                                                  CERTIFICATE_TOL),
                              CERTIFICATE_TOL, "[solver].certificate_tol")
    if frictional:
        if "name" in table:
            raise where.error(
                "[solver].name",
                f"solver {table['name']!r} is frictionless but [friction] is given: remove "
                "[solver].name and choose the route with [friction].solver (coulomb, tresca "
                "or polygonal)")
        for key in table:
            if key != "certificate_tol":
                raise where.error(f"[solver].{key}", "with [friction], [solver] holds only "
                                  "certificate_tol; solver options go in [friction]")
        return "", {}, certificate_tol
    name = table.get("name", "active-set")
    if not isinstance(name, str):
        raise where.error("[solver].name", f"must be a string, got {_describe(name)}")
    if name not in SOLVERS:
        expected = ", ".join(SOLVERS)
        raise where.error("[solver].name", f"unknown solver {name!r} (expected one of {expected})")
    named, extra = _solver_parameters(SOLVERS[name])
    options = _route_options(where, table, "[solver]", f"solver '{name}'", named, extra,
                             ("name", "certificate_tol"))
    return name, options, certificate_tol


def _per_contact(where: _Where, value, key: str):
    """A number, or an array or file of numbers (one per contact)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return _array(where, value, key, 1)


def _one_freedom_contacts(where: _Where, model: ReducedModel, obstacles) -> None:
    """Raise when a contact node has one freedom (no tangent, so no friction)."""
    for number, obstacle in enumerate(obstacles, 1):
        for row in obstacle.rows(model):
            node = row[0]
            if model.dofs_per_node[node] == 1:
                raise where.error(
                    "[friction]",
                    f"friction needs contact nodes with 2 or 3 freedoms (a tangent), but node "
                    f"{node} of [[obstacle]] #{number} has 1 ([model].dofs_per_node)")


def _friction(where: _Where, table, model: ReducedModel, loads: np.ndarray, obstacles,
              certificate_tol: float) -> tuple[FrictionalProblem, str, dict]:
    """The frictional problem of ``[friction]``, its route and the route's options."""
    table = _table(where, table, "[friction]")
    if "mu" not in table:
        raise where.error("[friction]", "missing 'mu' (the friction coefficient, >= 0)")
    _one_freedom_contacts(where, model, obstacles)
    n_contacts = assemble_constraints(model, obstacles).n_constraints
    given = {}
    for name in _FRICTION_LAW_KEYS:  # each key checked by the law, in turn, to name it
        if name in table:
            key = f"[friction].{name}"
            value = table[name]
            given[name] = value if name == "facets" else _per_contact(where, value, key)
            try:
                law = FrictionLaw(**given, n_contacts=n_contacts)
            except InvalidInputError as exc:
                raise where.rewrap(key, exc) from None
    route = table.get("solver")
    if route is not None and not isinstance(route, str):
        raise where.error("[friction].solver", f"must be a string, got {_describe(route)}")
    try:
        route, method = friction_route(law, route)
    except InvalidInputError as exc:
        raise where.rewrap("[friction].solver", exc) from None
    named, extra = _solver_parameters(method)
    for fixed in ("r0", "facets"):  # set by FrictionalProblem.solve
        named.pop(fixed, None)
    named["tol"] = inspect.signature(FrictionalProblem.solve).parameters["tol"].default
    options = _route_options(where, table, "[friction]", f"friction solver '{route}'", named,
                             extra, ("solver", *_FRICTION_LAW_KEYS))
    try:
        problem = FrictionalProblem(model, loads, obstacles, law.mu, law.cohesion, law.facets,
                                    certificate_tol=certificate_tol)
    except InvalidInputError as exc:
        raise where.rewrap("[friction]", exc) from None
    return problem, route, options


def _points(where: _Where, value, n: int) -> np.ndarray:
    """``[loading].points``: a matrix, a file holding one, or a list of vectors and files."""
    key = "[loading].points"
    if isinstance(value, list) and any(_is_file_ref(item) for item in value):
        rows = [_array(where, item, f"{key} #{number}", 1)
                for number, item in enumerate(value, 1)]
        for number, row in enumerate(rows, 1):
            if row.size != n:
                raise where.error(f"{key} #{number}", f"has {_count(row.size, 'value')}, the "
                                                      f"model has {_count(n, 'freedom')}")
        return np.array(rows)
    points = _array(where, value, key, 2)
    if points.shape[1] != n or points.shape[0] == 0:
        raise where.error(key, f"must have rows of {n} values (one per freedom), got shape "
                               f"{points.shape}")
    return points


def _loading(where: _Where, table, loads: np.ndarray | None, n: int):
    """``(history, factors)`` of ``[loading]``: loads of each step (K, n) and, for
    ``factors``, each step's multiple of ``loads`` (K,), else None."""
    table = _table(where, table, "[loading]")
    _check_keys(where, table, _LOADING_KEYS, "[loading]")
    given = [name for name in ("factors", "points") if name in table]
    if len(given) != 1:
        found = "both" if given else "neither"
        raise where.error("[loading]", f"give exactly one of factors and points ({found} given)")
    steps = _option(where, "steps", table.get("steps", 1), 1, "[loading].steps")
    if "factors" in table:
        factors = _array(where, table["factors"], "[loading].factors", 1)
        if factors.size == 0:
            raise where.error("[loading].factors", "is empty")
        turning = factors[:, None]
    else:
        if loads is not None:
            raise where.error("[loading].points", "give the loads here or in [loads], not both "
                                                  "(factors = [...] scales [loads])")
        turning = _points(where, table["points"], n)
    try:
        path = linear_path(turning, steps)
    except InvalidInputError as exc:
        raise where.rewrap("[loading].steps", exc) from None
    if "factors" in table:
        return path * loads, path[:, 0]
    return path, None


# --------------------------------------------------------------------------------------------
# Public API


@dataclass
class ProblemSpec:
    """A contact problem read from a file, with the solver it asks for.

    Attributes
    ----------
    problem : ContactProblem or FrictionalProblem
        The assembled problem (loads in N, lengths in m, as in the file): a
        :class:`~contactqp.FrictionalProblem` when the file has ``[friction]``, whose loads are
        the first of ``[loading].points`` when these replace ``[loads]``.
    solver : str
        A name from :data:`contactqp.SOLVERS`, or the friction route (``"coulomb"``,
        ``"tresca"`` or ``"polygonal"``).
    options : dict
        Keyword options for the solver (``[solver]``'s, or ``[friction]``'s for friction).
    name : str
        The problem's name (the file's stem when the file gives none).
    path : pathlib.Path or None
        The TOML file, as given to :func:`load_problem_file`.
    history : ndarray, shape (K, n_freedoms), optional
        Loads of each step (N) of ``[loading]``; None for a single load.
    factors : ndarray, shape (K,), optional
        Each step's multiple of ``[loads]`` for ``[loading].factors``; None otherwise.
    """

    problem: ContactProblem | FrictionalProblem
    solver: str = "active-set"
    options: dict = field(default_factory=dict)
    name: str = ""
    path: Path | None = None
    history: np.ndarray | None = None
    factors: np.ndarray | None = None

    @property
    def frictional(self) -> bool:
        """True when the problem has friction."""
        return isinstance(self.problem, FrictionalProblem)

    def solve(self, progress: Callable[[int, int], None] | None = None
              ) -> ContactResult | FrictionalResult | HistoryResult:
        """Solve :attr:`problem` (along :attr:`history` when given) with :attr:`solver`.

        Parameters
        ----------
        progress : callable, optional
            For a history, called as ``progress(done, total)`` after each step.

        Returns
        -------
        ContactResult, FrictionalResult or HistoryResult
            Frictionless, with friction, or one certified result per step of the history.
        """
        if self.history is not None:
            return solve_history(self.problem, self.history, solver=self.solver,
                                 progress=progress, **self.options)
        if self.frictional:
            return self.problem.solve(solver=self.solver, **self.options)
        return solve(self.problem, solver=self.solver, **self.options)

    def step_factor(self, step: int) -> float | None:
        """Multiple of ``[loads]`` at ``step`` of a ``factors`` history, else None."""
        return None if self.factors is None else float(self.factors[step])

    def summary(self, result) -> dict:
        """A JSON-ready summary (no arrays) of ``result``, an answer of :meth:`solve`.

        A single result gives its own ``summary()``. A history gives ``success``, ``solver``,
        ``steps`` (count), ``failed_steps`` (indices), ``iterations``, ``seconds``,
        ``dissipated`` (J, all steps), ``certificate_worst`` (largest residual of any step),
        ``final`` (open, stick and slip counts of the last step) and ``records``: per step,
        ``step``, ``factor`` (None for ``points``) and the step's ``summary()``. NaN and inf
        become None, so that the summary is valid JSON.
        """
        if not isinstance(result, HistoryResult):
            return _json_ready(result.summary())
        steps = result.steps
        last = steps[-1].summary()
        return _json_ready({
            "success": result.success, "solver": self.solver, "steps": len(steps),
            "failed_steps": [k for k, step in enumerate(steps) if not step.success],
            "iterations": sum(step.nit for step in steps),
            "seconds": sum(step.wall_time for step in steps),
            "dissipated": float(np.sum(result.dissipated)),
            "certificate_worst": max(step.certificate.worst for step in steps),
            "final": {label: last[label] for label in STATUS_LABELS},
            "records": [{"step": k, "factor": self.step_factor(k), **step.summary()}
                        for k, step in enumerate(steps)],
        })


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
        or solver, a friction law or load history that does not fit the model. Errors of the
        model or problem (e.g. :class:`NotPositiveDefiniteError`) keep their class. Every
        message is one line naming the file and the key.
    """
    path = Path(path)
    where = _Where(path)
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
    _check_keys(where, doc, _TOP_KEYS, "top level")
    name = doc.get("name", path.stem)
    if not isinstance(name, str):
        raise where.error("name", f"must be a string, got {_describe(name)}")
    frictional = "friction" in doc
    if "loading" in doc and not frictional:
        raise where.error("[loading]", "a load history needs [friction] (without friction the "
                                       "answer does not depend on the load path)")
    solver, options, certificate_tol = _solver(where, doc, frictional)
    model = _build_model(where, doc)
    loading = _table(where, doc.get("loading", {}), "[loading]")
    loads = None if "points" in loading and "loads" not in doc else _loads(where, doc, model)
    obstacles = _obstacles(where, doc, model)
    history = factors = None
    if "loading" in doc:
        history, factors = _loading(where, loading, loads, model.n_freedoms)
        if loads is None:
            loads = history[0]
    if frictional:
        problem, solver, options = _friction(where, doc["friction"], model, loads, obstacles,
                                             certificate_tol)
    else:
        try:
            problem = ContactProblem(model, loads, obstacles, certificate_tol=certificate_tol)
        except InvalidInputError as exc:
            raise where.rewrap("problem", exc) from None
    return ProblemSpec(problem=problem, solver=solver, options=options, name=name, path=path,
                       history=history, factors=factors)


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


def _expected_steps(spec: ProblemSpec, result) -> list:
    """The results of each step of ``result``, after checking its kind and shapes."""
    problem = spec.problem
    if spec.history is not None:
        kind, steps = HistoryResult, getattr(result, "steps", [])
    else:
        kind, steps = FrictionalResult if spec.frictional else ContactResult, [result]
    if not isinstance(result, kind):
        raise InvalidInputError(f"result must be a {kind.__name__} for this problem, got "
                                f"{type(result).__name__}")
    if spec.history is not None and len(steps) != len(spec.history):
        raise InvalidInputError(f"result has {len(steps)} steps, the history has "
                                f"{len(spec.history)}")
    n, m = problem.model.n_freedoms, problem.constraints.n_constraints
    for step in steps:
        if np.shape(step.x) != (n,) or np.shape(step.forces)[:1] != (m,):
            raise InvalidInputError(
                f"result has {np.size(step.x)} displacements and {len(step.forces)} contacts; "
                f"the problem has {n} freedoms and {m} constraints")
    return steps


def _tangential_header(name: str, dim: int) -> list[str]:
    return [name] if dim == 2 else [f"{name}_{j}" for j in range(1, dim)]


def write_results(spec: ProblemSpec, result, out_dir) -> list[Path]:
    """Write a solved problem's results to a directory (files and columns: module docstring).

    Parameters
    ----------
    spec : ProblemSpec
    result : ContactResult, FrictionalResult or HistoryResult
        The answer of ``spec.solve()``.
    out_dir : str or os.PathLike
        Created, with its parents, when missing; files in it are overwritten.

    Returns
    -------
    list of pathlib.Path
        The files written, in the order of :data:`RESULT_FILES` (:data:`HISTORY_FILES` for a
        load history).

    Raises
    ------
    InvalidInputError
        ``result`` is not of the kind, or does not have the shapes, of ``spec.problem``.
    FileFormatError
        The directory or a file cannot be written.
    """
    steps = _expected_steps(spec, result)
    problem = spec.problem
    model, constraints = problem.model, problem.constraints
    history = spec.history is not None
    lead = ["step"] if history else []
    out = Path(out_dir)
    paths = [out / name for name in (HISTORY_FILES if history else RESULT_FILES)]

    def rows_of(make):  # rows of every step, prefixed by the step index for a history
        return [[k] * history + row for k, step in enumerate(steps) for row in make(step)]

    freedoms = [(node, int(freedom)) for node in range(model.n_nodes)
                for freedom in model.freedoms(node)]
    displacements = rows_of(lambda step: [[node, freedom, _float_text(step.x[freedom])]
                                          for node, freedom in freedoms])
    base = ["row", "node", "label", "gap0", "gap"]
    fixed = [[row, int(constraints.nodes[row]), constraints.labels[row],
              _float_text(constraints.gaps[row])] for row in range(constraints.n_constraints)]
    if spec.frictional:
        dim = problem.dim
        header = base + ["normal_force"] + [
            column for name in ("tangential_force", "slip", "tangential_displacement")
            for column in _tangential_header(name, dim)] + ["dissipated", "status"]
        contacts = rows_of(lambda step: [
            fixed[row] + [_float_text(v) for v in (
                step.gaps[row], *step.forces[row], *step.slip[row],
                *step.tangential_displacements[row], step.dissipation[row])]
            + [step.status_labels[row]] for row in range(constraints.n_constraints)])
        fields = ("x", "forces", "nodal_forces", "gaps", "slip", "tangential_displacements",
                  "contact_status", "dissipation")
        arrays = {"normals": problem.frames.normals, "tangents": problem.frames.tangents}
    else:
        header = base + ["force", "status"]
        contacts = rows_of(lambda step: [
            fixed[row] + [_float_text(step.gaps[row]), _float_text(step.forces[row]),
                          step.status_labels[row]] for row in range(constraints.n_constraints)])
        fields = ("x", "forces", "nodal_forces", "gaps", "closed")
        arrays = {}
    for name in fields:
        stacked = np.array([getattr(step, name) for step in steps])
        arrays[name] = stacked if history else stacked[0]
    if history:
        arrays["loads"] = np.array([step.loads for step in steps])
        arrays["success"] = np.array([step.success for step in steps], dtype=bool)
        if spec.factors is not None:
            arrays["factors"] = np.asarray(spec.factors, dtype=float)
    summary = {
        "name": spec.name,
        "problem": os.path.abspath(spec.path) if spec.path is not None else None,
        "solver": spec.solver,
        "options": spec.options,
        "result": spec.summary(result),
    }
    if spec.frictional:
        law = problem.law
        summary["friction"] = {"mu": law.mu, "cohesion": law.cohesion, "facets": law.facets}
    try:
        out.mkdir(parents=True, exist_ok=True)
        write_rows(paths[0], lead + ["node", "freedom", "u"], displacements)
        write_rows(paths[1], lead + header, contacts)
        with open(paths[2], "wb") as handle:
            np.savez(handle, **arrays)
        with open(paths[3], "w", encoding="utf-8") as handle:
            json.dump(_json_ready(summary), handle, indent=2, allow_nan=False)
            handle.write("\n")
        if history:
            cumulative = np.cumsum([step.dissipated for step in steps])
            write_rows(paths[4], ["step", "factor", *STATUS_LABELS, "dissipated",
                                  "cumulative_dissipated", "iterations", "certificate_worst",
                                  "success"], [
                [k, "" if spec.factors is None else _float_text(spec.factors[k]),
                 *np.bincount(step.contact_status, minlength=3).tolist(),
                 _float_text(step.dissipated), _float_text(cumulative[k]), step.nit,
                 _float_text(step.certificate.worst), step.success]
                for k, step in enumerate(steps)])
    except OSError as exc:
        raise FileFormatError(_one_line(f"cannot write results to '{out}': {exc}")) from None
    return paths

"""NASTRAN matrices: OUTPUT4 (OP4) files and DMIG cards of a bulk-data file, through pyNastran."""

from __future__ import annotations

import contextlib
import io
import logging
from collections.abc import Hashable, Iterable, Sequence
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ...core.model import SYMMETRY_RTOL, ReducedModel
from ...errors import ContactError, FileFormatError, InvalidInputError
from ._common import (
    DofsPerNode,
    StrPath,
    about,
    backend,
    existing_file,
    freedom_indices,
    node_major,
    one_line,
    reduced_model,
    whole_numbers,
)

__all__ = ["read_op4", "op4_matrix", "read_dmig", "dmig_matrix"]

_BULK_START = "BEGIN BULK"


def _which(path: Path, names: Sequence[str], name: str | None, what: str, plural: str) -> str:
    if name is None:
        if len(names) != 1:
            raise InvalidInputError(
                f"{path}: the file holds {len(names)} {plural} "
                f"({', '.join(names) or 'none'}); choose one by name"
            )
        return names[0]
    if name not in names:
        raise InvalidInputError(
            f"{path}: no {what} named {name!r} (the file holds {', '.join(names) or 'none'})"
        )
    return name


def op4_matrix(path: StrPath, name: str | None = None) -> np.ndarray | sp.coo_matrix:
    """One matrix of a NASTRAN OUTPUT4 file, ASCII or binary, dense or sparse.

    Parameters
    ----------
    path : str or os.PathLike
    name : str, optional
        The matrix's name (e.g. ``"KAA"``); default: the file's only matrix.

    Returns
    -------
    ndarray or scipy.sparse.coo_matrix, shape (n_rows, n_columns)
        Real, float64, as stored (a sparse OP4 matrix stays sparse).

    Raises
    ------
    FileFormatError
        Missing, unreadable or foreign file.
    InvalidInputError
        No matrix of that name, several matrices and no name, or a complex matrix.
    """
    file = existing_file(path)
    op4 = backend("pyNastran.op4.op4", "pyNastran", "NASTRAN OP4 files", "nastran")
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            matrices = op4.read_op4(str(file), precision="double", log=_log())
    except ContactError:
        raise
    except Exception as exc:  # whatever pyNastran raises on a foreign or truncated file
        raise FileFormatError(
            f"{file}: not a readable OP4 file ({type(exc).__name__}: {one_line(exc)})"
        ) from None
    name = _which(file, list(matrices), name, "matrix", "matrices")
    matrix = matrices[name].data
    if np.iscomplexobj(matrix):
        raise InvalidInputError(f"{file}: matrix {name!r} is complex; a real matrix is needed")
    return matrix.astype(float)


def _log() -> logging.Logger:
    """pyNastran's messages go to the ``contactqp.importers`` logger, silent unless configured."""
    log = logging.getLogger("contactqp.importers")
    if not log.handlers:
        log.addHandler(logging.NullHandler())
    return log


def read_op4(
    path: StrPath,
    name: str | None = None,
    *,
    kind: str,
    freedoms: ArrayLike | None = None,
    fixed: ArrayLike | None = None,
    dofs_per_node: DofsPerNode = 1,
    symmetry_rtol: float = SYMMETRY_RTOL,
) -> ReducedModel:
    """Reduced model from a stiffness (``KAA``, ``KGG``, ...) or flexibility matrix in an OP4 file.

    Parameters
    ----------
    path : str or os.PathLike
    name : str, optional
        The matrix's name; default: the file's only matrix.
    kind : {"stiffness", "flexibility"}
        What the matrix is (an OP4 file does not say).
    freedoms : sequence of int, optional
        Rows (from 0) of the computational freedoms, in the model's order; default: every row not
        fixed. A stiffness is condensed to them, a flexibility cut to them.
    fixed : sequence of int, optional
        Rows of a stiffness that are clamped (e.g. the SPCs of an unconstrained ``KGG``).
    dofs_per_node : int or sequence of int
        Freedoms of each computational node (see :class:`~contactqp.core.model.ReducedModel`).
    symmetry_rtol : float
        See :func:`~contactqp.core.model.check_spd_matrix`.

    Returns
    -------
    ReducedModel
        Given as the stiffness when every free row is kept, as a flexibility otherwise; in the
        units of the NASTRAN model.

    Raises
    ------
    FileFormatError, InvalidInputError
        See :func:`op4_matrix`; also a non-square matrix or bad indices.
    NotPositiveDefiniteError
        The (reduced) matrix is not positive definite (:class:`RigidBodyModeError` for a
        stiffness with rigid-body modes).
    MissingDependencyError
        pyNastran is not installed.
    """
    file = Path(path)
    matrix = op4_matrix(file, name)
    with about(file):
        return reduced_model(
            matrix if isinstance(matrix, np.ndarray) else sp.csc_matrix(matrix),
            kind,
            freedoms,
            fixed,
            dofs_per_node=dofs_per_node,
            symmetry_rtol=symmetry_rtol,
        )


def _bulk_only(path: Path, lines: list[str]):
    """The lines after ``BEGIN BULK`` of a file with no executive and case control, or None.

    pyNastran reads a file with ``BEGIN BULK`` as a whole deck (it then wants executive and
    case control) and a file without it as bulk data only; a file that starts at ``BEGIN BULK``
    is neither, so its bulk data is read on its own.
    """
    start = next(i for i, line in enumerate(lines) if line.upper().lstrip().startswith(_BULK_START))
    if any(line.upper().lstrip().startswith("CEND") for line in lines[:start]):
        return None
    bulk = lines[start + 1 :]
    if any(line.upper().lstrip().startswith("INCLUDE") for line in bulk):
        raise FileFormatError(
            f"{path}: bulk data starting at BEGIN BULK, without executive and "
            "case control (CEND), cannot have INCLUDE statements here; remove "
            "the BEGIN BULK line or add the control decks"
        )
    return bulk


def _bulk(path: Path):
    """The BDF model of a bulk-data file, with or without executive and case control."""
    bdf = backend("pyNastran.bdf.bdf", "pyNastran", "NASTRAN bulk-data files", "nastran")
    try:
        with open(path, encoding="utf-8", errors="replace") as handle:
            lines = handle.readlines()
        has_bulk_start = any(line.upper().lstrip().startswith(_BULK_START) for line in lines)
        bulk = _bulk_only(path, lines) if has_bulk_start else None
        model = bdf.BDF(log=_log())
        with contextlib.redirect_stdout(io.StringIO()):  # pyNastran prints the failing card
            if bulk is not None:
                model.read_bdf(
                    io.StringIO("".join(bulk) or "\n"), xref=False, punch=True, validate=False
                )
            else:
                model.read_bdf(str(path), xref=False, punch=not has_bulk_start, validate=False)
    except ContactError:
        raise
    except Exception as exc:  # pyNastran's errors on malformed cards or foreign files
        raise FileFormatError(
            f"{path}: not a readable NASTRAN bulk-data file ({type(exc).__name__}: {one_line(exc)})"
        ) from None
    return model


def _assemble(path: Path, dmig) -> tuple[sp.csc_matrix, list[tuple[int, int]]]:
    """The square matrix of a DMIG and the (grid, component) of each row, sorted."""
    if dmig.matrix_form not in (1, 6):
        raise InvalidInputError(
            f"{path}: DMIG {dmig.name!r} has form IFO={dmig.matrix_form}; "
            "a square (1) or symmetric (6) matrix is needed"
        )
    rows = np.asarray(dmig.GCi, dtype=int).reshape(-1, 2)
    cols = np.asarray(dmig.GCj, dtype=int).reshape(-1, 2)
    values = np.asarray(dmig.Real, dtype=float)
    if dmig.is_complex:
        raise InvalidInputError(f"{path}: DMIG {dmig.name!r} is complex; a real matrix is needed")
    labels, index = np.unique(np.vstack((rows, cols)), axis=0, return_inverse=True)
    index = index.reshape(-1)
    i, j, n = index[: len(rows)], index[len(rows) :], len(labels)
    if dmig.matrix_form == 6:  # each off-diagonal term given once, above or below the diagonal
        off = i != j
        if np.isin(j[off] * n + i[off], i[off] * n + j[off]).any():
            raise FileFormatError(
                f"{path}: symmetric DMIG {dmig.name!r} gives a term both "
                "above and below the diagonal"
            )
        i, j, values = (
            np.concatenate((i, j[off])),
            np.concatenate((j, i[off])),
            np.concatenate((values, values[off])),
        )
    matrix = sp.csc_matrix((values, (i, j)), shape=(n, n))
    return matrix, [(int(g), int(c)) for g, c in labels]


def dmig_matrix(path: StrPath, name: str) -> tuple[sp.csc_matrix, list[tuple[int, int]]]:
    """The matrix of a DMIG entry of a bulk-data file and the (grid, component) of its rows.

    Parameters
    ----------
    path : str or os.PathLike
        A bulk-data file, with or without executive and case control; ``BEGIN BULK`` is
        optional, and ``INCLUDE`` is followed (except in bulk data opened by ``BEGIN BULK``
        without control decks, which is read on its own).
    name : str
        The DMIG's name (e.g. ``"KAAX"``).

    Returns
    -------
    matrix : scipy.sparse.csc_matrix, shape (n, n)
        A symmetric DMIG (``IFO=6``) is completed from the triangle given.
    labels : list of (int, int)
        ``(grid, component)`` of each row and column, sorted; component 0 is a scalar point.

    Raises
    ------
    FileFormatError
        Missing or unreadable file, malformed cards.
    InvalidInputError
        No DMIG of that name, a rectangular or complex matrix.
    """
    return _load_dmig(existing_file(path), name)[1:]


def _load_dmig(path: Path, name: str):
    model = _bulk(path)
    name = _which(path, sorted(model.dmig), name, "DMIG", "DMIGs")
    return (model, *_assemble(path, model.dmig[name]))


def read_dmig(
    path: StrPath,
    name: str,
    nodes: Sequence[int] | None = None,
    components: Sequence[int] = (1, 2, 3),
    *,
    kind: str,
    fixed: Iterable[Sequence[int]] | None = None,
    symmetry_rtol: float = SYMMETRY_RTOL,
) -> ReducedModel:
    """Reduced model of chosen grids from a DMIG matrix (``K2GG``, ``KAAX``, ...) in bulk data.

    Parameters
    ----------
    path : str or os.PathLike
        The bulk-data file (see :func:`dmig_matrix`).
    name : str
        The DMIG's name.
    nodes : sequence of int, optional
        Grid (or scalar point) numbers of the computational nodes, in order; default: every grid
        of the matrix, ascending.
    components : sequence of int
        NASTRAN components taken at every node (1-3 translations, 4-6 rotations, 0 for scalar
        points), 1 to 3 of them, in order.
    kind : {"stiffness", "flexibility"}
        What the matrix is.
    fixed : sequence of (int, int), optional
        ``(grid, component)`` freedoms of a stiffness that are clamped. Freedoms neither chosen
        nor fixed are condensed out of a stiffness and dropped from a flexibility.
    symmetry_rtol : float
        See :func:`~contactqp.core.model.check_spd_matrix`.

    Returns
    -------
    ReducedModel
        Freedoms node by node in the order of ``nodes`` and ``components``. Coordinates are those
        of the GRID cards in the file when every chosen node has one in the basic system.

    Raises
    ------
    FileFormatError, InvalidInputError
        See :func:`dmig_matrix`; also a grid or component not in the matrix.
    NotPositiveDefiniteError
        The (reduced) matrix is not positive definite (:class:`RigidBodyModeError` for a
        stiffness with rigid-body modes).
    MissingDependencyError
        pyNastran is not installed.

    Notes
    -----
    A DMIG's components are those of each grid's displacement coordinate system (the ``CD``
    field of its GRID card), as NASTRAN assembles them; the coordinates returned are in the
    basic system. Normals and gaps of a contact must be given in the same displacement systems.
    """
    path = existing_file(path)
    components = whole_numbers(components, "components")
    if nodes is not None:
        nodes = whole_numbers(nodes, "nodes")
    if fixed is not None:
        try:
            fixed = [tuple(whole_numbers(pair, "fixed")) for pair in fixed]
        except TypeError:
            fixed = [()]
        if any(len(pair) != 2 for pair in fixed):
            raise InvalidInputError("fixed must be a list of (grid, component) pairs")
    model, matrix, labels = _load_dmig(path, name)
    if nodes is None:
        nodes = sorted({grid for grid, _ in labels})
    grids = [model.nodes.get(node) for node in nodes]
    coordinates = None
    if all(grid is not None and grid.cp == 0 for grid in grids):
        coordinates = np.array([grid.xyz for grid in grids], dtype=float)

    def describe(grid: Hashable, component: Hashable) -> str:
        return f"grid {grid} component {component}"

    with about(path):
        keep = freedom_indices(labels, node_major(nodes, components), "grid", describe)
        fixed_index = None
        if fixed is not None:
            fixed_index = freedom_indices(labels, fixed, "grid", describe)
        names = [describe(g, c) for g, c in labels]
        return reduced_model(
            matrix,
            kind,
            keep,
            fixed_index,
            names,
            dofs_per_node=len(components),
            coordinates=coordinates,
            symmetry_rtol=symmetry_rtol,
        )

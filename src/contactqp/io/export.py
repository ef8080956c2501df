"""Result export: VTU meshes with point data (meshio) and CSV tables, for any result."""

from __future__ import annotations

import csv
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidInputError
from ..optional import require

__all__ = ["PointMesh", "write_vtu", "write_csv", "write_rows"]


class PointMesh(NamedTuple):
    """A mesh and its point fields, as :func:`write_vtu` takes them: ``write_vtu(path, *mesh)``.

    An application builds one from its results (e.g.
    :func:`contactqp.applications.riveting.result_mesh`); this module writes it.
    """

    points: np.ndarray
    cells: list
    point_data: dict


def write_vtu(
    path: str | os.PathLike[str],
    points: ArrayLike,
    cells: Iterable[tuple[str, ArrayLike]],
    point_data: Mapping[str, ArrayLike],
) -> Path:
    """Write a mesh and its point fields to a VTU file (ParaView): the one VTU writer.

    Parameters
    ----------
    path : str or Path
    points : array_like, shape (n, 2) or (n, 3)
        Coordinates (m); 2-D points get ``z = 0``.
    cells : sequence of (str, array_like)
        meshio cell blocks, e.g. ``[("quad", quads)]`` with ``quads`` of shape (c, 4).
    point_data : dict of array_like
        Fields of shape (n,) or (n, k), one value per point.

    Returns
    -------
    Path
    """
    meshio = require("meshio", "VTU output", "fem")
    xyz = np.asarray(points, dtype=float)
    if xyz.ndim != 2 or xyz.shape[1] not in (2, 3):
        raise InvalidInputError(f"points must have shape (n, 2) or (n, 3), got {xyz.shape}")
    if xyz.shape[1] == 2:
        xyz = np.column_stack([xyz, np.zeros(len(xyz))])
    data = {name: np.asarray(values) for name, values in point_data.items()}
    for name, values in data.items():
        if values.shape[0] != len(xyz):
            raise InvalidInputError(
                f"point_data[{name!r}] has {values.shape[0]} rows for {len(xyz)} points"
            )
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    meshio.write(str(path), meshio.Mesh(xyz, list(cells), point_data=data), file_format="vtu")
    return path


def write_csv(path: str | os.PathLike[str], columns: Mapping[str, ArrayLike]) -> Path:
    """Write equal-length columns as a CSV table with a header row.

    Parameters
    ----------
    path : str or Path
    columns : dict of array_like
        ``{header: values}``, each of shape (r,); floats written with full precision
        (``repr``), so that a table read back gives the same numbers.

    Returns
    -------
    Path
    """
    names = list(columns)
    values = [np.asarray(columns[name]).reshape(-1) for name in names]
    if not names or len({len(v) for v in values}) != 1:
        raise InvalidInputError(
            f"columns must be non-empty and of one length, got lengths {[len(v) for v in values]}"
        )
    return write_rows(path, names, zip(*(v.tolist() for v in values), strict=True))


def write_rows(
    path: str | os.PathLike[str], header: Sequence[str], rows: Iterable[Iterable[object]]
) -> Path:
    """Write a header row and ``rows`` (iterables of values) as a UTF-8 CSV table.

    Parameters
    ----------
    path : str or Path
        Created with its folders; overwritten.
    header : sequence of str
    rows : iterable of sequence

    Returns
    -------
    Path
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(header)
        writer.writerows(rows)
    return path

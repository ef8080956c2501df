"""Readers of measured height maps: CSV rows, NPY arrays and the ASCII grid with units.

Every map is one period of a periodic surface, ``heights[j, i]`` at ``x = i cell``,
``y = j cell`` (m): a file's rows are y, its columns x. Every failure is one line that names the
file (:class:`~contactqp.errors.FileFormatError`, or :class:`~contactqp.errors.InvalidInputError`
for an argument). Nothing is ever written.

Formats (by extension, :data:`HEIGHT_MAP_FORMATS`):

``.csv``, ``.txt``
    One row of heights (m) per line, commas or blanks between them, ``#`` starts a comment. The
    cell size is not in the file: give it.
``.npy``
    A 2-D numpy array of heights (m), read without pickle. The cell size is not in the file.
``.asc``
    The ASCII grid with units: header lines ``key value`` first, then ``nrows`` lines of
    ``ncols`` numbers (blanks or commas between them); ``#`` starts a comment anywhere::

        # a measured patch, 3 x 4 cells of 0.5 um
        ncols 4
        nrows 3
        cellsize 0.5 um
        unit nm
        12.0  13.5  11.2  10.9
        14.1  15.0  12.7  11.3
        13.3  12.2  10.8   9.6

    The four keys are required, each once, in any order (case-insensitive): ``ncols`` and
    ``nrows`` (positive integers: the grid's columns, along x, and rows, along y), ``cellsize``
    (a positive number and its unit: the side of a square cell) and ``unit`` (the unit of the
    heights). Units: :data:`UNITS`. The file gives the cell size, so none may be given besides.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import FileFormatError, InvalidInputError
from ...io.arrays import read_csv_array, read_numpy_array

__all__ = ["HEIGHT_MAP_FORMATS", "UNITS", "HeightMap", "read_height_map", "read_ascii_grid"]

#: Height map formats and the file name endings that select them.
HEIGHT_MAP_FORMATS = {"csv": (".csv", ".txt"), "npy": (".npy",), "asc": (".asc",)}
#: Length units of the ASCII grid, in metres.
UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "nm": 1e-9}
_KEYS = ("ncols", "nrows", "cellsize", "unit")


@dataclass(frozen=True)
class HeightMap:
    """One period of a surface: heights (m) on square cells.

    Attributes
    ----------
    heights : ndarray, shape (ny, nx)
        ``heights[j, i]`` at ``x = i cell``, ``y = j cell`` (m), finite.
    cell : float
        Side of a square cell (m).
    source : Path or None
        The file it was read from.
    """

    heights: np.ndarray
    cell: float
    source: Path | None = None

    @property
    def shape(self) -> tuple[int, int]:
        """``(ny, nx)``."""
        return (int(self.heights.shape[0]), int(self.heights.shape[1]))


def read_height_map(path: str | os.PathLike[str], cell: float | None = None) -> HeightMap:
    """Read a height map from a ``.csv``/``.txt``, ``.npy`` or ``.asc`` file.

    Parameters
    ----------
    path : str or os.PathLike
        The file; its format comes from its extension (:data:`HEIGHT_MAP_FORMATS`).
    cell : float, optional
        Side of a square cell (m): required for CSV and NPY files, refused for an ASCII grid
        (which gives its own).

    Returns
    -------
    HeightMap

    Raises
    ------
    FileFormatError
        The file is missing, unreadable, of an unknown extension, not a 2-D grid of at least
        2 x 2 numbers, or holds a value that is not finite.
    InvalidInputError
        ``cell`` is missing for a CSV or NPY file, given for an ASCII grid, or not positive.
    """
    path = Path(path)
    fmt = _format(path)
    if not path.is_file():
        raise FileFormatError(
            f"{path}: file not found" if not path.exists() else f"{path}: not a file"
        )
    if fmt == "asc":
        if cell is not None:
            raise InvalidInputError(f"{path}: the ASCII grid gives its cell size; give no cell")
        return read_ascii_grid(path)
    if cell is None:
        raise InvalidInputError(f"{path}: a .{fmt} height map holds no cell size; give the cell")
    if (
        isinstance(cell, bool)
        or not isinstance(cell, int | float)
        or not (math.isfinite(cell) and cell > 0)
    ):
        raise InvalidInputError(f"cell must be positive and finite (m), got {cell!r}")
    heights = read_csv_array(path) if fmt == "csv" else read_numpy_array(path)
    if np.iscomplexobj(heights) or not np.issubdtype(np.asarray(heights).dtype, np.number):
        raise FileFormatError(f"{path}: holds {np.asarray(heights).dtype} values, not real heights")
    return HeightMap(_checked(path, np.asarray(heights, dtype=float)), float(cell), path)


def read_ascii_grid(path: str | os.PathLike[str]) -> HeightMap:
    """Read the ASCII grid with units (the module's ``.asc`` format); heights and cell in m.

    Raises
    ------
    FileFormatError
        Unreadable text, a missing, repeated or unknown key, a bad value or unit, or rows that
        do not match ``nrows`` and ``ncols``; the message names the file and the line.
    """
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise FileFormatError(f"{path}: not a readable text file ({exc})") from None
    header: dict[str, tuple[int, list[str]]] = {}
    rows: list[tuple[int, str]] = []
    for number, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        words = text.split()
        key = words[0].lower()
        if not rows and key[0].isalpha():
            if key not in _KEYS:
                raise FileFormatError(
                    f"{path}, line {number}: unknown key {words[0]!r} (expected {', '.join(_KEYS)})"
                )
            if key in header:
                raise FileFormatError(f"{path}, line {number}: {key} given twice")
            header[key] = (number, words[1:])
        else:
            rows.append((number, text))
    missing = [key for key in _KEYS if key not in header]
    if missing:
        raise FileFormatError(f"{path}: the header lacks {', '.join(missing)}")
    ncols = _count(path, "ncols", *header["ncols"])
    nrows = _count(path, "nrows", *header["nrows"])
    cell = _length(path, "cellsize", *header["cellsize"])
    number, words = header["unit"]
    if len(words) != 1 or words[0] not in UNITS:
        raise FileFormatError(
            f"{path}, line {number}: unit must be one of {', '.join(UNITS)}, "
            f"got {' '.join(words)!r}"
        )
    scale = UNITS[words[0]]
    if len(rows) != nrows:
        raise FileFormatError(f"{path}: nrows is {nrows} but {len(rows)} rows of heights follow")
    heights = np.empty((nrows, ncols))
    for j, (number, text) in enumerate(rows):
        values = text.replace(",", " ").split()
        if len(values) != ncols:
            raise FileFormatError(
                f"{path}, line {number}: {len(values)} heights where ncols is {ncols}"
            )
        try:
            heights[j] = [float(value) for value in values]
        except ValueError:
            raise FileFormatError(f"{path}, line {number}: a height is not a number") from None
    return HeightMap(_checked(path, heights * scale), cell, path)


def _format(path: Path) -> str:
    name = path.name.lower()
    for fmt, endings in HEIGHT_MAP_FORMATS.items():
        if name.endswith(endings):
            return fmt
    known = ", ".join(e for endings in HEIGHT_MAP_FORMATS.values() for e in endings)
    raise FileFormatError(f"{path}: unknown height map extension (known: {known})")


def _checked(path: Path, heights: np.ndarray) -> np.ndarray:
    if heights.ndim != 2 or min(heights.shape) < 2:
        raise FileFormatError(
            f"{path}: a height map is a 2-D grid of at least 2 x 2, got shape {heights.shape}"
        )
    bad = ~np.isfinite(heights)
    if bad.any():
        j, i = np.argwhere(bad)[0]
        raise FileFormatError(
            f"{path}: {int(bad.sum())} heights are not finite (the first at row {j}, column {i})"
        )
    return heights


def _count(path: Path, key: str, number: int, words: list[str]) -> int:
    if len(words) == 1 and words[0].isdigit() and int(words[0]) >= 2:
        return int(words[0])
    raise FileFormatError(f"{path}, line {number}: {key} must be an integer of at least 2")


def _length(path: Path, key: str, number: int, words: list[str]) -> float:
    try:
        value = float(words[0]) if len(words) == 2 and words[1] in UNITS else math.nan
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise FileFormatError(
            f"{path}, line {number}: {key} must be a positive number and a unit "
            f"({', '.join(UNITS)}), e.g. '{key} 0.5 um'"
        )
    return value * UNITS[words[1]]

"""Typed values of an assembly file, on top of the problem files' helpers.

Arrays and file references are :func:`contactqp.io.problem_file.values.array`'s; this module adds
the scalars, choices, paths, the ``[units]`` conversion and the CSV tables with a header whose
columns may carry their unit (``x (mm)``).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import FileFormatError, InvalidInputError
from ...io.problem_file.messages import Where, as_table, check_keys, describe
from ...io.problem_file.values import array, is_file_ref
from .schema import FORCE_UNITS, LENGTH_UNITS, UNITS_KEYS

__all__ = [
    "Units",
    "units_section",
    "number",
    "integer",
    "choice",
    "boolean",
    "string",
    "file_path",
    "vector",
    "read_columns",
    "array",
    "is_file_ref",
]

_HEADER_UNIT = re.compile(r"^\s*([^()\[\]]*?)\s*(?:[(\[]\s*([^()\[\]]*?)\s*[)\]])?\s*$")


@dataclass(frozen=True)
class Units:
    """The file's units: what one length and one force of the file are in metres and newtons."""

    length: float = 1.0
    force: float = 1.0
    length_name: str = "m"
    force_name: str = "N"

    @property
    def stiffness(self) -> float:
        """One stiffness unit of the file (force / length) in N/m."""
        return self.force / self.length

    @property
    def pressure(self) -> float:
        """One pressure unit (force / length^2) in Pa: MPa for N and mm."""
        return self.force / self.length**2


def units_section(where: Where, doc: dict) -> Units:
    """The ``[units]`` table (default SI)."""
    table = as_table(where, doc.get("units", {}), "units")
    check_keys(where, table, UNITS_KEYS, "units")
    length = choice(where, table.get("length", "m"), "units.length", tuple(LENGTH_UNITS))
    force = choice(where, table.get("force", "N"), "units.force", tuple(FORCE_UNITS))
    return Units(LENGTH_UNITS[length], FORCE_UNITS[force], length, force)


def number(
    where: Where,
    value,
    key: str,
    *,
    positive: bool = False,
    nonnegative: bool = False,
    scale: float = 1.0,
) -> float:
    """A finite number (times ``scale``), optionally > 0 or >= 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise where.error(key, f"must be a number, got {describe(value)}")
    if not math.isfinite(value):
        raise where.error(key, f"must be finite, got {value}")
    if positive and value <= 0:
        raise where.error(key, f"must be positive, got {value}")
    if nonnegative and value < 0:
        raise where.error(key, f"must be >= 0, got {value}")
    return float(value) * scale


def integer(where: Where, value, key: str, minimum: int | None = None) -> int:
    """An integer, optionally at least ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise where.error(key, f"must be an integer, got {describe(value)}")
    if minimum is not None and value < minimum:
        raise where.error(key, f"must be at least {minimum}, got {value}")
    return value


def choice(where: Where, value, key: str, allowed: tuple[str, ...]) -> str:
    """One of the strings ``allowed``."""
    if not isinstance(value, str) or value not in allowed:
        shown = describe(value)
        raise where.error(key, f"must be one of {', '.join(map(repr, allowed))}, got {shown}")
    return value


def boolean(where: Where, value, key: str) -> bool:
    """``true`` or ``false``."""
    if not isinstance(value, bool):
        raise where.error(key, f"must be true or false, got {describe(value)}")
    return value


def string(where: Where, value, key: str) -> str:
    """A non-empty string."""
    if not isinstance(value, str) or not value:
        raise where.error(key, f"must be a non-empty string, got {describe(value)}")
    return value


def file_path(where: Where, value, key: str) -> Path:
    """An existing file named by ``value``, relative to the assembly file's directory."""
    name = string(where, value, key)
    path = Path(name).expanduser()
    if not path.is_absolute():
        path = where.base / path
    if not path.is_file():
        raise where.error(
            key, f"file not found: '{name}' (looked for {os.path.abspath(path)})", FileFormatError
        )
    return path


def vector(where: Where, value, key: str, size: int | tuple[int, ...], scale: float = 1.0):
    """An inline list of ``size`` numbers (one of the sizes when a tuple), times ``scale``."""
    sizes = (size,) if isinstance(size, int) else size
    values = array(where, value, key, 1)
    if values.size not in sizes:
        wanted = " or ".join(str(s) for s in sizes)
        raise where.error(key, f"must hold {wanted} numbers, got {values.size}")
    return values * scale


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def read_columns(
    where: Where, value, key: str, length_names: tuple[str, ...], units: Units
) -> tuple[dict[str, np.ndarray], Path]:
    """The columns of a CSV table with a header row, by name.

    The header names each column; a unit in parentheses or brackets (``x (mm)``, ``gap [um]``)
    gives the unit of a length column, else the file's length unit applies. Columns in
    ``length_names`` (and every column when it holds ``"*"``) are lengths, returned in metres;
    the others are numbers as written.
    """
    path = file_path(where, value, key)
    label = f"{key} ('{value}')"
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise where.error(label, f"not a readable text file ({exc})", FileFormatError) from None
    lines = [line.split("#", 1)[0].strip() for line in text.splitlines()]
    lines = [line for line in lines if line]
    if not lines:
        raise where.error(label, "the file holds no rows", FileFormatError)
    delimiter = "," if "," in lines[0] else None
    header = [token.strip() for token in lines[0].split(delimiter)]
    if all(_is_number(token) for token in header):
        raise where.error(label, "needs a header row naming its columns", FileFormatError)
    names, factors = [], []
    for token in header:
        match = _HEADER_UNIT.match(token)
        name, unit = (match.group(1), match.group(2)) if match else (token, None)
        name = name.strip().lower()
        is_length = name in length_names or "*" in length_names
        if unit:
            if unit in LENGTH_UNITS and is_length:
                factor = LENGTH_UNITS[unit]
            elif not is_length:
                raise where.error(label, f"column '{token}': only lengths carry a unit here")
            else:
                known = ", ".join(LENGTH_UNITS)
                raise where.error(label, f"column '{token}': unknown unit '{unit}' ({known})")
        else:
            factor = units.length if is_length else 1.0
        if name in names:
            raise where.error(label, f"column '{name}' appears twice")
        names.append(name)
        factors.append(factor)
    try:
        rows = np.loadtxt(lines[1:], delimiter=delimiter, ndmin=2, dtype=float)
    except ValueError as exc:
        message = "; ".join(str(exc).splitlines())
        raise where.error(label, f"not a table of numbers: {message}", FileFormatError) from None
    if rows.size == 0:
        raise where.error(label, "the table has a header but no rows", FileFormatError)
    if rows.shape[1] != len(names):
        raise where.error(
            label, f"rows have {rows.shape[1]} values, the header names {len(names)} columns"
        )
    if not np.all(np.isfinite(rows)):
        raise where.error(label, "contains NaN or inf")
    columns = {name: rows[:, i] * f for i, (name, f) in enumerate(zip(names, factors, strict=True))}
    return columns, path


def require_columns(where: Where, columns: dict, key: str, needed: tuple[str, ...]) -> None:
    """Raise naming ``key`` when a column of ``needed`` is missing."""
    missing = [name for name in needed if name not in columns]
    if missing:
        raise where.error(
            key,
            f"the header lacks the column{'s' if len(missing) > 1 else ''} "
            f"{', '.join(missing)} (it has {', '.join(columns)})",
            InvalidInputError,
        )

"""Values of a problem file: arrays (inline or file references) and typed scalar settings."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from ...errors import FileFormatError, InvalidInputError
from ..arrays import read_array
from .messages import Where, check_keys, describe
from .schema import FILE_REF_KEYS

__all__ = ["is_file_ref", "array", "option", "per_contact"]


def is_file_ref(value) -> bool:
    """True for a file reference: a path string or an inline table with ``file``."""
    return isinstance(value, str) or (isinstance(value, dict) and "file" in value)


def _load_ref(where: Where, value, key: str) -> tuple[np.ndarray, str]:
    """Read a file reference; return the array and the key label naming the file."""
    if isinstance(value, str):
        name, npz_key, fmt = value, None, None
    else:
        check_keys(where, value, FILE_REF_KEYS, key)
        name, npz_key, fmt = value["file"], value.get("key"), value.get("format")
        for sub, item in (("file", name), ("key", npz_key), ("format", fmt)):
            if item is not None and not isinstance(item, str):
                raise where.error(f"{key}.{sub}", f"must be a string, got {describe(item)}")
    if not name:
        raise where.error(key, "the file name is empty")
    label = f"{key} ('{name}')"
    path = Path(name).expanduser()
    if not path.is_absolute():
        path = where.base / path
    if not path.exists():
        raise where.error(
            key, f"file '{name}' not found (looked for {os.path.abspath(path)})", FileFormatError
        )
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


def _inline(where: Where, value, key: str) -> np.ndarray:
    if not isinstance(value, list):
        raise where.error(
            key, f"must be an array of numbers or a file reference, got {describe(value)}"
        )
    if not _numeric_leaves(value):
        raise where.error(key, "must hold numbers only (no strings, booleans or tables)")
    try:
        return np.array(value, dtype=float)
    except ValueError:
        raise where.error(key, "rows have different lengths") from None


def array(where: Where, value, key: str, ndim: int, integer: bool = False) -> np.ndarray:
    """An inline array or a file reference as a finite array with ``ndim`` dimensions.

    A vector (``ndim == 1``) read from a file may be stored as one row or one column. With
    ``integer`` the values must be whole numbers and an ``int`` array is returned.
    """
    label = key
    if is_file_ref(value):
        values, label = _load_ref(where, value, key)
        if ndim == 1 and values.ndim == 2 and 1 in values.shape:
            values = values.reshape(-1)
        elif ndim == 2 and values.ndim == 1 and values.size == 1:
            values = values.reshape(1, 1)
    else:
        if integer and _numeric_leaves(value) and not _numeric_leaves(value, integer=True):
            raise where.error(key, "must hold integers (indices count from 0)")
        values = _inline(where, value, key)
    if values.ndim != ndim:
        shape = "a list of numbers" if ndim == 1 else "an array of rows"
        raise where.error(label, f"must be {shape} ({ndim}-D), got shape {values.shape}")
    if not np.all(np.isfinite(values)):
        bad = np.argwhere(~np.isfinite(values))[0]
        position = ", ".join(str(i) for i in bad)
        raise where.error(
            label, f"contains NaN or inf (first at index [{position}], counting from 0)"
        )
    if integer:
        if np.any(values != np.round(values)):
            raise where.error(label, "must hold integers (indices count from 0)")
        return values.astype(int)
    return values


def option(where: Where, name: str, value, default, key: str):
    """A scalar setting checked against the type of its ``default`` (None: any type).

    ``tol``, ``max_iter`` and any ``*_tol`` must be positive, backends' ``tol_*`` and ``eps_*``
    >= 0, and every number finite.
    """
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
        raise where.error(key, f"must be {kind} (default {default!r}), got {describe(value)}")
    positive = name in ("tol", "max_iter") or name.endswith("_tol")
    nonnegative = name.startswith(("tol_", "eps_"))  # backends' tolerances
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if (positive or nonnegative) and not number:
        raise where.error(key, f"must be a number, got {describe(value)}")
    if number:
        if not math.isfinite(value):
            raise where.error(key, f"must be finite, got {value}")
        if positive and value <= 0:
            raise where.error(key, f"must be positive, got {value}")
        if nonnegative and value < 0:
            raise where.error(key, f"must be >= 0, got {value}")
    return value


def per_contact(where: Where, value, key: str):
    """A number, or an array or file of numbers (one per contact)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return array(where, value, key, 1)

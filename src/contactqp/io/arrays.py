"""Arrays from files (CSV tables, numpy's ``.npy`` and ``.npz``, MatrixMarket, NASTRAN OP4), read
safely: every failure is one line that names the file.

:func:`read_array` picks the reader from the file's extension (:data:`ARRAY_FORMATS`); the
MatrixMarket and OP4 matrices come from :mod:`contactqp.compliance.importers`.

``np.load`` of a truncated or corrupt file raises whatever its layers meet (``BadZipFile``,
``zlib.error``, ``EOFError``, ``OSError``, ``ValueError``, ``KeyError``), some only when an
array of the archive is read; :func:`read_numpy_array` turns each into a
:class:`~contactqp.errors.FileFormatError` that names the file.
"""

from __future__ import annotations

import os
import warnings
import zipfile
import zlib
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ..errors import FileFormatError, InvalidInputError

__all__ = ["read_array", "read_csv_array", "read_numpy_array", "ARRAY_FORMATS"]

#: Array file formats and the file name endings that select them.
ARRAY_FORMATS = {
    "csv": (".csv", ".txt", ".dat"),
    "npz": (".npz",),
    "npy": (".npy",),
    "mtx": (".mtx", ".mtx.gz"),
    "op4": (".op4",),
}

#: The arrays of an archive written by :func:`scipy.sparse.save_npz`.
SCIPY_SPARSE_NPZ = frozenset({"format", "shape", "data"})

_UNREADABLE = (zipfile.BadZipFile, zlib.error, EOFError, OSError, ValueError, KeyError)


def read_array(
    path: str | os.PathLike[str], key: str | None = None, format: str | None = None
) -> np.ndarray:
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
    fmt = array_format(path, format)
    if key is not None and fmt not in ("npz", "op4"):
        raise InvalidInputError(
            f"key {key!r} applies only to .npz and .op4 files, not to {fmt} files"
        )
    if not path.exists():
        raise FileFormatError(f"file '{path}' not found")
    if not path.is_file():
        raise FileFormatError(f"'{path}' is not a file")
    if fmt == "csv":
        array = read_csv_array(path)
    elif fmt in ("npz", "npy"):
        array = read_numpy_array(path, key)
    else:
        from ..compliance.importers import mtx_matrix, op4_matrix

        matrix = op4_matrix(path, key) if fmt == "op4" else mtx_matrix(path)
        array = matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix)
    array = np.asarray(array)
    if np.iscomplexobj(array):
        raise FileFormatError("the file holds complex numbers; a real array is needed")
    if not (np.issubdtype(array.dtype, np.number) or array.dtype == bool):
        raise FileFormatError(f"the file holds {array.dtype} values, not numbers")
    return array.astype(float)


def array_format(path: Path, fmt: str | None = None) -> str:
    """The format of :data:`ARRAY_FORMATS` that ``fmt`` names or ``path``'s extension selects.

    Raises
    ------
    InvalidInputError
        ``fmt`` is not a known format.
    FileFormatError
        No ``fmt`` and an extension no format has.
    """
    if fmt is not None:
        if fmt not in ARRAY_FORMATS:
            raise InvalidInputError(f"unknown format {fmt!r} (expected {', '.join(ARRAY_FORMATS)})")
        return fmt
    name = Path(path).name.lower()
    for candidate, endings in ARRAY_FORMATS.items():
        if name.endswith(endings):
            return candidate
    known = ", ".join(e for endings in ARRAY_FORMATS.values() for e in endings)
    raise FileFormatError(
        f"cannot tell the format of '{Path(path).name}' from its extension (known: {known}); "
        'give it with { file = ..., format = "csv" }'
    )


def read_numpy_array(path: str | os.PathLike[str], key: str | None = None) -> np.ndarray:
    """The array of a ``.npy`` file, or the array ``key`` of a ``.npz`` archive.

    Parameters
    ----------
    path : str or Path
        A ``.npy`` or ``.npz`` file (told apart by content, as :func:`numpy.load` does).
    key : str, optional
        The array to take from an archive; default its only array. An archive written by
        :func:`scipy.sparse.save_npz` is, without ``key``, read as one (densified) matrix.

    Raises
    ------
    FileFormatError
        Missing, truncated, corrupt or foreign file, or one that needs pickle.
    InvalidInputError
        ``key`` not in the archive, no ``key`` for an archive of several arrays, or ``key``
        given for a ``.npy`` file.
    """
    path = Path(path)
    if not path.is_file():
        raise FileFormatError(f"{path}: file not found")
    try:
        with open(path, "rb") as stream:
            loaded = np.load(stream, allow_pickle=False)
            if isinstance(loaded, np.ndarray):
                if key is not None:
                    raise InvalidInputError(
                        f"{path}: a .npy file holds one array; key {key!r} applies to .npz archives"
                    )
                return loaded
            with loaded as archive:
                return _archive_array(path, archive, key)
    except InvalidInputError:
        raise
    except _UNREADABLE as exc:
        kind = "zlib.error" if isinstance(exc, zlib.error) else type(exc).__name__
        raise FileFormatError(
            f"{path}: not a readable .npy / .npz file ({kind}: {_one_line(exc)})"
        ) from None


def read_csv_array(path: str | os.PathLike[str]) -> np.ndarray:
    """The numbers of a CSV table (commas or blanks between them; ``#`` starts a comment).

    Returns
    -------
    ndarray of float, 2-D
        One row per line.

    Raises
    ------
    FileFormatError
        A file that is not text, holds no numbers or not a table of numbers; numpy's warnings
        stay inside.
    """
    path = Path(path)
    try:
        with open(path, encoding="utf-8-sig") as handle:
            text = handle.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise FileFormatError(f"{path}: not a readable text file ({_one_line(exc)})") from None
    body = "\n".join(line.split("#", 1)[0] for line in text.splitlines())
    if not body.strip():
        raise FileFormatError(f"{path}: the file holds no numbers")
    delimiter = "," if "," in body else None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # an empty row's warning: the error says it
            return np.loadtxt(body.splitlines(), delimiter=delimiter, ndmin=2, dtype=float)
    except ValueError as exc:
        raise FileFormatError(f"{path}: not a table of numbers: {_one_line(exc)}") from None


def _archive_array(path: Path, archive: np.lib.npyio.NpzFile, key: str | None) -> np.ndarray:
    names = list(archive.files)
    if key is None and SCIPY_SPARSE_NPZ <= set(names):
        import scipy.sparse

        return scipy.sparse.load_npz(path).toarray()
    if key is None:
        if len(names) != 1:
            raise InvalidInputError(
                f"{path}: the archive holds {len(names)} arrays "
                f"({', '.join(names) or 'none'}); name the one to read"
            )
        key = names[0]
    if key not in names:
        raise InvalidInputError(
            f"{path}: the archive has no array {key!r} (it holds {', '.join(names) or 'none'})"
        )
    return archive[key]


def _one_line(exc: BaseException) -> str:
    return "; ".join(part.strip() for part in str(exc).splitlines() if part.strip())

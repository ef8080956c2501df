"""FCLIB problem files (HDF5) and Siconos ``.dat`` files.

FCLIB HDF5 layout, as read and written here:

* ``/fclib_local/W/{m,n,nz,nzmax,p,i,x}``: a CSparse-style sparse matrix. ``nz = -2``:
  compressed rows (``p`` row pointers, length ``m+1``; ``i`` column indices); ``nz = -1``:
  compressed columns (``p`` column pointers, ``i`` row indices); ``nz >= 0``: ``nz`` triplets
  (``i`` rows, ``p`` columns; if the indices only fit the other way round they are swapped).
  Only the first ``p[-1]`` (compressed) or ``nz`` (triplets) entries of ``i, x`` are used;
  duplicate triplets are summed.
* ``/fclib_local/vectors/{q,mu}``, ``/fclib_local/spacedim``, ``/fclib_local/info/title``.
* ``/fclib_global/{M,H}``, ``/fclib_global/vectors/{f,w,mu}``, ``/fclib_global/spacedim``;
  ``H`` is ``ndof x (d*nc)``.
* ``/solution/{r,u[,v]}``. A solution file written by ``contactqp fclib`` also carries the root
  attribute ``contactqp_solution_of`` (the input's path), by which it is known as one
  (:func:`is_own_solution`).

h5py is imported only when an HDF5 file is read or written.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..core.local_problem import DENSE_SIZE, GlobalProblem, LocalProblem
from ..errors import (
    ContactError,
    FileFormatError,
    FileLayoutError,
    InvalidInputError,
    UnsupportedProblemError,
)
from ..optional import require
from .siconos import read_dat

if TYPE_CHECKING:
    import scipy.sparse as sp

__all__ = [
    "read_problem",
    "read_global_problem",
    "read_any",
    "write_problem",
    "write_solution",
    "is_hdf5",
    "is_own_solution",
    "solution_source",
    "file_key",
    "SOLUTION_OF",
]

#: Root attribute of a solution file written with ``write_solution(..., source=...)``.
SOLUTION_OF = "contactqp_solution_of"

_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _h5py():
    return require("h5py", "reading or writing FCLIB HDF5 files", "hdf5")


def is_hdf5(path: str | os.PathLike[str]) -> bool:
    """Tell whether ``path`` starts with the HDF5 signature (also after a user block).

    The signature is looked for at byte 0 and at 512, 1024, 2048, ... as the HDF5
    specification allows. Returns False for a missing or unreadable file.
    """
    try:
        with open(path, "rb") as fh:
            size = fh.seek(0, os.SEEK_END)
            offset = 0
            while offset + 8 <= size:
                fh.seek(offset)
                if fh.read(8) == _HDF5_SIGNATURE:
                    return True
                offset = 512 if offset == 0 else 2 * offset
    except OSError:
        return False
    return False


def _dataset(group, name):
    obj = group.get(name)
    if obj is None:
        raise FileLayoutError(f"{group.name}/{name} is missing")
    if not hasattr(obj, "shape") or not hasattr(obj, "dtype"):
        raise FileLayoutError(f"{group.name}/{name} is not a dataset")
    return obj


def _int(group, name):
    arr = np.asarray(_dataset(group, name)[()])
    if arr.size != 1 or arr.dtype.kind not in "iu":
        raise FileLayoutError(
            f"{group.name}/{name} must hold one integer, got {arr.dtype} {arr.shape}"
        )
    return int(arr.reshape(-1)[0])


def _vector(group, name, length=None, dtype=float):
    arr = np.asarray(_dataset(group, name)[()])
    if arr.dtype.kind not in "iuf":
        raise FileLayoutError(f"{group.name}/{name} is not numeric ({arr.dtype})")
    arr = arr.reshape(-1).astype(dtype, copy=False)
    if length is not None and arr.shape[0] < length:
        raise FileLayoutError(
            f"{group.name}/{name} has {arr.shape[0]} values, at least {length} expected"
        )
    return arr if length is None else arr[:length]


def _text(group, name):
    obj = group.get(name)
    if obj is None or not hasattr(obj, "dtype"):
        return ""
    value = obj[()]
    if isinstance(value, np.ndarray):
        value = value.reshape(-1)[0] if value.size else b""
    if isinstance(value, bytes | np.bytes_):
        value = bytes(value).rstrip(b"\0").decode("utf-8", errors="replace")
    return str(value).strip()


def _read_matrix(group):
    """Read a CSparse-style matrix group into a csr_matrix."""
    import scipy.sparse as sp

    m, n, nz = _int(group, "m"), _int(group, "n"), _int(group, "nz")
    where = group.name
    if m < 0 or n < 0:
        raise FileLayoutError(f"{where}: negative size {m}x{n}")
    if nz in (-1, -2):
        outer, inner = (m, n) if nz == -2 else (n, m)
        p = _vector(group, "p", outer + 1, np.int64)
        nnz = int(p[-1])
        if p[0] != 0 or np.any(np.diff(p) < 0):
            raise FileLayoutError(f"{where}/p is not a valid pointer array")
        idx = _vector(group, "i", nnz, np.int64)
        x = _vector(group, "x", nnz)
        if nnz and (idx.min() < 0 or idx.max() >= inner):
            raise FileLayoutError(f"{where}/i has indices outside [0, {inner})")
        cls = sp.csr_matrix if nz == -2 else sp.csc_matrix
        return sp.csr_matrix(cls((x, idx, p), shape=(m, n)))
    if nz < -2:
        raise FileLayoutError(
            f"{where}/nz = {nz} is not a known storage (-2 CSR, -1 CSC, >= 0 triplets)"
        )
    rows = _vector(group, "i", nz, np.int64)
    cols = _vector(group, "p", nz, np.int64)
    x = _vector(group, "x", nz)

    def fits(r, c):
        return nz == 0 or (r.min() >= 0 and c.min() >= 0 and r.max() < m and c.max() < n)

    if not fits(rows, cols):
        if fits(cols, rows):  # the other convention: p rows, i columns
            rows, cols = cols, rows
        else:
            raise FileLayoutError(f"{where}: triplet indices do not fit the {m}x{n} matrix")
    return sp.csr_matrix((x, (rows, cols)), shape=(m, n))


#: A local ``W`` of more rows than this (:data:`~contactqp.core.local_problem.DENSE_SIZE`) and
#: at least this full is read as a dense array.
FULL_FILL = 2 / 3


def _dense_if_full(W: sp.csr_matrix) -> sp.csr_matrix | np.ndarray:
    """``W`` as a dense array when it is large and nearly full (:data:`FULL_FILL`), else as read.

    At that fill the array takes no more memory than the compressed rows (8 bytes an entry
    against 8 + 4), and every product, diagonal and block of it is read at memory speed
    without index arithmetic. Small matrices keep their sparse form.
    """
    m, n = W.shape
    if m == n and m > DENSE_SIZE and W.nnz >= FULL_FILL * m * n:
        return W.toarray()
    return W


def _read_hdf5(path):
    """Return a LocalProblem or GlobalProblem from an FCLIB HDF5 file."""
    h5py = _h5py()
    try:
        with h5py.File(path, "r") as fh:
            if "fclib_local" in fh:
                g = fh["fclib_local"]
                dim = _int(g, "spacedim")
                W = _dense_if_full(_read_matrix(_group(g, "W")))
                vec = _group(g, "vectors")
                q = _vector(vec, "q")
                mu = _vector(vec, "mu")
                title = _text(g["info"], "title") if "info" in g else ""
                return LocalProblem(W, q, mu, dim, title)
            if "fclib_global" in fh:
                g = fh["fclib_global"]
                dim = _int(g, "spacedim")
                M = _read_matrix(_group(g, "M"))
                H = _read_matrix(_group(g, "H"))
                vec = _group(g, "vectors")
                f = _vector(vec, "f")
                w = _vector(vec, "w")
                mu = _vector(vec, "mu")
                title = _text(g["info"], "title") if "info" in g else ""
                return GlobalProblem(M, H, f, w, mu, dim, title)
            raise FileLayoutError("has neither /fclib_local nor /fclib_global")
    except FileLayoutError as exc:
        raise FileFormatError(f"{path}: {exc}") from None
    except ContactError as exc:
        raise FileFormatError(f"{path}: {exc}") from None
    except (OSError, KeyError, ValueError, TypeError, RuntimeError) as exc:
        msg = " ".join(str(exc).split()) or type(exc).__name__
        raise FileFormatError(
            f"{path}: unreadable HDF5 file (truncated or corrupt?): {msg}"
        ) from None


def _group(parent, name):
    obj = parent.get(name)
    if obj is None or not hasattr(obj, "keys"):
        raise FileLayoutError(f"{parent.name.rstrip('/')}/{name} is missing or not a group")
    return obj


#: Suffixes that promise an HDF5 file: a failure to read such a file as text says so.
HDF5_SUFFIXES = (".hdf5", ".h5", ".hdf")


def read_any(path: str | os.PathLike[str]) -> LocalProblem | GlobalProblem:
    """Read a problem file as written: a :class:`LocalProblem` or an uncondensed
    :class:`GlobalProblem` (formats and errors as :func:`read_problem`)."""
    p = Path(os.fspath(path))
    if not p.exists():
        raise FileFormatError(f"{p}: no such file")
    if not p.is_file():
        raise FileFormatError(f"{p}: not a regular file")
    if is_hdf5(p):
        return _read_hdf5(p)
    try:
        return read_dat(p)
    except FileFormatError as exc:
        if p.suffix.lower() not in HDF5_SUFFIXES:
            raise
        raise FileFormatError(
            f"{p}: neither an HDF5 file (no HDF5 signature) nor a Siconos "
            f"text problem ({str(exc).removeprefix(f'{p}: ')})"
        ) from None


def read_problem(path: str | os.PathLike[str]) -> LocalProblem:
    """Read a frictional-contact problem as a local problem.

    The format is found from the content: a file with the HDF5 signature is read as FCLIB
    (``/fclib_local``, or ``/fclib_global`` condensed, as given, with
    :func:`~contactqp.core.local_problem.condense_global`; :func:`read_any` keeps it global, for
    :func:`~contactqp.solve` to certify on the global equations), anything else as a Siconos
    ``.dat`` text file (see :mod:`contactqp.io.siconos`).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    LocalProblem
        ``W`` is a ``csr_matrix``, except for ``.dat`` files in dense storage and HDF5 files
        whose ``W`` has more than 200 rows and is at least two-thirds full (ndarray).

    Raises
    ------
    FileFormatError
        Missing file, neither HDF5 nor a parseable ``.dat``, HDF5 without FCLIB groups,
        truncated or corrupt HDF5, inconsistent sizes or invalid values; the message is
        one line naming the file.
    MissingDependencyError
        If the file is HDF5 and h5py is not installed.
    NotPositiveDefiniteError
        If a global problem's ``M`` is singular.
    """
    problem = read_any(path)
    if isinstance(problem, GlobalProblem):
        try:
            return problem.condense()
        except ContactError as exc:
            raise type(exc)(f"{Path(os.fspath(path))}: {exc}") from None
    return problem


def read_global_problem(path: str | os.PathLike[str]) -> GlobalProblem:
    """Read a global problem (``/fclib_global`` or a global ``.dat``) without condensing it.

    Raises
    ------
    FileFormatError
        As :func:`read_problem`, and if the file holds a local problem.
    """
    problem = read_any(path)
    if not isinstance(problem, GlobalProblem):
        raise FileFormatError(f"{Path(os.fspath(path))}: holds a local problem, not a global one")
    return problem


def _create(fh, name, data):
    fh.create_dataset(name, data=data)


def write_problem(path: str | os.PathLike[str], problem: LocalProblem) -> None:
    """Write a local problem as an FCLIB HDF5 file (created or overwritten).

    ``W`` is stored in compressed rows (``nz = -2``) with int32 indices, as FCLIB does; a
    dense ``W`` is stored with its zeros dropped, a sparse one with its stored entries
    (explicit zeros included). :func:`read_problem` gives back the same values exactly.

    Parameters
    ----------
    path : str or os.PathLike
    problem : LocalProblem

    Raises
    ------
    MissingDependencyError
        If h5py is not installed.
    FileFormatError
        If the file cannot be written.
    UnsupportedProblemError
        If the problem has cohesion, which FCLIB cannot store.
    """
    if not isinstance(problem, LocalProblem):
        raise TypeError(f"problem must be a LocalProblem, got {type(problem).__name__}")
    if problem.cohesion is not None and np.any(problem.cohesion > 0):
        raise UnsupportedProblemError(
            f"{path}: FCLIB has no field for cohesion; the problem's Mohr-Coulomb cohesion "
            f"would be lost"
        )
    import scipy.sparse as sp

    h5py = _h5py()
    W = sp.csr_matrix(problem.W, copy=True)
    W.sort_indices()
    if W.nnz > np.iinfo(np.int32).max:
        raise FileFormatError(f"{path}: W has too many entries for int32 indices")
    p = Path(os.fspath(path))
    try:
        with h5py.File(p, "w") as fh:
            g = fh.create_group("fclib_local")
            gw = g.create_group("W")
            m, n = W.shape
            for key, value in (("m", m), ("n", n), ("nz", -2), ("nzmax", W.nnz)):
                _create(gw, key, np.array([value], dtype=np.int32))
            _create(gw, "p", W.indptr.astype(np.int32))
            _create(gw, "i", W.indices.astype(np.int32))
            _create(gw, "x", W.data.astype(np.float64))
            vec = g.create_group("vectors")
            _create(vec, "q", problem.q.astype(np.float64))
            _create(vec, "mu", problem.mu.astype(np.float64))
            _create(g, "spacedim", np.array([problem.dim], dtype=np.int32))
            info = g.create_group("info")
            _create(info, "title", np.bytes_(problem.title.encode("utf-8")))
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot be written ({exc})") from None


def solution_source(path: str | os.PathLike[str]) -> str | None:
    """The input a solution file was written for (:data:`SOLUTION_OF`), or None.

    None unless ``path`` is an HDF5 file holding only ``/solution`` and marked by
    ``write_solution(..., source=...)``.
    """
    if not is_hdf5(path):
        return None
    try:
        with _h5py().File(path, "r") as fh:
            if SOLUTION_OF not in fh.attrs or not set(fh.keys()) <= {"solution"}:
                return None
            value = fh.attrs[SOLUTION_OF]
    except OSError:
        return None
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


def is_own_solution(
    path: str | os.PathLike[str], source: str | os.PathLike[str] | None = None
) -> bool:
    """True if ``path`` is a solution file written by ``write_solution(..., source=...)``.

    With ``source``, only if it was written for that input (compared as real paths).
    """
    written_for = solution_source(path)
    if written_for is None or source is None:
        return written_for is not None
    return file_key(written_for) == file_key(source)


def file_key(path: str | os.PathLike[str]) -> str:
    """``path`` as the real, case-normalised path: equal for two names of one file."""
    return os.path.normcase(os.path.realpath(path))


def write_solution(
    path: str | os.PathLike[str],
    r: ArrayLike,
    u: ArrayLike,
    v: ArrayLike | None = None,
    *,
    source: str | os.PathLike[str] | None = None,
) -> None:
    """Store a solution as ``/solution/{r,u[,v]}`` in an HDF5 file.

    Without ``source``: a missing file is created; an existing HDF5 file (e.g. the problem
    file) is opened for appending and its ``/solution`` group, if any, is replaced; everything
    else is kept. With ``source`` (the input's path): a solution file of its own is written,
    marked with the root attribute :data:`SOLUTION_OF` (the input's real path); an existing file
    is replaced only if it is such a file written for the same input
    (:func:`is_own_solution`), never any other.

    Parameters
    ----------
    path : str or os.PathLike
    r, u : array_like, shape (m,)
        Reactions and relative velocities.
    v : array_like, shape (ndof,), optional
        Global velocities, for global problems.
    source : str or os.PathLike, optional
        The problem file solved.

    Raises
    ------
    FileFormatError
        If ``path`` exists but is not HDF5 (or, with ``source``, not the solution file of that
        input), or cannot be written.
    InvalidInputError
        If ``r`` and ``u`` are not 1-D arrays of the same length.
    """
    given = {"r": r, "u": u} if v is None else {"r": r, "u": u, "v": v}
    arrays: dict[str, np.ndarray] = {}
    for key, value in given.items():
        arr = np.asarray(value, dtype=float)
        if arr.ndim != 1:
            raise InvalidInputError(f"{key} must be 1-D, got shape {arr.shape}")
        arrays[key] = arr
    if arrays["r"].shape != arrays["u"].shape:
        raise InvalidInputError(
            f"r and u must have the same length, got {arrays['r'].shape} and {arrays['u'].shape}"
        )
    h5py = _h5py()
    p = Path(os.fspath(path))
    if p.exists() and not is_hdf5(p):
        raise FileFormatError(f"{p}: exists and is not an HDF5 file")
    if source is not None and p.exists() and not is_own_solution(p, source):
        raise FileFormatError(
            f"{p}: exists and is not the solution file of {source} written by "
            f"contactqp; not overwritten"
        )
    try:
        with h5py.File(p, "a" if source is None else "w") as fh:
            if source is not None:
                fh.attrs[SOLUTION_OF] = os.path.realpath(source)
            if "solution" in fh:
                del fh["solution"]
            g = fh.create_group("solution")
            for key, arr in arrays.items():
                _create(g, key, arr)
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot be written ({' '.join(str(exc).split())})") from None

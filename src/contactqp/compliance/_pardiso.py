"""Sparse Cholesky factorisation of a symmetric positive definite stiffness by MKL Pardiso.

:class:`PardisoCholesky` has the part of :class:`scipy.sparse.linalg.SuperLU` the sparse
operators use (``solve(b)`` for ``b`` of shape (n,) or (n, k), and ``nnz``). It calls MKL's
``pardiso`` through :mod:`ctypes` (the ``mkl`` wheel ships ``libmkl_rt``; no compiler needed):
matrix type 2 (real symmetric positive definite), METIS nested-dissection ordering, the upper
triangle in zero-based CSR, kept between the calls. A thin binding of its own rather than
pypardiso's: pypardiso hashes the matrix (SHA-1 of its arrays) and copies its indices at every
solve, which doubled the time of one solve at 202,248 freedoms (0.25 s against 0.13 s).

Checks, the same as :func:`~contactqp.compliance.condensation.factorize`'s: the diagonal and the
symmetry of ``K`` before (by its helper), and after the factorisation every pivot (Pardiso's
``pardiso_getdiag``, in the elimination order Pardiso returns) against its own diagonal entry:
below ``pivot_rtol`` is a rigid-body mode. A pivot that is not positive stops Pardiso (error -4);
SuperLU then factorises ``K`` once more to name the freedom and the kind of failure (a singular
model or an indefinite one), so the errors are those of the SuperLU route.

MKL's threads follow ``MKL_NUM_THREADS`` (or :mod:`threadpoolctl`). One factor is not re-entrant:
a lock serialises the solves of several threads.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import glob
import os
import sys
import threading
import weakref
from collections.abc import Sequence
from functools import cache

import numpy as np
import scipy.sparse as sp

from ..errors import NotPositiveDefiniteError, RigidBodyModeError, UnsupportedProblemError
from ..optional import require
from .condensation import factorize

__all__ = ["PardisoCholesky", "pardiso_installed"]

_REAL_SPD = 2  # Pardiso's matrix type
_INT = ctypes.POINTER(ctypes.c_int32)
_DOUBLE = ctypes.POINTER(ctypes.c_double)
_HANDLE = ctypes.POINTER(ctypes.c_int64)


@cache
def _library() -> ctypes.CDLL | None:
    """``libmkl_rt`` of the ``mkl`` wheel (or of the system), None when absent."""
    candidates = sorted(glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*")), key=len)
    found = ctypes.util.find_library("mkl_rt")
    for path in candidates + ([found] if found else []):
        try:
            library = ctypes.CDLL(path)
        except OSError:
            continue
        library.pardiso.restype = None
        library.pardiso_getdiag.restype = None
        # 32-bit integers (LP64), whatever MKL_INTERFACE_LAYER says: the binding passes int32
        library.MKL_Set_Interface_Layer(0)
        return library
    return None


def pardiso_installed() -> bool:
    """Whether MKL (the ``mkl`` package, or a system ``libmkl_rt``) can be loaded."""
    return _library() is not None


def _int(value: int):
    return ctypes.byref(ctypes.c_int32(value))


def _pardiso(library, handle, iparm, phase: int, matrix, order, b, x) -> int:
    """One call of ``pardiso`` (type 2) on ``matrix = (data, indptr, indices)``: its error."""
    data, indptr, indices = matrix
    error = ctypes.c_int32(0)
    library.pardiso(
        handle.ctypes.data_as(_HANDLE),
        _int(1),  # maxfct
        _int(1),  # mnum
        _int(_REAL_SPD),
        _int(phase),
        _int(indptr.size - 1),
        data.ctypes.data_as(_DOUBLE),
        indptr.ctypes.data_as(_INT),
        indices.ctypes.data_as(_INT),
        order.ctypes.data_as(_INT),
        _int(1 if b.ndim == 1 else b.shape[1]),
        iparm.ctypes.data_as(_INT),
        _int(0),  # no messages
        b.ctypes.data_as(_DOUBLE),
        x.ctypes.data_as(_DOUBLE),
        ctypes.byref(error),
    )
    return int(error.value)


class PardisoCholesky:
    """``K = L L^T`` by MKL Pardiso, for ``K`` checked symmetric with a positive diagonal.

    Parameters
    ----------
    K : scipy.sparse.csc_matrix, shape (n, n)
        The stiffness, checked by the caller (finite, square, symmetric, positive diagonal).
    labels : sequence of str, optional
        Names of the ``n`` freedoms, for the errors.
    pivot_rtol : float
        A pivot below ``pivot_rtol`` times its diagonal entry is taken for a rigid-body mode.

    Attributes
    ----------
    nnz : int
        Stored entries of ``L`` (its memory is about 8 bytes each).

    Raises
    ------
    RigidBodyModeError, NotPositiveDefiniteError
        ``K`` singular (a vanishing pivot) or indefinite.
    MissingDependencyError
        MKL is not installed.
    UnsupportedProblemError
        ``K`` has 2**31 stored entries or more (Pardiso's 32-bit interface).
    """

    def __init__(
        self, K: sp.csc_matrix, *, labels: Sequence[str] | None, pivot_rtol: float
    ) -> None:
        library = _library()
        if library is None:  # names the extra to install
            require("mkl_rt", "the Pardiso factorisation", "sparse", distribution="mkl")
        self._library = library
        self.n = n = K.shape[0]
        if K.nnz >= 2**31:  # the 32-bit interface
            raise UnsupportedProblemError(
                f"the Pardiso factorisation takes fewer than 2**31 stored entries, got {K.nnz}"
            )
        upper = sp.triu(K, format="csr")
        upper.sort_indices()
        self._matrix = (
            np.ascontiguousarray(upper.data, dtype=float),
            upper.indptr.astype(np.int32),
            upper.indices.astype(np.int32),
        )
        self._handle = np.zeros(64, dtype=np.int64)
        self._iparm = np.zeros(64, dtype=np.int32)
        # 1-based numbering of the manual: iparm(1) = 1 own values, (2) = 2 METIS ordering,
        # (5) = 2 return the ordering, (18) = -1 report nnz(L), (35) = 1 zero-based indices,
        # (56) = 1 keep the pivots for pardiso_getdiag
        for position, value in ((1, 1), (2, 2), (5, 2), (18, -1), (35, 1), (56, 1)):
            self._iparm[position - 1] = value
        self._order = np.zeros(n, dtype=np.int32)
        self._lock = threading.Lock()
        empty = np.zeros(1)
        # Pardiso's memory is released with the object, or at exit before the modules go
        self._release = weakref.finalize(
            self,
            _pardiso,
            library,
            self._handle,
            self._iparm,
            -1,
            self._matrix,
            self._order,
            empty,
            empty,
        )
        error = self._call(12, np.zeros(n), np.zeros(n))  # analysis and factorisation
        if error:
            self._release()
            if error == -4:  # a pivot <= 0: SuperLU names the freedom and the kind
                self._diagnose(K, labels, pivot_rtol)
            raise RuntimeError(f"MKL Pardiso failed with error {error}")
        self.nnz = int(self._iparm[17])
        try:
            self._check_pivots(K.diagonal(), labels, pivot_rtol)
        except RigidBodyModeError:
            self._release()
            raise

    def _call(self, phase: int, b: np.ndarray, x: np.ndarray) -> int:
        return _pardiso(
            self._library, self._handle, self._iparm, phase, self._matrix, self._order, b, x
        )

    def _diagnose(self, K, labels, pivot_rtol: float):
        factorize(K, labels=labels, pivot_rtol=pivot_rtol, symmetry_rtol=np.inf)
        raise NotPositiveDefiniteError(
            "stiffness is not positive definite: its Cholesky factorisation met a pivot <= 0"
        )

    def _check_pivots(self, diagonal: np.ndarray, labels, pivot_rtol: float) -> None:
        pivots, entries = np.zeros(self.n), np.zeros(self.n)
        error = ctypes.c_int32(0)
        self._library.pardiso_getdiag(  # type: ignore[union-attr]
            self._handle.ctypes.data_as(_HANDLE),
            pivots.ctypes.data_as(_DOUBLE),
            entries.ctypes.data_as(_DOUBLE),
            _int(1),
            ctypes.byref(error),
        )
        if error.value:
            raise RuntimeError(f"MKL pardiso_getdiag failed with error {error.value}")
        ratio = pivots / diagonal[self._order]  # _order[i]: the freedom of the i-th pivot
        weakest = int(np.argmin(ratio))
        if ratio[weakest] < pivot_rtol:
            freedom = int(self._order[weakest])
            name = labels[freedom] if labels is not None else f"freedom {freedom}"
            raise RigidBodyModeError(
                "the stiffness matrix is singular to working precision: the model has "
                "rigid-body modes (add fixations) or is too ill-conditioned to condense "
                f"accurately (pivot {ratio[weakest]:.3g} of the diagonal at {name})"
            )

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``K^-1 b`` for ``b`` of shape (n,) or (n, k)."""
        b = np.asfortranarray(b, dtype=float)
        x = np.empty_like(b, order="F")
        with self._lock:
            error = self._call(33, b, x)
        if error:
            raise RuntimeError(f"MKL Pardiso's solve failed with error {error}")
        return x

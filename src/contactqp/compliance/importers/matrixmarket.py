"""MatrixMarket files (``.mtx``, ``.mtx.gz``) of a stiffness or a flexibility matrix."""

from __future__ import annotations

import numpy as np
import scipy.io
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ...core.model import SYMMETRY_RTOL, ReducedModel
from ...errors import FileFormatError, InvalidInputError
from ._common import DofsPerNode, Matrix, StrPath, about, existing_file, one_line, reduced_model

__all__ = ["read_matrix_market", "mtx_matrix"]


def read_matrix_market(
    path: StrPath,
    *,
    kind: str,
    freedoms: ArrayLike | None = None,
    fixed: ArrayLike | None = None,
    dofs_per_node: DofsPerNode = 1,
    symmetry_rtol: float = SYMMETRY_RTOL,
) -> ReducedModel:
    """Reduced model from a MatrixMarket file (coordinate or array, ``symmetric`` included).

    Parameters
    ----------
    path : str or os.PathLike
    kind : {"stiffness", "flexibility"}
        What the matrix is.
    freedoms : sequence of int, optional
        Rows (from 0) of the computational freedoms, in the model's order; default: every row not
        fixed. A stiffness is condensed to them (one sparse factorisation), a flexibility cut.
    fixed : sequence of int, optional
        Rows of a stiffness that are clamped.
    dofs_per_node : int or sequence of int
        Freedoms of each computational node (see :class:`~contactqp.core.model.ReducedModel`).
    symmetry_rtol : float
        See :func:`~contactqp.core.model.check_spd_matrix`.

    Returns
    -------
    ReducedModel
        Given as the stiffness when every free row is kept, as a flexibility otherwise.

    Raises
    ------
    FileFormatError
        Missing or unreadable file, or not MatrixMarket.
    InvalidInputError
        Complex, non-square or non-finite matrix, bad indices.
    NotPositiveDefiniteError
        The (reduced) matrix is not positive definite (:class:`RigidBodyModeError` for a
        stiffness with rigid-body modes).
    """
    path = existing_file(path)
    matrix: Matrix = mtx_matrix(path)
    with about(path):
        return reduced_model(
            matrix, kind, freedoms, fixed, dofs_per_node=dofs_per_node, symmetry_rtol=symmetry_rtol
        )


def mtx_matrix(path: StrPath) -> Matrix:
    """The matrix of a MatrixMarket file (coordinate or array, ``symmetric`` storage included).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    ndarray or scipy.sparse matrix
        Real, float64, as stored (a coordinate file stays sparse).

    Raises
    ------
    FileFormatError
        Missing or unreadable file, or not MatrixMarket.
    InvalidInputError
        A complex matrix.
    """
    path = existing_file(path)
    try:
        read = scipy.io.mmread(str(path))
    except (OSError, ValueError, EOFError, UnicodeDecodeError, IndexError) as exc:
        raise FileFormatError(
            f"{path}: not a readable MatrixMarket file: {one_line(exc)}"
        ) from None
    if np.iscomplexobj(read.data if sp.issparse(read) else read):
        raise InvalidInputError(f"{path}: the matrix is complex; a real matrix is needed")
    return read.astype(float) if isinstance(read, np.ndarray) else sp.csc_matrix(read, dtype=float)

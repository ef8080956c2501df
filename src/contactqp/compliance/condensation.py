"""Static condensation: the flexibility of chosen freedoms from a sparse stiffness matrix.

One sparse LU factorisation of ``K`` (SuperLU, symmetric ordering) and one solve with as many
right-hand sides as chosen freedoms give the columns ``K^-1 e_j``; their rows at the chosen
freedoms are the flexibility ``R``. This is the unit-load procedure of the method done in one
factorisation instead of one finite-element analysis per unit load.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import InvalidInputError, NotPositiveDefiniteError

__all__ = ["condense", "RigidBodyModeError"]

#: Pivots smaller than this fraction of the largest diagonal stiffness mean a singular model.
SINGULAR_PIVOT_RTOL = 1e-10


class RigidBodyModeError(NotPositiveDefiniteError):
    """The stiffness matrix is singular: the model can move without deforming."""


def _checked_stiffness(stiffness) -> sp.csc_matrix:
    if not sp.issparse(stiffness):
        stiffness = np.asarray(stiffness, dtype=float)
    K = sp.csc_matrix(stiffness, dtype=float)
    if K.ndim != 2 or K.shape[0] != K.shape[1] or K.shape[0] == 0:
        raise InvalidInputError(f"stiffness must be a non-empty square matrix, got shape {K.shape}")
    if not np.all(np.isfinite(K.data)):
        raise InvalidInputError("stiffness contains NaN or inf")
    return K


def _checked_freedoms(freedoms, n: int) -> np.ndarray:
    idx = np.asarray(freedoms)
    if idx.ndim != 1 or idx.size == 0 or not np.issubdtype(idx.dtype, np.integer):
        raise InvalidInputError("freedoms must be a non-empty 1-D list of integer freedom indices")
    if idx.min() < 0 or idx.max() >= n:
        raise InvalidInputError(f"freedoms must lie in 0..{n - 1}, got {idx.min()}..{idx.max()}")
    if np.unique(idx).size != idx.size:
        raise InvalidInputError("freedoms contains repeated indices")
    return idx


def condense(stiffness, freedoms, *, labels=None) -> np.ndarray:
    """Flexibility matrix of ``freedoms`` for the (fixed, non-singular) sparse ``stiffness``.

    Parameters
    ----------
    stiffness : sparse or array_like, shape (n, n)
        Symmetric stiffness with the fixations already applied (fixed freedoms removed).
    freedoms : sequence of int, shape (k,)
        Indices of the computational freedoms in ``stiffness``.
    labels : sequence of str, optional
        Names of the ``n`` freedoms, used in the error raised for a singular model.

    Returns
    -------
    numpy.ndarray, shape (k, k)
        ``R[i, j]``: displacement of freedom ``freedoms[i]`` under a unit load on ``freedoms[j]``,
        symmetrised (the asymmetry is round-off of the solve).

    Raises
    ------
    RigidBodyModeError
        When a pivot of the factorisation vanishes: not enough fixations.
    """
    K = _checked_stiffness(stiffness)
    idx = _checked_freedoms(freedoms, K.shape[0])
    scale = float(np.max(np.abs(K.diagonal())))
    try:
        lu = spla.splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
        pivots = np.abs(lu.U.diagonal())
    except RuntimeError:  # SuperLU: "Factor is exactly singular"
        pivots = np.zeros(1)
        lu = None
    if lu is None or scale <= 0 or pivots.min() < SINGULAR_PIVOT_RTOL * scale:
        where = ""
        if lu is not None and scale > 0:
            freedom = int(lu.perm_c[np.argmin(pivots)])
            name = labels[freedom] if labels is not None else f"freedom {freedom}"
            where = f" (smallest pivot {pivots.min():.3g} at {name})"
        raise RigidBodyModeError(
            "the stiffness matrix is singular: the model has rigid-body modes, add fixations"
            + where)
    unit_loads = np.zeros((K.shape[0], idx.size))
    unit_loads[idx, np.arange(idx.size)] = 1.0
    R = lu.solve(unit_loads)[idx]
    return 0.5 * (R + R.T)

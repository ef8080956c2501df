"""Static condensation: the flexibility of chosen freedoms from a sparse stiffness matrix.

One sparse factorisation of ``K`` (SuperLU in symmetric mode: a symmetric fill-reducing ordering
and no pivoting, i.e. ``K = L D L^T`` for a positive definite ``K``) and one solve with as many
right-hand sides as chosen freedoms give the columns ``K^-1 e_j``; their rows at the chosen
freedoms are the flexibility ``R``. This is the unit-load procedure done with one factorisation
instead of one finite-element analysis per unit load.

When the ``k`` solves would cost more than a second factorisation (many chosen freedoms), ``K`` is
factorised again with the chosen freedoms eliminated last (the fill-reducing order of the first
factorisation otherwise kept). The trailing ``k x k`` block of that factorisation is the Schur
complement, the condensed stiffness

.. math::

    S = K_{cc} - K_{cr} K_{rr}^{-1} K_{rc} = L_{cc} U_{cc}, \\qquad R = S^{-1},

and no solve with the sparse factor is needed.

A pivot ``d_j`` of the factorisation is the stiffness of freedom ``j`` when the freedoms eliminated
after it are clamped. It is positive for a positive definite ``K``; it vanishes (up to round-off,
measured as ``d_j / K_jj`` so that the units of each freedom do not matter) when the model can
move without deforming.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike

from ..core.model import SYMMETRY_RTOL
from ..errors import InvalidInputError, NotPositiveDefiniteError, RigidBodyModeError

__all__ = ["condense", "factorize", "SINGULAR_PIVOT_RTOL"]

#: A pivot smaller than this fraction of its own diagonal stiffness means a singular model.
#: Measured on finite-element solids: rigid-body modes leave pivots of 1e-15 to 1e-12 of the
#: diagonal; the softest freedom of a cantilever of ``n`` beam elements leaves ``~ 1 / (4 n^3)``
#: (1.2e-10 at 2,000 elements, where the condensed bending flexibility is already off by 1e-4;
#: 2e-12 at 8,000, where it is off by 10 %), so the test also refuses models too
#: ill-conditioned to condense.
SINGULAR_PIVOT_RTOL = 1e-10


def _checked_stiffness(stiffness) -> sp.csc_matrix:
    if not sp.issparse(stiffness):
        try:
            stiffness = np.asarray(stiffness, dtype=float)
        except (TypeError, ValueError):
            raise InvalidInputError("stiffness must be a square matrix of numbers") from None
        if stiffness.ndim != 2:
            raise InvalidInputError(
                f"stiffness must be a non-empty square matrix, got shape {stiffness.shape}"
            )
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


def _checked_symmetric(
    stiffness, labels: Sequence[str] | None, symmetry_rtol: float
) -> tuple[sp.csc_matrix, np.ndarray]:
    """The checks before a factorisation of :func:`factorize`: ``(K, diagonal of K)``.

    Raises :class:`RigidBodyModeError` (a zero diagonal entry), :class:`NotPositiveDefiniteError`
    (a negative one) or :class:`InvalidInputError` (bad labels, ``K`` not symmetric).
    """
    K = _checked_stiffness(stiffness)
    if labels is not None and len(labels) != K.shape[0]:
        raise InvalidInputError(f"labels must name the {K.shape[0]} freedoms, got {len(labels)}")
    diagonal = K.diagonal()

    def label(freedom: int) -> str:
        return labels[freedom] if labels is not None else f"freedom {freedom}"

    if np.any(diagonal <= 0):
        freedom = int(np.argmin(diagonal))
        if diagonal[freedom] == 0:
            raise RigidBodyModeError(
                f"the stiffness matrix is singular: {label(freedom)} has no "
                "stiffness (unconnected), fix or remove it"
            )
        raise NotPositiveDefiniteError(
            f"stiffness is not positive definite: negative diagonal "
            f"{diagonal[freedom]:.3g} at {label(freedom)}"
        )
    scale = sp.diags(1.0 / np.sqrt(diagonal))
    asymmetry = (scale @ abs(K - K.T) @ scale).tocoo()
    if asymmetry.nnz and asymmetry.data.max() > symmetry_rtol:
        worst = int(np.argmax(asymmetry.data))
        i, j = int(asymmetry.row[worst]), int(asymmetry.col[worst])
        raise InvalidInputError(
            f"the stiffness is not symmetric: |K_ij - K_ji| / sqrt(K_ii K_jj) = "
            f"{asymmetry.data[worst]:.3g} > {symmetry_rtol:g} between {label(i)} and {label(j)}"
        )
    return K, diagonal


def factorize(
    stiffness: ArrayLike | sp.spmatrix | sp.sparray,
    *,
    labels: Sequence[str] | None = None,
    pivot_rtol: float = SINGULAR_PIVOT_RTOL,
    symmetry_rtol: float = SYMMETRY_RTOL,
) -> spla.SuperLU:
    """Factorise a symmetric positive definite sparse stiffness, refusing singular ones.

    Parameters
    ----------
    stiffness : sparse or array_like, shape (n, n)
        Symmetric stiffness (N/m for translations) with the fixations applied.
    labels : sequence of str, optional
        Names of the ``n`` freedoms, used in the error messages.
    pivot_rtol : float
        A pivot below ``pivot_rtol`` times its diagonal entry is taken for a rigid-body mode.
    symmetry_rtol : float
        Largest accepted ``|K_ij - K_ji| / sqrt(K_ii K_jj)`` (independent of the units of each
        freedom); the factorisation uses one triangle only, so an unsymmetric ``K`` would give
        the flexibility of another matrix.

    Returns
    -------
    scipy.sparse.linalg.SuperLU
        The factorisation; ``.solve(b)`` gives ``K^-1 b`` for ``b`` of shape (n,) or (n, m).

    Raises
    ------
    RigidBodyModeError
        A vanishing pivot: not enough fixations (the message names the freedom).
    NotPositiveDefiniteError
        A negative pivot: the stiffness is indefinite.
    InvalidInputError
        The stiffness is not symmetric.
    """
    K, diagonal = _checked_symmetric(stiffness, labels, symmetry_rtol)

    def label(freedom: int) -> str:
        return labels[freedom] if labels is not None else f"freedom {freedom}"

    try:
        lu = spla.splu(
            K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True}
        )
    except RuntimeError:  # SuperLU: "Factor is exactly singular"
        raise RigidBodyModeError(
            "the stiffness matrix is singular: the model has rigid-body "
            "modes, add fixations (a pivot is exactly zero)"
        ) from None

    if not np.array_equal(lu.perm_r, lu.perm_c):
        raise NotPositiveDefiniteError(
            "stiffness is not positive definite: its factorisation needed row pivoting"
        )
    eliminated = np.argsort(lu.perm_c)  # perm_c[i] is the position of freedom i in the factor

    def name(column: int) -> str:
        return label(int(eliminated[column]))

    pivots = lu.U.diagonal()
    ratio = pivots / diagonal[eliminated]
    weakest = int(np.argmin(ratio))
    if ratio[weakest] < -pivot_rtol:
        raise NotPositiveDefiniteError(
            f"stiffness is not positive definite: negative pivot {pivots[weakest]:.3g} "
            f"at {name(weakest)}"
        )
    if ratio[weakest] < pivot_rtol:
        raise RigidBodyModeError(
            "the stiffness matrix is singular to working precision: the model has rigid-body "
            "modes (add fixations) or is too ill-conditioned to condense accurately, e.g. a very "
            f"fine mesh of slender beams (pivot {ratio[weakest]:.3g} of the diagonal at "
            f"{name(weakest)})"
        )
    return lu


def condense(
    stiffness: ArrayLike | sp.spmatrix | sp.sparray,
    freedoms: ArrayLike,
    *,
    labels: Sequence[str] | None = None,
    pivot_rtol: float = SINGULAR_PIVOT_RTOL,
    symmetry_rtol: float = SYMMETRY_RTOL,
) -> np.ndarray:
    """Flexibility matrix of ``freedoms`` for the (fixed, non-singular) sparse ``stiffness``.

    Parameters
    ----------
    stiffness : sparse or array_like, shape (n, n)
        Symmetric stiffness with the fixations already applied (fixed freedoms removed).
    freedoms : sequence of int, shape (k,)
        Indices of the computational freedoms in ``stiffness``.
    labels : sequence of str, optional
        Names of the ``n`` freedoms, used in the error raised for a singular model.
    pivot_rtol, symmetry_rtol : float
        See :func:`factorize`.

    Returns
    -------
    numpy.ndarray, shape (k, k)
        ``R[i, j]``: displacement of freedom ``freedoms[i]`` under a unit load on ``freedoms[j]``,
        symmetrised (the asymmetry is round-off of the solve).

    Raises
    ------
    RigidBodyModeError
        When a pivot of the factorisation vanishes: not enough fixations.
    NotPositiveDefiniteError
        When a pivot is negative.
    InvalidInputError
        Bad freedoms, or a stiffness that is not symmetric.
    """
    K = _checked_stiffness(stiffness)
    idx = _checked_freedoms(freedoms, K.shape[0])
    lu = factorize(K, labels=labels, pivot_rtol=pivot_rtol, symmetry_rtol=symmetry_rtol)
    R = _by_schur_complement(K, lu, idx) if _schur_pays(lu, idx.size) else None
    if R is None:
        R = _by_solves(lu, idx)
    return 0.5 * (R + R.T)


def _schur_pays(lu, k: int) -> bool:
    """Whether ``k`` solves (``2 nnz(L + U)`` flops each) cost more than one factorisation.

    A factorisation costs ``2 sum c_j^2`` flops (``c_j``: off-diagonal entries of column ``j`` of
    ``L``) plus its copies and symbolic work, counted as ten passes over the factor.
    """
    nnz = float(lu.L.nnz + lu.U.nnz)
    off_diagonal = np.diff(lu.L.indptr).astype(float) - 1.0
    return 2.0 * nnz * k > 2.0 * np.sum(off_diagonal**2) + 10.0 * nnz


def _by_solves(lu, idx: np.ndarray) -> np.ndarray:
    """Rows ``idx`` of ``K^-1 e_j`` for each chosen freedom ``j``: one multi-column solve."""
    unit_loads = np.zeros((lu.shape[0], idx.size))
    unit_loads[idx, np.arange(idx.size)] = 1.0
    return lu.solve(unit_loads)[idx]


def _by_schur_complement(K: sp.csc_matrix, lu, idx: np.ndarray) -> np.ndarray | None:
    """``S^-1`` from a factorisation with the chosen freedoms last; None if SuperLU reorders."""
    n, k = K.shape[0], idx.size
    elimination = np.argsort(lu.perm_c)
    chosen = np.zeros(n, dtype=bool)
    chosen[idx] = True
    order = np.concatenate([elimination[~chosen[elimination]], idx])
    try:
        last = spla.splu(
            K[order][:, order].tocsc(),
            permc_spec="NATURAL",
            diag_pivot_thresh=0.0,
            options={"SymmetricMode": True},
        )
    except RuntimeError:  # "Factor is exactly singular" in this elimination order
        raise _ill_conditioned() from None
    if not (
        np.array_equal(last.perm_c[n - k :], np.arange(n - k, n))
        and np.array_equal(last.perm_r, last.perm_c)
    ):
        return None  # the chosen freedoms were not eliminated last
    S = (last.L[n - k :, n - k :] @ last.U[n - k :, n - k :]).toarray()
    try:
        factor = scipy.linalg.cho_factor(0.5 * (S + S.T), lower=True, check_finite=False)
    except np.linalg.LinAlgError:
        raise _ill_conditioned() from None
    return scipy.linalg.cho_solve(factor, np.eye(k), check_finite=False)


def _ill_conditioned() -> NotPositiveDefiniteError:
    return NotPositiveDefiniteError(
        "the condensed stiffness of the chosen freedoms is not positive definite in floating "
        "point: the model is too ill-conditioned (raise pivot_rtol to refuse it earlier)"
    )

"""Reduced models: computational nodes and the compliance (or stiffness) linking their freedoms.

A reduced model replaces a body, or an assembly, by its linear response at a few computational nodes
in the zone where contact may occur: ``U = R P`` with ``R`` the flexibility (compliance) matrix, or
``P = K U`` with ``K = R^{-1}`` the rigidity (stiffness) matrix.
"""

from __future__ import annotations

import math
import numbers
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidInputError, NotPositiveDefiniteError, SymmetrizedWarning

__all__ = [
    "ReducedModel",
    "UnitLoadCompliance",
    "unit_load_compliance",
    "check_spd_matrix",
    "checked_cholesky",
    "checked_matrix",
    "cholesky_factor",
    "finite_array",
    "warm_start",
    "real_array",
    "positive_tolerance",
    "iteration_cap",
    "true_or_false",
    "MAX_MAGNITUDE",
]

#: Relative asymmetry ``max|M - M^T| / max|M|`` below which a matrix is symmetrised (with a
#: warning) instead of refused.
SYMMETRY_RTOL = 1e-6


#: Largest magnitude accepted in a matrix, a load or a gap (and the inverse of the smallest
#: accepted matrix scale): products of several such numbers (an energy is a compliance times two
#: forces), even through an ill-conditioned inverse, stay far from overflow (1.8e308), and no
#: physical quantity in any unit system comes near it.
MAX_MAGNITUDE = 1e50


def real_array(value: ArrayLike, name: str) -> np.ndarray:
    """``value`` as a float array; complex values and non-numbers are refused, naming ``name``."""
    if _is_complex(value):
        raise InvalidInputError(f"{name} must be real, got complex values")
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{name} must be an array of real numbers: {exc}") from None


def finite_array(
    value: ArrayLike, name: str, ndim: int, *, magnitude: float | None = None
) -> np.ndarray:
    """``value`` as a float array of ``ndim`` dimensions, real and finite; errors name ``name``.

    ``magnitude``: also refuse entries larger in absolute value (see :data:`MAX_MAGNITUDE`).
    """
    if type(value) is np.ndarray and value.dtype == np.float64:
        array = value  # the common case: no casts (a microsecond each on small problems)
    else:
        array = real_array(value, name)
    if array.ndim != ndim:
        raise InvalidInputError(f"{name} must be {ndim}-D, got shape {array.shape}")
    if not np.isfinite(array).all():
        raise InvalidInputError(f"{name} contains NaN or inf (shape {array.shape})")
    if magnitude is not None and array.size and np.max(np.abs(array)) > magnitude:
        raise InvalidInputError(
            f"{name} has an entry of magnitude {np.max(np.abs(array)):.3g}, beyond {magnitude:g}: "
            f"its products with forces and displacements would overflow; rescale the units"
        )
    return array


def warm_start(r0: ArrayLike, size: int, name: str = "r0") -> np.ndarray:
    """A method's warm start as a real, finite, 1-D float array of shape ``(size,)``; errors name
    ``name``."""
    start = finite_array(r0, name, 1)
    if start.shape != (size,):
        raise InvalidInputError(f"{name} must have shape ({size},), got {start.shape}")
    return start


def _is_complex(value: ArrayLike) -> bool:
    """True when ``value`` holds complex numbers (which a cast to float would truncate)."""
    if isinstance(value, np.ndarray) or hasattr(value, "dtype"):
        return bool(np.iscomplexobj(value))
    try:
        return bool(np.iscomplexobj(np.asarray(value)))
    except (TypeError, ValueError):  # ragged or not numbers: the float cast reports it
        return False


def positive_tolerance(value: object, name: str = "tol", *, below_one: bool = False) -> float:
    """``value`` as a float, refused unless a finite number > 0 (and < 1 with ``below_one``)."""
    number = None
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        number = float(value)
    if number is None or not math.isfinite(number) or number <= 0 or (below_one and number >= 1):
        raise InvalidInputError(
            f"{name} must be a positive finite number"
            f"{' below 1' if below_one else ''}, got {value!r}"
        )
    return number


def iteration_cap(value: object, name: str = "max_iter") -> int:
    """``value`` as an int, refused unless an integer >= 1."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise InvalidInputError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def true_or_false(value: object, name: str) -> bool:
    """``value`` as a bool, refused unless a Python or numpy bool."""
    if not isinstance(value, (bool, np.bool_)):
        raise InvalidInputError(f"{name} must be True or False, got {value!r}")
    return bool(value)


#: Side of the square tiles that the O(n^2) checks of :func:`checked_matrix` read at a time.
_TILE = 256


def check_spd_matrix(
    matrix: ArrayLike, name: str, symmetry_rtol: float = SYMMETRY_RTOL
) -> np.ndarray:
    """Validate a symmetric positive definite matrix and return it as a float array.

    See :func:`checked_cholesky`, which also returns the factor computed by the check.
    """
    return checked_cholesky(matrix, name, symmetry_rtol)[0]


def checked_cholesky(
    matrix: ArrayLike, name: str, symmetry_rtol: float = SYMMETRY_RTOL
) -> tuple[np.ndarray, np.ndarray]:
    """Validate a symmetric positive definite matrix; return it and its lower Cholesky factor.

    The checks of :func:`checked_matrix`, then :func:`cholesky_factor`.

    Returns
    -------
    array : ndarray, shape (n, n)
        Symmetric (the symmetric part of a matrix within ``symmetry_rtol``).
    factor : ndarray, shape (n, n)
        Lower triangular ``L`` with ``L L^T = array``.
    """
    array = checked_matrix(matrix, name, symmetry_rtol)[1]
    return array, cholesky_factor(array, name)


def checked_matrix(
    matrix: ArrayLike, name: str, symmetry_rtol: float = SYMMETRY_RTOL
) -> tuple[np.ndarray, np.ndarray]:
    """The checks of a symmetric positive definite matrix that cost ``O(n^2)``, no factorisation.

    Shape, real finite entries, magnitude, symmetry, a positive diagonal and every 2 x 2
    principal block definite (``|M_ij| < sqrt(M_ii M_jj)``). These are necessary, not
    sufficient: definiteness itself is proven by a Cholesky factorisation
    (:func:`cholesky_factor`), made where a factor is needed (a model given by its stiffness,
    and the blocks of ``W`` a method factors), so that no check costs more than the work it
    guards.

    Parameters
    ----------
    matrix : array_like, shape (n, n)
    name : str
        The argument's name, used in error messages.
    symmetry_rtol : float
        Largest accepted relative asymmetry ``max|M - M^T| / max|M|``. A matrix within it is
        replaced by ``(M + M^T) / 2`` with a :class:`~contactqp.errors.SymmetrizedWarning`.

    Raises
    ------
    InvalidInputError
        Wrong shape, complex values, NaN or inf, entries beyond :data:`MAX_MAGNITUDE` (or all
        below its inverse), asymmetry beyond ``symmetry_rtol``, or a 2 x 2 principal block
        singular to working precision.
    NotPositiveDefiniteError
        A diagonal entry that is not positive, or an indefinite 2 x 2 principal block.

    Returns
    -------
    given : ndarray, shape (n, n)
        The matrix as given, as a float array.
    symmetric : ndarray, shape (n, n)
        ``given`` itself when it is exactly symmetric, else its symmetric part.
    """
    array = real_array(matrix, name)
    if array.ndim != 2:
        raise InvalidInputError(f"{name} must be 2-D, got shape {array.shape}")
    n, m = array.shape
    if n != m or n == 0:
        raise InvalidInputError(
            f"{name} must be a non-empty square matrix, got shape {array.shape}"
        )
    low, high = float(np.min(array)), float(np.max(array))  # NaN and inf show in either
    if not (math.isfinite(low) and math.isfinite(high)):
        raise InvalidInputError(f"{name} contains NaN or inf (shape {array.shape})")
    scale = max(-low, high)
    if scale > MAX_MAGNITUDE:
        raise InvalidInputError(
            f"{name} has an entry of magnitude {scale:.3g}, beyond {MAX_MAGNITUDE:g}: "
            f"its products with forces and displacements would overflow; rescale the units"
        )
    if scale == 0.0:
        raise InvalidInputError(
            f"{name} is singular: all its entries are zero (shape {array.shape})"
        )
    if scale < 1.0 / MAX_MAGNITUDE:
        raise InvalidInputError(
            f"{name}'s largest entry is {scale:.3g}, below {1.0 / MAX_MAGNITUDE:g}: its products "
            f"with forces and displacements would underflow; rescale the units"
        )
    diagonal = array.diagonal()
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse_root = np.where(diagonal > 0.0, 1.0 / np.sqrt(diagonal), 0.0)
    asymmetry, correlation, (i, j) = _tile_checks(array, inverse_root)
    asymmetry /= scale
    if asymmetry > symmetry_rtol:
        raise InvalidInputError(
            f"{name} is not symmetric: max|M - M^T| / max|M| = {asymmetry:.3g} > {symmetry_rtol:g}"
        )
    symmetric = array
    if asymmetry > 0.0:
        warnings.warn(
            f"{name} symmetrised: relative asymmetry {asymmetry:.3g} is within {symmetry_rtol:g}",
            SymmetrizedWarning,
            stacklevel=3,
        )
        symmetric = 0.5 * (array + array.T)
    if np.any(diagonal <= 0.0):
        k = int(np.argmin(diagonal))
        raise NotPositiveDefiniteError(
            f"{name} is not positive definite: diagonal entry {k} is {diagonal[k]:.6g}; "
            f"smallest eigenvalue {_smallest_eigenvalue(symmetric):.6g}"
        )
    if correlation > 1.0:
        raise NotPositiveDefiniteError(
            f"{name} is not positive definite: its 2x2 principal block on freedoms {i} and {j} "
            f"has |M_ij| = {correlation:.6g} sqrt(M_ii M_jj); "
            f"smallest eigenvalue {_smallest_eigenvalue(symmetric):.6g}"
        )
    if 1.0 - correlation * correlation <= 1e-14:
        raise InvalidInputError(
            f"{name} is singular to working precision: freedoms {i} and {j} have "
            f"|M_ij| = sqrt(M_ii M_jj) (relative pivot {max(1.0 - correlation**2, 0.0):.3g})"
        )
    return array, symmetric


def _tile_checks(
    array: np.ndarray, inverse_root: np.ndarray
) -> tuple[float, float, tuple[int, int]]:
    """``(max|M - M^T|, max |S_ij|, (i, j))`` with ``S = (M + M^T) / 2`` scaled by
    ``inverse_root`` on both sides, off its diagonal: one pass over the upper triangle's
    tiles, each read with its mirror (no full-size temporary, cache-sized reads)."""
    n = array.shape[0]
    asymmetry, worst, pair = 0.0, 0.0, (0, 0)
    for i in range(0, n, _TILE):
        rows = slice(i, i + _TILE)
        for j in range(i, n, _TILE):
            cols = slice(j, j + _TILE)
            upper, lower = array[rows, cols], array[cols, rows].T
            if np.array_equal(upper, lower):
                tile = np.abs(upper)
            else:
                asymmetry = max(asymmetry, float(np.max(np.abs(upper - lower))))
                tile = np.abs(upper + lower)
                tile *= 0.5
            tile *= inverse_root[None, cols]
            if i == j:
                np.fill_diagonal(tile, 0.0)
            scaled = tile.max(axis=1) * inverse_root[rows]  # row r: max_c |S_rc|
            r = int(np.argmax(scaled))
            if scaled[r] > worst:
                worst = float(scaled[r])
                pair = (i + r, j + int(np.argmax(tile[r])))
    return asymmetry, worst, pair


def _smallest_eigenvalue(array: np.ndarray) -> float:
    """The smallest eigenvalue (for an error message: the matrix is refused already)."""
    import scipy.linalg

    return float(scipy.linalg.eigvalsh(array, subset_by_index=[0, 0], check_finite=False)[0])


def cholesky_factor(array: np.ndarray, name: str) -> np.ndarray:
    """The lower Cholesky factor of a symmetric ``array``, with errors that name ``name``.

    Raises
    ------
    NotPositiveDefiniteError
        The factorisation fails; the message gives the failed pivot and the smallest
        eigenvalue.
    InvalidInputError
        A pivot at or below ``1e-14`` times the largest (singular to working precision).
    """
    import scipy.linalg

    try:
        factor = scipy.linalg.cholesky(array, lower=True, check_finite=False)
    except np.linalg.LinAlgError as exc:
        raise NotPositiveDefiniteError(
            f"{name} is not positive definite: Cholesky failed ({exc}); "
            f"smallest eigenvalue {_smallest_eigenvalue(array):.6g}"
        ) from None
    pivots = np.diag(factor) ** 2
    if pivots.min() <= 1e-14 * pivots.max():
        raise InvalidInputError(
            f"{name} is singular to working precision: smallest Cholesky pivot {pivots.min():.3g}, "
            f"largest {pivots.max():.3g}"
        )
    return factor


@dataclass(frozen=True)
class UnitLoadCompliance:
    """Outcome of the unit-load procedure.

    Attributes
    ----------
    flexibility : ndarray, shape (n, n)
        Column ``j`` is the displacement of every freedom under a unit load on freedom ``j``, as
        measured (not symmetrised).
    reciprocity_error : float
        Largest relative deviation from Maxwell-Betti reciprocity, ``max|R - R^T| / max|R|``.
    """

    flexibility: np.ndarray
    reciprocity_error: float


def unit_load_compliance(
    solve: Callable[[np.ndarray], np.ndarray], n_freedoms: int, unit: float = 1.0
) -> UnitLoadCompliance:
    """Assemble the flexibility matrix by applying a unit load to each freedom in turn.

    Parameters
    ----------
    solve : callable
        ``solve(P) -> U``: displacements (shape ``(n_freedoms,)``, metres) of the computational
        freedoms under the load vector ``P`` (newtons), e.g. one finite-element analysis.
    n_freedoms : int
        Number of computational freedoms (nodes times freedoms per node).
    unit : float
        Magnitude of the unit load (1 N by default); columns are divided by it.

    Returns
    -------
    UnitLoadCompliance
    """
    if int(n_freedoms) < 1:
        raise InvalidInputError(f"n_freedoms must be >= 1, got {n_freedoms}")
    n = int(n_freedoms)
    columns = []
    for j in range(n):
        load = np.zeros(n)
        load[j] = unit
        response = np.asarray(solve(load), dtype=float).reshape(-1)
        if response.shape != (n,):
            raise InvalidInputError(
                f"solve returned shape {response.shape} for unit load {j}, expected ({n},)"
            )
        columns.append(response / unit)
    flexibility = np.column_stack(columns)
    scale = np.max(np.abs(flexibility))
    deviation = float(np.max(np.abs(flexibility - flexibility.T)) / scale) if scale > 0 else 0.0
    return UnitLoadCompliance(flexibility, deviation)


class ReducedModel:
    """Computational nodes with 1, 2 or 3 freedoms each and the matrix linking them.

    Give exactly one of ``flexibility`` (``U = R P``) or ``stiffness`` (``P = K U``); the other is
    computed only when an algorithm asks for it, by a Cholesky factorisation.

    The matrix is checked at a cost of ``O(n^2)`` (:func:`checked_matrix`). A stiffness is also
    factored at once (its factor gives ``U = K^-1 P`` and is kept); a flexibility's definiteness
    is proven by the factorisations that use it (``K`` on first use, and the blocks of ``W`` a
    method factors), each raising :class:`~contactqp.errors.NotPositiveDefiniteError` if the
    matrix it meets is not definite. A route that factors neither (the frictional Newton
    route factors its own Jacobians) leaves an indefinite flexibility that passes the
    ``O(n^2)`` checks unproven; its certificate still judges the answer on the matrix as given,
    and :attr:`stiffness` proves definiteness on request.

    Parameters
    ----------
    flexibility, stiffness : array_like, shape (n, n)
        Symmetric positive definite, in metres per newton (resp. newtons per metre), freedoms
        ordered node by node.
    dofs_per_node : int or sequence of int
        Freedoms of every node (1, 2 or 3), or one count per node.
    coordinates : array_like, shape (n_nodes, d), optional
        Node coordinates in metres (needed by geometric obstacles).
    symmetry_rtol : float
        See :func:`checked_matrix`.
    """

    def __init__(
        self,
        flexibility: ArrayLike | None = None,
        stiffness: ArrayLike | None = None,
        dofs_per_node: int | Sequence[int] | np.ndarray = 1,
        coordinates: ArrayLike | None = None,
        symmetry_rtol: float = SYMMETRY_RTOL,
    ) -> None:
        if stiffness is None and flexibility is not None:
            name, given = "flexibility", flexibility
        elif flexibility is None and stiffness is not None:
            name, given = "stiffness", stiffness
        else:
            raise InvalidInputError("give exactly one of flexibility or stiffness")
        # O(n^2) checks only: a Cholesky factorisation proves definiteness where a factor is
        # needed (below for a stiffness, whose U = K^-1 P needs it; for a flexibility, when K is
        # asked for), and the methods' factorisations prove it on the blocks of W they use
        given, matrix = checked_matrix(given, name, symmetry_rtol)
        #: The matrix exactly as given (``flexibility`` or ``stiffness``): the certificates'
        #: equilibrium is judged on it, not on the symmetric part the solvers use.
        self.as_given = given
        self._flexibility = matrix if name == "flexibility" else None
        self._stiffness = matrix if name == "stiffness" else None
        # a flexibility's factor is made only if K is asked for, so no (n x n) factor is held
        self._factor: tuple[np.ndarray, bool] | None = (
            (cholesky_factor(matrix, name), True) if name == "stiffness" else None
        )
        n = matrix.shape[0]
        counts = self._dof_counts(dofs_per_node, n)
        self.dofs_per_node = counts
        self.offsets = np.concatenate(([0], np.cumsum(counts)))
        self.coordinates: np.ndarray | None = None
        if coordinates is not None:
            coords = finite_array(coordinates, "coordinates", 2)
            if coords.shape[0] != len(counts):
                raise InvalidInputError(
                    f"coordinates has {coords.shape[0]} rows for {len(counts)} nodes "
                    f"(shape {coords.shape})"
                )
            self.coordinates = coords

    @staticmethod
    def _dof_counts(dofs_per_node: int | Sequence[int] | np.ndarray, n_freedoms: int) -> np.ndarray:
        if np.isscalar(dofs_per_node):
            # a whole number: 2.0 is 2, while 2.5, "2" or 2j are refused (not truncated or cast)
            if not isinstance(dofs_per_node, numbers.Integral | float) or dofs_per_node not in (
                1,
                2,
                3,
            ):
                raise InvalidInputError(f"dofs_per_node must be 1, 2 or 3, got {dofs_per_node!r}")
            per = int(dofs_per_node)
            if n_freedoms % per:
                raise InvalidInputError(
                    f"matrix size {n_freedoms} is not a multiple of dofs_per_node={per}"
                )
            return np.full(n_freedoms // per, per, dtype=int)
        counts = np.asarray(dofs_per_node, dtype=int).reshape(-1)
        if counts.size == 0 or np.any((counts < 1) | (counts > 3)):
            raise InvalidInputError("dofs_per_node entries must each be 1, 2 or 3")
        if counts.sum() != n_freedoms:
            raise InvalidInputError(
                f"dofs_per_node sums to {counts.sum()} freedoms but the matrix has {n_freedoms}"
            )
        return counts

    @property
    def n_freedoms(self) -> int:
        """Number of computational freedoms."""
        return int(self.offsets[-1])

    @property
    def n_nodes(self) -> int:
        """Number of computational nodes."""
        return len(self.dofs_per_node)

    def freedoms(self, node: int) -> np.ndarray:
        """Indices of the freedoms of ``node`` in the global vectors."""
        if not 0 <= node < self.n_nodes:
            raise InvalidInputError(f"node {node} out of range 0..{self.n_nodes - 1}")
        return np.arange(self.offsets[node], self.offsets[node + 1])

    def _cholesky(self) -> tuple[np.ndarray, bool]:
        if self._factor is None:  # built from a flexibility: factored on first need
            self._factor = (cholesky_factor(self.flexibility, "flexibility"), True)
        return self._factor

    @property
    def given(self) -> str:
        """Which matrix the model was built from: ``"flexibility"`` or ``"stiffness"``."""
        return "flexibility" if self._flexibility is not None else "stiffness"

    def _inverse(self) -> np.ndarray:
        """The inverse of the given matrix, from its Cholesky factor."""
        import scipy.linalg

        return scipy.linalg.cho_solve(self._cholesky(), np.eye(self.n_freedoms), check_finite=False)

    @property
    def asymmetry(self) -> float:
        """Relative asymmetry ``max|M - M^T| / max|M|`` of the matrix as given (0 if symmetric)."""
        given = self.as_given
        if given is (self._flexibility if self.given == "flexibility" else self._stiffness):
            return 0.0
        return float(np.max(np.abs(given - given.T)) / np.max(np.abs(given)))

    @property
    def flexibility(self) -> np.ndarray:
        """``R``, computed from ``K`` on first use when the model was built from a stiffness."""
        if self._flexibility is None:
            self._flexibility = self._inverse()
        return self._flexibility

    @property
    def stiffness(self) -> np.ndarray:
        """``K``, computed from ``R`` on first use when the model was built from a flexibility."""
        if self._stiffness is None:
            self._stiffness = self._inverse()
        return self._stiffness

    def displacements(self, loads: ArrayLike) -> np.ndarray:
        """``U = R P`` without forming ``R`` when only ``K`` is known. ``loads``: (n,) or (n, k)."""
        values = np.asarray(loads, dtype=float)
        if self._flexibility is not None:
            return self._flexibility @ values
        import scipy.linalg

        return scipy.linalg.cho_solve(self._cholesky(), values, check_finite=False)

    def forces(self, displacements: ArrayLike) -> np.ndarray:
        """``P = K U`` without forming ``K`` when only ``R`` is known."""
        values = np.asarray(displacements, dtype=float)
        if self._stiffness is not None:
            return self._stiffness @ values
        import scipy.linalg

        return scipy.linalg.cho_solve(self._cholesky(), values, check_finite=False)

    def __repr__(self) -> str:
        return f"ReducedModel({self.n_nodes} nodes, {self.n_freedoms} freedoms, given {self.given})"

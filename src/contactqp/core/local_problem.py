"""The local frictional-contact problem ``u = W r + q`` with one Coulomb cone per contact.

This is the form used by FCLIB and Siconos: for ``n_contacts`` contacts in dimension ``dim``
(2 or 3) the unknowns are the reactions ``r`` and the relative velocities (or displacement
increments) ``u``, both of length ``m = dim * n_contacts``, ordered contact by contact with the
normal component first, then the tangential ones.

The module also condenses a global problem ``M v = H r + f, u = H^T v + w`` to its local form
(as given: ``W = H^T M^-1 H`` is not symmetrised), certifies a candidate against the global
equations (:meth:`GlobalProblem.certify`), and measures the accuracy of a candidate solution with
the natural-map error used by Siconos.

The problem as given is the problem as written: a file whose values carry only a few significant
digits (the Siconos ``.dat`` dumps) defines exactly that problem, and every error is measured on
it. :attr:`LocalProblem.digits` records the digits, so that a solution can also say how far the
rounding of the data limits what it means for the problem the file was written from
(:func:`accuracy_limits`).
"""

from __future__ import annotations

import copy
import functools
import math
import operator
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import kernels
from ..errors import InvalidInputError, NotPositiveDefiniteError
from .friction import FrictionLaw, apex_distance
from .model import finite_array
from .operators import (
    PSD_SHIFT,  # the shift accepted by check_positive_semidefinite
    is_sparse,
)

if TYPE_CHECKING:
    import scipy.sparse as sp

__all__ = [
    "AccuracyLimits",
    "GlobalCertificate",
    "GlobalProblem",
    "LocalProblem",
    "accuracy_limits",
    "certify_small",
    "SMALL_UNKNOWNS",
    "SmallArrays",
    "check_diagonal",
    "check_positive_semidefinite",
    "small_semidefinite",
    "column_products",
    "cone_residual",
    "condense_global",
    "contact_status",
    "contact_status_unchecked",
    "natural_map_error",
    "natural_map_residual",
    "project_rows",
    "projection_on_cones",
    "relative_rounding",
    "limits_from_norms",
]


#: Default relative threshold of :func:`contact_status`: a contact carries a force, and slips,
#: beyond this share of the problem's force and velocity scales.
STATUS_RTOL = 1e-6


def _check_dim(dim):
    try:
        d = operator.index(dim)
    except TypeError:
        raise InvalidInputError(f"dim must be 2 or 3, got {dim!r}") from None
    if isinstance(dim, bool) or d not in (2, 3):
        raise InvalidInputError(f"dim must be 2 or 3, got {dim!r}")
    return d


def _as_matrix(name, value):
    """Return ``value`` as a csr_matrix (if sparse) or a 2-D float ndarray, checked finite."""
    mat: sp.csr_matrix | np.ndarray
    data: np.ndarray
    try:
        if is_sparse(value):
            import scipy.sparse as sp

            if type(value) is sp.csr_matrix and value.dtype == np.float64:
                mat = value  # as stored: a copy costs a small solve
            else:
                # scipy-stubs: csr_matrix(x, dtype=d) is typed only for a d matching x's own
                # scalar type; scipy converts any of its sparse types
                mat = sp.csr_matrix(value, dtype=float)  # type: ignore[call-overload]
            data = np.asarray(mat.data)
        else:
            dense = np.asarray(value, dtype=float)
            if type(dense) is not np.ndarray:  # e.g. numpy.matrix
                dense = dense.view(np.ndarray)
            mat = data = dense
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{name} must be a real matrix: {exc}") from None
    if mat.ndim != 2:
        raise InvalidInputError(f"{name} must be 2-D, got shape {mat.shape}")
    if not np.isfinite(data).all():
        raise InvalidInputError(f"{name} contains NaN or inf")
    return mat


def _plain_csr(value) -> bool:
    """True when the sparse ``value`` is a ``csr_matrix`` of float64 C-contiguous values."""
    import scipy.sparse as sp

    return type(value) is sp.csr_matrix and _plain_array(value.data, 1)


def _one_pass_check(dim, title, digits) -> Callable[..., bool] | None:
    """:func:`~contactqp.kernels.compiled.local_arrays_valid` when a problem's ``dim``,
    ``title`` and ``digits`` are as stored (an int 2 or 3, a str, a dict), so that its arrays
    may be checked in one compiled pass; None otherwise or without the compiled kernels."""
    if type(dim) is int and (dim == 2 or dim == 3) and type(title) is str and type(digits) is dict:
        return kernels.local_arrays_valid
    return None


def _stored_values(matrix) -> np.ndarray | None:
    """The values of ``matrix`` as stored, one C-contiguous float64 vector (a dense matrix
    raveled, a ``csr_matrix``'s ``data``) to be checked in place; None for any other kind."""
    if isinstance(matrix, np.ndarray):
        return matrix.reshape(-1) if _plain_array(matrix, 2) else None
    if not is_sparse(matrix):
        return None
    csr: Any = matrix  # scipy-stubs: issparse narrows only to the sparse base classes
    return csr.data if _plain_csr(csr) else None


def _plain_array(value, ndim: int) -> bool:
    """True when ``value`` is a C-contiguous float64 ndarray of ``ndim`` dimensions."""
    return (
        type(value) is np.ndarray
        and value.dtype == np.float64
        and value.ndim == ndim
        and value.flags.c_contiguous
    )


@dataclass(frozen=True)
class LocalProblem:
    r"""A local frictional-contact problem in FCLIB form, optionally with cohesion.

    Find ``r`` and ``u`` with ``u = W r + q`` and, for each contact ``i``, the Coulomb law in
    its De Saxce form: ``r_i`` in the Mohr-Coulomb cone ``C_i = {||r_T|| <= mu_i r_N + c_i}``,
    i.e. ``r~_i = r_i + (c_i / mu_i) e_N`` in the Coulomb cone ``K_i = {||r_T|| <= mu_i r_N}``,
    ``u_i + mu_i ||u_iT|| e_N`` in the dual cone ``K_i*``, and the two orthogonal
    (see :func:`natural_map_error`).

    With cohesion ``c_i > 0`` the cone is the Coulomb cone translated along the normal, its
    apex at ``r_N = -c_i / mu_i`` (the tensile strength of the interface): the contact transmits
    shear up to ``c_i`` under zero normal reaction and opens only when the tensile reaction
    reaches ``c_i / mu_i``. With ``c = 0`` (the default) this is exactly the FCLIB problem.

    Parameters
    ----------
    W : scipy.sparse.csr_matrix or numpy.ndarray, shape (m, m)
        Delassus operator, ``m = dim * n_contacts``. Any scipy sparse matrix or array is
        stored as a ``csr_matrix``; anything else as a float ``ndarray``.
    q : array_like, shape (m,)
        Free velocity (or free gap increment).
    mu : array_like, shape (n_contacts,)
        Friction coefficients, ``>= 0``.
    dim : int
        Space dimension, 2 or 3 (the size of each contact block).
    title : str, optional
        Free text, e.g. the FCLIB ``info/title``.
    cohesion : array_like, shape (n_contacts,), optional
        Cohesion ``c_i >= 0`` per contact, in units of ``r``; ``c_i > 0`` needs ``mu_i > 0``.
        Stored as zeros when not given.
    digits : dict of str to int, optional
        Significant decimal digits of the data as written, for the arrays (``"W"``, ``"q"``)
        written with fewer than 16 (e.g. ``{"W": 6}`` for a Siconos sparse dump); arrays not
        named are exact doubles. The problem is the one written; this only tells a solution how
        far the data's rounding limits it (:func:`accuracy_limits`).

    Attributes
    ----------
    law : FrictionLaw
        The contacts' friction law (``mu``, ``cohesion``), validated once.

    Raises
    ------
    InvalidInputError
        If a shape is inconsistent, a value is NaN or infinite, ``mu < 0``, ``cohesion < 0``,
        cohesion on a frictionless contact, or ``dim`` is not 2 or 3.
    """

    kind = "local"  # the problem kind (contactqp.methods.registry); not a field

    W: sp.csr_matrix | np.ndarray
    q: np.ndarray
    mu: np.ndarray
    dim: int
    title: str = field(default="")
    cohesion: np.ndarray | None = field(default=None)
    digits: dict[str, int] = field(default_factory=dict, repr=False, compare=False)
    law: FrictionLaw = field(init=False, repr=False, compare=False)
    #: What was checked on ``W``, shared by reference with the :meth:`with_q` twins.
    _checks: dict[str, bool] = field(init=False, repr=False, compare=False, default_factory=dict)

    def __post_init__(self):
        if not self._validated_in_one_pass():
            self._validate()

    def _validated_in_one_pass(self) -> bool:
        """Validate and store the fields by one compiled pass
        (:func:`~contactqp.kernels.compiled.local_arrays_valid`) when they are already as
        stored: C-contiguous float64 arrays, ``W`` dense or a float64 ``csr_matrix``, an int
        ``dim``, a str ``title``. False, with nothing stored, otherwise or when a check
        fails: :meth:`_validate` then names what is wrong."""
        W, q, mu, cohesion, dim = self.W, self.q, self.mu, self.cohesion, self.dim
        check = _one_pass_check(dim, self.title, self.digits)
        if not (
            check is not None
            and _plain_array(q, 1)
            and _plain_array(mu, 1)
            and (cohesion is None or _plain_array(cohesion, 1))
            and q.shape[0] == dim * mu.shape[0]
            and W.shape == (q.shape[0], q.shape[0])
        ):
            return False
        values = _stored_values(W)
        if values is None or not check(values, q, mu, cohesion):
            return False
        if self.digits:
            object.__setattr__(self, "digits", _check_digits(self.digits, ("W", "q")))
        law = FrictionLaw.from_checked(mu, np.zeros(mu.shape[0]) if cohesion is None else cohesion)
        object.__setattr__(self, "cohesion", law.cohesion)
        object.__setattr__(self, "law", law)
        return True

    def _validate(self) -> None:
        """Check and store the fields, converting them to their stored types; raise
        :class:`~contactqp.errors.InvalidInputError` naming the first that is wrong."""
        dim = _check_dim(self.dim)
        object.__setattr__(self, "digits", _check_digits(self.digits, ("W", "q")))
        W = _as_matrix("W", self.W)
        q = np.ascontiguousarray(finite_array(self.q, "q", 1))  # read in place by the kernels
        mu = finite_array(self.mu, "mu", 1)
        nc = mu.shape[0]
        m = dim * nc
        if q.shape != (m,):
            raise InvalidInputError(
                f"q must have length dim*n_contacts = {dim}*{nc} = {m}, got shape {q.shape}"
            )
        if W.shape != (m, m):
            raise InvalidInputError(
                f"W must be square of size dim*n_contacts = {m}, got shape {W.shape}"
            )
        given_cohesion: float | np.ndarray = 0.0
        if self.cohesion is not None:
            given_cohesion = finite_array(self.cohesion, "cohesion", 1)
            if given_cohesion.shape != (nc,):
                raise InvalidInputError(
                    f"cohesion must have length n_contacts = {nc}, got shape {given_cohesion.shape}"
                )
        law = FrictionLaw(mu, given_cohesion, n_contacts=nc)
        mu, cohesion = law.mu, law.cohesion
        if not isinstance(self.title, str):
            raise InvalidInputError(f"title must be a str, got {type(self.title).__name__}")
        object.__setattr__(self, "dim", dim)
        object.__setattr__(self, "W", W)
        object.__setattr__(self, "q", q)
        object.__setattr__(self, "mu", mu)
        object.__setattr__(self, "cohesion", cohesion)
        object.__setattr__(self, "law", law)

    @property
    def n_contacts(self) -> int:
        """Number of contacts, ``len(mu)``."""
        return int(self.mu.shape[0])

    def with_q(self, q) -> LocalProblem:
        """The same ``W``, law, title and digits with another ``q`` (same shape).

        ``W`` is not validated again, and what was checked or computed once on this problem
        (its semidefiniteness, :meth:`check_semidefinite`; the apex shift) carries over: the
        cheap way to solve many problems that differ only in ``q``.
        """
        values = np.ascontiguousarray(finite_array(q, "q", 1))
        if values.shape != self.q.shape:
            raise InvalidInputError(
                f"q must have length dim*n_contacts = {self.q.shape[0]}, got shape {values.shape}"
            )
        twin = copy.copy(self)  # shares W, the law and the cached checks
        object.__setattr__(twin, "q", values)
        return twin

    def check_semidefinite(self) -> None:
        """:func:`check_positive_semidefinite` of ``W``, factored once per problem (and its
        :meth:`with_q` twins); raises on every call when ``W`` fails."""
        if not self._checks.get("semidefinite", False):
            W = self.small_W  # the same test in C first; numpy and LAPACK for the verdict
            if W is None or not small_semidefinite(W.reshape(1, *W.shape)).all():
                check_positive_semidefinite(self.W)
            self._checks["semidefinite"] = True

    @functools.cached_property
    def small_W(self) -> np.ndarray | None:
        """``W`` as the compiled small-problem route reads it (dense, C-contiguous, shape
        (m, m), read-only use), or None when ``W`` has more than :data:`SMALL_UNKNOWNS` rows,
        none, or the compiled kernels are absent: ``W`` itself when it is so stored, else a
        dense copy made once per problem (and shared by its :meth:`with_q` twins)."""
        m = self.q.shape[0]
        if m > SMALL_UNKNOWNS or m == 0 or kernels.small_solve is None:
            return None
        W = self.W
        if type(W) is np.ndarray and W.flags.c_contiguous:
            return W
        dense = np.ascontiguousarray(W if isinstance(W, np.ndarray) else W.toarray())
        dense.flags.writeable = False
        return dense

    @functools.cached_property
    def frictionless(self) -> bool:
        """True when ``mu = 0`` on every contact (the cones are rays)."""
        return not (self.mu > 0).any()

    @functools.cached_property
    def small(self) -> SmallArrays | None:
        """The arrays of the compiled small-problem route (:class:`SmallArrays`), or None when
        ``W`` has more than :data:`SMALL_UNKNOWNS` rows or the compiled kernels are absent.

        Computed once per problem (and shared by its :meth:`with_q` twins): a dense copy of a
        sparse ``W``, so that no solve converts it again.
        """
        W = self.small_W
        if W is None:
            return None
        m = W.shape[0]
        arrays = SmallArrays(
            W=W.reshape(1, m, m),  # float, as validated
            mu=np.ascontiguousarray(self.mu).reshape(1, -1),
            shift=np.ascontiguousarray(self.apex_shift).reshape(1, m),
            data_rounding=(
                relative_rounding(self.digits.get("W")),
                relative_rounding(self.digits.get("q")),
            ),
        )
        for array in (arrays.W, arrays.mu, arrays.shift):
            array.flags.writeable = False
        return arrays

    @functools.cached_property
    def _largest_diagonal(self) -> float:
        """``max |W_ii|`` (1 when every entry is 0): the velocity scale of
        :func:`contact_status`."""
        diagonal = np.abs(np.asarray(self.W.diagonal(), dtype=float))
        return float(diagonal.max(initial=0.0)) or 1.0

    @functools.cached_property
    def certified_rows(self) -> slice | np.ndarray:
        """The rows of ``u`` that :func:`natural_map_error`'s numerator depends on.

        On a contact without friction (``mu_i = 0``) the cone is the normal ray, so the
        tangential part of the natural map is ``r_T - 0 = r_T`` whatever ``u_T``: those rows of
        ``u`` (and their rounding) move the error only through its scale, at relative rounding
        level. Every row (a full slice) when every contact has friction; the normal rows (a
        slice) when none has; else an index array.
        """
        frictionless = self.mu == 0
        if not frictionless.any():
            return slice(None)
        if frictionless.all():
            return slice(None, None, self.dim)
        keep = np.ones((self.n_contacts, self.dim), dtype=bool)
        keep[frictionless, 1:] = False
        return np.flatnonzero(keep)

    @functools.cached_property
    def apex_shift(self) -> np.ndarray:
        """Shape (m,): ``c_i / mu_i`` on each normal component, 0 elsewhere.

        ``r + apex_shift`` lies in the Coulomb cone exactly when ``r`` lies in the Mohr-Coulomb
        cone: the translation that turns a cohesive problem into an FCLIB one.
        """
        shift = np.zeros((self.n_contacts, self.dim))
        if self.law.cohesion.any():
            shift[:, 0] = apex_distance(self.mu, self.law.cohesion)  # the field, as validated
        shift.flags.writeable = False
        return shift.reshape(-1)


#: Largest number of unknowns ``d k`` of a problem solved by the compiled small-problem route
#: (:attr:`LocalProblem.small`): a dense ``W`` of at most 512 kB. Its Newton steps factor the
#: whole Newton matrix by an unblocked LU (``m^3 / 3`` flops) but pay no numpy call; the Python
#: route (LAPACK, and the candidate-set reduction from 64 contacts) caught up at 300 to 450
#: unknowns on random problems of 30 % open contacts, and at 600 on 70 % (measured with one
#: BLAS thread): below 256 the compiled route was 1.2 to 4 times faster.
SMALL_UNKNOWNS = 256


@dataclass(frozen=True)
class SmallArrays:
    """A small problem's arrays as the compiled kernels take them (one problem of a batch).

    Attributes
    ----------
    W : numpy.ndarray, shape (1, m, m)
        Dense, C-contiguous, read-only.
    mu : numpy.ndarray, shape (1, k)
    shift : numpy.ndarray, shape (1, m)
        :attr:`LocalProblem.apex_shift`.
    data_rounding : tuple of float
        :func:`relative_rounding` of the digits of ``W`` and ``q``.
    """

    W: np.ndarray
    mu: np.ndarray
    shift: np.ndarray
    data_rounding: tuple[float, float]


def _check_digits(digits, names) -> dict[str, int]:
    """Validated ``{array name: significant digits}`` (see :attr:`LocalProblem.digits`)."""
    if not isinstance(digits, dict):
        raise InvalidInputError(f"digits must be a dict of array name to int, got {digits!r}")
    checked = {}
    for name, count in digits.items():
        if name not in names:
            raise InvalidInputError(f"digits names an unknown array {name!r} (known: {names})")
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise InvalidInputError(f"digits[{name!r}] must be a positive int, got {count!r}")
        checked[name] = count
    return checked


def relative_rounding(digits: int | None) -> float:
    """Largest relative rounding of a value written with ``digits`` significant digits.

    ``0.5 * 10**(1 - digits)`` (5e-6 for 6 digits); 0 for ``None`` (an exact double).
    """
    return 0.0 if digits is None else 0.5 * 10.0 ** (1 - digits)


def _check_global(M, H, f, w, mu, dim):
    """Validate and normalise the data of a global problem."""
    dim = _check_dim(dim)
    Mm = _as_matrix("M", M)
    Hm = _as_matrix("H", H)
    fv = finite_array(f, "f", 1)
    wv = finite_array(w, "w", 1)
    muv = finite_array(mu, "mu", 1)
    ndof = Mm.shape[0]
    m = dim * muv.shape[0]
    if Mm.shape != (ndof, ndof):
        raise InvalidInputError(f"M must be square, got shape {Mm.shape}")
    if Hm.shape != (ndof, m):
        raise InvalidInputError(
            f"H must have shape (ndof, dim*n_contacts) = ({ndof}, {m}), got {Hm.shape}"
        )
    if fv.shape != (ndof,):
        raise InvalidInputError(f"f must have length ndof = {ndof}, got shape {fv.shape}")
    if wv.shape != (m,):
        raise InvalidInputError(f"w must have length dim*n_contacts = {m}, got shape {wv.shape}")
    if np.any(muv < 0):
        raise InvalidInputError(f"mu must be >= 0, got min(mu) = {muv.min():g}")
    return Mm, Hm, fv, wv, muv, dim


@dataclass(frozen=True)
class AccuracyLimits:
    """How far rounding, and the data's written digits, limit a natural-map error.

    Both are relative, in the units of :func:`natural_map_error`, and are order-of-magnitude
    estimates (first-order bounds with norms), not guarantees.

    Attributes
    ----------
    rounding : float
        Natural-map error that evaluating the certificate in double precision can leave on the
        problem as given: about ``eps |W| |r|`` for a local problem, and ``cond(M) eps`` times
        the size of ``H^T v`` for a global one, ``cond`` that of the Jacobi-scaled ``M`` in which
        ``v`` is solved for. An error below it cannot be asked for.
    data : float
        Change of the natural map at this ``r`` when every value written with ``k`` significant
        digits (:attr:`LocalProblem.digits`) moves by its rounding, ``0.5 * 10**(1 - k)``
        relative: how closely ``r`` can be known to solve the problem the file was written
        from. 0 when the data are exact doubles.
    condition : float
        1-norm condition number (estimated) of the Jacobi-scaled ``M`` of a global problem,
        1 for a local one.
    digits : dict of str to int
        The data's digits, as in :attr:`LocalProblem.digits`.
    """

    rounding: float
    data: float
    condition: float = 1.0
    digits: dict[str, int] = field(default_factory=dict)

    def describe(self, tol: float) -> str:
        """One clause per limit above ``tol`` (empty string when none is)."""
        notes = []
        if self.rounding > tol:
            cause = (
                f"the conditioning of M (cond {self.condition:.1e} after Jacobi scaling)"
                if self.condition > 1.0
                else "rounding"
            )
            notes.append(
                f"{cause} limits the attainable natural-map error to about "
                f"{self.rounding:.1e} > tol {tol:g}"
            )
        if self.data > tol:
            written = ", ".join(f"{name} {count}" for name, count in self.digits.items())
            notes.append(
                f"the data carry only a few significant digits ({written}): the error "
                f"is on the problem as written; the problem it was written from is met "
                f"only to about {self.data:.1e}"
            )
        return "; ".join(notes)

    def as_dict(self) -> dict:
        """JSON-ready ``{"attainable", "data_limit", "condition", "digits"}``."""
        return {
            "attainable": self.rounding,
            "data_limit": self.data,
            "condition": self.condition,
            "digits": dict(self.digits),
        }


_EPS = float(np.finfo(float).eps)


#: :meth:`GlobalProblem.certify` reads a sparse ``M`` or ``H`` of at most this many entries
#: (dense) as a dense copy.
DENSE_READ = 1 << 16
#: Stored entries of a block of rows of a sparse matrix in :func:`_abs_product`.
_SPARSE_BLOCK = 1 << 18


def _abs_product(A, x) -> np.ndarray:
    """``|A| |x|`` for a dense or sparse ``A``; a dense ``A`` by blocks of rows, so that no copy
    of a large ``W`` is made."""
    ax = np.abs(np.asarray(x, dtype=float)).ravel()
    if is_sparse(A):
        sparse: Any = A
        if sparse.nnz <= _SPARSE_BLOCK:  # scipy's |A|: a small copy, no new CSR matrix
            return np.asarray(abs(sparse) @ ax).ravel()
    if not isinstance(A, np.ndarray):
        import scipy.sparse as sp

        return _abs_sparse_product(sp.csr_matrix(A), ax)  # no copy of a CSR matrix
    A = np.asarray(A)  # e.g. a numpy.matrix
    rows = max(1, (1 << 22) // max(1, A.shape[1]))  # blocks of at most 32 MB
    return np.concatenate(
        [np.abs(A[start : start + rows]) @ ax for start in range(0, A.shape[0], rows)]
        or [np.zeros(0)]
    )


def _abs_sparse_product(A: sp.csr_matrix, ax: np.ndarray) -> np.ndarray:
    """``|A| ax`` by blocks of rows of about 2**18 stored entries, sharing ``A``'s indices.

    The absolute values of a block go into one reused buffer (2 MB, which stays in cache) rather
    than into a copy of all of ``A``'s values.
    """
    import scipy.sparse as sp

    indptr, entries = A.indptr, _SPARSE_BLOCK
    out = np.empty(A.shape[0])
    scratch = np.empty(min(entries, A.nnz))
    first = 0
    while first < A.shape[0]:
        last = max(first + 1, int(np.searchsorted(indptr, indptr[first] + entries, "right")) - 1)
        last = min(last, A.shape[0])
        begin, end = indptr[first], indptr[last]
        values = A.data[begin:end]
        values = (
            np.abs(values, out=scratch[: end - begin])
            if end - begin <= scratch.size
            else np.abs(values)
        )  # one row longer than a block
        rows = sp.csr_matrix(
            (values, A.indices[begin:end], indptr[first : last + 1] - begin),
            shape=(last - first, A.shape[1]),
        )
        out[first:last] = rows @ ax
        first = last
    return out


def accuracy_limits(problem: LocalProblem, r, u, *, magnitude=None) -> AccuracyLimits:
    """:class:`AccuracyLimits` of reactions ``r`` and velocities ``u`` (shape (m,)) of a local
    problem.

    With ``s = max(||q||, ||r||, ||u||)`` (the scale of :func:`natural_map_error`):
    ``rounding = eps (|| |W| |r| || + ||q||) / s`` and
    ``data = (d_W || |W| |r| || + d_q ||q||) / s``, ``d`` the :func:`relative_rounding` of each
    array's digits, the norm of ``|W| |r|`` taken over the rows the error depends on
    (:attr:`LocalProblem.certified_rows`: all but the tangential rows of contacts without
    friction). ``magnitude`` is ``|W| |r|`` when the caller has it already
    (:func:`column_products`); only those rows of it are read.
    """
    rv, uv = np.asarray(r, dtype=float), np.asarray(u, dtype=float)
    scale = math.sqrt(max(problem.q @ problem.q, rv @ rv, uv @ uv))
    if magnitude is None:
        magnitude = _abs_product(problem.W, rv)
    product = float(np.linalg.norm(magnitude[problem.certified_rows]))
    return limits_from_norms(product, float(np.linalg.norm(problem.q)), scale, problem.digits)


def limits_from_norms(
    product: float,
    size_q: float,
    scale: float,
    digits: dict[str, int],
    data_rounding: tuple[float, float] | None = None,
) -> AccuracyLimits:
    """:func:`accuracy_limits` from its norms: ``product`` the norm of ``|W| |r|`` over the
    certified rows, ``size_q`` of ``q``, ``scale`` the error's (0 counts as 1).
    ``data_rounding``: the :func:`relative_rounding` of ``W``'s and ``q``'s digits, when the
    caller has them already."""
    scale = scale or 1.0
    if data_rounding is None:
        data_rounding = (relative_rounding(digits.get("W")), relative_rounding(digits.get("q")))
    data_w, data_q = data_rounding
    return AccuracyLimits(
        rounding=_EPS * (product + size_q) / scale,
        data=(data_w * product + data_q * size_q) / scale,
        digits=dict(digits),
    )


def certify_small(
    problem: LocalProblem, r: np.ndarray, *, per_contact: bool = False, rtol: float = STATUS_RTOL
) -> tuple[np.ndarray, float, AccuracyLimits, np.ndarray]:
    """``(u, error, limits, status)`` of reactions ``r`` (float, shape (m,)) of a problem with
    :attr:`LocalProblem.small` arrays, in one compiled pass over ``W``.

    The same figures as ``u = W r + q``, :func:`natural_map_residual` (its error),
    :func:`accuracy_limits` and :func:`contact_status_unchecked` (with ``rtol``), up to the order
    of the sums.
    """
    small = problem.small
    if small is None or kernels.small_certificate is None:
        raise InvalidInputError("certify_small needs a problem with small arrays")
    m = r.shape[0]
    u = np.empty((1, m))
    measures = np.empty((1, 4))
    status = np.empty((1, problem.n_contacts), dtype=np.intp)
    kernels.small_certificate(
        small.W,
        problem.q.reshape(1, m),  # C-contiguous, as validated
        small.mu,
        small.shift,
        np.ascontiguousarray(r, dtype=float).reshape(1, m),
        per_contact,
        CONTACT_FLOOR,
        rtol,
        u,
        measures,
        status,
    )
    error, product, size_q, scale = measures[0].tolist()
    limits = limits_from_norms(product, size_q, scale, problem.digits, small.data_rounding)
    return u[0], error, limits, status[0]


#: Entries of a block of rows (512 kB, in cache) by which :func:`column_products` reads a dense
#: matrix.
_BLOCK_ENTRIES = 1 << 16
#: column_products gathers the columns asked for when they are fewer than 1/FEW_COLUMNS of A's
FEW_COLUMNS = 8


def _as_slice(index):
    """Evenly spaced increasing indices as a slice (a view, not a gather), else as given."""
    if isinstance(index, slice):
        return index
    index = np.asarray(index)
    if index.dtype.kind in "iu" and index.size >= 2:
        step = int(index[1] - index[0])
        if step > 0 and np.array_equal(index, index[0] + step * np.arange(index.size)):
            return slice(int(index[0]), int(index[-1]) + 1, step)
    return index


def column_products(A, x, columns=None) -> tuple[np.ndarray, np.ndarray]:
    """``(B x, |B| |x|)`` of ``B = A[:, columns]`` (all of ``A`` when ``columns`` is None),
    reading ``A`` once.

    A dense ``A`` is read in place by blocks of whole rows that stay in cache: ``B x`` is
    ``A x'`` with ``x'`` zero off ``columns``, and ``|B|`` of a block goes into one reused
    buffer, so that neither product makes a temporary of ``B``'s size. A sparse ``A`` gives its
    columns in compressed rows.
    """
    xv = np.asarray(x, dtype=float).ravel()
    if is_sparse(A):
        sparse: Any = A
        B = sparse if columns is None else sparse.tocsr()[:, columns]
        return np.asarray(B @ xv).ravel(), _abs_product(B, xv)
    A = np.asarray(A)
    m, n = A.shape
    if columns is not None and FEW_COLUMNS * np.size(columns) < n:  # gather those columns only
        block = A[:, columns]
        return block @ xv, np.abs(block) @ np.abs(xv)
    if columns is None:
        columns, spread = slice(None), xv
    else:
        columns = _as_slice(columns)
        spread = np.zeros(n)
        spread[columns] = xv
    ax = np.abs(xv)
    product, magnitude = np.empty(m), np.empty(m)
    rows = max(1, _BLOCK_ENTRIES // max(1, n))
    buffer = np.empty((min(rows, m), xv.size))
    for start in range(0, m, rows):
        stop = min(start + rows, m)
        part = A[start:stop]
        np.dot(part, spread, out=product[start:stop])
        absolute = np.abs(part[:, columns], out=buffer[: stop - start])
        np.dot(absolute, ax, out=magnitude[start:stop])
    return product, magnitude


@dataclass(frozen=True)
class GlobalCertificate:
    """A candidate ``r`` judged on the global equations as written (:meth:`GlobalProblem.certify`).

    Attributes
    ----------
    v : numpy.ndarray, shape (ndof,)
        Solves ``M v = H r + f`` (one solve with the factorised ``M``).
    u : numpy.ndarray, shape (m,)
        ``H^T v + w``.
    error : float
        :func:`natural_map_error` of ``(r, u)``, with the scale of the condensed problem.
    equilibrium : float
        ``||S (M v - H r - f)|| / max(||S M v||, ||S H r||, ||S f||)``, ``S`` the Jacobi scaling
        ``|diag M|^-1/2``: the relative residual of the written equilibrium.
    limits : AccuracyLimits
    """

    v: np.ndarray
    u: np.ndarray
    error: float
    equilibrium: float
    limits: AccuracyLimits


class _ScaledFactor:
    """LU factorisation of the Jacobi-scaled ``S M S`` (``S = |diag M|^-1/2``, 1 on zeros).

    The scaling makes the singularity test scale-invariant: a diagonal mass matrix with masses
    and inertias of very different sizes is regular.
    """

    def __init__(self, M):
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        ndof = M.shape[0]
        diag = np.abs(M.diagonal())
        self.s = np.ones(ndof)
        self.s[diag > 0] = 1.0 / np.sqrt(diag[diag > 0])
        S = sp.diags(self.s)
        self.scaled = sp.csc_matrix(S @ sp.csc_matrix(M) @ S)
        try:
            self.lu = splu(self.scaled)
        except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
            raise NotPositiveDefiniteError(f"M ({ndof}x{ndof}) is singular: {exc}") from None
        pivots = np.abs(self.lu.U.diagonal())
        if pivots.min() <= ndof * _EPS * pivots.max():
            raise NotPositiveDefiniteError(
                f"M ({ndof}x{ndof}) is numerically singular: smallest/largest LU pivot of the "
                f"scaled matrix = {pivots.min() / pivots.max():.3g}"
            )

    def solve(self, rhs):
        """``M^-1 rhs = S (S M S)^-1 S rhs`` for rhs of shape (ndof,) or (ndof, k)."""
        sc = self.s[:, None] if rhs.ndim == 2 else self.s
        return sc * self.lu.solve(np.ascontiguousarray(sc * rhs))

    @functools.cached_property
    def condition(self) -> float:
        """1-norm condition number of ``S M S``: exact up to 100 freedoms, else estimated."""
        from scipy.sparse.linalg import LinearOperator, onenormest

        n = self.scaled.shape[0]
        norm = float(abs(self.scaled).sum(axis=0).max())
        if n <= 100:
            inverse = self.lu.solve(np.eye(n))
            return norm * float(np.abs(inverse).sum(axis=0).max())
        inverse_operator = LinearOperator(
            (n, n),
            matvec=self.lu.solve,
            dtype=np.float64,
            # scipy-stubs 1.17 leave out SuperLU.solve's ``trans`` argument (scipy has it)
            rmatvec=lambda x: self.lu.solve(x, trans="T"),  # type: ignore[call-overload]
        )
        return norm * float(onenormest(inverse_operator))


@dataclass(frozen=True)
class GlobalProblem:
    """A global frictional-contact problem ``M v = H r + f``, ``u = H^T v + w``.

    Kept as read from a file; :meth:`condense` gives the equivalent :class:`LocalProblem` and
    :meth:`certify` judges a candidate on the equations as written. Shapes and values are
    validated as in :func:`condense_global` (``InvalidInputError``).

    Parameters
    ----------
    M : scipy.sparse matrix or numpy.ndarray, shape (ndof, ndof)
        Mass (or stiffness) matrix, nonsingular; not necessarily symmetric (it is used as given).
    H : scipy.sparse matrix or numpy.ndarray, shape (ndof, m)
        Transpose of the contact Jacobian, ``m = dim * n_contacts``.
    f : numpy.ndarray, shape (ndof,)
    w : numpy.ndarray, shape (m,)
    mu : numpy.ndarray, shape (n_contacts,)
    dim : int
        2 or 3.
    title : str, optional
    digits : dict of str to int, optional
        Significant digits of the arrays ``"M"``, ``"H"``, ``"f"``, ``"w"`` written with fewer
        than 16, as :attr:`LocalProblem.digits`.
    """

    kind = "global"  # the problem kind (contactqp.methods.registry); not a field

    M: sp.csr_matrix | np.ndarray
    H: sp.csr_matrix | np.ndarray
    f: np.ndarray
    w: np.ndarray
    mu: np.ndarray
    dim: int
    title: str = field(default="")
    digits: dict[str, int] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        if self._validated_in_one_pass():
            return
        Mm, Hm, fv, wv, muv, dim = _check_global(self.M, self.H, self.f, self.w, self.mu, self.dim)
        for name, value in zip(
            ("M", "H", "f", "w", "mu", "dim"), (Mm, Hm, fv, wv, muv, dim), strict=True
        ):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "digits", _check_digits(self.digits, ("M", "H", "f", "w")))

    def _validated_in_one_pass(self) -> bool:
        """True when the fields are already as stored (C-contiguous float64 arrays, ``M`` and
        ``H`` dense or float64 ``csr_matrix``, an int ``dim``, a str ``title``) and pass the
        checks of :func:`_check_global` by two compiled passes
        (:func:`~contactqp.kernels.compiled.local_arrays_valid`); False otherwise or when a
        check fails, and :func:`_check_global` then names what is wrong."""
        M, H, f, w, mu, dim = self.M, self.H, self.f, self.w, self.mu, self.dim
        check = _one_pass_check(dim, self.title, self.digits)
        if not (
            check is not None
            and _plain_array(f, 1)
            and _plain_array(w, 1)
            and _plain_array(mu, 1)
            and w.shape[0] == dim * mu.shape[0]
            and M.shape == (f.shape[0], f.shape[0])
            and H.shape == (f.shape[0], w.shape[0])
        ):
            return False
        M_values, H_values = _stored_values(M), _stored_values(H)
        if not (
            M_values is not None
            and H_values is not None
            and check(M_values, f, mu, None)
            and check(H_values, w, mu, None)
        ):
            return False
        if self.digits:
            object.__setattr__(self, "digits", _check_digits(self.digits, ("M", "H", "f", "w")))
        return True

    @property
    def n_contacts(self) -> int:
        """Number of contacts, ``len(mu)``."""
        return int(self.mu.shape[0])

    @functools.cached_property
    def _factor(self) -> _ScaledFactor:
        return _ScaledFactor(self.M)

    @functools.cached_property
    def _read(self) -> tuple[sp.csr_matrix | np.ndarray, sp.csr_matrix | np.ndarray]:
        """``(M, H)`` as :meth:`certify` reads them: a sparse one of at most
        :data:`DENSE_READ` entries as a dense copy (a product costs numpy about a
        microsecond, scipy.sparse some tens: the certificate of a small problem cost 20 times
        its solve)."""
        M, H = self.M, self.H
        if is_sparse(M) and M.shape[0] * M.shape[1] <= DENSE_READ:
            M = M.toarray()
        if is_sparse(H) and H.shape[0] * H.shape[1] <= DENSE_READ:
            H = H.toarray()
        return M, H

    @functools.cached_property
    def _condensed(self) -> LocalProblem:
        import scipy.sparse as sp  # the factorisation of M is SuperLU's

        Mm, Hm, fv, wv, muv, dim = self.M, self.H, self.f, self.w, self.mu, self.dim
        ndof, m = Mm.shape[0], Hm.shape[1]
        if ndof == 0:  # no freedoms: H is empty, nothing to condense
            W = sp.csr_matrix((m, m)) if sp.issparse(Hm) else np.zeros((m, m))
            return LocalProblem(W, wv, muv, dim, self.title)
        solve = self._factor.solve
        sparse_h = sp.issparse(Hm)
        Hc = Hm if isinstance(Hm, np.ndarray) else sp.csc_matrix(Hm)
        Wd = np.empty((m, m))
        block = max(1, (1 << 24) // ndof)  # at most ~128 MB of dense right-hand sides at once
        for start in range(0, m, block):
            stop = min(m, start + block)
            columns = Hc[:, start:stop]
            rhs = np.array(columns) if isinstance(columns, np.ndarray) else columns.toarray()
            Wd[:, start:stop] = Hc.T @ solve(rhs)
        qv = np.asarray(Hc.T @ solve(fv)).ravel() + wv
        if not (np.all(np.isfinite(Wd)) and np.all(np.isfinite(qv))):
            raise NotPositiveDefiniteError(
                f"M ({ndof}x{ndof}) is singular: the solve is not finite"
            )
        if sparse_h:
            W = sp.csr_matrix(Wd)
            W.eliminate_zeros()
        else:
            W = Wd
        return LocalProblem(W, qv, muv, dim, self.title)

    def condense(self) -> LocalProblem:
        """Return the local problem, see :func:`condense_global` (computed once)."""
        return self._condensed

    def certify(self, r, *, factor=None, local: LocalProblem | None = None) -> GlobalCertificate:
        """Judge reactions ``r`` (shape (m,)) on the equations as written.

        ``factor`` (an exact factorisation of ``M``: ``solve(rhs)``, its Jacobi scaling ``s``
        and the ``condition`` of the scaled ``M``, as
        :class:`contactqp.methods.global_route.MassFactor`) and ``local`` (the condensed
        problem it gave) replace the LU factorisation and the condensation made here.

        ``v`` solves ``M v = H r + f`` with ``M`` as given, ``u = H^T v + w``; the error is the
        natural-map error of ``(r, u)``, the equilibrium the relative residual of the first
        equation, and :class:`AccuracyLimits` says how far the conditioning of ``M`` (and the
        data's digits) limit them.

        Raises
        ------
        InvalidInputError
            If ``r`` has the wrong length or is not finite.
        NotPositiveDefiniteError
            If ``M`` is singular.
        """
        local = self.condense() if local is None else local
        m = self.dim * self.n_contacts
        rv = finite_array(r, "r", 1)
        if rv.shape != (m,):
            raise InvalidInputError(
                f"r must have length dim*n_contacts = {m}, got shape {rv.shape}"
            )
        (M, H), f, w = self._read, self.f, self.w
        Hr = np.asarray(H @ rv).ravel()
        if M.shape[0] == 0:
            v, equilibrium, s, condition = np.zeros(0), 0.0, np.zeros(0), 1.0
        else:
            factor = self._factor if factor is None else factor
            s, condition = factor.s, factor.condition
            v = factor.solve(Hr + f)
            Mv = np.asarray(M @ v).ravel()
            sizes = [np.linalg.norm(s * x) for x in (Mv, Hr, f)]
            equilibrium = float(np.linalg.norm(s * (Mv - Hr - f)) / (max(sizes) or 1.0))
        u = np.asarray(H.T @ v).ravel() + w
        error = natural_map_residual(local, rv, u)[1]
        scale = math.sqrt(max(local.q @ local.q, rv @ rv, u @ u)) or 1.0
        # rounding: the scaled unknown y = v / s is solved to ~cond * eps relative, u = H^T S y + w
        if is_sparse(H):
            import scipy.sparse as sp

            scaled_h = sp.diags(s) @ H
            size_h = float(np.sqrt(abs(scaled_h).power(2).sum()))  # Frobenius: >= the 2-norm
        else:
            size_h = float(np.sqrt(((s[:, None] * H) ** 2).sum()))
        size_y = float(np.linalg.norm(v / s)) if v.size else 0.0
        transported = float(np.linalg.norm(_abs_product(H.T, v))) + float(np.linalg.norm(w))
        rounding = (condition * _EPS * size_h * size_y + _EPS * transported) / scale
        data = self._data_limit(rv, v, factor) / scale
        return GlobalCertificate(
            v=v,
            u=u,
            error=float(error),
            equilibrium=equilibrium,
            limits=AccuracyLimits(
                rounding=rounding, data=data, condition=condition, digits=dict(self.digits)
            ),
        )

    def _data_limit(self, r, v, factor=None) -> float:
        """Size of the change of ``u`` when the written values move by their rounding."""
        rel = {name: relative_rounding(self.digits.get(name)) for name in ("M", "H", "f", "w")}
        if not any(rel.values()):
            return 0.0
        M, H = self._read
        # first order: M dv = -dM v + dH r + df, du = H^T dv + dH^T v + dw
        forcing = rel["M"] * _abs_product(M, v) + rel["H"] * _abs_product(H, r)
        forcing += rel["f"] * np.abs(self.f)
        factor = self._factor if factor is None else factor
        moved = factor.solve(forcing) if M.shape[0] else forcing
        return float(
            np.linalg.norm(np.asarray(H.T @ moved).ravel())
            + rel["H"] * np.linalg.norm(_abs_product(H.T, v))
            + rel["w"] * np.linalg.norm(self.w)
        )


def condense_global(M, H, f, w, mu, dim, title="") -> LocalProblem:
    r"""Condense a global problem to its local form with one sparse LU factorisation of M.

    .. math::  W = H^T M^{-1} H, \qquad q = H^T M^{-1} f + w

    ``M^{-1} [H, f]`` is obtained by one ``scipy.sparse.linalg.splu`` factorisation (of the
    Jacobi-scaled ``M``) and multi-right-hand-side solves (by blocks of columns to bound
    memory). ``W`` is the problem's as given: it is not symmetrised, so an unsymmetric ``M``
    gives the unsymmetric ``W`` of the written equations.

    Parameters
    ----------
    M : scipy.sparse matrix or array_like, shape (ndof, ndof)
    H : scipy.sparse matrix or array_like, shape (ndof, m)
    f : array_like, shape (ndof,)
    w : array_like, shape (m,)
    mu : array_like, shape (n_contacts,), with ``m = dim * n_contacts``
    dim : int
        2 or 3.
    title : str, optional

    Returns
    -------
    LocalProblem
        ``W`` is a ``csr_matrix`` (exact zeros removed) when ``H`` is sparse, else an ndarray.

    Raises
    ------
    InvalidInputError
        On inconsistent shapes or non-finite values.
    NotPositiveDefiniteError
        If ``M`` is singular: exactly, or numerically (an LU pivot of the Jacobi-scaled
        ``M`` below ``ndof * eps`` times the largest one), or the solve is not finite.
    """
    return GlobalProblem(M, H, f, w, mu, dim, title).condense()


def projection_on_cones(x, mu, dim):
    """Project, contact by contact, on the Coulomb cones ``{||x_T|| <= mu x_N}``.

    Parameters
    ----------
    x : array_like, shape (dim * n_contacts,)
        Stacked contact vectors, normal component first in each block.
    mu : array_like, shape (n_contacts,)
        Friction coefficients, finite and ``>= 0``; ``mu = 0`` gives the ray
        ``{x_T = 0, x_N >= 0}``.
    dim : int
        2 or 3.

    Returns
    -------
    numpy.ndarray, shape (dim * n_contacts,)
        The Euclidean projection ``P_K(x)``.

    Notes
    -----
    Per contact, with ``t = ||x_T||``: inside the cone (``t <= mu x_N``, ``x_N >= 0``) ``x`` is
    kept; in the polar cone (``mu t <= -x_N``) the projection is 0; otherwise it is
    ``a (1, mu x_T / t)`` with ``a = (x_N + mu t) / (1 + mu^2)``.
    """
    dim = _check_dim(dim)
    muv = finite_array(mu, "mu", 1)
    xv = finite_array(x, "x", 1)
    nc = muv.shape[0]
    if xv.shape != (dim * nc,):
        raise InvalidInputError(
            f"x must have length dim*n_contacts = {dim * nc}, got shape {xv.shape}"
        )
    if np.any(muv < 0):
        raise InvalidInputError(f"mu must be >= 0, got min(mu) = {muv.min():g}")
    return project_rows(xv.reshape(nc, dim), muv).reshape(-1)


def project_rows(X, mu):
    """Row-wise :func:`projection_on_cones` of float arrays ``X`` (n, d), ``mu`` (n,), unchecked."""
    P = np.empty_like(X)
    kernels.project_rows(X, mu, P)
    return P


def _candidate(problem: LocalProblem, r, u):
    """Validated ``(r, u)`` of length ``m``; ``u = W r + q`` when not given."""
    m = problem.dim * problem.n_contacts
    rv = finite_array(r, "r", 1)
    if rv.shape != (m,):
        raise InvalidInputError(f"r must have length dim*n_contacts = {m}, got shape {rv.shape}")
    if u is None:
        return rv, np.asarray(problem.W @ rv).ravel() + problem.q
    uv = finite_array(u, "u", 1)
    if uv.shape != (m,):
        raise InvalidInputError(f"u must have length dim*n_contacts = {m}, got shape {uv.shape}")
    return rv, uv


def natural_map_error(problem: LocalProblem, r, u=None, *, per_contact: bool = False) -> float:
    r"""Relative natural-map error of a candidate solution (the current Siconos measure).

    .. math::

        e = \frac{\| \tilde r - P_K(\tilde r - (u + \mu \|u_T\| e_N)) \|}
                 {\max(\|q\|, \|r\|, \|u\|)},
        \qquad \tilde r = r + \frac{c}{\mu} e_N

    with :math:`P_K` the projection on the product of Coulomb cones
    (:func:`projection_on_cones`) and :math:`\tilde r` the reaction measured from the apex of
    the Mohr-Coulomb cone (:attr:`LocalProblem.apex_shift`; ``r`` itself without cohesion, the
    FCLIB measure). The numerator is zero exactly when ``(r, u)`` satisfies the law of
    :class:`LocalProblem`. The denominator is replaced by 1 when all three norms are 0.

    Units: the measure adds reactions and velocities (FCLIB's, with ``rho = 1``), so it weighs
    them alike only when ``W`` is O(1), as in FCLIB files. On a problem in newtons and metres
    with a stiff ``W`` (say 1e-6 m/N) the reactions dominate and a displacement error hardly
    shows: a reaction 1 % short, 1e-5 m of interpenetration, measures 2e-8. Solve such a
    problem made dimensionless, as :func:`~contactqp.solve` does for a ``FrictionalProblem``
    (:attr:`~contactqp.core.problem.FrictionStep.fclib`), whose certificate also checks the gaps
    in metres.

    Scale: the FCLIB measure is relative to the whole problem, so one contact with a wide gap
    (a large ``q_i``) loosens it for all the others. ``per_contact=True`` also measures each
    contact's residual against its own ``max(||q_i||, ||r_i||, ||u_i||)`` (at least
    :data:`CONTACT_FLOOR` times the denominator above) and returns the largest of these and
    ``e``.

    Parameters
    ----------
    problem : LocalProblem
    r : array_like, shape (m,)
        Reactions.
    u : array_like, shape (m,), optional
        Relative velocities; ``W r + q`` when not given.
    per_contact : bool
        Also hold every contact to its own scale (see above).

    Returns
    -------
    float
        0 exactly at a solution, positive otherwise.
    """
    return natural_map_residual(problem, *_candidate(problem, r, u), per_contact=per_contact)[1]


#: Smallest scale of one contact in ``natural_map_error(..., per_contact=True)``, relative to
#: the whole problem's: contacts whose reactions, velocities and free velocities are all below
#: it are measured against it. Rounding in ``u = W r + q`` is about 1e-16 of the problem's
#: scale, so a smaller floor could hold such a contact to less than its rounding at ``tol``
#: 1e-10.
CONTACT_FLOOR = 1e-6


def natural_map_residual(
    problem: LocalProblem, r, u, *, per_contact: bool = False
) -> tuple[float, float]:
    """``(residual, error)`` of float arrays ``r``, ``u`` of shape (m,), without checks.

    ``error`` is :func:`natural_map_error`; ``residual`` its numerator, an absolute measure
    that, unlike the ratio, does not fall when ``r`` grows without bound (on a problem with no
    solution): solvers accept steps on it.
    """
    return cone_residual(
        problem.q, problem.mu, problem.dim, r + problem.apex_shift, u, r, per_contact=per_contact
    )


def cone_residual(
    q: np.ndarray,
    mu: np.ndarray,
    dim: int,
    shifted: np.ndarray,
    u: np.ndarray,
    r: np.ndarray,
    *,
    per_contact: bool = False,
) -> tuple[float, float]:
    """``(residual, error)`` of :func:`natural_map_residual` from the arrays it reads: ``q``,
    ``mu``, ``dim``, the reactions from the apex ``shifted`` (``r + apex_shift``), ``u`` and
    ``r`` (float arrays of shape (m,), unchecked), without the problem's ``W``: for a caller
    that has ``u`` already (a certificate, from the returned displacements)."""
    d = dim
    R = shifted.reshape(-1, d)
    squares = np.empty(R.shape[0])
    residual = math.sqrt(kernels.natural_map_rows(R, u.reshape(-1, d), mu, squares))
    scale = math.sqrt(max(q @ q, r @ r, u @ u)) or 1.0
    error = residual / scale
    if per_contact and squares.size:
        own = np.maximum.reduce([_row_squares(q, d), _row_squares(r, d), _row_squares(u, d)])
        floor = (CONTACT_FLOOR * scale) ** 2
        error = max(error, math.sqrt(np.max(squares / np.maximum(own, floor))))
    return residual, error


def _row_squares(x, d):
    """Squared norm of each contact's block of ``x``."""
    X = x.reshape(-1, d)
    return np.einsum("ij,ij->i", X, X)


def contact_status(problem: LocalProblem, r, u=None, rtol: float = STATUS_RTOL) -> np.ndarray:
    """Per-contact status of a solution: open, stick or slip
    (:class:`~contactqp.core.status.ContactStatus` codes).

    A contact is open when its reaction, measured from the cone apex
    (``r + apex_shift``), is zero; otherwise it slips when its tangential velocity is nonzero,
    else it sticks (the rule of :meth:`~contactqp.core.friction.FrictionLaw.status`). "Zero" is
    relative and in the units of each quantity: a reaction is zero below ``rtol * F`` and a
    velocity below ``rtol * w F``, with ``w`` the largest diagonal entry of ``W`` and
    ``F = max(||r||, ||r + apex_shift||, ||q|| / w, ||u|| / w)``, so that the labels do not
    change with the units of ``r`` and ``u`` (a problem in newtons and metres, with ``W`` of
    1e-6 m/N, labels its slips as the same problem made dimensionless does).

    Parameters
    ----------
    problem : LocalProblem
    r : array_like, shape (m,)
    u : array_like, shape (m,), optional
        ``W r + q`` when not given.
    rtol : float
        Relative threshold for "zero".

    Returns
    -------
    numpy.ndarray of int, shape (n_contacts,)
    """
    rv, uv = _candidate(problem, r, u)
    return contact_status_unchecked(problem, rv, uv, rtol)


def contact_status_unchecked(problem: LocalProblem, r, u, rtol: float = STATUS_RTOL) -> np.ndarray:
    """:func:`contact_status` of float arrays ``r``, ``u`` of shape (m,), without checks (for
    methods, whose arrays are their own)."""
    d = problem.dim
    nc = problem.n_contacts
    w = problem._largest_diagonal
    size = math.sqrt(r @ r)
    shift = problem.apex_shift
    apex = r + shift
    largest = max(
        size,
        math.sqrt(apex @ apex),
        math.sqrt(problem.q @ problem.q) / w,
        math.sqrt(u @ u) / w,
    )
    force = largest if largest > 0 else 1.0
    return problem.law.status(
        r.reshape(nc, d), u.reshape(nc, d)[:, 1:], rtol * force, rtol * w * force
    )


#: A sparse matrix of at most this size, or at least this full, is factored dense (LAPACK beats
#: SuperLU and scipy.sparse's per-call costs there).
DENSE_SIZE, DENSE_FILL = 200, 0.1


def better_dense(W) -> bool:
    """True when a sparse ``W`` is better factored as a dense array (:data:`DENSE_SIZE`)."""
    m = W.shape[0]
    return m <= DENSE_SIZE or W.nnz >= DENSE_FILL * m * m


def check_diagonal(S, name: str = "W") -> np.ndarray:
    """The diagonal of a symmetric ``S`` (dense or sparse), checked as a semidefinite one's.

    The two tests of :func:`check_positive_semidefinite` that need no factorisation, at the cost
    of reading the diagonal and the rows whose diagonal entry is zero: no diagonal entry is
    negative, and a row with a zero diagonal entry is zero.

    Raises
    ------
    NotPositiveDefiniteError
        Naming ``name`` and the failed test.
    """
    diag = np.asarray(S.diagonal(), dtype=float)
    if np.any(diag < 0):
        i = int(np.argmin(diag))
        raise NotPositiveDefiniteError(
            f"{name} is not positive semidefinite: diagonal entry {i} is {diag[i]:.3g} < 0"
        )
    zero_rows = np.flatnonzero(diag == 0)
    if zero_rows.size:
        rows = S[zero_rows]
        if np.count_nonzero(rows) if isinstance(rows, np.ndarray) else rows.count_nonzero():
            raise NotPositiveDefiniteError(
                f"{name} is not positive semidefinite: a row with a zero diagonal entry "
                f"has nonzero off-diagonal entries"
            )
    return diag


def small_semidefinite(W: np.ndarray) -> np.ndarray:
    """Whether each of small dense matrices ``W`` (shape (P, m, m), C-contiguous) passes
    :func:`check_positive_semidefinite`'s test, shape (P,) of bool, by the compiled kernel
    (one unblocked Cholesky factorisation each, no numpy call per matrix)."""
    if kernels.small_semidefinite is None:
        raise InvalidInputError("small_semidefinite needs the compiled kernels")
    passed = np.zeros(W.shape[0], dtype=np.intp)
    kernels.small_semidefinite(W, PSD_SHIFT, passed)
    return passed.astype(bool)


def check_positive_semidefinite(W, name: str = "W") -> None:
    r"""Raise unless the symmetric part of ``W`` is positive semidefinite (to a small shift).

    What is checked, with :math:`S = (W + W^T)/2` and :math:`D = \mathrm{diag}(S)`:

    * no diagonal entry is negative, and a row with a zero diagonal entry is zero;
    * the Jacobi-scaled :math:`D^{-1/2} S D^{-1/2} + \delta I` (rows with a zero diagonal left
      out, :math:`\delta` = :data:`PSD_SHIFT`) has a Cholesky factorisation: dense LAPACK
      ``potrf``, or for a sparse ``W`` a SuperLU factorisation with symmetric (diagonal)
      pivoting whose pivots must all be positive (Sylvester's law of inertia).

    The cost is one factorisation, less than one Newton iteration of the friction solver.

    Raises
    ------
    NotPositiveDefiniteError
        With the failed test in the message.
    """
    S = 0.5 * (W + W.T)
    if not isinstance(S, np.ndarray) and better_dense(S):
        S = S.toarray()
    diag = check_diagonal(S, name)
    keep = np.flatnonzero(diag > 0)
    if keep.size == 0:
        return
    s = 1.0 / np.sqrt(diag[keep])
    if not isinstance(S, np.ndarray):
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        Sk = sp.csc_matrix(S)[keep][:, keep]
        scaled = sp.csc_matrix(sp.diags(s) @ Sk @ sp.diags(s) + PSD_SHIFT * sp.identity(keep.size))
        try:
            lu = splu(
                scaled,
                permc_spec="MMD_AT_PLUS_A",
                diag_pivot_thresh=0.0,
                options={"SymmetricMode": True},
            )
            pivots = lu.U.diagonal()
            ok = np.array_equal(lu.perm_r, lu.perm_c) and bool(np.all(pivots > 0))
        except RuntimeError:  # exactly singular
            ok = False
    else:
        import scipy.linalg

        scaled = s[:, None] * S[np.ix_(keep, keep)] * s[None, :] + PSD_SHIFT * np.eye(keep.size)
        try:
            scipy.linalg.cholesky(scaled, check_finite=False)
            ok = True
        except np.linalg.LinAlgError:
            ok = False
    if not ok:
        raise NotPositiveDefiniteError(
            f"{name} ({W.shape[0]}x{W.shape[1]}) is not positive semidefinite: the Cholesky "
            f"factorisation of its Jacobi-scaled symmetric part + {PSD_SHIFT:g} I fails"
        )

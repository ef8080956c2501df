r"""Global problems ``M v = H r + f, u = H^T v + w`` condensed exactly, without dense solves.

:meth:`~contactqp.core.local_problem.GlobalProblem.condense` forms ``W = H^T M^{-1} H`` by a
sparse LU factorisation of ``M`` and one solve per column of ``H`` into a dense array: ``ndof``
by ``m`` numbers, however sparse ``M^{-1} H`` is. That is what a general ``M`` needs, and it is
the cost of the global files of rigid bodies (``ndof`` 12,000 on Spheres-i099), whose ``M`` is
diagonal: there ``M^{-1}`` is known exactly and ``W`` is a sparse product.

:func:`condense` factors ``M`` once, by its structure (:func:`factor_mass`):

* block diagonal with blocks of at most :data:`BLOCK_MAX` freedoms (diagonal: blocks of 1; a
  rigid body's mass and inertia: 6): each block inverted exactly (LAPACK, per block), ``M^{-1}``
  a sparse block-diagonal matrix, ``W = H^T M^{-1} H`` and ``q = H^T M^{-1} f + w`` sparse
  products (:class:`BlockDiagonalMass`);
* otherwise, at most :data:`DENSE_FREEDOMS` freedoms: a dense LU factorisation of the
  Jacobi-scaled ``M`` and dense solves (:class:`DenseMass`: LAPACK beats SuperLU's per-call
  costs on the small finite-element files);
* otherwise the problem's own sparse LU factorisation and condensation.

A problem solved by the default method is done in one compiled call (:func:`solve_compiled`)
when its contacts fall into groups that ``W`` couples of at most
:data:`~contactqp.core.local_problem.SMALL_UNKNOWNS` unknowns each, and ``M`` is either block
diagonal (any size: the groups are read from ``H``, contacts that share no body are apart, and
only the groups' blocks of ``W`` are formed) or of at most :data:`DENSE_FREEDOMS` freedoms with
at most :data:`COMPILED_UNKNOWNS` contact unknowns. The call makes the same factorisation of
``M`` (LAPACK's, through scipy) and condensation, runs coulomb's Newton on each group and
certifies the answer on the global equations. The groups whose Newton runs stop short are
solved again together by coulomb's whole route, the others keeping their answers. Whatever the
call does not finish otherwise (a larger group, a singular ``M``, a ``W`` that fails the
semidefiniteness test, every group's run stopping short) is done again by the general route,
from the start; a group too large for the call is found from ``H`` before ``M`` is factored.

Each factor records the Jacobi scaling ``s = |diag M|^{-1/2}`` and the exact 1-norm condition of
the scaled ``M``, and refuses a singular ``M`` (a singular block, or an LU pivot below
``ndof * eps`` of the largest) with :class:`~contactqp.errors.NotPositiveDefiniteError`, as
the sparse factorisation does. The answer is certified on the global equations as written, with
the same factor (:meth:`~contactqp.core.local_problem.GlobalProblem.certify`): ``v`` solves
``M v = H r + f``, ``u = H^T v + w``, and the natural-map error and the equilibrium residual
must both meet ``tol``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import kernels
from ..core.local_problem import (
    CONTACT_FLOOR,
    DENSE_FILL,
    DENSE_SIZE,
    SMALL_UNKNOWNS,
    STATUS_RTOL,
    AccuracyLimits,
    GlobalCertificate,
    GlobalProblem,
    LocalProblem,
    better_dense,
    relative_rounding,
)
from ..core.model import iteration_cap, positive_tolerance, warm_start
from ..core.operators import PSD_SHIFT
from ..core.result import LocalResult
from ..errors import NotPositiveDefiniteError
from .coulomb import MAX_ITER, RUN_ITERATIONS, solve_coulomb
from .local_global import compiled_global_result

if TYPE_CHECKING:
    import scipy.sparse as sp

__all__ = [
    "BLOCK_MAX",
    "COMPILED_UNKNOWNS",
    "DENSE_ENTRIES",
    "DENSE_FREEDOMS",
    "BlockDiagonalMass",
    "Condensed",
    "DenseMass",
    "MassFactor",
    "block_size",
    "certify_compiled",
    "condense",
    "factor_mass",
    "solve_compiled",
]

BLOCK_MAX = 12  #: largest diagonal block of a block-diagonal ``M`` inverted block by block
DENSE_FREEDOMS = 400  #: a general ``M`` of at most this many freedoms is factored dense
DENSE_ENTRIES = 1 << 18  #: sparse ``M`` and ``H`` of at most this many entries are read dense
#: Most contact unknowns ``m`` of a problem with a dense ``M`` that :func:`solve_compiled`
#: takes (``W`` is formed dense there: 2.9 MB). With a block-diagonal ``M`` only the blocks of
#: the groups of contacts that ``W`` couples are formed: at most ``SMALL_UNKNOWNS`` numbers per
#: contact unknown when solving, this number squared (or that) when only certifying.
COMPILED_UNKNOWNS = 600
_EPS = float(np.finfo(float).eps)
_SOLVED, _NOT_CONVERGED = 0, 4  # codes of the compiled kernel (kernels.GLOBAL_CODES)


class MassFactor:
    """An exact factorisation of ``M``: what condensation and the certificate need.

    Attributes
    ----------
    s : numpy.ndarray, shape (ndof,)
        Jacobi scaling ``|diag M|^{-1/2}`` (1 where the diagonal is 0).
    condition : float
        1-norm condition number of the scaled ``S M S``.
    """

    s: np.ndarray
    condition: float
    #: True when ``M`` was found symmetric positive definite (then ``W = H^T M^-1 H`` is
    #: positive semidefinite by construction, and no factorisation of ``W`` need check it)
    positive_definite: bool = False

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``M^{-1} rhs`` for ``rhs`` of shape (ndof,) or (ndof, k)."""
        raise NotImplementedError


def _scaling(diagonal: np.ndarray) -> np.ndarray:
    size = np.abs(diagonal)
    s = np.ones(diagonal.shape[0])
    s[size > 0] = 1.0 / np.sqrt(size[size > 0])
    return s


def _singular(ndof: int, detail: str) -> NotPositiveDefiniteError:
    return NotPositiveDefiniteError(f"M ({ndof}x{ndof}) is {detail}")


class BlockDiagonalMass(MassFactor):
    """``M`` block diagonal with equal blocks of ``size`` freedoms, each inverted exactly.

    Parameters
    ----------
    M : scipy.sparse matrix or numpy.ndarray, shape (ndof, ndof)
        Nonzero only in its diagonal blocks (:func:`block_size`).
    size : int
        The blocks' size; ``ndof`` is a multiple of it.

    Raises
    ------
    NotPositiveDefiniteError
        A block is singular, exactly or numerically (the scaled block's condition number
        above ``1 / (ndof eps)``).
    """

    def __init__(self, M, size: int):
        ndof = M.shape[0]
        self.size = size
        n_blocks = ndof // size
        if size == 1:
            diagonal = np.asarray(M.diagonal(), dtype=float)
            if np.any(diagonal == 0):
                raise _singular(
                    ndof, f"singular: diagonal entry {int(np.argmin(diagonal != 0))} is 0"
                )
            self.s = _scaling(diagonal)
            self.inverse = (1.0 / diagonal).reshape(n_blocks, 1, 1)
            self.condition = 1.0  # S M S = diag(sign M_ii)
            self.positive_definite = bool(np.all(diagonal > 0))
            return
        blocks = _diagonal_blocks(M, size)
        self.s = _scaling(np.einsum("bii->bi", blocks).reshape(-1))
        s = self.s.reshape(n_blocks, size)
        scaled = s[:, :, None] * blocks * s[:, None, :]
        try:
            inverse_scaled = np.linalg.inv(scaled)
        except np.linalg.LinAlgError:
            raise _singular(ndof, "singular: a diagonal block is singular") from None
        norm = float(np.abs(scaled).sum(axis=1).max())
        inverse_norm = float(np.abs(inverse_scaled).sum(axis=1).max())
        self.condition = norm * inverse_norm
        if not np.isfinite(self.condition) or self.condition * ndof * _EPS >= 1.0:
            raise _singular(
                ndof,
                f"numerically singular: a scaled diagonal block has condition {self.condition:.3g}",
            )
        self.inverse = s[:, :, None] * inverse_scaled * s[:, None, :]
        self.positive_definite = _positive_definite(blocks, scaled)

    def matrix(self) -> sp.csr_matrix:
        """``M^{-1}``, sparse (block diagonal)."""
        import scipy.sparse as sp

        n_blocks, size = self.inverse.shape[0], self.size
        if size == 1:
            return sp.csr_matrix(sp.diags(self.inverse.reshape(-1)))
        return sp.bsr_matrix(
            (self.inverse, np.arange(n_blocks), np.arange(n_blocks + 1)),
            shape=(n_blocks * size, n_blocks * size),
        ).tocsr()

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``M^{-1} rhs``, block by block."""
        n_blocks, size = self.inverse.shape[0], self.size
        if size == 1:
            inverse = self.inverse.reshape(-1)
            return inverse * rhs if rhs.ndim == 1 else inverse[:, None] * rhs
        shaped = rhs.reshape(n_blocks, size, -1)
        return np.matmul(self.inverse, shaped).reshape(rhs.shape)


def _positive_definite(blocks: np.ndarray, scaled: np.ndarray) -> bool:
    """Whether every matrix of the stack ``blocks`` (k, n, n) is exactly symmetric and its
    Jacobi-scaled twin in ``scaled`` has a Cholesky factorisation."""
    if not np.array_equal(blocks, np.swapaxes(blocks, 1, 2)):
        return False
    try:
        np.linalg.cholesky(scaled)
    except np.linalg.LinAlgError:
        return False
    return True


def _diagonal_blocks(M, size: int) -> np.ndarray:
    """The diagonal blocks of ``M``, shape (ndof / size, size, size)."""
    ndof = M.shape[0]
    n_blocks = ndof // size
    if isinstance(M, np.ndarray):
        shaped = M.reshape(n_blocks, size, n_blocks, size)
        index = np.arange(n_blocks)
        return np.array(shaped[index, :, index, :])
    import scipy.sparse as sp

    bsr = sp.bsr_matrix(M, blocksize=(size, size))
    bsr.sort_indices()
    blocks = np.zeros((n_blocks, size, size))
    rows = np.repeat(np.arange(n_blocks), np.diff(bsr.indptr))
    blocks[rows[bsr.indices == rows]] = bsr.data[bsr.indices == rows]
    return blocks


class DenseMass(MassFactor):
    """Cholesky (exactly symmetric ``M``) or else LU factorisation (LAPACK) of the
    Jacobi-scaled dense ``S M S``.

    The singularity test and the scaling are those of the problem's sparse factorisation (a
    pivot below ``ndof * eps`` times the largest: for Cholesky, the squares of the factor's
    diagonal); the condition number is LAPACK's estimate from the factor (``pocon`` /
    ``gecon``), the 1-norm one of the sparse factorisation's ``onenormest``.

    Raises
    ------
    NotPositiveDefiniteError
        ``M`` singular, numerically or exactly.
    """

    def __init__(self, M: Any):
        import scipy.linalg

        ndof = M.shape[0]
        dense = np.array(M if isinstance(M, np.ndarray) else M.toarray(), dtype=np.float64)
        self.s = _scaling(np.diagonal(dense).copy())
        scaled = self.s[:, None] * dense * self.s[None, :]
        self._norm = float(np.abs(scaled).sum(axis=0).max())
        self.cholesky = None
        if np.array_equal(dense, dense.T):
            try:
                self.cholesky = scipy.linalg.cho_factor(scaled, check_finite=False)
            except np.linalg.LinAlgError:
                pass
        if self.cholesky is not None:
            pivots = np.diagonal(self.cholesky[0]) ** 2
            self.positive_definite = True
        else:
            self.lu = scipy.linalg.lu_factor(scaled, check_finite=False)
            pivots = np.abs(np.diagonal(self.lu[0]))
        if not np.all(np.isfinite(pivots)) or pivots.min() <= ndof * _EPS * pivots.max():
            raise _singular(
                ndof,
                "numerically singular: smallest/largest pivot of the scaled matrix = "
                f"{pivots.min() / pivots.max():.3g}",
            )

    @functools.cached_property
    def condition(self) -> float:  # type: ignore[override]
        """1-norm condition number of ``S M S``, estimated by LAPACK from the factor."""
        import scipy.linalg

        if self.cholesky is not None:
            rcond, _ = scipy.linalg.lapack.dpocon(self.cholesky[0], self._norm)
        else:
            rcond, _ = scipy.linalg.lapack.dgecon(self.lu[0], self._norm, norm="1")
        return 1.0 / rcond if rcond > 0 else float("inf")

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``M^{-1} rhs = S (S M S)^{-1} S rhs``."""
        import scipy.linalg

        sc = self.s[:, None] if rhs.ndim == 2 else self.s
        if self.cholesky is not None:
            return sc * scipy.linalg.cho_solve(self.cholesky, sc * rhs, check_finite=False)
        return sc * scipy.linalg.lu_solve(self.lu, sc * rhs, check_finite=False)


class _ProblemFactor(MassFactor):
    """The problem's own sparse LU factorisation (a general, large ``M``)."""

    def __init__(self, problem: GlobalProblem):
        self._factor = problem._factor
        self.s = self._factor.s

    @functools.cached_property
    def condition(self) -> float:  # type: ignore[override]
        """As the problem's factorisation computes it (estimated above 100 freedoms)."""
        return self._factor.condition

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        return self._factor.solve(rhs)


def block_size(M) -> int | None:
    """The smallest ``k <=`` :data:`BLOCK_MAX` dividing ``ndof`` such that ``M`` is nonzero only
    in its diagonal ``k x k`` blocks (1: diagonal), or None."""
    ndof = M.shape[0]
    if isinstance(M, np.ndarray):
        rows, cols = np.nonzero(M)
    else:
        import scipy.sparse as sp

        csr: Any = sp.csr_matrix(M)
        keep = csr.data != 0
        rows = np.repeat(np.arange(ndof), np.diff(csr.indptr))[keep]
        cols = csr.indices[keep]
    if np.array_equal(rows, cols):
        return 1
    spread = int(np.abs(rows - cols).max(initial=0))
    for k in range(max(2, spread + 1), BLOCK_MAX + 1):
        if ndof % k == 0 and np.array_equal(rows // k, cols // k):
            return k
    return None


def _is_diagonal(M) -> bool:
    """Whether a CSR ``M`` stores nothing off its diagonal (read from its index arrays)."""
    rows = np.repeat(np.arange(M.shape[0]), np.diff(M.indptr))
    return bool(np.array_equal(rows, M.indices))


def factor_mass(problem: GlobalProblem) -> MassFactor:
    """The factorisation :func:`condense` uses for ``problem.M`` (see the module notes).

    A sparse ``M`` of at most :data:`DENSE_ENTRIES` entries is read dense (numpy's cost per
    call is a microsecond, scipy.sparse's some tens).
    """
    M: Any = problem.M
    ndof = M.shape[0]
    if not isinstance(M, np.ndarray):
        if _is_diagonal(M):
            return BlockDiagonalMass(M, 1)
        if ndof * ndof <= DENSE_ENTRIES:
            M = M.toarray()
    size = block_size(M)
    if size is not None:
        return BlockDiagonalMass(M, size)
    if ndof <= DENSE_FREEDOMS:
        return DenseMass(M)
    return _ProblemFactor(problem)


@dataclass(frozen=True)
class Condensed:
    """A global problem's local form and the factorisation of ``M`` that gave it.

    Attributes
    ----------
    local : LocalProblem
        ``W = H^T M^{-1} H`` (dense where :func:`~contactqp.core.local_problem.better_dense`
        prefers it or ``H`` is dense, else CSR), ``q = H^T M^{-1} f + w``.
    factor : MassFactor
    """

    local: LocalProblem
    factor: MassFactor


def condense(problem: GlobalProblem) -> Condensed:
    """``problem``'s local form through :func:`factor_mass`; ``M^{-1}`` is never formed dense
    for a block-diagonal ``M``.

    Raises
    ------
    NotPositiveDefiniteError
        If ``M`` is singular.
    """
    M, H = problem.M, problem.H
    if M.shape[0] == 0:
        return Condensed(problem.condense(), _ProblemFactor(problem))
    factor = factor_mass(problem)
    if isinstance(factor, _ProblemFactor):
        return Condensed(problem.condense(), factor)
    W: Any
    ndof, m = H.shape
    f = problem.f
    if isinstance(H, np.ndarray) or ndof * m <= DENSE_ENTRIES:
        Hd = H if isinstance(H, np.ndarray) else H.toarray()
        W = Hd.T @ factor.solve(Hd)
        q = Hd.T @ factor.solve(f) + problem.w
        if not isinstance(H, np.ndarray) and not (
            m <= DENSE_SIZE or np.count_nonzero(W) >= DENSE_FILL * m * m
        ):  # CSR where the problem's condensation gives CSR that the local methods keep
            import scipy.sparse as sp

            W = sp.csr_matrix(W)
    else:  # a block-diagonal M (a general one was condensed by the problem)
        import scipy.sparse as sp

        assert isinstance(factor, BlockDiagonalMass)
        Hc: Any = sp.csr_matrix(H)
        W = sp.csr_matrix(Hc.T @ (factor.matrix() @ Hc))
        W.eliminate_zeros()
        if better_dense(W):
            W = W.toarray()
        q = np.asarray(Hc.T @ factor.solve(f)).ravel() + problem.w
    if not (
        np.all(np.isfinite(W if isinstance(W, np.ndarray) else W.data)) and np.all(np.isfinite(q))
    ):
        raise NotPositiveDefiniteError(
            f"M ({M.shape[0]}x{M.shape[0]}) is singular: the solve is not finite"
        )
    return Condensed(LocalProblem(W, q, problem.mu, problem.dim, problem.title), factor)


def _csr_arrays(A) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(indptr, indices, data)`` of ``A`` in compressed rows (scipy's int32 or int64
    indices, as stored)."""
    import scipy.sparse as sp

    csr: Any = A if sp.issparse(A) else sp.csr_matrix(A)
    return csr.indptr, csr.indices, csr.data


def solve_compiled(
    problem: GlobalProblem,
    start: float,
    *,
    r0=None,
    tol: float = 1e-8,
    max_iter: int = MAX_ITER,
    check_psd: bool = True,
    per_contact: bool = False,
) -> LocalResult | None:
    """``coulomb``'s answer to a small global problem in one compiled call, or None when the
    general route must give it (see the module notes).

    The options are ``coulomb``'s (:func:`~contactqp.methods.coulomb.solve_coulomb`), checked
    alike; ``start`` is the ``time.perf_counter()`` of the solve. The answer is that of the
    general route up to rounding: the same factorisation of ``M`` and condensation, the same
    Newton iterations (on each group of contacts that ``W`` couples, to ``tol / sqrt(3)`` when
    there are several, which bounds the whole problem's error by ``tol``), and the certificate
    of :meth:`~contactqp.core.local_problem.GlobalProblem.certify` computed from ``r``.

    Raises
    ------
    InvalidInputError
        On a bad ``tol``, ``max_iter`` or ``r0``.
    """
    global_small = kernels.global_small
    if global_small is None:
        return None
    ndof, m = problem.H.shape
    if ndof == 0 or m == 0:
        return None
    if not (type(tol) is float and 0.0 < tol < math.inf):
        tol = positive_tolerance(tol)
    if not (type(max_iter) is int and max_iter >= 1):
        max_iter = iteration_cap(max_iter)
    given = np.zeros(m) if r0 is None else np.array(warm_start(r0, m), dtype=float)
    r = given.copy()
    code, outputs = _run_kernel(
        global_small, problem, r, tol, min(RUN_ITERATIONS, max_iter), per_contact, check_psd, True
    )
    if code == _NOT_CONVERGED:
        restart = None if r0 is None else given
        return _groups_left(
            problem, r, restart, outputs, tol, max_iter, check_psd, per_contact, start
        )
    if outputs is None:
        return None
    return compiled_global_result(problem, r, *outputs, tol, bool(per_contact), start)


def _groups_left(
    problem: GlobalProblem, r, given, outputs, tol, max_iter, check_psd, per_contact, start
) -> LocalResult | None:
    """The answer when the compiled Newton runs of some groups of contacts stopped short.

    Those groups (the contacts of ``status`` -1) are solved together by coulomb's whole route
    (its rounds of Newton, Levenberg-Marquardt and the proximal stage) on their block of the
    condensed problem, from the caller's start ``given`` (None: coulomb's own), to
    ``tol / sqrt(3)`` as each group was; the others keep the compiled runs' reactions, and the
    whole answer is certified by the kernel. None (the general route from the start) when
    every group stopped short, or the whole does not meet ``tol``.
    """
    _, _, status, measures = outputs
    left = status < 0
    if left.all():
        return None
    d = problem.dim
    rows = np.flatnonzero(np.repeat(left, d))
    local = condense(problem).local
    W = local.W[np.ix_(rows, rows)] if isinstance(local.W, np.ndarray) else local.W[rows][:, rows]
    part = solve_coulomb(
        LocalProblem(W, local.q[rows], problem.mu[left], d),
        r0=None if given is None else given[rows],
        tol=tol / math.sqrt(3.0),
        max_iter=max_iter,
        check_psd=check_psd,
        per_contact=per_contact,
    )
    if not part.success:
        return None
    r[rows] = np.asarray(part.forces, dtype=float).reshape(-1)
    code, certified = _run_kernel(
        kernels.global_small, problem, r, 1.0, 1, per_contact, False, False
    )
    if code or certified is None:
        return None
    error, equilibrium = certified[3][:2].tolist()
    if not (error <= tol and equilibrium <= tol):
        return None
    return compiled_global_result(
        problem,
        r,
        *certified,
        tol,
        bool(per_contact),
        start,
        iterations=max(int(measures[9]), part.iterations),
        detail=f"newton {int(measures[9])} it. (converged) on the {int(measures[10])} groups of "
        f"contacts that W does not couple but those of {int(left.sum())} contacts, whose runs "
        f"stopped short; those solved again together by coulomb: {part.message}",
    )


def certify_compiled(problem: GlobalProblem, r) -> GlobalCertificate | None:
    """:meth:`~contactqp.core.local_problem.GlobalProblem.certify` of reactions ``r`` with the
    factorisation of ``M`` that :func:`condense` makes, computed by the compiled route's kernel;
    None where that route does not take ``problem`` (or without the compiled kernels).

    The same figures up to rounding (the sums in another order): what the compiled route's
    answers carry, and what its tests compare with the Python certificate.

    Raises
    ------
    InvalidInputError
        If ``r`` has the wrong length or is not finite.
    """
    global_small = kernels.global_small
    m = problem.H.shape[1]
    rv = np.array(warm_start(r, m, "r"), dtype=float)
    if global_small is None or problem.H.shape[0] == 0 or m == 0:
        return None
    _, outputs = _run_kernel(global_small, problem, rv, 1.0, 1, False, False, False)
    if outputs is None:
        return None
    u, v, _, measures = outputs
    error, equilibrium, rounding, data, condition = measures[:5].tolist()
    limits = AccuracyLimits(
        rounding=rounding, data=data, condition=condition, digits=dict(problem.digits)
    )
    return GlobalCertificate(v=v, u=u, error=error, equilibrium=equilibrium, limits=limits)


def _run_kernel(
    global_small, problem: GlobalProblem, r, tol, max_iter, per_contact, check_psd, solve
) -> tuple[int, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None]:
    """The code of :func:`~contactqp.kernels.compiled.global_small` on ``problem`` from ``r``
    (overwritten by the reactions), and its outputs ``(u, v, status, measures)``: None when it
    did not finish, but for "not converged" (then ``status`` and ``measures`` say which
    groups stopped short)."""
    ndof, m = problem.H.shape
    digits = problem.digits
    rel = (
        np.array([relative_rounding(digits.get(name)) for name in ("M", "H", "f", "w")])
        if digits
        else np.zeros(4)
    )
    u, v = np.empty(m), np.empty(ndof)
    status = np.empty(problem.n_contacts, dtype=np.intp)
    measures = np.empty(len(kernels.GLOBAL_MEASURES))
    code = global_small(
        *_csr_arrays(problem.M),
        *_csr_arrays(problem.H),
        np.ascontiguousarray(problem.f),
        np.ascontiguousarray(problem.w),
        np.ascontiguousarray(problem.mu),
        r,
        tol,
        max_iter,
        bool(per_contact),
        CONTACT_FLOOR,
        bool(check_psd),
        PSD_SHIFT,
        rel,
        STATUS_RTOL,
        solve,
        COMPILED_UNKNOWNS,
        DENSE_FREEDOMS,
        BLOCK_MAX,
        SMALL_UNKNOWNS,
        u,
        v,
        status,
        measures,
    )
    finished = code in (_SOLVED, _NOT_CONVERGED)
    return code, (u, v, status, measures) if finished else None

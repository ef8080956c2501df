"""Many independent small local problems ``u_p = W_p r_p + q_p`` of one size, solved together.

A :class:`LocalBatch` holds ``P`` FCLIB local problems
(:class:`~contactqp.core.local_problem.LocalProblem`, Coulomb cones, no cohesion) of ``k``
contacts each, stacked: the samples of a
variation study, the contacts of many independent bodies. :func:`~contactqp.solve` solves them
with the method ``coulomb-batch`` (:mod:`contactqp.methods.batch`) and returns a
:class:`LocalBatchResult`: per problem its reactions, velocities, natural-map error, verdict and
contact status, each problem certified on its own data as :func:`~contactqp.solve` certifies
that problem alone.
"""

from __future__ import annotations

import operator
from dataclasses import dataclass, field

import numpy as np

from ..errors import InvalidInputError
from .local_problem import LocalProblem
from .model import real_array
from .status import status_labels

__all__ = ["LocalBatch", "LocalBatchResult"]


def _stacked(value, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a C-contiguous float array of ``shape``, finite (one check for the stack)."""
    array = np.ascontiguousarray(real_array(value, name), dtype=float)
    if array.shape != shape:
        raise InvalidInputError(f"{name} must have shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        bad = np.flatnonzero(~np.isfinite(array.reshape(shape[0], -1)).all(axis=1))[0]
        raise InvalidInputError(f"{name} contains NaN or inf (problem {bad})")
    return array


@dataclass(frozen=True)
class LocalBatch:
    """``P`` local frictional-contact problems of ``k`` contacts each, in FCLIB form.

    Problem ``p`` is ``LocalProblem(W[p], q[p], mu[p], dim)`` (:meth:`problem`); solved
    together, they cost little more than their arithmetic.

    Parameters
    ----------
    W : array_like, shape (P, m, m)
        Delassus operators, ``m = dim * k``, dense.
    q : array_like, shape (P, m)
        Free velocities.
    mu : array_like, shape (P, k), (k,) or ()
        Friction coefficients ``>= 0``, broadcast to ``(P, k)``.
    dim : int
        2 or 3.

    Raises
    ------
    InvalidInputError
        Inconsistent shapes, NaN or inf, ``mu < 0``, ``dim`` not 2 or 3, or no problem.
    """

    kind = "local-batch"  # the problem kind (contactqp.methods.registry); not a field

    W: np.ndarray
    q: np.ndarray
    mu: np.ndarray
    dim: int = 3

    def __post_init__(self):
        try:
            dim = operator.index(self.dim)
        except TypeError:
            dim = 0
        if isinstance(self.dim, bool) or dim not in (2, 3):
            raise InvalidInputError(f"dim must be 2 or 3, got {self.dim!r}")
        W = real_array(self.W, "W")
        if W.ndim != 3 or W.shape[1] != W.shape[2] or W.shape[0] == 0:
            raise InvalidInputError(
                f"W must have shape (P, m, m) with P >= 1 problems, got {W.shape}"
            )
        P, m = W.shape[0], W.shape[1]
        if m == 0 or m % dim:
            raise InvalidInputError(f"W's size m = {m} must be dim * k = {dim} * k, k >= 1")
        k = m // dim
        W = _stacked(W, "W", (P, m, m))
        q = _stacked(self.q, "q", (P, m))
        mu_given = real_array(self.mu, "mu")
        try:
            mu_wide = np.broadcast_to(mu_given, (P, k))
        except ValueError:
            raise InvalidInputError(
                f"mu must have shape (P, k) = {(P, k)}, (k,) or (), got {mu_given.shape}"
            ) from None
        mu = _stacked(mu_wide, "mu", (P, k))
        if np.any(mu < 0):
            p = int(np.argmin(mu.min(axis=1)))
            raise InvalidInputError(f"mu must be >= 0, got {mu[p].min():g} in problem {p}")
        for name, value in (("W", W), ("q", q), ("mu", mu), ("dim", dim)):
            object.__setattr__(self, name, value)

    @property
    def n_problems(self) -> int:
        """``P``."""
        return int(self.W.shape[0])

    @property
    def n_contacts(self) -> int:
        """Contacts of each problem, ``k``."""
        return int(self.mu.shape[1])

    def problem(self, p: int) -> LocalProblem:
        """Problem ``p`` alone, as a :class:`~contactqp.core.local_problem.LocalProblem`."""
        return LocalProblem(self.W[p], self.q[p], self.mu[p], self.dim)


@dataclass(kw_only=True)
class LocalBatchResult:
    """The answers to a :class:`LocalBatch`, problem by problem (first axis ``P``).

    Attributes
    ----------
    forces : ndarray, shape (P, m)
        Reactions ``r`` of each problem.
    displacements : ndarray, shape (P, m)
        ``u = W r + q``, computed from ``r``.
    error : ndarray, shape (P,)
        Natural-map error of each problem
        (:func:`~contactqp.core.local_problem.natural_map_error`, on its own scale; with
        ``per_contact`` the largest of it and each contact's).
    success : ndarray of bool, shape (P,)
        ``error <= tol``.
    iterations : ndarray of int, shape (P,)
        Newton iterations plus Gauss-Seidel sweeps of each problem.
    contact_status : ndarray of int, shape (P, k)
        :class:`~contactqp.core.status.ContactStatus` codes (open, stick, slip).
    tol : float
    seconds : float
        Wall time of the whole batch.
    method : str
    messages : dict of int to str
        The account of each problem that needed more than the compiled Newton run (its index
        to the message of :func:`~contactqp.solve` on it alone).
    """

    forces: np.ndarray
    displacements: np.ndarray
    error: np.ndarray
    success: np.ndarray
    iterations: np.ndarray
    contact_status: np.ndarray
    tol: float
    seconds: float
    method: str
    messages: dict[int, str] = field(default_factory=dict)

    @property
    def n_problems(self) -> int:
        """``P``."""
        return int(self.success.shape[0])

    @property
    def all_solved(self) -> bool:
        """True when every problem's certificate passed."""
        return bool(np.all(self.success))

    @property
    def failed(self) -> np.ndarray:
        """Indices of the problems whose certificate failed."""
        return np.flatnonzero(~self.success)

    def status_labels(self, p: int) -> list[str]:
        """The label of each contact's status in problem ``p``."""
        return status_labels(self.contact_status[p])

    def summary(self) -> dict:
        """A JSON-ready summary: counts, the worst error, iterations and time."""
        return {
            "problems": self.n_problems,
            "solved": int(np.count_nonzero(self.success)),
            "worst_error": float(np.max(self.error, initial=0.0)),
            "max_iterations": int(np.max(self.iterations, initial=0)),
            "tol": self.tol,
            "seconds": self.seconds,
            "method": self.method,
        }

    def __repr__(self) -> str:
        solved = int(np.count_nonzero(self.success))
        return (
            f"LocalBatchResult(solved={solved}/{self.n_problems}, method={self.method!r}, "
            f"worst_error={float(np.max(self.error, initial=0.0)):.2e}, "
            f"seconds={self.seconds:.3g})"
        )

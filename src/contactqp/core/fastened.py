r"""Fastened problems: a frictionless contact problem with some rows closed by fasteners.

A fastener imposes closure: at its constraint row the gap is brought to zero and held there (a
bilateral constraint). Its multiplier ``lambda_f`` is free in sign: ``lambda_f >= 0`` is a
contact compression at the fastener, ``lambda_f < 0`` a tension ``-lambda_f`` carried by the
fastener. The fastener multipliers are eliminated once: with ``W`` of the dual
(:class:`~contactqp.core.problem.DualForm`) split into fastener (``f``) and contact (``c``) blocks
and ``q = A R P - Delta``,

.. math::

    \lambda_f = W_{ff}^{-1} (q_f - W_{fc} \lambda_c), \qquad
    \min_{\lambda_c \ge 0} \tfrac12 \lambda_c^T S \lambda_c
        - \lambda_c^T (q_c - W_{cf} W_{ff}^{-1} q_f),
    \quad S = W_{cc} - W_{cf} W_{ff}^{-1} W_{fc},

a frictionless contact dual whose Delassus operator ``S`` (a Schur complement, positive
definite) is that of the assembly with the fasteners closed. ``S`` depends on the fasteners
only, so :meth:`FastenedProblem.variant` shares it between gap fields. A method solves the
non-negative QP (see :mod:`contactqp.methods.fastened`); :meth:`FastenedProblem.make_result`
returns a certified result of the contact problem in which the fastener tensions are external
loads, the closure of each fastener checked separately.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError
from .model import real_array, warm_start
from .problem import ContactProblem
from .result import FastenedResult

__all__ = ["FastenedProblem"]


class _Reduction:
    """The elimination of the fastener rows of ``W``: factor, coupling and Schur complement."""

    def __init__(self, W: np.ndarray, rows: np.ndarray, contacts: np.ndarray):
        import scipy.linalg

        self.factor = scipy.linalg.cho_factor(W[np.ix_(rows, rows)])
        self.coupling = W[np.ix_(rows, contacts)]
        self.eliminated = scipy.linalg.cho_solve(self.factor, self.coupling)
        self.schur = W[np.ix_(contacts, contacts)] - self.coupling.T @ self.eliminated
        self._schur_cholesky: np.ndarray | None = None

    def schur_cholesky(self) -> np.ndarray:
        """Lower Cholesky factor of ``S``, computed on first use and kept."""
        if self._schur_cholesky is None:
            self._schur_cholesky = np.linalg.cholesky(self.schur)
        return self._schur_cholesky


class FastenedProblem:
    """A frictionless contact problem whose ``fasteners`` rows are closed (see the module notes).

    Parameters
    ----------
    problem : ContactProblem
        Node pairs; ``fasteners`` index its constraint rows.
    fasteners : array_like of int, shape (f,)
        Rows whose gap the fasteners close to zero, at least one.

    Attributes
    ----------
    problem : ContactProblem
    fasteners, contacts : ndarray of int
        The fastener rows and the other (contact) rows.
    """

    kind = "fastened"

    def __init__(self, problem: ContactProblem, fasteners):
        if not isinstance(problem, ContactProblem):
            raise InvalidInputError(
                f"problem must be a ContactProblem, got {type(problem).__name__}"
            )
        rows = np.asarray(fasteners, dtype=int).reshape(-1)
        m = problem.n_constraints
        if rows.size == 0 or rows.min() < 0 or rows.max() >= m or np.unique(rows).size != rows.size:
            raise InvalidInputError(f"fasteners must be distinct rows in 0..{m - 1}, at least one")
        self.problem, self.fasteners = problem, rows
        self.contacts = np.setdiff1d(np.arange(m), rows)
        self._reduction = _Reduction(problem.dual().W, rows, self.contacts)

    @property
    def n_constraints(self) -> int:
        """Number of constraint rows ``m`` (fasteners included)."""
        return self.problem.n_constraints

    @property
    def schur(self) -> np.ndarray:
        """``S``, the Delassus operator of the contact rows with the fasteners closed."""
        return self._reduction.schur

    def schur_cholesky(self) -> np.ndarray:
        """Lower Cholesky factor ``L`` of ``S = L L^T`` (kept, shared by variants)."""
        return self._reduction.schur_cholesky()

    def variant(self, *, gaps=None) -> FastenedProblem:
        """The same fasteners on other initial gaps (m, shape (m,)); ``S`` is shared."""
        twin = object.__new__(FastenedProblem)
        twin.__dict__.update(self.__dict__)
        if gaps is not None:
            twin.problem = self.problem.variant(gaps=gaps)
        return twin

    def contact_rhs(self) -> np.ndarray:
        """``q_c - W_cf W_ff^-1 q_f``: the linear term of the reduced QP on the contact rows."""
        b = self.problem.dual().b
        return b[self.contacts] - self._reduction.eliminated.T @ b[self.fasteners]

    def contact_start(self, r0) -> np.ndarray | None:
        """The contact part of a warm start ``r0`` (multipliers, shape (m,)), clipped at 0."""
        if r0 is None:
            return None
        start = warm_start(real_array(r0, "r0").reshape(-1), self.n_constraints)
        return np.maximum(start[self.contacts], 0.0)

    def make_result(
        self,
        forces,
        *,
        method: str,
        converged: bool,
        message: str,
        iterations: int,
        seconds: float,
        info: dict | None = None,
    ) -> FastenedResult:
        """The certified :class:`~contactqp.core.result.FastenedResult` of contact-row forces
        ``forces`` (N, >= 0)."""
        import scipy.linalg

        problem, rows, contacts = self.problem, self.fasteners, self.contacts
        dual = problem.dual()
        multipliers = np.empty(problem.n_constraints)
        multipliers[contacts] = forces
        multipliers[rows] = scipy.linalg.cho_solve(
            self._reduction.factor, dual.b[rows] - self._reduction.coupling @ forces
        )
        tension = np.maximum(-multipliers[rows], 0.0)
        compression = np.maximum(multipliers, 0.0)
        A = problem.constraints.matrix
        pulled = problem.variant(loads=problem.loads + A[rows].T @ tension)
        contact = pulled.make_result(
            dual.displacements(multipliers),
            compression,
            method=method,
            converged=converged,
            message=message,
            iterations=iterations,
            seconds=seconds,
            info=info,
        )
        return FastenedResult.from_contact(
            contact, rows, tension, multipliers, problem.constraints.gaps
        )

    def __repr__(self) -> str:
        return f"FastenedProblem({self.problem!r}, {self.fasteners.size} fasteners)"

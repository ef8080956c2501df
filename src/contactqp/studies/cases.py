"""Cases of a variation study: what one sample solves, records and warm starts from."""

from __future__ import annotations

import numpy as np

from ..core.problem import ContactProblem
from ..core.status import ContactStatus
from ..errors import InvalidInputError
from ..methods import solve
from .fingerprint import digest

__all__ = ["GapVariation"]


class GapVariation:
    """A frictionless :class:`~contactqp.ContactProblem` whose initial gaps vary by sample.

    Records (one row per sample in the store): ``gap`` final gaps (m), ``force`` contact forces
    (N), ``closed`` (status closed: in contact; a fastened pair is not counted), ``success``,
    ``iterations``. The warm start of a sample is the
    previous sample's ``force``.

    Parameters
    ----------
    problem : ContactProblem
        Its gaps are replaced by each sample's; its dual is assembled once.
    **options
        Passed to :func:`~contactqp.solve` (active-set solver), e.g. ``tol``.
    """

    def __init__(self, problem: ContactProblem, **options):
        if not isinstance(problem, ContactProblem):
            raise InvalidInputError(
                f"problem must be a ContactProblem, got {type(problem).__name__}"
            )
        self.problem = problem
        self.options = {"tol": 1e-10, **options}
        problem.dual()

    @property
    def n_contacts(self) -> int:
        """Number of constraints ``m`` (the length of a gap field)."""
        return self.problem.n_constraints

    def fields(self) -> dict:
        """``{name: (shape, dtype)}`` of one sample's record."""
        m = (self.n_contacts,)
        return {
            "gap": (m, "f8"),
            "force": (m, "f8"),
            "closed": (m, "?"),
            "success": ((), "?"),
            "iterations": ((), "i8"),
        }

    @staticmethod
    def _record(result) -> dict:
        return {
            "gap": result.gaps,
            "force": result.forces,
            "closed": result.contact_status == ContactStatus.CLOSED,
            "success": result.success,
            "iterations": result.iterations,
        }

    def solve_sample(self, gaps, warm):
        """Solve one sample: ``(record, warm start of the next sample)``."""
        result = solve(self.problem.variant(gaps=gaps), "active-set", r0=warm, **self.options)
        return self._record(result), result.forces

    def warm_start(self, record) -> np.ndarray:
        """The warm start a stored record gives to the next sample."""
        return np.asarray(record["force"], dtype=float)

    def describe(self) -> dict:
        """What identifies the case in a store: a digest of ``W``, the loads and ``A R P`` (the
        answer depends on all three), the certificate's tolerance and the options."""
        problem = self.problem
        dual = problem.dual()
        return {
            "type": type(self).__name__,
            "contacts": self.n_contacts,
            "digest": digest(
                dual.W, problem.loads, problem.constraints.matrix @ dual.free_displacements
            ),
            "certificate_tol": repr(problem.certificate_tol),
            "options": {k: repr(v) for k, v in sorted(self.options.items())},
        }

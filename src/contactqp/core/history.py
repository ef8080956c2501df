r"""Load histories: quasi-static friction solved increment by increment, the state carried over.

Friction depends on the load path, so a history of loads :math:`P_0, P_1, \dots` (totals, N) is
solved step by step. Step ``k`` starts from the state of step ``k - 1`` (displacements
:math:`U_{k-1}`, local forces :math:`r_{k-1}`; rest before the first step) and finds the total
local forces :math:`r_k = r_{k-1} + \Delta r` with, in the local frames of
:class:`~contactqp.FrictionalProblem` (``H``, ``W = H R H^T``, ``w`` the initial gaps),

.. math::

    u = W \Delta r + \bar q_k, \qquad
    \bar q_k = W r_{k-1} + H R P_k + w - \begin{pmatrix} 0 \\ (H U_{k-1})_T \end{pmatrix},

so that :math:`u_N = \Delta + (H U_k)_N` is the total gap and
:math:`u_T = (H U_k)_T - (H U_{k-1})_T` the *slip increment* of the step. The laws hold on the
totals of the forces and the increments of the slip: :math:`r_k` in the friction set
(:class:`~contactqp.core.friction.FrictionLaw`), :math:`u_N \ge 0` complementary to the normal
force, and :math:`-r_{T,k} \cdot u_T` the largest friction work (maximum dissipation). In the total
unknown :math:`r_k` this is the FCLIB problem :math:`u = W r_k + q_k` with
:math:`q_k = \bar q_k - W r_{k-1}`, solved by :func:`~contactqp.solve` warm started from
:math:`r_{k-1}` (:func:`~contactqp.methods.history.solve_history` chains the steps). The energy
dissipated in step ``k`` is :math:`-r_{T,k} \cdot u_T`
(backward Euler: exact while the friction bound stays constant during the step's slip).
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidInputError
from .model import finite_array
from .result import FrictionalResult

__all__ = ["MAX_STEPS", "HistoryResult", "linear_path"]

#: Default cap on the steps of :func:`linear_path`: each step is a full solve whose result is
#: kept, a few milliseconds and a few kilobytes each for small models, so 100000 steps are
#: minutes and hundreds of megabytes.
MAX_STEPS = 100_000


def linear_path(points: ArrayLike, steps: int, max_steps: int | None = MAX_STEPS) -> np.ndarray:
    """Loads along straight segments between turning points.

    Parameters
    ----------
    points : array_like, shape (j, n)
        Turning points of the load history (N), e.g. loading, unloading, reversal.
    steps : int
        Increments per segment, >= 1.
    max_steps : int or None
        Largest number of load steps (rows) accepted; None for no cap.

    Returns
    -------
    ndarray, shape (1 + steps * (j - 1), n)
        ``points[0]``, then ``steps`` equal increments towards each next point.

    Raises
    ------
    InvalidInputError
        ``steps`` is not an integer >= 1, or the path would have more than ``max_steps`` steps.
    """
    P = finite_array(points, "points", 2)
    if isinstance(steps, bool) or not isinstance(steps, numbers.Integral) or steps < 1:
        raise InvalidInputError(f"steps must be an integer >= 1, got {steps!r}")
    total = 1 + int(steps) * (P.shape[0] - 1)
    if max_steps is not None and total > max_steps:
        raise InvalidInputError(
            f"steps = {steps} gives {total} load steps for {P.shape[0]} turning points, more "
            f"than the {max_steps} allowed (each step is a full solve, and its result is kept)"
        )
    fractions = np.arange(1, int(steps) + 1) / int(steps)
    segments = [P[:1]] + [a + fractions[:, None] * (b - a) for a, b in pairwise(P)]
    return np.vstack(segments)


@dataclass(frozen=True)
class HistoryResult:
    """The steps of a load history, with their fields stacked.

    Attributes
    ----------
    steps : list of FrictionalResult
        One certified result per load step, in order.
    """

    steps: list[FrictionalResult]

    def __len__(self) -> int:
        return len(self.steps)

    def __getitem__(self, index: int) -> FrictionalResult:
        return self.steps[index]

    @property
    def success(self) -> bool:
        """True when every step succeeded (solver converged and certificate passed)."""
        return all(step.success for step in self.steps)

    @property
    def loads(self) -> np.ndarray:
        """Loads of each step (N), shape (K, n)."""
        return np.array([step.loads for step in self.steps])

    @property
    def iterations(self) -> int:
        """Iterations of all the steps."""
        return sum(step.iterations for step in self.steps)

    @property
    def seconds(self) -> float:
        """Wall time of all the steps (s)."""
        return float(sum(step.seconds for step in self.steps))

    @property
    def displacements(self) -> np.ndarray:
        """Displacements after each step (m), shape (K, n)."""
        return np.array([step.displacements for step in self.steps])

    @property
    def forces(self) -> np.ndarray:
        """Local contact forces after each step (N), shape (K, k, d)."""
        return np.array([step.forces for step in self.steps])

    @property
    def slip(self) -> np.ndarray:
        """Slip increment of each step (m), shape (K, k, d - 1)."""
        return np.array([step.slip for step in self.steps])

    @property
    def contact_status(self) -> np.ndarray:
        """Status codes (:class:`~contactqp.core.status.ContactStatus`: open, stick, slip) per
        step and contact, shape (K, k)."""
        return np.array([step.contact_status for step in self.steps])

    @property
    def dissipated(self) -> np.ndarray:
        """Energy dissipated by friction in each step (J), shape (K,)."""
        return np.array([step.dissipated for step in self.steps])

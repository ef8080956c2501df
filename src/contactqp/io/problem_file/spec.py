"""A problem read from a file (:class:`ProblemSpec`) and the thin glue that solves it."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...core.history import HistoryResult
from ...core.problem import ContactProblem, FrictionalProblem
from ...core.result import ContactResult, FrictionalResult
from ...errors import InvalidInputError
from ...methods import solve, solve_history

__all__ = ["ProblemSpec", "json_ready"]

#: What :meth:`ProblemSpec.solve` answers: frictionless, with friction, or a load history.
SpecResult = ContactResult | FrictionalResult | HistoryResult


@dataclass
class ProblemSpec:
    """A contact problem read from a file, with the solver it asks for.

    Attributes
    ----------
    problem : ContactProblem or FrictionalProblem
        The assembled problem (loads in N, lengths in m, as in the file): a
        :class:`~contactqp.FrictionalProblem` when the file has ``[friction]``, whose loads are
        the first of ``[loading].points`` when these replace ``[loads]``.
    solver : str or None
        None for the problem kind's default method, or a method name (``contactqp methods``):
        frictionless, or the friction route (``"coulomb"``, ``"tresca"`` or ``"polygonal"``).
    options : dict
        Keyword options for the solver (``[solver]``'s, or ``[friction]``'s for friction).
    name : str
        The problem's name (the file's stem when the file gives none).
    path : pathlib.Path or None
        The TOML file, as given to :func:`load_problem_file`.
    history : ndarray, shape (K, n_freedoms), optional
        Loads of each step (N) of ``[loading]``; None for a single load.
    factors : ndarray, shape (K,), optional
        Each step's multiple of ``[loads]`` for ``[loading].factors``; None otherwise.
    """

    problem: ContactProblem | FrictionalProblem
    solver: str | None = None
    options: dict[str, Any] = field(default_factory=dict)
    name: str = ""
    path: Path | None = None
    history: np.ndarray | None = None
    factors: np.ndarray | None = None

    @property
    def frictional(self) -> bool:
        """True when the problem has friction."""
        return isinstance(self.problem, FrictionalProblem)

    def solve(self, progress: Callable[[int, int], None] | None = None) -> SpecResult:
        """Solve :attr:`problem` (along :attr:`history` when given) with :attr:`solver`.

        Parameters
        ----------
        progress : callable, optional
            For a history, called as ``progress(done, total)`` after each step.

        Returns
        -------
        ContactResult, FrictionalResult or HistoryResult
            Frictionless, with friction, or one certified result per step of the history.
        """
        if self.history is not None:
            if not isinstance(self.problem, FrictionalProblem):  # files give [loading] no other
                raise InvalidInputError(
                    f"a load history needs a FrictionalProblem, got {type(self.problem).__name__}"
                )
            return solve_history(
                self.problem, self.history, self.solver, progress=progress, **self.options
            )
        return solve(self.problem, self.solver, **self.options)

    def step_factor(self, step: int) -> float | None:
        """Multiple of ``[loads]`` at ``step`` of a ``factors`` history, else None."""
        return None if self.factors is None else float(self.factors[step])

    def summary(self, result: SpecResult) -> dict[str, Any]:
        """A JSON-ready summary (no arrays) of ``result``, an answer of :meth:`solve`.

        A single result gives its own ``summary()``. A history gives ``success``, ``solver``,
        ``steps`` (count), ``failed_steps`` (indices), ``iterations``, ``seconds``,
        ``dissipated`` (J, all steps), ``certificate_worst`` (largest residual of any step),
        ``final`` (open, stick and slip counts of the last step) and ``records``: per step,
        ``step``, ``factor`` (None for ``points``) and the step's ``summary()``. NaN and inf
        become None, so that the summary is valid JSON.
        """
        if not isinstance(result, HistoryResult):
            return json_ready(result.summary())
        steps = result.steps
        last = steps[-1].summary()
        return json_ready(
            {
                "success": result.success,
                "solver": self.solver,
                "steps": len(steps),
                "failed_steps": [k for k, step in enumerate(steps) if not step.success],
                "iterations": result.iterations,
                "seconds": result.seconds,
                "dissipated": float(np.sum(result.dissipated)),
                "certificate_worst": max(step.certificate.worst for step in steps),
                "final": {status.label: last[status.label] for status in FrictionalResult.STATUSES},
                "records": [
                    {"step": k, "factor": self.step_factor(k), **step.summary()}
                    for k, step in enumerate(steps)
                ],
            }
        )


def json_ready(value: Any) -> Any:
    """``value`` with numpy types as Python ones and NaN or inf as None (valid JSON)."""
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if value is None or isinstance(value, str):
        return value
    return str(value)

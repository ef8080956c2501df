"""Load histories solved step by step with :func:`~contactqp.solve` (see
:mod:`contactqp.core.history` for the mechanics)."""

from __future__ import annotations

from collections.abc import Callable

from ..core.history import HistoryResult
from ..core.model import finite_array
from ..core.problem import FrictionalProblem
from ..errors import InvalidInputError
from .dispatch import resolve, solve

__all__ = ["solve_history"]


def solve_history(
    problem: FrictionalProblem,
    loads,
    method: str | None = None,
    *,
    progress: Callable[[int, int], None] | None = None,
    **options,
) -> HistoryResult:
    """Solve a frictional problem along a history of loads, step by step.

    Each step is ``solve(problem.with_loads(P_k, previous=result_k-1), method, **options)``,
    the first from ``problem.previous`` (rest by default).

    Parameters
    ----------
    problem : FrictionalProblem
        The contacts, the friction law and the state before the first step (its own loads are
        not used).
    loads : array_like, shape (K, n_freedoms)
        Total loads of each step (N); see :func:`~contactqp.core.history.linear_path`.
    method : str, optional
        As for :func:`~contactqp.solve`; method and options are checked before the first step.
    progress : callable, optional
        Called as ``progress(done, total)`` after each step (e.g. to show a progress bar).
    **options
        The method's options, as for :func:`~contactqp.solve`.

    Returns
    -------
    HistoryResult
        Every step, including failed ones (check :attr:`HistoryResult.success`).
    """
    if not isinstance(problem, FrictionalProblem):
        raise InvalidInputError(
            f"problem must be a FrictionalProblem, got {type(problem).__name__}"
        )
    history = finite_array(loads, "loads", 2)
    if history.shape[1] != problem.model.n_freedoms or history.shape[0] == 0:
        raise InvalidInputError(
            f"loads must have shape (K, {problem.model.n_freedoms}) with K >= 1, got "
            f"{history.shape}"
        )
    resolve(problem, method, options)  # a bad method or option fails before any step
    steps, previous = [], problem.previous
    for P in history:
        previous = solve(problem.with_loads(P, previous=previous), method, **options)
        steps.append(previous)
        if progress is not None:
            progress(len(steps), len(history))
    return HistoryResult(steps)

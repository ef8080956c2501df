"""A :class:`~contactqp.FrictionalProblem` solved by a local method on its FCLIB step.

The increment from the problem's ``previous`` state is the dimensionless FCLIB problem
:attr:`~contactqp.core.problem.FrictionStep.fclib` (cones translated to their apices, ``W`` and
``q`` scaled); a local method solves it and the forces, back in newtons, are certified by
:meth:`~contactqp.FrictionalProblem.make_result`.
"""

from __future__ import annotations

import time

import numpy as np

from ..core.model import finite_array, real_array
from ..core.problem import FrictionalProblem
from ..core.result import FrictionalResult
from ..errors import InvalidInputError

__all__ = ["solve_frictional"]


def _start(problem: FrictionalProblem, r0) -> np.ndarray | None:
    """The warm start in newtons, shape (d k,): ``r0``, else the previous state's forces."""
    if r0 is None:
        return None if problem.previous is None else problem.previous.forces.reshape(-1)
    start = finite_array(real_array(r0, "r0").reshape(-1), "r0", 1)
    if start.shape != (problem.n_contacts * problem.dim,):
        raise InvalidInputError(
            f"r0 must hold {problem.dim} local forces per contact "
            f"({problem.n_contacts * problem.dim} values), got shape {np.shape(r0)}"
        )
    return start


def solve_frictional(problem: FrictionalProblem, method, options: dict) -> FrictionalResult:
    """Solve ``problem`` with the registered local ``method`` and its checked ``options``.

    ``options["r0"]`` (N, local forces) defaults to the forces of ``problem.previous``;
    ``facets`` is the problem's for the polygonal method.
    """
    start = time.perf_counter()
    options = dict(options)
    r0 = _start(problem, options.pop("r0", None))
    step = problem.step()
    local, shift, unit = step.fclib, step.apex_shift, step.force_unit
    if "facets" in method.option_names:
        options["facets"] = problem.law.facets
    if r0 is not None:
        options["r0"] = (r0 + shift) / unit
    with np.errstate(over="ignore", invalid="ignore"):  # the certificate judges non-finite r
        solution = method.function(local, **options)
    return problem.make_result(
        unit * solution.forces - shift,
        method=method.name,
        converged=solution.success,
        message=solution.message,
        iterations=solution.iterations,
        seconds=time.perf_counter() - start,
        step=step,
    )

"""Writing results: the files ``contactqp solve`` leaves in its output directory."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ...core.history import HistoryResult
from ...core.problem import FrictionalProblem
from ...core.result import ContactResult, FrictionalResult
from ...core.status import status_counts
from ...errors import FileFormatError, InvalidInputError
from ..export import write_rows
from .messages import one_line
from .spec import ProblemSpec, SpecResult, json_ready

__all__ = ["write_results", "RESULT_FILES", "HISTORY_FILES"]

#: The files :func:`write_results` writes, in order.
RESULT_FILES = ("displacements.csv", "contacts.csv", "result.npz", "summary.json")

#: The files :func:`write_results` writes for a load history, in order.
HISTORY_FILES = RESULT_FILES + ("steps.csv",)

#: The arrays of ``result.npz`` every result has (the common fields of
#: :class:`~contactqp.core.result.ContactResult`).
COMMON_FIELDS = ("displacements", "forces", "nodal_forces", "gaps", "contact_status")


def _float_text(value) -> str:
    return repr(float(value))  # the shortest text that reads back to the same float


def _expected_steps(spec: ProblemSpec, result: SpecResult) -> list:
    """The results of each step of ``result``, after checking its kind and shapes."""
    problem = spec.problem
    kind: type[HistoryResult | FrictionalResult | ContactResult]
    if spec.history is not None:
        kind, steps = HistoryResult, getattr(result, "steps", [])
    else:
        kind, steps = FrictionalResult if spec.frictional else ContactResult, [result]
    if type(result) is not kind:
        raise InvalidInputError(
            f"result must be a {kind.__name__} for this problem, got {type(result).__name__}"
        )
    if spec.history is not None and len(steps) != len(spec.history):
        raise InvalidInputError(
            f"result has {len(steps)} steps, the history has {len(spec.history)}"
        )
    n, m = problem.model.n_freedoms, problem.constraints.n_constraints
    for step in steps:
        if np.shape(step.displacements) != (n,) or np.shape(step.forces)[:1] != (m,):
            raise InvalidInputError(
                f"result has {np.size(step.displacements)} displacements and "
                f"{len(step.forces)} contacts; "
                f"the problem has {n} freedoms and {m} constraints"
            )
    return steps


def _tangential_header(name: str, dim: int) -> list[str]:
    return [name] if dim == 2 else [f"{name}_{j}" for j in range(1, dim)]


def write_results(
    spec: ProblemSpec, result: SpecResult, out_dir: str | os.PathLike[str]
) -> list[Path]:
    """Write a solved problem's results to a directory (files, columns: docs/problem-files.md).

    Parameters
    ----------
    spec : ProblemSpec
    result : ContactResult, FrictionalResult or HistoryResult
        The answer of ``spec.solve()``.
    out_dir : str or os.PathLike
        Created, with its parents, when missing; files in it are overwritten.

    Returns
    -------
    list of pathlib.Path
        The files written, in the order of :data:`RESULT_FILES` (:data:`HISTORY_FILES` for a
        load history).

    Raises
    ------
    InvalidInputError
        ``result`` is not of the kind, or does not have the shapes, of ``spec.problem``.
    FileFormatError
        The directory or a file cannot be written.
    """
    steps = _expected_steps(spec, result)
    problem = spec.problem
    model, constraints = problem.model, problem.constraints
    history = spec.history is not None
    lead = ["step"] if history else []
    out = Path(out_dir)
    paths = [out / name for name in (HISTORY_FILES if history else RESULT_FILES)]

    def rows_of(make):  # rows of every step, prefixed by the step index for a history
        return [[k] * history + row for k, step in enumerate(steps) for row in make(step)]

    freedoms = [
        (node, int(freedom)) for node in range(model.n_nodes) for freedom in model.freedoms(node)
    ]
    displacements = rows_of(
        lambda step: [
            [node, freedom, _float_text(step.displacements[freedom])] for node, freedom in freedoms
        ]
    )
    base = ["row", "node", "label", "gap0", "gap"]
    fixed = [
        [
            row,
            int(constraints.nodes[row]),
            constraints.labels[row],
            _float_text(constraints.gaps[row]),
        ]
        for row in range(constraints.n_constraints)
    ]
    fields: tuple[str, ...]
    if isinstance(problem, FrictionalProblem):
        dim = problem.dim
        header = (
            base
            + ["normal_force"]
            + [
                column
                for name in ("tangential_force", "slip", "tangential_displacement")
                for column in _tangential_header(name, dim)
            ]
            + ["dissipated", "status"]
        )
        contacts = rows_of(
            lambda step: [
                fixed[row]
                + [
                    _float_text(v)
                    for v in (
                        step.gaps[row],
                        *step.forces[row],
                        *step.slip[row],
                        *step.tangential_displacements[row],
                        step.dissipation[row],
                    )
                ]
                + [step.status_labels[row]]
                for row in range(constraints.n_constraints)
            ]
        )
        fields = COMMON_FIELDS + ("slip", "tangential_displacements", "dissipation")
        arrays = {"normals": problem.frames.normals, "tangents": problem.frames.tangents}
    else:
        header = base + ["force", "status"]
        contacts = rows_of(
            lambda step: [
                fixed[row]
                + [
                    _float_text(step.gaps[row]),
                    _float_text(step.forces[row]),
                    step.status_labels[row],
                ]
                for row in range(constraints.n_constraints)
            ]
        )
        fields = COMMON_FIELDS
        arrays = {}
    for name in fields:
        stacked = np.array([getattr(step, name) for step in steps])
        arrays[name] = stacked if history else stacked[0]
    if history:
        arrays["loads"] = np.array([step.loads for step in steps])
        arrays["success"] = np.array([step.success for step in steps], dtype=bool)
        if spec.factors is not None:
            arrays["factors"] = np.asarray(spec.factors, dtype=float)
    summary = {
        "name": spec.name,
        "problem": os.path.abspath(spec.path) if spec.path is not None else None,
        "solver": spec.solver,
        "options": spec.options,
        "result": spec.summary(result),
    }
    if isinstance(problem, FrictionalProblem):
        law = problem.law
        summary["friction"] = {"mu": law.mu, "cohesion": law.cohesion, "facets": law.facets}
    try:
        out.mkdir(parents=True, exist_ok=True)
        write_rows(paths[0], lead + ["node", "freedom", "u"], displacements)
        write_rows(paths[1], lead + header, contacts)
        with open(paths[2], "wb") as archive:
            # allow_pickle: numpy's default, named so that **arrays cannot be read as setting it
            np.savez(archive, allow_pickle=True, **arrays)
        with open(paths[3], "w", encoding="utf-8") as text:
            json.dump(json_ready(summary), text, indent=2, allow_nan=False)
            text.write("\n")
        if history:
            cumulative = np.cumsum([step.dissipated for step in steps])
            labels = [status.label for status in FrictionalResult.STATUSES]
            write_rows(
                paths[4],
                [
                    "step",
                    "factor",
                    *labels,
                    "dissipated",
                    "cumulative_dissipated",
                    "iterations",
                    "certificate_worst",
                    "success",
                ],
                [
                    [
                        k,
                        "" if spec.factors is None else _float_text(spec.factors[k]),
                        *[status_counts(step.contact_status)[label] for label in labels],
                        _float_text(step.dissipated),
                        _float_text(cumulative[k]),
                        step.iterations,
                        _float_text(step.certificate.worst),
                        step.success,
                    ]
                    for k, step in enumerate(steps)
                ],
            )
    except OSError as exc:
        raise FileFormatError(one_line(f"cannot write results to '{out}': {exc}")) from None
    return paths

"""``contactqp solve``: a contact problem described by a TOML file.

Frictionless, with friction (``[friction]``) or along a load history (``[loading]``); the file
format and the files ``--out`` writes (columns and units) are described in
``docs/problem-files.md``. ``--json`` prints :meth:`ProblemSpec.summary` on one line,
with the problem's ``name`` and path. Exit 1 when the solve (or a step of the history) did not
converge or its certificate failed, with one line on stderr naming the first such step.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click
import numpy as np

from ..core.status import ContactStatus, status_counts
from .app import EXIT_NOT_SOLVED, console, fail, progress

#: The status counts of a load history's table, in its column order.
_HISTORY_STATUSES = (ContactStatus.STICK, ContactStatus.SLIP, ContactStatus.OPEN)


@click.command()
@click.argument("problem_file", type=click.Path(path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON line.")
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    help="Write displacements.csv, contacts.csv, result.npz and summary.json here "
    "(and steps.csv for a load history).",
)
def solve(problem_file, as_json, out):
    """Solve the contact problem (with friction, or a load history) in a TOML file."""
    from ..core.history import HistoryResult
    from ..io.problem_file import load_problem_file, write_results

    spec = load_problem_file(problem_file)
    with progress("step") as report:
        result = spec.solve(progress=report)
    written = write_results(spec, result, out) if out else []
    summary = spec.summary(result)
    if as_json:
        click.echo(json.dumps({"name": spec.name, "problem": str(problem_file), **summary}))
    elif spec.history is not None:
        _history_table(spec, result, summary, written)
    else:
        _result_table(spec, result, spec.name)
        _print_written(written)
    if isinstance(result, HistoryResult):  # spec.history was given
        failed = summary["failed_steps"]
        if failed:
            first = result.steps[failed[0]]
            factor = spec.step_factor(failed[0])
            at = "" if factor is None else f" (factor {factor:g})"
            more = f" ({len(failed) - 1} more steps failed)" if len(failed) > 1 else ""
            fail(f"{problem_file}: step {failed[0]}{at}: {first.message}{more}")
            sys.exit(EXIT_NOT_SOLVED)
    elif not result.success:
        fail(f"{problem_file}: {result.message}")
        sys.exit(EXIT_NOT_SOLVED)


def _table(title: str, columns, number_width: int | None = 10):
    """A rich table; numeric columns at least ``number_width`` wide (None: their longest word)."""
    from rich import box
    from rich.table import Table

    table = Table(title=title, box=box.SIMPLE_HEAD, pad_edge=False, collapse_padding=True)
    for column in columns:  # numbers keep their width, labels wrap
        if column == "contact":
            table.add_column(column, overflow="fold")
        else:
            table.add_column(
                column,
                justify="right",
                overflow="fold",
                min_width=number_width or max(map(len, column.split())),
            )
    return table


def _result_table(spec, result, title):
    """Per-contact table and certificate of one result (frictionless or with friction).

    With friction: gap, normal force, tangential force(s), slip of the step (along the tangent
    in 2-D, its length in 3-D) and status; ``--out``'s contacts.csv has every component and the
    dissipation.
    """
    constraints = spec.problem.constraints
    out = console()
    cert = result.certificate
    work = (
        f"potential energy {result.energy:.6g} J, {result.iterations} iterations, "
        f"{result.seconds * 1e3:.3g} ms; certificate worst residual {cert.worst:.2e} "
        f"({'passed' if cert.passed else 'FAILED'}"
    )
    if not spec.frictional:
        table = _table(
            f"{title}: {result.method}, {result.message}",
            ("contact", "gap0 (m)", "gap (m)", "force (N)", "status"),
        )
        for k in range(constraints.n_constraints):
            table.add_row(
                constraints.labels[k],
                f"{constraints.gaps[k]:.6g}",
                f"{result.gaps[k]:.6g}",
                f"{result.forces[k]:.6g}",
                result.status_labels[k],
            )
        out.print(table)
        out.print(f"{work})")
        return
    planar = spec.problem.dim == 2
    tangents = ["tangential (N)"] if planar else ["t1 (N)", "t2 (N)"]
    table = _table(
        f"{title}: {result.method}, {result.message}",
        (
            "contact",
            "gap (m)",
            "normal (N)",
            *tangents,
            "slip (m)" if planar else "|slip| (m)",
            "status",
        ),
    )
    slips = result.slip[:, 0] if planar else np.linalg.norm(result.slip, axis=1)
    for k in range(constraints.n_constraints):
        table.add_row(
            constraints.labels[k],
            *[f"{v:.4g}" for v in (result.gaps[k], *result.forces[k], slips[k])],
            result.status_labels[k],
        )
    out.print(table)
    residuals = ", ".join(
        f"{name} {getattr(cert, name):.1e}"
        for name in ("cone", "complementarity", "dissipation", "equilibrium", "natural_map")
    )
    out.print(
        f"dissipated {result.dissipated:.6g} J, elastic energy "
        f"{result.elastic_energy:.6g} J, {work}; {residuals})"
    )


def _history_table(spec, result, summary, written):
    """Per-step table, totals and the final state of a load history."""
    table = _table(
        f"{spec.name}: {spec.solver}, {summary['steps']} steps",
        (
            "step",
            "factor",
            *(status.label for status in _HISTORY_STATUSES),
            "dissipated (J)",
            "cumulative (J)",
            "iter",
            "residual",
        ),
        number_width=None,
    )
    cumulative = np.cumsum(result.dissipated)
    for k, step in enumerate(result.steps):
        factor = spec.step_factor(k)
        counts = status_counts(step.contact_status)
        table.add_row(
            str(k),
            "-" if factor is None else f"{factor:g}",
            *(str(counts[status.label]) for status in _HISTORY_STATUSES),
            f"{step.dissipated:.4g}",
            f"{cumulative[k]:.4g}",
            str(step.iterations),
            f"{step.certificate.worst:.1e}" if step.success else "FAILED",
        )
    out = console()
    out.print(table)
    failed = summary["failed_steps"]
    out.print(
        f"total dissipated {summary['dissipated']:.6g} J, {summary['iterations']} "
        f"iterations, {summary['seconds'] * 1e3:.3g} ms; worst certificate residual "
        f"{summary['certificate_worst']:.2e} "
        f"({'all steps passed' if not failed else f'{len(failed)} steps FAILED'})"
    )
    last = len(result.steps) - 1
    _result_table(spec, result.steps[last], f"final state (step {last})")
    _print_written(written)


def _print_written(written):
    out = console()
    for path in written:
        out.print(f"wrote {path}")

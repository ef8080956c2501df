"""``contactqp solve``: a frictionless problem described by a TOML file."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from .app import EXIT_NOT_SOLVED, cli, console, fail


@cli.command()
@click.argument("problem_file", type=click.Path(path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON line.")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              help="Write displacements.csv, contacts.csv, result.npz and summary.json here.")
def solve(problem_file, as_json, out):
    """Solve the frictionless contact problem described by a TOML file."""
    from ..io.problem_file import load_problem_file, write_results
    from ..solvers import solve as run_solver

    spec = load_problem_file(problem_file)
    result = run_solver(spec.problem, spec.solver, **spec.options)
    written = write_results(spec, result, out) if out else []
    summary = {"name": spec.name, "problem": str(problem_file), **result.summary()}
    if as_json:
        click.echo(json.dumps(summary))
    else:
        _solve_table(spec, result, written)
    if not result.success:
        fail(f"{problem_file}: {result.message}")
        sys.exit(EXIT_NOT_SOLVED)


def _solve_table(spec, result, written):
    from rich.table import Table

    table = Table(title=f"{spec.name}: {result.solver}, {result.message}")
    for column in ("contact", "gap0 (m)", "gap (m)", "force (N)", "status"):
        table.add_column(column, justify="right" if column != "contact" else "left")
    constraints = spec.problem.constraints
    for k in range(constraints.n_constraints):
        table.add_row(constraints.labels[k], f"{constraints.gaps[k]:.6g}", f"{result.gaps[k]:.6g}",
                      f"{result.forces[k]:.6g}", result.status_labels[k])
    out = console()
    out.print(table)
    cert = result.certificate
    out.print(f"energy {result.energy:.6g} J, {result.nit} iterations, "
                  f"{result.wall_time * 1e3:.3g} ms; certificate worst residual {cert.worst:.2e} "
                  f"({'passed' if cert.passed else 'FAILED'})")
    for path in written:
        out.print(f"wrote {path}")

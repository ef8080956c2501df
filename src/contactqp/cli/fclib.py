"""``contactqp fclib``: FCLIB problems (HDF5 or Siconos .dat)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click
import numpy as np

from ..errors import ContactError
from .app import EXIT_BAD_INPUT, EXIT_NOT_SOLVED, EXIT_OK, cli, console, fail

STATUSES = ("open", "stick", "slip")
COLUMNS = ("file", "dim", "contacts", "converged", "error", "iterations", "seconds", *STATUSES)


@cli.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--tol", type=click.FloatRange(min=0.0, min_open=True), default=1e-8,
              show_default=True, help="Target natural-map error.")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per file and line.")
@click.option("--solution-dir", type=click.Path(file_okay=False, path_type=Path),
              help="Write DIR/<file stem>.hdf5 with /solution/r and /solution/u (converged only).")
def fclib(files, tol, as_json, solution_dir):
    """Solve FCLIB problems (HDF5 or Siconos .dat), local or global, with Coulomb friction.

    Exit status 1 when a problem is not solved to --tol (its error and the solver's stages on
    stderr, no solution written), 2 when a file is unreadable or invalid.
    """
    from ..io.fclib import read_problem, write_solution
    from ..solvers.local import solve_local

    exit_code = EXIT_OK
    rows = []
    for path in files:
        try:
            problem = read_problem(path)
            solution = solve_local(problem, tol=tol)
        except ContactError as exc:
            message = str(exc)  # the reader's messages may already name the file
            fail(message if message.startswith(str(path)) else f"{path}: {message}")
            exit_code = EXIT_BAD_INPUT
            continue
        record = {"file": str(path), "dim": problem.dim, "contacts": problem.n_contacts,
                  "converged": solution.converged, "error": solution.error,
                  "iterations": solution.iterations, "seconds": solution.seconds,
                  **{s: int(np.count_nonzero(solution.status == s)) for s in STATUSES}}
        if not solution.converged:
            fail(f"{path}: {solution.message}" + ("; no solution written" if solution_dir else ""))
            exit_code = max(exit_code, EXIT_NOT_SOLVED)
        elif solution_dir:
            solution_dir.mkdir(parents=True, exist_ok=True)
            write_solution(solution_dir / f"{Path(path).stem}.hdf5", solution.r, solution.u)
        if as_json:
            click.echo(json.dumps(record))
        rows.append(record)
    if not as_json and rows:
        _fclib_table(rows)
    sys.exit(exit_code)


def _fclib_table(rows):
    from rich.table import Table

    table = Table(title="FCLIB problems")
    for column in COLUMNS:
        table.add_column(column, justify="left" if column == "file" else "right")
    for r in rows:
        table.add_row(Path(r["file"]).name, str(r["dim"]), str(r["contacts"]), str(r["converged"]),
                      f"{r['error']:.2e}", str(r["iterations"]), f"{r['seconds']:.3g}",
                      *(str(r[s]) for s in STATUSES))
    console().print(table)

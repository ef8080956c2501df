"""``contactqp fclib``: FCLIB problems (HDF5 or Siconos .dat)."""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

import click

from ..core.result import LocalResult
from ..core.status import status_counts
from ..errors import ContactError, SolverError
from .app import EXIT_BAD_INPUT, EXIT_NOT_SOLVED, EXIT_OK, console, fail, figures_table

STATUSES = tuple(status.label for status in LocalResult.STATUSES)
COLUMNS = ("file", "dim", "contacts", "converged", "error", "iterations", "seconds", *STATUSES)

#: ``--solution-dir`` writes the solution of ``x.dat`` to ``DIR/x.dat`` + this suffix.
SOLUTION_SUFFIX = ".solution.hdf5"


@click.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option(
    "--tol",
    type=click.FloatRange(min=0.0, min_open=True),
    default=1e-8,
    show_default=True,
    help="Target natural-map error.",
)
@click.option("--json", "as_json", is_flag=True, help="One JSON object per file and line.")
@click.option(
    "--solution-dir",
    type=click.Path(file_okay=False, path_type=Path),
    help=f"Write DIR/<file name>{SOLUTION_SUFFIX} (e.g. x.dat{SOLUTION_SUFFIX}) with "
    "/solution/r, /solution/u (and /solution/v for global problems), converged "
    "only. Refused if a target is an input, two inputs share a target, or a "
    "target exists and is not the solution file this command wrote for the same "
    "input.",
)
def fclib(files: tuple[Path, ...], tol: float, as_json: bool, solution_dir: Path | None) -> None:
    """Solve FCLIB problems (HDF5 or Siconos .dat), local or global, with Coulomb friction.

    Each problem is solved as written: a global one is certified on M v = H r + f,
    u = H^T v + w (M as given, not symmetrised). The JSON line's "attainable" is the
    natural-map error that rounding (the conditioning of M) allows, "data_limit" how closely the
    answer can meet the problem the file was written from when its values carry few digits
    ("digits"), and "limits" the sentence, also printed under the table, naming any above --tol.

    Exit status 1 when a problem is not solved to --tol (its error and the solver's stages on
    stderr, no solution written) or its solver fails, 2 when a file is unreadable or invalid,
    or a solution would overwrite an input, another input's solution or a file this command
    did not write.
    """
    from ..io.fclib import read_any, write_solution
    from ..methods import solve

    targets = _solution_targets(files, solution_dir) if solution_dir else {}
    exit_code = EXIT_OK
    rows = []
    for path in files:
        try:
            problem = read_any(path)
            solution = solve(problem, tol=tol)  # mu = 0 everywhere: the frictionless route
        except ContactError as exc:
            message = str(exc)  # the reader's messages may already name the file
            fail(message if message.startswith(str(path)) else f"{path}: {message}")
            exit_code = max(
                exit_code, EXIT_NOT_SOLVED if isinstance(exc, SolverError) else EXIT_BAD_INPUT
            )
            continue
        certificate = solution.certificate
        counts = status_counts(solution.contact_status)
        record = {
            "file": str(path),
            "dim": problem.dim,
            "contacts": problem.n_contacts,
            "converged": solution.success,
            "error": certificate.natural_map,
            "equilibrium": certificate.equilibrium,
            **certificate.limits.as_dict(),
            "iterations": solution.iterations,
            "seconds": solution.seconds,
            **{s: counts[s] for s in STATUSES},
            "limits": certificate.limits.describe(tol),
        }
        if not solution.success:
            fail(f"{path}: {solution.message}" + ("; no solution written" if solution_dir else ""))
            exit_code = max(exit_code, EXIT_NOT_SOLVED)
        elif solution_dir:
            solution_dir.mkdir(parents=True, exist_ok=True)
            write_solution(
                targets[path], solution.forces, solution.displacements, solution.v, source=path
            )
        if as_json:
            click.echo(json.dumps(record))
        rows.append(record)
    if not as_json and rows:
        _fclib_table(rows)
        for r in rows:
            if r["limits"]:
                click.echo(f"{r['file']}: {r['limits']}")
    sys.exit(exit_code)


def _solution_targets(files: Sequence[Path], solution_dir: Path) -> dict[Path, Path]:
    """The solution file of each input; exit 2 (one line) if any would damage a file.

    A target is refused when it is one of the inputs, when two different inputs share it, or
    when it exists and is not the solution file this command wrote for the same input
    (:func:`~contactqp.io.fclib.is_own_solution`): nothing is solved then.
    """
    from ..io.fclib import file_key as key
    from ..io.fclib import is_own_solution, solution_source

    inputs = {key(p): p for p in files}
    targets: dict[Path, Path] = {}
    owners: dict[str, Path] = {}
    for path in files:
        target = solution_dir / f"{path.name}{SOLUTION_SUFFIX}"
        where = key(target)
        if where in inputs:
            _refuse(
                f"{target}: the solution of {path} would overwrite the input "
                f"{inputs[where]}; choose another --solution-dir"
            )
        other = owners.setdefault(where, path)
        if key(other) != key(path):
            _refuse(
                f"{target}: {other} and {path} would write the same solution file; solve "
                f"them with different --solution-dir"
            )
        if target.exists() and not is_own_solution(target, path):
            written_for = solution_source(target)
            what = (
                f"the solution of another input, {written_for}"
                if written_for
                else "not a solution file written by contactqp fclib"
            )
            _refuse(
                f"{target}: exists and is {what}; not overwritten (remove it or choose "
                f"another --solution-dir)"
            )
        targets[path] = target
    return targets


def _refuse(message: str) -> NoReturn:
    fail(message)
    sys.exit(EXIT_BAD_INPUT)


def _fclib_table(rows: list[dict[str, Any]]) -> None:
    table = figures_table("FCLIB problems", COLUMNS, left=("file",))
    for r in rows:
        table.add_row(
            Path(r["file"]).name,
            str(r["dim"]),
            str(r["contacts"]),
            str(r["converged"]),
            f"{r['error']:.2e}",
            str(r["iterations"]),
            f"{r['seconds']:.3g}",
            *(str(r[s]) for s in STATUSES),
        )
    console().print(table)

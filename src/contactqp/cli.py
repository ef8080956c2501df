"""The ``contactqp`` command line.

Exit status: 0 success; 1 a solve did not converge (or its certificate failed, or the problem asks
for what this version cannot do); 2 unreadable or invalid input. Errors are one line on stderr,
never a traceback.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from .errors import ContactError, UnsupportedProblemError

__all__ = ["main", "cli"]

EXIT_OK, EXIT_NOT_SOLVED, EXIT_BAD_INPUT = 0, 1, 2


def _fail(message: str) -> None:
    click.echo(f"contactqp: error: {message}", err=True)


def _console():
    from rich.console import Console

    return Console()


def _float_list(ctx, param, text: str) -> list[float]:
    """Click callback: parse comma-separated numbers."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise click.BadParameter(f"expected comma-separated numbers, got {text!r}") from None
    if not values:
        raise click.BadParameter("expected at least one number")
    return values


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="contactqp")
def cli():
    """Fast elastic contact with friction on reduced (compliance-matrix) models."""


@cli.command()
@click.option("--n", "n", type=click.IntRange(min=1), default=3, show_default=True,
              help="Number of bodies.")
@click.option("--stiffness", type=float, default=1.0, show_default=True, help="Spring stiffness c (N/m).")
@click.option("--mu", type=float, default=0.2, show_default=True, help="Friction coefficient.")
@click.option("--mass", type=float, default=2.0, show_default=True, help="Mass of each body (kg).")
@click.option("--g", "gravity", type=float, default=10.0, show_default=True, help="Gravity (m/s^2).")
@click.option("--force", "forces", default="3,6,9,14", show_default=True,
              callback=_float_list, help="Pulling force(s) on the last body (N), comma-separated.")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per force and line.")
@click.option("--plot", type=click.Path(dir_okay=False, path_type=Path),
              help="Draw the bodies' displacements to this PNG file.")
def springs(n, stiffness, mu, mass, gravity, forces, as_json, plot):
    """A chain of bodies linked by springs on a floor with friction, pulled at its end."""
    from .springs import SpringChain

    chain = SpringChain(n=n, stiffness=stiffness, mu=mu, mass=mass, g=gravity)
    results = []
    for force in forces:
        result = chain.solve(force)
        results.append(result)
        if as_json:
            click.echo(json.dumps({"force": result.force, "x": result.x.tolist()}))
    if not as_json:
        _springs_table(chain, results)
    if plot:
        from .plot import plot_spring_chain

        plot_spring_chain(results, plot)
        if not as_json:
            click.echo(f"figure written to {plot}")
    if not all(r.converged for r in results):
        _fail("the spring chain did not converge for force(s) "
              + ", ".join(f"{r.force:g}" for r in results if not r.converged))
        sys.exit(EXIT_NOT_SOLVED)


def _springs_table(chain, results):
    from rich.table import Table

    n = chain.n
    shown = list(range(n)) if n <= 8 else [0, 1, 2, None, n - 3, n - 2, n - 1]
    table = Table(title=f"Spring chain: N={n}, c={chain.stiffness:g} N/m, "
                        f"friction limit mu m g={chain.friction_limit:g} N")
    table.add_column("F (N)", justify="right")
    for i in shown:
        table.add_column("..." if i is None else f"x{i + 1} (m)", justify="right")
    for r in results:
        table.add_row(f"{r.force:g}", *("..." if i is None else f"{r.x[i]:.6g}" for i in shown))
    _console().print(table)


@cli.command()
@click.argument("problem_file", type=click.Path(path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON line.")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              help="Write displacements.csv, contacts.csv, result.npz and summary.json here.")
def solve(problem_file, as_json, out):
    """Solve the frictionless contact problem described by a TOML file."""
    from .io.problem_file import load_problem_file, write_results
    from .solvers import solve as run_solver

    spec = load_problem_file(problem_file)
    result = run_solver(spec.problem, spec.solver, **spec.options)
    written = write_results(spec, result, out) if out else []
    summary = {"name": spec.name, "problem": str(problem_file), **result.summary()}
    if as_json:
        click.echo(json.dumps(summary))
    else:
        _solve_table(spec, result, written)
    if not result.success:
        _fail(f"{problem_file}: {result.message}")
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
    console = _console()
    console.print(table)
    cert = result.certificate
    console.print(f"energy {result.energy:.6g} J, {result.nit} iterations, "
                  f"{result.wall_time * 1e3:.3g} ms; certificate worst residual {cert.worst:.2e} "
                  f"({'passed' if cert.passed else 'FAILED'})")
    for path in written:
        console.print(f"wrote {path}")


@cli.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--tol", type=click.FloatRange(min=0.0, min_open=True), default=1e-8,
              show_default=True, help="Target natural-map error.")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per file and line.")
@click.option("--solution-dir", type=click.Path(file_okay=False, path_type=Path),
              help="Write DIR/<file stem>.hdf5 with /solution/r and /solution/u.")
def fclib(files, tol, as_json, solution_dir):
    """Solve FCLIB problems (HDF5 or Siconos .dat), local or global."""
    from .io.fclib import read_problem, write_solution
    from .solvers.local import solve_local

    exit_code = EXIT_OK
    rows = []
    for path in files:
        try:
            problem = read_problem(path)
            solution = solve_local(problem, tol=tol)
        except UnsupportedProblemError as exc:
            _fail(f"{path}: {exc}")
            exit_code = max(exit_code, EXIT_NOT_SOLVED)
            continue
        except ContactError as exc:
            _fail(f"{path}: {exc}")
            exit_code = EXIT_BAD_INPUT
            continue
        record = {"file": str(path), "dim": problem.dim, "contacts": problem.n_contacts,
                  "converged": solution.converged, "error": solution.error,
                  "iterations": solution.iterations, "seconds": solution.seconds}
        if solution_dir:
            solution_dir.mkdir(parents=True, exist_ok=True)
            write_solution(solution_dir / f"{Path(path).stem}.hdf5", solution.r, solution.u)
        if not solution.converged:
            _fail(f"{path}: not converged: {solution.message} (error {solution.error:.2e})")
            exit_code = max(exit_code, EXIT_NOT_SOLVED)
        if as_json:
            click.echo(json.dumps(record))
        rows.append(record)
    if not as_json and rows:
        _fclib_table(rows)
    sys.exit(exit_code)


def _fclib_table(rows):
    from rich.table import Table

    table = Table(title="FCLIB problems")
    for column in ("file", "dim", "contacts", "converged", "error", "iterations", "seconds"):
        table.add_column(column, justify="left" if column == "file" else "right")
    for r in rows:
        table.add_row(Path(r["file"]).name, str(r["dim"]), str(r["contacts"]), str(r["converged"]),
                      f"{r['error']:.2e}", str(r["iterations"]), f"{r['seconds']:.3g}")
    _console().print(table)


def main(argv=None) -> int:
    """Run the command line; return the exit status instead of raising."""
    try:
        cli.main(args=argv, prog_name="contactqp", standalone_mode=False)
    except click.exceptions.Exit as exc:
        return exc.exit_code
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_NOT_SOLVED
    except click.exceptions.Abort:
        _fail("interrupted")
        return 130
    except click.ClickException as exc:
        _fail(exc.format_message().replace("\n", " "))
        return EXIT_BAD_INPUT
    except ContactError as exc:
        _fail(str(exc).replace("\n", " "))
        return EXIT_BAD_INPUT
    except OSError as exc:
        _fail(f"{exc.filename or ''}: {exc.strerror or exc}".lstrip(": "))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        _fail("interrupted")
        return 130
    return EXIT_OK


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""``contactqp springs``: the spring chain with friction."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from .app import EXIT_NOT_SOLVED, console, fail, figures_table, float_list, progress

#: Largest chain offered: solved in about a second per force (the output then holds 1e6 numbers
#: per force).
MAX_BODIES = 1_000_000


@click.command()
@click.option(
    "--n",
    "n",
    type=click.IntRange(min=1, max=MAX_BODIES),
    default=3,
    show_default=True,
    help="Number of bodies.",
)
@click.option(
    "--stiffness", type=float, default=1.0, show_default=True, help="Spring stiffness c (N/m)."
)
@click.option("--mu", type=float, default=0.2, show_default=True, help="Friction coefficient.")
@click.option("--mass", type=float, default=2.0, show_default=True, help="Mass of each body (kg).")
@click.option(
    "--g", "gravity", type=float, default=10.0, show_default=True, help="Gravity (m/s^2)."
)
@click.option(
    "--force",
    "forces",
    default="3,6,9,14",
    show_default=True,
    callback=float_list,
    help="Pulling force(s) on the last body (N), comma-separated.",
)
@click.option("--json", "as_json", is_flag=True, help="One JSON object per force and line.")
@click.option(
    "--plot",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Draw the bodies' displacements to this PNG file.",
)
def springs(
    n: int,
    stiffness: float,
    mu: float,
    mass: float,
    gravity: float,
    forces: list[float],
    as_json: bool,
    plot: Path | None,
) -> None:
    """A chain of bodies linked by springs on a floor with friction, pulled at its end."""
    from ..applications.springs import SpringChain

    chain = SpringChain(n=n, stiffness=stiffness, mu=mu, mass=mass, g=gravity)
    results = []
    with progress("force") as report:
        for force in forces:
            result = chain.solve(force)
            results.append(result)
            if as_json:
                click.echo(json.dumps({"force": result.force, "x": result.x.tolist()}))
            report(len(results), len(forces))
    if not as_json:
        _springs_table(chain, results)
    if plot:
        from ..io.plot import plot_spring_chain

        plot_spring_chain([r.force for r in results], [r.x for r in results], plot)
        if not as_json:
            click.echo(f"figure written to {plot}")
    failed = [r for r in results if not r.converged]
    if failed:
        fail(
            "the spring chain did not converge for force(s) "
            + ", ".join(f"{r.force:g}" for r in failed)
            + f" ({failed[0].message})"
        )
        sys.exit(EXIT_NOT_SOLVED)


def _springs_table(chain, results):
    n = chain.n
    shown = list(range(n)) if n <= 8 else [0, 1, 2, None, n - 3, n - 2, n - 1]
    table = figures_table(
        f"Spring chain: N={n}, c={chain.stiffness:g} N/m, "
        f"friction limit mu m g={chain.friction_limit:g} N",
        ["F (N)", *("..." if i is None else f"x{i + 1} (m)" for i in shown)],
    )
    for r in results:
        table.add_row(f"{r.force:g}", *("..." if i is None else f"{r.x[i]:.6g}" for i in shown))
    console().print(table)

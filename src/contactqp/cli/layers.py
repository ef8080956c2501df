"""``contactqp layers``: two soil layers, frictional interface, growing lateral load."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from ..core.history import MAX_STEPS
from .app import EXIT_NOT_SOLVED, console, fail, figures_table, progress


@click.command()
@click.option(
    "--mu",
    type=click.FloatRange(min=0, max=10, min_open=True),
    default=0.5,
    show_default=True,
    help="Friction coefficient of the interface (soils: below 1.5).",
)
@click.option(
    "--cohesion",
    type=click.FloatRange(min=0, max=1e8),
    default=5e3,
    show_default=True,
    help="Cohesion of the interface (Pa; strong rock: 1e7 to 1e8).",
)
@click.option(
    "--steps",
    type=click.IntRange(min=2, max=MAX_STEPS - 1),
    default=40,
    show_default=True,
    help="Steps of the actuator travel.",
)
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help="End with one JSON line (SI units): mu, cohesion, area, normal_force, "
    "onset_force, curve [[load, relative displacement], ...].",
)
@click.option(
    "--plot",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Draw the load against the relative displacement to this PNG file.",
)
def layers(mu: float, cohesion: float, steps: int, as_json: bool, plot: Path | None) -> None:
    """A 1 m soil layer on a 2 m one (10 m long, plane strain), pulled sideways under gravity.

    The interface is Mohr-Coulomb; sliding starts when the load reaches c A + mu N. Exit status
    1 when a step is not solved or the layer does not slide within the travel.
    """
    from ..applications.layers import Layers, plot_layers

    model = Layers(mu=mu, cohesion=cohesion, steps=steps)
    with progress("step") as report:  # a step not solved: a LayersError (SolverError), exit 1
        result = model.solve(progress=report)
    if as_json:
        click.echo(json.dumps(result.as_record()))
    else:
        _layers_table(result)
    if plot:
        plot_layers(result, plot)
        if not as_json:
            click.echo(f"figure written to {plot}")
    if result.onset is None:
        fail(
            f"no sliding within the travel (largest load {result.load.max():.6g} N, "
            f"c A + mu N = {model.limit:.6g} N)"
        )
        sys.exit(EXIT_NOT_SOLVED)


def _layers_table(result):
    layers = result.layers
    table = figures_table(
        f"Two layers: mu = {layers.mu:g}, cohesion = {layers.cohesion:g} Pa, "
        f"area = {layers.area:g} m^2, weight = {layers.weight:.6g} N",
        ("step", "travel (mm)", "load (N)", "relative (mm)", "state"),
    )
    for k in range(len(result.load)):
        state = "onset" if k == result.onset else ("sliding" if result.sliding[k] else "")
        table.add_row(
            str(k),
            f"{result.travel[k] * 1e3:.4g}",
            f"{result.load[k]:.6g}",
            f"{result.relative[k] * 1e3:.4g}",
            state,
        )
    out = console()
    out.print(table)
    if result.onset is not None:
        out.print(
            f"onset of sliding at {result.onset_force:.6g} N; c A + mu N = "
            f"{layers.limit:.6g} N with N the weight"
        )

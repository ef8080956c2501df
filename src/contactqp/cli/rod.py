"""``contactqp rod``: the rod over an obstacle, reduced model against full finite-element
contact."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from ..applications.rod import MAX_ELEMENTS
from .app import EXIT_NOT_SOLVED, console, fail, figures_table


@click.command()
@click.option(
    "--elements",
    type=click.IntRange(min=8, max=MAX_ELEMENTS),
    default=80,
    show_default=True,
    help=f"Frame elements of the full mesh, a multiple of 8 (which keeps the 8 nodes on "
    f"it) up to {MAX_ELEMENTS}: the frame's stiffness is ill-conditioned like "
    f"elements^4, round-off reaches 1e-4 of the answer at {MAX_ELEMENTS} and the "
    f"stiffness is singular to working precision from about 2400.",
)
@click.option(
    "--json", "as_json", is_flag=True, help="Print the table as one JSON object (SI units)."
)
@click.option(
    "--plot",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Draw the deformed rod over the obstacle to this PNG file.",
)
@click.option(
    "--vtu",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Write the mesh and the solutions to this VTU file (ParaView).",
)
def rod(elements: int, as_json: bool, plot: Path | None, vtu: Path | None) -> None:
    """The published rod over an obstacle: reduced model (8 nodes) against full FE contact.

    The rod (40 mm, E = 1e12 Pa, A = 0.2 mm^2) is clamped at its right end; the gap to the
    obstacle grows from 1 mm under the free left end to 5 mm under the clamp.
    """
    from ..applications.rod import (
        Rod,
        as_record,
        compare,
        plot_rod,
        result_mesh,
    )
    from ..io.export import write_vtu

    model = Rod(n_elements=elements)
    comparisons = compare(model)  # a failed reference solve: a SolverError, exit 1
    if as_json:
        click.echo(json.dumps(as_record(model, comparisons)))
    else:
        _rod_tables(model, comparisons)
    written = []
    if plot:
        written.append(plot_rod(model, comparisons, plot))
    if vtu:
        written.append(write_vtu(vtu, *result_mesh(model, comparisons)))
    if not as_json:
        for path in written:
            click.echo(f"wrote {path}")
    unsolved = [c.case.name for c in comparisons if not c.reduced.success]
    if unsolved:
        fail("reduced solve failed for " + ", ".join(unsolved))
        sys.exit(EXIT_NOT_SOLVED)


def _rod_tables(model, comparisons):
    out = console()
    x = model.frame.coordinates[model.node_indices, 0]
    for c in comparisons:
        loads = ", ".join(
            f"({load.fx:g}, {load.fy:g}) N at {load.x * 1e3:g} mm" for load in c.case.loads
        )
        table = figures_table(
            f"{c.case.name}: {loads}",
            (
                "x (mm)",
                "gap (mm)",
                "uy (mm)",
                "uy ref (mm)",
                "eps_x (%)",
                "eps_y (%)",
                "force (N)",
            ),
            caption=f"max eps {c.max_eps:.2g} % (same-node reference "
            f"{c.max_eps_same_nodes:.2g} %); reduced {c.t_reduced * 1e3:.3g} "
            f"ms, full FE contact {c.t_full * 1e3:.3g} ms; ux in --json; "
            "* absolute (m)",
        )
        uy = c.reduced.displacements.reshape(-1, 2)[:, 1]
        uy_ref = c.reference.displacements[model.node_indices, 1]
        for i in range(len(x)):
            table.add_row(
                f"{x[i] * 1e3:g}",
                f"{model.gap(x[i]) * 1e3:.3g}",
                f"{uy[i] * 1e3:.6f}",
                f"{uy_ref[i] * 1e3:.6f}",
                _eps(c.eps_x[i], c.absolute_x[i]),
                _eps(c.eps_y[i], c.absolute_y[i]),
                f"{c.reduced.forces[i]:.4g}",
            )
        out.print(table)


def _eps(value: float, absolute: bool) -> str:
    return f"{value:.1e}*" if absolute else f"{value:.1e}"

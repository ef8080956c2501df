"""``contactqp rough``: a rigid flat pressed onto a periodic rough surface, over several loads."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import click

from ..errors import InvalidInputError
from .app import EXIT_NOT_SOLVED, console, fail, figures_table, float_list, progress

#: The generated surface's defaults (used when no --surface is given).
GENERATED = {"grid": 128, "hurst": 0.8, "rms_slope": 0.1, "seed": 0}
#: The default pressures, as fractions of E* h'_rms (the linear law's scale).
RELATIVE_PRESSURES = (0.002, 0.005, 0.01, 0.02, 0.05)
DEFAULT_CELL = 1e-6  # m, for a generated surface


@click.command()
@click.option(
    "--surface",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Height map (m): .npy, .csv rows, or an .asc grid with units (see the docs); one "
    "period of a periodic surface, rows along y. Default: a generated surface.",
)
@click.option(
    "--grid",
    type=click.IntRange(min=8, max=4096),
    help=f"Generated surface: cells per side [default: {GENERATED['grid']}].",
)
@click.option(
    "--hurst",
    type=click.FloatRange(min=0, max=1, min_open=True),
    help=f"Generated surface: Hurst exponent [default: {GENERATED['hurst']}].",
)
@click.option(
    "--rms-slope",
    type=click.FloatRange(min=0, max=10, min_open=True),
    help=f"Generated surface: spectral rms slope [default: {GENERATED['rms_slope']}].",
)
@click.option(
    "--rolloff",
    type=click.FloatRange(min=1),
    help="Generated surface: roll-off wavenumber, in multiples of 2 pi / L [default: 1, none].",
)
@click.option(
    "--cutoff",
    type=click.FloatRange(min=1),
    help="Generated surface: short-wavelength cut-off, in multiples of 2 pi / L "
    "[default: the grid's Nyquist, N / 2].",
)
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    help=f"Generated surface: random seed [default: {GENERATED['seed']}].",
)
@click.option(
    "--cell",
    type=click.FloatRange(min=0, min_open=True),
    help=f"Side of a square cell (m); required for .npy and .csv maps [generated: {DEFAULT_CELL}].",
)
@click.option(
    "--young",
    type=click.FloatRange(min=0, min_open=True),
    default=210e9,
    show_default="210e9",
    help="Young's modulus of the half-space (Pa).",
)
@click.option(
    "--poisson",
    type=click.FloatRange(min=0, max=0.5, max_open=True),
    default=0.3,
    show_default=True,
    help="Poisson's ratio of the half-space.",
)
@click.option(
    "--pressures",
    callback=lambda ctx, param, text: None if text is None else float_list(ctx, param, text),
    help="Mean pressures over the period (Pa), increasing, comma-separated "
    "[default: E* h'_rms times 0.002, 0.005, 0.01, 0.02, 0.05].",
)
@click.option(
    "--mu",
    type=float,
    help="Friction coefficient; above 0 each pressed state is also sheared along x by "
    "Q = shear * mu * P (Coulomb per cell, the normal-tangential coupling neglected): the "
    "stick fraction, the shift and the tangential stiffness are added [default: 0].",
)
@click.option(
    "--shear",
    type=float,
    help="With --mu: the tangential force over the friction limit, Q / (mu P), in (0, 1) "
    "[default: 0.5].",
)
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help="One JSON line per load (SI units): pressure, area_fraction, mean_gap, stiffness, "
    "seconds, iterations, certificate.",
)
@click.option(
    "--plot",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Draw the area-load curve beside the linear laws, and the pressure map, to this file.",
)
@click.option(
    "--vtu",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Write the surface grid with heights, gaps and pressures of every load (ParaView).",
)
def rough(
    surface: Path | None,
    grid: int | None,
    hurst: float | None,
    rms_slope: float | None,
    rolloff: float | None,
    cutoff: float | None,
    seed: int | None,
    cell: float | None,
    young: float,
    poisson: float,
    pressures: list[float] | None,
    mu: float | None,
    shear: float | None,
    as_json: bool,
    plot: Path | None,
    vtu: Path | None,
) -> None:
    """A rigid flat pressed onto a periodic rough surface on an elastic half-space.

    For each mean pressure: the real contact area fraction, the mean gap, and the normal
    stiffness -dp/d(mean gap) by finite differences over the loads. The surface is read
    (--surface) or generated (self-affine, --grid, --hurst, --rms-slope, --seed). Exit status 1
    when a load is not solved to its certificate.
    """
    if mu is not None and not (math.isfinite(mu) and mu >= 0):
        raise InvalidInputError(f"--mu must be a friction coefficient >= 0, got {mu!r}")
    if shear is not None and not mu:
        raise InvalidInputError("--shear shears a frictional contact: give --mu > 0 with it")
    if shear is not None and not (math.isfinite(shear) and 0 < shear < 1):
        raise InvalidInputError(f"--shear must be Q / (mu P) in (0, 1), got {shear!r}")
    generated = {
        "--grid": grid,
        "--hurst": hurst,
        "--rms-slope": rms_slope,
        "--rolloff": rolloff,
        "--cutoff": cutoff,
        "--seed": seed,
    }
    if surface is not None:
        given = [name for name, value in generated.items() if value is not None]
        if given:
            raise InvalidInputError(
                f"{', '.join(given)} shape a generated surface; --surface reads one instead"
            )
    _outputs_apart(surface, plot, vtu)
    if plot is not None:
        from ..io.plot import figure_path

        figure_path(plot)  # an unwritable figure format: refused before any solve
    from ..applications.rough import heightmap
    from ..applications.rough import surface as surfaces

    if surface is not None:
        height_map = heightmap.read_height_map(surface, cell)
    else:
        n = GENERATED["grid"] if grid is None else grid
        size = DEFAULT_CELL if cell is None else cell
        heights = surfaces.self_affine_surface(
            int(n),
            size,
            hurst=GENERATED["hurst"] if hurst is None else hurst,
            rms_slope=GENERATED["rms_slope"] if rms_slope is None else rms_slope,
            rolloff=rolloff,
            short_cutoff=cutoff,
            seed=int(GENERATED["seed"] if seed is None else seed),
        )
        height_map = heightmap.HeightMap(heights, size)
    slope = surfaces.rms_slope(height_map.heights, height_map.cell)
    if pressures is None:
        if not slope > 0:
            raise InvalidInputError("the surface is flat (rms slope 0); give --pressures")
        scale = young / (1 - poisson**2) * slope
        pressures = [fraction * scale for fraction in RELATIVE_PRESSURES]
    from ..applications.rough.contact import solve_rough_contact

    with progress("load") as report:
        contact = solve_rough_contact(
            height_map,
            pressures,
            young=young,
            poisson=poisson,
            mu=mu or 0.0,
            shear=0.5 if shear is None else shear,
            progress=report,
        )
    if as_json:
        for point in contact.points:
            click.echo(json.dumps(point.as_record()))
    else:
        _table(contact)
    if plot:
        from ..applications.rough.output import plot_rough_contact

        plot_rough_contact(contact, plot)
        if not as_json:
            click.echo(f"figure written to {plot}")
    if vtu:
        from ..applications.rough.output import rough_mesh
        from ..io.export import write_vtu

        write_vtu(vtu, *rough_mesh(contact))
        if not as_json:
            click.echo(f"grid written to {vtu}")
    if not contact.solved:
        failed = [f"{p.pressure:.6g}" for p in contact.points if not p.certificate]
        fail(f"not solved to the certificate at {len(failed)} load(s): {', '.join(failed)} Pa")
        sys.exit(EXIT_NOT_SOLVED)


def _outputs_apart(surface: Path | None, plot: Path | None, vtu: Path | None) -> None:
    """Refuse outputs that would overwrite the input surface or each other."""
    if plot is not None and vtu is not None and _same(plot, vtu):
        raise InvalidInputError(f"--plot and --vtu name the same file {plot}")
    for option, path in (("--plot", plot), ("--vtu", vtu)):
        if surface is not None and path is not None and _same(path, surface):
            raise InvalidInputError(f"{option} {path} would overwrite the input surface")


def _same(a: Path, b: Path) -> bool:
    if a.exists() and b.exists():
        return a.samefile(b)
    return a.resolve() == b.resolve()


def _table(contact) -> None:
    surface = contact.surface
    ny, nx = surface.shape
    table = figures_table(
        f"Rough contact: {nx} x {ny} cells of {surface.cell:.4g} m, "
        f"E* = {contact.modulus:.4g} Pa, h'rms = {contact.rms_slope:.4g}",
        (
            "pressure (Pa)",
            "area fraction",
            "linear law",
            "mean gap (m)",
            "stiffness (Pa/m)",
            "iterations",
            "seconds",
            "certified",
        ),
    )
    for point in contact.points:
        table.add_row(
            f"{point.pressure:.6g}",
            f"{point.area_fraction:.4f}",
            f"{float(contact.linear_law(point.pressure)):.4f}" if contact.rms_slope > 0 else "",
            f"{point.mean_gap:.4g}",
            "" if point.stiffness is None else f"{point.stiffness:.4g}",
            str(point.iterations),
            f"{point.seconds:.3g}",
            "yes" if point.certificate else "NO",
        )
    out = console()
    out.print(table)
    out.print(
        "linear law: area fraction = kappa p / (E* h'rms), kappa = sqrt(8/pi) (Persson); "
        "stiffness = -dp/d(mean gap)"
    )
    if contact.mu > 0:
        shear = figures_table(
            f"Sheared by Q = {contact.shear:g} mu P along x, mu = {contact.mu:g} (the "
            "normal-tangential coupling neglected)",
            ("pressure (Pa)", "stick fraction", "shift (m)", "stiffness Q/(A shift)"),
        )
        for point in contact.points:
            stiffness = point.tangential_stiffness
            shear.add_row(
                f"{point.pressure:.6g}",
                f"{point.stick_fraction:.4f}",
                f"{point.shift:.4g}",
                "" if stiffness is None else f"{stiffness:.4g} Pa/m",
            )
        out.print(shear)

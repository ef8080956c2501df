"""``contactqp assembly``: an assembly file's fastening sequence, variation study and shims."""

from __future__ import annotations

import json
import sys
from contextlib import nullcontext
from pathlib import Path

import click

from .app import EXIT_NOT_SOLVED, console, fail, progress

#: Columns of the printed tables when stdout is not a terminal.
WIDE = 160


@click.command()
@click.argument("assembly_file", metavar="ASSEMBLY.toml", type=click.Path(path_type=Path))
@click.option(
    "--samples",
    type=click.IntRange(min=1, max=10**7),  # batch.MAX_SAMPLES
    help="Samples of the variation study  [default: 1000 for random fields, every "
    "realisation of a file]",
)
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    help="Root seed of random gap fields, instead of the file's variation.seed.",
)
@click.option(
    "--workers",
    type=click.IntRange(min=1),
    default=1,
    show_default=True,
    help="Local worker processes (ignored with --scheduler).",
)
@click.option("--scheduler", metavar="ADDRESS", help="Dask scheduler address (tcp://host:port).")
@click.option(
    "--out",
    type=click.Path(path_type=Path),
    required=True,
    help="Output directory (may be the file's own); a study already there is resumed.",
)
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help="End with one JSON line: the nominal sequence's summary and the study's.",
)
@click.option(
    "--plot",
    is_flag=True,
    help="Also write gap.png, status.png, fastener_forces.png and statistics.png in --out.",
)
def assembly(assembly_file, samples, seed, workers, scheduler, out, as_json, plot):
    """Fasten the parts of an assembly file, then vary its gaps.

    Installs the fasteners in the file's order on the nominal gaps, then applies its load
    steps, and writes to --out: stages.csv and fasteners.csv (every pair and fastener at every
    stage), stage_001.vtu ... with stages.pvd (ParaView), shims.csv (with a shim tolerance).
    With a [variation] table, also samples.h5 (one row per sample, resumable) and
    statistics.csv (per pair: mean and quantiles of the residual gap, probability of contact
    and of a gap above the shim tolerance). The file's schema: docs/assembly-files.md.
    """
    from ..applications.fastening.output import sequence_summary
    from ..applications.fastening.workflow import run_assembly_study

    names = {param.name: param.opts[0] for param in click.get_current_context().command.params}
    names["assembly_file"] = "ASSEMBLY.toml"
    # a progress bar on a terminal only: elsewhere stderr stays for the one error line
    bar = progress("sample") if sys.stderr.isatty() else nullcontext(None)
    with bar as report:
        study = run_assembly_study(
            assembly_file,
            out,
            samples=samples,
            seed=seed,
            workers=workers,
            scheduler=scheduler,
            plot=plot,
            progress=report,
            names=names,
        )
    tolerance = study.input.shim_tolerance
    if as_json:
        click.echo(
            json.dumps(_summary(study, sequence_summary(study.nominal, shim_tolerance=tolerance)))
        )
    else:
        _print(study, tolerance)
    nominal, summary = study.nominal, study.summary
    if not nominal.success:
        failed = next(stage for stage in nominal.stages if not stage.success)
        fail(
            f"the nominal sequence failed at {failed.label!r}: {failed.result.message}; "
            f"what was computed is in {out}"
        )
        sys.exit(EXIT_NOT_SOLVED)
    if summary is not None and study.statistics is None:
        fail(
            f"all {summary.samples} samples failed (see 'success' in {summary.path}); "
            "no statistics written"
        )
        sys.exit(EXIT_NOT_SOLVED)
    if summary is not None and summary.failed:
        fail(
            f"{summary.failed} of {summary.samples} samples failed "
            f"(see 'success' in {summary.path})"
        )
        sys.exit(EXIT_NOT_SOLVED)


def _summary(study, nominal: dict) -> dict:
    """The JSON line: the nominal summary, the notes and the study's summary."""
    error = study.interpolation_error
    result = {
        "name": study.input.name,
        **nominal,
        "interpolation_error": None
        if error is None
        else {"max_abs": error.max_abs, "rms": error.rms, "points": error.n_points},
        "unmatched": [item.describe() for item in study.unmatched],
        "files": sorted(study.files),
        "study": None,
    }
    if study.summary is not None:
        stats = study.statistics
        result["study"] = {
            **study.summary.as_dict(),
            "variation": study.input.variation_description,
            "mean_gap": None if stats is None else stats.mean.tolist(),
            "contact_probability": None if stats is None else stats.contact_probability.tolist(),
            "shim_probability": None
            if stats is None or stats.shim_probability is None
            else stats.shim_probability.tolist(),
        }
    return result


def _print(study, tolerance) -> None:
    from ..applications.fastening.output import sequence_table

    out = console()
    if not out.is_terminal:  # a log or a pipe: room for the table's columns, unwrapped
        out.width = max(out.width, WIDE)
    name = study.input.name or study.input.path.name
    out.print(
        sequence_table(
            study.nominal,
            title=f"{name}: nominal fastening sequence ({study.assembly.n_pairs} pairs)",
            shim_tolerance=tolerance,
        )
    )
    for line in study.notes():
        out.print(line)
    if tolerance is not None:
        out.print(_shim_line(study.nominal.final, tolerance))
    summary, stats = study.summary, study.statistics
    if summary is not None:
        line = (
            f"variation study: {summary.samples} samples, {summary.computed} computed, "
            f"{summary.reused} reused, {summary.failed} failed in {summary.seconds:.3g} s"
        )
        if stats is not None:
            line += (
                f"; mean residual gap {stats.mean.mean() * 1e3:.4g} mm, largest probability "
                f"of contact {stats.contact_probability.max():.3g}"
            )
            if stats.shim_probability is not None:
                line += f", of a shim {stats.shim_probability.max():.3g}"
        out.print(line)
    folders = sorted({str(path.parent) for path in study.files.values()})
    out.print(f"wrote {len(study.files)} files to {', '.join(folders)}")


def _shim_line(stage, tolerance: float, shown: int = 20) -> str:
    """The pairs of the last stage above the shim tolerance, the first ``shown`` of them."""
    from ..applications.fastening.output import shim_pairs

    pairs = shim_pairs(stage, tolerance).tolist()
    listed = ", ".join(map(str, pairs[:shown])) + (", ..." if len(pairs) > shown else "")
    return f"pairs needing a shim (gap > {tolerance * 1e3:.4g} mm after the last stage): " + (
        f"{len(pairs)}: {listed} (shims.csv)" if pairs else "none"
    )

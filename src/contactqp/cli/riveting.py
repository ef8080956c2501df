"""``contactqp riveting``: two plates fastened over a gap field, nominal sequence and variation."""

from __future__ import annotations

import json
import sys
from contextlib import contextmanager
from pathlib import Path

import click
import numpy as np

from ..core.status import ContactStatus
from ..methods.registry import default_method, methods_for
from .app import EXIT_NOT_SOLVED, console, fail, figures_table


@click.command()
@click.option(
    "--samples",
    type=click.IntRange(min=1, max=10**7),  # batch.MAX_SAMPLES
    help="Gap-field samples of the variation study  [default: 1000, or every row of --gaps]",
)
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    default=0,
    show_default=True,
    help="Root seed: sample k is the same whatever the workers.",
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
    type=click.Path(file_okay=False, path_type=Path),
    required=True,
    help="Output directory; a study already there is resumed.",
)
@click.option(
    "--gaps",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Gap realisations (m), one per row (.npy or .csv), instead of random fields; "
    "the nominal gap is then their mean.",
)
@click.option(
    "--mean-gap",
    type=click.FloatRange(max=1.0),
    default=2e-4,
    show_default=True,
    help="Nominal gap (m); negative: interference.",
)
@click.option(
    "--amplitude",
    type=click.FloatRange(min=0, max=1.0),
    default=1e-4,
    show_default=True,
    help="Standard deviation of the gap field (m).",
)
@click.option(
    "--correlation-length",
    type=click.FloatRange(min=0, min_open=True, max=1e3),
    default=0.04,
    show_default=True,
    help="Correlation length of the gap field (m).",
)
@click.option(
    "--method",
    type=click.Choice([m.name for m in methods_for("fastened")]),
    default=default_method("fastened"),
    show_default=True,
    help="Solver of each sample (nnls: scipy's, not warm started).",
)
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help="End with one JSON line: samples, computed, reused, failed, seconds, residual_gap_mean.",
)
@click.option("--plot", is_flag=True, help="Write nominal.png and statistics.png in --out.")
def riveting(
    samples,
    seed,
    workers,
    scheduler,
    out,
    gaps,
    mean_gap,
    amplitude,
    correlation_length,
    method,
    as_json,
    plot,
):
    """Two 200 x 100 x 2 mm aluminium plates riveted over a gap field (frictionless).

    Writes to --out: nominal.vtu, nominal_contacts.csv and nominal_sequence.csv (the nominal
    gap, fasteners installed one by one), samples.h5 (one row per sample, resumable) and
    statistics.csv (mean, quantiles of the final gap and probability of contact per pair).
    """
    from ..applications.riveting_study import run_riveting_study

    names = {param.name: param.opts[0] for param in click.get_current_context().command.params}
    with _progress_bar() as progress:
        study = run_riveting_study(
            out,
            samples=samples,
            seed=seed,
            workers=workers,
            scheduler=scheduler,
            gaps=gaps,
            mean_gap=mean_gap,
            amplitude=amplitude,
            correlation_length=correlation_length,
            method=method,
            plot=plot,
            progress=progress,
            names=names,
        )
    summary, stats, sequence = study.summary, study.statistics, study.sequence
    if stats is None:  # a failed solve, not bad input: exit 1
        fail(
            f"all {summary.samples} samples failed (see 'success' in {summary.path}); "
            "no statistics written"
        )
        sys.exit(EXIT_NOT_SOLVED)
    if as_json:
        click.echo(json.dumps({**summary.as_dict(), "residual_gap_mean": stats.mean.tolist()}))
    else:
        _tables(study.model, sequence, summary, stats)
    if not sequence.success:
        fail(
            "the nominal fastening sequence failed: "
            + next(s.message for s in sequence.steps if not s.success)
        )
        sys.exit(EXIT_NOT_SOLVED)
    if summary.failed:
        fail(
            f"{summary.failed} of {summary.samples} samples failed (see 'success' in "
            f"{summary.path})"
        )
        sys.exit(EXIT_NOT_SOLVED)


@contextmanager
def _progress_bar():
    """A progress callback for the samples: a bar on stderr, shown from its first call, when
    that is a terminal; else None (stderr then stays for the one error line)."""
    from rich.console import Console

    terminal = Console(stderr=True)
    if not terminal.is_terminal:
        yield None
        return
    from rich.progress import Progress

    bar = Progress(console=terminal, transient=True)
    task = None

    def report(done: int, total: int) -> None:
        nonlocal task
        if task is None:
            bar.start()
            task = bar.add_task("samples", total=total)
        bar.update(task, completed=done)

    try:
        yield report
    finally:
        bar.stop()


def _tables(model, sequence, summary, stats):
    out = console()
    table = figures_table(
        f"Nominal fastening sequence ({model.n_pairs} pairs)",
        ("step", "x (mm)", "y (mm)", "tension (N)", "contacts", "max gap (mm)"),
    )
    for n, step in enumerate(sequence.steps, 1):
        pair = step.fasteners[-1]
        table.add_row(
            str(n),
            f"{model.points[pair, 0] * 1e3:.4g}",
            f"{model.points[pair, 1] * 1e3:.4g}",
            f"{step.fastener_forces[-1]:.4g}",
            str(int(np.count_nonzero(step.contact_status == ContactStatus.CLOSED))),
            f"{step.gaps.max() * 1e3:.4g}",
        )
    out.print(table)
    final = sequence.final
    out.print(
        "final fastener tensions (N): " + ", ".join(f"{t:.4g}" for t in final.fastener_forces)
    )
    out.print(
        f"variation: {summary.samples} samples, {summary.computed} computed, "
        f"{summary.reused} reused, {summary.failed} failed in {summary.seconds:.3g} s; "
        f"mean final gap {stats.mean.mean() * 1e3:.4g} mm, largest probability of "
        f"contact {stats.contact_probability.max():.3g}"
    )

"""``contactqp riveting``: two plates fastened over a gap field, nominal sequence and variation."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click
import numpy as np

from .app import EXIT_NOT_SOLVED, cli, console, fail, warn


@cli.command()
@click.option("--samples", type=click.IntRange(min=1, max=10**7),  # batch.MAX_SAMPLES
              help="Gap-field samples of the variation study  [default: 1000, or every row "
                   "of --gaps]")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True,
              help="Root seed: sample k is the same whatever the workers.")
@click.option("--workers", type=click.IntRange(min=1), default=1, show_default=True,
              help="Local worker processes (ignored with --scheduler).")
@click.option("--scheduler", metavar="ADDRESS", help="Dask scheduler address (tcp://host:port).")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output directory; a study already there is resumed.")
@click.option("--gaps", "gap_file", type=click.Path(dir_okay=False, path_type=Path),
              help="Gap realisations (m), one per row (.npy or .csv), instead of random fields; "
                   "the nominal gap is then their mean.")
@click.option("--mean-gap", type=click.FloatRange(max=1.0), default=2e-4, show_default=True,
              help="Nominal gap (m); negative: interference.")
@click.option("--amplitude", type=click.FloatRange(min=0, max=1.0), default=1e-4, show_default=True,
              help="Standard deviation of the gap field (m).")
@click.option("--correlation-length", type=click.FloatRange(min=0, min_open=True, max=1e3),
              default=0.04,
              show_default=True, help="Correlation length of the gap field (m).")
@click.option("--method", type=click.Choice(["lawson-hanson", "active-set", "nnls"]),
              default="lawson-hanson", show_default=True,
              help="Solver of each sample (nnls: scipy's, not warm started).")
@click.option("--json", "as_json", is_flag=True,
              help="End with one JSON line: samples, computed, reused, failed, seconds, "
                   "residual_gap_mean.")
@click.option("--plot", is_flag=True, help="Write nominal.png and statistics.png in --out.")
def riveting(samples, seed, workers, scheduler, out, gap_file, mean_gap, amplitude,
             correlation_length, method, as_json, plot):
    """Two 200 x 100 x 2 mm aluminium plates riveted over a gap field (frictionless).

    Writes to --out: nominal.vtu, nominal_contacts.csv and nominal_sequence.csv (the nominal
    gap, fasteners installed one by one), samples.h5 (one row per sample, resumable) and
    statistics.csv (mean, quantiles of the final gap and probability of contact per pair).
    """
    from ..studies.batch import GaussianGapField, load_batch, load_gap_samples, run_batch
    from ..io.export import write_csv, write_vtu
    from ..applications.riveting import Assembly, FasteningCase, STATUS_LABELS, result_mesh

    model = Assembly().build()
    if gap_file is not None:
        source = load_gap_samples(gap_file)
        nominal_gaps = source.samples.mean(axis=0)
        samples = source.n_available if samples is None else samples
    else:
        source = GaussianGapField(model.points, amplitude, correlation_length, mean=mean_gap,
                                  seed=seed)
        nominal_gaps = source.mean
        samples = 1000 if samples is None else samples
    if nominal_gaps.shape != (model.n_pairs,):
        raise click.BadParameter(f"gap realisations must have {model.n_pairs} columns, got "
                                 f"{nominal_gaps.shape[0]}", param_hint="--gaps")
    # absurd gaps are refused before anything is written (unusual ones are warned about below)
    model.check_gaps(nominal_gaps, "--mean-gap" if gap_file is None else "the mean of --gaps")
    out.mkdir(parents=True, exist_ok=True)
    case = FasteningCase(model, method=method)
    # a bad scheduler, or a store of another study in --out, is refused before the nominal
    # files are written
    run_batch(case, source, samples, out / "samples.h5", scheduler=scheduler, limit=0)
    sequence = model.fasten(nominal_gaps, method=method)
    # warnings once the input is known to be valid, so that bad input stays one line
    thickness = model.thickness
    for name, value in [("nominal gap", float(nominal_gaps.max())),
                        ("--amplitude", amplitude if gap_file is None else 0.0)]:
        if value > thickness:
            warn(f"{name} {value * 1e3:.4g} mm exceeds the {thickness * 1e3:.4g} mm plate "
                 "thickness: far beyond small deflections, where the linear plate model holds")
    if gap_file is None and mean_gap < 0:
        warn(f"--mean-gap {mean_gap:g} m is negative: the plates overlap by "
             f"{-mean_gap * 1e3:.4g} mm at rest (interference)")
    final = sequence.final
    xy = model.points
    write_vtu(out / "nominal.vtu", *result_mesh(model, final, nominal_gaps))
    write_csv(out / "nominal_contacts.csv", {
        "x": xy[:, 0], "y": xy[:, 1], "initial_gap": nominal_gaps, "gap": final.contact.gaps,
        "force": final.contact.forces, "status": [STATUS_LABELS[s] for s in final.status]})
    pairs = model.fasteners[sequence.order]
    write_csv(out / "nominal_sequence.csv", {
        "step": np.arange(1, len(pairs) + 1), "pair": pairs, "x": xy[pairs, 0], "y": xy[pairs, 1],
        "tension": [step.fastener_forces[-1] for step in sequence.steps],
        "closed": [int(np.count_nonzero(step.contact.closed)) for step in sequence.steps],
        "max_gap": [float(step.contact.gaps.max()) for step in sequence.steps]})

    summary = _run(case, source, samples, out / "samples.h5", workers, scheduler)
    data = load_batch(out / "samples.h5", samples)  # not the rest of a longer past study
    if not data.fields["success"].any():  # a failed solve, not bad input: exit 1
        fail(f"all {summary.samples} samples failed (see 'success' in {out / 'samples.h5'}); "
             "no statistics written")
        sys.exit(EXIT_NOT_SOLVED)
    stats = data.statistics()
    write_csv(out / "statistics.csv", {
        "x": xy[:, 0], "y": xy[:, 1], "mean_gap": stats.mean,
        **{f"gap_q{level * 100:g}": q for level, q in zip(stats.levels, stats.quantiles)},
        "contact_probability": stats.contact_probability})
    if plot:
        from ..applications.riveting import plot_status
        from ..io.plot import plot_statistics

        plot_status(model, final, nominal_gaps, out / "nominal.png")
        plot_statistics(stats, xy, out / "statistics.png")
    if as_json:
        click.echo(json.dumps({**summary.as_dict(), "residual_gap_mean": stats.mean.tolist()}))
    else:
        _tables(model, sequence, summary, stats)
    if not sequence.success:
        fail("the nominal fastening sequence failed: "
             + next(s.contact.message for s in sequence.steps if not s.success))
        sys.exit(EXIT_NOT_SOLVED)
    if summary.failed:
        fail(f"{summary.failed} of {summary.samples} samples failed (see 'success' in "
             f"{out / 'samples.h5'})")
        sys.exit(EXIT_NOT_SOLVED)


def _run(case, source, samples, path, workers, scheduler):
    """run_batch with a progress bar on stderr when it is a terminal (else stderr stays for
    the one error line)."""
    from rich.console import Console
    from rich.progress import Progress

    from ..studies.batch import run_batch

    terminal = Console(stderr=True)
    if not terminal.is_terminal:
        return run_batch(case, source, samples, path, workers=workers, scheduler=scheduler)
    with Progress(console=terminal, transient=True) as bar:
        task = bar.add_task("samples", total=samples)
        return run_batch(case, source, samples, path, workers=workers, scheduler=scheduler,
                         progress=lambda done, total: bar.update(task, completed=done))


def _tables(model, sequence, summary, stats):
    from rich.table import Table

    out = console()
    table = Table(title=f"Nominal fastening sequence ({model.n_pairs} pairs)")
    for column in ("step", "x (mm)", "y (mm)", "tension (N)", "contacts", "max gap (mm)"):
        table.add_column(column, justify="right")
    for n, step in enumerate(sequence.steps, 1):
        pair = step.fasteners[-1]
        table.add_row(str(n), f"{model.points[pair, 0] * 1e3:.4g}",
                      f"{model.points[pair, 1] * 1e3:.4g}", f"{step.fastener_forces[-1]:.4g}",
                      str(int(np.count_nonzero(step.contact.closed))),
                      f"{step.contact.gaps.max() * 1e3:.4g}")
    out.print(table)
    final = sequence.final
    out.print("final fastener tensions (N): "
              + ", ".join(f"{t:.4g}" for t in final.fastener_forces))
    out.print(f"variation: {summary.samples} samples, {summary.computed} computed, "
              f"{summary.reused} reused, {summary.failed} failed in {summary.seconds:.3g} s; "
              f"mean final gap {stats.mean.mean() * 1e3:.4g} mm, largest probability of "
              f"contact {stats.contact_probability.max():.3g}")

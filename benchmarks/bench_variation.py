"""Variation simulation of the riveted assembly: samples per second, cold and warm, 1 and 2 workers.

The assembly is :class:`contactqp.applications.riveting.Assembly` with its defaults: two
200 x 100 x 2 mm aluminium plates, 25 x 21 = 525 contact pairs, 6 fasteners closing their pairs.
Gap fields are :class:`contactqp.studies.sources.GaussianGapField` samples (mean 0.2 mm,
sigma 0.1 mm, correlation length 40 mm). Each row of the table runs
:func:`contactqp.studies.batch.run_batch` into a fresh HDF5 store (writing and flushing included)
and reports samples per second of wall time; building the model (assembly and condensation) is timed
once, apart.

Rows:

* ``<method>, cold``: every sample from the solver's own cold start;
* ``<method>, warm``: each sample warm started from the previous one of its chunk;

for the methods of fastened problems (:func:`contactqp.solve` on a
:class:`~contactqp.core.fastened.FastenedProblem`, the Schur-reduced dual):
``lawson-hanson`` (the default, bordered Cholesky factors), ``active-set`` (the project's
primal-dual box-QP solver) and ``nnls`` (scipy's, cold only),

each with 1 worker (in-process) and 2 worker processes. Then the target run: ``--target``
samples (10,000 by default) with the fastest configuration.

Run ``python benchmarks/bench_variation.py --help`` for the options.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from contactqp.applications.riveting import Assembly, FasteningCase
from contactqp.studies import GaussianGapField, run_batch


class ColdStart(FasteningCase):
    """Every sample from the solver's own cold start (the warm start is dropped)."""

    def solve_sample(self, gaps, warm):
        return super().solve_sample(gaps, None)


def rate(case, source, samples, workers, chunk, directory: Path, name: str):
    """(samples per second, failed) of one run_batch into a new store."""
    summary = run_batch(
        case, source, samples, directory / f"{name}.h5", workers=workers, chunk_size=chunk
    )
    assert summary.computed == samples
    return samples / summary.seconds, summary.failed


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--samples", type=int, default=400, help="samples per row of the comparison (default 400)"
    )
    parser.add_argument(
        "--target",
        type=int,
        default=10_000,
        help="samples of the final run (0: skip; default 10000)",
    )
    parser.add_argument("--chunk", type=int, default=50, help="samples per task (default 50)")
    args = parser.parse_args(argv)

    print(
        f"# machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"python {platform.python_version()}, numpy {np.__version__}"
    )
    start = time.perf_counter()
    model = Assembly().build()
    build = time.perf_counter() - start
    source = GaussianGapField(model.points, 1e-4, 0.04, mean=2e-4, seed=0)
    print(
        f"# model: {model.n_pairs} contact pairs, {len(model.fasteners)} fasteners; "
        f"build (2 plates, Morley, condensation) {build:.2f} s"
    )
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp)
        kinds = {"cold": ColdStart, "warm": FasteningCase}
        configurations = [
            (method, start)
            for method in ("lawson-hanson", "active-set")
            for start in ("cold", "warm")
        ] + [("nnls", "cold")]
        for method, start in configurations:
            case = kinds[start](model, method=method)
            for workers in (1, 2):
                samples = args.samples if method != "active-set" else max(args.samples // 4, 8)
                per_second, failed = rate(
                    case,
                    source,
                    samples,
                    workers,
                    args.chunk,
                    directory,
                    f"{method}-{start}-{workers}",
                )
                rows.append((f"{method}, {start}", workers, samples, per_second, failed))
        print()
        print("| solver | workers | samples | samples/s | s per 10,000 | failed |")
        print("|---|---:|---:|---:|---:|---:|")
        for label, workers, samples, per_second, failed in rows:
            print(
                f"| {label} | {workers} | {samples} | {per_second:.1f} | "
                f"{1e4 / per_second:.0f} | {failed} |"
            )
        if args.target:
            label, workers, *_ = max(rows, key=lambda r: r[3])
            method, start = label.split(", ")
            summary = run_batch(
                kinds[start](model, method=method),
                source,
                args.target,
                directory / "target.h5",
                workers=workers,
                chunk_size=args.chunk,
            )
            print()
            print(
                f"target: {summary.samples} samples ({label}, {workers} workers) in "
                f"{summary.seconds:.1f} s, {summary.failed} failed "
                f"({summary.samples / summary.seconds:.0f} samples/s; goal: 60 s)"
            )


if __name__ == "__main__":
    main()

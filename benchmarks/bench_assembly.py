"""Frictional fastening sequence of a ~500-pair assembly: nominal time and variation cost.

The assembly is an :class:`contactqp.applications.fastening.Assembly` of the two finite-element
parts of :class:`contactqp.applications.riveting_friction.FrictionAssembly`: 200 x 100 mm
aluminium plates (2 mm and 1.2 mm thick) meshed with ``--cells`` (27 x 18 by default: 26 x 19
= 494 pairs), each condensed to its interface (its own flexibility, 1,482 freedoms). The FE
build (meshing and condensation, about a minute under load) is cached in a ``.npz`` in the
temporary directory, keyed by the cells. Eight bonded clamp fasteners (500 N preload, axial
stiffness 1e8 N/m) are installed one by one along the middle row, ``mu = 0.3``; the initial
gaps are 20 um plus a 10 um white noise (seed 0).

Printed, as a markdown table:

* **nominal**: ``Assembly(...).sequence(gaps)`` on a fresh assembly (the contact operator
  assembled, then the 8 stages): the first call (the headline) and the best of 3 (each best
  wall and best CPU time, the CPU time in parentheses);
* **variation**: ``--samples`` samples of
  :class:`~contactqp.applications.fastening.SequenceVariation` (another 5 um of noise per
  sample), each the whole sequence, warm started from the nominal stages
  (``start="nominal"``) or from the sample's previous stage (``start="previous"``),
  frictional (``mu = 0.3``) and frictionless (the same assembly with ``mu = 0``), per sample,
  their ratio, and the extrapolation to 10,000 samples on 2 workers (half the samples each).

With ``--study N``, also a real study: ``N`` frictional samples (warm started from the nominal)
through :func:`contactqp.studies.run_batch` on ``--workers`` local processes into a temporary
HDF5 store, the way ``contactqp assembly --samples N --workers K`` runs them: its wall time
(the workers' start-up and the store included) beside the extrapolation.

Run ``python benchmarks/bench_assembly.py --help`` for the options. One BLAS thread is used
(as each of two workers would).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from contactqp import ReducedModel
from contactqp.applications.fastening import (
    Assembly,
    AssemblyPart,
    Fastener,
    InterfacePairs,
)
from contactqp.applications.fastening.study import SequenceVariation

MU = 0.3
CLAMP = 500.0  # N per fastener
STIFFNESS = 1e8  # N/m, each fastener's axial stiffness
FASTENERS = 8


def fe_parts(cells) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, int]]:
    """``(R_lower, R_upper, coordinates, grid)`` of FrictionAssembly's parts, cached."""
    nx, ny = (int(n) for n in cells)
    cache = Path(tempfile.gettempdir()) / f"contactqp-bench-assembly-{nx}x{ny}.npz"
    if cache.exists():
        data = np.load(cache)
        return data["lower"], data["upper"], data["coordinates"], tuple(data["grid"])
    from contactqp.applications.assembly import Part
    from contactqp.applications.riveting_friction import FrictionAssembly

    built = FrictionAssembly(
        lower=Part(length=0.2, width=0.1),
        upper=Part(length=0.2, width=0.1, thickness=0.0012),
        cells=(nx, ny),
    ).build()
    k = built.n_pairs
    R = built.model.flexibility
    lower, upper = R[: 3 * k, : 3 * k].copy(), R[3 * k :, 3 * k :].copy()
    coordinates, grid = built.model.coordinates, built.grid
    np.savez(cache, lower=lower, upper=upper, coordinates=coordinates, grid=np.array(grid))
    return lower, upper, coordinates, grid


def make_assembly(parts, mu) -> Assembly:
    """The two parts, their pairs node i to node i (normal +z), 8 clamps on the middle row."""
    lower, upper, coordinates, (nx, ny) = parts
    k = len(lower) // 3
    columns = np.linspace(1, nx - 2, FASTENERS).round().astype(int)
    fasteners = [
        Fastener(int(i + nx * (ny // 2)), kind="clamp", force=CLAMP, stiffness=STIFFNESS)
        for i in columns
    ]
    interface = InterfacePairs(
        "lower",
        "upper",
        np.column_stack([np.arange(k), np.arange(k)]),
        np.tile([0, 0, 1.0], (k, 1)),
    )
    return Assembly(
        [
            AssemblyPart(
                "lower", ReducedModel(flexibility=lower, dofs_per_node=3), coordinates[:k]
            ),
            AssemblyPart(
                "upper", ReducedModel(flexibility=upper, dofs_per_node=3), coordinates[k:]
            ),
        ],
        [interface],
        fasteners,
        mu=mu,
    )


def nominal(parts, gaps, mu):
    """``(seconds, CPU seconds, sequence)``: a fresh assembly's whole sequence (its operator
    included)."""
    assembly = make_assembly(parts, mu)
    start, cpu = time.perf_counter(), time.process_time()
    sequence = assembly.sequence(gaps)
    return time.perf_counter() - start, time.process_time() - cpu, sequence


def variation(parts, gaps, samples, mu, start):
    """``(seconds per sample, CPU seconds per sample, certified samples)`` of a
    SequenceVariation (its nominal sequence apart)."""
    case = SequenceVariation(make_assembly(parts, mu), gaps, start=start)
    clock, cpu, solved = time.perf_counter(), time.process_time(), 0
    for sample in samples:
        record, _ = case.solve_sample(sample, None)
        solved += bool(record["success"])
    n = len(samples)
    return (time.perf_counter() - clock) / n, (time.process_time() - cpu) / n, solved


def study(parts, gaps, samples, workers):
    """``(seconds, certified, failed)`` of a real frictional study of ``samples`` (rows) on
    ``workers`` processes, its nominal sequence apart."""
    from contactqp.studies import GapSamples, run_batch

    case = SequenceVariation(make_assembly(parts, MU), gaps, start="nominal")
    with tempfile.TemporaryDirectory() as directory:
        clock = time.perf_counter()
        summary = run_batch(
            case,
            GapSamples(samples),
            len(samples),
            Path(directory) / "samples.h5",
            workers=workers,
        )
        seconds = time.perf_counter() - clock
    return seconds, summary.computed - summary.failed, summary.failed


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cells", type=int, nargs=2, default=(27, 18), help="cells along x, y")
    parser.add_argument("--samples", type=int, default=100, help="variation samples")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--study", type=int, default=0, help="samples of a real study (0: none)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes of --study")
    args = parser.parse_args(argv)
    clock = time.perf_counter()
    parts = fe_parts(args.cells)
    built = time.perf_counter() - clock
    k = len(parts[0]) // 3
    rng = np.random.default_rng(args.seed)
    gaps = 2e-5 + 1e-5 * rng.standard_normal(k)
    first, first_cpu, sequence = nominal(parts, gaps, MU)
    best, best_cpu = (
        min(times) for times in zip(*(nominal(parts, gaps, MU)[:2] for _ in range(3)), strict=True)
    )
    first_0, first_0_cpu, _ = nominal(parts, gaps, 0.0)
    best_0, best_0_cpu = (
        min(times) for times in zip(*(nominal(parts, gaps, 0.0)[:2] for _ in range(3)), strict=True)
    )
    samples = gaps + 5e-6 * rng.standard_normal((args.samples, k))
    rows = {}
    for mu in (MU, 0.0):
        for start in ("nominal", "previous"):
            rows[mu, start] = variation(parts, gaps, samples, mu, start)
    print(
        f"model: {k} pairs, {FASTENERS} clamp fasteners ({CLAMP:g} N, {STIFFNESS:g} N/m), "
        f"mu = {MU}; parts loaded in {built:.1f} s (FE build cached); load average "
        f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"
    )
    iterations = [stage.result.iterations for stage in sequence.stages]
    print(f"nominal stages: iterations {iterations}, all certified: {sequence.success}\n")
    n = args.samples
    print("| run | first call (CPU) | best of 3 / per sample (CPU) | target |")
    print("| --- | ---: | ---: | --- |")
    print(
        f"| nominal sequence, mu = {MU} | {first:.3f} s ({first_cpu:.3f}) | {best:.3f} s "
        f"({best_cpu:.3f}) | < 0.5 s |"
    )
    print(
        f"| nominal sequence, mu = 0 | {first_0:.3f} s ({first_0_cpu:.3f}) | {best_0:.3f} s "
        f"({best_0_cpu:.3f}) | |"
    )
    for start in ("nominal", "previous"):
        (fr, fr_cpu, ok), (fl, fl_cpu, ok_0) = rows[MU, start], rows[0.0, start]
        print(
            f"| variation from {start}, mu = {MU} ({ok}/{n} certified) | | "
            f"{1e3 * fr:.1f} ms ({1e3 * fr_cpu:.1f}) | <= 120 ms per core |"
        )
        print(
            f"| variation from {start}, mu = 0 ({ok_0}/{n} certified) | | "
            f"{1e3 * fl:.1f} ms ({1e3 * fl_cpu:.1f}) | |"
        )
        print(f"| ratio frictional / frictionless, from {start} | | {fr / fl:.1f}x | <= 40x |")
        print(
            f"| 10,000 frictional samples on 2 workers, from {start} (extrapolated) | | "
            f"{10_000 * fr / 2 / 60:.1f} min | <= 10 min |"
        )

    if args.study:
        field = gaps + 5e-6 * np.random.default_rng(args.seed + 1).standard_normal((args.study, k))
        seconds, certified, failed = study(parts, gaps, field, args.workers)
        print(
            f"| {args.study:,} frictional samples on {args.workers} workers, from nominal "
            f"(run_batch, measured; {certified} certified, {failed} failed) | | "
            f"{seconds / 60:.1f} min | <= 10 min |"
        )


if __name__ == "__main__":
    main()

"""Frictional fastening sequence of a ~500-pair assembly: nominal time and variation cost.

The assembly is :class:`contactqp.applications.riveting_friction.FrictionAssembly`: two
200 x 100 mm aluminium parts (2 mm and 1.2 mm thick) meshed with ``--cells`` (27 x 18 by
default: 26 x 19 = 494 pairs), condensed to their interface. Eight clamp fasteners (500 N each)
are installed one by one along the middle row, ``mu = 0.3``; the initial gaps are 20 um plus a
10 um white noise (seed 0). Building the model (meshing and condensation) is timed once, apart.

Printed, as a markdown table:

* **nominal**: the whole sequence (the frictional problem assembled, then the 8 stages,
  each :func:`contactqp.solve` from the previous stage): the first call (the headline) and the
  best of 3;
* **variation**: ``--samples`` sequences on perturbed gaps (another 5 um of noise per sample),
  each stage warm started from the nominal stage of the same index, frictional
  (``mu = 0.3``) and frictionless (the same samples with ``mu = 0``, the frictionless route),
  per sample, their ratio, and the extrapolation to 10,000 samples on 2 cores (two independent
  workers, half the samples each).

Run ``python benchmarks/bench_assembly.py --help`` for the options. One BLAS thread is used
(as each of two workers would).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import time

import numpy as np

from contactqp import FrictionalProblem, solve
from contactqp.applications.assembly import Part
from contactqp.applications.riveting_friction import FrictionAssembly

MU = 0.3
CLAMP = 500.0  # N per fastener
FASTENERS = 8


def build(cells):
    """The reduced model and its fastener pairs (the middle row, evenly spaced)."""
    assembly = FrictionAssembly(
        lower=Part(length=0.2, width=0.1),
        upper=Part(length=0.2, width=0.1, thickness=0.0012),
        cells=cells,
    )
    model = assembly.build()
    nx, ny = model.grid
    columns = np.linspace(1, nx - 2, FASTENERS).round().astype(int)
    return model, [model.pair(int(i), ny // 2) for i in columns]


def sequence(problem, history, r0s=None):
    """Solve the stages of ``history`` from rest; each from the previous stage's state."""
    results, previous = [], None
    for k, loads in enumerate(history):
        options = {} if r0s is None else {"r0": r0s[k]}
        previous = solve(problem.with_loads(loads, previous=previous), **options)
        results.append(previous)
    return results


def nominal(model, gaps, pairs, mu):
    """One whole sequence: the problem assembled, then every stage; ``(seconds, results)``."""
    start = time.perf_counter()
    history = [model.clamp_loads(pairs[: n + 1], CLAMP) for n in range(len(pairs))]
    problem = FrictionalProblem(model.model, history[0], model.obstacles(gaps), mu)
    results = sequence(problem, history)
    return time.perf_counter() - start, problem, history, results


def variation(problem, history, gap_samples, r0s):
    """Seconds per sample of the sequences on ``gap_samples``, and how many succeeded."""
    start, solved = time.perf_counter(), 0
    for gaps in gap_samples:
        results = sequence(problem.with_gaps(gaps), history, r0s)
        solved += all(result.success for result in results)
    return (time.perf_counter() - start) / len(gap_samples), solved


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cells", type=int, nargs=2, default=(27, 18), help="cells along x, y")
    parser.add_argument("--samples", type=int, default=200, help="variation samples")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    start = time.perf_counter()
    model, pairs = build(tuple(args.cells))
    built = time.perf_counter() - start
    rng = np.random.default_rng(args.seed)
    gaps = 2e-5 + 1e-5 * rng.standard_normal(model.n_pairs)
    first, problem, history, results = nominal(model, gaps, pairs, MU)
    best = min(nominal(model, gaps, pairs, MU)[0] for _ in range(3))
    iterations = [result.iterations for result in results]
    ok = all(result.success for result in results)
    samples = gaps + 5e-6 * rng.standard_normal((args.samples, model.n_pairs))
    r0s = [result.forces for result in results]
    frictional, solved = variation(problem, history, samples, r0s)
    _, frictionless_problem, _, frictionless_results = nominal(model, gaps, pairs, 0.0)
    frictionless, solved_0 = variation(
        frictionless_problem, history, samples, [r.forces for r in frictionless_results]
    )
    total = 10_000 * frictional / 2  # two workers
    print(
        f"model: {model.n_pairs} pairs, {FASTENERS} clamp fasteners, mu = {MU}; "
        f"built in {built:.1f} s (once)"
    )
    print(f"nominal stages: Newton iterations {iterations}, all certified: {ok}\n")
    print("| run | first call | best of 3 / per sample | target |")
    print("| --- | ---: | ---: | --- |")
    print(f"| nominal sequence, mu = {MU} | {first:.3f} s | {best:.3f} s | < 0.5 s |")
    print(
        f"| variation, mu = {MU} ({solved}/{args.samples} certified) | | "
        f"{1e3 * frictional:.1f} ms | <= 120 ms per core |"
    )
    print(
        f"| variation, mu = 0 ({solved_0}/{args.samples} certified) | | "
        f"{1e3 * frictionless:.1f} ms | |"
    )
    print(f"| ratio frictional / frictionless | | {frictional / frictionless:.1f}x | <= 40x |")
    print(
        f"| 10,000 frictional samples on 2 cores (extrapolated) | | {total / 60:.1f} min | "
        f"<= 10 min |"
    )


if __name__ == "__main__":
    main()

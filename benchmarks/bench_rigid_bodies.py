"""Global problems of many rigid bodies: the compiled route group by group against one route.

The problems are those of the suite's tests (``rigid_bodies`` of
``tests/test_global_compiled.py``): pairs of rigid bodies with 6x6 SPD mass blocks, three
contacts between the two bodies of each pair, random ``H``, gaps and friction coefficients
(mu from 0.1 to 1). ``M`` is block diagonal and ``W = H^T M^-1 H`` couples only the contacts
of one pair, so the problem falls into as many groups as there are pairs; a few of them stall
a plain Newton run.

For each size the script times, in this process, one BLAS thread advised:

* grouped: ``contactqp.solve`` (the default route: the compiled call that solves each group
  apart and hands the groups whose Newton run stops short to coulomb's later rounds);
* one route: the same problem with the compiled kernel switched off (``kernels.global_small =
  None``): condensation, then coulomb on all of ``W``, whose iterations last as long as its
  hardest group needs.

Each is a first call on a new problem object (the modules imported and a small problem solved
before), and both answers are judged by their natural-map error on the global equations. The
last column is the largest difference of their reactions over the largest reaction.

Run ``python benchmarks/bench_rigid_bodies.py --help`` for the options.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg  # the methods import these on first use: start-up, not a solve
import scipy.sparse  # noqa: F401

import contactqp
from contactqp import kernels

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_global_compiled import fresh, rigid_bodies  # the tests' generator


def timed_solve(problem, tol: float, grouped: bool):
    """``(seconds, result)`` of a first ``contactqp.solve`` of a copy of ``problem``."""
    saved = kernels.global_small
    if not grouped:
        kernels.global_small = None
    try:
        copy = fresh(problem)
        start = time.perf_counter()
        result = contactqp.solve(copy, tol=tol)
        return time.perf_counter() - start, result
    finally:
        kernels.global_small = saved


def main(argv=None) -> int:
    """Run the benchmark and print its table; returns the exit code."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--pairs", default="200,2000,10000", help="comma-separated numbers of body pairs"
    )
    parser.add_argument("--seed", type=int, default=1, help="random seed of the problems (1)")
    parser.add_argument("--tol", type=float, default=1e-8, help="natural-map error (1e-8)")
    args = parser.parse_args(argv)
    if kernels.global_small is None:
        parser.error("the compiled kernels are not in use: nothing to compare")
    timed_solve(rigid_bodies(4, seed=0), args.tol, True)  # the code's first run, off the clock
    timed_solve(rigid_bodies(4, seed=0), args.tol, False)
    header = (
        f"{'pairs':>7} {'unknowns':>9} {'grouped s':>10} {'it':>4} {'error':>8} "
        f"{'one route s':>12} {'it':>4} {'error':>8} {'ratio':>7} {'max diff':>9}"
    )
    print(header)
    print("-" * len(header))
    for pairs in (int(p) for p in args.pairs.split(",") if p.strip()):
        problem = rigid_bodies(pairs, seed=args.seed)
        grouped_s, grouped = timed_solve(problem, args.tol, True)
        whole_s, whole = timed_solve(problem, args.tol, False)
        scale = float(np.abs(whole.forces).max()) or 1.0
        difference = float(np.abs(grouped.forces - whole.forces).max()) / scale
        print(
            f"{pairs:>7} {problem.H.shape[1]:>9} {grouped_s:>10.3g} {grouped.iterations:>4} "
            f"{grouped.certificate.natural_map:>8.1e} {whole_s:>12.3g} {whole.iterations:>4} "
            f"{whole.certificate.natural_map:>8.1e} {whole_s / grouped_s:>7.1f} "
            f"{difference:>9.1e}"
        )
        if not (grouped.success and whole.success):
            print(f"  not both converged: {grouped.message[:120]} / {whole.message[:120]}")
    print(
        "\ngrouped: the default route (compiled, group by group); one route: the kernel off "
        "(coulomb on all of W);\nratio: one route / grouped; max diff: max|r_grouped - r_one| "
        "/ max|r_one|"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Frictional contact: the own Coulomb solver against the Tresca and polygonal cross-check routes.

Three routes solve the same local problems ``u = W r + q`` with Coulomb cones to the same
natural-map error ``--tol`` (default 1e-8), checked independently by
:func:`contactqp.local.natural_map_error`:

* coulomb: :func:`contactqp.solvers.coulomb.solve_coulomb` (semismooth Newton, the own solver);
* tresca: :func:`contactqp.solvers.tresca.solve_tresca_fixed_point`, a fixed point on Tresca
  problems, each a second-order cone program solved by Clarabel;
* poly: :func:`contactqp.solvers.polygonal.solve_polygonal`, the same fixed point with the disc
  replaced by an inscribed polygon of ``--facets`` sides, each step a QP through qpsolvers
  (``--backend``). In 3-D it solves the polygonal problem, not the Coulomb one: its time is that
  of reaching its own fixed point, and its ``err`` column is its error against the exact cones
  (about ``mu (1 - cos(pi/F))`` to ``mu pi/F``); in 2-D the polygon is exact.

Problems:

* FCLIB / Siconos files of ``shared/data/fclib`` on which the Tresca fixed point converges
  (``--all-fclib`` adds the others: on rigid multibody problems with ``mu = 0.7`` and a singular
  ``W`` the fixed point stalls between 1e-4 and 1e-7);
* dense reduced problems of 100..1000 contacts: the cells of a square patch of an elastic
  half-space (:func:`contactqp.compliance.influence_matrix`, 3 unknowns per cell with the
  normal-tangential coupling, ``W`` scaled to a unit diagonal), random initial gaps
  ``U(0, 0.5)`` under an approach of 1 and a random tangential drive ``N(0, 0.1^2)`` per cell,
  ``mu = 0.3``: a third to a half of the cells close (the elastic interaction opens the
  others), most of them slipping, some sticking.

Each route is timed on its own call (a route taking less than 2 s is repeated 3 times and its
best time kept). Ratios are route time over coulomb time (x > 1: coulomb is faster); a ratio is
marked ``*`` when the route did not meet ``--tol`` (for poly in 3-D: did not reach its fixed
point within its 50 iterations). On a shared machine multi-threaded BLAS makes the dense
factorisations' times erratic; ``OPENBLAS_NUM_THREADS=1`` gives steadier figures (Clarabel's
factorisation is single-threaded anyway). Run ``python benchmarks/bench_friction_routes.py
--help`` for the options.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np

from contactqp.compliance import grid, influence_matrix
from contactqp.io.fclib import read_problem
from contactqp.local import LocalProblem, natural_map_error
from contactqp.solvers.coulomb import solve_coulomb
from contactqp.solvers.polygonal import solve_polygonal
from contactqp.solvers.tresca import solve_tresca_fixed_point

__all__ = ["random_problem", "main"]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
#: Files on which the Tresca fixed point reaches 1e-8 (see the module notes for the others).
FCLIB = ["FrictionContact3D_1c.dat", "FC3D_Example1.dat", "GFC3D_Example1.dat",
         "GFC3D_TwoRods1.dat", "Rover1041.dat", "Rover4516.dat",
         "LMGC_GlobalFrictionContactProblem00046.hdf5", "CubeH8.hdf5",
         "FrictionContactProblem00374.dat", "FrictionContactProblem00071.dat",
         "Box_Stacks-i0035-31-0.hdf5", "NESpheres_30_1.dat",
         "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5", "Confeti-ex13-Fc3D-SBM.dat",
         "spheres-in-a-box-98-i10000-256-10.hdf5"]
REPEAT_BELOW = 2.0  # seconds
REPEATS = 3


def random_problem(n_contacts: int, seed: int = 0, mu: float = 0.3) -> LocalProblem:
    """A dense 3-D reduced problem on half-space cells (see the module notes)."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(n_contacts)))
    x, y = grid(side, side, 1.0, 1.0)
    R = influence_matrix(x[:n_contacts], y[:n_contacts], 1.0, 1.0, 1.0, 0.3)
    # local frame per cell (N, T1, T2) = (-z, x, y); R is ordered (x, y, z)
    order = (3 * np.arange(n_contacts)[:, None] + [2, 0, 1]).ravel()
    sign = np.tile([-1.0, 1.0, 1.0], n_contacts)
    W = R[np.ix_(order, order)] * np.outer(sign, sign)
    W /= W[0, 0]
    q = np.empty((n_contacts, 3))
    q[:, 0] = rng.uniform(0.0, 0.5, n_contacts) - 1.0
    q[:, 1:] = 0.1 * rng.standard_normal((n_contacts, 2))
    return LocalProblem(W, q.ravel(), np.full(n_contacts, mu), 3, title=f"halfspace-{n_contacts}")


def timed(solve, problem):
    """``(best seconds, solution)``; short runs are repeated."""
    start = time.perf_counter()
    solution = solve(problem)
    best = time.perf_counter() - start
    if best < REPEAT_BELOW:
        for _ in range(REPEATS - 1):
            start = time.perf_counter()
            solve(problem)
            best = min(best, time.perf_counter() - start)
    return best, solution


def row(name, problem, routes, tol):
    """Solve with every route and format one table row."""
    results = {}
    for route, solve in routes.items():
        seconds, solution = timed(solve, problem)
        error = natural_map_error(problem, solution.r)  # not the solver's own figure
        met = error <= tol if route != "poly" or problem.dim == 2 else solution.converged
        results[route] = (seconds, error, solution.iterations, met)
    reference = results["coulomb"][0]
    cells = [f"{name[:34]:<34}{problem.dim:>2}{problem.n_contacts:>6}"]
    for route in routes:
        seconds, error, iterations, met = results[route]
        cells.append(f"{seconds:10.4f}{error:9.1e}{iterations:5d}")
    for route in list(routes)[1:]:
        seconds, _, _, met = results[route]
        cells.append(f"{seconds / reference:8.1f}{' ' if met else '*'}")
    return "".join(cells), results


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", default="100,200,400,700,1000",
                        help="contacts of the random half-space problems (comma separated)")
    parser.add_argument("--tol", type=float, default=1e-8)
    parser.add_argument("--facets", type=int, default=8)
    parser.add_argument("--backend", default="clarabel", help="qpsolvers backend of poly")
    parser.add_argument("--no-fclib", action="store_true")
    parser.add_argument("--all-fclib", action="store_true")
    args = parser.parse_args(argv)
    tol = args.tol
    routes = {
        "coulomb": lambda p: solve_coulomb(p, tol=tol),
        "tresca": lambda p: solve_tresca_fixed_point(p, tol=tol),
        "poly": lambda p: solve_polygonal(p, facets=args.facets, backend=args.backend, tol=tol),
    }
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"python {platform.python_version()}, tol {tol:g}, poly: {args.facets} facets, "
          f"{args.backend}")
    header = f"{'problem':<34}{'d':>2}{'nc':>6}"
    for route in routes:
        header += f"{route + ' s':>10}{'err':>9}{'it':>5}"
    header += f"{'tr/co':>9}{'po/co':>9}"
    print(header)
    ratios = []
    problems = []
    if not args.no_fclib:
        names = (sorted(p.name for p in DATA.iterdir() if p.suffix in (".dat", ".hdf5"))
                 if args.all_fclib else FCLIB)
        problems += [(name, lambda name=name: read_problem(DATA / name)) for name in names]
    problems += [("half-space, random gaps and drive", lambda n=int(n): random_problem(n))
                 for n in args.sizes.split(",") if n]
    for name, build in problems:
        problem = build()
        line, results = row(name, problem, routes, tol)
        print(line, flush=True)
        if results["coulomb"][3] and results["tresca"][3]:
            ratios.append((problem.n_contacts, results["tresca"][0] / results["coulomb"][0]))
    if ratios:
        large = [ratio for nc, ratio in ratios if nc >= 100]
        print(f"# tresca/coulomb over {len(ratios)} problems both solved: geometric mean "
              f"{np.exp(np.mean(np.log([r for _, r in ratios]))):.1f}x"
              + (f", on >= 100 contacts {np.exp(np.mean(np.log(large))):.1f}x" if large else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

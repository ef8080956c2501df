"""Frictional contact: the own Coulomb solver against the Tresca and polygonal cross-check routes.

Three routes solve the same local problems ``u = W r + q`` with Coulomb cones to the same
natural-map error ``--tol`` (default 1e-8), checked independently by
:func:`contactqp.core.local_problem.natural_map_error`:

* coulomb: :func:`contactqp.methods.coulomb.solve_coulomb` (semismooth Newton, the own solver);
* tresca: :func:`contactqp.methods.tresca.solve_tresca_fixed_point`, a fixed point on Tresca
  problems, each a second-order cone program solved by Clarabel;
* poly: :func:`contactqp.methods.polygonal.solve_polygonal`, the same fixed point with the disc
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

Each route is timed on its own call; a route taking less than 2 s is repeated (at least 3
runs, up to 7 while they take less than 1 s in all) and its best time kept, so that routes of a
millisecond are not timed on one cold call. Ratios are route time over coulomb time (x > 1: coulomb
is faster); a ratio is marked ``*`` when the route did not meet ``--tol`` (for poly in 3-D: did not
reach its fixed point within its 50 iterations). On a shared machine multi-threaded BLAS makes the
dense factorisations' times erratic; ``OPENBLAS_NUM_THREADS=1`` gives steadier figures (Clarabel's
factorisation is single-threaded anyway). Run ``python benchmarks/bench_friction_routes.py --help``
for the options.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np

from contactqp.compliance import grid, influence_matrix
from contactqp.core.local_problem import LocalProblem, natural_map_error
from contactqp.io.fclib import read_problem
from contactqp.methods.coulomb import solve_coulomb
from contactqp.methods.polygonal import solve_polygonal
from contactqp.methods.tresca import solve_tresca_fixed_point

__all__ = ["random_problem", "main"]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
#: Files on which the Tresca fixed point reaches 1e-8 (see the module notes for the others).
FCLIB = [
    "FrictionContact3D_1c.dat",
    "FC3D_Example1.dat",
    "GFC3D_Example1.dat",
    "GFC3D_TwoRods1.dat",
    "Rover1041.dat",
    "Rover4516.dat",
    "LMGC_GlobalFrictionContactProblem00046.hdf5",
    "CubeH8.hdf5",
    "FrictionContactProblem00374.dat",
    "FrictionContactProblem00071.dat",
    "Box_Stacks-i0035-31-0.hdf5",
    "NESpheres_30_1.dat",
    "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5",
    "Confeti-ex13-Fc3D-SBM.dat",
    "spheres-in-a-box-98-i10000-256-10.hdf5",
]
REPEAT_BELOW = 2.0  # s: runs shorter than this are repeated, the best time kept
MIN_REPEATS, MAX_REPEATS = 3, 7  # runs of a short route: at least, at most
REPEAT_BUDGET = 1.0  # s: more than MIN_REPEATS runs only while they take less than this in all


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
    """``(best seconds, solution)``; short runs are repeated (see the module notes)."""
    times = []
    while True:
        start = time.perf_counter()
        solution = solve(problem)
        times.append(time.perf_counter() - start)
        if (
            times[0] >= REPEAT_BELOW
            or len(times) == MAX_REPEATS
            or (len(times) >= MIN_REPEATS and sum(times) >= REPEAT_BUDGET)
        ):
            return min(times), solution


def row(name, problem, routes, tol):
    """Solve with every route and format one table row."""
    results = {}
    for route, solve in routes.items():
        seconds, solution = timed(solve, problem)
        error = natural_map_error(problem, solution.forces)  # not the solver's own figure
        met = error <= tol if route != "poly" or problem.dim == 2 else solution.success
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
    parser.add_argument(
        "--sizes",
        default="100,200,400,700,1000",
        help="contacts of the random half-space problems (comma separated)",
    )
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
    print(
        f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"python {platform.python_version()}, tol {tol:g}, poly: {args.facets} facets, "
        f"{args.backend}"
    )
    header = f"{'problem':<34}{'d':>2}{'nc':>6}"
    for route in routes:
        header += f"{route + ' s':>10}{'err':>9}{'it':>5}"
    header += f"{'tr/co':>9}{'po/co':>9}"
    print(header)
    times = {"FCLIB files": [], "half-space problems": []}  # (tresca s, coulomb s) per problem
    problems = []
    if not args.no_fclib:
        names = (
            sorted(p.name for p in DATA.iterdir() if p.suffix in (".dat", ".hdf5"))
            if args.all_fclib
            else FCLIB
        )
        problems += [
            ("FCLIB files", name, lambda name=name: read_problem(DATA / name)) for name in names
        ]
    problems += [
        (
            "half-space problems",
            "half-space, random gaps and drive",
            lambda n=int(n): random_problem(n),
        )
        for n in args.sizes.split(",")
        if n
    ]
    for group, name, build in problems:
        problem = build()
        line, results = row(name, problem, routes, tol)
        print(line, flush=True)
        if results["coulomb"][3] and results["tresca"][3]:
            times[group].append((results["tresca"][0], results["coulomb"][0]))
    for group, pairs in times.items():
        if pairs:
            tresca, coulomb = np.array(pairs).T
            values = tresca / coulomb
            print(
                f"# tresca/coulomb on the {len(values)} {group} both routes solved: geometric "
                f"mean {np.exp(np.mean(np.log(values))):.1f}x, range {min(values):.1f}x "
                f"to {max(values):.1f}x, total time {tresca.sum() / coulomb.sum():.1f}x; "
                f"target >= 10x"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

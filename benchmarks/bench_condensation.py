"""Static condensation against the unit-load procedure on a 3D finite-element block.

The body is a steel block ``1 x 1 x 0.25 m`` meshed by :func:`contactqp.compliance.fem.block`
(``c x c x c/4`` trilinear hexahedra, or quadratic tetrahedra with ``--cell tet``), clamped on its
bottom face. The computational nodes are ``n`` nodes of the top face, a square grid around its
centre, with three freedoms each: the flexibility ``R`` is ``3n x 3n``.

For each case the script times

* ``condense``: :meth:`ElasticModel.reduced_model` (one sparse factorisation, one solve with
  ``3n`` right-hand sides, and the :class:`~contactqp.ReducedModel` check of ``R``), best of 3;
* ``unit loads``: the unit-load procedure as a user drives a finite-element code, one full
  analysis (:meth:`ElasticModel.solve`: factorise, solve) per unit load, the assembled stiffness
  kept between analyses (a code re-running would also re-assemble: the comparison favours it);
* ``reuse``: the unit-load procedure with one factorisation reused for every load, one solve
  per load (what a user with access to the factor could do).

Every unit load costs one factorisation and one solve whatever the freedom, so by default the
unit-load time is measured on ``--sample`` loads and multiplied by ``3n`` (marked ``*``);
``--full`` applies all ``3n``. The columns measured are checked against ``R`` to 1e-10 of
``max |R|``. Assembly of the stiffness and the application of the fixations are done once,
before any timing.

Run ``python benchmarks/bench_condensation.py --help`` for the options.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np
import scipy

from contactqp.compliance.condensation import factorize
from contactqp.compliance.fem import ElasticModel, block

__all__ = ["build_model", "main"]

YOUNG, POISSON = 210e9, 0.3  # steel (Pa, -)
SIDE, DEPTH = 1.0, 0.25  # block (m)


def build_model(cells: int, cell: str):
    """The clamped block with ``cells`` cells along each side and its assembled stiffness."""
    order = 2 if cell == "tet" else 1
    mesh = block(SIDE, SIDE, DEPTH, cells, cells, max(1, cells // 4), cell=cell)
    model = ElasticModel(mesh, YOUNG, POISSON, order=order).fix("bottom")
    model.free_stiffness()  # assembly and fixations, shared by all methods, before any timing
    return model


def top_nodes(model: ElasticModel, n: int) -> np.ndarray:
    """``n`` (a square) top-face nodes nearest to a grid around the face's centre."""
    side = round(np.sqrt(n))
    if side * side != n:
        raise SystemExit(f"node counts must be perfect squares, got {n}")
    pitch = np.diff(np.unique(model.mesh.p[0]))[0]
    offsets = (np.arange(side) - side // 2) * pitch  # on mesh nodes when cells is even
    x, y = np.meshgrid(SIDE / 2 + offsets, SIDE / 2 + offsets)
    points = np.column_stack([x.ravel(), y.ravel(), np.full(n, DEPTH)])
    return model.select_nodes(points, where="top").nodes


def _unit_load_columns(model, nodes, loads, reuse):
    """Columns of R for the unit loads ``loads`` (freedom indices), by full analyses or reuse."""
    dim = model.dim
    columns = []
    if reuse:
        free, K = model.free_stiffness()
        position = np.full(model.basis.N, -1)
        position[free] = np.arange(free.size)
        freedoms = position[model.basis.nodal_dofs[:, nodes].T.ravel()]
        lu = factorize(K)
        for j in loads:
            vector = np.zeros(free.size)
            vector[freedoms[j]] = 1.0
            columns.append(lu.solve(vector)[freedoms])
    else:
        for j in loads:
            force = np.zeros((model.n_nodes, dim))
            force[nodes[j // dim], j % dim] = 1.0
            columns.append(model.solve(force)[nodes].ravel())
    return np.column_stack(columns)


def _timed(function, *args, repeat: int = 1):
    """Value of ``function(*args)`` and its best time (s) over ``repeat`` runs."""
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        value = function(*args)
        best = min(best, time.perf_counter() - start)
    return value, best


def run_case(cells: int, n: int, cell: str, sample: int, full: bool, rng) -> dict:
    model = build_model(cells, cell)
    nodes = top_nodes(model, n)
    k = 3 * n
    reduced, t_condense = _timed(model.reduced_model, nodes, repeat=3)
    R = reduced.flexibility
    loads = np.arange(k) if full else np.sort(rng.choice(k, size=min(sample, k), replace=False))
    unit, t_unit = _timed(_unit_load_columns, model, nodes, loads, False)
    reuse, t_reuse = _timed(_unit_load_columns, model, nodes, loads, True)
    scale = k / loads.size
    error = (
        max(np.abs(unit - R[:, loads]).max(), np.abs(reuse - R[:, loads]).max()) / np.abs(R).max()
    )
    return {
        "N": model.basis.N - model.fixed.size,
        "k": k,
        "condense": t_condense,
        "unit": t_unit * scale,
        "reuse": t_reuse * scale,
        "sampled": not full,
        "loads": loads.size,
        "error": error,
    }


def _seconds(value: float, sampled: bool) -> str:
    return f"{value:.2f}{'*' if sampled else ''}"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--cases",
        default="12x100,16x100,24x225,32x400",
        help="comma-separated CELLSxNODES: cells along a side x top nodes "
        "(perfect squares); default %(default)s",
    )
    parser.add_argument("--cell", choices=("hex", "tet"), default="hex")
    parser.add_argument(
        "--sample",
        type=int,
        default=24,
        help="unit loads actually applied per case (default %(default)s)",
    )
    parser.add_argument("--full", action="store_true", help="apply all 3n unit loads")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(0)
    print(
        f"# static condensation vs unit loads: steel block {SIDE} x {SIDE} x {DEPTH} m, "
        f"{args.cell} elements, clamped bottom, n top nodes"
    )
    print(
        f"# numpy {np.__version__}, scipy {scipy.__version__}, python "
        f"{platform.python_version()}, {os.cpu_count()} cores, "
        f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}"
    )
    print()
    print(
        "| FE freedoms | 3n | condense (s) | unit loads (s) | reuse (s) | unit/condense "
        "| reuse/condense | max col. error |"
    )
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    ratios, sampled = [], False
    for case in args.cases.split(","):
        cells, n = (int(v) for v in case.lower().split("x"))
        row = run_case(cells, n, args.cell, args.sample, args.full, rng)
        sampled |= row["sampled"]
        ratios.append(row["unit"] / row["condense"])
        print(
            f"| {row['N']} | {row['k']} | {row['condense']:.2f} | "
            f"{_seconds(row['unit'], row['sampled'])} | {_seconds(row['reuse'], row['sampled'])} "
            f"| {ratios[-1]:.0f}x | {row['reuse'] / row['condense']:.1f}x | "
            f"{row['error']:.1e} |",
            flush=True,
        )
    if sampled:
        print(
            f"\n`*` measured on {args.sample} random unit loads, times 3n / {args.sample} "
            "(each load costs the same: one factorisation and one solve)."
        )
    verdict = "met" if min(ratios) >= 20 else "NOT met"
    print(
        f"\nTarget: condensation at least 20x faster than the unit-load procedure: {verdict} "
        f"(smallest ratio {min(ratios):.0f}x)."
    )


if __name__ == "__main__":
    main()

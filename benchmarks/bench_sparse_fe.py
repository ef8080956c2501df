"""Frictionless contact of a 3-D finite-element block through its sparse compliance operator.

The body is a steel block ``1 x 1 x 6/c m`` of ``c x c x 6`` hexahedra, each split into six
linear tetrahedra (scikit-fem ``ElementTetP1``, assembled on one quadrature point, exact for
linear elements), clamped on its bottom face: ``3 (c+1)^2 6`` free freedoms and ``(c+1)^2``
top nodes, all of them contact nodes (their vertical freedoms). A rigid paraboloid pressed at a
fixed approach of 5 um, which would touch the undeformed face out to 0.3 m from its centre
(radius 9 km: a fifth to a quarter of the nodes touch).

For each size the script times, in one process:

* ``assemble``: the stiffness by scikit-fem and the fixations;
* ``factor``: :class:`~contactqp.compliance.sparse_compliance.SparseComplianceOperator` (one
  sparse factorisation, ``--factorizer``: MKL Pardiso's Cholesky by default when MKL is
  installed, or SuperLU; both with the singularity checks of ``factorize``), and its factor's
  size;
* ``product``: one product ``W x`` (one solve with the factor, a pair of triangular solves);
* ``solve``: the :class:`~contactqp.core.surface.SurfaceProblem` through the operator, by each
  ``--methods`` entry (default ``constrained-cg,dual-active-set``), and the number of products;
* ``dense``: up to ``--dense-max`` contact nodes, the dense route: the flexibility ``R`` by
  static condensation (``ElasticModel.reduced_model``) and the frictionless active-set solve
  of that reduced model (:func:`contactqp.solve_gaps`); the forces are compared to the
  operator's, relative to the peak force.

Times are wall-clock and CPU (``time.process_time``: the measure to read on a shared machine).
Peak memory is the process's resident high-water mark (``ru_maxrss``) after each stage; run one
size per process (``--sizes`` with one entry) to read a stage's own peak. The fitted exponent
``k`` of ``time ~ N^k`` (``N`` free freedoms) is printed over the sizes run.

Run ``python benchmarks/bench_sparse_fe.py --help`` for the options.
"""

from __future__ import annotations

import argparse
import os
import resource
import time

import numpy as np
import skfem
from skfem.models.elasticity import lame_parameters, linear_elasticity

import contactqp as cq
from contactqp.compliance.condensation import condense
from contactqp.compliance.fem import block
from contactqp.compliance.sparse_compliance import SparseComplianceOperator

__all__ = ["build", "main"]

E, NU, LAYERS, APPROACH, REACH = 210e9, 0.3, 6, 5e-6, 0.3


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def build(cells: int):
    """``(K, top freedoms, separation, top node indices, seconds)`` of a ``cells`` block."""
    start = time.perf_counter()
    mesh = block(1.0, 1.0, LAYERS / cells, cells, cells, LAYERS, cell="tet")
    basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTetP1()), intorder=1)
    K = skfem.asm(linear_elasticity(*lame_parameters(E, NU)), basis).tocsr()
    bottom = basis.get_dofs(lambda x: np.abs(x[2]) < 1e-9).all()
    fixed = np.zeros(basis.N, dtype=bool)
    fixed[bottom] = True
    free = np.flatnonzero(~fixed)
    K = K[free][:, free].tocsc()
    top = np.flatnonzero(np.abs(mesh.p[2] - LAYERS / cells) < 1e-9)
    position = np.full(basis.N, -1)
    position[free] = np.arange(free.size)
    freedoms = position[basis.nodal_dofs[2, top]]
    x, y = mesh.p[0, top] - 0.5, mesh.p[1, top] - 0.5
    separation = APPROACH * (x**2 + y**2) / REACH**2  # touching rigidly out to REACH
    return K, freedoms, separation, time.perf_counter() - start


class CountingFactor:
    """The operator's factor, counting its solves (one per right-hand side)."""

    def __init__(self, factor):
        self.factor, self.solves = factor, 0

    def solve(self, rhs):
        self.solves += 1 if rhs.ndim == 1 else rhs.shape[1]
        return self.factor.solve(rhs)


def run(
    cells: int, methods: list[str], dense_max: int, tol: float, factorizer: str | None = None
) -> dict:
    K, freedoms, s, assemble = build(cells)
    row: dict = {"cells": cells, "N": K.shape[0], "m": freedoms.size, "assemble": assemble}
    print(
        f"c={cells}: N={K.shape[0]} freedoms, m={freedoms.size} contact nodes, "
        f"nnz(K)={K.nnz}; assembled in {assemble:.1f} s, peak {peak_mb():.0f} MB",
        flush=True,
    )
    start, cpu = time.perf_counter(), time.process_time()
    W = SparseComplianceOperator(K, freedoms, factorizer=factorizer)
    row["factor"] = time.perf_counter() - start
    row["factor cpu"] = time.process_time() - cpu
    print(
        f"  factor ({W.factorizer}) {row['factor']:.2f} s (CPU {row['factor cpu']:.2f} s), "
        f"nnz({'L' if W.factorizer == 'pardiso' else 'L+U'}) = {W.factor_nnz / 1e6:.1f} M, "
        f"peak {peak_mb():.0f} MB",
        flush=True,
    )
    x = np.random.default_rng(0).standard_normal(freedoms.size)
    start = time.perf_counter()
    for _ in range(3):
        W @ x
    row["product"] = (time.perf_counter() - start) / 3
    print(f"  one product (pair of triangular solves) {row['product'] * 1e3:.0f} ms", flush=True)
    results = {}
    factor = W._lu
    for method in methods:
        counter = W._lu = CountingFactor(factor)
        problem = cq.SurfaceProblem(W, s, approach=APPROACH)
        start, cpu = time.perf_counter(), time.process_time()
        result = cq.solve(problem, method, tol=tol)
        seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
        results[method] = result
        row[method], row[f"{method} cpu"] = seconds, cpu
        print(
            f"  {method}: {seconds:.2f} s (CPU {cpu:.2f} s), {counter.solves} products, "
            f"{result.iterations} iterations, success={result.success}, "
            f"contact {np.mean(result.contact):.2f}, "
            f"load {result.load:.4g} N, peak {peak_mb():.0f} MB",
            flush=True,
        )
    if freedoms.size <= dense_max:
        start, cpu = time.perf_counter(), time.process_time()
        R = condense(K, freedoms)
        condensed = time.perf_counter() - start
        reference = cq.solve_gaps(R, np.zeros(s.size), s - APPROACH)
        row["dense"] = time.perf_counter() - start
        row["dense cpu"] = time.process_time() - cpu
        scale = reference.forces.max()
        differences = ", ".join(
            f"{name} {np.abs(result.forces - reference.forces).max() / scale:.1e}"
            for name, result in results.items()
        )
        print(
            f"  dense route: {row['dense']:.2f} s (CPU {row['dense cpu']:.2f} s; "
            f"condensation {condensed:.2f} s), "
            f"success={reference.success}; max |r - r_dense| / max r_dense: {differences}; "
            f"peak {peak_mb():.0f} MB",
            flush=True,
        )
    return row


def exponent(rows: list[dict], column: str) -> str:
    points = [(r["N"], r[column]) for r in rows if column in r and r[column] > 0]
    if len(points) < 3:
        return "n/a (fewer than 3 sizes)"
    N, t = np.log([p[0] for p in points]), np.log([p[1] for p in points])
    return f"{np.polyfit(N, t, 1)[0]:.2f}"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", default="20,30,45", help="cells per side, comma-separated")
    parser.add_argument("--methods", default="constrained-cg,dual-active-set")
    parser.add_argument("--dense-max", type=int, default=2500, help="largest m for the dense route")
    parser.add_argument("--tol", type=float, default=1e-10)
    parser.add_argument(
        "--factorizer",
        choices=["pardiso", "superlu"],
        default=None,
        help="the operator's factorisation (default: pardiso when MKL is installed)",
    )
    args = parser.parse_args(argv)
    print(
        f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, "
        f"MKL_NUM_THREADS={os.environ.get('MKL_NUM_THREADS', 'unset')}, "
        f"block 1 x 1 x {LAYERS}/c m, c x c x {LAYERS} hexahedra as tetrahedra",
        flush=True,
    )
    methods = [m for m in args.methods.split(",") if m]
    rows = [
        run(int(c), methods, args.dense_max, args.tol, args.factorizer)
        for c in args.sizes.split(",")
    ]
    print(f"\n{'N':>8} {'m':>6} {'assemble':>9} {'factor':>8} {'product':>8}", end="")
    for method in methods + ["dense"]:
        print(f" {method:>16}", end="")
    print()
    for row in rows:
        print(
            f"{row['N']:>8} {row['m']:>6} {row['assemble']:>9.2f} {row['factor']:>8.2f} "
            f"{row['product']:>8.3f}",
            end="",
        )
        for method in methods + ["dense"]:
            print(f" {row[method]:>16.2f}" if method in row else f" {'-':>16}", end="")
        print()
    for column in ["factor", *methods, "dense"]:
        print(
            f"k (time ~ N^k) of {column}: wall {exponent(rows, column)}, "
            f"CPU {exponent(rows, column + ' cpu')}"
        )
    print(f"k of one product (wall): {exponent(rows, 'product')}")


if __name__ == "__main__":
    main()

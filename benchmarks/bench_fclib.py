"""Coulomb friction on the shared FCLIB problems: time per file beside the published figures.

Every problem file in ``shared/data/fclib`` (or the files given) is read once, outside the timing,
then solved by :func:`contactqp.methods.coulomb.solve_coulomb` from a cold start (``r = 0``) to the
natural-map error ``--tol`` (default 1e-8, the README's measure). A global problem is condensed as
given (outside the timing) and its error is that of the global equations as written
(:meth:`~contactqp.core.local_problem.GlobalProblem.certify`: ``M v = H r + f``, ``u = H^T v + w``).
The time is the best of repeated solves (runs shorter than 0.5 s are repeated, up to 7 times, 2 s in
all), each including the positive-semidefiniteness check of ``W``.

Beside it stands the published mean time of the fastest solver of the file's test family
(Acary, Bremond and Huber 2018, as quoted in ``shared/data/fclib/README.md``) and the ratio
``own / published`` (< 1: faster). The published figure is a mean over the whole family, measured
on other hardware with a compiled code, sometimes at another accuracy (shown): the ratio is an
order of magnitude, not a race. Files of families without a quoted figure show ``-``.

``--perturbed N`` also solves each file from N starts perturbed by ``1e-10 max|r|`` and says
which files do not always converge: the semismooth Newton path on the rigid, rounded (6-digit)
granular problem depends on rounding.

Run ``python benchmarks/bench_fclib.py --help`` for the options.
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

from contactqp.core.local_problem import GlobalProblem, natural_map_error
from contactqp.io.fclib import read_any
from contactqp.methods.coulomb import solve_coulomb

__all__ = ["PUBLISHED", "family", "time_file", "main"]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
SHORT_RUN = 0.5  # s: runs shorter than this are repeated and the best time kept
MAX_REPEATS = 7
REPEAT_BUDGET = 2.0  # s spent on repetitions of one file at most

#: family -> (accuracy asked for, mean time in s of the fastest solver), from the data README
PUBLISHED = {
    "Capsules": (1e-8, 1.46e-2),
    "Chain": (1e-8, 6.2e-4),
    "100_PR_PerioBox": (1e-4, 0.064),
    "BoxesStack": (1e-8, 3.4e-2),
    "Cubes_H8": (1e-8, 1.73),
    "LowWall_FEM": (1e-8, 13.1),
}

#: file-name prefix -> family of PUBLISHED
_PREFIXES = {
    "Capsules": "Capsules",
    "Chain": "Chain",
    "LMGC_100_PR_PerioBox": "100_PR_PerioBox",
    "Box_Stacks": "BoxesStack",
    "CubeH8": "Cubes_H8",
    "LowWall_FEM": "LowWall_FEM",
}


def family(name: str) -> str | None:
    """The published test family of a file name, or None."""
    for prefix, fam in _PREFIXES.items():
        if name.startswith(prefix):
            return fam
    return None


def time_file(path: Path, tol: float, perturbed: int = 0) -> dict:
    """Solve one file (best time of the repetitions); the error is recomputed independently.

    With ``perturbed > 0`` the file is also solved from that many starts
    ``r0 = 1e-10 max|r| |z|`` (``z`` standard normal, seeds 0, 1, ...) near the cold start; the
    count of those that converge measures how much the result depends on rounding.
    """
    given = read_any(path)
    problem = given.condense() if isinstance(given, GlobalProblem) else given
    best = math.inf
    spent = 0.0
    for _ in range(MAX_REPEATS):
        start = time.perf_counter()
        solution = solve_coulomb(problem, tol=tol)
        elapsed = time.perf_counter() - start
        best = min(best, elapsed)
        spent += elapsed
        if elapsed >= SHORT_RUN or spent >= REPEAT_BUDGET:
            break
    size = 1e-10 * np.abs(solution.forces).max(initial=0.0)
    robust = sum(
        solve_coulomb(
            problem,
            r0=size * np.abs(np.random.default_rng(seed).standard_normal(problem.q.size)),
            tol=tol,
        ).success
        for seed in range(perturbed)
    )
    error = (
        given.certify(solution.forces).error
        if isinstance(given, GlobalProblem)
        else natural_map_error(problem, solution.forces)
    )
    return {
        "file": path.name,
        "dim": problem.dim,
        "contacts": problem.n_contacts,
        "error": error,
        "converged": solution.success and error <= tol,
        "iterations": solution.iterations,
        "seconds": best,
        "gauss_seidel": "gauss-seidel" in solution.message,
        "perturbed": (robust, perturbed),
    }


def _table(rows, tol):
    header = (
        f"{'file':44s} {'d':>1s} {'nc':>5s} {'error':>8s} {'it':>4s} {'own s':>9s} "
        f"{'family':>15s} {'acc.':>6s} {'publ. s':>8s} {'ratio':>7s}"
    )
    lines = [header, "-" * len(header)]
    for r in rows:
        fam = family(r["file"])
        published = PUBLISHED.get(fam)
        acc, ref, ratio = (
            (f"{published[0]:.0e}", f"{published[1]:.2e}", f"{r['seconds'] / published[1]:.3g}")
            if published
            else ("-", "-", "-")
        )
        mark = "" if r["converged"] else " (not converged)"
        lines.append(
            f"{r['file']:44s} {r['dim']:1d} {r['contacts']:5d} {r['error']:8.1e} "
            f"{r['iterations']:4d} {r['seconds']:9.2e} {fam or '-':>15s} "
            f"{acc:>6s} {ref:>8s} {ratio:>7s}{mark}"
        )
    solved = sum(r["converged"] for r in rows)
    total = sum(r["seconds"] for r in rows)
    lines.append("-" * len(header))
    lines.append(
        f"{solved}/{len(rows)} solved to natural-map error <= {tol:g} in {total:.3f} s "
        f"in all; ratio = own / published (< 1: faster)"
    )
    helped = [r["file"] for r in rows if r["gauss_seidel"]]
    if helped:
        lines.append("needed Gauss-Seidel sweeps: " + ", ".join(helped))
    fragile = [
        f"{r['file']} {r['perturbed'][0]}/{r['perturbed'][1]}"
        for r in rows
        if r["perturbed"][0] < r["perturbed"][1]
    ]
    if rows and rows[0]["perturbed"][1]:
        lines.append(
            "converged from perturbed starts: "
            + ("all" if not fragile else "all but " + ", ".join(fragile))
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "files", nargs="*", type=Path, help=f"problem files (default: every .dat/.hdf5 in {DATA})"
    )
    parser.add_argument("--tol", type=float, default=1e-8, help="natural-map error (1e-8)")
    parser.add_argument(
        "--perturbed",
        type=int,
        default=0,
        metavar="N",
        help="also solve each file from N starts perturbed by 1e-10 (0)",
    )
    args = parser.parse_args(argv)
    files = args.files or sorted(p for p in DATA.iterdir() if p.suffix in (".dat", ".hdf5"))
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}, "
        f"{platform.system()}"
    )
    rows = [time_file(path, args.tol, args.perturbed) for path in files]
    print(_table(rows, args.tol))
    return 0 if all(r["converged"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())

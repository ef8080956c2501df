"""Coulomb friction on the shared FCLIB problems: contactqp beside Siconos, file by file.

Every problem file in ``shared/data/fclib`` (or the files given) is read once, outside the timing,
and solved by :func:`contactqp.solve` (the default route: a global problem on its ``M``, ``H``,
``f``, ``w``, certified on the global equations as written) from a cold start (``r = 0``) to the
natural-map error ``--tol`` (default 1e-8, the README's measure). Each timed solve gets a fresh
problem object made from the arrays read (nothing one solve computed, such as a check of ``W``,
carries to the next):

* ``first``: the first solve of the file in this process (the package's modules imported
  before it, as in any program that solves: the import is start-up, not a solve);
* ``best`` and ``median``: of ``--repeats`` rounds of more solves. The files are solved in
  turn, round after round (file 1, file 2, ..., file 1, ...), so that a change of load on the
  machine falls on every file alike; in each round a file is solved 3 times in a row, as the
  Siconos figures are the best of 3 solves in a row (data and code in cache, as when a program
  solves many problems of one kind);
* ``cpu``: the best CPU time (``time.process_time``) of those solves: on a machine whose cores
  other jobs share, wall time also counts the time the process waits for a core, CPU time
  only the time it runs.

Beside them stand the Siconos numerics 4.5 times of ``shared/data/fclib/PEER-TIMES.md`` (measured
on this machine, best of 3, solve only, from ``r = 0``): its Alart-Curnier Newton (2-D: Lemke),
its Gauss-Seidel (NSGS), and for global files its own global Newton on ``M, H``. ``ratio`` is
contactqp's best time over the faster Siconos local solver that converged (``-`` when none
did), ``c.ratio`` the same of the best CPU time; ``g.ratio`` and ``c.g.ratio`` the best wall
and CPU times over Siconos' global Newton. The summary counts the files where contactqp
converged and was at least as fast as that solver, in wall and in CPU time (a file where no
Siconos solver converged counts when contactqp converged). The peer figures vary by up to 2x
with the machine's load:
compare ratios, and time the peer's files again when a ratio is near 1.

``--perturbed N`` also solves each file from N starts perturbed by ``1e-10 max|r|`` and says
which files do not always converge.

Run ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_fclib.py --help`` for the options.
"""

from __future__ import annotations

import argparse
import platform
import re
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg  # the methods import these on first use: start-up, not a solve
import scipy.sparse  # noqa: F401

import contactqp as cq
import contactqp.methods  # what cq.solve imports on its first use (start-up, not a solve)
from contactqp.core.local_problem import GlobalProblem, LocalProblem, natural_map_error
from contactqp.io.fclib import read_any

__all__ = ["PeerTimes", "fresh", "peer_times", "time_files", "main"]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
PEERS = DATA / "PEER-TIMES.md"

_TIME = re.compile(r"([0-9.]+(?:e[+-]?[0-9]+)?) s, ([0-9]+) it, ([yn])")


class PeerTimes(dict):
    """``{file name: {"newton": (s, converged) | None, "nsgs": ..., "global": s | None}}``."""

    def fastest(self, name: str) -> float | None:
        """The time of the faster Siconos local solver that converged on ``name``, or None."""
        row = self.get(name, {})
        times = [t for key in ("newton", "nsgs") if row.get(key) for t, ok in [row[key]] if ok]
        return min(times) if times else None


def peer_times(path: Path = PEERS) -> PeerTimes:
    """The Siconos times of ``PEER-TIMES.md``: its table, and its paragraph of global Newton
    times (named by file-name prefixes)."""
    peers = PeerTimes()
    if not path.exists():
        return peers
    text = path.read_text(encoding="utf-8")
    for line in text.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) != 5 or not cells[0].endswith((".dat", ".hdf5")):
            continue
        row = {}
        for key, cell in zip(("newton", "nsgs"), cells[3:], strict=True):
            found = _TIME.search(cell)
            row[key] = (float(found[1]), found[3] == "y") if found else None
        row["global"] = None
        peers[cells[0]] = row
    paragraph = text[text.find("own global Newton") :]
    for prefix, seconds in re.findall(
        r"([A-Za-z][\w-]+)\s+([0-9.]+(?:e[+-]?[0-9]+)?) s", paragraph
    ):
        for name, row in peers.items():
            if name.startswith(prefix):
                row["global"] = float(seconds)
    return peers


IN_A_ROW = 3  # solves of a file in a row in each round (the Siconos figures: best of 3)


def fresh(given):
    """A new problem object of the arrays read (no cached checks or factorisations)."""
    if isinstance(given, GlobalProblem):
        return GlobalProblem(
            given.M, given.H, given.f, given.w, given.mu, given.dim, given.title, given.digits
        )
    return LocalProblem(
        given.W, given.q, given.mu, given.dim, given.title, given.cohesion, given.digits
    )


def _solve(given, tol, r0=None):
    """``(result, wall seconds, CPU seconds)`` of one solve of a fresh copy of ``given``."""
    problem = fresh(given)
    cpu, start = time.process_time(), time.perf_counter()
    result = cq.solve(problem, tol=tol) if r0 is None else cq.solve(problem, tol=tol, r0=r0)
    return result, time.perf_counter() - start, time.process_time() - cpu


def time_files(paths, tol: float, repeats: int, perturbed: int = 0) -> list[dict]:
    """Solve each file once (``first``), then ``repeats`` rounds over all the files, each file
    :data:`IN_A_ROW` times in a row in each round."""
    problems = {path.name: read_any(path) for path in paths}
    rows = {}
    for name, given in problems.items():
        result, seconds, cpu = _solve(given, tol)
        error = (
            given.certify(result.forces).error
            if isinstance(given, GlobalProblem)
            else natural_map_error(given, result.forces)
        )  # recomputed by the problem as read, independently of the route
        rows[name] = {
            "file": name,
            "dim": given.dim,
            "contacts": given.n_contacts,
            "global": isinstance(given, GlobalProblem),
            "method": result.method,
            "iterations": result.iterations,
            "error": error,
            "converged": bool(result.success and error <= tol),
            "first": seconds,
            "first_cpu": cpu,
            "times": [],
            "cpu": [],
            "perturbed": (0, perturbed),
        }
    for _ in range(repeats):
        for name, given in problems.items():
            for _ in range(IN_A_ROW):
                _, seconds, cpu = _solve(given, tol)
                rows[name]["times"].append(seconds)
                rows[name]["cpu"].append(cpu)
    for name, given in problems.items():
        row = rows[name]
        size = 1e-10 * np.abs(_solve(given, tol)[0].forces).max(initial=0.0)
        robust = 0
        for seed in range(perturbed):
            start = size * np.abs(
                np.random.default_rng(seed).standard_normal(row["contacts"] * row["dim"])
            )
            robust += _solve(given, tol, r0=start)[0].success
        row["perturbed"] = (robust, perturbed)
    return list(rows.values())


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.2e}"


def _ratio(own: float, peer: float | None) -> str:
    return "-" if peer is None else f"{own / peer:.3g}"


def _table(rows, peers: PeerTimes, tol: float) -> str:
    header = (
        f"{'file':44s} {'d':>1s} {'nc':>4s} {'kind':>6s} {'method':>8s} {'it':>4s} "
        f"{'error':>8s} {'first s':>8s} {'best s':>8s} {'median s':>8s} {'NSN s':>12s} "
        f"{'NSGS s':>12s} {'glob. s':>8s} {'cpu s':>8s} {'ratio':>6s} {'c.ratio':>7s} "
        f"{'g.ratio':>7s} {'c.g.ratio':>9s}"
    )
    lines = [header, "-" * len(header)]
    wins = cpu_wins = 0
    for r in rows:
        best = min(r["times"], default=r["first"])
        cpu = min(r["cpu"], default=r["first_cpu"])
        median = statistics.median(r["times"]) if r["times"] else r["first"]
        peer = peers.get(r["file"], {})
        cells = []
        for key in ("newton", "nsgs"):
            entry = peer.get(key)
            cells.append("-" if entry is None else f"{entry[0]:.2e} {'y' if entry[1] else 'n'}")
        fastest = peers.fastest(r["file"])
        if r["converged"] and (fastest is None or best <= fastest):
            wins += 1
        if r["converged"] and (fastest is None or cpu <= fastest):
            cpu_wins += 1
        mark = "" if r["converged"] else " (not converged)"
        lines.append(
            f"{r['file']:44s} {r['dim']:1d} {r['contacts']:4d} "
            f"{'global' if r['global'] else 'local':>6s} {r['method']:>8s} {r['iterations']:4d} "
            f"{r['error']:8.1e} {r['first']:8.2e} {best:8.2e} {median:8.2e} {cells[0]:>12s} "
            f"{cells[1]:>12s} {_seconds(peer.get('global')):>8s} {cpu:8.2e} "
            f"{_ratio(best, fastest):>6s} {_ratio(cpu, fastest):>7s} "
            f"{_ratio(best, peer.get('global')):>7s} {_ratio(cpu, peer.get('global')):>9s}{mark}"
        )
    lines.append("-" * len(header))
    solved = sum(r["converged"] for r in rows)
    first = sum(r["first"] for r in rows)
    lines.append(
        f"{solved}/{len(rows)} solved to natural-map error <= {tol:g} ({first:.3f} s of first "
        f"calls in all); at least as fast as the faster converged Siconos solver on "
        f"{wins}/{len(rows)} in wall time, {cpu_wins}/{len(rows)} in CPU time (ratio, c.ratio = "
        f"contactqp best wall, CPU time / that solver's time, < 1: faster; g.ratio, c.g.ratio = "
        f"best wall, CPU time / Siconos' global Newton)"
    )
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
        "--repeats",
        type=int,
        default=5,
        help="rounds of timed solves after the first, 3 of each file in a row (5)",
    )
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
        f"{platform.system()}, contactqp kernels: {cq.kernels.IMPLEMENTATION}"
        if hasattr(cq, "kernels")
        else f"python {platform.python_version()}, numpy {np.__version__}"
    )
    rows = time_files(files, args.tol, max(0, args.repeats), args.perturbed)
    print(_table(rows, peer_times(), args.tol))
    return 0 if all(r["converged"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())

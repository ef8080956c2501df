"""Per-solve cost of the small shared FCLIB problems, and the throughput of a batch.

Part 1: every shared FCLIB file of at most ``--contacts`` contacts (default 10) is read once
(outside the timing; a global file is condensed once, as in ``PEER-TIMES.md``) and solved by
the ordinary entry point ``contactqp.solve(problem)`` from ``r = 0`` to ``--tol`` (1e-8), the
certificate included. ``first`` is the first solve of a freshly read problem (it pays what is
computed once per problem: the positive-semidefiniteness check, the dense copy of a sparse
``W``; the package's methods are imported before, as start-up); ``median`` is the median of
``--repeats`` further solves of the same problem. Both are
wall time (``time.perf_counter``) and CPU time of the process (``time.process_time``, steadier
on a shared machine). Beside them: Siconos 4.5's times on the same files (its Alart-Curnier
Newton ``NSN_AC`` and Gauss-Seidel ``NSGS``, from ``shared/data/fclib/PEER-TIMES.md``, best of
3 there) and the ratio of the median to the faster of the two (< 1: contactqp is faster).

Part 2: ``--batch`` (default 10,000) one-contact problems in one
:class:`~contactqp.LocalBatch`, solved by ``contactqp.solve(batch)``, in two draws: ``near 1c``
perturbs the shared ``FrictionContact3D_1c`` problem (W and q by 20 % entrywise, ``mu`` in
[0.1, 1]); ``wide`` draws ``W = A A^T + 0.5 I`` (A standard normal), q standard normal, ``mu`` in
[0, 1]: some of those stall in the first Newton run and take the compiled sweeps.
Printed: the best of 3 batch times and the time per problem, the count that needed the later
stages, and whether every problem was certified.

Run ``python benchmarks/bench_small.py --help`` for the options. Times on a loaded machine
vary by 2x or more; ``OPENBLAS_NUM_THREADS=1`` keeps BLAS from competing.
"""

from __future__ import annotations

import argparse
import re
import statistics
import time
from pathlib import Path

import numpy as np
import scipy.linalg  # the methods import these on first use: start-up, not a solve
import scipy.sparse  # noqa: F401

import contactqp
import contactqp.methods  # what contactqp.solve imports on its first use
from contactqp.io.fclib import read_any

__all__ = ["peer_times", "time_file", "time_batch", "main"]

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"


def peer_times(path: Path = DATA / "PEER-TIMES.md") -> dict[str, tuple[float, float]]:
    """``{file: (NSN_AC seconds, NSGS seconds)}`` from the peer table (NaN where absent)."""
    times: dict[str, tuple[float, float]] = {}
    if not path.exists():
        return times
    for line in path.read_text().splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) != 5 or not cells[0].endswith((".dat", ".hdf5")):
            continue
        found = [re.search(r"([0-9.]+(?:e-?[0-9]+)?) s", cell) for cell in cells[3:5]]
        times[cells[0]] = tuple(float(m.group(1)) if m else float("nan") for m in found)
    return times


def _local(path: Path):
    problem = read_any(path)
    return problem.condense() if problem.kind == "global" else problem


def time_file(path: Path, tol: float, repeats: int) -> dict:
    """First-call and median times (wall and CPU, s) of ``contactqp.solve`` on ``path``."""
    problem = _local(path)  # read and condensed outside the timing
    wall, cpu = time.perf_counter(), time.process_time()
    result = contactqp.solve(problem, tol=tol)
    first = (time.perf_counter() - wall, time.process_time() - cpu)
    walls, cpus = [], []
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        contactqp.solve(problem, tol=tol)
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return {
        "contacts": problem.n_contacts,
        "first": first,
        "median": (statistics.median(walls), statistics.median(cpus)),
        "iterations": result.iterations,
        "success": result.success,
        "error": result.certificate.natural_map,
    }


def _draw(kind: str, P: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    if kind == "near 1c":
        base = _local(DATA / "FrictionContact3D_1c.dat")
        W0 = np.asarray(base.W.toarray() if hasattr(base.W, "toarray") else base.W)
        noise = 1.0 + 0.2 * rng.uniform(-1, 1, (P, 3, 3))
        W = 0.5 * (W0 * noise + (W0 * noise).transpose(0, 2, 1))
        q = base.q * (1.0 + 0.2 * rng.uniform(-1, 1, (P, 3)))
        mu = rng.uniform(0.1, 1.0, (P, 1))
    else:
        A = rng.standard_normal((P, 3, 3))
        W = A @ A.transpose(0, 2, 1) + 0.5 * np.eye(3)
        q = rng.standard_normal((P, 3))
        mu = rng.uniform(0.0, 1.0, (P, 1))
    return contactqp.LocalBatch(W, q, mu, 3)


def time_batch(kind: str, P: int, tol: float) -> dict:
    """Best of 3 times (wall, s) of ``contactqp.solve`` on a batch of ``P`` problems."""
    batch = _draw(kind, P)
    best, result = float("inf"), None
    for _ in range(3):
        wall = time.perf_counter()
        result = contactqp.solve(batch, tol=tol)
        best = min(best, time.perf_counter() - wall)
    assert result is not None
    return {"seconds": best, "later": len(result.messages), "solved": result.all_solved}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--contacts", type=int, default=10, help="largest file size (contacts)")
    parser.add_argument("--tol", type=float, default=1e-8)
    parser.add_argument("--repeats", type=int, default=200, help="solves for the median")
    parser.add_argument("--batch", type=int, default=10_000, help="problems in the batch")
    args = parser.parse_args(argv)
    peers = peer_times()
    files = sorted(p for p in DATA.glob("*") if p.suffix in (".dat", ".hdf5"))
    print(f"contactqp {contactqp.__version__}, kernels {contactqp.kernels.IMPLEMENTATION}")
    print(
        f"{'file':46s} {'k':>3s} {'first us':>17s} {'median us':>17s} {'it':>3s} "
        f"{'error':>8s} {'NSN_AC us':>9s} {'NSGS us':>8s} {'ratio':>6s}"
    )
    print(f"{'':46s} {'':>3s} {'wall':>8s} {'cpu':>8s} {'wall':>8s} {'cpu':>8s}")
    for path in files:
        try:
            size = _local(path).n_contacts
        except contactqp.ContactError:
            continue
        if size > args.contacts:
            continue
        row = time_file(path, args.tol, args.repeats)
        newton, gauss_seidel = peers.get(path.name, (float("nan"), float("nan")))
        fastest = np.nanmin([newton, gauss_seidel]) if peers.get(path.name) else float("nan")
        (fw, fc), (mw, mc) = row["first"], row["median"]
        print(
            f"{path.name:46s} {row['contacts']:3d} {fw * 1e6:8.1f} {fc * 1e6:8.1f} "
            f"{mw * 1e6:8.1f} {mc * 1e6:8.1f} {row['iterations']:3d} {row['error']:8.1e} "
            f"{newton * 1e6:9.1f} {gauss_seidel * 1e6:8.1f} {mc / fastest:6.1f}"
            + ("" if row["success"] else "  NOT CONVERGED")
        )
    print()
    print(f"batch of {args.batch} one-contact problems (best of 3, wall)")
    for kind in ("near 1c", "wide"):
        row = time_batch(kind, args.batch, args.tol)
        print(
            f"  {kind:8s} {row['seconds'] * 1e3:8.1f} ms  "
            f"{row['seconds'] / args.batch * 1e6:6.2f} us/problem  "
            f"later stages {row['later']:4d}  all certified {row['solved']}"
        )


if __name__ == "__main__":
    main()

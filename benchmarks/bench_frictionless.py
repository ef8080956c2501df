"""Dense frictionless contact: the own dual solver against qpsolvers backends and one Cholesky.

The problem is a square grid of surface cells of an elastic half-space
(:func:`contactqp.compliance.normal_influence`) pressed by a rigid paraboloid, the approach
chosen so that about half of the cells close (Hertz: contact radius ``a = sqrt(Rs d)``), given to
:class:`contactqp.ContactProblem` with one freedom per cell. Its dual
``min 1/2 l^T W l - b^T l, l >= 0`` (``W = A R A^T`` dense) is assembled once, before any timing.

For each size the script times

* 1st fresh, the headline: the first ``contactqp.solve(problem)`` (default solver) of a new
  problem in each of ``--fresh`` new processes (the median, and the range), which assembles
  ``W = A R A^T`` and ``b`` (end to end: a user calls it once), its code and memory cold; the
  matrix ``R`` is built and the modules imported before the clock starts;
* own 1st: the same first call in this process (after the problems of the smaller sizes): one
  sample, noisier;
* from R: ``ReducedModel(flexibility=R)`` (its validation), ``ContactProblem`` and the first
  ``solve``, from the matrix ``R`` alone;
* own: the same solve's best of repeats (``W`` kept by the problem);
* assembly: ``problem.dual()`` (``W`` and ``b``) alone, on another new problem;
* core: :func:`contactqp.methods.box_qp.solve_box_qp` on ``(W, -b)`` alone, from the same cold
  start as the own solver;
* chol: one dense ``scipy.linalg.cho_factor(W)``, the yardstick of the project's target;
* every installed qpsolvers backend on the same dual box QP with contactqp's tight tolerances
  (:func:`contactqp.methods.qp.backend_options`), each run in a forked child process (killed after
  ``--timeout`` seconds). A backend's answer counts only when its forces agree with the own
  solver's to ``1e-6`` relative (``max|l - l_own| / max l_own``). A backend's first call and
  its best of repeats are both kept; the ratios below take its best.

At 1,600 contacts (or the middle size) the summary prints the project's targets on the first
call (1st fresh, or own 1st with ``--fresh 0``): over the median of repeats (at most 1.3), the
fastest accurate backend over it (at least 30x) and it over chol (at most 0.5); and the same
ratios of own 1st beside them.

The backends get the QP in scaled units, as a careful user would give it to them (in SI units
``W`` is ~1e-7 m/N and absolute tolerances lose their meaning): ``W' = W / w`` with ``w`` the mean
diagonal of ``W`` and ``c' = c / max|c|``, whose solution ``l'`` gives ``l = l' max|c| / w``.
``--raw-units`` hands them ``W`` and ``c`` unscaled instead. The own solver always gets SI units.

A backend is skipped at a size when its time at the previous size times the cube of the size
ratio (dense interior-point and active-set work grows like ``m^3``) exceeds ``--budget``.

Run ``python benchmarks/bench_frictionless.py --help`` for the options.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
import os
import platform
import subprocess
import sys
import textwrap
import time
import traceback
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg

import contactqp
from contactqp import ContactProblem, GapObstacle, ReducedModel
from contactqp.compliance import grid, normal_influence
from contactqp.methods import solve_box_qp
from contactqp.methods.active_set import cold_start
from contactqp.methods.qp import available_backends, backend_options

__all__ = ["Timing", "best_time", "build_problem", "half_space", "main", "timing"]

YOUNG, POISSON = 210e9, 0.3  # steel half-space (Pa, -)
CELL = 10e-6  # cell size (m)
SPHERE_RADIUS = 5e-3  # rigid paraboloid radius of curvature (m)
CLOSED_FRACTION = 0.5  # target fraction of closed contacts
ACCURACY = 1e-6  # max|l - l_own| / max l_own accepted from a backend
WAVY_INTERFERENCE = 10.0  # approach of the wavy surface, in amplitudes (about half closed)
SHORT_RUN = 0.5  # s: runs shorter than this are repeated and the best time kept


def build_problem(n_contacts: int, *, surface: str = "paraboloid") -> ContactProblem:
    """A half-space grid of ``n_contacts`` cells (a perfect square) pressed by a rigid body.

    Parameters
    ----------
    n_contacts : int
        Number of cells, ``side**2``.
    surface : {"paraboloid", "wavy"}
        See :func:`half_space`.

    Returns
    -------
    ContactProblem
        One freedom per cell, zero external load, gaps along the outward normal (m).
    """
    return contact_problem(*half_space(n_contacts, surface=surface))


def contact_problem(R: np.ndarray, gaps: np.ndarray) -> ContactProblem:
    """The model of flexibility ``R`` (one freedom per cell) against gaps ``gaps``, unloaded."""
    model = ReducedModel(flexibility=R)
    return ContactProblem(model, np.zeros(gaps.size), [GapObstacle(np.arange(gaps.size), gaps)])


def half_space(n_contacts: int, *, surface: str = "paraboloid") -> tuple[np.ndarray, np.ndarray]:
    """``(R, gaps)``: a half-space grid's flexibility (m/N) and the rigid body's initial gaps (m).

    Parameters
    ----------
    n_contacts : int
        Number of cells, ``side**2``.
    surface : {"paraboloid", "wavy"}
        ``"paraboloid"``: a sphere of radius 5 mm pushed so that the Hertz contact area covers
        half of the grid (one round patch). ``"wavy"``: an egg-box rigid surface
        ``A (2 - cos kx - cos ky)`` with 4 x 4 waves over the grid, pushed ``10 A`` into the
        half-space, so that about half of the cells close in 16 patches that start to merge
        (a less regular active set).
    """
    side = math.isqrt(n_contacts)
    if side * side != n_contacts:
        raise SystemExit(f"--sizes: {n_contacts} is not a perfect square (the grid is square)")
    x, y = grid(side, side, CELL, CELL)
    R = normal_influence(x, y, CELL, CELL, YOUNG, POISSON)
    if surface == "paraboloid":
        radius = side * CELL * math.sqrt(CLOSED_FRACTION / math.pi)
        approach = radius**2 / SPHERE_RADIUS
        gaps = (x**2 + y**2) / (2 * SPHERE_RADIUS) - approach
    elif surface == "wavy":
        wavelength = side * CELL / 4
        amplitude = 5e-9 * side  # geometrically similar at every size
        k = 2 * np.pi / wavelength
        height = amplitude * (2 - np.cos(k * x) - np.cos(k * y))
        gaps = height - WAVY_INTERFERENCE * amplitude
    else:
        raise SystemExit(f"--surface must be paraboloid or wavy, got {surface!r}")
    return R, gaps


@dataclass(frozen=True)
class Timing:
    """One call timed first, then repeated while short (see :func:`timing`).

    Attributes
    ----------
    first : float
        Seconds of the first call.
    repeats : tuple of float
        Seconds of each repetition after it (none when the first call took
        :data:`SHORT_RUN` or more).
    value
        What the first call returned.
    """

    first: float
    repeats: tuple
    value: object = None

    @property
    def best(self) -> float:
        """The fastest of all the calls, the first included."""
        return min((self.first, *self.repeats))

    @property
    def median(self) -> float:
        """The median of the repetitions (the first call's time when there are none)."""
        return float(np.median(self.repeats)) if self.repeats else self.first


def timing(run, budget: float = 2.0, max_repeat: int = 7) -> Timing:
    """Run ``run()`` once, then again while the best is under :data:`SHORT_RUN` (up to
    ``max_repeat`` calls in all and ``budget`` seconds)."""
    start = time.perf_counter()
    value = run()
    first = time.perf_counter() - start
    repeats: list[float] = []
    best, spent = first, first
    while best < SHORT_RUN and spent < budget and len(repeats) + 1 < max_repeat:
        start = time.perf_counter()
        run()
        elapsed = time.perf_counter() - start
        repeats.append(elapsed)
        best, spent = min(best, elapsed), spent + elapsed
    return Timing(first, tuple(repeats), value)


def best_time(run, budget: float = 2.0, max_repeat: int = 7):
    """``(best seconds, first value, first s)`` of :func:`timing`."""
    measured = timing(run, budget, max_repeat)
    return measured.best, measured.value, measured.first


def _backend_child(connection, backend, W, c, unscale):
    """Solve the dual box QP with one backend; send back ``(Timing, forces * unscale, note)``
    (``Timing`` None on an error)."""
    try:
        import qpsolvers
        import scipy.sparse

        matrix = W
        if backend not in qpsolvers.dense_solvers:  # sparse-only backends: convert untimed
            matrix = scipy.sparse.csc_matrix(W)
        problem = qpsolvers.Problem(P=matrix, q=c, lb=np.zeros(c.size))
        settings = backend_options(backend)

        def run():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return qpsolvers.solve_problem(problem, solver=backend, **settings)

        measured = timing(run)
        solution = measured.value
        forces = None if solution.x is None else unscale * np.asarray(solution.x, dtype=float)
        note = "" if solution.found is not False else "not found"
        connection.send((Timing(measured.first, measured.repeats), forces, note))
    except Exception as exc:  # a backend error is a table entry, not a crash
        note = f"error: {type(exc).__name__}: {exc}".splitlines()[0]
        connection.send((None, None, note))
        traceback.print_exc(file=sys.stderr)
    finally:
        connection.close()


def run_backend(backend, W, c, unscale, timeout):
    """Fork a child to time ``backend``; ``(Timing or None, forces, note)``, note "timeout" if
    killed."""
    context = multiprocessing.get_context("fork")
    parent, child = context.Pipe(duplex=False)
    process = context.Process(
        target=_backend_child, args=(child, backend, W, c, unscale), daemon=True
    )
    process.start()
    child.close()
    outcome = (None, None, "timeout")
    if parent.poll(timeout):
        try:
            outcome = parent.recv()
        except EOFError:
            outcome = (None, None, f"crashed (exit code {process.exitcode})")
    if process.is_alive():
        process.kill()
    process.join()
    return outcome


def first_call_seconds(size: int, surface: str) -> float:
    """Seconds of the first ``contactqp.solve`` of a new problem of ``size`` contacts in this
    process (``R`` built before the clock starts)."""
    R, gaps = half_space(size, surface=surface)
    problem = contact_problem(R, gaps)
    start = time.perf_counter()
    contactqp.solve(problem)
    return time.perf_counter() - start


def fresh_first_calls(size: int, surface: str, count: int) -> list[float]:
    """:func:`first_call_seconds` in each of ``count`` new processes, one after another (the
    environment, BLAS threads included, passed on)."""
    seconds = []
    for _ in range(count):
        done = subprocess.run(
            [sys.executable, __file__, "--first-call-child", str(size), "--surface", surface],
            capture_output=True,
            text=True,
            check=True,
        )
        seconds.append(float(done.stdout.split()[-1]))
    return seconds


def _fmt_seconds(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "-"
    if seconds < 1e-2:
        return f"{seconds * 1e3:.2f}ms"
    if seconds < 1.0:
        return f"{seconds * 1e3:.0f}ms"
    return f"{seconds:.2f}s"


def _print_table(headers, rows):
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) for i, h in enumerate(headers)]
    line = "  ".join(str(h).rjust(w) for h, w in zip(headers, widths, strict=True))
    print(line)
    print("-" * len(line))
    for row in rows:
        print("  ".join(str(v).rjust(w) for v, w in zip(row, widths, strict=True)))


def main(argv=None) -> int:
    """Run the benchmark and print its tables; returns the exit code."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--sizes",
        default="400,1600,6400",
        help="comma-separated contact counts, perfect squares (default 400,1600,6400)",
    )
    parser.add_argument(
        "--backends",
        default=None,
        help="comma-separated qpsolvers backends (default: every installed one); "
        "'none' for the own solver and Cholesky only",
    )
    parser.add_argument("--surface", default="paraboloid", choices=["paraboloid", "wavy"])
    parser.add_argument(
        "--budget",
        type=float,
        default=60.0,
        help="s: skip a backend when its predicted time exceeds this (default 60)",
    )
    parser.add_argument(
        "--raw-units",
        action="store_true",
        help="give the backends W and c in SI units instead of scaled ones",
    )
    parser.add_argument(
        "--timeout",
        type=float,
        default=None,
        help="s: kill a backend run after this (default 3 x budget)",
    )
    parser.add_argument(
        "--fresh",
        type=int,
        default=5,
        help="new processes timing a first call at each size (default 5; 0: none)",
    )
    parser.add_argument("--first-call-child", type=int, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.first_call_child is not None:  # one first call, in a process of its own
        print(repr(first_call_seconds(args.first_call_child, args.surface)))
        return 0

    sizes = [int(s) for s in args.sizes.split(",") if s.strip()]
    installed = available_backends()
    if args.backends is None:
        backends = installed
    elif args.backends.strip().lower() == "none":
        backends = []
    else:
        backends = [b.strip() for b in args.backends.split(",") if b.strip()]
        missing = [b for b in backends if b not in installed]
        if missing:
            parser.error(
                f"--backends: not installed: {', '.join(missing)}; "
                f"installed: {', '.join(installed)}"
            )
    timeout = args.timeout if args.timeout is not None else 3 * args.budget

    print(
        f"contactqp {contactqp.__version__}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"Python {platform.python_version()}, {os.cpu_count()} CPUs, {platform.machine()}"
    )
    print(
        f"problem: half-space grid ({CELL * 1e6:.0f} um cells, E = {YOUNG / 1e9:.0f} GPa, "
        f"nu = {POISSON}), rigid {args.surface}, dense dual W = A R A^T; "
        f"backends on the dual box QP, accepted when max|l - l_own| / max l_own < {ACCURACY:g}"
    )
    threads = {
        k: os.environ[k]
        for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
        if k in os.environ
    }
    print(
        f"BLAS threads: {threads or 'library default'}; backends get "
        f"{'SI units' if args.raw_units else 'scaled W / mean diag W, c / max|c|'}"
    )
    print(
        f"skip rule: time at previous size x (size ratio)^3 > {args.budget:g} s; "
        f"hard timeout {timeout:g} s\n"
    )

    rows, notes, summary = [], [], {}
    previous = {}  # backend -> (size, seconds) of its last completed run
    for size in sizes:
        start = time.perf_counter()
        R, gaps = half_space(size, surface=args.surface)
        build = time.perf_counter() - start
        # own 1st: the first solve of a new problem (W assembled in it); then its repeats
        problem = contact_problem(R, gaps)
        own = timing(lambda problem=problem: contactqp.solve(problem))
        result = own.value
        fresh_seconds = fresh_first_calls(size, args.surface, args.fresh)
        headline = float(np.median(fresh_seconds)) if fresh_seconds else own.first
        # from R: the model's validation, the problem and the first solve, end to end
        start = time.perf_counter()
        contactqp.solve(contact_problem(R, gaps))
        from_matrix = time.perf_counter() - start
        if not result.success:
            notes.append(f"{size}: own solver did not succeed: {result.message}")
        fresh = contact_problem(R, gaps)
        start = time.perf_counter()
        dual = fresh.dual()
        assembly = time.perf_counter() - start
        W, c = dual.W, -dual.b
        if args.raw_units:
            W_backend, c_backend, unscale = W, c, 1.0
        else:
            w_scale, c_scale = float(np.mean(np.diag(W))), float(np.max(np.abs(c)))
            W_backend, c_backend, unscale = W / w_scale, c / c_scale, c_scale / w_scale
        reference = result.forces
        scale = float(np.max(np.abs(reference)))
        core = timing(
            lambda W=W, c=c: solve_box_qp(W, c, lower=0.0, x0=cold_start(W, -c), check_finite=False)
        )
        chol = timing(lambda W=W: scipy.linalg.cho_factor(W, lower=True, check_finite=False))

        row = {
            "contacts": size,
            "closed": int(
                np.count_nonzero(result.contact_status == contactqp.ContactStatus.CLOSED)
            ),
            "1st fresh": (
                f"{_fmt_seconds(headline)} ({_fmt_seconds(min(fresh_seconds))}-"
                f"{_fmt_seconds(max(fresh_seconds))})"
                if fresh_seconds
                else "-"
            ),
            "own 1st": _fmt_seconds(own.first),
            "own med": _fmt_seconds(own.median),
            "own best": _fmt_seconds(own.best),
            "1st/med": f"{headline / own.median:.2f}",
            "from R": _fmt_seconds(from_matrix),
            "build R": _fmt_seconds(build),
            "assembly": _fmt_seconds(assembly),
            "core": _fmt_seconds(core.median),
            "it/fact/upd": f"{core.value.iterations}/{core.value.factorizations}/"
            f"{core.value.updates}",
            "chol med": _fmt_seconds(chol.median),
            "chol best": _fmt_seconds(chol.best),
            "1st/chol": f"{headline / chol.median:.2f}",
        }
        summary[size] = {
            "own": own,
            "first": headline,
            "fresh": len(fresh_seconds),
            "from R": from_matrix,
            "chol": chol,
            "backends": {},
        }
        for backend in backends:
            if backend in previous:
                last_size, last_seconds = previous[backend]
                predicted = last_seconds * (size / last_size) ** 3
                if predicted > args.budget:
                    row[backend] = "skipped"
                    notes.append(
                        f"{size}: {backend} skipped, predicted {predicted:.0f} s "
                        f"> budget {args.budget:g} s ({_fmt_seconds(last_seconds)} "
                        f"at {last_size} x ({size}/{last_size})^3)"
                    )
                    continue
            measured, forces, note = run_backend(backend, W_backend, c_backend, unscale, timeout)
            if note == "timeout":
                row[backend] = "timeout"
                notes.append(f"{size}: {backend} killed after {timeout:g} s")
                previous[backend] = (size, timeout)
                continue
            if forces is None or forces.shape != reference.shape or not np.all(np.isfinite(forces)):
                row[backend] = f"failed ({note or 'no solution'})"
                if measured is not None:
                    previous[backend] = (size, measured.median)
                continue
            previous[backend] = (size, measured.median)
            error = float(np.max(np.abs(forces - reference))) / scale
            if error > ACCURACY:
                row[backend] = f"{_fmt_seconds(measured.median)} inaccurate (err={error:.1e})"
            else:
                row[backend] = (
                    f"{_fmt_seconds(measured.first)}/{_fmt_seconds(measured.median)} "
                    f"x{measured.median / headline:.1f}"
                )
                summary[size]["backends"][backend] = measured
        rows.append(row)
        print(
            f"[{size} contacts done: first call {_fmt_seconds(headline)}, own 1st "
            f"{_fmt_seconds(own.first)}, own median "
            f"{_fmt_seconds(own.median)}, chol median {_fmt_seconds(chol.median)}]",
            file=sys.stderr,
            flush=True,
        )

    headers = [
        "contacts",
        "closed",
        "1st fresh",
        "own 1st",
        "own med",
        "own best",
        "1st/med",
        "from R",
        "build R",
        "assembly",
        "core",
        "it/fact/upd",
        "chol med",
        "chol best",
        "1st/chol",
    ] + backends
    _print_table(headers, [[row.get(h, "-") for h in headers] for row in rows])
    legend = (
        f"1st fresh: the first contactqp.solve(problem) of a new problem (W assembled in it) in "
        f"each of {args.fresh} new processes, median (range), the headline; 1st/med, 1st/chol "
        "and the backends' ratios use it (own 1st with --fresh 0). own 1st: the same first call "
        "in this process, one sample. own med / best: the median / best of its repeats (W kept "
        "by the problem). from R: ReducedModel(R) + ContactProblem + the first solve. build R: "
        "the half-space matrix. assembly: problem.dual() alone. core: solve_box_qp(W, -b) alone "
        "(median). it/fact/upd: core iterations / Cholesky factorisations / updated "
        "factorisations of free blocks. chol: one cho_factor of the full W (median and best of "
        "its repeats). Backend cells: first call / median of repeats (the first call alone when "
        "it took 0.5 s or more), and that median / the first call (x > 1: slower than own's "
        "first call)."
    )
    print("\n" + textwrap.fill(legend, width=100))
    for note in notes:
        print(f"note: {note}")

    target = 1600 if 1600 in summary else (sizes[len(sizes) // 2] if sizes else None)
    if target is not None:
        entry = summary[target]
        own, chol = entry["own"], entry["chol"]
        first = entry["first"]
        source = (
            f"median of {entry['fresh']} new processes" if entry["fresh"] else "own 1st, one sample"
        )
        print(f"\nsummary at {target} contacts (first call: {source}, {_fmt_seconds(first)}):")
        ratio = first / own.median
        print(
            f"  first call / median of repeats = {ratio:.2f} (target <= 1.3: "
            f"{'met' if ratio <= 1.3 else 'missed'}); / best of repeats = {first / own.best:.2f}; "
            f"own 1st (this process, {_fmt_seconds(own.first)}) / median = "
            f"{own.first / own.median:.2f}"
        )
        if entry["backends"]:
            fastest = min(entry["backends"], key=lambda name: entry["backends"][name].median)
            measured = entry["backends"][fastest]
            speedup = measured.median / first
            print(
                f"  fastest accurate backend / first call = {speedup:.1f}x ({fastest}, median "
                f"{_fmt_seconds(measured.median)}, best {_fmt_seconds(measured.best)}: "
                f"{measured.best / first:.1f}x; target >= 30: "
                f"{'met' if speedup >= 30 else 'missed'})"
            )
        else:
            print("  fastest accurate backend / first call: no accurate backend to compare with")
        ratio = first / chol.median
        print(
            f"  first call / one Cholesky of W = {ratio:.2f} (median {_fmt_seconds(chol.median)}; "
            f"target <= 0.5: {'met' if ratio <= 0.5 else 'missed'}); / the fastest Cholesky "
            f"({_fmt_seconds(chol.best)}) = {first / chol.best:.2f}"
        )
        print(
            f"  from R (model validation + problem + first call) / one Cholesky of W = "
            f"{entry['from R'] / chol.median:.2f}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

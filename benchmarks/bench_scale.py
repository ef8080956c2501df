"""Matrix-free contact at scale: contactqp against Tamaas and ContactMechanics, one thread.

Two problems, every contender run in its own subprocess (its peak resident memory is the
subprocess's ``ru_maxrss``, C++ allocations included), one thread everywhere
(``OMP_NUM_THREADS=1``, ``OPENBLAS_NUM_THREADS=1`` set before any import, FFT workers 1):

1. **Non-periodic Hertz**: a rigid sphere (paraboloid, ``R = 10 mm``) on a steel half-space
   (``E = 210 GPa``, ``nu = 0.3``), ``n x n`` square cells on a 1 mm square, the load ``F`` of
   Hertz's theory for a contact radius ``a = n / 4`` cells (contact diameter half the grid).

   * ``contactqp``: :class:`contactqp.compliance.HalfSpaceOperator` (non-periodic, zero padded)
     + :class:`contactqp.core.surface.SurfaceProblem` (``load=F``) + ``contactqp.solve``
     (``constrained-cg``, ``tol`` below);
   * ``ContactMechanics``: ``FreeFFTElasticHalfSpace`` (non-periodic, the same Love kernel of
     a uniformly loaded cell) + its ``constrained_conjugate_gradients`` (Polonsky-Keer);
   * ``Tamaas``: periodic only. Its period is padded to ``2n x 2n`` points of the same spacing
     (contact diameter a quarter of the period, the size of the padded FFT grids of the other
     two); ``PolonskyKeerRey`` on its nodal spectral (Westergaard) kernel. The periodic images
     and the nodal kernel make its answer differ from the non-periodic one by about 1e-3 in
     the contact radius (printed): that is a different discrete problem, not a solver error.

   Accuracy: load ``sum f / F``, contact radius ``a`` relative to Hertz's, measured two ways:
   ``a_area = sqrt(cells in contact * dx^2 / pi)`` (quantised by the grid) and the moment
   radius ``a_mom = sqrt(5/2 * sum(f r^2) / sum f)`` (Hertz's pressure gives ``a`` exactly;
   not quantised, the one compared to 1e-4), and the peak pressure over Hertz's ``p0``.

2. **Periodic rough surface**: a self-affine surface (Hurst 0.8, roll-off at 4 and cut-off at
   ``n / 8`` wavelengths per period, rms slope 0.1, seed 1) generated here with numpy, the SAME
   heights fed to both; mean pressures ``p / (E* h'_rms)`` of 0.01, 0.025 and 0.05 (about 2 to
   10 % of contact). ``contactqp``: the periodic ``HalfSpaceOperator`` (spectral kernel
   ``2 / (E* |q|)`` on forces per cell area) + ``SurfaceProblem(load=p L^2)``;
   ``Tamaas``: ``PolonskyKeerRey`` (kernel ``2 / (E* |q|)`` on nodal pressures): the same
   discrete operator, so the areas must agree to the solvers' tolerance.

3. **Partial slip** (``--slip-sizes``, off by default): the Hertz sphere pressed to ``P`` (a
   contact radius of ``n / 4`` cells) and sheared by ``Q = mu P / 2`` (``mu = 0.3``, Poisson's
   ratio 0.4999 for both, so that the normal-tangential coupling vanishes), in one step from
   the unloaded state, both forces fixed. ``contactqp``: ``SlidingSurfaceProblem(force=(Q,
   0))`` on the non-periodic full ``HalfSpaceOperator`` (``coupling=False``), solved by
   ``tangential-fista`` (tol 5e-9, natural-map error printed); ``Tamaas``:
   ``PolonskyKeerTan`` (tol 1e-8, mean tractions ``(Q, 0, P) / L^2`` on a ``2n x 2n`` period of
   its ``surface_2d`` model). Accuracy: the loads carried over ``P`` and ``Q``, the contact
   radius over Hertz's and the stick radius over Mindlin's ``c = a (1 - Q / mu P)^(1/3)``
   (both from the cell counts).

Time: ``first`` is the first call in a fresh process (operator/model construction and solve,
imports excluded); ``best`` the best of the repeats in the same process (up to ``--repeat``,
within a few seconds). ``MB`` is the subprocess's peak resident set (``ru_maxrss``) and
``base`` its resident set after the imports, before the first call. The cost growth ``k`` is
the least-squares slope of ``log(best time)`` on ``log(cells)`` over the sizes run.

Run from the repository root (``make bench-scale`` installs the peers, the ``bench`` extra)::

    .venv/bin/python benchmarks/bench_scale.py                  # Hertz 64..512, rough 512
    .venv/bin/python benchmarks/bench_scale.py --large          # + Hertz 1024^2, rough 2048^2
    .venv/bin/python benchmarks/bench_scale.py --sizes 64,128 --rough-sizes 256
    .venv/bin/python benchmarks/bench_scale.py --sizes "" --skip-rough --slip-sizes 128,256

A peer that cannot be imported is reported and skipped; the others run.
"""

from __future__ import annotations

import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

YOUNG, POISSON = 210e9, 0.3
E_STAR = YOUNG / (1.0 - POISSON**2)
SIDE = 1e-3  # m, the grid's side
RADIUS = 1e-2  # m, the sphere's
CONTACTQP_TOL = 1e-8  # constrained-cg: gap on the contact / length scale
TAMAAS_TOL = 1e-6  # PolonskyKeerRey relative error (1e-10: the same a_mom to 1e-6, 1.5-3x the time)
CM_PENTOL = 1e-6  # ContactMechanics: penetration tolerance, times Hertz's approach
CM_FORCETOL = 1e-6  # ContactMechanics: force outside the contact, times F / n^2
ROUGH_LOADS = (0.01, 0.025, 0.05)  # p / (E* h'_rms)
ROUGH_SLOPE = 0.1
HERTZ_PEERS = ("contactqp", "tamaas", "contactmechanics")
ROUGH_PEERS = ("contactqp", "tamaas")
SLIP_PEERS = ("contactqp", "tamaas")
SLIP_MU, SLIP_POISSON = 0.3, 0.4999
SLIP_TOL = 5e-9  # tangential-fista: natural-map errors of 6e-9 to 8e-9, below the target's 1e-8


# --- the problems --------------------------------------------------------------------------


def hertz_setup(n: int) -> dict:
    dx = SIDE / n
    a = n / 4 * dx
    load = 4.0 * E_STAR * a**3 / (3.0 * RADIUS)
    c = (np.arange(n) - (n - 1) / 2) * dx
    X, Y = np.meshgrid(c, c)
    r2 = X**2 + Y**2
    return {"n": n, "dx": dx, "a": a, "load": load, "r2": r2, "s": r2 / (2 * RADIUS)}


def tamaas_sphere(n: int, dx: float) -> tuple[int, np.ndarray]:
    """``(m, heights)``: Tamaas's period of ``m = 2n`` points of spacing ``dx`` padding the
    ``n x n`` grid, and the sphere's heights on it (the tip at its centre)."""
    m = 2 * n
    c = (np.arange(m) - (m - 1) / 2) * dx
    XX, YY = np.meshgrid(c, c)
    return m, -(XX**2 + YY**2) / (2 * RADIUS)


def rough_heights(n: int, seed: int = 1) -> tuple[np.ndarray, float]:
    """A periodic self-affine surface (m) on ``n x n`` points of spacing ``SIDE / n``.

    By default its cut-off is at ``n / 8`` wavelengths per period and its random field is
    drawn on the ``n x n`` grid: each size is another, rougher surface. With
    ``--rough-cutoff C`` (the environment variable ``BENCH_ROUGH_CUTOFF``, which the workers
    inherit) the cut-off is ``C`` and the field is drawn on the ``(2C + 2)^2`` modes below it:
    the same surface at every ``n >= 2C + 2``, only resolved more finely.
    """
    dx = SIDE / n
    rng = np.random.default_rng(seed)
    qx = 2 * np.pi * np.fft.fftfreq(n, dx)
    q = np.hypot(qx[None, :], qx[:, None])
    ql = 2 * np.pi / SIDE
    fixed = os.environ.get("BENCH_ROUGH_CUTOFF")
    cutoff = n / 8 if fixed is None else float(fixed)
    qr, qs = 4 * ql, cutoff * ql
    psd = np.where(q < qr, qr, q) ** (-2 * (1 + 0.8))
    psd[(q > qs) | (q == 0)] = 0.0
    if fixed is None:
        noise = np.fft.fft2(rng.standard_normal((n, n)))
    else:  # the same modes at every n: drawn on the smallest grid that holds the cut-off
        m = 2 * int(np.ceil(cutoff)) + 2
        if n < m:
            raise SystemExit(f"--rough-cutoff {cutoff:g} needs grids of at least {m} points")
        modes = np.fft.fftfreq(m, 1 / m).astype(int) % n
        noise = np.zeros((n, n), dtype=complex)
        noise[np.ix_(modes, modes)] = np.fft.fft2(rng.standard_normal((m, m))) * (n / m) ** 2
    h = np.fft.ifft2(noise * np.sqrt(psd)).real
    slope = np.sqrt(np.mean(np.abs(np.fft.ifft2(1j * qx[None, :] * np.fft.fft2(h))) ** 2) * 2)
    return h * (ROUGH_SLOPE / slope), dx


# --- the contenders (each runs in a worker subprocess) ---------------------------------------


def _import_lazy() -> None:
    """Import before the clock starts what contactqp imports on first use: pyFFTW (its FFT
    library when installed; 0.7 s, it pulls in dask) and the method registry that the first
    ``contactqp.solve`` loads (about 70 ms: every method module). Imports are excluded for
    every contender alike."""
    import contactqp.methods.registry  # noqa: F401

    try:
        import pyfftw  # noqa: F401
    except ImportError:
        pass


def run_hertz(name: str, n: int):
    setup = hertz_setup(n)
    dx, load, s = setup["dx"], setup["load"], setup["s"]
    if name == "contactqp":
        import contactqp as cq
        from contactqp.compliance.fft_halfspace import HalfSpaceOperator
        from contactqp.core.surface import SurfaceProblem

        _import_lazy()

        def call():
            W = HalfSpaceOperator(n, n, dx, dx, YOUNG, POISSON, workers=1)
            result = cq.solve(SurfaceProblem(W, s.ravel(), load=load), tol=CONTACTQP_TOL)
            assert result.success, result.message
            return result.forces.reshape(n, n), result.iterations

        tol = f"tol={CONTACTQP_TOL:g}"
    elif name == "tamaas":
        import tamaas as tm

        tm.set_log_level(tm.LogLevel.error)
        m, surface = tamaas_sphere(n, dx)
        o = n // 2

        def call():
            model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [m * dx] * 2, [m, m])
            model.E, model.nu = YOUNG, POISSON
            solver = tm.PolonskyKeerRey(model, surface, TAMAAS_TOL)
            solver.solve(load / (m * dx) ** 2)
            p = np.array(model.traction)
            return p[o : o + n, o : o + n] * dx * dx, -1

        tol = f"tol={TAMAAS_TOL:g}"
    else:
        from ContactMechanics import FreeFFTElasticHalfSpace
        from ContactMechanics.Optimization import constrained_conjugate_gradients

        delta = setup["a"] ** 2 / RADIUS

        def call():
            substrate = FreeFFTElasticHalfSpace((n, n), E_STAR, (SIDE, SIDE))
            out = constrained_conjugate_gradients(
                substrate,
                -s,
                external_force=load,
                pentol=CM_PENTOL * delta,
                forcetol=CM_FORCETOL * load / n**2,
                maxiter=20000,
            )
            assert out.success, out.message
            return np.asarray(out.jac), int(out.nit)

        tol = f"pentol={CM_PENTOL:g}*delta forcetol={CM_FORCETOL:g}*F/n^2"

    def judge(forces):
        f = np.asarray(forces)
        r2, a, p0 = setup["r2"], setup["a"], 3 * load / (2 * np.pi * setup["a"] ** 2)
        return {
            "load": float(f.sum() / load),
            "a_area": float(np.sqrt(np.sum(f > 1e-10 * f.max()) * dx * dx / np.pi) / a),
            "a_mom": float(np.sqrt(2.5 * np.sum(f * r2) / np.sum(f)) / a),
            "p_max": float(f.max() / (dx * dx) / p0),
            "tol": tol,
        }

    return call, judge


def run_rough(name: str, n: int, level: float):
    h, dx = rough_heights(n)
    pressure = level * E_STAR * ROUGH_SLOPE
    load = pressure * SIDE**2
    if name == "contactqp":
        import contactqp as cq
        from contactqp.compliance.fft_halfspace import HalfSpaceOperator
        from contactqp.core.surface import SurfaceProblem

        s = (h.max() - h).ravel()
        _import_lazy()

        def call():
            W = HalfSpaceOperator(n, n, dx, dx, YOUNG, POISSON, periodic=True, workers=1)
            result = cq.solve(SurfaceProblem(W, s, load=load), tol=CONTACTQP_TOL)
            assert result.success, result.message
            return result.forces.reshape(n, n), result.iterations

        tol = f"tol={CONTACTQP_TOL:g}"
    else:
        import tamaas as tm

        tm.set_log_level(tm.LogLevel.error)

        def call():
            model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [SIDE, SIDE], [n, n])
            model.E, model.nu = YOUNG, POISSON
            solver = tm.PolonskyKeerRey(model, h, TAMAAS_TOL)
            solver.solve(pressure)
            return np.array(model.traction) * dx * dx, -1

        tol = f"tol={TAMAAS_TOL:g}"

    def judge(forces):
        f = np.asarray(forces)
        return {
            "load": float(f.sum() / load),
            "area": float(np.mean(f > 1e-10 * f.max())),
            "tol": tol,
        }

    return call, judge


def run_slip(name: str, n: int):
    dx = SIDE / n
    e_star = YOUNG / (1.0 - SLIP_POISSON**2)
    a = n / 4 * dx
    load = 4.0 * e_star * a**3 / (3.0 * RADIUS)
    shear = 0.5 * SLIP_MU * load
    if name == "contactqp":
        import contactqp as cq
        from contactqp.compliance.fft_halfspace import HalfSpaceOperator
        from contactqp.core.sliding_surface import SlidingSurfaceProblem
        from contactqp.core.surface import SurfaceProblem

        s = hertz_setup(n)["s"].ravel()
        _import_lazy()

        def call():
            normal = HalfSpaceOperator(n, n, dx, dx, YOUNG, SLIP_POISSON, workers=1)
            full = HalfSpaceOperator(
                n, n, dx, dx, YOUNG, SLIP_POISSON, components="full", coupling=False, workers=1
            )
            problem = SlidingSurfaceProblem(
                SurfaceProblem(normal, s, load=load), full, SLIP_MU, force=(shear, 0.0)
            )
            result = cq.solve(problem, tol=SLIP_TOL)
            assert result.success, result.message
            f = result.forces  # (p, t_x, t_y) per cell
            return (f[:, 0], f[:, 1], f[:, 2], result.certificate.natural_map), result.iterations

        tol = f"tol={SLIP_TOL:g}"
    else:
        import tamaas as tm

        tm.set_log_level(tm.LogLevel.error)
        m, surface = tamaas_sphere(n, dx)
        area = (m * dx) ** 2

        def call():
            model = tm.ModelFactory.createModel(tm.model_type.surface_2d, [m * dx] * 2, [m, m])
            model.E, model.nu = YOUNG, SLIP_POISSON
            solver = tm.PolonskyKeerTan(model, surface, 1e-8, SLIP_MU)
            solver.max_iter = 100000
            solver.solve([shear / area, 0.0, load / area])
            f = np.array(model.traction).reshape(-1, 3) * dx * dx  # (t_x, t_y, p) per point
            return (f[:, 2], f[:, 0], f[:, 1], None), -1

        tol = "tol=1e-8"

    def judge(forces):
        p, tx, ty, natural_map = (np.asarray(v) if v is not None else None for v in forces)
        contact = p > 1e-10 * p.max()
        stick = contact & (np.hypot(tx, ty) < SLIP_MU * p * (1 - 1e-6))
        c = a * (1 - shear / (SLIP_MU * load)) ** (1 / 3)
        return {
            "load": float(p.sum() / load),
            "shear": float(tx.sum() / shear),
            "a": float(np.sqrt(contact.sum() * dx * dx / np.pi) / a),
            "c": float(np.sqrt(stick.sum() * dx * dx / np.pi) / c),
            "natural_map": None if natural_map is None else float(natural_map),
            "tol": tol,
        }

    return call, judge


def worker(case: str, name: str, n: int, level: float, repeat: int) -> dict:
    try:
        if case == "hertz":
            call, judge = run_hertz(name, n)
        elif case == "rough":
            call, judge = run_rough(name, n, level)
        else:
            call, judge = run_slip(name, n)
    except ImportError as error:
        return {"error": f"cannot import {name}: {error}"}
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    start = time.perf_counter()
    forces, iterations = call()
    first = time.perf_counter() - start
    times = [first]
    while len(times) < repeat and sum(times) < 3.0:
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return {
        "first": first,
        "best": min(times),
        "runs": len(times),
        "peak_mb": peak,
        "base_mb": base,
        "iterations": iterations,
        **judge(forces),
    }


def measure(case: str, name: str, n: int, level: float, repeat: int, timeout: float) -> dict:
    command = [sys.executable, __file__, "--worker", case, name, str(n), str(level), str(repeat)]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"timed out after {timeout:g} s"}
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    if done.returncode != 0 or not lines:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        return {"error": f"failed: {tail}"}
    return json.loads(lines[-1])


# --- the tables ----------------------------------------------------------------------------


def _time(seconds: float) -> str:
    return f"{seconds * 1e3:.0f} ms" if seconds < 10 else f"{seconds:.1f} s"


def exponent(sizes: list[int], times: list[float]) -> float:
    return float(np.polyfit(np.log(np.square(sizes)), np.log(times), 1)[0])


def print_growth(label: str, rows: dict[int, dict]) -> None:
    """The cost growth ``k`` over the sizes of ``rows`` (grid side -> row) that ran."""
    ok = [n for n, row in rows.items() if "error" not in row]
    if len(ok) >= 2:
        k = exponent(ok, [rows[n]["best"] for n in ok])
        print(f"  {label}: k = {k:.2f} over {ok[0]}^2..{ok[-1]}^2")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", default="64,128,256,512", help="Hertz grid sides")
    parser.add_argument("--rough-sizes", default="512", help="rough-surface grid sides")
    parser.add_argument("--large", action="store_true", help="add Hertz 1024 and rough 2048")
    parser.add_argument("--repeat", type=int, default=3, help="runs per contender (best kept)")
    parser.add_argument("--timeout", type=float, default=900.0, help="s per contender and size")
    parser.add_argument(
        "--rough-loads",
        default=",".join(str(v) for v in ROUGH_LOADS),
        help="rough-surface mean pressures p / (E* h'_rms)",
    )
    parser.add_argument("--skip-rough", action="store_true")
    parser.add_argument(
        "--rough-cutoff",
        type=float,
        help="a fixed cut-off (wavelengths per period): the same rough surface at every size",
    )
    parser.add_argument("--slip-sizes", default="", help="partial-slip grid sides (off: '')")
    args = parser.parse_args()
    slip_sizes = [int(v) for v in args.slip_sizes.split(",") if v]
    if args.rough_cutoff is not None:
        os.environ["BENCH_ROUGH_CUTOFF"] = repr(args.rough_cutoff)  # read by the workers
    sizes = [int(v) for v in args.sizes.split(",") if v]
    rough_sizes = [int(v) for v in args.rough_sizes.split(",") if v]
    rough_loads = [float(v) for v in args.rough_loads.split(",") if v]
    if args.large:
        sizes += [1024] if 1024 not in sizes else []
        rough_sizes += [2048] if 2048 not in rough_sizes else []

    print("one thread everywhere (OMP/OPENBLAS_NUM_THREADS=1, FFT workers 1)")
    print(
        "Non-periodic Hertz: rigid sphere on a steel half-space, a = n/4 cells; Tamaas on a "
        "2n x 2n period (contact diameter 1/4 of it)"
    )
    print(
        f"{'cells':>9} {'contender':>16} {'first':>9} {'best':>9} {'MB':>6} {'base':>5} "
        f"{'it':>5} {'load/F':>10} {'a_mom/a':>9} {'a_area/a':>9} {'p_max/p0':>9}  tolerance"
    )
    hertz: dict[str, dict[int, dict]] = {name: {} for name in HERTZ_PEERS}
    for n in sizes:
        for name in HERTZ_PEERS:
            row = measure("hertz", name, n, 0.0, args.repeat, args.timeout)
            hertz[name][n] = row
            if "error" in row:
                print(f"{n * n:>9,} {name:>16}  skipped: {row['error']}")
                continue
            print(
                f"{n * n:>9,} {name:>16} {_time(row['first']):>9} {_time(row['best']):>9} "
                f"{row['peak_mb']:>6.0f} {row['base_mb']:>5.0f} {row['iterations']:>5} "
                f"{row['load']:>10.7f} {row['a_mom']:>9.6f} {row['a_area']:>9.6f} "
                f"{row['p_max']:>9.5f}  {row['tol']}"
            )
        own = hertz["contactqp"].get(n, {})
        peers = {k: hertz[k][n] for k in HERTZ_PEERS[1:] if "error" not in hertz[k][n]}
        if "error" not in own and peers:
            parts = []
            for k, row in peers.items():
                differs = abs(own["a_mom"] / row["a_mom"] - 1)
                parts.append(
                    f"/{k} first {own['first'] / row['first']:.2f}x best "
                    f"{own['best'] / row['best']:.2f}x, a_mom differs {differs:.1e}"
                )
            fastest = min(peers, key=lambda k: peers[k]["best"])
            parts.append(f"faster peer {fastest}")
            print(f"{'':>9} {'contactqp':>16}  " + "; ".join(parts))
    print()
    print("cost growth, time ~ N^k (best times, least squares over the sizes run):")
    for name in HERTZ_PEERS:
        print_growth(f"Hertz {name:>16}", hertz[name])
    rough: dict[str, dict[tuple[int, float], dict]] = {name: {} for name in ROUGH_PEERS}
    if not args.skip_rough:
        print()
        print(
            "Periodic rough surface (Hurst 0.8, rms slope 0.1, the same heights for both), "
            "p / (E* h'_rms) per row"
        )
        print(
            f"{'cells':>9} {'p/E*h':>6} {'contender':>10} {'first':>9} {'best':>9} {'MB':>6} "
            f"{'it':>5} {'load/P':>10} {'area':>9}  tolerance"
        )
        for n in rough_sizes:
            for level in rough_loads:
                for name in ROUGH_PEERS:
                    row = measure("rough", name, n, level, args.repeat, args.timeout)
                    rough[name][(n, level)] = row
                    if "error" in row:
                        print(f"{n * n:>9,} {level:>6} {name:>10}  skipped: {row['error']}")
                        continue
                    print(
                        f"{n * n:>9,} {level:>6} {name:>10} {_time(row['first']):>9} "
                        f"{_time(row['best']):>9} {row['peak_mb']:>6.0f} {row['iterations']:>5} "
                        f"{row['load']:>10.7f} {row['area']:>9.6f}  {row['tol']}"
                    )
                own, peer = rough["contactqp"][(n, level)], rough["tamaas"][(n, level)]
                if "error" not in own and "error" not in peer:
                    print(
                        f"{'':>9} {'':>6} {'cq/tamaas':>10} first "
                        f"{own['first'] / peer['first']:.2f}x best "
                        f"{own['best'] / peer['best']:.2f}x; area differs "
                        f"{abs(own['area'] / peer['area'] - 1):.1e}, load "
                        f"{abs(own['load'] / peer['load'] - 1):.1e}"
                    )
        if len(rough_sizes) >= 2:
            surface = (
                "cut-off n/8: a rougher surface at each size"
                if args.rough_cutoff is None
                else f"the same surface, cut-off {args.rough_cutoff:g}"
            )
            print(f"cost growth, time ~ N^k (best times; {surface}):")
            for level in rough_loads:
                for name in ROUGH_PEERS:
                    rows = {n: rough[name][(n, level)] for n in rough_sizes}
                    print_growth(f"rough {level:>6} {name:>10}", rows)
    slip: dict[str, dict[int, dict]] = {name: {} for name in SLIP_PEERS}
    if slip_sizes:
        print()
        print(
            f"Partial slip: the Hertz sphere pressed to P and sheared by Q = mu P / 2 (mu = "
            f"{SLIP_MU}, nu = {SLIP_POISSON}), both forces fixed"
        )
        print(
            f"{'cells':>9} {'contender':>10} {'first':>9} {'best':>9} {'MB':>6} {'it':>5} "
            f"{'load/P':>9} {'shear/Q':>9} {'a/a_H':>7} {'c/c_M':>7} {'natural map':>11}  "
            "tolerance"
        )
        for n in slip_sizes:
            for name in SLIP_PEERS:
                row = measure("slip", name, n, 0.0, args.repeat, args.timeout)
                slip[name][n] = row
                if "error" in row:
                    print(f"{n * n:>9,} {name:>10}  skipped: {row['error']}")
                    continue
                nm = "" if row["natural_map"] is None else f"{row['natural_map']:.1e}"
                print(
                    f"{n * n:>9,} {name:>10} {_time(row['first']):>9} {_time(row['best']):>9} "
                    f"{row['peak_mb']:>6.0f} {row['iterations']:>5} {row['load']:>9.6f} "
                    f"{row['shear']:>9.6f} {row['a']:>7.4f} {row['c']:>7.4f} {nm:>11}  "
                    f"{row['tol']}"
                )
            own, peer = slip["contactqp"][n], slip["tamaas"][n]
            if "error" not in own and "error" not in peer:
                print(
                    f"{'':>9} {'cq/tamaas':>10} first {own['first'] / peer['first']:.2f}x best "
                    f"{own['best'] / peer['best']:.2f}x"
                )
        if len(slip_sizes) >= 2:
            print("cost growth, time ~ N^k (best times):")
            for name in SLIP_PEERS:
                print_growth(f"partial slip {name:>10}", slip[name])
    print()
    print("targets:")
    for n in sizes:
        own, tam = hertz["contactqp"][n], hertz["tamaas"][n]
        if "error" not in own and "error" not in tam:
            ratio = own["best"] / tam["best"]
            met = "met" if ratio <= 1.0 else "NOT met"
            print(f"  Hertz {n}^2: contactqp <= 1.0x Tamaas: {ratio:.2f}x ({met})")
    if 1024 in sizes:
        own = hertz["contactqp"][1024]
        peers = [hertz[k][1024] for k in HERTZ_PEERS[1:] if "error" not in hertz[k][1024]]
        if "error" not in own and peers:
            best = min(row["best"] for row in peers)
            ratio = own["best"] / best
            ok = ratio <= 0.5 and own["peak_mb"] <= 1024
            print(
                f"  Hertz 1024^2: <= 0.5x the faster peer in <= 1 GB: {ratio:.2f}x, "
                f"{own['peak_mb']:.0f} MB ({'met' if ok else 'NOT met'})"
            )
    for (n, level), own in rough["contactqp"].items():
        peer = rough["tamaas"][(n, level)]
        if "error" not in own and "error" not in peer:
            ratio = own["best"] / peer["best"]
            same = abs(own["area"] / peer["area"] - 1) <= 1e-3
            ok = ratio <= 1.0 and same
            print(
                f"  rough {n}^2 p/E*h'={level}: same area to 1e-3 ({same}), "
                f"{ratio:.2f}x Tamaas ({'met' if ok else 'NOT met'})"
            )

    for n, own in slip["contactqp"].items():
        peer = slip["tamaas"][n]
        if "error" not in own and "error" not in peer:
            ratio = own["best"] / peer["best"]
            ok = ratio <= 1.0 and own["natural_map"] <= 1e-8
            print(
                f"  partial slip {n}^2: <= 1.0x Tamaas's PolonskyKeerTan at natural map 1e-8: "
                f"{ratio:.2f}x, {own['natural_map']:.1e} ({'met' if ok else 'NOT met'}; "
                f"Tamaas carries {peer['load']:.4f} P and {peer['shear']:.4f} Q)"
            )


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        _, _, case, name, n, level, repeat = sys.argv
        print(json.dumps(worker(case, name, int(n), float(level), int(repeat))))
    else:
        main()

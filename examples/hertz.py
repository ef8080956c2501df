r"""Hertz contact: a rigid sphere pressed into an elastic half-space, against Hertz's theory.
=========================================================================================

The half-space surface is cut into square cells of side ``h`` carrying uniform pressure; their
normal flexibility is Love's closed form (:func:`contactqp.compliance.normal_influence`). The
sphere (radius ``R_s``, a paraboloid near the contact) is pushed a depth ``d`` into the surface:
the gap of cell ``i`` before deformation is ``r_i^2 / (2 R_s) - d``, and the frictionless contact
problem is solved with the project's own solver in one call (:func:`contactqp.solve_gaps`).

Hertz (rigid sphere, ``E* = E / (1 - nu^2)``): contact radius ``a = sqrt(R_s d)``, load
``P = 4/3 E* sqrt(R_s) d^{3/2}``, peak pressure ``p0 = 2 E* a / (pi R_s) = 3 P / (2 pi a^2)``.

The measured contact radius is that of the disc with the closed cells' area,
``sqrt(N_closed h^2 / pi)``. The discretisation bounds the agreement: the pressure is the
mean over each cell and the contact edge falls somewhere inside a cell, so the radius is known
to about half a cell, ``h / (2 a)`` relative; load and peak pressure converge faster (both under
1 % from 8 cells per contact radius). Run ``python examples/hertz.py --help``.
"""

from __future__ import annotations

import argparse

import numpy as np

import contactqp as cq
from contactqp.compliance import grid, normal_influence


def run(
    cells_per_radius: int = 12,
    sphere_radius: float = 5e-3,
    cell: float = 1e-5,
    young: float = 210e9,
    poisson: float = 0.3,
) -> dict:
    """Solve the indentation and return the measured and theoretical values (SI units)."""
    a_theory = cells_per_radius * cell
    depth = a_theory**2 / sphere_radius
    n = 2 * cells_per_radius + 8  # the contact disc and four free cells around it
    x, y = grid(n, n, cell, cell)
    r2 = x * x + y * y
    R = normal_influence(x, y, cell, cell, young, poisson)
    result = cq.solve_gaps(R, np.zeros(n * n), r2 / (2 * sphere_radius) - depth)
    e_star = young / (1 - poisson**2)
    load_theory = 4 / 3 * e_star * np.sqrt(sphere_radius) * depth**1.5
    return {
        "success": bool(result.success),
        "cell": cell,
        "load": float(result.forces.sum()),
        "load_theory": float(load_theory),
        "radius": float(
            np.sqrt(
                np.count_nonzero(result.contact_status == cq.ContactStatus.CLOSED)
                * cell
                * cell
                / np.pi
            )
        ),
        "radius_theory": float(a_theory),
        "peak_pressure": float(result.forces.max() / cell**2),
        "peak_pressure_theory": float(2 * e_star * a_theory / (np.pi * sphere_radius)),
        "seconds": float(result.seconds),
        "cells": n * n,
    }


def main(argv=None) -> dict:
    """Command line: print the comparison with Hertz's theory and return :func:`run`'s dict."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cells", type=int, default=12, help="cells per contact radius")
    parser.add_argument("--sphere-radius", type=float, default=5e-3, help="R_s (m)")
    parser.add_argument("--young", type=float, default=210e9, help="E of the half-space (Pa)")
    parser.add_argument("--poisson", type=float, default=0.3)
    args = parser.parse_args(argv)
    if args.cells < 1 or not args.sphere_radius > 0:
        parser.error("--cells must be >= 1 and --sphere-radius > 0")
    out = run(args.cells, args.sphere_radius, young=args.young, poisson=args.poisson)
    print(
        f"rigid sphere R_s = {args.sphere_radius:g} m on E = {args.young:g} Pa, "
        f"nu = {args.poisson:g}; {out['cells']} cells of {out['cell']:g} m, "
        f"solved in {out['seconds'] * 1e3:.1f} ms (certified: {out['success']})"
    )
    print(f"{'quantity':<22}{'contactqp':>14}{'Hertz':>14}{'rel. diff.':>12}")
    for label, key, unit in [
        ("load P", "load", "N"),
        ("contact radius a", "radius", "m"),
        ("peak pressure p0", "peak_pressure", "Pa"),
    ]:
        measured, theory = out[key], out[f"{key}_theory"]
        print(
            f"{label + ' (' + unit + ')':<22}{measured:14.6g}{theory:14.6g}"
            f"{measured / theory - 1:12.2e}"
        )
    return out


if __name__ == "__main__":
    main()

r"""Flat punch: a rigid cylinder pressed into an elastic half-space, without forming W.
====================================================================================

A rigid flat-ended cylinder of radius ``a`` is pushed a depth ``d`` into the surface of an
elastic half-space (Young's modulus ``E``, Poisson's ratio ``nu``, ``E* = E / (1 - nu^2)``). The
surface is a square grid of cells of side ``h`` carrying uniform pressure, applied by FFT
(:class:`~contactqp.compliance.fft_halfspace.HalfSpaceOperator`: the flexibility is never
formed), and the problem is a :class:`~contactqp.core.surface.SurfaceProblem` at a fixed
approach: separation 0 on the punch's face (the cells whose centres lie inside it) and, outside,
more than the approach (no indenter there). :func:`contactqp.solve` runs the constrained
conjugate gradient (:mod:`contactqp.methods.constrained_cg`) and certifies the answer.

Boussinesq's solution [Johnson1985d]_: the force ``F = 2 a E* d``, the pressure
``p(r) = F / (2 pi a sqrt(a^2 - r^2))``, singular at the edge. The theory is evaluated for the
radius of the discretised face (the disc of its area). The uniform pressure of the edge cells
misses part of the singular edge load: the force converges at first order, about ``0.12 h / a``
below the theory, and the edge pressure over the centre pressure grows like ``sqrt(a / h)``.
Run ``python examples/flat_punch.py --help``.

.. [Johnson1985d] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, sec. 3.8.
"""

from __future__ import annotations

import argparse

import numpy as np

import contactqp as cq
from contactqp.compliance import grid
from contactqp.compliance.fft_halfspace import HalfSpaceOperator


def run(
    cells_per_radius: int = 32,
    cell: float = 1e-5,
    depth: float = 1e-6,
    young: float = 210e9,
    poisson: float = 0.3,
) -> dict:
    """Solve the indentation and return the measured and theoretical values (SI units)."""
    n = 4 * cells_per_radius  # the face and a radius of free surface on each side
    x, y = grid(n, n, cell, cell)
    r = np.hypot(x - x.mean(), y - y.mean())
    face = r < cells_per_radius * cell
    W = HalfSpaceOperator(n, n, cell, cell, young, poisson)
    result = cq.solve(cq.SurfaceProblem(W, np.where(face, 0.0, 10 * depth), approach=depth))
    radius = float(np.sqrt(face.sum() * cell**2 / np.pi))
    force = 2 * radius * young / (1 - poisson**2) * depth
    pressure = result.forces / cell**2
    centre = int(np.argmin(r))
    return {
        "success": bool(result.success),
        "cell": cell,
        "cells": n * n,
        "radius": radius,
        "contact_is_face": bool(np.array_equal(result.contact, face)),
        "force": result.load,
        "force_theory": float(force),
        "centre_pressure": float(pressure[centre]),
        "centre_pressure_theory": float(force / (2 * np.pi * radius**2)),
        "edge_over_centre": float(pressure.max() / pressure[centre]),
        "iterations": result.iterations,
        "seconds": result.seconds,
    }


def main(argv=None) -> dict:
    """Command line: print the comparison with Boussinesq's solution and return :func:`run`'s
    dict."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cells", type=int, default=32, help="cells per punch radius")
    parser.add_argument("--young", type=float, default=210e9, help="E of the half-space (Pa)")
    parser.add_argument("--poisson", type=float, default=0.3)
    args = parser.parse_args(argv)
    if args.cells < 2:
        parser.error("--cells must be >= 2")
    out = run(args.cells, young=args.young, poisson=args.poisson)
    print(
        f"rigid flat punch of radius {out['radius']:.4g} m on E = {args.young:g} Pa, "
        f"nu = {args.poisson:g}; {out['cells']} cells of {out['cell']:g} m, "
        f"{out['iterations']} iterations in {out['seconds']:.2f} s (certified: {out['success']})"
    )
    print(f"{'quantity':<24}{'contactqp':>14}{'Boussinesq':>14}{'rel. diff.':>12}")
    for label, key, unit in [
        ("force F", "force", "N"),
        ("centre pressure", "centre_pressure", "Pa"),
    ]:
        measured, theory = out[key], out[f"{key}_theory"]
        print(
            f"{label + ' (' + unit + ')':<24}{measured:14.6g}{theory:14.6g}"
            f"{measured / theory - 1:12.2e}"
        )
    print(
        f"edge over centre pressure {out['edge_over_centre']:.3g} "
        f"(sqrt(a / h) = {np.sqrt(out['radius'] / out['cell']):.3g}); "
        f"contact = punch face: {out['contact_is_face']}"
    )
    return out


if __name__ == "__main__":
    main()

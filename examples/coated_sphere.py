r"""A rigid sphere on a coating: an elastic layer bonded to a rigid substrate, thick to thin.
==========================================================================================

A rigid sphere (radius ``R``, a paraboloid near the contact) is pressed with the load ``P``
onto an elastic layer of thickness ``h`` bonded to a rigid base. The layer is one period of
side ``L`` of :class:`~contactqp.compliance.fft_halfspace.HalfSpaceOperator` with
``thickness=h`` (its spectral kernel is the half-space's times a closed-form factor of
``|q| h``; never a matrix); ``P`` gives Hertz's contact radius ``a_H = L / 8`` on the
half-space, so the periodic images sit four contact diameters apart.
:func:`contactqp.solve` runs the constrained conjugate gradient at the fixed load.

Two limits bound the answer:

* a thick layer (``h >> a``) is the half-space: Hertz, ``a_H = (3 P R / (4 E*))^(1/3)``,
  ``p_0 = 3 P / (2 pi a_H^2)``;
* a thin one (``h << a``) is an oedometer: each point sinks by ``p h / M`` with the
  constrained modulus ``M = E (1 - nu) / ((1 + nu)(1 - 2 nu))``, so
  ``p = M (delta - r^2 / (2 R)) / h``, the contact radius is ``sqrt(2 R delta)``, the peak
  pressure ``M delta / h`` and the load ``pi M R delta^2 / h``.

Between them the contact shrinks and the peak pressure grows as the coating thins. Run
``python examples/coated_sphere.py --help``.
"""

from __future__ import annotations

import argparse

import numpy as np

import contactqp as cq
from contactqp.compliance import HalfSpaceOperator


def run(
    thickness_over_a: float,
    cells: int = 128,
    sphere_radius: float = 1e-2,
    period: float = 1e-3,
    young: float = 70e9,
    poisson: float = 0.3,
) -> dict:
    """Press the sphere on a layer of ``thickness_over_a * a_H`` (``inf``: the half-space)
    and return the measured radius and peak pressure beside both limits (SI units)."""
    cell = period / cells
    e_star = young / (1 - poisson**2)
    modulus = young * (1 - poisson) / ((1 + poisson) * (1 - 2 * poisson))
    a_hertz = period / 8
    load = 4 * e_star * a_hertz**3 / (3 * sphere_radius)
    centres = (np.arange(cells) - (cells - 1) / 2) * cell
    x, y = np.meshgrid(centres, centres)
    thickness = None if np.isinf(thickness_over_a) else thickness_over_a * a_hertz
    W = HalfSpaceOperator(
        cells, cells, cell, cell, young, poisson, periodic=True, thickness=thickness
    )
    problem = cq.SurfaceProblem(W, ((x * x + y * y) / (2 * sphere_radius)).ravel(), load=load)
    result = cq.solve(problem)
    forces = result.forces
    radius = float(np.sqrt(np.count_nonzero(result.contact) * cell * cell / np.pi))
    out = {
        "success": bool(result.success),
        "thickness": thickness,
        "cell": cell,
        "radius": radius,
        "peak_pressure": float(forces.max() / cell**2),
        "radius_hertz": a_hertz,
        "peak_pressure_hertz": float(3 * load / (2 * np.pi * a_hertz**2)),
        "iterations": result.iterations,
        "seconds": float(result.seconds),
    }
    if thickness is not None:
        delta = np.sqrt(load * thickness / (np.pi * modulus * sphere_radius))
        out["radius_oedometer"] = float(np.sqrt(2 * sphere_radius * delta))
        out["peak_pressure_oedometer"] = float(modulus * delta / thickness)
    return out


def main(argv=None) -> list[dict]:
    """Command line: print the table over coating thicknesses and return :func:`run`'s dicts."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--thickness",
        default="inf,2,1,0.5,0.2,0.1,0.05",
        help="coating thicknesses over Hertz's contact radius, comma-separated (inf: none)",
    )
    parser.add_argument("--cells", type=int, default=128, help="cells per side of the period")
    args = parser.parse_args(argv)
    try:
        ratios = [float(value) for value in args.thickness.split(",")]
    except ValueError:
        parser.error(f"--thickness must be numbers, got {args.thickness!r}")
    if args.cells < 16 or not all(ratio > 0 for ratio in ratios):
        parser.error("--cells must be >= 16 and every --thickness > 0")
    rows = [run(ratio, args.cells) for ratio in ratios]
    print(f"{'h / a_H':>8} {'a / a_H':>9} {'p0 / p0_H':>10} {'a / a_oed':>10} {'p0 / p0_oed':>12}")
    for ratio, row in zip(ratios, rows, strict=True):
        oedometer = (
            f"{row['radius'] / row['radius_oedometer']:>10.4f} "
            f"{row['peak_pressure'] / row['peak_pressure_oedometer']:>12.4f}"
            if "radius_oedometer" in row
            else f"{'':>10} {'':>12}"
        )
        print(
            f"{ratio:>8g} {row['radius'] / row['radius_hertz']:>9.4f} "
            f"{row['peak_pressure'] / row['peak_pressure_hertz']:>10.4f} {oedometer}"
        )
    print(f"certified: {all(row['success'] for row in rows)}")
    return rows


if __name__ == "__main__":
    main()

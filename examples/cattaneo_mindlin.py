r"""Cattaneo-Mindlin: a sphere pressed on a half-space, then sheared by ``Q < mu P``.
=================================================================================

A rigid sphere (radius ``R_s``) is pushed a depth ``d`` into an elastic half-space, then moved
tangentially by ``delta`` along x with the depth kept. The surface is cut into square cells of side
``h``, each with three unknowns: the normal reaction and the two tangential ones. Their flexibility
is the half-space's (:func:`contactqp.compliance.influence_matrix`: Love, Cerruti); the contact is
solved by default through operator products (``--solver tangential-fista``): the FFT half-space
:class:`~contactqp.compliance.fft_halfspace.HalfSpaceOperator` (never formed), the normal problem
:class:`~contactqp.core.surface.SurfaceProblem` at the depth ``d``, and the shear step
:class:`~contactqp.core.sliding_surface.SlidingSurfaceProblem`, solved by
:mod:`contactqp.methods.tangential_fista`. The dense route forms ``W``
(:func:`contactqp.compliance.influence_matrix`) and solves the local problem ``u = W r + q`` of
:mod:`contactqp.core.local_problem`, one Coulomb cone per cell, by
:func:`contactqp.methods.coulomb.solve_coulomb` (``--solver coulomb``; the Tresca fixed point of
:mod:`contactqp.methods.tresca` with ``--solver tresca``, a cross-check), with

* normal: gap ``u_N = r^2 / (2 R_s) - d + sum_j R_zz r_N,j`` (a compressive reaction sinks the
  surface);
* tangential: slip of the surface against the sphere ``u_T = sum_j R_tt r_T,j - (delta, 0)``.

The ``(1 - 2 nu)`` normal-tangential coupling is neglected (``coupling=False``), as in the
classical theory (exact for elastically similar bodies, where the terms of the two bodies
cancel): the pressure is then Hertz's whatever the shear, and Mindlin's solution applies. The
shear is applied in one step from a state without tangential traction, which for this monotonic
loading is the loading path of the theory.

Theory (Johnson, *Contact Mechanics*, §7.2): the contact of radius ``a`` sticks inside the circle

.. math:: c = a \left(1 - \frac{Q}{\mu P}\right)^{1/3}

and slips in the annulus ``c < r < a``; the tangential displacement of the sphere is
``delta = 3 mu P (2 - nu) / (16 G a) [1 - (1 - Q / (mu P))^{2/3}]``. Here ``delta`` is chosen
from this formula for a target ``Q / (mu P)``; the stick radius is then compared with the theory
at the *measured* ``Q / (mu P)``, and the measured ``Q`` with the target. The stick zone is the
set of cells the solver reports as sticking; its radius is that of the disc of the same area,
known to about half a cell. Mindlin's traction is parallel to x; for ``nu > 0`` Cerruti's
``u_y`` makes the exact slip in the annulus slightly oblique (Johnson, §7.2), a small effect
the vector friction law here does resolve. Run ``python examples/cattaneo_mindlin.py --help``.
"""

from __future__ import annotations

import argparse

import numpy as np

import contactqp as cq
from contactqp.compliance import HalfSpaceOperator, grid, influence_matrix
from contactqp.core.local_problem import LocalProblem
from contactqp.core.sliding_surface import SlidingSurfaceProblem
from contactqp.core.status import ContactStatus
from contactqp.core.surface import SurfaceProblem

# through operator products; the dense exact method and its cross-check (contactqp methods)
SOLVERS = ("tangential-fista", "coulomb", "tresca")


def operator_solve(cells_per_radius, sphere_radius, cell, young, poisson, mu, delta):
    """The same step through the FFT half-space: ``(forces (k, 3) normal first, statuses, x, y,
    natural-map error, converged, seconds)``."""
    a = cells_per_radius * cell
    n = 2 * cells_per_radius + 6
    x, y = grid(n, n, cell, cell)
    normal = HalfSpaceOperator(n, n, cell, cell, young, poisson)
    full = HalfSpaceOperator(n, n, cell, cell, young, poisson, components="full", coupling=False)
    surface = SurfaceProblem(
        normal, (x * x + y * y) / (2 * sphere_radius), approach=a * a / sphere_radius
    )
    solution = cq.solve(SlidingSurfaceProblem(surface, full, mu, shift=(delta, 0.0)))
    certificate = solution.certificate
    return (
        solution.forces,
        solution.contact_status,
        x,
        y,
        certificate.natural_map,
        solution.success,
        solution.seconds,
    )


def contact_problem(cells_per_radius, sphere_radius, cell, young, poisson, mu, delta):
    """The local problem (normal first, then x and y per cell), its units and the cells' centres.

    Returns ``(problem, length, force, x, y)``: the problem is written for ``u / length`` and
    ``r / force``, with ``length`` the indentation depth and ``force`` the reaction that sinks a
    cell by ``length``, so that ``W`` and ``q`` are O(1) and the natural-map error (which adds
    norms of ``r``, ``u`` and ``q``) weighs displacements and forces alike.
    """
    a = cells_per_radius * cell
    n = 2 * cells_per_radius + 6
    x, y = grid(n, n, cell, cell)
    R = influence_matrix(x, y, cell, cell, young, poisson, coupling=False)
    # local frame per cell (N, T1, T2) = (-z, x, y): a compressive reaction presses into the
    # half-space; R is ordered (x, y, z) per cell
    order = (3 * np.arange(n * n)[:, None] + [2, 0, 1]).ravel()
    sign = np.tile([-1.0, 1.0, 1.0], n * n)
    W = R[np.ix_(order, order)] * np.outer(sign, sign)
    q = np.zeros(3 * n * n)
    q[0::3] = (x * x + y * y) / (2 * sphere_radius) - a * a / sphere_radius
    q[1::3] = -delta
    length = a * a / sphere_radius
    force = length / W[0, 0]
    problem = LocalProblem(W * (force / length), q / length, np.full(n * n, mu), 3)
    return problem, length, force, x, y


def run(
    cells_per_radius: int = 12,
    ratio: float = 0.5,
    mu: float = 0.3,
    sphere_radius: float = 5e-3,
    cell: float = 1e-5,
    young: float = 210e9,
    poisson: float = 0.3,
    solver: str = "tangential-fista",
) -> dict:
    """Solve the shear step for a target ``Q / (mu P) = ratio``; measured and theoretical values."""
    a = cells_per_radius * cell
    e_star = young / (1 - poisson**2)
    shear_modulus = young / (2 * (1 + poisson))
    load = 4 / 3 * e_star * a**3 / sphere_radius  # Hertz, d = a^2 / R_s
    delta = 3 * mu * load * (2 - poisson) / (16 * shear_modulus * a) * (1 - (1 - ratio) ** (2 / 3))
    args = (cells_per_radius, sphere_radius, cell, young, poisson, mu, delta)
    if solver == "tangential-fista":
        r, status, x, y, error, converged, seconds = operator_solve(*args)
    else:
        problem, _, force, x, y = contact_problem(*args)
        solution = cq.solve(problem, solver, tol=1e-8)
        r = force * solution.forces.reshape(-1, 3)
        status = solution.contact_status
        error, converged = solution.certificate.natural_map, solution.success
        seconds = solution.seconds
    P, Q = float(r[:, 0].sum()), float(r[:, 1].sum())
    measured_ratio = Q / (mu * P)
    stick = status == ContactStatus.STICK
    area = cell * cell / np.pi
    stick_radius = float(np.sqrt(np.count_nonzero(stick) * area))
    contact_radius = float(np.sqrt(np.count_nonzero(status != ContactStatus.OPEN) * area))
    return {
        "converged": bool(converged),
        "error": float(error),
        "seconds": float(seconds),
        "solver": solver,
        "cell": cell,
        "load": P,
        "load_hertz": float(load),
        "contact_radius": contact_radius,
        "contact_radius_hertz": float(a),
        "ratio": float(measured_ratio),
        "ratio_target": float(ratio),
        "stick_radius": stick_radius,
        "stick_radius_theory": float(a * (1 - measured_ratio) ** (1 / 3)),
        "stick_outside_theory": float(np.sqrt(x[stick] ** 2 + y[stick] ** 2).max(initial=0.0)),
        "transverse_force": float(r[:, 2].sum()),
    }


def main(argv=None) -> dict:
    """Command line: print the comparison with Mindlin's theory and return :func:`run`'s dict."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cells", type=int, default=12, help="cells per contact radius")
    parser.add_argument("--ratio", type=float, default=0.5, help="target Q / (mu P), in (0, 1)")
    parser.add_argument("--mu", type=float, default=0.3)
    parser.add_argument("--poisson", type=float, default=0.3)
    parser.add_argument("--solver", choices=SOLVERS, default=SOLVERS[0])
    args = parser.parse_args(argv)
    if args.cells < 1 or not 0 < args.ratio <= 1 or not args.mu > 0:
        parser.error("--cells must be >= 1, --ratio in (0, 1] and --mu > 0")
    out = run(args.cells, args.ratio, args.mu, poisson=args.poisson, solver=args.solver)
    print(
        f"{args.solver}: natural-map error {out['error']:.1e} in {out['seconds']:.2f} s "
        f"(converged: {out['converged']}); cell {out['cell']:g} m"
    )
    print(f"{'quantity':<26}{'contactqp':>13}{'theory':>13}{'rel. diff.':>12}")
    rows = [
        ("normal load P (N)", "load", "load_hertz"),
        ("contact radius a (m)", "contact_radius", "contact_radius_hertz"),
        ("Q / (mu P)", "ratio", "ratio_target"),
        ("stick radius c (m)", "stick_radius", "stick_radius_theory"),
    ]
    for label, key, theory in rows:
        print(f"{label:<26}{out[key]:13.6g}{out[theory]:13.6g}{out[key] / out[theory] - 1:12.2e}")
    print(f"transverse force (N): {out['transverse_force']:.3g} (theory 0)")
    return out


if __name__ == "__main__":
    main()

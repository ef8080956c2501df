r"""Cyclic shear of the spring chain with friction: a hysteresis loop against its closed form.
==========================================================================================

The chain of :mod:`contactqp.applications.springs` (``n`` bodies of mass ``m`` on a floor, springs
of stiffness ``c`` from the wall to body 1 and between neighbours, a force ``F`` on the last body)
is built here as a 2-D reduced model: each body is a node with a horizontal and a vertical freedom,
pressed on the floor (a :class:`~contactqp.PlaneObstacle`) by its weight, with Coulomb friction
``mu``. The force goes 0 -> F_max -> -F_max -> F_max ... and each step is solved from the previous
state (:func:`~contactqp.methods.history.solve_history`).

Closed form (derived for this example; ``L = mu m g``). Loaded from rest (virgin curve),

.. math:: x_i(F) = \sum_{j \le i} \max(F - (n + 1 - j) L, 0) / c .

On a reversal from ``F_max`` every body that slides has its friction force at ``+-L``; the
increment problem is then the virgin problem with the thresholds doubled, whose solution is
``2 x(dF / 2)`` (Masing's rule): the unloading branch is ``x(F_max) - 2 x((F_max - F) / 2)``, the
reloading branch from ``-F_max`` its mirror, and the loop closes after the first reversal. Body
``i`` slides ``2 x_i(F_max)`` each way, so the energy dissipated per cycle is

.. math:: E = 4 L \sum_i x_i(F_max),

for one body ``E = 4 mu N (F_max - mu N) / c``. Run ``python examples/cyclic_shear.py --help``.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

import contactqp as cq
from contactqp.applications.springs import chain_flexibility
from contactqp.core.history import linear_path
from contactqp.methods import solve_history


def chain_problem(n: int, stiffness: float, mu: float, normal_stiffness: float = 1.0):
    """The chain as a 2-D reduced model on a floor: a :class:`FrictionalProblem` without load.

    Freedoms per body: (horizontal, vertical). The horizontal block is the chain's stiffness,
    the vertical one ``normal_stiffness`` per body (it does not change the contact forces, which
    equal the weights).
    """
    K = np.zeros((2 * n, 2 * n))
    K[0::2, 0::2] = np.linalg.inv(chain_flexibility(n, stiffness))
    K[1::2, 1::2] = normal_stiffness * np.eye(n)
    model = cq.ReducedModel(
        stiffness=K, dofs_per_node=2, coordinates=np.column_stack([np.arange(n), np.zeros(n)])
    )
    floor = cq.PlaneObstacle(point=[0.0, 0.0], normal=[0.0, -1.0])
    return cq.FrictionalProblem(model, np.zeros(2 * n), [floor], mu=mu)


def cycle_path(n: int, weight: float, force_max: float, cycles: int, steps: int) -> np.ndarray:
    """Loads (K, 2n): weights on the vertical freedoms, 0 -> F_max -> -F_max -> ... -> F_max."""
    turning = [0.0] + [force_max, -force_max] * cycles + [force_max]
    points = np.zeros((len(turning), 2 * n))
    points[:, 1::2] = -weight
    points[:, -2] = turning
    return linear_path(points, steps)


def virgin(n: int, stiffness: float, limit: float, force) -> np.ndarray:
    """Displacements (m) of the bodies loaded from rest to ``force``: shape (..., n)."""
    j = np.arange(1, n + 1)
    return np.cumsum(
        np.maximum(np.asarray(force)[..., None] - (n + 1 - j) * limit, 0.0) / stiffness, axis=-1
    )


def masing(
    n: int, stiffness: float, limit: float, force_max: float, forces: np.ndarray, steps: int
) -> np.ndarray:
    """Closed-form displacements (K, n) along :func:`cycle_path` (Masing's rule)."""
    x_max = virgin(n, stiffness, limit, force_max)
    segment = np.maximum(np.arange(len(forces)) - 1, 0) // steps  # step 0 belongs to segment 0
    down = x_max - 2.0 * virgin(n, stiffness, limit, (force_max - forces) / 2.0)
    up = -x_max + 2.0 * virgin(n, stiffness, limit, (forces + force_max) / 2.0)
    x = np.where((segment % 2 == 1)[:, None], down, up)
    return np.where((segment == 0)[:, None], virgin(n, stiffness, limit, forces), x)


def run(
    n: int = 3,
    stiffness: float = 1.0,
    mu: float = 0.2,
    mass: float = 2.0,
    g: float = 10.0,
    force_max: float = 14.0,
    cycles: int = 2,
    steps: int = 14,
    solver: str | None = None,
):
    """Solve the cycle; return the history, the closed form and the energies per cycle."""
    weight = mass * g
    limit = mu * weight
    problem = chain_problem(n, stiffness, mu)
    loads = cycle_path(n, weight, force_max, cycles, steps)
    history = solve_history(problem, loads, solver)
    forces = loads[:, -2]
    exact = masing(n, stiffness, limit, force_max, forces, steps)
    per_cycle = history.dissipated[1 + steps :].reshape(cycles, 2 * steps).sum(axis=1)
    return {
        "history": history,
        "force": forces,
        "x": history.displacements[:, 0::2],
        "exact": exact,
        "dissipated_per_cycle": per_cycle,
        "closed_form_per_cycle": 4.0
        * limit
        * float(np.sum(virgin(n, stiffness, limit, force_max))),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, default=3, help="bodies in the chain")
    parser.add_argument("--stiffness", type=float, default=1.0, help="spring stiffness c (N/m)")
    parser.add_argument("--mu", type=float, default=0.2, help="friction coefficient")
    parser.add_argument("--mass", type=float, default=2.0, help="mass of each body (kg)")
    parser.add_argument("--g", type=float, default=10.0, help="gravity (m/s^2)")
    parser.add_argument("--force-max", type=float, default=14.0, help="force amplitude (N)")
    parser.add_argument("--cycles", type=int, default=2)
    parser.add_argument("--steps", type=int, default=14, help="load steps per half cycle")
    parser.add_argument("--solver", choices=["coulomb", "tresca"], default=None)
    parser.add_argument("--plot", metavar="PNG", help="save the loop F - x_n to this file")
    args = parser.parse_args(argv)
    out = run(
        args.n,
        args.stiffness,
        args.mu,
        args.mass,
        args.g,
        args.force_max,
        args.cycles,
        args.steps,
        args.solver,
    )
    history = out["history"]
    print(
        f"{'step':>4} {'F (N)':>9} {'x_n (m)':>11} {'closed form':>11}  "
        "status (o open, s stick, S slip; body 1 first)"
    )
    for k, step in enumerate(history):
        status = "".join("osS"[code] for code in step.contact_status)
        print(
            f"{k:4d} {out['force'][k]:9.3f} {out['x'][k, -1]:11.6f} {out['exact'][k, -1]:11.6f}"
            f"  {status}"
        )
    error = np.max(np.abs(out["x"] - out["exact"]))
    print(f"largest deviation from the closed form: {error:.2e} m")
    for c, energy in enumerate(out["dissipated_per_cycle"], start=1):
        print(
            f"cycle {c}: dissipated {energy:.6f} J (closed form "
            f"{out['closed_form_per_cycle']:.6f} J)"
        )
    print(f"all steps certified: {history.success}")
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 4))
        ax.plot(out["x"][:, -1], out["force"], "o", ms=3, label="contactqp, step by step")
        ax.plot(out["exact"][:, -1], out["force"], "-", lw=1, label="closed form (Masing)")
        ax.set_xlabel("displacement of the last body (m)")
        ax.set_ylabel("force F (N)")
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
        print(f"loop saved to {args.plot}")
    return 0 if history.success else 1


if __name__ == "__main__":
    status = main()
    if status:  # exit 0 by returning (the docs gallery runs this file in its own process)
        sys.exit(status)

"""Hard rigid multibody local problems for the tests: a wall of rigid boxes.

A wall of ``nx`` by ``nz`` rigid boxes (3-D, 6 freedoms each) stands on a fixed ground. Each box
touches the box below it (or the ground) and its side neighbours through ``points`` contact
points per face (the corners of the shared face, moved a little at random), each with its own
frame (the face normal tilted at random by up to ``tilt`` radians). With
``M`` the block-diagonal mass/inertia matrix and ``H`` the map from body velocities to contact
relative velocities, the Delassus operator is ``W = H M^-1 H^T`` (the FCLIB ``H^T M^-1 H`` with
``H`` of FCLIB's shape), of rank at most ``6 nx nz``, far below ``m = 3 n_contacts``. The free
velocity ``q = H (v0 + h M^-1 f)`` comes from gravity over a step ``h`` and a random initial
velocity ``v0`` pushing the wall down and sideways; ``mu`` is drawn in [0.7, 1].

This is the kind of problem (many contacts per body pair, many at the cone tip, large friction)
on which the default route's Newton stages stall (issue 15, section 4).
"""

from __future__ import annotations

import numpy as np

from contactqp.core.local_problem import LocalProblem

__all__ = ["box_wall"]


def _frame(normal: np.ndarray) -> np.ndarray:
    """Rows (n, t1, t2): an orthonormal frame whose first row is ``normal``."""
    n = normal / np.linalg.norm(normal)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = np.cross(n, helper)
    t1 /= np.linalg.norm(t1)
    return np.vstack([n, t1, np.cross(n, t1)])


def _rotate(v: np.ndarray, rng: np.random.Generator, angle: float) -> np.ndarray:
    """``v`` turned by a random angle up to ``angle`` about a random axis (Rodrigues)."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    a = rng.uniform(0.0, angle)
    return v * np.cos(a) + np.cross(axis, v) * np.sin(a) + axis * (axis @ v) * (1.0 - np.cos(a))


def box_wall(
    nx: int = 4,
    nz: int = 4,
    *,
    points: int = 4,
    seed: int = 0,
    tilt: float = 0.05,
    step: float = 1e-2,
) -> LocalProblem:
    """A local problem of a wall of ``nx`` x ``nz`` unit boxes on a fixed ground (see module).

    Returns
    -------
    LocalProblem
        3-D, ``n_contacts = points * (nx * nz + (nx - 1) * nz)``, ``W`` dense and O(1).
    """
    rng = np.random.default_rng(seed)
    size = np.array([1.0, 1.0, 1.0])  # box edges (x, y, z)
    mass = 1.0
    inertia = (
        mass
        / 12.0
        * np.array(
            [size[1] ** 2 + size[2] ** 2, size[0] ** 2 + size[2] ** 2, size[0] ** 2 + size[1] ** 2]
        )
    )
    nb = nx * nz
    centre = np.array(
        [[i * size[0], 0.0, (k + 0.5) * size[2]] for k in range(nz) for i in range(nx)]
    )

    def body(i, k):
        return k * nx + i

    # contacts: (body a, body b or -1 for ground, point, normal from b towards a)
    contacts = []
    corners = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    for k in range(nz):
        for i in range(nx):
            a = body(i, k)
            below = body(i, k - 1) if k else -1
            for p in range(points):
                c = corners[p % 4] * 0.9 * (1.0 - 0.3 * (p // 4)) + rng.uniform(-0.02, 0.02, 2)
                x = centre[a] + np.array([c[0] * size[0], c[1] * size[1], -0.5 * size[2]])
                contacts.append((a, below, x, np.array([0.0, 0.0, 1.0])))
            if i + 1 < nx:
                b = body(i + 1, k)  # right neighbour: normal from b towards a is -x
                for p in range(points):
                    c = corners[p % 4] * 0.9 * (1.0 - 0.3 * (p // 4)) + rng.uniform(-0.02, 0.02, 2)
                    x = centre[a] + np.array([0.5 * size[0], c[0] * size[1], c[1] * size[2]])
                    contacts.append((a, b, x, np.array([-1.0, 0.0, 0.0])))
    nc = len(contacts)
    H = np.zeros((3 * nc, 6 * nb))  # u = H v, v = (velocity, angular velocity) per body
    for c, (a, b, x, normal) in enumerate(contacts):
        frame = _frame(_rotate(normal, rng, tilt))
        for sign, j in ((1.0, a), (-1.0, b)):
            if j < 0:
                continue
            arm = x - centre[j]
            cross = np.array(
                [[0.0, arm[2], -arm[1]], [-arm[2], 0.0, arm[0]], [arm[1], -arm[0], 0.0]]
            )
            # velocity of the material point: v + w x arm = v - [arm]x w = v + cross @ w
            H[3 * c : 3 * c + 3, 6 * j : 6 * j + 3] += sign * frame
            H[3 * c : 3 * c + 3, 6 * j + 3 : 6 * j + 6] += sign * frame @ cross
    inverse_mass = np.tile(np.concatenate([np.full(3, 1.0 / mass), 1.0 / inertia]), nb)
    W = (H * inverse_mass) @ H.T
    W = 0.5 * (W + W.T)
    v0 = np.zeros((nb, 6))
    v0[:, 0] = rng.uniform(-0.5, 0.5, nb)  # sideways
    v0[:, 2] = rng.uniform(-1.0, 0.0, nb)  # down
    v0[:, 3:] = rng.uniform(-0.3, 0.3, (nb, 3))
    force = np.zeros((nb, 6))
    force[:, 2] = -9.81 * mass
    v_free = v0.reshape(-1) + step * inverse_mass * force.reshape(-1)
    q = H @ v_free
    mu = rng.uniform(0.7, 1.0, nc)
    return LocalProblem(W, q, mu, 3, title=f"box wall {nx}x{nz}, {points} points per face")

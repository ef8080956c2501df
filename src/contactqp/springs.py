"""The spring chain with friction, the method's first application.

``N`` bodies of mass ``m`` rest on a floor with friction coefficient ``mu``; spring 1 links body 1
to a wall, spring ``i`` links bodies ``i-1`` and ``i``, all of stiffness ``c``; a horizontal force
``F`` pulls the last body. Loaded monotonically from rest, the displacements ``X`` minimise the
elastic energy ``c/2 X^T K X`` subject to every body's friction bound:

.. math::

    -\\mu m g \\le (F e_N - c K X)_i \\le \\mu m g, \\qquad i = 1..N,

``K`` being the chain's tridiagonal stiffness for ``c = 1``. With the friction forces ``f`` as
unknowns (``X = R (F e_N - f)``, ``R = (cK)^{-1}``, ``R_ij = min(i, j) / c``) this is the box QP

.. math::

    \\min_f \\tfrac12 f^T R f - f^T R F e_N, \\qquad -\\mu m g \\le f \\le \\mu m g,

solved by the project's own active-set solver.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InvalidInputError
from .solvers.box_qp import solve_box_qp

__all__ = ["SpringChain", "SpringChainResult", "chain_flexibility"]


def chain_flexibility(n: int, stiffness: float) -> np.ndarray:
    """Flexibility of a chain of ``n`` springs fixed to a wall: ``R_ij = min(i, j) / c`` (m/N)."""
    index = np.arange(1, n + 1)
    return np.minimum.outer(index, index) / stiffness


@dataclass(frozen=True)
class SpringChainResult:
    """Equilibrium of the chain under one pulling force.

    Attributes
    ----------
    force : float
        The pulling force ``F`` (N).
    x : ndarray, shape (N,)
        Displacements of the bodies (m).
    friction : ndarray, shape (N,)
        Friction force on each body, opposing the pull (N).
    sliding : ndarray of bool, shape (N,)
        True where friction is at its limit ``mu m g``.
    converged : bool
    iterations : int
    message : str
    """

    force: float
    x: np.ndarray
    friction: np.ndarray
    sliding: np.ndarray
    converged: bool
    iterations: int
    message: str


@dataclass(frozen=True)
class SpringChain:
    """A chain of ``n`` bodies linked by springs, on a floor with Coulomb friction.

    Parameters
    ----------
    n : int
        Number of bodies (>= 1).
    stiffness : float
        Spring stiffness ``c`` (N/m, > 0).
    mu : float
        Friction coefficient (>= 0).
    mass : float
        Mass of each body (kg, > 0).
    g : float
        Gravity (m/s^2, > 0).
    """

    n: int
    stiffness: float
    mu: float
    mass: float
    g: float = 9.81

    def __post_init__(self):
        if int(self.n) != self.n or self.n < 1:
            raise InvalidInputError(f"n must be a whole number >= 1, got {self.n}")
        for name in ("stiffness", "mass", "g"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise InvalidInputError(f"{name} must be finite and > 0, got {value}")
        if not (np.isfinite(self.mu) and self.mu >= 0):
            raise InvalidInputError(f"mu must be finite and >= 0, got {self.mu}")

    @property
    def friction_limit(self) -> float:
        """Largest friction force on one body, ``mu m g`` (N)."""
        return self.mu * self.mass * self.g

    def solve(self, force: float, tol: float = 1e-12) -> SpringChainResult:
        """Equilibrium under the pulling force ``force`` (N) applied from rest."""
        if not np.isfinite(force):
            raise InvalidInputError(f"force must be finite, got {force}")
        n = int(self.n)
        R = chain_flexibility(n, self.stiffness)
        pull = np.zeros(n)
        pull[-1] = force
        limit = self.friction_limit
        solution = solve_box_qp(R, -(R @ pull), lower=-limit, upper=limit, tol=tol)
        friction = solution.x
        x = R @ (pull - friction)
        sliding = np.abs(friction) >= limit * (1 - 1e-12) if limit > 0 else np.ones(n, bool)
        return SpringChainResult(force=float(force), x=x, friction=friction, sliding=sliding,
                                 converged=solution.converged, iterations=solution.iterations,
                                 message=solution.message)

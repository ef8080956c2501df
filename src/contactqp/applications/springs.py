"""The spring chain with friction, the method's first application.

``N`` bodies of mass ``m`` rest on a floor with friction coefficient ``mu``; spring 1 links body 1
to a wall, spring ``i`` links bodies ``i-1`` and ``i``, all of stiffness ``c``; a horizontal force
``F`` pulls the last body. Loaded monotonically from rest, the displacements ``X`` minimise the
elastic energy ``c/2 X^T K X`` subject to every body's friction bound:

.. math::

    -\\mu m g \\le (F e_N - c K X)_i \\le \\mu m g, \\qquad i = 1..N,

``K`` being the chain's tridiagonal stiffness for ``c = 1`` (:func:`chain_stiffness`). With the
friction forces ``f`` as unknowns (``X = R (F e_N - f)``, ``R = (cK)^{-1}``,
``R_ij = min(i, j) / c``) this is the box QP

.. math::

    \\min_f \\tfrac12 f^T R f - f^T R F e_N, \\qquad -\\mu m g \\le f \\le \\mu m g,

which :func:`~contactqp.methods.box_qp.solve_box_qp` solves on the dense ``R``. Here ``R`` is
never formed (it would take ``8 N^2`` bytes): in the spring tensions
``s_i = c (X_i - X_{i-1})``, ``(f - F e_N)^T R (f - F e_N) = |s|^2 / c`` and the box QP
reads ``min |s|^2`` with ``s_i - s_{i+1} = p_i - f_i`` (equilibrium of body ``i``, ``p`` the
loads), ``s_{N+1} = 0``. Every body but the last is
unloaded (``p_i = 0``), so each ``s_i`` may be anywhere within ``mu m g`` of ``s_{i+1}``, and
taking it as close to 0 as it can be is optimal for every later one too: the chain is solved
exactly, body by body from the loaded end, ``s_i = shrink(s_{i+1} + p_i, mu m g)``, in
``O(N)``. The answer is then checked on the sparse stiffness (equilibrium, friction bounds,
sliding bodies at the bound), which is what ``converged`` reports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse

from ..errors import InvalidInputError

__all__ = ["SpringChain", "SpringChainResult", "chain_flexibility", "chain_stiffness"]


def chain_flexibility(n: int, stiffness: float) -> np.ndarray:
    """Flexibility of a chain of ``n`` springs fixed to a wall: ``R_ij = min(i, j) / c`` (m/N).

    Dense, ``8 n^2`` bytes: for small chains and checks; :class:`SpringChain` does not use it.
    """
    index = np.arange(1, n + 1)
    return np.minimum.outer(index, index) / stiffness


def chain_stiffness(n: int, stiffness: float) -> scipy.sparse.csr_matrix:
    """Stiffness ``c K`` of the chain fixed to a wall (N/m), sparse tridiagonal, ``(n, n)``."""
    diagonal = np.full(n, 2.0 * stiffness)
    diagonal[-1] = stiffness
    off = np.full(n - 1, -float(stiffness))
    return scipy.sparse.diags([off, diagonal, off], [-1, 0, 1], format="csr")


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
        """Equilibrium under the pulling force ``force`` (N) applied from rest.

        ``tol`` bounds the relative residuals of the check (equilibrium, friction bounds):
        ``converged`` is False, with the worst one in ``message``, when one exceeds it.
        """
        if not np.isfinite(force):
            raise InvalidInputError(f"force must be finite, got {force}")
        n = int(self.n)
        limit = self.friction_limit
        pull = np.zeros(n)
        pull[-1] = force
        carried = [0.0] * n  # carried[i]: spring i + 1, between body i and the one before
        after = 0.0
        for i, load in zip(range(n - 1, -1, -1), pull[::-1].tolist(), strict=True):
            free = after + load  # what spring i + 1 carries if body i has no friction
            after = carried[i] = math.copysign(max(abs(free) - limit, 0.0), free)
        tension = np.array(carried)
        friction = np.empty(n)
        friction[:-1] = tension[1:] - tension[:-1]
        friction[-1] = force - tension[-1]
        with np.errstate(all="ignore"):  # overflow is reported below
            x = np.cumsum(tension) / self.stiffness
            residual = self._residual(x, friction, pull, x != 0)
        sliding = np.abs(friction) >= limit * (1 - 1e-12) if limit > 0 else np.ones(n, bool)
        converged = residual <= tol
        if not np.all(np.isfinite(x)):
            message = "the displacements overflow (beyond 1e308 m)"
        else:
            message = (
                f"solved body by body from the loaded end; worst relative residual "
                f"{residual:.1e}" + ("" if converged else f" above tol = {tol:g}")
            )
        return SpringChainResult(
            force=float(force),
            x=x,
            friction=friction,
            sliding=sliding,
            converged=converged,
            iterations=1,
            message=message,
        )

    def _residual(self, x, friction, pull, moving) -> float:
        """Worst of the equilibrium ``c K x = pull - friction`` (on the sparse stiffness), the
        friction bounds and the law of the bodies that move, relative to the largest force in
        these equations (a spring force ``c x`` included)."""
        limit = self.friction_limit
        scale = max(
            abs(pull[-1]), limit, self.stiffness * float(np.max(np.abs(x))), np.finfo(float).tiny
        )
        equilibrium = chain_stiffness(len(x), self.stiffness) @ x - (pull - friction)
        bound = np.maximum(np.abs(friction) - limit, 0.0)
        law = np.abs(friction[moving] - limit * np.sign(x[moving]))
        return (
            float(max(np.max(np.abs(equilibrium)), np.max(bound), np.max(law, initial=0.0))) / scale
        )

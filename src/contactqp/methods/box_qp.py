"""The project's own solver for convex quadratic programs with bounds.

.. math::

    \\min_x \\tfrac12 x^T W x + c^T x \\quad \\text{s.t.}\\quad l \\le x \\le u

with ``W`` symmetric positive (semi)definite. This is the dual of frictionless contact
(``x`` the contact forces, ``l = 0``, ``u = +inf``) and of the spring chain with friction
(``-mu m g <= x <= mu m g``).

Method: primal-dual active set, i.e. semismooth Newton on ``x = P_[l,u](x - sigma (W x + c))``
[HIK2002]_. Each iteration fixes the bounded variables and solves the free block through
:class:`~contactqp.methods.free_block.FreeBlockSolver`, which borders or trims one LAPACK
Cholesky factor instead of factoring every new free set. The plain iteration converges in a few
steps on contact problems but may cycle on general ``W`` (it does on the spring chain); a step
that does not lower the objective is therefore replaced by the best point of a projected search
along the Newton direction, so the objective decreases monotonically. Should no step decrease it,
Bertsekas' projected Newton method with an Armijo search along the projection arc [Ber1982]_
takes over; it converges globally.

References
----------
.. [HIK2002] M. Hintermüller, K. Ito, K. Kunisch, "The primal-dual active set strategy as a
   semismooth Newton method", SIAM J. Optim. 13(3), 2002.
.. [Ber1982] D. P. Bertsekas, "Projected Newton methods for optimization problems with simple
   constraints", SIAM J. Control Optim. 20(2), 1982.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.model import iteration_cap, positive_tolerance
from ..core.operators import DenseOperator, as_operator
from ..errors import InvalidInputError
from .free_block import FreeBlockSolver

__all__ = ["BoxQPSolution", "solve_box_qp"]

AT_LOWER, FREE, AT_UPPER = -1, 0, 1
_SHORTER_STEPS = 0.5 ** np.arange(1, 12)  # tried when the full active-set step fails


@dataclass(frozen=True)
class BoxQPSolution:
    """Outcome of :func:`solve_box_qp`.

    Attributes
    ----------
    x : ndarray, shape (n,)
        The minimiser, inside the bounds.
    gradient : ndarray, shape (n,)
        ``W x + c`` (the dual variables: >= 0 at a lower bound, <= 0 at an upper one).
    state : ndarray of int, shape (n,)
        -1 at the lower bound, +1 at the upper bound, 0 free.
    converged : bool
    iterations : int
        Newton iterations of both phases.
    factorizations : int
        Cholesky factorisations of free blocks.
    updates : int
        Free blocks solved by updating a factorisation instead (see
        :class:`~contactqp.methods.free_block.FreeBlockSolver`).
    residual : float
        ``max|x - P(x - sigma g)|`` relative to the scale of ``x``, at the returned point.
    message : str
    """

    x: np.ndarray
    gradient: np.ndarray
    state: np.ndarray
    converged: bool
    iterations: int
    factorizations: int
    updates: int
    residual: float
    message: str


def _validated(W, c, lower, upper, x0, check_finite):
    W = as_operator(W)
    c = np.asarray(c, dtype=float).reshape(-1)
    n = c.size
    if W.shape != (n, n):
        raise InvalidInputError(f"W must have shape ({n}, {n}) to match c, got {W.shape}")
    entries = W.matrix if isinstance(W, DenseOperator) else W.diagonal()
    if not (np.all(np.isfinite(c)) and (not check_finite or np.all(np.isfinite(entries)))):
        raise InvalidInputError("W or c contains NaN or inf")
    lower = (
        np.full(n, -np.inf)
        if lower is None
        else np.broadcast_to(np.asarray(lower, dtype=float), (n,)).copy()
    )
    upper = (
        np.full(n, np.inf)
        if upper is None
        else np.broadcast_to(np.asarray(upper, dtype=float), (n,)).copy()
    )
    if np.any(np.isnan(lower)) or np.any(np.isnan(upper)) or np.any(lower > upper):
        raise InvalidInputError("bounds must satisfy lower <= upper with no NaN")
    if x0 is not None:
        x0 = np.asarray(x0, dtype=float).reshape(-1)
        if x0.shape != (n,) or not np.all(np.isfinite(x0)):
            raise InvalidInputError(f"x0 must hold {n} finite values, got shape {x0.shape}")
    return W, c, lower, upper, x0


class _BoxQP:
    """The problem data and the operations both phases share."""

    def __init__(self, W, c, lower, upper, tol):
        self.W, self.c, self.lower, self.upper = W, c, lower, upper
        diagonal = W.diagonal()
        positive = diagonal[diagonal > 0]
        self.sigma = 1.0 / float(np.mean(positive)) if positive.size else 1.0
        self.tol = tol
        self.blocks = FreeBlockSolver(W)
        bounds = np.concatenate([lower[np.isfinite(lower)], upper[np.isfinite(upper)]])
        self.x_scale = max(
            self.sigma * float(np.max(np.abs(c), initial=0.0)),
            float(np.max(np.abs(bounds), initial=0.0)),
        )

    def gradient(self, x):
        return self.W @ x + self.c

    def decrease(self, x, g, step):
        """``f(x) - f(x + step)`` for the gradient ``g`` at ``x``, as
        ``-(g^T s + 1/2 s^T W s)``: its rounding error scales with the step, not with ``f``, so
        it keeps its sign near the minimiser, where the difference of two objective values is
        lost to cancellation."""
        return -float(step @ (g + 0.5 * (self.W @ step)))

    def project(self, x):
        return np.clip(x, self.lower, self.upper)

    def residual(self, x, g):
        """Natural residual ``max|x - P(x - sigma g)|`` relative to the scale of the solution."""
        scale = max(self.x_scale, float(np.max(np.abs(x), initial=0.0)), np.finfo(float).tiny)
        return float(np.max(np.abs(x - self.project(x - self.sigma * g)), initial=0.0)) / scale

    def state(self, x, g):
        trial = x - self.sigma * g
        state = np.zeros(x.size, dtype=np.int8)
        state[trial < self.lower] = AT_LOWER
        state[trial > self.upper] = AT_UPPER
        return state

    def newton_point(self, state):
        """Bounded variables at their bound, free ones solving ``W_FF x_F = -(c_F + W_FB x_B)``."""
        x = np.where(state == AT_LOWER, self.lower, np.where(state == AT_UPPER, self.upper, 0.0))
        free = state == FREE
        if free.any():
            rhs = -self.c[free]
            loaded = np.flatnonzero(x)  # bounded variables away from zero couple into the block
            if loaded.size:
                rhs -= self.W.block(free, loaded) @ x[loaded]
            x[free] = self.blocks.solve(free, rhs)
        return x


def _active_set_phase(qp: _BoxQP, x, max_iter):
    """Primal-dual active set iterations made monotone by a search along the projected path.

    The projected Newton point of the current active set is tried first (the plain primal-dual
    active set step, so nothing is lost where that converges). If it does not lower the objective,
    the best of the projected points ``P(x + alpha d)``, ``alpha = 1/2, ..., 2^-11`` (evaluated
    together in one matrix product) is taken if it does; so the objective decreases at every step
    and no active set can cycle.
    """
    x = qp.project(x)
    g = qp.gradient(x)
    f = float(0.5 * x @ (g + qp.c))
    for iteration in range(1, max_iter + 1):
        if qp.residual(x, g) <= qp.tol:
            return x, g, iteration - 1, True, "active set converged"
        newton = qp.newton_point(qp.state(x, g))
        full_step = qp.project(newton)
        product = qp.W @ full_step
        value = float(full_step @ (0.5 * product + qp.c))
        if value < f:
            x, g, f = full_step, product + qp.c, value
            continue
        direction = newton - x
        trials = np.clip(
            x[:, None] + direction[:, None] * _SHORTER_STEPS[None, :],
            qp.lower[:, None],
            qp.upper[:, None],
        )
        products = qp.W @ trials
        values = np.einsum("ij,ij->j", trials, 0.5 * products + qp.c[:, None])
        best = int(np.argmin(values))
        if not values[best] < f:
            return x, g, iteration, False, "active set step gave no decrease"
        x, g, f = trials[:, best], products[:, best] + qp.c, float(values[best])
    converged = qp.residual(x, g) <= qp.tol
    return (
        x,
        g,
        max_iter,
        converged,
        ("active set converged" if converged else "active set iteration limit"),
    )


def _projected_newton_phase(qp: _BoxQP, x, max_iter):
    """Bertsekas' projected Newton method with an Armijo search along the projection arc."""
    x = qp.project(x)
    for iteration in range(1, max_iter + 1):
        g = qp.gradient(x)
        step = x - qp.project(x - qp.sigma * g)
        if qp.residual(x, g) <= qp.tol:
            return x, g, iteration - 1, True, "projected Newton converged"
        epsilon = min(float(np.max(np.abs(step))), 1e-3 * max(qp.x_scale, 1e-300))
        binding = ((x <= qp.lower + epsilon) & (g > 0)) | ((x >= qp.upper - epsilon) & (g < 0))
        free = ~binding
        direction = -qp.sigma * g
        if free.any():
            direction[free] = -qp.blocks.solve(free, g[free])
        alpha = 1.0
        while True:
            trial = qp.project(x + alpha * direction)
            expected = alpha * -(g[free] @ direction[free]) + g[binding] @ (
                x[binding] - trial[binding]
            )
            if qp.decrease(x, g, trial - x) >= 1e-4 * expected:
                break
            alpha *= 0.5
            if alpha < 1e-14:
                return x, g, iteration, False, "projected Newton line search stalled"
        x = trial
    g = qp.gradient(x)
    converged = qp.residual(x, g) <= qp.tol
    return (
        x,
        g,
        max_iter,
        converged,
        ("projected Newton converged" if converged else "iteration limit reached"),
    )


def solve_box_qp(
    W,
    c,
    lower=None,
    upper=None,
    x0=None,
    *,
    tol: float = 1e-10,
    max_iter: int = 500,
    check_finite: bool = True,
) -> BoxQPSolution:
    """Minimise ``1/2 x^T W x + c^T x`` subject to ``lower <= x <= upper``.

    Parameters
    ----------
    W : array_like, shape (n, n), or Operator
        Symmetric positive (semi)definite. Reached through
        :func:`~contactqp.core.operators.as_operator` (products, diagonal, blocks and Cholesky
        factors of free blocks), so any :class:`~contactqp.core.operators.Operator` will do.
    c : array_like, shape (n,)
    lower, upper : array_like, shape (n,) or scalar, optional
        Bounds; ``-inf``/``+inf`` (the defaults) for none.
    x0 : array_like, shape (n,), optional
        Warm start; the initial active set is read from it.
    tol : float
        Stop when the natural residual ``max|x - P(x - sigma (W x + c))|`` is below ``tol`` times
        the scale of the solution (``sigma`` is the inverse mean diagonal of ``W``).
    max_iter : int
        Newton iterations allowed in both phases together.
    check_finite : bool
        Check ``W`` for NaN and inf (a full pass over a dense ``W``, the diagonal of any other
        operator); callers whose ``W`` is built from a validated model may skip it.

    Returns
    -------
    BoxQPSolution
        ``converged`` is False, with the reason in ``message``, when neither phase reached ``tol``.

    Raises
    ------
    InvalidInputError
        On inconsistent shapes, non-finite data or bounds ``lower > upper``.
    NotPositiveDefiniteError
        If a free block the method factors is not positive semidefinite (to rounding,
        :meth:`~contactqp.core.operators.Operator.cholesky`).
    """
    tol, max_iter = positive_tolerance(tol), iteration_cap(max_iter)
    W, c, lower, upper, x0 = _validated(W, c, lower, upper, x0, check_finite)
    qp = _BoxQP(W, c, lower, upper, tol)
    start = np.zeros(c.size) if x0 is None else x0
    x, g, iterations, converged, message = _active_set_phase(qp, start, max_iter)
    if not converged and iterations < max_iter:
        x, g, more, converged, message = _projected_newton_phase(qp, x, max_iter - iterations)
        iterations += more
        message = f"active set did not settle; {message}"
    state = np.where(x <= lower, AT_LOWER, np.where(x >= upper, AT_UPPER, FREE)).astype(np.int8)
    return BoxQPSolution(
        x=x,
        gradient=g,
        state=state,
        converged=converged,
        iterations=iterations,
        factorizations=qp.blocks.factorizations,
        updates=qp.blocks.updates,
        residual=qp.residual(x, g),
        message=message,
    )

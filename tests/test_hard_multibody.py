"""The hard multibody generator (tests/multibody_problems.py) and the proximal-point loop.

Truths: the generator's W = H M^-1 H^T is symmetric positive semidefinite of rank at most
6 bodies, far below m; the proximal loop's answer is certified by the natural-map error of
the problem as given (computed independently by :func:`natural_map_error`) and agrees with
the default route also converging there (answers are not compared: not unique).
"""

from __future__ import annotations

import numpy as np
import pytest

from contactqp.core.local_problem import natural_map_error, natural_map_residual
from contactqp.methods.coulomb import _Newton, solve_coulomb
from contactqp.methods.proximal import proximal_point
from multibody_problems import box_wall


def test_generator_is_singular_multibody():
    problem = box_wall(3, 3, points=4, seed=0)
    W = problem.W
    m = W.shape[0]
    assert m == 3 * 4 * (9 + 6)
    np.testing.assert_allclose(W, W.T, atol=1e-14)
    eigenvalues = np.linalg.eigvalsh(W)
    assert eigenvalues.min() > -1e-10 * eigenvalues.max()
    assert np.linalg.matrix_rank(W) <= 6 * 9 < m // 3
    assert np.all((problem.mu >= 0.7) & (problem.mu <= 1.0))


@pytest.mark.parametrize("start", range(5))
def test_proximal_point_reaches_tolerance_and_agrees(start):
    problem = box_wall(3, 3, points=4, seed=2)
    rng = np.random.default_rng(start)
    r0 = np.abs(rng.normal(scale=0.1, size=problem.q.size)) * (start > 0)

    def measure(r, u):
        return natural_map_residual(problem, r, u)

    r, error, iterations, reason = proximal_point(
        problem.W, problem.q, problem.mu, 3, r0, 1e-8, 2000, measure, _Newton
    )
    assert reason.startswith("converged"), reason
    assert natural_map_error(problem, r) <= 1e-8
    # the default route solves this small case too; the Coulomb problem's solutions are not
    # unique on a singular W (the two velocities differ by ~1e-2 of |u|), so each answer is
    # checked on its own certificate only
    assert solve_coulomb(problem).success

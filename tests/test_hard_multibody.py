"""Hard rigid multibody problems (tests/multibody_problems.py) and the proximal-point method.

Truths: the generator's ``W = H M^-1 H^T`` is symmetric positive semidefinite of rank at most
6 per body, far below ``m``; every answer is certified by :func:`natural_map_error` of the
problem as given, computed here from the returned reactions (independent of the method). The
Coulomb problem's solutions are not unique on a singular ``W`` (self-equilibrated contact
forces can be added), so answers are checked on their certificates, not compared.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import contactqp as cq
from contactqp.core.local_problem import GlobalProblem, natural_map_error, natural_map_residual
from contactqp.io.fclib import read_any
from contactqp.methods.coulomb import _Newton, solve_coulomb, solve_proximal
from contactqp.methods.proximal import proximal_point
from multibody_problems import box_wall

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
FILES = sorted(path for path in DATA.iterdir() if path.suffix in (".hdf5", ".dat"))


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


def _measure(problem):
    def measure(r, u):
        return natural_map_residual(problem, r, u)

    return measure


def test_default_route_converges_where_its_rounds_failed():
    """5x5 boxes, 8 points per face (360 contacts): before the proximal stage the default
    route stopped at 1.5e-5 (one BLAS thread; which stage converges depends on rounding, so
    only the outcome is asserted, and the stage's report when it ran); the certificate is
    recomputed here."""
    problem = box_wall(5, 5, points=8, seed=13)
    result = solve_coulomb(problem)
    assert result.success, result.message
    if "proximal" in result.message:
        assert "proximal from r = 0" in result.message
        assert "converged after" in result.message.split("proximal from r = 0")[1]
    assert natural_map_error(problem, result.forces) <= 1e-8
    assert result.iterations <= 1800


# Walls whose candidate subproblems stall the Newton rounds (the default route converges on
# them only through its whole-problem fallback), 224 contacts.
STALLING = [(4, 4, 8, 20), (4, 4, 8, 21)]


@pytest.mark.parametrize(("nx", "nz", "points", "seed"), STALLING)
@pytest.mark.parametrize("start", range(5))
def test_proximal_method_from_perturbed_starts(nx, nz, points, seed, start):
    problem = box_wall(nx, nz, points=points, seed=seed)
    rng = np.random.default_rng(start)
    r0 = np.abs(rng.normal(scale=0.1, size=problem.q.size)) * (start > 0)
    result = cq.solve(problem, method="proximal", r0=r0)
    assert result.success, result.message
    assert result.message.startswith("converged: proximal")
    assert natural_map_error(problem, result.forces) <= 1e-8


def test_proximal_point_loop_reports_its_stop():
    """A budget too small to converge: the best point, its error as measured, the reason."""
    problem = box_wall(4, 4, points=8, seed=20)
    measure = _measure(problem)
    r, error, iterations, reason = proximal_point(
        problem.W, problem.q, problem.mu, 3, np.zeros(problem.q.size), 1e-8, 3, measure, _Newton
    )
    assert iterations <= 3
    assert reason.startswith("iteration limit")
    assert error == pytest.approx(natural_map_error(problem, r), rel=1e-12)
    assert error > 1e-8


def test_default_route_unchanged_where_it_converged():
    """A wall the rounds solve: no proximal stage runs (the route is as before)."""
    problem = box_wall(3, 3, points=4, seed=2)
    result = solve_coulomb(problem)
    assert result.success
    assert "proximal" not in result.message
    assert natural_map_error(problem, result.forces) <= 1e-8


@pytest.mark.parametrize("path", FILES, ids=[path.name for path in FILES])
def test_proximal_alone_on_the_shared_fclib_files(path):
    problem = read_any(path)
    if isinstance(problem, GlobalProblem):
        problem = problem.condense()
    result = solve_proximal(problem)
    assert result.success, result.message
    assert natural_map_error(problem, result.forces) <= 1e-8

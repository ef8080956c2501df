"""Hard rigid multibody problems (tests/multibody_problems.py) and the proximal-point method.

Truths: the generator's ``W = H M^-1 H^T`` is symmetric positive semidefinite of rank at most
6 per body, far below ``m``; every answer is certified by :func:`natural_map_error` of the
problem as given, computed here from the returned reactions (independent of the method). The
Coulomb problem's solutions are not unique on a singular ``W`` (self-equilibrated contact
forces can be added), so answers are checked on their certificates, not compared.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import contactqp as cq
from contactqp.core.local_problem import GlobalProblem, natural_map_error, natural_map_residual
from contactqp.io.fclib import read_any
from contactqp.methods import coulomb, proximal
from contactqp.methods.coulomb import _Newton, solve_coulomb, solve_proximal
from contactqp.methods.proximal import low_rank_factor, proximal_point
from multibody_problems import box_wall

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
FILES = sorted(path for path in DATA.iterdir() if path.suffix in (".hdf5", ".dat"))

# 4 x 5 boxes, 4 points per face (140 contacts: the default's spatial route): its sweeps stall
# and the rounds of Newton, Levenberg-Marquardt and Gauss-Seidel stop short of 1e-8 (measured
# with one BLAS thread); the proximal iterations converge from r = 0 in about 160 iterations.
HARD = {"nx": 4, "nz": 5, "points": 4, "seed": 83}
STAGE_ERROR = re.compile(r"error (\d\.\de[-+]\d+)\)")


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


def test_default_route_tries_the_proximal_stage_on_a_wall_its_rounds_failed():
    """The spatial route's stall goes to coulomb, whose rounds fail here, and whose last stage
    converges; which stages converge can depend on rounding, so the stages' account is
    asserted when the proximal stage ran."""
    problem = box_wall(**HARD)
    result = cq.solve(problem)
    assert result.success, result.message
    assert result.message.startswith("gauss-seidel") and result.method == "coulomb"
    if "proximal" in result.message:
        before, after = result.message.split("proximal from r = 0")
        assert all(float(e) > 1e-8 for e in STAGE_ERROR.findall(before))  # they stopped short
        assert "converged after" in after
    assert natural_map_error(problem, result.forces) <= 1e-8


def test_proximal_stage_after_rounds_cut_short(monkeypatch):
    """Rounds of one iteration each cannot solve a wall: the spatial route's hand-over reaches
    the proximal stage, and every stage before it reports the error it stopped at."""
    monkeypatch.setattr(coulomb, "RUN_ITERATIONS", 1)
    monkeypatch.setattr(coulomb, "PGS_SWEEPS", 1)
    problem = box_wall(3, 3, points=4, seed=0)
    result = cq.solve(problem)
    assert result.success, result.message
    before, after = result.message.split("proximal from r = 0")
    assert before.startswith("gauss-seidel") and "(stalled; error" in before
    assert before.count("error") == 1 + 2 * coulomb.ROUNDS + (coulomb.ROUNDS - 1)
    assert all(float(e) > 1e-8 for e in STAGE_ERROR.findall(before))
    assert "converged after" in after
    assert natural_map_error(problem, result.forces) <= 1e-8


def test_a_route_stopped_short_reports_what_its_stages_reached():
    problem = box_wall(3, 3, points=4, seed=0)
    result = solve_coulomb(problem, max_iter=3)
    assert not result.success
    assert result.iterations == 3 and "max_iter = 3 reached" in result.message
    reached = STAGE_ERROR.findall(result.message)
    assert len(reached) == 1  # one Newton run, cut at the budget
    assert float(reached[0]) == pytest.approx(natural_map_error(problem, result.forces), rel=0.06)


@pytest.mark.parametrize("start", range(5))
def test_proximal_method_from_perturbed_starts(start):
    problem = box_wall(**HARD)
    rng = np.random.default_rng(start)
    r0 = np.abs(rng.normal(scale=0.1, size=problem.q.size)) * (start > 0)
    result = cq.solve(problem, method="proximal", r0=r0)
    assert result.success, result.message
    assert result.message.startswith("converged: proximal")
    assert natural_map_error(problem, result.forces) <= 1e-8


def test_proximal_point_loop_reports_its_stop():
    """A budget too small to converge: the best point, its error on the problem as given
    (never the regularised one's), the reason."""
    problem = box_wall(4, 4, points=8, seed=20)

    def measure(r, u):
        return natural_map_residual(problem, r, u)

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


def test_low_rank_factor_of_a_wall_is_its_w_and_none_where_w_is_not_low_rank():
    """The pivoted Cholesky factor of a wall's ``W`` (24 boxes, 528 unknowns) has at most the
    bodies' 144 freedoms as columns and gives ``W`` back to rounding; a full-rank ``W``, a
    small one and a nonsymmetric one get None."""
    W = box_wall(6, 4, points=4, seed=0).W
    G = low_rank_factor(W)
    assert G is not None and G.shape[0] == W.shape[0] and G.shape[1] <= 6 * 24
    assert np.abs(G @ G.T - W).max() <= 1e-13 * np.abs(W).max()
    rng = np.random.default_rng(0)
    B = rng.standard_normal((W.shape[0], W.shape[0]))
    assert low_rank_factor(B @ B.T) is None  # full rank
    assert low_rank_factor(box_wall(3, 3, points=4, seed=0).W) is None  # 180 unknowns
    skewed = W.copy()
    skewed[0, 1] += 1e-6 * np.abs(W).max()
    assert low_rank_factor(skewed) is None


def test_low_rank_newton_step_is_the_lu_step():
    """On a proximal operator ``W + diag(w)`` of a wall, the step through ``G`` (Woodbury) is
    the LU's to 1e-9 of its size, at a point where a third of the contacts carry no force."""
    problem = box_wall(6, 4, points=4, seed=1)
    W = np.asarray(problem.W)
    G = low_rank_factor(W)
    assert G is not None
    m, nc = W.shape[0], problem.n_contacts
    diagonal = W.diagonal().reshape(nc, 3).mean(axis=1)
    weights = np.repeat(1e-3 * diagonal, 3)
    operator = W + np.diag(weights)
    reference = _Newton(operator, problem.q, problem.mu, 3, None)
    low_rank = _Newton(operator, problem.q, problem.mu, 3, None, low_rank=(G, weights))
    r = np.abs(np.random.default_rng(2).standard_normal(m)) * 0.1
    r.reshape(nc, 3)[: nc // 3] = 0.0  # some contacts open
    u = operator @ r + problem.q
    expected = reference.direction(r, u, 1e-6)
    step = low_rank.direction(r, u, 1e-6)
    assert expected is not None and step is not None
    assert np.abs(step - expected).max() <= 1e-9 * np.abs(expected).max()


def test_proximal_stage_through_the_low_rank_factor_takes_the_same_steps(monkeypatch):
    """The proximal method on a wall of 528 unknowns reaches 1e-8 in the same iterations and
    to the same reactions with the Woodbury steps as with the LU (the factor switched off)."""
    problem = box_wall(6, 4, points=4, seed=0)
    with_factor = solve_proximal(problem, tol=1e-8)
    monkeypatch.setattr(proximal, "LOW_RANK_MIN", 10**9)
    without = solve_proximal(problem, tol=1e-8)
    for result in (with_factor, without):
        assert result.success and natural_map_error(problem, result.forces) <= 1e-8
    assert with_factor.iterations == without.iterations
    size = np.abs(without.forces).max()
    np.testing.assert_allclose(with_factor.forces, without.forces, rtol=0, atol=1e-7 * size)


def test_a_failed_first_round_on_a_low_rank_w_goes_to_the_proximal_stage(monkeypatch):
    """On the whole problem (not the candidate sets' subproblems, which have no proximal
    stage), a first round that failed (here cut to 2 iterations a run) on a ``W`` of low rank
    goes straight to the proximal stage, which converges; with the factor switched off the
    later rounds of Gauss-Seidel and Newton run first, as before."""
    problem = box_wall(6, 4, points=4, seed=0)
    monkeypatch.setattr(coulomb, "RUN_ITERATIONS", 2)
    for low_rank in (True, False):
        if not low_rank:
            monkeypatch.setattr(proximal, "LOW_RANK_MIN", 10**9)
        result = solve_coulomb(problem, tol=1e-8)
        assert result.success and natural_map_error(problem, result.forces) <= 1e-8
        whole = result.message.split("whole problem:")[-1]
        assert ("no more rounds (W of low rank)" in whole) is low_rank
        assert ("gauss-seidel" in whole) is not low_rank
        assert "proximal from r = 0" in whole

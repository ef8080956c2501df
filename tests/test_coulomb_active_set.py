"""The Coulomb solver's candidate-set reduction, and the checks a problem keeps for its twins."""

import numpy as np
import pytest

import contactqp.core.local_problem as local_problem
import contactqp.methods.coulomb as coulomb
from contactqp import solve
from contactqp.core.local_problem import LocalProblem, column_products, natural_map_error
from contactqp.errors import InvalidInputError, NotPositiveDefiniteError


def _plate_problem(n_contacts=100, closed=6, mu=0.3, seed=0, cohesion=None):
    """A dense local problem whose contacts are mostly open: a smooth SPD ``W`` (contacts on a
    line, coupling decaying with distance) and gaps closed at a few contacts only."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 1.0, n_contacts)
    kernel = np.exp(-np.abs(x[:, None] - x[None, :]) / 0.2)
    W = np.kron(kernel, np.diag([1.0, 0.6, 0.6])) + 0.05 * np.eye(3 * n_contacts)
    q = 0.02 * rng.standard_normal(3 * n_contacts)
    q[::3] = 0.05 + 0.02 * rng.random(n_contacts)
    pressed = rng.choice(n_contacts, closed, replace=False)
    q[3 * pressed] = -0.3 - 0.2 * rng.random(closed)
    return LocalProblem(W, q, np.full(n_contacts, mu), 3, cohesion=cohesion)


def _without_reduction(monkeypatch, problem, **options):
    with monkeypatch.context() as patch:
        patch.setattr(coulomb, "ACTIVE_SET_MIN", 10**9)
        return solve(problem, "coulomb", **options)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_candidate_set_gives_the_whole_problem_solution(monkeypatch, seed):
    problem = _plate_problem(seed=seed)
    reduced = solve(problem, "coulomb", tol=1e-12)
    whole = _without_reduction(monkeypatch, problem, tol=1e-12)
    assert reduced.success and whole.success
    assert "contacts:" in reduced.message and "contacts:" not in whole.message
    assert natural_map_error(problem, reduced.forces) <= 1e-12  # on every contact, from r alone
    closed = reduced.forces[::3] > 0
    assert 0 < closed.sum() < problem.n_contacts // 2  # a reduction that mattered
    np.testing.assert_allclose(
        reduced.forces, whole.forces, rtol=0, atol=1e-9 * np.abs(whole.forces).max()
    )
    assert np.all(reduced.forces.reshape(-1, 3)[~closed] == 0.0)  # open contacts exactly at rest


def test_candidate_set_from_a_warm_start_and_with_cohesion(monkeypatch):
    problem = _plate_problem(seed=3, cohesion=np.full(100, 0.01))
    cold = solve(problem, "coulomb", tol=1e-11)
    whole = _without_reduction(monkeypatch, problem, tol=1e-11)
    warm = solve(problem.with_q(problem.q * 1.01), "coulomb", tol=1e-11, r0=cold.forces)
    assert cold.success and whole.success and warm.success
    np.testing.assert_allclose(
        cold.forces, whole.forces, rtol=0, atol=1e-8 * np.abs(whole.forces).max()
    )
    assert natural_map_error(problem.with_q(problem.q * 1.01), warm.forces) <= 1e-11


def test_with_q_keeps_w_and_the_semidefinite_check(monkeypatch):
    sizes = []  # the rows of each matrix checked
    real = local_problem.check_positive_semidefinite

    def counting(W, *name):
        sizes.append(W.shape[0])
        return real(W, *name)

    monkeypatch.setattr(local_problem, "check_positive_semidefinite", counting)
    monkeypatch.setattr(coulomb, "check_positive_semidefinite", counting)
    problem = _plate_problem()
    m = problem.q.shape[0]
    twin = problem.with_q(-problem.q)
    assert twin.W is problem.W and twin.mu is problem.mu
    np.testing.assert_array_equal(twin.q, -problem.q)
    twins = (problem, twin, problem.with_q(problem.q))
    for candidate in twins:  # on candidate sets: their blocks only, never all of W
        assert solve(candidate, "coulomb").success
    assert sizes and max(sizes) < m
    sizes.clear()
    with monkeypatch.context() as patch:  # on the whole problem: all of W, factored once
        patch.setattr(coulomb, "ACTIVE_SET_MIN", 10**9)
        for candidate in twins:
            assert solve(candidate, "coulomb").success
    assert sizes == [m]
    with pytest.raises(InvalidInputError, match="q must have length"):
        problem.with_q(np.zeros(5))


def test_check_semidefinite_fails_on_every_call():
    bad = LocalProblem(-np.eye(3), np.zeros(3), [0.3], 3)
    for _ in range(2):
        with pytest.raises(NotPositiveDefiniteError):
            bad.check_semidefinite()


def test_column_products_gathered_equal_the_full_product():
    rng = np.random.default_rng(4)
    A = rng.standard_normal((90, 120))
    columns = np.array([3, 4, 5, 60, 61, 62])
    x = rng.standard_normal(columns.size)
    product, magnitude = column_products(A, x, columns)
    np.testing.assert_allclose(product, A[:, columns] @ x, rtol=1e-14)
    np.testing.assert_allclose(magnitude, np.abs(A[:, columns]) @ np.abs(x), rtol=1e-14)


def _stacked_pairs(n_pairs=70, seed=5):
    """Two 3-freedom node rows coupled by a smooth SPD flexibility, one pair per node column."""
    import contactqp as cq

    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 1.0, n_pairs)
    kernel = np.exp(-np.abs(x[:, None] - x[None, :]) / 0.3)
    flexibility = np.kron(np.eye(2), np.kron(kernel, np.diag([1.0, 1.0, 2.0]))) * 1e-6
    model = cq.ReducedModel(flexibility=flexibility, dofs_per_node=3)
    pairs = np.column_stack([np.arange(n_pairs), n_pairs + np.arange(n_pairs)])
    gaps = 2e-6 + 1e-6 * rng.random(n_pairs)
    loads = np.zeros(6 * n_pairs)
    loads[3 * np.array([10, 40]) + 2] = 2.0  # pull the lower nodes up, the upper ones down
    loads[3 * (n_pairs + np.array([10, 40])) + 2] = -2.0
    loads[3 * (n_pairs + np.arange(n_pairs))] = 0.01  # and shear the upper row
    return model, pairs, gaps, loads


def test_with_gaps_solves_as_a_problem_built_with_those_gaps():
    import contactqp as cq

    model, pairs, gaps, loads = _stacked_pairs()
    other = gaps + 5e-7 * np.random.default_rng(6).standard_normal(gaps.size)
    base = cq.FrictionalProblem(model, loads, [cq.NodePairs(pairs, gaps, [0, 0, 1.0])], 0.3)
    fresh = cq.FrictionalProblem(model, loads, [cq.NodePairs(pairs, other, [0, 0, 1.0])], 0.3)
    varied, built = solve(base.with_gaps(other)), solve(fresh)
    assert varied.success and built.success
    assert 0 < np.count_nonzero(built.forces[:, 0]) < len(pairs)
    np.testing.assert_allclose(varied.forces, built.forces, rtol=0, atol=1e-9)
    np.testing.assert_allclose(varied.gaps, built.gaps, rtol=0, atol=1e-15)
    with pytest.raises(InvalidInputError, match="gaps must have shape"):
        base.with_gaps(gaps[:-1])

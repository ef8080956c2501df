"""Principal-block solves through one re-used factor agree with direct dense solves."""

import numpy as np
import pytest

from contactqp.methods.free_block import FreeBlockSolver


def spd(n, rng):
    B = rng.standard_normal((n, n))
    return B @ B.T + n * np.eye(n)


def neighbours(n, rng, steps=12):
    """A walk of free sets, each differing from the previous one by a few indices."""
    free = rng.random(n) < 0.6
    for _ in range(steps):
        flip = rng.choice(n, size=rng.integers(1, 6), replace=False)
        free = free.copy()
        free[flip] = ~free[flip]
        if free.any():
            yield free


@pytest.mark.parametrize("seed", range(5))
def test_bordered_and_trimmed_solves_match_direct_solves(seed):
    rng = np.random.default_rng(seed)
    n = 80
    W = spd(n, rng)
    solver = FreeBlockSolver(W)
    for free in neighbours(n, rng):
        rhs = rng.standard_normal(int(free.sum()))
        expected = np.linalg.solve(W[np.ix_(free, free)], rhs)
        np.testing.assert_allclose(solver.solve(free, rhs), expected, rtol=1e-9, atol=1e-12)
    assert solver.updates > 0, "the walk should have been served by updates"
    assert solver.factorizations < solver.updates


def test_a_far_free_set_is_factored_afresh():
    rng = np.random.default_rng(7)
    W = spd(40, rng)
    solver = FreeBlockSolver(W)
    first = np.zeros(40, dtype=bool)
    first[:30] = True
    solver.solve(first, np.ones(30))
    far = ~first
    x = solver.solve(far, np.ones(10))
    np.testing.assert_allclose(W[np.ix_(far, far)] @ x, np.ones(10), rtol=1e-10)
    assert solver.factorizations == 2 and solver.updates == 0


def test_semidefinite_blocks_are_regularised_and_consistent_systems_solved():
    rng = np.random.default_rng(3)
    basis = rng.standard_normal((30, 10))
    W = basis @ basis.T  # rank 10
    solver = FreeBlockSolver(W)
    free = np.ones(30, dtype=bool)
    rhs = W @ rng.standard_normal(30)  # in the range of W
    x = solver.solve(free, rhs)
    assert np.linalg.norm(W @ x - rhs) <= 1e-6 * np.linalg.norm(rhs)


def test_updates_dropping_and_bordering_overlapping_sets_match_direct_solves():
    # free sets that drop (and border) the same indices again, as an active set settling near
    # one base does: each solve must equal a direct one of its own block
    rng = np.random.default_rng(11)
    n = 120
    W = spd(n, rng)
    solver = FreeBlockSolver(W)
    base = np.zeros(n, dtype=bool)
    base[:90] = True
    sets = [base]
    for dropped, added in (
        ([3, 40, 41, 88], []),
        ([3, 41], []),
        ([3, 40, 41, 88, 60], [95, 100]),
        ([40], [100]),
        ([], [95, 100, 110]),
    ):
        free = base.copy()
        free[dropped] = False
        free[added] = True
        sets.append(free)
    for free in sets:
        rhs = rng.standard_normal(int(free.sum()))
        expected = np.linalg.solve(W[np.ix_(free, free)], rhs)
        np.testing.assert_allclose(solver.solve(free, rhs), expected, rtol=1e-9, atol=1e-12)
    assert solver.factorizations == 1 and solver.updates == len(sets) - 1

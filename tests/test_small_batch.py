"""``LocalBatch``: many small problems solved together give what each gives alone.

Truths used:

* :func:`contactqp.solve` on each problem alone (``batch.problem(p)``): the batch's reactions
  agree with its to 1e-7 (both are converged to a natural-map error of 1e-10 or better, and
  the problems drawn have one solution: ``W`` definite and ``mu`` moderate), and the verdicts are
  equal;
* closed forms of one contact with a diagonal ``W``: separation (``r = 0``), sticking
  (``r = -W^-1 q``), sliding (``||r_T|| = mu r_N`` opposite to the slip), the tip of the cone
  (``q = 0`` gives ``r = 0``) and ``mu = 0`` (``r_T = 0``);
* the certificate of each problem is recomputed here from its own ``W``, ``q`` and ``r``.
"""

import numpy as np
import pytest

import contactqp
from contactqp import LocalBatch, LocalBatchResult, kernels
from contactqp.core.local_problem import natural_map_error
from contactqp.errors import InvalidInputError, NotPositiveDefiniteError
from contactqp.methods import batch as batch_module
from contactqp.methods import registry


def random_batch(P, nc, dim, seed, mu_high=0.8):
    rng = np.random.default_rng(seed)
    m = nc * dim
    A = rng.standard_normal((P, m, m)) / np.sqrt(m)
    W = A @ A.transpose(0, 2, 1) * 0.5 + np.eye(m)
    q = 0.4 * rng.standard_normal((P, m))
    q[:, ::dim] += np.where(rng.random((P, nc)) < 0.3, 0.5, -0.5)
    mu = np.where(rng.random((P, nc)) < 0.15, 0.0, rng.uniform(0.05, mu_high, (P, nc)))
    return LocalBatch(W, q, mu, dim)


def hard_cases():
    """One-contact problems with a diagonal W and their closed-form reactions."""
    W = np.diag([2.0, 1.0, 1.0])
    mu = 0.5
    cases = [
        ([1.0, 0.3, -0.2], mu, [0.0, 0.0, 0.0]),  # separation
        ([0.0, 0.0, 0.0], mu, [0.0, 0.0, 0.0]),  # tip of the cone
        ([-2.0, 0.3, 0.4], mu, [1.0, -0.3, -0.4]),  # sticking: ||r_T|| = 0.5 <= 0.5
        ([-2.0, 0.0, 2.0], mu, [1.0, 0.0, -0.5]),  # sliding
        ([-2.0, 0.6, -0.8], 0.0, [1.0, 0.0, 0.0]),  # mu = 0
        ([-2.0, 0.3, 0.0], 0.0, [1.0, 0.0, 0.0]),  # mu = 0, a tangential push
    ]
    Ws = np.repeat(W[None], len(cases), axis=0)
    q = np.array([case[0] for case in cases])
    mus = np.array([[case[1]] for case in cases])
    expected = np.array([case[2] for case in cases])
    return LocalBatch(Ws, q, mus, 3), expected


def assert_matches_one_by_one(batch, result, tol):
    assert isinstance(result, LocalBatchResult)
    for p in range(batch.n_problems):
        alone = contactqp.solve(batch.problem(p), tol=tol)
        assert bool(result.success[p]) == alone.success, p
        scale = max(1.0, float(np.max(np.abs(alone.forces))))
        np.testing.assert_allclose(result.forces[p], alone.forces, atol=1e-7 * scale, err_msg=p)
        problem = batch.problem(p)  # the certificate, recomputed from the problem's own data
        np.testing.assert_allclose(
            result.displacements[p], problem.W @ result.forces[p] + problem.q, atol=1e-12
        )
        assert result.error[p] == pytest.approx(natural_map_error(problem, result.forces[p]))


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("nc", [1, 3, 8])
def test_batch_agrees_with_one_by_one(nc, dim):
    batch = random_batch(40, nc, dim, seed=nc * 10 + dim)
    result = contactqp.solve(batch, tol=1e-10)
    assert result.method == "coulomb-batch"
    assert result.all_solved
    assert_matches_one_by_one(batch, result, tol=1e-10)


def test_closed_forms_of_one_contact():
    batch, expected = hard_cases()
    result = contactqp.solve(batch, tol=1e-12)
    assert result.all_solved
    np.testing.assert_allclose(result.forces, expected, atol=1e-10)
    labels = [result.status_labels(p)[0] for p in range(batch.n_problems)]
    assert labels == ["open", "open", "stick", "slip", "slip", "slip"]
    assert_matches_one_by_one(batch, result, tol=1e-12)


@pytest.mark.parametrize(("dim", "P"), [(3, 3000), (2, 20000)])
def test_problems_newton_stops_short_on_take_the_sweeps(dim, P):
    # a wide draw of one-contact problems (ill-conditioned W, mu up to 1): some stall in the
    # first Newton run; the compiled sweeps of their dimension (spatial, planar) then solve them
    # from their start, as alone
    rng = np.random.default_rng(0)
    A = rng.standard_normal((P, dim, dim))
    W = A @ A.transpose(0, 2, 1) + 0.5 * np.eye(dim)
    batch = LocalBatch(W, rng.standard_normal((P, dim)), rng.uniform(0, 1, (P, 1)), dim)
    result = contactqp.solve(batch)
    if kernels.small_newton is not None:
        assert result.messages, "expected some problems beyond the first Newton run"
        for p, message in result.messages.items():
            assert message.startswith("newton ") and "(stopped short), then converged" in message
            assert result.iterations[p] > int(message.split()[1])  # Newton's, then the sweeps'
    chosen = sorted(result.messages)[:5] + [0, 1, 2]
    sub = LocalBatch(W[chosen], batch.q[chosen], batch.mu[chosen], dim)
    assert_matches_one_by_one(sub, contactqp.solve(sub), tol=1e-8)
    assert result.all_solved


def test_warm_starts_and_budget():
    batch = random_batch(10, 2, 3, seed=5)
    cold = contactqp.solve(batch, tol=1e-10)
    warm = contactqp.solve(batch, tol=1e-10, r0=cold.forces)
    assert warm.all_solved and np.all(warm.iterations <= 1)
    short = contactqp.solve(batch, tol=1e-14, max_iter=1)
    assert np.all(short.iterations <= 1)
    for p in range(batch.n_problems):
        alone = contactqp.solve(batch.problem(p), "coulomb", tol=1e-14, max_iter=1)
        assert bool(short.success[p]) == alone.success


def test_pure_numpy_fallback_solves_one_by_one(monkeypatch):
    batch = random_batch(6, 2, 3, seed=9)
    expected = contactqp.solve(batch, tol=1e-10)
    monkeypatch.setattr(kernels, "small_newton", None)
    result = contactqp.solve(batch, tol=1e-10)
    assert result.all_solved and len(result.messages) == batch.n_problems
    np.testing.assert_allclose(result.forces, expected.forces, atol=1e-8)


def test_batch_is_registered():
    assert registry.default_method("local-batch") == "coulomb-batch"
    assert registry.kind_of(random_batch(1, 1, 3, 0)) == "local-batch"


def test_mu_broadcasts():
    rng = np.random.default_rng(3)
    W = np.repeat(np.eye(6)[None], 4, axis=0)
    q = rng.standard_normal((4, 6))
    assert np.array_equal(LocalBatch(W, q, 0.3, 3).mu, np.full((4, 2), 0.3))
    assert np.array_equal(LocalBatch(W, q, [0.1, 0.2], 3).mu, np.tile([0.1, 0.2], (4, 1)))


@pytest.mark.parametrize(
    "args, match",
    [
        ((np.eye(3), np.zeros((1, 3)), 0.3, 3), "shape \\(P, m, m\\)"),
        ((np.zeros((2, 3, 3)), np.zeros((2, 4)), 0.3, 3), "q must have shape"),
        ((np.zeros((2, 4, 4)), np.zeros((2, 4)), 0.3, 3), "dim \\* k"),
        ((np.zeros((2, 3, 3)), np.zeros((2, 3)), [0.3, 0.2], 3), "mu must have shape"),
        ((np.zeros((2, 3, 3)), np.zeros((2, 3)), -0.1, 3), "mu must be >= 0"),
        ((np.zeros((2, 3, 3)), np.full((2, 3), np.nan), 0.3, 3), "NaN or inf \\(problem 0\\)"),
        ((np.zeros((2, 3, 3)), np.zeros((2, 3)), 0.3, 4), "dim must be 2 or 3"),
        ((np.zeros((0, 3, 3)), np.zeros((0, 3)), 0.3, 3), "P >= 1"),
    ],
)
def test_bad_batches_are_refused(args, match):
    with pytest.raises(InvalidInputError, match=match):
        LocalBatch(*args)


def test_bad_options_and_indefinite_w():
    batch = random_batch(3, 1, 3, seed=1)
    with pytest.raises(InvalidInputError, match="r0 must have shape"):
        contactqp.solve(batch, r0=np.zeros(3))
    with pytest.raises(InvalidInputError, match="tol"):
        contactqp.solve(batch, tol=-1.0)
    W = batch.W.copy()
    W[2] = np.diag([1.0, -1.0, 1.0])
    with pytest.raises(NotPositiveDefiniteError, match="W\\[2\\]"):
        contactqp.solve(LocalBatch(W, batch.q, batch.mu, 3))
    assert batch_module.solve_coulomb_batch(batch).all_solved

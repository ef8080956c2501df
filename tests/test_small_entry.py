"""The fast entry of small local problems: one-pass validation and the one-call solve.

Truths used:

* the numpy checks of ``LocalProblem`` (its ``_validate``, which every problem took before the
  one-pass check existed and which any input not already stored as float64 arrays still
  takes) are the oracle: a problem validated in one pass stores the same fields, and any input
  the one pass refuses gets the numpy checks' own message;
* ``small_solve`` is ``small_newton`` then ``small_certificate`` on a batch of one problem
  (the batch kernels' tests tie those to the Python Newton run and the numpy certificate): the
  same iterations, reason, reactions and certificate figures.
"""

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp
from contactqp import kernels
from contactqp.core import local_problem as lp
from contactqp.core.local_problem import LocalProblem
from contactqp.errors import InvalidInputError

pytestmark = pytest.mark.skipif(
    kernels.small_solve is None, reason="compiled kernels not built: no one-pass entry to check"
)


def checked_by_numpy(monkeypatch, *args, **kwargs) -> LocalProblem:
    """The problem as the numpy checks build it (the one-pass check switched off)."""
    with monkeypatch.context() as patch:
        patch.setattr(kernels, "local_arrays_valid", None)
        return LocalProblem(*args, **kwargs)


def random_arrays(seed, nc=3, dim=3):
    rng = np.random.default_rng(seed)
    m = nc * dim
    A = rng.standard_normal((m, m))
    W = A @ A.T / m + np.eye(m)
    q = rng.standard_normal(m)
    mu = rng.uniform(0.1, 1.0, nc)
    return W, q, mu


@pytest.mark.parametrize("sparse", [False, True])
@pytest.mark.parametrize("cohesion", [False, True])
@pytest.mark.parametrize("digits", [{}, {"W": 7}])
def test_one_pass_stores_what_the_numpy_checks_store(monkeypatch, sparse, cohesion, digits):
    W, q, mu = random_arrays(0)
    W = sp.csr_matrix(W) if sparse else W
    c = np.array([0.0, 0.2, 0.1]) if cohesion else None
    fast = LocalProblem(W, q, mu, 3, "t", c, dict(digits))
    slow = checked_by_numpy(monkeypatch, W, q, mu, 3, "t", c, dict(digits))
    assert type(fast.W) is type(slow.W)
    dense = (lambda A: A.toarray()) if sparse else np.asarray
    np.testing.assert_array_equal(dense(fast.W), dense(slow.W))
    for name in ("q", "mu", "cohesion"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(slow, name))
        assert getattr(fast, name).dtype == np.float64
    np.testing.assert_array_equal(fast.law.mu, slow.law.mu)
    np.testing.assert_array_equal(fast.law.cohesion, slow.law.cohesion)
    assert fast.law.facets is None and fast.digits == slow.digits
    np.testing.assert_array_equal(fast.apex_shift, slow.apex_shift)
    a, b = contactqp.solve(fast), contactqp.solve(slow)
    assert a.success and a.iterations == b.iterations
    np.testing.assert_allclose(a.forces, b.forces, rtol=1e-12, atol=1e-12)


def bad_inputs():
    W, q, mu = random_arrays(1)
    nan_W = W.copy()
    nan_W[2, 4] = np.nan
    inf_q = q.copy()
    inf_q[5] = np.inf
    sparse_nan = sp.csr_matrix(W)
    sparse_nan.data[3] = np.nan
    return {
        "W NaN": (nan_W, q, mu, 3, None),
        "sparse W NaN": (sparse_nan, q, mu, 3, None),
        "q inf": (W, inf_q, mu, 3, None),
        "mu negative": (W, q, np.array([0.3, -0.1, 0.2]), 3, None),
        "mu NaN": (W, q, np.array([0.3, np.nan, 0.2]), 3, None),
        "cohesion negative": (W, q, mu, 3, np.array([0.0, -1.0, 0.0])),
        "cohesion NaN": (W, q, mu, 3, np.array([0.0, np.nan, 0.0])),
        "cohesion without friction": (W, q, np.array([0.3, 0.0, 0.2]), 3, np.array([0, 1.0, 0])),
        "cohesion too short": (W, q, mu, 3, np.array([0.0, 1.0])),
        "q too short": (W, q[:-1], mu, 3, None),
        "W not square": (W[:, :-1].copy(), q, mu, 3, None),
        "dim does not divide": (W, q, mu, 2, None),
        "dim 4": (W, q, mu, 4, None),
    }


@pytest.mark.parametrize("case", sorted(bad_inputs()))
def test_one_pass_refuses_with_the_numpy_checks_message(monkeypatch, case):
    W, q, mu, dim, c = bad_inputs()[case]
    with pytest.raises(InvalidInputError) as numpy_error:
        checked_by_numpy(monkeypatch, W, q, mu, dim, cohesion=c)
    with pytest.raises(InvalidInputError) as fast_error:
        LocalProblem(W, q, mu, dim, cohesion=c)
    assert str(fast_error.value) == str(numpy_error.value)


def test_arrays_not_stored_as_given_take_the_numpy_checks():
    W, q, mu = random_arrays(2)
    for problem in (
        LocalProblem(np.asfortranarray(W), q, mu, 3),  # not C-contiguous
        LocalProblem(W.tolist(), q.tolist(), mu.tolist(), 3),
        LocalProblem(W.astype(np.float32), q, mu, 3),
        LocalProblem(W, q[::1], mu, np.int64(3)),
    ):
        assert problem.W.dtype == np.float64 and isinstance(problem.dim, int)
        np.testing.assert_allclose(np.asarray(problem.W), W, rtol=1e-7)
        assert contactqp.solve(problem).success


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("cohesion", [False, True])
def test_small_solve_is_the_batch_kernels_on_one_problem(seed, cohesion):
    W, q, mu = random_arrays(seed, nc=4)
    c = np.where(np.arange(4) % 2, 0.15, 0.0) if cohesion else np.zeros(4)
    problem = LocalProblem(W, q, mu, 3, cohesion=c)
    small = problem.small
    m = q.size
    x = small.shift.copy()  # from r = 0, in apex coordinates
    counts, reasons, errors = np.empty(1, np.intp), np.empty(1, np.intp), np.empty(1)
    kernels.small_newton(
        small.W, q.reshape(1, m), small.mu, small.shift, x, 1e-10, 100, False,
        lp.CONTACT_FLOOR, counts, reasons, errors,
    )  # fmt: skip
    reactions = x - small.shift
    u, measures = np.empty((1, m)), np.empty((1, 4))
    status = np.empty((1, 4), dtype=np.intp)
    kernels.small_certificate(
        small.W, q.reshape(1, m), small.mu, small.shift, reactions, False, lp.CONTACT_FLOOR,
        lp.STATUS_RTOL, u, measures, status,
    )  # fmt: skip
    r, u_one, status_one = np.zeros(m), np.empty(m), np.empty(4, dtype=np.intp)
    k, code, run_error, *figures = kernels.small_solve(
        W, q, mu, c, r, 1e-10, 100, False, lp.CONTACT_FLOOR, lp.STATUS_RTOL, u_one, status_one
    )
    assert (k, code) == (counts[0], reasons[0])
    assert run_error == pytest.approx(errors[0], rel=1e-12, abs=1e-300)
    np.testing.assert_allclose(r, reactions[0], rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(u_one, u[0], rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(figures, measures[0], rtol=1e-12, atol=1e-300)
    np.testing.assert_array_equal(status_one, status[0])


def test_small_solve_refuses_inconsistent_arrays():
    W, q, mu = random_arrays(3)
    u, status = np.empty(9), np.empty(3, dtype=np.intp)
    args = (1e-8, 10, False, lp.CONTACT_FLOOR, lp.STATUS_RTOL)
    with pytest.raises(ValueError, match="inconsistent shapes"):
        kernels.small_solve(W, q, mu, np.zeros(2), np.zeros(9), *args, u, status)
    with pytest.raises(ValueError, match="do not make rows"):
        kernels.small_solve(W, q, mu[:2], np.zeros(2), np.zeros(9), *args, u, status)
    with pytest.raises(ValueError, match="C-contiguous"):
        kernels.small_solve(np.asfortranarray(W), q, mu, np.zeros(3), np.zeros(9), *args, u, status)


def test_a_warm_start_is_read_not_written():
    W, q, mu = random_arrays(4)
    start = np.full(9, 0.01)
    kept = start.copy()
    result = contactqp.solve(LocalProblem(W, q, mu, 3), r0=start)
    assert result.success
    np.testing.assert_array_equal(start, kept)

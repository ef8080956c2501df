"""The compiled small-problem route of ``coulomb`` gives the Python route's answers.

Truths used:

* the Python Newton run (``coulomb._Newton.run``), which every problem took before the
  compiled route existed and which problems larger than ``SMALL_UNKNOWNS`` still take, is the
  oracle: with the compiled route switched off (``problem.small`` None) the same problem gives
  the same iterations, the same stages in the message, the same verdict and the same reactions
  to rounding (sums run in another order, so agreement is to 1e-9 relative, not bit for bit);
* the certificate figures (``u = W r + q``, the natural-map error, the accuracy limits, the
  contact status) are those of the numpy functions of ``core.local_problem`` on the same ``r``;
* the compiled PSD test agrees with ``check_positive_semidefinite`` (LAPACK) on matrices clear
  of its boundary (eigenvalues at least 1e-3 from the shifted threshold);
* the shared FCLIB files with 1 to 10 contacts: the same iterations and an error no worse than
  the Python route's (and within tol).
"""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp
from contactqp import kernels
from contactqp.core import local_problem as lp
from contactqp.core.local_problem import (
    LocalProblem,
    accuracy_limits,
    certify_small,
    check_positive_semidefinite,
    contact_status_unchecked,
    natural_map_residual,
    small_semidefinite,
)
from contactqp.errors import NotPositiveDefiniteError
from contactqp.methods import coulomb
from contactqp.methods.coulomb import solve_coulomb

FCLIB = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
SMALL_FILES = [
    "FrictionContact3D_1c.dat",
    "FC3D_Example1.dat",
    "FC3D_Example1_SBM.dat",
    "Rover1041.dat",
    "Rover4516.dat",
    "CubeH8.hdf5",
    "GFC3D_Example1.dat",
    "GFC3D_TwoRods1.dat",
    "LMGC_GlobalFrictionContactProblem00046.hdf5",
]

pytestmark = pytest.mark.skipif(
    kernels.small_newton is None, reason="compiled kernels not built: no small route to check"
)


def python_route(problem: LocalProblem) -> LocalProblem:
    """The same problem with the compiled route switched off (its cached arrays set to None)."""
    twin = LocalProblem(problem.W, problem.q, problem.mu, problem.dim, cohesion=problem.cohesion)
    # the cached properties' slots: the Python route is taken
    twin.__dict__["small_W"] = twin.__dict__["small"] = None
    return twin


def random_problem(seed, nc, dim, *, cohesion=False, frictionless_share=0.2, open_share=0.3):
    """A random SPD ``W`` and a ``q`` mixing closed, open, sticking and sliding contacts."""
    rng = np.random.default_rng(seed)
    m = nc * dim
    A = rng.standard_normal((m, m)) / np.sqrt(m)
    W = A @ A.T * 0.5 + np.eye(m)
    q = 0.4 * rng.standard_normal(m)
    q[::dim] = np.where(rng.random(nc) < open_share, 0.5, -0.5) + 0.1 * rng.standard_normal(nc)
    mu = np.where(rng.random(nc) < frictionless_share, 0.0, rng.uniform(0.05, 1.2, nc))
    c = np.where(mu > 0, rng.uniform(0.0, 0.2, nc), 0.0) if cohesion else None
    return LocalProblem(W, q, mu, dim, cohesion=c)


def assert_same(fast, slow, rtol=1e-9):
    assert fast.iterations == slow.iterations
    assert fast.success == slow.success
    # the stages and verdict are the same; the printed error may differ in its last digits
    assert fast.message.split("; natural-map")[0] == slow.message.split("; natural-map")[0]
    scale = max(1.0, float(np.max(np.abs(slow.forces))))
    np.testing.assert_allclose(fast.forces, slow.forces, rtol=rtol, atol=rtol * scale)
    np.testing.assert_array_equal(fast.contact_status, slow.contact_status)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("nc", [1, 2, 5, 10])
@pytest.mark.parametrize("seed", range(6))
def test_compiled_route_repeats_the_python_iterations(seed, nc, dim):
    problem = random_problem(seed, nc, dim)
    assert problem.small is not None
    fast, slow = solve_coulomb(problem, tol=1e-10), solve_coulomb(python_route(problem), tol=1e-10)
    assert_same(fast, slow)


@pytest.mark.parametrize("seed", range(4))
def test_cohesion_and_per_contact_take_the_same_route(seed):
    problem = random_problem(seed, 4, 3, cohesion=True)
    for options in ({"per_contact": True, "tol": 1e-10}, {"tol": 1e-8}):
        assert_same(
            solve_coulomb(problem, **options), solve_coulomb(python_route(problem), **options)
        )


def test_a_run_that_stops_short_goes_on_to_the_later_stages():
    # one contact on which the first Newton run stalls (found among random draws): the
    # Levenberg-Marquardt run and the Gauss-Seidel round must follow exactly as in Python
    found = None
    rng = np.random.default_rng(7)
    for _ in range(4000):
        A = rng.standard_normal((3, 3))
        W = A @ A.T + 0.5 * np.eye(3)
        problem = LocalProblem(W, rng.standard_normal(3), rng.uniform(0, 1, 1), 3)
        x = np.zeros((1, 3))
        counts, reasons, errors = np.empty(1, np.intp), np.empty(1, np.intp), np.empty(1)
        small = problem.small
        kernels.small_newton(
            small.W, problem.q.reshape(1, 3), small.mu, small.shift, x, 1e-8, 100, False,
            lp.CONTACT_FLOOR, counts, reasons, errors,
        )  # fmt: skip
        if reasons[0] != 0:
            found = problem
            break
    assert found is not None, "no problem on which the first Newton run stops short"
    fast, slow = solve_coulomb(found), solve_coulomb(python_route(found))
    assert "levenberg-marquardt" in fast.message
    assert_same(fast, slow, rtol=1e-7)


def test_iteration_budget_is_shared_with_the_later_stages():
    problem = random_problem(3, 6, 3)
    for max_iter in (1, 2, 3):
        assert_same(
            solve_coulomb(problem, tol=1e-14, max_iter=max_iter),
            solve_coulomb(python_route(problem), tol=1e-14, max_iter=max_iter),
        )


def test_the_kernel_constants_are_coulombs():
    from contactqp.kernels import compiled

    assert compiled.SMALL_CONSTANTS == {
        "REGULARISATION": coulomb.REGULARISATION,
        "MEMORY": coulomb.MEMORY,
        "ARMIJO": coulomb.ARMIJO,
        "MAX_HALVINGS": coulomb.MAX_HALVINGS,
        "STALL": coulomb.STALL,
    }


@pytest.mark.parametrize("cohesion", [False, True])
@pytest.mark.parametrize("per_contact", [False, True])
def test_certificate_figures_are_the_numpy_ones(cohesion, per_contact):
    for seed in range(5):
        problem = random_problem(seed, 5, 3, cohesion=cohesion)
        r = np.random.default_rng(seed).standard_normal(15)
        r[3:6] = 0.0  # an open contact
        u, error, limits, status = certify_small(problem, r, per_contact=per_contact)
        expected_u = problem.W @ r + problem.q
        np.testing.assert_allclose(u, expected_u, rtol=1e-13, atol=1e-13)
        expected = natural_map_residual(problem, r, expected_u, per_contact=per_contact)[1]
        assert error == pytest.approx(expected, rel=1e-12)
        reference = accuracy_limits(problem, r, expected_u)
        assert limits.rounding == pytest.approx(reference.rounding, rel=1e-12)
        assert limits.data == reference.data
        np.testing.assert_array_equal(status, contact_status_unchecked(problem, r, expected_u))


def test_written_digits_enter_the_small_certificate():
    problem = random_problem(1, 3, 3)
    rounded = LocalProblem(problem.W, problem.q, problem.mu, 3, digits={"W": 6, "q": 8})
    r = np.ones(9)
    u = rounded.W @ r + rounded.q
    limits = certify_small(rounded, r)[2]
    assert limits.data > 0 and limits.digits == {"W": 6, "q": 8}
    assert limits.data == pytest.approx(accuracy_limits(rounded, r, u).data, rel=1e-12)


def psd_cases():
    rng = np.random.default_rng(11)
    cases = []
    for m in (1, 2, 3, 6, 9, 30):
        Q = np.linalg.qr(rng.standard_normal((m, m)))[0]
        for low in (1.0, 1e-2, -0.5):  # definite, nearly singular, indefinite
            values = np.linspace(low, 2.0, m)
            cases.append(Q @ np.diag(values) @ Q.T)
        singular = Q @ np.diag(np.r_[np.zeros(1), np.ones(m - 1)]) @ Q.T  # semidefinite
        cases.append(singular)
        skew = rng.standard_normal((m, m))
        cases.append(np.eye(m) + 0.3 * (skew - skew.T))  # unsymmetric, symmetric part I
    zero_row = np.diag([1.0, 0.0, 2.0])
    cases.append(zero_row)
    bad_row = zero_row.copy()
    bad_row[1, 0] = bad_row[0, 1] = 0.1
    cases.append(bad_row)
    cases.append(np.diag([1.0, -1e-3, 1.0]))
    return cases


@pytest.mark.parametrize("W", psd_cases(), ids=lambda W: f"m{W.shape[0]}")
def test_compiled_psd_test_agrees_with_lapack(W):
    try:
        check_positive_semidefinite(W)
        expected = True
    except NotPositiveDefiniteError:
        expected = False
    assert small_semidefinite(np.ascontiguousarray(W)[None]).tolist() == [expected]


def test_an_indefinite_small_w_is_refused_with_the_lapack_message():
    W = np.diag([1.0, -0.5, 1.0])
    problem = LocalProblem(W, [-1.0, 0.0, 0.0], [0.3], 3)
    with pytest.raises(NotPositiveDefiniteError, match="diagonal entry 1"):
        contactqp.solve(problem)


def test_a_small_sparse_w_is_converted_once():
    problem = random_problem(2, 4, 3)
    sparse = LocalProblem(sp.csr_matrix(problem.W), problem.q, problem.mu, 3)
    assert isinstance(sparse.small.W, np.ndarray)
    twin = sparse.with_q(problem.q * 2)
    assert twin.small is sparse.small  # shared by the twins
    assert_same(solve_coulomb(twin), solve_coulomb(python_route(twin)))


def test_larger_problems_keep_the_python_route():
    problem = random_problem(0, lp.SMALL_UNKNOWNS // 3 + 1, 3)
    assert problem.small is None
    assert solve_coulomb(problem).success


@pytest.mark.parametrize("name", SMALL_FILES)
def test_small_fclib_files_same_iterations_no_worse(name):
    from contactqp.io.fclib import read_any

    path = FCLIB / name
    if not path.exists():
        pytest.skip(f"{name} not in the shared FCLIB data")
    problem = read_any(path)
    local = problem.condense() if problem.kind == "global" else problem
    assert local.small is not None
    fast = contactqp.solve(local)
    slow = contactqp.solve(python_route(local))
    assert fast.success and fast.iterations == slow.iterations
    # no worse than the Python route's error, to rounding of the certificate itself
    assert fast.certificate.natural_map <= max(slow.certificate.natural_map * 1.01, 1e-14)

"""The planar route: Gauss-Seidel with the exact 2-D local solver (contactqp.methods.planar).

Truths used:

* the natural-map error (:func:`~contactqp.core.local_problem.natural_map_error`), computed
  from ``W`` as given and independent of the method: 0 exactly at a solution of the law;
* one contact's problem is solved exactly by one sweep of the local solver (the error is at
  rounding level, 1e-13, after one sweep, on random positive definite blocks of all four cases);
* a second solver, the semismooth Newton method of :mod:`contactqp.methods.coulomb`: on
  problems with a positive definite ``W`` and moderate friction the solution is unique, and the
  two agree to the accuracy asked for (both at 1e-10: agreement to 1e-6 relative, a margin for
  the conditioning of ``W``);
* the pure-numpy kernels (:mod:`contactqp.kernels.pure_numpy`) are the oracle of the compiled
  ones: the same sweeps agree to 1e-10 relative (sums in another order);
* the shared FCLIB 2-D files: converged to 1e-8 as Siconos' NSGS does; the large granular file,
  on which the sweeps stall, is handed to Newton from the cold start and gets Newton's answer
  (and the default route sends it to Newton directly, with Newton's iterations).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp as cq
import contactqp.kernels as kernel_choice
from contactqp.core.local_problem import GlobalProblem, LocalProblem, natural_map_error
from contactqp.errors import InvalidInputError, NotPositiveDefiniteError
from contactqp.io.fclib import read_any
from contactqp.kernels import pure_numpy
from contactqp.methods.coulomb import solve_coulomb
from contactqp.methods.planar import ROUTE_MAX_CONTACTS, SWEEPS, solve_planar
from contactqp.methods.sweeps import kernel_arrays

FCLIB = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"

try:
    from contactqp.kernels import compiled
except ImportError:  # a build without a C compiler: the oracle has nothing to check
    compiled = None


def planar_problem(nc=12, mu=0.3, seed=0, sparse=False, cohesion=None):
    """A 2-D local problem with a positive definite ``W`` (a random Gram matrix plus I)."""
    rng = np.random.default_rng(seed)
    m = 2 * nc
    A = rng.standard_normal((m, m)) / np.sqrt(m)
    W = A @ A.T + 0.5 * np.eye(m)
    q = 0.5 * rng.standard_normal(m)
    q[::2] -= 0.4  # most contacts pressed
    return LocalProblem(sp.csr_matrix(W) if sparse else W, q, np.full(nc, mu), 2, cohesion=cohesion)


@pytest.mark.parametrize("seed", range(40))
def test_one_contact_is_solved_exactly_by_one_sweep(seed):
    rng = np.random.default_rng(seed)
    B = rng.standard_normal((2, 2))
    W = B @ B.T + 0.1 * np.eye(2)
    q = rng.standard_normal(2)
    problem = LocalProblem(W, q, [rng.uniform(0.0, 1.5)], 2)
    r, u = np.zeros(2), np.empty(2)
    (compiled or pure_numpy).planar_gauss_seidel(
        *kernel_arrays(W), W.reshape(1, 4), q, problem.mu, r, u, 0.0, 1, 1, False
    )
    assert natural_map_error(problem, r) <= 1e-13


@pytest.mark.parametrize("sparse", [False, True])
@pytest.mark.parametrize("seed", range(3))
def test_compiled_and_pure_numpy_sweeps_agree(sparse, seed):
    if compiled is None:
        pytest.skip("the compiled kernels are not built here")
    problem = planar_problem(nc=9, seed=seed, sparse=sparse)
    arrays = kernel_arrays(problem.W)
    runs = []
    for kernels in (compiled, pure_numpy):
        blocks = np.empty((9, 4))
        kernels.planar_blocks(*arrays, blocks)
        x = np.random.default_rng(seed).standard_normal(18)
        product, magnitude = np.empty(18), np.empty(18)
        kernels.row_products(*arrays, x, product, magnitude)
        r, u = np.zeros(problem.q.size), np.empty(problem.q.size)
        sweeps, error = kernels.planar_gauss_seidel(
            *arrays, blocks, problem.q, problem.mu, r, u, 0.0, 7, 1, False
        )
        runs.append((sweeps, error, r, blocks, product, magnitude))
    W = problem.W.toarray() if sparse else problem.W
    np.testing.assert_array_equal(runs[0][3], runs[1][3])
    np.testing.assert_array_equal(runs[0][3][:, 1], np.diagonal(W, 1)[::2])
    for k in (4, 5):  # W x and |W| |x|, to rounding
        np.testing.assert_allclose(runs[0][k], runs[1][k], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(runs[0][4], W @ x, rtol=1e-12, atol=1e-14)
    assert runs[0][0] == runs[1][0] == 7
    np.testing.assert_allclose(runs[0][2], runs[1][2], rtol=1e-10, atol=1e-12)
    assert runs[0][1] == pytest.approx(runs[1][1], rel=1e-8)


@pytest.mark.parametrize("sparse", [False, True])
@pytest.mark.parametrize("mu", [0.0, 0.2, 0.8])
@pytest.mark.parametrize("seed", range(3))
def test_planar_agrees_with_newton(sparse, mu, seed):
    problem = planar_problem(seed=seed, mu=mu, sparse=sparse)
    planar = solve_planar(problem, tol=1e-10)
    newton = solve_coulomb(problem, tol=1e-10)
    assert planar.success and planar.method == "planar"
    assert natural_map_error(problem, planar.forces) <= 1e-10
    scale = np.abs(newton.forces).max()
    np.testing.assert_allclose(planar.forces, newton.forces, atol=1e-6 * scale)


def test_cohesion_is_solved_from_the_apex():
    problem = planar_problem(seed=4, mu=0.5, cohesion=np.full(12, 0.05))
    planar = solve_planar(problem, tol=1e-10)
    newton = solve_coulomb(problem, tol=1e-10)
    assert planar.success and natural_map_error(problem, planar.forces) <= 1e-10
    np.testing.assert_allclose(
        planar.forces, newton.forces, atol=1e-6 * np.abs(newton.forces).max()
    )


def test_per_contact_converges_on_every_contact():
    problem = planar_problem(seed=5)
    q = problem.q.copy()
    q[0] = 50.0  # one wide gap loosens the FCLIB measure for the others
    problem = problem.with_q(q)
    result = solve_planar(problem, tol=1e-9, per_contact=True)
    assert result.success
    assert natural_map_error(problem, result.forces, per_contact=True) <= 1e-9


def test_warm_start_at_a_solution_stops_at_once():
    problem = planar_problem(seed=6)
    cold = solve_planar(problem, tol=1e-10)
    again = solve_planar(problem, r0=cold.forces, tol=1e-10)
    assert again.success and again.iterations <= 1


def test_default_route_of_2d_problems_is_planar_and_coulomb_stays_callable():
    problem = planar_problem(seed=7)
    assert cq.solve(problem).method == "planar"
    assert cq.solve(problem, method="coulomb").method == "coulomb"
    three_d = LocalProblem(np.eye(3), [-1.0, 0.1, 0.0], [0.3], 3)
    # 3-D: the spatial route where the compiled kernels are built, else coulomb
    expected = "coulomb" if kernel_choice.spatial_solve is None else "spatial"
    assert cq.solve(three_d).method == expected


def test_global_2d_problem_takes_the_planar_route(monkeypatch):
    """Where the compiled global route gives no answer (here: switched off), a small 2-D global
    problem is condensed and solved by the planar route."""
    monkeypatch.setattr(kernel_choice, "global_small", None)
    rng = np.random.default_rng(8)
    n, nc = 10, 4
    B = rng.standard_normal((n, n))
    M = B @ B.T / n + np.eye(n)
    H = rng.standard_normal((n, 2 * nc))
    w = np.zeros(2 * nc)
    w[::2] = -0.3
    problem = GlobalProblem(M, H, rng.standard_normal(n), w, np.full(nc, 0.4), 2)
    result = cq.solve(problem, tol=1e-10)
    assert result.method == "planar" and result.success
    assert problem.certify(result.forces).error <= 1e-10


def test_bad_problems_are_refused():
    with pytest.raises(InvalidInputError, match="2-D"):
        solve_planar(LocalProblem(np.eye(3), [-1.0, 0.0, 0.0], [0.3], 3))
    W = np.array([[1.0, 3.0], [3.0, 1.0]])  # its symmetric part is indefinite
    with pytest.raises(NotPositiveDefiniteError, match="contact 0"):
        solve_planar(LocalProblem(W, [-1.0, 0.0], [0.3], 2))


@pytest.mark.parametrize(
    "name", ["FrictionContactProblem00071.dat", "FrictionContactProblem00374.dat"]
)
def test_shared_2d_files_converge_by_sweeps(name):
    problem = read_any(FCLIB / name)
    result = cq.solve(problem)
    assert result.method == "planar" and result.success
    assert natural_map_error(problem, result.forces) <= 1e-8
    assert result.iterations <= SWEEPS


def test_a_stall_is_handed_to_newton_from_the_cold_start():
    """The rounded rigid granular file: the sweeps' rate would need thousands of sweeps."""
    problem = read_any(FCLIB / "fc2d_granularflowonwall_02020_00213.dat")
    result = solve_planar(problem)
    newton = solve_coulomb(problem)
    assert result.success and result.method == "coulomb" and "stalled" in result.message
    sweeps = result.iterations - newton.iterations
    assert 0 < sweeps <= 50
    np.testing.assert_array_equal(result.forces, newton.forces)


def test_large_2d_problems_go_to_newton_directly():
    """More contacts than ROUTE_MAX_CONTACTS: the default is coulomb, with its iterations."""
    problem = read_any(FCLIB / "fc2d_granularflowonwall_02020_00213.dat")
    assert problem.n_contacts > ROUTE_MAX_CONTACTS
    result = cq.solve(problem)
    newton = solve_coulomb(problem)
    assert result.method == "coulomb" and result.success
    assert result.iterations == newton.iterations

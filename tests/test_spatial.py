"""The spatial route: 3-D Gauss-Seidel with a local solver by cases, Newton on a stall.

Truths used:

* the certificate: every answer's natural-map error is recomputed here by
  :func:`~contactqp.core.local_problem.natural_map_error` on the problem as given;
* a second solver: the semismooth Newton method ``coulomb`` on the same problems. On a positive
  definite ``W`` with moderate friction the solution is unique, so both give the same reactions
  and contact states;
* one-contact problems whose case is known in closed form (open, stick, frictionless) and a
  slip whose answer satisfies the law by construction;
* the shared FCLIB files of 3-D contacts (other codes' test problems), certified as read.
"""

import re
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp
from contactqp import kernels
from contactqp.core.local_problem import LocalProblem, natural_map_error
from contactqp.errors import InvalidInputError, NotPositiveDefiniteError
from contactqp.io.fclib import read_any
from contactqp.methods import spatial
from contactqp.methods.dispatch import resolve
from contactqp.methods.spatial import solve_spatial

FCLIB = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"

compiled = pytest.mark.skipif(
    kernels.spatial_solve is None, reason="compiled kernels not built: no sweeps to check"
)


def random_problem(seed, nc, *, coupling=0.3, mu=(0.1, 0.8), cohesion=False, sparse=False):
    """A positive definite ``W`` coupling neighbouring contacts, and a ``q`` mixing open,
    sticking and sliding contacts."""
    rng = np.random.default_rng(seed)
    m = 3 * nc
    blocks = rng.standard_normal((nc, 3, 3))
    W = np.zeros((m, m))
    for i in range(nc):
        W[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = blocks[i] @ blocks[i].T / 3 + np.eye(3)
    for i in range(nc - 1):  # a chain: each contact couples to the next
        C = coupling * rng.standard_normal((3, 3)) / 3
        W[3 * i : 3 * i + 3, 3 * i + 3 : 3 * i + 6] = C
        W[3 * i + 3 : 3 * i + 6, 3 * i : 3 * i + 3] = C.T
    q = rng.standard_normal(m)
    q[::3] = np.where(rng.random(nc) < 0.3, 0.5, -1.0)
    friction = rng.uniform(*mu, nc)
    c = np.where(rng.random(nc) < 0.5, 0.1, 0.0) if cohesion else None
    return LocalProblem(sp.csr_matrix(W) if sparse else W, q, friction, 3, cohesion=c)


@compiled
@pytest.mark.parametrize("sparse", [False, True])
@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("nc", [1, 4, 30])
def test_sweeps_give_newtons_solution(seed, nc, sparse):
    problem = random_problem(seed, nc, sparse=sparse)
    result = solve_spatial(problem, tol=1e-10)
    newton = contactqp.solve(problem, method="coulomb", tol=1e-10)
    assert result.success and result.method == "spatial", result.message
    assert natural_map_error(problem, result.forces) <= 1e-10
    scale = np.abs(newton.forces).max()
    np.testing.assert_allclose(result.forces, newton.forces, atol=1e-7 * scale)
    np.testing.assert_array_equal(result.contact_status, newton.contact_status)


@compiled
@pytest.mark.parametrize("seed", range(4))
def test_cohesion_per_contact_and_frictionless_contacts(seed):
    problem = random_problem(seed, 12, cohesion=True)
    mu = problem.mu.copy()
    mu[::4] = 0.0  # frictionless contacts beside cohesive ones
    c = np.where(mu > 0, problem.cohesion, 0.0)
    problem = LocalProblem(problem.W, problem.q, mu, 3, cohesion=c)
    for options in ({"per_contact": True, "tol": 1e-10}, {"tol": 1e-9}):
        result = solve_spatial(problem, **options)
        newton = contactqp.solve(problem, method="coulomb", **options)
        assert result.success and result.method == "spatial", result.message
        expected = natural_map_error(problem, result.forces, per_contact=options["tol"] == 1e-10)
        assert result.certificate.natural_map == pytest.approx(expected, rel=1e-6, abs=1e-15)
        scale = np.abs(newton.forces).max()
        np.testing.assert_allclose(result.forces, newton.forces, atol=1e-6 * scale)


@compiled
def test_one_contact_cases():
    W = np.array([[2.0, 0.3, 0.1], [0.3, 1.5, 0.2], [0.1, 0.2, 1.2]])
    opened = solve_spatial(LocalProblem(W, np.array([0.5, 1.0, -2.0]), np.array([0.5]), 3))
    assert opened.iterations == 0 and np.all(opened.forces == 0.0)  # r = 0 meets tol: no sweep
    q = -W @ np.array([1.0, 0.1, -0.1])  # u = 0 at r = (1, 0.1, -0.1), inside the cone
    stuck = solve_spatial(LocalProblem(W, q, np.array([0.5]), 3))
    np.testing.assert_allclose(stuck.forces, [1.0, 0.1, -0.1], rtol=1e-12)
    frictionless = solve_spatial(LocalProblem(W, np.array([-1.0, 3.0, 1.0]), np.array([0.0]), 3))
    np.testing.assert_allclose(frictionless.forces, [0.5, 0.0, 0.0], rtol=1e-15)
    # a slip by construction: r on the cone's surface, u = W r + q along -r_T, u_N = 0
    r = np.array([1.0, 0.3, -0.4])  # |r_T| = 0.5 = mu r_N
    u = np.array([0.0, -0.6, 0.8])
    slipping = solve_spatial(LocalProblem(W, u - W @ r, np.array([0.5]), 3), tol=1e-12)
    assert slipping.iterations == 1  # one contact: the first sweep solves it
    np.testing.assert_allclose(slipping.forces, r, rtol=1e-10)


def newton_stops_short(W, q, mu):
    """The problems (index) of a one-contact batch on which the compiled Newton run stops
    short of 1e-12 in 50 iterations."""
    P = q.shape[0]
    counts, reasons, errors = np.empty(P, np.intp), np.empty(P, np.intp), np.empty(P)
    r = np.zeros((P, 3))
    kernels.small_newton(
        W, q, mu, np.zeros((P, 3)), r, 1e-12, 50, False, 1e-3, counts, reasons, errors
    )
    return np.flatnonzero(reasons != 0)


@compiled
def test_a_slip_newton_misses_is_found_by_its_direction():
    # ill-conditioned one-contact problems with mu near 1: the one-contact Newton run stalls on
    # some; the local solver's cases solve each in the first sweep, a slip by its direction
    rng = np.random.default_rng(3)
    P = 4000
    A = rng.standard_normal((P, 3, 3))
    W = A @ A.transpose(0, 2, 1) + 0.5 * np.eye(3)
    q, mu = rng.standard_normal((P, 3)), rng.uniform(0.5, 1.0, (P, 1))
    hard = newton_stops_short(W, q, mu)
    slips = 0
    for p in hard:
        problem = LocalProblem(W[p], q[p], mu[p], 3)
        result = solve_spatial(problem, tol=1e-12)
        assert result.method == "spatial" and result.iterations == 1, result.message
        r = result.forces
        assert natural_map_error(problem, r) <= 1e-12  # recomputed from the problem
        if result.status_labels == ["slip"]:  # on the cone, u_N = 0, u_T along -r_T
            slips += 1
            u, scale = W[p] @ r + q[p], np.abs(q[p]).max()
            assert np.hypot(r[1], r[2]) == pytest.approx(mu[p, 0] * r[0], rel=1e-12)
            assert abs(u[0]) <= 1e-12 * scale
            assert abs(u[1] * r[2] - u[2] * r[1]) <= 1e-12 * scale * np.abs(r).max()
            assert u[1:] @ r[1:] < 0
    assert slips >= 2  # the draw has slips that Newton misses


@compiled
def test_stalled_sweeps_hand_over_to_newton(monkeypatch):
    problem = random_problem(1, 30)
    monkeypatch.setattr(spatial, "SWEEPS", 2)  # a budget the sweeps cannot meet
    result = solve_spatial(problem, tol=1e-10)
    assert result.success and result.method == "coulomb"
    stop = re.match(
        r"gauss-seidel 2 sweeps \(stalled; error (\S+)\), then converged", result.message
    )
    assert stop and float(stop[1]) > 1e-10  # where the sweeps stopped short
    assert natural_map_error(problem, result.forces) <= 1e-10


@compiled
def test_a_bad_diagonal_block_is_named():
    problem = random_problem(2, 5)
    W = problem.W.copy()
    W[6:9, 6:9] = np.diag([1.0, -0.5, 1.0])
    bad = LocalProblem(W, problem.q, problem.mu, 3)
    with pytest.raises(NotPositiveDefiniteError, match="block of contact 2 .*diagonal entry 1"):
        solve_spatial(bad)


def test_two_dimensional_problems_are_refused():
    problem = LocalProblem(np.eye(2), np.array([-1.0, 0.0]), np.array([0.3]), 2)
    with pytest.raises(InvalidInputError, match="solves 3-D problems"):
        solve_spatial(problem)


def test_without_the_compiled_kernels_it_is_newton(monkeypatch):
    problem = random_problem(3, 6)
    monkeypatch.setattr(kernels, "spatial_solve", None)
    result = solve_spatial(problem)
    assert result.success and result.method == "coulomb"
    assert resolve(problem)[1].name == "coulomb"  # the default route does not take it then


@compiled
def test_the_default_route_takes_it_up_to_its_size():
    small = random_problem(0, spatial.ROUTE_MAX_CONTACTS)
    assert resolve(small)[1].name == "spatial"
    assert resolve(small, "coulomb")[1].name == "coulomb"  # a method named runs as asked
    large = random_problem(0, spatial.ROUTE_MAX_CONTACTS + 1)
    assert resolve(large)[1].name == "coulomb"
    start = np.full(small.q.size, 0.01)
    kept = start.copy()
    assert contactqp.solve(small, r0=start).success
    np.testing.assert_array_equal(start, kept)  # the warm start is read, not written


SHARED_3D = [
    "FrictionContact3D_1c.dat",
    "FC3D_Example1.dat",
    "FC3D_Example1_SBM.dat",
    "Rover1041.dat",
    "Rover4516.dat",
    "NESpheres_30_1.dat",
    "Confeti-ex13-Fc3D-SBM.dat",
    "local_problem_test.hdf5",
    "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5",
    "Box_Stacks-i0035-31-0.hdf5",
    "Box_Stacks-i0122-82-5.hdf5",
    "LMGC_GlobalFrictionContactProblem00046.hdf5",
]


@compiled
@pytest.mark.parametrize("name", SHARED_3D)
def test_shared_files_are_certified_as_read(name):
    given = read_any(FCLIB / name)
    problem = given.condense() if given.kind == "global" else given
    result = solve_spatial(problem)
    assert result.success, result.message
    assert natural_map_error(problem, result.forces) <= 1e-8
    if given.kind == "global":  # and the default route, judged on the global equations
        assert given.certify(contactqp.solve(given).forces).error <= 1e-8

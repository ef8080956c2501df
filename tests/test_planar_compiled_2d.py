"""The compiled 2-D route (:func:`contactqp.kernels.compiled.planar_solve` through
:func:`contactqp.methods.planar.solve_planar`, the default of 2-D local problems).

Truths used:

* the exact solution of small 2-D problems by enumeration of the contact states. In the plane
  the Coulomb law with unilateral contact is a linear complementarity problem: each contact is
  open (``r = 0``, ``u_N >= 0``), sticks (``u = 0``, ``|r_T| <= mu r_N``) or slips either way
  (``u_N = 0``, ``r_T = -s mu r_N``, ``s u_T >= 0``, ``r_N >= 0``). Solving the ``4^n`` linear
  systems and keeping those whose inequalities hold finds every solution; with a symmetric,
  diagonally dominant ``W`` and ``mu <= 0.3`` there is exactly one (the test asserts it);
* the same method driven from Python over the pure-numpy-capable sweeps (the route taken when
  the compiled solve is absent, forced here by setting ``kernels.planar_solve`` to None): its
  error is evaluated on another schedule, so the two stop at different sweeps; both certified to
  ``tol`` = 1e-10, their reactions agree to 1e-6 of the largest (a margin of 1e4 over ``tol``
  for the conditioning of ``W``);
* the certificate of :mod:`contactqp.core.local_problem`, computed from ``r`` alone and ``W``
  as given: the compiled route's natural-map error, accuracy limits and contact status must be
  those figures (up to the rounding the certificate itself states: sums in another order);
* Newton's answer (:func:`~contactqp.methods.coulomb.solve_coulomb`) on the shared 2-D FCLIB
  files, whose solutions are unique (the two answers' distance falls with ``tol``: 2e-7 of the
  largest reaction at 1e-8, 2e-11 at 1e-12); compared at 1e-10 to 1e-6.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp as cq
from contactqp import kernels
from contactqp.core.local_problem import (
    LocalProblem,
    accuracy_limits,
    contact_status,
    natural_map_error,
)
from contactqp.errors import NotPositiveDefiniteError
from contactqp.io.fclib import read_any
from contactqp.methods.coulomb import solve_coulomb
from contactqp.methods.planar import solve_planar

FCLIB = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
SHARED_2D = ["FrictionContactProblem00071.dat", "FrictionContactProblem00374.dat"]

#: The tests that compare the compiled solve with the Python-driven sweeps need it; the others
#: check whichever route this build has.
needs_compiled = pytest.mark.skipif(
    kernels.planar_solve is None, reason="compiled kernels not built: no compiled solve to check"
)
ROUTES = ["compiled", "python"]


def route(name, monkeypatch):
    """Select the route ``name``: the compiled solve, or the sweeps driven from Python."""
    if name == "compiled" and kernels.planar_solve is None:
        pytest.skip("compiled kernels not built: no compiled solve to check")
    if name == "python":
        monkeypatch.setattr(kernels, "planar_solve", None)


def small_problem(seed, nc=4, mu=0.3, sparse=False):
    """A 2-D problem with a symmetric, diagonally dominant ``W`` and mixed contact states."""
    rng = np.random.default_rng(seed)
    m = 2 * nc
    A = rng.standard_normal((m, m))
    S = 0.3 * (A @ A.T) / m
    W = S + np.diag(np.abs(S).sum(axis=1) + 0.2)  # strictly diagonally dominant, SPD
    q = rng.standard_normal(m)
    q[::2] -= 0.5  # most contacts pressed
    return LocalProblem(sp.csr_matrix(W) if sparse else W, q, np.full(nc, mu), 2)


def enumerate_solutions(problem):
    """Every solution of a small 2-D problem, by the linear system of each state combination."""
    W = problem.W.toarray() if sp.issparse(problem.W) else np.asarray(problem.W)
    q, mu = problem.q, problem.mu
    m = q.size
    scale = max(1.0, np.abs(q).max())
    eps = 1e-10 * scale
    solutions = []
    for states in itertools.product(range(4), repeat=mu.size):
        A = np.zeros((m, m))
        b = np.zeros(m)
        for i, state in enumerate(states):
            n, t = 2 * i, 2 * i + 1
            if state == 0:  # open: r = 0
                A[n, n] = A[t, t] = 1.0
            else:  # closed: u_N = 0
                A[n], b[n] = W[n], -q[n]
                if state == 1:  # stick: u_T = 0
                    A[t], b[t] = W[t], -q[t]
                else:  # slip with sign s of u_T: r_T + s mu r_N = 0
                    A[t, t], A[t, n] = 1.0, (1.0 if state == 2 else -1.0) * mu[i]
        try:
            r = np.linalg.solve(A, b)
        except np.linalg.LinAlgError:
            continue
        u = W @ r + q
        feasible = True
        for i, state in enumerate(states):
            rn, rt, un, ut = r[2 * i], r[2 * i + 1], u[2 * i], u[2 * i + 1]
            if state == 0:
                feasible &= un >= -eps
            elif state == 1:
                feasible &= rn >= -eps and abs(rt) <= mu[i] * rn + eps
            else:
                feasible &= rn >= -eps and (1.0 if state == 2 else -1.0) * ut >= -eps
        if feasible and not any(np.allclose(r, s, atol=1e-8 * scale) for s in solutions):
            solutions.append(r)
    return solutions


@pytest.mark.parametrize("name", ROUTES)
@pytest.mark.parametrize("sparse", [False, True])
@pytest.mark.parametrize("mu", [0.1, 0.3])
@pytest.mark.parametrize("seed", range(6))
def test_planar_gives_the_exact_solution_found_by_enumeration(seed, mu, sparse, name, monkeypatch):
    route(name, monkeypatch)
    problem = small_problem(seed, mu=mu, sparse=sparse)
    solutions = enumerate_solutions(problem)
    assert len(solutions) == 1  # the problem is well posed: one solution
    exact = solutions[0]
    result = solve_planar(problem, tol=1e-12)
    assert result.success and result.method == "planar"
    scale = max(1.0, np.abs(exact).max())
    np.testing.assert_allclose(result.forces, exact, atol=1e-9 * scale)
    np.testing.assert_allclose(result.displacements, problem.W @ exact + problem.q, atol=1e-9)


def test_enumeration_sees_every_state():
    """The enumeration's problems are not trivial: open, stick and slip contacts all occur."""
    seen = set()
    for seed in range(6):
        for mu in (0.1, 0.3):
            problem = small_problem(seed, mu=mu)
            seen.update(contact_status(problem, enumerate_solutions(problem)[0]).tolist())
    assert seen == {0, 1, 2}


def random_problem(seed, nc=30, mu=0.3, sparse=False, cohesion=None):
    """A 2-D problem with a sparse-ish positive definite ``W`` (a banded Gram matrix plus I)."""
    rng = np.random.default_rng(seed)
    m = 2 * nc
    A = np.triu(np.tril(rng.standard_normal((m, m)), 4), -4) / 3.0  # band: blocks to skip
    W = A @ A.T + 0.5 * np.eye(m)
    q = 0.5 * rng.standard_normal(m)
    q[::2] -= 0.4
    return LocalProblem(sp.csr_matrix(W) if sparse else W, q, np.full(nc, mu), 2, cohesion=cohesion)


CASES = [
    dict(sparse=False, mu=0.3),
    dict(sparse=True, mu=0.3),
    dict(sparse=True, mu=0.9),
    dict(sparse=False, mu=0.0),
    dict(sparse=True, mu=0.5, cohesion=0.05),
]


@needs_compiled
@pytest.mark.parametrize("case", range(len(CASES)))
@pytest.mark.parametrize("per_contact", [False, True])
def test_compiled_and_python_driven_sweeps_agree(case, per_contact, monkeypatch):
    kwargs = dict(CASES[case])
    cohesion = kwargs.pop("cohesion", None)
    problem = random_problem(
        case, cohesion=None if cohesion is None else np.full(30, cohesion), **kwargs
    )
    compiled = solve_planar(problem, tol=1e-10, per_contact=per_contact)
    monkeypatch.setattr(kernels, "planar_solve", None)
    python = solve_planar(problem, tol=1e-10, per_contact=per_contact)
    for result in (compiled, python):
        assert result.success and result.method == "planar"
        assert natural_map_error(problem, result.forces, per_contact=per_contact) <= 1e-10
    scale = np.abs(python.forces).max()
    np.testing.assert_allclose(compiled.forces, python.forces, atol=1e-6 * scale)


@pytest.mark.parametrize("name", ROUTES)
@pytest.mark.parametrize("case", range(len(CASES)))
def test_the_certificate_is_that_of_the_problem_as_given(case, name, monkeypatch):
    route(name, monkeypatch)
    kwargs = dict(CASES[case])
    cohesion = kwargs.pop("cohesion", None)
    problem = random_problem(
        10 + case, cohesion=None if cohesion is None else np.full(30, cohesion), **kwargs
    )
    result = solve_planar(problem, tol=1e-9)
    r = result.forces
    u = np.asarray(problem.W @ r).ravel() + problem.q
    limits = accuracy_limits(problem, r, u)
    certificate = result.certificate
    # the same sums in another order: they differ by rounding, which the limits estimate
    np.testing.assert_allclose(result.displacements, u, rtol=0, atol=1e-14 * np.abs(u).max())
    assert abs(certificate.natural_map - natural_map_error(problem, r)) <= 10 * limits.rounding
    assert certificate.limits.rounding == pytest.approx(limits.rounding, rel=1e-9)
    assert certificate.limits.data == pytest.approx(limits.data, rel=1e-9)
    np.testing.assert_array_equal(result.contact_status, contact_status(problem, r))
    assert result.success == (natural_map_error(problem, r) <= 1e-9)


@pytest.mark.parametrize("name", SHARED_2D)
def test_shared_2d_files_are_certified_and_equal_newton(name):
    """The default route, compiled where built."""
    problem = read_any(FCLIB / name)
    result = cq.solve(problem)  # the default route, at its tol 1e-8
    assert result.method == "planar" and result.success
    assert natural_map_error(problem, result.forces) <= 1e-8  # the problem as read
    assert result.certificate.natural_map <= 1e-8
    fine = solve_planar(problem, tol=1e-10)
    newton = solve_coulomb(problem, tol=1e-10)
    assert fine.success and natural_map_error(problem, fine.forces) <= 1e-10
    scale = np.abs(newton.forces).max()
    np.testing.assert_allclose(fine.forces, newton.forces, atol=1e-6 * scale)
    np.testing.assert_array_equal(fine.contact_status, newton.contact_status)


@needs_compiled
@pytest.mark.parametrize("name", SHARED_2D)
def test_shared_2d_files_take_no_more_sweeps_than_before(name, monkeypatch):
    """The compiled route stops no later than the Python-driven sweeps (the former route)."""
    problem = read_any(FCLIB / name)
    compiled = cq.solve(problem)
    monkeypatch.setattr(kernels, "planar_solve", None)
    python = cq.solve(problem)
    assert compiled.success and python.success
    assert compiled.iterations <= python.iterations
    scale = np.abs(python.forces).max()
    np.testing.assert_allclose(compiled.forces, python.forces, atol=1e-6 * scale)


@pytest.mark.parametrize("name", ROUTES)
def test_a_spent_budget_is_reported_not_converged(name, monkeypatch):
    route(name, monkeypatch)
    problem = read_any(FCLIB / "FrictionContactProblem00071.dat")
    result = solve_planar(problem, max_iter=3)
    assert not result.success and result.iterations == 3
    assert "budget spent" in result.message and result.method == "planar"
    assert result.certificate.natural_map == pytest.approx(
        natural_map_error(problem, result.forces), rel=1e-6
    )


@pytest.mark.parametrize("name", ROUTES)
def test_duplicate_entries_of_a_sparse_w_are_summed(name, monkeypatch):
    """A CSR ``W`` may store an entry twice (its value is the sum), on the diagonal too."""
    route(name, monkeypatch)
    dense = small_problem(3, nc=4)
    W = np.asarray(dense.W)
    rows, cols = np.nonzero(W)
    values = W[rows, cols]
    halves = np.concatenate([0.5 * values, 0.5 * values])  # every entry stored as two halves
    order = np.argsort(np.concatenate([rows, rows]), kind="stable")
    indices = np.concatenate([cols, cols])[order]
    indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=W.shape[0]) * 2)])
    twice = sp.csr_matrix((halves[order], indices, indptr), shape=W.shape)
    assert twice.nnz == 2 * values.size and np.allclose(twice.toarray(), W)
    problem = LocalProblem(twice, dense.q, dense.mu, 2)
    result = solve_planar(problem, tol=1e-12)
    exact = enumerate_solutions(dense)[0]
    assert result.success
    np.testing.assert_allclose(result.forces, exact, atol=1e-9 * max(1.0, np.abs(exact).max()))


@pytest.mark.parametrize("name", ROUTES)
def test_warm_start_at_the_solution_needs_no_sweep_beyond_the_first(name, monkeypatch):
    route(name, monkeypatch)
    problem = random_problem(20, sparse=True)
    cold = solve_planar(problem, tol=1e-10)
    again = solve_planar(problem, r0=cold.forces, tol=1e-10)
    assert again.success and again.iterations <= 1


@needs_compiled
def test_an_open_problem_is_solved_at_the_start():
    """``q_N >= 0`` everywhere: ``r = 0`` solves it, and the error at the cold start says so."""
    problem = LocalProblem(np.eye(4) + 0.1, [0.5, 0.3, 0.2, -0.1], [0.3, 0.3], 2)
    result = solve_planar(problem)
    assert result.success and result.iterations == 0
    np.testing.assert_array_equal(result.forces, np.zeros(4))
    np.testing.assert_array_equal(result.contact_status, [0, 0])


@needs_compiled
def test_a_block_indefinite_once_its_duplicates_are_summed_is_refused():
    """``W_00`` stored as -1.9 and 2.0 is 0.1: with the coupling 1 the block is indefinite."""
    W = sp.csr_matrix(
        (np.array([-1.9, 2.0, 1.0, 1.0, 1.0]), np.array([0, 0, 1, 0, 1]), np.array([0, 3, 5])),
        shape=(2, 2),
    )
    assert np.allclose(W.toarray(), [[0.1, 1.0], [1.0, 1.0]])
    with pytest.raises(NotPositiveDefiniteError, match="contact 0"):
        solve_planar(LocalProblem(W, [-1.0, 0.0], [0.3], 2))


@pytest.mark.parametrize("name", ROUTES)
@pytest.mark.parametrize("sparse", [False, True])
def test_a_problem_without_contacts_is_solved(sparse, name, monkeypatch):
    route(name, monkeypatch)
    W = sp.csr_matrix((0, 0)) if sparse else np.zeros((0, 0))
    result = solve_planar(LocalProblem(W, np.zeros(0), np.zeros(0), 2))
    assert result.success and result.forces.shape == (0,)
    assert result.certificate.natural_map == 0.0


@pytest.mark.parametrize("name", ROUTES)
def test_strided_and_fortran_ordered_arrays_are_read(name, monkeypatch):
    """``mu`` a strided view and ``W`` in Fortran order: the same answer as contiguous ones."""
    route(name, monkeypatch)
    base = random_problem(30, nc=6)
    W = np.asfortranarray(base.W)
    mu = np.repeat(base.mu, 2)[::2]
    assert not mu.flags.c_contiguous and not W.flags.c_contiguous
    result = solve_planar(LocalProblem(W, base.q, mu, 2), tol=1e-12)
    reference = solve_planar(base, tol=1e-12)
    assert result.success
    np.testing.assert_allclose(result.forces, reference.forces, rtol=0, atol=1e-12)

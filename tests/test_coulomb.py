"""The Coulomb (Mohr-Coulomb) solver of local problems ``u = W r + q``.

Truths used:

* closed forms for one contact with ``W = diag(a, b[, b])``: open (``q_N >= 0``: ``r = 0``), stick
  (``r = -W^-1 q`` inside the cone) or slip (``r_N = -q_N / a``, ``r_T`` on the cone opposite to
  ``q_T``); the same with cohesion, the cone's apex moved to ``r_N = -c / mu``;
* a second algorithm, nonsmooth Gauss-Seidel run alone, on problems whose solution is unique
  (``W`` symmetric positive definite and well conditioned, small ``mu``);
* the natural-map error, recomputed from ``(r, W r + q)`` outside the solver, on every FCLIB file;
* finite differences for the Alart-Curnier Jacobian blocks.

Tolerances: solutions to ``tol = 1e-12`` agree with closed forms to 1e-9 relative (the error bound
times the condition number of ``W``, at most 1e3 here).
"""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import example, given, settings
from hypothesis import strategies as st

import contactqp.core.local_problem
from contactqp import solve
from contactqp.core.local_problem import (
    LocalProblem,
    check_positive_semidefinite,
    contact_status,
    natural_map_error,
)
from contactqp.core.status import ContactStatus
from contactqp.errors import InvalidInputError, NotPositiveDefiniteError
from contactqp.io import read_problem
from contactqp.methods import coulomb
from contactqp.methods.coulomb import ACTIVE_SET_MIN, alart_curnier, solve_coulomb
from contactqp.methods.pgs import GaussSeidel

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
FILES = sorted(p.name for p in DATA.iterdir() if p.suffix in (".dat", ".hdf5"))


def one_contact(a, b, q, mu, cohesion=0.0):
    """Closed-form solution for ``W = diag(a, b[, b])``; returns (r, status)."""
    q = np.asarray(q, dtype=float)
    s = cohesion / mu if cohesion else 0.0
    qn = q[0] - a * s  # the problem seen from the cone apex: q~ = q - W s e_N
    qt = q[1:]
    if qn >= 0:
        return np.concatenate([[-s], np.zeros_like(qt)]), "open"
    rn = -qn / a
    rt = -qt / b
    if np.linalg.norm(rt) <= mu * rn:
        return np.concatenate([[rn - s], rt]), "stick"
    rt = -mu * rn * qt / np.linalg.norm(qt)
    return np.concatenate([[rn - s], rt]), "slip"


coefficient = st.floats(0.1, 10.0)
component = st.floats(-10.0, 10.0).filter(lambda x: abs(x) > 1e-3)


@settings(max_examples=150, deadline=None)
@given(
    dim=st.sampled_from([2, 3]),
    a=coefficient,
    b=coefficient,
    mu=st.floats(0.05, 2.0),
    q=st.lists(component, min_size=3, max_size=3),
    sparse=st.booleans(),
)
@example(dim=2, a=0.1, b=0.99999, mu=0.1, q=[-1.0, 1.0, 0.0], sparse=False)  # slips by 1e-5
def test_one_contact_closed_forms(dim, a, b, mu, q, sparse):
    q = np.array(q[:dim])
    W = np.diag([a] + [b] * (dim - 1))
    problem = LocalProblem(sp.csr_matrix(W) if sparse else W, q, [mu], dim)
    solution = solve_coulomb(problem, tol=1e-12)
    expected, status = one_contact(a, b, q, mu)
    assert solution.success and solution.certificate.natural_map <= 1e-12
    np.testing.assert_allclose(solution.forces, expected, rtol=0, atol=1e-9 * (1 + np.abs(q).max()))
    np.testing.assert_allclose(
        solution.displacements, W @ solution.forces + q, rtol=0, atol=1e-12 * 10
    )
    # on the cone edge stick and slip are the same point: a slip velocity below the status's
    # threshold (1e-6 of max(a, b) times the force scale, see contact_status) is "zero"
    w = max(a, b)
    force = max(np.linalg.norm(expected), np.linalg.norm(q) / w)
    velocity = np.linalg.norm(q[1:]) - b * mu * max(-q[0], 0) / a
    if abs(velocity) > 1e-5 * w * force:
        assert solution.status_labels == [status]


@pytest.mark.parametrize("dim", [2, 3])
def test_cohesion_turns_slip_into_stick(dim):
    # W = diag(2, 4[, 4]), q = (-2, 6[, 0]): r_N = 1, stick would need ||r_T|| = 1.5 <= mu + c
    W = np.diag([2.0] + [4.0] * (dim - 1))
    q = np.array([-2.0, 6.0, 0.0][:dim])
    without = solve_coulomb(LocalProblem(W, q, [0.5], dim), tol=1e-12)
    np.testing.assert_allclose(without.forces[:2], [1.0, -0.5], atol=1e-10)  # slips on mu r_N = 0.5
    assert without.status_labels == ["slip"]
    sticky = LocalProblem(W, q, [0.5], dim, cohesion=[1.2])
    with_c = solve_coulomb(sticky, tol=1e-12)
    np.testing.assert_allclose(with_c.forces[:2], [1.0, -1.5], atol=1e-10)  # 1.5 <= 0.5 + 1.2
    assert with_c.status_labels == ["stick"] and with_c.certificate.natural_map <= 1e-12
    # the cohesionless answer is wrong for the cohesive problem, and the measure says so
    assert natural_map_error(sticky, without.forces) > 1e-3
    slipping = LocalProblem(W, q, [0.5], dim, cohesion=[0.7])
    slip = solve_coulomb(slipping, tol=1e-12)
    np.testing.assert_allclose(slip.forces[:2], [1.0, -1.2], atol=1e-10)  # ||r_T|| = 0.5 + 0.7
    assert slip.status_labels == ["slip"]


@settings(max_examples=100, deadline=None)
@given(
    dim=st.sampled_from([2, 3]),
    a=coefficient,
    b=coefficient,
    mu=st.floats(0.05, 2.0),
    c=st.floats(0.0, 5.0),
    q=st.lists(component, min_size=3, max_size=3),
)
def test_cohesion_closed_forms(dim, a, b, mu, c, q):
    q = np.array(q[:dim])
    W = np.diag([a] + [b] * (dim - 1))
    problem = LocalProblem(W, q, [mu], dim, cohesion=[c])
    # the error is measured from the apex, c/mu away: rounding costs ~eps * c/mu in absolute terms
    tol = 1e-12 * (1 + c / mu)
    solution = solve_coulomb(problem, tol=tol)
    expected, _ = one_contact(a, b, q, mu, c)
    assert solution.success
    np.testing.assert_allclose(
        solution.forces, expected, rtol=0, atol=1e-9 * (1 + np.abs(expected).max())
    )
    assert natural_map_error(problem, expected) <= tol


def test_open_cohesive_contact_holds_tension_until_its_strength():
    # q_N = 1 > 0 pulls the contact open; cohesion c = 1, mu = 0.5: tensile strength c/mu = 2,
    # reached only if a * 2 < q_N
    W = np.eye(3)
    held = solve_coulomb(LocalProblem(W, [1.0, 0.0, 0.0], [0.5], 3, cohesion=[1.0]), tol=1e-12)
    np.testing.assert_allclose(held.forces, [-1.0, 0.0, 0.0], atol=1e-12)  # u_N = 0, in tension
    assert held.status_labels == ["stick"]
    broken = solve_coulomb(LocalProblem(W, [3.0, 0.0, 0.0], [0.5], 3, cohesion=[1.0]), tol=1e-12)
    np.testing.assert_allclose(broken.forces, [-2.0, 0.0, 0.0], atol=1e-12)
    assert broken.status_labels == ["open"]


def assert_mohr_coulomb_law(problem, r, u, atol):
    """The cohesive Coulomb law checked contact by contact, without the natural map."""
    d, nc = problem.dim, problem.n_contacts
    R, U = r.reshape(nc, d), u.reshape(nc, d)
    mu, c = problem.mu, problem.cohesion
    rt, ut = np.linalg.norm(R[:, 1:], axis=1), np.linalg.norm(U[:, 1:], axis=1)
    bound = mu * R[:, 0] + c
    assert np.all(rt <= bound + atol) and np.all(bound >= -atol)  # inside the cone
    assert np.all(U[:, 0] >= -atol)  # no interpenetration
    carrying = bound > atol  # reaction away from the apex: closed contact
    np.testing.assert_allclose(U[carrying, 0], 0.0, atol=atol)
    sliding = ut > atol  # slip: on the cone's edge, opposite to the slip velocity
    np.testing.assert_allclose(
        R[sliding, 1:], -(bound / ut)[sliding, None] * U[sliding, 1:], atol=atol
    )
    return carrying, sliding


@pytest.mark.parametrize("dim", [2, 3])
def test_cohesive_solution_obeys_the_law_contact_by_contact(dim):
    base = random_problem(15, dim, seed=11)
    cohesion = np.random.default_rng(5).uniform(0.0, 0.3, 15)
    problem = LocalProblem(base.W, base.q, base.mu, dim, cohesion=cohesion)
    solution = solve_coulomb(problem, tol=1e-12)
    assert solution.success
    carrying, sliding = assert_mohr_coulomb_law(
        problem, solution.forces, solution.displacements, 1e-9
    )
    assert carrying.any() and sliding.any() and (carrying & ~sliding).any()
    np.testing.assert_array_equal(solution.contact_status == ContactStatus.SLIP, sliding & carrying)


def random_problem(nc, dim, seed, mu=0.3, sparse=False):
    """A well-conditioned SPD W (condition number < 10) and a q that closes most contacts."""
    rng = np.random.default_rng(seed)
    m = nc * dim
    A = rng.standard_normal((m, m)) / np.sqrt(m)
    W = A @ A.T * 0.5 + np.eye(m)
    q = 0.3 * rng.standard_normal(m)
    q[::dim] -= 0.5
    W = sp.csr_matrix(W) if sparse else W
    return LocalProblem(W, q, np.full(nc, mu), dim)


def gauss_seidel_alone(problem, tol, sweeps=5000):
    gs = GaussSeidel(problem.W, problem.q, problem.mu, problem.dim)
    r = np.zeros_like(problem.q)
    for _ in range(sweeps):
        r = gs.sweep(r)
        if natural_map_error(problem, r) <= tol:
            return r
    raise AssertionError("Gauss-Seidel did not converge")


@pytest.mark.parametrize("dim, sparse", [(2, False), (3, False), (3, True)])
def test_newton_agrees_with_gauss_seidel_where_unique(dim, sparse):
    problem = random_problem(12, dim, seed=3, sparse=sparse)
    solution = solve_coulomb(problem, tol=1e-12)
    assert solution.success and "gauss-seidel" not in solution.message
    assert set(solution.status_labels) == {"open", "stick", "slip"}  # every regime is exercised
    reference = gauss_seidel_alone(problem, 1e-13)
    np.testing.assert_allclose(
        solution.forces, reference, rtol=0, atol=1e-9 * np.abs(reference).max()
    )


def test_dense_and_sparse_newton_matrices_give_the_same_solution(monkeypatch):
    # a small sparse W is factored dense; lift the thresholds to run the SuperLU paths (Newton
    # and the PSD check), on a full W and on one with missing blocks (diagonally dominant, so SPD)
    monkeypatch.setattr(contactqp.core.local_problem, "DENSE_SIZE", 0)
    monkeypatch.setattr(contactqp.core.local_problem, "DENSE_FILL", 2.0)
    base = random_problem(10, 3, seed=7)
    pattern = np.kron(np.random.default_rng(1).random((10, 10)) < 0.3, np.ones((3, 3)))
    holes = base.W * np.maximum(pattern, pattern.T) + 3 * np.eye(30)
    for W in (base.W, holes):
        d = solve_coulomb(LocalProblem(W, base.q, base.mu, 3), tol=1e-12)
        s = solve_coulomb(LocalProblem(sp.csr_matrix(W), base.q, base.mu, 3), tol=1e-12)
        assert d.success and s.success
        np.testing.assert_allclose(s.forces, d.forces, rtol=0, atol=1e-10 * np.abs(d.forces).max())


def test_warm_start():
    problem = read_problem(DATA / "Capsules-i97-269.hdf5")
    cold = solve_coulomb(problem)
    assert cold.success
    again = solve_coulomb(problem, r0=cold.forces)
    assert again.iterations == 0 and again.certificate.natural_map == cold.certificate.natural_map
    rng = np.random.default_rng(0)
    near = solve_coulomb(
        problem, r0=cold.forces * (1 + 1e-4 * rng.standard_normal(cold.forces.size))
    )
    assert near.success and near.iterations < cold.iterations


def test_gauss_seidel_rounds_finish_what_newton_cannot(monkeypatch):
    # one Newton iteration per run cannot reach 1e-10 from zero; the Gauss-Seidel sweeps between
    # rounds must, and land on the (unique) solution
    problem = random_problem(12, 3, seed=3)
    reference = solve_coulomb(problem, tol=1e-12)
    monkeypatch.setattr(coulomb, "RUN_ITERATIONS", 1)
    solution = solve_coulomb(problem, tol=1e-10)
    assert solution.success and "gauss-seidel" in solution.message
    assert "levenberg-marquardt 1 it." in solution.message
    np.testing.assert_allclose(
        solution.forces, reference.forces, rtol=0, atol=1e-7 * np.abs(reference.forces).max()
    )


def test_non_convergence_is_reported_not_hidden():
    # W = 0 is positive semidefinite, but with q_N < 0 no reaction can close the contact:
    # u = q whatever r, so the problem has no solution (the iterates grow without bound and the
    # relative error falls like 1/||r||, but never to tol)
    problem = LocalProblem(np.zeros((3, 3)), [-1.0, 0.5, 0.0], [0.3], 3)
    solution = solve_coulomb(problem, max_iter=150)
    assert not solution.success and solution.iterations <= 150
    assert solution.certificate.natural_map == natural_map_error(problem, solution.forces) > 1e-8
    assert "not converged" in solution.message and "gauss-seidel" in solution.message
    assert f"{solution.certificate.natural_map:.2e}" in solution.message
    # steps are accepted on the absolute residual: with the relative error as the test, 100
    # full steps let r grow until the ratio fell below 1e-8 and the solver claimed success
    assert not solve_coulomb(problem).success


@pytest.mark.parametrize("dim", [2, 3])
def test_alart_curnier_jacobian_matches_finite_differences(dim):
    rng = np.random.default_rng(dim)
    nc = 200
    R = rng.standard_normal((nc, dim))
    U = rng.standard_normal((nc, dim))
    mu = rng.uniform(0.1, 1.0, nc)
    rho = rng.uniform(0.5, 2.0, nc)
    _, A, B = alart_curnier(R, U, mu, rho, jacobian=True)
    h = 1e-7
    for k in range(dim):
        e = np.zeros(dim)
        e[k] = h
        dr = (alart_curnier(R + e, U, mu, rho) - alart_curnier(R - e, U, mu, rho)) / (2 * h)
        du = (alart_curnier(R, U + e, mu, rho) - alart_curnier(R, U - e, mu, rho)) / (2 * h)
        # contacts within h of a kink have one-sided derivatives: leave them out
        smooth = np.all(np.abs(dr - A[:, :, k]) < 1e-3, axis=1) | np.all(
            np.abs(du - B[:, :, k]) < 1e-3, axis=1
        )
        assert smooth.mean() > 0.97
        np.testing.assert_allclose(dr[smooth], A[smooth, :, k], atol=1e-6)
        np.testing.assert_allclose(du[smooth], B[smooth, :, k], atol=1e-6)
    # each of the three regimes occurs in the sample
    Phi = alart_curnier(R, U, mu, rho)
    assert np.any(A[:, 0, 0] == 1) and np.any(A[:, 0, 0] == 0) and Phi.shape == R.shape


@pytest.mark.parametrize("name", FILES)
def test_every_fclib_file_is_solved(name):
    problem = read_problem(DATA / name)
    solution = solve(problem, tol=1e-8)
    assert solution.success, solution.message
    # the README's measure, recomputed from r alone (u = W r + q) outside the solver
    assert natural_map_error(problem, solution.forces) <= 1e-8
    assert np.array_equal(contact_status(problem, solution.forces), solution.contact_status)


@pytest.mark.parametrize("cohesion", [0.0, 0.4])
def test_contact_status_does_not_depend_on_units(cohesion):
    # the same problem in newtons and metres with W ~ 1e-6 m/N (stiff contacts): reactions of
    # ~1e3 N, slips of ~1e-5 m. The status used to call "zero" any velocity below 1e-6 times
    # the largest of ||q||, ||r||, ||u||, i.e. 1e-3 m here: every slip was labelled stick
    base = random_problem(12, 3, seed=3)
    c = np.full(12, cohesion)
    reference = solve_coulomb(LocalProblem(base.W, base.q, base.mu, 3, cohesion=c), tol=1e-13)
    assert reference.success and {"stick", "slip"} <= set(reference.status_labels)
    force, length = 1e3, 1e-5  # N and m per unit of the dimensionless problem
    si = LocalProblem(base.W * (length / force), base.q * length, base.mu, 3, cohesion=c * force)
    status = contact_status(si, reference.forces * force, reference.displacements * length)
    np.testing.assert_array_equal(status, reference.contact_status)


def test_frictionless_problems_stay_on_the_box_qp():
    problem = random_problem(8, 3, seed=3, mu=0.0)
    solution = solve(problem)
    assert solution.success and "newton" not in solution.message
    assert np.all(solution.forces.reshape(8, 3)[:, 1:] == 0)
    frictional = solve(random_problem(8, 3, seed=3, mu=0.3))
    assert frictional.success and frictional.method in ("spatial", "coulomb")  # with friction


@pytest.mark.parametrize("symmetric", [True, False])
def test_frictionless_route_reads_a_dense_w_as_a_sparse_one(symmetric):
    # a dense W is read through strided views of its normal columns, a sparse one through its
    # CSR columns: the same answer and the same certificate, judged on the whole W
    dense_problem = random_problem(40, 3, seed=11, mu=0.0)
    W = dense_problem.W
    if not symmetric:  # as a file written with few digits: unsymmetric at 1e-6
        W = W * (1 + 1e-6 * np.random.default_rng(5).standard_normal(W.shape))
        dense_problem = LocalProblem(W, dense_problem.q, dense_problem.mu, 3)
    sparse_problem = LocalProblem(sp.csr_matrix(W), dense_problem.q, dense_problem.mu, 3)
    a, b = solve(dense_problem, tol=1e-10), solve(sparse_problem, tol=1e-10)
    assert a.success and b.success, (a.message, b.message)
    assert a.method == b.method == "normal-qp"
    np.testing.assert_allclose(a.forces, b.forces, rtol=0, atol=1e-12 * np.abs(b.forces).max())
    for solution in (a, b):
        u = W @ solution.forces + dense_problem.q
        np.testing.assert_allclose(solution.displacements, u, rtol=0, atol=1e-13)
        error = natural_map_error(dense_problem, solution.forces)
        assert error <= 1e-10
        assert solution.certificate.natural_map == pytest.approx(error, rel=1e-3, abs=1e-16)
    np.testing.assert_array_equal(a.contact_status, b.contact_status)
    limits_a, limits_b = a.certificate.limits, b.certificate.limits
    assert limits_a.rounding == pytest.approx(limits_b.rounding, rel=1e-12)


# --- bad input ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"mu": [-0.1]}, "mu must be >= 0"),
        ({"cohesion": [-1.0]}, "cohesion must be >= 0"),
        ({"cohesion": [np.nan]}, "cohesion contains NaN"),
        ({"cohesion": [1.0, 2.0]}, "cohesion must have length"),
        ({"mu": [0.0], "cohesion": [1.0]}, "cohesion > 0 needs mu > 0"),
        ({"q": [np.nan, 0.0, 0.0]}, "q contains NaN"),
    ],
)
def test_invalid_problems(kwargs, match):
    args = {"W": np.eye(3), "q": [-1.0, 0.0, 0.0], "mu": [0.3], "dim": 3} | kwargs
    with pytest.raises(InvalidInputError, match=match) as info:
        LocalProblem(**args)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "W, match",
    [
        (np.array([[1.0, 0, 0], [0, 1.0, 2.0], [0, 2.0, 1.0]]), "Cholesky"),
        (sp.csr_matrix(np.array([[1.0, 0, 0], [0, 1.0, 2.0], [0, 2.0, 1.0]])), "Cholesky"),
        (np.diag([1.0, -1e-3, 1.0]), "diagonal entry 1 is -0.001"),
        (np.array([[1.0, 0, 0], [0, 0.0, 1.0], [0, 1.0, 1.0]]), "zero diagonal"),
    ],
)
def test_indefinite_w_is_refused(W, match):
    problem = LocalProblem(W, [-1.0, 0.0, 0.0], [0.3], 3)
    with pytest.raises(NotPositiveDefiniteError, match=match):
        solve_coulomb(problem)
    with pytest.raises(NotPositiveDefiniteError, match=match):
        solve(problem)
    # without friction only the normal block is solved on, and validated: the same matrix as
    # the normal block of three contacts (tangential blocks the identity) is refused alike
    normal = np.arange(3) * 3
    frictionless = sp.lil_matrix(sp.identity(9)) if sp.issparse(W) else np.eye(9)
    frictionless[np.ix_(normal, normal)] = W.toarray() if sp.issparse(W) else W
    q = np.zeros(9)
    q[normal] = [-1.0, -1.0, -1.5]  # its solution (1, 2/3, 1/6) frees the indefinite block
    with pytest.raises(NotPositiveDefiniteError, match=f"W's normal block.*{match}"):
        solve(LocalProblem(frictionless, q, np.zeros(3), 3))


def _one_indefinite_block(contact: int, nc: int = 100):
    """A dense problem of ``nc`` uncoupled contacts (enough for the candidate sets), ``W`` the
    identity but for an indefinite tangential block at ``contact``; contact 0 is pressed, the
    others open."""
    assert nc >= ACTIVE_SET_MIN
    W = np.eye(3 * nc)
    W[3 * contact + 1, 3 * contact + 2] = W[3 * contact + 2, 3 * contact + 1] = 2.0
    q = np.zeros(3 * nc)
    q[::3] = 1.0
    q[0], q[1] = -1.0, 0.2
    return LocalProblem(W, q, np.full(nc, 0.3), 3)


def test_candidate_sets_check_the_blocks_they_solve_on():
    # the indefinite block is the pressed contact's: the first candidate set holds it
    with pytest.raises(NotPositiveDefiniteError, match="block of the candidate contacts"):
        solve_coulomb(_one_indefinite_block(0))
    # it is an open contact's, which no candidate set takes: the answer is certified on the
    # whole problem, where only contact 0 carries force; all of W is indeed indefinite
    problem = _one_indefinite_block(50)
    result = solve_coulomb(problem)
    assert result.success and natural_map_error(problem, result.forces) <= 1e-8
    assert np.count_nonzero(result.forces.reshape(-1, 3).any(axis=1)) == 1
    with pytest.raises(NotPositiveDefiniteError):
        check_positive_semidefinite(problem.W)


def test_frictionless_route_needs_only_a_semidefinite_normal_block():
    # W is indefinite in its tangential block only; with mu = 0 the tangential reactions
    # vanish and the problem is the QP on W_NN = [[1]]: solved, and certified on the whole W
    W = np.array([[1.0, 0, 0], [0, 1.0, 2.0], [0, 2.0, 1.0]])
    for matrix in (W, sp.csr_matrix(W)):
        problem = LocalProblem(matrix, [-1.0, 0.0, 0.0], [0.0], 3)
        solution = solve(problem, tol=1e-12)
        assert solution.success, solution.message
        np.testing.assert_allclose(solution.forces, [1.0, 0.0, 0.0], atol=1e-14)
        assert natural_map_error(problem, solution.forces) <= 1e-12


def test_psd_check_accepts_singular_and_rounded_matrices():
    check_positive_semidefinite(np.zeros((3, 3)))
    v = np.array([1.0, 2.0, 3.0])
    check_positive_semidefinite(np.outer(v, v))  # rank one
    # 6-digit rounding leaves the granular file's W indefinite at -2.7e-6 (scaled): accepted
    check_positive_semidefinite(read_problem(DATA / "fc2d_granularflowonwall_02020_00213.dat").W)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"tol": 0.0}, "tol must be a positive"),
        ({"tol": float("nan")}, "tol must be a positive"),
        ({"max_iter": 0}, "max_iter must be an integer >= 1"),
        ({"r0": [1.0, 0.0]}, r"r0 must have shape \(3,\)"),
        ({"r0": [np.inf, 0.0, 0.0]}, "r0 contains NaN"),
    ],
)
def test_invalid_options(kwargs, match):
    with pytest.raises(InvalidInputError, match=match):
        solve_coulomb(LocalProblem(np.eye(3), [-1.0, 0.0, 0.0], [0.3], 3), **kwargs)


def test_numpy_scalars_are_valid_options():
    # as for the Tresca and polygonal routes (numbers.Real / numbers.Integral)
    problem = LocalProblem(np.eye(3), [-1.0, 0.0, 0.0], [0.3], 3)
    solution = solve_coulomb(problem, tol=np.float32(1e-8), max_iter=np.int64(5))
    assert solution.success
    np.testing.assert_allclose(solution.forces, [1.0, 0.0, 0.0], atol=1e-12)

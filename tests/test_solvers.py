"""The own dual active-set solver against the primal QP through qpsolvers, and the certificate."""

import numpy as np
import pytest
import qpsolvers
from hypothesis import given, settings
from hypothesis import strategies as st

import contactqp as cq
from contactqp.methods.box_qp import solve_box_qp


def random_problem(n, seed, dofs_per_node=1):
    rng = np.random.default_rng(seed)
    B = rng.standard_normal((n, n))
    R = B @ B.T / n + np.eye(n) * rng.uniform(0.05, 1.0)
    model = cq.ReducedModel(flexibility=R * 1e-6, dofs_per_node=dofs_per_node)
    loads = rng.standard_normal(n) * 1e3
    gaps = rng.uniform(-1e-4, 1e-3, model.n_nodes)
    directions = rng.standard_normal((model.n_nodes, dofs_per_node))
    return cq.ContactProblem(model, loads, [cq.GapObstacle(range(model.n_nodes), gaps, directions)])


@settings(max_examples=25, deadline=None)
@given(n=st.integers(1, 500), seed=st.integers(0, 2**32 - 1))
def test_own_solver_agrees_with_primal_qp(n, seed):
    # Independent truth: the primal QP on displacements, solved by quadprog (an exact dual active
    # set method of Goldfarb and Idnani) on K = R^-1, versus the own method on W = A R A^T.
    problem = random_problem(n, seed)
    own = cq.solve(problem)
    reference = cq.solve(problem, "qp", backend="quadprog")
    assert own.success and reference.success, (own.message, reference.message)
    scale_u = np.max(np.abs(reference.displacements))
    scale_f = max(np.max(np.abs(reference.forces)), np.max(np.abs(problem.loads)))
    assert np.max(np.abs(own.displacements - reference.displacements)) <= 1e-8 * scale_u
    assert np.max(np.abs(own.forces - reference.forces)) <= 1e-8 * scale_f
    assert own.certificate.worst < 1e-9


@pytest.mark.parametrize("backend", ["clarabel", "piqp", "daqp"])
def test_qp_backends_agree_on_two_freedom_nodes(backend):
    problem = random_problem(120, 7, dofs_per_node=2)
    own = cq.solve(problem)
    other = cq.solve(problem, "qp", backend=backend)
    assert own.success and other.success
    np.testing.assert_allclose(
        other.displacements, own.displacements, atol=1e-7 * np.max(np.abs(own.displacements))
    )


def test_single_contact_closed_form():
    # one freedom, flexibility r, load P, gap g: U = min(rP, g), force = max(P - g/r, 0)
    r, P, g = 2e-6, 1500.0, 1e-3
    result = cq.solve_gaps([[r]], [P], [g])
    assert result.success
    assert result.displacements[0] == pytest.approx(g, rel=1e-12)
    assert result.forces[0] == pytest.approx(P - g / r, rel=1e-12)
    assert result.status_labels == ["closed"]
    assert result.energy == pytest.approx(0.5 * g * g / r - P * g, rel=1e-12)


def test_certificate_rejects_a_wrong_answer():
    problem = random_problem(30, 3)
    good = cq.solve(problem)
    wrong = problem.make_result(
        good.displacements * 1.01,
        good.forces,
        method="test",
        converged=True,
        message="tampered",
        iterations=0,
        seconds=0.0,
    )
    assert good.success and not wrong.success and wrong.status == 2
    assert "certificate failed" in wrong.message


def test_stiffness_model_gives_the_same_answer():
    problem = random_problem(40, 11)
    K = np.linalg.inv(problem.model.flexibility)
    model = cq.ReducedModel(stiffness=0.5 * (K + K.T))
    twin = cq.ContactProblem(
        model,
        problem.loads,
        [
            cq.GapObstacle(
                range(40),
                problem.constraints.gaps,
                problem.constraints.matrix.toarray().sum(1)[:, None],
            )
        ],
    )
    a, b = cq.solve(problem), cq.solve(twin)
    assert a.success and b.success
    np.testing.assert_allclose(
        b.displacements, a.displacements, atol=1e-9 * np.max(np.abs(a.displacements))
    )


def test_warm_start_reaches_the_same_answer_in_fewer_iterations():
    problem = random_problem(300, 5)
    cold = cq.solve(problem)
    warm = cq.solve(problem, r0=cold.forces)
    assert warm.success and warm.iterations <= 1 < cold.iterations
    np.testing.assert_allclose(warm.forces, cold.forces, atol=1e-10 * np.max(cold.forces))


def test_box_qp_two_sided_bounds_match_kkt():
    rng = np.random.default_rng(2)
    B = rng.standard_normal((200, 200))
    W = B @ B.T / 200 + 0.01 * np.eye(200)
    c = rng.standard_normal(200)
    s = solve_box_qp(W, c, lower=-0.5, upper=0.3)
    g = W @ s.x + c
    assert s.converged
    assert np.all(s.x >= -0.5) and np.all(s.x <= 0.3)
    free = (s.x > -0.5 + 1e-12) & (s.x < 0.3 - 1e-12)
    assert np.max(np.abs(g[free])) < 1e-9
    assert np.all(g[s.x <= -0.5] >= -1e-9) and np.all(g[s.x >= 0.3] <= 1e-9)


def test_node_pairs_and_plane_obstacle():
    # two bodies on one axis: node 0 pushed by P towards node 1 with gap g; node 1 is held by a
    # spring; hand solution: contact force F = (r0 P - g) / (r0 + r1) when positive
    r0, r1, P, g = 1e-6, 3e-6, 2000.0, 1e-3
    model = cq.ReducedModel(flexibility=np.diag([r0, r1]), coordinates=[[0.0], [1.0]])
    problem = cq.ContactProblem(model, [P, 0.0], [cq.NodePairs([[0, 1]], [g], [1.0])])
    result = cq.solve(problem)
    assert result.forces[0] == pytest.approx((r0 * P - g) / (r0 + r1), rel=1e-12)
    plane = cq.ContactProblem(model, [P, 0.0], [cq.PlaneObstacle([0.0005], [1.0], nodes=[0])])
    assert cq.solve(plane).displacements[0] == pytest.approx(0.0005, rel=1e-12)


def test_unknown_solver_is_a_clear_error():
    with pytest.raises(
        cq.InvalidInputError,
        match="unknown method 'nope' for frictionless problems; choose one of "
        "active-set \\(default\\), qp",
    ):
        cq.solve(random_problem(3, 0), "nope")


@pytest.mark.parametrize("seed", range(6))
def test_lawson_hanson_agrees_with_quadprog(seed):
    from contactqp.methods.lawson_hanson import solve_nonnegative_qp

    rng = np.random.default_rng(seed)
    n = 60
    B = rng.standard_normal((n, n))
    S = B @ B.T + 0.1 * n * np.eye(n)
    q = rng.standard_normal(n) * 5
    solution = solve_nonnegative_qp(S, q)
    x, converged = solution.x, solution.converged
    expected = qpsolvers.solve_qp(S, -q, lb=np.zeros(n), solver="quadprog")
    assert converged
    np.testing.assert_allclose(x, expected, atol=1e-9 * np.max(np.abs(expected)))
    solution = solve_nonnegative_qp(S, q, x0=expected + 0.1)
    warm, converged = solution.x, solution.converged
    assert converged
    np.testing.assert_allclose(warm, expected, atol=1e-9 * np.max(np.abs(expected)))

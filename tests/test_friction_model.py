"""Frictional reduced models: frames, local form, laws, certificate and bad input.

Truths used: orthonormality of the frames; the frictionless dual form (W_NN = A R A^T, q_N = -b);
displacements recomputed from U = R (P + H^T r); single-contact solutions enumerated case by case
(open, stick, slip either way); closed forms of one contact with cohesion and with polygonal cones;
two solver routes (Coulomb Newton and Tresca fixed point).
"""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import contactqp as cq
from contactqp.core.contact import local_frames, tangent_basis
from contactqp.core.local_problem import natural_map_error


def one_node(stiffness=None, coords=(0.0, 0.0), flexibility=None):
    return cq.ReducedModel(
        stiffness=stiffness,
        flexibility=flexibility,
        dofs_per_node=len(coords),
        coordinates=[coords],
    )


def floor(dim):
    normal = [0.0] * (dim - 1) + [-1.0]
    return cq.PlaneObstacle(point=[0.0] * dim, normal=normal)


# ----------------------------------------------------------------------------------- frames


@settings(max_examples=50, deadline=None)
@given(dim=st.sampled_from([2, 3]), data=st.data())
def test_frames_are_orthonormal_and_right_handed(dim, data):
    v = np.array(data.draw(st.lists(st.floats(-1, 1), min_size=dim, max_size=dim)))
    if np.linalg.norm(v) < 1e-3:
        v[-1] = 1.0
    n = (v / np.linalg.norm(v))[None, :]
    frame = np.vstack([n, tangent_basis(n)[0]])
    np.testing.assert_allclose(frame @ frame.T, np.eye(dim), atol=1e-12)
    assert np.linalg.det(frame[[1, 2, 0]] if dim == 3 else frame) == pytest.approx(1.0)
    np.testing.assert_array_equal(tangent_basis(n), tangent_basis(n.copy()))


def test_frames_of_a_floor_follow_the_axes():
    np.testing.assert_array_equal(tangent_basis([[0.0, -1.0]])[0], [[1.0, 0.0]])
    np.testing.assert_array_equal(
        tangent_basis([[0.0, 0.0, -1.0]])[0], [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]
    )


def test_local_operator_of_planes_pairs_and_gaps_in_3d():
    rng = np.random.default_rng(1)
    coords = rng.normal(size=(4, 3))
    model = cq.ReducedModel(flexibility=np.eye(12), dofs_per_node=3, coordinates=coords)
    direction = np.array([1.0, 2.0, 2.0]) / 3.0
    obstacles = [
        cq.PlaneObstacle([0, 0, -5.0], [0, 0, -1.0], nodes=[0, 1]),
        cq.NodePairs([[2, 3]], [0.1], direction),
        cq.GapObstacle([3], [0.2], [[0.0, 1.0, 0.0]]),
    ]
    constraints = cq.ContactProblem(model, np.zeros(12), obstacles).constraints
    frames = local_frames(model, constraints)
    H = frames.operator.toarray()
    assert H.shape == (12, 12)
    np.testing.assert_allclose(H[0::3], -constraints.matrix.toarray())
    # rows of one contact are orthonormal (sqrt(2) for the pair, which acts on two nodes)
    gram = np.array([H[3 * i : 3 * i + 3] @ H[3 * i : 3 * i + 3].T for i in range(4)])
    np.testing.assert_allclose(gram, [np.eye(3), np.eye(3), 2 * np.eye(3), np.eye(3)], atol=1e-14)
    # the pair's tangents: +t on node 2, -t on node 3, orthogonal to the pair's direction
    t = frames.tangents[2]
    np.testing.assert_allclose(H[7:9, 6:9], t)
    np.testing.assert_allclose(H[7:9, 9:12], -t)
    np.testing.assert_allclose(t @ direction, 0.0, atol=1e-15)


# ------------------------------------------------------------------------------- local form


def coupled_problem(seed, mu=0.3, given="flexibility", **kwargs):
    """Three 2-D nodes on a floor, coupled through a random SPD compliance."""
    rng = np.random.default_rng(seed)
    B = rng.normal(size=(6, 6))
    R = B @ B.T / 6 + np.eye(6)
    K = np.linalg.inv(R)
    model = cq.ReducedModel(
        **{given: R if given == "flexibility" else 0.5 * (K + K.T)},
        dofs_per_node=2,
        coordinates=np.column_stack([np.arange(3.0), rng.uniform(0, 0.1, 3)]),
    )
    P = np.tile([1.0, -2.0], 3) + rng.normal(scale=0.5, size=6)
    return cq.FrictionalProblem(model, P, [floor(2)], mu=mu, **kwargs)


def test_local_form_extends_the_frictionless_dual_form():
    problem = coupled_problem(0)
    local = problem.local()
    dual = cq.ContactProblem(problem.model, problem.loads, [floor(2)]).dual()
    np.testing.assert_allclose(local.W[0::2, 0::2], dual.W, rtol=1e-12)
    np.testing.assert_allclose(local.q(problem.loads)[0::2], -dual.b, rtol=1e-12)
    H = local.operator.toarray()
    np.testing.assert_allclose(local.W, H @ problem.model.flexibility @ H.T, rtol=1e-12)
    twin = coupled_problem(0, given="stiffness")
    np.testing.assert_allclose(twin.local().W, local.W, rtol=1e-10)


def test_local_coordinates_are_gap_and_tangential_displacement():
    problem = coupled_problem(2)
    r = np.array([3.0, 0.5, 0.0, 0.0, 1.0, -0.2])
    U = problem.model.flexibility @ (problem.loads + problem.local().operator.T @ r)
    u = problem.local_problem().W @ r + problem.local_problem().q
    coords = problem.model.coordinates
    np.testing.assert_allclose(u[0::2], coords[:, 1] + U[1::2], rtol=1e-12)  # floor at y = 0
    np.testing.assert_allclose(u[1::2], U[0::2], rtol=1e-12)  # t = +x for the floor


# ---------------------------------------------------------------- one contact, by enumeration


def enumerate_single_contact(W, q, mu):
    """All solutions (r, u) of one 2-D Coulomb contact, by cases."""
    solutions = []
    if q[0] >= 0:
        solutions.append(np.zeros(2))
    r = -np.linalg.solve(W, q)
    if r[0] >= 0 and abs(r[1]) <= mu * r[0]:
        solutions.append(r)
    for sigma in (1.0, -1.0):  # slip direction: u_T has sign sigma, r_T = -sigma mu r_N
        direction = np.array([1.0, -sigma * mu])
        denominator = W[0] @ direction
        if denominator > 0:
            rn = -q[0] / denominator
            uT = rn * (W[1] @ direction) + q[1]
            if rn > 0 and sigma * uT > 0:
                solutions.append(rn * direction)
    return solutions


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), mu=st.floats(0.0, 1.0))
def test_single_contact_matches_enumeration(seed, mu):
    rng = np.random.default_rng(seed)
    B = rng.normal(size=(2, 2))
    R = B @ B.T + 0.1 * np.eye(2)
    P = rng.normal(size=2) * [1.0, 3.0]
    problem = cq.FrictionalProblem(one_node(flexibility=R), P, [floor(2)], mu=mu)
    step = problem.local_problem()
    exact = enumerate_single_contact(step.W, step.q, mu)
    # the Tresca fixed point s -> mu r_N(s) contracts, while slipping, by mu |W_NT| / W_NN per
    # iteration: a route only where that is below 1/2 (small mu alone is not enough when the
    # normal and tangential responses are strongly coupled, e.g. W_NT / W_NN = 5)
    contracts = mu * abs(step.W[0, 1]) / step.W[0, 0] < 0.5
    for solver in ("coulomb", "tresca") if contracts else ("coulomb",):
        result = cq.solve(problem, solver)
        assert result.success, result.message
        distance = min(np.linalg.norm(result.forces[0] - r) for r in exact)
        assert distance <= 1e-8 * max(1.0, np.max(np.abs(P)))


@pytest.mark.parametrize(
    "Q, slip, status", [(2.9, 0.0, "stick"), (4.0, 0.5, "slip"), (-6.0, -1.5, "slip")]
)
def test_one_spring_sticks_until_mu_n_then_slips(Q, slip, status):
    k, mu, N = 2.0, 0.3, 10.0
    problem = cq.FrictionalProblem(one_node(np.diag([k, 5.0])), [Q, -N], [floor(2)], mu=mu)
    result = cq.solve(problem)
    assert result.success and result.status_labels == [status]
    np.testing.assert_allclose(result.slip[0, 0], slip, atol=1e-12)
    np.testing.assert_allclose(result.forces[0], [N, -np.clip(Q, -mu * N, mu * N)], atol=1e-10)
    assert result.dissipated == pytest.approx(mu * N * abs(slip), abs=1e-10)


@pytest.mark.parametrize("Q", [2.0, 2.9, -7.0])
def test_two_bodies_in_frictional_contact_slip_relative_to_each_other(Q):
    # node 0 above node 1, pressed together by N, sheared by +Q on node 0 and -Q on node 1;
    # each node on its own springs (k tangential, 4 normal)
    k, mu, N, gap = 2.0, 0.3, 10.0, 0.5
    model = cq.ReducedModel(stiffness=np.diag([k, 4.0, k, 4.0]), dofs_per_node=2)
    pair = cq.NodePairs([[0, 1]], [gap], [0.0, -1.0])
    result = cq.solve(cq.FrictionalProblem(model, [Q, -N, -Q, N], [pair], mu=mu))
    assert result.success
    normal = N - 4.0 * gap / 2  # the springs close the gap, the rest is contact force
    friction = np.clip(Q, -mu * normal, mu * normal)
    np.testing.assert_allclose(result.forces[0], [normal, -friction], atol=1e-10)
    np.testing.assert_allclose(
        result.displacements[[0, 2]], [(Q - friction) / k, -(Q - friction) / k], atol=1e-10
    )
    np.testing.assert_allclose(result.slip[0, 0], 2 * (Q - friction) / k, atol=1e-10)
    assert result.status_labels == ["slip" if abs(Q) > mu * normal else "stick"]


def test_mohr_coulomb_cohesion_raises_the_slip_threshold_and_carries_tension():
    k, kn, mu, c, N = 2.0, 5.0, 0.3, 0.5, 10.0
    model = one_node(np.diag([k, kn]))
    shear = cq.solve(cq.FrictionalProblem(model, [4.0, -N], [floor(2)], mu=mu, cohesion=c))
    assert shear.success and shear.status_labels == ["slip"]
    np.testing.assert_allclose(shear.slip[0, 0], (4.0 - mu * N - c) / k, rtol=1e-10)
    np.testing.assert_allclose(shear.forces[0, 1], -(mu * N + c), rtol=1e-10)
    # pulled off the floor: closed while the tension is below c / mu, then open at that tension
    held = cq.solve(cq.FrictionalProblem(model, [0.0, 1.0], [floor(2)], mu=mu, cohesion=c))
    np.testing.assert_allclose([held.forces[0, 0], held.gaps[0]], [-1.0, 0.0], atol=1e-10)
    assert held.status_labels == ["stick"]
    with pytest.warns(cq.ContactWarning, match="no tension cut-off"):
        pulled = cq.solve(cq.FrictionalProblem(model, [0.0, 2.0], [floor(2)], mu=mu, cohesion=c))
    np.testing.assert_allclose(pulled.forces[0], [-c / mu, 0.0], atol=1e-10)
    np.testing.assert_allclose(pulled.gaps[0], (2.0 - c / mu) / kn, rtol=1e-10)
    assert pulled.success and pulled.status_labels == ["open"]


# ----------------------------------------------------------------------------- polygonal cone


@pytest.mark.parametrize("facets", [4, 8])
def test_polygonal_cone_reduces_the_limit_across_a_side_not_at_a_vertex(facets):
    k, mu, N, Q = 2.0, 0.4, 10.0, 7.0
    model = one_node(np.diag([k, k, 3.0]), coords=(0.0, 0.0, 0.0))
    # floor frame: t1 = +x, t2 = -y; side 0 of the polygon faces t1, a vertex lies at pi / F
    vertex = np.array([np.cos(np.pi / facets), -np.sin(np.pi / facets)])
    for direction, limit in (([1.0, 0.0], mu * N * np.cos(np.pi / facets)), (vertex, mu * N)):
        P = np.array([Q * direction[0], Q * direction[1], -N])
        polygonal = cq.solve(cq.FrictionalProblem(model, P, [floor(3)], mu=mu, facets=facets))
        exact = cq.solve(cq.FrictionalProblem(model, P, [floor(3)], mu=mu))
        assert polygonal.success and exact.success, (polygonal.message, exact.message)
        assert polygonal.method == "polygonal" and exact.method == "coulomb"
        local_direction = np.array([direction[0], -direction[1]])
        np.testing.assert_allclose(
            polygonal.tangential_forces[0], -limit * local_direction, atol=1e-7 * N
        )
        np.testing.assert_allclose(polygonal.slip[0], (Q - limit) / k * local_direction, atol=1e-7)
        np.testing.assert_allclose(np.linalg.norm(exact.tangential_forces[0]), mu * N, rtol=1e-9)
        # the polygon is certified against its own law; against the exact cone it is off
        # by the reduction of the limit
        assert (polygonal.certificate.natural_map > 1e-3) == (limit < mu * N)


def test_polygonal_answer_approaches_the_exact_cone_as_facets_grow():
    # a sliding force may turn by up to pi / F from the direction opposite to the slip, so the
    # forces move by O(mu pi / F) relative to the exact cone's
    rng = np.random.default_rng(3)
    B = rng.normal(size=(15, 15))
    model = cq.ReducedModel(
        flexibility=B @ B.T / 15 + np.eye(15),
        dofs_per_node=3,
        coordinates=np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)]),
    )
    P = np.zeros(15)
    P[2::3] = -3.0
    P[0::3], P[1::3] = rng.normal(size=(2, 5))
    mu = 0.3
    exact = cq.solve(cq.FrictionalProblem(model, P, [floor(3)], mu=mu))
    assert exact.success and exact.status_labels.count("slip") >= 2
    errors = {}
    for facets in (8, 16, 32, 64):
        linear = cq.solve(cq.FrictionalProblem(model, P, [floor(3)], mu=mu, facets=facets))
        assert linear.success, linear.message
        errors[facets] = np.abs(linear.forces - exact.forces).max() / np.abs(exact.forces).max()
        assert errors[facets] <= mu * np.pi / facets
    assert errors[64] < errors[8] / 4


def test_polygonal_law_in_2d_is_the_exact_cone():
    exact = cq.solve(coupled_problem(3, mu=0.2))
    linear = cq.solve(coupled_problem(3, mu=0.2, facets=6))
    assert exact.success and linear.success
    # so the certificate checks the 2-D polygonal answer against the natural map as well
    assert linear.certificate.exact_cone and linear.certificate.natural_map <= 1e-7
    np.testing.assert_allclose(linear.forces, exact.forces, atol=1e-8 * np.abs(exact.forces).max())


# -------------------------------------------------------------------------------- certificate


@pytest.mark.parametrize("seed", range(4))
def test_coupled_contacts_agree_across_routes_and_report_every_status(seed):
    # node 0 pressed hard, node 1 sheared hard, node 2 pulled off the floor
    problem = coupled_problem(seed, mu=0.3).with_loads([0.1, -5.0, 3.0, -2.0, 0.0, 4.0])
    results = [cq.solve(problem, name) for name in ("coulomb", "tresca")]
    for result in results:
        assert result.success, result.message
        assert result.status_labels == ["stick", "slip", "open"]
    np.testing.assert_allclose(results[0].forces, results[1].forces, atol=1e-8)
    assert results[0].dissipation[1] > 0 and results[0].dissipation[[0, 2]] == pytest.approx(
        0, abs=1e-9
    )


def test_certificate_rejects_wrong_answers():
    problem = coupled_problem(5)
    good = cq.solve(problem)
    assert good.success
    r = good.forces.copy()
    r[:, 1] *= 1.5  # friction beyond the cone somewhere, or sticking forces changed
    bad = problem.make_result(
        r.ravel(), method="test", converged=True, message="", iterations=0, seconds=0.0
    )
    assert not bad.success and bad.status == 2 and not bad.certificate.passed
    flipped = good.forces.copy()
    flipped[:, 1] *= -1.0  # friction pushing along the slip: no longer maximum dissipation
    wrong = problem.make_result(
        flipped.ravel(), method="test", converged=True, message="", iterations=0, seconds=0.0
    )
    assert wrong.certificate.equilibrium < 1e-12  # U is recomputed from the forces...
    assert not wrong.certificate.passed  # ...but the law is violated


def stiff_contact_beside_a_soft_node(dim, facets=None):
    """A stiff contact node (1e-6 m/N) and a soft node (1 m/N) away from the contact.

    Sheared by 310 N under 1000 N with mu = 0.3, the contact slips by 10 N * 1e-6 m/N = 1e-5 m
    (across side 0 of a polygon, by (310 - 300 cos(pi / F)) * 1e-6 m).
    """
    R = np.diag([1e-6] * dim + [1.0] * dim)
    model = cq.ReducedModel(
        flexibility=R, dofs_per_node=dim, coordinates=[[0.0] * dim, [5.0] + [1.0] * (dim - 1)]
    )
    P = np.zeros(2 * dim)
    P[0], P[dim - 1] = 310.0, -1000.0
    floor_ = cq.PlaneObstacle([0.0] * dim, [0.0] * (dim - 1) + [-1.0], nodes=[0])
    return cq.FrictionalProblem(model, P, [floor_], mu=0.3, facets=facets)


@pytest.mark.parametrize("dim, facets", [(2, None), (3, None), (3, 8)])
def test_a_soft_node_away_from_the_contacts_does_not_blunt_status_or_certificate(dim, facets):
    # the contact's scales are its own (gaps, local displacements, contact forces), not the
    # softest compliance times the largest force (1 m/N * 1000 N = 1000 m, which made a 1e-5 m
    # slip "stick" and accepted a 1e-5 m interpenetration)
    problem = stiff_contact_beside_a_soft_node(dim, facets)
    good = cq.solve(problem)
    assert good.success, good.message
    assert good.status_labels == ["slip"] and good.slip[0, 0] > 9e-6
    wrong = good.forces * 0.99  # 1 % short of the normal force: 1e-5 m interpenetration
    bad = problem.make_result(
        wrong.ravel(), method="test", converged=True, message="", iterations=0, seconds=0.0
    )
    assert bad.gaps[0] == pytest.approx(-1e-5, rel=1e-6)
    assert not bad.success and bad.certificate.penetration > 1e-3


def test_a_large_load_away_from_the_contacts_does_not_blunt_the_cone_check():
    # 1e6 N on a node the contact does not feel, 10 N on the contact: the cone excess was
    # measured against 1e6 N, so friction 1 % beyond a polygonal cone (where the natural map
    # is not a checked residual) passed at 3e-8
    R = np.diag([1e-6] * 3 + [1e-3] * 3)
    model = cq.ReducedModel(
        flexibility=R, dofs_per_node=3, coordinates=[[0.0, 0.0, 0.0], [5.0, 1.0, 1.0]]
    )
    problem = cq.FrictionalProblem(
        model,
        [5.0, 0.0, -10.0, 1e6, 0.0, 0.0],
        [cq.PlaneObstacle([0.0] * 3, [0.0, 0.0, -1.0], nodes=[0])],
        mu=0.3,
        facets=8,
    )
    good = cq.solve(problem)
    assert good.success and good.status_labels == ["slip"], good.message
    wrong = good.forces.copy()
    wrong[0, 1:] *= 1.01
    bad = problem.make_result(
        wrong.ravel(), method="test", converged=True, message="", iterations=0, seconds=0.0
    )
    assert not bad.success and bad.certificate.cone > 1e-3


def test_a_wide_gap_elsewhere_does_not_blunt_the_cone_check():
    # an open contact 1 m away from its obstacle on stiff springs (1e-6 m/N) is no force of
    # 1e6 N: friction 1 % beyond the cone on the loaded contact must still fail
    model = cq.ReducedModel(
        flexibility=1e-6 * np.eye(4), dofs_per_node=2, coordinates=[[0.0, 0.0], [5.0, 0.0]]
    )
    problem = cq.FrictionalProblem(
        model, [5.0, -10.0, 0.0, 0.0], [cq.GapObstacle([0, 1], [0.0, 1.0], [0.0, -1.0])], mu=0.3
    )
    good = cq.solve(problem)
    assert good.success and good.status_labels == ["slip", "open"], good.message
    wrong = good.forces.copy()
    wrong[0, 1] *= 1.01
    bad = problem.make_result(
        wrong.ravel(), method="test", converged=True, message="", iterations=0, seconds=0.0
    )
    assert not bad.success and bad.certificate.cone > 1e-3


def micrometre_contacts(far_gap=None, mu=0.3, facets=None, dim=2):
    """Six coupled nodes on gaps of micrometres; optionally a seventh, decoupled, far away.

    A :class:`FrictionalProblem` (polygonal with ``facets``), or with ``mu=None`` the
    frictionless ``ContactProblem``.
    """
    m = 6 * dim
    rng = np.random.default_rng(0)
    B = rng.normal(size=(m, m))
    R = (B @ B.T / m + np.eye(m)) * 1e-6  # m/N
    gaps = rng.uniform(0.0, 2e-6, 6)
    P = np.tile({2: [0.3, -1.5], 3: [0.3, 0.2, -1.5]}[dim], 6) + rng.normal(scale=0.3, size=m)
    if far_gap is not None:
        R = np.block([[R, np.zeros((m, dim))], [np.zeros((dim, m)), 1e-6 * np.eye(dim)]])
        gaps, P = np.append(gaps, far_gap), np.append(P, np.zeros(dim))
    n = gaps.size
    coordinates = np.zeros((n, dim))
    coordinates[:, 0] = np.arange(float(n))
    model = cq.ReducedModel(flexibility=R, dofs_per_node=dim, coordinates=coordinates)
    obstacles = [cq.GapObstacle(range(n), gaps, -np.eye(dim)[-1])]
    if mu is None:
        return cq.ContactProblem(model, P, obstacles)
    return cq.FrictionalProblem(model, P, obstacles, mu=mu, facets=facets)


@pytest.mark.parametrize(
    "solver, facets, rtol",
    [("coulomb", None, 1e-12), ("tresca", None, 1e-9), ("polygonal", 8, 1e-9)],
)
def test_a_wide_gap_elsewhere_does_not_loosen_the_solution(solver, facets, rtol):
    # a contact 1 m from its obstacle, decoupled from six contacts on micrometre gaps, changes
    # nothing physically. Measured on the whole problem (FCLIB's error), each route stopped when
    # the others were still 1e-5 off; each contact is now also held to its own scale (the 2-D
    # polygon is the exact cone, so all three routes solve the same problem)
    near = cq.solve(micrometre_contacts())
    assert near.success, near.message
    far = micrometre_contacts(far_gap=1.0, facets=facets)
    solved = cq.solve(far, solver)
    assert solved.success and solved.status_labels[-1] == "open", solved.message
    np.testing.assert_allclose(
        solved.forces[:6], near.forces, rtol=0, atol=rtol * np.abs(near.forces).max()
    )
    np.testing.assert_allclose(
        solved.displacements[:12],
        near.displacements,
        rtol=0,
        atol=rtol * np.abs(near.displacements).max(),
    )
    # the same solve stopped on the FCLIB measure alone: the certificate now sees the difference
    loose = cq.solve(far, solver, per_contact=False)
    assert np.abs(loose.forces[:6] - near.forces).max() > 1e-7 * np.abs(near.forces).max()
    assert loose.status == 2 and loose.certificate.natural_map > 1e-6, loose.message


@pytest.mark.parametrize("far_gap", [1e-2, 1.0])
def test_polygonal_cone_in_3d_beside_a_wide_gap(far_gap):
    # the QPs are scaled by the largest q, here the far gap: the micrometre contacts' forces
    # were a 1e-4 to 1e-6 fraction of that scale, and came back 1e-5 to 1e-2 off (at 1 m
    # "not converged"). The first iterate's largest force now rescales the QPs.
    near = cq.solve(micrometre_contacts(facets=8, dim=3))
    far = cq.solve(micrometre_contacts(far_gap=far_gap, facets=8, dim=3))
    assert near.success and far.success, (near.message, far.message)
    assert far.status_labels[-1] == "open"
    np.testing.assert_allclose(
        far.forces[:6], near.forces, rtol=0, atol=1e-9 * np.abs(near.forces).max()
    )


def test_each_contact_is_certified_on_its_own_scales():
    # 1 % too much force on contacts of micrometres: their gaps open by about 1e-8 m while
    # they push. Against the 1 m gap of the far contact that complementarity residual was 1e-8
    # and passed; against each contact's own length it is about 1e-2.
    problem = micrometre_contacts(far_gap=1.0)
    good = cq.solve(problem)
    assert good.success, good.message
    wrong = good.forces.copy()
    wrong[:6] *= 1.01
    bad = problem.make_result(
        wrong.ravel(), method="test", converged=True, message="", iterations=0, seconds=0.0
    )
    assert not bad.success and bad.certificate.complementarity > 1e-3
    # but a rounding-sized force on the open contact is judged against the contacts' forces
    noisy = good.forces.copy()
    noisy[6] = [1e-13, 1e-13]
    fine = problem.make_result(
        noisy.ravel(), method="test", converged=True, message="", iterations=0, seconds=0.0
    )
    assert fine.success and fine.status_labels[6] == "open", fine.message


def test_frictionless_certificate_judges_gaps_on_the_contacts_length():
    # the same soft node blunted the frictionless certificate too: 1e-5 m of interpenetration
    # over 1 m/N * 1000 N passed as 1e-8
    problem = stiff_contact_beside_a_soft_node(2)
    frictionless = cq.ContactProblem(
        problem.model, problem.loads, [cq.PlaneObstacle([0.0, 0.0], [0.0, -1.0], nodes=[0])]
    )
    forces = np.array([990.0])  # 1 % short of the 1000 N the contact carries
    U = frictionless.dual().displacements(forces)
    bad = frictionless.make_result(
        U, forces, method="test", converged=True, message="", iterations=0, seconds=0.0
    )
    assert bad.gaps[0] == pytest.approx(-1e-5, rel=1e-6)
    assert not bad.success and bad.certificate.penetration > 1e-3
    good = frictionless.make_result(
        frictionless.dual().displacements([1000.0]),
        [1000.0],
        method="test",
        converged=True,
        message="",
        iterations=0,
        seconds=0.0,
    )
    assert good.success, good.message


def test_frictionless_certificate_judges_each_contact_on_its_own_length():
    # the frictionless twin of test_each_contact_is_certified_on_its_own_scales
    problem = micrometre_contacts(far_gap=1.0, mu=None)
    good = cq.solve(problem)
    assert good.success, good.message
    wrong = good.forces * 1.01
    bad = problem.make_result(
        problem.dual().displacements(wrong),
        wrong,
        method="test",
        converged=True,
        message="",
        iterations=0,
        seconds=0.0,
    )
    assert not bad.success and bad.certificate.complementarity > 1e-3


# --------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "kwargs, argument",
    [
        ({"mu": -0.1}, "mu"),
        ({"mu": [0.1, np.nan, 0.2]}, "mu"),
        ({"mu": [0.1, 0.2]}, "mu"),
        ({"mu": 0.2, "cohesion": -1.0}, "cohesion"),
        ({"mu": 0.2, "cohesion": np.inf}, "cohesion"),
        ({"mu": 0.0, "cohesion": 1.0}, "cohesion"),
        ({"mu": 0.2, "facets": 2}, "facets"),
        ({"mu": 0.2, "facets": 6.5}, "facets"),
    ],
)
def test_bad_friction_input_names_the_argument(kwargs, argument):
    with pytest.raises(cq.InvalidInputError, match=argument):
        coupled_problem(0, **kwargs)


def test_bad_models_and_solvers_are_clear_errors():
    with pytest.raises(cq.InvalidInputError, match="no tangent"):
        cq.FrictionalProblem(
            cq.ReducedModel(flexibility=np.eye(2)),
            [0.0, 0.0],
            [cq.GapObstacle([0, 1], [0.0, 0.0])],
            mu=0.2,
        )
    mixed = cq.ReducedModel(
        flexibility=np.eye(5), dofs_per_node=[2, 3], coordinates=[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
    )
    with pytest.raises(cq.InvalidInputError, match="one number of freedoms"):
        cq.FrictionalProblem(
            mixed,
            np.zeros(5),
            [cq.GapObstacle([0], [0.0], [0.0, -1.0]), cq.GapObstacle([1], [0.0], [0.0, 0.0, -1.0])],
            mu=0.2,
        )
    with pytest.raises(cq.InvalidInputError, match="loads contains NaN"):
        coupled_problem(0).with_loads(np.full(6, np.nan))
    with pytest.raises(
        cq.InvalidInputError,
        match="'coulomb' does not solve frictional-polygonal problems.*polygonal",
    ):
        cq.solve(coupled_problem(0, facets=8), "coulomb")
    with pytest.raises(
        cq.InvalidInputError, match="unknown method 'magic' for frictional problems.*coulomb"
    ):
        cq.solve(coupled_problem(0), "magic")
    with pytest.raises(cq.InvalidInputError, match="previous"):
        coupled_problem(0).with_loads(np.zeros(6), previous="rest")
    # these raised ValueError from numpy (string loads, forces of the wrong length)
    with pytest.raises(cq.InvalidInputError, match="loads"):
        coupled_problem(0).with_loads(["a"] * 6)
    with pytest.raises(cq.InvalidInputError, match="forces must hold 2 local components"):
        coupled_problem(0).make_result(
            np.zeros(5), method="test", converged=True, message="", iterations=0, seconds=0.0
        )


def test_cohesion_on_a_gapped_contact_is_refused():
    model = cq.ReducedModel(flexibility=np.eye(2) * 1e-3, dofs_per_node=2)
    with pytest.raises(cq.InvalidInputError, match="contact 0 has cohesion 10 N and initial gap"):
        cq.FrictionalProblem(
            model, [0.0, 0.0], [cq.GapObstacle([0], [1e-3], [1.0, 0.0])], mu=0.5, cohesion=10.0
        )


# ------------------------------------------------- the certificate's natural map without W


def _dense_natural_map(problem, result):
    """The FCLIB natural-map error with ``u~ = W~ r~ + q~`` formed from ``W`` (the dense way)."""
    step = problem.step()
    scaled = (result.forces.reshape(-1) + step.apex_shift) / step.force_unit
    return natural_map_error(step.fclib, scaled, per_contact=True)


@pytest.mark.parametrize("seed", [0, 3, 7])
@pytest.mark.parametrize("kwargs", [{}, {"cohesion": 0.4}])
def test_the_certificate_reads_u_from_the_displacements_as_w_r_plus_q(seed, kwargs):
    # u = W r + q = H U + w - (0, (H U_prev)_T) for U = R (P + H^T r): the certificate reads
    # the right-hand side, the dense measure the left; they agree to rounding, at a solution
    # and at a wrong answer alike (1e-9 relative: the errors differ by ~1e-15 of the scale)
    problem = coupled_problem(seed, mu=0.5)
    if kwargs:  # cohesion needs closed contacts: the floor raised above the nodes
        raised = cq.PlaneObstacle(point=[0.0, 0.1], normal=[0.0, -1.0])
        problem = cq.FrictionalProblem(problem.model, problem.loads, [raised], 0.5, **kwargs)
    good = cq.solve(problem)
    assert good.success
    later = problem.with_loads(1.3 * problem.loads, previous=good)  # slips from a state
    for case in (problem, later):
        result = cq.solve(case)
        assert result.success
        r = result.forces.copy()
        r[:, 1] += 0.05 * np.max(np.abs(r))
        with warnings.catch_warnings():  # a wrong answer may pull a cohesive contact open
            warnings.simplefilter("ignore", cq.ContactWarning)
            wrong = case.make_result(
                r.ravel(), method="test", converged=True, message="", iterations=0, seconds=0.0
            )
        for answer in (result, wrong):
            dense = _dense_natural_map(case, answer)
            assert answer.certificate.natural_map == pytest.approx(dense, rel=1e-9, abs=1e-15)
        assert wrong.certificate.natural_map > 1e-4


def test_a_restricted_problem_is_certified_without_forming_its_w():
    problem = coupled_problem(4)
    kept = problem.restricted([2, 0])
    result = cq.solve(kept)  # the dense method forms its W...
    assert result.success and kept.local().formed
    again = problem.restricted([2, 0], loads=2 * problem.loads)
    assert again.local().formed  # the block gathered once is shared by the same contacts'
    fresh = problem.with_gaps(problem.constraints.gaps).restricted([1])
    certified = fresh.make_result(
        np.zeros(2), method="test", converged=True, message="", iterations=0, seconds=0.0
    )
    assert not fresh.local().formed  # ...the certificate does not
    assert certified.certificate.natural_map == pytest.approx(
        _dense_natural_map(fresh, certified), rel=1e-9, abs=1e-15
    )
    np.testing.assert_allclose(fresh.local().diagonal(), np.diag(fresh.local().W), rtol=0)
    np.testing.assert_allclose(fresh.local().W, problem.local().W[2:4, 2:4], rtol=0, atol=0)

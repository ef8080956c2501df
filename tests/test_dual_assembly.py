"""The dual's ``W = A R A^T`` built by indexing, and the model's O(n^2) validation.

``W`` is compared with the dense product ``A R A^T`` formed here independently; the validation
with matrices whose definiteness is known in closed form.
"""

import numpy as np
import pytest

import contactqp as cq
from contactqp.core.problem import ContactProblem
from contactqp.errors import InvalidInputError, NotPositiveDefiniteError


def spd(n, seed=0):
    rng = np.random.default_rng(seed)
    B = rng.standard_normal((n, n))
    return B @ B.T + n * np.eye(n)


def dense_delassus(problem):
    A = problem.constraints.matrix.toarray()
    R = problem.model.flexibility
    return A @ R @ A.T, R @ A.T


@pytest.mark.parametrize(
    "nodes, directions",
    [
        (np.arange(8), (1.0,)),  # the identity: views of R
        (np.array([5, 1, 7, 2]), (1.0,)),  # a selection, out of order
        (np.array([3, 0, 6]), (-1.0,)),  # scales -1
        (np.array([4, 2, 6]), [[1.0], [-1.0], [1.0]]),  # mixed signs
    ],
)
def test_selected_constraints_give_the_dense_product(nodes, directions):
    R = spd(8)
    model = cq.ReducedModel(flexibility=R)
    gaps = np.linspace(-1e-3, 1e-3, nodes.size)
    problem = ContactProblem(model, np.ones(8), [cq.GapObstacle(nodes, gaps, directions)])
    dual = problem.dual()
    W, influence = dense_delassus(problem)
    # the products here round differently from the indexing: a few ulps of max|W|
    np.testing.assert_allclose(dual.W, W, rtol=0, atol=1e-13 * np.abs(W).max())
    np.testing.assert_allclose(dual.influence, influence, rtol=0, atol=1e-13 * np.abs(W).max())
    np.testing.assert_array_equal(dual.W, dual.W.T)  # exactly symmetric, as R is
    A = problem.constraints.matrix.toarray()
    np.testing.assert_allclose(dual.b, A @ R @ np.ones(8) - gaps, rtol=1e-13)


def test_the_identity_shares_r_read_only():
    R = spd(6)
    model = cq.ReducedModel(flexibility=R)
    problem = ContactProblem(model, np.zeros(6), [cq.GapObstacle(np.arange(6), np.zeros(6))])
    dual = problem.dual()
    assert np.shares_memory(dual.W, model.flexibility) and not dual.W.flags.writeable
    with pytest.raises(ValueError):
        dual.W[0, 0] = 0.0
    np.testing.assert_array_equal(model.flexibility, R)
    forces = np.array([0.0, 2.0, 0.0, 1.0, 3.0, 0.0])  # U = R (P - lambda), one triangle read
    np.testing.assert_allclose(dual.displacements(forces), -R @ forces, rtol=1e-14)


def test_scaled_directions_on_two_freedom_nodes_give_the_dense_product():
    # 4 nodes x 2 freedoms; contacts along x on some, along -y on others, and one oblique
    # (two entries in its row: the general product)
    R = spd(8, seed=3)
    model = cq.ReducedModel(flexibility=R, dofs_per_node=2)
    obstacles = [
        cq.GapObstacle([0, 2], [0.0, 1e-4], [[1.0, 0.0], [0.0, -2.0]]),
        cq.GapObstacle([3], [2e-4], [[3.0, 4.0]]),
    ]
    problem = ContactProblem(model, np.zeros(8), obstacles)
    W, influence = dense_delassus(problem)
    np.testing.assert_allclose(problem.dual().W, W, rtol=0, atol=1e-13 * np.abs(W).max())
    np.testing.assert_allclose(problem.dual().influence, influence, rtol=0, atol=1e-13 * R.max())


def test_a_selected_problem_is_solved_as_the_dense_one():
    R = spd(30, seed=5)
    model = cq.ReducedModel(flexibility=R)
    nodes = np.arange(0, 30, 2)
    gaps = np.linspace(-0.02, 0.02, nodes.size)
    result = cq.solve(ContactProblem(model, np.zeros(30), [cq.GapObstacle(nodes, gaps)]))
    assert result.success, result.message
    # the gaps close where lambda > 0: W lambda - b >= 0 and complementary, on the dense W
    W = R[np.ix_(nodes, nodes)]
    slack = W @ result.forces + gaps
    assert slack.min() > -1e-10 * np.abs(gaps).max()
    assert np.abs(slack * result.forces).max() < 1e-10 * np.abs(gaps).max() * result.forces.max()


@pytest.mark.parametrize(
    "matrix, error, message",
    [
        (np.diag([1.0, 0.0, 2.0]), NotPositiveDefiniteError, "diagonal entry 1 is 0"),
        (
            np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 2.0], [0.0, 2.0, 1.0]]),
            NotPositiveDefiniteError,
            r"freedoms 1 and 2.*smallest eigenvalue -1\b",
        ),
        (np.array([[4.0, 2.0], [2.0, 1.0]]), InvalidInputError, "freedoms 0 and 1"),
    ],
)
def test_the_cheap_checks_name_the_failing_entries(matrix, error, message):
    with pytest.raises(error, match=message):
        cq.ReducedModel(flexibility=matrix)


def indefinite_with_definite_pairs():
    """Every 2 x 2 principal block definite, the whole indefinite: ``1 - 0.9 (J - I)`` on 3
    freedoms has eigenvalues 1 + 0.9 (twice) and 1 - 1.8 = -0.8."""
    return np.eye(3) - 0.9 * (np.ones((3, 3)) - np.eye(3))


def test_a_flexibility_is_proven_definite_where_it_is_factored():
    R = indefinite_with_definite_pairs()
    np.testing.assert_allclose(np.linalg.eigvalsh(R)[0], -0.8)
    model = cq.ReducedModel(flexibility=R)  # O(n^2) checks only: accepted
    with pytest.raises(NotPositiveDefiniteError, match="flexibility.*smallest eigenvalue -0.8"):
        _ = model.stiffness
    # a method meeting the indefinite block refuses it
    problem = ContactProblem(model, np.zeros(3), [cq.GapObstacle(np.arange(3), -np.ones(3))])
    with pytest.raises(NotPositiveDefiniteError):
        cq.solve(problem)


def test_a_stiffness_is_factored_at_once():
    with pytest.raises(NotPositiveDefiniteError, match="smallest eigenvalue -0.8"):
        cq.ReducedModel(stiffness=indefinite_with_definite_pairs())


def test_the_tiles_of_the_checks_cover_a_large_matrix(monkeypatch):
    # a symmetry defect and a bad pair in the last tiles are found
    from contactqp.core import model as model_module

    monkeypatch.setattr(model_module, "_TILE", 7)
    R = spd(20, seed=1)
    bad = R.copy()
    bad[19, 3] += 1.0
    with pytest.raises(InvalidInputError, match="not symmetric"):
        cq.ReducedModel(flexibility=bad)
    bad = R.copy()
    bad[18, 19] = bad[19, 18] = 1.01 * np.sqrt(R[18, 18] * R[19, 19])
    with pytest.raises(NotPositiveDefiniteError, match="freedoms 18 and 19"):
        cq.ReducedModel(flexibility=bad)


def test_axis_aligned_frames_are_a_selection_with_the_dense_product():
    # normals along -z: H stores the zero components of -n, t1, t2; W is read off R by indexing
    from contactqp.core.problem import _selection

    R = spd(12, seed=7)
    model = cq.ReducedModel(flexibility=R, dofs_per_node=3)
    obstacle = cq.GapObstacle(np.arange(4), np.zeros(4), (0.0, 0.0, -1.0))
    problem = cq.FrictionalProblem(model, np.zeros(12), [obstacle], mu=0.3)
    H = problem.local().operator
    assert H.nnz > H.shape[0] and _selection(H) is not None  # stored zeros, one nonzero a row
    W = problem.local().W
    dense = H.toarray() @ R @ H.toarray().T
    np.testing.assert_allclose(W, dense, rtol=0, atol=1e-13 * np.abs(dense).max())
    np.testing.assert_array_equal(W, W.T)


def test_scaled_selections_stay_exactly_symmetric():
    from contactqp.core.problem import _selected_delassus

    R = spd(9, seed=8)
    columns, scales = np.array([4, 0, 7, 2]), np.array([0.3, -1.7, 2.9, 1.1])
    influence, W = _selected_delassus(R, columns, scales)
    A = np.zeros((4, 9))
    A[np.arange(4), columns] = scales
    np.testing.assert_allclose(W, A @ R @ A.T, rtol=1e-14)
    np.testing.assert_allclose(influence, R @ A.T, rtol=1e-14)
    np.testing.assert_array_equal(W, W.T)


def test_displacements_from_the_solvers_product_are_those_of_r():
    """With ``A`` the identity the default solver takes ``U = R P - W lambda`` from its last
    gradient instead of a product with ``R``: the displacements equal ``R (P - lambda)``
    formed here, to rounding, and the certificate (which forms ``R f`` itself) passes."""
    n = 40
    R = spd(n, seed=4) * 1e-3
    loads = np.zeros(n)
    gaps = np.linspace(-2e-3, 2e-3, n)  # about half the nodes pressed
    problem = ContactProblem(
        cq.ReducedModel(flexibility=R), loads, [cq.GapObstacle(np.arange(n), gaps, (1.0,))]
    )
    assert problem.dual().influence is problem.dual().W  # the identity: the shared product
    result = cq.solve(problem)
    assert result.success and 0 < np.count_nonzero(result.forces) < n
    expected = R @ (loads - result.forces)
    scale = np.abs(R).max() * np.abs(result.forces).sum()
    np.testing.assert_allclose(result.displacements, expected, rtol=0, atol=1e-12 * scale)

"""core.links: the Woodbury elimination of links, against direct assemblies of the same model.

Elastic links are springs: the truth is the stiffness ``K + E C^-1 E^T`` under the loads
``P + E C^-1 d0``, solved directly. Rigid links are constraints: the truth is the bordered
(KKT) system ``[K -E; E^T 0] [U; f] = [P; d0]``.
"""

import numpy as np
import pytest

from contactqp import ReducedModel
from contactqp.core.links import LinkedModel, Links
from contactqp.errors import InvalidInputError

N, M, P_ROWS = 12, 4, 5


def _spd(rng, n):
    A = rng.standard_normal((n, n))
    return A @ A.T + n * np.eye(n)


def _symmetric(matrix):
    return 0.5 * (matrix + matrix.T)


@pytest.fixture(params=["flexibility", "stiffness"])
def case(request):
    rng = np.random.default_rng(7)
    K = _spd(rng, N) * 1e6  # N/m
    model = (
        ReducedModel(stiffness=K)
        if request.param == "stiffness"
        else ReducedModel(flexibility=_symmetric(np.linalg.inv(K)))
    )
    E = rng.standard_normal((N, M))
    P = rng.standard_normal(N) * 100.0
    d0 = rng.standard_normal(M) * 1e-5
    G = rng.standard_normal((P_ROWS, N))
    return model, K, E, P, d0, G


def test_elastic_links_equal_springs_added_to_the_stiffness(case):
    model, K, E, P, d0, G = case
    c = np.array([1e-6, 2e-7, 5e-6, 1e-7])
    linked = LinkedModel(model, Links(E, c, d0))
    U, f = linked.displacements(P)
    springs = E @ np.diag(1.0 / c) @ E.T
    truth = np.linalg.solve(K + springs, P + E @ (d0 / c))
    assert np.allclose(U, truth, rtol=1e-10, atol=1e-12 * np.abs(truth).max())
    assert np.allclose(f, (d0 - E.T @ truth) / c, rtol=1e-8)
    assert np.allclose(linked.flexibility(), np.linalg.inv(K + springs), rtol=1e-9, atol=0)
    # the contact operator seen through G: W' = G R' G^T
    B = linked.coupling(G)
    W = G @ model.flexibility @ G.T
    assert np.allclose(
        linked.reduced_operator(W, B), G @ np.linalg.inv(K + springs) @ G.T, rtol=1e-9
    )


def test_rigid_links_equal_the_bordered_system(case):
    model, K, E, P, d0, G = case
    linked = LinkedModel(model, Links(E, np.zeros(M), d0))
    U, f = linked.displacements(P)
    kkt = np.block([[K, -E], [E.T, np.zeros((M, M))]])
    solution = np.linalg.solve(kkt, np.concatenate([P, d0]))
    assert np.allclose(U, solution[:N], rtol=1e-9, atol=1e-12 * np.abs(U).max())
    assert np.allclose(f, solution[N:], rtol=1e-8)
    assert np.allclose(E.T @ U, d0, rtol=0, atol=1e-12 * np.abs(U).max())


def test_mixed_links_with_contact_forces_through_the_reduced_operator(case):
    """``G U`` predicted by ``W'`` and the offset equals the direct solve with ``G^T x``."""
    model, K, E, P, d0, G = case
    c = np.array([0.0, 1e-6, 0.0, 3e-7])
    linked = LinkedModel(model, Links(E, c, d0))
    x = np.random.default_rng(3).standard_normal(P_ROWS) * 10.0
    U, f = linked.displacements(P + G.T @ x)
    B = linked.coupling(G)
    W = G @ model.flexibility @ G.T
    free = model.displacements(P)
    predicted = G @ free + linked.offset(B, E.T @ free) + linked.reduced_operator(W, B) @ x
    assert np.allclose(G @ U, predicted, rtol=1e-9, atol=1e-12 * np.abs(G @ U).max())
    # the bordered truth with the elastic rows: [K -E; E^T C] [U; f] = [P + G^T x; d0]
    kkt = np.block([[K, -E], [E.T, np.diag(c)]])
    solution = np.linalg.solve(kkt, np.concatenate([P + G.T @ x, d0]))
    assert np.allclose(U, solution[:N], rtol=1e-9, atol=1e-12 * np.abs(U).max())
    assert np.allclose(f, solution[N:], rtol=1e-8)
    assert np.allclose(linked.links.residual(U, f), 0.0, atol=1e-12 * np.abs(U).max())


def test_links_refused_when_dependent_or_malformed():
    model = ReducedModel(flexibility=np.eye(3))
    E = np.array([[1.0, 1.0], [0.0, 0.0], [-1.0, -1.0]])
    with pytest.raises(InvalidInputError, match="not independent"):
        LinkedModel(model, Links(E, [0.0, 0.0], [0.0, 0.0]))
    with pytest.raises(InvalidInputError, match="compliance must be >= 0"):
        Links(E[:, :1], [-1.0], [0.0])
    with pytest.raises(InvalidInputError, match="zero direction"):
        Links(np.zeros((3, 1)), [0.0], [0.0])
    with pytest.raises(InvalidInputError, match="one value per component"):
        Links(E, [0.0], [0.0, 0.0])
    with pytest.raises(InvalidInputError, match="freedoms"):
        LinkedModel(ReducedModel(flexibility=np.eye(2)), Links(E[:, :1], [0.0], [0.0]))


def test_frictional_problem_restricted_equals_one_built_on_the_kept_contacts():
    """FrictionalProblem.restricted slices the local form; a problem assembled afresh on the
    kept contacts is the truth (operator, step and solution)."""
    from contactqp import FrictionalProblem, NodePairs, solve

    rng = np.random.default_rng(11)
    k = 6
    model = ReducedModel(flexibility=_symmetric(np.linalg.inv(_spd(rng, 6 * k))), dofs_per_node=3)
    pairs = np.column_stack([np.arange(k), k + np.arange(k)])
    gaps = rng.uniform(-1e-3, 1e-3, k)
    loads = rng.standard_normal(6 * k)
    normals = np.tile([0.0, 0.0, 1.0], (k, 1))
    whole = FrictionalProblem(model, loads, [NodePairs(pairs, gaps, normals)], 0.3)
    kept = np.array([0, 2, 3, 5])
    shifted = gaps[kept] + 1e-4
    restricted = whole.restricted(kept, gaps=shifted)
    fresh = FrictionalProblem(model, loads, [NodePairs(pairs[kept], shifted, normals[kept])], 0.3)
    assert np.allclose(restricted.local().W, fresh.local().W, rtol=1e-12, atol=0)
    assert np.allclose(restricted.step().local.q, fresh.step().local.q, rtol=1e-12, atol=1e-15)
    a, b = solve(restricted), solve(fresh)
    assert a.success and b.success
    assert np.allclose(a.forces, b.forces, rtol=1e-8, atol=1e-10 * np.abs(b.forces).max())
    with pytest.raises(InvalidInputError, match="distinct indices"):
        whole.restricted([0, 0])


def test_contact_problem_restricted_equals_one_built_on_the_kept_contacts():
    from contactqp import ContactProblem, NodePairs, solve

    rng = np.random.default_rng(5)
    k = 8
    model = ReducedModel(flexibility=_symmetric(np.linalg.inv(_spd(rng, 2 * k))))
    pairs = np.column_stack([np.arange(k), k + np.arange(k)])
    gaps = rng.uniform(-1e-3, 1e-3, k)
    loads = rng.standard_normal(2 * k)
    whole = ContactProblem(model, np.zeros(2 * k), [NodePairs(pairs, gaps)])
    whole.dual()
    kept = np.array([1, 2, 4, 7])
    restricted = whole.restricted(kept, loads=loads, gaps=gaps[kept] * 2)
    fresh = ContactProblem(model, loads, [NodePairs(pairs[kept], gaps[kept] * 2)])
    assert np.allclose(restricted.dual().W, fresh.dual().W, rtol=1e-12, atol=0)
    assert np.allclose(restricted.dual().b, fresh.dual().b, rtol=1e-12, atol=1e-15)
    a, b = solve(restricted), solve(fresh)
    assert a.success and b.success and np.allclose(a.forces, b.forces, rtol=1e-9)
    with pytest.raises(InvalidInputError, match="gaps must have shape"):
        whole.restricted(kept, gaps=gaps)

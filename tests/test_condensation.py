"""Static condensation against the unit-load procedure and against a closed form."""

import numpy as np
import pytest
import scipy.sparse as sp

from contactqp.compliance.condensation import (
    RigidBodyModeError,
    _by_schur_complement,
    _by_solves,
    _schur_pays,
    condense,
    factorize,
)
from contactqp.compliance.fem import ElasticModel, block, plate
from contactqp.core.model import unit_load_compliance
from contactqp.errors import InvalidInputError, NotPositiveDefiniteError


def bar_stiffness(n, k=3.0, fixed=True):
    """Chain of ``n`` springs ``k``; the first attached to a wall when ``fixed``."""
    main = np.full(n, 2 * k)
    main[-1] = k
    if not fixed:
        main[0] = k
    return sp.diags([main, -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, -1, 1], format="csr")


def test_spring_chain_flexibility_is_the_closed_form():
    k, n = 3.0, 40
    chosen = np.array([0, 7, 19, 39])
    R = condense(bar_stiffness(n, k), chosen)
    expected = (np.minimum.outer(chosen, chosen) + 1) / k
    np.testing.assert_allclose(R, expected, rtol=1e-12)


def test_equals_the_unit_load_procedure_on_a_random_sparse_model():
    rng = np.random.default_rng(1)
    n = 300
    B = sp.random(n, n, density=0.02, random_state=rng)
    K = (B @ B.T + sp.eye(n) * 0.5).tocsr()
    chosen = rng.choice(n, size=60, replace=False)
    Kd = K.toarray()

    def _embed(load):
        full = np.zeros(n)
        full[chosen] = load
        return full

    unit = unit_load_compliance(lambda p: np.linalg.solve(Kd, _embed(p))[chosen], chosen.size)
    R = condense(K, chosen)
    np.testing.assert_allclose(R, unit.flexibility, rtol=1e-10, atol=1e-10 * np.abs(R).max())
    assert np.array_equal(R, R.T)


def test_rigid_body_mode_is_a_clear_error():
    with pytest.raises(RigidBodyModeError, match="rigid-body modes"):
        condense(bar_stiffness(10, fixed=False), [3])


def test_bad_freedoms_are_named():
    with pytest.raises(InvalidInputError, match="freedoms must lie in"):
        condense(bar_stiffness(5), [5])
    with pytest.raises(InvalidInputError, match="repeated"):
        condense(bar_stiffness(5), [1, 1])
    with pytest.raises(InvalidInputError, match="stiffness contains NaN"):
        condense(sp.csr_matrix(np.full((2, 2), np.nan)), [0])


def nearly_singular(epsilon):
    """``[[1, 1 - e], [1 - e, 1]]``: eigenvalues ``e`` and ``2 - e``, second pivot ``~ 2 e``."""
    return sp.csr_matrix([[1.0, 1.0 - epsilon], [1.0 - epsilon, 1.0]])


def test_pivot_tolerance_separates_stiff_from_singular():
    R = condense(nearly_singular(1e-8), [0, 1])
    np.testing.assert_allclose(R, np.linalg.inv(nearly_singular(1e-8).toarray()), rtol=1e-7)
    with pytest.raises(RigidBodyModeError, match="pivot 2e-12 of the diagonal at freedom"):
        condense(nearly_singular(1e-12), [0])
    with pytest.raises(RigidBodyModeError):
        condense(nearly_singular(1e-8), [0], pivot_rtol=1e-7)


def test_pivot_check_does_not_depend_on_the_units_of_each_freedom():
    """Scaling freedoms (metres vs radians, say) changes R to D^-1 R D^-1 and nothing else."""
    K = bar_stiffness(6)
    D = sp.diags([1e-6, 1.0, 1e6, 1.0, 1e-3, 1e4])
    R = condense(D @ K @ D, np.arange(6))
    expected = condense(K, np.arange(6)) / np.outer(D.diagonal(), D.diagonal())
    np.testing.assert_allclose(R, expected, rtol=1e-12)


def test_indefinite_and_unconnected_freedoms_are_named():
    indefinite = sp.csr_matrix([[2.0, 3.0], [3.0, 2.0]])
    with pytest.raises(NotPositiveDefiniteError, match="negative pivot -2.5 at spring [AB]"):
        condense(indefinite, [0], labels=["spring A", "spring B"])
    loose = sp.csr_matrix(np.diag([1.0, 0.0, 2.0]))
    with pytest.raises(RigidBodyModeError, match="freedom 1 has no stiffness"):
        factorize(loose)


def test_factorize_solves_like_a_dense_solve():
    K = bar_stiffness(30, k=7.0)
    b = np.linspace(-1.0, 2.0, 30)
    np.testing.assert_allclose(factorize(K).solve(b), np.linalg.solve(K.toarray(), b), rtol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_finite_element_condensation_equals_unit_loads_and_is_reciprocal(dim):
    """Against one full FE analysis per unit load (ElasticModel.solve), to 1e-10 relative.

    The unit-load matrix is measured column by column and not symmetrised, so its agreement with
    the condensed R (and its own reciprocity error) checks Maxwell-Betti on the FE model.
    """
    if dim == 2:
        model = ElasticModel(
            plate(1.0, 0.3, 10, 3), 70e9, 0.33, plane="stress", thickness=2e-3, order=2
        ).fix("left")
        points = [[1.0, 0.3], [0.8, 0.3], [0.6, 0.3], [0.4, 0.3], [1.0, 0.0], [0.6, 0.0]]
    else:
        model = (
            ElasticModel(block(1.0, 0.4, 0.2, 5, 2, 2, cell="tet"), 210e9, 0.3, order=2)
            .fix("left")
            .fix("back", [1])
        )
        points = [[1.0, 0.0, 0.2], [0.6, 0.2, 0.2], [0.4, 0.0, 0.0], [1.0, 0.2, 0.0]]
    nodes = model.select_nodes(points, where="boundary").nodes
    R = model.reduced_model(nodes).flexibility

    def analysis(load):
        loads = np.zeros((model.n_nodes, dim))
        loads[nodes] = load.reshape(-1, dim)
        return model.solve(loads)[nodes].ravel()

    unit = unit_load_compliance(analysis, nodes.size * dim)
    np.testing.assert_allclose(R, unit.flexibility, rtol=0, atol=1e-10 * np.abs(R).max())
    assert unit.reciprocity_error < 1e-10
    assert np.all(np.linalg.eigvalsh(R) > 0)


def test_the_singular_freedom_is_named():
    """A healthy chain beside a (numerically) floating pair of freedoms 3 and 4."""
    floating = nearly_singular(1e-13)
    K = sp.block_diag([bar_stiffness(3, k=1e6), floating])
    with pytest.raises(RigidBodyModeError, match=r"at pair [ab]\)"):
        condense(K, [0], labels=["chain 0", "chain 1", "chain 2", "pair a", "pair b"])


def test_both_routes_give_the_closed_form_and_the_cheaper_one_is_taken():
    """Solves with the factor (few freedoms) and the Schur complement (many) agree.

    On a chain of springs, ``K^-1`` is ``min(i, j) + 1`` over ``k``; one chosen freedom is cheaper
    by a solve, all of them by the trailing block of a second factorisation.
    """
    k, n = 3.0, 200
    K = sp.csc_matrix(bar_stiffness(n, k))
    lu = factorize(K)
    chosen = np.array([150, 3, 77, 199, 0])
    expected = (np.minimum.outer(chosen, chosen) + 1) / k
    np.testing.assert_allclose(_by_solves(lu, chosen), expected, rtol=1e-12)
    np.testing.assert_allclose(_by_schur_complement(K, lu, chosen), expected, rtol=1e-12)
    assert not _schur_pays(lu, 1) and _schur_pays(lu, n)


def test_an_unsymmetric_stiffness_is_refused_not_symmetrised():
    """The factorisation reads one triangle; an unsymmetric K would give another matrix's R.

    The asymmetry is measured against ``sqrt(K_ii K_jj)``, so scaling the freedoms (units)
    changes neither the verdict nor the freedoms named.
    """
    K = bar_stiffness(4).toarray()
    K[2, 1] *= 1.01
    labels = ["a", "b", "c", "d"]
    with pytest.raises(
        InvalidInputError,
        match=r"not symmetric: .* = 0\.005 > 1e-06 between "
        r"[bc] and [bc]",
    ):
        condense(K, [0], labels=labels)
    D = np.diag([1e-6, 1e3, 1.0, 1e6])
    with pytest.raises(InvalidInputError, match=r"not symmetric: .* = 0\.005 > 1e-06"):
        factorize(D @ K @ D, labels=labels)
    assert condense(K, [0], symmetry_rtol=0.02).shape == (1, 1)
    # round-off asymmetry of a symmetric matrix in very different units is accepted
    S = bar_stiffness(4).toarray()
    S[2, 1] *= 1 + 1e-12
    np.testing.assert_allclose(
        condense(D @ S @ D, np.arange(4)), np.linalg.inv(D @ S @ D), rtol=1e-9
    )


def test_malformed_stiffness_and_labels_are_invalid_input():
    with pytest.raises(InvalidInputError, match="square matrix of numbers"):
        condense([["a", "b"], ["c", "d"]], [0])
    with pytest.raises(InvalidInputError, match=r"non-empty square matrix, got shape \(\)"):
        condense(None, [0])
    with pytest.raises(InvalidInputError, match="labels must name the 2 freedoms, got 1"):
        condense(np.diag([1.0, 0.0]), [0], labels=["a"])


def test_too_ill_conditioned_for_the_schur_route_is_a_contact_error():
    """A 16,000-element cantilever with the pivot test switched off: the condensed block loses
    positive definiteness to round-off. That used to escape as numpy's LinAlgError."""
    from contactqp.compliance.beam import Frame2D

    E, A, L = 1e12, 0.2e-6, 0.04
    frame = Frame2D.straight(L, 16000, E, A, A**2 / (4 * np.pi), fixed={-1: "xyr"})
    freedoms = [frame.index(k, c) for k in range(0, 16000, 2000) for c in ("ux", "uy")]
    with pytest.raises(NotPositiveDefiniteError):
        condense(frame.stiffness(), freedoms, pivot_rtol=0.0)
    # with the default pivot test the same model is refused at the factorisation already
    with pytest.raises(RigidBodyModeError, match="pivot"):
        condense(frame.stiffness(), freedoms)

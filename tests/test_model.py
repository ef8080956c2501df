"""Validation of reduced models and the unit-load procedure."""

import warnings

import numpy as np
import pytest

import contactqp as cq
from contactqp.errors import SymmetrizedWarning


def test_unit_load_procedure_rebuilds_the_flexibility_of_a_spring_chain():
    # the "finite-element solve" is a linear solve with the chain stiffness; R must be its inverse
    n = 6
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    K[-1, -1] = 1.0
    compliance = cq.unit_load_compliance(lambda P: np.linalg.solve(K, P), n)
    index = np.arange(1, n + 1)
    np.testing.assert_allclose(compliance.flexibility, np.minimum.outer(index, index), rtol=1e-12)
    assert compliance.reciprocity_error < 1e-12


def test_unit_load_reports_lack_of_reciprocity():
    M = np.array([[2.0, 0.1], [0.0, 1.0]])
    assert cq.unit_load_compliance(lambda P: M @ P, 2).reciprocity_error == pytest.approx(0.05)


@pytest.mark.parametrize(
    "matrix, message",
    [
        (np.ones((2, 3)), "square"),
        (np.array([[1.0, np.nan], [np.nan, 1.0]]), "NaN"),
        (np.array([[1.0, 0.5], [0.0, 1.0]]), "not symmetric"),
        (np.zeros((2, 2)), "singular"),
        (np.array([[1.0, 1.0], [1.0, 1.0 + 1e-16]]), "singular|positive definite"),
    ],
)
def test_bad_matrices_are_named(matrix, message):
    with pytest.raises(cq.InvalidInputError, match=message) as info:
        cq.ReducedModel(flexibility=matrix)
    assert "flexibility" in str(info.value)


def test_indefinite_matrix_reports_smallest_eigenvalue():
    with pytest.raises(cq.NotPositiveDefiniteError, match=r"smallest eigenvalue -1"):
        cq.ReducedModel(stiffness=np.diag([1.0, -1.0]))


def test_nearly_symmetric_matrix_is_symmetrised_with_a_warning():
    R = np.array([[1.0, 0.5], [0.5 + 1e-9, 1.0]])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = cq.ReducedModel(flexibility=R)
    assert any(issubclass(w.category, SymmetrizedWarning) for w in caught)
    np.testing.assert_array_equal(model.flexibility, model.flexibility.T)


def test_stiffness_and_flexibility_are_inverse():
    model = cq.ReducedModel(flexibility=[[2.0, 1.0], [1.0, 2.0]], dofs_per_node=2)
    np.testing.assert_allclose(model.stiffness @ model.flexibility, np.eye(2), atol=1e-14)
    assert model.n_nodes == 1 and list(model.freedoms(0)) == [0, 1]
    with pytest.raises(cq.InvalidInputError, match="multiple of dofs_per_node"):
        cq.ReducedModel(flexibility=np.eye(4), dofs_per_node=3)


@pytest.mark.parametrize("count", [2.5, "2", 2j, 4, 0])
def test_dofs_per_node_must_be_a_whole_count_of_1_to_3(count):
    # 2.5 was truncated to 2 and 2j raised TypeError; both now name the argument
    with pytest.raises(cq.InvalidInputError, match="dofs_per_node must be 1, 2 or 3"):
        cq.ReducedModel(flexibility=np.eye(4), dofs_per_node=count)


def test_dofs_per_node_accepts_a_whole_float_or_numpy_integer():
    assert cq.ReducedModel(flexibility=np.eye(4), dofs_per_node=2.0).n_nodes == 2
    assert cq.ReducedModel(flexibility=np.eye(6), dofs_per_node=np.int64(3)).n_nodes == 2

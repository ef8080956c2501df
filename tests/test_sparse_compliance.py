"""Sparse compliance and Delassus operators against the dense R of the same model; contact
solves through them against the dense route.

Truths: ``inv(K)`` by dense LAPACK (independent of the sparse factorisation), the flexibility
:meth:`ElasticModel.reduced_model` forms by static condensation, and the frictionless
active-set solve of the dense reduced model (``ContactProblem``). Tolerances: the products are
one sparse solve against one dense inverse of a well-conditioned stiffness (condition number
below 1e4 on these meshes), so they agree to ~1e-13 of the largest entry; 1e-10 leaves three
orders of margin.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp as cq
from contactqp.compliance import _pardiso, grid, normal_influence
from contactqp.compliance.sparse_compliance import (
    FACTORIZERS,
    SparseComplianceOperator,
    SparseDelassusOperator,
)
from contactqp.errors import (
    InvalidInputError,
    MissingDependencyError,
    NotPositiveDefiniteError,
    RigidBodyModeError,
    UnsupportedProblemError,
)

fem = pytest.importorskip("contactqp.compliance.fem")

# both factorisations; Pardiso needs MKL (the `sparse` extra, part of `test`): said, not silent
needs_mkl = pytest.mark.skipif(not _pardiso.pardiso_installed(), reason="MKL is not installed")
FACTORIZER = [pytest.param(f, marks=needs_mkl) if f == "pardiso" else f for f in FACTORIZERS]

E, NU = 70e9, 0.3


def slab(nx: int = 6, ny: int = 5, nz: int = 2, cell: str = "hex"):
    """A block 1 x 0.8 x 0.3 m clamped at its bottom; its top nodes (sorted by index)."""
    model = fem.ElasticModel(fem.block(1.0, 0.8, 0.3, nx, ny, nz, cell=cell), E, NU)
    model.fix("bottom")
    top = model.select_nodes(where="top").nodes
    return model, top


def dense_truth(model, nodes, components):
    free, K = model.free_stiffness()
    position = np.full(model.basis.N, -1)
    position[free] = np.arange(free.size)
    chosen = position[model.basis.nodal_dofs[components][:, nodes].T.ravel()]
    inverse = np.linalg.inv(K.toarray())
    return K, chosen, inverse


def close(actual, expected, scale):
    np.testing.assert_allclose(actual, expected, rtol=0, atol=1e-10 * scale)


# --- truths: products, diagonal, blocks ----------------------------------------------------


@pytest.mark.parametrize("factorizer", FACTORIZER)
@pytest.mark.parametrize("components", [None, [2]])
def test_compliance_equals_the_dense_flexibility_of_the_same_model(components, factorizer):
    model, top = slab()
    W = SparseComplianceOperator.of_model(model, top, components=components, factorizer=factorizer)
    assert W.factorizer == factorizer
    R = model.reduced_model(top, components=components).flexibility  # static condensation
    axes = [0, 1, 2] if components is None else components
    _, chosen, inverse = dense_truth(model, top, axes)
    truth = inverse[np.ix_(chosen, chosen)]
    scale = np.abs(truth).max()
    close(R, truth, scale)  # the two references agree
    m = top.size * len(axes)
    assert W.shape == (m, m)
    rng = np.random.default_rng(0)
    x, X = rng.standard_normal(m), rng.standard_normal((m, 4))
    close(W @ x, truth @ x, scale * np.abs(x).sum())
    close(W @ X, truth @ X, scale * np.abs(X).sum(axis=0).max())
    close(W.diagonal(), np.diag(truth), scale)
    if components is None:
        blocks = W.diagonal_blocks(3)
        close(
            blocks,
            np.stack([truth[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] for i in range(m // 3)]),
            scale,
        )


def test_blocks_on_every_kind_of_selection_equal_the_dense_ones():
    model, top = slab()
    W = SparseComplianceOperator.of_model(model, top, components=[2])
    _, chosen, inverse = dense_truth(model, top, [2])
    truth = inverse[np.ix_(chosen, chosen)]
    scale = np.abs(truth).max()
    m = truth.shape[0]
    rows, cols = np.array([7, 2, 30, 11]), np.array([5, 3, 0, 41, 22, 9, 2])
    mask = np.zeros(m, dtype=bool)
    mask[[1, 4, 40]] = True
    close(W.block(rows, cols), truth[np.ix_(rows, cols)], scale)  # fewer rows: by symmetry
    close(W.block(cols, rows), truth[np.ix_(cols, rows)], scale)
    close(W.block(mask, None), truth[mask], scale)
    close(W.block(slice(3, 9), mask), truth[3:9][:, mask], scale)
    close(W.block(), truth, scale)
    # asked again: the cached block, and a copy the caller may change
    again = W.block(rows, cols)
    again[:] = 0.0
    close(W.block(rows, cols), truth[np.ix_(rows, cols)], scale)
    factor = W.cholesky(rows)  # the base class's factor, through block()
    close(factor.lower @ factor.lower.T, truth[np.ix_(np.sort(rows), np.sort(rows))], scale)
    with pytest.raises(UnsupportedProblemError, match="does not form one"):
        _ = W.matrix


@pytest.mark.parametrize("factorizer", FACTORIZER)
def test_delassus_operator_equals_A_inv_K_At(factorizer):
    model, top = slab(cell="tet")
    free, K = model.free_stiffness()
    n = K.shape[0]
    rng = np.random.default_rng(1)
    # tilted normals at the top nodes (3 entries a row) and a relative displacement of two nodes
    _, chosen, inverse = dense_truth(model, top, [0, 1, 2])
    normals = rng.standard_normal((top.size, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    rows = np.repeat(np.arange(top.size), 3)
    A = sp.csr_matrix((normals.ravel(), (rows, chosen)), shape=(top.size, n))
    pair = sp.csr_matrix(([1.0, -1.0], ([0, 0], [chosen[2], chosen[5]])), shape=(1, n))
    A = sp.vstack([A, pair]).tocsr()
    W = SparseDelassusOperator(K, A, factorizer=factorizer)
    truth = A @ inverse @ A.T.toarray()
    scale = np.abs(truth).max()
    x = rng.standard_normal(A.shape[0])
    close(W @ x, truth @ x, scale * np.abs(x).sum())
    close(W.diagonal(), np.diag(truth), scale)
    close(W.block([0, 3, A.shape[0] - 1], None), truth[[0, 3, A.shape[0] - 1]], scale)
    assert W.factor_nnz > K.nnz // 2
    X = rng.standard_normal((A.shape[0], 3))  # several columns, in C order: solved together
    close(W @ X, truth @ X, scale * np.abs(X).sum(axis=0).max())


@needs_mkl
def test_pardiso_is_the_default_and_its_failures_are_named():
    model, top = slab(3, 3, 1)
    free, K = model.free_stiffness()
    assert SparseComplianceOperator(K, [0, 1]).factorizer == "pardiso"
    labels = [f"dof {i}" for i in range(K.shape[0])]
    # no fixation: rigid-body modes, a vanishing pivot (found by Pardiso's pivots or, where a
    # rounded pivot is <= 0, by SuperLU's diagnosis)
    with pytest.raises(RigidBodyModeError, match="rigid-body"):
        SparseComplianceOperator(model.stiffness, [0], factorizer="pardiso")
    chain = sp.diags([-np.ones(49), np.r_[1.0, 2.0 * np.ones(48), 1.0], -np.ones(49)], [-1, 0, 1])
    with pytest.raises(RigidBodyModeError, match="rigid-body"):  # a free chain of springs
        SparseComplianceOperator(chain.tocsc(), [0], factorizer="pardiso")
    # one mechanism in a fixed model: a freedom tied to nothing but a spring of another
    # freedom's stiffness turned negative
    indefinite = K.tolil()
    indefinite[0, 0] = -indefinite[0, 0]
    with pytest.raises(NotPositiveDefiniteError, match="dof 0"):
        SparseComplianceOperator(indefinite.tocsc(), [1], labels=labels, factorizer="pardiso")
    # positive diagonal, negative eigenvalue: Pardiso stops at a pivot <= 0, SuperLU names it
    coupled = sp.csc_matrix(np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]))
    with pytest.raises(NotPositiveDefiniteError, match="pivot"):
        SparseComplianceOperator(coupled, [0, 2], factorizer="pardiso")
    with pytest.raises(InvalidInputError, match="not symmetric"):
        SparseComplianceOperator(
            K + sp.csc_matrix(([1e3 * K.max()], ([0], [1])), K.shape), [0], factorizer="pardiso"
        )


def test_without_mkl_superlu_is_the_default_and_pardiso_names_the_extra(monkeypatch):
    model, top = slab(3, 3, 1)
    free, K = model.free_stiffness()
    monkeypatch.setattr(_pardiso, "_library", lambda: None)
    assert SparseComplianceOperator(K, [0, 1]).factorizer == "superlu"
    with pytest.raises(MissingDependencyError, match=r"contactqp\[sparse\]"):
        SparseComplianceOperator(K, [0, 1], factorizer="pardiso")
    with pytest.raises(InvalidInputError, match="factorizer must be"):
        SparseComplianceOperator(K, [0, 1], factorizer="cholmod")


# --- bad input ------------------------------------------------------------------------------


def test_bad_input_is_named():
    model, top = slab(3, 3, 1)
    free, K = model.free_stiffness()
    with pytest.raises(InvalidInputError, match="freedoms must lie in"):
        SparseComplianceOperator(K, [0, K.shape[0]])
    with pytest.raises(InvalidInputError, match="repeated"):
        SparseComplianceOperator(K, [1, 1])
    with pytest.raises(InvalidInputError, match=r"constraints must be a matrix of shape \(m, "):
        SparseDelassusOperator(K, sp.eye(3, K.shape[0] + 1))
    with pytest.raises(InvalidInputError, match="not symmetric"):
        SparseComplianceOperator(K + sp.csc_matrix(([1e3 * K.max()], ([0], [1])), K.shape), [0])
    with pytest.raises(RigidBodyModeError):
        SparseComplianceOperator(model.stiffness, [0])  # no fixation applied
    bottom = model.select_nodes(where="bottom").nodes
    with pytest.raises(InvalidInputError, match="is fixed"):
        SparseComplianceOperator.of_model(model, bottom[:2])
    with pytest.raises(InvalidInputError, match="components must be"):
        SparseComplianceOperator.of_model(model, top, components=[3])
    W = SparseComplianceOperator(K, [0, 1, 2])
    with pytest.raises(InvalidInputError, match=r"operand must have shape \(3,\)"):
        W @ np.ones(4)
    with pytest.raises(InvalidInputError, match="block indices"):
        W.block([5], None)


# --- contact through the operator ------------------------------------------------------------


def pressed(shape: str, cell: str = "hex", factorizer: str | None = None):
    """The top face of a slab under a rigid indenter: ``(operator, R, s, approach)``."""
    model, top = slab(10, 8, 3, cell=cell)
    W = SparseComplianceOperator.of_model(model, top, components=[2], factorizer=factorizer)
    R = model.reduced_model(top, components=[2]).flexibility
    x, y = model.mesh.p[0, top] - 0.5, model.mesh.p[1, top] - 0.4
    approach = 4e-6
    # sphere: touching the surface out to 0.3 m from the centre; flat: tilted about y, touching
    # the lower 40 % of the face
    sphere = approach * (x**2 + y**2) / 0.3**2
    s = sphere if shape == "sphere" else approach * (x + 0.5) / 0.4
    return W, R, s, approach


@pytest.mark.parametrize("factorizer", FACTORIZER)
@pytest.mark.parametrize(
    "shape, method, cell",
    [
        ("sphere", "constrained-cg", "hex"),
        ("sphere", "dual-active-set", "hex"),
        ("flat", "constrained-cg", "tet"),
        ("flat", "dual-active-set", "tet"),
    ],
)
def test_a_solve_through_the_operator_equals_the_dense_solve(shape, method, cell, factorizer):
    W, R, s, approach = pressed(shape, cell, factorizer)
    result = cq.solve(cq.SurfaceProblem(W, s, approach=approach), method, tol=1e-12)
    assert result.success, result.message
    # the dense route: the condensed R as a reduced model, gaps s - delta, no loads
    reference = cq.solve_gaps(R, np.zeros(s.size), s - approach)
    assert reference.success
    scale = reference.forces.max()
    closed = np.count_nonzero(reference.forces > 1e-10 * scale)
    assert 10 < closed < s.size - 10  # partial contact
    # gap residuals of 1e-12 of the displacement move the forces by ~cond(W_CC) 1e-12 (< 1e4
    # here): 1e-7 of the peak force leaves a margin of 10
    np.testing.assert_allclose(result.forces, reference.forces, rtol=0, atol=1e-7 * scale)
    np.testing.assert_array_equal(result.contact, reference.forces > 1e-10 * scale)
    np.testing.assert_allclose(result.gaps, reference.gaps, rtol=0, atol=1e-8 * approach)


@pytest.mark.parametrize("method", ["constrained-cg", "dual-active-set"])
def test_a_fixed_load_finds_the_approach_of_the_dense_solve(method):
    W, R, s, approach = pressed("sphere")
    reference = cq.solve_gaps(R, np.zeros(s.size), s - approach)
    load = float(reference.forces.sum())
    result = cq.solve(cq.SurfaceProblem(W, s, load=load), method, tol=1e-12)
    assert result.success, result.message
    assert result.approach == pytest.approx(approach, rel=1e-8)
    scale = reference.forces.max()
    np.testing.assert_allclose(result.forces, reference.forces, rtol=0, atol=1e-7 * scale)


def test_the_dual_active_set_warm_started_from_the_answer_takes_one_set():
    W, _, s, approach = pressed("sphere")
    problem = cq.SurfaceProblem(W, s, approach=approach)
    cold = cq.solve(problem, "dual-active-set", tol=1e-12)
    warm = cq.solve(problem, "dual-active-set", tol=1e-12, r0=cold.forces)
    assert cold.iterations > 1 and warm.iterations == 1 and warm.success
    np.testing.assert_allclose(warm.forces, cold.forces, rtol=0, atol=1e-9 * cold.forces.max())


def test_the_dual_active_set_out_of_cg_steps_says_so():
    W, _, s, approach = pressed("sphere")
    result = cq.solve(cq.SurfaceProblem(W, s, approach=approach), "dual-active-set", max_cg=2)
    assert not result.success and "did not converge in 2 steps" in result.message
    with pytest.raises(InvalidInputError, match="max_cg must be an integer >= 1"):
        cq.solve(cq.SurfaceProblem(W, s, approach=approach), "dual-active-set", max_cg=0)


@pytest.mark.parametrize("given", ["approach", "load"])
def test_the_dual_active_set_on_a_rough_half_space_equals_the_dense_active_set(given):
    # several contact patches on a dense half-space W (a W that is not an M-matrix)
    n, cell = 16, 1e-5
    x, y = grid(n, n, cell, cell)
    x, y = x - x.mean(), y - y.mean()
    W = normal_influence(x, y, cell, cell, 210e9, 0.3)
    s = (x**2 + y**2) / (2 * 5e-3) + 2e-7 * np.random.default_rng(3).uniform(0, 1, x.size)
    value = {"approach": 6e-7} if given == "approach" else {"load": 2.0}
    problem = cq.SurfaceProblem(W, s, **value)
    result = cq.solve(problem, "dual-active-set", tol=1e-12)
    reference = cq.solve(problem, "surface-active-set", tol=1e-12)
    assert result.success and reference.success, (result.message, reference.message)
    scale = reference.forces.max()
    np.testing.assert_allclose(result.forces, reference.forces, rtol=0, atol=1e-8 * scale)
    assert result.approach == pytest.approx(reference.approach, rel=1e-9)

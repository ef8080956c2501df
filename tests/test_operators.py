"""The operator seam (contactqp.core.operators): dense, sparse and a matrix-free operator."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator, aslinearoperator

from contactqp.core.operators import (
    PSD_SHIFT,
    DenseOperator,
    Operator,
    SparseOperator,
    as_operator,
    symmetric_product,
)
from contactqp.errors import InvalidInputError, NotPositiveDefiniteError, UnsupportedProblemError
from contactqp.methods.active_set import cold_start
from contactqp.methods.box_qp import solve_box_qp
from contactqp.methods.pgs import GaussSeidel


class GramOperator(Operator):
    """``W = A A^T + c I`` known only through ``A``: products through a LinearOperator, and
    blocks and the diagonal from rows of ``A``; the matrix ``W`` is never formed."""

    def __init__(self, A: np.ndarray, c: float):
        super().__init__((A.shape[0], A.shape[0]))
        self.A, self.c = A, c
        self.linear = aslinearoperator(A) @ aslinearoperator(A.T) + c * aslinearoperator(
            sp.identity(A.shape[0])
        )
        self.blocks_formed = 0

    def __matmul__(self, x):
        return self.linear.matmat(x) if np.ndim(x) == 2 else self.linear.matvec(x)

    def diagonal(self):
        return np.einsum("ij,ij->i", self.A, self.A) + self.c

    def block(self, rows=None, cols=None):
        self.blocks_formed += 1
        everything = np.arange(self.shape[0])
        rows = everything[rows] if rows is not None else everything
        cols = everything[cols] if cols is not None else everything
        return self.A[rows] @ self.A[cols].T + self.c * (rows[:, None] == cols[None, :])


def gram(n=30, k=12, c=0.1, seed=0):
    A = np.random.default_rng(seed).standard_normal((n, k)) / np.sqrt(k)
    return A, A @ A.T + c * np.eye(n)


def test_dense_and_sparse_operators_agree_with_the_matrix():
    _, W = gram()
    W[np.abs(W) < 0.2] = 0.0  # some structure for the sparse one
    x = np.random.default_rng(1).standard_normal((30, 2))
    rows, cols = np.array([4, 1, 7]), np.array([2, 9])
    mask = np.zeros(30, dtype=bool)
    mask[[3, 5]] = True
    for operator in (as_operator(W), as_operator(sp.csr_matrix(W)), as_operator(sp.coo_array(W))):
        assert operator.shape == (30, 30)
        np.testing.assert_allclose(operator @ x, W @ x, rtol=1e-14, atol=1e-14)
        np.testing.assert_array_equal(operator.diagonal(), np.diag(W))
        np.testing.assert_array_equal(operator.block(rows, cols), W[np.ix_(rows, cols)])
        np.testing.assert_array_equal(operator.block(mask, None), W[mask])
        np.testing.assert_array_equal(operator.block(slice(2, 5), cols), W[2:5][:, cols])
        np.testing.assert_array_equal(operator.diagonal_blocks(3)[4], W[12:15, 12:15])
    assert isinstance(as_operator(W), DenseOperator) and as_operator(W).matrix is W
    assert isinstance(as_operator(sp.csr_matrix(W)), SparseOperator)
    operator = as_operator(W)
    assert as_operator(operator) is operator
    with pytest.raises(InvalidInputError, match="square"):
        as_operator(np.ones((2, 3)))


def test_cholesky_is_cached_and_shared():
    A, W = gram()
    operator = GramOperator(A, 0.1)
    index = np.array([7, 2, 11, 3])
    factor = operator.cholesky(index)
    assert operator.cholesky(np.sort(index)) is factor and operator.blocks_formed == 1
    np.testing.assert_array_equal(factor.index, np.sort(index))
    block = W[np.ix_(factor.index, factor.index)]
    np.testing.assert_allclose(factor.lower @ factor.lower.T, block, rtol=1e-13, atol=1e-14)
    assert not factor.shifted
    rhs = np.arange(4.0)
    np.testing.assert_allclose(block @ factor.solve(rhs), rhs, atol=1e-12)


def test_cholesky_shifts_semidefinite_blocks_and_refuses_indefinite_ones():
    v = np.array([1.0, 2.0, 3.0])
    singular = as_operator(np.outer(v, v)).cholesky([0, 1, 2])  # rank one
    assert singular.uniform > 0 and singular.relative == 0
    rounded = np.outer(v, v) + np.diag([1.0, 0.0, 0.0])
    rounded[1, 2] = rounded[2, 1] = 6.0 * (1 + 1e-6)  # indefinite by rounding: accepted
    factor = as_operator(rounded).cholesky([1, 2])
    assert factor.relative == PSD_SHIFT
    with pytest.raises(NotPositiveDefiniteError, match=r"2x2 principal block.*Cholesky"):
        as_operator(np.array([[1.0, 2.0], [2.0, 1.0]])).cholesky([0, 1])
    with pytest.raises(NotPositiveDefiniteError, match="diagonal entry 1 is -1"):
        as_operator(np.diag([1.0, -1.0])).cholesky([0, 1])
    with pytest.raises(NotPositiveDefiniteError, match="zero diagonal"):
        as_operator(np.array([[0.0, 1.0], [1.0, 1.0]])).cholesky([0, 1])


def test_box_qp_runs_on_a_matrix_free_operator():
    # the frictionless dual: min 1/2 x^T W x + c^T x, x >= 0, with about half of x free
    A, W = gram(n=40, k=15)
    c = np.random.default_rng(2).standard_normal(40)
    operator = GramOperator(A, 0.1)
    reference = solve_box_qp(W, c, lower=0.0)
    solution = solve_box_qp(operator, c, lower=0.0, x0=cold_start(operator, -c))
    assert solution.converged and reference.converged
    assert 5 < np.count_nonzero(solution.x) < 35
    np.testing.assert_allclose(solution.x, reference.x, rtol=0, atol=1e-10)
    # the answer is a solution: complementarity on the matrix formed here, never by the solver
    gradient = W @ solution.x + c
    assert np.all(gradient >= -1e-10) and np.abs(gradient * solution.x).max() < 1e-10


def test_methods_built_on_entries_refuse_a_matrix_free_operator():
    A, _ = gram(n=6, k=4)
    operator = GramOperator(A, 0.1)
    with pytest.raises(UnsupportedProblemError, match="explicit matrix"):
        _ = operator.matrix  # the property itself raises
    with pytest.raises(UnsupportedProblemError, match="GramOperator"):
        GaussSeidel(operator, np.zeros(6), np.zeros(2), 3)


def test_linear_operator_wrapped_as_operator_needs_a_subclass():
    # a bare LinearOperator is not a matrix: as_operator does not guess its blocks
    with pytest.raises(InvalidInputError, match="LinearOperator"):
        as_operator(LinearOperator((3, 3), matvec=lambda x: x, dtype=float))


def test_symmetric_dense_operator_reads_one_triangle_for_the_same_product():
    from contactqp.core.operators import SymmetricDenseOperator

    rng = np.random.default_rng(3)
    A = rng.standard_normal((40, 40))
    A = A + A.T
    x = rng.standard_normal(40)
    X = rng.standard_normal((40, 3))
    op = SymmetricDenseOperator(A)
    np.testing.assert_allclose(op @ x, A @ x, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(op @ X, A @ X, rtol=1e-13, atol=1e-13)
    # the lower triangle alone is read: changing the upper one changes nothing
    B = np.tril(A).copy()
    np.testing.assert_allclose(SymmetricDenseOperator(B) @ x, A @ x, rtol=1e-13, atol=1e-13)
    for bad in (A[:, :30].copy(), np.asfortranarray(A), A.astype(np.float32)):
        with pytest.raises(InvalidInputError, match="symmetric operator"):
            SymmetricDenseOperator(bad)


def test_dense_block_on_runs_of_consecutive_indices_is_the_matrix_block():
    # long runs of consecutive rows are gathered run by run; every selection must give the same
    # entries as numpy's own indexing, and indices outside the matrix must still be refused
    W = np.random.default_rng(4).standard_normal((60, 60))
    operator = as_operator(W)
    runs = np.r_[2:14, 20:41, 50:60]
    mask = np.zeros(60, dtype=bool)
    mask[runs] = True
    for rows, cols in (
        (runs, runs),
        (mask, mask),
        (runs, np.array([59, 0, 7, 7])),
        (np.r_[-12:0, 0:12], runs),  # negative indices: numpy's meaning
        (runs, np.r_[-5:0]),
    ):
        np.testing.assert_array_equal(operator.block(rows, cols), W[np.ix_(rows, cols)])
    with pytest.raises(IndexError):
        operator.block(runs, np.array([3, 60]))
    with pytest.raises(IndexError):
        operator.block(np.r_[50:61], runs)


@pytest.mark.parametrize("form", ["dense", "fortran", "sparse", "operator"])
def test_cold_start_shares_each_interpenetration_over_its_row(form):
    A, W = gram(n=30, k=12)
    W[3] = W[:, 3] = 0.0  # a zero row where b <= 0: its guess is 0, not 0 / 0
    b = np.random.default_rng(4).standard_normal(30)
    b[3] = -1.0
    given = {
        "dense": W,
        "fortran": np.asfortranarray(W),
        "sparse": sp.csr_matrix(W),
        "operator": GramOperator(np.delete(A, 3, axis=0), 0.1),
    }[form]
    if form == "operator":
        b = np.delete(b, 3)
        W = np.delete(np.delete(W, 3, axis=0), 3, axis=1)
    expected = np.where(b > 0, np.maximum(b, 0.0) / np.abs(W).sum(axis=1).clip(1e-300), 0.0)
    guess = cold_start(given, b)
    assert np.all(np.isfinite(guess)) and np.count_nonzero(guess) == np.count_nonzero(b > 0)
    np.testing.assert_allclose(guess, expected, rtol=1e-13, atol=0)


@pytest.mark.parametrize("layout", ["C", "F", "strided", "float32"])
def test_a_symmetric_product_is_the_product(layout):
    _, W = gram(n=25, k=25)
    W = {
        "C": W,
        "F": np.asfortranarray(W),
        "strided": np.repeat(np.repeat(W, 2, axis=0), 2, axis=1)[::2, ::2],
        "float32": W.astype(np.float32),
    }[layout]
    x = np.random.default_rng(6).standard_normal(25)
    expected = W.astype(float) @ x
    np.testing.assert_allclose(
        symmetric_product(W, x), expected, rtol=1e-6 if layout == "float32" else 1e-13
    )
    X = np.stack([x, 2 * x], axis=1)  # several columns: the general product
    np.testing.assert_allclose(symmetric_product(W, X), W @ X, rtol=1e-13)

"""The mu = 0 route's one-pass reads of a dense W, against plain numpy on the same matrix."""

import numpy as np
import pytest
import scipy.sparse as sp

from contactqp import solve
from contactqp.core.local_problem import LocalProblem
from contactqp.methods import local_global


@pytest.fixture
def small_blocks(monkeypatch):
    """Blocks of a few rows, so that a small matrix crosses many block boundaries."""
    monkeypatch.setattr(local_global, "_BLOCK_ENTRIES", 40)


def _symmetric(rng, m):
    A = rng.standard_normal((m, m))
    return A + A.T


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("n", [1, 7, 23])
def test_dense_normal_block_is_the_copy_its_symmetry_and_row_sums(small_blocks, dim, n):
    rng = np.random.default_rng(n + 10 * dim)
    W = _symmetric(rng, n * dim)
    W_nn = W[::dim, ::dim]
    copy, symmetric, row_sums = local_global._dense_normal_block(W, dim)
    assert copy.flags.c_contiguous
    np.testing.assert_array_equal(copy, W_nn)
    assert symmetric
    np.testing.assert_array_equal(row_sums, np.abs(W_nn).sum(axis=1))
    for i, j in [(n - 1, 0), (0, n - 1), (n // 2, n // 3)]:  # one entry off, far or near
        if i == j:
            continue
        broken = W.copy()
        broken[i * dim, j * dim] = np.nextafter(broken[i * dim, j * dim], np.inf)
        copy, symmetric, _ = local_global._dense_normal_block(broken, dim)
        np.testing.assert_array_equal(copy, broken[::dim, ::dim])
        assert not symmetric


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize(
    "loaded", [[], [0], [5], [2, 3, 9], list(range(12))], ids=lambda v: f"loaded{len(v)}"
)
def test_dense_normal_products_are_those_of_the_whole_matrix(small_blocks, dim, loaded):
    rng = np.random.default_rng(len(loaded) + dim)
    n = 12
    W = rng.standard_normal((n * dim, n * dim))
    x = np.zeros(n)
    x[loaded] = rng.standard_normal(len(loaded))
    r = np.zeros(n * dim)
    r[::dim] = x
    product, magnitude = local_global._dense_normal_products(
        W, np.ascontiguousarray(W[::dim, ::dim]), x, dim
    )
    np.testing.assert_allclose(product, W @ r, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(magnitude, np.abs(W) @ np.abs(r), rtol=1e-14, atol=0)


@pytest.mark.parametrize("skew", [0.0, 1e-4])
def test_dense_and_sparse_routes_give_the_same_answer(skew):
    """The dense one-pass route against the sparse one on the same (possibly unsymmetric) W."""
    rng = np.random.default_rng(3)
    n, dim = 30, 3
    B = rng.standard_normal((n * dim, n * dim))
    W = B @ B.T / (n * dim) + np.eye(n * dim)
    W = W + skew * rng.standard_normal(W.shape)
    q = np.zeros(n * dim)
    q[::dim] = rng.standard_normal(n)
    dense = solve(LocalProblem(W, q, np.zeros(n), dim))
    sparse = solve(LocalProblem(sp.csr_matrix(W), q, np.zeros(n), dim))
    assert dense.success and sparse.success
    assert 0 < np.count_nonzero(dense.forces) < n
    np.testing.assert_allclose(dense.forces, sparse.forces, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(dense.displacements, sparse.displacements, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(dense.displacements, W @ dense.forces + q, rtol=1e-12, atol=1e-14)
    assert dense.certificate.limits.rounding == pytest.approx(
        sparse.certificate.limits.rounding, rel=1e-12
    )

"""The FFT half-space and half-plane operators against independent truths.

Non-periodic: the dense influence matrices of :mod:`contactqp.compliance.halfspace` (products
to 1e-12 relative: an FFT of a few hundred points rounds at ~1e-15), and for the half-plane a
quadrature of the line-load kernel. Periodic: closed-form Westergaard displacements of
sinusoidal tractions, which a grid mode reproduces to rounding (the kernel is spectral).
"""

from __future__ import annotations

import numpy as np
import pytest

from contactqp.compliance import (
    HalfSpaceOperator,
    grid,
    influence_matrix,
    normal_influence,
)
from contactqp.core.operators import as_operator
from contactqp.errors import UnsupportedProblemError

E, NU = 210e9, 0.3
GRIDS = [(1, 1, 1e-3, 1e-3), (7, 1, 1e-3, 2e-3), (1, 6, 2e-3, 1e-3), (5, 3, 1e-3, 2e-3),
         (8, 6, 1.5e-3, 1e-3), (13, 16, 1e-3, 1e-3)]  # fmt: skip
#: FFT products round at a few 1e-16 relative per transform on these sizes
PRODUCT_RTOL = 1e-12


def relative(a, b) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize(("nx", "ny", "dx", "dy"), GRIDS)
def test_normal_products_equal_the_dense_love_matrix(nx, ny, dx, dy):
    rng = np.random.default_rng(nx * 100 + ny)
    W = HalfSpaceOperator(nx, ny, dx, dy, E, NU)
    R = normal_influence(*grid(nx, ny, dx, dy), dx, dy, E, NU)
    assert W.shape == R.shape
    f = rng.standard_normal(nx * ny)
    F = rng.standard_normal((nx * ny, 3))
    assert relative(W @ f, R @ f) < PRODUCT_RTOL
    assert (W @ F).shape == F.shape
    assert relative(W @ F, R @ F) < PRODUCT_RTOL
    assert relative(W @ np.abs(f), R @ np.abs(f)) < PRODUCT_RTOL  # one-signed, like pressures


@pytest.mark.parametrize(("nx", "ny", "dx", "dy"), GRIDS)
@pytest.mark.parametrize(("poisson", "coupling"), [(0.3, True), (0.3, False), (-0.4, True)])
def test_full_products_equal_the_dense_cerruti_matrix(nx, ny, dx, dy, poisson, coupling):
    rng = np.random.default_rng(nx * 100 + ny)
    W = HalfSpaceOperator(nx, ny, dx, dy, E, poisson, components="full", coupling=coupling)
    R = influence_matrix(*grid(nx, ny, dx, dy), dx, dy, E, poisson, coupling=coupling)
    assert W.shape == R.shape
    f = rng.standard_normal(3 * nx * ny)
    F = rng.standard_normal((3 * nx * ny, 2))
    assert relative(W @ f, R @ f) < PRODUCT_RTOL
    assert relative(W @ F, R @ F) < PRODUCT_RTOL
    if nx > 1 and coupling:  # the odd coupling terms (along x) are there, with their signs
        tangential = np.zeros(3 * nx * ny)
        tangential[0::3] = rng.random(nx * ny)
        normal_part = (W @ tangential)[2::3]
        assert np.max(np.abs(normal_part)) > 1e-3 * np.max(np.abs(W @ tangential))
        assert relative(normal_part, (R @ tangential)[2::3]) < PRODUCT_RTOL


@pytest.mark.parametrize("components", ["normal", "full"])
def test_blocks_and_diagonals_are_the_dense_entries(components):
    nx, ny, dx, dy = 6, 5, 1e-3, 1.5e-3
    W = HalfSpaceOperator(nx, ny, dx, dy, E, NU, components=components)
    x, y = grid(nx, ny, dx, dy)
    R = (
        normal_influence(x, y, dx, dy, E, NU)
        if components == "normal"
        else influence_matrix(x, y, dx, dy, E, NU)
    )
    n = R.shape[0]
    rng = np.random.default_rng(3)
    rows = rng.permutation(n)[: n // 3]
    mask = rng.random(n) < 0.4
    # the same closed forms evaluated on the same offsets: equal to the last bit or two
    np.testing.assert_allclose(W.block(), R, rtol=1e-14, atol=0)
    np.testing.assert_allclose(W.block(rows, mask), R[rows][:, mask], rtol=1e-14, atol=0)
    np.testing.assert_allclose(W.block(slice(2, 9), rows), R[2:9][:, rows], rtol=1e-14, atol=0)
    np.testing.assert_allclose(W.diagonal(), np.diag(R), rtol=1e-14, atol=0)
    size = 1 if components == "normal" else 3
    dense = as_operator(R)
    np.testing.assert_allclose(
        W.diagonal_blocks(size), dense.diagonal_blocks(size), rtol=1e-14, atol=0
    )
    if components == "full":  # another size: the generic path of the base class
        np.testing.assert_allclose(
            W.diagonal_blocks(2), dense.diagonal_blocks(2), rtol=1e-14, atol=0
        )
    factor = W.cholesky(rows)  # the base class's factorisation works on the blocks
    principal = R[np.ix_(np.sort(rows), np.sort(rows))]
    scale = np.max(principal)
    np.testing.assert_allclose(factor.lower @ factor.lower.T, principal, atol=1e-14 * scale)


def test_the_operator_never_forms_its_matrix():
    W = HalfSpaceOperator(4, 4, 1e-3, 1e-3, E, NU)
    with pytest.raises(UnsupportedProblemError, match="HalfSpaceOperator does not form one"):
        _ = W.matrix
    assert as_operator(W) is W

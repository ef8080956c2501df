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
    # |W| |r| on the normal rows, the only ones a frictionless certificate depends on
    np.testing.assert_allclose(magnitude[::dim], (np.abs(W) @ np.abs(r))[::dim], rtol=1e-14, atol=0)
    assert not magnitude.reshape(n, dim)[:, 1:].any()


@pytest.mark.parametrize("mu", [[0.0, 0.0, 0.0], [0.3, 0.0, 0.5], [0.3, 0.2, 0.5]])
def test_certified_rows_are_those_the_natural_map_depends_on(mu):
    """The rows left out of the certificate's limits (tangential rows of frictionless contacts)
    do not move the natural map's numerator, whatever u there; all others are kept."""
    from contactqp.core.local_problem import natural_map_residual

    rng = np.random.default_rng(7)
    dim, n = 3, len(mu)
    frictionless = np.array(mu) == 0
    B = rng.standard_normal((n * dim, n * dim))
    problem = LocalProblem(B @ B.T, rng.standard_normal(n * dim), np.array(mu), dim)
    expected = np.ones((n, dim), dtype=bool)
    expected[frictionless, 1:] = False
    kept = np.zeros(n * dim, dtype=bool)
    kept[problem.certified_rows] = True
    np.testing.assert_array_equal(kept, expected.ravel())
    for _ in range(5):
        r = rng.standard_normal(n * dim)
        r.reshape(n, dim)[frictionless, 1:] = 0.0  # a frictionless contact's r_T is 0
        u = rng.standard_normal(n * dim)
        residual = natural_map_residual(problem, r, u)[0]
        moved = u + np.where(kept, 0.0, 10.0 * rng.standard_normal(n * dim))
        assert natural_map_residual(problem, r, moved)[0] == residual


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


def test_box_qp_decrease_is_accurate_where_objective_values_cancel():
    """Near a minimiser the decrease of a tiny step is far below the rounding of f itself; the
    projected Newton search judges steps by it, so it must keep its digits (exact reference)."""
    from fractions import Fraction

    from contactqp.core.operators import as_operator
    from contactqp.methods.box_qp import _BoxQP

    rng = np.random.default_rng(5)
    n = 8
    B = rng.standard_normal((n, n))
    W = B @ B.T + np.eye(n)
    c = rng.standard_normal(n)
    qp = _BoxQP(as_operator(W), c, np.full(n, -np.inf), np.full(n, np.inf), 1e-12)
    x = np.linalg.solve(W, -c) + 1e-6 * rng.standard_normal(n)
    step = -1e-9 * (W @ x + c)
    exact_W = [[Fraction(v) for v in row] for row in W]

    def exact_f(z):
        z = [Fraction(v) for v in z]
        Wz = [sum(a * b for a, b in zip(row, z, strict=True)) for row in exact_W]
        return sum(
            zi * (Fraction(1, 2) * wi + Fraction(ci)) for zi, wi, ci in zip(z, Wz, c, strict=True)
        )

    trial = x + step
    exact = float(exact_f(x) - exact_f(trial))
    assert exact > 0
    assert qp.decrease(x, W @ x + c, trial - x) == pytest.approx(exact, rel=1e-6, abs=0)
    difference = float(x @ (0.5 * (W @ x) + c) - trial @ (0.5 * (W @ trial) + c))
    assert difference != pytest.approx(exact, rel=0.5, abs=0)  # what the old search compared


@pytest.mark.parametrize("threads", ["1", "2"])
def test_singular_normal_block_converges_whatever_the_blas_threads(threads):
    """Capsules-i122's normal block is singular and slightly unsymmetric; its frictionless twin
    needs the projected Newton phase, whose line search once stalled one step short (error
    3.9e-8) with one BLAS thread only."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    fclib = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
    script = (
        "import numpy as np\n"
        "from contactqp import solve\n"
        "from contactqp.core.local_problem import LocalProblem, natural_map_error\n"
        "from contactqp.io.fclib import read_problem\n"
        f"p = read_problem({str(fclib / 'Capsules-i122-1617.dat')!r})\n"
        "p = LocalProblem(p.W, p.q, np.zeros_like(p.mu), p.dim)\n"
        "result = solve(p)\n"
        "print(result.success, natural_map_error(p, result.forces))\n"
    )
    env = {**os.environ, "OPENBLAS_NUM_THREADS": threads, "OMP_NUM_THREADS": threads}
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True
    )
    success, error = proc.stdout.split()
    assert success == "True" and float(error) <= 1e-8

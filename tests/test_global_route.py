"""Global problems condensed by the structure of M (contactqp.methods.global_route).

Truths used:

* the problem's own condensation (:meth:`GlobalProblem.condense`: a sparse LU factorisation of
  ``M`` and one solve per column of ``H``) is the reference: the exact condensation agrees with
  it to 1e-12 relative (both are exact up to rounding of well-conditioned matrices);
* the certificate on the global equations computed by a fresh problem, through its own LU
  factorisation (``GlobalProblem.certify`` without a factor): it agrees with the one made with
  the exact factor, and the shared global files meet 1e-8 on it;
* the shared global files need exactly the Newton iterations they needed through the dense
  condensation (``solve_coulomb`` of ``problem.condense()``);
* a singular ``M`` is refused, and an ``M`` that is not positive definite gives no proof that
  ``W`` is semidefinite: the check of ``W`` runs and refuses an indefinite one.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp as cq
from contactqp import kernels
from contactqp.core.local_problem import GlobalProblem
from contactqp.errors import NotPositiveDefiniteError
from contactqp.io.fclib import read_any
from contactqp.methods.coulomb import solve_coulomb
from contactqp.methods.global_route import (
    BlockDiagonalMass,
    DenseMass,
    block_size,
    condense,
    factor_mass,
)

FCLIB = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
GLOBAL_FILES = [
    "GFC3D_Example1.dat",
    "GFC3D_TwoRods1.dat",
    "Box_Stacks-i0035-31-0.hdf5",
    "Box_Stacks-i0122-82-5.hdf5",
    "CubeH8.hdf5",
    "LMGC_GlobalFrictionContactProblem00046.hdf5",
    "Spheres-i099-356-679.hdf5",
    "spheres-in-a-box-98-i10000-256-10.hdf5",
]


def mass(kind: str, ndof: int, rng) -> np.ndarray:
    """A nonsingular ``M`` of the given structure."""
    if kind == "diagonal":
        return np.diag(rng.uniform(0.5, 2.0, ndof) * 10.0 ** rng.integers(-3, 3, ndof))
    if kind == "blocks":  # rigid bodies: 6x6 SPD blocks of very different sizes
        blocks = []
        for _ in range(ndof // 6):
            B = rng.standard_normal((6, 6))
            blocks.append((B @ B.T + 6 * np.eye(6)) * 10.0 ** rng.integers(-2, 3))
        return sp.block_diag(blocks).toarray()
    B = rng.standard_normal((ndof, ndof))
    if kind == "symmetric":
        return B @ B.T / ndof + np.eye(ndof)
    return B / np.sqrt(ndof) + 3.0 * np.eye(ndof)  # unsymmetric


def global_problem(kind="diagonal", ndof=24, nc=5, dim=3, sparse=True, seed=0):
    rng = np.random.default_rng(seed)
    M = mass(kind, ndof, rng)
    H = rng.standard_normal((ndof, dim * nc)) * (rng.uniform(size=(ndof, dim * nc)) < 0.3)
    w = np.zeros(dim * nc)
    w[::dim] = -0.2
    f = rng.standard_normal(ndof)
    if sparse:
        M, H = sp.csr_matrix(M), sp.csr_matrix(H)
    return GlobalProblem(M, H, f, w, np.full(nc, 0.3), dim)


def dense_of(W):
    return W.toarray() if sp.issparse(W) else np.asarray(W)


@pytest.mark.parametrize(
    "kind, factor, size",
    [
        ("diagonal", BlockDiagonalMass, 1),
        ("blocks", BlockDiagonalMass, 6),
        ("symmetric", DenseMass, None),
        ("unsymmetric", DenseMass, None),
    ],
)
@pytest.mark.parametrize("sparse", [True, False])
def test_exact_condensation_agrees_with_the_lu_one(kind, factor, size, sparse):
    problem = global_problem(kind, sparse=sparse, seed=1)
    found = factor_mass(problem)
    assert isinstance(found, factor)
    assert block_size(problem.M) == size
    condensed = condense(problem)
    reference = GlobalProblem(*(getattr(problem, n) for n in ("M", "H", "f", "w", "mu", "dim")))
    W, W_ref = dense_of(condensed.local.W), dense_of(reference.condense().W)
    np.testing.assert_allclose(W, W_ref, rtol=1e-12, atol=1e-12 * np.abs(W_ref).max())
    q_ref = reference.condense().q
    np.testing.assert_allclose(
        condensed.local.q, q_ref, rtol=1e-12, atol=1e-12 * np.abs(q_ref).max()
    )
    assert found.condition == pytest.approx(reference._factor.condition, rel=0.5)  # both estimates
    assert found.positive_definite == (kind != "unsymmetric")


@pytest.mark.parametrize("kind", ["diagonal", "blocks", "symmetric", "unsymmetric"])
def test_certificate_with_the_exact_factor_agrees_with_the_problems_own(kind):
    problem = global_problem(kind, seed=2)
    result = cq.solve(problem, tol=1e-10)
    assert result.success
    fresh = GlobalProblem(*(getattr(problem, n) for n in ("M", "H", "f", "w", "mu", "dim")))
    own = fresh.certify(result.forces)
    assert own.error <= 1e-10 and own.equilibrium <= 1e-10
    assert result.certificate.natural_map == pytest.approx(own.error, rel=1e-3, abs=1e-14)
    np.testing.assert_allclose(result.v, own.v, rtol=1e-9, atol=1e-12 * np.abs(own.v).max())


def test_large_general_mass_uses_the_problems_sparse_factor():
    rng = np.random.default_rng(3)
    ndof = 600
    M = sp.random(ndof, ndof, density=0.005, random_state=3) + 4.0 * sp.identity(ndof)
    M = sp.csr_matrix(M + M.T)
    H = sp.csr_matrix(sp.random(ndof, 12, density=0.05, random_state=4))
    w = np.zeros(12)
    w[::3] = -0.1
    problem = GlobalProblem(M, H, rng.standard_normal(ndof), w, np.full(4, 0.3), 3)
    condensed = condense(problem)
    assert not isinstance(condensed.factor, (BlockDiagonalMass, DenseMass))
    assert condensed.local is problem.condense()


@pytest.mark.parametrize(
    "M",
    [
        np.diag([1.0, 0.0, 2.0, 1.0, 1.0, 1.0]),
        sp.block_diag([np.ones((2, 2)), np.eye(2), np.eye(2)]).toarray(),  # a singular block
        np.ones((6, 6)),  # one full block of rank 1
    ],
    ids=["zero-diagonal", "singular-block", "singular-full"],
)
def test_singular_mass_is_refused(M):
    """Each structure's factor refuses it; a dense general one is refused below too."""
    H = np.eye(6)
    problem = GlobalProblem(M, H, np.ones(6), -np.ones(6), [0.3, 0.3], 3)
    with pytest.raises(NotPositiveDefiniteError, match="singular"):
        cq.solve(problem)


def test_indefinite_mass_leaves_the_check_of_w_to_run():
    M = np.diag([-1.0, 1.0, 1.0, 1.0, 1.0, 1.0])  # nonsingular, W = H^T M^-1 H indefinite
    problem = GlobalProblem(M, np.eye(6), np.ones(6), -np.ones(6), [0.3, 0.3], 3)
    assert not factor_mass(problem).positive_definite
    with pytest.raises(NotPositiveDefiniteError, match="not positive semidefinite"):
        cq.solve(problem)


@pytest.mark.parametrize("name", GLOBAL_FILES)
def test_shared_global_files_keep_their_newton_iterations_and_certificates(name, monkeypatch):
    """The general route (the compiled one, which runs Newton on each group of contacts apart,
    switched off: tests/test_global_compiled.py compares the two)."""
    monkeypatch.setattr(kernels, "global_small", None)
    given = read_any(FCLIB / name)
    result = cq.solve(given, method="coulomb")
    fresh = read_any(FCLIB / name)
    reference = solve_coulomb(fresh.condense())  # the dense condensation's route
    assert result.success and result.iterations == reference.iterations
    certificate = fresh.certify(result.forces)  # the problem's own LU factorisation
    assert certificate.error <= 1e-8 and certificate.equilibrium <= 1e-8


def test_singular_general_mass_is_refused():
    rng = np.random.default_rng(5)
    B = rng.standard_normal((20, 19))
    M = B @ B.T  # rank 19 of 20, no block structure
    problem = GlobalProblem(M, np.eye(20)[:, :6], np.ones(20), -np.ones(6), [0.3, 0.3], 3)
    assert block_size(M) is None
    with pytest.raises(NotPositiveDefiniteError, match="singular"):
        cq.solve(problem)


@pytest.mark.parametrize(
    "name",
    [name for name in GLOBAL_FILES if "i0122" not in name and "pheres" not in name],
)  # the five files whose H has at most DENSE_READ entries
def test_the_certificate_reads_small_sparse_matrices_dense_to_the_same_values(name, monkeypatch):
    """The small shared files' M and H are read dense by the certificate (DENSE_READ); the
    sparse reading gives the same certificate to rounding."""
    from contactqp.core import local_problem

    given = read_any(FCLIB / name)
    assert sp.issparse(given.H) and isinstance(given._read[1], np.ndarray)
    r = cq.solve(given).forces
    dense = given.certify(r)
    monkeypatch.setattr(local_problem, "DENSE_READ", 0)
    sparse = read_any(FCLIB / name)
    assert sp.issparse(sparse._read[1])
    other = sparse.certify(r)
    for a, b in ((dense.error, other.error), (dense.equilibrium, other.equilibrium)):
        assert a == pytest.approx(b, rel=1e-6, abs=1e-15)
    # u = H^T v + w cancels at contacts at rest: rounding relative to the terms summed
    terms = abs(sparse.H.T) @ np.abs(other.v) + np.abs(sparse.w)
    assert np.all(np.abs(dense.u - other.u) <= 1e-12 * np.max(terms))
    assert np.allclose(dense.v, other.v, rtol=1e-12, atol=1e-14 * np.max(np.abs(other.v)))
    # (the rounding limit is not compared: its condition number is a randomised estimate)
    assert dense.limits.data == pytest.approx(other.limits.data, rel=1e-9, abs=1e-300)

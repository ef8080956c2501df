"""The compiled small global route (contactqp.methods.global_route.solve_compiled).

Truths used:

* the general route (condensation by :func:`~contactqp.methods.global_route.condense`,
  ``coulomb`` on the condensed problem, the Python certificate
  :meth:`GlobalProblem.certify` with the same factor): the compiled route gives the same
  verdict, iterations and answer on every shared global file, up to the solver tolerance;
* the Python certificate of the same reactions: the compiled one (``certify_compiled``) has
  the same fields up to rounding, on the shared files' answers and on perturbed reactions (where
  the residuals are far from zero and every term counts), for every structure of ``M`` (diagonal,
  rigid-body blocks, dense symmetric, dense unsymmetric, banded);
* the natural-map error recomputed by a fresh problem from the returned reactions
  (``GlobalProblem.certify`` through its own sparse LU factorisation);
* what the general route refuses (a singular ``M``; an indefinite ``W`` from an unsymmetric
  ``M``), the compiled one refuses with the same error, and a problem it does not take falls
  to the general route.

Rounding: the two certificates add the same terms in another order. Their natural-map errors
then differ by about the rounding that the certificate itself estimates
(``limits.rounding``), and the other figures by a few ulps relative; the tolerances below are
those bounds with a factor 100 of margin.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp as cq
from contactqp import kernels
from contactqp.core.local_problem import GlobalProblem
from contactqp.errors import InvalidInputError, NotPositiveDefiniteError
from contactqp.io.fclib import read_any
from contactqp.methods import global_route
from contactqp.methods.global_route import certify_compiled, condense

FCLIB = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
GLOBAL_FILES = [
    "GFC3D_Example1.dat",
    "GFC3D_TwoRods1.dat",
    "Box_Stacks-i0035-31-0.hdf5",
    "Box_Stacks-i0122-82-5.hdf5",
    "CubeH8.hdf5",
    "LMGC_GlobalFrictionContactProblem00046.hdf5",
]
#: the files the compiled route takes (every M block diagonal or at most 400 freedoms, m <= 600)
#: in one group of contacts, or in groups the general route also gives in one Newton run
#: (Spheres-i099, a block-diagonal M and 137 groups of 1,068 unknowns in all, is below)
EPS = np.finfo(float).eps

#: the compiled route's tests need its kernel (the pure-numpy run's test does not)
needs_kernels = pytest.mark.skipif(
    kernels.global_small is None, reason="the compiled kernels are not in use"
)


def fresh(problem: GlobalProblem) -> GlobalProblem:
    return GlobalProblem(
        problem.M,
        problem.H,
        problem.f,
        problem.w,
        problem.mu,
        problem.dim,
        problem.title,
        problem.digits,
    )


@pytest.fixture(scope="module")
def files():
    return {name: read_any(FCLIB / name) for name in GLOBAL_FILES}


def general(problem: GlobalProblem, monkeypatch, **options):
    """The general route's answer by ``coulomb`` (the compiled kernel switched off; without a
    method named, the general route would take the planar or spatial route by size)."""
    options.setdefault("method", "coulomb")
    with monkeypatch.context() as patch:
        patch.setattr(kernels, "global_small", None)
        return cq.solve(fresh(problem), **options)


def python_certificate(problem: GlobalProblem, r):
    """Today's Python certificate of ``r``, with the factor of the general route."""
    condensed = condense(fresh(problem))
    certificate = fresh(problem).certify(r, factor=condensed.factor, local=condensed.local)
    _R[id(certificate)] = np.asarray(r, dtype=float)
    return certificate


_R: dict[int, np.ndarray] = {}


def reference_r(certificate, problem):
    """The reactions a :func:`python_certificate` was made of."""
    return _R[id(certificate)]


def python_factor(problem):
    return condense(fresh(problem)).factor


def counting_kernel(monkeypatch) -> list[int]:
    """The codes the compiled kernel returns from now on (the kernel itself still runs)."""
    codes: list[int] = []
    real = kernels.global_small
    assert real is not None

    def counted(*args):
        codes.append(real(*args))
        return codes[-1]

    monkeypatch.setattr(kernels, "global_small", counted)
    return codes


def assert_same_certificate(compiled, reference, problem):
    """The figures of two certificates of the same ``r`` agree to their rounding: ``u`` to that
    of ``|H^T| |v| + |w|`` (its terms, which cancel at a solution), ``v`` to ``cond(M)`` ulps
    of ``|v|`` and of ``M^-1 (|H| |r| + |f|)``."""
    H = abs(sp.csr_matrix(problem.H))
    condition = reference.limits.condition
    terms_u = np.abs(H.T @ np.abs(reference.v)).max() + np.abs(problem.w).max()
    terms_v = (
        np.abs(reference.v).max()
        + np.abs(
            python_factor(problem).solve(
                H @ np.abs(reference_r(reference, problem)) + np.abs(problem.f)
            )
        ).max()
    )
    np.testing.assert_allclose(
        compiled.u, reference.u, rtol=0, atol=1e3 * condition * EPS * terms_u
    )
    np.testing.assert_allclose(
        compiled.v, reference.v, rtol=0, atol=1e3 * condition * EPS * terms_v
    )
    assert abs(compiled.error - reference.error) <= 100 * reference.limits.rounding + 1e-300
    assert abs(compiled.equilibrium - reference.equilibrium) <= 100 * condition * EPS
    limits, expected = compiled.limits, reference.limits
    assert limits.rounding == pytest.approx(expected.rounding, rel=1e-8)
    assert limits.data == pytest.approx(expected.data, rel=1e-8)
    assert limits.condition == pytest.approx(expected.condition, rel=1e-8)
    assert limits.digits == expected.digits


@pytest.mark.parametrize("name", GLOBAL_FILES)
@needs_kernels
def test_shared_files_are_solved_as_by_the_general_route(name, files, monkeypatch):
    problem = files[name]
    calls = counting_kernel(monkeypatch)
    result = cq.solve(fresh(problem), tol=1e-8)
    assert calls == [0]  # the compiled route gave the answer
    reference = general(problem, monkeypatch, tol=1e-8)
    assert result.success and reference.success
    assert result.iterations <= reference.iterations
    assert result.method == reference.method == "coulomb"
    assert result.message.startswith("converged on the global equations as written")
    # both answers solve the problem to 1e-8: they agree to about that, relative
    size = np.abs(reference.forces).max()
    np.testing.assert_allclose(result.forces, reference.forces, rtol=0, atol=1e-6 * size)
    np.testing.assert_array_equal(result.contact_status, reference.contact_status)
    # judged independently, by a fresh problem through its own LU factorisation
    own = fresh(problem).certify(result.forces)
    assert own.error <= 1e-8 and own.equilibrium <= 1e-8
    assert abs(own.error - result.certificate.natural_map) <= 100 * own.limits.rounding + 1e-15


@pytest.mark.parametrize("name", GLOBAL_FILES)
@needs_kernels
def test_compiled_certificate_equals_the_python_one_on_the_shared_files(name, files):
    problem = files[name]
    result = cq.solve(fresh(problem), tol=1e-8)
    reference = python_certificate(problem, result.forces)
    certificate = result.certificate
    assert abs(certificate.natural_map - reference.error) <= 100 * reference.limits.rounding
    assert abs(certificate.equilibrium - reference.equilibrium) <= (
        100 * reference.limits.condition * EPS
    )
    compiled = certify_compiled(fresh(problem), result.forces)
    assert compiled is not None
    assert_same_certificate(compiled, reference, problem)
    np.testing.assert_allclose(
        result.v, reference.v, rtol=0, atol=1e3 * EPS * np.abs(reference.v).max()
    )


@pytest.mark.parametrize("name", GLOBAL_FILES)
@needs_kernels
def test_compiled_certificate_of_perturbed_reactions(name, files):
    problem = files[name]
    r = cq.solve(fresh(problem), tol=1e-8).forces
    rng = np.random.default_rng(3)
    perturbed = r + 0.1 * np.abs(r).max() * rng.standard_normal(r.shape)
    reference = python_certificate(problem, perturbed)
    assert reference.error > 1e-6  # far from a solution: every term of the residual counts
    compiled = certify_compiled(fresh(problem), perturbed)
    assert compiled is not None
    assert compiled.error == pytest.approx(reference.error, rel=1e-9)
    assert_same_certificate(compiled, reference, problem)


def structured(kind: str, seed: int = 0, nc: int = 4, digits=None) -> GlobalProblem:
    """A global problem of ``nc`` contacts whose ``M`` has the structure ``kind``."""
    rng = np.random.default_rng(seed)
    ndof = 24
    if kind == "diagonal":
        M = np.diag(rng.uniform(0.5, 2.0, ndof) * 10.0 ** rng.integers(-3, 3, ndof))
    elif kind == "blocks":  # rigid bodies: 6x6 SPD blocks of very different sizes
        blocks = []
        for _ in range(ndof // 6):
            B = rng.standard_normal((6, 6))
            blocks.append((B @ B.T + 6 * np.eye(6)) * 10.0 ** rng.integers(-2, 3))
        M = sp.block_diag(blocks).toarray()
    elif kind in ("symmetric", "unsymmetric"):
        B = rng.standard_normal((ndof, ndof))
        M = B @ B.T / ndof + np.eye(ndof) if kind == "symmetric" else B / 5 + 3 * np.eye(ndof)
    else:  # banded: tridiagonal-ish symmetric, or an unsymmetric band (LAPACK band storage)
        ndof = 60
        M = 4.0 * np.eye(ndof)
        for k in (1, 2):
            band = rng.uniform(-0.5, 0.5, ndof - k)
            M += np.diag(band, k) + np.diag(band if kind == "band-symmetric" else band / 3, -k)
    H = rng.standard_normal((ndof, 3 * nc)) * (rng.uniform(size=(ndof, 3 * nc)) < 0.4)
    w = np.zeros(3 * nc)
    w[::3] = -0.2
    return GlobalProblem(
        sp.csr_matrix(M),
        sp.csr_matrix(H),
        rng.standard_normal(ndof),
        w,
        np.full(nc, 0.3),
        3,
        digits=digits or {},
    )


KINDS = ["diagonal", "blocks", "symmetric", "unsymmetric", "band-symmetric", "band-unsymmetric"]


@pytest.mark.parametrize("kind", KINDS)
@needs_kernels
def test_every_structure_of_m(kind, monkeypatch):
    problem = structured(kind)
    result = cq.solve(fresh(problem), tol=1e-10)
    reference = general(problem, monkeypatch, tol=1e-10)
    assert result.success == reference.success
    assert result.iterations == reference.iterations  # one group of contacts here: the same run
    assert result.certificate.limits.condition == pytest.approx(
        reference.certificate.limits.condition, rel=1e-8
    )
    np.testing.assert_allclose(
        result.forces, reference.forces, rtol=0, atol=1e-8 * np.abs(reference.forces).max()
    )
    assert_same_certificate(
        certify_compiled(fresh(problem), result.forces),
        python_certificate(problem, result.forces),
        problem,
    )


@pytest.mark.parametrize("kind", ["blocks", "unsymmetric"])
@needs_kernels
def test_written_digits_give_the_same_data_limit(kind):
    problem = structured(kind, digits={"M": 6, "H": 5, "f": 7, "w": 4})
    r = cq.solve(fresh(problem), tol=1e-10).forces
    reference = python_certificate(problem, r)
    assert reference.limits.data > 0
    assert_same_certificate(certify_compiled(fresh(problem), r), reference, problem)


@needs_kernels
def test_dense_arrays_and_wide_indices_give_the_same_answer():
    problem = structured("blocks", seed=4)
    sparse = cq.solve(fresh(problem), tol=1e-10)
    dense = cq.solve(
        GlobalProblem(
            problem.M.toarray(), problem.H.toarray(), problem.f, problem.w, problem.mu, 3
        ),
        tol=1e-10,
    )
    wide_m, wide_h = problem.M.copy(), problem.H.copy()
    for matrix in (wide_m, wide_h):
        matrix.indices = matrix.indices.astype(np.int64)
        matrix.indptr = matrix.indptr.astype(np.int64)
    wide = GlobalProblem(wide_m, wide_h, problem.f, problem.w, problem.mu, 3)
    assert wide.M.indices.dtype == np.int64
    wide_result = cq.solve(wide, tol=1e-10)
    for other in (dense, wide_result):
        np.testing.assert_allclose(other.forces, sparse.forces, rtol=0, atol=1e-12)
        assert other.iterations == sparse.iterations


@needs_kernels
def test_uncoupled_contacts_are_solved_apart(monkeypatch):
    """Contacts on different bodies (a block-diagonal M, each contact on its own body) make
    uncoupled groups: each is solved on its own, and the whole meets tol."""
    rng = np.random.default_rng(7)
    n_bodies = 5
    blocks, columns = [], []
    for body in range(n_bodies):
        B = rng.standard_normal((6, 6))
        blocks.append(B @ B.T + 6 * np.eye(6))
        J = np.zeros((6 * n_bodies, 3))
        J[6 * body : 6 * body + 6] = rng.standard_normal((6, 3))
        columns.append(J)
    H = np.hstack(columns)
    w = np.tile([-0.1, 0.02, 0.0], n_bodies)
    problem = GlobalProblem(
        sp.csr_matrix(sp.block_diag(blocks)),
        sp.csr_matrix(H),
        rng.standard_normal(6 * n_bodies),
        w,
        np.full(n_bodies, 0.4),
        3,
    )
    result = cq.solve(fresh(problem), tol=1e-10)
    assert result.success
    assert f"on {n_bodies} groups of contacts that W does not couple" in result.message
    assert fresh(problem).certify(result.forces).error <= 1e-10
    reference = general(problem, monkeypatch, tol=1e-10)
    np.testing.assert_allclose(
        result.forces, reference.forces, rtol=0, atol=1e-8 * np.abs(reference.forces).max()
    )


@pytest.mark.filterwarnings("ignore::scipy.linalg.LinAlgWarning")  # the general route's LU
@needs_kernels
def test_singular_m_is_refused_as_by_the_general_route(monkeypatch):
    problem = structured("symmetric")
    M = problem.M.toarray()
    M[:, 0] = M[:, 1]
    M[0, :] = M[1, :]  # two equal rows and columns
    singular = GlobalProblem(sp.csr_matrix(M), problem.H, problem.f, problem.w, problem.mu, 3)
    with pytest.raises(NotPositiveDefiniteError, match="singular"):
        cq.solve(fresh(singular), tol=1e-8)
    with pytest.raises(NotPositiveDefiniteError, match="singular"):
        general(singular, monkeypatch, tol=1e-8)
    zero = sp.diags(np.r_[0.0, np.ones(23)]).tocsr()
    with pytest.raises(NotPositiveDefiniteError, match="singular"):
        cq.solve(GlobalProblem(zero, problem.H, problem.f, problem.w, problem.mu, 3), tol=1e-8)


@needs_kernels
def test_indefinite_w_of_an_unsymmetric_m_is_refused():
    """``M = [[1, 5, 0], [0, 1, 0], [0, 0, 1]]`` (unsymmetric, not positive definite) and
    ``H = I`` give ``W = M^-1`` whose symmetric part has the eigenvalues 1 +- 2.5: the
    semidefiniteness check of W runs and refuses it, as on the general route."""
    M = np.eye(3)
    M[0, 1] = 5.0
    problem = GlobalProblem(
        sp.csr_matrix(M),
        sp.identity(3, format="csr"),
        np.zeros(3),
        np.array([-1.0, 0, 0]),
        np.array([0.3]),
        3,
    )
    with pytest.raises(NotPositiveDefiniteError, match="semidefinite"):
        cq.solve(problem, tol=1e-8)
    # without the check, the compiled route solves it (or hands it on) without error
    result = cq.solve(fresh(problem), tol=1e-8, check_psd=False)
    assert np.all(np.isfinite(result.forces))


@needs_kernels
def test_options_are_checked_as_by_coulomb():
    problem = structured("diagonal")
    with pytest.raises(InvalidInputError, match="tol"):
        cq.solve(fresh(problem), tol=-1.0)
    with pytest.raises(InvalidInputError, match="max_iter"):
        cq.solve(fresh(problem), max_iter=0)
    with pytest.raises(InvalidInputError, match="r0"):
        cq.solve(fresh(problem), r0=np.zeros(5))
    with pytest.raises(InvalidInputError, match="r"):
        certify_compiled(fresh(problem), np.zeros(5))


@needs_kernels
def test_warm_start_and_per_contact(monkeypatch):
    problem = structured("unsymmetric", seed=5)
    cold = cq.solve(fresh(problem), tol=1e-10)
    warm = cq.solve(fresh(problem), tol=1e-10, r0=cold.forces)
    assert warm.success and warm.iterations == 0
    strict = cq.solve(fresh(problem), tol=1e-10, per_contact=True)
    reference = general(problem, monkeypatch, tol=1e-10, per_contact=True)
    assert strict.success and strict.iterations == reference.iterations
    assert "each contact's" in strict.message


@needs_kernels
def test_problems_it_does_not_take_go_to_the_general_route(monkeypatch):
    """A dense ``M`` with more contact unknowns than COMPILED_UNKNOWNS, and a block-diagonal
    one whose group of coupled contacts has more than SMALL_UNKNOWNS: the kernel declines
    (code 1, "not handled") and the general route answers, as it does without the kernel."""
    not_handled = kernels.GLOBAL_CODES.index("not handled")
    for kind, patched in (("symmetric", "COMPILED_UNKNOWNS"), ("diagonal", "SMALL_UNKNOWNS")):
        problem = structured(kind, nc=6)
        with monkeypatch.context() as patch:
            patch.setattr(global_route, patched, 12)
            codes = counting_kernel(patch)
            result = cq.solve(fresh(problem), tol=1e-10)
            assert codes == [not_handled], kind
            if patched == "COMPILED_UNKNOWNS":
                assert certify_compiled(fresh(problem), result.forces) is None
        with monkeypatch.context() as patch:  # the default route without the kernel
            patch.setattr(kernels, "global_small", None)
            reference = cq.solve(fresh(problem), tol=1e-10)
        assert result.success and reference.success
        assert (result.method, result.iterations) == (reference.method, reference.iterations)
        size = np.abs(reference.forces).max()
        np.testing.assert_allclose(result.forces, reference.forces, rtol=0, atol=1e-12 * size)


def assert_certified_as_the_general_route(problem, result, monkeypatch, tol, agreement):
    """``result`` meets ``tol`` on the global equations as judged again by a fresh problem
    through its own sparse LU, and its reactions are the general route's (the kernel off) to
    ``agreement`` of the largest, its statuses the same; returns the general route's result."""
    assert result.success
    own = fresh(problem).certify(result.forces)
    assert own.error <= tol and own.equilibrium <= tol
    assert abs(own.error - result.certificate.natural_map) <= 100 * own.limits.rounding + 1e-15
    reference = general(problem, monkeypatch, tol=tol)
    assert reference.success
    size = np.abs(reference.forces).max()
    np.testing.assert_allclose(result.forces, reference.forces, rtol=0, atol=agreement * size)
    np.testing.assert_array_equal(result.contact_status, reference.contact_status)
    return reference


def rigid_bodies(n_pairs: int, seed: int = 0) -> GlobalProblem:
    """``n_pairs`` pairs of rigid bodies (6x6 SPD mass blocks), three contacts between the
    bodies of each pair: a block-diagonal ``M`` whose ``W`` couples only the contacts of one
    pair, far more contact unknowns (9 per pair) than COMPILED_UNKNOWNS."""
    rng = np.random.default_rng(seed)
    blocks, H = [], sp.lil_matrix((12 * n_pairs, 9 * n_pairs))
    for pair in range(n_pairs):
        for _ in range(2):
            B = rng.standard_normal((6, 6))
            blocks.append(B @ B.T + 6 * np.eye(6))
        H[12 * pair : 12 * pair + 12, 9 * pair : 9 * pair + 9] = rng.standard_normal((12, 9))
    w = np.zeros(9 * n_pairs)
    w[::3] = rng.uniform(-0.3, 0.1, 3 * n_pairs)  # most contacts pressed, some open
    return GlobalProblem(
        sp.csr_matrix(sp.block_diag(blocks)),
        sp.csr_matrix(H),
        rng.standard_normal(12 * n_pairs),
        w,
        rng.uniform(0.1, 1.0, 3 * n_pairs),
        3,
    )


@pytest.mark.parametrize(
    "case", ["Spheres-i099", "rigid-bodies"], ids=["Spheres-i099", "200-rigid-body-pairs"]
)
@needs_kernels
def test_block_diagonal_m_beyond_compiled_unknowns_is_solved_by_groups(case, monkeypatch):
    """With a block-diagonal ``M`` the compiled route takes any number of contact unknowns
    whose groups are small, each group solved apart and the whole certified (both cases have
    more than COMPILED_UNKNOWNS):

    * Spheres-i099: 356 contacts, 1,068 unknowns, 2,000 rigid spheres (``M`` diagonal of 12,000
      freedoms) in 137 groups of at most 13 contacts;
    * 200 rigid-body pairs, 1,800 unknowns in groups of 9.

    Judged again by a fresh problem through its own sparse LU, and the general route (the
    kernel off) finds the same reactions; the compiled certificate is the Python one. The
    iteration count, the most any group's Newton run took, is not above the general route's
    (one run on all of ``W``; 9 on Spheres-i099, where regularising each group on its own
    scale took 10)."""
    if case == "Spheres-i099":
        problem, tol, agreement, groups = read_any(FCLIB / f"{case}-356-679.hdf5"), 1e-8, 1e-6, 137
    else:
        problem, tol, agreement, groups = rigid_bodies(200), 1e-10, 1e-8, 200
    assert problem.H.shape[1] > global_route.COMPILED_UNKNOWNS
    codes = counting_kernel(monkeypatch)
    result = cq.solve(fresh(problem), tol=tol)
    assert codes == [0]
    assert f"on {groups} groups of contacts that W does not couple" in result.message
    reference = assert_certified_as_the_general_route(problem, result, monkeypatch, tol, agreement)
    assert result.iterations <= reference.iterations
    compiled = certify_compiled(fresh(problem), result.forces)
    assert compiled is not None
    assert_same_certificate(compiled, python_certificate(problem, result.forces), problem)


def test_pure_numpy_route_runs_without_the_kernel():
    script = (
        "import contactqp as cq\n"
        "from contactqp import kernels\n"
        "from contactqp.io.fclib import read_any\n"
        "assert kernels.global_small is None\n"
        f"r = cq.solve(read_any({str(FCLIB / 'GFC3D_TwoRods1.dat')!r}), tol=1e-8)\n"
        "assert r.success, r.message\n"
        "print(r.iterations)\n"
    )
    env = {**os.environ, kernels.FORCE_PURE_NUMPY: "1"}
    done = subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    assert int(done.stdout.split()[-1]) >= 1


@needs_kernels
def test_two_dimensional_contacts(monkeypatch):
    """2-D contacts (``coulomb`` named, so that the planar route does not take them)."""
    rng = np.random.default_rng(11)
    ndof, nc = 12, 4
    B = rng.standard_normal((ndof, ndof))
    M = B @ B.T / ndof + np.eye(ndof)
    H = rng.standard_normal((ndof, 2 * nc)) * (rng.uniform(size=(ndof, 2 * nc)) < 0.5)
    w = np.tile([-0.2, 0.05], nc)
    problem = GlobalProblem(
        sp.csr_matrix(M), sp.csr_matrix(H), rng.standard_normal(ndof), w, np.full(nc, 0.5), 2
    )
    result = cq.solve(fresh(problem), "coulomb", tol=1e-10)
    reference = general(problem, monkeypatch, tol=1e-10)
    assert result.success and reference.success
    assert result.iterations == reference.iterations
    np.testing.assert_allclose(
        result.forces, reference.forces, rtol=0, atol=1e-8 * np.abs(reference.forces).max()
    )
    assert_same_certificate(
        certify_compiled(fresh(problem), result.forces),
        python_certificate(problem, result.forces),
        problem,
    )


@needs_kernels
def test_groups_whose_newton_run_stops_short_are_solved_again_alone(monkeypatch):
    """rigid_bodies(100, seed=1): the compiled Newton run of one pair's group stalls (code "not
    converged"); that group alone is solved again by coulomb's whole route, the other 99 keep
    their compiled answers, and the whole meets tol on the global equations, judged again by a
    fresh problem through its own sparse LU; the reactions are the general route's (one route
    on all of W, the kernel off) to that accuracy."""
    problem = rigid_bodies(100, seed=1)
    codes = counting_kernel(monkeypatch)
    result = cq.solve(fresh(problem), tol=1e-10)
    not_converged = kernels.GLOBAL_CODES.index("not converged")
    assert codes == [not_converged, 0]  # the solve, then the certificate of the whole answer
    assert "but those of 3 contacts, whose runs stopped short" in result.message
    assert_certified_as_the_general_route(problem, result, monkeypatch, 1e-10, 1e-7)

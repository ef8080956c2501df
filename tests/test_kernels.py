"""The per-contact kernels: compiled and pure-numpy twins agree, and each drives the solvers.

Truths used:

* the pure-numpy kernels (:mod:`contactqp.kernels.pure_numpy`) are the oracle of the compiled
  ones: on random rows (exact zeros, mu = 0 and released contacts included) both give the same
  numbers to rounding. Sums may run in another order, so agreement is to 1e-12 relative, not
  bit for bit; the Alart-Curnier Jacobian, discontinuous where a contact changes regime, is
  compared on contacts at least 1e-9 away from a change;
* the solvers reach the same answers through either implementation (to their tolerance);
* ``CONTACTQP_PURE_NUMPY=1`` selects the pure-numpy kernels without a warning; an absent
  extension selects them with exactly one :class:`PureNumpyKernelsWarning`; and a selection of
  the solver tests passes with the variable set.
"""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import contactqp.kernels
from contactqp.core.local_problem import LocalProblem, natural_map_error
from contactqp.kernels import pure_numpy
from contactqp.methods import coulomb
from contactqp.methods.coulomb import solve_coulomb

ROOT = Path(__file__).resolve().parents[1]
FCLIB = ROOT.parent / "shared" / "data" / "fclib"

try:
    from contactqp.kernels import compiled
except ImportError:  # a build without a C compiler: the oracle has nothing to check
    compiled = None

needs_compiled = pytest.mark.skipif(compiled is None, reason="compiled kernels not built")
IMPLEMENTATIONS = [
    pytest.param(compiled, id="compiled", marks=needs_compiled),
    pytest.param(pure_numpy, id="pure_numpy"),
]
RTOL = 1e-12


def random_rows(seed, n, d):
    """Rows ``(R, U, mu, rho)``: normal draws with some exact zeros, zero rows and mu = 0."""
    rng = np.random.default_rng(seed)
    R, U = rng.standard_normal((n, d)), rng.standard_normal((n, d))
    for X in (R, U):
        X[rng.random((n, d)) < 0.15] = 0.0  # on an axis, a face or the apex
        X[rng.random(n) < 0.05] = 0.0
    mu = np.where(rng.random(n) < 0.1, 0.0, rng.uniform(0.0, 2.0, n))
    rho = rng.uniform(0.1, 10.0, n)
    return R, U, mu, rho


def close(actual, expected):
    scale = max(float(np.max(np.abs(expected), initial=0.0)), 1.0)
    np.testing.assert_allclose(actual, expected, rtol=RTOL, atol=RTOL * scale)


rows = dict(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 60), d=st.sampled_from([2, 3]))


@needs_compiled
@settings(max_examples=60, deadline=None)
@given(**rows)
def test_projection_rows_agree(seed, n, d):
    X, _, mu, _ = random_rows(seed, n, d)
    expected, actual = np.empty_like(X), np.empty_like(X)
    compiled.project_rows(X, mu, expected)
    pure_numpy.project_rows(X, mu, actual)
    close(actual, expected)


@needs_compiled
@settings(max_examples=60, deadline=None)
@given(**rows)
def test_natural_map_rows_agree(seed, n, d):
    R, U, mu, _ = random_rows(seed, n, d)
    expected, actual = np.empty(n), np.empty(n)
    total = compiled.natural_map_rows(R, U, mu, expected)
    assert pure_numpy.natural_map_rows(R, U, mu, actual) == pytest.approx(
        total, rel=RTOL, abs=1e-300
    )
    close(actual, expected)


def away_from_regime_changes(R, U, mu, rho, margin=1e-9):
    """Contacts whose trial point is ``margin`` or more from ``x_N = 0`` and the disc's edge."""
    xn = R[:, 0] - rho * U[:, 0]
    norm = np.linalg.norm(R[:, 1:] - rho[:, None] * U[:, 1:], axis=1)
    radius = mu * np.maximum(xn, 0.0)
    return (np.abs(xn) > margin) & (np.abs(norm - radius) > margin)


@needs_compiled
@settings(max_examples=60, deadline=None)
@given(**rows)
def test_alart_curnier_rows_agree(seed, n, d):
    R, U, mu, rho = random_rows(seed, n, d)
    expected = [np.empty((n, d)), np.empty((n, d, d)), np.empty((n, d, d))]
    actual = [np.empty((n, d)), np.empty((n, d, d)), np.empty((n, d, d))]
    compiled.alart_curnier_rows(R, U, mu, rho, *expected)
    pure_numpy.alart_curnier_rows(R, U, mu, rho, *actual)
    close(actual[0], expected[0])
    smooth = away_from_regime_changes(R, U, mu, rho)
    for jacobian, reference in zip(actual[1:], expected[1:], strict=True):
        close(jacobian[smooth], reference[smooth])
    no_jacobian = np.empty((0, 3, 3))
    Phi = np.empty((n, d))
    pure_numpy.alart_curnier_rows(R, U, mu, rho, Phi, no_jacobian, no_jacobian)
    close(Phi, expected[0])


def newton_structure(seed, nc, d, density):
    """The block structure of coulomb's sparse Newton for a random sparse SPD ``W``."""
    rng = np.random.default_rng(seed)
    pattern = np.kron(rng.random((nc, nc)) < density, np.ones((d, d)))
    base = rng.standard_normal((nc * d, nc * d))
    W = sp.csr_matrix(base @ base.T * np.maximum(pattern, pattern.T) + nc * d * np.eye(nc * d))
    newton = coulomb._Newton(W, np.zeros(nc * d), np.full(nc, 0.3), d, measure=None)
    return newton, rng


def assembled(kernel, newton, A, B, kept):
    kept_unknowns = np.repeat(kept, newton.d)[newton.order]
    renumber = np.cumsum(kept_unknowns, dtype=np.int64) - 1
    renumber[~kept_unknowns] = -1
    n = int(kept_unknowns.sum())
    data = np.empty(newton.csc_indices.size)
    indices = np.empty_like(newton.csc_indices)
    indptr = np.empty(n + 1, dtype=np.int64)
    count = kernel.sparse_newton_matrix(
        A,
        B,
        newton.W_blocks,
        newton.block_row,
        newton.block_col,
        newton.csc_entries,
        newton.csc_indptr,
        newton.csc_indices,
        renumber,
        data,
        indices,
        indptr,
    )
    assert indptr[0] == 0 and indptr[-1] == count and np.all(np.diff(indptr) >= 0)
    return sp.csc_matrix((data[:count], indices[:count], indptr), shape=(n, n)).toarray()


@needs_compiled
@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    nc=st.integers(1, 12),
    d=st.sampled_from([2, 3]),
    density=st.sampled_from([0.0, 0.3, 1.0]),
    kept_share=st.sampled_from([0.0, 0.5, 1.0]),
)
def test_sparse_newton_matrices_agree(seed, nc, d, density, kept_share):
    newton, rng = newton_structure(seed, nc, d, density)
    R, U, mu, rho = random_rows(seed, nc, d)
    Phi, A, B = np.empty((nc, d)), np.empty((nc, d, d)), np.empty((nc, d, d))
    pure_numpy.alart_curnier_rows(R, U, mu, rho, Phi, A, B)
    kept = rng.random(nc) < kept_share
    close(assembled(pure_numpy, newton, A, B, kept), assembled(compiled, newton, A, B, kept))


@pytest.mark.parametrize("kernel", IMPLEMENTATIONS)
@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 70), m=st.integers(0, 70))
def test_abs_row_sums_are_the_sums_of_the_rows_asked_for(kernel, seed, n, m):
    rng = np.random.default_rng(seed)
    W = rng.standard_normal((max(n, 1), m))
    W[rng.random(W.shape) < 0.2] = 0.0
    rows = rng.integers(0, W.shape[0], size=rng.integers(0, 3 * n + 1)).astype(np.int64)
    sums = np.full(rows.size, np.nan)
    kernel.abs_row_sums(W, rows, sums)
    close(sums, np.abs(W).sum(axis=1)[rows])  # repeated rows, any order, empty rows


@pytest.mark.parametrize("kernel", IMPLEMENTATIONS)
def test_rows_the_buffers_cannot_hold_are_refused(kernel):
    with pytest.raises(ValueError, match="2 or 3 components"):
        kernel.project_rows(np.zeros((2, 4)), np.zeros(2), np.zeros((2, 4)))
    with pytest.raises(ValueError, match="2 or 3 components"):
        kernel.natural_map_rows(np.zeros((2, 4)), np.zeros((2, 4)), np.zeros(2), np.zeros(2))
    with pytest.raises(ValueError, match="2 or 3 components"):
        kernel.alart_curnier_rows(
            np.zeros((2, 1)),
            np.zeros((2, 1)),
            np.zeros(2),
            np.ones(2),
            np.zeros((2, 1)),
            np.zeros((2, 1, 1)),
            np.zeros((2, 1, 1)),
        )


@pytest.fixture(params=IMPLEMENTATIONS)
def kernels_of(request, monkeypatch):
    """Route the solvers' kernel calls to one implementation for the test."""
    for name in pure_numpy.__all__:
        monkeypatch.setattr(contactqp.kernels, name, getattr(request.param, name))
    return request.param


def random_problem(nc, dim, seed, sparse=False):
    """A well-conditioned SPD W and a q that closes most contacts (as in test_coulomb)."""
    rng = np.random.default_rng(seed)
    m = nc * dim
    A = rng.standard_normal((m, m)) / np.sqrt(m)
    W = A @ A.T * 0.5 + np.eye(m)
    q = 0.3 * rng.standard_normal(m)
    q[::dim] -= 0.5
    return LocalProblem(sp.csr_matrix(W) if sparse else W, q, np.full(nc, 0.3), dim)


@pytest.mark.parametrize("dim, sparse", [(2, False), (3, False), (3, True)])
def test_solver_answers_do_not_depend_on_the_kernels(kernels_of, monkeypatch, dim, sparse):
    if sparse:  # a small sparse W is factored dense: run the SuperLU path with its kernel
        monkeypatch.setattr(contactqp.core.local_problem, "DENSE_SIZE", 0)
        monkeypatch.setattr(contactqp.core.local_problem, "DENSE_FILL", 2.0)
    problem = random_problem(12, dim, seed=3, sparse=sparse)
    solution = solve_coulomb(problem, tol=1e-12)
    assert solution.success and set(solution.status_labels) == {"open", "stick", "slip"}
    dense = LocalProblem(problem.W.toarray() if sparse else problem.W, problem.q, problem.mu, dim)
    # the reference: measured by numpy alone, whatever the kernels
    monkeypatch.setattr(contactqp.kernels, "natural_map_rows", pure_numpy.natural_map_rows)
    assert natural_map_error(dense, solution.forces) <= 1e-11


@pytest.mark.parametrize(
    "name", ["Capsules-i97-269.hdf5", "fc2d_granularflowonwall_02020_00213.dat"]
)
def test_fclib_files_are_solved_with_either_kernels(kernels_of, name):
    from contactqp.io import read_problem

    path = FCLIB / name
    if not path.exists():
        pytest.skip(f"{name} not in the shared FCLIB data")
    problem = read_problem(path)
    solution = solve_coulomb(problem, tol=1e-8)
    assert solution.success, solution.message
    assert natural_map_error(problem, solution.forces) <= 1e-8


def python(code, **environment):
    env = {**os.environ, **environment}
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=env, timeout=120
    )


SOLVE_ONE_CONTACT = """
import numpy as np
from contactqp.core.local_problem import LocalProblem
from contactqp.methods.coulomb import solve_coulomb
solution = solve_coulomb(LocalProblem(np.diag([1.0, 2.0, 2.0]), [-1.0, 0.8, 0.0], [0.3], 3))
assert solution.success, solution.message
np.testing.assert_allclose(solution.forces, [1.0, -0.3, 0.0], atol=1e-12)
"""


def test_the_variable_forces_pure_numpy_without_a_warning():
    code = (
        "import warnings; warnings.simplefilter('error')\n"
        "import contactqp, contactqp.kernels as k\n"
        "assert k.IMPLEMENTATION == 'pure_numpy', k.IMPLEMENTATION\n" + SOLVE_ONE_CONTACT
    )
    proc = python(code, CONTACTQP_PURE_NUMPY="1")
    assert proc.returncode == 0, proc.stderr
    expected = "pure_numpy" if compiled is None else "compiled"
    proc = python(
        "import contactqp.kernels as k; print(k.IMPLEMENTATION)", CONTACTQP_PURE_NUMPY="0"
    )
    assert proc.returncode == 0 and proc.stdout.strip() == expected, proc.stderr


#: Run before ``import contactqp``: the compiled extension cannot be found, as after a build
#: without a C compiler.
WITHOUT_EXTENSION = """
import sys
class NoCompiledKernels:
    def find_spec(self, name, path=None, target=None):
        if name == "contactqp.kernels.compiled":
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, NoCompiledKernels())
"""


def test_an_absent_extension_falls_back_with_one_warning():
    # the warning is recorded from the first import to the end of a solve: one, not one a call
    code = (
        WITHOUT_EXTENSION
        + """
import warnings
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    import contactqp
    import contactqp.kernels as k
    from contactqp.errors import PureNumpyKernelsWarning
"""
        + textwrap.indent(SOLVE_ONE_CONTACT, "    ")
        + """
said = [w for w in caught if issubclass(w.category, PureNumpyKernelsWarning)]
assert len(said) == 1, [str(w.message) for w in caught]
assert "pure-numpy" in str(said[0].message)
assert k.IMPLEMENTATION == "pure_numpy"
"""
    )
    proc = python(code, CONTACTQP_PURE_NUMPY="")  # not asked for: chosen, and said
    assert proc.returncode == 0, proc.stderr


#: Solver tests run again, in a process whose kernels are the pure-numpy ones.
SOLVER_TESTS = ["tests/test_coulomb.py", "tests/test_fclib_io.py"]
SELECTION = (
    "closed_forms or newton_agrees or dense_and_sparse or jacobian_matches or "
    "gauss_seidel_rounds or non_convergence or projection or natural_map"
)


@needs_compiled
def test_solver_tests_pass_on_pure_numpy_kernels():
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "-x",
            *SOLVER_TESTS,
            "-k",
            SELECTION,
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=600,
        env={**os.environ, "CONTACTQP_PURE_NUMPY": "1"},
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert " passed" in proc.stdout and " failed" not in proc.stdout

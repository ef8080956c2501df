"""FCLIB / Siconos problem files, the local problem and its natural-map error.

The data are the Siconos and FCLIB test problems in ``shared/data/fclib`` (see its README).
Tolerances: condensation is compared with a dense ``numpy.linalg.solve`` at 1e-9 relative
(both are backward-stable solves of matrices with condition numbers up to 1e7); everything
read or written by us is compared exactly.
"""

import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from contactqp.core.local_problem import (
    GlobalProblem,
    LocalProblem,
    column_products,
    condense_global,
    natural_map_error,
    projection_on_cones,
)
from contactqp.errors import (
    FileFormatError,
    InvalidInputError,
    MissingDependencyError,
    NotPositiveDefiniteError,
    UnsupportedProblemError,
)
from contactqp.io import read_problem, write_problem, write_solution
from contactqp.io.fclib import read_global_problem
from contactqp.io.siconos import parse_dat

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib"
FILES = (
    sorted(p.name for p in DATA.iterdir() if p.suffix in (".dat", ".hdf5")) if DATA.is_dir() else []
)

# (dim, n_contacts) of every file, from the file headers (spacedim and len(mu), or d and nc)
SIZES = {
    "Box_Stacks-i0035-31-0.hdf5": (3, 31),
    "Box_Stacks-i0122-82-5.hdf5": (3, 82),
    "Capsules-i122-1617.dat": (3, 296),
    "Capsules-i125-1213.hdf5": (3, 286),
    "Capsules-i97-269.hdf5": (3, 216),
    "Confeti-ex13-Fc3D-SBM.dat": (3, 107),
    "CubeH8.hdf5": (3, 1),
    "FC3D_Example1.dat": (3, 3),
    "FC3D_Example1_SBM.dat": (3, 3),
    "FrictionContact3D_1c.dat": (3, 1),
    "FrictionContactProblem00071.dat": (2, 89),
    "FrictionContactProblem00374.dat": (2, 28),
    "GFC3D_Example1.dat": (3, 1),
    "GFC3D_TwoRods1.dat": (3, 3),
    "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5": (3, 60),
    "LMGC_GlobalFrictionContactProblem00046.hdf5": (3, 9),
    "NESpheres_30_1.dat": (3, 44),
    "Rover1041.dat": (3, 5),
    "Rover4516.dat": (3, 4),
    "Spheres-i099-356-679.hdf5": (3, 356),
    "fc2d_granularflowonwall_02020_00213.dat": (2, 2020),
    "local_problem_test.hdf5": (3, 48),
    "spheres-in-a-box-98-i10000-256-10.hdf5": (3, 256),
}
FEM_BASED = ["CubeH8.hdf5", "GFC3D_TwoRods1.dat", "LMGC_GlobalFrictionContactProblem00046.hdf5"]


def dense(W):
    return W.toarray() if sp.issparse(W) else np.asarray(W)


def header_sizes(path):
    """(dim, n_contacts) read straight from the file, independently of the readers."""
    if path.suffix == ".hdf5":
        with h5py.File(path, "r") as fh:
            g = fh["fclib_local"] if "fclib_local" in fh else fh["fclib_global"]
            return int(g["spacedim"][0]), int(g["vectors/mu"].shape[0])
    d, nc = path.read_text().split()[:2]
    return int(d), int(nc)


def test_data_directory_present():
    assert DATA.is_dir(), f"missing test data directory {DATA}"
    assert len(FILES) >= len(SIZES)


@pytest.mark.parametrize("name", FILES or ["<missing data directory>"])
def test_every_file_loads(name):
    path = DATA / name
    assert path.is_file(), f"missing {path}"
    problem = read_problem(path)
    dim, nc = header_sizes(path)
    if name in SIZES:
        assert SIZES[name] == (dim, nc)
    m = dim * nc
    assert problem.dim == dim
    assert problem.n_contacts == nc
    assert problem.W.shape == (m, m)
    assert problem.q.shape == (m,)
    assert problem.mu.shape == (nc,)
    assert np.all(np.isfinite(dense(problem.W)))
    assert np.all(problem.mu >= 0)


@pytest.mark.parametrize("name", FEM_BASED)
def test_fem_based_w_positive_definite_and_as_given(name):
    W = dense(read_problem(DATA / name).W)
    M = dense(read_global_problem(DATA / name).M)
    d = np.sqrt(np.abs(np.diag(M)))
    m_asymmetry = (np.abs(M - M.T) / (d[:, None] * d[None, :])).max()  # Jacobi-scaled
    w_asymmetry = np.abs(W - W.T).max() / np.abs(W).max()
    # W = H^T M^-1 H as given, not symmetrised. The M of CubeH8 and of the LMGC file (the same
    # matrix) is unsymmetric, e.g. M[83, 86] = 9.81, M[86, 83] = 0 (constrained rows cleared,
    # not their columns): CubeH8's H does not see it, the LMGC file's W is 27 % unsymmetric
    if name == "GFC3D_TwoRods1.dat":
        assert m_asymmetry == 0.0
    else:
        assert m_asymmetry > 0.2
    if name.startswith("LMGC"):
        assert w_asymmetry > 0.1
    else:
        assert w_asymmetry <= 1e-8
    # the README says these have a full-rank W: its symmetric part is positive definite
    assert np.linalg.eigvalsh(0.5 * (W + W.T)).min() > 0


@pytest.mark.parametrize(
    "name, digits",
    [
        ("fc2d_granularflowonwall_02020_00213.dat", {"W": 6}),  # cs_print, %g
        ("FC3D_Example1_SBM.dat", {"W": 7}),  # sparse-block values, %e
        ("FC3D_Example1.dat", {}),  # dense, full precision
        ("GFC3D_TwoRods1.dat", {"M": 7, "H": 7}),
        ("FrictionContact3D_1c.dat", {}),  # integers are exact
        ("CubeH8.hdf5", {}),  # HDF5 holds doubles
    ],
)
def test_significant_digits_of_the_data_are_recorded(name, digits):
    from contactqp.io.fclib import read_any

    assert read_any(DATA / name).digits == digits


def test_example1_dense_equals_sbm():
    a = read_problem(DATA / "FC3D_Example1.dat")
    b = read_problem(DATA / "FC3D_Example1_SBM.dat")
    assert isinstance(a.W, np.ndarray) and sp.issparse(b.W)
    np.testing.assert_array_equal(dense(a.W), dense(b.W))
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.mu, b.mu)
    np.testing.assert_array_equal(dense(a.W), np.eye(9))
    np.testing.assert_array_equal(a.q, np.tile([-1.0, 1.0, 3.0], 3))


def test_one_contact_dat_read_by_hand():
    p = read_problem(DATA / "FrictionContact3D_1c.dat")
    np.testing.assert_array_equal(p.W, [[15, -1, -2], [-1, 14, 1], [-2, 1, 16]])
    np.testing.assert_array_equal(p.q, [-1, 2, 3])
    np.testing.assert_array_equal(p.mu, [0.1])


def _dense_condensation(g):
    M, H = dense(g.M), dense(g.H)
    return H.T @ np.linalg.solve(M, H), H.T @ np.linalg.solve(M, g.f) + g.w


@pytest.mark.parametrize(
    "name",
    [
        "GFC3D_Example1.dat",
        "GFC3D_TwoRods1.dat",
        "LMGC_GlobalFrictionContactProblem00046.hdf5",
        "Box_Stacks-i0035-31-0.hdf5",
    ],
)
def test_condensation_matches_dense_solve(name):
    g = read_global_problem(DATA / name)
    W_ref, q_ref = _dense_condensation(g)
    p = read_problem(DATA / name)
    assert p.dim == g.dim and np.array_equal(p.mu, g.mu)
    np.testing.assert_allclose(dense(p.W), W_ref, rtol=0, atol=1e-9 * np.abs(W_ref).max())
    np.testing.assert_allclose(p.q, q_ref, rtol=0, atol=1e-9 * max(np.abs(q_ref).max(), 1e-300))


def test_gfc3d_example1_layout():
    g = read_global_problem(DATA / "GFC3D_Example1.dat")
    np.testing.assert_array_equal(
        dense(g.M), [[106.5, 81, 126.5], [81, 91.5, 110], [126.5, 110, 163.5]]
    )
    np.testing.assert_array_equal(dense(g.H), np.eye(3))
    np.testing.assert_array_equal(g.f, [0, 0, 0])
    np.testing.assert_array_equal(g.w, [-2.5, -10, -5.5])
    np.testing.assert_array_equal(g.mu, [0.5])
    # H of GFC3D_TwoRods1 is sparse-block with 27x3 (non-square) blocks
    h = read_global_problem(DATA / "GFC3D_TwoRods1.dat")
    assert h.M.shape == (54, 54) and h.H.shape == (54, 9)


def test_global_read_refuses_local_file():
    with pytest.raises(FileFormatError, match="local_problem_test.hdf5"):
        read_global_problem(DATA / "local_problem_test.hdf5")


# --- writing ------------------------------------------------------------------------------


def _spd(n, seed):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    return A @ A.T + n * np.eye(n)


def _assert_same(a, b):
    assert sp.issparse(b.W)
    np.testing.assert_array_equal(dense(a.W), dense(b.W))
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.mu, b.mu)
    assert (a.dim, a.title, a.n_contacts) == (b.dim, b.title, b.n_contacts)


def test_round_trip_dense(tmp_path):
    rng = np.random.default_rng(1)
    p = LocalProblem(_spd(6, 0), rng.standard_normal(6), [0.3, 0.0, 1.7], 2, "dense é")
    write_problem(tmp_path / "p.hdf5", p)
    _assert_same(p, read_problem(tmp_path / "p.hdf5"))


def test_round_trip_sparse(tmp_path):
    rng = np.random.default_rng(2)
    W = sp.random(9, 9, density=0.3, random_state=3, format="csr")
    W = sp.csr_matrix(W + W.T + sp.eye(9))
    p = LocalProblem(W, rng.standard_normal(9) / 3, rng.random(3), 3)
    write_problem(tmp_path / "p.h5", p)
    _assert_same(p, read_problem(tmp_path / "p.h5"))
    with h5py.File(tmp_path / "p.h5", "r") as fh:
        assert int(fh["fclib_local/W/nz"][0]) == -2
        assert fh["fclib_local/W/p"].shape == (10,)


def test_round_trip_of_a_data_file(tmp_path):
    a = read_problem(DATA / "Capsules-i97-269.hdf5")
    write_problem(tmp_path / "c.hdf5", a)
    _assert_same(a, read_problem(tmp_path / "c.hdf5"))


def test_a_large_nearly_full_w_is_read_dense(tmp_path):
    # more than DENSE_SIZE rows and at least two-thirds full: an array, with the same values
    rng = np.random.default_rng(4)
    m = 3 * 70
    W = _spd(m, 4)
    W[rng.random((m, m)) < 0.2] = 0.0  # 80 % full, unsymmetric pattern
    p = LocalProblem(W, rng.standard_normal(m), np.zeros(70), 3)
    write_problem(tmp_path / "full.hdf5", p)
    full = read_problem(tmp_path / "full.hdf5")
    assert isinstance(full.W, np.ndarray)
    np.testing.assert_array_equal(full.W, W)
    # half full, or as full but of DENSE_SIZE rows or fewer: compressed rows, as stored
    W[rng.random((m, m)) < 0.5] = 0.0
    write_problem(tmp_path / "half.hdf5", LocalProblem(W, p.q, p.mu, 3))
    half = read_problem(tmp_path / "half.hdf5")
    assert sp.issparse(half.W)
    np.testing.assert_array_equal(half.W.toarray(), W)
    small = LocalProblem(_spd(198, 1), np.zeros(198), np.zeros(66), 3)
    write_problem(tmp_path / "small.hdf5", small)
    _assert_same(small, read_problem(tmp_path / "small.hdf5"))


@pytest.mark.parametrize("shape", [(0, 3), (5, 0), (7, 4), (700, 90)])
def test_column_products_read_columns_in_place(shape):
    rng = np.random.default_rng(8)
    W = rng.standard_normal((shape[0], 3 * shape[1]))
    x, normal = rng.standard_normal(shape[1]), np.arange(shape[1]) * 3
    copy = W[:, normal]
    for A, columns in [
        (W, slice(0, None, 3)),
        (W, normal),
        (copy, None),
        (sp.csr_matrix(W), normal),
        (sp.csr_matrix(copy), None),
    ]:
        product, magnitude = column_products(A, x, columns)
        np.testing.assert_allclose(product, copy @ x, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(magnitude, np.abs(copy) @ np.abs(x), rtol=1e-13, atol=0)


def test_write_solution(tmp_path):
    r, u = np.arange(3.0), np.array([0.5, -1.0, 2.0])
    write_solution(tmp_path / "s.hdf5", r, u)
    with h5py.File(tmp_path / "s.hdf5", "r") as fh:
        np.testing.assert_array_equal(fh["solution/r"][()], r)
        np.testing.assert_array_equal(fh["solution/u"][()], u)
    # into a problem file: the problem stays, the solution is replaced
    p = LocalProblem(np.eye(3), [-1.0, 0.0, 0.0], [0.3], 3)
    write_problem(tmp_path / "p.hdf5", p)
    write_solution(tmp_path / "p.hdf5", r, u)
    write_solution(tmp_path / "p.hdf5", [1.0, 0, 0], [0.0, 0, 0])
    with h5py.File(tmp_path / "p.hdf5", "r") as fh:
        np.testing.assert_array_equal(fh["solution/r"][()], [1, 0, 0])
    _assert_same(p, read_problem(tmp_path / "p.hdf5"))
    with pytest.raises(InvalidInputError, match="same length"):
        write_solution(tmp_path / "x.hdf5", [1.0, 2.0], [1.0])
    (tmp_path / "t.txt").write_text("hello")
    with pytest.raises(FileFormatError, match="t.txt"):
        write_solution(tmp_path / "t.txt", r, u)


# --- the natural-map error and the cone projection -----------------------------------------


def test_natural_map_error_sticking_contact():
    p = LocalProblem(np.eye(3), [-1.0, 0.0, 0.0], [0.3], 3)
    assert natural_map_error(p, [1.0, 0.0, 0.0]) == 0.0
    assert natural_map_error(p, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]) == 0.0
    assert natural_map_error(p, [0.0, 0.0, 0.0]) > 0.1
    assert natural_map_error(p, [1.0, 0.2, 0.0]) > 0.01


@pytest.mark.parametrize("dim", [2, 3])
def test_natural_map_error_sliding_contact(dim):
    # W = I, q = (-1, 2[, 0]), mu = 1/2: sliding with r = (1, -1/2), u = (0, 3/2), worked by hand
    q = np.array([-1.0, 2.0, 0.0][:dim])
    p = LocalProblem(sp.identity(dim, format="csr"), q, [0.5], dim)
    r = np.array([1.0, -0.5, 0.0][:dim])
    assert natural_map_error(p, r) == 0.0
    assert natural_map_error(p, r * 1.1) > 1e-3
    assert natural_map_error(p, np.array([1.0, 0.0, 0.0][:dim])) > 1e-3


def test_strided_views_are_measured_as_their_copies():
    # the compiled loops read arrays through their strides: a view must not need a copy
    W = np.eye(6)
    q = np.array([-1.0, 2.0, 0.0, 1.0, 0.0, 0.0])
    p = LocalProblem(W, q, [0.5, 0.3], 3)
    wide_r = np.zeros(12)
    wide_r[::2] = [1.0, -0.5, 0.0, 0.0, 0.0, 0.0]
    wide_u = np.zeros(12)
    wide_u[::2] = W @ wide_r[::2] + q
    assert (
        natural_map_error(p, wide_r[::2], wide_u[::2])
        == natural_map_error(p, wide_r[::2].copy(), wide_u[::2].copy())
        == 0.0
    )
    x = np.arange(12.0) - 5.0
    np.testing.assert_array_equal(
        projection_on_cones(x[::2], [0.5, 0.3], 3),
        projection_on_cones(x[::2].copy(), [0.5, 0.3], 3),
    )


def test_compiled_loops_refuse_rows_they_cannot_hold():
    # the per-contact buffers of contactqp.kernels hold 3 components: 4 must not overrun them
    from contactqp import kernels

    with pytest.raises(ValueError, match="2 or 3 components"):
        kernels.project_rows(np.zeros((2, 4)), np.zeros(2), np.zeros((2, 4)))
    with pytest.raises(ValueError, match="2 or 3 components"):
        kernels.natural_map_rows(np.zeros((2, 4)), np.zeros((2, 4)), np.zeros(2), np.zeros(2))


def test_natural_map_error_zero_problem():
    p = LocalProblem(np.zeros((2, 2)), [0.0, 0.0], [0.5], 2)
    assert natural_map_error(p, [0.0, 0.0]) == 0.0


def test_natural_map_error_per_contact_holds_each_contact_to_its_own_scale():
    # two decoupled sticking contacts pressed by 1 and by 1e-6: an error of 1e-9 on the small
    # one is 1e-9 of the problem but 1e-3 of that contact
    p = LocalProblem(np.eye(6), [-1.0, 0.0, 0.0, -1e-6, 0.0, 0.0], [0.3, 0.3], 3)
    exact = np.array([1.0, 0.0, 0.0, 1e-6, 0.0, 0.0])
    assert natural_map_error(p, exact, per_contact=True) == 0.0
    off = exact + [0.0, 0.0, 0.0, 1e-9, 0.0, 0.0]
    assert natural_map_error(p, off) == pytest.approx(1e-9, rel=1e-6)
    assert natural_map_error(p, off, per_contact=True) == pytest.approx(1e-3, rel=1e-3)
    # the same error on the large contact is the same relative size either way
    big = exact + [1e-9, 0.0, 0.0, 0.0, 0.0, 0.0]
    assert natural_map_error(p, big, per_contact=True) == pytest.approx(natural_map_error(p, big))


def test_projection_known_cases():
    mu = [0.5, 0.5, 0.5, 0.0, 0.0]
    x = np.concatenate(
        [
            [2.0, 0.3, -0.4],  # inside: kept
            [-2.0, 0.3, 0.4],  # polar cone (0.5*0.5 <= 2): 0
            [2.0, 0.6, 0.8],  # on the boundary: kept
            [-1.0, 0.0, 0.0],  # mu = 0, negative normal: 0
            [2.0, 3.0, 4.0],  # mu = 0: tangential part dropped
        ]
    )
    P = projection_on_cones(x, mu, 3).reshape(5, 3)
    np.testing.assert_array_equal(P[0], [2.0, 0.3, -0.4])
    np.testing.assert_array_equal(P[1], 0.0)
    np.testing.assert_allclose(P[2], [2.0, 0.6, 0.8], rtol=1e-15)
    np.testing.assert_array_equal(P[3], 0.0)
    np.testing.assert_array_equal(P[4], [2.0, 0.0, 0.0])
    # outside both cones: (x_N + mu t)/(1+mu^2) * (1, mu e_T) with t = 5, mu = 1
    np.testing.assert_allclose(projection_on_cones([0.0, 3.0, 4.0], [1.0], 3), [2.5, 1.5, 2.0])
    np.testing.assert_allclose(projection_on_cones([0.0, -4.0], [1.0], 2), [2.0, -2.0])


finite = st.floats(-1e3, 1e3, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(
    dim=st.sampled_from([2, 3]),
    data=st.data(),
)
def test_projection_moreau_decomposition(dim, data):
    nc = data.draw(st.integers(1, 4))
    mu = np.array(
        data.draw(st.lists(st.sampled_from([0.0, 0.1, 0.5, 1.0, 3.0]), min_size=nc, max_size=nc))
    )
    x = np.array(data.draw(st.lists(finite, min_size=dim * nc, max_size=dim * nc)))
    p = projection_on_cones(x, mu, dim)
    tol = 1e-9 * (1.0 + np.abs(x).max())
    np.testing.assert_allclose(projection_on_cones(p, mu, dim), p, rtol=0, atol=tol)  # idempotent
    P = p.reshape(nc, dim)
    Y = (p - x).reshape(nc, dim)  # -(x - P_K x) must lie in the dual cone K*
    assert np.all(np.linalg.norm(P[:, 1:], axis=1) <= mu * P[:, 0] + tol)  # P in K
    assert np.all(mu * np.linalg.norm(Y[:, 1:], axis=1) <= Y[:, 0] + tol)  # p - x in K*
    assert np.all(np.abs(np.sum(P * Y, axis=1)) <= tol * (1.0 + np.abs(x).max()))  # orthogonal


# --- validation and errors ------------------------------------------------------------------


@pytest.mark.parametrize(
    "args, match",
    [
        ((np.eye(3), [0, 0], [0.1], 3), "q must have length"),
        ((np.eye(2), [0, 0, 0], [0.1], 3), "W must be square of size"),
        ((np.eye(3), [0, 0, 0], [-0.1], 3), "mu must be >= 0"),
        ((np.eye(3), [0, np.nan, 0], [0.1], 3), "q contains NaN"),
        ((np.eye(4), [0, 0, 0, 0], [0.1], 4), "dim must be 2 or 3"),
        ((sp.csr_matrix(np.diag([1.0, np.inf, 1.0])), [0, 0, 0], [0.1], 3), "W contains NaN"),
    ],
)
def test_local_problem_validation(args, match):
    with pytest.raises(InvalidInputError, match=match) as info:
        LocalProblem(*args)
    assert "\n" not in str(info.value)


def _global_fields(**changes):
    """A valid global problem's fields as stored (float64, C-contiguous, H in CSR), with
    ``changes``: the compiled one-pass checks see them first."""
    fields = {
        "M": np.eye(3),
        "H": sp.csr_matrix(np.eye(3, 2)),
        "f": np.zeros(3),
        "w": np.zeros(2),
        "mu": np.array([0.1]),
        "dim": 2,
    }
    return {**fields, **changes}


@pytest.mark.parametrize(
    "changes, match",
    [
        ({"M": np.diag([1.0, np.nan, 1.0])}, "M contains NaN"),
        ({"H": sp.csr_matrix(np.array([[1.0, 0.0], [0.0, np.inf], [0.0, 0.0]]))}, "H contains"),
        ({"f": np.array([0.0, np.nan, 0.0])}, "f contains NaN"),
        ({"w": np.array([np.inf, 0.0])}, "w contains"),
        ({"mu": np.array([-0.1])}, "mu must be >= 0"),
        ({"w": np.zeros(3)}, "w must have length"),
        ({"M": np.eye(2)}, "H must have shape"),
    ],
)
def test_global_problem_validation(changes, match):
    with pytest.raises(InvalidInputError, match=match) as info:
        GlobalProblem(**_global_fields(**changes))
    assert "\n" not in str(info.value)
    fields = _global_fields()  # valid: kept as stored, not copied
    problem = GlobalProblem(**fields)
    assert all(getattr(problem, name) is fields[name] for name in ("M", "H", "f", "w", "mu"))


def test_condense_singular_m():
    M = sp.csr_matrix(np.array([[1.0, 1.0], [1.0, 1.0]]))
    with pytest.raises(NotPositiveDefiniteError, match="singular"):
        condense_global(M, np.eye(2), [0, 0], [0, 0], [0.1], 2)
    with pytest.raises(InvalidInputError, match="H must have shape"):
        condense_global(np.eye(3), np.eye(2), [0, 0, 0], [0, 0], [0.1], 2)
    with pytest.raises(InvalidInputError, match="M must be square"):
        GlobalProblem(np.ones((3, 2)), np.eye(3, 2), [0, 0, 0], [0, 0], [0.1], 2)


def test_condense_badly_scaled_but_regular_m():
    # masses 1 and inertias 1e-20: regular, and the Jacobi-scaled test must accept it
    M = sp.diags([1.0, 1e-20])
    p = condense_global(M, np.eye(2), [1.0, 1e-20], [0.0, 0.0], [0.1], 2)
    np.testing.assert_allclose(dense(p.W), np.diag([1.0, 1e20]))
    np.testing.assert_allclose(p.q, [1.0, 1.0])


def _expect_format_error(path, match=None):
    with pytest.raises(FileFormatError) as info:
        read_problem(path)
    msg = str(info.value)
    assert Path(path).name in msg and "\n" not in msg
    if match:
        assert match in msg
    return msg


def test_missing_file(tmp_path):
    _expect_format_error(tmp_path / "nope.hdf5", "no such file")


def test_garbage_text(tmp_path):
    path = tmp_path / "garbage.dat"
    path.write_text("hello world\nthis is not a problem\n")
    _expect_format_error(path)
    path.write_bytes(bytes(range(256)) * 4)
    _expect_format_error(path)


def test_truncated_dat(tmp_path):
    text = (DATA / "FrictionContact3D_1c.dat").read_text()
    path = tmp_path / "short.dat"
    path.write_text(text[: text.rindex("0.1")])
    _expect_format_error(path, "end of file")
    path.write_text(text + "\n1 2 3\n")
    _expect_format_error(path, "extra content")


def test_truncated_hdf5(tmp_path):
    raw = (DATA / "CubeH8.hdf5").read_bytes()
    for size in (len(raw) // 2, 4096, 100):
        path = tmp_path / f"cut{size}.hdf5"
        path.write_bytes(raw[:size])
        _expect_format_error(path)


def test_hdf5_without_fclib_groups(tmp_path):
    path = tmp_path / "other.hdf5"
    with h5py.File(path, "w") as fh:
        fh.create_dataset("something", data=np.arange(3))
    _expect_format_error(path, "has neither /fclib_local nor /fclib_global")


def test_hdf5_with_wrong_sizes(tmp_path):
    path = tmp_path / "bad.hdf5"
    write_problem(path, LocalProblem(np.eye(3), [-1.0, 0, 0], [0.3], 3))
    with h5py.File(path, "a") as fh:
        del fh["fclib_local/vectors/q"]
        fh["fclib_local/vectors/q"] = np.zeros(4)
    _expect_format_error(path, "q must have length")
    with h5py.File(path, "a") as fh:
        del fh["fclib_local/W/i"]
        fh["fclib_local/W/i"] = np.array([0, 1, 7], dtype=np.int32)
    _expect_format_error(path, "fclib_local/W/i")


def test_format_found_from_content_not_suffix(tmp_path):
    shutil.copy(DATA / "CubeH8.hdf5", tmp_path / "cube.dat")
    shutil.copy(DATA / "FC3D_Example1_SBM.dat", tmp_path / "ex.hdf5")
    assert read_problem(tmp_path / "cube.dat").n_contacts == 1
    assert read_problem(tmp_path / "ex.hdf5").n_contacts == 3


def test_missing_h5py(monkeypatch):
    monkeypatch.setitem(__import__("sys").modules, "h5py", None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'contactqp\[hdf5\]'"):
        read_problem(DATA / "CubeH8.hdf5")


# --- sparse storages that the data files do not use ---------------------------------------

_CS_BANNER = "CSparse Version 3.1.9, May 4, 2016.  Copyright (c) Timothy A. Davis, 2006-2016"


def test_csparse_triplet_and_csr_dumps():
    triplet = "\n".join(
        [
            "2",
            "1",
            "2",
            "2",
            "2",
            "1",
            _CS_BANNER,
            "triplet: 2-by-2, nzmax: 3 nnz: 3",
            "    0 0 : 4",
            "    1 0 : -1",
            "    1 1 : 3",
            "-1 0.5",
            "0.25",
            "0",
        ]
    )
    p = parse_dat(triplet)
    np.testing.assert_array_equal(dense(p.W), [[4, 0], [-1, 3]])
    np.testing.assert_array_equal(p.q, [-1, 0.5])
    csr = "\n".join(
        [
            "2",
            "1",
            "2",
            "2",
            "2",
            "3",
            _CS_BANNER,
            "2-by-2, nzmax: 3 nnz: 3, 1-norm: 5",
            "    col 0 : locations 0 to 1",
            "      0 : 4",
            "      1 : 2",
            "    col 1 : locations 2 to 2",
            "      1 : 3",
            "-1 0.5",
            "0.25",
        ]
    )
    np.testing.assert_array_equal(dense(parse_dat(csr).W), [[4, 2], [0, 3]])
    csc = csr.replace("\n3\n", "\n2\n", 1)
    np.testing.assert_array_equal(dense(parse_dat(csc).W), [[4, 0], [2, 3]])


def test_dense_is_column_major_and_global_dense():
    # local, dense storage of a non-symmetric W: values column by column
    text = "2 1\n0\n2\n2\n2 2\n1 2\n3 4\n0 0\n0.3\n"
    np.testing.assert_array_equal(parse_dat(text).W, [[1, 3], [2, 4]])
    g = parse_dat("2 1\n0 2 2\n2 2\n2 0 0 2\n0 2 2\n2 2\n1 0 0 1\n2 4\n0 -1\n0.5\n1\n")
    assert isinstance(g, GlobalProblem)
    p = g.condense()
    np.testing.assert_allclose(p.W, 0.5 * np.eye(2))
    np.testing.assert_allclose(p.q, [1.0, 1.0])


def test_writing_a_cohesive_problem_is_refused_not_lossy(tmp_path):
    problem = LocalProblem(np.eye(2), np.array([-1.0, 0.5]), [0.3], 2, cohesion=[1.0])
    with pytest.raises(UnsupportedProblemError, match="no field for cohesion"):
        write_problem(tmp_path / "c.hdf5", problem)
    assert not (tmp_path / "c.hdf5").exists()


def test_a_broken_file_named_hdf5_is_called_neither_hdf5_nor_text(tmp_path):
    path = tmp_path / "broken.hdf5"
    path.write_text("garbage\n")
    with pytest.raises(FileFormatError, match="neither an HDF5 file .* nor a Siconos"):
        read_problem(path)

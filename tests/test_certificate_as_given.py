"""Certificates judge the problem the user gave, not the one a solver changed it into.

Each test builds the problem as written independently (dense numpy, no project code) and
recomputes the error there. Symmetrising, rescaling, solving only some rows and reading few
digits are the changes audited; ``--solution-dir`` must never write over an input.
"""

import hashlib
import json
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

import contactqp as cq
from contactqp import solve
from contactqp.core.local_problem import LocalProblem, natural_map_error
from contactqp.io.fclib import read_global_problem, read_problem
from contactqp.io.siconos import parse_dat
from contactqp.methods.coulomb import solve_coulomb

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "fclib"
LMGC = DATA / "LMGC_GlobalFrictionContactProblem00046.hdf5"
TOL = 1e-8


def dense(A):
    return A.toarray() if sp.issparse(A) else np.asarray(A)


def written_local(g):
    """The local problem of the global equations as written, by dense numpy solves."""
    M, H = dense(g.M), dense(g.H)
    W = H.T @ np.linalg.solve(M, H)
    q = H.T @ np.linalg.solve(M, g.f) + g.w
    return LocalProblem(W, q, g.mu, g.dim), M, H


def run(*args):
    return subprocess.run(
        [sys.executable, "-m", "contactqp.cli", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )


def digest(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


# --- global problems: M as given, certified on M v = H r + f, u = H^T v + w ----------------


def test_lmgc_global_file_is_solved_as_written():
    g = read_global_problem(LMGC)
    written, M, _ = written_local(g)
    # the file's M is unsymmetric (22 % of the Jacobi-scaled entries), so is W = H^T M^-1 H
    assert np.abs(written.W - written.W.T).max() > 0.1 * np.abs(written.W).max()
    condensed = read_problem(LMGC)
    np.testing.assert_allclose(
        dense(condensed.W), written.W, rtol=0, atol=1e-9 * np.abs(written.W).max()
    )
    solution = solve(condensed, tol=TOL)
    assert solution.success, solution.message
    # was 3.9e-3 when W was symmetrised (the solver then reported 2e-14)
    assert natural_map_error(written, solution.forces) <= TOL
    # the unscaled cond(M) of 1e7 is the 2.6e8 constrained diagonal only
    assert np.linalg.cond(M) > 1e6


def test_global_solution_is_certified_on_the_written_equations():
    g = read_global_problem(LMGC)
    written, M, H = written_local(g)
    solution = solve(g, tol=TOL)
    assert solution.success, solution.message
    # v and u are those of the written equations, recomputed here
    v = np.linalg.solve(M, H @ solution.forces + g.f)
    np.testing.assert_allclose(solution.v, v, rtol=0, atol=1e-10 * np.abs(v).max())
    np.testing.assert_allclose(solution.displacements, H.T @ solution.v + g.w, rtol=0, atol=1e-15)
    assert natural_map_error(written, solution.forces, H.T @ v + g.w) <= TOL
    error = natural_map_error(written, solution.forces, solution.displacements)
    assert solution.certificate.natural_map == pytest.approx(error, rel=1e-6, abs=1e-15)
    assert solution.certificate.equilibrium <= 1e-13
    # Jacobi scaling removes the 1e7: the attainable error is at rounding, nothing to say
    limits = solution.certificate.limits
    assert limits.condition < 100 and limits.rounding < 1e-13
    assert "limits" not in solution.message and "global equations" in solution.message


def test_ill_conditioned_m_says_what_accuracy_it_allows():
    from contactqp.core.local_problem import GlobalProblem

    # cond(M) = 2e13 after Jacobi scaling: u = H^T M^-1 (H r + f) + w loses 13 digits
    delta = 1e-13
    M = np.array([[1.0, 1.0 - delta], [1.0 - delta, 1.0]])
    g = GlobalProblem(M, np.eye(2), [1.0, -1.0], [-1e13, 0.0], [0.3], 2)
    solution = solve(g, tol=TOL)
    limits = solution.certificate.limits
    assert limits.condition == pytest.approx(np.linalg.cond(M, 1), rel=1e-3)
    assert limits.rounding > TOL
    assert f"{limits.rounding:.1e}" in solution.message and "conditioning of M" in solution.message
    # the error is measured all the same, on the problem as written
    written, _, _ = written_local(g)
    error = natural_map_error(written, solution.forces, solution.displacements)
    assert solution.certificate.natural_map == pytest.approx(error, rel=1e-6)


def test_cli_json_certifies_global_files_and_reports_limits(tmp_path):
    proc = run(
        "fclib",
        str(LMGC),
        str(DATA / "GFC3D_TwoRods1.dat"),
        str(DATA / "fc2d_granularflowonwall_02020_00213.dat"),
        "--json",
    )
    assert proc.returncode == 0, proc.stderr
    lmgc, rods, granular = (json.loads(line) for line in proc.stdout.splitlines())
    assert lmgc["converged"] and lmgc["error"] <= TOL and lmgc["equilibrium"] <= 1e-13
    assert lmgc["attainable"] < 1e-13 and lmgc["data_limit"] == 0.0 and lmgc["limits"] == ""
    # a global .dat whose M and H carry 7 significant digits (%e)
    assert rods["digits"] == {"M": 7, "H": 7} and rods["equilibrium"] <= 1e-13
    assert rods["data_limit"] > TOL and "7" in rods["limits"]
    # a local .dat whose W is a cs_print dump (6 digits): solved on the problem as written
    assert granular["digits"] == {"W": 6} and granular["equilibrium"] is None
    assert granular["converged"] and granular["error"] <= TOL
    assert "problem as written" in granular["limits"]


# --- digits: the problem as written is that problem ---------------------------------------


def test_few_digits_define_the_problem_and_limit_its_meaning():
    text = "3\n1\n0\n3\n3\n3 3\n1.5 0.1 0.2 0.1 2.2501 0.3 0.2 0.3 1.75\n-1 0.5 0\n0.3\n"
    exact = parse_dat(text)
    # W's longest value has 5 significant digits; q's short values are taken as exact
    assert exact.digits == {"W": 5}
    solution = solve(exact, tol=TOL)
    # the error is on the written values, recomputed from them here
    W = np.array([[1.5, 0.1, 0.2], [0.1, 2.2501, 0.3], [0.2, 0.3, 1.75]]).T
    assert natural_map_error(LocalProblem(W, [-1, 0.5, 0], [0.3], 3), solution.forces) <= TOL
    assert solution.success and solution.certificate.limits.data > TOL
    assert "significant digits (W 5)" in solution.message
    # full-precision values: nothing to say
    full = parse_dat(text.replace("2.2501", "2.2501000000000002"))
    assert full.digits == {} and solve(full, tol=TOL).certificate.limits.data == 0.0


# --- other changes of the problem: the reported error is the given problem's -----------------


def _scaled_problem(seed=0):
    """Contacts of very different sizes: micrometre reactions beside a wide gap."""
    rng = np.random.default_rng(seed)
    nc, d = 6, 3
    A = rng.standard_normal((nc * d, nc * d))
    W = A @ A.T / (nc * d) + np.eye(nc * d)
    W += 1e-3 * np.triu(W, 1)  # slightly unsymmetric
    q = rng.standard_normal(nc * d) * 1e-6
    q[0] = 1e3  # one contact far from its obstacle
    W[-d:, :] = W[:, -d:] = 0.0  # and one whose rows are zero (open: q_N > 0)
    q[-d] = 1e-6
    return LocalProblem(W, q, np.full(nc, 0.4), d)


@pytest.mark.parametrize("route", ["newton", "tresca"])
def test_rescaling_solvers_report_the_given_problems_error(route):
    # the Newton solver scales each contact (rho = 1 / diag W_ii), the fixed point rescales
    # its sub-problems to the reactions' size: the error reported is still the given one's
    problem = _scaled_problem()
    if route == "newton":
        solution = solve_coulomb(problem, tol=TOL)
    else:
        from contactqp.methods.tresca import solve_tresca_fixed_point

        solution = solve_tresca_fixed_point(problem, tol=TOL)
    W = dense(problem.W)
    u = W @ solution.forces + problem.q
    assert solution.certificate.natural_map == pytest.approx(
        natural_map_error(LocalProblem(W, problem.q, problem.mu, 3), solution.forces, u),
        rel=1e-9,
        abs=1e-18,
    )
    assert solution.success == (solution.certificate.natural_map <= TOL)
    # the fixed point stalls near 6e-7 on this problem (the zero-row contact; with a unit
    # block there it converges), and says so; Newton converges
    assert solution.success or route == "tresca"


def test_frictionless_route_is_judged_on_every_row_of_the_unsymmetric_w():
    # without friction only the normal rows are solved (a QP on the symmetric part of W_NN);
    # the certificate still judges every row, and the unsymmetric W as given
    base = _scaled_problem(1)
    problem = LocalProblem(base.W, base.q, np.zeros(6), 3)
    solution = solve(problem, tol=TOL)
    assert solution.success, solution.message
    assert np.all(solution.forces.reshape(6, 3)[:, 1:] == 0)
    assert (
        natural_map_error(LocalProblem(dense(problem.W), problem.q, problem.mu, 3), solution.forces)
        <= TOL
    )


def test_symmetrised_model_is_certified_on_the_flexibility_given():
    rng = np.random.default_rng(0)
    n = 20
    A = rng.standard_normal((n, n))
    R = A @ A.T / n + np.eye(n)
    skew = rng.standard_normal((n, n))
    skew = (skew - skew.T) / np.abs(skew - skew.T).max()
    given = R + 4e-7 * np.abs(R).max() * skew  # within the symmetrising tolerance of 1e-6
    loads = rng.standard_normal(n)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cq.errors.SymmetrizedWarning)
        result = cq.solve_gaps(given, loads, np.full(n, 0.1))
    U, net = result.displacements, loads + result.nodal_forces
    # the solvers use the symmetric part; on the matrix given the equilibrium misses by ~4e-7,
    # and the certificate says so (it reported 1.7e-16, the symmetric part's residual)
    on_given = np.abs(U - given @ net).max()
    length = max(
        np.abs(U).max(), 0.1, np.diag(R).max() * max(np.abs(loads).max(), result.forces.max())
    )
    assert on_given / length > 1e-7  # the certificate's tolerance
    assert result.certificate.equilibrium >= 0.99 * on_given / length
    assert not result.success
    asymmetry = np.abs(given - given.T).max() / np.abs(given).max()
    assert f"symmetric part (relative asymmetry {asymmetry:.1e}" in result.message


# --- --solution-dir never writes over an input or another input's solution ----------------


def _inputs(tmp_path):
    folder = tmp_path / "dir"
    folder.mkdir()
    for source, name in (("GFC3D_Example1.dat", "x.dat"), ("CubeH8.hdf5", "x.hdf5")):
        shutil.copyfile(DATA / source, folder / name)
    return folder


def test_solution_dir_keeps_inputs_with_the_same_stem(tmp_path):
    folder = _inputs(tmp_path)
    before = {p.name: digest(p) for p in folder.iterdir()}
    proc = run(
        "fclib",
        str(folder / "x.dat"),
        str(folder / "x.hdf5"),
        "--json",
        "--solution-dir",
        str(folder),
    )
    assert proc.returncode == 0, proc.stderr
    # x.dat's solution used to be written into the input x.hdf5
    assert {name: digest(folder / name) for name in before} == before
    assert sorted(p.name for p in folder.iterdir()) == [
        "x.dat",
        "x.dat.solution.hdf5",
        "x.hdf5",
        "x.hdf5.solution.hdf5",
    ]
    g = read_global_problem(folder / "x.dat")
    with h5py.File(folder / "x.dat.solution.hdf5") as fh:
        r, u, v = (fh[f"solution/{k}"][()] for k in "ruv")
    written, M, H = written_local(g)
    np.testing.assert_allclose(M @ v, H @ r + g.f, atol=1e-12 * np.abs(M @ v).max())
    assert natural_map_error(written, r, u) <= TOL
    # running again replaces the command's own solution files
    again = run("fclib", str(folder / "x.dat"), "--solution-dir", str(folder))
    assert again.returncode == 0, again.stderr


def _assert_refused(proc, *names):
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("contactqp: error:"), proc.stderr
    assert all(name in lines[0] for name in names) and "Traceback" not in proc.stderr


def test_solution_dir_refuses_to_overwrite_inputs_or_foreign_files(tmp_path):
    folder = _inputs(tmp_path)
    other = tmp_path / "other"
    other.mkdir()
    shutil.copyfile(folder / "x.dat", other / "x.dat")
    out = tmp_path / "out"
    # two inputs, one solution file
    _assert_refused(
        run("fclib", str(folder / "x.dat"), str(other / "x.dat"), "--solution-dir", str(out)),
        "same solution file",
    )
    assert not out.exists()
    # the target is one of the inputs
    shutil.copyfile(folder / "x.hdf5", folder / "x.dat.solution.hdf5")
    before = digest(folder / "x.dat.solution.hdf5")
    _assert_refused(
        run(
            "fclib",
            str(folder / "x.dat"),
            str(folder / "x.dat.solution.hdf5"),
            "--solution-dir",
            str(folder),
        ),
        "overwrite the input",
    )
    # a file the command did not write is never replaced, inputs or not
    _assert_refused(
        run("fclib", str(folder / "x.dat"), "--solution-dir", str(folder)),
        "not a solution file written by contactqp",
    )
    assert digest(folder / "x.dat.solution.hdf5") == before
    # nor, in a later run, another input's solution
    assert run("fclib", str(folder / "x.dat"), "--solution-dir", str(out)).returncode == 0
    written = digest(out / "x.dat.solution.hdf5")
    _assert_refused(
        run("fclib", str(other / "x.dat"), "--solution-dir", str(out)),
        "the solution of another input",
        str(folder / "x.dat"),
    )
    assert digest(out / "x.dat.solution.hdf5") == written

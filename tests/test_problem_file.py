"""Problem files (TOML + matrix files): loading, validation messages and written results.

Truths used here are independent of the code under test: closed-form answers of one- and
two-freedom problems worked out by hand (each derivation is next to its test), and the same
problem assembled directly in Python. Tolerances: the active-set solver ends with an exact
factorisation of the active block, so displacements agree with the hand answers to ~1e-15
relative; we allow 1e-10 relative (and 1e-9 of the load scale for forces expected to be zero).
The qp route goes through an interior-point backend with tolerances ~1e-12, so it is compared at
1e-7 relative.
"""

from __future__ import annotations

import csv
import json
import math
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse
from hypothesis import given, settings
from hypothesis import strategies as st

from contactqp import (
    ContactProblem,
    FileFormatError,
    GapObstacle,
    InvalidInputError,
    NodePairs,
    NotPositiveDefiniteError,
    PlaneObstacle,
    ReducedModel,
    solve,
)
from contactqp.errors import SymmetrizedWarning
from contactqp.io.problem_file import (
    RESULT_FILES,
    ProblemSpec,
    load_problem_file,
    read_array,
    write_results,
)

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "problems" / "two_springs.toml"
RTOL = 1e-10


# ------------------------------------------------------------------------------------------
# Helpers


def write_matrix(directory: Path, stem: str, matrix, fmt: str) -> str:
    """Write ``matrix`` in one of the readable formats; return the file name."""
    matrix = np.asarray(matrix, dtype=float)
    if fmt == "csv":
        name = f"{stem}.csv"
        np.savetxt(directory / name, matrix, delimiter=",", fmt="%.17g")
    elif fmt == "csv-spaces":
        name = f"{stem}.txt"
        np.savetxt(directory / name, matrix, delimiter=" ", fmt="%.17g",
                   header="whitespace separated")
    elif fmt == "npz":
        name = f"{stem}.npz"
        np.savez(directory / name, matrix)
    elif fmt == "npz-sparse":
        name = f"{stem}.npz"
        scipy.sparse.save_npz(directory / name, scipy.sparse.csr_matrix(matrix))
    elif fmt == "mtx":
        name = f"{stem}.mtx"
        scipy.io.mmwrite(str(directory / name), matrix, precision=17)
    elif fmt == "mtx-sparse":
        name = f"{stem}.mtx"
        scipy.io.mmwrite(str(directory / name), scipy.sparse.coo_matrix(matrix), precision=17,
                         symmetry="symmetric")
    else:  # pragma: no cover
        raise AssertionError(fmt)
    return name


def write_toml(directory: Path, text: str, name: str = "problem.toml") -> Path:
    path = directory / name
    path.write_text(text, encoding="utf-8")
    return path


def toml_list(values) -> str:
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


MATRIX_FORMATS = ["csv", "csv-spaces", "npz", "npz-sparse", "mtx", "mtx-sparse"]


# ------------------------------------------------------------------------------------------
# Answers against hand derivations


@pytest.mark.parametrize("fmt", MATRIX_FORMATS)
@pytest.mark.parametrize("gap", [1e-3, 5e-3], ids=["closed", "open"])
def test_single_node_against_closed_form(tmp_path, fmt, gap):
    # One spring of flexibility r under a load P, a stop at distance g:
    # U = min(r P, g), contact force F = max(P - g / r, 0).
    r, P = 2e-6, 1000.0
    name = write_matrix(tmp_path, "R", [[r]], fmt)
    path = write_toml(tmp_path, f"""
[model]
flexibility = "{name}"
[loads]
values = [{P}]
[[obstacle]]
type = "gaps"
nodes = [0]
gaps = [{gap}]
""")
    spec = load_problem_file(path)
    result = spec.solve()
    assert result.success
    U_true, F_true = min(r * P, gap), max(P - gap / r, 0.0)
    np.testing.assert_allclose(result.x, [U_true], rtol=RTOL)
    np.testing.assert_allclose(result.forces, [F_true], rtol=RTOL, atol=1e-9 * P)
    assert bool(result.closed[0]) == (r * P > gap)

    # The same problem built in Python gives the same answer.
    direct = solve(ContactProblem(ReducedModel(flexibility=[[r]]), [P],
                                  [GapObstacle([0], [gap])]))
    np.testing.assert_allclose(result.x, direct.x, rtol=1e-14)
    np.testing.assert_allclose(result.forces, direct.forces, rtol=1e-14, atol=1e-12)


@pytest.mark.parametrize("fmt", MATRIX_FORMATS)
def test_two_node_coupled_problem_by_hand(tmp_path, fmt):
    # R = [[2, 1], [1, 2]] um/N, P = [1000, -200] N, stops at 1 mm on both nodes (+x).
    # Free: u = R P = [1.8, 0.6] mm -> node 0 crosses its stop, node 1 does not.
    # Guess node 0 closed, node 1 open: 2e-6 (1000 - F0) - 1e-6 * 200 = 1e-3 -> F0 = 400 N;
    # u1 = 1e-6 (1000 - 400) + 2e-6 (-200) = 0.2 mm < 1 mm (open), F0 > 0: the guess holds.
    R = np.array([[2e-6, 1e-6], [1e-6, 2e-6]])
    name = write_matrix(tmp_path, "R", R, fmt)
    path = write_toml(tmp_path, f"""
name = "coupled pair"
[model]
flexibility = "{name}"
[loads]
entries = [{{ freedom = 0, value = 1000.0 }}, {{ node = 1, component = 0, value = -200.0 }}]
[[obstacle]]
type = "gaps"
nodes = [0, 1]
gaps = [1e-3, 1e-3]
directions = [[1.0], [1.0]]
""")
    spec = load_problem_file(path)
    assert spec.name == "coupled pair"
    result = spec.solve()
    assert result.success
    np.testing.assert_allclose(result.x, [1e-3, 2e-4], rtol=RTOL)
    np.testing.assert_allclose(result.forces, [400.0, 0.0], rtol=RTOL, atol=1e-9 * 1000)
    assert result.status_labels == ["closed", "open"]
    np.testing.assert_allclose(result.gaps, [0.0, 8e-4], atol=1e-15)

    direct = solve(ContactProblem(ReducedModel(flexibility=R), [1000.0, -200.0],
                                  [GapObstacle([0, 1], [1e-3, 1e-3])]))
    np.testing.assert_allclose(result.x, direct.x, rtol=1e-14)


def test_stiffness_from_npz_key_and_qp_solver(tmp_path):
    # The same coupled problem given by K = R^-1 in an archive with two arrays, solved by the
    # qp route: the same hand answer (u = [1, 0.2] mm, F = [400, 0] N).
    R = np.array([[2e-6, 1e-6], [1e-6, 2e-6]])
    np.savez(tmp_path / "model.npz", K=np.linalg.inv(R), R=R)
    np.savetxt(tmp_path / "P.csv", [[1000.0], [-200.0]])
    path = write_toml(tmp_path, """
[model]
stiffness = { file = "model.npz", key = "K" }
[loads]
values = "P.csv"
[[obstacle]]
type = "gaps"
nodes = [0, 1]
gaps = [1e-3, 1e-3]
[solver]
name = "qp"
backend = "clarabel"
certificate_tol = 1e-6
[solver.backend_options]
max_iter = 300
""")
    spec = load_problem_file(path)
    assert spec.solver == "qp"
    assert spec.options == {"backend": "clarabel", "max_iter": 300}
    assert spec.problem.certificate_tol == 1e-6
    assert spec.problem.model.given == "stiffness"
    result = spec.solve()
    assert result.success, result.message
    np.testing.assert_allclose(result.x, [1e-3, 2e-4], rtol=1e-7)
    np.testing.assert_allclose(result.forces, [400.0, 0.0], rtol=1e-7, atol=1e-6)


def test_node_pairs_by_hand(tmp_path):
    # Two separate springs ra = 1, rb = 3 um/N; node 0 pushed by P = 1000 N towards node 1,
    # initial gap g = 0.5 mm. Closed pair: ra (P - F) - rb F = g -> F = (ra P - g)/(ra + rb)
    # = 125 N, u0 = ra (P - F) = 0.875 mm, u1 = rb F = 0.375 mm.
    np.savetxt(tmp_path / "R.csv", np.diag([1e-6, 3e-6]), delimiter=",")
    path = write_toml(tmp_path, """
[model]
flexibility = "R.csv"
[loads]
entries = [{ node = 0, value = 1000.0 }]
[[obstacle]]
type = "pairs"
pairs = [[0, 1]]
gaps = [0.5e-3]
direction = [1.0]
""")
    result = load_problem_file(path).solve()
    assert result.success
    np.testing.assert_allclose(result.forces, [125.0], rtol=RTOL)
    np.testing.assert_allclose(result.x, [0.875e-3, 0.375e-3], rtol=RTOL)
    direct = solve(ContactProblem(ReducedModel(flexibility=np.diag([1e-6, 3e-6])),
                                  [1000.0, 0.0], [NodePairs([[0, 1]], [0.5e-3])]))
    np.testing.assert_allclose(result.x, direct.x, rtol=1e-14)


def test_plane_obstacle_by_hand(tmp_path):
    # One 2-freedom node at the origin, R = [[2, 0.5], [0.5, 1]] um/N, load (0, -300) N, floor
    # at y = -0.1 mm (normal (0, -1) from the body to the floor): gap 0.1 mm.
    # Free: u = R P = (-0.15, -0.3) mm, crossing. Closed: u_y = -0.1 mm = R_yy (-300 + F)
    # -> F = 200 N; u_x = R_xy (-300 + 200) = -0.05 mm.
    R = np.array([[2e-6, 0.5e-6], [0.5e-6, 1e-6]])
    scipy.io.mmwrite(str(tmp_path / "R.mtx"), R, precision=17)
    path = write_toml(tmp_path, """
[model]
flexibility = "R.mtx"
dofs_per_node = 2
coordinates = [[0.0, 0.0]]
[loads]
values = [0.0, -300.0]
[[obstacle]]
type = "plane"
point = [0.0, -1e-4]
normal = [0.0, -1.0]
""")
    result = load_problem_file(path).solve()
    assert result.success
    np.testing.assert_allclose(result.forces, [200.0], rtol=RTOL)
    np.testing.assert_allclose(result.x, [-0.05e-3, -0.1e-3], rtol=RTOL)
    direct = solve(ContactProblem(ReducedModel(flexibility=R, dofs_per_node=2,
                                               coordinates=[[0.0, 0.0]]),
                                  [0.0, -300.0], [PlaneObstacle([0.0, -1e-4], [0.0, -1.0])]))
    np.testing.assert_allclose(result.x, direct.x, rtol=1e-14)


def test_example_two_springs_matches_its_derivation():
    # Derivation in the file's comment: u = [0.3, 1.0] mm, stop forces [100, 300] N.
    spec = load_problem_file(EXAMPLE)
    assert spec.name == "two springs against two stops"
    result = spec.solve()
    assert result.success
    np.testing.assert_allclose(result.x, [3e-4, 1e-3], rtol=RTOL)
    np.testing.assert_allclose(result.forces, [100.0, 300.0], rtol=RTOL)
    np.testing.assert_allclose(result.gaps, [0.0, 0.0], atol=1e-15)
    assert result.status_labels == ["closed", "closed"]
    # Springs: k1 = 2e6 N/m, k2 = 1e6 N/m, so R = [[1/k1, 1/k1], [1/k1, 1/k1 + 1/k2]].
    np.testing.assert_allclose(spec.problem.model.flexibility,
                               [[5e-7, 5e-7], [5e-7, 1.5e-6]], rtol=1e-15)


@settings(max_examples=30, deadline=None)
@given(r=st.floats(1e-9, 1e-3), P=st.floats(-1e4, 1e4), gap=st.floats(1e-6, 1e-2),
       interference=st.booleans())
def test_single_node_property(r, P, gap, interference):
    # Inline matrix, any r > 0, load of either sign, gap of either sign (negative: interference):
    # U = min(r P, g), F = max(P - g / r, 0). A gap of exactly zero has its own test
    # below.
    gap = -gap if interference else gap
    with tempfile.TemporaryDirectory() as directory:
        path = write_toml(Path(directory), f"""
[model]
flexibility = [[{r!r}]]
[loads]
values = [{P!r}]
[[obstacle]]
type = "gaps"
nodes = [0]
gaps = [{gap!r}]
""")
        result = load_problem_file(path).solve()
    assert result.success
    scale_u = max(abs(r * P), abs(gap))
    scale_f = max(abs(P), abs(gap) / r)
    np.testing.assert_allclose(result.x, [min(r * P, gap)], rtol=1e-9, atol=1e-12 * scale_u)
    np.testing.assert_allclose(result.forces, [max(P - gap / r, 0.0)], rtol=1e-9,
                               atol=1e-9 * scale_f)


def test_zero_gap_closed_contact_is_certified(tmp_path):
    # U = min(r P, 0) = 0, F = P: a perfectly ordinary answer that the solver finds.
    path = write_toml(tmp_path, """
[model]
flexibility = [[5.8196301223351394e-05]]
[loads]
values = [1.0]
[[obstacle]]
type = "gaps"
nodes = [0]
gaps = [0.0]
""")
    result = load_problem_file(path).solve()
    assert result.success, result.message
    np.testing.assert_allclose(result.forces, [1.0], rtol=RTOL)
    assert abs(result.x[0]) < 1e-15
    assert result.success, result.message


def test_read_array_formats_agree(tmp_path):
    matrix = np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 2.0]]) * 1e-6
    for fmt in MATRIX_FORMATS:
        sub = tmp_path / fmt
        sub.mkdir()
        name = write_matrix(sub, "M", matrix, fmt)
        np.testing.assert_array_equal(read_array(sub / name), matrix, err_msg=fmt)


# ------------------------------------------------------------------------------------------
# Validation: every error is one line naming the key

BASE_MODEL = """
[model]
flexibility = "R.csv"
"""
BASE_LOADS = """
[loads]
values = [1.0, 2.0]
"""
BASE_OBSTACLE = """
[[obstacle]]
type = "gaps"
nodes = [0, 1]
gaps = [0.1, 0.2]
"""
GOOD = BASE_MODEL + BASE_LOADS + BASE_OBSTACLE
SPD = "2,1\n1,2\n"

CASES = {
    "missing matrix file": (
        GOOD, {}, FileFormatError,
        ["problem.toml: [model].flexibility: file 'R.csv' not found"]),
    "malformed TOML": (
        "[model\nflexibility = 'R.csv'\n", {"R.csv": SPD}, FileFormatError,
        ["problem.toml: malformed TOML"]),
    "unknown top-level key": (
        GOOD + "\n[solvr]\nname = 'qp'\n", {"R.csv": SPD}, InvalidInputError,
        ["top level: unknown key 'solvr'", "did you mean 'solver'"]),
    "unknown model key": (
        GOOD.replace("flexibility =", "flexibilty ="), {"R.csv": SPD}, InvalidInputError,
        ["[model]: unknown key 'flexibilty'"]),
    "unknown obstacle key": (
        GOOD.replace("gaps = [0.1, 0.2]", "gap = [0.1, 0.2]"), {"R.csv": SPD},
        InvalidInputError, ["[[obstacle]] #1: unknown key 'gap'"]),
    "unknown solver option": (
        GOOD + "\n[solver]\nmax_iters = 10\n", {"R.csv": SPD}, InvalidInputError,
        ["[solver].max_iters: not an option of solver 'active-set'", "did you mean 'max_iter'"]),
    "unknown loads entry key": (
        BASE_MODEL + "[loads]\nentries = [{ freedom = 0, valeu = 1.0 }]\n" + BASE_OBSTACLE,
        {"R.csv": SPD}, InvalidInputError, ["[loads].entries #1: unknown key 'valeu'"]),
    "wrong loads length": (
        BASE_MODEL + "[loads]\nvalues = [1.0, 2.0, 3.0, 4.0]\n" + BASE_OBSTACLE,
        {"R.csv": SPD}, InvalidInputError,
        ["[loads].values has 4 entries, the model has 2 freedoms"]),
    "unknown obstacle type": (
        GOOD + "\n[[obstacle]]\ntype = 'sphere'\n", {"R.csv": SPD}, InvalidInputError,
        ["[[obstacle]] #2: unknown type 'sphere' (expected gaps, plane or pairs)"]),
    "profile in a file": (
        GOOD.replace("type = \"gaps\"", "type = \"profile\""), {"R.csv": SPD},
        InvalidInputError, ["[[obstacle]] #1: type 'profile' cannot be given in a file"]),
    "NaN in matrix file": (
        GOOD, {"R.csv": "2,1\n1,nan\n"}, InvalidInputError,
        ["[model].flexibility ('R.csv'): contains NaN or inf (first at index [1, 1]"]),
    "not positive definite": (
        GOOD, {"R.csv": "1,2\n2,1\n"}, NotPositiveDefiniteError,
        ["[model].flexibility ('R.csv'):", "not positive definite"]),
    "not a table of numbers": (
        GOOD, {"R.csv": "a,b\n1,2\n"}, FileFormatError,
        ["[model].flexibility ('R.csv'): not a table of numbers"]),
    "not square": (
        GOOD, {"R.csv": "1,2,3\n4,5,6\n"}, InvalidInputError,
        ["[model].flexibility ('R.csv'): must be a non-empty square matrix"]),
    "unknown file extension": (
        GOOD.replace("R.csv", "R.xlsx"), {"R.xlsx": SPD}, FileFormatError,
        ["[model].flexibility ('R.xlsx'): cannot tell the format"]),
    "both matrices": (
        GOOD.replace("[model]\n", "[model]\nstiffness = 'R.csv'\n"), {"R.csv": SPD},
        InvalidInputError, ["[model]: give exactly one of flexibility and stiffness (both"]),
    "dofs_per_node mismatch": (
        GOOD.replace("[model]\n", "[model]\ndofs_per_node = [1, 2]\n"), {"R.csv": SPD},
        InvalidInputError, ["[model].dofs_per_node: sums to 3 freedoms, the matrix has 2"]),
    "gaps length": (
        GOOD.replace("gaps = [0.1, 0.2]", "gaps = [0.1]"), {"R.csv": SPD}, InvalidInputError,
        ["[[obstacle]] #1.gaps has 1 value for 2 nodes"]),
    "node out of range": (
        GOOD.replace("nodes = [0, 1]", "nodes = [0, 7]"), {"R.csv": SPD}, InvalidInputError,
        ["[[obstacle]] #1.nodes: node 7 is outside 0..1"]),
    "float node index": (
        GOOD.replace("nodes = [0, 1]", "nodes = [0, 1.5]"), {"R.csv": SPD}, InvalidInputError,
        ["[[obstacle]] #1.nodes: must hold integers"]),
    "direction with wrong components (library error)": (
        GOOD + "direction = [1.0, 0.0]\n", {"R.csv": SPD}, InvalidInputError,
        ["[[obstacle]] #1 (gaps):", "freedoms but the direction has 2 components"]),
    "plane without coordinates": (
        GOOD + "\n[[obstacle]]\ntype = 'plane'\npoint = [0.0]\nnormal = [1.0]\n",
        {"R.csv": SPD}, InvalidInputError,
        ["[[obstacle]] #2: a plane obstacle needs [model].coordinates"]),
    "single-bracket obstacle": (
        BASE_MODEL + BASE_LOADS + "[obstacle]\ntype = 'gaps'\nnodes = [0]\ngaps = [0.1]\n",
        {"R.csv": SPD}, InvalidInputError, ["[[obstacle]]: write [[obstacle]]"]),
    "no obstacle": (
        BASE_MODEL + BASE_LOADS, {"R.csv": SPD}, InvalidInputError,
        ["[[obstacle]]: missing"]),
    "inline nan gap": (
        GOOD.replace("gaps = [0.1, 0.2]", "gaps = [0.1, nan]"), {"R.csv": SPD},
        InvalidInputError, ["[[obstacle]] #1.gaps: contains NaN or inf"]),
    "boolean in loads": (
        BASE_MODEL + "[loads]\nvalues = [1.0, true]\n" + BASE_OBSTACLE, {"R.csv": SPD},
        InvalidInputError, ["[loads].values: must hold numbers only"]),
    "duplicate load entry": (
        BASE_MODEL + "[loads]\nentries = [{ freedom = 1, value = 1.0 },"
        " { node = 1, value = 2.0 }]\n" + BASE_OBSTACLE, {"R.csv": SPD}, InvalidInputError,
        ["[loads].entries #2: freedom 1 is already loaded by entry #1"]),
    "unknown solver": (
        GOOD + "\n[solver]\nname = 'simplex'\n", {"R.csv": SPD}, InvalidInputError,
        ["[solver].name: unknown solver 'simplex'"]),
    "solver option of the wrong kind": (
        GOOD + "\n[solver]\ntol = 'small'\n", {"R.csv": SPD}, InvalidInputError,
        ["[solver].tol: must be a number (default 1e-10), got the string 'small'"]),
    "negative tolerance": (
        GOOD + "\n[solver]\ntol = -1e-8\n", {"R.csv": SPD}, InvalidInputError,
        ["[solver].tol: must be positive"]),
    "backend options for active-set": (
        GOOD + "\n[solver]\n[solver.backend_options]\neps_abs = 1e-9\n", {"R.csv": SPD},
        InvalidInputError, ["[solver].backend_options: not an option of solver 'active-set'"]),
    "npz with several arrays and no key": (
        GOOD.replace("R.csv", "R.npz"), {"R.npz": "several"}, InvalidInputError,
        ["[model].flexibility ('R.npz'): the archive holds 2 arrays (A, B)"]),
    "npz key not found": (
        GOOD.replace('"R.csv"', '{ file = "R.npz", key = "C" }'), {"R.npz": "several"},
        InvalidInputError, ["[model].flexibility ('R.npz'): the archive has no array 'C'"]),
    "missing loads file": (
        BASE_MODEL + "[loads]\nvalues = 'P.csv'\n" + BASE_OBSTACLE, {"R.csv": SPD},
        FileFormatError, ["[loads].values: file 'P.csv' not found"]),
}


@pytest.mark.parametrize("case", list(CASES))
def test_validation_errors_name_the_key(tmp_path, case):
    text, files, cls, fragments = CASES[case]
    for name, content in files.items():
        if content == "several":
            np.savez(tmp_path / name, A=np.eye(2), B=np.eye(2))
        else:
            (tmp_path / name).write_text(content)
    path = write_toml(tmp_path, text)
    with pytest.raises(cls) as info:
        load_problem_file(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(str(path) + ":")
    for fragment in fragments:
        assert fragment in message, message
    # A class below the expected one would also pass pytest.raises; say which was meant.
    if cls is InvalidInputError:
        assert not isinstance(info.value, FileFormatError), message


def test_missing_problem_file(tmp_path):
    with pytest.raises(FileFormatError, match="problem file not found"):
        load_problem_file(tmp_path / "nope.toml")


def test_symmetrised_warning_names_the_key(tmp_path):
    (tmp_path / "R.csv").write_text("2,1\n1.0000000001,2\n")
    path = write_toml(tmp_path, GOOD)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_problem_file(path)
    messages = [str(w.message) for w in caught if issubclass(w.category, SymmetrizedWarning)]
    assert len(messages) == 1
    assert "[model].flexibility ('R.csv'):" in messages[0]


# ------------------------------------------------------------------------------------------
# Results written to a directory


def test_write_results_round_trip(tmp_path):
    spec = load_problem_file(EXAMPLE)
    result = spec.solve()
    out = tmp_path / "deep" / "out"
    paths = write_results(spec, result, out)
    assert paths == [out / name for name in RESULT_FILES]
    assert all(p.is_file() for p in paths)

    with open(out / "displacements.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert list(rows[0]) == ["node", "freedom", "u"]
    assert [(int(r["node"]), int(r["freedom"])) for r in rows] == [(0, 0), (1, 1)]
    np.testing.assert_array_equal([float(r["u"]) for r in rows], result.x)

    with open(out / "contacts.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert list(rows[0]) == ["row", "node", "label", "gap0", "gap", "force", "status"]
    assert [int(r["row"]) for r in rows] == [0, 1]
    assert [int(r["node"]) for r in rows] == [0, 1]
    assert [r["label"] for r in rows] == spec.problem.constraints.labels
    np.testing.assert_array_equal([float(r["gap0"]) for r in rows], [3e-4, 1e-3])
    np.testing.assert_array_equal([float(r["gap"]) for r in rows], result.gaps)
    np.testing.assert_array_equal([float(r["force"]) for r in rows], result.forces)
    assert [r["status"] for r in rows] == ["closed", "closed"]

    with np.load(out / "result.npz") as data:
        assert sorted(data.files) == sorted(["x", "forces", "nodal_forces", "gaps", "closed"])
        np.testing.assert_array_equal(data["x"], result.x)
        np.testing.assert_array_equal(data["forces"], result.forces)
        np.testing.assert_array_equal(data["nodal_forces"], result.nodal_forces)
        np.testing.assert_array_equal(data["gaps"], result.gaps)
        assert data["closed"].dtype == bool
        np.testing.assert_array_equal(data["closed"], result.closed)
    # nodal forces are the stop forces acting against +x: -[100, 300] N (hand derivation)
    np.testing.assert_allclose(result.nodal_forces, [-100.0, -300.0], rtol=RTOL)

    summary = json.loads((out / "summary.json").read_text())
    assert summary["name"] == "two springs against two stops"
    assert Path(summary["problem"]) == EXAMPLE
    assert summary["solver"] == "active-set"
    assert summary["options"] == {"tol": 1e-12}
    assert summary["result"] == json.loads(json.dumps(result.summary()))
    assert summary["result"]["certificate"]["passed"] is True


def test_write_results_non_finite_summary_is_valid_json(tmp_path):
    # A failed solve may carry NaN (e.g. the energy of a qp backend that found nothing): JSON has
    # no NaN, so it is written as null.
    spec = load_problem_file(EXAMPLE)
    result = spec.solve()
    result.energy = math.nan
    write_results(spec, result, tmp_path)
    summary = json.loads((tmp_path / "summary.json").read_text(),
                         parse_constant=lambda name: pytest.fail(f"non-JSON constant {name}"))
    assert summary["result"]["energy"] is None


def test_write_results_rejects_mismatched_result(tmp_path):
    spec = load_problem_file(EXAMPLE)
    other = ProblemSpec(problem=ContactProblem(ReducedModel(flexibility=[[1.0]]), [1.0],
                                               [GapObstacle([0], [0.5])]))
    with pytest.raises(InvalidInputError, match="the problem has 2 freedoms"):
        write_results(spec, solve(other.problem), tmp_path)


def test_write_results_unwritable_directory(tmp_path):
    spec = load_problem_file(EXAMPLE)
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with pytest.raises(FileFormatError, match="cannot write results"):
        write_results(spec, spec.solve(), blocker / "out")

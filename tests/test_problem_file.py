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
from contactqp.core.history import HistoryResult
from contactqp.core.result import FrictionalResult
from contactqp.core.status import ContactStatus
from contactqp.errors import SymmetrizedWarning
from contactqp.io.problem_file import (
    HISTORY_FILES,
    RESULT_FILES,
    ProblemSpec,
    load_problem_file,
    read_array,
    write_results,
)

PROBLEMS = Path(__file__).resolve().parents[1] / "examples" / "problems"
EXAMPLE = PROBLEMS / "two_springs.toml"
BLOCKS = PROBLEMS / "block_on_floor.toml"
CYCLIC = PROBLEMS / "cyclic_block.toml"
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
        np.savetxt(
            directory / name, matrix, delimiter=" ", fmt="%.17g", header="whitespace separated"
        )
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
        scipy.io.mmwrite(
            str(directory / name),
            scipy.sparse.coo_matrix(matrix),
            precision=17,
            symmetry="symmetric",
        )
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
    path = write_toml(
        tmp_path,
        f"""
[model]
flexibility = "{name}"
[loads]
values = [{P}]
[[obstacle]]
type = "gaps"
nodes = [0]
gaps = [{gap}]
""",
    )
    spec = load_problem_file(path)
    result = spec.solve()
    assert result.success
    U_true, F_true = min(r * P, gap), max(P - gap / r, 0.0)
    np.testing.assert_allclose(result.displacements, [U_true], rtol=RTOL)
    np.testing.assert_allclose(result.forces, [F_true], rtol=RTOL, atol=1e-9 * P)
    assert bool(result.contact_status[0] == ContactStatus.CLOSED) == (r * P > gap)

    # The same problem built in Python gives the same answer.
    direct = solve(ContactProblem(ReducedModel(flexibility=[[r]]), [P], [GapObstacle([0], [gap])]))
    np.testing.assert_allclose(result.displacements, direct.displacements, rtol=1e-14)
    np.testing.assert_allclose(result.forces, direct.forces, rtol=1e-14, atol=1e-12)


@pytest.mark.parametrize("fmt", MATRIX_FORMATS)
def test_two_node_coupled_problem_by_hand(tmp_path, fmt):
    # R = [[2, 1], [1, 2]] um/N, P = [1000, -200] N, stops at 1 mm on both nodes (+x).
    # Free: u = R P = [1.8, 0.6] mm -> node 0 crosses its stop, node 1 does not.
    # Guess node 0 closed, node 1 open: 2e-6 (1000 - F0) - 1e-6 * 200 = 1e-3 -> F0 = 400 N;
    # u1 = 1e-6 (1000 - 400) + 2e-6 (-200) = 0.2 mm < 1 mm (open), F0 > 0: the guess holds.
    R = np.array([[2e-6, 1e-6], [1e-6, 2e-6]])
    name = write_matrix(tmp_path, "R", R, fmt)
    path = write_toml(
        tmp_path,
        f"""
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
""",
    )
    spec = load_problem_file(path)
    assert spec.name == "coupled pair"
    result = spec.solve()
    assert result.success
    np.testing.assert_allclose(result.displacements, [1e-3, 2e-4], rtol=RTOL)
    np.testing.assert_allclose(result.forces, [400.0, 0.0], rtol=RTOL, atol=1e-9 * 1000)
    assert result.status_labels == ["closed", "open"]
    np.testing.assert_allclose(result.gaps, [0.0, 8e-4], atol=1e-15)

    direct = solve(
        ContactProblem(
            ReducedModel(flexibility=R), [1000.0, -200.0], [GapObstacle([0, 1], [1e-3, 1e-3])]
        )
    )
    np.testing.assert_allclose(result.displacements, direct.displacements, rtol=1e-14)


def test_stiffness_from_npz_key_and_qp_solver(tmp_path):
    # The same coupled problem given by K = R^-1 in an archive with two arrays, solved by the
    # qp route: the same hand answer (u = [1, 0.2] mm, F = [400, 0] N).
    R = np.array([[2e-6, 1e-6], [1e-6, 2e-6]])
    np.savez(tmp_path / "model.npz", K=np.linalg.inv(R), R=R)
    np.savetxt(tmp_path / "P.csv", [[1000.0], [-200.0]])
    path = write_toml(
        tmp_path,
        """
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
""",
    )
    spec = load_problem_file(path)
    assert spec.solver == "qp"
    assert spec.options == {"backend": "clarabel", "max_iter": 300}
    assert spec.problem.certificate_tol == 1e-6
    assert spec.problem.model.given == "stiffness"
    result = spec.solve()
    assert result.success, result.message
    np.testing.assert_allclose(result.displacements, [1e-3, 2e-4], rtol=1e-7)
    np.testing.assert_allclose(result.forces, [400.0, 0.0], rtol=1e-7, atol=1e-6)


def test_node_pairs_by_hand(tmp_path):
    # Two separate springs ra = 1, rb = 3 um/N; node 0 pushed by P = 1000 N towards node 1,
    # initial gap g = 0.5 mm. Closed pair: ra (P - F) - rb F = g -> F = (ra P - g)/(ra + rb)
    # = 125 N, u0 = ra (P - F) = 0.875 mm, u1 = rb F = 0.375 mm.
    np.savetxt(tmp_path / "R.csv", np.diag([1e-6, 3e-6]), delimiter=",")
    path = write_toml(
        tmp_path,
        """
[model]
flexibility = "R.csv"
[loads]
entries = [{ node = 0, value = 1000.0 }]
[[obstacle]]
type = "pairs"
pairs = [[0, 1]]
gaps = [0.5e-3]
direction = [1.0]
""",
    )
    result = load_problem_file(path).solve()
    assert result.success
    np.testing.assert_allclose(result.forces, [125.0], rtol=RTOL)
    np.testing.assert_allclose(result.displacements, [0.875e-3, 0.375e-3], rtol=RTOL)
    direct = solve(
        ContactProblem(
            ReducedModel(flexibility=np.diag([1e-6, 3e-6])),
            [1000.0, 0.0],
            [NodePairs([[0, 1]], [0.5e-3])],
        )
    )
    np.testing.assert_allclose(result.displacements, direct.displacements, rtol=1e-14)


def test_plane_obstacle_by_hand(tmp_path):
    # One 2-freedom node at the origin, R = [[2, 0.5], [0.5, 1]] um/N, load (0, -300) N, floor
    # at y = -0.1 mm (normal (0, -1) from the body to the floor): gap 0.1 mm.
    # Free: u = R P = (-0.15, -0.3) mm, crossing. Closed: u_y = -0.1 mm = R_yy (-300 + F)
    # -> F = 200 N; u_x = R_xy (-300 + 200) = -0.05 mm.
    R = np.array([[2e-6, 0.5e-6], [0.5e-6, 1e-6]])
    scipy.io.mmwrite(str(tmp_path / "R.mtx"), R, precision=17)
    path = write_toml(
        tmp_path,
        """
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
""",
    )
    result = load_problem_file(path).solve()
    assert result.success
    np.testing.assert_allclose(result.forces, [200.0], rtol=RTOL)
    np.testing.assert_allclose(result.displacements, [-0.05e-3, -0.1e-3], rtol=RTOL)
    direct = solve(
        ContactProblem(
            ReducedModel(flexibility=R, dofs_per_node=2, coordinates=[[0.0, 0.0]]),
            [0.0, -300.0],
            [PlaneObstacle([0.0, -1e-4], [0.0, -1.0])],
        )
    )
    np.testing.assert_allclose(result.displacements, direct.displacements, rtol=1e-14)


def test_example_two_springs_matches_its_derivation():
    # Derivation in the file's comment: u = [0.3, 1.0] mm, stop forces [100, 300] N.
    spec = load_problem_file(EXAMPLE)
    assert spec.name == "two springs against two stops"
    result = spec.solve()
    assert result.success
    np.testing.assert_allclose(result.displacements, [3e-4, 1e-3], rtol=RTOL)
    np.testing.assert_allclose(result.forces, [100.0, 300.0], rtol=RTOL)
    np.testing.assert_allclose(result.gaps, [0.0, 0.0], atol=1e-15)
    assert result.status_labels == ["closed", "closed"]
    # Springs: k1 = 2e6 N/m, k2 = 1e6 N/m, so R = [[1/k1, 1/k1], [1/k1, 1/k1 + 1/k2]].
    np.testing.assert_allclose(
        spec.problem.model.flexibility, [[5e-7, 5e-7], [5e-7, 1.5e-6]], rtol=1e-15
    )


@settings(max_examples=30, deadline=None)
@given(
    r=st.floats(1e-9, 1e-3),
    P=st.floats(-1e4, 1e4),
    gap=st.floats(1e-6, 1e-2),
    interference=st.booleans(),
)
def test_single_node_property(r, P, gap, interference):
    # Inline matrix, any r > 0, load of either sign, gap of either sign (negative: interference):
    # U = min(r P, g), F = max(P - g / r, 0). A gap of exactly zero has its own test
    # below.
    gap = -gap if interference else gap
    with tempfile.TemporaryDirectory() as directory:
        path = write_toml(
            Path(directory),
            f"""
[model]
flexibility = [[{r!r}]]
[loads]
values = [{P!r}]
[[obstacle]]
type = "gaps"
nodes = [0]
gaps = [{gap!r}]
""",
        )
        result = load_problem_file(path).solve()
    assert result.success
    scale_u = max(abs(r * P), abs(gap))
    scale_f = max(abs(P), abs(gap) / r)
    np.testing.assert_allclose(
        result.displacements, [min(r * P, gap)], rtol=1e-9, atol=1e-12 * scale_u
    )
    np.testing.assert_allclose(
        result.forces, [max(P - gap / r, 0.0)], rtol=1e-9, atol=1e-9 * scale_f
    )


def test_zero_gap_closed_contact_is_certified(tmp_path):
    # U = min(r P, 0) = 0, F = P: a perfectly ordinary answer that the solver finds.
    path = write_toml(
        tmp_path,
        """
[model]
flexibility = [[5.8196301223351394e-05]]
[loads]
values = [1.0]
[[obstacle]]
type = "gaps"
nodes = [0]
gaps = [0.0]
""",
    )
    result = load_problem_file(path).solve()
    assert result.success, result.message
    np.testing.assert_allclose(result.forces, [1.0], rtol=RTOL)
    assert abs(result.displacements[0]) < 1e-15
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
        GOOD,
        {},
        FileFormatError,
        ["problem.toml: [model].flexibility: file 'R.csv' not found"],
    ),
    "malformed TOML": (
        "[model\nflexibility = 'R.csv'\n",
        {"R.csv": SPD},
        FileFormatError,
        ["problem.toml: malformed TOML"],
    ),
    "unknown top-level key": (
        GOOD + "\n[solvr]\nname = 'qp'\n",
        {"R.csv": SPD},
        InvalidInputError,
        ["top level: unknown key 'solvr'", "did you mean 'solver'"],
    ),
    "unknown model key": (
        GOOD.replace("flexibility =", "flexibilty ="),
        {"R.csv": SPD},
        InvalidInputError,
        ["[model]: unknown key 'flexibilty'"],
    ),
    "unknown obstacle key": (
        GOOD.replace("gaps = [0.1, 0.2]", "gap = [0.1, 0.2]"),
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]] #1: unknown key 'gap'"],
    ),
    "unknown solver option": (
        GOOD + "\n[solver]\nmax_iters = 10\n",
        {"R.csv": SPD},
        InvalidInputError,
        ["[solver].max_iters: not an option of solver 'active-set'", "did you mean 'max_iter'"],
    ),
    "unknown loads entry key": (
        BASE_MODEL + "[loads]\nentries = [{ freedom = 0, valeu = 1.0 }]\n" + BASE_OBSTACLE,
        {"R.csv": SPD},
        InvalidInputError,
        ["[loads].entries #1: unknown key 'valeu'"],
    ),
    "wrong loads length": (
        BASE_MODEL + "[loads]\nvalues = [1.0, 2.0, 3.0, 4.0]\n" + BASE_OBSTACLE,
        {"R.csv": SPD},
        InvalidInputError,
        ["[loads].values has 4 entries, the model has 2 freedoms"],
    ),
    "unknown obstacle type": (
        GOOD + "\n[[obstacle]]\ntype = 'sphere'\n",
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]] #2: unknown type 'sphere' (expected gaps, plane or pairs)"],
    ),
    "profile in a file": (
        GOOD.replace('type = "gaps"', 'type = "profile"'),
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]] #1: type 'profile' cannot be given in a file"],
    ),
    "NaN in matrix file": (
        GOOD,
        {"R.csv": "2,1\n1,nan\n"},
        InvalidInputError,
        ["[model].flexibility ('R.csv'): contains NaN or inf (first at index [1, 1]"],
    ),
    "not positive definite": (
        GOOD,
        {"R.csv": "1,2\n2,1\n"},
        NotPositiveDefiniteError,
        ["[model].flexibility ('R.csv'):", "not positive definite"],
    ),
    "not a table of numbers": (
        GOOD,
        {"R.csv": "a,b\n1,2\n"},
        FileFormatError,
        ["[model].flexibility ('R.csv'): not a table of numbers"],
    ),
    "not square": (
        GOOD,
        {"R.csv": "1,2,3\n4,5,6\n"},
        InvalidInputError,
        ["[model].flexibility ('R.csv'): must be a non-empty square matrix"],
    ),
    "unknown file extension": (
        GOOD.replace("R.csv", "R.xlsx"),
        {"R.xlsx": SPD},
        FileFormatError,
        ["[model].flexibility ('R.xlsx'): cannot tell the format"],
    ),
    "both matrices": (
        GOOD.replace("[model]\n", "[model]\nstiffness = 'R.csv'\n"),
        {"R.csv": SPD},
        InvalidInputError,
        ["[model]: give exactly one of flexibility and stiffness (both"],
    ),
    "dofs_per_node mismatch": (
        GOOD.replace("[model]\n", "[model]\ndofs_per_node = [1, 2]\n"),
        {"R.csv": SPD},
        InvalidInputError,
        ["[model].dofs_per_node: sums to 3 freedoms, the matrix has 2"],
    ),
    "gaps length": (
        GOOD.replace("gaps = [0.1, 0.2]", "gaps = [0.1]"),
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]] #1.gaps has 1 value for 2 nodes"],
    ),
    "node out of range": (
        GOOD.replace("nodes = [0, 1]", "nodes = [0, 7]"),
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]] #1.nodes: node 7 is outside 0..1"],
    ),
    "float node index": (
        GOOD.replace("nodes = [0, 1]", "nodes = [0, 1.5]"),
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]] #1.nodes: must hold integers"],
    ),
    "direction with wrong components (library error)": (
        GOOD + "direction = [1.0, 0.0]\n",
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]] #1 (gaps):", "freedoms but the direction has 2 components"],
    ),
    "plane without coordinates": (
        GOOD + "\n[[obstacle]]\ntype = 'plane'\npoint = [0.0]\nnormal = [1.0]\n",
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]] #2: a plane obstacle needs [model].coordinates"],
    ),
    "single-bracket obstacle": (
        BASE_MODEL + BASE_LOADS + "[obstacle]\ntype = 'gaps'\nnodes = [0]\ngaps = [0.1]\n",
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]]: write [[obstacle]]"],
    ),
    "no obstacle": (
        BASE_MODEL + BASE_LOADS,
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]]: missing"],
    ),
    "inline nan gap": (
        GOOD.replace("gaps = [0.1, 0.2]", "gaps = [0.1, nan]"),
        {"R.csv": SPD},
        InvalidInputError,
        ["[[obstacle]] #1.gaps: contains NaN or inf"],
    ),
    "boolean in loads": (
        BASE_MODEL + "[loads]\nvalues = [1.0, true]\n" + BASE_OBSTACLE,
        {"R.csv": SPD},
        InvalidInputError,
        ["[loads].values: must hold numbers only"],
    ),
    "duplicate load entry": (
        BASE_MODEL + "[loads]\nentries = [{ freedom = 1, value = 1.0 },"
        " { node = 1, value = 2.0 }]\n" + BASE_OBSTACLE,
        {"R.csv": SPD},
        InvalidInputError,
        ["[loads].entries #2: freedom 1 is already loaded by entry #1"],
    ),
    "unknown solver": (
        GOOD + "\n[solver]\nname = 'simplex'\n",
        {"R.csv": SPD},
        InvalidInputError,
        [
            "[solver].name: unknown method 'simplex' for frictionless problems; choose one of "
            "active-set (default), qp"
        ],
    ),
    "solver option of the wrong kind": (
        GOOD + "\n[solver]\ntol = 'small'\n",
        {"R.csv": SPD},
        InvalidInputError,
        ["[solver].tol: must be a number (default 1e-10), got the string 'small'"],
    ),
    "negative tolerance": (
        GOOD + "\n[solver]\ntol = -1e-8\n",
        {"R.csv": SPD},
        InvalidInputError,
        ["[solver].tol: must be positive"],
    ),
    "backend options for active-set": (
        GOOD + "\n[solver]\n[solver.backend_options]\neps_abs = 1e-9\n",
        {"R.csv": SPD},
        InvalidInputError,
        ["[solver].backend_options: not an option of solver 'active-set'"],
    ),
    "npz with several arrays and no key": (
        GOOD.replace("R.csv", "R.npz"),
        {"R.npz": "several"},
        InvalidInputError,
        ["[model].flexibility ('R.npz'): ", "the archive holds 2 arrays (A, B)"],
    ),
    "npz key not found": (
        GOOD.replace('"R.csv"', '{ file = "R.npz", key = "C" }'),
        {"R.npz": "several"},
        InvalidInputError,
        ["[model].flexibility ('R.npz'): ", "the archive has no array 'C'"],
    ),
    "missing loads file": (
        BASE_MODEL + "[loads]\nvalues = 'P.csv'\n" + BASE_OBSTACLE,
        {"R.csv": SPD},
        FileFormatError,
        ["[loads].values: file 'P.csv' not found"],
    ),
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
    np.testing.assert_array_equal([float(r["u"]) for r in rows], result.displacements)

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
        assert sorted(data.files) == sorted(
            ["displacements", "forces", "nodal_forces", "gaps", "contact_status"]
        )
        np.testing.assert_array_equal(data["displacements"], result.displacements)
        np.testing.assert_array_equal(data["forces"], result.forces)
        np.testing.assert_array_equal(data["nodal_forces"], result.nodal_forces)
        np.testing.assert_array_equal(data["gaps"], result.gaps)
        np.testing.assert_array_equal(data["contact_status"], [ContactStatus.CLOSED] * 2)
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
    summary = json.loads(
        (tmp_path / "summary.json").read_text(),
        parse_constant=lambda name: pytest.fail(f"non-JSON constant {name}"),
    )
    assert summary["result"]["energy"] is None


def test_write_results_rejects_mismatched_result(tmp_path):
    spec = load_problem_file(EXAMPLE)
    other = ProblemSpec(
        problem=ContactProblem(ReducedModel(flexibility=[[1.0]]), [1.0], [GapObstacle([0], [0.5])])
    )
    with pytest.raises(InvalidInputError, match="the problem has 2 freedoms"):
        write_results(spec, solve(other.problem), tmp_path)


def test_write_results_unwritable_directory(tmp_path):
    spec = load_problem_file(EXAMPLE)
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with pytest.raises(FileFormatError, match="cannot write results"):
        write_results(spec, spec.solve(), blocker / "out")


# ------------------------------------------------------------------------------------------
# Friction: answers against hand derivations
#
# The friction routes end on a natural-map error of 1e-12 (the files ask for tol = 1e-12) of
# the dimensionless problem, so forces agree with the hand answers to ~1e-12 of the load scale;
# we compare at 1e-9 relative (1e-9 of the load scale, or of the slip scale, for values that are
# zero by hand). The polygonal route solves QPs with an interior-point backend: 1e-7.


def block_parameters(spec):
    """kx, ky (N/m), horizontal and vertical loads per block (N), read from a block file."""
    R = spec.problem.model.flexibility
    kx, ky = 1.0 / R[0, 0], 1.0 / R[1, 1]
    P = spec.problem.loads if spec.history is None else spec.history[-1]
    return kx, ky, P[0::2], P[1::2]


def test_example_block_on_floor_matches_its_derivation():
    # Derivation in the file's comment: normal force N = W - ky g per block, friction limit
    # mu N; block 0 sticks (u_x = 0, r_T = -T0), block 1 slips (r_T = -mu N, u_x = (T1 - mu N)
    # / kx, dissipation mu N u_x). Computed here from the file's own inputs.
    spec = load_problem_file(BLOCKS)
    assert spec.frictional and spec.solver == "coulomb" and spec.options == {"tol": 1e-12}
    kx, ky, T, P_y = block_parameters(spec)
    gap = 2e-6  # floor at y = -2e-6, blocks at y = 0
    np.testing.assert_allclose(spec.problem.constraints.gaps, [gap, gap], rtol=1e-15)
    mu = spec.problem.law.mu
    np.testing.assert_array_equal(mu, [0.3, 0.3])
    N = -P_y - ky * gap
    limit = mu * N
    assert T[0] <= limit[0] and T[1] > limit[1]  # the example covers stick and slip
    u_x = np.maximum(T - limit, 0.0) / kx
    result = spec.solve()
    assert isinstance(result, FrictionalResult) and result.success, result.message
    assert result.status_labels == ["stick", "slip"]
    np.testing.assert_allclose(result.normal_forces, N, rtol=1e-9)
    np.testing.assert_allclose(result.tangential_forces[:, 0], -np.minimum(T, limit), rtol=1e-9)
    np.testing.assert_allclose(result.displacements[0::2], u_x, rtol=1e-9, atol=1e-9 * u_x.max())
    np.testing.assert_allclose(result.displacements[1::2], [-gap, -gap], rtol=1e-9)
    np.testing.assert_allclose(result.slip[:, 0], u_x, rtol=1e-9, atol=1e-9 * u_x.max())
    np.testing.assert_allclose(
        result.dissipation, limit * u_x, rtol=1e-9, atol=1e-9 * float(np.max(limit * u_x))
    )
    # elastic energy: springs kx stretched by u_x, ky by the gap
    np.testing.assert_allclose(
        result.elastic_energy, 0.5 * kx * np.sum(u_x**2) + ky * gap**2, rtol=1e-9
    )


def masing(force, amplitude, limit, stiffness, segment):
    """Closed-form displacement of a spring-held block under friction (Masing's rule).

    ``segment`` 0: loading from rest; odd: unloading from ``+amplitude``; even > 0: reloading
    from ``-amplitude``.
    """

    def virgin(f):
        return np.maximum(f - limit, 0.0) / stiffness

    top = virgin(amplitude)
    down = top - 2.0 * virgin((amplitude - force) / 2.0)
    up = -top + 2.0 * virgin((force + amplitude) / 2.0)
    return np.where(segment == 0, virgin(force), np.where(segment % 2 == 1, down, up))


def cyclic_closed_form(spec, steps_per_segment=4):
    """Per-step displacements (K, 2) and dissipation (K,) of the cyclic example, by hand."""
    kx, ky, A, _ = block_parameters(spec)
    N = ky * 1e-5  # interference 10 um, no vertical load
    limit = spec.problem.law.mu * N
    factors = spec.factors
    K = len(factors)
    segment = np.maximum(np.arange(K) - 1, 0) // steps_per_segment
    force = factors[:, None] * A[None, :]
    x = masing(force, A[None, :], limit[None, :], kx, segment[:, None])
    slid = np.abs(np.diff(np.vstack([np.zeros((1, 2)), x]), axis=0))
    return x, (slid * limit).sum(axis=1), limit, force


def test_example_cyclic_block_matches_masing():
    # Derivation in the file's comment: block 0 always sticks, block 1 follows Masing's rule;
    # each step dissipates L times the distance slid (the friction force is L while sliding).
    spec = load_problem_file(CYCLIC)
    assert spec.history.shape == (13, 4)
    np.testing.assert_allclose(
        spec.factors, [0, 0.25, 0.5, 0.75, 1, 0.5, 0, -0.5, -1, -0.5, 0, 0.5, 1], atol=1e-15
    )
    x, dissipated, limit, force = cyclic_closed_form(spec)
    history = spec.solve()
    assert isinstance(history, HistoryResult) and history.success
    assert len(history) == 13
    scale = np.max(np.abs(x))
    np.testing.assert_allclose(history.displacements[:, 0::2], x, rtol=1e-9, atol=1e-9 * scale)
    np.testing.assert_allclose(history.dissipated, dissipated, atol=1e-9 * dissipated.max())
    # the hand table of the file: 0.3 J in all, block 1 at +-x_max at the turning points
    np.testing.assert_allclose(history.dissipated.sum(), dissipated.sum(), rtol=1e-9)
    slipping = np.abs(np.diff(np.vstack([np.zeros((1, 2)), x]), axis=0)) > 1e-9 * scale
    np.testing.assert_array_equal(history.contact_status, np.where(slipping, 2, 1))
    # friction force: -F while sticking from rest, +-L while sliding
    np.testing.assert_allclose(
        history.forces[:, :, 1], x * 1e6 - force, rtol=1e-9, atol=1e-9 * limit.max()
    )
    summary = spec.summary(history)
    assert summary["steps"] == 13 and summary["failed_steps"] == []
    assert [r["step"] for r in summary["records"]] == list(range(13))
    assert [r["factor"] for r in summary["records"]] == spec.factors.tolist()
    assert [r["slip"] for r in summary["records"]] == slipping.sum(axis=1).tolist()
    np.testing.assert_allclose(summary["dissipated"], dissipated.sum(), rtol=1e-9)
    assert summary["final"] == {"open": 0, "stick": 1, "slip": 1}
    json.dumps(summary, allow_nan=False)  # JSON-ready


COUPLED = """
[model]
stiffness = [[1e6, 3e5], [3e5, 2e6]]        # N/m
dofs_per_node = 2
[loads]
values = [{T}, -1000.0]
[[obstacle]]
type = "gaps"
nodes = [0]
gaps = [1e-4]
direction = [0.0, -1.0]
[friction]
mu = 0.25
{extra}
"""


@pytest.mark.parametrize("route", ["coulomb", "tresca", "polygonal"])
@pytest.mark.parametrize("T", [150.0, 300.0], ids=["stick", "slip"])
def test_coupled_node_stick_and_slip_by_hand(tmp_path, route, T):
    # One node, K = [[kxx, kxy], [kxy, kyy]], load (T, -W), floor g below (normal (0, -1),
    # tangent +x), so the contact force on the node is (r_T, r_N) and K u = P + (r_T, r_N),
    # u_y = -g. Stick (u_x = 0): (r_T, r_N) = K (0, -g) - P = (-kxy g - T, W - kyy g), valid
    # while |kxy g + T| <= mu (W - kyy g). Slip towards +x (r_T = -mu r_N):
    # u_x = (T + kxy g - mu (W - kyy g)) / (kxx + mu kxy), r_N = kxy u_x - kyy g + W.
    # Numbers: W - kyy g = 800 N, limit 200 N: T = 150 -> 180 N (stick); T = 300 -> slip.
    kxx, kxy, kyy, W, g, mu = 1e6, 3e5, 2e6, 1000.0, 1e-4, 0.25
    extra = {
        "coulomb": 'solver = "coulomb"\ntol = 1e-12',
        "tresca": 'solver = "tresca"',
        "polygonal": "facets = 4",
    }[route]
    spec = load_problem_file(write_toml(tmp_path, COUPLED.format(T=T, extra=extra)))
    assert spec.solver == route
    result = spec.solve()
    assert result.success, result.message
    stick_force = kxy * g + T
    if abs(stick_force) <= mu * (W - kyy * g):
        u_x, r_N, r_T, status = 0.0, W - kyy * g, -stick_force, "stick"
    else:
        u_x = (T + kxy * g - mu * (W - kyy * g)) / (kxx + mu * kxy)
        r_N = kxy * u_x - kyy * g + W
        r_T, status = -mu * r_N, "slip"
    assert result.status_labels == [status]
    rtol = 1e-9 if route == "coulomb" else 1e-7
    np.testing.assert_allclose(result.forces[0], [r_N, r_T], rtol=rtol)
    np.testing.assert_allclose(result.displacements, [u_x, -g], rtol=rtol, atol=rtol * g)


def test_per_contact_mu_and_cohesion_from_files(tmp_path):
    # The blocks of block_on_floor.toml (T = 200 and 400 N) resting on the floor (no gap:
    # cohesion models a bonded interface, so N = W = 1000 N), with mu = [0.3, 0.1] (a file) and
    # cohesion [0, 50] N: limits mu N + c = 300 N and 150 N. Block 0 sticks (r_T = -200 N);
    # block 1 slips: r_T = -150 N, u_x = (400 - 150) / kx.
    text = BLOCKS.read_text().replace("point = [0.0, -2e-6]", "point = [0.0, 0.0]")
    text = text.replace("\nmu = 0.3\n", '\nmu = "mu.csv"\ncohesion = [0.0, 50.0]\n')
    np.savetxt(tmp_path / "mu.csv", [[0.3], [0.1]])
    spec = load_problem_file(write_toml(tmp_path, text))
    np.testing.assert_array_equal(spec.problem.law.mu, [0.3, 0.1])
    np.testing.assert_array_equal(spec.problem.law.cohesion, [0.0, 50.0])
    kx, ky, T, P_y = block_parameters(spec)
    np.testing.assert_array_equal(spec.problem.constraints.gaps, [0.0, 0.0])
    limit = np.array([0.3, 0.1]) * -P_y + [0.0, 50.0]
    result = spec.solve()
    assert result.success, result.message
    assert result.status_labels == ["stick", "slip"]
    np.testing.assert_allclose(result.tangential_forces[:, 0], -np.minimum(T, limit), rtol=1e-9)
    np.testing.assert_allclose(result.displacements[2], (T[1] - limit[1]) / kx, rtol=1e-9)


THREE_D = """
[model]
flexibility = [[1e-6, 0.0, 0.0], [0.0, 1e-6, 0.0], [0.0, 0.0, 1e-8]]
dofs_per_node = 3
[loads]
values = [{Tx!r}, {Ty!r}, -1000.0]
[[obstacle]]
type = "gaps"
nodes = [0]
gaps = [0.0]
direction = [0.0, 0.0, -1.0]
[friction]
mu = 0.3
{extra}
"""


def test_three_d_exact_cone_slips_along_the_push(tmp_path):
    # One 3-freedom node on a floor (N = W = 1000 N), pushed by T at 30 degrees in the plane:
    # the exact cone is round, so with |T| > mu N it slips along T by (|T| - mu N) / kt and the
    # floor's tangential force is -mu N T/|T|, whatever the tangent basis.
    kt, N, mu, T = 1e6, 1000.0, 0.3, 500.0
    direction = np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    Tx, Ty = map(float, T * direction)  # plain floats: repr(np.float64) is not TOML
    spec = load_problem_file(
        write_toml(tmp_path, THREE_D.format(Tx=Tx, Ty=Ty, extra="tol = 1e-12"))
    )
    result = spec.solve()
    assert result.success, result.message
    tangents = spec.problem.frames.tangents[0]  # (2, 3)
    friction = result.tangential_forces[0] @ tangents  # global force vector
    np.testing.assert_allclose(friction[:2], -mu * N * direction, rtol=1e-9)
    np.testing.assert_allclose(result.displacements[:2], (T - mu * N) / kt * direction, rtol=1e-9)
    assert result.status_labels == ["slip"]


@pytest.mark.parametrize("facets", [None, 4])
def test_three_d_square_cone_slips_below_the_round_one(tmp_path, facets):
    # Pushed along the first tangent t1 (the normal of the square's side 0) by T with
    # mu N cos(pi/4) < T < mu N: the round cone sticks (u = 0, r_T = -T), the inscribed square
    # (facets = 4, apothem mu N cos(pi/4)) slips along t1 by (T - mu N cos(pi/4)) / kt.
    kt, N, mu = 1e6, 1000.0, 0.3
    T = 0.85 * mu * N
    probe = load_problem_file(write_toml(tmp_path, THREE_D.format(Tx=0.0, Ty=0.0, extra="")))
    t1 = probe.problem.frames.tangents[0, 0]
    Tx, Ty = map(float, T * t1[:2])  # plain floats: repr(np.float64) is not TOML
    extra = "tol = 1e-12" if facets is None else f"facets = {facets}"
    spec = load_problem_file(write_toml(tmp_path, THREE_D.format(Tx=Tx, Ty=Ty, extra=extra)))
    assert spec.solver == ("coulomb" if facets is None else "polygonal")
    result = spec.solve()
    assert result.success, result.message
    bound = mu * N * (1.0 if facets is None else np.cos(np.pi / facets))
    expected = max(T - bound, 0.0) / kt
    np.testing.assert_allclose(
        result.displacements[:2], expected * t1[:2], rtol=1e-7, atol=1e-7 * T / kt
    )
    np.testing.assert_allclose(
        result.tangential_forces[0], [-min(T, bound), 0.0], rtol=1e-7, atol=1e-7 * T
    )
    assert result.status_labels == ["stick" if facets is None else "slip"]


def test_points_history_equals_the_factors_history(tmp_path):
    # The cyclic example's turning points written as full load vectors: inline rows and files
    # mixed, and as one matrix file. Same loads, same closed form (Masing).
    reference = load_problem_file(CYCLIC)
    turning = np.array([0.0, 1.0, -1.0, 1.0])[:, None] * reference.problem.loads
    np.savetxt(tmp_path / "P1.csv", turning[1][None, :], delimiter=",")
    np.save(tmp_path / "P2.npy", turning[2])
    np.savetxt(tmp_path / "points.csv", turning, delimiter=",")
    base = CYCLIC.read_text()
    base = base[: base.index("\n[loads]")] + base[base.index("\n[[obstacle]]") :]
    x, dissipated, _, _ = cyclic_closed_form(reference)
    for points in (
        f'[{toml_list(turning[0])}, "P1.csv", {{ file = "P2.npy" }}, {toml_list(turning[3])}]',
        '"points.csv"',
    ):
        text = base.replace("factors = [0.0, 1.0, -1.0, 1.0]", f"points = {points}")
        spec = load_problem_file(write_toml(tmp_path, text))
        assert spec.factors is None
        np.testing.assert_allclose(spec.history, reference.history, rtol=1e-15, atol=1e-12)
        history = spec.solve()
        assert history.success
        np.testing.assert_allclose(
            history.displacements[:, 0::2], x, rtol=1e-9, atol=1e-9 * np.abs(x).max()
        )
        np.testing.assert_allclose(history.dissipated, dissipated, atol=1e-9 * dissipated.max())
        assert all(r["factor"] is None for r in spec.summary(history)["records"])


# ------------------------------------------------------------------------------------------
# Friction: results written to a directory


def read_rows(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def test_write_friction_results(tmp_path):
    spec = load_problem_file(BLOCKS)
    result = spec.solve()
    paths = write_results(spec, result, tmp_path)
    assert paths == [tmp_path / name for name in RESULT_FILES]
    rows = read_rows(tmp_path / "contacts.csv")
    assert list(rows[0]) == [
        "row",
        "node",
        "label",
        "gap0",
        "gap",
        "normal_force",
        "tangential_force",
        "slip",
        "tangential_displacement",
        "dissipated",
        "status",
    ]
    assert [r["status"] for r in rows] == ["stick", "slip"]
    for name, values in (
        ("normal_force", result.normal_forces),
        ("tangential_force", result.tangential_forces[:, 0]),
        ("slip", result.slip[:, 0]),
        ("dissipated", result.dissipation),
        ("tangential_displacement", result.tangential_displacements[:, 0]),
        ("gap", result.gaps),
    ):
        np.testing.assert_array_equal([float(r[name]) for r in rows], values, err_msg=name)
    with np.load(tmp_path / "result.npz") as data:
        assert sorted(data.files) == sorted(
            [
                "displacements",
                "forces",
                "nodal_forces",
                "gaps",
                "slip",
                "tangential_displacements",
                "contact_status",
                "dissipation",
                "normals",
                "tangents",
            ]
        )
        np.testing.assert_array_equal(data["forces"], result.forces)
        np.testing.assert_array_equal(data["contact_status"], [1, 2])
        # floor normal (0, -1) from the file; tangent: the normal turned by +90 degrees
        np.testing.assert_array_equal(data["normals"], [[0.0, -1.0], [0.0, -1.0]])
        np.testing.assert_array_equal(data["tangents"], [[[1.0, 0.0]], [[1.0, 0.0]]])
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["solver"] == "coulomb" and summary["options"] == {"tol": 1e-12}
    assert summary["friction"] == {"mu": [0.3, 0.3], "cohesion": [0.0, 0.0], "facets": None}
    assert summary["result"]["stick"] == 1 and summary["result"]["slip"] == 1


def test_write_history_results(tmp_path):
    spec = load_problem_file(CYCLIC)
    history = spec.solve()
    paths = write_results(spec, history, tmp_path)
    assert paths == [tmp_path / name for name in HISTORY_FILES]
    K, n, k = 13, 4, 2
    rows = read_rows(tmp_path / "displacements.csv")
    assert list(rows[0]) == ["step", "node", "freedom", "u"] and len(rows) == K * n
    u = np.array([float(r["u"]) for r in rows]).reshape(K, n)
    np.testing.assert_array_equal(u, history.displacements)
    rows = read_rows(tmp_path / "contacts.csv")
    assert list(rows[0])[:2] == ["step", "row"] and len(rows) == K * k
    np.testing.assert_array_equal(
        np.array([float(r["tangential_force"]) for r in rows]).reshape(K, k),
        history.forces[:, :, 1],
    )
    rows = read_rows(tmp_path / "steps.csv")
    assert list(rows[0]) == [
        "step",
        "factor",
        "open",
        "stick",
        "slip",
        "dissipated",
        "cumulative_dissipated",
        "iterations",
        "certificate_worst",
        "success",
    ]
    np.testing.assert_array_equal([float(r["factor"]) for r in rows], spec.factors)
    np.testing.assert_array_equal(
        [int(r["slip"]) for r in rows], (history.contact_status == 2).sum(axis=1)
    )
    _, dissipated, _, _ = cyclic_closed_form(spec)
    np.testing.assert_allclose(
        [float(r["cumulative_dissipated"]) for r in rows],
        np.cumsum(dissipated),
        atol=1e-9 * dissipated.sum(),
    )
    with np.load(tmp_path / "result.npz") as data:
        assert data["displacements"].shape == (K, n) and data["forces"].shape == (K, k, 2)
        assert data["slip"].shape == (K, k, 1) and data["contact_status"].shape == (K, k)
        np.testing.assert_array_equal(data["loads"], spec.history)
        np.testing.assert_array_equal(data["factors"], spec.factors)
        assert data["success"].dtype == bool and data["success"].all()
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert len(summary["result"]["records"]) == K


def test_write_results_rejects_a_result_of_the_wrong_kind(tmp_path):
    spec = load_problem_file(CYCLIC)
    with pytest.raises(InvalidInputError, match="result must be a HistoryResult"):
        write_results(spec, solve(spec.problem), tmp_path)


# ------------------------------------------------------------------------------------------
# Friction and loading: validation

FRICTION_MODEL = """
[model]
flexibility = [[1e-6, 0.0, 0.0, 0.0], [0.0, 1e-8, 0.0, 0.0], [0.0, 0.0, 1e-6, 0.0],
               [0.0, 0.0, 0.0, 1e-8]]
dofs_per_node = 2
"""
FRICTION_LOADS = """
[loads]
values = [100.0, -1000.0, 100.0, -1000.0]
"""
FRICTION_OBSTACLE = """
[[obstacle]]
type = "gaps"
nodes = [0, 1]
gaps = [0.0, 0.0]
direction = [0.0, -1.0]
"""
FRICTION_BASE = FRICTION_MODEL + FRICTION_LOADS + FRICTION_OBSTACLE
FRICTION = FRICTION_BASE + "\n[friction]\nmu = 0.3\n"
LOADING = FRICTION + "\n[loading]\nfactors = [0.0, 1.0, -1.0]\nsteps = 2\n"

FRICTION_CASES = {
    "unknown friction key": (
        FRICTION + "muu = 0.2\n",
        ["[friction].muu: not an option of friction solver 'coulomb'", "did you mean 'mu'"],
    ),
    "misspelt friction option": (
        FRICTION + "max_iters = 5\n",
        ["[friction].max_iters:", "did you mean 'max_iter'"],
    ),
    "mu missing": (FRICTION.replace("mu = 0.3", "cohesion = 1.0"), ["[friction]: missing 'mu'"]),
    "negative mu": (
        FRICTION.replace("mu = 0.3", "mu = -0.1"),
        ["[friction].mu: mu must be >= 0, got -0.1"],
    ),
    "mu per contact of the wrong length": (
        FRICTION.replace("mu = 0.3", "mu = [0.3, 0.2, 0.1]"),
        ["[friction].mu:", "one value per contact (2), got shape (3,)"],
    ),
    "mu not a number": (
        FRICTION.replace("mu = 0.3", "mu = true"),
        ["[friction].mu: must be an array of numbers or a file reference"],
    ),
    "negative cohesion": (
        FRICTION + "cohesion = [1.0, -2.0]\n",
        ["[friction].cohesion: cohesion must be >= 0"],
    ),
    "cohesion without mu": (
        FRICTION.replace("mu = 0.3", "mu = [0.3, 0.0]") + "cohesion = 5.0\n",
        ["[friction].cohesion: cohesion > 0 needs mu > 0", "contact 1"],
    ),
    "cohesion on a gapped contact": (
        FRICTION.replace("gaps = [0.0, 0.0]", "gaps = [0.0, 1e-6]") + "cohesion = 5.0\n",
        ["[friction]: cohesion models a bonded interface", "contact 1"],
    ),
    "facets below 3": (
        FRICTION + "facets = 2\n",
        ["[friction].facets: facets must be an integer from 3 to 1024", "got 2"],
    ),
    "facets not an integer": (
        FRICTION + "facets = 6.5\n",
        ["[friction].facets: facets must be an integer from 3"],
    ),
    "facets with the coulomb route": (
        FRICTION + "facets = 8\nsolver = 'coulomb'\n",
        [
            "[friction].solver: method 'coulomb' does not solve frictional-polygonal problems",
            "methods for frictional-polygonal problems: polygonal (default)",
        ],
    ),
    "polygonal without facets": (
        FRICTION + "solver = 'polygonal'\n",
        [
            "[friction].solver: method 'polygonal' does not solve frictional problems",
            "coulomb (default)",
        ],
    ),
    "unknown friction route": (
        FRICTION + "solver = 'newton'\n",
        [
            "[friction].solver: unknown method 'newton' for frictional "
            "problems; choose one of coulomb (default), tresca"
        ],
    ),
    "friction tolerance not positive": (
        FRICTION + "tol = 0.0\n",
        ["[friction].tol: must be positive"],
    ),
    "frictionless solver name with friction": (
        FRICTION + "\n[solver]\nname = 'active-set'\n",
        [
            "[solver].name: solver 'active-set' is frictionless but [friction] is given",
            "[friction].solver",
        ],
    ),
    "frictionless solver option with friction": (
        FRICTION + "\n[solver]\ntol = 1e-9\n",
        ["[solver].tol: with [friction], [solver] holds only certificate_tol"],
    ),
    "friction on one-freedom nodes": (
        "[model]\nflexibility = [[1e-6]]\n[loads]\nvalues = [1.0]\n[[obstacle]]\n"
        "type = 'gaps'\nnodes = [0]\ngaps = [0.0]\n[friction]\nmu = 0.3\n",
        [
            "[friction]: friction needs contact nodes with 2 or 3 freedoms",
            "node 0 of [[obstacle]] #1 has 1",
        ],
    ),
    "friction on nodes with 2 and 3 freedoms": (
        "[model]\nflexibility = [[1e-6, 0, 0, 0, 0], [0, 1e-6, 0, 0, 0], [0, 0, 1e-6, 0, 0],"
        " [0, 0, 0, 1e-6, 0], [0, 0, 0, 0, 1e-6]]\ndofs_per_node = [2, 3]\n[loads]\n"
        "values = [0.0, 0.0, 0.0, 0.0, 0.0]\n[[obstacle]]\ntype = 'gaps'\nnodes = [0]\n"
        "gaps = [0.0]\ndirection = [0.0, -1.0]\n[[obstacle]]\ntype = 'gaps'\nnodes = [1]\n"
        "gaps = [0.0]\ndirection = [0.0, 0.0, -1.0]\n[friction]\nmu = 0.3\n",
        ["[friction]: local frames need contact nodes with one number of freedoms"],
    ),
    "friction as a value": (
        "friction = 0.3\n" + FRICTION_BASE,
        ["[friction]: must be a table, got the number 0.3"],
    ),
    "loading without friction": (
        FRICTION_BASE + "\n[loading]\nfactors = [0.0, 1.0]\n",
        ["[loading]: a load history needs [friction]"],
    ),
    "unknown loading key": (
        LOADING.replace("steps = 2", "step = 2"),
        ["[loading]: unknown key 'step'", "did you mean 'steps'"],
    ),
    "loading with both factors and points": (
        LOADING + "points = [[0.0, 0.0, 0.0, 0.0]]\n",
        ["[loading]: give exactly one of factors and points (both given)"],
    ),
    "loading with neither": (
        LOADING.replace("factors = [0.0, 1.0, -1.0]\n", ""),
        ["[loading]: give exactly one of factors and points (neither"],
    ),
    "steps zero": (
        LOADING.replace("steps = 2", "steps = 0"),
        ["[loading].steps: steps must be an integer >= 1, got 0"],
    ),
    "steps not an integer": (
        LOADING.replace("steps = 2", "steps = 1.5"),
        ["[loading].steps: must be an integer (default 1)"],
    ),
    "factors as a matrix": (
        LOADING.replace("[0.0, 1.0, -1.0]", "[[0.0, 1.0], [1.0, 0.0]]"),
        ["[loading].factors: must be a list of numbers (1-D)"],
    ),
    "empty factors": (LOADING.replace("[0.0, 1.0, -1.0]", "[]"), ["[loading].factors: is empty"]),
    "NaN factor": (
        LOADING.replace("[0.0, 1.0, -1.0]", "[0.0, nan]"),
        ["[loading].factors: contains NaN or inf"],
    ),
    "points rows of the wrong length": (
        FRICTION_MODEL + FRICTION_OBSTACLE + "[friction]\nmu = 0.3\n[loading]\n"
        "points = [[0.0, 0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]\n",
        ["[loading].points: rows have different lengths"],
    ),
    "points with too few freedoms": (
        FRICTION_MODEL + FRICTION_OBSTACLE + "[friction]\nmu = 0.3\n[loading]\n"
        "points = [[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]\n",
        ["[loading].points: must have rows of 4 values (one per freedom), got shape (2, 3)"],
    ),
    "points file entry of the wrong length": (
        FRICTION_MODEL + FRICTION_OBSTACLE + "[friction]\nmu = 0.3\n[loading]\n"
        "points = [[0.0, 0.0, 0.0, 0.0], 'P.csv']\n",
        ["[loading].points #2 has 3 values, the model has 4 freedoms"],
    ),
    "points and [loads]": (
        FRICTION + "\n[loading]\npoints = [[0.0, 0.0, 0.0, 0.0]]\n",
        ["[loading].points: give the loads here or in [loads], not both"],
    ),
    "factors without [loads]": (
        FRICTION_MODEL + FRICTION_OBSTACLE + "[friction]\nmu = 0.3\n[loading]\n"
        "factors = [0.0, 1.0]\n",
        ["[loads]: missing"],
    ),
}


@pytest.mark.parametrize("case", list(FRICTION_CASES))
def test_friction_and_loading_errors_name_the_key(tmp_path, case):
    text, fragments = FRICTION_CASES[case]
    (tmp_path / "P.csv").write_text("1.0, 2.0, 3.0\n")
    path = write_toml(tmp_path, text)
    with pytest.raises(InvalidInputError) as info:
        load_problem_file(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(path) + ":"), message
    for fragment in fragments:
        assert fragment in message, message


def test_friction_solver_options_reach_the_route(tmp_path):
    # max_iter and backend are checked against the polygonal route's signature; backend
    # settings are passed on verbatim.
    text = FRICTION + (
        "facets = 6\nmax_iter = 30\nbackend = 'clarabel'\n"
        "[friction.backend_options]\ntol_feas = 1e-9\n"
    )
    spec = load_problem_file(write_toml(tmp_path, text))
    assert spec.solver == "polygonal"
    assert spec.options == {"max_iter": 30, "backend": "clarabel", "tol_feas": 1e-9}
    assert spec.problem.law.facets == 6

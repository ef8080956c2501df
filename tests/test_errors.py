"""The error tree and the rule of contactqp.errors: bad input, no answer, or an unproven answer.

Truths used: a qpsolvers backend made to return no point (or to raise) on valid input is a
method that produced no answer, a :class:`SolverError`; one stopped by an iteration cap of 1
returns a finite point it does not claim, a result with ``success`` False. On the command line
the first exits 1, a bad input 2, each with one line on stderr and no traceback.
"""

from __future__ import annotations

import ast
import contextlib
import io
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import contactqp.errors as errors
from contactqp.cli import main
from contactqp.core.local_problem import LocalProblem
from contactqp.errors import (
    ContactError,
    InvalidInputError,
    LayersError,
    ReferenceSolveError,
    SolverError,
)
from contactqp.io.problem_file import load_problem_file
from contactqp.optional import require_backend

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "contactqp"
EXAMPLES = ROOT / "examples" / "problems"
FCLIB = ROOT.parent / "shared" / "data" / "fclib"

qpsolvers = pytest.importorskip("qpsolvers")


def exception_classes(path: Path) -> list[str]:
    """Classes defined in ``path`` whose bases are named like exceptions or warnings."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ClassDef):
            bases = [ast.unparse(base).rsplit(".", 1)[-1] for base in node.bases]
            if any(
                base.endswith(("Error", "Exception", "Warning")) or base in errors.__all__
                for base in bases
            ):
                found.append(node.name)
    return found


def test_every_exception_class_is_defined_in_errors_py():
    elsewhere = {
        str(path.relative_to(PACKAGE)): names
        for path in PACKAGE.rglob("*.py")
        if path.name != "errors.py" and (names := exception_classes(path))
    }
    assert elsewhere == {}
    assert set(exception_classes(PACKAGE / "errors.py")) == set(errors.__all__)


def test_a_solver_error_is_not_bad_input():
    assert issubclass(SolverError, ContactError)
    assert not issubclass(SolverError, (ValueError, InvalidInputError))
    assert issubclass(ReferenceSolveError, SolverError) and issubclass(LayersError, SolverError)


def test_a_backend_not_installed_is_named_with_those_that_are():
    with pytest.raises(
        InvalidInputError, match=r"^backend 'nope' is not installed; available: a, b$"
    ):
        require_backend("nope", ["b", "a"])
    require_backend("a", ["b", "a"])


def without_an_answer(monkeypatch, how: str):
    """Make every qpsolvers backend return no point (``"none"``), NaN, or raise."""
    solve_problem = qpsolvers.solve_problem

    def failing(problem, solver, **settings):
        if how == "raise":
            raise RuntimeError("the backend crashed")
        solution = solve_problem(problem, solver=solver, **settings)
        solution.x = None if how == "none" else np.full_like(solution.x, np.nan)
        return solution

    monkeypatch.setattr(qpsolvers, "solve_problem", failing)


def two_springs():
    return load_problem_file(EXAMPLES / "two_springs.toml").problem


@pytest.mark.parametrize("how", ["none", "nan", "raise"])
def test_qp_without_an_answer_raises_a_solver_error(monkeypatch, how):
    from contactqp.methods.qp import solve_qp

    without_an_answer(monkeypatch, how)
    with pytest.raises(SolverError, match="^qp backend 'clarabel' (found no solution|failed)"):
        solve_qp(two_springs(), backend="clarabel")


def test_qp_with_an_unproven_answer_returns_it_unsuccessful():
    from contactqp.methods.qp import solve_qp

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = solve_qp(two_springs(), backend="clarabel", max_iter=1)
    assert not result.success and "MaxIterations" in result.message
    assert np.all(np.isfinite(result.forces)) and np.all(np.isfinite(result.displacements))


@pytest.mark.parametrize("how", ["none", "nan", "raise"])
def test_polygonal_without_an_answer_raises_a_solver_error(monkeypatch, how):
    from contactqp.methods.polygonal import solve_polygonal

    problem = LocalProblem(np.diag([1.0, 2.0, 2.0]), [-1.0, 0.8, 0.0], [0.3], 3)
    assert solve_polygonal(problem).success
    without_an_answer(monkeypatch, how)
    with pytest.raises(SolverError, match="polygonal Tresca problem") as caught:
        solve_polygonal(problem)
    assert not isinstance(caught.value, InvalidInputError)


def test_tresca_without_an_answer_raises_a_solver_error(monkeypatch):
    import clarabel

    from contactqp.methods import tresca

    class NaNSolver:
        def __init__(self, P, q, *args):
            self.n = q.size

        def solve(self):
            return type("Solution", (), {"x": [np.nan] * self.n, "status": "NumericalError"})

    monkeypatch.setattr(clarabel, "DefaultSolver", NaNSolver)
    problem = LocalProblem(np.diag([1.0, 2.0, 2.0]), [-1.0, 0.8, 0.0], [0.3], 3)
    with pytest.raises(SolverError, match="Tresca cone program .status NumericalError"):
        tresca.solve_tresca_fixed_point(problem)


def run(*args) -> tuple[int, str, str]:
    """``contactqp ARGS`` in-process: (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with (
        contextlib.redirect_stdout(out),
        contextlib.redirect_stderr(err),
        warnings.catch_warnings(),
    ):
        warnings.simplefilter("ignore")
        status = main([str(arg) for arg in args])
    return status, out.getvalue(), err.getvalue()


def assert_one_line(status, err, expected_status, *needles):
    lines = err.strip().splitlines()
    assert status == expected_status, err
    assert len(lines) == 1 and lines[0].startswith("contactqp: error:"), err
    assert "Traceback" not in err
    for needle in needles:
        assert needle in lines[0], lines[0]


def qp_example(tmp_path, backend="clarabel", settings="") -> Path:
    """two_springs.toml solved by the qp solver with ``backend``."""
    shutil.copy(EXAMPLES / "two_springs_R.csv", tmp_path)
    text = (
        (EXAMPLES / "two_springs.toml")
        .read_text()
        .replace('name = "active-set"\ntol = 1e-12', f'name = "qp"\nbackend = "{backend}"')
    )
    target = tmp_path / "two_springs.toml"
    target.write_text(text + (f"\n[solver.backend_options]\n{settings}\n" if settings else ""))
    return target


def test_cli_exits_1_in_one_line_when_the_backend_finds_no_answer(tmp_path, monkeypatch):
    problem = qp_example(tmp_path)
    assert run("solve", problem)[0] == 0
    without_an_answer(monkeypatch, "none")
    status, _, err = run("solve", problem)
    assert_one_line(status, err, 1, "qp backend 'clarabel' found no solution")


def test_cli_exits_1_in_one_line_when_the_backend_crashes(tmp_path, monkeypatch):
    problem = qp_example(tmp_path)
    without_an_answer(monkeypatch, "raise")
    status, _, err = run("solve", problem)
    assert_one_line(status, err, 1, "RuntimeError: the backend crashed")


def test_cli_exits_1_when_the_backend_stops_short(tmp_path):
    status, out, err = run("solve", qp_example(tmp_path, settings="max_iter = 1"))
    assert_one_line(status, err, 1, "without claiming a solution")
    assert "nan" not in out.lower()


def test_cli_exits_2_in_one_line_for_an_unknown_backend(tmp_path):
    status, _, err = run("solve", qp_example(tmp_path, backend="no-such-qp"))
    assert_one_line(
        status, err, 2, "[solver].backend", "backend 'no-such-qp' is not installed", "available: "
    )


def test_fclib_exits_1_for_a_solver_error_and_2_for_bad_input(tmp_path, monkeypatch):
    import contactqp.methods

    good = FCLIB / "FrictionContact3D_1c.dat"
    if not good.exists():
        pytest.skip("FCLIB data not present")
    bad = tmp_path / "bad.dat"
    bad.write_text("not a problem\n")

    def no_answer(problem, **options):
        raise SolverError("the method found no answer")

    monkeypatch.setattr(contactqp.methods, "solve", no_answer)  # what the command calls
    status, _, err = run("fclib", good)
    assert_one_line(status, err, 1, "FrictionContact3D_1c.dat: the method found no answer")
    status, _, err = run("fclib", good, bad)
    assert status == 2 and len(err.strip().splitlines()) == 2, err


@pytest.mark.parametrize("backend", ["clarabel", "osqp", "quadprog"])
def test_a_setting_the_backend_refuses_is_bad_input_not_a_solver_error(backend):
    from contactqp.methods.polygonal import solve_polygonal
    from contactqp.methods.qp import solve_qp

    if backend not in qpsolvers.available_solvers:
        pytest.skip(f"{backend} not installed")
    with pytest.raises(InvalidInputError, match=f"^backend '{backend}' refuses foo = 1 "):
        solve_qp(two_springs(), backend=backend, foo=1)
    problem = LocalProblem(np.diag([1.0, 2.0, 2.0]), [-1.0, 0.8, 0.0], [0.3], 3)
    with pytest.raises(InvalidInputError, match=f"^backend '{backend}' refuses foo = 1 "):
        solve_polygonal(problem, backend=backend, foo=1)

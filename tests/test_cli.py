"""The command line, run as a user would: exit codes, one-line errors, JSON output."""

import json
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from contactqp.core.local_problem import LocalProblem, natural_map_error
from contactqp.io.fclib import read_problem, write_problem

ROOT = Path(__file__).resolve().parents[1]
FCLIB = ROOT.parent / "shared" / "data" / "fclib"


def run(*args):
    return subprocess.run(
        [sys.executable, "-m", "contactqp.cli", *args], capture_output=True, text=True, cwd=ROOT
    )


def assert_one_line_error(proc, code):
    assert proc.returncode == code, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("contactqp: error:"), proc.stderr
    assert "Traceback" not in proc.stderr


def test_springs_json_reproduces_the_published_table():
    proc = run(
        "springs",
        "--n",
        "3",
        "--stiffness",
        "1",
        "--mu",
        "0.2",
        "--mass",
        "2",
        "--g",
        "10",
        "--force",
        "3,6,9,14",
        "--json",
    )
    assert proc.returncode == 0, proc.stderr
    rows = [json.loads(line) for line in proc.stdout.splitlines()]
    assert [r["force"] for r in rows] == [3, 6, 9, 14]
    np.testing.assert_allclose(
        [r["x"] for r in rows], [[0, 0, 0], [0, 0, 2], [0, 1, 6], [2, 8, 18]], atol=1e-12
    )


def test_springs_plot_and_table(tmp_path):
    figure = tmp_path / "chain.png"
    proc = run("springs", "--plot", str(figure))
    assert proc.returncode == 0, proc.stderr
    assert "18" in proc.stdout and figure.stat().st_size > 1000


@pytest.mark.parametrize(
    "args",
    [
        ("springs", "--mu", "-1"),
        ("springs", "--force", "x"),
        ("springs", "--n", "0"),
        ("solve", "missing.toml"),
        ("fclib", "missing.hdf5"),
        ("nonsense",),
        ("springs", "--plot", "/tmp/contactqp-never-written.xyz"),  # no such figure format
        ("springs", "--plot", "/proc/none/chain.png"),  # unwritable
        ("solve", "examples/problems/two_springs.toml", "--out", "/proc/none"),
        ("layers", "--steps", "1"),
        ("riveting", "--samples", "-3", "--out", "/proc/none"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args):
    assert_one_line_error(run(*args), 2)


def test_solve_example_writes_results(tmp_path):
    proc = run("solve", "examples/problems/two_springs.toml", "--json", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert summary["success"] and summary["certificate"]["passed"]
    assert (tmp_path / "contacts.csv").exists() and (tmp_path / "summary.json").exists()


def frictionless_copy(source, target):
    problem = read_problem(source)
    write_problem(
        target, LocalProblem(problem.W, problem.q, np.zeros_like(problem.mu), problem.dim)
    )
    return target


def test_fclib_frictionless_problems_are_solved(tmp_path):
    # the shared files all have friction; their frictionless twins are solved to the README's
    # measure, recomputed here from the written solution (independent of the solver's report)
    files = [
        frictionless_copy(FCLIB / name, tmp_path / name.replace(".dat", ".hdf5"))
        for name in (
            "fc2d_granularflowonwall_02020_00213.dat",
            "Capsules-i122-1617.dat",
            "Spheres-i099-356-679.hdf5",
            "Rover1041.dat",
        )
    ]
    out = tmp_path / "solutions"
    proc = run("fclib", *map(str, files), "--json", "--solution-dir", str(out))
    assert proc.returncode == 0, proc.stderr
    rows = [json.loads(line) for line in proc.stdout.splitlines()]
    assert [r["contacts"] for r in rows] == [2020, 296, 356, 5]
    for path, row in zip(files, rows, strict=True):
        assert row["converged"] and row["error"] <= 1e-8
        with h5py.File(out / f"{path.name}.solution.hdf5") as solution:
            r, u = solution["solution/r"][()], solution["solution/u"][()]
        assert natural_map_error(read_problem(path), r, u) <= 1e-8


def test_fclib_solves_every_shared_file_with_friction(tmp_path):
    files = sorted(p for p in FCLIB.iterdir() if p.suffix in (".dat", ".hdf5"))
    assert len(files) == 23
    out = tmp_path / "solutions"
    proc = run("fclib", *map(str, files), "--json", "--solution-dir", str(out))
    assert proc.returncode == 0, proc.stderr
    rows = [json.loads(line) for line in proc.stdout.splitlines()]
    assert [Path(r["file"]).name for r in rows] == [p.name for p in files]
    for path, row in zip(files, rows, strict=True):
        assert row["converged"] and row["error"] <= 1e-8
        assert row["open"] + row["stick"] + row["slip"] == row["contacts"]
        with h5py.File(out / f"{path.name}.solution.hdf5") as solution:
            r, u = solution["solution/r"][()], solution["solution/u"][()]
        problem = read_problem(path)
        # the README's measure, recomputed here: from the written (r, u) and from r alone
        assert natural_map_error(problem, r, u) <= 1e-8
        assert natural_map_error(problem, r) <= 1e-8


def test_fclib_unsolvable_problem_says_why_and_keeps_other_results(tmp_path):
    # W = 0 with q_N < 0: no reaction closes the contact, the problem has no solution
    hopeless = tmp_path / "hopeless.hdf5"
    write_problem(hopeless, LocalProblem(np.zeros((3, 3)), [-1.0, 0.5, 0.0], [0.3], 3))
    out = tmp_path / "solutions"
    proc = run(
        "fclib", str(hopeless), str(FCLIB / "Rover4516.dat"), "--json", "--solution-dir", str(out)
    )
    assert_one_line_error(proc, 1)
    assert "hopeless.hdf5" in proc.stderr and "not converged" in proc.stderr
    bad, good = [json.loads(line) for line in proc.stdout.splitlines()]
    assert not bad["converged"] and bad["error"] > 1e-8
    assert f"{bad['error']:.2e}" in proc.stderr
    assert good["converged"]
    assert sorted(p.name for p in out.iterdir()) == ["Rover4516.dat.solution.hdf5"]


def test_fclib_bad_problems_exit_2(tmp_path):
    indefinite = tmp_path / "indefinite.hdf5"
    W = np.array([[1.0, 0, 0], [0, 1.0, 2.0], [0, 2.0, 1.0]])
    write_problem(indefinite, LocalProblem(W, [-1.0, 0.0, 0.0], [0.3], 3))
    proc = run("fclib", str(indefinite))
    assert_one_line_error(proc, 2)
    assert "not positive semidefinite" in proc.stderr
    for name, values in (("mu", [-0.3]), ("q", [np.nan, 0.0, 0.0])):
        path = tmp_path / f"bad_{name}.hdf5"
        write_problem(path, LocalProblem(np.eye(3), [-1.0, 0.0, 0.0], [0.3], 3))
        with h5py.File(path, "a") as fh:
            fh[f"fclib_local/vectors/{name}"][...] = values
        proc = run("fclib", str(path))
        assert_one_line_error(proc, 2)
        assert f"bad_{name}.hdf5" in proc.stderr and name in proc.stderr
    missing = str(tmp_path / "missing.hdf5")
    proc = run("fclib", missing)
    assert_one_line_error(proc, 2)
    assert proc.stderr.count(missing) == 1, proc.stderr  # the file named once


def test_a_figure_leaves_the_users_matplotlib_state_alone(tmp_path):
    # a notebook user's backend and pyplot figures must survive a figure drawn by contactqp
    script = f"""
import sys
import matplotlib
matplotlib.use("svg")
from contactqp.io.plot import plot_spring_chain
from contactqp.applications.springs import SpringChain
chain = SpringChain(n=3, stiffness=1.0, mu=0.2, mass=2.0, g=10.0)
results = [chain.solve(f) for f in (3.0, 14.0)]
forces, displacements = [r.force for r in results], [r.x for r in results]
plot_spring_chain(forces, displacements, {str(tmp_path / "chain.png")!r})
print(matplotlib.get_backend(), "matplotlib.pyplot" in sys.modules)
"""
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["svg", "False"]
    assert (tmp_path / "chain.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_version_has_one_source():
    from importlib.metadata import version

    import contactqp

    proc = run("--version")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split()[-1] == contactqp.__version__ == version("contactqp")


def test_fclib_table_written_to_a_pipe_keeps_every_figure():
    # rich cuts a table to 80 columns off a terminal; the figures must survive in full
    path = FCLIB / "FC3D_Example1.dat"
    table = run("fclib", str(path))
    data = run("fclib", str(path), "--json")
    assert table.returncode == 0 and data.returncode == 0, table.stderr + data.stderr
    row = json.loads(data.stdout)
    assert "…" not in table.stdout
    line = next(line for line in table.stdout.splitlines() if path.name in line)
    cells = [cell.strip() for cell in line.strip("│ ").split("│")]
    assert cells[0] == path.name and int(cells[2]) == row["contacts"] == 3
    assert cells[3] == str(row["converged"])
    assert abs(float(cells[4]) - row["error"]) <= 0.01 * row["error"]
    assert sum(map(int, cells[7:10])) == 3


TABLE_BOX = set("─━│┃┏┓┗┛┡┩┣┫┳┻╇╋└┘┌┐├┤┬┴┼╸╺╹╻ \n")


def test_a_figures_table_folds_its_cells_in_a_narrow_console_and_keeps_every_character():
    """rich cuts a cell to an ellipsis when a table is wider than the console; a figures table
    folds it onto more lines: at 40 columns it holds the characters it holds at 200."""
    import io

    from rich.console import Console

    from contactqp.cli.app import figures_table

    rows = [("sample-with-a-long-name", "-1.000000123456789e-03", "7.25e-08", "0.4860000001")] * 3
    printed = []
    for width in (40, 200):
        table = figures_table("a title", ("name", "uy (mm)", "eps (%)", "force (N)"), left="name")
        for row in rows:
            table.add_row(*row)
        out = io.StringIO()
        Console(file=out, width=width).print(table)
        printed.append(out.getvalue())
    narrow, wide = ([c for c in text if c not in TABLE_BOX] for text in printed)
    assert "…" not in printed[0] and len(printed[0]) > len(printed[1])
    assert sorted(narrow) == sorted(wide)
    assert max(len(line) for line in printed[0].splitlines()) <= 40


@pytest.mark.parametrize(
    "argv",
    [
        ["rod"],
        ["methods"],
        ["layers"],
        ["riveting"],
        ["rough"],
        ["springs", "--n", "9", "--stiffness", "1", "--mu", "0.2", "--mass", "2", "--force", "3,9"],
        ["fclib", str(FCLIB / "FC3D_Example1.dat")],
    ],
    ids=lambda argv: argv[0],
)
def test_command_tables_in_a_narrow_terminal_show_no_ellipsis(argv, capsys, monkeypatch, tmp_path):
    """Every command's table, 60 columns wide: no cell cut to an ellipsis, no line wider."""
    from contactqp.cli import app, main

    monkeypatch.setattr(app, "PIPED_WIDTH", 60)
    if argv[0] == "riveting":
        argv = [*argv, "--out", str(tmp_path)]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "│" in printed and "…" not in printed
    assert max(len(line) for line in printed.splitlines()) <= 60

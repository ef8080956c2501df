"""Start-up of the package and the command line: nothing heavy is imported before it is used.

The checks read ``sys.modules`` in a fresh interpreter (never a timing): importing
:mod:`contactqp` and building the command group must not import the optional packages
(plotting, HDF5, finite elements, task graphs, QP backends), and ``contactqp --help`` must list
every command from the lazy table without importing numpy or any command's module.
"""

import json
import subprocess
import sys
from pathlib import Path

import click

import contactqp
from contactqp.cli import app

ROOT = Path(__file__).resolve().parents[1]
CLI_FOLDER = ROOT / "src" / "contactqp" / "cli"

#: Imported only by the code that uses them.
HEAVY = ("matplotlib", "h5py", "skfem", "dask", "qpsolvers", "meshio", "rich", "pandas")


def imported_after(code: str) -> set[str]:
    """The top-level packages in ``sys.modules`` after running ``code`` in a new interpreter."""
    probe = (
        f"{code}\nimport json, sys\n"
        "print(json.dumps(sorted({name.split('.')[0] for name in sys.modules})))"
    )
    proc = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT, check=True
    )
    return set(json.loads(proc.stdout.splitlines()[-1]))


def test_importing_the_package_and_the_command_group_imports_nothing_heavy():
    loaded = imported_after("import contactqp\nfrom contactqp.cli import cli, main")
    assert "contactqp" in loaded and "click" in loaded
    assert not loaded & {*HEAVY, "numpy", "scipy"}, sorted(loaded & {*HEAVY, "numpy", "scipy"})


def test_the_public_api_imports_no_optional_package():
    # every public name resolved (numpy comes in), still no optional package
    code = "import contactqp\nfor name in contactqp.__all__: getattr(contactqp, name)"
    loaded = imported_after(code)
    assert "numpy" in loaded
    assert not loaded & set(HEAVY), sorted(loaded & set(HEAVY))


def test_the_help_lists_every_command_without_importing_them():
    code = (
        "import contextlib, io, sys\n"
        "from contactqp.cli import main\n"
        "out = io.StringIO()\n"
        "with contextlib.redirect_stdout(out): status = main(['--help'])\n"
        "assert status == 0, status\n"
        "names = [n for n in sys.modules if n.startswith('contactqp.cli.')]\n"
        "names.remove('contactqp.cli.app')\n"
        "assert not names, names\n"
        "print(out.getvalue(), file=sys.stderr)"
    )
    loaded = imported_after(code)
    assert "numpy" not in loaded
    proc = subprocess.run(
        [sys.executable, "-m", "contactqp.cli", "--help"], capture_output=True, text=True, cwd=ROOT
    )
    assert proc.returncode == 0, proc.stderr
    listed = proc.stdout.split("Commands:", 1)[1].split()
    for name in app.COMMANDS:
        assert name in listed, name


def test_the_lazy_table_matches_the_commands_own_help():
    context = click.Context(app.cli, info_name="contactqp")
    for name, (_, line) in app.COMMANDS.items():
        command = app.cli.get_command(context, name)
        assert isinstance(command, click.Command) and command.name == name
        assert command.get_short_help_str(limit=10**6) == line, name


def test_every_command_module_is_in_the_lazy_table():
    modules = {path.stem for path in CLI_FOLDER.glob("*.py")} - {"__init__", "__main__", "app"}
    assert modules == {module for module, _ in app.COMMANDS.values()}


def test_every_public_name_resolves_to_what_its_module_defines():
    exported = set(contactqp.__all__) - {"solve_gaps"}
    assert exported == set(contactqp._EXPORTS)
    for name in exported:
        assert getattr(contactqp, name) is getattr(
            __import__(f"contactqp{contactqp._EXPORTS[name]}", fromlist=[name]), name
        )
    assert contactqp.methods.__name__ == "contactqp.methods"


def test_a_dense_problem_is_read_and_solved_without_scipy():
    # scipy costs a third of a second to import (its array-API layer pulls in numpy.testing and
    # f2py): a dense local problem, from a file or from arrays, never needs it
    shared = ROOT.parent / "shared" / "data" / "fclib" / "FC3D_Example1.dat"
    code = (
        "import contextlib, io, numpy as np\n"
        "from contactqp.cli import main\n"
        "import contactqp as cq\n"
        "out = io.StringIO()\n"
        f"with contextlib.redirect_stdout(out): status = main(['fclib', {str(shared)!r}])\n"
        "assert status == 0, status\n"
        "W = np.array([[2.0, 0.1, 0.0], [0.1, 1.0, 0.0], [0.0, 0.0, 1.0]])\n"
        "result = cq.solve(cq.LocalProblem(W, np.array([-1.0, 0.3, 0.0]), np.array([0.5]), 3))\n"
        "assert result.success and list(result.status_labels) == ['slip'], result\n"
        "assert result.certificate.natural_map <= 1e-8, result.certificate\n"
    )
    loaded = imported_after(code)
    assert "numpy" in loaded and "contactqp" in loaded
    assert "scipy" not in loaded

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
    # every public name resolved (numpy and scipy come in), still no optional package
    code = "import contactqp\nfor name in contactqp.__all__: getattr(contactqp, name)"
    loaded = imported_after(code)
    assert {"numpy", "scipy"} <= loaded
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

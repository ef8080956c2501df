"""The build: without a C compiler, ``pip install`` still gives a working (slower) package.

Truths used: ``CC=false`` is a compiler that fails every compilation, as a missing one does; a
package built so must import, say which kernels it uses, and solve.
"""

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import setuptools.command.build_ext
from setuptools import Distribution
from setuptools.errors import CompileError

ROOT = Path(__file__).resolve().parents[1]


def setup_module_of_the_project():
    """``setup.py`` as a module (its ``setup()`` call runs only as ``__main__``)."""
    spec = importlib.util.spec_from_file_location("contactqp_setup", ROOT / "setup.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_build_ext_leaves_out_an_extension_it_cannot_compile(monkeypatch, capsys):
    project = setup_module_of_the_project()
    built = []

    def build_extension(self, ext):
        if ext.name == project.KERNELS.name:
            raise CompileError("command 'cc' failed: No such file or directory")
        built.append(ext.name)

    monkeypatch.setattr(setuptools.command.build_ext.build_ext, "build_extension", build_extension)
    other = setuptools.Extension("contactqp.other", ["other.c"])
    command = project.OptionalBuildExt(
        Distribution({"name": "contactqp", "ext_modules": [project.KERNELS, other]})
    )
    command.ensure_finalized()
    command.build_extensions()
    assert built == ["contactqp.other"] and command.extensions == [other]
    warning = capsys.readouterr().err
    assert "contactqp.kernels.compiled not built (CompileError: command 'cc' failed" in warning
    assert "pure-numpy kernels" in warning


def test_build_ext_fails_on_what_is_not_a_build_failure(monkeypatch):
    project = setup_module_of_the_project()

    def build_extension(self, ext):
        raise KeyError("a bug, not a missing compiler")

    monkeypatch.setattr(setuptools.command.build_ext.build_ext, "build_extension", build_extension)
    command = project.OptionalBuildExt(
        Distribution({"name": "contactqp", "ext_modules": [project.KERNELS]})
    )
    command.ensure_finalized()
    with pytest.raises(KeyError):
        command.build_extensions()


def copy_of_the_project(target: Path) -> Path:
    """The files a source build reads, without the products of an earlier build."""
    target.mkdir()
    for name in ("pyproject.toml", "setup.py", "README.md"):
        shutil.copy(ROOT / name, target / name)
    shutil.copytree(
        ROOT / "src" / "contactqp",
        target / "src" / "contactqp",
        ignore=shutil.ignore_patterns("*.so", "*.pyd", "*.c", "__pycache__"),
    )
    return target


def test_pip_install_without_a_compiler_gives_a_working_package(tmp_path):
    # the command the README gives: CC=false pip install --no-deps --target DIR .
    source = copy_of_the_project(tmp_path / "source")
    installed = tmp_path / "installed"
    build = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "-v",
            "--no-deps",
            "--target",
            str(installed),
            str(source),
        ],
        capture_output=True,
        text=True,
        cwd=source,
        timeout=300,
        env={**os.environ, "CC": "false", "PIP_DISABLE_PIP_VERSION_CHECK": "1"},
    )
    log = build.stdout + build.stderr
    if build.returncode and "No matching distribution" in log:
        pytest.skip("pip cannot fetch the build requirements here (offline)")
    assert build.returncode == 0, log[-3000:]
    assert "WARNING: contactqp.kernels.compiled not built" in log
    assert not list((installed / "contactqp" / "kernels").glob("compiled*.so"))
    # the annotations ship for users' type checkers, the compiled kernels' stub among them
    assert (installed / "contactqp" / "py.typed").is_file()
    assert (installed / "contactqp" / "kernels" / "compiled.pyi").is_file()
    check = subprocess.run(
        [
            sys.executable,
            "-W",
            "always",
            "-c",
            "import numpy as np, contactqp.kernels as k\n"
            "from contactqp.core.local_problem import LocalProblem\n"
            "from contactqp.methods.coulomb import solve_coulomb\n"
            "s = solve_coulomb(LocalProblem(np.diag([1.0, 2.0]), [-1.0, 0.8], [0.3], 2))\n"
            "print(k.IMPLEMENTATION, s.success, k.__file__)",
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
        env={**os.environ, "PYTHONPATH": str(installed), "CONTACTQP_PURE_NUMPY": ""},
    )
    assert check.returncode == 0, check.stderr
    implementation, converged, where = check.stdout.split()
    assert (implementation, converged) == ("pure_numpy", "True")
    assert Path(where).is_relative_to(installed)
    assert check.stderr.count("PureNumpyKernelsWarning") == 1

"""The documentation site (``make docs``, built by ``make test``) stays whole.

Sphinx itself fails the build on any warning; these tests check what it cannot: that the
registry page is generated from the registry (every method, option and kind on it), that every
example of the gallery is either run by the build or by a test, that the API reference reaches
every public subpackage, and that the README, the Makefile and the extras point at the site.
"""

from __future__ import annotations

import ast
import importlib.util
import pkgutil
import re
import tomllib
from pathlib import Path

import contactqp
from contactqp.methods import registry

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
EXAMPLES = ROOT / "examples"


def load_extension(name: str):
    spec = importlib.util.spec_from_file_location(name, DOCS / "_ext" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def conf_value(name: str):
    """The literal value assigned to ``name`` in docs/conf.py (read, not run)."""
    for node in ast.parse((DOCS / "conf.py").read_text(encoding="utf-8")).body:
        if isinstance(node, ast.Assign) and any(
            isinstance(target, ast.Name) and target.id == name for target in node.targets
        ):
            return ast.literal_eval(node.value)
    raise AssertionError(f"docs/conf.py assigns no {name}")


def test_the_registry_page_is_generated_from_the_registry():
    assert ".. method-registry::" in (DOCS / "methods.rst").read_text(encoding="utf-8")
    text = "\n".join(load_extension("registry_page").registry_rst())
    sections = re.split(r"\n``([a-z-]+)``\n-+\n", text)
    kinds_table, methods = sections[0], dict(zip(sections[1::2], sections[2::2], strict=True))
    assert list(methods) == list(registry.METHODS)
    for name, method in registry.METHODS.items():
        section = methods[name]
        assert method.role in section and method.function.__name__ in section
        assert (method.extra or "none (core)") in section
        options = re.findall(r"^   \* - ``(\w+)``$", section, flags=re.M)
        assert options == list(method.option_names), name
        for option in method.options:
            assert option.doc in section
    for kind in registry.KINDS.values():
        row = kinds_table.split(f"   * - ``{kind.name}``\n", 1)[1].split("   * - ", 1)[0]
        assert f"``{kind.default}``" in row
        for method in registry.methods_for(kind.name):
            assert f"``{method.name}``" in row


def test_every_command_named_on_the_application_pages_has_its_help():
    help_text = load_extension("registry_page").command_help
    for page in sorted((DOCS / "applications").glob("*.md")):
        for name in re.findall(r"```\{command-help\} (\w+)", page.read_text(encoding="utf-8")):
            assert help_text(name).startswith(f"Usage: contactqp {name} ")


def test_every_gallery_example_is_run_by_the_build_or_by_a_test():
    executed = set(conf_value("GALLERY_EXECUTED"))
    scripts = {path.stem for path in EXAMPLES.glob("*.py")}
    assert executed <= scripts, "docs/conf.py runs an example that does not exist"
    tests = "\n".join(path.read_text(encoding="utf-8") for path in ROOT.glob("tests/test_*.py"))
    for name in sorted(scripts - executed):
        assert re.search(rf"\b{name}\b", tests), f"examples/{name}.py is neither run nor tested"
    for name in sorted(scripts):  # the gallery takes its title from the docstring's heading
        lines = ast.get_docstring(ast.parse((EXAMPLES / f"{name}.py").read_text())).splitlines()
        titled = len(lines) > 1 and set(lines[1]) == {"="} and len(lines[1]) >= len(lines[0])
        assert titled, f"examples/{name}.py: underline the docstring's first line with '='"


def test_the_api_reference_reaches_every_public_module():
    pages = load_extension("api_pages")
    listed = re.findall(
        r"^   generated/(contactqp[\w.]*)$", (DOCS / "api" / "index.rst").read_text(), re.M
    )
    assert listed == list(pages.PACKAGES)
    public = {
        f"contactqp.{module.name}"
        for module in pkgutil.iter_modules(contactqp.__path__)
        if not module.name.startswith("_")
    }
    # the command line is documented by its commands' help on the application pages
    assert set(listed) == {"contactqp"} | (public - {"contactqp.cli"})
    source = ROOT / "src"
    for package in listed[1:]:
        text = pages.page(package)
        folder = source / package.replace(".", "/")
        files = (
            sorted(folder.rglob("*.py")) + sorted(folder.rglob("*.pyx")) if folder.is_dir() else []
        )
        for path in files:
            parts = path.relative_to(source).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            if any(part.startswith("_") for part in parts):
                continue
            name = ".".join(parts)
            assert f"\n.. automodule:: {name}\n" in f"\n{text}", name


def test_readme_keeps_the_two_commands_on_top_and_points_at_the_site():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    first_block = readme.split("```sh\n", 1)[1].split("```", 1)[0]
    assert first_block.splitlines()[0].startswith("make demo")
    assert first_block.splitlines()[1].startswith("make test")
    assert "make docs" in readme and "docs/_build/html/index.html" in readme


def test_make_test_builds_the_site_offline_with_warnings_as_errors():
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    assert re.search(r"^test: .*\bdocs\b", makefile, re.M)
    build = re.search(r"^docs: .*\n\t(.*)$", makefile, re.M).group(1)
    assert "sphinx-build" in build and "-W" in build and "--keep-going" in build
    assert " -n " in build  # nitpicky: every reference resolves
    assert "sphinx.ext.intersphinx" not in (DOCS / "conf.py").read_text(encoding="utf-8")
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"
    ]
    assert "docs" in extras["test"][0].split("[", 1)[1]
    for requirement in extras["docs"][1:]:  # pinned to a range, like the linters
        assert re.fullmatch(r"[\w-]+>=[\w.]+,<[\w.]+", requirement), requirement

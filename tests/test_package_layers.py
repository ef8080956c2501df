"""The package's layers, read from its imports: no circles, no import from a lower layer upwards.

errors, optional, kernels -> core -> methods, compliance -> io, studies -> applications -> cli.
Every import counts, those inside functions too: a lazy import is still a dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "contactqp"

#: Layer of each top-level part of the package; a module may import its own layer and below.
LAYERS = {
    "errors": 0,
    "optional": 0,
    "kernels": 0,
    "core": 1,
    "methods": 2,
    "compliance": 2,
    "io": 3,
    "studies": 3,
    "applications": 4,
    "cli": 5,
}


def _modules() -> dict[str, Path]:
    """Dotted name -> file, for every module of the package (packages by their __init__)."""
    modules = {}
    for path in PACKAGE.rglob("*.py"):
        parts = ("contactqp",) + path.relative_to(PACKAGE).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = path
    for path in PACKAGE.rglob("*.pyx"):  # a compiled module has a name too
        modules[".".join(("contactqp",) + path.relative_to(PACKAGE).with_suffix("").parts)] = path
    return modules


MODULES = _modules()


def _imports(name: str, path: Path) -> set[str]:
    """The package's modules that module ``name`` imports, anywhere in its body."""
    if path.suffix != ".py":
        return set()
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            # `from . import kernels` imports the module contactqp.kernels
            targets = [
                f"{module}.{alias.name}" if f"{module}.{alias.name}" in MODULES else module
                for alias in node.names
            ]
        else:
            continue
        found.update(target for target in targets if target.split(".")[0] == "contactqp")
    found.discard(name)
    return found


GRAPH = {name: _imports(name, path) for name, path in MODULES.items()}


def _layer(name: str) -> int | None:
    """The layer of a module; None for the facade ``contactqp`` itself."""
    parts = name.split(".")
    return LAYERS[parts[1]] if len(parts) > 1 else None


def test_every_part_of_the_package_has_a_layer():
    unplaced = sorted({name.split(".")[1] for name in MODULES if "." in name} - set(LAYERS))
    assert not unplaced, f"parts of the package without a layer in LAYERS: {unplaced}"


def test_the_facade_is_imported_by_nothing_inside_the_package():
    users = sorted(name for name, targets in GRAPH.items() if "contactqp" in targets)
    assert not users, f"modules importing the package's facade (contactqp/__init__.py): {users}"


def test_no_import_runs_from_a_lower_layer_upwards():
    upward = [
        f"{name} (layer {_layer(name)}) imports {target} (layer {_layer(target)})"
        for name, targets in sorted(GRAPH.items())
        if _layer(name) is not None
        for target in sorted(targets)
        if _layer(target) is not None and _layer(target) > _layer(name)
    ]
    assert not upward, "imports from a lower layer into a higher one:\n" + "\n".join(upward)


def _circle() -> list[str] | None:
    """One import circle among the package's modules, or None (depth-first search)."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(name):
        state[name] = 1
        path.append(name)
        for target in sorted(GRAPH.get(name, ())):
            if state.get(target) == 1:
                return path[path.index(target) :] + [target]
            if target not in state and (found := visit(target)):
                return found
        state[name] = 2
        path.pop()
        return None

    for name in sorted(GRAPH):
        if name not in state and (found := visit(name)):
            return found
    return None


def test_no_import_circle():
    circle = _circle()
    assert circle is None, "import circle: " + " -> ".join(circle)


@pytest.mark.parametrize(
    "source, circle",
    [
        ({"a": {"b"}, "b": {"c"}, "c": {"a"}}, ["a", "b", "c", "a"]),
        ({"a": {"b"}, "b": set(), "c": {"b"}}, None),
    ],
)
def test_the_circle_search_finds_circles(monkeypatch, source, circle):
    monkeypatch.setattr(f"{__name__}.GRAPH", source)
    assert _circle() == circle


def test_the_import_reader_sees_lazy_and_relative_imports(tmp_path):
    module = tmp_path / "m.py"
    module.write_text(
        "from ..errors import InvalidInputError\n"
        "def f():\n    from ..methods import registry\n    from .. import kernels\n"
    )
    found = _imports("contactqp.core.m", module)
    assert {"contactqp.errors", "contactqp.kernels"} <= found
    assert any(name.startswith("contactqp.methods") for name in found)

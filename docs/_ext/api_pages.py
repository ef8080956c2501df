"""The API reference pages, written from the package's structure when the build starts.

One page per public subpackage (:data:`PACKAGES`), each with every module under it found by
:func:`pkgutil.walk_packages` (private ``_name`` modules and ``__main__`` left out): the
package's docstring and a table of what its ``__all__`` exports, then each module's docstring
and every public name it defines. Each object is documented once, where it is defined; the
names it is imported by link there (see ``resolve_names``). A module added to the package
appears without editing any page.
"""

from __future__ import annotations

import importlib
import pkgutil
import types
from pathlib import Path

#: The pages of the reference, in order: the facade, then the layers from the bottom up.
PACKAGES = (
    "contactqp",
    "contactqp.errors",
    "contactqp.optional",
    "contactqp.kernels",
    "contactqp.core",
    "contactqp.methods",
    "contactqp.compliance",
    "contactqp.io",
    "contactqp.studies",
    "contactqp.applications",
)


def _modules(package: str) -> list[str]:
    """``package``'s public modules, depth first (the facade has none of its own here)."""
    module = importlib.import_module(package)
    if package == "contactqp" or not hasattr(module, "__path__"):
        return []
    found = pkgutil.walk_packages(module.__path__, prefix=package + ".")
    names = [info.name for info in found]
    return [name for name in names if not any(part.startswith("_") for part in name.split("."))]


def _heading(text: str, mark: str) -> list[str]:
    return [text, mark * len(text), ""]


def _is_alias(value) -> bool:
    """A type alias (``Record = dict[str, Any]``): described by its module's docstring, not
    documented as an object (autodoc takes it for a class it cannot import)."""
    return isinstance(value, types.GenericAlias | types.UnionType)


def _automodule(name: str) -> list[str]:
    module = importlib.import_module(name)
    lines = [f".. automodule:: {name}", "   :members:", "   :ignore-module-all:"]
    aliases = [key for key, value in vars(module).items() if _is_alias(value)]
    if aliases:
        lines.append(f"   :exclude-members: {', '.join(aliases)}")
    lines.append("")
    exported = [
        item for item in getattr(module, "__all__", ()) if not _is_alias(getattr(module, item))
    ]
    defined_elsewhere = [
        item for item in exported if getattr(getattr(module, item), "__module__", name) != name
    ]
    if defined_elsewhere:
        lines += [".. rubric:: Exports", "", ".. autosummary::", ""]
        lines += [f"   {item}" for item in exported]
        lines.append("")
    return lines


def page(package: str) -> str:
    """The reST of ``package``'s page."""
    lines = _heading(package, "=") + _automodule(package)
    for name in _modules(package):
        lines += _heading(name, "-") + _automodule(name)
    return "\n".join(lines)


def write_pages(app) -> None:
    folder = Path(app.srcdir) / "api" / "generated"
    folder.mkdir(parents=True, exist_ok=True)
    for package in PACKAGES:
        target = folder / f"{package}.rst"
        text = page(package)
        if not target.exists() or target.read_text(encoding="utf-8") != text:
            target.write_text(text, encoding="utf-8")  # unchanged pages are not reread


def setup(app):
    app.connect("builder-inited", write_pages)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}

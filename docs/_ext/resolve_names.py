"""Resolve a Python reference to where its object is documented.

The API pages document each object once, in the module that defines it. Docstrings also name
objects by the names users import (``contactqp.solve``, ``contactqp.ReducedModel``), by a
subclass that inherits them (``FrictionalResult.summary``), or relative to the module or class
they are written in. When Sphinx finds no entry for such a name, this extension imports it,
finds the object's defining module and class, and links to that entry. A name that leads to no
documented object stays unresolved, and the nitpicky build fails on it as before.

Fallbacks: an attribute that has no entry of its own (a field or instance attribute, listed in
its class's docstring) links to its class; module data without an entry links to the module
that assigns it; a bare name imported inside a function
(``RigidBodyModeError``) links to the one documented object of that name, if there is exactly
one.
"""

from __future__ import annotations

import importlib
import inspect
import sys

from sphinx.util.nodes import make_refnode


def _lookup(dotted: str):
    """The object called ``dotted`` (module path, then attributes), or None."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            value = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        try:
            for name in parts[cut:]:
                value = (
                    inspect.getattr_static(value, name)
                    if inspect.isclass(value)
                    else (getattr(value, name))
                )
        except AttributeError:
            return None
        return value
    return None


def _canonical(dotted: str) -> list[str]:
    """Names under which the object ``dotted`` may be documented, best first: where it is
    defined; for a class member without an entry of its own, its class."""
    parts = dotted.split(".")
    names, fallback = [], []
    owner = _lookup(".".join(parts[:-1])) if len(parts) > 1 else None
    if inspect.isclass(owner):  # a member: documented on the class of the MRO defining it
        for klass in inspect.getmro(owner):
            defines = parts[-1] in vars(klass) or parts[-1] in vars(klass).get(
                "__annotations__", {}
            )
            if defines:
                names.append(f"{klass.__module__}.{klass.__qualname__}.{parts[-1]}")
                break
        # an instance attribute or field, described by its class's docstring
        fallback.append(f"{owner.__module__}.{owner.__qualname__}")
    value = _lookup(dotted)
    module, qualname = getattr(value, "__module__", None), getattr(value, "__qualname__", None)
    if isinstance(module, str) and isinstance(qualname, str):
        names.append(f"{module}.{qualname}")
    if inspect.ismodule(owner) and not (inspect.isclass(value) or inspect.isroutine(value)):
        # module data re-exported by a package: documented in the module that assigns it
        homes = _data_homes(owner, parts[-1], value)
        names.extend(homes)
        # data without an entry of its own: the module that assigns it
        fallback.extend(home.rsplit(".", 1)[0] for home in homes)
    return names + fallback


def _data_homes(package, name: str, value) -> list[str]:
    """Modules of the project (already imported) other than ``package`` that hold the same
    ``value`` under ``name``."""
    prefix = package.__name__.split(".")[0] + "."
    return [
        f"{module_name}.{name}"
        for module_name, module in list(sys.modules.items())
        if module_name.startswith(prefix)
        and module is not package
        and getattr(module, name, None) is value
    ]


def resolve(app, env, node, contnode):
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"]
    module, klass = node.get("py:module"), node.get("py:class")
    candidates = [target]
    if klass and module:
        candidates.append(f"{module}.{klass}.{target}")
    if module:
        candidates.append(f"{module}.{target}")
    domain = env.get_domain("py")
    names = [name for candidate in candidates for name in _canonical(candidate)]
    if "." not in target:  # imported inside a function: the one entry of that name
        matches = [name for name in domain.objects if name.endswith("." + target)]
        names += matches if len(matches) == 1 else []
    for name in names:
        entry = domain.objects.get(name) or domain.modules.get(name)
        if entry is not None:
            return make_refnode(
                app.builder, node["refdoc"], entry.docname, entry.node_id, contnode, name
            )
    return None


def setup(app):
    app.connect("missing-reference", resolve)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}

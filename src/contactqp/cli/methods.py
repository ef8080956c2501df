"""``contactqp methods``: the registered methods, what they solve and whether they are installed."""

from __future__ import annotations

import json

import click

from .app import console, figures_table


def _describe(method, installed: bool) -> dict:
    """A JSON-ready description of a registered method."""
    return {
        "name": method.name,
        "kinds": list(method.kinds),
        "role": method.role,
        "extra": method.extra,
        "installed": installed,
        "summary": method.summary,
        "backend_settings": method.backend_settings,
        "options": [
            {"name": o.name, "type": o.type.__name__, "default": o.default, "doc": o.doc}
            for o in method.options
        ],
    }


@click.command()
@click.option("--json", "as_json", is_flag=True, help="One JSON object: methods and kinds.")
def methods(as_json):
    """List the methods: the problem kinds they solve, their role and options, what is installed.

    A kind's default method comes first in its list (see `contactqp methods --json`, "kinds").
    """
    from ..methods.registry import KINDS, METHODS, is_installed

    described = [_describe(m, is_installed(m.name)) for m in METHODS.values()]
    if as_json:
        kinds = [
            {
                "name": k.name,
                "problem": k.problem,
                "default": k.default,
                "defaults": dict(k.defaults),
                "fixed": list(k.fixed),
            }
            for k in KINDS.values()
        ]
        click.echo(json.dumps({"methods": described, "kinds": kinds}))
        return
    _table(described, KINDS)


def _table(described, kinds):
    columns = ("method", "kinds", "role", "extra", "installed", "options")
    table = figures_table("contactqp methods", columns, left=columns)
    defaults: dict[str, set[str]] = {k.default: set() for k in kinds.values()}
    for k in kinds.values():
        defaults[k.default].add(k.name)
    for m in described:
        kinds_text = ", ".join(
            f"{k} (default)" if k in defaults.get(m["name"], ()) else k for k in m["kinds"]
        )
        options = "\n".join(
            f"{o['name']}: {o['type']} = {o['default']!r}  {o['doc']}" for o in m["options"]
        )
        if m["backend_settings"]:
            options += "\n(further keywords go to the qpsolvers backend)"
        table.add_row(
            f"{m['name']}\n{m['summary']}",
            kinds_text,
            m["role"],
            m["extra"] or "-",
            "yes" if m["installed"] else "no",
            options or "-",
        )
    console().print(table)

"""Pages generated from the code at build time: the method registry and the commands' help.

``.. method-registry::`` writes the method registry's tables.

Everything is read from :mod:`contactqp.methods.registry` when the page is built (the problem
kinds with their default methods and option defaults, then each method with its kinds, role,
extra and options), so the page cannot drift from the code. :func:`registry_rst` gives the
reStructuredText the directive parses; the docs tests read it too.

``.. command-help:: NAME`` writes the ``--help`` text of ``contactqp NAME``, as the command
prints it.
"""

from __future__ import annotations

import click
from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

from contactqp.cli import cli
from contactqp.methods import registry


def _literal(value: object) -> str:
    """``value`` as inline literal text: ``repr`` for values, the type's name for types."""
    text = value.__name__ if isinstance(value, type) else repr(value)
    return "``" + text.replace("`", "'") + "``"


def _table(header: tuple[str, ...], rows: list[tuple[str, ...]]) -> list[str]:
    """A reST list-table."""
    lines = [".. list-table::", "   :header-rows: 1", ""]
    for row in (header, *rows):
        lines.append(f"   * - {row[0]}")
        lines.extend(f"     - {cell}" for cell in row[1:])
    return lines + [""]


def _kinds() -> list[str]:
    rows = []
    for kind in registry.KINDS.values():
        methods = ", ".join(f"``{m.name}``" for m in registry.methods_for(kind.name))
        defaults = ", ".join(f"``{k}={v!r}``" for k, v in kind.defaults.items()) or "none"
        fixed = ", ".join(f"``{name}``" for name in kind.fixed) or "none"
        rows.append(
            (f"``{kind.name}``", kind.problem, f"``{kind.default}``", methods, defaults, fixed)
        )
    header = (
        "kind",
        "problem",
        "default method",
        "methods",
        "option defaults it sets",
        "options the problem sets",
    )
    return _table(header, rows)


def _method(method: registry.Method) -> list[str]:
    title = f"``{method.name}``"
    extra = f"``pip install 'contactqp[{method.extra}]'``" if method.extra else "none (core)"
    kinds = ", ".join(f"``{kind}``" for kind in method.kinds)
    function = f"{method.function.__module__}.{method.function.__qualname__}"
    lines = [
        title,
        "-" * len(title),
        "",
        method.summary[0].upper() + method.summary[1:] + ".",
        "",
        f"- solves: {kinds}",
        f"- role: {method.role}",
        f"- extra: {extra}",
        f"- function: :func:`{function}`",
    ]
    if method.backend_settings:
        lines.append("- further keywords are passed on to the qpsolvers backend")
    lines.append("")
    if not method.options:
        return lines + ["No options.", ""]
    rows = []
    for option in method.options:
        overrides = [
            f"``{kind.name}``: {_literal(kind.defaults[option.name])}"
            for kind in registry.KINDS.values()
            if kind.name in method.kinds and option.name in kind.defaults
        ]
        fixed = [
            f"set by ``{kind.name}`` problems"
            for kind in registry.KINDS.values()
            if kind.name in method.kinds and option.name in kind.fixed
        ]
        rows.append(
            (
                f"``{option.name}``",
                _literal(option.type),
                _literal(option.default),
                "; ".join(overrides + fixed) or "",
                option.doc,
            )
        )
    header = ("option", "type", "default", "per kind", "meaning")
    return lines + _table(header, rows)


def registry_rst() -> list[str]:
    """The reST lines of the registry page's generated part."""
    lines = ["Problem kinds", "=============", "", *_kinds(), "Methods", "=======", ""]
    for method in registry.METHODS.values():
        lines.extend(_method(method))
    return lines


class MethodRegistry(SphinxDirective):
    """``.. method-registry::``: the kinds table and one section per method."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        self.env.note_dependency(registry.__file__)
        container = nodes.section()
        content = StringList(registry_rst(), source="contactqp.methods.registry")
        nested_parse_with_titles(self.state, content, container)
        return container.children


def command_help(name: str) -> str:
    """The ``--help`` text of ``contactqp NAME``, 88 columns wide."""
    parent = click.Context(
        cli, info_name="contactqp", terminal_width=88, max_content_width=88, **cli.context_settings
    )
    command = cli.get_command(parent, name)
    assert command is not None, name
    with click.Context(command, info_name=name, parent=parent) as context:
        return command.get_help(context)


class CommandHelp(SphinxDirective):
    """``.. command-help:: NAME``: the help of a ``contactqp`` command as a literal block."""

    required_arguments = 1

    def run(self) -> list[nodes.Node]:
        name = self.arguments[0]
        names = cli.list_commands(click.Context(cli))
        if name not in names:
            raise self.error(f"no contactqp command {name!r}; commands: {', '.join(names)}")
        text = command_help(name)
        block = nodes.literal_block(text, text, language="text")
        return [block]


def setup(app):
    app.add_directive("method-registry", MethodRegistry)
    app.add_directive("command-help", CommandHelp)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}

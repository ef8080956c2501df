"""The ``contactqp`` command group, its exit codes and the shared output helpers.

Exit status: 0 success; 1 a solve did not converge, its certificate failed, or the method found
no answer (:class:`~contactqp.errors.SolverError`); 2 unreadable or invalid input, a missing
optional package, or a problem this version cannot do. Errors are one line on stderr, never a
traceback (see :mod:`contactqp.errors` for which failure is which).
"""

from __future__ import annotations

import importlib
import sys
import time
import warnings
from collections.abc import Callable, Collection, Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, TextIO

import click

from ..errors import ContactError, ContactWarning, SolverError

if TYPE_CHECKING:
    from rich.console import Console
    from rich.progress import Progress, TaskID
    from rich.table import Table

__all__ = [
    "COMMANDS",
    "LazyGroup",
    "cli",
    "console",
    "fail",
    "float_list",
    "main",
    "progress",
    "warn",
]

EXIT_OK, EXIT_NOT_SOLVED, EXIT_BAD_INPUT = 0, 1, 2

#: Every command: the module of this package that defines it (as a function of the command's
#: name) and its one-line help, which ``contactqp --help`` shows without importing the module (a
#: test checks each line against the command's own help).
COMMANDS: dict[str, tuple[str, str]] = {
    "assembly": ("assembly", "Fasten the parts of an assembly file, then vary its gaps."),
    "fclib": (
        "fclib",
        "Solve FCLIB problems (HDF5 or Siconos .dat), local or global, with Coulomb friction.",
    ),
    "layers": (
        "layers",
        "A 1 m soil layer on a 2 m one (10 m long, plane strain), pulled sideways under gravity.",
    ),
    "methods": (
        "methods",
        "List the methods: the problem kinds they solve, their role and options, "
        "what is installed.",
    ),
    "riveting": (
        "riveting",
        "Two 200 x 100 x 2 mm aluminium plates riveted over a gap field (frictionless).",
    ),
    "rod": (
        "rod",
        "The published rod over an obstacle: reduced model (8 nodes) against full FE contact.",
    ),
    "rough": (
        "rough",
        "A rigid flat pressed onto a periodic rough surface on an elastic half-space.",
    ),
    "solve": (
        "solve",
        "Solve the contact problem (with friction, or a load history) in a TOML file.",
    ),
    "springs": (
        "springs",
        "A chain of bodies linked by springs on a floor with friction, pulled at its end.",
    ),
}


def fail(message: str) -> None:
    """One line on stderr: ``contactqp: error: MESSAGE``."""
    click.echo(f"contactqp: error: {message}", err=True)


def warn(message: str) -> None:
    """One line on stderr: ``contactqp: warning: MESSAGE``."""
    click.echo(f"contactqp: warning: {' '.join(str(message).split())}", err=True)


def _show_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: TextIO | None = None,
    line: str | None = None,
) -> None:
    """Python warnings as one :func:`warn` line; one not of contactqp's tree names its class."""
    own = issubclass(category, ContactWarning)
    warn(str(message) if own else f"{message} ({category.__name__})")


#: Width of the tables written to a file or a pipe, where rich would otherwise cut them to 80
#: columns and shorten numbers to an ellipsis (a table is only as wide as its contents).
PIPED_WIDTH = 200


def console() -> Console:
    """A rich console on stdout (rich is imported only when a command prints a table): the
    terminal's width, or :data:`PIPED_WIDTH` when stdout is not a terminal."""
    from rich.console import Console

    terminal = Console()
    return terminal if terminal.is_terminal else Console(width=PIPED_WIDTH)


def figures_table(
    title: str,
    columns: Iterable[str],
    *,
    left: Collection[str] = (),
    caption: str | None = None,
) -> Table:
    """A rich table of ``columns``, right-justified but those in ``left``, whose cells fold onto
    more lines in a narrow terminal instead of ending in an ellipsis: every figure is printed
    in full."""
    from rich.table import Table

    table = Table(title=title, caption=caption)
    for column in columns:
        table.add_column(column, justify="left" if column in left else "right", overflow="fold")
    return table


@contextmanager
def progress(
    what: str, after: float = 2.0, every: float = 10.0
) -> Iterator[Callable[[int, int], None]]:
    """Show on stderr how far a long run is; yield the callback ``report(done, total)``.

    Nothing is shown for runs shorter than ``after`` seconds. Then, on a terminal, a rich
    progress bar (erased at the end); elsewhere (a log, a pipe), a line every ``every`` seconds:
    ``contactqp: step 5200 of 30001 (17 %), 10 s``.
    """
    start = time.monotonic()
    last = start
    bar: Progress | None = None
    task: TaskID | None = None
    terminal = sys.stderr.isatty()

    def report(done: int, total: int) -> None:
        nonlocal bar, task, last
        now = time.monotonic()
        if now - start < after:
            return
        if terminal:
            if bar is None or task is None:
                from rich.console import Console
                from rich.progress import Progress

                bar = Progress(console=Console(stderr=True), transient=True)
                bar.start()
                task = bar.add_task(f"{what}s", total=total)
            bar.update(task, completed=done)
        elif now - last >= every or last == start:
            last = now
            click.echo(
                f"contactqp: {what} {done} of {total} ({100 * done // total} %), "
                f"{now - start:.0f} s",
                err=True,
            )

    try:
        yield report
    finally:
        if bar is not None:
            bar.stop()


def float_list(ctx: click.Context, param: click.Parameter, text: str) -> list[float]:
    """Click callback: parse comma-separated numbers."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise click.BadParameter(f"expected comma-separated numbers, got {text!r}") from None
    if not values:
        raise click.BadParameter("expected at least one number")
    return values


class LazyGroup(click.Group):
    """A command group that imports a command's module only when that command runs.

    ``lazy`` maps a command's name to ``(module, one-line help)`` (see :data:`COMMANDS`): the
    module, relative to this package, defines the command as the attribute of that name.
    """

    def __init__(self, *args, lazy: dict[str, tuple[str, str]], **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.lazy = dict(lazy)

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(set(super().list_commands(ctx)) | set(self.lazy))

    def get_command(self, ctx: click.Context | None, cmd_name: str) -> click.Command | None:
        if cmd_name not in self.commands and cmd_name in self.lazy:
            module = importlib.import_module(f"{__package__}.{self.lazy[cmd_name][0]}")
            self.add_command(getattr(module, cmd_name), cmd_name)
        return self.commands.get(cmd_name)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The commands and their one-line help, from the table (no command is imported)."""
        names = self.list_commands(ctx)
        if not names:
            return
        limit = formatter.width - 6 - max(len(name) for name in names)
        rows = []
        for name in names:
            if name in self.lazy:
                # shortened as click shortens a command's own help
                text = click.Command(name, help=self.lazy[name][1]).get_short_help_str(limit)
            else:
                text = self.commands[name].get_short_help_str(limit)
            rows.append((name, text))
        with formatter.section("Commands"):
            formatter.write_dl(rows)


@click.group(cls=LazyGroup, lazy=COMMANDS, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="contactqp")
def cli() -> None:
    """Fast elastic contact with friction on reduced (compliance-matrix) models."""


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status instead of raising."""
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        return _run(argv)


def _run(argv: Sequence[str] | None) -> int:
    try:
        cli.main(args=argv, prog_name="contactqp", standalone_mode=False)
    except click.exceptions.Exit as exc:
        return exc.exit_code
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_NOT_SOLVED
    except click.exceptions.Abort:
        fail("interrupted")
        return 130
    except click.ClickException as exc:
        fail(exc.format_message().replace("\n", " "))
        return EXIT_BAD_INPUT
    except SolverError as exc:
        fail(str(exc).replace("\n", " "))
        return EXIT_NOT_SOLVED
    except ContactError as exc:
        fail(str(exc).replace("\n", " "))
        return EXIT_BAD_INPUT
    except OSError as exc:
        fail(f"{exc.filename or ''}: {exc.strerror or exc}".lstrip(": "))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        fail("interrupted")
        return 130
    return EXIT_OK

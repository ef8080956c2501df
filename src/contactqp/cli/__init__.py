"""The ``contactqp`` command line: one module per command, imported when that command runs.

The commands are listed in :data:`contactqp.cli.app.COMMANDS`.
"""

from .app import cli, main

__all__ = ["cli", "main"]

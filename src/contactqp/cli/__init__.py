"""The ``contactqp`` command line: one module per command, each registering on :data:`cli`."""

from . import fclib, solve, springs  # noqa: F401  (register the commands)
from . import rod  # noqa: F401
from . import riveting  # noqa: F401
from . import layers  # noqa: F401
from . import methods  # noqa: F401
from .app import cli, main

__all__ = ["cli", "main"]

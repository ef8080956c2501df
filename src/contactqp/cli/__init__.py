"""The ``contactqp`` command line: one module per command, each registering on :data:`cli`."""

from . import (  # noqa: F401  (register the commands)
    assembly,
    fclib,
    layers,
    methods,
    riveting,
    rod,
    rough,
    solve,
    springs,
)
from .app import cli, main

__all__ = ["cli", "main"]

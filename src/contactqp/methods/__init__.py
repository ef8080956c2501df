"""Every algorithm, the registry that names them and :func:`solve`, the one entry point."""

from __future__ import annotations

from .active_set import solve_active_set
from .box_qp import BoxQPSolution, solve_box_qp
from .dispatch import solve
from .history import solve_history
from .qp import solve_qp
from .registry import (
    KINDS,
    METHODS,
    Kind,
    Method,
    Option,
    default_method,
    is_installed,
    methods_for,
)

__all__ = [
    "solve",
    "solve_history",
    "METHODS",
    "KINDS",
    "Method",
    "Option",
    "Kind",
    "methods_for",
    "default_method",
    "is_installed",
    "solve_active_set",
    "solve_qp",
    "solve_box_qp",
    "BoxQPSolution",
]

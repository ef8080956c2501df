"""Optional dependencies, imported where they are used: a missing one names the extra to install.

The one place that writes what to install: :func:`require` for a package,
:func:`require_backend` for a backend chosen by name among those a package found installed.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable
from types import ModuleType

from .errors import InvalidInputError, MissingDependencyError

__all__ = ["require", "require_backend"]


def require(module: str, purpose: str, extra: str, distribution: str | None = None) -> ModuleType:
    """Import the optional ``module`` needed for ``purpose``.

    Parameters
    ----------
    module : str
        Dotted module name, e.g. ``"h5py"`` or ``"ansys.mapdl.reader.full"``.
    purpose : str
        What needs it, as the start of the message (``"figures"``).
    extra : str
        The contactqp extra that installs it (``"plot"``).
    distribution : str, optional
        The package's name to show (default: the module's top-level name).

    Raises
    ------
    MissingDependencyError
        ``"{purpose} needs {distribution}: pip install 'contactqp[{extra}]'"``.
    """
    try:
        return importlib.import_module(module)
    except ImportError:
        name = distribution or module.split(".")[0]
        raise MissingDependencyError(
            f"{purpose} needs {name}: pip install 'contactqp[{extra}]'"
        ) from None


def require_backend(name: str, installed: Iterable[str]) -> None:
    """Refuse a backend ``name`` that is not among the ``installed`` ones.

    Raises
    ------
    InvalidInputError
        ``"backend {name!r} is not installed; available: {installed, sorted}"``: the name is
        the caller's choice (perhaps misspelt), so it is an input error.
    """
    installed = sorted(installed)
    if name not in installed:
        raise InvalidInputError(
            f"backend {name!r} is not installed; available: {', '.join(installed) or 'none'}"
        )

"""Optional dependencies, imported where they are used: a missing one names the extra to install."""

from __future__ import annotations

import importlib
from types import ModuleType

from .errors import MissingDependencyError

__all__ = ["require"]


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
            f"{purpose} needs {name}: pip install 'contactqp[{extra}]'") from None

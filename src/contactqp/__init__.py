"""contactqp: fast elastic contact with friction on reduced (compliance-matrix) models.

Importing the package does no work: each name below is imported from its module on first use
(PEP 562), so that a command or a program pays only for the modules it uses.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .core.certificate import Certificate, FrictionCertificate, LocalCertificate
    from .core.contact import GapObstacle, NodePairs, PlaneObstacle, ProfileObstacle
    from .core.fastened import FastenedProblem
    from .core.friction import FrictionLaw
    from .core.history import HistoryResult, linear_path
    from .core.local_batch import LocalBatch, LocalBatchResult
    from .core.local_problem import GlobalProblem, LocalProblem
    from .core.model import ReducedModel, unit_load_compliance
    from .core.problem import ContactProblem, FrictionalProblem
    from .core.result import ContactResult, FastenedResult, FrictionalResult, LocalResult
    from .core.status import STATUS_LABELS, ContactStatus
    from .core.surface import SurfaceProblem, SurfaceResult
    from .errors import (
        ContactError,
        ContactWarning,
        FileFormatError,
        InvalidInputError,
        MissingDependencyError,
        NotPositiveDefiniteError,
        SolverError,
        UnsupportedProblemError,
    )
    from .methods import METHODS, default_method, is_installed, methods_for, solve, solve_history

#: The public names and the modules they come from (relative to this package).
_EXPORTS: dict[str, str] = {
    "Certificate": ".core.certificate",
    "FrictionCertificate": ".core.certificate",
    "LocalCertificate": ".core.certificate",
    "GapObstacle": ".core.contact",
    "NodePairs": ".core.contact",
    "PlaneObstacle": ".core.contact",
    "ProfileObstacle": ".core.contact",
    "FastenedProblem": ".core.fastened",
    "FrictionLaw": ".core.friction",
    "HistoryResult": ".core.history",
    "linear_path": ".core.history",
    "LocalBatch": ".core.local_batch",
    "LocalBatchResult": ".core.local_batch",
    "GlobalProblem": ".core.local_problem",
    "LocalProblem": ".core.local_problem",
    "ReducedModel": ".core.model",
    "unit_load_compliance": ".core.model",
    "ContactProblem": ".core.problem",
    "FrictionalProblem": ".core.problem",
    "ContactResult": ".core.result",
    "FastenedResult": ".core.result",
    "FrictionalResult": ".core.result",
    "LocalResult": ".core.result",
    "STATUS_LABELS": ".core.status",
    "ContactStatus": ".core.status",
    "SurfaceProblem": ".core.surface",
    "SurfaceResult": ".core.surface",
    "ContactError": ".errors",
    "ContactWarning": ".errors",
    "FileFormatError": ".errors",
    "InvalidInputError": ".errors",
    "MissingDependencyError": ".errors",
    "NotPositiveDefiniteError": ".errors",
    "SolverError": ".errors",
    "UnsupportedProblemError": ".errors",
    "METHODS": ".methods",
    "default_method": ".methods",
    "is_installed": ".methods",
    "methods_for": ".methods",
    "solve": ".methods",
    "solve_history": ".methods",
}

#: The subpackages and modules, imported on first use as attributes (``contactqp.methods``).
_SUBMODULES = frozenset(
    {
        "applications",
        "cli",
        "compliance",
        "core",
        "errors",
        "io",
        "kernels",
        "methods",
        "optional",
        "studies",
    }
)

__all__ = [
    "ReducedModel",
    "unit_load_compliance",
    "ContactProblem",
    "ContactResult",
    "LocalResult",
    "ContactStatus",
    "STATUS_LABELS",
    "Certificate",
    "LocalCertificate",
    "FrictionalProblem",
    "FrictionalResult",
    "FrictionCertificate",
    "FrictionLaw",
    "LocalProblem",
    "GlobalProblem",
    "LocalBatch",
    "LocalBatchResult",
    "FastenedProblem",
    "FastenedResult",
    "SurfaceProblem",
    "SurfaceResult",
    "solve_history",
    "linear_path",
    "HistoryResult",
    "GapObstacle",
    "PlaneObstacle",
    "ProfileObstacle",
    "NodePairs",
    "solve",
    "solve_gaps",
    "METHODS",
    "methods_for",
    "default_method",
    "is_installed",
    "ContactError",
    "ContactWarning",
    "InvalidInputError",
    "NotPositiveDefiniteError",
    "FileFormatError",
    "UnsupportedProblemError",
    "MissingDependencyError",
    "SolverError",
]

__version__ = "0.1.0"


def __getattr__(name: str) -> Any:
    """Import a public name (or a subpackage) on first use, and keep it."""
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name], __name__), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS) | _SUBMODULES)


def solve_gaps(
    flexibility,
    loads,
    gaps,
    *,
    directions=(1.0,),
    nodes=None,
    dofs_per_node=1,
    method: str | None = None,
    **options,
) -> ContactResult:
    """Solve the common case in one call: a flexibility matrix, loads and per-node gaps.

    Parameters
    ----------
    flexibility : array_like, shape (n, n)
        ``R`` (m/N), freedoms ordered node by node.
    loads : array_like, shape (n,)
        External forces ``P`` (N).
    gaps : array_like, shape (k,)
        Initial gap of each contact node along its direction (m).
    directions : array_like, shape (d,) or (k, d)
        Directions towards the obstacle (default ``[1.0]``, for one freedom per node).
    nodes : sequence of int, optional
        Contact nodes (default: every node, then ``k`` must equal the node count).
    dofs_per_node : int
    method : str, optional
        A frictionless method (default ``"active-set"``), see :func:`solve`.

    Returns
    -------
    ContactResult
    """
    from .core.contact import GapObstacle
    from .core.model import ReducedModel
    from .core.problem import ContactProblem
    from .methods import solve

    model = ReducedModel(flexibility=flexibility, dofs_per_node=dofs_per_node)
    if nodes is None:
        nodes = range(model.n_nodes)
    problem = ContactProblem(model, loads, [GapObstacle(list(nodes), gaps, directions)])
    return solve(problem, method, **options)

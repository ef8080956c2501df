"""contactqp: fast elastic contact with friction on reduced (compliance-matrix) models."""

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
    model = ReducedModel(flexibility=flexibility, dofs_per_node=dofs_per_node)
    if nodes is None:
        nodes = range(model.n_nodes)
    problem = ContactProblem(model, loads, [GapObstacle(list(nodes), gaps, directions)])
    return solve(problem, method, **options)

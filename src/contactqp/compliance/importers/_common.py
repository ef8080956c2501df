"""What every importer shares: file checks, freedom selection, the reduction to a model."""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ...core.model import SYMMETRY_RTOL, ReducedModel
from ...errors import FileFormatError, InvalidInputError
from ...optional import require
from ..condensation import condense

__all__ = ["KINDS", "existing_file", "about", "one_line", "backend", "node_major",
           "freedom_indices", "index_list", "whole_numbers", "reduced_model"]

#: What a matrix read from a file may be.
KINDS = ("stiffness", "flexibility")


def one_line(text) -> str:
    """``text`` with its lines joined by ``"; "``."""
    return "; ".join(part.strip() for part in str(text).splitlines() if part.strip())


def existing_file(path) -> Path:
    """``path`` as a :class:`~pathlib.Path`; :class:`FileFormatError` unless it is a file."""
    path = Path(path)
    if not path.exists():
        raise FileFormatError(f"{path}: file not found")
    if not path.is_file():
        raise FileFormatError(f"{path}: not a file")
    return path


@contextmanager
def about(path: Path):
    """Raise :class:`InvalidInputError` (and subclasses) again with ``path`` first, class kept."""
    try:
        yield
    except InvalidInputError as exc:
        if str(exc).startswith(f"{path}: "):
            raise
        raise type(exc)(one_line(f"{path}: {exc}")) from None


def backend(module: str, distribution: str, what: str, extra: str):
    """Import an optional backend; :class:`MissingDependencyError` names the fix when absent:
    ``pip install 'contactqp[extra]'``."""
    return require(module, f"reading {what}", extra, distribution)


def node_major(nodes, components) -> list[tuple]:
    """The ``(node, component)`` pairs of the chosen nodes and components, node by node.

    Raises
    ------
    InvalidInputError
        Nothing chosen, or a node or a component listed twice.
    """
    nodes, components = list(nodes), list(components)
    if not nodes or not components:
        raise InvalidInputError("choose at least one node and one component")
    for name, chosen in (("nodes", nodes), ("components", components)):
        if len(set(chosen)) != len(chosen):
            twice = next(item for item in chosen if chosen.count(item) > 1)
            raise InvalidInputError(f"{name} lists {twice!r} twice")
    return [(node, component) for node in nodes for component in components]


def freedom_indices(available: Sequence[tuple[Hashable, Hashable]], pairs, noun: str = "node",
                    describe=None) -> np.ndarray:
    """Positions in ``available`` of the ``(node, component)`` ``pairs``.

    Parameters
    ----------
    available : sequence of (node, component)
        The label of each row of the file's matrix.
    pairs : sequence of (node, component)
        The freedoms wanted, in order (see :func:`node_major`).
    noun : str
        What the file calls a node ("node", "grid"), for error messages.
    describe : callable, optional
        ``describe(node, component) -> str`` for error messages (default: noun, node, component).

    Raises
    ------
    InvalidInputError
        A node or a component is not in ``available``.
    """
    describe = describe or (lambda node, component: f"{noun} {node} {component}")
    where = {label: i for i, label in enumerate(available)}
    present: dict = {}
    for node, component in available:
        present.setdefault(node, []).append(component)
    indices = []
    for node, component in pairs:
        if node not in present:
            raise InvalidInputError(f"{noun} {node} is not in the file ({len(present)} {noun}s)")
        if (node, component) not in where:
            has = ", ".join(str(c) for c in present[node])
            raise InvalidInputError(
                f"{describe(node, component)} is not in the file ({noun} {node} has {has})")
        indices.append(where[node, component])
    return np.asarray(indices, dtype=int)


def whole_numbers(values, name: str) -> list[int]:
    """``values`` (node or component numbers) as a list of ints; InvalidInputError otherwise."""
    try:
        items = list(values)
        numbers = [int(item) for item in items]
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be a list of whole numbers, got {values!r}") from None
    if any(isinstance(item, (bool, np.bool_)) or number != item
           for item, number in zip(items, numbers)):
        raise InvalidInputError(f"{name} must be a list of whole numbers, got {values!r}")
    return numbers


def index_list(values, n: int, name: str) -> np.ndarray:
    """``values`` as unique 0-based indices below ``n``."""
    idx = np.asarray(values)
    if idx.ndim != 1 or not (idx.size == 0 or np.issubdtype(idx.dtype, np.integer)):
        raise InvalidInputError(f"{name} must be a 1-D list of integer indices (from 0)")
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise InvalidInputError(f"{name} must lie in 0..{n - 1}, got {idx.min()}..{idx.max()}")
    if np.unique(idx).size != idx.size:
        raise InvalidInputError(f"{name} lists an index twice")
    return idx.astype(int)


def _dense(matrix) -> np.ndarray:
    return matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix)


def reduced_model(matrix, kind: str, keep=None, fixed=None, labels=None, dofs_per_node=1,
                  coordinates=None, symmetry_rtol: float = SYMMETRY_RTOL) -> ReducedModel:
    """The reduced model of the freedoms ``keep`` of a stiffness or flexibility matrix.

    A flexibility is cut to the rows and columns of ``keep``. A stiffness loses the rows and
    columns of ``fixed`` (zero displacement); when ``keep`` is every other freedom the model is
    built from that stiffness, otherwise the other freedoms are condensed out
    (:func:`~contactqp.compliance.condensation.condense`) and the model holds the flexibility.

    Parameters
    ----------
    matrix : ndarray or sparse matrix, shape (n, n)
        N/m for a stiffness, m/N for a flexibility (or consistent units).
    kind : {"stiffness", "flexibility"}
    keep : sequence of int, optional
        Computational freedoms, in the model's order (default: every freedom not fixed).
    fixed : sequence of int, optional
        Clamped freedoms of a stiffness.
    labels : sequence of str, optional
        Name of each of the ``n`` freedoms, for error messages.
    dofs_per_node, coordinates, symmetry_rtol
        Passed to :class:`~contactqp.core.model.ReducedModel`; ``symmetry_rtol`` also to
        :func:`~contactqp.compliance.condensation.condense`.

    Returns
    -------
    ReducedModel
    """
    if kind not in KINDS:
        raise InvalidInputError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1] or matrix.shape[0] == 0:
        raise InvalidInputError(f"the matrix must be square and non-empty, got shape "
                                f"{matrix.shape}")
    n = matrix.shape[0]
    fixed = index_list([] if fixed is None else fixed, n, "fixed")
    if fixed.size and kind == "flexibility":
        raise InvalidInputError("fixed freedoms apply to a stiffness matrix, not a flexibility")
    free = np.setdiff1d(np.arange(n), fixed)
    keep = free if keep is None else index_list(keep, n, "the chosen freedoms")
    clash = np.intersect1d(keep, fixed)
    if clash.size:
        name = labels[clash[0]] if labels is not None else f"freedom {clash[0]}"
        raise InvalidInputError(f"{name} is chosen but fixed (a fixed freedom does not move)")
    if keep.size == 0:
        raise InvalidInputError("no freedom is chosen")
    options = dict(dofs_per_node=dofs_per_node, coordinates=coordinates,
                   symmetry_rtol=symmetry_rtol)
    if kind == "flexibility":
        return ReducedModel(flexibility=_dense(matrix)[np.ix_(keep, keep)], **options)
    if keep.size == free.size:
        return ReducedModel(stiffness=_dense(matrix)[np.ix_(keep, keep)], **options)
    K = sp.csc_matrix(matrix, dtype=float)[free][:, free]
    position = np.full(n, -1)
    position[free] = np.arange(free.size)
    free_labels = None if labels is None else [labels[i] for i in free]
    R = condense(K, position[keep], labels=free_labels, symmetry_rtol=symmetry_rtol)
    return ReducedModel(flexibility=R, **options)

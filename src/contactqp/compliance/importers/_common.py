"""What every importer shares: file checks, freedom selection, the reduction to a model."""

from __future__ import annotations

import os
from collections.abc import Callable, Hashable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import ModuleType
from typing import Any, TypeAlias

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ...core.model import SYMMETRY_RTOL, ReducedModel
from ...errors import FileFormatError, InvalidInputError
from ...optional import require
from ..condensation import condense

__all__ = [
    "KINDS",
    "existing_file",
    "about",
    "one_line",
    "backend",
    "node_major",
    "freedom_indices",
    "index_list",
    "whole_numbers",
    "reduced_model",
    "StrPath",
    "Matrix",
    "DofsPerNode",
]

#: A file name: what :class:`pathlib.Path` accepts.
StrPath: TypeAlias = str | os.PathLike[str]
#: A matrix as the readers give it: dense, or sparse as the file stores it.
Matrix: TypeAlias = np.ndarray | sp.coo_matrix | sp.csc_matrix
#: Freedoms of every node, or of each node (see :class:`~contactqp.core.model.ReducedModel`).
DofsPerNode: TypeAlias = int | Sequence[int] | np.ndarray

#: What a matrix read from a file may be.
KINDS = ("stiffness", "flexibility")


def one_line(text: object) -> str:
    """``text`` with its lines joined by ``"; "``."""
    return "; ".join(part.strip() for part in str(text).splitlines() if part.strip())


def existing_file(path: StrPath) -> Path:
    """``path`` as a :class:`~pathlib.Path`; :class:`FileFormatError` unless it is a file."""
    file = Path(path)
    if not file.exists():
        raise FileFormatError(f"{file}: file not found")
    if not file.is_file():
        raise FileFormatError(f"{file}: not a file")
    return file


@contextmanager
def about(path: Path) -> Iterator[None]:
    """Raise :class:`InvalidInputError` (and subclasses) again with ``path`` first, class kept."""
    try:
        yield
    except InvalidInputError as exc:
        if str(exc).startswith(f"{path}: "):
            raise
        raise type(exc)(one_line(f"{path}: {exc}")) from None


def backend(module: str, distribution: str, what: str, extra: str) -> ModuleType:
    """Import an optional backend; :class:`MissingDependencyError` names the fix when absent:
    ``pip install 'contactqp[extra]'``."""
    return require(module, f"reading {what}", extra, distribution)


def node_major(
    nodes: Iterable[Hashable], components: Iterable[Hashable]
) -> list[tuple[Hashable, Hashable]]:
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


def freedom_indices(
    available: Sequence[tuple[Hashable, Hashable]],
    pairs: Iterable[Sequence[Hashable]],
    noun: str = "node",
    describe: Callable[[Hashable, Hashable], str] | None = None,
) -> np.ndarray:
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
    present: dict[Hashable, list[Hashable]] = {}
    for node, component in available:
        present.setdefault(node, []).append(component)
    indices = []
    for node, component in pairs:
        if node not in present:
            raise InvalidInputError(f"{noun} {node} is not in the file ({len(present)} {noun}s)")
        if (node, component) not in where:
            has = ", ".join(str(c) for c in present[node])
            raise InvalidInputError(
                f"{describe(node, component)} is not in the file ({noun} {node} has {has})"
            )
        indices.append(where[node, component])
    return np.asarray(indices, dtype=int)


def whole_numbers(values: Iterable[Any], name: str) -> list[int]:
    """``values`` (node or component numbers) as a list of ints; InvalidInputError otherwise."""
    try:
        items = list(values)
        numbers = [int(item) for item in items]
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be a list of whole numbers, got {values!r}") from None
    if any(
        isinstance(item, (bool, np.bool_)) or number != item
        for item, number in zip(items, numbers, strict=True)
    ):
        raise InvalidInputError(f"{name} must be a list of whole numbers, got {values!r}")
    return numbers


def index_list(values: ArrayLike, n: int, name: str) -> np.ndarray:
    """``values`` as unique 0-based indices below ``n``."""
    idx = np.asarray(values)
    if idx.ndim != 1 or not (idx.size == 0 or np.issubdtype(idx.dtype, np.integer)):
        raise InvalidInputError(f"{name} must be a 1-D list of integer indices (from 0)")
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise InvalidInputError(f"{name} must lie in 0..{n - 1}, got {idx.min()}..{idx.max()}")
    if np.unique(idx).size != idx.size:
        raise InvalidInputError(f"{name} lists an index twice")
    return idx.astype(int)


def _dense(matrix: Matrix) -> np.ndarray:
    return matrix if isinstance(matrix, np.ndarray) else matrix.toarray()


def reduced_model(
    matrix: Matrix,
    kind: str,
    keep: ArrayLike | None = None,
    fixed: ArrayLike | None = None,
    labels: Sequence[str] | None = None,
    dofs_per_node: DofsPerNode = 1,
    coordinates: ArrayLike | None = None,
    symmetry_rtol: float = SYMMETRY_RTOL,
) -> ReducedModel:
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
        raise InvalidInputError(
            f"the matrix must be square and non-empty, got shape {matrix.shape}"
        )
    n = matrix.shape[0]
    held = index_list([] if fixed is None else fixed, n, "fixed")
    if held.size and kind == "flexibility":
        raise InvalidInputError("fixed freedoms apply to a stiffness matrix, not a flexibility")
    free = np.setdiff1d(np.arange(n), held)
    kept = free if keep is None else index_list(keep, n, "the chosen freedoms")
    clash = np.intersect1d(kept, held)
    if clash.size:
        name = labels[clash[0]] if labels is not None else f"freedom {clash[0]}"
        raise InvalidInputError(f"{name} is chosen but fixed (a fixed freedom does not move)")
    if kept.size == 0:
        raise InvalidInputError("no freedom is chosen")
    if kind == "flexibility":
        return ReducedModel(
            flexibility=_dense(matrix)[np.ix_(kept, kept)],
            dofs_per_node=dofs_per_node,
            coordinates=coordinates,
            symmetry_rtol=symmetry_rtol,
        )
    if kept.size == free.size:
        return ReducedModel(
            stiffness=_dense(matrix)[np.ix_(kept, kept)],
            dofs_per_node=dofs_per_node,
            coordinates=coordinates,
            symmetry_rtol=symmetry_rtol,
        )
    K = sp.csc_matrix(matrix, dtype=float)[free][:, free]
    position = np.full(n, -1)
    position[free] = np.arange(free.size)
    free_labels = None if labels is None else [labels[i] for i in free]
    R = condense(K, position[kept], labels=free_labels, symmetry_rtol=symmetry_rtol)
    return ReducedModel(
        flexibility=R,
        dofs_per_node=dofs_per_node,
        coordinates=coordinates,
        symmetry_rtol=symmetry_rtol,
    )

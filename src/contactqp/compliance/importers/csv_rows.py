"""Unit-load tables: one CSV row of displacements per unit load, as the unit-load method gives.

File layout::

    # comments start with '#'
    12:UX, 12:UY, 40:UX, 40:UY          <- optional header, one NODE:COMPONENT per column
    1.0e-6, 2.0e-7, 3.0e-7, 1.0e-8      <- row j: displacements of every freedom (m)
    ...                                     under a unit load (1 N) on freedom j

Values are separated by commas, or by spaces or tabs when the file has no comma. Freedoms are
ordered node by node: the columns of one node are adjacent.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ...core.model import SYMMETRY_RTOL, ReducedModel
from ...errors import FileFormatError, InvalidInputError
from ._common import (
    DofsPerNode,
    StrPath,
    about,
    existing_file,
    freedom_indices,
    node_major,
    one_line,
    reduced_model,
    whole_numbers,
)

__all__ = ["read_unit_load_csv"]


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _label(path: Path, token: str) -> tuple[int, str]:
    node, sep, component = token.strip().partition(":")
    if not sep or not component.strip() or not node.strip().isdigit():
        raise FileFormatError(
            f"{path}: header label {token.strip()!r} is not NODE:COMPONENT (e.g. 12:UX)"
        )
    return int(node), component.strip().upper()


def _table(path: Path) -> tuple[np.ndarray, list[tuple[int, str]] | None]:
    """The numbers of the file (one row per line) and the header's labels, if any."""
    try:
        with open(path, encoding="utf-8-sig") as handle:
            lines = [line.split("#", 1)[0].strip() for line in handle]
    except (OSError, UnicodeDecodeError) as exc:
        raise FileFormatError(f"{path}: cannot read the file: {one_line(exc)}") from None
    lines = [line for line in lines if line]
    if not lines:
        raise FileFormatError(f"{path}: the file holds no numbers")
    delimiter = "," if any("," in line for line in lines) else None
    labels = None
    first = [token.strip() for token in lines[0].split(delimiter)]
    if not all(_is_number(token) for token in first):
        labels = [_label(path, token) for token in first]
        lines = lines[1:]
    if not lines:
        raise FileFormatError(f"{path}: the file has a header but no rows")
    try:
        table = np.loadtxt(lines, delimiter=delimiter, ndmin=2, dtype=float)
    except ValueError as exc:
        raise FileFormatError(f"{path}: not a table of numbers: {one_line(exc)}") from None
    return table, labels


def _node_counts(labels: list[tuple[int, str]]) -> list[int]:
    """Freedoms of each node, checking that a node's columns are adjacent."""
    counts: list[int] = []
    done: set[int] = set()
    for position, (node, _) in enumerate(labels):
        if position and node == labels[position - 1][0]:
            counts[-1] += 1
            continue
        if node in done:
            raise InvalidInputError(f"the columns of node {node} are not adjacent")
        done.add(node)
        counts.append(1)
    return counts


def read_unit_load_csv(
    path: StrPath,
    nodes: Sequence[int] | None = None,
    components: Sequence[str] | None = None,
    *,
    dofs_per_node: DofsPerNode | None = None,
    symmetry_rtol: float = SYMMETRY_RTOL,
) -> ReducedModel:
    """Flexibility from a table of unit-load responses (layout in the module docstring).

    Row ``j`` holds the displacements of all computational freedoms under a unit load on freedom
    ``j``, i.e. column ``j`` of ``R``; Maxwell-Betti reciprocity makes the table symmetric, and
    an asymmetry beyond ``symmetry_rtol`` is an error.

    Parameters
    ----------
    path : str or os.PathLike
    nodes : sequence of int, optional
        Nodes to keep, in order (needs the header); default: every node, in the file's order.
    components : sequence of str, optional
        Components kept at every chosen node, in order (needs the header); default: those of
        the header's first node.
    dofs_per_node : int or sequence of int, optional
        Freedoms of each node of a file without a header (default 1); with a header they come
        from its labels.
    symmetry_rtol : float
        See :func:`~contactqp.core.model.check_spd_matrix`.

    Returns
    -------
    ReducedModel
        Given as the flexibility, in the units of the table (m/N for metres per unit newton).

    Raises
    ------
    FileFormatError
        Missing or unreadable file, a malformed header, text among the numbers.
    InvalidInputError
        A non-square table, a header of the wrong length, a node or component not in the header,
        selection without a header.
    NotPositiveDefiniteError
        The flexibility is not positive definite.
    """
    path = existing_file(path)
    table, labels = _table(path)
    with about(path):
        rows, columns = table.shape
        if rows != columns:
            raise InvalidInputError(
                f"the table has {rows} rows (unit loads) and {columns} "
                "columns (freedoms); one row per freedom is needed"
            )
        if labels is None:
            if nodes is not None or components is not None:
                raise InvalidInputError(
                    "choosing nodes or components needs a header row of NODE:COMPONENT labels"
                )
            return reduced_model(
                table.T,
                "flexibility",
                dofs_per_node=1 if dofs_per_node is None else dofs_per_node,
                symmetry_rtol=symmetry_rtol,
            )
        if dofs_per_node is not None:
            raise InvalidInputError("dofs_per_node comes from the header; do not give it too")
        if len(labels) != columns:
            raise InvalidInputError(f"the header has {len(labels)} labels for {columns} columns")
        counts = _node_counts(labels)
        if nodes is None and components is None:
            return reduced_model(
                table.T, "flexibility", dofs_per_node=counts, symmetry_rtol=symmetry_rtol
            )
        order = list(dict.fromkeys(node for node, _ in labels))
        nodes = order if nodes is None else whole_numbers(nodes, "nodes")
        if components is None:
            components = [c for node, c in labels if node == order[0]]
        components = [str(c).upper() for c in components]
        keep = freedom_indices(labels, node_major(nodes, components))
        return reduced_model(
            table.T, "flexibility", keep, dofs_per_node=len(components), symmetry_rtol=symmetry_rtol
        )

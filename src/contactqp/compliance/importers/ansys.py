"""ANSYS Mechanical APDL full files (``Jobname.full``): stiffness, freedom map and constraints.

The file is read by ansys-mapdl-reader (:class:`ansys.mapdl.reader.full.FullFile`). Its layout is
first checked here against the file's length, because the reader's compiled code does not stop at
the end of a truncated file.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ...core.model import SYMMETRY_RTOL, ReducedModel
from ...errors import ContactError, FileFormatError, UnsupportedProblemError
from ._common import (
    StrPath,
    about,
    backend,
    existing_file,
    freedom_indices,
    node_major,
    one_line,
    reduced_model,
)

__all__ = ["read_ansys_full", "DOF_LABELS"]

#: MAPDL DOF reference numbers of the structural freedoms and their labels.
DOF_LABELS = {1: "UX", 2: "UY", 3: "UZ", 4: "ROTX", 5: "ROTY", 6: "ROTZ"}

_STANDARD_HEADER_END = 103  # words: [100][flags][100 items][pad]
_FULL_FILE_TYPE = 4  # item 1 of the standard header


def _label(reference: int) -> str:
    return DOF_LABELS.get(int(reference), f"DOF{int(reference)}")


class _Layout:
    """The file as 32-bit words, to check records before the reader's compiled code reads them
    (it does not stop at the end of a truncated file)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        size = path.stat().st_size
        if size < 4 * (_STANDARD_HEADER_END + 2):
            raise FileFormatError(f"{path}: not an ANSYS full file (only {size} bytes)")
        self.words = np.memmap(path, dtype="<i4", mode="r", shape=(size // 4,))
        if self.words[0] != 100:
            if self.words[0].byteswap() == 100:
                raise UnsupportedProblemError(
                    f"{path}: a big-endian ANSYS file; "
                    "ansys-mapdl-reader reads little-endian files only"
                )
            raise FileFormatError(f"{path}: not an ANSYS binary file (no standard header)")
        if self.words[2] != _FULL_FILE_TYPE:
            from ansys.mapdl.reader.common import ANSYS_BINARY_FILE_TYPES

            kind = ANSYS_BINARY_FILE_TYPES.get(int(self.words[2]), f"type {self.words[2]}")
            raise FileFormatError(
                f"{path}: an ANSYS binary file of another kind ({kind}), not a full file"
            )

    def record_end(self, pointer: int, what: str) -> int:
        """End (in words) of the record at ``pointer``, checked to lie within the file."""
        if 0 <= pointer < self.words.size - 1:
            end = pointer + int(self.words[pointer]) + 3
            if self.words[pointer] >= 0 and end <= self.words.size:
                return end
        raise self.error(what, "lies beyond its end")

    def check_matrix(self, pointer: int, n_terms: int, n_equations: int, what: str) -> None:
        """A matrix block: per equation, a record of ``k`` row indices and one of ``k`` doubles."""
        end = pointer + 6 * n_equations + 3 * n_terms
        if pointer <= 0 or end > self.words.size:
            raise self.error(what, "lies beyond its end")
        block = np.asarray(self.words[pointer:end])
        position = 0
        for _ in range(n_equations):
            rows = int(block[position])
            values = position + rows + 3
            if rows < 0 or values >= block.size or int(block[values]) != 2 * rows:
                break
            position = values + 2 * rows + 3
        if position != block.size:
            raise self.error(
                what, f"has record lengths that do not add up to the {n_terms} terms of the header"
            )

    def error(self, what: str, problem: str) -> FileFormatError:
        return FileFormatError(
            f"{self.path}: truncated or corrupt ANSYS full file: the {what} "
            f"{problem} ({self.words.size} words)"
        )


def _read(
    path: Path,
) -> tuple[sp.csc_matrix, list[tuple[int, str]], np.ndarray, dict[int, int], int]:
    """Stiffness (full symmetric, CSC), ``(node, label)`` of each equation, constrained mask,
    the number of DOFs of each node and the size of the file's DOF set."""
    full_module = backend(
        "ansys.mapdl.reader.full", "ansys-mapdl-reader", "ANSYS full files", "ansys"
    )
    from ansys.mapdl.reader.common import two_ints_to_long

    layout = _Layout(path)
    header_end = layout.record_end(_STANDARD_HEADER_END, "full-file header")
    try:
        full = full_module.FullFile(path)
        header = full._header  # parsed by FullFile; each pointer is checked before it is used
        dof_end = layout.record_end(header_end, "DOF reference record")
        layout.record_end(dof_end, "nodal equivalence table")
        const_at = layout.record_end(header["ptrDOF"], "DOF count record")
        layout.record_end(const_at, "constraint record")
        n_equations = int(header["neqn"])
        n_stiffness = two_ints_to_long(header["ntermKl"], header["ntermKh"])
        n_mass = two_ints_to_long(header["ntermMl"], header["ntermMh"])
        if n_stiffness <= 0 or n_equations <= 0:
            raise FileFormatError(f"{path}: the full file holds no stiffness matrix")
        layout.check_matrix(header["ptrSTF"], n_stiffness, n_equations, "stiffness matrix")
        if n_mass > 0:
            layout.check_matrix(header["ptrMAS"], n_mass, n_equations, "mass matrix")
        references = np.asarray(full.read_record(header_end))[: int(header["numdof"])]
        n_nodes = np.asarray(full.read_record(dof_end)).size
        counts = np.asarray(full.read_record(header["ptrDOF"]))
        n_const = np.asarray(full.read_record(const_at)).size
        if (
            counts.size > n_nodes
            or counts.sum() != n_equations
            or n_const != n_equations
            or counts.min() < 0
            or counts.max() > references.size
        ):
            raise layout.error(
                "DOF count record",
                f"does not match the {n_equations} equations, "
                f"{n_nodes} nodes and {references.size} DOF kinds of the header",
            )
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="Missing mass matrix")
            dof_ref, upper, _ = full.load_km(as_sparse=True, sort=True)
        const = full.const
    except ContactError:
        raise
    except NotImplementedError as exc:  # lumped mass or unsymmetric matrices
        raise UnsupportedProblemError(f"{path}: {one_line(exc)}") from None
    except Exception as exc:  # whatever the reader raises on a corrupt file
        raise FileFormatError(f"{path}: cannot read the full file: {one_line(exc)}") from None
    upper = sp.csc_matrix(upper)
    stiffness = (upper + sp.triu(upper, 1).T).tocsc()  # the file stores each pair once
    constrained_pairs = {(int(n), int(j)) for n, j in const}
    labels = [(int(n), _label(references[j])) for n, j in dof_ref]
    constrained = np.array([(int(n), int(j)) in constrained_pairs for n, j in dof_ref])
    nodes, per_node = np.unique(dof_ref[:, 0], return_counts=True)
    per_node_count = dict(zip(nodes.tolist(), per_node.tolist(), strict=True))
    return stiffness, labels, constrained, per_node_count, references.size


def read_ansys_full(
    path: StrPath,
    nodes: Sequence[int],
    components: Sequence[str] = ("UX", "UY", "UZ"),
    *,
    symmetry_rtol: float = SYMMETRY_RTOL,
) -> ReducedModel:
    """Flexibility of chosen nodes of an ANSYS model, from its full file (``Jobname.full``).

    The stiffness is read with ansys-mapdl-reader, the constrained freedoms (``D`` commands)
    are removed, and the stiffness is condensed to the chosen freedoms by one sparse
    factorisation (:func:`~contactqp.compliance.condensation.condense`).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.full`` file of a static (or modal) analysis: symmetric stiffness, consistent mass.
    nodes : sequence of int, shape (n_nodes,)
        ANSYS node numbers of the computational nodes, in the model's order.
    components : sequence of str
        Freedoms taken at every node, in order: ``"UX"``, ``"UY"``, ``"UZ"``, ``"ROTX"``,
        ``"ROTY"``, ``"ROTZ"`` (1 to 3 of them).
    symmetry_rtol : float
        See :func:`~contactqp.core.model.check_spd_matrix`.

    Returns
    -------
    ReducedModel
        Shape ``(n_nodes * len(components),) * 2``, freedoms node by node in the order of
        ``nodes`` and ``components``, in the units of the ANSYS model (m/N in SI). Given as the
        flexibility, or as the stiffness itself when every free freedom is chosen.

    Raises
    ------
    FileFormatError
        Missing, foreign (another ANSYS file type included), truncated or inconsistent file.
    InvalidInputError
        A node or a component is not in the file, or a chosen freedom is constrained.
    RigidBodyModeError
        The model is not fixed enough to have a flexibility.
    UnsupportedProblemError
        Lumped mass, unsymmetric matrices or a big-endian file (not read by ansys-mapdl-reader),
        or a chosen node whose freedoms are not the file's full DOF set (their labels cannot be
        told).
    MissingDependencyError
        ansys-mapdl-reader is not installed.

    Notes
    -----
    The components are those of each node's nodal coordinate system, as the full file stores
    them. Constraint equations and coupled freedoms (``CE``, ``CP``) are not read. Before the
    reader touches a record, its extent is checked against the file's length (a truncated file
    would otherwise be read past its end).
    """
    path = existing_file(path)
    chosen_components = [str(c).upper() for c in components]
    stiffness, labels, constrained, counts, n_dof_kinds = _read(path)
    for node in nodes:
        if node in counts and counts[node] != n_dof_kinds:
            raise UnsupportedProblemError(
                f"{path}: node {node} has {counts[node]} of the file's {n_dof_kinds} DOF kinds; "
                "which ones cannot be told from the file"
            )
    with about(path):
        keep = freedom_indices(labels, node_major(nodes, chosen_components))
        names = [f"node {n} {c}" for n, c in labels]
        return reduced_model(
            stiffness,
            "stiffness",
            keep,
            np.flatnonzero(constrained),
            names,
            dofs_per_node=len(chosen_components),
            symmetry_rtol=symmetry_rtol,
        )

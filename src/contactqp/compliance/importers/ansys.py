"""ANSYS Mechanical APDL full files (``Jobname.full``): stiffness, freedom map and constraints.

The file is read by ansys-mapdl-reader (:class:`ansys.mapdl.reader.full.FullFile`). Its layout is
first checked here against the file's length, because the reader's compiled code does not stop at
the end of a truncated file.
"""

from __future__ import annotations

import warnings
from typing import Sequence

import numpy as np
import scipy.sparse as sp

from ...errors import ContactError, FileFormatError, UnsupportedProblemError
from ...model import SYMMETRY_RTOL, ReducedModel
from ._common import about, backend, existing_file, freedom_indices, one_line, reduced_model

__all__ = ["read_ansys_full", "DOF_LABELS"]

#: MAPDL DOF reference numbers of the structural freedoms and their labels.
DOF_LABELS = {1: "UX", 2: "UY", 3: "UZ", 4: "ROTX", 5: "ROTY", 6: "ROTZ"}

_STANDARD_HEADER_END = 103  # words: [100][flags][100 items][pad]
_FULL_FILE_TYPE = 4  # item 1 of the standard header


def _label(reference: int) -> str:
    return DOF_LABELS.get(int(reference), f"DOF{int(reference)}")


class _Layout:
    """The file as 32-bit words, to check that records lie within it."""

    def __init__(self, path):
        self.path = path
        size = path.stat().st_size
        if size < 4 * (_STANDARD_HEADER_END + 2):
            raise FileFormatError(f"{path}: not an ANSYS full file (only {size} bytes)")
        self.words = np.memmap(path, dtype="<i4", mode="r", shape=(size // 4,))
        if self.words[0] != 100:
            raise FileFormatError(f"{path}: not an ANSYS binary file (no standard header)")
        if self.words[2] != _FULL_FILE_TYPE:
            from ansys.mapdl.reader.common import ANSYS_BINARY_FILE_TYPES

            kind = ANSYS_BINARY_FILE_TYPES.get(int(self.words[2]), f"type {self.words[2]}")
            raise FileFormatError(f"{path}: an ANSYS binary file of another kind ({kind}), "
                                  "not a full file")

    def record_end(self, pointer: int, what: str) -> int:
        """End (in words) of the record at ``pointer``, checked to lie within the file."""
        if 0 <= pointer < self.words.size - 1:
            end = pointer + int(self.words[pointer]) + 3
            if self.words[pointer] >= 0 and end <= self.words.size:
                return end
        raise self.truncated(what)

    def check_matrix(self, pointer: int, n_terms: int, n_equations: int, what: str) -> None:
        """A matrix block: two records (indices, values) per equation."""
        if pointer <= 0 or pointer + 6 * n_equations + 3 * n_terms > self.words.size:
            raise self.truncated(what)

    def truncated(self, what: str) -> FileFormatError:
        return FileFormatError(f"{self.path}: truncated or corrupt ANSYS full file: the {what} "
                               f"lies beyond its end ({self.words.size} words)")


def _read(path):
    """Stiffness (full symmetric, CSC), ``(node, label)`` of each equation, constrained mask,
    and the number of DOFs of each node."""
    full_module = backend("ansys.mapdl.reader.full", "ansys-mapdl-reader", "ANSYS full files")
    from ansys.mapdl.reader.common import two_ints_to_long

    layout = _Layout(path)
    header_end = layout.record_end(_STANDARD_HEADER_END, "full-file header")
    try:
        full = full_module.FullFile(path)
        header = full._header  # parsed by FullFile; the pointers are checked before use
        dof_end = layout.record_end(header_end, "DOF reference record")
        layout.record_end(dof_end, "nodal equivalence table")
        layout.record_end(layout.record_end(header["ptrDOF"], "DOF count record"),
                          "constraint record")
        n_equations = int(header["neqn"])
        n_stiffness = two_ints_to_long(header["ntermKl"], header["ntermKh"])
        n_mass = two_ints_to_long(header["ntermMl"], header["ntermMh"])
        if n_stiffness <= 0 or n_equations <= 0:
            raise FileFormatError(f"{path}: the full file holds no stiffness matrix")
        layout.check_matrix(header["ptrSTF"], n_stiffness, n_equations, "stiffness matrix")
        if n_mass > 0:
            layout.check_matrix(header["ptrMAS"], n_mass, n_equations, "mass matrix")
        references = np.asarray(full.read_record(header_end))[: int(header["numdof"])]
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
    constrained_pairs = {(int(n), int(j)) for n, j in const}
    if dof_ref.shape != (n_equations, 2) or upper.shape != (n_equations, n_equations):
        raise FileFormatError(f"{path}: inconsistent full file: {n_equations} equations but "
                              f"{dof_ref.shape[0]} freedoms and a {upper.shape} stiffness")
    upper = sp.csc_matrix(upper)
    stiffness = (upper + sp.triu(upper, 1).T).tocsc()  # the file stores each term once
    nodes, counts = np.unique(dof_ref[:, 0], return_counts=True)
    labels = [(int(n), _label(references[j]) if j < references.size else f"DOF#{j}")
              for n, j in dof_ref]
    constrained = np.array([(int(n), int(j)) in constrained_pairs for n, j in dof_ref])
    return stiffness, labels, constrained, dict(zip(nodes.tolist(), counts.tolist())), \
        references.size


def read_ansys_full(path, nodes: Sequence[int], components: Sequence[str] = ("UX", "UY", "UZ"),
                    *, symmetry_rtol: float = SYMMETRY_RTOL) -> ReducedModel:
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
        See :func:`~contactqp.model.check_spd_matrix`.

    Returns
    -------
    ReducedModel
        Given as a flexibility, shape ``(n_nodes * len(components),) * 2``, freedoms node by node
        in the order of ``nodes`` and ``components``, in the units of the ANSYS model (m/N in SI).

    Raises
    ------
    FileFormatError
        Missing, foreign (another ANSYS file type included), truncated or inconsistent file.
    InvalidInputError
        A node or a component is not in the file, or a chosen freedom is constrained.
    RigidBodyModeError
        The model is not fixed enough to have a flexibility.
    UnsupportedProblemError
        Lumped mass or unsymmetric matrices (not read by ansys-mapdl-reader), or a chosen node
        whose freedoms are not the file's full DOF set (their labels cannot be told).
    MissingDependencyError
        ansys-mapdl-reader is not installed.

    Notes
    -----
    Constraint equations and coupled freedoms (``CE``, ``CP``) stored in the file are not read.
    """
    path = existing_file(path)
    chosen_components = [str(c).upper() for c in components]
    stiffness, labels, constrained, counts, n_dof_kinds = _read(path)
    for node in nodes:
        if node in counts and counts[node] != n_dof_kinds:
            raise UnsupportedProblemError(
                f"{path}: node {node} has {counts[node]} of the file's {n_dof_kinds} DOF kinds; "
                "which ones cannot be told from the file")
    with about(path):
        keep = freedom_indices(labels, nodes, chosen_components)
        names = [f"node {n} {c}" for n, c in labels]
        return reduced_model(stiffness, "stiffness", keep, np.flatnonzero(constrained), names,
                             dofs_per_node=len(chosen_components), symmetry_rtol=symmetry_rtol)

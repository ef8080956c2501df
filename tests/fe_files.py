"""Minimal writers of finite-element matrix files, for the importer tests.

* :func:`write_ansys_full`: an ANSYS ``.full`` file (no writer exists in ansys-mapdl-reader). The
  layout is what ``ansys.mapdl.reader.full.FullFile`` reads (its ``load_km`` and the Cython
  ``read_array``), after the MAPDL Programmer's Reference (fdfull.inc): records of 32-bit words
  ``[length][flags][data][pad]``, a 100-word standard header, the full-file header, the DOF
  reference numbers, the nodal equivalence table, then at ``ptrDOF`` the DOF count of each node
  and the constraint flags, and at ``ptrSTF`` the stiffness, one column per equation as an index
  record (1-based rows, each off-diagonal term once) and a value record.
* :func:`write_op4_binary`: a dense, double precision binary NASTRAN OUTPUT4 file (the binary
  writer of pyNastran 1.4 fails); Fortran records ``[bytes][data][bytes]``.
"""

from __future__ import annotations

import struct

import numpy as np
import scipy.sparse as sp

__all__ = ["write_ansys_full", "write_op4_binary"]

INT_FLAGS = 0x80000000  # type flag (bit 7 of the record's 8th byte): integer data
DOUBLE_FLAGS = 0
FULL_HEADER_WORDS = 160  # FULLHDLEN
# positions in the full-file header (SYMBOLIC_FULL_HEADER_KEYS of ansys-mapdl-reader)
NEQN, NMROW, NMATRX, LENBAC, NUMDOF, NTERMKL, NTERMKH, LUMPM, KEYUNS = 1, 2, 3, 6, 7, 8, 9, 10, 13
PTRSTF, PTREND, NNODES, PTRDOF = 18, 22, 32, 35


def _int_record(values) -> np.ndarray:
    data = np.asarray(values, dtype="<i4")
    return np.concatenate(([data.size], [INT_FLAGS], data, [0])).astype("<u4").view("<i4")


def _double_record(values) -> np.ndarray:
    data = np.asarray(values, dtype="<f8").view("<i4")
    return np.concatenate(([data.size, DOUBLE_FLAGS], data, [0])).astype("<i4")


def _split(value: int) -> tuple[int, int]:
    return value & 0xFFFFFFFF, value >> 32


def write_ansys_full(
    path, stiffness, nodes, dofs=(1, 2, 3), constrained=(), counts=None, version="20.1"
):
    """Write a symmetric stiffness as an ANSYS ``.full`` file.

    Parameters
    ----------
    path : str or os.PathLike
    stiffness : array_like or sparse, shape (neqn, neqn)
        Symmetric, equations in storage order: node by node (in the order of ``nodes``), each node
        with its DOFs in the order of ``dofs``. Constrained equations are written too, as MAPDL
        does.
    nodes : sequence of int
        Node numbers in storage order (need not be sorted).
    dofs : sequence of int
        DOF reference numbers of every node (1 UX, 2 UY, 3 UZ, 4 ROTX, ...).
    constrained : sequence of int
        Storage indices of the constrained equations.
    counts : sequence of int, optional
        Number of DOFs of each node (the first ones of ``dofs``); default: all of them.
    version : str
        MAPDL version written in the standard header (``"NN.N"``).
    """
    K = sp.csc_matrix(stiffness, dtype=float)
    neqn, n_nodes, numdof = K.shape[0], len(nodes), len(dofs)
    counts = np.full(n_nodes, numdof) if counts is None else np.asarray(counts)
    assert K.shape == (neqn, neqn) and neqn == counts.sum()
    lower = sp.tril(K, format="csc")
    lower.eliminate_zeros()

    standard = np.zeros(100, dtype="<i4")
    standard[0] = 4  # item 1: file number of a .full file
    standard[2], standard[4], standard[5] = 120000, 20261122, 1  # time, date, units (SI)
    standard[9] = np.frombuffer(version.encode()[::-1], dtype="<i4")[0]  # reversed characters

    const = np.zeros(neqn, dtype=int)
    const[list(constrained)] = -1
    head = np.zeros(FULL_HEADER_WORDS, dtype=np.int64)
    records = [_int_record(standard), None, _int_record(dofs), _int_record(nodes)]
    position = sum(r.size for r in records if r is not None) + FULL_HEADER_WORDS + 3
    ptr_dof = position
    records += [_int_record(counts), _int_record(const)]
    position += records[-2].size + records[-1].size
    ptr_stf = position
    for column in range(neqn):
        rows = lower.indices[lower.indptr[column] : lower.indptr[column + 1]]
        records.append(_int_record(rows + 1))
        records.append(_double_record(lower.data[lower.indptr[column] : lower.indptr[column + 1]]))
        position += records[-2].size + records[-1].size
    head[0], head[NEQN], head[NMROW], head[NMATRX] = -4, neqn, neqn, 1
    head[LENBAC], head[NUMDOF], head[NNODES] = n_nodes, numdof, n_nodes
    head[NTERMKL], head[NTERMKH] = _split(lower.nnz)
    head[PTRSTF], head[PTRSTF + 1] = _split(ptr_stf)
    head[PTRDOF], head[PTRDOF + 1] = _split(ptr_dof)
    head[PTREND], head[PTREND + 1] = _split(position)
    records[1] = _int_record(head.astype("<i4"))
    with open(path, "wb") as handle:
        for record in records:
            handle.write(record.astype("<i4").tobytes())


def write_op4_binary(path, matrices: dict, form: int = 6):
    """Write dense real matrices, double precision, as a little-endian binary OP4 file.

    Parameters
    ----------
    path : str or os.PathLike
    matrices : dict of str to ndarray
        Name (at most 8 characters) to matrix.
    form : int
        NASTRAN matrix form written in each header (6: symmetric, 1: square, 2: rectangular).
    """
    out = bytearray()

    def record(payload: bytes):
        out.extend(struct.pack("<i", len(payload)) + payload + struct.pack("<i", len(payload)))

    for name, matrix in matrices.items():
        A = np.asarray(matrix, dtype=float)
        nrows, ncols = A.shape
        record(struct.pack("<4i8s", ncols, nrows, form, 2, name.ljust(8).encode()))
        for column in range(ncols):
            nonzero = np.flatnonzero(A[:, column])
            if nonzero.size:
                first, last = nonzero[0], nonzero[-1] + 1
                record(
                    struct.pack("<3i", column + 1, first + 1, 2 * (last - first))
                    + A[first:last, column].astype("<f8").tobytes()
                )
        record(struct.pack("<3id", ncols + 1, 1, 2, 1.0))
    with open(path, "wb") as handle:
        handle.write(bytes(out))

"""Reduced models from the matrix files of finite-element codes.

=========================  ==================================  ===============================
Format                     Function                            Selection
=========================  ==================================  ===============================
ANSYS ``.full``            :func:`read_ansys_full`             node numbers, ``"UX"``, ...
NASTRAN OUTPUT4 ``.op4``   :func:`read_op4`                    row indices, ``fixed`` rows
NASTRAN DMIG (bulk data)   :func:`read_dmig`                   grids, components 1-6
MatrixMarket ``.mtx``      :func:`read_matrix_market`          row indices, ``fixed`` rows
unit-load CSV              :func:`read_unit_load_csv`          header ``NODE:COMPONENT``
=========================  ==================================  ===============================

Every reader returns a :class:`~contactqp.core.model.ReducedModel` whose freedoms are ordered node
by node, in the order of the chosen nodes and components. A stiffness is condensed to the chosen
freedoms by one sparse factorisation (static condensation, exact for a linear model); when every
free freedom is kept the model holds the stiffness itself. :func:`load_compliance` picks the
reader from the file's extension.

The ANSYS reader needs ``pip install 'contactqp[ansys]'`` (ansys-mapdl-reader), the NASTRAN
readers ``pip install 'contactqp[nastran]'`` (pyNastran, which requires numpy < 2);
``contactqp[importers]`` is both. They are imported when a file is read. Every error is one line
that starts with the file's path: :class:`~contactqp.errors.FileFormatError` for a missing,
foreign, truncated or malformed file, :class:`~contactqp.errors.InvalidInputError` for a
selection the file cannot satisfy or an inconsistent matrix,
:class:`~contactqp.errors.NotPositiveDefiniteError` (and
:class:`~contactqp.compliance.condensation.RigidBodyModeError`) for a model that is not fixed
enough.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ...core.model import ReducedModel
from ...errors import FileFormatError, InvalidInputError
from ._common import StrPath
from .ansys import read_ansys_full
from .csv_rows import read_unit_load_csv
from .matrixmarket import mtx_matrix, read_matrix_market
from .nastran import dmig_matrix, op4_matrix, read_dmig, read_op4

__all__ = [
    "load_compliance",
    "read_ansys_full",
    "read_op4",
    "op4_matrix",
    "read_dmig",
    "dmig_matrix",
    "read_matrix_market",
    "mtx_matrix",
    "read_unit_load_csv",
    "READERS",
]

#: File name endings and the reader :func:`load_compliance` chooses for them.
READERS: dict[tuple[str, ...], Callable[..., ReducedModel]] = {
    (".full",): read_ansys_full,
    (".op4",): read_op4,
    (".bdf", ".nas", ".dat", ".blk", ".bulk", ".pch"): read_dmig,
    (".mtx", ".mtx.gz"): read_matrix_market,
    (".csv", ".txt"): read_unit_load_csv,
}


def load_compliance(path: StrPath, *args: Any, **selection: Any) -> ReducedModel:
    """Read a reduced model with the reader chosen by the file's extension (see :data:`READERS`).

    Parameters
    ----------
    path : str or os.PathLike
    *args, **selection
        Passed to the reader, e.g. ``load_compliance("model.full", nodes=[12, 40])`` or
        ``load_compliance("K.mtx", kind="stiffness", freedoms=[0, 5])``.

    Returns
    -------
    ReducedModel

    Raises
    ------
    FileFormatError
        An extension no reader knows; otherwise the reader's errors.
    InvalidInputError
        Arguments the chosen reader does not take (or a required one missing).
    """
    name = Path(path).name.lower()
    for endings, reader in READERS.items():
        if name.endswith(endings):
            try:
                inspect.signature(reader).bind(path, *args, **selection)
            except TypeError as exc:
                raise InvalidInputError(f"{path}: {reader.__name__}: {exc}") from None
            return reader(path, *args, **selection)
    known = ", ".join(ending for endings in READERS for ending in endings)
    raise FileFormatError(f"{path}: cannot tell the format from the extension (known: {known})")

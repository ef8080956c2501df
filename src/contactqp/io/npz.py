"""Reading ``.npz`` archives whose damage (truncation, corruption, pickles) is a clear error."""

from __future__ import annotations

import zipfile
import zlib
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from ..errors import ContactError, FileFormatError

__all__ = ["open_npz"]

#: What numpy and zipfile raise on a damaged or foreign archive, while opening or reading it.
_DAMAGED = (zipfile.BadZipFile, zlib.error, EOFError, ValueError, OSError)


@contextmanager
def open_npz(path) -> Iterator[np.lib.npyio.NpzFile]:
    """Open an ``.npz`` archive for reading, without pickles.

    Use it as ``with open_npz(path) as data: array = data["key"]``: reading the arrays inside
    the ``with`` block is covered too, since a truncated archive may open and fail only on the
    member that is damaged (so keep the block to reading; check names in ``data.files``).

    Raises
    ------
    FileFormatError
        The file is not a readable ``.npz`` archive (not a zip file, truncated, a corrupt
        member, an object array that would need pickles), with the reason on one line.
    """
    try:
        if not zipfile.is_zipfile(path):
            raise FileFormatError("not a readable .npz archive (not a zip file)")
        with np.load(path, allow_pickle=False) as data:
            yield data
    except ContactError:
        raise
    except _DAMAGED as exc:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise FileFormatError(f"not a readable .npz archive ({reason})") from None

"""Content digests that identify a study's inputs (model, options, gap source) in its store."""

from __future__ import annotations

import hashlib

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["digest"]


def digest(*arrays: ArrayLike) -> str:
    """SHA-1 of the arrays' values as float64, in order (hex string)."""
    sha = hashlib.sha1()
    for array in arrays:
        sha.update(np.ascontiguousarray(array, dtype=float).tobytes())
    return sha.hexdigest()

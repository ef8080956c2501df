"""Statistics of a study's stored samples: per-contact mean, quantiles, probabilities of contact
and of a gap above a shim tolerance."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInputError

__all__ = ["GapStatistics", "gap_statistics", "shim_tolerance_value"]


@dataclass(frozen=True)
class GapStatistics:
    """Per-contact statistics of the final gaps over the successful samples.

    Attributes
    ----------
    samples : int
        Samples used.
    mean : ndarray, shape (m,)
        Mean final gap (m).
    levels : ndarray, shape (q,)
        Quantile levels.
    quantiles : ndarray, shape (q, m)
        Final-gap quantiles (m).
    contact_probability : ndarray, shape (m,)
        Fraction of samples in which the contact is closed.
    shim_tolerance : float or None
        The gap (m) above which a shim is needed; None when none was given.
    shim_probability : ndarray, shape (m,), or None
        Fraction of samples whose final gap is above ``shim_tolerance`` (strictly); None
        without a tolerance.
    """

    samples: int
    mean: np.ndarray
    levels: np.ndarray
    quantiles: np.ndarray
    contact_probability: np.ndarray
    shim_tolerance: float | None = None
    shim_probability: np.ndarray | None = None


def gap_statistics(
    fields: Mapping[str, np.ndarray],
    levels: Sequence[float] = (0.05, 0.5, 0.95),
    *,
    shim_tolerance: float | None = None,
) -> GapStatistics:
    """:class:`GapStatistics` of the records ``fields`` (one row per sample).

    Parameters
    ----------
    fields : dict of ndarray
        At least ``gap`` (m, shape (s, m)), ``closed`` (shape (s, m)) and ``success``
        (shape (s,)); only the successful rows count.
    levels : sequence of float
        Quantile levels in [0, 1].
    shim_tolerance : float, optional
        Gap (m, finite, >= 0) above which a pair needs a shim: gives ``shim_probability``.

    Raises
    ------
    InvalidInputError
        No successful sample, or a shim tolerance that is negative or not finite.
    """
    tolerance = None if shim_tolerance is None else shim_tolerance_value(shim_tolerance)
    ok = np.asarray(fields["success"], dtype=bool)
    if not ok.any():
        raise InvalidInputError("no successful sample to compute statistics from")
    gaps, closed = fields["gap"][ok], fields["closed"][ok]
    probabilities = np.asarray(levels, dtype=float)
    return GapStatistics(
        int(ok.sum()),
        gaps.mean(axis=0),
        probabilities,
        np.quantile(gaps, probabilities, axis=0),
        closed.mean(axis=0),
        tolerance,
        None if tolerance is None else (gaps > tolerance).mean(axis=0),
    )


def shim_tolerance_value(shim_tolerance: float) -> float:
    """``shim_tolerance`` as a float, checked: a gap (m), finite and >= 0.

    Raises
    ------
    InvalidInputError
        Negative, not finite, or not a number.
    """
    try:
        tolerance = float(shim_tolerance)
    except (TypeError, ValueError):
        tolerance = float("nan")
    if not (np.isfinite(tolerance) and tolerance >= 0):
        raise InvalidInputError(
            f"shim_tolerance must be a finite gap >= 0 (m), got {shim_tolerance!r}"
        )
    return tolerance

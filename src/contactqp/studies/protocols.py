"""What a study asks of its case and of its gap source (structural types, for type checkers).

:class:`~contactqp.studies.cases.GapVariation` and
:class:`~contactqp.applications.riveting.FasteningCase` are cases;
:class:`~contactqp.studies.sources.GaussianGapField` and
:class:`~contactqp.studies.sources.GapSamples` are sources. Any object with these methods will
do, picklable when the samples are solved by workers.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any, Protocol

import numpy as np

__all__ = ["StudyCase", "GapSource", "Record", "Chunk", "Task"]

#: One sample's fields, by name (see :meth:`StudyCase.fields`).
Record = dict[str, Any]
#: Solved consecutive samples: their indices and, per field, one row per sample.
Chunk = tuple[np.ndarray, dict[str, np.ndarray]]
#: Samples to solve consecutively, and the warm start of the first (None: cold).
Task = tuple[np.ndarray, np.ndarray | None]


class StudyCase(Protocol):
    """What one sample of a study solves."""

    @property
    def n_contacts(self) -> int:
        """Length of a gap field."""
        ...

    def fields(self) -> Mapping[str, tuple[tuple[int, ...], str]]:
        """``{name: (shape, dtype)}`` of one sample's record."""
        ...

    def solve_sample(
        self, gaps: np.ndarray, warm: np.ndarray | None
    ) -> tuple[Record, np.ndarray | None]:
        """``(record, warm start of the next sample)`` of the sample of gap field ``gaps``."""
        ...

    def warm_start(self, record: Mapping[str, Any]) -> np.ndarray:
        """The warm start a stored record gives to the next sample."""
        ...

    def describe(self) -> dict[str, Any]:
        """What identifies the case in a store."""
        ...


class GapSource(Protocol):
    """Where the gap fields of the samples come from."""

    @property
    def n_available(self) -> int | None:
        """Samples it holds; None for any number."""
        ...

    def realisations(self, indices: Iterable[int]) -> np.ndarray:
        """Gap fields of the samples ``indices``, one row each."""
        ...

    def describe(self) -> dict[str, Any]:
        """What identifies the source in a store."""
        ...

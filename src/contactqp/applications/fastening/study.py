"""The variation study of an assembly's fastening sequence: the case each sample solves.

:class:`SequenceVariation` is a :class:`~contactqp.studies.protocols.StudyCase` of
:func:`~contactqp.studies.run_batch`: each sample runs the whole fastening sequence of an
:class:`~contactqp.applications.fastening.Assembly` (every fastener in order, then the load
steps) on its own gap field, with or without friction, and records the last stage. The per-pair
statistics of a store (:meth:`~contactqp.studies.store.BatchData.statistics`, with a shim
tolerance) read its ``gap``, ``closed`` and ``success`` fields.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...core.status import ContactStatus
from ...errors import InvalidInputError
from ...studies.fingerprint import digest

__all__ = ["SequenceVariation"]

#: Where a sample's stages start from (:class:`SequenceVariation`).
STARTS = ("nominal", "previous")
#: The statuses counted as contact by the records' ``closed`` field.
IN_CONTACT = (ContactStatus.STICK, ContactStatus.SLIP, ContactStatus.CLOSED)


class SequenceVariation:
    """An assembly fastened over a gap field that varies by sample.

    The nominal sequence is solved once, on ``nominal_gaps``. With ``start="nominal"`` every
    stage of every sample is warm started from the same stage of it
    (``Assembly.sequence(..., r0=nominal)``); with ``start="previous"`` from the sample's own
    previous stage (the first one cold). Never from another sample: a sample's answer is the
    same whichever worker solves it and whatever it solved before.

    Records (one row per sample, the last stage unless said): ``gap`` residual gap (m, (k,)),
    ``normal_force`` (N, (k,)), ``closed`` (in contact: stick, slip or closed; a fastened pair
    is not counted), ``status`` (:class:`~contactqp.core.status.ContactStatus` codes),
    ``fastener_force`` (N, tension, installation order), ``dissipated`` (J, friction, every
    stage), ``success`` (every stage succeeded) and ``iterations`` (every stage's).

    Parameters
    ----------
    assembly : Assembly
        Its pairs, fasteners, friction and model (:mod:`contactqp.applications.fastening`).
    nominal_gaps : array_like, shape (k,)
        The gap field (m) of the nominal sequence, e.g. the gap source's mean.
    order, load_steps, method, **options
        As :meth:`~contactqp.applications.fastening.Assembly.sequence` takes them, the same for
        every sample.
    start : {"nominal", "previous"}
        Where each stage's solve starts from (above).

    Raises
    ------
    InvalidInputError
        Bad arguments (those of
        :meth:`~contactqp.applications.fastening.Assembly.sequence`, checked on the nominal
        sequence), or an unknown ``start``.
    """

    def __init__(
        self,
        assembly: Any,
        nominal_gaps: ArrayLike,
        *,
        order: Sequence[int] | None = None,
        load_steps: Sequence[tuple[str, ArrayLike]] = (),
        method: str | None = None,
        start: str = "nominal",
        **options: Any,
    ):
        if start not in STARTS:
            raise InvalidInputError(f"start must be one of {', '.join(STARTS)}, got {start!r}")
        self.start = start
        self.assembly = assembly
        self.order = None if order is None else [int(p) for p in np.asarray(order).reshape(-1)]
        self.load_steps = [
            (str(label), np.asarray(loads, dtype=float)) for label, loads in load_steps
        ]
        self.method = method
        self.options = dict(options)
        self.nominal_gaps = np.asarray(nominal_gaps, dtype=float)
        self.nominal = self._sequence(self.nominal_gaps, None)
        self.n_fasteners = len(self.nominal.final.fasteners)

    def _sequence(self, gaps: ArrayLike, warm: Any) -> Any:
        return self.assembly.sequence(
            gaps,
            order=self.order,
            load_steps=self.load_steps,
            method=self.method,
            r0=warm,
            **self.options,
        )

    @property
    def n_contacts(self) -> int:
        """Number of pairs ``k`` (the length of a gap field)."""
        return int(self.assembly.n_pairs)

    def fields(self) -> dict[str, tuple[tuple[int, ...], str]]:
        """``{name: (shape, dtype)}`` of one sample's record."""
        k = (self.n_contacts,)
        return {
            "gap": (k, "f8"),
            "normal_force": (k, "f8"),
            "closed": (k, "?"),
            "status": (k, "i1"),
            "fastener_force": ((self.n_fasteners,), "f8"),
            "dissipated": ((), "f8"),
            "success": ((), "?"),
            "iterations": ((), "i8"),
        }

    def record(self, sequence: Any) -> dict[str, Any]:
        """The record of a solved sequence (:meth:`fields`)."""
        final = sequence.final
        status = np.asarray(final.status)
        return {
            "gap": np.asarray(final.gaps, dtype=float),
            "normal_force": np.asarray(final.normal_forces, dtype=float),
            "closed": np.isin(status, IN_CONTACT),
            "status": status.astype(np.int8),
            "fastener_force": np.asarray(final.fastener_forces, dtype=float),
            "dissipated": float(sum(stage.dissipated for stage in sequence.stages)),
            "success": bool(sequence.success),
            "iterations": int(sum(stage.result.iterations for stage in sequence.stages)),
        }

    def solve_sample(self, gaps: np.ndarray, warm: Any) -> tuple[dict[str, Any], None]:
        """Run the sequence on the gap field ``gaps``: ``(record, None)`` (nothing is carried
        to the next sample; ``warm`` is not used)."""
        gaps = np.asarray(gaps, dtype=float)
        if gaps.shape != (self.n_contacts,):
            raise InvalidInputError(
                f"a gap field must have {self.n_contacts} values, got shape {gaps.shape}"
            )
        warm = self.nominal if self.start == "nominal" else None
        return self.record(self._sequence(gaps, warm)), None

    def warm_start(self, record: Any) -> np.ndarray:
        """Nothing: no sample starts from another (an empty array)."""
        return np.zeros(0)

    def describe(self) -> dict[str, Any]:
        """What identifies the case in a store: a digest of the assembly's model, pairs,
        friction, loads and nominal gaps, its fasteners, the order and the solver's options."""
        assembly = self.assembly
        model = assembly.model
        return {
            "type": type(self).__name__,
            "pairs": self.n_contacts,
            "digest": digest(
                model.as_given,
                assembly.pairs,
                assembly.normals,
                np.broadcast_to(assembly.mu, (self.n_contacts,)),
                self.nominal_gaps,
                *(loads for _, loads in self.load_steps),
            ),
            "model": model.given,
            "facets": repr(getattr(assembly, "facets", None)),
            "fasteners": [
                {key: repr(value) for key, value in dataclasses.asdict(fastener).items()}
                for fastener in assembly.fasteners
            ],
            "order": self.order,
            "load_steps": [label for label, _ in self.load_steps],
            "method": repr(self.method),
            "start": self.start,
            "options": {key: repr(value) for key, value in sorted(self.options.items())},
        }

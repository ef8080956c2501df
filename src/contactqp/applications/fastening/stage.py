"""The state of an assembly after each stage of its fastening sequence."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...core.result import ContactResult

__all__ = ["AssemblyStage", "AssemblySequence"]


@dataclass
class AssemblyStage:
    """The state after one stage: a fastener installed, or a load step.

    Per pair (``k`` of them, in the assembly's order):

    Attributes
    ----------
    label : str
        What the stage did, e.g. ``"fastener 3 (pair 120)"`` or ``"shear 50 N"``.
    gaps : ndarray, shape (k,)
        Residual gap (m).
    normal_forces : ndarray, shape (k,)
        Contact compression (N, >= 0). At fastened pairs: 0 for a closure (its force is in
        ``fastener_forces``), the compression the parts bear under a clamp.
    tangential_forces : ndarray, shape (k, 2)
        Friction force on the first part, in the pair's tangents ``(t1, t2)`` (N); zeros
        without friction.
    status : ndarray of int, shape (k,)
        :class:`~contactqp.core.status.ContactStatus` codes: open, stick, slip, closed
        (frictionless contact), fastened.
    slip : ndarray, shape (k, 2)
        This stage's relative tangential displacement increment, first part relative to the
        second, in ``(t1, t2)`` (m); zeros for 1-freedom models.
    fasteners : ndarray of int, shape (f_s,)
        Pair index of each installed fastener, in installation order.
    fastener_forces : ndarray, shape (f_s,)
        Axial force of each installed fastener (N), tension > 0 (pulling the parts together).
    result : ContactResult
        The certified result of the parts' own problem with the fastener forces as external
        loads (a :class:`~contactqp.core.result.FrictionalResult` with friction), on the
        pairs that are not fastened (its ``displacements`` are the assembly's); a violated
        fastener law fails it (status 2).
    """

    label: str
    gaps: np.ndarray
    normal_forces: np.ndarray
    tangential_forces: np.ndarray
    status: np.ndarray
    slip: np.ndarray
    fasteners: np.ndarray
    fastener_forces: np.ndarray
    result: ContactResult

    @property
    def success(self) -> bool:
        """True when the stage was solved, certified and its fasteners' laws hold."""
        return bool(self.result.success)

    @property
    def dissipated(self) -> float:
        """Energy dissipated by friction in the stage (J); 0 without friction."""
        dissipation = getattr(self.result, "dissipation", None)
        return 0.0 if dissipation is None else float(np.sum(dissipation))


@dataclass
class AssemblySequence:
    """Every stage of a fastening sequence, in order."""

    stages: list[AssemblyStage]

    @property
    def final(self) -> AssemblyStage:
        """The last stage."""
        return self.stages[-1]

    @property
    def success(self) -> bool:
        """True when every stage succeeded."""
        return all(stage.success for stage in self.stages)

    def __len__(self) -> int:
        return len(self.stages)

    def __getitem__(self, index: int) -> AssemblyStage:
        return self.stages[index]

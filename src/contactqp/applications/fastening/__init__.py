"""Assemblies of parts from the user's models, fastened one fastener at a time, with friction.

:class:`Assembly` joins :class:`AssemblyPart` s (each a reduced model with node coordinates) by
:class:`InterfacePairs` and :class:`Fastener` s; :meth:`Assembly.sequence` installs the
fasteners in order, then applies load steps, and returns an :class:`AssemblySequence` of
certified :class:`AssemblyStage` s (see :mod:`~contactqp.applications.fastening.sequence` for
the mechanics).
"""

from .model import Assembly
from .parts import AssemblyPart, Fastener, InterfacePairs
from .stage import AssemblySequence, AssemblyStage

__all__ = [
    "Assembly",
    "AssemblyPart",
    "AssemblySequence",
    "AssemblyStage",
    "Fastener",
    "InterfacePairs",
]

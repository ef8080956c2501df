"""Assembly files: parts, interfaces, gaps, fasteners, friction and loads described in TOML.

:func:`read_assembly_file` reads an ``ASSEMBLY.toml`` into an :class:`AssemblyInput`: every
part's reduced model and node coordinates (SI), the interfaces' node pairs and normals, the
nominal gaps and their variation, the fasteners in installation order, friction, the load steps
after fastening, the shim tolerance and the solver. The schema is ``docs/assembly-files.md``;
``examples/assemblies/`` holds examples.

==================  ==========================================================================
:mod:`.schema`      the keys each table accepts
:mod:`.parsing`     TOML file to :class:`AssemblyInput`
:mod:`.values`      typed values, units, CSV tables with headers
:mod:`.parts`       the parts' reduced models (matrix files, meshes, Kirchhoff plates)
:mod:`.pairing`     node pairs by proximity (KD-tree), geometric normals
:mod:`.gaps`        gaps interpolated from a measured point cloud, leave-one-out error
:mod:`.result`      :class:`AssemblyInput` and what it holds
==================  ==========================================================================
"""

from .gaps import InterpolationError
from .pairing import UnmatchedNodes
from .parsing import read_assembly_file
from .parts import PartInput
from .result import AssemblyInput, load_vector

__all__ = [
    "read_assembly_file",
    "AssemblyInput",
    "PartInput",
    "UnmatchedNodes",
    "InterpolationError",
    "load_vector",
]

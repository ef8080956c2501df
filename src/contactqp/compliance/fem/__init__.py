"""Embedded finite elements: linear elastic bodies meshed and assembled with scikit-fem.

A body is meshed (:func:`plate`, :func:`block`, :func:`bar`, or any file meshio reads through
:func:`read_mesh`), given a material and fixations (:class:`ElasticModel`), and reduced to the
flexibility of a few computational nodes by static condensation
(:meth:`ElasticModel.reduced_model`, or :func:`elastic_compliance` in one call). Full analyses
under nodal loads (:meth:`ElasticModel.solve`) check the reduction.

Units are SI throughout: metres, pascals, newtons. This package needs scikit-fem (and meshio to
read files): ``pip install 'contactqp[fem]'``.
"""

from ...optional import require

require("skfem", "finite elements", "fem", "scikit-fem")  # here once: every module imports it

from .elastic import ElasticModel, NodeSelection, elastic_compliance
from .meshes import bar, block, plate, read_mesh
from .selection import Box

__all__ = [
    "ElasticModel",
    "NodeSelection",
    "elastic_compliance",
    "Box",
    "bar",
    "block",
    "plate",
    "read_mesh",
]

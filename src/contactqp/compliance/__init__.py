"""Where flexibility matrices come from.

Submodules
----------
halfspace
    Analytic influence coefficients of a linear elastic half-space (Boussinesq, Love;
    Cerruti tangential and coupling terms).
fft_halfspace
    The same half-space (and a plane-strain half-plane) as matrix-free operators applied by
    FFT, non-periodic (zero padding) or periodic (Westergaard); the composite modulus.
condensation
    Flexibility of chosen freedoms of a sparse stiffness matrix by static condensation.
importers
    ANSYS ``.full``, NASTRAN OP4/DMIG, MatrixMarket and unit-load CSV files to reduced models
    (the ``importers`` extra for ANSYS and NASTRAN).
beam
    A 2-D Euler-Bernoulli frame (rods and beams), condensed to computational nodes.
fem
    Embedded finite elements (scikit-fem): elastic bodies reduced to computational nodes;
    imported on its own (``contactqp.compliance.fem``) because it needs the ``fem`` extra.
"""

from .condensation import condense, factorize
from .fft_halfspace import HalfPlaneOperator, HalfSpaceOperator, composite_modulus
from .halfspace import grid, influence_matrix, normal_influence
from .importers import load_compliance

__all__ = [
    "grid",
    "normal_influence",
    "influence_matrix",
    "HalfSpaceOperator",
    "HalfPlaneOperator",
    "composite_modulus",
    "condense",
    "factorize",
    "load_compliance",
]

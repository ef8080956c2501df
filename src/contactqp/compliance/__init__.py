"""Where flexibility matrices come from.

Submodules
----------
halfspace
    Analytic influence coefficients of a linear elastic half-space (Boussinesq, Love;
    Cerruti tangential and coupling terms).
condensation
    Flexibility of chosen freedoms of a sparse stiffness matrix by static condensation.
fem
    Embedded finite elements (scikit-fem): elastic bodies reduced to computational nodes;
    imported on its own (``contactqp.compliance.fem``) because it needs the ``fem`` extra.
"""

from .halfspace import grid, influence_matrix, normal_influence
from .importers import load_compliance
from .condensation import RigidBodyModeError, condense, factorize

__all__ = ["grid", "normal_influence", "influence_matrix"]
__all__ += ["condense", "factorize", "RigidBodyModeError"]

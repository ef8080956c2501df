"""Where flexibility matrices come from.

Submodules
----------
halfspace
    Analytic influence coefficients of a linear elastic half-space (Boussinesq, Love;
    Cerruti tangential and coupling terms).
"""

from .halfspace import grid, influence_matrix, normal_influence
from .importers import load_compliance

__all__ = ["grid", "normal_influence", "influence_matrix"]

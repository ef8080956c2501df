"""Where flexibility matrices come from.

Submodules
----------
halfspace
    Analytic influence coefficients of a linear elastic half-space (Boussinesq, Love).
"""

from .halfspace import grid, normal_influence

__all__ = ["grid", "normal_influence"]

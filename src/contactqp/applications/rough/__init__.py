"""Rough surfaces for the tribology user: self-affine random surfaces, measured height maps and
their contact with a rigid flat on an elastic half-space over a range of loads.

Submodules
----------
surface
    Self-affine random surfaces (Hurst exponent, roll-off and cut-offs, rms height or slope,
    seed) and the spectral rms height and slope.
heightmap
    Readers of measured height maps: CSV rows, NPY, and the ASCII grid with units.
contact
    The load sweep: a rigid flat on the periodic FFT half-space at increasing mean pressures;
    area fraction, mean gap, stiffness, and the linear area-load law.
output
    The area-load figure and the VTU grid of the surface.
"""

from .heightmap import HeightMap, read_height_map
from .surface import rms_height, rms_slope, self_affine_surface

__all__ = ["HeightMap", "read_height_map", "rms_height", "rms_slope", "self_affine_surface"]

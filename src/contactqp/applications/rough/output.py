"""What a rough contact writes: the area-load figure and the VTU grid of the surface.

:func:`rough_mesh` gives the mesh for :func:`~contactqp.io.export.write_vtu`
(``write_vtu(path, *rough_mesh(contact))``); :func:`plot_rough_contact` draws with
:func:`~contactqp.io.plot.plot_area_load`.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ...io.export import PointMesh
from ...io.plot import plot_area_load
from .contact import KAPPA_BGT, KAPPA_PERSSON, RoughContact

__all__ = ["rough_mesh", "plot_rough_contact"]


def rough_mesh(contact: RoughContact) -> PointMesh:
    """The surface's cells as the points of a quad grid, with their fields.

    Points are the cells' corners ``(i cell, j cell, h)`` (one per cell, z the height in m);
    the quads join neighbouring points (the period is not closed). Point fields: ``height``
    (m), and for each load ``k`` (in the order of the pressures) ``gap_k`` (m) and
    ``pressure_k`` (Pa); sheared (with friction), also ``shear_k`` (Pa, the tangential
    traction along x) and ``status_k`` (:class:`~contactqp.core.status.ContactStatus` codes:
    open, stick or slip).
    """
    surface = contact.surface
    ny, nx = surface.shape
    x, y = np.meshgrid(np.arange(nx) * surface.cell, np.arange(ny) * surface.cell)
    points = np.column_stack([x.ravel(), y.ravel(), surface.heights.ravel()])
    index = np.arange(nx * ny).reshape(ny, nx)
    quads = np.column_stack(
        [
            index[:-1, :-1].ravel(),
            index[:-1, 1:].ravel(),
            index[1:, 1:].ravel(),
            index[1:, :-1].ravel(),
        ]
    )
    data: dict[str, np.ndarray] = {"height": surface.heights.ravel()}
    for k, point in enumerate(contact.points):
        data[f"gap_{k}"] = point.gap_map(surface.shape).ravel()
        data[f"pressure_{k}"] = point.pressure_map(surface.shape, surface.cell).ravel()
        if point.sheared is not None:
            data[f"shear_{k}"] = np.asarray(point.sheared.forces[:, 1]) / surface.cell**2
            data[f"status_{k}"] = np.asarray(point.sheared.contact_status, dtype=float)
    return PointMesh(points, [("quad", quads)], data)


def plot_rough_contact(contact: RoughContact, path: str | os.PathLike[str]) -> Path:
    """The area fraction against the mean pressure beside the linear laws of Persson
    (:data:`~contactqp.applications.rough.contact.KAPPA_PERSSON`) and of Bush, Gibson and
    Thomas (:data:`~contactqp.applications.rough.contact.KAPPA_BGT`), and the contact
    pressure at the largest load."""
    scale = contact.modulus * contact.rms_slope
    last = contact.points[-1]
    surface = contact.surface
    laws = (
        {  # none for a flat surface
            "Persson, kappa = sqrt(8/pi)": KAPPA_PERSSON / scale,
            "Bush-Gibson-Thomas, kappa = sqrt(2 pi)": KAPPA_BGT / scale,
        }
        if scale > 0
        else {}
    )
    return plot_area_load(
        [point.pressure for point in contact.points],
        [point.area_fraction for point in contact.points],
        laws,
        last.pressure_map(surface.shape, surface.cell),
        surface.cell,
        path,
        title=f"{surface.shape[1]} x {surface.shape[0]} cells, E* = {contact.modulus:.4g} Pa, "
        f"h'rms = {contact.rms_slope:.4g}",
    )

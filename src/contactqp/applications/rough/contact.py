r"""A rigid flat pressed onto a periodic rough surface: contact area, mean gap and stiffness
against the mean pressure.

Model
-----
One period of the surface (a :class:`~contactqp.applications.rough.heightmap.HeightMap` of
square cells, heights ``h``) is the surface of an elastic half-space of Young's modulus ``E``
and Poisson's ratio ``nu``; a rigid flat comes down on it (equivalently, a rigid rough surface
on an elastic flat; for two elastic bodies give the composite modulus). The compliance is the
periodic (Westergaard, spectral) half-space operator
:class:`~contactqp.compliance.fft_halfspace.HalfSpaceOperator`, which never forms ``W``; the
initial gap of cell ``i`` is ``s_i = max(h) - h_i``. Each mean pressure ``p`` (Pa, over the
whole period) is the fixed total load ``P = p L_x L_y`` of a
:class:`~contactqp.core.surface.SurfaceProblem`, solved by the kind's default matrix-free method
(a constrained conjugate gradient), each load warm-started from the previous one scaled by the
ratio of the loads. Every answer is certified (penetration, force sign, complementarity, load
balance, through one operator product).

Per load
--------
``area_fraction``
    The fraction of cells in contact (a positive force).
``mean_gap``
    The mean of the gaps over the period (m).
``stiffness``
    The normal contact stiffness per unit area :math:`k = -\mathrm{d}p / \mathrm{d}\bar g`
    (Pa/m), by finite differences on the loads' mean gaps (second order,
    :func:`numpy.gradient` on unequal steps); None for a single load and in full contact.

With friction (``mu > 0``)
    Each pressed state is then sheared along ``x`` by the tangential force
    ``Q = shear * mu * P`` (``0 < shear < 1``, force fixed, the shift the unknown: the periodic
    :class:`~contactqp.core.sliding_surface.SlidingSurfaceProblem`), Coulomb's law on each
    cell with the normal-tangential coupling of the half-space neglected (Cattaneo and
    Mindlin's assumption: exact for two elastically similar bodies; the pressure is then that
    of the frictionless solve). Per load: ``stick_fraction``, the fraction of the contact that
    sticks; ``shift``, the tangential displacement of the flat against the surface's mean
    (m); ``tangential_stiffness`` ``Q / (L_x L_y shift)`` (Pa/m), the interface's secant
    stiffness. Every answer is certified by the Coulomb problem's natural map.

Linear law
----------
At small loads the real contact area grows in proportion to the load,

.. math::

   \frac{A}{A_0} = \kappa \frac{p}{E^* h'_\mathrm{rms}}, \qquad E^* = \frac{E}{1 - \nu^2},

with :math:`h'_\mathrm{rms}` the rms slope
(:func:`~contactqp.applications.rough.surface.rms_slope`).
Persson's theory gives :math:`\kappa = \sqrt{8/\pi} \approx 1.60`, the asperity model of Bush,
Gibson and Thomas :math:`\kappa = \sqrt{2\pi} \approx 2.51`; exact numerical solutions fall
between them, near 2 (Hyun et al.).

References
----------
A. W. Bush, R. D. Gibson and T. R. Thomas, "The elastic contact of a rough surface", Wear 35
(1975) 87-111.
B. N. J. Persson, "Theory of rubber friction and contact mechanics", J. Chem. Phys. 115 (2001)
3840-3861.
S. Hyun, L. Pei, J.-F. Molinari and M. O. Robbins, "Finite-element analysis of contact between
elastic self-affine surfaces", Phys. Rev. E 70 (2004) 026117.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ...errors import InvalidInputError
from .heightmap import HeightMap
from .surface import rms_slope

__all__ = ["KAPPA_PERSSON", "KAPPA_BGT", "LoadPoint", "RoughContact", "solve_rough_contact"]

#: Persson's coefficient of the linear area-load law, :math:`\sqrt{8/\pi}`.
KAPPA_PERSSON = math.sqrt(8 / math.pi)
#: Bush, Gibson and Thomas's coefficient, :math:`\sqrt{2\pi}`.
KAPPA_BGT = math.sqrt(2 * math.pi)


@dataclass(frozen=True)
class LoadPoint:
    """The answer at one mean pressure.

    Attributes
    ----------
    pressure : float
        Mean pressure over the period (Pa).
    area_fraction : float
        Fraction of the cells in contact.
    mean_gap : float
        Mean gap over the period (m).
    stiffness : float or None
        ``-dp / d(mean gap)`` (Pa/m) by finite differences over the loads; None for one load
        or in full contact (the gap closed: infinitely stiff).
    seconds, iterations :
        The solve's wall time (s) and iterations.
    certificate : bool
        The method converged and its answer passed the certificate (``result.success``; with
        friction, the sheared state's as well).
    result : SurfaceResult
        The solve's full result (forces in N per cell, gaps, certificate).
    sheared : SlidingSurfaceResult or None
        With friction, the sheared state's result (forces ``(p, t_x, t_y)`` per cell); the
        properties ``stick_fraction``, ``shift`` and ``tangential_stiffness`` read it.
    """

    pressure: float
    area_fraction: float
    mean_gap: float
    stiffness: float | None
    seconds: float
    iterations: int
    certificate: bool
    result: Any = field(repr=False, compare=False)
    sheared: Any = field(default=None, repr=False, compare=False)

    @property
    def stick_fraction(self) -> float | None:
        """With friction, the fraction of the contact that sticks (the sheared result's own
        statuses: stick over stick and slip); else None."""
        if self.sheared is None:
            return None
        stick = int(np.count_nonzero(self.sheared.stick))
        return stick / max(1, stick + int(np.count_nonzero(self.sheared.slip)))

    @property
    def shift(self) -> float | None:
        """With friction, the shift of the flat along x against the surface's mean (m)."""
        return None if self.sheared is None else float(self.sheared.shift[0])

    @property
    def tangential_stiffness(self) -> float | None:
        """With friction, the secant ``Q / (area shift)`` (Pa/m; None at no shift)."""
        shift = self.shift
        if shift is None or not shift > 0:
            return None
        area = self.result.load / self.pressure
        return float(self.sheared.tangential_force[0]) / (area * shift)

    def as_record(self) -> dict[str, Any]:
        """A JSON-ready dict of the scalar fields (SI units); the frictional ones with
        friction only."""
        record = {
            "pressure": self.pressure,
            "area_fraction": self.area_fraction,
            "mean_gap": self.mean_gap,
            "stiffness": self.stiffness,
            "seconds": self.seconds,
            "iterations": self.iterations,
            "certificate": self.certificate,
        }
        if self.sheared is not None:
            record.update(
                stick_fraction=self.stick_fraction,
                shift=self.shift,
                tangential_stiffness=self.tangential_stiffness,
            )
        return record

    def pressure_map(self, shape: tuple[int, int], cell: float) -> np.ndarray:
        """The contact pressure (Pa) of each cell, shape ``(ny, nx)``."""
        return np.asarray(self.result.forces, dtype=float).reshape(shape) / cell**2

    def gap_map(self, shape: tuple[int, int]) -> np.ndarray:
        """The gap (m) of each cell, shape ``(ny, nx)``."""
        return np.asarray(self.result.gaps, dtype=float).reshape(shape)


@dataclass(frozen=True)
class RoughContact:
    """A surface, its material and the answers at increasing mean pressures.

    Attributes
    ----------
    surface : HeightMap
    young, poisson : float
        Young's modulus (Pa) and Poisson's ratio of the half-space.
    points : list of LoadPoint
        One per pressure, in increasing pressure.
    """

    surface: HeightMap
    young: float
    poisson: float
    points: list[LoadPoint]
    mu: float = 0.0
    shear: float | None = None

    @property
    def modulus(self) -> float:
        """The plane-strain modulus :math:`E^* = E / (1 - \\nu^2)` (Pa)."""
        return self.young / (1 - self.poisson**2)

    @property
    def rms_slope(self) -> float:
        """The surface's spectral rms slope."""
        return rms_slope(self.surface.heights, self.surface.cell)

    @property
    def solved(self) -> bool:
        """Every load passed its certificate."""
        return all(point.certificate for point in self.points)

    def linear_law(self, pressure, kappa: float = KAPPA_PERSSON):
        """:math:`\\kappa p / (E^* h'_\\mathrm{rms})`: the small-load area fraction (inf for a
        flat surface, where the law does not apply)."""
        with np.errstate(divide="ignore"):
            return kappa * np.asarray(pressure, dtype=float) / (self.modulus * self.rms_slope)


def solve_rough_contact(
    surface: HeightMap,
    pressures: Sequence[float],
    *,
    young: float = 210e9,
    poisson: float = 0.3,
    mu: float = 0.0,
    shear: float = 0.5,
    progress: Callable[[int, int], None] | None = None,
    **options: Any,
) -> RoughContact:
    """Press a rigid flat onto ``surface`` at each mean pressure (see the module's model).

    Parameters
    ----------
    surface : HeightMap
        One period of the surface (heights and cell in m).
    pressures : sequence of float
        Mean pressures over the period (Pa), positive, strictly increasing.
    young, poisson : float
        Young's modulus (Pa, > 0) and Poisson's ratio (in [0, 0.5)) of the half-space.
    mu : float
        Friction coefficient, >= 0; above 0 each load is then sheared (module notes).
    shear : float
        With friction, the tangential force over the friction limit, ``Q / (mu P)``, in (0, 1).
    progress : callable, optional
        Called as ``progress(done, total)`` after each load.
    **options
        Passed to the normal solve's method (e.g. ``tol``; ``tol`` to the sheared one too).

    Returns
    -------
    RoughContact

    Raises
    ------
    InvalidInputError
        No pressures, a pressure not positive and finite or not above the one before, a
        modulus not positive, a Poisson ratio out of range, ``mu`` negative or not finite, or
        ``shear`` outside (0, 1).
    """
    from ...compliance.fft_halfspace import HalfSpaceOperator
    from ...core.sliding_surface import SlidingSurfaceProblem
    from ...core.surface import SurfaceProblem
    from ...methods import solve

    p = np.asarray(pressures, dtype=float)
    if p.ndim != 1 or p.size == 0:
        raise InvalidInputError("give at least one pressure")
    if not (np.all(np.isfinite(p)) and np.all(p > 0)):
        raise InvalidInputError(f"pressures must be positive and finite (Pa), got {p.tolist()}")
    if np.any(np.diff(p) <= 0):
        raise InvalidInputError(f"pressures must increase, got {p.tolist()}")
    if not (math.isfinite(young) and young > 0):
        raise InvalidInputError(f"young must be a positive modulus (Pa), got {young!r}")
    if not (math.isfinite(poisson) and 0 <= poisson < 0.5):
        raise InvalidInputError(f"poisson must be in [0, 0.5), got {poisson!r}")
    if not (math.isfinite(mu) and mu >= 0):
        raise InvalidInputError(f"mu must be a friction coefficient >= 0, got {mu!r}")
    if mu > 0 and not (math.isfinite(shear) and 0 < shear < 1):
        raise InvalidInputError(f"shear must be Q / (mu P) in (0, 1), got {shear!r}")
    ny, nx = surface.shape
    cell = surface.cell
    operator = HalfSpaceOperator(nx, ny, cell, cell, young, poisson, periodic=True)
    full = None
    if mu > 0:
        full = HalfSpaceOperator(
            nx, ny, cell, cell, young, poisson, periodic=True, components="full", coupling=False
        )
    heights = surface.heights.ravel()
    separation = heights.max() - heights
    area = nx * ny * cell**2
    results, sheared = [], []
    previous: tuple[float, np.ndarray] | None = None
    for k, pressure in enumerate(p):
        problem = SurfaceProblem(operator, separation, load=float(pressure * area))
        r0 = None if previous is None else previous[1] * (pressure / previous[0])
        result = solve(problem, r0=r0, **options)
        results.append(result)
        previous = (float(pressure), np.asarray(result.forces, dtype=float))
        if full is not None:
            force = (shear * mu * float(pressure * area), 0.0)
            sliding = SlidingSurfaceProblem(problem, full, mu, force=force)
            tol = {"tol": options["tol"]} if "tol" in options else {}
            sheared.append(solve(sliding, p0=result.forces, **tol))
        if progress is not None:
            progress(k + 1, p.size)
    gaps = np.array([float(np.mean(result.gaps)) for result in results])
    stiffness: list[float | None] = [None] * p.size
    if p.size > 1:
        with np.errstate(all="ignore"):  # equal mean gaps (full contact): no finite stiffness
            slopes = -np.gradient(p, gaps)
        stiffness = [float(value) if np.isfinite(value) else None for value in slopes]
    for k, result in enumerate(results):  # full contact: the gap is closed, no finite stiffness
        if result.contact_fraction == 1.0:
            stiffness[k] = None
    points = [
        LoadPoint(
            pressure=float(pressure),
            area_fraction=float(result.contact_fraction),
            mean_gap=float(gap),
            stiffness=k,
            seconds=float(result.seconds),
            iterations=int(result.iterations),
            certificate=bool(result.success),
            result=result,
        )
        for pressure, result, gap, k in zip(p, results, gaps, stiffness, strict=True)
    ]
    if full is not None:
        points = [
            _with_shear(point, shearing) for point, shearing in zip(points, sheared, strict=True)
        ]
    return RoughContact(
        surface, float(young), float(poisson), points, float(mu), shear if mu > 0 else None
    )


def _with_shear(point: LoadPoint, sheared) -> LoadPoint:
    """``point`` with its sheared state (see the module notes)."""
    return replace(
        point,
        seconds=point.seconds + float(sheared.seconds),
        iterations=point.iterations + int(sheared.iterations),
        certificate=point.certificate and bool(sheared.success),
        sheared=sheared,
    )

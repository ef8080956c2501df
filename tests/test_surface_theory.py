"""Surface problems on the FFT half-space against closed-form contact mechanics.

Each answer is certified; the comparisons with theory are limited by the discretisation (square
cells of uniform pressure, collocated at their centres), and each tolerance says by how much:

* Hertz [Johnson1985c]_ (rigid sphere, 256 x 256 cells, contact radius 64 cells): load at a given
  approach, approach at a given load, contact radius, peak pressure and the pressure profile;
* a rigid flat punch (Boussinesq): total force ``F = 2 a E* delta`` converging at first order
  in the cell size, the punch face in contact and nothing else, and the edge singularity
  ``p ~ 1 / sqrt(a - r)`` showing as an edge-to-centre pressure ratio growing as
  ``sqrt(a / dx)``;
* a periodic wavy surface (Westergaard): the full-contact pressure ``p_mean + p* cos`` exactly,
  and Johnson's partial-contact solution (contact width and pressure).

.. [Johnson1985c] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985: Hertz
   sec. 3.4 and 4.2; the flat punch, sec. 3.8 (eq. 3.35); the wavy surface, sec. 13.2.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import contactqp as cq
from contactqp.compliance import grid
from contactqp.compliance.fft_halfspace import HalfSpaceOperator

E, NU = 210e9, 0.3
E_STAR = E / (1 - NU**2)
SIDE = 1e-3  # m, side of the grid


def centred_grid(n: int):
    dx = SIDE / n
    x, y = grid(n, n, dx, dx)
    return x - x.mean(), y - y.mean(), dx


# --- Hertz -----------------------------------------------------------------------------------

RADIUS, A = 5e-3, 0.25e-3  # sphere radius, contact radius (m): 64 cells on 256 x 256
DELTA = A**2 / RADIUS  # Hertz's approach for that contact radius
LOAD = 4 / 3 * E_STAR * RADIUS**0.5 * DELTA**1.5
P0 = 3 * LOAD / (2 * np.pi * A**2)


@pytest.fixture(scope="module")
def hertz():
    x, y, dx = centred_grid(256)
    W = HalfSpaceOperator(256, 256, dx, dx, E, NU)
    s = (x**2 + y**2) / (2 * RADIUS)
    at_approach = cq.solve(cq.SurfaceProblem(W, s, approach=DELTA))
    at_load = cq.solve(cq.SurfaceProblem(W, s, load=LOAD))
    return np.hypot(x, y), dx, at_approach, at_load


def test_hertz_load_and_approach(hertz):
    _, _, at_approach, at_load = hertz
    assert at_approach.success and at_load.success, (at_approach.message, at_load.message)
    # the discretisation error falls as (dx / a)^2: 3.4e-4, 7e-5 and 1.9e-5 at 16, 32 and 64
    # cells per radius; 1e-4 is five times the error at 64
    assert at_approach.load == pytest.approx(LOAD, rel=1e-4)
    assert at_load.load == pytest.approx(LOAD, rel=1e-13)
    assert at_load.approach == pytest.approx(DELTA, rel=1e-4 / 1.5)  # P ~ delta^1.5


def test_hertz_contact_radius_and_pressure(hertz):
    r, dx, at_approach, at_load = hertz
    for result in (at_approach, at_load):
        # the contact's area as a circle: its edge is resolved to a cell (0.08 cells here)
        radius = np.sqrt(result.contact.sum() * dx**2 / np.pi)
        assert abs(radius - A) < 0.5 * dx
        # outside the sphere's Hertz circle no force, inside every cell pressed
        assert not np.any(result.contact[r > A + dx]) and np.all(result.contact[r < A - dx])
        pressure = result.forces / dx**2
        assert pressure.max() == pytest.approx(P0, rel=2e-4)  # 5e-5 seen
        # the profile p0 sqrt(1 - r^2/a^2) away from the edge, where cells average the root
        profile = P0 * np.sqrt(np.maximum(1 - (r / A) ** 2, 0.0))
        inner = r < 0.9 * A
        assert np.max(np.abs(pressure - profile)[inner]) < 5e-4 * P0  # 8.5e-5 seen


# --- flat punch ----------------------------------------------------------------------------

PUNCH = 0.25e-3  # punch radius (m)


@functools.cache
def punch(n: int):
    """A flat rigid punch pressed ``1 um`` in: the separation is 0 on the punch's face (the cells
    whose centres lie within its radius) and, outside, more than any approach (no indenter)."""
    x, y, dx = centred_grid(n)
    r = np.hypot(x, y)
    face = r < PUNCH
    depth = 1e-6
    W = HalfSpaceOperator(n, n, dx, dx, E, NU)
    result = cq.solve(cq.SurfaceProblem(W, np.where(face, 0.0, 10 * depth), approach=depth))
    assert result.success, result.message
    radius = np.sqrt(face.sum() * dx**2 / np.pi)  # of the discretised face
    return result, face, r, dx, radius, 2 * radius * E_STAR * depth


def test_flat_punch_against_boussinesq():
    errors = []
    for n in (128, 256):
        result, face, r, dx, radius, force = punch(n)
        np.testing.assert_array_equal(result.contact, face)  # the face, nothing else
        error = result.load / force - 1
        # the uniform pressure of the edge cells misses part of the singular edge load: a
        # first-order error, -0.23 dx / a here; a quarter of a cell per radius bounds it
        assert abs(error) < 0.25 * dx / radius
        errors.append(error)
        # the centre: p(0) = F / (2 pi a^2), the same first-order error
        centre = result.forces[np.argmin(r)] / dx**2
        assert centre == pytest.approx(force / (2 * np.pi * radius**2), rel=0.25 * dx / radius)
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.2)  # first order: 1.96 seen


def test_flat_punch_edge_singularity():
    ratios, cells = [], []
    for n in (128, 256):
        result, face, r, dx, radius, _ = punch(n)
        pressure = result.forces / dx**2
        # the largest pressure sits on the edge, growing like 1 / sqrt(a - r) at one cell in
        edge = np.argmax(pressure)
        assert radius - dx < r[edge] < radius
        ratios.append(pressure[edge] / pressure[np.argmin(r)])
        cells.append(radius / dx)
    assert ratios[1] > ratios[0] > 5.0
    # edge over centre ~ sqrt(a / dx): 1.384 seen for sqrt(2) = 1.414
    assert ratios[1] / ratios[0] == pytest.approx(np.sqrt(cells[1] / cells[0]), rel=0.05)


# --- periodic wavy surface -----------------------------------------------------------------

WAVELENGTH, AMPLITUDE = 1e-3, 1e-6
P_STAR = np.pi * E_STAR * AMPLITUDE / WAVELENGTH  # mean pressure for full contact


def wavy(nx: int, ratio: float, ny: int = 4):
    """A sinusoidal surface ``s = Delta (1 - cos(2 pi x / lambda))`` (one period along x,
    uniform along y) under the mean pressure ``ratio * p*``."""
    dx = WAVELENGTH / nx
    x, _ = grid(nx, ny, dx, dx)
    W = HalfSpaceOperator(nx, ny, dx, dx, E, NU, periodic=True)
    s = AMPLITUDE * (1 - np.cos(2 * np.pi * x / WAVELENGTH))
    mean = ratio * P_STAR
    result = cq.solve(cq.SurfaceProblem(W, s, load=mean * WAVELENGTH * ny * dx))
    assert result.success, result.message
    return result, np.where(x > WAVELENGTH / 2, x - WAVELENGTH, x), dx, mean


@pytest.mark.parametrize("nx", [64, 256])
def test_wavy_surface_in_full_contact_is_westergaards(nx):
    result, x, dx, mean = wavy(nx, 2.0)
    assert result.contact_fraction == 1.0
    # a cosine mode of the grid is an exact eigenvector of the periodic operator: the
    # pressure is the closed form to rounding
    westergaard = mean + P_STAR * np.cos(2 * np.pi * x / WAVELENGTH)
    np.testing.assert_allclose(result.forces / dx**2, westergaard, rtol=0, atol=1e-12 * P_STAR)


def test_wavy_surface_in_partial_contact_is_johnsons():
    result, x, dx, mean = wavy(512, 0.5)
    # sin^2(pi a / lambda) = p_mean / p*: a = lambda / 4 here
    sine2 = 0.5
    a = WAVELENGTH / np.pi * np.arcsin(np.sqrt(sine2))
    rows = result.contact.reshape(4, 512)
    assert np.all(rows == rows[0])  # uniform along y
    assert abs(rows[0].sum() - 2 * a / dx) <= 2  # the edge cells either side
    pressure = result.forces / dx**2
    sines = np.maximum(sine2 - np.sin(np.pi * x / WAVELENGTH) ** 2, 0.0)
    johnson = np.where(
        np.abs(x) < a, 2 * mean * np.cos(np.pi * x / WAVELENGTH) / sine2 * np.sqrt(sines), 0.0
    )
    inner = np.abs(x) < 0.8 * a
    # the square-root edge is cell-averaged: 0.8 % of p* near the edge (0.4 % at 1024 cells)
    assert np.max(np.abs(pressure - johnson)[inner]) < 2e-3 * P_STAR
    assert np.max(np.abs(pressure - johnson)) < 2e-2 * P_STAR

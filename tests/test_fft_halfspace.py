"""The FFT half-space and half-plane operators against independent truths.

Non-periodic: the dense influence matrices of :mod:`contactqp.compliance.halfspace` (products
to 1e-12 relative: an FFT of a few hundred points rounds at ~1e-15), and for the half-plane a
quadrature of the line-load kernel. Periodic: closed-form Westergaard displacements of
sinusoidal tractions, which a grid mode reproduces to rounding (the kernel is spectral).
"""

from __future__ import annotations

import concurrent.futures
import math
import pickle
import sys

import numpy as np
import pytest
import scipy.integrate

from contactqp.compliance import (
    HalfPlaneOperator,
    HalfSpaceOperator,
    composite_modulus,
    grid,
    influence_matrix,
    normal_influence,
)
from contactqp.core.operators import as_operator
from contactqp.errors import InvalidInputError, MissingDependencyError, UnsupportedProblemError

E, NU = 210e9, 0.3
GRIDS = [(1, 1, 1e-3, 1e-3), (7, 1, 1e-3, 2e-3), (1, 6, 2e-3, 1e-3), (5, 3, 1e-3, 2e-3),
         (8, 6, 1.5e-3, 1e-3), (13, 16, 1e-3, 1e-3)]  # fmt: skip
#: both FFT libraries (pyFFTW comes with the test extra)
FFTS = ["scipy", "pyfftw"]
#: FFT products round at a few 1e-16 relative per transform on these sizes
PRODUCT_RTOL = 1e-12


def relative(a, b) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize("fft", FFTS)
@pytest.mark.parametrize(("nx", "ny", "dx", "dy"), GRIDS)
def test_normal_products_equal_the_dense_love_matrix(nx, ny, dx, dy, fft):
    rng = np.random.default_rng(nx * 100 + ny)
    W = HalfSpaceOperator(nx, ny, dx, dy, E, NU, fft=fft)
    assert W.fft == fft
    R = normal_influence(*grid(nx, ny, dx, dy), dx, dy, E, NU)
    assert W.shape == R.shape
    f = rng.standard_normal(nx * ny)
    F = rng.standard_normal((nx * ny, 3))
    assert relative(W @ f, R @ f) < PRODUCT_RTOL
    assert (W @ F).shape == F.shape
    assert (W @ np.empty((nx * ny, 0))).shape == (nx * ny, 0)
    assert relative(W @ F, R @ F) < PRODUCT_RTOL
    assert relative(W @ np.abs(f), R @ np.abs(f)) < PRODUCT_RTOL  # one-signed, like pressures


@pytest.mark.parametrize("fft", FFTS)
@pytest.mark.parametrize(("nx", "ny", "dx", "dy"), GRIDS)
@pytest.mark.parametrize(("poisson", "coupling"), [(0.3, True), (0.3, False), (-0.4, True)])
def test_full_products_equal_the_dense_cerruti_matrix(nx, ny, dx, dy, poisson, coupling, fft):
    rng = np.random.default_rng(nx * 100 + ny)
    W = HalfSpaceOperator(nx, ny, dx, dy, E, poisson, components="full", coupling=coupling, fft=fft)
    R = influence_matrix(*grid(nx, ny, dx, dy), dx, dy, E, poisson, coupling=coupling)
    assert W.shape == R.shape
    f = rng.standard_normal(3 * nx * ny)
    F = rng.standard_normal((3 * nx * ny, 2))
    assert relative(W @ f, R @ f) < PRODUCT_RTOL
    assert relative(W @ F, R @ F) < PRODUCT_RTOL
    for zero in (2, 0):  # a component zero everywhere (the operator skips its transforms)
        g = f.copy()
        g[zero::3] = 0.0
        assert relative(W @ g, R @ g) < PRODUCT_RTOL
    if nx > 1 and coupling:  # the odd coupling terms (along x) are there, with their signs
        tangential = np.zeros(3 * nx * ny)
        tangential[0::3] = rng.random(nx * ny)
        normal_part = (W @ tangential)[2::3]
        assert np.max(np.abs(normal_part)) > 1e-3 * np.max(np.abs(W @ tangential))
        assert relative(normal_part, (R @ tangential)[2::3]) < PRODUCT_RTOL


@pytest.mark.parametrize("components", ["normal", "full"])
def test_blocks_and_diagonals_are_the_dense_entries(components):
    nx, ny, dx, dy = 6, 5, 1e-3, 1.5e-3
    W = HalfSpaceOperator(nx, ny, dx, dy, E, NU, components=components)
    x, y = grid(nx, ny, dx, dy)
    R = (
        normal_influence(x, y, dx, dy, E, NU)
        if components == "normal"
        else influence_matrix(x, y, dx, dy, E, NU)
    )
    n = R.shape[0]
    rng = np.random.default_rng(3)
    rows = rng.permutation(n)[: n // 3]
    mask = rng.random(n) < 0.4
    # the same closed forms evaluated on the same offsets: equal to the last bit or two
    np.testing.assert_allclose(W.block(), R, rtol=1e-14, atol=0)
    np.testing.assert_allclose(W.block(rows, mask), R[rows][:, mask], rtol=1e-14, atol=0)
    np.testing.assert_allclose(W.block(slice(2, 9), rows), R[2:9][:, rows], rtol=1e-14, atol=0)
    np.testing.assert_allclose(W.diagonal(), np.diag(R), rtol=1e-14, atol=0)
    size = 1 if components == "normal" else 3
    dense = as_operator(R)
    np.testing.assert_allclose(
        W.diagonal_blocks(size), dense.diagonal_blocks(size), rtol=1e-14, atol=0
    )
    if components == "full":  # another size: the generic path of the base class
        np.testing.assert_allclose(
            W.diagonal_blocks(2), dense.diagonal_blocks(2), rtol=1e-14, atol=0
        )
    factor = W.cholesky(rows)  # the base class's factorisation works on the blocks
    principal = R[np.ix_(np.sort(rows), np.sort(rows))]
    scale = np.max(principal)
    np.testing.assert_allclose(factor.lower @ factor.lower.T, principal, atol=1e-14 * scale)


def test_the_operator_never_forms_its_matrix():
    W = HalfSpaceOperator(4, 4, 1e-3, 1e-3, E, NU)
    with pytest.raises(UnsupportedProblemError, match="HalfSpaceOperator does not form one"):
        _ = W.matrix
    assert as_operator(W) is W


def westergaard_grid(nx, ny, dx, dy):
    x, y = grid(nx, ny, dx, dy)
    return x, y, nx * dx, ny * dy


WAVY = [
    (nx, ny, dx, dy, mx, my)
    for nx, ny, dx, dy in [(32, 1, 1e-3, 1e-3), (16, 12, 1e-3, 2e-3), (15, 9, 2e-3, 1e-3)]
    for mx, my in [(1, 0), (3, 0), (2, 1), (1, -4)]
    if ny > 1 or my == 0  # one row has no mode along y
]


@pytest.mark.parametrize("fft", FFTS)
@pytest.mark.parametrize(("nx", "ny", "dx", "dy", "mx", "my"), WAVY)
def test_periodic_normal_sinusoid_is_westergaard(nx, ny, dx, dy, mx, my, fft):
    """p = p0 cos(q . x) gives u = 2 p0 cos(q . x) / (E* |q|) (Westergaard; Johnson 1985
    §13.2); the spectral kernel collocated at the centres makes a grid mode exact to rounding."""
    x, y, Lx, Ly = westergaard_grid(nx, ny, dx, dy)
    qx, qy = 2 * np.pi * mx / Lx, 2 * np.pi * my / Ly
    q = math.hypot(qx, qy)
    p0 = 3e6
    pressure = p0 * np.cos(qx * x + qy * y + 0.4)
    W = HalfSpaceOperator(nx, ny, dx, dy, E, NU, periodic=True, fft=fft)
    u = W @ (pressure * dx * dy)
    E_star = E / (1 - NU**2)
    expected = 2 * p0 / (E_star * q) * np.cos(qx * x + qy * y + 0.4)
    assert relative(u, expected) < 1e-12


def test_periodic_normal_operator_is_symmetric_semidefinite_with_zero_mean():
    nx, ny, dx, dy = 10, 8, 1e-3, 1.5e-3
    W = HalfSpaceOperator(nx, ny, dx, dy, E, NU, periodic=True)
    n = nx * ny
    dense = W @ np.eye(n)
    np.testing.assert_allclose(W.block(), dense, rtol=0, atol=1e-12 * np.max(dense))
    np.testing.assert_allclose(dense, dense.T, rtol=0, atol=1e-13 * np.max(dense))
    assert np.max(np.abs(W @ np.ones(n))) < 1e-13 * np.max(dense)  # the mean mode is null
    eigenvalues = np.linalg.eigvalsh(dense)
    assert eigenvalues[0] > -1e-12 * eigenvalues[-1] and eigenvalues[1] > 0
    u = W @ np.random.default_rng(1).random(n)
    assert abs(u.mean()) < 1e-12 * np.max(np.abs(u))
    np.testing.assert_allclose(W.diagonal(), np.diag(dense), rtol=1e-12)
    # a smooth load, small against the period, dents the surface as on an infinite half-space
    # (the images add a smooth field, the two discretisations differ by O((dx / width)^2)):
    # the dent between its centre and 12 cells away agrees with the Love kernel's to 1 %
    n = 64
    periodic = HalfSpaceOperator(n, n, dx, dx, E, NU, periodic=True)
    love = HalfSpaceOperator(n, n, dx, dx, E, NU)
    x, y = grid(n, n, dx, dx)
    f = np.exp(-(x**2 + y**2) / (2 * (3 * dx) ** 2))
    centre = (n // 2) * n + n // 2
    near = centre + np.arange(12)
    dent_periodic = (periodic @ f)[near] - (periodic @ f)[centre + 12]
    dent_love = (love @ f)[near] - (love @ f)[centre + 12]
    assert relative(dent_periodic, dent_love) < 0.01


@pytest.mark.parametrize("fft", FFTS)
@pytest.mark.parametrize(("nx", "ny"), [(16, 16), (15, 12), (12, 9)])
@pytest.mark.parametrize("poisson", [0.3, 0.0, -0.3])
def test_periodic_tangential_sinusoids_are_the_closed_forms(nx, ny, poisson, fft):
    """Longitudinal and transverse sinusoidal shear on a periodic half-space.

    A shear traction t0 cos(q . x) along q displaces the surface along q by 2 t0 / (E* q) (as
    a normal pressure does normally: plane strain) and normally by
    -(1 - 2 nu)(1 + nu) t0 sin(q . x) / (E q) (the line load's -(1 - 2 nu) Q sgn(x) / (4 G)
    convolved with the cosine: the surface sinks ahead of the force); across q it is antiplane
    shear, u = t0 cos(q . x) / (G q), with no normal part. A normal pressure moves the surface
    along q by the reciprocal term, (1 - 2 nu)(1 + nu) p0 sin(q . x) / (E q). The oblique wave
    vectors check the rotation of the kernel."""
    dx = dy = 1e-3
    x, y, Lx, Ly = westergaard_grid(nx, ny, dx, dy)
    W = HalfSpaceOperator(nx, ny, dx, dy, E, poisson, components="full", periodic=True, fft=fft)
    G = E / (2 * (1 + poisson))
    E_star = E / (1 - poisson**2)
    t0 = 2e6
    for mx, my in [(1, 0), (0, 2), (2, 1), (-1, 3)]:
        qx, qy = 2 * np.pi * mx / Lx, 2 * np.pi * my / Ly
        q = math.hypot(qx, qy)
        along = np.array([qx, qy]) / q
        across = np.array([-along[1], along[0]])
        phase = qx * x + qy * y
        wave, shifted = np.cos(phase), np.sin(phase)
        cases = [  # (traction direction 3-vector, expected tangential, expected normal)
            (np.r_[along, 0.0], 2 * t0 / (E_star * q) * along,
             -(1 - 2 * poisson) * (1 + poisson) * t0 / (E * q)),
            (np.r_[across, 0.0], t0 / (G * q) * across, 0.0),
        ]  # fmt: skip
        for direction, tangential, normal in cases:
            f = np.empty(3 * nx * ny)
            for a in range(3):
                f[a::3] = t0 * direction[a] * wave * dx * dy
            u = W @ f
            expected = np.empty_like(u)
            expected[0::3] = tangential[0] * wave
            expected[1::3] = tangential[1] * wave
            expected[2::3] = normal * shifted
            assert relative(u, expected) < 1e-12
        f = np.zeros(3 * nx * ny)
        f[2::3] = t0 * wave * dx * dy
        u = W @ f
        radial = (1 - 2 * poisson) * (1 + poisson) * t0 / (E * q)
        assert relative(u[2::3], 2 * t0 / (E_star * q) * wave) < 1e-12
        assert np.max(np.abs(u[0::3] - radial * along[0] * shifted)) < 1e-12 * np.max(np.abs(u))
        assert np.max(np.abs(u[1::3] - radial * along[1] * shifted)) < 1e-12 * np.max(np.abs(u))


@pytest.mark.parametrize(("nx", "ny"), [(8, 6), (7, 5), (6, 7)])
def test_periodic_full_operator_is_symmetric_semidefinite(nx, ny):
    """Even sizes have Nyquist modes, where the odd kernels must vanish to stay symmetric."""
    W = HalfSpaceOperator(nx, ny, 1e-3, 1e-3, E, NU, components="full", periodic=True)
    n = 3 * nx * ny
    dense = W @ np.eye(n)
    scale = np.max(np.abs(dense))
    np.testing.assert_allclose(dense, dense.T, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(W.block(), dense, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(W.diagonal_blocks(3), as_operator(dense).diagonal_blocks(3),
                               rtol=0, atol=1e-12 * scale)  # fmt: skip
    eigenvalues = np.linalg.eigvalsh(dense)
    assert eigenvalues[0] > -1e-12 * eigenvalues[-1]
    assert np.sum(eigenvalues < 1e-12 * eigenvalues[-1]) == 3  # the three mean modes
    uncoupled = HalfSpaceOperator(nx, ny, 1e-3, 1e-3, E, NU, components="full", periodic=True,
                                  coupling=False)  # fmt: skip
    f = np.zeros(n)
    f[2::3] = np.random.default_rng(0).random(nx * ny)
    assert not np.any((uncoupled @ f)[0::3]) and np.any((W @ f)[0::3])
    normal = HalfSpaceOperator(nx, ny, 1e-3, 1e-3, E, NU, periodic=True)
    assert relative((uncoupled @ f)[2::3], normal @ f[2::3]) < 1e-13


def strip_matrix_by_quadrature(n, dx, E_star, r0):
    """(1 / dx) times the integral over strip j of the line-load displacement
    (2 / (pi E*)) ln(r0 / |x_i - xi|) (Johnson 1985, eq. 2.19b), by adaptive quadrature."""
    centres = (np.arange(n) - 0.5 * (n - 1)) * dx
    matrix = np.empty((n, n))
    for i, xi in enumerate(centres):
        for j, xj in enumerate(centres):
            a, b = xj - dx / 2, xj + dx / 2
            points = [xi] if a < xi < b else None
            value, _ = scipy.integrate.quad(
                lambda s, xi=xi: np.log(r0 / abs(xi - s)), a, b, points=points,
                epsabs=1e-16, epsrel=1e-12, limit=200,
            )  # fmt: skip
            matrix[i, j] = 2 / (np.pi * E_star) * value / dx
    return matrix


@pytest.mark.parametrize("fft", FFTS)
@pytest.mark.parametrize(("n", "reference"), [(1, None), (9, None), (12, 2e-3), (7, 0.5)])
def test_half_plane_equals_the_strip_kernel_by_quadrature(n, reference, fft):
    dx = 1e-3
    W = HalfPlaneOperator(n, dx, E, NU, reference=reference, fft=fft)
    r0 = n * dx if reference is None else reference
    assert W.reference == r0
    R = strip_matrix_by_quadrature(n, dx, E / (1 - NU**2), r0)
    # quadrature to 1e-12 of a log-singular integrand (split at the singularity); the closed
    # form rounds at 1e-16
    np.testing.assert_allclose(W.block(), R, rtol=1e-11, atol=1e-12 * np.max(np.abs(R)))
    rng = np.random.default_rng(n)
    f, F = rng.standard_normal(n), rng.standard_normal((n, 4))
    dense = W.block()
    assert relative(W @ f, dense @ f) < PRODUCT_RTOL
    assert relative(W @ F, dense @ F) < PRODUCT_RTOL
    np.testing.assert_allclose(W.diagonal(), np.diag(dense), rtol=1e-15)
    if reference is None:  # r0 = n dx > n dx / 4: positive definite
        assert np.linalg.eigvalsh(dense)[0] > 0


def test_the_full_half_plane_is_the_plane_strain_limit_of_the_half_space():
    """Non-periodic: the full half-plane (x, z per strip) is symmetric, its two diagonal blocks
    are the normal operator, and a long line of 3-D cells under a line load (Cerruti and
    Boussinesq integrated along y) gives its coupling and, up to the log kernel's datum
    constant, its tangential displacements (a 40,001-cell line: the coupling's tails beyond it
    are 2e-4 of it)."""
    n, dx, M = 12, 1e-4, 40001
    W = HalfPlaneOperator(n, dx, E, NU, components="full")
    B = W.block()
    assert np.array_equal(B, B.T)
    normal = HalfPlaneOperator(n, dx, E, NU).block()
    np.testing.assert_allclose(B[1::2, 1::2], normal, rtol=1e-15)
    np.testing.assert_allclose(B[0::2, 0::2], normal, rtol=1e-15)
    f = np.random.default_rng(7).standard_normal(2 * n)
    assert relative(W @ f, B @ f) < PRODUCT_RTOL
    space = HalfSpaceOperator(n, M, dx, dx, E, NU, components="full")
    for source, column in ((0, 0), (2, 1)):  # x then z of strip 4: 3-D components 0 and 2
        line = np.zeros((M, n, 3))
        line[:, 4, source] = dx  # 1 N/m along y, as forces of the cells
        u3 = (space @ line.ravel()).reshape(M, n, 3)[M // 2][:, [0, 2]]
        u2 = B[:, 2 * 4 + column].reshape(n, 2)
        cross = 1 - column  # the other component: the coupling
        assert relative(u3[:, cross], u2[:, cross]) < 1e-3
        same = u3[:, column] - u3[0, column]  # the datum constant drops out of differences
        assert relative(same, u2[:, column] - u2[0, column]) < 1e-7  # measured 7e-9
    plain = HalfPlaneOperator(n, dx, E, NU, components="full", coupling=False).block()
    assert not np.any(plain[0::2, 1::2])


@pytest.mark.parametrize("n", [32, 33])
def test_the_periodic_full_half_plane_is_the_half_space_uniform_in_y(n):
    dx, dy = 2e-3, 1e-3
    W = HalfPlaneOperator(n, dx, E, NU, periodic=True, components="full")
    space = HalfSpaceOperator(n, 1, dx, dy, E, NU, periodic=True, components="full")
    f = np.random.default_rng(n).standard_normal((n, 2))
    f3 = np.zeros((n, 3))
    f3[:, [0, 2]] = f * dy
    u3 = (space @ f3.ravel()).reshape(n, 3)[:, [0, 2]]
    assert relative(W @ f.ravel(), u3.ravel()) < 1e-12
    B = W.block()
    np.testing.assert_allclose(B, B.T, rtol=0, atol=1e-13 * np.max(np.abs(B)))


def test_half_plane_datum_shifts_every_entry_by_one_constant():
    n, dx = 10, 1e-3
    near = HalfPlaneOperator(n, dx, E, NU, reference=1e-2).block()
    far = HalfPlaneOperator(n, dx, E, NU, reference=1.0).block()
    shift = 2 * (1 - NU**2) / (np.pi * E) * np.log(1.0 / 1e-2)
    np.testing.assert_allclose(far - near, shift, rtol=1e-12)


@pytest.mark.parametrize("fft", FFTS)
@pytest.mark.parametrize("n", [32, 33])
def test_periodic_half_plane_sinusoid_and_the_half_space_uniform_in_y(n, fft):
    dx, p0 = 2e-3, 5e6
    L = n * dx
    x = (np.arange(n) - 0.5 * (n - 1)) * dx
    W = HalfPlaneOperator(n, dx, E, NU, periodic=True, fft=fft)
    E_star = E / (1 - NU**2)
    for m in (1, 2, 5):
        q = 2 * np.pi * m / L
        u = W @ (p0 * np.cos(q * x - 1.0) * dx)
        assert relative(u, 2 * p0 / (E_star * q) * np.cos(q * x - 1.0)) < 1e-12
    # a load uniform along y on the periodic half-space is plane strain
    rng = np.random.default_rng(2)
    pressure = rng.random(n)
    ny, dy = 6, 1e-3
    space = HalfSpaceOperator(n, ny, dx, dy, E, NU, periodic=True, fft=fft)
    u3 = (space @ np.tile(pressure * dx * dy, ny)).reshape(ny, n)
    u2 = W @ (pressure * dx)
    for row in u3:
        assert relative(row, u2) < 1e-12
    np.testing.assert_allclose(W.block(), W @ np.eye(n), rtol=0, atol=1e-13 * W.diagonal()[0])
    assert abs(np.sum(u2)) < 1e-12 * np.max(np.abs(u2))


def test_composite_modulus_and_the_operator_of_two_bodies():
    E1, nu1, E2, nu2 = 210e9, 0.3, 70e9, 0.33
    E_star = composite_modulus(E1, nu1, E2, nu2)
    assert E_star == pytest.approx(1 / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2), rel=1e-15)
    assert composite_modulus(E1, nu1, math.inf, 0.0) == pytest.approx(E1 / (1 - nu1**2))
    assert composite_modulus(E1, 0.5, E1, 0.5) == pytest.approx(E1 / 1.5)  # incompressible
    nx, ny, d = 9, 7, 1e-3
    pair = HalfSpaceOperator(nx, ny, d, d, E_star, 0.0)
    one = HalfSpaceOperator(nx, ny, d, d, E1, nu1)
    two = HalfSpaceOperator(nx, ny, d, d, E2, nu2)
    f = np.random.default_rng(4).random(nx * ny)
    assert relative(pair @ f, one @ f + two @ f) < PRODUCT_RTOL


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: HalfSpaceOperator(0, 4, 1e-3, 1e-3, E, NU), "nx must be a positive integer"),
        (lambda: HalfSpaceOperator(4, 2.5, 1e-3, 1e-3, E, NU), "ny must be a positive integer"),
        (lambda: HalfSpaceOperator(4, 4, -1e-3, 1e-3, E, NU), "dx must be a positive finite"),
        (lambda: HalfSpaceOperator(4, 4, 1e-3, np.nan, E, NU), "dy must be a positive finite"),
        (lambda: HalfSpaceOperator(4, 4, 1e-3, 1e-3, 0.0, NU), "young must be a positive"),
        (lambda: HalfSpaceOperator(4, 4, 1e-3, 1e-3, E, 0.5), "poisson must be a finite number"),
        (
            lambda: HalfSpaceOperator(4, 4, 1e-3, 1e-3, E, NU, components="xyz"),
            'components must be "normal" or "full"',
        ),
        (
            lambda: HalfSpaceOperator(4, 4, 1e-3, 1e-3, E, NU, coupling=1),
            "coupling must be True or False",
        ),
        (
            lambda: HalfSpaceOperator(4, 4, 1e-3, 1e-3, E, NU, periodic="yes"),
            "periodic must be True or False",
        ),
        (
            lambda: HalfSpaceOperator(4, 4, 1e-3, 1e-3, E, NU, workers=0),
            "workers must be None or a nonzero integer",
        ),
        (
            lambda: HalfSpaceOperator(4, 4, 1e-3, 1e-3, E, NU) @ np.ones(15),
            r"a vector of 16 entries or a 2-D array of 16 rows, got shape \(15,\)",
        ),
        (lambda: HalfSpaceOperator(4, 4, 1e-3, 1e-3, E, NU) @ np.ones((16, 2, 2)), "got shape"),
        (
            lambda: HalfSpaceOperator(2, 2, 1e-3, 1e-3, E, NU) @ np.ones(4, dtype=complex),
            "real vectors",
        ),
        (
            lambda: HalfSpaceOperator(2, 2, 1e-3, 1e-3, E, NU).block([0, 4]),
            r"rows: indices must lie in \[0, 4\)",
        ),
        (
            lambda: HalfSpaceOperator(2, 2, 1e-3, 1e-3, E, NU).block(None, np.ones(3, bool)),
            r"cols: a boolean mask must have shape \(4,\)",
        ),
        (
            lambda: HalfSpaceOperator(2, 2, 1e-3, 1e-3, E, NU).block([0.5]),
            "rows must be None, a slice, a mask or 1-D indices",
        ),
        (
            lambda: HalfSpaceOperator(4, 4, 1e-3, 1e-3, E, NU, fft="mkl"),
            'fft must be None, "scipy" or "pyfftw"',
        ),
        (lambda: HalfPlaneOperator(0, 1e-3, E, NU), "n must be a positive integer"),
        (
            lambda: HalfPlaneOperator(4, 1e-3, E, NU, reference=0.0),
            "reference must be a positive finite length",
        ),
        (
            lambda: HalfPlaneOperator(4, 1e-3, E, NU, periodic=True, reference=1.0),
            "reference is for a non-periodic half-plane",
        ),
        (lambda: composite_modulus(-1.0, 0.3, E, 0.3), "young1 must be a positive modulus"),
        (lambda: composite_modulus(E, 0.3, "steel", 0.3), "young2 must be a positive modulus"),
        (lambda: composite_modulus(E, 0.7, E, 0.3), r"poisson1 must be a finite number in \(-1"),
        (lambda: composite_modulus(math.inf, 0.3, math.inf, 0.3), "both infinite"),
    ],
)
def test_bad_input_is_one_clear_line(make, message):
    with pytest.raises(InvalidInputError, match=message):
        make()


@pytest.mark.parametrize("fft", FFTS)
def test_threads_pickles_and_the_default_library(fft):
    """Threads and worker counts change no product beyond rounding; a pickled operator (sent
    to a worker process) plans its transforms afresh; products from several threads at once
    share the buffers safely."""
    nx, ny, d = 24, 20, 1e-3
    W = HalfSpaceOperator(nx, ny, d, d, E, NU, components="full", fft=fft)
    F = np.random.default_rng(5).standard_normal((3 * nx * ny, 8))
    expected = W @ F
    for workers in (2, -1):
        threaded = HalfSpaceOperator(nx, ny, d, d, E, NU, components="full", fft=fft,
                                     workers=workers)  # fmt: skip
        assert relative(threaded @ F, expected) < 1e-13
    copy = pickle.loads(pickle.dumps(W))
    assert copy.fft == fft and relative(copy @ F, expected) < 1e-15
    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        answers = list(pool.map(lambda j: W @ F[:, j], range(8)))
    for j, answer in enumerate(answers):
        assert relative(answer, expected[:, j]) < 1e-13
    # the default is the library measured faster (benchmarks/bench_fft.py): pyFFTW, but for
    # padded grids from 1024 x 1024
    assert HalfSpaceOperator(2, 2, d, d, E, NU).fft == "pyfftw"
    assert HalfSpaceOperator(64, 64, d, d, E, NU, periodic=True).fft == "pyfftw"
    assert HalfSpaceOperator(512, 512, d, d, E, NU).fft == "scipy"


def test_without_pyfftw_the_operators_use_scipy(monkeypatch):
    monkeypatch.setitem(sys.modules, "pyfftw", None)  # import pyfftw raises ImportError
    assert HalfSpaceOperator(4, 3, 1e-3, 1e-3, E, NU).fft == "scipy"
    with pytest.raises(MissingDependencyError, match=r"pip install 'contactqp\[fft\]'"):
        HalfPlaneOperator(4, 1e-3, E, NU, fft="pyfftw")

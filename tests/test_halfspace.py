"""Half-space normal influence coefficients against independent truths.

Truths used here, none of them derived from Love's closed form:

* numerical quadrature (scipy.integrate) of the Boussinesq point-load kernel
  ``(1 - nu^2) / (pi E r)`` over a cell, and of the Cerruti tangential and the coupling
  point-force kernels (Johnson, Contact Mechanics, eq. 2.19 at z = 0);
* the point-load (Boussinesq) value far from the cell, with its second-order correction;
* Hertz's solution for a rigid sphere pressed into an elastic half-space, solved through
  :class:`contactqp.ContactProblem` and the project's own solver;
* the displacements under a Hertz-type tangential traction on a circle (Johnson, §3.7).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from contactqp import ContactProblem, GapObstacle, InvalidInputError, ReducedModel, solve
from contactqp.compliance import grid, influence_matrix, normal_influence
from contactqp.core.status import ContactStatus

E, NU = 210e9, 0.3  # steel-like half-space (Pa, -)
KERNEL = (1.0 - NU**2) / (np.pi * E)  # Boussinesq: w = KERNEL * F / r  (m/N . m)


def homogeneous_integral(direction, X, Y, half_x, half_y):
    """Integral (m) of ``direction(theta) / r`` over ``|xi| <= half_x, |eta| <= half_y``.

    ``r, theta`` are the polar coordinates of ``(X - xi, Y - eta)``, the offset of the point
    ``(X, Y)`` from a source point: every surface kernel of the half-space is of this form.
    Computed by scipy quadrature, independently of the closed forms: in polar coordinates around
    the point when it lies inside the rectangle (the 1/r singularity cancels the Jacobian and
    the radial integral is the distance to the boundary), in Cartesian coordinates when it lies
    outside (smooth integrand).
    """
    tiny = 1e-14 * (half_x + half_y)  # absolute floor for the integrals that vanish by symmetry
    inside = abs(X) < half_x and abs(Y) < half_y
    if inside:

        def reach(theta):  # distance from the point to the boundary along -theta (to a source)
            c, s = -np.cos(theta), -np.sin(theta)
            distances = []
            if c > 0:
                distances.append((half_x - X) / c)
            elif c < 0:
                distances.append((-half_x - X) / c)
            if s > 0:
                distances.append((half_y - Y) / s)
            elif s < 0:
                distances.append((-half_y - Y) / s)
            return min(distances)

        corners = sorted(
            np.arctan2(Y - cy, X - cx) % (2 * np.pi)
            for cx in (-half_x, half_x)
            for cy in (-half_y, half_y)
        )
        value, _ = scipy.integrate.quad(
            lambda t: direction(t) * reach(t),
            0.0,
            2 * np.pi,
            points=corners,
            epsabs=tiny,
            epsrel=1e-12,
            limit=200,
        )
        return value
    value, _ = scipy.integrate.dblquad(
        lambda eta, xi: direction(np.arctan2(Y - eta, X - xi)) / np.hypot(X - xi, Y - eta),
        -half_x,
        half_x,
        -half_y,
        half_y,
        epsabs=tiny,
        epsrel=1e-11,
    )
    return value


def kernel_integral(X, Y, half_x, half_y):
    """Integral of ``1 / r`` (m) over the rectangle seen from ``(X, Y)``, by quadrature."""
    return homogeneous_integral(lambda theta: 1.0, X, Y, half_x, half_y)


# --------------------------------------------------------------------------------------------
# grid and input validation


def test_grid_is_centred_and_ordered_x_fastest():
    x, y = grid(4, 3, 2e-3, 1e-3)
    assert x.shape == y.shape == (12,)
    assert np.allclose([x.mean(), y.mean()], 0.0, atol=1e-18)
    assert np.allclose(x[:4], [-3e-3, -1e-3, 1e-3, 3e-3])
    assert np.allclose(y[::4], [-1e-3, 0.0, 1e-3])
    assert np.allclose(np.diff(x[:4]), 2e-3) and np.all(y[:4] == y[0])


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"young": 0.0}, "young"),
        ({"young": -1.0}, "young"),
        ({"young": np.nan}, "young"),
        ({"young": np.inf}, "young"),
        ({"poisson": 0.5}, "poisson"),
        ({"poisson": -1.0}, "poisson"),
        ({"poisson": np.nan}, "poisson"),
        ({"dx": 0.0}, "dx"),
        ({"dx": -1e-3}, "dx"),
        ({"dy": np.inf}, "dy"),
        ({"dy": "wide"}, "dy"),
        ({"x": [0.0, np.nan]}, "x"),
        ({"y": [0.0]}, "y"),
        ({"x": [[0.0, 1.0]]}, "x"),
        ({"x": []}, "x"),
    ],
)
def test_invalid_inputs_name_the_argument(kwargs, name):
    arguments = {
        "x": [0.0, 1e-3],
        "y": [0.0, 0.0],
        "dx": 1e-3,
        "dy": 1e-3,
        "young": E,
        "poisson": NU,
    }
    arguments.update(kwargs)
    with pytest.raises(InvalidInputError, match=rf"^{name} ") as info:
        normal_influence(**arguments)
    assert isinstance(info.value, ValueError)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "args, name",
    [
        ((0, 3, 1.0, 1.0), "nx"),
        ((3, 2.5, 1.0, 1.0), "ny"),
        ((3, True, 1.0, 1.0), "ny"),
        ((3, 3, -1.0, 1.0), "dx"),
        ((3, 3, 1.0, np.nan), "dy"),
    ],
)
def test_grid_rejects_bad_arguments(args, name):
    with pytest.raises(InvalidInputError, match=rf"^{name} "):
        grid(*args)


@pytest.mark.parametrize(
    "x, y",
    [
        ([0.0, 0.0], [0.0, 0.2e-3]),
        ([0.0, 0.4e-3], [0.0, 0.2e-3]),
        ([0.0, 1e-3, 0.0], [0.0, 0.0, 0.0]),
    ],
)
def test_overlapping_cells_are_rejected(x, y):
    """Overlapping or repeated cells (off and on the lattice) would make R singular."""
    with pytest.raises(InvalidInputError, match="overlap"):
        normal_influence(x, y, 1e-3, 1e-3, E, NU)


# --------------------------------------------------------------------------------------------
# (1) symmetry and positive definiteness


@pytest.mark.parametrize(
    "nx, ny, dx, dy", [(12, 12, 1e-4, 1e-4), (20, 6, 0.5e-4, 2e-4), (1, 30, 1e-3, 1e-4)]
)
def test_matrix_is_symmetric_and_positive_definite(nx, ny, dx, dy):
    """Exact symmetry (Maxwell-Betti for equal cells), SPD (the 1/r kernel is positive definite).

    Collocation of piecewise-constant pressures is not a Galerkin scheme, so positive
    definiteness is not guaranteed a priori: it is checked here for square cells and for
    elongated ones (aspect ratios 4 and 10).
    """
    x, y = grid(nx, ny, dx, dy)
    R = normal_influence(x, y, dx, dy, E, NU)
    assert np.array_equal(R, R.T)
    eigenvalues = np.linalg.eigvalsh(R)
    assert eigenvalues.min() > 0.0
    assert eigenvalues.min() > 1e-3 * eigenvalues.max()  # well conditioned: cond < 1e3 here
    assert np.all(R > 0.0)  # pressing in sinks every point of the surface


def test_irregular_arrangement_takes_the_general_path_and_agrees():
    """Rows shifted by half a cell are off the lattice: the general evaluation must be exactly
    symmetric, SPD, agree with the two-cell evaluation of each pair (the lattice path for pairs in
    rows of the same parity) and with quadrature of the kernel."""
    dx = dy = 1e-4
    x, y = grid(6, 6, dx, dy)
    shifted = x + 0.5 * dx * (np.rint(y / dy + 2.5) % 2)
    R = normal_influence(shifted, y, dx, dy, E, NU)
    assert np.array_equal(R, R.T)
    assert np.linalg.eigvalsh(R).min() > 0.0
    for i, j in [(0, 1), (0, 6), (3, 17), (7, 35)]:
        pair = normal_influence([shifted[i], shifted[j]], [y[i], y[j]], dx, dy, E, NU)
        assert pair[0, 1] == pytest.approx(R[i, j], rel=1e-13)
        X, Y = abs(shifted[i] - shifted[j]), abs(y[i] - y[j])
        assert R[i, j] == pytest.approx(
            KERNEL * kernel_integral(X, Y, dx / 2, dy / 2) / (dx * dy), rel=1e-9
        )


# --------------------------------------------------------------------------------------------
# (2) single-cell coefficients against quadrature, and the far field


@pytest.mark.parametrize("dx, dy", [(1e-4, 1e-4), (1e-4, 3e-4)])
@pytest.mark.parametrize("offset", [(0, 0), (1, 0), (0, 1), (1, 1), (2, 3), (7, -4)])
def test_coefficients_match_quadrature_of_the_boussinesq_kernel(dx, dy, offset):
    """Each entry is the Boussinesq kernel averaged over the loaded cell; scipy quadrature of the
    kernel (adaptive, relative tolerance 1e-11) is an independent truth, agreement to 1e-9."""
    x = np.array([0.0, offset[0] * dx])
    y = np.array([0.0, offset[1] * dy])
    if offset == (0, 0):
        x, y = x[:1], y[:1]
    R = normal_influence(x, y, dx, dy, E, NU)
    expected = KERNEL * kernel_integral(x[-1] - x[0], y[-1] - y[0], dx / 2, dy / 2) / (dx * dy)
    assert R[-1, 0] == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("dx, dy", [(1e-4, 1e-4), (1e-4, 2e-4)])
@pytest.mark.parametrize("direction", [(30, 0), (0, 30), (21, 21), (18, 24)])
def test_far_field_tends_to_the_point_load(dx, dy, direction):
    """At r = 30 cells the coefficient equals the point-load value (1 - nu^2) / (pi E r) within
    1e-3 relative; more precisely, its deviation is the second-order term of the cell average of
    1/r, (dx^2 (2 X^2 - Y^2) + dy^2 (2 Y^2 - X^2)) / (24 r^4), checked to 1e-6 (the
    O((cell / r)^4) remainder is below 1e-7 for cells up to 2:1 at r = 30 cells)."""
    X, Y = direction[0] * dx, direction[1] * dx  # r = 30 dx in every case
    r = np.hypot(X, Y)
    R = normal_influence([0.0, X], [0.0, Y], dx, dy, E, NU)
    point_load = KERNEL / r
    relative = R[0, 1] / point_load - 1.0
    assert abs(relative) < 1e-3
    predicted = (dx**2 * (2 * X**2 - Y**2) + dy**2 * (2 * Y**2 - X**2)) / (24 * r**4)
    assert relative == pytest.approx(predicted, abs=1e-6)


# --------------------------------------------------------------------------------------------
# (3) centre of a uniformly loaded square


def test_centre_of_a_uniformly_loaded_square():
    """A square of side 2b under pressure p sinks at its centre by

    .. math:: w_0 = \\frac{8}{\\pi} \\ln(1 + \\sqrt 2) \\frac{(1 - \\nu^2) p b}{E}
              \\approx 2.244 \\frac{(1 - \\nu^2) p b}{E}

    (in polar coordinates the integral of 1/r over the square is the integral of the distance to
    the boundary, 8 b ln(1 + sqrt 2)). The square is built from 11 x 11 cells loaded by the same
    pressure: superposition is exact, so the centre row of R times the cell forces must match the
    formula to rounding; the formula itself is checked against scipy quadrature.
    """
    b, p, m = 2.2e-3, 3e6, 11  # half-side (m), pressure (Pa), cells per side
    h = 2 * b / m
    x, y = grid(m, m, h, h)
    R = normal_influence(x, y, h, h, E, NU)
    centre = (m * m) // 2
    assert x[centre] == 0.0 and y[centre] == 0.0
    w_cells = R[centre] @ np.full(m * m, p * h * h)
    w_formula = 8 / np.pi * np.log(1 + np.sqrt(2)) * (1 - NU**2) * p * b / E
    w_quadrature = KERNEL * p * kernel_integral(0.0, 0.0, b, b)
    assert w_quadrature == pytest.approx(w_formula, rel=1e-11)
    assert w_cells == pytest.approx(w_formula, rel=1e-12)
    # Centre of the corner cell, by superposition of the cells against quadrature.
    corner = R[0] @ np.full(m * m, p * h * h)
    w_corner = KERNEL * p * kernel_integral(b - h / 2, b - h / 2, b, b)
    assert corner == pytest.approx(w_corner, rel=1e-9)


def test_single_cell_diagonal_has_the_closed_form():
    """The diagonal is the centre of one uniformly loaded cell (total force 1 N)."""
    dx, dy = 1e-4, 2.5e-4
    R = normal_influence([0.0], [0.0], dx, dy, E, NU)
    diagonal = 2 * (1 - NU**2) / (np.pi * E) * (np.arcsinh(dy / dx) / dy + np.arcsinh(dx / dy) / dx)
    assert R[0, 0] == pytest.approx(diagonal, rel=1e-14)


@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.2, 5.0),
    st.floats(0.2, 5.0),
    st.integers(-6, 6),
    st.integers(-6, 6),
    st.floats(-0.9, 0.49),
)
def test_swapping_axes_and_scaling(aspect_x, aspect_y, i, j, nu):
    """Invariances of the exact solution: exchanging x and y (with dx and dy) leaves the
    coefficient unchanged, scaling all lengths by s divides it by s, and it is proportional to
    (1 - nu^2) / E."""
    assume((i, j) != (0, 0))
    dx, dy = 1e-4 * aspect_x, 1e-4 * aspect_y
    a = normal_influence([0.0, i * dx], [0.0, j * dy], dx, dy, E, nu)
    b = normal_influence([0.0, j * dy], [0.0, i * dx], dy, dx, E, nu)
    c = normal_influence([0.0, 3 * i * dx], [0.0, 3 * j * dy], 3 * dx, 3 * dy, 2 * E, NU)
    assert b[0, 1] == pytest.approx(a[0, 1], rel=1e-12)
    assert c[0, 1] == pytest.approx(a[0, 1] / 6 * (1 - NU**2) / (1 - nu**2), rel=1e-12)


# --------------------------------------------------------------------------------------------
# (4) Hertz: a rigid sphere pressed into the half-space


@pytest.mark.parametrize("n, cells_per_radius", [(32, 12), (40, 16)])
def test_hertz_rigid_sphere(n, cells_per_radius):
    """A rigid sphere of radius Rs pushed a depth d into an elastic half-space (frictionless).

    Sign convention. Take z along the outward normal of the half-space, towards the sphere. Each
    cell has one freedom, its surface displacement U_i along +z, and the flexibility of
    :func:`normal_influence` links it to the cell's force P_i along the same +z axis (U = R P,
    R > 0: pulling the surface out lifts it). The sphere's surface stands above the undeformed
    cell at r_i^2 / (2 Rs) (paraboloid, small r / Rs); after a rigid approach d (imposed) the gap
    left along +z is Delta_i = r_i^2 / (2 Rs) - d, negative (an interference) inside r = sqrt(Rs d).
    Non-penetration is U_i <= Delta_i (``GapObstacle`` with direction +1). There is no external
    load (P = 0); the contact force lambda_i >= 0 of the sphere pushes the surface away from it,
    i.e. along -z: the load on the half-space is -A^T lambda, and the surface sinks
    (U_i = Delta_i < 0 in contact). The dual is min 1/2 l^T R l - l^T (d - r^2 / 2Rs), l >= 0.

    Hertz, with E* = E / (1 - nu^2) for a rigid indenter: contact radius a = sqrt(Rs d), total
    force F = (4/3) E* sqrt(Rs) d^(3/2), pressure p(r) = p0 sqrt(1 - r^2 / a^2) with
    p0 = 2 E* a / (pi Rs) = 3 F / (2 pi a^2).

    Tolerances, for a contact radius of 12 to 16 cells h (the pressure is represented by its
    mean over each cell and the contact edge falls inside a cell): total force within 0.5 %
    (measured: 5e-4 at 12 cells, falling with h / a), peak pressure within 1 %, pressure
    profile within 1 % of p0 for r < 0.8 a; every cell whose centre lies at r < a - h is closed
    and none at r > a + h (the edge is resolved to one cell), and the area-equivalent radius
    sqrt(N_closed h^2 / pi) is within half a cell of a.
    """
    Rs, h = 5e-3, 1e-5
    a = cells_per_radius * h
    d = a * a / Rs
    x, y = grid(n, n, h, h)
    r2 = x * x + y * y
    R = normal_influence(x, y, h, h, E, NU)
    model = ReducedModel(flexibility=R)
    gaps = r2 / (2 * Rs) - d
    problem = ContactProblem(model, np.zeros(n * n), [GapObstacle(list(range(n * n)), gaps, [1.0])])
    result = solve(problem)
    assert result.success, result.message

    E_star = E / (1 - NU**2)
    F_hertz = 4 / 3 * E_star * np.sqrt(Rs) * d**1.5
    p0 = 2 * E_star * a / (np.pi * Rs)
    pressure = result.forces / (h * h)
    F = result.forces.sum()
    assert F == pytest.approx(F_hertz, rel=5e-3)
    assert pressure.max() == pytest.approx(p0, rel=1e-2)
    inner = r2 < (0.8 * a) ** 2
    profile = p0 * np.sqrt(1 - r2[inner] / a**2)
    assert np.max(np.abs(pressure[inner] - profile)) < 1e-2 * p0

    r = np.sqrt(r2)
    assert np.all((result.contact_status == ContactStatus.CLOSED)[r < a - h])
    assert not np.any((result.contact_status == ContactStatus.CLOSED)[r > a + h])
    a_equivalent = np.sqrt(
        np.count_nonzero(result.contact_status == ContactStatus.CLOSED) * h * h / np.pi
    )
    assert abs(a_equivalent - a) < 0.5 * h

    # Physical signs: the surface sinks under the sphere and follows it in contact; the contact
    # loads on the half-space point into it; outside the contact the gap stays open.
    closed = result.contact_status == ContactStatus.CLOSED
    assert np.allclose(result.displacements[closed], gaps[closed], rtol=0, atol=1e-9 * d)
    assert np.all(result.displacements < 0.0)
    assert np.all(result.nodal_forces <= 0.0)
    assert np.all(result.gaps[~closed] >= -1e-9 * d)
    # Outside the contact the surface displacement matches Hertz's (Johnson, Contact Mechanics,
    # ch. 3) u_z(r) = -(d / pi) [(2 - r^2/a^2) asin(a/r) + sqrt(r^2/a^2 - 1)],
    # to 1 % of d for r > a + 2h (the cell discretisation of the pressure is felt near the edge).
    outside = r > a + 2 * h
    ratio = r[outside] / a
    u_hertz = -d / np.pi * ((2 - ratio**2) * np.arcsin(1 / ratio) + np.sqrt(ratio**2 - 1))
    assert np.max(np.abs(result.displacements[outside] - u_hertz)) < 1e-2 * d


# --------------------------------------------------------------------------------------------
# (5) tangential (Cerruti) and coupling coefficients: the 3 x 3 per cell flexibility

G_SHEAR = E / (2 * (1 + NU))


def point_force_kernels(nu=NU, shear=G_SHEAR):
    """Surface displacement per unit point force, ``r * green[a][b](theta)`` (Johnson eq. 2.19
    at z = 0, z the outward normal): a as the displacement axis, b the force axis."""
    c = 1.0 / (2 * np.pi * shear)
    k = (1 - 2 * nu) / (4 * np.pi * shear)

    def cross(t):
        return c * nu * np.cos(t) * np.sin(t)

    return [
        [lambda t: c * ((1 - nu) + nu * np.cos(t) ** 2), cross, lambda t: k * np.cos(t)],
        [cross, lambda t: c * ((1 - nu) + nu * np.sin(t) ** 2), lambda t: k * np.sin(t)],
        [lambda t: -k * np.cos(t), lambda t: -k * np.sin(t), lambda t: c * (1 - nu)],
    ]


@pytest.mark.parametrize("dx, dy", [(1e-4, 1e-4), (1e-4, 3e-4)])
@pytest.mark.parametrize("offset", [(0, 0), (1, 0), (0, 1), (1, 1), (-2, 3), (7, -4)])
def test_cerruti_and_coupling_coefficients_match_quadrature(dx, dy, offset):
    """Each of the nine entries linking two cells is the point-force solution averaged over the
    loaded cell: scipy quadrature of each kernel agrees to 1e-9 of the block's largest entry
    (entries zero by symmetry, e.g. the coupling of a cell with itself, to the same absolute
    level)."""
    X, Y = offset[0] * dx, offset[1] * dy
    if offset == (0, 0):
        block = influence_matrix([0.0], [0.0], dx, dy, E, NU)
    else:
        block = influence_matrix([X, 0.0], [Y, 0.0], dx, dy, E, NU)[:3, 3:]
    kernels = point_force_kernels()
    expected = np.array(
        [
            [
                homogeneous_integral(kernels[a][b], X, Y, dx / 2, dy / 2) / (dx * dy)
                for b in range(3)
            ]
            for a in range(3)
        ]
    )
    assert np.allclose(block, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    assert np.abs(expected).max() > 0


@pytest.mark.parametrize("direction", [(30, 0), (0, 30), (21, 21), (-18, 24)])
def test_full_far_field_tends_to_the_point_force(direction):
    """At 30 cells every entry equals the point-force value within 1e-3 of the largest."""
    dx = dy = 1e-4
    X, Y = direction[0] * dx, direction[1] * dy
    r, theta = np.hypot(X, Y), np.arctan2(Y, X)
    block = influence_matrix([X, 0.0], [Y, 0.0], dx, dy, E, NU)[:3, 3:]
    point = np.array([[kernel(theta) / r for kernel in row] for row in point_force_kernels()])
    assert np.allclose(block, point, rtol=0, atol=1e-3 * np.abs(point).max())


def test_influence_matrix_structure():
    """Reciprocity (exact symmetry), positive definiteness (the elastic energy), the normal
    part equal to normal_influence, the coupling sign (the surface sinks ahead of a tangential
    force), coupling=False dropping only the (1 - 2 nu) terms, and the off-lattice evaluation
    agreeing with the lattice one."""
    dx, dy = 1e-4, 2e-4
    x, y = grid(7, 5, dx, dy)
    R = influence_matrix(x, y, dx, dy, E, NU)
    assert R.shape == (105, 105)
    assert np.array_equal(R, R.T)
    assert np.linalg.eigvalsh(R).min() > 0.0
    assert np.array_equal(R[2::3, 2::3], normal_influence(x, y, dx, dy, E, NU))
    ahead = np.flatnonzero((x > 0) & (y == 0))
    centre = int(np.flatnonzero((x == 0) & (y == 0))[0])
    assert np.all(R[3 * ahead + 2, 3 * centre] < 0.0)  # u_z of cells ahead under Q_x
    uncoupled = influence_matrix(x, y, dx, dy, E, NU, coupling=False)
    coupling = np.zeros((3, 3), dtype=bool)
    coupling[2, :2] = coupling[:2, 2] = True
    mask = np.tile(coupling, (35, 35))
    assert np.all(uncoupled[mask] == 0.0) and np.abs(R[mask]).max() > 0.0
    assert np.array_equal(uncoupled[~mask], R[~mask])
    # rows shifted by half a cell: off the lattice, every pair evaluated directly
    shifted = x + 0.5 * dx * (np.rint(y / dy + 2) % 2)
    S = influence_matrix(shifted, y, dx, dy, E, NU)
    assert np.array_equal(S, S.T)
    for i, j in [(0, 1), (0, 7), (3, 20), (8, 34)]:
        pair = influence_matrix(shifted[[i, j]], y[[i, j]], dx, dy, E, NU)
        assert np.allclose(
            pair[:3, 3:],
            S[3 * i : 3 * i + 3, 3 * j : 3 * j + 3],
            rtol=1e-12,
            atol=1e-14 * np.abs(pair).max(),
        )


def test_hertz_type_tangential_traction():
    """A traction q_x = q0 sqrt(1 - r^2 / a^2) on a circle displaces the surface inside it by
    (Johnson, Contact Mechanics, §3.7)

    .. math::

        u_x = \\frac{\\pi q_0}{32 G a} \\left(4 (2 - \\nu) a^2 - (4 - 3\\nu) x^2
              - (4 - \\nu) y^2\\right), \\qquad u_y = \\frac{\\pi q_0 \\nu}{16 G a} x y .

    The traction is sampled at the centres of cells of a = 12 cells' radius; for r < 0.8 a the
    displacements agree within 0.5 % of u_x(0) (measured 1e-3 for u_x, 2e-4 for u_y: the
    midpoint sampling near the edge, where the traction has an infinite slope).
    """
    h = 1e-5
    a, q0 = 12 * h, 1e8
    x, y = grid(26, 26, h, h)
    r2 = x * x + y * y
    forces = np.zeros(3 * x.size)
    forces[0::3] = q0 * np.sqrt(np.clip(1 - r2 / a**2, 0.0, None)) * h * h
    U = influence_matrix(x, y, h, h, E, NU) @ forces
    inside = r2 < (0.8 * a) ** 2
    ux = (
        np.pi
        * q0
        / (32 * G_SHEAR * a)
        * (4 * (2 - NU) * a * a - (4 - 3 * NU) * x**2 - (4 - NU) * y**2)
    )
    uy = np.pi * q0 * NU / (16 * G_SHEAR * a) * x * y
    scale = ux.max()
    assert np.max(np.abs(U[0::3][inside] - ux[inside])) < 5e-3 * scale
    assert np.max(np.abs(U[1::3][inside] - uy[inside])) < 5e-3 * scale
    assert np.max(np.abs(uy[inside])) > 2e-2 * scale  # the u_y check is not vacuous


def test_text_centres_and_a_non_boolean_coupling_are_invalid_input():
    """``coupling="no"`` used to be taken as true, keeping the coupling asked to be dropped."""
    with pytest.raises(InvalidInputError, match="as numbers"):
        normal_influence(["a"], ["b"], 1e-4, 1e-4, E, NU)
    with pytest.raises(InvalidInputError, match="coupling must be True or False"):
        influence_matrix([0.0], [0.0], 1e-4, 1e-4, E, NU, coupling="no")

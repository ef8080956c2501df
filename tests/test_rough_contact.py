"""The rough-contact load sweep: its stiffness against the tangent of the contact, bad input."""

import numpy as np
import pytest
import scipy.sparse.linalg as sla

from contactqp.applications.rough import HeightMap, self_affine_surface
from contactqp.applications.rough.contact import solve_rough_contact
from contactqp.compliance.fft_halfspace import HalfSpaceOperator
from contactqp.errors import InvalidInputError

N, CELL, E, NU = 64, 1e-6, 210e9, 0.3


def surface():
    heights = self_affine_surface(
        N, CELL, hurst=0.8, rms_slope=0.1, rolloff=2, short_cutoff=16, seed=5
    )
    return HeightMap(heights, CELL)


def test_the_stiffness_is_the_tangent_of_the_contact_at_the_middle_load():
    eps = 0.02
    contact = solve_rough_contact(
        surface(), 2e9 * np.array([1 - eps, 1, 1 + eps]), young=E, poisson=NU, tol=1e-12
    )
    assert contact.solved
    middle = contact.points[1]
    # the tangent at fixed contact set A: the gaps stay 0 on A, W_AA dr = d(delta) 1, and the
    # mean gap moves by -d(delta) (the periodic W has zero-mean displacements), so
    # -dp/d(mean gap) = 1^T W_AA^-1 1 / area, solved here by scipy's CG through the operator
    active = np.flatnonzero(middle.result.contact)
    operator = HalfSpaceOperator(N, N, CELL, CELL, E, NU, periodic=True)

    def product(x):
        full = np.zeros(N * N)
        full[active] = x
        return (operator @ full)[active]

    block = sla.LinearOperator((active.size, active.size), matvec=product, dtype=float)
    x, info = sla.cg(block, np.ones(active.size), rtol=1e-12, maxiter=5000)
    assert info == 0
    tangent = x.sum() / (N * N * CELL**2)
    # the central difference spans the cells that join between the loads: second order in eps
    # (measured on this surface: 0.01 % at eps = 0.01, 0.3 % at eps = 0.05)
    assert middle.stiffness == pytest.approx(tangent, rel=1e-2)
    assert 0 < contact.points[0].area_fraction < middle.area_fraction < 1


@pytest.mark.parametrize(
    ("options", "words"),
    [
        ({"pressures": []}, "at least one pressure"),
        ({"pressures": [1e9, 1e9]}, "must increase"),
        ({"pressures": [np.nan]}, "positive and finite"),
        ({"pressures": [1e9], "young": -1.0}, "young"),
        ({"pressures": [1e9], "poisson": 0.5}, "poisson"),
    ],
)
def test_bad_arguments(options, words):
    with pytest.raises(InvalidInputError, match=words):
        solve_rough_contact(surface(), **options)


def test_a_small_shear_has_the_stick_stiffness_of_the_contact():
    """Sheared by 0.1 % of the friction limit every contact cell sticks, and the secant
    tangential stiffness is the full-stick one, ``Q / (area delta)`` with ``u_T = (delta, 0)``
    on the contact: ``W_TT`` on the contact solved by CG through the operator for both
    components (``t_y`` holds ``u_y`` at 0). At 1 % a few cells slip and the secant is softer,
    by about Mindlin's ``shear / 6`` (measured 0.16 %)."""
    points = [
        solve_rough_contact(
            surface(), [2e9], young=E, poisson=NU, mu=0.3, shear=shear, tol=1e-12
        ).points[0]
        for shear in (0.001, 0.01, 0.5)
    ]
    assert all(point.certificate for point in points)
    frictionless = solve_rough_contact(surface(), [2e9], young=E, poisson=NU, tol=1e-12)
    assert points[0].area_fraction == frictionless.points[0].area_fraction  # coupling neglected
    active = np.flatnonzero(points[0].result.contact)
    m = active.size
    full = HalfSpaceOperator(
        N, N, CELL, CELL, E, NU, periodic=True, components="full", coupling=False
    )

    def product(x):
        forces = np.zeros((N * N, 3))
        forces[active, :2] = x.reshape(m, 2)
        return (full @ forces.ravel()).reshape(-1, 3)[active, :2].ravel()

    block = sla.LinearOperator((2 * m, 2 * m), matvec=product, dtype=float)
    shift = np.zeros((m, 2))
    shift[:, 0] = 1.0
    x, info = sla.cg(block, shift.ravel(), rtol=1e-13, maxiter=5000)
    assert info == 0
    stick = x.reshape(m, 2)[:, 0].sum() / (N * N * CELL**2)
    tiny, small, half = points
    assert tiny.stick_fraction == 1.0
    assert tiny.tangential_stiffness == pytest.approx(stick, rel=1e-4)  # measured 8e-6
    assert 1 - 0.01 < small.tangential_stiffness / stick < 1
    # a larger shear slips more and is softer (the secant of a curve that bends over)
    assert half.stick_fraction < small.stick_fraction < 1
    assert half.tangential_stiffness < small.tangential_stiffness
    with pytest.raises(InvalidInputError, match="shear must be"):
        solve_rough_contact(surface(), [2e9], mu=0.3, shear=1.0)
    with pytest.raises(InvalidInputError, match="mu must be"):
        solve_rough_contact(surface(), [2e9], mu=-0.3)

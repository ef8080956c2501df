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

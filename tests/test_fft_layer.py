"""The elastic layer on a rigid base (``HalfSpaceOperator(..., thickness=h, base=...)``)
against a plane-strain finite-element solution computed here with scikit-fem directly.

A pressure ``p cos(q x)`` on a periodic layer is a plane-strain problem; by symmetry a half
wavelength ``0 <= x <= L / 2`` with rollers on its sides (``u_x = 0``) carries it. Quadratic
triangles on that strip, bonded (``u = 0``) or frictionless (``u_z = 0``) at the base, give the
surface displacement at ``x = 0``; the operator's product of the same mode must match it. The
thick and thin limits are checked against the half-space and the oedometer.
"""

from __future__ import annotations

import numpy as np
import pytest
import skfem as fe
from skfem.models.elasticity import lame_parameters, linear_elasticity

from contactqp.compliance import HalfSpaceOperator
from contactqp.errors import InvalidInputError

E, NU, L = 70e9, 0.3, 1e-3  # aluminium; the period (m)
E_STAR = E / (1 - NU**2)


def fe_surface_sinking(thickness: float, base: str, pressure: float = 1e6) -> float:
    """The surface's downward displacement at x = 0 under ``pressure cos(2 pi x / L)`` (m)."""
    q = 2 * np.pi / L
    nx, ny = 48, max(8, int(round(48 * 2 * thickness / L)))
    mesh = fe.MeshTri.init_tensor(np.linspace(0, L / 2, nx + 1), np.linspace(-thickness, 0, ny + 1))
    element = fe.ElementVector(fe.ElementTriP2())
    basis = fe.Basis(mesh, element, intorder=4)
    K = fe.asm(linear_elasticity(*lame_parameters(E, NU)), basis)
    top = fe.FacetBasis(mesh, element, facets=mesh.facets_satisfying(lambda x: x[1] > -1e-15))

    @fe.LinearForm
    def traction(v, w):
        return -pressure * np.cos(q * w.x[0]) * v[1]

    f = fe.asm(traction, top)
    sides = basis.get_dofs(lambda x: np.isclose(x[0], 0) | np.isclose(x[0], L / 2)).all("u^1")
    bottom = basis.get_dofs(lambda x: np.isclose(x[1], -thickness))
    fixed = bottom.all() if base == "bonded" else bottom.all("u^2")
    u = fe.solve(*fe.condense(K, f, D=np.concatenate([sides, fixed])))
    corner = np.flatnonzero((mesh.p[0] == 0) & (mesh.p[1] == 0))[0]
    return -float(u[basis.nodal_dofs[1, corner]])


def operator_sinking(thickness: float | None, base: str = "bonded", pressure: float = 1e6):
    """The operator's sinking at the crest of the same mode (cells of L / 32)."""
    n = 32
    dx = L / n
    W = HalfSpaceOperator(n, 4, dx, dx, E, NU, periodic=True, thickness=thickness, base=base)
    x = (np.arange(n) + 0.5) * dx  # the crest sampled at cell centres: read the amplitude
    mode = np.cos(2 * np.pi * x / L)
    u = (W @ np.tile(pressure * mode * dx * dx, 4)).reshape(4, n)[0]
    return float(u @ mode / (mode @ mode))


@pytest.mark.parametrize("base", ["bonded", "frictionless"])
@pytest.mark.parametrize("thickness", [0.05 * L, 0.2 * L])
def test_layer_equals_the_finite_element_strip(thickness, base):
    fe_value = fe_surface_sinking(thickness, base)
    half_space = 2 * 1e6 / (E_STAR * 2 * np.pi / L)
    assert fe_value < 0.9 * half_space  # the base stiffens the surface: a real effect
    # quadratic elements, 48 across half a wavelength: discretisation below 1e-4
    assert operator_sinking(thickness, base) == pytest.approx(fe_value, rel=2e-4)


def test_the_bonded_base_is_stiffer_than_the_frictionless_one():
    assert operator_sinking(0.1 * L, "bonded") < operator_sinking(0.1 * L, "frictionless")


def test_thick_and_thin_limits():
    half = operator_sinking(None)
    assert half == pytest.approx(2 * 1e6 / (E_STAR * 2 * np.pi / L), rel=1e-12)  # Westergaard
    assert operator_sinking(10 * L) == pytest.approx(half, rel=1e-12)
    thin = 1e-3 * L  # q h = 0.006: the layer is an oedometer (bonded) or in plane stress-free
    oedometer = thin * (1 + NU) * (1 - 2 * NU) / ((1 - NU) * E) * 1e6
    assert operator_sinking(thin, "bonded") == pytest.approx(oedometer, rel=1e-4)
    assert operator_sinking(thin, "frictionless") == pytest.approx(
        (1 - NU**2) * thin / E * 1e6, rel=1e-4
    )


def test_a_layer_problem_is_solved_with_the_layer_aids():
    """The coarsening keeps the layer and the preconditioner inverts the layer's kernel."""
    import contactqp as cq
    from contactqp.core.surface import SurfaceProblem

    n = 64
    W = HalfSpaceOperator(n, n, L / n, L / n, E, NU, periodic=True, thickness=0.05 * L)
    coarse = W.coarsening()
    assert coarse.operator.layer == W.layer
    x = np.random.default_rng(0).standard_normal(n * n)
    x -= x.mean()
    assert np.allclose(W.preconditioner()(W @ x, np.ones(n * n, bool)), x, rtol=0, atol=1e-10)
    X, Y = np.meshgrid((np.arange(n) + 0.5) * L / n, (np.arange(n) + 0.5) * L / n)
    s = 1e-7 * (2 - np.cos(2 * np.pi * X / L) - np.cos(2 * np.pi * Y / L))
    problem = SurfaceProblem(W, s.ravel(), load=0.02 * E_STAR * 1e-7 / L * L * L)
    aided = cq.solve(problem, tol=1e-10)
    plain = cq.solve(problem, tol=1e-10, precondition=False, multilevel=False)
    assert aided.success and plain.success
    assert np.max(np.abs(aided.forces - plain.forces)) <= 1e-6 * plain.forces.max()


@pytest.mark.parametrize(
    "arguments, message",
    [
        (dict(thickness=1e-4), "periodic grids and the normal component only"),
        (dict(thickness=1e-4, periodic=True, components="full"), "normal component only"),
        (dict(thickness=-1.0, periodic=True), "thickness must be a positive finite length"),
        (dict(thickness=1e-4, periodic=True, base="glued"), 'base must be "bonded"'),
    ],
)
def test_bad_layers_are_named(arguments, message):
    with pytest.raises(InvalidInputError, match=message):
        HalfSpaceOperator(16, 16, 1e-5, 1e-5, E, NU, **arguments)

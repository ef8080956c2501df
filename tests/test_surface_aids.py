"""The constrained CG's two aids on an FFT half-space: the preconditioner (an approximate
inverse of W) and the multilevel start (solves on coarser lattices).

The aids change the path, never the answer: the problem's solution is unique (W positive
definite), so the aided and the plain runs must meet at the same forces, each certified.
The preconditioner is checked against the operator it inverts, the coarsening against the
operator built directly on the coarse cells. Hertz's theory with the aids on is in
test_surface_theory.py (its solves use the defaults).
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp as cq
from contactqp.compliance import HalfSpaceOperator, grid, normal_influence
from contactqp.core.operators import as_operator
from contactqp.core.surface import SurfaceProblem
from contactqp.errors import InvalidInputError

E, NU, CELL, RADIUS = 210e9, 0.3, 1e-5, 5e-3
E_STAR = E / (1 - NU**2)


def hertz(n: int, fixed: str = "load") -> SurfaceProblem:
    """A sphere on an ``n x n`` FFT half-space, pressed to a contact radius of about n / 4."""
    x, y = grid(n, n, CELL, CELL)
    s = ((x - x.mean()) ** 2 + (y - y.mean()) ** 2) / (2 * RADIUS)
    a = n / 4 * CELL
    W = HalfSpaceOperator(n, n, CELL, CELL, E, NU)
    if fixed == "load":
        return SurfaceProblem(W, s, load=4 * E_STAR * a**3 / (3 * RADIUS))
    return SurfaceProblem(W, s, approach=a * a / RADIUS)


def rough(n: int, seed: int = 3) -> SurfaceProblem:
    """A periodic random surface (a few cells' correlation), pressed to about 10 % contact."""
    rng = np.random.default_rng(seed)
    q = np.hypot(*np.meshgrid(np.fft.fftfreq(n), np.fft.fftfreq(n)))
    h = np.fft.ifft2(np.fft.fft2(rng.standard_normal((n, n))) * (q < 0.1)).real
    h *= 1e-7 / h.std()
    W = HalfSpaceOperator(n, n, CELL, CELL, E, NU, periodic=True)
    slope = 1e-7 / (10 * CELL)  # about: h_rms over the correlation length
    return SurfaceProblem(W, (h.max() - h).ravel(), load=0.15 * E_STAR * slope * (n * CELL) ** 2)


def assert_same_answer(aided, plain):
    assert aided.success and plain.success
    scale = plain.forces.max()
    # both at tol 1e-10 of the length scale: the forces agree far below 1e-6 of the peak
    assert np.max(np.abs(aided.forces - plain.forces)) <= 1e-6 * scale
    assert np.array_equal(aided.contact, plain.contact)
    assert aided.approach == pytest.approx(plain.approach, rel=1e-8)


# --- the aids, against the operator -----------------------------------------------------------


@pytest.mark.parametrize("nx, ny", [(32, 32), (24, 40)])
def test_the_periodic_preconditioner_inverts_the_operator(nx, ny):
    W = HalfSpaceOperator(nx, ny, CELL, 1.5 * CELL, E, NU, periodic=True)
    M = W.preconditioner()
    x = np.random.default_rng(1).standard_normal(nx * ny)
    x -= x.mean()  # the mean mode is W's null space
    everywhere = np.ones(nx * ny, dtype=bool)
    assert np.max(np.abs(M(W @ x, everywhere) - x)) <= 1e-12 * np.max(np.abs(x))


def test_the_box_preconditioner_is_symmetric_positive_definite_on_the_contact():
    W = HalfSpaceOperator(40, 40, CELL, CELL, E, NU)
    M = W.preconditioner()
    rng = np.random.default_rng(2)
    x, y = grid(40, 40, 1.0, 1.0)
    on = (x - 14) ** 2 + (y - 22) ** 2 < 81  # a disc off the centre
    a, b = rng.standard_normal((2, 1600)) * on
    Ma, Mb = M(a, on), M(b, on)
    assert float(a @ (Mb * on)) == pytest.approx(float(b @ (Ma * on)), rel=1e-12)
    assert float(a @ (Ma * on)) > 0.0
    # and it is near W's inverse on the contact: a^T M W_CC a over a^T a within a factor 2 of 1
    Wa = np.where(on, W @ a, 0.0)
    ratio = float(a @ (M(Wa, on) * on)) / float(a @ a)
    assert 0.5 < ratio < 2.0


def test_the_coarsening_is_the_operator_of_the_merged_cells():
    W = HalfSpaceOperator(64, 32, CELL, 2 * CELL, E, NU)
    coarse = W.coarsening()
    direct = HalfSpaceOperator(32, 16, 2 * CELL, 4 * CELL, E, NU)
    f = np.random.default_rng(4).uniform(size=512)
    assert np.allclose(coarse.operator @ f, direct @ f, rtol=1e-13, atol=0)
    x, y = grid(64, 32, CELL, 2 * CELL)
    X, Y = grid(32, 16, 2 * CELL, 4 * CELL)
    # the mean over merged cells: exact for a linear field, centre to centre
    assert np.allclose(coarse.restrict(3 * x - y), 3 * X - Y, rtol=1e-13, atol=1e-18)
    forces = coarse.prolong(f)
    assert forces.sum() == pytest.approx(f.sum(), rel=1e-14)
    assert np.allclose(coarse.restrict(forces) * 4, f, rtol=1e-14, atol=0)


@pytest.mark.parametrize(
    "W",
    [
        HalfSpaceOperator(30, 31, CELL, CELL, E, NU),  # an odd side
        HalfSpaceOperator(24, 24, CELL, CELL, E, NU),  # 12 cells after merging: too few
    ],
)
def test_no_coarsening_where_none_is_exact(W):
    assert W.coarsening() is None


def test_the_full_coarsening_merges_each_component_apart():
    W = HalfSpaceOperator(32, 32, CELL, CELL, E, NU, components="full")
    coarse = W.coarsening()
    direct = HalfSpaceOperator(16, 16, 2 * CELL, 2 * CELL, E, NU, components="full")
    f = np.random.default_rng(5).standard_normal(3 * 256)
    assert np.allclose(coarse.operator @ f, direct @ f, rtol=1e-13, atol=0)
    forces = coarse.prolong(f).reshape(-1, 3)
    assert np.allclose(forces.sum(axis=0), f.reshape(-1, 3).sum(axis=0), rtol=1e-13)
    assert np.allclose(coarse.restrict(forces.ravel()) * 4, f, rtol=1e-14, atol=0)


def test_a_dense_compliance_runs_without_the_aids():
    x, y = grid(12, 12, CELL, CELL)
    W = normal_influence(x, y, CELL, CELL, E, NU)
    s = ((x - x.mean()) ** 2 + (y - y.mean()) ** 2) / (2 * RADIUS)
    assert as_operator(W).coarsening() is None and as_operator(W).preconditioner() is None
    result = cq.solve(SurfaceProblem(W, s, approach=1e-7))
    assert result.success and not result.info["preconditioned"] and result.info["levels"] == []


# --- the same answer, fewer iterations ----------------------------------------------------


@pytest.mark.parametrize("fixed", ["load", "approach"])
def test_the_aided_hertz_solve_is_the_plain_one(fixed):
    problem = hertz(128, fixed)
    aided = cq.solve(problem, tol=1e-10)
    plain = cq.solve(problem, tol=1e-10, precondition=False, multilevel=False)
    assert_same_answer(aided, plain)
    assert aided.info["preconditioned"] and not plain.info["preconditioned"]
    # 128 -> 64 -> 32 -> 16 cells a side, coarsest first
    assert [level["points"] for level in aided.info["levels"]] == [256, 1024, 4096]
    assert aided.iterations < plain.iterations / 2


@pytest.mark.parametrize("precondition, multilevel", [(True, False), (False, True)])
def test_each_aid_alone_gives_the_same_answer(precondition, multilevel):
    problem = hertz(64)
    one = cq.solve(problem, tol=1e-10, precondition=precondition, multilevel=multilevel)
    plain = cq.solve(problem, tol=1e-10, precondition=False, multilevel=False)
    assert_same_answer(one, plain)


def test_the_aided_rough_solve_is_the_plain_one():
    problem = rough(64)
    aided = cq.solve(problem, tol=1e-10)
    plain = cq.solve(problem, tol=1e-10, precondition=False, multilevel=False)
    assert_same_answer(aided, plain)
    assert 0.02 < np.mean(aided.contact) < 0.5  # several patches, not full contact
    assert aided.iterations < plain.iterations


def test_a_warm_start_skips_the_coarse_solves():
    problem = hertz(64)
    first = cq.solve(problem, tol=1e-10)
    again = cq.solve(problem, tol=1e-10, r0=first.forces)
    assert again.success and again.info["levels"] == [] and again.iterations <= 1


@pytest.mark.parametrize("option", ["precondition", "multilevel"])
def test_bad_flags_are_named(option):
    with pytest.raises(InvalidInputError, match=f"{option} must be True or False"):
        cq.solve(hertz(32), **{option: "yes"})

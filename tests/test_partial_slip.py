"""Partial slip through operators: Cattaneo-Mindlin, the dense Coulomb route, histories."""

import numpy as np
import pytest

import contactqp as cq
from contactqp.compliance import grid, influence_matrix
from contactqp.compliance.fft_halfspace import HalfSpaceOperator
from contactqp.core.local_problem import LocalProblem
from contactqp.core.sliding_surface import SlidingSurfaceProblem, certify_sliding
from contactqp.core.status import ContactStatus
from contactqp.core.surface import SurfaceProblem
from contactqp.errors import InvalidInputError
from contactqp.methods.tangential_fista import shear_history

E, NU, MU, RS, H = 210e9, 0.3, 0.3, 5e-3, 1e-5
E_STAR, G = E / (1 - NU**2), E / (2 * (1 + NU))


def sphere(n, cells_per_radius, ratio, *, fixed="load"):
    """A rigid sphere pressed to a contact radius of ``cells_per_radius`` cells, then shifted by
    Mindlin's displacement for ``Q / (mu P) = ratio``."""
    a = cells_per_radius * H
    x, y = grid(n, n, H, H)
    load = 4 / 3 * E_STAR * a**3 / RS
    pressing = {"load": load} if fixed == "load" else {"approach": a * a / RS}
    surface = SurfaceProblem(
        HalfSpaceOperator(n, n, H, H, E, NU), (x * x + y * y) / (2 * RS), **pressing
    )
    full = HalfSpaceOperator(n, n, H, H, E, NU, components="full", coupling=False)
    delta = 3 * MU * load * (2 - NU) / (16 * G * a) * (1 - (1 - ratio) ** (2 / 3))
    return surface, full, delta, a, x, y


@pytest.mark.parametrize(("n", "cells"), [(64, 24), (128, 40)])
def test_cattaneo_mindlin_stick_radius_and_load(n, cells):
    surface, full, delta, a, x, y = sphere(n, cells, 0.5)
    result = cq.solve(SlidingSurfaceProblem(surface, full, MU, shift=(delta, 0.0)))
    assert result.success and result.method == "tangential-fista"
    assert result.certificate.natural_map <= 1e-8
    P, (Qx, Qy) = result.load, result.tangential_force
    ratio = Qx / (MU * P)
    # Q against Mindlin's at this shift: the discretised contact (a to about 1/2 cell of
    # 24-40) moves it by a few 1e-4 (measured 2e-4 at 128^2)
    assert ratio == pytest.approx(0.5, abs=5e-3)
    assert abs(Qy) <= 1e-10 * Qx  # symmetric about y = 0
    # the stick zone: the disc of the same area as the sticking cells, known to half a cell
    stick_radius = np.sqrt(np.count_nonzero(result.stick) * H * H / np.pi)
    assert abs(stick_radius - a * (1 - ratio) ** (1 / 3)) <= 0.5 * H
    # every sticking cell inside the theory's stick circle (to a cell's half-diagonal)
    r = np.hypot(x, y)
    assert r[result.stick].max() <= a * (1 - ratio) ** (1 / 3) + 0.71 * H
    # the slipping cells' forces at the cone, along +x (the sphere moved along +x)
    t = result.forces[result.slip, 1:]
    bound = MU * result.forces[result.slip, 0]
    assert np.allclose(np.hypot(t[:, 0], t[:, 1]), bound, rtol=1e-8)
    assert np.all(t[:, 0] > 0)


def dense_partial_slip(x, y, a, delta, coupling):
    """The dense route's answer (influence_matrix, LocalProblem, coulomb), as
    examples/cattaneo_mindlin.py builds it, at a fixed approach: ``(forces (m, 3), statuses)``."""
    n2 = x.size
    R = influence_matrix(x, y, H, H, E, NU, coupling=coupling)
    order = (3 * np.arange(n2)[:, None] + [2, 0, 1]).ravel()  # (N, T1, T2) = (-z, x, y)
    sign = np.tile([-1.0, 1.0, 1.0], n2)
    W = R[np.ix_(order, order)] * np.outer(sign, sign)
    q = np.zeros(3 * n2)
    q[0::3] = (x * x + y * y) / (2 * RS) - a * a / RS
    q[1::3] = -delta
    length = a * a / RS
    force = length / W[0, 0]
    dense = cq.solve(
        LocalProblem(W * (force / length), q / length, np.full(n2, MU), 3), "coulomb", tol=1e-12
    )
    assert dense.success
    return force * dense.forces.reshape(-1, 3), dense.contact_status


def test_agrees_with_the_dense_coulomb_route():
    """The dense route on the same 14 x 14 grid at a fixed approach."""
    n, cells = 14, 4
    surface, full, delta, a, x, y = sphere(n, cells, 0.6, fixed="approach")
    result = cq.solve(SlidingSurfaceProblem(surface, full, MU, shift=(delta, 0.0)), tol=1e-12)
    assert result.success and result.info["rounds"] == 1 and not result.info["coupled"]
    r, status = dense_partial_slip(x, y, a, delta, coupling=False)
    scale = r[:, 0].max()
    # both certified near 1e-10: forces agree far below the natural-map tolerance 1e-8
    assert np.max(np.abs(result.forces - r)) <= 1e-7 * scale
    assert np.array_equal(result.stick, status == ContactStatus.STICK)


@pytest.mark.parametrize("ratio", [0.6, 0.0])
def test_a_coupled_compliance_agrees_with_the_dense_coulomb_route(ratio):
    """With the (1 - 2 nu) coupling (nu = 0.3), pressing and shifting in one increment: the
    normal and tangential solves alternate until they agree, and the answer is the dense route's
    on the coupled W (both to 1e-12). At zero shift this is Spence's frictional indentation:
    a sticking centre, an annulus slipping radially, no net tangential force."""
    n, cells = 14, 4
    surface, _, delta, a, x, y = sphere(n, cells, ratio, fixed="approach")
    coupled = HalfSpaceOperator(n, n, H, H, E, NU, components="full")
    problem = SlidingSurfaceProblem(surface, coupled, MU, shift=(delta, 0.0))
    result = cq.solve(problem, tol=1e-12)
    assert result.success and result.info["coupled"] and result.info["rounds"] > 1
    assert result.certificate.natural_map <= 1e-10
    r, status = dense_partial_slip(x, y, a, delta, coupling=True)
    scale = r[:, 0].max()
    assert np.max(np.abs(result.forces - r)) <= 1e-9 * scale
    assert np.array_equal(result.contact_status, status)
    assert np.any(result.stick) and np.any(result.slip)
    # the coupling matters: the uncoupled answer differs far beyond the solvers' accuracy
    uncoupled, _ = dense_partial_slip(x, y, a, delta, coupling=False)
    assert np.max(np.abs(uncoupled - r)) > 1e-3 * scale
    if ratio == 0.0:
        t = result.forces[:, 1:]
        assert np.max(np.abs(result.tangential_force)) <= 1e-9 * MU * result.load
        radial = (t[:, 0] * x + t[:, 1] * y)[result.slip]
        assert np.all(np.sign(radial) == np.sign(radial[0]))  # one sense all around
        # mostly radial: a square grid is not axisymmetric, and the circumferential part it
        # leaves is measured below 1 % of the radial one here
        tangential = (t[:, 1] * x - t[:, 0] * y)[result.slip]
        assert np.max(np.abs(tangential)) <= 0.05 * np.max(np.abs(radial))
    # the certificate judges the coupled problem: the uncoupled solve's answer fails it
    plain = HalfSpaceOperator(n, n, H, H, E, NU, components="full", coupling=False)
    wrong = cq.solve(SlidingSurfaceProblem(surface, plain, MU, shift=(delta, 0.0)), tol=1e-12)
    p, t = wrong.forces[:, 0], wrong.forces[:, 1:]
    assert not certify_sliding(problem, t, p, wrong.approach).passed


def test_history_warm_starts_and_matches_one_step():
    surface, full, delta, a, x, y = sphere(48, 16, 0.8)
    shifts = [(delta * k / 5, 0.0) for k in range(1, 6)]
    history = shear_history(surface, full, MU, shifts)
    assert all(r.success for r in history)
    Q = [r.tangential_force[0] for r in history]
    assert np.all(np.diff(Q) > 0)  # a growing shear
    slips = [np.count_nonzero(r.slip) for r in history]
    assert np.all(np.diff(slips) >= 0)  # the slip annulus only grows
    one = cq.solve(SlidingSurfaceProblem(surface, full, MU, shift=shifts[-1]))
    # monotonic shear is path independent (Cattaneo-Mindlin): the five increments, each from
    # the one before, end at the one-step answer, the same stick zone and Q (measured 1.3e-5);
    # the tractions differ only in the directions the increments' slips give near the stick
    # boundary (measured 1.4e-3 of the peak force)
    assert np.array_equal(history[-1].stick, one.stick)
    assert history[-1].tangential_force[0] == pytest.approx(one.tangential_force[0], rel=1e-4)
    assert np.max(np.abs(one.forces - history[-1].forces)) <= 5e-3 * one.forces[:, 0].max()
    assert history[-1].info["lipschitz"] == history[0].info["lipschitz"]  # computed once


def test_unloading_follows_mindlin_and_deresiewicz():
    """Sheared to Q* = 0.8 mu P in six increments, then unloaded step by step past zero: each
    increment's law acts on its own slip, and the force follows Mindlin and Deresiewicz's
    unloading branch ``Q = Q* - 2 Q_M((delta* - delta) / 2)``, ``Q_M`` the loading curve (to
    5e-3 of mu P: the loading's discretisation, measured 4e-4)."""
    surface, full, delta, a, x, y = sphere(48, 16, 0.8)
    P = surface.load
    compliance = 3 * MU * P * (2 - NU) / (16 * G * a)

    def loading(shift):  # Mindlin: Q(delta) of the virgin loading curve
        return MU * P * (1 - (1 - shift / compliance) ** 1.5)

    back = [delta * f for f in (0.75, 0.5, 0.25, 0.0, -0.25)]
    shifts = [(delta * k / 6, 0.0) for k in range(1, 7)] + [(d, 0.0) for d in back]
    history = shear_history(surface, full, MU, shifts)
    assert all(r.success and r.certificate.natural_map <= 1e-8 for r in history)
    peak = loading(delta)  # 0.8 mu P by the construction of delta
    for d, result in zip(back, history[6:], strict=True):
        theory = peak - 2 * loading((delta - d) / 2)
        assert result.tangential_force[0] == pytest.approx(theory, abs=5e-3 * MU * P)
    # unloading slips a new annulus from the edge: the stick zone shrinks, then reverses
    sticks = [np.count_nonzero(r.stick) for r in history[5:]]
    assert sticks[1] > sticks[0]  # the first unloading step sticks everywhere inside
    assert history[9].tangential_force[0] < 0  # back at zero shift the force has reversed


def test_gross_slip_carries_mu_p():
    surface, full, delta, a, x, y = sphere(32, 10, 0.5)
    result = cq.solve(SlidingSurfaceProblem(surface, full, MU, shift=(0.0, -50 * delta)))
    assert result.success
    assert not np.any(result.stick)
    t = result.forces[:, 1:]
    # every cell at the cone: the force magnitudes add up to mu P
    assert np.sum(np.hypot(t[:, 0], t[:, 1])) == pytest.approx(MU * result.load, rel=1e-12)
    # along -y, up to the slight obliquity of the slip Cerruti's coupling of u_x and t_y gives
    # for nu > 0 (measured 3e-7 here), symmetric about x = 0
    Q = result.tangential_force
    assert Q[1] == pytest.approx(-MU * result.load, rel=1e-5)
    assert abs(Q[0]) <= 1e-12 * MU * result.load


def test_certificate_catches_a_wrong_answer():
    surface, full, delta, a, x, y = sphere(32, 10, 0.5)
    problem = SlidingSurfaceProblem(surface, full, MU, shift=(delta, 0.0))
    result = cq.solve(problem)
    p, t = result.forces[:, 0], result.forces[:, 1:]
    assert certify_sliding(problem, t, p, result.approach).passed
    assert not certify_sliding(problem, 0.98 * t, p, result.approach).passed  # stick cells slip
    assert not certify_sliding(problem, 1.02 * t, p, result.approach).passed  # outside the cone
    assert not certify_sliding(problem, t[:, ::-1], p, result.approach).passed  # misaligned
    assert not certify_sliding(problem, t * np.nan, p, result.approach).finite


def test_refuses_a_coupled_history_and_bad_input():
    surface, full, delta, a, x, y = sphere(16, 5, 0.5)
    coupled = HalfSpaceOperator(16, 16, H, H, E, NU, components="full")
    with pytest.raises(InvalidInputError, match="max_outer must be"):
        cq.solve(SlidingSurfaceProblem(surface, coupled, MU, shift=(delta, 0.0)), max_outer=0)
    stopped = cq.solve(SlidingSurfaceProblem(surface, coupled, MU, shift=(delta, 0.0)), max_outer=2)
    assert not stopped.success and "did not settle in max_outer = 2" in stopped.message
    other = HalfSpaceOperator(16, 16, H, H, 2 * E, NU, components="full", coupling=False)
    with pytest.raises(InvalidInputError, match="normal .zz. entries"):
        cq.solve(SlidingSurfaceProblem(surface, other, MU, shift=(delta, 0.0)))
    with pytest.raises(InvalidInputError, match="compliance must have shape"):
        SlidingSurfaceProblem(surface, surface.compliance, MU, shift=(delta, 0.0))
    with pytest.raises(InvalidInputError, match="mu must be"):
        SlidingSurfaceProblem(surface, full, -0.1, shift=(delta, 0.0))
    with pytest.raises(InvalidInputError, match="shift must be"):
        SlidingSurfaceProblem(surface, full, MU, shift=(delta, 0.0, 0.0))
    with pytest.raises(InvalidInputError, match="surface must be a SurfaceProblem"):
        SlidingSurfaceProblem(None, full, MU, shift=(delta, 0.0))
    with pytest.raises(InvalidInputError, match="previous: the slips of the state before"):
        SlidingSurfaceProblem(surface, full, MU, shift=(delta, 0.0), previous=np.zeros((3, 2)))


def test_a_coupled_press_then_shear():
    """With the coupling (nu = 0.3) a press leaves Spence's frictional tractions, and the
    shear starts from them: the pressing increment is the one-step answer at zero shift, and
    every increment after it is certified on its own law (the coupled natural map)."""
    n, cells = 14, 4
    surface, _, delta, a, x, y = sphere(n, cells, 0.6, fixed="approach")
    coupled = HalfSpaceOperator(n, n, H, H, E, NU, components="full")
    history = shear_history(
        surface, coupled, MU, [(0.0, 0.0), (0.5 * delta, 0.0), (delta, 0.0)], tol=1e-12
    )
    assert all(r.success and r.info["coupled"] for r in history)
    assert all(r.certificate.natural_map <= 1e-10 for r in history)
    pressed = cq.solve(SlidingSurfaceProblem(surface, coupled, MU, shift=(0.0, 0.0)), tol=1e-12)
    scale = pressed.forces[:, 0].max()
    assert np.max(np.abs(history[0].forces - pressed.forces)) <= 1e-9 * scale
    assert abs(history[0].tangential_force[0]) <= 1e-9 * MU * pressed.load  # no net shear
    Q = [r.tangential_force[0] for r in history]
    assert Q[0] < Q[1] < Q[2] < MU * history[2].load
    # the press-then-shear path differs from pressing and shifting at once (the coupling
    # makes the history matter)
    together = cq.solve(SlidingSurfaceProblem(surface, coupled, MU, shift=(delta, 0.0)), tol=1e-12)
    assert np.max(np.abs(together.forces - history[2].forces)) > 1e-2 * scale  # measured 0.19


def test_fixed_force_finds_the_shift():
    """At the force a shift gives, the shift comes back (to the solves' 1e-10), with the same
    forces; an oblique force is carried exactly."""
    surface, full, delta, a, x, y = sphere(32, 10, 0.5)
    by_shift = cq.solve(SlidingSurfaceProblem(surface, full, MU, shift=(delta, 0.0)))
    problem = SlidingSurfaceProblem(surface, full, MU, force=by_shift.tangential_force)
    by_force = cq.solve(problem)
    assert by_force.success
    assert by_force.shift == pytest.approx([delta, 0.0], abs=1e-8 * delta)
    assert np.max(np.abs(by_force.forces - by_shift.forces)) <= 1e-8 * by_shift.load
    Q = np.array([0.3, -0.4]) * MU * by_shift.load
    oblique = cq.solve(SlidingSurfaceProblem(surface, full, MU, force=Q))
    assert oblique.success and oblique.certificate.natural_map <= 1e-8
    assert oblique.tangential_force == pytest.approx(Q, rel=1e-12)
    assert oblique.shift[0] > 0 > oblique.shift[1]
    p, t = oblique.forces[:, 0], oblique.forces[:, 1:]
    assert not certify_sliding(problem, t, p, oblique.approach, oblique.shift).passed  # load
    with pytest.raises(InvalidInputError, match="friction limit"):
        cq.solve(SlidingSurfaceProblem(surface, full, MU, force=(1.01 * MU * by_shift.load, 0)))
    with pytest.raises(InvalidInputError, match="exactly one of shift"):
        SlidingSurfaceProblem(surface, full, MU, shift=(delta, 0.0), force=(1.0, 0.0))
    with pytest.raises(InvalidInputError, match="exactly one of shift"):
        SlidingSurfaceProblem(surface, full, MU)


@pytest.mark.parametrize("ratio", [0.3, 0.7])
def test_a_periodic_asperity_is_hertz_and_mindlin(ratio):
    """One asperity per period, ``h = h0 (cos qx + cos qy)`` (tip radius ``1 / (h0 q^2)``),
    pressed to a Hertz radius of an eighth of the period and sheared by ``Q`` (force given:
    the periodic shift is free): the contact radius is Hertz's and the stick radius
    Mindlin's, each to the grid and the images' small pull."""
    n, L = 128, 128 * H
    q = 2 * np.pi / L
    x, y = grid(n, n, H, H)
    x, y = x - x.min() - L / 2 + H / 2, y - y.min() - L / 2 + H / 2  # the tip at a cell centre
    h0 = 1e-6
    tip = 1 / (h0 * q * q)
    s = h0 * (2 - np.cos(q * x) - np.cos(q * y))
    a = L / 8
    load = 4 * E_STAR * a**3 / (3 * tip)
    normal = HalfSpaceOperator(n, n, H, H, E, NU, periodic=True)
    full = HalfSpaceOperator(n, n, H, H, E, NU, periodic=True, components="full", coupling=False)
    problem = SlidingSurfaceProblem(
        SurfaceProblem(normal, s, load=load), full, MU, force=(ratio * MU * load, 0.0)
    )
    result = cq.solve(problem)
    assert result.success and result.certificate.natural_map <= 1e-8
    assert result.tangential_force[0] == pytest.approx(ratio * MU * load, rel=1e-12)
    contact = result.forces[:, 0] > 0
    radius = np.sqrt(np.count_nonzero(contact) * H * H / np.pi)
    stick = np.sqrt(np.count_nonzero(result.stick) * H * H / np.pi)
    assert abs(radius - a) <= H  # measured 0.47 of a cell above Hertz's
    # Mindlin's stick radius on the measured contact: measured 0.08 of a cell below
    assert abs(stick - radius * (1 - ratio) ** (1 / 3)) <= 0.5 * H
    with pytest.raises(InvalidInputError, match="give the tangential force instead"):
        SlidingSurfaceProblem(SurfaceProblem(normal, s, load=load), full, MU, shift=(1e-7, 0.0))
    plain = HalfSpaceOperator(n, n, H, H, E, NU, components="full", coupling=False)
    with pytest.raises(InvalidInputError, match="both periodic or both not"):
        SlidingSurfaceProblem(SurfaceProblem(normal, s, load=load), plain, MU, force=(1.0, 0.0))

"""SurfaceProblem and its methods against independent truths on small (dense) grids.

The constrained conjugate gradient (``constrained-cg``) against the project's frictionless
active-set solver of the same compliance written as a reduced model (ContactProblem), and
against the second surface method (``surface-active-set``); the certificate against answers
made wrong on purpose; the input checks. Half-space truths on large grids (Hertz, punch,
Westergaard) are in test_surface_theory.py.
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp as cq
from contactqp.compliance import grid, normal_influence
from contactqp.core.operators import Operator
from contactqp.core.surface import certify_surface

E, NU, CELL, RADIUS = 210e9, 0.3, 1e-5, 5e-3  # steel, 10 um cells, a 5 mm sphere


def sphere(n: int, rough: float = 0.0, seed: int = 0):
    """``(W, s)``: the dense compliance of an ``n x n`` patch and a sphere's separation, with
    random bumps of amplitude ``rough`` (m) added (several contact patches)."""
    x, y = grid(n, n, CELL, CELL)
    x, y = x - x.mean(), y - y.mean()
    W = normal_influence(x, y, CELL, CELL, E, NU)
    s = (x**2 + y**2) / (2 * RADIUS)
    if rough:
        s = s + rough * np.random.default_rng(seed).uniform(0.0, 1.0, s.size)
    return W, s


class ProductsOnly(Operator):
    """A dense matrix seen through its products only (blocks refused): what an FFT operator
    offers a method that must not form W."""

    def __init__(self, W):
        super().__init__(W.shape)
        self._W = W
        self.products = 0

    def __matmul__(self, x):
        self.products += 1
        return self._W @ x

    def diagonal(self):
        return np.diag(self._W).copy()

    def block(self, rows=None, cols=None):
        raise AssertionError("constrained-cg asked for a block of W")


# --- against the project's frictionless solver -------------------------------------------


@pytest.mark.parametrize("n, rough", [(12, 0.0), (20, 0.0), (16, 2e-7)])
def test_fixed_approach_equals_the_active_set_solve_of_the_same_model(n, rough):
    W, s = sphere(n, rough)
    approach = 6e-7
    operator = ProductsOnly(W)
    result = cq.solve(cq.SurfaceProblem(operator, s, approach=approach), tol=1e-12)
    assert result.success, result.message
    assert result.method == "constrained-cg" and result.approach == approach
    # the reduced model of the same cells: gaps s - delta, no loads, one freedom per cell
    reference = cq.solve_gaps(W, np.zeros(s.size), s - approach)
    assert reference.success
    # a gap residual of 1e-12 of the displacements moves the forces by at most about
    # cond(W_CC) times that: 1e-8 of the peak force is 4 orders of margin on these grids
    scale = reference.forces.max()
    np.testing.assert_allclose(result.forces, reference.forces, rtol=0, atol=1e-8 * scale)
    np.testing.assert_array_equal(result.contact, reference.forces > 1e-10 * scale)
    np.testing.assert_allclose(result.gaps, reference.gaps, rtol=0, atol=1e-8 * approach)
    assert result.load == pytest.approx(reference.forces.sum(), rel=1e-9)
    # the answer's displacements are W r (one more product, the certificate's)
    np.testing.assert_allclose(result.displacements, W @ result.forces, rtol=1e-12)
    # the start, one per step, a fresh one after a projection, the certificate's
    assert result.iterations + 2 <= operator.products <= 2 * result.iterations + 3


@pytest.mark.parametrize("n, rough", [(12, 0.0), (18, 3e-7)])
def test_fixed_load_finds_the_approach_of_that_load(n, rough):
    W, s = sphere(n, rough)
    load = 5.0
    result = cq.solve(cq.SurfaceProblem(ProductsOnly(W), s, load=load), tol=1e-12)
    assert result.success, result.message
    assert result.load == pytest.approx(load, rel=1e-13)
    assert result.certificate.equilibrium <= 1e-13
    # the reduced model at the approach found carries the same forces, hence the load
    reference = cq.solve_gaps(W, np.zeros(s.size), s - result.approach)
    scale = reference.forces.max()
    np.testing.assert_allclose(result.forces, reference.forces, rtol=0, atol=1e-8 * scale)
    assert reference.forces.sum() == pytest.approx(load, rel=1e-8)


@pytest.mark.parametrize("given", ["load", "approach"])
def test_the_two_surface_methods_agree(given):
    W, s = sphere(16, 1e-7, seed=3)
    problem = cq.SurfaceProblem(W, s, **{given: 4.0 if given == "load" else 5e-7})
    cg = cq.solve(problem, tol=1e-12)
    active = cq.solve(problem, "surface-active-set", tol=1e-12)
    assert cg.success and active.success, (cg.message, active.message)
    assert active.method == "surface-active-set"
    scale = active.forces.max()
    np.testing.assert_allclose(cg.forces, active.forces, rtol=0, atol=1e-8 * scale)
    assert cg.approach == pytest.approx(active.approach, rel=1e-8)
    if given == "load":
        assert active.load == pytest.approx(4.0, rel=1e-10) and active.info["newton"] >= 1


def test_an_indenter_that_does_not_reach_the_surface_carries_nothing():
    W, s = sphere(8)
    result = cq.solve(cq.SurfaceProblem(W, s + 1e-6, approach=5e-7))
    assert result.success and result.iterations == 0
    assert not np.any(result.forces) and result.contact_fraction == 0.0 and result.load == 0.0
    np.testing.assert_allclose(result.gaps, s + 5e-7)


def test_warm_start_from_the_answer_takes_no_step_and_a_nearby_one_fewer():
    W, s = sphere(16)
    cold = cq.solve(cq.SurfaceProblem(W, s, load=3.0))
    again = cq.solve(cq.SurfaceProblem(W, s, load=3.0), r0=cold.forces)
    assert again.iterations == 0 and again.success
    nearby = cq.solve(cq.SurfaceProblem(W, s, load=3.3), r0=cold.forces)
    fresh = cq.solve(cq.SurfaceProblem(W, s, load=3.3))
    assert nearby.success and nearby.iterations < fresh.iterations
    np.testing.assert_allclose(nearby.forces, fresh.forces, rtol=0, atol=1e-7 * fresh.forces.max())


def test_a_method_out_of_iterations_says_so():
    W, s = sphere(16)
    result = cq.solve(cq.SurfaceProblem(W, s, load=3.0), max_iter=2)
    assert not result.success and result.status == 1 and result.iterations == 2
    assert "max_iter = 2" in result.message


# --- the certificate ---------------------------------------------------------------------


def test_the_certificate_judges_the_problem_not_the_method():
    W, s = sphere(14)
    problem = cq.SurfaceProblem(W, s, load=3.0)
    good = cq.solve(problem)
    assert good.certificate.passed and good.certificate.worst <= 1e-9
    r, delta = good.forces, good.approach
    # more approach than the forces balance: the contact penetrates
    worse = certify_surface(problem, r, delta * (1 + 1e-4))
    assert worse.penetration > 1e-6 and not worse.passed
    # a pulling force
    pulled = r.copy()
    pulled[np.argmin(s + 1.0 * (r > 0))] = -1e-3 * r.max()  # an open cell pulled
    assert certify_surface(problem, pulled, delta).force_sign == pytest.approx(1e-3, rel=1e-9)
    # force on an open cell: complementarity fails
    pushed = r.copy()
    pushed[np.argmax(s)] = 0.01 * r.max()
    assert certify_surface(problem, pushed, delta).complementarity > 1e-5
    # the load not carried
    assert certify_surface(problem, 0.9 * r, delta).equilibrium == pytest.approx(0.1, rel=1e-9)
    assert np.isinf(certify_surface(problem, np.full(s.size, np.nan), delta).worst)


def test_a_result_reads_like_the_other_results():
    W, s = sphere(12)
    result = cq.solve(cq.SurfaceProblem(W, s, load=2.0))
    assert isinstance(result, cq.ContactResult)
    summary = result.summary()
    assert summary["load"] == pytest.approx(2.0) and summary["approach"] == result.approach
    assert summary["closed"] == int(result.contact.sum()) > 0
    assert summary["contact_fraction"] == pytest.approx(result.contact.mean())
    assert summary["certificate"]["passed"] is True
    assert result.energy == pytest.approx(0.5 * result.forces @ (W @ result.forces), rel=1e-12)
    assert "SurfaceResult" in result._repr_html_() and "constrained-cg" in repr(result)


# --- bad input ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "arguments, match",
    [
        ({}, "give exactly one of load .* got neither"),
        ({"load": 1.0, "approach": 0.0}, "give exactly one of load .* got both"),
        ({"load": -1.0}, "load must be a positive finite force in N, got -1.0"),
        ({"load": 0.0}, "load must be a positive finite force"),
        ({"load": np.nan}, "load must be a positive finite force"),
        ({"load": "1"}, "load must be a positive finite force"),
        ({"approach": np.inf}, "approach must be a finite length in m"),
        ({"approach": True}, "approach must be a finite length in m"),
        ({"load": 1.0, "certificate_tol": 0.0}, "certificate_tol must be a positive"),
    ],
)
def test_bad_load_or_approach_is_named(arguments, match):
    with pytest.raises(cq.InvalidInputError, match=match):
        cq.SurfaceProblem(np.eye(3), np.zeros(3), **arguments)


@pytest.mark.parametrize(
    "compliance, separation, match",
    [
        (np.eye(3), np.zeros(4), r"separation must have shape \(3,\) to match the compliance"),
        (np.eye(3), np.zeros((3, 1)), "separation must be 1-D, got shape"),
        (np.eye(3), [0.0, np.nan, 0.0], "separation contains NaN or inf"),
        (np.ones((3, 2)), np.zeros(3), "W must be square"),
        (np.zeros((0, 0)), np.zeros(0), "separation must hold at least one point"),
    ],
)
def test_bad_compliance_or_separation_is_named(compliance, separation, match):
    with pytest.raises(cq.InvalidInputError, match=match):
        cq.SurfaceProblem(compliance, separation, load=1.0)


@pytest.mark.parametrize("method", ["constrained-cg", "surface-active-set"])
@pytest.mark.parametrize(
    "options, match",
    [
        ({"tol": 0.0}, "tol must be a positive finite number"),
        ({"max_iter": 0}, "max_iter must be an integer >= 1"),
        ({"r0": np.ones(5)}, r"r0 must have shape \(64,\)"),
        ({"facets": 8}, "unknown option 'facets'"),
    ],
)
def test_bad_options_are_named(method, options, match):
    W, s = sphere(8)
    with pytest.raises(cq.InvalidInputError, match=match):
        cq.solve(cq.SurfaceProblem(W, s, load=1.0), method, **options)


def test_a_surface_method_does_not_take_other_problems_nor_they_it():
    W, s = sphere(6)
    with pytest.raises(cq.InvalidInputError, match="does not solve frictionless problems"):
        cq.solve_gaps(W, np.zeros(s.size), s, method="constrained-cg")
    with pytest.raises(cq.InvalidInputError, match="does not solve surface problems"):
        cq.solve(cq.SurfaceProblem(W, s, load=1.0), "active-set")

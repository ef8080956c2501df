"""Cross-check routes for Coulomb friction: Tresca fixed point (Clarabel) and polygonal cones.

Truths used here:

* closed forms of a single contact with a diagonal ``W`` (normal and tangential decoupled):
  separation, stick and slip, and the polygonal law's reduced force across a side;
* the project's own Coulomb solver (semismooth Newton), an independent algorithm, on small
  random problems with ``W`` SPD and small ``mu``, where the solution is unique;
* the natural-map error, recomputed here from ``r`` alone.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from contactqp import InvalidInputError
from contactqp.core.friction import polygon_normals
from contactqp.core.local_problem import LocalProblem, natural_map_error
from contactqp.methods.coulomb import solve_coulomb
from contactqp.methods.polygonal import solve_polygonal
from contactqp.methods.tresca import solve_tresca_fixed_point

TOL = 1e-8


def random_problem(seed, dim, nc, mu_max=0.3, skew=0.0, cohesion=False):
    """W = B B^T / m + 0.2 I (SPD, condition number ~ 30), q ~ N(0, 1) (mixed open/stick/slip)."""
    rng = np.random.default_rng(seed)
    m = dim * nc
    B = rng.standard_normal((m, m))
    W = B @ B.T / m + 0.2 * np.eye(m)
    if skew:
        S = rng.standard_normal((m, m))
        W = W + skew * (S - S.T)
    c = np.where(rng.random(nc) < 0.5, 0.5 * rng.random(nc), 0.0) if cohesion else None
    return LocalProblem(W, rng.standard_normal(m), rng.uniform(0.05, mu_max, nc), dim, cohesion=c)


def single_contact(dim, q, a=2.0, b=3.0, mu=0.4):
    W = np.diag([a] + [b] * (dim - 1))
    return LocalProblem(W, np.asarray(q, dtype=float), [mu], dim)


def routes(dim):
    """Each route as (name, solver); the polygonal one is exact in 2-D only."""
    named = [("tresca", solve_tresca_fixed_point)]
    if dim == 2:
        named += [
            ("polygonal-clarabel", solve_polygonal),
            ("polygonal-daqp", lambda p, **k: solve_polygonal(p, backend="daqp", **k)),
        ]
    return named


# --------------------------------------------------------------------------------------------
# single contact, W = diag(a, b[, b]): r_N = -q_N / a when q_N < 0, then stick if the sticking
# force -q_T / b fits in the disc of radius mu r_N, else slip at mu r_N opposite to q_T


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("case", ["open", "stick", "slip"])
def test_single_contact_closed_forms(dim, case):
    a, b, mu = 2.0, 3.0, 0.4
    q_normal = {"open": 1.5, "stick": -4.0, "slip": -4.0}[case]
    q_tangent = {"open": [0.7, -0.2], "stick": [0.6, -0.8], "slip": [3.0, -4.0]}[case][: dim - 1]
    problem = single_contact(dim, [q_normal, *q_tangent], a, b, mu)
    q_tangent = np.asarray(q_tangent)
    if case == "open":
        expected = np.zeros(dim)
    else:
        normal = -q_normal / a  # 2.0, friction bound mu r_N = 0.8
        sticking = -q_tangent / b  # |.| = 1/3 (stick) or 5/3 (slip) in 3-D; 0.2 or 1.0 in 2-D
        fits = np.linalg.norm(sticking) <= mu * normal
        assert fits == (case == "stick")
        tangent = sticking if fits else mu * normal * sticking / np.linalg.norm(sticking)
        expected = np.concatenate([[normal], tangent])
    for name, solve in routes(dim):
        solution = solve(problem, tol=TOL)
        assert solution.success, (name, solution.message)
        assert np.allclose(solution.forces, expected, rtol=0, atol=1e-8), (name, solution.forces)
        assert solution.status_labels[0] == case


def test_polygonal_cone_reduces_the_force_across_a_side_not_at_a_vertex():
    """Sliding across the middle of side 0 (along the first tangent axis), the polygonal law
    transmits mu r_N cos(pi / F), 1 - cos(pi / F) less than Coulomb; sliding towards a vertex
    (angle pi / F) it transmits the full mu r_N. The exact-cone error is then nonzero and
    reported, not hidden."""
    a, b, mu, facets = 2.0, 3.0, 0.4, 8
    normal = 2.0
    for angle, reach in [(0.0, np.cos(np.pi / facets)), (np.pi / facets, 1.0)]:
        direction = np.array([np.cos(angle), np.sin(angle)])
        problem = single_contact(3, [-normal * a, *(-5.0 * direction)], a, b, mu)
        solution = solve_polygonal(problem, facets=facets, tol=1e-10)
        assert solution.success
        expected = np.concatenate([[normal], mu * normal * reach * direction])
        assert np.allclose(solution.forces, expected, rtol=0, atol=1e-8)
        error = natural_map_error(problem, solution.forces)
        assert error == pytest.approx(solution.certificate.natural_map, rel=1e-12)
        if reach < 1.0:
            assert error > 1e-3  # 7.6 % of the friction force is missing
            assert "exact cones" in solution.message
        else:
            assert error < 1e-8


def test_polygon_normals():
    normals = polygon_normals(6)
    assert normals.shape == (6, 2)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert np.allclose(normals[0], [1.0, 0.0])
    assert np.allclose(normals.sum(axis=0), 0.0, atol=1e-15)


# --------------------------------------------------------------------------------------------
# agreement with the own Coulomb solver where the solution is unique


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_routes_agree_with_solve_coulomb(dim, seed):
    """Small random problems (12 contacts, mu <= 0.3): every exact route and solve_coulomb meet
    the 1e-8 natural-map error, and their reactions agree to 1e-6 relative (the error bound
    amplified by the condition of W, ~30, and the fixed point's contraction)."""
    problem = random_problem(seed, dim, 12)
    reference = solve_coulomb(problem, tol=TOL)
    assert reference.success
    statuses = set(reference.status_labels)
    assert len(statuses) >= 2  # the draw mixes open, stick and slip contacts
    for name, solve in routes(dim):
        solution = solve(problem, tol=TOL)
        assert solution.success, (name, solution.message)
        assert solution.certificate.natural_map <= TOL
        assert natural_map_error(problem, solution.forces) == pytest.approx(
            solution.certificate.natural_map, rel=1e-12
        )
        assert np.allclose(
            solution.displacements, problem.W @ solution.forces + problem.q, rtol=0, atol=1e-12
        )
        difference = np.linalg.norm(solution.forces - reference.forces) / np.linalg.norm(
            reference.forces
        )
        assert difference < 1e-6, (name, difference)


def test_polygonal_3d_tends_to_coulomb_as_facets_grow():
    """In 3-D the polygonal answer is off by the direction error pi / F of the sliding force:
    its distance to the Coulomb solution shrinks at least 4 times from 8 to 64 facets, and
    its exact-cone error stays well above tol (it is reported, not claimed converged to it)."""
    problem = random_problem(4, 3, 12)
    reference = solve_coulomb(problem, tol=TOL).forces
    distances = []
    for facets in (8, 64):
        solution = solve_polygonal(problem, facets=facets, backend="daqp", tol=TOL)
        assert solution.success
        assert solution.certificate.natural_map > 10 * TOL
        distances.append(np.linalg.norm(solution.forces - reference) / np.linalg.norm(reference))
    assert distances[1] < distances[0] / 4
    assert distances[1] < 1e-2


def test_unsymmetric_w_and_cohesion():
    """A skew part of W (as in FCLIB files written with few digits) is iterated on, and
    cohesion is handled in apex coordinates: the Tresca route still meets the error on the
    problem as given and agrees with solve_coulomb."""
    problem = random_problem(5, 3, 10, skew=1e-3, cohesion=True)
    assert np.any(problem.cohesion > 0) and not np.allclose(problem.W, problem.W.T)
    reference = solve_coulomb(problem, tol=TOL)
    solution = solve_tresca_fixed_point(problem, tol=TOL)
    assert reference.success and solution.success, solution.message
    assert natural_map_error(problem, solution.forces) <= TOL
    assert np.allclose(
        solution.forces, reference.forces, rtol=0, atol=1e-6 * np.abs(reference.forces).max()
    )


def test_a_slowly_contracting_fixed_point_is_not_called_stalled():
    """One contact with a strong normal-tangential coupling (W_NT / W_NN = 2.2, mu = 0.25): the
    Tresca fixed point contracts at a rate of about 0.55 per iteration, so the error halves
    every two iterations but never in one; it must run on to tol (it was stopped as stalled
    at 3e-3)."""
    W = np.array([[0.15121387, 0.33389275], [0.33389275, 1.0]])
    problem = LocalProblem(W, [-0.36260698, -1.0], [0.25], 2)
    solution = solve_tresca_fixed_point(problem, tol=TOL)
    assert solution.success, solution.message
    reference = solve_coulomb(problem, tol=1e-12)
    assert np.allclose(solution.forces, reference.forces, rtol=0, atol=1e-7)


def test_warm_start_at_the_solution_needs_one_iteration():
    problem = random_problem(6, 3, 8)
    first = solve_tresca_fixed_point(problem, tol=TOL)
    again = solve_tresca_fixed_point(problem, tol=TOL, r0=first.forces)
    assert first.iterations > 2 and again.iterations == 1 and again.success


# --------------------------------------------------------------------------------------------
# bad input


@pytest.mark.parametrize("facets", [2, 0, -3, 2.5, True, "8"])
def test_facets_below_three_or_not_integers_are_rejected(facets):
    problem = single_contact(3, [-1.0, 0.1, 0.1])
    with pytest.raises(InvalidInputError, match="^facets "):
        solve_polygonal(problem, facets=facets)


@pytest.mark.parametrize("solve", [solve_tresca_fixed_point, solve_polygonal])
@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"tol": 0.0}, "tol"),
        ({"tol": 1.0}, "tol"),
        ({"tol": np.nan}, "tol"),
        ({"tol": "1e-8"}, "tol"),
        ({"max_iter": 0}, "max_iter"),
        ({"max_iter": 2.0}, "max_iter"),
        ({"r0": np.zeros(2)}, "r0"),
        ({"r0": [np.nan, 0.0, 0.0]}, "r0"),
    ],
)
def test_bad_arguments_are_rejected(solve, kwargs, name):
    problem = single_contact(3, [-1.0, 0.1, 0.1])
    with pytest.raises(InvalidInputError, match=f"^{name} "):
        solve(problem, **kwargs)


def test_bad_problem_and_backend_are_rejected():
    with pytest.raises(InvalidInputError, match="^problem "):
        solve_tresca_fixed_point(np.eye(3))
    with pytest.raises(InvalidInputError, match="^backend 'nope' is not installed"):
        solve_polygonal(single_contact(2, [-1.0, 0.1]), backend="nope")


@pytest.mark.parametrize(
    "name", ["FrictionContactProblem00071.dat", "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5"]
)
def test_tresca_meets_the_certificate_on_fclib_files(name):
    """Real problems written by other codes (2-D, 89 contacts, mu = 0.9; 3-D, 60 contacts,
    unsymmetric W): the natural-map error of the answer, recomputed here, is below 1e-8."""
    from contactqp.io.fclib import read_problem

    problem = read_problem(Path(__file__).resolve().parents[2] / "shared" / "data" / "fclib" / name)
    solution = solve_tresca_fixed_point(problem, tol=TOL)
    assert solution.success, solution.message
    assert natural_map_error(problem, solution.forces) <= TOL
    assert np.linalg.norm(solution.forces) > 0.0


def test_polygonal_cone_converges_on_the_hex_block_where_the_exact_cone_does():
    """Issue 11: a 3-D hex block (8 x 8 x 4 cells, its 81 bottom nodes on a floor, mu = 0.3,
    pressed 10 um into it and sheared). The exact cone converges in 4 Newton steps; the
    8-facet polygon used to stop at max_iter = 50, its fixed point cycling at a relative change
    of 2.2e-10 (the interior-point answers' accuracy) against tol = 1e-10. Each QP answer is now
    refined by an exact KKT solve on its active set: it converges in 14 iterations. Its
    natural-map error against the exact cones (3e-2) is the polygon's distance from Coulomb,
    which the result reports and does not check (exact_cone is False)."""
    import contactqp as cq
    from contactqp.compliance.fem import ElasticModel, block

    fe = ElasticModel(block(0.08, 0.08, 0.04, 8, 8, 4), 2e11, 0.3).fix("top")
    model = fe.reduced_model(fe.select_nodes(where="bottom"))
    floor = cq.PlaneObstacle([0.0, 0.0, 1e-5], [0.0, 0.0, -1.0])
    loads = np.tile([4000.0, 1500.0, 0.0], model.n_nodes)
    exact = cq.solve(cq.FrictionalProblem(model, loads, floor, mu=0.3))
    polygon = cq.solve(cq.FrictionalProblem(model, loads, floor, mu=0.3, facets=8))
    assert exact.success and polygon.success, polygon.message
    assert polygon.iterations < 50 and "fixed point reached" in polygon.message
    assert not polygon.certificate.exact_cone
    # the linearisation's distance from Coulomb: O(pi / facets) on the sliding contacts
    assert 1e-3 < polygon.certificate.natural_map < np.pi / 8
    np.testing.assert_array_equal(polygon.contact_status, exact.contact_status)


@pytest.mark.parametrize("route", ["tresca", "polygonal"])
def test_the_fixed_point_does_not_change_the_data_it_is_given(route):
    # was: run_fixed_point set data.f to its first iterate's force scale, so a second run on
    # the same FixedPointData skipped the rescaled first solve and gave another answer
    from contactqp.methods.polygonal import _PolygonalTresca
    from contactqp.methods.tresca import FixedPointData, _ClarabelTresca, run_fixed_point

    rng = np.random.default_rng(4)
    nc, d = 4, 3
    A = rng.standard_normal((nc * d, nc * d))
    q = -1e-6 * np.abs(rng.standard_normal(nc * d))
    q[0] = 1e3  # one contact far from its obstacle: the first iterate is rescaled
    problem = LocalProblem(A @ A.T / (nc * d) + np.eye(nc * d), q, np.full(nc, 0.3), d)
    data = FixedPointData(problem)
    scale = data.f
    make = {
        "tresca": lambda: _ClarabelTresca(data),
        "polygonal": lambda: _PolygonalTresca(data, 8, "clarabel", {}),
    }[route]
    runs = [
        run_fixed_point(
            problem,
            data,
            make(),
            tol=TOL,
            max_iter=30,
            r0=None,
            exact=route == "tresca",
            method=route,
        )
        for _ in range(2)
    ]
    assert data.f == scale
    assert runs[0].iterations == runs[1].iterations
    np.testing.assert_array_equal(runs[0].forces, runs[1].forces)
    fresh = (
        solve_tresca_fixed_point(problem, tol=TOL, max_iter=30)
        if route == "tresca"
        else solve_polygonal(problem, facets=8, tol=TOL, max_iter=30)
    )
    np.testing.assert_array_equal(fresh.forces, runs[0].forces)

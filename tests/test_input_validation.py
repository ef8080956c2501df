"""Library-level bad input: each gets one clear InvalidInputError, or a failed certificate.

Overflowing scales, non-finite answers, bad tolerances and iteration caps, duplicate contacts,
complex arrays, a single obstacle not in a list, and iteration caps that cap the work.
"""

import warnings

import numpy as np
import pytest

import contactqp as cq
from contactqp import InvalidInputError
from contactqp.methods import solve_box_qp

R = np.array([[1.0e-6, 0.4e-6], [0.4e-6, 1.0e-6]])  # the README's flexibility, m/N
LOADS = [1500.0, 500.0]
GAPS = [1e-3, 1e-3]


@pytest.fixture(autouse=True)
def no_numpy_warnings():
    """Every test here runs with numpy's warnings (overflow, complex casts) as errors."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        warnings.simplefilter("error", np.exceptions.ComplexWarning)
        yield


def frictional_block(n=6, seed=0):
    """``n`` 3-D nodes with a random SPD stiffness, pressed on a floor and sheared."""
    rng = np.random.default_rng(seed)
    B = rng.standard_normal((3 * n, 3 * n))
    model = cq.ReducedModel(
        stiffness=1e6 * (B @ B.T + 3 * n * np.eye(3 * n)),
        dofs_per_node=3,
        coordinates=np.c_[np.arange(n), np.zeros(n), np.zeros(n)],
    )
    return model, np.tile([300.0, -200.0, -1000.0], n)


FLOOR = cq.PlaneObstacle([0.0, 0.0, 0.0], [0.0, 0.0, -1.0])


# 1. overflow and non-finite values -------------------------------------------------------------


@pytest.mark.parametrize("factor", [1e300, 1e60])
def test_a_flexibility_whose_products_overflow_is_refused(factor):
    # was: success, displacements of -2.9e281 m (the rounding of R P - R lambda)
    with pytest.raises(InvalidInputError, match="^flexibility has an entry of magnitude"):
        cq.solve_gaps(R * factor, LOADS, GAPS)


def test_a_stiffness_too_small_to_multiply_is_refused():
    with pytest.raises(InvalidInputError, match="^stiffness's largest entry .* underflow"):
        cq.ReducedModel(stiffness=np.eye(2) * 1e-300)


@pytest.mark.parametrize(
    "loads, gaps, match",
    [
        ([1e300, 0.0], GAPS, "^loads has an entry of magnitude"),
        (LOADS, [1e300, 1e-3], "^the gap of node 0 is 1e\\+300 m"),
    ],
)
def test_loads_and_gaps_that_would_overflow_are_refused(loads, gaps, match):
    with pytest.raises(InvalidInputError, match=match):
        cq.solve_gaps(R, loads, gaps)


@pytest.mark.parametrize("bad", [np.nan, np.inf, 1e300])
def test_a_non_finite_or_overflowing_answer_fails_the_certificate(bad):
    # was: NaN residuals read as 0 (max(0, nan) is 0): a NaN answer "passed" its certificate
    problem = cq.ContactProblem(
        cq.ReducedModel(flexibility=R), LOADS, [cq.GapObstacle([0, 1], GAPS)]
    )
    result = problem.make_result(
        [bad, 0.0],
        [bad, 0.0],
        method="test",
        converged=True,
        message="done",
        iterations=1,
        seconds=0.0,
    )
    assert not result.certificate.passed and not result.success and result.status == 2
    assert result.certificate.worst == np.inf
    assert "NaN or inf" in result.message


def test_a_non_finite_frictional_answer_fails_the_certificate():
    model, loads = frictional_block()
    problem = cq.FrictionalProblem(model, loads, [FLOOR], mu=0.3)
    forces = np.zeros(3 * problem.n_contacts)
    forces[0] = 1e300  # finite, but U = R H^T r and the residuals overflow
    for r in (forces, np.where(forces > 0, np.inf, 0.0)):
        result = problem.make_result(
            r, method="test", converged=True, message="done", iterations=1, seconds=0.0
        )
        assert not result.success and result.status == 2 and "NaN or inf" in result.message


# 2. tolerances and iteration caps ------------------------------------------------------------

BAD_TOLERANCES = [-1.0, 0.0, np.nan, np.inf, "1e-8", True]
BAD_CAPS = [0, -1, 2.5, True, "10"]


@pytest.mark.parametrize("tol", BAD_TOLERANCES)
def test_solve_gaps_refuses_a_bad_tol(tol):
    # was: tol=-1 ran, "did not settle", success False without a word about tol
    with pytest.raises(InvalidInputError, match="^tol must be a positive finite number"):
        cq.solve_gaps(R, LOADS, GAPS, tol=tol)


@pytest.mark.parametrize("max_iter", BAD_CAPS)
def test_solve_gaps_refuses_a_bad_max_iter(max_iter):
    with pytest.raises(InvalidInputError, match="^max_iter must be an integer >= 1"):
        cq.solve_gaps(R, LOADS, GAPS, max_iter=max_iter)


@pytest.mark.parametrize("kwargs, name", [({"tol": -1.0}, "tol"), ({"max_iter": 0}, "max_iter")])
def test_the_box_qp_solver_refuses_bad_options(kwargs, name):
    with pytest.raises(InvalidInputError, match=f"^{name} must be"):
        solve_box_qp(np.eye(2), [-1.0, 1.0], lower=0.0, **kwargs)


@pytest.mark.parametrize("certificate_tol", [-1.0, 0.0, np.nan, "1e-7"])
def test_a_bad_certificate_tol_is_refused(certificate_tol):
    model = cq.ReducedModel(flexibility=R)
    with pytest.raises(InvalidInputError, match="^certificate_tol must be a positive"):
        cq.ContactProblem(
            model, LOADS, [cq.GapObstacle([0, 1], GAPS)], certificate_tol=certificate_tol
        )


@pytest.mark.parametrize("solver, facets", [("coulomb", None), ("tresca", None), ("polygonal", 8)])
@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"tol": -1.0}, "tol"),
        ({"tol": 0.0}, "tol"),
        ({"tol": np.nan}, "tol"),
        ({"max_iter": 0}, "max_iter"),
        ({"max_iter": -3}, "max_iter"),
        ({"max_iter": 2.5}, "max_iter"),
    ],
)
def test_frictional_solve_refuses_bad_options(solver, facets, kwargs, name):
    model, loads = frictional_block(2)
    problem = cq.FrictionalProblem(model, loads, [FLOOR], mu=0.3, facets=facets)
    with pytest.raises(InvalidInputError, match=f"^{name} must be"):
        cq.solve(problem, solver, **kwargs)


# 3. duplicate contacts -----------------------------------------------------------------------


def test_a_node_listed_twice_is_refused():
    # was: accepted, W singular, an arbitrary split of the force between the two copies
    model = cq.ReducedModel(flexibility=R)
    with pytest.raises(InvalidInputError, match="^node 0 is constrained twice along the same"):
        cq.ContactProblem(model, LOADS, [cq.GapObstacle([0, 0], GAPS)])


def test_two_obstacles_on_one_node_and_direction_are_refused():
    model = cq.ReducedModel(
        flexibility=np.kron(np.eye(2), R), dofs_per_node=2, coordinates=[[0.0, 0.0], [1.0, 0.0]]
    )
    obstacles = [
        cq.GapObstacle([1], [1e-3], [0.0, -1.0]),
        cq.PlaneObstacle([0.0, -2e-3], [0.0, -2.0], nodes=[1]),
    ]  # same direction
    with pytest.raises(
        InvalidInputError, match="^node 1 / plane is constrained twice.*constraints 0 and 1"
    ):
        cq.ContactProblem(model, [0.0, -1500.0, 0.0, -500.0], obstacles)


def test_a_pair_given_both_ways_is_refused():
    model = cq.ReducedModel(flexibility=R)
    pairs = cq.NodePairs([[0, 1], [1, 0]], [1e-3, 1e-3], [[1.0], [-1.0]])  # one contact twice
    with pytest.raises(InvalidInputError, match="^pair 1-0 is constrained twice"):
        cq.ContactProblem(model, LOADS, [pairs])


class RowsOnly:
    """An obstacle of the protocol alone (its ``rows``), as a user may write one."""

    def __init__(self, obstacle):
        self.obstacle = obstacle

    def rows(self, model):
        return self.obstacle.rows(model)


def test_an_obstacle_with_rows_only_assembles_as_the_built_in_ones():
    from contactqp.core.contact import assemble_constraints

    model = cq.ReducedModel(flexibility=np.kron(np.eye(3), R), dofs_per_node=2)
    built_in = [
        cq.GapObstacle([2, 0], [1e-3, -2e-3], [[0.0, -1.0], [0.6, 0.8]]),
        cq.NodePairs([[0, 1]], [5e-4], [1.0, 0.0]),
        cq.GapObstacle([1], [0.0], [0.0, 1.0]),
    ]
    expected = assemble_constraints(model, built_in)
    given = assemble_constraints(model, [RowsOnly(obstacle) for obstacle in built_in])
    assert (given.matrix != expected.matrix).nnz == 0 and given.matrix.shape == (4, 6)
    np.testing.assert_array_equal(given.gaps, expected.gaps)
    np.testing.assert_array_equal(given.nodes, [2, 0, 0, 1])
    assert given.labels == expected.labels == ["node 2", "node 0", "pair 0-1", "node 1"]
    with pytest.raises(
        InvalidInputError, match="^node 2 is constrained twice.*constraints 0 and 4"
    ):
        assemble_constraints(model, [*built_in, RowsOnly(cq.GapObstacle([2], [0.0], [0.0, -3.0]))])


def test_a_node_between_two_walls_or_in_a_corner_is_legitimate():
    model = cq.ReducedModel(flexibility=np.kron(np.eye(2), R), dofs_per_node=2)
    slot = [cq.GapObstacle([0], [1e-3], [1.0, 0.0]), cq.GapObstacle([0], [1e-3], [-1.0, 0.0])]
    corner = [cq.GapObstacle([0], [1e-3], [1.0, 0.0]), cq.GapObstacle([0], [1e-3], [0.0, 1.0])]
    for obstacles in (slot, corner):
        result = cq.solve(cq.ContactProblem(model, [1500.0, 1500.0, 0.0, 0.0], obstacles))
        assert result.success
        np.testing.assert_allclose(result.displacements[0], 1e-3, rtol=1e-9)


# 4. complex input ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "build, name",
    [
        (lambda: cq.ReducedModel(flexibility=R + 1e-9j), "flexibility"),
        (lambda: cq.ReducedModel(stiffness=np.linalg.inv(R).astype(complex)), "stiffness"),
        (lambda: cq.solve_gaps(R, np.array(LOADS) + 0j, GAPS), "loads"),
        (lambda: cq.solve_gaps(R, [1500.0 + 1j, 500.0], GAPS), "loads"),
        (lambda: cq.solve_gaps(R, LOADS, [1e-3 + 0j, 1e-3]), "GapObstacle.gaps"),
        (lambda: cq.solve_gaps(R, LOADS, GAPS, directions=[1.0 + 0j]), "GapObstacle.directions"),
        (lambda: cq.FrictionalProblem(*frictional_block(2), [FLOOR], mu=0.3 + 0.1j), "mu"),
    ],
)
def test_complex_input_is_refused(build, name):
    # was: cast to real with a ComplexWarning (an error here), the imaginary part dropped
    with pytest.raises(InvalidInputError, match=f"^{name} must be real, got complex values"):
        build()


# 5. a single obstacle ------------------------------------------------------------------------


def test_a_single_obstacle_needs_no_list():
    # was: TypeError: 'GapObstacle' object is not iterable
    model = cq.ReducedModel(flexibility=R)
    obstacle = cq.GapObstacle([0, 1], GAPS)
    alone = cq.solve(cq.ContactProblem(model, LOADS, obstacle))
    listed = cq.solve(cq.ContactProblem(model, LOADS, [obstacle]))
    assert alone.success and np.array_equal(alone.displacements, listed.displacements)
    frictional = cq.solve(cq.FrictionalProblem(*frictional_block(2), FLOOR, mu=0.3))
    assert frictional.success and frictional.forces.shape == (2, 3)


@pytest.mark.parametrize(
    "obstacles, match",
    [
        (42, "^obstacles must be an obstacle or a sequence of obstacles, got int"),
        ([cq.GapObstacle([0], [1e-3]), "floor"], r"^obstacles\[1\] is a str, not an obstacle"),
    ],
)
def test_something_that_is_not_an_obstacle_is_refused(obstacles, match):
    with pytest.raises(InvalidInputError, match=match):
        cq.ContactProblem(cq.ReducedModel(flexibility=R), LOADS, obstacles)


# 6. an iteration cap caps the work ------------------------------------------------------------


@pytest.mark.parametrize("solver, facets", [("coulomb", None), ("tresca", None), ("polygonal", 8)])
@pytest.mark.parametrize("max_iter", [1, 3])
def test_the_friction_routes_stop_at_max_iter(solver, facets, max_iter):
    # was, for coulomb: max_iter per Newton run, with up to 6 runs and 200 Gauss-Seidel sweeps
    # on top (max_iter = 1 ran 42 iterations on a problem file); for the fixed points the
    # rescaled first sub-problem was solved twice
    model, loads = frictional_block()
    problem = cq.FrictionalProblem(model, loads, FLOOR, mu=0.3, facets=facets)
    free = cq.solve(problem, solver)
    assert free.success and free.iterations > max_iter  # the problem needs more than max_iter
    capped = cq.solve(problem, solver, max_iter=max_iter)
    assert capped.iterations <= max_iter
    assert not capped.success and capped.status == 1
    assert f"max_iter = {max_iter} reached" in capped.message


def test_the_coulomb_cap_counts_gauss_seidel_sweeps():
    from contactqp.core.local_problem import LocalProblem
    from contactqp.methods.coulomb import solve_coulomb

    # W = 0 with q_N < 0 has no solution: the stages run until the budget is spent (the later
    # ones stop by themselves, which the default budget leaves room for)
    problem = LocalProblem(np.zeros((3, 3)), [-1.0, 0.5, 0.0], [0.3], 3)
    for max_iter in (1, 50, 150):
        solution = solve_coulomb(problem, max_iter=max_iter)
        assert not solution.success and solution.iterations == max_iter
        assert f"max_iter = {max_iter} reached" in solution.message


def test_the_active_set_cap_caps_both_phases():
    # a chain of springs on a wall needs several active-set iterations
    n = 30
    K = 2e6 * np.eye(n) - 1e6 * (np.eye(n, k=1) + np.eye(n, k=-1))
    model = cq.ReducedModel(stiffness=K)
    problem = cq.ContactProblem(
        model, np.linspace(-1.0, 1.0, n) * 1e3, [cq.GapObstacle(range(n), np.full(n, 1e-5))]
    )
    free = cq.solve(problem)
    assert free.success and free.iterations > 2
    capped = cq.solve(problem, max_iter=2)
    assert capped.iterations <= 2 and not capped.success and capped.status == 1

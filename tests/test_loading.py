"""Load histories with friction: hysteresis against closed forms, energy balance, carried state.

Truths used: the spring chain's virgin curve (tests/test_springs.py's analytic formula and the
box-QP solver of contactqp.applications.springs) and Masing's rule for its reversals (derived in
examples/cyclic_shear.py); the one-spring friction element's closed-form loop and dissipation
4 mu N (Q_max - mu N) / k; the work of the loads over a cycle (trapezoid rule, exact when the
response is linear in every step); a second solver route on a coupled problem.
"""

import importlib.util
import pathlib

import numpy as np
import pytest

import contactqp as cq
from contactqp.applications.springs import SpringChain
from contactqp.core.history import MAX_STEPS

EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "cyclic_shear.py"


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("cyclic_shear", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def work_of_loads(history):
    """Trapezoid rule for the work of the loads, step by step (J)."""
    P, U = history.loads, history.displacements
    return np.sum(0.5 * (P[1:] + P[:-1]) * np.diff(U, axis=0), axis=1)


def test_example_runs_and_prints_the_loop(example, capsys, tmp_path):
    figure = tmp_path / "loop.png"
    assert example.main(["--cycles", "1", "--steps", "7", "--plot", str(figure)]) == 0
    out = capsys.readouterr().out
    assert "cycle 1: dissipated 448.000000 J (closed form 448.000000 J)" in out
    assert "all steps certified: True" in out
    assert figure.stat().st_size > 0


@pytest.mark.parametrize("n, force_max", [(1, 10.0), (3, 14.0), (5, 17.0), (5, 30.0)])
def test_chain_loop_follows_masing_and_dissipates_the_closed_form(example, n, force_max):
    out = example.run(n=n, force_max=force_max, cycles=2, steps=8)
    assert out["history"].success
    scale = np.max(np.abs(out["exact"]))
    np.testing.assert_allclose(out["x"], out["exact"], atol=1e-9 * scale)
    # the virgin branch is the monotonic spring chain of contactqp.applications.springs (box QP)
    chain = SpringChain(n, 1.0, 0.2, 2.0, 10.0)
    np.testing.assert_allclose(out["x"][8], chain.solve(force_max).x, atol=1e-9 * scale)
    per_cycle = out["dissipated_per_cycle"]
    assert np.all(per_cycle > 0)
    np.testing.assert_allclose(per_cycle, out["closed_form_per_cycle"], rtol=1e-9)


def test_one_spring_element_closed_form_loop(example):
    # one body: stick while |Q - Q_reversal| <= 2 mu N, then slip with x = (Q -+ mu N) / k
    k, mu, m, g, q_max = 2.5, 0.3, 1.5, 9.81, 11.0
    L = mu * m * g
    out = example.run(n=1, stiffness=k, mu=mu, mass=m, g=g, force_max=q_max, cycles=1, steps=40)
    Q, x = out["force"], out["x"][:, 0]
    down = slice(41, 81)
    expected_down = np.minimum((q_max - L) / k, (Q[down] + L) / k)
    np.testing.assert_allclose(x[down], expected_down, atol=1e-10)
    stick = np.abs(Q[down] - q_max) <= 2 * L
    assert np.all(out["history"].contact_status[down][stick] == 1)
    assert np.all(out["history"].contact_status[down][~stick] == 2)
    np.testing.assert_allclose(out["dissipated_per_cycle"], 4 * L * (q_max - L) / k, rtol=1e-9)


def test_work_of_the_loads_over_a_cycle_is_the_dissipated_energy(example):
    # steps of 2 N put every kink of the n = 3 loop (multiples of L = 4 N from the reversal
    # points) on a step, so the trapezoid rule is exact
    out = example.run(n=3, force_max=14.0, cycles=2, steps=14)
    history = out["history"]
    work = work_of_loads(history)
    cycle = slice(14, 14 + 28)  # steps 15..42: one full cycle from F_max back to F_max
    np.testing.assert_allclose(work[cycle].sum(), history.dissipated[15:43].sum(), rtol=1e-9)
    energies = [step.elastic_energy for step in history]
    np.testing.assert_allclose(energies[14], energies[42], rtol=1e-9)


def test_state_is_carried_over(example):
    # loaded to F = 7 N < 2 L and unloaded to 0, one body keeps (F - L) / c; from rest it is 0
    problem = example.chain_problem(1, 1.0, 0.2)  # L = 0.2 * 20 N = 4 N
    loads = cq.linear_path([[0.0, -20.0], [7.0, -20.0], [0.0, -20.0]], 2)
    history = cq.solve_history(problem, loads)
    assert history.success
    np.testing.assert_allclose(history.displacements[-1, 0], 7.0 - 4.0, atol=1e-10)
    np.testing.assert_allclose(
        cq.solve(problem.with_loads(loads[-1])).displacements[0], 0.0, atol=1e-12
    )
    np.testing.assert_allclose(history.slip[:, 0, 0], [0.0, 0.0, 3.0, 0.0, 0.0], atol=1e-9)
    assert history.contact_status[:, 0].tolist() == [1, 1, 2, 1, 1]


def coupled_history(solver, cycles=1, steps=12):
    rng = np.random.default_rng(7)
    B = rng.normal(size=(8, 8))
    R = B @ B.T / 8 + np.eye(8)
    model = cq.ReducedModel(
        flexibility=R, dofs_per_node=2, coordinates=np.column_stack([np.arange(4.0), np.zeros(4)])
    )
    problem = cq.FrictionalProblem(model, np.zeros(8), [cq.PlaneObstacle([0, 0], [0, -1])], mu=0.25)
    points = np.zeros((2 + 2 * cycles, 8))
    points[:, 1::2] = -3.0
    points[1:, 0::2] = np.array([1.0] + [-1.0, 1.0] * cycles)[:, None] * [2.0, 1.0, -0.5, 1.5]
    return cq.solve_history(problem, cq.linear_path(points, steps), solver)


def test_coupled_cyclic_history_dissipates_and_agrees_across_routes():
    newton, tresca = coupled_history("coulomb"), coupled_history("tresca")
    assert newton.success and tresca.success
    np.testing.assert_allclose(newton.forces, tresca.forces, atol=1e-7)
    assert np.all(newton.dissipated >= -1e-9)
    # energy balance over the history: work of the loads = elastic energy + dissipation, to the
    # accuracy of the trapezoid rule (status changes inside steps)
    work = work_of_loads(newton).sum()
    stored = newton[-1].elastic_energy - newton[0].elastic_energy
    dissipated = newton.dissipated[1:].sum()
    assert dissipated > 0
    assert work == pytest.approx(stored + dissipated, rel=1e-2)
    assert 2 in newton.contact_status and 1 in newton.contact_status


def test_polygonal_cone_changes_the_loop_by_its_inradius():
    # one 3-D contact sheared along the first tangent, across a side of the polygon: the
    # friction limit is mu N cos(pi / F), the loop shrinks accordingly
    k, mu, N, q_max, facets = 2.0, 0.4, 10.0, 8.0, 6
    model = cq.ReducedModel(
        stiffness=np.diag([k, k, 3.0]), dofs_per_node=3, coordinates=[[0.0, 0.0, 0.0]]
    )
    points = [[0, 0, -N], [q_max, 0, -N], [-q_max, 0, -N], [q_max, 0, -N]]
    loads = cq.linear_path(points, 8)
    floor = cq.PlaneObstacle([0, 0, 0], [0, 0, -1])
    for sides, limit in ((None, mu * N), (facets, mu * N * np.cos(np.pi / facets))):
        problem = cq.FrictionalProblem(model, np.zeros(3), [floor], mu=mu, facets=sides)
        history = cq.solve_history(problem, loads)
        assert history.success
        np.testing.assert_allclose(
            history.dissipated[9:].sum(), 4 * limit * (q_max - limit) / k, rtol=1e-7
        )


def test_bad_histories_are_clear_errors(example):
    problem = example.chain_problem(2, 1.0, 0.2)
    with pytest.raises(cq.InvalidInputError, match="loads must have shape"):
        cq.solve_history(problem, np.zeros((3, 5)))
    with pytest.raises(cq.InvalidInputError, match="NaN"):
        cq.solve_history(problem, np.full((2, 4), np.nan))
    with pytest.raises(cq.InvalidInputError, match="FrictionalProblem"):
        frictionless = cq.ContactProblem(
            problem.model, np.zeros(4), [cq.PlaneObstacle([0.0, 0.0], [0.0, -1.0])]
        )
        cq.solve_history(frictionless, np.zeros((1, 4)))
    for steps in (0, None, 2.0, [2]):  # None and [2] used to raise TypeError from int()
        with pytest.raises(cq.InvalidInputError, match="steps"):
            cq.linear_path(np.zeros((2, 4)), steps)
    assert cq.linear_path(np.zeros((2, 4)), np.int64(3)).shape == (4, 4)


def test_a_path_of_more_steps_than_the_cap_is_refused_before_it_is_built():
    with pytest.raises(cq.InvalidInputError, match="gives 300000000000000000001 load steps"):
        cq.linear_path(np.zeros((4, 2)), 10**20)  # used to raise numpy's ValueError
    with pytest.raises(cq.InvalidInputError, match="more than the 7 allowed"):
        cq.linear_path(np.zeros((3, 2)), 4, max_steps=7)
    assert cq.linear_path(np.zeros((3, 2)), 3, max_steps=7).shape == (7, 2)
    assert cq.linear_path(np.zeros((2, 1)), 2 * MAX_STEPS, max_steps=None).shape == (
        2 * MAX_STEPS + 1,
        1,
    )


def test_progress_is_reported_after_every_step(example):
    problem = example.chain_problem(2, 1.0, 0.2)
    loads = cq.linear_path([[0.0, -20.0, 0.0, -20.0], [7.0, -20.0, 7.0, -20.0]], 4)
    calls = []
    history = cq.solve_history(
        problem, loads, progress=lambda done, total: calls.append((done, total))
    )
    assert history.success and calls == [(k, 5) for k in range(1, 6)]

"""One entry point and one registry: contactqp.solve on every problem kind, default methods,
errors for unknown or unfitting methods and options, the warm start r0 of every method, mu = 0
dispatch, the registry against the functions' signatures, and ``contactqp methods``."""

from __future__ import annotations

import inspect
import json

import numpy as np
import pytest

import contactqp as cq
from contactqp import kernels
from contactqp.cli import main
from contactqp.core.local_problem import GlobalProblem, LocalProblem
from contactqp.core.result import FrictionalResult, LocalResult
from contactqp.methods import registry


def contact_problem(seed=0, n=8):
    """Frictionless: ``n`` one-freedom nodes, a random SPD flexibility, gaps closed by loads."""
    rng = np.random.default_rng(seed)
    B = rng.standard_normal((n, n))
    model = cq.ReducedModel(flexibility=1e-6 * (B @ B.T / n + np.eye(n)))
    gaps = 1e-4 * rng.uniform(0.0, 1.0, n)
    return cq.ContactProblem(
        model, 300.0 * rng.uniform(0.5, 1.5, n), [cq.GapObstacle(list(range(n)), gaps)]
    )


def frictional_problem(mu=0.3, facets=None, n=3, seed=1, previous=None):
    """``n`` 3-D nodes on a floor, pressed and sheared, a random SPD compliance."""
    rng = np.random.default_rng(seed)
    B = rng.standard_normal((3 * n, 3 * n))
    model = cq.ReducedModel(
        flexibility=1e-6 * (B @ B.T / (3 * n) + np.eye(3 * n)),
        dofs_per_node=3,
        coordinates=np.c_[np.arange(n), np.zeros(n), np.zeros(n)],
    )
    floor = cq.PlaneObstacle([0.0, 0.0, 0.0], [0.0, 0.0, -1.0])
    loads = np.tile([200.0, -100.0, -1000.0], n) + 50.0 * rng.standard_normal(3 * n)
    return cq.FrictionalProblem(model, loads, [floor], mu=mu, facets=facets, previous=previous)


def local_problem(mu=0.3, nc=6, dim=3, seed=2):
    rng = np.random.default_rng(seed)
    m = nc * dim
    A = rng.standard_normal((m, m)) / np.sqrt(m)
    q = 0.3 * rng.standard_normal(m)
    q[::dim] -= 0.5
    return LocalProblem(A @ A.T * 0.5 + np.eye(m), q, np.full(nc, mu), dim)


def global_problem(mu=0.3, nc=4, dim=3, seed=3):
    rng = np.random.default_rng(seed)
    n, m = 3 * nc, nc * dim
    B = rng.standard_normal((n, n))
    M = B @ B.T / n + np.eye(n)
    H = rng.standard_normal((n, m))
    w = np.zeros(m)
    w[::dim] = -0.2
    return GlobalProblem(M, H, rng.standard_normal(n), w, np.full(nc, mu), dim)


def fastened_problem(k=6, seed=4):
    """Two rows of ``k`` one-freedom nodes paired across a gap, the first pair fastened."""
    rng = np.random.default_rng(seed)
    blocks = []
    for _ in range(2):
        B = rng.standard_normal((k, k))
        blocks.append(1e-6 * (B @ B.T / k + np.eye(k)))
    R = np.block([[blocks[0], np.zeros((k, k))], [np.zeros((k, k)), blocks[1]]])
    model = cq.ReducedModel(flexibility=R)
    pairs = cq.NodePairs(
        np.column_stack([np.arange(k), k + np.arange(k)]), 2e-4 + 1e-4 * rng.standard_normal(k)
    )
    problem = cq.ContactProblem(model, np.zeros(2 * k), [pairs])
    return cq.FastenedProblem(problem, [0, 3])


def surface_problem(load=2.0, n=6):
    """A rigid sphere (radius 5 mm) pressed on an ``n x n`` patch of a steel half-space."""
    from contactqp.compliance import grid, normal_influence

    x, y = grid(n, n, 1e-5, 1e-5)
    x, y = x - x.mean(), y - y.mean()
    W = normal_influence(x, y, 1e-5, 1e-5, 210e9, 0.3)
    return cq.SurfaceProblem(W, (x**2 + y**2) / 1e-2, load=load)


# --- solve() on every kind, default methods ------------------------------------------------


def test_every_problem_class_carries_its_kind():
    assert contact_problem().kind == "frictionless"
    assert frictional_problem().kind == "frictional"
    assert frictional_problem(facets=8).kind == "frictional-polygonal"
    assert local_problem().kind == "local" and global_problem().kind == "global"
    assert fastened_problem().kind == "fastened"
    assert set(registry.KINDS) == {
        "frictionless",
        "frictional",
        "frictional-polygonal",
        "local",
        "global",
        "fastened",
        "surface",
        "local-batch",
        "sliding-surface",
    }


@pytest.mark.parametrize(
    "make, kind, default, result_type",
    [
        (contact_problem, "frictionless", "active-set", cq.ContactResult),
        (frictional_problem, "frictional", "coulomb", FrictionalResult),
        (
            lambda: frictional_problem(facets=8),
            "frictional-polygonal",
            "polygonal",
            FrictionalResult,
        ),
        (local_problem, "local", "coulomb", LocalResult),
        (global_problem, "global", "coulomb", LocalResult),
        (fastened_problem, "fastened", "lawson-hanson", cq.FastenedResult),
        (surface_problem, "surface", "constrained-cg", cq.SurfaceResult),
    ],
)
def test_solve_takes_every_kind_with_its_default_method(make, kind, default, result_type):
    assert cq.default_method(kind) == default
    assert cq.methods_for(kind)[0].name == default  # the default is listed first
    problem = make()
    result = cq.solve(problem)
    assert isinstance(result, result_type)
    if isinstance(result, LocalResult):  # 3-D contacts: the spatial route, not normal-qp
        assert result.success, result.message
        # a local one takes the spatial route where the kernels are built; a small global one
        # coulomb's compiled global route (or, without kernels, coulomb on the condensed form)
        spatial = kind == "local" and kernels.spatial_solve is not None
        assert result.method == ("spatial" if spatial else "coulomb")
    elif isinstance(result, cq.FastenedResult):
        assert result.success and result.method == default
    else:
        assert result.success, result.message
        assert result.method == default
    named = cq.solve(problem, default)
    if isinstance(result, LocalResult):  # the same solution by coulomb's Newton
        assert named.method == default and "newton" in named.message
        scale = np.abs(result.forces).max()
        np.testing.assert_allclose(named.forces, result.forces, rtol=0, atol=1e-7 * scale)
    elif isinstance(result, cq.FastenedResult):
        np.testing.assert_array_equal(named.multipliers, result.multipliers)
    else:
        np.testing.assert_array_equal(named.forces, result.forces)


def test_frictional_problem_by_name_and_its_cross_check():
    # were: AttributeError 'dual', and "choose one of active-set, qp"
    problem = frictional_problem()
    exact, check = cq.solve(problem, "coulomb"), cq.solve(problem, "tresca")
    assert exact.success and check.success and check.method == "tresca"
    np.testing.assert_allclose(
        check.forces, exact.forces, rtol=0, atol=1e-6 * np.abs(exact.forces).max()
    )


def test_global_problem_is_certified_on_its_own_equations():
    problem = global_problem()
    solution = cq.solve(problem, tol=1e-10)
    assert solution.success and solution.certificate.equilibrium <= 1e-10
    assert "global equations" in solution.message and solution.v is not None


def test_previous_state_is_part_of_the_frictional_problem():
    first = cq.solve(frictional_problem())
    again = frictional_problem(previous=first)
    assert again.previous is first
    # the same loads from the state they lead to: nothing slips, the forces stay
    second = cq.solve(again)
    assert second.success
    np.testing.assert_allclose(
        second.forces, first.forces, rtol=0, atol=1e-8 * np.abs(first.forces).max()
    )
    np.testing.assert_allclose(second.slip, 0.0, atol=1e-12)
    twin = again.with_loads(again.loads)
    assert twin.previous is None  # with_loads starts from rest unless told
    assert again.with_loads(again.loads, previous=first).previous is first


def test_solve_history_checks_method_and_options_before_the_first_step():
    problem = frictional_problem()
    loads = np.array([problem.loads * f for f in (0.5, 1.0)])
    history = cq.solve_history(problem, loads, "tresca", tol=1e-9)
    assert history.success and [s.method for s in history.steps] == ["tresca", "tresca"]
    calls = []
    with pytest.raises(cq.InvalidInputError, match="unknown option 'tols'"):
        cq.solve_history(problem, loads, tols=1e-9, progress=lambda *a: calls.append(a))
    with pytest.raises(cq.InvalidInputError, match="unknown method 'newton'"):
        cq.solve_history(problem, loads, "newton", progress=lambda *a: calls.append(a))
    assert calls == []  # nothing was solved


# --- errors: unknown or unfitting method, unknown option -------------------------------------


@pytest.mark.parametrize(
    "make, method, match",
    [
        (
            frictional_problem,
            "magic",
            r"unknown method 'magic' for frictional problems; choose one of coulomb \(default\), "
            r"tresca, normal-qp",
        ),
        (
            frictional_problem,
            "qp",
            r"method 'qp' does not solve frictional problems \(it solves frictionless\); "
            r"methods for frictional problems: coulomb \(default\), tresca, normal-qp",
        ),
        (
            lambda: frictional_problem(facets=8),
            "coulomb",
            r"method 'coulomb' does not solve frictional-polygonal problems .*: "
            r"polygonal \(default\), normal-qp",
        ),
        (
            contact_problem,
            "coulomb",
            r"does not solve frictionless problems .*: active-set \(default\), qp$",
        ),
        (local_problem, "lawson-hanson", r"methods for local problems: coulomb \(default\)"),
        (
            fastened_problem,
            "qp",
            r"methods for fastened problems: lawson-hanson \(default\), active-set, nnls",
        ),
    ],
)
def test_unknown_or_unfitting_method_lists_the_methods_of_the_kind(make, method, match):
    with pytest.raises(cq.InvalidInputError, match=match):
        cq.solve(make(), method)


@pytest.mark.parametrize(
    "make, method, option, valid",
    [
        (contact_problem, None, "forces0", "r0, tol, max_iter"),
        (frictional_problem, "tresca", "check_psd", "r0, tol, max_iter, per_contact"),
        (local_problem, None, "tols", "r0, tol, max_iter, check_psd, per_contact"),
        (fastened_problem, "nnls", "tol", "none"),
    ],
)
def test_unknown_option_is_named_with_the_valid_ones(make, method, option, valid):
    with pytest.raises(
        cq.InvalidInputError,
        match=f"unknown option '{option}' for method '.*'; its options: {valid}$",
    ):
        cq.solve(make(), method, **{option: 1.0})


def test_options_set_by_the_problem_are_refused():
    with pytest.raises(
        cq.InvalidInputError,
        match="option 'facets' is set by the FrictionalProblem with facets itself",
    ):
        cq.solve(frictional_problem(facets=8), facets=6)


def test_a_non_problem_is_refused():
    with pytest.raises(
        cq.InvalidInputError,
        match="cannot solve a ndarray: give one of ContactProblem, FrictionalProblem",
    ):
        cq.solve(np.eye(3))


def test_options_are_keyword_only():
    with pytest.raises(TypeError):
        cq.solve(contact_problem(), "active-set", None)


# --- the warm start r0 of every method -------------------------------------------------------


def _answer(result):
    if isinstance(result, LocalResult):
        return result.forces, result.iterations
    if isinstance(result, cq.FastenedResult):
        return result.multipliers, result.iterations
    return result.forces, result.iterations


@pytest.mark.parametrize(
    "make, method",
    [
        (contact_problem, "active-set"),
        (frictional_problem, "coulomb"),
        (frictional_problem, "tresca"),
        (lambda: frictional_problem(facets=8), "polygonal"),
        (lambda: frictional_problem(mu=0.0), "normal-qp"),
        (local_problem, "coulomb"),
        (local_problem, "tresca"),
        (local_problem, "polygonal"),
        (lambda: local_problem(mu=0.0), "normal-qp"),
        (global_problem, "coulomb"),
        (fastened_problem, "lawson-hanson"),
        (fastened_problem, "active-set"),
        (surface_problem, "constrained-cg"),
        (surface_problem, "surface-active-set"),
    ],
)
def test_r0_warm_starts_every_method(make, method):
    assert "r0" in registry.get_method(method).option_names
    problem = make()
    cold = cq.solve(problem, method)
    solution, cold_iterations = _answer(cold)
    warm = cq.solve(problem, method, r0=solution)
    answer, warm_iterations = _answer(warm)
    assert warm_iterations <= cold_iterations and (
        warm_iterations < cold_iterations or cold_iterations <= 1
    )
    np.testing.assert_allclose(
        answer, solution, rtol=0, atol=1e-6 * max(np.abs(solution).max(), 1e-300)
    )
    with pytest.raises(cq.InvalidInputError, match="r0"):
        cq.solve(problem, method, r0=np.ones(np.size(solution) + 1))


def test_the_default_warm_start_of_a_frictional_step_is_its_previous_state():
    first = cq.solve(frictional_problem())
    from_state = cq.solve(frictional_problem(previous=first))
    told = cq.solve(frictional_problem(previous=first), r0=first.forces)
    assert from_state.iterations == told.iterations
    cold = cq.solve(frictional_problem(previous=first), r0=np.zeros(first.forces.size))
    assert from_state.iterations < cold.iterations


# --- mu = 0 goes to the frictionless method --------------------------------------------------


@pytest.mark.parametrize("facets", [None, 8])
@pytest.mark.parametrize("method", [None, "default"])
def test_frictional_problem_without_friction_is_solved_frictionless(facets, method):
    problem = frictional_problem(mu=0.0, facets=facets)
    asked = cq.default_method(problem.kind) if method == "default" else None
    result = cq.solve(problem, asked)
    assert isinstance(result, FrictionalResult) and result.success, result.message
    assert result.method == "normal-qp" and result.certificate.passed
    assert np.all(result.forces[:, 1:] == 0.0)
    # the frictionless problem on the same contacts gives the same normal forces
    frictionless = cq.ContactProblem(
        problem.model, problem.loads, [cq.PlaneObstacle([0.0, 0.0, 0.0], [0.0, 0.0, -1.0])]
    )
    reference = cq.solve(frictionless)
    np.testing.assert_allclose(
        result.forces[:, 0], reference.forces, rtol=1e-7, atol=1e-9 * reference.forces.max()
    )


def test_local_and_global_problems_without_friction_take_the_frictionless_route():
    for problem in (local_problem(mu=0.0), global_problem(mu=0.0)):
        for method in (None, "coulomb"):
            solution = cq.solve(problem, method)
            assert solution.success and "newton" not in solution.message
            assert "active set converged" in solution.message  # the box QP's own account
            assert np.all(solution.forces.reshape(-1, problem.dim)[:, 1:] == 0)
    # a cross-check named explicitly runs as asked
    tresca = cq.solve(local_problem(mu=0.0), "tresca")
    assert tresca.success and "active set converged" not in tresca.message
    with pytest.raises(cq.InvalidInputError, match="needs mu = 0 on every contact"):
        cq.solve(local_problem(mu=0.3), "normal-qp")


def test_mu_zero_goes_frictionless_from_every_entry_point(tmp_path, capsys):
    from contactqp.io import write_problem
    from contactqp.io.problem_file import load_problem_file
    from contactqp.methods.coulomb import solve_coulomb

    # contactqp fclib: the record's iterations are those of the box QP, not of Newton
    problem = local_problem(mu=0.0)
    write_problem(tmp_path / "p.hdf5", problem)
    assert main(["fclib", str(tmp_path / "p.hdf5"), "--json"]) == 0
    record = json.loads(capsys.readouterr().out.splitlines()[0])
    frictionless, newton = cq.solve(problem), solve_coulomb(problem)
    assert record["converged"] and record["iterations"] == frictionless.iterations
    assert frictionless.iterations != newton.iterations
    # a problem file with mu = 0 (its route defaults to coulomb), alone and along a history
    text = FRICTION_FILE.replace("mu = 0.3", "mu = 0.0")
    (tmp_path / "p.toml").write_text(text)
    spec = load_problem_file(tmp_path / "p.toml")
    assert spec.solver == "coulomb"
    result = spec.solve()
    assert result.success and result.method == "normal-qp"
    (tmp_path / "h.toml").write_text(text + "\n[loading]\nfactors = [0.5, 1.0]\n")
    history = load_problem_file(tmp_path / "h.toml").solve()
    assert history.success and {step.method for step in history.steps} == {"normal-qp"}
    # solve_history directly
    problem = frictional_problem(mu=0.0)
    steps = cq.solve_history(problem, np.array([0.5 * problem.loads, problem.loads])).steps
    assert [step.method for step in steps] == ["normal-qp", "normal-qp"]


FRICTION_FILE = """
[model]
flexibility = [[1e-6, 0.0, 0.0, 0.0], [0.0, 1e-8, 0.0, 0.0], [0.0, 0.0, 1e-6, 0.0],
               [0.0, 0.0, 0.0, 1e-8]]
dofs_per_node = 2

[loads]
values = [100.0, -1000.0, 100.0, -1000.0]

[[obstacle]]
type = "gaps"
nodes = [0, 1]
gaps = [0.0, 0.0]
direction = [0.0, -1.0]

[friction]
mu = 0.3
"""


# --- the registry against the functions ------------------------------------------------------


@pytest.mark.parametrize("name", list(registry.METHODS))
def test_registry_options_match_the_function_signature(name):
    method = registry.METHODS[name]
    parameters = list(inspect.signature(method.function).parameters.values())[1:]
    keyword = [p for p in parameters if p.kind is inspect.Parameter.KEYWORD_ONLY]
    others = [p for p in parameters if p.kind is not inspect.Parameter.KEYWORD_ONLY]
    assert [p.kind for p in others] == (
        [inspect.Parameter.VAR_KEYWORD] if method.backend_settings else []
    )
    assert [p.name for p in keyword] == list(method.option_names)
    for parameter, option in zip(keyword, method.options, strict=True):
        assert parameter.default == option.default, (name, option.name)
        assert option.default is None or isinstance(option.default, option.type)
        assert option.doc and "\n" not in option.doc
    assert method.role in ("exact", "cross-check") and method.summary
    assert method.extra is None or method.extra in registry.EXTRA_MODULES
    assert set(method.kinds) <= set(registry.KINDS)


def test_every_kind_has_a_fitting_default_and_sane_defaults():
    for kind in registry.KINDS.values():
        default = registry.METHODS[kind.default]
        assert kind.name in default.kinds
        for name in (*kind.defaults, *kind.fixed):
            assert any(name in m.option_names for m in registry.methods_for(kind.name))


def test_problem_files_take_their_options_from_the_registry(monkeypatch):
    from contactqp.io.problem_file.options import solver_options

    named, extra = solver_options("coulomb", "frictional")
    expected = registry.method_options("coulomb", "frictional")
    del expected["r0"]  # a file starts from rest or from the previous step
    assert named == expected
    assert named["tol"] == 1e-10 and named["per_contact"] is True and not extra
    named, extra = solver_options("polygonal", "frictional-polygonal")
    assert "facets" not in named and "r0" not in named and extra
    # what a function's signature says does not change what files accept
    function = registry.METHODS["active-set"].function
    monkeypatch.setattr(
        function,
        "__signature__",
        inspect.signature(lambda problem, *, tolerance=1e-10: None),
        raising=False,
    )
    assert solver_options("active-set", "frictionless")[0] == {"tol": 1e-10, "max_iter": 500}


# --- contactqp methods -----------------------------------------------------------------------


def test_methods_command_lists_every_method_as_json(capsys):
    assert main(["methods", "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    by_name = {m["name"]: m for m in listing["methods"]}
    assert list(by_name) == list(registry.METHODS)
    for name, method in registry.METHODS.items():
        described = by_name[name]
        assert described["kinds"] == list(method.kinds)
        assert described["role"] == method.role and described["extra"] == method.extra
        assert described["installed"] == cq.is_installed(name)
        assert [(o["name"], o["type"], o["default"], o["doc"]) for o in described["options"]] == [
            (o.name, o.type.__name__, o.default, o.doc) for o in method.options
        ]
    assert {k["name"]: k["default"] for k in listing["kinds"]} == {
        k.name: k.default for k in registry.KINDS.values()
    }
    assert by_name["qp"]["extra"] == "qp" and by_name["qp"]["installed"]  # the test env has it


def test_methods_command_table(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")
    assert main(["methods"]) == 0
    out = capsys.readouterr().out
    for name in registry.METHODS:
        assert name in out
    assert "frictional (default)" in out and "cross-check" in out and "max_iter" in out


def test_is_installed_looks_for_the_modules_of_the_extra(monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "clarabel" else real(name, *a)
    )
    assert not cq.is_installed("tresca") and not cq.is_installed("qp")
    assert cq.is_installed("coulomb") and cq.is_installed("active-set")

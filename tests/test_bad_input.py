"""Bad input, tried as a new user would: one line on stderr, exit 2, never a traceback.

The command line runs in-process (:func:`contactqp.cli.main` with stdout and stderr captured),
so that the property test at the end can try hundreds of inputs in seconds.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
import shutil
import sys
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from contactqp.cli import main
from contactqp.errors import FileFormatError
from contactqp.io.problem_file import load_problem_file

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "problems"
FCLIB = ROOT.parent / "shared" / "data" / "fclib"


def run(*args) -> tuple[int, str, str]:
    """``contactqp ARGS`` in-process: (exit status, stdout, stderr); warnings go to stderr."""
    out, err = io.StringIO(), io.StringIO()
    with (
        contextlib.redirect_stdout(out),
        contextlib.redirect_stderr(err),
        warnings.catch_warnings(),
    ):
        warnings.simplefilter("default")
        status = main([str(arg) for arg in args])
    return status, out.getvalue(), err.getvalue()


def assert_one_line_error(status, err, *needles):
    lines = err.strip().splitlines()
    assert status == 2 and len(lines) == 1 and lines[0].startswith("contactqp: error:"), err
    for needle in needles:
        assert needle in lines[0], lines[0]


def example(tmp_path, name="two_springs.toml", edit=lambda text: text) -> Path:
    """A copy of an example problem (with its matrix files), its text edited."""
    for path in EXAMPLES.glob("*.csv"):
        shutil.copy(path, tmp_path)
    target = tmp_path / name
    target.write_text(edit((EXAMPLES / name).read_text()))
    return target


def qp_problem(tmp_path, backend, settings: str) -> Path:
    """two_springs.toml solved by the qp solver with ``backend`` and these backend settings."""
    return example(
        tmp_path,
        edit=lambda text: (
            text.replace('name = "active-set"\ntol = 1e-12', f'name = "qp"\nbackend = "{backend}"')
            + f"\n[solver.backend_options]\n{settings}\n"
        ),
    )


# --------------------------------------------------------------------------------------------
# qp backend settings


@pytest.mark.parametrize(
    "backend, settings, needle",
    [
        ("clarabel", "foo = 1", "no attribute 'foo'"),
        ("clarabel", 'max_iter = "abc"', "must be a number, got the string 'abc'"),
        ("clarabel", 'verbose = "abc"', "refuses verbose = 'abc'"),
        ("piqp", "foo = 1", "undefined solver setting foo"),  # piqp warns, when verbose only
        ("osqp", "eps_abs = 1e300\neps_rel = -1.0", "eps_rel: must be >= 0"),
        ("osqp", "polish_refine_iter = -3", "polish_refine_iter"),  # osqp's own check (C code)
        ("quadprog", "max_iter = 50", "unexpected keyword argument 'max_iter'"),
        ("clarabel", "max_iter = 0", "must be positive"),
    ],
)
def test_a_backend_setting_the_backend_refuses_is_one_line_naming_it(
    tmp_path, capfd, backend, settings, needle
):
    problem = qp_problem(tmp_path, backend, settings)
    status, _, err = run("solve", problem)
    key = settings.splitlines()[-1].split(" =")[0]
    assert_one_line_error(status, err, f"[solver.backend_options].{key}", needle)
    assert "Traceback" not in err and capfd.readouterr().out == ""  # nothing from C code either


@pytest.mark.parametrize(
    "edit, needle",
    [
        (
            lambda text: text.replace('name = "active-set"', "name = []"),
            "[solver].name: must be a string, got an array of 0 entries",
        ),
        (
            lambda text: (
                text.replace('name = "active-set"\ntol = 1e-12', 'name = "qp"')
                + "\n[solver.backend_options]\nmax_iter = true\n"
            ),
            "[solver.backend_options].max_iter: must be a number, got the boolean true",
        ),
    ],
)
def test_solver_entries_of_the_wrong_type_are_one_line(tmp_path, edit, needle):
    status, _, err = run("solve", example(tmp_path, edit=edit))
    assert_one_line_error(status, err, needle)


def test_backend_settings_it_accepts_reach_the_solve(tmp_path):
    problem = qp_problem(tmp_path, "clarabel", "max_iter = 300\ntol_feas = 1e-11")
    spec = load_problem_file(problem)
    assert spec.options == {"backend": "clarabel", "max_iter": 300, "tol_feas": 1e-11}
    status, _, err = run("solve", problem, "--json")
    assert status == 0 and err == ""


def test_an_unknown_backend_is_named_when_the_file_is_read(tmp_path):
    problem = qp_problem(tmp_path, "no-such-qp", "max_iter = 3")
    status, _, err = run("solve", problem)
    assert_one_line_error(status, err, "[solver].backend", "'no-such-qp' is not installed")


@pytest.mark.parametrize(
    "settings, needle",
    [
        ("foo = 1", "[friction.backend_options].foo: backend 'clarabel' refuses foo = 1"),
        ('tol_feas = "tight"', "[friction.backend_options].tol_feas"),
        ("max_iter = 5", "max_iter: is an option of friction solver 'polygonal'"),
    ],
)
def test_friction_backend_settings_are_checked_too(tmp_path, settings, needle):
    problem = example(
        tmp_path,
        "cyclic_block.toml",
        lambda text: (
            text.replace("\nmu = 0.3\n", "\nmu = 0.3\nfacets = 8\n")
            + f"\n[friction.backend_options]\n{settings}\n"
        ),
    )
    status, _, err = run("solve", problem)
    assert_one_line_error(status, err, needle)


# --------------------------------------------------------------------------------------------
# Files a problem file names, and the problem file itself


def damaged_archives(directory: Path) -> dict[str, Path]:
    R = np.array([[5e-7, 5e-7], [5e-7, 1.5e-6]])
    good = directory / "good.npz"
    np.savez(good, R=R, spare=R)
    data = good.read_bytes()
    files = {
        "truncated": data[: len(data) // 2],
        "tail cut": data[:-30],
        "corrupt member": data[:100] + b"x" * 40 + data[140:],
        "not a zip": b"hello",
    }
    paths = {}
    for name, content in files.items():
        paths[name] = directory / f"{name.replace(' ', '_')}.npz"
        paths[name].write_bytes(content)
    paths["object array"] = directory / "objects.npz"
    np.savez(paths["object array"], R=np.array([1, "a"], dtype=object))
    return paths


@pytest.mark.parametrize(
    "damage", ["truncated", "tail cut", "corrupt member", "not a zip", "object array"]
)
def test_a_damaged_npz_is_one_line_naming_the_key_and_the_file(tmp_path, damage):
    path = damaged_archives(tmp_path)[damage]
    problem = example(
        tmp_path,
        edit=lambda text: text.replace(
            '"two_springs_R.csv"', f'{{ file = "{path.name}", key = "R" }}'
        ),
    )
    with pytest.raises(
        FileFormatError,
        match=r"\[model\]\.flexibility \('.*\.npz'\): not a "
        r"readable \.npy / \.npz file",
    ):
        load_problem_file(problem)
    status, _, err = run("solve", problem)
    assert_one_line_error(status, err, "[model].flexibility", path.name)


def test_a_toml_file_with_a_byte_order_mark_is_read(tmp_path):
    plain = example(tmp_path)
    marked = tmp_path / "marked.toml"
    marked.write_bytes(b"\xef\xbb\xbf" + plain.read_bytes())
    assert load_problem_file(marked).problem.loads.tolist() == [0.0, 1000.0]
    status, out, err = run("solve", marked, "--json")
    assert status == 0 and err == "" and '"success": true' in out


# --------------------------------------------------------------------------------------------
# Sizes: load steps, bodies


@pytest.mark.parametrize(
    "steps, total", [("100000000000000000000", "300000000000000000001"), ("50000", "150001")]
)
def test_an_absurd_number_of_load_steps_is_one_line(tmp_path, steps, total):
    problem = example(
        tmp_path,
        "cyclic_block.toml",
        lambda text: text.replace("\nsteps = 4\n", f"\nsteps = {steps}\n"),
    )
    status, _, err = run("solve", problem)
    assert_one_line_error(
        status, err, "[loading].steps", f"gives {total} load steps", "more than the 100000 allowed"
    )


def _without_seconds(err: str) -> list[str]:
    """The progress lines with their elapsed time (", N s", load-dependent) checked and cut."""
    lines = err.splitlines()
    assert all(re.fullmatch(r".*, \d+ s", line) for line in lines), lines
    return [line.rsplit(", ", 1)[0] for line in lines]


def test_a_long_history_shows_its_progress_on_stderr(tmp_path, monkeypatch):
    from contactqp.cli import app
    from contactqp.cli import solve as solve_command

    # as if every step took longer than the delay before progress is shown
    monkeypatch.setattr(
        solve_command, "progress", lambda what: app.progress(what, after=0.0, every=0.0)
    )
    problem = example(tmp_path, "cyclic_block.toml")  # 13 steps
    status, out, err = run("solve", problem, "--json")
    assert status == 0 and '"steps": 13' in out
    assert _without_seconds(err) == [
        f"contactqp: step {k} of 13 ({100 * k // 13} %)" for k in range(1, 14)
    ]


def test_many_forces_on_a_long_chain_show_their_progress(monkeypatch):
    from contactqp.cli import app
    from contactqp.cli import springs as springs_command

    monkeypatch.setattr(
        springs_command, "progress", lambda what: app.progress(what, after=0.0, every=0.0)
    )
    status, out, err = run("springs", "--n", "1000", "--force", "1,2,3", "--json")
    assert status == 0 and len(out.splitlines()) == 3
    assert _without_seconds(err) == [
        f"contactqp: force {k} of 3 ({100 * k // 3} %)" for k in (1, 2, 3)
    ]


def test_a_short_run_shows_no_progress(tmp_path):
    status, _, err = run("solve", example(tmp_path, "cyclic_block.toml"), "--json")
    assert status == 0 and err == ""


def test_a_hundred_thousand_springs_from_the_command_line():
    n, F, limit = 100_000, 3.0e5, 0.2 * 2.0 * 10.0
    status, out, err = run("springs", "--n", n, "--force", F, "--json")
    assert status == 0 and err == ""
    x = np.array(json.loads(out)["x"])
    i = np.arange(1, n + 1)  # closed form: body i slides once F > (n + 1 - i) mu m g
    np.testing.assert_allclose(
        x, np.cumsum(np.maximum(F - (n + 1 - i) * limit, 0.0)), rtol=0, atol=1e-9 * x.max()
    )


@pytest.mark.parametrize(
    "args, needle",
    [
        (("springs", "--n", "1000001"), "--n"),
        (("springs", "--n", "10" * 40), "--n"),
        (("layers", "--steps", "100000"), "--steps"),
        (("layers", "--mu", "1e300"), "--mu"),
        (("layers", "--cohesion", "1e300"), "--cohesion"),
    ],
)
def test_sizes_beyond_what_is_offered_are_one_line(args, needle):
    status, _, err = run(*args)
    assert_one_line_error(status, err, needle)


# --------------------------------------------------------------------------------------------
# Optional dependencies


def without(monkeypatch, module: str) -> None:
    """Make ``import module`` fail, as after an install without its extra; modules of contactqp
    that import it at their top are dropped too, so that they are imported again."""
    for name in list(sys.modules):
        if (
            name == module
            or name.startswith(module + ".")
            or (module == "skfem" and name.startswith("contactqp.compliance.fem"))
        ):
            monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, module, None)


def op4_problem(tmp_path) -> Path:
    (tmp_path / "R.op4").write_text("not read: pyNastran is missing\n")
    return example(
        tmp_path,
        edit=lambda text: text.replace('"two_springs_R.csv"', '{ file = "R.op4", key = "KAA" }'),
    )


@pytest.mark.parametrize(
    "module, extra, command",
    [
        ("skfem", "fem", lambda tmp: ["layers", "--steps", "2"]),
        ("matplotlib", "plot", lambda tmp: ["layers", "--steps", "2", "--plot", tmp / "l.png"]),
        ("matplotlib", "plot", lambda tmp: ["springs", "--plot", tmp / "s.png"]),
        ("qpsolvers", "qp", lambda tmp: ["solve", qp_problem(tmp, "clarabel", "max_iter = 99")]),
        (
            "qpsolvers",
            "qp",
            lambda tmp: [
                "solve",
                example(
                    tmp,
                    "cyclic_block.toml",
                    lambda text: text.replace("\nmu = 0.3\n", "\nmu = 0.3\nfacets = 6\n"),
                ),
            ],
        ),
        ("pyNastran", "nastran", lambda tmp: ["solve", op4_problem(tmp)]),
        ("clarabel", "qp", lambda tmp: ["rod"]),
        (
            "clarabel",
            "qp",
            lambda tmp: [
                "solve",
                example(
                    tmp,
                    "cyclic_block.toml",
                    lambda text: text.replace("\nmu = 0.3\n", "\nmu = 0.3\nsolver = 'tresca'\n"),
                ),
            ],
        ),
        ("h5py", "hdf5", lambda tmp: ["fclib", FCLIB / "CubeH8.hdf5"]),
    ],
)
def test_a_missing_optional_dependency_names_its_extra(
    tmp_path, monkeypatch, module, extra, command
):
    without(monkeypatch, module)
    status, _, err = run(*command(tmp_path))
    assert_one_line_error(status, err, f"pip install 'contactqp[{extra}]'")


# --------------------------------------------------------------------------------------------
# Property test: broken problem files and command lines


def toml_value(value) -> str:
    """``value`` written as a TOML value (inline arrays and tables, nan and inf included)."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return (
            "nan"
            if math.isnan(value)
            else ("inf" if value > 0 else "-inf")
            if math.isinf(value)
            else repr(value)
        )
    if isinstance(value, (int, str)):
        return str(value) if isinstance(value, int) else json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(item) for item in value) + "]"
    return "{ " + ", ".join(f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()) + " }"


def toml_text(doc: dict) -> str:
    """A problem file's text: scalars first, then one [table] or [[table]] per entry."""
    lines = [
        f"{key} = {toml_value(value)}"
        for key, value in doc.items()
        if not isinstance(value, dict)
        and not (isinstance(value, list) and value and all(isinstance(v, dict) for v in value))
    ]
    for key, value in doc.items():
        if isinstance(value, dict):
            lines += [f"[{key}]"] + [f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()]
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for table in value:
                lines += [f"[[{key}]]"] + [
                    f"{json.dumps(k)} = {toml_value(v)}" for k, v in table.items()
                ]
    return "\n".join(lines) + "\n"


MISSING = object()  # a key removed from the file

#: Values a new user might type by mistake: wrong types and shapes, non-finite and huge
#: numbers, negative and empty ones, files that are missing, empty or damaged.
BAD_VALUES = [
    math.nan,
    math.inf,
    -math.inf,
    1e300,
    -1e300,
    -1,
    0,
    -0.5,
    1.5,
    10**30,
    True,
    "",
    "abc",
    [],
    [[]],
    [1, "a"],
    [math.nan, 1.0],
    [1e300, 1e300],
    [[1.0, 2.0], [3.0]],
    [[1e300]],
    [-1, 0],
    [0, 0],
    {},
    {"file": "R.csv", "key": "R"},
    {"file": "good.npz"},
    "missing.csv",
    "empty.csv",
    "commas.csv",
    "text.csv",
    "corrupt.npz",
    "good.npz",
    "two_springs_R.csv",
    MISSING,
]

BASES = {
    "two_springs.toml": [
        "name",
        "model.flexibility",
        "model.dofs_per_node",
        "model.stiffness",
        "model.coordinates",
        "loads.values",
        "loads.entries",
        "obstacle",
        "obstacle.0.type",
        "obstacle.0.nodes",
        "obstacle.0.gaps",
        "obstacle.0.direction",
        "obstacle.0.directions",
        "solver",
        "solver.name",
        "solver.tol",
        "solver.max_iter",
        "solver.certificate_tol",
        "model",
    ],
    "cyclic_block.toml": [
        "friction.mu",
        "friction.cohesion",
        "friction.facets",
        "friction.solver",
        "friction.tol",
        "friction.max_iter",
        "friction.backend",
        "friction.backend_options",
        "loading.factors",
        "loading.steps",
        "loading.points",
        "loads.entries",
        "loads.entries.0.value",
        "loads.entries.1.node",
        "obstacle.0.gaps",
        "friction",
        "loading",
        "model.flexibility",
    ],
    "qp.toml": [
        "solver.backend",
        "solver.backend_options",
        "solver.backend_options.max_iter",
        "solver.backend_options.tol_feas",
        "loads.values",
        "obstacle.0.gaps",
    ],
}


#: Cases the property test found (each once a traceback, a leaked warning or a silently wrong
#: exit 0), kept as regressions: (base file, key, value).
FOUND = {
    # overflow: RuntimeWarnings on stderr, exit 0 with a huge or NaN answer ("silently wrong",
    # result.py / problem.py / box_qp.py certificates)
    ("two_springs.toml", "loads.values", 1e300),
    ("qp.toml", "loads.values", 1e300),
    ("cyclic_block.toml", "friction.cohesion", 1e300),
    ("cyclic_block.toml", "loading.factors", 1e300),
    ("cyclic_block.toml", "loads.entries.0.value", 1e300),
    ("cyclic_block.toml", "loads.entries.0.value", -1e300),
    # contact.py: a direction of 1e300 overflows its norm (RuntimeWarning) before the one line
    ("two_springs.toml", "obstacle.0.direction", 1e300),
    # friction.py / solvers/polygonal.py: facets = 1e30 is numpy's ValueError
    ("cyclic_block.toml", "friction.facets", 10**30),
    # result.py: zero initial gaps with friction, RuntimeWarning: invalid value in divide
    ("cyclic_block.toml", "obstacle.0.gaps", 0),
    # solvers/qp.py: a backend's own warnings reach stderr (Clarabel.rs terminated ...)
    ("qp.toml", "solver.backend_options.tol_feas", 0),
}


def property_files(directory: Path) -> None:
    """The base problems of the property test and the files their broken values name."""
    example(directory, "cyclic_block.toml")
    qp = qp_problem(directory, "clarabel", "max_iter = 200\ntol_feas = 1e-10")
    qp.rename(directory / "qp.toml")
    example(directory)
    damaged_archives(directory)["corrupt member"].rename(directory / "corrupt.npz")
    (directory / "empty.csv").write_text("")
    (directory / "commas.csv").write_text(",,\n,,\n")
    (directory / "text.csv").write_text("a,b\nc,d\n")


def mutated(doc: dict, path: str, value) -> dict:
    """``doc`` with the entry at ``path`` (dotted, list indices as numbers) set or removed;
    unchanged when an earlier mutation replaced a table on the way by something else."""
    *keys, last = path.split(".")
    parent = doc
    for key in keys:
        if isinstance(parent, list) and key.isdigit() and int(key) < len(parent):
            parent = parent[int(key)]
        elif isinstance(parent, dict) and not key.isdigit():
            parent = parent.setdefault(key, {})
        else:
            return doc
    if isinstance(parent, list) and last.isdigit() and int(last) < len(parent):
        if value is not MISSING:
            parent[int(last)] = value
    elif isinstance(parent, dict) and value is MISSING:
        parent.pop(last, None)
    elif isinstance(parent, dict):
        parent[last] = value
    return doc


def assert_clean_exit(status, err):
    """Exit 0, 1 or 2, no traceback, no warning; exit 2 with exactly one line on stderr."""
    assert status in (0, 1, 2), (status, err)
    assert "Traceback" not in err and "Warning" not in err, err
    if status == 2:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("contactqp: error:"), err


@pytest.fixture(scope="module")
def property_dir(tmp_path_factory):
    directory = tmp_path_factory.mktemp("broken")
    property_files(directory)
    return directory


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_broken_problem_files_give_one_line_and_the_right_exit_code(property_dir, data):
    base = data.draw(st.sampled_from(sorted(BASES)), label="base")
    doc = tomllib.loads((property_dir / base).read_text())
    for _ in range(data.draw(st.integers(1, 3), label="mutations")):
        path = data.draw(st.sampled_from(BASES[base]), label="key")
        value = data.draw(st.sampled_from(BAD_VALUES), label="value")
        doc = mutated(doc, path, value)
    assert_solve_exits_clean(property_dir, doc)


@pytest.mark.parametrize(("base", "path", "value"), sorted(FOUND, key=repr))
def test_broken_values_found_give_one_line_and_the_right_exit_code(property_dir, base, path, value):
    doc = tomllib.loads((property_dir / base).read_text())
    assert_solve_exits_clean(property_dir, mutated(doc, path, value))


def assert_solve_exits_clean(directory: Path, doc: dict) -> None:
    """``contactqp solve`` of ``doc``, written as a file, exits cleanly (see assert_clean_exit)."""
    problem = directory / "broken.toml"
    problem.write_text(toml_text(doc))
    try:
        status, _, err = run("solve", problem, "--json")
    except BaseException as exc:
        pytest.fail(f"traceback: {type(exc).__name__}: {exc}\n{problem.read_text()}")
    assert_clean_exit(status, err)


BAD_OPTION_VALUES = [
    "nan",
    "inf",
    "-inf",
    "1e300",
    "-1e300",
    "-1",
    "0",
    "",
    "abc",
    "1.5",
    "1" + "0" * 30,
    "1,,2",
    "missing.npy",
]

COMMANDS = {  # command, options that take a value, options fixed to keep a run cheap
    "springs": (["--n", "--stiffness", "--mu", "--mass", "--g", "--force"], []),
    "layers": (["--mu", "--cohesion", "--steps"], ["--steps", "2"]),
    "rod": (["--elements"], []),
    "fclib": (["--tol"], []),
    "riveting": (
        [
            "--samples",
            "--seed",
            "--workers",
            "--mean-gap",
            "--amplitude",
            "--correlation-length",
            "--method",
            "--gaps",
        ],
        ["--samples", "1"],
    ),
}


#: Command lines the property test found, kept as regressions: (command, option, value).
OPTIONS_FOUND = {
    # riveting / batch.py: tracebacks (OverflowError from h5py, from the gap field)
    ("riveting", "--samples", "1" + "0" * 30),
    ("riveting", "--amplitude", "1e300"),
    ("riveting", "--correlation-length", "1e300"),
    # riveting: RuntimeWarnings on stderr and exit 0 (gaps of 1e300 m, or none)
    ("riveting", "--mean-gap", "1e300"),
    ("riveting", "--mean-gap", "-1e300"),
    ("riveting", "--mean-gap", "0"),
    # rod.py: RuntimeWarning (invalid value in cast) before the one line
    ("rod", "--elements", "1" + "0" * 30),
}


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_broken_command_lines_give_one_line_and_the_right_exit_code(
    property_dir, tmp_path_factory, data
):
    command = data.draw(st.sampled_from(sorted(COMMANDS)), label="command")
    options, fixed = COMMANDS[command]
    option = data.draw(st.sampled_from(options), label="option")
    value = data.draw(st.sampled_from(BAD_OPTION_VALUES), label="value")
    assert_command_exits_clean(property_dir, tmp_path_factory, command, option, value)


@pytest.mark.parametrize(("command", "option", "value"), sorted(OPTIONS_FOUND))
def test_broken_command_lines_found_give_one_line_and_the_right_exit_code(
    property_dir, tmp_path_factory, command, option, value
):
    assert_command_exits_clean(property_dir, tmp_path_factory, command, option, value)


def assert_command_exits_clean(property_dir, tmp_path_factory, command, option, value) -> None:
    """``contactqp COMMAND ... OPTION VALUE`` exits cleanly (:func:`assert_clean_exit`)."""
    _, fixed = COMMANDS[command]
    args = [command, *fixed, option, value]
    if command == "fclib":
        args.append(str(property_dir / "corrupt.npz"))
    if command == "riveting":
        args += ["--out", str(tmp_path_factory.mktemp("study"))]
    try:
        status, _, err = run(*args)
    except BaseException as exc:
        pytest.fail(f"traceback: {type(exc).__name__}: {exc} for {args}")
    assert_clean_exit(status, err)


@pytest.mark.parametrize("content", ["", "# only a comment\n", ",,\n", "a,b\n", "\xff\xfe"])
def test_an_empty_or_foreign_gap_csv_is_one_line_and_no_warning(tmp_path, content):
    (tmp_path / "gaps.csv").write_bytes(content.encode("latin-1"))
    status, _, err = run("riveting", "--gaps", tmp_path / "gaps.csv", "--out", tmp_path / "out")
    assert_one_line_error(status, err, "gaps.csv")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("content", ["", "\n\n", "# only a comment\n", ",,\n", " , \n"])
def test_an_empty_csv_is_one_line_and_no_warning(tmp_path, content):
    from contactqp.compliance.importers import read_unit_load_csv

    (tmp_path / "empty.csv").write_text(content)
    problem = example(tmp_path, edit=lambda text: text.replace("two_springs_R.csv", "empty.csv"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        status, _, err = run("solve", problem)
        with pytest.raises(FileFormatError, match="empty.csv"):
            read_unit_load_csv(tmp_path / "empty.csv")
    assert_one_line_error(status, err, "[model].flexibility ('empty.csv')")


def test_a_warning_on_the_command_line_is_one_line(tmp_path):
    problem = example(
        tmp_path,
        edit=lambda text: text.replace(
            '"two_springs_R.csv"', "[[5e-7, 5e-7], [5.0000000001e-7, 1.5e-6]]"
        ),
    )
    status, _, err = run("solve", problem)
    assert status in (0, 1) and "Traceback" not in err
    warning = [line for line in err.splitlines() if "symmetrised" in line]
    assert len(warning) == 1 and warning[0].startswith("contactqp: warning: ")
    assert "[model].flexibility: flexibility symmetrised: relative asymmetry" in warning[0]
    assert "Warning" not in err  # contactqp's own warnings do not show a class name

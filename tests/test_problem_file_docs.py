"""docs/problem-files.md is the schema of problem files: its key tables must be what the parser
accepts, both ways, and the examples it points to must load.

The parser's accepted keys are read from the parser itself: an unknown key is put into each
table of a valid problem, and the error lists the keys that table allows.
"""

import copy
import re
import tomllib
from pathlib import Path

import pytest

from contactqp.errors import InvalidInputError
from contactqp.io.problem_file import load_problem_file
from contactqp.io.problem_file.schema import fixed_keys
from contactqp.methods.registry import methods_for

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "problem-files.md"
EXAMPLES = sorted((ROOT / "examples" / "problems").glob("*.toml"))
FRICTION_ROUTES = ("coulomb", "tresca", "polygonal")
UNKNOWN = "not_a_key"

BASE = {
    "model": {
        "flexibility": [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ],
        "dofs_per_node": 2,
        "coordinates": [[0.0, 0.0], [1.0, 0.0]],
    },
    "loads": {"entries": [{"freedom": 1, "value": -1.0}]},
    "obstacle": [{"type": "plane", "point": [0.0, -0.001], "normal": [0.0, -1.0], "nodes": [0]}],
}
OBSTACLES = {
    "gaps": {"type": "gaps", "nodes": [1], "gaps": [0.001], "direction": [0.0, -1.0]},
    "plane": BASE["obstacle"][0],
    "pairs": {"type": "pairs", "pairs": [[0, 1]], "gaps": [0.001], "direction": [1.0, 0.0]},
}


def documented_tables() -> dict[tuple[str, str], set[str]]:
    """``{(kind, name): keys}`` of every table after a ``<!-- keys: ... -->`` or
    ``<!-- options: ... -->`` marker: the first code span of each row's first cell."""
    tables, lines = {}, PAGE.read_text(encoding="utf-8").splitlines()
    for number, line in enumerate(lines):
        marker = re.fullmatch(r"<!-- (keys|options): (.+?) -->", line.strip())
        if not marker:
            continue
        rows = []
        for row in lines[number + 1 :]:
            if not row.startswith("|"):
                break
            rows.append(row)
        assert len(rows) > 2, f"{PAGE.name}: no table after {line.strip()}"
        keys = set()
        for row in rows[2:]:  # after the header and the |---| line
            span = re.search(r"`([^`]+)`", row.split("|")[1])
            assert span, f"{PAGE.name}: row without a key: {row}"
            keys.add(span.group(1))
        assert (marker.group(1), marker.group(2)) not in tables, f"{line.strip()} twice"
        tables[marker.group(1), marker.group(2)] = keys
    return tables


DOCUMENTED = documented_tables()


def toml_text(doc: dict) -> str:
    """``doc`` as TOML (tables, arrays of tables, inline tables in arrays)."""

    def value(item):
        if isinstance(item, dict):
            return "{ " + ", ".join(f"{k} = {value(v)}" for k, v in item.items()) + " }"
        if isinstance(item, list):
            return "[" + ", ".join(value(v) for v in item) + "]"
        if isinstance(item, bool):
            return str(item).lower()
        return repr(item) if not isinstance(item, str) else f'"{item}"'

    lines = [f"{k} = {value(v)}" for k, v in doc.items() if not isinstance(v, (dict, list))]
    for name, item in doc.items():
        if isinstance(item, dict):
            lines.append(f"[{name}]")
            lines += [f"{k} = {value(v)}" for k, v in item.items()]
        elif isinstance(item, list) and item and isinstance(item[0], dict):
            for entry in item:
                lines.append(f"[[{name}]]")
                lines += [f"{k} = {value(v)}" for k, v in entry.items()]
    return "\n".join(lines) + "\n"


def frictional(route: str) -> dict:
    doc = copy.deepcopy(BASE)
    doc["friction"] = {"mu": 0.3, "solver": route}
    if route == "polygonal":
        doc["friction"]["facets"] = 8
    return doc


def with_unknown_key(section: str) -> dict:
    """A valid problem with :data:`UNKNOWN` in the table ``section`` names."""
    doc = copy.deepcopy(BASE)
    if section == "top level":
        doc = {UNKNOWN: 1, **doc}
    elif section in ("[model]", "[loads]"):
        doc[section[1:-1]][UNKNOWN] = 1
    elif section == "[loads].entries":
        doc["loads"]["entries"][0][UNKNOWN] = 1
    elif section == "file reference":
        doc["model"]["flexibility"] = {"file": "R.csv", UNKNOWN: 1}
    elif section.startswith("[[obstacle]] "):
        doc["obstacle"] = [{**OBSTACLES[section.split()[1]], UNKNOWN: 1}]
    elif section == "[loading]":
        doc = frictional("coulomb")
        doc["loading"] = {"factors": [0.0, 1.0], UNKNOWN: 1}
    elif section.startswith("[friction] "):
        doc = frictional(section.split()[1])
        doc["friction"][UNKNOWN] = 1
    elif section.startswith("[solver] "):
        doc["solver"] = {"name": section.split()[1], UNKNOWN: 1}
    else:
        raise KeyError(f"no way to reach table {section!r}: add one to with_unknown_key")
    return doc


def accepted_keys(tmp_path: Path, section: str) -> set[str]:
    """The keys the parser allows in ``section``, from its message about an unknown key."""
    path = tmp_path / "problem.toml"
    path.write_text(toml_text(with_unknown_key(section)), encoding="utf-8")
    with pytest.raises(InvalidInputError, match=UNKNOWN) as caught:
        load_problem_file(path)
    allowed = re.search(r"allowed: ([^)]*)\)", str(caught.value))
    assert allowed, str(caught.value)
    return set(allowed.group(1).split(", "))


def test_the_page_documents_every_table_the_schema_has():
    documented = {name for kind, name in DOCUMENTED if kind == "keys"}
    assert documented == set(fixed_keys())
    assert {name for kind, name in DOCUMENTED if kind == "options"} == {
        *(f"[solver] {name}" for name in (method.name for method in methods_for("frictionless"))),
        *(f"[friction] {route}" for route in FRICTION_ROUTES),
    }


@pytest.mark.parametrize(
    "section",
    [
        name
        for kind, name in DOCUMENTED
        if kind == "keys" and name not in ("[solver]", "[friction]")
    ],
)
def test_documented_keys_are_the_accepted_keys(tmp_path, section):
    accepted = accepted_keys(tmp_path, section)
    documented = DOCUMENTED["keys", section]
    assert accepted - documented == set(), f"accepted but not documented in {PAGE.name}"
    assert documented - accepted == set(), f"documented in {PAGE.name} but not accepted"
    assert accepted == set(fixed_keys()[section])


@pytest.mark.parametrize("section", [name for kind, name in DOCUMENTED if kind == "options"])
def test_documented_options_are_the_accepted_options(tmp_path, section):
    """[solver] and [friction] allow their fixed keys and the chosen method's options."""
    table = section.split()[0]
    accepted = accepted_keys(tmp_path, section)
    documented = DOCUMENTED["keys", table] | DOCUMENTED["options", section]
    assert accepted - documented == set(), f"accepted but not documented in {PAGE.name}"
    assert documented - accepted == set(), f"documented in {PAGE.name} but not accepted"


def test_a_warm_start_is_not_a_file_option(tmp_path):
    doc = copy.deepcopy(BASE)
    doc["solver"] = {"name": "active-set", "forces0": [0.0]}
    path = tmp_path / "problem.toml"
    path.write_text(toml_text(doc), encoding="utf-8")
    with pytest.raises(InvalidInputError, match=r"\[solver\]\.forces0: not an option"):
        load_problem_file(path)


def test_the_base_problem_of_these_tests_loads(tmp_path):
    for doc in (BASE, frictional("tresca"), frictional("polygonal")):
        path = tmp_path / "problem.toml"
        path.write_text(toml_text(doc), encoding="utf-8")
        assert load_problem_file(path).problem.constraints.n_constraints == 1


def test_the_toml_blocks_of_the_page_are_toml():
    blocks = re.findall(r"```toml\n(.*?)```", PAGE.read_text(encoding="utf-8"), re.S)
    assert len(blocks) == 2
    for block in blocks:
        tomllib.loads(block)


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda path: path.name)
def test_every_example_problem_loads(example):
    spec = load_problem_file(example)
    assert spec.problem.constraints.n_constraints > 0
    assert spec.name

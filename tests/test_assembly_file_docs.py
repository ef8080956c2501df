"""docs/assembly-files.md is the schema of assembly files: its key tables must be what the
parser accepts, both ways, and the examples must load.

The accepted keys are read from the parser itself: an unknown key is put into each table of a
valid assembly, and the error lists the keys that table allows.
"""

import copy
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from contactqp.applications.assembly_file import read_assembly_file
from contactqp.applications.assembly_file.schema import fixed_keys
from contactqp.errors import InvalidInputError
from contactqp.io.problem_file.options import solver_options
from test_problem_file_docs import toml_text

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "assembly-files.md"
EXAMPLES = sorted((ROOT / "examples" / "assemblies").glob("*.toml"))
#: Examples whose part files a script writes (into a directory, with a copy of the example).
GENERATED_BY = {"blocks.toml": "make_blocks.py", "blocks-ansys.toml": "make_blocks.py"}
UNKNOWN = "not_a_key"
SQUARE = [[0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.01, 0.01, 0.0]]
MATRIX_PART = {
    "type": "matrix",
    "compliance": "R.mtx",
    "kind": "flexibility",
    "dofs_per_node": 3,
    "coordinates": SQUARE,
}
BASE = {
    "parts": {"lower": MATRIX_PART, "upper": MATRIX_PART},
    "interfaces": [{"first": "lower", "second": "upper", "tolerance": 1e-3, "normal": [0, 0, 1]}],
}
MESH_PART = {
    "type": "mesh",
    "mesh": {"block": [0.01, 0.01, 0.01], "cells": [1, 1, 1]},
    "young": 70e9,
    "poisson": 0.3,
    "fix": [{"at": "bottom"}],
    "interface": "top",
}


def documented_tables() -> dict[str, set[str]]:
    """``{name: keys}`` of every table after a ``<!-- keys: ... -->`` marker: the first code
    span of each row's first cell."""
    tables, lines = {}, PAGE.read_text(encoding="utf-8").splitlines()
    for number, line in enumerate(lines):
        marker = re.fullmatch(r"<!-- keys: (.+?) -->", line.strip())
        if not marker:
            continue
        rows = []
        for row in lines[number + 1 :]:
            if not row.startswith("|"):
                break
            rows.append(row)
        assert len(rows) > 2, f"{PAGE.name}: no table after {line.strip()}"
        keys = set()
        for row in rows[2:]:
            span = re.search(r"`([^`]+)`", row.split("|")[1])
            assert span, f"{PAGE.name}: row without a key: {row}"
            keys.add(span.group(1))
        assert marker.group(1) not in tables, f"{line.strip()} twice"
        tables[marker.group(1)] = keys
    return tables


DOCUMENTED = documented_tables()


def with_unknown_key(section: str) -> dict:
    """A valid assembly with :data:`UNKNOWN` in the table ``section`` names."""
    doc = copy.deepcopy(BASE)
    lower = doc["parts"]["lower"]
    if section == "top level":
        doc[UNKNOWN] = 1
    elif section == "[parts.NAME] matrix":
        lower[UNKNOWN] = 1
    elif section.startswith("[parts.NAME] "):
        kind = section.split()[1]
        doc["parts"]["lower"] = {**(MESH_PART if kind == "mesh" else {"type": kind}), UNKNOWN: 1}
    elif section == "mesh generator":
        doc["parts"]["lower"] = copy.deepcopy(MESH_PART)
        doc["parts"]["lower"]["mesh"][UNKNOWN] = 1
    elif section == "fixation":
        doc["parts"]["lower"] = {**MESH_PART, "fix": [{"at": "bottom", UNKNOWN: 1}]}
    elif section == "box":
        box = {"lower": [0.0, 0.0, 0.01], "upper": [0.01, 0.01, 0.01], UNKNOWN: 1}
        doc["parts"]["lower"] = {**MESH_PART, "interface": box}
    elif section.startswith("[[") and section.endswith("]]"):
        name = section[2:-2]
        entry = {"interfaces": doc["interfaces"][0], "fasteners": {"pair": 0}}.get(
            name, {"part": "lower"}
        )
        doc[name] = [{**entry, UNKNOWN: 1}]
    elif section.startswith("[variation] "):
        doc["variation"] = {"type": section.split()[1], UNKNOWN: 1}
    elif section == "[solver]":
        doc["solver"] = {"method": "lawson-hanson", UNKNOWN: 1}
    else:
        doc[section[1:-1]] = {UNKNOWN: 1}
    return doc


@pytest.fixture
def folder(tmp_path):
    scipy.io.mmwrite(tmp_path / "R.mtx", 1e-9 * np.eye(12))
    return tmp_path


def accepted_keys(folder: Path, section: str) -> set[str]:
    path = folder / "assembly.toml"
    path.write_text(toml_text(with_unknown_key(section)), encoding="utf-8")
    with pytest.raises(InvalidInputError, match=UNKNOWN) as caught:
        read_assembly_file(path)
    allowed = re.search(r"allowed: ([^)]*)\)", str(caught.value))
    assert allowed, str(caught.value)
    return set(allowed.group(1).split(", "))


def test_the_page_documents_every_table_the_schema_has():
    assert set(DOCUMENTED) == set(fixed_keys())


@pytest.mark.parametrize("section", sorted(fixed_keys()))
def test_documented_keys_are_the_accepted_keys(folder, section):
    accepted = accepted_keys(folder, section)
    documented = DOCUMENTED[section]
    if section == "[solver]":  # the method's options come on top of the fixed keys
        accepted -= set(solver_options("lawson-hanson", "fastened")[0])
    assert accepted - documented == set(), f"accepted but not documented in {PAGE.name}"
    assert documented - accepted == set(), f"documented in {PAGE.name} but not accepted"
    assert accepted == set(fixed_keys()[section])


def test_the_base_assembly_of_these_tests_loads(folder):
    path = folder / "assembly.toml"
    path.write_text(toml_text(BASE), encoding="utf-8")
    assert read_assembly_file(path).n_pairs == 4


def test_the_toml_block_of_the_page_is_toml():
    blocks = re.findall(r"```toml\n(.*?)```", PAGE.read_text(encoding="utf-8"), re.S)
    assert len(blocks) == 1
    for block in blocks:
        tomllib.loads(block)


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda path: path.name)
def test_every_example_assembly_loads(example, tmp_path):
    if example.name in GENERATED_BY:
        script = example.parent / GENERATED_BY[example.name]
        subprocess.run(
            [sys.executable, str(script), str(tmp_path)], check=True, capture_output=True
        )
        example = tmp_path / example.name
    parsed = read_assembly_file(example)
    assert parsed.n_pairs > 0 and parsed.name

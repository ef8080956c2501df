"""Small assembly files for the tests of the assembly study and its command: the riveting
plates example (1 freedom per node, frictionless) and two 3-D blocks meshed by the embedded
finite elements (3 freedoms per node, with friction), written into a test's directory."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np

from test_problem_file_docs import toml_text

PLATES = Path(__file__).parent.parent / "examples" / "assemblies" / "riveting-plates.toml"

#: Two 40 x 20 x 10 mm aluminium blocks, one on the other, the lower fixed at its bottom, the
#: upper at its top; 3 x 2 pairs on the interface, gaps from a measured cloud (``gaps.csv``,
#: :func:`write`: interference in the middle, open at the ends), a closure and a clamp at two
#: corners, mu = 0.3, a shear load on the upper block after fastening and its removal.
BLOCKS = {
    "name": "two blocks",
    "units": {"length": "mm"},
    "parts": {
        "lower": {
            "type": "mesh",
            "mesh": {"block": [40.0, 20.0, 10.0], "cells": [2, 1, 1]},
            "young": 70e3,
            "poisson": 0.33,
            "fix": [{"at": "bottom"}],
            "interface": "top",
        },
        "upper": {
            "type": "mesh",
            "mesh": {"block": [40.0, 20.0, 10.0], "cells": [2, 1, 1], "origin": [0, 0, 10.0]},
            "young": 70e3,
            "poisson": 0.33,
            "fix": [{"at": "top"}],
            "interface": "bottom",
        },
    },
    "interfaces": [{"first": "lower", "second": "upper", "tolerance": 0.1}],
    "gaps": {"cloud": "gaps.csv", "interpolant": "thin-plate"},
    "variation": {
        "type": "random",
        "amplitude": 0.0005,
        "correlation_length": 20.0,
        "seed": 4,
    },
    "fasteners": [
        {"position": [0.0, 0.0, 10.0]},
        {"position": [40.0, 20.0, 10.0], "kind": "clamp", "force": 500.0, "stiffness": 1e5},
    ],
    "fastening": {"tolerance": 1.0, "order": [1, 0]},
    "friction": {"mu": 0.3},
    "loads": [{"label": "shear", "part": "upper", "force": [200.0, 0.0, 0.0]}],
    "criteria": {"shim_tolerance": 0.00005},
}


def blocks(**changes) -> dict:
    """A copy of :data:`BLOCKS` with top-level tables replaced (``None`` removes one)."""
    doc = copy.deepcopy(BLOCKS)
    for key, value in changes.items():
        if value is None:
            doc.pop(key, None)
        else:
            doc[key] = value
    return doc


def cloud_gap(x):
    """The measured gap (mm) at ``x`` (mm): 0.8 um interference in the middle, 0.2 um open
    at the ends."""
    return 2e-4 - 1e-3 * (1.0 - ((x - 20.0) / 20.0) ** 2)


def write(folder: Path, doc: dict, name: str = "assembly.toml") -> Path:
    """Write ``doc`` as TOML into ``folder``, with the measured cloud ``gaps.csv``; its path."""
    folder.mkdir(parents=True, exist_ok=True)
    rows = [
        f"{float(x)!r}, {float(y)!r}, {float(cloud_gap(x))!r}"
        for x in np.linspace(0.0, 40.0, 9)
        for y in np.linspace(0.0, 20.0, 5)
    ]
    (folder / "gaps.csv").write_text("x, y, gap\n" + "\n".join(rows) + "\n", encoding="utf-8")
    path = folder / name
    path.write_text(toml_text(doc), encoding="utf-8")
    return path

"""The keys an assembly file accepts, table by table.

The page ``docs/assembly-files.md`` documents each of them; ``tests/test_assembly_file_docs.py``
fails when the page and these tables differ. The solver's options come on top of the fixed keys
of ``[solver]``, from the method registry.
"""

from __future__ import annotations

__all__ = [
    "TOP_KEYS",
    "UNITS_KEYS",
    "LENGTH_UNITS",
    "FORCE_UNITS",
    "PART_TYPES",
    "PART_KEYS",
    "GENERATOR_KEYS",
    "FIX_KEYS",
    "BOX_KEYS",
    "INTERFACE_KEYS",
    "GAPS_KEYS",
    "INTERPOLANTS",
    "VARIATION_TYPES",
    "VARIATION_KEYS",
    "FASTENER_KEYS",
    "FASTENING_KEYS",
    "FRICTION_KEYS",
    "LOAD_KEYS",
    "CRITERIA_KEYS",
    "SOLVER_KEYS",
    "fixed_keys",
]

TOP_KEYS = (
    "name",
    "units",
    "parts",
    "interfaces",
    "gaps",
    "variation",
    "fasteners",
    "fastening",
    "friction",
    "loads",
    "criteria",
    "solver",
)
UNITS_KEYS = ("length", "force")
#: Length units and their size in metres.
LENGTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6}
#: Force units and their size in newtons.
FORCE_UNITS = {"N": 1.0, "kN": 1e3, "mN": 1e-3}

#: Where a part's compliance comes from.
PART_TYPES = ("matrix", "mesh", "plate")
PART_KEYS = {
    "matrix": (
        "type",
        "compliance",
        "kind",
        "matrix",
        "nodes",
        "components",
        "freedoms",
        "fixed",
        "dofs_per_node",
        "coordinates",
    ),
    "mesh": ("type", "mesh", "young", "poisson", "order", "fix", "interface"),
    "plate": (
        "type",
        "length",
        "width",
        "thickness",
        "young",
        "poisson",
        "grid",
        "supports",
        "refine",
        "origin",
    ),
}
#: Keys of a generated mesh, ``mesh = { block = [...], cells = [...] }``.
GENERATOR_KEYS = ("block", "cells", "cell", "origin")
#: Keys of one fixation of a mesh part, ``fix = [{ at = "left" }, ...]``.
FIX_KEYS = ("at", "components")
#: Keys of a box of nodes, ``{ lower = [x, y, z], upper = [x, y, z] }``.
BOX_KEYS = ("lower", "upper")

INTERFACE_KEYS = ("first", "second", "pairs", "tolerance", "normal")

GAPS_KEYS = ("nominal", "cloud", "interpolant", "extrapolate")
#: Interpolants of a measured point cloud.
INTERPOLANTS = ("linear", "thin-plate")

VARIATION_TYPES = ("random", "samples", "measured")
VARIATION_KEYS = {
    "random": ("type", "amplitude", "correlation_length", "seed"),
    "samples": ("type", "file"),
    "measured": ("type", "file"),
}

FASTENER_KEYS = ("position", "pair", "kind", "force", "stiffness", "shear", "label")
FASTENING_KEYS = ("order", "tolerance")
FRICTION_KEYS = ("mu", "cone", "facets")
LOAD_KEYS = ("label", "part", "nodes", "box", "force", "steps", "remove")
CRITERIA_KEYS = ("shim_tolerance",)
#: Fixed keys of ``[solver]``; the chosen method's options come on top.
SOLVER_KEYS = ("method",)


def fixed_keys() -> dict[str, tuple[str, ...]]:
    """Every table's fixed keys, by the table's name as the documentation page writes it."""
    return {
        "top level": TOP_KEYS,
        "[units]": UNITS_KEYS,
        **{f"[parts.NAME] {kind}": keys for kind, keys in PART_KEYS.items()},
        "mesh generator": GENERATOR_KEYS,
        "fixation": FIX_KEYS,
        "box": BOX_KEYS,
        "[[interfaces]]": INTERFACE_KEYS,
        "[gaps]": GAPS_KEYS,
        **{f"[variation] {kind}": keys for kind, keys in VARIATION_KEYS.items()},
        "[[fasteners]]": FASTENER_KEYS,
        "[fastening]": FASTENING_KEYS,
        "[friction]": FRICTION_KEYS,
        "[[loads]]": LOAD_KEYS,
        "[criteria]": CRITERIA_KEYS,
        "[solver]": SOLVER_KEYS,
    }

"""The keys a problem file accepts, table by table.

The page ``docs/problem-files.md`` documents each of them; ``tests/test_problem_file_docs.py``
fails when the page and these tables differ. A solver's options come on top of the fixed keys
of ``[solver]`` and ``[friction]`` (:func:`~contactqp.io.problem_file.options.solver_options`).
"""

from __future__ import annotations

__all__ = [
    "TOP_KEYS",
    "MODEL_KEYS",
    "LOADS_KEYS",
    "LOAD_ENTRY_KEYS",
    "FILE_REF_KEYS",
    "OBSTACLE_TYPES",
    "OBSTACLE_KEYS",
    "FRICTION_LAW_KEYS",
    "FRICTION_KEYS",
    "LOADING_KEYS",
    "SOLVER_KEYS",
    "BACKEND_OPTIONS",
    "fixed_keys",
]

TOP_KEYS = ("name", "model", "loads", "obstacle", "friction", "loading", "solver")
MODEL_KEYS = ("flexibility", "stiffness", "dofs_per_node", "coordinates")
LOADS_KEYS = ("values", "entries")
#: Keys of one inline table of ``[loads].entries``.
LOAD_ENTRY_KEYS = ("value", "freedom", "node", "component")
#: Keys of a file reference written as an inline table, ``{ file = "m.npz", key = "R" }``.
FILE_REF_KEYS = ("file", "key", "format")

#: Obstacle types a problem file may use.
OBSTACLE_TYPES = ("gaps", "plane", "pairs")
OBSTACLE_KEYS = {
    "gaps": ("type", "nodes", "gaps", "direction", "directions"),
    "plane": ("type", "point", "normal", "nodes"),
    "pairs": ("type", "pairs", "gaps", "direction", "directions"),
}

#: Keys of ``[friction]`` that make the friction law.
FRICTION_LAW_KEYS = ("mu", "cohesion", "facets")
#: Fixed keys of ``[friction]``; the chosen route's options come on top.
FRICTION_KEYS = ("solver", *FRICTION_LAW_KEYS)
LOADING_KEYS = ("factors", "points", "steps")
#: Fixed keys of ``[solver]``; the chosen solver's options come on top (frictionless only).
SOLVER_KEYS = ("name", "certificate_tol")
#: The sub-table of ``[solver]`` or ``[friction]`` given verbatim to a qpsolvers backend.
BACKEND_OPTIONS = "backend_options"


def fixed_keys() -> dict[str, tuple[str, ...]]:
    """Every table's fixed keys, by the table's name as the documentation page writes it.

    ``[[obstacle]] gaps`` and its siblings are the keys of one obstacle type.
    """
    return {
        "top level": TOP_KEYS,
        "[model]": MODEL_KEYS,
        "[loads]": LOADS_KEYS,
        "[loads].entries": LOAD_ENTRY_KEYS,
        "file reference": FILE_REF_KEYS,
        **{f"[[obstacle]] {kind}": keys for kind, keys in OBSTACLE_KEYS.items()},
        "[friction]": FRICTION_KEYS,
        "[loading]": LOADING_KEYS,
        "[solver]": SOLVER_KEYS,
    }

"""Problem files: a contact problem described in TOML, and its results written out.

This is what ``contactqp solve PROBLEM.toml`` reads (:func:`load_problem_file`) and writes
(:func:`write_results`): a frictionless problem, a problem with friction, or a problem with
friction along a load history. The schema, the result files and the errors are documented in
``docs/problem-files.md``; ``examples/problems/`` holds examples.

==================  ==========================================================================
:mod:`.schema`      the keys each table accepts
:mod:`.parsing`     TOML file to :class:`ProblemSpec` (:mod:`.values`, :mod:`.options`,
                    :mod:`.messages` check values, solver options and word the errors)
:mod:`.spec`        :class:`ProblemSpec`: the problem, and the glue that solves it
:mod:`.writing`     the result files
==================  ==========================================================================
"""

from ..arrays import ARRAY_FORMATS, read_array
from .parsing import load_problem_file
from .schema import OBSTACLE_TYPES
from .spec import ProblemSpec
from .writing import HISTORY_FILES, RESULT_FILES, write_results

__all__ = [
    "ProblemSpec",
    "load_problem_file",
    "write_results",
    "read_array",
    "ARRAY_FORMATS",
    "OBSTACLE_TYPES",
    "RESULT_FILES",
    "HISTORY_FILES",
]

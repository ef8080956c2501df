"""Per-contact loops of the friction solvers: compiled when the package was built with them.

:mod:`contactqp.kernels.compiled` is the Cython extension that ``pip install`` builds where a C
compiler is found; :mod:`contactqp.kernels.pure_numpy` computes the same maps with whole-array
numpy expressions (slower on small problems, where the fixed cost of each numpy call dominates).
This module offers the first that loads: the compiled one unless it is absent, in which case
one :class:`~contactqp.errors.PureNumpyKernelsWarning` says so when the package is imported, or
unless the environment variable ``CONTACTQP_PURE_NUMPY`` is set to anything but ``""`` or
``"0"`` (then silently: the choice was the user's). :data:`IMPLEMENTATION` names the one in
use. Callers: :mod:`contactqp.core.local_problem`, :mod:`contactqp.methods.coulomb`,
:mod:`contactqp.methods.planar` and (the cold start's row sums)
:mod:`contactqp.methods.active_set`.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Mapping

from ..errors import PureNumpyKernelsWarning

__all__ = [
    "project_rows",
    "natural_map_rows",
    "alart_curnier_rows",
    "sparse_newton_matrix",
    "planar_gauss_seidel",
    "planar_blocks",
    "row_products",
    "abs_row_sums",
    "small_newton",
    "small_certificate",
    "small_semidefinite",
    "small_solve",
    "local_arrays_valid",
    "SMALL_REASONS",
    "planar_solve",
    "PLANAR_REASONS",
    "spatial_solve",
    "SPATIAL_REASONS",
    "IMPLEMENTATION",
    "FORCE_PURE_NUMPY",
    "pure_numpy_forced",
]

#: Environment variable that selects the pure-numpy kernels even where the compiled ones exist.
FORCE_PURE_NUMPY = "CONTACTQP_PURE_NUMPY"


def pure_numpy_forced(environ: Mapping[str, str] = os.environ) -> bool:
    """Whether :data:`FORCE_PURE_NUMPY` asks for the pure-numpy kernels (set, not ``0``)."""
    return environ.get(FORCE_PURE_NUMPY, "").strip() not in ("", "0")


#: ``"compiled"`` or ``"pure_numpy"``: the module whose functions this one offers.
IMPLEMENTATION: str

#: The compiled small-problem route (:func:`contactqp.kernels.compiled.small_newton`, its
#: certificate and PSD check), None with the pure-numpy kernels: it has no numpy twin, its
#: oracle is the Python Newton run of :mod:`contactqp.methods.coulomb`, which the solvers use
#: where it is None.
small_newton: Callable[..., None] | None = None
small_certificate: Callable[..., None] | None = None
small_semidefinite: Callable[..., None] | None = None
#: One small problem in one call (:func:`contactqp.kernels.compiled.small_solve`: the Newton
#: run and the certificate), and the one-pass check of a local problem's arrays
#: (:func:`contactqp.kernels.compiled.local_arrays_valid`); None with the pure-numpy kernels,
#: where the numpy checks and the Python route run instead.
small_solve: Callable[..., tuple] | None = None
local_arrays_valid: Callable[..., bool] | None = None
#: The reasons of :func:`~contactqp.kernels.compiled.small_newton`'s codes (coulomb's Newton run).
SMALL_REASONS: tuple[str, ...] = ()
#: The compiled 2-D solve (:func:`contactqp.kernels.compiled.planar_solve`: the Gauss-Seidel
#: sweeps and the certificate in one call), None with the pure-numpy kernels: its oracle is the
#: sweeps of :func:`planar_gauss_seidel` driven from Python, which
#: :mod:`contactqp.methods.planar` runs where it is None.
planar_solve: Callable[..., tuple[int, int]] | None = None
#: The reasons of :func:`~contactqp.kernels.compiled.planar_solve`'s codes.
PLANAR_REASONS: tuple[str, ...] = ()
#: The compiled 3-D solve (:func:`contactqp.kernels.compiled.spatial_solve`: Gauss-Seidel sweeps
#: with a local solver by cases, and the certificate), None with the pure-numpy kernels, where
#: :mod:`contactqp.methods.spatial` is the Newton route alone.
spatial_solve: Callable[..., tuple[int, int]] | None = None
#: The reasons of :func:`~contactqp.kernels.compiled.spatial_solve`'s codes.
SPATIAL_REASONS: tuple[str, ...] = ()

if pure_numpy_forced():
    from .pure_numpy import (
        abs_row_sums,
        alart_curnier_rows,
        natural_map_rows,
        planar_blocks,
        planar_gauss_seidel,
        project_rows,
        row_products,
        sparse_newton_matrix,
    )

    IMPLEMENTATION = "pure_numpy"
else:
    try:
        from . import compiled as _compiled
        from .compiled import (
            abs_row_sums,
            alart_curnier_rows,
            natural_map_rows,
            planar_blocks,
            planar_gauss_seidel,
            project_rows,
            row_products,
            sparse_newton_matrix,
        )

        small_newton = _compiled.small_newton
        small_certificate = _compiled.small_certificate
        small_semidefinite = _compiled.small_semidefinite
        small_solve = _compiled.small_solve
        local_arrays_valid = _compiled.local_arrays_valid
        SMALL_REASONS = _compiled.SMALL_REASONS
        planar_solve = _compiled.planar_solve
        PLANAR_REASONS = _compiled.PLANAR_REASONS
        spatial_solve = _compiled.spatial_solve
        SPATIAL_REASONS = _compiled.SPATIAL_REASONS

        IMPLEMENTATION = "compiled"
    except ImportError as _missing:
        from .pure_numpy import (
            abs_row_sums,
            alart_curnier_rows,
            natural_map_rows,
            planar_blocks,
            planar_gauss_seidel,
            project_rows,
            row_products,
            sparse_newton_matrix,
        )

        IMPLEMENTATION = "pure_numpy"
        warnings.warn(
            f"contactqp's compiled kernels are not available ({_missing}): the "
            f"pure-numpy kernels are used, slower on small problems; reinstall with a C "
            f"compiler to build them",
            PureNumpyKernelsWarning,
            stacklevel=2,
        )
        del _missing

#: The compiled small global route (:func:`contactqp.kernels.compiled.global_small`: the
#: factorisation of ``M``, the condensation, the Newton runs and the global certificate in one
#: call), None with the pure-numpy kernels: its oracle is the general route of
#: :func:`contactqp.solve` (condensation, ``coulomb`` and
#: :meth:`~contactqp.core.local_problem.GlobalProblem.certify`), which runs where it is None.
global_small: Callable[..., int] | None = None
#: The reasons of :func:`~contactqp.kernels.compiled.global_small`'s codes, and the names of
#: its measures.
GLOBAL_CODES: tuple[str, ...] = ()
GLOBAL_MEASURES: tuple[str, ...] = ()
if IMPLEMENTATION == "compiled":
    global_small = _compiled.global_small
    GLOBAL_CODES = _compiled.GLOBAL_CODES
    GLOBAL_MEASURES = _compiled.GLOBAL_MEASURES
__all__ += ["global_small", "GLOBAL_CODES", "GLOBAL_MEASURES"]

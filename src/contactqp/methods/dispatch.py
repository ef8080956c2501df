"""One entry point: :func:`solve` solves a problem of any kind with a registered method."""

from __future__ import annotations

import time

import numpy as np

from .. import kernels
from .frictional import solve_frictional
from .global_route import condense, solve_compiled
from .local_global import certify_global
from .planar import ROUTE_MAX_CONTACTS
from .registry import (
    FRICTIONLESS_ROUTE,
    METHODS,
    PLANAR_ROUTE,
    SPATIAL_ROUTE,
    Method,
    check_options,
    get_kind,
    get_method,
    kind_of,
)
from .spatial import ROUTE_MAX_CONTACTS as SPATIAL_MAX_CONTACTS

__all__ = ["solve", "resolve"]

#: The method whose answers to small global problems
#: :func:`~contactqp.methods.global_route.solve_compiled` gives in one compiled call.
COMPILED_GLOBAL = "coulomb"

#: The routes :func:`resolve` picks by size: on a global problem the compiled global route
#: goes first (measured 7-30x faster on the shared files, the condensation included).
_SIZE_ROUTES = (PLANAR_ROUTE, SPATIAL_ROUTE)


def _is_frictionless(problem, kind: str) -> bool:
    """True when ``mu = 0`` on every contact of a problem of a frictional ``kind``."""
    if kind in ("frictional", "frictional-polygonal"):
        return problem.frictionless
    if kind in ("local", "global"):  # read directly: a cached property's lock costs more
        return not np.count_nonzero(problem.mu)  # on the small problems of these kinds (mu >= 0)
    return False


def resolve(
    problem, method: str | None = None, options: dict | None = None
) -> tuple[str, Method, dict]:
    """``(kind, method, options)`` that :func:`solve` runs for ``problem``.

    The kind's option defaults (:attr:`~contactqp.methods.registry.Kind.defaults`) are added
    under ``options``. With ``mu = 0`` on every contact, the kind's default method (asked for
    by name or by None) is replaced by the frictionless route
    (:data:`~contactqp.methods.registry.FRICTIONLESS_ROUTE`), which receives the options it
    takes; with 2-D contacts (``dim == 2``) a local or global problem of at most
    :data:`~contactqp.methods.planar.ROUTE_MAX_CONTACTS` contacts with no method named takes
    the planar route (:data:`~contactqp.methods.registry.PLANAR_ROUTE`), which
    takes the same options and hands the default a problem on which it stalls; with 3-D
    contacts, up to :data:`~contactqp.methods.spatial.ROUTE_MAX_CONTACTS`, the spatial route
    (:data:`~contactqp.methods.registry.SPATIAL_ROUTE`) does the same where the compiled
    kernels are built.

    Raises
    ------
    InvalidInputError
        Not a problem, an unknown or unfitting method, or an unknown option.
    """
    kind = kind_of(problem)
    spec = get_kind(kind)
    entry = get_method(method, kind)
    options = dict(options or {})
    check_options(entry, kind, options)
    if entry.name == spec.default and _is_frictionless(problem, kind):
        entry = METHODS[FRICTIONLESS_ROUTE]
        options = {name: value for name, value in options.items() if name in entry.option_names}
    elif method is None and kind in ("local", "global"):
        if problem.dim == 2 and problem.n_contacts <= ROUTE_MAX_CONTACTS:
            entry = METHODS[PLANAR_ROUTE]  # takes the default's options, hands it a stall
        elif (
            problem.dim == 3
            and problem.n_contacts <= SPATIAL_MAX_CONTACTS
            and kernels.spatial_solve is not None
        ):
            entry = METHODS[SPATIAL_ROUTE]  # the same, in 3-D
    defaults = {name: value for name, value in spec.defaults.items() if name in entry.option_names}
    return kind, entry, {**defaults, **options}


def solve(problem, method: str | None = None, **options):
    """Solve ``problem``, of any kind, with the named method (None: the kind's default).

    ==========================================  ====================  ===========================
    problem                                     default method        result
    ==========================================  ====================  ===========================
    :class:`~contactqp.ContactProblem`          ``active-set``        ContactResult
    :class:`~contactqp.FrictionalProblem`       ``coulomb``           FrictionalResult
    the same with ``facets``                    ``polygonal``         FrictionalResult
    ``LocalProblem`` (FCLIB)                    ``coulomb``           LocalResult
    ``GlobalProblem`` (FCLIB)                   ``coulomb``           LocalResult (certified on
                                                                      the global equations)
    ``FastenedProblem``                         ``lawson-hanson``     FastenedResult
    ``SurfaceProblem``                          ``constrained-cg``    SurfaceResult
    ``LocalBatch`` (many small local problems)  ``coulomb-batch``     LocalBatchResult
    ``SlidingSurfaceProblem``                   ``tangential-fista``  SlidingSurfaceResult
    ==========================================  ====================  ===========================

    ``mu = 0`` on every contact of a frictional, local or global problem: the default method
    (None or its name) is replaced by the frictionless route ``normal-qp`` (the box QP on the
    normal block); the result keeps its kind's shape and certificate. A cross-check named
    explicitly runs as asked. A local or global problem of 2-D contacts (at most
    :data:`~contactqp.methods.planar.ROUTE_MAX_CONTACTS`) with no method named takes the planar
    route ``planar`` (:mod:`~contactqp.methods.planar`), which hands a stall
    to ``coulomb``. A global problem is condensed by the structure of its ``M``
    (:func:`~contactqp.methods.global_route.condense`: block-diagonal ``M`` inverted exactly,
    small ones factored dense), and the answer certified on the global equations with the same
    factorisation; one whose contacts fall into small groups that ``W`` couples (with a
    block-diagonal ``M`` of any size, or a small dense one), with ``coulomb`` or no method named,
    goes through all of this in one compiled call first
    (:func:`~contactqp.methods.global_route.solve_compiled`), before the routes by size. The
    methods, their kinds and options: :mod:`the registry <contactqp.methods.registry>`, or
    ``contactqp methods``.

    Parameters
    ----------
    problem
        A problem of a registered kind (its ``kind`` attribute).
    method : str, optional
        A method registered for the problem's kind.
    **options
        The method's keyword options (see the registry); ``r0`` is the warm start of every
        method that takes one. For a frictional problem, ``r0`` is in newtons (local forces,
        shape (k, d) or (d k,)) and defaults to the forces of its ``previous`` state.

    Raises
    ------
    InvalidInputError
        An unknown or unfitting method (the message lists those for the kind), an unknown
        option (the message names it and the valid ones), or bad option values.
    MissingDependencyError
        The method needs an extra that is not installed.
    """
    kind, entry, options = resolve(problem, method, options)
    if kind in ("frictional", "frictional-polygonal"):
        return solve_frictional(problem, entry, options)
    if kind == "global":
        start = time.perf_counter()
        if entry.name == COMPILED_GLOBAL or (method is None and entry.name in _SIZE_ROUTES):
            # small problems: coulomb in one compiled call, or None
            result = solve_compiled(problem, start, **options)
            if result is not None:
                return result
        condensed = condense(problem)  # M factored once, by its structure
        if condensed.factor.positive_definite and "check_psd" in entry.option_names:
            options = {**options, "check_psd": False}  # W = H^T M^-1 H, M checked SPD
        local = entry.function(condensed.local, **options)
        tol = options.get("tol", _default(entry, "tol"))
        return certify_global(
            problem, local, tol, start, factor=condensed.factor, condensed=condensed.local
        )
    return entry.function(problem, **options)


def _default(method: Method, name: str):
    return next(option.default for option in method.options if option.name == name)

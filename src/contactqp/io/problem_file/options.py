"""Solver options of a problem file: which ones a method takes, and their checks.

:func:`solver_options` is the one place that gives a method's options: the method registry's
(:mod:`contactqp.methods.registry`), never the function's signature.
"""

from __future__ import annotations

import math

from ...core.certificate import CERTIFICATE_TOL
from ...core.problem import ContactProblem
from ...errors import InvalidInputError
from ...methods.registry import default_method, get_method, method_options
from .messages import Where, as_table, close_match, describe
from .schema import BACKEND_OPTIONS, SOLVER_KEYS
from .values import option

__all__ = ["solver_options", "route_options", "solver_section"]


def solver_options(name: str, kind: str) -> tuple[dict, bool]:
    """The options a problem file may give method ``name`` on problems of ``kind``, from the
    method registry, and whether the method passes extra ones on.

    Returns
    -------
    options : dict
        ``{name: default}``: the kind's defaults applied, without the warm start ``r0`` (a file
        starts from rest, or from the previous step of a history) and the options the problem
        sets itself (``facets``).
    extra : bool
        True when it hands backend settings on (``backend_options`` in a file).
    """
    named = method_options(name, kind)
    named.pop("r0", None)
    return named, get_method(name, kind).backend_settings


def route_options(
    where: Where, section_table: dict, section: str, route: str, named: dict, extra: bool, reserved
) -> dict:
    """The solver options in ``section_table`` (its keys beyond ``reserved``), checked against
    ``named`` (name: default); ``[section.backend_options]`` when the solver passes extra ones
    on."""
    allowed = {*reserved, *named}
    if extra:
        allowed.add(BACKEND_OPTIONS)
    for key in section_table:
        if key not in allowed:
            hint = close_match(key, allowed)
            if extra:
                hint += f"; backend settings go in [{section[1:-1]}.{BACKEND_OPTIONS}]"
            raise where.error(
                f"{section}.{key}",
                f"not an option of {route} (allowed: {', '.join(sorted(allowed))}){hint}",
            )
    options = {
        key: option(where, key, section_table[key], named[key], f"{section}.{key}")
        for key in section_table
        if key in named
    }
    if BACKEND_OPTIONS in section_table:
        sub = f"[{section[1:-1]}.{BACKEND_OPTIONS}]"
        backend = as_table(where, section_table[BACKEND_OPTIONS], sub)
        for key, value in backend.items():
            if isinstance(value, (dict, list)) or (
                isinstance(value, float) and not math.isfinite(value)
            ):
                raise where.error(
                    f"{sub}.{key}",
                    f"must be a finite number, a string or a boolean, got {describe(value)}",
                )
            if key in named or key in options:
                raise where.error(f"{sub}.{key}", f"is an option of {route}: set it in {section}")
            option(where, key, value, None, f"{sub}.{key}")
            options[key] = value
    if "backend" in named:
        _check_backend(
            where,
            section,
            options.get("backend", named["backend"]),
            {key: options[key] for key in section_table.get(BACKEND_OPTIONS, {})},
        )
    return options


def _check_backend(where: Where, section: str, backend, settings: dict) -> None:
    """Raise, naming the key, when the qpsolvers ``backend`` is not installed or refuses one of
    ``settings`` (see :func:`~contactqp.methods.qp.refused_setting`)."""
    from ...methods.qp import installed_backend, refused_setting

    try:
        installed_backend(backend)
    except InvalidInputError as exc:
        raise where.error(f"{section}.backend", str(exc)) from None
    for key, value in settings.items():
        reason = refused_setting(backend, key, value)
        if reason:
            raise where.error(
                f"[{section[1:-1]}.{BACKEND_OPTIONS}].{key}",
                f"backend '{backend}' refuses {key} = {value!r} ({reason})",
            )


def solver_section(where: Where, doc: dict, frictional: bool) -> tuple[str, dict, float]:
    """``(solver, options, certificate_tol)`` of ``[solver]``; with friction only the
    certificate tolerance (the route and its options are ``[friction]``'s)."""
    section = as_table(where, doc.get("solver", {}), "[solver]")
    certificate_tol = option(
        where,
        "certificate_tol",
        section.get("certificate_tol", CERTIFICATE_TOL),
        CERTIFICATE_TOL,
        "[solver].certificate_tol",
    )
    if frictional:
        if "name" in section:
            raise where.error(
                "[solver].name",
                f"solver {section['name']!r} is frictionless but [friction] is given: remove "
                "[solver].name and choose the route with [friction].solver (coulomb, tresca "
                "or polygonal)",
            )
        for key in section:
            if key != "certificate_tol":
                raise where.error(
                    f"[solver].{key}",
                    "with [friction], [solver] holds only "
                    "certificate_tol; solver options go in [friction]",
                )
        return "", {}, certificate_tol
    name = section.get("name", default_method(ContactProblem.kind))
    if not isinstance(name, str):
        raise where.error("[solver].name", f"must be a string, got {describe(name)}")
    try:
        named, extra = solver_options(name, ContactProblem.kind)
    except InvalidInputError as exc:
        raise where.rewrap("[solver].name", exc) from None
    options = route_options(
        where, section, "[solver]", f"solver '{name}'", named, extra, SOLVER_KEYS
    )
    return name, options, certificate_tol

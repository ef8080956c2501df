"""The registry of methods: what each one solves, its options, what it needs.

Every method is registered here, in one place (:data:`METHODS`), with its metadata; the problem
kinds are listed in :data:`KINDS`. :func:`~contactqp.methods.dispatch.solve`, the problem files
and the command line take their method names and valid options from here, never from a
function's signature (a test checks that the two agree).

A problem carries its kind as the attribute ``kind``:

========================  ===================================================================
``frictionless``          :class:`~contactqp.ContactProblem`
``frictional``            :class:`~contactqp.FrictionalProblem`, exact cone
``frictional-polygonal``  :class:`~contactqp.FrictionalProblem` with ``facets``
``local``                 :class:`~contactqp.core.local_problem.LocalProblem` (FCLIB local)
``global``                :class:`~contactqp.core.local_problem.GlobalProblem` (FCLIB global)
``local-batch``           :class:`~contactqp.core.local_batch.LocalBatch` (many small local)
``fastened``              :class:`~contactqp.core.fastened.FastenedProblem`
``surface``               :class:`~contactqp.core.surface.SurfaceProblem` (through products)
``sliding-surface``       :class:`~contactqp.core.sliding_surface.SlidingSurfaceProblem`
                          (partial slip, through products)
========================  ===================================================================
"""

from __future__ import annotations

import functools
import importlib.util
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from ..errors import InvalidInputError
from .active_set import solve_active_set
from .batch import solve_coulomb_batch
from .constrained_cg import MAX_ITER as CG_MAX_ITER
from .constrained_cg import solve_constrained_cg
from .coulomb import MAX_ITER, PROXIMAL_MAX_ITER, solve_coulomb, solve_proximal
from .fastened import solve_lawson_hanson, solve_nnls
from .local_global import solve_frictionless
from .planar import SWEEPS, solve_planar
from .polygonal import solve_polygonal
from .qp import DEFAULT_BACKEND, solve_qp
from .spatial import SWEEPS as SPATIAL_SWEEPS
from .spatial import solve_spatial
from .surface_active_set import solve_surface_active_set
from .surface_dual_active_set import MAX_CG, solve_dual_active_set
from .tangential_fista import MAX_ITER as FISTA_MAX_ITER
from .tangential_fista import MAX_OUTER as FISTA_MAX_OUTER
from .tangential_fista import solve_tangential_fista
from .tresca import solve_tresca_fixed_point

__all__ = [
    "Option",
    "Method",
    "Kind",
    "METHODS",
    "KINDS",
    "EXTRA_MODULES",
    "get_method",
    "get_kind",
    "kind_of",
    "methods_for",
    "default_method",
    "is_installed",
    "method_options",
    "check_options",
    "FRICTIONLESS_ROUTE",
    "PLANAR_ROUTE",
    "SPATIAL_ROUTE",
]

#: The method :func:`~contactqp.solve` takes instead of a kind's default when ``mu = 0`` on
#: every contact.
FRICTIONLESS_ROUTE = "normal-qp"

#: The method :func:`~contactqp.solve` takes instead of a local or global problem's default
#: when its contacts are 2-D (``dim == 2``); it hands a stalled problem to the default.
PLANAR_ROUTE = "planar"

#: The same for 3-D contacts (``dim == 3``), up to
#: :data:`~contactqp.methods.spatial.ROUTE_MAX_CONTACTS` contacts.
SPATIAL_ROUTE = "spatial"


@dataclass(frozen=True)
class Option:
    """A keyword option of a method: its name, type, default and one line of documentation."""

    name: str
    type: type
    default: object
    doc: str


@dataclass(frozen=True)
class Method:
    """A registered method.

    Attributes
    ----------
    name : str
        What :func:`~contactqp.solve` and the files call it.
    kinds : tuple of str
        The problem kinds it solves (see :data:`KINDS`).
    function : callable
        ``function(problem, **options)``; for the ``frictional*`` and ``global`` kinds it
        receives the local problem :func:`~contactqp.solve` derives.
    options : tuple of Option
        Its keyword options (all of them keyword-only in ``function``).
    extra : str or None
        The contactqp extra it needs (``pip install 'contactqp[extra]'``).
    role : {"exact", "cross-check"}
        ``"exact"``: the project's reference method for its kinds; ``"cross-check"``: a second,
        independent route to compare with.
    summary : str
        One line.
    backend_settings : bool
        True when further keywords are passed on to a qpsolvers backend.
    """

    name: str
    kinds: tuple[str, ...]
    function: Callable
    options: tuple[Option, ...]
    extra: str | None
    role: str
    summary: str
    backend_settings: bool = False

    @functools.cached_property
    def option_names(self) -> tuple[str, ...]:
        """The names of :attr:`options`, in order."""
        return tuple(option.name for option in self.options)


@dataclass(frozen=True)
class Kind:
    """A problem kind: its default method and the option defaults it sets.

    Attributes
    ----------
    name : str
    problem : str
        The problem class, for messages and listings.
    default : str
        The method used when none is named.
    defaults : Mapping
        Option defaults this kind sets over the method's own (the frictional kinds solve a
        scaled local problem to a tighter ``tol``, on every contact's own scale).
    fixed : tuple of str
        Options the problem itself sets (``facets`` of a polygonal cone); refused from callers.
    """

    name: str
    problem: str
    default: str
    defaults: Mapping = field(default_factory=dict)
    fixed: tuple[str, ...] = ()


def _frozen(**values) -> Mapping:
    return MappingProxyType(values)


_R0_FRICTIONLESS = Option(
    "r0", np.ndarray, None, "warm start: contact forces of a nearby problem (N), shape (m,)"
)
_R0_LOCAL = Option(
    "r0",
    np.ndarray,
    None,
    "warm start: local reactions, shape (d k,) (frictional: N, default the previous state's)",
)
_PER_CONTACT = Option(
    "per_contact", bool, False, "also converge on every contact's own scale (natural-map error)"
)


def _local_tol(default: float) -> Option:
    return Option("tol", float, default, "target natural-map error")


def _sweeps_options(most: int) -> tuple[Option, ...]:
    """The options of a Gauss-Seidel route of at most ``most`` sweeps (planar, spatial): those
    of coulomb, to which it hands a stall."""
    return (
        _R0_LOCAL,
        _local_tol(1e-8),
        Option(
            "max_iter",
            int,
            MAX_ITER,
            f"budget of Gauss-Seidel sweeps (at most {most}) and, after a stall, of the coulomb "
            "method",
        ),
        Option(
            "check_psd",
            bool,
            True,
            "check W's contact blocks (and what coulomb solves on, when it takes over)",
        ),
        _PER_CONTACT,
    )


#: Every method, by name (explicit registration: add a method here and nowhere else).
METHODS: Mapping[str, Method] = MappingProxyType(
    {
        method.name: method
        for method in (
            Method(
                "active-set",
                ("frictionless", "fastened"),
                solve_active_set,
                (
                    _R0_FRICTIONLESS,
                    Option("tol", float, 1e-10, "relative natural residual of the box QP"),
                    Option("max_iter", int, 500, "largest number of box-QP iterations"),
                ),
                None,
                "exact",
                "primal-dual active set on the dual QP (forces >= 0), never inverting R",
            ),
            Method(
                "qp",
                ("frictionless",),
                solve_qp,
                (Option("backend", str, DEFAULT_BACKEND, "the qpsolvers backend"),),
                "qp",
                "cross-check",
                "the primal QP on displacements through a qpsolvers backend (settings passed on)",
                backend_settings=True,
            ),
            Method(
                "coulomb",
                ("frictional", "local", "global"),
                solve_coulomb,
                (
                    _R0_LOCAL,
                    _local_tol(1e-8),
                    Option(
                        "max_iter",
                        int,
                        MAX_ITER,
                        "budget of Newton iterations and Gauss-Seidel sweeps",
                    ),
                    Option(
                        "check_psd",
                        bool,
                        True,
                        "check that W (on candidate sets: their blocks) is positive semidefinite",
                    ),
                    _PER_CONTACT,
                ),
                None,
                "exact",
                "semismooth Newton on Alart-Curnier, Gauss-Seidel fallback",
            ),
            Method(
                "proximal",
                ("local", "global"),
                solve_proximal,
                (
                    _R0_LOCAL,
                    _local_tol(1e-8),
                    Option(
                        "max_iter",
                        int,
                        PROXIMAL_MAX_ITER,
                        "budget of the inner Newton iterations",
                    ),
                    Option("check_psd", bool, True, "check that W is positive semidefinite"),
                    _PER_CONTACT,
                ),
                None,
                "cross-check",
                "proximal-point iterations around Newton, for a very singular W (the last stage "
                "of coulomb)",
            ),
            Method(
                "coulomb-batch",
                ("local-batch",),
                solve_coulomb_batch,
                (
                    Option("r0", np.ndarray, None, "warm starts: reactions, shape (P, d k)"),
                    _local_tol(1e-8),
                    Option(
                        "max_iter",
                        int,
                        MAX_ITER,
                        "budget of Newton iterations and Gauss-Seidel sweeps per problem",
                    ),
                    Option("check_psd", bool, True, "check that every W is positive semidefinite"),
                    _PER_CONTACT,
                ),
                None,
                "exact",
                "coulomb on every problem of a batch, in one compiled loop",
            ),
            Method(
                "planar",
                ("local", "global"),
                solve_planar,
                _sweeps_options(SWEEPS),
                None,
                "exact",
                "2-D contacts: Gauss-Seidel with the exact planar local solver, then coulomb "
                "(taken for the default)",
            ),
            Method(
                "spatial",
                ("local", "global"),
                solve_spatial,
                _sweeps_options(SPATIAL_SWEEPS),
                None,
                "exact",
                "3-D contacts: Gauss-Seidel with a local solver by cases, then coulomb "
                "(taken for the default)",
            ),
            Method(
                "tresca",
                ("frictional", "local", "global"),
                solve_tresca_fixed_point,
                (
                    _R0_LOCAL,
                    _local_tol(1e-8),
                    Option("max_iter", int, 50, "largest number of cone programs"),
                    _PER_CONTACT,
                ),
                "qp",
                "cross-check",
                "fixed point on Tresca cone programs solved by Clarabel",
            ),
            Method(
                "polygonal",
                ("frictional-polygonal", "local", "global"),
                solve_polygonal,
                (
                    _R0_LOCAL,
                    Option(
                        "facets", int, 8, "sides of the polygon inscribed in each friction disc"
                    ),
                    Option("backend", str, "clarabel", "the qpsolvers backend"),
                    _local_tol(1e-8),
                    Option("max_iter", int, 50, "largest number of quadratic programs"),
                    _PER_CONTACT,
                ),
                "qp",
                "exact",
                "polygonal (linearised) cones: fixed point of QPs through qpsolvers",
                backend_settings=True,
            ),
            Method(
                "normal-qp",
                ("frictional", "frictional-polygonal", "local", "global"),
                solve_frictionless,
                (
                    _R0_LOCAL,
                    _local_tol(1e-8),
                    Option("max_iter", int, None, "cap on the box-QP iterations (None: 500)"),
                    Option("check_psd", bool, True, "check that W is positive semidefinite"),
                    _PER_CONTACT,
                ),
                None,
                "exact",
                "mu = 0 on every contact: the box QP on the normal block (taken for the default)",
            ),
            Method(
                "lawson-hanson",
                ("fastened",),
                solve_lawson_hanson,
                (
                    Option(
                        "r0",
                        np.ndarray,
                        None,
                        "warm start: multipliers of a nearby state, shape (m,)",
                    ),
                    Option("tol", float, 1e-10, "on q - S x, relative to max|q|"),
                ),
                None,
                "exact",
                "Lawson and Hanson's active set on the Schur complement, one contact at a time",
            ),
            Method(
                "constrained-cg",
                ("surface",),
                solve_constrained_cg,
                (
                    Option(
                        "r0", np.ndarray, None, "warm start: forces of a nearby problem (N), (m,)"
                    ),
                    Option(
                        "tol", float, 1e-10, "gap on the contact, penetration off it (relative)"
                    ),
                    Option("max_iter", int, CG_MAX_ITER, "largest number of iterations"),
                    Option(
                        "precondition",
                        bool,
                        True,
                        "precondition by the operator's approximate inverse, if it has one",
                    ),
                    Option(
                        "multilevel",
                        bool,
                        True,
                        "without r0, start from solves on the operator's coarser lattices",
                    ),
                ),
                None,
                "exact",
                "Polonsky and Keer's constrained conjugate gradient (preconditioned, nested "
                "from coarse lattices where the operator allows), through W's products only",
            ),
            Method(
                "surface-active-set",
                ("surface",),
                solve_surface_active_set,
                (
                    Option(
                        "r0", np.ndarray, None, "warm start: forces of a nearby problem (N), (m,)"
                    ),
                    Option("tol", float, 1e-10, "box-QP natural residual and load balance"),
                    Option("max_iter", int, 500, "largest number of iterations of each box QP"),
                ),
                None,
                "cross-check",
                "the box QP's active set at each approach (Newton on it at a fixed load); "
                "factors blocks of W",
            ),
            Method(
                "dual-active-set",
                ("surface",),
                solve_dual_active_set,
                (
                    Option(
                        "r0", np.ndarray, None, "warm start: forces of a nearby problem (N), (m,)"
                    ),
                    Option(
                        "tol", float, 1e-10, "gap on the contact, penetration off it (relative)"
                    ),
                    Option("max_iter", int, 100, "largest number of active sets"),
                    Option("max_cg", int, MAX_CG, "largest number of CG steps of each set"),
                ),
                None,
                "cross-check",
                "primal-dual active set, each set's equations by CG through W's products only",
            ),
            Method(
                "tangential-fista",
                ("sliding-surface",),
                solve_tangential_fista,
                (
                    Option(
                        "r0",
                        np.ndarray,
                        None,
                        "warm start: tangential forces of a smaller shift (N), (m, 2)",
                    ),
                    Option("p0", np.ndarray, None, "warm start: normal forces (N), (m,)"),
                    Option("tol", float, 1e-10, "projected slip and normal gaps (relative)"),
                    Option("max_iter", int, FISTA_MAX_ITER, "largest number of iterations"),
                    Option(
                        "lipschitz",
                        float,
                        None,
                        "largest eigenvalue of W_TT on the contact (m/N); default: Lanczos",
                    ),
                    Option(
                        "max_outer",
                        int,
                        FISTA_MAX_OUTER,
                        "largest number of normal-then-tangential rounds of a coupled compliance",
                    ),
                    Option(
                        "multilevel",
                        bool,
                        True,
                        "without warm starts, start from solves on coarser lattices",
                    ),
                ),
                None,
                "exact",
                "the normal problem by constrained CG, then FISTA with restart on the friction "
                "discs (in turn until a coupled compliance settles), through W's products only",
            ),
            Method(
                "nnls",
                ("fastened",),
                solve_nnls,
                (),
                None,
                "cross-check",
                "scipy's NNLS on the Cholesky factor of the Schur complement (cold start)",
            ),
        )
    }
)

_FRICTIONAL_DEFAULTS = _frozen(tol=1e-10, per_contact=True, check_psd=False)

#: The problem kinds, by name.
KINDS: Mapping[str, Kind] = MappingProxyType(
    {
        kind.name: kind
        for kind in (
            Kind("frictionless", "ContactProblem", "active-set"),
            Kind("frictional", "FrictionalProblem", "coulomb", _FRICTIONAL_DEFAULTS),
            Kind(
                "frictional-polygonal",
                "FrictionalProblem with facets",
                "polygonal",
                _FRICTIONAL_DEFAULTS,
                fixed=("facets",),
            ),
            Kind("local", "LocalProblem", "coulomb"),
            Kind("global", "GlobalProblem", "coulomb"),
            Kind("local-batch", "LocalBatch", "coulomb-batch"),
            Kind("fastened", "FastenedProblem", "lawson-hanson"),
            Kind("surface", "SurfaceProblem", "constrained-cg"),
            Kind("sliding-surface", "SlidingSurfaceProblem", "tangential-fista"),
        )
    }
)

#: The modules each extra brings that methods need (what :func:`is_installed` looks for).
EXTRA_MODULES: Mapping[str, tuple[str, ...]] = _frozen(qp=("qpsolvers", "clarabel"))


def get_kind(name: str) -> Kind:
    """The :class:`Kind` called ``name``."""
    try:
        return KINDS[name]
    except (KeyError, TypeError):
        raise InvalidInputError(
            f"unknown problem kind {name!r}; kinds: {', '.join(KINDS)}"
        ) from None


def kind_of(problem) -> str:
    """The kind of ``problem`` (its ``kind`` attribute), checked."""
    kind = getattr(problem, "kind", None)
    if not isinstance(kind, str) or kind not in KINDS:
        raise InvalidInputError(
            f"cannot solve a {type(problem).__name__}: give one of "
            f"{', '.join(dict.fromkeys(k.problem.split()[0] for k in KINDS.values()))}"
        )
    return kind


def methods_for(kind: str) -> tuple[Method, ...]:
    """The methods that solve problems of ``kind``, the default first."""
    default = get_kind(kind).default
    fitting = [m for m in METHODS.values() if kind in m.kinds]
    return tuple(sorted(fitting, key=lambda m: m.name != default))


def default_method(kind: str) -> str:
    """The name of the method used for ``kind`` when none is named."""
    return get_kind(kind).default


def _listing(kind: str) -> str:
    default = default_method(kind)
    return ", ".join(
        f"{m.name} (default)" if m.name == default else m.name for m in methods_for(kind)
    )


def get_method(name: str | None, kind: str | None = None) -> Method:
    """The method ``name`` (None: the default of ``kind``), checked to fit ``kind``.

    Raises
    ------
    InvalidInputError
        Unknown name, or a method that does not solve ``kind``; the message lists the methods
        for ``kind`` (every method when ``kind`` is None).
    """
    if name is None:
        if kind is None:
            raise InvalidInputError("name a method (or a problem kind for its default)")
        name = default_method(kind)
    where = f" for {kind} problems" if kind else ""
    if not isinstance(name, str) or name not in METHODS:
        listing = _listing(kind) if kind else ", ".join(METHODS)
        raise InvalidInputError(f"unknown method {name!r}{where}; choose one of {listing}")
    method = METHODS[name]
    if kind is not None and kind not in method.kinds:
        listing = _listing(kind)
        raise InvalidInputError(
            f"method {name!r} does not solve {kind} problems (it solves "
            f"{', '.join(method.kinds)}); methods for {kind} problems: {listing}"
        )
    return method


def method_options(name: str | None, kind: str) -> dict[str, object]:
    """``{option: default}`` of method ``name`` on ``kind``: the kind's defaults applied, the
    options the problem sets (:attr:`Kind.fixed`) left out."""
    method, spec = get_method(name, kind), get_kind(kind)
    return {
        option.name: spec.defaults.get(option.name, option.default)
        for option in method.options
        if option.name not in spec.fixed
    }


def check_options(method: Method, kind: str, options: Mapping) -> None:
    """Raise :class:`InvalidInputError` naming any of ``options`` that ``method`` does not
    take on ``kind`` (backend settings pass for methods that hand them on)."""
    spec = get_kind(kind)
    for name in options:
        if name in spec.fixed:
            raise InvalidInputError(
                f"option {name!r} is set by the {spec.problem} itself, not given to {method.name!r}"
            )
        if name not in method.option_names and not method.backend_settings:
            valid = ", ".join(n for n in method.option_names if n not in spec.fixed) or "none"
            raise InvalidInputError(
                f"unknown option {name!r} for method {method.name!r}; its options: {valid}"
            )


def is_installed(name: str) -> bool:
    """True when the optional modules method ``name`` needs can be imported here."""
    method = get_method(name)
    modules = EXTRA_MODULES.get(method.extra, ()) if method.extra else ()
    return all(importlib.util.find_spec(module) is not None for module in modules)

"""Certificates: an answer checked independently of the method that found it.

:func:`certify` judges a frictionless answer (:class:`Certificate`), :func:`certify_friction`
one with friction (:class:`FrictionCertificate`); :class:`LocalCertificate` holds the
natural-map check of an FCLIB answer. Every residual is computed from the problem's own data and
the returned displacements and forces, never from a method's internal quantities.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .local_problem import CONTACT_FLOOR, AccuracyLimits, cone_residual
from .operators import symmetric_product

__all__ = [
    "CERTIFICATE_TOL",
    "Certificate",
    "certify",
    "FrictionCertificate",
    "certify_friction",
    "LocalCertificate",
    "scales",
    "contact_scales",
]


#: Default largest accepted relative residual of a certificate.
CERTIFICATE_TOL = 1e-7


@dataclass(frozen=True)
class Certificate:
    """Residuals of the contact conditions, each relative to the problem's scale.

    Computed from the model's own matrix, the constraints and the returned displacements and
    forces, never from the solver's internal quantities, so that a wrong answer cannot look right.

    Attributes
    ----------
    penetration : float
        ``max(A U - Delta, 0)`` over each contact's length scale: the largest of its ``|A U|``,
        ``|Delta|`` and ``|A R P|`` (at least
        :data:`~contactqp.core.local_problem.CONTACT_FLOOR` times
        the largest over the contacts).
    force_sign : float
        ``max(-lambda, 0)`` over the force scale (contact forces push, never pull).
    complementarity : float
        ``max |lambda_i (Delta - A U)_i|`` over the force scale times the contact's length
        scale.
    equilibrium : float
        ``max |U - R (P - A^T lambda)|`` over the length scale (or ``K U`` against the forces over
        the force scale when the model was given by its stiffness).
    tol : float
        The tolerance ``passed`` compares each residual with.
    """

    penetration: float
    force_sign: float
    complementarity: float
    equilibrium: float
    tol: float = CERTIFICATE_TOL

    @property
    def worst(self) -> float:
        """The largest of the four residuals (inf when the answer holds NaN or inf)."""
        return max(self.penetration, self.force_sign, self.complementarity, self.equilibrium)

    @property
    def passed(self) -> bool:
        """True when every residual is within ``tol``."""
        return bool(self.worst <= self.tol)

    @property
    def finite(self) -> bool:
        """False when the answer or a residual overflowed, or holds NaN."""
        return bool(np.isfinite(self.worst))

    def as_dict(self) -> dict:
        """Plain dictionary (for JSON)."""
        return {
            "penetration": self.penetration,
            "force_sign": self.force_sign,
            "complementarity": self.complementarity,
            "equilibrium": self.equilibrium,
            "tol": self.tol,
            "passed": self.passed,
        }


def certify(problem, displacements, forces, tol: float = CERTIFICATE_TOL) -> Certificate:
    """Check displacements and contact forces against a :class:`~contactqp.ContactProblem`.

    Parameters
    ----------
    problem : ContactProblem
    displacements : ndarray, shape (n_freedoms,)
        ``U`` in metres.
    forces : ndarray, shape (n_constraints,)
        Contact force magnitudes ``lambda`` in newtons (the force on the body is ``-A^T lambda``).
    tol : float

    Every residual is inf when ``U`` or ``lambda`` holds NaN or inf, or a residual overflows.
    """
    with np.errstate(all="ignore"):  # an overflow shows as an infinite residual
        return _certify(
            problem, np.asarray(displacements, dtype=float), np.asarray(forces, dtype=float), tol
        )


def _certify(problem, U, lam, tol) -> Certificate:
    if not (np.all(np.isfinite(U)) and np.all(np.isfinite(lam))):
        return Certificate(np.inf, np.inf, np.inf, np.inf, tol)
    A, gaps, P = problem.constraints.matrix, problem.constraints.gaps, problem.loads
    force, length = scales(problem.model, P, U, lam, gaps)
    AU = A @ U
    final_gaps = gaps - AU
    free = problem.free_displacements()
    # gaps are judged on each contact's own length: its displacement, initial gap and the
    # interpenetration the loads alone would cause there (not max diag(R) times the largest
    # force, which a soft freedom away from the contacts makes metres long, nor another
    # contact's wide gap)
    contact_length = _floored(np.maximum.reduce([np.abs(AU), np.abs(gaps), np.abs(A @ free)]))
    return Certificate(
        penetration=_worst(-final_gaps / contact_length),
        force_sign=_worst(-lam / force),
        complementarity=_worst(np.abs(lam * final_gaps) / (force * contact_length)),
        equilibrium=_equilibrium(problem.model, U, P - A.T @ lam, force, length),
        tol=tol,
    )


def scales(model, loads, displacements, forces, gaps) -> tuple[float, float]:
    """``(force, length)``: the scales (N, m) that make a certificate's residuals relative.

    The force scale is the largest load or contact force; the length scale the largest
    displacement or gap, or the displacement the force scale would cause, which keeps it
    meaningful when gaps and displacements are both (near) zero, e.g. a closed contact with zero
    initial gap.
    """
    tiny = np.finfo(float).tiny
    force = max(np.max(np.abs(loads), initial=0.0), np.max(np.abs(forces), initial=0.0), tiny)
    compliance = (
        np.max(np.diag(model.flexibility))
        if model.given == "flexibility"
        else 1.0 / np.max(np.diag(model.stiffness))
    )
    length = max(
        np.max(np.abs(displacements), initial=0.0),
        np.max(np.abs(gaps), initial=0.0),
        compliance * force,
        tiny,
    )
    return float(force), float(length)


def contact_scales(problem, local_displacements, forces, step) -> tuple[float, np.ndarray]:
    """``(force, length)``: the force scale (N) of the contacts and each one's length scale (m).

    Measured on the contacts only, so that a soft or heavily loaded freedom away from them does
    not loosen the contact checks (nor turn real slips into "stick"). The force scale is the
    largest local contact force, tensile strength ``c / mu`` or ``max |q~ - w| / max diag(W)``
    (the force that takes up the largest local displacement the loads cause, initial gaps ``w``
    left out, at the softest contact): one figure for all contacts, since whether a force is
    zero is a question about the whole problem's forces (an open contact's force is the
    solver's rounding of them). Never ``max diag(R)`` times a force, which mixes the softest
    freedom with the largest load, nor the largest load, which may not reach the contacts.

    The length scale is each contact's own: the largest of its local displacement ``H U``,
    initial gap and local displacement the loads cause with the apex forces applied (``q~``,
    :attr:`~contactqp.core.problem.FrictionStep.q_apex`), so that another contact's wide gap does
    not loosen its gap checks; at least
    :data:`~contactqp.core.local_problem.CONTACT_FLOOR` times the
    largest over the contacts.

    Parameters
    ----------
    problem : FrictionalProblem
    local_displacements : ndarray, shape (k, d)
        ``H U`` (m).
    forces : ndarray, shape (d k,) or (k, d)
        Local forces ``r`` (N).
    step : FrictionStep
        The step (:meth:`~contactqp.FrictionalProblem.step`).
    """
    k, d = problem.n_contacts, problem.dim
    free = step.q_apex.reshape(k, d)
    compliance = step.compliance
    # the floor left when no contact carries force: what the loads (and the previous state)
    # do at the contacts, without the initial gaps (a 1 m gap is no force of 1 m / W)
    loaded = step.q_apex - problem.local().offset
    force = max(
        np.max(np.abs(forces), initial=0.0),
        np.max(step.apex_shift, initial=0.0),
        np.max(np.abs(loaded), initial=0.0) / compliance if compliance > 0 else 0.0,
        np.finfo(float).tiny,
    )
    length = np.maximum.reduce(
        [
            np.abs(free).max(axis=1),
            np.abs(local_displacements).max(axis=1),
            np.abs(problem.constraints.gaps),
        ]
    )
    return float(force), _floored(length)


def _floored(scale):
    """``scale`` raised to :data:`~contactqp.core.local_problem.CONTACT_FLOOR` times its largest
    value."""
    tiny = np.finfo(float).tiny
    return np.maximum(scale, max(CONTACT_FLOOR * float(np.max(scale, initial=0.0)), tiny))


def _product_on_support(model, forces: np.ndarray) -> np.ndarray:
    """``R f`` with ``R`` the flexibility as given, read only where ``f`` is nonzero when that is
    a small part of it: rows of ``R`` (contiguous) when it is the symmetric matrix stored,
    else its columns; otherwise all of ``R``, one triangle of the symmetric one."""
    given = model.as_given
    symmetric = given is model.flexibility  # the validated, exactly symmetric matrix
    support = np.flatnonzero(forces)
    if 4 * support.size >= forces.size:
        return symmetric_product(given, forces) if symmetric else given @ forces
    if symmetric:  # R[:, s] = R[s].T
        return forces[support] @ given[support]
    return given[:, support] @ forces[support]


def _equilibrium(model, displacements, net_load, force: float, length: float) -> float:
    """``max|U - R f| / length`` (or ``max|K U - f| / force`` for a stiffness model).

    ``R`` (``K``) is the matrix as the user gave it (:attr:`~contactqp.ReducedModel.as_given`),
    not its symmetric part, which the solvers use.
    """
    if model.given == "flexibility":
        residual = displacements - _product_on_support(model, net_load)
        return _worst(np.abs(residual) / length)
    return _worst(np.abs(model.as_given @ displacements - net_load) / force)


@dataclass(frozen=True)
class FrictionCertificate:
    """Residuals of the frictional contact conditions, each relative to the problem's scale.

    Computed from the model's own matrix, the local frames and the returned displacements and
    forces (see :func:`certify_friction`), never from the solver's internal quantities. The
    contact residuals are relative to the contacts' force scale and to each contact's own
    length scale (:func:`contact_scales`), the largest over the contacts kept; the equilibrium
    is relative to the model's scales (:func:`scales`).

    Attributes
    ----------
    penetration : float
        ``max(-gap_i, 0)`` over the contact's length scale.
    force_sign : float
        ``max(-r~_N, 0)`` over the force scale, ``r~`` the force from the cone's apex.
    cone : float
        Largest excess of a tangential force over its friction set (disc or polygon of radius
        ``mu r_N + c``), over the force scale.
    complementarity : float
        ``max ||r~_i|| |gap_i|`` over the force scale times the contact's length: an open
        contact carries no force (beyond the tension ``c / mu`` of a cohesive one).
    dissipation : float
        Largest maximum-dissipation gap ``(mu r_N + c) support(-s_T) + r_T . s_T`` over the
        force scale times the contact's length: zero when every slip is opposed by a friction
        force on the bound.
    equilibrium : float
        ``max |U - R (P + H^T r)|`` over the model's length scale (``K U`` against the forces
        over its force scale for a stiffness model).
    natural_map : float
        :func:`~contactqp.core.local_problem.natural_map_error` of the step's dimensionless
        FCLIB problem
        (:attr:`~contactqp.core.problem.FrictionStep.fclib`, exact cones), each contact also on its
        own scale (``per_contact=True``). For a polygonal law it measures the distance the
        linearisation puts between the answer and the Coulomb one.
    exact_cone : bool
        True for the exact cone, or any cone in 2-D (where the polygonal law is exact):
        ``natural_map`` is then one of the checked residuals.
    tol : float
    """

    penetration: float
    force_sign: float
    cone: float
    complementarity: float
    dissipation: float
    equilibrium: float
    natural_map: float
    exact_cone: bool
    tol: float = CERTIFICATE_TOL

    @property
    def finite(self) -> bool:
        """False when the answer or a residual overflowed, or holds NaN."""
        return bool(np.isfinite(self.worst))

    @property
    def worst(self) -> float:
        """The largest checked residual (inf when the answer holds NaN or inf)."""
        checked = [
            self.penetration,
            self.force_sign,
            self.cone,
            self.complementarity,
            self.dissipation,
            self.equilibrium,
        ]
        return max(checked + [self.natural_map] * self.exact_cone)

    @property
    def passed(self) -> bool:
        """True when every checked residual is within ``tol``."""
        return bool(self.worst <= self.tol)

    def as_dict(self) -> dict:
        """Plain dictionary (for JSON)."""
        return {
            "penetration": self.penetration,
            "force_sign": self.force_sign,
            "cone": self.cone,
            "complementarity": self.complementarity,
            "dissipation": self.dissipation,
            "equilibrium": self.equilibrium,
            "natural_map": self.natural_map,
            "exact_cone": self.exact_cone,
            "tol": self.tol,
            "passed": self.passed,
        }


def certify_friction(
    problem, displacements, forces, step, tol: float = CERTIFICATE_TOL
) -> FrictionCertificate:
    """Check displacements and local forces against a :class:`~contactqp.FrictionalProblem`.

    Parameters
    ----------
    problem : FrictionalProblem
    displacements : ndarray, shape (n_freedoms,)
        ``U`` (m).
    forces : ndarray, shape (d k,)
        Local forces ``r`` (N), normal first per contact; the force on the body is ``H^T r``.
    step : FrictionStep
        The step (:meth:`~contactqp.FrictionalProblem.step`); its tangential displacements are
        the origin of the slip increments.
    tol : float

    Every residual is inf when ``U`` or ``r`` holds NaN or inf, or a residual overflows.
    """
    with np.errstate(all="ignore"):  # an overflow shows as an infinite residual
        return _certify_friction(
            problem,
            np.asarray(displacements, dtype=float),
            np.asarray(forces, dtype=float),
            step,
            tol,
        )


def _certify_friction(problem, U, r, step, tol) -> FrictionCertificate:
    if not (np.all(np.isfinite(U)) and np.all(np.isfinite(r))):
        return FrictionCertificate(
            penetration=np.inf,
            force_sign=np.inf,
            cone=np.inf,
            complementarity=np.inf,
            dissipation=np.inf,
            equilibrium=np.inf,
            natural_map=np.inf,
            exact_cone=problem.law.facets is None or problem.dim == 2,
            tol=tol,
        )
    k, d = problem.n_contacts, problem.dim
    R = r.reshape(k, d)
    H, gaps, P, law = problem.frames.operator, problem.constraints.gaps, problem.loads, problem.law
    HU = (H @ U).reshape(k, d)
    final_gaps = gaps + HU[:, 0]
    slip = HU[:, 1:] - step.tangential
    apex = law.apex_forces(R)
    force, length = contact_scales(problem, HU, r, step)
    # the equilibrium of every freedom is measured on the model's own scales
    global_force, global_length = scales(problem.model, P, U, r, gaps)
    return FrictionCertificate(
        penetration=_worst(-final_gaps / length),
        force_sign=_worst(-apex[:, 0] / force),
        cone=_worst(law.cone_excess(R) / force),
        complementarity=_worst(
            np.linalg.norm(apex, axis=1) * np.abs(final_gaps) / (force * length)
        ),
        dissipation=_worst(np.abs(law.dissipation_gap(R, slip)) / (force * length)),
        equilibrium=_equilibrium(problem.model, U, P + H.T @ r, global_force, global_length),
        natural_map=_finite_or_inf(_fclib_natural_map(problem, step, r, HU)),
        exact_cone=law.facets is None or d == 2,  # in 2-D every polygon is the exact cone
        tol=tol,
    )


def _fclib_natural_map(problem, step, r: np.ndarray, HU: np.ndarray) -> float:
    """:func:`~contactqp.core.local_problem.natural_map_error` (``per_contact=True``) of the
    step's FCLIB problem at ``r~ = (r + apex_shift) / force_unit``, with its ``u~ = W~ r~ + q~``
    read from the displacements: ``u = W r + q = H U + w - (0, (H U_prev)_T)`` for
    ``U = R (P + H^T r)``, which the equilibrium residual checks, and ``u~ = u / L``. No ``W`` is
    formed (an assembly's stages are restricted forms whose ``W`` is gathered only on use)."""
    k, d = problem.n_contacts, problem.dim
    u = HU + problem.local().offset.reshape(k, d)
    u[:, 1:] -= step.tangential
    scaled = (r + step.apex_shift) / step.force_unit
    return cone_residual(
        step.q_apex / step.length,
        problem.law.mu,
        d,
        scaled,
        u.reshape(-1) / step.length,
        scaled,
        per_contact=True,
    )[1]


def _worst(relative) -> float:
    """The largest of per-contact relative residuals, 0 when none is positive, inf when one is
    NaN or inf."""
    relative = np.asarray(relative, dtype=float)
    if not np.all(np.isfinite(relative)):
        return np.inf
    return float(max(0.0, np.max(relative, initial=0.0)))


def _finite_or_inf(value: float) -> float:
    """``value``, or inf when it is NaN or inf."""
    return float(value) if np.isfinite(value) else np.inf


@dataclass(frozen=True)
class LocalCertificate:
    """The natural-map check of an FCLIB answer, computed from ``r`` alone.

    Attributes
    ----------
    natural_map : float
        :func:`~contactqp.core.local_problem.natural_map_error` of ``(r, u)``, ``u = W r + q``
        (of a global problem: ``u = H^T v + w`` with ``v`` solving ``M v = H r + f`` as
        written).
    equilibrium : float or None
        Relative residual of a global problem's ``M v = H r + f``; None for a local problem,
        which has no global equations.
    limits : AccuracyLimits
        How far rounding and the data's written digits limit ``natural_map``.
    tol : float
        The tolerance ``passed`` compares the residuals with (the method's target).
    """

    natural_map: float
    equilibrium: float | None
    limits: AccuracyLimits
    tol: float

    @property
    def worst(self) -> float:
        """The largest residual (inf when one is NaN or inf)."""
        values = [self.natural_map] + ([] if self.equilibrium is None else [self.equilibrium])
        return max(_finite_or_inf(value) for value in values)

    @property
    def passed(self) -> bool:
        """True when every residual is within ``tol``."""
        return bool(self.worst <= self.tol)

    @property
    def finite(self) -> bool:
        """False when the answer or a residual overflowed, or holds NaN."""
        return bool(np.isfinite(self.worst))

    def as_dict(self) -> dict:
        """Plain dictionary (for JSON): the residuals, ``tol``, ``passed`` and the limits'
        ``attainable``, ``data_limit``, ``condition`` and ``digits``."""
        return {
            "natural_map": self.natural_map,
            "equilibrium": self.equilibrium,
            "tol": self.tol,
            "passed": self.passed,
            **self.limits.as_dict(),
        }

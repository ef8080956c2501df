"""A rigid indenter pressed on an elastic surface, then shifted tangentially: partial slip.

A :class:`SlidingSurfaceProblem` adds a tangential step to a frictionless
:class:`~contactqp.core.surface.SurfaceProblem`: the indenter, pressed as that problem says, is
shifted rigidly by ``delta_T = (delta_x, delta_y)`` (m) along the surface (given, or found so
that the tangential forces add up to a given ``Q``), and each point ``i``
in contact carries a tangential force ``t_i`` (N, on the elastic body) with Coulomb's law of
friction ``mu_i`` on its normal force ``p_i``. With ``W`` the *full* compliance of the surface
(three entries per point, ``(x, y, z)`` as :func:`~contactqp.compliance.influence_matrix`
orders them, ``z`` the outward normal) and the slip of the surface against the indenter
``w_i = (W f)_{T,i} - delta_T``, ``f`` the forces ``(t_x, t_y, -p)`` per point:

.. math::

    |t_i| \\le \\mu_i p_i, \\qquad
    |t_i| < \\mu_i p_i \\Rightarrow w_i = 0 \\ \\text{(stick)}, \\qquad
    w_i \\ne 0 \\Rightarrow t_i = -\\mu_i p_i\\, w_i / |w_i| \\ \\text{(slip)}.

Coupling: when the normal and tangential problems decouple (no ``(1 - 2 nu)`` terms in ``W``:
elastically similar bodies, an incompressible body, or
:class:`~contactqp.compliance.fft_halfspace.HalfSpaceOperator` with ``coupling=False``), the
normal forces are those of the frictionless problem whatever the shear, the tangential problem
is Tresca's with the bound ``mu p``, and its answer is exactly Coulomb's. With a coupled ``W``
(``coupling=True``, a rigid indenter on one elastic body of ``nu < 1/2``) the tangential forces
move the surface normally and the normal forces move it tangentially: the gap and the slip
above are then those of the full product ``W f``, and the method solves the normal and the
tangential problems in turn until they agree.

Periodic surfaces (one period of a rough surface, ``periodic=True`` operators): the mean
tangential displacement of a periodic half-space under a net shear is free, as its mean
normal one is under a net load, so a periodic problem gives the tangential ``force`` (and its
surface the load); the shift is then the unknown that balances it, the tangential compliance
of the interface beyond the bulk's.

Load history: the shift is measured from the unloaded state, and the problem is one
increment of the law from the state ``previous`` (its slips ``w``; by default the unloaded
state): Coulomb's law acts on ``w - w_previous``, the slip of this increment, the tractions
being the total ones. One increment from the unloaded state is the answer of a pressing and a
shift growing together in proportion (without coupling, of a press followed by a monotonic
shear, as in Cattaneo and Mindlin's theory: each point's slip keeps its direction; with
coupling at zero shift, Spence's self-similar frictional indentation). A chain of increments,
each from the one before (:func:`~contactqp.methods.tangential_fista.shear_history`), follows
any path: a press then a shear with coupling, an unloading or a reversed shear
(Mindlin-Deresiewicz's hysteresis); its accuracy is that of the increments taken.

:func:`certify_sliding` judges an answer through one product of ``W`` with the returned forces
(:class:`SlidingCertificate`): the frictionless residuals of
:func:`~contactqp.core.surface.certify_surface`, the cone, stick, slip alignment and the
natural-map error of the whole (normal and tangential) Coulomb problem, measured as the dense
route measures it (:func:`~contactqp.core.local_problem.natural_map_error`, per contact, in the
dimensionless units of the dense Cattaneo-Mindlin example).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInputError
from .certificate import CERTIFICATE_TOL
from .local_problem import CONTACT_FLOOR, projection_on_cones
from .model import finite_array, positive_tolerance
from .operators import Operator, as_operator
from .result import ContactResult, verdict
from .status import ContactStatus
from .surface import SurfaceProblem

__all__ = [
    "SlidingSurfaceProblem",
    "SlidingCertificate",
    "SlidingSurfaceResult",
    "certify_sliding",
    "SLIP_RTOL",
]

#: A point in contact slips (:attr:`SlidingSurfaceResult.contact_status`) when its slip exceeds
#: this fraction of the certificate's length scale, the rule of the dense route's statuses.
SLIP_RTOL = 1e-6


class SlidingSurfaceProblem:
    """A pressed indenter shifted tangentially: partial or full slip with Coulomb friction.

    Parameters
    ----------
    surface : SurfaceProblem
        The frictionless normal problem (its compliance the normal one, ``m x m``; its load or
        approach the pressing).
    compliance : Operator, ndarray or scipy.sparse matrix, shape (3 m, 3 m)
        The full compliance ``W`` (m/N), three entries per point in ``(x, y, z)`` order (e.g.
        ``HalfSpaceOperator(..., components="full")``, coupled or with ``coupling=False``); its
        ``zz`` entries are ``surface.compliance``. Reached through products only.
    mu : float or array_like, shape (m,)
        Friction coefficient(s), finite and >= 0.
    shift : array_like, shape (2,), optional
        Rigid tangential displacement ``(delta_x, delta_y)`` of the indenter (m), from the
        unloaded state (see the module notes); the total tangential force is then an
        unknown.
    force : array_like, shape (2,), optional
        Total tangential force ``Q = (Q_x, Q_y)`` on the surface (N), below the friction limit
        ``sum mu_i p_i``; the shift is then an unknown. Exactly one of ``shift`` and ``force``.
    previous : SlidingSurfaceResult or array_like of shape (m, 2), optional
        The state this increment starts from: its slips ``w`` (m; a result's ``slips``).
        Coulomb's law then acts on the slip of this increment, ``w - w_previous``, as in a load
        history (see the module notes). Default: the unloaded state (zero).
    certificate_tol : float
        Largest relative residual the certificate accepts.

    Attributes
    ----------
    kind : str
        ``"sliding-surface"``.
    surface : SurfaceProblem
    compliance : Operator
    mu : ndarray, shape (m,)
    shift, force : ndarray, shape (2,), or None
        The one given; the other is None.
    fixed : {"shift", "force"}
    previous_slips : ndarray, shape (m, 2)
        The slips of the state the increment starts from (zero: the unloaded state).
    certificate_tol : float

    Raises
    ------
    InvalidInputError
        ``surface`` not a SurfaceProblem, a compliance not of shape (3 m, 3 m), ``mu`` negative,
        not finite or of the wrong size, not exactly one of ``shift`` and ``force``, either not
        two finite numbers, a periodic compliance with a shift (its mean tangential
        displacement is free: give the force), or one periodic and one non-periodic compliance.
    """

    kind = "sliding-surface"

    def __init__(
        self,
        surface: SurfaceProblem,
        compliance,
        mu,
        *,
        shift=None,
        force=None,
        previous=None,
        certificate_tol: float = CERTIFICATE_TOL,
    ):
        if not isinstance(surface, SurfaceProblem):
            raise InvalidInputError(
                f"surface must be a SurfaceProblem, got {type(surface).__name__}"
            )
        m = surface.size
        operator = as_operator(compliance)
        if operator.shape != (3 * m, 3 * m):
            raise InvalidInputError(
                f"compliance must have shape ({3 * m}, {3 * m}) (x, y, z per point of the "
                f"surface), got {operator.shape}"
            )
        periodic = getattr(operator, "periodic", False)
        if periodic != getattr(surface.compliance, "periodic", False):
            raise InvalidInputError(
                "compliance and surface.compliance must be both periodic or both not"
            )
        if periodic and shift is not None:
            raise InvalidInputError(
                "shift: a periodic compliance has no stiffness against a uniform shift; "
                "give the tangential force instead"
            )
        mu_arr = np.asarray(mu, dtype=float) if np.ndim(mu) else np.full(m, float(mu))
        mu_arr = finite_array(mu_arr, "mu", 1)
        if mu_arr.shape != (m,) or np.any(mu_arr < 0):
            raise InvalidInputError(
                f"mu must be a number >= 0 or an array of {m} numbers >= 0, got {mu!r}"
            )
        if (shift is None) == (force is None):
            raise InvalidInputError(
                "give exactly one of shift (m) and force (total tangential force, N), "
                f"got {'both' if shift is not None else 'neither'}"
            )
        given, name, what = (shift, "shift", "(delta_x, delta_y) in m")
        if force is not None:
            given, name, what = (force, "force", "(Q_x, Q_y) in N")
        value = finite_array(given, name, 1)
        if value.shape != (2,):
            raise InvalidInputError(f"{name} must be {what}, got {given!r}")
        self.surface = surface
        self.compliance: Operator = operator
        self.mu: np.ndarray = mu_arr
        self.shift: np.ndarray | None = value if force is None else None
        self.force: np.ndarray | None = value if force is not None else None
        self.fixed = "shift" if force is None else "force"
        self.previous_slips = _previous_slips(previous, m)
        self.certificate_tol = positive_tolerance(certificate_tol, "certificate_tol")

    @property
    def size(self) -> int:
        """Number of surface points ``m``."""
        return self.surface.size

    def full_forces(self, tangential: np.ndarray, normal: np.ndarray) -> np.ndarray:
        """The ``(3 m,)`` force vector ``(t_x, t_y, -p)`` per point, in ``W``'s layout."""
        f = np.empty((self.size, 3))
        f[:, :2] = tangential
        f[:, 2] = -normal
        return f.ravel()

    def make_result(
        self,
        tangential,
        normal,
        approach: float,
        shift,
        *,
        method: str,
        converged: bool,
        message: str,
        iterations: int,
        seconds: float,
        info: dict | None = None,
    ) -> SlidingSurfaceResult:
        """Wrap a method's tangential forces ``(m, 2)``, normal forces ``(m,)`` (N), approach
        (m) and shift ``(2,)`` (m; the given one at a fixed shift) in a certified
        :class:`SlidingSurfaceResult` (one product ``W f``)."""
        t = np.asarray(tangential, dtype=float).reshape(self.size, 2)
        p = np.asarray(normal, dtype=float)
        with np.errstate(all="ignore"):
            f = self.full_forces(t, p)
            u = np.asarray(self.compliance @ f, dtype=float)
            delta = np.asarray(shift, dtype=float)
            certificate, slips, gaps, length = _certify(self, t, p, approach, delta, u)
        status, success, message = verdict(converged, certificate, message)
        peak = float(np.max(np.abs(p), initial=0.0))
        closed = p > 1e-10 * peak
        step = slips - self.previous_slips  # the law acts on this increment's slip
        slipping = np.hypot(step[:, 0], step[:, 1]) > SLIP_RTOL * length
        codes = np.where(
            closed,
            np.where(slipping, ContactStatus.SLIP, ContactStatus.STICK),
            ContactStatus.OPEN,
        )
        forces = np.column_stack([p, t])  # normal first, as the frictional results
        return SlidingSurfaceResult(
            displacements=u,
            forces=forces,
            nodal_forces=f,
            gaps=gaps,
            contact_status=codes,
            energy=0.5 * float(f @ u),
            success=success,
            status=status,
            message=message,
            iterations=int(iterations),
            seconds=float(seconds),
            method=method,
            certificate=certificate,
            info=dict(info or {}),
            approach=float(approach),
            load=float(np.sum(p)),
            shift=delta.copy(),
            tangential_force=t.sum(axis=0),
            slips=slips,
        )

    def __repr__(self) -> str:
        given = np.asarray(self.shift if self.force is None else self.force)
        return (
            f"SlidingSurfaceProblem({type(self.compliance).__name__}, {self.size} points, "
            f"{self.fixed}={tuple(float(v) for v in given)!r})"
        )


def _previous_slips(previous, m: int) -> np.ndarray:
    """The previous state's slips, (m, 2), from a result, an array or None (zeros)."""
    if previous is None:
        return np.zeros((m, 2))
    slips = previous.slips if isinstance(previous, SlidingSurfaceResult) else previous
    value = finite_array(np.asarray(slips, dtype=float), "previous", 2)
    if value.shape != (m, 2):
        raise InvalidInputError(
            f"previous: the slips of the state before must have shape ({m}, 2), got {value.shape}"
        )
    return value


@dataclass(frozen=True)
class SlidingCertificate:
    """The check of a partial-slip answer, from one product ``W f``.

    Residuals are relative to the force scale ``F = max p`` and the length scale ``L`` of
    :func:`~contactqp.core.surface.certify_surface` (with the shift's length as well).

    Attributes
    ----------
    penetration, force_sign, complementarity : float
        The frictionless residuals.
    equilibrium : float
        The load balances: ``|sum p - P| / P`` at a fixed load, ``|sum t - Q| / max(|Q|, F)``
        at a fixed tangential force (the larger of the two).
    cone : float
        ``max(|t_i| - mu_i p_i, 0) / F``.
    stick : float
        ``max |w_i| (mu_i p_i - |t_i|)_+ / (F L)``: no slip where the force is inside the cone.
    alignment : float
        ``max | |w_i| t_i + mu_i p_i w_i | / (F L)``: a slipping point's force opposes its slip
        at the cone's bound (0 also where ``w_i = 0``).
    natural_map : float
        The dense route's measure (:func:`~contactqp.core.local_problem.natural_map_error`,
        per contact) of the whole Coulomb problem, forces in units of ``L / W_max`` and
        displacements in units of ``L``.
    tol : float
    """

    penetration: float
    force_sign: float
    complementarity: float
    equilibrium: float
    cone: float
    stick: float
    alignment: float
    natural_map: float
    tol: float

    def _values(self) -> list[float]:
        return [
            self.penetration,
            self.force_sign,
            self.complementarity,
            self.equilibrium,
            self.cone,
            self.stick,
            self.alignment,
            self.natural_map,
        ]

    @property
    def worst(self) -> float:
        """The largest residual (inf when one is NaN or inf)."""
        return max(v if np.isfinite(v) else np.inf for v in self._values())

    @property
    def passed(self) -> bool:
        """True when every residual is within ``tol``."""
        return bool(self.worst <= self.tol)

    @property
    def finite(self) -> bool:
        """False when the answer or a residual overflowed, or holds NaN."""
        return bool(np.isfinite(self.worst))

    def as_dict(self) -> dict:
        """Plain dictionary (for JSON): the residuals, ``tol`` and ``passed``."""
        names = (
            "penetration",
            "force_sign",
            "complementarity",
            "equilibrium",
            "cone",
            "stick",
            "alignment",
            "natural_map",
        )
        return {
            **dict(zip(names, self._values(), strict=True)),
            "tol": self.tol,
            "passed": self.passed,
        }


def certify_sliding(
    problem: SlidingSurfaceProblem, tangential, normal, approach: float, shift=None
) -> SlidingCertificate:
    """Check tangential forces ``(m, 2)``, normal forces ``(m,)`` (N), an approach (m) and a
    shift ``(2,)`` (m; default the problem's, which a fixed force requires) against a
    :class:`SlidingSurfaceProblem`, through one product ``W f``."""
    t = np.asarray(tangential, dtype=float).reshape(problem.size, 2)
    p = np.asarray(normal, dtype=float)
    if p.shape != (problem.size,):
        raise InvalidInputError(f"normal must have shape ({problem.size},), got {p.shape}")
    with np.errstate(all="ignore"):
        u = np.asarray(problem.compliance @ problem.full_forces(t, p), dtype=float)
        delta = problem.shift if shift is None else finite_array(shift, "shift", 1)
        if delta is None or delta.shape != (2,):
            raise InvalidInputError("shift must be (delta_x, delta_y) in m")
        return _certify(problem, t, p, approach, delta, u)[0]


def _certify(problem, t, p, approach, shift, u):
    """``(certificate, slips (m, 2), gaps (m,), length)`` of forces and their product ``u``."""
    tol = problem.certificate_tol
    surface = problem.surface
    inf = np.inf
    U = u.reshape(-1, 3)
    slips = U[:, :2] - shift
    gaps = surface.gaps(-U[:, 2], approach)  # the normal forces sink the surface along -z
    finite = np.all(np.isfinite(t)) and np.all(np.isfinite(p)) and np.isfinite(approach)
    if not (finite and np.all(np.isfinite(u)) and np.all(np.isfinite(shift))):
        nan = SlidingCertificate(inf, inf, inf, inf, inf, inf, inf, inf, tol)
        return nan, slips, gaps, 1.0
    tiny = np.finfo(float).tiny
    force = max(float(np.max(np.abs(p))), tiny)
    length = max(
        float(np.max(np.abs(u))),
        abs(approach - float(np.min(surface.separation))),
        float(np.hypot(*shift)),
        tiny,
    )
    bound = problem.mu * p
    size = np.hypot(t[:, 0], t[:, 1])
    step = slips - problem.previous_slips  # the law acts on this increment's slip
    slip = np.hypot(step[:, 0], step[:, 1])
    balance = 0.0
    if surface.load is not None:
        balance = abs(float(np.sum(p)) - surface.load) / surface.load
    if problem.force is not None:
        Q = problem.force
        miss = float(np.hypot(*(t.sum(axis=0) - Q)))
        balance = max(balance, miss / max(float(np.hypot(*Q)), force))
    aligned = slip[:, None] * t + bound[:, None] * step
    certificate = SlidingCertificate(
        penetration=max(0.0, float(np.max(-gaps))) / length,
        force_sign=max(0.0, float(np.max(-p))) / force,
        complementarity=float(np.max(np.abs(p * gaps))) / (force * length),
        equilibrium=balance,
        cone=max(0.0, float(np.max(size - bound))) / force,
        stick=float(np.max(slip * np.maximum(bound - size, 0.0))) / (force * length),
        alignment=float(np.max(np.hypot(aligned[:, 0], aligned[:, 1]))) / (force * length),
        natural_map=_natural_map(problem, t, p, gaps, step, approach, shift, length),
        tol=tol,
    )
    return certificate, slips, gaps, length


def _natural_map(problem, t, p, gaps, slips, approach, shift, length) -> float:
    """The per-contact natural-map error of the dense route, in dimensionless units, of the
    increment's slips ``slips``."""
    scale_force = length / float(np.max(problem.compliance.diagonal()))
    r = np.column_stack([p, t]) / scale_force  # (N, T1, T2) per point
    v = np.column_stack([gaps, slips]) / length
    q = np.column_stack([problem.surface.separation - approach, -shift - problem.previous_slips])
    q = q / length
    mu = problem.mu
    shifted = v.copy()
    shifted[:, 0] += mu * np.hypot(v[:, 1], v[:, 2])
    projected = projection_on_cones((r - shifted).ravel(), mu, 3).reshape(-1, 3)
    rows = np.einsum("ij,ij->i", r - projected, r - projected)
    scale = math.sqrt(max(float(np.sum(q * q)), float(np.sum(r * r)), float(np.sum(v * v))))
    scale = scale or 1.0
    error = math.sqrt(float(np.sum(rows))) / scale
    own = np.maximum.reduce(
        [np.einsum("ij,ij->i", x, x) for x in (q, r, v)]  # each contact's own scale
    )
    floor = (CONTACT_FLOOR * scale) ** 2
    return max(error, math.sqrt(float(np.max(rows / np.maximum(own, floor)))))


@dataclass(kw_only=True, repr=False)
class SlidingSurfaceResult(ContactResult):
    """The answer to a :class:`SlidingSurfaceProblem`.

    ``forces`` are per point ``(p, t_x, t_y)`` (N, shape (m, 3), normal first as the frictional
    results), ``nodal_forces`` the vector ``(t_x, t_y, -p)`` per point in ``W``'s layout,
    ``displacements`` ``W`` times it (m), ``gaps`` the normal gaps (m), ``contact_status`` open,
    stick or slip (:data:`SLIP_RTOL`), ``energy`` the stored elastic energy (J), ``certificate``
    a :class:`SlidingCertificate`.

    Attributes
    ----------
    approach : float
        Normal approach of the indenter (m).
    load : float
        Total normal force (N).
    shift : ndarray, shape (2,)
        The indenter's tangential shift (m): the given one, or found.
    tangential_force : ndarray, shape (2,)
        Total tangential force ``Q`` on the surface (N).
    slips : ndarray, shape (m, 2)
        Slip of the surface against the indenter ``w`` (m).
    """

    STATUSES = (ContactStatus.OPEN, ContactStatus.STICK, ContactStatus.SLIP)

    approach: float
    load: float
    shift: np.ndarray
    tangential_force: np.ndarray
    slips: np.ndarray

    @property
    def stick(self) -> np.ndarray:
        """Bool mask of the sticking points, shape (m,)."""
        return np.asarray(self.contact_status == ContactStatus.STICK)

    @property
    def slip(self) -> np.ndarray:
        """Bool mask of the slipping points, shape (m,)."""
        return np.asarray(self.contact_status == ContactStatus.SLIP)

    def _summary_extra(self) -> dict:
        return {
            "approach": self.approach,
            "load": self.load,
            "shift": [float(v) for v in self.shift],
            "tangential_force": [float(v) for v in self.tangential_force],
        }

"""A rigid indenter on an elastic surface: the frictionless contact of a surface compliance.

A :class:`SurfaceProblem` holds the compliance ``W`` (m/N) of ``m`` surface points (cells of a
half-space, nodes of a finite-element face), their separation ``s`` (m) from a rigid indenter at
zero load and zero approach, and either the total load ``P`` (N) or the indenter's rigid-body
approach ``delta`` (m). A compressive force ``r_i >= 0`` on point ``i`` sinks the surface there
by ``(W r)_i``, so the gaps are

.. math::

    g = s - \\delta\\, \\mathbf{1} + W r, \\qquad 0 \\le r \\perp g \\ge 0,
    \\qquad \\textstyle\\sum_i r_i = P \\ \\text{(fixed load, } \\delta \\text{ unknown)}.

This is the frictionless problem of a reduced model whose contacts are all the surface points,
written for operators that never form ``W`` (an FFT half-space,
:class:`~contactqp.core.operators.Operator`): every method and the certificate reach ``W``
through products only. :func:`~contactqp.solve` solves it with ``constrained-cg`` (Polonsky and
Keer's constrained conjugate gradient, :mod:`contactqp.methods.constrained_cg`) by default.

:func:`certify_surface` judges an answer through one product ``W r`` of the returned forces
(:class:`~contactqp.core.certificate.Certificate`; its ``equilibrium`` is the load balance).
:class:`SurfaceResult` is the answer: a :class:`~contactqp.core.result.ContactResult` with the
approach, the load and the contact area.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInputError
from .certificate import CERTIFICATE_TOL, Certificate
from .model import finite_array, positive_tolerance
from .operators import Coarsening, Operator, as_operator
from .result import ContactResult, verdict
from .status import ContactStatus

__all__ = ["SurfaceProblem", "SurfaceResult", "certify_surface", "CONTACT_RTOL"]

#: A point is in contact (:attr:`SurfaceResult.contact`) when its force exceeds this fraction of
#: the largest force.
CONTACT_RTOL = 1e-10


def _finite_number(value, name: str, expected: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidInputError(f"{name} must be {expected}, got {value!r}")
    number = float(value)
    if not np.isfinite(number):
        raise InvalidInputError(f"{name} must be {expected}, got {value!r}")
    return number


class SurfaceProblem:
    """Frictionless contact of a rigid indenter with a surface of compliance ``W``.

    Parameters
    ----------
    compliance : Operator, ndarray or scipy.sparse matrix, shape (m, m)
        ``W`` (m/N), symmetric positive definite: ``(W r)_i`` is how far the forces ``r``
        (N, compressive positive) sink surface point ``i``. A matrix is wrapped by
        :func:`~contactqp.core.operators.as_operator`; an operator is used as it is (e.g.
        :class:`~contactqp.compliance.fft_halfspace.HalfSpaceOperator`, which never forms
        ``W``). Methods and the certificate use its products only.
    separation : array_like, shape (m,)
        ``s``: each point's gap to the indenter at zero load and zero approach (m), e.g.
        ``(x^2 + y^2) / (2 R)`` for a sphere of radius ``R``, or ``max(h) - h`` for a rigid flat
        on a rough surface of heights ``h``.
    load : float, optional
        Total compressive force ``P`` (N, > 0); the approach is then an unknown.
    approach : float, optional
        Rigid-body approach ``delta`` of the indenter (m); the load is then an unknown.
        Exactly one of ``load`` and ``approach`` is given.
    certificate_tol : float
        Largest relative residual the certificate accepts.

    Attributes
    ----------
    kind : str
        ``"surface"``.
    compliance : Operator
    separation : ndarray, shape (m,)
    load, approach : float or None
        The one given; the other is None.
    fixed : {"load", "approach"}
        Which of them is given.
    certificate_tol : float

    Raises
    ------
    InvalidInputError
        Not exactly one of ``load`` and ``approach``; a load that is not a positive finite
        number, an approach that is not finite or given with a periodic compliance (whose
        mean displacement is free: give the load); a separation that is not a finite 1-D array
        of the compliance's size; a compliance that is not a square matrix or operator.
    """

    kind = "surface"

    def __init__(
        self,
        compliance,
        separation,
        *,
        load: float | None = None,
        approach: float | None = None,
        certificate_tol: float = CERTIFICATE_TOL,
    ):
        if (load is None) == (approach is None):
            raise InvalidInputError(
                "give exactly one of load (total force, N) and approach (m), "
                f"got {'both' if load is not None else 'neither'}"
            )
        operator = as_operator(compliance)
        s = finite_array(separation, "separation", 1)
        m = operator.shape[0]
        if s.shape != (m,):
            raise InvalidInputError(
                f"separation must have shape ({m},) to match the compliance {operator.shape}, "
                f"got {s.shape}"
            )
        if m == 0:
            raise InvalidInputError("separation must hold at least one point, got shape (0,)")
        if load is not None:
            load = _finite_number(load, "load", "a positive finite force in N")
            if not load > 0.0:
                raise InvalidInputError(f"load must be a positive finite force in N, got {load!r}")
        if approach is not None:
            approach = _finite_number(approach, "approach", "a finite length in m")
            if getattr(operator, "periodic", False):
                raise InvalidInputError(
                    "approach: a periodic compliance has no stiffness against a uniform "
                    "approach (its mean displacement is free); give the load instead"
                )
        self.compliance: Operator = operator
        self.separation: np.ndarray = s
        self.load: float | None = load
        self.approach: float | None = approach
        self.fixed = "load" if load is not None else "approach"
        self.certificate_tol = positive_tolerance(certificate_tol, "certificate_tol")

    @property
    def size(self) -> int:
        """Number of surface points ``m``."""
        return int(self.separation.size)

    def coarsened(self) -> tuple[SurfaceProblem, Coarsening] | None:
        """The same problem on the compliance's coarser lattice
        (:meth:`~contactqp.core.operators.Operator.coarsening`: the separation averaged over
        the merged points, the same load or approach) and that coarsening, or None when the
        compliance has none."""
        coarsening = self.compliance.coarsening()
        if coarsening is None:
            return None
        coarse = SurfaceProblem(
            coarsening.operator,
            coarsening.restrict(self.separation),
            load=self.load,
            approach=self.approach,
        )
        return coarse, coarsening

    def gaps(self, displacements: np.ndarray, approach: float) -> np.ndarray:
        """``s - delta + u``: the gaps (m) for surface displacements ``u = W r`` (m)."""
        return self.separation - approach + displacements

    def make_result(
        self,
        forces,
        approach: float,
        *,
        method: str,
        converged: bool,
        message: str,
        iterations: int,
        seconds: float,
        info: dict | None = None,
    ) -> SurfaceResult:
        """Wrap a method's forces (N, shape (m,)) and approach (m) in a certified
        :class:`SurfaceResult`: the certificate's product ``W r`` gives the displacements and
        gaps reported. Forces or an approach holding NaN or inf fail the certificate."""
        r = np.asarray(forces, dtype=float)
        with np.errstate(all="ignore"):
            displacements = np.asarray(self.compliance @ r, dtype=float)
            certificate = certify_surface(self, r, approach, displacements)
            gaps = self.gaps(displacements, approach)
            energy = 0.5 * float(r @ displacements)
            peak = float(np.max(np.abs(r), initial=0.0))
        status, success, message = verdict(converged, certificate, message)
        closed = r > CONTACT_RTOL * peak
        return SurfaceResult(
            displacements=displacements,
            forces=r,
            nodal_forces=r,
            gaps=gaps,
            contact_status=np.where(closed, ContactStatus.CLOSED, ContactStatus.OPEN),
            energy=energy,
            success=success,
            status=status,
            message=message,
            iterations=int(iterations),
            seconds=float(seconds),
            method=method,
            certificate=certificate,
            info=dict(info or {}),
            approach=float(approach),
            load=float(np.sum(r)),
        )

    def __repr__(self) -> str:
        given = f"load={self.load!r}" if self.fixed == "load" else f"approach={self.approach!r}"
        return f"SurfaceProblem({type(self.compliance).__name__}, {self.size} points, {given})"


def certify_surface(
    problem: SurfaceProblem, forces, approach: float, displacements=None
) -> Certificate:
    """Check forces ``r`` (N) and an approach ``delta`` (m) against a :class:`SurfaceProblem`.

    One product ``u = W r`` (skipped when ``displacements`` gives it, as
    :meth:`SurfaceProblem.make_result` does with the product it reports) gives the gaps
    ``g = s - delta + u``; the residuals are relative to the force scale ``F = max r`` and the
    length scale ``L = max(max |u|, |delta - min s|)`` (the largest surface displacement, or the
    rigid interference of the indenter):

    * ``penetration``: ``max(-g, 0) / L``;
    * ``force_sign``: ``max(-r, 0) / F``;
    * ``complementarity``: ``max |r_i g_i| / (F L)``;
    * ``equilibrium``: the load balance ``|sum r - P| / P`` at a fixed load (0 at a fixed
      approach, where the load is whatever ``sum r`` is).

    Every residual is inf when ``r``, ``delta`` or ``u`` holds NaN or inf.
    """
    r = np.asarray(forces, dtype=float)
    tol = problem.certificate_tol
    if r.shape != problem.separation.shape:
        raise InvalidInputError(f"forces must have shape {problem.separation.shape}, got {r.shape}")
    infinite = Certificate(np.inf, np.inf, np.inf, np.inf, tol)
    if not (np.all(np.isfinite(r)) and np.isfinite(approach)):
        return infinite
    with np.errstate(all="ignore"):
        u = np.asarray(problem.compliance @ r if displacements is None else displacements)
        if not np.all(np.isfinite(u)):
            return infinite
        g = problem.gaps(u, approach)
        tiny = np.finfo(float).tiny
        force = max(float(np.max(np.abs(r))), tiny)
        length = max(
            float(np.max(np.abs(u))), abs(approach - float(np.min(problem.separation))), tiny
        )
        balance = 0.0
        if problem.load is not None:
            balance = abs(float(np.sum(r)) - problem.load) / problem.load
        return Certificate(
            penetration=max(0.0, float(np.max(-g))) / length,
            force_sign=max(0.0, float(np.max(-r))) / force,
            complementarity=float(np.max(np.abs(r * g))) / (force * length),
            equilibrium=balance,
            tol=tol,
        )


@dataclass(kw_only=True, repr=False)
class SurfaceResult(ContactResult):
    """The answer to a :class:`SurfaceProblem`.

    The common fields of :class:`~contactqp.core.result.ContactResult` in the surface's terms:
    ``forces`` (and ``nodal_forces``) the compressive force on each point ``r`` (N, shape
    (m,)), ``displacements`` the surface displacements ``u = W r`` (m), ``gaps``
    ``s - delta + u`` (m), ``contact_status`` closed where the force exceeds
    :data:`CONTACT_RTOL` times the largest, ``energy`` the stored elastic energy
    ``1/2 r . u`` (J), ``certificate`` from :func:`certify_surface` (``equilibrium`` is the load
    balance).

    Attributes
    ----------
    approach : float
        Rigid-body approach ``delta`` of the indenter (m): the given one, or found.
    load : float
        Total force ``sum r`` (N).
    """

    approach: float
    load: float

    @property
    def contact(self) -> np.ndarray:
        """Bool mask of the points in contact, shape (m,)."""
        return np.asarray(self.contact_status == ContactStatus.CLOSED)

    @property
    def contact_fraction(self) -> float:
        """Fraction of the points in contact (of the area, for equal cells)."""
        return float(np.mean(self.contact)) if self.contact.size else 0.0

    def _summary_extra(self) -> dict:
        return {
            "approach": self.approach,
            "load": self.load,
            "contact_fraction": self.contact_fraction,
            "max_force": float(np.max(self.forces, initial=0.0)),
        }

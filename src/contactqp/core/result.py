"""Results: one shape for every answer, shaped like :class:`scipy.optimize.OptimizeResult`.

:class:`ContactResult` holds the fields every answer has: the displacements, contact forces and
gaps, a per-contact status (:class:`~contactqp.core.status.ContactStatus` codes), the energy,
the verdict (``success``, ``status``, ``message``), the work done (``iterations``, ``seconds``,
``method``) and the certificate that checked the answer independently of the method. A
frictionless answer is a :class:`ContactResult`; the subclasses add what their physics adds:

* :class:`FrictionalResult`: slips, tangential displacements, dissipation, elastic energy;
* :class:`LocalResult`: an FCLIB problem's answer (and a global problem's velocities ``v``);
* :class:`FastenedResult`: the fastener forces and the closure of an assembly.

The certificates are in :mod:`contactqp.core.certificate`.
"""

from __future__ import annotations

import dataclasses
import html
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from .certificate import Certificate, FrictionCertificate, LocalCertificate
from .status import ContactStatus, status_counts, status_labels

__all__ = [
    "ContactResult",
    "FrictionalResult",
    "LocalResult",
    "FastenedResult",
    "SUCCESS",
    "NOT_CONVERGED",
    "CERTIFICATE_FAILED",
    "verdict",
]

#: Values of :attr:`ContactResult.status`: solved, the method did not converge, the certificate
#: (or, for an assembly, the fastener closure) failed.
SUCCESS, NOT_CONVERGED, CERTIFICATE_FAILED = 0, 1, 2


def verdict(converged: bool, certificate, message: str, note: str = "") -> tuple[int, bool, str]:
    """``(status, success, message)`` of an answer from its method's word and its certificate.

    Parameters
    ----------
    converged : bool
        Whether the method says it converged.
    certificate
        Any certificate of :mod:`contactqp.core.certificate` (or one with the same ``finite``,
        ``passed``, ``worst`` and ``tol``).
    message : str
        The method's message; the certificate's failure is appended to it.
    note : str, optional
        Appended to a failed certificate's message (for example why the residual is bounded).

    Returns
    -------
    tuple of (int, bool, str)
        :data:`SUCCESS`, :data:`NOT_CONVERGED` or :data:`CERTIFICATE_FAILED`; whether that is
        success; the message.
    """
    if not certificate.finite:
        failure = "the answer holds NaN or inf (overflow or a failed solve)"
        return CERTIFICATE_FAILED, False, f"{message}; certificate failed: {failure}"
    if not converged:
        return NOT_CONVERGED, False, message
    if not certificate.passed:
        worst = f"worst relative residual {certificate.worst:.2e} > {certificate.tol:.0e}"
        return CERTIFICATE_FAILED, False, f"{message}; certificate failed ({worst}){note}"
    return SUCCESS, True, message


def _figure(value) -> str:
    """A certificate's entry as shown in :meth:`ContactResult._repr_html_`."""
    if isinstance(value, float):
        return f"{value:.2e}"
    return str(value)


@dataclass(kw_only=True)
class ContactResult:
    """The answer to a contact problem; a frictionless answer is one of these.

    ``repr`` gives one line; in a notebook the result shows as a small table of the same
    (``_repr_html_``: method, verdict, message, iterations, seconds, contacts by status and the
    certificate's residuals).

    Attributes
    ----------
    displacements : ndarray, shape (n,)
        The displacements of the solved freedoms (m): ``U`` of the model's computational
        freedoms; for an FCLIB problem (:class:`LocalResult`), whose unknowns are per contact,
        the local velocities (or displacement increments) ``u = W r + q``, shape (d k,).
    forces : ndarray
        Contact forces (N): one magnitude per constraint, shape (m,), without friction; the
        local forces ``r``, shape (k, d), normal first, with friction; for an FCLIB problem
        FCLIB's reactions ``r``, shape (d k,).
    nodal_forces : ndarray, shape (n,)
        The contact forces acting on the freedoms of ``displacements`` (N): ``-A^T lambda``
        without friction, ``H^T r`` with; ``r`` itself for an FCLIB problem.
    gaps : ndarray, shape (k,)
        Final gap of each contact (m; ``u_N`` for an FCLIB problem).
    contact_status : ndarray of int, shape (k,)
        One :class:`~contactqp.core.status.ContactStatus` code per contact;
        :attr:`status_labels` gives their labels.
    energy : float
        Total potential energy ``1/2 U^T K U - P^T U`` (J) at the answer, ``P`` the loads
        (with friction too; the stored elastic energy alone is
        :attr:`FrictionalResult.elastic_energy`). NaN for an FCLIB problem, whose data carry no
        loads.
    success : bool
        The method converged *and* the certificate passed.
    status : int
        0 (:data:`SUCCESS`), 1 (:data:`NOT_CONVERGED`: the method did not converge) or 2
        (:data:`CERTIFICATE_FAILED`).
    message : str
        The method's account and the verdict.
    iterations : int
        Iterations of the method.
    seconds : float
        Wall time of the solve (assembly of the dual or local form included, reading files
        excluded).
    method : str
        Name of the method that found the answer.
    certificate : Certificate, FrictionCertificate or LocalCertificate
        The independent check.
    info : dict
        Method-specific extras (e.g. factorisation counts).
    """

    #: The statuses this kind of result reports, counted by :meth:`summary`.
    STATUSES: ClassVar[tuple[ContactStatus, ...]] = (ContactStatus.OPEN, ContactStatus.CLOSED)

    displacements: np.ndarray
    forces: np.ndarray
    nodal_forces: np.ndarray
    gaps: np.ndarray
    contact_status: np.ndarray
    energy: float
    success: bool
    status: int
    message: str
    iterations: int
    seconds: float
    method: str
    certificate: Certificate | FrictionCertificate | LocalCertificate
    info: dict = field(default_factory=dict)

    @property
    def n_contacts(self) -> int:
        """Number of contacts."""
        return int(np.size(self.contact_status))

    @property
    def status_labels(self) -> list[str]:
        """The label of each contact's status, e.g. ``"closed"`` or ``"slip"``."""
        return status_labels(self.contact_status)

    def as_dict(self) -> dict:
        """Every field, by name (arrays included; the certificate as its ``as_dict()``)."""
        fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        fields["certificate"] = self.certificate.as_dict()
        return fields

    def summary(self) -> dict:
        """A JSON-ready summary (no arrays): the scalar fields, the count of each status of
        :attr:`STATUSES` under its label, what the subclass adds and the certificate."""
        counts = status_counts(self.contact_status)
        return {
            "success": self.success,
            "status": self.status,
            "message": self.message,
            "method": self.method,
            "iterations": self.iterations,
            "seconds": self.seconds,
            "contacts": self.n_contacts,
            "energy": self.energy,
            **{s.label: counts[s.label] for s in self.STATUSES},
            **self._summary_extra(),
            "certificate": self.certificate.as_dict(),
        }

    def _summary_extra(self) -> dict:
        return {
            "max_force": float(np.max(self.forces, initial=0.0)),
            "min_gap": float(np.min(self.gaps, initial=np.inf)),
        }

    def _repr_html_(self) -> str:
        """A small HTML table for notebooks: the verdict, the work done, the contacts by status
        and the certificate's worst residual against its tolerance (every text escaped)."""
        counts = status_counts(self.contact_status)
        certificate = self.certificate
        verdict = "passed" if certificate.passed else "failed"
        rows = [
            ("method", self.method),
            ("success", f"{self.success} (status {self.status})"),
            ("message", self.message),
            ("iterations", str(self.iterations)),
            ("seconds", f"{self.seconds:.3g}"),
            (
                "contacts",
                f"{self.n_contacts}: "
                + ", ".join(f"{counts[s.label]} {s.label}" for s in self.STATUSES),
            ),
            (
                "certificate",
                f"{verdict}: worst residual {certificate.worst:.2e} "
                f"(tolerance {certificate.tol:.0e})",
            ),
            (
                "residuals",
                ", ".join(
                    f"{name} {_figure(value)}"
                    for name, value in certificate.as_dict().items()
                    if name not in ("tol", "passed")
                ),
            ),
        ]
        body = "".join(
            f"<tr><th style='text-align:left'>{html.escape(name)}</th>"
            f"<td style='text-align:left'>{html.escape(value)}</td></tr>"
            for name, value in rows
        )
        return f"<table><caption>{html.escape(type(self).__name__)}</caption>{body}</table>"

    def __repr__(self) -> str:
        counts = status_counts(self.contact_status)
        shown = "/".join(s.label for s in self.STATUSES)
        numbers = "/".join(str(counts[s.label]) for s in self.STATUSES)
        return (
            f"{type(self).__name__}(success={self.success}, method={self.method!r}, "
            f"{shown}={numbers}, iterations={self.iterations}, "
            f"message={self.message!r})"
        )


@dataclass(kw_only=True, repr=False)
class FrictionalResult(ContactResult):
    """The answer to one step of a frictional problem.

    The common fields are those of :class:`ContactResult`: ``displacements`` ``U`` (m) and
    ``forces`` ``r`` (N, shape (k, d): compressive normal force, then the tangential force on
    the body, on the first node of a pair, along each tangent of the frame) are totals;
    ``contact_status`` is open, stick or slip: "open" when the force from the cone's apex is
    below ``1e-10`` times the contacts' force scale, "slip" when the slip exceeds
    ``certificate_tol`` times the contact's length scale (both of
    :func:`~contactqp.core.certificate.contact_scales`), below which the certificate could not
    tell a slip from none; ``certificate`` is a
    :class:`~contactqp.core.certificate.FrictionCertificate`.

    Attributes
    ----------
    slip : ndarray, shape (k, d - 1)
        Slip increment of the step along the tangents (m).
    tangential_displacements : ndarray, shape (k, d - 1)
        ``(H U)_T``, total tangential displacement (m): the origin of the next step's slips.
    dissipation : ndarray, shape (k,)
        Energy dissipated by friction during the step, ``-r_T . s_T`` per contact (J), with the
        end-of-step force (exact when the friction bound is constant during the slip).
    elastic_energy : float
        Stored elastic energy ``1/2 U^T K U`` (J), from ``K U = P + H^T r``: with the
        dissipation, the energy balance of a load path.
    loads : ndarray, shape (n_freedoms,)
        The loads of the step (N).
    """

    STATUSES: ClassVar[tuple[ContactStatus, ...]] = (
        ContactStatus.OPEN,
        ContactStatus.STICK,
        ContactStatus.SLIP,
    )

    slip: np.ndarray
    tangential_displacements: np.ndarray
    dissipation: np.ndarray
    elastic_energy: float
    loads: np.ndarray

    @property
    def normal_forces(self) -> np.ndarray:
        """Compressive normal force per contact (N), shape (k,)."""
        return self.forces[:, 0]

    @property
    def tangential_forces(self) -> np.ndarray:
        """Tangential force per contact (N), shape (k, d - 1)."""
        return self.forces[:, 1:]

    @property
    def dissipated(self) -> float:
        """Energy dissipated in the step by all contacts (J)."""
        return float(np.sum(self.dissipation))

    def _summary_extra(self) -> dict:
        return {"dissipated": self.dissipated, "elastic_energy": self.elastic_energy}


@dataclass(kw_only=True, repr=False)
class LocalResult(ContactResult):
    """The answer to an FCLIB problem ``u = W r + q`` (local) or ``M v = H r + f`` (global).

    The common fields in FCLIB's terms: ``displacements`` is ``u`` and ``forces`` is ``r``
    (both of shape (d k,), contact by contact, normal first; ``nodal_forces`` is ``r`` too, the
    problem's freedoms being the contacts'); ``gaps`` is ``u_N``; ``contact_status`` is open,
    stick or slip (:func:`~contactqp.core.local_problem.contact_status`); ``energy`` is NaN;
    ``certificate`` is a :class:`~contactqp.core.certificate.LocalCertificate` (natural-map
    error, the global equilibrium, the accuracy limits, all computed from ``r``). ``success``
    (status 0, else 1) is the route's verdict: that certificate passed at the method's tolerance
    for the Coulomb and box-QP routes and the Tresca fixed point; for the polygonal cones, whose
    answer the exact-cone natural map does not judge, the fixed point reached.

    Attributes
    ----------
    v : ndarray or None, shape (ndof,)
        Global velocities solving ``M v = H r + f`` for a global problem, else None.
    """

    STATUSES: ClassVar[tuple[ContactStatus, ...]] = (
        ContactStatus.OPEN,
        ContactStatus.STICK,
        ContactStatus.SLIP,
    )

    v: np.ndarray | None = None

    def _summary_extra(self) -> dict:
        certificate = self.certificate
        assert isinstance(certificate, LocalCertificate)  # set so by every local method
        return {"error": certificate.natural_map}


@dataclass(kw_only=True, repr=False)
class FastenedResult(ContactResult):
    """The state of an assembly after some fasteners are installed.

    The common fields are those of the contact problem in which the fastener tensions are
    external loads (``gaps`` final, ``forces`` the contact compression per pair, N); the
    status of a fastened pair is ``fastened``, the others ``open`` or ``closed``. ``success``
    also asks that the closure hold within the certificate's tolerance (status 2 otherwise).

    Attributes
    ----------
    fasteners : ndarray of int, shape (f,)
        Pairs closed by a fastener.
    fastener_forces : ndarray, shape (f,)
        Tension of each fastener (N, >= 0).
    closure : float
        Largest ``|gap|`` at the fasteners (m): zero up to round-off when the closure holds.
    multipliers : ndarray, shape (k,)
        The dual solution: contact forces, minus the tension at fasteners (warm starts).
    """

    STATUSES: ClassVar[tuple[ContactStatus, ...]] = (
        ContactStatus.OPEN,
        ContactStatus.CLOSED,
        ContactStatus.FASTENED,
    )

    fasteners: np.ndarray
    fastener_forces: np.ndarray
    closure: float
    multipliers: np.ndarray

    @classmethod
    def from_contact(
        cls, contact: ContactResult, fasteners, fastener_forces, multipliers, initial_gaps
    ) -> FastenedResult:
        """The state whose contact problem, pulled by the ``fastener_forces`` (N) at the
        ``fasteners`` rows, has the certified result ``contact``: the closure is checked against
        the certificate's tolerance times the largest initial gap or displacement (m), and the
        fastened pairs are marked ``fastened``."""
        rows = np.asarray(fasteners, dtype=int)
        closure = float(np.max(np.abs(contact.gaps[rows])))
        scale = max(
            float(np.max(np.abs(initial_gaps))),
            float(np.max(np.abs(contact.displacements))),
            np.finfo(float).tiny,
        )
        closed = bool(closure <= contact.certificate.tol * scale)
        common = {f.name: getattr(contact, f.name) for f in dataclasses.fields(ContactResult)}
        if contact.success and not closed:
            common.update(
                status=CERTIFICATE_FAILED,
                message=(
                    f"{contact.message}; fastener closure failed (largest |gap| {closure:.2e} m > "
                    f"{contact.certificate.tol:.0e} times {scale:.2e} m)"
                ),
            )
        codes = contact.contact_status.copy()
        codes[rows] = ContactStatus.FASTENED
        common.update(contact_status=codes, success=bool(contact.success and closed))
        return cls(
            **common,
            fasteners=rows,
            fastener_forces=np.asarray(fastener_forces),
            closure=closure,
            multipliers=np.asarray(multipliers),
        )

    def _summary_extra(self) -> dict:
        return {
            **super()._summary_extra(),
            "closure": self.closure,
            "max_fastener_force": float(np.max(self.fastener_forces, initial=0.0)),
        }

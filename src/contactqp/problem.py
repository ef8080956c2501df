"""ContactProblem: a reduced model, its loads and its unilateral constraints.

Primal form (the method's QP, on displacements):

.. math::

    \\min_U \\tfrac12 U^T K U - P^T U \\quad \\text{s.t.} \\quad A U \\le \\Delta

Dual form (on contact forces, built from ``R`` without inverting it):

.. math::

    \\min_{\\lambda \\ge 0} \\tfrac12 \\lambda^T W \\lambda - \\lambda^T (A R P - \\Delta),
    \\qquad W = A R A^T, \\qquad U = R (P - A^T \\lambda)
"""

from __future__ import annotations

import numpy as np

from .contact import Constraints, assemble_constraints
from .errors import InvalidInputError
from .model import ReducedModel
from .result import CERTIFICATE_TOL, ContactResult, certify

__all__ = ["ContactProblem", "DualForm"]

#: A contact is reported closed when its force exceeds this fraction of the problem's force scale.
CLOSED_RTOL = 1e-10


class DualForm:
    """The dual quadratic program of a frictionless contact problem.

    Attributes
    ----------
    W : ndarray, shape (m, m)
        Delassus operator ``A R A^T`` (m/N).
    b : ndarray, shape (m,)
        ``A R P - Delta``: the interpenetration the free deformation would cause (m).
    free_displacements : ndarray, shape (n,)
        ``R P``.
    influence : ndarray, shape (n, m)
        ``R A^T``: displacements caused by unit contact forces.
    """

    def __init__(self, model: ReducedModel, constraints: Constraints, loads: np.ndarray):
        A = constraints.matrix
        if model.given == "flexibility":
            # only the freedoms the constraints touch enter R A^T
            used = np.unique(A.indices)
            self.influence = model.flexibility[:, used] @ A[:, used].T.toarray()
        else:
            self.influence = model.displacements(A.T.toarray())
        W = np.asarray(A @ self.influence)
        self.W = 0.5 * (W + W.T)
        self.free_displacements = model.displacements(loads)
        self.b = A @ self.free_displacements - constraints.gaps

    def displacements(self, forces: np.ndarray) -> np.ndarray:
        """``U = R (P - A^T lambda)`` for contact forces ``lambda``."""
        return self.free_displacements - self.influence @ forces


class ContactProblem:
    """A frictionless contact problem on a reduced model.

    Parameters
    ----------
    model : ReducedModel
    loads : array_like, shape (n_freedoms,)
        External forces ``P`` on the computational freedoms (N).
    obstacles : sequence
        :class:`~contactqp.contact.GapObstacle`, :class:`~contactqp.contact.PlaneObstacle`,
        :class:`~contactqp.contact.ProfileObstacle` or :class:`~contactqp.contact.NodePairs`.
    certificate_tol : float
        Largest relative residual the certificate accepts.
    """

    def __init__(self, model: ReducedModel, loads, obstacles, certificate_tol: float = CERTIFICATE_TOL):
        if not isinstance(model, ReducedModel):
            raise InvalidInputError(f"model must be a ReducedModel, got {type(model).__name__}")
        P = np.asarray(loads, dtype=float).reshape(-1)
        if P.shape != (model.n_freedoms,):
            raise InvalidInputError(
                f"loads must have shape ({model.n_freedoms},) to match the model, got "
                f"{np.shape(loads)}"
            )
        if not np.all(np.isfinite(P)):
            raise InvalidInputError("loads contains NaN or inf")
        if not certificate_tol > 0:
            raise InvalidInputError(f"certificate_tol must be > 0, got {certificate_tol}")
        self.model = model
        self.loads = P
        self.constraints = assemble_constraints(model, obstacles)
        self.certificate_tol = float(certificate_tol)
        self._dual = None

    @property
    def n_constraints(self) -> int:
        """Number of unilateral constraints."""
        return self.constraints.n_constraints

    def dual(self) -> DualForm:
        """The dual form, assembled on first use and kept."""
        if self._dual is None:
            self._dual = DualForm(self.model, self.constraints, self.loads)
        return self._dual

    def energy(self, displacements: np.ndarray, forces: np.ndarray) -> float:
        """Potential energy ``1/2 U^T K U - P^T U`` (J) at equilibrium.

        Uses ``K U = P - A^T lambda`` (checked by the certificate) so that no factorisation of the
        model's matrix is needed.
        """
        U = np.asarray(displacements, dtype=float)
        internal = self.loads - self.constraints.matrix.T @ np.asarray(forces, dtype=float)
        return float(0.5 * U @ internal - self.loads @ U)

    def make_result(self, displacements, forces, *, solver: str, converged: bool, message: str,
                    nit: int, wall_time: float, info: dict | None = None) -> ContactResult:
        """Wrap a solver's answer in a :class:`ContactResult` with its certificate."""
        U = np.asarray(displacements, dtype=float)
        lam = np.asarray(forces, dtype=float)
        certificate = certify(self, U, lam, self.certificate_tol)
        force_scale = max(np.max(np.abs(self.loads), initial=0.0), np.max(np.abs(lam), initial=0.0))
        if not converged:
            status, success = 1, False
        elif not certificate.passed:
            status, success = 2, False
            message = (f"{message}; certificate failed (worst relative residual "
                       f"{certificate.worst:.2e} > {certificate.tol:.0e})")
        else:
            status, success = 0, True
        A = self.constraints.matrix
        return ContactResult(
            x=U, forces=lam, nodal_forces=-(A.T @ lam), gaps=self.constraints.gaps - A @ U,
            closed=lam > CLOSED_RTOL * force_scale, energy=self.energy(U, lam), success=success,
            status=status, message=message, nit=int(nit), wall_time=float(wall_time),
            solver=solver, certificate=certificate, info=dict(info or {}),
        )

    def __repr__(self) -> str:
        return f"ContactProblem({self.model!r}, {self.n_constraints} constraints)"

"""ContactResult and the certificate that checks an answer independently of the solver."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Certificate", "ContactResult", "certify"]

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
        ``max(A U - Delta, 0)`` over the length scale.
    force_sign : float
        ``max(-lambda, 0)`` over the force scale (contact forces push, never pull).
    complementarity : float
        ``max |lambda_i (Delta - A U)_i|`` over force scale times length scale.
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
        """The largest of the four residuals."""
        return max(self.penetration, self.force_sign, self.complementarity, self.equilibrium)

    @property
    def passed(self) -> bool:
        """True when every residual is within ``tol``."""
        return bool(self.worst <= self.tol)

    def as_dict(self) -> dict:
        """Plain dictionary (for JSON)."""
        return {"penetration": self.penetration, "force_sign": self.force_sign,
                "complementarity": self.complementarity, "equilibrium": self.equilibrium,
                "tol": self.tol, "passed": self.passed}


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
    """
    U = np.asarray(displacements, dtype=float)
    lam = np.asarray(forces, dtype=float)
    A, gaps, P = problem.constraints.matrix, problem.constraints.gaps, problem.loads
    tiny = np.finfo(float).tiny
    model = problem.model
    force = max(np.max(np.abs(P), initial=0.0), np.max(np.abs(lam), initial=0.0), tiny)
    compliance = (np.max(np.diag(model.flexibility)) if model.given == "flexibility"
                  else 1.0 / np.max(np.diag(model.stiffness)))
    # the displacement the force scale would cause keeps the scale meaningful when gaps and
    # displacements are both (near) zero, e.g. a closed contact with zero initial gap
    length = max(np.max(np.abs(U), initial=0.0), np.max(np.abs(gaps), initial=0.0),
                 compliance * force, tiny)
    final_gaps = gaps - A @ U
    net_load = P - A.T @ lam
    if model.given == "flexibility":
        equilibrium = np.max(np.abs(U - model.flexibility @ net_load), initial=0.0) / length
    else:
        equilibrium = np.max(np.abs(model.stiffness @ U - net_load), initial=0.0) / force
    return Certificate(
        penetration=float(max(0.0, -np.min(final_gaps, initial=0.0)) / length),
        force_sign=float(max(0.0, -np.min(lam, initial=0.0)) / force),
        complementarity=float(np.max(np.abs(lam * final_gaps), initial=0.0) / (force * length)),
        equilibrium=float(equilibrium),
        tol=tol,
    )


@dataclass
class ContactResult:
    """The answer to a contact problem, shaped like :class:`scipy.optimize.OptimizeResult`.

    Attributes
    ----------
    x : ndarray, shape (n_freedoms,)
        Displacements ``U`` of the computational freedoms (m).
    forces : ndarray, shape (n_constraints,)
        Contact force of each constraint (N, >= 0).
    nodal_forces : ndarray, shape (n_freedoms,)
        Contact forces on the body's freedoms, ``-A^T lambda`` (N).
    gaps : ndarray, shape (n_constraints,)
        Final gaps ``Delta - A U`` (m).
    closed : ndarray of bool, shape (n_constraints,)
        Contact status: True where the contact carries force (closed), False where open.
    energy : float
        Potential energy ``1/2 U^T K U - P^T U`` (J).
    success : bool
        The solver converged *and* the certificate passed.
    status : int
        0 success, 1 the solver did not converge, 2 the certificate failed.
    message : str
    nit : int
        Iterations.
    wall_time : float
        Seconds spent in the solve (assembly of the dual included, reading files excluded).
    solver : str
    certificate : Certificate
    info : dict
        Solver-specific extras (e.g. factorisations).
    """

    x: np.ndarray
    forces: np.ndarray
    nodal_forces: np.ndarray
    gaps: np.ndarray
    closed: np.ndarray
    energy: float
    success: bool
    status: int
    message: str
    nit: int
    wall_time: float
    solver: str
    certificate: Certificate
    info: dict = field(default_factory=dict)

    @property
    def displacements(self) -> np.ndarray:
        """Alias of ``x``."""
        return self.x

    @property
    def status_labels(self) -> list[str]:
        """``"closed"`` or ``"open"`` per constraint."""
        return ["closed" if c else "open" for c in self.closed]

    def summary(self) -> dict:
        """A JSON-ready summary (no arrays)."""
        return {"success": self.success, "status": self.status, "message": self.message,
                "solver": self.solver, "iterations": self.nit, "seconds": self.wall_time,
                "contacts": int(self.forces.size), "closed": int(np.count_nonzero(self.closed)),
                "energy": self.energy, "max_force": float(np.max(self.forces, initial=0.0)),
                "min_gap": float(np.min(self.gaps, initial=np.inf)),
                "certificate": self.certificate.as_dict()}

    def __repr__(self) -> str:
        return (f"ContactResult(success={self.success}, solver={self.solver!r}, "
                f"closed={int(np.count_nonzero(self.closed))}/{self.forces.size}, nit={self.nit}, "
                f"message={self.message!r})")

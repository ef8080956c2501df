"""ContactProblem and FrictionalProblem: a reduced model, its loads and its contacts.

Primal form (the method's QP, on displacements):

.. math::

    \\min_U \\tfrac12 U^T K U - P^T U \\quad \\text{s.t.} \\quad A U \\le \\Delta

Dual form (on contact forces, built from ``R`` without inverting it):

.. math::

    \\min_{\\lambda \\ge 0} \\tfrac12 \\lambda^T W \\lambda - \\lambda^T (A R P - \\Delta),
    \\qquad W = A R A^T, \\qquad U = R (P - A^T \\lambda)

Local form with friction (FCLIB's ``u = W r + q``, see :class:`LocalForm`): with the operator
``H`` of :func:`~contactqp.core.contact.local_frames` (per contact the rows ``-n, t_1[, t_2]``),

.. math::

    U = R (P + H^T r), \\qquad u = H U + w = W r + q, \\qquad W = H R H^T,
    \\qquad q = H R P + w,

``w`` holding the initial gap ``Delta`` in each normal slot and zero in the tangential ones:
``u_N`` is the gap opening (>= 0), ``r_N`` the compressive normal force (>= 0), ``u_T`` the
tangential displacement and ``r_T`` the tangential force on the body. The normal block of ``W``
is the frictionless ``A R A^T`` and ``q_N = -b``.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import warnings
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ContactWarning, InvalidInputError
from .certificate import CERTIFICATE_TOL, certify, certify_friction, contact_scales
from .contact import Constraints, LocalFrames, assemble_constraints, local_frames
from .friction import FrictionLaw, apex_distance
from .local_problem import LocalProblem
from .model import MAX_MAGNITUDE, ReducedModel, finite_array, positive_tolerance, real_array
from .operators import symmetric_product
from .result import ContactResult, FrictionalResult, verdict
from .status import ContactStatus

if TYPE_CHECKING:
    import scipy.sparse

__all__ = ["ContactProblem", "DualForm", "FrictionalProblem", "FrictionStep", "LocalForm"]

#: A contact is reported closed when its force exceeds this fraction of the problem's force scale.
CLOSED_RTOL = 1e-10
#: How many restrictions to contact sets a problem keeps (:meth:`FrictionalProblem.restricted`).
RESTRICTIONS_KEPT = 16


def _delassus(model: ReducedModel, matrix: scipy.sparse.csr_matrix):
    """``(R M^T, M R M^T)`` for a sparse constraint matrix ``M``: the displacements under unit
    contact forces and the Delassus operator, symmetrised (its asymmetry is round-off)."""
    if model.given == "flexibility":
        selection = _selection(matrix)
        if selection is not None:
            return _selected_delassus(model.flexibility, *selection)
        # only the freedoms the constraints touch enter R M^T
        used = np.unique(matrix.indices)
        # R is exactly symmetric (ReducedModel symmetrises it): R M^T = (M R)^T, one sparse
        # product (a few entries per row of M) instead of a dense one; kept as the transpose
        # of M R, whose rows (one per local force) are contiguous
        influence = np.asarray(matrix[:, used] @ model.flexibility[used, :]).T
    else:
        influence = model.displacements(matrix.T.toarray())
    W = np.asarray(matrix @ influence)
    return influence, 0.5 * (W + W.T)


def _selection(matrix: scipy.sparse.csr_matrix) -> tuple[np.ndarray, np.ndarray] | None:
    """``(columns, scales)`` when every row of ``M`` holds one nonzero entry (each constraint acts
    on one freedom: ``M = diag(scales) I[columns]``), else None. Stored zeros do not count: the
    frame of an axis-aligned normal stores its zero components."""
    stored = np.diff(matrix.indptr)
    if matrix.shape[0] == 0 or np.any(stored == 0):
        return None
    if np.all(stored == 1):
        return matrix.indices, matrix.data
    nonzero = matrix.data != 0.0
    rows = np.repeat(np.arange(matrix.shape[0]), stored)[nonzero]
    if rows.size != matrix.shape[0] or np.any(np.diff(rows) != 1):
        return None
    return matrix.indices[nonzero], matrix.data[nonzero]


#: Entries of ``W`` scaled at a time by :func:`_selected_delassus` (a temporary of 512 kB).
_SCALED_ENTRIES = 1 << 16


def _selected_delassus(R: np.ndarray, columns: np.ndarray, scales: np.ndarray):
    """``(R M^T, M R M^T)`` for ``M = diag(scales) I[columns]`` by indexing ``R``: no product.

    ``W_ij = R_{c_i c_j} (s_i s_j)`` is exactly symmetric, as ``R`` is. When ``M`` is the
    identity (every freedom a constraint, in order, scale 1), both are read-only views of ``R``.
    """
    unit = bool(np.all(scales == 1.0))
    if unit and columns.size == R.shape[0] and np.array_equal(columns, np.arange(columns.size)):
        view = R.view()
        view.flags.writeable = False
        return view, view
    rows = R.take(columns, axis=0)  # M R up to the scales: contiguous rows of R (R = R^T)
    W = rows.take(columns, axis=1)
    if not unit:
        rows *= scales[:, None]
        if np.all(np.abs(scales) == 1.0):  # signs (unit directions): exact in either order
            W *= scales[:, None]
            W *= scales[None, :]
        else:
            step = max(1, _SCALED_ENTRIES // scales.size)
            for start in range(0, scales.size, step):  # s_i s_j by row blocks, no m x m temporary
                block = slice(start, start + step)
                W[block] *= np.multiply.outer(scales[block], scales)
    return rows.T, W


def _sparse_product(model: ReducedModel, loads: np.ndarray) -> np.ndarray:
    """``R P``: of a flexibility model with few loaded freedoms, on those columns of ``R``."""
    if model.given != "flexibility":
        return model.displacements(loads)
    loaded = np.flatnonzero(loads)
    if 4 * loaded.size >= loads.size:
        return model.flexibility @ loads
    # R is exactly symmetric: R[:, s] = R[s].T, read as contiguous rows
    return loads[loaded] @ model.flexibility[loaded]


def _checked_loads(model: ReducedModel, loads, certificate_tol: float) -> np.ndarray:
    """Validate the model, the loads ``(n_freedoms,)`` and the tolerance; return the loads."""
    if not isinstance(model, ReducedModel):
        raise InvalidInputError(f"model must be a ReducedModel, got {type(model).__name__}")
    P = finite_array(real_array(loads, "loads").reshape(-1), "loads", 1, magnitude=MAX_MAGNITUDE)
    if P.shape != (model.n_freedoms,):
        raise InvalidInputError(
            f"loads must have shape ({model.n_freedoms},) to match the model, got {np.shape(loads)}"
        )
    positive_tolerance(certificate_tol, "certificate_tol")
    return P


def _restricted_constraints(
    constraints: Constraints, contacts, gaps
) -> tuple[np.ndarray, Constraints]:
    """``(kept, constraints)``: the rows ``contacts`` (distinct indices) of ``constraints``, on
    the initial gaps ``gaps`` (m, one per kept row; theirs by default)."""
    kept = np.asarray(contacts, dtype=int).reshape(-1)
    m = constraints.n_constraints
    if kept.size == 0 or kept.min() < 0 or kept.max() >= m or np.unique(kept).size < kept.size:
        raise InvalidInputError(f"contacts must be distinct indices in 0..{m - 1}, at least one")
    values = constraints.gaps[kept]
    if gaps is not None:
        values = finite_array(gaps, "gaps", 1, magnitude=MAX_MAGNITUDE)
        if values.shape != kept.shape:
            raise InvalidInputError(f"gaps must have shape ({kept.size},), got {values.shape}")
    restricted = dataclasses.replace(
        constraints,
        matrix=constraints.matrix[kept],
        gaps=values,
        nodes=constraints.nodes[kept],
        labels=[constraints.labels[i] for i in kept] if constraints.labels else [],
    )
    return kept, restricted


class DualForm:
    """The dual quadratic program of a frictionless contact problem.

    Attributes
    ----------
    W : ndarray, shape (m, m)
        Delassus operator ``A R A^T`` (m/N), exactly symmetric; read-only (a view of ``R``) when
        ``A`` is the identity.
    b : ndarray, shape (m,)
        ``A R P - Delta``: the interpenetration the free deformation would cause (m).
    free_displacements : ndarray, shape (n,)
        ``R P``.
    influence : ndarray, shape (n, m)
        ``R A^T``: displacements caused by unit contact forces.
    """

    def __init__(self, model: ReducedModel, constraints: Constraints, loads: np.ndarray):
        A = constraints.matrix
        self.influence, self.W = _delassus(model, A)
        self.free_displacements = _sparse_product(model, loads)
        self.b = A @ self.free_displacements - constraints.gaps

    def displacements(self, forces: np.ndarray, W_forces: np.ndarray | None = None) -> np.ndarray:
        """``U = R (P - A^T lambda)`` for contact forces ``lambda``; ``W_forces`` is
        ``W lambda`` when the caller has it (a solver's last product), which is ``R A^T lambda``
        when ``A`` is the identity and then saves a product with ``R``."""
        if self.influence is self.W:  # A = I: R A^T is R, exactly symmetric
            if W_forces is None:
                W_forces = symmetric_product(self.W, forces)
            return self.free_displacements - W_forces
        return self.free_displacements - self.influence @ forces


class ContactProblem:
    """A frictionless contact problem on a reduced model.

    Parameters
    ----------
    model : ReducedModel
    loads : array_like, shape (n_freedoms,)
        External forces ``P`` on the computational freedoms (N).
    obstacles : sequence
        :class:`~contactqp.core.contact.GapObstacle`,
        :class:`~contactqp.core.contact.PlaneObstacle`,
        :class:`~contactqp.core.contact.ProfileObstacle` or
        :class:`~contactqp.core.contact.NodePairs`.
    certificate_tol : float
        Largest relative residual the certificate accepts.

    Attributes
    ----------
    kind : str
        ``"frictionless"`` (see :mod:`contactqp.methods.registry`).
    """

    kind = "frictionless"

    def __init__(
        self, model: ReducedModel, loads, obstacles, certificate_tol: float = CERTIFICATE_TOL
    ):
        self.loads = _checked_loads(model, loads, certificate_tol)
        self.model = model
        self.constraints = assemble_constraints(model, obstacles)
        self.certificate_tol = float(certificate_tol)
        self._dual: DualForm | None = None

    @property
    def n_constraints(self) -> int:
        """Number of unilateral constraints."""
        return self.constraints.n_constraints

    def dual(self) -> DualForm:
        """The dual form, assembled on first use and kept."""
        if self._dual is None:
            self._dual = DualForm(self.model, self.constraints, self.loads)
        return self._dual

    def free_displacements(self) -> np.ndarray:
        """``R P`` (m): the displacements under the loads alone (the dual's, once assembled)."""
        if self._dual is not None:
            return self._dual.free_displacements
        return _sparse_product(self.model, self.loads)

    def variant(self, *, loads=None, gaps=None) -> ContactProblem:
        """The same model and constraints under other loads and/or initial gaps.

        The dual's ``W`` and influence are shared (assembled once, on first use); only
        ``b = A R P - Delta`` (and ``R P`` for new loads) is computed again.

        Parameters
        ----------
        loads : array_like, shape (n_freedoms,), optional
            External forces (N).
        gaps : array_like, shape (n_constraints,), optional
            Initial gaps of the constraints, in their order (m).
        """
        twin = copy.copy(self)
        dual = copy.copy(self.dual())
        if loads is not None:
            twin.loads = _checked_loads(self.model, loads, self.certificate_tol)
            dual.free_displacements = self.model.displacements(twin.loads)
        if gaps is not None:
            values = finite_array(gaps, "gaps", 1, magnitude=MAX_MAGNITUDE)
            if values.shape != (self.n_constraints,):
                raise InvalidInputError(
                    f"gaps must have shape ({self.n_constraints},), got {values.shape}"
                )
            twin.constraints = dataclasses.replace(self.constraints, gaps=values)
        dual.b = twin.constraints.matrix @ dual.free_displacements - twin.constraints.gaps
        twin._dual = dual
        return twin

    def restricted(self, contacts, *, loads=None, gaps=None) -> ContactProblem:
        """The same model on the constraints ``contacts`` only (distinct indices, in the order
        they take; e.g. those fasteners leave), without assembling them again; its dual is
        assembled on first use.

        Parameters
        ----------
        loads : array_like, shape (n_freedoms,), optional
            External forces (N); this problem's by default.
        gaps : array_like, shape (len(contacts),), optional
            Initial gaps of the kept constraints (m); theirs in this problem by default.
        """
        twin = copy.copy(self)
        _, twin.constraints = _restricted_constraints(self.constraints, contacts, gaps)
        if loads is not None:
            twin.loads = _checked_loads(self.model, loads, self.certificate_tol)
        twin._dual = None
        return twin

    def energy(self, displacements: np.ndarray, forces: np.ndarray) -> float:
        """Potential energy ``1/2 U^T K U - P^T U`` (J) at equilibrium.

        Uses ``K U = P - A^T lambda`` (checked by the certificate) so that no factorisation of the
        model's matrix is needed.
        """
        U = np.asarray(displacements, dtype=float)
        internal = self.loads - self.constraints.matrix.T @ np.asarray(forces, dtype=float)
        return float(0.5 * U @ internal - self.loads @ U)

    def make_result(
        self,
        displacements,
        forces,
        *,
        method: str,
        converged: bool,
        message: str,
        iterations: int,
        seconds: float,
        info: dict | None = None,
    ) -> ContactResult:
        """Wrap a solver's answer in a :class:`ContactResult` with its certificate.

        An answer holding NaN or inf (an overflow, or a backend that found nothing) fails the
        certificate (status 2) and the message says so; numpy's warnings are kept inside.
        """
        with np.errstate(all="ignore"):
            return self._result(
                displacements,
                forces,
                method=method,
                converged=converged,
                message=message,
                iterations=iterations,
                seconds=seconds,
                info=info,
            )

    def _result(
        self, displacements, forces, *, method, converged, message, iterations, seconds, info
    ) -> ContactResult:
        U = np.asarray(displacements, dtype=float)
        lam = np.asarray(forces, dtype=float)
        certificate = certify(self, U, lam, self.certificate_tol)
        force_scale = max(np.max(np.abs(self.loads), initial=0.0), np.max(np.abs(lam), initial=0.0))
        status, success, message = _verdict(converged, certificate, message, self.model)
        A = self.constraints.matrix
        closed = lam > CLOSED_RTOL * force_scale
        return ContactResult(
            displacements=U,
            forces=lam,
            nodal_forces=-(A.T @ lam),
            gaps=self.constraints.gaps - A @ U,
            contact_status=np.where(closed, ContactStatus.CLOSED, ContactStatus.OPEN),
            energy=self.energy(U, lam),
            success=success,
            status=status,
            message=message,
            iterations=int(iterations),
            seconds=float(seconds),
            method=method,
            certificate=certificate,
            info=dict(info or {}),
        )

    def __repr__(self) -> str:
        return f"ContactProblem({self.model!r}, {self.n_constraints} constraints)"


class _Delassus:
    """``W``, or the block of a larger ``W`` on some of its rows and columns, formed on first
    use and then kept; shared by the :class:`LocalForm` copies of one contact set.

    A restricted form's block is gathered only when a method or a user asks for the matrix:
    its certificate needs only the diagonal, which is read from the full one. Gathering a
    block of a few thousand rows touches fresh memory, the larger part of a fastening stage's
    cost when it is done on every stage.
    """

    def __init__(self, full: np.ndarray, rows: np.ndarray | None = None):
        self._full, self._rows = full, rows
        self._matrix: np.ndarray | None = full if rows is None else None
        self._diagonal: np.ndarray | None = None

    def block(self, rows: np.ndarray) -> _Delassus:
        """The block on ``rows`` (indices into this one's rows), of the same full ``W``."""
        return _Delassus(self._full, rows if self._rows is None else self._rows[rows])

    @property
    def matrix(self) -> np.ndarray:
        if self._matrix is None:
            assert self._rows is not None
            # two gathers: faster than ix_
            self._matrix = self._full.take(self._rows, axis=0).take(self._rows, axis=1)
        return self._matrix

    @property
    def formed(self) -> bool:
        return self._matrix is not None

    @property
    def diagonal(self) -> np.ndarray:
        if self._diagonal is None:
            diagonal = np.diagonal(self._full)
            self._diagonal = diagonal.copy() if self._rows is None else diagonal[self._rows]
        return self._diagonal


class LocalForm:
    """The local (FCLIB) form ``u = W r + q`` of a frictional problem; see the module notes.

    Attributes
    ----------
    offset : ndarray, shape (d k,)
        ``w``: the initial gaps in the normal slots, zeros in the tangential ones (m).
    operator : scipy.sparse.csr_matrix, shape (d k, n)
        ``H``.
    """

    def __init__(self, model: ReducedModel, constraints: Constraints, frames: LocalFrames):
        H = frames.operator
        self.operator = H
        self._influence, W = _delassus(model, H)
        self._delassus = _Delassus(W)
        self._columns: np.ndarray | None = None  # a restricted form's columns of _influence
        self.offset = np.zeros(H.shape[0])
        self.offset[:: frames.dim] = constraints.gaps
        self.dim = frames.dim
        self._model = model
        self._templates: dict[tuple[str, int], tuple[FrictionLaw, LocalProblem]] = {}

    @property
    def W(self) -> np.ndarray:
        """``H R H^T`` (m/N, shape (d k, d k)), contact by contact, normal first; a restricted
        form's is gathered on first use."""
        return self._delassus.matrix

    def diagonal(self) -> np.ndarray:
        """The diagonal of :attr:`W` (m/N), without forming a restricted form's ``W``."""
        return self._delassus.diagonal

    @property
    def formed(self) -> bool:
        """True once :attr:`W` is held in memory (always for an unrestricted form)."""
        return self._delassus.formed

    @property
    def influence(self) -> np.ndarray:
        """``R H^T`` (m/N, shape (n, d k)): displacements caused by unit local forces."""
        if self._columns is None:
            return self._influence
        return self._influence[:, self._columns]

    def restricted(self, contacts: np.ndarray, dim: int, gaps: np.ndarray) -> LocalForm:
        """The form of the contacts ``contacts`` (indices) only, on initial gaps ``gaps``
        (m, one per kept contact): rows and blocks of this one, its influence shared and its
        ``W`` gathered when first used."""
        rows = (dim * np.asarray(contacts, dtype=int)[:, None] + np.arange(dim)).ravel()
        twin = copy.copy(self)
        twin.operator = self.operator[rows]
        twin._columns = rows if self._columns is None else self._columns[rows]
        twin._delassus = self._delassus.block(rows)
        twin.offset = np.zeros(len(rows))
        twin.offset[::dim] = gaps
        twin._templates = {}  # its W is new: no shared local problem
        return twin

    def free_displacements(self, loads: np.ndarray) -> np.ndarray:
        """``R P`` (m); of a flexibility model, read on the columns of the loaded freedoms
        when they are few."""
        return _sparse_product(self._model, loads)

    def q(self, loads: np.ndarray) -> np.ndarray:
        """``H R P + w`` (m): the local displacements the loads cause without contact forces."""
        return self.operator @ self.free_displacements(loads) + self.offset

    def displacements(
        self, loads: np.ndarray, forces: np.ndarray, free: np.ndarray | None = None
    ) -> np.ndarray:
        """``U = R (P + H^T r)`` (m) for local forces ``r`` (N, shape (d k,)); ``free`` is
        ``R P`` when known. Only the columns of ``R H^T`` under nonzero forces are read."""
        if free is None:
            free = self.free_displacements(loads)
        if self._columns is None and np.all(forces != 0):
            return free + self._influence @ forces
        used = np.flatnonzero(forces)
        columns = used if self._columns is None else self._columns[used]
        return free + forces[used] @ self._influence.T[columns]  # rows of (R H^T)^T

    def local_template(self, law: FrictionLaw) -> LocalProblem:
        """``W`` as a :class:`LocalProblem` with ``law``'s ``mu`` and cohesion (q zero),
        validated once per law: each step's local problem is its ``with_q``."""
        return self._template("local", law)

    def fclib_template(self, law: FrictionLaw) -> LocalProblem:
        """``W / max diag(W)`` as a :class:`LocalProblem` with ``law``'s ``mu`` (q zero),
        scaled and validated once per law: each step's FCLIB problem is its ``with_q``."""
        return self._template("fclib", law)

    def _template(self, view: str, law: FrictionLaw) -> LocalProblem:
        cached = self._templates.get((view, id(law)))
        if cached is None or cached[0] is not law:
            zeros = np.zeros(self.operator.shape[0])
            if view == "local":
                problem = LocalProblem(self.W, zeros, law.mu, self.dim, cohesion=law.cohesion)
            else:
                problem = LocalProblem(self.W / np.max(self.diagonal()), zeros, law.mu, self.dim)
            cached = self._templates[view, id(law)] = (law, problem)
        return cached[1]


class FrictionStep:
    """One increment of a :class:`FrictionalProblem`: its local problem in three views.

    The two :class:`LocalProblem` views (:attr:`local`, :attr:`fclib`) are made when first
    read: the certificate needs neither, so a result built from a method's forces never forms
    ``W`` for them.

    Attributes
    ----------
    tangential : ndarray, shape (k, d - 1)
        ``(H U_prev)_T`` (m), the origin of the step's slips.
    q : ndarray, shape (d k,)
        ``H R P + w - (0, (H U_prev)_T)`` (m): the step's ``q`` in the model's units.
    apex_shift : ndarray, shape (d k,)
        Forces from the cones' apices: ``r~ = r + apex_shift`` (N).
    q_apex : ndarray, shape (d k,)
        ``q - W apex_shift`` (m): the local displacements the loads cause with the apex forces
        applied.
    compliance : float
        ``w``, the largest diagonal entry of ``W`` (m/N).
    length : float
        ``L``, the largest ``|q~|`` (m; 1 when ``q~`` is zero).
    force_unit : float
        ``L / w`` (N): ``r = force_unit r_fclib - apex_shift``.
    """

    def __init__(self, tangential: np.ndarray, q: np.ndarray, law: FrictionLaw, form: LocalForm):
        self.tangential, self.q = tangential, q
        self._law, self._form = law, form
        shift = np.zeros((law.mu.shape[0], form.dim))
        if law.cohesion.any():
            shift[:, 0] = apex_distance(law.mu, law.cohesion)
        self.apex_shift = shift.reshape(-1)
        self.q_apex = q - form.W @ self.apex_shift if law.cohesion.any() else q
        self.compliance = float(np.max(form.diagonal()))
        self.length = float(np.max(np.abs(self.q_apex))) or 1.0
        self.force_unit = self.length / self.compliance

    @functools.cached_property
    def local(self) -> LocalProblem:
        """The step in the model's units (m, N), with the law's cohesion."""
        return self._form.local_template(self._law).with_q(self.q)

    @functools.cached_property
    def fclib(self) -> LocalProblem:
        """The dimensionless FCLIB problem the solvers receive: cones translated to their
        apices (no cohesion left), ``W / w`` and ``q~ / L``, so that a natural-map error weighs
        forces and displacements alike."""
        return self._form.fclib_template(self._law).with_q(self.q_apex / self.length)


class FrictionalProblem:
    r"""A contact problem with friction on a reduced model, solved from a given state.

    From the state of a previous result (``previous``, or from rest), the loads ``P`` are
    applied in one increment. The normal law acts on the total gap and the friction law on the
    slip increment ``s_T = (H U)_T - (H U_prev)_T``, so the step's local problem (see
    :meth:`local_problem`) is

    .. math::

        u = W r + q - \begin{pmatrix} 0 \\ (H U_{prev})_T \end{pmatrix},
        \qquad u_N = \text{gap}, \quad u_T = s_T,

    with ``r`` the total local forces, in the friction set of
    :class:`~contactqp.core.friction.FrictionLaw` and complementary to ``u`` (FCLIB's Coulomb
    problem for the exact cone without cohesion).

    Parameters
    ----------
    model : ReducedModel
        Contact nodes with 2 or 3 freedoms each (one frame dimension for all contacts).
    loads : array_like, shape (n_freedoms,)
        External forces ``P`` (N), totals (not increments).
    obstacles : sequence
        As for :class:`ContactProblem`; each direction towards the obstacle (from the first node
        of a pair towards the second) is its frame's normal, the tangents those of
        :func:`~contactqp.core.contact.tangent_basis`.
    mu : float or array_like, shape (k,)
        Friction coefficient per contact, >= 0.
    cohesion : float or array_like, shape (k,)
        Mohr-Coulomb cohesion per contact (N), >= 0, where ``mu > 0``: ``||r_T|| <= mu r_N + c``
        and tension up to ``c / mu`` (the cone's apex; see :mod:`contactqp.core.friction`): a bonded
        interface, so a cohesive contact must start closed (gap <= 0). One pulled open keeps
        pulling with ``c / mu`` (no tension cut-off): the result then carries a
        :class:`~contactqp.errors.ContactWarning` and says so in its message.
    facets : int, optional
        Replace each friction disc by the inscribed polygon of ``facets`` sides (>= 3), the
        method's linearised cone (3-D; in 2-D the cone is already linear).
    certificate_tol : float
        Largest relative residual the certificate accepts.
    previous : FrictionalResult, optional
        The state the increment starts from (None: rest): its tangential displacements are the
        origin of the slip increments and its forces the default warm start. The state is part
        of the problem because the step's local problem and its certificate depend on it; a
        load history chains ``with_loads(P, previous=result)``.

    Attributes
    ----------
    kind : str
        ``"frictional"`` for the exact cone, ``"frictional-polygonal"`` with ``facets`` (see
        :mod:`contactqp.methods.registry`).

    Raises
    ------
    InvalidInputError
        Bad loads, obstacles, ``mu``, ``cohesion``, ``facets`` or ``previous``; contact nodes
        with one freedom (no tangent) or with different numbers of freedoms.
    """

    def __init__(
        self,
        model: ReducedModel,
        loads,
        obstacles,
        mu,
        cohesion=0.0,
        facets=None,
        certificate_tol: float = CERTIFICATE_TOL,
        *,
        previous=None,
    ):
        self.loads = _checked_loads(model, loads, certificate_tol)
        self.model = model
        self.constraints = assemble_constraints(model, obstacles)
        self.frames = local_frames(model, self.constraints)
        if self.frames.dim == 1:
            raise InvalidInputError(
                "friction needs contact nodes with 2 or 3 freedoms: a node with one freedom has "
                "no tangent"
            )
        self.law = FrictionLaw(mu, cohesion, facets, n_contacts=self.n_contacts)
        _refuse_open_cohesion(self.law, self.constraints.gaps)
        self.certificate_tol = float(certificate_tol)
        self._local: LocalForm | None = None
        self._free_displacements: np.ndarray | None = None
        # restrictions to contact sets (restricted), shared with the with_loads twins
        self._restrictions: dict[bytes, FrictionalProblem] = {}
        self.previous = previous
        self._previous_tangential()  # checked now, not at the solve

    @property
    def kind(self) -> str:
        """``"frictional"`` (exact cone) or ``"frictional-polygonal"`` (``facets`` given)."""
        return "frictional" if self.law.facets is None else "frictional-polygonal"

    @property
    def frictionless(self) -> bool:
        """True when ``mu = 0`` on every contact (no cohesion then either)."""
        return not np.any(self.law.mu > 0)

    @property
    def n_contacts(self) -> int:
        """Number of contacts ``k``."""
        return self.constraints.n_constraints

    @property
    def dim(self) -> int:
        """Size of each contact block: 2 or 3."""
        return self.frames.dim

    def local(self) -> LocalForm:
        """The local form, assembled on first use and shared with :meth:`with_loads` copies."""
        if self._local is None:
            self._local = LocalForm(self.model, self.constraints, self.frames)
        return self._local

    def with_loads(self, loads, *, previous=None) -> FrictionalProblem:
        """The same contacts and law under other loads, from the state ``previous`` (None:
        rest); nothing is assembled again."""
        twin = copy.copy(self)
        twin.loads = _checked_loads(self.model, loads, self.certificate_tol)
        twin._local = self.local()
        twin._free_displacements = None
        twin.previous = previous
        twin._previous_tangential()
        return twin

    def with_gaps(self, gaps) -> FrictionalProblem:
        """The same model, contacts, law, loads and state with other initial gaps (m, shape
        (k,)): ``W`` and ``R H^T`` are shared, only the gaps' offset is new (a variation study's
        samples)."""
        values = finite_array(gaps, "gaps", 1, magnitude=MAX_MAGNITUDE)
        if values.shape != (self.n_contacts,):
            raise InvalidInputError(
                f"gaps must have shape ({self.n_contacts},), got {values.shape}"
            )
        _refuse_open_cohesion(self.law, values)
        twin = copy.copy(self)
        twin.constraints = dataclasses.replace(self.constraints, gaps=values)
        twin._free_displacements = None
        form = copy.copy(self.local())
        form.offset = np.zeros_like(form.offset)
        form.offset[:: self.dim] = values
        twin._local = form
        return twin

    def restricted(self, contacts, *, loads=None, gaps=None, previous=None) -> FrictionalProblem:
        """The same model and law on the contacts ``contacts`` only (e.g. those a fastener
        leaves), their local form sliced from this problem's: nothing is assembled again.

        The slice of a contact set (its ``W``, law and validated local problems) is kept and
        shared by every later restriction to the same contacts (a sequence's stages on each
        sample of a study): only the gaps, loads and state are new.

        Parameters
        ----------
        contacts : array_like of int
            Distinct indices of the kept contacts, in the order they take.
        loads : array_like, shape (n_freedoms,), optional
            External forces (N); this problem's by default.
        gaps : array_like, shape (len(contacts),), optional
            Initial gaps of the kept contacts (m); theirs in this problem by default.
        previous : FrictionalResult, optional
            The state the increment starts from, a result with the kept contacts (None: rest).
        """
        kept = np.asarray(contacts, dtype=int).reshape(-1)
        prototype = self._restrictions.pop(kept.tobytes(), None)
        if prototype is None:  # contacts checked, then sliced
            prototype = self._restriction(*_restricted_constraints(self.constraints, kept, None))
        self._restrictions[kept.tobytes()] = prototype  # the most recent last
        values = self.constraints.gaps[kept]
        if gaps is not None:
            values = finite_array(gaps, "gaps", 1, magnitude=MAX_MAGNITUDE)
            if values.shape != kept.shape:
                raise InvalidInputError(f"gaps must have shape ({kept.size},), got {values.shape}")
        if np.any((prototype.law.cohesion > 0) & (values > 0)):
            raise InvalidInputError("cohesion models a bonded interface, which starts closed")
        twin = copy.copy(prototype)
        twin.constraints = dataclasses.replace(prototype.constraints, gaps=values)
        form = copy.copy(prototype.local())  # W, influence and FCLIB templates shared
        form.offset = np.zeros_like(form.offset)
        form.offset[:: self.dim] = values
        twin._local = form
        twin._free_displacements = None
        twin.loads = (
            self.loads if loads is None else _checked_loads(self.model, loads, self.certificate_tol)
        )
        twin.previous = previous
        twin._previous_tangential()
        return twin

    def _restriction(self, kept: np.ndarray, constraints: Constraints) -> FrictionalProblem:
        """The problem on the contacts ``kept`` (checked; ``constraints`` their rows), this
        one's loads, from rest: sliced once, then kept by :meth:`restricted` (the last
        :data:`RESTRICTIONS_KEPT` contact sets)."""
        d = self.dim
        rows = (d * kept[:, None] + np.arange(d)).ravel()
        cached = copy.copy(self)
        cached.constraints = constraints
        frames = self.frames
        cached.frames = dataclasses.replace(
            frames,
            normals=frames.normals[kept],
            tangents=frames.tangents[kept],
            operator=frames.operator[rows],
        )
        law = self.law
        cached.law = FrictionLaw(
            law.mu[kept], law.cohesion[kept], law.facets, n_contacts=int(kept.size)
        )
        cached._local = self.local().restricted(kept, d, constraints.gaps)
        cached._restrictions = {}
        cached._free_displacements = None
        cached.previous = None
        while len(self._restrictions) >= RESTRICTIONS_KEPT:
            self._restrictions.pop(next(iter(self._restrictions)))
        return cached

    def _previous_tangential(self) -> np.ndarray:
        """``(H U_prev)_T`` of shape (k, d - 1): zero from rest."""
        previous = self.previous
        if previous is None:
            return np.zeros((self.n_contacts, self.dim - 1))
        if not isinstance(previous, FrictionalResult):
            raise InvalidInputError(
                f"previous must be a FrictionalResult or None, got {type(previous).__name__}"
            )
        if previous.tangential_displacements.shape != (self.n_contacts, self.dim - 1):
            raise InvalidInputError(
                f"previous has {len(previous.tangential_displacements)} contacts, this problem "
                f"{self.n_contacts}"
            )
        return previous.tangential_displacements

    def local_problem(self) -> LocalProblem:
        """The step's :class:`~contactqp.core.local_problem.LocalProblem` from :attr:`previous`.

        In the model's units (m, N), with the cohesion of the law; FCLIB's problem when there
        is none. To solve it, prefer :func:`~contactqp.solve` (which solves
        :attr:`FrictionStep.fclib`): in these
        units the natural-map error that the local solvers stop on weighs newtons against
        metres and, for a stiff ``W``, barely sees displacement errors
        (:func:`~contactqp.core.local_problem.natural_map_error`).
        """
        return self.step().local

    def step(self) -> FrictionStep:
        """The increment from :attr:`previous`, assembled once for method and certificate."""
        tangential = self._previous_tangential()
        form = self.local()
        q = (form.operator @ self._free() + form.offset).reshape(self.n_contacts, self.dim)
        q[:, 1:] -= tangential
        return FrictionStep(tangential, q.reshape(-1), self.law, form)

    def _free(self) -> np.ndarray:
        """``R P`` (m) of this problem's loads, computed once."""
        if self._free_displacements is None:
            self._free_displacements = self.local().free_displacements(self.loads)
        return self._free_displacements

    def make_result(
        self,
        forces,
        *,
        method: str,
        converged: bool,
        message: str,
        iterations: int,
        seconds: float,
        info: dict | None = None,
        step: FrictionStep | None = None,
    ) -> FrictionalResult:
        """Wrap local forces ``r`` (N, shape (d k,)) in a certified :class:`FrictionalResult`.

        ``step`` is :meth:`step` when the caller has it already. Forces holding
        NaN or inf (an overflow, or a failed solve) fail the certificate (status 2) and the
        message says so; numpy's warnings are kept inside.
        """
        with np.errstate(all="ignore"):
            return self._result(
                forces,
                method=method,
                converged=converged,
                message=message,
                iterations=iterations,
                seconds=seconds,
                info=info,
                step=step,
            )

    def _result(
        self, forces, *, method, converged, message, iterations, seconds, info, step
    ) -> FrictionalResult:
        r = real_array(forces, "forces").reshape(-1)
        if r.shape != (self.n_contacts * self.dim,):
            raise InvalidInputError(
                f"forces must hold {self.dim} local components per contact "
                f"({self.n_contacts * self.dim} values), got shape {np.shape(forces)}"
            )
        local = self.local()
        U = local.displacements(self.loads, r, self._free())
        if step is None:
            step = self.step()
        tangential = step.tangential
        certificate = certify_friction(self, U, r, step, self.certificate_tol)
        status, success, message = _verdict(converged, certificate, message, self.model)
        k, d = self.n_contacts, self.dim
        R = r.reshape(k, d)
        HU = (local.operator @ U).reshape(k, d)
        slip = HU[:, 1:] - tangential
        force, length = contact_scales(self, HU, r, step)
        gaps = self.constraints.gaps + HU[:, 0]
        pulling = np.flatnonzero((self.law.cohesion > 0) & (gaps > self.certificate_tol * length))
        if pulling.size:
            note = (
                f"{pulling.size} cohesive contact(s) pulled open (first: contact "
                f"{pulling[0]}) still pull with their tensile strength c/mu: the model has no "
                f"tension cut-off, results past the opening are not physical"
            )
            warnings.warn(note, ContactWarning, stacklevel=4)
            message = f"{message}; {note}"
        nodal = local.operator.T @ r
        elastic = float(0.5 * U @ (self.loads + nodal))
        return FrictionalResult(
            displacements=U,
            forces=R,
            nodal_forces=nodal,
            gaps=gaps,
            contact_status=self.law.status(
                R, slip, CLOSED_RTOL * force, self.certificate_tol * length
            ),
            energy=elastic - float(self.loads @ U),
            success=success,
            status=status,
            message=message,
            iterations=int(iterations),
            seconds=float(seconds),
            method=method,
            certificate=certificate,
            info=dict(info or {}),
            slip=slip,
            tangential_displacements=HU[:, 1:],
            dissipation=-np.sum(R[:, 1:] * slip, axis=1),
            elastic_energy=elastic,
            loads=self.loads.copy(),
        )

    def __repr__(self) -> str:
        return (
            f"FrictionalProblem({self.model!r}, {self.n_contacts} contacts in {self.dim}-D, "
            f"{'exact cone' if self.law.facets is None else f'{self.law.facets} facets'})"
        )


def _refuse_open_cohesion(law: FrictionLaw, gaps: np.ndarray) -> None:
    """Raise when a cohesive contact starts open (gap > 0)."""
    gapped = np.flatnonzero((law.cohesion > 0) & (gaps > 0))
    if gapped.size:
        raise InvalidInputError(
            f"cohesion models a bonded interface, which starts closed: contact {gapped[0]} "
            f"has cohesion {law.cohesion[gapped[0]]:g} N and initial gap "
            f"{gaps[gapped[0]]:g} m (it would pull itself shut)"
        )


def _verdict(converged: bool, certificate, message: str, model) -> tuple[int, bool, str]:
    """:func:`~contactqp.core.result.verdict`, saying when the model was symmetrised to be
    solved: the certificate judges the matrix as given, so its asymmetry bounds the equilibrium
    residual attainable."""
    note = ""
    if model.asymmetry > 0.0 and certificate.equilibrium > certificate.tol:
        note = (
            f"; the model's matrix was solved as its symmetric part (relative asymmetry "
            f"{model.asymmetry:.1e} as given), which limits the equilibrium residual "
            f"on the matrix as given"
        )
    return verdict(converged, certificate, message, note)

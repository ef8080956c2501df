r"""Linear links between the freedoms of a reduced model, eliminated by the Woodbury identity.

A link has ``m`` components. Component ``j`` measures the relative displacement
``e_j^T U`` (``e_j`` the ``j``-th column of ``E``, shape (n_freedoms, m)), carries the force
``f_j`` (applied to the model as ``E f``) and obeys

.. math::

    E^T U + C f = d_0, \qquad C = \operatorname{diag}(c), \quad c_j \ge 0,

with ``c_j`` its compliance (m/N; 0 for a rigid link, a bilateral constraint) and ``d_0`` its
reference (m). An elastic component (``c_j > 0``) is a spring of stiffness ``1 / c_j`` whose
force vanishes at ``e_j^T U = d_{0,j}``. On a model ``U = R (P + E f)`` the link forces and
displacements are

.. math::

    f = S^{-1} (d_0 - E^T R P), \qquad S = C + E^T R E, \qquad
    U = R' P + R E S^{-1} d_0, \qquad R' = R - R E S^{-1} E^T R,

the Woodbury (push-through) identity, which holds for rigid and elastic components alike; for
``c > 0`` everywhere, ``R' = (K + E C^{-1} E^T)^{-1}``. Contact forces ``x`` entering through
an operator ``G`` (``U = R (P + G^T x + E f)``) see the linked model through

.. math::

    G U = G R P + B S^{-1} (d_0 - E^T R P) + (W - B S^{-1} B^T) x,
    \qquad f = S^{-1} (d_0 - E^T R P - B^T x),

with ``W = G R G^T`` and ``B = G R E``: a contact problem on ``W' = W - B S^{-1} B^T`` (a Schur
complement, as :mod:`~contactqp.core.fastened` eliminates rigid closures).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidInputError
from .model import ReducedModel, finite_array
from .operators import Operator, is_sparse

__all__ = ["Links", "LinkedModel", "ReducedOperator"]

#: ``S``'s smallest Cholesky pivot below this fraction of its largest: links not independent.
SINGULAR_PIVOT = 1e-12


@dataclass(frozen=True)
class Links:
    """The components of linear links: directions ``E``, compliances ``c``, references ``d0``.

    Parameters
    ----------
    directions : array_like, shape (n_freedoms, m)
        ``E``: column ``j`` gives the relative displacement ``e_j^T U`` component ``j``
        measures (m) and the pattern of its force on the model (``E f``, N).
    compliance : array_like, shape (m,)
        ``c >= 0`` (m/N): 0 for a rigid component.
    reference : array_like, shape (m,)
        ``d0`` (m): ``E^T U + c f = d0``.
    """

    directions: np.ndarray
    compliance: np.ndarray
    reference: np.ndarray

    def __init__(self, directions: ArrayLike, compliance: ArrayLike, reference: ArrayLike):
        if is_sparse(directions):
            directions = directions.toarray()
        E = finite_array(directions, "link directions", 2)
        m = E.shape[1]
        c = finite_array(np.reshape(compliance, -1), "link compliance", 1)
        d0 = finite_array(np.reshape(reference, -1), "link reference", 1)
        if c.shape != (m,) or d0.shape != (m,):
            raise InvalidInputError(
                f"link compliance and reference must hold one value per component ({m}), got "
                f"shapes {c.shape} and {d0.shape}"
            )
        if np.any(c < 0):
            raise InvalidInputError(
                f"link compliance must be >= 0, got {c.min():g} at component {int(np.argmin(c))}"
            )
        empty = np.flatnonzero(~np.any(E != 0, axis=0))
        if empty.size:
            raise InvalidInputError(f"link component {empty[0]} has a zero direction")
        object.__setattr__(self, "directions", E)
        object.__setattr__(self, "compliance", c)
        object.__setattr__(self, "reference", d0)

    @property
    def n_components(self) -> int:
        """Number of link components ``m``."""
        return int(self.directions.shape[1])

    @property
    def n_freedoms(self) -> int:
        """Number of freedoms of the model the links join."""
        return int(self.directions.shape[0])

    def relative(self, displacements: ArrayLike) -> np.ndarray:
        """``E^T U`` (m): the relative displacement each component measures."""
        return self.directions.T @ np.asarray(displacements, dtype=float)

    def residual(self, displacements: ArrayLike, forces: ArrayLike) -> np.ndarray:
        """``E^T U + C f - d0`` (m), zero when the links hold."""
        return self.relative(displacements) + self.compliance * forces - self.reference


class LinkedModel:
    """A reduced model with links: ``S = C + E^T R E`` factored once, ``R E`` kept.

    Parameters
    ----------
    model : ReducedModel
    links : Links
        On the model's freedoms.
    influence : array_like, shape (n_freedoms, m), optional
        ``R E`` when the caller has it (e.g. cached per link); computed otherwise.

    Raises
    ------
    InvalidInputError
        The links do not match the model, or are not independent (``S`` singular: e.g. two
        rigid components measuring the same relative displacement).
    """

    def __init__(self, model: ReducedModel, links: Links, influence: ArrayLike | None = None):
        if links.n_freedoms != model.n_freedoms:
            raise InvalidInputError(
                f"links act on {links.n_freedoms} freedoms, the model has {model.n_freedoms}"
            )
        self.model, self.links = model, links
        E = links.directions
        if influence is None:
            self.influence = np.asarray(model.displacements(E)).reshape(E.shape)
        else:
            self.influence = finite_array(influence, "link influence", 2)
            if self.influence.shape != E.shape:
                raise InvalidInputError(
                    f"link influence must have shape {E.shape}, got {self.influence.shape}"
                )
        S = E.T @ self.influence
        S = 0.5 * (S + S.T) + np.diag(links.compliance)
        self.schur = S
        self._factor = _cholesky(S) if links.n_components else None

    @property
    def n_components(self) -> int:
        """Number of link components ``m``."""
        return self.links.n_components

    def with_reference(self, reference: ArrayLike) -> LinkedModel:
        """The same links (``S`` factored, ``R E`` kept) with other references ``d0`` (m,
        shape (m,)): only ``d0`` is new, e.g. on another sample's gaps."""
        d0 = finite_array(np.reshape(reference, -1), "link reference", 1)
        if d0.shape != (self.n_components,):
            raise InvalidInputError(
                f"link reference must hold one value per component ({self.n_components}), "
                f"got shape {d0.shape}"
            )
        links = copy.copy(self.links)
        object.__setattr__(links, "reference", d0)
        twin = copy.copy(self)
        twin.links = links
        return twin

    def solve_schur(self, rhs: ArrayLike) -> np.ndarray:
        """``S^{-1} rhs`` for ``rhs`` of shape (m,) or (m, p)."""
        import scipy.linalg

        values = np.asarray(rhs, dtype=float)
        if self._factor is None:
            return np.zeros_like(values)
        return scipy.linalg.cho_solve(self._factor, values, check_finite=False)

    def forces(self, free_relative: ArrayLike) -> np.ndarray:
        """Link forces ``f = S^{-1} (d0 - E^T U_0)`` (N) for ``E^T U_0`` (m), ``U_0`` the
        displacements every other force causes (``R P``, contact forces included)."""
        return self.solve_schur(self.links.reference - np.asarray(free_relative, dtype=float))

    def displacements(self, loads: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """``(U, f)``: displacements (m) and link forces (N) under ``loads`` ``P`` (N)."""
        free = self.model.displacements(loads)
        f = self.forces(self.links.relative(free))
        return free + self.influence @ f, f

    def coupling(self, operator) -> np.ndarray:
        """``B = G R E`` (shape (p, m)) for a contact operator ``G`` (sparse or dense, (p, n))."""
        return np.asarray(operator @ self.influence)

    def reduced_operator(self, W: ArrayLike, coupling: ArrayLike) -> np.ndarray:
        """``W' = W - B S^{-1} B^T``: the contact operator ``W = G R G^T`` (symmetric) with
        the links."""
        import scipy.linalg

        B = np.asarray(coupling, dtype=float)
        if self._factor is None:
            return np.array(W, dtype=float)
        # S = L L^T: B S^-1 B^T = X^T X with X = L^-1 B^T, symmetric by construction
        X = scipy.linalg.solve_triangular(
            self._factor[0], np.ascontiguousarray(B.T), lower=True, check_finite=False
        )
        X = np.ascontiguousarray(X)
        correction = X.T @ X  # a symmetric rank-m product (BLAS syrk)
        return np.subtract(np.asarray(W, dtype=float), correction, out=correction)

    def reduced(self, W: np.ndarray, rows: ArrayLike, coupling: ArrayLike) -> ReducedOperator:
        """``W'`` of :meth:`reduced_operator` scaled by its largest diagonal, as an operator
        that reads ``W`` (the contact operator of a larger set, ``rows`` the contacts' rows
        in it) only where asked: ``B = G R E`` on those rows."""
        import scipy.linalg

        B = np.asarray(coupling, dtype=float)
        if self._factor is None:
            return ReducedOperator(W, rows, None)
        X = scipy.linalg.solve_triangular(
            self._factor[0], np.ascontiguousarray(B.T), lower=True, check_finite=False
        )
        return ReducedOperator(W, rows, np.ascontiguousarray(X))

    def offset(self, coupling: ArrayLike, free_relative: ArrayLike) -> np.ndarray:
        """``B S^{-1} (d0 - E^T R P)`` (m): what the links add to ``G R P``."""
        return np.asarray(coupling, dtype=float) @ self.forces(free_relative)

    def flexibility(self) -> np.ndarray:
        """``R' = R - R E S^{-1} E^T R`` (m/N), dense: the linked model's flexibility (its
        links' references aside)."""
        R = self.model.flexibility
        if self._factor is None:
            return R.copy()
        linked = R - self.influence @ self.solve_schur(self.influence.T)
        return 0.5 * (linked + linked.T)


class ReducedOperator(Operator):
    r"""``W' = (W_{cc} - X^T X) / w`` read lazily: blocks, diagonal and products, never formed
    unless :attr:`matrix` is asked for.

    ``W_cc = W[rows][:, rows]`` is the contact operator of the remaining contacts (``W`` that of
    a larger set, e.g. every pair of an assembly, symmetric), ``X = L^{-1} B^T`` with
    ``S = L L^T`` the links' Schur matrix and ``B = G R E`` (so ``X^T X = B S^{-1} B^T``, the
    links' rank-``m`` correction), and ``w`` the largest diagonal entry of ``W_cc - X^T X``:
    the dimensionless FCLIB operator of a linked stage (:meth:`LinkedModel.reduced`). A block on
    ``p`` rows and ``q`` columns costs ``p q (m + 1)``; :attr:`matrix` the full product, as
    :meth:`LinkedModel.reduced_operator`.

    Parameters
    ----------
    W : ndarray, shape (N, N)
        Symmetric, not copied.
    rows : array_like of int, shape (n,)
        The remaining contacts' rows (and columns) in ``W``.
    factor : ndarray, shape (m, n), or None
        ``X``; None without links.
    """

    def __init__(self, W: np.ndarray, rows: ArrayLike, factor: np.ndarray | None):
        self._W = W
        self.rows = np.asarray(rows, dtype=np.intp).reshape(-1)
        n = self.rows.size
        super().__init__((n, n))
        self._X = factor if factor is not None and factor.shape[0] else None
        diagonal = np.diagonal(W)[self.rows].copy()
        if self._X is not None:
            diagonal -= np.einsum("ij,ij->j", self._X, self._X)
        self.scale = float(np.max(diagonal, initial=0.0)) or 1.0
        self._diagonal = diagonal / self.scale

    def diagonal(self) -> np.ndarray:
        return self._diagonal

    def block(self, rows=None, cols=None) -> np.ndarray:
        n = self.shape[0]
        r = np.arange(n)[rows] if rows is not None else np.arange(n)
        c = np.arange(n)[cols] if cols is not None else np.arange(n)
        W = self._W
        if c.size < r.size:  # W is symmetric: the fewer rows read whole, then transposed
            picked = W.take(self.rows[c], axis=0).take(self.rows[r], axis=1).T.copy()
        else:
            picked = W.take(self.rows[r], axis=0).take(self.rows[c], axis=1)
        if self._X is not None:
            picked -= self._X[:, r].T @ self._X[:, c]
        picked /= self.scale
        return picked

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        full = np.zeros((self._W.shape[0],) + x.shape[1:])
        full[self.rows] = x
        product = (self._W @ full)[self.rows]
        if self._X is not None:
            product -= self._X.T @ (self._X @ x)
        return product / self.scale

    @property
    def matrix(self) -> np.ndarray:
        """The dense ``W'`` (``n x n``), formed on each call."""
        W = self._W.take(self.rows, axis=0).take(self.rows, axis=1)
        if self._X is not None:
            W -= self._X.T @ self._X
        W /= self.scale
        return W


def _cholesky(S: np.ndarray) -> tuple[np.ndarray, bool]:
    """Cholesky factor of ``S``; refused when the links are not independent."""
    import scipy.linalg

    scale = float(np.max(np.abs(np.diag(S)), initial=0.0))
    try:
        factor = scipy.linalg.cho_factor(S, lower=True, check_finite=False)
    except np.linalg.LinAlgError:
        factor = None
    pivots = np.diag(factor[0]) ** 2 if factor is not None else np.zeros(1)
    if factor is None or scale <= 0 or pivots.min() <= SINGULAR_PIVOT * scale:
        raise InvalidInputError(
            f"the links are not independent: S = C + E^T R E ({len(S)} x {len(S)}) is singular "
            f"(two rigid components constrain the same relative displacement?)"
        )
    return factor

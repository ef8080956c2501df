r"""Friction laws on local contact forces: Coulomb, Mohr-Coulomb, exact and polygonal cones.

Per contact, with the compressive normal force :math:`r_N` (N) and the tangential force
:math:`r_T` on the body (N, ``d - 1`` components in the local frame), the admissible forces are
the (Mohr-)Coulomb cone

.. math::

    C_i = \{ \|r_T\| \le \mu_i r_N + c_i \}, \qquad r_N \ge -c_i / \mu_i ,

Coulomb's for cohesion :math:`c_i = 0`. With cohesion the cone is Coulomb's translated to its
apex :math:`r_N = -c_i/\mu_i` (the law of :class:`~contactqp.core.local_problem.LocalProblem`):
a closed contact carries shear up to :math:`c_i` without normal force and tension up to
:math:`c_i/\mu_i`, and the gap opens when that tension is reached (perfectly plastic, no
softening: an open cohesive contact keeps transmitting :math:`c_i/\mu_i`). The normal law acts on
the force measured from the apex, :math:`\tilde r = r + (c/\mu) e_N`: :math:`\tilde r_N \ge 0`,
gap :math:`\ge 0`, and :math:`\tilde r = 0` where the gap is open.

The *polygonal* law of the method replaces the disc :math:`\|r_T\| \le s` by the inscribed
regular polygon of ``facets`` sides :math:`n_k \cdot r_T \le s \cos(\pi / F)`, with the outward
normals :math:`n_k` of :func:`polygon_normals` (vertices on the circle
at the angles :math:`(2k + 1)\pi / F`). In 2-D the tangential "disc" is the segment
:math:`|r_T| \le s`, which every polygon reproduces: the polygonal law is then exact.

The slip :math:`s_T` (m) obeys maximum dissipation: the friction force does the most negative
work over the admissible set, :math:`-r_T \cdot s_T = \max_{f \in D} f \cdot (-s_T)` with ``D``
the disc or polygon of radius :math:`\mu r_N + c`; so :math:`r_T = -(\mu r_N + c) s_T / \|s_T\|`
on the exact cone whenever :math:`s_T \ne 0`.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidInputError
from .model import finite_array
from .status import ContactStatus

__all__ = ["FrictionLaw", "MAX_FACETS", "apex_distance", "polygon_normals"]

_OPEN, _STICK, _SLIP = int(ContactStatus.OPEN), int(ContactStatus.STICK), int(ContactStatus.SLIP)


#: Most sides of a polygonal cone: 1024 sides are within 5e-6 of the circle, and more would only
#: add rows to every cone program; the exact cone (``facets=None``) is the route beyond that.
MAX_FACETS = 1024


def polygon_normals(facets: int) -> np.ndarray:
    """Outward unit normals of the regular polygon of ``facets`` sides, shape (facets, 2).

    Side ``k`` is orthogonal to the angle ``2 pi k / facets`` (side 0 across the first tangent
    axis) at the distance ``cos(pi / facets)`` from the centre of the unit circle.
    """
    if (
        isinstance(facets, bool)
        or not isinstance(facets, numbers.Integral)
        or facets < 3
        or facets > MAX_FACETS
    ):
        raise InvalidInputError(
            f"facets must be an integer from 3 to {MAX_FACETS} (beyond, use "
            f"the exact cone), got {facets!r}"
        )
    angles = 2.0 * np.pi * np.arange(int(facets)) / int(facets)
    return np.column_stack([np.cos(angles), np.sin(angles)])


def _per_contact(value: ArrayLike, name: str, count: int) -> np.ndarray:
    """A scalar or a ``(count,)`` array of finite values ``>= 0``, as a ``(count,)`` array."""
    scalar = np.ndim(value) == 0
    array = finite_array(np.atleast_1d(value) if scalar else value, name, 1)
    if scalar:
        array = np.full(count, array[0])
    elif array.shape != (count,):
        raise InvalidInputError(
            f"{name} must be a scalar or hold one value per contact ({count}), got shape "
            f"{array.shape}"
        )
    if (array < 0).any():
        raise InvalidInputError(
            f"{name} must be >= 0, got {array.min():g} at contact {int(np.argmin(array))}"
        )
    return array


def apex_distance(mu: np.ndarray, cohesion: np.ndarray) -> np.ndarray:
    """``c / mu`` per contact (N): how far the Mohr-Coulomb cone's apex lies below ``r_N = 0``
    (zero without cohesion; cohesion needs ``mu > 0``)."""
    distance = np.zeros(np.shape(mu))
    np.divide(cohesion, mu, out=distance, where=np.asarray(cohesion) > 0)
    return distance


@dataclass(frozen=True)
class FrictionLaw:
    """Friction coefficients, cohesions and the cone (exact or polygonal) of ``k`` contacts.

    Parameters
    ----------
    mu : array_like, shape () or (k,)
        Friction coefficients, >= 0.
    cohesion : array_like, shape () or (k,)
        Cohesion ``c`` (N): the tangential force a closed contact carries without normal force.
    facets : int, optional
        Sides of the polygon replacing each friction disc (>= 3); None for the exact cone.
    n_contacts : int
        ``k``, to which scalars are broadcast.

    Raises
    ------
    InvalidInputError
        ``mu`` or ``cohesion`` negative, NaN, inf or of the wrong length; cohesion where
        ``mu = 0`` (the cone has no apex); ``facets`` not an integer from 3 to
        :data:`MAX_FACETS`.
    """

    mu: np.ndarray
    cohesion: np.ndarray
    facets: int | None

    def __init__(
        self,
        mu: ArrayLike,
        cohesion: ArrayLike = 0.0,
        facets: int | None = None,
        *,
        n_contacts: int,
    ) -> None:
        object.__setattr__(self, "mu", _per_contact(mu, "mu", n_contacts))
        object.__setattr__(self, "cohesion", _per_contact(cohesion, "cohesion", n_contacts))
        bad = np.flatnonzero((self.cohesion > 0) & (self.mu == 0))
        if bad.size:
            raise InvalidInputError(
                f"cohesion > 0 needs mu > 0 (the cone's apex is at r_N = -c/mu): contact "
                f"{bad[0]} has mu = 0 and cohesion {self.cohesion[bad[0]]:g}"
            )
        if facets is not None:
            polygon_normals(facets)
            facets = int(facets)
        object.__setattr__(self, "facets", facets)

    @classmethod
    def from_checked(cls, mu: np.ndarray, cohesion: np.ndarray) -> FrictionLaw:
        """The exact-cone law of arrays already checked as :class:`FrictionLaw` checks them
        (float, shape (k,), finite, ``>= 0``, cohesion only where ``mu > 0``), stored as they
        are, without checking them again."""
        law = object.__new__(cls)
        object.__setattr__(law, "mu", mu)
        object.__setattr__(law, "cohesion", cohesion)
        object.__setattr__(law, "facets", None)
        return law

    @property
    def n_contacts(self) -> int:
        """Number of contacts ``k``."""
        return int(self.mu.size)

    def apex_forces(self, forces: ArrayLike) -> np.ndarray:
        """Local forces measured from the cone's apex, ``r + (c / mu) e_N``, shape (k, d)."""
        shifted = np.array(forces, dtype=float)
        shifted[:, 0] += apex_distance(self.mu, self.cohesion)
        return shifted

    def bound(self, normal_forces: ArrayLike) -> np.ndarray:
        """Radius ``mu r_N + c`` of each friction disc (N), for normal forces ``(k,)``."""
        return self.mu * np.asarray(normal_forces, dtype=float) + self.cohesion

    @staticmethod
    def _vertices(facets: int) -> np.ndarray:
        """Unit vertices of the polygon of ``facets`` sides in the tangent plane, (facets, 2).

        Vertex ``k`` joins sides ``k`` and ``k + 1``: it is along the sum of their normals.
        """
        normals = polygon_normals(facets)
        vertices = normals + np.roll(normals, -1, axis=0)
        return vertices / np.linalg.norm(vertices, axis=1)[:, None]

    def support(self, vectors: ArrayLike) -> np.ndarray:
        """Support function of the unit disc (or polygon) at tangential vectors ``(k, d - 1)``.

        ``max_{f in D_1} f . x``: the norm for the exact cone (and in 2-D), the largest vertex
        projection for a 3-D polygon. Times the bound, it is the largest friction work.
        """
        x = np.asarray(vectors, dtype=float)
        if self.facets is None or x.shape[1] != 2:
            return np.linalg.norm(x, axis=1)
        return np.max(x @ self._vertices(self.facets).T, axis=1)

    def gauge(self, vectors: ArrayLike) -> np.ndarray:
        """Gauge of the unit disc (or polygon): ``x`` is in ``t D_1`` iff ``gauge(x) <= t``."""
        x = np.asarray(vectors, dtype=float)
        if self.facets is None or x.shape[1] != 2:
            return np.linalg.norm(x, axis=1)
        return np.max(x @ polygon_normals(self.facets).T, axis=1) / np.cos(np.pi / self.facets)

    def cone_excess(self, forces: ArrayLike) -> np.ndarray:
        """``gauge(r_T) - (mu r_N + c)`` per contact (N): positive outside the friction set.

        ``forces``: local forces, shape (k, d), normal first.
        """
        r = np.asarray(forces, dtype=float)
        return self.gauge(r[:, 1:]) - self.bound(r[:, 0])

    def dissipation_gap(self, forces: ArrayLike, slips: ArrayLike) -> np.ndarray:
        """``(mu r_N + c) support(-s_T) + r_T . s_T`` per contact (J), zero under the law.

        It is >= 0 for admissible forces, and zero exactly when the friction force does the
        largest negative work on the slip (maximum dissipation).
        """
        r = np.asarray(forces, dtype=float)
        s = np.asarray(slips, dtype=float)
        return self.bound(r[:, 0]) * self.support(-s) + np.sum(r[:, 1:] * s, axis=1)

    def status(
        self, forces: ArrayLike, slips: ArrayLike, force_tol: ArrayLike, slip_tol: ArrayLike
    ) -> np.ndarray:
        """:class:`~contactqp.core.status.ContactStatus` code per contact: open, stick or slip.

        Open: the force measured from the apex is zero (``||r~|| <= force_tol``, N). Slip:
        closed and ``||s_T|| > slip_tol`` (m). Stick otherwise. Each tolerance is a scalar or
        holds one value per contact.
        """
        measured = self.apex_forces(forces) if self.cohesion.any() else forces
        carries = np.linalg.norm(measured, axis=1) > force_tol
        slipping = np.linalg.norm(np.asarray(slips, dtype=float), axis=1) > slip_tol
        return np.where(carries, np.where(slipping, _SLIP, _STICK), _OPEN)

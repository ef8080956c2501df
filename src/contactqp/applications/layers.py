r"""Two soil layers with a frictional interface under gravity and a growing lateral load.

Model
-----
Two elastic layers in plane strain (:class:`~contactqp.compliance.fem.ElasticModel`, a slice of
``depth`` metres): the lower one clamped at its base, the upper one resting on it through the
interface, a line of node pairs (:class:`~contactqp.core.contact.NodePairs`, normal ``+y``) with the
Mohr-Coulomb law of :class:`~contactqp.core.friction.FrictionLaw`: ``|r_T| <= mu r_N + c_i``, the
cohesion ``c_i`` of a contact being the cohesion (Pa) times its tributary area. The upper layer
carries its weight and is pushed sideways over its left side by an actuator, springs spread
evenly over the side (stiffness ``k_a`` in all) whose far ends move by ``d``: the lateral load
is ``H = sum_j k_j (d - u_j)``, so the load can be followed past the onset of sliding (a load
control would have no equilibrium beyond it).
The upper layer's vertical rigid motions are held by soft springs on its top (``k_s`` per node,
carrying ``k_s`` times the settlement of each top node: the normal force at the interface is
reported, to be compared with the weight).

Both layers are condensed (:func:`~contactqp.compliance.condensation.condense`) to the interface
nodes and the nodes of the upper layer's left side; gravity enters through the loads that give,
on these nodes, the displacements of the full model under gravity alone. The history
``d = 0 .. d_max`` (gravity first) is solved by
:func:`~contactqp.methods.history.solve_history`, the
friction state carried over.

The analytic limit of the sliding block: when no contact sticks, the interface carries
``H = sum_i (mu r_N,i + c_i) = c A + mu N`` with ``A`` the interface area and ``N`` the normal
force, here the weight of the upper layer. Sliding starts when the load reaches it.
"""

from __future__ import annotations

import math
import numbers
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.linalg
import scipy.sparse

from ..core.contact import NodePairs
from ..core.history import MAX_STEPS
from ..core.model import ReducedModel
from ..core.problem import FrictionalProblem
from ..core.status import ContactStatus
from ..errors import InvalidInputError, LayersError
from ..methods import solve_history

__all__ = ["Layers", "LayersResult", "plot_layers"]


@dataclass(frozen=True)
class Layers:
    """Geometry, materials, interface and loading of the two-layer problem (SI units).

    Defaults: 10 m long, lower layer 2 m and upper layer 1 m thick, a 1 m slice; soil of density
    2000 kg/m^3, ``E = 50 MPa``, ``nu = 0.3``; interface ``mu = 0.5`` and cohesion 5 kPa.
    """

    length: float = 10.0
    lower_height: float = 2.0
    upper_height: float = 1.0
    depth: float = 1.0
    density: float = 2000.0
    young: float = 50e6
    poisson: float = 0.3
    mu: float = 0.5
    cohesion: float = 5e3
    gravity: float = 9.81
    cells: tuple = (20, 4, 4)
    actuator_stiffness: float = 2e7
    support_stiffness: float = 1e3
    steps: int = 40

    def __post_init__(self):
        positive = (
            "length",
            "lower_height",
            "upper_height",
            "depth",
            "density",
            "young",
            "actuator_stiffness",
            "support_stiffness",
        )
        for name in (*positive, "poisson", "mu", "cohesion", "gravity"):
            value = getattr(self, name)
            low_open = name in positive
            if (
                isinstance(value, bool)
                or not isinstance(value, numbers.Real)
                or not math.isfinite(value)
                or value < 0
                or (low_open and value == 0)
            ):
                raise InvalidInputError(
                    f"{name} must be finite and {'>' if low_open else '>='} 0, got {value!r}"
                )
        if not self.poisson < 0.5:
            raise InvalidInputError(f"poisson must be < 0.5, got {self.poisson!r}")
        counts = (*tuple(self.cells), self.steps) if np.ndim(self.cells) == 1 else ()
        if len(counts) != 4 or any(
            isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1 for n in counts
        ):
            raise InvalidInputError(
                f"cells must be 3 integers >= 1 and steps an integer >= 1, "
                f"got {self.cells!r}, {self.steps!r}"
            )
        if self.steps >= MAX_STEPS:  # the history has steps + 1 load steps
            raise InvalidInputError(f"steps must be below {MAX_STEPS}, got {self.steps}")

    @property
    def area(self) -> float:
        """Interface area ``A = length x depth`` (m^2)."""
        return self.length * self.depth

    @property
    def weight(self) -> float:
        """Weight of the upper layer (N)."""
        return self.density * self.gravity * self.upper_height * self.length * self.depth

    @property
    def limit(self) -> float:
        """Analytic sliding load ``c A + mu N`` with ``N`` the weight of the upper layer (N)."""
        return self.cohesion * self.area + self.mu * self.weight

    def _layer(self, height: float, rows: int):
        from ..compliance.fem import ElasticModel, plate  # noqa: I001  (first: names the extra)
        import skfem

        body = ElasticModel(
            plate(self.length, height, self.cells[0], rows),
            self.young,
            self.poisson,
            plane="strain",
            thickness=self.depth,
        )

        @skfem.LinearForm
        def weight(v, _):
            return -self.density * self.gravity * v[1]

        return body, skfem.asm(weight, body.basis) * self.depth

    def reduced(self):
        """``(model, pairs, actuator, gravity_loads, cohesions)``.

        ``model``: the two layers condensed to the ``n`` lower interface nodes, the ``n``
        upper ones (ordered along ``x``), then the other nodes of the upper layer's left side
        (2 freedoms each); ``pairs``: (lower, upper) node indices; ``actuator``: the
        ``(nodes, stiffnesses)`` of the actuator's springs on the left side (N/m, summing to
        ``k_a``); ``gravity_loads`` (N, on the model's freedoms); ``cohesions`` (N, per pair).
        """
        from ..compliance.condensation import condense, factorize

        lower, lower_weight = self._layer(self.lower_height, self.cells[1])
        lower.fix("bottom")
        top = lower.select_nodes(where="top").nodes
        top = top[np.argsort(lower.mesh.p[0, top])]
        lower_model = lower.reduced_model(top)
        lower_free = lower.solve(lower_weight[lower.basis.nodal_dofs].T)[top].ravel()

        upper, upper_weight = self._layer(self.upper_height, self.cells[2])
        dofs = upper.basis.nodal_dofs
        bottom = upper.select_nodes(where="bottom").nodes
        bottom = bottom[np.argsort(upper.mesh.p[0, bottom])]
        side = upper.select_nodes(where="left").nodes
        side = side[np.argsort(upper.mesh.p[1, side])]  # from the corner on the interface up
        share = np.full(len(side), 1.0 / (len(side) - 1))  # trapezoidal rule: a uniform push
        share[[0, -1]] /= 2
        springs = np.zeros(upper.basis.N)
        springs[dofs[1, upper.select_nodes(where="top").nodes]] = self.support_stiffness
        springs[dofs[0, side]] += self.actuator_stiffness * share
        K = upper.stiffness + scipy.sparse.diags(springs)
        kept = np.concatenate([bottom, side[1:]])
        freedoms = dofs[:, kept].T.ravel()
        upper_all = factorize(K).solve(upper_weight)

        blocks = [lower_model.flexibility, condense(K, freedoms)]
        coords = np.vstack(
            [lower.mesh.p[:, top].T, upper.mesh.p[:, kept].T + [0.0, self.lower_height]]
        )
        model = ReducedModel(
            flexibility=scipy.linalg.block_diag(*blocks), dofs_per_node=2, coordinates=coords
        )
        free = np.concatenate([lower_free, upper_all[freedoms]])
        loads = model.forces(free)
        n = len(top)
        pairs = np.column_stack([np.arange(n), n + np.arange(n)])
        spacing = self.length / self.cells[0]
        tributary = np.full(n, spacing)
        tributary[[0, -1]] = spacing / 2
        actuator = (
            np.concatenate([[n], 2 * n + np.arange(len(side) - 1)]),
            self.actuator_stiffness * share,
        )
        return model, pairs, actuator, loads, self.cohesion * tributary * self.depth

    def solve(self, d_max: float | None = None, **options: Any) -> LayersResult:
        """Apply gravity, then move the actuator from 0 to ``d_max`` in :attr:`steps` steps.

        ``d_max`` (m) defaults to twice the travel that brings the load to the analytic limit
        when the spring and the upper layer stretched over its length act in series,
        ``2 H_lim (1 / k_a + length / (E h_upper depth))``: beyond the onset of sliding.
        ``options`` go to :func:`~contactqp.methods.history.solve_history` (``method``,
        ``progress``, the method's options).

        Raises
        ------
        LayersError
            A step failed (its message is given).
        """
        model, pairs, actuator, gravity, cohesions = self.reduced()
        n = len(pairs)
        if d_max is None:
            stretch = self.length / (self.young * self.upper_height * self.depth)
            d_max = 2.0 * self.limit * (1.0 / self.actuator_stiffness + stretch)
        travel = np.linspace(0.0, d_max, self.steps + 1)
        nodes, stiffness = actuator
        pull = np.zeros(model.n_freedoms)
        pull[2 * nodes] = stiffness
        problem = FrictionalProblem(
            model,
            gravity,
            [NodePairs(pairs, np.zeros(n), (0.0, 1.0))],
            mu=self.mu,
            cohesion=cohesions,
        )
        history = solve_history(problem, gravity + np.outer(travel, pull), **options)
        failed = next((k for k, step in enumerate(history.steps) if not step.success), None)
        if failed is not None:
            raise LayersError(
                f"step {failed} (actuator at {travel[failed]:.4g} m) not solved: "
                f"{history.steps[failed].message}"
            )
        U = history.displacements.reshape(len(travel), -1, 2)
        load = (travel[:, None] - U[:, nodes, 0]) @ stiffness
        relative = (U[:, n : 2 * n, 0] - U[:, :n, 0]).mean(axis=1)
        status = history.contact_status
        sliding = np.all(status != ContactStatus.STICK, axis=1) & np.any(
            status == ContactStatus.SLIP, axis=1
        )
        normal = history.forces[:, :, 0].sum(axis=1)
        return LayersResult(self, travel, load, relative, sliding, normal)


@dataclass(frozen=True)
class LayersResult:
    """The load history of :meth:`Layers.solve`, one entry per step (gravity alone first).

    Attributes
    ----------
    layers : Layers
    travel : ndarray, shape (K,)
        Actuator travel ``d`` (m).
    load : ndarray, shape (K,)
        Lateral load ``H`` on the upper layer (N).
    relative : ndarray, shape (K,)
        Mean relative horizontal displacement of the upper layer over the lower one along the
        interface (m).
    sliding : ndarray of bool, shape (K,)
        No contact sticks and some slip: the upper layer slides as a whole (a contact opened
        by the cohesive tension cut-off ``r_N = -c_i / mu`` carries no shear and is counted
        in ``c A + mu N`` with its ``mu r_N + c_i = 0``).
    normal_force : ndarray, shape (K,)
        Sum of the normal contact forces (N): the weight of the upper layer less what the soft
        supports carry.
    """

    layers: Layers
    travel: np.ndarray
    load: np.ndarray
    relative: np.ndarray
    sliding: np.ndarray
    normal_force: np.ndarray

    @property
    def onset(self) -> int | None:
        """Index of the first step in which the upper layer slides (None: it does not)."""
        hits = np.flatnonzero(self.sliding)
        return int(hits[0]) if hits.size else None

    @property
    def onset_force(self) -> float | None:
        """Lateral load at the onset of sliding (N)."""
        return None if self.onset is None else float(self.load[self.onset])

    def as_record(self) -> dict:
        """JSON-ready summary in SI units."""
        at = self.onset if self.onset is not None else -1
        layers = self.layers
        return {
            "mu": layers.mu,
            "cohesion": layers.cohesion,
            "area": layers.area,
            "normal_force": float(self.normal_force[at]),
            "weight": layers.weight,
            "analytic_onset_force": layers.limit,
            "onset_force": self.onset_force,
            "curve": np.column_stack([self.load, self.relative]).tolist(),
        }


def plot_layers(result: LayersResult, path: str | os.PathLike[str]) -> Path:
    """Lateral load against relative displacement, with the analytic limit (drawn by
    :func:`contactqp.io.plot.plot_sliding_curve`)."""
    from ..io.plot import plot_sliding_curve

    layers = result.layers
    return plot_sliding_curve(
        result.relative,
        result.load,
        layers.limit,
        path,
        onset=result.onset,
        title=f"Two layers: mu = {layers.mu:g}, c = {layers.cohesion:g} Pa",
    )

r"""Fastening sequences: fasteners installed one at a time, then load steps, friction carried.

A fastener is a link between the two nodes of its pair, in the pair frame ``(n, t1, t2)``: an
axial component (the opening ``n . (u_second - u_first)``) and, bonded, two tangential ones
(:mod:`contactqp.core.links`, ``E^T U + C f = d0``, force ``E f`` on the parts; the axial
tension is ``-f_n``):

* ``"closure"``: rigid axial, ``d0 = -g0``: the pair's gap is 0 from its installation on;
* ``"clamp"``: tightened to its preload ``F``: in the stage that installs it the fastener pulls
  with exactly ``F`` (an external load on the pair); from then on it is an axial spring of
  stiffness ``k`` about that state, tension ``F + k (d - d_inst)`` with ``d`` the pair's opening
  (it rises when the parts are pulled apart, falls when they come together). Where it presses
  the parts together, its pair *bears*: the gap is held at 0 (a rigid axial link, the tension
  still ``F + k (d - d_inst)``) and the difference between the link force and the tension is
  the compression the parts bear there, >= 0. Each stage switches clamps between spring and
  bearing until no pair penetrates and none bears in tension (a few solves at most);
* ``"bonded"`` shear: rigid tangential, ``d0_t`` the relative tangential displacement of the
  pair before its installation.

A fastened pair is no contact. Each stage eliminates the links from the contact problem of the
remaining pairs (``W' = W - B S^{-1} B^T``, the parts' ``W`` assembled once per assembly) and
solves it: without friction the non-negative QP on ``W'`` (Lawson-Hanson or the box QP); with
friction the step's local problem ``u = W' r + q'`` from the previous stage's state, by
:func:`~contactqp.solve` in the dimensionless form :class:`~contactqp.core.problem.FrictionStep`
gives it. The link forces follow, and the stage is certified as the parts' own problem with the
link forces as external loads (``make_result`` of a ContactProblem or FrictionalProblem), so
the certificate judges the parts' model, not the reduced one; each fastener's law is checked on
the recovered displacements, and a violated one fails the stage (status 2, the message naming
the fastener).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ...core.certificate import CERTIFICATE_TOL
from ...core.contact import local_frames
from ...core.links import LinkedModel, Links, ReducedOperator
from ...core.local_problem import LocalProblem
from ...core.model import finite_array, iteration_cap, positive_tolerance, real_array
from ...core.problem import ContactProblem, FrictionalProblem
from ...core.result import CERTIFICATE_FAILED, ContactResult, FrictionalResult
from ...core.status import ContactStatus
from ...errors import InvalidInputError
from ...methods import solve
from ...methods.box_qp import solve_box_qp
from ...methods.coulomb import ACTIVE_SET_MIN, solve_on_candidates
from ...methods.dispatch import resolve
from ...methods.lawson_hanson import solve_nonnegative_qp
from .parts import Fastener
from .stage import AssemblySequence, AssemblyStage

if TYPE_CHECKING:
    from ...core.contact import NodePairs
    from ...core.model import ReducedModel

__all__ = ["run_sequence", "AssemblyLayout", "FRICTIONLESS_METHODS"]

#: Methods of the frictionless reduced QP and the options each takes.
FRICTIONLESS_METHODS: dict[str, tuple[str, ...]] = {
    "lawson-hanson": ("tol",),
    "active-set": ("tol", "max_iter"),
}


class AssemblyLayout(Protocol):
    """What a sequence needs of an assembly
    (:class:`~contactqp.applications.fastening.model.Assembly`)."""

    fasteners: tuple[Fastener, ...]
    pairs: np.ndarray
    normals: np.ndarray
    tangents: np.ndarray
    dofs_per_node: int
    model: ReducedModel
    operators: dict  # what the stages share: linked models and reduced operators, by structure

    @property
    def n_pairs(self) -> int: ...

    @property
    def n_freedoms(self) -> int: ...

    @property
    def base_problem(self) -> ContactProblem | FrictionalProblem: ...

    def fastener_links(self, position: int) -> tuple[np.ndarray, np.ndarray]: ...

    def node_pairs(self, gaps, pairs=None) -> NodePairs: ...


@dataclass
class _Fastening:
    """An installed fastener: its link components (axial first, then the tangential ones) and
    the state of a clamp."""

    position: int
    fastener: Fastener
    columns: np.ndarray  # E, (n_freedoms, c)
    influence: np.ndarray  # R E
    gap: float  # the pair's initial gap (m)
    tangential: np.ndarray  # references of the tangential components (m)
    tightened: bool = False  # a clamp: False in the stage that tightens it
    opening: float = math.nan  # a clamp: the pair's opening once tightened (m)
    bearing: bool = False  # a clamp: the parts bear on each other at its pair (gap 0)

    @property
    def name(self) -> str:
        return f"fastener {self.position} (pair {self.fastener.pair})"

    @property
    def clamp(self) -> bool:
        return self.fastener.kind == "clamp"

    def axial(self) -> tuple[float, float] | None:
        """``(compliance, reference)`` of the axial link now; None while a clamp, not bearing,
        is tightened (its preload is then a load)."""
        if not self.clamp or self.bearing:
            return 0.0, -self.gap
        if not self.tightened:
            return None
        k = self.fastener.stiffness
        return 1.0 / k, self.opening - self.fastener.force / k

    def components(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(columns, compliance, reference)`` of the components that are links now."""
        axial = self.axial()
        if axial is None:
            return self.columns[:, 1:], np.zeros(len(self.tangential)), self.tangential
        compliance = np.concatenate([[axial[0]], np.zeros(len(self.tangential))])
        return self.columns, compliance, np.concatenate([[axial[1]], self.tangential])

    def load(self) -> np.ndarray | None:
        """The preload of a clamp being tightened, along the pair's axis (N), else None."""
        if self.axial() is not None:
            return None
        return -self.fastener.force * self.columns[:, 0]

    def tension(self, opening: float, axial_force: float | None) -> float:
        """The fastener's axial force (N, tension > 0) at the pair's ``opening`` (m), from
        its axial link force (None while it is a load)."""
        if not self.clamp:
            assert axial_force is not None
            return -axial_force
        if not self.tightened:
            return float(self.fastener.force)
        return float(self.fastener.force + self.fastener.stiffness * (opening - self.opening))

    def bearing_force(self, opening: float, axial_force: float | None) -> float:
        """The compression the parts bear at a clamp's pair (N): 0 unless bearing."""
        if not (self.clamp and self.bearing):
            return 0.0
        assert axial_force is not None
        return float(axial_force + self.tension(opening, axial_force))


#: How many linked models and reduced operators an assembly keeps (its :attr:`operators`).
OPERATORS_KEPT = 48


def _kept(cache: dict, key: tuple, value: Any) -> Any:
    """Keep ``value`` under ``key`` in ``cache``, the oldest entries dropped past
    :data:`OPERATORS_KEPT`; return ``value``."""
    while len(cache) >= OPERATORS_KEPT:
        cache.pop(next(iter(cache)))
    cache[key] = value
    return value


def _free_displacements(model: ReducedModel, loads: np.ndarray) -> np.ndarray:
    """``R P`` (m); of a flexibility model, on the columns of the loaded freedoms when few
    (a stage's loads are its clamps' preloads, on a handful of freedoms)."""
    loaded = np.flatnonzero(loads)
    if model.given != "flexibility" or 4 * loaded.size >= loads.size:
        return np.asarray(model.displacements(loads)).reshape(-1)
    return model.flexibility[:, loaded] @ loads[loaded]


def _checked_order(assembly: AssemblyLayout, order: Sequence[int] | None) -> list[int]:
    n = len(assembly.fasteners)
    positions = list(range(n)) if order is None else np.asarray(order).reshape(-1).tolist()
    for position in positions:
        if isinstance(position, bool) or not isinstance(position, int) or not 0 <= position < n:
            raise InvalidInputError(
                f"order must hold positions in the fastener list 0..{n - 1}, got {position!r}"
            )
    if len(set(positions)) != len(positions):
        raise InvalidInputError(f"order installs a fastener twice: {positions}")
    return positions


def _checked_steps(assembly: AssemblyLayout, load_steps) -> list[tuple[str, np.ndarray]]:
    steps = []
    for position, step in enumerate(load_steps):
        if not (isinstance(step, tuple | list) and len(step) == 2 and isinstance(step[0], str)):
            raise InvalidInputError(
                f"load_steps[{position}] must be a (label, loads) pair, got {type(step).__name__}"
            )
        loads = finite_array(real_array(step[1], "loads").reshape(-1), "loads", 1)
        if loads.shape != (assembly.n_freedoms,):
            raise InvalidInputError(
                f"load_steps[{position}] ({step[0]!r}): loads must have shape "
                f"({assembly.n_freedoms},), got {loads.shape}"
            )
        steps.append((step[0], loads))
    return steps


def run_sequence(
    assembly: AssemblyLayout,
    gaps,
    order: Sequence[int] | None,
    load_steps,
    method: str | None,
    r0: Any,
    options: dict,
) -> AssemblySequence:
    """:meth:`~contactqp.applications.fastening.model.Assembly.sequence` (see there)."""
    g0 = finite_array(real_array(gaps, "gaps").reshape(-1), "gaps", 1)
    if g0.shape != (assembly.n_pairs,):
        raise InvalidInputError(
            f"gaps must hold one value per pair ({assembly.n_pairs}), got shape {g0.shape}"
        )
    positions = _checked_order(assembly, order)
    steps = _checked_steps(assembly, load_steps)
    if not positions and not steps:
        raise InvalidInputError("nothing to solve: no fastener to install and no load step")
    if len({assembly.fasteners[p].pair for p in positions}) == assembly.n_pairs:
        raise InvalidInputError("every pair would be fastened: no contact is left to solve")
    sequencer = _Sequencer(assembly, g0, method, dict(options), r0)
    stages = []
    for position in positions:
        stages.append(sequencer.install(position))
    for label, loads in steps:
        stages.append(sequencer.load_step(label, loads))
    return AssemblySequence(stages)


class _Sequencer:
    """The state carried from stage to stage, and the solve of one stage."""

    def __init__(self, assembly: AssemblyLayout, gaps: np.ndarray, method, options: dict, r0):
        self.assembly, self.gaps = assembly, gaps
        self.model = assembly.model
        self.base = assembly.base_problem
        self.frictional = isinstance(self.base, FrictionalProblem)
        self.method, self.options = method, options
        if not self.frictional:
            self._check_frictionless_options()
        self.tol = CERTIFICATE_TOL
        n = assembly.n_freedoms
        self.displacements = np.zeros(n)
        self.loads = np.zeros(n)
        self.installed: list[_Fastening] = []
        self.previous: ContactResult | None = None
        self.previous_contacts = np.arange(assembly.n_pairs)
        self.stage_index = 0
        self.warm = r0
        A = self.base.constraints.matrix
        self.normal_rows = A  # gaps: g = g0 - A U
        self.frames = None if assembly.dofs_per_node == 1 else self._frames()

    def _frames(self):
        """``H`` of every pair (the slips' operator): the frictional problem's, or assembled
        once per assembly and kept."""
        if isinstance(self.base, FrictionalProblem):
            return self.base.frames.operator
        cache = self.assembly.operators
        if ("frames",) not in cache:
            _kept(cache, ("frames",), local_frames(self.model, self.base.constraints).operator)
        return cache[("frames",)]

    # ------------------------------------------------------------------ options

    def _check_frictionless_options(self) -> None:
        name = "lawson-hanson" if self.method is None else self.method
        if name not in FRICTIONLESS_METHODS:
            raise InvalidInputError(
                f"method {name!r} does not solve a frictionless assembly; methods: "
                f"{', '.join(FRICTIONLESS_METHODS)} (the first is the default)"
            )
        unknown = sorted(set(self.options) - set(FRICTIONLESS_METHODS[name]))
        if unknown:
            raise InvalidInputError(
                f"method {name!r} has no option {unknown[0]!r}; its options: "
                f"{', '.join(FRICTIONLESS_METHODS[name])}"
            )
        self.method = name
        if "tol" in self.options:
            positive_tolerance(self.options["tol"])
        if "max_iter" in self.options:
            iteration_cap(self.options["max_iter"])

    # ------------------------------------------------------------------ stages

    def _fastening(self, position: int) -> _Fastening:
        fastener = self.assembly.fasteners[position]
        columns, influence = self.assembly.fastener_links(position)
        return _Fastening(
            position=position,
            fastener=fastener,
            columns=columns,
            influence=influence,
            gap=float(self.gaps[fastener.pair]),
            tangential=columns[:, 1:].T @ self.displacements,  # frozen as found
        )

    def install(self, position: int) -> AssemblyStage:
        fastening = self._fastening(position)
        if fastening.clamp:
            fastening.bearing = self._bears(fastening)
        self.installed.append(fastening)
        label = fastening.fastener.label or fastening.name
        stage = self._solve(label, self.loads)
        if fastening.clamp:  # tightened: an axial spring about this state from here on
            fastening.opening = float(fastening.columns[:, 0] @ stage.result.displacements)
            fastening.tightened = True
        return stage

    def _bears(self, fastening: _Fastening) -> bool:
        """A guess of whether a clamp being installed ends its stage bearing (the stage
        switches it when wrong; a right guess saves a solve): as in the warm start's stage,
        or when its preload alone would close its pair on the linked model."""
        warm = self.warm
        if isinstance(warm, AssemblySequence) and self.stage_index < len(warm.stages):
            return bool(warm.stages[self.stage_index].normal_forces[fastening.fastener.pair] > 0)
        axis, moved = fastening.columns[:, 0], fastening.influence[:, 0]
        flexibility = float(axis @ moved)  # e^T R' e, R' the model with the installed links
        linked = self._links()[0]
        if linked is not None:
            coupling = linked.links.relative(moved)
            flexibility -= float(coupling @ linked.solve_schur(coupling))
        gap = fastening.gap + float(axis @ self.displacements)
        return gap - fastening.fastener.force * flexibility < 0.0

    def load_step(self, label: str, loads: np.ndarray) -> AssemblyStage:
        self.loads = loads
        return self._solve(label, loads)

    def _links(self) -> tuple[LinkedModel | None, list[tuple[_Fastening, int | None]], tuple]:
        """The links of this stage, per installed fastener the index of its axial link
        component (None while its preload is a load), and the links' structure (what ``S``
        and ``W'`` depend on: the components and their compliances, not the references)."""
        columns, compliance, reference, influence, axial, structure = [], [], [], [], [], []
        offset = 0
        for fastening in self.installed:
            E, c, d0 = fastening.components()
            tangential_only = fastening.axial() is None
            axial.append((fastening, None if tangential_only else offset))
            structure.append((fastening.position, tangential_only, *c.tolist()))
            if E.shape[1]:
                columns.append(E)
                compliance.append(c)
                reference.append(d0)
                influence.append(
                    fastening.influence[:, 1:] if tangential_only else fastening.influence
                )
            offset += E.shape[1]
        key = tuple(structure)
        if not columns:
            return None, axial, key
        cache = self.assembly.operators
        linked = cache.get(("links", key))
        if linked is None:  # S factored once per link structure, shared by every sample
            links = Links(np.hstack(columns), np.concatenate(compliance), np.concatenate(reference))
            linked = _kept(
                cache, ("links", key), LinkedModel(self.model, links, np.hstack(influence))
            )
            return linked, axial, key
        return linked.with_reference(np.concatenate(reference)), axial, key

    def _prescribed(self) -> np.ndarray:
        """Loads of the clamps being tightened: their preload along the pair's axis (N)."""
        loads = np.zeros(self.assembly.n_freedoms)
        for fastening in self.installed:
            load = fastening.load()
            if load is not None:
                loads += load
        return loads

    def _warm_start(self, contacts: np.ndarray) -> np.ndarray | None:
        """Per-contact start forces (N): the previous stage's, or the given ``r0``."""
        warm = self.warm
        if warm is not None and not isinstance(warm, AssemblySequence) and self.stage_index:
            warm = None
        if isinstance(warm, AssemblySequence):
            if self.stage_index >= len(warm.stages):
                warm = None
            else:
                stage = warm.stages[self.stage_index]
                forces = np.column_stack([stage.normal_forces, stage.tangential_forces])
                if self.frictional and self.stage_index and self.previous is not None:
                    # this sequence's previous stage plus what the stage changed in the warm one
                    before = warm.stages[self.stage_index - 1]
                    change = forces - np.column_stack(
                        [before.normal_forces, before.tangential_forces]
                    )
                    where = np.searchsorted(self.previous_contacts, contacts)
                    return self.previous.forces[where] + change[contacts]
                return forces[contacts] if self.frictional else forces[contacts, 0]
        if warm is not None:
            d = self.base.dim if isinstance(self.base, FrictionalProblem) else 1
            start = finite_array(real_array(warm, "r0").reshape(-1), "r0", 1)
            k = self.assembly.n_pairs
            if start.size == k:
                start = np.column_stack([start, np.zeros((k, d - 1))]).reshape(-1)
            if start.size != k * d:
                raise InvalidInputError(
                    f"r0 must hold one normal force per pair ({k},) or {d} local forces per "
                    f"pair ({k}, {d}), got shape {np.shape(warm)}"
                )
            forces = start.reshape(k, d)
            return forces[contacts] if self.frictional else forces[contacts, 0]
        if self.previous is None:
            return None
        where = np.searchsorted(self.previous_contacts, contacts)
        return self.previous.forces[where]

    def _solve(self, label: str, loads: np.ndarray) -> AssemblyStage:
        """Solve the stage; clamps whose pair would close (or, bearing, pull open) switch
        between spring and bearing until none does."""
        fastened = {f.fastener.pair for f in self.installed}
        contacts = np.array([i for i in range(self.assembly.n_pairs) if i not in fastened])
        start = self._warm_start(contacts)
        clamps = [f for f in self.installed if f.clamp]
        for _ in range(2 * len(clamps) + 2):
            P = loads + self._prescribed()
            linked, axial, structure = self._links()
            if self.frictional:
                result, link_forces = self._frictional(contacts, P, linked, start, structure)
            else:
                result, link_forces = self._frictionless(contacts, P, linked, start, structure)
            switched = self._switch_bearing(result, linked, link_forces, axial, P)
            if not switched:
                break
            start = result.forces
        result = self._checked_links(result, linked, link_forces, axial, P, switched)
        stage = self._stage(label, contacts, result, link_forces, axial)
        self.previous, self.previous_contacts = result, contacts
        self.displacements = result.displacements
        self.stage_index += 1
        return stage

    def _scales(self, result, link_forces, P) -> tuple[float, float]:
        """``(length, force)`` (m, N) against which fastener residuals are judged."""
        U = result.displacements
        length = max(
            float(np.max(np.abs(U), initial=0.0)),
            float(np.max(np.abs(self.gaps), initial=0.0)),
            np.finfo(float).tiny,
        )
        force = max(
            float(np.max(np.abs(P), initial=0.0)),
            float(np.max(np.abs(link_forces), initial=0.0)),
            float(np.max(np.abs(result.forces), initial=0.0)),
            np.finfo(float).tiny,
        )
        return length, force

    def _clamp_states(self, result, link_forces, axial):
        """Per clamp: ``(fastening, gap (m), bearing force (N))``."""
        states = []
        for fastening, index in axial:
            if not fastening.clamp:
                continue
            opening = float(fastening.columns[:, 0] @ result.displacements)
            force = None if index is None else float(link_forces[index])
            states.append(
                (fastening, fastening.gap + opening, fastening.bearing_force(opening, force))
            )
        return states

    def _switch_bearing(self, result, linked, link_forces, axial, P) -> bool:
        """Switch the clamps whose pair penetrates to bearing, and those bearing in tension
        back to springs; True when one switched."""
        length, force = self._scales(result, link_forces, P)
        switched = False
        for fastening, gap, bearing in self._clamp_states(result, link_forces, axial):
            if not fastening.bearing and gap < -self.tol * length:
                fastening.bearing, switched = True, True
            elif fastening.bearing and bearing < -self.tol * force:
                fastening.bearing, switched = False, True
        return switched

    # ------------------------------------------------------------------ the two routes

    def _frictionless(self, contacts, P, linked, start, structure):
        clock = time.perf_counter()
        base = self.base
        assert isinstance(base, ContactProblem)
        dual = base.dual()
        A = base.constraints.matrix[contacts]
        free = _free_displacements(self.model, P)
        offset = -(A @ free)
        key = ("frictionless", contacts.tobytes(), structure)
        cached = self.assembly.operators.get(key)
        if cached is None:  # W' (B) once per contact set and link structure
            W = dual.W[np.ix_(contacts, contacts)]
            B = None if linked is None else linked.coupling(-A)
            if linked is not None:
                W = linked.reduced_operator(W, B)
            cached = _kept(self.assembly.operators, key, (B, W))
        B, W = cached
        if linked is not None:
            offset = offset + linked.offset(B, linked.links.relative(free))
        q = -(offset + self.gaps[contacts])
        x0 = None if start is None else np.maximum(np.asarray(start, dtype=float), 0.0)
        tol = self.options.get("tol", 1e-10)
        if self.method == "lawson-hanson":
            solution = solve_nonnegative_qp(W, q, x0, tol, max_iter=3 * len(q))
            message = f"Lawson-Hanson {'converged' if solution.converged else 'did not converge'}"
        else:
            solution = solve_box_qp(
                W, -q, lower=0.0, x0=x0, tol=tol, max_iter=self.options.get("max_iter", 500)
            )
            message = solution.message
        forces = solution.x
        loaded = np.flatnonzero(forces)  # U = R (P - A^T x), read on the loaded contacts
        U = free - forces[loaded] @ dual.influence.T[contacts[loaded]]
        link_forces = np.zeros(0)
        if linked is not None:
            link_forces = linked.forces(linked.links.relative(U))
            U = U + linked.influence @ link_forces
            P = P + linked.links.directions @ link_forces
        problem = base.restricted(contacts, loads=P, gaps=self.gaps[contacts])
        result = problem.make_result(
            U,
            forces,
            method=str(self.method),
            converged=solution.converged,
            message=message,
            iterations=solution.iterations,
            seconds=time.perf_counter() - clock,
            info={"factorizations": solution.factorizations},
        )
        return result, link_forces

    def _frictional(self, contacts, P, linked, start, structure):
        clock = time.perf_counter()
        base = self.base
        assert isinstance(base, FrictionalProblem)
        previous = self._previous_on(contacts)
        problem = base.restricted(contacts, loads=P, gaps=self.gaps[contacts], previous=previous)
        form = problem.local()
        d, k = problem.dim, len(contacts)
        tangential = np.zeros((k, d - 1)) if previous is None else previous.tangential_displacements
        free = form.free_displacements(P)
        q = (form.operator @ free + form.offset).reshape(k, d)
        q[:, 1:] -= tangential
        q = q.reshape(-1)
        coupling = None
        if linked is not None:
            coupling = self._coupling(contacts, structure, linked, form)
            q = q + linked.offset(coupling, linked.links.relative(free))
        # the FCLIB problem W' / w, q / L (FrictionStep's scaling; no cohesion here)
        length = float(np.max(np.abs(q))) or 1.0
        _, entry, options = resolve(problem, self.method, self.options)
        if "facets" in entry.option_names:
            options["facets"] = problem.law.facets
        solution = None
        if self._candidates_apply(entry, problem, options):  # W' read on candidates only
            operator = self._operator(contacts, structure, linked, coupling)
            force_unit = length / operator.scale
            given = {option.name: option.default for option in entry.options} | options
            with np.errstate(over="ignore", invalid="ignore"):
                solution = solve_on_candidates(
                    operator,
                    q / length,
                    problem.law.mu,
                    problem.dim,
                    r0=None if start is None else np.reshape(start, -1) / force_unit,
                    tol=given["tol"],
                    max_iter=given["max_iter"],
                    per_contact=given["per_contact"],
                    # warm started from another sequence (a study's nominal), not this one's
                    # previous stage: the contacts that start closes are candidates at once
                    look_ahead=isinstance(self.warm, AssemblySequence),
                )
        if solution is None:  # the whole W' / w formed (once per contact set and links)
            if linked is None:
                template = form.fclib_template(problem.law)
                scale = float(np.max(form.W.diagonal()))
            else:
                scale, template = self._reduced(contacts, structure, linked, problem)
            force_unit = length / scale
            if start is not None and "r0" in entry.option_names:
                options["r0"] = np.asarray(start, dtype=float).reshape(-1) / force_unit
            with np.errstate(over="ignore", invalid="ignore"):
                solution = solve(template.with_q(q / length), entry.name, **options)
        success = getattr(solution, "success", True)  # a candidate solution has converged
        r = force_unit * np.asarray(solution.forces).reshape(-1)
        link_forces = np.zeros(0)
        if linked is not None:
            U0 = form.displacements(P, r, free)
            link_forces = linked.forces(linked.links.relative(U0))
            problem = problem.with_loads(
                P + linked.links.directions @ link_forces, previous=previous
            )
        result = problem.make_result(
            r,
            method=entry.name,
            converged=success,
            message=solution.message,
            iterations=solution.iterations,
            seconds=time.perf_counter() - clock,
        )
        return result, link_forces

    def _candidates_apply(self, entry, problem, options) -> bool:
        """True when the stage is solved by coulomb's candidate-set path on a lazily read
        ``W'`` (:func:`~contactqp.methods.coulomb.solve_on_candidates`): the coulomb method,
        a dense contact operator, enough contacts for that path and no cohesion. ``W'`` is not
        checked for semidefiniteness there: it is ``H R' H^T`` with ``R'`` the linked model's
        flexibility (:meth:`~contactqp.core.links.LinkedModel.flexibility`), semidefinite by
        construction."""
        return (
            entry.name == "coulomb"
            and "r0" not in options
            and isinstance(self._local_base()[1].W, np.ndarray)
            and problem.n_contacts >= ACTIVE_SET_MIN
            and not np.any(problem.law.cohesion)
        )

    def _local_base(self):
        """The assembly's frictional problem (every pair) and its local form."""
        base = self.base
        assert isinstance(base, FrictionalProblem)
        return base, base.local()

    def _coupling(self, contacts, structure, linked, form) -> np.ndarray:
        """``B = H R E`` of the contacts ``contacts`` under links of ``structure``, kept."""
        cache = self.assembly.operators
        key = ("coupling", contacts.tobytes(), structure)
        cached = cache.get(key)
        if cached is None:
            cached = _kept(cache, key, linked.coupling(form.operator))
        return cached

    def _operator(self, contacts, structure, linked, coupling) -> ReducedOperator:
        """``W' / w`` of the contacts ``contacts`` under links of ``structure`` (``B`` their
        ``coupling``) as an operator on the assembly's ``W``, read where asked; kept."""
        cache = self.assembly.operators
        key = ("operator", contacts.tobytes(), structure)
        cached = cache.get(key)
        if cached is None:
            base, form = self._local_base()
            W, d = form.W, base.dim
            rows = (d * contacts[:, None] + np.arange(d)).reshape(-1)
            if linked is None:
                operator = ReducedOperator(W, rows, None)
            else:
                operator = linked.reduced(W, rows, coupling)
            cached = _kept(cache, key, operator)
        return cached

    def _reduced(self, contacts, structure, linked, problem):
        """``(w, W' / w)`` of the contacts ``contacts`` under links of ``structure``:
        ``W' = W - B S^{-1} B^T`` (``B = H R E``) scaled by its largest diagonal ``w`` as an
        FCLIB problem (validated, and its semidefiniteness checked, once per structure)."""
        cache = self.assembly.operators
        key = ("reduced", contacts.tobytes(), structure)
        cached = cache.get(key)
        if cached is None:
            form = problem.local()
            coupling = self._coupling(contacts, structure, linked, form)
            W = linked.reduced_operator(form.W, coupling)
            scale = float(np.max(W.diagonal()))
            W /= scale  # W' is new here: scaled in place
            template = LocalProblem(W, np.zeros(W.shape[0]), problem.law.mu, problem.dim)
            cached = _kept(cache, key, (scale, template))
        return cached

    def _previous_on(self, contacts: np.ndarray) -> FrictionalResult | None:
        """The previous stage's result on ``contacts`` (a subset of its own), or None."""
        previous = self.previous
        if previous is None:
            return None
        assert isinstance(previous, FrictionalResult)
        if np.array_equal(contacts, self.previous_contacts):
            return previous
        where = np.searchsorted(self.previous_contacts, contacts)
        return dataclasses.replace(
            previous,
            forces=previous.forces[where],
            gaps=previous.gaps[where],
            contact_status=previous.contact_status[where],
            slip=previous.slip[where],
            tangential_displacements=previous.tangential_displacements[where],
            dissipation=previous.dissipation[where],
        )

    # ------------------------------------------------------------------ checks and records

    def _checked_links(self, result, linked, link_forces, axial, P, switched) -> ContactResult:
        """``result``, failed (status 2) when a fastener's law does not hold on its
        displacements: the link residuals ``E^T U + C f - d0``, and a clamp's pair neither
        penetrating nor, bearing, in tension."""
        notes = []
        length, force = self._scales(result, link_forces, P)
        if linked is not None:
            links = linked.links
            residual = np.abs(links.residual(result.displacements, link_forces))
            relative = residual / np.maximum(length, links.compliance * force)
            worst = int(np.argmax(relative))
            if relative[worst] > self.tol:
                owner, component = self._component(worst, axial)
                law = (
                    "bonded tangential motion"
                    if component > 0
                    else ("clamp force" if owner.clamp and not owner.bearing else "closure gap")
                )
                notes.append(
                    f"{owner.name} breaks its {law} (relative residual {relative[worst]:.2e} "
                    f"> {self.tol:.0e})"
                )
        for fastening, gap, bearing in self._clamp_states(result, link_forces, axial):
            if gap < -self.tol * length:
                notes.append(f"{fastening.name}: its pair penetrates ({gap:.3g} m)")
            if bearing < -self.tol * force:
                notes.append(f"{fastening.name}: its pair bears in tension ({bearing:.3g} N)")
        if switched:
            notes.append("the clamps' bearing did not settle")
        if not notes:
            return result
        return dataclasses.replace(
            result,
            success=False,
            status=CERTIFICATE_FAILED,
            message="; ".join([result.message, *notes]),
        )

    @staticmethod
    def _component(index: int, axial) -> tuple[_Fastening, int]:
        """The fastener and component (0 axial) of link component ``index``."""
        for fastening, position in axial:
            count = fastening.components()[0].shape[1]
            if index < count:
                return fastening, index + (1 if position is None else 0)
            index -= count
        raise IndexError(index)

    def _stage(self, label, contacts, result, link_forces, axial) -> AssemblyStage:
        k = self.assembly.n_pairs
        U = result.displacements
        gaps = self.gaps - self.normal_rows @ U
        normal = np.zeros(k)
        tangential = np.zeros((k, 2))
        status = np.full(k, int(ContactStatus.FASTENED))
        status[contacts] = result.contact_status
        if isinstance(result, FrictionalResult):
            normal[contacts] = result.forces[:, 0]
            tangential[contacts] = result.forces[:, 1:]
        else:
            normal[contacts] = result.forces
        slip = np.zeros((k, 2))
        if self.frames is not None:
            motion = (self.frames @ (U - self.displacements)).reshape(k, 3)
            slip = motion[:, 1:]
        tensions = []
        for fastening, index in axial:
            opening = float(fastening.columns[:, 0] @ U)
            force = None if index is None else float(link_forces[index])
            tensions.append(fastening.tension(opening, force))
            normal[fastening.fastener.pair] = fastening.bearing_force(opening, force)
        return AssemblyStage(
            label=label,
            gaps=gaps,
            normal_forces=normal,
            tangential_forces=tangential,
            status=status,
            slip=slip,
            fasteners=np.array([f.fastener.pair for f in self.installed], dtype=int),
            fastener_forces=np.array(tensions),
            result=result,
        )

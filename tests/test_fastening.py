"""applications.fastening: assemblies of the user's parts, checked against independent truths.

Two assemblies are built once:

* the riveting plates (:mod:`contactqp.applications.riveting`, 7 x 5 pairs, 1 freedom per
  node), whose own sequence (:meth:`RivetingModel.fasten`, a FastenedProblem per step) is the
  truth for closure fasteners without friction;
* the 3-D finite-element parts of :mod:`contactqp.applications.riveting_friction` (45 pairs,
  ``u_x, u_y, u_z``), split into their two parts, for friction: the full finite-element
  analysis of each part is the truth for the reported forces.
"""

import numpy as np
import pytest

import contactqp
from contactqp import ContactProblem, NodePairs, ReducedModel
from contactqp.applications.fastening import (
    Assembly,
    AssemblyPart,
    AssemblySequence,
    Fastener,
    InterfacePairs,
)
from contactqp.applications.riveting import Assembly as Plates
from contactqp.applications.riveting_friction import FrictionAssembly
from contactqp.core.fastened import FastenedProblem
from contactqp.core.status import ContactStatus
from contactqp.errors import InvalidInputError

PLATE_FASTENERS = ((1, 2), (3, 2), (5, 2), (3, 0))


def _interface(k):
    return InterfacePairs(
        "lower",
        "upper",
        np.column_stack([np.arange(k), np.arange(k)]),
        np.tile([0, 0, 1.0], (k, 1)),
    )


@pytest.fixture(scope="module")
def plates():
    riveting = Plates(grid=(7, 5), fasteners=PLATE_FASTENERS).build()
    k = riveting.n_pairs
    lower, upper = riveting.assembly.flexibilities
    points = np.column_stack([riveting.points, np.zeros(k)])
    parts = [
        AssemblyPart("lower", ReducedModel(flexibility=lower), points),
        AssemblyPart("upper", ReducedModel(flexibility=upper), points + [0, 0, 0.002]),
    ]
    x, y = riveting.points.T
    gaps = 2e-4 * np.sin(np.pi * x / 0.2) + 5e-5 * y / 0.1 - 2e-5
    return riveting, parts, gaps


@pytest.fixture(scope="module")
def blocks():
    """The FE parts of riveting_friction, as two parts, with a bow-and-tilt gap field."""
    friction = FrictionAssembly().build()
    k = friction.n_pairs
    R, coordinates = friction.model.flexibility, friction.model.coordinates
    parts = [
        AssemblyPart(
            "lower", ReducedModel(flexibility=R[: 3 * k, : 3 * k], dofs_per_node=3), coordinates[:k]
        ),
        AssemblyPart(
            "upper", ReducedModel(flexibility=R[3 * k :, 3 * k :], dofs_per_node=3), coordinates[k:]
        ),
    ]
    x, y = friction.points.T
    gaps = 2e-4 * np.sin(np.pi * x / 0.1) + 5e-5 * y / 0.04
    fasteners = [friction.pair(1, 2), friction.pair(4, 2), friction.pair(7, 2)]
    return friction, parts, gaps, fasteners


def _blocks_assembly(blocks, mu=0.0, **fastener):
    friction, parts, gaps, pairs = blocks
    fasteners = [Fastener(p, **fastener) for p in pairs]
    return Assembly(parts, [_interface(friction.n_pairs)], fasteners, mu=mu)


def _symmetric(matrix):
    return 0.5 * (matrix + matrix.T)


def _relative(a, b):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) / max(np.max(np.abs(b)), 1e-300)


# ---------------------------------------------------------------------------- no friction


def test_plates_with_closures_reproduce_the_riveting_sequence(plates):
    """1-freedom parts: every stage's gaps and tensions are RivetingModel.fasten's."""
    riveting, parts, gaps = plates
    fasteners = [Fastener(int(p), shear="free") for p in riveting.fasteners]
    assembly = Assembly(parts, [_interface(riveting.n_pairs)], fasteners)
    order = [2, 0, 3, 1]
    truth = riveting.fasten(gaps, order)
    sequence = assembly.sequence(gaps, order=order)
    assert sequence.success and truth.success
    for stage, step in zip(sequence.stages, truth.steps, strict=True):
        assert np.allclose(stage.gaps, step.gaps, rtol=0, atol=1e-9 * np.abs(gaps).max())
        tension = -step.multipliers[step.fasteners]
        assert np.array_equal(stage.fasteners, step.fasteners)
        assert np.allclose(stage.fastener_forces, tension, rtol=1e-7, atol=1e-9)
        contacts = stage.status != ContactStatus.FASTENED
        assert np.allclose(stage.normal_forces[contacts], step.forces[contacts], atol=1e-9)
        assert np.all(stage.normal_forces[~contacts] == 0)
        assert np.all(stage.tangential_forces == 0) and np.all(stage.slip == 0)


def test_free_closures_equal_the_fastened_problem_at_every_stage(blocks):
    """3-freedom parts, mu = 0, shear free: each stage is FastenedProblem on the same rows (an
    independent elimination, solved by its own method)."""
    friction, parts, gaps, pairs = blocks
    assembly = _blocks_assembly(blocks, shear="free")
    sequence = assembly.sequence(gaps, order=[1, 2, 0])
    problem = ContactProblem(
        assembly.model,
        np.zeros(assembly.n_freedoms),
        [NodePairs(assembly.pairs, gaps, assembly.normals)],
    )
    installed = [pairs[i] for i in (1, 2, 0)]
    for count, stage in enumerate(sequence.stages, start=1):
        assert stage.success, stage.result.message
        truth = contactqp.solve(FastenedProblem(problem, installed[:count]))
        assert truth.success
        assert _relative(stage.gaps, truth.gaps) < 1e-7
        contacts = np.setdiff1d(np.arange(assembly.n_pairs), installed[:count])
        assert _relative(stage.normal_forces[contacts], truth.forces[contacts]) < 1e-7
        assert _relative(stage.fastener_forces, -truth.multipliers[installed[:count]]) < 1e-7
        assert np.all(stage.status[installed[:count]] == ContactStatus.FASTENED)
        assert np.allclose(stage.gaps[installed[:count]], 0.0, atol=1e-12)


def test_without_friction_the_end_state_does_not_depend_on_the_order(blocks):
    friction, parts, gaps, pairs = blocks
    assembly = _blocks_assembly(blocks, shear="free")
    first = assembly.sequence(gaps, order=[0, 1, 2]).final
    second = assembly.sequence(gaps, order=[2, 0, 1]).final
    assert _relative(first.gaps, second.gaps) < 1e-8
    assert _relative(first.normal_forces, second.normal_forces) < 1e-8
    by_pair = dict(zip(second.fasteners, second.fastener_forces, strict=True))
    assert _relative(first.fastener_forces, [by_pair[p] for p in first.fasteners]) < 1e-8


def test_a_clamp_is_a_spring_added_to_the_part_stiffness(plates):
    """A clamp tightened to a small preload (its pair stays open) pulls with exactly that
    preload; under a later load it is a spring of its stiffness about that state: the truth is
    the contact problem on ``K + k e e^T`` with the spring's pre-stretch as a load."""
    (
        riveting,
        parts,
        gaps,
    ) = plates
    pair, force, stiffness = int(riveting.fasteners[1]), 0.5, 2e4
    fastener = Fastener(pair, kind="clamp", force=force, stiffness=stiffness, shear="free")
    assembly = Assembly(parts, [_interface(riveting.n_pairs)], [fastener])
    push = assembly.load_vector("upper", np.arange(riveting.n_pairs), -40.0)
    sequence = assembly.sequence(gaps, load_steps=[("push", push)])
    assert sequence.success
    tightened, pushed = sequence.stages
    assert tightened.fastener_forces[0] == force
    others = np.setdiff1d(np.arange(assembly.n_pairs), [pair])
    k = riveting.n_pairs
    e = np.zeros(assembly.n_freedoms)
    e[k + pair], e[pair] = 1.0, -1.0
    # the tightening stage: the preload as a load
    truth = contactqp.solve(
        ContactProblem(
            assembly.model, -force * e, [NodePairs(assembly.pairs[others], gaps[others])]
        )
    )
    assert _relative(tightened.gaps[others], truth.gaps) < 1e-7
    assert tightened.gaps[pair] > 0  # open: the clamp does not bear
    opening = e @ tightened.result.displacements
    reference = opening - force / stiffness
    K = assembly.model.stiffness + stiffness * np.outer(e, e)
    sprung = ReducedModel(stiffness=0.5 * (K + K.T))
    truth = contactqp.solve(
        ContactProblem(
            sprung,
            push + stiffness * reference * e,
            [NodePairs(assembly.pairs[others], gaps[others])],
        )
    )
    assert truth.success
    assert _relative(pushed.gaps[others], truth.gaps) < 1e-6
    assert _relative(pushed.normal_forces[others], truth.forces) < 1e-6
    expected = force + stiffness * (e @ truth.displacements - opening)
    assert abs(pushed.fastener_forces[0] - expected) < 1e-6 * force
    assert pushed.fastener_forces[0] < force  # the push closes the pair: the clamp relaxes


def test_a_clamp_tightened_hard_bears_on_the_parts(blocks):
    """A preload beyond what closing needs: the pair closes (gap 0, not penetrating), the parts
    bear the difference, and the clamp keeps its preload."""
    friction, parts, gaps, pairs = blocks
    assembly = _blocks_assembly(blocks, kind="clamp", force=500.0, stiffness=1e8)
    closure = _blocks_assembly(blocks).sequence(gaps)
    sequence = assembly.sequence(gaps)
    assert sequence.success
    final = sequence.final
    assert np.allclose(final.gaps[pairs], 0.0, atol=1e-12)
    assert np.allclose(final.fastener_forces, 500.0)
    # bearing at every clamp: the same geometry as closures, the clamp force less the closing
    # force pressing the parts together at the pair
    assert _relative(final.gaps, closure.final.gaps) < 1e-7
    assert np.allclose(final.normal_forces[pairs], 500.0 - closure.final.fastener_forces, rtol=1e-6)


# ---------------------------------------------------------------------------- friction


@pytest.fixture(scope="module")
def frictional(blocks):
    """Closure fasteners, bonded, mu = 0.3, in two orders, then a shear load and its removal."""
    friction, parts, gaps, pairs = blocks
    assembly = _blocks_assembly(blocks, mu=0.3)
    shear = assembly.load_vector("upper", np.arange(friction.n_pairs), [150.0, 0.0, 0.0])
    steps = [("shear 150 N", shear), ("unloaded", np.zeros_like(shear))]
    return assembly, {
        order: assembly.sequence(gaps, order=list(order), load_steps=steps)
        for order in ((0, 1, 2), (1, 0, 2))
    }


def test_with_friction_the_end_state_depends_on_the_order(frictional):
    assembly, sequences = frictional
    first, second = (sequences[o] for o in ((0, 1, 2), (1, 0, 2)))
    assert first.success and second.success
    # after fastening, and after the shear load and its removal
    for stage in (3 - 1, -1):
        a, b = first.stages[stage], second.stages[stage]
        by_pair = dict(zip(b.fasteners, b.fastener_forces, strict=True))
        assert _relative(a.fastener_forces, [by_pair[p] for p in a.fasteners]) > 1e-3
        assert _relative(a.tangential_forces, b.tangential_forces) > 1e-2
    assert any(np.any(s.status == ContactStatus.SLIP) for s in first.stages)


def test_dissipation_is_non_negative_at_every_stage(frictional):
    assembly, sequences = frictional
    for sequence in sequences.values():
        for stage in sequence.stages:
            dissipation = stage.result.dissipation
            assert np.all(dissipation >= -1e-9 * np.abs(dissipation).max(initial=1e-300))
        assert sum(stage.dissipated for stage in sequence.stages) > 0


def test_mu_zero_on_the_contacts_equals_the_frictionless_route(blocks):
    """The frictional route, mu > 0 only at the fastener pairs (open until fastened, then no
    contacts), reproduces the frictionless one stage by stage, bonded shear included."""
    friction, parts, gaps, pairs = blocks
    mu = np.zeros(friction.n_pairs)
    mu[pairs] = 0.5
    frictional = _blocks_assembly(blocks, mu=mu).sequence(gaps, order=[2, 0, 1])
    frictionless = _blocks_assembly(blocks).sequence(gaps, order=[2, 0, 1])
    for a, b in zip(frictional.stages, frictionless.stages, strict=True):
        assert a.success and b.success
        assert _relative(a.gaps, b.gaps) < 1e-7
        assert _relative(a.normal_forces, b.normal_forces) < 1e-6
        assert _relative(a.fastener_forces, b.fastener_forces) < 1e-6
        assert np.all(a.tangential_forces == 0)
    # once every fastener is in, no contact has friction: the frictional route's mu = 0 branch
    assert frictional.final.result.method == "normal-qp"


def test_full_finite_element_analysis_reproduces_every_stage(blocks, frictional):
    """Each part's full FE model under the reported contact and fastener forces (and the
    shear) deforms as the reduced model says, at every stage: the link forces are real."""
    friction, parts, gaps, pairs = blocks
    assembly, sequences = frictional
    k = friction.n_pairs
    for stage in sequences[(1, 0, 2)].stages:
        result = stage.result
        applied = (result.loads + result.nodal_forces).reshape(2 * k, 3)
        for side, (body, nodes) in enumerate(friction.parts):
            nodal = np.zeros((body.n_nodes, 3))
            nodal[nodes] = applied[side * k : (side + 1) * k]
            full = body.solve(nodal)[nodes]
            reduced = result.displacements.reshape(2 * k, 3)[side * k : (side + 1) * k]
            assert np.max(np.abs(full - reduced)) < 1e-8 * np.max(np.abs(reduced))
    # the closures hold and bonded pairs did not move tangentially after installation
    for stage in sequences[(1, 0, 2)].stages[1:]:
        assert np.allclose(stage.gaps[stage.fasteners], 0.0, atol=1e-12)
        assert np.max(np.abs(stage.slip[stage.fasteners])) < 1e-9 * np.abs(gaps).max()


def test_a_nominal_sequence_warm_starts_a_nearby_one(blocks, frictional):
    friction, parts, gaps, pairs = blocks
    assembly, sequences = frictional
    nominal = sequences[(0, 1, 2)]
    steps = [(s.label, s.result.loads * 0) for s in nominal.stages[3:]]
    nearby = gaps * 1.001
    cold = assembly.sequence(nearby, load_steps=steps)
    warm = assembly.sequence(nearby, load_steps=steps, r0=nominal)
    assert isinstance(warm, AssemblySequence) and warm.success
    assert _relative(warm.final.gaps, cold.final.gaps) < 1e-6


# ---------------------------------------------------------------------------- bad input


def test_bad_input_is_refused_naming_it(plates, blocks):
    riveting, parts, gaps = plates
    k = riveting.n_pairs
    good = _interface(k)
    with pytest.raises(InvalidInputError, match="unknown part 'middle'"):
        Assembly(parts, [InterfacePairs("lower", "middle", good.nodes, good.normals)])
    nodes = good.nodes.copy()
    nodes[3, 1] = k
    with pytest.raises(InvalidInputError, match=r"nodes\[3\] has node 35 of part 'upper'"):
        Assembly(parts, [InterfacePairs("lower", "upper", nodes, good.normals)])
    normals = good.normals.copy()
    normals[2] = [0, 0, 2.0]
    with pytest.raises(InvalidInputError, match=r"normals\[2\] is not a unit vector"):
        Assembly(parts, [InterfacePairs("lower", "upper", good.nodes, normals)])
    twice = InterfacePairs("lower", "upper", good.nodes[:2], good.normals[:2])
    with pytest.raises(InvalidInputError, match="pairs 0 and 35 join the same two nodes"):
        Assembly(parts, [good, twice])
    with pytest.raises(InvalidInputError, match="pair 35 is outside 0..34"):
        Assembly(parts, [good], [Fastener(35, shear="free")])
    with pytest.raises(InvalidInputError, match="pair 3 already has fastener 0"):
        Assembly(parts, [good], [Fastener(3, shear="free"), Fastener(3, shear="free")])
    for stiffness in (np.inf, 0.0, -1.0):
        with pytest.raises(InvalidInputError, match="finite positive axial stiffness"):
            Assembly(parts, [good], [Fastener(3, "clamp", 10.0, stiffness, shear="free")])
    with pytest.raises(InvalidInputError, match="no in-plane freedoms"):
        Assembly(parts, [good], mu=0.2)
    with pytest.raises(InvalidInputError, match="shear 'bonded' needs in-plane freedoms"):
        Assembly(parts, [good], [Fastener(3)])
    with pytest.raises(InvalidInputError, match="two parts are named 'lower'"):
        Assembly([parts[0], parts[0]], [good])
    assembly = Assembly(parts, [good], [Fastener(3, shear="free")])
    with pytest.raises(InvalidInputError, match="order must hold positions"):
        assembly.sequence(gaps, order=[1])
    with pytest.raises(InvalidInputError, match="gaps must hold one value per pair"):
        assembly.sequence(gaps[:-1])
    with pytest.raises(InvalidInputError, match="has no option 'facets'"):
        assembly.sequence(gaps, facets=4)
    friction, block_parts, block_gaps, _ = blocks
    with pytest.raises(InvalidInputError, match="same two nodes"):
        Assembly(block_parts, [_interface(friction.n_pairs)] * 2)


def test_load_vector_shares_the_force(blocks):
    assembly = _blocks_assembly(blocks)
    loads = assembly.load_vector("upper", [0, 1, 2, 3], [4.0, -8.0, 2.0])
    k = blocks[0].n_pairs
    assert np.allclose(loads.reshape(-1, 3)[k : k + 4], [1.0, -2.0, 0.5])
    assert np.allclose(loads.reshape(-1, 3).sum(axis=0), [4.0, -8.0, 2.0])
    assert np.allclose(assembly.points[:, 2], 0.002)  # between the parts
    assert assembly.n_pairs == k and assembly.normals.shape == (k, 3)


def test_a_broken_fastener_law_fails_the_stage(blocks, monkeypatch):
    """The link check is independent of the reduction: link forces off by 1 % fail the stage
    (status 2), the message naming the fastener."""
    from contactqp.core import links

    friction, parts, gaps, pairs = blocks
    assembly = _blocks_assembly(blocks)
    original = links.LinkedModel.forces
    monkeypatch.setattr(links.LinkedModel, "forces", lambda self, x: 1.01 * original(self, x))
    sequence = assembly.sequence(gaps, order=[0])
    stage = sequence.final
    assert not stage.success and stage.result.status == 2
    assert f"fastener 0 (pair {pairs[0]})" in stage.result.message


def test_clamps_with_friction_under_shear_are_certified_and_reproduced(blocks):
    """Bonded clamps, mu = 0.3, a shear load and its removal: every stage certified, the
    dissipation non-negative, the final state reproduced by the full FE parts, and each clamp's
    tension its preload plus stiffness times its opening since tightening."""
    friction, parts, gaps, pairs = blocks
    stiffness = 2e6
    assembly = _blocks_assembly(blocks, mu=0.3, kind="clamp", force=60.0, stiffness=stiffness)
    shear = assembly.load_vector("upper", np.arange(friction.n_pairs), [150.0, 0.0, 0.0])
    sequence = assembly.sequence(gaps, load_steps=[("shear", shear), ("unloaded", 0 * shear)])
    assert sequence.success, [s.result.message for s in sequence.stages]
    k = friction.n_pairs
    openings = {}
    for number, stage in enumerate(sequence.stages):
        U = stage.result.displacements.reshape(2 * k, 3)
        opening = {p: float(U[k + p, 2] - U[p, 2]) for p in stage.fasteners}
        if number < len(pairs):
            openings[stage.fasteners[-1]] = opening[stage.fasteners[-1]]
            assert stage.fastener_forces[-1] == 60.0
        for p, tension in zip(stage.fasteners, stage.fastener_forces, strict=True):
            bearing = abs(stage.gaps[p]) < 1e-12
            if not bearing:
                assert abs(tension - 60.0 - stiffness * (opening[p] - openings[p])) < 1e-6 * 60
            assert stage.gaps[p] >= -1e-12 and stage.normal_forces[p] >= -1e-9
        assert np.all(stage.result.dissipation >= -1e-12)
    final = sequence.final.result
    applied = (final.loads + final.nodal_forces).reshape(2 * k, 3)
    for side, (body, nodes) in enumerate(friction.parts):
        nodal = np.zeros((body.n_nodes, 3))
        nodal[nodes] = applied[side * k : (side + 1) * k]
        reduced = final.displacements.reshape(2 * k, 3)[side * k : (side + 1) * k]
        assert np.max(np.abs(body.solve(nodal)[nodes] - reduced)) < 1e-8 * np.abs(reduced).max()


def test_parts_given_as_stiffness_give_the_same_assembly(blocks):
    friction, parts, gaps, pairs = blocks
    stiff = AssemblyPart(
        "upper",
        ReducedModel(stiffness=_symmetric(parts[1].model.stiffness), dofs_per_node=3),
        parts[1].coordinates,
    )
    mixed = Assembly(
        [parts[0], stiff], [_interface(friction.n_pairs)], [Fastener(p) for p in pairs], mu=0.3
    )
    both = [
        AssemblyPart(
            p.name,
            ReducedModel(stiffness=_symmetric(p.model.stiffness), dofs_per_node=3),
            p.coordinates,
        )
        for p in parts
    ]
    stiffness = Assembly(both, [_interface(friction.n_pairs)], [Fastener(p) for p in pairs], mu=0.3)
    assert mixed.model.given == "flexibility" and stiffness.model.given == "stiffness"
    reference = _blocks_assembly(blocks, mu=0.3).sequence(gaps)
    for assembly in (mixed, stiffness):
        sequence = assembly.sequence(gaps)
        assert sequence.success
        assert _relative(sequence.final.gaps, reference.final.gaps) < 1e-6
        assert _relative(sequence.final.fastener_forces, reference.final.fastener_forces) < 1e-6


def test_an_array_warm_start_is_taken_and_checked(plates):
    riveting, parts, gaps = plates
    fasteners = [Fastener(int(p), shear="free") for p in riveting.fasteners]
    assembly = Assembly(parts, [_interface(riveting.n_pairs)], fasteners)
    cold = assembly.sequence(gaps)
    warm = assembly.sequence(gaps, r0=cold.stages[0].normal_forces, method="active-set")
    assert warm.success and _relative(warm.final.gaps, cold.final.gaps) < 1e-8
    with pytest.raises(InvalidInputError, match="r0 must hold one normal force per pair"):
        assembly.sequence(gaps, r0=np.zeros(3))
    with pytest.raises(InvalidInputError, match="does not solve a frictionless assembly"):
        assembly.sequence(gaps, method="coulomb")


def test_soft_clamps_reproduce_the_clamp_forces_of_riveting_friction(blocks):
    """mu = 0: riveting_friction's sequence (each fastener a clamping force on a contact pair)
    is a clamp of vanishing stiffness whose pair bears: every stage agrees, the compression at
    a fastener pair included."""
    friction, parts, gaps, pairs = blocks
    positions = [(1, 2), (4, 2), (7, 2)]
    assert [friction.pair(*p) for p in positions] == pairs
    truth = friction.fasten(gaps, positions, 0.0, clamp=500.0)
    assembly = _blocks_assembly(
        blocks, kind="clamp", force=500.0, stiffness=1.0, shear="free"
    )  # 1 N/m: a change of opening of 0.1 mm changes the tension by 1e-4 N
    sequence = assembly.sequence(gaps)
    assert sequence.success
    for stage, step in zip(sequence.stages, truth, strict=True):
        assert step.result.success
        assert _relative(stage.gaps, step.result.gaps) < 1e-9
        assert _relative(stage.normal_forces, step.result.normal_forces) < 1e-9
        assert np.allclose(stage.fastener_forces, 500.0, rtol=1e-6)

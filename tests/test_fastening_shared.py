"""What the fastening stages share between sequences and samples gives what a fresh start gives.

The truths are fresh objects: an assembly built anew (nothing kept), a problem assembled afresh
on the kept contacts, a linked model factored anew. Kept (shared) objects must change no stage
beyond rounding, and a wrong guess of a clamp's bearing must change nothing.
"""

import numpy as np
import pytest

from contactqp import FrictionalProblem, NodePairs, ReducedModel, solve
from contactqp.applications.fastening import Assembly, AssemblyPart, Fastener, InterfacePairs
from contactqp.core.links import LinkedModel, Links
from contactqp.errors import InvalidInputError

NX, NY = 5, 3
K = NX * NY


def _part(name, z, compliance):
    x, y = np.meshgrid(np.arange(NX) * 0.02, np.arange(NY) * 0.02)
    xyz = np.column_stack([x.ravel(), y.ravel(), np.full(K, z)])
    distance = np.linalg.norm(xyz[:, None, :] - xyz[None, :, :], axis=2)
    kernel = compliance * np.exp(-distance / 0.03)
    return AssemblyPart(name, ReducedModel(np.kron(kernel, np.eye(3)), dofs_per_node=3), xyz)


def _assembly(mu, force=50.0):
    pairs = InterfacePairs(
        "lower",
        "upper",
        np.column_stack([np.arange(K), np.arange(K)]),
        np.tile([0, 0, 1.0], (K, 1)),
    )
    fasteners = [
        Fastener(1, kind="clamp", force=force, stiffness=1e7),
        Fastener(K - 2, kind="clamp", force=force, stiffness=1e7),
        Fastener(7),
    ]
    return Assembly(
        [_part("lower", 0.0, 2e-6), _part("upper", 1e-3, 3e-6)], [pairs], fasteners, mu=mu
    )


def _inverse(K):
    R = np.linalg.inv(K)
    return 0.5 * (R + R.T)


def _gaps(seed):
    rng = np.random.default_rng(seed)
    return np.linspace(0.0, 2e-5, K) + rng.normal(0.0, 1e-5, K)


def _same(a, b, scale):
    return np.max(np.abs(np.asarray(a) - np.asarray(b)), initial=0.0) <= 1e-7 * scale


def _assert_same_sequences(got, truth):
    assert got.success and truth.success
    for stage, fresh in zip(got.stages, truth.stages, strict=True):
        assert np.array_equal(stage.status, fresh.status)
        assert _same(stage.gaps, fresh.gaps, np.abs(fresh.gaps).max())
        force = max(np.abs(fresh.normal_forces).max(), np.abs(fresh.fastener_forces).max())
        assert _same(stage.normal_forces, fresh.normal_forces, force)
        assert _same(stage.tangential_forces, fresh.tangential_forces, force)
        assert _same(stage.fastener_forces, fresh.fastener_forces, force)


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_a_kept_operator_gives_the_stages_of_a_fresh_assembly(mu):
    """Samples on one assembly (W' and S kept from the first, only q new) equal each sample
    solved on an assembly built anew, warm started or not."""
    shared = _assembly(mu)
    nominal = shared.sequence(_gaps(0))
    assert nominal.success
    if mu > 0:
        assert shared.operators  # the sequence kept its reduced operators
    for seed in (1, 2):
        gaps = _gaps(seed)
        _assert_same_sequences(shared.sequence(gaps), _assembly(mu).sequence(gaps))
        _assert_same_sequences(shared.sequence(gaps, r0=nominal), _assembly(mu).sequence(gaps))


def test_a_wrong_bearing_guess_changes_nothing():
    """The warm start's stages guess each new clamp's bearing: from a sequence whose clamps
    did not bear (a weak preload), the stage switches them and ends as a cold start does."""
    strong, weak = _assembly(0.3, force=400.0), _assembly(0.3, force=1e-3)
    gaps = _gaps(3)
    cold = strong.sequence(gaps)
    guide = weak.sequence(gaps)
    pairs = [f.pair for f in strong.fasteners if f.kind == "clamp"]
    bore = [cold.stages[i].normal_forces[p] > 0 for i, p in enumerate(pairs)]
    guessed = [guide.stages[i].normal_forces[p] > 0 for i, p in enumerate(pairs)]
    assert bore != guessed  # the guide guesses wrong somewhere
    _assert_same_sequences(strong.sequence(gaps, r0=guide), cold)


def test_restrictions_are_kept_and_follow_their_problem():
    """A restriction kept from an earlier call takes this call's gaps, loads and state: it
    equals a problem assembled afresh on the kept contacts (also from a with_loads twin)."""
    rng = np.random.default_rng(4)
    k = 6
    A = rng.standard_normal((6 * k, 6 * k))
    model = ReducedModel(flexibility=_inverse(A @ A.T + 6 * k * np.eye(6 * k)), dofs_per_node=3)
    pairs = np.column_stack([np.arange(k), k + np.arange(k)])
    normals = np.tile([0.0, 0.0, 1.0], (k, 1))
    gaps = rng.uniform(-1e-3, 1e-3, k)
    whole = FrictionalProblem(model, np.zeros(6 * k), [NodePairs(pairs, gaps, normals)], 0.3)
    kept = np.array([0, 2, 3, 5])
    whole.restricted(kept)  # kept from here on
    for loads, shift in ((rng.standard_normal(6 * k), 1e-4), (rng.standard_normal(6 * k), -2e-4)):
        twin = whole.with_loads(loads)
        for restricted in (
            whole.restricted(kept, loads=loads, gaps=gaps[kept] + shift),
            twin.restricted(kept, gaps=gaps[kept] + shift),
        ):
            fresh = FrictionalProblem(
                model, loads, [NodePairs(pairs[kept], gaps[kept] + shift, normals[kept])], 0.3
            )
            assert np.array_equal(restricted.loads, fresh.loads)
            assert np.allclose(
                restricted.step().local.q, fresh.step().local.q, rtol=1e-12, atol=1e-15
            )
            a, b = solve(restricted), solve(fresh)
            assert a.success and b.success
            assert np.allclose(a.forces, b.forces, rtol=1e-8, atol=1e-10 * np.abs(b.forces).max())


def test_a_linked_model_with_another_reference_equals_a_fresh_one():
    rng = np.random.default_rng(2)
    n, m = 9, 3
    A = rng.standard_normal((n, n))
    model = ReducedModel(flexibility=_inverse(A @ A.T + n * np.eye(n)))
    E, c = rng.standard_normal((n, m)), np.array([0.0, 1e-3, 0.0])
    P, d0, other = rng.standard_normal(n), rng.standard_normal(m), rng.standard_normal(m)
    twin = LinkedModel(model, Links(E, c, d0)).with_reference(other)
    fresh = LinkedModel(model, Links(E, c, other))
    for got, truth in zip(twin.displacements(P), fresh.displacements(P), strict=True):
        assert np.allclose(got, truth, rtol=1e-12, atol=1e-14)
    with pytest.raises(InvalidInputError, match="one value per component"):
        twin.with_reference(other[:2])

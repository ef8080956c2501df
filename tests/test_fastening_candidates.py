"""A frictional stage on coulomb's candidate-set path, ``W'`` read lazily
(:class:`~contactqp.core.links.ReducedOperator`), against the dense route that forms ``W'``.

The lazy route and the dense one solve the same FCLIB problem; they differ only in how the
entries of ``W' = W_cc - B S^-1 B^T`` are summed (a few blocks against one full product), so
the answers agree to rounding carried through the Newton iterations: 1e-10 relative to the
largest force is a thousand times the differences seen (~1e-13) and far below the solver's
tolerance on the answer.
"""

import numpy as np
import pytest

from contactqp import ReducedModel
from contactqp.applications.fastening import (
    Assembly,
    AssemblyPart,
    Fastener,
    InterfacePairs,
)
from contactqp.applications.fastening import sequence as sequence_module
from contactqp.applications.riveting_friction import FrictionAssembly
from contactqp.core.links import LinkedModel, Links, ReducedOperator
from contactqp.methods.coulomb import ACTIVE_SET_MIN

AGREE = 1e-10  # relative to the largest force (see the module notes)


@pytest.fixture(scope="module")
def parts():
    """The FE parts of riveting_friction on 9 x 8 = 72 pairs (past coulomb's ACTIVE_SET_MIN)."""
    built = FrictionAssembly(cells=(10, 7)).build()
    k = built.n_pairs
    assert k >= ACTIVE_SET_MIN
    R, xyz = built.model.flexibility, built.model.coordinates
    lower = ReducedModel(flexibility=R[: 3 * k, : 3 * k], dofs_per_node=3)
    upper = ReducedModel(flexibility=R[3 * k :, 3 * k :], dofs_per_node=3)
    return built, [AssemblyPart("lower", lower, xyz[:k]), AssemblyPart("upper", upper, xyz[k:])]


def _assembly(built, parts, kind):
    k = built.n_pairs
    nx, ny = built.grid
    pairs = [i + nx * (ny // 2) for i in (1, nx // 2, nx - 2)]
    fasteners = [Fastener(p, kind=kind, force=300.0, stiffness=1e8) for p in pairs]
    if kind == "closure":
        fasteners = [Fastener(p) for p in pairs]
    interface = InterfacePairs(
        "lower",
        "upper",
        np.column_stack([np.arange(k), np.arange(k)]),
        np.tile([0, 0, 1.0], (k, 1)),
    )
    return Assembly(parts, [interface], fasteners, mu=0.3)


@pytest.mark.parametrize("kind", ["clamp", "closure"])
def test_the_candidate_path_equals_the_dense_route(parts, kind, monkeypatch):
    built, assembly_parts = parts
    k = built.n_pairs
    gaps = 2e-5 + 1e-5 * np.random.default_rng(1).standard_normal(k)
    assembly = _assembly(built, assembly_parts, kind)
    shear = assembly.load_vector("upper", np.arange(k), [80.0, 20.0, 0.0])
    steps = [("shear", shear), ("unloaded", np.zeros_like(shear))]
    lazy = assembly.sequence(gaps, load_steps=steps)
    # each stage's W' was read where the candidates asked, and its certificate needs no W:
    # no restriction of the assembly's W was gathered
    restrictions = assembly.base_problem._restrictions.values()
    assert restrictions and not any(kept.local().formed for kept in restrictions)
    monkeypatch.setattr(sequence_module, "ACTIVE_SET_MIN", 10**9)  # the dense route only
    dense = _assembly(built, assembly_parts, kind).sequence(gaps, load_steps=steps)
    assert lazy.success and dense.success
    for a, b in zip(lazy.stages, dense.stages, strict=True):
        assert "candidate set" in a.result.message and "candidate set" not in b.result.message
        scale = np.max(np.abs(b.normal_forces))
        assert scale > 0
        np.testing.assert_allclose(a.normal_forces, b.normal_forces, rtol=0, atol=AGREE * scale)
        np.testing.assert_allclose(
            a.tangential_forces, b.tangential_forces, rtol=0, atol=AGREE * scale
        )
        np.testing.assert_allclose(a.fastener_forces, b.fastener_forces, rtol=0, atol=AGREE * scale)
        assert np.array_equal(a.status, b.status)
    assert np.any(np.abs(lazy.stages[-2].tangential_forces) > 1e-3 * scale)  # friction works


def test_a_reduced_operator_reads_the_dense_reduced_operator():
    """Blocks, diagonal, products and the matrix of the lazy W' / w equal the dense
    ``W - B S^-1 B^T`` (LinkedModel.reduced_operator) scaled by its largest diagonal."""
    rng = np.random.default_rng(3)
    n, m, p = 30, 4, 18  # freedoms, link components, local rows of the remaining contacts
    A = rng.standard_normal((n, n))
    model = ReducedModel(flexibility=A @ A.T / n + np.eye(n))
    E = rng.standard_normal((n, m))
    linked = LinkedModel(model, Links(E, [0.0, 0.0, 1e-3, 0.5], np.zeros(m)))
    G = rng.standard_normal((n + 6, n))  # every contact's rows; the remaining ones: rows
    W = G @ model.flexibility @ G.T
    W = 0.5 * (W + W.T)
    rows = np.sort(rng.choice(n + 6, p, replace=False))
    coupling = linked.coupling(G[rows])
    dense = linked.reduced_operator(W[np.ix_(rows, rows)], coupling)
    dense /= np.max(dense.diagonal())
    lazy = linked.reduced(W, rows, coupling)
    assert isinstance(lazy, ReducedOperator) and lazy.shape == (p, p)
    tol = 1e-13 * np.max(np.abs(dense))
    np.testing.assert_allclose(lazy.matrix, dense, rtol=0, atol=tol)
    np.testing.assert_allclose(lazy.diagonal(), dense.diagonal(), rtol=0, atol=tol)
    some, others = np.array([5, 1, 7]), np.arange(2, 12)
    np.testing.assert_allclose(
        lazy.block(some, others), dense[np.ix_(some, others)], rtol=0, atol=tol
    )
    x = rng.standard_normal(p)
    np.testing.assert_allclose(lazy @ x, dense @ x, rtol=0, atol=tol * np.abs(x).sum())
    # without links: the slice of W scaled
    plain = ReducedOperator(W, rows, None)
    sliced = W[np.ix_(rows, rows)] / np.max(W[rows, rows])
    np.testing.assert_allclose(plain.matrix, sliced, rtol=0, atol=1e-15 * np.max(sliced))


def test_a_sample_warm_started_from_the_nominal_equals_a_cold_solve(parts):
    """A study's sample (r0 = the nominal sequence: each stage from its previous one plus the
    nominal's change, the contacts that start closes among the first candidates) and the same
    gaps solved cold agree to the solvers' accuracy: both certified to a natural-map error of
    1e-10 from different starts, the loosest figures being the tangential forces of sticking
    contacts (seen differing by 2e-8 of the largest force on the 494-pair benchmark); 1e-6."""
    built, assembly_parts = parts
    k = built.n_pairs
    rng = np.random.default_rng(5)
    nominal_gaps = 2e-5 + 1e-5 * rng.standard_normal(k)
    gaps = nominal_gaps + 5e-6 * rng.standard_normal(k)
    assembly = _assembly(built, assembly_parts, "clamp")
    nominal = assembly.sequence(nominal_gaps)
    warm = assembly.sequence(gaps, r0=nominal)
    cold = _assembly(built, assembly_parts, "clamp").sequence(gaps)
    assert nominal.success and warm.success and cold.success
    for a, b in zip(warm.stages, cold.stages, strict=True):
        assert "candidate set" in a.result.message
        scale = np.max(np.abs(b.normal_forces))
        for name in ("normal_forces", "tangential_forces", "fastener_forces"):
            np.testing.assert_allclose(
                getattr(a, name), getattr(b, name), rtol=0, atol=1e-6 * scale, err_msg=name
            )

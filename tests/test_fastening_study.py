"""The variation study of a fastening sequence: every sample's record against its own direct
sequence, the store's statistics against a direct count, chunking and resuming changing nothing.
"""

from __future__ import annotations

import numpy as np
import pytest

from contactqp.applications.fastening import Assembly, AssemblyPart, Fastener, InterfacePairs
from contactqp.applications.fastening.study import SequenceVariation
from contactqp.core.model import ReducedModel
from contactqp.core.status import ContactStatus
from contactqp.studies import GapSamples, load_batch, run_batch

NX, NY = 4, 3
K = NX * NY


def _part(name: str, z: float, compliance: float) -> AssemblyPart:
    """A part with a node per pair, 3 freedoms each; its flexibility couples nearby nodes
    (an exponential kernel, positive definite) so that one fastener moves its neighbours."""
    x, y = np.meshgrid(np.arange(NX) * 0.02, np.arange(NY) * 0.02)
    xyz = np.column_stack([x.ravel(), y.ravel(), np.full(K, z)])
    distance = np.linalg.norm(xyz[:, None, :] - xyz[None, :, :], axis=2)
    kernel = compliance * np.exp(-distance / 0.03)
    return AssemblyPart(name, ReducedModel(np.kron(kernel, np.eye(3)), dofs_per_node=3), xyz)


def _assembly(mu: float) -> Assembly:
    pairs = InterfacePairs(
        "lower",
        "upper",
        np.column_stack([np.arange(K), np.arange(K)]),
        np.tile([0, 0, 1.0], (K, 1)),
    )
    fasteners = [Fastener(0), Fastener(K - 1), Fastener(5, kind="clamp", force=50.0, stiffness=1e7)]
    return Assembly(
        [_part("lower", 0.0, 2e-6), _part("upper", 1e-3, 3e-6)], [pairs], fasteners, mu=mu
    )


def _gaps(rng, samples: int) -> np.ndarray:
    base = np.linspace(0.0, 2e-5, K)
    return base + rng.normal(0.0, 1e-5, (samples, K))


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_each_sample_is_its_own_sequence_and_chunks_change_nothing(mu, tmp_path):
    assembly = _assembly(mu)
    rng = np.random.default_rng(3)
    samples = _gaps(rng, 6)
    shear = assembly.load_vector("upper", np.arange(K), [5.0, 0.0, 0.0])
    steps = [("shear 5 N", shear), ("unloaded", np.zeros_like(shear))]
    case = SequenceVariation(assembly, samples.mean(axis=0), order=[2, 0, 1], load_steps=steps)
    assert case.nominal.success and case.n_contacts == K
    summary = run_batch(case, GapSamples(samples), 6, tmp_path / "a.h5", chunk_size=2)
    assert summary.failed == 0
    fields = load_batch(tmp_path / "a.h5").fields
    for n, gaps in enumerate(samples):
        direct = assembly.sequence(gaps, order=[2, 0, 1], load_steps=steps)  # cold, stage by stage
        final = direct.final
        scale = np.abs(final.normal_forces).max()
        np.testing.assert_allclose(fields["gap"][n], final.gaps, atol=1e-10)
        np.testing.assert_allclose(
            fields["normal_force"][n], final.normal_forces, atol=1e-7 * scale
        )
        np.testing.assert_allclose(
            fields["fastener_force"][n], final.fastener_forces, rtol=1e-6, atol=1e-7 * scale
        )
        np.testing.assert_array_equal(fields["status"][n], final.status)
        in_contact = np.isin(
            final.status, [ContactStatus.STICK, ContactStatus.SLIP, ContactStatus.CLOSED]
        )
        np.testing.assert_array_equal(fields["closed"][n], in_contact)
        assert fields["dissipated"][n] == pytest.approx(
            sum(stage.dissipated for stage in direct.stages), rel=1e-6, abs=1e-15
        )
    if mu == 0:
        assert not np.isin(fields["status"], [ContactStatus.STICK, ContactStatus.SLIP]).any()
    else:
        assert np.isin(fields["status"], [ContactStatus.STICK, ContactStatus.SLIP]).any()
    # every sample starts from the nominal sequence: one chunk or three, the same numbers
    run_batch(case, GapSamples(samples), 6, tmp_path / "b.h5", chunk_size=6)
    other = load_batch(tmp_path / "b.h5").fields
    for name, values in fields.items():
        np.testing.assert_array_equal(other[name], values, err_msg=name)
    # each stage from the sample's previous one: the same answers, to the solver's accuracy
    previous = SequenceVariation(
        assembly, samples.mean(axis=0), order=[2, 0, 1], load_steps=steps, start="previous"
    )
    run_batch(previous, GapSamples(samples), 6, tmp_path / "c.h5", chunk_size=4)
    other = load_batch(tmp_path / "c.h5").fields
    np.testing.assert_allclose(other["gap"], fields["gap"], atol=1e-10)
    np.testing.assert_array_equal(other["status"], fields["status"])


def test_store_statistics_count_the_samples_above_the_shim_tolerance(tmp_path):
    assembly = _assembly(0.3)
    samples = _gaps(np.random.default_rng(8), 8)
    case = SequenceVariation(assembly, samples.mean(axis=0))
    run_batch(case, GapSamples(samples), 8, tmp_path / "s.h5", chunk_size=3)
    data = load_batch(tmp_path / "s.h5")
    tolerance = float(np.median(data.fields["gap"][data.fields["gap"] > 0]))
    stats = data.statistics(levels=(0.1, 0.9), shim_tolerance=tolerance)
    ok = data.fields["success"]
    assert ok.all() and stats.samples == 8
    above = np.zeros(K)
    for row in data.fields["gap"]:
        above += [gap > tolerance for gap in row]
    np.testing.assert_array_equal(stats.shim_probability, above / 8)
    assert 0 < stats.shim_probability.max() and stats.shim_probability.min() < 1
    np.testing.assert_array_equal(stats.contact_probability, data.fields["closed"].mean(axis=0))
    # the fastened pairs are never in contact, the record says so
    assert not data.fields["closed"][:, [0, 5, K - 1]].any()


def test_a_store_of_another_assembly_is_refused(tmp_path):
    from contactqp.errors import InvalidInputError

    samples = _gaps(np.random.default_rng(1), 2)
    run_batch(
        SequenceVariation(_assembly(0.3), samples[0]), GapSamples(samples), 2, tmp_path / "s.h5"
    )
    other = SequenceVariation(_assembly(0.2), samples[0])
    with pytest.raises(InvalidInputError):
        run_batch(other, GapSamples(samples), 2, tmp_path / "s.h5")
    with pytest.raises(InvalidInputError, match="start"):
        SequenceVariation(_assembly(0.3), samples[0], start="sample")


def test_a_real_sequence_goes_through_the_writers(tmp_path):
    """The output module on an Assembly's own stages: files read back, forces consistent."""
    import meshio

    from contactqp.applications.fastening.output import sequence_summary, write_sequence

    assembly = _assembly(0.3)
    shear = assembly.load_vector("upper", np.arange(K), [5.0, 0.0, 0.0])
    gaps = _gaps(np.random.default_rng(5), 1)[0]
    sequence = assembly.sequence(gaps, load_steps=[("shear 5 N", shear)])
    files = write_sequence(
        tmp_path, sequence, assembly.points, assembly.normals, initial_gaps=gaps, plot=True
    )
    assert len([name for name in files if name.endswith(".vtu")]) == len(sequence.stages) == 4
    final = meshio.read(files["stage_004.vtu"]).point_data
    np.testing.assert_array_equal(final["gap"], sequence.final.gaps)
    np.testing.assert_allclose(
        np.sum(final["contact_force"] * assembly.normals, axis=1), -sequence.final.normal_forces
    )
    table = np.genfromtxt(files["fasteners.csv"], delimiter=",", names=True, dtype=None)
    np.testing.assert_array_equal(table["force_N"][-3:], sequence.final.fastener_forces)
    summary = sequence_summary(sequence)
    assert summary["success"] is sequence.success is True
    assert summary["stages"][-1]["contacts"]["fastened"] == 3

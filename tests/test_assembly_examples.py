"""The assembly files of examples/assemblies/, each checked against independent truths.

* ``riveting.toml``: today's riveting plates (``contactqp riveting``, 25 x 21 pairs) as an
  assembly file. Truth: :class:`~contactqp.applications.riveting.RivetingModel` and the
  ``contactqp riveting`` command's files (nominal sequence, nominal contacts, statistics).
* ``blocks.toml``: two 3-D blocks meshed with the embedded finite elements, read from the mesh
  files ``make_blocks.py`` writes, with friction. Truths: the order changes the end state;
  mu = 0 is the frictionless fastened problem; dissipation is non-negative; each part's full
  finite-element analysis under the reported forces gives the reduced displacements.
* ``blocks-ansys.toml``: the same, the lower part from an ANSYS ``.full`` file. Truth: the
  answers of ``blocks.toml`` and of the same assembly built in Python.
"""

from __future__ import annotations

import csv
import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

import contactqp
from contactqp import ContactProblem, NodePairs, ReducedModel
from contactqp.applications.assembly_file import read_assembly_file
from contactqp.applications.fastening import Assembly, AssemblyPart, Fastener, InterfacePairs
from contactqp.applications.fastening.study import SequenceVariation
from contactqp.applications.riveting import Assembly as Plates
from contactqp.core.fastened import FastenedProblem
from contactqp.core.status import ContactStatus
from contactqp.studies import GaussianGapField, load_batch, run_batch

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "assemblies"
SAMPLES, SEED = 4, 0


def _relative(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def _csv(path: Path) -> dict:
    """``{header: column}``: numbers as float arrays, words as lists."""
    with open(path, newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    columns = {}
    for name in rows[0]:
        values = [row[name] for row in rows]
        try:
            columns[name] = np.array(values, dtype=float)
        except ValueError:
            columns[name] = values
    return columns


def _sequence(read, assembly, **extra):
    return assembly.sequence(
        read.gaps, load_steps=read.load_steps, method=read.method, **read.options, **extra
    )


# ---------------------------------------------------------------------------- riveting plates


@pytest.fixture(scope="module")
def plates():
    """Today's riveting model (the truth) and the assembly file read, each built once."""
    model = Plates().build()
    read = read_assembly_file(EXAMPLES / "riveting.toml")
    return model, read, read.to_assembly()


@pytest.fixture(scope="module")
def riveting_command(tmp_path_factory):
    """``contactqp riveting`` with a few samples: today's files."""
    from contactqp.cli import main

    out = tmp_path_factory.mktemp("riveting")
    assert (
        main(["riveting", "--samples", str(SAMPLES), "--seed", str(SEED), "--out", str(out)]) == 0
    )
    return out


def test_the_riveting_file_is_todays_assembly(plates):
    model, read, assembly = plates
    lower, upper = model.assembly.flexibilities
    assert assembly.n_pairs == model.n_pairs == 525 and assembly.dofs_per_node == 1
    assert np.array_equal(assembly.points[:, :2], model.points)
    assert [f.pair for f in assembly.fasteners] == model.fasteners.tolist()
    assert all(f.kind == "closure" and f.shear == "free" for f in assembly.fasteners)
    assert np.array_equal(read.gaps, np.full(525, 2e-4)) and not np.any(assembly.mu)
    assert read.kind == "fastened" and read.method == "lawson-hanson"
    k = model.n_pairs
    assert _relative(assembly.model.flexibility[:k, :k], lower) < 1e-12
    assert _relative(assembly.model.flexibility[k:, k:], upper) < 1e-12
    # the variation is today's random field: the same realisations for the same seed
    today = GaussianGapField(model.points, 1e-4, 0.04, mean=2e-4, seed=SEED)
    indices = np.arange(SAMPLES)
    assert np.array_equal(read.variation.realisations(indices), today.realisations(indices))


def test_the_riveting_file_gives_todays_nominal_sequence(plates, riveting_command):
    model, read, assembly = plates
    sequence = _sequence(read, assembly)
    truth = model.fasten(read.gaps)
    assert sequence.success and truth.success
    for stage, step in zip(sequence.stages, truth.steps, strict=True):
        assert np.array_equal(stage.fasteners, step.fasteners)
        # the link's axial force, signed (today's fastener_forces are its tension part)
        assert _relative(stage.fastener_forces, -step.multipliers[step.fasteners]) < 1e-9
        assert np.max(np.abs(stage.gaps - step.gaps)) < 1e-12 * 2e-4
    # the command's files, written to 17 digits
    rows = _csv(riveting_command / "nominal_sequence.csv")
    assert rows["pair"].tolist() == model.fasteners.tolist()
    tensions = [stage.fastener_forces[-1] for stage in sequence.stages]
    assert _relative(tensions, rows["tension"]) < 1e-9
    assert rows["tension"][0] == pytest.approx(97.145067, rel=1e-7)  # the first rivet
    closed = [np.count_nonzero(s.status == ContactStatus.CLOSED) for s in sequence.stages]
    assert closed == rows["closed"].tolist()
    assert _relative([s.gaps.max() for s in sequence.stages], rows["max_gap"]) < 1e-9
    contacts = _csv(riveting_command / "nominal_contacts.csv")
    final = sequence.final
    assert np.max(np.abs(final.gaps - contacts["gap"])) < 1e-12 * 2e-4
    # today's contact force includes a fastener's compression (a negative axial force)
    compression = final.normal_forces.copy()
    compression[final.fasteners] = np.maximum(-final.fastener_forces, 0.0)
    assert np.max(np.abs(compression - contacts["force"])) < 1e-9 * np.max(contacts["force"])
    labels = {"open": ContactStatus.OPEN, "closed": ContactStatus.CLOSED}
    labels["fastened"] = ContactStatus.FASTENED
    assert [labels[s] for s in contacts["status"]] == final.status.tolist()


def test_the_riveting_files_variation_gives_todays_statistics(plates, riveting_command, tmp_path):
    """The same samples of the same field: the per-pair statistics of ``contactqp riveting``
    (every fastener at once) equal those of the file's sequences (one by one: without
    friction the end state does not depend on the order)."""
    model, read, assembly = plates
    case = SequenceVariation(assembly, read.gaps, method=read.method)
    run_batch(case, read.variation, SAMPLES, tmp_path / "samples.h5")
    statistics = load_batch(tmp_path / "samples.h5", SAMPLES).statistics()
    today = _csv(riveting_command / "statistics.csv")
    scale = 2e-4
    assert np.max(np.abs(statistics.mean - today["mean_gap"])) < 1e-9 * scale
    for level, quantile in zip(statistics.levels, statistics.quantiles, strict=True):
        assert np.max(np.abs(quantile - today[f"gap_q{level * 100:g}"])) < 1e-9 * scale
    # fastened pairs are not counted as contact in either
    assert np.array_equal(statistics.contact_probability, today["contact_probability"])
    assert 0 < np.mean(today["contact_probability"]) < 1


# ---------------------------------------------------------------------------- the blocks


@pytest.fixture(scope="module")
def generator():
    """examples/assemblies/make_blocks.py as a module."""
    spec = importlib.util.spec_from_file_location("make_blocks", EXAMPLES / "make_blocks.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def block_files(generator, tmp_path_factory):
    return generator.main(tmp_path_factory.mktemp("blocks"))


@pytest.fixture(scope="module")
def reference_parts(generator):
    """The generator's parts built in Python: ``[(body, interface nodes, reduced model)]``."""
    parts = []
    for body in (generator.lower_body(), generator.upper_body()):
        nodes = generator.interface_nodes(body)
        parts.append((body, nodes, body.reduced_model(nodes)))
    return parts


@pytest.fixture(scope="module")
def blocks(block_files):
    """blocks.toml read, its assembly, and its sequence in the file's order and in another."""
    read = read_assembly_file(block_files / "blocks.toml")
    assembly = read.to_assembly()
    sequences = {
        "file": _sequence(read, assembly),
        "other": _sequence(read, assembly, order=[1, 0, 2]),  # left, middle, right
    }
    return read, assembly, sequences


def test_the_blocks_come_from_their_mesh_files(generator, reference_parts, blocks):
    read, assembly, _ = blocks
    assert assembly.n_pairs == 45 and not read.unmatched and assembly.dofs_per_node == 3
    assert [f.label for f in read.fasteners] == ["middle", "left", "right"]
    assert all(f.kind == "closure" and f.shear == "bonded" for f in read.fasteners)
    assert np.all(assembly.mu == 0.3) and read.kind == "frictional"
    assert [label for label, _ in read.load_steps] == ["shear", "shear removed"]
    for part, (body, nodes, model) in zip(read.parts, reference_parts, strict=True):
        assert np.array_equal(part.fe_model.mesh.p, body.mesh.p)
        assert np.array_equal(part.mesh_nodes, nodes)
        assert _relative(part.model.flexibility, model.flexibility) < 1e-10
    # the measured cloud, linearly interpolated: within its reported error of the measured shape
    truth = generator.measured_gap(*assembly.points[:, :2].T)
    assert np.max(np.abs(read.gaps - truth)) <= read.interpolation_error.max_abs
    assert read.interpolation_error.max_abs < 0.1 * np.max(truth)


def test_with_friction_the_blocks_end_state_depends_on_the_order(blocks):
    read, assembly, sequences = blocks
    first, second = sequences["file"], sequences["other"]
    assert first.success and second.success
    n = len(read.fasteners)
    for stage in (n - 1, -1):  # fastened, and after the shear load and its removal
        a, b = first.stages[stage], second.stages[stage]
        by_pair = dict(zip(b.fasteners, b.fastener_forces, strict=True))
        difference = _relative(a.fastener_forces, [by_pair[p] for p in a.fasteners])
        tolerance = max(a.result.certificate.tol, b.result.certificate.tol)
        assert difference > 1e-3 and difference > 1e4 * tolerance
        assert _relative(a.tangential_forces, b.tangential_forces) > 1e-2
        assert np.max(np.abs(a.gaps - b.gaps)) > 1e3 * tolerance * np.max(read.gaps)
    assert any(np.any(s.status == ContactStatus.SLIP) for s in first.stages)


def test_the_blocks_dissipation_is_non_negative_at_every_stage(blocks):
    read, assembly, sequences = blocks
    for sequence in sequences.values():
        for stage in sequence.stages:
            dissipation = stage.result.dissipation
            assert np.all(dissipation >= -1e-9 * np.abs(dissipation).max(initial=1e-300))
            assert stage.dissipated >= 0
        assert sum(stage.dissipated for stage in sequence.stages) > 1e-6  # J


def _frictionless_variant(block_files: Path) -> Path:
    """blocks.toml with mu = 0 and fasteners free in shear (the fastened problem's closures)."""
    text = (block_files / "blocks.toml").read_text()
    text = text.replace("mu = 0.3", "mu = 0.0")
    text = re.sub(r"\[\[fasteners\]\]\n", '[[fasteners]]\nshear = "free"\n', text)
    path = block_files / "blocks-frictionless.toml"
    path.write_text(text)
    return path


def test_mu_zero_through_the_file_is_the_frictionless_fastened_problem(
    block_files, reference_parts
):
    """Every stage of the file with mu = 0 equals FastenedProblem on the parts built in Python
    (an independent elimination of the closures), the shear stages included."""
    read = read_assembly_file(_frictionless_variant(block_files))
    assembly = read.to_assembly()
    assert read.kind == "fastened" and not assembly.frictional
    sequence = _sequence(read, assembly)
    assert sequence.success
    blocks = [model.flexibility for _, _, model in reference_parts]
    model = ReducedModel(flexibility=scipy.linalg.block_diag(*blocks), dofs_per_node=3)
    k = assembly.n_pairs
    pairs = NodePairs(assembly.pairs, read.gaps, np.tile([0.0, 0.0, 1.0], (k, 1)))
    shear = np.zeros((2 * k, 3))
    shear[k:, 0] = 150.0 / k  # on the upper part's interface nodes
    loads = [np.zeros(6 * k)] * len(read.fasteners) + [shear.ravel(), np.zeros(6 * k)]
    installed = [f.pair for f in read.fasteners]
    for number, (stage, load) in enumerate(zip(sequence.stages, loads, strict=True)):
        count = min(number + 1, len(installed))
        truth = contactqp.solve(
            FastenedProblem(ContactProblem(model, load, [pairs]), installed[:count])
        )
        assert truth.success
        assert _relative(stage.gaps, truth.gaps) < 1e-7
        contacts = np.setdiff1d(np.arange(k), installed[:count])
        assert _relative(stage.normal_forces[contacts], truth.forces[contacts]) < 1e-7
        assert _relative(stage.fastener_forces, -truth.multipliers[installed[:count]]) < 1e-7
        assert np.all(stage.tangential_forces == 0)


def test_full_fe_analyses_of_the_blocks_reproduce_every_stage(reference_parts, blocks):
    """Each part's full finite-element model (built in Python), under the contact, fastener
    and shear forces the stage reports at its interface nodes, deforms as the reduced model
    says there."""
    read, assembly, sequences = blocks
    k = assembly.n_pairs
    for sequence in sequences.values():
        for stage in sequence.stages:
            result = stage.result
            applied = (result.loads + result.nodal_forces).reshape(2 * k, 3)
            reduced = result.displacements.reshape(2 * k, 3)
            for side, (body, nodes, _) in enumerate(reference_parts):
                nodal = np.zeros((body.n_nodes, 3))
                nodal[nodes] = applied[side * k : (side + 1) * k]
                full = body.solve(nodal)[nodes]
                part = reduced[side * k : (side + 1) * k]
                assert np.max(np.abs(full - part)) < 1e-8 * np.max(np.abs(part))
        # the closures hold, bonded: no tangential motion after installation
        for stage in sequence.stages[1:]:
            assert np.allclose(stage.gaps[stage.fasteners], 0.0, atol=1e-12)
            assert np.max(np.abs(stage.slip[stage.fasteners])) < 1e-9 * np.max(read.gaps)


# ---------------------------------------------------------------------------- from ANSYS


@pytest.fixture(scope="module")
def ansys_blocks(block_files):
    read = read_assembly_file(block_files / "blocks-ansys.toml")
    return read, read.to_assembly()


def _same_stages(sequence, reference, rtol):
    assert sequence.success and reference.success
    assert len(sequence.stages) == len(reference.stages)
    for a, b in zip(sequence.stages, reference.stages, strict=True):
        assert a.label == b.label and np.array_equal(a.fasteners, b.fasteners)
        assert np.array_equal(a.status, b.status)
        assert _relative(a.gaps, b.gaps) < rtol
        assert _relative(a.normal_forces, b.normal_forces) < rtol
        assert _relative(a.tangential_forces, b.tangential_forces) < rtol
        assert _relative(a.fastener_forces, b.fastener_forces) < rtol


def test_the_ansys_part_is_the_mesh_part(ansys_blocks, blocks, reference_parts):
    read, assembly = ansys_blocks
    mesh_read, mesh_assembly, _ = blocks
    lower = read.part("lower")
    assert lower.fe_model is None  # a matrix part: no mesh behind it
    assert np.array_equal(lower.coordinates, mesh_read.part("lower").coordinates)
    # condensed on reading from the whole stiffness, clamped freedoms removed
    assert _relative(lower.model.flexibility, reference_parts[0][2].flexibility) < 1e-9
    assert np.array_equal(assembly.pairs, mesh_assembly.pairs)
    assert np.array_equal(read.gaps, mesh_read.gaps)


def test_the_ansys_blocks_give_the_mesh_blocks_answers(ansys_blocks, blocks):
    read, assembly = ansys_blocks
    _, _, sequences = blocks
    _same_stages(_sequence(read, assembly), sequences["file"], 1e-8)


def test_the_ansys_blocks_give_the_answers_of_the_assembly_built_in_python(
    generator, ansys_blocks, reference_parts
):
    read, _ = ansys_blocks
    parts = [
        AssemblyPart(name, model, model.coordinates)
        for name, (_, _, model) in zip(("lower", "upper"), reference_parts, strict=True)
    ]
    lower, upper = (model.coordinates for _, _, model in reference_parts)
    # pair the facing nodes by position (x, y): each upper node lies on a lower one
    key = lambda xyz: np.lexsort((xyz[:, 1], xyz[:, 0]))  # noqa: E731
    pairs = np.column_stack([key(lower), key(upper)])
    pairs = pairs[np.argsort(pairs[:, 0])]
    assert np.allclose(lower[pairs[:, 0]], upper[pairs[:, 1]], rtol=0, atol=1e-12)
    k = len(pairs)
    interface = InterfacePairs("lower", "upper", pairs, np.tile([0.0, 0.0, 1.0], (k, 1)))
    points = lower[pairs[:, 0], :2]
    order = [(0.05, 0.02), (0.02, 0.02), (0.08, 0.02)]  # middle, left, right
    fasteners = [
        Fastener(int(np.argmin(np.linalg.norm(points - p, axis=1))), label=label)
        for p, label in zip(order, ("middle", "left", "right"), strict=True)
    ]
    python = Assembly(parts, [interface], fasteners, mu=0.3)
    shear = python.load_vector("upper", np.arange(k), [150.0, 0.0, 0.0])
    steps = [("shear", shear), ("shear removed", np.zeros_like(shear))]
    reference = python.sequence(read.gaps, load_steps=steps)
    _same_stages(_sequence(read, read.to_assembly()), reference, 1e-8)


# ---------------------------------------------------------------------------- contactqp assembly


def _command(assembly_file: Path, out: Path, *options: str) -> Path:
    from contactqp.cli import main

    argv = ["assembly", str(assembly_file), "--out", str(out), "--samples", str(SAMPLES)]
    assert main([*argv, *options]) == 0
    return out


def _stage(table: dict, number: int) -> dict:
    """The rows of stage ``number`` (from 1) of ``stages.csv``, in pair order."""
    rows = np.flatnonzero(table["stage"] == number)
    assert np.array_equal(table["pair"][rows], np.arange(rows.size))
    return {
        name: (column[rows] if isinstance(column, np.ndarray) else [column[i] for i in rows])
        for name, column in table.items()
    }


def test_contactqp_assembly_on_the_riveting_file_writes_todays_numbers(
    plates, riveting_command, tmp_path
):
    """``contactqp assembly riveting.toml`` against ``contactqp riveting``: the nominal
    sequence's tensions, the final gaps and statuses, and the statistics of the same samples."""
    model, _, _ = plates
    out = _command(EXAMPLES / "riveting.toml", tmp_path / "assembly", "--seed", str(SEED))
    today = _csv(riveting_command / "nominal_sequence.csv")
    fasteners = _csv(out / "fasteners.csv")
    n = len(today["tension"])
    installed = [
        fasteners["force (N)"][(fasteners["stage"] == s) & (fasteners["fastener"] == s)][0]
        for s in range(1, n + 1)
    ]
    assert _relative(installed, today["tension"]) < 1e-9
    final = _stage(_csv(out / "stages.csv"), n)
    contacts = _csv(riveting_command / "nominal_contacts.csv")
    assert np.max(np.abs(final["gap (m)"] - contacts["gap"])) < 1e-12 * 2e-4
    assert final["status"] == contacts["status"]
    free = np.setdiff1d(np.arange(model.n_pairs), model.fasteners)
    force = final["normal_force (N)"][free]
    assert np.max(np.abs(force - contacts["force"][free])) < 1e-9 * np.max(contacts["force"])
    statistics, expected = _csv(out / "statistics.csv"), _csv(riveting_command / "statistics.csv")
    for name in ("mean_gap", "gap_q5", "gap_q50", "gap_q95"):
        assert np.max(np.abs(statistics[f"{name} (m)"] - expected[name])) < 1e-9 * 2e-4
    assert np.array_equal(statistics["contact_probability (-)"], expected["contact_probability"])


def test_contactqp_assembly_on_the_blocks_files_writes_their_sequences(
    block_files, blocks, tmp_path
):
    """Both blocks files through the command: every stage in ``stages.csv`` and
    ``fasteners.csv`` is the library's sequence, and both files' variation studies agree."""
    read, assembly, sequences = blocks
    statistics = []
    for name in ("blocks.toml", "blocks-ansys.toml"):
        out = _command(block_files / name, tmp_path / name.removesuffix(".toml"))
        table, forces = _csv(out / "stages.csv"), _csv(out / "fasteners.csv")
        for number, stage in enumerate(sequences["file"].stages, start=1):
            rows = _stage(table, number)
            assert rows["label"][0] == stage.label
            assert _relative(rows["gap (m)"], stage.gaps) < 1e-7
            assert _relative(rows["normal_force (N)"], stage.normal_forces) < 1e-7
            tangential = np.column_stack(
                [rows["tangential_force_t1 (N)"], rows["tangential_force_t2 (N)"]]
            )
            assert _relative(tangential, stage.tangential_forces) < 1e-7
            written = forces["force (N)"][forces["stage"] == number]
            assert _relative(written, stage.fastener_forces) < 1e-7
        statistics.append(_csv(out / "statistics.csv"))
    blocks_statistics, ansys_statistics = statistics
    for column in ("mean_gap (m)", "gap_q5 (m)", "gap_q95 (m)"):
        assert _relative(ansys_statistics[column], blocks_statistics[column]) < 1e-7
    shim = [c for c in blocks_statistics if c.startswith("shim_probability")]
    assert shim and np.all((0 <= blocks_statistics[shim[0]]) & (blocks_statistics[shim[0]] <= 1))

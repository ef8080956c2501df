"""The assembly study as a library call (``run_assembly_study``): the files hold a direct
``Assembly.sequence``, the statistics the samples solved one by one; a resumed study computes
nothing again, a study run in two calls or on a pool or a Dask cluster stores the numbers of one
run in one process; bad input is refused before anything is written."""

from __future__ import annotations

import csv

import meshio
import numpy as np
import pytest

from assembly_files import PLATES, blocks, write
from contactqp.applications.assembly_file import read_assembly_file
from contactqp.applications.fastening.workflow import run_assembly_study
from contactqp.core.status import status_labels
from contactqp.errors import ContactError, InvalidInputError
from contactqp.studies import load_batch

SAMPLES = 6


def read_table(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def direct(path):
    """The file's nominal sequence, solved directly, and its input."""
    given = read_assembly_file(path)
    assembly = given.to_assembly()
    sequence = assembly.sequence(
        given.gaps, load_steps=given.load_steps, method=given.method, **given.options
    )
    return given, assembly, sequence


def assert_same_store(first, second):
    """Two stores hold the same samples, bit for bit."""
    ours, theirs = load_batch(first), load_batch(second)
    np.testing.assert_array_equal(ours.indices, theirs.indices)
    assert ours.fields.keys() == theirs.fields.keys()
    for name, values in theirs.fields.items():
        np.testing.assert_array_equal(ours.fields[name], values, err_msg=name)


def column(rows, name):
    return np.array([float(row[name]) for row in rows])


@pytest.fixture(scope="module")
def blocks_file(tmp_path_factory):
    return write(tmp_path_factory.mktemp("blocks"), blocks())


@pytest.fixture(scope="module")
def blocks_study(blocks_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("blocks_out")
    return run_assembly_study(blocks_file, out, samples=SAMPLES), out


@pytest.mark.parametrize("example", ["plates", "blocks"])
def test_the_files_hold_the_direct_sequence(example, blocks_file, blocks_study, tmp_path):
    if example == "plates":
        path, out = PLATES, tmp_path
        study = run_assembly_study(path, out, samples=2)
    else:
        path, (study, out) = blocks_file, blocks_study
    given, assembly, sequence = direct(path)
    assert study.success and study.assembly.n_pairs == assembly.n_pairs
    k, stages = assembly.n_pairs, sequence.stages
    rows = read_table(out / "stages.csv")
    assert len(rows) == len(stages) * k
    for number, stage in enumerate(stages):
        block = rows[number * k : (number + 1) * k]
        assert {row["label"] for row in block} == {stage.label}
        np.testing.assert_array_equal(column(block, "initial_gap (m)"), given.gaps)
        np.testing.assert_array_equal(column(block, "gap (m)"), stage.gaps)
        np.testing.assert_array_equal(column(block, "normal_force (N)"), stage.normal_forces)
        for axis in (0, 1):
            np.testing.assert_array_equal(
                column(block, f"tangential_force_t{axis + 1} (N)"),
                stage.tangential_forces[:, axis],
            )
            np.testing.assert_array_equal(
                column(block, f"slip_t{axis + 1} (m)"), stage.slip[:, axis]
            )
        assert [row["status"] for row in block] == status_labels(stage.status)
        mesh = meshio.read(out / f"stage_{number + 1:03d}.vtu")
        np.testing.assert_array_equal(mesh.points, assembly.points)
        np.testing.assert_array_equal(mesh.point_data["gap"], stage.gaps)
    forces = read_table(out / "fasteners.csv")
    last = [row for row in forces if int(row["stage"]) == len(stages)]
    assert [int(row["pair"]) for row in last] == sequence.final.fasteners.tolist()
    np.testing.assert_array_equal(column(last, "force (N)"), sequence.final.fastener_forces)
    installed = [int(row["pair"]) for row in forces if int(row["stage"]) == len(given.fasteners)]
    assert installed == [f.pair for f in given.fasteners]  # the file's order
    shims = read_table(out / "shims.csv")
    expected = np.flatnonzero(sequence.final.gaps > given.shim_tolerance)
    assert [int(row["pair"]) for row in shims] == expected.tolist()
    assert (out / "stages.pvd").is_file() and (out / "statistics.csv").is_file()
    assert all(path.is_file() and path.parent == out for path in study.files.values())


def test_the_frictional_example_slips_and_dissipates(blocks_study):
    study, _ = blocks_study
    upper = study.input.part("upper")
    shear = study.assembly.load_vector("upper", np.arange(upper.model.n_nodes), [200.0, 0, 0])
    np.testing.assert_array_equal(study.input.load_steps[0][1], shear)  # h3's layout is h2's
    labels = [stage.label for stage in study.nominal.stages]
    assert labels[-2:] == ["shear", "shear removed"]
    assert "slip" in status_labels(study.nominal.stages[-2].status)
    dissipated = np.array([stage.dissipated for stage in study.nominal.stages])
    assert dissipated[-2] > 0 and np.all(dissipated >= -1e-9 * dissipated.max())  # round-off


def test_the_statistics_are_those_of_the_samples_solved_one_by_one(blocks_file, blocks_study):
    study, out = blocks_study
    given, assembly, sequence = direct(blocks_file)
    fields = given.variation.realisations(range(SAMPLES))
    finals = [
        assembly.sequence(
            gaps, load_steps=given.load_steps, method=given.method, **given.options
        ).final
        for gaps in fields
    ]
    gaps = np.array([final.gaps for final in finals])
    rows = read_table(out / "statistics.csv")
    scale = np.abs(gaps).max()
    np.testing.assert_allclose(column(rows, "mean_gap (m)"), gaps.mean(axis=0), atol=1e-9 * scale)
    np.testing.assert_allclose(
        column(rows, "shim_probability (-)"), (gaps > given.shim_tolerance).mean(axis=0)
    )
    np.testing.assert_array_equal(study.statistics.mean, column(rows, "mean_gap (m)"))
    assert study.statistics.samples == SAMPLES


def test_the_interpolation_error_and_the_unmatched_nodes_are_in_the_study(tmp_path):
    doc = blocks(variation=None)
    doc["parts"]["lower"]["mesh"]["cells"] = [4, 1, 1]  # 10 nodes on top, 6 below the upper
    study = run_assembly_study(write(tmp_path, doc), tmp_path / "out")
    assert study.summary is None and study.statistics is None and study.success
    error = study.interpolation_error
    assert error is not None and error.n_points == 45 and error.max_abs > 0
    assert len(study.unmatched) == 1
    notes = study.notes()
    assert notes[0] == error.describe() and notes[1] == study.unmatched[0].describe()
    assert "4" in notes[1]
    assert not (tmp_path / "out" / "samples.h5").exists()


def test_a_finished_study_resumed_computes_nothing(blocks_file, blocks_study):
    _, out = blocks_study
    again = run_assembly_study(blocks_file, out, samples=SAMPLES)
    assert (again.summary.computed, again.summary.reused) == (0, SAMPLES)


def test_a_study_in_two_calls_stores_the_numbers_of_one_run(blocks_file, tmp_path):
    first = run_assembly_study(blocks_file, tmp_path / "split", samples=2)
    assert first.summary.computed == 2
    second = run_assembly_study(blocks_file, tmp_path / "split", samples=4)
    assert (second.summary.computed, second.summary.reused) == (2, 2)
    whole = run_assembly_study(blocks_file, tmp_path / "whole", samples=4)
    assert_same_store(tmp_path / "split" / "samples.h5", tmp_path / "whole" / "samples.h5")
    for name in ("statistics.csv", "stages.csv"):
        assert (tmp_path / "split" / name).read_bytes() == (tmp_path / "whole" / name).read_bytes()
    np.testing.assert_array_equal(second.statistics.mean, whole.statistics.mean)


def test_a_process_pool_stores_the_numbers_of_one_process(blocks_file, blocks_study, tmp_path):
    _, out = blocks_study
    pool = run_assembly_study(blocks_file, tmp_path, samples=SAMPLES, workers=2)
    assert pool.summary.computed == SAMPLES
    assert_same_store(tmp_path / "samples.h5", out / "samples.h5")
    assert (tmp_path / "statistics.csv").read_bytes() == (out / "statistics.csv").read_bytes()


def test_a_dask_cluster_stores_the_numbers_of_one_process(blocks_file, blocks_study, tmp_path):
    import distributed

    _, out = blocks_study
    # threads in this process, reached over TCP like a remote scheduler
    with distributed.LocalCluster(
        n_workers=1,
        processes=False,
        threads_per_worker=1,
        protocol="tcp",
        host="127.0.0.1",
        dashboard_address=":0",  # a free port: no clash with another run on this machine
    ) as cluster:
        study = run_assembly_study(
            blocks_file, tmp_path, samples=SAMPLES, scheduler=cluster.scheduler_address
        )
    assert study.summary.computed == SAMPLES
    assert_same_store(tmp_path / "samples.h5", out / "samples.h5")


def test_a_seed_given_replaces_the_files_seed(tmp_path):
    doc = blocks()
    seeded = run_assembly_study(write(tmp_path / "a", doc), tmp_path / "a", samples=3, seed=9)
    doc["variation"]["seed"] = 9
    same = run_assembly_study(write(tmp_path / "b", doc), tmp_path / "b", samples=3)
    assert_same_store(tmp_path / "a" / "samples.h5", tmp_path / "b" / "samples.h5")
    assert seeded.input.variation_description.endswith("seed 9 (seed)")
    assert seeded.notes()[-1] == f"variation: {seeded.input.variation_description}"
    np.testing.assert_array_equal(seeded.statistics.mean, same.statistics.mean)
    doc["variation"]["seed"] = 4
    other = run_assembly_study(write(tmp_path / "c", doc), tmp_path / "c", samples=3)
    assert not np.array_equal(other.statistics.mean, same.statistics.mean)


def test_a_failed_solve_is_not_an_exception_and_its_files_are_written(tmp_path):
    doc = blocks(solver={"method": "coulomb", "max_iter": 1})
    study = run_assembly_study(write(tmp_path, doc), tmp_path / "out", samples=2)
    assert not study.success and not study.nominal.success
    assert (tmp_path / "out" / "stages.csv").is_file()
    assert study.summary.failed == 2 and study.statistics is None
    assert not (tmp_path / "out" / "statistics.csv").exists()


def listing(folder):
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else None


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("missing file", r"no-such\.toml"),
        ("bad key", r"assembly\.toml: gaps: unknown key 'nominl'"),
        ("samples without variation", r"^samples: the assembly file has no \[variation\]"),
        ("seed of realisations", r"^seed: the variation is not random"),
        ("too many samples", r"^samples: 5 asked, the variation has 2 realisations"),
        ("out is a file", r"^out: '.*' is a file, not a directory"),
        ("out over an input", r"^out: the study would overwrite its input file '.*stages\.csv'"),
        ("bad samples", r"^samples must be an integer >= 1, got 0"),
        ("bad scheduler", r"Dask scheduler 'no-port'"),
        ("no workers", r"^workers must be an integer >= 1, got None"),
    ],
)
def test_bad_input_is_refused_before_anything_is_written(tmp_path, case, message):
    folder = tmp_path / "in"
    doc = blocks()
    out = tmp_path / "out"
    options: dict = {}
    if case == "bad key":
        doc["gaps"]["nominl"] = 0.1
    elif case == "samples without variation":
        doc.pop("variation")
        options["samples"] = 2
    elif case in ("seed of realisations", "too many samples"):
        doc["variation"] = {"type": "samples", "file": "rows.csv"}
        options = {"seed": 1} if case.startswith("seed") else {"samples": 5}
    elif case == "out is a file":
        out = folder / "gaps.csv"
    elif case == "out over an input":
        doc["gaps"]["cloud"] = "stages.csv"
        out = folder
    elif case == "bad samples":
        options["samples"] = 0
    elif case == "bad scheduler":
        options["scheduler"] = "no-port"
    elif case == "no workers":
        options["workers"] = None
    path = write(folder, doc)
    (folder / "rows.csv").write_text("\n".join(["0.0," * 5 + "0.0"] * 2) + "\n", encoding="utf-8")
    (folder / "stages.csv").write_text((folder / "gaps.csv").read_text(), encoding="utf-8")
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    if case == "missing file":
        path = folder / "no-such.toml"
    with pytest.raises(ContactError, match=message) as caught:
        run_assembly_study(path, out, **options)
    assert "\n" not in str(caught.value)
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    if out != folder and not out.is_file():
        assert listing(out) is None


def test_a_store_of_another_study_is_refused_and_nothing_else_is_written(blocks_file, tmp_path):
    run_assembly_study(PLATES, tmp_path, samples=2)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    with pytest.raises(InvalidInputError, match="samples.h5"):
        run_assembly_study(blocks_file, tmp_path, samples=2)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_messages_name_the_parameters_as_asked(tmp_path):
    with pytest.raises(InvalidInputError, match=r"^--samples: the assembly file has no"):
        run_assembly_study(
            write(tmp_path, blocks(variation=None)),
            tmp_path / "out",
            samples=3,
            names={"samples": "--samples"},
        )

"""The riveting variation study as a library call: the same stored data as the command."""

from __future__ import annotations

import json

import numpy as np
import pytest

from contactqp.applications.riveting import Assembly
from contactqp.applications.riveting_study import run_riveting_study
from contactqp.errors import ContactWarning, InvalidInputError
from contactqp.studies import load_batch

OUTPUTS = ("nominal_contacts.csv", "nominal_sequence.csv", "statistics.csv")


def assert_same_study(library_dir, command_dir):
    """The two directories hold the same samples and the same tables, bit for bit."""
    ours, theirs = load_batch(library_dir / "samples.h5"), load_batch(command_dir / "samples.h5")
    np.testing.assert_array_equal(ours.indices, theirs.indices)
    assert ours.fields.keys() == theirs.fields.keys()
    for name, values in theirs.fields.items():
        np.testing.assert_array_equal(ours.fields[name], values, err_msg=name)
    for name in OUTPUTS:
        assert (library_dir / name).read_bytes() == (command_dir / name).read_bytes(), name


def test_the_library_call_stores_what_the_command_stores(tmp_path, capsys):
    from contactqp.cli import main

    options = {
        "samples": 6,
        "seed": 3,
        "mean_gap": 1.5e-4,
        "amplitude": 8e-5,
        "correlation_length": 0.03,
    }
    argv = [f"--{key.replace('_', '-')}={value}" for key, value in options.items()]
    assert main(["riveting", *argv, "--out", str(tmp_path / "cli"), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    study = run_riveting_study(tmp_path / "lib", **options)
    assert study.success and study.model.n_pairs == 525
    assert_same_study(tmp_path / "lib", tmp_path / "cli")
    assert {k: printed[k] for k in ("samples", "computed", "reused", "failed")} == {
        k: v for k, v in study.summary.as_dict().items() if k != "seconds"
    }
    np.testing.assert_array_equal(printed["residual_gap_mean"], study.statistics.mean)
    assert sorted(study.files) == ["nominal.vtu", *OUTPUTS[:2], "samples.h5", OUTPUTS[2]]
    assert all(path.parent == tmp_path / "lib" for path in study.files.values())
    # resumed: nothing computed again
    again = run_riveting_study(tmp_path / "lib", **options)
    assert (again.summary.computed, again.summary.reused) == (0, 6)


def test_gap_rows_given_as_an_array_match_the_command_given_them_as_a_file(tmp_path, capsys):
    from contactqp.cli import main

    gaps = 2e-4 + 5e-5 * np.sin(np.arange(3 * 525)).reshape(3, 525)
    np.save(tmp_path / "g.npy", gaps)
    assert (
        main(["riveting", "--gaps", str(tmp_path / "g.npy"), "--out", str(tmp_path / "cli")]) == 0
    )
    capsys.readouterr()
    study = run_riveting_study(tmp_path / "lib", gaps=gaps)
    assert study.summary.samples == 3
    np.testing.assert_array_equal(study.nominal_gaps, gaps.mean(axis=0))
    assert_same_study(tmp_path / "lib", tmp_path / "cli")


def test_library_messages_name_the_parameters(tmp_path):
    small = Assembly(grid=(11, 7), refine=1, fasteners=((1, 3), (5, 3), (9, 3)))
    with pytest.raises(InvalidInputError, match=r"^mean_gap: an overlap of 1000 mm is deeper"):
        run_riveting_study(tmp_path / "a", mean_gap=-1.0, assembly=small)
    with pytest.raises(
        InvalidInputError,
        match=r"^gaps: gap realisations must have 77 columns, "
        r"got 5",
    ):
        run_riveting_study(tmp_path / "a", gaps=np.zeros((2, 5)), assembly=small)
    assert not (tmp_path / "a").exists()  # refused before anything is written
    with pytest.warns(ContactWarning, match=r"^mean_gap -0\.001 m is negative"):
        study = run_riveting_study(
            tmp_path / "b",
            samples=2,
            mean_gap=-1e-3,
            amplitude=0.0,
            assembly=small,
            names={"amplitude": "--amplitude"},
        )
    assert study.success and study.model.n_pairs == 77
    with pytest.warns(ContactWarning, match=r"^--amplitude 3 mm exceeds the 2 mm plate"):
        run_riveting_study(
            tmp_path / "c",
            samples=1,
            amplitude=3e-3,
            assembly=small,
            names={"amplitude": "--amplitude"},
        )

"""The assembly study as a library call: the nominal files equal a direct Assembly.sequence,
resumed and split studies give the numbers of one run, a pool the numbers of one process."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from contactqp.applications.assembly_file import read_assembly_file
from contactqp.applications.fastening.workflow import run_assembly_study
from contactqp.studies import load_batch

PLATES = Path(__file__).parent.parent / "examples" / "assemblies" / "riveting-plates.toml"


def read_table(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def test_the_nominal_files_hold_the_direct_sequence(tmp_path):
    study = run_assembly_study(PLATES, tmp_path, samples=4)
    given = read_assembly_file(PLATES)
    direct = given.to_assembly().sequence(
        given.gaps, load_steps=given.load_steps, method=given.method, **given.options
    )
    assert study.success and len(study.nominal.stages) == len(direct.stages) == 3
    rows = read_table(tmp_path / "stages.csv")
    k = study.assembly.n_pairs
    assert len(rows) == 3 * k
    for number, stage in enumerate(direct.stages):
        block = rows[number * k : (number + 1) * k]
        np.testing.assert_array_equal([float(r["gap (m)"]) for r in block], stage.gaps)
        np.testing.assert_array_equal(
            [float(r["normal_force (N)"]) for r in block], stage.normal_forces
        )
    assert study.summary is not None and study.summary.computed == 4
    assert load_batch(tmp_path / "samples.h5").fields["gap"].shape == (4, k)

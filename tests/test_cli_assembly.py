"""``contactqp assembly``: the files and the JSON line of the library call, the tables, exit
codes (bad input: one line, exit 2, nothing written; a failed solve: exit 1, files written)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from assembly_files import PLATES, blocks, write
from contactqp.applications.fastening.output import sequence_summary
from contactqp.applications.fastening.workflow import run_assembly_study
from contactqp.cli import main

NOMINAL = ("stages.csv", "fasteners.csv", "shims.csv", "stages.pvd")


def run(capsys, *args):
    code = main(["assembly", *map(str, args)])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.parametrize("example", ["plates", "blocks"])
def test_the_command_writes_what_the_library_writes(example, tmp_path, capsys):
    path = PLATES if example == "plates" else write(tmp_path / "in", blocks())
    code, out, err = run(
        capsys, path, "--samples", 3, "--seed", 2, "--out", tmp_path / "cli", "--json"
    )
    assert (code, err) == (0, "")
    printed = json.loads(out.strip().splitlines()[-1])
    study = run_assembly_study(path, tmp_path / "lib", samples=3, seed=2)
    for name in (*NOMINAL, "statistics.csv", "stage_001.vtu", "samples.h5"):
        cli, lib = tmp_path / "cli" / name, tmp_path / "lib" / name
        if name != "samples.h5":
            assert cli.read_bytes() == lib.read_bytes(), name
    expected = sequence_summary(study.nominal, shim_tolerance=study.input.shim_tolerance)
    assert {key: printed[key] for key in expected} == json.loads(json.dumps(expected))
    assert printed["files"] == sorted(study.files)
    summary = printed["study"]
    assert (summary["samples"], summary["computed"], summary["failed"]) == (3, 3, 0)
    np.testing.assert_array_equal(summary["mean_gap"], study.statistics.mean)
    np.testing.assert_array_equal(summary["shim_probability"], study.statistics.shim_probability)
    assert "seed 2" in summary["variation"]
    if example == "blocks":
        error = study.interpolation_error
        assert printed["interpolation_error"] == {
            "max_abs": error.max_abs,
            "rms": error.rms,
            "points": error.n_points,
        }
    # resumed: nothing computed again
    code, out, _ = run(
        capsys, path, "--samples", 3, "--seed", 2, "--out", tmp_path / "cli", "--json"
    )
    assert code == 0 and json.loads(out.splitlines()[-1])["study"]["reused"] == 3


def test_the_tables_and_the_notes(tmp_path, capsys):
    doc = blocks()
    doc["parts"]["lower"]["mesh"]["cells"] = [4, 1, 1]  # 4 lower nodes unmatched
    path = write(tmp_path, doc)
    code, out, err = run(capsys, path, "--samples", 2, "--out", tmp_path / "out", "--plot")
    assert (code, err) == (0, "")
    study = run_assembly_study(path, tmp_path / "out", samples=2)
    text = " ".join(out.split())
    assert "two blocks: nominal fastening sequence (6 pairs)" in text
    for line in study.notes():
        assert " ".join(line.split()) in text
    assert "gap interpolation (thin-plate" in text and "unmatched" in text
    assert "variation study: 2 samples, 2 computed, 0 reused, 0 failed" in text
    shims = np.flatnonzero(study.nominal.final.gaps > study.input.shim_tolerance)
    assert shims.size == 2
    listed = f"{shims.size}: {', '.join(map(str, shims))} (shims.csv)" if shims.size else "none"
    assert f"pairs needing a shim (gap > 5e-05 mm after the last stage): {listed}" in text
    for name in ("gap.png", "status.png", "fastener_forces.png", "statistics.png"):
        assert (tmp_path / "out" / name).stat().st_size > 0, name


def test_without_variation_there_is_no_study(tmp_path, capsys):
    path = write(tmp_path, blocks(variation=None))
    code, out, err = run(capsys, path, "--out", tmp_path, "--json")  # --out: the file's own
    assert (code, err) == (0, "")
    printed = json.loads(out.splitlines()[-1])
    assert printed["study"] is None and printed["success"] and len(printed["stages"]) == 4
    assert not (tmp_path / "samples.h5").exists() and (tmp_path / "stages.csv").is_file()


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("missing file", "no-such.toml"),
        ("bad key", "gaps: unknown key 'nominl'"),
        ("out is a file", "--out: '"),
        ("out over an input", "--out: the study would overwrite its input file"),
        ("seed without variation", "--seed: the assembly file has no [variation] table"),
        ("bad scheduler", "Dask scheduler 'no-port'"),
        ("bad samples", "--samples"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_nothing_written(tmp_path, capsys, case, message):
    folder, doc, out = tmp_path / "in", blocks(), tmp_path / "out"
    extra: list = []
    if case == "bad key":
        doc["gaps"]["nominl"] = 1.0
    elif case == "out is a file":
        out = folder / "gaps.csv"
    elif case == "out over an input":
        doc["gaps"]["cloud"] = "fasteners.csv"
        out = folder
    elif case == "seed without variation":
        doc.pop("variation")
        extra = ["--seed", 3]
    elif case == "bad scheduler":
        extra = ["--scheduler", "no-port"]
    elif case == "bad samples":
        extra = ["--samples", 0]
    path = write(folder, doc)
    (folder / "fasteners.csv").write_text((folder / "gaps.csv").read_text(), encoding="utf-8")
    if case == "missing file":
        path = folder / "no-such.toml"
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    code, out_text, err = run(capsys, path, "--out", out, *extra)
    assert code == 2 and out_text == ""
    assert err.startswith("contactqp: error: ") and err.count("\n") == 1, err
    assert message in err and "Traceback" not in err
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    if out != folder and not out.is_file():
        assert not out.exists()


def test_a_failed_solve_exits_1_with_the_files_written(tmp_path, capsys):
    path = write(tmp_path, blocks(solver={"method": "coulomb", "max_iter": 1}))
    code, out, err = run(capsys, path, "--samples", 2, "--out", tmp_path / "out", "--json")
    assert code == 1 and err.count("\n") == 1
    assert "the nominal sequence failed at 'fastener 1" in err
    printed = json.loads(out.splitlines()[-1])
    assert printed["success"] is False and printed["study"]["failed"] == 2
    for name in (*NOMINAL, "samples.h5"):
        assert (tmp_path / "out" / name).is_file(), name


def test_help_names_every_option(capsys):
    assert main(["assembly", "--help"]) == 0
    text = capsys.readouterr().out
    for option in ("--samples", "--seed", "--workers", "--scheduler", "--out", "--json", "--plot"):
        assert option in text
    assert "ASSEMBLY.toml" in text


def test_a_missing_plot_extra_is_one_line_exit_2(tmp_path, capsys, monkeypatch):
    import sys

    path = write(tmp_path / "in", blocks())
    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)  # an import that fails
    code, out, err = run(capsys, path, "--samples", 2, "--out", tmp_path / "out", "--plot")
    assert (code, out) == (2, "") and err.count("\n") == 1
    assert "figures needs matplotlib: pip install 'contactqp[plot]'" in err
    assert (tmp_path / "out" / "stages.csv").is_file()  # what was computed is kept

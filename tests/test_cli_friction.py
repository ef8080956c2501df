"""``contactqp solve`` with friction and load histories, run as a user would.

Truths: the hand derivations written in the example files (examples/problems/block_on_floor.toml
and cyclic_block.toml), recomputed here from their physical inputs. The friction routes end at a
natural-map error of 1e-12 (the files' tol), so values are compared at 1e-9 relative (1e-9 of
the scale for values that are zero by hand).
"""

import csv
import itertools
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BLOCKS = "examples/problems/block_on_floor.toml"
CYCLIC = "examples/problems/cyclic_block.toml"

# block_on_floor.toml: springs kx = 1e6, ky = 1e8 N/m, weight 1000 N, floor 2 um below, mu 0.3,
# pushes 200 and 400 N.
KX, KY, WEIGHT, GAP, MU = 1e6, 1e8, 1000.0, 2e-6, 0.3
PUSH = np.array([200.0, 400.0])
# cyclic_block.toml: interference 10 um (N = 1000 N), amplitudes 200 and 500 N, factors
# 0 -> 1 -> -1 -> 1 in 4 steps per segment.
INTERFERENCE, AMPLITUDE, STEPS = 1e-5, np.array([200.0, 500.0]), 4


def run(*args):
    return subprocess.run(
        [sys.executable, "-m", "contactqp.cli", *args], capture_output=True, text=True, cwd=ROOT
    )


def assert_one_line_error(proc, code, *fragments):
    assert proc.returncode == code, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("contactqp: error:"), proc.stderr
    assert "Traceback" not in proc.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def read_rows(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def blocks_by_hand():
    """Normal force, friction force, u_x and dissipation per block of block_on_floor.toml."""
    normal = WEIGHT - KY * GAP
    limit = MU * normal
    u_x = np.maximum(PUSH - limit, 0.0) / KX
    return np.full(2, normal), -np.minimum(PUSH, limit), u_x, limit * u_x


def cyclic_by_hand():
    """Factors, u_x (K, 2) and dissipation (K,) of cyclic_block.toml (Masing's rule)."""
    turning = [0.0, 1.0, -1.0, 1.0]
    factors = np.concatenate(
        [[0.0]]
        + [a + (b - a) * np.arange(1, STEPS + 1) / STEPS for a, b in itertools.pairwise(turning)]
    )
    limit = MU * KY * INTERFERENCE
    force = factors[:, None] * AMPLITUDE
    segment = (np.maximum(np.arange(len(factors)) - 1, 0) // STEPS)[:, None]

    def virgin(f):
        return np.maximum(f - limit, 0.0) / KX

    top = virgin(AMPLITUDE)
    down = top - 2.0 * virgin((AMPLITUDE - force) / 2.0)
    up = -top + 2.0 * virgin((force + AMPLITUDE) / 2.0)
    x = np.where(segment == 0, virgin(force), np.where(segment % 2 == 1, down, up))
    slid = np.abs(np.diff(np.vstack([np.zeros((1, 2)), x]), axis=0))
    return factors, x, limit * slid.sum(axis=1), slid


def test_friction_json_and_files_match_the_hand_answer(tmp_path):
    proc = run("solve", BLOCKS, "--json", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    normal, friction, u_x, dissipation = blocks_by_hand()
    assert summary["success"] and summary["certificate"]["passed"]
    assert (summary["stick"], summary["slip"], summary["open"]) == (1, 1, 0)
    np.testing.assert_allclose(summary["dissipated"], dissipation.sum(), rtol=1e-9)

    rows = read_rows(tmp_path / "contacts.csv")
    assert [r["status"] for r in rows] == ["stick", "slip"]
    np.testing.assert_allclose([float(r["normal_force"]) for r in rows], normal, rtol=1e-9)
    np.testing.assert_allclose([float(r["tangential_force"]) for r in rows], friction, rtol=1e-9)
    np.testing.assert_allclose(
        [float(r["slip"]) for r in rows], u_x, rtol=1e-9, atol=1e-9 * u_x.max()
    )
    np.testing.assert_allclose(
        [float(r["dissipated"]) for r in rows],
        dissipation,
        rtol=1e-9,
        atol=1e-9 * dissipation.max(),
    )
    u = [float(r["u"]) for r in read_rows(tmp_path / "displacements.csv")]
    np.testing.assert_allclose(u, [u_x[0], -GAP, u_x[1], -GAP], rtol=1e-9, atol=1e-9 * GAP)


def test_friction_table_shows_forces_status_and_certificate():
    proc = run("solve", BLOCKS)
    assert proc.returncode == 0, proc.stderr
    normal, friction, u_x, dissipation = blocks_by_hand()
    lines = proc.stdout.splitlines()
    stick = next(line for line in lines if line.rstrip().endswith("stick"))
    slip = next(line for line in lines if line.rstrip().endswith("slip"))
    assert f"{normal[0]:.4g}" in stick and f"{friction[0]:.4g}" in stick
    assert f"{friction[1]:.4g}" in slip and f"{u_x[1]:.4g}" in slip
    text = " ".join(proc.stdout.split())
    assert f"dissipated {dissipation.sum():.6g} J" in text
    assert "(passed;" in text and "cone" in text and "natural_map" in text


def test_history_json_records_match_masing():
    proc = run("solve", CYCLIC, "--json")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert len(lines) == 1
    summary = json.loads(lines[0])
    factors, _, dissipated, slid = cyclic_by_hand()
    assert summary["success"] and summary["failed_steps"] == []
    assert summary["steps"] == len(factors) == len(summary["records"])
    records = summary["records"]
    np.testing.assert_allclose([r["factor"] for r in records], factors, atol=1e-15)
    slipping = (slid > 1e-12).sum(axis=1)
    assert [r["slip"] for r in records] == slipping.tolist()
    assert [r["stick"] for r in records] == (2 - slipping).tolist()
    np.testing.assert_allclose(
        [r["dissipated"] for r in records], dissipated, atol=1e-9 * dissipated.max()
    )
    np.testing.assert_allclose(summary["dissipated"], dissipated.sum(), rtol=1e-9)
    assert all(r["certificate"]["passed"] for r in records)


def test_history_files_and_table(tmp_path):
    proc = run("solve", CYCLIC, "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    factors, x, dissipated, _ = cyclic_by_hand()
    K = len(factors)
    rows = read_rows(tmp_path / "displacements.csv")
    u = np.array([float(r["u"]) for r in rows]).reshape(K, 4)
    np.testing.assert_allclose(u[:, 0::2], x, rtol=1e-9, atol=1e-9 * np.abs(x).max())
    np.testing.assert_allclose(u[:, 1::2], INTERFERENCE, rtol=1e-9)
    steps = read_rows(tmp_path / "steps.csv")
    np.testing.assert_allclose(
        [float(r["cumulative_dissipated"]) for r in steps],
        np.cumsum(dissipated),
        atol=1e-9 * dissipated.sum(),
    )
    assert all(r["success"] == "True" for r in steps)
    text = " ".join(proc.stdout.split())
    assert f"{K} steps" in text and f"total dissipated {dissipated.sum():.6g} J" in text
    assert "all steps passed" in text and "final state (step 12)" in text
    for name in ("displacements.csv", "contacts.csv", "steps.csv", "result.npz", "summary.json"):
        assert f"wrote {tmp_path / name}" in text


def test_failed_history_step_exits_1_and_names_the_step(tmp_path):
    # A certificate tolerance below rounding fails the steps' certificates: exit 1, one line
    # naming the first failed step (the one the JSON summary lists first).
    path = tmp_path / "cyclic.toml"
    path.write_text((ROOT / CYCLIC).read_text() + "\n[solver]\ncertificate_tol = 1e-30\n")
    proc = run("solve", str(path), "--json")
    summary = json.loads(proc.stdout)
    failed = summary["failed_steps"]
    assert failed and not summary["success"]
    factor = summary["records"][failed[0]]["factor"]
    line = assert_one_line_error(
        proc, 1, f"step {failed[0]} (factor {factor:g})", "certificate failed"
    )
    if len(failed) > 1:
        assert f"({len(failed) - 1} more steps failed)" in line
    proc = run("solve", str(path))  # the table marks it too
    assert proc.returncode == 1 and "FAILED" in proc.stdout


def test_failed_friction_solve_exits_1(tmp_path):
    path = tmp_path / "blocks.toml"
    path.write_text((ROOT / BLOCKS).read_text() + "\n[solver]\ncertificate_tol = 1e-30\n")
    assert_one_line_error(run("solve", str(path)), 1, "certificate failed")


def test_bad_friction_input_exits_2(tmp_path):
    text = (ROOT / BLOCKS).read_text()
    cases = {
        "mu.toml": (text.replace("\nmu = 0.3\n", "\nmu = -0.3\n"), "[friction].mu"),
        "facets.toml": (text.replace('solver = "coulomb"', "facets = 2"), "[friction].facets"),
        "key.toml": (text.replace("tol = 1e-12", "tols = 1e-12"), "did you mean 'tol'"),
        "loading.toml": (text + "\n[loading]\nfactors = [[1.0]]\n", "[loading].factors"),
        "solver.toml": (text + "\n[solver]\nname = 'qp'\n", "[solver].name"),
    }
    for name, (content, fragment) in cases.items():
        path = tmp_path / name
        path.write_text(content)
        assert_one_line_error(run("solve", str(path)), 2, fragment)

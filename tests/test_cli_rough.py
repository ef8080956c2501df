"""``contactqp rough``, run in-process as a user would: JSON per load, truths, bad input."""

from __future__ import annotations

import contextlib
import io
import json
import math
import warnings

import numpy as np
import pytest

import contactqp as cq
from contactqp.cli import main

E, NU = 210e9, 0.3
E_STAR = E / (1 - NU**2)
KEYS = {"pressure", "area_fraction", "mean_gap", "stiffness", "seconds", "iterations"}


def run(*args) -> tuple[int, str, str]:
    """``contactqp rough ARGS`` in-process: (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with (
        contextlib.redirect_stdout(out),
        contextlib.redirect_stderr(err),
        warnings.catch_warnings(),
    ):
        warnings.simplefilter("default")
        status = main(["rough", *(str(arg) for arg in args)])
    return status, out.getvalue(), err.getvalue()


def records(*args) -> list[dict]:
    status, out, err = run(*args, "--json")
    assert status == 0, err
    return [json.loads(line) for line in out.splitlines()]


def sinusoid(tmp_path, nx=128, ny=4, cell=1e-6, amplitude=1e-7):
    """A wavy surface ``amplitude cos(2 pi x / lambda)``, one wavelength per period, as .npy."""
    x = (np.arange(nx) + 0.5) * cell - nx * cell / 2
    path = tmp_path / "wavy.npy"
    np.save(path, np.tile(amplitude * np.cos(2 * np.pi * x / (nx * cell)), (ny, 1)))
    return path, math.pi * E_STAR * amplitude / (nx * cell)  # Westergaard's full contact


def test_json_is_one_object_per_load_with_area_growing_and_gap_closing():
    pressures = [2e8, 5e8, 1e9, 2e9]
    rows = records("--grid", 32, "--seed", 7, "--pressures", ",".join(map(str, pressures)))
    assert [set(row) for row in rows] == [KEYS | {"certificate"}] * 4
    assert [row["pressure"] for row in rows] == pressures
    assert all(row["certificate"] is True and row["iterations"] >= 1 for row in rows)
    area = [row["area_fraction"] for row in rows]
    gap = [row["mean_gap"] for row in rows]
    assert all(0 < a < b <= 1 for a, b in zip(area, area[1:], strict=False))
    assert all(a > b > 0 for a, b in zip(gap, gap[1:], strict=False))
    assert all(row["stiffness"] > 0 for row in rows)
    # the end loads' stiffness is the one-sided difference of the reported numbers
    assert rows[0]["stiffness"] == pytest.approx(
        -(pressures[1] - pressures[0]) / (gap[1] - gap[0]), rel=1e-12
    )


def test_the_same_seed_gives_the_same_answers():
    first = records("--grid", 16, "--seed", 3, "--pressures", "1e9")
    again = records("--grid", 16, "--seed", 3, "--pressures", "1e9")
    other = records("--grid", 16, "--seed", 4, "--pressures", "1e9")
    for row in (*first, *again, *other):
        row.pop("seconds")
    assert first == again and first != other
    assert first[0]["stiffness"] is None  # one load: no difference to take


def test_mu_zero_is_the_frictionless_contact():
    assert records("--grid", 8, "--pressures", "1e9", "--mu", 0)[0]["certificate"]


def test_mu_shears_each_load():
    plain = records("--grid", 32, "--pressures", "1e9,2e9")
    sheared = records("--grid", 32, "--pressures", "1e9,2e9", "--mu", 0.3, "--shear", 0.4)
    for a, b in zip(plain, sheared, strict=True):
        assert b["certificate"] and b["area_fraction"] == a["area_fraction"]
        assert 0 < b["stick_fraction"] < 1 and b["shift"] > 0 and b["tangential_stiffness"] > 0
        assert "stick_fraction" not in a
    assert sheared[1]["shift"] > sheared[0]["shift"]  # Q = 0.4 mu P grows with the load
    status, out, err = run("--grid", "32", "--pressures", "1e9", "--mu", "0.3")
    assert status == 0 and "stick fraction" in out and "Sheared by Q = 0.5 mu P" in out


def test_mu_writes_the_shear_and_the_status_to_the_grid(tmp_path):
    meshio = pytest.importorskip("meshio")
    mesh = tmp_path / "sheared.vtu"
    status, out, err = run("--grid", "32", "--pressures", "1e9", "--mu", "0.3", "--vtu", mesh)
    assert status == 0, err
    data = meshio.read(mesh).point_data
    shear, codes = data["shear_0"], data["status_0"]
    # the tractions along x add up to Q = 0.5 mu P (mean pressure 1e9 Pa over the period)
    assert np.mean(shear) == pytest.approx(0.5 * 0.3 * 1e9, rel=1e-10)
    labels = {int(cq.ContactStatus.OPEN), int(cq.ContactStatus.STICK), int(cq.ContactStatus.SLIP)}
    assert set(np.unique(codes).astype(int)) == labels
    assert np.all(shear[codes == int(cq.ContactStatus.OPEN)] == 0.0)


def test_a_wavy_surface_follows_westergaard_up_to_full_contact(tmp_path):
    nx = 128
    path, full = sinusoid(tmp_path, nx=nx)
    ratios = [0.05, 0.2, 0.5, 0.8, 0.95, 1.05]
    rows = records(
        "--surface", path, "--cell", 1e-6, "--young", E, "--poisson", NU,
        "--pressures", ",".join(str(r * full) for r in ratios),
    )  # fmt: skip
    for ratio, row in zip(ratios, rows, strict=True):
        assert row["certificate"]
        # Westergaard (Johnson, Contact Mechanics, 13.2): p / p* = sin^2(pi a / lambda), the
        # contact band 2a wide; counted in cells, the band is off by at most one cell per row
        theory = 2 / math.pi * math.asin(math.sqrt(min(ratio, 1.0)))
        assert abs(row["area_fraction"] - theory) <= 1 / nx + 1e-12, ratio
    assert rows[-1]["area_fraction"] == 1.0 and rows[-1]["stiffness"] is None
    assert all(row["stiffness"] > 0 for row in rows[:-1])
    assert abs(rows[-1]["mean_gap"]) < 1e-9 * 1e-7  # full contact: no gap left


def test_the_small_load_area_follows_the_linear_law_between_persson_and_bgt():
    # a resolved surface: 8 cells per shortest wavelength (Prodanov, Dapp and Muser, Tribol.
    # Lett. 53 (2014) 433: the area converges as the cell shrinks), 4 roll-off wavelengths per
    # period for many asperities (below area fractions of ~1 % a few Hertzian spots are left
    # and the area grows as p^(2/3), not linearly)
    slope, relative = 0.1, [0.005, 0.01, 0.02]
    rows = records(
        "--grid", 128, "--hurst", 0.8, "--rms-slope", slope, "--rolloff", 4, "--cutoff", 16,
        "--young", E, "--poisson", NU,
        "--pressures", ",".join(str(r * E_STAR * slope) for r in relative),
    )  # fmt: skip
    for r, row in zip(relative, rows, strict=True):
        kappa = row["area_fraction"] / r
        # Persson's sqrt(8/pi) = 1.60 and Bush-Gibson-Thomas's sqrt(2 pi) = 2.51 bracket the
        # exact solutions (kappa near 2, Hyun et al. 2004); counting whole cells in contact
        # overestimates the area of small contact spots, by up to 25 % at these resolutions
        assert math.sqrt(8 / math.pi) <= kappa <= 1.25 * math.sqrt(2 * math.pi), (r, kappa)


def test_the_ascii_grid_and_the_figures(tmp_path):
    meshio = pytest.importorskip("meshio")
    path, full = sinusoid(tmp_path, nx=32, ny=2)
    heights = np.load(path) * 1e9  # nm
    grid = tmp_path / "wavy.asc"
    rows = "\n".join(" ".join(repr(float(v)) for v in row) for row in heights)
    grid.write_text(f"ncols 32\nnrows 2\ncellsize 1 um\nunit nm\n{rows}\n")
    figure, mesh = tmp_path / "area.png", tmp_path / "wavy.vtu"
    pressures = [0.3 * full, 0.6 * full]
    status, out, err = run(
        "--surface", grid, "--pressures", ",".join(map(str, pressures)),
        "--plot", figure, "--vtu", mesh,
    )  # fmt: skip
    assert status == 0, err
    assert "figure written" in out and figure.stat().st_size > 10_000
    written = meshio.read(mesh)
    assert len(written.points) == 64 and written.cells[0].data.shape == (31, 4)
    np.testing.assert_allclose(written.point_data["height"], heights.ravel() * 1e-9, rtol=1e-15)
    for k, pressure in enumerate(pressures):  # the cells' pressures carry the mean pressure
        assert np.mean(written.point_data[f"pressure_{k}"]) == pytest.approx(pressure, rel=1e-8)
        assert np.all(written.point_data[f"gap_{k}"] > -1e-12)


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (("--grid", "8", "--shear", "0.5"), "--shear shears a frictional contact"),
        (("--grid", "8", "--mu", "0.3", "--shear", "1.5"), "--shear must be Q / (mu P)"),
        (("--mu", "-1"), "--mu must be a friction coefficient >= 0"),
        (("--surface", "FLAT", "--cell", "1e-6"), "the surface is flat"),
        (("--surface", "SURFACE", "--grid", "32"), "--grid shape a generated surface"),
        (("--surface", "missing.npy", "--cell", "1e-6"), "missing.npy: file not found"),
        (("--surface", "SURFACE"), "holds no cell size"),
        (("--surface", "SURFACE", "--cell", "1e-6", "--plot", "SURFACE"), "would overwrite"),
        (("--grid", "8", "--plot", "a.png", "--vtu", "a.png"), "name the same file"),
        (("--grid", "8", "--pressures", "2e9,1e9"), "pressures must increase"),
        (("--grid", "8", "--pressures", "-1e9"), "pressures must be positive"),
        (("--grid", "8", "--pressures", "x"), "comma-separated numbers"),
        (("--grid", "8", "--hurst", "1.5"), "--hurst"),
        (("--grid", "8", "--cutoff", "5"), "Nyquist"),
        (("--grid", "8", "--pressures", "1e9", "--plot", "OUT/area.xyz"), "area.xyz"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, needle):
    path, _ = sinusoid(tmp_path, nx=8, ny=8)
    flat = tmp_path / "flat.npy"
    np.save(flat, np.zeros((8, 8)))
    names = {"SURFACE": str(path), "FLAT": str(flat), "a.png": str(tmp_path / "a.png")}
    args = [names.get(a, a.replace("OUT", str(tmp_path))) for a in args]
    before = path.read_bytes()
    status, out, err = run(*args)
    lines = err.strip().splitlines()
    assert status == 2 and len(lines) == 1 and lines[0].startswith("contactqp: error:"), err
    assert needle in lines[0] and "Traceback" not in err
    assert path.read_bytes() == before  # the input is never written

"""Riveting: the plate model against Navier's series, one fastener against the direct solve,
fastening sequences, the two routes, outputs and bad input."""

from __future__ import annotations

import numpy as np
import pytest

import contactqp as cq
from contactqp.applications.assembly import Part
from contactqp.applications.riveting import Assembly, plate_flexibility, plot_status, result_mesh
from contactqp.core.status import ContactStatus
from contactqp.errors import InvalidInputError
from contactqp.io.export import write_vtu

ALL_EDGES = ("left", "right", "bottom", "top")


def navier(points, plate: Part, terms: int = 200) -> np.ndarray:
    """Deflection at ``points`` under unit forces at ``points``, simply supported rectangle.

    Navier's double sine series (Timoshenko & Woinowsky-Krieger, Theory of plates and shells,
    sec. 29): ``w = 4 P / (pi^4 D a b) sum sin sin sin sin / ((m/a)^2 + (n/b)^2)^2``.
    """
    a, b = plate.length, plate.width
    k = np.arange(1, terms + 1)
    sx = np.sin(np.pi * np.outer(points[:, 0], k) / a)  # (p, m)
    sy = np.sin(np.pi * np.outer(points[:, 1], k) / b)  # (p, n)
    weight = 1.0 / ((k[:, None] / a) ** 2 + (k[None, :] / b) ** 2) ** 2
    series = np.einsum("im,in,mn,jm,jn->ij", sx, sy, weight, sx, sy)
    return 4.0 / (np.pi**4 * plate.rigidity * a * b) * series


def test_plate_flexibility_converges_to_navier_at_second_order():
    # 7 x 3 interior points, 25 mm apart, of a plate simply supported on its four edges; the
    # Morley element converges as h^2 (a halving of h divides the error by about 4)
    plate = Part()
    xs, ys = np.meshgrid(np.arange(1, 8) * 0.025, np.arange(1, 4) * 0.025)
    points = np.column_stack([xs.ravel(), ys.ravel()])
    exact = navier(points, plate)
    errors = [
        np.max(np.abs(plate_flexibility(plate, points, (8 * r, 4 * r), ALL_EDGES) - exact))
        / np.max(exact)
        for r in (4, 8)
    ]
    assert errors[1] < 0.02
    assert errors[0] / errors[1] > 3.0


@pytest.fixture(scope="module")
def small():
    """11 x 7 pairs, plates of different thickness, fasteners in a row."""
    assembly = Assembly(
        lower=Part(thickness=0.002),
        upper=Part(thickness=0.0016),
        grid=(11, 7),
        fasteners=((1, 3), (5, 3), (9, 3)),
        refine=2,
    )
    return assembly.build()


def test_default_assembly_layout():
    assembly = Assembly()
    nx, ny = assembly.grid
    assert 450 <= nx * ny <= 550
    cells = assembly.fastener_cells()
    assert len(cells) >= 4 and all(j == ny // 2 for _, j in cells)


def test_one_fastener_closing_a_uniform_gap_matches_the_direct_solve(small):
    # One fastener pulling the plates shut over a uniform gap g: if only its pair closes, its
    # tension is g / W_ff and the gaps become g (1 - W_if / W_ff), W = R_lower + R_upper
    # computed here from the two plates directly.
    k, f, g = small.n_pairs, 5, 3e-4  # mid-span on a free edge: no other pair deflects more
    held = small.assembly.supports
    cells = (2 * 12, 2 * 6)  # refine 2 over 12 x 6 intervals (left/right held, y edges free)
    W = sum(
        plate_flexibility(p, small.points, cells, held)
        for p in (small.assembly.lower, small.assembly.upper)
    )
    assert np.all(np.delete(W[:, f], f) < W[f, f])  # the premise: no other pair closes
    fastened = cq.FastenedProblem(small.problem(np.full(k, g)), [f])
    for method in ("lawson-hanson", "nnls", "active-set"):
        state = cq.solve(fastened, method)
        assert state.success
        np.testing.assert_allclose(state.fastener_forces, [g / W[f, f]], rtol=1e-9)
        np.testing.assert_allclose(
            state.gaps, g * (1 - W[:, f] / W[f, f]), rtol=1e-9, atol=1e-12 * g
        )
        assert np.all(state.forces == 0) and state.closure < 1e-12 * g
        assert np.bincount(state.contact_status, minlength=5).tolist() == [k - 1, 0, 0, 0, 1]


@pytest.fixture(scope="module")
def rough_gaps(small):
    rng = np.random.default_rng(7)
    return 2e-4 + 1e-4 * rng.standard_normal(small.n_pairs)


def test_sequence_order_changes_the_path_not_the_end_without_friction(small, rough_gaps):
    forward = small.fasten(rough_gaps)
    backward = small.fasten(rough_gaps, order=[2, 1, 0], method="active-set")
    assert forward.success and backward.success and len(forward.steps) == 3
    assert not np.allclose(forward.steps[0].gaps, backward.steps[0].gaps)
    np.testing.assert_allclose(forward.final.gaps, backward.final.gaps, rtol=1e-7, atol=1e-12)
    np.testing.assert_array_equal(backward.final.fasteners, small.fasteners[::-1])
    np.testing.assert_allclose(
        forward.final.fastener_forces, backward.final.fastener_forces[::-1], rtol=1e-7, atol=1e-9
    )
    final = forward.final
    assert final.closure < 1e-12
    assert np.all(final.contact_status[small.fasteners] == ContactStatus.FASTENED)


def test_three_routes_agree_on_a_rough_gap_field(small, rough_gaps):
    fastened = cq.FastenedProblem(small.problem(rough_gaps), small.fasteners)
    reference = cq.solve(fastened, "nnls")  # scipy's NNLS on the factor: independent
    assert reference.success
    assert np.count_nonzero(reference.contact_status == ContactStatus.CLOSED) > 0
    warm = reference.multipliers * (1 + 0.3 * np.cos(np.arange(small.n_pairs)))  # a nearby start
    for method, start in [
        ("lawson-hanson", None),
        ("lawson-hanson", warm),
        ("active-set", None),
        ("active-set", warm),
    ]:
        state = cq.solve(fastened, method, r0=start)
        assert state.success, (method, state.message)
        np.testing.assert_allclose(
            state.multipliers,
            reference.multipliers,
            rtol=1e-6,
            atol=1e-8 * np.max(np.abs(reference.multipliers)),
        )
        np.testing.assert_array_equal(state.contact_status, reference.contact_status)


def test_outputs_vtu_and_figure(small, rough_gaps, tmp_path):
    import meshio

    final = small.fasten(rough_gaps).final
    path = write_vtu(tmp_path / "r.vtu", *result_mesh(small, final, rough_gaps))
    mesh = meshio.read(path)
    k = small.n_pairs
    assert mesh.points.shape == (2 * k, 3)
    np.testing.assert_allclose(mesh.point_data["gap"][:k], final.gaps)
    np.testing.assert_allclose(mesh.point_data["displacement"][:, 2], final.displacements)
    np.testing.assert_array_equal(mesh.point_data["status"][k:], final.contact_status)
    assert mesh.cells[0].data.shape == (2 * 10 * 6, 4)
    png = plot_status(small, final, rough_gaps, tmp_path / "s.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"fasteners": ((11, 3),)}, "outside"),
        ({"fasteners": ((1, 3), (1, 3))}, "share"),
        ({"supports": ("left", "middle")}, "supports"),
        ({"upper": Part(length=0.3)}, "same length"),
    ],
)
def test_bad_assemblies(kwargs, match):
    with pytest.raises(InvalidInputError, match=match):
        Assembly(**{"grid": (11, 7), "refine": 1, **kwargs}).build()


def test_bad_fastening(small, rough_gaps):
    with pytest.raises(InvalidInputError, match="permutation"):
        small.fasten(rough_gaps, order=[0, 0, 1])
    with pytest.raises(
        InvalidInputError,
        match="unknown method 'simplex' for fastened problems; "
        "choose one of lawson-hanson \\(default\\)",
    ):
        cq.solve(cq.FastenedProblem(small.problem(rough_gaps), [3]), "simplex")
    with pytest.raises(InvalidInputError, match="gaps"):
        small.problem(rough_gaps[:-1])


def test_an_overlap_deeper_than_a_plate_is_refused(small, rough_gaps):
    # plates of 2 and 1.6 mm: 1.5 mm of interference is a (severe) press fit, 1.7 mm is absurd
    assert small.thickness == 0.0016
    assert small.fasten(np.full(small.n_pairs, -1.5e-3)).success
    with pytest.raises(
        InvalidInputError,
        match=r"^gaps: an overlap of 1\.7 mm is deeper than "
        r"the 1\.6 mm plates",
    ):
        small.fasten(np.where(np.arange(small.n_pairs) == 3, -1.7e-3, rough_gaps))
    with pytest.raises(InvalidInputError, match="gaps contains NaN"):
        small.fasten(np.full(small.n_pairs, np.nan))


@pytest.mark.parametrize(
    "args, code, message",
    [
        (
            ["--mean-gap", "-1"],
            2,
            (
                "contactqp: error: --mean-gap: an overlap of 1000 mm is deeper "
                "than the 2 mm plates (a negative gap is interference)\n"
            ),
        ),
        (
            ["--mean-gap", "-1e-3", "--amplitude", "0"],
            0,
            (
                "contactqp: warning: --mean-gap -0.001 m is negative: the plates overlap by 1 mm "
                "at rest (interference)\n"
            ),
        ),
        (
            ["--mean-gap", "5e-3", "--amplitude", "0"],
            0,
            (
                "contactqp: warning: nominal gap 5 mm exceeds the 2 mm plate thickness: far beyond "
                "small deflections, where the linear plate model holds\n"
            ),
        ),
    ],
)
def test_cli_absurd_gaps_are_refused_and_unusual_ones_warned(tmp_path, capsys, args, code, message):
    from contactqp.cli import main

    out = tmp_path / "study"
    assert main(["riveting", "--samples", "1", "--out", str(out), "--json", *args]) == code
    assert capsys.readouterr().err == message
    assert out.exists() == (code == 0)  # refused before anything is written


def test_cli_json_resume_and_outputs(tmp_path, capsys):
    import json

    from contactqp.cli import main

    out = tmp_path / "study"
    assert main(["riveting", "--samples", "12", "--seed", "4", "--out", str(out), "--json"]) == 0
    first = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert {k: first[k] for k in ("samples", "computed", "reused", "failed")} == {
        "samples": 12,
        "computed": 12,
        "reused": 0,
        "failed": 0,
    }
    assert len(first["residual_gap_mean"]) == 525 and min(first["residual_gap_mean"]) > -1e-15
    assert (
        main(
            [
                "riveting",
                "--samples",
                "16",
                "--seed",
                "4",
                "--out",
                str(out),
                "--json",
                "--workers",
                "2",
            ]
        )
        == 0
    )
    second = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert (second["computed"], second["reused"]) == (4, 12)
    for name in (
        "nominal.vtu",
        "nominal_contacts.csv",
        "nominal_sequence.csv",
        "samples.h5",
        "statistics.csv",
    ):
        assert (out / name).stat().st_size > 0
    table = np.genfromtxt(out / "statistics.csv", delimiter=",", names=True)
    np.testing.assert_allclose(table["mean_gap"], second["residual_gap_mean"], rtol=1e-12)
    sequence = np.genfromtxt(out / "nominal_sequence.csv", delimiter=",", names=True)
    assert len(sequence) == len(Assembly().fastener_cells()) and np.all(sequence["tension"] >= 0)
    # fewer samples than the store holds: the statistics are those of the samples asked for
    assert main(["riveting", "--samples", "12", "--seed", "4", "--out", str(out), "--json"]) == 0
    third = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert (third["samples"], third["computed"], third["reused"]) == (12, 0, 12)
    np.testing.assert_allclose(
        third["residual_gap_mean"], first["residual_gap_mean"], rtol=1e-12, atol=1e-18
    )
    # another seed in the same directory is another study: refused, exit 2, and the nominal
    # files of the study there are left as they were
    nominal = {name: (out / name).read_bytes() for name in ("nominal.vtu", "nominal_contacts.csv")}
    assert main(["riveting", "--samples", "16", "--seed", "5", "--out", str(out)]) == 2
    assert "another study" in capsys.readouterr().err
    assert main(["riveting", "--samples", "16", "--mean-gap", "3e-4", "--out", str(out)]) == 2
    assert "another study" in capsys.readouterr().err
    assert nominal == {name: (out / name).read_bytes() for name in nominal}


def test_cli_bad_scheduler_is_one_line_exit_2(tmp_path, capsys):
    from contactqp.cli import main

    args = ["riveting", "--samples", "2", "--out", str(tmp_path), "--scheduler", "no-port"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Dask scheduler" in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []  # refused before a store or nominal file is written


def test_cli_bad_gap_file(tmp_path, capsys):
    from contactqp.cli import main

    np.save(tmp_path / "g.npy", np.zeros((3, 10)))
    assert main(["riveting", "--gaps", str(tmp_path / "g.npy"), "--out", str(tmp_path)]) == 2
    assert "525 columns" in capsys.readouterr().err


def test_cli_corrupt_gap_file_is_one_line_exit_2(tmp_path, capsys):
    from contactqp.cli import main

    np.savez_compressed(tmp_path / "g.npz", gaps=np.full((3, 525), 2e-4))
    whole = (tmp_path / "g.npz").read_bytes()
    (tmp_path / "cut.npz").write_bytes(whole[: len(whole) // 2])
    out = tmp_path / "study"
    assert main(["riveting", "--gaps", str(tmp_path / "cut.npz"), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cut.npz: not a readable .npy / .npz file" in err
    assert not out.exists()


def test_cli_every_sample_failing_exits_1(tmp_path, capsys, monkeypatch):
    from contactqp.applications.riveting import FasteningCase
    from contactqp.cli import main

    solve_sample = FasteningCase.solve_sample

    def failing(self, gaps, warm):
        record, warm = solve_sample(self, gaps, warm)
        return {**record, "success": False}, warm

    monkeypatch.setattr(FasteningCase, "solve_sample", failing)
    assert main(["riveting", "--samples", "2", "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "all 2 samples failed" in err
    assert not (tmp_path / "statistics.csv").exists()


def test_cli_gap_file_runs_every_row_by_default(tmp_path, capsys):
    import json

    from contactqp.cli import main

    gaps = 2e-4 + 5e-5 * np.cos(np.arange(3 * 525)).reshape(3, 525)
    np.save(tmp_path / "g.npy", gaps)
    out = tmp_path / "study"
    assert main(["riveting", "--gaps", str(tmp_path / "g.npy"), "--out", str(out), "--json"]) == 0
    record = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert (record["samples"], record["computed"]) == (3, 3)
    nominal = np.genfromtxt(out / "nominal_contacts.csv", delimiter=",", names=True)
    np.testing.assert_allclose(nominal["initial_gap"], gaps.mean(axis=0), rtol=1e-15)


def test_csv_export_round_trips_and_refuses_ragged_columns(tmp_path):
    from contactqp.io.export import write_csv

    values = np.array([1 / 3, -2.5e-19, 7e8])
    path = write_csv(tmp_path / "t.csv", {"a": values, "b": ["x", "y", "z"]})
    table = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding=None)
    np.testing.assert_array_equal(table["a"], values)  # full precision
    assert table["b"].tolist() == ["x", "y", "z"]
    with pytest.raises(InvalidInputError, match="one length"):
        write_csv(tmp_path / "u.csv", {"a": [1.0, 2.0], "b": [1.0]})

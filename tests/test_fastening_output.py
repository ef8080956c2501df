"""Files, figures and summaries of a fastening sequence and of its variation study, read back.

Stages are built here as small stand-ins with the attributes of an AssemblyStage, so that the
writers are checked on known arrays: CSV and VTU read back (csv, numpy, meshio), figures
inspected through their matplotlib objects, the shim probability against a direct count.
"""

from __future__ import annotations

import csv
import json
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass

import matplotlib
import meshio
import numpy as np
import pytest

from contactqp.applications.fastening.output import (
    FASTENER_HEADER,
    STAGE_HEADER,
    fastener_force_history,
    fastener_forces_figure,
    gap_map_figure,
    map_plane,
    plot_statistics_maps,
    sequence_summary,
    sequence_table,
    stage_mesh,
    statistics_map_figure,
    status_map_figure,
    write_sequence,
    write_statistics,
)
from contactqp.core.contact import tangent_basis
from contactqp.core.status import STATUS_LABELS, ContactStatus, status_labels
from contactqp.errors import InvalidInputError
from contactqp.io.plot import STATUS_COLOURS
from contactqp.studies.statistics import gap_statistics

NX, NY = 5, 4
K = NX * NY


@dataclass
class Stage:
    """What the writers read of an AssemblyStage."""

    label: str
    gaps: np.ndarray
    normal_forces: np.ndarray
    tangential_forces: np.ndarray
    status: np.ndarray
    slip: np.ndarray
    fasteners: np.ndarray
    fastener_forces: np.ndarray
    ok: bool = True

    @property
    def success(self) -> bool:
        return self.ok


@dataclass
class Sequence:
    stages: list


@pytest.fixture
def geometry():
    """A 5 x 4 grid of pairs, 10 mm apart, on z = 1 mm, normals along +z."""
    x, y = np.meshgrid(np.arange(NX) * 0.01, np.arange(NY) * 0.01)
    points = np.column_stack([x.ravel(), y.ravel(), np.full(K, 1e-3)])
    normals = np.tile([0.0, 0.0, 1.0], (K, 1))
    return points, normals


def _stage(rng, label, fasteners, forces, *, friction=True, ok=True):
    """A stage whose arrays look like a solve's: open pairs carry no force and have a gap,
    closed ones a zero gap and a force; fastened pairs are closed with a fastener force."""
    status = rng.choice(
        [ContactStatus.OPEN, ContactStatus.STICK, ContactStatus.SLIP]
        if friction
        else [ContactStatus.OPEN, ContactStatus.CLOSED],
        size=K,
    )
    status[fasteners] = ContactStatus.FASTENED
    open_ = status == ContactStatus.OPEN
    gaps = np.where(open_, rng.uniform(1e-6, 3e-4, K), 0.0)
    normal = np.where(open_ | (status == ContactStatus.FASTENED), 0.0, rng.uniform(1, 50, K))
    tangential = rng.uniform(-0.3, 0.3, (K, 2)) * normal[:, None] if friction else np.zeros((K, 2))
    slip = np.where((status == ContactStatus.SLIP)[:, None], rng.normal(0, 1e-6, (K, 2)), 0.0)
    return Stage(
        label,
        gaps,
        normal,
        tangential,
        status.astype(int),
        slip,
        np.asarray(fasteners, dtype=int),
        np.asarray(forces, dtype=float),
        ok,
    )


@pytest.fixture
def stages():
    rng = np.random.default_rng(13)
    return [
        _stage(rng, "fastener 1 (pair 0)", [0], [120.0]),
        _stage(rng, "fastener 2 (pair 19)", [0, 19], [95.5, 210.25]),
        _stage(rng, "shear 50 N", [0, 19], [101.0, 180.0]),
    ]


def _read_csv(path):
    with path.open(newline="", encoding="utf-8") as handle:
        reader = csv.reader(handle)
        header = next(reader)
        return header, list(reader)


def test_stage_table_reads_back_with_units_and_every_value(stages, geometry, tmp_path):
    points, normals = geometry
    files = write_sequence(tmp_path, Sequence(stages), points, normals)
    header, rows = _read_csv(files["stages.csv"])
    assert tuple(header) == STAGE_HEADER
    for unit in ("gap (m)", "normal_force (N)", "tangential_force_t1 (N)", "slip_t2 (m)"):
        assert unit in header
    assert len(rows) == len(stages) * K
    column = {name: j for j, name in enumerate(header)}
    for number, stage in enumerate(stages, 1):
        mine = [row for row in rows if row[column["stage"]] == str(number)]
        assert [int(row[column["pair"]]) for row in mine] == list(range(K))
        assert {row[column["label"]] for row in mine} == {stage.label}

        def values(name, mine=mine):
            return np.array([float(row[column[name]]) for row in mine])

        np.testing.assert_array_equal(values("gap (m)"), stage.gaps)
        np.testing.assert_array_equal(values("normal_force (N)"), stage.normal_forces)
        np.testing.assert_array_equal(
            np.column_stack([values("tangential_force_t1 (N)"), values("tangential_force_t2 (N)")]),
            stage.tangential_forces,
        )
        np.testing.assert_array_equal(
            np.column_stack([values("slip_t1 (m)"), values("slip_t2 (m)")]), stage.slip
        )
        for axis, name in enumerate(("x (m)", "y (m)", "z (m)")):
            np.testing.assert_array_equal(values(name), points[:, axis])
        assert [row[column["status"]] for row in mine] == status_labels(stage.status)
        tension = np.zeros(K)
        tension[stage.fasteners] = stage.fastener_forces
        np.testing.assert_array_equal(values("fastener_force (N)"), tension)
    # numpy reads the numeric columns by their headers too
    table = np.genfromtxt(files["stages.csv"], delimiter=",", names=True, dtype=None)
    np.testing.assert_array_equal(table["gap_m"][-K:], stages[-1].gaps)


def test_fastener_table_lists_every_installed_fastener_at_every_stage(stages, geometry, tmp_path):
    points, normals = geometry
    files = write_sequence(tmp_path, stages, points, normals)
    header, rows = _read_csv(files["fasteners.csv"])
    assert tuple(header) == FASTENER_HEADER
    assert "force (N)" in header
    expected = [
        (n, stage.label, rank + 1, pair, *points[pair], force)
        for n, stage in enumerate(stages, 1)
        for rank, (pair, force) in enumerate(
            zip(stage.fasteners, stage.fastener_forces, strict=True)
        )
    ]
    got = [(int(r[0]), r[1], int(r[2]), int(r[3]), *map(float, r[4:7]), float(r[7])) for r in rows]
    assert got == expected
    assert len(rows) == 1 + 2 + 2


def test_vtu_per_stage_reads_back_with_meshio_every_field_its_shape(stages, geometry, tmp_path):
    points, normals = geometry
    files = write_sequence(tmp_path, stages, points, normals)
    collection = ElementTree.parse(files["stages.pvd"]).getroot()
    listed = [d.attrib["file"] for d in collection.iter("DataSet")]
    assert listed == ["stage_001.vtu", "stage_002.vtu", "stage_003.vtu"]
    assert [d.attrib["timestep"] for d in collection.iter("DataSet")] == ["1", "2", "3"]
    shapes = {
        "gap": (K,),
        "normal_force": (K,),
        "tangential_force": (K, 2),
        "contact_force": (K, 3),
        "slip": (K, 2),
        "status": (K,),
        "fastener_force": (K,),
        "normal": (K, 3),
    }
    tangents = tangent_basis(normals)
    for name, stage in zip(listed, stages, strict=True):
        mesh = meshio.read(tmp_path / name)
        np.testing.assert_allclose(mesh.points, points)
        assert mesh.cells[0].type == "vertex" and len(mesh.cells[0].data) == K
        assert {f: mesh.point_data[f].shape for f in mesh.point_data} == shapes
        data = mesh.point_data
        np.testing.assert_array_equal(data["gap"], stage.gaps)
        np.testing.assert_array_equal(data["status"], stage.status)
        np.testing.assert_array_equal(data["tangential_force"], stage.tangential_forces)
        np.testing.assert_array_equal(data["slip"], stage.slip)
        np.testing.assert_array_equal(
            data["fastener_force"][stage.fasteners], stage.fastener_forces
        )
        # the vector force on the first part: -N along the normal, T along the tangents
        force = data["contact_force"]
        np.testing.assert_allclose(np.sum(force * normals, axis=1), -stage.normal_forces)
        np.testing.assert_allclose(
            np.einsum("kd,kjd->kj", force, tangents), stage.tangential_forces, atol=1e-12
        )


def test_bad_stage_arrays_are_refused_by_name(stages, geometry, tmp_path):
    points, normals = geometry
    stages[1].tangential_forces = np.zeros((K, 3))
    with pytest.raises(InvalidInputError, match=r"stage 2 .*tangential_forces"):
        write_sequence(tmp_path, stages, points, normals)
    with pytest.raises(InvalidInputError, match="points"):
        stage_mesh(stages[0], points[:, :2], normals)
    stages[1].tangential_forces = np.zeros((K, 2))
    stages[0].status[3] = 7
    with pytest.raises(InvalidInputError, match="status codes"):
        write_sequence(tmp_path, stages, points, normals)
    with pytest.raises(InvalidInputError, match="at least one stage"):
        write_sequence(tmp_path, [], points, normals)


def _legend_labels(figure):
    return [text.get_text() for text in figure.axes[0].get_legend().get_texts()]


def test_plots_are_written_without_touching_the_backend(stages, geometry, tmp_path):
    import sys

    points, normals = geometry
    backend = matplotlib.get_backend()
    figures_before = (
        sys.modules["matplotlib.pyplot"].get_fignums() if "matplotlib.pyplot" in sys.modules else []
    )
    files = write_sequence(tmp_path, stages, points, normals, plot=True)
    for name in ("gap.png", "status.png", "fastener_forces.png"):
        assert files[name].stat().st_size > 1000
        assert files[name].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert matplotlib.get_backend() == backend
    if "matplotlib.pyplot" in sys.modules:
        assert sys.modules["matplotlib.pyplot"].get_fignums() == figures_before


def test_status_map_is_categorical_with_exactly_the_statuses_present(stages, geometry):
    points, normals = geometry
    stage = stages[-1]
    present = [label for label in STATUS_LABELS if label in status_labels(stage.status)]
    assert present == ["open", "stick", "slip", "fastened"]
    figure = status_map_figure(stage, points, normals)
    assert _legend_labels(figure) == present
    handles = figure.axes[0].get_legend().legend_handles
    colours = [matplotlib.colors.to_hex(h.get_facecolor()[0]) for h in handles]
    assert colours == [STATUS_COLOURS[label] for label in present]
    assert len(figure.axes) == 1  # no colour bar: categories, not a colour scale
    # frictionless: only open, closed and fastened, whatever the other stages hold
    plain = _stage(np.random.default_rng(1), "fastener 1", [4], [10.0], friction=False)
    assert _legend_labels(status_map_figure(plain, points, normals)) == [
        "open",
        "closed",
        "fastened",
    ]
    assert set(STATUS_COLOURS) == set(STATUS_LABELS)


def test_gap_map_marks_the_fasteners_and_fastener_plot_has_a_line_each(stages, geometry):
    points, normals = geometry
    figure = gap_map_figure(stages[1], points, normals)
    crosses = [line for line in figure.axes[0].get_lines() if line.get_marker() == "+"]
    assert len(crosses) == 1
    np.testing.assert_allclose(crosses[0].get_xydata(), points[[0, 19], :2] * 1e3)
    assert _legend_labels(figure) == ["fasteners"]
    assert len(figure.axes) == 2  # the map and its colour bar

    pairs, forces = fastener_force_history(stages)
    np.testing.assert_array_equal(pairs, [0, 19])
    np.testing.assert_array_equal(forces, [[120.0, np.nan], [95.5, 210.25], [101.0, 180.0]])
    figure = fastener_forces_figure(stages)
    assert _legend_labels(figure) == ["pair 0", "pair 19"]
    lines = {line.get_label(): line for line in figure.axes[0].get_lines()}
    np.testing.assert_array_equal(lines["pair 19"].get_xdata(), [1, 2, 3])
    np.testing.assert_array_equal(lines["pair 19"].get_ydata(), forces[:, 1])
    assert [t.get_text() for t in figure.axes[0].get_xticklabels()] == [s.label for s in stages]


def test_map_plane_drops_the_axis_along_the_normal(geometry):
    points, _ = geometry
    along_x = np.tile([-1.0, 0.0, 0.0], (K, 1))
    xy, axes = map_plane(points, along_x)
    np.testing.assert_array_equal(xy, points[:, [1, 2]])
    assert axes == ("y (mm)", "z (mm)")
    xy, axes = map_plane(points, np.tile([0.0, 0.0, 1.0], (K, 1)))
    assert axes == ("x (mm)", "y (mm)")


@pytest.fixture
def samples():
    """Five samples of four pairs, the third failed; gaps on both sides of 1e-4 m, one exactly
    at it (not above)."""
    gaps = np.array(
        [
            [0.0, 2e-4, 1e-4, 5e-5],
            [0.0, 0.0, 3e-4, 1.5e-4],
            [9e-4, 9e-4, 9e-4, 9e-4],
            [1e-5, 2e-4, 0.0, 1e-4],
            [0.0, 1.1e-4, 2e-4, 0.0],
        ]
    )
    return {"gap": gaps, "closed": gaps == 0.0, "success": np.array([1, 1, 0, 1, 1], bool)}


def test_shim_probability_is_the_fraction_of_successful_samples_above_the_tolerance(samples):
    tolerance = 1e-4
    stats = gap_statistics(samples, shim_tolerance=tolerance)
    counted = []
    for pair in range(4):
        above = used = 0
        for row in range(5):
            if samples["success"][row]:
                used += 1
                above += samples["gap"][row, pair] > tolerance
        counted.append(above / used)
    np.testing.assert_array_equal(stats.shim_probability, counted)
    np.testing.assert_array_equal(stats.shim_probability, [0.0, 0.75, 0.5, 0.25])
    assert stats.shim_tolerance == tolerance and stats.samples == 4
    np.testing.assert_array_equal(stats.contact_probability, [0.75, 0.25, 0.25, 0.25])
    assert gap_statistics(samples).shim_probability is None
    with pytest.raises(InvalidInputError, match="shim_tolerance"):
        gap_statistics(samples, shim_tolerance=-1e-4)
    with pytest.raises(InvalidInputError, match="shim_tolerance"):
        gap_statistics(samples, shim_tolerance=float("nan"))


def test_statistics_table_and_maps(samples, tmp_path):
    points = np.column_stack([np.arange(4) * 0.01, np.zeros(4), np.zeros(4)])
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    stats = gap_statistics(samples, levels=(0.05, 0.5, 0.95), shim_tolerance=1e-4)
    header, rows = _read_csv(write_statistics(tmp_path / "statistics.csv", stats, points))
    assert header == [
        "pair",
        "x (m)",
        "y (m)",
        "z (m)",
        "mean_gap (m)",
        "gap_q5 (m)",
        "gap_q50 (m)",
        "gap_q95 (m)",
        "contact_probability (-)",
        "shim_probability (-)",
    ]
    table = np.array(rows, dtype=float)
    np.testing.assert_array_equal(table[:, 0], range(4))
    np.testing.assert_array_equal(table[:, 4], stats.mean)
    np.testing.assert_array_equal(table[:, 5:8], stats.quantiles.T)
    np.testing.assert_array_equal(table[:, 8], stats.contact_probability)
    np.testing.assert_array_equal(table[:, 9], stats.shim_probability)
    header, _ = _read_csv(write_statistics(tmp_path / "plain.csv", gap_statistics(samples), points))
    assert "shim_probability (-)" not in header

    figure = statistics_map_figure(stats, points, normals)
    maps = [ax for ax in figure.axes if ax.get_title()]
    assert len(maps) == 3 and "above 0.1 mm" in maps[2].get_title()
    for ax in maps[1:]:  # both probabilities on the scale 0..1
        assert ax.collections[0].get_clim() == (0, 1)
    png = plot_statistics_maps(stats, points, normals, tmp_path / "statistics.png")
    assert png.stat().st_size > 1000


def test_summary_is_json_ready_and_the_table_renders(stages):
    from rich.console import Console

    stages[2].ok = False
    summary = json.loads(json.dumps(sequence_summary(Sequence(stages))))
    assert summary["success"] is False and summary["pairs"] == K
    assert [row["label"] for row in summary["stages"]] == [s.label for s in stages]
    for row, stage in zip(summary["stages"], stages, strict=True):
        assert row["max_gap"] == stage.gaps.max()
        assert sum(row["contacts"].values()) == K
        assert row["contacts"]["fastened"] == len(stage.fasteners)
        assert row["contacts"]["slip"] == np.count_nonzero(stage.status == ContactStatus.SLIP)
        assert row["fastener_forces"] == stage.fastener_forces.tolist()
        assert row["fasteners"] == stage.fasteners.tolist()
    console = Console(record=True, width=200)
    console.print(sequence_table(stages))
    text = console.export_text()
    assert "shear 50 N" in text and "210.2" in text and "closed" not in text
    assert "stick" in text and "slip" in text


def test_point_maps_mix_scales_and_categories_each_legend_its_own(geometry):
    """As riveting.plot_status draws them: gaps on a colour scale, then the status as labels;
    the marked points are named on the first panel only."""
    from contactqp.io.plot import point_maps_figure

    points, _ = geometry
    xy = points[:, :2]
    labels = np.where(np.arange(K) % 3 == 0, "closed", "open").astype(object)
    labels[[2, 7]] = "fastened"
    figure = point_maps_figure(
        xy,
        [(np.arange(K) * 1e-5, "gap", "viridis"), (labels, "status", STATUS_COLOURS)],
        marked=xy[[2, 7]],
        marked_label="fasteners",
    )
    panels = {ax.get_title(): ax for ax in figure.axes}
    gap_axes, status_axes = panels["gap"], panels["status"]
    assert len(figure.axes) == 3  # one colour bar: the gap panel's
    assert [t.get_text() for t in gap_axes.get_legend().get_texts()] == ["fasteners"]
    assert [t.get_text() for t in status_axes.get_legend().get_texts()] == [
        "open",
        "closed",
        "fastened",
    ]
    with pytest.raises(InvalidInputError, match="values for 20 points"):
        point_maps_figure(xy, [(np.zeros(3), "bad", "viridis")])


def test_initial_gaps_are_written_beside_the_residual_ones(stages, geometry, tmp_path):
    points, normals = geometry
    initial = np.linspace(-1e-5, 4e-4, K)
    files = write_sequence(tmp_path, stages, points, normals, initial_gaps=initial)
    table = np.genfromtxt(files["stages.csv"], delimiter=",", names=True, dtype=None)
    header, _ = _read_csv(files["stages.csv"])
    assert header.index("initial_gap (m)") == header.index("gap (m)") - 1
    np.testing.assert_array_equal(table["initial_gap_m"], np.tile(initial, len(stages)))
    np.testing.assert_array_equal(table["gap_m"], np.concatenate([s.gaps for s in stages]))
    mesh = meshio.read(files["stage_002.vtu"])
    np.testing.assert_array_equal(mesh.point_data["initial_gap"], initial)
    with pytest.raises(InvalidInputError, match="initial_gaps"):
        write_sequence(tmp_path, stages, points, normals, initial_gaps=initial[:-1])


def test_shim_table_and_summary_list_the_pairs_above_the_tolerance(stages, geometry, tmp_path):
    from rich.console import Console

    points, normals = geometry
    final = stages[-1]
    final.gaps[[3, 8, 11]] = [1e-4, 1.0001e-4, 2.5e-4]  # exactly at it: no shim
    tolerance = 1e-4
    expected = [p for p in range(K) if final.gaps[p] > tolerance]
    assert 8 in expected and 11 in expected and 3 not in expected
    files = write_sequence(tmp_path, stages, points, normals, shim_tolerance=tolerance)
    header, rows = _read_csv(files["shims.csv"])
    assert header == ["pair", "x (m)", "y (m)", "z (m)", "gap (m)"]
    assert [int(row[0]) for row in rows] == expected
    np.testing.assert_array_equal([float(row[4]) for row in rows], final.gaps[expected])
    np.testing.assert_array_equal(np.array(rows, dtype=float)[:, 1:4], points[expected])
    summary = sequence_summary(stages, shim_tolerance=tolerance)
    assert summary["shim_pairs"] == expected and summary["shim_tolerance"] == tolerance
    assert [row["shims"] for row in summary["stages"]] == [
        int(np.count_nonzero(s.gaps > tolerance)) for s in stages
    ]
    assert "shims" not in sequence_summary(stages)["stages"][0]
    console = Console(record=True, width=200)
    console.print(sequence_table(stages, shim_tolerance=tolerance))
    assert "gap > 0.1 mm" in console.export_text()
    with pytest.raises(InvalidInputError, match="shim_tolerance"):
        sequence_summary(stages, shim_tolerance=-1.0)

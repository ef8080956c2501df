"""Assembly files: every part source parses to the model the embedded FE gives, units convert,
pairs are found by proximity, gaps are interpolated, and every bad input names its key.

The two 3-D parts are blocks meshed by the embedded finite elements and written to files in a
temporary directory (a mesh file, an ANSYS ``.full``, MatrixMarket and unit-load CSV), so that
the file readers are exercised; the truth is the FE model's own condensed flexibility.
"""

from __future__ import annotations

import copy
import re

import numpy as np
import pytest
import scipy.io

from contactqp.applications.assembly_file import read_assembly_file
from contactqp.applications.assembly_file.schema import LENGTH_UNITS
from contactqp.applications.riveting import Assembly as RivetingAssembly
from contactqp.applications.riveting import Part
from contactqp.compliance.fem import Box, ElasticModel, block
from contactqp.errors import ContactError, FileFormatError, InvalidInputError
from fe_files import write_ansys_full
from test_problem_file_docs import toml_text

E, NU = 70e9, 0.33
SIZE = (0.04, 0.02, 0.01)  # m
RTOL = 1e-9
ROOT_EXAMPLE = "examples/assemblies/riveting-plates.toml"


def lower_body():
    """The lower block, fixed at z = 0; its interface is its top face (5 x 3 nodes)."""
    body = ElasticModel(block(*SIZE, 4, 2, 1), E, NU)
    body.fix(Box((0, 0, 0), (SIZE[0], SIZE[1], 0)))
    return body


def upper_body():
    """The upper block on top, z in [0.01, 0.02], fixed at its top; coarser (3 x 3 nodes on its
    bottom face, all of them on lower nodes)."""
    body = ElasticModel(block(*SIZE, 2, 2, 1).translated((0, 0, SIZE[2])), E, NU)
    body.fix(Box((0, 0, 2 * SIZE[2]), (SIZE[0], SIZE[1], 2 * SIZE[2])))
    return body


def face_nodes(body, z):
    return np.flatnonzero(np.abs(body.mesh.p[2] - z) < 1e-12)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The parts written to files, and their truths."""
    folder = tmp_path_factory.mktemp("parts")
    lower, upper = lower_body(), upper_body()
    lower.mesh.save(folder / "lower.vtu")  # skfem converts its hexahedra to VTK's order
    lower.mesh.scaled(1e3).save(folder / "lower_mm.vtu")
    nodes = face_nodes(upper, SIZE[2])
    truth = upper.reduced_model(nodes).flexibility
    # the whole stiffness, node by node (UX, UY, UZ), with the fixed freedoms constrained
    eq = upper.basis.nodal_dofs.T.ravel()
    position = np.empty_like(eq)
    position[eq] = np.arange(eq.size)
    numbers = np.arange(upper.n_nodes) + 101
    write_ansys_full(
        folder / "upper.full",
        upper.stiffness[eq][:, eq],
        numbers,
        constrained=position[upper.fixed],
    )
    scipy.io.mmwrite(
        folder / "upper_K.mtx", upper.stiffness[eq][:, eq].tocoo(), symmetry="symmetric"
    )
    scipy.io.mmwrite(folder / "upper_R.mtx", truth)
    header = ", ".join(f"{n}:{c}" for n in numbers[nodes] for c in ("UX", "UY", "UZ"))
    np.savetxt(folder / "upper_R.csv", truth, delimiter=",", header=header, comments="")
    rows = [
        f"{numbers[n]}, {float(x) * 1e3!r}, {float(y) * 1e3!r}, {float(z) * 1e3!r}"
        for n, (x, y, z) in zip(nodes, upper.mesh.p[:, nodes].T, strict=True)
    ]
    (folder / "upper_nodes.csv").write_text(
        "node, x (mm), y (mm), z (mm)\n" + "\n".join(rows) + "\n", encoding="utf-8"
    )
    index_rows = [f"{i}, {r.split(',', 1)[1]}" for i, r in enumerate(rows)]
    (folder / "upper_index_nodes.csv").write_text(
        "node, x (mm), y (mm), z (mm)\n" + "\n".join(index_rows) + "\n", encoding="utf-8"
    )
    lower_nodes = lower.select_nodes(where=Box((0, 0, SIZE[2]), SIZE)).nodes
    return {
        "folder": folder,
        "upper_truth": truth,
        "upper_nodes": nodes,
        "upper_numbers": numbers[nodes],
        "upper_fixed": position[upper.fixed],
        "upper_free": np.setdiff1d(np.arange(eq.size), position[upper.fixed]),
        "upper_interface_freedoms": np.concatenate(
            [position[upper.basis.nodal_dofs[:, n]] for n in nodes]
        ),
        "lower_truth": lower.reduced_model(lower_nodes).flexibility,
        "lower_coordinates": lower.mesh.p[:, lower_nodes].T,
        "upper_coordinates": upper.mesh.p[:, nodes].T,
    }


def lower_mesh_part(**extra):
    return {
        "type": "mesh",
        "mesh": "lower.vtu",
        "young": E,
        "poisson": NU,
        "fix": [{"at": {"lower": [0.0, 0.0, 0.0], "upper": [SIZE[0], SIZE[1], 0.0]}}],
        "interface": {"lower": [0.0, 0.0, SIZE[2]], "upper": list(SIZE)},
        **extra,
    }


def upper_full_part(files):
    return {
        "type": "matrix",
        "compliance": "upper.full",
        "nodes": files["upper_numbers"].tolist(),
        "components": ["UX", "UY", "UZ"],
        "coordinates": "upper_nodes.csv",
    }


def base(files) -> dict:
    return {
        "name": "two blocks",
        "parts": {"lower": lower_mesh_part(), "upper": upper_full_part(files)},
        "interfaces": [{"first": "lower", "second": "upper", "tolerance": 1e-4}],
        "gaps": {"nominal": 1e-5},
        "fasteners": [{"position": [0.02, 0.01, 0.01]}],
        "fastening": {"tolerance": 1e-3},
        "friction": {"mu": 0.3},
    }


def read(files, doc, name="assembly.toml"):
    path = files["folder"] / name
    path.write_text(toml_text(doc), encoding="utf-8")
    return read_assembly_file(path)


def assert_close(actual, expected):
    np.testing.assert_allclose(actual, expected, rtol=RTOL, atol=RTOL * np.abs(expected).max())


# ----------------------------------------------------------------------------------------------
# parts from every source


def test_mesh_file_and_ansys_full_parts_are_the_fe_models(files):
    parsed = read(files, base(files))
    lower, upper = parsed.parts
    assert_close(lower.model.flexibility, files["lower_truth"])
    assert_close(upper.model.flexibility, files["upper_truth"])
    assert_close(upper.coordinates, files["upper_coordinates"])
    assert lower.fe_model is not None and lower.mesh_nodes.size == 15


@pytest.mark.parametrize(
    "source",
    ["mtx-stiffness", "mtx-flexibility", "csv-rows", "inline-coordinates"],
)
def test_matrix_sources_give_the_same_flexibility(files, source):
    doc = base(files)
    part = {"type": "matrix", "coordinates": "upper_index_nodes.csv"}
    if source == "mtx-stiffness":
        part.update(
            compliance="upper_K.mtx",
            kind="stiffness",
            dofs_per_node=3,
            freedoms=files["upper_interface_freedoms"].tolist(),
            fixed=files["upper_fixed"].tolist(),
        )
    elif source == "mtx-flexibility":
        part.update(compliance="upper_R.mtx", kind="flexibility", dofs_per_node=3)
    elif source == "csv-rows":
        part.update(
            compliance="upper_R.csv",
            coordinates="upper_nodes.csv",
            nodes=files["upper_numbers"].tolist(),
        )
    else:
        part.update(
            compliance="upper_R.mtx",
            kind="flexibility",
            dofs_per_node=3,
            coordinates=(files["upper_coordinates"]).tolist(),
        )
    doc["parts"]["upper"] = part
    parsed = read(files, doc)
    assert_close(parsed.parts[1].model.flexibility, files["upper_truth"])
    assert_close(parsed.parts[1].coordinates, files["upper_coordinates"])


def test_generated_block_is_the_mesh_file(files):
    doc = base(files)
    doc["parts"]["lower"]["mesh"] = {"block": list(SIZE), "cells": [4, 2, 1]}
    doc["parts"]["lower"]["fix"] = [{"at": "bottom"}]
    doc["parts"]["lower"]["interface"] = "top"
    assert_close(read(files, doc).parts[0].model.flexibility, files["lower_truth"])


def test_plate_part_is_todays_riveting_plate(files):
    doc = base(files)
    doc["parts"] = {
        name: {"type": "plate", "grid": [5, 3], "origin": [0.0, 0.0, z]}
        for name, z in (("lower", 0.0), ("upper", 0.0))
    }
    doc["interfaces"][0]["normal"] = [0.0, 0.0, 1.0]
    doc.pop("friction")
    doc["fasteners"] = [{"position": [0.1, 0.05]}]
    parsed = read(files, doc)
    plates = RivetingAssembly(Part(), Part(), grid=(5, 3), fasteners=())
    assert_close(parsed.parts[0].model.flexibility, plates.flexibilities[0])
    assert parsed.fasteners[0].pair == 7 and parsed.fasteners[0].shear == "free"
    assert parsed.kind == "fastened" and parsed.method == "lawson-hanson"


def test_the_riveting_example_parses():
    parsed = read_assembly_file(ROOT_EXAMPLE)
    assert parsed.n_pairs == 35 and [f.pair for f in parsed.fasteners] == [17, 15, 19]
    np.testing.assert_allclose(parsed.gaps, 1e-4)
    assert parsed.shim_tolerance == pytest.approx(5e-5)
    assert parsed.variation.amplitude == pytest.approx(5e-5)
    plates = RivetingAssembly(Part(), Part(), grid=(7, 5), fasteners=())
    assert_close(parsed.parts[1].model.flexibility, plates.flexibilities[1])


# ----------------------------------------------------------------------------------------------
# units


def test_millimetres_and_megapascals_give_the_si_model(files):
    doc = base(files)
    doc["units"] = {"length": "mm", "force": "N"}
    part = lower_mesh_part(mesh="lower_mm.vtu", young=E * 1e-6)
    part["fix"] = [{"at": {"lower": [0.0, 0.0, 0.0], "upper": [40.0, 20.0, 0.0]}}]
    part["interface"] = {"lower": [0.0, 0.0, 10.0], "upper": [40.0, 20.0, 10.0]}
    doc["parts"]["lower"] = part
    doc["interfaces"][0]["tolerance"] = 0.1
    doc["gaps"]["nominal"] = 0.01
    doc["fasteners"] = [
        {"position": [20.0, 10.0, 10.0], "kind": "clamp", "force": 2.0, "stiffness": 3.0}
    ]
    doc["fastening"]["tolerance"] = 1.0
    doc["loads"] = [{"part": "upper", "force": [5.0, 0.0, 0.0]}]
    doc["criteria"] = {"shim_tolerance": 0.05}
    doc["units"]["force"] = "kN"
    doc["parts"]["lower"]["young"] = E * 1e-9  # kN / mm^2
    parsed = read(files, doc)
    assert_close(parsed.parts[0].model.flexibility, files["lower_truth"])
    assert_close(parsed.parts[1].model.flexibility, files["upper_truth"] * 1e-6)  # mm/kN
    np.testing.assert_allclose(parsed.gaps, 1e-5)
    clamp = parsed.fasteners[0]
    assert clamp.force == pytest.approx(2e3) and clamp.stiffness == pytest.approx(3e6)
    assert parsed.shim_tolerance == pytest.approx(5e-5)
    assert parsed.load_steps[0][1].sum() == pytest.approx(5e3)


def test_a_matrix_file_in_millimetres_is_converted(files, tmp_path):
    scipy.io.mmwrite(tmp_path / "R_mm.mtx", files["upper_truth"] * 1e3)  # mm/N
    nodes = (files["folder"] / "upper_index_nodes.csv").read_text(encoding="utf-8")
    (tmp_path / "nodes.csv").write_text(nodes.replace(" (mm)", ""), encoding="utf-8")
    part = {
        "type": "matrix",
        "compliance": "R_mm.mtx",
        "kind": "flexibility",
        "dofs_per_node": 3,
        "coordinates": "nodes.csv",
    }
    doc = {
        "units": {"length": "mm"},
        "parts": {"lower": part, "upper": part},
        "interfaces": [
            {"first": "lower", "second": "upper", "tolerance": 0.1, "normal": [0.0, 0.0, 1.0]}
        ],
    }
    path = tmp_path / "a.toml"
    path.write_text(toml_text(doc), encoding="utf-8")
    parsed = read_assembly_file(path)
    assert_close(parsed.parts[1].model.flexibility, files["upper_truth"])
    assert_close(parsed.parts[1].coordinates, files["upper_coordinates"])
    assert parsed.interfaces[0].nodes.shape == (9, 2) and parsed.fasteners == ()


# ----------------------------------------------------------------------------------------------
# pairing and normals


def test_proximity_pairs_the_coinciding_nodes_and_reports_the_others(files):
    parsed = read(files, base(files))
    (interface,) = parsed.interfaces
    lower, upper = parsed.parts
    assert interface.nodes.shape == (9, 2)
    np.testing.assert_allclose(
        lower.coordinates[interface.nodes[:, 0]],
        upper.coordinates[interface.nodes[:, 1]],
        atol=1e-12,
    )
    (unmatched,) = parsed.unmatched
    assert unmatched.part == "lower" and unmatched.nodes.size == 6 and unmatched.n_nodes == 15
    assert re.fullmatch(
        r"interfaces\[0\]: 6 of 15 nodes of 'lower' unmatched \(e\.g\. .*\)", unmatched.describe()
    )
    xs = lower.coordinates[unmatched.nodes, 0]
    assert set(np.round(xs, 6)) == {0.01, 0.03}
    np.testing.assert_allclose(interface.normals, np.tile([0.0, 0.0, 1.0], (9, 1)), atol=1e-12)


def test_parts_too_far_apart_have_no_pairs(files):
    doc = base(files)
    doc["parts"] = {
        name: {"type": "plate", "grid": [3, 3], "origin": [0.0, 0.0, z]}
        for name, z in (("lower", 0.0), ("upper", 0.01))
    }
    doc["interfaces"][0]["tolerance"] = 1e-3
    with pytest.raises(InvalidInputError, match=r"interfaces\[0\]\.tolerance: no node of 'lower' "):
        read(files, doc)


def test_proximity_is_one_to_one_closest_first():
    from contactqp.applications.assembly_file.pairing import pair_by_proximity

    first = np.array([[0.0, 0, 0], [1.0, 0, 0], [5.0, 0, 0]])
    second = np.array([[0.9, 0, 0], [0.2, 0, 0], [9.0, 0, 0]])
    pairs, alone_first, alone_second = pair_by_proximity(first, second, 1.0)
    np.testing.assert_array_equal(pairs, [[0, 1], [1, 0]])
    np.testing.assert_array_equal(alone_first, [2])
    np.testing.assert_array_equal(alone_second, [2])


def test_geometric_normals_follow_a_tilted_surface():
    from contactqp.applications.assembly_file.pairing import geometric_normals

    x, y = np.meshgrid(np.linspace(0, 1, 6), np.linspace(0, 1, 5))
    plane = np.column_stack([x.ravel(), y.ravel(), 0.3 * x.ravel() - 0.2 * y.ravel()])
    expected = np.array([-0.3, 0.2, 1.0]) / np.linalg.norm([-0.3, 0.2, 1.0])
    normals, problem = geometric_normals(plane, np.arange(30), np.array([0.0, 0.0, 1.0]))
    assert problem == ""
    np.testing.assert_allclose(normals, np.tile(expected, (30, 1)), atol=1e-12)
    flipped, _ = geometric_normals(plane, np.arange(3), np.array([0.0, 0.0, -1.0]))
    np.testing.assert_allclose(flipped, -np.tile(expected, (3, 1)), atol=1e-12)


def test_explicit_pairs_and_per_pair_normals(files):
    doc = base(files)
    doc["interfaces"][0] = {
        "first": "lower",
        "second": "upper",
        "pairs": [[0, 0], [2, 1]],
        "normal": [[0.0, 0.0, 2.0], [0.0, 0.0, 1.0]],
    }
    doc["fasteners"] = [{"pair": 0}]
    parsed = read(files, doc)
    np.testing.assert_array_equal(parsed.interfaces[0].nodes, [[0, 0], [2, 1]])
    np.testing.assert_allclose(parsed.interfaces[0].normals, [[0, 0, 1.0], [0, 0, 1.0]])
    assert parsed.unmatched == ()


# ----------------------------------------------------------------------------------------------
# gaps


def write_cloud(path, xy, gaps, unit="mm", z=None):
    header = (
        f"x ({unit}), y ({unit}), " + (f"z ({unit}), " if z is not None else "") + f"gap ({unit})"
    )
    scale = 1.0 / LENGTH_UNITS[unit]
    columns = [xy[:, 0] * scale, xy[:, 1] * scale]
    if z is not None:
        columns.append(z * scale)
    columns.append(gaps * scale)
    np.savetxt(path, np.column_stack(columns), delimiter=",", header=header, comments="")


def linear_gap(points):
    return 2e-5 + 1e-4 * points[:, 0] - 3e-4 * points[:, 1]


@pytest.mark.parametrize("interpolant", ["linear", "thin-plate"])
@pytest.mark.parametrize("with_z", [False, True])
def test_a_linear_gap_field_is_reproduced_and_its_error_reported(files, interpolant, with_z):
    rng = np.random.default_rng(1)
    xy = np.vstack(
        [
            [[-0.001, -0.001], [0.041, -0.001], [-0.001, 0.021], [0.041, 0.021]],
            rng.uniform((0, 0), (0.04, 0.02), (30, 2)),
        ]
    )
    name = f"cloud_{interpolant}_{with_z}.csv"
    write_cloud(
        files["folder"] / name, xy, linear_gap(xy), z=np.full(len(xy), 0.01) if with_z else None
    )
    doc = base(files)
    doc["gaps"] = {"cloud": name, "interpolant": interpolant}
    parsed = read(files, doc)
    np.testing.assert_allclose(parsed.gaps, linear_gap(parsed.points), rtol=0, atol=1e-15)
    error = parsed.interpolation_error
    assert error.n_points + error.n_skipped == len(xy) and error.max_abs < 1e-15
    assert "leave-one-out" in error.describe()


def test_the_interpolation_error_of_a_curved_field_is_reported(files):
    x, y = np.meshgrid(np.linspace(0, 0.04, 9), np.linspace(0, 0.02, 5))
    xy = np.column_stack([x.ravel(), y.ravel()])
    write_cloud(files["folder"] / "curved.csv", xy, 1e-3 * (xy[:, 0] / 0.04) ** 2)
    doc = base(files)
    doc["gaps"] = {"cloud": "curved.csv"}
    error = read(files, doc).interpolation_error
    # leave-one-out at an inner point of a parabola sampled every h: h^2 a = (0.005/0.04)^2 1e-3
    assert error.max_abs == pytest.approx(1e-3 * (0.005 / 0.04) ** 2, rel=1e-9)


def test_pairs_outside_the_cloud_are_refused_unless_extrapolating(files):
    xy = np.array([[0.0, 0.0], [0.03, 0.0], [0.0, 0.02], [0.03, 0.02]])
    write_cloud(files["folder"] / "short.csv", xy, linear_gap(xy))
    doc = base(files)
    doc["gaps"] = {"cloud": "short.csv"}
    with pytest.raises(InvalidInputError, match=r"gaps\.cloud: 3 pairs outside .*extrapolate"):
        read(files, doc)
    doc["gaps"]["extrapolate"] = True
    parsed = read(files, doc)
    outside = parsed.points[:, 0] > 0.03
    np.testing.assert_allclose(
        parsed.gaps[~outside], linear_gap(parsed.points[~outside]), atol=1e-15
    )
    # outside the hull each pair takes the gap of a nearest measured point
    nearest = np.linalg.norm(parsed.points[outside, None, :2] - xy[None], axis=2)
    for gap, distance in zip(parsed.gaps[outside], nearest, strict=True):
        closest = np.flatnonzero(np.isclose(distance, distance.min()))
        assert np.isclose(gap, linear_gap(xy[closest]), rtol=0, atol=1e-15).any()


def test_variation_sources(files):
    doc = base(files)
    doc["variation"] = {"type": "random", "amplitude": 1e-5, "correlation_length": 0.01}
    parsed = read(files, doc)
    fields = parsed.variation.realisations(range(4))
    assert fields.shape == (4, 9) and "random field" in parsed.variation_description
    np.testing.assert_allclose(parsed.variation.mean, 1e-5)
    samples = np.arange(27.0).reshape(3, 9) * 1e-6
    np.savetxt(files["folder"] / "samples.csv", samples, delimiter=",")
    doc["variation"] = {"type": "samples", "file": "samples.csv"}
    np.testing.assert_array_equal(read(files, doc).variation.realisations([2]), samples[2:])
    x, y = np.meshgrid(np.linspace(0, 0.04, 3), np.linspace(0, 0.02, 3))
    xy = np.column_stack([x.ravel(), y.ravel()])
    table = np.column_stack([xy * 1e3, linear_gap(xy) * 1e3, 2 * linear_gap(xy) * 1e3])
    np.savetxt(
        files["folder"] / "measured.csv",
        table,
        delimiter=",",
        header="x (mm), y (mm), A (mm), B (mm)",
        comments="",
    )
    doc["variation"] = {"type": "measured", "file": "measured.csv"}
    parsed = read(files, doc)
    assert parsed.variation.n_available == 2
    np.testing.assert_allclose(
        parsed.variation.realisations([1])[0], 2 * linear_gap(parsed.points), atol=1e-15
    )


# ----------------------------------------------------------------------------------------------
# fasteners, friction, loads, solver


def test_fasteners_order_kinds_and_labels(files):
    doc = base(files)
    doc["fasteners"] = [
        {"position": [0.0, 0.0, 0.01], "label": "A"},
        {"pair": 4, "kind": "clamp", "force": 100.0, "stiffness": 1e8, "shear": "free"},
        {"position": [0.04, 0.02]},
    ]
    doc["fastening"]["order"] = [2, "A", 1]
    parsed = read(files, doc)
    labels = [f.label for f in parsed.fasteners]
    assert labels == ["fastener 2 (pair 8)", "A", "fastener 1 (pair 4)"]
    assert parsed.fasteners[2].kind == "clamp" and parsed.fasteners[2].force == 100.0
    assert parsed.fasteners[1].shear == "bonded" and parsed.fasteners[2].shear == "free"
    assert [f.pair for f in parsed.fasteners] == [8, 0, 4]


def test_friction_and_solver(files):
    doc = base(files)
    doc["friction"] = {"mu": [0.1] * 9, "cone": "polygonal", "facets": 6}
    doc["solver"] = {"method": "polygonal", "tol": 1e-9}
    parsed = read(files, doc)
    assert parsed.kind == "frictional-polygonal" and parsed.facets == 6
    assert parsed.options == {"tol": 1e-9}
    np.testing.assert_allclose(parsed.mu, 0.1)


def test_load_steps_apply_and_remove_a_shear(files):
    doc = base(files)
    doc["loads"] = [
        {"label": "shear", "part": "upper", "force": [50.0, 0.0, 0.0], "steps": 2},
        {
            "part": "lower",
            "box": {"lower": [0.0, 0.0, 0.01], "upper": [0.0, 0.02, 0.01]},
            "force": [0.0, 0.0, -3.0],
            "remove": False,
        },
    ]
    parsed = read(files, doc)
    labels = [label for label, _ in parsed.load_steps]
    assert labels == ["shear 1/2", "shear 2/2", "shear removed 1/2", "shear removed 2/2", "load 1"]
    n_lower = parsed.parts[0].model.n_freedoms
    full = parsed.load_steps[1][1]
    assert full[n_lower::3].sum() == pytest.approx(50.0) and full[:n_lower].sum() == 0.0
    np.testing.assert_allclose(parsed.load_steps[3][1], 0.0, atol=1e-12)
    last = parsed.load_steps[4][1]
    edge = parsed.parts[0].coordinates[:, 0] == 0.0
    np.testing.assert_allclose(last[2:n_lower:3][edge], -1.0)
    assert last.sum() == pytest.approx(-3.0)


def test_the_assembly_file_is_never_written(files):
    doc = base(files)
    before = {p.name: p.read_bytes() for p in files["folder"].iterdir() if p.is_file()}
    read(files, doc, "untouched.toml")
    after = {p.name: p.read_bytes() for p in files["folder"].iterdir() if p.is_file()}
    assert {k: v for k, v in after.items() if k in before and k != "untouched.toml"} == {
        k: v for k, v in before.items() if k != "untouched.toml"
    }


# ----------------------------------------------------------------------------------------------
# every bad input is one line naming its key


def _set(path, value):
    def change(doc):
        *parents, last = path
        target = doc
        for name in parents:
            target = target[name]
        if value is _DELETE:
            del target[last]
        else:
            target[last] = value

    return change


_DELETE = object()

BAD = [
    (_set(["parts", "lower", "tpye"], 1), r"parts\.lower: unknown key 'tpye'.*did you mean"),
    (_set(["parts", "lower", "type"], "fem"), r"parts\.lower\.type: must be one of"),
    (_set(["parts", "lower", "mesh"], "missing.vtu"), r"parts\.lower\.mesh: file not found"),
    (
        _set(["parts", "upper", "compliance"], "gone.full"),
        r"parts\.upper\.compliance: file not found",
    ),
    (_set(["parts", "upper", "kind"], "stiffness"), r"parts\.upper\.kind: not taken by"),
    (_set(["parts", "upper", "nodes"], [1, 2, 3]), r"parts\.upper\.compliance: .*node"),
    (
        _set(["parts", "upper", "coordinates"], "nothere.csv"),
        r"parts\.upper\.coordinates: file not found",
    ),
    (_set(["parts", "lower", "young"], -1.0), r"parts\.lower\.young: must be positive"),
    (_set(["parts", "lower", "poisson"], 0.5), r"parts\.lower\.poisson: must lie in"),
    (_set(["parts", "lower", "fix"], [{"at": "side"}]), r"parts\.lower\.fix\[0\]\.at: .*no face"),
    (
        _set(
            ["parts", "lower", "fix"],
            [{"at": {"lower": [0.0, 0.0, 0.0], "upper": [0.0, 0.0, 0.0]}}],
        ),
        r"parts\.lower\.fix: .*rigid",
    ),
    (_set(["parts", "lower", "interface"], 3), r"parts\.lower\.interface: must be a face name"),
    (
        _set(
            [
                "units",
            ],
            {"length": "inch"},
        ),
        r"units\.length: must be one of",
    ),
    (_set(["interfaces", 0, "first"], "middle"), r"interfaces\[0\]\.first: no part named"),
    (_set(["interfaces", 0, "second"], "lower"), r"interfaces\[0\]\.second: must differ"),
    (
        _set(["interfaces", 0, "tolerance"], 0.0),
        r"interfaces\[0\]\.tolerance: must be positive",
    ),
    (
        _set(["interfaces", 0, "pairs"], [[0, 0], [1, 0]]),
        r"interfaces\[0\]\.pairs: node 0 of 'upper' is in more than one pair",
    ),
    (
        _set(["interfaces", 0, "pairs"], [[14, 0]]),
        r"interfaces\[0\]\.pairs: pair 0 \(14, 0\) is 0\.04472 m apart, beyond the tolerance",
    ),
    (_set(["interfaces", 0, "normal"], [0.0, 0.0, 0.0]), r"interfaces\[0\]\.normal: normal 0 is"),
    (
        _set(["interfaces", 0, "normal"], [[0.0, 0.0, 1.0]]),
        r"interfaces\[0\]\.normal: must have shape \(9, 3\)",
    ),
    (_set(["gaps", "nominal"], [0.0, 1.0]), r"gaps\.nominal has 2 values, the interfaces have 9"),
    (_set(["gaps", "cloud"], "cloud.csv"), r"gaps: give nominal or cloud, not both"),
    (_set(["gaps", "interpolant"], "cubic"), r"gaps\.interpolant: must be one of"),
    (
        _set(["variation"], {"type": "random", "amplitude": 1e-5}),
        r"variation\.correlation_length: missing",
    ),
    (
        _set(["variation"], {"type": "samples", "file": "nope.npy"}),
        r"variation\.file: file not found",
    ),
    (
        _set(["fasteners", 0, "position"], [0.5, 0.5, 0.5]),
        r"fasteners\[0\]\.position: the nearest pair \(\d+\) is .* beyond fastening\.tolerance",
    ),
    (_set(["fasteners", 0, "pair"], 3), r"fasteners\[0\]: give position or pair"),
    (_set(["fasteners", 0, "kind"], "clamp"), r"fasteners\[0\]\.force: missing"),
    (_set(["fasteners", 0, "force"], 10.0), r"fasteners\[0\]\.force: only a clamp"),
    (_set(["fasteners", 0, "shear"], "glued"), r"fasteners\[0\]\.shear: must be one of"),
    (_set(["fastening", "order"], [0, 0]), r"fastening\.order: must list every fastener once"),
    (_set(["fastening", "tolerance"], _DELETE), r"fastening\.tolerance: missing"),
    (_set(["friction", "mu"], -0.1), r"friction\.mu: must be >= 0"),
    (_set(["friction", "facets"], 8), r"friction\.facets: applies to cone"),
    (_set(["friction", "cone"], "round"), r"friction\.cone: must be one of"),
    (_set(["loads"], [{"part": "upper"}]), r"loads\[0\]\.force: missing"),
    (
        _set(["loads"], [{"part": "side", "force": [1.0, 0.0, 0.0]}]),
        r"loads\[0\]\.part: no part named",
    ),
    (
        _set(["loads"], [{"part": "upper", "force": [1.0, 0.0], "steps": 0}]),
        r"loads\[0\]\.force: must hold 3 numbers",
    ),
    (_set(["criteria"], {"shim_tolerance": -1.0}), r"criteria\.shim_tolerance: must be >= 0"),
    (_set(["solver"], {"method": "lawson-hanson"}), r"\[solver\]\.method: .*does not solve"),
    (
        _set(["solver"], {"method": "coulomb", "tolerance": 1.0}),
        r"\[solver\]\.tolerance: not an option",
    ),
    (_set(["extra"], 1), r"top level: unknown key 'extra'"),
]


@pytest.mark.parametrize("change, message", BAD, ids=[m for _, m in BAD])
def test_bad_input_is_one_line_naming_the_key(files, change, message):
    doc = copy.deepcopy(base(files))
    change(doc)
    with pytest.raises(ContactError) as caught:
        read(files, doc, "bad.toml")
    text = str(caught.value)
    assert "\n" not in text and text.startswith(str(files["folder"] / "bad.toml") + ": ")
    assert re.search(message, text), text


def test_friction_needs_the_in_plane_freedoms(files):
    doc = base(files)
    doc["parts"] = {name: {"type": "plate", "grid": [3, 3]} for name in ("lower", "upper")}
    doc["interfaces"][0]["normal"] = [0.0, 0.0, 1.0]
    doc["fasteners"] = [{"pair": 0}]
    with pytest.raises(InvalidInputError, match=r"friction\.mu: pair 0's nodes have no in-plane"):
        read(files, doc)
    doc.pop("friction")
    doc["fasteners"][0]["shear"] = "bonded"
    with pytest.raises(InvalidInputError, match=r"fasteners\[0\]\.shear: pair 0's nodes"):
        read(files, doc)


def test_missing_and_invalid_files(tmp_path):
    with pytest.raises(FileFormatError, match="assembly file not found"):
        read_assembly_file(tmp_path / "none.toml")
    (tmp_path / "broken.toml").write_text("[parts\n", encoding="utf-8")
    with pytest.raises(FileFormatError, match="not valid TOML"):
        read_assembly_file(tmp_path / "broken.toml")

"""Embedded finite elements against closed-form elasticity, beam theory and brute force."""

import meshio
import numpy as np
import pytest
import skfem

from contactqp.compliance.fem import (
    Box,
    ElasticModel,
    bar,
    block,
    elastic_compliance,
    plate,
    read_mesh,
)
from contactqp.errors import (
    FileFormatError,
    InvalidInputError,
    RigidBodyModeError,
    UnsupportedProblemError,
)

E, NU = 200e9, 0.3  # steel (Pa, -)
STRESS = 1e6  # applied traction (Pa)


def _distorted(mesh, rng):
    """The mesh with its interior nodes moved at random by up to 0.05 m (a fifth of a cell)."""
    p = mesh.p.copy()
    interior = np.setdiff1d(np.arange(p.shape[1]), mesh.boundary_nodes())
    p[:, interior] += rng.uniform(-0.05, 0.05, (p.shape[0], interior.size))
    return type(mesh)(p, mesh.t).with_boundaries(
        {"left": lambda x: x[0] == 0.0, "right": lambda x: x[0] == 2.0}
    )


def _tension_model(cell, order, plane, distort=False):
    """A bar under uniform tension along x, held by symmetry rollers only (no end restraint)."""
    if cell in ("tri", "quad"):
        mesh = plate(2.0, 0.5, 8, 2, cell=cell)
        mesh = _distorted(mesh, np.random.default_rng(3)) if distort else mesh
        model = ElasticModel(mesh, E, NU, plane=plane, thickness=0.1, order=order)
        model.fix("left", [0]).fix(Box((0, 0), (0, 0)), [1])
    else:
        mesh = block(2.0, 0.5, 0.4, 8, 2, 2, cell=cell)
        mesh = _distorted(mesh, np.random.default_rng(3)) if distort else mesh
        model = ElasticModel(mesh, E, NU, order=order)
        model.fix("left", [0]).fix(Box((0, 0, 0), (0, 0.5, 0)), [2])
        model.fix(Box((0, 0, 0), (0, 0, 0.4)), [1])
    traction = np.zeros(mesh.p.shape[0])
    traction[0] = STRESS
    return model, model.solve(tractions={"right": traction})


@pytest.mark.parametrize("distort", [False, True], ids=["regular", "distorted"])
@pytest.mark.parametrize(
    "cell,order,plane",
    [
        ("tri", 1, "stress"),
        ("tri", 2, "strain"),
        ("quad", 1, "strain"),
        ("quad", 2, "stress"),
        ("tet", 1, None),
        ("tet", 2, None),
        ("hex", 1, None),
    ],
)
def test_bar_in_tension_is_exact(cell, order, plane, distort):
    """Patch test: a uniform stress lies in every element space, so the answer is exact, on a
    regular mesh and on one whose interior nodes are moved at random.

    Plane stress: ``eps_xx = s / E``, ``eps_yy = -nu s / E``; plane strain (``eps_zz = 0``):
    ``eps_xx = (1 - nu^2) s / E``, ``eps_yy = -nu (1 + nu) s / E``; 3D as plane stress.
    """
    model, u = _tension_model(cell, order, plane, distort)
    axial, lateral = (
        (STRESS / E, -NU * STRESS / E)
        if plane != "strain"
        else ((1 - NU**2) * STRESS / E, -NU * (1 + NU) * STRESS / E)
    )
    x = model.mesh.p
    scale = axial * 2.0
    np.testing.assert_allclose(u[:, 0], axial * x[0], rtol=0, atol=1e-11 * scale)
    for axis in range(1, model.dim):
        np.testing.assert_allclose(u[:, axis], lateral * x[axis], rtol=0, atol=1e-11 * scale)


def test_plane_stress_uses_the_modified_lame_parameter():
    mesh = plate(1.0, 1.0, 1, 1)
    stress = ElasticModel(mesh, E, NU, plane="stress")
    strain = ElasticModel(mesh, E, NU, plane="strain")
    assert stress.lame[0] == pytest.approx(E * NU / (1 - NU**2), rel=1e-14)
    assert strain.lame[0] == pytest.approx(E * NU / ((1 + NU) * (1 - 2 * NU)), rel=1e-14)
    assert stress.lame[1] == strain.lame[1] == pytest.approx(E / (2 * (1 + NU)), rel=1e-14)


@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_cantilever_tip_deflection_matches_timoshenko_beam_theory(plane):
    """Clamped 2D cantilever, L/h = 10, end shear P: ``P L^3 / (3 E' I) + P L / (k G A)``.

    ``E' = E`` (plane stress) or ``E / (1 - nu^2)`` (plane strain), ``k = 5/6``. Quadratic
    quadrilaterals converge to within 0.02 % between 4 and 8 cells across. The clamped root
    restrains shear and Poisson contraction, which beam theory ignores (a Saint-Venant end
    effect), so the answer lies between Euler-Bernoulli (no shear) and Timoshenko: 0.2 % (plane
    stress) and 0.4 % (plane strain) below the latter. Tolerance 0.5 %.
    """
    length, height, thickness, force = 1.0, 0.1, 0.02, 100.0
    mesh = bar(length, height, across=4)
    model = ElasticModel(mesh, E, NU, plane=plane, thickness=thickness, order=2).fix("left")
    u = model.solve(tractions={"right": (0.0, force / (height * thickness))})
    tip = model.select_nodes([[length, height / 2]]).nodes
    inertia, area = thickness * height**3 / 12, thickness * height
    bending = E if plane == "stress" else E / (1 - NU**2)
    euler_bernoulli = force * length**3 / (3 * bending * inertia)
    timoshenko = euler_bernoulli + force * length / (5 / 6 * E / (2 * (1 + NU)) * area)
    assert euler_bernoulli < u[tip[0], 1] < timoshenko
    assert u[tip[0], 1] == pytest.approx(timoshenko, rel=5e-3)


def test_3d_cantilever_tip_deflection_matches_beam_theory():
    """Square-section block cantilever (L/h = 10), quadratic tetrahedra, two cells across.

    Against Timoshenko's ``P L^3 / (3 E I) + P L / (k G A)``: the coarse mesh is 1.1 % stiff
    (0.8 % with four cells across; the rest is the clamped root). Tolerance 2 %.
    """
    length, side, force = 1.0, 0.1, 100.0
    model = ElasticModel(bar(length, side, side, cell="tet"), E, NU, order=2).fix("left")
    u = model.solve(tractions={"right": (0.0, 0.0, force / side**2)})
    tip = model.select_nodes([[length, side / 2, side / 2]]).nodes[0]
    beam = force * length**3 / (3 * E * side**4 / 12) + force * length / (
        5 / 6 * E / (2 * (1 + NU)) * side**2
    )
    assert u[tip, 2] == pytest.approx(beam, rel=2e-2)
    assert max(abs(u[tip, 0]), abs(u[tip, 1])) < 1e-3 * u[tip, 2]


def test_point_loads_and_tractions_superpose():
    model = ElasticModel(plate(1.0, 0.2, 5, 2), E, NU, plane="stress").fix("left")
    loads = np.zeros((model.n_nodes, 2))
    loads[model.select_nodes([[1.0, 0.2]]).nodes, :] = (30.0, -50.0)
    traction = {"top": (0.0, -1e4)}
    both = model.solve(loads, tractions=traction)
    np.testing.assert_allclose(
        both,
        model.solve(loads) + model.solve(tractions=traction),
        rtol=1e-12,
        atol=1e-12 * np.abs(both).max(),
    )


def test_thickness_scales_the_flexibility():
    mesh = plate(1.0, 0.2, 5, 2)
    nodes = [mesh.p.shape[1] - 1]
    thin = ElasticModel(mesh, E, NU, plane="stress", thickness=0.01).fix("left")
    thick = ElasticModel(mesh, E, NU, plane="stress", thickness=0.04).fix("left")
    np.testing.assert_allclose(
        thin.reduced_model(nodes).flexibility,
        4 * thick.reduced_model(nodes).flexibility,
        rtol=1e-12,
    )


def test_quadratic_faces_are_clamped_at_mid_side_points():
    """A clamped face of quadratic elements must hold its mid-side freedoms too."""
    model = ElasticModel(block(1.0, 0.5, 0.5, 2, 1, 1, cell="tet"), E, NU, order=2).fix("left")
    on_face = np.isclose(model.basis.doflocs[0], 0.0)
    assert on_face.sum() > model.dim * np.isclose(model.mesh.p[0], 0.0).sum()
    np.testing.assert_array_equal(np.flatnonzero(on_face), model.fixed)


def test_nearest_nodes_and_distances_match_brute_force():
    model = ElasticModel(plate(1.0, 0.5, 10, 5, cell="tri"), E, NU, plane="strain")
    points = np.array([[0.33, 0.52], [0.71, 0.26], [0.0, 0.0]])
    chosen = model.select_nodes(points)
    gaps = np.linalg.norm(model.mesh.p.T[None, :, :] - points[:, None, :], axis=2)
    np.testing.assert_array_equal(chosen.nodes, gaps.argmin(axis=1))
    np.testing.assert_allclose(chosen.distances, gaps.min(axis=1), rtol=1e-14)
    assert chosen.distances[2] == 0.0 and chosen.distances[0] == pytest.approx(np.hypot(0.03, 0.02))


def test_where_restricts_the_candidates_to_a_face_inside_a_box():
    model = ElasticModel(block(1.0, 1.0, 1.0, 4, 4, 4), E, NU)
    top_middle = model.select_nodes(where=("top", Box((0.25, 0.25, 0.0), (0.75, 0.75, 1.0))))
    np.testing.assert_allclose(model.mesh.p[2, top_middle.nodes], 1.0)
    assert top_middle.nodes.size == 9 and not top_middle.distances.any()
    on_top = model.select_nodes([[0.5, 0.5, 0.6]], where="top")
    assert model.mesh.p[2, on_top.nodes[0]] == 1.0 and on_top.distances[0] == pytest.approx(0.4)
    by_function = model.select_nodes(where=lambda x: x[0] + x[1] < 0.3)
    assert set(by_function.nodes) == set(np.flatnonzero(model.mesh.p[0] + model.mesh.p[1] < 0.3))


def test_points_sharing_a_node_are_refused():
    model = ElasticModel(plate(1.0, 1.0, 2, 2), E, NU, plane="stress")
    with pytest.raises(InvalidInputError, match=r"points \[0, 1\] share their nearest node"):
        model.select_nodes([[0.01, 0.0], [0.0, 0.02]])


def test_one_call_equals_the_model_route():
    mesh = plate(1.0, 0.2, 10, 2)
    points = [[1.0, 0.2], [0.5, 0.2]]
    reduced = elastic_compliance(
        mesh, E, NU, "left", points, plane="stress", where="top", components=[1]
    )
    model = ElasticModel(mesh, E, NU, plane="stress").fix("left")
    nodes = model.select_nodes(points, where="top")
    np.testing.assert_array_equal(
        reduced.flexibility, model.reduced_model(nodes, components=[1]).flexibility
    )
    assert reduced.n_freedoms == 2 and reduced.coordinates.tolist() == [[1.0, 0.2], [0.5, 0.2]]


@pytest.mark.parametrize(
    "fixing,motions",
    [
        (lambda m: None, "translation along x, translation along y, rotation in the plane"),
        (lambda m: m.fix("left", [0]), "translation along y"),
        (lambda m: m.fix(Box((0, 0), (0, 0))), "rotation in the plane"),
    ],
)
def test_missing_fixations_name_the_free_motions_2d(fixing, motions):
    model = ElasticModel(plate(1.0, 1.0, 3, 3), E, NU, plane="strain")
    fixing(model)
    with pytest.raises(RigidBodyModeError, match=f"rigid-body modes \\({motions}\\)"):
        model.reduced_model([5])


@pytest.mark.parametrize(
    "fixing,motions",
    [
        (
            lambda m: m.fix("left", [0]),
            "translation along y, translation along z, rotation about x",
        ),
        (lambda m: m.fix(lambda x: (x[0] == 0) & (x[1] == 0)), "rotation about an axis along z"),
    ],
)
def test_missing_fixations_name_the_free_motions_3d(fixing, motions):
    model = ElasticModel(block(1.0, 1.0, 1.0, 2, 2, 2), E, NU)
    fixing(model)
    with pytest.raises(RigidBodyModeError, match=f"rigid-body modes \\({motions}\\)"):
        model.solve(np.zeros((model.n_nodes, 3)))


def test_a_loose_part_of_the_mesh_is_named():
    held = plate(1.0, 1.0, 2, 2)
    loose = skfem.MeshQuad(held.p + np.array([[3.0], [0.0]]), held.t)
    model = ElasticModel(held + loose, E, NU, plane="stress").fix(Box((0, 0), (0, 1)))
    with pytest.raises(RigidBodyModeError, match=r"part of the mesh around \(3\.5, 0\.5\)"):
        model.reduced_model(model.select_nodes([[4.0, 1.0]]).nodes)


def test_a_mesh_read_from_a_file_gives_the_same_model(tmp_path):
    mesh = plate(1.0, 0.2, 5, 2, cell="tri")
    path = tmp_path / "plate.msh"
    mesh.save(path, file_format="gmsh")
    read = read_mesh(path)
    assert set(read.boundaries) >= {"left", "right"}
    reduced = [
        ElasticModel(m, E, NU, plane="stress").fix("left").reduced_model([6, 11])
        for m in (mesh, read)
    ]
    np.testing.assert_allclose(reduced[1].flexibility, reduced[0].flexibility, rtol=1e-12)


def test_unused_nodes_of_a_file_are_dropped():
    mesh = plate(1.0, 1.0, 1, 1, cell="tri")
    points = np.vstack([[[5.0, 5.0, 0.0]], np.c_[mesh.p.T, np.zeros(4)]])
    read = read_mesh(meshio.Mesh(points, [("triangle", mesh.t.T + 1)]))
    left = Box((0, 0), (0, 1))
    model = ElasticModel(read, E, NU, plane="stress").fix(left)
    np.testing.assert_array_equal(model.mesh.p, mesh.p)
    expected = ElasticModel(mesh, E, NU, plane="stress").fix(left).reduced_model([3])
    np.testing.assert_allclose(
        model.reduced_model([3]).flexibility, expected.flexibility, rtol=1e-12
    )


def test_unreadable_and_unsupported_meshes_are_clear_errors(tmp_path):
    bad = tmp_path / "bad.vtk"
    bad.write_text("not a mesh")
    with pytest.raises(FileFormatError, match="could not be read by meshio"):
        read_mesh(bad)
    with pytest.raises(FileFormatError, match="does not exist"):
        read_mesh(tmp_path / "missing.msh")
    lines = meshio.Mesh(np.eye(3), [("line", np.array([[0, 1], [1, 2]]))])
    with pytest.raises(UnsupportedProblemError, match="MeshLine1 is not supported"):
        read_mesh(lines)


def test_bar_picks_nearly_square_cells():
    flat = bar(2.0, 0.1, across=3)
    assert flat.t.shape[1] == 60 * 3 and flat.p[1].max() == 0.1
    solid = bar(2.0, 0.1, 0.2, across=2, cell="tet")
    assert isinstance(solid, skfem.MeshTet) and np.allclose(solid.p.max(axis=1), [2.0, 0.2, 0.1])


@pytest.mark.parametrize(
    "call,message",
    [
        (
            lambda: ElasticModel(plate(1, 1, 1, 1), -1.0, NU, plane="stress"),
            "young must be a positive",
        ),
        (lambda: ElasticModel(plate(1, 1, 1, 1), E, 0.5, plane="stress"), r"poisson must lie in"),
        (lambda: ElasticModel(plate(1, 1, 1, 1), E, NU), "plane must be 'stress' or 'strain'"),
        (lambda: ElasticModel(block(1, 1, 1, 1, 1, 1), E, NU, thickness=0.1), "2D meshes only"),
        (lambda: ElasticModel(plate(1, 1, 1, 1), E, NU, plane="stress", order=3), "order must be"),
        (lambda: plate(1.0, 0.0, 2, 2), "width must be a positive"),
        (lambda: block(1, 1, 1, 1, 1, 1, cell="tri"), "cell must be one of tet, hex"),
        (
            lambda: ElasticModel(plate(1, 1, 1, 1), E, NU, plane="stress").fix("side"),
            "no boundary named 'side'",
        ),
        (
            lambda: ElasticModel(plate(1, 1, 1, 1), E, NU, plane="stress").fix(
                Box((0, 0, 0), (1, 1, 1))
            ),
            "Box has 3 coordinates but the mesh is 2-D",
        ),
        (
            lambda: ElasticModel(plate(1, 1, 1, 1), E, NU, plane="stress").fix("left", [2]),
            "components must be distinct directions in 0..1",
        ),
        (
            lambda: ElasticModel(plate(1, 1, 1, 1), E, NU, plane="stress").fix(lambda x: x[0]),
            "selector function must return 8 booleans",
        ),
        (
            lambda: (
                ElasticModel(plate(1, 1, 1, 1), E, NU, plane="stress").fix("left").solve(np.ones(8))
            ),
            "loads must be 2-D",
        ),
        (
            lambda: (
                ElasticModel(plate(1, 1, 1, 1), E, NU, plane="stress")
                .fix("left")
                .solve(tractions={"top": (1.0, 2.0, 3.0)})
            ),
            r"tractions\['top'\] must have shape \(2,\)",
        ),
        (
            lambda: (
                ElasticModel(plate(1, 1, 1, 1), E, NU, plane="stress")
                .fix("left")
                .reduced_model([0])
            ),
            "u_x of node 0 at \\(0, 0\\) is fixed",
        ),
        (
            lambda: ElasticModel(plate(1, 1, 1, 1), E, NU, plane="stress").reduced_model([1, 1]),
            "nodes must be distinct",
        ),
        (
            lambda: (
                ElasticModel(plate(1, 1, 1, 1), E, NU, plane="stress")
                .fix("left")
                .solve(tractions=[("top", (1.0, 2.0))])
            ),
            "tractions must be a dict",
        ),
        (lambda: read_mesh(3), "a file path or a meshio.Mesh"),
    ],
)
def test_bad_input_names_the_argument(call, message):
    with pytest.raises(InvalidInputError, match=message):
        call()


def test_second_order_cells_are_taken_with_straight_edges(tmp_path):
    """10-node tetrahedra read from a file: the same answers as the 4-node mesh with order=2."""
    linear = block(1.0, 0.4, 0.4, 4, 2, 2, cell="tet")
    quadratic = skfem.MeshTet2.from_mesh(linear)  # mid-side nodes added
    path = tmp_path / "tet10.msh"
    quadratic.save(path, file_format="gmsh")
    read = read_mesh(path)
    assert isinstance(read, skfem.MeshTet2)
    models = [
        ElasticModel(m, E, NU, order=2).fix(Box((0, 0, 0), (0, 0.4, 0.4))) for m in (linear, read)
    ]
    assert models[1].n_nodes == linear.p.shape[1]
    tip = [
        models[0].select_nodes([[1.0, 0.4, 0.4]]).nodes,
        models[1].select_nodes([[1.0, 0.4, 0.4]]).nodes,
    ]
    np.testing.assert_allclose(
        models[1].reduced_model(tip[1]).flexibility,
        models[0].reduced_model(tip[0]).flexibility,
        rtol=1e-10,
    )

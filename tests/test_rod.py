"""The Euler-Bernoulli frame against beam theory, and the rod over an obstacle against full FE
contact.

Tolerances: Euler-Bernoulli elements are exact at the nodes for nodal loads, so beam theory is met
to round-off (1e-9 relative, the sparse solve of a stiffness whose entries span 12 decades). The
reduced model with contacts at the computational nodes is the same problem as the full mesh with
contacts at those nodes, so the two agree to the solvers' accuracy (1e-8 relative). Against the
full mesh with contacts at every node the method's bar is 0.3 %.
"""

import json
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

from contactqp.applications.rod import (
    ABSOLUTE_BELOW,
    DEFAULT_CASES,
    MAX_ELEMENTS,
    Rod,
    RodLoad,
    RodLoadCase,
    compare,
    deviations,
    solve_full,
)
from contactqp.compliance.beam import Frame2D, frame_element_stiffness
from contactqp.core.status import ContactStatus
from contactqp.errors import InvalidInputError, RigidBodyModeError

ROOT = Path(__file__).resolve().parents[1]
E, A, L = 1e12, 0.2e-6, 0.04
I_z = A**2 / (4 * np.pi)  # second moment of area of a circular section (A = pi r^2)


def cantilever(n_elements=8, angle=0.0):
    """Rod from the origin at ``angle``, clamped at its far end."""
    s = np.linspace(0.0, L, n_elements + 1)
    nodes = np.column_stack([s * np.cos(angle), s * np.sin(angle)])
    elements = np.column_stack([np.arange(n_elements), np.arange(1, n_elements + 1)])
    return Frame2D(nodes, elements, E, A, I_z, fixed={-1: "xyr"})


def test_cantilever_tip_load_meets_beam_theory_at_every_node():
    frame = cantilever(8)
    P = 0.3
    u = frame.displacements(frame.load_vector([(0, 0.0, -P)]))
    a = L - frame.coordinates[:, 0]  # distance from the clamp
    np.testing.assert_allclose(u[:, 1], -P * a**2 * (3 * L - a) / (6 * E * I_z), rtol=1e-9, atol=0)
    assert u[0, 1] == pytest.approx(-P * L**3 / (3 * E * I_z), rel=1e-9)
    np.testing.assert_allclose(u[:, 2], P * a * (2 * L - a) / (2 * E * I_z), rtol=1e-9, atol=0)
    assert u[0, 2] == pytest.approx(P * L**2 / (2 * E * I_z), rel=1e-9)
    np.testing.assert_array_equal(u[-1], 0.0)


def test_axial_load_stretches_by_PL_over_EA():
    frame = cantilever(5)
    u = frame.displacements(frame.load_vector([(0, -2.0, 0.0)]))
    a = L - frame.coordinates[:, 0]
    np.testing.assert_allclose(u[:, 0], -2.0 * a / (E * A), rtol=1e-9, atol=0)
    np.testing.assert_allclose(u[:, 1:], 0.0, atol=1e-20)


def test_inclined_cantilever_is_the_rotated_one():
    angle = np.radians(30.0)
    frame = cantilever(4, angle)
    c, s = np.cos(angle), np.sin(angle)
    axial, lateral = 1.5, -0.2  # along the rod and across it
    load = (0, axial * c - lateral * s, axial * s + lateral * c)
    u = frame.displacements(frame.load_vector([load]))[0]
    along, across = u[0] * c + u[1] * s, -u[0] * s + u[1] * c
    assert along == pytest.approx(axial * L / (E * A), rel=1e-9)  # pushed towards the clamp
    assert across == pytest.approx(lateral * L**3 / (3 * E * I_z), rel=1e-9)
    element = frame_element_stiffness([0, 0], [c, s], E, A, I_z)
    assert np.allclose(element, element.T) and np.allclose(element @ [c, s, 0, c, s, 0], 0)


def test_condensed_flexibility_is_the_cantilever_influence_function():
    frame = cantilever(16)
    nodes = [0, 4, 10]
    R = frame.compliance(nodes, "xy")
    a = L - frame.coordinates[nodes, 0]
    near, far = np.minimum.outer(a, a), np.maximum.outer(a, a)
    np.testing.assert_allclose(R[1::2, 1::2], near**2 * (3 * far - near) / (6 * E * I_z), rtol=1e-9)
    np.testing.assert_allclose(R[0::2, 0::2], near / (E * A), rtol=1e-9)
    np.testing.assert_allclose(R[0::2, 1::2], 0.0, atol=1e-12 * np.abs(R).max())


def test_frame_errors_name_the_problem():
    nodes = [[0, 0], [1, 0]]
    with pytest.raises(RigidBodyModeError, match="rigid-body modes"):
        Frame2D(nodes, [[0, 1]], E, A, I_z, fixed={0: "xy"}).compliance([1])
    with pytest.raises(InvalidInputError, match="letters among"):
        Frame2D(nodes, [[0, 1]], E, A, I_z, fixed={0: "xz"})
    with pytest.raises(InvalidInputError, match="young"):
        Frame2D(nodes, [[0, 1]], -E, A, I_z)
    with pytest.raises(InvalidInputError, match="is fixed"):
        Frame2D(nodes, [[0, 1]], E, A, I_z, fixed={0: "xyr"}).load_vector([(0, 1.0, 0.0)])
    with pytest.raises(InvalidInputError, match="zero length"):
        Frame2D([[0, 0], [0, 0]], [[0, 1]], E, A, I_z)


@pytest.fixture(scope="module")
def table():
    return compare(Rod(), repeat=1)


def test_one_force_contact_force_is_the_propped_cantilever(table):
    """Force P at distance a from the clamp, tip held on the inclined obstacle (compatibility)."""
    rod = Rod()
    comparison = table[0]
    (load,) = comparison.case.loads
    a = rod.length - load.x
    free_tip = -load.fy * a**2 * (3 * L - a) / (6 * E * I_z)
    # a normal force lam pushes the tip by lam c L^3/(3EI) up and lam s L/(EA) along the rod;
    # the tip on the obstacle, n . u = gap_free c with n = -(s, c), divided by c:
    # free_tip - lam (c L^3/(3EI) + (s^2 / c) L/(EA)) = gap_free, and s^2 / c = s slope
    c, s = 1 / np.hypot(1, rod.slope), rod.slope / np.hypot(1, rod.slope)
    lam = (free_tip - rod.gap_free) / (c * L**3 / (3 * E * I_z) + s * rod.slope * L / (E * A))
    assert comparison.reduced.forces[0] == pytest.approx(lam, rel=1e-8)
    # the axial term (3e-7 of lam) is resolved: without it the force is off by more than 1e-8
    bending_only = (free_tip - rod.gap_free) / (c * L**3 / (3 * E * I_z))
    assert comparison.reduced.forces[0] != pytest.approx(bending_only, rel=1e-8)
    assert comparison.reference.forces[0] == pytest.approx(lam, rel=1e-8)
    np.testing.assert_array_equal(comparison.reduced.forces[1:], 0.0)


def test_reduced_model_is_exact_against_contact_at_the_same_nodes(table):
    rod = Rod()
    for comparison in table:
        assert comparison.reduced.success
        assert comparison.max_eps_same_nodes < 1e-6  # percent: 1e-8 relative
        np.testing.assert_allclose(
            comparison.reduced.forces, comparison.same_nodes.forces, rtol=1e-8, atol=1e-10
        )
        u = comparison.same_nodes.displacements[rod.node_indices, :2]
        np.testing.assert_allclose(
            comparison.reduced.displacements.reshape(-1, 2),
            u,
            rtol=1e-8,
            atol=1e-8 * np.abs(u).max(),
        )


def test_method_bar_against_contact_at_every_mesh_node(table):
    rod = Rod()
    for comparison in table:
        assert comparison.max_eps <= 0.3
        touching = comparison.reference.contact_nodes[comparison.reference.forces > 0]
        assert touching.size and set(touching) <= set(rod.node_indices)
        assert comparison.max_penetration < 1e-8 * rod.gap_free  # round-off at the closed end
        assert 0 < comparison.t_reduced and 0 < comparison.t_full
        # the free end closes and the rest of the rod stays open: part of the rod in contact
        closed = comparison.reduced.contact_status == ContactStatus.CLOSED
        assert closed[0] and not closed[1:].any()


def test_contact_between_nodes_is_seen_and_breaks_the_bar():
    """Obstacle reversed (5 mm under the free end): the rod touches near 7 mm, between nodes."""
    rod = Rod(gap_free=5e-3, gap_clamped=1e-3)
    case = RodLoadCase(
        "between nodes",
        (
            RodLoad(0.0, 0.0, -1.0),
            RodLoad(0.01, 0.0, -4.0),
            RodLoad(0.02, 0.0, -4.0),
            RodLoad(0.03, 0.0, -4.0),
        ),
    )
    (comparison,) = compare(rod, [case], repeat=1)
    touching = comparison.reference.contact_nodes[comparison.reference.forces > 0]
    assert not set(touching) <= set(rod.node_indices)
    assert comparison.max_penetration > 1e-6
    assert comparison.max_eps > 0.3
    assert comparison.max_eps_same_nodes < 1e-6


def test_deviations_switch_to_absolute_below_the_floor():
    eps, absolute = deviations([1.01, 2e-9], [1.0, 1e-9], floor=ABSOLUTE_BELOW)
    np.testing.assert_allclose(eps, [1.0, 1e-9])
    np.testing.assert_array_equal(absolute, [False, True])


def test_rod_rejects_nodes_off_the_mesh_and_loads_off_the_nodes():
    with pytest.raises(InvalidInputError, match="not a free mesh node"):
        Rod(n_elements=12)
    with pytest.raises(InvalidInputError, match="not on a computational node"):
        compare(Rod(), [RodLoadCase("off", (RodLoad(0.012, 0.0, -1.0),))], repeat=1)


def run(*args):
    return subprocess.run(
        [sys.executable, "-m", "contactqp.cli", "rod", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )


def test_cli_json_schema_and_values():
    proc = run("--json")
    assert proc.returncode == 0, proc.stderr
    record = json.loads(proc.stdout)
    assert record["clamped_end"] == "right"
    assert [c["name"] for c in record["cases"]] == [c.name for c in DEFAULT_CASES]
    for case, expected in zip(record["cases"], DEFAULT_CASES, strict=True):
        assert {"name", "loads", "nodes", "max_eps", "t_reduced", "t_full"} <= set(case)
        assert case["loads"] == [
            {"x": load.x, "fx": load.fx, "fy": load.fy} for load in expected.loads
        ]
        assert len(case["nodes"]) == 8
        largest = max(max(abs(n["ux_ref"]), abs(n["uy_ref"])) for n in case["nodes"])
        for node in case["nodes"]:
            assert {"x", "gap", "ux", "uy", "ux_ref", "uy_ref", "eps_x", "eps_y"} <= set(node)
            assert node["gap"] == pytest.approx(1e-3 + 0.1 * node["x"], rel=1e-12)
            for axis in "xy":
                value, ref = node[f"u{axis}"], node[f"u{axis}_ref"]
                absolute = abs(ref) < ABSOLUTE_BELOW * largest
                assert node[f"eps_{axis}_absolute"] == absolute
                expected_eps = abs(value - ref) if absolute else 100 * abs(value - ref) / abs(ref)
                assert node[f"eps_{axis}"] == pytest.approx(expected_eps, rel=1e-9, abs=1e-30)
        assert 0 <= case["max_eps"] <= 0.3
        assert case["t_reduced"] > 0 and case["t_full"] > 0
        assert case["nodes"][0]["uy"] == pytest.approx(-1e-3, rel=1e-5)  # the free end touches


def test_cli_writes_a_figure_and_a_readable_vtu(tmp_path):
    png, vtu = tmp_path / "rod.png", tmp_path / "out" / "rod.vtu"
    proc = run("--plot", str(png), "--vtu", str(vtu))
    assert proc.returncode == 0, proc.stderr
    assert "several forces" in proc.stdout and "eps_y" in proc.stdout
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    mesh = meshio.read(vtu)
    rod = Rod()
    assert mesh.points.shape == (rod.n_elements + 1, 3)
    assert mesh.cells[0].type == "line" and len(mesh.cells[0].data) == rod.n_elements
    np.testing.assert_allclose(mesh.point_data["gap"], rod.gap(mesh.points[:, 0]))
    reference = compare(rod, DEFAULT_CASES[:1], repeat=1)[0]
    np.testing.assert_allclose(
        mesh.point_data["one_force_displacement"][:, :2],
        reference.reference.displacements[:, :2],
        rtol=1e-9,
        atol=1e-15,
    )
    force = mesh.point_data["one_force_contact_force_reduced"]
    assert force[0, 1] == pytest.approx(reference.reduced.forces[0] / np.hypot(1, rod.slope))
    np.testing.assert_array_equal(force[1:], 0.0)


@pytest.mark.parametrize(
    "args",
    [
        ["--elements", "12"],
        ["--elements", "0"],
        ["--elements", "4000"],
        ["--elements", "1608"],
        ["--vtu", "/proc/forbidden/rod.vtu"],
    ],
)
def test_cli_bad_input_is_one_line_and_exit_2(args):
    proc = run(*args)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("contactqp: error:"), proc.stderr


def test_displacements_of_a_frame_free_to_move_raise_instead_of_returning_garbage():
    """Only x and y held at one end: the rod can turn about it; no finite answer exists."""
    frame = Frame2D([[0, 0], [L, 0]], [[0, 1]], E, A, I_z, fixed={0: "xy"})
    with pytest.raises(RigidBodyModeError, match="rigid-body modes"):
        frame.displacements(frame.load_vector([(1, 0.0, 1.0)]))
    with pytest.raises(InvalidInputError, match="load_vector must be 4 finite values"):
        frame.displacements([1.0, 2.0])


def test_a_fractional_node_is_refused_not_truncated():
    """Node 1.5 used to load (and condense) node 1 without a word."""
    frame = cantilever(4)
    with pytest.raises(InvalidInputError, match="whole node index, got 1.5"):
        frame.load_vector([(1.5, 0.0, -1.0)])
    with pytest.raises(InvalidInputError, match="whole node index, got 1.5"):
        frame.compliance([1.5])
    np.testing.assert_array_equal(
        frame.load_vector(np.array([[1.0, 0.0, -1.0]])), frame.load_vector([(1, 0.0, -1.0)])
    )


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Rod(length="40 mm"), "length must be finite and > 0"),
        (lambda: Rod(n_elements=None), "n_elements must be a whole number"),
        (lambda: Rod(nodes=("a",)), "nodes must be a non-empty list"),
        (lambda: Frame2D.straight("1 m", 4, E, A, I_z), "length must be > 0"),
        (lambda: Frame2D([[0, 0], [1, 0]], [[0, 1]], E, A, I_z, fixed={"a": "xy"}), "fixed node"),
        (lambda: Frame2D([[0, 0], [1, 0]], [[0, 1]], E, A, I_z, fixed={0: 1}), "letters among"),
        (lambda: cantilever(2).load_vector([5]), "a load must be"),
        (lambda: cantilever(2).index(-1, "ux"), "outside 0..2"),
    ],
)
def test_bad_rod_and_frame_arguments_raise_invalid_input(make, message):
    with pytest.raises(InvalidInputError, match=message):
        make()


@pytest.mark.parametrize("n_elements", [240, 400, 1600])
def test_the_reference_solves_on_every_mesh_offered(n_elements):
    """Was: "the polished reference violates contact" from 240 elements (Clarabel stops short
    with a wrong or empty active set on the ill-conditioned fine frames and one KKT solve on it
    penetrates by 2 to 3 mm). The exact active-set polish corrects the set: the contact force
    at the free end is the coarse mesh's (nodal loads: exact at the nodes) to round-off, which
    grows like n_elements^4."""
    coarse = solve_full(Rod(), DEFAULT_CASES[1])
    fine = solve_full(Rod(n_elements=n_elements), DEFAULT_CASES[1])
    assert np.flatnonzero(fine.forces).tolist() == [0]
    assert fine.forces[0] == pytest.approx(coarse.forces[0], rel=1e-3 if n_elements > 400 else 1e-5)


def test_meshes_beyond_the_finest_offered_are_refused_saying_why():
    with pytest.raises(
        InvalidInputError,
        match=f"^n_elements must be at most {MAX_ELEMENTS}, "
        "got 4000: the frame's stiffness is ill-cond",
    ):
        Rod(n_elements=4000)
    proc = run("--help")
    assert f"up to {MAX_ELEMENTS}" in " ".join(proc.stdout.split())

"""Write the part files of ``blocks.toml`` and ``blocks-ansys.toml`` (two 3-D elastic blocks).

Usage::

    python examples/assemblies/make_blocks.py [DIR]

``DIR`` defaults to this script's directory; elsewhere, the two assembly files are copied
there too, so that ``DIR`` holds everything ``contactqp assembly DIR/blocks.toml`` reads.
It needs ``contactqp[fem]`` (scikit-fem, meshio) and, for the ANSYS file, the project's test
suite (``tests/fe_files.py`` writes ``.full`` files; no ANSYS runs here).

The parts are the blocks of :mod:`contactqp.applications.riveting_friction`: a lower part
100 x 40 x 2 mm and an upper part 100 x 40 x 1.2 mm lying on it (``2 <= z <= 3.2`` mm),
aluminium, each one layer of 10 x 4 hexahedral cells split into tetrahedra (quadratic elements
in the assembly files, ``order = 2``), both clamped at their short end faces ``x = 0`` and
``x = 100`` mm. Files written (SI units, metres):

``blocks-lower.vtu``
    The lower mesh, with its faces (``left``, ``right``, ``front``, ``back``, ``bottom``,
    ``top``) as cell sets: ``blocks.toml`` fixes it by face name.
``blocks-upper.msh``
    The upper mesh (Gmsh 4.1, no named faces): ``blocks.toml`` fixes it by boxes.
``blocks-gaps.csv``
    A measured gap cloud ``x, y, gap`` on a 9 x 6 grid, not at the pairs: a bow along x
    (0.2 mm at mid-length) and a tilt along y (0.05 mm across).
``blocks-lower.full`` and ``blocks-lower-nodes.csv``
    The lower part as an ANSYS full file (the stiffness of every freedom, the clamped ones
    flagged as constrained) and its nodes' coordinates (``node, x, y, z``), read by
    ``blocks-ansys.toml``.

The functions below (``lower_body``, ``upper_body``, ``interface_nodes``, ...) build the same
parts in Python; the tests use them as the reference.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ASSEMBLY_FILES = ("blocks.toml", "blocks-ansys.toml")

LENGTH, WIDTH = 0.100, 0.040  # m
LOWER_THICKNESS, UPPER_THICKNESS = 0.002, 0.0012  # m
CELLS = (10, 4)  # along x and y; one cell through the thickness
YOUNG, POISSON = 70e9, 0.33  # Pa
ORDER = 2  # quadratic tetrahedra: linear ones lock in bending
#: Interface nodes: the facing surface off the clamped ends (x strictly between 0 and L).
INTERFACE_X = (0.005, 0.095)


def measured_gap(x, y):
    """The measured gap (m) at ``(x, y)``: a bow along x and a tilt along y."""
    return 2e-4 * np.sin(np.pi * np.asarray(x) / LENGTH) + 5e-5 * np.asarray(y) / WIDTH


def lower_mesh():
    """The lower block's tetrahedral mesh, ``[0, L] x [0, W] x [0, t_l]``, with named faces."""
    from contactqp.compliance.fem import block

    return block(LENGTH, WIDTH, LOWER_THICKNESS, *CELLS, 1, cell="tet")


def upper_mesh():
    """The upper block's mesh, lying on the lower one (``t_l <= z <= t_l + t_u``)."""
    from contactqp.compliance.fem import block

    mesh = block(LENGTH, WIDTH, UPPER_THICKNESS, *CELLS, 1, cell="tet")
    return mesh.translated([0.0, 0.0, LOWER_THICKNESS])


def end_boxes(bottom: float, top: float):
    """The two clamped end faces ``x = 0`` and ``x = L`` of a block, as boxes."""
    from contactqp.compliance.fem import Box

    return (
        Box([0.0, 0.0, bottom], [0.0, WIDTH, top]),
        Box([LENGTH, 0.0, bottom], [LENGTH, WIDTH, top]),
    )


def interface_box():
    """The facing surfaces ``z = t_l`` off the clamped ends, as a box."""
    from contactqp.compliance.fem import Box

    return Box([INTERFACE_X[0], 0.0, LOWER_THICKNESS], [INTERFACE_X[1], WIDTH, LOWER_THICKNESS])


def lower_body():
    """The lower part's finite-element model, clamped at both ends."""
    from contactqp.compliance.fem import ElasticModel

    return ElasticModel(lower_mesh(), YOUNG, POISSON, order=ORDER).fix("left").fix("right")


def upper_body():
    """The upper part's finite-element model, clamped at both ends."""
    from contactqp.compliance.fem import ElasticModel

    body = ElasticModel(upper_mesh(), YOUNG, POISSON, order=ORDER)
    for box in end_boxes(LOWER_THICKNESS, LOWER_THICKNESS + UPPER_THICKNESS):
        body.fix(box)
    return body


def interface_nodes(body) -> np.ndarray:
    """The body's mesh nodes on the interface (by index)."""
    return body.select_nodes(where=interface_box()).nodes


def write_meshes(directory: Path) -> None:
    import meshio
    from skfem.io.meshio import to_meshio

    # the .vtu keeps the generated faces as cell sets (read back as face names)
    meshio.write(directory / "blocks-lower.vtu", to_meshio(lower_mesh()))
    meshio.write(directory / "blocks-upper.msh", to_meshio(upper_mesh()), file_format="gmsh")


def write_gap_cloud(directory: Path) -> None:
    x, y = np.meshgrid(np.linspace(0.0, LENGTH, 9), np.linspace(0.0, WIDTH, 6))
    x, y = x.ravel(), y.ravel()
    table = np.column_stack([x, y, measured_gap(x, y)])
    np.savetxt(directory / "blocks-gaps.csv", table, delimiter=",", header="x,y,gap", comments="")


def ansys_storage(body) -> tuple[np.ndarray, np.ndarray]:
    """``(freedoms, numbers)``: the body's freedoms in ``.full`` storage order (node by node,
    ``UX, UY, UZ``) and each stored node's number: mesh vertex ``v`` is node ``v + 1``, the
    quadratic elements' mid-side points follow."""
    basis = body.basis
    vertices = basis.nodal_dofs  # (3, n_vertices)
    others = np.setdiff1d(np.arange(basis.N), vertices.ravel())
    # the other freedoms come in (x, y, z) triples at one point each
    locations = basis.doflocs[:, others].T
    order = np.lexsort((body._component[others], *locations.T[::-1]))
    others = others[order].reshape(-1, 3)
    freedoms = np.concatenate([vertices.T.ravel(), others.ravel()])
    numbers = np.arange(1, vertices.shape[1] + len(others) + 1)
    return freedoms, numbers


def write_ansys_part(directory: Path) -> None:
    """``blocks-lower.full`` and ``blocks-lower-nodes.csv`` (the interface nodes only)."""
    sys.path.insert(0, str(HERE.parents[1] / "tests"))
    try:
        from fe_files import write_ansys_full
    finally:
        sys.path.pop(0)
    body = lower_body()
    freedoms, numbers = ansys_storage(body)
    position = np.empty(body.basis.N, dtype=int)
    position[freedoms] = np.arange(freedoms.size)
    stiffness = body.stiffness[freedoms][:, freedoms]
    write_ansys_full(
        directory / "blocks-lower.full",
        stiffness,
        numbers,
        dofs=(1, 2, 3),
        constrained=np.sort(position[body.fixed]),
    )
    nodes = interface_nodes(body)
    table = np.column_stack([nodes + 1, body.mesh.p[:, nodes].T])
    np.savetxt(
        directory / "blocks-lower-nodes.csv",
        table,
        delimiter=",",
        header="node,x,y,z",
        comments="",
        fmt=["%d", "%.17g", "%.17g", "%.17g"],
    )


def main(directory: str | Path = HERE) -> Path:
    """Write every part file into ``directory`` (made if missing); returns it."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    write_meshes(directory)
    write_gap_cloud(directory)
    write_ansys_part(directory)
    if directory.resolve() != HERE:
        for name in ASSEMBLY_FILES:
            shutil.copy(HERE / name, directory / name)
    return directory


if __name__ == "__main__":
    written = main(sys.argv[1] if len(sys.argv) > 1 else HERE)
    print(f"wrote the blocks' part files in {written}")

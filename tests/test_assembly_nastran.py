"""Assembly files with NASTRAN parts: the upper block of :mod:`test_assembly_file` written as an
OP4 matrix (binary dense, ASCII sparse; its stiffness or its interface flexibility) and as a DMIG
stiffness with its GRID cards parses to the FE model's own condensed flexibility, and the
assembly built from each solves the fastening sequence of the MatrixMarket source.

pyNastran holds numpy < 2: these tests are marked ``nastran`` and run in ``.venv-nastran``
(``make test`` runs them there).
"""

from __future__ import annotations

import numpy as np
import pytest

import test_assembly_file
from fe_files import write_op4_binary
from test_assembly_file import assert_close, base, read, upper_body

#: The parts of test_assembly_file written to files (its fixture, run once for this module).
files = test_assembly_file.files

pytestmark = pytest.mark.nastran

#: The same model read from two files differs by the rounding of each reader's condensation
#: (a Cholesky factorisation of the same stiffness): 1e-9 relative to the largest force.
SAME = 1e-9
INTERFERENCE = 2e-7  # m, of the blocks before fastening


@pytest.fixture(scope="module")
def nastran_files(files):
    """The upper block's stiffness and flexibility as OP4 and DMIG files beside the others."""
    import scipy.sparse as sp
    from pyNastran.bdf.bdf import BDF
    from pyNastran.op2.result_objects.matrix import Matrix
    from pyNastran.op4.op4 import write_op4

    folder = files["folder"]
    upper = upper_body()
    eq = upper.basis.nodal_dofs.T.ravel()  # node by node: UX, UY, UZ
    K = upper.stiffness[eq][:, eq]
    write_op4_binary(folder / "upper_K.op4", {"KAA": K.toarray()})
    write_op4(
        str(folder / "upper_K_ascii.op4"),
        {"KAA": Matrix("KAA", 6, data=sp.coo_matrix(K))},
        is_binary=False,
        precision="double",
    )
    write_op4_binary(folder / "upper_R.op4", {"RFLEX": files["upper_truth"]})
    bdf = BDF(debug=None)
    numbers = np.arange(upper.n_nodes) + 101
    for node, number in enumerate(numbers):
        bdf.add_grid(int(number), upper.mesh.p[:, node].tolist())
    labels = [(int(number), c) for number in numbers for c in (1, 2, 3)]
    lower = sp.tril(sp.coo_matrix(K))  # a symmetric DMIG (form 6) holds one triangle
    bdf.add_dmig(
        "KAAX",
        6,
        2,
        2,
        0,
        None,
        [labels[j] for j in lower.col],
        [labels[i] for i in lower.row],
        lower.data.tolist(),
    )
    bdf.write_bdf(str(folder / "upper.bdf"), size=16, is_double=True)
    fixed = [list(labels[i]) for i in files["upper_fixed"]]
    return {"dmig_fixed": fixed}


def nastran_part(files, nastran_files, source):
    """The ``[parts.upper]`` table of ``source``."""
    part = {"type": "matrix", "coordinates": "upper_index_nodes.csv"}
    op4_stiffness = {
        "kind": "stiffness",
        "dofs_per_node": 3,
        "freedoms": files["upper_interface_freedoms"].tolist(),
        "fixed": files["upper_fixed"].tolist(),
    }
    if source == "op4-binary-stiffness":
        part.update(compliance="upper_K.op4", **op4_stiffness)
    elif source == "op4-ascii-sparse-stiffness":
        part.update(compliance="upper_K_ascii.op4", matrix="KAA", **op4_stiffness)
    elif source == "op4-flexibility":
        part.update(compliance="upper_R.op4", kind="flexibility", dofs_per_node=3)
    else:
        part.update(
            compliance="upper.bdf",
            matrix="KAAX",
            kind="stiffness",
            nodes=files["upper_numbers"].tolist(),
            components=[1, 2, 3],
            fixed=nastran_files["dmig_fixed"],
            coordinates="upper_nodes.csv",
        )
    return part


SOURCES = ["op4-binary-stiffness", "op4-ascii-sparse-stiffness", "op4-flexibility", "dmig"]


@pytest.mark.parametrize("source", SOURCES)
def test_nastran_parts_give_the_fe_flexibility(files, nastran_files, source):
    doc = base(files)
    doc["parts"]["upper"] = nastran_part(files, nastran_files, source)
    parsed = read(files, doc, f"assembly-{source}.toml")
    assert_close(parsed.parts[1].model.flexibility, files["upper_truth"])
    assert_close(parsed.parts[1].coordinates, files["upper_coordinates"])


def _solved(files, upper, name):
    """The fastening sequence of :func:`test_assembly_file.base` with ``upper`` as the upper
    part, the blocks in a 0.2 um interference (so that contacts carry force from the start),
    then a 50 N shear on the upper block and its removal."""
    doc = base(files)
    doc["parts"]["upper"] = upper
    doc["gaps"] = {"nominal": -INTERFERENCE}
    doc["loads"] = [{"label": "shear", "part": "upper", "force": [50.0, 0.0, 0.0]}]
    parsed = read(files, doc, name)
    return parsed.to_assembly().sequence(
        parsed.gaps, load_steps=parsed.load_steps, method=parsed.method, **parsed.options
    )


@pytest.mark.parametrize("source", SOURCES)
def test_nastran_parts_solve_the_matrix_market_assembly(files, nastran_files, source):
    """The fastening sequence (mu = 0.3) of the assembly with the NASTRAN part equals that of
    the same part read from MatrixMarket (its stiffness, condensed the same way)."""
    matrix_market = {
        "type": "matrix",
        "coordinates": "upper_index_nodes.csv",
        "compliance": "upper_K.mtx",
        "kind": "stiffness",
        "dofs_per_node": 3,
        "freedoms": files["upper_interface_freedoms"].tolist(),
        "fixed": files["upper_fixed"].tolist(),
    }
    reference = _solved(files, matrix_market, "assembly-mtx.toml")
    got = _solved(files, nastran_part(files, nastran_files, source), f"assembly-{source}.toml")
    assert reference.success and got.success
    assert len(got.stages) == 3  # the fastener, the shear, its removal
    assert np.max(np.abs(reference.stages[1].tangential_forces)) > 1.0  # friction carries it
    for a, b in zip(got.stages, reference.stages, strict=True):
        scale = np.max(np.abs(b.normal_forces))
        assert scale > 0
        for name in ("normal_forces", "tangential_forces", "fastener_forces"):
            np.testing.assert_allclose(
                getattr(a, name), getattr(b, name), rtol=0, atol=SAME * scale, err_msg=name
            )
        # closed contacts' gaps are rounding: measured against the interference
        np.testing.assert_allclose(a.gaps, b.gaps, rtol=0, atol=SAME * INTERFERENCE)

"""Importers: files written here (ANSYS .full, NASTRAN OP4 and DMIG, MatrixMarket, CSV) against
flexibilities known independently: the spring chain's closed form and the dense inverse of a
scikit-fem plane-strain stiffness.

Tolerance: 1e-10 relative to the largest flexibility term. The stiffness is stored in the files
to full double precision; condensation and the dense inverse differ by round-off of order
cond(K) * 1e-16 (cond ~ 1e4 here).
"""

import sys

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

from contactqp.compliance.importers import (
    READERS,
    dmig_matrix,
    load_compliance,
    op4_matrix,
    read_ansys_full,
    read_dmig,
    read_matrix_market,
    read_op4,
    read_unit_load_csv,
)
from contactqp.errors import (
    FileFormatError,
    InvalidInputError,
    MissingDependencyError,
    NotPositiveDefiniteError,
    RigidBodyModeError,
    UnsupportedProblemError,
)
from contactqp.io.problem_file import load_problem_file, read_array
from fe_files import write_ansys_full, write_op4_binary

# pyNastran holds numpy < 2: the tests that need it are marked `nastran` and run in their own
# environment (`make test` makes it; the main run deselects them), so they import it inside.
nastran = pytest.mark.nastran

RTOL = 1e-10
K_SPRING = 3.0e4  # N/m


def assert_flexibility(actual, expected):
    scale = np.abs(expected).max()
    np.testing.assert_allclose(actual, expected, rtol=0, atol=RTOL * scale)
    assert np.array_equal(actual, actual.T)  # reciprocity (Maxwell-Betti)


def chain_stiffness(n, fixed_first=True):
    """``n`` nodes joined by springs K_SPRING; node 0 tied to a wall by one more spring."""
    K = np.zeros((n, n))
    for i in range(n - 1):
        K[np.ix_([i, i + 1], [i, i + 1])] += K_SPRING * np.array([[1, -1], [-1, 1]])
    if fixed_first:
        K[0, 0] += K_SPRING
    return K


def chain_flexibility(chosen):
    """Closed form for :func:`chain_stiffness`: a unit load at j stretches the j + 1 springs
    between the wall and node j; node i moves by the springs it shares with that path."""
    chosen = np.asarray(chosen)
    return (np.minimum.outer(chosen, chosen) + 1) / K_SPRING


def make_plate(digits=None):
    """Plane-strain plate (aluminium, 100 x 20 mm, Q1), clamped on its left edge; its stiffness
    rounded to ``digits`` significant digits when given (what a file of that precision holds)."""
    from skfem import Basis, ElementQuad1, ElementVector, MeshQuad, asm
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh = MeshQuad.init_tensor(np.linspace(0, 0.1, 9), np.linspace(0, 0.02, 4))
    basis = Basis(mesh, ElementVector(ElementQuad1()))
    K = asm(linear_elasticity(*lame_parameters(70e9, 0.33)), basis).toarray()
    K = 0.5 * (K + K.T)  # the files store one triangle: make the truth exactly symmetric
    if digits is not None:
        K = np.vectorize(lambda v: float(f"{v:.{digits - 1}e}"))(K)
    n_nodes = mesh.p.shape[1]
    dof = basis.nodal_dofs.T  # (node, component) -> equation
    left = np.flatnonzero(np.isclose(mesh.p[0], 0.0))
    right = np.flatnonzero(np.isclose(mesh.p[0], 0.1))
    fixed = np.sort(dof[left].ravel())
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    inverse = np.zeros_like(K)
    inverse[np.ix_(free, free)] = np.linalg.inv(K[np.ix_(free, free)])
    inverse = 0.5 * (inverse + inverse.T)
    numbers = 1000 + 3 * np.arange(n_nodes)  # ANSYS / NASTRAN node numbers
    return dict(
        K=K,
        dof=dof,
        right=right,
        left=left,
        fixed=fixed,
        inverse=inverse,
        numbers=numbers,
        xy=mesh.p.T,
    )


@pytest.fixture(scope="module")
def plate():
    return make_plate()


@pytest.fixture(scope="module")
def plate10():
    """The plate as large-field bulk data holds it: 10 significant digits."""
    return make_plate(digits=10)


def plate_truth(plate, nodes, components):
    """Dense-inverse flexibility of ``components`` (0: x, 1: y) at the plate's ``nodes``."""
    eq = np.array([plate["dof"][p, c] for p in nodes for c in components])
    return plate["inverse"][np.ix_(eq, eq)]


# --------------------------------------------------------------------------------------------
# ANSYS .full


def write_plate_full(path, plate, storage):
    """The plate as a .full file, nodes stored in the order ``storage`` (indices)."""
    eq = plate["dof"][storage].ravel()  # node by node, UX then UY
    position = np.empty_like(eq)
    position[eq] = np.arange(eq.size)
    write_ansys_full(
        path,
        plate["K"][np.ix_(eq, eq)],
        plate["numbers"][storage],
        dofs=(1, 2),
        constrained=position[plate["fixed"]],
    )


@pytest.fixture(scope="module")
def plate_full(plate, tmp_path_factory):
    path = tmp_path_factory.mktemp("ansys") / "plate.full"
    storage = np.random.default_rng(3).permutation(len(plate["numbers"]))
    write_plate_full(path, plate, storage)
    return path


def test_ansys_full_spring_chain_is_the_closed_form(tmp_path):
    path = tmp_path / "chain.full"
    n = 12
    K = chain_stiffness(n + 1, fixed_first=False)  # node 0 is the wall, constrained in the file
    storage = np.arange(n + 1)[::-1]  # stored backwards: the reader sorts by node number
    write_ansys_full(path, K[np.ix_(storage, storage)], storage + 1, dofs=(1,), constrained=[n])
    chosen = np.array([2, 5, 11])
    model = read_ansys_full(path, chosen + 2, ["UX"])  # node numbers are index + 1
    assert model.given == "flexibility" and model.n_nodes == 3
    assert_flexibility(model.flexibility, chain_flexibility(chosen))


def test_ansys_full_plate_condensation_matches_the_dense_inverse(plate, plate_full):
    chosen = plate["right"][[3, 0, 2]]
    model = read_ansys_full(plate_full, plate["numbers"][chosen], ("UX", "UY"))
    assert model.n_freedoms == 6 and list(model.dofs_per_node) == [2, 2, 2]
    assert_flexibility(model.flexibility, plate_truth(plate, chosen, [0, 1]))


def test_ansys_full_components_in_the_order_asked(plate, plate_full):
    chosen = plate["right"][:2]
    model = read_ansys_full(plate_full, plate["numbers"][chosen], ("uy", "UX"))
    assert_flexibility(model.flexibility, plate_truth(plate, chosen, [1, 0]))


def test_ansys_full_every_free_node_gives_the_stiffness(plate, plate_full):
    free_nodes = np.setdiff1d(np.arange(len(plate["numbers"])), plate["left"])
    model = read_ansys_full(plate_full, plate["numbers"][free_nodes], ("UX", "UY"))
    assert model.given == "stiffness"
    eq = plate["dof"][free_nodes].ravel()
    np.testing.assert_array_equal(model.stiffness, plate["K"][np.ix_(eq, eq)])


def test_ansys_full_selection_errors_name_file_node_and_component(plate, plate_full):
    number = int(plate["numbers"][plate["right"][0]])
    with pytest.raises(InvalidInputError, match=r"plate\.full: node 7 is not in the file"):
        read_ansys_full(plate_full, [7])
    with pytest.raises(
        InvalidInputError,
        match=rf"node {number} UZ is not in the file "
        rf"\(node {number} has UX, UY\)",
    ):
        read_ansys_full(plate_full, [number], ("UX", "UZ"))
    clamped = int(plate["numbers"][plate["left"][0]])
    with pytest.raises(InvalidInputError, match=rf"node {clamped} UX is chosen but fixed"):
        read_ansys_full(plate_full, [clamped], ("UX",))
    with pytest.raises(InvalidInputError, match="nodes lists 1000 twice"):
        read_ansys_full(plate_full, [1000, 1000])


def test_ansys_full_unfixed_model_is_a_rigid_body_error(tmp_path):
    path = tmp_path / "free.full"
    write_ansys_full(path, chain_stiffness(4, fixed_first=False), [1, 2, 3, 4], dofs=(1,))
    with pytest.raises(RigidBodyModeError, match=r"free\.full: .*rigid-body modes"):
        read_ansys_full(path, [4], ["UX"])


def test_ansys_full_node_with_fewer_dofs_is_unsupported(tmp_path):
    path = tmp_path / "mixed.full"
    K = chain_stiffness(5) + np.eye(5)  # nodes 1, 2 with UX, UY; node 3 with UX only
    write_ansys_full(path, K, [1, 2, 3], dofs=(1, 2), counts=[2, 2, 1])
    np.testing.assert_allclose(
        read_ansys_full(path, [2], ["UX", "UY"]).flexibility, np.linalg.inv(K)[2:4, 2:4], rtol=1e-12
    )
    with pytest.raises(UnsupportedProblemError, match="node 3 has 1 of the file's 2 DOF kinds"):
        read_ansys_full(path, [3], ["UX"])


@pytest.mark.parametrize(
    "keep_bytes, part",
    [
        (0, "only 0 bytes"),
        (40, "only 40 bytes"),
        (430, "full-file header"),
        (1072, "DOF reference record"),
        (1200, "nodal equivalence table"),
        (1320, "DOF count record"),
        (1600, "constraint record"),
        (-4, "stiffness matrix"),
    ],
)
def test_ansys_full_truncated_file_is_a_format_error(plate_full, tmp_path, keep_bytes, part):
    """Every record is checked against the file's end before the reader's compiled code reads
    it (it would read past the end). Records of the plate file, in words: standard header
    0-102, full header 103-265, DOF references 266-270, nodes 271-309, DOF counts 310-348,
    constraints 349-423, stiffness from 424."""
    data = plate_full.read_bytes()
    path = tmp_path / "cut.full"
    path.write_bytes(data[:keep_bytes] if keep_bytes >= 0 else data[:keep_bytes])
    with pytest.raises(FileFormatError, match=rf"cut\.full: .*{part}"):
        read_ansys_full(path, [1000])


HEADER = 105  # first word of the full-file header's items (after the standard header record)


@pytest.mark.parametrize(
    "word, value, error, message",
    [
        (HEADER + 8, 0, FileFormatError, "holds no stiffness matrix"),  # ntermK
        (HEADER + 8, 10**6, FileFormatError, "stiffness matrix lies beyond its end"),
        (
            HEADER + 8,
            300,
            FileFormatError,
            "stiffness matrix has record lengths that do not add up",
        ),
        (424, 5, FileFormatError, "record lengths that do not add up to the 514 terms"),  # column 1
        (312, 3, FileFormatError, "DOF count record does not match the 72 equations"),  # node 1
        (HEADER + 35, 10**7, FileFormatError, "DOF count record lies beyond its end"),  # ptrDOF
        (0, 100 << 24, UnsupportedProblemError, "big-endian"),
    ],
)
def test_ansys_full_corrupt_file_is_a_clear_error(
    plate_full, tmp_path, word, value, error, message
):
    """Word offsets as in the truncation test; the stiffness starts at word 424."""
    words = np.fromfile(plate_full, dtype="<i4")
    assert words[HEADER + 18] == 424  # ptrSTF: the layout the offsets above assume
    words[word] = value
    path = tmp_path / "bad.full"
    words.tofile(path)
    with pytest.raises(error, match=rf"bad\.full: .*{message}"):
        read_ansys_full(path, [1000])


def test_ansys_full_foreign_files_are_format_errors(plate_full, tmp_path):
    text = tmp_path / "text.full"
    text.write_text("1.0, 2.0\n" * 200)
    with pytest.raises(FileFormatError, match=r"text\.full: not an ANSYS binary file"):
        read_ansys_full(text, [1])
    result = tmp_path / "result.full"
    data = bytearray(plate_full.read_bytes())
    data[8:12] = (12).to_bytes(4, "little")  # standard header item 1: a result file
    result.write_bytes(bytes(data))
    with pytest.raises(FileFormatError, match="another kind .*Result File.*not a full file"):
        read_ansys_full(result, [1000])
    with pytest.raises(FileFormatError, match="file not found"):
        read_ansys_full(tmp_path / "missing.full", [1])


# --------------------------------------------------------------------------------------------
# NASTRAN OP4


@nastran
@pytest.mark.parametrize("storage", ["ascii-dense", "ascii-sparse", "binary-dense"])
def test_op4_stiffness_condensed_is_the_closed_form(tmp_path, storage):
    from pyNastran.op2.result_objects.matrix import Matrix
    from pyNastran.op4.op4 import write_op4

    path = tmp_path / "k.op4"
    K = chain_stiffness(10)
    if storage == "binary-dense":
        write_op4_binary(path, {"KAA": K})
    else:
        data = sp.coo_matrix(K) if storage == "ascii-sparse" else K
        write_op4(
            str(path), {"KAA": Matrix("KAA", 6, data=data)}, is_binary=False, precision="double"
        )
    whole = read_op4(path, kind="stiffness")
    assert whole.given == "stiffness"
    np.testing.assert_array_equal(whole.stiffness, K)
    chosen = [9, 0, 4]
    assert_flexibility(
        read_op4(path, "KAA", kind="stiffness", freedoms=chosen).flexibility,
        chain_flexibility(chosen),
    )


@nastran
def test_op4_unconstrained_kgg_with_fixed_rows(tmp_path):
    path = tmp_path / "kgg.op4"
    write_op4_binary(path, {"KGG": chain_stiffness(8, fixed_first=False), "MGG": np.eye(8)})
    with pytest.raises(RigidBodyModeError, match=r"kgg\.op4: .*rigid-body"):
        read_op4(path, "KGG", kind="stiffness", freedoms=[3])
    model = read_op4(path, "KGG", kind="stiffness", freedoms=[3, 7], fixed=[0])
    assert_flexibility(model.flexibility, chain_flexibility([2, 6]))  # node 1 is the first spring


@nastran
def test_op4_flexibility_is_cut_to_the_freedoms(tmp_path, plate):
    path = tmp_path / "r.op4"
    R = plate_truth(plate, plate["right"], [0, 1])
    write_op4_binary(path, {"RFLEX": R})
    model = read_op4(path, kind="flexibility", freedoms=[2, 3, 6, 7], dofs_per_node=2)
    np.testing.assert_array_equal(model.flexibility, R[np.ix_([2, 3, 6, 7], [2, 3, 6, 7])])
    assert model.n_nodes == 2


@nastran
def test_op4_errors(tmp_path):
    from pyNastran.op2.result_objects.matrix import Matrix
    from pyNastran.op4.op4 import write_op4

    path = tmp_path / "two.op4"
    write_op4_binary(path, {"KAA": chain_stiffness(3), "MAA": np.eye(3)})
    with pytest.raises(
        InvalidInputError,
        match=r"two\.op4: the file holds 2 matrices "
        r"\(KAA, MAA\)",
    ):
        read_op4(path, kind="stiffness")
    with pytest.raises(InvalidInputError, match=r"no matrix named 'KGG' .*KAA, MAA"):
        op4_matrix(path, "KGG")
    with pytest.raises(InvalidInputError, match="fixed freedoms apply to a stiffness"):
        read_op4(path, "MAA", kind="flexibility", fixed=[0])
    with pytest.raises(InvalidInputError, match=r"the chosen freedoms must lie in 0\.\.2"):
        read_op4(path, "KAA", kind="stiffness", freedoms=[3])
    with pytest.raises(InvalidInputError, match="kind must be one of"):
        read_op4(path, "KAA", kind="compliance")
    rect = tmp_path / "rect.op4"
    write_op4_binary(rect, {"PHI": np.ones((4, 2))}, form=2)
    with pytest.raises(InvalidInputError, match=r"rect\.op4: the matrix must be square"):
        read_op4(rect, kind="flexibility")
    cut = tmp_path / "cut.op4"
    cut.write_bytes(path.read_bytes()[:60])
    with pytest.raises(FileFormatError, match=r"cut\.op4: not a readable OP4 file"):
        op4_matrix(cut)
    ascii_ = tmp_path / "ascii.op4"
    write_op4(
        str(ascii_),
        {"KAA": Matrix("KAA", 6, data=chain_stiffness(3))},
        is_binary=False,
        precision="double",
    )
    cut.write_text("\n".join(ascii_.read_text().splitlines()[:4]) + "\n")  # mid-matrix
    with pytest.raises(FileFormatError, match=r"cut\.op4: not a readable OP4 file"):
        op4_matrix(cut)
    text = tmp_path / "text.op4"
    text.write_text("this is not an OP4 file\n")
    with pytest.raises(FileFormatError, match=r"text\.op4: not a readable OP4 file"):
        op4_matrix(text)


# --------------------------------------------------------------------------------------------
# NASTRAN DMIG


def plate_dmig_model(plate, name="KAAX", nodes=None):
    """BDF with GRID cards and the plate's stiffness as a symmetric DMIG (lower triangle,
    components 1 and 2) of ``nodes`` (default: all, unconstrained)."""
    from pyNastran.bdf.bdf import BDF

    model = BDF(debug=None)
    for p, number in enumerate(plate["numbers"]):
        model.add_grid(int(number), [*plate["xy"][p], 0.0])
    nodes = np.arange(len(plate["numbers"])) if nodes is None else nodes
    eq = plate["dof"][nodes].ravel()
    labels = [(int(plate["numbers"][p]), c) for p in nodes for c in (1, 2)]
    K = sp.tril(sp.coo_matrix(plate["K"][np.ix_(eq, eq)]))
    GCj = [labels[j] for j in K.col]
    GCi = [labels[i] for i in K.row]
    model.add_dmig(name, 6, 2, 2, 0, None, GCj, GCi, K.data.tolist())
    return model


@nastran
def test_dmig_grids_and_components_with_fixed_freedoms(tmp_path, plate10):
    path = tmp_path / "plate.bdf"
    plate_dmig_model(plate10).write_bdf(str(path), size=16, is_double=True)
    chosen = plate10["right"][[1, 3]]
    fixed = [(int(plate10["numbers"][p]), c) for p in plate10["left"] for c in (1, 2)]
    model = read_dmig(
        path, "KAAX", plate10["numbers"][chosen], (2, 1), kind="stiffness", fixed=fixed
    )
    assert_flexibility(model.flexibility, plate_truth(plate10, chosen, [1, 0]))
    np.testing.assert_allclose(model.coordinates[:, :2], plate10["xy"][chosen], rtol=1e-9)
    # unconstrained: rounded to 10 digits, the rigid-body modes show either as vanishing pivots
    # (RigidBodyModeError) or as an indefinite flexibility; both are NotPositiveDefiniteError
    with pytest.raises(NotPositiveDefiniteError, match=r"plate\.bdf: "):
        read_dmig(path, "KAAX", plate10["numbers"][chosen], (1, 2), kind="stiffness")


@nastran
def test_dmig_in_a_full_deck_and_the_assembled_matrix(tmp_path, plate10):
    free = np.setdiff1d(np.arange(len(plate10["numbers"])), plate10["left"])
    bulk = tmp_path / "bulk.bdf"
    plate_dmig_model(plate10, "K2GG", free).write_bdf(
        str(bulk), size=16, is_double=True, enddata=False
    )
    deck = tmp_path / "deck.dat"
    body = [line for line in bulk.read_text().splitlines() if not line.startswith("$")]
    deck.write_text("SOL 101\nCEND\nSUBCASE 1\nBEGIN BULK\n" + "\n".join(body) + "\nENDDATA\n")
    matrix, labels = dmig_matrix(deck, "K2GG")
    eq = plate10["dof"][free].ravel()
    expected = {
        (int(plate10["numbers"][p]), c): plate10["dof"][p, c - 1] for p in free for c in (1, 2)
    }
    order = [expected[label] for label in labels]
    assert sorted(order) == sorted(eq)
    np.testing.assert_array_equal(matrix.toarray(), plate10["K"][np.ix_(order, order)])
    model = load_compliance(deck, "K2GG", components=(1, 2), kind="stiffness")  # every grid
    assert model.given == "stiffness"  # nothing to condense
    np.testing.assert_array_equal(model.stiffness, plate10["K"][np.ix_(eq, eq)])


@nastran
def test_dmig_errors(tmp_path, plate10):
    from pyNastran.bdf.bdf import BDF

    path = tmp_path / "k.bdf"
    model = plate_dmig_model(plate10, "KAAX", plate10["right"][:2])
    model.add_dmig("PHI", 2, 2, 2, 0, None, [(1000, 1)], [(1003, 1)], [1.0])
    model.write_bdf(str(path), size=16, is_double=True)
    number = int(plate10["numbers"][plate10["right"][0]])
    with pytest.raises(InvalidInputError, match=r"k\.bdf: no DMIG named 'KGG' .*KAAX, PHI"):
        read_dmig(path, "KGG", kind="stiffness")
    with pytest.raises(
        InvalidInputError,
        match=r"k\.bdf: grid 1000 is not in the file "
        r"\(2 grids\)",
    ):
        read_dmig(path, "KAAX", [1000], (1, 2), kind="stiffness")
    with pytest.raises(
        InvalidInputError,
        match=rf"grid {number} component 3 is not in the "
        rf"file \(grid {number} has 1, 2\)",
    ):
        read_dmig(path, "KAAX", [number], kind="stiffness")
    with pytest.raises(InvalidInputError, match="IFO=2; a square"):
        read_dmig(path, "PHI", kind="flexibility")
    both = tmp_path / "both.bdf"
    twice = BDF(debug=None)
    twice.add_dmig(
        "K", 6, 2, 2, 0, None, [(1, 1), (1, 1), (2, 1)], [(1, 1), (2, 1), (1, 1)], [2.0, -1.0, -1.0]
    )
    twice.write_bdf(str(both))
    with pytest.raises(FileFormatError, match="both above and below the diagonal"):
        dmig_matrix(both, "K")
    bad = tmp_path / "bad.bdf"
    bad.write_text(
        "BEGIN BULK\nDMIG    K       0       6       2       0\n"
        "DMIG    K       1       1               x       1       2.0\nENDDATA\n"
    )
    with pytest.raises(
        FileFormatError,
        match=r"bad\.bdf: not a readable NASTRAN bulk-data "
        r"file \(SyntaxError: Gi = 'x'",
    ):
        dmig_matrix(bad, "K")


@nastran
def test_dmig_file_starting_at_begin_bulk(tmp_path):
    """Bulk data opened by BEGIN BULK without executive and case control (a common hand-made
    file) is read; it used to fail for lack of the control decks."""
    path = tmp_path / "k.bdf"
    path.write_text(
        "$ stiffness\nBEGIN BULK\nDMIG    K       0       6       1       0\n"
        "DMIG    K       1       1               1       1       2.0\n"
        "DMIG    K       2       1               1       1       -1.0\n"
        "        2       1       2.0\nENDDATA\n"
    )
    matrix, labels = dmig_matrix(path, "K")
    assert labels == [(1, 1), (2, 1)]
    np.testing.assert_array_equal(matrix.toarray(), [[2.0, -1.0], [-1.0, 2.0]])
    (tmp_path / "inc.bdf").write_text("")
    path.write_text("BEGIN BULK\nINCLUDE 'inc.bdf'\nENDDATA\n")
    with pytest.raises(FileFormatError, match="cannot have INCLUDE statements"):
        dmig_matrix(path, "K")


# --------------------------------------------------------------------------------------------
# MatrixMarket and CSV


def test_matrix_market_sparse_symmetric_stiffness_and_dense_flexibility(tmp_path):
    K = sp.csr_matrix(chain_stiffness(30))
    path = tmp_path / "k.mtx"
    scipy.io.mmwrite(str(path), K, symmetry="symmetric")
    chosen = [29, 3, 10]
    model = read_matrix_market(path, kind="stiffness", freedoms=chosen)
    assert_flexibility(model.flexibility, chain_flexibility(chosen))
    R = chain_flexibility(np.arange(4))
    dense = tmp_path / "r.mtx"
    scipy.io.mmwrite(str(dense), R)
    model = load_compliance(dense, kind="flexibility", dofs_per_node=2)
    np.testing.assert_allclose(model.flexibility, R, rtol=1e-15)
    assert model.n_nodes == 2


def test_matrix_market_errors(tmp_path):
    cut = tmp_path / "cut.mtx"
    cut.write_text("%%MatrixMarket matrix coordinate real symmetric\n3 3 3\n1 1 2.0\n")
    with pytest.raises(FileFormatError, match=r"cut\.mtx: not a readable MatrixMarket"):
        read_matrix_market(cut, kind="stiffness")
    complex_ = tmp_path / "c.mtx"
    scipy.io.mmwrite(str(complex_), np.eye(2) * (1 + 1j))
    with pytest.raises(InvalidInputError, match="complex"):
        read_matrix_market(complex_, kind="stiffness")
    unsymmetric = tmp_path / "u.mtx"
    K = chain_stiffness(4)
    K[0, 1] *= 1.01
    scipy.io.mmwrite(str(unsymmetric), sp.coo_matrix(K))
    with pytest.raises(InvalidInputError, match=r"u\.mtx: the stiffness is not symmetric"):
        read_matrix_market(unsymmetric, kind="stiffness", freedoms=[3])
    with pytest.raises(InvalidInputError, match=r"u\.mtx: no freedom is chosen"):
        read_matrix_market(unsymmetric, kind="stiffness", freedoms=[])
    indefinite = tmp_path / "i.mtx"
    scipy.io.mmwrite(str(indefinite), np.diag([1.0, -1.0]))
    with pytest.raises(NotPositiveDefiniteError, match=r"i\.mtx: stiffness is not positive"):
        read_matrix_market(indefinite, kind="stiffness")


def write_rows(path, table, header=None, delimiter=","):
    lines = ["# unit-load responses"] + ([delimiter.join(header)] if header else [])
    lines += [delimiter.join(repr(float(v)) for v in row) for row in table]
    path.write_text("\n".join(lines) + "\n")


def test_unit_load_csv_rows_with_header(tmp_path, plate):
    nodes = plate["right"]
    R = plate_truth(plate, nodes, [0, 1])
    header = [f"{plate['numbers'][p]}:{c}" for p in nodes for c in ("UX", "UY")]
    path = tmp_path / "rows.csv"
    write_rows(path, R.T, header)  # row j: displacements under a unit load on freedom j
    model = read_unit_load_csv(path)
    np.testing.assert_array_equal(model.flexibility, R)
    assert list(model.dofs_per_node) == [2] * len(nodes)
    chosen = plate["numbers"][nodes[[2, 0]]]
    picked = load_compliance(path, chosen, ["uy"])
    np.testing.assert_array_equal(picked.flexibility, plate_truth(plate, nodes[[2, 0]], [1]))


def test_unit_load_csv_without_header(tmp_path):
    R = chain_flexibility(np.arange(6))
    path = tmp_path / "rows.txt"
    write_rows(path, R.T, delimiter=" ")
    model = read_unit_load_csv(path, dofs_per_node=3)
    np.testing.assert_array_equal(model.flexibility, R)
    assert model.n_nodes == 2
    with pytest.raises(InvalidInputError, match="needs a header row"):
        read_unit_load_csv(path, nodes=[1])


def test_unit_load_csv_errors(tmp_path):
    R = chain_flexibility(np.arange(3))
    cases = {
        "square": (R[:2], None, InvalidInputError, "2 rows \\(unit loads\\) and 3 columns"),
        "label": (R, ["1:UX", "1-UY", "2:UX"], FileFormatError, "'1-UY' is not NODE:COMPONENT"),
        "apart": (R, ["1:UX", "2:UX", "1:UY"], InvalidInputError, "node 1 are not adjacent"),
        "length": (R, ["1:UX", "2:UX"], InvalidInputError, "2 labels for 3 columns"),
        "reciprocity": (R + np.triu(R, 1) * 0.1, None, InvalidInputError, "not symmetric"),
    }
    for name, (table, header, error, message) in cases.items():
        path = tmp_path / f"{name}.csv"
        write_rows(path, table, header)
        with pytest.raises(error, match=rf"{name}\.csv: .*{message}"):
            read_unit_load_csv(path)
    text = tmp_path / "text.csv"
    text.write_text("1.0, 2.0\n3.0, abc\n")
    with pytest.raises(FileFormatError, match=r"text\.csv: not a table of numbers"):
        read_unit_load_csv(text)


# --------------------------------------------------------------------------------------------
# Dispatch, problem files and missing backends


@nastran
def test_problem_file_takes_an_op4_matrix_by_name(tmp_path):
    K = chain_stiffness(3)
    write_op4_binary(tmp_path / "model.op4", {"KAA": K, "MAA": np.eye(3)})
    (tmp_path / "p.toml").write_text(
        '[model]\nstiffness = { file = "model.op4", key = "KAA" }\n'
        "[loads]\nvalues = [0.0, 0.0, 1.0]\n"
        '[[obstacle]]\ntype = "gaps"\nnodes = [2]\ngaps = [1.0]\n'
    )
    spec = load_problem_file(tmp_path / "p.toml")
    np.testing.assert_array_equal(spec.problem.model.stiffness, K)
    np.testing.assert_array_equal(read_array(tmp_path / "model.op4", key="MAA"), np.eye(3))
    with pytest.raises(InvalidInputError, match=r"model\.op4: the file holds 2 matrices"):
        read_array(tmp_path / "model.op4")


def test_load_compliance_knows_every_extension_and_names_the_unknown(tmp_path):
    assert set(READERS.values()) == {
        read_ansys_full,
        read_op4,
        read_dmig,
        read_matrix_market,
        read_unit_load_csv,
    }
    with pytest.raises(FileFormatError, match=r"model\.h5: cannot tell the format .*\.full"):
        load_compliance(tmp_path / "model.h5")
    # arguments the chosen reader does not take: InvalidInputError, not a bare TypeError
    path = tmp_path / "K.mtx"
    scipy.io.mmwrite(str(path), chain_stiffness(3))
    with pytest.raises(InvalidInputError, match=r"K\.mtx: read_matrix_market: .*'nodes'"):
        load_compliance(path, nodes=[1], kind="stiffness")
    with pytest.raises(InvalidInputError, match=r"K\.mtx: read_matrix_market: .*'kind'"):
        load_compliance(path)
    assert load_compliance(path, kind="stiffness", freedoms=[2]).flexibility.shape == (1, 1)


@pytest.mark.parametrize(
    "module, reader, args, extra",
    [
        ("ansys.mapdl.reader.full", read_ansys_full, dict(nodes=[1]), "ansys"),
        ("pyNastran.op4.op4", read_op4, dict(kind="stiffness"), "nastran"),
        ("pyNastran.bdf.bdf", read_dmig, dict(name="K", kind="stiffness"), "nastran"),
    ],
)
def test_missing_backend_names_the_pip_install(tmp_path, monkeypatch, module, reader, args, extra):
    path = tmp_path / "any.file"
    path.write_bytes(b"\0" * 1024)
    monkeypatch.setitem(sys.modules, module, None)  # import of it raises ImportError
    with pytest.raises(MissingDependencyError, match=rf"pip install 'contactqp\[{extra}\]'"):
        reader(path, **args)


@nastran
def test_non_numeric_nodes_and_components_are_invalid_input(tmp_path):
    """``int('x')`` used to escape as a bare ValueError (outside the exception tree)."""
    from pyNastran.bdf.bdf import BDF

    path = tmp_path / "k.bdf"
    model = BDF(debug=None)
    model.add_dmig(
        "K", 6, 2, 2, 0, None, [(1, 1), (1, 1), (2, 1)], [(1, 1), (2, 1), (2, 1)], [2.0, -1.0, 2.0]
    )
    model.write_bdf(str(path))
    expected = np.linalg.inv([[2.0, -1.0], [-1.0, 2.0]])
    np.testing.assert_allclose(
        read_dmig(path, "K", components=[1], kind="stiffness").flexibility, expected, rtol=1e-14
    )
    for kwargs, message in [
        (dict(components=["x"]), "components must be a list of whole"),
        (dict(nodes=["a"], components=[1]), "nodes must be a list of whole"),
        (dict(components=[1.5]), "components must be a list of whole"),
        (dict(components=[1], fixed=[(1,)]), r"\(grid, component\) pairs"),
        (dict(components=[1], fixed=[1]), "fixed must be a list"),
    ]:
        with pytest.raises(InvalidInputError, match=message):
            read_dmig(path, "K", kind="stiffness", **kwargs)
    rows = tmp_path / "rows.csv"
    write_rows(rows, chain_flexibility(np.arange(2)), ["1:UX", "2:UX"])
    with pytest.raises(InvalidInputError, match="nodes must be a list of whole numbers"):
        read_unit_load_csv(rows, nodes=["a"])


def test_ansys_full_file_written_by_mapdl():
    """The example full file shipped with ansys-mapdl-reader (written by MAPDL, not by the
    test writer): the flexibility of free nodes equals the dense inverse of the stiffness that
    the reader's ``load_km`` returns, with its constrained DOFs (``const``) removed and the
    freedoms located through its own ``dof_ref`` (0, 1, 2 = UX, UY, UZ)."""
    from ansys.mapdl.reader import examples
    from ansys.mapdl.reader.full import FullFile

    full = FullFile(examples.fullfile)
    dof_ref, upper, _ = full.load_km(sort=True)
    upper = sp.csc_matrix(upper)
    K = (upper + sp.triu(upper, 1).T).toarray()
    constrained = {tuple(pair) for pair in full.const.tolist()}
    free = np.array([tuple(pair) not in constrained for pair in dof_ref.tolist()])
    nodes = [22, 23, 40]
    assert not any((n, j) in constrained for n in nodes for j in range(3))
    reference = dof_ref[free]
    eq = [
        int(np.flatnonzero((reference[:, 0] == n) & (reference[:, 1] == j))[0])
        for n in nodes
        for j in (2, 0)
    ]
    expected = np.linalg.inv(K[np.ix_(free, free)])[np.ix_(eq, eq)]
    model = read_ansys_full(examples.fullfile, nodes, ("UZ", "UX"))
    assert_flexibility(model.flexibility, 0.5 * (expected + expected.T))

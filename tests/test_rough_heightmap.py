"""Height maps from files: CSV rows, NPY, the ASCII grid with units; one-line errors."""

import numpy as np
import pytest

from contactqp.applications.rough.heightmap import read_height_map
from contactqp.errors import FileFormatError, InvalidInputError

HEIGHTS = np.array([[1.0, 2.0, 3.0, 4.0], [5.0, 6.0, 7.5, 8.0], [-1.0, 0.0, 2.5e-3, 1e3]]) * 1e-9

ASCII = """# a measured patch
ncols 4
NROWS 3   # keys in any case
cellsize 0.5 um
unit nm
1 2 3 4
5, 6, 7.5, 8
-1 0 2.5e-3 1e3
"""


def test_csv_rows_are_y_and_columns_x(tmp_path):
    path = tmp_path / "map.csv"
    np.savetxt(path, HEIGHTS, delimiter=",")
    before = path.read_bytes()
    surface = read_height_map(path, cell=2e-6)
    np.testing.assert_array_equal(surface.heights, HEIGHTS)  # repr round trip: exact
    assert surface.cell == 2e-6 and surface.shape == (3, 4) and surface.source == path
    assert path.read_bytes() == before  # read, never written


def test_npy(tmp_path):
    path = tmp_path / "map.npy"
    np.save(path, HEIGHTS)
    np.testing.assert_array_equal(read_height_map(path, cell=1e-6).heights, HEIGHTS)


def test_the_ascii_grid_converts_its_units_to_metres(tmp_path):
    path = tmp_path / "map.asc"
    path.write_text(ASCII)
    surface = read_height_map(path)
    np.testing.assert_allclose(surface.heights, HEIGHTS, rtol=1e-15)
    assert surface.cell == pytest.approx(0.5e-6, rel=1e-15)


@pytest.mark.parametrize(
    ("name", "content", "cell", "words"),
    [
        ("none.csv", None, 1e-6, "file not found"),
        ("map.dat", "1 2\n3 4\n", 1e-6, "unknown height map extension"),
        ("map.csv", "1,2\n3,4\n", None, "holds no cell size"),
        ("map.csv", "1,2\n3,4\n", -1.0, "cell must be positive"),
        ("map.csv", "1,2,3\n", 1e-6, "at least 2 x 2"),
        ("map.csv", "1,2\n3,nan\n", 1e-6, "1 heights are not finite"),
        ("map.csv", "1,2\n3,x\n", 1e-6, "not a table of numbers"),
        ("map.asc", ASCII, 1e-6, "gives its cell size"),
        ("map.asc", ASCII.replace("unit nm", "unit inch"), None, "line 5: unit must be"),
        ("map.asc", ASCII.replace("0.5 um", "0.5"), None, "line 4: cellsize must be"),
        ("map.asc", ASCII.replace("ncols 4", "ncols four"), None, "line 2: ncols must be"),
        ("map.asc", ASCII.replace("ncols", "columns"), None, "line 2: unknown key .columns."),
        ("map.asc", ASCII.replace("NROWS 3", "NROWS 4"), None, "nrows is 4 but 3 rows"),
        ("map.asc", ASCII.replace("5, 6, 7.5, 8", "5 6 7.5"), None, "line 7: 3 heights"),
        ("map.asc", ASCII.replace("unit nm\n", ""), None, "the header lacks unit"),
        ("map.asc", ASCII + "ncols 4\n", None, "rows of heights follow"),
        ("map.asc", ASCII.replace("1e3", "1e3x"), None, "line 8: a height is not a number"),
    ],
)
def test_bad_files_are_one_line_errors_naming_the_file(tmp_path, name, content, cell, words):
    path = tmp_path / name
    if content is not None:
        path.write_text(content)
    with pytest.raises((FileFormatError, InvalidInputError), match=words) as caught:
        read_height_map(path, cell=cell)
    message = str(caught.value)
    assert "\n" not in message and (str(path) in message or "cell must" in message)


def test_a_one_dimensional_npy_is_refused(tmp_path):
    path = tmp_path / "line.npy"
    np.save(path, np.arange(5.0))
    with pytest.raises(FileFormatError, match="2-D grid"):
        read_height_map(path, cell=1e-6)

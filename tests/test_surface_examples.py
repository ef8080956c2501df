"""The matrix-free half-space example (examples/flat_punch.py) runs and agrees with Boussinesq.

Tolerances from the discretisation (see the example's notes): the force and the centre pressure
converge at first order in the cell size, about 0.12 h / a off the theory; a quarter of a cell
per radius bounds both.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load_example(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("cells", [8, 16])
def test_flat_punch_example(cells, capsys):
    out = load_example("flat_punch").main(["--cells", str(cells)])
    printed = capsys.readouterr().out
    assert "certified: True" in printed and "Boussinesq" in printed
    assert out["success"] and out["contact_is_face"]
    bound = 0.25 * out["cell"] / out["radius"]
    assert out["force"] == pytest.approx(out["force_theory"], rel=bound)
    assert out["centre_pressure"] == pytest.approx(out["centre_pressure_theory"], rel=bound)
    # the singular edge: the edge cell's pressure over the centre's, about 1.8 sqrt(a / h)
    assert out["edge_over_centre"] == pytest.approx(
        1.8 * np.sqrt(out["radius"] / out["cell"]), rel=0.1
    )


def test_flat_punch_example_refuses_too_few_cells(capsys):
    with pytest.raises(SystemExit) as info:
        load_example("flat_punch").main(["--cells", "1"])
    assert info.value.code == 2
    capsys.readouterr()


def test_coated_sphere_example_between_hertz_and_the_oedometer(capsys):
    """Thick: Hertz (the contact radius to the grid's quantisation, half a cell of 16 per
    radius; the peak pressure to 1 %, with the periodic images); thin (h = a_H / 20): the
    oedometer to 2 % (measured 1 %, the cells per radius falling to 8); between them the
    contact shrinks and the peak pressure rises as the coating thins."""
    rows = load_example("coated_sphere").main(["--thickness", "inf,1,0.2,0.05"])
    printed = capsys.readouterr().out
    assert "certified: True" in printed
    thick, thin = rows[0], rows[-1]
    assert thick["radius"] == pytest.approx(thick["radius_hertz"], abs=0.5 * thick["cell"])
    assert thick["peak_pressure"] == pytest.approx(thick["peak_pressure_hertz"], rel=0.01)
    assert thin["radius"] == pytest.approx(thin["radius_oedometer"], abs=0.5 * thin["cell"])
    assert thin["peak_pressure"] == pytest.approx(thin["peak_pressure_oedometer"], rel=0.02)
    radii = [row["radius"] for row in rows]
    peaks = [row["peak_pressure"] for row in rows]
    assert np.all(np.diff(radii) < 0) and np.all(np.diff(peaks) > 0)


def test_coated_sphere_example_refuses_bad_arguments(capsys):
    for argv in (["--cells", "4"], ["--thickness", "x"], ["--thickness", "0"]):
        with pytest.raises(SystemExit) as info:
            load_example("coated_sphere").main(argv)
        assert info.value.code == 2
    capsys.readouterr()

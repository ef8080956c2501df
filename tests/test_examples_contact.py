"""The half-space contact examples run and agree with the theory they print.

Each example is imported from ``examples/`` and its ``main`` run with small grids; the checks are
against closed forms (Hertz, Mindlin), with tolerances set by the discretisation: pressure is the
mean over a cell of side ``h`` and a contact or stick edge falls somewhere inside a cell, so radii
are known to about half a cell while integrated quantities (loads) converge faster.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load_example(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("cells", [6, 10])
def test_hertz_example(cells, capsys):
    """Load within 0.5 % (measured 2.6e-3 at 6 cells per radius, 5e-4 at 12), peak pressure
    within 1 % (measured 5e-3 at 6 cells), contact radius within half a cell."""
    out = load_example("hertz").main(["--cells", str(cells)])
    printed = capsys.readouterr().out
    assert "peak pressure" in printed and "certified: True" in printed
    assert out["success"]
    assert out["load"] == pytest.approx(out["load_theory"], rel=5e-3)
    assert out["peak_pressure"] == pytest.approx(out["peak_pressure_theory"], rel=1e-2)
    assert abs(out["radius"] - out["radius_theory"]) < 0.5 * out["cell"]


@pytest.mark.parametrize(
    "solver, ratio", [("tangential-fista", 0.5), ("coulomb", 0.5), ("tresca", 0.75)]
)
def test_cattaneo_mindlin_example(solver, ratio, capsys):
    """With 8 cells per contact radius: the shear force reached by Mindlin's displacement is the
    target within 1 % (measured 2e-3 at Q / mu P = 0.5: the discrete load and radius differ from
    Hertz's by that much), the stick radius is Mindlin's c = a (1 - Q / mu P)^(1/3) within half
    a cell (measured a tenth of a cell), no cell sticks beyond c + h, some cells slip, and the
    transverse force vanishes (symmetry)."""
    out = load_example("cattaneo_mindlin").main(
        ["--cells", "8", "--ratio", str(ratio), "--solver", solver]
    )
    printed = capsys.readouterr().out
    assert "stick radius" in printed
    assert out["converged"] and out["error"] <= 1e-8
    assert out["load"] == pytest.approx(out["load_hertz"], rel=5e-3)
    assert out["ratio"] == pytest.approx(ratio, rel=1e-2)
    h = out["cell"]
    assert abs(out["stick_radius"] - out["stick_radius_theory"]) < 0.5 * h
    assert out["stick_outside_theory"] < out["stick_radius_theory"] + h
    assert out["stick_radius"] < out["contact_radius"] - h  # a slipping annulus exists
    assert abs(out["transverse_force"]) < 1e-9 * out["load"]


def test_cattaneo_mindlin_full_sliding_and_bad_arguments(capsys):
    """At Q = mu P nothing sticks (the stick radius is 0, no crash on the empty stick set);
    arguments outside the theory's range are a usage error, not a traceback."""
    out = load_example("cattaneo_mindlin").main(["--cells", "4", "--ratio", "1"])
    assert out["stick_radius"] == 0.0 and out["stick_outside_theory"] == 0.0
    for name, args in [("cattaneo_mindlin", ["--ratio", "1.5"]), ("hertz", ["--cells", "0"])]:
        with pytest.raises(SystemExit) as info:
            load_example(name).main(args)
        assert info.value.code == 2
    capsys.readouterr()

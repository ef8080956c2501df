"""One module draws figures (io/plot.py) and one writes VTU files (io/export.py); applications
and the CLI only hand them arrays."""

import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "contactqp"


def modules_matching(pattern: str) -> set[str]:
    """The package's modules (paths from the package root) whose source matches ``pattern``."""
    return {
        path.relative_to(PACKAGE).as_posix()
        for path in PACKAGE.rglob("*.py")
        if re.search(pattern, path.read_text(encoding="utf-8"))
    }


@pytest.mark.parametrize(
    "pattern", [r"\bmatplotlib\b", r"\bsubplots\(", r"\bsave_figure\(", r"\.savefig\("]
)
def test_only_io_plot_draws(pattern):
    assert modules_matching(pattern) == {"io/plot.py"}


@pytest.mark.parametrize("pattern", [r"def write_vtu\b", r"meshio\.write\b", r"\"vtu\""])
def test_only_io_export_writes_vtu(pattern):
    assert modules_matching(pattern) == {"io/export.py"}

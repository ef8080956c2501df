"""Figures (matplotlib, imported when a figure is asked for)."""

from __future__ import annotations

from pathlib import Path

from .errors import MissingDependencyError

__all__ = ["plot_spring_chain"]


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise MissingDependencyError(
            "figures need matplotlib: pip install 'contactqp[plot]'"
        ) from None
    return plt


def plot_spring_chain(results, path) -> Path:
    """Displacement of each body for each pulling force, as a PNG.

    Parameters
    ----------
    results : sequence of SpringChainResult
    path : str or Path
        Output file; its suffix chooses the format.
    """
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(7, 4.5))
    for result in results:
        bodies = range(1, len(result.x) + 1)
        axes.plot(bodies, result.x, marker="o" if len(result.x) <= 50 else None,
                  label=f"F = {result.force:g} N")
    axes.xaxis.get_major_locator().set_params(integer=True)
    axes.set_xlabel("body")
    axes.set_ylabel("displacement x (m)")
    axes.set_title("Spring chain with friction")
    axes.grid(True, alpha=0.3)
    axes.legend()
    figure.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path

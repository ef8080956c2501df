"""Figures (matplotlib, imported when a figure is asked for).

Figures are made outside pyplot (:func:`subplots`), so drawing one never switches the user's
matplotlib backend nor leaves a figure registered in a notebook's pyplot state.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InvalidInputError
from ..optional import require

__all__ = ["plot_spring_chain", "plot_rod", "save_figure", "subplots"]


def subplots(nrows: int = 1, ncols: int = 1, *, figsize=(7, 4.5), **options):
    """``(figure, axes)`` as :func:`matplotlib.pyplot.subplots` gives, without pyplot.

    The :class:`matplotlib.figure.Figure` is written by :func:`save_figure` (Agg for raster
    formats); no backend is selected and no pyplot state changes. ``options`` go to
    :meth:`~matplotlib.figure.Figure.subplots` (``sharex``, ...).
    """
    figure = require("matplotlib.figure", "figures", "plot", "matplotlib").Figure(figsize=figsize)
    return figure, figure.subplots(nrows, ncols, **options)


def save_figure(figure, path) -> Path:
    """Write ``figure`` to ``path`` (its suffix chooses the format), creating folders.

    Raises
    ------
    InvalidInputError
        The suffix is not a format matplotlib writes (png, pdf, svg, ...).
    """
    path = Path(path)
    formats = figure.canvas.get_supported_filetypes()
    if path.suffix.lstrip(".").lower() not in formats:
        raise InvalidInputError(f"{path}: a figure file needs a suffix among "
                                f"{', '.join(sorted(formats))}")
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=120)
    return path


def plot_spring_chain(results, path) -> Path:
    """Displacement of each body for each pulling force, as a PNG.

    Parameters
    ----------
    results : sequence of SpringChainResult
    path : str or Path
        Output file; its suffix chooses the format.
    """
    figure, axes = subplots(figsize=(7, 4.5))
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
    return save_figure(figure, path)


def plot_rod(rod, comparisons, path) -> Path:
    """The rod deformed over its obstacle, one panel per load case, as a PNG (true scale, mm).

    Parameters
    ----------
    rod : contactqp.applications.rod.Rod
    comparisons : sequence of contactqp.applications.rod.CaseComparison
        Drawn: the reference deflection on the mesh (line), the reduced solution at the
        computational nodes (markers), the applied forces and the reduced contact forces (arrows,
        labelled in N).
    path : str or Path
        Output file; its suffix chooses the format.
    """
    import numpy as np

    x = rod.frame.coordinates[:, 0] * 1e3
    nodes = rod.node_indices
    figure, panels = subplots(len(comparisons), 1, figsize=(8, 3.2 * len(comparisons)),
                              sharex=True, squeeze=False)
    arrow = 0.25 * rod.gap_clamped * 1e3
    for axes, c in zip(panels[:, 0], comparisons):
        obstacle = -rod.gap(rod.frame.coordinates[:, 0]) * 1e3
        axes.fill_between(x, obstacle, obstacle.min() - 1.0, color="0.85", label="obstacle")
        axes.plot(x, obstacle, color="0.3", lw=1)
        axes.plot(x, 0 * x, color="0.6", ls="--", lw=1, label="rod at rest")
        deformed = rod.frame.coordinates[:, :2] + c.reference.displacements[:, :2]
        axes.plot(deformed[:, 0] * 1e3, deformed[:, 1] * 1e3, color="C0", lw=2,
                  label="full FE contact")
        U = c.reduced.displacements.reshape(-1, 2)
        axes.plot((x[nodes] + U[:, 0] * 1e3), U[:, 1] * 1e3, "o", color="C1",
                  label="reduced model (nodes)")
        axes.plot([x[-1]] * 2, [-arrow, arrow], color="k", lw=4)
        scale = arrow / max(max(abs(load.fy) for load in c.case.loads), 1e-300)
        for load in c.case.loads:
            uy = c.reference.displacements[int(np.argmin(np.abs(x - load.x * 1e3))), 1] * 1e3
            axes.annotate(f"{abs(load.fy):.3g} N", (load.x * 1e3, uy),
                          (load.x * 1e3, uy - load.fy * scale), color="C3", ha="center",
                          arrowprops={"arrowstyle": "->", "color": "C3"})
        for i in np.flatnonzero(c.reduced.forces > 0):
            force = c.reduced.forces[i]
            tip = (x[nodes[i]] + U[i, 0] * 1e3, U[i, 1] * 1e3)
            tail = (tip[0] + force * scale * rod.normal[0], tip[1] + force * scale * rod.normal[1])
            axes.annotate(f"{force:.3g} N", tip, tail, color="C2", ha="center", va="top",
                          arrowprops={"arrowstyle": "->", "color": "C2"})
        axes.set_title(f"{c.case.name}: largest deviation {c.max_eps:.2g} %")
        axes.set_ylabel("y (mm)")
        axes.grid(True, alpha=0.3)
    panels[0, 0].legend(loc="upper left", fontsize="small")
    panels[-1, 0].set_xlabel("x (mm), clamped at the right end")
    figure.tight_layout()
    return save_figure(figure, path)

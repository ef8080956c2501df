"""Figures (matplotlib, imported when a figure is asked for): the one module that draws.

Figures are made outside pyplot (:func:`subplots`), so drawing one never switches the user's
matplotlib backend nor leaves a figure registered in a notebook's pyplot state. Each figure
takes plain arrays in SI units (an application picks them from its own objects, e.g.
:func:`contactqp.applications.riveting.plot_status`) and is written by :func:`save_figure`.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidInputError
from ..optional import require

__all__ = [
    "plot_spring_chain",
    "plot_deflections",
    "DeflectionCase",
    "MapPanel",
    "STATUS_COLOURS",
    "point_maps_figure",
    "plot_point_maps",
    "fastener_forces_figure",
    "plot_fastener_forces",
    "plot_statistics",
    "plot_sliding_curve",
    "plot_area_load",
    "save_figure",
    "figure_path",
    "subplots",
]


def subplots(
    nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float] = (7, 4.5), **options: Any
) -> tuple[Any, Any]:
    """``(figure, axes)`` as :func:`matplotlib.pyplot.subplots` gives, without pyplot.

    The :class:`matplotlib.figure.Figure` is written by :func:`save_figure` (Agg for raster
    formats); no backend is selected and no pyplot state changes. ``options`` go to
    :meth:`~matplotlib.figure.Figure.subplots` (``sharex``, ...).
    """
    figure = require("matplotlib.figure", "figures", "plot", "matplotlib").Figure(figsize=figsize)
    return figure, figure.subplots(nrows, ncols, **options)


def figure_path(path: str | os.PathLike[str]) -> Path:
    """``path`` as a Path, checked (before any work) to end in a format matplotlib writes.

    Raises
    ------
    InvalidInputError
        The suffix is not a format matplotlib writes (png, pdf, svg, ...).
    """
    path = Path(path)
    backends = require("matplotlib.backend_bases", "figures", "plot", "matplotlib")
    formats = backends.FigureCanvasBase.get_supported_filetypes()
    if path.suffix.lstrip(".").lower() not in formats:
        raise InvalidInputError(
            f"{path}: a figure file needs a suffix among {', '.join(sorted(formats))}"
        )
    return path


def save_figure(figure: Any, path: str | os.PathLike[str]) -> Path:
    """Write ``figure`` to ``path`` (its suffix chooses the format), creating folders.

    Raises
    ------
    InvalidInputError
        The suffix is not a format matplotlib writes (png, pdf, svg, ...).
    """
    path = figure_path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=120)
    return path


def plot_spring_chain(
    forces: Sequence[float],
    displacements: Sequence[np.ndarray | Sequence[float]],
    path: str | os.PathLike[str],
) -> Path:
    """Displacement of each body for each pulling force.

    Parameters
    ----------
    forces : sequence of float
        The pulling forces (N).
    displacements : sequence of array_like
        For each force, the displacement of each body (m).
    path : str or Path
        Output file; its suffix chooses the format.
    """
    figure, axes = subplots(figsize=(7, 4.5))
    for force, x in zip(forces, displacements, strict=False):  # as many as both give
        bodies = range(1, len(x) + 1)
        axes.plot(bodies, x, marker="o" if len(x) <= 50 else None, label=f"F = {force:g} N")
    axes.xaxis.get_major_locator().set_params(integer=True)
    axes.set_xlabel("body")
    axes.set_ylabel("displacement x (m)")
    axes.set_title("Spring chain with friction")
    axes.grid(True, alpha=0.3)
    axes.legend()
    figure.tight_layout()
    return save_figure(figure, path)


class MapPanel(NamedTuple):
    """One panel of :func:`point_maps_figure`; a plain ``(values, title, colours)`` tuple will do.

    ``values`` of shape (m,) are numbers, drawn on a colour scale (``colours`` a matplotlib
    colormap name, ``limits`` its ``(low, high)``, default the values' range), or labels (str),
    drawn as categories: one colour per label present (``colours`` a ``{label: colour}``
    mapping, whose order is the legend's; labels it lacks take the next ``tab10`` colour) and
    a legend instead of a colour bar.
    """

    values: ArrayLike
    title: str
    colours: str | Mapping[str, str] = "viridis"
    limits: tuple[float, float] | None = None


#: Colour of each contact status label (:data:`contactqp.core.status.STATUS_LABELS`) on maps.
STATUS_COLOURS: dict[str, str] = {
    "open": "#bdbdbd",
    "stick": "#1b9e77",
    "slip": "#d95f02",
    "closed": "#1f78b4",
    "fastened": "#000000",
}


def point_maps_figure(
    points: ArrayLike,
    panels: Sequence[MapPanel | tuple],
    *,
    marked: ArrayLike | None = None,
    marked_label: str = "",
    axis_labels: tuple[str, str] = ("x (mm)", "y (mm)"),
) -> Any:
    """The figure :func:`plot_point_maps` writes (a :class:`matplotlib.figure.Figure`).

    A categorical panel's legend holds exactly the labels present in its values (and, on the
    first panel, the marked points); each other panel has a colour bar.
    """
    xy = np.asarray(points, dtype=float)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise InvalidInputError(f"map points must have shape (m, 2), got {xy.shape}")
    xy = xy * 1e3
    figure, axes = subplots(
        len(panels), 1, figsize=(7, 0.5 + 3.0 * len(panels)), sharex=True, squeeze=False
    )
    axes = axes[:, 0]
    for n, (ax, panel) in enumerate(zip(axes, panels, strict=True)):
        panel = MapPanel(*panel)
        values = np.asarray(panel.values)
        if values.shape != (len(xy),):
            raise InvalidInputError(
                f"map panel {panel.title!r}: {values.shape} values for {len(xy)} points"
            )
        categorical = values.dtype.kind in "USO"
        if categorical:
            _draw_categories(ax, xy, values.astype(str), panel.colours)
        else:
            low, high = panel.limits if panel.limits is not None else (None, None)
            colours = panel.colours if isinstance(panel.colours, str) else "viridis"
            shown = ax.scatter(
                xy[:, 0], xy[:, 1], c=values, cmap=colours, vmin=low, vmax=high, s=18
            )
            figure.colorbar(shown, ax=ax)
        if marked is not None:  # named in the first panel's legend only
            ax.plot(
                *(np.asarray(marked, dtype=float).reshape(-1, 2) * 1e3).T,
                "k+",
                ms=10,
                label=marked_label if n == 0 else "_nolegend_",
            )
        if categorical:  # beside the map, where a colour bar would be
            ax.legend(loc="center left", bbox_to_anchor=(1.02, 0.5), fontsize="small")
        elif marked is not None and n == 0:
            ax.legend(loc="best", fontsize="small")
        ax.set_title(panel.title)
        ax.set_ylabel(axis_labels[1])
        ax.set_aspect("equal")
    axes[-1].set_xlabel(axis_labels[0])
    figure.tight_layout()
    return figure


def _draw_categories(ax: Any, xy: np.ndarray, labels: np.ndarray, colours: Any) -> None:
    """Scatter ``xy`` one label at a time, each label its colour (named for the legend)."""
    given = dict(colours) if isinstance(colours, Mapping) else {}
    present = [label for label in given if label in set(labels)]
    present += sorted(set(labels) - set(present))
    spare = iter(f"C{i % 10}" for i in range(len(present)))
    for label in present:
        where = labels == label
        colour = given[label] if label in given else next(spare)
        ax.scatter(xy[where, 0], xy[where, 1], color=colour, s=18, label=label)


def plot_point_maps(
    points: ArrayLike,
    panels: Sequence[MapPanel | tuple],
    path: str | os.PathLike[str],
    *,
    marked: ArrayLike | None = None,
    marked_label: str = "",
    axis_labels: tuple[str, str] = ("x (mm)", "y (mm)"),
) -> Path:
    """Maps of values at points in a plane, one panel above the other, sharing the x axis.

    Parameters
    ----------
    points : array_like, shape (m, 2)
        Positions (m); drawn in mm.
    panels : sequence of MapPanel or (array_like, str, str)
        ``(values, title, colours[, limits])`` of each panel (:class:`MapPanel`): numbers on a
        colour scale, or labels as categories with a legend.
    path : str or Path
        Output file; its suffix chooses the format.
    marked : array_like, shape (j, 2), optional
        Positions (m) marked with a cross on every panel, named ``marked_label`` in a legend.
    axis_labels : (str, str)
        Labels of the horizontal and vertical axes (the coordinates are drawn in mm).
    """
    figure = point_maps_figure(
        points, panels, marked=marked, marked_label=marked_label, axis_labels=axis_labels
    )
    return save_figure(figure, path)


def fastener_forces_figure(
    stage_labels: Sequence[str], forces: ArrayLike, names: Sequence[str]
) -> Any:
    """The figure :func:`plot_fastener_forces` writes (a :class:`matplotlib.figure.Figure`):
    one line per fastener, in ``names`` order."""
    force = np.asarray(forces, dtype=float)
    if force.ndim != 2 or force.shape != (len(stage_labels), len(names)):
        raise InvalidInputError(
            f"fastener forces must have shape ({len(stage_labels)} stages, {len(names)} "
            f"fasteners), got {force.shape}"
        )
    stages = np.arange(1, len(stage_labels) + 1)
    figure, axes = subplots(figsize=(8, 4.5))
    for column, name in enumerate(names):
        axes.plot(stages, force[:, column], marker="o", ms=4, label=name)
    axes.axhline(0.0, color="0.5", lw=0.8)
    axes.set_xticks(stages)
    if len(stages) <= 20:
        axes.set_xticklabels(stage_labels, rotation=30, ha="right", fontsize="small")
    axes.set_xlabel("stage of the installation sequence")
    axes.set_ylabel("fastener force (N), tension > 0")
    axes.set_title("Fastener forces along the sequence")
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize="small", ncol=max(1, len(names) // 10 + 1))
    figure.tight_layout()
    return figure


def plot_fastener_forces(
    stage_labels: Sequence[str],
    forces: ArrayLike,
    names: Sequence[str],
    path: str | os.PathLike[str],
) -> Path:
    """Each fastener's force against the stages of an installation sequence.

    Parameters
    ----------
    stage_labels : sequence of str
        The stages, in order (drawn at x = 1, 2, ...).
    forces : array_like, shape (s, f)
        Force of fastener ``j`` after stage ``i`` (N, tension > 0); NaN before it is installed
        (no point drawn).
    names : sequence of str
        One legend entry per fastener.
    path : str or Path
        Output file; its suffix chooses the format.
    """
    return save_figure(fastener_forces_figure(stage_labels, forces, names), path)


def plot_statistics(statistics: Any, coordinates: ArrayLike, path: str | os.PathLike[str]) -> Path:
    """Maps of the mean final gap, its highest quantile and the probability of contact.

    Parameters
    ----------
    statistics : contactqp.studies.batch.GapStatistics
        Its ``mean`` and ``quantiles`` (m), ``levels``, ``contact_probability`` and ``samples``.
    coordinates : array_like, shape (m, 2)
        The position of each contact (m); drawn in mm.
    path : str or Path
        Output file; its suffix chooses the format.
    """
    samples = f", {statistics.samples} samples"
    panels = [
        (np.asarray(statistics.mean) * 1e3, f"mean final gap (mm){samples}", "viridis"),
        (
            np.asarray(statistics.quantiles[-1]) * 1e3,
            f"{statistics.levels[-1]:.0%} quantile of the final gap (mm){samples}",
            "viridis",
        ),
        (statistics.contact_probability, f"probability of contact{samples}", "viridis"),
    ]
    return plot_point_maps(coordinates, panels, path)


def plot_sliding_curve(
    relative: ArrayLike,
    load: ArrayLike,
    limit: float,
    path: str | os.PathLike[str],
    *,
    onset: int | None = None,
    title: str = "",
) -> Path:
    """Lateral load against the relative displacement of two layers, with the analytic limit.

    Parameters
    ----------
    relative, load : array_like, shape (s,)
        Relative displacement (m, drawn in mm) and lateral load (N, drawn in kN) of each step.
    limit : float
        The analytic sliding load ``c A + mu N`` (N).
    path : str or Path
        Output file; its suffix chooses the format.
    onset : int, optional
        The step at which sliding starts, marked with a star.
    title : str
    """
    relative, load = np.asarray(relative) * 1e3, np.asarray(load) / 1e3
    figure, axes = subplots(figsize=(7, 4.5))
    axes.plot(relative, load, "o-", ms=3, label="reduced model")
    axes.axhline(limit / 1e3, color="C3", ls="--", label="c A + mu N (sliding block)")
    if onset is not None:
        axes.plot(relative[onset], load[onset], "k*", ms=12, label="onset of sliding")
    axes.set_xlabel("relative displacement of the layers (mm)")
    axes.set_ylabel("lateral load (kN)")
    axes.set_title(title)
    axes.grid(True, alpha=0.3)
    axes.legend()
    figure.tight_layout()
    return save_figure(figure, path)


def plot_area_load(
    pressure: ArrayLike,
    area_fraction: ArrayLike,
    laws: Mapping[str, float],
    pressure_map: ArrayLike,
    cell: float,
    path: str | os.PathLike[str],
    *,
    title: str = "",
) -> Path:
    """The real contact area against the mean pressure beside linear laws, and a pressure map.

    Parameters
    ----------
    pressure, area_fraction : array_like, shape (n,)
        Mean pressure (Pa, drawn in MPa) and fraction of the area in contact of each load.
    laws : dict of float
        ``{label: slope}``: lines ``area_fraction = slope * pressure`` (slope in 1/Pa), e.g. the
        small-load law ``kappa / (E* h'_rms)``.
    pressure_map : array_like, shape (ny, nx)
        Contact pressure (Pa, drawn in MPa) of each cell at the largest (last) load.
    cell : float
        Side of a cell (m; the map's axes in um).
    path : str or Path
        Output file; its suffix chooses the format.
    title : str
    """
    pressure, fraction = np.asarray(pressure, dtype=float), np.asarray(area_fraction)
    grid = np.asarray(pressure_map, dtype=float) / 1e6
    figure, (curve, image) = subplots(1, 2, figsize=(11, 4.5))
    curve.plot(pressure / 1e6, fraction, "o-", ms=4, label="computed")
    span = np.linspace(0.0, float(pressure.max()), 50)
    for k, (label, slope) in enumerate(laws.items()):
        curve.plot(span / 1e6, slope * span, ls="--", color=f"C{k + 1}", label=label)
    curve.set_ylim(0, min(1.0, 1.15 * float(max(fraction.max(), 1e-12))))
    curve.set_xlabel("mean pressure (MPa)")
    curve.set_ylabel("real contact area fraction")
    curve.grid(True, alpha=0.3)
    curve.legend()
    ny, nx = grid.shape
    extent = (0.0, nx * cell * 1e6, 0.0, ny * cell * 1e6)
    shown = image.imshow(grid, origin="lower", extent=extent, cmap="magma", interpolation="none")
    figure.colorbar(shown, ax=image, label="contact pressure (MPa)")
    image.set_xlabel("x (um)")
    image.set_ylabel("y (um)")
    image.set_title(f"at {pressure[-1] / 1e6:.4g} MPa")
    figure.suptitle(title)
    figure.tight_layout()
    return save_figure(figure, path)


class DeflectionCase(NamedTuple):
    """One panel of :func:`plot_deflections`: a load case's solutions (m) and forces (N).

    ``loads`` and ``contacts`` are ``(point, force)`` pairs, each of shape (2,): the force on
    the beam, drawn as an arrow that ends at the point and is labelled with its magnitude.
    """

    title: str
    deformed: np.ndarray  #: (p, 2): positions of the mesh nodes, deformed (reference solution)
    nodes: np.ndarray  #: (k, 2): positions of the computational nodes, deformed (reduced model)
    loads: Sequence[tuple[np.ndarray, np.ndarray]]
    contacts: Sequence[tuple[np.ndarray, np.ndarray]]


def plot_deflections(
    x: ArrayLike,
    obstacle: ArrayLike,
    cases: Sequence[DeflectionCase],
    path: str | os.PathLike[str],
    *,
    clamp: float,
    xlabel: str = "x (mm)",
) -> Path:
    """A beam deformed over its obstacle, one panel per load case, at true scale in mm.

    Parameters
    ----------
    x : array_like, shape (p,)
        Positions of the mesh nodes along the beam at rest (m), the beam lying on ``y = 0``.
    obstacle : array_like, shape (p,)
        Height of the obstacle's surface under each node (m).
    cases : sequence of DeflectionCase
    path : str or Path
        Output file; its suffix chooses the format.
    clamp : float
        Half height of the clamp drawn at the right end (m); also the length of the arrow of
        each panel's largest load.
    xlabel : str
    """
    x, obstacle = np.asarray(x, dtype=float) * 1e3, np.asarray(obstacle, dtype=float) * 1e3
    figure, panels = subplots(
        len(cases), 1, figsize=(8, 3.2 * len(cases)), sharex=True, squeeze=False
    )
    arrow = clamp * 1e3
    for axes, case in zip(panels[:, 0], cases, strict=True):
        largest = max((np.hypot(*force) for _, force in case.loads), default=0.0)
        scale = arrow / max(largest, 1e-300)  # mm per N: the largest load is `arrow` long
        axes.fill_between(x, obstacle, obstacle.min() - 1.0, color="0.85", label="obstacle")
        axes.plot(x, obstacle, color="0.3", lw=1)
        axes.plot(x, 0 * x, color="0.6", ls="--", lw=1, label="rod at rest")
        deformed, nodes = np.asarray(case.deformed) * 1e3, np.asarray(case.nodes) * 1e3
        axes.plot(deformed[:, 0], deformed[:, 1], color="C0", lw=2, label="full FE contact")
        axes.plot(nodes[:, 0], nodes[:, 1], "o", color="C1", label="reduced model (nodes)")
        axes.plot([x[-1]] * 2, [-arrow, arrow], color="k", lw=4)
        for arrows, color, options in (
            (case.loads, "C3", {}),
            (case.contacts, "C2", {"va": "top"}),
        ):
            for point, force in arrows:
                tip = np.asarray(point, dtype=float) * 1e3
                tail = tip - np.asarray(force, dtype=float) * scale
                axes.annotate(
                    f"{np.hypot(*force):.3g} N",
                    tuple(tip),
                    tuple(tail),
                    color=color,
                    ha="center",
                    arrowprops={"arrowstyle": "->", "color": color},
                    **options,
                )
        axes.set_title(case.title)
        axes.set_ylabel("y (mm)")
        axes.grid(True, alpha=0.3)
    panels[0, 0].legend(loc="upper left", fontsize="small")
    panels[-1, 0].set_xlabel(xlabel)
    figure.tight_layout()
    return save_figure(figure, path)

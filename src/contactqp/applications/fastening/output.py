"""Files, figures and summaries of an assembly's fastening sequence and of its variation study.

Everything here takes plain arrays: the stages of a sequence (any objects with the attributes
of :class:`~contactqp.applications.fastening.AssemblyStage`: ``label``, ``gaps``,
``normal_forces``, ``tangential_forces``, ``status``, ``slip``, ``fasteners``,
``fastener_forces``, ``success``), the pair positions ``points`` (k, 3) and unit normals
``normals`` (k, 3). Units are SI (m, N); CSV headers carry them, e.g. ``gap (m)``. Stages are
numbered from 1 in installation order (each fastener, then each load step).

:func:`write_sequence` writes, in one directory:

- ``stages.csv``: every stage's pairs, one row per (stage, pair), long form: ``stage``,
  ``label``, ``pair``, ``x (m)``, ``y (m)``, ``z (m)``, (given the initial gaps:
  ``initial_gap (m)``), ``gap (m)`` (residual), ``normal_force (N)``,
  ``tangential_force_t1 (N)``, ``tangential_force_t2 (N)``, ``status`` (a label of
  :data:`~contactqp.core.status.STATUS_LABELS`), ``slip_t1 (m)``, ``slip_t2 (m)`` (the
  stage's slip increment), ``fastener_force (N)`` (0 away from installed fasteners);
- ``fasteners.csv``: every installed fastener at every stage: ``stage``, ``label``,
  ``fastener`` (its rank in the installation order, from 1), ``pair``, ``x (m)``, ``y (m)``,
  ``z (m)``, ``force (N)`` (tension > 0);
- ``stage_001.vtu``, ``stage_002.vtu``, ...: the pairs as vertices with their fields
  (:func:`stage_mesh`), and ``stages.pvd``, the ParaView collection of them (one time step per
  stage);
- with a shim tolerance: ``shims.csv``, the pairs of the last stage whose residual gap is
  above it: ``pair``, ``x (m)``, ``y (m)``, ``z (m)``, ``gap (m)``;
- with ``plot``: ``gap.png`` (residual gap of the last stage, fasteners marked),
  ``status.png`` (its pair status, categorical) and ``fastener_forces.png`` (each fastener's
  force against the stages).

:func:`write_statistics` writes the variation study's per-pair statistics
(:class:`~contactqp.studies.GapStatistics`) and :func:`plot_statistics_maps` draws the
probabilities of contact and of a gap above the shim tolerance.
:func:`sequence_summary` (a JSON-ready dict) and :func:`sequence_table` (a rich table) are what
the command line prints.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ElementTree
from collections.abc import Iterable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...core.contact import tangent_basis
from ...core.status import STATUS_LABELS, status_counts, status_labels
from ...errors import InvalidInputError
from ...io.export import PointMesh, write_rows, write_vtu
from ...studies.statistics import GapStatistics, shim_tolerance_value

__all__ = [
    "stage_rows",
    "write_stage_table",
    "write_fastener_table",
    "stage_mesh",
    "write_stage_meshes",
    "shim_pairs",
    "write_shim_table",
    "fastener_force_history",
    "map_plane",
    "gap_map_figure",
    "status_map_figure",
    "fastener_forces_figure",
    "write_plots",
    "write_sequence",
    "write_statistics",
    "statistics_map_figure",
    "plot_statistics_maps",
    "sequence_summary",
    "sequence_table",
]

#: Header of ``stages.csv``.
STAGE_HEADER = (
    "stage",
    "label",
    "pair",
    "x (m)",
    "y (m)",
    "z (m)",
    "gap (m)",
    "normal_force (N)",
    "tangential_force_t1 (N)",
    "tangential_force_t2 (N)",
    "status",
    "slip_t1 (m)",
    "slip_t2 (m)",
    "fastener_force (N)",
)
#: Where ``initial_gap (m)`` goes in :data:`STAGE_HEADER` when the initial gaps are given.
INITIAL_GAP_COLUMN = STAGE_HEADER.index("gap (m)")
#: Header of ``fasteners.csv``.
FASTENER_HEADER = ("stage", "label", "fastener", "pair", "x (m)", "y (m)", "z (m)", "force (N)")


def _geometry(points: ArrayLike, normals: ArrayLike | None = None) -> tuple[np.ndarray, ...]:
    """``points`` (k, 3) and ``normals`` (k, 3) as float arrays, checked."""
    xyz = np.asarray(points, dtype=float)
    if xyz.ndim != 2 or xyz.shape[1] != 3 or not np.isfinite(xyz).all():
        raise InvalidInputError(f"points must be finite, of shape (k, 3), got {xyz.shape}")
    if normals is None:
        return (xyz,)
    n = np.asarray(normals, dtype=float)
    if n.shape != xyz.shape or not np.isfinite(n).all():
        raise InvalidInputError(f"normals must be finite, of shape {xyz.shape}, got {n.shape}")
    return xyz, n


def _initial_gaps(initial_gaps: ArrayLike | None, k: int) -> np.ndarray | None:
    """The initial gaps (k,) as floats, checked; None stays None."""
    if initial_gaps is None:
        return None
    gaps = np.asarray(initial_gaps, dtype=float)
    if gaps.shape != (k,) or not np.isfinite(gaps).all():
        raise InvalidInputError(f"initial_gaps must be finite, of shape ({k},), got {gaps.shape}")
    return gaps


def _stages(sequence: Any) -> list:
    """The stages of an ``AssemblySequence`` (its ``stages``) or of a sequence of stages."""
    stages = list(getattr(sequence, "stages", sequence))
    if not stages:
        raise InvalidInputError("a fastening sequence needs at least one stage")
    return stages


def _checked(stage: Any, k: int, number: int) -> SimpleNamespace:
    """The arrays of ``stage`` (the ``number``-th, from 1) as floats/ints, shapes checked."""
    what = f"stage {number} ({getattr(stage, 'label', '?')!r})"
    shapes = {
        "gaps": (k,),
        "normal_forces": (k,),
        "tangential_forces": (k, 2),
        "status": (k,),
        "slip": (k, 2),
    }
    arrays = {}
    for name, shape in shapes.items():
        values = np.asarray(getattr(stage, name))
        if values.shape != shape:
            raise InvalidInputError(f"{what}: {name} must have shape {shape}, got {values.shape}")
        arrays[name] = values
    status = arrays["status"].astype(int)
    if status.size and (status.min() < 0 or status.max() >= len(STATUS_LABELS)):
        highest = len(STATUS_LABELS) - 1
        raise InvalidInputError(f"{what}: status codes must be ContactStatus codes 0..{highest}")
    pairs = np.asarray(stage.fasteners, dtype=int).reshape(-1)
    forces = np.asarray(stage.fastener_forces, dtype=float).reshape(-1)
    if forces.shape != pairs.shape or (pairs.size and (pairs.min() < 0 or pairs.max() >= k)):
        raise InvalidInputError(
            f"{what}: fasteners must be pair indices below {k}, one fastener_forces value each"
        )
    tension = np.zeros(k)
    tension[pairs] = forces
    return SimpleNamespace(
        label=str(stage.label),
        success=bool(stage.success),
        gaps=arrays["gaps"].astype(float),
        normal_forces=arrays["normal_forces"].astype(float),
        tangential_forces=arrays["tangential_forces"].astype(float),
        status=status,
        slip=arrays["slip"].astype(float),
        fasteners=pairs,
        fastener_forces=forces,
        tension=tension,
    )


def stage_rows(
    stage: Any, points: ArrayLike, number: int = 1, initial_gaps: ArrayLike | None = None
) -> list[list]:
    """The rows of ``stages.csv`` of one stage (``number``: its place in the sequence), with
    an ``initial_gap`` column when ``initial_gaps`` (k,) are given."""
    (xyz,) = _geometry(points)
    s = _checked(stage, len(xyz), number)
    initial = _initial_gaps(initial_gaps, len(xyz))
    columns = [
        [number] * len(xyz),
        [s.label] * len(xyz),
        range(len(xyz)),
        *xyz.T.tolist(),
        *([] if initial is None else [initial.tolist()]),
        s.gaps.tolist(),
        s.normal_forces.tolist(),
        *s.tangential_forces.T.tolist(),
        status_labels(s.status),
        *s.slip.T.tolist(),
        s.tension.tolist(),
    ]
    return [list(row) for row in zip(*columns, strict=True)]


def write_stage_table(
    path: str | os.PathLike[str],
    sequence: Any,
    points: ArrayLike,
    initial_gaps: ArrayLike | None = None,
) -> Path:
    """Write ``stages.csv``: every pair of every stage, one row each (header
    :data:`STAGE_HEADER`; module docstring).

    Parameters
    ----------
    path : str or Path
    sequence : AssemblySequence or sequence of AssemblyStage
    points : array_like, shape (k, 3)
        Pair positions (m).
    initial_gaps : array_like, shape (k,), optional
        The gaps before fastening (m): an ``initial_gap (m)`` column before ``gap (m)``.
    """
    stages = _stages(sequence)
    header = list(STAGE_HEADER)
    if initial_gaps is not None:
        header.insert(INITIAL_GAP_COLUMN, "initial_gap (m)")
    rows = (
        row
        for n, stage in enumerate(stages, 1)
        for row in stage_rows(stage, points, n, initial_gaps)
    )
    return write_rows(path, header, rows)


def write_fastener_table(path: str | os.PathLike[str], sequence: Any, points: ArrayLike) -> Path:
    """Write ``fasteners.csv``: every installed fastener's force at every stage (header
    :data:`FASTENER_HEADER`; module docstring)."""
    (xyz,) = _geometry(points)
    rows = []
    for number, stage in enumerate(_stages(sequence), 1):
        s = _checked(stage, len(xyz), number)
        for rank, (pair, force) in enumerate(zip(s.fasteners, s.fastener_forces, strict=True)):
            rows.append([number, s.label, rank + 1, int(pair), *xyz[pair].tolist(), float(force)])
    return write_rows(path, FASTENER_HEADER, rows)


def stage_mesh(
    stage: Any,
    points: ArrayLike,
    normals: ArrayLike,
    number: int = 1,
    initial_gaps: ArrayLike | None = None,
) -> PointMesh:
    """One stage's pairs as vertices with their fields, for
    :func:`~contactqp.io.export.write_vtu` (``write_vtu(path, *stage_mesh(...))``).

    Point data (SI): ``gap`` (m), ``normal_force`` (N, compression), ``tangential_force``
    (N, on the first part, components along ``t1, t2`` of
    :func:`~contactqp.core.contact.tangent_basis`), ``contact_force`` (N, the contact force on
    the first part as a vector in x, y, z: ``-normal_force n + tangential_force . (t1, t2)``),
    ``slip`` (m, the stage's increment along ``t1, t2``), ``status`` (codes of
    :data:`~contactqp.core.status.STATUS_LABELS`), ``fastener_force`` (N, tension, 0 away from
    installed fasteners), ``normal`` (the pair normal); given ``initial_gaps`` (k,), also
    ``initial_gap`` (m).
    """
    xyz, n = _geometry(points, normals)
    s = _checked(stage, len(xyz), number)
    initial = _initial_gaps(initial_gaps, len(xyz))
    tangents = tangent_basis(n)  # (k, 2, 3)
    force = -s.normal_forces[:, None] * n + np.einsum("kj,kjd->kd", s.tangential_forces, tangents)
    data = {
        "gap": s.gaps,
        "normal_force": s.normal_forces,
        "tangential_force": s.tangential_forces,
        "contact_force": force,
        "slip": s.slip,
        "status": s.status,
        "fastener_force": s.tension,
        "normal": n,
    }
    if initial is not None:
        data["initial_gap"] = initial
    return PointMesh(xyz, [("vertex", np.arange(len(xyz)).reshape(-1, 1))], data)


def write_stage_meshes(
    directory: str | os.PathLike[str],
    sequence: Any,
    points: ArrayLike,
    normals: ArrayLike,
    *,
    stem: str = "stage",
    initial_gaps: ArrayLike | None = None,
) -> dict[str, Path]:
    """Write one VTU per stage (``stage_001.vtu``, ...; :func:`stage_mesh`) and
    ``stages.pvd``, their ParaView collection (time step = stage number);
    ``{file name: path}``."""
    directory = Path(directory)
    files = {}
    collection = ElementTree.Element("VTKFile", type="Collection", version="0.1")
    datasets = ElementTree.SubElement(collection, "Collection")
    for number, stage in enumerate(_stages(sequence), 1):
        name = f"{stem}_{number:03d}.vtu"
        files[name] = write_vtu(
            directory / name, *stage_mesh(stage, points, normals, number, initial_gaps)
        )
        ElementTree.SubElement(datasets, "DataSet", timestep=str(number), part="0", file=name)
    pvd = directory / f"{stem}s.pvd"
    ElementTree.indent(collection)
    ElementTree.ElementTree(collection).write(pvd, encoding="utf-8", xml_declaration=True)
    files[pvd.name] = pvd
    return files


def shim_pairs(stage: Any, shim_tolerance: float) -> np.ndarray:
    """The pairs (indices, ascending) whose residual gap in ``stage`` is above
    ``shim_tolerance`` (m, strictly): where a shim is needed."""
    tolerance = shim_tolerance_value(shim_tolerance)
    gaps = np.asarray(stage.gaps, dtype=float).reshape(-1)
    return np.flatnonzero(gaps > tolerance)


def write_shim_table(
    path: str | os.PathLike[str], stage: Any, points: ArrayLike, shim_tolerance: float
) -> Path:
    """Write ``shims.csv``: the pairs of :func:`shim_pairs`, one row each: ``pair``, ``x (m)``,
    ``y (m)``, ``z (m)``, ``gap (m)``."""
    (xyz,) = _geometry(points)
    s = _checked(stage, len(xyz), 1)
    pairs = shim_pairs(stage, shim_tolerance)
    rows = ([int(p), *xyz[p].tolist(), float(s.gaps[p])] for p in pairs)
    return write_rows(path, ["pair", "x (m)", "y (m)", "z (m)", "gap (m)"], rows)


def fastener_force_history(sequence: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(pairs, forces)``: the pair of each fastener in order of first installation (f,) and
    its force after each stage (s, f), N, NaN before it is installed."""
    stages = _stages(sequence)
    installed = [np.asarray(stage.fasteners, dtype=int).reshape(-1) for stage in stages]
    pairs = list(dict.fromkeys(int(p) for stage_pairs in installed for p in stage_pairs))
    column = {pair: j for j, pair in enumerate(pairs)}
    forces = np.full((len(stages), len(pairs)), np.nan)
    for i, (stage, stage_pairs) in enumerate(zip(stages, installed, strict=True)):
        values = np.asarray(stage.fastener_forces, dtype=float).reshape(-1)
        if values.shape != stage_pairs.shape:
            raise InvalidInputError(
                f"stage {i + 1}: {len(stage_pairs)} fasteners, {len(values)} fastener_forces"
            )
        forces[i, [column[int(p)] for p in stage_pairs]] = values
    return np.array(pairs, dtype=int), forces


def map_plane(points: ArrayLike, normals: ArrayLike) -> tuple[np.ndarray, tuple[str, str]]:
    """``(xy, axis_labels)``: the pair positions drawn on a map, in the coordinate plane most
    nearly normal to the mean pair normal (normal mostly along z: x, y; along x: y, z; along
    y: z, x), and the names of the map's axes in mm."""
    xyz, n = _geometry(points, normals)
    across = int(np.argmax(np.abs(n.mean(axis=0)))) if len(n) else 2
    first, second = (across + 1) % 3, (across + 2) % 3
    names = "xyz"
    return xyz[:, [first, second]], (f"{names[first]} (mm)", f"{names[second]} (mm)")


def _gap_map(stage: Any, points: ArrayLike, normals: ArrayLike) -> dict[str, Any]:
    """What :func:`~contactqp.io.plot.point_maps_figure` takes to draw a stage's gap map."""
    xy, axes = map_plane(points, normals)
    s = _checked(stage, len(xy), 1)
    return {
        "points": xy,
        "panels": [(s.gaps * 1e3, f"residual gap (mm), {s.label}", "viridis")],
        "marked": xy[s.fasteners] if s.fasteners.size else None,
        "marked_label": "fasteners",
        "axis_labels": axes,
    }


def _status_map(stage: Any, points: ArrayLike, normals: ArrayLike) -> dict[str, Any]:
    """What :func:`~contactqp.io.plot.point_maps_figure` takes to draw a stage's status map."""
    from ...io.plot import STATUS_COLOURS

    xy, axes = map_plane(points, normals)
    s = _checked(stage, len(xy), 1)
    labels = np.array(status_labels(s.status), dtype=str)
    return {
        "points": xy,
        "panels": [(labels, f"status, {s.label}", STATUS_COLOURS)],
        "axis_labels": axes,
    }


def _fastener_series(sequence: Any) -> tuple[list[str], np.ndarray, list[str]]:
    """``(stage labels, forces (s, f), fastener names)`` for the fastener force plot."""
    stages = _stages(sequence)
    pairs, forces = fastener_force_history(stages)
    return [str(stage.label) for stage in stages], forces, [f"pair {pair}" for pair in pairs]


def gap_map_figure(stage: Any, points: ArrayLike, normals: ArrayLike) -> Any:
    """Map of a stage's residual gap (mm, colour scale), its installed fasteners marked."""
    from ...io.plot import point_maps_figure

    return point_maps_figure(**_gap_map(stage, points, normals))


def status_map_figure(stage: Any, points: ArrayLike, normals: ArrayLike) -> Any:
    """Map of a stage's pair status: one colour per status present
    (:data:`~contactqp.io.plot.STATUS_COLOURS`), named in the legend."""
    from ...io.plot import point_maps_figure

    return point_maps_figure(**_status_map(stage, points, normals))


def fastener_forces_figure(sequence: Any) -> Any:
    """Each fastener's force (N) against the stages, one line per fastener."""
    from ...io import plot

    return plot.fastener_forces_figure(*_fastener_series(sequence))


def write_plots(
    directory: str | os.PathLike[str], sequence: Any, points: ArrayLike, normals: ArrayLike
) -> dict[str, Path]:
    """Write ``gap.png`` and ``status.png`` (the last stage) and ``fastener_forces.png``."""
    from ...io.plot import plot_fastener_forces, plot_point_maps

    directory = Path(directory)
    stages = _stages(sequence)
    return {
        "gap.png": plot_point_maps(
            path=directory / "gap.png", **_gap_map(stages[-1], points, normals)
        ),
        "status.png": plot_point_maps(
            path=directory / "status.png", **_status_map(stages[-1], points, normals)
        ),
        "fastener_forces.png": plot_fastener_forces(
            *_fastener_series(stages), directory / "fastener_forces.png"
        ),
    }


def write_sequence(
    directory: str | os.PathLike[str],
    sequence: Any,
    points: ArrayLike,
    normals: ArrayLike,
    *,
    initial_gaps: ArrayLike | None = None,
    shim_tolerance: float | None = None,
    plot: bool = False,
) -> dict[str, Path]:
    """Write every file of a fastening sequence (module docstring) into ``directory``.

    Parameters
    ----------
    directory : str or Path
        Made if missing; files there of the same names are overwritten.
    sequence : AssemblySequence or sequence of AssemblyStage
    points, normals : array_like, shape (k, 3)
        Pair positions (m) and unit normals (from the first part towards the second).
    initial_gaps : array_like, shape (k,), optional
        The gaps before fastening (m), written beside the residual ones (CSV and VTU).
    shim_tolerance : float, optional
        Gap (m) above which a pair needs a shim: writes ``shims.csv`` (the last stage).
    plot : bool
        Also write the PNG figures (the ``plot`` extra).

    Returns
    -------
    dict of str to Path
        Each file written, by name.
    """
    directory = Path(directory)
    stages = _stages(sequence)
    files = {
        "stages.csv": write_stage_table(directory / "stages.csv", stages, points, initial_gaps),
        "fasteners.csv": write_fastener_table(directory / "fasteners.csv", stages, points),
    }
    files.update(write_stage_meshes(directory, stages, points, normals, initial_gaps=initial_gaps))
    if shim_tolerance is not None:
        files["shims.csv"] = write_shim_table(
            directory / "shims.csv", stages[-1], points, shim_tolerance
        )
    if plot:
        files.update(write_plots(directory, stages, points, normals))
    return files


def _statistics_columns(statistics: GapStatistics) -> dict[str, np.ndarray]:
    """``{header: values}`` of the per-pair statistics (with units)."""
    columns = {"mean_gap (m)": np.asarray(statistics.mean)}
    for level, values in zip(statistics.levels, statistics.quantiles, strict=True):
        columns[f"gap_q{level * 100:g} (m)"] = np.asarray(values)
    columns["contact_probability (-)"] = np.asarray(statistics.contact_probability)
    if statistics.shim_probability is not None:
        columns["shim_probability (-)"] = np.asarray(statistics.shim_probability)
    return columns


def write_statistics(
    path: str | os.PathLike[str], statistics: GapStatistics, points: ArrayLike
) -> Path:
    """Write the variation study's per-pair statistics as CSV, one row per pair.

    Columns: ``pair``, ``x (m)``, ``y (m)``, ``z (m)``, ``mean_gap (m)``, one ``gap_qL (m)``
    per quantile level (``L`` in percent, e.g. ``gap_q95 (m)``), ``contact_probability (-)``
    and, when the statistics have a shim tolerance, ``shim_probability (-)`` (the fraction of
    samples whose residual gap is above it).
    """
    (xyz,) = _geometry(points)
    columns = _statistics_columns(statistics)
    for name, values in columns.items():
        if values.shape != (len(xyz),):
            raise InvalidInputError(f"statistics {name}: {values.shape} for {len(xyz)} pairs")
    header = ["pair", "x (m)", "y (m)", "z (m)", *columns]
    rows: Iterable = zip(
        range(len(xyz)), *xyz.T.tolist(), *(v.tolist() for v in columns.values()), strict=True
    )
    return write_rows(path, header, rows)


def _statistics_maps(
    statistics: GapStatistics, points: ArrayLike, normals: ArrayLike
) -> dict[str, Any]:
    """What :func:`~contactqp.io.plot.point_maps_figure` takes to draw the study's maps."""
    from ...io.plot import MapPanel

    xy, axes = map_plane(points, normals)
    samples = f", {statistics.samples} samples"
    panels = [
        MapPanel(np.asarray(statistics.mean) * 1e3, f"mean residual gap (mm){samples}"),
        MapPanel(
            statistics.contact_probability, f"probability of contact{samples}", "viridis", (0, 1)
        ),
    ]
    if statistics.shim_probability is not None and statistics.shim_tolerance is not None:
        title = f"probability of a gap above {statistics.shim_tolerance * 1e3:.4g} mm{samples}"
        panels.append(MapPanel(statistics.shim_probability, title, "magma", (0, 1)))
    return {"points": xy, "panels": panels, "axis_labels": axes}


def statistics_map_figure(statistics: GapStatistics, points: ArrayLike, normals: ArrayLike) -> Any:
    """Maps of the mean residual gap (mm), the probability of contact and, with a shim
    tolerance, the probability of a gap above it (both on the scale 0 to 1)."""
    from ...io.plot import point_maps_figure

    return point_maps_figure(**_statistics_maps(statistics, points, normals))


def plot_statistics_maps(
    statistics: GapStatistics,
    points: ArrayLike,
    normals: ArrayLike,
    path: str | os.PathLike[str],
) -> Path:
    """Write the maps of :func:`statistics_map_figure` to ``path`` (its suffix chooses the
    format)."""
    from ...io.plot import plot_point_maps

    return plot_point_maps(path=path, **_statistics_maps(statistics, points, normals))


def sequence_summary(sequence: Any, *, shim_tolerance: float | None = None) -> dict[str, Any]:
    """A JSON-ready summary of a sequence (SI units).

    ``{"success": bool, "pairs": k, "stages": [{"stage", "label", "success", "max_gap" (m),
    "contacts" ({status label: count}, every label), "fasteners" (pairs, installation order),
    "fastener_forces" (N)}, ...]}``; with ``shim_tolerance`` (m), each stage also has
    ``"shims"`` (pairs above it) and the summary ``"shim_tolerance"`` and ``"shim_pairs"``
    (the last stage's pairs above it).
    """
    tolerance = None if shim_tolerance is None else shim_tolerance_value(shim_tolerance)
    stages = _stages(sequence)
    k = len(np.asarray(stages[0].gaps))
    rows = []
    for number, stage in enumerate(stages, 1):
        s = _checked(stage, k, number)
        rows.append(
            {
                "stage": number,
                "label": s.label,
                "success": s.success,
                "max_gap": float(s.gaps.max()) if k else 0.0,
                "contacts": status_counts(s.status),
                "fasteners": s.fasteners.tolist(),
                "fastener_forces": s.fastener_forces.tolist(),
            }
        )
        if tolerance is not None:
            rows[-1]["shims"] = int(np.count_nonzero(s.gaps > tolerance))
    summary: dict[str, Any] = {
        "success": all(row["success"] for row in rows),
        "pairs": k,
        "stages": rows,
    }
    if tolerance is not None:
        summary["shim_tolerance"] = tolerance
        summary["shim_pairs"] = shim_pairs(stages[-1], tolerance).tolist()
    return summary


def sequence_table(
    sequence: Any, *, title: str | None = None, shim_tolerance: float | None = None
) -> Any:
    """A :class:`rich.table.Table` of a sequence, one row per stage: label, success, largest
    gap (mm), the pairs of each status present in any stage, with ``shim_tolerance`` the pairs
    above it, and the newest fastener's force, the smallest and the largest fastener force (N)."""
    from rich.table import Table

    summary = sequence_summary(sequence, shim_tolerance=shim_tolerance)
    shims = [] if shim_tolerance is None else [f"gap > {summary['shim_tolerance'] * 1e3:.4g} mm"]
    present = [
        label for label in STATUS_LABELS if any(row["contacts"][label] for row in summary["stages"])
    ]
    table = Table(title=title or f"Fastening sequence ({summary['pairs']} pairs)")
    table.add_column("stage", justify="right")
    table.add_column("label")
    table.add_column("ok")
    for column in ("max gap (mm)", *present, *shims, "newest fastener (N)", "min (N)", "max (N)"):
        table.add_column(column, justify="right")
    for row in summary["stages"]:
        forces = row["fastener_forces"]
        numbers = [f"{f:.4g}" for f in (forces[-1], min(forces), max(forces))] if forces else []
        table.add_row(
            str(row["stage"]),
            row["label"],
            "yes" if row["success"] else "[red]no[/red]",
            f"{row['max_gap'] * 1e3:.4g}",
            *(str(row["contacts"][label]) for label in present),
            *([str(row["shims"])] if shims else []),
            *(numbers or ["-"] * 3),
        )
    return table

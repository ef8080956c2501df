"""An assembly file's whole study as one call: nominal fastening sequence, variation, outputs.

:func:`run_assembly_study` does what ``contactqp assembly`` does (the command only parses its
options, calls it and prints). It reads the assembly file
(:func:`~contactqp.applications.assembly_file.read_assembly_file`), builds its
:class:`~contactqp.applications.fastening.Assembly`, runs the nominal sequence (the fasteners in
the file's order, then its load steps, with its solver) and writes, in the output directory
(:func:`~contactqp.applications.fastening.output.write_sequence`):

- ``stages.csv``, ``fasteners.csv``: every pair and every fastener at every stage;
- ``stage_001.vtu``, ... and ``stages.pvd``: the stages for ParaView;
- with a shim tolerance, ``shims.csv``; with ``plot``, ``gap.png``, ``status.png`` and
  ``fastener_forces.png``.

When the file has a ``[variation]`` table, it then runs the resumable variation study
(:class:`~contactqp.applications.fastening.study.SequenceVariation` through
:func:`~contactqp.studies.run_batch`, on a local pool or a Dask cluster, the same numbers
either way) and writes:

- ``samples.h5``: one row per sample (a study already there is continued);
- ``statistics.csv``: mean and quantiles of the residual gap, probability of contact and of a
  gap above the shim tolerance, per pair
  (:func:`~contactqp.applications.fastening.output.write_statistics`);
- with ``plot``, ``statistics.png``: their maps.
"""

from __future__ import annotations

import dataclasses
import numbers
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...errors import InvalidInputError
from ...studies import BatchSummary, GapStatistics, GaussianGapField, load_batch, run_batch
from ...studies.executors import check_scheduler
from .model import Assembly
from .output import plot_statistics_maps, write_sequence, write_statistics
from .stage import AssemblySequence
from .study import SequenceVariation

__all__ = ["AssemblyStudy", "run_assembly_study", "DEFAULT_SAMPLES", "OUTPUT_NAMES"]

#: Samples of a study on random gap fields when neither the call nor the file says.
DEFAULT_SAMPLES = 1000

#: The names of the files a study may write (``stage_NNN.vtu`` stands for each stage's VTU).
OUTPUT_NAMES = (
    "stages.csv",
    "fasteners.csv",
    "stages.pvd",
    "shims.csv",
    "gap.png",
    "status.png",
    "fastener_forces.png",
    "samples.h5",
    "statistics.csv",
    "statistics.png",
)


@dataclass
class AssemblyStudy:
    """What :func:`run_assembly_study` computed and wrote.

    Attributes
    ----------
    input : AssemblyInput
        The assembly file, read.
    assembly : Assembly
        Its parts, pairs, fasteners and friction.
    nominal : AssemblySequence
        The fasteners installed in the file's order on the nominal gaps, then the load steps.
    summary : BatchSummary or None
        What the variation study did (samples computed, reused, failed); None without a study.
    statistics : GapStatistics or None
        Per-pair statistics of the successful samples, with the file's shim tolerance; None
        without a study or when every sample failed (then ``statistics.csv`` is not written).
    files : dict of str to Path
        Each file written, by name (``"stages.csv"``, ``"samples.h5"``, ...).
    """

    input: Any
    assembly: Assembly
    nominal: AssemblySequence
    summary: BatchSummary | None
    statistics: GapStatistics | None
    files: dict[str, Path] = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """The nominal sequence succeeded and, with a study, so did every sample."""
        if not self.nominal.success:
            return False
        if self.summary is None:
            return True
        return self.summary.failed == 0 and self.statistics is not None

    @property
    def interpolation_error(self) -> Any:
        """The leave-one-out error of the gaps interpolated from a measured cloud
        (:class:`~contactqp.applications.assembly_file.InterpolationError`), or None."""
        return self.input.interpolation_error

    @property
    def unmatched(self) -> tuple:
        """Nodes that proximity pairing left without a partner
        (:class:`~contactqp.applications.assembly_file.UnmatchedNodes`, one per interface
        that has some)."""
        return tuple(self.input.unmatched)

    def notes(self) -> list[str]:
        """One line each: the interpolation error, the unmatched nodes and the variation."""
        lines = []
        if self.interpolation_error is not None:
            lines.append(self.interpolation_error.describe())
        lines.extend(item.describe() for item in self.unmatched)
        if self.input.variation is not None:
            lines.append(f"variation: {self.input.variation_description}")
        return lines


def run_assembly_study(
    assembly_file: str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    samples: int | None = None,
    seed: int | None = None,
    workers: int = 1,
    scheduler: str | None = None,
    plot: bool = False,
    progress: Callable[[int, int], None] | None = None,
    names: dict[str, str] | None = None,
) -> AssemblyStudy:
    """Run (or resume) the study of an assembly file into the directory ``out``.

    Parameters
    ----------
    assembly_file : str or Path
        The ``ASSEMBLY.toml`` (schema: the assembly-file reference).
    out : str or Path
        Output directory (made if missing; it may be the assembly file's own). A study already
        there is resumed; a store of another study is refused before anything is written.
    samples : int, optional
        Samples of the variation study; default 1000 for random fields, every realisation for
        a file of them. Refused when the file has no ``[variation]``.
    seed : int, optional
        Root seed of the random gap fields, instead of the file's ``variation.seed``: sample
        ``k`` is the same whatever the workers. Refused unless the variation is random.
    workers : int
        Local worker processes (ignored with ``scheduler``).
    scheduler : str, optional
        Dask scheduler address (``tcp://host:port``), checked before any solve. ``workers``
        and ``scheduler`` are not used without a ``[variation]``.
    plot : bool
        Also write the figures (the ``plot`` extra; without it a
        :class:`~contactqp.errors.MissingDependencyError` once the nominal files are written).
    progress : callable, optional
        ``progress(done, samples)`` after each stored chunk of samples.
    names : dict, optional
        How messages name the parameters (e.g. ``{"samples": "--samples"}`` for a command
        line); default their names.

    Returns
    -------
    AssemblyStudy
        Check :attr:`AssemblyStudy.success`: a failed solve is not an exception; what was
        computed is written.

    Raises
    ------
    InvalidInputError
        Bad parameters, an ``out`` that is a file or would overwrite one of the study's input
        files, a bad assembly file (the message names the key), or a store of another study
        in ``out``.
    """

    def name(parameter: str) -> str:
        return (names or {}).get(parameter, parameter)

    samples = _count(samples, name("samples"), minimum=1)
    seed = _count(seed, name("seed"), minimum=0)
    workers_count = _count(workers, name("workers"), minimum=1, required=True)
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InvalidInputError(f"{name('out')}: '{out}' is a file, not a directory")

    from ..assembly_file import read_assembly_file

    given = read_assembly_file(Path(assembly_file))
    _check_no_overwrite(Path(assembly_file), out, name("out"))
    assembly = given.to_assembly()
    given = _seeded(given, seed, name)
    source, samples = _variation_source(given, samples, seed, name)
    options = {"load_steps": given.load_steps, "method": given.method, **given.options}
    case = None
    if source is None:
        nominal = assembly.sequence(given.gaps, **options)
    else:
        if scheduler is not None:  # a bad address is told before the nominal solve
            check_scheduler(scheduler)
        case = SequenceVariation(assembly, given.gaps, **options)
        nominal = case.nominal
    out.mkdir(parents=True, exist_ok=True)
    store = out / "samples.h5"
    if case is not None:
        # a store of another study in out is refused before the nominal files are written
        run_batch(case, source, samples, store, scheduler=scheduler, limit=0)
    files = write_sequence(
        out,
        nominal,
        assembly.points,
        assembly.normals,
        initial_gaps=given.gaps,
        shim_tolerance=given.shim_tolerance,
        plot=plot,
    )
    if case is None:
        return AssemblyStudy(given, assembly, nominal, None, None, files)
    summary = run_batch(
        case,
        source,
        samples,
        store,
        workers=workers_count,
        scheduler=scheduler,
        progress=progress,
    )
    files["samples.h5"] = store
    data = load_batch(store, samples)  # not the rest of a longer past study
    if not data.fields["success"].any():  # a failed solve, not bad input
        return AssemblyStudy(given, assembly, nominal, summary, None, files)
    statistics = data.statistics(shim_tolerance=given.shim_tolerance)
    files["statistics.csv"] = write_statistics(out / "statistics.csv", statistics, assembly.points)
    if plot:
        files["statistics.png"] = plot_statistics_maps(
            statistics, assembly.points, assembly.normals, out / "statistics.png"
        )
    return AssemblyStudy(given, assembly, nominal, summary, statistics, files)


def _count(value: Any, what: str, *, minimum: int, required: bool = False) -> Any:
    """``value`` as an int >= ``minimum`` (None stays None unless ``required``); else one
    clear line."""
    if value is None and not required:
        return None
    if not isinstance(value, numbers.Integral) or isinstance(value, bool) or value < minimum:
        raise InvalidInputError(f"{what} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _seeded(given: Any, seed: int | None, name) -> Any:
    """``given`` with its random gap fields drawn from ``seed`` instead of the file's (and
    its variation's description saying so); as it is without a seed or a random variation."""
    source = given.variation
    if seed is None or not isinstance(source, GaussianGapField):
        return given
    seeded = GaussianGapField(
        source.coordinates, source.amplitude, source.correlation_length, source.mean, seed
    )
    description = given.variation_description.rsplit(", seed ", 1)[0]
    return dataclasses.replace(
        given,
        variation=seeded,
        variation_description=f"{description}, seed {seed} ({name('seed')})",
    )


def _variation_source(given: Any, samples: int | None, seed: int | None, name) -> tuple:
    """``(gap source, samples)`` of the study, or ``(None, None)`` without a variation."""
    source = given.variation
    if source is None:
        for parameter, value in (("samples", samples), ("seed", seed)):
            if value is not None:
                raise InvalidInputError(
                    f"{name(parameter)}: the assembly file has no [variation] table to sample"
                )
        return None, None
    if isinstance(source, GaussianGapField):
        return source, DEFAULT_SAMPLES if samples is None else samples
    if seed is not None:
        raise InvalidInputError(
            f"{name('seed')}: the variation is not random ({given.variation_description}); "
            "it has no seed"
        )
    available = int(source.n_available)
    if samples is not None and samples > available:
        raise InvalidInputError(
            f"{name('samples')}: {samples} asked, the variation has {available} realisations"
        )
    return source, available if samples is None else samples


def _written(path: Path) -> bool:
    """Whether a study may write a file of this name."""
    return path.name in OUTPUT_NAMES or (path.name.startswith("stage_") and path.suffix == ".vtu")


def _check_no_overwrite(assembly_file: Path, out: Path, what: str) -> None:
    """Refuse an ``out`` where the study would write over the assembly file or a file it names
    (any string value of the file that, relative to its directory, names a file in ``out``)."""
    import tomllib

    out = out.resolve()
    base = assembly_file.resolve().parent
    inputs = [assembly_file.resolve()]
    with open(assembly_file, "rb") as handle:  # read already: valid TOML
        pending: list[Any] = [tomllib.load(handle)]
    while pending:
        value = pending.pop()
        if isinstance(value, dict):
            pending.extend(value.values())
        elif isinstance(value, list):
            pending.extend(value)
        elif isinstance(value, str) and value:
            inputs.append((base / Path(value).expanduser()).resolve())
    for path in inputs:
        if path.parent == out and _written(path):
            raise InvalidInputError(f"{what}: the study would overwrite its input file '{path}'")

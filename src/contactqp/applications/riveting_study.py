"""The riveting variation study as one call: model, nominal fastening, sample study, outputs.

:func:`run_riveting_study` does what ``contactqp riveting`` does (the command only parses its
options, calls it and prints): it builds the assembly's reduced model, installs the fasteners
one by one on the nominal gap field, runs the resumable variation study over a gap source
(:mod:`contactqp.studies`) with every fastener installed, computes the per-pair statistics
and writes, in the output directory:

- ``nominal.vtu``, ``nominal_contacts.csv``, ``nominal_sequence.csv``: the nominal state;
- ``samples.h5``: one row per sample (resumable: a study already there is continued);
- ``statistics.csv``: mean, quantiles of the final gap and probability of contact per pair;
- with ``plot``: ``nominal.png`` and ``statistics.png``.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..core.status import ContactStatus
from ..errors import ContactWarning, InvalidInputError
from ..io.export import write_csv, write_vtu
from ..studies import (
    BatchSummary,
    GapSamples,
    GapStatistics,
    GaussianGapField,
    load_batch,
    load_gap_samples,
    run_batch,
)
from .riveting import (
    Assembly,
    FasteningCase,
    FasteningSequence,
    RivetingModel,
    result_mesh,
)

__all__ = ["RivetingStudy", "run_riveting_study"]

#: Samples of a study on random gap fields when none are asked for.
DEFAULT_SAMPLES = 1000


@dataclass
class RivetingStudy:
    """What :func:`run_riveting_study` computed and wrote.

    Attributes
    ----------
    model : RivetingModel
        The assembly's reduced model.
    nominal_gaps : ndarray, shape (k,)
        The nominal gap field (m): the source's mean.
    sequence : FasteningSequence
        The fasteners installed one by one on the nominal gaps.
    summary : BatchSummary
        What the variation study did (samples computed, reused, failed).
    statistics : GapStatistics or None
        Per-pair statistics of the successful samples; None when every sample failed (then
        ``statistics.csv`` is not written).
    files : dict of str to Path
        Each file written, by name (``"nominal.vtu"``, ``"samples.h5"``, ...).
    """

    model: RivetingModel
    nominal_gaps: np.ndarray
    sequence: FasteningSequence
    summary: BatchSummary
    statistics: GapStatistics | None
    files: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """The nominal sequence succeeded and so did every sample."""
        return self.sequence.success and self.summary.failed == 0 and self.statistics is not None


def run_riveting_study(
    out: str | PathLike[str],
    *,
    samples: int | None = None,
    seed: int = 0,
    workers: int = 1,
    scheduler: str | None = None,
    gaps: str | PathLike[str] | ArrayLike | None = None,
    mean_gap: float = 2e-4,
    amplitude: float = 1e-4,
    correlation_length: float = 0.04,
    method: str = "lawson-hanson",
    plot: bool = False,
    assembly: Assembly | None = None,
    progress: Callable[[int, int], None] | None = None,
    names: dict[str, str] | None = None,
) -> RivetingStudy:
    """Run (or resume) the riveting variation study into the directory ``out``.

    Parameters
    ----------
    out : str or Path
        Output directory (made if missing); a study already there is resumed, a store of
        another study refused before anything is written.
    samples : int, optional
        Samples of the study; default 1000, or every row of ``gaps``.
    seed : int
        Root seed of the random gap fields: sample ``k`` is the same whatever the workers.
    workers : int
        Local worker processes (ignored with ``scheduler``).
    scheduler : str, optional
        Dask scheduler address (``tcp://host:port``).
    gaps : str, Path or array_like, shape (N, k), optional
        Gap realisations (m), one per row, as an array or a file (``.npy``, ``.npz``, ``.csv``),
        instead of random fields; the nominal gap is then their mean.
    mean_gap, amplitude, correlation_length : float
        The random gap fields (m): nominal gap (negative: interference), standard deviation and
        correlation length (:class:`~contactqp.studies.GaussianGapField`).
    method : {"lawson-hanson", "active-set", "nnls"}
        Solver of the nominal steps and of each sample
        (``contactqp.solve`` of the fastened problem, kind ``"fastened"``).
    plot : bool
        Also write ``nominal.png`` and ``statistics.png``.
    assembly : Assembly, optional
        Default: ``Assembly()``, two 200 x 100 x 2 mm aluminium plates, 525 pairs.
    progress : callable, optional
        ``progress(done, samples)`` after each stored chunk of samples.
    names : dict, optional
        How messages name the parameters (e.g. ``{"mean_gap": "--mean-gap"}`` for a command
        line); default their names.

    Returns
    -------
    RivetingStudy

    Warns
    -----
    ContactWarning
        A nominal gap or amplitude beyond the plate thickness (far from small deflections), or
        a negative ``mean_gap`` (interference).

    Raises
    ------
    InvalidInputError
        Bad parameters, a gap file of the wrong width or unreadable, an overlap deeper than a
        plate, or a store of another study in ``out``.
    """

    def name(parameter: str) -> str:
        return (names or {}).get(parameter, parameter)

    model = (Assembly() if assembly is None else assembly).build()
    source: GapSamples | GaussianGapField
    if gaps is not None:
        source = load_gap_samples(gaps) if isinstance(gaps, (str, PathLike)) else GapSamples(gaps)
        nominal_gaps = source.samples.mean(axis=0)
        samples = source.n_available if samples is None else samples
    else:
        source = GaussianGapField(
            model.points, amplitude, correlation_length, mean=mean_gap, seed=seed
        )
        nominal_gaps = source.mean
        samples = DEFAULT_SAMPLES if samples is None else samples
    if nominal_gaps.shape != (model.n_pairs,):
        raise InvalidInputError(
            f"{name('gaps')}: gap realisations must have {model.n_pairs} "
            f"columns, got {nominal_gaps.shape[0]}"
        )
    # absurd gaps are refused before anything is written (unusual ones are warned about below)
    model.check_gaps(
        nominal_gaps, name("mean_gap") if gaps is None else f"the mean of {name('gaps')}"
    )
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    case = FasteningCase(model, method=method)
    store = out / "samples.h5"
    # a bad scheduler, or a store of another study in out, is refused before the nominal
    # files are written
    run_batch(case, source, samples, store, scheduler=scheduler, limit=0)
    sequence = model.fasten(nominal_gaps, method=method)
    # warnings once the input is known to be valid, so that bad input stays one line
    _warn_unusual_gaps(
        model.thickness,
        float(nominal_gaps.max()),
        amplitude if gaps is None else 0.0,
        mean_gap if gaps is None else 0.0,
        name,
    )
    files = _write_nominal(out, model, sequence, nominal_gaps)
    summary = run_batch(
        case, source, samples, store, workers=workers, scheduler=scheduler, progress=progress
    )
    files["samples.h5"] = store
    data = load_batch(store, samples)  # not the rest of a longer past study
    if not data.fields["success"].any():  # a failed solve, not bad input
        return RivetingStudy(model, nominal_gaps, sequence, summary, None, files)
    statistics = data.statistics()
    xy = model.points
    files["statistics.csv"] = write_csv(
        out / "statistics.csv",
        {
            "x": xy[:, 0],
            "y": xy[:, 1],
            "mean_gap": statistics.mean,
            **{
                f"gap_q{level * 100:g}": q
                for level, q in zip(statistics.levels, statistics.quantiles, strict=True)
            },
            "contact_probability": statistics.contact_probability,
        },
    )
    if plot:
        from ..io.plot import plot_statistics
        from .riveting import plot_status

        files["nominal.png"] = plot_status(model, sequence.final, nominal_gaps, out / "nominal.png")
        files["statistics.png"] = plot_statistics(statistics, xy, out / "statistics.png")
    return RivetingStudy(model, nominal_gaps, sequence, summary, statistics, files)


def _warn_unusual_gaps(
    thickness: float, largest_gap: float, amplitude: float, mean_gap: float, name
) -> None:
    """ContactWarnings for gaps that are valid but far from the plate model's range."""
    for what, value in [("nominal gap", largest_gap), (name("amplitude"), amplitude)]:
        if value > thickness:
            warnings.warn(
                f"{what} {value * 1e3:.4g} mm exceeds the {thickness * 1e3:.4g} mm "
                "plate thickness: far beyond small deflections, where the linear "
                "plate model holds",
                ContactWarning,
                stacklevel=3,
            )
    if mean_gap < 0:
        warnings.warn(
            f"{name('mean_gap')} {mean_gap:g} m is negative: the plates overlap by "
            f"{-mean_gap * 1e3:.4g} mm at rest (interference)",
            ContactWarning,
            stacklevel=3,
        )


def _write_nominal(
    out: Path, model: RivetingModel, sequence: FasteningSequence, nominal_gaps
) -> dict:
    """Write the nominal state's files; ``{name: path}``."""
    final = sequence.final
    xy = model.points
    nominal_mesh = result_mesh(model, final, nominal_gaps)
    files = {"nominal.vtu": write_vtu(out / "nominal.vtu", *nominal_mesh)}
    files["nominal_contacts.csv"] = write_csv(
        out / "nominal_contacts.csv",
        {
            "x": xy[:, 0],
            "y": xy[:, 1],
            "initial_gap": nominal_gaps,
            "gap": final.gaps,
            "force": final.forces,
            "status": final.status_labels,
        },
    )
    pairs = model.fasteners[sequence.order]
    files["nominal_sequence.csv"] = write_csv(
        out / "nominal_sequence.csv",
        {
            "step": np.arange(1, len(pairs) + 1),
            "pair": pairs,
            "x": xy[pairs, 0],
            "y": xy[pairs, 1],
            "tension": [step.fastener_forces[-1] for step in sequence.steps],
            "closed": [
                int(np.count_nonzero(step.contact_status == ContactStatus.CLOSED))
                for step in sequence.steps
            ],
            "max_gap": [float(step.gaps.max()) for step in sequence.steps],
        },
    )
    return files

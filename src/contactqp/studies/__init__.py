"""Variation studies: many samples of one problem, solved in a pool or on a cluster and stored
as they finish.

Modules: :mod:`.cases` (what one sample solves), :mod:`.sources` (gap fields),
:mod:`.store` (the resumable HDF5 store), :mod:`.executors` (serial, process pool, Dask),
:mod:`.statistics` (per-contact statistics) and :mod:`.batch` (the driver, :func:`run_batch`).
"""

from .batch import BatchSummary, run_batch
from .cases import GapVariation
from .executors import check_scheduler
from .sources import GapSamples, GaussianGapField, load_gap_samples
from .statistics import GapStatistics, gap_statistics
from .store import BatchData, load_batch

__all__ = [
    "BatchData",
    "BatchSummary",
    "GapSamples",
    "GapStatistics",
    "GapVariation",
    "GaussianGapField",
    "check_scheduler",
    "gap_statistics",
    "load_batch",
    "load_gap_samples",
    "run_batch",
]

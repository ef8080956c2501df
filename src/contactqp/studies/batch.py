"""Variation simulation: many gap fields on one reduced model, stored as they come, resumable.

A *case* (:mod:`~contactqp.studies.cases`) solves one sample from its initial gaps; a *source*
(:mod:`~contactqp.studies.sources`) gives the gaps of sample ``k``. :func:`run_batch` solves
samples ``0 .. N-1`` in chunks of consecutive samples, each sample warm started from the
previous one of its chunk, on an executor (:mod:`~contactqp.studies.executors`), and writes each
finished chunk to an HDF5 store (:mod:`~contactqp.studies.store`). Running it again on the same
file computes only the samples not yet done, with the warm start of the interrupted chunk read
back from the file, so the results do not depend on interruptions, on the number of workers or
on the executor (in-process, local process pool, Dask cluster).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InvalidInputError
from .executors import check_scheduler, executor
from .protocols import GapSource, StudyCase
from .store import BatchStore

__all__ = ["BatchSummary", "DEFAULT_CHUNK", "MAX_SAMPLES", "run_batch"]

DEFAULT_CHUNK = 50

#: Most samples of one study: 10^7 samples of tens of milliseconds each are days of work on
#: a workstation, and their store already holds 10^7 rows per field.
MAX_SAMPLES = 10**7


@dataclass(frozen=True)
class BatchSummary:
    """What a :func:`run_batch` call did.

    Attributes
    ----------
    samples : int
        Samples of the study (``N``).
    computed : int
        Samples solved by this call.
    reused : int
        Samples found already done in the store.
    failed : int
        Samples in the store whose solve failed (not converged or certificate failed).
    seconds : float
        Wall time of the call.
    path : Path
        The HDF5 store.
    """

    samples: int
    computed: int
    reused: int
    failed: int
    seconds: float
    path: Path

    @property
    def complete(self) -> bool:
        """True when every sample is done."""
        return self.computed + self.reused == self.samples

    def as_dict(self) -> dict:
        return {
            "samples": self.samples,
            "computed": self.computed,
            "reused": self.reused,
            "failed": self.failed,
            "seconds": self.seconds,
        }


def _store_all(results, store_chunk):
    """``store_chunk(indices, records)`` for each result of the generator ``results``.

    Ctrl-C while a chunk is stored (not only while waiting for the next) is thrown into
    ``results``, so an executor gives what its workers finish; the chunk being stored is stored
    again, whole. ``store_chunk`` must skip a chunk already stored.
    """
    current = None
    try:
        for current in results:
            store_chunk(*current)
            current = None
    except KeyboardInterrupt as interrupt:
        if current is not None:
            store_chunk(*current, report=False)
        try:
            store_chunk(*results.throw(interrupt), report=False)
            for current in results:
                store_chunk(*current, report=False)
        except StopIteration:
            pass
        raise
    finally:  # on any error: stop the executor now, not when the generator is collected
        results.close()


def run_batch(
    case: StudyCase,
    source: GapSource,
    n_samples: int,
    path: str | os.PathLike[str],
    *,
    workers: int = 1,
    scheduler: str | None = None,
    chunk_size: int = DEFAULT_CHUNK,
    limit: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> BatchSummary:
    """Solve samples ``0`` to ``n_samples - 1`` of ``source`` with ``case``; store and resume.

    Parameters
    ----------
    case : GapVariation
        Or any object with its methods (``n_contacts``, ``fields``, ``solve_sample``,
        ``warm_start``, ``describe``); picklable for workers.
    source : GaussianGapField or GapSamples
        Gap fields (``realisations(indices)``, ``describe()``, ``n_available``).
    n_samples : int
    path : str or Path
        HDF5 store, created or resumed (it must hold the same case and source).
    workers : int
        Local worker processes (1: in this process).
    scheduler : str, optional
        Address of a Dask distributed scheduler (see
        :func:`~contactqp.studies.executors.check_scheduler`); ``workers`` is then ignored.
    chunk_size : int
        Samples per task, for a new store (a resumed store keeps its own).
    limit : int, optional
        Solve at most this many samples in this call (a time budget; the rest on resume).
    progress : callable, optional
        ``progress(done, n_samples)`` after each stored chunk.

    Returns
    -------
    BatchSummary
    """
    start = time.perf_counter()
    if (
        isinstance(n_samples, bool)
        or int(n_samples) != n_samples
        or not 1 <= n_samples <= MAX_SAMPLES
    ):
        raise InvalidInputError(
            f"n_samples must be an integer from 1 to {MAX_SAMPLES:g}, got {n_samples!r}"
        )
    n_samples = int(n_samples)
    if source.n_available is not None and n_samples > source.n_available:
        raise InvalidInputError(
            f"asked for {n_samples} samples, the source has {source.n_available}"
        )
    if int(workers) < 1 or int(chunk_size) < 1:
        raise InvalidInputError(f"workers and chunk_size must be >= 1, got {workers}, {chunk_size}")
    if scheduler is not None:
        check_scheduler(scheduler)
    width = np.shape(source.realisations([0]))[-1]
    if width != case.n_contacts:  # before a store is made for a study that cannot run
        raise InvalidInputError(
            f"gap fields have {width} values, the case has {case.n_contacts} contacts"
        )
    path = Path(path)
    with BatchStore.open(path, case, source, n_samples, int(chunk_size)) as store:
        reused = int(np.count_nonzero(store.done(n_samples)))
        tasks = [
            (run, None if record is None else case.warm_start(record))
            for run, record in store.pending(n_samples, case.fields(), limit)
        ]
        results = executor((case, source), tasks, workers=int(workers), scheduler=scheduler)
        stored = {}  # first sample of each chunk stored by this call: its length

        def store_chunk(indices, records, report=True):
            first = int(indices[0])
            if first in stored:
                return
            store.write(indices, records)
            stored[first] = len(indices)
            if progress is not None and report:
                progress(reused + sum(stored.values()), n_samples)

        _store_all(results, store_chunk)
        computed = sum(stored.values())
        failed = store.failed(n_samples)
    return BatchSummary(n_samples, computed, reused, failed, time.perf_counter() - start, path)

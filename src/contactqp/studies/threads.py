"""One BLAS thread for the per-sample work of a study."""

from __future__ import annotations

from contextlib import AbstractContextManager

__all__ = ["single_threaded_blas"]


def single_threaded_blas() -> AbstractContextManager[object]:
    """Limit BLAS to one thread (a context manager).

    Per-sample products are too small to gain from threads, and threads of several workers (or
    of other jobs) fighting for the cores slow them down many times (measured: 1.1 s against
    42 ms per sample on the riveting case, 2 busy cores). One thread also fixes the summation
    order of the factorisations a source computes (see
    :meth:`~contactqp.studies.sources.GaussianGapField.realisations`).
    """
    from threadpoolctl import threadpool_limits

    return threadpool_limits(1)

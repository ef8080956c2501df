"""Executors of a study: where its chunks of samples are solved.

Each executor is a generator of ``(indices, records)``, one per chunk, in the order the chunks
finish: :func:`serial` (in this process), :func:`process_pool` (local worker processes) and
:func:`dask_cluster` (a Dask distributed cluster); :func:`executor` picks one. A task is
``(indices, warm)``: consecutive samples and the warm start of the first; the study's
``state`` is ``(case, source)``, sent to each worker once.

Interrupts: on Ctrl-C, raised while an executor waits or thrown into it by its consumer while
that stores a chunk, the pool and cluster executors cancel the chunks not started and give
every chunk finished or still running before the interrupt goes on (the consumer skips those
it stored already): work a worker started is stored, not thrown away.
"""

from __future__ import annotations

import signal
from collections.abc import Iterator, Sequence
from contextlib import contextmanager

import numpy as np

from ..errors import InvalidInputError
from ..optional import require
from .protocols import Chunk, GapSource, StudyCase, Task
from .threads import single_threaded_blas

__all__ = ["check_scheduler", "dask_cluster", "executor", "process_pool", "serial", "solve_chunk"]

#: What every chunk of a study shares: its case and its gap source.
State = tuple[StudyCase, GapSource]


def solve_chunk(state: State, indices: np.ndarray, warm: np.ndarray | None) -> Chunk:
    """Solve consecutive samples, each warm started from the previous: ``(indices, records)``.

    ``records`` maps each field (the case's, plus ``initial_gap``) to one row per sample.
    """
    case, source = state
    rows = []
    with single_threaded_blas():
        for gaps in source.realisations(indices):
            record, warm = case.solve_sample(gaps, warm)
            record["initial_gap"] = gaps
            rows.append(record)
    return indices, {name: np.array([row[name] for row in rows]) for name in rows[0]}


def serial(state: State, tasks: Sequence[Task]) -> Iterator[Chunk]:
    """The chunks solved one after another in this process."""
    for indices, warm in tasks:
        yield solve_chunk(state, indices, warm)


def executor(
    state: State, tasks: Sequence[Task], *, workers: int = 1, scheduler: str | None = None
) -> Iterator[Chunk]:
    """The executor for ``tasks``: the Dask cluster at ``scheduler`` if given, else a pool of
    ``workers`` processes when there are several workers and chunks, else :func:`serial`."""
    if tasks and scheduler is not None:
        return dask_cluster(state, tasks, scheduler)
    if workers > 1 and len(tasks) > 1:
        return process_pool(state, tasks, workers)
    return serial(state, tasks)


# The study's state in a pool worker process, set there by the pool's initializer (so that the
# state, a case holding its Delassus operator, is pickled once per worker, not once per chunk).
# A module global is the only place a ProcessPoolExecutor initializer can leave something for
# the tasks that follow it in the same process; it stays None in the parent process.
_worker_state: State | None = None


def _init_worker(state: State) -> None:
    global _worker_state
    _worker_state = state
    _sigint_unblocked()  # a worker forked while the pool was starting inherits the block


def _pool_chunk(indices: np.ndarray, warm: np.ndarray | None) -> Chunk:
    assert _worker_state is not None, "a pool task runs in a worker its initializer prepared"
    return solve_chunk(_worker_state, indices, warm)


@contextmanager
def _sigint_blocked():
    """Hold Ctrl-C (SIGINT) back until the end of the block, where it is raised if it came.

    An executor interrupted while it starts can be left half made (a manager thread never
    started, which its shutdown cannot join); held back, the interrupt comes once it runs.
    """
    if not hasattr(signal, "pthread_sigmask"):  # Windows
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _sigint_unblocked():
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def process_pool(state: State, tasks: Sequence[Task], workers: int) -> Iterator[Chunk]:
    """Chunks solved by ``workers`` local processes, as they finish (interrupts: see the
    module notes)."""
    from concurrent.futures import ProcessPoolExecutor, as_completed

    pool, futures = None, []
    try:
        with _sigint_blocked():  # a Ctrl-C meanwhile is raised at its end, inside this try
            pool = ProcessPoolExecutor(workers, initializer=_init_worker, initargs=(state,))
            futures = [pool.submit(_pool_chunk, indices, warm) for indices, warm in tasks]
        for future in as_completed(futures):
            yield future.result()
    except KeyboardInterrupt:
        for future in futures:
            future.cancel()
        for future in futures:
            if not future.cancelled() and future.exception() is None:
                yield future.result()  # (a worker interrupted too has an exception)
        raise
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


def _distributed():
    return require("distributed", "a Dask scheduler", "cluster")


_SOCKET_SCHEMES = ("tcp", "tls", "ws", "wss")


def check_scheduler(scheduler: str) -> str:
    """The Dask scheduler address ``scheduler``, checked before any client or store is made.

    The form is checked by Dask's own parser; a TCP-based address (``tcp://``, ``tls://``,
    ``ws://``, ``wss://``, or ``host:port``) must also accept a connection. A plain socket does
    that, so a malformed or refused address is told at once, whatever the load: a Dask client
    first starts an IO loop, and gives up with an ``AssertionError`` when that takes over 10 s.

    Raises
    ------
    InvalidInputError
        Malformed, unresolvable or refusing address.
    """
    import socket

    distributed = _distributed()
    from distributed.comm.addressing import parse_address, parse_host_port

    if not isinstance(scheduler, str):
        raise InvalidInputError(
            "scheduler must be an address string like tcp://host:port, got "
            f"{type(scheduler).__name__}"
        )
    try:
        scheme, location = parse_address(scheduler)
        if scheme in _SOCKET_SCHEMES:
            host, port = parse_host_port(location)
            if not 0 < port < 65536:
                raise ValueError(f"port {port} out of range")
        elif scheme not in distributed.comm.registry.backends:
            raise ValueError(f"unknown scheme {scheme!r}")
    except (ValueError, TypeError) as exc:
        raise InvalidInputError(
            f"Dask scheduler {scheduler!r} is not an address like tcp://host:port: {exc}"
        ) from None
    if scheme in _SOCKET_SCHEMES:
        import dask

        timeout = dask.utils.parse_timedelta(
            dask.config.get("distributed.comm.timeouts.connect"), default="seconds"
        )
        try:
            socket.create_connection((host, port), timeout=timeout).close()
        except OSError as exc:
            raise InvalidInputError(
                f"cannot reach the Dask scheduler {scheduler!r}: {exc.strerror or exc}"
            ) from None
    return scheduler


def dask_cluster(state: State, tasks: Sequence[Task], scheduler: str) -> Iterator[Chunk]:
    """Chunks solved on the Dask cluster at ``scheduler``, as they finish (interrupts: see the
    module notes)."""
    distributed = _distributed()
    try:
        client = distributed.Client(scheduler)
    except (OSError, ValueError, TypeError) as exc:  # gone since check_scheduler
        raise InvalidInputError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from None
    with client:
        shared = client.scatter(state, broadcast=True)
        futures = [
            client.submit(solve_chunk, shared, indices, warm, pure=False) for indices, warm in tasks
        ]
        try:
            for future in distributed.as_completed(futures):
                yield future.result()
        except KeyboardInterrupt:  # give what the cluster finished
            finished = [future for future in futures if future.status == "finished"]
            client.cancel([future for future in futures if future not in finished])
            for future in finished:
                yield future.result()
            raise
        finally:
            client.cancel(futures)

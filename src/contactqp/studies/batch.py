r"""Variation simulation: many gap fields on one reduced model, stored as they come, resumable.

A *case* solves one sample from its initial gaps; a *source* gives the gaps of sample ``k``.
:func:`run_batch` solves samples ``0 .. N-1`` in chunks of consecutive samples, each sample warm
started from the previous one of its chunk, and writes each finished chunk to an HDF5 file (one
row per sample and field, then the ``done`` flag, each flushed). Running it again on the same
file computes only the samples not yet done, with the warm start of the interrupted chunk read
back from the file, so the results do not depend on interruptions, on the number of workers or
on the executor (in-process, local process pool, Dask cluster).

Gaussian gap fields (:class:`GaussianGapField`) have the squared-exponential covariance

.. math::

    C(x, x') = \sigma^2 \exp\!\Big(-\frac{\|x - x'\|^2}{2 \ell^2}\Big)

(amplitude :math:`\sigma`, correlation length :math:`\ell`); sample ``k`` is
``mean + L z_k`` with ``L L^T = C`` and ``z_k`` standard normal drawn from
``SeedSequence(seed, spawn_key=(k,))``: the same whoever computes it.
"""

from __future__ import annotations

import errno
import hashlib
import json
import signal
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import FileFormatError, InvalidInputError
from ..core.model import MAX_MAGNITUDE, finite_array
from ..optional import require
from ..core.problem import ContactProblem
from ..methods import solve

__all__ = ["BatchData", "BatchSummary", "GapSamples", "GapStatistics", "GapVariation",
           "GaussianGapField", "check_scheduler", "load_batch", "load_gap_samples",
           "run_batch"]

FORMAT = "contactqp-batch/1"
DEFAULT_CHUNK = 50


def _digest(*arrays) -> str:
    sha = hashlib.sha1()
    for array in arrays:
        sha.update(np.ascontiguousarray(array, dtype=float).tobytes())
    return sha.hexdigest()


class GapVariation:
    """A frictionless :class:`~contactqp.ContactProblem` whose initial gaps vary by sample.

    Records (one row per sample in the store): ``gap`` final gaps (m), ``force`` contact forces
    (N), ``closed`` contact status, ``success``, ``iterations``. The warm start of a sample is the
    previous sample's ``force``.

    Parameters
    ----------
    problem : ContactProblem
        Its gaps are replaced by each sample's; its dual is assembled once.
    **options
        Passed to :func:`~contactqp.solve` (active-set solver), e.g. ``tol``.
    """

    def __init__(self, problem: ContactProblem, **options):
        if not isinstance(problem, ContactProblem):
            raise InvalidInputError(
                f"problem must be a ContactProblem, got {type(problem).__name__}")
        self.problem = problem
        self.options = {"tol": 1e-10, **options}
        problem.dual()

    @property
    def n_contacts(self) -> int:
        """Number of constraints ``m`` (the length of a gap field)."""
        return self.problem.n_constraints

    def fields(self) -> dict:
        """``{name: (shape, dtype)}`` of one sample's record."""
        m = (self.n_contacts,)
        return {"gap": (m, "f8"), "force": (m, "f8"), "closed": (m, "?"), "success": ((), "?"),
                "iterations": ((), "i8")}

    @staticmethod
    def _record(result) -> dict:
        return {"gap": result.gaps, "force": result.forces, "closed": result.closed,
                "success": result.success, "iterations": result.nit}

    def solve_sample(self, gaps, warm):
        """Solve one sample: ``(record, warm start of the next sample)``."""
        result = solve(self.problem.variant(gaps=gaps), "active-set", forces0=warm,
                       **self.options)
        return self._record(result), result.forces

    def warm_start(self, record) -> np.ndarray:
        """The warm start a stored record gives to the next sample."""
        return np.asarray(record["force"], dtype=float)

    def describe(self) -> dict:
        """What identifies the case in a store: a digest of ``W``, the loads and ``A R P`` (the
        answer depends on all three), the certificate's tolerance and the options."""
        problem = self.problem
        dual = problem.dual()
        return {"type": type(self).__name__, "contacts": self.n_contacts,
                "digest": _digest(dual.W, problem.loads,
                                  problem.constraints.matrix @ dual.free_displacements),
                "certificate_tol": repr(problem.certificate_tol),
                "options": {k: repr(v) for k, v in sorted(self.options.items())}}


class GaussianGapField:
    """Gaussian random gap fields with squared-exponential covariance (see the module notes).

    Parameters
    ----------
    coordinates : array_like, shape (m, d)
        Position of each gap (m).
    amplitude : float
        Standard deviation ``sigma`` (m), >= 0.
    correlation_length : float
        ``ell`` (m), > 0.
    mean : float or array_like, shape (m,)
        Nominal gap field (m).
    seed : int
        Root of the per-sample seed sequences.
    """

    def __init__(self, coordinates, amplitude: float, correlation_length: float, mean=0.0,
                 seed: int = 0):
        self.coordinates = finite_array(coordinates, "coordinates", 2)
        m = len(self.coordinates)
        if not (np.isfinite(amplitude) and 0 <= amplitude <= MAX_MAGNITUDE):
            raise InvalidInputError(f"amplitude must be >= 0 and at most {MAX_MAGNITUDE:g} m, "
                                    f"got {amplitude!r}")
        if not (np.isfinite(correlation_length) and 0 < correlation_length <= MAX_MAGNITUDE):
            raise InvalidInputError(f"correlation_length must be > 0 and at most "
                                    f"{MAX_MAGNITUDE:g} m, got {correlation_length!r}")
        self.amplitude, self.correlation_length = float(amplitude), float(correlation_length)
        self.mean = np.broadcast_to(finite_array(np.atleast_1d(mean), "mean", 1), (m,)).copy()
        if isinstance(seed, bool) or int(seed) != seed or seed < 0:
            raise InvalidInputError(f"seed must be an integer >= 0, got {seed!r}")
        self.seed = int(seed)
        self._factor = None

    @property
    def n_available(self):
        """None: any number of samples."""
        return None

    @property
    def covariance(self) -> np.ndarray:
        """``C`` (m^2), shape (m, m)."""
        diff = self.coordinates[:, None, :] - self.coordinates[None, :, :]
        squared = np.einsum("ijk,ijk->ij", diff, diff)
        return self.amplitude ** 2 * np.exp(-squared / (2.0 * self.correlation_length ** 2))

    def _square_root(self) -> np.ndarray:
        """``L`` with ``L L^T = C``, from the eigenvectors (``C`` is often numerically singular).

        The eigenvectors of clustered eigenvalues change with the BLAS threads (measured: 1e-6
        of sigma on the riveting grid), so ``L`` is computed on one thread, and once: pickling
        (to workers, a Dask cluster) carries it, so every worker draws the same fields.
        """
        if self._factor is None:
            with _single_threaded_blas():
                values, vectors = np.linalg.eigh(self.covariance)
            self._factor = np.ascontiguousarray(vectors * np.sqrt(np.clip(values, 0.0, None)))
        return self._factor

    def __getstate__(self):
        self._square_root()
        return self.__dict__

    def realisations(self, indices) -> np.ndarray:
        """Gap fields of the samples ``indices`` (m), shape (len(indices), m).

        Each sample is drawn and transformed on its own, so sample ``k`` is bitwise the same in
        any batch: a product of the batch with ``L`` lets BLAS choose another kernel and
        summation order for another batch size (measured: 1 ulp, 5e-20 m, between ``[k]``
        alone and inside a batch of 2 or more).
        """
        factor = self._square_root()
        indices = list(indices)
        fields = np.empty((len(indices), len(self.mean)))
        for row, k in zip(fields, indices):
            stream = np.random.SeedSequence(self.seed, spawn_key=(int(k),))
            row[:] = self.mean + _fixed_order_product(
                factor, np.random.default_rng(stream).standard_normal(len(self.mean)))
        return fields

    def describe(self) -> dict:
        return {"type": "gaussian", "amplitude": self.amplitude,
                "correlation_length": self.correlation_length, "seed": self.seed,
                "digest": _digest(self.coordinates, self.mean)}


def _fixed_order_product(matrix: np.ndarray, vector: np.ndarray, rows: int = 256) -> np.ndarray:
    """``matrix @ vector`` summed in an order fixed by the shapes alone.

    Each entry is numpy's pairwise sum of one row's products, independent of BLAS (its
    kernel, threads and the alignment of the arrays); blocks of ``rows`` bound the temporary.
    """
    out = np.empty(len(matrix))
    for start in range(0, len(matrix), rows):
        block = matrix[start:start + rows]
        np.add.reduce(block * vector, axis=1, out=out[start:start + rows])
    return out


class GapSamples:
    """Gap fields given as an array, one realisation per row (m), shape (N, m)."""

    def __init__(self, samples):
        self.samples = finite_array(samples, "gap samples", 2)

    @property
    def n_available(self) -> int:
        """Number of realisations ``N``."""
        return len(self.samples)

    def realisations(self, indices) -> np.ndarray:
        """Rows ``indices``, shape (len(indices), m)."""
        return self.samples[np.asarray(indices, dtype=int)]

    def describe(self) -> dict:
        return {"type": "array", "shape": list(self.samples.shape),
                "digest": _digest(self.samples)}


def load_gap_samples(path) -> GapSamples:
    """Realisations from a file: ``.npy``, ``.npz`` (its only array), or ``.csv`` / ``.txt``
    (comma-separated, one row per sample).

    Values in metres, shape (N, m). A missing, truncated or corrupt file is a one-line
    :class:`~contactqp.errors.FileFormatError`.
    """
    from ..io.arrays import read_csv_array, read_numpy_array

    path = Path(path)
    if not path.is_file():
        raise FileFormatError(f"{path}: gap samples file not found")
    if path.suffix not in (".npy", ".npz", ".csv", ".txt"):
        raise FileFormatError(f"{path}: gap samples must be .npy, .npz or .csv (or .txt)")
    data = read_numpy_array(path) if path.suffix in (".npy", ".npz") else read_csv_array(path)
    try:
        return GapSamples(data)
    except InvalidInputError as exc:
        raise FileFormatError(f"{path}: {exc}") from None


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
        return {"samples": self.samples, "computed": self.computed, "reused": self.reused,
                "failed": self.failed, "seconds": self.seconds}


def _h5py():
    return require("h5py", "batch stores", "hdf5")


def _open_store(path: Path, case, source, n_samples: int, chunk: int):
    """Open (or create) the store, check it belongs to this study, grow it to ``n_samples``."""
    h5py = _h5py()
    identity = json.dumps({"case": case.describe(), "source": source.describe()}, sort_keys=True)
    fields = {"initial_gap": ((case.n_contacts,), "f8"), **case.fields()}
    try:
        store = h5py.File(path, "a")
    except OSError as exc:  # h5py's errors do not name the file
        if exc.errno is None:
            raise FileFormatError(f"{path}: not a contactqp batch store ({exc})") from None
        busy = " (in use by another run?)" if exc.errno == errno.EAGAIN else ""
        raise FileFormatError(f"{path}: cannot open the batch store{busy}: {exc}") from None
    try:
        ours = store.attrs.get("format") == FORMAT  # written first when a store is made
        if not ours and (len(store) or len(store.attrs)):
            raise FileFormatError(f"{path} is not a contactqp batch store (it holds other "
                                  "HDF5 data, left as it is): give another output")
        if "done" not in store:  # new, or its creation was interrupted: nothing stored yet
            for name in list(store):
                del store[name]
            store.attrs.update({"format": FORMAT, "identity": identity, "chunk": chunk})
            store.flush()
            for name, (shape, dtype) in fields.items():
                store.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape),
                                     dtype=dtype, chunks=(chunk, *shape))
            # last: its presence says the store is complete
            store.create_dataset("done", shape=(0,), maxshape=(None,), dtype="?", chunks=(chunk,))
        elif store.attrs.get("format") != FORMAT or store.attrs.get("identity") != identity:
            raise InvalidInputError(f"{path} holds another study (other model, options or gap "
                                    "source): give another output")
        for name in (*fields, "done"):  # each, in case an earlier resize was interrupted
            if store[name].shape[0] < n_samples:
                store[name].resize(n_samples, axis=0)
    except BaseException:
        store.close()
        raise
    return store


def _runs(pending: np.ndarray, chunk: int) -> list:
    """Split sorted pending indices into runs of consecutive samples within one chunk."""
    breaks = np.flatnonzero((np.diff(pending) != 1) | (np.diff(pending // chunk) != 0)) + 1
    return np.split(pending, breaks) if pending.size else []


def _single_threaded_blas():
    """Limit BLAS to one thread: per-sample products are too small to gain from threads, and
    threads of several workers (or of other jobs) fighting for the cores slow them down many
    times (measured: 1.1 s against 42 ms per sample on the riveting case, 2 busy cores)."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(1)


def _solve_chunk(state, indices, warm):
    """Solve consecutive samples, each warm started from the previous: ``(indices, records)``."""
    case, source = state
    rows = []
    with _single_threaded_blas():
        for gaps in source.realisations(indices):
            record, warm = case.solve_sample(gaps, warm)
            record["initial_gap"] = gaps
            rows.append(record)
    return indices, {name: np.array([row[name] for row in rows]) for name in rows[0]}


_WORKER_STATE = None


def _init_worker(state):
    global _WORKER_STATE
    _WORKER_STATE = state
    _sigint_unblocked()  # a worker forked while the pool was starting inherits the block


def _pool_chunk(indices, warm):
    return _solve_chunk(_WORKER_STATE, indices, warm)


def _serial(state, tasks):
    for indices, warm in tasks:
        yield _solve_chunk(state, indices, warm)


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


def _process_pool(state, tasks, workers):
    """Chunks solved by ``workers`` local processes, as they finish.

    On Ctrl-C, raised here or thrown in by the consumer while it stores a chunk, the chunks
    not started are cancelled, and every chunk finished or still running is given (once more
    for those given before: the consumer skips what it stored) before the interrupt goes on.
    """
    from concurrent.futures import ProcessPoolExecutor, as_completed

    executor, futures = None, []
    try:
        with _sigint_blocked():  # a Ctrl-C meanwhile is raised at its end, inside this try
            executor = ProcessPoolExecutor(workers, initializer=_init_worker, initargs=(state,))
            futures = [executor.submit(_pool_chunk, indices, warm) for indices, warm in tasks]
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
        if executor is not None:
            executor.shutdown(wait=True, cancel_futures=True)


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
        raise InvalidInputError("scheduler must be an address string like tcp://host:port, got "
                                f"{type(scheduler).__name__}")
    try:
        scheme, location = parse_address(scheduler)
        if scheme in _SOCKET_SCHEMES:
            host, port = parse_host_port(location)
            if not 0 < port < 65536:
                raise ValueError(f"port {port} out of range")
        elif scheme not in distributed.comm.registry.backends:
            raise ValueError(f"unknown scheme {scheme!r}")
    except (ValueError, TypeError) as exc:
        raise InvalidInputError(f"Dask scheduler {scheduler!r} is not an address like "
                                f"tcp://host:port: {exc}") from None
    if scheme in _SOCKET_SCHEMES:
        import dask

        timeout = dask.utils.parse_timedelta(
            dask.config.get("distributed.comm.timeouts.connect"), default="seconds")
        try:
            socket.create_connection((host, port), timeout=timeout).close()
        except OSError as exc:
            raise InvalidInputError(f"cannot reach the Dask scheduler {scheduler!r}: "
                                    f"{exc.strerror or exc}") from None
    return scheduler


def _dask(state, tasks, scheduler):
    distributed = _distributed()
    try:
        client = distributed.Client(scheduler)
    except (OSError, ValueError, TypeError) as exc:  # gone since check_scheduler
        raise InvalidInputError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from None
    with client:
        shared = client.scatter(state, broadcast=True)
        futures = [client.submit(_solve_chunk, shared, indices, warm, pure=False)
                   for indices, warm in tasks]
        try:
            for future in distributed.as_completed(futures):
                yield future.result()
        except KeyboardInterrupt:  # give what the cluster finished (see _process_pool)
            finished = [future for future in futures if future.status == "finished"]
            client.cancel([future for future in futures if future not in finished])
            for future in finished:
                yield future.result()
            raise
        finally:
            client.cancel(futures)


#: Most samples of one study: 10^7 samples of tens of milliseconds each are days of work on
#: a workstation, and their store already holds 10^7 rows per field.
MAX_SAMPLES = 10**7


def run_batch(case, source, n_samples: int, path, *, workers: int = 1, scheduler=None,
              chunk_size: int = DEFAULT_CHUNK, limit: int | None = None,
              progress=None) -> BatchSummary:
    """Solve samples ``0 .. n_samples-1`` of ``source`` with ``case``; store and resume.

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
        Address of a Dask distributed scheduler (see :func:`check_scheduler`); ``workers`` is
        then ignored.
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
    if (isinstance(n_samples, bool) or int(n_samples) != n_samples
            or not 1 <= n_samples <= MAX_SAMPLES):
        raise InvalidInputError(f"n_samples must be an integer from 1 to {MAX_SAMPLES:g}, got "
                                f"{n_samples!r}")
    n_samples = int(n_samples)
    if source.n_available is not None and n_samples > source.n_available:
        raise InvalidInputError(f"asked for {n_samples} samples, the source has "
                                f"{source.n_available}")
    if int(workers) < 1 or int(chunk_size) < 1:
        raise InvalidInputError(f"workers and chunk_size must be >= 1, got {workers}, {chunk_size}")
    if scheduler is not None:
        check_scheduler(scheduler)
    width = np.shape(source.realisations([0]))[-1]
    if width != case.n_contacts:  # before a store is made for a study that cannot run
        raise InvalidInputError(f"gap fields have {width} values, the case has "
                                f"{case.n_contacts} contacts")
    path = Path(path)
    store = _open_store(path, case, source, n_samples, int(chunk_size))
    with store:
        chunk = int(store.attrs["chunk"])
        done = store["done"][:n_samples]
        reused = int(np.count_nonzero(done))
        pending = np.flatnonzero(~done)
        if limit is not None:
            pending = pending[:max(int(limit), 0)]
        tasks = []
        for run in _runs(pending, chunk):
            before = run[0] - 1
            resumed = before >= 0 and before // chunk == run[0] // chunk and done[before]
            warm = case.warm_start({name: store[name][before] for name in case.fields()}) \
                if resumed else None
            tasks.append((run, warm))
        state = (case, source)
        if not tasks:
            results = _serial(state, tasks)
        elif scheduler is not None:
            results = _dask(state, tasks, scheduler)
        elif int(workers) > 1 and len(tasks) > 1:
            results = _process_pool(state, tasks, int(workers))
        else:
            results = _serial(state, tasks)
        stored = {}  # first sample of each chunk stored by this call: its length

        def store_chunk(indices, records, report=True):
            first, last = int(indices[0]), int(indices[-1]) + 1
            if first in stored:
                return
            for name, values in records.items():
                store[name][first:last] = values
            store.flush()
            store["done"][first:last] = True
            store.flush()
            stored[first] = last - first
            if progress is not None and report:
                progress(reused + sum(stored.values()), n_samples)

        _store_all(results, store_chunk)
        computed = sum(stored.values())
        finished = store["done"][:n_samples]
        failed = int(np.count_nonzero(finished & ~store["success"][:n_samples]))
    return BatchSummary(n_samples, computed, reused, failed, time.perf_counter() - start, path)


@dataclass(frozen=True)
class GapStatistics:
    """Per-contact statistics of the final gaps over the successful samples.

    Attributes
    ----------
    samples : int
        Samples used.
    mean : ndarray, shape (m,)
        Mean final gap (m).
    levels : ndarray, shape (q,)
        Quantile levels.
    quantiles : ndarray, shape (q, m)
        Final-gap quantiles (m).
    contact_probability : ndarray, shape (m,)
        Fraction of samples in which the contact is closed.
    """

    samples: int
    mean: np.ndarray
    levels: np.ndarray
    quantiles: np.ndarray
    contact_probability: np.ndarray


@dataclass(frozen=True)
class BatchData:
    """The done samples of a store.

    Attributes
    ----------
    indices : ndarray of int, shape (s,)
        Sample numbers done.
    fields : dict of ndarray
        Each stored field, rows in the order of ``indices``.
    """

    indices: np.ndarray
    fields: dict

    def statistics(self, levels=(0.05, 0.5, 0.95)) -> GapStatistics:
        """:class:`GapStatistics` of the ``gap`` and ``closed`` fields (successful samples)."""
        ok = self.fields["success"]
        if not ok.any():
            raise InvalidInputError("no successful sample to compute statistics from")
        gaps, closed = self.fields["gap"][ok], self.fields["closed"][ok]
        levels = np.asarray(levels, dtype=float)
        return GapStatistics(int(ok.sum()), gaps.mean(axis=0), levels,
                             np.quantile(gaps, levels, axis=0), closed.mean(axis=0))


def load_batch(path, n_samples: int | None = None) -> BatchData:
    """Read the done samples of a store written by :func:`run_batch`.

    ``n_samples``: read only samples ``0 .. n_samples-1`` (a store may hold more, from an
    earlier, longer study); default all.
    """
    h5py = _h5py()
    path = Path(path)
    if not path.is_file():
        raise FileFormatError(f"{path}: no such batch store")
    with h5py.File(path, "r") as store:
        if store.attrs.get("format") != FORMAT:
            raise FileFormatError(f"{path} is not a contactqp batch store")
        done = np.flatnonzero(store["done"][:n_samples])
        fields = {name: store[name][:][done] for name in store if name != "done"}
    return BatchData(done, fields)

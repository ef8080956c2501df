"""The HDF5 store of a study: one row per sample and field, a ``done`` flag, resumable.

A store is made with its attributes first (``format``, then the study's ``identity`` and
``chunk``), then one dataset per field, then ``done``, whose presence says the store is
complete. A chunk of samples is written field by field, flushed, and only then marked done and
flushed again, so a process killed at any point leaves every sample marked done whole on disk;
samples not marked are computed again on resume.
"""

from __future__ import annotations

import errno
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import FileFormatError, InvalidInputError
from ..optional import require
from .statistics import GapStatistics, gap_statistics

__all__ = ["FORMAT", "BatchData", "BatchStore", "load_batch"]

FORMAT = "contactqp-batch/1"


def _h5py():
    return require("h5py", "batch stores", "hdf5")


class BatchStore:
    """An open store of one study (a context manager; see the module notes).

    Use :meth:`open`; ``file`` is the open ``h5py.File``.
    """

    def __init__(self, file):
        self._file = file

    @classmethod
    def open(cls, path: Path, case, source, n_samples: int, chunk: int) -> BatchStore:
        """Open (or create) the store at ``path``, check it belongs to this study (``case`` and
        ``source`` describe it), grow it to ``n_samples`` rows; ``chunk`` for a new store.

        Raises
        ------
        FileFormatError
            Not an HDF5 file, in use by another process, or HDF5 data of something else (left
            as it is).
        InvalidInputError
            A store of another study.
        """
        h5py = _h5py()
        identity = json.dumps(
            {"case": case.describe(), "source": source.describe()}, sort_keys=True
        )
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
                raise FileFormatError(
                    f"{path} is not a contactqp batch store (it holds other "
                    "HDF5 data, left as it is): give another output"
                )
            if "done" not in store:  # new, or its creation was interrupted: nothing stored yet
                for name in list(store):
                    del store[name]
                store.attrs.update({"format": FORMAT, "identity": identity, "chunk": chunk})
                store.flush()
                for name, (shape, dtype) in fields.items():
                    store.create_dataset(
                        name,
                        shape=(0, *shape),
                        maxshape=(None, *shape),
                        dtype=dtype,
                        chunks=(chunk, *shape),
                    )
                # last: its presence says the store is complete
                store.create_dataset(
                    "done", shape=(0,), maxshape=(None,), dtype="?", chunks=(chunk,)
                )
            elif store.attrs.get("format") != FORMAT or store.attrs.get("identity") != identity:
                raise InvalidInputError(
                    f"{path} holds another study (other model, options or "
                    "gap source): give another output"
                )
            for name in (*fields, "done"):  # each, in case an earlier resize was interrupted
                if store[name].shape[0] < n_samples:
                    store[name].resize(n_samples, axis=0)
        except BaseException:
            store.close()
            raise
        return cls(store)

    def __enter__(self) -> BatchStore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        self._file.close()

    @property
    def chunk(self) -> int:
        """Samples per chunk, fixed when the store was made."""
        return int(self._file.attrs["chunk"])

    def done(self, n_samples: int) -> np.ndarray:
        """Done flag of samples ``0 .. n_samples-1`` (bool, shape (n_samples,))."""
        return self._file["done"][:n_samples]

    def failed(self, n_samples: int) -> int:
        """Samples among the first ``n_samples`` done whose solve failed."""
        return int(np.count_nonzero(self.done(n_samples) & ~self._file["success"][:n_samples]))

    def pending(self, n_samples: int, fields, limit: int | None = None) -> list:
        """The samples to compute, as runs of consecutive samples within one chunk.

        Parameters
        ----------
        n_samples : int
        fields : iterable of str
            The fields of the record handed back for a resumed run.
        limit : int, optional
            Only the first ``limit`` samples not done.

        Returns
        -------
        list of (ndarray of int, dict or None)
            Each run's samples and, when the run resumes a chunk whose previous sample is done,
            that sample's record (``{field: value}``, for the warm start), else None.
        """
        done = self.done(n_samples)
        todo = np.flatnonzero(~done)
        if limit is not None:
            todo = todo[: max(int(limit), 0)]
        chunk, runs = self.chunk, []
        for run in _runs(todo, chunk):
            before = run[0] - 1
            resumed = before >= 0 and before // chunk == run[0] // chunk and done[before]
            record = {name: self._file[name][before] for name in fields} if resumed else None
            runs.append((run, record))
        return runs

    def write(self, indices, records: dict) -> None:
        """Store the records (``{field: rows}``) of the consecutive samples ``indices``, then
        mark them done (each step flushed)."""
        first, last = int(indices[0]), int(indices[-1]) + 1
        for name, values in records.items():
            self._file[name][first:last] = values
        self._file.flush()
        self._file["done"][first:last] = True
        self._file.flush()


def _runs(pending: np.ndarray, chunk: int) -> list:
    """Split sorted pending indices into runs of consecutive samples within one chunk."""
    breaks = np.flatnonzero((np.diff(pending) != 1) | (np.diff(pending // chunk) != 0)) + 1
    return np.split(pending, breaks) if pending.size else []


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

    def statistics(
        self,
        levels: Sequence[float] = (0.05, 0.5, 0.95),
        *,
        shim_tolerance: float | None = None,
    ) -> GapStatistics:
        """:class:`GapStatistics` of the ``gap`` and ``closed`` fields (successful samples);
        with ``shim_tolerance`` (m), also the probability of a gap above it."""
        return gap_statistics(self.fields, levels, shim_tolerance=shim_tolerance)


def load_batch(path: str | os.PathLike[str], n_samples: int | None = None) -> BatchData:
    """Read the done samples of a store written by :func:`~contactqp.studies.batch.run_batch`.

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

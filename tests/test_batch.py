"""Variation simulation: gap fields against their target statistics, shared duals against fresh
problems, identical results serially / on a process pool / on a Dask cluster, resumption."""

from __future__ import annotations

import numpy as np
import pytest

from contactqp import ContactProblem, NodePairs, solve
from contactqp.applications.riveting import Assembly, FasteningCase
from contactqp.core.status import ContactStatus
from contactqp.errors import FileFormatError, InvalidInputError
from contactqp.io.plot import plot_statistics
from contactqp.studies import (
    GapSamples,
    GapVariation,
    GaussianGapField,
    load_batch,
    load_gap_samples,
    run_batch,
)

N = 24


@pytest.fixture(scope="module")
def riveted():
    return Assembly(grid=(11, 7), refine=1, fasteners=((1, 3), (5, 3), (9, 3))).build()


@pytest.fixture(scope="module")
def source(riveted):
    return GaussianGapField(riveted.points, 1e-4, 0.03, mean=1.5e-4, seed=11)


def test_gaussian_field_has_its_target_amplitude_and_correlation():
    x = np.arange(40) * 0.01
    field = GaussianGapField(
        np.column_stack([x, 0 * x]), amplitude=2e-4, correlation_length=0.03, mean=5e-4, seed=3
    )
    samples = field.realisations(range(4000))
    # 4000 samples: standard errors about 1.1 % of sigma for the deviation, 0.016 for a
    # correlation; the bounds are 4 to 5 standard errors
    np.testing.assert_allclose(samples.mean(axis=0), 5e-4, atol=0.1 * 2e-4)
    np.testing.assert_allclose(samples.std(axis=0), 2e-4, rtol=0.05)
    corr = np.corrcoef(samples.T)
    for lag in (1, 2, 3, 5):
        target = np.exp(-((lag * 0.01) ** 2) / (2 * 0.03**2))
        np.testing.assert_allclose(np.diagonal(corr, lag).mean(), target, atol=0.03)


def test_sample_k_does_not_depend_on_who_draws_it(source):
    # alone, in batches of 2, 7 and 64, in any order: a product of the whole batch with the
    # factor made BLAS pick another kernel (gemv for one sample, gemm for more) and sum in
    # another order, 1 ulp apart
    alone = np.array([source.realisations([k])[0] for k in range(64)])
    np.testing.assert_array_equal(source.realisations(range(64)), alone)
    np.testing.assert_array_equal(source.realisations(range(63, -1, -1)), alone[::-1])
    for batch in ([5, 17], [0, 5, 17, 40, 41, 2, 63], list(range(7))):
        np.testing.assert_array_equal(source.realisations(batch), alone[batch])
    other = GaussianGapField(source.coordinates, 1e-4, 0.03, mean=1.5e-4, seed=12)
    assert not np.allclose(other.realisations([5]), source.realisations([5]))


def test_sample_k_does_not_depend_on_blas_threads_or_pickling(source):
    # eigh's eigenvectors of clustered eigenvalues move with the BLAS thread count; workers
    # get the parent's factor with the field
    import pickle

    from threadpoolctl import threadpool_limits

    xs, ys = np.meshgrid(np.arange(1, 26) * 0.2 / 26, np.arange(21) * 0.1 / 20)
    grid = np.column_stack([xs.ravel(), ys.ravel()])  # the default riveting grid
    fields = [GaussianGapField(grid, 1e-4, 0.04, seed=11) for _ in range(2)]
    with threadpool_limits(1):
        single = fields[0].realisations(range(8))
    with threadpool_limits(None):
        many = fields[1].realisations(range(8))
    np.testing.assert_array_equal(many, single)
    fresh = GaussianGapField(source.coordinates, 1e-4, 0.03, mean=1.5e-4, seed=11)
    shipped = pickle.loads(pickle.dumps(fresh))
    assert shipped._factor is not None and fresh._factor is not None
    np.testing.assert_array_equal(shipped._factor, fresh._factor)


def test_shared_dual_gives_the_fresh_problem_answer(riveted, source):
    # GapVariation re-uses one assembled dual; a fresh ContactProblem assembles everything
    k = riveted.n_pairs
    pairs = np.column_stack([np.arange(k), k + np.arange(k)])
    loads = np.zeros(2 * k)
    loads[riveted.fasteners] = 40.0  # clamping forces: plates pushed together at the fasteners
    loads[k + riveted.fasteners] = -40.0
    base = ContactProblem(riveted.model, loads, [NodePairs(pairs, np.zeros(k))])
    case = GapVariation(base)
    warm = None
    for gaps in source.realisations(range(3)):
        record, warm = case.solve_sample(gaps, warm)
        fresh = solve(ContactProblem(riveted.model, loads, [NodePairs(pairs, gaps)]))
        assert record["success"] and fresh.success
        assert np.any(fresh.contact_status == ContactStatus.CLOSED)
        np.testing.assert_allclose(record["force"], fresh.forces, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(record["gap"], fresh.gaps, rtol=1e-8, atol=1e-14)
    twin = base.variant(gaps=np.ones(k))
    assert twin.dual().W is base.dual().W and np.all(base.constraints.gaps == 0)


@pytest.fixture(scope="module")
def serial(riveted, source, tmp_path_factory):
    path = tmp_path_factory.mktemp("serial") / "s.h5"
    summary = run_batch(FasteningCase(riveted), source, N, path, chunk_size=5)
    assert summary.as_dict() | {"seconds": 0} == {
        "samples": N,
        "computed": N,
        "reused": 0,
        "failed": 0,
        "seconds": 0,
    }
    return load_batch(path)


def assert_same(data, reference):
    """Equal up to round-off: BLAS may sum in another order in another process or thread."""
    np.testing.assert_array_equal(data.indices, reference.indices)
    for name, values in reference.fields.items():
        scale = float(np.max(np.abs(values.astype(float))))
        np.testing.assert_allclose(
            data.fields[name], values, rtol=1e-10, atol=1e-12 * scale, err_msg=name
        )


def test_process_pool_gives_the_serial_results(riveted, source, serial, tmp_path):
    summary = run_batch(
        FasteningCase(riveted), source, N, tmp_path / "p.h5", workers=2, chunk_size=5
    )
    assert summary.computed == N
    assert_same(load_batch(tmp_path / "p.h5"), serial)
    from contactqp.studies import executors

    assert executors._worker_state is None  # the workers' state stays in the workers


def test_dask_cluster_gives_the_serial_results(riveted, source, serial, tmp_path):
    import distributed

    # threads in this process, reached over TCP like a remote scheduler
    with distributed.LocalCluster(
        n_workers=1,
        processes=False,
        threads_per_worker=1,
        protocol="tcp",
        host="127.0.0.1",
        dashboard_address=":0",  # a free port: no clash with another run on this machine
    ) as cluster:
        summary = run_batch(
            FasteningCase(riveted),
            source,
            N,
            tmp_path / "d.h5",
            scheduler=cluster.scheduler_address,
            chunk_size=5,
        )
    assert summary.computed == N
    assert_same(load_batch(tmp_path / "d.h5"), serial)


def test_interrupted_runs_resume_with_the_rest_only(riveted, source, serial, tmp_path):
    case, path = FasteningCase(riveted), tmp_path / "r.h5"
    first = run_batch(case, source, N, path, chunk_size=5, limit=7)  # stops inside a chunk
    assert (first.computed, first.reused, first.complete) == (7, 0, False)

    def interrupt(done, total):  # Ctrl-C after the next stored chunk
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_batch(case, source, N, path, progress=interrupt)
    partial = load_batch(path)
    assert partial.indices.tolist() == list(range(10))
    rest = run_batch(case, source, N, path)
    assert (rest.computed, rest.reused, rest.complete) == (N - 10, 10, True)
    assert_same(load_batch(path), serial)
    again = run_batch(case, source, N, path)
    assert (again.computed, again.reused) == (0, N)


def test_a_store_refuses_another_study(riveted, source, tmp_path):
    path = tmp_path / "x.h5"
    run_batch(FasteningCase(riveted), source, 3, path)
    other = GaussianGapField(source.coordinates, 1e-4, 0.03, mean=1.5e-4, seed=99)
    with pytest.raises(InvalidInputError, match="another study"):
        run_batch(FasteningCase(riveted), other, 3, path)


def test_statistics_from_file_samples_match_direct_solves(riveted, source, tmp_path):
    gaps = source.realisations(range(6))
    np.save(tmp_path / "g.npy", gaps)
    np.savetxt(tmp_path / "g.csv", gaps, delimiter=",")
    from_csv = load_gap_samples(tmp_path / "g.csv")
    np.testing.assert_allclose(from_csv.samples, gaps, rtol=1e-15)
    case = FasteningCase(riveted)
    summary = run_batch(
        case, load_gap_samples(tmp_path / "g.npy"), 6, tmp_path / "f.h5", workers=2, chunk_size=2
    )
    assert summary.complete and summary.failed == 0
    stats = load_batch(tmp_path / "f.h5").statistics(levels=(0.5, 0.9))
    final = [riveted.fasten(g).final for g in gaps]
    np.testing.assert_allclose(
        stats.mean, np.mean([r.gaps for r in final], axis=0), rtol=1e-9, atol=1e-15
    )
    np.testing.assert_allclose(
        stats.quantiles[1], np.quantile([r.gaps for r in final], 0.9, axis=0), rtol=1e-9, atol=1e-15
    )
    np.testing.assert_allclose(
        stats.contact_probability,
        np.mean([r.contact_status == ContactStatus.CLOSED for r in final], axis=0),
    )
    assert 0 < stats.contact_probability.max() <= 1
    png = plot_statistics(stats, riveted.points, tmp_path / "stats.png")
    assert png.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(InvalidInputError, match="has 6"):
        run_batch(case, GapSamples(gaps), 7, tmp_path / "g.h5")


def test_a_store_refuses_the_same_delassus_operator_with_another_free_deformation(tmp_path):
    # contact on node 0 only, a load on node 1: W = R_00 and the loads are the same, but the
    # coupling R_01 (so A R P, so every answer) differs; resuming would reuse wrong samples
    from contactqp import GapObstacle, ReducedModel

    loads = np.array([0.0, 5.0])
    cases = [
        GapVariation(
            ContactProblem(
                ReducedModel(flexibility=[[1.0, c], [c, 2.0]], dofs_per_node=1),
                loads,
                [GapObstacle([0], [1.0])],
            )
        )
        for c in (0.1, 0.5)
    ]
    samples = GapSamples(np.linspace(0.0, 3.0, 4)[:, None])
    run_batch(cases[0], samples, 4, tmp_path / "c.h5")
    with pytest.raises(InvalidInputError, match="another study"):
        run_batch(cases[1], samples, 4, tmp_path / "c.h5")
    strict = ContactProblem(
        cases[0].problem.model, loads, [GapObstacle([0], [1.0])], certificate_tol=1e-12
    )
    with pytest.raises(InvalidInputError, match="another study"):
        run_batch(GapVariation(strict), samples, 4, tmp_path / "c.h5")


def test_bad_scheduler_or_store_is_bad_input(riveted, source, tmp_path, monkeypatch):
    import socket

    import distributed

    def slow_client(*args, **kwargs):  # what a Client does when its IO loop is slow to start
        raise AssertionError("the IO loop did not start within 10 s")

    # told before any Dask client (no IO loop, no timer) and before any store is made
    monkeypatch.setattr(distributed, "Client", slow_client)
    with socket.socket() as free:  # a port nobody listens on
        free.bind(("127.0.0.1", 0))
        closed = free.getsockname()[1]
    case = FasteningCase(riveted)
    for address, message in [
        (
            "no-port",
            (
                "Dask scheduler 'no-port' is not an address like tcp://host:port: "
                "missing port number"
            ),
        ),
        ("tcp://127.0.0.1:99999", "port 99999 out of range"),
        ("foo://host:1", "unknown scheme 'foo'"),
        (
            f"tcp://127.0.0.1:{closed}",
            f"cannot reach the Dask scheduler 'tcp://127.0.0.1:{closed}'",
        ),
    ]:
        with pytest.raises(InvalidInputError, match=message):
            run_batch(case, source, 2, tmp_path / "a.h5", scheduler=address)
        assert not (tmp_path / "a.h5").exists(), address
    monkeypatch.undo()
    import subprocess
    import sys

    holder = subprocess.Popen(  # another process holds the store open (HDF5 locks it)
        [
            sys.executable,
            "-c",
            "import h5py, sys, time; f = h5py.File(sys.argv[1], 'w'); "
            "print('open', flush=True); time.sleep(60)",
            str(tmp_path / "busy.h5"),
        ],
        stdout=subprocess.PIPE,
    )
    try:
        assert holder.stdout.readline().strip() == b"open"
        with pytest.raises(FileFormatError, match="busy.h5: cannot open the batch store"):
            run_batch(case, source, 2, tmp_path / "busy.h5")
    finally:
        holder.kill()
        holder.wait()
    (tmp_path / "junk.h5").write_text("not hdf5")
    with pytest.raises(FileFormatError, match="junk.h5: not a contactqp batch store"):
        run_batch(case, source, 2, tmp_path / "junk.h5")


def test_a_store_whose_creation_was_interrupted_is_started_again(riveted, source, serial, tmp_path):
    import h5py

    from contactqp.studies.store import FORMAT

    path = tmp_path / "half.h5"
    with h5py.File(path, "w") as store:  # killed while creating the datasets (marked first)
        store.attrs["format"] = FORMAT
        store.create_dataset(
            "initial_gap", shape=(0, riveted.n_pairs), maxshape=(None, riveted.n_pairs), dtype="f8"
        )
    summary = run_batch(FasteningCase(riveted), source, N, path, chunk_size=5)
    assert summary.computed == N
    assert_same(load_batch(path), serial)


def test_a_store_refuses_an_hdf5_file_that_is_not_a_store_and_leaves_it_as_it_is(
    riveted, source, tmp_path
):
    # was: any HDF5 file without a 'done' dataset was wiped and reused
    import h5py

    case = FasteningCase(riveted)
    with h5py.File(tmp_path / "mine.h5", "w") as other:
        other["results"] = np.arange(5.0)
    with h5py.File(tmp_path / "tagged.h5", "w") as other:
        other.attrs["author"] = "someone"
    for name in ("mine.h5", "tagged.h5"):
        before = (tmp_path / name).read_bytes()
        with pytest.raises(FileFormatError) as info:
            run_batch(case, source, 2, tmp_path / name)
        assert str(info.value) == (
            f"{tmp_path / name} is not a contactqp batch store (it "
            "holds other HDF5 data, left as it is): give another output"
        )
        assert (tmp_path / name).read_bytes() == before
    h5py.File(tmp_path / "empty.h5", "w").close()  # an empty file holds nothing to lose
    assert run_batch(case, source, 2, tmp_path / "empty.h5").computed == 2


def test_a_store_whose_growth_was_interrupted_grows_on_resume(riveted, source, serial, tmp_path):
    import h5py

    path = tmp_path / "grow.h5"
    run_batch(FasteningCase(riveted), source, 3, path, chunk_size=5)
    with h5py.File(path, "a") as store:  # killed after growing 'done' only
        store["done"].resize(N, axis=0)
    summary = run_batch(FasteningCase(riveted), source, N, path)
    assert (summary.reused, summary.computed) == (3, N - 3)
    assert_same(load_batch(path), serial)


def test_gap_fields_of_the_wrong_width_are_refused_before_a_store_is_made(riveted, tmp_path):
    path = tmp_path / "w.h5"
    with pytest.raises(InvalidInputError, match="gap fields have 5 values, the case has 77"):
        run_batch(FasteningCase(riveted), GapSamples(np.zeros((3, 5))), 3, path)
    assert not path.exists()
    summary = run_batch(FasteningCase(riveted), GapSamples(np.full((3, 77), 1e-4)), 3, path)
    assert summary.complete


def test_load_batch_reads_the_first_samples_only(riveted, source, tmp_path):
    path = tmp_path / "n.h5"
    run_batch(FasteningCase(riveted), source, 6, path, chunk_size=4)
    data = load_batch(path, 3)
    assert data.indices.tolist() == [0, 1, 2]
    np.testing.assert_array_equal(data.fields["gap"], load_batch(path).fields["gap"][:3])


def test_bad_sources(tmp_path):
    with pytest.raises(FileFormatError, match="not found"):
        load_gap_samples(tmp_path / "none.npy")
    (tmp_path / "g.h5").write_text("1,2\n")
    with pytest.raises(FileFormatError) as info:
        load_gap_samples(tmp_path / "g.h5")
    assert (
        str(info.value) == f"{tmp_path / 'g.h5'}: gap samples must be .npy, .npz or .csv (or .txt)"
    )
    (tmp_path / "g.txt").write_text("1,2\n3,x\n")
    with pytest.raises(FileFormatError, match=r"g\.txt: not a table of numbers"):
        load_gap_samples(tmp_path / "g.txt")
    with pytest.raises(InvalidInputError, match="correlation_length"):
        GaussianGapField(np.zeros((3, 2)), 1e-4, 0.0)


def test_corrupt_or_truncated_numpy_gap_files_are_one_line_format_errors(tmp_path):
    gaps = np.full((4, 6), 1e-4)
    np.savez_compressed(tmp_path / "g.npz", gaps=gaps)
    np.save(tmp_path / "g.npy", gaps)
    np.testing.assert_array_equal(load_gap_samples(tmp_path / "g.npz").samples, gaps)
    whole = (tmp_path / "g.npz").read_bytes()
    broken = {
        "cut.npz": whole[: len(whole) // 2],  # truncated: BadZipFile
        "crc.npz": whole[:60] + bytes(b ^ 0xFF for b in whole[60:90]) + whole[90:],
        "junk.npz": b"PK\x03\x04 not really a zip",
        "cut.npy": (tmp_path / "g.npy").read_bytes()[:100],  # EOF in the data
        "zip.npy": whole[: len(whole) // 2],
    }  # np.load goes by content, not name
    for name, data in broken.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(FileFormatError) as info:
            load_gap_samples(tmp_path / name)
        assert str(info.value).startswith(f"{tmp_path / name}: ") and "\n" not in str(info.value), (
            name
        )
    np.savez(tmp_path / "two.npz", a=gaps, b=gaps)
    with pytest.raises(InvalidInputError, match=r"two\.npz: the archive holds 2 arrays"):
        load_gap_samples(tmp_path / "two.npz")
    np.save(tmp_path / "objects.npy", np.array([{}, 1], dtype=object), allow_pickle=True)
    with pytest.raises(FileFormatError, match=r"objects\.npy: not a readable"):
        load_gap_samples(tmp_path / "objects.npy")


CHILD = """
import sys, time
import numpy as np
from contactqp.studies import GaussianGapField, run_batch
from contactqp.applications.riveting import Assembly, FasteningCase

class SlowField(GaussianGapField):  # the same study, 50 ms per sample: time to stop it
    def realisations(self, indices):
        time.sleep(0.05 * len(indices))
        return super().realisations(indices)

model = Assembly(grid=(11, 7), refine=1, fasteners=((1, 3), (5, 3), (9, 3))).build()
field = SlowField(model.points, 1e-4, 0.03, mean=1.5e-4, seed=11)
print("started", flush=True)
run_batch(FasteningCase(model), field, int(sys.argv[2]), sys.argv[1], chunk_size=5,
          progress=lambda done, total: print("stored", done, flush=True))
"""


@pytest.mark.parametrize("how", ["SIGINT", "SIGKILL"])
def test_a_killed_process_loses_nothing_stored(riveted, source, serial, tmp_path, how):
    # Ctrl-C (SIGINT to the process group, as a terminal sends it) or kill -9 of a running
    # study; the rerun computes the samples not stored and gives the uninterrupted results
    import os
    import signal
    import subprocess
    import sys

    path = tmp_path / "k.h5"
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(path), str(N)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    assert child.stdout.readline().strip() == b"started"
    assert child.stdout.readline().split()[0] == b"stored"  # (a fixed delay may come sooner)
    os.killpg(child.pid, getattr(signal, how))
    _, err = child.communicate(timeout=30)
    assert child.returncode != 0, err.decode()
    stored = load_batch(path).indices
    assert 0 < len(stored) < N and stored.tolist() == list(range(len(stored)))
    rest = run_batch(FasteningCase(riveted), source, N, path)
    assert (rest.reused, rest.computed) == (len(stored), N - len(stored))
    assert_same(load_batch(path), serial)


POOL_CHILD = """
import multiprocessing, sys, time
from contactqp.studies import GaussianGapField, run_batch
from contactqp.applications.riveting import Assembly, FasteningCase

class LoggedField(GaussianGapField):  # 50 ms per sample; logs each chunk a worker starts
    def realisations(self, indices):
        if multiprocessing.parent_process() is not None:  # not the parent's check of sample 0
            with open(sys.argv[3], "a") as log:
                log.write(" ".join(str(int(k)) for k in indices) + "\\n")
        time.sleep(0.05 * len(indices))
        return super().realisations(indices)

model = Assembly(grid=(11, 7), refine=1, fasteners=((1, 3), (5, 3), (9, 3))).build()
field = LoggedField(model.points, 1e-4, 0.03, mean=1.5e-4, seed=11)
print("started", flush=True)
run_batch(FasteningCase(model), field, int(sys.argv[2]), sys.argv[1], workers=2, chunk_size=5)
"""


def test_ctrl_c_of_a_pool_study_stores_the_chunks_its_workers_finish(
    riveted, source, serial, tmp_path
):
    # Ctrl-C reaching the parent only (kill -INT of its pid): the chunks the workers had
    # started still finish, and are stored rather than thrown away
    import os
    import signal
    import subprocess
    import sys

    path, log = tmp_path / "p.h5", tmp_path / "started.txt"
    child = subprocess.Popen(
        [sys.executable, "-c", POOL_CHILD, str(path), str(4 * N), str(log)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    assert child.stdout.readline().strip() == b"started"
    wait_for_lines(log, 1)  # a worker runs a chunk (a fixed delay may pass before the pool runs)
    os.kill(child.pid, signal.SIGINT)
    _, err = child.communicate(timeout=60)
    assert child.returncode != 0 and b"KeyboardInterrupt" in err, err.decode()
    started = sorted(int(k) for line in log.read_text().split("\n") for k in line.split())
    stored = load_batch(path).indices.tolist()
    assert 0 < len(stored) < 4 * N and set(started) <= set(stored), (started, stored)
    rest = run_batch(FasteningCase(riveted), source, 4 * N, path)
    assert (rest.reused, rest.computed) == (len(stored), 4 * N - len(stored))
    assert_same(load_batch(path, N), serial)


def wait_for_lines(path, count):
    """Until the file ``path`` has ``count`` lines (a bounded wait: 60 s)."""
    import time

    for _ in range(6000):
        if path.exists() and path.read_text().count("\n") >= count:
            return
        time.sleep(0.01)
    raise AssertionError(f"{path} did not get {count} lines in 60 s")


class LoggedField(GaussianGapField):
    """Logs the samples of each chunk a pool worker starts to the file ``log``."""

    def __init__(self, *args, log, **kwargs):
        super().__init__(*args, **kwargs)
        self.log = log

    def realisations(self, indices):
        import multiprocessing

        if multiprocessing.parent_process() is not None:  # not the parent's check of sample 0
            with open(self.log, "a") as log:
                log.write(" ".join(str(int(k)) for k in indices) + "\n")
        return super().realisations(indices)


def test_ctrl_c_while_a_pool_study_stores_a_chunk_keeps_the_chunks_its_workers_run(
    riveted, source, serial, tmp_path
):
    # Ctrl-C while the parent stores the first chunk and a worker runs another: that chunk
    # was computed and thrown away, and the pool went on with the whole study until exit
    path, log = tmp_path / "s.h5", tmp_path / "started.txt"
    field = LoggedField(source.coordinates, 1e-4, 0.03, mean=1.5e-4, seed=11, log=log)

    def interrupt(done, total):
        wait_for_lines(log, 2)  # another chunk is running
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_batch(
            FasteningCase(riveted), field, 4 * N, path, workers=2, chunk_size=5, progress=interrupt
        )
    started = sorted(int(k) for line in log.read_text().split("\n") for k in line.split())
    stored = load_batch(path).indices.tolist()
    assert len(started) >= 10 and set(started) <= set(stored) and len(stored) < 4 * N, (
        started,
        stored,
    )
    rest = run_batch(FasteningCase(riveted), source, 4 * N, path)
    assert (rest.reused, rest.computed) == (len(stored), 4 * N - len(stored))
    assert_same(load_batch(path, N), serial)

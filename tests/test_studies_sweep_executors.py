"""snoworm.studies.sweep.executors: serial, process, Dask and batched executors agree; executor failures."""

from __future__ import annotations

import pytest

import snoworm.studies.sweep as sweep_mod
from snoworm.config.schema import ScenarioError
from snoworm.studies.sweep import BatchExecutor, SerialExecutor, SweepTask, run_sweep
from tests.sweep_helpers import SHORT, SMALL, TOW6, comparable, csv_rows


def test_serial_and_two_processes_give_identical_rows(tmp_path):
    serial = run_sweep(TOW6, SMALL, out_dir=tmp_path / "s", plot=False)
    par = run_sweep(TOW6, SMALL, out_dir=tmp_path / "p", jobs=2, plot=False)
    assert len(serial) == 4 and all(r["status"] == "ok" for r in serial)
    assert comparable(serial) == comparable(par)
    # the files hold the same rows too (the CSV may be in completion order)
    a = sorted(csv_rows(tmp_path / "s" / "summary.csv"), key=lambda r: r["case_id"])
    b = sorted(csv_rows(tmp_path / "p" / "summary.csv"), key=lambda r: r["case_id"])
    for r in a + b:
        r.pop("wall_time_s")
    assert a == b
    # towing costs speed; fresher snow gives speed
    v = {(r["terrain.xt"], r["tow.force_N"]): r["mean_speed_mps"] for r in serial}
    assert v[(0.9, 200)] < v[(0.9, 0)] and v[(0.7, 0)] < v[(0.9, 0)]


def test_dask_cluster_gives_identical_rows(tmp_path):
    distributed = pytest.importorskip(
        "distributed", reason="dask[distributed] not installed (pip install snoworm[dask])"
    )
    serial = run_sweep(TOW6, SMALL, plot=False)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        table = run_sweep(TOW6, SMALL, out_dir=tmp_path / "d", scheduler=cluster.scheduler_address, plot=False)
    assert comparable(table) == comparable(serial)
    assert len(csv_rows(tmp_path / "d" / "summary.csv")) == 4


def test_missing_dask_gives_an_install_hint(monkeypatch):
    monkeypatch.setitem(__import__("sys").modules, "distributed", None)
    with pytest.raises(ScenarioError, match=r"snoworm\[dask\]"):
        run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], scheduler="tcp://127.0.0.1:1", plot=False)


def test_executor_failure_is_reported_and_rows_kept(tmp_path):
    class Dying:
        def map_unordered(self, fn, tasks):
            it = iter(tasks)
            yield fn(next(it))
            raise OSError("worker lost")

        def close(self):
            pass

    with pytest.raises(sweep_mod.SweepExecutionError, match="worker lost.*1 finished cases"):
        run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], out_dir=tmp_path, executor=Dying(), plot=False)
    assert len(csv_rows(tmp_path / "summary.csv")) == 1
    assert len(run_sweep(TOW6, ["terrain.xt=0.7,0.9", SHORT], out_dir=tmp_path, plot=False)) == 2


def test_batch_executor_without_pool_yields_every_task_once():
    """Tasks that are not scenarios go one by one through fn, in chunks of batch_size."""
    seen = []

    def fn(task):
        seen.append(task.index)
        return {"index": task.index, "status": "stub"}

    ex = BatchExecutor(batch_size=3, metrics=None)
    out = list(ex.map_unordered(fn, (SweepTask(j, raw="not a mapping") for j in range(7))))
    ex.close()
    assert sorted(r["index"] for r in out) == list(range(7)) == sorted(seen)
    assert list(SerialExecutor().map_unordered(lambda t: 2 * t, [1, 2, 3])) == [2, 4, 6]


def _listener(answer: bytes):
    """A local TCP service that is not Dask: it accepts and stays silent (``b""``) or answers junk."""
    import socket
    import threading

    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    conns = []

    def serve():
        while True:
            try:
                c, _ = srv.accept()
            except OSError:
                return
            conns.append(c)
            if answer:
                c.sendall(answer)

    threading.Thread(target=serve, daemon=True).start()
    return srv, conns


@pytest.mark.parametrize("answer", [b"", b"HTTP/1.0 200 OK\r\n\r\n" + b"hello" * 1000])
def test_a_service_other_than_dask_is_exit_2_not_a_hang(monkeypatch, answer):
    pytest.importorskip("distributed", reason="dask[distributed] not installed")
    from snoworm.studies.sweep import executors

    monkeypatch.setattr(executors, "HANDSHAKE_TIMEOUT_S", 1.0)  # the bound under test, shortened
    srv, conns = _listener(answer)
    try:
        with pytest.raises(ScenarioError, match=r"--scheduler .*cannot connect to the Dask scheduler"):
            run_sweep(TOW6, ["terrain.xt=0.7", SHORT], scheduler=f"tcp://127.0.0.1:{srv.getsockname()[1]}", plot=False)
    finally:
        srv.close()
        for c in conns:
            c.close()


@pytest.mark.parametrize("address", ["tls://127.0.0.1:1", "ucx://127.0.0.1:1", "inproc://x"])
def test_other_protocols_are_refused_naming_the_option(address):
    pytest.importorskip("distributed", reason="dask[distributed] not installed")
    with pytest.raises(ScenarioError, match=r"--scheduler: .*tcp://host:port addresses only"):
        run_sweep(TOW6, ["terrain.xt=0.7", SHORT], scheduler=address, plot=False)

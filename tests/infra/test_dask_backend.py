"""The Dask backend on a real ``distributed.LocalCluster`` (2 worker processes, loopback only).

Bit-identical results against the local path (a batch on a measured spindle whose store the
workers never see, and a library sync), a worker killed mid-job, the scheduler going away
mid-job, and a scheduler that is not there at all.
"""

from __future__ import annotations

import io
import os
import socket
import threading
import time
from collections.abc import Iterator

import orjson
import pytest

distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed (pip install 'rcsa[dask]')")

from rcsa.app.jobs import Workbench, job_handlers, job_store, run_work, stream_work  # noqa: E402
from rcsa.app.libraries import prepare_batch, prepare_sync  # noqa: E402
from rcsa.app.measurements import demo_measurement  # noqa: E402
from rcsa.infra.compute_backends import ComputeUnavailable, LocalBackend, compute_backend  # noqa: E402
from rcsa.infra.job_queue import JobRunner  # noqa: E402
from rcsa.libraries import chunks  # noqa: E402
from rcsa.libraries import sync as library_sync  # noqa: E402
from rcsa.measured.store import MeasurementStore  # noqa: E402
from rcsa.reference import ra1  # noqa: E402
from tests.infra import dask_helpers  # noqa: E402
from tests.libraries.test_sync import make_library, tool_id  # noqa: E402

GRID = {"start_hz": 50.0, "stop_hz": 1000.0, "step_hz": 10.0}  # 96 lines
#: The scheduler's HTTP server (health, metrics; no dashboard without bokeh) on a free loopback
#: port: ``dashboard_address=None`` only drops the dashboard and still binds port 8787.
_HTTP = "127.0.0.1:0"


class _LockedStore:
    """A measurement source that cannot be pickled: proof that no chunk ships the store."""

    def __init__(self, store: MeasurementStore) -> None:
        self._store = store
        self._lock = threading.Lock()

    def get(self, measurement_id: str):
        with self._lock:
            return self._store.get(measurement_id)


@pytest.fixture
def nobody_listens() -> Iterator[str]:
    """A loopback address where connections are refused for the whole test: its port stays
    bound by this socket, which never listens, so no other process can start a server there."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        yield f"tcp://127.0.0.1:{s.getsockname()[1]}"


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    marker = tmp_path_factory.mktemp("dask") / "killed-once"
    os.environ[dask_helpers.KILL_MARKER] = str(marker)  # inherited by the worker processes
    try:
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                      dashboard_address=_HTTP, silence_logs=50) as c:
            yield c, marker
    finally:
        os.environ.pop(dask_helpers.KILL_MARKER, None)


@pytest.fixture
def dask(cluster):
    backend = compute_backend(cluster[0].scheduler_address, connect_timeout_s=10)
    yield backend
    backend.close()


@pytest.fixture
def small_chunks(monkeypatch):
    """Ten tools per chunk at this grid, so that a few tools make several chunks."""
    monkeypatch.setattr(chunks, "CHUNK_TOOL_LINES", 960)


def _batch(assembly, n):
    combos = [{"id": f"T{i}", "holder": assembly["holder"], "joints": assembly["joints"],
               "tool": {**assembly["tool"], "stickout_m": 0.04 + 0.001 * i}} for i in range(n)]
    combos[13]["tool"] = {**combos[13]["tool"], "stickout_m": 0.5}  # refused by the model: an error result
    return {"frequency": GRID, "spindle": assembly["spindle"], "combinations": combos}


def test_a_batch_on_dask_is_bit_identical_and_ships_no_store(tmp_path, dask, small_chunks):
    store = MeasurementStore(tmp_path / "store")
    mid = store.put(demo_measurement())
    assembly = {**ra1(GRID), "spindle": {"measurement_id": mid}}
    bench = Workbench(_LockedStore(store))
    work = prepare_batch(bench, _batch(assembly, 25))
    local = orjson.dumps(run_work(bench, "batch", work.request, backend=LocalBackend()).document,
                         option=orjson.OPT_SERIALIZE_NUMPY)
    seen = []
    out = io.BytesIO()
    summary = stream_work(bench, "batch", work.request, backend=dask,
                          progress=lambda d, t: seen.append((d, t))).write(out)
    assert out.getvalue() == local  # the same bytes, computed on the workers from the shipped receptance
    assert summary == {"ok": 24, "error": 1} and seen[-1] == (25, 25)
    doc = orjson.loads(local)
    assert doc["results"][13]["error"]["field"] == "combinations[13].tool.stickout_m"  # in the whole batch


def test_a_sync_on_dask_is_bit_identical_and_a_killed_worker_loses_nothing(tmp_path, cluster, dask, small_chunks,
                                                                              monkeypatch):
    _, marker = cluster
    library = make_library(24)
    settings = {"spindle": ra1(GRID)["spindle"], "frequency": GRID, "joints": ra1(GRID)["joints"]}
    local = Workbench(None, tmp_path / "local")
    run_work(local, "library-sync", prepare_sync(local, "shop", library, **settings).request)

    # the same sync as a job on the cluster, whose first chunk kills its worker process
    monkeypatch.setattr(library_sync, "compute_chunk", dask_helpers.compute_chunk_killing_its_worker_once)
    if marker.exists():
        marker.unlink()
    bench = Workbench(None, tmp_path / "remote", backend=dask)
    jobs = job_store(tmp_path / "remote")
    job = jobs.submit("library-sync", prepare_sync(bench, "shop", library, **settings).request)
    runner = JobRunner(jobs, job_handlers(bench), heartbeat_s=0.2)
    assert runner.run_one()
    assert marker.exists()  # a worker was killed mid-job
    done = jobs.get(job.id)
    assert done.status == "succeeded", done.error
    assert done.attempts == 1 and done.progress == 1.0 and done.summary["computed"] == 24
    remote_libs, local_libs = bench.libraries, local.libraries
    tools = remote_libs.get("shop")["tools"]
    assert [t["id"] for t in tools] == [tool_id(i) for i in range(24)]  # each tool once
    assert remote_libs.cache.missing(t["result_sha256"] for t in tools) == set()
    with remote_libs.cache._connect() as con:
        assert con.execute("SELECT COUNT(*) FROM results").fetchone()[0] == 24  # nothing stored twice
    assert orjson.dumps(remote_libs.results("shop")["results"], option=orjson.OPT_SERIALIZE_NUMPY) == \
        orjson.dumps(local_libs.results("shop")["results"], option=orjson.OPT_SERIALIZE_NUMPY)


@pytest.mark.slow
def test_losing_the_scheduler_fails_the_job_with_the_reason(tmp_path, monkeypatch):
    monkeypatch.setattr(library_sync, "compute_chunk", dask_helpers.compute_chunk_slowly)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=_HTTP, silence_logs=50) as doomed:
        backend = compute_backend(doomed.scheduler_address, connect_timeout_s=10)
        bench = Workbench(None, tmp_path, backend=backend)
        jobs = job_store(tmp_path)
        library = make_library(2)
        request = prepare_sync(bench, "shop", library, spindle=ra1(GRID)["spindle"], frequency=GRID).request
        job = jobs.submit("library-sync", request)
        runner = JobRunner(jobs, job_handlers(bench), heartbeat_s=0.2)
        worker = threading.Thread(target=runner.run_one)
        worker.start()
        deadline = time.monotonic() + 300
        while jobs.get(job.id).status == "queued" and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.5)
        doomed.close()  # the scheduler (and its worker) go away mid-job
    worker.join()  # a hang is caught by pytest-timeout, not timed here
    failed = jobs.get(job.id)
    assert failed.status == "failed" and failed.error["status"] == 503
    assert failed.error["title"] == "Compute cluster unavailable" and "scheduler" in failed.error["detail"]
    assert "shop" not in bench.libraries  # nothing half-committed
    backend.close()


def test_a_missing_scheduler_is_a_clear_error_not_a_hang(nobody_listens):
    address = nobody_listens
    with pytest.raises(ComputeUnavailable, match=f"cannot reach the Dask scheduler at {address} within 1 s"):
        compute_backend(address, connect_timeout_s=1)


def test_service_and_cli_refuse_to_start_on_a_missing_scheduler(tmp_path, monkeypatch, nobody_listens):
    from service.main import create_app
    from typer.testing import CliRunner

    from rcsa.cli import app as cli
    from tests.service.conftest import TestClient, settings_for

    address = nobody_listens
    app = create_app(settings_for(tmp_path / "store", dask_scheduler=address, dask_connect_timeout_s=1))
    with pytest.raises(ComputeUnavailable, match="cannot reach the Dask scheduler"), TestClient(app):
        pass

    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "store"))
    lib, spindle = tmp_path / "lib.json", tmp_path / "ra1.json"
    lib.write_text(orjson.dumps(make_library(1)).decode())
    spindle.write_text(orjson.dumps(ra1(GRID)).decode())
    r = CliRunner().invoke(cli, ["library", "sync", str(lib), "--spindle", str(spindle), "-q", "--dask-scheduler",
                                 address], env={"RCSA_DASK_CONNECT_TIMEOUT_S": "1"})
    assert r.exit_code == 1 and f"error: cannot reach the Dask scheduler at {address}" in r.stderr


@pytest.mark.slow
def test_readyz_says_not_ready_with_the_reason_when_the_scheduler_is_gone(tmp_path):
    from service.main import create_app

    from tests.service.conftest import TestClient, settings_for

    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=_HTTP, silence_logs=50) as doomed:
        app = create_app(settings_for(tmp_path / "store", dask_scheduler=doomed.scheduler_address,
                                      dask_connect_timeout_s=2, job_workers=0))
        with TestClient(app) as client:
            ready = client.get("/readyz")
            assert ready.status_code == 200 and ready.json()["checks"]["compute"] == "ok"
            doomed.close()  # the scheduler goes away
            gone = client.get("/readyz")
    assert gone.status_code == 503, gone.text
    assert gone.json()["status"] == "not ready"
    assert doomed.scheduler_address.removeprefix("tcp://") in gone.json()["checks"]["compute"]


@pytest.mark.slow
def test_chatter_safe_pockets_on_dask_equal_the_local_ones(dask):
    """Issue 20: a library's pockets are found in chunks of tools on the cluster (a large
    recommendation job's path); each tool gets the pocket it gets here, with progress."""
    from rcsa.libraries.recommend import pockets_on
    from tests.infra.pocket_cases import pocket_case

    cuts, settings = pocket_case(3)
    seen = []
    there = pockets_on(dask, tools_per_chunk=1)(cuts, settings, lambda d, t: seen.append((d, t)))
    here = pockets_on(LocalBackend())(cuts, settings)
    assert [a.pocket for a in there] == [b.pocket for b in here] and all(a.pocket for a in there)
    assert seen[-1] == (3, 3) and len(seen) == 4


def test_a_lobes_job_on_the_cluster_answers_as_here(dask, monkeypatch):
    """A lobes job of a service with a Dask cluster (and ``rcsa lobes --dask-scheduler``): the
    semi-discretization's speeds in parts on the cluster's workers, joined to the answer of one
    process (``tests/app/test_lobes_spread.py`` says how close)."""
    from rcsa.app import analyses
    from rcsa.app.analyses import stability_lobes
    from tests.app.test_lobes_spread import REQUEST, assert_same_answers

    monkeypatch.setattr(analyses, "SDM_MIN_SPREAD_COST", 0.0)  # a small request, spread all the same
    there = run_work(Workbench(None, backend=dask), "lobes", REQUEST).document
    assert_same_answers(there, stability_lobes(REQUEST))

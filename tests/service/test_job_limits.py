"""Jobs at scale: a time limit, fair claiming and quotas, a disk budget, results streamed both ways."""

from __future__ import annotations

import asyncio
import io
import sqlite3
import time
import tracemalloc
from contextlib import closing

import orjson
import pytest

from rcsa.app.jobs import Workbench, run_work, stream_work
from rcsa.app.libraries import prepare_batch
from rcsa.infra.compute_backends import LocalBackend
from rcsa.infra.job_queue import JobRunner, JobStore, ResultEvicted
from rcsa.libraries import chunks
from rcsa.reference import ra1

from .conftest import JOB_TOKEN, READ, assert_problem


def _batch(n: int, grid: dict, bad: tuple[int, ...] = ()) -> dict:
    doc = ra1(grid)
    combos = [{"id": f"T{i}", "holder": doc["holder"], "joints": doc["joints"],
               "tool": {**doc["tool"], "stickout_m": 0.04 + 0.04 * i / max(n, 1)}} for i in range(n)]
    for i in bad:
        combos[i]["tool"] = {**combos[i]["tool"], "stickout_m": 0.5}  # longer than the tool: refused
    return {"frequency": grid, "spindle": doc["spindle"], "combinations": combos}


def _wait(client, location: str, timeout_s: float = 300.0) -> dict:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        job = client.get(location).json()
        if job["status"] in ("succeeded", "failed"):
            return job
        time.sleep(0.05)
    raise AssertionError(f"{location} did not finish")


# --------------------------------------------------------------------------- time limit

def test_a_job_past_its_time_limit_fails_with_a_clear_reason(store_path):
    jobs = JobStore(store_path / "jobs")
    steps = []

    def endless(request, progress):
        for i in range(200):  # 20 s if nobody stops it
            time.sleep(0.1)
            steps.append(i)
            progress(i, 200)
        return {"never": True}, None

    job = jobs.submit("endless", {})
    runner = JobRunner(jobs, {"endless": endless}, heartbeat_s=0.05, time_limit_s=0.4)
    assert runner.run_one()
    assert len(steps) < 20  # stopped at its next progress report, not after all 200 steps
    failed = jobs.get(job.id)
    assert failed.status == "failed" and failed.error["status"] == 504
    assert failed.error["title"] == "Job time limit exceeded" and "0.4 s" in failed.error["detail"]
    assert not list((store_path / "jobs" / "results").iterdir())  # no partial result left behind


# --------------------------------------------------------------------------- fairness and quotas

def test_a_small_job_of_another_caller_is_claimed_before_a_flood_s_tail(store_path):
    jobs = JobStore(store_path / "jobs")
    flood = [jobs.submit("batch", {"n": i}, owner="anonymous@10.0.0.7").id for i in range(20)]
    small = jobs.submit("batch", {"small": True}, owner="k-0a1b2c3d").id
    late = jobs.submit("batch", {"late": True}, owner="k-99999999").id
    first, second, third = (jobs.claim(f"r{i}").id for i in range(3))
    assert first == flood[0] and {second, third} == {small, late}  # not after the 19 others
    jobs.succeed(first, "r0", b"{}")
    assert jobs.claim("r3").id == flood[1]  # then round-robin: the flood's owner again

    capped = JobStore(store_path / "capped")
    one = [capped.submit("batch", {"n": i}, owner="a").id for i in range(3)]
    assert capped.claim("r", max_running_per_owner=1).id == one[0]
    assert capped.claim("r", max_running_per_owner=1) is None  # the owner's cap, with nobody else waiting


def test_anonymous_callers_share_one_runner_and_a_keyed_caller_s_job_takes_the_other(store_path):
    """Two runners: two anonymous jobs (two addresses) cannot hold both; a keyed caller's small
    job is claimed by the second runner at once, and a keyed caller is capped on its own."""
    jobs = JobStore(store_path / "jobs")
    anon = [jobs.submit("batch", {"n": i}, owner=f"anonymous@10.0.0.{i}", pool="anonymous").id for i in range(2)]
    assert jobs.claim("r0", max_running_per_owner=1).id == anon[0]
    assert jobs.claim("r1", max_running_per_owner=1) is None  # the anonymous pool already runs one
    keyed = jobs.submit("batch", {"small": True}, owner="k-0a1b2c3d").id
    more = jobs.submit("batch", {"more": True}, owner="k-0a1b2c3d").id
    assert jobs.claim("r1", max_running_per_owner=1).id == keyed
    assert jobs.claim("r2", max_running_per_owner=1) is None  # the keyed caller's cap too
    jobs.succeed(anon[0], "r0", b"{}")
    assert jobs.claim("r0", max_running_per_owner=1).id == anon[1]  # the pool served least recently... tie
    jobs.succeed(keyed, "r1", b"{}")
    assert jobs.claim("r1", max_running_per_owner=1).id == more


def test_the_service_puts_anonymous_jobs_in_one_pool_and_never_shares_a_job_across_callers(make_client,
                                                                                            store_path):
    from service.jobs import ANONYMOUS_POOL

    body = _batch(2, {"start_hz": 5.0, "stop_hz": 500.0, "step_hz": 5.0})
    asynchronous = {"Prefer": "respond-async", "Idempotency-Key": "same-body-1"}
    with make_client(job_workers=0) as client:
        anonymous = client.post("/v1/tool-point-frf/batch", json=body, headers=asynchronous)
        keyed = client.post("/v1/tool-point-frf/batch", json=body, headers={**asynchronous, **READ})
        again = client.post("/v1/tool-point-frf/batch", json=body, headers={**asynchronous, **READ,
                                                                            "Idempotency-Key": "same-body-2"})
        assert anonymous.status_code == keyed.status_code == again.status_code == 202
        a, k, k2 = (r.json()["id"] for r in (anonymous, keyed, again))
        assert a != k  # the same body from another caller is another job
        assert k2 == k  # the same caller's retry of the same body reuses its unfinished job
        with closing(sqlite3.connect(store_path / "jobs" / "jobs.sqlite")) as con:  # the pools as stored
            pools = dict(con.execute("SELECT id, pool FROM jobs").fetchall())
        assert pools[a] == ANONYMOUS_POOL and pools[k] is None


def test_a_caller_with_too_many_unfinished_jobs_gets_429_and_others_do_not(make_client, assembly):
    body = _batch(2, {"start_hz": 5.0, "stop_hz": 500.0, "step_hz": 5.0})
    asynchronous = {"Prefer": "respond-async"}
    with make_client(job_workers=0, job_max_unfinished_per_caller=2) as client:
        for _ in range(2):
            assert client.post("/v1/tool-point-frf/batch", json=body, headers=asynchronous).status_code == 202
        refused = client.post("/v1/tool-point-frf/batch", json=body, headers=asynchronous)
        problem = assert_problem(refused, 429)
        assert problem["title"] == "Too many unfinished jobs" and refused.headers["retry-after"]
        assert "anonymous@testclient" in problem["detail"]
        keyed = client.post("/v1/tool-point-frf/batch", json=body, headers={**asynchronous, **READ})
        assert keyed.status_code == 202  # another caller has its own quota
        assert client.post("/v1/tool-point-frf/batch", json=body).status_code == 200  # answered at once: no job


# --------------------------------------------------------------------------- disk budget

def test_the_oldest_results_are_evicted_beyond_the_disk_budget(store_path):
    jobs = JobStore(store_path / "jobs", max_result_bytes=250)
    ids = []
    for i in range(3):
        job = jobs.submit("batch", {"i": i})
        jobs.claim("r")
        jobs.succeed(job.id, "r", b"x" * 100)
        ids.append(job.id)
    assert jobs.kept_result_bytes() == 200
    old = jobs.get(ids[0])
    assert old.status == "succeeded" and old.result_evicted_utc is not None and not old.has_result
    with pytest.raises(ResultEvicted, match="disk budget"):
        jobs.result_path(ids[0])
    assert jobs.result_path(ids[2]).read_bytes() == b"x" * 100
    big = jobs.submit("batch", {"big": True})
    jobs.claim("r")
    jobs.succeed(big.id, "r", b"y" * 1000)  # larger than the budget alone: kept, the others go
    assert jobs.get(big.id).has_result and jobs.kept_result_bytes() == 1000
    assert [jobs.get(i).has_result for i in ids] == [False, False, False]


def test_an_evicted_result_is_410_and_its_job_says_when(make_client):
    body = _batch(3, {"start_hz": 5.0, "stop_hz": 500.0, "step_hz": 5.0})
    with make_client(job_results_max_bytes=1024) as client:  # smaller than one result
        first = _wait(client, client.post("/v1/tool-point-frf/batch", json=body,
                                          headers={"Prefer": "respond-async"}).headers["location"])
        second = _wait(client, client.post("/v1/tool-point-frf/batch", json=body, params={"tool_point": "h"},
                                           headers={"Prefer": "respond-async"}).headers["location"])
        assert second["result_bytes"] > 1024 and client.get(second["result_url"]).status_code == 200
        gone = client.get(first["status_url"]).json()
        assert gone["status"] == "succeeded" and gone["result_evicted_utc"] and gone["result_url"] is None
        problem = assert_problem(client.get(f"{first['status_url']}/result"), 410)
        assert "disk budget" in problem["detail"] and problem["job"]["result_evicted_utc"]


# --------------------------------------------------------------------------- streaming

def test_a_streamed_result_is_the_immediate_answer_byte_for_byte(monkeypatch):
    monkeypatch.setattr(chunks, "CHUNK_TOOL_LINES", 1000)  # 10 tools per chunk at 100 lines
    grid = {"start_hz": 10.0, "stop_hz": 1000.0, "step_hz": 10.0}
    bench = Workbench(None)
    work = prepare_batch(bench, _batch(30, grid, bad=(4, 17)), {25: {"field": "combinations[25].tool",
                                                                      "detail": "refused by the schema"}},
                         tool_point=["h", "n"])
    whole = run_work(bench, "batch", work.request, backend=LocalBackend()).document
    out = io.BytesIO()
    progress = []
    summary = stream_work(bench, "batch", work.request, progress=lambda d, t: progress.append((d, t))).write(out)
    assert out.getvalue() == orjson.dumps(whole, option=orjson.OPT_SERIALIZE_NUMPY)
    assert summary == whole["summary"] == {"ok": 27, "error": 3}
    assert progress[-1] == (29, 29) and len(progress) > 3  # after every chunk
    errors = {r["error"]["field"].split(".")[0] for r in whole["results"] if r["status"] == "error"}
    assert errors == {"combinations[4]", "combinations[17]", "combinations[25]"}  # fields in the whole batch


def test_a_large_job_result_is_written_and_served_in_bounded_memory(make_client, monkeypatch):
    monkeypatch.setattr(chunks, "CHUNK_TOOL_LINES", 20_000)  # 10 tools per chunk at 2 000 lines
    grid = {"start_hz": 2.5, "stop_hz": 5000.0, "step_hz": 2.5}
    with make_client() as client:
        app = client.app
        warm = client.post("/v1/tool-point-frf/batch", json=_batch(2, grid), headers={"Prefer": "respond-async"})
        warm_job = _wait(client, warm.headers["location"])  # modules imported on first use are not the result
        asyncio.run(_serve(app, f"/v1/jobs/{warm_job['id']}/result"))
        tracemalloc.start()
        try:
            base, _ = tracemalloc.get_traced_memory()
            r = client.post("/v1/tool-point-frf/batch", json=_batch(120, grid), headers={"Prefer": "respond-async"})
            job = _wait(client, r.headers["location"])
            _, computing_peak = tracemalloc.get_traced_memory()
            tracemalloc.reset_peak()
            base_serving, _ = tracemalloc.get_traced_memory()
            sent = asyncio.run(_serve(app, f"/v1/jobs/{job['id']}/result"))
            _, serving_peak = tracemalloc.get_traced_memory()
        finally:
            tracemalloc.stop()
    size = job["result_bytes"]
    computing_peak -= base
    serving_peak -= base_serving
    print(f"result {size / 1e6:.1f} MB; memory peak while computing {computing_peak / 1e6:.1f} MB, "
          f"while serving {serving_peak / 1e6:.2f} MB")
    assert job["status"] == "succeeded" and size > 40e6 and sent["bytes"] == size and sent["status"] == 200
    assert computing_peak < size / 3, (computing_peak, size)  # one chunk at a time, never the whole document
    assert serving_peak < size / 20 and sent["largest"] <= 1 << 20, (serving_peak, sent)


async def _serve(app, path: str) -> dict:
    """GET ``path`` straight through the ASGI app, counting and dropping the body pieces."""
    sent = {"status": None, "bytes": 0, "largest": 0}
    requested = False
    forever = asyncio.Event()

    async def receive() -> dict:
        nonlocal requested
        if not requested:
            requested = True
            return {"type": "http.request", "body": b"", "more_body": False}
        await forever.wait()
        return {"type": "http.disconnect"}

    async def send(message: dict) -> None:
        if message["type"] == "http.response.start":
            sent["status"] = message["status"]
        elif message["type"] == "http.response.body":
            n = len(message.get("body", b""))
            sent["bytes"] += n
            sent["largest"] = max(sent["largest"], n)

    scope = {"type": "http", "asgi": {"version": "3.0", "spec_version": "2.3"}, "http_version": "1.1",
             "method": "GET", "scheme": "http", "path": path, "raw_path": path.encode(), "query_string": b"",
             "root_path": "", "headers": [(b"host", b"testserver"), (b"x-job-token", JOB_TOKEN.encode())],
             "client": ("127.0.0.1", 50000),
             "server": ("testserver", 80), "state": {}}
    await app(scope, receive, send)
    return sent

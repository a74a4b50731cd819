"""Batches (sync and as jobs), the job store's claims, and jobs surviving a restart."""

from __future__ import annotations

import multiprocessing
import os
import socket
import time

import numpy as np
import pytest

import rcsa
from rcsa.errors import NotFoundError
from rcsa.infra.job_queue import JobRunner, JobStore
from rcsa.libraries import library_prediction as library_api

from .conftest import GRID, assert_problem, job_access


def _batch(assembly, n_good=2, bad=True):
    combos = [{"id": f"T{i}", "holder": assembly["holder"], "joints": assembly["joints"],
               "tool": {**assembly["tool"], "stickout_m": 0.05 + 0.002 * i}} for i in range(n_good)]
    if bad:
        combos.insert(1, {"id": "bad-stickout", "holder": assembly["holder"],
                          "tool": {**assembly["tool"], "stickout_m": -0.01}})
        combos.append({"id": "bad-type", "holder": assembly["holder"], "tool": "not a tool"})
        combos.append({"holder": assembly["holder"], "tool": assembly["tool"]})
        combos.append({"id": "too-long", "holder": assembly["holder"],  # only rcsa knows this rule
                       "tool": {**assembly["tool"], "stickout_m": 0.5}})
    return {"frequency": GRID, "spindle": assembly["spindle"], "combinations": combos}


def _wait(client, location, timeout_s=300.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        r = client.get(location)
        assert r.status_code == 200, r.text
        job = r.json()
        if job["status"] in ("succeeded", "failed"):
            assert "retry-after" not in r.headers
            return job
        assert r.headers["retry-after"] == "1"
        time.sleep(0.05)
    raise AssertionError(f"job {location} did not finish")


def test_batch_with_bad_combinations_among_good_ones(client, assembly):
    request = _batch(assembly)
    r = client.post("/v1/tool-point-frf/batch", json=request)
    assert r.status_code == 200, r.text
    out = r.json()
    assert [x["id"] for x in out["results"]] == ["T0", "bad-stickout", "T1", "bad-type", None, "too-long"]
    assert [x["status"] for x in out["results"]] == ["ok", "error", "ok", "error", "error", "error"]
    assert out["results"][1]["error"] == {"field": "combinations[1].tool.stickout_m",
                                          "detail": "Input should be greater than or equal to 0.000001"}
    assert out["results"][3]["error"]["field"] == "combinations[3].tool"
    assert out["results"][4]["error"] == {"field": "combinations[4].id", "detail": "is required"}
    assert out["results"][5]["error"]["field"] == "combinations[5].tool.stickout_m"
    assert "overall_length_m" in out["results"][5]["error"]["detail"]
    assert out["summary"] == {"ok": 2, "error": 4}
    expected = rcsa.predict({**assembly, "tool": request["combinations"][2]["tool"]}).to_dict()
    np.testing.assert_allclose(out["results"][2]["tool_point"]["h"]["imag"], expected["tool_point"]["h"]["imag"],
                               rtol=1e-12)


def test_batch_errors_of_the_shared_part_and_limits(make_client, assembly):
    with make_client(max_batch_combinations=3) as client:
        request = _batch(assembly, n_good=2, bad=False)
        bad_grid = {**request, "frequency": {"start_hz": 0.0, "stop_hz": 10.0, "step_hz": 1.0}}
        assert_problem(client.post("/v1/tool-point-frf/batch", json=bad_grid), 422, "frequency.start_hz")
        assert_problem(client.post("/v1/tool-point-frf/batch", json={**request, "combinations": []}), 422,
                       "combinations")
        too_many = {**request, "combinations": request["combinations"] * 2}
        assert "at most 3" in assert_problem(client.post("/v1/tool-point-frf/batch", json=too_many), 422,
                                             "combinations")["detail"]
        unknown = {**request, "spindle": {"measurement_id": "m-00000000abcd"}}
        assert_problem(client.post("/v1/tool-point-frf/batch", json=unknown, headers={"Prefer": "respond-async"}),
                       422, "spindle.measurement_id")


def test_async_job_path_202_poll_result(make_client, assembly):
    with make_client(async_batch_threshold=3) as client:
        request = _batch(assembly, n_good=4)
        r = client.post("/v1/tool-point-frf/batch", json=request)
        assert r.status_code == 202, r.text
        location = r.headers["location"]
        assert location == f"/v1/jobs/{r.json()['id']}" and r.headers["retry-after"] == "1"
        assert r.json()["status"] in ("queued", "running", "succeeded")
        job = _wait(client, location)
        assert job["status"] == "succeeded" and job["progress"] == 1.0 and job["summary"] == {"ok": 4, "error": 4}
        result = client.get(job["result_url"])
        assert result.status_code == 200 and result.headers["content-type"].startswith("application/json")
        sync = client.post("/v1/tool-point-frf/batch", json=request, headers={"Prefer": "respond-sync"})
        assert sync.status_code == 202  # above the threshold: a job whatever is preferred
        small = {**request, "combinations": request["combinations"][:2]}
        direct = client.post("/v1/tool-point-frf/batch", json=small).json()
        assert result.json()["results"][:2] == direct["results"]

        r = client.post("/v1/tool-point-frf/batch", json=small, headers={"Prefer": "respond-async, wait=5"},
                        params={"tool_point": "h,p"})
        assert r.status_code == 202 and r.headers["preference-applied"] == "respond-async"
        job = _wait(client, r.headers["location"])
        assert job["summary"] == {"ok": 1, "error": 1}
        trimmed = client.get(job["result_url"]).json()["results"]
        assert set(trimmed[0]["tool_point"]) == {"h", "p"} and trimmed[1]["status"] == "error"
        assert trimmed[0]["tool_point"]["p"] == direct["results"][0]["tool_point"]["p"]

        assert_problem(client.get("/v1/jobs/j-00000000000000000000000000000000"), 404)
        assert_problem(client.get("/v1/jobs/nonsense/result"), 404)


def test_result_of_an_unfinished_job_is_409_and_restart_finishes_it(make_client, store_path, assembly):
    request = _batch(assembly, n_good=3)
    with make_client(job_workers=0) as client:  # this process runs no jobs
        r = client.post("/v1/tool-point-frf/batch", json=request, headers={"Prefer": "respond-async"})
        assert r.status_code == 202
        location = r.headers["location"]
        time.sleep(0.2)
        assert client.get(location).json()["status"] == "queued"
        body = assert_problem(client.get(location + "/result"), 409)
        assert body["type"].endswith("job-not-finished") and "poll" in body["detail"]
    with make_client() as client:  # a restarted service on the same store sees and finishes it
        job = _wait(client, location)
        assert job["status"] == "succeeded" and job["attempts"] == 1
        assert [x["status"] for x in client.get(job["result_url"]).json()["results"]] == \
            ["ok", "error", "ok", "ok", "error", "error", "error"]


def test_a_job_whose_runner_died_is_resumed(make_client, store_path, assembly):
    with make_client(job_workers=0) as client:
        r = client.post("/v1/tool-point-frf/batch", json=_batch(assembly, n_good=2, bad=False),
                        headers={"Prefer": "respond-async"})
        location = r.headers["location"]
    jobs = JobStore(store_path / "jobs", stale_after_s=0.3)
    claimed = jobs.claim("dead-host:1:cafe")  # a runner that claims it and then dies
    assert claimed is not None and claimed.status == "running" and jobs.claim("other") is None
    with make_client(job_stale_s=0.3) as client:
        job = _wait(client, location)
        assert job["status"] == "succeeded" and job["attempts"] == 2


def test_a_job_that_keeps_killing_its_runner_fails(store_path):
    jobs = JobStore(store_path / "jobs", stale_after_s=0.0, max_attempts=2)
    job = jobs.submit("batch", {"combinations": []})
    assert jobs.claim("r1").attempts == 1 and jobs.claim("r2").attempts == 2
    assert jobs.claim("r3") is None
    failed = jobs.get(job.id)
    assert failed.status == "failed" and "interrupted 2 times" in failed.error["detail"]


def test_failed_job_reports_a_problem(make_client, store_path, assembly):
    jobs_dir = store_path / "jobs"
    with make_client(job_workers=0):
        pass
    jobs = JobStore(jobs_dir)
    bad = {"frequency": {"start_hz": 0.0}, "spindle": {}, "combinations": [{}]}
    job = jobs.submit("batch", library_api.checked_batch(bad, {}), access=job_access())
    with make_client() as client:
        status = _wait(client, f"/v1/jobs/{job.id}")
        assert status["status"] == "failed" and status["error"]["status"] == 422
        body = assert_problem(client.get(f"/v1/jobs/{job.id}/result"), 409)
        assert body["type"].endswith("job-failed") and body["errors"][0]["field"].startswith("frequency")


def _claim_all(directory: str) -> list[str]:
    store = JobStore(directory)
    got = []
    while (job := store.claim(f"proc-{multiprocessing.current_process().pid}")) is not None:
        got.append(job.id)
    return got


def test_two_processes_never_claim_the_same_job(store_path):
    jobs = JobStore(store_path / "jobs")
    ids = {jobs.submit("batch", {"n": i}).id for i in range(40)}
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        parts = pool.map(_claim_all, [str(store_path / "jobs")] * 2)
    claimed = [i for part in parts for i in part]
    assert sorted(claimed) == sorted(ids)  # each exactly once


def test_runner_takes_over_only_what_it_owns(store_path):
    jobs = JobStore(store_path / "jobs", stale_after_s=0.2)
    calls = []

    def slow(request, progress):
        calls.append(request)
        for i in range(5):
            time.sleep(0.1)
            progress(i + 1, 5)
        return {"ok": True}, {"ok": 1}

    job = jobs.submit("slow", {"x": 1})
    a = JobRunner(jobs, {"slow": slow}, heartbeat_s=0.05)
    assert a.run_one() and jobs.get(job.id).status == "succeeded"
    assert jobs.result_path(job.id).read_bytes() == b'{"ok":true}'
    with pytest.raises(NotFoundError, match="not found"):
        jobs.result_path("j-" + "0" * 32)


def test_a_job_of_a_dead_local_process_is_resumed_at_once(store_path):
    proc = multiprocessing.get_context("spawn").Process(target=time.sleep, args=(0,))
    proc.start()
    proc.join()
    jobs = JobStore(store_path / "jobs", stale_after_s=3600)
    job = jobs.submit("batch", {"x": 1})
    assert jobs.claim(f"{socket.gethostname()}:{proc.pid}:dead") is not None
    assert jobs.claim(f"{socket.gethostname()}:{os.getpid()}:alive") is not None  # the dead one's job
    assert jobs.get(job.id).attempts == 2
    assert jobs.claim("elsewhere:1:x") is None  # a live claim (another host) is left alone

"""Stored libraries over REST: sync (incremental, idempotent, as a job, resumed), reads, exports."""

from __future__ import annotations

import io
import json
import socket
import subprocess
import threading
import time
import zipfile

import h5py
import numpy as np
import pytest

from rcsa.infra.job_queue import JobStore
from rcsa.libraries import sync as library_sync
from rcsa.reference import ra1
from tests.libraries.test_sync import make_library, make_tool, tool_id

from .conftest import READ, WRITE, assert_problem

GRID = {"start_hz": 5.0, "stop_hz": 1000.0, "step_hz": 5.0}
RA1 = ra1(GRID)
FORM = {"spindle": json.dumps(RA1["spindle"]), "frequency": json.dumps(GRID), "joints": json.dumps(RA1["joints"])}


def _json_body(library: dict) -> dict:
    return {"library": library, "spindle": RA1["spindle"], "frequency": GRID, "joints": RA1["joints"]}


def _wait(client, location: str, timeout_s: float = 300.0) -> dict:
    """Poll a sync job (a write key's job: read with that key)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        job = client.get(location, headers=WRITE).json()
        if job["status"] in ("succeeded", "failed"):
            return job
        time.sleep(0.05)
    raise AssertionError(f"{location} did not finish: {job}")


@pytest.fixture
def counted(monkeypatch):
    """Counts the tools handed to the model."""
    count = {"tools": 0}
    original = library_sync.compute_chunk

    def counting(batch, **kwargs):
        count["tools"] += len(batch["combinations"])
        return original(batch, **kwargs)

    monkeypatch.setattr(library_sync, "compute_chunk", counting)
    return count


def test_sync_is_incremental_and_replays_byte_for_byte(client, counted):
    lib = make_library(4)
    files = {"library": ("shop.json", json.dumps(lib).encode())}
    key = {**WRITE, "Idempotency-Key": "nightly-2026-01-01"}
    first = client.post("/v1/libraries/shop:sync", files=files, data=FORM, headers=key)
    assert first.status_code == 201 and first.headers["location"] == "/v1/libraries/shop", first.text
    report = first.json()
    assert report["added"] == [tool_id(i) for i in range(4)] and report["computed"] == 4 and report["revision"] == 1
    assert first.headers["location"] == "/v1/libraries/shop" and report["results_url"] == "/v1/libraries/shop/results"
    replay = client.post("/v1/libraries/shop:sync", files=files, data=FORM, headers=key)
    assert replay.status_code == 201 and replay.content == first.content and counted["tools"] == 4  # the same answer
    assert replay.headers["location"] == first.headers["location"]
    other = client.post("/v1/libraries/shop:sync", files=files, data={**FORM, "natural_frequencies": "false"},
                        headers=key)
    assert_problem(other, 422, "Idempotency-Key")

    again = client.post("/v1/libraries/shop:sync", json=_json_body(lib), headers=WRITE).json()  # same export, JSON
    assert again["computed"] == 0 and again["unchanged"] == report["added"] and counted["tools"] == 4

    lib["data"][1]["geometry"]["LB"] += 5.0
    lib["data"][1]["geometry"]["assemblyGaugeLength"] += 5.0
    del lib["data"][3]
    lib["data"].append(make_tool(6, 14.0, 50.0))
    third = client.post("/v1/libraries/shop:sync", json=_json_body(lib), headers=WRITE).json()
    assert third["changed"] == [tool_id(1)] and third["removed"] == [tool_id(3)] and third["added"] == [tool_id(6)]
    assert third["unchanged"] == [tool_id(0), tool_id(2)] and third["computed"] == 2 and counted["tools"] == 6

    summary = client.get("/v1/libraries/shop").json()  # reads: anonymous by default
    assert summary["revision"] == 3 and summary["summary"] == {"ok": 4, "skipped": 0, "error": 0}
    assert [t["id"] for t in summary["tools"]] == [tool_id(i) for i in (0, 1, 2, 6)]
    assert summary["last_sync"]["counts"] == {"added": 1, "changed": 1, "unchanged": 2, "removed": 1}
    assert [x["id"] for x in client.get("/v1/libraries").json()["items"]] == ["shop"]


def test_results_as_json_hdf5_and_uff_zip(client):
    r = client.post("/v1/libraries/shop:sync", json=_json_body(make_library(2)), headers=WRITE)
    assert r.status_code == 201, r.text
    full = client.get("/v1/libraries/shop/results")
    assert full.status_code == 200 and full.headers["content-type"] == "application/json"
    results = full.json()["results"]
    assert [x["status"] for x in results] == ["ok", "ok"] and set(results[0]["tool_point"]) == {"h", "l", "n", "p"}
    lean = client.get("/v1/libraries/shop/results", params={"tool_point": "h"}).json()["results"]
    assert set(lean[0]["tool_point"]) == {"h"} and lean[0]["tool_point"]["h"] == results[0]["tool_point"]["h"]
    h0 = np.asarray(results[0]["tool_point"]["h"]["real"]) + 1j * np.asarray(results[0]["tool_point"]["h"]["imag"])

    r = client.get("/v1/libraries/shop/results", headers={"Accept": "application/x-hdf5"})
    assert r.status_code == 200 and r.headers["content-type"] == "application/x-hdf5"
    assert r.headers["content-disposition"] == 'attachment; filename="shop-r1.h5"'
    with h5py.File(io.BytesIO(r.content), "r") as f:
        assert f.attrs["schema"] == "rcsa.library-results" and f.attrs["library_id"] == "shop"
        assert f["id"].asstr()[0] == tool_id(0)
        np.testing.assert_array_equal(f["tool_point/h"][0], h0)
        assert len(f["frequency_hz"]) == 200

    r = client.get("/v1/libraries/shop/results", headers={"Accept": "application/zip, application/json;q=0.5"})
    assert r.status_code == 200 and r.headers["content-type"] == "application/zip"
    archive = zipfile.ZipFile(io.BytesIO(r.content))
    assert sorted(archive.namelist()) == sorted(["index.json", f"{tool_id(0)}.uff", f"{tool_id(1)}.uff"])
    assert client.get("/v1/libraries/shop/results", params={"format": "hdf5"}).headers["content-type"] == \
        "application/x-hdf5"
    assert_problem(client.get("/v1/libraries/shop/results", headers={"Accept": "text/csv"}), 406)
    assert_problem(client.get("/v1/libraries/nope/results"), 404)
    assert_problem(client.get("/v1/libraries/bad%20id"), 422, "library_id")


def test_writes_need_a_write_key_and_reads_follow_the_read_policy(make_client):
    body = _json_body(make_library(1))
    with make_client(anonymous_read=False) as client:
        assert_problem(client.post("/v1/libraries/shop:sync", json=body), 401)
        assert_problem(client.post("/v1/libraries/shop:sync", json=body, headers=READ), 403)
        assert client.post("/v1/libraries/shop:sync", json=body, headers=WRITE).status_code == 201
        assert_problem(client.get("/v1/libraries/shop"), 401)
        assert client.get("/v1/libraries/shop", headers=READ).status_code == 200
        assert_problem(client.delete("/v1/libraries/shop", headers=READ), 403)
        assert client.delete("/v1/libraries/shop", headers=WRITE).json() == {"deleted": "shop"}
        assert_problem(client.get("/v1/libraries/shop", headers=READ), 404)


def test_sync_on_a_stored_measurement(make_client):
    with make_client(seed_demo=True) as client:
        mid = client.get("/v1/measurements").json()["items"][0]["id"]
        form = {"measurement_id": mid, "frequency": json.dumps({"start_hz": 50.0, "stop_hz": 1000.0,
                                                                "step_hz": 10.0})}
        files = {"library": ("shop.json", json.dumps(make_library(2)).encode())}
        r = client.post("/v1/libraries/hybrid:sync", files=files, data=form, headers=WRITE)
        assert r.status_code == 201, r.text
        assert r.json()["summary"]["ok"] == 2
        assert client.get("/v1/libraries/hybrid").json()["measurement_sha256"]
        r = client.post("/v1/libraries/hybrid:sync", files=files, data={**form, "measurement_id": "m-000000000000"},
                        headers=WRITE)
        assert_problem(r, 422, "spindle.measurement_id")


def test_replay_while_the_sync_job_runs_is_a_409(make_client, monkeypatch):
    release, entered = threading.Event(), threading.Event()
    original = library_sync.compute_chunk

    def slow(batch, **kwargs):
        entered.set()
        release.wait(30)
        return original(batch, **kwargs)

    monkeypatch.setattr(library_sync, "compute_chunk", slow)
    body = _json_body(make_library(2))
    key = {**WRITE, "Idempotency-Key": "sync-as-job", "Prefer": "respond-async"}
    with make_client() as client:
        try:
            first = client.post("/v1/libraries/shop:sync", json=body, headers=key)
            assert first.status_code == 202 and first.json()["kind"] == "library-sync"
            assert entered.wait(30)
            busy = client.post("/v1/libraries/shop:sync", json=body, headers=key)
            problem = assert_problem(busy, 409)
            assert problem["job"]["status"] == "running" and busy.headers["location"] == first.headers["location"]
            assert busy.headers["retry-after"]
        finally:
            release.set()
        job = _wait(client, first.headers["location"])
        assert job["status"] == "succeeded" and job["summary"]["added"] == 2
        report = client.get(job["result_url"], headers=WRITE).json()
        assert report["added"] == [tool_id(0), tool_id(1)] and report["computed"] == 2
        replay = client.post("/v1/libraries/shop:sync", json=body, headers=key)
        assert replay.status_code == 202 and replay.content == first.content


def test_a_killed_sync_job_is_resumed_and_takes_finished_tools_from_the_cache(make_client, store_path, counted):
    body = _json_body(make_library(5))
    key = {**WRITE, "Idempotency-Key": "resume-me", "Prefer": "respond-async"}
    with make_client(job_workers=0) as client:
        first = client.post("/v1/libraries/shop:sync", json=body, headers=key)
        assert first.status_code == 202
    job_id = first.headers["location"].rsplit("/", 1)[1]

    # a worker claims it, computes two tools and dies (its pid no longer exists)
    jobs = JobStore(store_path / "jobs")
    dead = subprocess.Popen(["true"])
    dead.wait()
    assert jobs.claim(f"{socket.gethostname()}:{dead.pid}:gone").id == job_id

    class Killed(Exception):
        pass

    def die_after_two(done, total):
        if done >= 2:
            raise Killed

    with pytest.raises(Killed):
        library_sync.run_sync(library_sync.LibraryStore.in_store(store_path), jobs.request(job_id),
                              progress=die_after_two, chunk_tools=1)
    assert counted["tools"] == 2 and jobs.get(job_id).status == "running"

    with make_client() as client:  # the restarted service resumes it at once
        busy = client.post("/v1/libraries/shop:sync", json=body, headers=key)
        assert busy.status_code in (409, 202)
        job = _wait(client, first.headers["location"])
        assert job["status"] == "succeeded" and job["attempts"] == 2
        report = client.get(job["result_url"], headers=WRITE).json()
        assert report["computed"] == 3 and report["from_cache"] == 2 and counted["tools"] == 5
        assert report["added"] == [tool_id(i) for i in range(5)] and report["revision"] == 1
        tools = client.get("/v1/libraries/shop").json()["tools"]
        assert [t["id"] for t in tools] == [tool_id(i) for i in range(5)]  # each tool exactly once
        replay = client.post("/v1/libraries/shop:sync", json=body, headers=key)
        assert replay.status_code == 202 and replay.content == first.content
        assert JobStore(store_path / "jobs").counts()["succeeded"] == 1

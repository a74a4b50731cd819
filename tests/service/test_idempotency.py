"""Idempotency-Key: replays, reuse with another body, duplicates in flight, owners, restarts."""

from __future__ import annotations

import json
import socket
import subprocess
import time
from contextlib import closing

import pytest
from service.idempotency import IdempotencyStore, Stored, parse_key, store_for

from rcsa.infra.job_queue import JobStore
from tests.helpers import REPO

from .conftest import GRID, READ, WRITE, assert_problem

DATA = REPO / "tests" / "data" / "measurements"
META = {"spindle_id": "mc1", "direction": "x", "plane": "spindle_nose", "units": "m/N"}


def _measurement() -> dict:
    return json.loads((DATA / "point_receptance.json").read_text())


def _batch(assembly, n=2) -> dict:
    return {"frequency": GRID, "spindle": assembly["spindle"],
            "combinations": [{"id": f"T{i}", "holder": assembly["holder"], "joints": assembly["joints"],
                              "tool": {**assembly["tool"], "stickout_m": 0.05 + 0.002 * i}} for i in range(n)]}


def test_measurement_upload_replay_returns_the_first_answer_and_stores_once(client):
    key = {**WRITE, "Idempotency-Key": "upload-0001"}
    first = client.post("/v1/measurements", json=_measurement(), headers=key)
    assert first.status_code == 201 and "idempotent-replayed" not in first.headers
    # the same document with another key order and spacing is the same request
    body = json.dumps(dict(reversed(list(_measurement().items()))), indent=2)
    again = client.post("/v1/measurements", content=body, headers={**key, "content-type": "application/json"})
    assert again.status_code == 201 and again.content == first.content
    assert again.headers["location"] == first.headers["location"]
    assert again.headers["idempotent-replayed"] == "true"
    assert [m["id"] for m in client.get("/v1/measurements").json()["items"]] == [first.json()["id"]]

    other = {**_measurement(), "spindle_id": "another-spindle"}
    body = assert_problem(client.post("/v1/measurements", json=other, headers=key), 422, "Idempotency-Key")
    assert body["type"].endswith("idempotency-key-reused")
    assert len(client.get("/v1/measurements").json()["items"]) == 1
    # another key stores another copy
    assert client.post("/v1/measurements", json=_measurement(), headers={**WRITE, "Idempotency-Key": '"u-2"'}
                       ).status_code == 201
    assert len(client.get("/v1/measurements").json()["items"]) == 2


def test_multipart_retry_with_a_new_boundary_is_a_replay(client):
    key = {**WRITE, "Idempotency-Key": "csv-upload-1"}
    content = (DATA / "direct_frf_um_per_n.csv").read_bytes()
    meta = {**META, "units": "um/N"}
    first = client.post("/v1/measurements", files={"file": ("tap.csv", content)}, data=meta, headers=key)
    assert first.status_code == 201, first.text
    again = client.post("/v1/measurements", files={"file": ("tap.csv", content)}, data=meta, headers=key)
    assert again.content == first.content and again.headers["idempotent-replayed"] == "true"
    changed = client.post("/v1/measurements", files={"file": ("tap.csv", content)}, data={**meta, "notes": "x"},
                          headers=key)
    assert_problem(changed, 422, "Idempotency-Key")


def test_failures_are_not_kept_and_free_the_key(client):
    key = {**WRITE, "Idempotency-Key": "fix-and-retry"}
    broken = {**_measurement(), "plane": "somewhere"}
    assert_problem(client.post("/v1/measurements", json=broken, headers=key), 422, "plane")
    assert client.post("/v1/measurements", json=_measurement(), headers=key).status_code == 201
    # no write key: 401, and nothing kept under the anonymous owner either
    anonymous = {"Idempotency-Key": "no-key-yet"}
    assert_problem(client.post("/v1/measurements", json=_measurement(), headers=anonymous), 401)
    assert_problem(client.post("/v1/measurements", json=_measurement(), headers={
        **anonymous, "X-API-Key": "not-a-key"}), 401)
    assert client.post("/v1/measurements", json=_measurement(), headers={**WRITE, **anonymous}).status_code == 201


@pytest.mark.parametrize("bad", ["", " ", "x" * 256, "naïve"])
def test_malformed_keys_are_a_400(client, bad):
    r = client.post("/v1/measurements", json=_measurement(), headers={**WRITE, "Idempotency-Key": bad.encode()})
    assert_problem(r, 400, "Idempotency-Key")


def test_keys_are_scoped_per_api_key(client, assembly):
    body = _batch(assembly)
    mine = client.post("/v1/tool-point-frf/batch", json=body, headers={**READ, "Idempotency-Key": "shared"})
    assert mine.status_code == 200 and mine.json()["summary"] == {"ok": 2, "error": 0}
    body2 = {**body, "combinations": body["combinations"][:1]}
    theirs = client.post("/v1/tool-point-frf/batch", json=body2, headers={"Idempotency-Key": "shared"})  # anonymous
    assert theirs.status_code == 200 and theirs.json()["summary"]["ok"] == 1
    replay = client.post("/v1/tool-point-frf/batch", json=body, headers={**READ, "Idempotency-Key": "shared"})
    assert replay.content == mine.content
    # the query is part of the request
    r = client.post("/v1/tool-point-frf/batch?tool_point=h", json=body, headers={**READ, "Idempotency-Key": "shared"})
    assert_problem(r, 422, "Idempotency-Key")


def test_batch_job_replays_409_while_queued_then_the_202_after_a_restart(make_client, assembly):
    body = _batch(assembly)
    key = {"Idempotency-Key": "nightly-batch-2026-01-01", "Prefer": "respond-async"}
    with make_client(job_workers=0) as client:  # nobody runs jobs: it stays queued
        first = client.post("/v1/tool-point-frf/batch", json=body, headers=key)
        assert first.status_code == 202
        location = first.headers["location"]
        busy = client.post("/v1/tool-point-frf/batch", json=body, headers=key)
        problem = assert_problem(busy, 409)
        assert problem["type"].endswith("idempotent-job-running") and problem["job"]["status"] == "queued"
        assert busy.headers["location"] == location and int(busy.headers["retry-after"]) >= 1
    with make_client() as client:  # a restart: the key and the job survive; a runner finishes the job
        for _ in range(6000):  # up to 5 min on a loaded machine; pytest-timeout is the last guard
            job = client.get(location).json()
            if job["status"] in ("succeeded", "failed"):
                break
            time.sleep(0.05)
        assert job["status"] == "succeeded"
        replay = client.post("/v1/tool-point-frf/batch", json=body, headers=key)
        assert replay.status_code == 202 and replay.content == first.content
        assert replay.headers["location"] == location and replay.headers["preference-applied"] == "respond-async"
        assert client.get("/v1/jobs/" + location.rsplit("/", 1)[1]).json()["attempts"] == 1
        assert JobStore(client.app.state.rcsa.jobs.directory).counts()["succeeded"] == 1  # one job, not two


def test_a_duplicate_in_flight_is_a_409_and_a_dead_holder_is_taken_over(client):
    state = client.app.state.rcsa
    store = store_for(state)
    fingerprint_of = {}

    def reserve(key: str) -> str:
        # run the real request once to learn its fingerprint, then forget its answer
        r = client.post("/v1/measurements", json=_measurement(), headers={**WRITE, "Idempotency-Key": key})
        assert r.status_code == 201
        with closing(store._connect()) as con:
            fp, = con.execute("SELECT fingerprint FROM idempotency WHERE key = ?", (key,)).fetchone()
            con.execute("DELETE FROM idempotency WHERE key = ?", (key,))
        fingerprint_of[key] = fp
        return fp

    owner = state.keys.authenticate(WRITE["X-API-Key"]).key_id
    fp = reserve("in-flight")
    kind, _ = store.begin(owner, "in-flight", fp, "POST", "/v1/measurements")  # this (live) process answers it
    assert kind == "new"
    r = client.post("/v1/measurements", json=_measurement(), headers={**WRITE, "Idempotency-Key": "in-flight"})
    assert assert_problem(r, 409)["type"].endswith("idempotent-request-in-progress") and r.headers["retry-after"]

    fp = reserve("orphaned")
    gone = _dead_pid()
    with closing(store._connect()) as con:  # a reservation left by a process that died on this host
        con.execute("INSERT INTO idempotency (owner, key, fingerprint, method, path, state, holder, created_unix) "
                    "VALUES (?, 'orphaned', ?, 'POST', '/v1/measurements', 'running', ?, ?)",
                    (owner, fp, f"{socket.gethostname()}:{gone}:dead", time.time()))
    r = client.post("/v1/measurements", json=_measurement(), headers={**WRITE, "Idempotency-Key": "orphaned"})
    assert r.status_code == 201


def _dead_pid() -> int:
    child = subprocess.Popen(["true"])
    child.wait()
    return child.pid


def test_store_keeps_answers_across_instances_and_forgets_them_after_the_retention(tmp_path):
    store = IdempotencyStore(tmp_path, retention_s=3600)
    kind, holder = store.begin("k1", "abc", "f" * 64, "POST", "/v1/x")
    assert kind == "new"
    assert store.complete("k1", "abc", holder, Stored(201, {"location": "/v1/x/1"}, b"{}"))
    again = IdempotencyStore(tmp_path, retention_s=3600)  # another process, or after a restart
    assert again.begin("k1", "abc", "f" * 64, "POST", "/v1/x") == ("replay", Stored(201, {"location": "/v1/x/1"},
                                                                                     b"{}"))
    assert again.begin("k1", "abc", "e" * 64, "POST", "/v1/x") == ("mismatch", None)
    assert again.begin("k2", "abc", "e" * 64, "POST", "/v1/x")[0] == "new"  # another owner
    short = IdempotencyStore(tmp_path, retention_s=0.0)
    assert short.begin("k1", "abc", "e" * 64, "POST", "/v1/x")[0] == "new"  # expired: a fresh key
    assert short.purge() >= 1
    assert parse_key('"a\\"b"') == 'a"b' and parse_key(" k ") == "k"

"""The service under a real ``uvicorn --workers 2`` on loopback, sharing one store."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time

import httpx
import pytest

from rcsa.reference import ra1
from tests.helpers import REPO, start_uvicorn
from tests.service.conftest import wait_until_ready

from .conftest import GRID, WRITE_KEY

DATA = REPO / "tests" / "data" / "measurements"


@pytest.mark.slow
def test_two_workers_upload_predict_batch_delete_and_shutdown(tmp_path):
    prom = tmp_path / "prom"
    prom.mkdir()
    env = {**os.environ, "RCSA_STORE": str(tmp_path / "store"), "RCSA_API_KEYS": f"{WRITE_KEY}:write",
           "RCSA_JOB_POLL_S": "0.1", "PROMETHEUS_MULTIPROC_DIR": str(prom), "RCSA_SEED_DEMO": "true"}
    proc, base = start_uvicorn(["service.main:create_app", "--factory", "--http", "service.http:NoDelayHTTPProtocol",
                                "--workers", "2"], env, tmp_path / "uvicorn.log", workers=2)
    try:
        with httpx.Client(base_url=base, timeout=60) as client:
            wait_until_ready(base, proc, tmp_path / "uvicorn.log")
            demo = client.get("/v1/measurements", params={"spindle_id": "demo-ra1"}).json()["items"]
            assert len(demo) == 1  # two workers started, the store was seeded once

            doc = json.loads((DATA / "point_receptance.json").read_text())
            assert client.post("/v1/measurements", json=doc).status_code == 401
            r = client.post("/v1/measurements", files={"file": ("tip.json", json.dumps(demo_doc(client, demo[0]["id"])))},
                            data={"spindle_id": "mc1-copy"}, headers={"X-API-Key": WRITE_KEY})
            assert r.status_code == 201, r.text
            mid = r.json()["id"]

            assembly = {**ra1(GRID), "spindle": {"measurement_id": mid}}
            for i in range(4):  # several requests: both workers answer
                r = client.post("/v1/tool-point-frf", json=assembly, headers={"X-Request-ID": f"uvicorn-{i}"})
                assert r.status_code == 200 and r.headers["x-request-id"] == f"uvicorn-{i}"
                assert r.json()["natural_frequencies_method"] == "modal_fit"

            combos = [{"id": f"T{i}", "holder": assembly["holder"], "joints": assembly["joints"],
                       "tool": {**assembly["tool"], "stickout_m": 0.05 + 0.005 * i}} for i in range(4)]
            batch = {"frequency": GRID, "spindle": {"measurement_id": mid}, "combinations": combos}
            r = client.post("/v1/tool-point-frf/batch", json=batch)
            assert r.status_code == 200 and r.json()["summary"] == {"ok": 4, "error": 0}
            r = client.post("/v1/tool-point-frf/batch", json=batch, headers={"Prefer": "respond-async"})
            assert r.status_code == 202
            location = r.headers["location"]
            mine = {"X-Job-Token": r.headers["x-job-token"]}  # an anonymous job is its maker's alone
            for _ in range(3000):  # up to 5 min on a loaded machine
                job = client.get(location, headers=mine).json()
                if job["status"] in ("succeeded", "failed"):
                    break
                time.sleep(0.1)
            assert job["status"] == "succeeded" and job["attempts"] == 1
            result = client.get(job["result_url"], headers={"Accept-Encoding": "gzip", **mine})
            assert result.headers["content-encoding"] == "gzip"
            assert [x["id"] for x in result.json()["results"]] == ["T0", "T1", "T2", "T3"]

            assert client.delete(f"/v1/measurements/{mid}", headers={"X-API-Key": WRITE_KEY}).status_code == 200
            r = client.post("/v1/tool-point-frf", json=assembly)
            assert r.status_code == 422 and r.json()["errors"][0]["field"] == "spindle.measurement_id"
            metrics = client.get("/metrics").text
            assert 'rcsa_http_requests_total{method="POST",route="/v1/tool-point-frf",status="200"} 4.0' in metrics
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            code = proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise
    text = (tmp_path / "uvicorn.log").read_text()
    assert code == 0, text
    assert "request_id=uvicorn-2" in text and "Traceback" not in text


def demo_doc(client: httpx.Client, mid: str) -> dict:
    """The demo measurement as contract JSON (what a user would upload)."""
    doc = client.get(f"/v1/measurements/{mid}").json()
    return {k: v for k, v in doc.items() if k not in ("id", "source", "spindle_id")}

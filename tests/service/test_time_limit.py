"""Answers given at once stop at their time limit (``RCSA_SYNC_TIME_LIMIT_S``) with a 503 problem."""

from __future__ import annotations

import asyncio

import pytest

from rcsa.analysis.progress import check_time, time_limit
from rcsa.errors import TimeLimitExceeded
from rcsa.reference import ra1

from .conftest import assert_problem


def _sdm_lobes() -> dict:
    return {"assembly": ra1({"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 10.0}), "teeth": 4,
            "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": 0.5, "milling": "down",
            "method": "semi_discretization", "spindle_speed_rpm": {"start": 10000, "stop": 30000, "count": 40}}


def test_a_computation_past_its_time_limit_is_a_503_problem_and_a_job_is_not_limited(make_client):
    with make_client(sync_time_limit_s=1e-3, job_workers=0) as client:
        r = client.post("/v1/stability-lobes", json=_sdm_lobes())
        problem = assert_problem(r, 503)
        assert problem["type"].endswith("compute-time-limit") and problem["time_limit_s"] == 1e-3
        assert "Prefer: respond-async" in problem["detail"]
        queued = client.post("/v1/stability-lobes", json=_sdm_lobes(), headers={"Prefer": "respond-async"})
        assert queued.status_code == 202  # a job has the job limits, not this one
        upload = client.get("/healthz")
        assert upload.status_code == 200  # GETs are not limited


def test_without_a_limit_the_same_request_is_answered(make_client):
    small = {**_sdm_lobes(), "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 3}}
    with make_client(sync_time_limit_s=0) as client:
        assert client.post("/v1/stability-lobes", json=small).status_code == 200


def test_the_limit_follows_the_computation_into_its_thread_and_stops_at_a_step():
    async def main() -> None:
        with time_limit(0.0):
            await asyncio.to_thread(check_time)

    with pytest.raises(TimeLimitExceeded):
        asyncio.run(main())
    check_time()  # no limit outside


def test_an_answer_without_step_boundaries_is_cut_off_at_the_limit(monkeypatch):
    from service import routing

    monkeypatch.setattr(routing, "TIME_LIMIT_GRACE_S", 0.0)

    async def main() -> None:
        never = asyncio.get_running_loop().create_future()  # a computation that never ends
        await routing.within(0.0, never)

    with pytest.raises(TimeLimitExceeded):
        asyncio.run(main())


@pytest.mark.slow
def test_a_real_server_answers_503_at_the_limit_and_stops_on_sigterm_without_waiting(tmp_path):
    """uvicorn with a 1 s limit: a semi-discretization of ~5 s of work answers 503 and its
    computation stops (the server logs it); SIGTERM then shuts the server down gracefully
    (``wait``'s timeout only guards against a hang; nothing here is timed)."""
    import os
    import signal
    import socket
    import subprocess
    import sys

    import httpx

    from tests.helpers import REPO
    from tests.service.conftest import wait_until_ready

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {**os.environ, "RCSA_STORE": str(tmp_path / "store"), "RCSA_SEED_DEMO": "false",
           "RCSA_SYNC_TIME_LIMIT_S": "1", "RCSA_JOB_WORKERS": "0"}
    log = tmp_path / "uvicorn.log"
    with log.open("w") as out:
        proc = subprocess.Popen([sys.executable, "-m", "uvicorn", "service.main:create_app", "--factory",
                                 "--host", "127.0.0.1", "--port", str(port)], cwd=REPO, env=env, stdout=out,
                                stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    try:
        wait_until_ready(base, proc, log)
        heavy = {**_sdm_lobes(), "spindle_speed_rpm": {"start": 8000, "stop": 30000, "count": 120}}
        r = httpx.post(base + "/v1/stability-lobes", json=heavy, timeout=120)
        assert r.status_code == 503 and r.json()["type"].endswith("compute-time-limit"), r.text[:300]
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=120) in (0, -signal.SIGTERM)  # uvicorn re-raises the signal once shut down
    finally:
        if proc.poll() is None:
            proc.kill()
    text = log.read_text()
    assert "time limit: POST /v1/stability-lobes stopped after 1 s" in text and "Traceback" not in text
    assert "Application shutdown complete" in text  # a graceful shutdown, not a kill

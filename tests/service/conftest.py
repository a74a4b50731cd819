"""Fixtures of the service tests: an app on a temporary store, keys, reference requests."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest

with warnings.catch_warnings():  # starlette asks for httpx2, which the project does not install
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

from service.config import Settings
from service.main import create_app

from rcsa.reference import ra1

WRITE_KEY = "test-write-key-0123456789abcdef"
READ_KEY = "test-read-key-0123456789abcdef"
WRITE = {"X-API-Key": WRITE_KEY}
READ = {"X-API-Key": READ_KEY}
#: The job token every anonymous request of the test client carries (``X-Job-Token``): the
#: jobs it submits are its own; tests of privacy send other tokens or none.
JOB_TOKEN = "test-job-token-0123456789abcdef0123456789"
GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
PROBLEM = "application/problem+json"

__all__ = ["GRID", "JOB_TOKEN", "PROBLEM", "READ", "READ_KEY", "WRITE", "WRITE_KEY", "TestClient", "assert_problem"]


def settings_for(store, **overrides: Any) -> Settings:
    """Settings on ``store`` with both test keys, no demo seed, fast job polling."""
    base: dict[str, Any] = {"store": store, "api_keys": f"{WRITE_KEY}:write,{READ_KEY}:read", "seed_demo": False,
                            "job_poll_s": 0.05, "job_heartbeat_s": 0.2, "access_log": False}
    base.update(overrides)
    return Settings(**base)


@pytest.fixture
def store_path(tmp_path):
    """A fresh store directory (created by the app)."""
    return tmp_path / "store"


@pytest.fixture
def make_client(store_path) -> Callable[..., Any]:
    """``with make_client(**settings) as client:`` — a started app on the test store."""

    @contextmanager
    def make(**overrides: Any) -> Iterator[TestClient]:
        app = create_app(settings_for(overrides.pop("store", store_path), **overrides))
        with TestClient(app, headers={"X-Job-Token": JOB_TOKEN}) as client:
            yield client

    return make


@pytest.fixture
def client(make_client) -> Iterator[TestClient]:
    """A started app with default test settings."""
    with make_client() as c:
        yield c


@pytest.fixture
def assembly() -> dict[str, Any]:
    """RA-1 on a 1 000-line grid."""
    return ra1(GRID)


def assert_problem(response, status: int, field: str | None = None) -> dict[str, Any]:
    """The response is an RFC 9457 problem with this status (and names ``field``)."""
    assert response.status_code == status, response.text
    assert response.headers["content-type"].startswith(PROBLEM), response.headers
    body = response.json()
    assert body["status"] == status and body["type"].startswith("urn:rcsa:problem:")
    assert body["title"] and body["detail"] and body["instance"].startswith("/")
    assert body["request_id"] == response.headers["x-request-id"]
    if field is not None:
        fields = [e["field"] for e in body.get("errors", [])]
        assert field in fields, (field, body)
    return body


#: how many times a started uvicorn is asked for /readyz, 0.2 s apart, before the test gives up
READY_ATTEMPTS = 450


def wait_until_ready(base: str, proc: Any, log_path: Any) -> None:
    """Poll ``base + /readyz`` until it answers 200; fail with the server's log if it dies first.

    Counts attempts rather than reading a clock: a slow machine only makes the loop longer,
    and a server that never comes up fails the test with its log (pytest-timeout is the last guard).
    """
    import time

    import httpx

    for _ in range(READY_ATTEMPTS):
        try:
            if httpx.get(base + "/readyz", timeout=10).status_code == 200:
                return
        except httpx.TransportError:
            pass
        if proc.poll() is not None:
            pytest.fail("uvicorn exited before it was ready:\n" + log_path.read_text())
        time.sleep(0.2)
    pytest.fail("uvicorn did not become ready:\n" + log_path.read_text())


def job_access(token: str = JOB_TOKEN) -> str:
    """The access identity of an anonymous caller holding ``token`` (for jobs submitted to the
    job store directly, as the service would)."""
    import hashlib

    return "token:" + hashlib.sha256(token.encode()).hexdigest()

"""The request envelope (``service.middleware``): body timeouts, client disconnects, security headers.

Called as an ASGI app with hand-made ``receive`` functions (a body that stalls, one that
trickles, a client that goes away mid-body), and through the test client for the headers.
The head's timeout lives in the HTTP protocol (``service.http``) and is tried against a real
uvicorn in ``test_slow_clients_uvicorn.py``.
"""

from __future__ import annotations

import asyncio
import logging
from typing import Any

import orjson
from service.main import create_app
from service.middleware import CLIENT_CLOSED_REQUEST

from .conftest import WRITE, assert_problem, settings_for


def _call(app: Any, method: str, path: str, body_pieces: list[bytes | None], *, pause_s: float = 0.0,
          headers: list[tuple[bytes, bytes]] | None = None, complete: bool = True) -> list[dict[str, Any]]:
    """Run one request through ``app``; ``None`` in ``body_pieces`` is the client going away;
    ``complete=False``: the last piece says more is coming, and then the client stalls."""
    sent: list[dict[str, Any]] = []

    async def run() -> None:
        pieces = list(body_pieces)

        async def receive() -> dict[str, Any]:
            if not pieces:
                await asyncio.sleep(3600)  # a client that stalls: the app must give up first
            piece = pieces.pop(0)
            if pause_s:
                await asyncio.sleep(pause_s)
            if piece is None:
                return {"type": "http.disconnect"}
            return {"type": "http.request", "body": piece, "more_body": bool(pieces) or not complete}

        async def send(message: dict[str, Any]) -> None:
            sent.append(message)

        scope = {"type": "http", "asgi": {"version": "3.0"}, "http_version": "1.1", "method": method,
                 "scheme": "http", "path": path, "raw_path": path.encode(), "query_string": b"", "root_path": "",
                 "headers": [(b"host", b"test"), (b"content-type", b"application/json"),
                             (b"transfer-encoding", b"chunked"), *(headers or [])],
                 "client": ("203.0.113.9", 5555), "server": ("test", 80), "state": {}}
        await app(scope, receive, send)

    asyncio.run(run())
    return sent


def _status_and_headers(sent: list[dict[str, Any]]) -> tuple[int, dict[str, str]]:
    start = next(m for m in sent if m["type"] == "http.response.start")
    return start["status"], {k.decode().lower(): v.decode() for k, v in start["headers"]}


def _metric(app: Any, status: int) -> str:
    from service.state import ensure_state

    text = ensure_state(app).metrics.exposition().decode()
    return "\n".join(line for line in text.splitlines() if f'status="{status}"' in line)


def test_a_stalled_body_is_a_408_and_the_connection_closes(tmp_path):
    app = create_app(settings_for(tmp_path / "store", body_timeout_s=0.2))
    sent = _call(app, "POST", "/v1/tool-point-frf", [b'{"frequency": '], complete=False)  # then nothing more
    status, headers = _status_and_headers(sent)
    assert status == 408 and headers["connection"] == "close"
    body = orjson.loads(b"".join(m.get("body", b"") for m in sent if m["type"] == "http.response.body"))
    assert body["type"].endswith(":request-timeout") and "RCSA_BODY_TIMEOUT_S" in body["detail"]
    assert 'route="/v1/tool-point-frf"' in _metric(app, 408)


def test_a_trickling_body_is_cut_by_the_average_rate(tmp_path):
    # every piece comes within the pause limit, but at 1 byte per 20 ms the body never reaches
    # the average rate required once the grace has passed
    app = create_app(settings_for(tmp_path / "store", body_timeout_s=0.3, body_min_rate_bytes_s=1000.0))
    sent = _call(app, "POST", "/v1/tool-point-frf", [b"{"] + [b" "] * 200 + [b"}"], pause_s=0.02)
    status, headers = _status_and_headers(sent)
    assert status == 408 and headers["connection"] == "close"


def test_a_client_gone_mid_body_is_a_disconnect_not_a_500(tmp_path, caplog):
    app = create_app(settings_for(tmp_path / "store"))
    with caplog.at_level(logging.INFO, logger="service"):
        sent = _call(app, "POST", "/v1/tool-point-frf", [b'{"frequency": {"start_hz": 5', None])
        upload = _call(app, "POST", "/v1/measurements", [b"--x\r\nContent-Disposition: form-data", None],
                       headers=[(b"content-type", b"multipart/form-data; boundary=x"),
                                *[(k.lower().encode(), v.encode()) for k, v in WRITE.items()]])
    assert sent == [] and upload == []  # nobody to answer
    assert 'route="/v1/tool-point-frf"' in _metric(app, CLIENT_CLOSED_REQUEST)
    assert 'route="/v1/measurements"' in _metric(app, CLIENT_CLOSED_REQUEST)
    assert _metric(app, 500) == ""
    assert "client disconnected" in caplog.text and "Traceback" not in caplog.text
    assert not any(r.levelno >= logging.ERROR for r in caplog.records)


def test_every_answer_carries_the_security_headers(client, assembly):
    answers = {
        "prediction": client.post("/v1/tool-point-frf", json=assembly),
        "problem": client.post("/v1/tool-point-frf", json={}),
        "401": client.post("/v1/measurements", json={}),
        "404": client.get("/v1/no-such-thing"),
        "metrics": client.get("/metrics"),
        "openapi": client.get("/openapi.json"),
        "docs page": client.get("/docs"),
        "web view": client.get("/ui/"),
    }
    for name, r in answers.items():
        assert r.headers["x-content-type-options"] == "nosniff", name
        assert r.headers["x-frame-options"] == "DENY", name
        assert r.headers["referrer-policy"] == "no-referrer", name
    for name in ("prediction", "problem", "401", "404", "metrics", "openapi"):
        assert answers[name].headers["content-security-policy"].startswith("default-src 'none'"), name
    assert "script-src 'self'" in answers["web view"].headers["content-security-policy"]  # its own policy
    assert "content-security-policy" not in answers["docs page"].headers  # the page loads its own assets
    assert_problem(answers["problem"], 422)


def test_a_refused_upload_is_not_read_on(client):
    r = client.post("/v1/measurements", content=b"x" * 100_000, headers={"content-type": "application/json"})
    assert_problem(r, 401)
    assert r.headers["connection"] == "close"  # the rest of the body is not waited for

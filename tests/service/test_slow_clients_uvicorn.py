"""Slow clients against a real ``uvicorn --workers 2`` with the service's HTTP protocol.

Ten sockets trickle the head of a request a byte at a time, ten more send a head and trickle
the body: the server closes the first ten (``RCSA_HEADER_TIMEOUT_S``) and answers the others
``408`` and closes them (``RCSA_BODY_TIMEOUT_S``), while an ordinary request is answered at
once; a client that sends half a body and goes away is counted as ``499`` in ``/metrics``,
never as a 500, and leaves no traceback in the log. The time the clients would need (12 s
for a head, 30 s for a body) is far above the timeouts set here (1 s), so the server must be
the one that ends them; the sockets' own timeouts only guard against a hang.
"""

from __future__ import annotations

import os
import socket
import threading
import time
from pathlib import Path

import httpx
import pytest

from tests.helpers import start_uvicorn, stop_uvicorn
from tests.service.conftest import wait_until_ready

HEAD = (b"POST /v1/tool-point-frf HTTP/1.1\r\nHost: test\r\nContent-Type: application/json\r\n"
        b"Content-Length: 150\r\n\r\n")


def _trickle(base: str, first: bytes, data: bytes, pause_s: float, out: list[bytes], index: int) -> None:
    """Send ``first`` at once, then ``data`` a byte at a time; keep what the server answered
    (b"" if it just closed)."""
    host, port = base.removeprefix("http://").split(":")
    answer = b""
    with socket.create_connection((host, int(port)), timeout=60) as sock:
        try:
            sock.sendall(first)
            for k in range(len(data)):
                sock.sendall(data[k:k + 1])
                time.sleep(pause_s)
            sock.shutdown(socket.SHUT_WR)
        except OSError:
            pass  # the server closed the connection under us
        try:
            while chunk := sock.recv(65536):
                answer += chunk
        except OSError:
            pass
    out[index] = answer


@pytest.mark.slow
def test_trickling_heads_and_bodies_are_ended_by_the_server(tmp_path: Path):
    prom = tmp_path / "prom"
    prom.mkdir()
    env = {**os.environ, "RCSA_STORE": str(tmp_path / "store"), "RCSA_SEED_DEMO": "false",
           "PROMETHEUS_MULTIPROC_DIR": str(prom), "RCSA_HEADER_TIMEOUT_S": "1", "RCSA_BODY_TIMEOUT_S": "1",
           "RCSA_BODY_MIN_RATE_BYTES_S": "100"}
    log = tmp_path / "uvicorn.log"
    proc, base = start_uvicorn(["service.main:create_app", "--factory", "--http", "service.http:NoDelayHTTPProtocol",
                                "--workers", "2"], env, log, workers=2)
    try:
        wait_until_ready(base, proc, log)
        heads: list[bytes] = [b"?"] * 10
        bodies: list[bytes] = [b"?"] * 10
        threads = [threading.Thread(target=_trickle, args=(base, b"", HEAD, 0.2, heads, i)) for i in range(10)]
        threads += [threading.Thread(target=_trickle, args=(base, HEAD, b" " * 150, 0.2, bodies, i))
                    for i in range(10)]
        for t in threads:
            t.start()
        time.sleep(0.5)  # the slow clients are connected and sending
        assert httpx.get(base + "/healthz", timeout=30).status_code == 200  # others are served meanwhile
        for t in threads:
            t.join(timeout=120)
        assert heads == [b""] * 10  # closed without an answer: no complete head
        for answer in bodies:
            assert answer.startswith(b"HTTP/1.1 408 "), answer[:200]
            assert b"connection: close" in answer.lower() and b"request-timeout" in answer

        # half a body, then the client is gone
        host, port = base.removeprefix("http://").split(":")
        for _ in range(4):  # both workers
            with socket.create_connection((host, int(port)), timeout=30) as sock:
                sock.sendall(HEAD + b'{"frequency": ')
                time.sleep(0.2)
        metrics = ""
        for _ in range(100):  # the workers notice the disconnects
            metrics = httpx.get(base + "/metrics", timeout=30).text
            if 'status="499"' in metrics:
                break
            time.sleep(0.1)
        assert 'route="/v1/tool-point-frf",status="499"' in metrics
        assert 'status="500"' not in metrics
    finally:
        stop_uvicorn(proc)
    text = log.read_text()
    assert "Traceback" not in text and "no complete request head within 1 s" in text

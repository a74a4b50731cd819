"""The HTTP protocol uvicorn should run the service with: its own, plus ``TCP_NODELAY``.

Why: with ``--workers N`` (and with ``--fd``) uvicorn binds the listening socket itself as
``socket.socket(family)``, whose ``proto`` is 0. asyncio sets ``TCP_NODELAY`` on a new
connection only when its socket says ``proto == IPPROTO_TCP``
(``asyncio.base_events._set_nodelay``), so the accepted sockets of a multi-worker uvicorn
keep Nagle's algorithm on. uvicorn writes a response's head and body as two small
``send()``\\s; the second waits for the client's ACK of the first, which a Linux client
delays by ~40 ms. The second request on a keep-alive connection then takes ~44 ms instead
of ~1 ms. (A single-worker uvicorn binds through ``loop.create_server(host, port)``, whose
sockets carry ``IPPROTO_TCP``, and is not affected.)

Fix: uvicorn's documented hook for the HTTP implementation, ``--http MODULE:CLASS``. This
module's :class:`NoDelayHTTPProtocol` is uvicorn's own automatic choice (httptools when
installed, else h11) that sets ``TCP_NODELAY`` on every TCP connection it is given::

    uvicorn --factory service.main:create_app --workers 2 --http service.http:NoDelayHTTPProtocol

``rcsa serve`` and the Docker image do this. ``benchmarks/bench_service.py`` measures the
keep-alive latency of ``/healthz``.

The same class bounds the time the **head of a request** may take (uvicorn has no such
timeout: its keep-alive timer stops at the first byte of the next request, so a client that
sends its headers a byte at a time held a connection for as long as it liked): from the
moment a connection opens, or the first byte of a request after the previous answer, the
request line and headers must be complete within ``RCSA_HEADER_TIMEOUT_S`` (10 s), or the
connection is closed. The body's own timeout is the service's
(:class:`service.middleware.RequestContextMiddleware`).
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import socket
from typing import Any

from uvicorn.protocols.http.auto import AutoHTTPProtocol

from .config import Settings

__all__ = ["HTTP_PROTOCOL", "NoDelayHTTPProtocol", "header_timeout_s", "set_nodelay"]

log = logging.getLogger("service")

#: The ``--http`` value (import string) that selects :class:`NoDelayHTTPProtocol`.
HTTP_PROTOCOL = "service.http:NoDelayHTTPProtocol"


def set_nodelay(transport: asyncio.BaseTransport) -> bool:
    """Turn Nagle's algorithm off on a TCP transport's socket; whether it was set."""
    sock = transport.get_extra_info("socket")
    if sock is None or sock.family not in (socket.AF_INET, socket.AF_INET6) or sock.type != socket.SOCK_STREAM:
        return False
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return True
    return False


@functools.cache
def header_timeout_s() -> float:
    """``RCSA_HEADER_TIMEOUT_S`` of this process's settings, s (read once)."""
    return Settings().header_timeout_s


class NoDelayHTTPProtocol(AutoHTTPProtocol):  # type: ignore[misc,valid-type]
    """uvicorn's automatic HTTP protocol, with ``TCP_NODELAY`` on each connection and a
    timeout on the head of every request (module docstring)."""

    _head_timer: asyncio.TimerHandle | None = None

    def connection_made(self, transport: Any) -> None:
        """Set ``TCP_NODELAY``, let uvicorn take the connection, and start waiting for a head."""
        set_nodelay(transport)
        super().connection_made(transport)
        self._arm_head_timer()

    def data_received(self, data: bytes) -> None:
        """Start the head's clock at the first byte of a request; stop it once its head is complete."""
        if self._between_requests():
            self._arm_head_timer()
        super().data_received(data)
        if not self._between_requests():
            self._disarm_head_timer()

    def connection_lost(self, exc: Exception | None) -> None:
        """Forget the head's clock, then let uvicorn close."""
        self._disarm_head_timer()
        super().connection_lost(exc)

    def _between_requests(self) -> bool:
        cycle = getattr(self, "cycle", None)
        return cycle is None or bool(cycle.response_complete)

    def _arm_head_timer(self) -> None:
        if self._head_timer is None:
            self._head_timer = asyncio.get_running_loop().call_later(header_timeout_s(), self._head_too_slow)

    def _disarm_head_timer(self) -> None:
        if self._head_timer is not None:
            self._head_timer.cancel()
            self._head_timer = None

    def _head_too_slow(self) -> None:
        self._head_timer = None
        if self._between_requests() and not self.transport.is_closing():
            client = getattr(self, "client", None)
            log.info("closed a connection from %s: no complete request head within %g s (RCSA_HEADER_TIMEOUT_S)",
                     client[0] if client else "-", header_timeout_s())
            self.transport.close()

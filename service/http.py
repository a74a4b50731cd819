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
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
from typing import Any

from uvicorn.protocols.http.auto import AutoHTTPProtocol

__all__ = ["HTTP_PROTOCOL", "NoDelayHTTPProtocol", "set_nodelay"]

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


class NoDelayHTTPProtocol(AutoHTTPProtocol):  # type: ignore[misc,valid-type]
    """uvicorn's automatic HTTP protocol, with ``TCP_NODELAY`` on each connection."""

    def connection_made(self, transport: Any) -> None:
        """Set ``TCP_NODELAY``, then let uvicorn take the connection."""
        set_nodelay(transport)
        super().connection_made(transport)

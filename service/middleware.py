"""The request envelope: request id, body-size limit, metrics, access log, last-resort 500.

:class:`RequestContextMiddleware` is a plain ASGI middleware (no per-request task or body
copy). For every HTTP request it

* takes ``X-Request-ID`` from the client when it is a sane token (≤ 128 of
  ``A-Z a-z 0-9 . _ : -``) or makes one, echoes it in the response and puts it in every log
  line written while the request runs (``%(request_id)s``, via a context variable);
* refuses bodies over the limit with ``413`` — at once when ``Content-Length`` says so, else
  while the body is read (chunked uploads are counted byte by byte);
* bounds the time a body may take to arrive (uvicorn has no such timeout): while the app
  waits for the next piece of the body, at most ``body_timeout_s`` may pass, and in all at
  most ``body_timeout_s`` plus the bytes received over ``body_min_rate_bytes_s`` — a client
  that trickles its body is answered ``408`` and disconnected, whatever the size it announced
  (:class:`BodyTimeout`; the head of a request has its own timeout in :mod:`service.http`);
* a client that disconnects before its request was answered is counted and logged as such
  (status ``499``, as nginx says it, without a traceback), not as a ``500``;
* puts the security headers (:data:`SECURITY_HEADERS`) on every answer, and a
  Content-Security-Policy that allows nothing on every answer that is not a page;
* closes the connection after answering a request whose body was not read to its end (a
  refused upload is not read on);
* counts the request and its latency by route template and status (``/metrics``);
* turns an exception nobody handled (a bug) into a generic ``500`` problem after logging
  its traceback with the request id.
"""

from __future__ import annotations

import asyncio
import logging
import re
import time
import uuid
from contextvars import ContextVar

import orjson
from starlette.datastructures import Headers, MutableHeaders
from starlette.requests import ClientDisconnect
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from .errors import PROBLEM_MEDIA_TYPE, BodyTooLarge, problem_body
from .metrics import Metrics

__all__ = ["BODY_LIMIT_KEY", "CLIENT_CLOSED_REQUEST", "SECURITY_HEADERS", "BodyTimeout", "RequestContextMiddleware",
           "RequestIdFilter", "configure_logging", "request_id_var"]

#: Status counted (``/metrics``, access log) for a request whose client went away before the
#: answer (nginx's 499 "client closed request"; never sent: nobody is there to read it).
CLIENT_CLOSED_REQUEST = 499
#: Headers every answer carries (a route's own value wins).
SECURITY_HEADERS = ((b"x-content-type-options", b"nosniff"), (b"x-frame-options", b"DENY"),
                    (b"referrer-policy", b"no-referrer"), (b"cross-origin-opener-policy", b"same-origin"))
#: Content-Security-Policy of every answer that is not an HTML page (JSON, files, pictures): nothing
#: may run, load or frame it. Pages (the web view, the API reference) bring their own policy.
_NO_CONTENT_POLICY = b"default-src 'none'; frame-ancestors 'none'; sandbox"


class BodyTimeout(Exception):
    """The request body did not arrive in time (see the module docstring)."""

    def __init__(self, received: int, seconds: float) -> None:
        super().__init__(f"the request body did not arrive in time: {received} bytes in {seconds:.1f} s of waiting; "
                         "send it without pauses (the server waits at most RCSA_BODY_TIMEOUT_S between pieces and "
                         "needs RCSA_BODY_MIN_RATE_BYTES_S on average)")
        self.detail = str(self)

log = logging.getLogger("service")
access_log = logging.getLogger("service.access")

#: Scope key through which a route lowers the body limit for its own requests
#: (:class:`service.routing.ServiceRoute`).
BODY_LIMIT_KEY = "rcsa.max_body_bytes"

request_id_var: ContextVar[str] = ContextVar("rcsa_request_id", default="-")
_REQUEST_ID = re.compile(r"^[A-Za-z0-9._:\-]{1,128}$")
_LOG_FORMAT = "%(asctime)s %(levelname)s %(name)s [request_id=%(request_id)s] %(message)s"


class RequestIdFilter(logging.Filter):
    """Adds ``record.request_id`` (the current request's id, ``-`` outside requests)."""

    def filter(self, record: logging.LogRecord) -> bool:
        if not hasattr(record, "request_id"):
            record.request_id = request_id_var.get()
        return True


def configure_logging(access: bool) -> None:
    """Give the service's loggers a handler that prints request ids (idempotent).

    Leaves logging alone when the root logger is already configured (the application that
    embeds us decides). With ``access``, our access line (which carries the request id)
    replaces uvicorn's.
    """
    flt = RequestIdFilter()
    factory = logging.getLogRecordFactory()
    if not getattr(factory, "_rcsa", False):  # every record of the process gets request_id

        def record_factory(*args, **kwargs):  # type: ignore[no-untyped-def]
            record = factory(*args, **kwargs)
            record.request_id = request_id_var.get()
            return record

        record_factory._rcsa = True  # type: ignore[attr-defined]
        logging.setLogRecordFactory(record_factory)
    for name in ("service", "rcsa"):
        logger = logging.getLogger(name)
        if logger.level == logging.NOTSET:
            logger.setLevel(logging.INFO)
        if not logging.getLogger().handlers and not any(getattr(h, "_rcsa", False) for h in logger.handlers):
            handler = logging.StreamHandler()
            handler.setFormatter(logging.Formatter(_LOG_FORMAT))
            handler.addFilter(flt)
            handler._rcsa = True  # type: ignore[attr-defined]
            logger.addHandler(handler)
            logger.propagate = False
    for name in ("uvicorn", "uvicorn.error", "uvicorn.access"):
        for handler in logging.getLogger(name).handlers:
            if not any(isinstance(f, RequestIdFilter) for f in handler.filters):
                handler.addFilter(flt)
    if access:
        logging.getLogger("uvicorn.access").disabled = True


async def _send_problem(scope: Scope, send: Send, status: int, detail: str, request_id: str,
                        *, slug: str | None = None) -> None:
    body = orjson.dumps(problem_body(status, detail, slug=slug, instance=scope.get("path"), request_id=request_id))
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", PROBLEM_MEDIA_TYPE.encode()),
                            (b"content-length", str(len(body)).encode())]})  # the caller's send adds the id
    await send({"type": "http.response.body", "body": body})


def _has_body(headers: Headers) -> bool:
    """Whether the request announces a body (a length above 0, or chunked)."""
    length = headers.get("content-length", "")
    return (length.isdigit() and int(length) > 0) or "transfer-encoding" in headers


def _secure(message: Message, close: bool) -> None:
    """Add the security headers (and ``Connection: close``) to a response start, in place."""
    raw = list(message.get("headers", []))
    names = {k.lower() for k, _ in raw}
    raw += [(k, v) for k, v in SECURITY_HEADERS if k not in names]
    if b"content-security-policy" not in names:
        media = next((v for k, v in raw if k.lower() == b"content-type"), b"")
        if not media.lower().startswith(b"text/html"):
            raw.append((b"content-security-policy", _NO_CONTENT_POLICY))
    if close and b"connection" not in names:
        raw.append((b"connection", b"close"))
    message["headers"] = raw


class RequestContextMiddleware:
    """See the module docstring.

    Parameters
    ----------
    app : ASGI app
    metrics : Metrics
    max_body_bytes : int
    access : bool
        Write one access-log line per request.
    body_timeout_s : float
        Longest wait for the next piece of a body, and the grace before the rate counts, s.
    body_min_rate_bytes_s : float
        Average rate a body must keep arriving at beyond the grace, bytes/s.
    """

    def __init__(self, app: ASGIApp, *, metrics: Metrics, max_body_bytes: int, access: bool = True,
                 body_timeout_s: float = 10.0, body_min_rate_bytes_s: float = 4096.0) -> None:
        self.app = app
        self.metrics = metrics
        self.max_body_bytes = int(max_body_bytes)
        self.access = access
        self.body_timeout_s = float(body_timeout_s)
        self.body_min_rate_bytes_s = float(body_min_rate_bytes_s)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = Headers(scope=scope)
        given = headers.get("x-request-id", "")
        rid = given if _REQUEST_ID.match(given) else uuid.uuid4().hex
        token = request_id_var.set(rid)
        scope.setdefault("state", {})["request_id"] = rid
        t0 = time.perf_counter()
        status, started = 500, False
        limit = self.max_body_bytes
        received = 0
        waited = 0.0  # seconds spent waiting for pieces of the body
        body_done = not _has_body(headers)
        disconnected = False

        async def receive_limited() -> Message:
            nonlocal received, waited, body_done, disconnected
            if body_done:
                message = await receive()
            else:
                allowance = self.body_timeout_s + received / self.body_min_rate_bytes_s - waited
                pause = min(self.body_timeout_s, max(allowance, 0.0))
                t = time.monotonic()
                try:
                    message = await asyncio.wait_for(receive(), timeout=pause)
                except TimeoutError:
                    raise BodyTimeout(received, waited + pause) from None
                finally:
                    waited += time.monotonic() - t
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if not message.get("more_body", False):
                    body_done = True
                own = scope.get(BODY_LIMIT_KEY)  # set by the route before it reads the body
                if received > limit or (own is not None and received > own):
                    raise BodyTooLarge(limit if own is None else min(limit, int(own)),
                                       where=None if own is None else f"{scope.get('method')} {scope.get('path')}")
            elif message["type"] == "http.disconnect" and not started:
                disconnected = True
            return message

        async def send_with_id(message: Message) -> None:
            nonlocal status, started
            if message["type"] == "http.response.start":
                started, status = True, int(message["status"])
                MutableHeaders(scope=message).append("X-Request-ID", rid)
                _secure(message, close=not body_done)
            await send(message)

        async def refuse(code: int, detail: str, slug: str | None = None) -> None:
            nonlocal status, started
            status, started = code, True
            await _send_problem(scope, send_with_id, code, detail, rid, slug=slug)

        try:
            length = headers.get("content-length", "")
            if length.isdigit() and int(length) > limit:
                await refuse(413, BodyTooLarge(limit).detail)
                return
            await self.app(scope, receive_limited, send_with_id)
        except BodyTooLarge as exc:
            if started:
                raise
            await refuse(413, exc.detail)
        except BodyTimeout as exc:
            if started:
                raise
            log.info("%s %s: %s", scope.get("method"), scope.get("path"), exc)
            await refuse(408, exc.detail, slug="request-timeout")
        except Exception as exc:
            if disconnected or isinstance(exc, ClientDisconnect):  # nobody is there to answer
                status = CLIENT_CLOSED_REQUEST
                log.info("client disconnected before the answer to %s %s (%d bytes of the body received)",
                         scope.get("method"), scope.get("path"), received)
                return
            log.exception("unhandled error in %s %s", scope.get("method"), scope.get("path"))
            if started:
                raise
            await refuse(500, "internal error: this is a bug in the service, not in your request; report it with "
                              "the request_id")
        finally:
            if disconnected and not started:
                status = CLIENT_CLOSED_REQUEST
            elapsed = time.perf_counter() - t0
            route = scope.get("route")
            template = getattr(route, "path", None) or "<unmatched>"
            method = scope.get("method", "")
            self.metrics.requests.labels(method, template, str(status)).inc()
            self.metrics.latency.labels(method, template).observe(elapsed)
            if self.access:
                access_log.info('%s "%s %s" %d %.1f ms', (scope.get("client") or ("-",))[0], method,
                                scope.get("path"), status, elapsed * 1e3)
            request_id_var.reset(token)

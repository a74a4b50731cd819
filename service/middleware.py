"""The request envelope: request id, body-size limit, metrics, access log, last-resort 500.

:class:`RequestContextMiddleware` is a plain ASGI middleware (no per-request task or body
copy). For every HTTP request it

* takes ``X-Request-ID`` from the client when it is a sane token (≤ 128 of
  ``A-Z a-z 0-9 . _ : -``) or makes one, echoes it in the response and puts it in every log
  line written while the request runs (``%(request_id)s``, via a context variable);
* refuses bodies over the limit with ``413`` — at once when ``Content-Length`` says so, else
  while the body is read (chunked uploads are counted byte by byte);
* counts the request and its latency by route template and status (``/metrics``);
* turns an exception nobody handled (a bug) into a generic ``500`` problem after logging
  its traceback with the request id.
"""

from __future__ import annotations

import logging
import re
import time
import uuid
from contextvars import ContextVar

import orjson
from starlette.datastructures import Headers, MutableHeaders
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from .errors import PROBLEM_MEDIA_TYPE, BodyTooLarge, problem_body
from .metrics import Metrics

__all__ = ["BODY_LIMIT_KEY", "RequestContextMiddleware", "RequestIdFilter", "configure_logging", "request_id_var"]

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


async def _send_problem(scope: Scope, send: Send, status: int, detail: str, request_id: str) -> None:
    body = orjson.dumps(problem_body(status, detail, instance=scope.get("path"), request_id=request_id))
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", PROBLEM_MEDIA_TYPE.encode()),
                            (b"content-length", str(len(body)).encode()),
                            (b"x-request-id", request_id.encode())]})
    await send({"type": "http.response.body", "body": body})


class RequestContextMiddleware:
    """See the module docstring.

    Parameters
    ----------
    app : ASGI app
    metrics : Metrics
    max_body_bytes : int
    access : bool
        Write one access-log line per request.
    """

    def __init__(self, app: ASGIApp, *, metrics: Metrics, max_body_bytes: int, access: bool = True) -> None:
        self.app = app
        self.metrics = metrics
        self.max_body_bytes = int(max_body_bytes)
        self.access = access

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

        async def receive_limited() -> Message:
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                own = scope.get(BODY_LIMIT_KEY)  # set by the route before it reads the body
                if received > limit or (own is not None and received > own):
                    raise BodyTooLarge(limit if own is None else min(limit, int(own)),
                                       where=None if own is None else f"{scope.get('method')} {scope.get('path')}")
            return message

        async def send_with_id(message: Message) -> None:
            nonlocal status, started
            if message["type"] == "http.response.start":
                started, status = True, int(message["status"])
                MutableHeaders(scope=message).append("X-Request-ID", rid)
            await send(message)

        try:
            length = headers.get("content-length", "")
            if length.isdigit() and int(length) > limit:
                status, started = 413, True
                await _send_problem(scope, send, 413, BodyTooLarge(limit).detail, rid)
                return
            await self.app(scope, receive_limited, send_with_id)
        except BodyTooLarge as exc:
            if started:
                raise
            status, started = 413, True
            await _send_problem(scope, send, 413, exc.detail, rid)
        except Exception:
            log.exception("unhandled error in %s %s", scope.get("method"), scope.get("path"))
            if started:
                raise
            status, started = 500, True
            await _send_problem(scope, send, 500, "internal error: this is a bug in the service, not in "
                                "your request; report it with the request_id", rid)
        finally:
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

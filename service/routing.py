"""The route class of every router: what happens before FastAPI looks at a request's body.

FastAPI reads and parses a route's body before it runs the route's dependencies, so a
check made by a dependency (the API key) comes after the body was read. :class:`ServiceRoute`
puts the checks that must come first in front, in this order:

1. **Body size** — the route's own limit (``openapi_extra["x-max-body-bytes"]``, stated in
   the OpenAPI; never above ``RCSA_MAX_BODY_BYTES``): a ``Content-Length`` above it is a
   ``413`` at once, and :class:`service.middleware.RequestContextMiddleware` counts a chunked
   body against it while it is read.
2. **Authentication and scope** — the route's access (``require_read`` or ``require_write``
   among its dependencies) is checked from the ``X-API-Key`` header before a byte of the body
   is read: a refused write never reads, parses or stores anything.
3. **The JSON policy** — a JSON body's objects, arrays and elements are counted while it
   arrives (:func:`rcsa.app.inputs.json_counter`: at most ``MAX_JSON_CONTAINERS`` and
   ``MAX_JSON_ITEMS``), so a body of millions of tiny items is refused before the rest of it is
   read and before anything is parsed; then it is decoded once by
   :func:`rcsa.app.inputs.decode_json` (RFC 8259 strict: no NaN/Infinity; nesting ≤
   ``MAX_JSON_DEPTH``; every number's magnitude ≤ ``MAX_JSON_NUMBER``). Text that is not JSON
   is a ``400``; a well-formed document that breaks a rule a ``422`` naming the field. A body
   larger than :data:`OFF_LOOP_BYTES` is decoded, and validated against the route's body model,
   in a worker thread, never on the event loop that serves every other caller. FastAPI's body
   parsing, :func:`service.bodies.read_body` and the idempotency fingerprint then take that
   document (:class:`ServiceRequest`), never the raw bytes again.

Then the route's own handler runs (for :class:`service.idempotency.IdempotentRoute`, under
its ``Idempotency-Key``). A ``POST`` that only reads (every computation answered at once:
predictions, batches, lobes, analyses, figures, exports, library predictions, file reads)
runs under the **time limit** ``RCSA_SYNC_TIME_LIMIT_S`` (:func:`rcsa.app.budget.time_limited`):
the computation stops at its next step boundary once the limit has passed, and the client gets
a ``503`` problem (``compute-time-limit``) at the limit plus a short grace in any case — the
request never holds the connection, or a shutdown (SIGTERM), for longer. Writes (uploads,
syncs, deletes) are not cut short: they finish what they started.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any

from fastapi import Request
from fastapi.concurrency import run_in_threadpool
from fastapi.exceptions import RequestValidationError
from fastapi.routing import APIRoute
from starlette.responses import Response

from rcsa.app.budget import time_limited
from rcsa.app.inputs import decode_json, json_counter
from rcsa.errors import MalformedInput, TimeLimitExceeded
from rcsa.infra.api_keys import Principal

from .errors import BodyTooLarge, malformed_body
from .middleware import BODY_LIMIT_KEY
from .security import access_of, principal, require_read, require_write
from .state import ensure_state

__all__ = ["BODY_LIMIT_KEY", "MAX_BODY_EXTENSION", "OFF_LOOP_BYTES", "ServiceRequest", "ServiceRoute",
           "is_json_media"]

#: ``openapi_extra`` key (an OpenAPI extension) holding a route's largest body, bytes.
MAX_BODY_EXTENSION = "x-max-body-bytes"
#: Scope key of the caller's principal once the route class has authenticated it.
PRINCIPAL_KEY = "rcsa.principal"
#: JSON bodies larger than this are decoded and validated in a worker thread, bytes (a
#: prediction's body is ~1 KiB; 8 MiB of batch takes ~0.1 s to decode and more to validate).
OFF_LOOP_BYTES = 64 * 1024
#: Bodies whose Content-Length says at most this many bytes are not counted while they arrive
#: (too short to exceed the JSON policy's bounds, which :func:`rcsa.app.inputs.decode_json` checks).
_COUNT_ABOVE_BYTES = 200_000

Handler = Callable[[Request], Awaitable[Response]]


def is_json_media(media: str) -> bool:
    """Whether a media type (no parameters, lower case) is JSON."""
    return media == "application/json" or (media.startswith("application/") and media.endswith("+json"))


class ServiceRequest(Request):
    """A request whose JSON body is counted as it arrives and decoded once, under the JSON policy."""

    def _media(self) -> str:
        return self.headers.get("content-type", "").split(";")[0].strip().lower()

    async def body(self) -> bytes:
        """The body; a JSON body's objects, arrays and elements counted piece by piece as they
        arrive (:func:`rcsa.app.inputs.json_counter`: refused past the bounds before the
        rest is read)."""
        if not hasattr(self, "_body"):
            length = self.headers.get("content-length", "")
            count = json_counter() if is_json_media(self._media()) and not (
                length.isdigit() and int(length) <= _COUNT_ABOVE_BYTES) else None
            chunks: list[bytes] = []
            async for chunk in self.stream():
                if count is not None and chunk:
                    count(chunk)
                chunks.append(chunk)
            self._body = b"".join(chunks)
            self._rcsa_counted = True
        return self._body

    async def document(self) -> Any:
        """The body decoded by :func:`rcsa.app.inputs.decode_json` (cached; in a worker thread
        when larger than :data:`OFF_LOOP_BYTES`)."""
        if not hasattr(self, "_rcsa_json"):
            body = await self.body()
            counted = getattr(self, "_rcsa_counted", False)
            try:
                if len(body) > OFF_LOOP_BYTES:
                    self._rcsa_json = await run_in_threadpool(decode_json, body, counted=counted)
                else:
                    self._rcsa_json = decode_json(body, counted=counted)
            except MalformedInput as exc:
                raise malformed_body(exc) from None
        return self._rcsa_json

    async def json(self) -> Any:
        """What FastAPI validates the body as: the route's body model when :class:`ServiceRoute`
        validated it already (in a worker thread: pydantic accepts the instance as it is), else
        :meth:`document`."""
        validated = getattr(self, "_rcsa_validated", None)
        return validated if validated is not None else await self.document()


class ServiceRoute(APIRoute):
    """An ``APIRoute`` with the checks of the module docstring in front of its handler."""

    def __init__(self, path: str, endpoint: Callable[..., Any], **kwargs: Any) -> None:
        super().__init__(path, endpoint, **kwargs)  # builds the handler (get_route_handler)

    def wrap_handler(self, handler: Handler) -> Handler:
        """Hook for subclasses: wrap FastAPI's handler (runs after the checks)."""
        return handler

    def get_route_handler(self) -> Handler:  # type: ignore[override]
        """FastAPI's handler behind the body-size, authentication and JSON checks."""
        inner = self.wrap_handler(super().get_route_handler())
        limit_given = (self.openapi_extra or {}).get(MAX_BODY_EXTENSION)
        route_limit = int(limit_given) if limit_given is not None else None
        access = access_of(self.dependant)
        where = f"{sorted(self.methods or ())[0] if self.methods else ''} {self.path}".strip()
        timed = "POST" in (self.methods or set()) and access == "read"  # writes finish what they start

        async def handler(request: Request) -> Response:
            request = ServiceRequest(request.scope, request.receive)
            state = await run_in_threadpool(ensure_state, request.app)
            limit = state.settings.max_body_bytes
            if route_limit is not None and route_limit < limit:
                limit = route_limit
                request.scope[BODY_LIMIT_KEY] = limit
            length = request.headers.get("content-length", "")
            if length.isdigit() and int(length) > limit:
                raise BodyTooLarge(limit, where=where if limit == route_limit else None)
            if access is not None:
                request.scope[PRINCIPAL_KEY] = await run_in_threadpool(_authorize, state, request, access)
            if request.method in ("POST", "PUT", "PATCH") and is_json_media(request._media()):
                doc = await request.document()
                if self.body_field is not None and len(await request.body()) > OFF_LOOP_BYTES:
                    request._rcsa_validated = await run_in_threadpool(self._validated_body, doc)
            if timed and state.settings.sync_time_limit_s:
                return await within(state.settings.sync_time_limit_s, inner(request))
            return await inner(request)

        return handler

    def _validated_body(self, doc: Any) -> Any:
        """The body validated against the route's body model, as FastAPI would (its errors too)."""
        assert self.body_field is not None
        value, errors = self.body_field.validate(doc, {}, loc=("body",))
        if errors:
            raise RequestValidationError(errors, body=None)
        return value


#: How long after its time limit an answer given at once is cut off, if the computation has
#: not stopped by itself at a step boundary (a prediction has none), s.
TIME_LIMIT_GRACE_S = 2.0


async def within(seconds: float, answer: Awaitable[Response]) -> Response:
    """``answer`` under a time limit of ``seconds`` (:func:`rcsa.app.budget.time_limited`).

    The computation sees the limit and stops at its next step boundary (raising
    :class:`~rcsa.errors.TimeLimitExceeded`); when it has none, the answer is not awaited
    beyond ``seconds + TIME_LIMIT_GRACE_S`` (its thread finishes on its own; its result is
    dropped).

    Raises
    ------
    TimeLimitExceeded
        The limit passed (the service answers 503).
    """
    with time_limited(seconds):  # the task (and the thread it starts) copy this context
        task = asyncio.ensure_future(answer)
    done, _ = await asyncio.wait({task}, timeout=seconds + TIME_LIMIT_GRACE_S)
    if task in done:
        return task.result()
    task.add_done_callback(_drop)
    raise TimeLimitExceeded(seconds)


def _drop(task: asyncio.Future[Any]) -> None:
    if not task.cancelled():
        task.exception()  # retrieved: no "exception was never retrieved" warning


def _authorize(state: Any, request: Request, access: str) -> Principal:
    who = principal(state, request.headers.get("x-api-key"))
    return require_write(who) if access == "write" else require_read(state, who)


def caller(request: Request) -> Principal | None:
    """The principal the route class authenticated (None on routes without access checks)."""
    found = request.scope.get(PRINCIPAL_KEY)
    return found if isinstance(found, Principal) else None

"""RFC 9457 problem details: every error of the service as ``application/problem+json``.

A problem has ``type`` (a URN naming the kind of problem), ``title``, ``status``,
``detail`` (what went wrong and what to do, for a person), ``instance`` (the request path),
``request_id`` (the ``X-Request-ID`` of the request, to find its log lines) and, for invalid
input, ``errors``: ``[{"field": "holder.segments[2].length_m", "detail": "..."}]`` with the
offending field as a dotted path into the request (form fields and query parameters by
name). Past :data:`MAX_PROBLEM_ERRORS` offending fields the list stops, and ``detail`` and
``errors_total`` say how many there were.

Mapping: a JSON request body that is not JSON at all (:class:`rcsa.errors.MalformedInput`:
syntax, NaN/Infinity tokens, not UTF-8; :func:`malformed_body`) → 400; pydantic's ``RequestValidationError`` and
:class:`rcsa.errors.InputError` (a well-formed document that breaks a rule) → 422;
:class:`rcsa.errors.NotFoundError` → 404; :class:`rcsa.errors.DamagedError` (one stored
object cannot be read) and :class:`rcsa.errors.ConflictError` → 409;
:class:`rcsa.errors.StoreError` (the store as a whole) → 503; HTTP
errors keep their status; anything else is a bug → 500 with a generic detail, its traceback
logged with the request id (see :mod:`service.middleware`).
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import Any

import orjson
from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.responses import Response
from starlette.routing import BaseRoute, Match

from rcsa.app.budget import BudgetExceeded
from rcsa.errors import (
    ConflictError,
    DamagedError,
    InputError,
    MalformedInput,
    NotFoundError,
    StoreError,
    TimeLimitExceeded,
)

from .field_errors import pydantic_errors

__all__ = [
    "MAX_PROBLEM_ERRORS",
    "PROBLEM_MEDIA_TYPE",
    "BodyTooLarge",
    "ProblemError",
    "allowed_methods",
    "install_error_handlers",
    "iter_routes",
    "malformed_body",
    "problem_body",
    "problem_response",
    "pydantic_errors",
]

log = logging.getLogger("service.errors")

PROBLEM_MEDIA_TYPE = "application/problem+json"
#: Most offending fields a problem lists (the rest are counted in ``errors_total``).
MAX_PROBLEM_ERRORS = 100
TYPE_PREFIX = "urn:rcsa:problem:"

_BY_STATUS = {
    400: ("bad-request", "Bad request"),
    401: ("unauthorized", "API key required"),
    403: ("forbidden", "Not allowed with this API key"),
    404: ("not-found", "Not found"),
    405: ("method-not-allowed", "Method not allowed"),
    406: ("not-acceptable", "Not acceptable"),
    409: ("conflict", "Conflict"),
    413: ("content-too-large", "Request too large"),
    415: ("unsupported-media-type", "Unsupported media type"),
    422: ("invalid-input", "Invalid input"),
    500: ("internal-error", "Internal server error"),
    501: ("not-implemented", "Not implemented"),
    503: ("unavailable", "Service unavailable"),
}


class ProblemError(Exception):
    """Raise to answer with a problem document.

    Parameters
    ----------
    status : int
        HTTP status.
    detail : str
        What went wrong and what to do about it.
    slug : str, optional
        Kind of problem (``type`` is ``urn:rcsa:problem:<slug>``); default from the status.
    title : str, optional
    errors : sequence of dict, optional
        ``{"field", "detail"}`` per offending field.
    headers : mapping, optional
        Extra response headers (``WWW-Authenticate``, ``Retry-After``, ``Location``).
    extra : mapping, optional
        Extension members.
    """

    def __init__(self, status: int, detail: str, *, slug: str | None = None, title: str | None = None,
                 errors: Sequence[Mapping[str, Any]] | None = None, headers: Mapping[str, str] | None = None,
                 extra: Mapping[str, Any] | None = None) -> None:
        super().__init__(detail)
        default_slug, default_title = _BY_STATUS.get(status, ("http-error", "Error"))
        self.status = status
        self.detail = detail
        self.slug = slug or default_slug
        self.title = title or default_title
        self.errors = list(errors) if errors else None
        self.headers = dict(headers or {})
        self.extra = dict(extra or {})


class BodyTooLarge(StarletteHTTPException):
    """The request body exceeds the configured limit (raised while it is being read)."""

    def __init__(self, limit_bytes: int, where: str | None = None) -> None:
        if where is None:
            detail = (f"the request body exceeds the limit of {limit_bytes} bytes ({limit_bytes / 2**20:g} MiB); "
                      "send less (e.g. split a batch) or ask the operator to raise RCSA_MAX_BODY_BYTES")
        else:
            detail = (f"the request body exceeds the limit of {where}, {limit_bytes} bytes "
                      f"({limit_bytes / 2**20:g} MiB, stated in the OpenAPI as x-max-body-bytes); send less "
                      "(fewer lines or measurements, split a batch)")
        super().__init__(413, detail)
        self.limit_bytes = limit_bytes


def problem_body(status: int, detail: str, *, slug: str | None = None, title: str | None = None,
                 instance: str | None = None, request_id: str | None = None,
                 errors: Sequence[Mapping[str, Any]] | None = None,
                 extra: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The problem document (a dict) for these members."""
    default_slug, default_title = _BY_STATUS.get(status, ("http-error", "Error"))
    body: dict[str, Any] = {"type": TYPE_PREFIX + (slug or default_slug), "title": title or default_title,
                            "status": status, "detail": detail}
    if instance is not None:
        body["instance"] = instance
    if request_id is not None:
        body["request_id"] = request_id
    if errors:
        body["errors"] = [dict(e) for e in errors[:MAX_PROBLEM_ERRORS]]
        if len(errors) > MAX_PROBLEM_ERRORS:
            body["errors_total"] = len(errors)
    if extra:
        body.update({k: v for k, v in extra.items() if k not in body})
    return body


def problem_response(request: Request | None, status: int, detail: str, *,
                     headers: Mapping[str, str] | None = None, **members: Any) -> Response:
    """A ``Response`` carrying a problem document for ``request``."""
    instance = request_id = None
    if request is not None:
        instance = request.url.path
        request_id = request.scope.get("state", {}).get("request_id")
    body = problem_body(status, detail, instance=instance, request_id=request_id, **members)
    return Response(orjson.dumps(body), status_code=status, media_type=PROBLEM_MEDIA_TYPE,
                    headers=dict(headers or {}))


def _validation_errors(exc: RequestValidationError) -> list[dict[str, str]]:
    return pydantic_errors(exc.errors())


# --------------------------------------------------------------------------- handlers

def _detail_of(errors: Sequence[Mapping[str, str]]) -> str:
    first = errors[0]
    text = f"{first['field']}: {first['detail']}" if first["field"] else first["detail"]
    if len(errors) > MAX_PROBLEM_ERRORS:
        text += (f" (and {len(errors) - 1} more problems; errors lists the first {MAX_PROBLEM_ERRORS}, errors_total "
                 "counts them all)")
    elif len(errors) > 1:
        text += f" (and {len(errors) - 1} more problem{'s' if len(errors) > 2 else ''}, listed in errors)"
    return text


async def _on_validation(request: Request, exc: RequestValidationError) -> Response:
    errors = _validation_errors(exc) or [{"field": "", "detail": "invalid request"}]
    return problem_response(request, 422, _detail_of(errors), errors=errors)


async def _on_input(request: Request, exc: InputError) -> Response:
    errors = [{"field": exc.field, "detail": exc.rule}]
    return problem_response(request, 422, _detail_of(errors), errors=errors)


def malformed_body(exc: MalformedInput) -> ProblemError:
    """The ``400`` problem of a request body that is not JSON at all (a JSON form field or an
    uploaded file that is not JSON is a ``422``: the request itself was well-formed)."""
    return ProblemError(400, exc.rule, slug="malformed-body", title="Malformed body",
                        errors=[{"field": exc.field, "detail": exc.rule}])


_NOT_FOUND_HINTS = {
    "measurement": "list the stored measurements with GET /v1/measurements",
    "job": "job ids come from a 202 answer's Location header, and a job is read with the API key or job token "
           "(X-Job-Token) that started it; finished jobs are purged after a while",
    "library": "list the stored libraries with GET /v1/libraries",
    "tool": "list the library's tools with GET /v1/libraries/{library_id}",
    "result of job": "the job has not succeeded; GET /v1/jobs/{id} shows its status",
}


async def _on_budget(request: Request, exc: BudgetExceeded) -> Response:
    limits = {"estimated_seconds": exc.limits.seconds, "estimated_memory_bytes": int(exc.limits.memory_bytes)}
    return problem_response(request, 422, exc.rule, slug="compute-budget-exceeded", title="Compute budget exceeded",
                            errors=[{"field": exc.field, "detail": "the request asks for more work than allowed"}],
                            extra={"budget": {"mode": exc.mode, "limit": limits, "cost": exc.cost.to_dict(),
                                              "shrink": list(exc.cost.shrink)}})


async def _on_not_found(request: Request, exc: NotFoundError) -> Response:
    hint = _NOT_FOUND_HINTS.get(exc.what, "check the id")
    return problem_response(request, 404, f"{exc}; {hint}", extra={"resource": exc.what, "id": exc.ident})


async def _on_store(request: Request, exc: StoreError) -> Response:
    log.error("store error: %s", exc)
    return problem_response(request, 503, f"the measurement store is unavailable: {exc}",
                            slug="store-unavailable", headers={"Retry-After": "5"})


async def _on_damaged(request: Request, exc: DamagedError) -> Response:
    log.error("damaged %s %s: %s", exc.what, exc.ident, exc.reason)
    return problem_response(request, 409, f"{exc.what} {exc.ident} is damaged and cannot be read ({exc.reason}); "
                                          "retrying will not help. The operator can run `rcsa store check` and "
                                          f"delete it (DELETE /v1/measurements/{exc.ident}); upload it again",
                            slug="damaged", title="Stored object damaged",
                            extra={"resource": exc.what, "id": exc.ident, "reason": exc.reason})


async def _on_time_limit(request: Request, exc: TimeLimitExceeded) -> Response:
    log.warning("time limit: %s %s stopped after %g s", request.method, request.url.path, exc.seconds)
    return problem_response(request, 503, f"this request took longer than the {exc.seconds:g} s an answer given at "
                                          "once may take (RCSA_SYNC_TIME_LIMIT_S) and was stopped; send it with the "
                                          "header Prefer: respond-async to run it as a job, or make it smaller",
                            slug="compute-time-limit", title="Computation time limit exceeded",
                            extra={"time_limit_s": exc.seconds})


async def _on_conflict(request: Request, exc: ConflictError) -> Response:
    return problem_response(request, 409, f"{exc.what} {exc.ident} {exc.reason}", slug="conflict",
                            extra={"resource": exc.what, "id": exc.ident})


async def _on_problem(request: Request, exc: ProblemError) -> Response:
    return problem_response(request, exc.status, exc.detail, slug=exc.slug, title=exc.title,
                            errors=exc.errors, extra=exc.extra, headers=exc.headers)


_HTTP_DETAILS = {
    400: "the body could not be parsed: send UTF-8 JSON (Content-Type application/json) or a well-formed "
         "multipart/form-data upload",
    404: "no such endpoint; the API is described at /docs and /openapi.json",
    405: "this endpoint does not accept that method; see /docs",
}


def iter_routes(routes: Iterable[Any]) -> Iterator[BaseRoute]:
    """Every route, with included routers opened (newer FastAPI versions wrap them)."""
    for route in routes:
        inner = getattr(route, "original_router", None)
        if inner is not None:
            yield from iter_routes(inner.routes)
        elif isinstance(route, BaseRoute):
            yield route


def allowed_methods(request: Request) -> list[str]:
    """Every method some route accepts at the request's path (the ``Allow`` of a 405).

    Starlette answers a 405 with the methods of the first route whose path matched, so a
    path served by several routes (``GET`` and ``POST /v1/measurements``) named only one.
    """
    scope = {**request.scope, "type": "http"}
    methods: set[str] = set()
    for route in iter_routes(request.app.router.routes):
        match, _ = route.matches(scope)
        if match != Match.NONE:
            methods |= set(getattr(route, "methods", None) or ())
    return sorted(methods)


async def _on_http(request: Request, exc: StarletteHTTPException) -> Response:
    detail = exc.detail if isinstance(exc.detail, str) else str(exc.detail)
    if exc.status_code in _HTTP_DETAILS and detail in ("Not Found", "Method Not Allowed",
                                                       "There was an error parsing the body"):
        detail = _HTTP_DETAILS[exc.status_code]
    headers = dict(getattr(exc, "headers", None) or {})
    if exc.status_code == 405:
        allow = allowed_methods(request)
        if allow:
            headers["Allow"] = ", ".join(allow)
            if detail == _HTTP_DETAILS[405]:
                detail = (f"{request.method} is not accepted at {request.url.path}, which accepts {', '.join(allow)}; "
                          "see /docs")
    return problem_response(request, exc.status_code, detail, headers=headers or None)


def install_error_handlers(app: FastAPI) -> None:
    """Register the problem handlers on ``app`` (the 500 one lives in the middleware)."""
    app.add_exception_handler(RequestValidationError, _on_validation)
    app.add_exception_handler(InputError, _on_input)
    app.add_exception_handler(BudgetExceeded, _on_budget)
    app.add_exception_handler(NotFoundError, _on_not_found)
    app.add_exception_handler(StoreError, _on_store)
    app.add_exception_handler(DamagedError, _on_damaged)
    app.add_exception_handler(ConflictError, _on_conflict)
    app.add_exception_handler(TimeLimitExceeded, _on_time_limit)
    app.add_exception_handler(ProblemError, _on_problem)
    app.add_exception_handler(StarletteHTTPException, _on_http)

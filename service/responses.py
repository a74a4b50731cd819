"""Fast JSON responses (orjson, numpy arrays as lists) and the documented error responses."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import orjson
from starlette.responses import Response

from rcsa.app import budget

from .errors import PROBLEM_MEDIA_TYPE

__all__ = ["ASYNC_ACCEPTED", "body_limit", "json_response", "problems"]

#: OpenAPI ``responses`` entry of a computation that may run as a job.
ASYNC_ACCEPTED: dict[int | str, dict[str, Any]] = {
    202: {"description": "Prefer: respond-async: queued as a job (Location: /v1/jobs/{id}); its result is this "
                         "endpoint's 200 body.", "content": {"application/json": {"schema": {
                             "$ref": "#/components/schemas/JobStatus"}}}}}


def body_limit(operation: str, extra: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """``openapi_extra`` stating the route's largest body (``x-max-body-bytes``), which
    :class:`service.routing.ServiceRoute` enforces (413 above)."""
    return {**(extra or {}), "x-max-body-bytes": budget.body_limit(operation)}

_OPTIONS = orjson.OPT_SERIALIZE_NUMPY


def json_response(document: Any, status_code: int = 200, headers: Mapping[str, str] | None = None) -> Response:
    """``application/json`` built by orjson (numpy arrays must be C-contiguous)."""
    return Response(orjson.dumps(document, option=_OPTIONS), status_code=status_code,
                    media_type="application/json", headers=dict(headers or {}))


_DESCRIPTIONS = {
    400: "Malformed request (e.g. a broken multipart body).",
    401: "No API key, or an unknown or revoked one, where one is needed.",
    403: "The API key's scope does not allow this (writes need scope write).",
    404: "No such resource.",
    409: "Conflict with the stored state: the job has not succeeded (still running, or failed), or the stored "
         "object is damaged (its id and the reason are given; retrying does not help).",
    413: "The request body (above the endpoint's x-max-body-bytes) or an uploaded file is too large.",
    410: "The job's result was deleted (disk budget of kept results); submit the job again.",
    429: "Too many unfinished jobs for this caller; retry after Retry-After.",
    415: "Unsupported Content-Type.",
    422: "Invalid input (errors[] names each offending field), or more work than allowed: type "
         "urn:rcsa:problem:compute-budget-exceeded with budget.cost (estimated seconds and memory, and their terms), "
         "budget.limit and how to shrink the request or run it as a job (Prefer: respond-async).",
    501: "Not available in this version of rcsa.",
    503: "The store is unavailable (retry later).",
}


def problems(*codes: int) -> dict[int | str, dict[str, Any]]:
    """OpenAPI ``responses`` entries for problem documents with these status codes."""
    return {code: {"description": _DESCRIPTIONS.get(code, "Problem."),
                   "content": {PROBLEM_MEDIA_TYPE: {"schema": {"$ref": "#/components/schemas/Problem"}}}}
            for code in sorted({400, 422, *codes, 503})}

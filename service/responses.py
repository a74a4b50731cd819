"""Fast JSON responses (orjson, numpy arrays as lists) and the documented error responses."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import orjson
from starlette.responses import Response

from .errors import PROBLEM_MEDIA_TYPE

__all__ = ["json_response", "problems"]

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
    409: "The job has not succeeded (still running, or failed).",
    410: "The job's result was deleted (disk budget of kept results); submit the job again.",
    429: "Too many unfinished jobs for this caller; retry after Retry-After.",
    413: "The request body or an uploaded file is too large.",
    415: "Unsupported Content-Type.",
    422: "Invalid input; errors[] names each offending field.",
    501: "Not available in this version of rcsa.",
    503: "The store is unavailable (retry later).",
}


def problems(*codes: int) -> dict[int | str, dict[str, Any]]:
    """OpenAPI ``responses`` entries for problem documents with these status codes."""
    return {code: {"description": _DESCRIPTIONS.get(code, "Problem."),
                   "content": {PROBLEM_MEDIA_TYPE: {"schema": {"$ref": "#/components/schemas/Problem"}}}}
            for code in sorted({400, 422, *codes, 503})}

"""JSON responses written straight from arrays (rcsa.app.results.json_bytes) and the documented error responses."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from starlette.responses import Response

from rcsa.app import budget
from rcsa.app.results import MEDIA_TYPES, Format, encode_result, json_bytes, missing_extra

from .errors import PROBLEM_MEDIA_TYPE, ProblemError

__all__ = ["ACCEPTED_HEADERS", "ASYNC_ACCEPTED", "RESULT_FORMS", "accepted_entry", "RESULT_MEDIA", "body_limit", "json_response", "negotiate", "problems",
           "result_form", "result_response"]

#: Media types of the forms a batch or library result may take (``Accept``), JSON first.
RESULT_MEDIA: tuple[str, ...] = tuple(MEDIA_TYPES.values())
#: The form of each result media type.
RESULT_FORMS: dict[str, Format] = {media: fmt for fmt, media in MEDIA_TYPES.items()}

#: OpenAPI ``headers`` of a ``202 Accepted`` (a job was queued).
ACCEPTED_HEADERS: dict[str, Any] = {
    "Location": {"description": "The job: /v1/jobs/{id}.", "schema": {"type": "string"}},
    "Retry-After": {"description": "Seconds before polling it.", "schema": {"type": "integer"}},
    "X-Job-Token": {"description": "Anonymous callers only: the job token; send it in X-Job-Token to read the job "
                                   "(GET /v1/jobs/{id}, its result, GET /v1/jobs). Jobs of a key are the key's.",
                    "schema": {"type": "string"}}}


def accepted_entry(description: str) -> dict[int | str, dict[str, Any]]:
    """OpenAPI ``responses`` entry of a ``202`` that queued a job (body: JobStatus)."""
    return {202: {"description": description, "headers": ACCEPTED_HEADERS, "content": {"application/json": {
        "schema": {"$ref": "#/components/schemas/JobStatus"}}}}}


#: OpenAPI ``responses`` entry of a computation that may run as a job.
ASYNC_ACCEPTED = accepted_entry("Prefer: respond-async: queued as a job (Location: /v1/jobs/{id}); its result is "
                                "this endpoint's 200 body.")


def body_limit(operation: str, extra: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """``openapi_extra`` stating the route's largest body (``x-max-body-bytes``), which
    :class:`service.routing.ServiceRoute` enforces (413 above)."""
    return {**(extra or {}), "x-max-body-bytes": budget.body_limit(operation)}


def json_response(document: Any, status_code: int = 200, headers: Mapping[str, str] | None = None) -> Response:
    """``application/json`` written straight from the document's arrays (:func:`rcsa.app.results.json_bytes`)."""
    return Response(json_bytes(document), status_code=status_code, media_type="application/json",
                    headers=dict(headers or {}))


def negotiate(accept: str | None, offered: tuple[str, ...], what: str = "results") -> str:
    """The best of ``offered`` for an Accept header (the first when it says nothing); 406 when none."""
    if not accept or not accept.strip():
        return offered[0]
    q: dict[str, float] = {}
    for part in accept.split(","):
        media, *params = [p.strip().lower() for p in part.split(";")]
        weight = 1.0
        for p in params:
            if p.startswith("q="):
                try:
                    weight = float(p[2:])
                except ValueError:
                    weight = 0.0
        q[media] = max(q.get(media, 0.0), weight)
    wildcard = max(q.get("*/*", 0.0), q.get("application/*", 0.0))
    ranked = [(q.get(m, wildcard), -i, m) for i, m in enumerate(offered)]
    best = max(ranked)
    if best[0] <= 0:
        raise ProblemError(406, f"{what} are available as {' or '.join(offered)}; the Accept header {accept!r} "
                                "allows none of them")
    return best[2]


def result_form(accept: str | None, what: str = "batch and library results") -> Format:
    """The result form (JSON, HDF5, Parquet) an Accept header asks for; 406 when the server lacks its extra."""
    fmt = RESULT_FORMS[negotiate(accept, RESULT_MEDIA, what)]
    missing = missing_extra(fmt)
    if missing is None:
        return fmt
    available = tuple(m for m in RESULT_MEDIA if missing_extra(RESULT_FORMS[m]) is None)
    try:  # the next best form the client accepts
        return RESULT_FORMS[negotiate(accept, available, what)]
    except ProblemError:
        raise ProblemError(406, f"{MEDIA_TYPES[fmt]} is not available on this server: {missing}; ask for "
                                f"{' or '.join(available)}") from None


def result_response(document: Any, fmt: Format, kind: str, headers: Mapping[str, str] | None = None) -> Response:
    """A batch or library result in the form asked for (:func:`rcsa.app.results.encode_result`)."""
    if fmt == "json":
        return json_response(document, headers=headers)
    return Response(encode_result(document, fmt, kind), media_type=MEDIA_TYPES[fmt], headers=dict(headers or {}))


_DESCRIPTIONS = {
    400: "Malformed request (e.g. a broken multipart body).",
    401: "No API key, or an unknown or revoked one, where one is needed.",
    403: "The API key's scope does not allow this (writes need scope write).",
    404: "No such resource.",
    406: "The Accept header asks for no form this endpoint gives (or for Parquet on a server without pyarrow, "
         "the extra rcsa[parquet]).",
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

"""What the OpenAPI document says beyond what FastAPI derives from the routes.

* **Who may call an operation.** FastAPI marks every operation that reads ``X-API-Key``
  as requiring it (``security: [{"APIKey": []}]``). Reads and computations are open to
  anonymous callers while ``RCSA_ANONYMOUS_READ`` is true (:mod:`service.security`): those
  operations are declared ``security: [{}, {"APIKey": []}]`` (no key, or a key), so that
  generated clients do not insist on one. Writes keep the key as required.
* **Operation ids** a client generator turns into good names: the route function's name in
  lower camel case (``predict_tool_point`` → ``predictToolPoint``, ``list_measurements`` →
  ``listMeasurements``; :func:`operation_id`).
* **Which operations need a write key**: the description lists them, from the routes
  themselves (:func:`write_operations`), so the text never goes stale.
* **The job token.** Every operation that may answer ``202`` (it queues a job) takes the
  anonymous caller's ``X-Job-Token`` header (:mod:`service.jobs`), as the job routes do.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from fastapi.routing import APIRoute

from .errors import iter_routes
from .security import access_of

__all__ = ["OPTIONAL_KEY", "document_job_token", "mark_anonymous_operations", "operation_id", "route_access",
           "write_operations"]

#: ``security`` of an operation that anonymous callers may use: no key, or a key.
OPTIONAL_KEY: list[dict[str, list[str]]] = [{}, {"APIKey": []}]


def route_access(route: APIRoute) -> str | None:
    """``"write"``, ``"read"`` or None: the route's access (:func:`service.security.access_of`)."""
    return access_of(route.dependant)


def mark_anonymous_operations(doc: dict[str, Any], routes: Iterable[Any], anonymous_read: bool) -> None:
    """Declare the key optional on the operations anonymous callers may use (in place)."""
    if not anonymous_read:
        return
    paths = doc.get("paths", {})
    for route in iter_routes(routes):
        if not isinstance(route, APIRoute) or not route.include_in_schema or route_access(route) != "read":
            continue
        for method in route.methods:
            operation = paths.get(route.path_format, {}).get(method.lower())
            if operation is not None and "security" in operation:
                operation["security"] = [dict(s) for s in OPTIONAL_KEY]


def document_job_token(doc: dict[str, Any]) -> None:
    """Add the ``X-Job-Token`` header parameter to every operation that may answer ``202`` (in place)."""
    from .jobs import JOB_TOKEN_HEADER

    parameter = {"name": JOB_TOKEN_HEADER, "in": "header", "required": False, "schema": {"type": "string"},
                 "description": "Anonymous callers: a job token of an earlier 202, so that a job started now joins "
                                "it (GET /v1/jobs lists them together); without one, a 202 hands out a new one."}
    for operations in doc.get("paths", {}).values():
        for operation in operations.values():
            if not isinstance(operation, dict) or "202" not in operation.get("responses", {}):
                continue
            params = operation.setdefault("parameters", [])
            if not any(p.get("name", "").lower() == JOB_TOKEN_HEADER.lower() for p in params):
                params.append(parameter)


def operation_id(route: APIRoute) -> str:
    """The OpenAPI ``operationId`` of a route: its function's name in lower camel case.

    >>> from fastapi.routing import APIRoute
    >>> def list_measurements(): ...
    >>> operation_id(APIRoute("/v1/measurements", list_measurements))
    'listMeasurements'
    """
    first, *rest = route.name.split("_")
    return first + "".join(part[:1].upper() + part[1:] for part in rest)


def write_operations(routes: Iterable[Any]) -> list[str]:
    """``"METHOD /path"`` of every operation that needs a write key, in route order."""
    out = []
    for route in iter_routes(routes):
        if isinstance(route, APIRoute) and route.include_in_schema and route_access(route) == "write":
            out += [f"{method} {route.path_format}" for method in sorted(route.methods)]
    return out

"""``POST /v1/tool-libraries:predict``: a whole Fusion tool library on one spindle.

Upload the library (``.json`` or ``.tools``) as multipart with the spindle and the
frequency grid as form fields (JSON text), or send everything as one JSON document. Every
library item gets one result in library order: ``ok`` (its tool-point FRF), ``skipped``
(e.g. no holder, a probe) with the reason, or ``error`` naming the field. Libraries with
more tools than ``RCSA_ASYNC_BATCH_THRESHOLD`` (or ``Prefer: respond-async``) run as a job.
"""

from __future__ import annotations

import json
from typing import Annotated, Any

from fastapi import APIRouter, Header, Request
from fastapi.concurrency import run_in_threadpool
from starlette.responses import Response

from rcsa import library_api
from rcsa.errors import InputError

from ..bodies import form_text, read_body, read_upload, validate_json
from ..deps import StateDep
from ..jobs import accepted, wants_async
from ..responses import json_response, problems
from ..schemas import JobStatus, LibraryPredictionRequest, LibraryResult
from ..security import ReadAccess

router = APIRouter(prefix="/v1", tags=["tool libraries"])

_JSON_FIELDS = ("spindle", "frequency", "joints", "materials", "options", "shear_coefficient")
_FORM_FIELDS = {
    "library": "The Fusion tool library: .json, or .tools (zip holding tools.json).",
    "spindle": 'JSON: the spindle, {"segments": [...], "bearings": [...]} or {"measurement_id": "m-..."}.',
    "measurement_id": "Instead of spindle: a stored measurement's id (hybrid).",
    "frequency": 'JSON: {"start_hz", "stop_hz", "step_hz"} or {"values_hz": [...]}, Hz.',
    "joints": 'JSON: {"spindle_holder": {...}, "holder_tool": {...}} applied to every tool (default rigid).',
    "materials": "JSON: materials by name (added to steel and carbide).",
    "beam_theory": "timoshenko | euler_bernoulli.",
    "shear_coefficient": "hutchinson | cowper | a number.",
    "natural_frequencies": "true | false: compute exact natural frequencies (default true).",
    "options": "JSON: holder_material, tool_material_default, holder_segments_per_cone, fluted_diameter_ratio, "
               "shaft_origin, default_holder.",
}
_BODY = {"requestBody": {"required": True, "content": {
    "multipart/form-data": {"schema": {
        "type": "object", "required": ["library", "frequency"],
        "properties": {name: ({"type": "string", "format": "binary", "description": text} if name == "library"
                              else {"type": "string", "description": text}) for name, text in _FORM_FIELDS.items()},
        "additionalProperties": False}},
    "application/json": {"schema": {"$ref": "#/components/schemas/LibraryPredictionRequest"}}}}}


@router.post("/tool-libraries:predict", response_model=LibraryResult, openapi_extra=_BODY, responses={
    202: {"model": JobStatus, "description": "Queued as a job; poll Location."},
    **problems(400, 401, 413, 415, 422)}, summary="Tool-point FRFs of a Fusion tool library")
async def predict_library(request: Request, state: StateDep, _: ReadAccess,
                          prefer: Annotated[str | None, Header(description="respond-async: always a job.")] = None,
                          ) -> Response:
    """One tool-point FRF per library tool that has a holder; the others skipped with a reason."""
    kind, body = await read_body(request)
    try:
        if kind == "json":
            doc = validate_json(LibraryPredictionRequest, body).model_dump(exclude_unset=True)
            library = doc.pop("library")
        else:
            library, doc = await _from_form(body, state.settings.max_upload_bytes)
    finally:
        if kind == "form":
            await body.close()
    s = state.settings
    plan = await run_in_threadpool(lambda: library_api.library_request(library, **doc))
    n = len(plan["batch"]["combinations"])
    if n > s.max_batch_combinations:
        raise InputError("library", f"has {n} tools to predict; at most {s.max_batch_combinations} per request")
    await run_in_threadpool(lambda: library_api.check_common(plan["batch"], store=state.reader,
                                                             max_lines=s.max_frequency_lines))
    asked = wants_async(prefer)
    if n and (asked or n > s.async_batch_threshold):
        return accepted(state, state.jobs.submit("library", plan), preference_applied=asked)

    def run() -> dict[str, Any]:
        with state.metrics.timed("library"):
            return library_api.run_library_request(plan, store=state.reader, max_lines=s.max_frequency_lines,
                                                   max_combinations=s.max_batch_combinations, arrays="numpy")

    out = await run_in_threadpool(run)
    state.metrics.frfs.labels("library").inc(out["summary"]["ok"])
    return json_response(out)


async def _from_form(form: Any, limit_bytes: int) -> tuple[bytes, dict[str, Any]]:
    unknown = sorted(set(form.keys()) - set(_FORM_FIELDS))
    if unknown:
        raise InputError(unknown[0], f"unknown form field (allowed: {', '.join(_FORM_FIELDS)})")
    files = form.getlist("library")
    if len(files) != 1:
        raise InputError("library", "send exactly one library file (.json or .tools)")
    data, _ = await read_upload(files[0], "library", limit_bytes)
    doc: dict[str, Any] = {}
    for name in _FORM_FIELDS:
        text = form_text(form, name) if name != "library" else None
        if text is None or text == "":
            continue
        if name in _JSON_FIELDS:
            try:
                doc[name] = json.loads(text)
            except ValueError as exc:
                if name == "shear_coefficient":
                    doc[name] = text
                    continue
                raise InputError(name, f"must be JSON ({exc})") from None
        elif name == "natural_frequencies":
            if text.lower() not in ("true", "false"):
                raise InputError(name, "must be true or false")
            doc[name] = text.lower() == "true"
        else:
            doc[name] = text
    measurement_id = doc.pop("measurement_id", None)
    if measurement_id is not None:
        if "spindle" in doc:
            raise InputError("measurement_id", "give either spindle or measurement_id, not both")
        doc["spindle"] = {"measurement_id": measurement_id}
    for required in ("spindle", "frequency"):
        if required not in doc:
            raise InputError(required, "is required" + (" (or measurement_id)" if required == "spindle" else ""))
    return data, doc

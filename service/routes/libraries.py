"""Whole CAM tool libraries (Fusion, FreeCAD) on one spindle: predicted once, or kept and synced.

``POST /v1/tool-libraries:predict``: upload the library as multipart with the spindle and the
frequency grid as form fields (JSON text), or send everything as one JSON document. The
library is a Fusion ``.json``/``.tools``, or FreeCAD toolbits: a ``.fctb``, or a zip of
``.fctb`` files (with their ``.fctl`` and ``.fcholder``), the holder also as the ``holder``
file field, and ``options.stickout_m`` (FreeCAD stores none). The format follows the file
name and the part's Content-Type, checked against the content
(:mod:`rcsa.libraries.formats`); the JSON form takes a Fusion document or
``{"format": "freecad", "toolbits": {...}, "holder": {...}}``. Every library item gets one result in library order:
``ok`` (its tool-point FRF), ``skipped`` (e.g. no holder, a probe) with the reason, or
``error`` naming the field. Libraries with more tools than ``RCSA_ASYNC_BATCH_THRESHOLD`` (or
``Prefer: respond-async``) run as a job.

Stored libraries (:mod:`rcsa.libraries.sync`; writes need a write key, reads follow the read
policy):

* ``POST /v1/libraries/{library_id}:sync`` — the same body as ``:predict``. Computes only
  the tools whose result is not stored yet (content hash of the combination, the spindle
  measurement's content, the grid and the model version) and answers the sync report
  (``added``, ``changed``, ``unchanged``, ``removed`` tool ids against the previous sync).
  More tools to compute than ``RCSA_ASYNC_BATCH_THRESHOLD`` (or ``Prefer: respond-async``):
  a ``library-sync`` job (``202``), whose result is the report. ``Idempotency-Key`` makes
  retries safe; a job interrupted by a dead worker is resumed and takes the tools computed
  before the interruption from the cache.
* ``POST /v1/libraries/{library_id}:recommend`` — chatter-safe presets: multipart with the Fusion
  library (``.json``/``.tools``) as the file field ``library`` and the options (``material``,
  ``max_rpm``, ...) as text fields. From the stored results of this library's last sync, each
  milling tool's best stable pocket is written into the file as a preset. ``Accept:
  application/json`` (default): the report, with the updated file in it (``file.content_base64``);
  ``Accept: application/octet-stream`` (or ``?format=file``): the updated file itself, as a
  download. Write key.
* ``GET /v1/libraries`` · ``GET /v1/libraries/{library_id}`` (summary, per-tool status) ·
  ``GET /v1/libraries/{library_id}/results`` (``Accept: application/json`` — the shape of a
  library prediction —, ``application/x-hdf5`` or ``application/zip`` — one UFF 58 file per
  tool) · ``DELETE /v1/libraries/{library_id}``.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Header, Path, Query, Request
from fastapi.concurrency import run_in_threadpool
from starlette.responses import Response

from rcsa.app.inputs import decode_json
from rcsa.app.libraries import (
    LIBRARY_ID_PATTERN,
    export_file,
    library_tool_result,
    list_stored_libraries,
    prepare_library,
    prepare_sync,
)
from rcsa.app.presets import (
    OPTION_FIELDS,
    RECOMMEND_JOB,
    recommend_job_request,
    recommend_stored,
    report_document,
    synced_library_file,
)
from rcsa.errors import InputError

from ..bodies import check_form_fields, form_json, form_text, form_uploads, read_body, validate_json
from ..deps import StateDep
from ..idempotency import IDEMPOTENCY_PROBLEMS, IdempotencyKeyHeader, IdempotentRoute
from ..jobs import answer, caller, submit, wants_async
from ..responses import accepted_entry, body_limit, json_response, negotiate, problems, result_form
from ..schemas import (
    Deleted,
    LibraryPage,
    LibraryPredictionRequest,
    LibraryResult,
    LibraryResultItem,
    LibrarySummary,
    RecommendReport,
    SyncReport,
)
from ..security import ReadAccess, WriteAccess
from ..state import AppState
from .batches import BINARY_RESULT, ResultAccept

router = APIRouter(prefix="/v1", tags=["tool libraries"], route_class=IdempotentRoute)

_JSON_FIELDS = ("spindle", "frequency", "joints", "materials", "options", "shear_coefficient", "uncertainty")
_FORM_FIELDS = {
    "library": "The tool library: Fusion .json or .tools (zip holding tools.json); FreeCAD .fctb, or a zip of "
               ".fctb files (with their .fctl and .fcholder).",
    "holder": "FreeCAD only: the holder (.fcholder) of the toolbits, when the library has none.",
    "spindle": 'JSON: the spindle, {"segments": [...], "bearings": [...]} or {"measurement_id": "m-..."}.',
    "measurement_id": "Instead of spindle: a stored measurement's id (hybrid).",
    "frequency": 'JSON: {"start_hz", "stop_hz", "step_hz"} or {"values_hz": [...]}, Hz.',
    "joints": 'JSON: {"spindle_holder": {...}, "holder_tool": {...}} applied to every tool (default rigid).',
    "holder_tool": 'Every tool\'s holder-tool clamping, replacing the joints\' own: bonded, point, or JSON '
                   '{"model": "contact", "interface_stiffness_n_m3": 5e13}.',
    "materials": "JSON: materials by name (added to steel and carbide).",
    "beam_theory": "timoshenko | euler_bernoulli.",
    "shear_coefficient": "hutchinson | cowper | a number.",
    "natural_frequencies": "true | false: compute exact natural frequencies (default true).",
    "options": "JSON: holder_material, tool_material_default, holder_segments_per_cone, fluted_diameter_ratio; "
               "Fusion: shaft_origin, default_holder; FreeCAD: stickout_m (required; m, or {toolbit id: m}).",
    "uncertainty": 'JSON: every tool\'s uncertainty band, e.g. {"draws": 200, "seed": 1} (p05/p50/p95 of |h|; '
                   "the prediction's uncertainty option).",
}
_BODY = {"requestBody": {"required": True, "content": {
    "multipart/form-data": {"schema": {
        "type": "object", "required": ["library", "frequency"],
        "properties": {name: ({"type": "string", "format": "binary", "description": text}
                              if name in ("library", "holder")
                              else {"type": "string", "description": text}) for name, text in _FORM_FIELDS.items()},
        "additionalProperties": False}},
    "application/json": {"schema": {"$ref": "#/components/schemas/LibraryPredictionRequest"}}}}}


PreferHeader = Annotated[str | None, Header(description="respond-async: always a job.")]


async def _library_inputs(request: Request, state: AppState) -> tuple[dict[str, Any], dict[str, Any]]:
    """The library and what the upload says it is (:func:`rcsa.app.libraries.prepare_library`'s
    ``library``, ``file_name``, ``content_type``, ``holder``, ``holder_name``), and the other fields."""
    kind, body = await read_body(request)
    try:
        if kind == "json":  # validated in a worker thread: a library may be large
            doc = (await run_in_threadpool(validate_json, LibraryPredictionRequest, body)).model_dump(
                exclude_unset=True)
            return {"library": doc.pop("library")}, doc
        return await _from_form(body, state.settings.max_upload_bytes)
    finally:
        if kind == "form":
            await body.close()


@router.post("/tool-libraries:predict", response_model=LibraryResult, openapi_extra=body_limit("library", _BODY), responses={
    200: {"description": "The results (LibraryResult), or the same as HDF5 or Parquet (Accept).",
          "content": BINARY_RESULT},
    **accepted_entry("Queued as a job; poll Location."),
    **problems(400, 401, 406, 413, 415, 422, 429), **IDEMPOTENCY_PROBLEMS},
    summary="Tool-point FRFs of a Fusion tool library")
async def predict_library(request: Request, state: StateDep, who: ReadAccess, prefer: PreferHeader = None,
                          idempotency_key: IdempotencyKeyHeader = None, accept: ResultAccept = None) -> Response:
    """One tool-point FRF per library tool that has a holder; the others skipped with a reason."""
    fmt = result_form(accept)
    source, doc = await _library_inputs(request, state)
    work = await run_in_threadpool(lambda: prepare_library(state.bench, **source, result_format=fmt, **doc))
    return await run_in_threadpool(lambda: answer(state, work, prefer=prefer, idempotency_key=idempotency_key,
                                                  owner=caller(who, request), result_format=fmt))


async def library_upload(form: Any, limit_bytes: int, *, holder: bool = True) -> dict[str, Any]:
    """The library file of an upload form (and, with ``holder``, a FreeCAD holder file):
    :func:`rcsa.app.libraries.prepare_library`'s ``library``, ``file_name``, ``content_type``,
    ``holder`` and ``holder_name`` (also read by the web view's ``POST /v1/tool-libraries:entries``)."""
    [(data, name, media)] = await form_uploads(form, "library", limit_bytes,
                                               what="library file (.json, .tools, .fctb or a zip)")
    source: dict[str, Any] = {"library": data, "file_name": name or None, "content_type": media}
    if holder:
        holders = await form_uploads(form, "holder", limit_bytes, least=0, most=1, what="holder file (.fcholder)")
        if holders:
            source["holder"], holder_name, _ = holders[0]
            source["holder_name"] = holder_name or None
    return source


async def _from_form(form: Any, limit_bytes: int) -> tuple[dict[str, Any], dict[str, Any]]:
    check_form_fields(form, _FORM_FIELDS)
    source = await library_upload(form, limit_bytes)
    doc: dict[str, Any] = {}
    for name in _FORM_FIELDS:
        text = form_text(form, name) if name not in ("library", "holder") else None
        if text is None or text == "":
            continue
        if name == "holder_tool":
            doc[name] = decode_json(text, path=name, what="form field holder_tool") if text.lstrip().startswith("{") \
                else text
        elif name in _JSON_FIELDS:
            try:
                doc[name] = decode_json(text, path=name, what=f"form field {name}")
            except InputError:
                if name == "shear_coefficient":
                    doc[name] = text
                    continue
                raise
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
    return source, doc


# --------------------------------------------------------------------------- stored libraries

LibraryId = Annotated[str, Path(pattern=LIBRARY_ID_PATTERN.pattern, description=(
    "Your name for the library (1-128 letters, digits, '.', '_', '-'), e.g. the CAM library's name; each sync "
    "is compared with the previous sync under the same id."), examples=["bt40-mills"])]
HDF5, ZIP, JSON, PARQUET = "application/x-hdf5", "application/zip", "application/json", "application/vnd.apache.parquet"


@router.post("/libraries/{library_id}:sync", response_model=SyncReport, openapi_extra=body_limit("library", _BODY), responses={
    201: {"model": SyncReport, "description": "The library did not exist: created by this first sync (Location: "
                                              "/v1/libraries/{library_id}).",
          "headers": {"Location": {"description": "The library.", "schema": {"type": "string"}}}},
    **accepted_entry("Queued as a library-sync job; poll Location (its result is the sync report)."),
    **problems(400, 401, 403, 413, 415, 422, 429), **IDEMPOTENCY_PROBLEMS},
    summary="Sync a stored library with a new export (write key)")
async def sync_library(library_id: LibraryId, request: Request, state: StateDep, who: WriteAccess,
                       prefer: PreferHeader = None, idempotency_key: IdempotencyKeyHeader = None) -> Response:
    """Bring the stored library ``library_id`` up to date with this export of the tool library.

    The body is that of ``POST /v1/tool-libraries:predict`` (multipart or JSON). Only tools
    whose result is not stored yet are computed; the report lists the tool ids ``added``,
    ``changed``, ``unchanged`` and ``removed`` since the previous sync of this id. The first sync
    of an id creates the library: ``201`` with ``Location``; later ones ``200``. Send an
    ``Idempotency-Key`` from automated (retrying) callers.
    """
    source, doc = await _library_inputs(request, state)
    work = await run_in_threadpool(lambda: prepare_sync(state.bench, library_id, **source, **doc))
    return await run_in_threadpool(lambda: answer(state, work, prefer=prefer, idempotency_key=idempotency_key,
                                                  headers={"Location": f"/v1/libraries/{library_id}"},
                                                  owner=caller(who, request)))


@router.get("/libraries", response_model=LibraryPage, responses=problems(401, 422), summary="List stored libraries")
def list_libraries(
    state: StateDep, _: ReadAccess,
    limit: Annotated[int, Query(ge=1, le=1000, description="Items per page.")] = 100,
    cursor: Annotated[str | None, Query(max_length=1000, description="next_cursor of the previous page.")] = None,
) -> Response:
    """The stored libraries by id, a page at a time (``limit`` + ``cursor``, as the measurements
    and jobs): settings, grid, counts and last sync report (no per-tool list)."""
    return json_response(list_stored_libraries(state.bench, limit=limit, cursor=cursor))


@router.get("/libraries/{library_id}", response_model=LibrarySummary, responses=problems(401, 404),
            summary="A stored library and the status of each tool")
def get_library(library_id: LibraryId, state: StateDep, _: ReadAccess) -> Response:
    """Summary of a stored library with every tool's status and result key (no arrays)."""
    return json_response(state.bench.libraries.get(library_id))


ToolId = Annotated[str, Path(min_length=1, max_length=300, description=(
    "A tool's id in the library (the Fusion guid; FreeCAD: <toolbit>@<holder>), as GET /v1/libraries/{library_id} "
    "lists them."), examples=["00000000-0000-4000-8000-000000000101"])]


@router.get("/libraries/{library_id}/tools/{tool_id}", response_model=LibraryResultItem,
            responses=problems(401, 404, 422), summary="One tool's result from a stored library")
def get_library_tool(
    library_id: LibraryId, tool_id: ToolId, state: StateDep, _: ReadAccess,
    tool_point: Annotated[str | None, Query(pattern=r"^[hlnp](,[hlnp]){0,3}$", description=(
        "Receptances to return in tool_point, e.g. h; default h,l,n,p."))] = None,
) -> Response:
    """The stored result of one tool of the library's last sync — its tool-point FRF (``ok``), why it
    was skipped, or its error — without fetching the whole library's results."""
    return json_response(library_tool_result(state.bench, library_id, tool_id,
                                             tool_point.split(",") if tool_point else None))


@router.get("/libraries/{library_id}/results", response_model=LibraryResult, responses={
    200: {"description": "application/json: the shape of a library prediction (one result per item, in library "
                         "order). application/x-hdf5: frequency_hz and each ok tool's complex h, l, n, p (schema "
                         "rcsa.library-results). application/vnd.apache.parquet: one row per ok tool and line "
                         "(needs the extra rcsa[parquet] on the server). application/zip: index.json and one UFF 58 "
                         "file (with a dataset 164, SI) of the tool-point h per ok tool.",
          "content": {HDF5: {"schema": {"type": "string", "format": "binary"}},
                      PARQUET: {"schema": {"type": "string", "format": "binary"}},
                      ZIP: {"schema": {"type": "string", "format": "binary"}}}},
    **problems(401, 404, 406)}, summary="Results of a stored library (JSON, HDF5, Parquet or zip of UFF 58)")
def get_library_results(
    library_id: LibraryId, state: StateDep, _: ReadAccess,
    accept: Annotated[str | None, Header(description="application/json (default), application/x-hdf5, "
                                                     "application/vnd.apache.parquet or application/zip.")] = None,
    format: Annotated[Literal["json", "hdf5", "zip", "parquet"] | None, Query(
        description="Instead of Accept (e.g. for a browser link).")] = None,
    tool_point: Annotated[str | None, Query(pattern=r"^[hlnp](,[hlnp]){0,3}$", description=(
        "JSON only: receptances to return in each result's tool_point, e.g. h; default h,l,n,p."))] = None,
) -> Response:
    """Every tool's stored result, fetched again by library id."""
    media = {"json": JSON, "hdf5": HDF5, "zip": ZIP, "parquet": PARQUET}[format] if format else \
        negotiate(accept, (JSON, HDF5, ZIP, PARQUET))
    if media == JSON:
        return json_response(state.bench.libraries.results(library_id, tool_point.split(",") if tool_point else None))
    if media == PARQUET:
        result_form(PARQUET)  # 406 naming the extra when pyarrow is missing
    export = export_file(state.bench.libraries, library_id, {HDF5: "hdf5", ZIP: "zip", PARQUET: "parquet"}[media])
    return Response(export.data, media_type=media,
                    headers={"Content-Disposition": f'attachment; filename="{export.file_name}"'})


@router.delete("/libraries/{library_id}", response_model=Deleted, responses=problems(401, 403, 404),
               summary="Forget a stored library (write key)")
def delete_library(library_id: LibraryId, state: StateDep, _: WriteAccess) -> Response:
    """Forget a library and its per-tool status (the shared result cache keeps the results)."""
    return json_response(state.bench.libraries.delete(library_id))


# --------------------------------------------------------------------------- chatter-safe presets

OCTET = "application/octet-stream"
_TEXT_OPTIONS = ("material", "milling", "method")
_RECOMMEND_FIELDS = {
    "library": "The Autodesk Fusion tool library (.json, or .tools: a zip holding tools.json) to write the presets "
               "into; its tools are matched to the stored library by id.",
    "material": "Workpiece material: a table entry (aluminium-7075, aluminium-6082, carbon-steel, alloy-steel, "
                "stainless-steel, cast-iron, titanium-alloy, hardened-steel, or an alias such as 7075) or your own "
                "name with tangential_coefficient_n_m2 and radial_ratio.",
    "max_rpm": "The machine's highest spindle speed, rpm (required).",
    "min_rpm": "The lowest spindle speed to consider, rpm (default 1000).",
    "tangential_coefficient_n_m2": "K_tc of the linear edge-force model, N/m² (with radial_ratio; default: the "
                                   "table's).",
    "radial_ratio": "K_rc / K_tc.",
    "radial_immersion": "Radial depth of cut / diameter, a_e/D (default 0.5).",
    "milling": "down (default) or up.",
    "safety_factor": "Stepdown = the smallest depth limit within the speed window / safety_factor (default 1.25).",
    "speed_tolerance": "Relative half-width of the speed window that must stay stable (default 0.03).",
    "max_surface_speed_m_min": "Surface-speed limit, m/min (default: the table's, for carbide tools).",
    "feed_per_tooth_m": "Feed per tooth for the preset's feeds, m (default: f_z of the tool's own first preset).",
    "method": "Stability-lobe method: auto (default: zoa only where it is exact, even-toothed slotting; else "
              "semi_discretization), zoa or semi_discretization.",
    "uncertainty": "Robust presets: the uncertainty option as JSON ({\"draws\": 200, \"seed\": 1, \"tolerances\": "
                   "{...}}); every tool's assembly is drawn with the stored sync's settings and the pocket chosen on "
                   "the robust depth limit.",
    "confidence": "With uncertainty: the robust limit's confidence (default 0.95).",
}
assert set(_RECOMMEND_FIELDS) - {"library"} == set(OPTION_FIELDS)
_RECOMMEND_BODY = {"requestBody": {"required": True, "content": {
    "application/json": {"schema": {
        "type": "object", "required": ["material", "max_rpm"], "additionalProperties": False,
        "description": "Presets by reference: the options alone; the presets are written into the Fusion file the "
                       "library's last sync kept in the store.",
        "properties": {name: ({"type": "object"} if name == "uncertainty" else {"type": "string"}
                              if name in _TEXT_OPTIONS else {"type": "number"}) | {"description": text}
                       for name, text in _RECOMMEND_FIELDS.items() if name != "library"}}},
    "multipart/form-data": {"schema": {
        "type": "object", "required": ["library", "material", "max_rpm"],
        "properties": {name: ({"type": "string", "format": "binary", "description": text} if name == "library"
                              else {"type": "string", "description": text})
                       for name, text in _RECOMMEND_FIELDS.items()},
        "additionalProperties": False}}}}}


async def _recommend_inputs(request: Request, state: AppState, library_id: str
                            ) -> tuple[bytes, str | None, str | None, dict[str, Any]]:
    """The library file and the options: from a form, or (JSON) the options alone and the file the
    library's last sync kept (presets by reference)."""
    kind, form = await read_body(request)
    if kind == "json":
        if not isinstance(form, dict):
            raise InputError("", "send the options as a JSON object (material, max_rpm, ...)")
        unknown = sorted(set(form) - set(OPTION_FIELDS))
        if unknown:
            raise InputError(unknown[0], f"unknown option (allowed: {', '.join(OPTION_FIELDS)})")
        data, name, content_type = await run_in_threadpool(synced_library_file, state.bench, library_id)
        return data, name, content_type, dict(form)
    limit_bytes = state.settings.max_upload_bytes
    try:
        check_form_fields(form, _RECOMMEND_FIELDS)
        source = await library_upload(form, limit_bytes, holder=False)
        options: dict[str, Any] = {}
        for field in OPTION_FIELDS:
            text = form_text(form, field)
            if text is None or text.strip() == "":
                continue
            if field in _TEXT_OPTIONS:
                options[field] = text.strip()
                continue
            if field == "uncertainty":
                options[field] = form_json(form, field)
                continue
            try:
                options[field] = float(text)
            except ValueError:
                raise InputError(field, f"must be a number, got {text!r}") from None
        return source["library"], source["file_name"], source["content_type"], options
    finally:
        await form.close()


@router.post("/libraries/{library_id}:recommend", response_model=RecommendReport,
             openapi_extra=body_limit("library", _RECOMMEND_BODY),
             responses={200: {"description": "application/json: the report, with the updated library in "
                                             "file.content_base64. application/octet-stream: the updated library "
                                             "file (same format and name as uploaded).",
                              "content": {OCTET: {"schema": {"type": "string", "format": "binary"}}}},
                        **accepted_entry("Queued as a library-recommend job; poll Location (its result is the "
                                         "report with the file)."),
                        **problems(400, 401, 403, 404, 406, 413, 415, 422, 429), **IDEMPOTENCY_PROBLEMS},
             summary="Write chatter-safe presets into a Fusion library from a stored library's results (write key)")
async def recommend_presets(
    library_id: LibraryId, request: Request, state: StateDep, who: WriteAccess,
    accept: Annotated[str | None, Header(description="application/json (default: the report with the file in "
                                                     "it) or application/octet-stream (the file).")] = None,
    format: Annotated[Literal["report", "file"] | None, Query(
        description="Instead of Accept: report (JSON) or file (the updated library).")] = None,
    prefer: PreferHeader = None,
    idempotency_key: IdempotencyKeyHeader = None,
) -> Response:
    """Per milling tool, the best stable pocket (speed, stepdown at the safety factor) as a Fusion preset.

    The body is the Fusion library and the options as a form, or — by reference — the options alone
    as JSON: the presets are then written into the Fusion file the library's last sync kept.

    The FRFs are the stored results of this library's last sync; a tool whose geometry changed
    since (or that the sync does not know) is skipped with the reason. The preset is named
    ``rcsa chatter-safe: <material>`` and its guid is fixed by the tool and the material, so that
    sending the returned file again replaces it; nothing else in the file changes.

    A library of more tools than ``RCSA_ASYNC_BATCH_THRESHOLD``, or ``Prefer: respond-async``,
    becomes a job (``202``, ``Location: /v1/jobs/{id}``): its progress counts the tools whose
    pockets are found (in chunks, on the Dask cluster when one is configured), and its result is
    the JSON report with the file.
    """
    media = {"report": JSON, "file": OCTET}[format] if format else negotiate(accept, (JSON, OCTET),
                                                                                "a recommendation's report and file")
    data, name, content_type, options = await _recommend_inputs(request, state, library_id)
    owner = caller(who, request)
    job_request = await run_in_threadpool(lambda: recommend_job_request(library_id, data, options, file_name=name,
                                                                        content_type=content_type))
    asked = wants_async(prefer)
    if asked or job_request["items"] > state.settings.async_batch_threshold:
        return await run_in_threadpool(lambda: submit(state, RECOMMEND_JOB, job_request, owner,
                                                      reuse_unfinished=idempotency_key is not None,
                                                      preference_applied=asked))
    result = await run_in_threadpool(lambda: recommend_stored(state.bench, library_id, data, options,
                                                              file_name=name, content_type=content_type))
    written = result.report["summary"]["written"]
    if media == OCTET:
        return Response(result.data, media_type=OCTET, headers={
            "Content-Disposition": f'attachment; filename="{result.file_name}"', "X-RCSA-Presets-Written": str(written)})
    return json_response(report_document(library_id, result))


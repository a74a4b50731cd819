"""The web view for the shop floor, and the small endpoints it needs.

* ``GET /`` redirects to ``GET /ui/``: one static page (``service/web/index.html`` with
  ``app.js`` and ``app.css``, plain HTML and JavaScript, nothing fetched from elsewhere, so
  it works on a network without internet). It calls the ``/v1`` API like any client: pick a
  stored spindle or RA-1's modelled one, a tool from an uploaded Fusion library or RA-1's,
  predict, read the tool-point FRF and its key numbers, compute stability lobes, download
  CSV and PNG/SVG; and diagnose tap tests of the tool point at a few stickouts against the
  model (``diagnosis.js``: the verdict, the gap map and the corrected FRFs).
* ``GET /v1/examples/ra1`` — the reference assembly RA-1 (the page's defaults).
* ``POST /v1/tool-libraries:entries`` — the entries of a Fusion tool library (``.json`` or
  ``.tools``) mapped to holders and tools, without computing anything.
* ``POST /v1/measurements:read`` — a measurement file (UFF 58, CSV, CutPro, contract JSON,
  raw tap) read into the contract's JSON form with the store's importers, without storing
  it: the page's diagnosis sends tap tests of the tool point on to ``POST /v1/diagnoses``.

The page is served with a Content-Security-Policy that allows only this origin.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from fastapi import APIRouter, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.exceptions import RequestValidationError
from pydantic import BaseModel, ConfigDict, Field, ValidationError
from starlette.responses import FileResponse, RedirectResponse, Response

from rcsa.app import measurements as M
from rcsa.app.libraries import library_entries as read_entries
from rcsa.app.predictions import example_assembly

from ..bodies import check_form_fields, form_json, read_body, validate_json
from ..deps import StateDep
from ..errors import ProblemError
from ..responses import body_limit, json_response, problems
from ..routing import ServiceRoute
from ..schemas import Assembly, ComplexArray, LibraryOptions, MeasurementSource
from ..security import ReadAccess
from .libraries import library_upload
from .measurements import UPLOAD_FIELDS, measurement_form

router = APIRouter(route_class=ServiceRoute)

WEB_DIR = Path(__file__).resolve().parent.parent / "web"
#: The page's files and their media types (nothing else under /ui/ is served).
ASSETS = {"index.html": "text/html; charset=utf-8", "app.js": "text/javascript; charset=utf-8",
          "diagnosis.js": "text/javascript; charset=utf-8", "app.css": "text/css; charset=utf-8"}
CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; "
       "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
_PAGE_HEADERS = {"Cache-Control": "no-cache", "Content-Security-Policy": CSP, "X-Content-Type-Options": "nosniff",
                 "Referrer-Policy": "no-referrer"}


@router.get("/", include_in_schema=False)
def root() -> Response:
    """The web view lives at /ui/."""
    return RedirectResponse("ui/", status_code=307)


@router.get("/ui/", include_in_schema=False)
def page() -> Response:
    """The web view (static HTML)."""
    return _asset("index.html")


@router.get("/ui/{name}", include_in_schema=False)
def asset(name: str) -> Response:
    """The page's script and style sheet."""
    if name not in ASSETS:
        raise ProblemError(404, f"no file {name!r} in the web view; open /ui/")
    return _asset(name)


def _asset(name: str) -> Response:
    return FileResponse(WEB_DIR / name, media_type=ASSETS[name], headers=_PAGE_HEADERS)


# --------------------------------------------------------------------------- examples

@router.get("/v1/examples/ra1", tags=["examples"], response_model=Assembly, responses=problems(401),
            summary="The reference assembly RA-1")
def get_example_ra1(_: ReadAccess) -> Response:
    """RA-1 (a BT40-class spindle on four bearings, a shrink-fit holder, a Ø12.7 mm carbide end
    mill at 74 mm stickout, the seed paper's joints) as an assembly document, SI units, grid
    5–10 000 Hz by 1 Hz. Its first natural frequency is 599.85 Hz."""
    return json_response(example_assembly("ra1"))


# --------------------------------------------------------------------------- library entries

class LibraryEntriesRequest(BaseModel):
    """JSON form of POST /v1/tool-libraries:entries (the multipart form has the same fields)."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)

    library: dict[str, Any] = Field(description='The Fusion tool library document {"data": [...], "version": n}.')
    options: LibraryOptions | None = Field(None, description="How items are mapped (holder material, cones, "
                                                             "fluted diameter ratio, default holder, ...).")


class LibraryEntry(BaseModel):
    """One library item: a holder and tool ready for an assembly (status ok), or why not."""

    model_config = ConfigDict(extra="allow")

    id: str = Field(description="Fusion guid, else T<number>, else a content hash.")
    index: int = Field(description="Position in the library's data list.")
    status: str = Field(description="ok, skipped or error.")
    description: str = Field(description="The item's description.")
    number: int | None = Field(None, description="Fusion T number.")
    teeth: int | None = Field(None, description="Number of flutes NOF (teeth for stability lobes).")
    tool_type: str | None = Field(None, description="Fusion type, e.g. flat end mill.")
    reason: str | None = Field(None, description="Why it was skipped, or field: rule of its error.")
    warnings: list[str] = Field(default_factory=list, description="Approximations noticed on the way.")
    holder: dict[str, Any] | None = Field(None, description="An assembly's holder (segments, m), status ok.")
    tool: dict[str, Any] | None = Field(None, description="An assembly's tool (lengths m), status ok.")


class LibraryEntries(BaseModel):
    """Every item of a library, in library order."""

    model_config = ConfigDict(extra="allow")

    library: dict[str, Any] = Field(description="source, file_name, library_sha256 and summary (counts of ok, "
                                                "skipped, error).")
    entries: list[LibraryEntry]


_ENTRIES_FIELDS = {"library": "The Fusion tool library: .json, or .tools (zip holding tools.json).",
                   "options": "JSON: holder_material, tool_material_default, holder_segments_per_cone, "
                              "fluted_diameter_ratio, shaft_origin, default_holder."}
_ENTRIES_BODY = {"requestBody": {"required": True, "content": {
    "multipart/form-data": {"schema": {
        "type": "object", "required": ["library"],
        "properties": {"library": {"type": "string", "format": "binary", "description": _ENTRIES_FIELDS["library"]},
                       "options": {"type": "string", "description": _ENTRIES_FIELDS["options"]}},
        "additionalProperties": False}},
    "application/json": {"schema": {
        "type": "object", "required": ["library"], "additionalProperties": False,
        "properties": {"library": {"type": "object", "description": "The Fusion tool library document."},
                       "options": LibraryOptions.model_json_schema()}}}}}}


@router.post("/v1/tool-libraries:entries", tags=["tool libraries"], response_model=LibraryEntries,
             openapi_extra=body_limit("library", _ENTRIES_BODY), responses=problems(400, 401, 413, 415, 422),
             summary="List a Fusion tool library's entries (no computation)")
async def read_library_entries(request: Request, state: StateDep, _: ReadAccess) -> Response:
    """Read a Fusion tool library and list every item: its id, description, status (ok,
    skipped with the reason, or error naming the field), T number, teeth (NOF), and for ok
    items the holder and tool in the assembly format (SI metres), ready for
    ``POST /v1/tool-point-frf``. Nothing is computed and nothing is stored."""
    kind, body = await read_body(request)
    file_name = None
    try:
        if kind == "json":
            doc = validate_json(LibraryEntriesRequest, body)
            library: Any = doc.library
            options = doc.options
        else:
            library, file_name, options = await _entries_form(body, state.settings.max_upload_bytes)
    finally:
        if kind == "form":
            await body.close()
    opts = options.model_dump(exclude_none=True) if options is not None else {}
    return json_response(await run_in_threadpool(lambda: read_entries(library, options=opts, file_name=file_name)))


async def _entries_form(form: Any, limit_bytes: int) -> tuple[bytes, str, LibraryOptions | None]:
    """The library upload of ``POST /v1/tool-libraries:predict`` (:func:`.libraries.library_upload`)
    and its ``options`` field, validated by the same schema as the JSON body's."""
    check_form_fields(form, _ENTRIES_FIELDS)
    source = await library_upload(form, limit_bytes, holder=False)
    options = form_json(form, "options")
    if options is None:
        return source["library"], source["file_name"], None
    try:
        return source["library"], source["file_name"], LibraryOptions.model_validate(options)
    except ValidationError as exc:
        raise RequestValidationError([{**e, "loc": ("body", "options", *e["loc"])} for e in exc.errors()]) from None


# --------------------------------------------------------------------------- measurement files, not stored

class MeasurementRead(BaseModel):
    """A measurement file in the contract's JSON form (SI units), not stored."""

    model_config = ConfigDict(extra="allow")

    kind: str = Field(description="direct_frf, point_receptance or artifact_frfs.")
    frequency_hz: list[float] = Field(description="Frequency lines, Hz.")
    h: ComplexArray | None = Field(None, description="Receptance h, m/N (converted from the file's quantity and "
                                                     "units).")
    coherence: list[float] | dict[str, list[float]] | None = Field(None, description="Coherence, when the file "
                                                                                     "has it.")
    units: dict[str, str] = Field(description="Unit of every array.")
    source: MeasurementSource
    summary: dict[str, Any] = Field(description="Peak magnitude and frequency of every FRF.")


#: The form of POST /v1/measurements, field for field (the same reading: :func:`.measurements.measurement_form`);
#: the metadata a stored measurement needs is optional here.
_READ_DEFAULTS = {"spindle_id": "tap-test", "direction": "x, or a UFF file's own", "plane": "spindle_nose",
                  "kind": "direct_frf"}
_READ_FIELDS = {name: (f"{text} Optional here; default {_READ_DEFAULTS[name]}." if name in _READ_DEFAULTS else text)
                for name, text in UPLOAD_FIELDS.items()}
_READ_BODY = {"requestBody": {"required": True, "content": {"multipart/form-data": {"schema": {
    "type": "object", "required": ["file"],
    "properties": {name: ({"type": "string", "format": "binary", "description": text} if name == "file"
                          else {"type": "string", "description": text}) for name, text in _READ_FIELDS.items()},
    "additionalProperties": False}}}}}


@router.post("/v1/measurements:read", tags=["measurements"], response_model=MeasurementRead,
             openapi_extra=body_limit("measurement", _READ_BODY), responses=problems(400, 401, 413, 415, 422),
             summary="Read a measurement file without storing it")
async def read_measurement_file(request: Request, state: StateDep, _: ReadAccess) -> Response:
    """Read a measurement file with the store's importers (UFF 58, CSV/TSV, CutPro ``.frf``,
    contract JSON, raw tap; units never guessed) and answer it in the contract's JSON form,
    SI units, without storing anything: e.g. tap tests of a tool point, sent on inline to
    ``POST /v1/diagnoses`` or ``POST /v1/identifications``. A read key is enough."""
    kind, form = await read_body(request)
    if kind != "form":
        raise ProblemError(415, "send the file as multipart/form-data (field file, and the importer options as "
                                "form fields)")
    try:
        upload = await measurement_form(form, _READ_FIELDS, state.settings.max_upload_bytes)
    finally:
        await form.close()
    return json_response(await run_in_threadpool(lambda: M.read_measurement(upload.data, **upload.reading)))

"""Stored measurements: upload (JSON or file), list, get (JSON or HDF5), delete."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Header, Path, Query, Request
from fastapi.concurrency import run_in_threadpool
from starlette.responses import Response

from rcsa.app import measurements as M
from rcsa.errors import InputError

from ..bodies import check_form_fields, form_text, form_uploads, read_body, validate_json
from ..deps import StateDep
from ..errors import ProblemError
from ..idempotency import IDEMPOTENCY_PROBLEMS, IdempotencyKeyHeader, IdempotentRoute, reservation
from ..responses import body_limit, json_response, problems
from ..schemas import (
    Deleted,
    MeasurementDocument,
    MeasurementInfo,
    MeasurementPage,
    MeasurementUpload,
)
from ..security import ReadAccess, WriteAccess
from ..state import AppState

router = APIRouter(prefix="/v1/measurements", tags=["measurements"], route_class=IdempotentRoute)

MeasurementId = Annotated[str, Path(description="Measurement id.", examples=["m-0123456789ab"])]
HDF5 = "application/x-hdf5"

#: The fields of a measurement upload form (also those of ``POST /v1/measurements:read``).
UPLOAD_FIELDS = {
    "file": "The measurement file (repeat for several taps of format tap).",
    "format": "uff | csv | frf | json | tap (default: from the file name: .uff/.unv, .csv/.tsv, .frf, .json).",
    "spindle_id": "Spindle id (required except for JSON files that carry it).",
    "direction": "x | y (UFF: default from the file's response direction).",
    "plane": "spindle_nose | holder_tip.",
    "kind": "point_receptance | artifact_frfs | direct_frf (default direct_frf).",
    "machine": "Machine name.",
    "notes": "Free text.",
    "points_m": "artifact_frfs: point positions from the tip, m, e.g. 0,0.025.",
    "artifact": "artifact_frfs: JSON object (diameter_m, stickout_m, ...).",
    "units": "FRF unit of the file, e.g. m/N, um/N, in/lbf, m/s^2/N, g/N, dB re 1 m/N (never guessed; "
             "default: the one the file's header or UFF datasets state).",
    "columns": "CSV: f,re,im | f,mag,phase | f,h11.re,h11.im,... (default: from the file's header); "
               "tap: t,force,response.",
    "frequency_unit": "CSV frequency unit: Hz | kHz | rad/s (default: the header's, else Hz).",
    "phase_unit": "CSV phase unit: deg | rad.",
    "roles": "UFF: NAME=RSP_NODE:REF_NODE,..., e.g. h11=1:1,h21=2:1,h22=2:2.",
    "scalar_direction": "UFF: direction x | y of scalar FRFs (direction code 0), which the file does not say.",
    "sensor_mass_kg": "Remove this accelerometer mass from the driving-point FRF, kg.",
    "drop_nonpositive": "true: drop rows at f <= 0 Hz instead of refusing the file.",
    "force_unit": "tap: force unit, e.g. N.",
    "response_unit": "tap: response unit, e.g. m/s^2 or g.",
    "sample_rate_hz": "tap: sampling rate, Hz.",
    "force_window_s": "tap: force window width, s.",
    "exponential_tau_s": "tap: exponential window time constant, s.",
    "max_frequency_hz": "tap: keep f <= this, Hz.",
}
_UPLOAD_BODY = {"requestBody": {"required": True, "content": {
    "application/json": {"schema": {"$ref": "#/components/schemas/MeasurementUpload"}},
    "multipart/form-data": {"schema": {
        "type": "object", "required": ["file"],
        "properties": {name: ({"type": "string", "format": "binary", "description": text} if name == "file"
                              else {"type": "string", "description": text}) for name, text in UPLOAD_FIELDS.items()},
        "additionalProperties": False}}}}}


@router.post("", status_code=201, response_model=MeasurementInfo, openapi_extra=body_limit("measurement", _UPLOAD_BODY),
             responses={**problems(400, 401, 403, 413, 415, 422), **IDEMPOTENCY_PROBLEMS},
             summary="Store a measurement (write key)")
async def upload_measurement(request: Request, state: StateDep, _: WriteAccess,
                             idempotency_key: IdempotencyKeyHeader = None) -> Response:
    """Store a measured spindle FRF; answers its metadata with the new ``id`` (``201``).

    With ``Idempotency-Key`` (recommended for automated uploads), a retry of the same upload
    answers the first ``201`` again instead of storing a second copy (see
    :mod:`service.idempotency`; the key itself is handled by the route class).

    Either the contract's measurement JSON (``application/json``: SI receptances) or a file
    upload (``multipart/form-data``): UFF 58, CSV/TSV, CutPro ``.frf``, contract JSON or a
    raw tap, with the metadata and the importer options as form fields. Units are never
    guessed: a file whose units are not declared (in the file or by ``units``) is refused.
    """
    kind, body = await read_body(request)
    fmt = "json-body"
    try:
        info = await _import(request, kind, body, fmt, state)
    finally:
        if kind == "form":
            await body.close()
    return json_response(info, status_code=201, headers={"Location": f"/v1/measurements/{info['id']}"})


@dataclass(frozen=True)
class MeasurementForm:
    """A measurement file upload as a multipart form gives it (``POST /v1/measurements`` and
    ``POST /v1/measurements:read``: one form, one reading).

    Attributes
    ----------
    data : bytes
        The (first) file.
    file_name : str
    format : str or None
        The ``format`` field as sent.
    extra_taps : list of bytes
        Further files (taps averaged with the first).
    metadata, options : dict
        The metadata fields and the importer options as sent (text, None when absent).
    """

    data: bytes
    file_name: str
    format: str | None
    extra_taps: list[bytes]
    metadata: dict[str, str | None]
    options: dict[str, str | None]

    @property
    def reading(self) -> dict[str, Any]:
        """Keyword arguments of :func:`rcsa.app.measurements.import_measurement` (and
        ``read_measurement``) besides the bytes."""
        return {"file_name": self.file_name, "fmt": self.format, "metadata": self.metadata,
                "options": self.options, "extra_taps": self.extra_taps}


async def measurement_form(form: Any, allowed: Mapping[str, str], limit_bytes: int) -> MeasurementForm:
    """Read a measurement upload form: unknown fields refused, the files (413 above
    ``limit_bytes``), the metadata (:data:`rcsa.app.measurements.META_FIELDS`) and the importer
    options (:data:`rcsa.app.measurements.IMPORT_OPTIONS`) as text."""
    check_form_fields(form, allowed)
    uploads = await form_uploads(form, "file", limit_bytes, most=None, what="measurement file")
    (data, name, _), extra = uploads[0], [d for d, _, _ in uploads[1:]]
    return MeasurementForm(data, name, form_text(form, "format"), extra,
                           {k: form_text(form, k) for k in M.META_FIELDS},
                           {k: form_text(form, k) for k in M.IMPORT_OPTIONS})


async def _import(request: Request, kind: str, body: Any, fmt: str, state: AppState) -> dict[str, Any]:
    try:
        if kind == "json":
            upload = await run_in_threadpool(validate_json, MeasurementUpload, body)  # may be large: off the loop
            measurement = await run_in_threadpool(M.measurement_from_document, upload.to_document())
        else:
            upload = await measurement_form(body, UPLOAD_FIELDS, state.settings.max_upload_bytes)
            fmt = M.upload_format(upload.file_name, upload.format)
            measurement = await run_in_threadpool(lambda: M.import_measurement(upload.data, **upload.reading))
    except (InputError, ProblemError):
        state.metrics.import_failures.labels(fmt).inc()
        raise
    held = reservation(request)
    if held is None:
        info = await run_in_threadpool(M.store_measurement, state.store, measurement)
    else:  # the id is recorded with the key before the write: a retry after a crash finds the file
        info = await run_in_threadpool(lambda: M.store_measurement_once(state.store, measurement,
                                                                        recorded_id=held.effect, record=held.record))
    state.metrics.imports.labels(fmt).inc()
    return info


@router.get("", response_model=MeasurementPage, responses=problems(401, 422), summary="List measurements")
def list_measurements(
    state: StateDep, _: ReadAccess,
    spindle_id: Annotated[str | None, Query(max_length=128, description="Only this spindle.")] = None,
    machine: Annotated[str | None, Query(max_length=128, description="Only this machine.")] = None,
    direction: Annotated[Literal["x", "y"] | None, Query(description="Only this direction.")] = None,
    plane: Annotated[Literal["spindle_nose", "holder_tip"] | None, Query(description="Only this plane.")] = None,
    kind: Annotated[Literal["point_receptance", "artifact_frfs", "direct_frf"] | None,
                    Query(description="Only this kind.")] = None,
    limit: Annotated[int, Query(ge=1, le=1000, description="Items per page.")] = 100,
    cursor: Annotated[str | None, Query(max_length=1000, description="next_cursor of the previous page.")] = None,
) -> Response:
    """Metadata of the stored measurements, oldest first, a page at a time (``limit`` + ``cursor``)."""
    return json_response(M.list_measurements(state.store, limit=limit, cursor=cursor, spindle_id=spindle_id,
                                             machine=machine, direction=direction, plane=plane, kind=kind))


@router.get("/{measurement_id}", response_model=MeasurementDocument, responses={
    200: {"content": {HDF5: {"schema": {"type": "string", "format": "binary"}}},
          "description": "The measurement in the contract's JSON form, or its HDF5 file (Accept: application/x-hdf5)."},
    **problems(401, 404, 409)}, summary="Get a measurement (JSON or HDF5)")
def get_measurement(
    measurement_id: MeasurementId, state: StateDep, _: ReadAccess,
    data: Annotated[bool, Query(description="Include the arrays (false: metadata and summary only).")] = True,
    accept: Annotated[str | None, Header(description="application/json (default) or application/x-hdf5.")] = None,
) -> Response:
    """Metadata and data in the contract JSON (receptances ``{real, imag}``, SI), or the stored
    HDF5 file when ``Accept`` prefers ``application/x-hdf5``."""
    if _prefers_hdf5(accept):
        return Response(M.measurement_hdf5(state.store, measurement_id), media_type=HDF5,
                        headers={"Content-Disposition": f'attachment; filename="{measurement_id}.h5"'})
    return json_response(M.measurement_document(state.store, measurement_id, include_data=data))


@router.delete("/{measurement_id}", response_model=Deleted, responses=problems(401, 403, 404),
               summary="Delete a measurement (write key)")
def delete_measurement(measurement_id: MeasurementId, state: StateDep, _: WriteAccess) -> Response:
    """Delete a measurement (its id is never reused)."""
    return json_response(M.delete_measurement(state.store, measurement_id))


def _prefers_hdf5(accept: str | None) -> bool:
    """Whether the Accept header ranks application/x-hdf5 above JSON."""
    best: dict[str, float] = {}
    for part in (accept or "").split(","):
        media, *params = [p.strip().lower() for p in part.split(";")]
        q = 1.0
        for p in params:
            if p.startswith("q="):
                try:
                    q = float(p[2:])
                except ValueError:
                    q = 0.0
        best[media] = max(best.get(media, 0.0), q)
    hdf5 = best.get(HDF5, 0.0)
    json_q = max(best.get("application/json", 0.0), best.get("application/*", 0.0), best.get("*/*", 0.0))
    return hdf5 > 0 and hdf5 >= json_q



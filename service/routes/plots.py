"""Figures and CSV files: what a person downloads next to the JSON.

* ``POST /v1/plots/frf`` — the tool-point FRF as PNG or SVG (:func:`rcsa.app.figures.frf_picture`:
  real and imaginary parts, magnitude and phase, in µm/N), from an inline FRF (``frf``, as
  in the stability-lobes request) or from an ``assembly`` predicted first.
* ``POST /v1/plots/lobes`` — the stability lobe diagram (axial depth mm vs spindle speed
  rpm, :func:`rcsa.app.figures.lobes_picture`); the body is a stability-lobes request plus
  optional drawing options (operating point, y limit, title).
* ``POST /v1/exports/frf.csv`` — an assembly's prediction as CSV: frequency and the real
  and imaginary parts of ``h, l, n, p`` in SI units (the header names every unit).
* ``POST /v1/exports/lobes.csv`` — the lobe envelope as CSV: speed, depth limit, chatter
  frequency and governing lobe.

Images are PNG unless ``?format=svg`` (or an ``Accept`` that names ``image/svg+xml`` and not
``image/png``). Numbers in CSV files are written with Python's shortest round-trip repr, so
they equal the JSON results exactly; a missing value (no lobe reaches that speed) is an empty
cell.
"""

from __future__ import annotations

import threading
from contextlib import nullcontext
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Depends, Header, Query
from pydantic import BaseModel, ConfigDict, Field
from starlette.responses import Response

from rcsa.app import budget, exports, figures
from rcsa.app.analyses import stability_lobes, stability_lobes_answer
from rcsa.app.bounds import MAX_LENGTH_M, MAX_SPEED_RPM, MIN_SPEED_RPM
from rcsa.app.predictions import example_assembly, predict

from ..bodies import require_json
from ..deps import StateDep
from ..responses import body_limit, problems
from ..routing import ServiceRoute
from ..schemas import FrfIn, LobesRequest, PredictionRequest
from ..security import ReadAccess
from .lobes import lobes_document

router = APIRouter(prefix="/v1", tags=["plots and exports"], route_class=ServiceRoute)

PNG = "image/png"
SVG = "image/svg+xml"
CSV_MEDIA = "text/csv"

# matplotlib keeps caches (fonts, text layout) shared by all figures; draw one at a time.
_RENDER_LOCK = threading.Lock()

FormatQuery = Annotated[Literal["png", "svg"] | None, Query(
    description="Image format: png or svg. Default: svg when Accept names image/svg+xml and not image/png, "
                "else png.")]
AcceptHeader = Annotated[str | None, Header(description="image/png or image/svg+xml (the format query wins).")]

_IMAGE = {200: {"description": "The figure (PNG, 150 dpi, or SVG with text as paths).",
                "content": {PNG: {"schema": {"type": "string", "format": "binary"}},
                            SVG: {"schema": {"type": "string"}}}}}


def _csv_response(description: str) -> dict[int | str, dict[str, Any]]:
    return {200: {"description": description, "content": {CSV_MEDIA: {"schema": {"type": "string"}}}}}


_GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
_RA1 = example_assembly("ra1", _GRID)
_STRICT = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)


class FrfPlotRequest(BaseModel):
    """Body of POST /v1/plots/frf: an inline FRF or an assembly, and how to draw it."""

    model_config = ConfigDict(**_STRICT, json_schema_extra={"examples": [
        {"assembly": _RA1, "layout": "full", "title": "RA-1"},
        {"frf": {"frequency_hz": [100.0, 200.0, 300.0],
                 "h": {"real": [1.0e-7, 1.2e-7, -3.0e-7], "imag": [-1.0e-9, -5.0e-9, -2.0e-7]}}}]})

    frf: FrfIn | None = Field(None, description="Inline tool-point FRF (frequency_hz in Hz, h in m/N); "
                                                "give frf or assembly.")
    assembly: PredictionRequest | None = Field(None, description="Predict this assembly's tool-point h and draw "
                                                                 "it (with uncertainty: its p05–p95 band shaded).")
    layout: Literal["full", "real_imag", "bode"] = Field(
        "full", description="full: real, imaginary, magnitude (log) and phase; real_imag; bode: magnitude and "
                            "phase. Receptance shown in µm/N, phase in degrees, frequency in Hz.")
    title: str | None = Field(None, max_length=200, description="Figure title.")


class OperatingPoint(BaseModel):
    """The current cutting condition, drawn as a marker (green below the limit, red above)."""

    model_config = _STRICT

    spindle_speed_rpm: float = Field(ge=MIN_SPEED_RPM, le=MAX_SPEED_RPM, description="Spindle speed, rpm.")
    depth_m: float = Field(gt=0, le=MAX_LENGTH_M, description="Axial depth of cut, m.")


class LobesPlotRequest(LobesRequest):
    """Body of POST /v1/plots/lobes: a stability-lobes request and drawing options."""

    show_lobes: bool = Field(True, description="Draw every lobe as a thin line under the envelope.")
    operating_point: OperatingPoint | None = Field(None, description="Marker for the current (n, ap).")
    depth_max_mm: float | None = Field(None, gt=0, le=1.0e6, description="Upper y limit, mm (default: from the "
                                                                         "envelope, at most 8 × the absolute limit).")
    title: str | None = Field(None, max_length=200, description="Figure title.")


@router.post("/plots/frf", dependencies=[Depends(require_json)], response_class=Response, openapi_extra=body_limit("plot"),
             responses={**_IMAGE, **problems(401, 413, 415, 422)}, summary="Figure of a tool-point FRF (PNG/SVG)")
def plot_frf(body: FrfPlotRequest, state: StateDep, _: ReadAccess, format: FormatQuery = None,  # noqa: A002
             accept: AcceptHeader = None) -> Response:
    """Draw a tool-point receptance h: real and imaginary parts, magnitude (log scale) and
    phase, in µm/N and degrees against frequency in Hz.

    Give ``frf`` (``frequency_hz`` in Hz and ``h`` in m/N, e.g. from a prediction result) or
    an ``assembly``, which is predicted first (as ``POST /v1/tool-point-frf``).
    """
    doc = body.model_dump(exclude_unset=True, include={"frf", "assembly"})
    if body.assembly is not None:
        budget.check("prediction", doc["assembly"], mode="sync")
    with state.metrics.timed("predict") if body.assembly is not None else nullcontext():
        curve = figures.tool_point_curve(**doc, store=state.reader, max_lines=state.settings.max_frequency_lines)
    fmt = _image_format(format, accept)
    with state.metrics.timed("plot"), _RENDER_LOCK:
        image = figures.frf_picture(curve, fmt=fmt, layout=body.layout, title=body.title)
    return _image(image, fmt, "tool-point-frf")


@router.post("/plots/lobes", dependencies=[Depends(require_json)], response_class=Response, openapi_extra=body_limit("plot"),
             responses={**_IMAGE, **problems(401, 413, 415, 422)},
             summary="Stability lobe diagram (PNG/SVG)")
def plot_lobes(body: LobesPlotRequest, state: StateDep, _: ReadAccess, format: FormatQuery = None,  # noqa: A002
               accept: AcceptHeader = None) -> Response:
    """Axial depth-of-cut limit (mm) against spindle speed (rpm): the lower envelope, every
    lobe, the stable region shaded, the absolute limit dashed and, when given, the operating
    point; with ``uncertainty``, the robust limit dashed. The body is a ``POST /v1/stability-lobes``
    request plus the drawing options."""
    request = lobes_document(body, state, exclude={"show_lobes", "operating_point", "depth_max_mm", "title"})
    budget.check("lobes", request, mode="sync")
    with state.metrics.timed("lobes"):
        answer = stability_lobes_answer(request, store=state.reader, max_lines=state.settings.max_frequency_lines,
                                        within=budget.SYNC)
    point = body.operating_point
    fmt = _image_format(format, accept)
    with state.metrics.timed("plot"), _RENDER_LOCK:
        image = figures.lobes_picture(answer.nominal, fmt=fmt, robust=answer.extras(),
                                      show_lobes=body.show_lobes, depth_max_mm=body.depth_max_mm,
                                      title=body.title, operating_point=None if point is None else
                                      (point.spindle_speed_rpm, point.depth_m))
    return _image(image, fmt, "stability-lobes")


@router.post("/exports/frf.csv", dependencies=[Depends(require_json)], response_class=Response, openapi_extra=body_limit("plot"),
             responses={**_csv_response(
                 "Header row frequency_hz, h_real_m_n, h_imag_m_n, l_real_1_n, l_imag_1_n, n_real_rad_n, "
                 "n_imag_rad_n, p_real_rad_n_m, p_imag_rad_n_m (with uncertainty also h_magnitude_p05_m_n, "
                 "h_magnitude_p50_m_n, h_magnitude_p95_m_n); one row per frequency line."),
                 **problems(401, 413, 415, 422)},
             summary="Tool-point FRF of one assembly as CSV")
def export_frf_csv(body: PredictionRequest, state: StateDep, _: ReadAccess) -> Response:
    """Predict the assembly (exactly as ``POST /v1/tool-point-frf``) and answer its tool-point
    receptances as CSV: frequency in Hz, then real and imaginary parts of h (m/N), l (1/N),
    n (rad/N) and p (rad/(N·m)); with ``uncertainty``, the band's p05/p50/p95 of ``|h|`` (m/N).
    The numbers equal the JSON result's."""
    doc = body.model_dump(exclude_unset=True)
    budget.check("prediction", doc, mode="sync")
    with state.metrics.timed("predict"):
        result = predict(doc, store=state.reader, max_lines=state.settings.max_frequency_lines)
    state.metrics.computed("predict", 1)
    return _csv(exports.frf_csv(result.to_dict()), "tool-point-frf")


@router.post("/exports/lobes.csv", dependencies=[Depends(require_json)], response_class=Response, openapi_extra=body_limit("plot"),
             responses={**_csv_response(
                 "Header row spindle_speed_rpm, depth_limit_m, chatter_frequency_hz, governing_lobe (with "
                 "uncertainty also depth_limit_robust_m); one row per "
                 "speed; empty cells where no lobe reaches the speed (governing_lobe -1)."),
                 **problems(401, 413, 415, 422)},
             summary="Stability lobes (lower envelope) as CSV")
def export_lobes_csv(body: LobesRequest, state: StateDep, _: ReadAccess) -> Response:
    """Compute the lobes (exactly as ``POST /v1/stability-lobes``) and answer the lower
    envelope as CSV: spindle speed in rpm, depth limit in m, chatter frequency in Hz and the
    index k of the governing lobe."""
    request = lobes_document(body, state)
    budget.check("lobes", request, mode="sync")
    with state.metrics.timed("lobes"):
        doc = stability_lobes(request, store=state.reader, max_lines=state.settings.max_frequency_lines,
                              within=budget.SYNC)
    return _csv(exports.lobes_csv(doc), "stability-lobes")


# --------------------------------------------------------------------------- helpers

def _image_format(format: str | None, accept: str | None) -> str:  # noqa: A002
    if format is not None:
        return format
    media = {part.split(";")[0].strip().lower() for part in (accept or "").split(",")}
    return "svg" if SVG in media and PNG not in media else "png"


def _image(data: bytes, fmt: str, stem: str) -> Response:
    return Response(data, media_type=PNG if fmt == "png" else SVG,
                    headers={"Content-Disposition": f'inline; filename="{stem}.{fmt}"'})


def _csv(data: bytes, stem: str) -> Response:
    return Response(data, media_type=f"{CSV_MEDIA}; charset=utf-8",
                    headers={"Content-Disposition": f'attachment; filename="{stem}.csv"'})

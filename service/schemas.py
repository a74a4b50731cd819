"""Request and response models of the REST API (pydantic), field names as in ``contract.md``.

SI units everywhere; every numeric field name ends in its unit and every description says
it. Request models forbid unknown fields and refuse strings where numbers belong (strict
mode). They check types and the library's own bounds (:mod:`rcsa.app.bounds`, so the
OpenAPI document publishes exactly what :mod:`rcsa` accepts); every rule between fields
(stickout within the overall length, the shank fits the bore, ...) is checked by
:mod:`rcsa`, which names the field in the same way. Response models allow extra fields (the
contract lets results grow).

A batch's combinations are validated one by one by :mod:`rcsa` (so that one bad
combination never fails the others): their schema is documented here, but an item that does
not fit it is passed on as it came and reported in its own result.
"""

from __future__ import annotations

import math
import re
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    ValidationError,
    ValidatorFunctionWrapHandler,
    WrapValidator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from rcsa.app.bounds import (
    MAX_COHERENCE,
    MAX_CUTTING_COEFFICIENT_N_M2,
    MAX_DAMPING,
    MAX_DENSITY_KG_M3,
    MAX_FREQUENCY_HZ,
    MAX_FRF_VALUE,
    MAX_HOLDER_SEGMENTS_PER_CONE,
    MAX_LENGTH_M,
    MAX_LOSS_FACTOR,
    MAX_MODULUS_PA,
    MAX_NECK_SEGMENTS,
    MAX_POISSON_RATIO,
    MAX_RADIAL_RATIO,
    MAX_SHEAR_COEFFICIENT,
    MAX_SPEED_COUNT,
    MAX_SPEED_RPM,
    MAX_STIFFNESS,
    MAX_TEETH,
    MIN_CUTTING_COEFFICIENT_N_M2,
    MIN_DENSITY_KG_M3,
    MIN_FLUTED_DIAMETER_RATIO,
    MIN_FREQUENCY_HZ,
    MIN_JOINT_STIFFNESS,
    MIN_LENGTH_M,
    MIN_MODULUS_PA,
    MIN_POISSON_RATIO,
    MIN_RADIAL_IMMERSION,
    MIN_SHEAR_COEFFICIENT,
    MIN_SPEED_COUNT,
    MIN_SPEED_RPM,
)
from rcsa.app.examples import ra1

from .field_errors import pydantic_errors

__all__ = [
    "Assembly",
    "BatchRequest",
    "BatchResult",
    "JobStatus",
    "LibraryPredictionRequest",
    "LibraryResult",
    "LobesRequest",
    "LobesResult",
    "MeasurementDocument",
    "MeasurementInfo",
    "MeasurementPage",
    "MeasurementUpload",
    "PredictionResult",
    "Problem",
    "RecommendReport",
]

_EXAMPLE_GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
_RA1 = ra1(_EXAMPLE_GRID)


class _Request(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)


class _Response(BaseModel):
    model_config = ConfigDict(extra="allow")


# --------------------------------------------------------------------------- assembly

FrequencyValue = Annotated[float, Field(le=MAX_FREQUENCY_HZ)]  # > 0 and increasing: checked by rcsa
FrfValue = Annotated[float, Field(ge=-MAX_FRF_VALUE, le=MAX_FRF_VALUE)]
Coherence = Annotated[float, Field(ge=0, le=MAX_COHERENCE)]


class FrequencyRange(_Request):
    """Evenly spaced lines from ``start_hz`` to ``stop_hz`` (included)."""

    start_hz: float = Field(ge=MIN_FREQUENCY_HZ, le=MAX_FREQUENCY_HZ, description="First frequency line, Hz (0 Hz is singular: >= 1 mHz; <= 10 MHz).")
    stop_hz: float = Field(ge=MIN_FREQUENCY_HZ, le=MAX_FREQUENCY_HZ, description="Last frequency line (included), Hz; >= start_hz.")
    step_hz: float = Field(gt=0, le=MAX_FREQUENCY_HZ, description="Spacing of the lines, Hz.")

    @model_validator(mode="after")
    def _finite_line_count(self) -> FrequencyRange:
        # rcsa.model.contract.parse_frequency counts the lines with math.floor, which overflows (a 500)
        # when (stop - start) / step is infinite; refuse such a grid here with the same field.
        if not math.isfinite((self.stop_hz - self.start_hz) / self.step_hz):
            raise PydanticCustomError("frequency_lines", "step_hz is too small for this band: the grid would "
                                                         "have an unbounded number of lines")
        return self


class FrequencyValues(_Request):
    """Explicit frequency lines."""

    values_hz: list[FrequencyValue] = Field(min_length=1, description="Frequency lines, Hz: strictly increasing, > 0.")


def _frequency_tag(value: Any) -> str | None:
    if isinstance(value, dict):
        return "frequency-values" if "values_hz" in value else "frequency-range"
    if isinstance(value, FrequencyValues):
        return "frequency-values"
    return "frequency-range" if isinstance(value, FrequencyRange) else None


Frequency = Annotated[
    Annotated[FrequencyRange, Tag("frequency-range")] | Annotated[FrequencyValues, Tag("frequency-values")],
    Discriminator(_frequency_tag, custom_error_type="frequency",
                  custom_error_message="must be an object {start_hz, stop_hz, step_hz} or {values_hz}"),
    Field(description="Frequency grid (Hz): {start_hz, stop_hz, step_hz} (stop included) or {values_hz}. "
                      "The number of lines is limited (RCSA_MAX_FREQUENCY_LINES).",
          examples=[_EXAMPLE_GRID]),
]


class Material(_Request):
    """Material properties; a built-in (steel, carbide) may be overridden field by field."""

    youngs_modulus_pa: float | None = Field(None, ge=MIN_MODULUS_PA, le=MAX_MODULUS_PA, description="Young's modulus E, Pa.")
    poisson_ratio: float | None = Field(None, gt=MIN_POISSON_RATIO, lt=MAX_POISSON_RATIO,
                                       description="Poisson's ratio ν (dimensionless).")
    density_kg_m3: float | None = Field(None, ge=MIN_DENSITY_KG_M3, le=MAX_DENSITY_KG_M3, description="Density ρ, kg/m³.")
    loss_factor: float | None = Field(None, ge=0, lt=MAX_LOSS_FACTOR,
                                      description="Loss factor η (E and G become E(1+iη)).")


class Segment(_Request):
    """A uniform (hollow) circular beam segment."""

    length_m: float = Field(ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Segment length, m.")
    outer_diameter_m: float = Field(ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Outer diameter, m.")
    inner_diameter_m: float = Field(0.0, ge=0, le=MAX_LENGTH_M, description="Bore diameter, m (0: solid); < outer_diameter_m.")
    material: str = Field("steel", min_length=1, description="Material name: steel, carbide, or one of `materials`.")


class Bearing(_Request):
    """A spring/damper to rigid ground on the spindle."""

    position_m: float = Field(ge=0, le=MAX_LENGTH_M, description="Position from the spindle nose (gauge line), m.")
    stiffness_n_m: float = Field(ge=0, le=MAX_STIFFNESS, description="Radial stiffness, N/m.")
    damping_ns_m: float = Field(0.0, ge=0, le=MAX_DAMPING, description="Radial viscous damping, N·s/m.")
    rotational_stiffness_nm_rad: float = Field(0.0, ge=0, le=MAX_STIFFNESS, description="Tilting stiffness, N·m/rad.")
    rotational_damping_nms_rad: float = Field(0.0, ge=0, le=MAX_DAMPING, description="Tilting damping, N·m·s/rad.")


class AnalyticalSpindle(_Request):
    """A modelled spindle: segments from the nose toward the rear, and bearings."""

    segments: list[Segment] = Field(min_length=1, description="Shaft segments, nose → rear.")
    bearings: list[Bearing] = Field(default_factory=list, description="Bearings (positions from the nose).")


class MeasuredSpindle(_Request):
    """A stored measured spindle (hybrid prediction)."""

    measurement_id: str = Field(min_length=1, description="Id of a stored measurement (GET /v1/measurements).",
                                examples=["m-0123456789ab"])
    artifact_method: Literal["exact", "finite_difference"] = Field(
        "exact", description="How an artifact_frfs measurement is identified: the exact three-FRF method, or "
                             "the labelled finite-difference fallback.")
    effective_length_m: float = Field(0.2, ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Equivalent-cantilever length used to estimate the "
                                                             "rotations of a direct_frf measurement, m.")


def _spindle_tag(value: Any) -> str | None:
    if isinstance(value, dict):
        return "spindle-measured" if "measurement_id" in value else "spindle-analytical"
    if isinstance(value, MeasuredSpindle):
        return "spindle-measured"
    return "spindle-analytical" if isinstance(value, AnalyticalSpindle) else None


Spindle = Annotated[
    Annotated[AnalyticalSpindle, Tag("spindle-analytical")] | Annotated[MeasuredSpindle, Tag("spindle-measured")],
    Discriminator(_spindle_tag, custom_error_type="spindle",
                  custom_error_message="must be an object {segments, bearings} or {measurement_id}"),
    Field(description="The spindle: modelled (segments + bearings) or a stored measurement (hybrid)."),
]


class Holder(_Request):
    """Tool holder: segments from the gauge line toward the tool end."""

    segments: list[Segment] = Field(min_length=1, description="Holder segments, gauge line → tool end; "
                                                              "inner_diameter_m is the bore.")


class NeckSegment(_Request):
    """One piece of a stepped (or stepped-conical) neck."""

    length_m: float = Field(ge=MIN_LENGTH_M, description="Length of the piece, m (all pieces together at most "
                                                         "stickout_m − flute_length_m).")
    diameter_m: float = Field(ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Its diameter, m.")


class Tool(_Request):
    """Parametric cutting tool (ISO 13399 / Fusion meaning)."""

    material: str = Field("carbide", min_length=1, description="Tool material name.")
    diameter_m: float = Field(ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Cutting diameter DC, m.")
    shank_diameter_m: float | None = Field(None, ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Shank diameter SFDM, m (default: diameter_m).")
    overall_length_m: float = Field(ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Overall length OAL, m.")
    flute_length_m: float = Field(ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Flute length LCF, m; <= stickout_m.")
    stickout_m: float = Field(ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Length from the holder's tool-end face to the tip (Fusion LB), m.")
    fluted_diameter_ratio: float = Field(0.8, ge=MIN_FLUTED_DIAMETER_RATIO, le=1, description="Equivalent fluted diameter / DC "
                                                                      "(dimensionless).")
    fluted_mass_diameter_ratio: float | None = Field(None, ge=MIN_FLUTED_DIAMETER_RATIO, le=1, description="Separate equivalent diameter "
                                                     "ratio for the flutes' mass (default: fluted_diameter_ratio).")
    shoulder_length_m: float | None = Field(None, ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Reduced neck: from the tip to the neck's end, "
                                            "m (with shoulder_diameter_m).")
    shoulder_diameter_m: float | None = Field(None, ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Reduced neck diameter, m.")
    neck_segments: list[NeckSegment] | None = Field(None, max_length=MAX_NECK_SEGMENTS, description=(
        "Instead of shoulder_length_m/shoulder_diameter_m: a stepped neck, pieces listed from the flute end toward "
        "the holder (a conical neck as steps); together at most stickout_m − flute_length_m long."))


class Joint(_Request):
    """Elastic joint diag(k_t + iωc_t, k_r + iωc_r); a rotational stiffness left out is rigid."""

    stiffness_n_m: float = Field(ge=MIN_JOINT_STIFFNESS, le=MAX_STIFFNESS, description="Translational stiffness k_t, N/m.")
    damping_ns_m: float = Field(0.0, ge=0, le=MAX_DAMPING, description="Translational damping c_t, N·s/m.")
    rotational_stiffness_nm_rad: float | None = Field(None, ge=MIN_JOINT_STIFFNESS, le=MAX_STIFFNESS, description="Rotational stiffness k_r, N·m/rad.")
    rotational_damping_nms_rad: float = Field(0.0, ge=0, le=MAX_DAMPING, description="Rotational damping c_r, N·m·s/rad.")


class Joints(_Request):
    """The two joints; one left out is rigid."""

    spindle_holder: Joint | None = Field(None, description="Spindle nose ↔ holder base (gauge line).")
    holder_tool: Joint | None = Field(None, description="Holder tip ↔ tool base (holder face).")


BeamTheory = Literal["timoshenko", "euler_bernoulli"]
ShearCoefficient = Literal["hutchinson", "cowper"] | Annotated[float, Field(ge=MIN_SHEAR_COEFFICIENT,
                                                                          le=MAX_SHEAR_COEFFICIENT)]


class Assembly(_Request):
    """A spindle–holder–tool assembly (contract "Assembly"); body of POST /v1/tool-point-frf."""

    model_config = ConfigDict(json_schema_extra={"examples": [_RA1]})

    frequency: Frequency
    beam_theory: BeamTheory = Field("timoshenko", description="Beam theory of every segment.")
    shear_coefficient: ShearCoefficient = Field("hutchinson", description="Shear coefficient model, or a "
                                                "number (dimensionless).")
    materials: dict[str, Material] | None = Field(None, description="Materials added to or overriding the "
                                                  "built-ins (steel, carbide), by name.")
    spindle: Spindle
    holder: Holder | None = Field(None, description="The holder (leave out only on a holder_tip measurement).")
    tool: Tool
    joints: Joints | None = Field(None, description="Elastic joints; left out = rigid.")
    name: str | None = Field(None, max_length=200, description="Free label, echoed nowhere.")
    description: str | None = Field(None, max_length=10_000, description="Free text.")


# --------------------------------------------------------------------------- batch

class Combination(_Request):
    """One tool–holder combination of a batch."""

    id: str = Field(min_length=1, max_length=200, description="Caller's id, echoed in the result "
                    "(e.g. a Fusion guid or T number).", examples=["T12-BT40-A"])
    holder: Holder | None = None
    tool: Tool
    joints: Joints | None = None


class RefusedCombination:
    """A combination that does not fit the schema: kept as sent, with what is wrong."""

    def __init__(self, raw: Any, errors: list[dict[str, Any]]) -> None:
        self.raw = raw
        self.errors = errors


def _keep_invalid(value: Any, handler: ValidatorFunctionWrapHandler) -> Any:
    """Validate a combination; if it does not fit, keep it (refused) so that only it fails."""
    try:
        return handler(value)
    except ValidationError as exc:
        return RefusedCombination(value, exc.errors(include_url=False, include_context=True, include_input=False))


class BatchRequest(_Request):
    """Many tool–holder combinations on one spindle (POST /v1/tool-point-frf/batch)."""

    model_config = ConfigDict(json_schema_extra={"examples": [{
        "frequency": _EXAMPLE_GRID, "spindle": _RA1["spindle"],
        "combinations": [{"id": "T1", "holder": _RA1["holder"], "tool": _RA1["tool"], "joints": _RA1["joints"]},
                         {"id": "T2", "holder": _RA1["holder"], "tool": {**_RA1["tool"], "stickout_m": 0.05},
                          "joints": _RA1["joints"]}]}]})

    frequency: Frequency
    beam_theory: BeamTheory = "timoshenko"
    shear_coefficient: ShearCoefficient = "hutchinson"
    materials: dict[str, Material] | None = None
    spindle: Spindle
    natural_frequencies: bool = Field(True, description="Compute the exact natural frequencies of every "
                                      "combination (analytical spindles; costs time on big batches).")
    combinations: list[Annotated[Combination, WrapValidator(_keep_invalid)]] = Field(
        min_length=1, description="Combinations (at most RCSA_MAX_BATCH_COMBINATIONS). Each is checked on "
                                  "its own: one that is invalid gets status error in its result.")

    def to_request(self) -> tuple[dict[str, Any], dict[int, dict[str, str]]]:
        """The batch document (combinations as sent) and the refused ones: index → {field, detail}."""
        doc = self.model_dump(exclude_unset=True, exclude={"combinations"})
        combos: list[Any] = []
        refused: dict[int, dict[str, str]] = {}
        for i, c in enumerate(self.combinations):
            if isinstance(c, RefusedCombination):
                combos.append(c.raw)
                refused[i] = pydantic_errors(c.errors, prefix=f"combinations[{i}]")[0]
            else:
                combos.append(c.model_dump(exclude_unset=True))
        doc["combinations"] = combos
        return doc, refused


# --------------------------------------------------------------------------- results

class ComplexArray(_Response):
    """A complex array as two real arrays."""

    real: list[float] = Field(description="Real parts.")
    imag: list[float] = Field(description="Imaginary parts.")


class ToolPoint(_Response):
    """Tool-point receptance [[h, l], [n, p]]."""

    h: ComplexArray | None = Field(None, description="Displacement / force, m/N (always present unless "
                                   "?tool_point= leaves it out).")
    l: ComplexArray | None = Field(None, description="Displacement / moment, m/(N·m) = 1/N (absent likewise).")  # noqa: E741
    n: ComplexArray | None = Field(None, description="Rotation / force, rad/N (absent likewise).")
    p: ComplexArray | None = Field(None, description="Rotation / moment, rad/(N·m) (absent likewise).")


class Peak(_Response):
    """A local maximum of |h|."""

    frequency_hz: float = Field(description="Frequency of the peak, Hz.")
    magnitude_m_n: float = Field(description="|h| at the peak, m/N.")


class PredictionResult(_Response):
    """Tool-point prediction (contract "Prediction result")."""

    frequency_hz: list[float] = Field(description="Frequency lines, Hz.")
    tool_point: ToolPoint
    natural_frequencies_hz: list[float] = Field(description="Undamped natural frequencies in the band, Hz "
                                                "(exact for a modelled spindle; modal-fit estimates for a "
                                                "hybrid one, see natural_frequencies_method).")
    natural_frequencies_method: str = Field(description="wittrick_williams (exact) or modal_fit.")
    natural_frequencies_sd_hz: list[float] | None = Field(None, description="Hybrid only: the standard "
                                                          "uncertainty of each modal-fit natural frequency, Hz.")
    modal_fit: list[dict[str, Any]] | None = Field(None, description="Hybrid only: each fitted mode (frequency_hz, "
                                                   "damping_ratio, sd_hz, damping_ratio_sd, band_hz, modes_in_band, "
                                                   "residual_rel, significance, peak).")
    peaks: list[Peak] = Field(description="Peaks of |h| (hybrid: those above the noise, one per mode).")
    static_stiffness_n_m: float | None = Field(description="Static stiffness 1/h(0), N/m; null when it cannot "
                                               "be given (hybrid, ungrounded).")
    min_real_m_n: float = Field(description="Most negative real part of h, m/N.")
    min_real_frequency_hz: float = Field(description="Where it occurs, Hz.")
    notes: list[str] = Field(description="What the numbers mean where it is not obvious.")


class ItemError(_Response):
    """Why one combination failed."""

    field: str = Field(description="Offending field, dotted path inside the request.")
    detail: str | None = Field(description="The rule it broke.")


class BatchResultItem(_Response):
    """The result of one combination: the prediction fields (status ok) or an error."""

    id: str | None = Field(description="The combination's id as sent.")
    status: Literal["ok", "error"]
    error: ItemError | None = None
    frequency_hz: list[float] | None = Field(None, description="Frequency lines, Hz (status ok).")
    tool_point: ToolPoint | None = None
    natural_frequencies_hz: list[float] | None = Field(None, description="Natural frequencies, Hz.")
    peaks: list[Peak] | None = None
    static_stiffness_n_m: float | None = Field(None, description="Static stiffness, N/m.")
    min_real_m_n: float | None = Field(None, description="Most negative real part of h, m/N.")


class BatchSummary(_Response):
    ok: int = Field(description="Combinations computed.")
    error: int = Field(description="Combinations refused.")


class BatchResult(_Response):
    """One result per combination, in input order."""

    results: list[BatchResultItem]
    summary: BatchSummary


class JobStatus(_Response):
    """State of a background job (202 answers and GET /v1/jobs/{id})."""

    id: str = Field(description="Job id.", examples=["j-0123456789abcdef0123456789abcdef"])
    kind: str = Field(description="batch or library.")
    status: Literal["queued", "running", "succeeded", "failed"]
    progress: float = Field(ge=0, le=1, description="Fraction done (0…1).")
    created_utc: str
    started_utc: str | None
    finished_utc: str | None
    attempts: int = Field(description="Runs started (a run interrupted by a restart is resumed).")
    error: dict[str, Any] | None = Field(description="Problem document when failed.")
    summary: dict[str, Any] | None = Field(description="Counts by status when succeeded.")
    status_url: str = Field(description="Poll here.")
    result_url: str | None = Field(description="The result, once succeeded.")


# --------------------------------------------------------------------------- libraries

class LibraryOptions(_Request):
    """How a library is mapped to combinations (shaft_origin, default_holder: Fusion; stickout_m: FreeCAD)."""

    holder_material: str | None = Field(None, description="Material of every holder segment (default steel).")
    tool_material_default: str | None = Field(None, description="Tool material when BMC is missing (default "
                                              "carbide).")
    holder_segments_per_cone: int | None = Field(None, ge=1, le=MAX_HOLDER_SEGMENTS_PER_CONE, description="Cylinders per conical holder "
                                                 "segment (default: from each cone's taper, within 0.5 % of the cone).")
    fluted_diameter_ratio: float | None = Field(None, ge=MIN_FLUTED_DIAMETER_RATIO, le=1,
                                                description="Equivalent fluted diameter / DC.")
    shaft_origin: Literal["shoulder", "flute_end"] | None = Field(None, description="Where shaft.segments start.")
    default_holder: str | dict[str, Any] | None = Field(None, description="Holder for tools without one: the guid "
                                                        "of a standalone holder in the library, or a Fusion "
                                                        "holder object.")
    stickout_m: float | dict[str, float] | None = Field(None, description="FreeCAD (required there): the "
                                                        "stickout of every toolbit, m, or {toolbit id: m}.")


class LibraryPredictionRequest(_Request):
    """JSON form of POST /v1/tool-libraries:predict (the multipart form carries the same fields)."""

    library: dict[str, Any] = Field(description='The Fusion tool library document {"data": [...], "version": n}, '
                                                'or FreeCAD toolbits {"format": "freecad", "toolbits": {"<id>": '
                                                '{.fctb}}, "holder": {"<id>": {.fcholder}}, "library": {.fctl}}.')
    spindle: Spindle
    frequency: Frequency
    joints: Joints | None = Field(None, description="Joints applied to every tool (the library has none); "
                                  "rigid when left out.")
    materials: dict[str, Material] | None = None
    beam_theory: BeamTheory | None = None
    shear_coefficient: ShearCoefficient | None = None
    natural_frequencies: bool | None = Field(None, description="Compute exact natural frequencies (default true).")
    options: LibraryOptions | None = None


class LibraryResultItem(_Response):
    """One library item: its prediction (ok), why it was skipped, or its error."""

    id: str = Field(description="Fusion guid, else T<number>, else a content hash.")
    index: int = Field(description="Position in the library's data list.")
    description: str | None = None
    number: int | None = Field(None, description="Fusion T number.")
    teeth: int | None = Field(None, description="Number of flutes NOF.")
    tool_type: str | None = None
    warnings: list[str] = Field(default_factory=list)
    status: Literal["ok", "skipped", "error"]
    reason: str | None = Field(None, description="Why it was skipped.")
    error: ItemError | None = None


class LibraryResult(_Response):
    """One result per library item, in library order."""

    library: dict[str, Any] = Field(description="source, library_sha256, import summary.")
    results: list[LibraryResultItem]
    summary: dict[str, int] = Field(description="Counts of ok, skipped, error.")


# --------------------------------------------------------------------------- measurements

class ComplexArrayIn(_Request):
    """A complex array as two real arrays of equal length."""

    real: list[FrfValue] = Field(description="Real parts.")
    imag: list[FrfValue] = Field(description="Imaginary parts.")


_OUTPUT_ONLY = ("id", "created_utc", "software_version", "source", "frfs", "n_frequencies",
                "frequency_min_hz", "frequency_max_hz", "units", "convention", "summary")


class MeasurementUpload(_Request):
    """A measurement in the contract's JSON form (body of POST /v1/measurements, JSON)."""

    model_config = ConfigDict(extra="allow", json_schema_extra={
        "examples": [{"spindle_id": "mc1-hsk63", "direction": "x", "plane": "spindle_nose", "kind": "direct_frf",
                      "frequency_hz": [100.0, 200.0, 300.0],
                      "h": {"real": [1.0e-7, 1.1e-7, 1.3e-7], "imag": [-1.0e-9, -2.0e-9, -4.0e-9]}}],
        "patternProperties": {"^h[1-9][1-9]$": {"$ref": "#/components/schemas/ComplexArrayIn"}}})
    __pydantic_extra__: dict[str, ComplexArrayIn]

    spindle_id: str = Field(min_length=1, max_length=128, description="Spindle (or spindle + holder) id.")
    direction: Literal["x", "y"] = Field(description="Machine direction of this measurement.")
    plane: Literal["spindle_nose", "holder_tip"] = Field(description="Coupling plane of the receptances.")
    kind: Literal["point_receptance", "artifact_frfs", "direct_frf"]
    machine: str | None = Field(None, max_length=128, description="Machine tool name.")
    notes: str | None = Field(None, max_length=10_000)
    frequency_hz: list[FrequencyValue] = Field(min_length=1, description="Frequency lines, Hz, strictly increasing, > 0.")
    h: ComplexArrayIn | None = Field(None, description="Receptance h, m/N (point_receptance, direct_frf).")
    l: ComplexArrayIn | None = Field(None, description="Receptance l, m/(N·m) (point_receptance).")  # noqa: E741
    n: ComplexArrayIn | None = Field(None, description="Receptance n, rad/N (point_receptance).")
    p: ComplexArrayIn | None = Field(None, description="Receptance p, rad/(N·m) (point_receptance).")
    points_m: list[Annotated[float, Field(le=MAX_LENGTH_M)]] | None = Field(None, description="artifact_frfs: positions of points 1, 2, ... from "
                                         "the artifact tip toward the spindle, m. The FRFs themselves are h11, "
                                         "h21, h22, ... (m/N), named h<response><excitation>.")
    artifact: dict[str, Any] | None = Field(None, description="artifact_frfs: diameter_m, stickout_m, and where "
                                            "known length_m, inner_diameter_m, material, holder.")
    coherence: list[Coherence] | dict[str, list[Coherence]] | None = Field(None, description="Coherence (0…1): a list "
                                                                   "for h alone, or lists by FRF name.")
    # accepted back from GET /v1/measurements/{id}, so an export can be uploaded again (new id)
    id: str | None = Field(None, description="Ignored (an upload gets a new id).")
    created_utc: str | None = Field(None, description="Ignored.")
    software_version: str | None = Field(None, description="Ignored.")
    source: dict[str, Any] | None = Field(None, description="Provenance of an exported measurement (kept).")
    frfs: list[str] | None = Field(None, description="Ignored.")
    n_frequencies: int | None = Field(None, description="Ignored.")
    frequency_min_hz: float | None = Field(None, description="Ignored.")
    frequency_max_hz: float | None = Field(None, description="Ignored.")
    units: dict[str, str] | None = Field(None, description="Ignored (uploads are SI).")
    convention: str | None = Field(None, description="Ignored (the contract's convention).")
    summary: dict[str, Any] | None = Field(None, description="Ignored.")

    @model_validator(mode="before")
    @classmethod
    def _only_artifact_frf_names(cls, data: Any) -> Any:
        if isinstance(data, dict):
            for key in data:
                if key not in cls.model_fields and not re.fullmatch(r"h[1-9][1-9]", str(key)):
                    raise PydanticCustomError(
                        "unknown_field", "unknown field; artifact FRFs are named h<response><excitation>, "
                        "e.g. h21, and the other fields are listed in the schema at /docs", {"field": str(key)})
        return data

    def to_document(self) -> dict[str, Any]:
        """The contract JSON document for :func:`rcsa.measured.importers.measurement_from_contract`."""
        doc = self.model_dump(exclude_none=True)
        for key in ("id", "created_utc", "software_version", "frfs", "n_frequencies", "frequency_min_hz",
                    "frequency_max_hz", "units", "convention", "summary"):
            doc.pop(key, None)
        return doc


class MeasurementSource(_Response):
    """Provenance of a measurement."""

    format: str = Field(description="uff58, csv, cutpro_frf, contract_json, tap or api.")
    file: str = Field(description="Uploaded file name.")
    sha256: str = Field(description="SHA-256 of the uploaded file.")
    original_quantity: str = Field(description="receptance, mobility or accelerance.")
    original_units: str = Field(description="Units the file carried, e.g. um/N.")
    conversions: list[str] = Field(description="Steps applied on import.")
    sensor_mass_kg: float | None = Field(description="Accelerometer mass removed, kg.")


class MeasurementInfo(_Response):
    """A stored measurement's metadata."""

    id: str = Field(examples=["m-0123456789ab"])
    spindle_id: str
    machine: str
    direction: Literal["x", "y"]
    plane: Literal["spindle_nose", "holder_tip"]
    kind: Literal["point_receptance", "artifact_frfs", "direct_frf"]
    frfs: list[str] = Field(description="Names of the stored receptances.")
    n_frequencies: int = Field(description="Number of frequency lines.")
    frequency_min_hz: float = Field(description="First frequency, Hz.")
    frequency_max_hz: float = Field(description="Last frequency, Hz.")
    points_m: list[float] | None = Field(description="artifact_frfs point positions, m.")
    artifact: dict[str, Any] | None
    notes: str
    created_utc: str | None
    software_version: str | None
    source: MeasurementSource


class MeasurementPage(_Response):
    """One page of the store listing, oldest first."""

    items: list[MeasurementInfo]
    next_cursor: str | None = Field(description="Pass as ?cursor= for the next page; null on the last page.")


class MeasurementDocument(MeasurementInfo):
    """Metadata and data in the contract JSON form (receptances as h, l, n, p or hij: {real, imag})."""

    units: dict[str, str] = Field(description="Unit of every array.")
    convention: str = Field(description="Sign and axis conventions of the receptances.")
    summary: dict[str, Any] = Field(description="Peak magnitude and frequency of every FRF.")
    frequency_hz: list[float] | None = Field(None, description="Frequency lines, Hz (absent with data=false).")


class Deleted(_Response):
    deleted: str = Field(description="Id of the deleted measurement.")


# --------------------------------------------------------------------------- stability lobes

class FrfIn(_Request):
    """An inline tool-point FRF."""

    frequency_hz: list[FrequencyValue] = Field(min_length=1, description="Frequency lines, Hz.")
    h: ComplexArrayIn = Field(description="Tool-point receptance, m/N.")


class SpeedRange(_Request):
    """Spindle-speed grid: count values from start to stop."""

    start: float = Field(ge=MIN_SPEED_RPM, le=MAX_SPEED_RPM, description="Lowest spindle speed, rpm.")
    stop: float = Field(ge=MIN_SPEED_RPM, le=MAX_SPEED_RPM, description="Highest spindle speed, rpm.")
    count: int = Field(ge=MIN_SPEED_COUNT, le=MAX_SPEED_COUNT, description="Number of speeds.")


class LobesRequest(_Request):
    """Stability-lobes request (contract "Stability lobes"): inline FRFs or an assembly."""

    model_config = ConfigDict(json_schema_extra={"examples": [{
        "assembly": _RA1, "teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3,
        "radial_immersion": 0.5, "milling": "down", "spindle_speed_rpm": {"start": 2000, "stop": 30000,
                                                                          "count": 2000}}]})

    frf_x: FrfIn | None = Field(None, description="Tool-point FRF in x (or give assembly).")
    frf_y: FrfIn | None = Field(None, description="FRF in y on the same grid; null: same as x.")
    assembly: Assembly | None = Field(None, description="Predict the FRF of this assembly instead.")
    teeth: int = Field(ge=1, le=MAX_TEETH, description="Number of teeth (flutes).")
    tangential_coefficient_n_m2: float = Field(ge=MIN_CUTTING_COEFFICIENT_N_M2, le=MAX_CUTTING_COEFFICIENT_N_M2,
                                               description="Tangential cutting coefficient Kt, N/m².")
    radial_ratio: float = Field(ge=0, le=MAX_RADIAL_RATIO, description="Radial to tangential coefficient ratio Kr "
                                                                       "(dimensionless).")
    radial_immersion: float = Field(ge=MIN_RADIAL_IMMERSION, le=1, description="Radial immersion ae/D "
                                                                                "(dimensionless).")
    milling: Literal["up", "down"]
    spindle_speed_rpm: SpeedRange


class Lobe(_Response):
    index: int = Field(description="Lobe number k.")
    spindle_speed_rpm: list[float | None] = Field(description="Spindle speeds, rpm.")
    depth_limit_m: list[float | None] = Field(description="Depth limit of this lobe, m (null: none).")


class LobesResult(_Response):
    """Stability lobes: the lower envelope and every lobe."""

    spindle_speed_rpm: list[float | None] = Field(description="Spindle speeds, rpm.")
    depth_limit_m: list[float | None] = Field(description="Axial depth limit (lower envelope), m.")
    chatter_frequency_hz: list[float | None] = Field(description="Chatter frequency at the limit, Hz.")
    lobes: list[Lobe]


# --------------------------------------------------------------------------- problems, health

class FieldProblem(_Response):
    field: str = Field(description="Offending field, dotted path ('' for the whole request).")
    detail: str = Field(description="What it must satisfy.")


class Problem(_Response):
    """RFC 9457 problem details (application/problem+json)."""

    type: str = Field(description="Kind of problem (a URN).", examples=["urn:rcsa:problem:invalid-input"])
    title: str
    status: int
    detail: str = Field(description="What went wrong and what to do.")
    instance: str | None = Field(None, description="The request path.")
    request_id: str | None = Field(None, description="X-Request-ID of the request (find it in the logs).")
    errors: list[FieldProblem] | None = None


class Health(_Response):
    status: Literal["ok"]


class Ready(_Response):
    status: Literal["ready", "not ready"]
    checks: dict[str, str] = Field(description="Outcome of each readiness check.")


# --------------------------------------------------------------------------- stored libraries (issue 8)

class SyncReport(_Response):
    """What a library sync did, per tool id (Fusion guid when present)."""

    library_id: str = Field(description="The library synced.")
    revision: int = Field(description="The library's revision after this sync (1 for the first).")
    synced_utc: str
    added: list[str] = Field(description="Tool ids new in this sync.")
    changed: list[str] = Field(description="Tool ids whose result inputs (or skip/error reason) changed.")
    unchanged: list[str] = Field(description="Tool ids whose result inputs are as in the previous sync.")
    removed: list[str] = Field(description="Tool ids of the previous sync that are gone.")
    counts: dict[str, int] = Field(description="Number of added, changed, unchanged, removed tools.")
    computed: int = Field(description="Results computed by this sync (the others came from the result cache).")
    from_cache: int = Field(description="Tools whose result was already computed.")
    summary: dict[str, int] = Field(description="Tools by status: ok, skipped, error.")
    failed: list[dict[str, Any]] = Field(description="{id, error: {field, detail}} of every tool in error.")
    library_url: str | None = Field(None, description="GET the library here.")
    results_url: str | None = Field(None, description="GET its results here (JSON, HDF5 or zip of UFF 58).")


class LibraryTool(LibraryResultItem):
    """One item of a stored library: its status and the key of its stored result."""

    result_sha256: str | None = Field(None, description="Content hash its result is filed under.")
    revision: int = Field(description="Library revision in which this tool last changed.")


class LibrarySummary(_Response):
    """A stored library: settings, frequency grid, counts, last sync and (GET by id) its tools."""

    id: str
    revision: int
    created_utc: str
    synced_utc: str
    source: str = Field(description="File name (or <mapping>) of the last synced export.")
    library_sha256: str = Field(description="SHA-256 of the last synced library's canonical JSON.")
    settings: dict[str, Any] = Field(description="Spindle, frequency, materials, joints, options of the last sync.")
    measurement_sha256: str | None = Field(description="Content hash of the spindle measurement (hybrid).")
    frequency: dict[str, Any] = Field(description="n_lines, min_hz, max_hz, sha256 of the grid.")
    model_version: str = Field(description="Fingerprint of the model that computed the results (SHA-256 of its "
                               "source; older libraries: a version number).")
    software_version: str
    summary: dict[str, int] = Field(description="Tools by status: ok, skipped, error.")
    last_sync: SyncReport
    tools: list[LibraryTool] | None = Field(None, description="Every tool, in library order (GET by id only).")


class RecommendedFile(_Response):
    """The library with the presets written in (same format and name as uploaded)."""

    file_name: str
    media_type: str = Field(description="application/json (.json) or application/zip (.tools).")
    size_bytes: int
    sha256: str
    content_base64: str = Field(description="The file's bytes, base64.")


class RecommendedTool(_Response):
    """One library item: the preset written (speed, depth, pocket), or why not."""

    id: str | None = None
    index: int | None = None
    description: str | None = None
    number: int | None = None
    tool_type: str | None = None
    status: Literal["written", "skipped", "failed"]
    reason: str | None = Field(None, description="Why skipped or failed.")
    spindle_speed_rpm: int | None = Field(None, description="The preset's n, rpm.")
    stepdown_m: float | None = Field(None, description="The axial depth allowed, m (the preset's stepdown, in the "
                                                        "tool's unit, rounds it down).")
    depth_limit_m: float | None = Field(None, description="The smallest depth limit within the speed window, m.")
    safety_factor: float | None = None
    robust_depth_limit_m: float | None = Field(None, description="The robust limit used, when uncertainty is given.")
    pocket: dict[str, float] | None = Field(None, description="low_rpm, high_rpm, width_rpm of the stable pocket.")
    lobe_method: str | None = None


class RecommendReport(_Response):
    """Chatter-safe presets written into a Fusion library, and how each was chosen."""

    library_id: str
    library: dict[str, Any] = Field(description="file_name, format, sha256_before, sha256_after.")
    frf_source: dict[str, Any] = Field(description="Where the tool-point FRFs came from (the stored sync).")
    options: dict[str, Any] = Field(description="Material, cutting coefficients and their source, speed range, "
                                                "rule parameters.")
    rule: dict[str, Any] = Field(description="The pocket rule.")
    preset_name: str
    summary: dict[str, int] = Field(description="Tools by status: written, skipped, failed.")
    tools: list[RecommendedTool]
    file: RecommendedFile


class LibraryList(_Response):
    """Every stored library (without the per-tool lists)."""

    libraries: list[LibrarySummary]

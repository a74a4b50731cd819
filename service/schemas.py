"""Request and response models of the REST API (pydantic), field names as in ``docs/contract.md``.

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
    create_model,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from rcsa.app.bounds import (
    ANALYSIS_MAX_MEASUREMENTS,
    DIAGNOSIS_EFFECTS,
    DIAGNOSIS_LIKELIHOODS,
    DIAGNOSIS_OPTION_BOUNDS,
    DIAGNOSIS_TOLERANCES,
    EFFECTS_MAX_RELATIVE_STEP,
    IDENTIFIABLE_PARAMETERS,
    IDENTIFICATION_MIN_LINES,
    MAX_BATCH_COMBINATIONS,
    MAX_BEARINGS,
    MAX_COHERENCE,
    MAX_CONFIDENCE,
    MAX_CONTACT_ARC_DEG,
    MAX_CONTACT_PRESSURE_PA,
    MAX_CUTTING_COEFFICIENT_N_M2,
    MAX_DAMPING,
    MAX_DENSITY_KG_M3,
    MAX_DIAMETER_M,
    MAX_FREQUENCY_HZ,
    MAX_FREQUENCY_LINES,
    MAX_FRF_VALUE,
    MAX_HOLDER_SEGMENTS_PER_CONE,
    MAX_INTERFACE_STIFFNESS_N_M3,
    MAX_INTERFACE_STIFFNESS_SCALE,
    MAX_INTERFACE_TANGENTIAL_RATIO,
    MAX_LENGTH_M,
    MAX_LOSS_FACTOR,
    MAX_MODAL_DAMPING_RATIO,
    MAX_MODAL_FREQUENCY_HZ,
    MAX_MODAL_MASS_KG,
    MAX_MODAL_STIFFNESS_N_M,
    MAX_MODAL_TABLE_MODES,
    MAX_MODULUS_PA,
    MAX_NECK_SEGMENTS,
    MAX_POISSON_RATIO,
    MAX_RADIAL_RATIO,
    MAX_SEGMENTS,
    MAX_SENSOR_MASS_KG,
    MAX_SHEAR_COEFFICIENT,
    MAX_SPEED_COUNT,
    MAX_SPEED_RPM,
    MAX_STIFFNESS,
    MAX_SURFACE_ROUGHNESS_M,
    MAX_TEETH,
    MAX_TOLERANCE,
    MAX_UNCERTAINTY_DRAWS,
    MAX_UNCERTAINTY_SEED,
    MIN_CONFIDENCE,
    MIN_CONTACT_ARC_DEG,
    MIN_CONTACT_PRESSURE_PA,
    MIN_CUTTING_COEFFICIENT_N_M2,
    MIN_DENSITY_KG_M3,
    MIN_FLUTED_DIAMETER_RATIO,
    MIN_FREQUENCY_HZ,
    MIN_INTERFACE_STIFFNESS_N_M3,
    MIN_INTERFACE_STIFFNESS_SCALE,
    MIN_INTERFACE_TANGENTIAL_RATIO,
    MIN_JOINT_STIFFNESS,
    MIN_LENGTH_M,
    MIN_MODAL_DAMPING_RATIO,
    MIN_MODAL_FREQUENCY_HZ,
    MIN_MODAL_MASS_KG,
    MIN_MODAL_STIFFNESS_N_M,
    MIN_MODULUS_PA,
    MIN_POISSON_RATIO,
    MIN_RADIAL_IMMERSION,
    MIN_RELATIVE_STEP,
    MIN_SHEAR_COEFFICIENT,
    MIN_SPEED_COUNT,
    MIN_SPEED_RPM,
    MIN_SURFACE_ROUGHNESS_M,
    MIN_UNCERTAINTY_DRAWS,
    SDM_DEFAULT_MODES_PER_DIRECTION,
    SDM_MAX_MODES_PER_DIRECTION,
    SDM_MAX_STEPS_PER_PERIOD,
    SDM_MIN_MODES_PER_DIRECTION,
    SDM_MIN_STEPS_PER_PERIOD,
    TOOL_OVERRIDES,
    UNCERTAINTY_SOLVERS,
)
from rcsa.app.predictions import example_assembly

from .field_errors import UNION_TAGS, pydantic_errors

__all__ = [
    "Assembly",
    "PredictionRequest",
    "Robust",
    "Uncertainty",
    "BatchRequest",
    "BatchResult",
    "DiagnosisRequest",
    "DiagnosisResult",
    "EffectsRequest",
    "EffectsResult",
    "IdentificationRequest",
    "IdentificationResult",
    "JobPage",
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
_RA1 = example_assembly("ra1", _EXAMPLE_GRID)


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


def _keyed_union(absent: type[BaseModel], absent_tag: str, present: type[BaseModel], present_tag: str, key: str,
                 kind: str, message: str) -> Any:
    """One of two request models, told apart by whether ``key`` is given: the union (tags in
    :data:`service.field_errors.UNION_TAGS`, which keeps them out of the fields errors name) and a
    one-line error when neither fits."""
    if not {absent_tag, present_tag} <= UNION_TAGS:
        raise ValueError(f"add {absent_tag!r} and {present_tag!r} to service.field_errors.UNION_TAGS")

    def tag(value: Any) -> str | None:
        if isinstance(value, dict):
            return present_tag if key in value else absent_tag
        if isinstance(value, present):
            return present_tag
        return absent_tag if isinstance(value, absent) else None

    return Annotated[Annotated[absent, Tag(absent_tag)] | Annotated[present, Tag(present_tag)],  # type: ignore[valid-type]
                     Discriminator(tag, custom_error_type=kind, custom_error_message=message)]


Frequency = Annotated[
    _keyed_union(FrequencyRange, "frequency-range", FrequencyValues, "frequency-values", "values_hz", "frequency",
                 "must be an object {start_hz, stop_hz, step_hz} or {values_hz}"),
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
    outer_diameter_m: float = Field(ge=MIN_LENGTH_M, le=MAX_DIAMETER_M, description="Outer diameter, m.")
    inner_diameter_m: float = Field(0.0, ge=0, le=MAX_DIAMETER_M, description="Bore diameter, m (0: solid); < outer_diameter_m.")
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

    segments: list[Segment] = Field(min_length=1, max_length=MAX_SEGMENTS, description="Shaft segments, nose → rear.")
    bearings: list[Bearing] = Field(default_factory=list, max_length=MAX_BEARINGS,
                                    description="Bearings (positions from the nose).")


class MeasuredSpindle(_Request):
    """A stored measured spindle (hybrid prediction)."""

    measurement_id: str = Field(min_length=1, description="Id of a stored measurement (GET /v1/measurements).",
                                examples=["m-0123456789ab"])
    artifact_method: Literal["exact", "finite_difference"] = Field(
        "exact", description="How an artifact_frfs measurement is identified: the exact three-FRF method, or "
                             "the labelled finite-difference fallback.")
    effective_length_m: float = Field(0.2, ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Equivalent-cantilever length used to estimate the "
                                                             "rotations of a direct_frf measurement, m.")


Spindle = Annotated[
    _keyed_union(AnalyticalSpindle, "spindle-analytical", MeasuredSpindle, "spindle-measured", "measurement_id",
                 "spindle", "must be an object {segments, bearings} or {measurement_id}"),
    Field(description="The spindle: modelled (segments + bearings) or a stored measurement (hybrid)."),
]


class Holder(_Request):
    """Tool holder: segments from the gauge line toward the tool end."""

    segments: list[Segment] = Field(min_length=1, max_length=MAX_SEGMENTS,
                                    description="Holder segments, gauge line → tool end; inner_diameter_m is the bore.")


class NeckSegment(_Request):
    """One piece of a stepped (or stepped-conical) neck."""

    length_m: float = Field(ge=MIN_LENGTH_M, description="Length of the piece, m (all pieces together at most "
                                                         "stickout_m − flute_length_m).")
    diameter_m: float = Field(ge=MIN_LENGTH_M, le=MAX_DIAMETER_M, description="Its diameter, m.")


class Tool(_Request):
    """Parametric cutting tool (ISO 13399 / Fusion meaning)."""

    material: str = Field("carbide", min_length=1, description="Tool material name.")
    diameter_m: float = Field(ge=MIN_LENGTH_M, le=MAX_DIAMETER_M, description="Cutting diameter DC, m.")
    shank_diameter_m: float | None = Field(None, ge=MIN_LENGTH_M, le=MAX_DIAMETER_M, description="Shank diameter SFDM, m (default: diameter_m).")
    overall_length_m: float = Field(ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Overall length OAL, m.")
    flute_length_m: float = Field(ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Flute length LCF, m; <= stickout_m.")
    stickout_m: float = Field(ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Length from the holder's tool-end face to the tip (Fusion LB), m.")
    fluted_diameter_ratio: float = Field(0.8, ge=MIN_FLUTED_DIAMETER_RATIO, le=1, description="Equivalent fluted diameter / DC "
                                                                      "(dimensionless).")
    fluted_mass_diameter_ratio: float | None = Field(None, ge=MIN_FLUTED_DIAMETER_RATIO, le=1, description="Separate equivalent diameter "
                                                     "ratio for the flutes' mass (default: fluted_diameter_ratio).")
    shoulder_length_m: float | None = Field(None, ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description="Reduced neck: from the tip to the neck's end, "
                                            "m (with shoulder_diameter_m).")
    shoulder_diameter_m: float | None = Field(None, ge=MIN_LENGTH_M, le=MAX_DIAMETER_M, description="Reduced neck diameter, m.")
    neck_segments: list[NeckSegment] | None = Field(None, max_length=MAX_NECK_SEGMENTS, description=(
        "Instead of shoulder_length_m/shoulder_diameter_m: a stepped neck, pieces listed from the flute end toward "
        "the holder (a conical neck as steps); together at most stickout_m − flute_length_m long."))


class Joint(_Request):
    """Elastic joint diag(k_t + iωc_t, k_r + iωc_r); a rotational stiffness left out is rigid."""

    stiffness_n_m: float = Field(ge=MIN_JOINT_STIFFNESS, le=MAX_STIFFNESS, description="Translational stiffness k_t, N/m.")
    damping_ns_m: float = Field(0.0, ge=0, le=MAX_DAMPING, description="Translational damping c_t, N·s/m.")
    rotational_stiffness_nm_rad: float | None = Field(None, ge=MIN_JOINT_STIFFNESS, le=MAX_STIFFNESS, description="Rotational stiffness k_r, N·m/rad.")
    rotational_damping_nms_rad: float = Field(0.0, ge=0, le=MAX_DAMPING, description="Rotational damping c_r, N·m·s/rad.")


class HolderToolJoint(_Request):
    """The holder–tool joint (contract v1.2): a point joint at the holder face (``model`` "point", the
    default: the fields of Joint), or a clamping along the inserted length — ``bonded`` (ideal, from
    geometry and materials, calibrated on 3-D elasticity) or ``contact`` (the same with a finite
    interface stiffness per unit area)."""

    model: Literal["point", "bonded", "contact"] = Field("point", description=(
        "point: elastic joint diag(k_t + iωc_t, k_r + iωc_r) at the holder face; bonded: the shank bonded to "
        "the bore over the insertion (no stiffness fields); contact: bonded plus interface_stiffness_n_m3."))
    stiffness_n_m: float | None = Field(None, ge=MIN_JOINT_STIFFNESS, le=MAX_STIFFNESS, description="point: "
                                        "translational stiffness k_t, N/m (required).")
    damping_ns_m: float | None = Field(None, ge=0, le=MAX_DAMPING, description="point: translational damping c_t, N·s/m.")
    rotational_stiffness_nm_rad: float | None = Field(None, ge=MIN_JOINT_STIFFNESS, le=MAX_STIFFNESS, description=(
        "point: rotational stiffness k_r, N·m/rad (left out: rigid)."))
    rotational_damping_nms_rad: float | None = Field(None, ge=0, le=MAX_DAMPING, description="point: rotational "
                                                     "damping c_r, N·m·s/rad.")
    interface_stiffness_n_m3: float | None = Field(None, ge=MIN_INTERFACE_STIFFNESS_N_M3,
                                                   le=MAX_INTERFACE_STIFFNESS_N_M3, description=(
        "contact: normal interface stiffness per unit area, N/m³ (or contact_pressure_pa with surface_roughness_m)."))
    contact_pressure_pa: float | None = Field(None, ge=MIN_CONTACT_PRESSURE_PA, le=MAX_CONTACT_PRESSURE_PA,
                                              description="contact: nominal clamping pressure p, Pa (k_n = p/σ).")
    surface_roughness_m: float | None = Field(None, ge=MIN_SURFACE_ROUGHNESS_M, le=MAX_SURFACE_ROUGHNESS_M,
                                              description="contact: asperity height scale σ, m (k_n = p/σ).")
    interface_tangential_ratio: float | None = Field(None, ge=MIN_INTERFACE_TANGENTIAL_RATIO,
                                                     le=MAX_INTERFACE_TANGENTIAL_RATIO, description=(
        "contact: tangential over normal interface stiffness (default 1)."))
    interface_loss_factor: float | None = Field(None, ge=0, lt=MAX_LOSS_FACTOR, description="contact: hysteretic "
                                                "loss factor of the interface (default 0).")
    front_gap_length_m: float | None = Field(None, ge=0, le=MAX_LENGTH_M, description=(
        "bonded/contact: length from the holder face into the bore over which the shank does not touch, m."))
    contact_length_m: float | None = Field(None, ge=MIN_LENGTH_M, le=MAX_LENGTH_M, description=(
        "bonded/contact: length of the contact behind the front gap, m (default: the rest of the insertion)."))
    interface_stiffness_scale: float | None = Field(None, ge=MIN_INTERFACE_STIFFNESS_SCALE,
                                                    le=MAX_INTERFACE_STIFFNESS_SCALE, description=(
        "bonded/contact: a factor on the whole interface stiffness (default 1; what an identification finds)."))
    contact_arc_deg: float | None = Field(None, ge=MIN_CONTACT_ARC_DEG, le=MAX_CONTACT_ARC_DEG, description=(
        "bonded/contact: the arc of the bore's circumference the contact covers, degrees, centred on the FRF's "
        "direction (a side-lock screw pushing the shank against the back of its bore; default 360)."))
    screw_diameter_m: float | None = Field(None, ge=MIN_LENGTH_M, le=MAX_DIAMETER_M, description=(
        "bonded/contact: a side-lock screw's contact face on the shank's flat, opposite the contact's arc, m."))


class Joints(_Request):
    """The two joints; one left out is rigid."""

    spindle_holder: Joint | None = Field(None, description="Spindle nose ↔ holder base (gauge line).")
    holder_tool: HolderToolJoint | None = Field(None, description="Holder tip ↔ tool base (holder face): a point "
                                                "joint, or a clamping along the insertion (model bonded/contact).")


BeamTheory = Literal["timoshenko", "euler_bernoulli"]
ShearCoefficient = Literal["hutchinson", "cowper"] | Annotated[float, Field(ge=MIN_SHEAR_COEFFICIENT,
                                                                          le=MAX_SHEAR_COEFFICIENT)]


class Uncertainty(_Request):
    """Uncertainty band (contract v1.1): the assembly drawn under the diagnosis's tolerances."""

    draws: int = Field(200, ge=MIN_UNCERTAINTY_DRAWS, le=MAX_UNCERTAINTY_DRAWS, description="Monte-Carlo draws "
                       "(draws × frequency lines bounded too).")
    seed: int = Field(0, ge=0, le=MAX_UNCERTAINTY_SEED, description="Seed of the draws (same seed, same band).")
    tolerances: dict[str, Annotated[float, Field(ge=0, le=MAX_TOLERANCE)]] | None = Field(
        None, description="Tolerance by name (as the diagnosis's tolerances; a measured spindle adds its "
                          "measurement uncertainty); left out: the defaults.")
    solver: Literal[UNCERTAINTY_SOLVERS] = Field(  # type: ignore[valid-type]
        "reduced", description="How the draws are solved: 'reduced' (default) — each draw exactly on a few "
                               "percent of the lines and fitted rationally, its error checked on held-out lines "
                               "(a draw that fails the check is solved on every line); 'exact' — every draw on "
                               "every line.")


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


class PredictionRequest(Assembly):
    """Body of POST /v1/tool-point-frf: an assembly, optionally with an uncertainty band."""

    uncertainty: Uncertainty | None = Field(None, description="Add an uncertainty band to the prediction "
                                            "(p05/p50/p95 of |h|, mean/sd of the natural frequencies).")


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
    uncertainty: Uncertainty | None = Field(None, description="Every combination's uncertainty band (same seed).")
    combinations: list[Annotated[Combination, WrapValidator(_keep_invalid)]] = Field(
        min_length=1, max_length=MAX_BATCH_COMBINATIONS,
        description=f"Combinations (at most RCSA_MAX_BATCH_COMBINATIONS, itself at most {MAX_BATCH_COMBINATIONS}; "
                    "a longer list is refused before any item is looked at). Each is checked on its own: one that "
                    "is invalid gets status error in its result.")

    @field_validator("combinations", mode="before")
    @classmethod
    def _few_enough(cls, combos: Any) -> Any:
        """Refuse too many combinations before any of them is validated (pydantic's own length
        check comes after the items)."""
        if isinstance(combos, list) and len(combos) > MAX_BATCH_COMBINATIONS:
            raise PydanticCustomError("too_long", f"at most {MAX_BATCH_COMBINATIONS} per batch, got {len(combos)}; "
                                                  "split the batch")
        return combos

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
    result_bytes: int | None = Field(None, description="Size of the result (JSON), bytes, once succeeded.")
    result_evicted_utc: str | None = Field(None, description="When the result was deleted to keep the kept "
                                           "results within their disk budget (RCSA_JOB_RESULTS_MAX_BYTES).")
    status_url: str = Field(description="Poll here.")
    result_url: str | None = Field(description="The result, once succeeded (and while it is kept).")
    job_token: str | None = Field(None, description="Anonymous submissions (202) only: the token to send in "
                                  "X-Job-Token to read this job (and to list it); also in the X-Job-Token header.")


class JobPage(_Response):
    """One page of your jobs, newest first."""

    items: list[JobStatus]
    next_cursor: str | None = Field(description="Pass as ?cursor= for the next page; null on the last page.")


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
    holder_tool: Literal["point", "bonded"] | HolderToolJoint | None = Field(None, description=(
        "Every tool's holder–tool clamping, replacing the joints' own: a model name, or a joints.holder_tool "
        "object (contact with its interface stiffness)."))
    materials: dict[str, Material] | None = None
    beam_theory: BeamTheory | None = None
    shear_coefficient: ShearCoefficient | None = None
    natural_frequencies: bool | None = Field(None, description="Compute exact natural frequencies (default true).")
    options: LibraryOptions | None = None
    uncertainty: Uncertainty | None = Field(None, description="Every tool's uncertainty band (same seed).")


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
    frequency_hz: list[FrequencyValue] = Field(min_length=1, max_length=MAX_FREQUENCY_LINES,
                                               description="Frequency lines, Hz, strictly increasing, > 0.")
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
    damaged: list[str] | None = Field(None, description="Ids of stored measurement files that cannot be read "
                                      "(left out of items; GET one for the reason, `rcsa store check` for all).")


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

    frequency_hz: list[FrequencyValue] = Field(min_length=1, max_length=MAX_FREQUENCY_LINES,
                                               description="Frequency lines, Hz.")
    h: ComplexArrayIn = Field(description="Tool-point receptance, m/N.")


class StoredFrf(_Request):
    """A stored measurement's driving-point receptance h, used as the tool-point FRF as it is."""

    measurement_id: str = Field(min_length=1, max_length=200, description="Id of a stored measurement with an h "
                                "(GET /v1/measurements), e.g. a tool-tip tap test.", examples=["m-0123456789ab"])


FrfRef = _keyed_union(FrfIn, "frf-inline", StoredFrf, "frf-stored", "measurement_id", "frf",
                      "must be an object {frequency_hz, h} or {measurement_id}")


class LibraryToolRef(_Request):
    """A tool of a stored library's last sync (GET /v1/libraries/{library_id} lists them)."""

    library_id: str = Field(min_length=1, max_length=128, description="The stored library.",
                            examples=["fusion-library"])
    tool_id: str = Field(min_length=1, max_length=300, description="The tool's id in it (Fusion guid).",
                         examples=["00000000-0000-4000-8000-000000000101"])


class SpeedRange(_Request):
    """Spindle-speed grid: count values from start to stop."""

    start: float = Field(ge=MIN_SPEED_RPM, le=MAX_SPEED_RPM, description="Lowest spindle speed, rpm.")
    stop: float = Field(ge=MIN_SPEED_RPM, le=MAX_SPEED_RPM, description="Highest spindle speed, rpm.")
    count: int = Field(ge=MIN_SPEED_COUNT, le=MAX_SPEED_COUNT, description="Number of speeds.")


SpeedList = Annotated[list[Annotated[float, Field(ge=MIN_SPEED_RPM, le=MAX_SPEED_RPM)]],
                      Field(min_length=MIN_SPEED_COUNT, max_length=MAX_SPEED_COUNT,
                            description="The spindle speeds themselves, rpm, strictly increasing.")]


class ModeIn(_Request):
    """One mode of a modal table: natural frequency, damping ratio, and the modal mass or the modal stiffness."""

    frequency_hz: float = Field(ge=MIN_MODAL_FREQUENCY_HZ, le=MAX_MODAL_FREQUENCY_HZ,
                                description="Undamped natural frequency, Hz.")
    damping_ratio: float = Field(ge=MIN_MODAL_DAMPING_RATIO, le=MAX_MODAL_DAMPING_RATIO,
                                 description="Damping ratio ζ (dimensionless).")
    modal_mass_kg: float | None = Field(None, ge=MIN_MODAL_MASS_KG, le=MAX_MODAL_MASS_KG,
                                        description="Modal mass, kg (give this or stiffness_n_m).")
    stiffness_n_m: float | None = Field(None, ge=MIN_MODAL_STIFFNESS_N_M, le=MAX_MODAL_STIFFNESS_N_M,
                                        description="Modal stiffness k = (2πf)² m, N/m (give this or modal_mass_kg).")


class Robust(_Request):
    """How sure the robust depth limit is."""

    confidence: float = Field(0.95, ge=MIN_CONFIDENCE, le=MAX_CONFIDENCE, description="The robust limit holds "
                              "in this fraction of the draws (its percentile is 100 (1 - confidence)).")


class LobesRequest(_Request):
    """Stability-lobes request (contract "Stability lobes"): inline FRFs or an assembly."""

    model_config = ConfigDict(json_schema_extra={"examples": [{
        "assembly": _RA1, "teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3,
        "radial_immersion": 0.5, "milling": "down", "spindle_speed_rpm": {"start": 2000, "stop": 30000,
                                                                          "count": 2000}}]})

    frf_x: FrfRef | None = Field(None, description="Tool-point FRF in x, the feed direction, inline or a stored "
                                 "measurement's h ({\"measurement_id\": ...}); or give modal_x, assembly or library_tool.")
    frf_y: FrfRef | None = Field(None, description="FRF in y, normal to the feed in the plane of the cut, on the same "
                                                   "grid; null: the same as x (a round tool, holder and spindle).")
    modal_x: list[ModeIn] | None = Field(None, max_length=MAX_MODAL_TABLE_MODES,
                                         description="A modal table of the feed direction (x) instead of an FRF.")
    modal_y: list[ModeIn] | None = Field(None, max_length=MAX_MODAL_TABLE_MODES,
                                         description="The modal table of y; null: the same as x; []: rigid in y.")
    assembly: Assembly | None = Field(None, description="Predict the FRF of this assembly instead.")
    library_tool: LibraryToolRef | None = Field(None, description="Instead of assembly: a tool of a stored "
                                                "library, by reference (its assembly is rebuilt from the library's "
                                                "last sync and predicted; teeth default to its flute count).")
    teeth: int | None = Field(None, ge=1, le=MAX_TEETH, description="Number of teeth (flutes); required unless "
                              "library_tool gives it.")
    tangential_coefficient_n_m2: float = Field(ge=MIN_CUTTING_COEFFICIENT_N_M2, le=MAX_CUTTING_COEFFICIENT_N_M2,
                                               description="Tangential cutting coefficient Kt, N/m².")
    radial_ratio: float = Field(ge=0, le=MAX_RADIAL_RATIO, description="Radial to tangential coefficient ratio Kr "
                                                                       "(dimensionless).")
    radial_immersion: float = Field(ge=MIN_RADIAL_IMMERSION, le=1, description="Radial immersion ae/D "
                                                                                "(dimensionless).")
    milling: Literal["up", "down"]
    spindle_speed_rpm: SpeedRange | SpeedList
    uncertainty: Uncertainty | None = Field(None, description="Robust lobes: draw the assembly and give "
                                            "depth_limit_robust_m beside the nominal limit (zoa: every draw's "
                                            "lobes; semi_discretization: a reduced model of the draws).")
    robust: Robust | None = Field(None, description="Confidence of the robust limit (needs uncertainty).")
    method: Literal["zoa", "semi_discretization", "auto"] = Field(
        "auto", description="auto (default): zoa only where it is exact (even-toothed slotting, 4 teeth or more), "
                            "else semi_discretization (the response says which: method, method_reason); zoa: "
                            "zero-order (Altintas–Budak); semi_discretization: first-order semi-discretization "
                            "(time-periodic force, flip lobes) with the steps that resolve the cut, every speed "
                            "checked at a second resolution (resolved).")
    steps_per_period: int | None = Field(None, ge=SDM_MIN_STEPS_PER_PERIOD, le=SDM_MAX_STEPS_PER_PERIOD,
                                         description="SDM only: fixed steps over the whole tooth period instead of "
                                                     "the steps that resolve the cut (each speed is still checked: "
                                                     "resolved).")
    modes_per_direction: int | None = Field(None, ge=SDM_MIN_MODES_PER_DIRECTION, le=SDM_MAX_MODES_PER_DIRECTION,
                                            description=f"SDM only: at most this many modes in x and in y (default "
                                                        f"{SDM_DEFAULT_MODES_PER_DIRECTION}).")


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
    notes: list[str] | None = Field(None, description="Caveats: speeds whose semi-discretization limit is not "
                                                      "resolved, modes left out, an FRF grid too coarse for "
                                                      "zero-order lobes.")
    method: str | None = Field(None, description="The method used: zoa or semi_discretization.")
    method_reason: str | None = Field(None, description="Why auto chose it.")
    resolved: list[bool] | None = Field(None, description="Semi-discretization: per speed, whether the limits at two "
                                                          "resolutions agree within 1 % (false: do not trust it).")
    discretization: dict[str, Any] | None = Field(None, description="Semi-discretization: scheme (cut_window or "
                                                                    "full_period), steps and check_steps per speed.")
    flute_length_m: float | None = Field(None, description="The assembly tool's flute length, m: no stepdown "
                                                           "exceeds it.")


# --------------------------------------------------------------------------- analyses (diagnoses, identifications, effects)

def _no_null_default(schema: dict[str, Any]) -> None:
    """Leave out ``"default": null`` where null is not allowed (the field is optional, not nullable)."""
    for prop in schema.get("properties", {}).values():
        nullable = prop.get("type") == "null" or any(b.get("type") == "null" for b in prop.get("anyOf", ()))
        if "default" in prop and prop["default"] is None and not nullable:
            del prop["default"]


class _AnalysisRequest(_Request):
    model_config = ConfigDict(json_schema_extra=_no_null_default)


def _tool_override_fields() -> dict[str, Any]:
    """The tool fields a tap test may override: as in :class:`Tool`, each optional."""
    out: dict[str, Any] = {}
    for name in TOOL_OVERRIDES:
        info = Tool.model_fields[name]
        out[name] = (info.annotation, Field(None, description=info.description, json_schema_extra=None,
                                            **_constraints(info)))
    return out


def _constraints(info: Any) -> dict[str, Any]:
    """The numeric and length constraints of a pydantic field, as ``Field`` keyword arguments."""
    keys = ("ge", "gt", "le", "lt", "min_length", "max_length")
    return {k: getattr(m, k) for m in info.metadata for k in keys if getattr(m, k, None) is not None}


ToolOverrides = create_model(  # type: ignore[call-overload]
    "ToolOverrides", __base__=_AnalysisRequest,
    __doc__="The base assembly's tool fields that differ in this measurement (typically stickout_m); "
            "the same meaning, units and bounds as in Tool.",
    **_tool_override_fields())


class TapTest(_AnalysisRequest):
    """A measured tool-point receptance of the base assembly with some tool fields overridden."""

    tool: ToolOverrides | None = Field(None, description="Overrides of assembly.tool for this measurement, "
                                       "e.g. {\"stickout_m\": 0.05}; left out: the base tool.")
    frequency_hz: list[FrequencyValue] = Field(min_length=1, max_length=MAX_FREQUENCY_LINES,
                                               description="Frequency lines, Hz: strictly increasing, > 0.")
    h: ComplexArrayIn = Field(description="Measured tool-point receptance h, m/N (non-zero on every line; "
                                          "convert accelerance or mobility first, e.g. with rcsa store import).")
    coherence: list[Annotated[float, Field(ge=0, le=1)]] | None = Field(
        None, description="Ordinary coherence γ² per line (0…1).")


class DiagnosisMeasurement(TapTest):
    """One tap test of a diagnosis."""

    n_averages: float = Field(5.0, ge=1, description="Impacts averaged (sets the noise from the coherence).")
    sensor_mass_kg: float | None = Field(None, ge=0, le=MAX_SENSOR_MASS_KG, description="Accelerometer mass, kg (bounds the "
                                         "sensor_mass effect).")
    label: str = Field(None, description="Name in the report and figure (default #<index>).")  # type: ignore[assignment]


class DiagnosisTolerances(_AnalysisRequest):
    """Known imperfections of the base model (one standard deviation); left out: the defaults."""

    tool_youngs_modulus_rel: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["tool_youngs_modulus_rel"],
                                           description="Tool Young's modulus, relative (default 0.03).")
    tool_density_rel: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["tool_density_rel"],
                                    description="Tool density, relative (default 0.01).")
    structure_youngs_modulus_rel: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["structure_youngs_modulus_rel"],
                                                description="Young's modulus of spindle and holder, relative "
                                                            "(default 0.02).")
    structure_density_rel: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["structure_density_rel"],
                                         description="Density of spindle and holder, relative (default 0.01).")
    loss_factor_log: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["loss_factor_log"],
                                   description="Every material loss factor, on a ln scale (default 0.25).")
    bearing_stiffness_log: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["bearing_stiffness_log"],
                                         description="All bearing stiffnesses, ln scale (default 0.08).")
    bearing_damping_log: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["bearing_damping_log"],
                                       description="All bearing dampers, ln scale (default 0.25).")
    spindle_holder_stiffness_log: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["spindle_holder_stiffness_log"],
                                                description="Spindle–holder k_t and k_r, ln scale (default 0.15).")
    spindle_holder_damping_log: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["spindle_holder_damping_log"],
                                              description="Spindle–holder dampers, ln scale (default 0.25).")
    holder_tool_stiffness_log: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["holder_tool_stiffness_log"],
                                             description="Holder–tool k_t and k_r, ln scale, drawn per measurement "
                                                         "(re-clamping; default 0.15).")
    holder_tool_damping_log: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["holder_tool_damping_log"],
                                           description="Holder–tool dampers, ln scale, per measurement "
                                                       "(default 0.25).")
    stickout_m: float = Field(None, ge=0, le=DIAGNOSIS_TOLERANCES["stickout_m"],
                              description="Stickout setting, m, per measurement (default 0.0003).")
    spindle_effective_length_log: float = Field(
        None, ge=0, le=DIAGNOSIS_TOLERANCES["spindle_effective_length_log"],
        description="Measured direct_frf spindle: its equivalent cantilever length, ln scale (default 0.35).")
    spindle_rotation_shape_log: float = Field(
        None, ge=0, le=DIAGNOSIS_TOLERANCES["spindle_rotation_shape_log"],
        description="Measured direct_frf spindle: the shape PH/N² of its estimated rotations, ln scale "
                    "(default 0.35).")
    spindle_noise_rel: float = Field(
        None, ge=0, le=DIAGNOSIS_TOLERANCES["spindle_noise_rel"],
        description="Measured spindle stored without coherence: relative noise of its FRFs (default 0.005).")


def _option(name: str, default: float, description: str) -> Any:
    low, high = DIAGNOSIS_OPTION_BOUNDS[name]
    return Field(default, ge=low, le=high, description=description)


class DiagnosisOptions(_AnalysisRequest):
    """Decision and effort settings of a diagnosis (counts may carry a fraction: it is dropped)."""

    effects: list[Literal[DIAGNOSIS_EFFECTS]] = Field(  # type: ignore[valid-type]
        None, min_length=1, description="Candidate effects to consider (default: all).")
    held_out: list[Annotated[int, Field(ge=0)]] | None = Field(
        None, description="Indices of the measurements held out for validation (default: chosen by stickout).")
    seed: int = Field(0, ge=0, description="Seed of the Monte-Carlo draws.")
    monte_carlo_draws: float = _option("monte_carlo_draws", 200, "Draws of the tolerance Monte Carlo.")
    likelihood: Literal[DIAGNOSIS_LIKELIHOODS] = Field(  # type: ignore[valid-type]
        "student_t", description="Likelihood of the feature residuals.")
    claim_threshold: float = _option("claim_threshold", 3.0, "ln Bayes factor an effect needs to be named.")
    ambiguity_window: float = _option("ambiguity_window", 2.3, "Effects within this ln Bayes factor of the best "
                                                               "are reported as ambiguous.")
    max_effects: float = _option("max_effects", 2, "At most this many effects (1 or 2) in the verdict.")
    max_lines: float = _option("max_lines", 1200, "Analysis lines per measurement (the FRFs are decimated).")


class AnalysisAssembly(Assembly):
    """The base assembly of a diagnosis; its frequency grid is not used (each measurement has its own)."""

    model_config = ConfigDict(json_schema_extra={"examples": [{k: v for k, v in _RA1.items() if k != "frequency"}]})

    frequency: Frequency | None = None  # type: ignore[assignment]


class DiagnosisRequest(_AnalysisRequest):
    """Body of POST /v1/diagnoses (contract "Diagnosis"): a base model and tap tests of it."""

    assembly: AnalysisAssembly = Field(description="The base model (contract \"Assembly\"; frequency not used).")
    measurements: list[DiagnosisMeasurement] = Field(min_length=1, max_length=ANALYSIS_MAX_MEASUREMENTS,
                                                     description="Tap tests, typically at several stickouts.")
    tolerances: DiagnosisTolerances | None = Field(None, description="Overrides of the default tolerances.")
    options: DiagnosisOptions | None = None


class IdentificationMeasurement(TapTest):
    """One tap test of a joint identification."""

    frequency_hz: list[FrequencyValue] = Field(min_length=IDENTIFICATION_MIN_LINES, max_length=MAX_FREQUENCY_LINES,
                                               description="Frequency lines, Hz: strictly increasing, > 0.")
    id: Any = Field(None, description="Caller's label (not used by the computation).")


IdentifiableParameter = Literal[IDENTIFIABLE_PARAMETERS]  # type: ignore[valid-type]
SearchRange = Annotated[list[Annotated[float, Field(gt=0)]], Field(min_length=2, max_length=2)]


class IdentificationRequest(_AnalysisRequest):
    """Body of POST /v1/identifications (contract "Joint identification")."""

    assembly: Assembly = Field(description="The base assembly; its joints are the starting guess (elastic "
                                           "joints only are identified).")
    measurements: list[IdentificationMeasurement] = Field(min_length=1, max_length=ANALYSIS_MAX_MEASUREMENTS,
                                                          description="Measured tool-point FRFs with tool overrides.")
    bounds: dict[IdentifiableParameter, SearchRange] | None = Field(
        None, description="Search range [low, high] of a parameter (SI; must contain its start); default: "
                          "the start ÷ and × 100.")
    max_residual_to_noise: float = Field(4.0, gt=1, description="Largest accepted ratio of the fit's RMS residual "
                                                                "to the measurement noise.")


class EffectAnalysisRequest(_AnalysisRequest):
    """An effect analysis with its settings (POST /v1/effects also takes a bare assembly)."""

    assembly: Assembly
    parameters: list[str] | None = Field(None, description="Parameter names, e.g. holder_tool.stiffness_n_m, "
                                         "bearings[0].damping_ns_m, tool.stickout_m (default: every non-zero one).")
    relative_step: float = Field(0.001, ge=MIN_RELATIVE_STEP, le=EFFECTS_MAX_RELATIVE_STEP,
                                 description="Finite-difference step δ in ln(parameter).")
    band_hz: Annotated[list[Annotated[float, Field(ge=MIN_FREQUENCY_HZ)]], Field(
        min_length=2, max_length=2)] | None = Field(None, description="[start, stop] Hz: the modes analysed "
                                                                      "(default: the assembly's grid).")


EffectsRequest = Annotated[
    _keyed_union(Assembly, "effects-assembly", EffectAnalysisRequest, "effects-request", "assembly",
                 "effects_request", "must be an assembly, or an object {assembly, parameters, relative_step, band_hz}"),
    Field(description="An assembly (all parameters, its grid's band, δ = 1e-3), or {assembly, parameters, "
                      "relative_step, band_hz}."),
]


class NotApplicable(_Response):
    """Something that cannot exist on this spindle (e.g. bearings of a measured one), and why."""

    parameter: str | None = Field(None, description="The parameter (effects, identifications).")
    effect: str | None = Field(None, description="The effect (diagnoses).")
    reason: str


class GapFeature(_Response):
    """One feature of one measurement in the gap map, judged against tolerances and noise."""

    measurement: int = Field(description="Index of the measurement.")
    label: str
    stickout_m: float
    kind: str = Field(description="static, peak, antiresonance, ...")
    feature: str = Field(description="frequency, amplitude, level or compliance.")
    mode: int | None = Field(None, description="Mode number within the measurement.")
    z: float = Field(description="Departure in standard deviations of what tolerances and noise explain.")
    flagged: bool = Field(description="|z| > 3.")
    model_frequency_hz: float | None = None
    measured_frequency_hz: float | None = None
    shift_pct: float | None = Field(None, description="Measured/model frequency − 1, %.")
    peak_ratio: float | None = None
    level_ratio: float | None = None
    compliance_ratio: float | None = None


class GapBand(_Response):
    """RMS gap (dB) of one band of one measurement."""

    measurement: int
    label: str
    band: int
    start_hz: float
    stop_hz: float
    rms_db: float
    expected_rms_db: float = Field(description="What tolerances and noise explain, dB.")
    z: float
    flagged: bool


class Gap(_Response):
    """Where the measurements depart from the base model."""

    modes: list[GapFeature]
    bands: list[GapBand]
    chi2: float
    n_features: int
    chi2_per_feature: float
    p_value: float
    significant: bool
    max_abs_z: float
    worst: GapFeature
    db_rms: float = Field(description="RMS of 20 log10|h_model/h_measured| over all lines, dB.")
    summary: str


class Verdict(_Response):
    """Which unmodelled effect explains the gap."""

    effect: str = Field(description="An effect name of the contract, or none.")
    status: Literal["identified", "ambiguous", "none"]
    ambiguous_with: list[str]
    log_bayes_factor: float | None = None
    snr: float | None = None
    confirmed_on_held_out: bool | None = None
    collinear_rivals: list[dict[str, Any]] = Field(default_factory=list)
    residual_p_value: float | None = None
    sentence: str


class FittedParameter(_Response):
    """One fitted parameter of an effect (SI, see unit)."""

    value: float
    sd: float
    lo: float
    hi: float
    null: float | None = Field(None, description="The value that means 'no effect'.")
    unit: str | None = None
    at_bound: bool


class DiagnosedEffect(_Response):
    """One candidate effect: fit, evidence and gaps before and after."""

    effect: str
    log_bayes_factor: float
    posterior_probability: float | None = None
    parameters: dict[str, FittedParameter]
    physical: dict[str, float] = Field(default_factory=dict, description="The fit in physical terms.")
    snr: float | None = None
    gap_before_db: float
    gap_after_db: float
    chi2_before: float | None = None
    chi2_after: float | None = None
    held_out_gap_before_db: float | None = None
    held_out_gap_after_db: float | None = None
    held_out_gap_ratio: float | None = None
    held_out_chi2_before: float | None = None
    held_out_chi2_after: float | None = None
    confirmed_on_held_out: bool | None = None
    evidence_method: str | None = None
    residual_p_value: float | None = None
    given: str | None = Field(None, description="A second effect: the first, held at its fit.")
    proposed_model: str | None = Field(None, description="A model-form candidate (clamping_model, interface_scale): "
                                                         "the holder-tool model form it proposes (point, bonded, "
                                                         "contact).")
    corrected_h: list[ComplexArray] | None = Field(None, description="Per measurement, in request order: the "
                                                   "prediction with this effect added, m/N.")


class ModelFormAlternative(_Response):
    """One form a ``clamping_model`` candidate weighed (its evidence is their mean)."""

    model: str = Field(description="point, bonded or contact.")
    log_bayes_factor: float
    parameters: dict[str, FittedParameter] = Field(default_factory=dict)


class ModelFormCandidate(_Response):
    """A model-form candidate: another form of the holder-tool model, not an effect inside it."""

    candidate: str = Field(description="clamping_model or interface_scale.")
    proposed_model: str = Field(description="The holder-tool model form it proposes (point, bonded, contact).")
    log_bayes_factor: float = Field(description="Against the base model, at the stated tolerances.")
    log_evidence_over_best_effect: float | None = Field(None, description="ln evidence over the best effect's "
                                                                           "(positive: the form explains more).")
    parameters: dict[str, FittedParameter] = Field(default_factory=dict)
    physical: dict[str, float] = Field(default_factory=dict, description="The fit in physical terms.")
    forms: list[ModelFormAlternative] | None = None


class ModelFormProposal(_Response):
    """The model form the verdict proposes."""

    candidate: str
    model: str


class ModelForm(_Response):
    """The model-form candidates beside the effects (extension)."""

    base_model: str = Field(description="The base's holder-tool model form (point, bonded, contact).")
    candidates: list[ModelFormCandidate] = Field(default_factory=list)
    proposed: ModelFormProposal | None = Field(None, description="The form proposed as the verdict, if any.")
    sentence: str


class CalibratedModel(_Response):
    """The verdict's model with the base's own parameters moved within their tolerances to where the
    measurements put them (extension): the best prediction of what was measured."""

    effects: list[str] = Field(description="The verdict's effect(s) or model form included (none: empty).")
    h: list[ComplexArray] = Field(description="Per measurement, in request order, on its lines, m/N.")
    gap_db: float = Field(description="dB rms to the measurements on the analysis lines.")
    parameters_moved_sd: dict[str, float] = Field(description="Each nuisance parameter's move, in its own "
                                                              "stated sd.")


class DiagnosisResult(_Response):
    """The diagnosis (contract "Diagnosis"): gap map, verdict, effects and ranking."""

    gap: Gap
    verdict: Verdict
    effects: list[DiagnosedEffect] = Field(description="The verdict's effect(s), with corrected_h.")
    ranking: list[DiagnosedEffect] = Field(default_factory=list, description="Every candidate, best first "
                                                                             "(without FRFs).")
    model_form: ModelForm | None = Field(None, description="The model-form candidates beside the effects: each "
                                                            "form's ln BF, its margin over the best effect, and "
                                                            "the form proposed, if any.")
    calibrated: CalibratedModel | None = None
    not_observable_at_standstill: list[str] = Field(default_factory=list)
    not_observable_sentence: str | None = None
    not_applicable: list[NotApplicable] | None = Field(None, description="Effects that cannot exist on this "
                                                       "spindle, and why (measured spindles).")
    spindle_measurement: dict[str, Any] | None = Field(None, description="What the measured spindle is.")
    held_out: dict[str, Any] | None = None
    analysis: dict[str, Any] | None = None
    notes: list[str] = Field(default_factory=list)
    runtime_s: float | None = None


class JointUncertainty(_Response):
    stiffness_n_m: float | None = Field(None, description="Standard uncertainty, N/m.")
    damping_ns_m: float | None = Field(None, description="Standard uncertainty, N·s/m.")


class IdentifiedJoint(_Response):
    """A joint's parameters (identified, or unchanged from the start) and their uncertainty."""

    stiffness_n_m: float | None = None
    damping_ns_m: float | None = None
    rotational_stiffness_nm_rad: float | None = None
    rotational_damping_nms_rad: float | None = None
    uncertainty: JointUncertainty
    status: Literal["not_applicable"] | None = Field(None, description="Set when the joint cannot exist on this "
                                                     "spindle.")
    reason: str | None = None


class IdentifiedJoints(_Response):
    spindle_holder: IdentifiedJoint | None = None
    holder_tool: IdentifiedJoint | None = None


class ModeUsed(_Response):
    frequency_hz: float
    controls: str = Field(description="The parameter this peak informs.")
    measurement: int | None = None
    sensitivity: float | None = None


class Flag(_Response):
    parameter: str
    reason: str


class IdentificationResult(_Response):
    """Joint identification (contract "Joint identification")."""

    joints: IdentifiedJoints
    status: Literal["identified", "not_identifiable"]
    detail: str | None = Field(None, description="Why not identifiable.")
    modes_used: list[ModeUsed]
    residual_db: float | None = None
    residual_rel: float | None = None
    noise_rel: float | None = None
    flags: list[Flag] = Field(default_factory=list, description="Parameters the data do not inform well.")
    start: dict[str, float | None] = Field(default_factory=dict, description="The starting values.")
    band_hz: list[float | None] = Field(default_factory=list)
    windows_hz: list[Any] = Field(default_factory=list)
    runtime_s: float | None = None
    not_applicable: list[NotApplicable] | None = None
    spindle_measurement: dict[str, Any] | None = None
    notes: list[str] | None = None


class EffectMode(_Response):
    """A mode in the band and which parameter controls each of its features."""

    index: int
    frequency_hz: float = Field(description="Natural frequency, Hz.")
    frequency_sd_hz: float | None = Field(None, description="Its standard uncertainty (modal fit), Hz.")
    tip_residue_1_kg: float | None = None
    tip_participation: float | None = Field(None, description="Tip residue / the band's largest (0…1).")
    peak_frequency_hz: float | None = None
    peak_magnitude_m_n: float | None = None
    damping_ratio: float | None = None
    controlled_by: dict[str, str | None] = Field(description="Per feature, the parameter with the largest |S|.")
    controlled_by_interface: dict[str, str | None] = Field(description="The same among joints and bearings.")


class EffectParameterRow(_Response):
    """One parameter: its value and d ln(feature)/d ln(parameter) per mode, per feature."""

    parameter: str
    value: float = Field(description="Nominal value, SI.")
    frequency_hz: list[float | None]
    peak_magnitude_m_n: list[float | None]
    damping_ratio: list[float | None]
    peak_frequency_hz: list[float | None]
    controls_mode: int | None = None
    controls_frequency_hz: float | None = None


class EffectsResult(_Response):
    """Effect analysis: modes × parameters sensitivity table."""

    band_hz: list[float]
    relative_step: float
    sensitivity: str = Field(description="What the numbers are.")
    modes_method: str = Field(description="wittrick_williams (exact) or modal_fit (measured spindle).")
    features: list[str]
    modes: list[EffectMode]
    parameters: list[EffectParameterRow]
    notes: list[str]
    not_applicable: list[NotApplicable] | None = None
    spindle_measurement: dict[str, Any] | None = None


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


class RecommendedPocket(_Response):
    """The stable pocket around a preset's speed: the contiguous speeds whose limit reaches the stepdown
    times the safety factor."""

    low_rpm: float
    high_rpm: float
    width_rpm: float
    low_open: bool = Field(False, description="Followed only this far down (semi-discretization pockets are "
                                              "followed at most twice slower than their speed): stable here, it "
                                              "may go on below.")
    high_open: bool = Field(False, description="Likewise above (at most twice faster).")


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
    pocket: RecommendedPocket | None = Field(None, description="The stable pocket around the preset's speed.")
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


class LibraryPage(_Response):
    """One page of the stored libraries, by id (without the per-tool lists)."""

    items: list[LibrarySummary]
    next_cursor: str | None = Field(description="Pass as ?cursor= for the next page; null on the last page.")

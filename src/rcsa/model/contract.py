"""The contract's assembly document, parsed into immutable, validated specifications.

Every rule of ``docs/contract.md`` "Assembly" is checked here, once, at the edge; a violation
raises :class:`~rcsa.errors.InputError` naming the field (dotted path) and the rule. The
numerical code downstream never sees an unchecked value.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from rcsa.errors import InputError
from rcsa.model.bounds import (
    MAX_BEARINGS,
    MAX_CONTACT_ARC_DEG,
    MAX_CONTACT_PRESSURE_PA,
    MAX_DAMPING,
    MAX_DENSITY_KG_M3,
    MAX_DIAMETER_M,
    MAX_FREQUENCY_HZ,
    MAX_FREQUENCY_LINES,
    MAX_INTERFACE_STIFFNESS_N_M3,
    MAX_INTERFACE_STIFFNESS_SCALE,
    MAX_INTERFACE_TANGENTIAL_RATIO,
    MAX_LENGTH_M,
    MAX_LOSS_FACTOR,
    MAX_MODULUS_PA,
    MAX_NECK_SEGMENTS,
    MAX_POISSON_RATIO,
    MAX_SEGMENTS,
    MAX_SHEAR_COEFFICIENT,
    MAX_STIFFNESS,
    MAX_SURFACE_ROUGHNESS_M,
    MIN_CONTACT_ARC_DEG,
    MIN_CONTACT_PRESSURE_PA,
    MIN_DENSITY_KG_M3,
    MIN_FLUTED_DIAMETER_RATIO,
    MIN_FREQUENCY_HZ,
    MIN_INTERFACE_STIFFNESS_N_M3,
    MIN_INTERFACE_STIFFNESS_SCALE,
    MIN_INTERFACE_TANGENTIAL_RATIO,
    MIN_JOINT_STIFFNESS,
    MIN_LENGTH_M,
    MIN_MODULUS_PA,
    MIN_POISSON_RATIO,
    MIN_SHEAR_COEFFICIENT,
    MIN_SURFACE_ROUGHNESS_M,
)
from rcsa.model.fields import Fields
from rcsa.physics.arrays import FloatArray
from rcsa.physics.insertion import contact_stiffness_n_m3
from rcsa.physics.materials import BUILTIN_MATERIALS, Material
from rcsa.physics.receptance import check_frequency_hz
from rcsa.physics.sections import BeamTheory, ShearModel

__all__ = [
    "AssemblySpec",
    "BearingSpec",
    "ClampingSpec",
    "HolderSpec",
    "JointSpec",
    "MeasuredSpindleSpec",
    "SegmentSpec",
    "SpindleSpec",
    "ToolSpec",
    "CLAMPING_MODELS",
    "CombinationSpec",
    "CommonSpec",
    "assemble",
    "parse_assembly",
    "parse_combination",
    "parse_common",
    "parse_frequency",
    "parse_holder_tool",
    "parse_holder",
    "parse_joint",
    "parse_materials",
    "parse_spindle",
    "parse_tool",
]

_BEAM_THEORIES: tuple[BeamTheory, ...] = ("timoshenko", "euler_bernoulli")
_SHEAR_MODELS: tuple[ShearModel, ...] = ("hutchinson", "cowper")


# ---------------------------------------------------------------------------- specs


@dataclass(frozen=True, slots=True)
class SegmentSpec:
    """A uniform (hollow) circular segment; lengths and diameters in m.

    Parameters
    ----------
    length_m : float
    outer_diameter_m : float
    inner_diameter_m : float
        0 for a solid segment.
    material : str
        Name of a material of the document.
    """

    length_m: float
    outer_diameter_m: float
    inner_diameter_m: float
    material: str


@dataclass(frozen=True, slots=True)
class BearingSpec:
    """A bearing: spring/damper to rigid ground at ``position_m`` from the spindle nose.

    Parameters
    ----------
    position_m : float
        Distance from the spindle nose, m.
    stiffness_n_m : float
        Radial stiffness, N/m.
    damping_ns_m : float
        Radial viscous damping, N·s/m.
    rotational_stiffness_nm_rad : float
        Tilting stiffness, N·m/rad.
    rotational_damping_nms_rad : float
        Tilting viscous damping, N·m·s/rad.
    """

    position_m: float
    stiffness_n_m: float
    damping_ns_m: float = 0.0
    rotational_stiffness_nm_rad: float = 0.0
    rotational_damping_nms_rad: float = 0.0


@dataclass(frozen=True, slots=True)
class SpindleSpec:
    """Analytical spindle: segments listed from the nose toward the rear, bearings.

    Parameters
    ----------
    segments : tuple of SegmentSpec
        From the nose toward the rear.
    bearings : tuple of BearingSpec
    """

    segments: tuple[SegmentSpec, ...]
    bearings: tuple[BearingSpec, ...]

    @property
    def length_m(self) -> float:
        """Total shaft length, m."""
        return sum(s.length_m for s in self.segments)


@dataclass(frozen=True, slots=True)
class MeasuredSpindleSpec:
    """A stored measured spindle (hybrid assembly).

    Parameters
    ----------
    measurement_id : str
        Id of the stored measurement (``m-`` and 12 hex digits).
    artifact_method : {"exact", "finite_difference"}
        How an ``artifact_frfs`` measurement is identified: the exact three-FRF method, or the
        labelled finite-difference fallback.
    effective_length_m : float
        Equivalent-cantilever length used to estimate the rotations of a ``direct_frf``
        measurement, m (:mod:`rcsa.measured.hybrid`).
    """

    measurement_id: str
    artifact_method: str = "exact"
    effective_length_m: float = 0.2


@dataclass(frozen=True, slots=True)
class HolderSpec:
    """Holder segments listed from the gauge line toward the tool end.

    Parameters
    ----------
    segments : tuple of SegmentSpec
        From the gauge line toward the tool end.
    """

    segments: tuple[SegmentSpec, ...]

    @property
    def length_m(self) -> float:
        """Gauge length of the modelled holder, m."""
        return sum(s.length_m for s in self.segments)


@dataclass(frozen=True, slots=True)
class ToolSpec:
    """Parametric tool (ISO 13399 / Fusion meaning; ``docs/contract.md`` "Assembly").

    ``shoulder_length_m``/``shoulder_diameter_m`` (extension) describe a reduced neck from
    the flute end up to ``shoulder_length_m`` from the tip; ``neck_segments`` (extension,
    instead of them) a stepped neck as ``(length_m, diameter_m)`` pieces from the flute end
    toward the holder (a conical neck, stepped). ``fluted_mass_diameter_ratio``
    (extension) uses a separate equivalent diameter for the flutes' mass (default: the
    stiffness one, ``docs/physics.md`` §5.1).

    Parameters
    ----------
    material : str
        Name of a material of the document.
    diameter_m : float
        Cutting diameter DC, m.
    shank_diameter_m : float
        Shank diameter, m.
    overall_length_m : float
        Overall length OAL, m.
    flute_length_m : float
        Flute length LCF, m.
    stickout_m : float
        Length from the holder face to the tip, m.
    fluted_diameter_ratio : float
        Equivalent diameter of the fluted section for its stiffness, as a fraction of DC.
    fluted_mass_diameter_ratio : float, optional
        The same for the flutes' mass (extension).
    shoulder_length_m, shoulder_diameter_m : float, optional
        A reduced neck (extension, see above).
    neck_segments : tuple of (float, float)
        A stepped neck (extension, see above): ``(length_m, diameter_m)`` pieces, m.
    """

    material: str
    diameter_m: float
    shank_diameter_m: float
    overall_length_m: float
    flute_length_m: float
    stickout_m: float
    fluted_diameter_ratio: float = 0.8
    fluted_mass_diameter_ratio: float | None = None
    shoulder_length_m: float | None = None
    shoulder_diameter_m: float | None = None
    neck_segments: tuple[tuple[float, float], ...] = ()

    @property
    def inserted_length_m(self) -> float:
        """Length of the shank inside the holder, OAL − stickout, m."""
        return self.overall_length_m - self.stickout_m


@dataclass(frozen=True, slots=True)
class JointSpec:
    """Elastic joint ``diag(k_t + iωc_t, k_r + iωc_r)``; ``None`` rotational stiffness = rigid.

    Parameters
    ----------
    stiffness_n_m : float
        Translational stiffness k_t, N/m.
    damping_ns_m : float
        Translational viscous damping c_t, N·s/m.
    rotational_stiffness_nm_rad : float or None
        Rotational stiffness k_r, N·m/rad; ``None`` is rigid.
    rotational_damping_nms_rad : float
        Rotational viscous damping c_r, N·m·s/rad.
    """

    stiffness_n_m: float
    damping_ns_m: float = 0.0
    rotational_stiffness_nm_rad: float | None = None
    rotational_damping_nms_rad: float = 0.0


#: The holder–tool clamping models (``joints.holder_tool.model``; contract v1.2).
CLAMPING_MODELS = ("point", "bonded", "contact")


@dataclass(frozen=True, slots=True)
class ClampingSpec:
    """A holder–tool clamping along the inserted length (``joints.holder_tool.model`` bonded/contact).

    The shank and the holder nose are two beams sharing load through a distributed interface
    over the insertion (:mod:`rcsa.model.clamping` derives its stiffness from geometry and
    materials); ``contact`` adds a finite interface stiffness per unit area in series.

    Parameters
    ----------
    model : {"bonded", "contact"}
        ``bonded``: an ideal clamping (the shank bonded to the bore); ``contact``: the same with a
        finite interface stiffness.
    interface_stiffness_n_m3 : float or None
        Normal interface stiffness per unit area, N/m³ (``contact``; ``None`` for bonded).
    interface_tangential_ratio : float
        Tangential over normal interface stiffness (dimensionless).
    interface_loss_factor : float
        Hysteretic loss factor of the interface stiffness (dimensionless).
    front_gap_length_m : float
        Length from the holder face into the bore over which the shank does not touch, m
        (a bell-mouthed bore, or contact lost at the front); 0 by default.
    contact_length_m : float or None
        Length of the contact behind the front gap, m (a collet gripping the front of the
        shank only); ``None``: the rest of the insertion.
    contact_pressure_pa, surface_roughness_m : float or None
        The contact model's inputs when ``interface_stiffness_n_m3`` was derived from them
        (kept for the result's notes), Pa and m.
    interface_stiffness_scale : float
        A factor on the whole interface stiffness per unit length (dimensionless; default 1):
        what an identification finds and analyses vary (``holder_tool.interface_stiffness_scale``:
        identification, effect analysis, tolerance draws, diagnosis candidates).
    contact_arc_deg : float
        The arc of the bore's circumference the contact covers, degrees, centred on the
        direction of the tool-point FRF (a side-lock screw pushes the shank against the back of
        its bore); 360 by default.
    screw_diameter_m : float or None
        A side-lock screw's contact face on the shank's flat, opposite the arc, m (``None``: no
        screw).
    """

    model: str
    interface_stiffness_n_m3: float | None = None
    interface_tangential_ratio: float = 1.0
    interface_loss_factor: float = 0.0
    front_gap_length_m: float = 0.0
    contact_pressure_pa: float | None = None
    surface_roughness_m: float | None = None
    interface_stiffness_scale: float = 1.0
    contact_length_m: float | None = None
    contact_arc_deg: float = 360.0
    screw_diameter_m: float | None = None


@dataclass(frozen=True, slots=True)
class AssemblySpec:
    """A validated assembly document (``docs/contract.md`` "Assembly").

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Read-only, strictly increasing, > 0 Hz.
    spindle : SpindleSpec or MeasuredSpindleSpec
    holder : HolderSpec or None
        ``None`` only on a measured spindle whose plane is the holder tip.
    tool : ToolSpec
    spindle_holder : JointSpec or None
        The spindle–holder joint; ``None`` is rigid.
    holder_tool : JointSpec, ClampingSpec or None
        The holder–tool joint: a point joint (``None`` is rigid) or a clamping along the insertion.
    beam_theory : {"timoshenko", "euler_bernoulli"}
    shear_coefficient : {"hutchinson", "cowper"} or float
    materials : mapping of str to Material
        Built-in materials updated by the document's own.
    """

    frequency_hz: FloatArray
    spindle: SpindleSpec | MeasuredSpindleSpec
    holder: HolderSpec | None
    tool: ToolSpec
    spindle_holder: JointSpec | None = None
    holder_tool: JointSpec | ClampingSpec | None = None
    beam_theory: BeamTheory = "timoshenko"
    shear_coefficient: ShearModel | float = "hutchinson"
    materials: Mapping[str, Material] = field(default_factory=lambda: MappingProxyType(dict(BUILTIN_MATERIALS)))


# ---------------------------------------------------------------------------- parsers


def parse_frequency(value: object, path: str = "frequency", max_lines: int = MAX_FREQUENCY_LINES) -> FloatArray:
    """Frequency grid from ``{start_hz, stop_hz, step_hz}`` (stop included) or ``{values_hz}``.

    Parameters
    ----------
    value : dict
        The document's ``frequency`` object.
    path : str
        Where the value sits in the document, for error messages.
    max_lines : int
        Largest accepted number of frequency lines.

    Returns
    -------
    numpy.ndarray, shape (nfreq,)
        Read-only, strictly increasing, > 0 Hz.
    """
    o = Fields(value, path)
    if "values_hz" in o.value:
        o.only("values_hz")
        values = o.array("values_hz")
        if len(values) > max_lines:
            raise InputError(o.at("values_hz"), f"at most {max_lines} frequency lines, got {len(values)}")
        if any(isinstance(v, bool) or not isinstance(v, int | float) for v in values):
            raise InputError(o.at("values_hz"), "must be a list of numbers")
        f = check_frequency_hz(values, o.at("values_hz"))
        if f[-1] > MAX_FREQUENCY_HZ:
            raise InputError(o.at("values_hz"), f"frequencies must be <= {MAX_FREQUENCY_HZ:g} Hz")
        return f
    o.only("start_hz", "stop_hz", "step_hz")
    start = o.number("start_hz", gt=0.0, ge=MIN_FREQUENCY_HZ, le=MAX_FREQUENCY_HZ)
    stop = o.number("stop_hz", gt=0.0, ge=MIN_FREQUENCY_HZ, le=MAX_FREQUENCY_HZ)
    step = o.number("step_hz", gt=0.0, le=MAX_FREQUENCY_HZ)
    if stop < start:
        raise InputError(o.at("stop_hz"), f"must be >= start_hz ({start:g}), got {stop:g}")
    span = (stop - start) / step
    if not span < max_lines:
        raise InputError(path, f"at most {max_lines} frequency lines, this grid has {span + 1:.6g}")
    n = math.floor(span * (1 + 1e-12) + 1e-9) + 1
    if n > max_lines:
        raise InputError(path, f"at most {max_lines} frequency lines, this grid has {n}")
    return check_frequency_hz(start + step * np.arange(n), path)


_MATERIAL_FIELDS = ("youngs_modulus_pa", "poisson_ratio", "density_kg_m3", "loss_factor")


def parse_materials(value: object, path: str = "materials") -> Mapping[str, Material]:
    """Built-in materials, updated by the document's ``materials`` (new names or overrides).

    A built-in may be overridden field by field; a new material needs E, ν and ρ.

    Parameters
    ----------
    value : dict or None
        The document's ``materials`` object (name → properties), or ``None``.
    path : str
        Where the value sits in the document, for error messages.
    """
    out = dict(BUILTIN_MATERIALS)
    if value is None:
        return MappingProxyType(out)
    o = Fields(value, path)
    for name, raw in o.value.items():
        m = Fields(raw, o.at(name))
        m.only(*_MATERIAL_FIELDS)
        base = BUILTIN_MATERIALS.get(name)
        out[name] = Material(
            youngs_modulus_pa=m.number("youngs_modulus_pa", gt=0.0, ge=MIN_MODULUS_PA, le=MAX_MODULUS_PA,
                                       default=base.youngs_modulus_pa if base else None),
            poisson_ratio=m.number("poisson_ratio", gt=MIN_POISSON_RATIO, lt=MAX_POISSON_RATIO,
                                   default=base.poisson_ratio if base else None),
            density_kg_m3=m.number("density_kg_m3", gt=0.0, ge=MIN_DENSITY_KG_M3, le=MAX_DENSITY_KG_M3,
                                   default=base.density_kg_m3 if base else None),
            loss_factor=m.number("loss_factor", ge=0.0, lt=MAX_LOSS_FACTOR, default=base.loss_factor if base else 0.0),
        )
    return MappingProxyType(out)


def _material(o: Fields, materials: Mapping[str, Material], default: str) -> str:
    name = o.string("material", default)
    if name not in materials:
        raise InputError(o.at("material"), f"unknown material {name!r} (known: {', '.join(sorted(materials))})")
    return name


def _segments(value: object, path: str, materials: Mapping[str, Material]) -> tuple[SegmentSpec, ...]:
    if not isinstance(value, list) or not value:
        raise InputError(path, "must be a non-empty list of segments")
    if len(value) > MAX_SEGMENTS:
        raise InputError(path, f"at most {MAX_SEGMENTS} segments, got {len(value)}; merge neighbouring segments "
                               "of equal section (each costs a condensation per frequency line)")
    out = []
    for i, raw in enumerate(value):
        o = Fields(raw, f"{path}[{i}]")
        o.only("length_m", "outer_diameter_m", "inner_diameter_m", "material")
        length = o.number("length_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_LENGTH_M)
        outer = o.number("outer_diameter_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_DIAMETER_M)
        inner = o.number("inner_diameter_m", ge=0.0, le=MAX_DIAMETER_M, default=0.0)
        if inner >= outer:
            raise InputError(o.at("inner_diameter_m"),
                             f"must be smaller than outer_diameter_m ({outer:g}), got {inner:g}")
        out.append(SegmentSpec(length, outer, inner, _material(o, materials, "steel")))
    return tuple(out)


def parse_spindle(value: object, materials: Mapping[str, Material], path: str = "spindle"
                  ) -> SpindleSpec | MeasuredSpindleSpec:
    """An analytical spindle (segments nose → rear, bearings) or a stored measurement id.

    Parameters
    ----------
    value : object
        The parsed JSON of ``spindle``.
    materials : mapping of str to Material
        The materials a segment may name (built-in and the request's own).
    path : str
        The value's path in the request, named in errors.

    Returns
    -------
    SpindleSpec or MeasuredSpindleSpec

    Raises
    ------
    InputError
        A missing, mistyped or out-of-bounds field, named by its path.
    """
    o = Fields(value, path)
    if "measurement_id" in o.value:
        o.only("measurement_id", "artifact_method", "effective_length_m")
        return MeasuredSpindleSpec(o.string("measurement_id"),
                                   o.string("artifact_method", "exact", ("exact", "finite_difference")),
                                   o.number("effective_length_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_LENGTH_M,
                                            default=0.2))
    o.only("segments", "bearings")
    segments = _segments(o.value.get("segments"), o.at("segments"), materials)
    total = sum(s.length_m for s in segments)
    raw_bearings = o.value.get("bearings", [])
    if not isinstance(raw_bearings, list):
        raise InputError(o.at("bearings"), "must be a list")
    if len(raw_bearings) > MAX_BEARINGS:
        raise InputError(o.at("bearings"), f"at most {MAX_BEARINGS} bearings, got {len(raw_bearings)}")
    bearings = []
    for i, raw in enumerate(raw_bearings):
        b = Fields(raw, f"{o.at('bearings')}[{i}]")
        b.only("position_m", "stiffness_n_m", "damping_ns_m", "rotational_stiffness_nm_rad",
               "rotational_damping_nms_rad")
        pos = b.number("position_m", ge=0.0, le=MAX_LENGTH_M)
        if pos > total * (1 + 1e-12):
            raise InputError(b.at("position_m"),
                             f"bearing lies outside the spindle: must be <= its length {total:g} m, got {pos:g}")
        bearings.append(BearingSpec(
            min(pos, total), b.number("stiffness_n_m", ge=0.0, le=MAX_STIFFNESS),
            b.number("damping_ns_m", ge=0.0, le=MAX_DAMPING, default=0.0),
            b.number("rotational_stiffness_nm_rad", ge=0.0, le=MAX_STIFFNESS, default=0.0),
            b.number("rotational_damping_nms_rad", ge=0.0, le=MAX_DAMPING, default=0.0)))
    return SpindleSpec(segments, tuple(bearings))


def parse_holder(value: object, materials: Mapping[str, Material], path: str = "holder") -> HolderSpec:
    """Holder segments from the gauge line toward the tool end.

    Parameters
    ----------
    value : object
        The parsed JSON of ``holder``.
    materials : mapping of str to Material
        The materials a segment may name (built-in and the request's own).
    path : str
        The value's path in the request, named in errors.

    Returns
    -------
    HolderSpec

    Raises
    ------
    InputError
        A missing, mistyped or out-of-bounds field, named by its path.
    """
    o = Fields(value, path)
    o.only("segments")
    return HolderSpec(_segments(o.value.get("segments"), o.at("segments"), materials))


_TOOL_FIELDS = ("material", "diameter_m", "shank_diameter_m", "overall_length_m", "flute_length_m",
                "stickout_m", "fluted_diameter_ratio", "fluted_mass_diameter_ratio",
                "shoulder_length_m", "shoulder_diameter_m", "neck_segments")


def parse_tool(value: object, materials: Mapping[str, Material], path: str = "tool") -> ToolSpec:
    """The parametric tool, with the geometric rules of the contract checked.

    Parameters
    ----------
    value : object
        The parsed JSON of ``tool``.
    materials : mapping of str to Material
        The materials a segment may name (built-in and the request's own).
    path : str
        The value's path in the request, named in errors.

    Returns
    -------
    ToolSpec

    Raises
    ------
    InputError
        A missing, mistyped or out-of-bounds field, or a broken geometric rule
        (flute ≤ stickout ≤ overall length, shoulder between flute and stickout, …).
    """
    o = Fields(value, path)
    o.only(*_TOOL_FIELDS)
    diameter = o.number("diameter_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_DIAMETER_M)
    shank = o.number("shank_diameter_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_DIAMETER_M, default=diameter)
    overall = o.number("overall_length_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_LENGTH_M)
    stickout = o.number("stickout_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_LENGTH_M)
    if stickout > overall:
        raise InputError(o.at("stickout_m"), f"must be <= overall_length_m ({overall:g}), got {stickout:g}")
    flute = o.number("flute_length_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_LENGTH_M)
    if flute > stickout:
        raise InputError(o.at("flute_length_m"), f"must be <= stickout_m ({stickout:g}), got {flute:g}")
    ratio = o.number("fluted_diameter_ratio", gt=0.0, ge=MIN_FLUTED_DIAMETER_RATIO, le=1.0, default=0.8)
    mass_ratio = o.optional_number("fluted_mass_diameter_ratio", gt=0.0, ge=MIN_FLUTED_DIAMETER_RATIO, le=1.0)
    shoulder_length = o.optional_number("shoulder_length_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_LENGTH_M)
    shoulder_diameter = o.optional_number("shoulder_diameter_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_DIAMETER_M)
    if (shoulder_length is None) != (shoulder_diameter is None):
        raise InputError(o.at("shoulder_length_m"), "shoulder_length_m and shoulder_diameter_m go together")
    if shoulder_length is not None and not flute <= shoulder_length <= stickout:
        raise InputError(o.at("shoulder_length_m"),
                         f"must lie between flute_length_m ({flute:g}) and stickout_m ({stickout:g})")
    necks = _neck_segments(o, flute, stickout) if o.has("neck_segments") else ()
    if necks and shoulder_length is not None:
        raise InputError(o.at("neck_segments"), "give either neck_segments or shoulder_length_m/shoulder_diameter_m")
    return ToolSpec(_material(o, materials, "carbide"), diameter, shank, overall, flute, stickout,
                    ratio, mass_ratio, shoulder_length, shoulder_diameter, necks)


def _neck_segments(o: Fields, flute: float, stickout: float) -> tuple[tuple[float, float], ...]:
    """``[{length_m, diameter_m}]`` from the flute end; together within stickout − flute_length."""
    raw = o.array("neck_segments")
    if len(raw) > MAX_NECK_SEGMENTS:
        raise InputError(o.at("neck_segments"), f"at most {MAX_NECK_SEGMENTS} pieces, got {len(raw)}")
    out = []
    for i, item in enumerate(raw):
        s = Fields(item, f"{o.at('neck_segments')}[{i}]", ("length_m", "diameter_m"))
        out.append((s.number("length_m", gt=0.0, ge=MIN_LENGTH_M),  # at most stickout − flute, below
                    s.number("diameter_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_DIAMETER_M)))
    total = math.fsum(length for length, _ in out)
    if total > (stickout - flute) * (1 + 1e-9) + 1e-12:
        raise InputError(o.at("neck_segments"), f"reach {total:g} m beyond the flutes, more than the "
                                                f"{stickout - flute:g} m between flute_length_m and stickout_m")
    return tuple(out)


def parse_joint(value: object, path: str) -> JointSpec | None:
    """An elastic joint; ``None`` (left out) means rigid.

    Parameters
    ----------
    value : dict or None
        A joint object (``stiffness_n_m`` ...), or ``None`` when left out.
    path : str
        Where the value sits in the document, for error messages.
    """
    if value is None:
        return None
    o = Fields(value, path)
    o.only("stiffness_n_m", "damping_ns_m", "rotational_stiffness_nm_rad", "rotational_damping_nms_rad")
    return JointSpec(o.number("stiffness_n_m", gt=0.0, ge=MIN_JOINT_STIFFNESS, le=MAX_STIFFNESS),
                     o.number("damping_ns_m", ge=0.0, le=MAX_DAMPING, default=0.0),
                     o.optional_number("rotational_stiffness_nm_rad", gt=0.0, ge=MIN_JOINT_STIFFNESS,
                                       le=MAX_STIFFNESS),
                     o.number("rotational_damping_nms_rad", ge=0.0, le=MAX_DAMPING, default=0.0))


_POINT_FIELDS = ("stiffness_n_m", "damping_ns_m", "rotational_stiffness_nm_rad", "rotational_damping_nms_rad")
_CLAMPING_FIELDS = ("interface_stiffness_n_m3", "interface_tangential_ratio", "interface_loss_factor",
                    "front_gap_length_m", "contact_length_m", "contact_pressure_pa", "surface_roughness_m",
                    "interface_stiffness_scale", "contact_arc_deg", "screw_diameter_m")


def parse_holder_tool(value: object, path: str = "joints.holder_tool") -> JointSpec | ClampingSpec | None:
    """The holder–tool joint: a point joint (``model`` absent or ``"point"``) or a clamping.

    ``bonded`` takes no stiffness: the clamping follows from geometry and materials
    (optionally ``front_gap_length_m`` and ``contact_length_m``: where along the bore the shank
    touches; ``contact_arc_deg``: over which arc of the bore's circumference; ``screw_diameter_m``:
    a side-lock screw's face on the shank's flat, opposite the arc; and
    ``interface_stiffness_scale``, a factor on it, as an identification finds). ``contact`` takes ``interface_stiffness_n_m3``, or
    ``contact_pressure_pa`` and ``surface_roughness_m`` from which it is derived
    (:func:`rcsa.physics.insertion.contact_stiffness_n_m3`), and optionally
    ``interface_tangential_ratio``, ``interface_loss_factor`` and ``front_gap_length_m``.

    Parameters
    ----------
    value : dict or None
        The ``joints.holder_tool`` object, or ``None`` when left out (rigid point joint).
    path : str
        Where the value sits in the document, for error messages.

    Returns
    -------
    JointSpec, ClampingSpec or None

    Raises
    ------
    InputError
        An unknown model, a field the model does not take, or a value out of bounds.
    """
    if value is None:
        return None
    o = Fields(value, path)
    model = o.choice("model", "point", CLAMPING_MODELS)
    if model == "point":
        o.only("model", *_POINT_FIELDS)
        return parse_joint({k: v for k, v in o.value.items() if k != "model"}, path)
    stray = [k for k in _POINT_FIELDS if k in o.value]
    if stray:
        raise InputError(o.at(stray[0]), f"belongs to the point joint (model \"point\"); model {model!r} derives "
                                         "the clamping's stiffness from the geometry"
                                         + (" and interface_stiffness_n_m3" if model == "contact" else
                                            " (use model \"contact\" with interface_stiffness_n_m3 for a softer one)"))
    gap = o.number("front_gap_length_m", ge=0.0, le=MAX_LENGTH_M, default=0.0)
    contact = o.optional_number("contact_length_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_LENGTH_M)
    scale = o.number("interface_stiffness_scale", gt=0.0, ge=MIN_INTERFACE_STIFFNESS_SCALE,
                     le=MAX_INTERFACE_STIFFNESS_SCALE, default=1.0)
    arc = o.number("contact_arc_deg", ge=MIN_CONTACT_ARC_DEG, le=MAX_CONTACT_ARC_DEG, default=360.0)
    screw = o.optional_number("screw_diameter_m", gt=0.0, ge=MIN_LENGTH_M, le=MAX_DIAMETER_M)
    if model == "bonded":
        o.only("model", "front_gap_length_m", "contact_length_m", "interface_stiffness_scale", "contact_arc_deg",
               "screw_diameter_m")
        return ClampingSpec("bonded", front_gap_length_m=gap, contact_length_m=contact, interface_stiffness_scale=scale,
                            contact_arc_deg=arc, screw_diameter_m=screw)
    o.only("model", *_CLAMPING_FIELDS)
    stiffness = o.optional_number("interface_stiffness_n_m3", gt=0.0, ge=MIN_INTERFACE_STIFFNESS_N_M3,
                                  le=MAX_INTERFACE_STIFFNESS_N_M3)
    pressure = o.optional_number("contact_pressure_pa", gt=0.0, ge=MIN_CONTACT_PRESSURE_PA, le=MAX_CONTACT_PRESSURE_PA)
    roughness = o.optional_number("surface_roughness_m", gt=0.0, ge=MIN_SURFACE_ROUGHNESS_M,
                                  le=MAX_SURFACE_ROUGHNESS_M)
    if stiffness is None:
        if pressure is None or roughness is None:
            raise InputError(o.at("interface_stiffness_n_m3"), "is required for model \"contact\" (N/m³), unless "
                                                               "contact_pressure_pa and surface_roughness_m are given")
        stiffness = contact_stiffness_n_m3(pressure, roughness)
        if not MIN_INTERFACE_STIFFNESS_N_M3 <= stiffness <= MAX_INTERFACE_STIFFNESS_N_M3:
            raise InputError(o.at("contact_pressure_pa"),
                             f"with surface_roughness_m gives an interface stiffness of {stiffness:.3g} N/m³, outside "
                             f"[{MIN_INTERFACE_STIFFNESS_N_M3:g}, {MAX_INTERFACE_STIFFNESS_N_M3:g}]")
    elif pressure is not None or roughness is not None:
        raise InputError(o.at("interface_stiffness_n_m3"),
                         "give either interface_stiffness_n_m3 or contact_pressure_pa with surface_roughness_m")
    return ClampingSpec(
        "contact", stiffness, o.number("interface_tangential_ratio", gt=0.0, ge=MIN_INTERFACE_TANGENTIAL_RATIO,
                           le=MAX_INTERFACE_TANGENTIAL_RATIO, default=1.0),
        o.number("interface_loss_factor", ge=0.0, lt=MAX_LOSS_FACTOR, default=0.0), gap, pressure, roughness,
        interface_stiffness_scale=scale, contact_length_m=contact, contact_arc_deg=arc, screw_diameter_m=screw)


@dataclass(frozen=True, slots=True)
class CombinationSpec:
    """One tool–holder combination of a batch: holder, tool and joints.

    Parameters
    ----------
    holder : HolderSpec or None
    tool : ToolSpec
    spindle_holder : JointSpec or None
        The spindle–holder joint; ``None`` is rigid.
    holder_tool : JointSpec, ClampingSpec or None
        The holder–tool joint (:func:`parse_holder_tool`).
    """

    holder: HolderSpec | None
    tool: ToolSpec
    spindle_holder: JointSpec | None
    holder_tool: JointSpec | ClampingSpec | None


def parse_combination(value: object, materials: Mapping[str, Material], path: str = "",
                      extra_fields: tuple[str, ...] = ()) -> CombinationSpec:
    """Holder, tool and joints of one assembly or batch combination.

    Parameters
    ----------
    value : dict
        Object holding ``holder`` (optional), ``tool`` and ``joints`` (optional).
    materials : mapping of str to Material
        Materials by name (from :func:`parse_materials`).
    path : str
        Path prefix for error messages (``"combinations[3]"``).
    extra_fields : tuple of str
        Other keys allowed in ``value`` (checked by the caller).
    """
    o = Fields(value, path)
    o.only("holder", "tool", "joints", *extra_fields)
    holder = parse_holder(o.value["holder"], materials, o.at("holder")) if o.has("holder") else None
    if not o.has("tool"):
        raise InputError(o.at("tool"), "is required")
    tool = parse_tool(o.value["tool"], materials, o.at("tool"))
    joints = Fields(o.value.get("joints") or {}, o.at("joints"))
    joints.only("spindle_holder", "holder_tool")
    return CombinationSpec(holder, tool,
                           parse_joint(joints.value.get("spindle_holder"), joints.at("spindle_holder")),
                           parse_holder_tool(joints.value.get("holder_tool"), joints.at("holder_tool")))


@dataclass(frozen=True, slots=True)
class CommonSpec:
    """What every combination of an assembly or batch shares: grid, options, materials, spindle.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Read-only, strictly increasing, > 0 Hz.
    beam_theory : {"timoshenko", "euler_bernoulli"}
    shear_coefficient : {"hutchinson", "cowper"} or float
    materials : mapping of str to Material
    spindle : SpindleSpec or MeasuredSpindleSpec
    """

    frequency_hz: FloatArray
    beam_theory: BeamTheory
    shear_coefficient: ShearModel | float
    materials: Mapping[str, Material]
    spindle: SpindleSpec | MeasuredSpindleSpec


_COMMON_FIELDS = ("frequency", "beam_theory", "shear_coefficient", "materials", "spindle")


def parse_common(document: object, path: str = "", max_lines: int = MAX_FREQUENCY_LINES) -> CommonSpec:
    """Frequency grid, beam theory, shear coefficient, materials and spindle of a document.

    Parameters
    ----------
    document : object
        A parsed request (an assembly, or the shared part of a batch).
    path : str
        Its path in the request (``""`` for the request itself).
    max_lines : int
        Largest accepted number of frequency lines.

    Returns
    -------
    CommonSpec

    Raises
    ------
    InputError
        A missing, mistyped or out-of-bounds field, named by its path.
    """
    o = Fields(document, path)
    if "frequency" not in o.value:
        raise InputError(o.at("frequency"), "is required")
    frequency = parse_frequency(o.value["frequency"], o.at("frequency"), max_lines=max_lines)
    theory = o.choice("beam_theory", "timoshenko", _BEAM_THEORIES)
    kappa: ShearModel | float
    if isinstance(o.value.get("shear_coefficient", "hutchinson"), str):
        kappa = o.choice("shear_coefficient", "hutchinson", _SHEAR_MODELS)
    else:
        kappa = o.number("shear_coefficient", gt=0.0, ge=MIN_SHEAR_COEFFICIENT, le=MAX_SHEAR_COEFFICIENT)
    materials = parse_materials(o.value.get("materials"), o.at("materials"))
    if "spindle" not in o.value:
        raise InputError(o.at("spindle"), "is required")
    spindle = parse_spindle(o.value["spindle"], materials, o.at("spindle"))
    return CommonSpec(frequency, theory, kappa, materials, spindle)


def assemble(common: CommonSpec, combination: CombinationSpec) -> AssemblySpec:
    """An assembly from the shared part and one combination.

    Parameters
    ----------
    common : CommonSpec
    combination : CombinationSpec
    """
    if combination.holder is None and isinstance(common.spindle, SpindleSpec):
        raise InputError("holder", "is required for an analytical spindle")
    return AssemblySpec(
        frequency_hz=common.frequency_hz, spindle=common.spindle, holder=combination.holder,
        tool=combination.tool, spindle_holder=combination.spindle_holder,
        holder_tool=combination.holder_tool, beam_theory=common.beam_theory,
        shear_coefficient=common.shear_coefficient, materials=common.materials)


def parse_assembly(document: object, max_lines: int = MAX_FREQUENCY_LINES) -> AssemblySpec:
    """Validate a contract assembly document.

    Parameters
    ----------
    document : dict
        The assembly as in ``docs/contract.md`` "Assembly" (SI units).
    max_lines : int
        Largest accepted number of frequency lines.

    Returns
    -------
    AssemblySpec

    Raises
    ------
    InputError
        Naming the offending field and the rule.
    """
    o = Fields(document, "")
    o.only(*_COMMON_FIELDS, "holder", "tool", "joints", "name", "description")
    common = parse_common(document, max_lines=max_lines)
    rest = {k: v for k, v in o.value.items() if k in ("holder", "tool", "joints")}
    return assemble(common, parse_combination(rest, common.materials))

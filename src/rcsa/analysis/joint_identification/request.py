"""Validation of a joint-identification request (``docs/contract.md`` "Joint identification").

The request is a base assembly (its joints are the starting guess) and one or more measured
tool-point FRFs, each of the base assembly with some ``tool`` fields overridden::

    {"assembly": {...},
     "measurements": [{"tool": {"stickout_m": 0.050}, "frequency_hz": [...],
                       "h": {"real": [...], "imag": [...]}, "coherence": [...]}],
     "bounds": {"holder_tool.stiffness_n_m": [1e6, 1e8]},      # optional
     "max_residual_to_noise": 4.0}                              # optional

The assembly's spindle may be a stored measurement (``"spindle": {"measurement_id": ...}``,
``docs/contract.md`` "Additions in v1.1"); the caller then passes a
:data:`~rcsa.model.spindle_side.BaseResolver` (the application layer knows the store), and
the spindle is resolved once on all the measurements' lines. On a ``holder_tip``
measurement the spindle–holder joint is inside the measurement: it is not applicable
(reported, never identified), and ``bounds`` that name it are refused.

Every rule is checked here and a violation raises :class:`~rcsa.errors.InputError` naming
the field; the algorithm in :mod:`rcsa.analysis.joint_identification.identify` only sees checked values.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from rcsa.analysis.measured_tool_point import MAX_TAP_TESTS, TapTest, parse_tap_tests
from rcsa.analysis.tool_point_model import MeasuredSpindle
from rcsa.errors import InputError
from rcsa.model import fields
from rcsa.model.assembly import build_model
from rcsa.model.bounds import MAX_STIFFNESS
from rcsa.model.contract import AssemblySpec, ClampingSpec, MeasuredSpindleSpec, parse_assembly
from rcsa.model.parameters import get_parameter
from rcsa.model.spindle_side import BaseResolver

__all__ = [
    "CLAMPING_REASON",
    "HOLDER_TIP_REASON",
    "POINT_REASON",
    "IDENTIFIABLE",
    "IdentificationRequest",
    "MeasurementData",
    "parse_identification_request",
]

#: The parameters a joint identification estimates: point joints' translational stiffness and
#: damping; a holder–tool clamping along the insertion (model bonded/contact) its interface stiffness
#: (a factor on it: below 1 a clamping softer than the model's).
IDENTIFIABLE = ("spindle_holder.stiffness_n_m", "spindle_holder.damping_ns_m",
                "holder_tool.stiffness_n_m", "holder_tool.damping_ns_m", "holder_tool.interface_stiffness_scale")

_REQUEST_FIELDS = ("assembly", "measurements", "bounds", "max_residual_to_noise")
MAX_MEASUREMENTS = MAX_TAP_TESTS
MIN_LINES = 16
#: Default search range of each parameter around its starting value (factor either way).
DEFAULT_BOUND_FACTOR = 100.0
DEFAULT_MAX_RESIDUAL_TO_NOISE = 4.0
#: Why the spindle–holder joint cannot be identified on a holder-tip measurement.
HOLDER_TIP_REASON = ("not applicable: the measured spindle's plane is holder_tip, so the spindle–holder joint "
                     "is inside the measurement (measure at the spindle nose to identify it)")
#: Why a point joint's parameters are not identified on a clamping along the insertion, and back.
CLAMPING_REASON = ("not applicable: the holder–tool joint is a clamping along the insertion (model {model!r}); its "
                   "interface stiffness is identified (holder_tool.interface_stiffness_scale)")
POINT_REASON = ("not applicable: the holder–tool joint is a point joint; a clamping along the insertion (model bonded "
                "or contact) has an interface stiffness instead")


@dataclass(frozen=True)
class MeasurementData:
    """One measured tool-point FRF and the assembly it was measured on.

    Attributes
    ----------
    spec : AssemblySpec
        Base assembly with the measurement's tool overrides; its grid is the measurement's.
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,), complex
        Measured tool-point receptance, m/N.
    coherence : numpy.ndarray, shape (nfreq,), or None
        Ordinary coherence γ² in [0, 1].
    tool : dict
        The overrides as given (echoed in the result).
    """

    spec: AssemblySpec
    frequency_hz: np.ndarray
    h: np.ndarray
    coherence: np.ndarray | None
    tool: Mapping[str, Any]


@dataclass(frozen=True)
class IdentificationRequest:
    """A validated identification request.

    Attributes
    ----------
    base : AssemblySpec
        The base assembly; its joints are the starting guess.
    measurements : tuple of MeasurementData
    parameters : tuple of str
        Translational joint parameters to estimate (elastic joints only).
    bounds : dict of str to (float, float)
        Search range of each parameter, SI.
    max_residual_to_noise : float
        Largest accepted ratio of the fit's RMS residual to the estimated noise.
    spindle : MeasuredSpindle or None
        The measured spindle on all the measurements' lines (hybrid), else None.
    not_applicable : dict of str to str
        Joint parameters of the assembly that cannot be identified on this spindle, and why.
    """

    base: AssemblySpec
    measurements: tuple[MeasurementData, ...]
    parameters: tuple[str, ...]
    bounds: Mapping[str, tuple[float, float]]
    max_residual_to_noise: float
    spindle: MeasuredSpindle | None = None
    not_applicable: Mapping[str, str] = field(default_factory=dict)


def _bounds(raw: object, base: AssemblySpec, names: tuple[str, ...], holder_tip: bool = False
            ) -> dict[str, tuple[float, float]]:
    out = {}
    given = raw if raw is not None else {}
    if not isinstance(given, Mapping):
        raise InputError("bounds", "must be an object {parameter: [low, high]}")
    for key in given:
        if key not in IDENTIFIABLE:
            raise InputError(f"bounds.{key}", f"unknown parameter (allowed: {', '.join(IDENTIFIABLE)})")
        if holder_tip and key.startswith("spindle_holder."):
            raise InputError(f"bounds.{key}", HOLDER_TIP_REASON)
        if key not in names:
            raise InputError(f"bounds.{key}", "this joint is rigid in the assembly, or of the other kind (a point joint "
                                              "or a clamping along the insertion): nothing to identify")
    for name in names:
        start = float(get_parameter(base, name) or 0.0)
        lo, hi = start / DEFAULT_BOUND_FACTOR, start * DEFAULT_BOUND_FACTOR
        if name in given:
            pair = given[name]
            if (not isinstance(pair, list) or len(pair) != 2
                    or any(isinstance(v, bool) or not isinstance(v, int | float) for v in pair)):
                raise InputError(f"bounds.{name}", "must be [low, high]")
            lo, hi = float(pair[0]), float(pair[1])
            if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi <= MAX_STIFFNESS):
                raise InputError(f"bounds.{name}", f"must satisfy 0 < low < high <= {MAX_STIFFNESS:g}, got "
                                                   f"[{lo:g}, {hi:g}]")
            if not lo <= start <= hi:
                raise InputError(f"bounds.{name}",
                                 f"must contain the starting value {start:g} from the assembly's joints")
        out[name] = (lo, hi)
    return out


def _resolve(spindle: MeasuredSpindleSpec, base: AssemblySpec, tests: Sequence[TapTest],
             resolve_base: BaseResolver | None) -> MeasuredSpindle:
    """The measured spindle on all the measurements' lines, checked against the assembly."""
    if resolve_base is None:
        raise InputError("assembly.spindle", "a measured spindle needs a measurement store: call "
                         "rcsa.app.analyses.identify (the CLI's --store, or the service), which knows it")
    grid = np.unique(np.concatenate([t.frequency_hz for t in tests]))
    try:
        measured = MeasuredSpindle.from_base(grid, resolve_base(spindle, grid))
    except InputError as exc:
        where = "measurements" if exc.field == "frequency" else f"assembly.{exc.field}".rstrip(".")
        raise InputError(where, exc.rule) from None
    try:
        build_model(base, measured.plane)
    except InputError as exc:
        raise InputError(f"assembly.{exc.field}".rstrip("."), exc.rule) from None
    d = measured.artifact_diameter_m
    if measured.plane == "holder_tip" and d is not None:
        for t in tests:
            if abs(t.tool.shank_diameter_m - d) > 1e-6 * d:
                raise InputError(f"{t.path}.tool.shank_diameter_m" if "shank_diameter_m" in t.overrides
                                 else "assembly.tool.shank_diameter_m",
                                 f"must match the shank the holder-tip measurement was taken with ({d:g} m); "
                                 f"got {t.tool.shank_diameter_m:g} m")
    return measured


def parse_identification_request(request: object, resolve_base: BaseResolver | None = None
                                 ) -> IdentificationRequest:
    """Check a joint-identification request and build the measured assemblies.

    Parameters
    ----------
    request : dict
        See the module docstring.
    resolve_base : BaseResolver, optional
        Turns a measured spindle into its receptance (needed when the assembly's spindle is
        ``{"measurement_id": ...}``).

    Returns
    -------
    IdentificationRequest

    Raises
    ------
    InputError
        Unknown fields, arrays of unequal length, frequencies not increasing or not > 0,
        unknown tool overrides, rigid or undamped joints, bounds not containing the start,
        a measured spindle without a store or whose band does not cover the measurements,
        bounds on a joint that is inside a holder-tip measurement, …
    """
    if not isinstance(request, Mapping):
        raise InputError("", "the identification request must be a JSON object")
    o = fields.Fields(request, "", _REQUEST_FIELDS)
    if "assembly" not in request:
        raise InputError("assembly", "is required")
    document = fields.json_object(request["assembly"], "assembly")
    try:
        base = parse_assembly(document)
    except InputError as exc:
        raise InputError(f"assembly.{exc.field}".rstrip("."), exc.rule) from None
    if isinstance(base.spindle, MeasuredSpindleSpec) and resolve_base is None:
        _resolve(base.spindle, base, [], None)  # raises: no store to look the spindle up in
    tests = parse_tap_tests(request.get("measurements"), document.get("tool") or {}, base.materials,
                            extra_fields=("id",), min_lines=MIN_LINES, max_tests=MAX_MEASUREMENTS)
    spindle = None
    if isinstance(base.spindle, MeasuredSpindleSpec):
        spindle = _resolve(base.spindle, base, tests, resolve_base)
    holder_tip = spindle is not None and spindle.plane == "holder_tip"
    not_applicable = {n: HOLDER_TIP_REASON for n in IDENTIFIABLE
                      if holder_tip and n.startswith("spindle_holder.") and base.spindle_holder is not None}
    clamped = isinstance(base.holder_tool, ClampingSpec)
    kind_of = {n: n.endswith("_scale") for n in IDENTIFIABLE if n.startswith("holder_tool.")}
    other = {n for n, is_clamping in kind_of.items() if is_clamping != clamped}
    names = tuple(n for n in IDENTIFIABLE if getattr(base, n.split(".")[0]) is not None and n not in not_applicable
                  and n not in other)
    if not names:
        raise InputError("assembly.joints", "no elastic joint to identify: give starting values for the "
                         "holder–tool joint" + (" (the spindle–holder joint is inside the holder_tip measurement)"
                                                if holder_tip else " or the spindle–holder joint"))
    for name in names:
        if not (get_parameter(base, name) or 0.0) > 0:
            joint, field_name = name.split(".")
            raise InputError(f"assembly.joints.{joint}.{field_name}", "must be > 0: it is the starting guess of "
                             "the identification")
    measurements = tuple(MeasurementData(replace(base, tool=t.tool, frequency_hz=t.frequency_hz), t.frequency_hz,
                                         t.h, t.coherence, t.overrides) for t in tests)
    ratio = o.number("max_residual_to_noise", gt=1.0, le=1.0e6, default=DEFAULT_MAX_RESIDUAL_TO_NOISE)
    return IdentificationRequest(base, measurements, names, _bounds(request.get("bounds"), base, names, holder_tip),
                                 ratio, spindle, not_applicable)

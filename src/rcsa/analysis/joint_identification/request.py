"""Validation of a joint-identification request (``contract.md`` "Joint identification").

The request is a base assembly (its joints are the starting guess) and one or more measured
tool-point FRFs, each of the base assembly with some ``tool`` fields overridden::

    {"assembly": {...},
     "measurements": [{"tool": {"stickout_m": 0.050}, "frequency_hz": [...],
                       "h": {"real": [...], "imag": [...]}, "coherence": [...]}],
     "bounds": {"holder_tool.stiffness_n_m": [1e6, 1e8]},      # optional
     "max_residual_to_noise": 4.0}                              # optional

Every rule is checked here and a violation raises :class:`~rcsa.errors.InputError` naming
the field; the algorithm in :mod:`rcsa.analysis.joint_identification.identify` only sees checked values.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from rcsa.analysis.measured_tool_point import MAX_TAP_TESTS, parse_tap_tests
from rcsa.errors import InputError
from rcsa.model import fields
from rcsa.model.bounds import MAX_STIFFNESS
from rcsa.model.contract import AssemblySpec, SpindleSpec, parse_assembly
from rcsa.model.parameters import get_parameter

__all__ = [
    "IDENTIFIABLE",
    "IdentificationRequest",
    "MeasurementData",
    "parse_identification_request",
]

#: The parameters a joint identification estimates (translational stiffness and damping).
IDENTIFIABLE = ("spindle_holder.stiffness_n_m", "spindle_holder.damping_ns_m",
                "holder_tool.stiffness_n_m", "holder_tool.damping_ns_m")

_REQUEST_FIELDS = ("assembly", "measurements", "bounds", "max_residual_to_noise")
MAX_MEASUREMENTS = MAX_TAP_TESTS
MIN_LINES = 16
#: Default search range of each parameter around its starting value (factor either way).
DEFAULT_BOUND_FACTOR = 100.0
DEFAULT_MAX_RESIDUAL_TO_NOISE = 4.0


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
    """

    base: AssemblySpec
    measurements: tuple[MeasurementData, ...]
    parameters: tuple[str, ...]
    bounds: Mapping[str, tuple[float, float]]
    max_residual_to_noise: float


def _bounds(raw: object, base: AssemblySpec, names: tuple[str, ...]) -> dict[str, tuple[float, float]]:
    out = {}
    given = raw if raw is not None else {}
    if not isinstance(given, Mapping):
        raise InputError("bounds", "must be an object {parameter: [low, high]}")
    for key in given:
        if key not in IDENTIFIABLE:
            raise InputError(f"bounds.{key}", f"unknown parameter (allowed: {', '.join(IDENTIFIABLE)})")
        if key not in names:
            raise InputError(f"bounds.{key}", "this joint is rigid in the assembly: nothing to identify")
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


def parse_identification_request(request: object) -> IdentificationRequest:
    """Check a joint-identification request and build the measured assemblies.

    Parameters
    ----------
    request : dict
        See the module docstring.

    Returns
    -------
    IdentificationRequest

    Raises
    ------
    InputError
        Unknown fields, arrays of unequal length, frequencies not increasing or not > 0,
        unknown tool overrides, rigid or undamped joints, bounds not containing the start, …
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
    if not isinstance(base.spindle, SpindleSpec):
        raise InputError("assembly.spindle", "joint identification needs an analytical spindle (segments "
                         "and bearings), not a measured one")
    names = tuple(n for n in IDENTIFIABLE if getattr(base, n.split(".")[0]) is not None)
    if not names:
        raise InputError("assembly.joints", "both joints are rigid: give starting values for at least one "
                         "elastic joint")
    for name in names:
        if not (get_parameter(base, name) or 0.0) > 0:
            joint, field = name.split(".")
            raise InputError(f"assembly.joints.{joint}.{field}", "must be > 0: it is the starting guess of "
                             "the identification")
    tests = parse_tap_tests(request.get("measurements"), document.get("tool") or {}, base.materials,
                            extra_fields=("id",), min_lines=MIN_LINES, max_tests=MAX_MEASUREMENTS)
    measurements = tuple(MeasurementData(replace(base, tool=t.tool, frequency_hz=t.frequency_hz), t.frequency_hz,
                                         t.h, t.coherence, t.overrides) for t in tests)
    ratio = o.number("max_residual_to_noise", gt=1.0, le=1.0e6, default=DEFAULT_MAX_RESIDUAL_TO_NOISE)
    return IdentificationRequest(base, measurements, names, _bounds(request.get("bounds"), base, names), ratio)

"""Geometry of one Fusion library item: tool lengths, holder segments, neck profile (SI metres).

The rules are listed in :mod:`rcsa.libraries.fusion` (module docstring); this module holds
their code, item by item, for :func:`rcsa.libraries.fusion.library_combinations`. Every
number is read with :func:`rcsa.libraries.quantities.length_value` (numbers stored as strings
accepted, a contradicting unit refused) in the unit of the object it belongs to.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from rcsa.errors import InputError
from rcsa.libraries.profiles import cone_cylinders
from rcsa.libraries.quantities import Unit, length_value, unit_fraction
from rcsa.model.bounds import MIN_LENGTH_M

__all__ = [
    "LENGTH_TOL_M",
    "HolderGeometry",
    "Segment",
    "ShaftOrigin",
    "check_tool_lengths",
    "face_mounted",
    "holder_geometry",
    "holder_segments",
    "mm",
    "neck_fields",
    "shaft_pieces",
    "stickout",
    "tool_geometry",
]

ShaftOrigin = Literal["shoulder", "flute_end"]

LENGTH_TOL_M = 1e-9
"""Equal lengths / diameters after conversion, m."""
_STICKOUT_TOL_M = 1e-5  # assemblyGaugeLength - gaugeLength vs LB


def mm(x_m: float) -> str:
    """A length for messages: ``"40 mm"``."""
    return f"{x_m * 1e3:.6g} mm"


def _length(obj: Mapping[str, Any], key: str, path: str, unit: Unit, *, required: bool) -> float | None:
    """``obj[key]``, a finite number > 0 in the object's unit, or None when absent."""
    value = obj.get(key)
    if value is None:
        if required:
            raise InputError(f"{path}{key}", "missing (required)")
        return None
    return length_value(value, f"{path}{key}", unit)


def _si(x: float, unit: Unit, divisor: int = 1) -> float:
    """``x / divisor`` in metres with a single rounding for integer-valued ``x``."""
    return x * unit[0] / (unit[1] * divisor)


# --------------------------------------------------------------------------- tool


def _tool_unit(item: Mapping[str, Any]) -> Unit:
    if item.get("unit") is None:
        expr = item.get("expressions")
        if isinstance(expr, dict) and isinstance(expr.get("tool_unit"), str):
            return unit_fraction(expr["tool_unit"], "expressions.tool_unit")
    return unit_fraction(item.get("unit"), "unit")


def tool_geometry(item: Mapping[str, Any]) -> dict[str, Any]:
    """Tool lengths in metres (None when absent) plus ``unit`` = (num, den) of the tool.

    Raises
    ------
    InputError
        No unit, no ``geometry`` object, a required length missing, or a value that is not
        a positive number in the tool's unit.
    """
    unit = _tool_unit(item)
    g = item.get("geometry")
    if not isinstance(g, dict):
        raise InputError("geometry", "missing or not a JSON object")
    out: dict[str, Any] = {"unit": unit}
    for key, req in (("DC", True), ("SFDM", True), ("OAL", True), ("LCF", True), ("LB", False),
                     ("shoulder-length", False), ("shoulder-diameter", False),
                     ("assemblyGaugeLength", False)):
        v = _length(g, key, "geometry.", unit, required=req)
        out[key] = None if v is None else _si(v, unit)
    return out


def stickout(geo: Mapping[str, Any], gauge_length_m: float | None, warnings: list[str]) -> float:
    """LB, else ``assemblyGaugeLength − holder gaugeLength`` (with a warning), m."""
    agl = geo["assemblyGaugeLength"]
    derived = None if agl is None or gauge_length_m is None else agl - gauge_length_m
    lb = geo["LB"]
    if lb is None:
        if derived is None or derived <= 0:
            raise InputError("geometry.LB", "missing, and not derivable from "
                                            "assemblyGaugeLength − holder gaugeLength")
        warnings.append(f"LB missing; stickout {mm(derived)} = assemblyGaugeLength − gaugeLength")
        return float(derived)
    if derived is not None and abs(derived - lb) > _STICKOUT_TOL_M:
        warnings.append(f"LB {mm(lb)} differs from assemblyGaugeLength − holder gaugeLength "
                        f"= {mm(derived)}; LB used")
    return float(lb)


def face_mounted(geo: Mapping[str, Any], stickout_m: float) -> bool:
    """True for a tool whose whole length is below the holder (LB = OAL): a shell or face mill on an
    arbor, clamped on the arbor's face rather than in a bore."""
    return bool(abs(stickout_m - geo["OAL"]) <= _STICKOUT_TOL_M)


def check_tool_lengths(geo: Mapping[str, Any], stickout_m: float) -> None:
    """Stickout at most OAL (equal: face-mounted) and flutes within the stickout, or the field at fault named."""
    if stickout_m > geo["OAL"] and not face_mounted(geo, stickout_m):
        raise InputError("geometry.LB", f"stickout {mm(stickout_m)} must not exceed the overall "
                                        f"length OAL {mm(geo['OAL'])}")
    if geo["LCF"] > stickout_m:
        raise InputError("geometry.LCF", f"flute length {mm(geo['LCF'])} exceeds the stickout "
                                         f"LB {mm(stickout_m)}")


# --------------------------------------------------------------------------- holder


@dataclass(frozen=True, slots=True)
class Segment:
    """A Fusion segment in its object's unit: height, tool-side and spindle-side diameters."""

    height: float
    lower: float
    upper: float


@dataclass(frozen=True, slots=True)
class HolderGeometry:
    """Holder segments in Fusion order (tool end first), cut at the gauge line, native unit."""

    segments: tuple[Segment, ...]
    unit: Unit
    gauge_length_m: float | None
    length_m: float


def _segments(obj: Mapping[str, Any], path: str, unit: Unit) -> list[Segment]:
    raw = obj.get("segments")
    if not isinstance(raw, list) or not raw:
        raise InputError(f"{path}segments", "must be a non-empty list of segments")
    out = []
    for k, s in enumerate(raw):
        p = f"{path}segments[{k}]."
        if not isinstance(s, dict):
            raise InputError(p[:-1], "must be a JSON object")
        if s.get("height") is not None and length_value(s["height"], f"{p}height", unit, gt=None) == 0:
            continue  # a zero-height segment adds nothing to a beam
        vals = [_length(s, key, p, unit, required=True) for key in ("height", "lower-diameter", "upper-diameter")]
        out.append(Segment(*vals))  # type: ignore[arg-type]
    return out


def holder_geometry(holder: Mapping[str, Any], warnings: list[str]) -> HolderGeometry:
    """The holder below its gauge line (module docstring of :mod:`rcsa.libraries.fusion`)."""
    unit = unit_fraction(holder.get("unit"), "holder.unit")
    segs = _segments(holder, "holder.", unit)
    tol = LENGTH_TOL_M * unit[1] / unit[0]
    total = sum(s.height for s in segs)
    gauge = _length(holder, "gaugeLength", "holder.", unit, required=False)
    if gauge is None:
        warnings.append("holder.gaugeLength missing; all holder segments used")
        return HolderGeometry(tuple(segs), unit, None, _si(total, unit))
    if gauge > total + tol:
        warnings.append(f"holder.gaugeLength {mm(_si(gauge, unit))} exceeds the segments' total "
                        f"height {mm(_si(total, unit))}; all segments used")
        return HolderGeometry(tuple(segs), unit, _si(gauge, unit), _si(total, unit))
    kept, z = [], 0.0
    for s in segs:
        if z + s.height <= gauge + tol:
            kept.append(s)
            z += s.height
            continue
        if gauge - z > tol:
            part = gauge - z
            if kept and _si(part, unit) < MIN_LENGTH_M:  # a sliver below the shortest beam: the last segment takes it
                last = kept.pop()
                kept.append(Segment(last.height + part, last.lower, last.upper))
            else:
                kept.append(Segment(part, s.lower, s.lower + (s.upper - s.lower) * part / s.height))
            z = gauge
            warnings.append("holder.gaugeLength falls inside a segment; it is cut at the gauge line")
        break
    return HolderGeometry(tuple(kept), unit, _si(gauge, unit), _si(z, unit))


def holder_segments(h: HolderGeometry, bore_m: float, per_cone: int | None, material: str) -> list[dict[str, Any]]:
    """Contract holder segments, gauge line first; a cone in :func:`~rcsa.libraries.profiles.cone_steps`
    cylinders (``per_cone`` overrides)."""
    out = []
    for k, s in enumerate(h.segments):
        if _si(min(s.lower, s.upper), h.unit) <= bore_m + LENGTH_TOL_M:
            raise InputError(f"holder.segments[{k}]",
                             f"outer diameter {mm(_si(min(s.lower, s.upper), h.unit))} is not "
                             f"larger than the bore SFDM {mm(bore_m)}")
        pieces = cone_cylinders(s.height, s.lower, s.upper, per_cone)
        most = max(1, int(_si(s.height, h.unit) / MIN_LENGTH_M))  # no cylinder below the shortest beam
        if len(pieces) > most:
            pieces = cone_cylinders(s.height, s.lower, s.upper, most)
        for _, d in pieces:
            out.append({"length_m": _si(s.height, h.unit, len(pieces)), "outer_diameter_m": _si(d, h.unit),
                        "inner_diameter_m": bore_m, "material": material})
    out.reverse()  # contract order: from the gauge line toward the tool end
    return out


# --------------------------------------------------------------------------- necks


def shaft_pieces(item: Mapping[str, Any], unit: Unit) -> list[Segment] | None:
    """``shaft.segments`` in metres (tool end first), or None when the item has none."""
    shaft = item.get("shaft")
    if shaft is None or (isinstance(shaft, dict) and not shaft.get("segments")):
        return None
    if not isinstance(shaft, dict):
        raise InputError("shaft", "must be a JSON object")
    return [Segment(_si(g.height, unit), _si(g.lower, unit), _si(g.upper, unit))
            for g in _segments(shaft, "shaft.", unit)]


_Piece = tuple[float, float, float, float]  # (z0, z1, d0, d1) from the tip, m


def _clipped(p: _Piece, a: float, b: float) -> _Piece | None:
    z0, z1 = max(p[0], a), min(p[1], b)
    if z1 - z0 <= LENGTH_TOL_M:
        return None
    slope = 0.0 if math.isinf(p[1]) else (p[3] - p[2]) / (p[1] - p[0])
    return (z0, z1, p[2] + slope * (z0 - p[0]), p[2] + slope * (z1 - p[0]))


def neck_fields(geo: Mapping[str, Any], stickout_m: float, shaft: list[Segment] | None, origin: ShaftOrigin,
                warnings: list[str]) -> dict[str, Any]:
    """The tool's neck fields: none, one neck (``shoulder_*``) or a stepped profile.

    The overhang between the flute end and LB is the body up to ``shoulder-length`` and the
    ``shaft`` segments, then SFDM. Where it is thinner than SFDM, a constant diameter gives
    ``shoulder_length_m``/``shoulder_diameter_m``; a varying one (steps, cones) gives
    ``neck_segments`` ``[{"length_m", "diameter_m"}]`` from the flute end toward the holder,
    a cone split by :func:`~rcsa.libraries.profiles.cone_steps`. Parts thicker than SFDM
    are modelled at SFDM (with a warning).
    """
    lcf, sfdm, tol = geo["LCF"], geo["SFDM"], LENGTH_TOL_M
    shoulder, body_d = geo["shoulder-length"], geo["shoulder-diameter"]
    pieces: list[_Piece] = []
    z, body_at_dc = lcf, False
    if shoulder is not None and shoulder > lcf + tol and not (shaft and origin == "flute_end"):
        d = body_d if body_d is not None else geo["DC"]
        body_at_dc = body_d is None and d < sfdm - tol
        pieces.append((lcf, shoulder, d, d))
        z = shoulder
    for s in shaft or ():
        pieces.append((z, z + s.height, s.lower, s.upper))
        z += s.height
    pieces.append((z, math.inf, sfdm, sfdm))

    over = [c for p in pieces if (c := _clipped(p, lcf, stickout_m)) is not None]
    thin = [c for c in over if min(c[2], c[3]) < sfdm - tol]
    if any(max(c[2], c[3]) > sfdm + tol for c in over):
        warnings.append("the tool body between the flutes and the holder is partly thicker than "
                        "the shank; modelled at the shank diameter")
    if not thin:
        return {}
    if body_at_dc:
        warnings.append("shoulder-diameter missing; the body up to shoulder-length taken at DC")
    inside = [c for p in pieces if (c := _clipped(p, stickout_m, stickout_m + 1.0)) is not None
              and min(c[2], c[3]) < sfdm - tol]
    if inside:
        warnings.append(f"the reduced diameter continues into the holder (to "
                        f"{mm(max(c[1] for c in inside))} from the tip, stickout "
                        f"{mm(stickout_m)}); the clamped part is modelled at SFDM")
    end = max(c[1] for c in thin)
    within = [c for c in over if c[0] < end - tol]
    d_min = min(min(c[2], c[3]) for c in within)
    d_max = max(max(c[2], c[3]) for c in within)
    if d_max - d_min <= tol:
        return {"shoulder_length_m": end, "shoulder_diameter_m": d_min}
    steps: list[list[float]] = []  # [length, diameter], from the flute end
    for z0, z1, d0, d1 in within:
        for length, d in cone_cylinders(min(z1, end) - z0, d0, d1):
            d = min(d, sfdm)
            if steps and (abs(steps[-1][1] - d) <= tol or length < MIN_LENGTH_M):
                steps[-1][0] += length  # same diameter, or a sliver the model cannot take
            elif steps and steps[-1][0] < MIN_LENGTH_M:
                steps[-1] = [steps[-1][0] + length, d]
            else:
                steps.append([length, d])
    return {"neck_segments": [{"length_m": length, "diameter_m": d} for length, d in steps]}

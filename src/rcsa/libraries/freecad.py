"""FreeCAD CAM toolbits (``.fctb``) and holders (``.fcholder``) → a tool–holder combination.

A toolbit is ``{"version": 2, "name", "shape", "shape-type", "parameter": {...},
"attribute": {...}}`` whose parameter values are strings with units (``"5.0000 mm"``); a
holder is ``{"version": 1, "name", "units", "profile": [[r, z], ...]}``, an outline revolved
about the tool axis with ``z`` measured from the face the bit comes out of toward the
spindle (FreeCAD ``Path/Tool/toolholder``). :func:`freecad_combination` maps one pair to the
same :class:`~rcsa.libraries.fusion.Combination` as the Fusion importer.

Mapping rules
-------------
* Quantities are parsed strictly: a decimal number, optional spaces, and a length unit
  (``mm``, ``in``, ``m`` and the long spellings of :func:`~rcsa.libraries.unit_to_metres`);
  a bare number or any other unit is an ``error`` entry, never guessed.
* Tool: ``diameter_m`` ← ``Diameter``, ``shank_diameter_m`` ← ``ShankDiameter``,
  ``overall_length_m`` ← ``Length``, ``flute_length_m`` ← ``CuttingEdgeHeight``; FreeCAD has
  no stickout, so the caller gives ``stickout_m``. ``teeth`` ← ``Flutes``; material ←
  ``Material`` through :func:`~rcsa.libraries.tool_materials.tool_material` ("HSS",
  "Carbide", legacy "HighSpeedSteel", "HighCarbonToolSteel", "Sialon", ...), else the
  default with a warning. Neck parameters are not read (a warning says so). An inserted
  length ``Length − stickout`` below twice ``ShankDiameter`` is a warning.
* Holder: the outer radius R(z) of the outline (the largest radius of the outline's edges at
  that height) between consecutive vertex heights is linear; a constant stretch is one
  cylinder, a sloped one equal cylinders at their mid-height diameters, as many as
  :func:`~rcsa.libraries.profiles.cone_steps` gives for its taper (as for Fusion cones;
  ``holder_segments_per_cone`` overrides). FreeCAD holders carry no gauge line: the whole outline is
  taken as the holder below the gauge line, with a warning. Segments run from the top of
  the outline (spindle side) to z = 0 (tool face), the bore is ``ShankDiameter``.
* Id: ``"<toolbit id>@<holder id>"``, each the file stem when read from a path, else
  ``"freecad-<16 hex>"`` of the object's canonical JSON.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from collections.abc import Mapping
from functools import partial
from pathlib import Path
from typing import Any

from rcsa.errors import InputError
from rcsa.libraries.combination import Combination
from rcsa.libraries.profiles import cone_cylinders
from rcsa.libraries.quantities import count_value, unit_to_metres
from rcsa.libraries.tool_materials import tool_material
from rcsa.model import fields
from rcsa.model.assembly import shallow_insertion_note
from rcsa.model.bounds import MAX_HOLDER_SEGMENTS_PER_CONE, MAX_LENGTH_M, MAX_TEETH
from rcsa.model.input_policy import load_json

__all__ = ["MAX_FILE_BYTES", "freecad_combination", "load_freecad_object", "map_toolbit", "parse_length_m"]

MAX_FILE_BYTES = 1024 * 1024
"""Largest accepted ``.fctb`` / ``.fcholder`` file, bytes."""

_QUANTITY = re.compile(r"\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)\s*([A-Za-z]+)\s*")
_SKIPPED_SHAPES = {"probe": "probe", "threadmill": "thread mill", "slittingsaw": "slitting saw"}


def parse_length_m(text: object, field: str) -> float:
    """Parse a FreeCAD length quantity such as ``"5.0000 mm"`` to metres.

    Parameters
    ----------
    text : str
        Number and length unit.
    field : str
        Name used in the error message.

    Returns
    -------
    float
        Length, m.

    Raises
    ------
    InputError
        Not a string, no unit, an unknown unit, or not finite.

    Examples
    --------
    >>> parse_length_m("5.0000 mm", "Diameter")
    0.005
    >>> parse_length_m("0.5in", "Diameter")
    0.0127
    """
    if not isinstance(text, str):
        raise InputError(field, f"must be a quantity string such as '5.0 mm', got {text!r}")
    m = _QUANTITY.fullmatch(text)
    if m is None:
        raise InputError(field, f"must be a number with a length unit such as '5.0 mm', got {text!r}")
    try:
        value = unit_to_metres(float(m.group(1)), m.group(2))
    except InputError as exc:
        raise InputError(field, f"unknown length unit {m.group(2)!r} in {text!r}") from exc
    if not math.isfinite(value):
        raise InputError(field, f"must be finite, got {text!r}")
    if abs(value) > MAX_LENGTH_M:
        raise InputError(field, f"{text!r} is {value:g} m, longer than any machine-tool part ({MAX_LENGTH_M:g} m)")
    return value


def load_freecad_object(source: str | os.PathLike[str] | bytes | Mapping[str, Any]) -> tuple[dict[str, Any], str]:
    """Read a ``.fctb`` or ``.fcholder`` JSON object.

    Parameters
    ----------
    source : path, bytes or Mapping
        A path (``str`` is always a path), the file's bytes, or the parsed object.

    Returns
    -------
    (dict, str)
        The object and its id (file stem, or ``"freecad-<16 hex>"`` of its canonical JSON).

    Raises
    ------
    InputError
        Unreadable, not JSON, or not a JSON object.
    """
    stem = None
    if isinstance(source, Mapping):
        obj: object = json.loads(json.dumps(dict(source)))
    else:
        if isinstance(source, (str, os.PathLike)):
            path = Path(source)
            try:
                if path.stat().st_size > MAX_FILE_BYTES:
                    raise InputError("path", f"{path}: larger than {MAX_FILE_BYTES} bytes")
                raw = path.read_bytes()
            except OSError as exc:
                raise InputError("path", f"{path}: cannot be read ({exc.strerror or exc})") from exc
            stem = path.stem
        elif isinstance(source, (bytes, bytearray, memoryview)):
            raw = bytes(source)
        else:
            raise InputError("source", f"expected a path, bytes or a mapping, got {type(source).__name__}")
        obj = load_json(raw, what="the FreeCAD file")
    if not isinstance(obj, dict):
        raise InputError("", f"a FreeCAD toolbit or holder is a JSON object, got {type(obj).__name__}")
    if stem is None:
        canonical = json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
        stem = "freecad-" + hashlib.sha256(canonical.encode()).hexdigest()[:16]
    return obj, stem


def freecad_combination(
    toolbit: str | os.PathLike[str] | bytes | Mapping[str, Any],
    holder: str | os.PathLike[str] | bytes | Mapping[str, Any],
    *,
    stickout_m: float,
    holder_material: str = "steel",
    tool_material_default: str = "carbide",
    holder_segments_per_cone: int | None = None,
    fluted_diameter_ratio: float = 0.8,
) -> Combination:
    """Map a FreeCAD toolbit in a FreeCAD holder to a tool–holder combination.

    Parameters
    ----------
    toolbit, holder : path, bytes or Mapping
        The ``.fctb`` and ``.fcholder`` (see :func:`load_freecad_object`).
    stickout_m : float
        Length from the holder's tool-end face to the tip, m (FreeCAD does not store it).
    holder_material, tool_material_default : str
        As in :func:`~rcsa.libraries.library_combinations`.
    holder_segments_per_cone : int, optional
        Cylinders per sloped stretch of the holder outline (≥ 1); default from its taper.
    fluted_diameter_ratio : float
        Equivalent fluted diameter / DC, in (0, 1].

    Returns
    -------
    Combination
        ``ok`` with ``holder`` and ``tool`` in the contract format (m), ``skipped`` for a
        probe, thread mill or slitting saw, or ``error`` naming the offending field.

    Raises
    ------
    InputError
        A file cannot be read as a JSON object, or an option is invalid.
    """
    tool_obj, tool_id = load_freecad_object(toolbit)
    holder_obj, holder_id = load_freecad_object(holder)
    return map_toolbit(tool_obj, tool_id, holder_obj, holder_id, stickout_m=stickout_m,
                       holder_material=holder_material, tool_material_default=tool_material_default,
                       holder_segments_per_cone=holder_segments_per_cone,
                       fluted_diameter_ratio=fluted_diameter_ratio)


def map_toolbit(tool_obj: Mapping[str, Any], tool_id: str, holder_obj: Mapping[str, Any] | None,
                holder_id: str | None, *, stickout_m: float, holder_material: str = "steel",
                tool_material_default: str = "carbide", holder_segments_per_cone: int | None = None,
                fluted_diameter_ratio: float = 0.8, index: int = 0, number: int | None = None) -> Combination:
    """:func:`freecad_combination` on objects already read, with their ids (``holder_obj`` None: skipped).

    ``index`` and ``number`` (the ``.fctl`` tool number) are the item's place in its library.
    """
    if isinstance(stickout_m, bool) or not isinstance(stickout_m, (int, float)) \
            or not math.isfinite(stickout_m) or stickout_m <= 0:
        raise InputError("stickout_m", f"must be a number > 0, got {stickout_m!r}")
    if holder_segments_per_cone is not None:
        fields.integer(holder_segments_per_cone, "holder_segments_per_cone", ge=1, le=MAX_HOLDER_SEGMENTS_PER_CONE)
    if isinstance(fluted_diameter_ratio, bool) or not isinstance(fluted_diameter_ratio, (int, float)) \
            or not 0 < fluted_diameter_ratio <= 1:
        raise InputError("fluted_diameter_ratio", f"must be a number in (0, 1], got {fluted_diameter_ratio!r}")
    params: Mapping[str, Any] = tool_obj["parameter"] if isinstance(tool_obj.get("parameter"), dict) else {}
    attrs: Mapping[str, Any] = tool_obj["attribute"] if isinstance(tool_obj.get("attribute"), dict) else {}
    shape = _shape(tool_obj)
    name = tool_obj.get("name")
    warnings: list[str] = []
    entry = partial(Combination, tool_id if holder_id is None else f"{tool_id}@{holder_id}", index,
                    number=number, description=name if isinstance(name, str) else "",
                    teeth=_flutes(params.get("Flutes", attrs.get("Flutes")), warnings), tool_type=shape)
    if shape.lower() in _SKIPPED_SHAPES:
        return entry(status="skipped", reason=f"unsupported tool type: {_SKIPPED_SHAPES[shape.lower()]}",
                     warnings=tuple(warnings))
    if holder_obj is None:
        return entry(status="skipped", reason="no holder", warnings=tuple(warnings))
    try:
        tool = _tool(params, attrs, float(stickout_m), tool_material_default, float(fluted_diameter_ratio),
                     warnings)
        segments = _holder_segments(holder_obj, tool["shank_diameter_m"], holder_segments_per_cone,
                                    holder_material, warnings)
    except InputError as err:
        return entry(status="error", reason=str(err), warnings=tuple(warnings))
    return entry(status="ok", holder={"segments": segments}, tool=tool, warnings=tuple(warnings))


def _shape(obj: Mapping[str, Any]) -> str:
    shape = obj.get("shape-type")
    if isinstance(shape, str) and shape.strip():
        return shape.strip()
    stem = obj.get("shape")
    return Path(stem).stem if isinstance(stem, str) and stem.strip() else "unknown"


def _flutes(value: object, warnings: list[str]) -> int | None:
    if value is None:
        return None
    count = count_value(value)
    if count is not None and 1 <= count <= MAX_TEETH:
        return count
    warnings.append(f"Flutes {value!r} is not an integer from 1 to {MAX_TEETH}; teeth unknown")
    return None


def _tool(params: Mapping[str, Any], attrs: Mapping[str, Any], stickout: float, default_material: str,
          ratio: float, warnings: list[str]) -> dict[str, Any]:
    def length(key: str) -> float:
        if key not in params:
            raise InputError(f"parameter.{key}", "missing (required)")
        v = parse_length_m(params[key], f"parameter.{key}")
        if v <= 0:
            raise InputError(f"parameter.{key}", f"must be > 0, got {params[key]!r}")
        return v

    dc, sfdm, oal, lcf = (length(k) for k in ("Diameter", "ShankDiameter", "Length", "CuttingEdgeHeight"))
    if stickout >= oal:
        raise InputError("stickout_m", f"must be less than the overall length Length ({oal:g} m), got {stickout:g}")
    if lcf > stickout:
        raise InputError("parameter.CuttingEdgeHeight", f"flute length {lcf:g} m exceeds the stickout {stickout:g} m")
    if any(k.lower().startswith("neck") for k in params):
        warnings.append("neck parameters are not modelled; the overhang above the flutes uses ShankDiameter")
    raw = params.get("Material", attrs.get("Material"))
    material, note = tool_material(raw)
    if material is None:
        material = default_material
        what = "missing" if raw is None else f"{raw!r} names no known tool material"
        warnings.append(f"Material {what}; material {default_material!r} assumed")
    elif note is not None:
        warnings.append(f"Material {raw!r} {note}")
    if (shallow := shallow_insertion_note(oal - stickout, sfdm)) is not None:
        warnings.append(shallow)
    return {"material": material, "diameter_m": dc, "shank_diameter_m": sfdm, "overall_length_m": oal,
            "flute_length_m": lcf, "stickout_m": stickout, "fluted_diameter_ratio": ratio}


def outline_radius(profile: list[tuple[float, float]], z: float) -> float:
    """Largest radius of a closed ``(r, z)`` outline at height ``z`` (0 where none).

    Parameters
    ----------
    profile : list of (r, z)
        Vertices in order; the last connects back to the first.
    z : float
        Height, same unit as the profile.

    Returns
    -------
    float
    """
    best = 0.0
    for (r0, z0), (r1, z1) in zip(profile, profile[1:] + profile[:1], strict=True):
        if z0 != z1 and min(z0, z1) <= z <= max(z0, z1):
            best = max(best, r0 + (r1 - r0) * (z - z0) / (z1 - z0))
    return best


def _profile(holder: Mapping[str, Any]) -> tuple[list[tuple[float, float]], str]:
    units = holder.get("units")
    if not isinstance(units, str):
        raise InputError("holder.units", "missing; the outline's length unit must be stated (mm)")
    unit_to_metres(1.0, units)  # validates the spelling
    raw = holder.get("profile")
    if not isinstance(raw, list) or len(raw) < 2:
        raise InputError("holder.profile", "must be a list of at least two [r, z] points")
    pts = []
    for k, p in enumerate(raw):
        ok = isinstance(p, list) and len(p) == 2 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0 for v in p)
        if not ok:
            raise InputError(f"holder.profile[{k}]", f"must be [r, z] with finite numbers ≥ 0, got {p!r}")
        pts.append((float(p[0]), float(p[1])))
        if max(pts[-1]) * unit_to_metres(1.0, units) > MAX_LENGTH_M:
            raise InputError(f"holder.profile[{k}]", f"{p!r} {units} lies {max(pts[-1]) * unit_to_metres(1.0, units):g} m "
                                                     f"from the axis or the base, beyond any holder ({MAX_LENGTH_M:g} m)")
    return pts, units


def _holder_segments(holder: Mapping[str, Any], bore_m: float, per_cone: int | None, material: str,
                     warnings: list[str]) -> list[dict[str, Any]]:
    try:
        pts, units = _profile(holder)
    except InputError as err:  # unit spelling errors carry the generic field name
        raise InputError(err.field if err.field.startswith("holder.") else "holder.units", err.rule) from err
    heights = sorted({z for _, z in pts})
    if len(heights) < 2:
        raise InputError("holder.profile", "has no height (all points at one z)")
    pieces: list[tuple[float, float]] = []  # (length, diameter), from z = 0 upward, native unit
    for z0, z1 in zip(heights, heights[1:], strict=False):
        h = z1 - z0
        r_lo, r_hi = outline_radius(pts, z0 + 0.25 * h), outline_radius(pts, z0 + 0.75 * h)
        if min(r_lo, r_hi) <= 0:
            raise InputError("holder.profile", f"leaves a gap between z = {z0:g} and {z1:g}")
        # R is linear over the stretch: its values at the quarter points fix the end diameters
        d0, d1 = 2 * (1.5 * r_lo - 0.5 * r_hi), 2 * (1.5 * r_hi - 0.5 * r_lo)
        pieces.extend(cone_cylinders(h, d0, d1, 1 if r_lo == r_hi else per_cone))  # None: from the taper
    out = []
    for length, d in reversed(pieces):
        outer, length_m = unit_to_metres(d, units), unit_to_metres(length, units)
        if outer <= bore_m:
            raise InputError("holder.profile", f"outer diameter {outer:g} m is not larger than the bore "
                                               f"ShankDiameter {bore_m:g} m")
        out.append({"length_m": length_m, "outer_diameter_m": outer, "inner_diameter_m": bore_m,
                    "material": material})
    warnings.append(f"FreeCAD holders have no gauge line: the whole outline "
                    f"({unit_to_metres(heights[-1] - heights[0], units):g} m) is taken as the holder")
    return out

"""Autodesk Fusion (HSM / Inventor CAM) tool libraries → tool–holder combinations.

A Fusion library is ``{"data": [...], "version": n}`` (``.json``), or the same JSON stored as
``tools.json`` in a zip (``.tools``). Each ``data`` item is a cutting tool, possibly with its
holder embedded under ``"holder"``, or a standalone holder (``"type": "holder"``).
:func:`library_combinations` turns every item into one :class:`Combination` whose ``holder``
and ``tool`` are in the contract's assembly format (SI metres, ``contract.md``).

Mapping rules (the choices made here)
-------------------------------------
Units
    Per object: the tool's ``unit`` (or ``expressions.tool_unit``) and the holder's own
    ``unit`` independently. Accepted spellings (case-insensitive): millimeters, millimeter,
    millimetres, millimetre, mm; inches, inch, in; meters, meter, metres, metre, m.
    Anything else is an ``error`` entry; a unit is never guessed.
Ids
    The Fusion ``guid`` when present; else ``"T<post-process.number>"`` when that number is
    unique among the library's guid-less items; else ``"fusion-<16 hex>"``, the start of the
    SHA-256 of the item's canonical JSON (sorted keys), stable for identical content.
    Ids are unique within one import: a repeated id gets ``"~2"``, ``"~3"``, ... in library
    order, with a warning.
Holder
    Fusion lists holder segments from the tool end (first element) to the spindle end;
    ``lower-diameter`` is the tool-side face. Segments whose cumulative height from the tool
    end is within ``gaugeLength`` are kept (a segment straddling the gauge line is cut at it,
    with a warning); without ``gaugeLength`` all segments are kept, with a warning. The kept
    list is reversed so that it runs from the gauge line toward the tool end (contract order).
    A cone (lower ≠ upper diameter) becomes ``holder_segments_per_cone`` cylinders of equal
    length, each at the cone's diameter at the middle of its piece (this preserves the
    length and the mean diameter exactly; the volume is underestimated by
    π·h·Δd²/(48·n²), 0.03 % for a 42→50 mm, 8 mm cone with n = 4). A cylinder stays one.
    The bore (``inner_diameter_m``) is the tool's shank diameter SFDM everywhere.
Tool
    ``diameter_m`` ← DC, ``shank_diameter_m`` ← SFDM, ``overall_length_m`` ← OAL,
    ``flute_length_m`` ← LCF, ``stickout_m`` ← LB (Fusion "length below holder"; when LB is
    absent it is ``assemblyGaugeLength − holder gaugeLength``, with a warning; when both are
    present a mismatch over 0.01 mm is a warning). ``material`` ← ``BMC`` ("carbide",
    "hss"), else ``tool_material_default`` with a warning.
Necks
    The overhang profile from the flute end to LB is built from ``shoulder-length`` /
    ``shoulder-diameter`` (the body between the flute end and the shoulder; at DC when no
    shoulder diameter is given) and ``shaft.segments`` (same schema and order as holder
    segments, stacked from the shoulder, or from the flute end with
    ``shaft_origin="flute_end"``), then SFDM. Where it is thinner than SFDM the tool gets the
    contract extension fields ``shoulder_length_m`` (from the tip to the end of the thin part,
    capped at the stickout) and ``shoulder_diameter_m`` (the smallest diameter there); a
    profile that is not one constant neck is approximated that way with a warning.
    A body thicker than the shank is modelled at the shank diameter, with a warning.
"""

from __future__ import annotations

import copy
import hashlib
import io
import json
import math
import os
import zipfile
from collections import Counter
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any, Literal

from rcsa.errors import InputError
from rcsa.model import fields
from rcsa.model.bounds import MAX_HOLDER_SEGMENTS_PER_CONE, MIN_FLUTED_DIAMETER_RATIO

__all__ = [
    "SUPPORTED_TOOL_TYPES",
    "Combination",
    "FusionLibrary",
    "cone_cylinders",
    "LibraryImport",
    "library_combinations",
    "load_fusion_library",
    "unit_to_metres",
]

Status = Literal["ok", "skipped", "error"]
ShaftOrigin = Literal["shoulder", "flute_end"]

MAX_LIBRARY_BYTES = 64 * 1024 * 1024
"""Largest accepted library file or ``tools.json`` inside a ``.tools`` zip, bytes."""

_UNIT_FRACTIONS: dict[str, tuple[int, int]] = {}
for _names, _frac in (
    (("millimeters", "millimeter", "millimetres", "millimetre", "mm"), (1, 1000)),
    (("inches", "inch", "in"), (254, 10000)),
    (("meters", "meter", "metres", "metre", "m"), (1, 1)),
):
    for _name in _names:
        _UNIT_FRACTIONS[_name] = _frac

SUPPORTED_TOOL_TYPES = frozenset({
    "flat end mill", "ball end mill", "bull nose end mill", "chamfer mill", "face mill",
    "slot mill", "radius mill", "dovetail mill", "tapered mill", "lollipop mill", "drill",
    "center drill", "spot drill", "counter bore", "counter sink", "reamer", "boring bar",
    "bore mill", "tap right hand", "tap left hand", "form mill",
})
"""Fusion ``type`` values imported; a ``form mill`` also needs a ``profile``."""

_LENGTH_TOL_M = 1e-9   # equal lengths / diameters after conversion
_STICKOUT_TOL_M = 1e-5  # assemblyGaugeLength - gaugeLength vs LB


class _Skip(Exception):
    """Internal: the item is not a tool we model (status ``skipped``)."""


# --------------------------------------------------------------------------- loading


@dataclass(frozen=True, slots=True)
class FusionLibrary:
    """A parsed Fusion tool library.

    Parameters
    ----------
    items : tuple
        The ``data`` items in file order, as parsed JSON (normally dicts).
    version : object
        The document's ``version`` (informative only; it varies between exports).
    sha256 : str
        SHA-256 (hex) of the document's canonical JSON: the same for a ``.json`` file, the
        ``.tools`` zip holding it and the parsed dict.
    source : str
        File path, ``"<bytes>"`` or ``"<mapping>"``.
    """

    items: tuple[Any, ...]
    version: object
    sha256: str
    source: str


def unit_to_metres(value: float, unit: str) -> float:
    """Convert a length in a Fusion unit spelling to metres.

    Parameters
    ----------
    value : float
        Length in ``unit``.
    unit : str
        A spelling listed in the module docstring (e.g. ``"inches"``, ``"millimeters"``).

    Returns
    -------
    float
        Length, m (one rounding: ``value * num / den`` with an exact integer ratio).

    Examples
    --------
    >>> unit_to_metres(0.5, "inches")
    0.0127
    >>> unit_to_metres(72, "millimeters")
    0.072
    """
    num, den = _unit_fraction(unit, "unit")
    return value * num / den


def _unit_fraction(unit: object, field: str) -> tuple[int, int]:
    if not isinstance(unit, str) or not unit.strip():
        raise InputError(field, "missing; the length unit must be stated (millimeters or inches)")
    key = unit.strip().strip("'\"").strip().lower()
    if key not in _UNIT_FRACTIONS:
        raise InputError(field, f"unknown length unit {unit!r} (use millimeters or inches)")
    return _UNIT_FRACTIONS[key]


def load_fusion_library(source: str | os.PathLike[str] | bytes | Mapping[str, Any] | FusionLibrary,
                        ) -> FusionLibrary:
    """Read a Fusion tool library from a ``.json``/``.tools`` file, its bytes, or a dict.

    Parameters
    ----------
    source : str, os.PathLike, bytes or Mapping
        A path (``str`` is always a path), the file's bytes (a zip is recognised by its
        ``PK`` signature and must hold ``tools.json``), or the parsed document.

    Returns
    -------
    FusionLibrary

    Raises
    ------
    InputError
        Unreadable file, not JSON, a zip without ``tools.json``, or no ``data`` list.
    """
    if isinstance(source, FusionLibrary):
        return source
    if isinstance(source, Mapping):
        return _library_from_document(copy.deepcopy(dict(source)), "<mapping>")
    if isinstance(source, (bytes, bytearray, memoryview)):
        return _library_from_document(_parse_bytes(bytes(source)), "<bytes>")
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        try:
            if path.stat().st_size > MAX_LIBRARY_BYTES:
                raise InputError("path", f"{path}: larger than {MAX_LIBRARY_BYTES} bytes")
            raw = path.read_bytes()
        except OSError as exc:
            raise InputError("path", f"{path}: cannot be read ({exc.strerror or exc})") from exc
        return _library_from_document(_parse_bytes(raw), str(path))
    raise InputError("source", f"expected a path, bytes or a mapping, got {type(source).__name__}")


def _parse_bytes(raw: bytes) -> object:
    if raw.startswith(b"PK"):
        raw = _tools_json_from_zip(raw)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError("", "not UTF-8 text: expected a Fusion tool-library JSON or a .tools zip"
                         ) from exc
    try:
        return json.loads(text, parse_constant=_reject_constant)
    except json.JSONDecodeError as exc:
        raise InputError("", f"not valid JSON ({exc.msg} at line {exc.lineno} column {exc.colno})"
                         ) from exc


def _reject_constant(name: str) -> float:
    raise InputError("", f"not valid JSON: {name} is not a number")


def _tools_json_from_zip(raw: bytes) -> bytes:
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as zf:
            infos = [i for i in zf.infolist()
                     if not i.is_dir() and PurePosixPath(i.filename).name.lower() == "tools.json"]
            root = [i for i in infos if i.filename.lower() == "tools.json"]
            if root:
                infos = root
            if len(infos) != 1:
                names = ", ".join(zf.namelist()[:10]) or "none"
                what = "no tools.json" if not infos else "several tools.json"
                raise InputError("", f".tools archive has {what} (members: {names})")
            if infos[0].file_size > MAX_LIBRARY_BYTES:
                raise InputError("", f"tools.json is larger than {MAX_LIBRARY_BYTES} bytes")
            with zf.open(infos[0]) as fh:
                data = fh.read(MAX_LIBRARY_BYTES + 1)
    except (zipfile.BadZipFile, RuntimeError, NotImplementedError, OSError) as exc:
        raise InputError("", f"not a readable .tools zip archive ({exc})") from exc
    if len(data) > MAX_LIBRARY_BYTES:
        raise InputError("", f"tools.json is larger than {MAX_LIBRARY_BYTES} bytes")
    return data


def _library_from_document(doc: object, source: str) -> FusionLibrary:
    if not isinstance(doc, dict):
        raise InputError("", "a Fusion tool library is a JSON object {\"data\": [...], ...}, "
                             f"got a JSON {type(doc).__name__}")
    if "data" not in doc:
        raise InputError("data", "missing: a Fusion tool library is a JSON object "
                                 "{\"data\": [tools and holders], \"version\": n}")
    if not isinstance(doc["data"], list):
        raise InputError("data", f"must be a list of tools and holders, got {type(doc['data']).__name__}")
    return FusionLibrary(items=tuple(doc["data"]), version=doc.get("version"),
                         sha256=hashlib.sha256(_canonical(doc)).hexdigest(), source=source)


def _canonical(obj: object) -> bytes:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=False,
                      default=str).encode()


# --------------------------------------------------------------------------- results


@dataclass(frozen=True, slots=True)
class Combination:
    """One library item mapped to a tool–holder combination.

    Parameters
    ----------
    id : str
        Stable identifier (module docstring, "Ids").
    index : int
        Position of the item in the library's ``data`` list.
    status : {"ok", "skipped", "error"}
    description : str
    number : int or None
        Fusion T number (``post-process.number``).
    teeth : int or None
        Number of flutes ``NOF`` (for stability lobes).
    tool_type : str or None
        Fusion ``type``.
    reason : str or None
        Why the item was skipped or rejected (``"field: rule"`` for errors).
    holder : dict or None
        ``{"segments": [{"length_m", "outer_diameter_m", "inner_diameter_m", "material"}]}``
        from the gauge line toward the tool end, metres; ``ok`` entries only. Treat as read-only.
    tool : dict or None
        Contract tool (``material, diameter_m, shank_diameter_m, overall_length_m,
        flute_length_m, stickout_m, fluted_diameter_ratio`` and, for necked tools,
        ``shoulder_length_m, shoulder_diameter_m``), metres; ``ok`` entries only.
    warnings : tuple of str
        Approximations and inconsistencies noticed on the way.
    """

    id: str
    index: int
    status: Status
    description: str = ""
    number: int | None = None
    teeth: int | None = None
    tool_type: str | None = None
    reason: str | None = None
    holder: dict[str, Any] | None = None
    tool: dict[str, Any] | None = None
    warnings: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-ready dict (fresh copies of ``holder`` and ``tool``)."""
        return {"id": self.id, "index": self.index, "status": self.status,
                "description": self.description, "number": self.number, "teeth": self.teeth,
                "tool_type": self.tool_type, "reason": self.reason,
                "warnings": list(self.warnings), "holder": copy.deepcopy(self.holder),
                "tool": copy.deepcopy(self.tool)}

    def batch_item(self) -> dict[str, Any]:
        """Return ``{"id", "holder", "tool"}`` for the batch endpoint (``ok`` entries only).

        Raises
        ------
        InputError
            The entry is skipped or in error.
        """
        if self.status != "ok":
            raise InputError(self.id, f"is {self.status} ({self.reason}), not a combination")
        return {"id": self.id, "holder": copy.deepcopy(self.holder), "tool": copy.deepcopy(self.tool)}


@dataclass(frozen=True, slots=True)
class LibraryImport:
    """All items of one library, in library order, with a count by status.

    Parameters
    ----------
    combinations : tuple of Combination
    summary : dict
        ``{"ok": n, "skipped": n, "error": n}``.
    source : str
    library_sha256 : str
    """

    combinations: tuple[Combination, ...]
    summary: dict[str, int]
    source: str
    library_sha256: str

    def __iter__(self) -> Iterator[Combination]:
        """Iterate over the combinations in library order."""
        return iter(self.combinations)

    def __len__(self) -> int:
        """Return the number of library items."""
        return len(self.combinations)

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-ready dict."""
        return {"source": self.source, "library_sha256": self.library_sha256,
                "summary": dict(self.summary),
                "combinations": [c.to_dict() for c in self.combinations]}


# --------------------------------------------------------------------------- mapping


def library_combinations(
    library: FusionLibrary | str | os.PathLike[str] | bytes | Mapping[str, Any],
    *,
    holder_material: str = "steel",
    tool_material_default: str = "carbide",
    holder_segments_per_cone: int = 4,
    fluted_diameter_ratio: float = 0.8,
    shaft_origin: ShaftOrigin = "shoulder",
    default_holder: str | Mapping[str, Any] | None = None,
) -> LibraryImport:
    """Map every item of a Fusion library to a tool–holder combination.

    Parameters
    ----------
    library : FusionLibrary, path, bytes or Mapping
        Anything :func:`load_fusion_library` accepts.
    holder_material : str
        Material name given to every holder segment.
    tool_material_default : str
        Tool material when ``BMC`` is absent or neither "carbide" nor "hss".
    holder_segments_per_cone : int
        Cylinders per conical holder segment (≥ 1).
    fluted_diameter_ratio : float
        Equivalent fluted diameter / DC, in (0, 1].
    shaft_origin : {"shoulder", "flute_end"}
        Where ``shaft.segments`` start: at ``shoulder-length`` (default) or at the flute end.
    default_holder : str, Mapping or None
        Holder for tools that have none: the ``guid`` of a standalone holder in the library,
        or a Fusion holder object. ``None`` skips such tools ("no holder").

    Returns
    -------
    LibraryImport
        One :class:`Combination` per ``data`` item, in library order; a bad item is an
        ``error`` entry and never fails the others.

    Raises
    ------
    InputError
        The library cannot be read, or an option is invalid.
    """
    lib = load_fusion_library(library)
    opts = _Options(
        holder_material=_name_option(holder_material, "holder_material"),
        tool_material_default=_name_option(tool_material_default, "tool_material_default"),
        per_cone=_per_cone_option(holder_segments_per_cone),
        ratio=_ratio_option(fluted_diameter_ratio),
        shaft_origin=_shaft_origin_option(shaft_origin),
        default_holder=_default_holder_option(default_holder, lib),
    )
    ids = _assign_ids(lib.items)
    combos = tuple(_combination(i, item, ident, dup, opts)
                   for i, (item, (ident, dup)) in enumerate(zip(lib.items, ids, strict=True)))
    counts = Counter(c.status for c in combos)
    summary = {s: counts.get(s, 0) for s in ("ok", "skipped", "error")}
    return LibraryImport(combos, summary, lib.source, lib.sha256)


@dataclass(frozen=True, slots=True)
class _Options:
    holder_material: str
    tool_material_default: str
    per_cone: int
    ratio: float
    shaft_origin: ShaftOrigin
    default_holder: Mapping[str, Any] | None


def _name_option(value: object, field: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise InputError(field, "must be a non-empty material name")
    return value


def _per_cone_option(value: object) -> int:
    return fields.integer(value, "holder_segments_per_cone", ge=1, le=MAX_HOLDER_SEGMENTS_PER_CONE)


def _ratio_option(value: object) -> float:
    return fields.number(value, "fluted_diameter_ratio", gt=0.0, ge=MIN_FLUTED_DIAMETER_RATIO, le=1.0)


def _shaft_origin_option(value: object) -> ShaftOrigin:
    if value not in ("shoulder", "flute_end"):
        raise InputError("shaft_origin", f"must be 'shoulder' or 'flute_end', got {value!r}")
    return value  # type: ignore[return-value]


def _default_holder_option(value: object, lib: FusionLibrary) -> Mapping[str, Any] | None:
    if value is None or isinstance(value, Mapping):
        return value
    if isinstance(value, str):
        for item in lib.items:
            if isinstance(item, dict) and item.get("type") == "holder" and item.get("guid") == value:
                return item
        raise InputError("default_holder", f"no standalone holder with guid {value!r} in the library")
    raise InputError("default_holder", "must be a holder guid, a Fusion holder object or None")


def _assign_ids(items: tuple[Any, ...]) -> list[tuple[str, int]]:
    """Return ``(id, occurrence)`` per item; occurrence > 1 marks a repeated base id."""
    def guid(item: object) -> str | None:
        g = item.get("guid") if isinstance(item, dict) else None
        return g.strip() if isinstance(g, str) and g.strip() else None

    numbers = [None if guid(it) else _t_number(it) for it in items]
    number_counts = Counter(n for n in numbers if n is not None)
    base = []
    for item, n in zip(items, numbers, strict=True):
        g = guid(item)
        if g is not None:
            base.append(g)
        elif n is not None and number_counts[n] == 1:
            base.append(f"T{n}")
        else:
            base.append("fusion-" + hashlib.sha256(_canonical(item)).hexdigest()[:16])
    seen: Counter[str] = Counter()
    out = []
    for b in base:
        seen[b] += 1
        out.append((b if seen[b] == 1 else f"{b}~{seen[b]}", seen[b]))
    return out


def _t_number(item: object) -> int | None:
    pp = item.get("post-process") if isinstance(item, dict) else None
    n = pp.get("number") if isinstance(pp, dict) else None
    return _as_int(n)


def _as_int(value: object) -> int | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    if isinstance(value, float) and not (math.isfinite(value) and value.is_integer()):
        return None
    return int(value)


def _combination(index: int, item: object, ident: str, occurrence: int, opts: _Options) -> Combination:
    warnings: list[str] = []
    if occurrence > 1:
        warnings.append(f"id repeated in the library; this entry is {ident!r}")
    if not isinstance(item, dict):
        return Combination(ident, index, "error", reason=f"data[{index}]: not a JSON object",
                           warnings=tuple(warnings))
    desc = item.get("description")
    tool_type = item.get("type") if isinstance(item.get("type"), str) else None
    nof = item.get("geometry", {}).get("NOF") if isinstance(item.get("geometry"), dict) else None
    teeth = _as_int(nof)
    if teeth is not None and teeth < 1:
        teeth = None
    if nof is not None and teeth is None:
        warnings.append(f"geometry.NOF {nof!r} is not a positive integer; teeth unknown")
    meta = {"description": desc if isinstance(desc, str) else "", "number": _t_number(item),
            "teeth": teeth, "tool_type": tool_type}
    try:
        holder, tool = _map_item(item, opts, warnings)
    except _Skip as skip:
        return Combination(ident, index, "skipped", reason=str(skip), warnings=tuple(warnings), **meta)
    except InputError as err:
        return Combination(ident, index, "error", reason=str(err), warnings=tuple(warnings), **meta)
    return Combination(ident, index, "ok", holder=holder, tool=tool, warnings=tuple(warnings), **meta)


def _map_item(item: dict[str, Any], opts: _Options, warnings: list[str],
              ) -> tuple[dict[str, Any], dict[str, Any]]:
    tool_type = item.get("type")
    if not isinstance(tool_type, str) or not tool_type.strip():
        raise InputError("type", "missing: the Fusion tool type is required")
    kind = tool_type.strip().lower()
    if kind == "holder":
        raise _Skip("standalone holder (type: holder), not a tool")
    if kind not in SUPPORTED_TOOL_TYPES:
        raise _Skip(f"unsupported tool type: {tool_type}")
    if kind == "form mill":
        if not item.get("profile"):
            raise _Skip("unsupported tool type: form mill without profile")
        warnings.append("form mill: the profile is not modelled; the fluted section uses DC")
    holder_obj = item.get("holder")
    if holder_obj is not None and not isinstance(holder_obj, dict):
        raise InputError("holder", "must be a JSON object")
    if not holder_obj:
        if opts.default_holder is None:
            raise _Skip("no holder")
        holder_obj = opts.default_holder
        warnings.append("no holder in the library entry; default_holder used")
        own_holder = False
    else:
        own_holder = True
    geo = _tool_geometry(item, warnings)
    holder_si = _holder_geometry(holder_obj, warnings)
    stickout = _stickout(geo, holder_si.gauge_length_m if own_holder else None, warnings)
    _check_tool_lengths(geo, stickout)
    tool = {
        "material": _tool_material(item.get("BMC"), opts.tool_material_default, warnings),
        "diameter_m": geo["DC"], "shank_diameter_m": geo["SFDM"],
        "overall_length_m": geo["OAL"], "flute_length_m": geo["LCF"], "stickout_m": stickout,
        "fluted_diameter_ratio": opts.ratio,
    }
    neck = _neck(geo, stickout, _shaft_pieces(item, geo["unit"]), opts.shaft_origin, warnings)
    if neck is not None:
        tool["shoulder_length_m"], tool["shoulder_diameter_m"] = neck
    holder = {"segments": _holder_segments(holder_si, geo["SFDM"], opts)}
    inserted = geo["OAL"] - stickout
    if inserted > holder_si.length_m + _LENGTH_TOL_M:
        warnings.append(f"inserted length {_mm(inserted)} exceeds the holder length "
                        f"{_mm(holder_si.length_m)} below the gauge line; the excess is ignored")
    return holder, tool


def _mm(x_m: float) -> str:
    return f"{x_m * 1e3:.6g} mm"


def _number(obj: Mapping[str, Any], key: str, path: str, *, required: bool) -> float | None:
    """Return ``obj[key]``, a finite number > 0 in the object's unit, or None when absent."""
    value = obj.get(key)
    if value is None:
        if required:
            raise InputError(f"{path}{key}", "missing (required)")
        return None
    return fields.number(value, f"{path}{key}", gt=0.0)


def _tool_unit(item: Mapping[str, Any]) -> tuple[int, int]:
    if item.get("unit") is None:
        expr = item.get("expressions")
        if isinstance(expr, dict) and isinstance(expr.get("tool_unit"), str):
            return _unit_fraction(expr["tool_unit"], "expressions.tool_unit")
    return _unit_fraction(item.get("unit"), "unit")


def _tool_geometry(item: Mapping[str, Any], warnings: list[str]) -> dict[str, Any]:
    """Tool lengths in metres (None when absent) plus ``unit`` = (num, den)."""
    num, den = _tool_unit(item)
    g = item.get("geometry")
    if not isinstance(g, dict):
        raise InputError("geometry", "missing or not a JSON object")
    out: dict[str, Any] = {"unit": (num, den)}
    for key, req in (("DC", True), ("SFDM", True), ("OAL", True), ("LCF", True), ("LB", False),
                     ("shoulder-length", False), ("shoulder-diameter", False),
                     ("assemblyGaugeLength", False)):
        v = _number(g, key, "geometry.", required=req)
        out[key] = None if v is None else v * num / den
    return out


def _tool_material(bmc: object, default: str, warnings: list[str]) -> str:
    key = bmc.strip().lower() if isinstance(bmc, str) else None
    if key in ("carbide", "hss"):
        if key == "hss":
            warnings.append("material 'hss' is not built in: define it under 'materials'")
        return key
    what = "missing" if bmc is None else f"{bmc!r} is neither 'carbide' nor 'hss'"
    warnings.append(f"BMC {what}; material {default!r} assumed")
    return default


def _stickout(geo: Mapping[str, Any], gauge_length_m: float | None, warnings: list[str]) -> float:
    agl = geo["assemblyGaugeLength"]
    derived = None if agl is None or gauge_length_m is None else agl - gauge_length_m
    lb = geo["LB"]
    if lb is None:
        if derived is None or derived <= 0:
            raise InputError("geometry.LB", "missing, and not derivable from "
                                            "assemblyGaugeLength − holder gaugeLength")
        warnings.append(f"LB missing; stickout {_mm(derived)} = assemblyGaugeLength − gaugeLength")
        return derived
    if derived is not None and abs(derived - lb) > _STICKOUT_TOL_M:
        warnings.append(f"LB {_mm(lb)} differs from assemblyGaugeLength − holder gaugeLength "
                        f"= {_mm(derived)}; LB used")
    return lb


def _check_tool_lengths(geo: Mapping[str, Any], stickout: float) -> None:
    if stickout >= geo["OAL"]:
        raise InputError("geometry.LB", f"stickout {_mm(stickout)} must be less than the overall "
                                        f"length OAL {_mm(geo['OAL'])}")
    if geo["LCF"] > stickout:
        raise InputError("geometry.LCF", f"flute length {_mm(geo['LCF'])} exceeds the stickout "
                                         f"LB {_mm(stickout)}")


# --------------------------------------------------------------------------- holder


@dataclass(frozen=True, slots=True)
class _Segment:
    """A Fusion segment in its object's unit: height, tool-side and spindle-side diameters."""

    height: float
    lower: float
    upper: float


@dataclass(frozen=True, slots=True)
class _HolderGeometry:
    """Holder segments in Fusion order (tool end first), cut at the gauge line, native unit."""

    segments: tuple[_Segment, ...]
    unit: tuple[int, int]
    gauge_length_m: float | None
    length_m: float


def _si(x: float, unit: tuple[int, int], divisor: int = 1) -> float:
    """``x / divisor`` in metres with a single rounding for integer-valued ``x``."""
    return x * unit[0] / (unit[1] * divisor)


def _segments(obj: Mapping[str, Any], path: str) -> list[_Segment]:
    raw = obj.get("segments")
    if not isinstance(raw, list) or not raw:
        raise InputError(f"{path}segments", "must be a non-empty list of segments")
    out = []
    for k, s in enumerate(raw):
        p = f"{path}segments[{k}]."
        if not isinstance(s, dict):
            raise InputError(p[:-1], "must be a JSON object")
        h = s.get("height")
        if isinstance(h, (int, float)) and not isinstance(h, bool) and h == 0:
            continue  # a zero-height segment adds nothing to a beam
        vals = [_number(s, key, p, required=True) for key in ("height", "lower-diameter", "upper-diameter")]
        out.append(_Segment(*vals))  # type: ignore[arg-type]
    return out


def _holder_geometry(holder: Mapping[str, Any], warnings: list[str]) -> _HolderGeometry:
    unit = _unit_fraction(holder.get("unit"), "holder.unit")
    segs = _segments(holder, "holder.")
    tol = _LENGTH_TOL_M * unit[1] / unit[0]
    total = sum(s.height for s in segs)
    gauge = _number(holder, "gaugeLength", "holder.", required=False)
    if gauge is None:
        warnings.append("holder.gaugeLength missing; all holder segments used")
        return _HolderGeometry(tuple(segs), unit, None, _si(total, unit))
    if gauge > total + tol:
        warnings.append(f"holder.gaugeLength {_mm(_si(gauge, unit))} exceeds the segments' total "
                        f"height {_mm(_si(total, unit))}; all segments used")
        return _HolderGeometry(tuple(segs), unit, _si(gauge, unit), _si(total, unit))
    kept, z = [], 0.0
    for s in segs:
        if z + s.height <= gauge + tol:
            kept.append(s)
            z += s.height
            continue
        if gauge - z > tol:
            part = gauge - z
            kept.append(_Segment(part, s.lower, s.lower + (s.upper - s.lower) * part / s.height))
            z = gauge
            warnings.append("holder.gaugeLength falls inside a segment; it is cut at the gauge line")
        break
    return _HolderGeometry(tuple(kept), unit, _si(gauge, unit), _si(z, unit))


def cone_cylinders(height: float, lower: float, upper: float, n: int) -> list[tuple[float, float]]:
    """Approximate a cone by ``n`` equal-length cylinders at their mid-length diameters.

    Parameters
    ----------
    height : float
        Cone length (any length unit; the output uses the same).
    lower, upper : float
        Diameters at the first and the last end.
    n : int
        Number of cylinders; a cylinder (``lower == upper``) always gives one.

    Returns
    -------
    list of (length, diameter)
        From the ``lower`` end to the ``upper`` end. The lengths add up to ``height`` and the
        mean diameter is kept; the volume is low by π·height·(upper − lower)²/(48·n²).

    Examples
    --------
    >>> cone_cylinders(8.0, 42.0, 50.0, 4)
    [(2.0, 43.0), (2.0, 45.0), (2.0, 47.0), (2.0, 49.0)]
    """
    if upper == lower:
        return [(height, lower)]
    return [(height / n, lower + (upper - lower) * (2 * k + 1) / (2 * n)) for k in range(n)]


def _holder_segments(h: _HolderGeometry, bore_m: float, opts: _Options) -> list[dict[str, Any]]:
    out = []
    for k, s in enumerate(h.segments):
        if _si(min(s.lower, s.upper), h.unit) <= bore_m + _LENGTH_TOL_M:
            raise InputError(f"holder.segments[{k}]",
                             f"outer diameter {_mm(_si(min(s.lower, s.upper), h.unit))} is not "
                             f"larger than the bore SFDM {_mm(bore_m)}")
        n = 1 if s.upper == s.lower else opts.per_cone
        for _, d in cone_cylinders(s.height, s.lower, s.upper, n):
            out.append({"length_m": _si(s.height, h.unit, n), "outer_diameter_m": _si(d, h.unit),
                        "inner_diameter_m": bore_m, "material": opts.holder_material})
    out.reverse()  # contract order: from the gauge line toward the tool end
    return out


# --------------------------------------------------------------------------- necks


def _shaft_pieces(item: Mapping[str, Any], unit: tuple[int, int]) -> list[_Segment] | None:
    shaft = item.get("shaft")
    if shaft is None or (isinstance(shaft, dict) and not shaft.get("segments")):
        return None
    if not isinstance(shaft, dict):
        raise InputError("shaft", "must be a JSON object")
    return [_Segment(_si(g.height, unit), _si(g.lower, unit), _si(g.upper, unit))
            for g in _segments(shaft, "shaft.")]


def _neck(geo: Mapping[str, Any], stickout: float, shaft: list[_Segment] | None,
          origin: ShaftOrigin, warnings: list[str]) -> tuple[float, float] | None:
    """Return ``(shoulder_length_m, shoulder_diameter_m)`` or None; see the module docstring."""
    lcf, sfdm, tol = geo["LCF"], geo["SFDM"], _LENGTH_TOL_M
    shoulder, body_d = geo["shoulder-length"], geo["shoulder-diameter"]
    pieces: list[tuple[float, float, float, float]] = []   # (z0, z1, d0, d1) from the tip
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

    def clipped(p: tuple[float, float, float, float], a: float, b: float,
                ) -> tuple[float, float, float, float] | None:
        z0, z1 = max(p[0], a), min(p[1], b)
        if z1 - z0 <= tol:
            return None
        slope = 0.0 if math.isinf(p[1]) else (p[3] - p[2]) / (p[1] - p[0])
        return (z0, z1, p[2] + slope * (z0 - p[0]), p[2] + slope * (z1 - p[0]))

    over = [c for p in pieces if (c := clipped(p, lcf, stickout)) is not None]
    thin = [c for c in over if min(c[2], c[3]) < sfdm - tol]
    if any(max(c[2], c[3]) > sfdm + tol for c in over):
        warnings.append("the tool body between the flutes and the holder is partly thicker than "
                        "the shank; modelled at the shank diameter")
    if not thin:
        return None
    end = max(c[1] for c in thin)
    within = [c for c in over if c[0] < end - tol]
    d_min = min(min(c[2], c[3]) for c in within)
    d_max = max(max(c[2], c[3]) for c in within)
    if d_max - d_min > tol:
        warnings.append(f"neck profile between {_mm(lcf)} and {_mm(end)} from the tip varies from "
                        f"{_mm(d_min)} to {_mm(d_max)}; modelled as one neck at {_mm(d_min)}")
    if body_at_dc:
        warnings.append("shoulder-diameter missing; the body up to shoulder-length taken at DC")
    inside = [c for p in pieces if (c := clipped(p, stickout, stickout + 1.0)) is not None
              and min(c[2], c[3]) < sfdm - tol]
    if inside:
        warnings.append(f"the reduced diameter continues into the holder (to "
                        f"{_mm(max(c[1] for c in inside))} from the tip, stickout "
                        f"{_mm(stickout)}); the clamped part is modelled at SFDM")
    return end, d_min

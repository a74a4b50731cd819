"""Autodesk Fusion (HSM / Inventor CAM) tool libraries → tool–holder combinations.

A Fusion library is ``{"data": [...], "version": n}`` (``.json``), or the same JSON stored as
``tools.json`` in a zip (``.tools``). Each ``data`` item is a cutting tool, possibly with its
holder embedded under ``"holder"``, or a standalone holder (``"type": "holder"``).
:func:`library_combinations` turns every item into one :class:`Combination` whose ``holder``
and ``tool`` are in the contract's assembly format (SI metres, ``docs/contract.md``). This module
reads the library and maps items; the geometry of one item is
:mod:`rcsa.libraries.fusion_geometry`.

Mapping rules (the choices made here)
-------------------------------------
Units
    Per object: the tool's ``unit`` (or ``expressions.tool_unit``) and the holder's own
    ``unit`` independently. Accepted spellings (case-insensitive): millimeters, millimeter,
    millimetres, millimetre, mm; inches, inch, in; meters, meter, metres, metre, m.
    Anything else is an ``error`` entry; a unit is never guessed.
Numbers
    A JSON number, or a string holding one number (``"44"``), in the object's unit; a
    string with a unit (``"44 mm"``) only when that unit is the object's own; anything else
    is an ``error`` entry naming the field (:mod:`rcsa.libraries.quantities`). ``NOF`` and
    ``post-process.number`` may be integer strings.
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
    A cone (lower ≠ upper diameter) becomes equal-length cylinders at the cone's diameter
    at the middle of each piece, as many as :func:`~rcsa.libraries.profiles.cone_steps`
    says for its taper (within 0.5 % of the converged cone) unless
    ``holder_segments_per_cone`` fixes the number. A cylinder stays one.
    The bore (``inner_diameter_m``) is the tool's shank diameter SFDM everywhere.
Tool
    ``diameter_m`` ← DC, ``shank_diameter_m`` ← SFDM, ``overall_length_m`` ← OAL,
    ``flute_length_m`` ← LCF, ``stickout_m`` ← LB (Fusion "length below holder"; when LB is
    absent it is ``assemblyGaugeLength − holder gaugeLength``, with a warning; when both are
    present a mismatch over 0.01 mm is a warning). ``material`` ← ``BMC`` through
    :func:`~rcsa.libraries.tool_materials.tool_material` ("carbide", "hss", "ti coated",
    "ceramics", vendor spellings such as "HSS-Co"), else ``tool_material_default`` with a
    warning. An inserted length OAL − LB below twice SFDM is a warning (shallow clamping).
    LB = OAL is a face-mounted tool (a shell or face mill on an arbor): nothing is inserted,
    the holder is solid, and the tool sits on the holder's face (a warning says so).
Necks
    The overhang profile from the flute end to LB is built from ``shoulder-length`` /
    ``shoulder-diameter`` (the body between the flute end and the shoulder; at DC when no
    shoulder diameter is given) and ``shaft.segments`` (same schema and order as holder
    segments, stacked from the shoulder, or from the flute end with
    ``shaft_origin="flute_end"``), then SFDM. Where it is thinner than SFDM the tool gets
    ``shoulder_length_m``/``shoulder_diameter_m`` (one constant neck) or ``neck_segments``
    (steps and cones, a cone stepped like a holder cone), from the flute end toward the
    holder. A body thicker than the shank is modelled at the shank diameter, with a warning.
"""

from __future__ import annotations

import copy
import hashlib
import io
import json
import os
import zipfile
import zlib
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from functools import partial
from pathlib import Path, PurePosixPath
from typing import Any

from rcsa.errors import InputError
from rcsa.libraries import fusion_geometry as geometry
from rcsa.libraries.combination import Combination, LibraryImport
from rcsa.libraries.fusion_geometry import ShaftOrigin
from rcsa.libraries.profiles import cone_cylinders
from rcsa.libraries.quantities import count_value, unit_to_metres
from rcsa.libraries.tool_materials import tool_material
from rcsa.model import fields
from rcsa.model.assembly import shallow_insertion_note
from rcsa.model.bounds import MAX_HOLDER_SEGMENTS_PER_CONE, MAX_TEETH, MIN_FLUTED_DIAMETER_RATIO
from rcsa.model.input_policy import load_json

__all__ = [
    "MAX_LIBRARY_BYTES",
    "SUPPORTED_TOOL_TYPES",
    "Combination",
    "FusionLibrary",
    "LibraryImport",
    "cone_cylinders",
    "library_combinations",
    "load_fusion_library",
    "tools_json_member",
    "unit_to_metres",
]

MAX_LIBRARY_BYTES = 64 * 1024 * 1024
"""Largest accepted library file or ``tools.json`` inside a ``.tools`` zip, bytes."""

SUPPORTED_TOOL_TYPES = frozenset({
    "flat end mill", "ball end mill", "bull nose end mill", "chamfer mill", "face mill",
    "slot mill", "radius mill", "dovetail mill", "tapered mill", "lollipop mill", "drill",
    "center drill", "spot drill", "counter bore", "counter sink", "reamer", "boring bar",
    "bore mill", "tap right hand", "tap left hand", "form mill",
})
"""Fusion ``type`` values imported; a ``form mill`` also needs a ``profile``."""


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
        raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError("", "not UTF-8 text: expected a Fusion tool-library JSON or a .tools zip"
                         ) from exc
    return load_json(raw, what="the tool library")


def tools_json_member(zf: zipfile.ZipFile) -> zipfile.ZipInfo:
    """The member of a ``.tools`` zip that holds the library: ``tools.json``.

    The one at the root when there is one, else the only ``tools.json`` in a folder.

    Raises
    ------
    InputError
        None or several, or larger than :data:`MAX_LIBRARY_BYTES`.
    """
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
    return infos[0]


def _tools_json_from_zip(raw: bytes) -> bytes:
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as zf:
            with zf.open(tools_json_member(zf)) as fh:
                data = fh.read(MAX_LIBRARY_BYTES + 1)
    except (zipfile.BadZipFile, RuntimeError, NotImplementedError, OSError, EOFError, zlib.error) as exc:
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


# --------------------------------------------------------------------------- mapping


def library_combinations(
    library: FusionLibrary | str | os.PathLike[str] | bytes | Mapping[str, Any],
    *,
    holder_material: str = "steel",
    tool_material_default: str = "carbide",
    holder_segments_per_cone: int | None = None,
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
        Tool material when ``BMC`` is absent or names no known material.
    holder_segments_per_cone : int, optional
        Cylinders per conical holder segment (≥ 1); default: from each cone's taper
        (:func:`~rcsa.libraries.profiles.cone_steps`).
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
    per_cone: int | None
    ratio: float
    shaft_origin: ShaftOrigin
    default_holder: Mapping[str, Any] | None


def _name_option(value: object, field: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise InputError(field, "must be a non-empty material name")
    return value


def _per_cone_option(value: object) -> int | None:
    if value is None:
        return None
    return fields.integer(value, "holder_segments_per_cone", ge=1, le=MAX_HOLDER_SEGMENTS_PER_CONE)


def _ratio_option(value: object) -> float:
    return fields.number(value, "fluted_diameter_ratio", gt=0.0, ge=MIN_FLUTED_DIAMETER_RATIO, le=1.0)


def _shaft_origin_option(value: object) -> ShaftOrigin:
    if value not in ("shoulder", "flute_end"):
        raise InputError("shaft_origin", f"must be 'shoulder' or 'flute_end', got {value!r}")
    return value


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
    return count_value(n)


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
    teeth = count_value(nof)
    if teeth is not None and not 1 <= teeth <= MAX_TEETH:
        teeth = None
    if nof is not None and teeth is None:
        warnings.append(f"geometry.NOF {nof!r} is not an integer from 1 to {MAX_TEETH}; teeth unknown")
    entry = partial(Combination, ident, index, description=desc if isinstance(desc, str) else "",
                    number=_t_number(item), teeth=teeth, tool_type=tool_type)
    try:
        holder, tool = _map_item(item, opts, warnings)
    except _Skip as skip:
        return entry("skipped", reason=str(skip), warnings=tuple(warnings))
    except InputError as err:
        return entry("error", reason=str(err), warnings=tuple(warnings))
    return entry("ok", holder=holder, tool=tool, warnings=tuple(warnings))


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
    geo = geometry.tool_geometry(item)
    holder_si = geometry.holder_geometry(holder_obj, warnings)
    stickout = geometry.stickout(geo, holder_si.gauge_length_m if own_holder else None, warnings)
    geometry.check_tool_lengths(geo, stickout)
    on_face = geometry.face_mounted(geo, stickout)
    if on_face:
        stickout = geo["OAL"]
        warnings.append("face-mounted (LB = OAL): the tool sits on the holder's face, no shank in a bore; the "
                        "holder is modelled solid and the holder-tool joint is the face contact "
                        "(joints.holder_tool: the point joint, or a face contact for model bonded/contact)")
    tool = {
        "material": _tool_material(item.get("BMC"), opts.tool_material_default, warnings),
        "diameter_m": geo["DC"], "shank_diameter_m": geo["SFDM"],
        "overall_length_m": geo["OAL"], "flute_length_m": geo["LCF"], "stickout_m": stickout,
        "fluted_diameter_ratio": opts.ratio,
    }
    tool.update(geometry.neck_fields(geo, stickout, geometry.shaft_pieces(item, geo["unit"]), opts.shaft_origin,
                                     warnings))
    holder = {"segments": geometry.holder_segments(holder_si, 0.0 if on_face else geo["SFDM"], opts.per_cone,
                                                   opts.holder_material)}
    inserted = geo["OAL"] - stickout
    if inserted > holder_si.length_m + geometry.LENGTH_TOL_M:
        warnings.append(f"inserted length {geometry.mm(inserted)} exceeds the holder length "
                        f"{geometry.mm(holder_si.length_m)} below the gauge line; the excess is ignored")
    if not on_face and (note := shallow_insertion_note(inserted, geo["SFDM"])) is not None:
        warnings.append(note)
    return holder, tool




def _tool_material(bmc: object, default: str, warnings: list[str]) -> str:
    name, note = tool_material(bmc)
    if name is not None:
        if note is not None:
            warnings.append(f"BMC {bmc!r} {note}")
        return name
    what = "missing" if bmc is None else f"{bmc!r} names no known tool material"
    warnings.append(f"BMC {what}; material {default!r} assumed")
    return default

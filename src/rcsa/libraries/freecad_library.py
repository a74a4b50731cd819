"""FreeCAD tool libraries: toolbits (``.fctb``) in one holder (``.fcholder``), as one library.

FreeCAD keeps one JSON file per toolbit in ``Tools/Bit``, libraries ``.fctl`` in
``Tools/Library`` (``{"version": 1, "tools": [{"nr": 1, "path": "5mm_Endmill.fctb"}]}``: tool
numbers → toolbit files, looked up by file stem in ``../Bit`` the way FreeCAD's
``FCTLSerializer`` does) and holders ``.fcholder`` in ``Tools/Holder``. What is accepted:

* a ``.fctb`` file (one toolbit), a ``.fctl`` file (its toolbits next to it or in ``../Bit``),
  or a folder (every ``.fctb`` in it, ordered by the one ``.fctl`` there if any, else by name);
* a zip of such files (members by base name; ``.fctb``, at most one ``.fcholder``, at most one
  ``.fctl``), the form to upload a FreeCAD library;
* a JSON document ``{"format": "freecad", "toolbits": {"<id>": {fctb}, ...},
  "holder": {"<id>": {fcholder}}, "library": {fctl}}`` (``holder``, ``library`` optional), the
  REST JSON form; or a single toolbit object.

The holder is the one ``.fcholder`` of the folder or zip, or given separately (``holder``);
toolbits with none are ``skipped`` ("no holder"). FreeCAD stores no stickout: the import
option ``stickout_m`` gives it, one length for all tools or ``{"<toolbit id>": m}``.
Ids are ``"<toolbit id>@<holder id>"``, each the file stem (the key in the JSON document),
so an unchanged toolbit keeps its id from one sync to the next; ``number`` is the
``.fctl`` ``nr``.
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
from pathlib import Path, PurePosixPath
from typing import Any

from rcsa.errors import InputError
from rcsa.libraries.combination import Combination, LibraryImport
from rcsa.libraries.freecad import MAX_FILE_BYTES, load_freecad_object, map_toolbit
from rcsa.libraries.quantities import count_value
from rcsa.model import fields
from rcsa.model.bounds import MAX_BATCH_COMBINATIONS
from rcsa.model.input_policy import check_zip_members

__all__ = ["FREECAD_SUFFIXES", "FreeCADLibrary", "freecad_library_combinations", "load_freecad_library"]

#: File suffixes of FreeCAD's tool files.
FREECAD_SUFFIXES = (".fctb", ".fctl", ".fcholder")
_MAX_ZIP_BYTES = 64 * 1024 * 1024
_MAX_TOOLBITS = MAX_BATCH_COMBINATIONS


@dataclass(frozen=True, slots=True)
class Toolbit:
    """One library entry: its id, the toolbit object (None when it could not be read), number."""

    id: str
    obj: dict[str, Any] | None
    number: int | None = None
    problem: str | None = None


@dataclass(frozen=True, slots=True)
class FreeCADLibrary:
    """FreeCAD toolbits and the holder they sit in, read and identified.

    Attributes
    ----------
    toolbits : tuple of Toolbit
        In library order.
    holder : (str, dict) or None
        The holder's id and object.
    sha256 : str
        SHA-256 of the canonical JSON of everything above (ids included).
    source : str
    """

    toolbits: tuple[Toolbit, ...]
    holder: tuple[str, dict[str, Any]] | None
    sha256: str
    source: str


def load_freecad_library(source: str | os.PathLike[str] | bytes | Mapping[str, Any] | FreeCADLibrary, *,
                         holder: str | os.PathLike[str] | bytes | Mapping[str, Any] | None = None,
                         file_name: str | None = None, holder_name: str | None = None) -> FreeCADLibrary:
    """Read a FreeCAD library in any of the forms of the module docstring.

    Parameters
    ----------
    source : path, bytes, mapping or FreeCADLibrary
        A ``str`` is a path. Bytes are a zip, a ``.fctb`` or the JSON document.
    holder : path, bytes or mapping, optional
        The ``.fcholder`` (when ``source`` has none).
    file_name, holder_name : str, optional
        The uploaded files' names: a single toolbit's and the holder's ids are their stems.

    Raises
    ------
    InputError
        Unreadable, not a FreeCAD library, a ``.fctl`` without its toolbits' folder, two
        holders, or too many toolbits.
    """
    if isinstance(source, FreeCADLibrary):
        if holder is not None:
            raise InputError("holder", "the library is already read with its holder")
        return source
    if isinstance(source, Mapping):
        bits, own_holder, name = _from_document(source, file_name), None, "<mapping>"
        if source.get("format") == "freecad":
            own_holder = _document_holder(source.get("holder"))
    elif isinstance(source, (bytes, bytearray, memoryview)):
        raw, name = bytes(source), file_name or "<bytes>"
        if raw.startswith(b"PK"):
            bits, own_holder = _from_zip(raw)
        else:
            obj, _ = load_freecad_object(raw)
            if obj.get("format") == "freecad":
                bits, own_holder = _from_document(obj, file_name), _document_holder(obj.get("holder"))
            else:
                bits, own_holder = _from_document(obj, file_name), None
    elif isinstance(source, (str, os.PathLike)):
        bits, own_holder = _from_path(Path(source))
        name = str(source)
    else:
        raise InputError("source", f"expected a path, bytes or a mapping, got {type(source).__name__}")
    if own_holder is not None and holder is not None:
        raise InputError("holder", f"the library already has its holder {own_holder[0]!r}; give only one")
    if holder is not None:
        obj, ident = load_freecad_object(holder)
        named = holder_name or (os.fspath(holder) if isinstance(holder, (str, os.PathLike)) else None)
        own_holder = (Path(named).stem if named else ident, obj)
    if len(bits) > _MAX_TOOLBITS:
        raise InputError("library", f"has {len(bits)} toolbits; at most {_MAX_TOOLBITS}")
    canonical = json.dumps({"toolbits": [[b.id, b.obj, b.number, b.problem] for b in bits],
                            "holder": own_holder}, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    return FreeCADLibrary(tuple(bits), own_holder, hashlib.sha256(canonical.encode()).hexdigest(), name)


def _document_holder(raw: object) -> tuple[str, dict[str, Any]] | None:
    if raw is None:
        return None
    if not isinstance(raw, Mapping) or len(raw) != 1 or not isinstance(next(iter(raw.values())), Mapping):
        raise InputError("library.holder", 'must be {"<holder id>": {the .fcholder object}}')
    ident, obj = next(iter(raw.items()))
    return str(ident), copy.deepcopy(dict(obj))


def _from_document(doc: Mapping[str, Any], file_name: str | None) -> list[Toolbit]:
    if doc.get("format") != "freecad":
        if "parameter" not in doc and "shape" not in doc:
            raise InputError("library", "is neither a FreeCAD toolbit nor a FreeCAD library document "
                                        '{"format": "freecad", "toolbits": {...}}')
        obj, ident = load_freecad_object(doc)
        return [Toolbit(Path(file_name).stem if file_name else ident, obj)]
    raw = doc.get("toolbits")
    if not isinstance(raw, Mapping) or not raw:
        raise InputError("library.toolbits", 'must be {"<toolbit id>": {the .fctb object}, ...}')
    bits = {str(k): Toolbit(str(k), copy.deepcopy(dict(v)) if isinstance(v, Mapping) else None,
                            problem=None if isinstance(v, Mapping) else "not a JSON object")
            for k, v in raw.items()}
    return _ordered(bits, doc.get("library"), "library.library")


def _ordered(bits: dict[str, Toolbit], fctl: object, field: str) -> list[Toolbit]:
    """Toolbits in ``.fctl`` order with its numbers (missing files as problems), else by id."""
    if fctl is None:
        return [bits[k] for k in sorted(bits)]
    if not isinstance(fctl, Mapping) or not isinstance(fctl.get("tools"), list):
        raise InputError(field, 'a .fctl is {"tools": [{"nr": n, "path": "x.fctb"}, ...]}')
    out = []
    for k, entry in enumerate(fctl["tools"]):
        path = entry.get("path") if isinstance(entry, Mapping) else None
        if not isinstance(path, str) or not path.strip():
            raise InputError(f"{field}.tools[{k}].path", "missing: the toolbit file of this tool number")
        stem = PurePosixPath(path.replace("\\", "/")).stem
        number = count_value(entry.get("nr"))
        bit = bits.get(stem)
        out.append(Toolbit(stem, bit.obj, number, bit.problem) if bit is not None
                   else Toolbit(stem, None, number, f"toolbit file {path!r} not found"))
    return out


def _from_zip(raw: bytes) -> tuple[list[Toolbit], tuple[str, dict[str, Any]] | None]:
    check_zip_members(raw, "library")
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as zf:
            members = [i for i in zf.infolist() if not i.is_dir()]
            if sum(i.file_size for i in members) > _MAX_ZIP_BYTES:
                raise InputError("library", f"the zip unpacks to more than {_MAX_ZIP_BYTES} bytes")
            files: dict[str, list[tuple[str, bytes]]] = {s: [] for s in FREECAD_SUFFIXES}
            for info in members:
                name = PurePosixPath(info.filename)
                if name.suffix.lower() in files:
                    if info.file_size > MAX_FILE_BYTES:
                        raise InputError("library", f"{info.filename}: larger than {MAX_FILE_BYTES} bytes")
                    files[name.suffix.lower()].append((name.stem, zf.read(info)))
    except (zipfile.BadZipFile, RuntimeError, NotImplementedError, OSError, EOFError, zlib.error) as exc:
        raise InputError("library", f"not a readable zip archive ({exc})") from exc
    if not files[".fctb"]:
        raise InputError("library", "the zip holds no FreeCAD toolbit (.fctb) and no Fusion tools.json")
    return _assemble(files[".fctb"], files[".fcholder"], files[".fctl"], "the zip")


def _from_path(path: Path) -> tuple[list[Toolbit], tuple[str, dict[str, Any]] | None]:
    if path.is_dir():
        found = {s: sorted(p for p in path.iterdir() if p.suffix.lower() == s and p.is_file())
                 for s in FREECAD_SUFFIXES}
        return _assemble([(p.stem, _read(p)) for p in found[".fctb"]], [(p.stem, _read(p)) for p in found[".fcholder"]],
                         [(p.stem, _read(p)) for p in found[".fctl"]], str(path))
    suffix = path.suffix.lower()
    if suffix == ".fctb":
        return [Toolbit(path.stem, load_freecad_object(path)[0])], None
    if suffix == ".fctl":
        fctl, _ = load_freecad_object(path)
        folders = (path.parent, path.parent.parent / "Bit")
        bits = {}
        for entry in fctl.get("tools") or ():
            raw = entry.get("path") if isinstance(entry, Mapping) else None
            if not isinstance(raw, str):
                continue
            stem = PurePosixPath(raw.replace("\\", "/")).stem
            candidates = [f / f"{stem}.fctb" for f in folders]
            hit = next((c for c in candidates if c.is_file()), None)
            if hit is not None:
                bits[stem] = Toolbit(stem, load_freecad_object(hit)[0])
        return _ordered(bits, fctl, "library"), None
    if suffix == ".fcholder":
        raise InputError("library", f"{path}: a holder alone is not a library; give the toolbits, with this "
                                    "file as the holder")
    raise InputError("library", f"{path}: not a FreeCAD file (.fctb, .fctl, a folder or a zip of them)")


def _read(path: Path) -> bytes:
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise InputError("library", f"{path}: larger than {MAX_FILE_BYTES} bytes")
        return path.read_bytes()
    except OSError as exc:
        raise InputError("library", f"{path}: cannot be read ({exc.strerror or exc})") from exc


def _assemble(fctb: list[tuple[str, bytes]], fcholder: list[tuple[str, bytes]], fctl: list[tuple[str, bytes]],
              where: str) -> tuple[list[Toolbit], tuple[str, dict[str, Any]] | None]:
    if len(fcholder) > 1:
        raise InputError("holder", f"{where} has {len(fcholder)} holders ({', '.join(s for s, _ in fcholder)}); "
                                   "keep one, or give the holder separately")
    if len(fctl) > 1:
        raise InputError("library", f"{where} has {len(fctl)} .fctl libraries; keep one")
    bits = {}
    for stem, data in fctb:
        try:
            bits[stem] = Toolbit(stem, load_freecad_object(data)[0])
        except InputError as err:
            bits[stem] = Toolbit(stem, None, problem=err.rule)
    holder = None
    if fcholder:
        holder = (fcholder[0][0], load_freecad_object(fcholder[0][1])[0])
    return _ordered(bits, load_freecad_object(fctl[0][1])[0] if fctl else None, "library"), holder


def freecad_library_combinations(library: FreeCADLibrary | str | os.PathLike[str] | bytes | Mapping[str, Any], *,
                                 stickout_m: float | Mapping[str, float] | None = None,
                                 holder_material: str = "steel", tool_material_default: str = "carbide",
                                 holder_segments_per_cone: int | None = None,
                                 fluted_diameter_ratio: float = 0.8) -> LibraryImport:
    """Every toolbit of a FreeCAD library in its holder: one :class:`Combination` each.

    Parameters
    ----------
    library : FreeCADLibrary, path, bytes or mapping
        Anything :func:`load_freecad_library` reads.
    stickout_m : float or mapping
        Required: one stickout for every toolbit, or ``{"<toolbit id>": m}`` (a toolbit
        missing from it is an ``error`` entry).
    holder_material, tool_material_default, holder_segments_per_cone, fluted_diameter_ratio
        As in :func:`rcsa.libraries.freecad.freecad_combination`.

    Raises
    ------
    InputError
        The library cannot be read, or ``stickout_m`` is missing or invalid.
    """
    lib = load_freecad_library(library)
    if stickout_m is None:
        raise InputError("stickout_m", "required for FreeCAD toolbits (they store no stickout): a length in m for "
                                       'every tool, or {"<toolbit id>": m}')
    if isinstance(stickout_m, Mapping):
        stickouts = {str(k): fields.number(v, f"stickout_m.{k}", gt=0.0) for k, v in stickout_m.items()}
    else:
        common = fields.number(stickout_m, "stickout_m", gt=0.0)
        stickouts = {b.id: common for b in lib.toolbits}
    holder_id, holder_obj = lib.holder if lib.holder is not None else (None, None)
    combos = []
    for index, bit in enumerate(lib.toolbits):
        ident = bit.id if holder_id is None else f"{bit.id}@{holder_id}"
        if bit.obj is None:
            combos.append(Combination(ident, index, "error", number=bit.number, reason=f"toolbit: {bit.problem}"))
        elif bit.id not in stickouts:
            combos.append(Combination(ident, index, "error", number=bit.number,
                                      reason=f"stickout_m.{bit.id}: missing (no stickout for this toolbit)"))
        else:
            combos.append(map_toolbit(bit.obj, bit.id, holder_obj, holder_id, stickout_m=stickouts[bit.id],
                                      holder_material=holder_material, tool_material_default=tool_material_default,
                                      holder_segments_per_cone=holder_segments_per_cone,
                                      fluted_diameter_ratio=fluted_diameter_ratio, index=index, number=bit.number))
    counts = Counter(c.status for c in combos)
    return LibraryImport(tuple(combos), {s: counts.get(s, 0) for s in ("ok", "skipped", "error")}, lib.source,
                         lib.sha256)

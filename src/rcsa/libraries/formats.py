"""Which CAM library a file is, and its import: Fusion or FreeCAD, by suffix, content type and content.

:func:`read_library` decides from what is known about the input — a path's suffix or a
folder, an upload's file name and ``Content-Type`` — and checks the content agrees:

* Fusion: ``.json`` / ``.tools``, a JSON object with ``data``, a zip holding ``tools.json``;
* FreeCAD (:mod:`rcsa.libraries.freecad_library`): ``.fctb`` / ``.fctl``, a folder, a zip of
  ``.fctb`` files, a JSON object with ``"format": "freecad"`` or a toolbit's ``parameter``;
  media types ``application/x-freecad-toolbit`` (…``-library``) as FreeCAD writes them.

A name or media type saying one format while the content is the other is refused (a
renamed file is a mistake worth hearing about). :func:`import_library` then maps it, with
the options that apply to its format (a Fusion-only option given for FreeCAD, or
``stickout_m`` for Fusion, is refused naming the option).
"""

from __future__ import annotations

import io
import os
import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path, PurePosixPath
from typing import Any, Literal

from rcsa.errors import InputError
from rcsa.libraries.combination import LibraryImport
from rcsa.libraries.freecad_library import (
    FREECAD_SUFFIXES,
    FreeCADLibrary,
    freecad_library_combinations,
    load_freecad_library,
)
from rcsa.libraries.fusion import FusionLibrary, library_combinations, load_fusion_library
from rcsa.model.input_policy import load_json

__all__ = ["FREECAD_OPTIONS", "FUSION_OPTIONS", "Library", "LibraryFormat", "LibrarySource", "detect_format",
           "import_library", "read_library"]

LibraryFormat = Literal["fusion", "freecad"]
#: A library read by :func:`read_library`.
Library = FusionLibrary | FreeCADLibrary
#: What :func:`read_library` and :func:`import_library` take.
LibrarySource = Library | str | os.PathLike[str] | bytes | Mapping[str, Any]

#: Import options of each format.
FUSION_OPTIONS = ("holder_material", "tool_material_default", "holder_segments_per_cone", "fluted_diameter_ratio",
                  "shaft_origin", "default_holder")
FREECAD_OPTIONS = ("holder_material", "tool_material_default", "holder_segments_per_cone", "fluted_diameter_ratio",
                   "stickout_m")

_FUSION_SUFFIXES = (".tools",)  # .json may be either: the content decides
_FREECAD_MEDIA = ("application/x-freecad-toolbit", "application/x-freecad-toolbit-library",
                  "application/x-freecad-toolholder")


def _content_format(source: bytes | Mapping[str, Any]) -> LibraryFormat | None:
    """The format the content itself shows, None when it shows neither."""
    if isinstance(source, Mapping):
        if source.get("format") == "freecad" or "parameter" in source or "shape" in source:
            return "freecad"
        return "fusion" if "data" in source else None
    if source.startswith(b"PK"):
        try:
            with zipfile.ZipFile(io.BytesIO(source)) as zf:
                names = [PurePosixPath(n).name.lower() for n in zf.namelist()]
        except (zipfile.BadZipFile, RuntimeError, NotImplementedError, OSError, EOFError, zlib.error):
            return None
        if "tools.json" in names:
            return "fusion"
        return "freecad" if any(n.endswith(FREECAD_SUFFIXES) for n in names) else None
    try:
        doc = load_json(source)
    except InputError:  # the reader says why
        return None
    return _content_format(doc) if isinstance(doc, dict) else None


def detect_format(source: bytes | Mapping[str, Any], *, file_name: str | None = None,
                  content_type: str | None = None) -> LibraryFormat:
    """Fusion or FreeCAD, from the name and media type given and the content (module docstring).

    Raises
    ------
    InputError
        Field ``library``: the name or media type contradicts the content.
    """
    suffix = PurePosixPath(file_name).suffix.lower() if file_name else ""
    media = (content_type or "").split(";")[0].strip().lower()
    claimed: LibraryFormat | None = None
    if suffix in FREECAD_SUFFIXES or media in _FREECAD_MEDIA:
        claimed = "freecad"
    elif suffix in _FUSION_SUFFIXES:
        claimed = "fusion"
    found = _content_format(source)
    if claimed is not None and found is not None and claimed != found:
        what = f"{file_name!r}" if file_name else f"Content-Type {media}"
        raise InputError("library", f"{what} says a {_NAMES[claimed]} file, but the content is a "
                                    f"{_NAMES[found]} library")
    return found or claimed or "fusion"  # unreadable content: the Fusion reader says why


_NAMES = {"fusion": "Fusion", "freecad": "FreeCAD"}


def read_library(source: LibrarySource, *, file_name: str | None = None, content_type: str | None = None,
                 holder: str | os.PathLike[str] | bytes | Mapping[str, Any] | None = None,
                 holder_name: str | None = None) -> Library:
    """Read a Fusion or FreeCAD library from a path, an upload's bytes or a JSON document.

    Parameters
    ----------
    source : path, bytes, mapping, or a library already read
        A ``str`` is a path (a folder is a FreeCAD library).
    file_name, content_type : str, optional
        What the upload says it is.
    holder : path, bytes or mapping, optional
        A FreeCAD holder (``.fcholder``) for the toolbits; refused for Fusion.
    holder_name : str, optional
        The holder upload's file name (its stem is the holder's id).

    Raises
    ------
    InputError
        Unreadable, the format contradicted, or a holder given for a Fusion library.
    """
    if isinstance(source, (FusionLibrary, FreeCADLibrary)):
        fmt: LibraryFormat = "freecad" if isinstance(source, FreeCADLibrary) else "fusion"
    elif isinstance(source, (str, os.PathLike)):
        path = Path(source)
        if path.is_dir() or path.suffix.lower() in FREECAD_SUFFIXES:
            fmt = "freecad"
        elif path.is_file() and path.stat().st_size <= 64 * 1024 * 1024:
            fmt = detect_format(path.read_bytes(), file_name=path.name, content_type=content_type)
        else:
            fmt = "fusion"  # missing or too large: the reader says so
    else:
        data = bytes(source) if isinstance(source, (bytearray, memoryview)) else source
        fmt = detect_format(data, file_name=file_name, content_type=content_type)
    if fmt == "freecad":
        return load_freecad_library(source, holder=holder, file_name=file_name,  # type: ignore[arg-type]
                                    holder_name=holder_name)
    if holder is not None:
        raise InputError("holder", "a Fusion library carries its holders; a separate holder file is for FreeCAD "
                                   "toolbits")
    return load_fusion_library(source)  # type: ignore[arg-type]


def import_library(library: LibrarySource, **options: Any) -> LibraryImport:
    """Every item of a library mapped to a combination (:func:`read_library` first when needed).

    ``options`` are those of the library's format (:data:`FUSION_OPTIONS`,
    :data:`FREECAD_OPTIONS`); ``None`` values are left out.

    Raises
    ------
    InputError
        The library cannot be read, or an option is unknown, for the other format, or invalid.
    """
    lib = read_library(library)
    given = {k: v for k, v in options.items() if v is not None}
    allowed = FREECAD_OPTIONS if isinstance(lib, FreeCADLibrary) else FUSION_OPTIONS
    wrong = sorted(set(given) - set(allowed))
    if wrong:
        if wrong[0] not in (*FUSION_OPTIONS, *FREECAD_OPTIONS):
            raise InputError(wrong[0], f"unknown option (options here: {', '.join(allowed)})")
        other = "a Fusion" if isinstance(lib, FreeCADLibrary) else "a FreeCAD"
        raise InputError(wrong[0], f"applies to {other} library, not to this one (options here: {', '.join(allowed)})")
    if isinstance(lib, FreeCADLibrary):
        return freecad_library_combinations(lib, **given)
    return library_combinations(lib, **given)

"""Chatter-safe presets as the CLI and the REST service ask for them (``contract.md`` v1.1).

``rcsa library recommend LIBRARY ...`` and ``POST /v1/libraries/{id}:recommend`` read a Fusion
library (``.json`` or ``.tools``), find each milling tool's best stable pocket from its
tool-point FRF — stored by a sync (:func:`recommend_stored`) or predicted now
(:func:`recommend_predicted`) — and give back the library with rcsa's presets written in
(nothing else changed) and a report (:mod:`rcsa.libraries.recommend`). FreeCAD libraries are
refused: their toolbits have no presets of this form.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path, PurePath
from typing import Any

from rcsa.app.jobs import Workbench
from rcsa.errors import InputError
from rcsa.infra.atomic_files import atomic_write_bytes
from rcsa.libraries.formats import read_library
from rcsa.libraries.fusion import FusionLibrary
from rcsa.libraries.fusion_presets import FusionFile, read_fusion_file
from rcsa.libraries.recommend import (
    OPTION_FIELDS,
    PRESET_PREFIX,
    RecommendOptions,
    parse_recommend_options,
    recommend_presets,
)
from rcsa.libraries.recommend_sources import FrfSource, predicted_frfs, stored_frfs

__all__ = ["OPTION_FIELDS", "PRESET_PREFIX", "PresetFile", "check_recommendation", "recommend_predicted", "recommend_stored", "write_preset_file"]

_FREECAD_REFUSAL = ("chatter-safe presets are written into Autodesk Fusion libraries (.json or .tools) only: "
                    "FreeCAD toolbits (.fctb) and libraries have no start-values presets to write them into")


@dataclass(frozen=True)
class PresetFile:
    """The library with rcsa's presets, and what was done.

    Attributes
    ----------
    data : bytes
        The new library file (same format as the one given).
    file_name : str
        The name it was given under (``library.json`` / ``library.tools`` when none).
    media_type : str
        ``application/json`` or ``application/zip`` (``.tools``).
    report : dict
        :func:`rcsa.libraries.recommend.recommend_presets`'s report, plus ``library``
        (file name, format, SHA-256 before and after) and ``frf_source``.
    """

    data: bytes
    file_name: str
    media_type: str
    report: dict[str, Any]


def _read(data: bytes, file_name: str | None, content_type: str | None) -> tuple[FusionFile, FusionLibrary]:
    if not isinstance(data, bytes | bytearray):
        raise InputError("library", "send the library file's bytes")
    data = bytes(data)
    library = read_library(data, file_name=file_name, content_type=content_type)
    if not isinstance(library, FusionLibrary):
        raise InputError("library", _FREECAD_REFUSAL)
    return read_fusion_file(data), library


def check_recommendation(data: bytes, options: Mapping[str, Any], *, file_name: str | None = None) -> None:
    """Check the options and that the file is a Fusion library, before anything is computed.

    Raises
    ------
    InputError
        Bad options, or not a Fusion library (FreeCAD: no presets to write into).
    """
    parse_recommend_options(options)
    _read(data, file_name, None)


def _answer(file: FusionFile, file_name: str | None, source: FrfSource, options: RecommendOptions) -> PresetFile:
    result = recommend_presets(file, source.entries, source.frfs, options)
    name = PurePath(file_name).name if file_name else ("library.tools" if file.kind == "tools" else "library.json")
    report = {"library": {"file_name": name, "format": "fusion-" + file.kind,
                          "sha256_before": hashlib.sha256(file.raw).hexdigest(),
                          "sha256_after": hashlib.sha256(result.data).hexdigest()},
              "frf_source": source.source, **result.report}
    return PresetFile(result.data, name, "application/zip" if file.kind == "tools" else "application/json", report)


def recommend_stored(bench: Workbench, library_id: str, data: bytes, options: Mapping[str, Any], *,
                     file_name: str | None = None, content_type: str | None = None) -> PresetFile:
    """Presets from a stored library's results (``POST /v1/libraries/{id}:recommend``).

    Parameters
    ----------
    bench : Workbench
        With the store holding the library (and its measured spindle, if any).
    library_id : str
        The stored library, synced from this (or an earlier export of this) Fusion library.
    data : bytes
        The Fusion ``.json`` / ``.tools`` file to write the presets into.
    options : mapping
        :data:`rcsa.libraries.recommend.OPTION_FIELDS` (material, machine speed range, ...).
    file_name, content_type : str, optional
        What the upload says it is.

    Raises
    ------
    InputError
        Bad options, not a Fusion library, or stored settings that no longer validate.
    NotFoundError
        No such library.
    """
    opts = parse_recommend_options(options)
    file, library = _read(data, file_name, content_type)
    source = stored_frfs(bench.libraries, library_id, library, store=bench.store, max_lines=bench.max_lines,
                         uncertainty=opts.uncertainty)
    return _answer(file, file_name, source, opts)


def recommend_predicted(bench: Workbench, data: bytes, options: Mapping[str, Any], *, spindle: Mapping[str, Any],
                        frequency: Mapping[str, Any], file_name: str | None = None, content_type: str | None = None,
                        progress: Callable[[int, int], None] | None = None,
                        import_options: Mapping[str, Any] | None = None, **fields: Any) -> PresetFile:
    """Presets from tool-point FRFs predicted now on a spindle (``rcsa library recommend --spindle``).

    Parameters
    ----------
    bench : Workbench
        Measurement source and limits.
    data : bytes
        The Fusion ``.json`` / ``.tools`` file.
    options : mapping
        :data:`rcsa.libraries.recommend.OPTION_FIELDS`.
    spindle, frequency : mapping
        As for a library prediction.
    file_name, content_type : str, optional
        What the file says it is.
    progress : callable, optional
        ``progress(done, total)`` over the tools predicted.
    import_options : mapping, optional
        The library import's options (holder material, cones, ...: ``options`` of
        :func:`rcsa.libraries.library_prediction.library_request`).
    **fields
        ``joints``, ``materials``, ``beam_theory``, ``shear_coefficient`` as in
        :func:`rcsa.libraries.library_prediction.library_request`.
    """
    opts = parse_recommend_options(options)
    file, library = _read(data, file_name, content_type)
    source = predicted_frfs(library, spindle=spindle, frequency=frequency, store=bench.store,
                            max_lines=bench.max_lines, max_combinations=bench.max_combinations, progress=progress,
                            uncertainty=opts.uncertainty,
                            options=import_options, **{k: v for k, v in fields.items() if v is not None})
    return _answer(file, file_name, source, opts)


def write_preset_file(preset_file: PresetFile, path: str | os.PathLike[str]) -> None:
    """Write the library with its presets to ``path`` atomically (a reader never sees half a file).

    Raises
    ------
    OSError
        The file cannot be written.
    """
    atomic_write_bytes(Path(path), preset_file.data)

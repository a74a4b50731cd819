"""Chatter-safe presets as the CLI and the REST service ask for them (``docs/contract.md`` "Additions in v1.1").

``rcsa library recommend LIBRARY ...`` and ``POST /v1/libraries/{id}:recommend`` read a Fusion
library (``.json`` or ``.tools``), find each milling tool's best stable pocket from its
tool-point FRF — stored by a sync (:func:`recommend_stored`) or predicted now
(:func:`recommend_predicted`) — and give back the library with rcsa's presets written in
(nothing else changed) and a report (:mod:`rcsa.libraries.recommend`). FreeCAD libraries are
refused: their toolbits have no presets of this form.
"""

from __future__ import annotations

import base64
import hashlib
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path, PurePath
from typing import Any

from rcsa.app.jobs import Workbench
from rcsa.errors import InputError
from rcsa.infra.atomic_files import atomic_write_bytes
from rcsa.infra.compute_backends import Backend
from rcsa.infra.job_queue import Handler
from rcsa.libraries.formats import read_library
from rcsa.libraries.fusion import FusionLibrary
from rcsa.libraries.fusion_presets import FusionFile, read_fusion_file
from rcsa.libraries.recommend import (
    OPTION_FIELDS,
    PRESET_PREFIX,
    RecommendOptions,
    parse_recommend_options,
    pockets_on,
    recommend_presets,
)
from rcsa.libraries.recommend_sources import FrfSource, predicted_frfs, stored_frfs

__all__ = ["OPTION_FIELDS", "PRESET_PREFIX", "RECOMMEND_JOB", "PresetFile", "check_recommendation",
           "recommend_job_handlers", "recommend_job_request", "recommend_predicted", "recommend_stored",
           "report_document", "write_preset_file"]

#: Kind of the job that writes presets into a large library (``Prefer: respond-async``).
RECOMMEND_JOB = "library-recommend"

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


def _answer(file: FusionFile, file_name: str | None, source: FrfSource, options: RecommendOptions, *,
            progress: Callable[[int, int], None] | None = None, backend: Backend | None = None) -> PresetFile:
    entries: list[Mapping[str, Any]] = list(source.entries)
    result = recommend_presets(file, entries, source.frfs, options, progress, pockets_on(backend))
    name = PurePath(file_name).name if file_name else ("library.tools" if file.kind == "tools" else "library.json")
    report = {"library": {"file_name": name, "format": "fusion-" + file.kind,
                          "sha256_before": hashlib.sha256(file.raw).hexdigest(),
                          "sha256_after": hashlib.sha256(result.data).hexdigest()},
              "frf_source": source.source, **result.report}
    return PresetFile(result.data, name, "application/zip" if file.kind == "tools" else "application/json", report)


def recommend_stored(bench: Workbench, library_id: str, data: bytes, options: Mapping[str, Any], *,
                     file_name: str | None = None, content_type: str | None = None,
                     progress: Callable[[int, int], None] | None = None, backend: Backend | None = None) -> PresetFile:
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
    progress : callable, optional
        ``progress(done, total)`` over the tools whose pockets are computed.
    backend : Backend, optional
        Where the pockets' chunks run (default: this process; a job passes the workbench's).

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
    return _answer(file, file_name, source, opts, progress=progress, backend=backend)


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
        ``progress(done, total)`` over the tools predicted, then over the tools whose pockets are
        computed (on the workbench's backend).
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
    return _answer(file, file_name, source, opts, progress=progress, backend=bench.backend)


def write_preset_file(preset_file: PresetFile, path: str | os.PathLike[str]) -> None:
    """Write the library with its presets to ``path`` atomically (a reader never sees half a file).

    Raises
    ------
    OSError
        The file cannot be written.
    """
    atomic_write_bytes(Path(path), preset_file.data)


def report_document(library_id: str, result: PresetFile) -> dict[str, Any]:
    """The JSON answer of ``POST /v1/libraries/{id}:recommend`` (and of its job): the report and
    the file (base64)."""
    return {"library_id": library_id, **result.report, "file": {
        "file_name": result.file_name, "media_type": result.media_type, "size_bytes": len(result.data),
        "sha256": hashlib.sha256(result.data).hexdigest(),
        "content_base64": base64.b64encode(result.data).decode("ascii")}}


def recommend_job_request(library_id: str, data: bytes, options: Mapping[str, Any], *, file_name: str | None = None,
                          content_type: str | None = None) -> dict[str, Any]:
    """The JSON-ready request of a :data:`RECOMMEND_JOB` (the file travels as base64), checked first;
    ``items`` counts the library's items (whether it is large enough to be a job).

    Raises
    ------
    InputError
        Bad options or not a Fusion library (:func:`check_recommendation`).
    """
    parse_recommend_options(options)
    _, library = _read(data, file_name, content_type)
    return {"library_id": library_id, "options": dict(options), "file_name": file_name, "content_type": content_type,
            "library_base64": base64.b64encode(data).decode("ascii"), "items": len(library.items)}


def recommend_job_handlers(bench: Workbench) -> dict[str, Handler]:
    """The job runner's handler of :data:`RECOMMEND_JOB`: :func:`recommend_stored` on the
    workbench's backend (this process, or a Dask cluster), progress over the tools; its result
    is :func:`report_document`."""
    def run(request: dict[str, Any], progress: Callable[[int, int], None]) -> tuple[Any, dict[str, Any]]:
        result = recommend_stored(bench, str(request["library_id"]), base64.b64decode(request["library_base64"]),
                                  request["options"], file_name=request.get("file_name"),
                                  content_type=request.get("content_type"), progress=progress,
                                  backend=bench.backend)
        return report_document(str(request["library_id"]), result), dict(result.report["summary"])

    return {RECOMMEND_JOB: run}

"""Batches and whole tool libraries as the CLI and the REST service use them.

A batch, a library prediction and a library sync are *prepared* here — read, sized and
given the checks to make before queuing — into a :class:`rcsa.app.jobs.Work` that
:func:`rcsa.app.jobs.answer_or_queue` runs now or queues (or the CLI runs with
:func:`rcsa.app.jobs.run_work`).
Stored libraries are listed, shown and exported (HDF5, a zip of UFF 58 files, JSON) here too.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from rcsa.app.jobs import Work, Workbench
from rcsa.app.results import RESULT_FORMAT_FIELD, Format, encode_result, json_bytes, require_format
from rcsa.errors import InputError
from rcsa.infra.atomic_files import atomic_write_bytes
from rcsa.infra.pages import paginate
from rcsa.libraries.exports import library_uff_zip
from rcsa.libraries.formats import LibrarySource, import_library, read_library
from rcsa.libraries.fusion import FusionLibrary
from rcsa.libraries.library_prediction import (
    LIBRARY_OPTIONS,
    check_common,
    checked_batch,
    library_request,
)
from rcsa.libraries.sync import (
    LIBRARY_ID_PATTERN,
    LibraryStore,
    library_id_from_name,
    plan_sync,
    sync_request,
)
from rcsa.measured.hybrid import MeasurementSource
from rcsa.model.contract import CLAMPING_MODELS

__all__ = [
    "DEFAULT_GRID",
    "EXPORT_FORMATS",
    "LIBRARY_ID_PATTERN",
    "LIBRARY_OPTIONS",
    "ExportFile",
    "export_file",
    "library_entries",
    "library_tool_result",
    "list_stored_libraries",
    "prepare_batch",
    "prepare_library",
    "prepare_sync",
    "spindle_settings",
    "write_export",
]

#: Frequency grid of a library prediction when neither the caller, the spindle's assembly
#: nor a measured spindle gives one, Hz.
DEFAULT_GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 1.0}
ExportFormat = Literal["hdf5", "zip", "json", "parquet"]
#: Export formats of a stored library's results, by file suffix.
EXPORT_FORMATS: dict[str, ExportFormat] = {".h5": "hdf5", ".hdf5": "hdf5", ".zip": "zip", ".json": "json",
                                           ".parquet": "parquet"}
_SUFFIX = {"hdf5": ".h5", "zip": ".zip", "json": ".json", "parquet": ".parquet"}


def _with_format(request: dict[str, Any], result_format: Format) -> dict[str, Any]:
    """The work request, naming the form its job writes when that is not JSON."""
    require_format(result_format)
    return request if result_format == "json" else {**request, RESULT_FORMAT_FIELD: result_format}


def _check_tools(n: int, limit: int) -> None:
    if n > limit:
        raise InputError("library", f"has {n} tools to predict; at most {limit} per request")


# --------------------------------------------------------------------------- preparing work

def prepare_batch(bench: Workbench, request: Mapping[str, Any],
                  refused: Mapping[int, Mapping[str, str]] | None = None,
                  tool_point: list[str] | None = None, result_format: Format = "json") -> Work:
    """A batch request (``docs/contract.md`` "Batch"), read and sized: work of kind ``batch``.

    Parameters
    ----------
    bench : Workbench
    request : mapping
        The batch request, combinations as sent.
    refused : mapping of int to dict, optional
        Combinations already refused by the caller (the REST schema), by index: they get an
        ``error`` result in their place (:func:`rcsa.libraries.library_prediction.checked_batch`).
    tool_point : list of str, optional
        Keep only these receptances of each result (``["h"]``).
    result_format : {"json", "hdf5", "parquet"}
        The form a job of it writes its result in (:mod:`rcsa.app.results`).

    Raises
    ------
    InputError
        Too many combinations, or the grid, spindle or materials they share are invalid;
        Parquet without pyarrow.
    """
    combinations = request.get("combinations") if isinstance(request, Mapping) else None
    n = len(combinations) if isinstance(combinations, list) else 0
    if n > bench.max_combinations:
        raise InputError("combinations", f"at most {bench.max_combinations} per request, got {n}; split the batch")
    checked = _with_format(checked_batch(request, refused or {}, tool_point), result_format)
    return Work("batch", checked, n, check=lambda: check_common(request, store=bench.store, max_lines=bench.max_lines))


def prepare_library(bench: Workbench, library: LibrarySource, *, file_name: str | None = None,
                    content_type: str | None = None, holder: Any = None, holder_name: str | None = None,
                    result_format: Format = "json", **fields: Any) -> Work:
    """A Fusion or FreeCAD tool library on one spindle, imported and sized: work of kind ``library``.

    Parameters
    ----------
    bench : Workbench
    library : path, bytes or mapping
        The library as :func:`rcsa.libraries.formats.read_library` reads it: a path (a folder
        is a FreeCAD library), an upload's bytes or a JSON document.
    file_name, content_type : str, optional
        What an upload says it is.
    holder : path, bytes or mapping, optional
        A FreeCAD holder (``.fcholder``) for the toolbits; refused for Fusion.
    holder_name : str, optional
        The holder upload's file name.
    result_format : {"json", "hdf5", "parquet"}
        The form a job of it writes its result in (as in :func:`prepare_batch`).
    **fields
        Those of :func:`rcsa.libraries.library_prediction.library_request`: ``spindle``,
        ``frequency``, ``joints``, ``materials``, ``beam_theory``, ``shear_coefficient``,
        ``natural_frequencies``, ``options`` and ``uncertainty``; and ``holder_tool``, every
        tool's holder–tool joint (:func:`every_tool_joints`).
    """
    library = read_library(library, file_name=file_name, content_type=content_type, holder=holder,
                           holder_name=holder_name)
    request = _with_format(library_request(library, **_library_fields(fields)), result_format)
    n = len(request["batch"]["combinations"])
    _check_tools(n, bench.max_combinations)
    return Work("library", request, n,
                check=lambda: check_common(request["batch"], store=bench.store, max_lines=bench.max_lines))


def prepare_sync(bench: Workbench, library_id: str | None, library: LibrarySource, *, file_name: str | None = None,
                 content_type: str | None = None, holder: Any = None, holder_name: str | None = None,
                 **fields: Any) -> Work:
    """A sync of the stored library ``library_id`` with this export: work of kind ``library-sync``.

    Its size is the number of results not in the result cache yet (only those are
    computed). ``library_id`` None: the library file's name without suffix, made id-safe
    (``"Mill tools (BT40).tools"`` → ``Mill-tools-BT40``; the request's ``library_id`` says
    which). The other arguments as in :func:`prepare_library`.
    """
    if library_id is None:
        library_id = library_id_from_name(str(library)) if isinstance(library, str | os.PathLike) else "library"
    source = library
    library = read_library(library, file_name=file_name, content_type=content_type, holder=holder,
                           holder_name=holder_name)
    request = sync_request(library_id, library, **_library_fields(fields))
    _check_tools(len(request["batch"]["combinations"]), bench.max_combinations)
    if isinstance(library, FusionLibrary):  # kept: presets can be written into it later by reference
        request["settings"]["source_file"] = _keep_file(bench.libraries, source, file_name, content_type)
    plan = plan_sync(bench.libraries, request, store=bench.store, max_lines=bench.max_lines)
    return Work("library-sync", request, len(plan.pending), plan,
                check=lambda: check_common(request["batch"], store=bench.store, max_lines=bench.max_lines))


def _keep_file(libraries: LibraryStore, source: LibrarySource, file_name: str | None,
               content_type: str | None) -> dict[str, Any]:
    """Keep a synced Fusion library's file in the store; ``{"sha256", "file_name", "content_type"}``."""
    if isinstance(source, str | os.PathLike):
        data, file_name = Path(source).read_bytes(), file_name or Path(source).name
    elif isinstance(source, bytes | bytearray | memoryview):
        data = bytes(source)
    else:  # a JSON document (the REST JSON form)
        data, file_name, content_type = json_bytes(source), file_name or "library.json", "application/json"
    return {"sha256": libraries.keep_file(data), "file_name": file_name, "content_type": content_type}


def every_tool_joints(joints: Mapping[str, Any] | None, holder_tool: str | Mapping[str, Any] | None
                      ) -> Mapping[str, Any] | None:
    """The joints applied to every tool of a library, with ``holder_tool`` replacing their own.

    Parameters
    ----------
    joints : mapping or None
        ``{"spindle_holder": {...}, "holder_tool": {...}}`` (either may be left out).
    holder_tool : str or mapping or None
        A clamping model name (``"bonded"``; ``"point"`` = a rigid point joint) or a whole
        ``joints.holder_tool`` object (``{"model": "contact", "interface_stiffness_n_m3": 5e13}``);
        ``None`` keeps the joints as they are.

    Returns
    -------
    mapping or None

    Raises
    ------
    InputError
        ``holder_tool`` is neither a model name nor an object.

    Examples
    --------
    >>> every_tool_joints({"holder_tool": {"stiffness_n_m": 1e7}}, "bonded")
    {'holder_tool': {'model': 'bonded'}}
    """
    if holder_tool is None:
        return joints
    if isinstance(holder_tool, str):
        if holder_tool not in CLAMPING_MODELS:
            raise InputError("holder_tool", f"must be one of {', '.join(CLAMPING_MODELS)} or a holder_tool object, "
                                            f"got {holder_tool!r}")
        if holder_tool == "contact":
            raise InputError("holder_tool", 'a contact clamping needs its interface stiffness: give the object '
                                            '{"model": "contact", "interface_stiffness_n_m3": ...}')
        holder_tool = {} if holder_tool == "point" else {"model": holder_tool}
    elif not isinstance(holder_tool, Mapping):
        raise InputError("holder_tool", "must be a clamping model name or a joints.holder_tool object")
    out = {k: v for k, v in dict(joints or {}).items() if k != "holder_tool"}
    if holder_tool:
        out["holder_tool"] = dict(holder_tool)
    return out


def _library_fields(fields: dict[str, Any]) -> dict[str, Any]:
    """The fields of a library request with a ``holder_tool`` shortcut merged into its joints."""
    if "holder_tool" not in fields:
        return fields
    rest = dict(fields)
    rest["joints"] = every_tool_joints(rest.get("joints"), rest.pop("holder_tool"))
    return rest


def spindle_settings(base: Mapping[str, Any], *, frequency: Mapping[str, Any] | None = None,
                     joints: Mapping[str, Any] | None = None, holder_tool: str | Mapping[str, Any] | None = None,
                     store: MeasurementSource | None = None) -> dict[str, Any]:
    """The spindle, grid, joints and materials of a library prediction from a base document.

    Parameters
    ----------
    base : mapping
        An assembly (its ``spindle``, ``frequency``, ``joints``, ``materials``,
        ``beam_theory`` and ``shear_coefficient`` are used) or ``{"spindle": {...}}``.
    frequency : mapping, optional
        The grid; default the base's, else a measured spindle's own lines, else
        :data:`DEFAULT_GRID`.
    joints : mapping, optional
        Joints for every tool; default the base's (rigid when it has none).
    holder_tool : str or mapping, optional
        The holder–tool joint of every tool, replacing the joints' own: a clamping model name
        (``"bonded"``, ``"point"`` = rigid point joint) or a whole ``joints.holder_tool`` object
        (e.g. ``{"model": "contact", "interface_stiffness_n_m3": 5e13}``): how a whole library
        is switched to a clamping model.
    store : MeasurementSource, optional
        Where a measured spindle's lines are read.

    Returns
    -------
    dict
        Keyword arguments of :func:`prepare_library` / :func:`prepare_sync`.

    Raises
    ------
    InputError
        ``holder_tool`` is neither a model name nor an object.
    """
    spindle = base["spindle"]
    if frequency is not None:
        grid = dict(frequency)
    elif "frequency" in base:
        grid = base["frequency"]
    elif isinstance(spindle, Mapping) and spindle.get("measurement_id") is not None and store is not None:
        grid = {"values_hz": store.get(spindle["measurement_id"]).frequency_hz.tolist()}
    else:
        grid = dict(DEFAULT_GRID)
    chosen = every_tool_joints(joints if joints is not None else base.get("joints"), holder_tool)
    return {"spindle": spindle, "frequency": grid, "joints": chosen,
            "materials": base.get("materials"), "beam_theory": base.get("beam_theory"),
            "shear_coefficient": base.get("shear_coefficient")}


# --------------------------------------------------------------------------- reading libraries

def library_entries(library: LibrarySource, *,
                    options: Mapping[str, Any] | None = None, file_name: str | None = None) -> dict[str, Any]:
    """Every item of a Fusion or FreeCAD library mapped to a holder and tool, without computing anything.

    Returns
    -------
    dict
        ``{"library": {"source", "file_name", "library_sha256", "summary"}, "entries": [...]}``;
        each entry has ``id``, ``index``, ``status`` (``ok``/``skipped``/``error``), and for
        ``ok`` items the assembly's ``holder`` and ``tool``.
    """
    out = import_library(library, **dict(options or {})).to_dict()
    return {"library": {"source": out["source"], "file_name": file_name, "library_sha256": out["library_sha256"],
                        "summary": out["summary"]},
            "entries": out["combinations"]}


# --------------------------------------------------------------------------- exports

@dataclass(frozen=True)
class ExportFile:
    """A stored library's results as one file.

    Attributes
    ----------
    data : bytes
    file_name : str
        ``<library_id>-r<revision>.<suffix>``.
    ok : int
        Tools with a result in it.
    revision : int
        The library revision exported.
    """

    data: bytes
    file_name: str
    ok: int
    revision: int


def list_stored_libraries(bench: Workbench, *, limit: int = 100, cursor: str | None = None) -> dict[str, Any]:
    """One page of the stored libraries' summaries, by id: ``{"items": [...], "next_cursor"}``
    (:mod:`rcsa.infra.pages`, as the measurements and jobs are listed).

    Raises
    ------
    InputError
        A cursor this service did not hand out, or ``limit`` below 1.
    """
    items, next_cursor = paginate(bench.libraries.list(), key=lambda lib: (lib["id"],), limit=limit, cursor=cursor)
    return {"items": items, "next_cursor": next_cursor}


def library_tool_result(bench: Workbench, library_id: str, tool_id: str,
                        tool_point: list[str] | None = None) -> dict[str, Any]:
    """One tool's result from a stored library's last sync (an item of its results: ``ok`` with
    its tool-point FRF, ``skipped`` with the reason or ``error``); long arrays as numpy arrays.

    Raises
    ------
    NotFoundError
        No such library or tool.
    """
    return bench.libraries.tool_result(library_id, tool_id, tool_point)


def export_file(libraries: LibraryStore, library_id: str, fmt: ExportFormat) -> ExportFile:
    """A stored library's results as HDF5, a zip of UFF 58 files, JSON or Parquet.

    Raises
    ------
    NotFoundError
        No such library.
    InputError
        An unknown format, or Parquet without pyarrow (naming the extra ``rcsa[parquet]``).
    """
    if fmt not in _SUFFIX:
        raise InputError("format", f"must be one of {', '.join(_SUFFIX)}, got {fmt!r}")
    if fmt == "parquet":
        require_format(fmt)
    results = libraries.results(library_id)
    if fmt == "json":
        data = json_bytes(results)
    elif fmt == "zip":
        data = library_uff_zip(results)
    else:
        data = encode_result(results, fmt, "library-results")
    revision = int(results["library"]["revision"])
    return ExportFile(data, f"{library_id}-r{revision}{_SUFFIX[fmt]}", int(results["summary"]["ok"]), revision)


def write_export(libraries: LibraryStore, library_id: str, path: str | os.PathLike[str]) -> ExportFile:
    """Write a stored library's results to ``path`` (atomically); the format follows its suffix.

    Raises
    ------
    InputError
        Field ``out``: a suffix that names no format (:data:`EXPORT_FORMATS`).
    NotFoundError
        No such library.
    OSError
        The file cannot be written.
    """
    suffix = Path(path).suffix.lower()
    if suffix not in EXPORT_FORMATS:
        raise InputError("out", f"{path}: the file name must end in {', '.join(EXPORT_FORMATS)}")
    export = export_file(libraries, library_id, EXPORT_FORMATS[suffix])
    atomic_write_bytes(Path(path), export.data)
    return export

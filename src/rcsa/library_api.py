"""Tool-point FRFs of a whole CAM tool library on one spindle (REST and CLI).

A Fusion library (``.json`` or ``.tools``) becomes a *library request*: the import report of
every item (``ok`` / ``skipped`` with a reason / ``error``) and one batch request holding
the ``ok`` tool–holder combinations on the given spindle and frequency grid. Running it calls
:func:`rcsa.api.predict_batch` (the spindle and every distinct holder are condensed once)
and merges the outcome back in library order: one result per library item, each with its
own ``status``. The request is plain JSON, so the service can queue it as a job.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import Any

from . import api
from .errors import InputError
from .spec import MAX_FREQUENCY_LINES, MeasuredSpindleSpec, parse_common

__all__ = [
    "LIBRARY_OPTIONS",
    "check_common",
    "library_request",
    "predict_library",
    "run_library_request",
]

#: Options of :func:`rcsa.libraries.library_combinations` a caller may set.
LIBRARY_OPTIONS = ("holder_material", "tool_material_default", "holder_segments_per_cone",
                   "fluted_diameter_ratio", "shaft_origin", "default_holder")
_COMMON = ("frequency", "spindle", "materials", "beam_theory", "shear_coefficient")
_ENTRY_FIELDS = ("id", "index", "description", "number", "teeth", "tool_type", "warnings")


def check_common(request: Mapping[str, Any], *, store: Any = None,
                 max_lines: int = MAX_FREQUENCY_LINES) -> None:
    """Validate what a batch or library request's combinations share, before queuing it.

    Checks the frequency grid, beam theory, shear coefficient, materials and spindle, and
    for a measured spindle that the measurement exists and covers the grid.

    Raises
    ------
    InputError
        Naming the field, exactly as the computation itself would.
    """
    if not isinstance(request, Mapping):
        raise InputError("", "the request must be a JSON object")
    common = parse_common({k: request[k] for k in _COMMON if k in request}, max_lines=max_lines)
    if isinstance(common.spindle, MeasuredSpindleSpec):
        from .hybrid import measured_base

        sp = common.spindle
        measured_base(sp.measurement_id, common.frequency_hz, store, artifact_method=sp.artifact_method,
                      effective_length_m=sp.effective_length_m)


def library_request(
    library: str | os.PathLike[str] | bytes | Mapping[str, Any],
    *,
    spindle: Mapping[str, Any],
    frequency: Mapping[str, Any],
    joints: Mapping[str, Any] | None = None,
    materials: Mapping[str, Any] | None = None,
    beam_theory: str | None = None,
    shear_coefficient: str | float | None = None,
    natural_frequencies: bool | None = None,
    options: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Turn a Fusion tool library into a library request (JSON-ready).

    Parameters
    ----------
    library : path, bytes or mapping
        The ``.json``/``.tools`` file, its bytes, or the parsed document.
    spindle : mapping
        The contract's spindle: segments and bearings, or ``{"measurement_id": ...}``.
    frequency : mapping
        ``{start_hz, stop_hz, step_hz}`` or ``{values_hz}``.
    joints : mapping, optional
        ``{"spindle_holder": {...}, "holder_tool": {...}}`` applied to every tool (the library
        carries no joint data); rigid when left out.
    materials, beam_theory, shear_coefficient, natural_frequencies : optional
        As in the batch request.
    options : mapping, optional
        :data:`LIBRARY_OPTIONS` for the import (holder material, cones, fluted ratio, ...).

    Returns
    -------
    dict
        ``{"library": {"source", "library_sha256", "summary"}, "entries": [...],
        "batch": {...batch request of the ok tools...}}``.

    Raises
    ------
    InputError
        The library cannot be read, or an option is invalid.
    """
    from .libraries import library_combinations

    if options is not None and not isinstance(options, Mapping):
        raise InputError("options", f"must be an object ({', '.join(LIBRARY_OPTIONS)})")
    opts = dict(options or {})
    unknown = sorted(set(opts) - set(LIBRARY_OPTIONS))
    if unknown:
        raise InputError(f"options.{unknown[0]}", f"unknown option (allowed: {', '.join(LIBRARY_OPTIONS)})")
    if joints is not None and not isinstance(joints, Mapping):
        raise InputError("joints", "must be an object {spindle_holder, holder_tool}")
    imported = library_combinations(library, **opts)
    entries, combos = [], []
    for c in imported:
        entry = {k: v for k, v in c.to_dict().items() if k in (*_ENTRY_FIELDS, "status", "reason")}
        entries.append(entry)
        if c.status == "ok":
            item = c.batch_item()
            if joints:
                item["joints"] = dict(joints)
            combos.append(item)
    batch: dict[str, Any] = {"spindle": spindle, "frequency": frequency, "combinations": combos}
    for key, value in (("materials", materials), ("beam_theory", beam_theory),
                       ("shear_coefficient", shear_coefficient), ("natural_frequencies", natural_frequencies)):
        if value is not None:
            batch[key] = value
    return {"library": {"source": imported.source, "library_sha256": imported.library_sha256,
                        "summary": dict(imported.summary)},
            "entries": entries, "batch": batch}


def run_library_request(
    request: Mapping[str, Any],
    *,
    store: Any = None,
    max_lines: int = MAX_FREQUENCY_LINES,
    max_combinations: int = api.MAX_BATCH_COMBINATIONS,
    progress: Callable[[int, int], None] | None = None,
    arrays: str = "list",
) -> dict[str, Any]:
    """Predict every ``ok`` tool of a library request; merge with the skipped and failed ones.

    Returns
    -------
    dict
        ``{"library": {...}, "results": [...], "summary": {"ok", "skipped", "error"}}``:
        one result per library item in library order, with its ``id``, ``index``,
        ``description``, ``number`` (T number), ``teeth``, ``tool_type``, ``warnings`` and
        ``status``: ``ok`` (the prediction fields), ``skipped`` (``reason``) or ``error``
        (``error: {"field", "detail"}``).
    """
    if not isinstance(request, Mapping) or not {"entries", "batch", "library"} <= set(request):
        raise InputError("", "not a library request (see rcsa.library_api.library_request)")
    batch = request["batch"]
    predicted: dict[str, dict[str, Any]] = {}
    if batch.get("combinations"):
        out = api.predict_batch(batch, store=store, max_lines=max_lines, max_combinations=max_combinations,
                                progress=progress, arrays=arrays)
        predicted = {r["id"]: r for r in out["results"]}
    elif progress is not None:
        progress(0, 0)
    results = []
    for entry in request["entries"]:
        head = {k: entry.get(k) for k in _ENTRY_FIELDS}
        if entry["status"] == "ok":
            r = predicted[entry["id"]]
            results.append({**head, **{k: v for k, v in r.items() if k != "id"}})
        elif entry["status"] == "skipped":
            results.append({**head, "status": "skipped", "reason": entry.get("reason")})
        else:
            field, sep, detail = (entry.get("reason") or "").partition(": ")
            error = {"field": field, "detail": detail} if sep else {"field": "", "detail": entry.get("reason")}
            results.append({**head, "status": "error", "error": error})
    summary = {s: sum(r["status"] == s for r in results) for s in ("ok", "skipped", "error")}
    return {"library": dict(request["library"]), "results": results, "summary": summary}


def predict_library(library: str | os.PathLike[str] | bytes | Mapping[str, Any], *, store: Any = None,
                    max_lines: int = MAX_FREQUENCY_LINES,
                    max_combinations: int = api.MAX_BATCH_COMBINATIONS,
                    progress: Callable[[int, int], None] | None = None, arrays: str = "list",
                    **kwargs: Any) -> dict[str, Any]:
    """:func:`library_request` then :func:`run_library_request` (``kwargs`` go to the first)."""
    request = library_request(library, **kwargs)
    return run_library_request(request, store=store, max_lines=max_lines, max_combinations=max_combinations,
                               progress=progress, arrays=arrays)

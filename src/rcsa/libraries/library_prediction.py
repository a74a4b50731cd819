"""Tool-point FRFs of a whole CAM tool library, or a checked batch, on one spindle (REST and CLI).

A Fusion library (``.json`` or ``.tools``) or a FreeCAD one (``.fctb``/``.fctl``/a folder or
zip of them with an ``.fcholder``, :mod:`rcsa.libraries.formats`) becomes a *library request*: the import report of
every item (``ok`` / ``skipped`` with a reason / ``error``) and one batch request holding
the ``ok`` tool–holder combinations on the given spindle and frequency grid. Running it calls
:func:`rcsa.model.batch.predict_batch` (the spindle and every distinct holder are condensed once)
and merges the outcome back in library order: one result per library item, each with its
own ``status``. The request is plain JSON, so the service can queue it as a job.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from rcsa.errors import InputError
from rcsa.libraries.formats import FREECAD_OPTIONS, FUSION_OPTIONS, LibrarySource, import_library
from rcsa.measured.hybrid import MeasurementSource, base_resolver
from rcsa.model import batch as batches
from rcsa.model.bounds import MAX_BATCH_COMBINATIONS, MAX_FREQUENCY_LINES
from rcsa.model.contract import MeasuredSpindleSpec, parse_common
from rcsa.model.spindle_side import BaseResolver, MeasuredBase

__all__ = [
    "resolver_of",
    "LIBRARY_OPTIONS",
    "check_common",
    "library_request",
    "predict_library",
    "checked_batch",
    "run_entries",
    "select_tool_point",
]

#: Import options a caller may set (each format takes its own: :mod:`rcsa.libraries.formats`).
LIBRARY_OPTIONS = tuple(dict.fromkeys((*FUSION_OPTIONS, *FREECAD_OPTIONS)))
_COMMON = ("frequency", "spindle", "materials", "beam_theory", "shear_coefficient")
_ENTRY_FIELDS = ("id", "index", "description", "number", "teeth", "tool_type", "warnings")


def check_common(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
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
        resolver_of(store)(common.spindle, common.frequency_hz)


def library_request(
    library: LibrarySource,
    *,
    spindle: Mapping[str, Any],
    frequency: Mapping[str, Any],
    joints: Mapping[str, Any] | None = None,
    materials: Mapping[str, Any] | None = None,
    beam_theory: str | None = None,
    shear_coefficient: str | float | None = None,
    natural_frequencies: bool | None = None,
    options: Mapping[str, Any] | None = None,
    uncertainty: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Turn a Fusion or FreeCAD tool library into a library request (JSON-ready).

    Parameters
    ----------
    library : path, bytes, mapping or a library read by :func:`rcsa.libraries.formats.read_library`
        The Fusion ``.json``/``.tools`` file, a FreeCAD library, their bytes, or the parsed document.
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
    uncertainty : mapping, optional
        ``{"draws", "seed", "tolerances"}``: every tool's uncertainty band, as in the batch
        request (:mod:`rcsa.model.uncertainty`).

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
    if options is not None and not isinstance(options, Mapping):
        raise InputError("options", f"must be an object ({', '.join(LIBRARY_OPTIONS)})")
    opts = dict(options or {})
    unknown = sorted(set(opts) - set(LIBRARY_OPTIONS))
    if unknown:
        raise InputError(f"options.{unknown[0]}", f"unknown option (allowed: {', '.join(LIBRARY_OPTIONS)})")
    if joints is not None and not isinstance(joints, Mapping):
        raise InputError("joints", "must be an object {spindle_holder, holder_tool}")
    imported = import_library(library, **opts)
    entries, combos = [], []
    for c in imported:
        entry = {k: v for k, v in c.to_dict().items() if k in (*_ENTRY_FIELDS, "status", "reason")}
        if c.status == "error":
            field, sep, detail = (c.reason or "").partition(": ")
            entry["error"] = {"field": field, "detail": detail} if sep else {"field": "", "detail": c.reason}
        entries.append(entry)
        if c.status == "ok":
            item = c.batch_item()
            if joints:
                item["joints"] = dict(joints)
            combos.append(item)
    batch: dict[str, Any] = {"spindle": spindle, "frequency": frequency, "combinations": combos}
    for key, value in (("materials", materials), ("beam_theory", beam_theory),
                       ("shear_coefficient", shear_coefficient), ("natural_frequencies", natural_frequencies),
                       ("uncertainty", uncertainty)):
        if value is not None:
            batch[key] = value
    return {"library": {"source": imported.source, "library_sha256": imported.library_sha256,
                        "summary": dict(imported.summary)},
            "entries": entries, "batch": batch}


def checked_batch(request: Mapping[str, Any], refused: Mapping[int, Mapping[str, str]],
                  tool_point: list[str] | None = None) -> dict[str, Any]:
    """A batch request some of whose combinations were refused before computing.

    The REST layer checks every combination against its schema (types, bounds); the
    refused ones must still get a result in their place. This returns an *entries request*
    for :func:`run_entries`: the refused combinations as ``error`` entries, the others
    passed on to :func:`rcsa.model.batch.predict_batch`.

    Parameters
    ----------
    request : mapping
        The batch request (``combinations`` as sent).
    refused : mapping of int to dict
        Index of a refused combination → ``{"field", "detail"}`` (field paths from the
        request root, e.g. ``"combinations[3].tool.stickout_m"``).
    tool_point : list of str, optional
        Keep only these receptances of each result (:func:`select_tool_point`).
    """
    if not isinstance(request, Mapping) or not isinstance(request.get("combinations"), list):
        raise InputError("combinations", "must be a non-empty list")
    entries, kept = [], []
    for i, combo in enumerate(request["combinations"]):
        ident = combo.get("id") if isinstance(combo, Mapping) else None
        ident = ident if isinstance(ident, str) else None
        if i in refused:
            entries.append({"id": ident, "status": "error", "error": dict(refused[i])})
        else:
            entries.append({"id": ident, "status": "ok", "path": f"combinations[{i}]"})
            kept.append(combo)
    out: dict[str, Any] = {"entries": entries, "batch": {**request, "combinations": kept}}
    if tool_point is not None:
        out["tool_point"] = list(tool_point)
    return out


def run_entries(
    request: Mapping[str, Any],
    *,
    store: MeasurementSource | None = None,
    max_lines: int = MAX_FREQUENCY_LINES,
    max_combinations: int = MAX_BATCH_COMBINATIONS,
    progress: Callable[[int, int], None] | None = None,
    arrays: str = "list",
) -> dict[str, Any]:
    """Run an entries request (:func:`library_request` or :func:`checked_batch`).

    The ``ok`` entries are computed together by :func:`rcsa.model.batch.predict_batch` (spindle and
    holders condensed once); every entry gets one result in its place.

    Returns
    -------
    dict
        ``{"results": [...], "summary": {...}}`` (and ``"library"`` for a library request).
        A library request's results carry the item's ``id``, ``index``, ``description``,
        ``number`` (T number), ``teeth``, ``tool_type``, ``warnings`` and ``status``: ``ok``
        (the prediction fields), ``skipped`` (``reason``) or ``error`` (``error: {"field",
        "detail"}``, the field relative to the tool).
    """
    if not isinstance(request, Mapping) or not {"entries", "batch"} <= set(request):
        raise InputError("", "not an entries request (see rcsa.libraries.library_prediction.library_request)")
    batch = request["batch"]
    computed: list[dict[str, Any]] = []
    if batch.get("combinations"):
        computed = batches.predict_batch(batch, resolve_base=resolver_of(store), max_lines=max_lines,
                                         max_combinations=max_combinations,
                                     progress=progress, arrays=arrays)["results"]
    else:
        check_common(batch, store=store, max_lines=max_lines)
        if progress is not None:
            progress(0, 0)
    keep = request.get("tool_point")
    results, position = [], 0
    for entry in request["entries"]:
        head = {k: entry[k] for k in _ENTRY_FIELDS if k in entry}
        if entry["status"] == "ok":
            r = computed[position] if keep is None else select_tool_point(computed[position], keep)
            if r["status"] == "error":
                r = {**r, "error": _rebase(r["error"], position, entry.get("path", ""))}
            position += 1
            results.append({**head, **r})
        elif entry["status"] == "skipped":
            results.append({**head, "status": "skipped", "reason": entry.get("reason")})
        else:
            results.append({**head, "status": "error", "error": dict(entry["error"])})
    statuses = ("ok", "skipped", "error") if "library" in request else ("ok", "error")
    out: dict[str, Any] = {"results": results, "summary": {s: sum(r["status"] == s for r in results)
                                                           for s in statuses}}
    if "library" in request:
        out = {"library": dict(request["library"]), **out}
    return out


def select_tool_point(result: Mapping[str, Any], keep: Any) -> dict[str, Any]:
    """A prediction result with only some of ``tool_point``'s receptances (e.g. ``["h"]``).

    Big batches are mostly ``h``, ``l``, ``n``, ``p`` arrays; a caller that needs only the
    translational ``h`` (stability lobes, most plots) can cut the result to a third.
    """
    if not isinstance(keep, list | tuple) or not keep or any(k not in ("h", "l", "n", "p") for k in keep):
        raise InputError("tool_point", "must list some of h, l, n, p")
    if "tool_point" not in result:
        return dict(result)
    return {**result, "tool_point": {k: v for k, v in result["tool_point"].items() if k in keep}}


def _rebase(error: Mapping[str, Any], position: int, path: str) -> dict[str, Any]:
    """Point a batch error's field at the entry's own place (``path``) instead of its position."""
    field = str(error.get("field", ""))
    prefix = f"combinations[{position}]"
    if field.startswith(prefix):
        rest = field[len(prefix):]
        field = (path + rest) if path else rest.lstrip(".")
    return {**error, "field": field}


def predict_library(library: LibrarySource, *, store: MeasurementSource | None = None,
                    max_lines: int = MAX_FREQUENCY_LINES,
                    max_combinations: int = MAX_BATCH_COMBINATIONS,
                    progress: Callable[[int, int], None] | None = None, arrays: str = "list",
                    **kwargs: Any) -> dict[str, Any]:
    """:func:`library_request` then :func:`run_entries` (``kwargs`` go to the first)."""
    request = library_request(library, **kwargs)
    return run_entries(request, store=store, max_lines=max_lines, max_combinations=max_combinations,
                               progress=progress, arrays=arrays)


def resolver_of(store: MeasurementSource | None) -> BaseResolver:
    """Looks measured spindles up in ``store``; without one, a measured spindle is refused."""
    if store is not None:
        return base_resolver(store)

    def refuse(spindle: MeasuredSpindleSpec, frequency_hz: np.ndarray) -> MeasuredBase:
        raise InputError("spindle.measurement_id", "a measured spindle needs a measurement store")

    return refuse

"""Tool-point FRFs of a whole CAM tool library, or a checked batch, on one spindle (REST and CLI).

A Fusion library (``.json`` or ``.tools``) or a FreeCAD one (``.fctb``/``.fctl``/a folder or
zip of them with an ``.fcholder``, :mod:`rcsa.libraries.formats`) becomes a *library request*: the import report of
every item (``ok`` / ``skipped`` with a reason / ``error``) and one batch request holding
the ``ok`` tool–holder combinations on the given spindle and frequency grid. Running it
computes the combinations in chunks (:mod:`rcsa.libraries.chunks`: one
:func:`rcsa.model.batch.predict_batch` per chunk, here or on a cluster) and merges the outcome
back in library order: one result per library item, each with its own ``status``. The
request is plain JSON, so the service can queue it as a job; :func:`iter_entries` hands the
results over one by one, so a job writes them as they come instead of holding them all.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from functools import partial
from typing import Any

import orjson

from rcsa.analysis.progress import check_time
from rcsa.errors import InputError
from rcsa.infra.compute_backends import Backend, LocalBackend
from rcsa.libraries.chunks import (
    Shared,
    chunk_ranges,
    chunk_size,
    compute_chunk,
    prepare_shared,
    resolver_of,
    run_chunk,
)
from rcsa.libraries.formats import FREECAD_OPTIONS, FUSION_OPTIONS, LibrarySource, import_library
from rcsa.measured.hybrid import MeasurementSource
from rcsa.model.bounds import MAX_BATCH_COMBINATIONS, MAX_FREQUENCY_LINES
from rcsa.model.contract import MeasuredSpindleSpec, parse_common

__all__ = [
    "EntryResults",
    "iter_entries",
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
        # the entry's own fields (not to_dict(): its copies of holder and tool would be thrown away)
        entry = {"id": c.id, "index": c.index, "status": c.status, "description": c.description, "number": c.number,
                 "teeth": c.teeth, "tool_type": c.tool_type, "reason": c.reason, "warnings": list(c.warnings)}
        if c.status == "error":
            field, sep, detail = (c.reason or "").partition(": ")
            entry["error"] = {"field": field, "detail": detail} if sep else {"field": "", "detail": c.reason}
        entries.append(entry)
        if c.status == "ok":
            # the import's own holder and tool dicts (batch_item() would copy them): the import is
            # dropped when this returns, and nothing downstream modifies a request
            item = {"id": c.id, "holder": c.holder, "tool": c.tool}
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


@dataclass(frozen=True)
class EntryResults:
    """An entries request being computed: the head of its result, then one result per entry.

    Attributes
    ----------
    head : dict
        ``{"library": {...}}`` for a library request, else empty: what comes before
        ``results`` in the result document.
    results : iterator of dict
        One result per entry, in entry order, computed chunk by chunk as it is consumed.
    statuses : tuple of str
        The statuses :meth:`summary` counts.
    """

    head: dict[str, Any]
    results: Iterator[dict[str, Any]]
    statuses: tuple[str, ...]

    def summary(self, counts: Mapping[str, int]) -> dict[str, int]:
        """The result's ``summary`` from counts of statuses."""
        return {s: int(counts.get(s, 0)) for s in self.statuses}


def iter_entries(
    request: Mapping[str, Any],
    *,
    store: MeasurementSource | None = None,
    max_lines: int = MAX_FREQUENCY_LINES,
    max_combinations: int = MAX_BATCH_COMBINATIONS,
    progress: Callable[[int, int], None] | None = None,
    backend: Backend | None = None,
    chunk_tools: int | None = None,
) -> EntryResults:
    """Start an entries request (:func:`library_request` or :func:`checked_batch`).

    The ``ok`` entries are computed in chunks (:mod:`rcsa.libraries.chunks`) by ``backend``
    (default: here, one chunk after the other); every entry gets one result in its place.
    Everything the whole request can get wrong is raised here, before anything is computed.

    Parameters
    ----------
    request : mapping
        An entries request.
    store : MeasurementSource, optional
        Where a measured spindle is read (once, here; chunks receive its receptance).
    max_lines, max_combinations : int
        Largest accepted number of frequency lines and of combinations.
    progress : callable, optional
        ``progress(done, total)`` after each chunk (over the combinations to compute), and
        while waiting for a cluster: whatever it raises stops the computation.
    backend : Backend, optional
        Where the chunks run (default: here).
    chunk_tools : int, optional
        Tools per chunk; default :func:`rcsa.libraries.chunks.chunk_size` of the grid.

    Returns
    -------
    EntryResults
    """
    if not isinstance(request, Mapping) or not {"entries", "batch"} <= set(request):
        raise InputError("", "not an entries request (see rcsa.libraries.library_prediction.library_request)")
    batch = request["batch"]
    combos: list[Any] = []
    shared = None
    if batch.get("combinations"):
        combos, shared = prepare_shared(batch, store=store, max_lines=max_lines, max_combinations=max_combinations)
    else:
        check_common(batch, store=store, max_lines=max_lines)
    statuses = ("ok", "skipped", "error") if "library" in request else ("ok", "error")
    head = {"library": dict(request["library"])} if "library" in request else {}
    return EntryResults(head, _entry_results(request, combos, shared, backend or LocalBackend(), progress,
                                             chunk_tools), statuses)


def _computed(combos: list[Any], shared: Shared | None, backend: Backend,
              progress: Callable[[int, int], None] | None, chunk_tools: int | None) -> Iterator[dict[str, Any]]:
    """Every combination's result, in order, chunk by chunk (errors' fields point into the whole batch)."""
    total = len(combos)
    if progress is not None:
        progress(0, total)
    if shared is None:
        return
    ranges = chunk_ranges(total, chunk_tools or chunk_size(shared.n_lines))
    done = 0

    def waiting() -> None:
        check_time()
        if progress is not None:
            progress(done, total)

    for i, results in backend.map(partial(run_chunk, compute_chunk), [combos[a:b] for a, b in ranges],
                                  shared=shared, ordered=True, on_wait=waiting):
        check_time()  # an answer given at once stops at its time limit, between chunks
        start = ranges[i][0]
        done += len(results)
        if progress is not None:
            progress(done, total)
        for k, r in enumerate(results):
            if r.get("status") == "error" and start:
                r = {**r, "error": _rebase(r["error"], k, f"combinations[{start + k}]")}
            yield r


def _entry_results(request: Mapping[str, Any], combos: list[Any], shared: Shared | None, backend: Backend,
                   progress: Callable[[int, int], None] | None, chunk_tools: int | None
                   ) -> Iterator[dict[str, Any]]:
    computed = _computed(combos, shared, backend, progress, chunk_tools)
    keep = request.get("tool_point")
    position = 0
    for entry in request["entries"]:
        head = {k: entry[k] for k in _ENTRY_FIELDS if k in entry}
        if entry["status"] == "ok":
            r = next(computed)
            if keep is not None:
                r = select_tool_point(r, keep)
            if r["status"] == "error":
                r = {**r, "error": _rebase(r["error"], position, entry.get("path", ""))}
            position += 1
            yield {**head, **r}
        elif entry["status"] == "skipped":
            yield {**head, "status": "skipped", "reason": entry.get("reason")}
        else:
            yield {**head, "status": "error", "error": dict(entry["error"])}
    for _ in computed:  # a request with fewer ok entries than combinations: finish the progress
        pass


def run_entries(
    request: Mapping[str, Any],
    *,
    store: MeasurementSource | None = None,
    max_lines: int = MAX_FREQUENCY_LINES,
    max_combinations: int = MAX_BATCH_COMBINATIONS,
    progress: Callable[[int, int], None] | None = None,
    arrays: str = "list",
    backend: Backend | None = None,
) -> dict[str, Any]:
    """Run an entries request (:func:`library_request` or :func:`checked_batch`) into one document.

    :func:`iter_entries`, collected.

    Returns
    -------
    dict
        ``{"results": [...], "summary": {...}}`` (and ``"library"`` for a library request).
        A library request's results carry the item's ``id``, ``index``, ``description``,
        ``number`` (T number), ``teeth``, ``tool_type``, ``warnings`` and ``status``: ``ok``
        (the prediction fields), ``skipped`` (``reason``) or ``error`` (``error: {"field",
        "detail"}``, the field relative to the tool).
    """
    started = iter_entries(request, store=store, max_lines=max_lines, max_combinations=max_combinations,
                           progress=progress, backend=backend)
    results = list(started.results)
    if arrays == "list":  # JSON-ready lists (the floats round-trip exactly)
        results = orjson.loads(orjson.dumps(results, option=orjson.OPT_SERIALIZE_NUMPY))
    counts: dict[str, int] = {}
    for r in results:
        counts[r["status"]] = counts.get(r["status"], 0) + 1
    return {**started.head, "results": results, "summary": started.summary(counts)}


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

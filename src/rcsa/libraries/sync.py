"""Tool libraries kept in the store: incremental sync and per-tool results (CLI and REST).

A *library* is a named, stored set of tool-point results: one per item of a CAM tool
library (Fusion ``.json``/``.tools``), computed on one spindle and frequency grid. A
**sync** brings it up to date with a new export of the tool library:

1. The library is imported (:func:`rcsa.libraries.library_prediction.library_request`): one entry per item,
   ``ok`` (a tool–holder combination), ``skipped`` or ``error``, each with a stable id (the
   Fusion ``guid`` when present, see :mod:`rcsa.libraries.fusion`).
2. Every ``ok`` combination gets its result key (:func:`rcsa.libraries.results_cache.result_key`: the
   content of the combination, the spindle — a stored measurement by its *content* hash —,
   the grid and the model version). Only keys not yet in the result cache are computed
   in chunks of tools sharing a holder (:mod:`rcsa.libraries.chunks`; here, or on a Dask
   cluster); each chunk is written to the cache in one transaction as it arrives, so a sync
   killed half-way resumes where it stopped and nothing is stored twice.
3. The new state is committed in one SQLite transaction and compared with the previous sync
   of the same library: every tool id is ``added``, ``changed`` (its result key, or its
   skip/error reason, differs), ``unchanged`` or ``removed``. Descriptions and T numbers are
   updated but do not make a tool ``changed``: only what determines its result does.

Library ids are chosen by the caller: the REST path (``/v1/libraries/{library_id}:sync``),
or ``rcsa library sync --library-id``; the CLI's default is the library file's name
(:func:`library_id_from_name`). Ids match :data:`LIBRARY_ID_PATTERN`.

Layout (under ``<store>/libraries/``)::

    index.sqlite          libraries and their tools (WAL): settings, per-tool status, result key
    results/              content-addressed results (:class:`rcsa.libraries.results_cache.ResultCache`),
                          shared by every library; durable before any commit references
                          them, never modified
    tmp/                  scratch files

Safety: result files are durable before the transaction that references them commits, and
commits are serialised by SQLite (``BEGIN IMMEDIATE``), so two service processes (or the CLI
and the service) may sync at once; each diff is taken against the commit before it.
"""

from __future__ import annotations

import builtins
import contextlib
import hashlib
import json
import os
import re
import sqlite3
from collections.abc import Callable, Mapping
from contextlib import closing
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from rcsa._version import __version__
from rcsa.errors import InputError, NotFoundError, StoreError
from rcsa.infra.clock import utc_now_iso
from rcsa.infra.compute_backends import Backend, LocalBackend
from rcsa.infra.sqlite import connect, transaction
from rcsa.libraries.chunks import chunk_ranges, chunk_size, compute_chunk, prepare_shared, run_chunk
from rcsa.libraries.formats import LibrarySource
from rcsa.libraries.library_prediction import library_request, select_tool_point
from rcsa.libraries.results_cache import (
    ResultCache,
    canonical_json,
    frequency_sha256,
    measurement_sha256,
    model_fingerprint,
    result_keys,
    shared_part,
)
from rcsa.measured.hybrid import MeasurementSource
from rcsa.model.bounds import MAX_FREQUENCY_LINES
from rcsa.model.contract import MeasuredSpindleSpec, parse_common

__all__ = [
    "DIRECTORY",
    "LIBRARY_ID_PATTERN",
    "LibraryStore",
    "SyncPlan",
    "SyncReport",
    "is_library_id",
    "library_id_from_name",
    "plan_sync",
    "run_sync",
    "sync_library",
    "sync_request",
]

#: Sub-directory of the store holding the libraries.
DIRECTORY = "libraries"
#: Library ids: a letter or digit, then up to 127 letters, digits, ``.``, ``_`` or ``-``.
LIBRARY_ID_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$")

_COMMON = ("frequency", "spindle", "materials", "beam_theory", "shear_coefficient")
_HEAD = ("id", "index", "description", "number", "teeth", "tool_type", "warnings")
_BUSY_TIMEOUT_S = 60.0

_SCHEMA = """
CREATE TABLE IF NOT EXISTS libraries (
    id                 TEXT PRIMARY KEY,
    revision           INTEGER NOT NULL,
    created_utc        TEXT NOT NULL,
    synced_utc         TEXT NOT NULL,
    source             TEXT NOT NULL,
    library_sha256     TEXT NOT NULL,
    settings           TEXT NOT NULL,
    measurement_sha256 TEXT,
    frequency_sha256   TEXT NOT NULL,
    n_frequencies      INTEGER NOT NULL,
    frequency_min_hz   REAL NOT NULL,
    frequency_max_hz   REAL NOT NULL,
    model_version      TEXT NOT NULL,
    software_version   TEXT NOT NULL,
    last_sync          TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS tools (
    library_id   TEXT NOT NULL,
    tool_id      TEXT NOT NULL,
    position     INTEGER NOT NULL,
    status       TEXT NOT NULL CHECK (status IN ('ok', 'skipped', 'error')),
    fingerprint  TEXT NOT NULL,
    result_key   TEXT,
    entry        TEXT NOT NULL,
    revision     INTEGER NOT NULL,
    PRIMARY KEY (library_id, tool_id)
);
CREATE INDEX IF NOT EXISTS tools_by_position ON tools (library_id, position);
"""


def is_library_id(text: object) -> bool:
    """Whether ``text`` is a valid library id (:data:`LIBRARY_ID_PATTERN`)."""
    return isinstance(text, str) and LIBRARY_ID_PATTERN.match(text) is not None


def library_id_from_name(name: str | os.PathLike[str]) -> str:
    """The default library id of a library file: its name without suffix, made id-safe.

    Examples
    --------
    >>> library_id_from_name("/share/CAM/Mill tools (BT40).tools")
    'Mill-tools-BT40'
    """
    stem = Path(name).name.split(".")[0] if Path(name).name.startswith(".") else Path(name).stem
    slug = re.sub(r"[^A-Za-z0-9._-]+", "-", stem).strip("-._")[:128].rstrip("-._")
    return slug if is_library_id(slug) else "library"


def _check_id(library_id: object, field_name: str = "library_id") -> str:
    if not is_library_id(library_id):
        raise InputError(field_name, "must be 1-128 letters, digits, '.', '_' or '-', starting with a letter "
                                     f"or digit; got {library_id!r}")
    return str(library_id)



# --------------------------------------------------------------------------- reports


@dataclass(frozen=True, slots=True)
class SyncReport:
    """What a sync did.

    Attributes
    ----------
    library_id : str
    revision : int
        The library's revision after this sync (1 for the first).
    synced_utc : str
    added, changed, unchanged, removed : tuple of str
        Tool ids, in library order (``removed`` in the previous sync's order).
    computed : int
        Results computed by this sync (cache misses).
    from_cache : int
        ``ok`` tools whose result was already in the cache.
    summary : dict
        Tools by final status: ``{"ok", "skipped", "error"}``.
    failed : tuple of dict
        ``{"id", "error": {"field", "detail"}}`` of every tool in error.
    """

    library_id: str
    revision: int
    synced_utc: str
    added: tuple[str, ...]
    changed: tuple[str, ...]
    unchanged: tuple[str, ...]
    removed: tuple[str, ...]
    computed: int
    from_cache: int
    summary: dict[str, int] = field(default_factory=dict)
    failed: tuple[dict[str, Any], ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready report."""
        return {"library_id": self.library_id, "revision": self.revision, "synced_utc": self.synced_utc,
                "added": list(self.added), "changed": list(self.changed), "unchanged": list(self.unchanged),
                "removed": list(self.removed),
                "counts": {"added": len(self.added), "changed": len(self.changed),
                           "unchanged": len(self.unchanged), "removed": len(self.removed)},
                "computed": self.computed, "from_cache": self.from_cache, "summary": dict(self.summary),
                "failed": [dict(f) for f in self.failed]}


@dataclass(frozen=True, slots=True)
class SyncPlan:
    """A sync request checked and keyed, before anything is computed.

    Attributes
    ----------
    request : dict
        The sync request (:func:`sync_request`).
    frequency_hz : numpy.ndarray
    frequency_sha256 : str
    measurement_sha256 : str or None
        Content hash of the stored spindle measurement (hybrid), else None.
    keys : tuple of str
        Result key of every combination of ``request["batch"]``, in order.
    pending : tuple of int
        Positions of the combinations to compute (result not cached; one per distinct key).
    """

    request: Mapping[str, Any]
    frequency_hz: np.ndarray
    frequency_sha256: str
    measurement_sha256: str | None
    keys: tuple[str, ...]
    pending: tuple[int, ...]

    @property
    def library_id(self) -> str:
        """The library this plan syncs."""
        return str(self.request["library_id"])


# --------------------------------------------------------------------------- the store


class LibraryStore:
    """Stored libraries and their results; safe for several processes and for crashes.

    Parameters
    ----------
    directory : str or os.PathLike
        Normally ``<store>/libraries`` (:meth:`in_store`); created on first use.
    """

    def __init__(self, directory: str | os.PathLike[str]) -> None:
        self.directory = Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        self.cache = ResultCache(self.directory / "results", self.directory / "tmp")
        with closing(self._connect()) as con:
            con.executescript(_SCHEMA)
        with contextlib.suppress(OSError):
            self.cache.clean_tmp()

    @classmethod
    def in_store(cls, store_path: str | os.PathLike[str]) -> LibraryStore:
        """The libraries of the store at ``store_path``."""
        return cls(Path(store_path) / DIRECTORY)

    def __repr__(self) -> str:
        return f"LibraryStore({str(self.directory)!r})"

    def _connect(self) -> sqlite3.Connection:
        # FULL: a commit is a library revision its caller was told about (the sync report)
        try:
            return connect(self.directory / "index.sqlite", synchronous="FULL", timeout_s=_BUSY_TIMEOUT_S)
        except sqlite3.Error as exc:
            raise StoreError(f"cannot open the library index in {self.directory}: {exc}") from None

    # ------------------------------------------------------------------ reads
    def __contains__(self, library_id: object) -> bool:
        if not is_library_id(library_id):
            return False
        with closing(self._connect()) as con:
            return con.execute("SELECT 1 FROM libraries WHERE id = ?", (library_id,)).fetchone() is not None

    def ids(self) -> builtins.list[str]:
        """Ids of the stored libraries, sorted."""
        with closing(self._connect()) as con:
            return [r[0] for r in con.execute("SELECT id FROM libraries ORDER BY id")]

    def list(self) -> builtins.list[dict[str, Any]]:
        """Summaries of every stored library (without the per-tool list), sorted by id."""
        with closing(self._connect()) as con:
            rows = con.execute(f"SELECT {_LIB_COLUMNS} FROM libraries ORDER BY id").fetchall()
            counts: dict[str, dict[str, int]] = {lib: {} for lib, *_ in rows}
            for lib, status, n in con.execute("SELECT library_id, status, COUNT(*) FROM tools GROUP BY 1, 2"):
                counts.setdefault(lib, {})[status] = n
        return [_library_doc(r, counts.get(r[0], {})) for r in rows]

    def get(self, library_id: str) -> dict[str, Any]:
        """Summary of one library with the status of every tool (no arrays).

        Returns
        -------
        dict
            ``id, revision, created_utc, synced_utc, source, library_sha256, settings,
            measurement_sha256, frequency, model_version, software_version, summary,
            last_sync`` and ``tools``: ``[{id, index, description, number, teeth, tool_type,
            warnings, status, reason, error, result_sha256, revision}]`` in library order.

        Raises
        ------
        NotFoundError
            No such library.
        """
        row, tools = self._snapshot(library_id)
        counts: dict[str, int] = {}
        for t in tools:
            counts[t["status"]] = counts.get(t["status"], 0) + 1
        doc = _library_doc(row, counts)
        doc["tools"] = tools
        return doc

    def _snapshot(self, library_id: str) -> tuple[tuple[Any, ...], builtins.list[dict[str, Any]]]:
        if not is_library_id(library_id):
            raise NotFoundError("library", str(library_id))
        with closing(self._connect()) as con, transaction(con, immediate=False):
            row = con.execute(f"SELECT {_LIB_COLUMNS} FROM libraries WHERE id = ?", (library_id,)).fetchone()
            tools = con.execute("SELECT tool_id, position, status, result_key, entry, revision FROM tools "
                                "WHERE library_id = ? ORDER BY position, tool_id", (library_id,)).fetchall()
        if row is None:
            raise NotFoundError("library", library_id)
        out = []
        for tool_id, position, status, key, entry, revision in tools:
            e = json.loads(entry)
            out.append({"id": tool_id, "index": position, **{k: e.get(k) for k in _HEAD[2:]},
                        "status": status, "reason": e.get("reason"), "error": e.get("error"),
                        "result_sha256": key, "revision": revision})
        return row, out

    def results(self, library_id: str, tool_point: builtins.list[str] | None = None) -> dict[str, Any]:
        """The library's results in the shape of a library prediction (``LibraryResult``).

        Parameters
        ----------
        library_id : str
        tool_point : list of str, optional
            Keep only these receptances (``["h"]`` cuts the size to a third).

        Returns
        -------
        dict
            ``{"library": {...summary without tools...}, "results": [...], "summary": {...}}``;
            each result carries the tool's ``id, index, description, number, teeth,
            tool_type, warnings, status`` and the prediction (``ok``), ``reason``
            (``skipped``) or ``error``. Long arrays are numpy arrays (use orjson with
            ``OPT_SERIALIZE_NUMPY``).
        """
        row, tools = self._snapshot(library_id)
        results = []
        for t in tools:
            head = {k: t[k] for k in _HEAD}
            if t["status"] == "skipped":
                results.append({**head, "status": "skipped", "reason": t["reason"]})
                continue
            if t["result_sha256"] is None:
                results.append({**head, "status": "error", "error": t["error"]})
                continue
            try:
                doc = self.cache.get(t["result_sha256"])
            except KeyError:
                results.append({**head, "status": "error", "error": {
                    "field": "", "detail": "the stored result is missing (the result cache was cleared); "
                                           "sync the library again to recompute it"}})
                continue
            if tool_point is not None and doc.get("status") == "ok":
                doc = select_tool_point(doc, tool_point)
            results.append({**head, "status": doc.pop("status"), "result_sha256": t["result_sha256"], **doc})
        summary = {s: sum(r["status"] == s for r in results) for s in ("ok", "skipped", "error")}
        library = _library_doc(row, summary)
        return {"library": library, "results": results, "summary": summary}

    # ------------------------------------------------------------------ writes
    def delete(self, library_id: str) -> dict[str, Any]:
        """Forget a library (its cached results stay: they are shared, and safe to delete).

        Raises
        ------
        NotFoundError
            No such library.
        """
        if not is_library_id(library_id):
            raise NotFoundError("library", str(library_id))
        with closing(self._connect()) as con, transaction(con):
            cur = con.execute("DELETE FROM libraries WHERE id = ?", (library_id,))
            con.execute("DELETE FROM tools WHERE library_id = ?", (library_id,))
        if cur.rowcount != 1:
            raise NotFoundError("library", library_id)
        return {"deleted": library_id}

    def commit(self, plan: SyncPlan, statuses: Mapping[str, Mapping[str, Any]], *, computed: int) -> SyncReport:
        """Record a sync whose results are all in the cache; compare with the previous one.

        Parameters
        ----------
        plan : SyncPlan
        statuses : mapping of str to dict
            Result key → ``{"status", "error"?}`` for results whose status is known (those
            just computed); others are read from the previous commit or the cache.
        computed : int
            Results computed by this sync (for the report).
        """
        request = plan.request
        rows = _tool_rows(request, plan.keys)
        known = {k: dict(v) for k, v in statuses.items()}
        library_id = plan.library_id
        with closing(self._connect()) as con:  # statuses of earlier commits: read without the write lock
            for key, status, entry in con.execute(
                    "SELECT result_key, status, entry FROM tools WHERE library_id = ? AND result_key IS NOT NULL",
                    (library_id,)):
                known.setdefault(key, {"status": status, "error": json.loads(entry).get("error")})
        unknown = [r["result_key"] for r in rows if r["result_key"] is not None and r["result_key"] not in known]
        try:
            known.update(self.cache.statuses(unknown))
        except KeyError as exc:
            raise StoreError(f"the result {exc.args[0]} vanished from the cache before the sync could record "
                             "it; sync again") from None
        for r in rows:
            key = r["result_key"]
            if key is None:
                continue
            r["status"] = known[key]["status"]
            if r["status"] == "error":
                r["entry"]["error"] = known[key].get("error")
        now = utc_now_iso()
        batch = request["batch"]
        settings = {**{k: v for k, v in batch.items() if k != "combinations"}, **request.get("settings", {})}
        f = plan.frequency_hz
        with closing(self._connect()) as con, transaction(con):
            prev_row = con.execute("SELECT revision, created_utc FROM libraries WHERE id = ?",
                                   (library_id,)).fetchone()
            prev = {tid: (fp, rev) for tid, fp, rev in con.execute(
                "SELECT tool_id, fingerprint, revision FROM tools WHERE library_id = ? ORDER BY position, "
                "tool_id", (library_id,))}
            revision = 1 if prev_row is None else prev_row[0] + 1
            new_ids = {r["id"] for r in rows}
            added = tuple(r["id"] for r in rows if r["id"] not in prev)
            changed = tuple(r["id"] for r in rows if r["id"] in prev and prev[r["id"]][0] != r["fingerprint"])
            unchanged = tuple(r["id"] for r in rows if r["id"] in prev and prev[r["id"]][0] == r["fingerprint"])
            removed = tuple(tid for tid in prev if tid not in new_ids)
            summary = {s: sum(r["status"] == s for r in rows) for s in ("ok", "skipped", "error")}
            failed = tuple({"id": r["id"], "error": r["entry"].get("error")} for r in rows
                           if r["status"] == "error")
            n_ok_entries = sum(r["result_key"] is not None for r in rows)
            same = frozenset(unchanged)
            report = SyncReport(library_id, revision, now, added, changed, unchanged, removed, computed,
                                max(n_ok_entries - computed, 0), summary, failed)
            con.execute("DELETE FROM tools WHERE library_id = ?", (library_id,))
            con.executemany(
                "INSERT INTO tools (library_id, tool_id, position, status, fingerprint, result_key, entry, "
                "revision) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                [(library_id, r["id"], r["index"], r["status"], r["fingerprint"], r["result_key"],
                  json.dumps(r["entry"]), prev[r["id"]][1] if r["id"] in same else revision)
                 for r in rows])
            con.execute(
                "INSERT OR REPLACE INTO libraries (id, revision, created_utc, synced_utc, source, library_sha256, "
                "settings, measurement_sha256, frequency_sha256, n_frequencies, frequency_min_hz, "
                "frequency_max_hz, model_version, software_version, last_sync) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (library_id, revision, now if prev_row is None else prev_row[1], now,
                 str(request["library"].get("source", "")), str(request["library"].get("library_sha256", "")),
                 json.dumps(settings), plan.measurement_sha256, plan.frequency_sha256, int(f.size),
                 float(f[0]), float(f[-1]), model_fingerprint(), __version__, json.dumps(report.to_dict())))
        return report


_LIB_COLUMNS = ("id, revision, created_utc, synced_utc, source, library_sha256, settings, measurement_sha256, "
                "frequency_sha256, n_frequencies, frequency_min_hz, frequency_max_hz, model_version, "
                "software_version, last_sync")


def _library_doc(row: tuple[Any, ...], counts: Mapping[str, int]) -> dict[str, Any]:
    (lib, revision, created, synced, source, sha, settings, msha, fsha, n, fmin, fmax, model, software,
     last) = row
    return {"id": lib, "revision": revision, "created_utc": created, "synced_utc": synced, "source": source,
            "library_sha256": sha, "settings": json.loads(settings), "measurement_sha256": msha,
            "frequency": {"n_lines": n, "min_hz": fmin, "max_hz": fmax, "sha256": fsha},
            "model_version": str(model), "software_version": software,
            "summary": {s: int(counts.get(s, 0)) for s in ("ok", "skipped", "error")},
            "last_sync": json.loads(last)}


def _tool_rows(request: Mapping[str, Any], keys: tuple[str, ...]) -> list[dict[str, Any]]:
    """One row per library entry: id, index, status, fingerprint, result key, entry JSON."""
    rows: list[dict[str, Any]] = []
    position = 0
    for entry in request["entries"]:
        meta = {k: entry.get(k) for k in _HEAD[2:]}
        meta["warnings"] = list(entry.get("warnings") or [])
        if entry["status"] == "ok":
            key = keys[position]
            position += 1
            rows.append({"id": entry["id"], "index": entry.get("index", len(rows)), "status": "ok",
                         "fingerprint": key, "result_key": key, "entry": meta})
        else:
            outcome = {"status": entry["status"], "reason": entry.get("reason"), "error": entry.get("error")}
            meta.update(reason=outcome["reason"], error=outcome["error"])
            rows.append({"id": entry["id"], "index": entry.get("index", len(rows)), "status": entry["status"],
                         "fingerprint": hashlib.sha256(canonical_json(outcome)).hexdigest(), "result_key": None,
                         "entry": meta})
    return rows


# --------------------------------------------------------------------------- sync


def sync_request(
    library_id: str,
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
    """A JSON-ready sync request: the library imported, keyed by ``library_id``.

    Parameters are those of :func:`rcsa.libraries.library_prediction.library_request`.

    Returns
    -------
    dict
        ``{"library_id", "library", "entries", "batch", "settings": {"joints", "options"}}``.
    """
    _check_id(library_id)
    request = library_request(library, spindle=spindle, frequency=frequency, joints=joints, materials=materials,
                              beam_theory=beam_theory, shear_coefficient=shear_coefficient,
                              natural_frequencies=natural_frequencies, options=options, uncertainty=uncertainty)
    settings = {k: v for k, v in (("joints", joints), ("options", options)) if v}
    return {"library_id": library_id, **request, "settings": settings}


def _measurement_sha(store: MeasurementSource | None, measurement_id: str, coherence: bool = False) -> str:
    if store is None:
        raise InputError("spindle.measurement_id", "a measured spindle needs a measurement store")
    try:
        m = store.get(measurement_id)
    except NotFoundError:
        raise InputError("spindle.measurement_id", f"no stored measurement {measurement_id!r}") from None
    return measurement_sha256(m, coherence=coherence)


def plan_sync(libraries: LibraryStore, request: Mapping[str, Any], *, store: MeasurementSource | None = None,
              max_lines: int = MAX_FREQUENCY_LINES) -> SyncPlan:
    """Check a sync request and find which results must be computed.

    Parameters
    ----------
    libraries : LibraryStore
    request : mapping
        From :func:`sync_request`.
    store : MeasurementStore, optional
        Where a measured spindle is looked up (default store when omitted).
    max_lines : int
        Largest accepted number of frequency lines.

    Raises
    ------
    InputError
        The request is malformed, or names a measurement that does not exist.
    """
    if not isinstance(request, Mapping) or not {"library_id", "entries", "batch", "library"} <= set(request):
        raise InputError("", "not a sync request (see rcsa.libraries.sync.sync_request)")
    _check_id(request["library_id"])
    batch = request["batch"]
    common = parse_common({k: batch[k] for k in _COMMON if k in batch}, max_lines=max_lines)
    msha = None
    if isinstance(common.spindle, MeasuredSpindleSpec):
        # an uncertainty band's noise draws read the stored coherences too
        msha = _measurement_sha(store, common.spindle.measurement_id, coherence=batch.get("uncertainty") is not None)
    shared = shared_part(batch, msha)
    fsha = frequency_sha256(common.frequency_hz)
    combos = batch.get("combinations") or []
    keys = tuple(result_keys(combos, shared, fsha))
    absent = libraries.cache.missing(keys)
    pending, seen = [], set()
    for i, key in enumerate(keys):
        if key not in seen and key in absent:
            pending.append(i)
        seen.add(key)
    return SyncPlan(request, common.frequency_hz, fsha, msha, keys, tuple(pending))


def run_sync(libraries: LibraryStore, request: Mapping[str, Any], *, store: MeasurementSource | None = None,
             max_lines: int = MAX_FREQUENCY_LINES, progress: Callable[[int, int], None] | None = None,
             chunk_tools: int | None = None, plan: SyncPlan | None = None,
             backend: Backend | None = None) -> SyncReport:
    """Compute what is missing, then record the sync (see the module docstring).

    Parameters
    ----------
    libraries : LibraryStore
    request : mapping
        From :func:`sync_request`.
    store : MeasurementStore, optional
        For a measured spindle (resolved here once; chunks receive its receptance).
    max_lines : int
    progress : callable, optional
        ``progress(done, total)`` over the results to compute (``(0, 0)`` when none), after
        each chunk is durably cached and while waiting for a cluster; whatever it raises
        stops the sync (what was cached stays cached).
    chunk_tools : int, optional
        Results computed (and cached in one transaction) per chunk; default
        :func:`rcsa.libraries.chunks.chunk_size` of the grid.
    plan : SyncPlan, optional
        :func:`plan_sync`'s answer, when the caller already has it.
    backend : Backend, optional
        Where the chunks run (default: here, one after the other).

    Returns
    -------
    SyncReport
    """
    plan = plan if plan is not None else plan_sync(libraries, request, store=store, max_lines=max_lines)
    batch = plan.request["batch"]
    combos = batch["combinations"]
    # tools sharing a holder in one chunk, so that the holder is condensed once
    order = sorted(plan.pending, key=lambda i: (canonical_json(combos[i].get("holder") or {}), i))
    total, done = len(order), 0
    statuses: dict[str, dict[str, Any]] = {}
    if progress is not None:
        progress(0, total)
    if total:
        _, shared = prepare_shared({**batch, "combinations": [combos[i] for i in order[:1]]}, store=store,
                                   max_lines=max_lines)
        ranges = chunk_ranges(total, chunk_tools or chunk_size(shared.n_lines))
        chunks = [[combos[i] for i in order[a:b]] for a, b in ranges]

        def waiting() -> None:
            if progress is not None:
                progress(done, total)

        runner = partial(run_chunk, compute_chunk)  # looked up now: tests replace compute_chunk
        for c, results in (backend or LocalBackend()).map(runner, chunks, shared=shared, ordered=False,
                                                           on_wait=waiting):
            items = []
            for k, (i, r) in enumerate(zip(order[ranges[c][0]:ranges[c][1]], results, strict=True)):
                r = dict(r)
                if r.get("status") == "error":
                    r["error"] = _relative(r.get("error") or {}, k)
                key = plan.keys[i]
                statuses[key] = {"status": r.get("status", "ok"), "error": r.get("error")}
                items.append((key, r))
            libraries.cache.put_many(items)  # one durable write per chunk
            done += len(items)
            if progress is not None:
                progress(done, total)
    return libraries.commit(plan, statuses, computed=total)


def _relative(error: Mapping[str, Any], position: int) -> dict[str, Any]:
    """A batch error's field relative to the tool (``combinations[3].tool.x`` → ``tool.x``)."""
    field_name = str(error.get("field", ""))
    prefix = f"combinations[{position}]"
    if field_name.startswith(prefix):
        field_name = field_name[len(prefix):].lstrip(".")
    return {"field": field_name, "detail": str(error.get("detail", ""))}


def sync_library(libraries: LibraryStore, library_id: str,
                 library: str | os.PathLike[str] | bytes | Mapping[str, Any], *, store: MeasurementSource | None = None,
                 max_lines: int = MAX_FREQUENCY_LINES, progress: Callable[[int, int], None] | None = None,
                 **kwargs: Any) -> SyncReport:
    """:func:`sync_request` then :func:`run_sync` (``kwargs`` go to the first)."""
    return run_sync(libraries, sync_request(library_id, library, **kwargs), store=store, max_lines=max_lines,
                    progress=progress)


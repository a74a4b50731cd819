"""Durable background jobs (large batches, tool libraries) in a store directory.

Layout (under ``<store>/jobs/``)::

    jobs.sqlite          one row per job (SQLite, WAL): request, owner, status, progress,
                         heartbeat, result size
    results/<id>.json    the finished result (JSON), written (piece by piece for large ones,
                         :class:`StreamedResult`) to a temporary file, fsynced and renamed
                         before the row says "succeeded"

Life of a job: :meth:`JobStore.submit` inserts it ``queued``. A :class:`JobRunner` (a
thread in every service process, or ``run_one`` from a command) **claims** it in one
``BEGIN IMMEDIATE`` transaction — the database's write lock makes the claim atomic across
processes, so two uvicorn workers never run the same job — and marks it ``running`` with
its runner id and a heartbeat. While computing, the runner refreshes the heartbeat and the
progress; at the end it writes the result file and marks the job ``succeeded`` (or
``failed`` with a problem document). Every update checks that the runner still owns the job.

Restarts: a job whose runner died (process killed, machine rebooted) keeps ``running`` with
a heartbeat that stops moving; once it is older than ``stale_after_s`` any runner may claim
it again (``attempts`` counts the tries). A runner on the same host whose process no longer
exists (runner ids are ``host:pid:token``) is recognised at once, so a restarted service
resumes its own interrupted jobs without waiting for the heartbeat to go stale. After ``max_attempts`` interrupted tries the job is
failed instead of being retried for ever (a request that kills its worker, e.g. by memory).

Limits:

* **time limit** — a :class:`JobRunner` with ``time_limit_s`` fails a job that runs longer
  (problem "Job time limit exceeded"); the job's status says so at once, and the computation
  stops at its next progress report;
* **per-caller quota, running cap and fair claiming** — a job is submitted for an ``owner``
  (whoever asked for it) in a ``pool`` (whose runners it shares; default: its owner's own —
  the service puts every anonymous caller in one pool); ``submit(..., max_unfinished=N)``
  refuses the owner's N+1st unfinished job (:class:`QuotaExceeded`), ``claim(...,
  max_running_per_owner=M)`` lets a pool run at most M jobs at once (so anonymous callers
  share one runner and leave the others to keyed callers), and :meth:`JobStore.claim` serves
  pools round-robin: the queued job of the pool with the fewest running jobs, then the one
  served least recently, then the oldest — so a flood of one caller's jobs never makes
  another caller's job wait for the flood's tail;
* **disk budget** — ``max_result_bytes`` caps the total size of the kept result files: after
  each success the oldest results are evicted (file deleted, row kept with
  ``result_evicted_utc``) until the rest fit; the newest result is always kept.
  :meth:`JobStore.result_path` of an evicted result raises :class:`ResultEvicted`.

Duplicates: every row carries ``request_sha256``, the SHA-256 of the request's canonical
JSON (:func:`canonical_request`). ``submit(..., reuse_unfinished=True)`` returns the
unfinished job of the same kind, request *and owner* instead of queuing a copy (a job is
never shared with another caller who happens to send the same body) — for callers that
retry a submission (the REST service does so for requests with an ``Idempotency-Key``;
the key itself, and every other HTTP rule of idempotency, live in :mod:`service.idempotency`).
Tables created by earlier versions get the new columns on first use; their
``idempotency_key`` column is no longer written.
"""

from __future__ import annotations

import builtins
import contextlib
import hashlib
import json
import logging
import os
import secrets
import socket
import sqlite3
import threading
import time
from collections.abc import Callable, Mapping
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import orjson

from rcsa.errors import InputError, NotFoundError, RcsaError
from rcsa.infra.clock import utc_iso, utc_now_iso
from rcsa.infra.sqlite import connect, transaction

__all__ = [
    "JOB_STATUSES",
    "Job",
    "JobRunner",
    "JobStore",
    "LostClaim",
    "QuotaExceeded",
    "ResultEvicted",
    "StreamedResult",
    "canonical_request",
    "is_job_id",
    "runner_is_dead",
]

log = logging.getLogger("rcsa.infra.job_queue")

JOB_STATUSES = ("queued", "running", "succeeded", "failed")
_JOB_ID_CHARS = set("0123456789abcdef")

_SCHEMA = """
CREATE TABLE IF NOT EXISTS jobs (
    id               TEXT PRIMARY KEY,
    kind             TEXT NOT NULL,
    status           TEXT NOT NULL CHECK (status IN ('queued', 'running', 'succeeded', 'failed')),
    progress         REAL NOT NULL DEFAULT 0,
    request          BLOB NOT NULL,
    request_sha256   TEXT NOT NULL,
    created_utc      TEXT NOT NULL,
    started_utc      TEXT,
    finished_utc     TEXT,
    heartbeat_unix   REAL,
    runner           TEXT,
    attempts         INTEGER NOT NULL DEFAULT 0,
    result_file      TEXT,
    error            TEXT,
    summary          TEXT,
    owner            TEXT,
    result_bytes     INTEGER,
    result_evicted_utc TEXT,
    pool             TEXT
);
CREATE INDEX IF NOT EXISTS jobs_status ON jobs (status, created_utc);
CREATE INDEX IF NOT EXISTS jobs_request ON jobs (request_sha256, kind);
"""
#: Columns added since the first version (``ALTER TABLE`` on tables created before them).
_ADDED_COLUMNS = {"owner": "TEXT", "result_bytes": "INTEGER", "result_evicted_utc": "TEXT", "pool": "TEXT"}
_INDEXES = """
CREATE INDEX IF NOT EXISTS jobs_owner ON jobs (owner, status);
CREATE INDEX IF NOT EXISTS jobs_kept ON jobs (status, finished_utc) WHERE result_file IS NOT NULL;
"""
_COLUMNS = ("id, kind, status, progress, created_utc, started_utc, finished_utc, attempts, "
            "error, summary, request_sha256, heartbeat_unix, result_bytes, result_evicted_utc")
_BUSY_TIMEOUT_S = 30.0
_PURGE_EVERY_S = 3600.0
#: Fair choice of a queued job: fewest running jobs of its pool (its owner's own unless it was
#: given one), then the pool served least recently, then its owner served least recently, then
#: the oldest job. Parameters: the per-pool running cap, twice (NULL: none).
_FAIR_CLAIM = """
WITH keyed AS (SELECT *, COALESCE(pool, owner) AS k FROM jobs),
     running AS (SELECT k, COUNT(*) AS n FROM keyed WHERE status = 'running' GROUP BY k),
     served AS (SELECT k, MAX(started_utc) AS last FROM keyed WHERE started_utc IS NOT NULL GROUP BY k),
     owner_served AS (SELECT owner, MAX(started_utc) AS last FROM jobs WHERE started_utc IS NOT NULL GROUP BY owner)
SELECT j.id, j.attempts FROM keyed AS j
LEFT JOIN running AS r ON r.k IS j.k
LEFT JOIN served AS s ON s.k IS j.k
LEFT JOIN owner_served AS o ON o.owner IS j.owner
WHERE j.status = 'queued' AND (? IS NULL OR COALESCE(r.n, 0) < ?)
ORDER BY COALESCE(r.n, 0), COALESCE(s.last, ''), COALESCE(o.last, ''), j.created_utc, j.id
LIMIT 1
"""


_HOST = socket.gethostname()


def runner_is_dead(runner: str | None) -> bool:
    """Whether a runner id ``host:pid:token`` of this host names a process that no longer exists.

    False for other hosts, for this process and whenever it cannot be told.
    """
    try:
        host, pid, _ = str(runner).split(":")
        if host != _HOST or int(pid) == os.getpid():
            return False
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return True
    except (ValueError, PermissionError, OSError):
        return False
    return False


def is_job_id(text: object) -> bool:
    """Whether ``text`` has the shape of a job id (``j-`` + 32 hex digits)."""
    return (isinstance(text, str) and len(text) == 34 and text.startswith("j-")
            and set(text[2:]) <= _JOB_ID_CHARS)



def canonical_request(request: Mapping[str, Any]) -> tuple[bytes, str]:
    """Canonical JSON bytes of a request (sorted keys) and their SHA-256 (``request_sha256``)."""
    data = orjson.dumps(request, option=orjson.OPT_SORT_KEYS | orjson.OPT_SERIALIZE_NUMPY)
    return data, hashlib.sha256(data).hexdigest()


class LostClaim(RcsaError):
    """The runner no longer owns the job (another runner took it over as stale, or it was
    failed for running past its time limit)."""


class QuotaExceeded(RcsaError):
    """The owner already has as many unfinished jobs as allowed.

    Attributes
    ----------
    owner : str
    limit : int
    """

    def __init__(self, owner: str, limit: int) -> None:
        super().__init__(f"{owner} already has {limit} unfinished jobs (queued or running), the most one caller "
                         "may have; wait for some to finish")
        self.owner = owner
        self.limit = limit


class ResultEvicted(RcsaError):
    """A succeeded job's result file was deleted to keep the kept results within their disk budget."""

    def __init__(self, job_id: str, evicted_utc: str) -> None:
        super().__init__(f"the result of job {job_id} was deleted on {evicted_utc} to keep the kept job results "
                         "within their disk budget (oldest first); submit the job again")
        self.job_id = job_id
        self.evicted_utc = evicted_utc


@dataclass(frozen=True)
class StreamedResult:
    """A result too large to build in memory, returned by a :data:`Handler` instead of a document.

    ``write(fh)`` computes and writes the result's bytes (JSON, or a binary form) to the
    binary file ``fh`` (readable and seekable) piece by piece, and returns the job's summary. The runner calls it with the job's temporary
    result file, then fsyncs and renames it as for any other result.
    """

    write: Callable[[BinaryIO], Mapping[str, Any] | None]


@dataclass(frozen=True, slots=True)
class Job:
    """A job's public state (never its request or result, which may be large).

    Attributes
    ----------
    id : str
    kind : str
        What it computes, e.g. ``"batch"`` or ``"library"``.
    status : {"queued", "running", "succeeded", "failed"}
    progress : float
        Fraction done, 0…1.
    created_utc, started_utc, finished_utc : str or None
    attempts : int
        How many times a runner started it.
    error : dict or None
        A problem document (``title``, ``detail``, ``status``, ``errors``) when failed.
    summary : dict or None
        Small result summary when succeeded (e.g. ``{"ok": 997, "error": 3}``).
    request_sha256 : str
        SHA-256 of the request's canonical JSON (:func:`canonical_request`).
    heartbeat_unix : float or None
        Last sign of life of its runner, s since the epoch.
    result_bytes : int or None
        Size of the result file (succeeded jobs).
    result_evicted_utc : str or None
        When the result file was deleted to keep the results within their disk budget.
    """

    id: str
    kind: str
    status: str
    progress: float
    created_utc: str
    started_utc: str | None
    finished_utc: str | None
    attempts: int
    error: dict[str, Any] | None
    summary: dict[str, Any] | None
    request_sha256: str
    heartbeat_unix: float | None
    result_bytes: int | None = None
    result_evicted_utc: str | None = None

    @classmethod
    def _from_row(cls, row: tuple[Any, ...]) -> Job:
        (jid, kind, status, progress, created, started, finished, attempts, error, summary,
         sha, heartbeat, result_bytes, evicted) = row
        return cls(jid, kind, status, float(progress), created, started, finished, int(attempts),
                   json.loads(error) if error else None, json.loads(summary) if summary else None,
                   sha, heartbeat, None if result_bytes is None else int(result_bytes), evicted)

    @property
    def has_result(self) -> bool:
        """Whether the job succeeded and its result file is kept."""
        return self.status == "succeeded" and self.result_evicted_utc is None

    @property
    def finished(self) -> bool:
        """Whether the job reached ``succeeded`` or ``failed``."""
        return self.status in ("succeeded", "failed")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready public state."""
        return {"id": self.id, "kind": self.kind, "status": self.status, "progress": self.progress,
                "created_utc": self.created_utc, "started_utc": self.started_utc,
                "finished_utc": self.finished_utc, "attempts": self.attempts,
                "error": self.error, "summary": self.summary, "result_bytes": self.result_bytes,
                "result_evicted_utc": self.result_evicted_utc}


class JobStore:
    """The job table and result files of one store directory; safe across processes.

    Parameters
    ----------
    directory : str or os.PathLike
        Normally ``<store>/jobs``; created on first use.
    stale_after_s : float
        A running job whose heartbeat is older than this is considered abandoned, s.
    max_attempts : int
        Interrupted tries after which a job is failed rather than resumed.
    max_result_bytes : int, optional
        Disk budget of the kept result files: the oldest are evicted beyond it (None: no cap).
    """

    def __init__(self, directory: str | os.PathLike[str], *, stale_after_s: float = 60.0,
                 max_attempts: int = 3, max_result_bytes: int | None = None) -> None:
        self.directory = Path(directory)
        self.results = self.directory / "results"
        self.stale_after_s = float(stale_after_s)
        self.max_attempts = int(max_attempts)
        self.max_result_bytes = None if max_result_bytes is None else int(max_result_bytes)
        self.results.mkdir(parents=True, exist_ok=True)
        with closing(self._connect()) as con:
            con.executescript(_SCHEMA)
            have = {r[1] for r in con.execute("PRAGMA table_info(jobs)")}
            for name, sql_type in _ADDED_COLUMNS.items():
                if name not in have:
                    with contextlib.suppress(sqlite3.OperationalError):  # another process added it first
                        con.execute(f"ALTER TABLE jobs ADD COLUMN {name} {sql_type}")
            con.executescript(_INDEXES)

    def __repr__(self) -> str:
        return f"JobStore({str(self.directory)!r})"

    def _connect(self) -> sqlite3.Connection:
        # FULL: a queued job was acknowledged (202) and its result row is what the client polls
        return connect(self.directory / "jobs.sqlite", synchronous="FULL", timeout_s=_BUSY_TIMEOUT_S)

    # ------------------------------------------------------------------ submit / read
    def submit(self, kind: str, request: Mapping[str, Any], *, reuse_unfinished: bool = False,
               owner: str | None = None, max_unfinished: int | None = None, pool: str | None = None) -> Job:
        """Queue a job; return its state.

        Parameters
        ----------
        kind : str
            Name of the handler that will run it.
        request : mapping
            JSON-ready request document (kept until the job is purged).
        reuse_unfinished : bool
            Return the queued or running job of this kind with the same request (same
            ``request_sha256``) and the same owner, if there is one, instead of queuing a copy.
        owner : str, optional
            Who asked for it (quotas count per owner).
        max_unfinished : int, optional
            Refuse the job when ``owner`` already has this many queued or running jobs.
        pool : str, optional
            Whose runners it shares: claims are fair across pools and the running cap counts
            per pool (default: the owner's own).

        Raises
        ------
        QuotaExceeded
            ``owner`` is at ``max_unfinished`` (checked atomically with the insert).
        """
        data, sha = canonical_request(request)
        job_id = "j-" + secrets.token_hex(16)
        with closing(self._connect()) as con, transaction(con):
            if reuse_unfinished:
                row = con.execute("SELECT id FROM jobs WHERE request_sha256 = ? AND kind = ? AND owner IS ? AND "
                                  "status IN ('queued', 'running') ORDER BY created_utc, id LIMIT 1",
                                  (sha, kind, owner)).fetchone()
                if row is not None:
                    return self.get(row[0])
            if max_unfinished is not None:
                n = con.execute("SELECT COUNT(*) FROM jobs WHERE owner IS ? AND status IN ('queued', 'running')",
                                (owner,)).fetchone()[0]
                if n >= max_unfinished:
                    raise QuotaExceeded(owner or "this caller", int(max_unfinished))
            con.execute(
                "INSERT INTO jobs (id, kind, status, request, request_sha256, created_utc, owner, pool) "
                "VALUES (?, ?, 'queued', ?, ?, ?, ?, ?)", (job_id, kind, data, sha, utc_now_iso(), owner, pool))
        return self.get(job_id)

    def get(self, job_id: str) -> Job:
        """The job's state.

        Raises
        ------
        NotFoundError
            No such job (or not a job id).
        """
        if not is_job_id(job_id):
            raise NotFoundError("job", str(job_id))
        with closing(self._connect()) as con:
            row = con.execute(f"SELECT {_COLUMNS} FROM jobs WHERE id = ?", (job_id,)).fetchone()
        if row is None:
            raise NotFoundError("job", job_id)
        return Job._from_row(row)

    def request(self, job_id: str) -> dict[str, Any]:
        """The request document a job was submitted with."""
        self.get(job_id)
        with closing(self._connect()) as con:
            row = con.execute("SELECT request FROM jobs WHERE id = ?", (job_id,)).fetchone()
        if row is None:
            raise NotFoundError("job", job_id)
        doc: dict[str, Any] = orjson.loads(row[0])
        return doc

    def result_path(self, job_id: str) -> Path:
        """The result file of a succeeded job.

        Raises
        ------
        NotFoundError
            No such job, or it has not succeeded (see :meth:`get` for its status).
        ResultEvicted
            It succeeded, but its result was evicted (disk budget).
        """
        job = self.get(job_id)
        if job.status == "succeeded" and job.result_evicted_utc is not None:
            raise ResultEvicted(job.id, job.result_evicted_utc)
        path = self.results / f"{job.id}.json"
        if job.status != "succeeded" or not path.is_file():
            raise NotFoundError("result of job", job_id)
        return path

    def list(self, status: str | None = None, limit: int = 100) -> builtins.list[Job]:
        """Jobs, newest first, optionally of one status."""
        sql, args = f"SELECT {_COLUMNS} FROM jobs", builtins.list[str | int]()
        if status is not None:
            sql += " WHERE status = ?"
            args.append(status)
        sql += " ORDER BY created_utc DESC, id LIMIT ?"
        args.append(int(limit))
        with closing(self._connect()) as con:
            return [Job._from_row(r) for r in con.execute(sql, args)]

    def counts(self) -> dict[str, int]:
        """Number of jobs by status."""
        with closing(self._connect()) as con:
            found = dict(con.execute("SELECT status, COUNT(*) FROM jobs GROUP BY status").fetchall())
        return {s: int(found.get(s, 0)) for s in JOB_STATUSES}

    def kept_result_bytes(self) -> int:
        """Total size of the kept result files, bytes (what the disk budget caps)."""
        with closing(self._connect()) as con:
            return int(con.execute("SELECT COALESCE(SUM(result_bytes), 0) FROM jobs WHERE status = 'succeeded' "
                                   "AND result_file IS NOT NULL").fetchone()[0])

    # ------------------------------------------------------------------ runner side
    def claim(self, runner: str, *, max_running_per_owner: int | None = None) -> Job | None:
        """Atomically take a job for ``runner``: an abandoned running one first, else a queued one.

        Queued jobs are served fairly across pools (an owner's own, unless submitted in a
        shared one): the job of the pool with the fewest running jobs, then of the pool served
        least recently, then of its owner served least recently, then the oldest. With
        ``max_running_per_owner``, a pool's jobs wait while it has that many running.
        """
        now = time.time()
        with closing(self._connect()) as con, transaction(con):
            dead = [(job_id,) for job_id, owner in con.execute(
                "SELECT id, runner FROM jobs WHERE status = 'running' AND runner LIKE ?", (_HOST + ":%",))
                if runner_is_dead(owner)]
            if dead:  # its process is gone from this machine: no need to wait for the heartbeat
                con.executemany("UPDATE jobs SET heartbeat_unix = NULL WHERE id = ?", dead)
            while True:
                row = con.execute(
                    "SELECT id, attempts FROM jobs WHERE status = 'running' AND (heartbeat_unix IS NULL OR "
                    "heartbeat_unix < ?) ORDER BY created_utc, id LIMIT 1", (now - self.stale_after_s,)).fetchone()
                if row is None:
                    row = con.execute(_FAIR_CLAIM, (max_running_per_owner, max_running_per_owner)).fetchone()
                if row is None:
                    job_id = None
                    break
                job_id, attempts = row
                if attempts >= self.max_attempts:
                    error = {"title": "Job abandoned", "status": 500,
                             "detail": f"the job was interrupted {attempts} times (its worker stopped "
                                       "while running it); submit it again, perhaps split into "
                                       "smaller batches"}
                    con.execute("UPDATE jobs SET status = 'failed', finished_utc = ?, error = ?, "
                                "runner = NULL WHERE id = ?", (utc_now_iso(), json.dumps(error), job_id))
                    continue
                con.execute(
                    "UPDATE jobs SET status = 'running', runner = ?, heartbeat_unix = ?, progress = 0, "
                    "attempts = attempts + 1, started_utc = ? WHERE id = ?",
                    (runner, now, utc_now_iso(), job_id))
                break
        return None if job_id is None else self.get(job_id)

    def heartbeat(self, job_id: str, runner: str, progress: float | None = None) -> None:
        """Refresh the heartbeat (and progress) of a job ``runner`` owns.

        Raises
        ------
        LostClaim
            Another runner has taken the job over.
        """
        with closing(self._connect()) as con:
            if progress is None:
                cur = con.execute("UPDATE jobs SET heartbeat_unix = ? WHERE id = ? AND runner = ? "
                                  "AND status = 'running'", (time.time(), job_id, runner))
            else:
                cur = con.execute("UPDATE jobs SET heartbeat_unix = ?, progress = ? WHERE id = ? AND "
                                  "runner = ? AND status = 'running'",
                                  (time.time(), min(max(float(progress), 0.0), 1.0), job_id, runner))
        if cur.rowcount != 1:
            raise LostClaim(f"job {job_id} is no longer owned by {runner}")

    def result_tmp(self, job_id: str, runner: str) -> Path:
        """Where ``runner`` writes the result of ``job_id`` before :meth:`succeed_with_file`."""
        return self.results / f".{job_id}.{runner.replace(':', '_')}.tmp"

    def succeed(self, job_id: str, runner: str, result: bytes,
                summary: Mapping[str, Any] | None = None) -> None:
        """Store the result (JSON bytes) and mark the job succeeded."""
        tmp = self.result_tmp(job_id, runner)
        with open(tmp, "wb") as fh:
            fh.write(result)
            fh.flush()
            os.fsync(fh.fileno())
        self.succeed_with_file(job_id, runner, tmp, summary)

    def succeed_with_file(self, job_id: str, runner: str, tmp: Path,
                          summary: Mapping[str, Any] | None = None) -> None:
        """Mark the job succeeded with the result ``runner`` wrote (and fsynced) to ``tmp``
        (:meth:`result_tmp`); then evict old results beyond the disk budget."""
        self._finish(job_id, runner, "succeeded", summary=summary, rename=(tmp, self.results / f"{job_id}.json"))

    def fail(self, job_id: str, runner: str, error: Mapping[str, Any]) -> None:
        """Mark the job failed with a problem document."""
        self._finish(job_id, runner, "failed", error=error)

    def _finish(self, job_id: str, runner: str, status: str, *, summary: Mapping[str, Any] | None = None,
                error: Mapping[str, Any] | None = None, rename: tuple[Path, Path] | None = None) -> None:
        try:
            with closing(self._connect()) as con, transaction(con):
                owned = con.execute("SELECT 1 FROM jobs WHERE id = ? AND runner = ? AND status = 'running'",
                                    (job_id, runner)).fetchone()
                if owned is None:
                    raise LostClaim(f"job {job_id} is no longer owned by {runner}")
                size = None
                if rename is not None:
                    size = rename[0].stat().st_size
                    os.replace(*rename)
                con.execute(
                    "UPDATE jobs SET status = ?, progress = CASE WHEN ? = 'succeeded' THEN 1 ELSE progress END, "
                    "finished_utc = ?, result_file = ?, error = ?, summary = ?, runner = NULL, result_bytes = ? "
                    "WHERE id = ?",
                    (status, status, utc_now_iso(), rename[1].name if rename else None,
                     json.dumps(error) if error is not None else None,
                     json.dumps(summary) if summary is not None else None, size, job_id))
                # in the same transaction: nobody sees the new result before the old ones are evicted
                evicted = self._evict(con, self.max_result_bytes) if rename and self.max_result_bytes is not None \
                    else []
        except BaseException:
            if rename is not None:
                with contextlib.suppress(OSError):
                    rename[0].unlink()
            raise
        self._unlink_evicted(evicted)

    def evict(self, max_bytes: int) -> builtins.list[str]:
        """Delete the oldest kept results until the rest take at most ``max_bytes``; return their job ids.

        The newest result is always kept (even when it alone is larger). An evicted job keeps
        its row: ``status`` stays ``succeeded``, ``result_evicted_utc`` says when.
        """
        with closing(self._connect()) as con, transaction(con):
            evicted = self._evict(con, max_bytes)
        self._unlink_evicted(evicted)
        return evicted

    def _evict(self, con: sqlite3.Connection, max_bytes: int) -> builtins.list[str]:
        """Mark the results to evict (inside the caller's transaction); :meth:`_unlink_evicted` after it."""
        rows = con.execute("SELECT id, result_bytes FROM jobs WHERE status = 'succeeded' AND result_file IS NOT "
                           "NULL ORDER BY finished_utc DESC, id DESC").fetchall()
        total, evicted = 0, []
        for k, (job_id, size) in enumerate(rows):
            if size is None:  # a result of an earlier version: measure it once
                with contextlib.suppress(OSError):
                    size = (self.results / f"{job_id}.json").stat().st_size
                    con.execute("UPDATE jobs SET result_bytes = ? WHERE id = ?", (size, job_id))
            total += int(size or 0)
            if k > 0 and total > max_bytes:
                evicted.append(job_id)
        if evicted:
            now = utc_now_iso()
            con.executemany("UPDATE jobs SET result_file = NULL, result_evicted_utc = ? WHERE id = ?",
                            [(now, i) for i in evicted])
        return evicted

    def _unlink_evicted(self, evicted: builtins.list[str]) -> None:
        for i in evicted:
            with contextlib.suppress(FileNotFoundError):
                (self.results / f"{i}.json").unlink()
        if evicted:
            log.warning("job results: evicted %d oldest result(s) to keep the kept results within %s bytes: %s",
                        len(evicted), self.max_result_bytes, ", ".join(evicted))

    def purge(self, older_than_s: float) -> int:
        """Delete finished jobs (rows and result files) finished more than ``older_than_s`` ago."""
        cutoff = utc_iso(time.time() - older_than_s)
        with closing(self._connect()) as con:
            ids = [r[0] for r in con.execute(
                "SELECT id FROM jobs WHERE status IN ('succeeded', 'failed') AND finished_utc < ?", (cutoff,))]
            con.executemany("DELETE FROM jobs WHERE id = ?", [(i,) for i in ids])
        for i in ids:
            with contextlib.suppress(FileNotFoundError):
                (self.results / f"{i}.json").unlink()
        return len(ids)


#: A handler computes a job: ``handler(request, progress) -> (result, summary)``, where
#: ``progress(done, total)`` may be called as work advances (it raises :class:`LostClaim`
#: when the run must stop: the job was taken over, or failed for its time limit) and the
#: result is a JSON-ready document or a :class:`StreamedResult`.
Handler = Callable[[dict[str, Any], Callable[[int, int], None]], tuple[Any, Mapping[str, Any] | None]]


class JobRunner:
    """Runs claimed jobs in a background thread of this process.

    Parameters
    ----------
    jobs : JobStore
    handlers : mapping of str to Handler
        One per job ``kind``. A handler raising :class:`~rcsa.errors.InputError` fails the
        job with a 422 problem naming the field; any other exception with a 500 problem
        (and a logged traceback).
    poll_s : float
        How often an idle runner looks for work, s (``wake`` makes it look at once).
    heartbeat_s : float
        How often a busy runner refreshes its heartbeat and progress, s.
    on_finish : callable, optional
        ``on_finish(job, seconds)`` after each job (for metrics).
    retention_s : float, optional
        Purge finished jobs older than this, hourly (:meth:`JobStore.purge`); None keeps them.
    time_limit_s : float, optional
        A run longer than this fails the job ("Job time limit exceeded", checked at every
        heartbeat); the computation stops at its next progress report. None: no limit.
    max_running_per_owner : int, optional
        Passed to :meth:`JobStore.claim`.
    """

    def __init__(self, jobs: JobStore, handlers: Mapping[str, Handler], *, poll_s: float = 1.0,
                 heartbeat_s: float = 2.0, on_finish: Callable[[Job, float], None] | None = None,
                 retention_s: float | None = None, time_limit_s: float | None = None,
                 max_running_per_owner: int | None = None) -> None:
        self.jobs = jobs
        self.time_limit_s = None if time_limit_s is None else float(time_limit_s)
        self.max_running_per_owner = max_running_per_owner
        self.handlers = dict(handlers)
        self.poll_s = float(poll_s)
        self.heartbeat_s = float(heartbeat_s)
        self.on_finish = on_finish
        self.retention_s = retention_s
        self._next_purge = time.monotonic() + _PURGE_EVERY_S
        self.runner_id = f"{_HOST}:{os.getpid()}:{secrets.token_hex(4)}"
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def alive(self) -> bool:
        """Whether the background thread is running."""
        return self._thread is not None and self._thread.is_alive()

    def start(self) -> None:
        """Start the background thread (idempotent)."""
        if self._thread is None or not self._thread.is_alive():
            self._stop.clear()
            self._thread = threading.Thread(target=self._loop, name="rcsa-job-runner", daemon=True)
            self._thread.start()

    def stop(self, timeout_s: float = 30.0) -> None:
        """Ask the thread to stop after the current job and wait for it.

        A job still running when the timeout expires is left ``running``; its heartbeat goes
        stale and a runner resumes it later.
        """
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout_s)

    def wake(self) -> None:
        """Look for work now (after a submit in this process)."""
        self._wake.set()

    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                worked = self.run_one()
            except Exception:  # the database itself failed: log, wait, try again
                log.exception("job runner: could not claim or record a job")
                worked = False
            if self.retention_s is not None and time.monotonic() > self._next_purge:
                self._next_purge = time.monotonic() + _PURGE_EVERY_S
                try:
                    self.jobs.purge(self.retention_s)
                except Exception:
                    log.exception("job runner: could not purge old jobs")
            if not worked:
                self._wake.wait(self.poll_s)
                self._wake.clear()

    def run_one(self) -> bool:
        """Claim and run one job; return whether there was one."""
        job = self.jobs.claim(self.runner_id, max_running_per_owner=self.max_running_per_owner)
        if job is None:
            return False
        t0 = time.perf_counter()
        log.info("job %s (%s) started, attempt %d", job.id, job.kind, job.attempts)
        state = {"progress": 0.0}
        done = threading.Event()
        lost = threading.Event()
        started = time.monotonic()

        def beat() -> None:
            while not done.wait(min(self.heartbeat_s, self.time_limit_s or self.heartbeat_s)):
                try:
                    if self.time_limit_s is not None and time.monotonic() - started > self.time_limit_s:
                        self._time_out(job)
                        lost.set()
                        return
                    self.jobs.heartbeat(job.id, self.runner_id, state["progress"])
                except LostClaim:
                    lost.set()
                    return
                except Exception:  # keep computing; a later beat or the finish will tell
                    log.exception("job %s: heartbeat failed", job.id)

        def progress(n_done: int, total: int) -> None:
            state["progress"] = n_done / total if total else 1.0
            if lost.is_set():
                raise LostClaim(f"job {job.id} was taken over by another runner or stopped")

        beater = threading.Thread(target=beat, name=f"rcsa-job-heartbeat-{job.id}", daemon=True)
        beater.start()
        tmp = self.jobs.result_tmp(job.id, self.runner_id)
        for stale in self.jobs.results.glob(f".{job.id}.*.tmp"):  # a half-written result of an interrupted run
            with contextlib.suppress(OSError):
                stale.unlink()
        try:
            handler = self.handlers.get(job.kind)
            if handler is None:
                raise InputError("kind", f"this service cannot run jobs of kind {job.kind!r}")
            document, summary = handler(self.jobs.request(job.id), progress)
            with open(tmp, "w+b") as fh:  # readable too: an HDF5 writer reads back what it wrote
                if isinstance(document, StreamedResult):
                    written = document.write(fh)  # computed as it is written, heartbeats going on
                    summary = written if written is not None else summary
                else:
                    fh.write(orjson.dumps(document, option=orjson.OPT_SERIALIZE_NUMPY))
                fh.flush()
                os.fsync(fh.fileno())
            done.set()
            beater.join()
            if lost.is_set():
                raise LostClaim(f"job {job.id} was stopped")
            self.jobs.succeed_with_file(job.id, self.runner_id, tmp, summary)
        except LostClaim:
            log.warning("job %s was taken over by another runner or stopped; dropping this run", job.id)
            return True
        except InputError as exc:
            self._fail(job, {"title": "Invalid job request", "status": 422, "detail": str(exc),
                             "errors": [{"field": exc.field, "detail": exc.rule}]})
        except RcsaError as exc:
            status = getattr(exc, "http_status", 409)
            self._fail(job, {"title": getattr(exc, "title", "Job failed"), "status": status, "detail": str(exc)})
        except OSError as exc:
            log.exception("job %s: could not write its result", job.id)
            self._fail(job, {"title": "Job failed", "status": 507, "detail": "the job's result could not be "
                             f"written ({exc.strerror or exc}); the operator should check the store's disk"})
        except Exception:
            log.exception("job %s failed with an internal error", job.id)
            self._fail(job, {"title": "Internal error", "status": 500,
                             "detail": "the job failed with an internal error; the service log has the "
                                       f"traceback (job {job.id})"})
        finally:
            done.set()
            beater.join()
            with contextlib.suppress(OSError):
                tmp.unlink()
        elapsed = time.perf_counter() - t0
        with contextlib.suppress(NotFoundError):
            final = self.jobs.get(job.id)
            log.info("job %s %s in %.2f s", job.id, final.status, elapsed)
            if self.on_finish is not None:
                try:
                    self.on_finish(final, elapsed)
                except Exception:
                    log.exception("job %s: on_finish hook failed", job.id)
        return True

    def _time_out(self, job: Job) -> None:
        limit = self.time_limit_s
        log.warning("job %s ran past its time limit of %g s: failed", job.id, limit)
        self.jobs.fail(job.id, self.runner_id, {
            "title": "Job time limit exceeded", "status": 504,
            "detail": f"the job ran longer than its time limit of {limit:g} s and was stopped; split the work "
                      "into smaller jobs, or ask the operator to raise RCSA_JOB_TIME_LIMIT_S"})

    def _fail(self, job: Job, error: Mapping[str, Any]) -> None:
        with contextlib.suppress(LostClaim):
            self.jobs.fail(job.id, self.runner_id, error)

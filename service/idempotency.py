"""``Idempotency-Key`` on the POSTs that store or start something.

Follows the IETF draft draft-ietf-httpapi-idempotency-key-header-06. Routes of a
router built with ``route_class=IdempotentRoute`` honour the header on ``POST``:

* **First request** with a key: it runs; a ``2xx`` answer is kept (status, body bytes and the
  ``Content-Type``, ``Location``, ``Retry-After`` and ``Preference-Applied`` headers). Any
  other answer (a 4xx, a 5xx, an exception) is not kept and frees the key, so a corrected
  request may use it again.
* **Replay** (same key, same request): the kept answer, byte for byte, with
  ``Idempotent-Replayed: true`` — except while a job that the first answer started
  (``202`` with ``Location: /v1/jobs/{id}``) is still queued or running: then ``409``
  (``urn:rcsa:problem:idempotent-job-running``) with ``Location`` (the job) and
  ``Retry-After``.
* **Concurrent duplicate** (same key while the first request is still being answered):
  ``409`` (``urn:rcsa:problem:idempotent-request-in-progress``) with ``Retry-After``.
* **Same key, different request**: ``422`` naming the ``Idempotency-Key`` header
  (``urn:rcsa:problem:idempotency-key-reused``).
* A malformed key (empty, longer than 200 characters, anything but visible ASCII ``!``…``~``):
  ``400``. The key may be sent bare or as a structured-field string (``"..."``).
* **Crash consistency of effects.** A handler whose effect is a new stored object (a
  measurement upload) records the object's id with the key (:meth:`Reservation.record`,
  durable) *before* it writes the object under that id. If the process dies after the write
  but before the answer is kept, the retry takes the dead process's reservation over, finds
  the recorded id and answers with the object that was written: no second copy, nothing lost.

"Same request" means the same method, path, query, media type, ``Prefer`` and ``Accept`` headers
(the result's form) and body;
JSON bodies are compared after parsing (key order and spacing do not matter), multipart bodies
with the boundary taken out (a retry with a new boundary is the same request).

Keys are scoped per caller: the owner is the API key's id, and for anonymous callers the
client's network address (``anonymous@<address>``), so that anonymous callers never share
replays: one client's key cannot fetch another client's answer. (Behind a reverse proxy,
run uvicorn with ``--proxy-headers`` and ``--forwarded-allow-ips`` so that the address is the
client's; clients behind one NAT still share an address: they should use unguessable keys
such as UUIDs, or an API key.) Idempotent writes need a write key anyway; anonymous callers
reach only batches and library predictions, which are computations. The route class
(:class:`service.routing.ServiceRoute`) authenticates the caller *before* the body is read,
so a request refused for its key never has its body parsed or fingerprinted. Keys are kept in ``<store>/idempotency/keys.sqlite`` (WAL; shared by every service process,
kept across restarts) for ``RCSA_JOB_RETENTION_S`` (the same retention as finished jobs, 7
days by default), purged at startup and hourly. A reservation whose process died (same
host, pid gone) or that is older than 5 minutes is taken over by the next request.
Answers above 32 MiB are not kept (only pure computations answer that much; a replay
computes them again).

Which POSTs honour it: measurement uploads, batches (small ones answered at once as well as
jobs), library predictions and library syncs. ``POST /v1/tool-point-frf`` (one synchronous
prediction, stores nothing) and the analysis POSTs ignore the header: repeating them is
harmless.
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import os
import re
import secrets
import socket
import sqlite3
import threading
import time
from collections.abc import Awaitable, Callable
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import orjson
from fastapi import Header, Request
from fastapi.concurrency import run_in_threadpool
from starlette.responses import Response

from rcsa.errors import NotFoundError
from rcsa.infra.job_queue import runner_is_dead
from rcsa.infra.sqlite import connect as connect_sqlite
from rcsa.infra.sqlite import transaction

from .bodies import json_document
from .errors import PROBLEM_MEDIA_TYPE, ProblemError
from .jobs import job_document
from .routing import ServiceRoute, caller, is_json_media
from .state import ensure_state

__all__ = [
    "IDEMPOTENCY_PROBLEMS",
    "KEY_HEADER",
    "IdempotencyKeyHeader",
    "IdempotencyStore",
    "IdempotentRoute",
    "Reservation",
    "Stored",
    "parse_key",
    "reservation",
    "request_fingerprint",
    "store_for",
]

log = logging.getLogger("service.idempotency")

KEY_HEADER = "Idempotency-Key"
DIRECTORY = "idempotency"
MAX_KEY_LENGTH = 200
#: What a key may hold: visible ASCII (``!`` to ``~``), bare or as a quoted sf-string.
KEY_PATTERN = r'^(?:[!#-~][!-~]{0,199}|"[!-~]{1,200}")$'
_RELEASED = "released"
LEASE_S = 300.0
MAX_STORED_BYTES = 32 * 1024 * 1024
_PURGE_EVERY_S = 3600.0
_KEPT_HEADERS = ("content-type", "location", "retry-after", "preference-applied", "x-job-token")
_JOB_LOCATION = re.compile(r"^/v1/jobs/(j-[0-9a-f]{32})$")
_HOST = socket.gethostname()

_SCHEMA = """
CREATE TABLE IF NOT EXISTS idempotency (
    owner          TEXT NOT NULL,
    key            TEXT NOT NULL,
    fingerprint    TEXT NOT NULL,
    method         TEXT NOT NULL,
    path           TEXT NOT NULL,
    state          TEXT NOT NULL CHECK (state IN ('running', 'done')),
    holder         TEXT,
    created_unix   REAL NOT NULL,
    completed_unix REAL,
    status         INTEGER,
    headers        TEXT,
    body           BLOB,
    effect         TEXT,
    PRIMARY KEY (owner, key)
);
CREATE INDEX IF NOT EXISTS idempotency_age ON idempotency (created_unix);
"""

IdempotencyKeyHeader = Annotated[str | None, Header(
    alias=KEY_HEADER, max_length=MAX_KEY_LENGTH + 2, pattern=KEY_PATTERN,
    description="Any unique string of 1 to 200 visible ASCII characters (! to ~, e.g. a UUID), bare or quoted, "
                "for this request: a retry with the same key and request gets the first answer again instead of "
                "acting twice (a malformed key is a 400). Kept per API key (anonymous callers: per client address) "
                "for RCSA_JOB_RETENTION_S (7 days).",
    examples=["8e03978e-40d5-43e8-bc93-6894a57f9324"])]

#: OpenAPI ``responses`` entries of an idempotent route (merge after :func:`service.responses.problems`).
IDEMPOTENCY_PROBLEMS: dict[int | str, dict[str, Any]] = {
    400: {"description": "Malformed request, or a malformed Idempotency-Key.",
          "content": {PROBLEM_MEDIA_TYPE: {"schema": {"$ref": "#/components/schemas/Problem"}}}},
    409: {"description": "A request with this Idempotency-Key is still being answered, or the job it started "
                         "is still queued or running (Location: the job); retry after Retry-After.",
          "content": {PROBLEM_MEDIA_TYPE: {"schema": {"$ref": "#/components/schemas/Problem"}}}},
    422: {"description": "Invalid input (errors[] names each offending field), or an Idempotency-Key already "
                         "used for a different request.",
          "content": {PROBLEM_MEDIA_TYPE: {"schema": {"$ref": "#/components/schemas/Problem"}}}},
}


def parse_key(raw: str) -> str:
    """The key of an ``Idempotency-Key`` header value (bare or a quoted sf-string).

    Raises
    ------
    ProblemError
        400 when the key is empty, too long or not printable ASCII.
    """
    key = raw.strip()
    if len(key) >= 2 and key[0] == key[-1] == '"':
        key = key[1:-1].replace('\\"', '"').replace("\\\\", "\\")
    if not key or len(key) > MAX_KEY_LENGTH or any(not (33 <= ord(c) < 127) for c in key):
        raise ProblemError(400, f"the {KEY_HEADER} header must be 1 to {MAX_KEY_LENGTH} visible ASCII characters "
                                "(! to ~, no spaces; e.g. a UUID)", slug="invalid-idempotency-key",
                           errors=[{"field": KEY_HEADER,
                                    "detail": f"1 to {MAX_KEY_LENGTH} visible ASCII characters"}])
    return key


def _boundary(content_type: str) -> bytes | None:
    for param in content_type.split(";")[1:]:
        name, _, value = param.strip().partition("=")
        if name.strip().lower() == "boundary" and value:
            return value.strip().strip('"').encode("latin-1")
    return None


async def request_fingerprint(request: Request) -> str:
    """SHA-256 of what makes two requests "the same" (see the module docstring)."""
    body = await request.body()
    ctype = request.headers.get("content-type", "")
    media = ctype.split(";")[0].strip().lower()
    if is_json_media(media):  # decoded once, under the JSON policy, by the route class
        body = b"json:" + orjson.dumps(await json_document(request), option=orjson.OPT_SORT_KEYS)
    elif media == "multipart/form-data":
        boundary = _boundary(ctype)
        if boundary:
            body = body.replace(b"--" + boundary, b"--")
    digest = hashlib.sha256()
    query = sorted((k, v) for k, v in request.query_params.multi_items())
    for part in (request.method, request.url.path, orjson.dumps(query).decode(), media,
                 request.headers.get("prefer", ""), request.headers.get("accept", "")):
        data = part.encode()
        digest.update(len(data).to_bytes(8, "big") + data)
    digest.update(body)
    return digest.hexdigest()


@dataclass(frozen=True, slots=True)
class Stored:
    """A kept answer.

    Attributes
    ----------
    status : int
    headers : dict of str to str
        The kept headers (lower-case names).
    body : bytes
    """

    status: int
    headers: dict[str, str]
    body: bytes


class IdempotencyStore:
    """Keys and kept answers in SQLite; safe across processes and restarts.

    Parameters
    ----------
    directory : str or os.PathLike
        Normally ``<store>/idempotency``; created on first use.
    retention_s : float
        Keys older than this are forgotten, s.
    lease_s : float
        A reservation older than this (its request never finished) may be taken over, s.
    """

    def __init__(self, directory: str | os.PathLike[str], *, retention_s: float, lease_s: float = LEASE_S) -> None:
        self.directory = Path(directory)
        self.retention_s = float(retention_s)
        self.lease_s = float(lease_s)
        self.directory.mkdir(parents=True, exist_ok=True)
        with closing(self._connect()) as con:
            con.executescript(_SCHEMA)
            columns = {row[1] for row in con.execute("PRAGMA table_info(idempotency)")}
            if "effect" not in columns:  # a store written by an older rcsa
                with contextlib.suppress(sqlite3.OperationalError):  # another process added it first
                    con.execute("ALTER TABLE idempotency ADD COLUMN effect TEXT")
        self._next_purge = 0.0
        self._maybe_purge()

    def _connect(self) -> sqlite3.Connection:
        # FULL: a kept answer is what stops a retried upload or batch from acting twice
        return connect_sqlite(self.directory / "keys.sqlite", synchronous="FULL", timeout_s=30.0)

    def _maybe_purge(self) -> None:
        now = time.monotonic()
        if now >= self._next_purge:
            self._next_purge = now + _PURGE_EVERY_S
            try:
                n = self.purge()
                if n:
                    log.info("forgot %d idempotency keys older than %g s", n, self.retention_s)
            except sqlite3.Error:
                log.exception("could not purge old idempotency keys")

    def purge(self) -> int:
        """Forget keys older than the retention period; return how many."""
        with closing(self._connect()) as con:
            cur = con.execute("DELETE FROM idempotency WHERE created_unix < ?", (time.time() - self.retention_s,))
        return cur.rowcount

    def begin(self, owner: str, key: str, fingerprint: str, method: str, path: str
              ) -> tuple[str, Stored | str | None]:
        """Reserve a key for a request, or say why not.

        Returns
        -------
        ("new", holder) : the caller answers the request, then :meth:`complete` or :meth:`release`
        ("replay", Stored) : the kept answer
        ("running", None) : the first request with this key is still being answered
        ("mismatch", None) : the key was used for a different request
        """
        self._maybe_purge()
        holder = f"{_HOST}:{os.getpid()}:{secrets.token_hex(4)}"
        now = time.time()
        with closing(self._connect()) as con, transaction(con):
            row = con.execute("SELECT fingerprint, state, holder, created_unix, status, headers, body FROM "
                              "idempotency WHERE owner = ? AND key = ?", (owner, key)).fetchone()
            if row is not None and now - row[3] > self.retention_s:
                row = None  # expired but not purged yet: a fresh key
            if row is None:
                con.execute("INSERT OR REPLACE INTO idempotency (owner, key, fingerprint, method, path, state, "
                            "holder, created_unix) VALUES (?, ?, ?, ?, ?, 'running', ?, ?)",
                            (owner, key, fingerprint, method, path, holder, now))
                outcome: tuple[str, Stored | str | None] = ("new", holder)
            elif row[0] != fingerprint:
                outcome = ("mismatch", None)
            elif row[1] == "done":
                outcome = ("replay", Stored(int(row[4]), orjson.loads(row[5]), bytes(row[6])))
            elif now - row[3] > self.lease_s or row[2] in (None, _RELEASED) or runner_is_dead(row[2]):
                con.execute("UPDATE idempotency SET holder = ?, created_unix = ? WHERE owner = ? AND key = ?",
                            (holder, now, owner, key))
                outcome = ("new", holder)
            else:
                outcome = ("running", None)
        return outcome

    def complete(self, owner: str, key: str, holder: str, answer: Stored) -> bool:
        """Keep the answer of a reserved key; False if the reservation was lost."""
        with closing(self._connect()) as con:
            cur = con.execute("UPDATE idempotency SET state = 'done', holder = NULL, completed_unix = ?, status = ?, "
                              "headers = ?, body = ? WHERE owner = ? AND key = ? AND holder = ? AND state = 'running'",
                              (time.time(), answer.status, orjson.dumps(answer.headers), answer.body, owner, key,
                               holder))
        return cur.rowcount == 1

    def release(self, owner: str, key: str, holder: str) -> None:
        """Free a reserved key (its request was not answered with a kept answer).

        A reservation that recorded an effect (:meth:`record_effect`) is kept, released to
        the next request with the same key, which then finds that effect: the effect may
        have been committed before the failure.
        """
        with closing(self._connect()) as con, transaction(con):
            con.execute("DELETE FROM idempotency WHERE owner = ? AND key = ? AND holder = ? AND state = 'running' "
                        "AND effect IS NULL", (owner, key, holder))
            con.execute("UPDATE idempotency SET holder = ? WHERE owner = ? AND key = ? AND holder = ? "
                        "AND state = 'running'", (_RELEASED, owner, key, holder))

    def record_effect(self, owner: str, key: str, holder: str, effect: str) -> bool:
        """Durably note, before acting, what the reserved request is about to create (an id).

        Returns False when the reservation was lost (taken over): the caller must not act.
        """
        with closing(self._connect()) as con:
            cur = con.execute("UPDATE idempotency SET effect = ? WHERE owner = ? AND key = ? AND holder = ? "
                              "AND state = 'running'", (effect, owner, key, holder))
        return cur.rowcount == 1

    def effect_of(self, owner: str, key: str) -> str | None:
        """The effect recorded for a key (by an earlier, interrupted attempt), if any."""
        with closing(self._connect()) as con:
            row = con.execute("SELECT effect FROM idempotency WHERE owner = ? AND key = ?", (owner, key)).fetchone()
        return None if row is None else row[0]


@dataclass(frozen=True, slots=True)
class Reservation:
    """The key a request runs under, for handlers whose effect must be crash-consistent.

    Attributes
    ----------
    effect : str or None
        What an earlier, interrupted attempt of the same request recorded it would create
        (e.g. a measurement id); the handler must look for it before creating anything.
    """

    store: IdempotencyStore
    owner: str
    key: str
    holder: str
    effect: str | None

    def record(self, effect: str) -> None:
        """Durably record the effect before acting (raises if the reservation was lost)."""
        if not self.store.record_effect(self.owner, self.key, self.holder, effect):
            raise ProblemError(409, f"the reservation of this {KEY_HEADER} was taken over by a retry; retry after "
                                    "Retry-After to get its answer", slug="idempotent-request-in-progress",
                               title="Request in progress", headers={"Retry-After": "1"})


def reservation(request: Request) -> Reservation | None:
    """The request's :class:`Reservation` (None without a key, or for anonymous callers)."""
    found = getattr(request.state, "idempotency", None)
    return found if isinstance(found, Reservation) else None


_STORES: dict[str, IdempotencyStore] = {}
_STORES_LOCK = threading.Lock()


def store_for(state: Any) -> IdempotencyStore:
    """The key store of a service's store directory (one per process and directory)."""
    directory = Path(state.store.path) / DIRECTORY
    retention = float(getattr(state.settings, "idempotency_retention_s", None) or state.settings.job_retention_s)
    with _STORES_LOCK:
        found = _STORES.get(str(directory))
        if found is None or found.retention_s != retention or not directory.is_dir():
            found = _STORES[str(directory)] = IdempotencyStore(directory, retention_s=retention)
        return found


def _owner(request: Request, state: Any) -> str | None:
    """The key id of the caller, ``anonymous@<client address>`` without a key; None for an
    unknown key (the route refuses it)."""
    who = caller(request)
    if who is None:  # a route without access checks: authenticate here
        api_key = request.headers.get("x-api-key")
        if api_key:
            who = state.keys.authenticate(api_key)
            if who is None:
                return None
    if who is None or who.scope is None:
        client = request.client.host if request.client is not None else "unknown"
        return f"anonymous@{client}"
    return str(who.key_id)


def _replayed(stored: Stored) -> Response:
    headers = {k: v for k, v in stored.headers.items() if k != "content-type"}
    headers["Idempotent-Replayed"] = "true"
    return Response(stored.body, status_code=stored.status, media_type=stored.headers.get("content-type"),
                    headers=headers)


def _running_job(stored: Stored, state: Any) -> Any:
    """The job a kept ``202`` answer started, if it is still queued or running."""
    if stored.status != 202:
        return None
    match = _JOB_LOCATION.match(stored.headers.get("location", ""))
    if match is None:
        return None
    try:
        job = state.jobs.get(match.group(1))
    except NotFoundError:
        return None
    return None if job.finished else job


async def run_idempotent(request: Request, raw_key: str, handler: Callable[[Request], Awaitable[Response]]
                         ) -> Response:
    """Answer ``request`` under its ``Idempotency-Key`` (see the module docstring)."""
    key = parse_key(raw_key)
    state = await run_in_threadpool(ensure_state, request.app)
    owner = _owner(request, state)
    if owner is None:  # an unknown key, which the route refuses: nothing is kept
        return await handler(request)
    fingerprint = await request_fingerprint(request)
    store = await run_in_threadpool(store_for, state)
    kind, found = await run_in_threadpool(store.begin, owner, key, fingerprint, request.method, request.url.path)
    retry = str(state.settings.retry_after_s)
    if kind == "mismatch":
        raise ProblemError(422, f"this {KEY_HEADER} was already used for a different request (another body, path "
                                "or query); send a new key for a new request", slug="idempotency-key-reused",
                           title="Idempotency key reused",
                           errors=[{"field": KEY_HEADER, "detail": "already used for a different request"}])
    if kind == "running":
        raise ProblemError(409, f"a request with this {KEY_HEADER} is still being answered; retry after "
                                f"{retry} s to get its answer", slug="idempotent-request-in-progress",
                           title="Request in progress", headers={"Retry-After": retry})
    if kind == "replay":
        assert isinstance(found, Stored)
        job = await run_in_threadpool(_running_job, found, state)
        if job is not None:
            raise ProblemError(409, f"the job {job.id} started by the request with this {KEY_HEADER} is still "
                                    f"{job.status} ({job.progress:.0%} done); poll /v1/jobs/{job.id}, or retry "
                                    "after Retry-After to get the first answer", slug="idempotent-job-running",
                               title="Job still running", headers={"Retry-After": retry,
                                                                   "Location": f"/v1/jobs/{job.id}"},
                               extra={"job": job_document(job)})
        return _replayed(found)
    holder = str(found)
    effect = await run_in_threadpool(store.effect_of, owner, key)
    request.state.idempotency = Reservation(store, owner, key, holder, effect)
    try:
        response = await handler(request)
    except BaseException:
        await run_in_threadpool(store.release, owner, key, holder)
        raise
    body = getattr(response, "body", None)
    if 200 <= response.status_code < 300 and isinstance(body, bytes) and len(body) <= MAX_STORED_BYTES:
        kept = Stored(response.status_code, {k: response.headers[k] for k in _KEPT_HEADERS if k in response.headers},
                      body)
        try:
            if not await run_in_threadpool(store.complete, owner, key, holder, kept):
                log.warning("the reservation of an idempotency key was taken over before its answer was kept")
        except sqlite3.Error:
            log.exception("could not keep the answer of an idempotent request")
    else:
        await run_in_threadpool(store.release, owner, key, holder)
    return response


class IdempotentRoute(ServiceRoute):
    """A route that honours ``Idempotency-Key`` on ``POST`` (see the module docstring)."""

    def wrap_handler(self, handler: Callable[[Request], Awaitable[Response]]
                     ) -> Callable[[Request], Awaitable[Response]]:
        """The route's handler, wrapped for ``POST`` (after the checks of ServiceRoute)."""
        if "POST" not in (self.methods or set()):
            return handler

        async def idempotent_handler(request: Request) -> Response:
            raw = request.headers.get(KEY_HEADER)
            if raw is None:
                return await handler(request)
            return await run_idempotent(request, raw, handler)

        return idempotent_handler

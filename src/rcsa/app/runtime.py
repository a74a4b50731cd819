"""Plumbing a long-running process shares with the library: SQLite and process liveness.

The REST service keeps one database of its own (the ``Idempotency-Key`` answers) next to the
job queue; it opens it as every rcsa database is opened (:mod:`rcsa.infra.sqlite`: WAL,
busy timeout, explicit transactions) and recognises a dead holder as the job queue does.
"""

from __future__ import annotations

from rcsa.infra.job_queue import runner_is_dead
from rcsa.infra.sqlite import connect as connect_sqlite
from rcsa.infra.sqlite import transaction

__all__ = ["connect_sqlite", "runner_is_dead", "transaction"]

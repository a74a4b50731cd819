"""One way to open the project's SQLite databases, and one transaction helper.

Five databases live in a store directory, each opened by a short-lived connection per
call (nothing is shared across threads or ``fork``), all in WAL mode so that readers never
wait for a writer and several processes may share a file:

=============================  ==============  ==============================================
database                       ``synchronous``  why
=============================  ==============  ==============================================
``jobs/jobs.sqlite``           ``FULL``        a queued job was acknowledged (``202``); a
                                               power cut must not lose it or its result row
``libraries/index.sqlite``     ``FULL``        a sync commits a revision its caller was told
                                               about (the sync report)
``libraries/results/…sqlite``  ``FULL``        computed results (a chunk per transaction): a
                                               library commit references them once written
``idempotency/keys.sqlite``    ``FULL``        a kept answer is what stops a retried upload
                                               or batch from acting twice
``index.sqlite`` (catalogue)   ``NORMAL``      a cache of the measurement files' metadata,
                                               rebuilt from the (fsynced) files on demand
=============================  ==============  ==============================================

In WAL mode ``NORMAL`` never corrupts the database, but the last transactions before a power
loss may roll back; ``FULL`` syncs the log at every commit, so a commit that returned is
durable.

Connections use autocommit (``isolation_level=None``): a statement outside
:func:`transaction` commits on its own, and a transaction is always explicit.
"""

from __future__ import annotations

import os
import sqlite3
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Literal

__all__ = ["Synchronous", "connect", "transaction"]

#: ``PRAGMA synchronous`` levels used here (see the table in the module docstring).
Synchronous = Literal["FULL", "NORMAL"]


def connect(path: str | os.PathLike[str], *, synchronous: Synchronous = "FULL", timeout_s: float = 30.0,
            schema: str | None = None) -> sqlite3.Connection:
    """Open a connection in WAL mode, autocommit, waiting up to ``timeout_s`` for a lock.

    Parameters
    ----------
    path : str or os.PathLike
        The database file (created if missing; its directory must exist).
    synchronous : {"FULL", "NORMAL"}
        ``FULL`` for anything that records acknowledged work, ``NORMAL`` for rebuildable
        caches (see the module docstring).
    timeout_s : float
        How long a statement waits for another connection's write lock before
        ``sqlite3.OperationalError: database is locked``, s.
    schema : str, optional
        SQL script run on every connection (``CREATE ... IF NOT EXISTS``), for databases that
        may be deleted at any time and must come back by themselves.

    Returns
    -------
    sqlite3.Connection
        The caller closes it (``with contextlib.closing(connect(...)) as con``).
    """
    if synchronous not in ("FULL", "NORMAL"):
        raise ValueError(f"synchronous must be FULL or NORMAL, got {synchronous!r}")
    con = sqlite3.connect(path, timeout=timeout_s, isolation_level=None)
    try:
        con.execute("PRAGMA journal_mode=WAL")
        con.execute(f"PRAGMA synchronous={synchronous}")
        if schema is not None:
            con.executescript(schema)
    except BaseException:
        con.close()
        raise
    return con


@contextmanager
def transaction(con: sqlite3.Connection, *, immediate: bool = True) -> Iterator[sqlite3.Connection]:
    """Run the block in one transaction: commit at its end, roll back if it raises.

    Parameters
    ----------
    con : sqlite3.Connection
        An autocommit connection from :func:`connect`.
    immediate : bool
        ``BEGIN IMMEDIATE`` (take the write lock at once: read-then-write blocks never
        interleave with another writer) or a plain ``BEGIN`` (a consistent snapshot for reads).
    """
    con.execute("BEGIN IMMEDIATE" if immediate else "BEGIN")
    try:
        yield con
    except BaseException:
        if con.in_transaction:  # SQLite may already have rolled back (e.g. on SQLITE_FULL)
            con.execute("ROLLBACK")
        raise
    con.execute("COMMIT")

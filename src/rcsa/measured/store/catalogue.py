"""A rebuildable SQLite catalogue of the measurement files (metadata only).

The files under ``measurements/`` are the truth. The catalogue only saves opening every
file to list the store: each :meth:`MeasurementStore.list` compares it with a directory
listing, adds rows for files it does not know (reading their attributes) and drops rows
whose file is gone. A crash between a file's rename and its row insert, a lost or corrupt
``index.sqlite``, or a read-only store directory therefore never lose a measurement; the
catalogue is repaired (or bypassed) on the next listing.

SQLite in WAL mode is safe for several processes; every call opens its own short-lived
connection (nothing is shared across ``fork``).
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Iterable, Mapping
from contextlib import closing
from pathlib import Path

from rcsa.infra.sqlite import connect, transaction
from rcsa.measured.store.measurement import MeasurementInfo

__all__ = ["Catalogue"]

_SCHEMA = """
CREATE TABLE IF NOT EXISTS measurements (
    id TEXT PRIMARY KEY,
    spindle_id TEXT NOT NULL,
    machine TEXT NOT NULL,
    direction TEXT NOT NULL,
    plane TEXT NOT NULL,
    kind TEXT NOT NULL,
    created_utc TEXT NOT NULL,
    info_json TEXT NOT NULL
);
CREATE INDEX IF NOT EXISTS measurements_spindle ON measurements (spindle_id);
"""
FILTERS = ("spindle_id", "machine", "direction", "plane", "kind")
#: Seconds a connection waits for another process's write transaction.
_BUSY_TIMEOUT_S = 30.0


class Catalogue:
    """SQLite index of measurement metadata at ``db_path`` (created on first use)."""

    def __init__(self, db_path: Path) -> None:
        self.db_path = Path(db_path)

    def _connect(self) -> sqlite3.Connection:
        # NORMAL: a rebuildable cache of the (fsynced) files; the schema on every connection,
        # since the index may be deleted at any time
        return connect(self.db_path, synchronous="NORMAL", timeout_s=_BUSY_TIMEOUT_S, schema=_SCHEMA)

    def ids(self) -> set[str]:
        """Every id with a row."""
        with closing(self._connect()) as con:
            return {r[0] for r in con.execute("SELECT id FROM measurements")}

    def add(self, infos: Iterable[MeasurementInfo]) -> None:
        """Insert (or replace) rows, in one transaction."""
        rows = [
            (
                i.id,
                i.meta.spindle_id,
                i.meta.machine,
                i.meta.direction,
                i.meta.plane,
                i.meta.kind,
                i.created_utc or "",
                json.dumps(i.to_dict()),
            )
            for i in infos
        ]
        if not rows:
            return
        with closing(self._connect()) as con, transaction(con):
            con.executemany(
                "INSERT OR REPLACE INTO measurements VALUES (?, ?, ?, ?, ?, ?, ?, ?)", rows
            )

    def remove(self, ids: Iterable[str]) -> None:
        """Drop the rows of ``ids`` (missing ones are ignored)."""
        rows = [(i,) for i in ids]
        if not rows:
            return
        with closing(self._connect()) as con, transaction(con):
            con.executemany("DELETE FROM measurements WHERE id = ?", rows)

    def query(self, filters: Mapping[str, str | None]) -> list[MeasurementInfo]:
        """Rows matching every non-None filter (keys from :data:`FILTERS`), oldest first."""
        where, args = [], []
        for key, value in filters.items():
            if key not in FILTERS:
                raise ValueError(f"unknown filter {key!r}")
            if value is not None:
                where.append(f"{key} = ?")
                args.append(value)
        sql = "SELECT info_json FROM measurements"
        if where:
            sql += " WHERE " + " AND ".join(where)
        sql += " ORDER BY created_utc, id"
        with closing(self._connect()) as con:
            return [MeasurementInfo.from_dict(json.loads(r[0])) for r in con.execute(sql, args)]

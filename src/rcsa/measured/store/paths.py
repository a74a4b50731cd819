"""Where the store lives on disk, and measurement ids.

Layout of a store directory (every name below is relative to the store root)::

    rcsa-store.json         marker: {"schema": "rcsa.store", "schema_version": 1, ...}
    .write.lock             filelock.FileLock serialising writers (put, delete, cleanup)
    index.sqlite            catalogue cache (WAL); rebuilt from the files whenever needed
    measurements/<id>.h5    one immutable HDF5 file per measurement: the truth
    deleted/<id>            empty tombstones, so that an id is never handed out twice
    tmp/                    in-flight writes and deletes; stale once the lock is free
"""

from __future__ import annotations

import os
import re
import secrets
from pathlib import Path

__all__ = [
    "ID_PATTERN",
    "default_store_path",
    "is_measurement_id",
    "new_measurement_id",
]

#: Measurement ids: ``m-`` and 12 lowercase hex digits (48 random bits), URL- and file-safe.
ID_PATTERN = re.compile(r"^m-[0-9a-f]{12}$")

MARKER = "rcsa-store.json"
LOCK = ".write.lock"
INDEX = "index.sqlite"
MEASUREMENTS = "measurements"
DELETED = "deleted"
TMP = "tmp"
#: Neighbours kept in the store directory by the service: the job store and the API-key hashes.
JOBS = "jobs"
KEYS = "api-keys.json"
#: Names a store root may contain (anything else means the directory is not ours).
OWN_NAMES = frozenset(
    {
        MARKER,
        LOCK,
        INDEX,
        INDEX + "-wal",
        INDEX + "-shm",
        INDEX + "-journal",
        MEASUREMENTS,
        DELETED,
        TMP,
        JOBS,
        KEYS,
        "libraries", "idempotency",  # rcsa.libraries.sync.DIRECTORY, service.idempotency (issue 8)
    }
)


def default_store_path() -> Path:
    """Store location used when none is given.

    ``$RCSA_STORE`` if set and non-empty, else ``$XDG_DATA_HOME/rcsa/store``, else
    ``~/.local/share/rcsa/store``. The directory is created on first use by
    :class:`~rcsa.measured.store.MeasurementStore`, not here.

    Returns
    -------
    pathlib.Path
    """
    env = os.environ.get("RCSA_STORE", "").strip()
    if env:
        return Path(env).expanduser()
    xdg = os.environ.get("XDG_DATA_HOME", "").strip()
    base = Path(xdg).expanduser() if xdg else Path.home() / ".local" / "share"
    return base / "rcsa" / "store"


def new_measurement_id() -> str:
    """A fresh random id (uniqueness against the store is checked by the writer)."""
    return "m-" + secrets.token_hex(6)


def is_measurement_id(text: object) -> bool:
    """Whether ``text`` has the shape of a measurement id (never a path)."""
    return isinstance(text, str) and ID_PATTERN.match(text) is not None

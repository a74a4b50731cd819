"""``MeasurementStore``: a directory of immutable per-measurement HDF5 files.

Safety model (``docs/architecture.md`` "Durable storage"):

* **One file per measurement, never modified.** ``put`` writes ``tmp/<id>.h5.tmp``, closes
  and fsyncs it, ``os.replace``-s it to ``measurements/<id>.h5`` and fsyncs the directory.
  A reader lists and opens only final names, so it never sees a half-written file; a
  writer killed at any moment leaves at worst a stale file in ``tmp/``.
* **Writers are serialised** by a ``filelock.FileLock`` on ``.write.lock`` (an ``flock``
  the kernel releases when a process dies). Under it a writer reserves an id that is
  neither live nor tombstoned, and removes whatever ``tmp/`` holds (stale by definition,
  since every writer works under the lock).
* **Delete is atomic**: under the lock, write the tombstone ``deleted/<id>`` (ids are never
  reused), rename the file into ``tmp/``, fsync, then unlink it.
* **Reads take no lock.** Files are immutable, so several processes read at once; a file
  deleted after being listed gives :class:`~rcsa.errors.NotFoundError`.
* The catalogue (``index.sqlite``) is a cache; see :mod:`rcsa.measured.store.catalogue`.
"""

from __future__ import annotations

import builtins
import contextlib
import json
import os
import sqlite3
from collections.abc import Iterator
from pathlib import Path

import filelock

from rcsa._version import __version__
from rcsa.errors import ConflictError, DamagedError, NotFoundError, StoreError
from rcsa.infra.atomic_files import fsync_dir as _fsync_dir
from rcsa.infra.atomic_files import fsync_file
from rcsa.infra.clock import utc_now_iso
from rcsa.measured.store import paths as P
from rcsa.measured.store.catalogue import Catalogue
from rcsa.measured.store.hdf5io import read_info_file, read_measurement_file, write_measurement_file
from rcsa.measured.store.measurement import Measurement, MeasurementInfo
from rcsa.measured.store.schema import SCHEMA_VERSION, STORE_SCHEMA, SUPPORTED_VERSIONS

__all__ = ["MeasurementStore"]

#: Attempts at drawing a fresh id; 48 random bits make even a second attempt unlikely.
_ID_ATTEMPTS = 100



class MeasurementStore:
    """Measured spindle FRFs on disk; safe for several processes and for crashes.

    Parameters
    ----------
    path : str or os.PathLike, optional
        Store directory; default :func:`~rcsa.measured.store.default_store_path`. Created (with its
        marker file) on first use. An existing non-empty directory that is not an rcsa store
        is refused, so a mistyped path never scatters files.
    lock_timeout_s : float
        How long a writer waits for another writer, s; then :class:`StoreError`.
    """

    def __init__(
        self, path: str | os.PathLike[str] | None = None, *, lock_timeout_s: float = 60.0
    ) -> None:
        self.path = Path(path).expanduser() if path is not None else P.default_store_path()
        self.lock_timeout_s = float(lock_timeout_s)
        self._measurements = self.path / P.MEASUREMENTS
        self._deleted = self.path / P.DELETED
        self._tmp = self.path / P.TMP
        self._catalogue = Catalogue(self.path / P.INDEX)
        self._open_or_create()

    def __repr__(self) -> str:
        return f"MeasurementStore({str(self.path)!r})"

    # ------------------------------------------------------------------ layout
    def _open_or_create(self) -> None:
        marker = self.path / P.MARKER
        if marker.is_file():
            self._check_marker(marker)
            return
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise StoreError(
                f"cannot create the store directory {self.path}: {e.strerror}"
            ) from None
        if not self.path.is_dir():
            raise StoreError(f"{self.path} is not a directory")
        foreign = sorted(
            n for n in os.listdir(self.path) if n not in P.OWN_NAMES and not n.startswith(".")
        )
        if foreign:
            raise StoreError(
                f"{self.path} is not an rcsa store (no {P.MARKER}) and is not empty "
                f"(e.g. {foreign[0]!r}); choose an empty or new directory"
            )
        with self._lock():
            if not marker.is_file():
                for d in (self._measurements, self._deleted, self._tmp):
                    d.mkdir(exist_ok=True)
                doc = {
                    "schema": STORE_SCHEMA,
                    "schema_version": SCHEMA_VERSION,
                    "created_utc": utc_now_iso(),
                }
                tmp = self._tmp / (P.MARKER + ".tmp")
                tmp.write_text(json.dumps(doc) + "\n", encoding="utf-8")
                fsync_file(tmp)
                os.replace(tmp, marker)
                _fsync_dir(self.path)
        self._check_marker(marker)

    def _check_marker(self, marker: Path) -> None:
        try:
            doc = json.loads(marker.read_text(encoding="utf-8"))
        except (OSError, ValueError) as e:
            raise StoreError(f"{marker}: unreadable store marker ({e})") from None
        if not isinstance(doc, dict) or doc.get("schema") != STORE_SCHEMA:
            raise StoreError(
                f"{marker}: foreign store schema {doc.get('schema') if isinstance(doc, dict) else doc!r}"
            )
        if doc.get("schema_version") not in SUPPORTED_VERSIONS:
            raise StoreError(
                f"{marker}: store schema version {doc.get('schema_version')!r} is not supported "
                f"by this rcsa (reads {sorted(SUPPORTED_VERSIONS)}); upgrade rcsa"
            )
        for d in (self._measurements, self._deleted, self._tmp):
            d.mkdir(exist_ok=True)

    @contextlib.contextmanager
    def _lock(self) -> Iterator[None]:
        """Hold the store's writer lock (a new ``flock`` each time, so threads exclude too)."""
        lock = filelock.FileLock(str(self.path / P.LOCK), timeout=self.lock_timeout_s)
        try:
            lock.acquire()
        except filelock.Timeout:
            raise StoreError(
                f"another process has held the write lock of {self.path} for "
                f"{self.lock_timeout_s:g} s; try again"
            ) from None
        try:
            yield
        finally:
            lock.release()

    def _file(self, measurement_id: str) -> Path:
        return self._measurements / f"{measurement_id}.h5"

    def _ids_on_disk(self) -> set[str]:
        with os.scandir(self._measurements) as it:
            names = [e.name for e in it]
        return {n[:-3] for n in names if n.endswith(".h5") and P.is_measurement_id(n[:-3])}

    def _clean_tmp(self) -> int:
        """Remove everything in ``tmp/``; call only while holding the writer lock."""
        n = 0
        with os.scandir(self._tmp) as it:
            for e in it:
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(e.path)
                    n += 1
        return n

    # ------------------------------------------------------------------ API
    def new_id(self) -> str:
        """A fresh measurement id, neither live nor deleted (for :meth:`put` with an id chosen
        beforehand, e.g. recorded with an idempotency key before the write)."""
        for _ in range(_ID_ATTEMPTS):
            mid = P.new_measurement_id()
            if not self._file(mid).exists() and not (self._deleted / mid).exists():
                return mid
        raise StoreError("could not draw a fresh measurement id")  # pragma: no cover - 2**48 ids

    def was_deleted(self, measurement_id: str) -> bool:
        """Whether ``measurement_id`` was stored once and deleted since (its tombstone)."""
        return P.is_measurement_id(measurement_id) and (self._deleted / measurement_id).exists()

    def put(self, measurement: Measurement, *, measurement_id: str | None = None) -> str:
        """Store ``measurement`` and return its new id (``m-`` + 12 hex digits).

        When this returns, the file is on stable storage under its final name.

        Parameters
        ----------
        measurement : Measurement
        measurement_id : str, optional
            The id to store it under (from :meth:`new_id`); default a fresh one.

        Raises
        ------
        ConflictError
            ``measurement_id`` is already stored, or was deleted (ids are never reused).
        """
        if not isinstance(measurement, Measurement):
            raise TypeError("put() takes an rcsa.measured.store.Measurement")
        if measurement_id is not None and not P.is_measurement_id(measurement_id):
            raise StoreError(f"internal: {measurement_id!r} is not a measurement id")
        with self._lock():
            self._clean_tmp()
            if measurement_id is None:
                mid = self.new_id()
            else:
                mid = measurement_id
                if self._file(mid).exists():
                    raise ConflictError("measurement", mid, "is already stored")
                if (self._deleted / mid).exists():
                    raise ConflictError("measurement", mid, "was deleted; its id is never reused")
            stored = Measurement(
                frequency_hz=measurement.frequency_hz,
                frfs=measurement.frfs,
                meta=measurement.meta,
                provenance=measurement.provenance,
                coherence=measurement.coherence,
                id=mid,
                created_utc=utc_now_iso(),
                software_version=__version__,
            )
            tmp = self._tmp / f"{mid}.h5.tmp"
            try:
                write_measurement_file(tmp, stored)
                os.replace(tmp, self._file(mid))
                _fsync_dir(self._measurements)
            except OSError as e:
                with contextlib.suppress(OSError):
                    tmp.unlink()
                raise StoreError(f"could not write measurement to {self.path}: {e}") from None
        with contextlib.suppress(sqlite3.Error, OSError):  # a cache: list() repairs it
            self._catalogue.add([stored.info()])
        return mid

    def get(self, measurement_id: str) -> Measurement:
        """The stored measurement ``measurement_id`` (immutable, read-only arrays).

        Raises
        ------
        NotFoundError
            No such measurement (or a string that is not an id).
        StoreError
            The file exists but is unreadable or of a foreign/newer schema.
        """
        if not P.is_measurement_id(measurement_id):
            raise NotFoundError("measurement", str(measurement_id))
        try:
            return read_measurement_file(self._file(measurement_id))
        except FileNotFoundError:
            raise NotFoundError("measurement", measurement_id) from None
        except StoreError as exc:  # this one file: retrying does not help
            raise DamagedError("measurement", measurement_id, str(exc)) from None

    def info(self, measurement_id: str) -> MeasurementInfo:
        """Metadata of one measurement, without reading its arrays."""
        if not P.is_measurement_id(measurement_id):
            raise NotFoundError("measurement", str(measurement_id))
        try:
            return read_info_file(self._file(measurement_id))
        except FileNotFoundError:
            raise NotFoundError("measurement", measurement_id) from None
        except StoreError as exc:
            raise DamagedError("measurement", measurement_id, str(exc)) from None

    def file_identity(self, measurement_id: str) -> tuple[int, int, int] | None:
        """``(inode, size, mtime in ns)`` of a measurement's file, None when there is none.

        A cache keyed by it notices a file replaced, rewritten or damaged in place (any
        write changes the modification time) with one ``stat``.
        """
        if not P.is_measurement_id(measurement_id):
            return None
        try:
            st = os.stat(self._file(measurement_id))
        except OSError:
            return None
        return st.st_ino, st.st_size, st.st_mtime_ns

    def __contains__(self, measurement_id: object) -> bool:
        return P.is_measurement_id(measurement_id) and self._file(str(measurement_id)).is_file()

    def delete(self, measurement_id: str) -> None:
        """Remove a measurement atomically; its id is never handed out again."""
        if not P.is_measurement_id(measurement_id):
            raise NotFoundError("measurement", str(measurement_id))
        with self._lock():
            final = self._file(measurement_id)
            if not final.is_file():
                raise NotFoundError("measurement", measurement_id)
            tomb = self._deleted / measurement_id
            tomb.touch()
            _fsync_dir(self._deleted)
            trash = self._tmp / f"{measurement_id}.deleting"
            os.replace(final, trash)
            _fsync_dir(self._measurements)
            trash.unlink()
        with contextlib.suppress(sqlite3.Error, OSError):
            self._catalogue.remove([measurement_id])

    def list(
        self,
        spindle_id: str | None = None,
        *,
        machine: str | None = None,
        direction: str | None = None,
        plane: str | None = None,
        kind: str | None = None,
    ) -> builtins.list[MeasurementInfo]:
        """Metadata of the stored measurements matching every given filter, oldest first.

        Cheap: reads the catalogue, opening only files it does not know yet. Files that
        cannot be read are left out (see :meth:`check`).
        """
        filters = {
            "spindle_id": spindle_id,
            "machine": machine,
            "direction": direction,
            "plane": plane,
            "kind": kind,
        }
        on_disk = self._ids_on_disk()
        try:
            known = self._catalogue.ids()
            new = [
                i for i in (self._try_info(mid) for mid in sorted(on_disk - known)) if i is not None
            ]
            self._catalogue.add(new)
            self._catalogue.remove(known - on_disk)
            rows = self._catalogue.query(filters)
        except (sqlite3.Error, OSError):  # catalogue unusable (corrupt, read-only): scan the files
            infos = [i for i in (self._try_info(mid) for mid in sorted(on_disk)) if i is not None]
            rows = [
                i
                for i in infos
                if all(v is None or getattr(i.meta, k) == v for k, v in filters.items())
            ]
            rows.sort(key=lambda i: (i.created_utc or "", i.id or ""))
        return [r for r in rows if r.id in on_disk]

    def damaged(self) -> builtins.list[str]:
        """Ids of the measurement files that :meth:`list` leaves out because they cannot be
        read (or carry another id); :meth:`check` says why."""
        listed = {i.id for i in self.list()}
        return sorted(self._ids_on_disk() - listed)

    def _try_info(self, measurement_id: str) -> MeasurementInfo | None:
        try:
            info = read_info_file(self._file(measurement_id))
        except (FileNotFoundError, StoreError):
            return None
        return info if info.id == measurement_id else None  # a misnamed file is not listed

    def check(self) -> builtins.list[str]:
        """Open every measurement file completely; return one line per problem found."""
        problems = []
        for mid in sorted(self._ids_on_disk()):
            try:
                m = read_measurement_file(self._file(mid))
                if m.id != mid:
                    problems.append(f"{mid}: file carries id {m.id!r}")
            except FileNotFoundError:
                continue
            except StoreError as e:
                problems.append(str(e))
        return problems

    def verify(self) -> dict[str, object]:
        """Verify the whole store without changing it: every file read completely (schema
        of every object, Fletcher-32 checksums of every dataset, metadata, its id against its
        name) and the catalogue against the files.

        Returns
        -------
        dict
            ``store``, ``ok``, ``measurements`` (files), ``readable``, ``problems`` (each
            ``{"id", "problem", "detail"}``, problem one of ``damaged``, ``misnamed``,
            ``catalogue-missing``, ``catalogue-stale``, ``catalogue-unreadable``) and
            ``notes`` (harmless findings, e.g. leftovers of an interrupted write in ``tmp/``).
        """
        problems: builtins.list[dict[str, str | None]] = []
        on_disk = self._ids_on_disk()
        readable: set[str] = set()
        for mid in sorted(on_disk):
            try:
                m = read_measurement_file(self._file(mid))
            except FileNotFoundError:  # deleted meanwhile
                continue
            except StoreError as e:
                problems.append({"id": mid, "problem": "damaged", "detail": str(e)})
                continue
            if m.id != mid:
                problems.append({"id": mid, "problem": "misnamed", "detail": f"the file carries id {m.id!r}"})
            else:
                readable.add(mid)
        try:
            known: set[str] | None = self._catalogue.ids()
        except (sqlite3.Error, OSError) as e:
            known = None
            problems.append({"id": None, "problem": "catalogue-unreadable",
                             "detail": f"{P.INDEX}: {e}; `rcsa store rebuild` makes it again from the files"})
        if known is not None:
            problems += [{"id": mid, "problem": "catalogue-missing", "detail": "readable file without a catalogue row "
                          "(the next listing or `rcsa store rebuild` adds it)"} for mid in sorted(readable - known)]
            problems += [{"id": mid, "problem": "catalogue-stale", "detail": "catalogue row without a file"}
                         for mid in sorted(known - on_disk)]
        with os.scandir(self._tmp) as it:
            leftovers = sorted(e.name for e in it)
        notes = [f"tmp/ holds {len(leftovers)} leftover(s) of interrupted writes or deletes (removed by the next "
                 f"write): {', '.join(leftovers[:5])}"] if leftovers else []
        return {"store": str(self.path), "ok": not problems, "measurements": len(on_disk), "readable": len(readable),
                "problems": problems, "notes": notes}

    def rebuild_index(self) -> int:
        """Recreate ``index.sqlite`` from the files; returns the number of measurements."""
        with self._lock():
            for suffix in ("", "-wal", "-shm", "-journal"):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(str(self.path / P.INDEX) + suffix)
        return len(self.list())

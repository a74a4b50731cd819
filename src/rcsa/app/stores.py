"""Which measurement store a call uses, and how a long-running process reads it.

The default store is ``$RCSA_STORE`` if set, else the per-user location
(:func:`rcsa.measured.store.paths.default_store_path`); only the application layer picks
it, so everything below receives its store explicitly. The stored tool libraries live in
the same directory (:func:`library_store`). A server process reads measurements through
:class:`CachedMeasurements` (immutable files, so a cached copy stays exact).
"""

from __future__ import annotations

import os
import threading
from pathlib import Path
from typing import Any

from rcsa.libraries.sync import DIRECTORY as LIBRARIES_DIRECTORY
from rcsa.libraries.sync import LibraryStore
from rcsa.measured.hybrid import MeasurementSource, base_resolver
from rcsa.measured.store import Measurement, MeasurementStore, is_measurement_id
from rcsa.model.spindle_side import BaseResolver
from rcsa.physics.subassembly_cache import LruStore

__all__ = ["CachedMeasurements", "library_store", "open_store", "resolver", "spindle_reference"]


def open_store(path: str | os.PathLike[str] | None = None) -> MeasurementStore:
    """The store at ``path`` (the default store when None), created on first use."""
    return MeasurementStore(path)


_LIBRARY_STORES: dict[str, LibraryStore] = {}
_LIBRARY_STORES_LOCK = threading.Lock()


def library_store(store_path: str | os.PathLike[str] | None = None) -> LibraryStore:
    """The stored libraries of the store at ``store_path`` (``<store>/libraries``).

    One :class:`LibraryStore` per directory and process (it sets its database up once),
    made again if the directory was removed. None: the default store's.
    """
    with _LIBRARY_STORES_LOCK:
        if store_path is not None:
            found = _LIBRARY_STORES.get(str(Path(store_path).expanduser() / LIBRARIES_DIRECTORY))
            if found is not None and found.directory.is_dir():
                return found
        root = MeasurementStore(store_path).path  # the store (and its marker) first: never a stray directory
        found = _LIBRARY_STORES[str(root / LIBRARIES_DIRECTORY)] = LibraryStore(root / LIBRARIES_DIRECTORY)
        return found


def spindle_reference(text: str) -> dict[str, Any] | None:
    """``{"spindle": {"measurement_id": text}}`` when ``text`` is a measurement id, else None.

    How a door reads a ``--spindle`` that may name a stored measurement (``m-...``) or a
    file (None: the caller reads the file).

    Examples
    --------
    >>> spindle_reference("m-0123456789ab")
    {'spindle': {'measurement_id': 'm-0123456789ab'}}
    >>> spindle_reference("ra1.json") is None
    True
    """
    return {"spindle": {"measurement_id": text}} if is_measurement_id(text) else None


def resolver(store: MeasurementSource | None = None) -> BaseResolver:
    """Looks measured spindles up in ``store`` (the default store, opened on first use)."""
    opened: list[MeasurementSource] = []

    def resolve(spindle, frequency_hz):  # type: ignore[no-untyped-def]
        if not opened:
            opened.append(store if store is not None else MeasurementStore())
        return base_resolver(opened[0])(spindle, frequency_hz)

    return resolve


class CachedMeasurements:
    """Read-through cache of stored measurements for computations (per process).

    Stored measurements are immutable and ids are never reused, so a cached copy is exact
    for as long as its file is the one it was read from; each ``get`` checks that with one
    ``stat`` (inode, size, modification time: :meth:`MeasurementStore.file_identity`), so a
    deleted measurement is never used by a request that starts after the delete, and a file
    damaged or replaced since it was cached is read again — and refused as damaged when its
    checksum fails — instead of being served from memory. (A damage that keeps inode, size
    and modification time alike, which no ordinary write does, is not noticed.)

    Parameters
    ----------
    store : MeasurementStore
    size : int
        Measurements kept (least recently used dropped first); 0 disables the cache.
    """

    def __init__(self, store: MeasurementStore, size: int) -> None:
        self.store = store
        self.path = store.path
        self.size = int(size)
        # the package's one eviction policy (least recently used first; atomic per operation)
        self._items: LruStore[str, tuple[Any, Measurement]] = LruStore(self.size)

    def get(self, measurement_id: str) -> Measurement:
        """The measurement, from memory when its file is unchanged (``NotFoundError`` if gone,
        ``DamagedError`` if damaged)."""
        identity = self._identity(measurement_id)
        if identity is None:
            return self.store.get(measurement_id)
        hit = self._items.peek(measurement_id)
        if hit is not None and hit[0] == identity:
            return hit[1]
        return self._items.put(measurement_id, (identity, self.store.get(measurement_id)))[1]

    def __contains__(self, measurement_id: object) -> bool:
        return measurement_id in self.store

    def _identity(self, measurement_id: str) -> Any:
        identity = getattr(self.store, "file_identity", None)
        if identity is not None:
            return identity(measurement_id)
        return measurement_id if measurement_id in self.store else None

    def __getattr__(self, name: str) -> Any:
        return getattr(self.store, name)

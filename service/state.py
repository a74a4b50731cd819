"""What one service process holds: settings, store, key ring, jobs, metrics, caches."""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

from rcsa.infra.api_keys import KeyRing
from rcsa.infra.job_queue import JobRunner, JobStore
from rcsa.measured.store import Measurement, MeasurementStore

from .config import Settings
from .metrics import Metrics

__all__ = ["AppState", "CachedMeasurements"]


class CachedMeasurements:
    """Read-through cache of stored measurements for computations (per process).

    Stored measurements are immutable and ids are never reused, so a cached copy is exact
    for as long as the file exists; each ``get`` checks that it still does (one ``stat``),
    so a deleted measurement is never used by a request that starts after the delete.

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
        self._items: OrderedDict[str, Measurement] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, measurement_id: str) -> Measurement:
        """The measurement, from memory when possible (``NotFoundError`` if gone)."""
        if self.size and measurement_id in self.store:
            with self._lock:
                hit = self._items.get(measurement_id)
                if hit is not None:
                    self._items.move_to_end(measurement_id)
                    return hit
        m = self.store.get(measurement_id)
        if self.size:
            with self._lock:
                self._items[measurement_id] = m
                while len(self._items) > self.size:
                    self._items.popitem(last=False)
        return m

    def __getattr__(self, name: str) -> Any:
        return getattr(self.store, name)


@dataclass
class AppState:
    """Everything the routes need, built by the lifespan (``app.state.rcsa``)."""

    settings: Settings
    store: MeasurementStore
    reader: CachedMeasurements
    keys: KeyRing
    jobs: JobStore
    metrics: Metrics
    runners: list[JobRunner]


def ensure_state(app: Any) -> AppState:
    """The app's :class:`AppState`, built once (thread-safe) on first need.

    The lifespan builds it at startup; when an app is served without lifespan events (a
    ``TestClient`` outside a ``with`` block) the first request builds it instead.
    """
    state = getattr(app.state, "rcsa", None)
    if state is None:
        with app.state.rcsa_lock:
            state = getattr(app.state, "rcsa", None)
            if state is None:
                state = app.state.rcsa = app.state.rcsa_factory()
    return state

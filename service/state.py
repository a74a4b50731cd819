"""What one service process holds: settings, store, key ring, jobs, metrics, caches."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rcsa.app.jobs import Workbench
from rcsa.app.stores import CachedMeasurements
from rcsa.infra.api_keys import KeyRing
from rcsa.infra.job_queue import JobRunner, JobStore

from .config import Settings
from .metrics import Metrics

__all__ = ["AppState", "ensure_state"]


@dataclass
class AppState:
    """Everything the routes need, built by the lifespan (``app.state.rcsa``).

    ``bench`` is where batches, libraries and syncs run: the cached store, the size limits
    of the settings, and the metrics as observer.
    """

    settings: Settings
    store: Any  # the measurement store the service opened (rcsa.app.stores.open_store)
    reader: CachedMeasurements
    keys: KeyRing
    jobs: JobStore
    metrics: Metrics
    bench: Workbench
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

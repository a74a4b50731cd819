"""Which measurement store a call uses: the caller's, or the default one.

The default store is ``$RCSA_STORE`` if set, else the per-user location
(:func:`rcsa.measured.store.paths.default_store_path`); only the application layer picks
it, so everything below receives its store explicitly.
"""

from __future__ import annotations

from rcsa.measured.hybrid import base_resolver
from rcsa.measured.store import MeasurementStore
from rcsa.model.spindle_side import BaseResolver

__all__ = ["measurement_store", "resolver"]


def measurement_store(store: MeasurementStore | None = None) -> MeasurementStore:
    """``store``, or the default store when it is None."""
    return store if store is not None else MeasurementStore()


def resolver(store: MeasurementStore | None = None) -> BaseResolver:
    """Looks measured spindles up in ``store`` (the default store, opened on first use)."""
    opened: list[MeasurementStore] = []

    def resolve(spindle, frequency_hz):  # type: ignore[no-untyped-def]
        if not opened:
            opened.append(measurement_store(store))
        return base_resolver(opened[0])(spindle, frequency_hz)

    return resolve

"""Measured spindle FRF store: immutable per-measurement HDF5 files, multi-process and crash safe.

>>> from rcsa.store import MeasurementStore          # doctest: +SKIP
>>> store = MeasurementStore()                       # $RCSA_STORE or ~/.local/share/rcsa/store
>>> mid = store.put(measurement)                     # -> "m-0123456789ab"
>>> store.get(mid).frfs["h"]                         # complex receptance, m/N
>>> [i.id for i in store.list(spindle_id="mc1")]     # metadata only
>>> store.delete(mid)
"""

from __future__ import annotations

from .measurement import Measurement, MeasurementInfo, MeasurementMeta, Provenance
from .paths import default_store_path, is_measurement_id
from .schema import MEASUREMENT_SCHEMA, SCHEMA_VERSION, STORE_SCHEMA
from .store import MeasurementStore

__all__ = [
    "MEASUREMENT_SCHEMA",
    "SCHEMA_VERSION",
    "STORE_SCHEMA",
    "Measurement",
    "MeasurementInfo",
    "MeasurementMeta",
    "MeasurementStore",
    "Provenance",
    "default_store_path",
    "is_measurement_id",
]

"""Measured spindle FRF store: immutable per-measurement HDF5 files, multi-process and crash safe.

>>> import tempfile
>>> import numpy as np
>>> store = MeasurementStore(tempfile.mkdtemp() + "/store")   # default: $RCSA_STORE or ~/.local/share/rcsa/store
>>> m = Measurement(np.array([100.0, 200.0]), {"h": [1e-7 - 1e-8j, 2e-7 - 3e-8j]},
...                 MeasurementMeta("mc1", "x", "spindle_nose", "direct_frf"))
>>> mid = store.put(m)                                         # -> "m-0123456789ab"
>>> complex(store.get(mid).frfs["h"][0])                       # complex receptance, m/N
(1e-07-1e-08j)
>>> [i.id for i in store.list(spindle_id="mc1")] == [mid]     # metadata only
True
>>> store.delete(mid)
"""

from __future__ import annotations

from rcsa.measured.store.measurement import (
    Measurement,
    MeasurementInfo,
    MeasurementMeta,
    Provenance,
)
from rcsa.measured.store.paths import default_store_path, is_measurement_id
from rcsa.measured.store.schema import MEASUREMENT_SCHEMA, SCHEMA_VERSION, STORE_SCHEMA
from rcsa.measured.store.store import MeasurementStore

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

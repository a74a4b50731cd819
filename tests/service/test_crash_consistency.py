"""An upload under an Idempotency-Key stores at most once, whatever moment its process died at.

The route records the new measurement's id with the key before writing the file
(:func:`rcsa.app.measurements.store_measurement_once`); a retry takes the dead attempt's
reservation over and finds that id. Here each crash moment is replayed without processes
(the real SIGKILL loop against uvicorn is ``test_hostile_uvicorn.py``).
"""

from __future__ import annotations

import json
import socket

import pytest
from service.idempotency import IdempotencyStore

from rcsa.app.measurements import measurement_from_document, store_measurement_once
from rcsa.errors import ConflictError
from rcsa.measured.store import MeasurementStore
from tests.helpers import REPO

DOC = json.loads((REPO / "tests" / "data" / "measurements" / "point_receptance.json").read_text())
DEAD = f"{socket.gethostname()}:999999999:dead"  # a holder whose process is gone


def _attempt(keys: IdempotencyStore, store: MeasurementStore, crash: str | None) -> dict | None:
    kind, holder = keys.begin("k-1", "upload-1", "f" * 64, "POST", "/v1/measurements")
    assert kind == "new"
    recorded = keys.effect_of("k-1", "upload-1")

    def record(mid: str) -> None:
        assert keys.record_effect("k-1", "upload-1", str(holder), mid)
        if crash == "before-put":
            raise SystemExit

    measurement = measurement_from_document(DOC)
    if crash == "after-put":
        store_measurement_once(store, measurement, recorded_id=recorded, record=record)
        raise SystemExit
    return store_measurement_once(store, measurement, recorded_id=recorded, record=record)


def _die(keys: IdempotencyStore) -> None:
    """The attempt's process died: its reservation names a dead holder."""
    with keys._connect() as con:
        con.execute("UPDATE idempotency SET holder = ? WHERE key = 'upload-1'", (DEAD,))


@pytest.mark.parametrize("crash", ["before-put", "after-put"])
def test_a_retry_after_a_crash_stores_once_and_answers_the_stored_measurement(tmp_path, crash):
    store, keys = MeasurementStore(tmp_path / "store"), IdempotencyStore(tmp_path / "keys", retention_s=3600)
    with pytest.raises(SystemExit):
        _attempt(keys, store, crash)
    _die(keys)
    info = _attempt(keys, store, None)
    assert [i.id for i in store.list()] == [info["id"]] == [keys.effect_of("k-1", "upload-1")]


def test_a_failed_attempt_keeps_the_recorded_id_for_the_retry(tmp_path):
    store, keys = MeasurementStore(tmp_path / "store"), IdempotencyStore(tmp_path / "keys", retention_s=3600)
    with pytest.raises(SystemExit):
        _attempt(keys, store, "after-put")
    _, holder = keys.begin("k-2", "other", "e" * 64, "POST", "/v1/measurements")  # unrelated key: untouched
    keys.release("k-2", "other", str(holder))
    with keys._connect() as con:  # the attempt failed (an exception) instead of dying: released, not deleted
        holder_1 = con.execute("SELECT holder FROM idempotency WHERE key = 'upload-1'").fetchone()[0]
    keys.release("k-1", "upload-1", holder_1)
    info = _attempt(keys, store, None)
    assert [i.id for i in store.list()] == [info["id"]]


def test_a_retry_whose_first_measurement_was_deleted_is_a_conflict(tmp_path):
    store, keys = MeasurementStore(tmp_path / "store"), IdempotencyStore(tmp_path / "keys", retention_s=3600)
    with pytest.raises(SystemExit):
        _attempt(keys, store, "after-put")
    store.delete(keys.effect_of("k-1", "upload-1"))
    _die(keys)
    with pytest.raises(ConflictError, match="deleted since"):
        _attempt(keys, store, None)
    assert store.list() == []

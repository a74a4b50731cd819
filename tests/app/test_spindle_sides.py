"""Spindle sides kept across predictions (``rcsa.app.predictions.SpindleSides``): same bytes, never stale."""

from __future__ import annotations

import pytest

from rcsa.app import predictions
from rcsa.app.measurements import demo_measurement
from rcsa.app.results import json_bytes
from rcsa.errors import InputError, RcsaError
from rcsa.measured.store import MeasurementStore
from rcsa.model.contract import CommonSpec
from rcsa.model.spindle_side import SpindleSide
from rcsa.model.uncertainty import parse_prediction_request
from rcsa.reference import ra1

GRID = {"start_hz": 200.0, "stop_hz": 3000.0, "step_hz": 20.0}


def _fresh(document, store=None):
    spec, _ = parse_prediction_request(document, 100_000)
    common = CommonSpec(spec.frequency_hz, spec.beam_theory, spec.shear_coefficient, spec.materials, spec.spindle)
    return SpindleSide(common, predictions.resolver(store)).predict(spec)


def test_a_kept_side_gives_the_fresh_sides_bytes(monkeypatch):
    sides = predictions.SpindleSides(4)
    monkeypatch.setattr(predictions, "SIDES", sides)
    base = ra1(GRID)
    tools = [{**base, "tool": {**base["tool"], "stickout_m": s}} for s in (0.05, 0.06, 0.05)]
    for doc in tools:
        assert json_bytes(predictions.predict(doc)) == json_bytes(_fresh(doc))
    assert len(sides._items) == 1  # one spindle, grid and materials: one side, reused
    other = {**base, "frequency": {**GRID, "step_hz": 40.0}}
    assert json_bytes(predictions.predict(other)) == json_bytes(_fresh(other))
    assert len(sides._items) == 2


def test_sides_are_bounded(monkeypatch):
    sides = predictions.SpindleSides(2)
    monkeypatch.setattr(predictions, "SIDES", sides)
    for step in (20.0, 25.0, 40.0):
        predictions.predict(ra1({**GRID, "step_hz": step}))
    assert len(sides._items) == 2
    monkeypatch.setattr(predictions, "PREFIXES_PER_SIDE", 0)  # a side holding too many chains is dropped
    predictions.predict(ra1({**GRID, "step_hz": 50.0}))
    assert len(sides._items) == 2 and all(len(k.side.cache) <= 3 for k in sides._items.values())


def test_a_measured_spindle_deleted_since_is_not_used(tmp_path, monkeypatch):
    monkeypatch.setattr(predictions, "SIDES", predictions.SpindleSides(4))
    store = MeasurementStore(tmp_path / "store")
    mid = store.put(demo_measurement(GRID))
    doc = {**ra1(GRID), "spindle": {"measurement_id": mid}}
    first = predictions.predict(doc, store=store)
    assert json_bytes(predictions.predict(doc, store=store)) == json_bytes(first) == json_bytes(_fresh(doc, store))
    path = next(p for p in (tmp_path / "store").rglob(f"{mid}*") if p.is_file())
    path.write_bytes(path.read_bytes()[:100])  # damaged in place: the kept side is not used
    with pytest.raises(RcsaError):
        predictions.predict(doc, store=store)
    store.delete(mid)
    with pytest.raises(InputError, match=f"spindle.measurement_id: no stored measurement '{mid}'"):
        predictions.predict(doc, store=store)


def test_the_same_request_again_is_its_kept_prediction_and_only_while_its_side_is(tmp_path, monkeypatch):
    sides = predictions.SpindleSides(4)
    monkeypatch.setattr(predictions, "SIDES", sides)
    store = MeasurementStore(tmp_path / "store")
    mid = store.put(demo_measurement(GRID))
    doc = {**ra1(GRID), "spindle": {"measurement_id": mid}}
    first = predictions.predict(doc, store=store)
    again = predictions.predict({**doc, "tool": dict(doc["tool"])}, store=store)  # equal, not the same object
    assert again is first and json_bytes(first) == json_bytes(_fresh(doc, store))
    assert not first.natural_frequencies_hz.flags.writeable and not first.tool_point.h.flags.writeable
    other = predictions.predict({**doc, "tool": {**doc["tool"], "stickout_m": 0.06}}, store=store)
    assert other is not first
    for k in range(predictions.PREDICTIONS_PER_SIDE):  # more tools than a side keeps: the oldest dropped
        predictions.predict({**doc, "tool": {**doc["tool"], "stickout_m": 0.05 + 0.001 * k}}, store=store)
    kept = predictions.predict(doc, store=store)
    assert kept is not first and predictions.predict(doc, store=store) is kept
    # a side dropped (more spindle sides asked for than are kept) takes its predictions along
    for k in range(sides.size):
        predictions.predict({**doc, "frequency": {**GRID, "stop_hz": GRID["stop_hz"] - 20.0 * (k + 1)}}, store=store)
    again = predictions.predict(doc, store=store)
    assert again is not kept and json_bytes(again) == json_bytes(kept)
    # and a side whose measurement is gone is not used
    store.delete(mid)
    with pytest.raises(InputError):
        predictions.predict(doc, store=store)

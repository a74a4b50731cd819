"""POST /v1/diagnoses and ``rcsa diagnose`` on a measured spindle: combinations that mean nothing are a clear 4xx.

The stored spindle is RA-1's receptance at the holder face (``holder_tip``: spindle, both
joints and the holder are inside it) or at the spindle nose. Every refusal names the field
and says why; none of them runs the diagnosis.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from rcsa.measured.store import Measurement, MeasurementMeta, MeasurementStore
from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.elimination import march
from tests.analysis.diagnosis.test_hybrid import (
    F_HZ,
    holder_tip_chain,
    hybrid_request,
    nose_receptance,
)
from tests.analysis.diagnosis.truth import base_document

from .conftest import READ, assert_problem

_IJ = {"h": (0, 0), "l": (0, 1), "n": (1, 0), "p": (1, 1)}


def _put(store: MeasurementStore, plane: str, r: np.ndarray) -> str:
    frfs = {n: r[:, i, j].copy() for n, (i, j) in _IJ.items()}
    return store.put(Measurement(F_HZ, frfs, MeasurementMeta("ra1", "x", plane, "point_receptance")))


@pytest.fixture
def ids(store_path) -> dict[str, str]:
    st = MeasurementStore(store_path)
    return {"spindle_nose": _put(st, "spindle_nose", nose_receptance()),
            "holder_tip": _put(st, "holder_tip", inv2(march(holder_tip_chain(), 2 * np.pi * F_HZ)[0]))}


def _request(ids: dict[str, str], plane: str, **options) -> dict:
    req = hybrid_request({("point_receptance", plane): ids[plane]}, "point_receptance", plane)
    req["options"].update(options)
    return req


def _refusals(ids: dict[str, str]) -> list[tuple[dict, str, str]]:
    """(request, field the answer must name, words its reason must contain)."""
    tip_with_holder = _request(ids, "holder_tip")
    tip_with_holder["assembly"]["holder"] = base_document()["holder"]
    missing = _request(ids, "spindle_nose")
    missing["assembly"]["spindle"]["measurement_id"] = "m-missing"
    wide = _request(ids, "spindle_nose")
    wide["measurements"][1]["frequency_hz"] = (np.asarray(wide["measurements"][1]["frequency_hz"]) + 30.0).tolist()
    return [
        (_request(ids, "holder_tip", effects=["spindle_holder_joint"]), "options.effects",
         "spindle-holder joint is inside"),
        (_request(ids, "holder_tip", effects=["sensor_mass", "spindle_holder_joint"]), "options.effects",
         "spindle-holder joint is inside"),
        (_request(ids, "spindle_nose", effects=["bearings"]), "options.effects", "bearings are inside"),
        (_request(ids, "holder_tip", effects=["bearings"]), "options.effects", "bearings are inside"),
        (tip_with_holder, "assembly.holder", "left out"),
        (missing, "assembly.spindle.measurement_id", "no stored"),
        (wide, "measurements[1].frequency_hz", "outside"),
    ]


def test_rest_refuses_meaningless_hybrid_combinations_with_a_422_naming_the_field(make_client, ids):
    with make_client() as client:
        for req, field, words in _refusals(ids):
            r = client.post("/v1/diagnoses", json=req, headers=READ)
            assert r.status_code == 422, (field, r.status_code, r.text[:300])
            body = assert_problem(r, 422, field)
            assert words in body["detail"], (field, body["detail"])


def test_an_async_request_is_refused_at_once_not_as_a_failed_job(make_client, ids):
    """``Prefer: respond-async`` validates what the run would check first, the measured spindle included."""
    async_read = {**READ, "Prefer": "respond-async"}
    with make_client() as client:
        for req, field, words in _refusals(ids)[:2]:
            body = assert_problem(client.post("/v1/diagnoses", json=req, headers=async_read), 422, field)
            assert words in body["detail"], body["detail"]
        r = client.post("/v1/diagnoses", json=_request(ids, "holder_tip", effects=["sensor_mass"]),
                        headers=async_read)
        assert r.status_code == 202, r.text[:300]


def test_cli_refuses_meaningless_hybrid_combinations_naming_the_field(store_path, ids, tmp_path):
    from rcsa.cli import app

    for n, (req, field, words) in enumerate(_refusals(ids)):
        path = tmp_path / f"req{n}.json"
        path.write_text(json.dumps(req))
        result = CliRunner().invoke(app, ["diagnose", str(path), "--store", str(store_path)])
        assert result.exit_code == 1, result.output
        line = result.output.strip().splitlines()[-1]
        assert line.startswith(f"error: {field}") and words in line, line


def test_rest_hybrid_diagnosis_reports_bearings_and_the_joint_not_applicable(make_client, ids):
    """At holder_tip the answer runs and says what it did not consider, and why."""
    req = _request(ids, "holder_tip", effects=["sensor_mass", "spindle_rotational_receptance"])
    req["tolerances"] = {"spindle_noise_rel": 0.002}  # the spindle's own tolerances pass the typed schema
    with make_client() as client:
        r = client.post("/v1/diagnoses", json=copy.deepcopy(req), headers=READ)
    assert r.status_code == 200, r.text
    body = r.json()
    na = {x["effect"]: x["reason"] for x in body["not_applicable"]}
    assert "measured" in na["bearings"] and "inside" in na["spindle_holder_joint"]
    assert {e["effect"] for e in body["ranking"]} == {"sensor_mass", "spindle_rotational_receptance"}
    assert body["spindle_measurement"]["plane"] == "holder_tip"
    noise = body["spindle_measurement"]["uncertainty_in_expected_scatter"]["noise"]
    assert noise["default_relative_sd"] == 0.002
    assert body["verdict"]["effect"] == "none"  # the taps are the model itself

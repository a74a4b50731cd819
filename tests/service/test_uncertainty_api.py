"""Uncertainty bands and robust lobes through REST: the library's results, refused options named."""

from __future__ import annotations

import numpy as np

from rcsa import app

from .conftest import assert_problem

OPTION = {"draws": 8, "seed": 3}
CUT = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
       "milling": "down", "spindle_speed_rpm": {"start": 3000, "stop": 24000, "count": 200}}


def test_prediction_with_uncertainty_is_the_librarys_band(client, assembly):
    r = client.post("/v1/tool-point-frf", json={**assembly, "uncertainty": OPTION})
    assert r.status_code == 200, r.text
    band = r.json()["uncertainty"]
    expected = app.predict({**assembly, "uncertainty": OPTION}).to_dict()["uncertainty"]
    assert band["draws"] == 8
    for p in ("p05", "p50", "p95"):
        np.testing.assert_array_equal(band["h_magnitude_m_n"][p], expected["h_magnitude_m_n"][p])


def test_batch_with_uncertainty_gives_every_combination_a_band(client, assembly):
    combo = {"id": "T1", "holder": assembly["holder"], "tool": assembly["tool"], "joints": assembly["joints"]}
    doc = {"frequency": assembly["frequency"], "spindle": assembly["spindle"], "combinations": [combo],
           "uncertainty": OPTION}
    r = client.post("/v1/tool-point-frf/batch", json=doc)
    assert r.status_code == 200, r.text
    assert r.json()["results"][0]["uncertainty"]["draws"] == 8


def test_robust_lobes_through_rest(client, assembly):
    r = client.post("/v1/stability-lobes", json={"assembly": assembly, **CUT, "uncertainty": OPTION,
                                                 "robust": {"confidence": 0.9}})
    assert r.status_code == 200, r.text
    body = r.json()
    nominal = np.array([np.nan if v is None else v for v in body["depth_limit_m"]])
    robust = np.array([np.nan if v is None else v for v in body["depth_limit_robust_m"]])
    ok = np.isfinite(robust)
    assert ok.any() and np.all(robust[ok] <= nominal[ok])
    assert body["robust"]["percentile"] == 10.0


def test_bad_options_are_422_naming_the_field(client, assembly):
    r = client.post("/v1/tool-point-frf", json={**assembly, "uncertainty": {"draws": 1}})
    assert_problem(r, 422, "uncertainty.draws")
    r = client.post("/v1/stability-lobes", json={"assembly": assembly, **CUT, "robust": {"confidence": 0.9}})
    assert_problem(r, 422, "robust")
    r = client.post("/v1/stability-lobes", json={"assembly": assembly, **CUT, "uncertainty": OPTION,
                                                 "method": "semi_discretization"})
    assert_problem(r, 422, "uncertainty")

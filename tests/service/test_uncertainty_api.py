"""Uncertainty bands and robust lobes through REST: the library's results, refused options named."""

from __future__ import annotations

import csv
import io

import numpy as np

import rcsa

from .conftest import assert_problem

OPTION = {"draws": 8, "seed": 3}
CUT = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
       "milling": "down", "spindle_speed_rpm": {"start": 3000, "stop": 24000, "count": 200}}


def test_prediction_with_uncertainty_is_the_librarys_band(client, assembly):
    r = client.post("/v1/tool-point-frf", json={**assembly, "uncertainty": OPTION})
    assert r.status_code == 200, r.text
    band = r.json()["uncertainty"]
    expected = rcsa.predict({**assembly, "uncertainty": OPTION}).to_dict()["uncertainty"]
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
    r = client.post("/v1/stability-lobes", json={"assembly": assembly, **CUT, "uncertainty": {"draws": 1},
                                                 "method": "semi_discretization"})
    assert_problem(r, 422, "uncertainty.draws")


def _csv(response) -> tuple[list[str], list[list[str]]]:
    assert response.status_code == 200, response.text
    rows = list(csv.reader(io.StringIO(response.text)))
    return rows[0], rows[1:]


def test_frf_csv_with_uncertainty_has_the_bands_percentiles(client, assembly):
    body = {**assembly, "uncertainty": OPTION}
    header, rows = _csv(client.post("/v1/exports/frf.csv", json=body))
    assert header[-3:] == ["h_magnitude_p05_m_n", "h_magnitude_p50_m_n", "h_magnitude_p95_m_n"]
    band = client.post("/v1/tool-point-frf", json=body).json()["uncertainty"]["h_magnitude_m_n"]
    columns = list(zip(*rows, strict=True))
    for k, p in enumerate(("p05", "p50", "p95")):
        assert [float(v) for v in columns[len(header) - 3 + k]] == band[p]


def test_lobes_csv_and_picture_carry_the_robust_limit(client, assembly):
    request = {"assembly": assembly, **CUT, "uncertainty": OPTION}
    header, rows = _csv(client.post("/v1/exports/lobes.csv", json=request))
    assert header[-1] == "depth_limit_robust_m"
    robust = client.post("/v1/stability-lobes", json=request).json()["depth_limit_robust_m"]
    assert [None if v == "" else float(v) for v in list(zip(*rows, strict=True))[-1]] == robust
    svg = client.post("/v1/plots/lobes?format=svg", json=request)
    assert svg.status_code == 200 and 'id="robust' in svg.text


def test_the_page_asks_for_draws_and_draws_the_band_and_the_robust_limit(client):
    page, script = client.get("/ui/").text, client.get("/ui/app.js").text
    assert 'id="draws"' in page
    assert "frf-band" in script and "lobes-robust-path" in script and "uncertainty:" in script


def test_a_bad_option_is_refused_before_it_is_queued(client, assembly):
    async_ = {"Prefer": "respond-async"}
    body = {**assembly, "uncertainty": {"draws": 2, "tolerances": {"stickout_m": 1.0}}}
    assert_problem(client.post("/v1/tool-point-frf", json=body, headers=async_), 422, "uncertainty.tolerances.stickout_m")
    lobes = {"assembly": assembly, **CUT, "robust": {"confidence": 0.9}}
    assert_problem(client.post("/v1/stability-lobes", json=lobes, headers=async_), 422, "robust")


def test_frf_picture_of_an_assembly_with_uncertainty_shades_the_band(client, assembly):
    plain = client.post("/v1/plots/frf?format=svg", json={"assembly": assembly, "layout": "bode"})
    banded = client.post("/v1/plots/frf?format=svg", json={"assembly": {**assembly, "uncertainty": OPTION},
                                                           "layout": "bode"})
    assert plain.status_code == banded.status_code == 200, banded.text
    # the band is one more filled area on the magnitude axes (a PolyCollection: an SVG path group)
    assert banded.text.count("<path") > plain.text.count("<path")
    assert_problem(client.post("/v1/plots/frf", json={"assembly": {**assembly, "uncertainty": {"draws": 1}}}),
                   422, "assembly.uncertainty.draws")

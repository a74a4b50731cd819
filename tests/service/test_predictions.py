"""POST /v1/tool-point-frf and /v1/stability-lobes through the app, and their error paths."""

from __future__ import annotations

import gzip

import numpy as np
import pytest

import rcsa
from rcsa.reference import ra1

from .conftest import GRID, assert_problem


def test_prediction_matches_the_library(client, assembly):
    r = client.post("/v1/tool-point-frf", json=assembly)
    assert r.status_code == 200 and r.headers["content-type"] == "application/json"
    body = r.json()
    expected = rcsa.predict(assembly).to_dict()
    assert body["frequency_hz"] == expected["frequency_hz"]
    np.testing.assert_array_equal(body["tool_point"]["h"]["real"], expected["tool_point"]["h"]["real"])
    np.testing.assert_array_equal(body["tool_point"]["p"]["imag"], expected["tool_point"]["p"]["imag"])
    assert body["natural_frequencies_hz"] == expected["natural_frequencies_hz"]
    assert [round(f, 2) for f in body["natural_frequencies_hz"]][:3] == [599.85, 921.69, 1115.51]
    assert body["peaks"] == expected["peaks"] and body["static_stiffness_n_m"] == expected["static_stiffness_n_m"]


def test_hybrid_prediction_on_the_seeded_demo_spindle(make_client, assembly):
    with make_client(seed_demo=True) as client:
        items = client.get("/v1/measurements", params={"spindle_id": "demo-ra1"}).json()["items"]
        assert len(items) == 1 and items[0]["kind"] == "point_receptance"
        hybrid = {**assembly, "spindle": {"measurement_id": items[0]["id"]}}
        r = client.post("/v1/tool-point-frf", json=hybrid)
        assert r.status_code == 200, r.text
        body = r.json()
        assert body["natural_frequencies_method"] == "modal_fit"
        assert body["spindle_measurement"]["id"] == items[0]["id"]
        # the demo spindle is RA-1's own spindle: the hybrid FRF equals the analytical one
        exact = np.array(rcsa.predict(assembly).to_dict()["tool_point"]["h"]["real"])
        np.testing.assert_allclose(body["tool_point"]["h"]["real"], exact, rtol=1e-6, atol=1e-9 * np.abs(exact).max())
    with make_client(seed_demo=True) as client:  # seeding happens once in the store's life
        assert len(client.get("/v1/measurements").json()["items"]) == 1


@pytest.mark.parametrize(("frequency", "field"), [
    ({"start_hz": 0.0, "stop_hz": 100.0, "step_hz": 1.0}, "frequency.start_hz"),
    ({"start_hz": -5.0, "stop_hz": 100.0, "step_hz": 1.0}, "frequency.start_hz"),
    ({"start_hz": 5.0, "stop_hz": 100.0, "step_hz": 0.0}, "frequency.step_hz"),
    ({"start_hz": 50.0, "stop_hz": 10.0, "step_hz": 1.0}, "frequency.stop_hz"),
    ({"values_hz": [30.0, 20.0, 40.0]}, "frequency.values_hz"),
    ({"values_hz": [0.0, 20.0]}, "frequency.values_hz"),
    ({"values_hz": []}, "frequency.values_hz"),
    ({"start_hz": 1.0, "stop_hz": 50000.0, "step_hz": 1.0}, "frequency"),
    ({"values_hz": list(np.arange(1.0, 20002.0))}, "frequency.values_hz"),
    ({"start_hz": "5", "stop_hz": 100.0, "step_hz": 1.0}, "frequency.start_hz"),
    ("5-5000", "frequency"),
])
def test_bad_frequency_grids_are_422_naming_the_field(client, assembly, frequency, field):
    r = client.post("/v1/tool-point-frf", json={**assembly, "frequency": frequency})
    body = assert_problem(r, 422, field)
    assert body["detail"].startswith(field)


def test_unknown_field_missing_field_and_physics_rules(client, assembly):
    r = client.post("/v1/tool-point-frf", json={**assembly, "tool": {**assembly["tool"], "stickoutt_m": 0.05}})
    assert "unknown field" in assert_problem(r, 422, "tool.stickoutt_m")["detail"]
    tool = {k: v for k, v in assembly["tool"].items() if k != "diameter_m"}
    assert_problem(client.post("/v1/tool-point-frf", json={**assembly, "tool": tool}), 422, "tool.diameter_m")
    long = {**assembly["tool"], "stickout_m": 0.5}  # longer than the tool: a rule rcsa checks
    body = assert_problem(client.post("/v1/tool-point-frf", json={**assembly, "tool": long}), 422, "tool.stickout_m")
    assert "overall_length_m" in body["detail"]
    seg = [{**assembly["holder"]["segments"][0], "length_m": -0.01}]
    assert_problem(client.post("/v1/tool-point-frf", json={**assembly, "holder": {"segments": seg}}), 422,
                   "holder.segments[0].length_m")
    assert_problem(client.post("/v1/tool-point-frf", json={**assembly, "extra": 1}), 422, "extra")


def test_unknown_measurement_is_422_naming_the_spindle(client, assembly):
    r = client.post("/v1/tool-point-frf", json={**assembly, "spindle": {"measurement_id": "m-000000000000"}})
    assert "m-000000000000" in assert_problem(r, 422, "spindle.measurement_id")["detail"]


def test_bad_json_wrong_content_type_and_empty_body(client):
    # text that is not JSON is a 400 (malformed); a well-formed document that breaks a rule a 422
    r = client.post("/v1/tool-point-frf", content=b'{"frequency": ', headers={"content-type": "application/json"})
    body = assert_problem(r, 400, "")
    assert "not valid JSON" in body["detail"] and body["type"].endswith(":malformed-body")
    r = client.post("/v1/tool-point-frf", content=b"frequency=5", headers={"content-type": "text/plain"})
    assert "application/json" in assert_problem(r, 415)["detail"]
    assert_problem(client.post("/v1/tool-point-frf", content=b"[1, 2]", headers={"content-type": "application/json"}),
                   422)
    assert_problem(client.post("/v1/tool-point-frf"), 422)
    assert_problem(client.post("/v1/tool-point-frf", content=b"NaN", headers={"content-type": "application/json"}),
                   400)
    assert_problem(client.post("/v1/tool-point-frf", content=b'{"a": 1e400}', headers={"content-type": "application/json"}),
                   422)


def test_body_over_the_limit_is_413_with_or_without_content_length(make_client, assembly):
    with make_client(max_body_bytes=4096) as client:
        big = {**assembly, "description": "x" * 5000}
        body = assert_problem(client.post("/v1/tool-point-frf", json=big), 413)
        assert "4096 bytes" in body["detail"]

        def chunks():  # no Content-Length: the limit counts the bytes as they arrive
            yield b'{"description": "'
            for _ in range(10):
                yield b"y" * 1000
            yield b'"}'

        r = client.post("/v1/tool-point-frf", content=chunks(), headers={"content-type": "application/json"})
        assert "content-length" not in r.request.headers
        assert_problem(r, 413)
        assert client.post("/v1/tool-point-frf", json=ra1({"start_hz": 100.0, "stop_hz": 200.0, "step_hz": 50.0})
                           ).status_code == 200


def test_frequency_line_limit_is_a_setting(make_client, assembly):
    with make_client(max_frequency_lines=500) as client:
        body = assert_problem(client.post("/v1/tool-point-frf", json=assembly), 422, "frequency")
        assert "500" in body["detail"]


def test_request_id_is_echoed_or_made_and_gzip_when_accepted(client, assembly):
    r = client.post("/v1/tool-point-frf", json=assembly, headers={"X-Request-ID": "abc-123"})
    assert r.headers["x-request-id"] == "abc-123"
    r = client.post("/v1/tool-point-frf", json=assembly, headers={"X-Request-ID": "bad id with spaces"})
    assert len(r.headers["x-request-id"]) == 32
    r = client.post("/v1/tool-point-frf", json=assembly, headers={"Accept-Encoding": "gzip"})
    assert r.headers["content-encoding"] == "gzip" and r.json()["frequency_hz"][0] == GRID["start_hz"]
    raw = client.post("/v1/tool-point-frf", json=assembly, headers={"Accept-Encoding": "identity"})
    assert "content-encoding" not in raw.headers
    assert gzip.compress(raw.content)  # identity body is plain JSON
    assert raw.json()["frequency_hz"] == r.json()["frequency_hz"]


def test_stability_lobes_from_an_assembly_and_inline(client, assembly):
    base = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
            "milling": "down", "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 200}, "method": "zoa"}
    r = client.post("/v1/stability-lobes", json={**base, "assembly": assembly})
    assert r.status_code == 200, r.text
    body = r.json()
    assert len(body["spindle_speed_rpm"]) == 200 and len(body["depth_limit_m"]) == 200 and body["lobes"]
    assert body == rcsa.stability_lobes({**base, "assembly": assembly})
    pred = client.post("/v1/tool-point-frf", json=assembly).json()
    frf = {"frequency_hz": pred["frequency_hz"], "h": pred["tool_point"]["h"]}
    inline = client.post("/v1/stability-lobes", json={**base, "frf_x": frf}).json()
    assert inline["depth_limit_m"] == body["depth_limit_m"]
    assert_problem(client.post("/v1/stability-lobes", json={**base, "frf_x": frf, "assembly": assembly}), 422,
                   "frf_x")
    assert_problem(client.post("/v1/stability-lobes", json={**base, "frf_x": frf, "teeth": 0}), 422, "teeth")


def test_tool_point_selection_trims_the_result(client, assembly):
    full = client.post("/v1/tool-point-frf", json=assembly).json()
    only_h = client.post("/v1/tool-point-frf", json=assembly, params={"tool_point": "h"}).json()
    assert set(only_h["tool_point"]) == {"h"} and only_h["tool_point"]["h"] == full["tool_point"]["h"]
    assert only_h["peaks"] == full["peaks"]
    assert_problem(client.post("/v1/tool-point-frf", json=assembly, params={"tool_point": "x"}), 422, "tool_point")


def test_a_measurement_damaged_after_a_first_request_is_never_served_from_the_cache(make_client, store_path,
                                                                                    assembly):
    with make_client(seed_demo=True) as client:
        mid = client.get("/v1/measurements", params={"spindle_id": "demo-ra1"}).json()["items"][0]["id"]
        hybrid = {**assembly, "spindle": {"measurement_id": mid}}
        assert client.post("/v1/tool-point-frf", json=hybrid).status_code == 200  # now in the cache
        path = store_path / "measurements" / f"{mid}.h5"
        raw = bytearray(path.read_bytes())
        middle = len(raw) // 2
        raw[middle:middle + 4096] = bytes(4096)  # damaged in place: same inode, same size
        with path.open("r+b") as fh:
            fh.write(raw)
        damaged = client.post("/v1/tool-point-frf", json=hybrid)
        problem = assert_problem(damaged, 422)
        assert mid in problem["detail"]
        assert_problem(client.get(f"/v1/measurements/{mid}"), 409)

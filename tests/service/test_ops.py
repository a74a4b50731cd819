"""Operations endpoints, OpenAPI quality, analysis routes, logging with request ids."""

from __future__ import annotations

import logging
import shutil

from .conftest import WRITE, assert_problem


def test_health_ready_and_not_ready(client, store_path):
    assert client.get("/healthz").json() == {"status": "ok"}
    r = client.get("/readyz")
    assert r.status_code == 200 and r.json()["checks"] == {"store": "ok", "jobs": "ok", "job_runner": "ok"}
    assert not [p for p in store_path.iterdir() if p.name.startswith(".readyz")]  # the probe is removed
    shutil.rmtree(store_path)
    r = client.get("/readyz")
    assert r.status_code == 503 and r.json()["status"] == "not ready"
    assert r.json()["checks"]["store"].startswith("error")


def test_metrics_count_requests_frfs_and_import_failures(client, assembly):
    client.post("/v1/tool-point-frf", json=assembly)
    client.post("/v1/tool-point-frf", json={**assembly, "frequency": {"values_hz": [2.0, 1.0]}})
    client.post("/v1/measurements", files={"file": ("x.csv", b"1,2,3\n")}, headers=WRITE,
                data={"spindle_id": "a", "direction": "x", "plane": "spindle_nose"})
    client.get("/v1/measurements/m-000000000000")
    r = client.get("/metrics")
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/plain")
    text = r.text
    assert 'rcsa_http_requests_total{method="POST",route="/v1/tool-point-frf",status="200"} 1.0' in text
    assert 'rcsa_http_requests_total{method="POST",route="/v1/tool-point-frf",status="422"} 1.0' in text
    assert 'route="/v1/measurements/{measurement_id}",status="404"' in text
    assert 'rcsa_frfs_computed_total{operation="predict"} 1.0' in text
    assert 'rcsa_measurement_import_failures_total{format="csv"} 1.0' in text
    assert "rcsa_http_request_duration_seconds_bucket" in text and "rcsa_compute_seconds_count" in text


def test_docs_and_openapi_carry_units_and_examples(client):
    assert client.get("/docs").status_code == 200
    spec = client.get("/openapi.json").json()
    schemas = spec["components"]["schemas"]
    tool = schemas["Tool"]["properties"]
    assert "m" in tool["stickout_m"]["description"] and "LB" in tool["stickout_m"]["description"]
    assert schemas["Assembly"]["examples"][0]["tool"]["stickout_m"] == 0.074
    assert schemas["Joint"]["properties"]["stiffness_n_m"]["description"].endswith("N/m.")
    for name in ("Problem", "MeasurementUpload", "LibraryPredictionRequest", "BatchResult", "LibraryResult"):
        assert name in schemas
    paths = spec["paths"]
    for path in ("/v1/tool-point-frf", "/v1/tool-point-frf/batch", "/v1/measurements", "/v1/measurements/{measurement_id}",
                 "/v1/jobs/{job_id}", "/v1/jobs/{job_id}/result", "/v1/stability-lobes", "/v1/tool-libraries:predict",
                 "/v1/diagnoses", "/v1/identifications", "/v1/effects", "/healthz", "/readyz", "/metrics"):
        assert path in paths, path
    upload = paths["/v1/measurements"]["post"]["requestBody"]["content"]
    assert set(upload) == {"application/json", "multipart/form-data"}
    assert "application/problem+json" in paths["/v1/tool-point-frf"]["post"]["responses"]["422"]["content"]
    assert spec["components"]["securitySchemes"]["APIKey"]["name"] == "X-API-Key"


def test_analysis_routes_call_the_library(client, assembly):
    for path in ("/v1/diagnoses", "/v1/identifications", "/v1/effects"):
        r = client.post(path, json={})
        assert r.status_code == 422, (path, r.text)
        assert r.headers["content-type"].startswith("application/problem+json")
    assert_problem(client.post("/v1/effects", json=[1, 2]), 422)
    r = client.post("/v1/effects", json={**assembly, "frequency": {"start_hz": 300.0, "stop_hz": 2000.0,
                                                                   "step_hz": 10.0}})
    assert r.status_code == 200, r.text
    assert "modes" in r.json()


def test_diagnosis_over_rest_speaks_the_contract(client):
    # A measurement that is the base model itself (plus nothing): the verdict must be "none".
    import rcsa
    from rcsa.reference import ra1

    doc = ra1({"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 10.0})
    h = rcsa.predict(doc).tool_point.h
    request = {"assembly": doc, "options": {"monte_carlo_draws": 50, "max_lines": 300},
               "measurements": [{"tool": {"stickout_m": 0.074}, "frequency_hz": doc_frequencies(doc),
                                 "h": {"real": h.real.tolist(), "imag": h.imag.tolist()}}]}
    r = client.post("/v1/diagnoses", json=request)
    assert r.status_code == 200, r.text
    body = r.json()
    assert set(body) >= {"gap", "verdict", "effects"}
    assert body["verdict"]["status"] == "none" and body["verdict"]["effect"] == "none"


def doc_frequencies(doc):
    f = doc["frequency"]
    n = round((f["stop_hz"] - f["start_hz"]) / f["step_hz"]) + 1
    return [f["start_hz"] + i * f["step_hz"] for i in range(n)]


def test_log_lines_carry_the_request_id(make_client, assembly, caplog):
    with make_client(access_log=True) as client, caplog.at_level(logging.INFO):
        client.post("/v1/tool-point-frf", json=assembly, headers={"X-Request-ID": "trace-42"})
        client.get("/v1/jobs/j-" + "0" * 32)
    access = [r for r in caplog.records if r.name == "service.access"]
    assert [r.request_id for r in access] == ["trace-42", access[1].request_id]
    assert "POST /v1/tool-point-frf\" 200" in access[0].getMessage()
    assert all(hasattr(r, "request_id") for r in caplog.records)


def test_the_app_works_without_its_lifespan(tmp_path, monkeypatch):
    # Integrators often write TestClient(app) without a ``with`` block, or mount the app in
    # an ASGI server that skips lifespan events: the state is then built on first use.
    from fastapi.testclient import TestClient
    from service.main import create_app

    from rcsa.reference import ra1

    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "store"))
    client = TestClient(create_app())
    r = client.post("/v1/tool-point-frf", json=ra1({"start_hz": 500.0, "stop_hz": 700.0, "step_hz": 5.0}))
    assert r.status_code == 200, r.text
    assert [round(f, 2) for f in r.json()["natural_frequencies_hz"]] == [599.85]
    for runner in client.app.state.rcsa.runners:
        runner.stop(10.0)


def test_module_level_app_for_uvicorn_without_factory(tmp_path, monkeypatch):
    import service.main

    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "store"))
    monkeypatch.delitem(service.main.__dict__, "app", raising=False)
    app = service.main.app
    assert app is service.main.app  # built once, on first access
    assert "/v1/tool-point-frf" in app.openapi()["paths"]


def test_docs_pages_name_only_local_assets(client):
    """/docs and /redoc work on a network without internet: every asset they name is served here."""
    import re

    for page in ("/docs", "/redoc"):
        r = client.get(page)
        assert r.status_code == 200 and r.headers["content-type"].startswith("text/html")
        urls = re.findall(r'(?:src|href)="([^"]+)"', r.text)
        assert urls and not [u for u in urls if "//" in u], (page, urls)
        for url in urls:
            asset = client.get(url)
            assert asset.status_code == 200 and len(asset.content) > 1000, url
        assert "fonts.googleapis" not in r.text
    assert '"validatorUrl": null' in client.get("/docs").text  # no badge from validator.swagger.io
    assert client.get("/favicon.ico").headers["content-type"] == "image/png"
    assert_problem(client.get("/docs-assets/../main.py"), 404)
    assert_problem(client.get("/docs-assets/index.html"), 404)


def test_405_allow_names_every_method_of_the_path(client):
    """A path served by several routes (GET and POST /v1/measurements) allows all their methods."""
    for method, path, allow in (("PUT", "/v1/measurements", "GET, POST"),
                                ("PATCH", "/v1/measurements/m-0123456789ab", "DELETE, GET"),
                                ("GET", "/v1/tool-point-frf", "POST"), ("POST", "/healthz", "GET")):
        r = client.request(method, path)
        body = assert_problem(r, 405)
        assert r.headers["allow"] == allow, (method, path, r.headers)
        assert allow in body["detail"] and method in body["detail"]

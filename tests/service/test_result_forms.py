"""Batch and library results as HDF5 or Parquet over REST (``Accept``): the JSON's numbers to the last bit."""

from __future__ import annotations

import json
import time

import pytest

from rcsa.app.results import json_bytes
from tests.helpers import REPO
from tests.result_files import read_hdf5, read_parquet

from .conftest import GRID, WRITE, assert_problem

HDF5, PARQUET = "application/x-hdf5", "application/vnd.apache.parquet"
READERS = {HDF5: read_hdf5, PARQUET: read_parquet}
LIBRARY = json.loads((REPO / "tests/data/tool-libraries/fusion-synthetic/synthetic_library.json").read_text())


def _batch(assembly):
    return {"frequency": GRID, "spindle": assembly["spindle"], "combinations": [
        {"id": "T0", "holder": assembly["holder"], "tool": assembly["tool"], "joints": assembly["joints"]},
        {"id": "bad", "holder": assembly["holder"], "tool": {**assembly["tool"], "stickout_m": 0.5}},
        {"id": "T1", "holder": assembly["holder"], "tool": {**assembly["tool"], "stickout_m": 0.06}}]}


def _finished(client, location):
    for _ in range(1200):
        job = client.get(location).json()
        if job["status"] in ("succeeded", "failed"):
            return job
        time.sleep(0.05)
    raise AssertionError(f"{location} did not finish")


@pytest.mark.parametrize("media", [HDF5, PARQUET])
def test_a_batch_in_a_binary_form_holds_the_json_numbers(client, assembly, media):
    request = _batch(assembly)
    as_json = client.post("/v1/tool-point-frf/batch", json=request)
    r = client.post("/v1/tool-point-frf/batch", json=request, headers={"Accept": media})
    assert r.status_code == 200 and r.headers["content-type"] == media
    assert json_bytes(READERS[media](r.content)) == as_json.content
    lean = client.post("/v1/tool-point-frf/batch", json=request, params={"tool_point": "h"},
                       headers={"Accept": f"{media}, application/json;q=0.5"})
    assert json_bytes(READERS[media](lean.content)) == \
        client.post("/v1/tool-point-frf/batch", json=request, params={"tool_point": "h"}).content


def test_a_batch_job_writes_the_form_asked_for_when_it_was_submitted(client, assembly):
    request = _batch(assembly)
    r = client.post("/v1/tool-point-frf/batch", json=request, headers={"Prefer": "respond-async", "Accept": HDF5})
    assert r.status_code == 202, r.text
    job = _finished(client, r.headers["location"])
    result = client.get(job["result_url"])
    assert result.status_code == 200 and result.headers["content-type"] == HDF5
    assert json_bytes(read_hdf5(result.content)) == client.post("/v1/tool-point-frf/batch", json=request).content
    refused = client.get(job["result_url"], headers={"Accept": "application/json"})
    assert_problem(refused, 406)
    assert "available as application/x-hdf5" in refused.json()["detail"]
    r = client.post("/v1/tool-point-frf/batch", json=request, headers={"Prefer": "respond-async"})
    json_job = _finished(client, r.headers["location"])
    assert json_job["id"] != job["id"]  # another form is another job
    assert client.get(json_job["result_url"]).headers["content-type"] == "application/json"


def test_parquet_without_pyarrow_is_406_naming_the_extra(client, assembly, monkeypatch):
    import rcsa.app.results as results

    monkeypatch.setattr(results, "parquet_available", lambda: False)
    r = client.post("/v1/tool-point-frf/batch", json=_batch(assembly), headers={"Accept": PARQUET})
    assert_problem(r, 406)
    assert "pip install 'rcsa[parquet]'" in r.json()["detail"]
    fallback = client.post("/v1/tool-point-frf/batch", json=_batch(assembly),
                           headers={"Accept": f"{PARQUET}, application/json;q=0.1"})
    assert fallback.status_code == 200 and fallback.headers["content-type"] == "application/json"
    csv = client.post("/v1/tool-point-frf/batch", json=_batch(assembly), headers={"Accept": "text/csv"})
    assert_problem(csv, 406)
    assert "application/json or application/x-hdf5 or application/vnd.apache.parquet" in csv.json()["detail"]


@pytest.mark.parametrize("media", [HDF5, PARQUET])
def test_a_library_prediction_in_a_binary_form(client, media):
    body = {"library": LIBRARY, "spindle": json.loads((REPO / "examples/ra1.json").read_text())["spindle"],
            "frequency": GRID}
    as_json = client.post("/v1/tool-libraries:predict", json=body)
    r = client.post("/v1/tool-libraries:predict", json=body, headers={"Accept": media})
    assert r.status_code == 200 and r.headers["content-type"] == media
    document = READERS[media](r.content)
    assert [x["status"] for x in document["results"]] == ["ok", "ok", "skipped", "skipped"]
    assert json_bytes(document) == as_json.content


def test_stored_library_results_as_parquet(client):
    body = {"library": LIBRARY, "spindle": json.loads((REPO / "examples/ra1.json").read_text())["spindle"],
            "frequency": GRID}
    assert client.post("/v1/libraries/shop:sync", json=body, headers=WRITE).status_code == 201
    as_json = client.get("/v1/libraries/shop/results")
    for kwargs in ({"headers": {"Accept": PARQUET}}, {"params": {"format": "parquet"}}):
        r = client.get("/v1/libraries/shop/results", **kwargs)
        assert r.status_code == 200 and r.headers["content-type"] == PARQUET
        assert r.headers["content-disposition"] == 'attachment; filename="shop-r1.parquet"'
        assert json_bytes(read_parquet(r.content)) == as_json.content

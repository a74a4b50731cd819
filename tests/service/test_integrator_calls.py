"""The calls a CAM integration needs: one tool's result, lobes by reference, lists of one shape,
operation ids, 201 + Location on create, and the OpenAPI naming every write operation."""

from __future__ import annotations

import json
import re

import pytest

from rcsa.reference import ra1
from tests.helpers import REPO

from .conftest import READ, WRITE, assert_problem

SAMPLE = (REPO / "tests" / "data" / "tool-libraries" / "fusion-synthetic" / "synthetic_library.json").read_bytes()
GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
RA1 = ra1(GRID)
SYNC = {"spindle": json.dumps(RA1["spindle"]), "frequency": json.dumps(GRID), "joints": json.dumps(RA1["joints"])}
TOOL = "00000000-0000-4000-8000-000000000101"
CUT = {"tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": 0.5, "milling": "down",
       "spindle_speed_rpm": {"start": 4000, "stop": 24000, "count": 120}}


@pytest.fixture
def synced(client):
    first = client.post("/v1/libraries/shop:sync", headers=WRITE, files={"library": ("shop.json", SAMPLE)}, data=SYNC)
    assert first.status_code == 201 and first.headers["location"] == "/v1/libraries/shop", first.text
    again = client.post("/v1/libraries/shop:sync", headers=WRITE, files={"library": ("shop.json", SAMPLE)}, data=SYNC)
    assert again.status_code == 200 and again.json()["revision"] == 2  # created once, synced after
    return client


def test_one_tools_result_equals_its_item_of_the_whole_results(synced):
    whole = {r["id"]: r for r in synced.get("/v1/libraries/shop/results").json()["results"]}
    one = synced.get(f"/v1/libraries/shop/tools/{TOOL}", headers=READ)
    assert one.status_code == 200 and one.json() == whole[TOOL]
    h_only = synced.get(f"/v1/libraries/shop/tools/{TOOL}", params={"tool_point": "h"}).json()
    assert set(h_only["tool_point"]) == {"h"} and h_only["tool_point"]["h"] == whole[TOOL]["tool_point"]["h"]
    skipped = next(i for i, r in whole.items() if r["status"] == "skipped")
    assert synced.get(f"/v1/libraries/shop/tools/{skipped}").json() == whole[skipped]
    assert "GET /v1/libraries/{library_id}" in assert_problem(synced.get("/v1/libraries/shop/tools/nope"), 404)["detail"]
    assert_problem(synced.get(f"/v1/libraries/nope/tools/{TOOL}"), 404)


def test_lobes_of_a_stored_tool_equal_lobes_of_its_assembly(synced):
    assembly = synced.get("/v1/libraries/shop").json()  # what the library knows
    tool = next(t for t in assembly["tools"] if t["id"] == TOOL)
    by_reference = synced.post("/v1/stability-lobes", json={**CUT, "library_tool": {"library_id": "shop",
                                                                                   "tool_id": TOOL}})
    assert by_reference.status_code == 200, by_reference.text
    # the same request with the assembly sent in full: the tool's combination from the library import
    from rcsa.app.libraries import library_entries
    entry = next(e for e in library_entries(SAMPLE, file_name="shop.json")["entries"] if e["id"] == TOOL)
    full = {**CUT, "teeth": tool["teeth"], "assembly": {"frequency": GRID, "spindle": RA1["spindle"],
                                                       "holder": entry["holder"], "tool": entry["tool"],
                                                       "joints": RA1["joints"]}}
    sent = synced.post("/v1/stability-lobes", json=full)
    assert sent.status_code == 200, sent.text
    assert by_reference.json() == sent.json()
    # the lobes picture and CSV take the reference too
    csv = synced.post("/v1/exports/lobes.csv", json={**CUT, "library_tool": {"library_id": "shop", "tool_id": TOOL}})
    assert csv.status_code == 200 and csv.text.startswith("spindle_speed_rpm")
    # a reference beside what it replaces, a tool without an assembly
    both = {**full, "library_tool": {"library_id": "shop", "tool_id": TOOL}}
    assert_problem(synced.post("/v1/stability-lobes", json=both), 422, "library_tool")
    skipped = next(t["id"] for t in assembly["tools"] if t["status"] == "skipped")
    r = synced.post("/v1/stability-lobes", json={**CUT, "teeth": 2, "library_tool": {"library_id": "shop",
                                                                                    "tool_id": skipped}})
    assert "skipped" in assert_problem(r, 422, "library_tool.tool_id")["detail"]


def test_lobes_of_a_stored_measurement_equal_lobes_of_its_frf_sent_inline(client):
    frf = client.post("/v1/tool-point-frf", json=RA1).json()
    doc = {"spindle_id": "tap-T1", "direction": "x", "plane": "holder_tip", "kind": "direct_frf",
           "frequency_hz": frf["frequency_hz"], "h": frf["tool_point"]["h"]}
    mid = client.post("/v1/measurements", json=doc, headers=WRITE).json()["id"]
    inline = client.post("/v1/stability-lobes", json={**CUT, "teeth": 4, "frf_x": {
        "frequency_hz": frf["frequency_hz"], "h": frf["tool_point"]["h"]}})
    stored = client.post("/v1/stability-lobes", json={**CUT, "teeth": 4, "frf_x": {"measurement_id": mid}})
    assert stored.status_code == 200 and stored.json() == inline.json()
    assert_problem(client.post("/v1/stability-lobes", json={**CUT, "teeth": 4, "frf_x": {"measurement_id": mid,
                                                                                         "h": 1}}), 422)
    assert_problem(client.post("/v1/stability-lobes", json={**CUT, "teeth": 4,
                                                            "frf_x": {"measurement_id": "m-000000000000"}}), 422,
                   "frf_x.measurement_id")


def test_lists_have_one_shape_and_pages(synced):
    for path, headers in (("/v1/measurements", {}), ("/v1/libraries", {}), ("/v1/jobs", READ)):
        page = synced.get(path, params={"limit": 1}, headers=headers).json()
        assert {"items", "next_cursor"} <= set(page), path
        assert_problem(synced.get(path, params={"cursor": "!"}, headers=headers), 422, "cursor")
    synced.post("/v1/libraries/other:sync", headers=WRITE, files={"library": ("o.json", SAMPLE)}, data=SYNC)
    first = synced.get("/v1/libraries", params={"limit": 1}).json()
    second = synced.get("/v1/libraries", params={"limit": 1, "cursor": first["next_cursor"]}).json()
    assert [x["id"] for x in first["items"] + second["items"]] == ["other", "shop"]
    assert second["next_cursor"] is None


def test_operation_ids_are_names_a_generator_can_use(client):
    doc = client.get("/openapi.json").json()
    ids = [op["operationId"] for ops in doc["paths"].values() for op in ops.values()]
    assert len(ids) == len(set(ids))
    assert all(re.fullmatch(r"[a-z][A-Za-z0-9]*", i) for i in ids), ids
    assert {"predictToolPoint", "predictBatch", "listMeasurements", "getMeasurement", "uploadMeasurement",
            "listLibraries", "getLibraryTool", "syncLibrary", "recommendPresets", "computeStabilityLobes",
            "listJobs", "getJob", "getJobResult"} <= set(ids)


def test_the_description_names_every_write_operation(client):
    doc = client.get("/openapi.json").json()
    text = doc["info"]["description"]
    writes = [(path, method) for path, ops in doc["paths"].items() for method, op in ops.items()
              if op.get("security") == [{"APIKey": []}]]
    assert len(writes) >= 5
    for path, method in writes:
        assert f"`{method.upper()} {path}`" in text, (method, path)

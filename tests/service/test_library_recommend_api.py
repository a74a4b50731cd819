"""``POST /v1/libraries/{id}:recommend``: write key, the report with the file, the file as a download."""

from __future__ import annotations

import base64
import hashlib
import json

from rcsa.reference import ra1
from tests.helpers import REPO

from .conftest import READ, WRITE, assert_problem

SAMPLES = REPO / "tests" / "data" / "tool-libraries"
SAMPLE = (SAMPLES / "fusion-synthetic" / "synthetic_library.json").read_bytes()
GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
RA1 = ra1(GRID)
SYNC_FORM = {"spindle": json.dumps(RA1["spindle"]), "frequency": json.dumps(GRID), "joints": json.dumps(RA1["joints"]),
             "natural_frequencies": "false"}
OPTIONS = {"material": "aluminium-7075", "max_rpm": "24000", "safety_factor": "1.25", "method": "zoa"}
NAME = "rcsa chatter-safe: aluminium 7075"


def _sync(client) -> None:
    r = client.post("/v1/libraries/shop:sync", headers=WRITE, files={"library": ("shop.json", SAMPLE)},
                    data=SYNC_FORM)
    assert r.status_code in (200, 201), r.text


def test_report_with_the_file_then_the_file_itself(client):
    _sync(client)
    r = client.post("/v1/libraries/shop:recommend", headers=WRITE, files={"library": ("shop.json", SAMPLE)},
                    data=OPTIONS)
    assert r.status_code == 200, r.text
    report = r.json()
    assert report["library_id"] == "shop" and report["summary"] == {"written": 2, "skipped": 2, "failed": 0}
    assert report["frf_source"] == {"kind": "stored", "library_id": "shop", "revision": 1}
    tool = report["tools"][0]
    assert tool["status"] == "written" and tool["lobe_method"] == "zoa" and tool["pocket"]["width_rpm"] > 0
    # a zero-order pocket is read off the whole grid: never left open (booleans on the wire, not 0.0)
    assert tool["pocket"]["low_open"] is False and tool["pocket"]["high_open"] is False
    assert tool["depth_limit_m"] >= tool["stepdown_m"] * tool["safety_factor"] * (1 - 1e-12)
    data = base64.b64decode(report["file"]["content_base64"])
    assert hashlib.sha256(data).hexdigest() == report["file"]["sha256"] == report["library"]["sha256_after"]
    assert report["file"]["file_name"] == "shop.json" and report["file"]["media_type"] == "application/json"
    assert NAME in [p["name"] for p in json.loads(data)["data"][0]["start-values"]["presets"]]

    # the file as a download (Accept, or ?format=file): the same bytes
    r = client.post("/v1/libraries/shop:recommend", headers={**WRITE, "Accept": "application/octet-stream"},
                    files={"library": ("shop.json", SAMPLE)}, data=OPTIONS)
    assert r.status_code == 200 and r.content == data
    assert r.headers["content-type"] == "application/octet-stream"
    assert r.headers["content-disposition"] == 'attachment; filename="shop.json"'
    assert r.headers["x-rcsa-presets-written"] == "2"
    # sending the returned file again replaces rcsa's presets: the same file comes back
    r = client.post("/v1/libraries/shop:recommend?format=file", headers=WRITE,
                    files={"library": ("shop.json", data)}, data=OPTIONS)
    assert r.status_code == 200 and r.content == data


def test_write_key_and_problems(client):
    files = {"library": ("shop.json", SAMPLE)}
    assert_problem(client.post("/v1/libraries/shop:recommend", files=files, data=OPTIONS), 401)
    assert_problem(client.post("/v1/libraries/shop:recommend", headers=READ, files=files, data=OPTIONS), 403)
    assert_problem(client.post("/v1/libraries/shop:recommend", headers=WRITE, files=files, data=OPTIONS), 404)
    _sync(client)
    assert_problem(client.post("/v1/libraries/shop:recommend", headers=WRITE, json={"material": "7075",
                                                                                "colour": "red"}), 422, "colour")
    assert_problem(client.post("/v1/libraries/shop:recommend", headers={**WRITE, "content-type": "text/plain"},
                               content=b"material=7075"), 415)
    assert_problem(client.post("/v1/libraries/shop:recommend", headers={**WRITE, "Accept": "text/csv"},
                               files=files, data=OPTIONS), 406)
    assert_problem(client.post("/v1/libraries/shop:recommend", headers=WRITE, files=files,
                               data={**OPTIONS, "material": "carbon-steel"}), 422, "tangential_coefficient_n_m2")
    assert_problem(client.post("/v1/libraries/shop:recommend", headers=WRITE, files=files,
                               data={**OPTIONS, "max_rpm": "fast"}), 422, "max_rpm")
    assert_problem(client.post("/v1/libraries/shop:recommend", headers=WRITE, files=files,
                               data={**OPTIONS, "colour": "red"}), 422, "colour")
    fctb = (SAMPLES / "freecad" / "5mm_Endmill.fctb").read_bytes()
    body = assert_problem(client.post("/v1/libraries/shop:recommend", headers=WRITE,
                                      files={"library": ("5mm_Endmill.fctb", fctb)}, data=OPTIONS), 422, "library")
    assert "FreeCAD" in body["detail"]


def test_robust_presets_from_the_uncertainty_form_field(client):
    _sync(client)
    r = client.post("/v1/libraries/shop:recommend", headers=WRITE, files={"library": ("shop.json", SAMPLE)},
                    data={**OPTIONS, "uncertainty": json.dumps({"draws": 12, "seed": 2}), "confidence": "0.9",
                          "method": "zoa"})
    assert r.status_code == 200, r.text
    tools = [t for t in r.json()["tools"] if t["status"] == "written"]
    assert tools and all(t["confidence"] == 0.9 and t["robust_depth_limit_m"] <= t["depth_limit_m"] for t in tools)
    assert r.json()["options"]["uncertainty"] == {"draws": 12, "seed": 2} and r.json()["options"]["method"] == "zoa"
    for bad, field in (({"uncertainty": "{not json"}, "uncertainty"), ({"confidence": "0.9"}, "confidence")):
        assert_problem(client.post("/v1/libraries/shop:recommend", headers=WRITE,
                                   files={"library": ("shop.json", SAMPLE)}, data={**OPTIONS, **bad}), 422, field)


def test_presets_by_reference_to_the_file_the_sync_kept(client):
    _sync(client)
    options = {"material": "aluminium-7075", "max_rpm": 24000, "safety_factor": 1.25, "method": "zoa"}
    by_reference = client.post("/v1/libraries/shop:recommend", headers=WRITE, json=options)
    assert by_reference.status_code == 200, by_reference.text
    uploaded = client.post("/v1/libraries/shop:recommend", headers=WRITE, files={"library": ("shop.json", SAMPLE)},
                           data=OPTIONS).json()
    report = by_reference.json()
    assert report["summary"] == uploaded["summary"] == {"written": 2, "skipped": 2, "failed": 0}
    assert report["file"]["sha256"] == uploaded["file"]["sha256"]  # the same file, the same presets
    assert report["library"]["sha256_before"] == hashlib.sha256(SAMPLE).hexdigest()
    # a library whose sync kept no file (FreeCAD, or synced before files were kept) says what to do
    assert_problem(client.post("/v1/libraries/nowhere:recommend", headers=WRITE, json=options), 404)

"""Measurements over HTTP: JSON and file uploads, listing with pages, JSON/HDF5 download, delete."""

from __future__ import annotations

import io
import json

import h5py
import numpy as np
import pytest

from rcsa.measured.store import MeasurementStore
from tests.helpers import REPO

from .conftest import WRITE, assert_problem

DATA = REPO / "tests" / "data" / "measurements"
META = {"spindle_id": "mc1", "direction": "x", "plane": "spindle_nose"}


def _upload(client, name, fields, content=None, headers=WRITE):
    content = content if content is not None else (DATA / name).read_bytes()
    return client.post("/v1/measurements", files={"file": (name, content)}, data=fields, headers=headers)


def test_json_upload_then_get_list_delete(client, store_path):
    doc = json.loads((DATA / "point_receptance.json").read_text())
    r = client.post("/v1/measurements", json=doc, headers=WRITE)
    assert r.status_code == 201, r.text
    info = r.json()
    assert r.headers["location"] == f"/v1/measurements/{info['id']}"
    assert info["kind"] == "point_receptance" and info["spindle_id"] == doc["spindle_id"]
    got = client.get(f"/v1/measurements/{info['id']}").json()
    assert got["frequency_hz"] == doc["frequency_hz"] and got["h"] == doc["h"] and got["p"] == doc["p"]
    assert got["units"]["h"] == "m/N" and got["summary"]["h"]["units"] == "m/N"
    meta_only = client.get(f"/v1/measurements/{info['id']}", params={"data": "false"}).json()
    assert "frequency_hz" not in meta_only and meta_only["id"] == info["id"]
    again = client.post("/v1/measurements", json=got, headers=WRITE)  # an export uploads again
    assert again.status_code == 201 and again.json()["id"] != info["id"]
    assert again.json()["source"]["format"] == "contract_json"

    r = client.delete(f"/v1/measurements/{info['id']}", headers=WRITE)
    assert r.status_code == 200 and r.json() == {"deleted": info["id"]}
    assert_problem(client.get(f"/v1/measurements/{info['id']}"), 404)
    assert_problem(client.delete(f"/v1/measurements/{info['id']}", headers=WRITE), 404)
    assert [m.id for m in MeasurementStore(store_path).list()] == [again.json()["id"]]


@pytest.mark.parametrize(("name", "fields", "kind"), [
    ("direct_frf_um_per_n.csv", {**META, "units": "um/N"}, "direct_frf"),
    ("direct_frf_mag_phase_deg.tsv", {**META, "units": "um/N", "columns": "f,mag,phase", "phase_unit": "deg"},
     "direct_frf"),
    ("direct_frf.frf", META, "direct_frf"),
    ("point_receptance.json", {}, "point_receptance"),
    ("artifact_frfs_accelerance.uff", {**META, "kind": "artifact_frfs", "roles": "h11=1:1,h21=2:1,h22=2:2",
                                       "points_m": "0,0.03",
                                       "artifact": json.dumps({"diameter_m": 0.02, "stickout_m": 0.08})},
     "artifact_frfs"),
    ("tap_synthetic.txt", {**META, "format": "tap", "force_unit": "N", "response_unit": "m/s^2"}, "direct_frf"),
])
def test_file_uploads_of_every_format(client, name, fields, kind):
    r = _upload(client, name, fields)
    assert r.status_code == 201, r.text
    info = r.json()
    assert info["kind"] == kind and info["source"]["file"] == name
    doc = client.get(f"/v1/measurements/{info['id']}").json()
    assert len(doc["frequency_hz"]) == info["n_frequencies"]


def test_csv_agrees_with_the_json_fixture(client):
    csv = _upload(client, "direct_frf_um_per_n.csv", {**META, "units": "um/N"}).json()
    ref = json.loads((DATA / "point_receptance.json").read_text())
    got = client.get(f"/v1/measurements/{csv['id']}").json()
    np.testing.assert_allclose(got["h"]["real"], ref["h"]["real"], rtol=1e-12)


@pytest.mark.parametrize(("name", "content", "fields", "field"), [
    ("broken.uff", b"    -1\n    58\nthis is not a universal file\n    -1\n",
     {**META, "kind": "artifact_frfs", "roles": "h11=1:1", "points_m": "0,0.03",
      "artifact": json.dumps({"diameter_m": 0.02, "stickout_m": 0.08})}, None),
    ("tip.csv", None, META, "units"),
    ("tip.csv", None, {**META, "units": "furlongs"}, "units"),
    ("tip.csv", None, {"direction": "x", "plane": "spindle_nose", "units": "um/N"}, "spindle_id"),
    ("tip.csv", None, {**META, "direction": "z", "units": "um/N"}, "direction"),
    ("tip.dat", None, META, "format"),
    ("tip.csv", None, {**META, "units": "um/N", "colour": "red"}, "colour"),
    ("tip.csv", b"f,re,im\n0,1,2\n10,1,2\n", {**META, "units": "um/N"}, None),
    ("tip.csv", b"\xff\xfe\x00garbage", {**META, "units": "um/N"}, None),
    ("tip.json", b"{not json", {}, "file"),
    ("tip.frf", None, {**META, "points_m": "a,b"}, "points_m"),
    ("tip.frf", None, {**META, "sample_rate_hz": "100"}, "sample_rate_hz"),
])
def test_bad_uploads_are_422_and_store_nothing(client, store_path, name, content, fields, field):
    if content is None:
        content = (DATA / ("direct_frf_um_per_n.csv" if name.endswith((".csv", ".dat")) else "direct_frf.frf")).read_bytes()
    before = MeasurementStore(store_path).list()
    body = assert_problem(_upload(client, name, fields, content), 422, field)
    assert body["errors"][0]["detail"]
    assert MeasurementStore(store_path).list() == before


def test_upload_shape_errors(make_client, store_path):
    with make_client(max_upload_bytes=2048) as client:
        big = (DATA / "direct_frf_um_per_n.csv").read_bytes() * 3
        assert len(big) > 2048
        assert_problem(_upload(client, "tip.csv", {**META, "units": "um/N"}, big), 413, "file")
        r = client.post("/v1/measurements", data={**META}, files={"other": ("x.csv", b"1,2,3")}, headers=WRITE)
        assert_problem(r, 422, "other")
        r = client.post("/v1/measurements", data={**META, "units": "um/N"}, headers=WRITE,
                        files={"ignored": ("", b"")})
        assert_problem(r, 422)
        r = client.post("/v1/measurements", content=b"f,re,im", headers={**WRITE, "content-type": "text/csv"})
        assert_problem(r, 415)
        r = client.post("/v1/measurements", json={"spindle_id": "a", "direction": "x", "plane": "spindle_nose",
                                                  "kind": "direct_frf", "frequency_hz": [1.0, 2.0],
                                                  "h": {"real": [1.0], "imag": [0.0, 1.0]}}, headers=WRITE)
        assert_problem(r, 422, "h.imag")
        r = client.post("/v1/measurements", json={"spindel_id": "a"}, headers=WRITE)
        assert_problem(r, 422, "spindel_id")
        r = client.post("/v1/measurements", content=b"{", headers={**WRITE, "content-type": "application/json"})
        assert_problem(r, 400, "")  # not JSON at all: malformed
        assert MeasurementStore(store_path).list() == []


def test_listing_filters_and_pages(client):
    ids = []
    for i in range(5):
        fields = {**META, "spindle_id": "s-even" if i % 2 == 0 else "s-odd", "units": "um/N"}
        ids.append(_upload(client, "direct_frf_um_per_n.csv", fields).json()["id"])
    page = client.get("/v1/measurements", params={"limit": 2}).json()
    seen = [m["id"] for m in page["items"]]
    while page["next_cursor"]:
        page = client.get("/v1/measurements", params={"limit": 2, "cursor": page["next_cursor"]}).json()
        seen += [m["id"] for m in page["items"]]
    assert seen == ids
    even = client.get("/v1/measurements", params={"spindle_id": "s-even"}).json()
    assert [m["id"] for m in even["items"]] == ids[0::2] and even["next_cursor"] is None
    assert client.get("/v1/measurements", params={"kind": "point_receptance"}).json()["items"] == []
    assert_problem(client.get("/v1/measurements", params={"cursor": "garbage!"}), 422, "cursor")
    assert_problem(client.get("/v1/measurements", params={"limit": 0}), 422, "limit")
    assert_problem(client.get("/v1/measurements", params={"direction": "q"}), 422, "direction")


def test_hdf5_download(client):
    mid = _upload(client, "direct_frf.frf", META).json()["id"]
    r = client.get(f"/v1/measurements/{mid}", headers={"Accept": "application/x-hdf5"})
    assert r.status_code == 200 and r.headers["content-type"] == "application/x-hdf5"
    assert f'filename="{mid}.h5"' in r.headers["content-disposition"]
    with h5py.File(io.BytesIO(r.content), "r") as f:
        assert f.attrs["id"] == mid and f["frf"]["h"].shape[0] == f.attrs["n_frequencies"]
    r = client.get(f"/v1/measurements/{mid}", headers={"Accept": "application/json, application/x-hdf5;q=0.5"})
    assert r.headers["content-type"] == "application/json"
    assert_problem(client.get("/v1/measurements/m-000000000000", headers={"Accept": "application/x-hdf5"}), 404)

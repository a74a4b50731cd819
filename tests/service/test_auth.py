"""API keys: writes need a write key and change nothing otherwise; reads optionally need a key."""

from __future__ import annotations

import json

import pytest

from rcsa.infra.api_keys import KeyFile, KeyRing, hash_key, parse_key_list
from rcsa.measured.store import MeasurementStore
from tests.helpers import REPO

from .conftest import READ, WRITE, assert_problem

DOC = json.loads((REPO / "tests" / "data" / "measurements" / "point_receptance.json").read_text())
CSV = (REPO / "tests" / "data" / "measurements" / "direct_frf_um_per_n.csv").read_bytes()
FORM = {"spindle_id": "mc1", "direction": "x", "plane": "spindle_nose", "units": "um/N"}


def _listing(store_path):
    return [(m.id, m.meta.spindle_id) for m in MeasurementStore(store_path).list()]


@pytest.mark.parametrize(("headers", "status"), [({}, 401), (READ, 403), ({"X-API-Key": "wrong-key-0123456789"}, 401)])
def test_writes_without_a_write_key_change_nothing(client, store_path, headers, status):
    kept = client.post("/v1/measurements", json=DOC, headers=WRITE).json()["id"]
    before = _listing(store_path)
    body = assert_problem(client.post("/v1/measurements", json=DOC, headers=headers), status)
    assert "write" in body["detail"] or "not valid" in body["detail"]
    assert_problem(client.post("/v1/measurements", files={"file": ("t.csv", CSV)}, data=FORM, headers=headers), status)
    assert_problem(client.post("/v1/measurements", content=b"garbage", headers={**headers, "content-type": "text/csv"}),
                   status)  # refused before the body is even looked at
    assert_problem(client.delete(f"/v1/measurements/{kept}", headers=headers), status)
    assert_problem(client.delete("/v1/measurements/m-000000000000", headers=headers), status)
    assert _listing(store_path) == before
    r = client.post("/v1/measurements", json=DOC, headers=headers)
    if status == 401:
        assert r.headers["www-authenticate"].startswith("APIKey")


def test_reads_are_anonymous_by_default_but_can_require_a_key(make_client, assembly):
    with make_client() as client:
        assert client.get("/v1/measurements").status_code == 200
        assert client.get("/v1/measurements", headers=READ).status_code == 200
        assert_problem(client.get("/v1/measurements", headers={"X-API-Key": "not-a-key-at-all-123"}), 401)
    with make_client(anonymous_read=False) as client:
        assert_problem(client.get("/v1/measurements"), 401)
        assert_problem(client.post("/v1/tool-point-frf", json=assembly), 401)
        assert client.get("/v1/measurements", headers=READ).status_code == 200
        assert client.get("/v1/measurements", headers=WRITE).status_code == 200
        assert client.post("/v1/tool-point-frf", json=assembly, headers=READ).status_code == 200
        assert client.get("/healthz").status_code == 200 and client.get("/metrics").status_code == 200


def test_keys_from_the_key_file_work_and_revocation_takes_effect(make_client, store_path):
    with make_client(api_keys="") as client:  # no environment keys at all
        assert_problem(client.post("/v1/measurements", json=DOC, headers=WRITE), 401)
        keys = KeyFile.in_store(store_path)
        record, secret = keys.create("write", "test")
        assert secret.startswith("rcsa_") and len(secret) >= 40
        assert secret not in (store_path / "api-keys.json").read_text()
        assert hash_key(secret) in (store_path / "api-keys.json").read_text()
        r = client.post("/v1/measurements", json=DOC, headers={"X-API-Key": secret})
        assert r.status_code == 201, r.text
        read_record, read_secret = keys.create("read")
        assert_problem(client.post("/v1/measurements", json=DOC, headers={"X-API-Key": read_secret}), 403)
        keys.revoke(record.id)
        assert_problem(client.post("/v1/measurements", json=DOC, headers={"X-API-Key": secret}), 401)
        assert [k.id for k in keys.list()] == [read_record.id]
        assert [k.id for k in keys.list(include_revoked=True)] == [record.id, read_record.id]


def test_key_parsing_and_ring():
    entries = parse_key_list(f"abcdefghijklmnop:write, sha256:{hash_key('qrstuvwxyz0123456')}:read")
    ring = KeyRing(entries)
    assert ring.authenticate("abcdefghijklmnop").scope == "write"
    assert ring.authenticate("qrstuvwxyz0123456").scope == "read"
    assert ring.authenticate("abcdefghijklmnoq") is None and ring.authenticate("") is None
    for bad in ("short:write", "abcdefghijklmnop:admin", "abcdefghijklmnop", "sha256:12:read"):
        with pytest.raises(ValueError, match="RCSA_API_KEYS"):
            parse_key_list(bad)


def _operations(spec):
    for path, ops in spec["paths"].items():
        for method, op in ops.items():
            if "security" in op:
                yield method.upper(), path.replace("{measurement_id}", "m-0123456789ab").replace(
                    "{job_id}", "j-0").replace("{library_id}", "lib-x"), op["security"]


@pytest.mark.parametrize("anonymous_read", [True, False])
def test_openapi_security_says_which_operations_need_a_key(make_client, anonymous_read):
    """Optional security ([{}, {"APIKey": []}]) exactly where an anonymous call gets past the key check."""
    with make_client(anonymous_read=anonymous_read) as client:
        operations = list(_operations(client.get("/openapi.json").json()))
        assert len(operations) > 20
        for method, path, security in operations:
            optional = {} in security
            assert {"APIKey": []} in security, (method, path)
            r = client.request(method, path, json={})  # no key
            assert (r.status_code != 401) == optional, (method, path, security, r.status_code)
            write = (method == "DELETE" or (method, path) == ("POST", "/v1/measurements") or ":sync" in path
                     or ":recommend" in path)
            assert optional == (anonymous_read and not write), (method, path)

"""Jobs are private: readable (status, result, listing) only by the key or the job token that made them."""

from __future__ import annotations

import time

from .conftest import GRID, READ, WRITE, assert_problem

OTHER_TOKEN = "another-callers-token-0123456789abcdefghij"


def _batch(assembly: dict, n: int = 2) -> dict:
    return {"frequency": GRID, "spindle": assembly["spindle"],
            "combinations": [{"id": f"T{i}", "holder": assembly["holder"], "tool": assembly["tool"],
                              "joints": assembly["joints"]} for i in range(n)]}


def _finish(client, location: str, headers: dict) -> dict:
    for _ in range(3000):  # attempts: a loaded machine is slow
        job = client.get(location, headers=headers).json()
        if job["status"] in ("succeeded", "failed"):
            return job
        time.sleep(0.05)
    raise AssertionError(job)


def test_an_anonymous_job_is_read_with_its_token_only(client, assembly):
    client.headers.pop("X-Job-Token")  # an anonymous caller without a token yet
    r = client.post("/v1/tool-point-frf/batch", json=_batch(assembly), headers={"Prefer": "respond-async"})
    assert r.status_code == 202
    token = r.headers["x-job-token"]
    assert r.json()["job_token"] == token and len(token) >= 32
    mine = {"X-Job-Token": token}
    job = _finish(client, r.headers["location"], mine)
    assert job["status"] == "succeeded" and "job_token" not in job  # handed out once, never shown again
    assert client.get(job["result_url"], headers=mine).json()["summary"] == {"ok": 2, "error": 0}
    for who in ({}, {"X-Job-Token": OTHER_TOKEN}, READ, WRITE):
        for url in (r.headers["location"], job["result_url"]):
            body = assert_problem(client.get(url, headers=who), 404)
            assert job["id"] in body["detail"]  # as for a job that does not exist
    # a second job under the same token: listed together, newest first
    second = client.post("/v1/tool-point-frf/batch", json=_batch(assembly, 1),
                         headers={"Prefer": "respond-async", **mine})
    assert second.headers["x-job-token"] == token
    listed = client.get("/v1/jobs", headers=mine).json()
    assert [j["id"] for j in listed["items"]] == [second.json()["id"], job["id"]]
    assert listed["next_cursor"] is None
    assert client.get("/v1/jobs").json() == {"items": [], "next_cursor": None}
    assert client.get("/v1/jobs", headers={"X-Job-Token": OTHER_TOKEN}).json()["items"] == []


def test_a_keyed_job_is_the_keys_alone(client, assembly):
    r = client.post("/v1/tool-point-frf/batch", json=_batch(assembly), headers={"Prefer": "respond-async", **READ})
    assert r.status_code == 202 and "x-job-token" not in r.headers and "job_token" not in r.json()
    job = _finish(client, r.headers["location"], READ)
    assert client.get(job["result_url"], headers=READ).status_code == 200
    for who in ({}, WRITE, {"X-Job-Token": OTHER_TOKEN}):
        assert_problem(client.get(r.headers["location"], headers=who), 404)
        assert_problem(client.get(job["result_url"], headers=who), 404)
    assert [j["id"] for j in client.get("/v1/jobs", headers=READ).json()["items"]] == [job["id"]]
    assert client.get("/v1/jobs", headers=WRITE).json()["items"] == []


def test_the_list_of_ones_jobs_is_paged(client, assembly):
    ids = [client.post("/v1/tool-point-frf/batch", json=_batch(assembly, 1),
                       headers={"Prefer": "respond-async", **READ}).json()["id"] for _ in range(3)]
    seen, cursor = [], None
    for _ in range(5):
        page = client.get("/v1/jobs", params={"limit": 1, **({"cursor": cursor} if cursor else {})},
                          headers=READ).json()
        assert set(page) == {"items", "next_cursor"} and len(page["items"]) <= 1
        seen += [j["id"] for j in page["items"]]
        cursor = page["next_cursor"]
        if cursor is None:
            break
    assert seen == ids[::-1]
    assert_problem(client.get("/v1/jobs", params={"cursor": "not-a-cursor"}, headers=READ), 422, "cursor")


def test_a_token_that_is_not_one_is_refused(client, assembly):
    r = client.post("/v1/tool-point-frf/batch", json=_batch(assembly), headers={"Prefer": "respond-async",
                                                                             "X-Job-Token": "short"})
    assert_problem(r, 422, "X-Job-Token")


def test_the_openapi_documents_the_job_token(client):
    doc = client.get("/openapi.json").json()
    for path, method in (("/v1/jobs", "get"), ("/v1/jobs/{job_id}", "get"), ("/v1/jobs/{job_id}/result", "get"),
                         ("/v1/tool-point-frf/batch", "post"), ("/v1/tool-point-frf", "post")):
        names = [p["name"] for p in doc["paths"][path][method].get("parameters", [])]
        assert "X-Job-Token" in names, (path, names)
    accepted = doc["paths"]["/v1/tool-point-frf/batch"]["post"]["responses"]["202"]
    assert {"Location", "X-Job-Token"} <= set(accepted["headers"])

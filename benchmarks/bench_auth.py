"""Credentials against a real ``rcsa serve --workers 2``: every write operation, and every job read.

Run: ``.venv/bin/python benchmarks/bench_auth.py``. The service runs with a write key and a read
key from ``RCSA_API_KEYS``; a second write key is made with ``rcsa keys create`` and then revoked
(``rcsa keys revoke``), as an operator would. Then:

* **writes** — every operation the OpenAPI marks as needing a write key (its ``security``), with
  a valid body each, is sent with each of the credentials of :func:`credentials`: none, an empty
  header, the read key, the revoked key, forged and mangled keys (random, a valid key with one
  character changed, cut short, padded, upper-cased, its SHA-256 hash, 10 000 characters), and the
  valid write key in places that are not the ``X-API-Key`` header (a query parameter,
  ``Authorization: Bearer``, a cookie). Every answer must be 401 or 403 (a bypass is any 2xx),
  and the store must be exactly as before (measurements, libraries and their revisions, keys).
* **jobs** — a job of the write key, one of the read key and two anonymous ones (two job
  tokens) are read (status, result, and the listing of one's jobs) with every credential that
  did not start them: the other keys, no credential, the other token, forged and mangled tokens.
  A bypass is any answer that shows the job (a 2xx on its status or result, or its id in a
  listing).

Results go to ``benchmarks/results/auth.json``: cases, answers by status, bypasses (0), 5xx (0).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import secrets
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import httpx

from _service import REPO, rcsa, start_service, stop_service
from record import load_average, write

WRITE_KEY = "auth-bench-write-key-0123456789abcdef"
READ_KEY = "auth-bench-read-key-0123456789abcdef"
DOC = json.loads((REPO / "tests" / "data" / "measurements" / "point_receptance.json").read_text())
LIBRARY = (REPO / "examples" / "fusion-library.json").read_bytes()
SYNC_FORM = {"spindle": json.dumps({"segments": [{"length_m": 0.07, "outer_diameter_m": 0.09, "material": "steel"}],
                                    "bearings": [{"position_m": 0.05, "stiffness_n_m": 2e8}]}),
             "frequency": json.dumps({"start_hz": 100, "stop_hz": 3000, "step_hz": 10})}
RECOMMEND = {"material": "aluminium-7075", "max_rpm": "24000"}


def _rcsa(store: Path, *args: str) -> str:
    done = rcsa(store, *args)
    done.check_returncode()
    return done.stdout.strip()


def credentials(valid: str, read: str, revoked: str) -> list[tuple[str, dict[str, str], dict[str, str]]]:
    """(label, headers, query) that must not pass as the write key ``valid``."""
    mangled = valid[:-1] + ("A" if valid[-1] != "A" else "B")
    out = [("none", {}, {}), ("empty header", {"X-API-Key": ""}, {}), ("read key", {"X-API-Key": read}, {}),
           ("revoked write key", {"X-API-Key": revoked}, {}),
           ("one character changed", {"X-API-Key": mangled}, {}), ("cut short", {"X-API-Key": valid[:-3]}, {}),
           ("padded", {"X-API-Key": valid + "x"}, {}), ("upper-cased", {"X-API-Key": valid.upper()}, {}),
           ("its SHA-256", {"X-API-Key": hashlib.sha256(valid.encode()).hexdigest()}, {}),
           ("sha256: form", {"X-API-Key": "sha256:" + hashlib.sha256(valid.encode()).hexdigest()}, {}),
           ("10 000 characters", {"X-API-Key": "k" * 10_000}, {}),
           ("in the query", {}, {"api_key": valid}), ("as a bearer token", {"Authorization": f"Bearer {valid}"}, {}),
           ("as a cookie", {"Cookie": f"X-API-Key={valid}"}, {}),
           ("in another header", {"X-Api-Token": valid}, {}),
           ("job token instead of a key", {"X-Job-Token": secrets.token_urlsafe(32)}, {})]
    out += [(f"forged {i}", {"X-API-Key": f"rcsa_{secrets.token_urlsafe(30)}"}, {}) for i in range(8)]
    return out


def _state(base: str, store: Path) -> dict:
    measurements = httpx.get(base + "/v1/measurements", params={"limit": 1000}, timeout=60).json()["items"]
    libraries = httpx.get(base + "/v1/libraries", params={"limit": 1000}, timeout=60).json()["items"]
    return {"measurements": sorted(m["id"] for m in measurements),
            "libraries": sorted((lib["id"], lib["revision"]) for lib in libraries),
            "keys": _rcsa(store, "keys", "list")}


def writes(base: str, mid: str) -> list[tuple[str, str, str, dict]]:
    """(label, method, path, request keyword arguments) of every write operation, each valid."""
    return [("upload JSON", "POST", "/v1/measurements", {"json": DOC}),
            ("upload file", "POST", "/v1/measurements", {"files": {"file": ("m.json", json.dumps(DOC).encode())}}),
            ("delete measurement", "DELETE", f"/v1/measurements/{mid}", {}),
            ("sync library", "POST", "/v1/libraries/auth:sync", {"files": {"library": ("l.json", LIBRARY)},
                                                                  "data": SYNC_FORM}),
            ("delete library", "DELETE", "/v1/libraries/auth", {}),
            ("recommend (file)", "POST", "/v1/libraries/auth:recommend", {"files": {"library": ("l.json", LIBRARY)},
                                                                          "data": RECOMMEND}),
            ("recommend (by reference)", "POST", "/v1/libraries/auth:recommend",
             {"json": {"material": "aluminium-7075", "max_rpm": 24000}})]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" / "auth.json")
    args = parser.parse_args()
    load_start = load_average()
    rows: list[dict] = []
    with tempfile.TemporaryDirectory() as tmp:
        store = Path(tmp) / "store"
        proc, base, log = start_service(Path(tmp), env={"RCSA_API_KEYS": f"{WRITE_KEY}:write,{READ_KEY}:read"})
        try:
            revoked = _rcsa(store, "keys", "create", "--scope", "write", "--label", "revoked").splitlines()[0]
            w = {"X-API-Key": WRITE_KEY}
            with httpx.Client(base_url=base, timeout=120) as client:
                assert client.post("/v1/measurements", json=DOC, headers={"X-API-Key": revoked}).status_code == 201
                _rcsa(store, "keys", "revoke", revoked)
                mid = client.post("/v1/measurements", json=DOC, headers=w).json()["id"]
                assert client.post("/v1/libraries/auth:sync", files={"library": ("l.json", LIBRARY)}, data=SYNC_FORM,
                                   headers=w).status_code in (200, 201)
                # every operation the OpenAPI says needs a write key is probed
                doc = client.get("/openapi.json").json()
                declared = {f"{m.upper()} {p}" for p, ops in doc["paths"].items() for m, op in ops.items()
                            if op.get("security") == [{"APIKey": []}]}
                probed = {f"{m} {p}" for _, m, p, _ in writes(base, mid)}
                templated = {f"{m.upper()} {p}" for p, ops in doc["paths"].items() for m in ops
                             for q in probed if _matches(f"{m.upper()} {p}", q)}
                assert declared <= templated, declared - templated
                state = _state(base, store)
                for label, method, path, kwargs in writes(base, mid):
                    for cred, headers, query in credentials(WRITE_KEY, READ_KEY, revoked):
                        r = client.request(method, path, headers=headers, params=query, **kwargs)
                        rows.append({"probe": "write", "operation": label, "credential": cred, "status": r.status_code,
                                     "bypass": 200 <= r.status_code < 300})
                unchanged = _state(base, store) == state
                rows += jobs(client, revoked)
        finally:
            stop_service(proc)
        tracebacks = log.read_text().count("Traceback")
    by_status = Counter(str(r["status"]) for r in rows)
    bypasses = [r for r in rows if r["bypass"]]
    server_errors = [r for r in rows if r["status"] >= 500]
    figures = {"cases": len(rows),
              "write_cases": sum(r["probe"] == "write" for r in rows),
              "job_cases": sum(r["probe"] == "job" for r in rows), "operations_probed": sorted(declared),
              "by_status": dict(sorted(by_status.items())), "bypasses": bypasses, "server_errors": server_errors,
              "store_unchanged": unchanged, "tracebacks": tracebacks, "rows": rows}
    write("auth", figures, load_start=load_start, out=args.out)
    print(f"{len(rows)} cases ({figures['write_cases']} on {len(declared)} write operations, {figures['job_cases']} job "
          f"reads): {dict(sorted(by_status.items()))}; bypasses {len(bypasses)}, 5xx {len(server_errors)}, store "
          f"unchanged: {unchanged}, tracebacks {tracebacks}; load average {load_start[0]:.1f}")
    sys.exit(1 if bypasses or server_errors or not unchanged or tracebacks else 0)


def _matches(template: str, concrete: str) -> bool:
    """Whether ``METHOD /path/{x}`` matches ``METHOD /path/value``."""
    t_method, t_path = template.split(" ", 1)
    c_method, c_path = concrete.split(" ", 1)
    t, c = t_path.split("/"), c_path.split("/")
    return t_method == c_method and len(t) == len(c) and all(
        a == b or (a.startswith("{") and (a.split("}")[1] == "" or b.endswith(a.split("}")[1]))) for a, b in zip(t, c, strict=True))


def jobs(client: httpx.Client, revoked: str) -> list[dict]:
    """Read each job with every credential that did not start it."""
    batch = {"frequency": {"start_hz": 100, "stop_hz": 2000, "step_hz": 10}, "spindle": json.loads(SYNC_FORM["spindle"]),
             "combinations": [{"id": "T1", "holder": {"segments": [{"length_m": 0.05, "outer_diameter_m": 0.05,
                                                                    "inner_diameter_m": 0.012, "material": "steel"}]},
                               "tool": {"diameter_m": 0.012, "shank_diameter_m": 0.012, "overall_length_m": 0.08,
                                        "flute_length_m": 0.03, "stickout_m": 0.045, "material": "carbide"}}]}
    async_ = {"Prefer": "respond-async"}
    owners = {"write key": {"X-API-Key": WRITE_KEY}, "read key": {"X-API-Key": READ_KEY}}
    made = {}
    for name, headers in owners.items():
        r = client.post("/v1/tool-point-frf/batch", json=batch, headers={**async_, **headers})
        made[name] = (r.json()["id"], headers)
    for name in ("token A", "token B"):
        r = client.post("/v1/tool-point-frf/batch", json=batch, headers=async_)
        made[name] = (r.json()["id"], {"X-Job-Token": r.headers["x-job-token"]})
    for job_id, headers in made.values():  # each finished, as its owner sees it
        for _ in range(600):
            if client.get(f"/v1/jobs/{job_id}", headers=headers).json()["status"] in ("succeeded", "failed"):
                break
            time.sleep(0.1)
    others = [("none", {}), ("revoked key", {"X-API-Key": revoked}), ("forged token", {"X-Job-Token": secrets.token_urlsafe(32)}),
              ("malformed token", {"X-Job-Token": "x"}), ("forged key", {"X-API-Key": "rcsa_" + secrets.token_urlsafe(30)})]
    rows = []
    for owner, (job_id, own) in made.items():
        creds = [(name, h) for name, (_, h) in made.items() if name != owner] + others
        for cred, headers in creds:
            for what, url in (("status", f"/v1/jobs/{job_id}"), ("result", f"/v1/jobs/{job_id}/result")):
                r = client.get(url, headers=headers)
                rows.append({"probe": "job", "operation": f"{what} of the {owner}'s job", "credential": cred,
                             "status": r.status_code, "bypass": 200 <= r.status_code < 300})
            r = client.get("/v1/jobs", headers=headers)
            shown = r.status_code == 200 and job_id in {j["id"] for j in r.json()["items"]}
            rows.append({"probe": "job", "operation": f"list showing the {owner}'s job", "credential": cred,
                         "status": r.status_code, "bypass": shown})
        assert client.get(f"/v1/jobs/{job_id}/result", headers=own).status_code == 200  # its owner reads it
    return rows


if __name__ == "__main__":
    main()

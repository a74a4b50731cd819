"""Crashes: idempotent uploads and jobs while workers of a real ``rcsa serve --workers 2`` are killed.

Run: ``.venv/bin/python benchmarks/bench_crash.py`` (``--uploads 210 --jobs 20``). Client threads
upload measurements (each its own spindle id and numbers, each with its own
``Idempotency-Key``) and submit batch jobs, retrying on a broken connection, a 5xx or a 409
(the first attempt still running) until the upload answers 201 and the job has finished; a
killer thread meanwhile SIGKILLs a random worker every ``--kill-every`` seconds (uvicorn's
supervisor starts a new one), among those up for ``--min-age`` seconds (a worker killed while
it still starts would leave a service that answers nothing). Then every upload is looked up: *lost* (no measurement of its
spindle id), *duplicated* (more than one), *unreadable* (its GET fails, or its numbers are
not those sent, bit for bit), and every job must have succeeded with all its results;
``rcsa store check`` must pass. Results go to ``benchmarks/results/crash.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx

from _service import REPO, rcsa, start_service, stop_service, workers
from record import load_average, write

KEY = "crash-bench-write-key-0123456789abcdef"
DOC = json.loads((REPO / "tests" / "data" / "measurements" / "point_receptance.json").read_text())
BATCH = {"frequency": {"start_hz": 100, "stop_hz": 2000, "step_hz": 5},
         "spindle": {"segments": [{"length_m": 0.2, "outer_diameter_m": 0.07, "material": "steel"}],
                     "bearings": [{"position_m": 0.05, "stiffness_n_m": 2e8}, {"position_m": 0.18, "stiffness_n_m": 2e8}]},
         "combinations": [{"id": f"T{i}", "holder": {"segments": [{"length_m": 0.05, "outer_diameter_m": 0.05,
                                                                  "inner_diameter_m": 0.012, "material": "steel"}]},
                           "tool": {"diameter_m": 0.012, "shank_diameter_m": 0.012, "overall_length_m": 0.08,
                                    "flute_length_m": 0.03, "stickout_m": 0.035 + 0.0002 * i, "material": "carbide"}}
                          for i in range(80)]}


def _document(i: int) -> dict:
    doc = json.loads(json.dumps(DOC))
    doc["spindle_id"] = f"crash-{i:04d}"
    scale = 1.0 + i * 1e-6  # numbers of its own: a mix-up would show
    for value in doc.values():
        if isinstance(value, dict) and "real" in value:
            value["real"] = [x * scale for x in value["real"]]
    return doc


def _retry(call, attempts: int = 400) -> httpx.Response:
    last = None
    for _ in range(attempts):
        try:
            r = call()
        except httpx.TransportError:
            time.sleep(0.2)
            continue
        if r.status_code < 500 and r.status_code != 409:
            return r
        last = r
        time.sleep(0.2)
    raise RuntimeError(f"no answer after {attempts} attempts: {last.status_code if last else 'transport errors'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--uploads", type=int, default=210)
    parser.add_argument("--jobs", type=int, default=20)
    parser.add_argument("--clients", type=int, default=3)
    parser.add_argument("--kill-every", type=float, default=0.5)
    parser.add_argument("--min-age", type=float, default=3.0, help="Seconds a worker lives before it may be killed.")
    parser.add_argument("--seed", type=int, default=30)
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" / "crash.json")
    args = parser.parse_args()
    load_start = load_average()
    rng = random.Random(args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        proc, base, log = start_service(Path(tmp), env={"RCSA_API_KEYS": f"{KEY}:write", "RCSA_JOB_POLL_S": "0.2",
                                                        "RCSA_JOB_STALE_S": "5", "RCSA_JOB_MAX_ATTEMPTS": "50",
                                                        "RCSA_JOB_MAX_UNFINISHED_PER_CALLER": "100"})
        headers = {"X-API-Key": KEY}
        todo = list(range(args.uploads))
        lock = threading.Lock()
        answers: dict[int, dict] = {}
        job_ids: list[str] = []
        done = threading.Event()
        kills: list[dict] = []

        first_seen: dict[int, float] = {}

        def killer() -> None:
            # Only a worker up for --min-age s is killed: one killed while it still imports never
            # serves, and with both workers so the service would answer nothing (no test at all).
            while not done.wait(args.kill_every * (0.5 + rng.random())):
                now = time.monotonic()
                alive = [pid for pid in workers(proc) if now - first_seen.setdefault(pid, now) >= args.min_age]
                if alive:
                    pid = rng.choice(alive)
                    try:
                        os.kill(pid, signal.SIGKILL)
                        kills.append({"pid": pid, "t": time.time()})
                    except ProcessLookupError:
                        pass

        def uploader() -> None:
            with httpx.Client(base_url=base, timeout=120, headers=headers) as client:
                while True:
                    with lock:
                        if not todo:
                            return
                        i = todo.pop()
                    key = {"Idempotency-Key": f"crash-{args.seed}-{i}"}
                    if i < args.jobs:  # a batch job too, of its own (the same batch again would be the same job)
                        own = {**BATCH, "combinations": [{**c, "id": f"J{i}-{c['id']}"} for c in BATCH["combinations"]]}
                        r = _retry(lambda key=key, own=own: client.post("/v1/tool-point-frf/batch", json=own,
                                                                        headers={**key, "Prefer": "respond-async"}))
                        with lock:
                            job_ids.append(r.json()["id"])
                    r = _retry(lambda i=i: client.post("/v1/measurements", json=_document(i),
                                                       headers={"Idempotency-Key": f"crash-{args.seed}-m{i}"}))
                    answers[i] = {"status": r.status_code, "id": r.json().get("id")}

        t0 = time.monotonic()
        killing = threading.Thread(target=killer)
        killing.start()
        clients = [threading.Thread(target=uploader) for _ in range(args.clients)]
        try:
            for t in clients:
                t.start()
            for t in clients:
                t.join()
            with httpx.Client(base_url=base, timeout=120, headers=headers) as client:
                finished = {}
                for job_id in job_ids:
                    for _ in range(3000):
                        job = _retry(lambda job_id=job_id: client.get(f"/v1/jobs/{job_id}")).json()
                        if job["status"] in ("succeeded", "failed"):
                            break
                        time.sleep(0.2)
                    result = _retry(lambda job=job: client.get(job["result_url"])) if job.get("result_url") else None
                    finished[job_id] = {"status": job["status"], "attempts": job["attempts"],
                                        "summary": result.json()["summary"] if result is not None else None}
            done.set()
            killing.join()
            wall = time.monotonic() - t0
            with httpx.Client(base_url=base, timeout=120) as client:
                items = _retry(lambda: client.get("/v1/measurements", params={"limit": 1000})).json()["items"]
                by_spindle: dict[str, list[str]] = {}
                for m in items:
                    by_spindle.setdefault(m["spindle_id"], []).append(m["id"])
                lost, duplicated, unreadable = [], [], []
                for i in range(args.uploads):
                    ids = by_spindle.get(f"crash-{i:04d}", [])
                    if not ids:
                        lost.append(i)
                        continue
                    if len(ids) > 1:
                        duplicated.append(i)
                    got = _retry(lambda ids=ids: client.get(f"/v1/measurements/{ids[0]}"))
                    sent = _document(i)
                    if got.status_code != 200 or got.json()["h"] != sent["h"] or ids[0] != answers[i]["id"]:
                        unreadable.append(i)
        finally:
            done.set()
            stop_service(proc)
        check = rcsa(Path(tmp) / "store", "store", "check")
    jobs_bad = {j: f for j, f in finished.items()
                if f["status"] != "succeeded" or f["summary"] != {"ok": len(BATCH["combinations"]), "error": 0}}
    figures = {"uploads": args.uploads, "jobs": len(job_ids),
              "workers_killed": len(kills), "kill_every_s": args.kill_every, "min_age_s": args.min_age, "wall_seconds": round(wall, 1), "lost": lost, "duplicated": duplicated,
              "unreadable": unreadable, "jobs_not_complete": jobs_bad,
              "job_attempts": sorted(f["attempts"] for f in finished.values()), "store_check_exit": check.returncode,
              "store_check": check.stdout[-2000:]}
    write("crash", figures, load_start=load_start, out=args.out)
    print(f"{args.uploads} idempotent uploads and {len(job_ids)} batch jobs, {len(kills)} workers killed in "
          f"{wall:.0f} s: lost {len(lost)}, duplicated {len(duplicated)}, unreadable {len(unreadable)}, jobs not "
          f"complete {len(jobs_bad)}; rcsa store check exit {check.returncode}; load average "
          f"{load_start[0]:.1f}")
    sys.exit(1 if lost or duplicated or unreadable or jobs_bad or check.returncode else 0)


if __name__ == "__main__":
    main()

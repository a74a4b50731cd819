"""Soak: worker memory of a real ``rcsa serve --workers 2`` under a long mixed load.

Run: ``nice -n 5 .venv/bin/python benchmarks/bench_soak.py --minutes 15`` (``--minutes 2`` for a
look). The service is started as a user starts it (``rcsa serve``, a temporary store, a write
key); a stored spindle (RA-1's analytical nose receptance, 5 000 lines) and a synced Fusion
library are set up first. Then ``--clients`` client threads loop over a mix, each request chosen
at random (seed ``--seed``):

* hybrid predictions on the stored spindle, 5 000 lines: the same tool again (40 %) or a tool
  never asked before (a new stickout each time; 15 %);
* analytical RA-1 predictions at 1 000 lines (10 %);
* batches of 20 tools answered at once (5 %) and of 60 tools as jobs, polled and fetched (3 %);
* stability lobes of a stored library's tool, by reference (5 %);
* reads: the measurement list and one measurement, the library's results and one tool, the
  caller's job list (15 %);
* refused requests: a 1 MiB body of tiny items, malformed JSON, a body over a bound (7 %).

Every ``--sample-s`` seconds the resident memory (``VmRSS``) of each worker is recorded. The
figures: each worker's RSS at the start of the load, its highest, and at the end; the growth
over the last third of the run against the first two thirds (a worker whose memory levels off
grows by ~0 in the last third); the requests by kind and status (any 5xx is reported).
Results go to ``benchmarks/results/soak.json`` (``--out``).
"""

from __future__ import annotations

import argparse
import json
import random
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path

import httpx

from _service import REPO, memory_mb, start_service, stop_service, workers
from rcsa.app.measurements import demo_measurement
from rcsa.measured.importers import measurement_to_contract
from rcsa.reference import ra1
from record import load_average, write

KEY = "soak-write-key-0123456789abcdef0123"
GRID = {"start_hz": 1.0, "stop_hz": 5000.0, "step_hz": 1.0}
SMALL = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
LIBRARY = (REPO / "examples" / "fusion-library.json").read_bytes()
TOOL = "00000000-0000-4000-8000-000000000101"
CUT = {"tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": 0.5, "milling": "down",
       "spindle_speed_rpm": {"start": 4000, "stop": 24000, "count": 400}}


def _setup(base: str) -> str:
    spindle = measurement_to_contract(demo_measurement(GRID))
    spindle = {k: v for k, v in spindle.items() if k not in ("id", "source", "created_utc")}
    r = httpx.post(base + "/v1/measurements", json=spindle, headers={"X-API-Key": KEY}, timeout=120)
    assert r.status_code == 201, r.text
    mid = str(r.json()["id"])
    a = ra1()
    form = {"spindle": json.dumps(a["spindle"]), "frequency": json.dumps(SMALL), "joints": json.dumps(a["joints"])}
    r = httpx.post(base + "/v1/libraries/soak:sync", files={"library": ("soak.json", LIBRARY)}, data=form,
                   headers={"X-API-Key": KEY}, timeout=300)
    assert r.status_code in (200, 201), r.text
    return mid


class Mix:
    """The requests of the soak (module docstring), one chosen at random per call."""

    def __init__(self, base: str, mid: str, seed: int) -> None:
        self.base, self.mid = base, mid
        self.rng = random.Random(seed)
        self.hybrid = {**ra1(GRID), "spindle": {"measurement_id": mid}}
        self.counter = iter(range(10**9))
        tool = ra1(SMALL)
        self.combo = {"holder": tool["holder"], "joints": tool["joints"], "tool": tool["tool"]}
        self.tiny = b'{"frequency": {"start_hz": 1, "stop_hz": 2, "step_hz": 1}, "spindle": {}, "combinations": [' + \
            b'{"a":1},' * (2**20 // 8) + b'{}]}'
        self.kinds = [("hybrid same tool", 40), ("hybrid new tool", 15), ("analytical", 10), ("batch now", 5),
                      ("batch job", 3), ("lobes by reference", 5), ("reads", 15), ("refused", 7)]

    def batch(self, n: int) -> dict:
        return {"frequency": SMALL, "spindle": {"measurement_id": self.mid},
                "combinations": [{"id": f"T{i}", **self.combo, "tool": {**self.combo["tool"],
                                                                        "stickout_m": 0.04 + 0.0005 * i}}
                                 for i in range(n)]}

    def one(self, client: httpx.Client) -> list[tuple[str, int]]:
        kind = self.rng.choices([k for k, _ in self.kinds], [w for _, w in self.kinds])[0]
        out: list[tuple[str, int]] = []

        def note(r: httpx.Response) -> httpx.Response:
            out.append((kind, r.status_code))
            return r

        if kind == "hybrid same tool":
            note(client.post("/v1/tool-point-frf", json=self.hybrid))
        elif kind == "hybrid new tool":
            stickout = 0.045 + 0.04 * (next(self.counter) % 100_000) / 100_000
            note(client.post("/v1/tool-point-frf", json={**self.hybrid, "tool": {**self.hybrid["tool"],
                                                                                  "stickout_m": stickout}}))
        elif kind == "analytical":
            note(client.post("/v1/tool-point-frf", json=ra1(SMALL)))
        elif kind == "batch now":
            note(client.post("/v1/tool-point-frf/batch", json=self.batch(20)))
        elif kind == "batch job":
            r = note(client.post("/v1/tool-point-frf/batch", json=self.batch(60), headers={"Prefer": "respond-async"}))
            if r.status_code == 202:
                token = {"X-Job-Token": r.headers["x-job-token"]}
                for _ in range(600):
                    job = client.get(r.headers["location"], headers=token).json()
                    if job.get("status") in ("succeeded", "failed"):
                        break
                    time.sleep(0.2)
                if job.get("result_url"):
                    note(client.get(job["result_url"], headers=token))
                note(client.get("/v1/jobs", headers=token))
        elif kind == "lobes by reference":
            note(client.post("/v1/stability-lobes", json={**CUT, "library_tool": {"library_id": "soak",
                                                                                   "tool_id": TOOL}}))
        elif kind == "reads":
            note(client.get("/v1/measurements"))
            note(client.get(f"/v1/measurements/{self.mid}"))
            note(client.get("/v1/libraries/soak/results", params={"tool_point": "h"}))
            note(client.get(f"/v1/libraries/soak/tools/{TOOL}"))
        else:
            note(client.post("/v1/tool-point-frf/batch", content=self.tiny, headers={"content-type": "application/json"}))
            note(client.post("/v1/tool-point-frf", content=b'{"frequency": ', headers={"content-type": "application/json"}))
            note(client.post("/v1/tool-point-frf", json={**ra1(SMALL), "tool": {**ra1()["tool"], "stickout_m": 22.0}}))
        return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--minutes", type=float, default=15.0)
    parser.add_argument("--clients", type=int, default=2)
    parser.add_argument("--sample-s", type=float, default=10.0)
    parser.add_argument("--seed", type=int, default=30)
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" / "soak.json")
    args = parser.parse_args()
    load_start = load_average()
    with tempfile.TemporaryDirectory() as tmp:
        proc, base, log = start_service(Path(tmp), env={"RCSA_API_KEYS": f"{KEY}:write", "RCSA_JOB_POLL_S": "0.2"})
        try:
            mid = _setup(base)
            pids = workers(proc)
            samples: list[dict] = []
            counts: Counter = Counter()
            stop = threading.Event()
            t0 = time.monotonic()

            def sample() -> None:
                samples.append({"t_s": round(time.monotonic() - t0, 1),
                                "rss_mb": {str(p): round(memory_mb(p).get("rss_mb", float("nan")), 1)
                                           for p in workers(proc)}})

            def client_loop(k: int) -> None:
                mix = Mix(base, mid, args.seed + k)
                with httpx.Client(base_url=base, timeout=300) as client:
                    while not stop.is_set():
                        try:
                            for kind, status in mix.one(client):
                                counts[f"{kind}: {status}"] += 1
                        except httpx.TransportError as exc:
                            counts[f"transport error: {type(exc).__name__}"] += 1

            sample()
            threads = [threading.Thread(target=client_loop, args=(k,)) for k in range(args.clients)]
            for t in threads:
                t.start()
            while time.monotonic() - t0 < args.minutes * 60:
                time.sleep(args.sample_s)
                sample()
                last = samples[-1]
                print(f"{last['t_s']:7.0f} s  " + "  ".join(f"{mb:6.0f} MB" for mb in last["rss_mb"].values())
                      + f"   {sum(counts.values())} requests", flush=True)
            stop.set()
            for t in threads:
                t.join(timeout=600)
            sample()
            same_workers = workers(proc) == pids
        finally:
            stop_service(proc)
        text = log.read_text()
        tracebacks = text.count("Traceback")
        first_traceback = text[max(text.find("Traceback") - 300, 0):text.find("Traceback") + 4000] if tracebacks else None
    per_worker: dict[str, dict[str, float]] = {}
    for pid in pids:
        series = [(s["t_s"], s["rss_mb"].get(str(pid))) for s in samples if s["rss_mb"].get(str(pid)) is not None]
        third = series[-1][0] * 2 / 3
        early = max(mb for t, mb in series if t <= third)
        per_worker[str(pid)] = {"start_mb": series[0][1], "peak_mb": max(mb for _, mb in series),
                                "end_mb": series[-1][1], "max_first_two_thirds_mb": early,
                                "growth_last_third_mb": round(max(mb for t, mb in series if t >= third) - early, 1)}
    errors = {k: v for k, v in counts.items() if k.split(": ")[-1].startswith("5") or "transport" in k}
    figures = {"minutes": args.minutes, "clients": args.clients,
              "seed": args.seed, "requests": sum(counts.values()), "by_kind_status": dict(sorted(counts.items())),
              "server_errors": errors, "same_workers_throughout": same_workers, "tracebacks": tracebacks,
              "first_traceback": first_traceback,
              "workers": per_worker, "samples": samples}
    write("soak", figures, load_start=load_start, out=args.out)
    for pid, w in per_worker.items():
        print(f"worker {pid}: {w['start_mb']:.0f} MB at the start, peak {w['peak_mb']:.0f} MB, end {w['end_mb']:.0f} MB; "
              f"last third above the first two thirds' highest: {w['growth_last_third_mb']:+.0f} MB")
    print(f"{figures['requests']} requests, server errors: {errors or 'none'}, tracebacks: {tracebacks}, "
          f"workers replaced: {not same_workers}; load average {load_start[0]:.1f} before, "
          f"{load_average()[0]:.1f} after")


if __name__ == "__main__":
    main()

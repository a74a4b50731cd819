"""Service load test (issue 4): a real ``uvicorn --workers 2`` on loopback.

Run: ``.venv/bin/python benchmarks/bench_service.py``. It starts the service as a user does
(``rcsa serve --workers 2``, ``benchmarks/_service.py``) on a free port with a temporary store
and a write key, uploads RA-1's analytical spindle-nose receptance as
a ``point_receptance`` measurement (5 000 lines, 1–5 000 Hz), then measures

* single hybrid predictions of RA-1's holder and tool on that stored spindle at 5 000 lines:
  p50 and p99 latency and requests per second, from 1, 2 and 4 concurrent client threads
  (targets: p50 <= 30 ms, >= 50 requests/s), without and with gzip;
* keep-alive latency: ``GET /healthz`` 300 times on one HTTP/1.1 connection, p50 and p99
  (target: p50 <= 3 ms with 2 workers; without ``--http service.http:NoDelayHTTPProtocol``,
  Nagle + delayed ACK made it ~44 ms), and the same from 8 concurrent connections;
* a 1 000-combination batch on the same spindle at 1 000 lines (a job: 202, poll, GET
  result), wall time from the POST to the last byte of the result (target <= 5 s), with the
  full tool_point (h, l, n, p) and with ``?tool_point=h``.

The single predictions are measured three ways: the same request over and over (the figure of
earlier runs; the service answers it from its kept prediction), a different tool (stickout) in
every request on the same spindle and holder, 50 tools in turn (what a CAM system asking tool
after tool sends: each tool's modal fit is kept, its prediction not), and a tool never asked
before in every request (nothing of the tool kept: the cold cost on a kept spindle side). ``--stages`` first times, in this process and
without HTTP, each stage of one such request — JSON decoding and schema validation, the
prediction (spindle side kept or cold; of it the modal fit), the result document and its JSON
bytes, gzip — and the whole ASGI app (routing, middleware) called in-process: where the time
goes, and so where the floor is.

``--largest``: only the largest batch the default limits allow per request in lines, 1 000
combinations at 20 000 lines (``RCSA_MAX_FREQUENCY_LINES``; a 3.7 GB JSON result), as a job on
the 2-worker service: it must complete in one attempt (no worker killed for missing uvicorn's
health ping while its result is written, as happened when the result was serialised in one
piece), streamed back to the client in pieces; reported with the peak resident memory of each
uvicorn worker process (``VmHWM``). Figures go to ``benchmarks/results/service-largest.json``.
(A benchmark, not a CI test: it takes minutes and 4 GB of disk.)

Results are printed and written to ``benchmarks/results/service.json``. The numbers depend
on the machine and on whatever else runs on it; the client threads share its cores.
"""

from __future__ import annotations

import argparse
import http.client
import json
import os
import shutil
import statistics
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import httpx
import orjson

from _service import memory_mb, start_service, stop_service, workers
from rcsa.app.measurements import demo_measurement
from rcsa.measured.importers import measurement_to_contract
from rcsa.reference import ra1
from record import load_average, write

KEY = "bench-write-key-0123456789abcdef"
GRID_5000 = {"start_hz": 1.0, "stop_hz": 5000.0, "step_hz": 1.0}


#: The service's settings for the benchmark: a write key, jobs polled often.
ENV = {"RCSA_API_KEYS": f"{KEY}:write", "RCSA_JOB_POLL_S": "0.05"}


def _percentile(values: list[float], q: float) -> float:
    values = sorted(values)
    k = max(0, min(len(values) - 1, round(q / 100 * (len(values) - 1))))
    return values[k]


def load(base: str, body: bytes | list[bytes], *, threads: int, requests: int, headers: dict[str, str]
         ) -> dict[str, float]:
    """``requests`` POSTs of ``body`` (or of the bodies in turn) from ``threads`` client threads; ms."""
    bodies = body if isinstance(body, list) else [body]
    latencies: list[float] = []
    lock = threading.Lock()
    todo = iter(range(requests))
    errors = []

    def worker() -> None:
        with httpx.Client(base_url=base, timeout=60, headers=headers) as client:
            while True:
                with lock:
                    k = next(todo, None)
                    if k is None:
                        return
                t0 = time.perf_counter()
                r = client.post("/v1/tool-point-frf", content=bodies[k % len(bodies)],
                                headers={"content-type": "application/json"})
                r.read()
                dt = (time.perf_counter() - t0) * 1e3
                if r.status_code != 200:
                    errors.append(r.status_code)
                with lock:
                    latencies.append(dt)

    t0 = time.perf_counter()
    pool = [threading.Thread(target=worker) for _ in range(threads)]
    for t in pool:
        t.start()
    for t in pool:
        t.join()
    wall = time.perf_counter() - t0
    if errors:
        raise RuntimeError(f"{len(errors)} failed requests: {errors[:5]}")
    return {"requests": len(latencies), "threads": threads, "p50_ms": statistics.median(latencies),
            "p99_ms": _percentile(latencies, 99), "mean_ms": statistics.fmean(latencies),
            "requests_per_s": len(latencies) / wall}


def keepalive(base: str, *, requests: int = 300, connections: int = 1) -> dict[str, float]:
    """``GET /healthz`` ``requests`` times on each of ``connections`` keep-alive connections; ms."""
    host, port = base.removeprefix("http://").split(":")
    latencies: list[float] = []
    lock = threading.Lock()

    def one() -> None:
        conn = http.client.HTTPConnection(host, int(port), timeout=30)
        mine = []
        for _ in range(requests):
            t0 = time.perf_counter()
            conn.request("GET", "/healthz")
            response = conn.getresponse()
            response.read()
            mine.append((time.perf_counter() - t0) * 1e3)
            assert response.status == 200
        conn.close()
        with lock:
            latencies.extend(mine[1:])  # the first request also opens the connection

    pool = [threading.Thread(target=one) for _ in range(connections)]
    for t in pool:
        t.start()
    for t in pool:
        t.join()
    return {"connections": connections, "requests": len(latencies), "p50_ms": statistics.median(latencies),
            "p99_ms": _percentile(latencies, 99), "max_ms": max(latencies)}


def _finished_job(client: httpx.Client, accepted: httpx.Response, pause_s: float) -> dict:
    """Poll the job a ``202`` accepted until it ends; its status document. An anonymous job is
    private to the token its ``202`` handed out (``X-Job-Token``), so the client sends it from now on."""
    assert accepted.status_code == 202, accepted.text
    client.headers["X-Job-Token"] = accepted.headers["x-job-token"]
    while True:
        answer = client.get(accepted.headers["location"])
        answer.raise_for_status()
        if (job := answer.json())["status"] in ("succeeded", "failed"):
            assert job["status"] == "succeeded", job
            return job
        time.sleep(pause_s)


def batch(base: str, mid: str, n: int, grid: dict[str, float], *, tool_point: str | None,
          accept_encoding: str) -> dict[str, float]:
    doc = ra1(grid)
    combos = [{"id": f"T{i:04d}", "holder": doc["holder"], "joints": doc["joints"],
               "tool": {**doc["tool"], "stickout_m": 0.040 + 0.05 * i / n}} for i in range(n)]
    request = {"frequency": grid, "spindle": {"measurement_id": mid}, "combinations": combos}
    params = {"tool_point": tool_point} if tool_point else {}
    with httpx.Client(base_url=base, timeout=300, headers={"Accept-Encoding": accept_encoding}) as client:
        t0 = time.perf_counter()
        job = _finished_job(client, client.post("/v1/tool-point-frf/batch", json=request, params=params), 0.05)
        t_done = time.perf_counter()
        result = client.get(job["result_url"])
        raw = result.content
        t_bytes = time.perf_counter()
        summary = orjson.loads(raw)["summary"]
        t_parsed = time.perf_counter()
    assert summary == {"ok": n, "error": 0}, summary
    return {"combinations": n, "lines": _lines(grid), "tool_point": tool_point or "h,l,n,p",
            "accept_encoding": accept_encoding, "job_done_s": t_done - t0, "result_received_s": t_bytes - t0,
            "result_parsed_s": t_parsed - t0, "result_mb": len(raw) / 1e6}


def _server_side(base: str) -> dict[str, float]:
    """Mean request latency and compute time of /v1/tool-point-frf from the service's own metrics."""
    text = httpx.get(base + "/metrics", timeout=30).text
    values: dict[str, float] = {}
    for line in text.splitlines():
        if line.startswith(("rcsa_http_request_duration_seconds_sum", "rcsa_http_request_duration_seconds_count",
                            "rcsa_compute_seconds_sum", "rcsa_compute_seconds_count")) and \
                ('route="/v1/tool-point-frf"' in line or 'operation="predict"' in line):
            name, value = line.rsplit(" ", 1)
            values[name.split("{")[0]] = float(value)
    return {"mean_request_ms": 1e3 * values["rcsa_http_request_duration_seconds_sum"]
            / values["rcsa_http_request_duration_seconds_count"],
            "mean_predict_ms": 1e3 * values["rcsa_compute_seconds_sum"] / values["rcsa_compute_seconds_count"]}


def largest(base: str, mid: str, n: int, grid: dict[str, float], proc: subprocess.Popen) -> dict[str, object]:
    """The largest batch the limits allow, as a job; its result streamed and counted, not parsed."""
    doc = ra1(grid)
    combos = [{"id": f"T{i:04d}", "holder": doc["holder"], "joints": doc["joints"],
               "tool": {**doc["tool"], "stickout_m": 0.040 + 0.05 * i / n}} for i in range(n)]
    request = {"frequency": grid, "spindle": {"measurement_id": mid}, "combinations": combos}
    with httpx.Client(base_url=base, timeout=600) as client:
        t0 = time.perf_counter()
        job = _finished_job(client, client.post("/v1/tool-point-frf/batch", json=request,
                                                headers={"Accept-Encoding": "identity"}), 0.5)
        t_done = time.perf_counter()
        received, tail = 0, b""
        with client.stream("GET", job["result_url"], headers={"Accept-Encoding": "identity"}) as result:
            for piece in result.iter_bytes():
                received += len(piece)
                tail = (tail + piece)[-200:]
        t_bytes = time.perf_counter()
    summary = orjson.loads(tail[tail.rindex(b'"summary":') + 10:-1])
    assert summary == {"ok": n, "error": 0}, summary
    return {"combinations": n, "lines": _lines(grid), "attempts": job["attempts"], "job_done_s": t_done - t0,
            "result_received_s": t_bytes - t0, "result_gb": received / 1e9, "result_bytes": job["result_bytes"],
            "worker_peak_rss_mb": {pid: memory_mb(pid)["peak_rss_mb"] for pid in workers(proc)}}


def tool_bodies(mid: str, n: int = 50, offset_m: float = 0.0) -> list[bytes]:
    """RA-1's holder and tool on the stored spindle, stickouts 50–80 mm (+ ``offset_m``): one body per tool."""
    doc = ra1(GRID_5000)
    return [json.dumps({**doc, "spindle": {"measurement_id": mid},
                        "tool": {**doc["tool"], "stickout_m": round(0.050 + offset_m + 0.030 * i / n, 9)}}).encode()
            for i in range(n)]


def stages(repeats: int = 30) -> dict[str, float]:
    """Each stage of one hybrid prediction request at 5 000 lines, in this process; median ms."""
    import gzip
    import warnings

    from rcsa.app import predictions
    from rcsa.app.inputs import decode_json
    from rcsa.app.results import json_bytes
    from rcsa.model import modal_fit as modal_fit_module

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from fastapi.testclient import TestClient
    from service.config import Settings
    from service.main import create_app
    from service.schemas import PredictionRequest

    def median_ms(fn: object) -> float:
        fn()  # type: ignore[operator]
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            fn()  # type: ignore[operator]
            times.append(time.perf_counter() - t0)
        return statistics.median(times) * 1e3

    store = Path(tempfile.mkdtemp(prefix="rcsa-stages-")) / "store"
    app = create_app(Settings(store=store, api_keys=f"{KEY}:write", seed_demo=False, access_log=False))
    out: dict[str, float] = {}
    with TestClient(app) as client:
        spindle = measurement_to_contract(demo_measurement(GRID_5000))
        spindle = {k: v for k, v in spindle.items() if k not in ("id", "source", "created_utc")}
        mid = client.post("/v1/measurements", json=spindle, headers={"X-API-Key": KEY}).json()["id"]
        bodies = tool_bodies(mid)
        docs = [decode_json(b) for b in bodies]
        state = app.state.rcsa_state if hasattr(app.state, "rcsa_state") else None
        from service.state import ensure_state
        reader = (state or ensure_state(app)).reader
        counter = iter(range(10**9))

        def next_doc() -> dict:
            return docs[next(counter) % len(docs)]

        result = predictions.predict(docs[0], store=reader)
        h, f = result.tool_point.h, result.frequency_hz
        out["decode JSON body (JSON policy)"] = median_ms(lambda: decode_json(bodies[0]))
        out["validate (pydantic schema) + model_dump"] = median_ms(
            lambda: PredictionRequest.model_validate(docs[0]).model_dump(exclude_unset=True))
        out["predict, spindle side kept (another tool)"] = median_ms(lambda: predictions.predict(next_doc(),
                                                                                                   store=reader))
        predictions.SIDES.size = 0
        out["predict, cold (spindle side rebuilt)"] = median_ms(lambda: predictions.predict(next_doc(), store=reader))
        predictions.SIDES.size = predictions.SIDES_KEPT
        out["  of which the modal fit of h (hybrid natural frequencies)"] = median_ms(
            lambda: modal_fit_module.modal_fit(f, h))
        out["result document + JSON bytes (json_bytes)"] = median_ms(lambda: json_bytes(result.to_dict("numpy")))
        body = json_bytes(result.to_dict("numpy"))
        out["gzip of the body (level 1, when asked)"] = median_ms(lambda: gzip.compress(body, 1))
        headers = {"content-type": "application/json", "accept-encoding": "identity"}
        out["whole app in-process (TestClient: routing, middleware, all of the above)"] = median_ms(
            lambda: client.post("/v1/tool-point-frf", content=next_doc_body(bodies, counter), headers=headers))
    shutil.rmtree(store.parent, ignore_errors=True)
    print(f"stages of one hybrid prediction request, 5 000 lines, median of {repeats} "
          f"(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores):")
    for name, ms in out.items():
        print(f"  {name:72s} {ms:6.2f} ms")
    return out


def next_doc_body(bodies: list[bytes], counter: object) -> bytes:
    """The next of ``bodies`` in turn."""
    return bodies[next(counter) % len(bodies)]  # type: ignore[call-overload]


def _lines(grid: dict[str, float]) -> int:
    return int(round((grid["stop_hz"] - grid["start_hz"]) / grid["step_hz"])) + 1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2, 4])
    parser.add_argument("--requests", type=int, default=400)
    parser.add_argument("--batch", type=int, default=1000)
    parser.add_argument("--keepalive-only", action="store_true", help="Measure only the keep-alive latency.")
    parser.add_argument("--largest", action="store_true", help="only the largest batch the limits allow")
    parser.add_argument("--stages", action="store_true", help="first time each stage of a request in-process")
    parser.add_argument("--skip-batch", action="store_true", help="single predictions only (no batch jobs)")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    if args.largest:
        main_largest(args)
        return
    staged = stages() if args.stages else None

    load_start = load_average()
    tmp = Path(tempfile.mkdtemp(prefix="rcsa-bench-"))
    proc, base, _ = start_service(tmp, workers=args.workers, env=ENV)
    results: dict[str, object] = {"uvicorn_workers": args.workers}
    if staged is not None:
        results["stages_ms"] = staged
    try:
        results["keepalive_healthz"] = [keepalive(base), keepalive(base, requests=100, connections=8)]
        for row in results["keepalive_healthz"]:
            print(f"keep-alive GET /healthz, {row['connections']} connection(s): p50 {row['p50_ms']:.2f} ms, "
                  f"p99 {row['p99_ms']:.2f} ms, max {row['max_ms']:.1f} ms ({row['requests']} requests)")
        if args.keepalive_only:
            return
        spindle = measurement_to_contract(demo_measurement(GRID_5000))
        spindle = {k: v for k, v in spindle.items() if k not in ("id", "source", "created_utc")}
        r = httpx.post(base + "/v1/measurements", json=spindle, headers={"X-API-Key": KEY}, timeout=60)
        assert r.status_code == 201, r.text
        mid = r.json()["id"]
        body = json.dumps({**ra1(GRID_5000), "spindle": {"measurement_id": mid}}).encode()
        load(base, body, threads=2, requests=8 * args.workers, headers={})  # warm-up: caches of both workers
        single = {f"{n}_threads": load(base, body, threads=n, requests=args.requests,
                                       headers={"Accept-Encoding": "identity"}) for n in args.threads}
        single["2_threads_gzip"] = load(base, body, threads=2, requests=max(40, args.requests // 4),
                                        headers={"Accept-Encoding": "gzip"})
        tools = tool_bodies(mid)
        load(base, tools, threads=2, requests=len(tools), headers={})  # warm-up
        for n in args.threads:
            single[f"{n}_threads_tool_per_request"] = load(base, tools, threads=n, requests=args.requests,
                                                           headers={"Accept-Encoding": "identity"})
        for n in args.threads:  # a tool never asked before in every request: nothing of it kept
            fresh = tool_bodies(mid, args.requests, offset_m=0.001 * n)
            single[f"{n}_threads_new_tool_per_request"] = load(base, fresh, threads=n, requests=args.requests,
                                                               headers={"Accept-Encoding": "identity"})
        results["single_prediction_5000_lines"] = single
        results["server_side"] = _server_side(base)
        grid_1000 = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
        results["batch"] = [] if args.skip_batch else [
            batch(base, mid, args.batch, grid_1000, tool_point=None, accept_encoding="identity"),
            batch(base, mid, args.batch, grid_1000, tool_point="h", accept_encoding="identity"),
            batch(base, mid, args.batch, grid_1000, tool_point="h", accept_encoding="gzip"),
        ]
    finally:
        stop_service(proc)
        shutil.rmtree(tmp, ignore_errors=True)

    print(f"single hybrid prediction (RA-1 holder + tool on a stored spindle), 5 000 lines, {args.workers} workers:")
    for name, row in results["single_prediction_5000_lines"].items():
        print(f"  {name:15s} p50 {row['p50_ms']:6.1f} ms   p99 {row['p99_ms']:6.1f} ms   "
              f"{row['requests_per_s']:6.1f} requests/s   ({row['requests']} requests)")
    srv = results["server_side"]
    print(f"  server side: mean request {srv['mean_request_ms']:.1f} ms, of which rcsa.app.predictions.predict "
          f"{srv['mean_predict_ms']:.1f} ms")
    for b in results["batch"]:
        print(f"batch of {b['combinations']} at {b['lines']} lines, tool_point={b['tool_point']}, "
              f"Accept-Encoding {b['accept_encoding']}: job done {b['job_done_s']:.2f} s, result received "
              f"{b['result_received_s']:.2f} s ({b['result_mb']:.0f} MB), parsed {b['result_parsed_s']:.2f} s")
    write("service", results, load_start=load_start, out=args.out)


def main_largest(args: argparse.Namespace) -> None:
    tmp = Path(tempfile.mkdtemp(prefix="rcsa-bench-"))
    proc, base, _ = start_service(tmp, workers=args.workers, env=ENV)
    try:
        grid = {"start_hz": 0.25, "stop_hz": 5000.0, "step_hz": 0.25}  # 20 000 lines
        spindle = measurement_to_contract(demo_measurement(grid))
        spindle = {k: v for k, v in spindle.items() if k not in ("id", "source", "created_utc")}
        r = httpx.post(base + "/v1/measurements", json=spindle, headers={"X-API-Key": KEY}, timeout=120)
        assert r.status_code == 201, r.text
        load_start = load_average()
        figures = largest(base, r.json()["id"], args.batch, grid, proc)
    finally:
        stop_service(proc)
        shutil.rmtree(tmp, ignore_errors=True)  # 4 GB of result
    figures = {"uvicorn_workers": args.workers, **figures}
    peaks = ", ".join(f"{mb:.0f} MB" for mb in figures["worker_peak_rss_mb"].values())
    print(f"largest batch: {figures['combinations']} combinations x {figures['lines']} lines on {args.workers} uvicorn "
          f"workers (load average {load_start[0]:.1f} on {os.cpu_count()} cores): job done in {figures['job_done_s']:.0f} s "
          f"(attempt {figures['attempts']}), {figures['result_gb']:.2f} GB received by "
          f"{figures['result_received_s']:.0f} s; peak RSS of the workers {peaks}")
    write("service-largest", figures, load_start=load_start, out=args.out)


if __name__ == "__main__":
    main()

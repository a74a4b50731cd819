"""Hostile input against a real ``uvicorn --workers 2``: every operation, uploaded files included.

Run: ``.venv/bin/python benchmarks/bench_hostile.py`` against a real ``rcsa serve --workers 2``
(``--per-operation 60 --seed 21``: about
2 100 cases over 34 operations; ``--heavy`` adds the largest files: 250 000-row tables and a
2 100 000-row tap test). The cases come from ``tests/service/hostile_cases.py``: mutations of a
valid request of each operation — numbers beyond the input policy (1e308, 1e400, 400 digits,
NaN, Infinity), nesting 33–5 000 deep, 20 000-character strings, values beyond a physical
bound (a 22 m segment, a 1e30 kg sensor, a 1e11 Hz line, ``relative_step`` 1e-300 ...),
unit factors of 0, truncated and bit-flipped files, values of the wrong type. It prints the
answers per status and per operation and every case judged wrong: a 5xx, a *wrong 2xx* (a
request that breaks the policy or a physical bound answered 2xx), or an error that is not a
problem document. Results go to ``benchmarks/results/hostile.json``; the exit status is 1 when
any case is wrong.

``--bulk`` (or ``--bulk-only``): bulk bodies from an anonymous caller against a real ``rcsa serve
--workers 2`` — 4 MiB and 63 MiB of tiny batch items (objects, numbers, small objects with
members, strings), one 63 MiB string, 10 001 valid combinations, a 4 MiB and a 63 MiB library of
tiny items and one of 4 MiB of numbers — each sent on a raw socket while the server's answer is read, so that an answer
given before the body ends is seen (with how much of the body had been sent). Meanwhile another
caller sends predictions without pause (its failures and slowest answer are counted) and every
worker's resident memory is sampled every 20 ms: each case's growth is the highest RSS during
the case above the highest just before it. A worker that died would show as a new pid. Results
go to ``benchmarks/results/bulk.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import sys
import tempfile
import time
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import httpx

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "benchmarks"))

from tests.service.hostile_cases import Case, cases, judge, operations  # noqa: E402

from _service import memory_mb, start_service, stop_service, workers  # noqa: E402
from record import load_average, write  # noqa: E402

KEY = "bench-hostile-write-key-0123456789"


def _send(client: httpx.Client, case: Case) -> dict[str, object]:
    t0 = time.perf_counter()
    try:
        r = client.post(case.path, **case.request_kwargs())
    except httpx.TimeoutException:
        return {"operation": case.operation, "label": case.label, "status": 0, "verdict": "timeout",
                "seconds": time.perf_counter() - t0, "detail": ""}
    verdict = judge(case, r.status_code, r.headers.get("content-type", ""), r.content)
    detail = ""
    if r.headers.get("content-type", "").startswith("application/problem+json"):
        detail = str(r.json().get("detail", ""))[:160]
    elif verdict != "ok":
        detail = r.text[:160]
    return {"operation": case.operation, "label": case.label, "expect": case.expect, "status": r.status_code,
            "verdict": verdict, "seconds": round(time.perf_counter() - t0, 4), "detail": detail}


MIB = 2**20


def _tiny_batch(item: bytes, size: int) -> bytes:
    head = b'{"frequency": {"start_hz": 5, "stop_hz": 5000, "step_hz": 5}, "spindle": {"measurement_id": "m-0"}, ' \
           b'"combinations": ['
    n = max((size - len(head)) // len(item), 1)
    return head + item * (n - 1) + item.rstrip(b",") + b"]}"


def bulk_bodies() -> list[tuple[str, str, bytes]]:
    """(label, path, body) of the bulk cases (module docstring), all anonymous."""
    from rcsa.reference import ra1

    a = ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0})
    combo = json.dumps({"id": "T", "holder": a["holder"], "tool": a["tool"], "joints": a["joints"]}).encode()
    over = b'{"frequency": ' + json.dumps(a["frequency"]).encode() + b', "spindle": ' + \
        json.dumps(a["spindle"]).encode() + b', "combinations": [' + b",".join([combo] * 10_001) + b"]}"
    library = b'{"spindle": {"measurement_id": "m-0"}, "frequency": {"start_hz": 5, "stop_hz": 50, "step_hz": 5}, ' \
              b'"library": {"data": ['
    return [
        ("batch: 4 MiB of tiny objects", "/v1/tool-point-frf/batch", _tiny_batch(b'{"a":1},', 4 * MIB)),
        ("batch: 4 MiB of numbers", "/v1/tool-point-frf/batch", _tiny_batch(b"0,", 4 * MIB)),
        ("batch: 4 MiB of small objects with members", "/v1/tool-point-frf/batch",
         _tiny_batch(b'{"id":"T","tool":{}},', 4 * MIB)),
        ("batch: 4 MiB of short strings", "/v1/tool-point-frf/batch", _tiny_batch(b'"ab",', 4 * MIB)),
        ("batch: 10 001 valid combinations", "/v1/tool-point-frf/batch", over),
        ("batch: 63 MiB of tiny objects", "/v1/tool-point-frf/batch", _tiny_batch(b'{"a":1},', 63 * MIB)),
        ("batch: 63 MiB of numbers", "/v1/tool-point-frf/batch", _tiny_batch(b"0,", 63 * MIB)),
        ("batch: one string of 63 MiB", "/v1/tool-point-frf/batch",
         _tiny_batch(b'{"id": "' + b"x" * (63 * MIB) + b'"},', 63 * MIB)),
        ("library: 4 MiB of tiny items", "/v1/tool-libraries:predict", library + b'{"a":1},' * (4 * MIB // 8) + b"{}]}}"),
        ("library: 63 MiB of tiny items", "/v1/tool-libraries:predict", library + b'{"a":1},' * (63 * MIB // 8) + b"{}]}}"),
        ("library: 4 MiB of numbers", "/v1/tool-libraries:predict", library + b"0," * (4 * MIB // 2) + b"0]}}"),
    ]


def post_raw(base: str, path: str, body: bytes, timeout_s: float = 300.0) -> dict[str, object]:
    """POST ``body`` on a raw socket, reading the answer while it is sent: status, seconds to the
    answer's first byte, bytes sent by then, the problem's detail."""
    import threading as th

    host, port = base.removeprefix("http://").split(":")
    sock = socket.create_connection((host, int(port)), timeout=timeout_s)
    head = (f"POST {path} HTTP/1.1\r\nHost: bench\r\nContent-Type: application/json\r\n"
            f"Content-Length: {len(body)}\r\n\r\n").encode()
    sent = [0]

    def send() -> None:
        try:
            sock.sendall(head)
            view = memoryview(body)
            for k in range(0, len(body), 65536):
                sock.sendall(view[k:k + 65536])
                sent[0] = k + len(view[k:k + 65536])
        except OSError:
            pass  # the server answered and closed: it read no further

    t0 = time.perf_counter()
    sender = th.Thread(target=send)
    sender.start()
    answer, first = b"", None
    try:
        while True:
            chunk = sock.recv(65536)
            if not chunk:
                break
            first = first if first is not None else (time.perf_counter() - t0, sent[0])
            answer += chunk
            if b"\r\n\r\n" in answer:
                head_part, _, rest = answer.partition(b"\r\n\r\n")
                length = [int(line.split(b":")[1]) for line in head_part.split(b"\r\n")
                          if line.lower().startswith(b"content-length:")]
                if length and len(rest) >= length[0]:
                    break
    except OSError:
        pass
    finally:
        sock.close()
        sender.join()
    status = int(answer.split(b" ", 2)[1]) if answer.startswith(b"HTTP/1.1 ") else 0
    body_part = answer.partition(b"\r\n\r\n")[2]
    try:
        detail = str(json.loads(body_part).get("detail", ""))[:200]
    except ValueError:
        detail = body_part[:200].decode(errors="replace")
    return {"status": status, "seconds": round(first[0], 3) if first else None,
            "body_sent_bytes": first[1] if first else sent[0], "body_bytes": len(body), "detail": detail}


def bulk(args: argparse.Namespace) -> None:
    """The bulk cases against ``rcsa serve --workers 2`` (module docstring); ``results/bulk.json``."""
    import threading as th

    from rcsa.reference import ra1

    load_start = load_average()
    cases = bulk_bodies()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        proc, base, log = start_service(Path(tmp))
        pids = workers(proc)
        rss: dict[int, float] = {}
        stop = th.Event()
        neighbour = {"requests": 0, "failures": 0, "slowest_s": 0.0}

        def sampler() -> None:
            while not stop.is_set():
                for pid in workers(proc):
                    rss[pid] = max(rss.get(pid, 0.0), memory_mb(pid).get("rss_mb", 0.0))
                time.sleep(0.02)

        def other_caller() -> None:
            body = ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0})
            with httpx.Client(base_url=base, timeout=120) as client:
                while not stop.is_set():
                    t = time.perf_counter()
                    try:
                        ok = client.post("/v1/tool-point-frf", json=body).status_code == 200
                    except httpx.TransportError:
                        ok = False
                    neighbour["requests"] += 1
                    neighbour["failures"] += 0 if ok else 1
                    neighbour["slowest_s"] = max(neighbour["slowest_s"], time.perf_counter() - t)

        threads = [th.Thread(target=sampler), th.Thread(target=other_caller)]
        for t in threads:
            t.start()
        try:
            time.sleep(2.0)
            for label, path, body in cases:
                time.sleep(1.0)  # memory settles between cases
                start = {pid: memory_mb(pid).get("rss_mb", 0.0) for pid in workers(proc)}
                rss.clear()
                row = {"case": label, "path": path, **post_raw(base, path, body, args.timeout)}
                time.sleep(0.5)
                row["worker_rss_before_mb"] = {str(p): round(v, 1) for p, v in start.items()}
                row["worker_growth_mb"] = round(max(rss.get(p, v) - v for p, v in start.items()), 1)
                row["workers_alive"] = workers(proc) == pids
                rows.append(row)
                print(f"{label:46s} {row['status']} in {row['seconds']} s after {row['body_sent_bytes'] / MIB:.1f} "
                      f"of {row['body_bytes'] / MIB:.1f} MiB; worker growth {row['worker_growth_mb']:+.0f} MB; "
                      f"{row['detail'][:90]}", flush=True)
        finally:
            stop.set()
            for t in threads:
                t.join()
            stop_service(proc)
        tracebacks = log.read_text().count("Traceback")
    wrong = [r for r in rows if not 400 <= int(r["status"]) < 500 or not r["workers_alive"]]
    figures = {"cases": rows,
              "other_caller": {**neighbour, "slowest_s": round(neighbour["slowest_s"], 3)},
              "workers_unchanged": all(r["workers_alive"] for r in rows),
              "tracebacks": tracebacks, "wrong": wrong}
    write("bulk", figures, load_start=load_start,
          out=args.out.with_name("bulk.json") if args.out.name == "hostile.json" else args.out)
    print(f"other caller: {neighbour['requests']} predictions, {neighbour['failures']} failed, slowest "
          f"{neighbour['slowest_s']:.2f} s; tracebacks {tracebacks}; wrong {len(wrong)}; load average "
          f"{load_start[0]:.1f}")
    if wrong or neighbour["failures"] or tracebacks:
        sys.exit(1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=21)
    parser.add_argument("--per-operation", type=int, default=60)
    parser.add_argument("--heavy", action="store_true", help="Add 250 000-row tables and a 2 100 000-row tap test.")
    parser.add_argument("--clients", type=int, default=2, help="Concurrent client threads.")
    parser.add_argument("--timeout", type=float, default=300.0, help="Seconds before a request counts as hung.")
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" / "hostile.json")
    parser.add_argument("--bulk", action="store_true", help="Then the bulk cases (results/bulk.json).")
    parser.add_argument("--bulk-only", action="store_true", help="Only the bulk cases.")
    args = parser.parse_args()
    if args.bulk_only:
        bulk(args)
        return
    todo = cases(args.seed, args.per_operation, heavy=args.heavy, write_headers={"X-API-Key": KEY})
    load_start = load_average()
    print(f"{len(todo)} cases over {len(operations())} operations (seed {args.seed}); load average "
          f"{', '.join(map(str, load_start))} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        proc, base, log = start_service(Path(tmp), env={"RCSA_API_KEYS": f"{KEY}:write"})
        t0 = time.perf_counter()
        try:
            with httpx.Client(base_url=base, timeout=args.timeout) as client, \
                    ThreadPoolExecutor(args.clients) as pool:
                rows = list(pool.map(lambda c: _send(client, c), todo))
        finally:
            stop_service(proc)
        wall = time.perf_counter() - t0
        traceback_lines = log.read_text().count("Traceback")
    by_status = Counter(r["status"] for r in rows)
    by_verdict = Counter(r["verdict"] for r in rows)
    per_op: dict[str, Counter] = defaultdict(Counter)
    for r in rows:
        per_op[str(r["operation"])][str(r["status"])] += 1
    print(f"answered in {wall:.0f} s; per status: " + ", ".join(f"{s}: {n}" for s, n in sorted(by_status.items())))
    print("verdicts: " + ", ".join(f"{v}: {n}" for v, n in sorted(by_verdict.items())))
    print(f"tracebacks in the server log: {traceback_lines}")
    width = max(len(op) for op in per_op)
    for op in sorted(per_op):
        print(f"  {op:{width}s}  " + "  ".join(f"{s}: {n}" for s, n in sorted(per_op[op].items())))
    wrong = [r for r in rows if r["verdict"] != "ok"]
    for r in wrong:
        print(f"WRONG {r['verdict']}: {r['operation']} | {r['label']} -> {r['status']} {r['detail']}")
    write("hostile", {
        "seed": args.seed, "per_operation": args.per_operation, "heavy": args.heavy, "cases": len(rows),
        "operations": len(per_op), "wall_seconds": round(wall, 1),
        "by_status": {str(k): v for k, v in sorted(by_status.items())}, "by_verdict": dict(by_verdict),
        "tracebacks": traceback_lines, "per_operation_status": {op: dict(c) for op, c in sorted(per_op.items())},
        "wrong": wrong}, load_start=load_start, out=args.out)
    if args.bulk:
        bulk(args)
    sys.exit(1 if wrong or traceback_lines else 0)


if __name__ == "__main__":
    main()

"""Hostile input against a real ``uvicorn --workers 2``: every operation, uploaded files included.

Run: ``.venv/bin/python benchmarks/bench_hostile.py`` (``--per-operation 60 --seed 21``: about
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
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import httpx

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.service.hostile_cases import Case, cases, judge, operations  # noqa: E402

KEY = "bench-hostile-write-key-0123456789"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _start(tmp: Path) -> tuple[subprocess.Popen, str, Path]:
    port = _free_port()
    prom = tmp / "prom"
    prom.mkdir()
    env = {**os.environ, "RCSA_STORE": str(tmp / "store"), "RCSA_API_KEYS": f"{KEY}:write",
           "RCSA_SEED_DEMO": "false", "PROMETHEUS_MULTIPROC_DIR": str(prom), "RCSA_ACCESS_LOG": "false"}
    log = tmp / "uvicorn.log"
    with log.open("w") as out:
        proc = subprocess.Popen([sys.executable, "-m", "uvicorn", "service.main:create_app", "--factory",
                                 "--workers", "2", "--host", "127.0.0.1", "--port", str(port)], cwd=REPO, env=env,
                                stdout=out, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    for _ in range(600):
        try:
            if httpx.get(base + "/readyz", timeout=5).status_code == 200:
                time.sleep(1.0)  # the second worker
                return proc, base, log
        except httpx.TransportError:
            pass
        if proc.poll() is not None:
            raise SystemExit("uvicorn exited:\n" + log.read_text())
        time.sleep(0.2)
    raise SystemExit("uvicorn did not become ready:\n" + log.read_text())


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=21)
    parser.add_argument("--per-operation", type=int, default=60)
    parser.add_argument("--heavy", action="store_true", help="Add 250 000-row tables and a 2 100 000-row tap test.")
    parser.add_argument("--clients", type=int, default=2, help="Concurrent client threads.")
    parser.add_argument("--timeout", type=float, default=300.0, help="Seconds before a request counts as hung.")
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" / "hostile.json")
    args = parser.parse_args()
    todo = cases(args.seed, args.per_operation, heavy=args.heavy, write_headers={"X-API-Key": KEY})
    load = os.getloadavg()
    print(f"{len(todo)} cases over {len(operations())} operations (seed {args.seed}); load average "
          f"{load[0]:.2f}, {load[1]:.2f}, {load[2]:.2f} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        proc, base, log = _start(Path(tmp))
        t0 = time.perf_counter()
        try:
            with httpx.Client(base_url=base, timeout=args.timeout) as client, \
                    ThreadPoolExecutor(args.clients) as pool:
                rows = list(pool.map(lambda c: _send(client, c), todo))
        finally:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                proc.kill()
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
    load_after = os.getloadavg()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(), "platform": platform.platform()},
        "load_average_before": load, "load_average_after": load_after, "seed": args.seed,
        "per_operation": args.per_operation, "heavy": args.heavy, "cases": len(rows), "operations": len(per_op),
        "wall_seconds": round(wall, 1), "by_status": {str(k): v for k, v in sorted(by_status.items())},
        "by_verdict": dict(by_verdict), "tracebacks": traceback_lines,
        "per_operation_status": {op: dict(c) for op, c in sorted(per_op.items())}, "wrong": wrong}, indent=1) + "\n")
    sys.exit(1 if wrong or traceback_lines else 0)


if __name__ == "__main__":
    main()

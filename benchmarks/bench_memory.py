"""Peak memory of batches, measured, against the compute budget's estimate (``rcsa.app.budget``).

Run: ``.venv/bin/python benchmarks/bench_memory.py`` (``--quick`` for a smaller grid). Each
point — combinations × frequency lines, answered at once (the whole document held and
serialised, as a synchronous request does) or as a job (results streamed to a file one
chunk at a time, as the job runner does) — runs in a fresh process; the peak resident
memory above that of the same process after a small warm-up batch is the batch's own
peak, compared with ``budget.check_work``'s estimate minus the process base it assumes
(``MEM_BASE_BYTES``). Prints the table and the worst ratio; the estimate must lie within
1.5× of every measured peak (and above it). Results go to
``benchmarks/results/memory.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

#: (combinations, lines, mode) of the full grid.
GRID = [(n, lines, mode) for mode in ("job", "sync") for n, lines in (
    (10, 2_000), (50, 2_000), (50, 20_000), (200, 2_000), (200, 20_000), (542, 20_000), (1000, 20_000),
    (1000, 1_000), (2000, 5_000)) if mode == "job" or n * lines <= 1_000_000]
QUICK = [(50, 2_000, "job"), (200, 20_000, "job"), (50, 2_000, "sync"), (50, 20_000, "sync")]

_PROBE = r"""
import json, os, sys, tempfile
from rcsa.app import budget
from tests.service._budget_probe import peak_rss_bytes  # the process's own peak (VmHWM), not the parent's
from rcsa.app.jobs import run_work, stream_work, Workbench
from rcsa.app.libraries import prepare_batch
from rcsa.reference import ra1

n, lines, mode = json.loads(sys.argv[1])
def batch(n, lines):
    asm = ra1({"start_hz": 5.0, "stop_hz": 20000.0, "step_hz": (20000.0 - 5.0) / (lines - 1)})
    return {"spindle": asm["spindle"], "frequency": asm["frequency"],
            "combinations": [{"id": f"T{i}", "holder": asm["holder"], "joints": asm["joints"],
                              "tool": {**asm["tool"], "stickout_m": 0.05 + 0.03 * i / max(n, 1)}}
                             for i in range(n)]}
bench = Workbench(store=None)
import orjson
run_work(bench, "batch", prepare_batch(bench, batch(3, 200)).request)  # warm-up: imports and caches
base = peak_rss_bytes()
req = prepare_batch(bench, batch(n, lines)).request
cost = budget.check_work("batch", req, n, mode=mode, limits=budget.Limits(1e12, 1e15))
if mode == "sync":
    out = run_work(bench, "batch", req)
    body = orjson.dumps(out.document, option=orjson.OPT_SERIALIZE_NUMPY)
    del out, body
else:
    with tempfile.TemporaryFile() as fh:
        stream_work(bench, "batch", req).write(fh)
peak = peak_rss_bytes()
print(json.dumps({"n": n, "lines": lines, "mode": mode, "base_rss_bytes": base, "peak_rss_bytes": peak,
                  "estimated_bytes": cost.memory_bytes, "estimated_base_bytes": budget.MEM_BASE_BYTES}))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="A four-point grid.")
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" / "memory.json")
    args = parser.parse_args()
    load = os.getloadavg()
    print(f"batch peak memory, estimate vs measured (load average {load[0]:.2f} on {os.cpu_count()} cores)")
    print(f"  {'combinations':>12s} {'lines':>7s} {'answered':>8s} {'measured MiB':>13s} {'estimate MiB':>13s} "
          f"{'ratio':>6s}")
    rows = []
    for n, lines, mode in (QUICK if args.quick else GRID):
        out = subprocess.run([sys.executable, "-c", _PROBE, json.dumps([n, lines, mode])], capture_output=True,
                             text=True, cwd=REPO, check=True)
        r = json.loads(out.stdout.splitlines()[-1])
        measured = r["peak_rss_bytes"] - r["base_rss_bytes"]
        estimate = r["estimated_bytes"] - r["estimated_base_bytes"]
        r.update(measured_bytes=measured, estimate_bytes=estimate, ratio=estimate / max(measured, 1))
        rows.append(r)
        print(f"  {n:12d} {lines:7d} {'at once' if mode == 'sync' else 'job':>8s} {measured / 2**20:13.0f} "
              f"{estimate / 2**20:13.0f} {r['ratio']:6.2f}", flush=True)
    worst = max(max(r["ratio"], 1 / r["ratio"]) for r in rows)
    under = [r for r in rows if r["ratio"] < 1.0]
    print(f"worst factor {worst:.2f}; estimates below the measured peak: {len(under)}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                                                "platform": platform.platform()},
                                    "load_average": load, "rows": rows, "worst_factor": worst}, indent=1) + "\n")
    sys.exit(0 if worst <= 1.5 else 1)


if __name__ == "__main__":
    main()

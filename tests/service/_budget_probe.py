"""Run requests in a fresh process and measure each: ``python -m tests.service._budget_probe``.

Reads ``[{"operation": ..., "request": {...}}, ...]`` as JSON on stdin. A small warm-up
request of each operation runs first (imports, caches), then every request in turn; prints
one JSON line per request: its estimate, the CPU seconds it took (user + system, this
process and its threads), and the process's peak resident memory before the request
(imports, warm-up, earlier requests: ``base_rss_bytes``) and after it (``peak_rss_bytes``),
bytes — both in a failing assertion's message.
"""

from __future__ import annotations

import json
import resource
import sys
import time

from rcsa.app import analyses, budget


def main() -> None:
    jobs = json.load(sys.stdin)
    warm = {job["operation"]: job.get("warmup") for job in jobs}
    for operation, request in warm.items():
        if request is not None:
            analyses.run_analysis(operation, request)
    for job in jobs:
        cost = budget.estimate(job["operation"], job["request"])
        base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        t0, w0 = time.process_time(), time.perf_counter()
        analyses.run_analysis(job["operation"], job["request"])
        cpu, wall = time.process_time() - t0, time.perf_counter() - w0
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        print(json.dumps({"label": job.get("label", job["operation"]), "estimated_seconds": cost.seconds,
                          "estimated_memory_bytes": cost.memory_bytes, "cpu_seconds": cpu, "wall_seconds": wall,
                          "peak_rss_bytes": rss, "base_rss_bytes": base, "terms": dict(cost.terms)}), flush=True)


if __name__ == "__main__":
    main()

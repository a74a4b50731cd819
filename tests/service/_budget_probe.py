"""Run requests in a fresh process and measure each: ``python -m tests.service._budget_probe``.

Reads ``[{"operation": ..., "request": {...}}, ...]`` as JSON on stdin. A small warm-up
request of each operation runs first (imports, caches), then every request in turn; prints
one JSON line per request: its estimate, the CPU seconds it took (user + system, this
process and its threads), and the process's peak resident memory before the request
(imports, warm-up, earlier requests: ``base_rss_bytes``) and after it (``peak_rss_bytes``),
bytes — both in a failing assertion's message.

The peak is the kernel's high-water mark of this process's own memory (``VmHWM``), not
``getrusage``'s ``ru_maxrss``: Linux folds the *parent's* peak into a child's ``ru_maxrss`` when
the child execs (``subprocess`` forks by ``vfork``), so a probe started by an xdist worker that
had grown to 1 GB reported 1010 MiB for a prediction that takes 155 MiB (seen in a full run).
"""

from __future__ import annotations

import json
import resource
import sys
import time
from pathlib import Path

from rcsa.app import analyses, budget


def peak_rss_bytes() -> int:
    """This process's peak resident memory, bytes: ``VmHWM`` of ``/proc/self/status`` (Linux), else
    ``ru_maxrss`` (which on Linux would include the parent's peak, see the module docstring)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    scale = 1 if sys.platform == "darwin" else 1024  # macOS reports bytes, Linux and BSD KiB
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * scale


def main() -> None:
    jobs = json.load(sys.stdin)
    warm = {job["operation"]: job.get("warmup") for job in jobs}
    for operation, request in warm.items():
        if request is not None:
            analyses.run_analysis(operation, request)
    for job in jobs:
        cost = budget.estimate(job["operation"], job["request"])
        base = peak_rss_bytes()
        t0, w0 = time.process_time(), time.perf_counter()
        analyses.run_analysis(job["operation"], job["request"])
        cpu, wall = time.process_time() - t0, time.perf_counter() - w0
        rss = peak_rss_bytes()
        print(json.dumps({"label": job.get("label", job["operation"]), "estimated_seconds": cost.seconds,
                          "estimated_memory_bytes": cost.memory_bytes, "cpu_seconds": cpu, "wall_seconds": wall,
                          "peak_rss_bytes": rss, "base_rss_bytes": base, "terms": dict(cost.terms)}), flush=True)


if __name__ == "__main__":
    main()

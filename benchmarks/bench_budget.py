"""The compute budget at full scale: the worst synchronous request of each shape, measured.

Run: ``.venv/bin/python benchmarks/bench_budget.py``. For every shape of request
(``tests/service/budget_cases.py``: prediction lines, segments and band top; effect-analysis
band; diagnosis measurements and draws on distinct grids; identification measurements;
lobes speeds) it builds the largest request whose estimate fits the sync limits
(:data:`rcsa.app.budget.SYNC`: 20 s, 1 GiB), runs them all in one fresh process, and reports
the estimate against the CPU time and the peak RSS measured. The stated bound
(:data:`rcsa.app.budget.STATED_SYNC_BOUND`: 60 s CPU, 1.5 GiB) must hold for every one.
Results go to ``benchmarks/results/budget.json``. ``--scale 0.1`` runs a tenth of the limit.
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

from tests.service.budget_cases import worst_cases  # noqa: E402

from rcsa.app import budget  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scale", type=float, default=1.0, help="Fraction of the sync limits.")
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" / "budget.json")
    args = parser.parse_args()
    cases = worst_cases(args.scale * budget.SYNC.seconds, args.scale * budget.SYNC.memory_bytes)
    out = subprocess.run([sys.executable, "-m", "tests.service._budget_probe"], input=json.dumps(cases),
                         capture_output=True, text=True, cwd=REPO, check=True)
    rows = [json.loads(line) for line in out.stdout.splitlines()]
    bound = budget.STATED_SYNC_BOUND
    print(f"sync limits x {args.scale:g}: {args.scale * budget.SYNC.seconds:g} s, "
          f"{args.scale * budget.SYNC.memory_bytes / 2**20:.0f} MiB; stated bound {bound.seconds:g} s CPU, "
          f"{bound.memory_bytes / 2**30:g} GiB RSS")
    for r in rows:
        print(f"  {r['label']:45s} estimate {r['estimated_seconds']:6.2f} s {r['estimated_memory_bytes'] / 2**20:6.0f} MiB"
              f" | measured CPU {r['cpu_seconds']:6.2f} s (wall {r['wall_seconds']:6.2f} s), "
              f"peak RSS {r['peak_rss_bytes'] / 2**20:6.0f} MiB")
    ok = all(r["cpu_seconds"] <= bound.seconds * args.scale and r["peak_rss_bytes"] <= bound.memory_bytes for r in rows)
    print("within the stated bound" if ok else "ABOVE THE STATED BOUND")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                                                "platform": platform.platform()},
                                    "scale": args.scale, "sync_limit": {"seconds": budget.SYNC.seconds,
                                                                        "memory_bytes": budget.SYNC.memory_bytes},
                                    "stated_bound": {"seconds": bound.seconds, "memory_bytes": bound.memory_bytes},
                                    "cases": rows, "within_bound": ok}, indent=1) + "\n")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()

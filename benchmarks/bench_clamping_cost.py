"""What a clamping along the insertion costs: RA-1 bonded against RA-1 with the point joint.

``rcsa.predict`` of RA-1 at 10 000 lines (1–10 000 Hz) with the contract's point holder–tool
joint, and the same assembly with ``joints.holder_tool = {"model": "bonded"}`` (the shank in
the bore as two beams on an interface, ``rcsa.physics.insertion``), timed two ways:

* **first call** in a fresh process (``python -c`` child, after ``import rcsa``): what a
  one-off CLI run pays — the bonded insertion builds its two-port fits once per process;
* **repeated**: the median of ``--repeats`` further calls in one process, no spindle side kept
  (``rcsa.app.predictions.SIDES.size = 0``, as ``bench_engine.py`` times a cold prediction)
  but the insertion's fits kept — a new assembly of known pieces in a long-running process;
* **warm**: the same with the spindle side kept (``SIDES`` as the service runs it): the
  holder and its clamping are condensed once, as the point joint's holder is.

The ratio bonded / point is reported for each (first calls: the median of ``--children`` fresh
processes).
Written to ``benchmarks/results/clamping_cost.json``.

Run: ``.venv/bin/python benchmarks/bench_clamping_cost.py [--repeats 9] [--children 5]``
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import rcsa
from rcsa.app import predictions
from rcsa.reference import ra1
from record import load_average, write

GRID = {"start_hz": 1.0, "stop_hz": 10000.0, "step_hz": 1.0}
_CHILD = """
import json, sys, time
import rcsa
from rcsa.app import predictions
from rcsa.reference import ra1
doc = ra1(json.loads(sys.argv[1]))
if sys.argv[2] == "bonded":
    doc["joints"] = {**doc["joints"], "holder_tool": {"model": "bonded"}}
predictions.SIDES.size = 0
t0 = time.perf_counter()
rcsa.predict(doc)
print(time.perf_counter() - t0)
"""


def assembly(joint: str) -> dict:
    doc = ra1(GRID)
    if joint == "bonded":
        doc["joints"] = {**doc["joints"], "holder_tool": {"model": "bonded"}}
    return doc


def first_call_s(joint: str, children: int) -> float:
    runs = [float(subprocess.run([sys.executable, "-c", _CHILD, json.dumps(GRID), joint], check=True,
                                 capture_output=True, text=True).stdout) for _ in range(children)]
    return statistics.median(runs)


def repeated_s(joint: str, repeats: int, kept_sides: int) -> float:
    predictions.SIDES.size = kept_sides
    doc = assembly(joint)
    rcsa.predict(doc)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        rcsa.predict(doc)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--children", type=int, default=5)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    start = load_average()
    figures: dict[str, object] = {"lines": 10000, "repeats": args.repeats, "children": args.children}
    times = {joint: {"first_call_s": first_call_s(joint, args.children),
                     "repeated_s": repeated_s(joint, args.repeats, 0),
                     "warm_s": repeated_s(joint, args.repeats, predictions.SIDES_KEPT)} for joint in ("point", "bonded")}
    figures.update(times)
    print(f"RA-1 at 10 000 lines (load at start {start[0]:.1f}), bonded against point:")
    for key in ("first_call_s", "repeated_s", "warm_s"):
        ratio = times["bonded"][key] / times["point"][key]
        figures[key.replace("_s", "_ratio")] = ratio
        print(f"  {key[:-2]:<11s} point {times['point'][key] * 1e3:7.1f} ms  bonded {times['bonded'][key] * 1e3:7.1f} ms"
              f"  {ratio:5.2f}x")
    write("clamping_cost", figures, load_start=start, out=args.out)


if __name__ == "__main__":
    main()

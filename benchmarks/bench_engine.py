"""Engine benchmarks (issue 2): RA-1 at 10 000 lines, and 1 000 tools on one spindle + holder.

Run: ``.venv/bin/python benchmarks/bench_engine.py``. Prints median wall times over repeats
and the ratio against a straightforward baseline run in the same process:

* baseline for one FRF: the same exact solver called once per frequency line (a Python loop
  over frequency — what the vectorised code replaces);
* baseline for the tool library: every tool solved as a full assembly, nothing reused.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from rcsa import app
from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.elimination import tip_receptance
from rcsa.reference import ra1


def median_time_s(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def tools(n: int, rng: np.random.Generator) -> list[dict]:
    base = ra1()["tool"]
    out = []
    for i in range(n):
        stickout = float(rng.uniform(0.040, 0.090))
        out.append({**base, "stickout_m": stickout, "flute_length_m": float(rng.uniform(0.015, 0.035)),
                    "overall_length_m": stickout + 0.101, "diameter_m": float(rng.choice([0.010, 0.0127, 0.012])),
                    "shank_diameter_m": 0.0127, "fluted_diameter_ratio": float(rng.uniform(0.7, 0.85))})
        out[-1]["id"] = f"T{i:04d}"
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--tools", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()

    doc = ra1({"start_hz": 1.0, "stop_hz": 10000.0, "step_hz": 1.0})
    spec = parse_assembly(doc)
    model = build_model(spec)
    chain = model.chain()
    omega = 2 * np.pi * spec.frequency_hz
    t_vec = median_time_s(lambda: tip_receptance(chain, omega), args.repeats)
    t_pred = median_time_s(lambda: app.predict(spec), max(3, args.repeats // 2))
    sub = omega[::20]  # the loop baseline is timed on 500 lines and scaled to 10 000
    t_loop = median_time_s(lambda: [tip_receptance(chain, sub[i:i + 1]) for i in range(sub.size)], 3) * 20
    print("RA-1 tool-point FRF, 10 000 lines")
    print(f"  vectorised dynamic-stiffness solve   {t_vec * 1e3:8.1f} ms")
    print(f"  per-frequency loop (baseline)        {t_loop * 1e3:8.1f} ms   ratio {t_loop / t_vec:6.0f}x")
    print(f"  full prediction (+ exact modes, peaks, static)  {t_pred * 1e3:8.1f} ms")

    rng = np.random.default_rng(2026)
    grid = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 2.5}  # 1 999 lines
    combos = [{"id": t.pop("id"), "holder": doc["holder"], "tool": t, "joints": doc["joints"]}
              for t in tools(args.tools, rng)]
    request = {"frequency": grid, "spindle": doc["spindle"], "combinations": combos}
    # results kept as numpy arrays (what the service serialises with orjson); "list" adds ~0.7 ms/tool
    t_frf = median_time_s(lambda: app.predict_batch({**request, "natural_frequencies": False}, arrays="numpy"), 3)
    t_full = median_time_s(lambda: app.predict_batch(request, arrays="numpy"), 1)
    n_base = max(20, args.tools // 20)
    t_base = median_time_s(lambda: [app.predict({**ra1(grid), "tool": c["tool"]}) for c in combos[:n_base]], 1)
    t_base *= args.tools / n_base
    print(f"{args.tools} tools on one spindle + holder, 1 999 lines (results as contract documents)")
    print(f"  batch, FRFs + peaks (spindle+holder reused)  {t_frf:7.2f} s")
    print(f"  batch, + exact natural frequencies           {t_full:7.2f} s")
    print(f"  each tool as a full assembly (baseline)      {t_base:7.2f} s   ratio {t_base / t_full:5.1f}x")


if __name__ == "__main__":
    main()

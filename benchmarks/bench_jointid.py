"""Joint-identification benchmark (issue 5; hybrid analyses): one identification on RA-1.

Run: ``.venv/bin/python benchmarks/bench_jointid.py [--repeats N] [--stickouts 1|2]
[--spindle analytical|measured|both]`` (both by default; written to
``benchmarks/results/jointid.json``). The measurement is RA-1 (seed Table 2 joints) on
50–5000 Hz at 1 Hz (4951 lines) with 1 % complex noise; the identification starts 3× off in
both joints' k_t and c_t. ``--spindle measured`` puts RA-1's spindle in a temporary store as
its point receptance at the nose and identifies on that hybrid model. Prints the median wall
time of ``rcsa.analysis.joint_identification.identify.identify`` (request validation and,
when measured, the spindle's lookup included) and the identified values' relative errors.

Measured on the 2-core development machine (shared): analytical 1.18 s before the
condensed evaluator (``rcsa.analysis.tool_point_model``), 0.19 s after; measured spindle
0.2–0.3 s.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from rcsa.analysis.joint_identification.identify import identify
from rcsa.app.predictions import predict
from rcsa.app.stores import open_store, resolver
from rcsa.measured.store import Measurement, MeasurementMeta
from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.elimination import tip_receptance
from rcsa.reference import ra1
from record import load_average, write

TRUE = {"spindle_holder.stiffness_n_m": 3.05e7, "spindle_holder.damping_ns_m": 365.0,
        "holder_tool.stiffness_n_m": 1.14e7, "holder_tool.damping_ns_m": 34.0}


def measurement(stickout_m: float, seed: int) -> dict:
    doc = ra1({"start_hz": 50.0, "stop_hz": 5000.0, "step_hz": 1.0})
    doc["tool"]["stickout_m"] = stickout_m
    p = predict(doc)
    rng = np.random.default_rng(seed)
    h = p.tool_point.h * (1 + 0.01 * (rng.standard_normal(p.frequency_hz.size)
                                      + 1j * rng.standard_normal(p.frequency_hz.size)) / np.sqrt(2))
    return {"tool": {"stickout_m": stickout_m}, "frequency_hz": p.frequency_hz.tolist(),
            "h": {"real": h.real.tolist(), "imag": h.imag.tolist()}}


def run(spindle: str, stickouts: int, repeats: int) -> dict:
    """Identify RA-1's joints ``repeats`` times; the median time and the identified values."""
    start = ra1()
    resolve = None
    if spindle == "measured":
        spec = parse_assembly(ra1({"start_hz": 50.0, "stop_hz": 5000.0, "step_hz": 1.0}))
        s = tip_receptance(build_model(spec).spindle, 2 * np.pi * spec.frequency_hz)
        store = open_store(Path(tempfile.mkdtemp()) / "store")
        mid = store.put(Measurement(spec.frequency_hz, {"h": s[:, 0, 0], "l": s[:, 0, 1], "n": s[:, 1, 0],
                                                        "p": s[:, 1, 1]},
                                    MeasurementMeta("ra1", "x", "spindle_nose", "point_receptance")))
        start["spindle"] = {"measurement_id": mid}
        resolve = resolver(store)
    for joint in ("spindle_holder", "holder_tool"):
        start["joints"][joint]["stiffness_n_m"] *= 3.0
        start["joints"][joint]["damping_ns_m"] *= 3.0
    meas = [measurement(0.074, 1), measurement(0.060, 2)][:stickouts]
    request = {"assembly": start, "measurements": meas}
    times, out = [], {}
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = identify(request, resolve)
        times.append(time.perf_counter() - t0)
    print(f"joint identification, RA-1 ({spindle} spindle), {stickouts} measurement(s) x 4951 lines, "
          "start 3x off: "
          f"median {statistics.median(times):.2f} s over {repeats} runs (min {min(times):.2f} s)")
    print(f"status: {out['status']}  residual {100 * out['residual_rel']:.2f} % "
          f"(noise {100 * out['noise_rel']:.2f} %), {out['residual_db']:.3f} dB")
    errors = {}
    for name, truth in TRUE.items():
        joint, field = name.split(".")
        got = out["joints"][joint]
        errors[name] = got[field] / truth - 1
        print(f"  {name:32s} {got[field]:.6g}  error {got[field] / truth - 1:+.2e}  "
              f"u {got['uncertainty'][field]:.3g}")
    return {"measurements": stickouts, "lines": 4951, "median_s": statistics.median(times), "min_s": min(times),
            "status": out["status"], "relative_errors": errors, "load_average": load_average()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--stickouts", type=int, choices=(1, 2), default=1)
    parser.add_argument("--spindle", choices=("analytical", "measured", "both"), default="both")
    parser.add_argument("--out", type=Path, default=None, help="the JSON (default benchmarks/results/jointid.json)")
    args = parser.parse_args()
    begin = load_average()
    spindles = ("analytical", "measured") if args.spindle == "both" else (args.spindle,)
    figures = {spindle: run(spindle, args.stickouts, args.repeats) for spindle in spindles}
    write("jointid", {"repeats": args.repeats, **figures}, load_start=begin, out=args.out)


if __name__ == "__main__":
    main()

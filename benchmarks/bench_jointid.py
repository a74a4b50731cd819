"""Joint-identification benchmark (issue 5): one identification on RA-1.

Run: ``.venv/bin/python benchmarks/bench_jointid.py [--repeats N] [--stickouts 1|2]``.
The measurement is RA-1 (seed Table 2 joints) on 50–5000 Hz at 1 Hz (4951 lines) with 1 %
complex noise; the identification starts 3× off in both joints' k_t and c_t. Prints the
median wall time of ``rcsa.analysis.joint_identification.identify.identify`` (request validation included) and the
identified values' relative errors.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from rcsa.analysis.joint_identification.identify import identify
from rcsa.app.predictions import predict
from rcsa.reference import ra1

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--stickouts", type=int, choices=(1, 2), default=1)
    args = parser.parse_args()
    start = ra1()
    for joint in ("spindle_holder", "holder_tool"):
        start["joints"][joint]["stiffness_n_m"] *= 3.0
        start["joints"][joint]["damping_ns_m"] *= 3.0
    meas = [measurement(0.074, 1), measurement(0.060, 2)][:args.stickouts]
    request = {"assembly": start, "measurements": meas}
    times, out = [], {}
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        out = identify(request)
        times.append(time.perf_counter() - t0)
    print(f"joint identification, RA-1, {args.stickouts} measurement(s) x 4951 lines, start 3x off: "
          f"median {statistics.median(times):.2f} s over {args.repeats} runs (min {min(times):.2f} s)")
    print(f"status: {out['status']}  residual {100 * out['residual_rel']:.2f} % "
          f"(noise {100 * out['noise_rel']:.2f} %), {out['residual_db']:.3f} dB")
    for name, truth in TRUE.items():
        joint, field = name.split(".")
        got = out["joints"][joint]
        print(f"  {name:32s} {got[field]:.6g}  error {got[field] / truth - 1:+.2e}  "
              f"u {got['uncertainty'][field]:.3g}")


if __name__ == "__main__":
    main()

"""Uncertainty bands and robust lobes: time of the drawn assemblies beside one plain prediction.

RA-1 on 2 000 lines (2.5–5 000 Hz), the default tolerances. Printed (median of ``--repeat``
runs, after one warm-up):

* one plain prediction (with its exact natural frequencies), as ``rcsa.predict``;
* the same request with ``"uncertainty": {"draws": 200}`` (p05/p50/p95 of |h| and the
  natural frequencies' mean/sd over the draws: every draw's chain in one stacked march);
* the ratio of the two (issue 15's target: ≤ 10×);
* robust lobes (200 draws, 500 speeds, ZOA) end to end, beside the nominal lobes.

Run: ``.venv/bin/python benchmarks/bench_uncertainty.py [--repeat 3] [--draws 200]``
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import rcsa as app  # noqa: E402  (rcsa.predict, rcsa.stability_lobes: the application layer's calls)
from rcsa.reference import ra1  # noqa: E402

GRID = {"start_hz": 2.5, "stop_hz": 5000.0, "step_hz": 2.5}  # 2 000 lines
CUT = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
       "milling": "down", "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 500}}


def _median_s(fn, repeat: int) -> float:
    fn()  # warm-up (imports, caches)
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    """Time the band and the robust lobes and print one line each."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--draws", type=int, default=200)
    args = parser.parse_args()
    assembly = ra1(GRID)
    option = {"draws": args.draws, "seed": 1}
    plain = _median_s(lambda: app.predict(assembly), args.repeat)
    band = _median_s(lambda: app.predict({**assembly, "uncertainty": option}), args.repeat)
    print(f"RA-1, 2 000 lines: one prediction {plain:.3f} s; with {args.draws} draws {band:.3f} s "
          f"= {band / plain:.1f}x one prediction (target <= 10x)")
    nominal = _median_s(lambda: app.stability_lobes({"assembly": assembly, **CUT}), args.repeat)
    robust = _median_s(lambda: app.stability_lobes({"assembly": assembly, **CUT, "uncertainty": option}),
                       args.repeat)
    print(f"lobes, 500 speeds (ZOA): nominal {nominal:.3f} s; robust over {args.draws} draws {robust:.3f} s "
          f"= {robust / nominal:.1f}x")


if __name__ == "__main__":
    main()

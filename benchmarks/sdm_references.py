"""Converged stability limits of the cases of ``tests/analysis/lobes/converged_cases.py``.

Each limit comes from the spectral-element collocation oracle (``tests/oracles/milling_collocation.py``:
another family of method than the product's semi-discretization) at 10 collocation points per cycle
of the highest mode, bracketed to 1e-4; 14 points per cycle must put the crossing within 0.1 % of
that bracket. The search runs upwards from 10 µm to 0.2 m (a 36-point geometric scan, ratio 1.32,
then bisection).

Run: ``.venv/bin/python benchmarks/sdm_references.py [--write]`` (``--write`` stores
``tests/data/lobes/converged_limits.json``, the references ``tests/analysis/lobes/test_sdm_converged.py``
reads; a few minutes on the 2-core VM).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.analysis.lobes.converged_cases import AL7075, CASES, LIMITS  # noqa: E402
from tests.oracles.milling_collocation import Mode, depth_limit  # noqa: E402

AGREEMENT = 1e-3


def modes_of(case: dict) -> list[Mode]:
    """The case's modal table as oracle modes (y copies x when ``modal_y`` is None)."""
    y = case["modal_x"] if case["modal_y"] is None else case["modal_y"]
    return [Mode(m["frequency_hz"], m["damping_ratio"], m["modal_mass_kg"], d)
            for d, table in ((0, case["modal_x"]), (1, y)) for m in table]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--write", action="store_true", help="store tests/data/lobes/converged_limits.json")
    parser.add_argument("--case", action="append", help="only these cases")
    args = parser.parse_args()
    out = {"method": "spectral-element collocation (tests/oracles/milling_collocation.py), 10 and 14 points "
                      "per cycle of the highest mode", "cutting_coefficients": list(AL7075), "cases": {}}
    for name, case in CASES.items():
        if args.case and name not in args.case:
            continue
        modes = modes_of(case)
        rows = []
        for rpm in case["speeds"]:
            t0 = time.perf_counter()
            lim = depth_limit(modes, case["teeth"], AL7075[0], AL7075[1], case["radial_immersion"], case["milling"],
                              rpm, low_m=1e-5, high_m=0.2, scan=36, agreement=AGREEMENT)
            rows.append({"spindle_speed_rpm": rpm, "depth_limit_m": lim.depth_m, "unstable_m": lim.unstable_m,
                         "finer_agrees": lim.finer_agrees})
            print(f"{name:18s} {rpm:8.0f} rpm  {lim.depth_m * 1e3:9.4f} mm  finer agrees: {lim.finer_agrees}  "
                  f"{time.perf_counter() - t0:5.1f} s", flush=True)
            if not lim.finer_agrees:
                raise SystemExit(f"{name} at {rpm} rpm: 1.4 times the points move the limit by more than {AGREEMENT}")
        out["cases"][name] = rows
    if args.write:
        Path(LIMITS).write_text(json.dumps(out, indent=1) + "\n")
        print(f"wrote {LIMITS}")


if __name__ == "__main__":
    main()

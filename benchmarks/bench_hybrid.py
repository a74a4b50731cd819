"""Hybrid accuracy (issue 3): RA-1's 74 mm tool predicted on a spindle identified from a blank.

Synthetic tap test: h11, h21, h22 at the tip and 15 mm below it on a Ø12.7 × 60 mm carbide
blank in RA-1's holder (exact dynamic-stiffness truth), complex Gaussian relative noise,
identification by the exact three-FRF method and by the finite-difference fallback, then
the 74 mm tool coupled to the identified holder-tip receptance. Error = max |h − h_true|
over 300–5000 Hz divided by the true peak (``docs/physics.md`` §4.6). Median over seeds.

Run: ``.venv/bin/python benchmarks/bench_hybrid.py [--seeds 10]`` (written to
``benchmarks/results/hybrid.json``)
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.helpers import max_error_of_peak  # noqa: E402
from tests.measured.test_hybrid import GRID, blank_frfs, hybrid_doc, put_blank  # noqa: E402

import rcsa  # noqa: E402
from rcsa.measured.store import MeasurementStore  # noqa: E402
from rcsa.reference import ra1  # noqa: E402
from record import load_average, write  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--out", type=Path, default=None, help="the JSON (default benchmarks/results/hybrid.json)")
    args = parser.parse_args()
    begin = load_average()
    rows = []
    truth = rcsa.predict(ra1(GRID)).tool_point.h
    store = MeasurementStore(Path(tempfile.mkdtemp()) / "store")
    print("tool-point h error, fraction of the true peak, 300–5000 Hz (median over seeds)")
    print(f"{'noise':>8} {'exact 3-FRF':>12} {'FD fallback':>12}")
    for noise in (0.0, 0.002, 0.01):
        errors = {"exact": [], "finite_difference": []}
        for seed in range(args.seeds if noise else 1):
            f, frfs = blank_frfs(noise, seed)
            mid = put_blank(store, frfs, f)
            band = f >= 300
            for method in errors:
                doc = hybrid_doc(mid, holder=False)
                doc["spindle"]["artifact_method"] = method
                h = rcsa.predict(doc, store=store).tool_point.h
                errors[method].append(max_error_of_peak(h[band], truth[band]))
        print(f"{noise * 100:7.1f}% {statistics.median(errors['exact']):12.2e} "
              f"{statistics.median(errors['finite_difference']):12.3f}")
        rows.append({"noise_rel": noise, "seeds": args.seeds if noise else 1,
                     "exact_three_frf": statistics.median(errors["exact"]),
                     "finite_difference": statistics.median(errors["finite_difference"])})
    write("hybrid", {"band_hz": [300.0, 5000.0], "error": "max |h - h_true| / true peak, median over seeds",
                     "rows": rows}, load_start=begin, out=args.out)


if __name__ == "__main__":
    main()

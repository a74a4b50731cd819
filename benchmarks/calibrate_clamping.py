"""Fit the clamping model's coefficients to the 3-D reference and measure it on held-out cases.

Run: ``.venv/bin/python benchmarks/calibrate_clamping.py`` (reads ``tests/data/solid3d``, which
``benchmarks/bench_solid3d.py --write-data`` regenerates). ``--fit`` refits
:data:`rcsa.model.clamping.BULK_COEFFICIENTS` on the calibration cases (Nelder–Mead in the
logarithms of the coefficients, on every 3rd line of the band) and prints the new values;
without it, the current coefficients are scored. Results go to
``benchmarks/results/clamping.json``.

For every case of the data set and both bases (the holder's base face clamped; RA-1's spindle
and spindle–holder joint) it compares rcsa's tool-point h with the 3-D truth over 100–6000 Hz:
mean |dB|, and the largest peak's frequency and height. Models: ``point`` (the contract's beam
model: composite insertion, rigid point joint) and the case's clamping (``bonded``, or
``contact`` with the case's interface, front gap and contact length). Cases the clamping model
is not meant for (a real flute section, a rigid holder) are reported for information.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import minimize

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.oracles.solid3d import clamping_scores, dataset  # noqa: E402
from tests.oracles.solid3d.clamping_scores import CALIBRATION_CASES, INFORMATION, scores  # noqa: E402

import rcsa.model.clamping as clamping  # noqa: E402

#: Where the 3-D reference data are read (``--data`` overrides).
DATA = dataset.DATA_DIR
_FIT_EVERY = 3


def load(name: str) -> dict[str, Any]:
    """A case of the 3-D data set from :data:`DATA`."""
    return clamping_scores.load(name, DATA)


def rcsa_h(name: str, model: str, base: str, frequency_hz: np.ndarray) -> np.ndarray:
    """rcsa's tool-point h of a case of :data:`DATA` (:func:`tests.oracles.solid3d.clamping_scores.rcsa_h`)."""
    return clamping_scores.rcsa_h(name, model, base, frequency_hz, DATA)


def _objective(log_c: np.ndarray, truths: dict[tuple[str, str], np.ndarray], f: np.ndarray) -> float:
    clamping.BULK_COEFFICIENTS = _coefficients(log_c)
    total = 0.0
    for (name, base), truth in truths.items():
        s = scores(f, rcsa_h(name, "clamping", base, f), truth)
        # mean |dB| plus the largest peak's frequency error (0.1 per %²); peak heights are left out:
        # on a thinned grid a lightly damped peak's height is a sampling accident
        total += s["mean_abs_db"] + (100 * s["peak_frequency_error"]) ** 2 / 10
    return total / len(truths)


def _coefficients(log_c: np.ndarray) -> clamping.BulkCoefficients:
    a_h, b_h, a_s, c_theta, cone = np.exp(log_c)
    return clamping.BulkCoefficients(float(a_h), float(b_h), float(a_s), float(c_theta), float(cone))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fit", action="store_true", help="refit the coefficients on the calibration cases")
    parser.add_argument("--max-evaluations", type=int, default=300)
    parser.add_argument("--data", type=Path, default=dataset.DATA_DIR, help="the 3-D data set's folder")
    args = parser.parse_args()
    global DATA
    DATA = args.data
    index = json.loads((DATA / "cases.json").read_text())
    names = list(index["cases"])
    t0 = time.perf_counter()
    if args.fit:
        f_fit = load(names[0])["frequency_hz"][::_FIT_EVERY]
        truths = {(n, b): load(n)[f"h_{b}"][::_FIT_EVERY] for n in CALIBRATION_CASES if n in names for b in dataset.BASES}
        start = np.log(np.array(list(asdict(clamping.BULK_COEFFICIENTS).values())) + 1e-3)
        res = minimize(_objective, start, args=(truths, f_fit), method="Nelder-Mead",
                       options={"maxfev": args.max_evaluations, "xatol": 1e-3, "fatol": 1e-4})
        clamping.BULK_COEFFICIENTS = _coefficients(res.x)
        print(f"fitted in {res.nfev} evaluations, objective {res.fun:.4f}: {clamping.BULK_COEFFICIENTS}")
    rows = []
    for name in names:
        data = load(name)
        f = data["frequency_hz"]
        for base in dataset.BASES:
            truth = data[f"h_{base}"]
            row: dict[str, Any] = {"case": name, "base": base,
                                   "role": "calibration" if name in CALIBRATION_CASES else
                                   "information" if name in INFORMATION else "held-out"}
            for model in ("point", "clamping"):
                if name == "rigid_holder" and model == "clamping":
                    continue
                row[model] = scores(f, rcsa_h(name, model, base, f), truth)
            rows.append(row)
            c = row.get("clamping", {})
            print(f"{name:24s} {base:8s} {row['role']:11s} point {row['point']['mean_abs_db']:5.2f} dB "
                  f"{100 * row['point']['peak_frequency_error']:+6.1f} % {100 * row['point']['peak_height_error']:+5.0f} %"
                  + (f" | clamping {c['mean_abs_db']:5.2f} dB {100 * c['peak_frequency_error']:+6.2f} % "
                     f"{100 * c['peak_height_error']:+5.0f} %" if c else ""))
    held = [r["clamping"] for r in rows if r["role"] == "held-out"]
    summary = {"held_out_cases": len(held),
               "median_mean_abs_db": float(np.median([r["mean_abs_db"] for r in held])) if held else None,
               "max_mean_abs_db": float(max(r["mean_abs_db"] for r in held)) if held else None,
               "max_abs_peak_frequency_error": float(max(abs(r["peak_frequency_error"]) for r in held)) if held else None,
               "max_abs_peak_height_error": float(max(abs(r["peak_height_error"]) for r in held)) if held else None}
    print(json.dumps(summary, indent=1))
    out = {"machine": platform.processor() or platform.machine(), "python": platform.python_version(),
           "coefficients": asdict(clamping.BULK_COEFFICIENTS), "summary": summary, "rows": rows,
           "seconds": time.perf_counter() - t0}
    (REPO / "benchmarks" / "results").mkdir(exist_ok=True)
    (REPO / "benchmarks" / "results" / "clamping.json").write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()

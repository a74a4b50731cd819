"""Where zero-order lobes can be trusted: ZOA against semi-discretization over immersion × teeth.

The evidence for ``"method": "auto"`` (:func:`rcsa.analysis.lobes.options.auto_method`). For
RA-1's tool point (its two most flexible modes, fitted to the predicted FRF, the same in x
and y) and, with ``--tools``, the single-flute library's tools on RA-1's spindle, in aluminium
7075 (Kt 1319 N/mm², Kr 0.598), down milling, 160 speeds 3 000–30 000 rpm: the zero-order and
the semi-discretization limits (the default steps: resolving the cut, every speed checked at a
second resolution and refined), compared per speed (``ratio``: zero-order over
semi-discretization; ``outside``: the share of speeds outside −10 %…+5 %, the band a default
answer must keep) and reduced to their window minima over ±3 % (what a preset may use):

* **unsafe** — the share of speeds where the zero-order window limit exceeds the
  semi-discretization one by more than the safety factor 1.25: a zero-order preset there
  would chatter;
* **cautious** — the share where it is below half of it (a preset would give away more than
  half the depth);
* the median ratio.

Run: ``.venv/bin/python benchmarks/bench_zoa_vs_sdm.py [--tools]``; writes
``benchmarks/results/zoa_vs_sdm.json``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import rcsa  # noqa: E402
from rcsa.analysis.lobes.modal_model import fit_modal_model  # noqa: E402
from rcsa.analysis.lobes.options import teeth_in_cut  # noqa: E402
from rcsa.analysis.lobes.pockets import window_minimum  # noqa: E402
from rcsa.analysis.lobes.semi_discretization import semi_discretization_lobes_many  # noqa: E402
from rcsa.analysis.lobes.zoa import stability_lobes  # noqa: E402
from rcsa.reference import ra1  # noqa: E402

KT, KR = 1319.41e6, 788.83 / 1319.41
TEETH = (1, 2, 3, 4, 6)
IMMERSIONS = (0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.75, 1.0)
SPEEDS = np.geomspace(3000.0, 30000.0, 160)
OUT = ROOT / "benchmarks" / "results" / "zoa_vs_sdm.json"
BAND = (-0.10, 0.05)


def _tool_frfs(with_library: bool) -> list[tuple[str, np.ndarray, np.ndarray]]:
    grid = {"start_hz": 5.0, "stop_hz": 6000.0, "step_hz": 0.5}
    p = rcsa.predict(ra1(grid))
    out = [("RA-1", p.frequency_hz, p.tool_point.h)]
    if with_library:
        from rcsa.libraries.formats import read_library
        from rcsa.libraries.recommend_sources import predicted_frfs

        lib = ROOT / "tests" / "data" / "tool-libraries" / "fusion-single-flute" / "single_flute_library.json"
        a = ra1(grid)
        frfs = predicted_frfs(read_library(lib.read_bytes(), file_name=lib.name), spindle=a["spindle"],
                              frequency=grid, joints=a["joints"]).frfs
        out += [(k[-4:], f.frequency_hz, f.h) for k, f in list(frfs.items())[::5] if not isinstance(f, str)]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--tools", action="store_true", help="also every 5th tool of the single-flute library")
    args = parser.parse_args()
    rows = []
    start = [round(x, 2) for x in os.getloadavg()]
    t0 = time.perf_counter()
    for name, f, h in _tool_frfs(args.tools):
        model = fit_modal_model(f, h, modes_per_direction=2)
        # both methods on the same dynamics: the zero-order solution of the fitted modes' own FRF
        # (the tool point's measured-like FRF has modes the fit leaves out, which would be charged
        # to the method)
        f_model = model.frf_grid()
        h_model = model.receptance(f_model, 0)
        for teeth in TEETH:
            for ae in IMMERSIONS:
                z = stability_lobes(f_model, h_model, None, teeth=teeth, tangential_coefficient_n_m2=KT, radial_ratio=KR,
                                    radial_immersion=ae, milling="down", spindle_speed_rpm=SPEEDS)
                s = semi_discretization_lobes_many([model], teeth=teeth, tangential_coefficient_n_m2=KT, radial_ratio=KR,
                                                   radial_immersion=ae, milling="down", spindle_speed_rpm=[SPEEDS],
                                                   depth_rtol=2e-3)[0]
                both = np.isfinite(z.depth_limit_m) & np.isfinite(s.depth_limit_m) & s.resolved
                per_speed = z.depth_limit_m[both] / s.depth_limit_m[both] - 1.0
                zw = window_minimum(SPEEDS, z.depth_limit_m, 0.03)
                sw = window_minimum(SPEEDS, np.where(np.isnan(s.depth_limit_m), np.inf, s.depth_limit_m), 0.03)
                ok = np.isfinite(zw) & np.isfinite(sw)
                ratio = zw[ok] / sw[ok]
                row = {"tool": name, "teeth": teeth, "radial_immersion": ae, "teeth_in_cut": teeth_in_cut(teeth, ae),
                       "speeds_compared": int(ok.sum()),
                       "median_ratio": float(np.median(ratio)) if ratio.size else None,
                       "unsafe": float(np.mean(ratio > 1.25)) if ratio.size else None,
                       "cautious": float(np.mean(ratio < 0.5)) if ratio.size else None,
                       "speed_ratio_min": float(1 + per_speed.min()) if per_speed.size else None,
                       "speed_ratio_max": float(1 + per_speed.max()) if per_speed.size else None,
                       "outside_band": float(np.mean((per_speed < BAND[0]) | (per_speed > BAND[1])))
                       if per_speed.size else None, "sdm_unresolved": int(np.count_nonzero(~s.resolved))}
                rows.append(row)
                print(f"{name:5s} N={teeth} a_e/D={ae:4.2f} in cut {row['teeth_in_cut']:4.2f}: ZOA/SDM per speed "
                      f"{row['speed_ratio_min'] or float('nan'):5.2f}…{row['speed_ratio_max'] or float('nan'):5.2f}, "
                      f"outside -10…+5 % {row['outside_band'] or 0:4.2f}; window median "
                      f"{row['median_ratio'] or float('nan'):5.2f}, unsafe {row['unsafe'] or 0:4.2f}", flush=True)
    below = [r for r in rows if r["teeth_in_cut"] < 1.0 - 1e-9 and r["unsafe"] is not None]
    above = [r for r in rows if r["teeth_in_cut"] >= 1.0 - 1e-9 and r["unsafe"] is not None]
    summary = {"below_one_tooth_in_cut": {"cuts": len(below), "worst_unsafe": max(r["unsafe"] for r in below),
                                          "mean_unsafe": float(np.mean([r["unsafe"] for r in below]))},
               "at_least_one_tooth_in_cut": {"cuts": len(above), "worst_unsafe": max(r["unsafe"] for r in above),
                                             "worst_cautious": max(r["cautious"] for r in above),
                                             "speed_ratio_range": [min(r["speed_ratio_min"] for r in above),
                                                                   max(r["speed_ratio_max"] for r in above)],
                                             "worst_outside_band": max(r["outside_band"] for r in above),
                                             "mean_outside_band": float(np.mean([r["outside_band"] for r in above])),
                                             "median_ratio_range": [min(r["median_ratio"] for r in above),
                                                                    max(r["median_ratio"] for r in above)]}}
    print(json.dumps(summary, indent=1))
    from benchmarks.record import write

    write("zoa_vs_sdm", {"seconds": time.perf_counter() - t0, "band": list(BAND), "summary": summary, "rows": rows},
          load_start=start)


if __name__ == "__main__":
    main()

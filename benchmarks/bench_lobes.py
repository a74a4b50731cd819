"""Stability lobes: semi-discretization (SDM) time for a web-page request, beside baselines.

Typical request: RA-1's tool point as 2 modes in x and 2 in y (its two most flexible modes,
fitted to the predicted FRF), 4 teeth, half-immersion down-milling, 500 speeds
2 000–30 000 rpm, 40 steps per tooth period. Printed:

* SDM, vectorised over speeds (this library), median of ``--repeat`` runs;
* a straightforward per-speed SDM (a Python loop over speeds: the period map built step by
  step with ``scipy.linalg.expm`` of the augmented step matrix and the full delay chain,
  dense eigenvalues, the same scan-and-bisect depth search), timed on every
  ``--baseline-every``-th speed and scaled to 500 (its depths are checked against the SDM's);
* ZOA (Altintas–Budak) on the predicted FRF for the same speeds;
* the SDM with the default 3 modes per direction, at low immersion (a/D = 0.05, 2 teeth),
  and end to end through the application layer (prediction + exact modes + SDM);
* the issue-22.4 yardstick: the SDM time over ``rcsa.predict`` of RA-1 at 10 000 lines in the
  same process (target ≤ 25×; in wall and in CPU time — on a loaded machine the CPU ratio is the
  steadier figure), and the limits against those the replaced per-speed search gave
  on the same three 500-speed cuts (``tests/data/lobes/sdm_reference.json``; target: within
  0.5 %).

BLAS runs single-threaded here (``OPENBLAS_NUM_THREADS=1`` unless set): on this shared 2-core
VM, threaded OpenBLAS makes the baseline's small 88 × 88 products ~100× slower, which would
flatter the ratio; the vectorised SDM is unaffected (±5 %).

Run: ``.venv/bin/python benchmarks/bench_lobes.py [--repeat 3] [--baseline-every 25]``
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy.linalg import expm  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import rcsa  # noqa: E402
from rcsa.analysis.lobes.modal_model import ModalModel, fit_modal_model  # noqa: E402
from rcsa.analysis.lobes.semi_discretization import semi_discretization_lobes  # noqa: E402
from rcsa.analysis.lobes.zoa import (  # noqa: E402
    directional_factors,
    engagement_angles_rad,
    stability_lobes,
)
from rcsa.reference import ra1  # noqa: E402

GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
CUT = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
       "milling": "down"}
SPEEDS = np.linspace(2000.0, 30000.0, 500)
STEPS = 40


def _timed(fn, repeat: int, cpu: list | None = None):
    """Median wall time and the result; the median CPU time of the process is appended to ``cpu``."""
    times, cpus, out = [], [], None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        times.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    if cpu is not None:
        cpu.append(statistics.median(cpus))
    return statistics.median(times), out


def _loop_rho(model: ModalModel, rpm: float, depth: float) -> float:
    """Spectral radius of the SDM map built the straightforward way (one speed, one depth)."""
    teeth, kt, kr = CUT["teeth"], CUT["tangential_coefficient_n_m2"], CUT["radial_ratio"]
    st, ex = engagement_angles_rad(CUT["radial_immersion"], CUT["milling"])
    w = 2 * np.pi * model.frequency_hz
    d = w.size
    c = np.zeros((2, d))
    c[model.direction, np.arange(d)] = np.sqrt(model.residue_1_kg)
    dphi, h = 2 * np.pi / (teeth * STEPS), 60.0 / (rpm * teeth) / STEPS
    size = 2 * d + 2 * STEPS
    phi = np.eye(size)
    for i in range(STEPS):
        force = np.zeros((2, 2))
        for j in range(teeth):
            lo = min(max(i * dphi + j * 2 * np.pi / teeth, st), ex)
            hi = min(max((i + 1) * dphi + j * 2 * np.pi / teeth, st), ex)
            if hi > lo:
                force += -0.5 * directional_factors(lo, hi, kr) / dphi
        kf = depth * kt * force
        aug = np.zeros((2 * d + 4, 2 * d + 4))
        aug[:d, d : 2 * d] = np.eye(d)
        aug[d : 2 * d, :d] = -np.diag(w**2) - c.T @ kf @ c
        aug[d : 2 * d, d : 2 * d] = -np.diag(2 * model.damping_ratio * w)
        aug[d : 2 * d, 2 * d : 2 * d + 2] = c.T @ kf
        aug[2 * d : 2 * d + 2, 2 * d + 2 :] = np.eye(2) / h
        e = expm(aug * h)
        step = np.zeros((size, size))
        step[: 2 * d, : 2 * d] = e[: 2 * d, : 2 * d]
        step[: 2 * d, size - 2 :] += e[: 2 * d, 2 * d : 2 * d + 2] - e[: 2 * d, 2 * d + 2 :]
        step[: 2 * d, size - 4 : size - 2] += e[: 2 * d, 2 * d + 2 :]
        step[2 * d : 2 * d + 2, :d] = c
        step[2 * d + 2 :, 2 * d : size - 2] = np.eye(2 * STEPS - 2)
        phi = step @ phi
    return float(np.max(np.abs(np.linalg.eigvals(phi))))


def _loop_depth(model: ModalModel, rpm: float, start_m: float, rtol: float = 1e-3) -> float:
    """Scan upward by 1.6× from ``start_m``, then bisect the first crossing of |μ| = 1."""
    lo, hi = 0.0, start_m
    while _loop_rho(model, rpm, hi) < 1.0:
        lo, hi = hi, 1.6 * hi
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _loop_rho(model, rpm, mid) >= 1.0 else (mid, hi)
    return lo


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--baseline-every", type=int, default=25)
    args = parser.parse_args()
    prediction = rcsa.predict(ra1(GRID))
    f, h = prediction.frequency_hz, prediction.tool_point.h
    typical = fit_modal_model(f, h, modes_per_direction=2)
    default = fit_modal_model(f, h, modes_per_direction=3)
    print(f"stability lobes, RA-1 tool point, {SPEEDS.size} speeds 2 000–30 000 rpm, 4 teeth, a/D = 0.5 "
          f"down, k = {STEPS}  (load average {os.getloadavg()[0]:.1f})")

    def sdm(model: ModalModel, **cut):
        return semi_discretization_lobes(model, **{**CUT, **cut}, spindle_speed_rpm=SPEEDS,
                                         steps_per_period=STEPS)

    cpu_sdm: list[float] = []
    t_sdm, result = _timed(lambda: sdm(typical), args.repeat, cpu_sdm)
    print(f"  SDM, 4 modes (2 in x, 2 in y), vectorised   {t_sdm:8.2f} s")
    sub = np.arange(0, SPEEDS.size, args.baseline_every)
    start = result.depth_search_max_m / 64.0 / 4.0  # the SDM's own scan start, b_ref/4
    t0 = time.perf_counter()
    loop = np.array([_loop_depth(typical, SPEEDS[i], start) for i in sub])
    t_loop = (time.perf_counter() - t0) * SPEEDS.size / sub.size
    agree = np.max(np.abs(loop / result.depth_limit_m[sub] - 1))
    print(f"  per-speed loop SDM (baseline, {sub.size} speeds × {SPEEDS.size / sub.size:g})"
          f" {t_loop:8.1f} s   ratio {t_loop / t_sdm:6.0f}x   depths agree to {agree:.1e}")
    t_zoa, _ = _timed(lambda: stability_lobes(f, h, **CUT, spindle_speed_rpm=SPEEDS), args.repeat)
    print(f"  ZOA on the predicted FRF                     {t_zoa * 1e3:8.1f} ms")
    t_def, _ = _timed(lambda: sdm(default), args.repeat)
    print(f"  SDM, default 3 modes per direction (6 modes) {t_def:8.2f} s")
    t_low, low = _timed(lambda: sdm(typical, teeth=2, radial_immersion=0.05), args.repeat)
    print(f"  SDM, 4 modes, a/D = 0.05, 2 teeth            {t_low:8.2f} s   "
          f"({int(np.sum(low.instability == 'flip'))} speeds flip-limited)")
    request = {"assembly": ra1(GRID), **CUT, "method": "semi_discretization",
               "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 500}}
    t_app, _ = _timed(lambda: rcsa.stability_lobes(request), args.repeat)
    print(f"  end to end (predict + exact modes + SDM, 3 per direction) {t_app:6.2f} s")
    big = ra1({"start_hz": 1.0, "stop_hz": 10000.0, "step_hz": 1.0})
    from rcsa.app import predictions

    warm: list[float] = []
    t_warm, _ = _timed(lambda: rcsa.predict(big), 5 * args.repeat, warm)
    kept, predictions.SIDES.size = predictions.SIDES.size, 0  # cold, as bench_engine.py and the issue time it
    cpu_pred: list[float] = []
    t_pred, _ = _timed(lambda: rcsa.predict(big), 5 * args.repeat, cpu_pred)
    predictions.SIDES.size = kept
    print(f"  rcsa.predict of RA-1, 10 000 lines, cold       {t_pred * 1e3:8.1f} ms   SDM (4 modes) / prediction "
          f"{t_sdm / t_pred:5.1f}x  (target <= 25x)")
    print(f"    (warm, the spindle side kept from the call before: {t_warm * 1e3:.1f} ms, ratio {t_sdm / t_warm:.1f}x)")
    print(f"  the same in CPU time: SDM {cpu_sdm[0]:.2f} s, prediction {cpu_pred[0] * 1e3:.1f} ms, "
          f"ratio {cpu_sdm[0] / cpu_pred[0]:5.1f}x  (load average {os.getloadavg()[0]:.1f})")
    _against_reference()


def _against_reference() -> None:
    """The three 500-speed cuts of tests/data/lobes/sdm_reference.json, solved again."""
    reference = json.loads((Path(__file__).resolve().parents[1] / "tests" / "data" / "lobes" /
                            "sdm_reference.json").read_text())
    for case in (c for c in reference["cases"] if c["benchmark_only"]):
        grid = case["spindle_speed_rpm"]
        model = ModalModel.of(**case["modal_model"])
        t0 = time.perf_counter()
        r = semi_discretization_lobes(model, **{k: case[k] for k in ("teeth", "tangential_coefficient_n_m2",
                                                                       "radial_ratio", "radial_immersion", "milling")},
                                      spindle_speed_rpm=np.linspace(grid["start"], grid["stop"], grid["count"]))
        elapsed = time.perf_counter() - t0
        old = np.array([np.nan if x is None else x for x in case["depth_limit_m"]])
        dev = np.nanmax(np.abs(r.depth_limit_m / old - 1))
        same_kind = np.mean(r.instability == np.array(case["instability"]))
        print(f"  vs the replaced solver, {case['name']:24s} {elapsed:6.2f} s   max |limit/old - 1| {dev:.1e}   "
              f"same kind at {same_kind:.0%} of speeds")


if __name__ == "__main__":
    main()

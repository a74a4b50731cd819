"""Stability lobes: the resolved semi-discretization a request with only the cut gets, timed (issue 29).

The yardstick of issue 29: RA-1's tool point (its exact modes, every one above the peak
threshold: 4 a direction), 2 teeth, a/D = 0.05 down milling, 500 speeds 2 000–30 000 rpm, the
default steps (resolving the cut, every speed checked at a second resolution, refined where they
differ), against a warm ``rcsa.predict`` of RA-1 at 10 000 lines in the same process (its spindle
side kept, as a user's next tool; the prediction computed, not answered from the kept predictions:
``benchmarks/_yardstick.py``; target ≤ 25×). Printed beside it:

* a straightforward per-speed loop of the same cut-window maps (``scipy.linalg.expm`` of the
  augmented step matrix per step, the full chain of delayed samples, dense eigenvalues, a
  scan-and-bisect search), timed on every ``--baseline-every``-th speed with each speed's final
  steps and scaled to 500 (its depths are checked against the vectorised ones);
* the last release's default for the same cut (40 steps over the period): faster, and wrong
  where it is not resolved;
* the request end to end through the application layer (prediction + exact modes + lobes), and
  with its speeds shared by two worker processes as ``rcsa lobes`` runs here by default (the
  workers started in the call, and kept from the call before);
* the (speed, depth) evaluations the resolved diagram takes, counted in one more run, and the
  ratio it would have at :data:`FLOOR_EVALUATIONS` a speed with today's cost per evaluation
  (why the 25× target is out of this method's reach);
* the replaced solver's three 500-speed cuts (``tests/data/lobes/sdm_reference.json``) with its
  40 steps over the period: the limits within 0.5 %.

BLAS runs single-threaded here (``OPENBLAS_NUM_THREADS=1`` unless set): on this shared 2-core
VM, threaded OpenBLAS makes the baseline's small products far slower, which would flatter the
ratio. Results: ``benchmarks/results/lobes.json``.

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

from benchmarks import record  # noqa: E402
from benchmarks._yardstick import warm_ra1_prediction_s  # noqa: E402

import rcsa  # noqa: E402
from rcsa.analysis.lobes import semi_discretization  # noqa: E402
from rcsa.analysis.lobes.modal_model import ModalModel, modal_model_from_assembly  # noqa: E402
from rcsa.analysis.lobes.semi_discretization import resolving_steps, semi_discretization_lobes  # noqa: E402
from rcsa.analysis.lobes.zoa import (  # noqa: E402
    directional_factors,
    engagement_angles_rad,
)
from rcsa.app.analyses import LobesAnswer, stability_lobes_answer  # noqa: E402
from rcsa.infra.compute_backends import ProcessBackend  # noqa: E402
from rcsa.model.contract import parse_assembly  # noqa: E402
from rcsa.reference import ra1  # noqa: E402

GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
CUT = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
       "milling": "down"}
SPEEDS = np.linspace(2000.0, 30000.0, 500)
STEPS = 40
#: A generous floor on the evaluations a limit checked at a second resolution needs: a stable and an
#: unstable depth to bracket it (only if the first guess is right to the bracket's tolerance) and one
#: at the other resolution (a check within ±1 % takes two).
FLOOR_EVALUATIONS = 3


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


def _window_rho(model: ModalModel, teeth: int, immersion: float, rpm: float, depth: float, steps: int) -> float:
    """Spectral radius of the cut-window map built the straightforward way: ``scipy.linalg.expm`` of the
    augmented step matrix per cutting step, one ``expm`` for the free flight, the full chain of the
    window's delayed samples, dense eigenvalues (one speed, one depth)."""
    kt, kr = CUT["tangential_coefficient_n_m2"], CUT["radial_ratio"]
    st, ex = engagement_angles_rad(immersion, "down")
    w = 2 * np.pi * model.frequency_hz
    d = w.size
    c = np.zeros((2, d))
    c[model.direction, np.arange(d)] = np.sqrt(model.residue_1_kg)
    period = 60.0 / (rpm * teeth)
    cut = teeth * (ex - st) / (2 * np.pi) * period
    dphi, h = (ex - st) / steps, cut / steps
    nodes = steps + 1
    size = 2 * d + 2 * nodes  # [q; q̇; r_0 … r_K of the previous window]
    phi = np.eye(size)
    state = np.eye(size)[: 2 * d]  # the state as a function of the start of the window
    rows = []
    for i in range(steps):
        rows.append(c @ state[:d])
        kf = depth * kt * (-0.5 * directional_factors(st + i * dphi, st + (i + 1) * dphi, kr) / dphi)
        aug = np.zeros((2 * d + 4, 2 * d + 4))
        aug[:d, d : 2 * d] = np.eye(d)
        aug[d : 2 * d, :d] = -np.diag(w**2) - c.T @ kf @ c
        aug[d : 2 * d, d : 2 * d] = -np.diag(2 * model.damping_ratio * w)
        aug[d : 2 * d, 2 * d : 2 * d + 2] = c.T @ kf
        aug[2 * d : 2 * d + 2, 2 * d + 2 :] = np.eye(2) / h
        e = expm(aug * h)
        delayed = np.zeros((4, size))
        delayed[:, 2 * d + 2 * i : 2 * d + 2 * i + 4] = np.eye(4)
        state = e[: 2 * d, : 2 * d] @ state + np.hstack([e[: 2 * d, 2 * d : 2 * d + 2] - e[: 2 * d, 2 * d + 2 :],
                                                        e[: 2 * d, 2 * d + 2 :]]) @ delayed
    rows.append(c @ state[:d])
    free = np.zeros((2 * d, 2 * d))
    free[:d, d:] = np.eye(d)
    free[d:, :d] = -np.diag(w**2)
    free[d:, d:] = -np.diag(2 * model.damping_ratio * w)
    phi[: 2 * d] = expm(free * (period - cut)) @ state
    phi[2 * d :] = np.vstack(rows)
    return float(np.max(np.abs(np.linalg.eigvals(phi))))


def _window_depth(model: ModalModel, teeth: int, immersion: float, rpm: float, steps: int, start_m: float,
                  rtol: float = 1e-3) -> float:
    """Scan upward by 1.6× from ``start_m``, then bisect the first crossing of |μ| = 1."""
    lo, hi = 0.0, start_m
    while _window_rho(model, teeth, immersion, rpm, hi, steps) < 1.0:
        lo, hi = hi, 1.6 * hi
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _window_rho(model, teeth, immersion, rpm, mid, steps) >= 1.0 else (mid, hi)
    return lo


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--baseline-every", type=int, default=25)
    args = parser.parse_args()
    load = record.load_average()
    spec = parse_assembly(ra1(GRID))
    prediction = rcsa.predict(ra1(GRID))
    f, h = prediction.frequency_hz, prediction.tool_point.h
    exact = modal_model_from_assembly(spec, frequency_hz=f, h=h)  # every mode above the threshold
    low = {"teeth": 2, "radial_immersion": 0.05}
    print(f"resolved stability lobes, RA-1's tool point ({exact.n_modes // 2} modes a direction), "
          f"{SPEEDS.size} speeds 2 000–30 000 rpm, 2 teeth, a/D = 0.05 down (load average {load[0]:.1f})")

    def resolved():
        return semi_discretization_lobes(exact, **{**CUT, **low}, spindle_speed_rpm=SPEEDS)

    cpu: list[float] = []
    t_sdm, result = _timed(resolved, args.repeat, cpu)
    evaluations = _count_evaluations(resolved)
    per_eval_s = t_sdm / evaluations
    refined = int(np.count_nonzero(result.steps > resolving_steps(exact, 2, SPEEDS, radial_immersion=0.05)))
    print(f"  resolved semi-discretization (default steps, checked, refined)  {t_sdm:8.2f} s   "
          f"{int(result.resolved.sum())}/{SPEEDS.size} resolved, {refined} refined, steps "
          f"{int(result.steps.min())}–{int(result.steps.max())}")
    sub = np.arange(0, SPEEDS.size, args.baseline_every)
    t0 = time.perf_counter()
    loop = np.array([_window_depth(exact, 2, 0.05, SPEEDS[i], int(result.steps[i]),
                                   0.5 * float(np.nanmin(result.depth_limit_m))) for i in sub])
    t_loop = (time.perf_counter() - t0) * SPEEDS.size / sub.size
    agree = float(np.nanmax(np.abs(loop / result.depth_limit_m[sub] - 1)))
    print(f"  per-speed loop of the same maps (baseline, {sub.size} speeds × {SPEEDS.size / sub.size:g})"
          f" {t_loop:8.1f} s   ratio {t_loop / t_sdm:6.1f}x   depths agree to {agree:.1e}")
    t_old, _ = _timed(lambda: semi_discretization_lobes(exact, **{**CUT, **low}, spindle_speed_rpm=SPEEDS,
                                                        steps_per_period=STEPS), args.repeat)
    print(f"  the last release's default: 40 steps over the period, checked, not refined  {t_old:8.2f} s")
    t_warm, cpu_warm = warm_ra1_prediction_s(5 * args.repeat)
    warm = [cpu_warm]
    print(f"  rcsa.predict of RA-1, 10 000 lines, warm (spindle side kept, prediction computed)  "
          f"{t_warm * 1e3:8.1f} ms   resolved lobes / prediction {t_sdm / t_warm:7.1f}x  (target <= 25x)")
    floor = FLOOR_EVALUATIONS * SPEEDS.size * per_eval_s
    print(f"  (speed, depth) evaluations {evaluations} ({evaluations / SPEEDS.size:.1f} a speed, "
          f"{per_eval_s * 1e3:.2f} ms each); at {FLOOR_EVALUATIONS} a speed, the least a checked limit could need: "
          f"{floor:.2f} s = {floor / t_warm:.0f}x the warm prediction")
    print(f"  in CPU time: lobes {cpu[0]:.2f} s, prediction {warm[0] * 1e3:.1f} ms, ratio {cpu[0] / warm[0]:7.1f}x")
    request = {"assembly": ra1(GRID), **CUT, **low, "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 500}}
    t_app, app_result = _timed(lambda: rcsa.stability_lobes(request), args.repeat)
    print(f"  end to end, a request with only the cut (auto: predict + exact modes + resolved SDM) {t_app:6.2f} s")
    whole = np.array([np.nan if x is None else x for x in app_result["depth_limit_m"]], dtype=float)
    spread = _spread(request, whole, args.repeat, t_app, t_warm)
    figures = {"speeds": int(SPEEDS.size), "modes_per_direction": exact.n_modes // 2, "resolved_s": t_sdm,
               "resolved_cpu_s": cpu[0], "resolved_speeds": int(result.resolved.sum()), "refined_speeds": refined,
               "steps_min": int(result.steps.min()), "steps_max": int(result.steps.max()),
               "baseline_loop_s": t_loop, "baseline_ratio": t_loop / t_sdm, "baseline_agreement": agree,
               "old_default_k40_s": t_old, "warm_prediction_s": t_warm, "warm_prediction_cpu_s": warm[0],
               "ratio_to_warm_prediction": t_sdm / t_warm, "cpu_ratio_to_warm_prediction": cpu[0] / warm[0],
               "end_to_end_s": t_app, "evaluations": evaluations, "evaluations_per_speed": evaluations / SPEEDS.size,
               "seconds_per_evaluation": per_eval_s, "floor_evaluations_per_speed": FLOOR_EVALUATIONS,
               "floor_s": floor, "floor_ratio_to_warm_prediction": floor / t_warm, **spread}
    figures["against_replaced_solver"] = _against_reference()
    record.write("lobes", figures, load_start=load)


def _count_evaluations(solve) -> int:
    """The (speed, depth) pairs whose period map ``solve()`` evaluates, counted in one more (untimed)
    run by wrapping the solver's evaluator (instrumentation only: the numbers are not touched)."""
    evaluator = semi_discretization._Evaluator
    original = evaluator.__call__
    count = 0

    def counted(self, idx, depth_m, record_stable=False):
        nonlocal count
        count += int(np.size(idx))
        return original(self, idx, depth_m, record_stable)

    evaluator.__call__ = counted
    try:
        solve()
    finally:
        evaluator.__call__ = original
    return count


def on_two_workers(request: dict, repeat: int) -> tuple[list[float], list[float], list[LobesAnswer]]:
    """``request`` end to end with its semi-discretizations shared by two worker processes, ``repeat``
    times: the seconds with the workers started in the call (a fresh ``ProcessBackend(2)`` each time,
    as one command pays), those with them kept from the call before (as a long-running caller that
    keeps its backend), and the answers of the kept calls."""
    fresh, kept, answers = [], [], []
    for _ in range(repeat):
        backend = ProcessBackend(2)
        try:
            t0 = time.perf_counter()
            stability_lobes_answer(request, backend=backend)
            fresh.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            answers.append(stability_lobes_answer(request, backend=backend))
            kept.append(time.perf_counter() - t0)
        finally:
            backend.close()
    return fresh, kept, answers


def _spread(request: dict, whole: np.ndarray, repeat: int, t_app: float, t_warm: float) -> dict:
    """The same request end to end with its speeds shared by two worker processes, as ``rcsa lobes``
    runs here by default (``--workers 0``: one per core): the workers started in the call (a
    fresh ``ProcessBackend(2)`` each time, as one command pays), and kept from the call before
    (as a long-running caller that keeps its backend); their limits against ``whole``, one process's."""
    fresh, kept, answers = on_two_workers(request, repeat)
    agree = max(float(np.nanmax(np.abs(a.nominal.depth_limit_m / whole - 1))) for a in answers)
    t_fresh, t_kept = statistics.median(fresh), statistics.median(kept)
    print(f"  … its speeds shared by 2 worker processes (rcsa lobes' default here): workers started in the call "
          f"{t_fresh:6.2f} s ({t_app / t_fresh:.2f}x faster, {t_fresh / t_warm:.0f}x the warm prediction), workers "
          f"kept {t_kept:6.2f} s ({t_app / t_kept:.2f}x, {t_kept / t_warm:.0f}x); limits within {agree:.1e} of one "
          "process's")
    return {"spread_2_workers_fresh_s": t_fresh, "spread_2_workers_kept_s": t_kept,
            "spread_speedup_fresh": t_app / t_fresh, "spread_speedup_kept": t_app / t_kept,
            "spread_fresh_ratio_to_warm_prediction": t_fresh / t_warm,
            "spread_kept_ratio_to_warm_prediction": t_kept / t_warm, "spread_agreement": agree}


def _against_reference() -> list[dict]:
    """The three 500-speed cuts of tests/data/lobes/sdm_reference.json, solved again with the replaced
    solver's 40 steps over the period."""
    out = []
    reference = json.loads((Path(__file__).resolve().parents[1] / "tests" / "data" / "lobes" /
                            "sdm_reference.json").read_text())
    for case in (c for c in reference["cases"] if c["benchmark_only"]):
        grid = case["spindle_speed_rpm"]
        model = ModalModel.of(**case["modal_model"])
        t0 = time.perf_counter()
        r = semi_discretization_lobes(model, **{k: case[k] for k in ("teeth", "tangential_coefficient_n_m2",
                                                                       "radial_ratio", "radial_immersion", "milling")},
                                      spindle_speed_rpm=np.linspace(grid["start"], grid["stop"], grid["count"]),
                                      steps_per_period=STEPS)
        elapsed = time.perf_counter() - t0
        old = np.array([np.nan if x is None else x for x in case["depth_limit_m"]])
        dev = np.nanmax(np.abs(r.depth_limit_m / old - 1))
        same_kind = np.mean(r.instability == np.array(case["instability"]))
        print(f"  vs the replaced solver, {case['name']:24s} {elapsed:6.2f} s   max |limit/old - 1| {dev:.1e}   "
              f"same kind at {same_kind:.0%} of speeds")
        out.append({"case": case["name"], "seconds": elapsed, "max_deviation": float(dev),
                    "same_kind": float(same_kind)})
    return out


if __name__ == "__main__":
    main()

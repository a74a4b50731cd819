"""Uncertainty bands and robust lobes: the reduced model of the draws beside one plain prediction.

RA-1 on 2 000 lines (2.5–5 000 Hz), the default tolerances, 200 draws. Printed, each a median
of ``--repeat`` runs after one warm-up, in one process:

* one plain prediction (with its exact natural frequencies), as ``rcsa.predict``;
* the same request with ``"uncertainty": {"draws": 200}`` — the reduced model of the draws
  (``rcsa.model.reduced_draws``, the default solver) — and its ratio to the prediction
  (issue 22's target: ≤ 10×), wall time and CPU time;
* the same with ``"solver": "exact"`` (every draw on every line: the baseline);
* how far the reduced band is from the exact one: the largest pointwise relative error of
  p05/p50/p95 of |h| over the band, and of each natural frequency's mean and sd (target 2 %);
* the same on a measured spindle (RA-1's modelled spindle stored as a direct FRF): without
  noise (the reduced model applies) and with the default noise (solved exactly, line by line);
* robust lobes (200 draws, 500 speeds, ZOA), reduced and exact, beside the nominal lobes.

Run: ``.venv/bin/python benchmarks/bench_uncertainty.py [--repeat 3] [--draws 200] [--quick]``
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import rcsa as app  # noqa: E402  (rcsa.predict, rcsa.stability_lobes: the application layer's calls)
from rcsa.app import predictions  # noqa: E402
from rcsa.measured.store import Measurement, MeasurementMeta, MeasurementStore  # noqa: E402
from rcsa.model.assembly import build_model  # noqa: E402
from rcsa.model.contract import parse_assembly  # noqa: E402
from rcsa.physics.elimination import tip_receptance  # noqa: E402
from rcsa.reference import ra1  # noqa: E402
from record import load_average, write  # noqa: E402

GRID = {"start_hz": 2.5, "stop_hz": 5000.0, "step_hz": 2.5}  # 2 000 lines
CUT = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
       "milling": "down", "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 500}}


def _median(fn: Callable[[], object], repeat: int) -> tuple[float, float]:
    """Median wall and CPU time of ``fn`` over ``repeat`` runs after a warm-up, s."""
    fn()
    wall, cpu = [], []
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu)


def _band(result: dict) -> np.ndarray:
    u = result["uncertainty"]["h_magnitude_m_n"]
    return np.array([u[k] for k in ("p05", "p50", "p95")])


def _errors(reduced: dict, exact: dict) -> dict[str, float]:
    """The band's and the natural frequencies' largest relative errors."""
    a, b = _band(reduced), _band(exact)
    out = {"band_pointwise": float(np.max(np.abs(a / b - 1.0))), "band_of_peak": float(np.max(np.abs(a - b)) / np.max(b))}
    ra, rb = reduced["uncertainty"]["natural_frequencies_hz"], exact["uncertainty"]["natural_frequencies_hz"]
    if rb["mean"]:
        out["modes_mean"] = float(np.max(np.abs(np.array(ra["mean"]) / rb["mean"] - 1.0)))
        out["modes_sd"] = float(np.max(np.abs(np.array(ra["sd"]) / rb["sd"] - 1.0)))
    return out


def _said(errors: dict[str, float]) -> str:
    """:func:`_errors` as printed."""
    text = (f"band (p05/p50/p95 of |h|, pointwise) {errors['band_pointwise']:.2%}, relative to the peak "
            f"{errors['band_of_peak']:.3%}")
    if "modes_mean" in errors:
        text += f"; natural frequencies: mean {errors['modes_mean']:.3%}, sd {errors['modes_sd']:.2%}"
    return text


def _times(t: tuple[float, float], plain: tuple[float, float]) -> dict[str, float]:
    return {"wall_ms": t[0] * 1e3, "cpu_ms": t[1] * 1e3, "wall_ratio": t[0] / plain[0], "cpu_ratio": t[1] / plain[1]}


def _line(label: str, t: tuple[float, float], plain: tuple[float, float]) -> str:
    return (f"  {label:44s} {t[0] * 1e3:8.1f} ms wall = {t[0] / plain[0]:5.1f}x, "
            f"CPU {t[1] * 1e3:7.1f} ms = {t[1] / plain[1]:5.1f}x one prediction")


def _hybrid(draws: int, repeat: int) -> dict[str, object]:
    """RA-1 on its own modelled spindle stored as a direct FRF (rotations estimated)."""
    store = MeasurementStore(Path(tempfile.mkdtemp()) / "store")
    spec = parse_assembly(ra1(GRID))
    s = tip_receptance(build_model(spec).spindle, 2 * np.pi * spec.frequency_hz)
    ident = store.put(Measurement(spec.frequency_hz, {"h": s[:, 0, 0]},
                                  MeasurementMeta("ra1", "x", "spindle_nose", "direct_frf")))
    doc = {**ra1(GRID), "spindle": {"measurement_id": ident}}
    plain = _median(lambda: app.predict(doc, store=store), repeat)
    print(f"measured spindle (RA-1's as a direct FRF), 2 000 lines: one prediction {plain[0] * 1e3:.1f} ms")
    out: dict[str, object] = {"prediction_ms": plain[0] * 1e3}
    for key, label, option in (("no_noise", "no noise (rotation lengths drawn)",
                                {"tolerances": {"spindle_noise_rel": 0.0}}),
                               ("default_noise", "default noise (0.5 % on every line)", {})):
        opt = {"draws": draws, "seed": 1, **option}
        reduced = _median(lambda o=opt: app.predict({**doc, "uncertainty": o}, store=store), repeat)
        exact = _median(lambda o=opt: app.predict({**doc, "uncertainty": {**o, "solver": "exact"}}, store=store),
                        repeat)
        print(_line(f"{label}: {draws} draws", reduced, plain))
        print(_line("  the same, every draw exact", exact, plain))
        r = app.predict({**doc, "uncertainty": opt}, store=store)
        e = app.predict({**doc, "uncertainty": {**opt, "solver": "exact"}}, store=store)
        errors = _errors(r, e)
        print(f"    reduced vs exact: {_said(errors)}"
              + ("" if "reduced_model" in r["uncertainty"] else " (solved exactly: noise on every line)"))
        out[key] = {"reduced": _times(reduced, plain), "exact": _times(exact, plain), "errors": errors,
                    "reduced_model_used": "reduced_model" in r["uncertainty"]}
    return out


def main() -> None:
    """Time the bands and robust lobes, print their errors."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--draws", type=int, default=200)
    parser.add_argument("--quick", action="store_true", help="RA-1 only: no measured spindle, no lobes")
    parser.add_argument("--out", type=Path, default=None, help="the JSON (default benchmarks/results/uncertainty.json)")
    args = parser.parse_args()
    begin = load_average()
    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}, "
          f"{os.cpu_count()} cores; load average {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    predictions.SIDES.size = 0  # cold predictions, as bench_engine.py times them: no spindle side kept across calls
    assembly = ra1(GRID)
    option = {"draws": args.draws, "seed": 1}
    plain = _median(lambda: app.predict(assembly), args.repeat)
    reduced = _median(lambda: app.predict({**assembly, "uncertainty": option}), args.repeat)
    exact = _median(lambda: app.predict({**assembly, "uncertainty": {**option, "solver": "exact"}}), args.repeat)
    print(f"RA-1, 2 000 lines: one prediction {plain[0] * 1e3:.1f} ms wall, {plain[1] * 1e3:.1f} ms CPU")
    print(_line(f"band, {args.draws} draws, reduced model (target <= 10x)", reduced, plain))
    print(_line(f"band, {args.draws} draws, every draw exact (baseline)", exact, plain))
    r = app.predict({**assembly, "uncertainty": option})
    e = app.predict({**assembly, "uncertainty": {**option, "solver": "exact"}})
    model = r["uncertainty"]["reduced_model"]
    errors = _errors(r, e)
    print(f"  reduced vs exact: {_said(errors)}")
    print(f"  reduced model: {model['lines_per_draw_mean']:.0f} of 2 000 lines per draw, {model['resonances']} "
          f"resonances, largest check error {model['max_check_error']:.2%}, "
          f"{model['draws_solved_on_every_line']} draws solved on every line")
    figures: dict[str, object] = {
        "lines": 2000, "draws": args.draws, "repeat": args.repeat,
        "ra1": {"prediction_wall_ms": plain[0] * 1e3, "prediction_cpu_ms": plain[1] * 1e3,
                "reduced": _times(reduced, plain), "exact": _times(exact, plain), "errors": errors,
                "lines_per_draw_mean": model["lines_per_draw_mean"], "load_average": load_average()}}
    if args.quick:
        write("uncertainty", figures, load_start=begin, out=args.out)
        return
    figures["measured_spindle"] = _hybrid(args.draws, args.repeat)
    nominal = _median(lambda: app.stability_lobes({"assembly": assembly, **CUT}), args.repeat)
    robust = _median(lambda: app.stability_lobes({"assembly": assembly, **CUT, "uncertainty": option}), args.repeat)
    robust_exact = _median(lambda: app.stability_lobes({"assembly": assembly, **CUT,
                                                        "uncertainty": {**option, "solver": "exact"}}), args.repeat)
    print(f"lobes, 500 speeds (ZOA): nominal {nominal[0] * 1e3:.1f} ms; robust over {args.draws} draws "
          f"{robust[0] * 1e3:.1f} ms (reduced) = {robust[0] / nominal[0]:.1f}x, {robust_exact[0] * 1e3:.1f} ms "
          f"(every draw exact) = {robust_exact[0] / nominal[0]:.1f}x")
    a = app.stability_lobes({"assembly": assembly, **CUT, "uncertainty": option})
    b = app.stability_lobes({"assembly": assembly, **CUT, "uncertainty": {**option, "solver": "exact"}})
    x = np.array(a["depth_limit_robust_m"], dtype=float)
    y = np.array(b["depth_limit_robust_m"], dtype=float)
    print(f"  robust depth limit, reduced vs exact: largest relative difference {np.nanmax(np.abs(x / y - 1.0)):.2%}")
    print(f"load average at the end {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    figures["robust_lobes"] = {"speeds": 500, "nominal_ms": nominal[0] * 1e3, "reduced_ms": robust[0] * 1e3,
                               "exact_ms": robust_exact[0] * 1e3,
                               "robust_limit_difference": float(np.nanmax(np.abs(x / y - 1.0)))}
    write("uncertainty", figures, load_start=begin, out=args.out)


if __name__ == "__main__":
    main()

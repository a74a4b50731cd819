"""The heaviest requests of each operation that still fit a given compute budget.

Each case grows one size of a request (lines, segments, band, measurements, draws, speeds)
until its estimate (:func:`rcsa.app.budget.estimate`) would exceed ``seconds``: the worst
request of that shape the budget lets through. Used by ``tests/service/test_budget.py``
(at a tenth of the sync limit) and ``benchmarks/bench_budget.py`` (at the limit).
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

from rcsa.app import budget
from rcsa.app.predictions import predict
from rcsa.reference import ra1

__all__ = ["worst_cases"]


def _tap(stickout: float, lines: int, shift: float = 0.0) -> dict[str, Any]:
    p = predict({**ra1({"start_hz": 100.0 + shift, "stop_hz": 3000.0 + shift, "step_hz": 2900.0 / (lines - 1)}),
                 "tool": {**ra1()["tool"], "stickout_m": stickout}})
    h = p.tool_point.h
    return {"tool": {"stickout_m": stickout}, "frequency_hz": p.frequency_hz.tolist(),
            "h": {"real": h.real.tolist(), "imag": h.imag.tolist()}}


def _largest(operation: str, make: Callable[[int], dict[str, Any]], seconds: float, memory: float,
             lo: int, hi: int) -> tuple[int, dict[str, Any]]:
    """The largest k in [lo, hi] whose request fits; (k, request)."""
    def fits(k: int) -> bool:
        c = budget.estimate(operation, make(k))
        return c.seconds <= seconds and c.memory_bytes <= memory

    if not fits(lo):
        raise ValueError(f"{operation}: even k={lo} exceeds the budget")
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if fits(mid):
            lo = mid
        else:
            hi = mid - 1
    return lo, make(lo)


def worst_cases(seconds: float, memory: float, only: tuple[str, ...] | None = None) -> list[dict[str, Any]]:
    """``[{"label", "operation", "request", "warmup"}]``: the worst request of each shape
    (of the shapes whose label starts with one of ``only``, when given)."""
    cases: list[dict[str, Any]] = []

    def wanted(label: str) -> bool:
        return only is None or label.startswith(only)

    small = ra1({"start_hz": 5.0, "stop_hz": 500.0, "step_hz": 5.0})

    def lines(k: int) -> dict[str, Any]:
        return ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 4995.0 / (k - 1)})

    def segments(k: int) -> dict[str, Any]:
        doc = ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 2.5})
        seg = doc["holder"]["segments"][0]
        length = sum(s["length_m"] for s in doc["holder"]["segments"])
        doc["holder"]["segments"] = [dict(seg, length_m=length / k)] * k
        return doc

    def band(k: int) -> dict[str, Any]:
        return ra1({"values_hz": [5.0, 1000.0 * k]})

    for label, make, lo, hi in (("prediction: lines", lines, 2, 200_000), ("prediction: segments", segments, 1, 1000),
                                ("prediction: band top (kHz)", band, 1, 10_000)):
        if not wanted(label):
            continue
        k, request = _largest("prediction", make, seconds, memory, lo, hi)
        cases.append({"label": f"{label} = {k}", "operation": "prediction", "request": request, "warmup": small})

    def effects_band(k: int) -> dict[str, Any]:
        return {"assembly": ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}), "band_hz": [5.0, 1000.0 * k]}

    if wanted("effects"):
        k, request = _largest("effects", effects_band, seconds, memory, 1, 10_000)
        cases.append({"label": f"effects: band top (kHz) = {k}", "operation": "effects", "request": request,
                      "warmup": {"assembly": small, "parameters": ["holder_tool.stiffness_n_m"]}})
    if not wanted("diagnosis") and not wanted("identification") and not wanted("lobes"):
        return cases

    base = {k: v for k, v in ra1().items() if k != "frequency"}
    n_taps = 20 if only is None or wanted("identification") else 3
    taps = [_tap(0.05 + 0.002 * i, 1200, shift=0.37 * i) for i in range(n_taps)]  # distinct grids: the worst
    warm_diag = {"assembly": base, "measurements": [_tap(0.05, 300)], "options": {"monte_carlo_draws": 50}}

    def diagnosis(k: int) -> dict[str, Any]:
        n, draws = (k, 200) if k <= len(taps) else (len(taps), 200 + 50 * (k - len(taps)))
        return {"assembly": base, "measurements": copy.deepcopy(taps[:n]),
                "options": {"monte_carlo_draws": draws, "seed": 1}}

    if wanted("diagnosis"):
        k, request = _largest("diagnosis", diagnosis, seconds, memory, 1, 116)
        cases.append({"label": f"diagnosis: measurements/draws step = {k}", "operation": "diagnosis",
                      "request": request, "warmup": warm_diag})

    def identification(k: int) -> dict[str, Any]:
        return {"assembly": ra1({"start_hz": 100.0, "stop_hz": 3000.0, "step_hz": 10.0}),
                "measurements": copy.deepcopy(taps[:k])}

    if wanted("identification"):
        k, request = _largest("identification", identification, seconds, memory, 1, 20)
        cases.append({"label": f"identification: measurements = {k}", "operation": "identification",
                      "request": request, "warmup": {"assembly": ra1({"start_hz": 100.0, "stop_hz": 3000.0,
                                                                         "step_hz": 10.0}),
                                                     "measurements": [_tap(0.074, 300)]}})

    def lobes(k: int) -> dict[str, Any]:
        return {"assembly": ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 1.0}), "teeth": 4,
                "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": 0.5, "milling": "down",
                "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": k}}

    if wanted("lobes"):
        k, request = _largest("lobes", lobes, seconds, memory, 2, 100_000)
        cases.append({"label": f"lobes: speeds = {k}", "operation": "lobes", "request": request,
                      "warmup": {**lobes(10), "assembly": ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0})}})

    def sdm(k: int) -> dict[str, Any]:
        return {**lobes(k), "assembly": ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}),
                "method": "semi_discretization", "steps_per_period": 40, "modes_per_direction": 3}

    if wanted("lobes sdm"):
        k, request = _largest("lobes", sdm, seconds, memory, 2, 5000)
        cases.append({"label": f"lobes sdm: speeds = {k}", "operation": "lobes", "request": request,
                      "warmup": sdm(3)})
    return cases

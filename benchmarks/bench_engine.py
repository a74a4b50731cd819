"""Engine benchmarks (issue 14): RA-1 at 10 000 lines, 1 000 tools on one spindle + holder, start-up.

Run: ``.venv/bin/python benchmarks/bench_engine.py``. Prints, in one run, median wall times
over repeats with the machine's load, and the ratios against baselines run in the same
process:

* ``rcsa.predict`` of RA-1 at 10 000 lines (FRF + exact natural frequencies + peaks + static
  stiffness, from the contract document; cold: no spindle side kept from an earlier call)
  against two vectorised numpy FRFs (``numpy_baseline.py``, the FRF alone): the dense one
  (global dynamic stiffness and ``np.linalg.solve``) and the stronger 2×2 block sweep over the
  chain; where the floor is (the exact beam terms' transcendental functions); and the same
  prediction warm (the next tool on a spindle + holder kept from the call before);
* 1 000 tools × 1 999 lines on one spindle + holder with every tool's exact modes;
* where the time goes: each part of a prediction timed on its own, and cProfile of the batch;
* ``import rcsa`` and ``rcsa --help`` in fresh interpreters.

``--slow-baselines`` adds the older yardsticks (the solver called per frequency line; each
tool solved as a full assembly), which take about a minute. The figures are also written to
``benchmarks/results/engine.json`` (``--out`` elsewhere; :mod:`record`).
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

import rcsa
from numpy_baseline import beam_dynamic_stiffness, block_sweep_receptance
from numpy_baseline import tip_receptance as numpy_tip_receptance
from rcsa.app import predictions
from rcsa.app.results import json_bytes
from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.model.peaks import find_frf_peaks
from rcsa.model.prediction import count_lines_hz, tool_point_receptance
from rcsa.physics.chain import Beam
from rcsa.physics.elimination import static_tip_receptance, tip_receptance
from rcsa.physics.natural_frequencies import natural_frequencies_batch
from rcsa.physics.subassembly_cache import SubassemblyCache
from rcsa.reference import ra1
from record import load_average, write


def median_time_s(fn: Callable[[], object], repeats: int, warm: bool = True) -> float:
    if warm:
        fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"load average {one:.2f}, {five:.2f}, {fifteen:.2f} on {os.cpu_count()} cores"


def tools(n: int, rng: np.random.Generator) -> list[dict]:
    base = ra1()["tool"]
    out = []
    for i in range(n):
        stickout = float(rng.uniform(0.040, 0.090))
        out.append({**base, "stickout_m": stickout, "flute_length_m": float(rng.uniform(0.015, 0.035)),
                    "overall_length_m": stickout + 0.101, "diameter_m": float(rng.choice([0.010, 0.0127, 0.012])),
                    "shank_diameter_m": 0.0127, "fluted_diameter_ratio": float(rng.uniform(0.7, 0.85))})
        out[-1]["id"] = f"T{i:04d}"
    return out


def fresh_interpreter_s(argv: list[str], repeats: int) -> float:
    """Median wall time of a command in a fresh process."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        subprocess.run(argv, check=True, capture_output=True)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def ra1_section(repeats: int, slow: bool) -> dict[str, object]:
    doc = ra1({"start_hz": 1.0, "stop_hz": 10000.0, "step_hz": 1.0})
    spec = parse_assembly(doc)
    model = build_model(spec)
    chain = model.chain()
    f = spec.frequency_hz
    omega = 2 * np.pi * f
    h = rcsa.predict(doc).tool_point.h
    err = np.max(np.abs(numpy_tip_receptance(chain, omega)[:, 0, 0] - h)) / np.max(np.abs(h))
    err_block = np.max(np.abs(block_sweep_receptance(chain, omega)[:, 0, 0] - h)) / np.max(np.abs(h))
    t_pred = median_time_s(lambda: rcsa.predict(doc), repeats)
    t_numpy = median_time_s(lambda: numpy_tip_receptance(chain, omega), max(3, repeats // 3))
    t_block = median_time_s(lambda: block_sweep_receptance(chain, omega), repeats)
    print(f"RA-1 tool point, 10 000 lines ({load()})")
    print(f"  rcsa.predict, cold (FRF + exact modes + peaks + static) {t_pred * 1e3:8.1f} ms")
    print(f"  dense numpy FRF alone (numpy_baseline.tip_receptance)   {t_numpy * 1e3:8.1f} ms   "
          f"ratio {t_numpy / t_pred:5.1f}x   (|h| agree to {err:.0e})")
    print(f"  numpy 2x2 block sweep FRF alone (block_sweep_receptance) {t_block * 1e3:7.1f} ms   "
          f"ratio {t_block / t_pred:5.1f}x   (|h| agree to {err_block:.0e})")
    beams = [item for item in chain if isinstance(item, Beam)]
    t_bterms = median_time_s(lambda: [beam_dynamic_stiffness(omega, b.section, b.length_m) for b in beams], repeats)
    x = np.linspace(0.0, 3.0, 2 * omega.size).reshape(2, -1)
    sections = {b.section for b in beams}  # equal sections share their wavenumbers
    z = x + 0.5j

    def transcendentals() -> None:  # what any exact solver evaluates: per beam sin, cos, sinh, cosh of both waves
        for _ in beams:
            np.sin(x), np.cos(x), np.sinh(x), np.cosh(x)
        for _ in sections:  # per section the two wavenumbers' square roots (complex)
            np.sqrt(z)

    t_floor = median_time_s(transcendentals, repeats)
    print(f"  where the floor is (RA-1: {len(chain)} items, {len(beams)} beams of {len(sections)} sections):")
    print(f"    block sweep: its {len(beams)} beam stiffnesses alone                      {t_bterms * 1e3:7.1f} ms")
    print(f"    transcendentals alone (sin, cos, sinh, cosh per beam, sqrt per section) {t_floor * 1e3:7.1f} ms")
    predictions.SIDES.size = predictions.SIDES_KEPT
    t_warm = median_time_s(lambda: rcsa.predict(doc), repeats)
    predictions.SIDES.size = 0
    print(f"  rcsa.predict, warm (spindle + holder kept from the call before)  {t_warm * 1e3:7.1f} ms   "
          f"block sweep ratio {t_block / t_warm:5.1f}x")
    out: dict[str, object] = {
        "lines": int(f.size), "load_average": load_average(), "predict_cold_ms": t_pred * 1e3,
        "dense_numpy_ms": t_numpy * 1e3, "block_sweep_ms": t_block * 1e3, "dense_agreement": float(err),
        "block_sweep_agreement": float(err_block), "beams": len(beams), "items": len(chain),
        "block_sweep_beam_terms_ms": t_bterms * 1e3, "transcendentals_ms": t_floor * 1e3,
        "predict_warm_ms": t_warm * 1e3}

    # where the time goes: each part of rcsa.predict timed on its own
    prefix, rest = model.to_holder_tip(), model.tool_side()
    grid = count_lines_hz(f)
    g = tool_point_receptance(model, SubassemblyCache(omega))
    result = rcsa.predict(doc)
    parts = {
        "parse the document + build the chain": lambda: build_model(parse_assembly(doc)),
        "FRF: spindle + holder condensed, tool marched, 2x2 inverse":
            lambda: tool_point_receptance(model, SubassemblyCache(omega)),
        "  of which spindle + holder (cached across tools)": lambda: SubassemblyCache(omega).stiffness(prefix),
        "natural frequencies: count on the grid + lockstep refinement":
            lambda: natural_frequencies_batch(prefix, [rest], float(f[0]), float(f[-1]), grid_hz=grid),
        "  of which the count on the grid (undamped, real)":
            lambda: natural_frequencies_batch(prefix, [rest], float(f[0]), float(f[-1]), grid_hz=grid, rtol=0.5),
        "peaks of h": lambda: find_frf_peaks(f, g[:, 0, 0]),
        "static stiffness": lambda: static_tip_receptance(rest, SubassemblyCache(omega).static(prefix)),
        "contract document alone (to_dict, lists)": lambda: result.to_dict(),
        "its JSON bytes from the arrays (rcsa.app.results.json_bytes)": lambda: json_bytes(result),
    }
    print("  where the time goes (each part alone, median):")
    out["parts_ms"] = {}
    for name, fn in parts.items():
        out["parts_ms"][name.strip()] = part = median_time_s(fn, repeats) * 1e3  # type: ignore[index]
        print(f"    {name:<64s} {part:7.1f} ms")
    print("    (rcsa.predict returns the Prediction; the document and its bytes are made when a caller serialises it)")
    if slow:
        sub = omega[::20]  # the loop is timed on 500 lines and scaled to 10 000
        t_vec = median_time_s(lambda: tip_receptance(chain, omega), repeats)
        t_loop = median_time_s(lambda: [tip_receptance(chain, sub[i:i + 1]) for i in range(sub.size)], 3) * 20
        print(f"  same solver per frequency line (loop)               {t_loop * 1e3:8.1f} ms   "
              f"ratio {t_loop / t_vec:5.0f}x the vectorised FRF")
        out.update(per_line_loop_ms=t_loop * 1e3, vectorised_frf_ms=t_vec * 1e3)
    return out


def batch_section(n_tools: int, slow: bool) -> dict[str, object]:
    doc = ra1()
    rng = np.random.default_rng(2026)
    grid = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 2.5}  # 1 999 lines
    combos = [{"id": t.pop("id"), "holder": doc["holder"], "tool": t, "joints": doc["joints"]}
              for t in tools(n_tools, rng)]
    request = {"frequency": grid, "spindle": doc["spindle"], "combinations": combos}
    # results kept as numpy arrays (what the service serialises with orjson)
    rcsa.predict_batch({**request, "combinations": combos[:10]}, arrays="numpy")
    t_frf = median_time_s(lambda: rcsa.predict_batch({**request, "natural_frequencies": False}, arrays="numpy"), 3,
                          warm=False)
    t_full = median_time_s(lambda: rcsa.predict_batch(request, arrays="numpy"), 3, warm=False)
    n_modes = sum(len(r["natural_frequencies_hz"]) for r in rcsa.predict_batch(request, arrays="numpy")["results"])
    print(f"{n_tools} tools on one spindle + holder, 1 999 lines ({load()})")
    print(f"  batch, FRFs + peaks + static stiffness          {t_frf:7.2f} s")
    print(f"  batch, + every tool's exact natural frequencies {t_full:7.2f} s   ({n_modes} modes)")
    out: dict[str, object] = {"tools": n_tools, "lines": 1999, "load_average": load_average(),
                              "frf_peaks_static_s": t_frf, "with_modes_s": t_full, "modes": n_modes}
    profile = cProfile.Profile()
    profile.enable()
    rcsa.predict_batch(request, arrays="numpy")
    profile.disable()
    stats = pstats.Stats(profile)
    total = max(v[3] for v in stats.stats.values())  # type: ignore[attr-defined]
    wanted = {"march_tools": "stacked FRF elimination (tools x lines)", "inv2": "2x2 inverses (receptance)",
              "static_condense_rows": "stacked static stiffness", "natural_frequencies_batch": "exact modes",
              "evaluate": "  of which count + det passes of the refinement", "find_frf_peaks": "peaks",
              "build_model": "chains built from the documents", "parse_combination": "documents parsed",
              "to_dict": "results as contract documents"}
    print("  where the time goes (cProfile, cumulative; profiling adds its overhead to Python-heavy parts):")
    seen: dict[str, float] = {}
    for (file, _, name), (_, _, _, cum, _) in stats.stats.items():  # type: ignore[attr-defined]
        if name in wanted and "rcsa" in file:
            seen[name] = seen.get(name, 0.0) + cum
    out["profile_share"] = {}
    for name, label in wanted.items():
        if name in seen:
            out["profile_share"][label.strip()] = seen[name] / total  # type: ignore[index]
            print(f"    {label:<52s} {seen[name]:6.2f} s  {100 * seen[name] / total:4.0f} %")
    if slow:
        n_base = max(20, n_tools // 20)
        t_base = median_time_s(lambda: [rcsa.predict({**ra1(grid), "tool": c["tool"]}) for c in combos[:n_base]], 1,
                               warm=False) * n_tools / n_base
        print(f"  each tool as a full assembly (baseline)        {t_base:7.2f} s   ratio {t_base / t_full:5.1f}x")
        out["full_assemblies_s"] = t_base
    return out


def startup_section(repeats: int) -> dict[str, object]:
    exe = sys.executable
    cli = str(Path(exe).with_name("rcsa"))
    t_python = fresh_interpreter_s([exe, "-c", "pass"], repeats)
    t_import = fresh_interpreter_s([exe, "-c", "import rcsa"], repeats)
    t_help = fresh_interpreter_s([cli, "--help"], repeats)
    print(f"start-up, fresh processes, median of {repeats} ({load()})")
    print(f"  python -c pass         {t_python * 1e3:6.0f} ms")
    print(f"  python -c 'import rcsa' {t_import * 1e3:6.0f} ms")
    print(f"  rcsa --help            {t_help * 1e3:6.0f} ms")
    return {"repeats": repeats, "load_average": load_average(), "python_pass_ms": t_python * 1e3,
            "import_rcsa_ms": t_import * 1e3, "rcsa_help_ms": t_help * 1e3}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tools", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--slow-baselines", action="store_true", help="also the per-line loop and full assemblies")
    parser.add_argument("--out", type=Path, default=None, help="the JSON (default benchmarks/results/engine.json)")
    args = parser.parse_args()
    start = load_average()
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, {os.uname().machine}")
    predictions.SIDES.size = 0  # cold predictions: no spindle side kept across calls (the warm row says so)
    figures = {"ra1": ra1_section(args.repeats, args.slow_baselines),
               "batch": batch_section(args.tools, args.slow_baselines), "startup": startup_section(7),
               "repeats": args.repeats}
    write("engine", figures, load_start=start, out=args.out)


if __name__ == "__main__":
    main()

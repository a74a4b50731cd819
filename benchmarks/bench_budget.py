"""The compute budget at full scale: the worst synchronous request of each shape, measured.

Run: ``.venv/bin/python benchmarks/bench_budget.py``. For every shape of request
(``tests/service/budget_cases.py``: prediction lines, segments and band top; effect-analysis
band; diagnosis measurements and draws on distinct grids; identification measurements;
lobes speeds) it builds the largest request whose estimate fits the sync limits
(:data:`rcsa.app.budget.SYNC`: 20 s, 1 GiB), runs them all in one fresh process, and reports
the estimate against the CPU time and the peak RSS measured. The stated bound
(:data:`rcsa.app.budget.STATED_SYNC_BOUND`: 60 s CPU, 1.5 GiB) must hold for every one.
Results go to ``benchmarks/results/budget.json``. ``--scale 0.1`` runs a tenth of the limit.

``--fit-sdm`` fits the semi-discretization's cost model instead (:data:`rcsa.app.budget.SDM_COST`):
it runs SDM lobes of RA-1 with the default steps over a grid of speeds, cuts (teeth, immersion,
lowest speed) and ``modes_per_direction``, each in a fresh process (CPU seconds and peak RSS), fits the
constants by non-negative least squares (on relative errors), prints the estimate against
the measurement for every point and the ``SDM_COST = ...`` line to paste into
``src/rcsa/app/budget.py``, and writes ``benchmarks/results/budget_sdm.json``.
``--check-sdm`` runs the same grid and reports the current constants' ratios only.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.service.budget_cases import worst_cases  # noqa: E402

from rcsa.app import budget  # noqa: E402

#: (speeds, teeth, radial immersion, modes_per_direction, low speed) of the SDM fit: the default
#: (automatic) steps, RA-1's tool point.
SDM_GRID = [
    (20, 2, 0.05, 2, 2000), (100, 2, 0.05, 2, 2000), (300, 2, 0.05, 4, 2000), (60, 1, 0.05, 8, 1000),
    (40, 1, 0.3, 4, 3000), (100, 2, 0.2, 3, 4000), (30, 4, 0.5, 2, 5000), (60, 4, 0.5, 4, 3000),
    (200, 3, 0.1, 4, 6000), (20, 1, 0.05, 1, 3000), (500, 2, 0.05, 8, 2000), (80, 2, 0.5, 8, 8000),
]


def _sdm_request(speeds: int, teeth: int, immersion: float, modes: int, low_rpm: float) -> dict:
    from rcsa.reference import ra1

    return {"assembly": ra1({"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 5.0}), "teeth": teeth,
            "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": immersion,
            "milling": "down", "method": "semi_discretization", "modes_per_direction": modes,
            "spindle_speed_rpm": {"start": low_rpm, "stop": 30000, "count": speeds}}


def _label(point: tuple) -> str:
    speeds, teeth, immersion, modes, low = point
    return f"sdm {speeds} speeds {low:g}-30000 rpm N={teeth} ae/D={immersion} m<={modes}"


def _measure_sdm() -> list[dict]:
    """Each grid point in its own fresh process (its peak RSS is its own); warm-up first."""
    rows = []
    warm = _sdm_request(3, 2, 0.5, 1, 20000)
    base = None
    for point in SDM_GRID:
        job = [{"label": _label(point), "operation": "lobes", "request": _sdm_request(*point), "warmup": warm}]
        out = subprocess.run([sys.executable, "-m", "tests.service._budget_probe"], input=json.dumps(job),
                             capture_output=True, text=True, cwd=REPO, check=True)
        row = json.loads(out.stdout.splitlines()[-1])
        if base is None:  # the process with the warm-up alone: what is not the request's
            empty = subprocess.run([sys.executable, "-m", "tests.service._budget_probe"],
                                   input=json.dumps([{**job[0], "request": warm}]), capture_output=True, text=True,
                                   cwd=REPO, check=True)
            base = json.loads(empty.stdout.splitlines()[-1])["peak_rss_bytes"]
        row.update(point=list(point), base_rss_bytes=base)
        rows.append(row)
        print(f"  {row['label']:58s} CPU {row['cpu_seconds']:7.2f} s  peak RSS {row['peak_rss_bytes'] / 2**20:6.0f} MiB",
              flush=True)
    return rows


def _terms(row: dict) -> tuple[dict, budget.SdmTerms, float]:
    req = _sdm_request(*row["point"])
    zoa = budget.estimate("lobes", {**req, "method": "zoa", "modes_per_direction": None}).seconds  # the prediction
    return req, budget.sdm_terms(req), zoa


def _fit_sdm(rows: list[dict]) -> budget.SdmCostModel:
    """Non-negative least squares on relative errors, scaled so that no point is under-estimated."""
    import numpy as np
    from scipy.optimize import nnls

    evals = budget.SDM_COST.evaluations
    feats, mem_feats, cpu, mem = [], [], [], []
    for r in rows:
        _, t, zoa = _terms(r)
        n = t.states
        feats.append([evals * t.step_sum * n * n, evals * t.step_sum * n**3, t.step_max])
        cpu.append(max(r["cpu_seconds"] - zoa, 1e-3))
        mem_feats.append([t.speeds * t.step_max * n * (n + 8.0), t.speeds])
        mem.append(r["peak_rss_bytes"] - r["base_rss_bytes"])
    a, c = np.array(feats), np.array(cpu)
    x, _ = nnls(a / c[:, None], np.ones_like(c))  # relative errors
    x = x / np.min(a @ x / c)  # no calibration point above its estimate
    am, m = np.array(mem_feats), np.array(mem)
    big = m >= 16 * 2**20  # smaller peaks are within the RSS's noise
    if big.sum() >= 2:
        y, _ = nnls(am[big] / m[big, None], np.ones(int(big.sum())))
        y = y / np.min(am[big] @ y / m[big])
    else:
        y = np.array([budget.SDM_COST.mem_pair_step_bytes, budget.SDM_COST.mem_speed_bytes])
    return budget.SdmCostModel(evaluations=evals, per_square_s=float(x[0]), per_cube_s=float(x[1]),
                               rounds=1.0, per_round_step_s=float(x[2]), mem_pair_step_bytes=float(y[0]),
                               mem_speed_bytes=float(y[1]), chunk_bytes=budget.SDM_COST.chunk_bytes)


def sdm(fit: bool, out_path: Path, reuse: bool = False) -> None:
    """``--fit-sdm`` / ``--check-sdm`` (``--reuse``: the measurements of the last run)."""
    if reuse:
        saved = json.loads(out_path.read_text())
        load, rows = saved["load_average"], saved["rows"]
        print(f"SDM cost model from the measurements in {out_path.name} (load average {load[0]:.2f})")
    else:
        load = os.getloadavg()
        print(f"SDM cost model, load average {load[0]:.2f}, {load[1]:.2f}, {load[2]:.2f} on {os.cpu_count()} cores")
        rows = _measure_sdm()
    model = _fit_sdm(rows) if fit else budget.SDM_COST
    if fit:
        fields = ", ".join(f"{k}={v:.2g}" for k, v in model.__dict__.items() if k != "chunk_bytes")
        print(f"SDM_COST = SdmCostModel({fields})")
    worst_t, worst_m = 0.0, 0.0
    for r in rows:
        req, t, _ = _terms(r)
        est = budget.estimate("lobes", req).seconds - budget.SDM_COST.seconds(t) + model.seconds(t)
        est_m = model.memory_bytes(t) + r["base_rss_bytes"]
        rt, rm = est / r["cpu_seconds"], est_m / r["peak_rss_bytes"]
        worst_t, worst_m = max(worst_t, rt, 1 / rt), max(worst_m, rm, 1 / rm)
        r.update(estimated_seconds=est, estimated_peak_bytes=est_m)
        print(f"  {r['label']:58s} estimate/measured: CPU {rt:5.2f}  peak RSS {rm:5.2f}")
    print(f"worst factor between estimate and measurement: CPU {worst_t:.2f}, peak RSS {worst_m:.2f}")
    out_path.parent.mkdir(parents=True, exist_ok=True)
    out_path.write_text(json.dumps({"load_average": list(load), "load_average_end": list(os.getloadavg()),
                                    "model": model.__dict__, "rows": rows,
                                    "worst_factor": {"cpu": worst_t, "rss": worst_m}}, indent=1) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scale", type=float, default=1.0, help="Fraction of the sync limits.")
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results" / "budget.json")
    parser.add_argument("--fit-sdm", action="store_true", help="Fit SDM_COST (see above).")
    parser.add_argument("--check-sdm", action="store_true", help="Report SDM_COST against measurements.")
    parser.add_argument("--reuse", action="store_true", help="With --fit-sdm/--check-sdm: refit the measurements "
                                                             "of the last run instead of measuring again.")
    args = parser.parse_args()
    if args.fit_sdm or args.check_sdm:
        sdm(args.fit_sdm, REPO / "benchmarks" / "results" / "budget_sdm.json", reuse=args.reuse)
        return
    cases = worst_cases(args.scale * budget.SYNC.seconds, args.scale * budget.SYNC.memory_bytes)
    out = subprocess.run([sys.executable, "-m", "tests.service._budget_probe"], input=json.dumps(cases),
                         capture_output=True, text=True, cwd=REPO, check=True)
    rows = [json.loads(line) for line in out.stdout.splitlines()]
    bound = budget.STATED_SYNC_BOUND
    print(f"sync limits x {args.scale:g}: {args.scale * budget.SYNC.seconds:g} s, "
          f"{args.scale * budget.SYNC.memory_bytes / 2**20:.0f} MiB; stated bound {bound.seconds:g} s CPU, "
          f"{bound.memory_bytes / 2**30:g} GiB RSS")
    for r in rows:
        print(f"  {r['label']:45s} estimate {r['estimated_seconds']:6.2f} s {r['estimated_memory_bytes'] / 2**20:6.0f} MiB"
              f" | measured CPU {r['cpu_seconds']:6.2f} s (wall {r['wall_seconds']:6.2f} s), "
              f"peak RSS {r['peak_rss_bytes'] / 2**20:6.0f} MiB")
    ok = all(r["cpu_seconds"] <= bound.seconds * args.scale and r["peak_rss_bytes"] <= bound.memory_bytes for r in rows)
    print("within the stated bound" if ok else "ABOVE THE STATED BOUND")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                                                "platform": platform.platform()},
                                    "scale": args.scale, "sync_limit": {"seconds": budget.SYNC.seconds,
                                                                        "memory_bytes": budget.SYNC.memory_bytes},
                                    "stated_bound": {"seconds": bound.seconds, "memory_bytes": bound.memory_bytes},
                                    "cases": rows, "within_bound": ok}, indent=1) + "\n")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()

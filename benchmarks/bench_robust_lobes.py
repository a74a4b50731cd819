"""Robust stability lobes on one process and on two worker processes (issue 29, ``docs/lobes.md``).

The README's robust example (``examples/lobes-robust.json``: RA-1, 4 teeth at a/D = 0.5, 40
speeds, 50 drawn assemblies, 95 % confidence) through the application layer, as ``rcsa lobes``
runs it: the nominal resolved semi-discretization, then the robust limits from the reduced model
of the draws, whose damping levels' diagrams (a stretched grid twice as dense as the request's)
are most of the work. Timed warm (a call first, so the prediction, the draws and the spindle side
are kept, as a user's second call has them):

* in this process (``LocalBackend``: one call over every level and speed), the baseline;
* with the speeds shared by two worker processes (``ProcessBackend(2)``, ``rcsa lobes``' default
  on this 2-core VM; ``rcsa.app.analyses.spread_sdm_diagrams``): the workers started in the call
  (as one command pays), and kept from the call before (``bench_lobes.on_two_workers``);
* the robust limits of the two against each other (the reduced model's diagrams are bracketed
  to 0.5 %, so where each speed's search starts may move them within that).

BLAS runs single-threaded (``OPENBLAS_NUM_THREADS=1`` unless set), as in ``bench_lobes.py``.
Results: ``benchmarks/results/robust_lobes.json``.

Run: ``.venv/bin/python benchmarks/bench_robust_lobes.py [--repeat 3]``
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

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import record  # noqa: E402
from benchmarks.bench_lobes import on_two_workers  # noqa: E402

from rcsa.app.analyses import stability_lobes_answer  # noqa: E402
from rcsa.infra.compute_backends import LocalBackend  # noqa: E402

REQUEST = Path(__file__).resolve().parents[1] / "examples" / "lobes-robust.json"


def _limits(answer) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(answer.nominal.depth_limit_m, dtype=float), np.asarray(answer.robust.depth_limit_m, dtype=float)


def _worst(a: np.ndarray, b: np.ndarray) -> float:
    """Largest relative difference of ``a`` from ``b`` where both are finite (NaN where they are not: a mismatch)."""
    if not np.array_equal(np.isnan(a), np.isnan(b)):
        return float("nan")
    ok = np.isfinite(b)
    return float(np.max(np.abs(a[ok] / b[ok] - 1.0))) if ok.any() else 0.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    load = record.load_average()
    request = json.loads(REQUEST.read_text())
    print(f"robust lobes of {REQUEST.name}: {request['spindle_speed_rpm']['count']} speeds, "
          f"{request['uncertainty']['draws']} draws (load average {load[0]:.1f})")
    local = LocalBackend()
    stability_lobes_answer(request, backend=local)  # warm: prediction, draws and spindle side kept
    here, cpu_here = [], []
    for _ in range(args.repeat):
        c0, t0 = time.process_time(), time.perf_counter()
        one = stability_lobes_answer(request, backend=local)
        here.append(time.perf_counter() - t0)
        cpu_here.append(time.process_time() - c0)
    nominal_one, robust_one = _limits(one)
    fresh, kept, answers = on_two_workers(request, args.repeat)
    agree_nominal = max(_worst(_limits(two)[0], nominal_one) for two in answers)
    agree_robust = max(_worst(_limits(two)[1], robust_one) for two in answers)
    t_here, t_fresh, t_kept = (statistics.median(x) for x in (here, fresh, kept))
    print(f"  one process (baseline)                        {t_here:6.2f} s  (CPU {statistics.median(cpu_here):.2f} s)")
    print(f"  2 worker processes, started in the call       {t_fresh:6.2f} s  ({t_here / t_fresh:.2f}x faster)")
    print(f"  2 worker processes, kept from the call before {t_kept:6.2f} s  ({t_here / t_kept:.2f}x faster)")
    print(f"  robust limits within {agree_robust:.1e} of one process's, nominal within {agree_nominal:.1e}")
    figures = {"speeds": int(request["spindle_speed_rpm"]["count"]), "draws": int(request["uncertainty"]["draws"]),
               "one_process_s": t_here, "one_process_cpu_s": statistics.median(cpu_here),
               "two_workers_fresh_s": t_fresh, "two_workers_kept_s": t_kept,
               "speedup_fresh": t_here / t_fresh, "speedup_kept": t_here / t_kept,
               "robust_agreement": agree_robust, "nominal_agreement": agree_nominal}
    record.write("robust_lobes", figures, load_start=load)


if __name__ == "__main__":  # ProcessBackend spawns workers that import this module
    main()

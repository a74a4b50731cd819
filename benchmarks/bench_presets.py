"""Chatter-safe presets of tool libraries, judged by converged stability limits (issues 20 and 29).

The libraries (``--library``): ``small`` — 25 single-flute O-flute carbide tools Ø1–6 mm, flute
lengths 3–42 mm (``tests/data/tool-libraries/fusion-single-flute/single_flute_small_library.json``,
the range of issue 29's vendor library), ``standard`` — 25 single-flute tools 2–12 mm
(``single_flute_library.json``), ``multi`` — 25 two-, three- and four-flute tools Ø3–16 mm
(``fusion-multi-flute/multi_flute_library.json``), ``sample`` — the three-tool sample of
``fusion-synthetic``, each on
RA-1's spindle and joints, aluminium 7075, down milling, 24 000 rpm machine, the default rule (±3 %
window, safety factor 1.25, flute length cap). For each a_e/D the library is recommended twice —
``method zoa`` (for comparison) and ``method auto`` (the default) — and every tool is judged:

* **unstable preset**: the preset's depth exceeds the converged limit somewhere in its ±3 %
  window: the window solved densely (121 speeds) by the semi-discretization with twice the steps
  per cycle the recommendation uses (20), every speed checked at a second resolution and refined
  until the two agree within 1 % (the tool's modes fitted to its FRF as the recommendation does);
  with ``--oracle-sample N`` the weakest speed of N windows is also solved by the spectral-element
  collocation oracle (``tests/oracles/milling_collocation.py``, another family of method);
* **false refusal**: a tool refused with "cannot chatter", or refused while the dense
  semi-discretization finds a stable pocket under the same rule;
* **productivity**: ``n · stepdown`` over the best the dense semi-discretization allows under
  the same rule (window, safety factor, speed range, flute length), on the fine pocket grid
  (relative spacing τ/10) over the whole speed range;
* **time-domain**: a sample of stability-limited presets, the lowest speeds first, simulated by
  the independent oracle (``tests/oracles/milling_time_domain``, 30 time steps per cycle of 1.2 ×
  the highest mode): the preset must not chatter, 1.25 × its window's limit (at the window's
  weakest speed, same fine solution) must.

It also times the recommendation (prediction + pockets; 400 semi-discretization speeds per
tool) in this process — every timing first, at every immersion, before the judge starts, so that the
long judge cannot load the machine under a timing (``timing_load_after`` records the load they saw) — and the default method again as a user runs it — ``rcsa library recommend``
in a process of its own with ``--workers 2`` (``--workers``; the CLI's default is one worker process
per core, so this is the default on the 2-core development VM), its start and its workers' CPU time
counted, its presets compared with the in-process ones — and with ``--job-tools N`` runs a library of N tools (the 25, repeated with stickouts
0.5 mm longer each round) as a job on a local backend or ``--dask`` a LocalCluster, printing
its progress.

Run: ``.venv/bin/python benchmarks/bench_presets.py [--library small] [--immersions 0.05 0.5]
[--sample 4] [--oracle-sample 3] [--job-tools 1000 [--dask]]``; writes
``benchmarks/results/presets_<library>.json`` (``--immersions`` given no value: only the job, into
``benchmarks/results/presets_job.json``).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported

import argparse  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks import record  # noqa: E402
from tests.oracles import milling_collocation as collocation  # noqa: E402
from tests.oracles.milling_time_domain import Cut, Mode, resolving_steps, simulate  # noqa: E402

from rcsa.analysis.lobes.modal_model import ModalModel, fit_modal_model  # noqa: E402
from rcsa.analysis.lobes.pockets import PocketRule, best_pocket, pocket_speed_grid  # noqa: E402
from rcsa.analysis.lobes.semi_discretization import semi_discretization_lobes_many  # noqa: E402
from rcsa.app.jobs import Workbench  # noqa: E402
from rcsa.app.presets import recommend_predicted  # noqa: E402
from rcsa.libraries.formats import read_library  # noqa: E402
from rcsa.libraries.recommend_sources import predicted_frfs  # noqa: E402
from rcsa.reference import ra1  # noqa: E402

LIBRARIES = {"small": ROOT / "tests" / "data" / "tool-libraries" / "fusion-single-flute" / "single_flute_small_library.json",
             "standard": ROOT / "tests" / "data" / "tool-libraries" / "fusion-single-flute" / "single_flute_library.json",
             "multi": ROOT / "tests" / "data" / "tool-libraries" / "fusion-multi-flute" / "multi_flute_library.json",
             "sample": ROOT / "tests" / "data" / "tool-libraries" / "fusion-synthetic" / "synthetic_library.json"}
LIBRARY = LIBRARIES["small"]
#: Steps per cycle the judge resolves with: twice the recommendation's.
JUDGE_STEPS_PER_CYCLE = 20.0
GRID = {"start_hz": 5.0, "stop_hz": 6000.0, "step_hz": 2.0}
RA1 = ra1(GRID)
SETTINGS = {"spindle": RA1["spindle"], "frequency": GRID, "joints": RA1["joints"]}
OPTIONS = {"material": "aluminium-7075", "max_rpm": 24000, "milling": "down"}
KT, KR = 1319.41e6, 788.83 / 1319.41


def _recommend(data: bytes, immersion: float, method: str) -> tuple[dict, float, float]:
    t0, c0 = time.perf_counter(), time.process_time()
    result = recommend_predicted(Workbench(None), data, {**OPTIONS, "radial_immersion": immersion, "method": method},
                                 file_name="single_flute.json", **SETTINGS)
    return result.report, time.perf_counter() - t0, time.process_time() - c0


def _recommend_with_the_cli(data: bytes, immersion: float, method: str, workers: int, alone: dict) -> dict:
    """The same recommendation as a user runs it: ``rcsa library recommend`` in a process of its own with
    ``--workers`` (its start, imports and worker processes counted; RA-1 with this benchmark's grid
    given as the spindle document), its CPU time with its children's, and how far its presets are from
    the in-process ones (``alone``)."""
    with tempfile.TemporaryDirectory() as tmp:
        lib, spindle, report = Path(tmp) / "library.json", Path(tmp) / "ra1.json", Path(tmp) / "report.json"
        lib.write_bytes(data)
        spindle.write_text(json.dumps(RA1))
        command = [str(Path(sys.executable).with_name("rcsa")), "library", "recommend", str(lib), "--spindle",
                   str(spindle), "--material", OPTIONS["material"], "--max-rpm", str(OPTIONS["max_rpm"]),
                   "--milling", OPTIONS["milling"], "--radial-immersion", str(immersion), "--method", method,
                   "-o", str(Path(tmp) / "out.json"), "--report", str(report), "-q", "--workers", str(workers)]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        got = json.loads(report.read_text())
    pairs = list(zip(alone["tools"], got["tools"], strict=True))
    depth = [abs(b["depth_limit_m"] / a["depth_limit_m"] - 1) for a, b in pairs
             if a.get("depth_limit_m") and b.get("depth_limit_m")]
    return {"workers": workers, "wall_s": wall,
            "cpu_s": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime),
            "same_speeds": all(a.get("spindle_speed_rpm") == b.get("spindle_speed_rpm") for a, b in pairs),
            "max_depth_limit_difference": max(depth, default=0.0)}


def _limits(model, teeth, immersion, speeds, floor_m, finer=1):
    """The judge's limits: resolved semi-discretization (``finer`` times the default steps per cycle,
    checked and refined); an unresolved speed's finest answer is kept and counted."""
    r = semi_discretization_lobes_many([model], teeth=teeth, tangential_coefficient_n_m2=KT, radial_ratio=KR,
                                       radial_immersion=immersion, milling="down", spindle_speed_rpm=[speeds],
                                       steps_per_cycle=10.0 * finer, min_depth_search_max_m=[floor_m])[0]
    return r, np.where(np.isfinite(r.depth_limit_m), r.depth_limit_m,
                       np.inf if r.depth_search_max_m >= floor_m else r.depth_search_max_m)


def _judge(report: dict, frfs: dict, immersion: float, rule: PocketRule, library: dict) -> list[dict]:
    rows = []
    for tool in report["tools"]:
        frf = frfs.get(tool["id"])
        if tool.get("tool_type") != "flat end mill" or frf is None or isinstance(frf, str):
            continue
        model = fit_modal_model(frf.frequency_hz, frf.h)
        item = next(t for t in library["data"] if t.get("guid") == tool["id"])
        teeth = int(item["geometry"]["NOF"])
        flute = tool.get("flute_length_m")
        lo, hi = (tool["speed_range"]["min_rpm"], tool["speed_range"]["max_rpm"]) if "speed_range" in tool else \
            (1000.0, 24000.0)
        row = {"id": tool["id"], "status": tool["status"], "method": tool.get("lobe_method"),
               "reason": tool.get("reason")}
        # the best the dense SDM allows under the same rule
        fine = pocket_speed_grid(lo, hi, rule.speed_tolerance)
        if flute is None:
            flute = item["geometry"]["LCF"] * (0.0254 if item["unit"] == "inches" else 1e-3)
        need = rule.safety_factor * flute * 1.02
        _, fine_limit = _limits(model, teeth, immersion, fine, need)
        best = best_pocket(fine, fine_limit, min_rpm=lo, max_rpm=hi, rule=replace(rule, max_depth_m=flute))
        row["sdm_best_index_rpm_m"] = None if best is None else best.removal_index_rpm_m
        if tool["status"] == "written":
            n, step = float(tool["spindle_speed_rpm"]), float(tool["stepdown_m"])
            window = np.geomspace(n * (1 - rule.speed_tolerance), n * (1 + rule.speed_tolerance), 121)
            judged, dense = _limits(model, teeth, immersion, window, need, finer=2)
            weakest = int(np.argmin(dense))
            row.update(spindle_speed_rpm=n, stepdown_m=step, window_min_m=float(np.min(dense)), teeth=teeth,
                       judge_unresolved=int(np.count_nonzero(~judged.resolved)),
                       weakest_rpm=float(window[weakest]),
                       unstable=bool(np.min(dense) < step), productivity=None if best is None else
                       n * step / best.removal_index_rpm_m, limited_by=tool.get("limited_by"),
                       depth_limit_m=tool.get("depth_limit_m"))
        else:
            row["false_refusal"] = ("cannot chatter" in (tool.get("reason") or "")) or best is not None
        row["modes"] = [[float(f), float(z), float(1.0 / r), int(d)] for f, z, r, d in
                        zip(model.frequency_hz, model.damping_ratio, model.residue_1_kg, model.direction, strict=True)]
        rows.append(row)
    return rows


def _oracle(rows: list[dict], immersion: float, sample: int) -> list[dict]:
    """The weakest speed of ``sample`` written windows (the lowest speeds first) by the collocation oracle."""
    picked = sorted([r for r in rows if r["status"] == "written" and np.isfinite(r["window_min_m"])],
                    key=lambda r: r["spindle_speed_rpm"])[:sample]
    out = []
    for r in picked:
        modes = [collocation.Mode(f, z, m, d) for f, z, m, d in r["modes"]]
        truth = collocation.depth_limit(modes, r["teeth"], KT, KR, immersion, "down", r["weakest_rpm"],
                                        low_m=r["window_min_m"] / 3, high_m=r["window_min_m"] * 3, scan=12)
        out.append({"id": r["id"], "at_rpm": r["weakest_rpm"], "judge_m": r["window_min_m"],
                    "oracle_m": truth.depth_m, "oracle_finer_agrees": truth.finer_agrees,
                    "stepdown_m": r["stepdown_m"], "preset_over_oracle": r["stepdown_m"] / truth.depth_m})
    return out


def _time_domain(rows: list[dict], immersion: float, sample: int) -> list[dict]:
    picked = sorted([r for r in rows if r["status"] == "written" and r.get("limited_by") == "stability"],
                    key=lambda r: r["spindle_speed_rpm"])[:sample]
    out = []
    for r in picked:
        modes = [Mode(f, z, m, d) for f, z, m, d in r["modes"]]
        n, step = r["spindle_speed_rpm"], r["stepdown_m"]
        window = np.geomspace(n * 0.97, n * 1.03, 61)
        f, z, mass, d = (np.array([x[i] for x in r["modes"]]) for i in range(4))
        teeth = r["teeth"]
        _, dense = _limits(ModalModel.of(f, z, 1.0 / mass, d.astype(int)), teeth, immersion, window, 1.0, finer=2)
        weakest = float(window[int(np.argmin(dense))])
        up = 1.25 * float(np.min(dense))
        cuts = [Cut(n, step, teeth, KT, KR, immersion, "down", 5e-5),
                Cut(weakest, up, teeth, KT, KR, immersion, "down", 5e-5)]
        sim = simulate(modes, cuts, steps_per_period=resolving_steps(modes, cuts))
        out.append({"id": r["id"], "spindle_speed_rpm": n, "stepdown_m": step, "preset_stable": bool(sim.stable[0]),
                    "next_step_up_m": up, "at_rpm": weakest, "next_step_up_chatters": bool(sim.chatter[1]),
                    "ratios": [float(x) for x in sim.ratio]})
    return out


def _summary(rows: list[dict]) -> dict:
    written = [r for r in rows if r["status"] == "written"]
    refused = [r for r in rows if r["status"] != "written"]
    prod = [r["productivity"] for r in written if r.get("productivity") is not None]
    return {"tools": len(rows), "written": len(written), "refused": len(refused),
            "unstable_by_sdm": sum(r["unstable"] for r in written),
            "worst_depth_over_window_limit": max((r["stepdown_m"] / r["window_min_m"] for r in written), default=None),
            "judge_unresolved_speeds": sum(r.get("judge_unresolved", 0) for r in written),
            "false_refusals": sum(r["false_refusal"] for r in refused),
            "productivity_median": float(np.median(prod)) if prod else None,
            "productivity_min": float(np.min(prod)) if prod else None,
            "by_method": {m: sum(r["method"] == m for r in written) for m in ("zoa", "semi_discretization")}}


def _job(n_tools: int, dask: bool) -> dict:
    """A library of ``n_tools`` recommended as a job (local backend or a Dask LocalCluster)."""
    from rcsa.app.presets import recommend_job_handlers, recommend_job_request
    from rcsa.infra.compute_backends import LocalBackend, compute_backend
    from rcsa.libraries.sync import sync_library

    base = json.loads(LIBRARY.read_text())
    items = []
    for i in range(n_tools):
        t = json.loads(json.dumps(base["data"][i % len(base["data"])]))
        k = i // len(base["data"])
        t["guid"] = f"00000000-0000-4000-9000-{i:012x}"
        step = 0.5 / (25.4 if t["unit"] == "inches" else 1.0)
        t["geometry"]["LB"] = round(t["geometry"]["LB"] + k * step, 6)
        t["geometry"]["assemblyGaugeLength"] = round(t["geometry"]["assemblyGaugeLength"] + k * step, 6)
        t["geometry"]["OAL"] = round(t["geometry"]["OAL"] + k * step, 6)
        items.append(t)
    data = json.dumps({"data": items, "version": 1}).encode()

    cluster = None
    with tempfile.TemporaryDirectory() as tmp:
        backend = LocalBackend()
        if dask:
            import dask
            import distributed

            from rcsa.infra.compute_backends import DASK_WORKER_ENVIRON

            dask.config.set({"distributed.nanny.pre-spawn-environ": DASK_WORKER_ENVIRON})
            cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                               dashboard_address=None)
            backend = compute_backend(cluster.scheduler_address)
        bench = Workbench(None, Path(tmp) / "store", backend=backend)
        t0 = time.perf_counter()
        sync_library(bench.libraries, "big", data, **SETTINGS, natural_frequencies=False)
        t_sync = time.perf_counter() - t0
        handler = recommend_job_handlers(bench)["library-recommend"]
        request = recommend_job_request("big", data, {**OPTIONS, "radial_immersion": 0.05}, file_name="big.json")
        ticks = []
        t0 = time.perf_counter()

        def progress(done: int, total: int) -> None:
            ticks.append((round(time.perf_counter() - t0, 2), done, total))
            print(f"    job progress {done}/{total} at {ticks[-1][0]:.1f} s", flush=True)

        doc, summary = handler(request, progress)
        t_job = time.perf_counter() - t0
        if cluster is not None:
            backend.close()
            cluster.close()
    return {"tools": n_tools, "backend": "dask LocalCluster (2 workers)" if dask else "local", "sync_s": t_sync,
            "recommend_job_s": t_job, "summary": summary, "progress_ticks": len(ticks)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--library", choices=sorted(LIBRARIES), default="small")
    parser.add_argument("--methods", nargs="+", default=["zoa", "auto"], choices=["zoa", "semi_discretization", "auto"])
    parser.add_argument("--oracle-sample", type=int, default=0,
                        help="written windows per immersion whose weakest speed the collocation oracle solves")
    parser.add_argument("--immersions", type=float, nargs="*", default=[0.05, 0.5],
                        help="radial immersions a_e/D to judge (none: only the --job-tools run)")
    parser.add_argument("--sample", type=int, default=4, help="presets per immersion simulated in the time domain")
    parser.add_argument("--job-tools", type=int, default=0)
    parser.add_argument("--dask", action="store_true")
    parser.add_argument("--workers", type=int, default=2,
                        help="also time the default method through the CLI with --workers N (0: not)")
    args = parser.parse_args()
    path = LIBRARIES[args.library]
    data = path.read_bytes()
    library = json.loads(data)
    rule = PocketRule()
    frfs = predicted_frfs(read_library(data, file_name="library.json"), **SETTINGS).frfs
    load_start = record.load_average()
    results: dict = {"library": str(path.relative_to(ROOT)), "immersions": {}}
    # First every timing (in this process and through the CLI), while the machine is as idle as it was
    # at the start; then the judge, whose answers do not depend on the load and which takes most of the run.
    timed: dict = {}
    for ae in args.immersions:
        entry = results["immersions"][str(ae)] = {}
        for method in args.methods:
            report, wall, cpu = _recommend(data, ae, method)
            timed[(ae, method)] = report
            entry[method] = {"wall_s": wall, "cpu_s": cpu}
            print(f"a_e/D {ae}: method {method:5s} {wall:6.1f} s ({cpu:.1f} s CPU, load {os.getloadavg()[0]:.1f})",
                  flush=True)
            if method == "auto" and args.workers > 1:
                par = entry[method]["cli"] = _recommend_with_the_cli(data, ae, method, args.workers, report)
                print(f"    rcsa library recommend --workers {par['workers']}: {par['wall_s']:.1f} s ({par['cpu_s']:.1f} s "
                      f"CPU with its workers'), same speeds {par['same_speeds']}, depth limits within "
                      f"{par['max_depth_limit_difference']:.1e}", flush=True)
        entry["timing_load_after"] = record.load_average()
    for ae in args.immersions:
        entry = results["immersions"][str(ae)]
        for method in args.methods:
            rows = _judge(timed[(ae, method)], frfs, ae, rule, library)
            entry[method].update(summary=_summary(rows), tools=rows)
            s = entry[method]["summary"]
            print(f"a_e/D {ae}: method {method:5s} written {s['written']}, unstable by SDM {s['unstable_by_sdm']}, "
                  f"refused {s['refused']} ({s['false_refusals']} falsely), productivity median "
                  f"{s['productivity_median']} min {s['productivity_min']}, methods {s['by_method']}", flush=True)
        entry["machine_load_after"] = record.load_average()
        main_rows = entry[args.methods[-1]]["tools"]
        entry["oracle"] = _oracle(main_rows, ae, args.oracle_sample)
        for t in entry["oracle"]:
            print(f"    oracle {t['id'][-4:]} at {t['at_rpm']:.0f} rpm: judge {t['judge_m'] * 1e3:.4f} mm, collocation "
                  f"{t['oracle_m'] * 1e3:.4f} mm; preset / oracle {t['preset_over_oracle']:.3f}", flush=True)
        entry["time_domain"] = _time_domain(main_rows, ae, args.sample)
        for t in entry["time_domain"]:
            print(f"    time domain {t['id'][-4:]}: preset {t['stepdown_m'] * 1e3:.3f} mm at {t['spindle_speed_rpm']:.0f} "
                  f"rpm stable={t['preset_stable']}; {t['next_step_up_m'] * 1e3:.3f} mm at {t['at_rpm']:.0f} rpm "
                  f"chatters={t['next_step_up_chatters']}", flush=True)
        _write(results, args, load_start)  # after each immersion: a long run killed later keeps what it measured
    if args.job_tools:
        results["job"] = _job(args.job_tools, args.dask)
        print("job:", results["job"])
    print(f"wrote {_write(results, args, load_start)}")


def _write(results: dict, args: argparse.Namespace, load_start: list[float]) -> Path:
    """``results`` as the library's record (``benchmarks/results/presets_<library>.json``), or the job's."""
    name = f"presets_{args.library}" if args.immersions else "presets_job"
    return record.write(name, results, load_start=load_start)


if __name__ == "__main__":
    main()

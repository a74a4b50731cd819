#!/usr/bin/env python3
"""Render every published figure of the documents from ``benchmarks/results/*.json``.

A figure in a Markdown document stands between two markers, and only this script writes what
is between them::

    The fit's sd is cautious: rms z <!-- figure: modal_fit.json:figures.rms_z_pooled|.2f -->0.75<!-- /figure -->.

    <!-- figure: benchmarks-table -->
    | what | figure | ... |
    <!-- /figure -->

The name after ``figure:`` is either

* ``FILE.json:PATH|SPEC`` — one value of ``benchmarks/results/FILE.json``: ``PATH`` is dotted
  (object keys, list indices); ``SPEC`` is ``[*SCALE][:]FORMAT``, a Python format spec applied
  to the value times ``SCALE`` (``*1e3:.1f`` for s → ms; ``.0%``; ``_`` groups thousands with a
  space, ``,.0f`` is not used); or
* a named figure of :data:`FIGURES` below (tables, ratios, ranges, bounds computed from the
  JSON: nothing typed by hand).

A figure whose rendering spans lines (a table) is written on lines of its own between the
markers. The benchmarks write the JSON (``benchmarks/record.py``); a document and its JSON
that disagree fail ``tests/test_figures_rendered.py``.

Usage::

    python scripts/render_figures.py           # rewrite the documents in place
    python scripts/render_figures.py --check   # list the figures that differ; exit 1 if any
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Callable, Iterable
from functools import cache
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "benchmarks" / "results"
#: The documents whose figures are rendered: the README, the manual and the examples' README.
DOCUMENTS = ("README.md", "docs/**/*.md", "examples/README.md")
MARKER = re.compile(r"<!-- figure: (?P<name>[^>]+?) -->(?P<body>.*?)<!-- /figure -->", re.S)


class FigureError(ValueError):
    """A figure that cannot be rendered: unknown name, missing file or key, bad format."""


@cache
def result(name: str) -> Any:
    """The parsed ``benchmarks/results/NAME`` (``.json`` added when missing)."""
    path = RESULTS / (name if name.endswith(".json") else f"{name}.json")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FigureError(f"no results file {path.relative_to(REPO)}") from None


def value(name: str, path: str) -> Any:
    """The value at dotted ``path`` of the results file ``name``."""
    node = result(name)
    for key in path.split("."):
        try:
            node = node[int(key)] if isinstance(node, list) else node[key]
        except (KeyError, IndexError, ValueError, TypeError):
            raise FigureError(f"{name}: no {path!r} (at {key!r})") from None
    return node


def fmt(x: Any, spec: str = "") -> str:
    """``x`` formatted by ``[*SCALE][:]FORMAT`` (see the module docstring).

    >>> fmt(0.0123, "*1e3:.1f"), fmt(0.914, ".0%"), fmt(10000, "_"), fmt(3.0, ".3g")
    ('12.3', '91%', '10 000', '3')
    """
    scale = 1.0
    if spec.startswith("*"):
        head, _, spec = spec[1:].partition(":")
        scale = float(head)
    if isinstance(x, bool) or not isinstance(x, int | float):
        if spec:
            raise FigureError(f"{x!r} is not a number for format {spec!r}")
        return str(x)
    y = x * scale if scale != 1.0 else x
    try:
        text = format(y, spec)
    except ValueError as exc:
        raise FigureError(f"bad format {spec!r}: {exc}") from None
    return text.replace("_", " ")


def load_text(*loads: Iterable[float] | float | None) -> str:
    """``load 4.8`` or ``load 4.8–5.3``: the 1-minute load averages a figure was measured at."""
    ones = []
    for load in loads:
        if load is None:
            continue
        ones.append(float(load) if isinstance(load, int | float) else float(list(load)[0]))
    if not ones:
        return "load not recorded"
    lo, hi = min(ones), max(ones)
    return f"load {lo:.1f}" if f"{lo:.1f}" == f"{hi:.1f}" else f"load {lo:.1f}–{hi:.1f}"


def clopper_pearson_upper(k: int, n: int, confidence: float = 0.95) -> float:
    """One-sided upper confidence bound of a rate seen ``k`` times in ``n`` trials (exact, binomial).

    For ``k = 0`` it is ``1 − (1 − confidence)^(1/n)``; otherwise found by bisection on the
    binomial tail ``P(X ≤ k; n, p) = 1 − confidence``.

    >>> round(clopper_pearson_upper(0, 60), 4), round(clopper_pearson_upper(2, 75), 4)
    (0.0487, 0.0816)
    """
    if k >= n:
        return 1.0
    alpha = 1.0 - confidence

    def tail(p: float) -> float:  # P(X <= k)
        return sum(math.comb(n, i) * p**i * (1 - p) ** (n - i) for i in range(k + 1))

    lo, hi = 0.0, 1.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if tail(mid) > alpha else (lo, mid)
    return hi


def count(n: int) -> str:
    """An integer with its thousands grouped by a space: ``count(10000) == '10 000'``."""
    return f"{n:_}".replace("_", " ")


def goal(target: str, met: bool) -> str:
    """A target, marked **missed** when the figure does not meet it (computed, never typed)."""
    return target if met else f"{target} — **missed**"


def pct(x: float, digits: int = 1) -> str:
    """A fraction as a percentage with a space before the sign: ``pct(0.029) == '2.9 %'``."""
    return f"{x * 100:.{digits}f} %"


def table(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |" for row in rows]
    return "\n".join(lines)


# --------------------------------------------------------------------------- named figures

def _engine() -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    f = value("engine", "figures")
    return f["ra1"], f["batch"], f["startup"]


def _benchmark_rows() -> list[list[str]]:
    """One row per benchmark figure: what, figure (with its baseline), target, load, source."""
    ra1, batch, startup = _engine()
    parts = ra1["parts_ms"]
    rows = [
        ["`rcsa.predict` of RA-1 at 10 000 lines, cold: FRF + exact natural frequencies + peaks + static stiffness",
         f"{ra1['predict_cold_ms']:.1f} ms; warm (spindle + holder kept) {ra1['predict_warm_ms']:.1f} ms",
         goal("≤ 25 ms", ra1["predict_cold_ms"] <= 25), load_text(ra1["load_average"]), "engine.json"],
        ["… against a vectorised dense numpy FRF alone (`numpy_baseline.tip_receptance`)",
         f"{ra1['dense_numpy_ms'] / ra1['predict_cold_ms']:.1f}× faster (baseline {ra1['dense_numpy_ms']:.0f} ms)",
         goal("≥ 15×", ra1["dense_numpy_ms"] / ra1["predict_cold_ms"] >= 15),
         load_text(ra1["load_average"]), "engine.json"],
        ["… against the 2×2 block sweep (`numpy_baseline.block_sweep_receptance`, closed-form 2×2 inverses)",
         f"{ra1['block_sweep_ms'] / ra1['predict_cold_ms']:.1f}× cold, "
         f"{ra1['block_sweep_ms'] / ra1['predict_warm_ms']:.1f}× warm (baseline {ra1['block_sweep_ms']:.0f} ms)",
         goal("≥ 8× cold", ra1["block_sweep_ms"] / ra1["predict_cold_ms"] >= 8),
         load_text(ra1["load_average"]), "engine.json"],
        ["… where the floor is: the block sweep's beam stiffnesses / the transcendentals any exact solver "
         f"evaluates ({ra1['beams']} beams)",
         f"{ra1['block_sweep_beam_terms_ms']:.0f} ms / {ra1['transcendentals_ms']:.1f} ms", "",
         load_text(ra1["load_average"]), "engine.json"],
        ["… where the time goes: FRF (of it spindle + holder) / natural frequencies / static stiffness / "
         "parse + chain / the contract document / its JSON bytes",
         f"{parts['FRF: spindle + holder condensed, tool marched, 2x2 inverse']:.1f} "
         f"({parts['of which spindle + holder (cached across tools)']:.1f}) / "
         f"{parts['natural frequencies: count on the grid + lockstep refinement']:.1f} / "
         f"{parts['static stiffness']:.1f} / {parts['parse the document + build the chain']:.1f} / "
         f"{parts['contract document alone (to_dict, lists)']:.1f} / "
         f"{parts['its JSON bytes from the arrays (rcsa.app.results.json_bytes)']:.1f} ms", "",
         load_text(ra1["load_average"]), "engine.json"],
    ]
    if "per_line_loop_ms" in ra1:
        rows.append(["… against the same solver called per frequency line (a loop)",
                     f"{ra1['per_line_loop_ms'] / ra1['vectorised_frf_ms']:.0f}× faster (FRF)",
                     goal("≥ 20×", ra1["per_line_loop_ms"] / ra1["vectorised_frf_ms"] >= 20),
                     load_text(ra1["load_average"]), "engine.json"])
    rows += [
        [f"{count(batch['tools'])} tools on one spindle + holder, {count(batch['lines'])} lines: FRFs + peaks + static stiffness"
         , f"{batch['frf_peaks_static_s']:.2f} s", goal("≤ 2 s", batch["frf_peaks_static_s"] <= 2), load_text(batch["load_average"]),
         "engine.json"],
        [f"… with every tool's exact natural frequencies ({count(batch['modes'])} modes)",
         f"{batch['with_modes_s']:.2f} s", goal("≤ 1 s", batch["with_modes_s"] <= 1),
         load_text(batch["load_average"]), "engine.json"],
    ]
    if "full_assemblies_s" in batch:
        rows.append(["… against solving each tool as a full assembly",
                     f"{batch['full_assemblies_s'] / batch['with_modes_s']:.1f}× faster", "",
                     load_text(batch["load_average"]), "engine.json"])
    rows.append(["start-up, fresh processes: `python -c \"import rcsa\"` / `rcsa --help` (bare `python -c pass`)",
                 f"{startup['import_rcsa_ms']:.0f} ms / {startup['rcsa_help_ms']:.0f} ms "
                 f"({startup['python_pass_ms']:.0f} ms)",
                 goal("≤ 0.3 s / ≤ 0.5 s", startup["import_rcsa_ms"] <= 300 and startup["rcsa_help_ms"] <= 500), load_text(startup["load_average"]),
                 "engine.json"])
    rows += _service_rows() + _wire_rows() + _analysis_rows()
    return rows


def _service_rows() -> list[list[str]]:
    s = value("service", "figures.single_prediction_5000_lines")
    load = load_text(value("service", "load_average_start"), value("service", "load_average_end"))
    one, new1 = s["1_threads"], s["1_threads_new_tool_per_request"]
    new_best = max((row for name, row in s.items() if name.endswith("_threads_new_tool_per_request")),
                   key=lambda row: row["requests_per_s"])
    same_best = max((row for name, row in s.items() if name[0].isdigit() and name.endswith("_threads")),
                    key=lambda row: row["requests_per_s"])
    kept1 = s["1_threads_tool_per_request"]
    kept_best = max((row for name, row in s.items() if name.endswith("_threads_tool_per_request")),
                    key=lambda row: row["requests_per_s"])
    largest = result("service-largest")
    peak = max(largest["worker_peak_rss_mb"].values())
    return [
        ["REST, hybrid RA-1 prediction at 5 000 lines on a stored spindle, `rcsa serve --workers 2` "
         "(`bench_service.py`): a tool never asked before in each request, 1 client thread / the best of "
         f"{', '.join(str(n) for n in sorted({r['threads'] for r in s.values()}))} threads",
         f"p50 {new1['p50_ms']:.1f} ms, {new1['requests_per_s']:.0f} requests/s / {new_best['requests_per_s']:.0f} "
         f"requests/s ({new_best['threads']} threads, p50 {new_best['p50_ms']:.1f} ms)",
         goal("p50 ≤ 8 ms, ≥ 250/s", new1["p50_ms"] <= 8 and new_best["requests_per_s"] >= 250), load,
         "service.json"],
        ["… requests asked before: the same body again (its prediction kept), 1 thread / the best thread count; "
         "50 tools in turn (their modal fits kept, not their predictions), 1 thread / the best",
         f"p50 {one['p50_ms']:.1f} ms, {one['requests_per_s']:.0f} requests/s / {same_best['requests_per_s']:.0f} "
         f"requests/s ({same_best['threads']} threads); p50 {kept1['p50_ms']:.1f} ms, "
         f"{kept1['requests_per_s']:.0f} requests/s / {kept_best['requests_per_s']:.0f} requests/s "
         f"({kept_best['threads']} threads)", "", load, "service.json"],
        [f"REST, the largest batch per request: {count(largest['combinations'])} combinations × {count(largest['lines'])} lines "
         "as a job on 2 uvicorn workers (`bench_service.py --largest`)",
         f"done in {largest['job_done_s']:.0f} s, {largest['result_gb']:.2f} GB streamed by "
         f"{largest['result_received_s']:.0f} s; peak worker RSS {peak:.0f} MB", "completes (no worker lost)",
         load_text(largest["load_average_start"]), "service-largest.json"],
    ]


def _wire_rows() -> list[list[str]]:
    w = value("wire", "figures")
    p = w["prediction"]
    rows = [["JSON bytes of RA-1's 10 000-line result (`rcsa.app.results.json_bytes`) / `to_dict()` + orjson / "
             "`to_dict()` + `json.dumps`, against a cold `rcsa.predict` (`bench_wire.py`)",
             " / ".join(f"{p[k]:.1f} ms = {p[k] / p['predict_ms']:.2f}×" for k in (
                 "json_bytes(prediction), compact (REST, jobs, exports)", "to_dict() lists + orjson (the CLI before)",
                 "to_dict() lists + json.dumps (standard library)")) + f" (prediction {p['predict_ms']:.1f} ms)",
             goal("≤ 0.3×", p["json_bytes(prediction), compact (REST, jobs, exports)"] <= 0.3 * p["predict_ms"]),
             load_text(p["load_average"]), "wire.json"]]
    if "batch" in w:
        b = w["batch"]
        js, h5, pq = b["JSON (the job's writer)"], b["HDF5"], b["Parquet (uncompressed)"]
        rows.append([f"a {count(b['tools'])} × {count(b['lines'])}-line batch result written and fsynced result by result, "
                     "as a job writes it",
                     f"JSON {js['bytes'] / 1e9:.2f} GB in {js['write_s']:.1f} s; HDF5 {h5['bytes'] / 1e9:.2f} GB "
                     f"({h5['bytes'] / js['bytes']:.2f}×) in {h5['write_s']:.1f} s, "
                     f"{js['write_s'] / h5['write_s']:.1f}× faster; Parquet {pq['bytes'] / 1e9:.2f} GB "
                     f"({pq['bytes'] / js['bytes']:.2f}×) in {pq['write_s']:.1f} s, "
                     f"{js['write_s'] / pq['write_s']:.1f}× faster",
                     goal("≤ ⅓ of the bytes, ≥ 5× faster", max(h5["bytes"], pq["bytes"]) <= js["bytes"] / 3
                          and js["write_s"] >= 5 * max(h5["write_s"], pq["write_s"])),
                     load_text(b["load_average"]), "wire.json"])
    return rows


def _presets_job() -> tuple[dict[str, Any], str]:
    """The library job of ``bench_presets.py --job-tools`` and its load: a ``benchmarks/record.py``
    record (``figures.job``), or the first runs' plain file (``job``, ``machine_load``)."""
    r = result("presets_job")
    if "figures" in r:
        return r["figures"]["job"], load_text(r["load_average_start"], r["load_average_end"])
    return r["job"], load_text(r["machine_load"])


def _analysis_rows() -> list[list[str]]:
    j = value("jointid", "figures")
    sync = result("sync")
    timing = value("diagnosis_timing_fresh", "timing_fresh")
    ex, five = timing["example"], timing["analytical5"]
    u = value("uncertainty", "figures")
    job, job_load = _presets_job()
    rows = [
        ["joint identification, one RA-1 measurement of 4 951 lines, start 3× off (`bench_jointid.py`): "
         "analytical / measured spindle",
         f"{j['analytical']['median_s']:.2f} s / {j['measured']['median_s']:.2f} s",
         goal("≤ 0.5 s", max(j["analytical"]["median_s"], j["measured"]["median_s"]) <= 0.5),
         load_text(j["analytical"]["load_average"], j["measured"]["load_average"]), "jointid.json"],
        [f"library sync, {count(sync['tools'])} Fusion tools × {count(sync['frequency_lines'])} lines (`bench_sync.py`, best of "
         f"{sync['repeat']}): raw batch / first sync / unchanged re-sync / one tool changed",
         f"{sync['raw_batch']['total_s']:.2f} s / {sync['first_sync']['total_s']:.2f} s "
         f"({sync['first_over_raw_batch']:.2f}×) / {sync['unchanged_resync']['total_s']:.2f} s "
         f"({pct(sync['unchanged_over_first'], 1)}) / {sync['one_tool_changed']['total_s']:.2f} s",
         goal("first ≤ 1.5× raw batch, re-sync ≤ 5 %", sync["first_over_raw_batch"] <= 1.5
              and sync["unchanged_over_first"] <= 0.05), load_text(sync["load_average"]), "sync.json"],
        ["the first diagnosis in a fresh process (CPU, modules' bytecode compiled as installed) against a warm "
         "`rcsa.predict` of RA-1 at 10 000 lines (`bench_diagnosis.py --timing-fresh`): `examples/diagnosis.json` / "
         "5 stickouts",
         f"{ex['first_cpu_s']:.2f} s = {ex['first_over_warm_prediction_cpu']:.0f}× warm "
         f"({ex['first_over_prediction_cpu']:.0f}× cold; of it the Monte-Carlo Σ alone "
         f"{ex['first_call_counted']['over_warm_prediction_cpu']['monte_carlo']:.0f}×) / {five['first_cpu_s']:.2f} s "
         f"(Σ kept {five['warm_cpu_s']:.2f} s)",
         goal("≤ 35× / ≤ 2 s", ex["first_over_warm_prediction_cpu"] <= 35 and five["first_cpu_s"] <= 2),
         load_text(ex["load_average"], five["load_average"]), "diagnosis_timing_fresh.json"],
        [f"uncertainty band, RA-1 at {count(u['lines'])} lines, {u['draws']} draws (the reduced model), against one cold "
         "`rcsa.predict` (`bench_uncertainty.py`)",
         f"{u['ra1']['reduced']['wall_ratio']:.1f}× wall, {u['ra1']['reduced']['cpu_ratio']:.1f}× CPU "
         f"({u['ra1']['reduced']['wall_ms']:.0f} ms); every draw exact {u['ra1']['exact']['wall_ratio']:.0f}×; band "
         f"within {pct(u['ra1']['errors']['band_pointwise'], 2)} of the exact one pointwise, natural frequencies' mean "
         f"{pct(u['ra1']['errors']['modes_mean'], 2)}, sd {pct(u['ra1']['errors']['modes_sd'], 1)}",
         goal("≤ 10× and ≤ 2 %", u["ra1"]["reduced"]["wall_ratio"] <= 10 and u["ra1"]["errors"]["band_pointwise"] <= 0.02),
         load_text(u["ra1"]["load_average"]), "uncertainty.json"],
    ]
    if "robust_lobes" in u:
        r = u["robust_lobes"]
        rows.append([f"robust lobes (ZOA), {r['speeds']} speeds, {u['draws']} draws",
                     f"{r['reduced_ms'] / 1e3:.2f} s (reduced draws) against {r['exact_ms'] / 1e3:.2f} s (exact draws) "
                     f"and {r['nominal_ms']:.0f} ms nominal; robust limit within {pct(r['robust_limit_difference'], 2)}",
                     "", load_text(u["ra1"]["load_average"]), "uncertainty.json"])
    lobes = result("lobes")
    lf = lobes["figures"]
    rows.append([f"resolved stability lobes (the default semi-discretization), RA-1's tool point, {lf['speeds']} speeds "
                 "2 000–30 000 rpm, 2 teeth, a/D = 0.05, against a warm `rcsa.predict` of RA-1 at 10 000 lines "
                 "(spindle side kept, prediction computed) (`bench_lobes.py`)",
                 f"{lf['resolved_s']:.2f} s = {lf['ratio_to_warm_prediction']:.0f}× warm "
                 f"({lf['warm_prediction_s'] * 1e3:.1f} ms); {lf['resolved_speeds']} of {lf['speeds']} speeds resolved; "
                 f"{lf['baseline_ratio']:.1f}× faster than a per-speed loop of the same maps"
                 + (f"; its speeds shared by 2 worker processes (`rcsa lobes`' default here), end to end: "
                    f"{lf['spread_2_workers_fresh_s']:.2f} s = {lf['spread_fresh_ratio_to_warm_prediction']:.0f}× "
                    f"with the workers started in the call, {lf['spread_2_workers_kept_s']:.2f} s = "
                    f"{lf['spread_kept_ratio_to_warm_prediction']:.0f}× with them kept "
                    f"(one process: {lf['end_to_end_s']:.2f} s)" if "spread_2_workers_fresh_s" in lf else "")
                 + (f"; {lf['evaluations_per_speed']:.1f} (speed, depth) evaluations a speed at "
                    f"{lf['seconds_per_evaluation'] * 1e3:.2f} ms each: at {lf['floor_evaluations_per_speed']} a speed, "
                    f"the least a checked limit could need, {lf['floor_ratio_to_warm_prediction']:.0f}×"
                    if "evaluations" in lf else ""),
                 goal("≤ 25×", lf["ratio_to_warm_prediction"] <= 25),
                 load_text(lobes["load_average_start"], lobes["load_average_end"]), "lobes.json"])
    robust = result("robust_lobes")
    rf = robust["figures"]
    rows.append([f"robust stability lobes of `examples/lobes-robust.json` ({rf['speeds']} speeds, {rf['draws']} draws; "
                 "the reduced model's damping levels), warm, end to end (`bench_robust_lobes.py`): one process / its "
                 "speeds shared by 2 worker processes (`rcsa lobes`' default here)",
                 f"{rf['one_process_s']:.1f} s / {rf['two_workers_fresh_s']:.1f} s with the workers started in the call "
                 f"({rf['speedup_fresh']:.2f}× faster), {rf['two_workers_kept_s']:.1f} s with them kept "
                 f"({rf['speedup_kept']:.2f}×); robust limits within {pct(rf['robust_agreement'], 2)} of one process's",
                 "", load_text(robust["load_average_start"], robust["load_average_end"]), "robust_lobes.json"])
    for library, what in (("small", "25 single-flute tools Ø1–6 mm (issue 29's range)"),
                          ("multi", "25 two-, three- and four-flute tools Ø3–16 mm")):
        presets = value(f"presets_{library}", "figures.immersions")
        done = [k for k in ("0.05", "0.5") if k in presets]
        cli = [presets[k]["auto"].get("cli") for k in done]
        by_cli = all(cli)
        rows.append([f"chatter-safe presets, {what}, the default `auto` (`bench_presets.py --library {library}`): "
                     "a_e/D = " + " / ".join(done),
                     "in one process " + " / ".join(f"{presets[k]['auto']['wall_s']:.1f} s "
                                                    f"({presets[k]['auto']['cpu_s']:.1f} s CPU)" for k in done)
                     + ("; as `rcsa library recommend` runs by default here (`--workers 2`: one process a core), "
                        "start included " + " / ".join(f"{c['wall_s']:.1f} s ({c['cpu_s']:.1f} s CPU)" for c in cli)
                        if by_cli else ""),
                     goal("≤ 15 s", len(done) == 2 and max((c["wall_s"] for c in cli) if by_cli else
                                                           (presets[k]["auto"]["wall_s"] for k in done)) <= 15),
                     load_text(value(f"presets_{library}", "load_average_start"),
                               *(presets[k].get("timing_load_after", presets[k]["machine_load_after"]) for k in done)),
                     f"presets_{library}.json"])
    ext = result("pocket_extent")
    rows.append(["chatter-safe presets on the example grid (5–10 000 Hz), the multi-flute library at a_e/D 0.5, "
                 "pockets followed at most 2× from their speed against followed over the whole range "
                 "(`bench_pocket_extent.py`): its three-flute Ø4 mm tool / the 25 tools, CPU",
                 f"{ext['figures']['bounded']['tool_cpu_s']:.1f} s / {ext['figures']['bounded']['library_cpu_s']:.1f} s "
                 f"against {ext['figures']['whole_range']['tool_cpu_s']:.1f} s / "
                 f"{ext['figures']['whole_range']['library_cpu_s']:.1f} s ({ext['figures']['tool_ratio']:.1f}× / "
                 f"{ext['figures']['library_ratio']:.2f}×); the same presets: "
                 f"{'yes' if ext['figures']['same_presets'] else 'NO'}", "",
                 load_text(ext["load_average_start"], ext["load_average_end"]), "pocket_extent.json"])
    rows.append([f"chatter-safe presets: {count(job['tools'])} tools as a `library-recommend` job on a 2-worker Dask "
                 "`LocalCluster` (`bench_presets.py --job-tools 1000 --dask`)",
                 f"{job['recommend_job_s']:.0f} s, {count(job['summary']['written'])} presets written", "",
                 job_load, "presets_job.json"])
    return rows


def benchmarks_table() -> str:
    """The benchmark figures, each with its baseline, target, load and JSON."""
    return table(["what", "figure", "target", "load", "JSON"], _benchmark_rows())


def hybrid_accuracy_table() -> str:
    """The artifact route's error against the noise on the blank's FRFs (``bench_hybrid.py``)."""
    rows = [[f"{r['noise_rel'] * 100:g} %", f"{r['exact_three_frf']:.2g}", f"{r['finite_difference']:.3f}"]
            for r in value("hybrid", "figures.rows")]
    return table(["complex noise on each FRF", "exact three-FRF", "FD + P = N²/H fallback"], rows)


def modal_fit_sd() -> str:
    """How the modal fit's sd covers the true modes (``bench_modal_fit.py``)."""
    f = value("modal_fit", "figures")
    by = f["by_noise"]
    within = min(v["share_within_3sd"] for v in by.values())
    return (f"rms z {f['rms_z_pooled']:.2f} over {f['modes_pooled']} modes of "
            f"{next(iter(by.values()))['seeds']} evaluation seeds at 1 % and 3 % noise, "
            f"{within * 100:.0f} % within 3 sd: the sd is cautious")


def clamping_cost() -> str:
    """What a bonded clamping costs against the point joint (``bench_clamping_cost.py``)."""
    f = value("clamping_cost", "figures")
    load = load_text(value("clamping_cost", "load_average_start"), value("clamping_cost", "load_average_end"))
    return (f"{f['first_call_ratio']:.1f}× the point joint on a first call in a fresh process "
            f"({f['bonded']['first_call_s'] * 1e3:.0f} ms against {f['point']['first_call_s'] * 1e3:.0f} ms), "
            f"{f['repeated_ratio']:.1f}× repeated in one process without a kept spindle side, "
            f"{f['warm_ratio']:.2f}× warm (spindle side kept, as the service runs); {load}")


def spct(x: float, digits: int = 2) -> str:
    """A signed fraction as a percentage, the minus a real one: ``spct(-0.0246) == '−2.46 %'``."""
    return f"{x * 100:+.{digits}f} %".replace("-", "−")


def _coefficients(c: dict[str, float]) -> str:
    return ", ".join(f"{c[n]:.3g}" for n in ("interface", "step_cone", "holder_shear"))


def _run_load(name: str) -> str:
    return load_text(value(name, "load_average_start"), value(name, "load_average_end"))


def clamping_fit_table() -> str:
    """The calibration from the committed coefficients and random starts (``calibrate_clamping.py --fit``)."""
    rows = [[r["start_kind"], _coefficients(r["start"]), _coefficients(r["coefficients"]), f"{r['cost']:.3f}",
             f"{r['rms']:.3f}", str(r["evaluations"]), f"{min(r['singular_values']):.1f}"]
            for r in value("clamping_fit", "figures.starts")]
    return table(["start", "from (interface, step_cone, holder_shear)", "lands on", "cost ½Σr²", "rms r",
                  "evaluations", "smallest singular value"], rows)


def clamping_fit_summary() -> str:
    """How far apart the starts land and how far the fit moves the committed coefficients."""
    f = value("clamping_fit", "figures")
    return (f"{len(f['starts'])} starts land within {f['max_spread'] * 100:.2f} % of each other in every "
            f"coefficient, and the fit from the committed coefficients moves none by more than "
            f"{f['max_from_committed'] * 100:.2f} % ({f['rows']} rows, {f['peaks']} peaks; {_run_load('clamping_fit')})")


def _worst_cells(w: dict[str, Any]) -> list[str]:
    return [f"{w['rows_within_target']}/{w['rows']}", f"{spct(w['frequency_error'])} ({w['frequency_at_hz']:.0f} Hz)",
            f"{spct(w['height_error'], 1)} ({w['height_at_hz']:.0f} Hz)"]


def clamping_held_out_table() -> str:
    """The committed coefficients on every row, clamped base apart, extrapolating cases named (``calibrate_clamping.py``)."""
    s = value("clamping", "figures.summary")
    labels = {"held_out_interpolating": "held out, inside the calibrated range",
              "held_out_extrapolating": "held out, extrapolated", "calibration": "calibration"}
    rows = []
    for base in ("clamped", "spindle"):
        for key, label in labels.items():
            w = s.get(f"{base}_{key}")
            if w is None:
                continue
            named = f": {', '.join(f'`{c}`' for c in w['cases'])}" if key == "held_out_extrapolating" else ""
            rows.append([f"{base}", f"{label}{named}", str(w["peaks"]), *_worst_cells(w),
                         f"{w['median_mean_abs_db']:.2f} ({w['max_mean_abs_db']:.2f})",
                         f"{w['point_max_frequency_error'] * 100:.0f} % / {w['point_median_mean_abs_db']:.1f} dB"])
    return table(["base", "rows", "peaks", "rows within 1.5 % / 15 %", "worst peak frequency", "worst peak height",
                  "mean \\|dB\\| median (max)", "point joint: worst peak / median dB"], rows)


def clamping_lofo_table() -> str:
    """Leave one holder family out: each fold's coefficients and its family's worst peaks (``--lofo``)."""
    rows = []
    for fold in value("clamping_lofo", "figures.folds"):
        w = fold["worst"]
        rows.append([f"`{fold['family']}`", f"{len(fold['trained_on'])} cases", _coefficients(fold["coefficients"]),
                     str(len(fold["cases"])), *_worst_cells(w["clamped"]), *_worst_cells(w["spindle"]),
                     ", ".join(f"`{c}`" for c in fold["extrapolating"]) or "none"])
    return table(["family left out", "fitted on", "its coefficients", "cases", "clamped: rows within",
                  "worst frequency", "worst height", "spindle: rows within", "worst frequency", "worst height",
                  "outside the fold's training span"], rows)


def clamping_lofo_cases() -> str:
    """Every case of every fold: its peaks on each base against the fold's coefficients (``--lofo``)."""
    rows = []
    for fold in value("clamping_lofo", "figures.folds"):
        by_case: dict[str, dict[str, Any]] = {}
        for r in fold["rows"]:
            by_case.setdefault(r["case"], {})[r["base"]] = r
        for case, bases in by_case.items():
            cells = []
            for base in ("clamped", "spindle"):
                c = bases[base]["clamping"]
                f = max(c["peaks"], key=lambda p: abs(p["frequency_error"]))
                h = max(c["peaks"], key=lambda p: abs(p["height_error"]))
                mark = "" if c["max_frequency_error"] <= 0.015 and c["max_height_error"] <= 0.15 else " **missed**"
                cells.append(f"{len(c['peaks'])}: {spct(f['frequency_error'])} ({f['frequency_hz']:.0f} Hz), "
                             f"{spct(h['height_error'], 1)} ({h['frequency_hz']:.0f} Hz){mark}")
            r0 = bases["clamped"]
            rows.append([f"`{fold['family']}`", f"`{case}`", r0["role"], *cells,
                         ", ".join(r0["outside_training"]) or ""])
    return table(["family", "case", "role in the committed fit", "clamped: peaks, worst frequency, worst height",
                  "spindle: peaks, worst frequency, worst height", "outside the fold's span"], rows)


def scatter2_false_claims() -> str:
    """False claims of the doubled-scatter benchmark on its evaluation seed, and their exact 95 %
    upper bound (seed 4 is the one the claims' weighing was tuned on: ``diagnosis_scatter2.json``)."""
    s = value("diagnosis_scatter2_eval", "summary")
    k, n = (int(x) for x in s["false_claims_all_count"].split("/"))
    upper = clopper_pearson_upper(k, n)
    verdict = "met" if upper <= 0.05 else "met by the rate seen, not shown at 95 %" if k / n <= 0.05 else "missed"
    return f"**false claims {k}/{n}** (≤ 5 %: {verdict}; 95 % upper bound {upper * 100:.1f} %)"


def _seed(summary: dict[str, Any]) -> str:
    """``seed 3112, evaluation``: the seed of a diagnosis benchmark and its role (tuning or evaluation)."""
    settings = summary.get("settings", summary)
    return f"seed {settings['seed']}, {settings['seed_role']}"


def _load(summary: dict[str, Any]) -> str:
    settings = summary.get("settings", summary)
    load = settings.get("load_average")
    return load_text(load["min"], load["max"]) if load else "load not recorded"


def _claims(s: dict[str, Any]) -> str:
    k, n = (int(x) for x in s["false_claims_all_count"].split("/"))
    return f"false claims {k}/{n} (95 % upper bound {clopper_pearson_upper(k, n) * 100:.1f} %)"


def _db(x: float | None) -> str:
    return "—" if x is None else f"{x:.2f}"


def diagnosis_evaluation_table() -> str:
    """Issue 31's figures of the diagnosis, each from a run on a seed never used while tuning
    (``bench_diagnosis.py --evaluation``), with its target (met or missed, computed)."""
    rows = []
    h = value("diagnosis_hybrid_eval", "summary")
    p = h["pooled"]
    rows.append([f"withheld effects on measured spindles, 3 kinds pooled ({_seed(h)})", count(p["trials"]),
                 f"top-1 at SNR ≥ 10 **{p['top1_snr_ge_10']:.2f}** (n = {p['n_snr_ge_10']}), misses "
                 f"**{pct(p['miss_rate'], 0)}**, {_claims(p)}",
                 goal("top-1 ≥ 0.91, misses ≤ 20 %", p["top1_snr_ge_10"] >= 0.91 and p["miss_rate"] <= 0.20),
                 _load(h), "diagnosis_hybrid_eval.json"])
    s = value("diagnosis_scatter2_eval", "summary")
    k = int(s["false_claims_all_count"].split("/")[0])
    rows.append([f"every tolerance drawn at twice its stated σ ({_seed(s)})", count(s["trials"]),
                 f"**{_claims(s)}**; top-1 at SNR ≥ 10 {s['top1_snr_ge_10']:.2f}, misses {pct(s['miss_rate'], 0)}",
                 goal("0 false claims", k == 0), _load(s), "diagnosis_scatter2_eval.json"])
    d = value("diagnosis_solid3d", "summary")
    for model, what in (("bonded", "`bonded` base"), ("point", "`point` base, stiff joint")):
        m = d[model]
        rows.append([f"3-D truths (4 classes), {what} ({_seed(d)})", count(m["n"]),
                     f"mean |dB| to the truth, median: base {_db(m['median_base_db_error'])} → corrected "
                     f"**{_db(m['median_corrected_db_error'])}** ({pct(m['share_corrected_within_1db'], 0)} of trials "
                     f"within 1 dB), calibrated **{_db(m['median_calibrated_db_error'])}** (worst "
                     f"{_db(m['max_calibrated_db_error'])}; {pct(m['share_calibrated_within_1db'], 0)} within 1 dB)",
                     goal("corrected ≤ 1 dB (median)", m["median_corrected_db_error"] <= 1.0), _load(d),
                     "diagnosis_solid3d.json"])
    c = value("diagnosis_solid3d_cases", "summary")
    for model in ("point", "point_ra1", "bonded"):
        if model not in c:
            continue
        m = c[model]
        rows.append([f"3-D holder families outside the clamping calibration, `{model}` base ({_seed(c)})",
                     count(m["n"]),
                     f"base {_db(m['median_base_db_error'])} → corrected **{_db(m['median_corrected_db_error'])}** "
                     f"(worst {_db(m['max_corrected_db_error'])}), calibrated {_db(m['median_calibrated_db_error'])}; "
                     f"left unexplained although a model switch explains it: "
                     f"{m['unexplained_although_switch_explains']}",
                     goal("≤ 1 dB, 0 unexplained", m["median_corrected_db_error"] <= 1.0
                          and m["unexplained_although_switch_explains"] == 0), _load(c),
                     "diagnosis_solid3d_cases.json"])
    ex = value("diagnosis_timing_fresh", "timing_fresh.example")
    rows.append(["the first diagnosis in a fresh process (`examples/diagnosis.json`, CPU) over a warm RA-1 "
                 "prediction at 10 000 lines", "3 processes",
                 f"**{ex['first_over_warm_prediction_cpu']:.0f}×** ({ex['first_cpu_s']:.2f} s / "
                 f"{ex['warm_prediction_cpu_s'] * 1e3:.1f} ms); the Monte-Carlo Σ of its "
                 f"{ex['first_call_counted']['tip_solves_by_phase']['monte_carlo']} solves alone "
                 f"{ex['first_call_counted']['over_warm_prediction_cpu']['monte_carlo']:.0f}×",
                 goal("≤ 35×", ex["first_over_warm_prediction_cpu"] <= 35), load_text(ex["load_average"]),
                 "diagnosis_timing_fresh.json"])
    return table(["benchmark (seed)", "trials", "figure", "target", "load", "JSON"], rows)


def solid3d_table() -> str:
    """The 3-D truths per base model and class: verdicts, FRF errors (``diagnosis_solid3d.json``)."""
    d = value("diagnosis_solid3d", "summary")
    rows = []
    for model in ("bonded", "point"):
        for klass, c in d[model]["per_class"].items():
            verdicts = ", ".join(f"{v} {n}" for v, n in sorted(c["verdicts"].items(), key=lambda x: -x[1]))
            rows.append([f"`{model}`", klass, str(c["n"]), verdicts, _db(c["median_base_db_error"]),
                         _db(c["median_corrected_db_error"]), _db(c["median_calibrated_db_error"]),
                         _db(c["median_corrected_db_error_at_true_nuisance"])])
    return table(["base", "class", "n", "verdicts (status:effect)", "base dB", "corrected dB", "calibrated dB",
                  "corrected at the truth's own draw, dB"], rows)


def machine() -> str:
    """The machine the engine benchmark ran on (``benchmarks/record.py``)."""
    m = value("engine", "machine")
    return f"{m['cpu']}, {m['cores']} cores, {m['memory_gb']:g} GB, Python {m['python']}, numpy {m['numpy']}"


def _dask() -> dict[str, Any]:
    d = result("dask")
    chunk_mb = d["result_cache_mb"] / d["dask"]["chunks"]
    writes = sorted((d["local"]["chunk_write_here"]["mean_s"], d["dask"]["chunk_write_here"]["mean_s"]))
    return {"chunk_mb": chunk_mb, "writes": writes, "fixed": d["dask"]["import_s"] + d["dask"]["plan_s"],
            "chunks": d["dask"]["chunks"], "compute": d["local"]["chunk_compute_here"]["mean_s"]}


def dask_writes() -> str:
    """The range of one chunk's write into the result cache, local and on the cluster (``bench_dask.py``)."""
    lo, hi = _dask()["writes"]
    return f"{lo:.2f}–{hi:.2f} s to write its {_dask()['chunk_mb']:.0f} MB"


def dask_expected() -> str:
    """The expected first sync on N machines: fixed costs + max(compute / N, the service's writing)."""
    d, e = _dask(), result("dask")["expected_wall_s_on_n_machines_with_local_chunk_cost"]
    lo, hi = d["writes"]
    return (f"{d['fixed']:.1f} s + max({d['chunks']} chunks × {d['compute']:.2f} s / N, {d['chunks']} × "
            f"{lo:.2f}–{hi:.2f} s of writing) — about {e['2']:.0f} s on 2, {d['fixed'] + d['chunks'] * lo:.0f}–"
            f"{e['4']:.0f} s from 4 on")


def dask_write_rate() -> str:
    """The service's single writer's rate of results (``bench_dask.py``)."""
    d = _dask()
    lo, hi = d["writes"]
    return f"≈ {d['chunk_mb'] / hi:.0f}–{d['chunk_mb'] / lo:.0f} MB/s"



# --------------------------------------------------------------------------- the service under abuse (issue 30)

def _record(name: str) -> tuple[dict[str, Any], str]:
    """A service benchmark's figures and the load they were measured at: ``benchmarks/record.py``'s
    form (``figures``, ``load_average_start``/``_end``), or the first records' (``machine_before``/``_after``)."""
    r = result(name)
    if "figures" in r:
        return r["figures"], load_text(r["load_average_start"], r["load_average_end"])
    return r, load_text(r["machine_before"]["load_average"], r["machine_after"]["load_average"])


def bulk_refusals() -> str:
    """Bulk bodies an anonymous caller sends to ``rcsa serve --workers 2`` (``bench_hostile.py --bulk``)."""
    f, load = _record("bulk")
    four = [c for c in f["cases"] if c["body_bytes"] < 5 * 2**20]
    big = [c for c in f["cases"] if c["body_bytes"] > 60 * 2**20]
    tiny = next(c for c in four if "tiny objects" in c["case"])
    other = f["other_caller"]
    return (f"a 4 MiB batch of tiny objects is a {tiny['status']} in {tiny['seconds']:.2f} s, its worker grown by "
            f"{tiny['worker_growth_mb']:.0f} MB; the {len(four)} bodies of about 4 MiB (batches and libraries of tiny "
            f"objects, numbers, strings) are all refused within {max(c['seconds'] for c in four):.2f} s, a worker grown by at most "
            f"{max(c['worker_growth_mb'] for c in four):.0f} MB; the {len(big)} bodies of 63 MiB are refused after "
            f"at most {max(c['body_sent_bytes'] for c in big) / 2**20:.1f} MiB were read, within "
            f"{max(c['seconds'] for c in big):.2f} s, "
            f"{'no worker lost' if f['workers_unchanged'] else '**a worker lost**'}; meanwhile another caller's "
            f"{count(other['requests'])} predictions: {other['failures']} failed, the slowest "
            f"{other['slowest_s']:.2f} s; {f['tracebacks']} tracebacks ({load})")


def auth_probes() -> str:
    """Forged, missing, revoked and read-only credentials on every write and job read (``bench_auth.py``)."""
    f, load = _record("auth")
    return (f"{count(f['cases'])} probes — {count(f['write_cases'])} on the {len(f['operations_probed'])} write "
            f"operations (no key, forged, revoked, read-only), {count(f['job_cases'])} reading another caller's "
            f"jobs — found **{len(f['bypasses'])} bypasses**, {len(f['server_errors'])} × 5xx, the store "
            f"{'unchanged' if f['store_unchanged'] else '**changed**'} ({load}; `benchmarks/bench_auth.py`, "
            "`auth.json`).")


def crash_losses() -> str:
    """Idempotent uploads and jobs while workers are killed (``bench_crash.py``)."""
    f, load = _record("crash")
    every = f"in {f['wall_seconds']:.0f} s"
    if "min_age_s" in f:
        every += f": every {f['kill_every_s']:g} s or so, one that had been up {f['min_age_s']:g} s"
    return (f"{count(f['uploads'])} idempotent uploads and {f['jobs']} batch jobs while {f['workers_killed']} "
            f"workers were killed ({every}): {len(f['lost'])} lost, {len(f['duplicated'])} duplicated, "
            f"{len(f['unreadable'])} unreadable, {len(f['jobs_not_complete'])} jobs not complete"
            f", `rcsa store check` exit {f['store_check_exit']} ({load})")


def soak_memory() -> str:
    """Worker memory under mixed load (``bench_soak.py``)."""
    f, load = _record("soak")
    workers = f["workers"].values()
    errors = sum(f["server_errors"].values())
    growth = max(w["growth_last_third_mb"] for w in workers)
    return (f"{f['minutes']:g} min of mixed load ({f['clients']} clients, {count(f['requests'])} requests: "
            f"predictions, batches and jobs, lobes by reference, reads, refusals): {errors} × 5xx, "
            f"{'the same workers throughout' if f['same_workers_throughout'] else '**workers replaced**'}; worker "
            "memory " + ", ".join(f"{w['start_mb']:.0f} → peak {w['peak_mb']:.0f} → {w['end_mb']:.0f} MB"
                                   for w in workers)
            + f", at most {growth:+.1f} MB in the last third above the first two thirds' highest: "
            f"{'it levels off' if growth <= 10 else '**still growing**'} ({load})")


def hostile_run() -> str:
    """The hostile run over every operation (``bench_hostile.py``)."""
    f, load = _record("hostile")
    five = sum(v for k, v in f["by_status"].items() if k.startswith("5"))
    statuses = ", ".join(f"{count(v)} × {k}" for k, v in f["by_status"].items())
    return (f"{count(f['cases'])} cases over {f['operations']} operations (seed {f['seed']}, {load}) answered in "
            f"{f['wall_seconds']:.0f} s: **{five} × 5xx, {len(f['wrong'])} wrong**, {f['tracebacks']} tracebacks "
            f"— {statuses}")


def presets_safety_table(library: str = "small") -> str:
    """How safe and how productive the default presets are, per immersion (``bench_presets.py --library LIBRARY``)."""
    f = value(f"presets_{library}", "figures")
    rows = []
    for ae, entry in f["immersions"].items():
        for method in (m for m in ("auto", "zoa", "semi_discretization") if m in entry):
            s = entry[method]["summary"]
            worst = s["worst_depth_over_window_limit"]
            rows.append([ae, f"`{method}`", f"{s['written']} of {s['tools']}",
                         f"**{s['unstable_by_sdm']}** (deepest {worst:.2f}× its window's limit)" if worst else "—",
                         f"{s['refused']} ({s['false_refusals']} falsely)",
                         f"{s['productivity_median']:.2f} ({s['productivity_min']:.2f})",
                         f"{entry[method]['wall_s']:.1f} s ({entry[method]['cpu_s']:.1f} s CPU)"
                         + (f"; CLI, {entry[method]['cli']['workers']} worker processes: "
                            f"{entry[method]['cli']['wall_s']:.1f} s ({entry[method]['cli']['cpu_s']:.1f} s CPU)"
                            if "cli" in entry[method] else "")])
        oracle = entry.get("oracle", [])
        td = entry.get("time_domain", [])
        rows.append([ae, "checks of `auto`",
                     f"collocation oracle at the weakest speed of {len(oracle)} windows: preset / oracle limit "
                     + ", ".join(f"{o['preset_over_oracle']:.2f}" for o in oracle),
                     f"time domain: {sum(t['preset_stable'] for t in td)} of {len(td)} presets stable, "
                     f"{sum(t['next_step_up_chatters'] for t in td)} of {len(td)} chatter at 1.25× the window's limit",
                     "", "", ""])
    return table(["a_e/D", "method", "presets written", "unstable by the dense SDM over the window",
                  "refused", "productivity, median (min)", "time, 25 tools: in one process; the CLI"], rows)


def presets_cli_summary() -> str:
    """The presets benchmarks' command-line runs beside their in-process ones, per library and immersion."""
    parts, diffs, same = [], [], True
    for library, what in (("small", "single-flute library"), ("multi", "multi-flute library")):
        imm = value(f"presets_{library}", "figures.immersions")
        runs = [(k, imm[k]["auto"]) for k in ("0.05", "0.5") if k in imm and "cli" in imm[k]["auto"]]
        if not runs:
            continue
        workers = runs[0][1]["cli"]["workers"]
        parts.append(f"the {what} at a_e/D " + " and ".join(
            f"{k} in {a['cli']['wall_s']:.1f} s ({a['cli']['cpu_s']:.1f} s CPU; in one process {a['wall_s']:.1f} s)"
            for k, a in runs) + f" with {workers} workers")
        diffs += [a["cli"]["max_depth_limit_difference"] for _, a in runs]
        same &= all(a["cli"]["same_speeds"] for _, a in runs)
    if not parts:
        return "(no command-line runs recorded)"
    return ("; ".join(parts) + f". Speeds {'the same' if same else 'NOT the same'} in every run, depth limits within "
            f"{max(diffs):.1e} of the in-process ones.")


#: Named figures: each renders Markdown from the results files.
FIGURES: dict[str, Callable[[], str]] = {
    "benchmarks-table": benchmarks_table,
    "machine": machine,
    "hybrid-accuracy-table": hybrid_accuracy_table,
    "modal-fit-sd": modal_fit_sd,
    "clamping-cost": clamping_cost,
    "clamping-fit-table": clamping_fit_table,
    "clamping-fit-summary": clamping_fit_summary,
    "clamping-held-out-table": clamping_held_out_table,
    "clamping-lofo-table": clamping_lofo_table,
    "clamping-lofo-cases": clamping_lofo_cases,
    "clamping-load": lambda: _run_load("clamping"),
    "clamping-lofo-load": lambda: _run_load("clamping_lofo"),
    "scatter2-false-claims": scatter2_false_claims,
    "diagnosis-evaluation-table": diagnosis_evaluation_table,
    "solid3d-table": solid3d_table,
    "dask-writes": dask_writes,
    "dask-expected": dask_expected,
    "dask-write-rate": dask_write_rate,
    "dask-load": lambda: load_text(value("dask", "load_average_start"), value("dask", "load_average_end")),
    "dask-overhead-share": lambda: pct(value("dask", "dask.overhead_s") / value("dask", "dask.wall_s"), 0),
    "bulk-refusals": bulk_refusals,
    "auth-probes": auth_probes,
    "crash-losses": crash_losses,
    "soak-memory": soak_memory,
    "hostile-run": hostile_run,
    "presets-safety-table": presets_safety_table,
    "presets-safety-table-multi": lambda: presets_safety_table("multi"),
    "presets-cli-summary": presets_cli_summary,
}


# --------------------------------------------------------------------------- rendering

def render_figure(name: str) -> str:
    """The text of the figure ``name`` (module docstring)."""
    name = name.strip()
    if name in FIGURES:
        return FIGURES[name]()
    file, sep, rest = name.partition(":")
    if not sep or not file.endswith(".json"):
        raise FigureError(f"unknown figure {name!r}: not a named figure nor FILE.json:PATH|SPEC")
    path, _, spec = rest.partition("|")
    return fmt(value(file, path), spec)


def render(text: str) -> str:
    """``text`` with every figure rendered between its markers."""
    def one(match: re.Match[str]) -> str:
        name = match["name"]
        rendered = render_figure(name)
        body = f"\n{rendered}\n" if "\n" in rendered or match["body"].startswith("\n") else rendered
        return f"<!-- figure: {name} -->{body}<!-- /figure -->"

    return MARKER.sub(one, text)


def documents() -> list[Path]:
    """The documents rendered (:data:`DOCUMENTS`)."""
    found: list[Path] = []
    for pattern in DOCUMENTS:
        found += sorted(REPO.glob(pattern))
    return found


def differences(path: Path) -> list[str]:
    """The figures of ``path`` whose text differs from their rendering, as ``NAME: 'old' → 'new'``."""
    out = []
    for match in MARKER.finditer(path.read_text(encoding="utf-8")):
        new = render(match[0])
        if new != match[0]:
            now = MARKER.match(new)
            assert now is not None
            shown = path.relative_to(REPO) if path.is_relative_to(REPO) else path
            out.append(f"{shown}: {match['name']}: {match['body'].strip()!r} → {now['body'].strip()!r}")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only list the figures that differ (exit 1 if any)")
    args = parser.parse_args(argv)
    stale = [d for path in documents() for d in differences(path)]
    if args.check:
        print("\n".join(stale) or "every figure matches its JSON")  # noqa: T201 (the script's output)
        return 1 if stale else 0
    for path in documents():
        text = path.read_text(encoding="utf-8")
        new = render(text)
        if new != text:
            path.write_text(new, encoding="utf-8")
            print(f"rendered {path.relative_to(REPO)}")  # noqa: T201 (the script's output)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Fit the clamping model's coefficients to the 3-D reference and measure it on cases held out.

Run (reads ``tests/data/solid3d``, which ``benchmarks/bench_solid3d.py --write-data`` regenerates)::

    .venv/bin/python benchmarks/calibrate_clamping.py            # score every row -> results/clamping.json
    .venv/bin/python benchmarks/calibrate_clamping.py --fit      # the fit from several starts -> clamping_fit.json
    .venv/bin/python benchmarks/calibrate_clamping.py --lofo     # leave one holder family out -> clamping_lofo.json

``--fit`` fits the coefficients of :data:`rcsa.model.clamping.FITTED` on the calibration cases
(:data:`tests.oracles.solid3d.clamping_scores.CALIBRATION_CASES`, both bases) by least squares
over every peak's frequency and height and the static compliance
(:mod:`tests.oracles.solid3d.clamping_fit`), from the committed coefficients and from
:data:`STARTS` other starts drawn log-uniformly over the start box (seed :data:`SEED`), and says
how far apart the answers land and how far the fit from the committed coefficients moves them
(the committed coefficients are this fit's answer, rounded: it must stay within 1 %).

``--lofo``: for each holder family, the same fit on the calibration cases of the *other*
families only, from the centre of the start box (nothing of the family left out enters it),
scored on every case of the family left out (both bases, every peak of the band); each fold
names the cases that lie outside the geometry its own training cases span.

Scoring (no option): for every case of the data set and both bases (the holder's base face
clamped; RA-1's spindle and spindle–holder joint), rcsa's tool-point h against the 3-D truth
over the band: every peak's frequency and height (:func:`tests.oracles.solid3d.clamping_scores.score_row`),
the mean |dB|, the static compliance. Models: ``point`` (the contract's beam: composite
insertion, rigid point joint) and the case's clamping (``bonded``, or ``contact`` with the
case's interface, front gap, contact length and arc). Summaries keep the clamped base apart
(the spindle rows share RA-1's spindle with the truth, whose modes both sides match by
construction, which halves their errors) and name the held-out cases that extrapolate.

Every run writes its figures with the machine and its load (``benchmarks/record.py``);
``scripts/render_figures.py`` renders the README's clamping tables from them.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.oracles.solid3d import clamping_fit, clamping_scores, dataset  # noqa: E402
from tests.oracles.solid3d.clamping_scores import CALIBRATION_CASES, INFORMATION, role  # noqa: E402

import rcsa.model.clamping as clamping  # noqa: E402
from record import load_average, write  # noqa: E402

#: Starts of ``--fit`` besides the committed coefficients (log-uniform in the start box, seed :data:`SEED`).
STARTS = 5
SEED = 20240531
#: Tolerances the issue sets (every peak in the band; any row).
TARGET = {"frequency": 0.015, "height": 0.15}


def _random_starts(names: list[str], committed: clamping.BulkCoefficients, count: int, seed: int
                   ) -> list[clamping.BulkCoefficients]:
    rng = np.random.default_rng(seed)
    box = clamping_fit.START_BOX
    return [replace(committed, **{n: float(np.exp(rng.uniform(np.log(box[n][0]), np.log(box[n][1])))) for n in names})
            for _ in range(count)]


def _centre(names: list[str], committed: clamping.BulkCoefficients) -> clamping.BulkCoefficients:
    """The geometric centre of the start box (a start that knows nothing of the data)."""
    return replace(committed, **{n: math.sqrt(clamping_fit.START_BOX[n][0] * clamping_fit.START_BOX[n][1])
                                 for n in names})


def _coefficients_text(c: clamping.BulkCoefficients, names: list[str]) -> str:
    return ", ".join(f"{n} {getattr(c, n):.4g}" for n in names)


def run_fit(directory: Path, starts: int, seed: int) -> dict[str, Any]:
    """The committed fit from several starts (module docstring)."""
    names = list(clamping.FITTED)
    committed = clamping.BULK_COEFFICIENTS
    rows = clamping_fit.prepare(list(CALIBRATION_CASES), directory=directory)
    peaks = sum(r.peak_hz.size for r in rows)
    print(f"fitting {names} on {len(rows)} rows ({len(CALIBRATION_CASES)} cases x 2 bases), {peaks} peaks", flush=True)
    results = []
    for k, start in enumerate([committed, *_random_starts(names, committed, starts, seed)]):
        load = load_average()
        t0 = time.perf_counter()
        res = clamping_fit.fit(rows, names, start, directory)
        results.append({"start_kind": "committed" if k == 0 else f"random {k}", **res.to_dict(names),
                        "seconds": time.perf_counter() - t0, "load_average": load})
        print(f"  start {k} ({results[-1]['start_kind']}): {_coefficients_text(start, names)} -> "
              f"{_coefficients_text(res.coefficients, names)}; cost {res.cost:.4f}, rms {res.rms:.3f}, "
              f"{res.evaluations} evaluations, {results[-1]['seconds']:.0f} s", flush=True)
    best = min(results, key=lambda r: r["cost"])
    spread = {n: max(abs(r["coefficients"][n] / best["coefficients"][n] - 1) for r in results) for n in names}
    from_committed = {n: results[0]["coefficients"][n] / getattr(committed, n) - 1 for n in names}
    print("largest spread over the starts (relative to the best): "
          + ", ".join(f"{n} {100 * v:.3f} %" for n, v in spread.items()))
    print("the fit from the committed coefficients vs the committed: "
          + ", ".join(f"{n} {100 * v:+.3f} %" for n, v in from_committed.items()))
    return {"fitted": names, "committed": asdict(committed), "calibration_cases": list(CALIBRATION_CASES),
            "rows": len(rows), "peaks": peaks, "sigma": clamping_fit.SIGMA, "bounds": clamping_fit.BOUNDS,
            "start_box": clamping_fit.START_BOX, "seed": seed, "starts": results, "best": best["coefficients"],
            "spread": spread, "max_spread": max(spread.values()), "from_committed": from_committed,
            "max_from_committed": max(abs(v) for v in from_committed.values()),
            "smallest_singular_value": min(min(r["singular_values"]) for r in results)}


def _row(name: str, base: str, directory: Path, models: tuple[str, ...] = ("point", "clamping")) -> dict[str, Any]:
    row: dict[str, Any] = {"case": name, "base": base, "family": dataset.case_family(name), "role": role(name),
                           "extrapolated": clamping_scores.extrapolation_notes(name, directory)}
    for model in models:
        if name == "rigid_holder" and model == "clamping":
            continue
        row[model] = clamping_scores.score_row(name, base, model, directory)
    return row


def _within(score: dict[str, Any]) -> bool:
    return bool(score["max_frequency_error"] <= TARGET["frequency"] and score["max_height_error"] <= TARGET["height"])


def _worst(scores: list[dict[str, Any]]) -> dict[str, Any]:
    """The largest |errors| over the rows' peaks, signed, with where they are."""
    peaks = [(s_i, p) for s_i, s in enumerate(scores) for p in s["peaks"]]
    f = max(peaks, key=lambda x: abs(x[1]["frequency_error"]))
    h = max(peaks, key=lambda x: abs(x[1]["height_error"]))
    return {"peaks": len(peaks), "frequency_error": f[1]["frequency_error"], "frequency_at_hz": f[1]["frequency_hz"],
            "height_error": h[1]["height_error"], "height_at_hz": h[1]["frequency_hz"],
            "max_mean_abs_db": max(s["mean_abs_db"] for s in scores),
            "rows_within_target": sum(_within(s) for s in scores), "rows": len(scores)}


def run_lofo(directory: Path) -> dict[str, Any]:
    """Leave one holder family out: fit on the others' calibration cases, score the family's cases."""
    names = list(clamping.FITTED)
    committed = clamping.BULK_COEFFICIENTS
    start = _centre(names, committed)
    folds = []
    for family in dataset.FAMILIES:
        train = [n for n in CALIBRATION_CASES if dataset.case_family(n) != family]
        test = [n for n in dataset.reference_cases() if dataset.case_family(n) == family and n not in INFORMATION]
        ranges = clamping_scores.geometry_ranges(train)
        load = load_average()
        t0 = time.perf_counter()
        res = clamping_fit.fit(clamping_fit.prepare(train, directory=directory), names, start, directory)
        clamping.BULK_COEFFICIENTS = res.coefficients
        try:
            rows = [_row(n, b, directory, models=("clamping",)) for n in test for b in dataset.BASES]
        finally:
            clamping.BULK_COEFFICIENTS = committed
        for r in rows:
            r["outside_training"] = clamping_scores.outside(r["case"], ranges)
        by_base = {b: _worst([r["clamping"] for r in rows if r["base"] == b]) for b in dataset.BASES}
        folds.append({"family": family, "trained_on": train, "training_ranges": ranges, "start": asdict(start),
                      "coefficients": {n: getattr(res.coefficients, n) for n in names}, "rms": res.rms,
                      "singular_values": res.singular_values.tolist(), "cases": test,
                      "extrapolating": sorted({r["case"] for r in rows if r["outside_training"]}),
                      "worst": by_base, "rows": rows, "seconds": time.perf_counter() - t0, "load_average": load})
        print(f"  without {family:15s}: {_coefficients_text(res.coefficients, names)} | its {len(test)} cases: "
              + "; ".join(f"{b} peaks within {100 * abs(w['frequency_error']):.2f} % / {100 * abs(w['height_error']):.1f} %"
                          f" ({w['rows_within_target']}/{w['rows']} rows)" for b, w in by_base.items()), flush=True)
    every = [r for fold in folds for r in fold["rows"]]
    totals = {b: _worst([r["clamping"] for r in every if r["base"] == b]) for b in dataset.BASES}
    return {"fitted": names, "families": list(dataset.FAMILIES), "start": asdict(start), "target": TARGET,
            "totals": totals, "folds": folds}


def _summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for base in dataset.BASES:
        for label, select in (("held_out", lambda r: r["role"] == "held-out"),
                              ("held_out_interpolating", lambda r: r["role"] == "held-out" and not r["extrapolated"]),
                              ("held_out_extrapolating", lambda r: r["role"] == "held-out" and r["extrapolated"]),
                              ("calibration", lambda r: r["role"] == "calibration")):
            chosen = [r for r in rows if r["base"] == base and select(r) and "clamping" in r]
            if not chosen:
                continue
            c = [r["clamping"] for r in chosen]
            p = [r["point"] for r in chosen]
            out[f"{base}_{label}"] = {
                "cases": [r["case"] for r in chosen], **_worst(c),
                "median_mean_abs_db": float(np.median([s["mean_abs_db"] for s in c])),
                "point_median_mean_abs_db": float(np.median([s["mean_abs_db"] for s in p])),
                "point_max_frequency_error": float(max(s["max_frequency_error"] for s in p)),
                "point_max_height_error": float(max(s["max_height_error"] for s in p))}
    return out


def run_scores(directory: Path) -> dict[str, Any]:
    """Every row with the committed coefficients."""
    rows = []
    for name in dataset.reference_cases():
        for base in dataset.BASES:
            row = _row(name, base, directory)
            rows.append(row)
            c = row.get("clamping")
            print(f"{name:24s} {base:8s} {row['role']:11s} point {row['point']['mean_abs_db']:5.2f} dB "
                  f"{100 * row['point']['max_frequency_error']:5.1f} % | "
                  + (f"clamping {c['mean_abs_db']:5.2f} dB, {len(c['peaks'])} peaks within "
                     f"{100 * c['max_frequency_error']:5.2f} % / {100 * c['max_height_error']:5.1f} %" if c else "")
                  + (" (extrapolated)" if row["extrapolated"] else ""), flush=True)
    summary = _summary(rows)
    for key, s in summary.items():
        print(f"{key:32s} {s['rows_within_target']}/{s['rows']} rows within target; peaks within "
              f"{100 * abs(s['frequency_error']):.2f} % / {100 * abs(s['height_error']):.1f} %; "
              f"median mean |dB| {s['median_mean_abs_db']:.2f} (point {s['point_median_mean_abs_db']:.2f})")
    return {"coefficients": asdict(clamping.BULK_COEFFICIENTS), "fitted": list(clamping.FITTED),
            "calibration_cases": list(CALIBRATION_CASES), "information": list(INFORMATION), "target": TARGET,
            "calibrated_geometry_ranges": clamping.CALIBRATED_GEOMETRY_RANGES, "summary": summary, "rows": rows}


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--fit", action="store_true", help="fit from several starts (results/clamping_fit.json)")
    parser.add_argument("--lofo", action="store_true", help="leave one family out (results/clamping_lofo.json)")
    parser.add_argument("--starts", type=int, default=STARTS, help="random starts besides the committed one")
    parser.add_argument("--seed", type=int, default=SEED)
    parser.add_argument("--data", type=Path, default=dataset.DATA_DIR, help="the 3-D data set's folder")
    args = parser.parse_args()
    if args.fit:
        load = load_average()
        t0 = time.perf_counter()
        write("clamping_fit", {**run_fit(args.data, args.starts, args.seed), "seconds": time.perf_counter() - t0},
              load_start=load)
    if args.lofo:
        load = load_average()
        t0 = time.perf_counter()
        write("clamping_lofo", {**run_lofo(args.data), "seconds": time.perf_counter() - t0}, load_start=load)
    if not (args.fit or args.lofo):
        load = load_average()
        t0 = time.perf_counter()
        write("clamping", {**run_scores(args.data), "seconds": time.perf_counter() - t0}, load_start=load)


if __name__ == "__main__":
    main()

"""Claim rules compared offline on a withheld-effect record (issue 31: false claims under doubled scatter).

A record of ``bench_diagnosis.py`` (its trials keep every candidate's ln BF at the stated Σ, the
first effect's held-out gap ratio and, since stop 38, the remainder's scatter scale ``ŝ``) is
re-decided under rules that change only the verdict's status and its set, and scored as the
benchmark scores it (:func:`bench_diagnosis._false_claim`, top-1 at SNR ≥ 10, misses):

* ``as_run`` — the record's own verdicts (the diagnosis's rule);
* ``ambiguity_at_scatter`` — where the claim was weighed at ``ŝ > 1``, every rival whose stated
  ln BF margin divided by ``ŝ²`` is below the ambiguity window joins the verdict's set (the
  margins between candidates compressed as the claim's own evidence is; an approximation: the
  rivals are not refitted at Σ·ŝ²);
* ``claim_threshold_<10 τ>`` — a lower claim threshold τ: a trial answered ``none`` whose best
  stated ln BF lies in (τ, 3] names it (with the rivals within the window by ln BF); trials
  refused at their remainder's scatter stay ``none``;
* ``held_out_gap_ratio_at_most_<100 r>`` — a claim whose first effect leaves more than ``r`` of the held-out
  gap becomes ``none``.

Use it on *tuning* records only (``TUNING_SEEDS``): a rule chosen on an evaluation record has
been tuned on it. Run: ``.venv/bin/python benchmarks/diagnosis_claim_rules.py
benchmarks/results/diagnosis_scatter2_tune3113.json`` (writes ``diagnosis_claim_rules.json``).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import record  # noqa: E402
from benchmarks.bench_diagnosis import _false_claim, _names  # noqa: E402

from rcsa.analysis.diagnosis.request import Options  # noqa: E402

#: The diagnosis's ambiguity window in ln evidence and its claim threshold in ln BF (its default options).
AMBIGUITY_WINDOW = Options().ambiguity_window
CLAIM_THRESHOLD = Options().claim_threshold
GAP_RATIOS = (1.0, 0.95, 0.9, 0.85)
CLAIM_THRESHOLDS = (2.5, 2.0, 1.5)


def ambiguity_at_scatter(r: dict) -> dict:
    """The verdict with the rivals whose margin over ``ŝ²`` falls inside the window."""
    s = r.get("scatter_scale") or 1.0
    if r["status"] == "none" or s <= 1.0:
        return r
    best = r["ranking"][0][1]
    rivals = {name for name, lnbf in r["ranking"][1:] if (best - lnbf) / s**2 < AMBIGUITY_WINDOW}
    together = sorted(set(r["ambiguous_with"]) | rivals)
    return {**r, "ambiguous_with": together, "status": "ambiguous" if together else r["status"]}


def gap_ratio_gate(limit: float) -> Callable[[dict], dict]:
    """A claim leaving more than ``limit`` of its held-out gap answered ``none``."""
    def rule(r: dict) -> dict:
        ratio = r["held_out_gap_ratio"]
        if r["status"] != "none" and (ratio is None or ratio > limit):
            return {**r, "status": "none", "verdict": "none", "ambiguous_with": []}
        return r
    return rule


def claim_threshold(tau: float) -> Callable[[dict], dict]:
    """The verdict under claim threshold ``tau`` (below the diagnosis's 3) for trials answered ``none``."""
    def rule(r: dict) -> dict:
        if r["status"] != "none" or not r["ranking"]:
            return r
        top, best = r["ranking"][0]
        if best > CLAIM_THRESHOLD or best <= tau:  # refused at its scatter, or still below τ
            return r
        rivals = [name for name, lnbf in r["ranking"][1:] if best - lnbf < AMBIGUITY_WINDOW]
        return {**r, "status": "ambiguous" if rivals else "identified", "verdict": top, "ambiguous_with": rivals}
    return rule


def score(trials: list[dict], rule: Callable[[dict], dict]) -> dict:
    """False claims, top-1 at SNR ≥ 10 and misses of the trials re-decided by ``rule``."""
    rs = [rule(r) for r in trials]
    eff = [r for r in rs if r["effect"] != "none"]
    strong = [r for r in eff if r["snr_true"] >= 10]
    return {"false_claims": int(sum(_false_claim(r) for r in rs)), "trials": len(rs),
            "top1_snr_ge_10": float(np.mean([r["status"] == "identified"
                                             and _names(r["effect"], r["verdict"], r.get("form_verdict"))
                                             for r in strong])),
            "n_snr_ge_10": len(strong), "miss_rate": float(np.mean([r["status"] == "none" for r in eff]))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("record", type=Path, help="a bench_diagnosis.py result file (a tuning seed's)")
    ap.add_argument("--out", type=Path, default=record.RESULTS / "diagnosis_claim_rules.json")
    args = ap.parse_args()
    trials = json.loads(args.record.read_text())["trials"]
    rules: dict[str, Callable[[dict], dict]] = {"as_run": lambda r: r, "ambiguity_at_scatter": ambiguity_at_scatter}
    rules.update({f"claim_threshold_{round(10 * t)}": claim_threshold(t) for t in CLAIM_THRESHOLDS})
    rules.update({f"held_out_gap_ratio_at_most_{round(100 * x)}": gap_ratio_gate(x) for x in GAP_RATIOS})
    out = {"record": args.record.name, "rules": {name: score(trials, rule) for name, rule in rules.items()},
           "false_claims_as_run": [{"index": r["index"], "effect": r["effect"], "verdict": r["verdict"],
                                    "scatter_scale": r.get("scatter_scale"),
                                    "held_out_gap_ratio": r["held_out_gap_ratio"],
                                    "margin": r["ranking"][0][1] - r["ranking"][1][1], "runner_up": r["ranking"][1][0]}
                                   for r in trials if _false_claim(r)]}
    for name, s in out["rules"].items():
        print(f"{name:28s} false claims {s['false_claims']}/{s['trials']}, top-1 at SNR >= 10 "
              f"{s['top1_snr_ge_10']:.2f} (n = {s['n_snr_ge_10']}), misses {s['miss_rate']:.0%}")
    record.write(args.out.stem, out, load_start=record.load_average(), out=args.out)


if __name__ == "__main__":
    main()

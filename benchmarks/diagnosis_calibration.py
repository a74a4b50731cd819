"""Calibration of the diagnosis's second-effect gates (``bench_diagnosis.py --form-error``).

On a seed the benchmark does not use, single hidden effects (and two pairs with two) are
diagnosed; for every trial whose first verdict is right, the second-effect search is scored
under several relative form errors added to Σ and several minimum shift ratios, and the
rate of spurious second effects (single) and of found second effects (pairs) is printed.
``rcsa.analysis.diagnosis.state.MIN_SECOND_SHIFT_RATIO`` is read from this table.
"""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from tests.analysis.diagnosis import truth

from rcsa.analysis.diagnosis.state import analyse

FORM_ERRORS = (0.0, 0.1, 0.2)
SHIFT_RATIOS = (0.0, 0.1, 0.2, 0.3)
PAIRS = (("holder_tool_joint", "sensor_mass"), ("fluted_section", "joint_damping"))


def _pair_trial(rng: np.random.Generator, pair: tuple[str, str]) -> dict:
    """A request with two hidden effects (FE truth; the pairs of :data:`PAIRS` combine in one FE model)."""
    nz = truth.draw_nuisance(rng, len(truth.STICKOUTS_M))
    pa, pb = truth.draw_effect(rng, pair[0]), truth.draw_effect(rng, pair[1])
    docs = truth.config_documents(truth.base_document(), nz, truth.STICKOUTS_M)
    f = truth.FREQUENCY_HZ
    clean = []
    for d in docs:
        if pair == PAIRS[0]:
            spec = truth._distributed(d, truth.HT_DISTRIBUTED, pa["translational_scale"] * d["_per"]["ht_kt"],
                                      pa["rotational_scale"] * d["_per"]["ht_kr"], d["_per"]["ht_c"])
            side = (pb["mass_kg"] / 4000.0) ** (1 / 3)
            tip = {"mass_kg": pb["mass_kg"], "rotary_inertia_kg_m2": pb["mass_kg"] * side**2 / 6,
                   "distance_from_tip_m": pb["distance_from_tip_m"], "offset_m": 0.0}
            clean.append(truth._solve(d, f, {"holder_tool_distributed": spec, "tip_mass": tip}))
        else:
            dia = d["tool"]["diameter_m"]
            fl = {"area_m2": pa["area_ratio"] * np.pi * dia**2 / 4,
                  "second_moment_m4": pa["inertia_ratio"] * np.pi * dia**4 / 64}
            clean.append(truth._solve(d, f, {"fluted_section": fl},
                                      modify=lambda built, doc, pb=pb: truth._hysteretic_joints(built, doc, pb)))
    measurements = []
    for stickout, h in zip(truth.STICKOUTS_M, clean, strict=True):
        noisy, coherence = truth.measure(h, rng)
        measurements.append({"tool": {"stickout_m": stickout}, "frequency_hz": f.tolist(),
                             "h": {"real": noisy.real.tolist(), "imag": noisy.imag.tolist()},
                             "coherence": coherence.tolist(), "n_averages": truth.N_AVERAGES})
    return {"assembly": truth.base_document(), "measurements": measurements}


def form_error_trial(index: int, hidden: str, seed: int) -> dict | None:
    """The second-effect search of one trial under each form error (calibrates the second-effect gates).

    ``hidden``: one effect, or two joined by ``+`` (:data:`PAIRS`). Only trials whose verdict
    names (one of) the hidden effect(s) count. Per form error: the remainder p-value and
    every second candidate's conditional ln BF, cosine, held-out improvement and shift ratio.
    """
    rng = np.random.default_rng([seed, index])
    pair = tuple(hidden.split("+"))
    request = _pair_trial(rng, pair) if len(pair) == 2 else truth.make_trial(rng, hidden, with_null=False).request
    a = analyse(request)
    d = a.decision
    if d.status != "identified" or d.effect not in pair:
        return None
    first = d.ranking[0]
    p = a.problem
    f1 = a.features_at(first.candidate, first.map)
    shift = f1 - p.base_features
    r = p.measured_features - (f1 + a.disc.mu)
    moved = np.abs(shift) > 3 * a.disc.sd
    out: dict = {"hidden": hidden, "first": d.effect, "relative_remainder":
                 float(np.median(np.abs(r[moved]) / np.abs(shift[moved]))) if moved.any() else None}
    for rho in FORM_ERRORS:
        p_value, cands = a.second_candidates(rho)
        out[f"{rho:g}"] = {"p": p_value, "candidates": [
            {"effect": c.fit.candidate.name, "log_bayes_factor": c.fit.log_bayes_factor, "cosine": c.cosine,
             "held_out_improves": c.held_out_improves, "shift_ratio": c.shift_ratio} for c in cands]}
    return out


def _second(row: dict, rho: float, ratio: float, tau: float = 3.0) -> str | None:
    """The second effect the gates accept for one calibration row (None: none)."""
    res = row[f"{rho:g}"]
    if res["p"] >= 0.05:
        return None
    ok = [c for c in res["candidates"] if c["log_bayes_factor"] > tau and abs(c["cosine"]) < 0.9
          and c["held_out_improves"] and c["shift_ratio"] > ratio]
    return max(ok, key=lambda c: c["log_bayes_factor"])["effect"] if ok else None


def form_error(args: argparse.Namespace) -> None:
    """Calibration of the second-effect gates on seed ``args.seed`` (use one the benchmark does not)."""
    effects = [e for e in truth.EFFECTS if e != "none"]
    plan = [e for _ in range(args.trials_per_class) for e in effects]
    plan += [f"{a}+{b}" for _ in range(args.trials_per_class) for a, b in PAIRS]
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        rows = [r for r in pool.map(form_error_trial, range(len(plan)), plan, [args.seed] * len(plan)) if r]
    single = [r for r in rows if "+" not in r["hidden"]]
    pairs = [r for r in rows if "+" in r["hidden"]]
    print(f"{len(single)} single-effect and {len(pairs)} two-effect trials with a correct first effect "
          f"(seed {args.seed})")
    rel = [r["relative_remainder"] for r in single if r["relative_remainder"] is not None]
    print(f"median relative remainder |r|/|shift| over features moved > 3 sd: {np.median(rel):.3f} "
          f"(quartiles {np.quantile(rel, 0.25):.3f}-{np.quantile(rel, 0.75):.3f})")
    print("form error  shift ratio  spurious 2nd (single)  2nd found (pairs)")
    for rho in FORM_ERRORS:
        for ratio in SHIFT_RATIOS:
            spurious = np.mean([_second(r, rho, ratio) is not None for r in single])
            found = np.mean([_second(r, rho, ratio) in r["hidden"].split("+") and _second(r, rho, ratio) != r["first"]
                             for r in pairs]) if pairs else float("nan")
            print(f"{rho:10.2f}  {ratio:11.2f}  {spurious:21.2f}  {found:17.2f}")
    Path(args.out).with_name("second_effect_calibration.json").write_text(json.dumps(rows, indent=1))


# ---------------------------------------------------------------------------------- the claim rule
#: Scales of Σ at which the claims of the best effects and the best model form are re-weighed.
CLAIM_SCALES = (1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0)
#: Effects (best ranked) whose ln BF is recorded at every scale (ambiguity at a scale).
CLAIM_EFFECTS = 3


def claim_data(a) -> dict:  # type: ignore[no-untyped-def]
    """What an offline claim rule needs of one diagnosis: every candidate's stated fit, and for the
    best :data:`CLAIM_EFFECTS` effects and the best model form their remainder and their ln BF at
    :data:`CLAIM_SCALES`."""
    from rcsa.analysis.diagnosis.attribution import Likelihood, fit_candidate

    p = a.problem
    fits = a.stated_fits
    out: dict = {"fits": [[f.candidate.key, f.candidate.name, bool(f.candidate.model_form), f.log_bayes_factor,
                           f.log_evidence] for f in fits]}
    w = a.like.w
    null = np.sum((a.disc.samples @ w.T) ** 2, axis=1)
    judges = [Likelihood(p.measured_features, a.disc, np.arange(p.base_features.size), a.request.options.likelihood,
                         scale=s) for s in CLAIM_SCALES]
    effects = sorted((f for f in fits if not f.candidate.model_form), key=lambda x: -x.log_bayes_factor)
    forms = sorted((f for f in fits if f.candidate.model_form), key=lambda x: -x.log_bayes_factor)
    for tag, group in (("effects", effects[:CLAIM_EFFECTS]), ("forms", forms[:1])):
        out[tag] = []
        for f in group:
            feats = a.features_at(f.candidate, f.map)
            r = p.measured_features - (feats + a.disc.mu)
            lnbf = [fit_candidate(f.group or f.candidate, a.features_at, j, float(j(p.base_features))
                                  ).log_bayes_factor for j in judges]
            out[tag].append({"key": f.candidate.key, "name": f.candidate.name,
                             "chi2_remainder": float(np.sum((w @ r) ** 2)), "null_median": float(np.median(null)),
                             "p_remainder": a.residual_p_value(feats),
                             "chi2_shift": float(np.sum((w @ (feats - p.base_features)) ** 2)),
                             "scale": a.remainder_scale(feats), "lnbf_at_scale": lnbf})
    out["chi2_base"] = float(np.sum((w @ (p.measured_features - p.base_features - a.disc.mu)) ** 2))
    out["p_base"] = a.residual_p_value(p.base_features)
    return out


def claim_trial(index: int, hidden: str, kind: str, seed: int, tolerance_scale: float = 1.0) -> dict:
    """One tuning trial: ``kind`` a measured spindle's kind (hybrid) or ``matched`` (RA-1, FE truth)."""
    from benchmarks import bench_diagnosis as bench

    if kind == "matched":
        rec = bench.run_trial(index, hidden, seed, tolerance_scale, extra=claim_data)
        rec["kind"] = "matched" if tolerance_scale == 1.0 else f"scatter{tolerance_scale:g}"
        return rec
    return bench.run_hybrid_trial(index, hidden, kind, seed, extra=claim_data)

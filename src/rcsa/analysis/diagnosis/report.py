"""The diagnosis response (``docs/contract.md`` "Diagnosis") and its figure.

Response fields: ``gap`` (``modes`` and ``bands``: each feature and band judged as a z-score
against what tolerances and noise already explain, plus χ², p-value and a sentence),
``verdict`` (``effect``, ``status``, ``ambiguous_with``, held-out confirmation, SNR,
sentence), ``effects`` (the verdict's effects with parameters ± sd, gaps before/after on the
fitted and held-out measurements, and ``corrected_h`` per measurement in request order),
``ranking`` (every candidate, best first, without FRFs), ``not_applicable`` (effects that are
no candidate here, each with its reason: e.g. ``bearings`` on a measured spindle),
``not_observable_at_standstill``, ``held_out``, ``analysis``, ``notes``, ``runtime_s`` and,
for a measured spindle, ``spindle_measurement`` (what was measured, how it was turned into a
receptance, and the uncertainty of it that entered the expected scatter).

The figure (:func:`diagnosis_figure`) is a :class:`matplotlib.figure.Figure` on the Agg
canvas (no pyplot): measured, base and corrected |h| per measurement, and the gap map
(z-scores of every feature) before and after the verdict's effect.
"""

from __future__ import annotations

import re
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rcsa.analysis.diagnosis.attribution import Fit
from rcsa.analysis.diagnosis.candidates import NOT_OBSERVABLE_AT_STANDSTILL, STANDSTILL_SENTENCE
from rcsa.analysis.diagnosis.validation import HeldOut
from rcsa.model.wire import complex_from_wire, complex_to_wire

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from rcsa.analysis.diagnosis.state import Analysis

__all__ = ["build_response", "diagnosis_figure", "gap_map"]

Z_FLAG = 3.0  # |z| above this is flagged in the gap map (docs/diagnosis.md §4.4)
P_GAP = 0.05


def _db_rms(a: Analysis, hs: Sequence[np.ndarray], configs: Sequence[int] | None = None) -> float:
    cs = a.problem.configs if configs is None else [a.problem.configs[i] for i in configs]
    err = np.concatenate([c.db_error(hs[c.index]) for c in cs])
    return float(np.sqrt(np.mean(err**2)))


def gap_map(a: Analysis, model_features: np.ndarray, model_h: Sequence[np.ndarray]) -> dict[str, Any]:
    """Per-measurement, per-mode and per-band gap of the measurements against a model.

    Parameters
    ----------
    a : Analysis
    model_features : numpy.ndarray, shape (nfeat,)
    model_h : list of numpy.ndarray
        Model ``h`` per measurement on its analysis lines.
    """
    p, disc = a.problem, a.disc
    r = p.measured_features - (model_features + disc.mu)
    z = r / disc.sd
    modes: list[dict[str, Any]] = []
    offset = 0
    for c in p.configs:
        m = a.request.measurements[c.index]
        for k, name in enumerate(c.windows.names):
            i = offset + k
            entry: dict[str, Any] = {"measurement": c.index, "label": m.label,
                                     "stickout_m": m.tool.stickout_m}
            if name == "static":
                entry.update(kind="static", feature="compliance",
                             compliance_ratio=float(np.exp(p.measured_features[i] - model_features[i])), z=float(z[i]))
            else:
                what, quantity = name.split(".")
                kind = what.rstrip("0123456789")
                entry.update(kind=kind, mode=int(what[len(kind):]), feature=quantity, z=float(z[i]))
                ratio = float(np.exp(p.measured_features[i] - model_features[i]))
                if quantity == "frequency":
                    entry.update(model_frequency_hz=float(np.exp(model_features[i])),
                                 measured_frequency_hz=float(np.exp(p.measured_features[i])),
                                 shift_pct=float(100 * (ratio - 1)))
                elif quantity == "amplitude":
                    entry.update(peak_ratio=ratio)
                else:
                    entry.update(level_ratio=ratio)
            entry["flagged"] = bool(abs(entry["z"]) > Z_FLAG)
            modes.append(entry)
        offset += c.windows.size
    band_meas = p.band_db([c.h_meas for c in p.configs], model_h)
    mc_mean, mc_sd = disc.band_db.mean(axis=0), disc.band_db.std(axis=0)
    bands = []
    k = 0
    for c in p.configs:
        for j, b in enumerate(c.bands):
            f = c.frequency_hz[b[[0, -1]]]
            zb = float((band_meas[k] - mc_mean[k]) / max(mc_sd[k], 1e-9))
            bands.append({"measurement": c.index, "label": a.request.measurements[c.index].label, "band": j,
                          "start_hz": float(f[0]), "stop_hz": float(f[-1]), "rms_db": float(band_meas[k]),
                          "expected_rms_db": float(mc_mean[k]), "z": zb, "flagged": bool(zb > Z_FLAG)})
            k += 1
    w = a.like.w
    chi2 = float(np.sum((w @ r) ** 2))
    p_value = a.residual_p_value(model_features)
    worst = int(np.argmax(np.abs(z)))
    return {"modes": modes, "bands": bands, "chi2": chi2, "n_features": int(z.size),
            "chi2_per_feature": chi2 / z.size, "p_value": p_value, "significant": bool(p_value < P_GAP),
            "max_abs_z": float(np.abs(z).max()), "worst": modes[worst], "db_rms": _db_rms(a, model_h)}


def _params(fit: Fit) -> dict[str, Any]:
    out = {}
    for prm, x, sd, ab in zip(fit.candidate.parameters, fit.map, fit.sd, fit.at_bound, strict=True):
        out[prm.name] = {"value": float(x), "sd": float(sd), "lo": prm.lo, "hi": prm.hi, "null": prm.null,
                         "unit": prm.unit, "at_bound": ab}
    return out


def _effect(a: Analysis, fit: Fit, ho: HeldOut | None, probs: dict[str, float], with_h: bool,
            first: Fit | None = None) -> dict[str, Any]:
    cands = [first.candidate, fit.candidate] if first else [fit.candidate]
    values = [first.map, fit.map] if first else [fit.map]
    feats = a.features_of(cands, values)
    h_after = a.problem.h(a.knobs_of(cands, values))
    entry: dict[str, Any] = {
        "effect": fit.candidate.name,
        "log_bayes_factor": fit.log_bayes_factor,
        "posterior_probability": None if first is not None else probs.get(fit.candidate.name),
        "parameters": _params(fit),
        "physical": {k: float(v) for k, v in fit.candidate.meaning(fit.map).items()},
        "snr": a.snr(cands, values),
        "gap_before_db": _db_rms(a, [c.h_base for c in a.problem.configs]),
        "gap_after_db": _db_rms(a, h_after),
        "chi2_before": float(a.like.chi2(a.problem.base_features)),
        "chi2_after": float(a.like.chi2(feats)),
        "held_out_gap_before_db": None if ho is None else ho.db_before,
        "held_out_gap_after_db": None if ho is None else ho.db_after,
        "held_out_gap_ratio": None if ho is None else ho.gap_ratio,
        "held_out_chi2_before": None if ho is None else ho.chi2_before,
        "held_out_chi2_after": None if ho is None else ho.chi2_after,
        "confirmed_on_held_out": None if ho is None else ho.confirmed,
        "evidence_method": fit.method,
        "residual_p_value": a.residual_p_value(feats),
    }
    if first is not None:  # a second effect: its ln BF is conditional on the first at its MAP
        entry["given"] = first.candidate.name
    if with_h:
        entry["corrected_h"] = [complex_to_wire(h) for h in a.full_h(cands, values)]
    return entry


def _sentence(a: Analysis, effects: list[dict[str, Any]]) -> str:
    d = a.decision
    tau = a.request.options.claim_threshold
    if d.status == "none":
        best = d.ranking[0] if d.ranking else None
        tail = (f" The best candidate, {best.candidate.name}, reaches ln BF = {best.log_bayes_factor:.1f}"
                f" (a claim needs > {tau:g}).") if best else ""
        p_gap = a.residual_p_value(a.problem.base_features)
        if p_gap < P_GAP:
            return ("The measurements depart from the base model beyond its tolerances and the noise "
                    f"(p = {p_gap:.3f}), but no candidate effect explains the gap: it is left unexplained "
                    "(the gap map says where it lies)." + tail)
        return "No unmodelled effect is needed to explain these measurements." + tail
    e = effects[0]
    held = ""
    if e["confirmed_on_held_out"] is not None:
        verdict = ("confirmed" if e["confirmed_on_held_out"] else
                   "NOT confirmed: the fit may only compensate on the fitted measurements")
        held = (f"; on held-out measurements the gap goes from {e['held_out_gap_before_db']:.2f} dB to "
                f"{e['held_out_gap_after_db']:.2f} dB ({verdict})")
    if d.status == "ambiguous":
        return (f"The gap is explained equally well by {', '.join([d.effect, *d.ambiguous_with])} (ln BF within "
                f"{a.request.options.ambiguity_window:g} of each other); these data cannot tell them apart, so none is "
                f"named alone{held}.")
    bound = [n for n, v in e["parameters"].items() if v["at_bound"]]
    flag = f" Parameter(s) {', '.join(bound)} sit at a prior bound." if bound else ""
    if e["residual_p_value"] < 0.05:
        flag += (f" It does not explain everything: the remainder is still beyond tolerances and noise "
                 f"(p = {e['residual_p_value']:.3f}).")
    if a.scatter_scale > 1.0:
        flag += (f" The remainder scatters {a.scatter_scale:.2g} times more than the stated tolerances and noise "
                 "allow; the claim was weighed with them widened that much.")
    return (f"{d.effect} explains the gap (ln BF = {e['log_bayes_factor']:.1f} against the base model, "
            f"SNR {e['snr']:.1f}){held}.{flag}")


def build_response(a: Analysis) -> dict[str, Any]:
    """The JSON-ready response of a finished :class:`~rcsa.analysis.diagnosis.state.Analysis`."""
    response_started = time.perf_counter()
    d, p = a.decision, a.problem
    log_z = {f.candidate.name: f.log_evidence for f in d.ranking}
    top = max([a.log_z0, *log_z.values()])
    norm_ = np.exp(a.log_z0 - top) + sum(np.exp(v - top) for v in log_z.values())
    probs = {k: float(np.exp(v - top) / norm_) for k, v in log_z.items()}
    reported = a.reported_names()
    effects = [_effect(a, f, a.held.get(f.candidate.name), probs, True) for f in d.ranking
               if f.candidate.name in reported]
    effects.sort(key=lambda e: reported.index(e["effect"]))
    if a.second is not None:
        fit2, ho2, cos = a.second
        e2 = _effect(a, fit2, ho2, probs, True, first=d.ranking[0])
        e2["signature_cosine_with_first"] = cos
        effects.append(e2)
    ranking = [_effect(a, f, a.held.get(f.candidate.name), probs, False) for f in d.ranking]
    gap = gap_map(a, p.base_features, [c.h_base for c in p.configs])
    if gap["significant"]:
        w = gap["worst"]
        gap["summary"] = (f"The measurements depart from the base model by more than tolerances and noise explain "
                          f"(chi2/n = {gap['chi2_per_feature']:.1f}, p = {gap['p_value']:.3f}); the largest "
                          f"departure is {w['kind']} {w.get('mode', '')} {w['feature']} of '{w['label']}' "
                          f"(z = {w['z']:.1f}).")
    else:
        gap["summary"] = (f"The measurements agree with the base model within its tolerances and the measurement "
                          f"noise (chi2/n = {gap['chi2_per_feature']:.1f}, p = {gap['p_value']:.2f}).")
    first = effects[0] if effects else None
    rivals = a.collinear_rivals()
    fold_kind = ("requested" if a.request.options.held_out is not None else
                 "alternate_stickouts" if len(p.configs) >= 4 else
                 "leave_one_out" if len(p.configs) >= 2 else "none")
    notes = list(a.notes)
    if fold_kind == "none":
        notes.append("Only one measurement: nothing can be held out, so no claim is confirmed on unseen data.")
    if any(m.coherence is None for m in a.request.measurements):
        notes.append("A measurement without coherence was given 1 % relative noise per line.")
    spindle: dict[str, Any] = {}
    if p.measured is not None:
        report = {k: v for k, v in p.measured.report.items() if k != "condition_number"}
        spindle = {"spindle_measurement": {**report, "notes": list(p.measured.notes),
                                           "uncertainty_in_expected_scatter": p.spindle_uncertainty()}}
        notes.append("The spindle is measured: its own uncertainty (see spindle_measurement) is part of the expected "
                     "scatter, so a gap it already explains is not blamed on an effect.")
    return {
        "gap": gap,
        "verdict": {"effect": d.effect, "status": d.status, "ambiguous_with": list(d.ambiguous_with),
                    "log_bayes_factor": first["log_bayes_factor"] if first else
                    (d.ranking[0].log_bayes_factor if d.ranking else None),
                    "snr": first["snr"] if first else None,
                    "confirmed_on_held_out": first["confirmed_on_held_out"] if first else None,
                    "collinear_rivals": rivals,
                    "residual_p_value": first["residual_p_value"] if first else gap["p_value"],
                    "sentence": _sentence(a, effects) + (
                        f" {', '.join(str(r['effect']) for r in rivals)} move(s) the features the same way "
                        f"(signature cosine > 0.9) and the best fit leaves a significant remainder: "
                        f"treat the mechanism as uncertain between them." if rivals else "")},
        "effects": effects,
        "ranking": ranking,
        "not_applicable": [{"effect": e, "reason": reason} for e, (reason, _) in a.not_applicable.items()],
        "not_observable_at_standstill": list(NOT_OBSERVABLE_AT_STANDSTILL),
        "not_observable_sentence": STANDSTILL_SENTENCE,
        "held_out": {"method": fold_kind, "folds": [{"fit": tr, "held_out": te} for tr, te in a.folds]},
        "analysis": {"lines": [int(c.lines.size) for c in p.configs],
                     "band_hz": [[float(c.frequency_hz[0]), float(c.frequency_hz[-1])] for c in p.configs],
                     "n_features": int(p.base_features.size),
                     "monte_carlo_draws": a.request.options.monte_carlo_draws,
                     "likelihood": a.request.options.likelihood,
                     "claim_threshold": a.request.options.claim_threshold,
                     "ambiguity_window": a.request.options.ambiguity_window,
                     "tolerances": dict(a.request.tolerances),
                     "log_evidence_base": a.log_z0,
                     "scatter_scale": a.scatter_scale,
                     "timings_s": {**a.timings_s, "response": time.perf_counter() - response_started}},
        "notes": notes,
        **spindle,
        "runtime_s": time.perf_counter() - a.started,  # analysis and this response
    }


def _z_matrix(a: Analysis, model_features: np.ndarray) -> tuple[np.ndarray, list[str]]:
    p = a.problem
    z = (p.measured_features - model_features - a.disc.mu) / a.disc.sd
    names = list(dict.fromkeys(n for c in p.configs for n in c.windows.names))
    out = np.full((len(p.configs), len(names)), np.nan)
    k = 0
    for c in p.configs:
        for n in c.windows.names:
            out[c.index, names.index(n)] = z[k]
            k += 1
    return out, names


#: What the columns of the gap map are (drawn under it).
GAP_MAP_KEY = ("Gap-map columns, window k counted from low to high frequency: peak k f / |h| = frequency / height "
               "of its resonance; anti k f = the antiresonance after it; band k = the window's level; static = "
               "quasi-static compliance; white = that measurement has no such feature. z = departure from the base "
               "model in standard deviations of what tolerances and noise already explain.")


def gap_map_label(feature: str) -> str:
    """The gap map's column label of a feature name (``peak0.frequency`` → ``peak 1 f``).

    Examples
    --------
    >>> [gap_map_label(s) for s in ("static", "peak0.frequency", "peak0.amplitude", "antiresonance1.frequency",
    ...                             "band2.level")]
    ['static', 'peak 1 f', 'peak 1 |h|', 'anti 2 f', 'band 3']
    """
    m = re.fullmatch(r"(peak|antiresonance|band)(\d+)\.(frequency|amplitude|level)", feature)
    if m is None:
        return feature
    kind = {"peak": "peak", "antiresonance": "anti", "band": "band"}[m.group(1)]
    what = {"frequency": " f", "amplitude": " |h|", "level": ""}[m.group(3)]
    return f"{kind} {int(m.group(2)) + 1}{what}"


def diagnosis_figure(a: Analysis, response: dict[str, Any] | None = None) -> Figure:
    """Measured, base and corrected FRFs per measurement, and the gap map before/after.

    Parameters
    ----------
    a : Analysis
    response : dict, optional
        The response of ``a`` (its first effect is drawn as "corrected").
    """
    # matplotlib (~0.3 s to import): only when a figure is drawn, not for every diagnosis
    from matplotlib.colors import TwoSlopeNorm

    from rcsa.analysis.figures import freeze_layout, log_frequency_ticks, new_figure

    response = build_response(a) if response is None else response
    p = a.problem
    n = len(p.configs)
    cols = 2 if n > 1 else 1
    rows = (n + cols - 1) // cols
    fig = new_figure(5.2 * cols, 2.3 * rows + 3.1)
    grid = fig.add_gridspec(rows + 2, cols, height_ratios=[1.0] * rows + [1.2, 0.32])
    effects = response["effects"]
    corrected = None
    if effects:
        e = effects[0]
        corrected = [complex_from_wire(h, f"effects[0].corrected_h[{i}]", finite=False)
                     for i, h in enumerate(e["corrected_h"])]
    base_full = a.full_h([], [])
    for i, m in enumerate(a.request.measurements):
        ax = fig.add_subplot(grid[i // cols, i % cols])
        # the measurement as a wide light band under the thin model lines: visible where they match
        ax.loglog(m.frequency_hz, np.abs(m.h) * 1e6, color="0.2", alpha=0.3, lw=3.2, label="measured",
                  solid_capstyle="butt", zorder=1)
        ax.loglog(m.frequency_hz, np.abs(base_full[i]) * 1e6, "--", color="tab:blue", lw=1.0, label="base model",
                  zorder=2)
        if corrected is not None:
            ax.loglog(m.frequency_hz, np.abs(corrected[i]) * 1e6, color="tab:red", lw=0.9,
                      label=f"+ {effects[0]['effect']}", zorder=3)
        log_frequency_ticks(ax, float(m.frequency_hz[0]), float(m.frequency_hz[-1]))
        ax.set_title(f"measurement {m.label} (stickout {m.tool.stickout_m * 1e3:.1f} mm)", fontsize=9)
        ax.set_ylabel("|h| [µm/N]", fontsize=8)
        ax.tick_params(labelsize=7)
        if i == 0:
            ax.legend(fontsize=7, loc="lower left")
        if i // cols == rows - 1 or (i + cols >= n):
            ax.set_xlabel("frequency [Hz]", fontsize=8)
    zb, names = _z_matrix(a, p.base_features)
    panels = [("gap map: base model", zb)]
    if effects:
        first = a.decision.ranking[0]
        za, _ = _z_matrix(a, a.features_at(first.candidate, first.map))
        panels.append((f"after {first.candidate.name}", za))
    sub = grid[rows, :].subgridspec(1, len(panels))
    lim = 8.0
    for k, (title, zz) in enumerate(panels):
        ax = fig.add_subplot(sub[0, k])
        im = ax.imshow(np.clip(zz, -lim, lim), cmap="RdBu_r", norm=TwoSlopeNorm(0.0, -lim, lim), aspect="auto")
        ax.set_xticks(range(len(names)), [gap_map_label(s) for s in names], rotation=60, fontsize=6)
        ax.set_yticks(range(n), [a.request.measurements[c.index].label for c in p.configs], fontsize=7)
        ax.set_title(f"{title} (z, |z| > {Z_FLAG:g} flagged)", fontsize=8)
        for (r_, c_), v in np.ndenumerate(zz):
            if np.isfinite(v) and abs(v) > Z_FLAG:
                ax.text(c_, r_, f"{v:.0f}", ha="center", va="center", fontsize=6)
        if k == len(panels) - 1:
            fig.colorbar(im, ax=ax, shrink=0.8, label="z")
    key = fig.add_subplot(grid[rows + 1, :])
    key.axis("off")
    key.text(0.0, 0.5, GAP_MAP_KEY, fontsize=7, va="center", ha="left", transform=key.transAxes, wrap=True)
    v = response["verdict"]
    fig.suptitle(f"verdict: {v['effect']} ({v['status']})", fontsize=10)
    return freeze_layout(fig)

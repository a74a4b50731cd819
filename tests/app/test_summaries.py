"""The short tables the CLI shows: each number is the result's own, in the shop floor's units."""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.analysis.lobes.pockets import PocketRule, best_pocket
from rcsa.app.analyses import stability_lobes_answer
from rcsa.app.predictions import predict
from rcsa.app.summaries import (
    MAX_ROWS,
    batch_summary,
    diagnosis_summary,
    lobes_summary,
    prediction_summary,
    unsettled_speeds,
)
from rcsa.reference import ra1

GRID = {"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 5.0}


def _rows(table):
    return {row[0]: row[1:] for row in table.rows}


def test_prediction_summary_is_the_result():
    result = predict(ra1(GRID))
    modes, tool_point = prediction_summary(result)
    freqs = result.natural_frequencies_hz
    assert [float(r[1]) for r in modes.rows] == pytest.approx(freqs[:MAX_ROWS], rel=5e-5)  # 5 digits shown
    assert "exact" in modes.title
    rows = _rows(tool_point)
    assert float(rows["static stiffness"][0].split()[0]) == pytest.approx(result.static_stiffness_n_m / 1e6, rel=5e-4)
    value, at = rows["most negative real part of h"][0].split(" µm/N at ")
    assert float(value) == pytest.approx(result.min_real_m_n * 1e6, rel=5e-4)
    assert float(at.split()[0]) == pytest.approx(result.min_real_frequency_hz, rel=5e-5)
    top = max(result.peaks, key=lambda p: p["magnitude_m_n"])
    assert rows["largest peak of |h|"][0].startswith(f"{top['magnitude_m_n'] * 1e6:.4g} µm/N")


def test_a_long_mode_list_is_cut_and_says_so():
    result = {"natural_frequencies_hz": list(np.arange(1.0, 31.0) * 100.0), "natural_frequencies_method": "modal_fit",
              "natural_frequencies_sd_hz": [1.0] * 30, "static_stiffness_n_m": None, "min_real_m_n": -1e-6,
              "min_real_frequency_hz": 700.0, "peaks": [], "notes": ["a note"], "frequency_hz": [1.0, 2.0]}
    modes, tool_point = prediction_summary(result)
    assert len(modes.rows) == MAX_ROWS and "18 more" in modes.caption
    assert modes.columns[-1] == "± sd (Hz)" and "modal-fit" in modes.title
    assert _rows(tool_point)["static stiffness"] == ("not given (measured spindle)",)
    assert tool_point.caption == "a note"


def test_batch_summary_one_row_per_combination():
    result = {"results": [
        {"id": "a", "status": "ok", "natural_frequencies_hz": [600.0], "static_stiffness_n_m": 2.5e6,
         "min_real_m_n": -3e-6, "min_real_frequency_hz": 1400.0},
        {"id": "b", "status": "error", "error": {"field": "tool.stickout_m", "detail": "must be > 0"}},
    ], "summary": {"ok": 1, "error": 1}}
    (table,) = batch_summary(result)
    assert table.rows[0] == ("a", "ok", "600 Hz", "2.5 N/µm", "-3 at 1400 Hz")
    assert table.rows[1][:3] == ("b", "error", "must be > 0")
    assert table.caption == "1 ok, 1 with an error"


def test_diagnosis_summary_says_verdict_and_shrink():
    response = {
        "gap": {"db_rms": 9.8, "chi2_per_feature": 10.5, "p_value": 0.0099},
        "verdict": {"effect": "holder_tool_joint", "status": "identified", "sentence": "it explains the gap"},
        "effects": [{"effect": "holder_tool_joint", "log_bayes_factor": 36.5, "snr": 16.6,
                     "confirmed_on_held_out": True, "gap_before_db": 9.82, "gap_after_db": 0.199,
                     "held_out_gap_before_db": 9.82, "held_out_gap_after_db": 0.198, "held_out_gap_ratio": 0.043,
                     "physical": {"holder_tool.stiffness_n_m": 5.758e6}}],
        "ranking": [{"effect": "holder_tool_joint", "log_bayes_factor": 36.5, "posterior_probability": 1.0,
                     "held_out_gap_ratio": 0.043},
                    {"effect": "fluted_section", "log_bayes_factor": 4.1, "posterior_probability": 8.9e-15}],
    }
    verdict, fitted, ranking = diagnosis_summary(response)
    rows = _rows(verdict)
    assert rows["verdict"] == ("holder_tool_joint (identified)",)
    assert rows["shrink"] == ("9.82 → 0.199 dB rms",)
    assert rows["shrink on held-out"] == ("9.82 → 0.198 dB rms (ratio 0.043)",)
    assert verdict.caption == "it explains the gap"
    assert fitted.rows == (("holder_tool.stiffness_n_m", "5.758e+06"),)
    assert [r[0] for r in ranking.rows] == ["holder_tool_joint", "fluted_section"]
    assert ranking.rows[1][3] == "—"  # no held-out ratio: said, not invented


def test_diagnosis_summary_names_a_proposed_model_form_and_the_calibrated_model():
    """A model form as the verdict reads ``clamping_model → bonded``; the calibrated model's gap and
    its most moved nuisance parameter are shown; the model-form candidates get their own table."""
    response = {
        "gap": {"db_rms": 3.1, "chi2_per_feature": 12.0, "p_value": 0.005},
        "verdict": {"effect": "clamping_model", "status": "identified", "sentence": "switch to bonded"},
        "effects": [{"effect": "clamping_model", "proposed_model": "bonded", "log_bayes_factor": 14.2, "snr": 9.0,
                     "confirmed_on_held_out": True, "gap_before_db": 3.2, "gap_after_db": 0.25}],
        "ranking": [{"effect": "clamping_model", "log_bayes_factor": 14.2}],
        "model_form": {"base_model": "point", "sentence": "Proposed: switching ...",
                       "candidates": [{"candidate": "clamping_model", "proposed_model": "bonded",
                                       "log_bayes_factor": 14.2, "log_evidence_over_best_effect": 8.1}],
                       "proposed": {"candidate": "clamping_model", "model": "bonded"}},
        "calibrated": {"effects": ["clamping_model"], "h": [], "gap_db": 0.21,
                       "parameters_moved_sd": {"bearing_stiffness_scale": 0.4, "tool_youngs_scale": -1.6}},
    }
    tables = diagnosis_summary(response)
    assert [t.title for t in tables] == ["Diagnosis", "Candidates, best first", "Model form (base: point)"]
    rows = _rows(tables[0])
    assert rows["verdict"] == ("clamping_model → bonded (identified)",)
    assert rows["calibrated model"] == ("0.21 dB rms (clamping_model; tolerances where the data put them, most "
                                        "moved: tool_youngs_scale -1.6 σ)",)
    assert tables[2].rows == (("clamping_model → bonded", "14.2", "8.1"),)
    assert tables[2].caption == "Proposed: switching ..."


def test_diagnosis_summary_without_a_claim():
    response = {"gap": {"db_rms": 0.4, "chi2_per_feature": 0.9, "p_value": 0.6, "summary": "no gap"},
                "verdict": {"effect": "none", "status": "none"}, "effects": [], "ranking": []}
    tables = diagnosis_summary(response)
    assert [t.title for t in tables] == ["Diagnosis", "Candidates, best first"]
    assert "shrink" not in _rows(tables[0]) and tables[0].caption == "no gap"


@pytest.fixture(scope="module")
def lobes_result():
    request = {"assembly": ra1({"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 1.0}), "teeth": 4,
               "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
               "milling": "down", "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 1500},
               "method": "zoa"}  # the summary's reading of a diagram, on the quick method
    return stability_lobes_answer(request).to_dict()


def test_lobes_summary_limit_and_pockets(lobes_result):
    limits, pockets = lobes_summary(lobes_result)
    rows = _rows(limits)
    assert rows["absolute limit"][0].startswith(f"{lobes_result['min_depth_limit_m'] * 1e3:.3g} mm")
    assert rows["method"] == ("zero-order (Altintas–Budak)",)
    # the first pocket is the pocket rule's own best pocket of the whole diagram
    speed = np.asarray(lobes_result["spindle_speed_rpm"])
    best = best_pocket(speed, np.asarray(lobes_result["depth_limit_m"], dtype=float), min_rpm=speed[0],
                       max_rpm=speed[-1], rule=PocketRule(max_depth_m=lobes_result["flute_length_m"]))
    assert pockets.rows[0][1] == f"{best.spindle_speed_rpm:.0f}"
    assert 1 <= len(pockets.rows) <= 3
    # each later pocket lies outside the ones before it and is no better
    spans = [tuple(float(x) for x in r[4].split("–")) for r in pockets.rows]
    stepdowns = [float(r[2]) for r in pockets.rows]
    for i in range(1, len(spans)):
        assert all(not (lo <= float(pockets.rows[i][1]) <= hi) for lo, hi in spans[:i])
    removal = [float(r[1]) * s for r, s in zip(pockets.rows, stepdowns, strict=True)]
    assert removal == sorted(removal, reverse=True)


def test_lobes_response_carries_its_conditions(lobes_result):
    assert lobes_result["conditions"] == {"teeth": 4, "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3,
                                          "radial_immersion": 0.5, "milling": "down", "method": "zoa",
                                          "frf": "assembly"}


def test_unsettled_speeds_finds_the_chords_of_a_coarse_lobe():
    """A smooth limit, drawn straight between sparse points above 20 000 rpm (as a lobe through a
    coarse FRF grid is): only the speeds on chords longer than 3 % of the speed are flagged."""
    speed = np.linspace(5000.0, 30000.0, 1001)
    smooth = 1e-3 * (1.5 + np.sin(speed / 900.0))
    sparse = speed[speed >= 20000.0][::40]  # chords of 1 000 rpm (≥ 3.3 % of the speed)
    depth = np.where(speed >= 20000.0, np.interp(speed, sparse, 1e-3 * (1.5 + np.sin(sparse / 900.0))), smooth)
    flags = unsettled_speeds({"spindle_speed_rpm": speed.tolist(), "depth_limit_m": depth.tolist()})
    coarse = flags["coarse grid"]
    assert not coarse[speed < 19990.0].any()
    assert coarse[(speed > 20000.0) & (speed < sparse[-1])].all()
    dense = np.interp(speed, speed[::3], smooth[::3])  # chords of 3 steps: 75 rpm, < 3 % everywhere
    assert "coarse grid" not in unsettled_speeds({"spindle_speed_rpm": speed.tolist(),
                                                  "depth_limit_m": dense.tolist()})


def test_unsettled_speeds_reads_the_sdm_flags():
    speed = [1000.0, 2000.0, 3000.0, 4000.0]
    flags = unsettled_speeds({"spindle_speed_rpm": speed, "depth_limit_m": [1.0, 2.0, 1.5, 3.0],
                              "steps_per_chatter_cycle": [4.0, 12.0, None, 9.0],
                              "resolved": [True, False, True, True]})
    assert "under-resolved" not in flags  # the per-speed check is the better evidence
    assert flags["unresolved"].tolist() == [False, True, False, False]
    old = unsettled_speeds({"spindle_speed_rpm": speed, "depth_limit_m": [1.0, 2.0, 1.5, 3.0],
                            "steps_per_chatter_cycle": [4.0, 12.0, None, 9.0]})
    assert old["under-resolved"].tolist() == [True, False, False, False]
    assert unsettled_speeds({"spindle_speed_rpm": speed, "resolved": [True] * 4}) == {}


def test_the_chord_limit_is_the_pocket_rules_speed_tolerance():
    from rcsa.analysis.lobes.pockets import DEFAULT_SPEED_TOLERANCE
    from rcsa.app.summaries import MAX_CHORD

    assert MAX_CHORD == DEFAULT_SPEED_TOLERANCE

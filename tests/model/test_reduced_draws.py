"""The reduced model of an uncertainty band against the full draws.

Oracle: the same request with ``"solver": "exact"`` — every draw solved on every line (itself
checked against a plain loop of predictions in ``tests/model/test_uncertainty.py``). The band's
measure is pointwise: the relative error of p05, p50 and p95 of |h| at every line (the dB
error of a band drawn in dB, 2 % ≈ 0.17 dB), and the relative error of each natural
frequency's mean and sd. The issue's target is 2 %; the reduced model measured here stays
below 1 % (``benchmarks/bench_uncertainty.py`` prints it at 2 000 lines and 200 draws).
"""

from __future__ import annotations

import numpy as np
import pytest

import rcsa
from rcsa.measured.store import Measurement, MeasurementMeta, MeasurementStore
from rcsa.model import reduced_draws as reduced_module
from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.model.draw_chains import drawn_chains
from rcsa.model.reduced_draws import antiresonances, frequency_ratio_bounds
from rcsa.model.tolerances import DEFAULT_TOLERANCES, draw_nuisance
from rcsa.physics.elimination import tip_receptance
from rcsa.physics.natural_frequencies import natural_frequencies_batch
from rcsa.reference import ra1
from tests.helpers import RTOL_ALGEBRA

GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}   # 1 000 lines, every RA-1 mode in the band
DRAWS, SEED = 60, 3
#: The issue's target for the band's quantiles and the natural frequencies' mean and sd.
TARGET = 0.02


def band_error(reduced: dict, exact: dict) -> float:
    """Largest pointwise relative error of p05, p50, p95 of |h| over the band."""
    a = np.array([reduced["h_magnitude_m_n"][k] for k in ("p05", "p50", "p95")])
    b = np.array([exact["h_magnitude_m_n"][k] for k in ("p05", "p50", "p95")])
    return float(np.max(np.abs(a / b - 1.0)))


def mode_errors(reduced: dict, exact: dict) -> tuple[float, float]:
    a, b = reduced["natural_frequencies_hz"], exact["natural_frequencies_hz"]
    return (float(np.max(np.abs(np.array(a["mean"]) / b["mean"] - 1.0))),
            float(np.max(np.abs(np.array(a["sd"]) / b["sd"] - 1.0))))


def both(doc: dict, option: dict, **kwargs) -> tuple[dict, dict]:
    reduced = rcsa.predict({**doc, "uncertainty": option}, **kwargs)
    exact = rcsa.predict({**doc, "uncertainty": {**option, "solver": "exact"}}, **kwargs)
    return reduced["uncertainty"], exact["uncertainty"]


@pytest.fixture(scope="module")
def ra1_bands():
    return both(ra1(GRID), {"draws": DRAWS, "seed": SEED})


def test_ra1_band_and_natural_frequencies_agree_with_the_full_draws(ra1_bands):
    reduced, exact = ra1_bands
    assert band_error(reduced, exact) < TARGET / 2
    mean, sd = mode_errors(reduced, exact)
    assert mean < 1e-3 and sd < TARGET
    assert reduced["draws"] == DRAWS
    np.testing.assert_array_equal(reduced["natural_frequencies_hz"]["in_band_fraction"],
                                  exact["natural_frequencies_hz"]["in_band_fraction"])


def test_the_result_says_how_the_draws_were_solved(ra1_bands):
    reduced, exact = ra1_bands
    model = reduced["reduced_model"]
    assert reduced["solver"] == "reduced" and exact["solver"] == "exact" and "reduced_model" not in exact
    assert 20 < model["lines_per_draw_mean"] < 0.2 * 1000          # a few per cent of the lines
    assert model["max_check_error"] <= model["check_tolerance"] or model["draws_solved_on_every_line"] > 0
    assert any("reduced model of the draws" in n for n in reduced["notes"])
    assert "exact in" in reduced["natural_frequencies_matching"]


def test_a_library_of_tools_on_one_spindle():
    """Three tools of a batch, each with its band: the reduced band of each agrees with its full draws."""
    doc = ra1(GRID)
    tool = doc["tool"]
    combos = [{"id": "74", "holder": doc["holder"], "tool": tool, "joints": doc["joints"]},
              {"id": "60", "holder": doc["holder"], "tool": {**tool, "stickout_m": 0.060}, "joints": doc["joints"]},
              {"id": "d10", "holder": doc["holder"], "joints": doc["joints"],
               "tool": {**tool, "diameter_m": 0.010, "stickout_m": 0.065}}]
    request = {"spindle": doc["spindle"], "frequency": doc["frequency"], "combinations": combos}
    option = {"draws": 40, "seed": 9}
    reduced = rcsa.predict_batch({**request, "uncertainty": option})["results"]
    exact = rcsa.predict_batch({**request, "uncertainty": {**option, "solver": "exact"}})["results"]
    for r, e in zip(reduced, exact, strict=True):
        assert r["status"] == e["status"] == "ok", r.get("error")
        assert band_error(r["uncertainty"], e["uncertainty"]) < TARGET / 2, r["id"]
        assert mode_errors(r["uncertainty"], e["uncertainty"])[1] < TARGET, r["id"]


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """RA-1's modelled spindle stored as a direct FRF (rotations estimated)."""
    store = MeasurementStore(tmp_path_factory.mktemp("store"))
    spec = parse_assembly(ra1(GRID))
    s = tip_receptance(build_model(spec).spindle, 2 * np.pi * spec.frequency_hz)
    ident = store.put(Measurement(spec.frequency_hz, {"h": s[:, 0, 0]},
                                  MeasurementMeta("ra1", "x", "spindle_nose", "direct_frf")))
    return store, ident


def test_a_measured_spindle_whose_draws_are_smooth(store):
    """A direct FRF without noise: its rotation estimate is drawn (one length per draw), so each
    draw's base is smooth in frequency and the reduced model applies."""
    st, ident = store
    doc = {**ra1(GRID), "spindle": {"measurement_id": ident}}
    reduced, exact = both(doc, {"draws": DRAWS, "seed": SEED, "tolerances": {"spindle_noise_rel": 0.0}}, store=st)
    assert "reduced_model" in reduced
    assert band_error(reduced, exact) < TARGET / 2
    mean, sd = mode_errors(reduced, exact)
    assert mean < 1e-3 and sd < TARGET


def test_a_measured_spindle_drawn_with_noise_on_every_line_is_solved_exactly(store):
    st, ident = store
    doc = {**ra1(GRID), "spindle": {"measurement_id": ident}}
    reduced, exact = both(doc, {"draws": 8, "seed": SEED}, store=st)
    assert "reduced_model" not in reduced and any("noise on every line" in n for n in reduced["notes"])
    for k in ("p05", "p50", "p95"):
        np.testing.assert_allclose(reduced["h_magnitude_m_n"][k], exact["h_magnitude_m_n"][k], rtol=RTOL_ALGEBRA)


def test_draws_failing_their_check_are_solved_on_every_line(monkeypatch):
    monkeypatch.setattr(reduced_module, "CHECK_TOLERANCE", 0.0)
    option = {"draws": 6, "seed": 1}
    reduced, exact = both(ra1({"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 25.0}), option)
    assert reduced["reduced_model"]["draws_solved_on_every_line"] == 6
    for k in ("p05", "p50", "p95"):
        np.testing.assert_allclose(reduced["h_magnitude_m_n"][k], exact["h_magnitude_m_n"][k], rtol=RTOL_ALGEBRA)


def test_every_drawn_natural_frequency_lies_within_its_min_max_bound():
    """Min–max theorem: stiffnesses scaled within [a, b] and masses within [c, d] keep every
    ω² within [a/d, b/c] of the nominal one (stickout fixed: the bound is then rigorous)."""
    spec = parse_assembly(ra1({"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 100.0}))
    knobs = draw_nuisance(np.random.default_rng(2), {**DEFAULT_TOLERANCES, "stickout_m": 0.0,
                                                     "holder_tool_stiffness_log": 0.5}, 12)
    low, high = frequency_ratio_bounds(knobs, spec.tool.stickout_m)
    drawn = drawn_chains(spec, knobs)
    nominal = rcsa.predict(ra1({"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 100.0})).natural_frequencies_hz
    found = natural_frequencies_batch((), [drawn.chain(d) for d in range(12)], 100.0, 5000.0)
    for d in range(12):
        assert found[d].size == nominal.size
        ratio = found[d] / nominal
        assert np.all(ratio >= low[d] * (1 - 1e-9)) and np.all(ratio <= high[d] * (1 + 1e-9))


def test_antiresonances_are_the_dips_of_the_modulus():
    """h = (ω − z)/(ω − p): the dip lies at Re z with half-width Im z."""
    w = np.linspace(50.0, 150.0, 2001)
    z, p = 80.0 + 0.5j, 120.0 + 1.0j
    found = antiresonances(w, (w - z) / (w - p))
    np.testing.assert_allclose(found.real, [80.0], atol=0.05)
    np.testing.assert_allclose(found.imag, [0.5], rtol=0.05)

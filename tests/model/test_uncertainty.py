"""Uncertainty bands on predictions: the exact vectorised draws against a plain loop of predictions.

The band of ``"uncertainty": {..., "solver": "exact"}`` is computed with every draw stacked into
one chain (:mod:`rcsa.model.draws`); the oracle here draws the same knobs from the same seed
and predicts each drawn assembly on its own with ``rcsa.predict``. The default solver, the
reduced model, is checked against the exact one in ``tests/model/test_reduced_draws.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

import rcsa
from rcsa.errors import InputError
from rcsa.model.bounds import MAX_UNCERTAINTY_DRAW_LINES, MAX_UNCERTAINTY_DRAWS
from rcsa.model.tolerances import DEFAULT_TOLERANCES, draw_nuisance, perturbed_spec
from rcsa.model.uncertainty import parse_prediction_request
from rcsa.reference import ra1
from tests.helpers import RTOL_ALGEBRA

GRID = {"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 25.0}  # 197 lines, every RA-1 mode inside
DRAWS, SEED = 16, 7


@pytest.fixture(scope="module")
def banded():
    doc = {**ra1(GRID), "uncertainty": {"draws": DRAWS, "seed": SEED, "solver": "exact"}}
    return doc, rcsa.predict(doc)


@pytest.fixture(scope="module")
def loop(banded):
    """The oracle: the same knobs, drawn from the same seed, each assembly predicted on its own."""
    spec, options = parse_prediction_request(banded[0])
    knobs = draw_nuisance(np.random.default_rng(SEED), options.tolerances, DRAWS)
    return [rcsa.predict(perturbed_spec(spec, knobs.fields(d))) for d in range(DRAWS)]


def test_the_band_equals_a_plain_loop_of_predictions_with_the_same_seed(banded, loop):
    band = banded[1]["uncertainty"]["h_magnitude_m_n"]
    expected = np.percentile(np.abs([p.tool_point.h for p in loop]), [5.0, 50.0, 95.0], axis=0)
    for name, row in zip(("p05", "p50", "p95"), expected, strict=True):
        np.testing.assert_allclose(band[name], row, rtol=RTOL_ALGEBRA, err_msg=name)


def test_natural_frequencies_are_those_of_the_loop_matched_by_order(banded, loop):
    result = banded[1]
    modes = np.array([p.natural_frequencies_hz for p in loop])  # every draw keeps RA-1's 7 modes in band
    stats = result["uncertainty"]["natural_frequencies_hz"]
    assert len(stats["mean"]) == len(result["natural_frequencies_hz"]) == modes.shape[1]
    np.testing.assert_allclose(stats["mean"], modes.mean(axis=0), rtol=1e-9)
    np.testing.assert_allclose(stats["sd"], modes.std(axis=0, ddof=1), rtol=1e-6)
    assert stats["in_band_fraction"] == [1.0] * modes.shape[1]
    assert 0.001 < min(np.array(stats["sd"]) / stats["mean"]) < 0.1  # tolerances move every mode a little


def test_the_percentiles_are_ordered_and_the_result_says_what_was_drawn(banded):
    result = banded[1].to_dict()
    u = result["uncertainty"]
    p05, p50, p95 = (np.array(u["h_magnitude_m_n"][k]) for k in ("p05", "p50", "p95"))
    assert p05.size == len(result["frequency_hz"])
    assert np.all(p05 <= p50) and np.all(p50 <= p95) and np.any(p05 < p95)
    assert (u["draws"], u["seed"], u["solver"]) == (DRAWS, SEED, "exact")
    assert u["tolerances"] == dict(DEFAULT_TOLERANCES)
    assert "reduced_model" not in u
    assert "by order" in u["natural_frequencies_matching"]


def test_zero_tolerances_give_a_band_of_zero_width_on_the_nominal():
    zero = dict.fromkeys(DEFAULT_TOLERANCES, 0.0)
    result = rcsa.predict({**ra1(GRID), "uncertainty": {"draws": 3, "tolerances": zero}})
    u = result["uncertainty"]
    nominal = np.abs(result.tool_point.h)
    for name in ("p05", "p50", "p95"):
        np.testing.assert_allclose(u["h_magnitude_m_n"][name], nominal, rtol=RTOL_ALGEBRA)
    np.testing.assert_allclose(u["h_magnitude_m_n"]["p05"], u["h_magnitude_m_n"]["p95"], rtol=1e-12)
    assert u["natural_frequencies_hz"]["sd"] == [0.0] * len(result["natural_frequencies_hz"])
    np.testing.assert_allclose(u["natural_frequencies_hz"]["mean"], result["natural_frequencies_hz"], rtol=1e-9)


def test_without_the_option_the_result_is_unchanged():
    plain = rcsa.predict(ra1(GRID))
    assert plain.uncertainty is None and "uncertainty" not in plain


@pytest.mark.parametrize(("option", "field", "words"), [
    ({"draws": 1}, "uncertainty.draws", "between 2 and"),
    ({"draws": MAX_UNCERTAINTY_DRAWS + 1}, "uncertainty.draws", f"and {MAX_UNCERTAINTY_DRAWS}"),
    ({"draws": 2.5}, "uncertainty.draws", "integer"),
    ({"seed": -1}, "uncertainty.seed", "between 0 and"),
    ({"samples": 3}, "uncertainty.samples", "unknown"),
    ({"solver": "fast"}, "uncertainty.solver", "one of"),
    ({"tolerances": {"youngs": 0.1}}, "uncertainty.tolerances.youngs", "unknown"),
    ({"tolerances": {"stickout_m": 0.5}}, "uncertainty.tolerances.stickout_m", "<= 0.05"),
    ({"tolerances": {"loss_factor_log": -0.1}}, "uncertainty.tolerances.loss_factor_log", ">= 0"),
    ({"tolerances": {"spindle_noise_rel": 0.01}}, "uncertainty.tolerances.spindle_noise_rel", "unknown"),
    ("many", "uncertainty", "object"),
])
def test_a_bad_option_is_refused_naming_its_field(option, field, words):
    with pytest.raises(InputError) as info:
        rcsa.predict({**ra1(GRID), "uncertainty": option})
    assert info.value.field == field
    assert words in info.value.rule


def test_draws_times_lines_stay_within_the_compute_budget():
    lines = MAX_UNCERTAINTY_DRAW_LINES // 500 + 1
    doc = {**ra1({"start_hz": 1.0, "stop_hz": float(lines), "step_hz": 1.0}), "uncertainty": {"draws": 500}}
    with pytest.raises(InputError) as info:
        parse_prediction_request(doc)
    assert info.value.field == "uncertainty.draws" and "compute budget" in info.value.rule

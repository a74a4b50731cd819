"""A batch solves its tools stacked; every result must equal that tool predicted on its own."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import rcsa
from rcsa.model import prediction as prediction_module
from rcsa.physics import elimination
from rcsa.reference import ra1

GRID = {"start_hz": 5.0, "stop_hz": 6000.0, "step_hz": 15.0}


def _combos() -> tuple[dict, list[dict]]:
    doc = ra1(GRID)
    short_holder = copy.deepcopy(doc["holder"])
    short_holder["segments"][2]["length_m"] = 0.03
    combos = []
    for i in range(7):
        tool = {**doc["tool"], "stickout_m": 0.045 + 0.006 * i, "flute_length_m": 0.02 + 0.002 * i,
                "fluted_diameter_ratio": 0.7 + 0.02 * i}
        if i % 3 == 2:  # a plain shank: a tool side of another structure (no fluted part)
            tool["diameter_m"], tool["shank_diameter_m"] = 0.012, 0.012
        combos.append({"id": f"T{i}", "holder": short_holder if i % 2 else doc["holder"], "tool": tool,
                       "joints": doc["joints"]})
    combos.insert(3, {"id": "bad", "holder": doc["holder"], "tool": {**doc["tool"], "stickout_m": 0.5}})
    return doc, combos


@pytest.mark.parametrize("per_pass, block", [(64, 4096), (2, 4096), (64, 300)])
def test_stacked_batch_equals_tools_predicted_one_by_one(monkeypatch, per_pass, block):
    # a few tools per pass, and blocks shorter than the grid (no tiling), take the other paths
    monkeypatch.setattr(prediction_module, "TOOLS_PER_PASS", per_pass)
    monkeypatch.setattr(elimination, "_BLOCK", block)
    doc, combos = _combos()
    seen: list[tuple[int, int]] = []
    out = rcsa.predict_batch({"frequency": GRID, "spindle": doc["spindle"], "combinations": combos},
                            progress=lambda done, total: seen.append((done, total)), arrays="numpy")
    assert out["summary"] == {"ok": 7, "error": 1}
    assert seen[-1] == (8, 8) and all(a[0] <= b[0] for a, b in zip(seen, seen[1:], strict=False))
    for combo, result in zip(combos, out["results"], strict=True):
        assert result["id"] == combo["id"]
        if combo["id"] == "bad":
            assert result["status"] == "error"
            continue
        alone = rcsa.predict({**doc, "holder": combo["holder"], "tool": combo["tool"]}).to_dict("numpy")
        h = np.asarray(result["tool_point"]["h"]["real"]) + 1j * np.asarray(result["tool_point"]["h"]["imag"])
        h0 = np.asarray(alone["tool_point"]["h"]["real"]) + 1j * np.asarray(alone["tool_point"]["h"]["imag"])
        np.testing.assert_allclose(h, h0, rtol=1e-11, atol=1e-11 * np.abs(h0).max())
        nat, nat0 = np.asarray(result["natural_frequencies_hz"]), np.asarray(alone["natural_frequencies_hz"])
        assert nat.size == nat0.size > 0
        np.testing.assert_allclose(nat, nat0, rtol=2e-11)
        assert result["static_stiffness_n_m"] == pytest.approx(alone["static_stiffness_n_m"], rel=1e-12)
        assert result["notes"] == alone["notes"]
        assert [p["frequency_hz"] for p in result["peaks"]] == pytest.approx(
            [p["frequency_hz"] for p in alone["peaks"]], rel=1e-9)


def test_batch_without_natural_frequencies_leaves_them_empty():
    doc, combos = _combos()
    out = rcsa.predict_batch({"frequency": GRID, "spindle": doc["spindle"], "combinations": combos,
                             "natural_frequencies": False}, arrays="numpy")
    assert out["summary"] == {"ok": 7, "error": 1}
    assert all(len(r["natural_frequencies_hz"]) == 0 for r in out["results"] if r["status"] == "ok")


def test_a_tools_result_does_not_depend_on_its_companions():
    # the lockstep search spends a fixed number of points per mode: the same bits alone or in company
    doc, combos = _combos()
    combos = [c for c in combos if c["id"] != "bad"]
    request = {"frequency": GRID, "spindle": doc["spindle"]}
    everyone = rcsa.predict_batch({**request, "combinations": combos}, arrays="numpy")["results"]
    for k in (0, 4):
        alone = rcsa.predict_batch({**request, "combinations": combos[k:k + 1]}, arrays="numpy")["results"][0]
        assert list(alone["natural_frequencies_hz"]) == list(everyone[k]["natural_frequencies_hz"])
        assert alone["static_stiffness_n_m"] == everyone[k]["static_stiffness_n_m"]

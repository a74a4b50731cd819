"""Robust chatter-safe presets: the pocket chosen on the robust depth limit of drawn assemblies."""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.analysis.lobes.pockets import pocket_speed_grid, window_minimum
from rcsa.analysis.lobes.zoa import depth_limit_envelopes, stability_lobes
from rcsa.app.jobs import Workbench
from rcsa.app.presets import recommend_predicted, recommend_stored
from rcsa.errors import InputError
from rcsa.libraries import recommend_sources
from rcsa.libraries.formats import read_library
from rcsa.libraries.recommend import parse_recommend_options
from rcsa.libraries.recommend_sources import predicted_frfs
from rcsa.libraries.sync import sync_library
from rcsa.model.tolerances import DEFAULT_TOLERANCES
from rcsa.reference import ra1
from tests.helpers import REPO

SAMPLE = (REPO / "tests" / "data" / "tool-libraries" / "fusion-synthetic" / "synthetic_library.json").read_bytes()
GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}  # 1 000 lines
RA1 = ra1(GRID)
SETTINGS = {"spindle": RA1["spindle"], "frequency": GRID, "joints": RA1["joints"]}
OPTIONS = {"material": "aluminium-7075", "max_rpm": 24000, "method": "zoa"}  # robust SDM: test_recommend_methods.py
DRAWS = {"draws": 24, "seed": 3}


def recommend(**options):
    return recommend_predicted(Workbench(None), SAMPLE, {**OPTIONS, **options}, file_name="shop.json", **SETTINGS)


def written(result):
    return {t["id"]: t for t in result.report["tools"] if t["status"] == "written"}


@pytest.fixture(scope="module")
def nominal():
    return recommend()


@pytest.fixture(scope="module")
def robust():
    return recommend(uncertainty=DRAWS, confidence=0.9)


def test_robust_presets_are_never_deeper_than_nominal_ones(nominal, robust):
    plain, safe = written(nominal), written(robust)
    assert safe and set(safe) == set(plain)
    for ident, tool in safe.items():
        assert tool["confidence"] == 0.9
        assert tool["robust_depth_limit_m"] <= tool["depth_limit_m"] * (1 + 1e-12)
        # the nominal choice maximises n * stepdown over a limit that is everywhere >= the robust one
        assert tool["spindle_speed_rpm"] * tool["stepdown_m"] <= \
            plain[ident]["spindle_speed_rpm"] * plain[ident]["stepdown_m"] * (1 + 1e-9)
    assert robust.report["options"]["uncertainty"] == DRAWS
    assert "robust: the 10th percentile over 24 drawn assemblies" in robust.data.decode()


def test_the_robust_preset_lies_in_a_pocket_stable_for_the_drawn_assemblies(robust):
    """Recompute the robust limit independently (every draw's envelope) at the preset's window."""
    source = predicted_frfs(read_library(SAMPLE, file_name="shop.json"), uncertainty=DRAWS, **SETTINGS)
    options = parse_recommend_options({**OPTIONS, "uncertainty": DRAWS, "confidence": 0.9})
    for ident, tool in written(robust).items():
        frf = source.frfs[ident]
        assert frf.h_draws.shape == (24, frf.h.size)
        lo, hi = tool["speed_range"]["min_rpm"], tool["speed_range"]["max_rpm"]
        grid = pocket_speed_grid(lo, hi, options.speed_tolerance)
        cut = {"teeth": tool["teeth"], "tangential_coefficient_n_m2": options.tangential_coefficient_n_m2,
               "radial_ratio": options.radial_ratio, "radial_immersion": options.radial_immersion,
               "milling": options.milling, "spindle_speed_rpm": grid}
        draws = depth_limit_envelopes(frf.frequency_hz, frf.h_draws, **cut)
        nominal = stability_lobes(frf.frequency_hz, frf.h, None, **cut).depth_limit_m
        limit = np.minimum(np.percentile(draws, 10.0, axis=0), nominal)
        window = window_minimum(grid, limit, options.speed_tolerance)
        at = int(np.argmin(np.abs(grid - tool["spindle_speed_rpm"])))
        assert window[at] == pytest.approx(tool["robust_depth_limit_m"], rel=1e-6)
        assert tool["stepdown_m"] * options.safety_factor <= window[at] * (1 + 1e-9)


def test_zero_tolerances_give_the_nominal_presets(nominal):
    zero = recommend(uncertainty={"draws": 3, "tolerances": dict.fromkeys(DEFAULT_TOLERANCES, 0.0)})
    plain, same = written(nominal), written(zero)
    assert set(same) == set(plain)
    for ident, tool in same.items():
        for key in ("spindle_speed_rpm", "stepdown_m", "depth_limit_m"):
            assert tool[key] == pytest.approx(plain[ident][key], rel=1e-9), key
        assert tool["robust_depth_limit_m"] == pytest.approx(tool["depth_limit_m"], rel=1e-9)


def test_too_many_drawn_lines_are_refused_before_drawing(monkeypatch):
    monkeypatch.setattr(recommend_sources, "MAX_DRAWN_LINES", 10_000)  # 2 tools x 24 draws x 1 000 lines = 48 000
    with pytest.raises(InputError, match="drawn lines") as err:
        recommend(uncertainty=DRAWS)
    assert err.value.field == "uncertainty" and "at most 10,000 per recommendation" in str(err.value)


@pytest.mark.parametrize(("options", "field"), [
    ({"confidence": 0.9}, "confidence"),                                  # without uncertainty
    ({"uncertainty": DRAWS, "confidence": 0.3}, "confidence"),
    ({"uncertainty": [1]}, "uncertainty"),
])
def test_robust_options_are_checked(options, field):
    with pytest.raises(InputError) as err:
        parse_recommend_options({**OPTIONS, **options})
    assert err.value.field == field


def test_a_stored_library_gives_robust_presets_from_its_sync_settings(tmp_path, robust):
    bench = Workbench(None, tmp_path / "store")
    sync_library(bench.libraries, "shop", SAMPLE, **SETTINGS, natural_frequencies=False)
    stored = recommend_stored(bench, "shop", SAMPLE, {**OPTIONS, "uncertainty": DRAWS, "confidence": 0.9},
                              file_name="shop.json")
    assert stored.data == robust.data

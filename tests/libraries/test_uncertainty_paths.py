"""Batches and library syncs carry the uncertainty option, and a sync's result key includes it."""

from __future__ import annotations

import numpy as np
import pytest

import rcsa
from rcsa.errors import InputError
from rcsa.libraries import sync as library_sync
from rcsa.model.tolerances import DEFAULT_TOLERANCES
from rcsa.reference import ra1
from tests.libraries.test_sync import SETTINGS, make_library, tool_id

GRID = {"start_hz": 100.0, "stop_hz": 3000.0, "step_hz": 20.0}
OPTION = {"draws": 8, "seed": 5}


def test_a_batch_gives_every_combination_the_band_of_its_own_prediction():
    doc = ra1(GRID)
    short = {**doc["tool"], "stickout_m": 0.05}
    request = {"frequency": GRID, "spindle": doc["spindle"], "uncertainty": OPTION,
               "combinations": [{"id": "long", "holder": doc["holder"], "tool": doc["tool"], "joints": doc["joints"]},
                                {"id": "short", "holder": doc["holder"], "tool": short, "joints": doc["joints"]},
                                {"id": "bad", "holder": doc["holder"], "tool": {**short, "stickout_m": -1.0}}]}
    results = rcsa.predict_batch(request)["results"]
    assert [r["status"] for r in results] == ["ok", "ok", "error"]
    for result, tool in zip(results[:2], (doc["tool"], short), strict=True):
        alone = rcsa.predict({**doc, "tool": tool, "uncertainty": OPTION})
        for name in ("p05", "p50", "p95"):
            np.testing.assert_allclose(result["uncertainty"]["h_magnitude_m_n"][name],
                                       alone["uncertainty"]["h_magnitude_m_n"][name], rtol=1e-10)
        np.testing.assert_allclose(result["uncertainty"]["natural_frequencies_hz"]["mean"],
                                   alone["uncertainty"]["natural_frequencies_hz"]["mean"], rtol=1e-9)
        assert len(result["uncertainty"]["natural_frequencies_hz"]["sd"]) == len(result["natural_frequencies_hz"])


def test_a_batch_refuses_a_bad_option_naming_it():
    doc = ra1(GRID)
    request = {"frequency": GRID, "spindle": doc["spindle"], "uncertainty": {"draws": 0},
               "combinations": [{"id": "a", "holder": doc["holder"], "tool": doc["tool"]}]}
    with pytest.raises(InputError) as info:
        rcsa.predict_batch(request)
    assert info.value.field == "uncertainty.draws"


@pytest.fixture
def libs(tmp_path):
    return library_sync.LibraryStore(tmp_path / "store" / "libraries")


def test_a_library_sync_carries_the_option_and_keys_results_by_it(libs):
    lib = make_library(2)
    plain = library_sync.sync_library(libs, "shop", lib, **SETTINGS)
    banded = library_sync.sync_library(libs, "shop", lib, **SETTINGS, uncertainty=OPTION)
    assert plain.computed == 2 and banded.computed == 2  # another option: other keys, computed again
    results = {r["id"]: r for r in libs.results("shop")["results"]}
    band = results[tool_id(0)]["uncertainty"]
    assert band["draws"] == 8 and band["tolerances"] == dict(DEFAULT_TOLERANCES)
    p05, p95 = (np.asarray(band["h_magnitude_m_n"][k]) for k in ("p05", "p95"))
    assert p05.size == len(results[tool_id(0)]["frequency_hz"]) and np.all(p05 <= p95)
    again = library_sync.sync_library(libs, "shop", lib, **SETTINGS, uncertainty={**OPTION, "tolerances": {}})
    assert again.computed == 0  # the same option with its defaults spelt out or left out: the same keys
    other_seed = library_sync.sync_library(libs, "shop", lib, **SETTINGS, uncertainty={**OPTION, "seed": 6})
    assert other_seed.computed == 2

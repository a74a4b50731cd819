"""Uncertainty bands on a measured spindle: its noise and its rotation estimate widen the band."""

from __future__ import annotations

import numpy as np
import pytest

import rcsa
from rcsa.errors import InputError
from rcsa.measured.store import Measurement, MeasurementMeta, MeasurementStore
from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.model.tolerances import DEFAULT_TOLERANCES
from rcsa.physics.elimination import tip_receptance
from rcsa.reference import ra1

GRID = {"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 10.0}
ZERO = dict.fromkeys(DEFAULT_TOLERANCES, 0.0)


@pytest.fixture(scope="module")
def stored(tmp_path_factory):
    """RA-1's modelled spindle stored twice: as its full 2×2 and as its h alone (direct FRF)."""
    store = MeasurementStore(tmp_path_factory.mktemp("store"))
    spec = parse_assembly(ra1(GRID))
    s = tip_receptance(build_model(spec).spindle, 2 * np.pi * spec.frequency_hz)
    full = store.put(Measurement(spec.frequency_hz, {"h": s[:, 0, 0], "l": s[:, 0, 1], "n": s[:, 1, 0],
                                                     "p": s[:, 1, 1]},
                                 MeasurementMeta("ra1", "x", "spindle_nose", "point_receptance")))
    direct = store.put(Measurement(spec.frequency_hz, {"h": s[:, 0, 0]},
                                   MeasurementMeta("ra1", "x", "spindle_nose", "direct_frf")))
    return store, full, direct


def width(result) -> np.ndarray:
    band = result["uncertainty"]["h_magnitude_m_n"]
    return (np.array(band["p95"]) - np.array(band["p05"])) / np.abs(result.tool_point.h)  # relative, per line


def banded(store, measurement_id, **tolerances):
    doc = ra1(GRID)
    doc["spindle"] = {"measurement_id": measurement_id}
    doc["uncertainty"] = {"draws": 24, "seed": 3, "tolerances": {**ZERO, **tolerances}}
    return rcsa.predict(doc, store=store)


def test_a_noise_free_measurement_without_tolerances_gives_no_band(stored):
    store, full, _ = stored
    result = banded(store, full, spindle_noise_rel=0.0)
    assert np.max(width(result)) < 1e-12
    assert result["uncertainty"]["measured_spindle"]["noise"]["without_coherence"] == ["h", "l", "n", "p"]


def test_the_measurement_noise_widens_the_band_most_where_the_spindle_shows(stored):
    store, full, _ = stored
    result = banded(store, full, spindle_noise_rel=0.01)
    # 1 % noise on the spindle: little at most lines (the tool dominates), tens of % at its modes
    assert 1e-4 < np.median(width(result)) < 0.01 < 0.05 < np.max(width(result))
    u = result["uncertainty"]
    assert u["tolerances"]["spindle_noise_rel"] == 0.01 and "bearings are inside" in u["notes"][0]
    assert len(u["natural_frequencies_hz"]["mean"]) == len(result["natural_frequencies_hz"])
    assert "modal-fit" in u["natural_frequencies_matching"]


def test_a_direct_frf_spindle_widens_the_band_by_its_rotation_estimate(stored):
    store, _, direct = stored
    noise_only = banded(store, direct, spindle_noise_rel=0.005, spindle_effective_length_log=0.0)
    with_rotations = banded(store, direct, spindle_noise_rel=0.005)
    assert np.median(width(with_rotations)) > 2 * np.median(width(noise_only))
    u = with_rotations["uncertainty"]
    assert u["measured_spindle"]["effective_length_m"]["bounds"] == [0.1, 0.4]
    assert "h_bounds" in u  # the estimate's bounds, as without the option


def test_spindle_tolerances_are_refused_on_a_modelled_spindle():
    doc = {**ra1(GRID), "uncertainty": {"tolerances": {"spindle_noise_rel": 0.01}}}
    with pytest.raises(InputError) as info:
        rcsa.predict(doc)
    assert info.value.field == "uncertainty.tolerances.spindle_noise_rel"

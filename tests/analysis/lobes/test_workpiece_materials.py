"""The workpiece-material table: every value as its source gives it, sources named, lookups."""

from __future__ import annotations

import pytest

from rcsa.analysis.lobes.workpiece_materials import (
    COEFFICIENT_MODEL,
    SPEED_SOURCE,
    WORKPIECE_MATERIALS,
    engagement_band,
    workpiece_material,
)
from rcsa.errors import InputError

# Table 5 of the CJME review (doi:10.1186/s10033-021-00536-9): K_tc, K_rc in N/mm²
CJME_TABLE_5 = {"aluminium-7075": ("[47]", 1319.41, 788.83), "aluminium-6082": ("[189]", 631.0, 99.0)}
# Tungaloy 2020-2021, solid carbide end mills: upper ends of v_c, m/min (slotting, semi-finishing, finishing)
TUNGALOY = {"aluminium-7075": (750, 850, 900), "aluminium-6082": (750, 850, 900), "carbon-steel": (180, 220, 280),
            "alloy-steel": (150, 160, 220), "stainless-steel": (100, 130, 160), "cast-iron": (180, 220, 280),
            "titanium-alloy": (50, 60, 70), "hardened-steel": (30, 70, 80)}


@pytest.mark.parametrize("key", sorted(CJME_TABLE_5), ids=str)
def test_cutting_coefficients_are_the_sources(key):
    row_ref, ktc, krc = CJME_TABLE_5[key]
    m = WORKPIECE_MATERIALS[key]
    assert m.tangential_coefficient_n_m2 == pytest.approx(ktc * 1e6, rel=1e-12), f"{key}: K_tc, CJME Table 5"
    assert m.radial_ratio == pytest.approx(krc / ktc, rel=1e-12), f"{key}: K_rc/K_tc, CJME Table 5"
    assert "10.1186/s10033-021-00536-9" in m.coefficient_source and row_ref in m.coefficient_source


def test_7075_matches_the_mal_example_and_the_ecosystem_notes():
    m = WORKPIECE_MATERIALS["aluminium-7075"]  # LobeZOAAltintas.m: Kt = 1319.4e6, Kn = 788.8/1319.4
    assert m.tangential_coefficient_n_m2 == pytest.approx(1319.4e6, rel=1e-5)
    assert m.radial_ratio == pytest.approx(788.8 / 1319.4, rel=1e-4) == pytest.approx(0.598, abs=5e-4)


@pytest.mark.parametrize("key", sorted(TUNGALOY), ids=str)
def test_surface_speed_limits_are_the_vendors(key):
    assert WORKPIECE_MATERIALS[key].carbide_surface_speed_m_min == TUNGALOY[key], f"{key}: {SPEED_SOURCE}"


def test_rows_without_a_citable_value_have_no_coefficients():
    for key, m in WORKPIECE_MATERIALS.items():
        assert (m.tangential_coefficient_n_m2 is None) == (key not in CJME_TABLE_5)
        assert (m.coefficient_source is None) == (key not in CJME_TABLE_5)
    assert set(WORKPIECE_MATERIALS) == set(TUNGALOY)
    assert "linear edge-force" in COEFFICIENT_MODEL
    doc = WORKPIECE_MATERIALS["aluminium-7075"].to_dict()
    assert doc["coefficient_model"] == COEFFICIENT_MODEL and doc["surface_speed_source"] == SPEED_SOURCE


@pytest.mark.parametrize(("name", "key"), [("Aluminum", "aluminium-7075"), ("AL 7075-T6", "aluminium-7075"),
                                           ("6082", "aluminium-6082"), ("Ti-6Al-4V", "titanium-alloy"),
                                           ("C45", "carbon-steel"), ("stainless", "stainless-steel")])
def test_lookup_by_alias(name, key):
    assert workpiece_material(name).key == key


def test_unknown_and_invalid_names():
    assert workpiece_material("Inconel 718") is None
    with pytest.raises(InputError):
        workpiece_material("  ")


def test_engagement_bands():
    assert [engagement_band(x) for x in (1.0, 0.4, 0.39, 0.1, 0.09)] == [0, 0, 1, 1, 2]
    assert WORKPIECE_MATERIALS["carbon-steel"].max_surface_speed_m_min(0.05) == 280.0

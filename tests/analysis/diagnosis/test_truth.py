"""Self-checks of the benchmark's FE truth generator (``tests/analysis/diagnosis/truth.py``)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.analysis.diagnosis import truth as T

F_HZ = np.geomspace(60.0, 7000.0, 300)
ONES = dict.fromkeys(["tool_e", "tool_rho", "steel_e", "steel_rho", "loss", "bearing_k", "bearing_c",
                      "sh_kt", "sh_kr", "sh_c"], 1.0)


@pytest.fixture(scope="module")
def nominal():
    nz = T.Nuisance(dict(ONES), [{"ht_kt": 1.0, "ht_kr": 1.0, "ht_c": 1.0, "stickout_dm": 0.0}])
    doc = T.config_documents(T.base_document(), nz, [0.066])[0]
    return doc, T.effect_frf("none", {}, doc, F_HZ)


def test_no_effect_truth_is_the_exact_model_within_the_mesh_error(nominal):
    from rcsa.analysis.diagnosis.perturbed_model import Knobs, Solver, config_parts
    from rcsa.model.contract import parse_assembly
    doc, h = nominal
    spec = parse_assembly({**T._clean(doc), "frequency": {"values_hz": F_HZ.tolist()}})
    exact = Solver(F_HZ).tip_h(config_parts(spec, spec.tool, Knobs()))
    # 2 mm Friedman-Kosmatka elements: ≤ 0.05 % of the peak, far below the 1 % noise.
    assert np.max(np.abs(h - exact)) / np.max(np.abs(exact)) < 5e-4


def test_spindle_substructure_matches_the_exact_spindle_and_unit_scale_changes_nothing(nominal):
    from rcsa.analysis.diagnosis.perturbed_model import Knobs, Solver, config_parts
    from rcsa.model.contract import parse_assembly
    doc, h = nominal
    r_fe = T._spindle_nose_receptance(T._clean(doc), F_HZ)
    spec = parse_assembly({**T._clean(doc), "frequency": {"values_hz": F_HZ.tolist()}})
    r = np.linalg.inv(Solver(F_HZ).nose_stiffness(config_parts(spec, spec.tool, Knobs())))
    assert np.max(np.abs(r_fe - r) / np.abs(r).max(axis=0)) < 2e-3
    np.testing.assert_allclose(T._scaled_spindle_rotation(doc, F_HZ, 1.0), h, rtol=1e-8)


@pytest.mark.parametrize("effect", [e for e in T.EFFECTS if e not in ("none", "shear_and_rotary_inertia")])
def test_every_hidden_effect_changes_the_frf(nominal, effect):
    doc, h = nominal
    params = T.draw_effect(np.random.default_rng(1), effect)
    he = T.effect_frf(effect, params, doc, F_HZ)
    rms_db = np.sqrt(np.mean((20 * np.log10(np.abs(he / h))) ** 2))
    assert rms_db > 0.2, (effect, params, rms_db)


def test_measurement_noise_and_coherence_are_consistent():
    rng = np.random.default_rng(0)
    h = np.full(20000, 1e-6 + 0j)
    noisy, coherence = T.measure(h, rng)
    sigma_rel = np.std((noisy - h).real) / 1e-6
    # 1 % + a floor at -50 dB of the peak (0.316 %): sqrt(0.01² + 0.00316²) = 1.05 %
    assert sigma_rel == pytest.approx(np.hypot(0.01, 10 ** (-50 / 20)), rel=0.03)
    assert np.allclose(coherence, 1 / (1 + 10 * sigma_rel**2), rtol=0.01)

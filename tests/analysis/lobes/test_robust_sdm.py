"""The reduced model of the draws behind robust semi-discretization lobes and presets.

Oracle: one full semi-discretization per drawn modal model. For a single mode the reduced
model is exact but for its interpolations (the similarity law ``b = (ω²/R) Φ(n/ω, ζ)``); with
two modes that shift differently it is an approximation whose error is measured here (and
stated in the module docstring and the manual).
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.analysis.lobes.modal_model import ModalModel
from rcsa.analysis.lobes.robust_sdm import drawn_models, modal_ratios, robust_sdm_limits
from rcsa.analysis.lobes.semi_discretization import semi_discretization_lobes_many
from rcsa.app.analyses import stability_lobes
from rcsa.model.tolerances import DEFAULT_TOLERANCES
from rcsa.reference import ra1

CUT = {"teeth": 1, "tangential_coefficient_n_m2": 1.31941e9, "radial_ratio": 0.5979, "radial_immersion": 0.05,
       "milling": "down"}
F = np.arange(200.0, 3000.0, 0.5)


def _draws(base: ModalModel, n: int, seed: int):
    rng = np.random.default_rng(seed)
    m = base.n_modes
    s, c, k = (np.exp(rng.normal(0, sd, (n, m))) for sd in (0.03, 0.25, 0.1))
    models = [ModalModel.of(base.frequency_hz * s[d], base.damping_ratio * c[d], base.residue_1_kg * s[d] ** 2 / k[d],
                            base.direction) for d in range(n)]
    return models, np.array([mm.receptance(F, 0) for mm in models]), (s, c, k)


def _full(models, speeds):
    out = semi_discretization_lobes_many(models, **CUT, spindle_speed_rpm=[speeds] * len(models))
    return np.array([r.depth_limit_m for r in out])


def test_the_draws_modal_changes_are_recovered_from_their_frfs():
    base = ModalModel.of([1400.0], [0.015], [50.0], [0])
    _, h_draws, (s, c, k) = _draws(base, 12, 1)
    r = modal_ratios(base, F, base.receptance(F, 0), h_draws)
    np.testing.assert_allclose(r.frequency, s, rtol=1e-9)
    np.testing.assert_allclose(r.damping, c, rtol=1e-9)
    np.testing.assert_allclose(r.stiffness, k, rtol=1e-9)
    models = drawn_models(base, r)
    np.testing.assert_allclose([m.frequency_hz[0] for m in models], 1400.0 * s[:, 0], rtol=1e-9)


@pytest.mark.slow
def test_one_mode_the_reduced_model_is_the_full_one_but_for_its_interpolations():
    """Measured: 0.6 % median and 5 % at the 90th percentile per draw and speed (24 draws)."""
    base = ModalModel.of([1400.0], [0.015], [50.0], [0])
    models, h_draws, _ = _draws(base, 16, 2)
    speeds = np.geomspace(14000.0, 24000.0, 50)
    nominal = semi_discretization_lobes_many([base], **CUT, spindle_speed_rpm=[speeds])[0]
    per_draw: list[np.ndarray] = []
    robust = robust_sdm_limits(base, F, base.receptance(F, 0), h_draws, nominal, 0.9, **CUT, draws_out=per_draw)
    full = _full(models, speeds)
    err = np.abs(per_draw[0] / full - 1)
    assert np.nanmedian(err) < 0.02 and np.nanpercentile(err, 90) < 0.1, (np.nanmedian(err), np.nanpercentile(err, 90))
    q_full = np.fmin(np.percentile(np.nan_to_num(full, nan=1.0), 10.0, axis=0), nominal.depth_limit_m)
    assert np.nanmedian(np.abs(robust / q_full - 1)) < 0.03
    assert np.all(robust <= nominal.depth_limit_m * (1 + 1e-12))


def test_zero_tolerances_give_the_nominal_semi_discretization_limit():
    assembly = ra1({"start_hz": 200.0, "stop_hz": 3000.0, "step_hz": 2.0})
    zero = {"draws": 3, "tolerances": dict.fromkeys(DEFAULT_TOLERANCES, 0.0)}
    response = stability_lobes({"assembly": assembly, **CUT, "method": "semi_discretization",
                                "spindle_speed_rpm": {"start": 20000, "stop": 24000, "count": 12},
                                "uncertainty": zero, "robust": {"confidence": 0.9}})
    nominal = np.array([np.nan if v is None else v for v in response["depth_limit_m"]])
    robust = np.array([np.nan if v is None else v for v in response["depth_limit_robust_m"]])
    assert response["robust"]["method"] == "semi_discretization" and "reduced model" in response["robust"]["rule"]
    # the reduced model's own grid and 0.5 % brackets, and its diagrams unchecked (each resolution within ~1 %)
    np.testing.assert_allclose(robust, nominal, rtol=1.5e-2)
    assert np.all(robust <= nominal * (1 + 1e-12))

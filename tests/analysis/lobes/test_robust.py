"""Robust stability lobes: the lobes of drawn assemblies, at a stated confidence."""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.analysis.lobes.zoa import depth_limit_envelopes, stability_lobes
from rcsa.app.analyses import stability_lobes as lobes_response
from rcsa.app.analyses import stability_lobes_results
from rcsa.app.predictions import predict_draws
from rcsa.errors import InputError
from rcsa.model.tolerances import DEFAULT_TOLERANCES
from rcsa.reference import ra1

GRID = {"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 10.0}
CUT = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
       "milling": "down", "spindle_speed_rpm": {"start": 3000, "stop": 24000, "count": 600}, "method": "zoa"}
OPTION = {"draws": 24, "seed": 11}


def _array(values) -> np.ndarray:
    return np.array([np.nan if v is None else v for v in values])


@pytest.fixture(scope="module")
def robust_response():
    return lobes_response({"assembly": ra1(GRID), **CUT, "uncertainty": OPTION, "robust": {"confidence": 0.9}})


def test_every_draws_envelope_equals_its_own_lobe_diagram():
    _, draws, _ = predict_draws(ra1(GRID), {"draws": 6, "seed": 2})
    speeds = np.linspace(3000.0, 24000.0, 600)
    cut = {k: v for k, v in CUT.items() if k not in ("spindle_speed_rpm", "method")}
    f = np.arange(100.0, 5000.0 + 1e-9, 10.0)
    together = depth_limit_envelopes(f, draws.h, spindle_speed_rpm=speeds, **cut)
    one_by_one = [stability_lobes(f, h, spindle_speed_rpm=speeds, **cut).depth_limit_m for h in draws.h]
    np.testing.assert_array_equal(together, np.array(one_by_one))


def test_robust_limits_are_the_draws_percentile_and_never_above_the_nominal(robust_response):
    nominal, robust = _array(robust_response["depth_limit_m"]), _array(robust_response["depth_limit_robust_m"])
    assert robust.shape == nominal.shape and not np.isnan(robust).any()
    assert np.all(robust <= nominal)
    assert np.median(robust / nominal) < 0.95  # the tolerances cost depth at most speeds
    r = robust_response["robust"]
    assert (r["confidence"], r["percentile"], r["draws"], r["seed"]) == (0.9, 10.0, 24, 11)
    assert r["method"] == "zoa" and r["tolerances"] == dict(DEFAULT_TOLERANCES)


def test_the_robust_limit_is_the_percentile_of_the_draws_envelopes():
    request = {"assembly": ra1(GRID), **CUT, "uncertainty": OPTION}
    nominal, robust = stability_lobes_results(request)
    assert robust is not None and robust.confidence == 0.95
    expected = np.fmin(np.percentile(robust.draws_depth_limit_m, 5.0, axis=0), nominal.depth_limit_m)
    np.testing.assert_array_equal(robust.depth_limit_m, expected)


def test_zero_tolerances_give_the_nominal_limits():
    zero = {"draws": 3, "tolerances": dict.fromkeys(DEFAULT_TOLERANCES, 0.0)}
    response = lobes_response({"assembly": ra1(GRID), **CUT, "uncertainty": zero})
    np.testing.assert_allclose(_array(response["depth_limit_robust_m"]), _array(response["depth_limit_m"]),
                               rtol=1e-9)


@pytest.mark.parametrize(("extra", "field"), [
    ({"robust": {"confidence": 0.9}}, "robust"),
    ({"uncertainty": OPTION, "robust": {"confidence": 0.4}}, "robust.confidence"),
    ({"uncertainty": OPTION, "robust": {"level": 0.9}}, "robust.level"),
    ({"uncertainty": {"draws": 1}}, "uncertainty.draws"),
])
def test_bad_robust_requests_name_the_field(extra, field):
    with pytest.raises(InputError) as info:
        lobes_response({"assembly": ra1(GRID), **CUT, **extra})
    assert info.value.field == field


def test_robust_lobes_need_an_assembly():
    frf = {"frequency_hz": [100.0, 200.0], "h": {"real": [1e-7, -1e-7], "imag": [-1e-8, -2e-7]}}
    with pytest.raises(InputError) as info:
        lobes_response({"frf_x": frf, **CUT, "uncertainty": OPTION})
    assert info.value.field == "uncertainty"

"""The pocket rule: window minimum (against a loop oracle), the best speed, the pocket, the caps."""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.analysis.lobes.pockets import (
    PocketRule,
    best_pocket,
    pocket_speed_grid,
    window_minimum,
)
from rcsa.analysis.lobes.zoa import stability_lobes
from rcsa.errors import InputError


def window_minimum_oracle(n: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
    """The readable form: for every speed, the minimum over its window (NaN if unsettled or cut)."""
    out = np.full(n.size, np.nan)
    for i, ni in enumerate(n):
        lo, hi = ni * (1 - tol), ni * (1 + tol)
        if lo < n[0] * (1 - 1e-12) or hi > n[-1] * (1 + 1e-12):
            continue
        below, above = n[n <= lo * (1 + 1e-12)], n[n >= hi * (1 - 1e-12)]  # the bracketing grid speeds
        w = b[(n >= below.max()) & (n <= above.min())]
        out[i] = np.nan if np.any(~np.isfinite(w)) else w.min()
    return out


@pytest.mark.parametrize("tol", [0.0, 0.004, 0.03, 0.1])
def test_window_minimum_equals_the_loop(tol):
    rng = np.random.default_rng(7)
    n = np.cumsum(rng.uniform(1.0, 30.0, 700)) + 1000.0
    b = rng.uniform(0.1, 5.0, n.size)
    b[rng.integers(0, n.size, 8)] = np.nan
    np.testing.assert_array_equal(window_minimum(n, b, tol), window_minimum_oracle(n, b, tol))


def single_mode_lobes(grid):
    f = np.linspace(50.0, 3000.0, 5901)
    w, wn, z, k = 2 * np.pi * f, 2 * np.pi * 900.0, 0.03, 2e7
    h = 1.0 / (k * (1 - (w / wn) ** 2 + 2j * z * (w / wn)))
    return stability_lobes(f, h, teeth=4, tangential_coefficient_n_m2=8e8, radial_ratio=0.3,
                           radial_immersion=0.5, milling="down", spindle_speed_rpm=grid)


def test_best_pocket_keeps_its_window_stable_and_maximises_removal():
    rule = PocketRule(safety_factor=1.25, speed_tolerance=0.03)
    grid = pocket_speed_grid(3000.0, 16000.0, rule.speed_tolerance)
    lobes = single_mode_lobes(grid)
    p = best_pocket(grid, lobes.depth_limit_m, min_rpm=3000.0, max_rpm=16000.0, rule=rule,
                    chatter_frequency_hz=lobes.chatter_frequency_hz, governing_lobe=lobes.governing_lobe)
    assert p is not None and 3000.0 <= p.spindle_speed_rpm <= 16000.0
    window = (grid >= p.spindle_speed_rpm * 0.97 / 1.003) & (grid <= p.spindle_speed_rpm * 1.03 * 1.003)
    assert np.all(lobes.depth_limit_m[window] >= p.stepdown_m * 1.25 * (1 - 1e-12))
    assert p.stepdown_m == pytest.approx(np.nanmin(lobes.depth_limit_m[window]) / 1.25, rel=1e-12)
    # no other speed of the range gives a higher n * allowed depth
    allowed = window_minimum(grid, lobes.depth_limit_m, 0.03) / 1.25
    inside = (grid >= 3000.0) & (grid <= 16000.0)
    assert p.removal_index_rpm_m == pytest.approx(np.nanmax(grid[inside] * allowed[inside]), rel=1e-12)
    # a lobe pocket, far above the absolute limit, at least the window wide
    assert p.stepdown_m > 1.5 * lobes.min_depth_limit_m
    # the pocket holds the whole window (to one grid step, 0.3 %, at each end)
    assert p.pocket_low_rpm <= p.spindle_speed_rpm * 0.97 * 1.003 and p.pocket_high_rpm >= p.spindle_speed_rpm * 1.03 / 1.003
    assert p.pocket_width_rpm >= (0.06 - 0.006) * p.spindle_speed_rpm
    assert p.governing_lobe >= 0 and 800.0 < p.chatter_frequency_hz < 1200.0 and p.limited_by == "stability"


def test_a_wider_tolerance_never_allows_more_depth_at_a_speed():
    grid = pocket_speed_grid(3000.0, 16000.0, 0.1)
    b = single_mode_lobes(grid).depth_limit_m
    narrow, wide = window_minimum(grid, b, 0.01), window_minimum(grid, b, 0.05)
    both = np.isfinite(narrow) & np.isfinite(wide)
    assert both.sum() > 100 and np.all(wide[both] <= narrow[both])


def test_flute_length_caps_the_stepdown_and_then_the_highest_speed_wins():
    grid = pocket_speed_grid(2000.0, 10000.0, 0.03)
    b = np.full(grid.size, 5e-3)
    p = best_pocket(grid, b, min_rpm=2000.0, max_rpm=10000.0, rule=PocketRule(max_depth_m=1e-3))
    assert p.stepdown_m == 1e-3 and p.limited_by == "flute_length"
    assert p.spindle_speed_rpm == grid[grid <= 10000.0 * (1 + 1e-12)].max()


def test_below_the_lobes_the_highest_speed_of_the_range_is_chosen():
    grid = pocket_speed_grid(2000.0, 10000.0, 0.03)
    p = best_pocket(grid, np.full(grid.size, 2e-3), min_rpm=2000.0, max_rpm=10000.0)
    assert p.spindle_speed_rpm == pytest.approx(10000.0, rel=3e-3) and p.stepdown_m == pytest.approx(1.6e-3)


def test_unsettled_speeds_are_never_chosen_and_none_when_nothing_is_stable():
    grid = pocket_speed_grid(2000.0, 10000.0, 0.03)
    b = np.where(grid > 6000.0, np.nan, 1e-3)
    p = best_pocket(grid, b, min_rpm=2000.0, max_rpm=10000.0)
    assert p.pocket_high_rpm <= 6000.0 and p.spindle_speed_rpm * 1.03 <= 6000.0 * 1.003  # the window's grid speeds
    assert best_pocket(grid, np.full(grid.size, np.nan), min_rpm=2000.0, max_rpm=10000.0) is None


@pytest.mark.parametrize(("kwargs", "field"), [({"safety_factor": 0.9}, "safety_factor"),
                                               ({"speed_tolerance": 0.5}, "speed_tolerance"),
                                               ({"max_depth_m": 0.0}, "max_depth_m")])
def test_rule_parameters_are_checked(kwargs, field):
    with pytest.raises(InputError) as err:
        PocketRule(**kwargs)
    assert err.value.field == field


def test_grid_resolves_the_window():
    g = pocket_speed_grid(1000.0, 30000.0, 0.03)
    assert g[0] == pytest.approx(970.0) and g[-1] == pytest.approx(30900.0)
    assert np.max(g[1:] / g[:-1] - 1) <= 0.003 + 1e-12

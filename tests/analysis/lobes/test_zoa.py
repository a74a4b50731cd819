"""Unit, oracle and property tests of :mod:`rcsa.analysis.lobes.zoa` (zero-order stability lobes).

Oracles used here:

* force geometry integrated numerically (directional factors);
* closed forms for one flexible direction and for symmetric slotting (derived in the
  test docstrings from the ZOA equations, independent of the implementation);
* a literal per-frequency ``np.roots`` loop (the readable form of the vectorised code).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from rcsa.analysis.lobes.request import parse_lobes_request
from rcsa.analysis.lobes.zoa import (
    LobeResult,
    directional_factors,
    engagement_angles_rad,
    stability_lobes,
    zoa_depth_limit,
)
from rcsa.errors import FrequencyMismatch, InputError

# Identities evaluated in float64 on O(1e3) values: a few ulps of relative error.
RTOL_ALGEBRA = 1e-10
# Quadrature of smooth trigonometric integrands (scipy quad, default epsabs 1.5e-8 on O(1)).
RTOL_QUAD = 1e-8


def single_mode(frequency_hz, fn_hz, zeta, k_n_m):
    """Receptance of one mode, ``1/(k (1 − r² + 2iζr))`` (exp(iωt): Im <= 0), m/N."""
    r = np.asarray(frequency_hz) / fn_hz
    return 1.0 / (k_n_m * (1.0 - r * r + 2j * zeta * r))


def two_modes(frequency_hz, fn_hz, zeta, k_n_m):
    return sum(
        single_mode(frequency_hz, f, z, k) for f, z, k in zip(fn_hz, zeta, k_n_m, strict=True)
    )


# --------------------------------------------------------------------------- geometry


@pytest.mark.parametrize(
    ("immersion", "milling", "expected"),
    [
        (0.5, "up", (0.0, math.pi / 2)),
        (0.5, "down", (math.pi / 2, math.pi)),
        (1.0, "up", (0.0, math.pi)),
        (1.0, "down", (0.0, math.pi)),
        (0.25, "up", (0.0, math.acos(0.5))),
        (0.25, "down", (math.acos(-0.5), math.pi)),
    ],
    ids=["half-up", "half-down", "slot-up", "slot-down", "quarter-up", "quarter-down"],
)
def test_engagement_angles(immersion, milling, expected):
    np.testing.assert_allclose(
        engagement_angles_rad(immersion, milling), expected, rtol=RTOL_ALGEBRA, atol=1e-15
    )


@pytest.mark.parametrize("immersion", [0.05, 0.3, 0.5, 0.77, 1.0])
@pytest.mark.parametrize("milling", ["up", "down"])
@pytest.mark.parametrize("kr", [0.0, 0.3, 0.598])
def test_directional_factors_equal_integrated_force_geometry(immersion, milling, kr):
    """α = ∫ 2·∂F/∂Δ / (a Kt) dφ over the engagement, from the force geometry directly.

    Chip ``h = Δx sinφ + Δy cosφ``; ``Ft = Kt a h``, ``Fr = Kr Ft``;
    ``Fx = −Ft cosφ − Fr sinφ``, ``Fy = Ft sinφ − Fr cosφ``. Altintas writes
    ``F = ½ a Kt A Δ``, hence the factor 2.
    """
    phi_st, phi_ex = engagement_angles_rad(immersion, milling)

    def coeff(i, j):
        def g(phi):
            dh = (math.sin(phi), math.cos(phi))[j]
            fx = -(math.cos(phi) + kr * math.sin(phi)) * dh
            fy = (math.sin(phi) - kr * math.cos(phi)) * dh
            return 2.0 * (fx, fy)[i]

        return quad(g, phi_st, phi_ex)[0]

    expected = np.array([[coeff(0, 0), coeff(0, 1)], [coeff(1, 0), coeff(1, 1)]])
    np.testing.assert_allclose(
        directional_factors(phi_st, phi_ex, kr), expected, rtol=RTOL_QUAD, atol=RTOL_QUAD
    )


# --------------------------------------------------------------------------- analytic oracles


def test_one_flexible_direction_slotting_matches_tlusty_closed_form():
    """Only x flexible (Φyy = 0), slotting: a scalar regenerative loop.

    Averaged over a revolution the x force per unit Δx is ``−N Kr Kt a / 4`` (mean of
    ``sinφ cosφ + Kr sin²φ`` over the N/2 teeth in cut), so Tlusty's orthogonal result
    ``b_lim = −1/(2 K Re G)`` with ``K = N Kn/4`` gives ``b_lim = −2/(N Kr Kt Re G)`` and,
    with ``min Re G = −1/(4 k ζ (1+ζ))`` at ``f = fn √(1+2ζ)``,
    ``b_lim,min = 8 k ζ (1+ζ) / (N Kr Kt)``. The phase is Tlusty's
    ``ε = 2π − 2 atan(Re G / Im G)``.
    """
    fn, zeta, k, teeth, kt, kr = 922.0, 0.011, 1.3e6, 2, 6e8, 1.0 / 3.0
    f_star = fn * math.sqrt(1.0 + 2.0 * zeta)
    f = np.sort(np.r_[np.linspace(600.0, 1300.0, 1401), f_star])
    g = single_mode(f, fn, zeta, k)
    r = stability_lobes(
        f,
        g,
        np.zeros_like(g),
        teeth=teeth,
        tangential_coefficient_n_m2=kt,
        radial_ratio=kr,
        radial_immersion=1.0,
        milling="up",
        spindle_speed_rpm=np.linspace(5000, 30000, 300),
    )
    expected_min = 8.0 * k * zeta * (1.0 + zeta) / (teeth * kr * kt)
    # f_star is on the grid, so only rounding separates the two: identity tolerance.
    np.testing.assert_allclose(
        r.min_depth_limit_m, expected_min, rtol=RTOL_ALGEBRA, err_msg="b_lim,min"
    )
    np.testing.assert_allclose(r.min_depth_chatter_frequency_hz, f_star, rtol=RTOL_ALGEBRA)
    assert r.same_frf_in_y is False

    depth, eps = zoa_depth_limit(
        g,
        np.zeros_like(g),
        teeth=teeth,
        tangential_coefficient_n_m2=kt,
        alpha=directional_factors(0.0, math.pi, kr),
    )
    chatter = g.real < 0
    b = np.fmin(depth[:, 0], depth[:, 1])
    np.testing.assert_array_equal(np.isfinite(b), chatter)
    np.testing.assert_allclose(
        b[chatter], -2.0 / (teeth * kr * kt * g.real[chatter]), rtol=RTOL_ALGEBRA
    )
    e = eps[np.arange(f.size), np.nanargmin(np.where(np.isfinite(depth), depth, np.inf), axis=1)]
    tlusty = 2 * np.pi - 2 * np.arctan(g.real / g.imag)
    np.testing.assert_allclose(e[chatter], tlusty[chatter], rtol=RTOL_ALGEBRA)


@pytest.mark.parametrize("immersion", [0.1, 0.5, 0.9])
@pytest.mark.parametrize("milling", ["up", "down"])
def test_one_flexible_direction_any_immersion(immersion, milling):
    """Φyy = 0: ``a0 = 0`` and ``Λ = −1/(αxx Φxx)``, so ``b = 2π/(N Kt αxx Re Φxx)``."""
    f = np.linspace(300.25, 900.25, 601)  # fn = 600 Hz is not on the grid (Re G = 0 there)
    g = single_mode(f, 600.0, 0.03, 5e6)
    alpha = directional_factors(*engagement_angles_rad(immersion, milling), 0.4)
    depth, _ = zoa_depth_limit(
        g, np.zeros_like(g), teeth=4, tangential_coefficient_n_m2=7e8, alpha=alpha
    )
    expected = 2 * np.pi / (4 * 7e8 * alpha[0, 0] * g.real)
    expected[expected <= 0] = np.nan
    np.testing.assert_allclose(
        np.fmin(depth[:, 0], depth[:, 1]), expected, rtol=RTOL_ALGEBRA, equal_nan=True
    )


def test_symmetric_slotting_closed_form():
    """Φxx = Φyy = G, slotting: ``α = [[−πKr, −π], [π, −πKr]]`` has eigenvalues
    ``π(−Kr ± i)``, so ``b = 2π/(N Kt Re λ) = −2/(N Kt (Kr Re G ± Im G))``."""
    f = np.linspace(200.0, 2000.0, 1801)
    g = two_modes(f, (700.0, 1500.0), (0.02, 0.04), (2e7, 4e7))
    teeth, kt, kr = 3, 9e8, 0.25
    depth, _ = zoa_depth_limit(
        g,
        g,
        teeth=teeth,
        tangential_coefficient_n_m2=kt,
        alpha=directional_factors(0.0, math.pi, kr),
    )
    closed = np.stack(
        [-2.0 / (teeth * kt * (kr * g.real + s * g.imag)) for s in (1.0, -1.0)], axis=1
    )
    closed[closed <= 0] = np.nan
    np.testing.assert_allclose(
        np.sort(depth, axis=1), np.sort(closed, axis=1), rtol=RTOL_ALGEBRA, equal_nan=True
    )


def _roots_loop_oracle(f, hxx, hyy, teeth, kt, alpha):
    """Readable form: one ``np.roots`` per frequency (Altintas 2012 §4.4)."""
    out = []
    for fi, x, y in zip(f, hxx, hyy, strict=True):
        a0 = x * y * (alpha[0, 0] * alpha[1, 1] - alpha[0, 1] * alpha[1, 0])
        a1 = alpha[0, 0] * x + alpha[1, 1] * y
        for lam in np.roots([a0, a1, 1.0]):
            kappa = lam.imag / lam.real
            b = -2 * np.pi * lam.real * (1 + kappa**2) / (teeth * kt)
            if lam.real < 0 and b > 0:
                out.append((fi, b, np.pi - 2 * np.arctan(kappa)))
    return np.array(sorted(out))


@pytest.mark.parametrize("milling", ["up", "down"])
@pytest.mark.parametrize("immersion", [0.3, 1.0])
def test_vectorised_eigenvalues_equal_roots_loop(milling, immersion):
    f = np.linspace(100.0, 3000.0, 2901)
    hxx = two_modes(f, (450.0, 1450.0), (0.12, 0.017), (8e6, 1.5e7))
    hyy = two_modes(f, (516.0, 1408.0), (0.025, 0.031), (9.4e6, 1.2e7))
    alpha = directional_factors(*engagement_angles_rad(immersion, milling), 0.598)
    depth, eps = zoa_depth_limit(
        hxx, hyy, teeth=2, tangential_coefficient_n_m2=1.3194e9, alpha=alpha
    )
    ok = np.isfinite(depth)
    got = np.array(
        sorted(zip(np.broadcast_to(f[:, None], depth.shape)[ok], depth[ok], eps[ok], strict=True))
    )
    expected = _roots_loop_oracle(f, hxx, hyy, 2, 1.3194e9, alpha)
    assert got.shape == expected.shape
    # np.roots goes through a companion-matrix eigensolver: ~1e-12 relative agreement.
    np.testing.assert_allclose(got, expected, rtol=1e-9)


def test_up_and_down_milling_agree_for_symmetric_dynamics():
    """With Φxx = Φyy only the eigenvalues of α matter, and they are equal for up- and
    down-milling at the same immersion (mirror symmetry φ → π − φ)."""
    f = np.linspace(300.0, 1200.0, 901)
    g = single_mode(f, 700.0, 0.02, 1e7)
    kw = {
        "teeth": 3,
        "tangential_coefficient_n_m2": 8e8,
        "radial_ratio": 0.3,
        "radial_immersion": 0.3,
        "spindle_speed_rpm": np.linspace(4000, 20000, 400),
    }
    up = stability_lobes(f, g, milling="up", **kw)
    down = stability_lobes(f, g, milling="down", **kw)
    np.testing.assert_allclose(up.depth_limit_m, down.depth_limit_m, rtol=1e-9, equal_nan=True)


# --------------------------------------------------------------------------- envelope


@pytest.fixture(scope="module")
def two_dof_result() -> LobeResult:
    f = np.linspace(100.0, 3000.0, 5801)
    hxx = two_modes(f, (450.0, 1450.0), (0.12, 0.017), (8e6, 1.5e7))
    hyy = two_modes(f, (516.0, 1408.0), (0.025, 0.031), (9.4e6, 1.2e7))
    return stability_lobes(
        f,
        hxx,
        hyy,
        teeth=2,
        tangential_coefficient_n_m2=1.3194e9,
        radial_ratio=0.598,
        radial_immersion=0.5,
        milling="down",
        spindle_speed_rpm=np.linspace(3000, 40000, 3000),
    )


def test_envelope_is_min_over_lobes(two_dof_result):
    r = two_dof_result
    grid = r.spindle_speed_rpm
    stacked = np.full((r.n_lobes, grid.size), np.inf)
    for lobe in r.lobes:
        idx = np.searchsorted(grid, lobe.spindle_speed_rpm)
        np.testing.assert_array_equal(grid[idx], lobe.spindle_speed_rpm)
        stacked[lobe.index, idx] = lobe.depth_limit_m
    np.testing.assert_array_equal(r.depth_limit_m, stacked.min(axis=0))
    np.testing.assert_array_equal(r.governing_lobe, stacked.argmin(axis=0))
    assert [lobe.index for lobe in r.lobes] == list(range(r.n_lobes))


def test_envelope_never_below_absolute_minimum(two_dof_result):
    r = two_dof_result
    assert np.all(np.isfinite(r.depth_limit_m))
    # Linear interpolation between points above the minimum stays above it (1 ulp slack).
    assert np.all(r.depth_limit_m >= r.min_depth_limit_m * (1 - 1e-12))


def test_envelope_reaches_minimum_at_lobe_minimum_speeds(two_dof_result):
    r = two_dof_result
    grid = r.spindle_speed_rpm
    for n in r.min_depth_spindle_speed_rpm:
        if grid[0] < n < grid[-1]:
            j = np.argmin(np.abs(grid - n))
            # The nearest grid speed is within 6.2 rpm (half a step) of the lobe bottom,
            # where the lobe is flat: observed deviations <= 7e-4, so 2e-3 has margin.
            np.testing.assert_allclose(r.depth_limit_m[j], r.min_depth_limit_m, rtol=2e-3)


def test_chatter_frequency_is_inside_frf_band(two_dof_result):
    r = two_dof_result
    assert np.all((r.chatter_frequency_hz >= 100.0) & (r.chatter_frequency_hz <= 3000.0))


def test_envelope_converges_with_frequency_resolution():
    """Interpolating between chatter frequencies is consistent: halving the frequency step
    four times moves the envelope by < 0.5 % (observed 1.5e-3: linear interpolation
    between 1 Hz-spaced chatter frequencies near a 24 Hz-wide resonance)."""
    kw = {
        "teeth": 4,
        "tangential_coefficient_n_m2": 7e8,
        "radial_ratio": 0.3,
        "radial_immersion": 0.5,
        "milling": "down",
        "spindle_speed_rpm": np.linspace(6000, 24000, 600),
    }
    coarse_f = np.linspace(400.0, 1400.0, 1001)
    fine_f = np.linspace(400.0, 1400.0, 16001)
    coarse = stability_lobes(coarse_f, single_mode(coarse_f, 800.0, 0.03, 2e7), **kw)
    fine = stability_lobes(fine_f, single_mode(fine_f, 800.0, 0.03, 2e7), **kw)
    np.testing.assert_allclose(coarse.depth_limit_m, fine.depth_limit_m, rtol=5e-3)
    np.testing.assert_allclose(coarse.chatter_frequency_hz, fine.chatter_frequency_hz, rtol=5e-3)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(scale=st.floats(0.1, 10.0), teeth=st.sampled_from([1, 2, 3, 4, 6]))
def test_scaling_laws(scale, teeth):
    """``b ∝ 1/(N Kt)`` and lobe speeds ``∝ 1/N``: scaled inputs give scaled lobes."""
    f = np.linspace(300.0, 1300.0, 801)
    g = single_mode(f, 800.0, 0.03, 2e7)
    base_grid = np.linspace(4000.0, 30000.0, 200)
    kw = {"radial_ratio": 0.3, "radial_immersion": 0.4, "milling": "up", "n_lobes": 12}
    ref = stability_lobes(
        f, g, teeth=1, tangential_coefficient_n_m2=7e8, spindle_speed_rpm=base_grid, **kw
    )
    r = stability_lobes(
        f,
        g,
        teeth=teeth,
        tangential_coefficient_n_m2=7e8 * scale,
        spindle_speed_rpm=base_grid / teeth,
        **kw,
    )
    np.testing.assert_allclose(
        r.depth_limit_m, ref.depth_limit_m / (teeth * scale), rtol=1e-9, equal_nan=True
    )
    np.testing.assert_allclose(
        r.chatter_frequency_hz, ref.chatter_frequency_hz, rtol=1e-9, equal_nan=True
    )


def test_uncovered_speeds_are_nan_and_null():
    f = np.linspace(400.0, 1400.0, 1001)
    r = stability_lobes(
        f,
        single_mode(f, 800.0, 0.03, 2e7),
        teeth=4,
        tangential_coefficient_n_m2=7e8,
        radial_ratio=0.3,
        radial_immersion=0.5,
        milling="down",
        spindle_speed_rpm=np.linspace(1000, 30000, 300),
        n_lobes=1,
    )
    low = r.spindle_speed_rpm < 8000  # lobe 0 lives above 60·f/(N·2π)·… ≈ 12 000 rpm here
    assert np.all(np.isnan(r.depth_limit_m[low]))
    assert np.all(r.governing_lobe[low] == -1)
    d = r.to_dict()
    assert d["depth_limit_m"][0] is None and d["chatter_frequency_hz"][0] is None


def test_too_few_lobes_never_overstate_stability():
    """Stiff 300 Hz mode + flexible 800 Hz mode, 3 lobes only: at low speeds the 300 Hz
    lobes exist but the governing 800 Hz lobes (k >= 3) are missing. Those speeds must be
    NaN rather than the (higher, unsafe) 300 Hz value; elsewhere the result equals the
    complete one."""
    f = np.linspace(150.0, 1400.0, 2501)
    h = single_mode(f, 300.0, 0.03, 2e8) + single_mode(f, 800.0, 0.03, 2e7)
    kw = {
        "teeth": 4, "tangential_coefficient_n_m2": 7e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
        "milling": "down", "spindle_speed_rpm": np.linspace(1000, 30000, 600),
    }  # fmt: skip
    full = stability_lobes(f, h, **kw)
    few = stability_lobes(f, h, n_lobes=3, **kw)
    assert np.all(np.isfinite(full.depth_limit_m))
    withdrawn = np.isnan(few.depth_limit_m)
    assert withdrawn.sum() > 20 and np.all(few.governing_lobe[withdrawn] == -1)
    kept = ~withdrawn
    np.testing.assert_array_equal(few.depth_limit_m[kept], full.depth_limit_m[kept])
    # without the check, 300 Hz lobes would have been reported at some withdrawn speeds
    lobe_cover = np.zeros(few.spindle_speed_rpm.size, dtype=bool)
    for lobe in few.lobes:
        lobe_cover |= np.isin(few.spindle_speed_rpm, lobe.spindle_speed_rpm)
    assert np.any(withdrawn & lobe_cover)


def test_automatic_lobe_count_covers_the_lowest_speed():
    f = np.linspace(400.0, 1400.0, 1001)
    r = stability_lobes(
        f,
        single_mode(f, 800.0, 0.03, 2e7),
        teeth=4,
        tangential_coefficient_n_m2=7e8,
        radial_ratio=0.3,
        radial_immersion=0.5,
        milling="down",
        spindle_speed_rpm=np.linspace(1000, 30000, 300),
    )
    assert np.all(np.isfinite(r.depth_limit_m))
    assert r.n_lobes == math.ceil(60 * 1400.0 / (4 * 1000.0)) + 1


# --------------------------------------------------------------------------- result object


def test_same_frf_flag_and_contract_dict():
    f = np.linspace(400.0, 1400.0, 501)
    g = single_mode(f, 800.0, 0.03, 2e7)
    kw = {
        "teeth": 4,
        "tangential_coefficient_n_m2": 7e8,
        "radial_ratio": 0.3,
        "radial_immersion": 0.5,
        "milling": "down",
        "spindle_speed_rpm": np.linspace(8000, 30000, 50),
    }
    same = stability_lobes(f, g, **kw)
    given_y = stability_lobes(f, g, 2 * g, **kw)
    assert same.same_frf_in_y and not given_y.same_frf_in_y
    d = same.to_dict()
    assert {"spindle_speed_rpm", "depth_limit_m", "chatter_frequency_hz", "lobes"} <= d.keys()
    assert d["frf_y_source"] == "same_as_x" and given_y.to_dict()["frf_y_source"] == "given"
    assert set(d["lobes"][0]) == {"index", "spindle_speed_rpm", "depth_limit_m"}
    assert d["lobes"][0]["index"] == 0
    assert (
        len(d["spindle_speed_rpm"])
        == len(d["depth_limit_m"])
        == len(d["chatter_frequency_hz"])
        == 50
    )
    json.dumps(d, allow_nan=False)  # strict JSON: no NaN leaks
    assert d["min_depth_limit_m"] == pytest.approx(same.min_depth_limit_m, rel=1e-15)


def test_result_arrays_are_read_only():
    f = np.linspace(400.0, 1400.0, 201)
    r = stability_lobes(
        f,
        single_mode(f, 800.0, 0.03, 2e7),
        teeth=4,
        tangential_coefficient_n_m2=7e8,
        radial_ratio=0.3,
        radial_immersion=0.5,
        milling="down",
        spindle_speed_rpm=np.linspace(8000, 30000, 20),
    )
    for a in (
        r.spindle_speed_rpm,
        r.depth_limit_m,
        r.chatter_frequency_hz,
        r.lobes[0].depth_limit_m,
    ):
        with pytest.raises(ValueError):
            a[0] = 1.0


# --------------------------------------------------------------------------- input errors


def _kwargs(**over):
    f = np.linspace(400.0, 1400.0, 101)
    kw = {
        "frequency_hz": f,
        "frf_xx": single_mode(f, 800.0, 0.03, 2e7),
        "teeth": 4,
        "tangential_coefficient_n_m2": 7e8,
        "radial_ratio": 0.3,
        "radial_immersion": 0.5,
        "milling": "down",
        "spindle_speed_rpm": np.linspace(8000, 30000, 20),
    }
    kw.update(over)
    return kw


@pytest.mark.parametrize(
    ("over", "field"),
    [
        ({"teeth": 0}, "teeth"),
        ({"teeth": 2.5}, "teeth"),
        ({"teeth": True}, "teeth"),
        ({"tangential_coefficient_n_m2": 0.0}, "tangential_coefficient_n_m2"),
        ({"tangential_coefficient_n_m2": float("nan")}, "tangential_coefficient_n_m2"),
        ({"radial_ratio": -0.1}, "radial_ratio"),
        ({"radial_immersion": 0.0}, "radial_immersion"),
        ({"radial_immersion": 1.5}, "radial_immersion"),
        ({"milling": "climb"}, "milling"),
        ({"spindle_speed_rpm": [3000.0, 2000.0]}, "spindle_speed_rpm"),
        ({"spindle_speed_rpm": [0.0, 2000.0]}, "spindle_speed_rpm"),
        ({"frf_xx": np.ones(5)}, "frf_x"),
        ({"frf_yy": np.ones(3)}, "frf_y"),
        ({"n_lobes": 0}, "n_lobes"),
    ],
)
def test_invalid_arguments_name_the_field(over, field):
    with pytest.raises(InputError) as info:
        stability_lobes(**_kwargs(**over))
    assert info.value.field == field


def test_wrong_sign_convention_is_refused():
    kw = _kwargs()
    kw["frf_xx"] = np.conj(kw["frf_xx"])
    with pytest.raises(InputError, match="exp"):
        stability_lobes(**kw)


def test_structure_that_cannot_chatter_is_refused():
    """A static positive spring has Re Φ > 0 everywhere: no positive depth limit."""
    kw = _kwargs()
    kw["frf_xx"] = np.full(kw["frequency_hz"].size, 1e-7 + 0j)
    kw["radial_immersion"] = 1.0
    with pytest.raises(InputError, match="positive depth"):
        stability_lobes(**kw)


# --------------------------------------------------------------------------- request parsing


def _body(**over):
    f = [400.0, 800.0, 1200.0]
    h = single_mode(np.array(f), 800.0, 0.03, 2e7)
    body = {
        "method": "zoa",
        "frf_x": {"frequency_hz": f, "h": {"real": h.real.tolist(), "imag": h.imag.tolist()}},
        "frf_y": None,
        "assembly": None,
        "teeth": 4,
        "tangential_coefficient_n_m2": 6.0e8,
        "radial_ratio": 0.3,
        "radial_immersion": 0.5,
        "milling": "down",
        "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 2000},
    }
    body.update(over)
    return body


def test_parse_contract_example():
    req = parse_lobes_request(_body())
    assert req.teeth == 4 and req.milling == "down" and req.frf_yy is None and req.assembly is None
    np.testing.assert_array_equal(req.spindle_speed_rpm, np.linspace(2000, 30000, 2000))
    np.testing.assert_array_equal(req.frequency_hz, [400.0, 800.0, 1200.0])
    assert req.frf_xx.dtype == complex


def test_parse_with_frf_y_and_with_assembly():
    body = _body()
    body["frf_y"] = body["frf_x"]
    both = parse_lobes_request(body)
    np.testing.assert_array_equal(both.frf_yy, both.frf_xx)  # frf_y is read, not just present
    req = parse_lobes_request(_body(frf_x=None, assembly={"tool": {"length_m": 0.1}}))
    assert req.assembly == {"tool": {"length_m": 0.1}} and req.frf_xx is None
    with pytest.raises(InputError, match="assembly"):
        req.solve()


def test_request_solve_equals_direct_call():
    f = np.linspace(400.0, 1400.0, 201)
    h = single_mode(f, 800.0, 0.03, 2e7)
    body = _body(
        frf_x={"frequency_hz": f.tolist(), "h": {"real": h.real.tolist(), "imag": h.imag.tolist()}},
        spindle_speed_rpm={"start": 8000, "stop": 30000, "count": 100},
    )
    got = parse_lobes_request(body).solve()
    direct = stability_lobes(
        f,
        h,
        teeth=4,
        tangential_coefficient_n_m2=6e8,
        radial_ratio=0.3,
        radial_immersion=0.5,
        milling="down",
        spindle_speed_rpm=np.linspace(8000, 30000, 100),
    )
    np.testing.assert_array_equal(got.depth_limit_m, direct.depth_limit_m)
    assert got.same_frf_in_y


def _frf_y_mismatch():
    body = _body()
    body["frf_y"] = {**body["frf_x"], "frequency_hz": [400.0, 800.0, 1300.0]}
    return body


@pytest.mark.parametrize(
    ("body", "field"),
    [
        (_body(colour="red"), "colour"),
        (_body(frf_x=None), "frf_x"),
        (_body(assembly={"tool": {}}), "frf_x"),
        (_body(frf_x=None, assembly={"tool": {}}, frf_y=_body()["frf_x"]), "frf_y"),
        (_body(teeth="4"), "teeth"),
        (_body(teeth=0), "teeth"),
        (_body(tangential_coefficient_n_m2=-1.0), "tangential_coefficient_n_m2"),
        (_body(radial_immersion=0), "radial_immersion"),
        (_body(radial_immersion=1.01), "radial_immersion"),
        (_body(milling="climb"), "milling"),
        (
            _body(spindle_speed_rpm={"start": 3000, "stop": 2000, "count": 10}),
            "spindle_speed_rpm.stop",
        ),
        (
            _body(spindle_speed_rpm={"start": 2000, "stop": 3000, "count": 1}),
            "spindle_speed_rpm.count",
        ),
        (
            _body(spindle_speed_rpm={"start": 2000, "stop": 3000, "count": 100_001}),
            "spindle_speed_rpm.count",
        ),
        (_body(spindle_speed_rpm={"start": 2000, "stop": 3000}), "spindle_speed_rpm.count"),
        (
            _body(spindle_speed_rpm={"start": 2000, "stop": 3000, "count": 5, "step": 1}),
            "spindle_speed_rpm.step",
        ),
        (
            _body(frf_x={"frequency_hz": [1.0, 2.0], "h": {"real": [1e-7], "imag": [0.0]}}),
            "frf_x.h.real",
        ),
        (
            _body(frf_x={"frequency_hz": [1.0], "h": {"real": [1e-7], "imag": [0.0]}, "x": 1}),
            "frf_x.x",
        ),
        (
            _body(frf_x={"frequency_hz": [2.0, 1.0], "h": {"real": [0, 0], "imag": [0, 0]}}),
            "frf_x.frequency_hz",
        ),
        (_frf_y_mismatch(), "frf_y.frequency_hz"),
    ],
    ids=lambda v: v if isinstance(v, str) else "",
)
def test_parse_errors_name_the_field(body, field):
    with pytest.raises(InputError) as info:
        parse_lobes_request(body)
    assert info.value.field == field


def test_parse_missing_required_and_frequency_mismatch_type():
    body = _body()
    del body["teeth"]
    with pytest.raises(InputError) as info:
        parse_lobes_request(body)
    assert info.value.field == "teeth"
    with pytest.raises(FrequencyMismatch):
        parse_lobes_request(_frf_y_mismatch())
    with pytest.raises(InputError):
        parse_lobes_request([1, 2])

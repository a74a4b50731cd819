"""Modal fit of sampled FRFs (hybrid natural frequencies): one mode per peak, sorted, distinct,
each within its stated uncertainty; and on the real tap test used as a spindle."""

from __future__ import annotations

import numpy as np
import pytest

import rcsa
from rcsa.measured.importers import read_csv
from rcsa.measured.store import MeasurementMeta, MeasurementStore
from rcsa.model.modal_fit import kept_modal_fit, modal_fit, rational_fit, refit_mode
from rcsa.reference import ra1
from tests.helpers import SHARED_DATA

#: (natural frequency Hz, damping ratio, modal constant 1/kg): a close pair at 1380/1450 Hz
MODES = ((600.0, 0.02, 1.0), (1380.0, 0.012, 0.6), (1450.0, 0.015, 0.5), (2500.0, 0.01, 0.3))
F = np.arange(200.0, 3000.0, 1.0)
#: a true mode must lie within this many of its stated standard uncertainties
K_SD = 3.0


def synthetic(noise: float, seed: int, modes=MODES) -> np.ndarray:
    w = 2 * np.pi * F
    h = sum(a / ((2 * np.pi * fn) ** 2 - w**2 + 2j * z * 2 * np.pi * fn * w) for fn, z, a in modes) + 2e-8
    rng = np.random.default_rng(seed)
    return h * (1 + noise * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size)) / np.sqrt(2))


def assert_sorted_and_distinct(fit) -> None:
    f = fit.frequency_hz
    assert np.all(np.diff(f) > 0)
    for a, b in zip(fit.modes[:-1], fit.modes[1:], strict=True):  # never two within a half-power width
        if a.modes_in_band == 2 and a.band_hz == b.band_hz:
            continue  # unless resolved by one two-pole fit
        assert b.frequency_hz - a.frequency_hz > max(a.damping_ratio * a.frequency_hz,
                                                     b.damping_ratio * b.frequency_hz)


@pytest.mark.parametrize("noise", [0.01, 0.03])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_noisy_modes_are_found_once_each_within_their_sd(noise, seed):
    fit = modal_fit(F, synthetic(noise, seed))
    assert_sorted_and_distinct(fit)
    assert len(fit.modes) == len(MODES)
    for mode, (fn, zeta, _) in zip(fit.modes, MODES, strict=True):
        assert 0 < mode.sd_hz < 0.002 * fn
        assert abs(mode.frequency_hz - fn) <= K_SD * mode.sd_hz, (fn, mode)
        assert abs(mode.damping_ratio - zeta) <= K_SD * mode.damping_ratio_sd + 0.05 * zeta, (fn, mode)
    # the close pair is fitted together, the others alone
    assert [m.modes_in_band for m in fit.modes] == [1, 2, 2, 1]


def test_noise_free_modes_are_nearly_exact():
    # the residual terms stand in for the modes outside a band: a model-form error of up to
    # 20 ppm (the close pair), which the spread over band choices covers
    fit = modal_fit(F, synthetic(0.0, 0))
    for mode, (fn, zeta, a) in zip(fit.modes, MODES, strict=True):
        assert mode.frequency_hz == pytest.approx(fn, rel=2e-5)
        assert abs(mode.frequency_hz - fn) <= K_SD * mode.sd_hz + 1e-7 * fn
        assert mode.sd_hz < 1e-5 * fn
        assert mode.damping_ratio == pytest.approx(zeta, rel=1e-3)
        assert mode.residue_1_kg == pytest.approx(a, rel=1e-2)


def test_a_single_noisy_peak_is_one_mode():
    # one broad mode (ζ = 3 %) under 8 % noise: dozens of ripples on top, one mode
    h = synthetic(0.08, 4, modes=((1500.0, 0.03, 1.0),))
    assert len(np.flatnonzero((np.abs(h[1:-1]) > np.abs(h[:-2])) & (np.abs(h[1:-1]) > np.abs(h[2:])))) > 100
    fit = modal_fit(F, h)
    assert len(fit.modes) == 1 and fit.peak_lines.size == 1
    assert abs(fit.modes[0].frequency_hz - 1500.0) <= K_SD * fit.modes[0].sd_hz


def test_rational_fit_needs_enough_lines_and_refit_tracks_a_mode():
    assert rational_fit(F[:4], synthetic(0.0, 0)[:4]) is None
    h = synthetic(0.01, 5)
    mode = modal_fit(F, h).modes[0]
    w = 2 * np.pi * F
    bump = 1e-3 / ((2 * np.pi * 600.0) ** 2 - w**2 + 2j * 0.02 * 2 * np.pi * 600.0 * w)
    again = refit_mode(F, h + bump, mode)  # a 0.1 % change of the mode's constant: same pole
    assert again is not None and again.band_hz == mode.band_hz
    assert again.frequency_hz == pytest.approx(mode.frequency_hz, rel=1e-5)


def test_noise_free_ra1_frf_gives_its_dominant_modes():
    exact = rcsa.predict(ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 1.0}))
    fit = modal_fit(exact.frequency_hz, exact.tool_point.h)
    assert_sorted_and_distinct(fit)
    # the dominant damped resonances (599, 1386, 4034 Hz, docs/physics.md §1.5), sharply determined
    for peak in (599.0, 1386.0, 4034.0):
        k = int(np.argmin(np.abs(fit.frequency_hz - peak)))
        assert abs(fit.frequency_hz[k] - peak) < 3.0 and fit.sd_hz[k] < 0.5


# ---------------------------------------------------------------------------- the real tap test

TAP = SHARED_DATA / "leekunhwee-tool-tap" / "Point_1_Channel_1_CH1.txt"


@pytest.mark.skipif(not TAP.is_file(), reason=f"third-party tap-test data not present at {TAP.parent} "
                                              "(unlicensed, kept outside the repository; set RCSA_SHARED_DATA)")
@pytest.mark.parametrize("plane", ["holder_tip", "spindle_nose"])
def test_real_tap_test_as_a_spindle_gives_sorted_distinct_frequencies(tmp_path, plane):
    store = MeasurementStore(tmp_path / "store")
    m = read_csv(TAP, MeasurementMeta("ubc-mal-2019", "x", plane, "direct_frf"), units="m/N",
                 columns="f,re,im", drop_nonpositive=True)
    doc = ra1({"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 1.0})
    doc["spindle"] = {"measurement_id": store.put(m)}
    if plane == "holder_tip":
        del doc["holder"]
        doc["joints"].pop("spindle_holder")
    result = rcsa.predict(doc, store=store)
    nat = np.array(result["natural_frequencies_hz"])
    sd = np.array(result["natural_frequencies_sd_hz"])
    assert result["natural_frequencies_method"] == "modal_fit"
    assert nat.size == sd.size == len(result["modal_fit"]) and 3 <= nat.size <= 8
    assert np.all(np.diff(nat) > 0.02 * nat[:-1])  # sorted, and no near-duplicates (was 7 in 4014–4029 Hz)
    assert np.all((sd > 0) & (sd < 0.02 * nat))
    assert ((nat > 3900) & (nat < 4300)).sum() == 1  # the noisy broad mode near 4.1 kHz is one mode
    assert len(result["peaks"]) == nat.size  # one peak per mode, not one per ripple
    fit = result["modal_fit"][0]
    assert {"frequency_hz", "damping_ratio", "sd_hz", "band_hz", "modes_in_band"} <= set(fit)


def test_a_kept_fit_is_the_fit_of_the_same_bytes_and_only_of_them():
    h = synthetic(0.01, 7)
    first = kept_modal_fit(F, h)
    assert kept_modal_fit(F.copy(), h.copy()) is first  # found by content, not by identity
    fresh = modal_fit(F, h)
    assert [m.to_dict() for m in first.modes] == [m.to_dict() for m in fresh.modes]
    assert np.array_equal(first.peak_lines, fresh.peak_lines) and not first.peak_lines.flags.writeable
    other = h.copy()
    other[100] *= 1 + 1e-12  # one sample differs in its last bits: another fit
    assert kept_modal_fit(F, other) is not first

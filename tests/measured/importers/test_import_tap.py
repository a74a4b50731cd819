"""Raw tap signals → receptance (H1), windows, double hits; accelerometer mass correction."""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.errors import InputError
from rcsa.measured.importers import (
    add_sensor_mass,
    correct_sensor_mass,
    read_csv,
    read_tap,
    remove_sensor_mass,
)
from rcsa.measured.importers.tap import h1_estimate

from ._synth import ARTIFACT_META, META, two_mode_receptance

FS = 20480.0
N = 20480  # 1 s record: 1 Hz bins
T = np.arange(N) / FS
#: Below the first zero of the 1 ms half-sine pulse's spectrum (1.5 kHz), |F| stays large, so
#: the FFT round trip (≈1e-16 of the largest bin) stays far below the 1e-9 tolerance used here.
F_MAX = 1000.0


def _pulse(t0: float = 0.01, width: float = 1e-3, peak: float = 200.0) -> np.ndarray:
    x = np.where((T >= t0) & (T <= t0 + width), peak * np.sin(np.pi * (T - t0) / width), 0.0)
    return np.clip(x, 0.0, None)


def _acceleration(force: np.ndarray, h_of_f=two_mode_receptance) -> np.ndarray:
    f = np.fft.rfftfreq(N, 1 / FS)
    accelerance = -((2 * np.pi * f) ** 2) * h_of_f(f)
    return np.fft.irfft(np.fft.rfft(force) * accelerance, n=N)


def _write(path, *cols) -> str:
    path.write_text(
        "".join("\t".join(f"{v:.17g}" for v in row) + "\n" for row in zip(*cols, strict=True))
    )
    return path


def test_h1_of_a_synthetic_tap_is_the_receptance(tmp_path):
    force = _pulse()
    path = _write(tmp_path / "tap.txt", T, force, _acceleration(force) / 9.80665)
    m = read_tap(path, META, force_unit="N", response_unit="g", max_frequency_hz=F_MAX)
    np.testing.assert_array_equal(m.frequency_hz, np.arange(1.0, F_MAX + 1))
    np.testing.assert_allclose(m.frfs["h"], two_mode_receptance(m.frequency_hz), rtol=1e-9, atol=0)
    assert m.provenance.original_quantity == "accelerance" and not m.coherence
    assert "0 Hz bin dropped" in m.provenance.conversions[1]
    assert np.all(m.frfs["h"].imag <= 0)  # e^{iwt}: damped driving point


def test_several_taps_average_with_coherence(tmp_path):
    paths = []
    for k, peak in enumerate((150.0, 260.0)):
        force = _pulse(t0=0.01 + 0.002 * k, peak=peak)
        paths.append(_write(tmp_path / f"tap{k}.txt", T, force, _acceleration(force)))
    m = read_tap(paths, META, force_unit="N", response_unit="m/s^2", max_frequency_hz=F_MAX)
    np.testing.assert_allclose(m.frfs["h"], two_mode_receptance(m.frequency_hz), rtol=1e-9, atol=0)
    np.testing.assert_allclose(m.coherence["h"], 1.0, rtol=0, atol=1e-9)


def test_h1_estimate_with_noise_has_coherence_below_one():
    rng = np.random.default_rng(7)
    force = [_pulse(peak=p) for p in (100.0, 200.0, 300.0)]
    resp = [_acceleration(fk) + rng.normal(0, 5.0, N) for fk in force]
    f, h1, coh = h1_estimate(force, resp, 1 / FS)
    assert f[0] == 0 and coh is not None
    band = (f > 100) & (f < F_MAX)
    assert 0.0 < coh[band].min() < 1.0 and coh[band].max() <= 1.0 + 1e-12


def test_force_and_exponential_windows(tmp_path):
    force = _pulse()
    acc = _acceleration(force)
    noisy = force + np.where(
        T > 0.2, 0.5 * np.sin(2 * np.pi * 50 * T), 0.0
    )  # noise after the pulse
    clean = read_tap(
        _write(tmp_path / "c.txt", T, force, acc),
        META,
        force_unit="N",
        response_unit="m/s^2",
        max_frequency_hz=F_MAX,
    )
    windowed = read_tap(
        _write(tmp_path / "n.txt", T, noisy, acc),
        META,
        force_unit="N",
        response_unit="m/s^2",
        max_frequency_hz=F_MAX,
        force_window_s=0.01,
    )
    assert (
        windowed.frfs["h"].tobytes() == clean.frfs["h"].tobytes()
    )  # the window removed exactly the noise
    expo = read_tap(
        tmp_path / "c.txt",
        META,
        force_unit="N",
        response_unit="m/s^2",
        max_frequency_hz=F_MAX,
        exponential_tau_s=0.05,
    )
    assert any("exponential window tau=0.05 s" in c for c in expo.provenance.conversions)
    # the added damping lowers the resonance peak
    assert np.abs(expo.frfs["h"]).max() < np.abs(clean.frfs["h"]).max()


def test_tap_refusals_name_the_field(tmp_path):
    force = _pulse()
    acc = _acceleration(force)
    good = _write(tmp_path / "g.txt", T, force, acc)
    twice = _write(tmp_path / "d.txt", T, force + _pulse(t0=0.3, peak=120.0), acc)
    bumpy_t = T.copy()
    bumpy_t[100] += 0.5 / FS
    cases = [
        (lambda: read_tap(twice, META, force_unit="N", response_unit="m/s^2"), "force"),
        (
            lambda: read_tap(
                _write(tmp_path / "t.txt", bumpy_t, force, acc),
                META,
                force_unit="N",
                response_unit="m/s^2",
            ),
            "t",
        ),
        (
            lambda: read_tap(good, META, force_unit="N", response_unit="m/s^2", columns="t,force"),
            "columns",
        ),
        (lambda: read_tap(good, META, force_unit="m/s^2", response_unit="m/s^2"), "force_unit"),
        (lambda: read_tap(good, META, force_unit="N", response_unit=""), "response_unit"),
        (
            lambda: read_tap(
                good, META, force_unit="N", response_unit="m/s^2", sample_rate_hz=10000.0
            ),
            "sample_rate_hz",
        ),
        (lambda: read_tap(good, ARTIFACT_META, force_unit="N", response_unit="m/s^2"), "kind"),
    ]
    for build, field in cases:
        with pytest.raises(InputError) as err:
            build()
        assert err.value.field == field, str(err.value)
    m = read_tap(
        twice,
        META,
        force_unit="N",
        response_unit="m/s^2",
        allow_double_hit=True,
        max_frequency_hz=F_MAX,
    )
    assert m.n_frequencies == F_MAX


def test_sensor_mass_correction_inverts_the_mass_loading(tmp_path):
    f = np.arange(20.0, 3000.0, 2.0)
    h = two_mode_receptance(f)
    mass_kg = 0.012
    measured = add_sensor_mass(f, h, mass_kg)
    assert np.abs(measured - h).max() > 0.05 * np.abs(h).max()  # the mass matters here
    # one division each way: relative error a few ulp of the (1 ± w^2 m H) factors
    np.testing.assert_allclose(remove_sensor_mass(f, measured, mass_kg), h, rtol=1e-12, atol=0)
    (tmp_path / "m.csv").write_text(
        "".join(f"{a:.17g},{b.real:.17g},{b.imag:.17g}\n" for a, b in zip(f, measured, strict=True))
    )
    m = read_csv(tmp_path / "m.csv", META, units="m/N", columns="f,re,im", sensor_mass_kg=mass_kg)
    np.testing.assert_allclose(m.frfs["h"], h, rtol=1e-12, atol=0)
    assert m.provenance.sensor_mass_kg == mass_kg
    assert any("sensor mass 0.012 kg removed" in c for c in m.provenance.conversions)
    with pytest.raises(InputError, match="already corrected"):
        correct_sensor_mass(m, mass_kg)
    with pytest.raises(InputError) as err:
        remove_sensor_mass(f, measured, -1.0)
    assert err.value.field == "sensor_mass_kg"

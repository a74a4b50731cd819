"""Tap files with few-digit time stamps: the sample rate is the roundest one the stamps allow,
the frequency grid is exact, and a hybrid request up to the last line is inside the band.

Tolerances: the synthetic taps are computed exactly at 51.2 kHz and written with 17 digits
(signals) while only the stamps are rounded, so H1 equals the truth to the FFT round trip
(1e-9 below the pulse spectrum's first zero, as in test_import_tap).
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.errors import InputError
from rcsa.measured.hybrid import measured_base
from rcsa.measured.importers import read_tap
from rcsa.measured.importers.tap import roundest_within, sample_rate_from_time
from rcsa.measured.store import MeasurementStore

from ._synth import META, two_mode_receptance

FS = 51200.0
N = 5120  # 0.1 s: 10 Hz lines
T = np.arange(N) / FS


def _tap(stamp_fmt: str, t=T) -> str:
    width = 1e-3
    force = np.where(T <= width, 200.0 * np.sin(np.pi * T / width), 0.0).clip(0.0)
    f = np.fft.rfftfreq(N, 1 / FS)
    acc = np.fft.irfft(np.fft.rfft(force) * -((2 * np.pi * f) ** 2) * two_mode_receptance(f), n=N)
    return "".join(
        f"{stamp_fmt % a}\t{b:.17g}\t{c:.17g}\n" for a, b, c in zip(t, force, acc, strict=True)
    )


@pytest.mark.parametrize("stamp_fmt", ["%.6e", "%.7f", "%.17g", "%.9e"])
def test_rate_from_rounded_stamps_gives_an_exact_grid(tmp_path, stamp_fmt):
    path = tmp_path / "tap.txt"
    path.write_text(_tap(stamp_fmt))
    m = read_tap(path, META, force_unit="N", response_unit="m/s^2", max_frequency_hz=1000.0)
    np.testing.assert_array_equal(m.frequency_hz, np.arange(10.0, 1001.0, 10.0))
    np.testing.assert_allclose(m.frfs["h"], two_mode_receptance(m.frequency_hz), rtol=1e-9, atol=0)
    assert "sample rate 51200 Hz from the time column" in m.provenance.conversions[0]


def test_seven_digit_stamps_then_a_hybrid_request_up_to_the_last_line(tmp_path):
    """The reported defect: 7-digit stamps gave 0.99999997-Hz lines, and 100-5000 Hz was
    'outside the measured band 1-5000 Hz'."""
    path = tmp_path / "tap.txt"
    path.write_text(_tap("%.6e"))
    t = np.loadtxt(path, usecols=0)
    assert 1 / ((t[-1] - t[0]) / (N - 1)) != FS  # the raw estimate is off in the 8th digit
    m = read_tap(path, META, force_unit="N", response_unit="m/s^2", max_frequency_hz=5000.0)
    assert m.frequency_hz[-1] == 5000.0 and m.frequency_hz[0] == 10.0
    store = MeasurementStore(tmp_path / "store")
    mid = store.put(m)
    base = measured_base(mid, np.arange(100.0, 5001.0, 10.0), store)
    assert base is not None


def test_declared_rate_wins_within_one_percent_and_is_refused_beyond(tmp_path):
    path = tmp_path / "tap.txt"
    path.write_text(_tap("%.6e"))
    kw = {"force_unit": "N", "response_unit": "m/s^2", "max_frequency_hz": 1000.0}
    same = read_tap(path, META, sample_rate_hz=51200.0, **kw)
    auto = read_tap(path, META, **kw)
    assert same.frfs["h"].tobytes() == auto.frfs["h"].tobytes()
    assert "(declared; the time column gives 51200 Hz)" in same.provenance.conversions[0]
    with pytest.raises(
        InputError, match="52500 Hz was declared but the time column gives 51200 Hz"
    ) as err:
        read_tap(path, META, sample_rate_hz=52500.0, **kw)
    assert err.value.field == "sample_rate_hz"
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(InputError) as err:
            read_tap(path, META, sample_rate_hz=bad, **kw)
        assert err.value.field == "sample_rate_hz"


def test_a_missing_sample_is_refused(tmp_path):
    t = np.delete(T, 300)
    with pytest.raises(InputError, match=r"not uniform: step 300 .*missing or repeated") as err:
        sample_rate_from_time(t, "tap.txt: ")
    assert err.value.field == "t"


@pytest.mark.parametrize(
    ("fs", "n", "fmt"),
    [
        (51200.0, 51200, "%.6e"),
        (1024.0, 1024, "%.3e"),
        (48000.0, 4800, "%.5e"),
        (25600.0, 2560, "%.8f"),
    ],
)
def test_rate_from_stamps_of_various_precision(fs, n, fmt):
    t = np.array([float(fmt % x) for x in np.arange(n) / fs])
    rate, how = sample_rate_from_time(t)
    assert rate == fs, how


def test_roundest_within():
    assert roundest_within(51199.99847, 0.0052) == 51200.0
    assert roundest_within(20480.000000000004, 4e-11) == 20480.0
    assert roundest_within(12345.6781, 0.0012) == 12345.678
    assert roundest_within(0.99999997, 1e-9) == 0.99999997

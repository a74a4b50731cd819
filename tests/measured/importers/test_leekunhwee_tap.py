"""Real tap-test data (leekunhwee/Vibration-Signal-Processing, UBC MAL 2019).

The files are third-party and unlicensed: they are read from the shared data directory
next to the repository and never copied into it; without that directory these tests skip.
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.errors import InputError
from rcsa.measured.importers import read_csv, read_tap
from rcsa.measured.store import MeasurementMeta, MeasurementStore
from tests.helpers import SHARED_DATA

DATA = SHARED_DATA / "leekunhwee-tool-tap"
POINT_1 = DATA / "Point_1_Channel_1_CH1.txt"
RAW_TAP = DATA / "ImpactTesting_Point1_Channel1_CH1.txt"
META = MeasurementMeta(
    "ubc-mal-2019", "x", "holder_tip", "direct_frf", notes="tool tip H11 (leekunhwee)"
)

pytestmark = pytest.mark.skipif(
    not (POINT_1.is_file() and RAW_TAP.is_file()),
    reason=f"third-party tap-test data not present at {DATA} (kept outside the repository; set RCSA_SHARED_DATA)",
)


def _point_1():
    return read_csv(POINT_1, META, units="m/N", columns="f,re,im", drop_nonpositive=True)


def test_point_1_imports_as_a_direct_frf_and_stores_bit_exact(tmp_path):
    with pytest.raises(InputError) as err:  # row 0 is 0 Hz: refused unless dropped explicitly
        read_csv(POINT_1, META, units="m/N", columns="f,re,im")
    assert err.value.field == "frequency_hz" and "line 1" in err.value.rule
    m = _point_1()
    assert m.n_frequencies == 5000 and m.frequency_hz[0] == 1.0 and m.frequency_hz[-1] == 5000.0
    assert m.provenance.conversions == ("dropped 1 row(s) at f <= 0 Hz",)
    band = m.frequency_hz >= 200
    i = int(np.argmax(np.abs(m.frfs["h"][band])))
    assert m.frequency_hz[band][i] == 1056.0
    # the data's own SOURCE.md (beside it, outside the repository): |H11| peak 6.78e-7 m/N at 1056 Hz (3 significant digits)
    assert abs(np.abs(m.frfs["h"][band][i]) / 6.78e-7 - 1) < 5e-3
    store = MeasurementStore(tmp_path / "store")
    got = store.get(store.put(m))
    assert got.frfs["h"].tobytes() == m.frfs["h"].tobytes()
    assert (
        got.provenance.source_sha256
        == "db1e513a982afbb9aa60a930f9e2b430c378bd6e0409338887b29e6358fddbcb"
    )


def test_raw_tap_reproduces_point_1():
    ref = _point_1()
    tap = read_tap(
        RAW_TAP,
        META,
        force_unit="N",
        response_unit="m/s^2",
        sample_rate_hz=51200.0,
        max_frequency_hz=5000.0,
    )
    np.testing.assert_array_equal(tap.frequency_hz, ref.frequency_hz)  # 1 s record: 1 Hz bins
    ratio = {
        f: abs(tap.frfs["h"][int(f) - 1]) / abs(ref.frfs["h"][int(f) - 1]) - 1
        for f in (500, 1056, 1935, 2607)
    }
    # Measured here: +0.11 % at 500 Hz, -0.21 % at 1056 Hz (the dominant tool mode).
    assert abs(ratio[500]) <= 0.01 and abs(ratio[1056]) <= 0.01, ratio
    # Measured here: +2.19 % at 1935 Hz and +1.06 % at 2607 Hz. The data's SOURCE.md claims 0.3 % at all
    # four; no processing of this single tap reproduces that (plain H1, exponential windows of
    # 0.02-0.5 s, a sensor mass of ±4 g all leave >= 1 % at 1935 Hz). The ratio is smooth
    # across each mode, so Point_1 is most likely an average of several taps of which this
    # is one. The bound below pins today's result with ~15 % headroom, not the 1 % goal.
    assert abs(ratio[1935]) <= 0.025 and abs(ratio[2607]) <= 0.0125, ratio
    # phase agrees too: |H_tap/H_ref - 1| measured 0.2 %, 1.2 %, 2.4 %, 1.3 % at the four
    for f in ratio:
        i = int(f) - 1
        assert abs(tap.frfs["h"][i] / ref.frfs["h"][i] - 1) <= 0.03, f


def test_raw_tap_rate_from_its_seven_digit_stamps(tmp_path):
    """The stamps carry 7 significant digits (9.999805e-001): the rate is 51200 Hz, not the
    raw 51199.998 Hz, so the lines are exactly 1..5000 Hz and a hybrid request over 100-5000
    Hz is inside the band (it was refused as 'outside the measured band 1-5000 Hz')."""
    from rcsa.measured.hybrid import measured_base

    auto = read_tap(RAW_TAP, META, force_unit="N", response_unit="m/s^2", max_frequency_hz=5000.0)
    np.testing.assert_array_equal(auto.frequency_hz, np.arange(1.0, 5001.0))
    assert "sample rate 51200 Hz from the time column" in auto.provenance.conversions[0]
    declared = read_tap(
        RAW_TAP,
        META,
        force_unit="N",
        response_unit="m/s^2",
        sample_rate_hz=51200.0,
        max_frequency_hz=5000.0,
    )
    assert auto.frfs["h"].tobytes() == declared.frfs["h"].tobytes()
    store = MeasurementStore(tmp_path / "store")
    measured_base(store.put(auto), np.arange(100.0, 5001.0, 1.0), store)

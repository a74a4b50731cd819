"""Property: any finite float64/complex128 data (subnormals, -0.0, extremes) round-trips
bit-exactly through the store (gzip + shuffle + Fletcher-32 are lossless)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from rcsa.measured.store import Measurement, MeasurementMeta, MeasurementStore

finite = st.floats(allow_nan=False, allow_infinity=False, allow_subnormal=True)


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return MeasurementStore(tmp_path_factory.mktemp("prop") / "store")


@given(data=st.data(), n=st.integers(1, 40))
def test_arbitrary_finite_values_round_trip_bit_exact(store, data, n):
    steps = data.draw(hnp.arrays(np.float64, n, elements=st.floats(1e-6, 1e6)))
    f = 1e-3 + np.cumsum(steps)
    if np.any(np.diff(f) <= 0):  # steps lost to rounding at large sums
        return
    re = data.draw(hnp.arrays(np.float64, n, elements=finite))
    im = data.draw(hnp.arrays(np.float64, n, elements=finite))
    h = np.empty(n, dtype=np.complex128)
    h.real, h.imag = re, im  # keeps -0.0 and subnormals exactly (re + 1j*im would not)
    m = Measurement(f, {"h": h}, MeasurementMeta("prop", "x", "spindle_nose", "direct_frf"))
    got = store.get(store.put(m))
    assert got.frequency_hz.tobytes() == m.frequency_hz.tobytes()
    assert got.frfs["h"].tobytes() == m.frfs["h"].tobytes()

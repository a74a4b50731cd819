"""Plausibility bounds: absurd values are refused with the row, the value and the bound,
whatever format they came in; values at the edge of the physically possible still pass."""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.errors import InputError
from rcsa.measured.importers import measurement_from_contract, read_uff
from rcsa.measured.importers.bounds import (
    BOUNDS_BY_UNIT,
    MAX_FREQUENCY_HZ,
    MAX_RECEPTANCE_M_N,
    MIN_RECEPTANCE_M_N,
)

from ._synth import META, frf58, two_mode_receptance, write_uff

F = np.arange(20.0, 2020.0, 20.0)
H = two_mode_receptance(F)


def _doc(f=F, h=H, kind="direct_frf", **frfs):
    doc = {"spindle_id": "s", "direction": "x", "plane": "spindle_nose", "kind": kind,
           "frequency_hz": list(map(float, f))}  # fmt: skip
    for name, v in {"h": h, **frfs}.items():
        doc[name] = {"real": np.real(v).tolist(), "imag": np.imag(v).tolist()}
    return doc


@pytest.mark.parametrize(
    ("scale", "side"),
    [(1e9, "above"), (1e-9, "below")],  # nm/N values read as m/N, and the reverse
)
def test_magnitude_out_of_bounds_is_refused_with_row_and_value(scale, side):
    h = H.copy()
    h[7] *= scale
    with pytest.raises(InputError) as err:
        measurement_from_contract(_doc(h=h))
    e = err.value
    assert e.field == "h" and f"index 7 at {F[7]:g} Hz" in e.rule and side in e.rule, e.rule
    assert "1 of 100 values" in e.rule


def test_exact_zero_and_huge_values_are_refused():
    for v in (0.0, 1.7e308, 1.8e308):  # 1.8e308 parses as inf
        h = H.copy()
        h[3] = v
        with pytest.raises(InputError, match="index 3") as err:
            measurement_from_contract(_doc(h=h))
        assert err.value.field == "h"


def test_edges_of_the_bounds_pass():
    h = np.full(F.size, MAX_RECEPTANCE_M_N * (1 - 1e-12), dtype=complex)
    h[::2] = MIN_RECEPTANCE_M_N * (1 + 1e-12)
    m = measurement_from_contract(_doc(h=h))
    assert m.frfs["h"].tobytes() == h.tobytes()


def test_rotational_receptances_have_their_own_bounds():
    assert BOUNDS_BY_UNIT["rad/(N*m)"] == pytest.approx((1e-13, 1e4))
    l_ = n_ = -40 * H
    p = 2000 * H  # ~1e-4 rad/(N m): fine for p, too large for h
    m = measurement_from_contract(_doc(kind="point_receptance", l=l_, n=n_, p=p))
    assert m.frfs["p"].tobytes() == p.tobytes()
    with pytest.raises(InputError) as err:
        measurement_from_contract(_doc(kind="point_receptance", l=l_, n=n_, p=p * 1e9))
    assert err.value.field == "p" and "rad/(N*m)" in err.value.rule


def test_frequency_above_the_bound_is_refused():
    f = F.copy()
    f[-1] = 1.7e308
    with pytest.raises(InputError) as err:
        measurement_from_contract(_doc(f=f))
    assert err.value.field == "frequency_hz" and f"{MAX_FREQUENCY_HZ:g} Hz" in err.value.rule


def test_pyuff_writes_inf_as_the_largest_double_which_is_refused_by_the_number_policy(tmp_path):
    h = H.copy()
    h[5] = np.inf  # pyuff's writer turns inf into 1.7976931348623157e308 (np.nan_to_num)
    path = write_uff(tmp_path / "inf.uff", [frf58(F, h, binary=1)], (1, 1.0, 1.0))
    with pytest.raises(InputError) as err:
        read_uff(path, META)
    assert err.value.field == "h" and "row 6, column 1 (real)" in err.value.rule, str(err.value)
    assert "out of range" in err.value.rule


def test_accelerance_is_judged_after_conversion(tmp_path):
    """1e3 (m/s^2)/N at 20 Hz is 6e-2 m/N (fine); 1e6 is 63 m/N (refused)."""
    a = -((2 * np.pi * F) ** 2) * H
    a[0] = 1e6
    path = write_uff(tmp_path / "a.uff", [frf58(F, a, binary=1, numerator=12)], (1, 1.0, 1.0))
    with pytest.raises(InputError, match=r"index 0 at 20 Hz has \|h\| = 63\.3 m/N"):
        read_uff(path, META)

"""The shared ``measurements`` parser of identification and diagnosis requests."""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.analysis.measured_tool_point import parse_tap_tests
from rcsa.errors import InputError
from rcsa.physics.materials import BUILTIN_MATERIALS
from rcsa.reference import ra1

TOOL = ra1()["tool"]


def tap(n=20, **changes):
    f = np.linspace(100.0, 2000.0, n)
    m = {"tool": {"stickout_m": 0.06}, "frequency_hz": f.tolist(),
         "h": {"real": (1e-7 * np.ones(n)).tolist(), "imag": (-1e-8 * np.ones(n)).tolist()}}
    m.update(changes)
    return m


def test_overrides_apply_to_the_base_tool_and_arrays_are_read_only():
    (t,) = parse_tap_tests([tap(coherence=[0.9] * 20, label="a")], TOOL, BUILTIN_MATERIALS, extra_fields=("label",))
    assert t.tool.stickout_m == 0.06 and t.tool.diameter_m == TOOL["diameter_m"]
    assert t.overrides == {"stickout_m": 0.06} and t.extra == {"label": "a"}
    assert not t.frequency_hz.flags.writeable and not t.h.flags.writeable and not t.coherence.flags.writeable


@pytest.mark.parametrize("measurement, field", [
    (tap(colour="red"), "measurements[0].colour"),
    (tap(tool={"stickout_mm": 60}), "measurements[0].tool.stickout_mm"),
    (tap(tool={"stickout_m": 0.5}), "measurements[0].tool.stickout_m"),
    (tap(frequency_hz=[3.0, 2.0] + list(range(4, 22))), "measurements[0].frequency_hz"),
    (tap(h={"real": [1e-7] * 19, "imag": [0.0] * 19}), "measurements[0].h.real"),
    (tap(h={"real": [0.0] * 20, "imag": [0.0] * 20}), "measurements[0].h"),
    (tap(coherence=[1.5] * 20), "measurements[0].coherence"),
    (tap(n=5), "measurements[0].frequency_hz"),
])
def test_bad_measurements_name_the_field(measurement, field):
    with pytest.raises(InputError) as info:
        parse_tap_tests([measurement], TOOL, BUILTIN_MATERIALS, min_lines=16)
    assert info.value.field == field


def test_list_bounds():
    with pytest.raises(InputError, match="non-empty list"):
        parse_tap_tests([], TOOL, BUILTIN_MATERIALS)
    with pytest.raises(InputError, match="at most 2 measurements"):
        parse_tap_tests([tap()] * 3, TOOL, BUILTIN_MATERIALS, max_tests=2)

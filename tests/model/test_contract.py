"""Bad input gets a clear error naming the field and the rule — never a traceback or a NaN."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import rcsa
from rcsa.errors import InputError
from rcsa.model.contract import parse_assembly, parse_frequency
from rcsa.reference import ra1


def edited(path: str, value=None, delete: bool = False) -> dict:
    doc = ra1({"start_hz": 100.0, "stop_hz": 200.0, "step_hz": 10.0})
    node = doc
    keys = [int(k) if k.isdigit() else k for k in path.replace("[", ".").replace("]", "").split(".")]
    for k in keys[:-1]:
        node = node[k]
    if delete:
        del node[keys[-1]]
    else:
        node[keys[-1]] = value
    return doc


BAD = [
    # (path, value, expected field, words in the rule)
    ("holder.segments[1].length_m", 0.0, "holder.segments[1].length_m", "> 0"),
    ("holder.segments[0].length_m", -0.01, "holder.segments[0].length_m", "> 0"),
    ("spindle.segments[2].outer_diameter_m", 0.0, "spindle.segments[2].outer_diameter_m", "> 0"),
    ("holder.segments[2].inner_diameter_m", 0.032, "holder.segments[2].inner_diameter_m", "smaller than outer"),
    ("spindle.segments[4].inner_diameter_m", 0.09, "spindle.segments[4].inner_diameter_m", "smaller than outer"),
    ("spindle.bearings[3].position_m", 0.6, "spindle.bearings[3].position_m", "outside the spindle"),
    ("spindle.bearings[0].position_m", -0.1, "spindle.bearings[0].position_m", ">= 0"),
    ("tool.stickout_m", 0.2, "tool.stickout_m", "<= overall_length_m"),
    ("tool.flute_length_m", 0.08, "tool.flute_length_m", "<= stickout_m"),
    ("tool.diameter_m", "12.7", "tool.diameter_m", "must be a number"),
    ("tool.material", "unobtainium", "tool.material", "unknown material"),
    ("holder.segments[0].material", "wood", "holder.segments[0].material", "unknown material"),
    ("frequency", {"start_hz": 0.0, "stop_hz": 10.0, "step_hz": 1.0}, "frequency.start_hz", "> 0"),
    ("frequency", {"start_hz": 10.0, "stop_hz": 5.0, "step_hz": 1.0}, "frequency.stop_hz", ">= start_hz"),
    ("frequency", {"values_hz": [10.0, 5.0]}, "frequency.values_hz", "strictly increasing"),
    ("frequency", {"values_hz": [0.0, 5.0]}, "frequency.values_hz", "> 0 Hz"),
    ("frequency", {"values_hz": [-3.0]}, "frequency.values_hz", "> 0 Hz"),
    ("frequency", {"start_hz": 1.0, "stop_hz": 10.0, "step_hz": 0.0}, "frequency.step_hz", "> 0"),
    ("frequency", {"start_hz": 1.0, "stop_hz": 10.0}, "frequency.step_hz", "is required"),
    ("tool.colour", "red", "tool.colour", "unknown field"),
    ("joints.holder_tool.stiffness", 1e7, "joints.holder_tool.stiffness", "unknown field"),
    ("joints.holder_tool.stiffness_n_m", 0.0, "joints.holder_tool.stiffness_n_m", "> 0"),
    ("beam_theory", "bernoulli", "beam_theory", "must be one of"),
    ("shear_coefficient", "magic", "shear_coefficient", "must be one of"),
    ("materials", {"steel": {"poisson_ratio": 0.7}}, "materials.steel.poisson_ratio", "< 0.5"),
    ("materials", {"ti": {"youngs_modulus_pa": 1.1e11}}, "materials.ti.poisson_ratio", "is required"),
    ("spindle.segments", [], "spindle.segments", "non-empty"),
    ("tool.fluted_diameter_ratio", 1.3, "tool.fluted_diameter_ratio", "<= 1"),
    ("tool.diameter_m", float("nan"), "tool.diameter_m", "finite"),
]


@pytest.mark.parametrize("path, value, field, words", BAD, ids=[f"{b[0]}={b[1]!r}" for b in BAD])
def test_bad_input_names_field_and_rule(path, value, field, words):
    with pytest.raises(InputError) as info:
        rcsa.predict(edited(path, value))
    assert info.value.field == field
    assert words in info.value.rule


@pytest.mark.parametrize("path, field", [("tool", "tool"), ("frequency", "frequency"), ("spindle", "spindle"),
                                         ("holder", "holder"), ("tool.overall_length_m", "tool.overall_length_m")])
def test_missing_required_parts(path, field):
    with pytest.raises(InputError) as info:
        parse_assembly(edited(path, delete=True))
    assert info.value.field == field


def test_shank_wider_than_bore_is_refused():
    doc = edited("tool.shank_diameter_m", 0.016)
    with pytest.raises(InputError, match="does not fit the bore"):
        rcsa.predict(doc)


def test_frequency_line_limit():
    with pytest.raises(InputError, match="at most 100 frequency lines"):
        parse_frequency({"start_hz": 1.0, "stop_hz": 1000.0, "step_hz": 1.0}, max_lines=100)


def test_grid_includes_stop_and_avoids_accumulation():
    f = parse_frequency({"start_hz": 5.0, "stop_hz": 10000.0, "step_hz": 0.1})
    assert f.size == 99951 and f[-1] == pytest.approx(10000.0, abs=1e-9)
    assert not f.flags.writeable


def test_valid_input_is_not_modified_and_gives_finite_results():
    doc = edited("tool.stickout_m", 0.06)
    before = copy.deepcopy(doc)
    result = rcsa.predict(doc)
    assert doc == before
    assert np.all(np.isfinite(result.tool_point.values))


@pytest.mark.parametrize("path, value, field", [
    ("frequency", {"start_hz": 1.0, "stop_hz": 1e7, "step_hz": 1e-300}, "frequency"),
    ("frequency", {"start_hz": 1.0, "stop_hz": 1e9, "step_hz": 1.0}, "frequency.stop_hz"),
    ("frequency", {"values_hz": [1.0, 1e12]}, "frequency.values_hz"),
    ("holder.segments[0].outer_diameter_m", 5e-324, "holder.segments[0].outer_diameter_m"),
    ("tool.diameter_m", 1e200, "tool.diameter_m"),
    ("materials", {"steel": {"youngs_modulus_pa": 1e300}}, "materials.steel.youngs_modulus_pa"),
    ("joints.holder_tool.stiffness_n_m", 1e300, "joints.holder_tool.stiffness_n_m"),
])
def test_absurd_magnitudes_are_refused_before_they_overflow(path, value, field):
    with pytest.raises(InputError) as info:
        rcsa.predict(edited(path, value))
    assert info.value.field == field

"""Fusion libraries as vendors write them: variants of the sample library, each read right or refused.

Built in tmp from ``tests/data/tool-libraries/fusion-synthetic/synthetic_library.json``:
numbers stored as strings, HSS and other tool materials, a shallow insertion, conical necks
and holders. Every variant is compared with the sample it came from: either the same
numbers (strings read as numbers), or a refusal naming the field, never a silently
different tool.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from rcsa.libraries import library_combinations
from rcsa.libraries.library_prediction import predict_library
from rcsa.libraries.tool_materials import tool_material
from rcsa.model.contract import parse_tool
from rcsa.physics.materials import BUILTIN_MATERIALS
from rcsa.reference import ra1

SAMPLE = Path(__file__).resolve().parents[1] / "data" / "tool-libraries" / "fusion-synthetic" / "synthetic_library.json"
GRID = {"start_hz": 100.0, "stop_hz": 3000.0, "step_hz": 100.0}


def sample() -> dict:
    return json.loads(SAMPLE.read_text())


def write(tmp_path: Path, doc: dict, name: str = "variant.json") -> Path:
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    return path


def stringify(obj: object, unit: str | None = None) -> object:
    """Every number as a string, lengths with ``unit`` appended when given (booleans kept)."""
    if isinstance(obj, dict):
        return {k: stringify(v, unit) for k, v in obj.items()}
    if isinstance(obj, list):
        return [stringify(v, unit) for v in obj]
    if isinstance(obj, bool) or not isinstance(obj, int | float):
        return obj
    return f"{obj} {unit}" if unit else str(obj)


# --------------------------------------------------------------------------- numbers as strings


def test_numbers_stored_as_strings_read_as_the_same_numbers(tmp_path):
    ref = library_combinations(SAMPLE).to_dict()
    doc = sample()
    for item in doc["data"]:
        item["geometry"] = stringify(item.get("geometry"))
        if isinstance(item.get("holder"), dict):
            item["holder"]["gaugeLength"] = str(item["holder"].get("gaugeLength"))
            item["holder"]["segments"] = stringify(item["holder"]["segments"])
        item["post-process"] = stringify(item.get("post-process"))
    got = library_combinations(write(tmp_path, doc)).to_dict()
    assert [c["tool"] for c in got["combinations"]] == [c["tool"] for c in ref["combinations"]]
    assert [c["holder"] for c in got["combinations"]] == [c["holder"] for c in ref["combinations"]]
    assert [(c["number"], c["teeth"]) for c in got["combinations"]] == [(1, 4), (2, 2), (3, 2), (None, None)]


def test_strings_with_the_objects_own_unit_are_read(tmp_path):
    doc = sample()
    mm_tool = doc["data"][0]
    mm_tool["geometry"] = {k: v for k, v in stringify(mm_tool["geometry"], "mm").items()
                           if k not in ("CSP", "HAND", "NOF")} | {"NOF": "4"}
    mm_tool["holder"]["segments"] = stringify(mm_tool["holder"]["segments"], "millimeters")
    inch_tool = doc["data"][1]
    inch_tool["geometry"]["DC"] = "0.25in"
    combos = library_combinations(write(tmp_path, doc)).combinations
    ref = library_combinations(SAMPLE).combinations
    assert combos[0].status == "ok" and combos[0].tool == ref[0].tool and combos[0].holder == ref[0].holder
    assert combos[1].tool == ref[1].tool


@pytest.mark.parametrize(("where", "value", "field", "words"), [
    ("DC", "10 in", "geometry.DC", "states inches but the object's unit is millimeters"),
    ("DC", "10 cm", "geometry.DC", "unknown length unit 'cm'"),
    ("DC", "10,5", "geometry.DC", "must be a number"),
    ("OAL", "seventy-two", "geometry.OAL", "must be a number"),
    ("LB", "", "geometry.LB", "must be a number"),
    ("LB", "NaN", "geometry.LB", "must be a number"),
    ("LB", "1e999", "geometry.LB", "finite"),
    ("SFDM", "-10", "geometry.SFDM", "must be > 0"),
    ("segment", "8 in", "holder.segments[0].height", "states inches"),
    ("gauge", "70mm", None, None),  # the holder's own unit: read
])
def test_garbage_strings_are_refused_naming_the_field(tmp_path, where, value, field, words):
    doc = sample()
    item = doc["data"][0]
    if where == "segment":
        item["holder"]["segments"][0]["height"] = value
    elif where == "gauge":
        item["holder"]["gaugeLength"] = value
    else:
        item["geometry"][where] = value
    combo = library_combinations(write(tmp_path, doc)).combinations[0]
    if field is None:
        assert combo.status == "ok" and combo.holder == library_combinations(SAMPLE).combinations[0].holder
    else:
        assert combo.status == "error" and combo.reason.startswith(f"{field}:") and words in combo.reason, combo.reason


def test_a_flute_count_that_is_not_an_integer_is_a_warning_not_a_guess(tmp_path):
    doc = sample()
    doc["data"][0]["geometry"]["NOF"] = "4.5"
    combo = library_combinations(write(tmp_path, doc)).combinations[0]
    assert combo.status == "ok" and combo.teeth is None and any("NOF" in w for w in combo.warnings)


# --------------------------------------------------------------------------- materials


@pytest.mark.parametrize(("bmc", "material", "note"), [
    ("hss", "hss", False), ("HSS", "hss", False), ("HSS-Co", "hss_cobalt", False), ("hsco", "hss_cobalt", False),
    ("HSS-E", "hss_cobalt", False), ("ti coated", "hss", True), ("Tool Steel", "tool_steel", False),
    ("ceramics", "ceramic", True), ("SiAlON", "ceramic", True), ("VHM", "carbide", False),
])
def test_vendor_material_spellings_map_to_built_ins(tmp_path, bmc, material, note):
    doc = sample()
    doc["data"][0]["BMC"] = bmc
    combo = library_combinations(write(tmp_path, doc)).combinations[0]
    assert combo.tool["material"] == material
    assert any(bmc in w for w in combo.warnings) is note
    parse_tool(combo.tool, BUILTIN_MATERIALS)  # known without a "materials" section


@pytest.mark.parametrize("bmc", ["unspecified", "diamond", "PCD", 7])
def test_unknown_materials_fall_back_to_the_default_with_a_warning(tmp_path, bmc):
    doc = sample()
    doc["data"][0]["BMC"] = bmc
    combo = library_combinations(write(tmp_path, doc), tool_material_default="hss").combinations[0]
    assert combo.tool["material"] == "hss" and any("'hss' assumed" in w for w in combo.warnings)
    assert tool_material(bmc) == (None, None)


def test_an_hss_library_predicts_without_a_materials_section(tmp_path):
    doc = sample()
    for item in doc["data"]:
        item["BMC"] = "hss"
    spindle = ra1(GRID)["spindle"]
    out = predict_library(write(tmp_path, doc), spindle=spindle, frequency=GRID)
    assert out["summary"] == {"ok": 2, "skipped": 2, "error": 0}
    carbide = predict_library(SAMPLE, spindle=spindle, frequency=GRID)
    # HSS (E 210 GPa) is softer than carbide (600 GPa): a softer tool point
    assert out["results"][0]["static_stiffness_n_m"] < carbide["results"][0]["static_stiffness_n_m"]


# --------------------------------------------------------------------------- shallow insertion


def test_a_shallow_insertion_is_warned_on_the_item_and_noted_in_the_prediction(tmp_path):
    doc = sample()
    geometry = doc["data"][0]["geometry"]
    geometry["OAL"] = geometry["LB"] + 3  # 3 mm of the 10 mm shank in the holder
    path = write(tmp_path, doc)
    combo = library_combinations(path).combinations[0]
    assert combo.status == "ok" and any("shallow insertion: 3 mm of the 10 mm shank" in w for w in combo.warnings)
    out = predict_library(path, spindle=ra1(GRID)["spindle"], frequency=GRID)
    first = out["results"][0]
    assert any("shallow insertion" in w for w in first["warnings"])
    assert any("shallow insertion" in n for n in first["notes"])
    assert not any("shallow" in n for n in out["results"][1]["notes"])  # 1.25 in of a 0.25 in shank


# --------------------------------------------------------------------------- cones


def test_a_conical_neck_is_stepped_by_its_taper_not_taken_at_its_smallest_diameter(tmp_path):
    doc = sample()
    item = doc["data"][0]
    item["geometry"].update({"DC": 6, "SFDM": 10, "LCF": 10, "shoulder-length": 10, "shoulder-diameter": 6})
    item["shaft"] = {"segments": [{"height": 30, "lower-diameter": 6, "upper-diameter": 10}]}
    combo = library_combinations(write(tmp_path, doc)).combinations[0]
    steps = combo.tool["neck_segments"]
    assert len(steps) == 12  # taper 4/6: ⌈√(0.667/0.005)⌉
    assert sum(s["length_m"] for s in steps) == pytest.approx(0.030, rel=1e-12)
    assert [s["diameter_m"] for s in steps] == pytest.approx([0.006 + 0.004 * (2 * k + 1) / 24 for k in range(12)])
    assert "shoulder_length_m" not in combo.tool and combo.warnings == ()
    parse_tool(combo.tool, BUILTIN_MATERIALS)


def test_holder_cones_follow_their_taper_and_the_option_overrides(tmp_path):
    doc = sample()
    doc["data"][0]["holder"]["segments"][0] = {"height": 8, "lower-diameter": 42, "upper-diameter": 43}
    path = write(tmp_path, doc)
    default = library_combinations(path).combinations[0].holder["segments"]
    fixed = library_combinations(path, holder_segments_per_cone=2).combinations[0].holder["segments"]
    assert [s["length_m"] for s in default[-3:]] == pytest.approx([8e-3 / 3] * 3)  # 1/42 taper: 3 steps
    assert [s["outer_diameter_m"] for s in fixed[-2:]] == pytest.approx([0.04275, 0.04225])


def test_every_variant_entry_is_a_valid_contract_tool(tmp_path):
    doc = copy.deepcopy(sample())
    doc["data"][0]["geometry"] = stringify(doc["data"][0]["geometry"])
    doc["data"][1]["BMC"] = "HSS-Co"
    for combo in library_combinations(write(tmp_path, doc)):
        if combo.status == "ok":
            parse_tool(combo.tool, BUILTIN_MATERIALS)

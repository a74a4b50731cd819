"""Fusion tool-library import: hand-computed SI values on the synthetic sample, rules, errors.

Fixtures: ``tests/data/tool-libraries/fusion-synthetic`` (ours, see SOURCE.md there).
"""

from __future__ import annotations

import copy
import io
import json
import math
import zipfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rcsa.errors import InputError
from rcsa.libraries import (
    cone_cylinders,
    library_combinations,
    load_fusion_library,
    unit_to_metres,
)
from rcsa.model.contract import parse_holder, parse_tool
from rcsa.physics.materials import BUILTIN_MATERIALS, Material

DATA = Path(__file__).resolve().parents[1] / "data" / "tool-libraries" / "fusion-synthetic"
JSON_PATH = DATA / "synthetic_library.json"
TOOLS_PATH = DATA / "synthetic_library.tools"
RTOL = 1e-12  # unit conversion: one rounding per value
INCH_M = 0.0254

# The sample holder, in Fusion order (tool end first), mm: (height, lower-, upper-diameter).
# Cumulative heights 8, 22, 44, 54, 70 | 135.4; gaugeLength 70 keeps the first five.
# Expected contract segments, from the gauge line toward the tool end, mm: each cone in
# cone_steps pieces of equal length at the mid-piece diameters — 42→46 over 22: taper
# 4/42, ⌈√(0.0952/0.005)⌉ = 5 pieces of 4.4 at 42.4, 43.2, 44.0, 44.8, 45.6; 42→50 over 8:
# taper 8/42, ⌈√(0.1905/0.005)⌉ = 7 pieces of 8/7 at 42 + 8(2k+1)/14 — then reversed.
HOLDER_MM = [(16, 63), (10, 46), (4.4, 45.6), (4.4, 44.8), (4.4, 44.0), (4.4, 43.2), (4.4, 42.4),
             (14, 50), *[(8 / 7, 42 + 8 * (2 * k + 1) / 14) for k in reversed(range(7))]]


def sample() -> dict:
    return json.loads(JSON_PATH.read_text())


def lib(*items: dict) -> dict:
    return {"data": list(items), "version": 1}


def tool_item(**geometry: float) -> dict:
    """The sample's mm flat end mill (with its mm holder), geometry overridden."""
    item = copy.deepcopy(sample()["data"][0])
    for key, value in geometry.items():
        if value is None:
            item["geometry"].pop(key, None)
        else:
            item["geometry"][key] = value
    return item


def one(item: dict, **options: object):
    (combo,) = library_combinations(lib(item), **options).combinations
    return combo


def expected_holder(bore_m: float) -> list[dict]:
    return [{"length_m": pytest.approx(h / 1000, rel=RTOL),
             "outer_diameter_m": pytest.approx(d / 1000, rel=RTOL),
             "inner_diameter_m": bore_m, "material": "steel"} for h, d in HOLDER_MM]


# --------------------------------------------------------------------------- the sample


def test_sample_statuses_in_library_order_with_summary():
    result = library_combinations(JSON_PATH)
    assert [c.status for c in result] == ["ok", "ok", "skipped", "skipped"]
    assert [c.index for c in result] == [0, 1, 2, 3]
    assert result.summary == {"ok": 2, "skipped": 2, "error": 0}
    assert [c.number for c in result] == [1, 2, 3, None]
    assert [c.teeth for c in result] == [4, 2, 2, None]
    assert result.combinations[2].reason == "no holder"
    assert result.combinations[3].reason == "standalone holder (type: holder), not a tool"
    assert result.combinations[3].holder is None and result.combinations[3].tool is None


def test_mm_tool_in_mm_holder_exact_si_values():
    combo = library_combinations(JSON_PATH).combinations[0]
    assert combo.id == "00000000-0000-4000-8000-000000000101"
    assert combo.description == "SYNTH 10mm 4FL flat end mill, 40mm stickout"
    assert combo.tool == {
        "material": "carbide", "diameter_m": 0.010, "shank_diameter_m": 0.010,
        "overall_length_m": 0.072, "flute_length_m": 0.022, "stickout_m": 0.040,
        "fluted_diameter_ratio": 0.8,
    }  # shoulder-diameter 10 = SFDM: no neck fields
    assert combo.holder == {"segments": expected_holder(0.010)}
    assert combo.warnings == ()  # LB 40 = assemblyGaugeLength 110 − gaugeLength 70


def test_inch_tool_in_mm_holder_with_shaft_neck():
    combo = library_combinations(JSON_PATH).combinations[1]
    assert combo.tool == {
        "material": "carbide",
        "diameter_m": pytest.approx(0.25 * INCH_M, rel=RTOL),        # 0.00635
        "shank_diameter_m": pytest.approx(0.00635, rel=RTOL),
        "overall_length_m": pytest.approx(2.5 * INCH_M, rel=RTOL),   # 0.0635
        "flute_length_m": pytest.approx(0.375 * INCH_M, rel=RTOL),   # 0.009525
        "stickout_m": pytest.approx(1.25 * INCH_M, rel=RTOL),        # 0.03175
        "fluted_diameter_ratio": 0.8,
        # body LCF→shoulder (0.375→0.9 in) at shoulder-diameter 0.23 in, then the shaft's
        # 0.525 in at 0.23 in from the shoulder: thin over the whole overhang, up to LB.
        "shoulder_length_m": pytest.approx(1.25 * INCH_M, rel=RTOL),
        "shoulder_diameter_m": pytest.approx(0.23 * INCH_M, rel=RTOL),  # 0.005842
    }
    # the holder keeps its own unit (mm); only the bore follows the inch shank
    assert combo.holder == {"segments": expected_holder(pytest.approx(0.00635, rel=RTOL))}
    assert len(combo.warnings) == 1 and "continues into the holder" in combo.warnings[0]


def test_shaft_from_flute_end_gives_the_shorter_neck_its_cone_stepped():
    combo = library_combinations(JSON_PATH, shaft_origin="flute_end").combinations[1]
    # shaft from LCF: 0.375 + 0.525 = 0.9 in at 0.23 in, then a 0.05 in cone to 0.25 in (SFDM):
    # taper 0.02/0.23, ⌈√(0.087/0.005)⌉ = 5 steps of 0.01 in at 0.232 ... 0.248 in
    assert "shoulder_length_m" not in combo.tool
    assert combo.tool["neck_segments"] == [
        {"length_m": pytest.approx(0.525 * INCH_M, rel=1e-9), "diameter_m": pytest.approx(0.23 * INCH_M, rel=RTOL)},
        *[{"length_m": pytest.approx(0.01 * INCH_M, rel=1e-9), "diameter_m": pytest.approx(d * INCH_M, rel=1e-9)}
          for d in (0.232, 0.236, 0.240, 0.244, 0.248)]]
    assert not any("one neck" in w for w in combo.warnings)


def test_json_tools_bytes_and_dict_give_the_same_result():
    def strip(result):
        d = result.to_dict()
        d.pop("source")
        return d

    ref = strip(library_combinations(JSON_PATH))
    assert strip(library_combinations(TOOLS_PATH)) == ref
    assert strip(library_combinations(str(TOOLS_PATH))) == ref
    assert strip(library_combinations(TOOLS_PATH.read_bytes())) == ref
    assert strip(library_combinations(JSON_PATH.read_bytes())) == ref
    assert strip(library_combinations(sample())) == ref
    assert strip(library_combinations(load_fusion_library(TOOLS_PATH))) == ref


def test_result_is_json_serialisable_and_batch_items():
    result = library_combinations(TOOLS_PATH)
    json.dumps(result.to_dict())
    item = result.combinations[0].batch_item()
    assert set(item) == {"id", "holder", "tool"}
    item["tool"]["stickout_m"] = 1.0  # a copy: the entry is not changed
    assert result.combinations[0].tool["stickout_m"] == 0.040
    with pytest.raises(InputError, match="skipped"):
        result.combinations[2].batch_item()


def test_every_ok_entry_is_accepted_by_the_assembly_parser():
    materials = dict(BUILTIN_MATERIALS)
    materials["hss"] = Material(youngs_modulus_pa=2.15e11, poisson_ratio=0.29,
                                density_kg_m3=8100.0, loss_factor=0.004)
    for options in ({}, {"shaft_origin": "flute_end"}, {"holder_segments_per_cone": 1}):
        ok = [combo for combo in library_combinations(JSON_PATH, **options) if combo.status == "ok"]
        assert ok, options  # the checks below run on something
        for combo in ok:
            parse_holder(combo.holder, materials)
            tool = parse_tool(combo.tool, materials)
            assert tool.stickout_m <= tool.overall_length_m


# --------------------------------------------------------------------------- holder rules


def test_cone_subdivision_preserves_length_and_uses_midpoint_diameters():
    pieces = cone_cylinders(22.0, 42.0, 46.0, 4)
    assert pieces == [(5.5, 42.5), (5.5, 43.5), (5.5, 44.5), (5.5, 45.5)]
    assert math.fsum(h for h, _ in pieces) == 22.0
    assert cone_cylinders(14.0, 50.0, 50.0, 4) == [(14.0, 50.0)]
    # volume: the midpoint rule is low by exactly π h Δd² / (48 n²)
    for n in (1, 2, 4, 7):
        h, d1, d2 = 8.0, 42.0, 50.0
        exact = math.pi * h * (d1 * d1 + d1 * d2 + d2 * d2) / 12
        approx = sum(math.pi / 4 * d * d * length for length, d in cone_cylinders(h, d1, d2, n))
        assert exact - approx == pytest.approx(math.pi * h * (d2 - d1) ** 2 / (48 * n * n), rel=1e-9)
        assert sum(d for _, d in cone_cylinders(h, d1, d2, n)) / n == pytest.approx((d1 + d2) / 2)


def test_segments_per_cone_option():
    combo = library_combinations(JSON_PATH, holder_segments_per_cone=1).combinations[0]
    got = [(round(s["length_m"] * 1e3, 9), round(s["outer_diameter_m"] * 1e3, 9))
           for s in combo.holder["segments"]]
    assert got == [(16, 63), (10, 46), (22, 44), (14, 50), (8, 46)]
    with pytest.raises(InputError, match="holder_segments_per_cone"):
        library_combinations(JSON_PATH, holder_segments_per_cone=0)


def test_segment_order_is_reversed_to_run_from_the_gauge_line():
    item = tool_item()
    item["holder"]["segments"] = [{"height": 10, "lower-diameter": 30, "upper-diameter": 30},
                                  {"height": 20, "lower-diameter": 40, "upper-diameter": 40}]
    item["holder"]["gaugeLength"] = 30
    item["geometry"]["assemblyGaugeLength"] = 70
    item["geometry"]["OAL"] = 70  # inserted length 30 mm = the holder's
    combo = one(item)
    assert [(s["length_m"], s["outer_diameter_m"]) for s in combo.holder["segments"]] == [
        (0.020, 0.040), (0.010, 0.030)]
    assert combo.warnings == ()


def test_gauge_line_inside_a_segment_cuts_it():
    item = tool_item(assemblyGaugeLength=None)
    item["holder"]["gaugeLength"] = 60  # inside the 16 mm, 63 mm flange (54 → 70)
    combo = one(item)
    segs = combo.holder["segments"]
    assert segs[0]["length_m"] == pytest.approx(0.006, rel=RTOL)
    assert segs[0]["outer_diameter_m"] == 0.063
    assert math.fsum(s["length_m"] for s in segs) == pytest.approx(0.060, rel=RTOL)
    assert any("cut at the gauge line" in w for w in combo.warnings)


def test_cut_cone_at_the_gauge_line_keeps_the_diameter_at_the_cut():
    item = tool_item(assemblyGaugeLength=None)
    item["holder"]["segments"] = [{"height": 10, "lower-diameter": 30, "upper-diameter": 40}]
    item["holder"]["gaugeLength"] = 5  # cut cone: 30 → 35 over 5 mm
    combo = one(item, holder_segments_per_cone=2)
    got = [(s["length_m"], s["outer_diameter_m"]) for s in combo.holder["segments"]]
    assert got == [(0.0025, pytest.approx(0.03375, rel=RTOL)), (0.0025, pytest.approx(0.03125, rel=RTOL))]


def test_without_gauge_length_all_segments_are_used_with_a_warning():
    item = tool_item(assemblyGaugeLength=None)
    del item["holder"]["gaugeLength"]
    combo = one(item)
    assert combo.status == "ok"
    assert math.fsum(s["length_m"] for s in combo.holder["segments"]) == pytest.approx(0.1354, rel=RTOL)
    # the 44.45 → 25 mm taper (r = 0.778) in ⌈√(0.778/0.005)⌉ = 13 pieces; the first at 25 + 19.45/26
    assert combo.holder["segments"][0]["outer_diameter_m"] == pytest.approx(0.025 + 19.45e-3 / 26, rel=RTOL)
    assert any("gaugeLength missing" in w for w in combo.warnings)


def test_gauge_length_beyond_the_segments_is_a_warning():
    item = tool_item(assemblyGaugeLength=None)
    item["holder"]["gaugeLength"] = 200
    combo = one(item)
    assert combo.status == "ok" and any("exceeds the segments" in w for w in combo.warnings)


def test_holder_thinner_than_the_shank_is_an_error():
    item = tool_item(SFDM=43, DC=43)
    combo = one(item)
    assert combo.status == "error" and combo.reason.startswith("holder.segments[")


# --------------------------------------------------------------------------- units


@pytest.mark.parametrize(("spelling", "metres"), [
    ("millimeters", 1e-3), ("millimeter", 1e-3), ("mm", 1e-3), ("Millimeters", 1e-3),
    ("inches", INCH_M), ("inch", INCH_M), ("in", INCH_M), ("meters", 1.0), ("meter", 1.0),
])
def test_unit_spellings(spelling, metres):
    assert unit_to_metres(2.0, spelling) == pytest.approx(2.0 * metres, rel=RTOL)


def test_exact_conversions():
    assert unit_to_metres(0.5, "inches") == 0.0127
    assert unit_to_metres(2.5, "inch") == 0.0635
    assert unit_to_metres(65.4, "millimeters") == pytest.approx(0.0654, rel=RTOL)


def test_inch_holder_with_mm_tool():
    item = tool_item(assemblyGaugeLength=None)
    item["holder"] = {"unit": "inches", "gaugeLength": 2.0, "segments": [
        {"height": 0.5, "lower-diameter": 1.5, "upper-diameter": 1.5},
        {"height": 1.5, "lower-diameter": 2.0, "upper-diameter": 2.0}]}
    combo = one(item)
    assert combo.tool["stickout_m"] == 0.040
    assert combo.holder["segments"] == [
        {"length_m": pytest.approx(1.5 * INCH_M, rel=RTOL), "outer_diameter_m": 0.0508,
         "inner_diameter_m": 0.010, "material": "steel"},
        {"length_m": 0.0127, "outer_diameter_m": pytest.approx(1.5 * INCH_M, rel=RTOL),
         "inner_diameter_m": 0.010, "material": "steel"}]


@pytest.mark.parametrize(("where", "field"), [("tool", "unit"), ("holder", "holder.unit")])
@pytest.mark.parametrize("unit", ["furlongs", "", None, 25.4])
def test_unknown_or_missing_unit_is_an_error_entry(where, field, unit):
    item = tool_item()
    target = item if where == "tool" else item["holder"]
    if unit is None:
        del target["unit"]
    else:
        target["unit"] = unit
    other = tool_item()
    result = library_combinations(lib(item, other))
    bad, good = result.combinations
    assert bad.status == "error" and bad.reason.startswith(f"{field}:")
    assert good.status == "ok"
    assert result.summary == {"ok": 1, "skipped": 0, "error": 1}


def test_unit_from_expressions_when_unit_is_absent():
    item = copy.deepcopy(sample()["data"][1])
    del item["unit"]
    item["expressions"] = {"tool_unit": "'inches'"}
    assert one(item).tool["diameter_m"] == pytest.approx(0.00635, rel=RTOL)


# --------------------------------------------------------------------------- ids


def test_ids_guid_then_t_number_then_content_hash():
    a, b, c = (tool_item() for _ in range(3))
    for item, n in ((a, 7), (b, 8), (c, 8)):
        del item["guid"]
        item["post-process"]["number"] = n
    c["description"] = "another T8"
    ids = [x.id for x in library_combinations(lib(a, b, c, tool_item()))]
    assert ids[0] == "T7"
    assert ids[1].startswith("fusion-") and ids[2].startswith("fusion-") and ids[1] != ids[2]
    assert ids[3] == "00000000-0000-4000-8000-000000000101"
    # stable: same content, same id, whatever the position or the other items
    again = [x.id for x in library_combinations(lib(c, b))]
    assert again == [ids[2], ids[1]]


def test_repeated_ids_get_a_suffix_and_a_warning():
    result = library_combinations(lib(tool_item(), tool_item()))
    assert [c.id for c in result] == ["00000000-0000-4000-8000-000000000101",
                                      "00000000-0000-4000-8000-000000000101~2"]
    assert result.combinations[0].warnings == ()
    assert any("repeated" in w for w in result.combinations[1].warnings)


# --------------------------------------------------------------------------- skipped


@pytest.mark.parametrize(("tool_type", "reason"), [
    ("probe", "unsupported tool type: probe"),
    ("thread mill", "unsupported tool type: thread mill"),
    ("form mill", "unsupported tool type: form mill without profile"),
    ("turning general", "unsupported tool type: turning general"),
    ("holder", "standalone holder (type: holder), not a tool"),
])
def test_skipped_reasons(tool_type, reason):
    item = tool_item()
    item["type"] = tool_type
    combo = one(item)
    assert (combo.status, combo.reason, combo.holder, combo.tool) == ("skipped", reason, None, None)


@pytest.mark.parametrize("holder", [None, {}, "absent"])
def test_no_holder_is_skipped(holder):
    item = tool_item()
    if holder == "absent":
        del item["holder"]
    else:
        item["holder"] = holder
    assert (one(item).status, one(item).reason) == ("skipped", "no holder")


def test_default_holder_by_guid_for_tools_without_one():
    result = library_combinations(JSON_PATH, default_holder="00000000-0000-4000-8000-000000000002")
    drill = result.combinations[2]
    assert drill.status == "ok"
    assert drill.tool["stickout_m"] == 0.038 and drill.tool["overall_length_m"] == 0.066
    assert drill.holder == {"segments": expected_holder(0.006)}
    assert any("default_holder" in w for w in drill.warnings)
    with pytest.raises(InputError, match="default_holder"):
        library_combinations(JSON_PATH, default_holder="no-such-guid")


# --------------------------------------------------------------------------- tool rules


@pytest.mark.parametrize(("geometry", "field"), [
    ({"LB": 80}, "geometry.LB"),                       # LB > OAL 72
    ({"LCF": 45}, "geometry.LCF"),                     # LCF > LB 40
    ({"DC": None}, "geometry.DC"),
    ({"OAL": None}, "geometry.OAL"),
    ({"SFDM": -10}, "geometry.SFDM"),
    ({"DC": "10 in"}, "geometry.DC"),                  # a unit contradicting the tool's (mm)
    ({"DC": "10,5"}, "geometry.DC"),
    ({"DC": True}, "geometry.DC"),
    ({"DC": float("nan")}, "geometry.DC"),
])
def test_validation_failures_name_the_field_and_spare_the_others(geometry, field):
    result = library_combinations(lib(tool_item(**geometry), tool_item()))
    bad, good = result.combinations
    assert bad.status == "error" and bad.reason.startswith(f"{field}:"), bad.reason
    assert good.status == "ok"


def test_a_tool_whose_whole_length_is_below_the_holder_is_face_mounted():
    """LB = OAL: a shell or face mill on an arbor, on the holder's face (joints.holder_tool: the face
    contact); the holder is solid (no bore for a shank that is not there)."""
    item = tool_item(LB=72)
    face = library_combinations(lib(item)).combinations[0]
    assert face.status == "ok" and any("face-mounted" in w for w in face.warnings)
    assert face.tool["stickout_m"] == face.tool["overall_length_m"]
    assert all(s["inner_diameter_m"] == 0.0 for s in face.holder["segments"])
    assert not any("shallow insertion" in w for w in face.warnings)


def test_inch_tool_missing_oal_is_an_error():
    item = copy.deepcopy(sample()["data"][1])
    del item["geometry"]["OAL"]
    combo = one(item)
    assert combo.status == "error" and combo.reason == "geometry.OAL: missing (required)"


def test_lb_derived_from_gauge_lengths_when_absent():
    combo = one(tool_item(LB=None))
    assert combo.tool["stickout_m"] == pytest.approx(0.040, rel=RTOL)
    assert any("LB missing" in w for w in combo.warnings)
    assert one(tool_item(LB=None, assemblyGaugeLength=None)).reason.startswith("geometry.LB:")


def test_stickout_mismatch_is_a_warning_and_lb_wins():
    combo = one(tool_item(assemblyGaugeLength=112))
    assert combo.tool["stickout_m"] == 0.040
    assert any("differs from assemblyGaugeLength" in w for w in combo.warnings)


@pytest.mark.parametrize(("bmc", "material", "warns"), [
    ("carbide", "carbide", False), ("Carbide", "carbide", False), ("hss", "hss", False),
    ("ceramics", "ceramic", True), (None, "carbide", True),
])
def test_material_from_bmc(bmc, material, warns):
    item = tool_item()
    if bmc is None:
        del item["BMC"]
    else:
        item["BMC"] = bmc
    combo = one(item)
    assert combo.tool["material"] == material
    assert any("BMC" in w or "hss" in w for w in combo.warnings) is warns


def test_tool_material_default_and_ratio_options():
    item = tool_item()
    item["BMC"] = "unspecified"
    combo = one(item, tool_material_default="hss", fluted_diameter_ratio=0.7, holder_material="steel42")
    assert combo.tool["material"] == "hss" and combo.tool["fluted_diameter_ratio"] == 0.7
    assert {s["material"] for s in combo.holder["segments"]} == {"steel42"}
    with pytest.raises(InputError, match="fluted_diameter_ratio"):
        library_combinations(JSON_PATH, fluted_diameter_ratio=1.5)


def test_simple_neck_from_shoulder_fields():
    # 3 mm cutter, 6 mm shank, 2.8 mm neck to 15 mm from the tip, stickout 20 mm
    combo = one(tool_item(DC=3, SFDM=6, LCF=5, LB=20, OAL=60, assemblyGaugeLength=90,
                          **{"shoulder-length": 15, "shoulder-diameter": 2.8}))
    assert combo.tool["shoulder_length_m"] == 0.015
    assert combo.tool["shoulder_diameter_m"] == 0.0028
    assert combo.warnings == ()


def test_neck_without_shoulder_diameter_is_taken_at_dc():
    combo = one(tool_item(DC=3, SFDM=6, LCF=5, LB=20, OAL=60, assemblyGaugeLength=90,
                          **{"shoulder-length": 15, "shoulder-diameter": None}))
    assert (combo.tool["shoulder_length_m"], combo.tool["shoulder_diameter_m"]) == (0.015, 0.003)
    assert any("taken at DC" in w for w in combo.warnings)


def test_body_thicker_than_the_shank_is_not_a_neck():
    combo = one(tool_item(DC=12, **{"shoulder-length": 30, "shoulder-diameter": 12}))
    assert "shoulder_length_m" not in combo.tool
    assert any("thicker than the shank" in w for w in combo.warnings)


def test_stepped_shaft_is_modelled_step_by_step():
    item = tool_item(DC=6, SFDM=10, LCF=10, LB=40, **{"shoulder-length": None,
                                                         "shoulder-diameter": None})
    item["shaft"] = {"segments": [{"height": 10, "lower-diameter": 5.5, "upper-diameter": 5.5},
                                  {"height": 5, "lower-diameter": 7, "upper-diameter": 7}]}
    combo = one(item)
    # from the flute end (10 mm from the tip): 10 mm at 5.5, 5 mm at 7, then the shank
    assert combo.tool["neck_segments"] == [{"length_m": pytest.approx(0.010, rel=1e-9), "diameter_m": 0.0055},
                                           {"length_m": pytest.approx(0.005, rel=1e-9), "diameter_m": 0.007}]
    assert "shoulder_length_m" not in combo.tool and combo.warnings == ()


# --------------------------------------------------------------------------- malformed input


def _zip(members: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return buf.getvalue()


@pytest.mark.parametrize(("source", "message"), [
    (b"this is not json", "not valid JSON"),
    (b"\xff\xfe\x00garbage", "not UTF-8"),
    (b'{"data": [NaN]}', "NaN is not a number"),
    (b'{"version": 1}', "data: missing"),
    (b'{"data": {"a": 1}}', "data: must be a list"),
    (b"[1, 2]", "JSON object"),
    (_zip({"readme.txt": b"hi"}), "no tools.json"),
    (_zip({"a/tools.json": b"{}", "b/tools.json": b"{}"}), "several tools.json"),
    (_zip({"tools.json": b"not json"}), "not valid JSON"),
    (b"PK\x03\x04 truncated", "not a readable .tools zip"),
])
def test_malformed_library_is_an_input_error(source, message):
    with pytest.raises(InputError, match=message):
        load_fusion_library(source)


def test_zip_with_tools_json_in_a_folder_is_accepted():
    lib_ = load_fusion_library(_zip({"export/tools.json": JSON_PATH.read_bytes()}))
    assert len(lib_.items) == 4
    assert lib_.sha256 == load_fusion_library(JSON_PATH).sha256


def test_missing_file_and_wrong_type_are_input_errors(tmp_path):
    with pytest.raises(InputError, match="cannot be read"):
        load_fusion_library(tmp_path / "nope.tools")
    with pytest.raises(InputError, match="expected a path"):
        load_fusion_library(42)  # type: ignore[arg-type]


def test_non_object_items_are_error_entries():
    result = library_combinations(lib(7, tool_item(), {"description": "no type"}))
    assert [c.status for c in result] == ["error", "ok", "error"]
    assert result.combinations[0].reason == "data[0]: not a JSON object"
    assert result.combinations[2].reason.startswith("type:")


def test_empty_library():
    result = library_combinations(lib())
    assert len(result) == 0 and result.summary == {"ok": 0, "skipped": 0, "error": 0}


# --------------------------------------------------------------------------- property


@st.composite
def valid_tools(draw):
    unit = draw(st.sampled_from(["millimeters", "inches"]))
    s = 1.0 if unit == "millimeters" else 1 / 25.4
    pos = lambda lo, hi: draw(st.floats(lo * s, hi * s, allow_nan=False))  # noqa: E731
    dc, sfdm = pos(0.5, 40), pos(1, 40)
    lcf = pos(0.5, 60)
    lb = lcf + pos(0, 80)
    oal = lb + pos(0.5, 100)
    geometry = {"DC": dc, "SFDM": sfdm, "LCF": lcf, "LB": lb, "OAL": oal, "NOF": 3}
    if draw(st.booleans()):
        geometry["shoulder-length"] = lcf + pos(0, 50)
        geometry["shoulder-diameter"] = pos(0.3, 40)
    item = {"type": "flat end mill", "unit": unit, "BMC": "carbide", "geometry": geometry}
    if draw(st.booleans()):
        n = draw(st.integers(1, 3))
        item["shaft"] = {"segments": [
            {"height": pos(0.1, 30), "lower-diameter": pos(0.3, 40), "upper-diameter": pos(0.3, 40)}
            for _ in range(n)]}
    hunit = draw(st.sampled_from(["millimeters", "inches"]))
    hs = 1.0 if hunit == "millimeters" else 1 / 25.4
    bore_native = sfdm / s * hs  # SFDM in the holder's unit
    segs = [{"height": draw(st.floats(0.5 * hs, 60 * hs)),
             "lower-diameter": bore_native + draw(st.floats(1 * hs, 40 * hs)),
             "upper-diameter": bore_native + draw(st.floats(1 * hs, 40 * hs))}
            for _ in range(draw(st.integers(1, 6)))]
    holder = {"type": "holder", "unit": hunit, "segments": segs}
    if draw(st.booleans()):
        holder["gaugeLength"] = sum(x["height"] for x in segs) * draw(st.floats(0.05, 1.0))
    item["holder"] = holder
    return item


@settings(max_examples=150, deadline=None)
@given(valid_tools(), st.integers(1, 6))
def test_property_valid_tools_give_positive_lengths_and_stickout_within_oal(item, per_cone):
    combo = one(item, holder_segments_per_cone=per_cone)
    assert combo.status == "ok", combo.reason
    tool = combo.tool
    lengths = [v for k, v in tool.items() if k.endswith("_m")]
    assert all(math.isfinite(v) and v > 0 for v in lengths)
    assert tool["flute_length_m"] <= tool["stickout_m"] < tool["overall_length_m"]
    if "shoulder_length_m" in tool:
        assert tool["flute_length_m"] < tool["shoulder_length_m"] <= tool["stickout_m"]
        assert tool["shoulder_diameter_m"] < tool["shank_diameter_m"]
    if "neck_segments" in tool:
        reach = math.fsum(s["length_m"] for s in tool["neck_segments"])
        assert reach <= (tool["stickout_m"] - tool["flute_length_m"]) * (1 + 1e-9)
        assert all(s["diameter_m"] <= tool["shank_diameter_m"] for s in tool["neck_segments"])
    segs = combo.holder["segments"]
    assert segs and all(s["length_m"] > 0 and s["outer_diameter_m"] > s["inner_diameter_m"] > 0
                        for s in segs)
    gauge = item["holder"].get("gaugeLength")
    if gauge is not None:
        scale = 1e-3 if item["holder"]["unit"] == "millimeters" else INCH_M
        assert math.fsum(s["length_m"] for s in segs) == pytest.approx(gauge * scale, rel=1e-9)
    parse_holder(combo.holder, BUILTIN_MATERIALS)
    parse_tool(tool, BUILTIN_MATERIALS)


@pytest.mark.parametrize("per_cone", [None, 6])
def test_a_gauge_line_a_sliver_inside_a_cone_gives_no_segment_below_the_shortest_beam(per_cone):
    """Found by the property test: a gauge line 0.6 um into a cone, split in 6, gave 0.1 um
    cylinders that the contract refuses (length >= 1 um). The last kept segment takes the sliver."""
    item = {"type": "flat end mill", "unit": "millimeters", "BMC": "carbide",
            "geometry": {"DC": 10.0, "SFDM": 10.0, "LCF": 20.0, "LB": 30.0, "OAL": 70.0, "NOF": 3},
            "holder": {"type": "holder", "unit": "millimeters", "gaugeLength": 40.0006,
                       "segments": [{"height": 40.0, "lower-diameter": 20.0, "upper-diameter": 30.0},
                                    {"height": 20.0, "lower-diameter": 30.0, "upper-diameter": 50.0}]}}
    combo = one(item, holder_segments_per_cone=per_cone)
    assert combo.status == "ok", combo.reason
    lengths = [s["length_m"] for s in combo.holder["segments"]]
    assert min(lengths) >= 1e-6
    assert math.fsum(lengths) == pytest.approx(0.0400006, rel=1e-12)


def test_a_library_of_too_many_items_is_refused_before_any_is_read():
    from rcsa.libraries.fusion import load_fusion_library
    from rcsa.model.bounds import MAX_LIBRARY_ITEMS

    with pytest.raises(InputError, match=f"at most {MAX_LIBRARY_ITEMS} items") as caught:
        load_fusion_library({"data": [0] * (MAX_LIBRARY_ITEMS + 1)})
    assert caught.value.field == "data"


def test_a_zip_of_too_many_files_is_refused_before_it_is_opened():
    import io
    import zipfile

    from rcsa.libraries.formats import read_library
    from rcsa.model.bounds import MAX_LIBRARY_ITEMS

    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as zf:
        for i in range(MAX_LIBRARY_ITEMS + 1):
            zf.writestr(f"t{i}.fctb", b"")
    with pytest.raises(InputError, match=f"more than {MAX_LIBRARY_ITEMS} files"):
        read_library(buffer.getvalue(), file_name="tools.zip")


# --------------------------------------------------------------------------- the benchmark libraries


@pytest.mark.parametrize(("folder", "name", "teeth"), [
    ("fusion-single-flute", "single_flute_small_library.json", {1}),
    ("fusion-single-flute", "single_flute_library.json", {1}),
    ("fusion-multi-flute", "multi_flute_library.json", {2, 3, 4}),
])
def test_the_benchmark_libraries_read_whole_with_their_flutes(folder, name, teeth):
    """The presets benchmark's libraries (``benchmarks/write_tool_libraries.py``): every tool
    becomes an assembly, with the flutes it was written with."""
    path = DATA.parent / folder / name
    result = library_combinations(json.loads(path.read_text()))
    assert len(result.combinations) == 25 and all(c.status == "ok" for c in result.combinations)
    flutes = {item["geometry"]["NOF"] for item in json.loads(path.read_text())["data"]}
    assert flutes == teeth

"""FreeCAD toolbit + holder import, on the copied FreeCAD samples (LGPL, see SOURCE.md)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rcsa.errors import InputError
from rcsa.libraries import freecad_combination, load_freecad_object, parse_length_m
from rcsa.libraries.freecad import outline_radius
from rcsa.model.contract import parse_holder, parse_tool
from rcsa.physics.materials import BUILTIN_MATERIALS

DATA = Path(__file__).resolve().parents[1] / "data" / "tool-libraries" / "freecad"
ENDMILL = DATA / "5mm_Endmill.fctb"
BALL = DATA / "6mm_Ball_End.fctb"
ER32 = DATA / "ER32_Standard.fcholder"
RTOL = 1e-12

# ER32 nut outline (mm): (0,0) (23,0) (25,2) (25,22.5) (0,22.5): a 23→25 mm radius chamfer
# over z 0..2, then r 25 up to 22.5. From the top down: 20.5 mm at Ø50, then the chamfer
# (taper 4/46, ⌈√(0.087/0.005)⌉ = 5 steps) in five 0.4 mm pieces at the mid-piece
# diameters 49.6, 48.8, 48.0, 47.2, 46.4 mm.
ER32_MM = [(20.5, 50), (0.4, 49.6), (0.4, 48.8), (0.4, 48.0), (0.4, 47.2), (0.4, 46.4)]


def toolbit(**params: str | None) -> dict:
    obj = json.loads(ENDMILL.read_text())
    for key, value in params.items():
        if value is None:
            obj["parameter"].pop(key, None)
        else:
            obj["parameter"][key] = value
    return obj


def test_endmill_in_er32_exact_si_values():
    combo = freecad_combination(ENDMILL, ER32, stickout_m=0.040)
    assert combo.status == "ok"
    assert combo.id == "5mm_Endmill@ER32_Standard"
    assert combo.description == "5mm Endmill" and combo.tool_type == "Endmill"
    assert combo.tool == {"material": "carbide", "diameter_m": 0.005, "shank_diameter_m": 0.003,
                          "overall_length_m": 0.050, "flute_length_m": 0.030, "stickout_m": 0.040,
                          "fluted_diameter_ratio": 0.8}
    assert combo.holder == {"segments": [
        {"length_m": pytest.approx(h / 1000, rel=RTOL), "outer_diameter_m": pytest.approx(d / 1000, rel=RTOL),
         "inner_diameter_m": 0.003, "material": "steel"} for h, d in ER32_MM]}
    assert any("no gauge line" in w for w in combo.warnings)
    assert any("Material missing" in w for w in combo.warnings)
    parse_holder(combo.holder, BUILTIN_MATERIALS)
    parse_tool(combo.tool, BUILTIN_MATERIALS)


def test_ball_end_and_inputs_as_bytes_or_dicts():
    by_path = freecad_combination(BALL, ER32, stickout_m=0.045, holder_segments_per_cone=1)
    assert by_path.tool["diameter_m"] == 0.006 and by_path.tool["flute_length_m"] == 0.040
    assert [s["outer_diameter_m"] for s in by_path.holder["segments"]] == [0.050, pytest.approx(0.048)]
    by_bytes = freecad_combination(BALL.read_bytes(), json.loads(ER32.read_text()), stickout_m=0.045,
                                   holder_segments_per_cone=1)
    assert by_bytes.tool == by_path.tool and by_bytes.holder == by_path.holder
    assert by_bytes.id.startswith("freecad-") and "@freecad-" in by_bytes.id
    again = freecad_combination(BALL.read_bytes(), ER32.read_bytes(), stickout_m=0.045)
    assert again.id == by_bytes.id  # content ids are stable


@pytest.mark.parametrize(("text", "metres"), [
    ("5.0000 mm", 0.005), ("5mm", 0.005), (" 0.25 in ", 0.00635), ("1e-3 m", 0.001),
    ("2 millimeters", 0.002), (".5 in", 0.0127),
])
def test_quantities(text, metres):
    assert parse_length_m(text, "x") == pytest.approx(metres, rel=RTOL)


@pytest.mark.parametrize("text", ["5", "5 cm", "5 mm 3", "mm", "five mm", "nan mm", 5.0, None, "5 °"])
def test_quantities_are_parsed_strictly(text):
    with pytest.raises(InputError, match="^x:"):
        parse_length_m(text, "x")


@pytest.mark.parametrize(("params", "stickout", "field"), [
    ({"Diameter": "5"}, 0.04, "parameter.Diameter"),
    ({"ShankDiameter": None}, 0.04, "parameter.ShankDiameter"),
    ({"Length": "-50 mm"}, 0.04, "parameter.Length"),
    ({}, 0.050, "stickout_m"),
    ({}, 0.020, "parameter.CuttingEdgeHeight"),
])
def test_errors_name_the_field(params, stickout, field):
    combo = freecad_combination(toolbit(**params), ER32, stickout_m=stickout)
    assert combo.status == "error" and combo.reason.startswith(f"{field}:"), combo.reason


def test_probe_is_skipped_and_material_flutes_read():
    obj = toolbit()
    obj["shape-type"] = "Probe"
    assert freecad_combination(obj, ER32, stickout_m=0.04).reason == "unsupported tool type: probe"
    obj = toolbit(Flutes="3")
    obj["attribute"] = {"Material": "HSS"}
    combo = freecad_combination(obj, ER32, stickout_m=0.04)
    assert combo.teeth == 3 and combo.tool["material"] == "hss"


def test_inch_holder_and_outline_errors():
    holder = {"units": "in", "profile": [[0, 0], [1, 0], [1, 2], [0, 2]]}
    combo = freecad_combination(ENDMILL, holder, stickout_m=0.04)
    assert combo.holder["segments"] == [{"length_m": 0.0508, "outer_diameter_m": 0.0508,
                                         "inner_diameter_m": 0.003, "material": "steel"}]
    for bad, field in (({"units": "furlong", "profile": holder["profile"]}, "holder.units"),
                       ({"units": "mm", "profile": [[0, 0], [5, 0]]}, "holder.profile"),
                       ({"units": "mm", "profile": [[0, 0], [-1, 2]]}, "holder.profile[1]"),
                       ({"units": "mm", "profile": [[0, 0], [1, 0], [1, 2], [0, 2]]}, "holder.profile")):
        combo = freecad_combination(ENDMILL, bad, stickout_m=0.04)
        assert combo.status == "error" and combo.reason.startswith(f"{field}:"), combo.reason


def test_outline_radius():
    pts = [(0.0, 0.0), (23.0, 0.0), (25.0, 2.0), (25.0, 22.5), (0.0, 22.5)]
    assert outline_radius(pts, 1.0) == 24.0
    assert outline_radius(pts, 10.0) == 25.0
    assert outline_radius(pts, 30.0) == 0.0


def test_malformed_files_and_options(tmp_path):
    with pytest.raises(InputError, match="FreeCAD file is not valid JSON"):
        load_freecad_object(b"{nope")
    with pytest.raises(InputError, match="JSON object"):
        load_freecad_object(b"[1]")
    with pytest.raises(InputError, match="cannot be read"):
        load_freecad_object(tmp_path / "missing.fctb")
    with pytest.raises(InputError, match="stickout_m"):
        freecad_combination(ENDMILL, ER32, stickout_m=0)
    with pytest.raises(InputError, match="holder_segments_per_cone"):
        freecad_combination(ENDMILL, ER32, stickout_m=0.04, holder_segments_per_cone=0)

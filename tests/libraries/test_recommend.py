"""Chatter-safe presets: pockets that are stable, a library that round-trips, reruns that replace."""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest

from rcsa.analysis.lobes.zoa import stability_lobes
from rcsa.app.jobs import Workbench
from rcsa.app.presets import recommend_predicted, recommend_stored
from rcsa.errors import InputError
from rcsa.libraries.formats import read_library
from rcsa.libraries.fusion import library_combinations
from rcsa.libraries.fusion_presets import read_fusion_file
from rcsa.libraries.recommend import FrfFailure, parse_recommend_options, recommend_presets
from rcsa.libraries.recommend_sources import predicted_frfs
from rcsa.libraries.sync import sync_library
from rcsa.reference import ra1
from tests.helpers import REPO

SAMPLES = REPO / "tests" / "data" / "tool-libraries"
SAMPLE = (SAMPLES / "fusion-synthetic" / "synthetic_library.json").read_bytes()
GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
RA1 = ra1(GRID)
SETTINGS = {"spindle": RA1["spindle"], "frequency": GRID, "joints": RA1["joints"]}
OPTIONS = {"material": "aluminium-7075", "max_rpm": 24000, "method": "zoa"}  # the zero-order path (auto: test_recommend_methods.py)
NAME = "rcsa chatter-safe: aluminium 7075"


def recommend(data: bytes = SAMPLE, **options):
    return recommend_predicted(Workbench(None), data, {**OPTIONS, **options}, file_name="shop.json", **SETTINGS)


def without_presets(doc: dict) -> dict:
    doc = copy.deepcopy(doc)
    for item in doc["data"]:
        item.pop("start-values", None)
    return doc


def library(**changes) -> bytes:
    doc = json.loads(SAMPLE)
    for index, fields in changes.items():
        item = doc["data"][int(index[1:])]
        for key, value in fields.items():
            target = item
            *path, last = key.split(".")
            for p in path:
                target = target[p]
            target[last] = value
    return json.dumps(doc, indent=2).encode()


@pytest.fixture(scope="module")
def first():
    return recommend()


@pytest.fixture(scope="module")
def frfs():
    return predicted_frfs(read_library(SAMPLE, file_name="shop.json"), **SETTINGS).frfs


def test_presets_lie_in_stable_pockets(first, frfs):
    doc = json.loads(first.data)
    written = [t for t in first.report["tools"] if t["status"] == "written"]
    assert [t["index"] for t in written] == [0, 1]
    for t in written:
        item = doc["data"][t["index"]]
        preset = next(p for p in item["start-values"]["presets"] if p["name"] == NAME)
        per_unit = 1e-3 if item["unit"] == "millimeters" else 0.0254
        n, stepdown_m = preset["n"], preset["stepdown"] * per_unit
        step_m = 1e-6 if per_unit == 1e-3 else 2.54e-6  # stepdowns are rounded down to 0.001 mm / 0.0001 in
        assert n == t["spindle_speed_rpm"] and stepdown_m <= t["stepdown_m"] < stepdown_m + step_m
        assert stepdown_m <= item["geometry"]["LCF"] * per_unit
        # the lobes again, on a fine grid of the speed window only: stable at stepdown x safety factor
        tol, sf = t["speed_tolerance"], t["safety_factor"]
        window = np.linspace(n * (1 - tol), n * (1 + tol), 401)
        frf = frfs[t["id"]]
        lobes = stability_lobes(frf.frequency_hz, frf.h, teeth=item["geometry"]["NOF"],
                                tangential_coefficient_n_m2=first.report["options"]["tangential_coefficient_n_m2"],
                                radial_ratio=first.report["options"]["radial_ratio"], radial_immersion=0.5,
                                milling="down", spindle_speed_rpm=window)
        assert np.all(np.isfinite(lobes.depth_limit_m))
        assert lobes.depth_limit_m.min() >= stepdown_m * sf, (t["id"], lobes.depth_limit_m.min(), stepdown_m * sf)
        assert t["pocket"]["low_rpm"] <= n * (1 - tol) and t["pocket"]["high_rpm"] >= n * (1 + tol) / 1.003
        assert t["speed_range"]["min_rpm"] <= n <= t["speed_range"]["max_rpm"]
        # Fusion's own consistency: v_c from the stored n and DC, in the tool's unit
        dc = item["geometry"]["DC"]
        assert preset["v_c"] == pytest.approx(math.pi * dc * n / (1000.0 if per_unit == 1e-3 else 12.0))
        assert t["lobe_method"] == "zoa" and t["robust_depth_limit_m"] is None


def test_the_library_round_trips_except_for_the_presets(first):
    before, after = json.loads(SAMPLE), json.loads(first.data)
    assert without_presets(after) == without_presets(before)
    assert library_combinations(first.data).to_dict()["combinations"] == \
        library_combinations(SAMPLE).to_dict()["combinations"]
    steel = before["data"][0]["start-values"]["presets"][0]
    assert after["data"][0]["start-values"]["presets"][0] == steel
    assert first.report["library"]["sha256_after"] != first.report["library"]["sha256_before"]


def test_rerun_replaces_rcsas_preset_only(first):
    again = recommend(first.data)
    assert again.data == first.data  # same inputs: byte-identical, no second preset
    assert all(t["preset"]["replaced"] for t in again.report["tools"] if t["status"] == "written")
    other = recommend(first.data, material="6082")
    presets = json.loads(other.data)["data"][0]["start-values"]["presets"]
    assert [p["name"] for p in presets] == ["Steel", NAME, "rcsa chatter-safe: aluminium 6082"]
    assert presets[:2] == json.loads(first.data)["data"][0]["start-values"]["presets"]


def test_feeds_follow_the_tools_own_preset(first):
    preset = json.loads(first.data)["data"][0]["start-values"]["presets"][1]
    assert preset["f_z"] == 0.05 and preset["v_f"] == pytest.approx(preset["n"] * 0.05 * 4)
    assert preset["v_f_plunge"] == pytest.approx(preset["v_f"] * 300 / 1200) and preset["tool-coolant"] == "flood"
    ball = first.report["tools"][1]
    assert any("no feed per tooth" in w for w in ball["warnings"])
    given = recommend(feed_per_tooth_m=2.54e-5)  # 0.001 in on the inch tool
    assert json.loads(given.data)["data"][1]["start-values"]["presets"][0]["f_z"] == pytest.approx(0.001)


def test_skips_say_why(first):
    by_index = {t["index"]: t for t in first.report["tools"]}
    assert by_index[2]["status"] == "skipped" and by_index[2]["reason"] == "no holder"
    assert by_index[3]["status"] == "skipped" and "standalone holder" in by_index[3]["reason"]
    hss = recommend(library(d0={"BMC": "hss"}))
    t0 = hss.report["tools"][0]
    assert t0["status"] == "skipped" and "max_surface_speed_m_min" in t0["reason"]
    assert recommend(library(d0={"BMC": "hss"}), max_surface_speed_m_min=200.0).report["tools"][0]["status"] == \
        "written"
    drill = recommend(library(d0={"type": "drill"})).report["tools"][0]
    assert drill["status"] == "skipped" and "not a milling cutter" in drill["reason"]
    fast = recommend(min_rpm=30000.0, max_rpm=40000.0).report["tools"][0]  # 750 m/min on 10 mm: 23 873 rpm
    assert fast["status"] == "skipped" and "no speed range" in fast["reason"] and "surface speed" in fast["reason"]


def test_the_tools_own_preset_for_the_material_caps_the_speed():
    data = library(**{"d0": {"start-values.presets": [{"name": "Aluminum 6061", "n": 8000, "f_z": 0.04}]}})
    t = recommend(data).report["tools"][0]
    assert t["speed_range"]["max_rpm"] == 8000 and t["spindle_speed_rpm"] <= 8000
    assert "own aluminium 7075 preset" in t["speed_range"]["limited_by"][0]


@pytest.mark.parametrize(("options", "field"), [
    ({"material": "carbon-steel"}, "tangential_coefficient_n_m2"),
    ({"material": "Inconel 718"}, "tangential_coefficient_n_m2"),
    ({"tangential_coefficient_n_m2": 1e9}, "radial_ratio"),
    ({"max_rpm": None}, "max_rpm"),
    ({"min_rpm": 30000}, "max_rpm"),
    ({"safety_factor": 0.8}, "safety_factor"),
    ({"method": "fourier"}, "method"),
    ({"confidence": 0.95}, "confidence"),
    ({"spindle_speed": 1}, "spindle_speed"),
])
def test_options_are_checked(options, field):
    with pytest.raises(InputError) as err:
        parse_recommend_options({k: v for k, v in {**OPTIONS, **options}.items() if v is not None})
    assert err.value.field == field


def test_own_material_with_its_coefficients():
    o = parse_recommend_options({"material": "Inconel 718", "tangential_coefficient_n_m2": 2.5e9,
                                 "radial_ratio": 0.4, "max_rpm": 8000, "max_surface_speed_m_min": 40})
    assert o.workpiece is None and o.coefficient_source == "given" and o.display_name == "Inconel 718"
    r = recommend(**{k: v for k, v in o.to_dict().items() if k in ("material", "tangential_coefficient_n_m2",
                                                                   "radial_ratio", "max_surface_speed_m_min")})
    assert r.report["preset_name"] == "rcsa chatter-safe: Inconel 718"
    assert r.report["options"]["coefficient_source"] == "given by the caller"


def test_freecad_libraries_are_refused():
    fctb = (SAMPLES / "freecad" / "5mm_Endmill.fctb").read_bytes()
    with pytest.raises(InputError, match="Fusion libraries .* only: FreeCAD"):
        recommend_predicted(Workbench(None), fctb, OPTIONS, file_name="5mm_Endmill.fctb", **SETTINGS)


def test_stored_results_give_the_same_presets_and_changed_tools_are_skipped(tmp_path, first):
    bench = Workbench(None, tmp_path / "store")
    sync_library(bench.libraries, "shop", SAMPLE, **SETTINGS, natural_frequencies=False)
    stored = recommend_stored(bench, "shop", SAMPLE, OPTIONS, file_name="shop.json")
    assert stored.data == first.data
    assert stored.report["frf_source"] == {"kind": "stored", "library_id": "shop", "revision": 1}
    # the file with rcsa's presets still matches the sync (presets are not part of a tool's result key)
    assert recommend_stored(bench, "shop", stored.data, OPTIONS).data == first.data
    moved = recommend_stored(bench, "shop", library(d0={"geometry.LB": 45, "geometry.assemblyGaugeLength": 115}),
                             OPTIONS)
    t0, t1 = moved.report["tools"][:2]
    assert t0["status"] == "skipped" and "changed since the last sync" in t0["reason"] and t1["status"] == "written"


def test_a_failed_frf_fails_the_tool_and_a_missing_one_skips_it():
    source = predicted_frfs(read_library(SAMPLE, file_name="shop.json"), **SETTINGS)
    ids = [e["id"] for e in source.entries]
    frfs = {ids[0]: FrfFailure("its tool-point FRF failed: tool.x: broken")}
    result = recommend_presets(read_fusion_file(SAMPLE), source.entries, frfs, parse_recommend_options(OPTIONS))
    t0, t1 = result.report["tools"][:2]
    assert t0["status"] == "failed" and "broken" in t0["reason"]
    assert t1["status"] == "skipped" and t1["reason"] == "no tool-point FRF for this tool"
    assert result.data == SAMPLE and result.report["summary"] == {"written": 0, "skipped": 3, "failed": 1}

"""``rcsa library recommend``: presets written into the Fusion file, the report, the failures."""

from __future__ import annotations

import io
import json
import zipfile

from typer.testing import CliRunner

from rcsa.cli import app
from rcsa.reference import ra1
from tests.helpers import REPO

SAMPLES = REPO / "tests" / "data" / "tool-libraries"
GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
NAME = "rcsa chatter-safe: aluminium 7075"
runner = CliRunner()
#: These tests are about files, flags and reports, not the lobes method: zero-order keeps each
#: recommendation to ~1 s (``auto`` verifies every preset by the resolved semi-discretization, ~15 s a
#: tool; that path is tests/libraries/test_recommend_methods.py's).


def test_recommend_on_a_spindle_writes_a_new_file_and_the_report(tmp_path):
    spindle = tmp_path / "ra1.json"
    spindle.write_text(json.dumps(ra1(GRID)))
    lib = SAMPLES / "fusion-synthetic" / "synthetic_library.tools"
    out, report = tmp_path / "with presets.tools", tmp_path / "report.json"
    args = ["library", "recommend", str(lib), "--spindle", str(spindle), "--material", "aluminium-7075",
            "--max-rpm", "24000", "--method", "zoa", "-o", str(out), "--report", str(report), "-q"]
    r = runner.invoke(app, args)
    assert r.exit_code == 0, r.stderr
    doc = json.loads(report.read_text())
    assert doc["summary"] == {"written": 2, "skipped": 2, "failed": 0} and r.stdout == ""
    assert "rpm, stepdown" in r.stderr and "2 presets written, 2 skipped, 0 failed" in r.stderr
    with zipfile.ZipFile(io.BytesIO(out.read_bytes())) as zf:
        tools = json.loads(zf.read("tools.json"))
    assert NAME in [p["name"] for p in tools["data"][0]["start-values"]["presets"]]
    assert lib.read_bytes() != out.read_bytes()  # LIBRARY itself untouched

    # --in-place twice on a copy: the second run replaces rcsa's presets, the file stays the same
    copy = tmp_path / "shop.tools"
    copy.write_bytes(lib.read_bytes())
    in_place = ["library", "recommend", str(copy), "--spindle", str(spindle), "--material", "7075",
                "--max-rpm", "24000", "--method", "zoa", "--in-place", "-q"]
    r = runner.invoke(app, in_place)
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["tools"][0]["preset"]["replaced"] is False
    with zipfile.ZipFile(copy) as a, zipfile.ZipFile(out) as b:
        assert a.read("tools.json") == b.read("tools.json")
    r = runner.invoke(app, in_place)
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["tools"][0]["preset"]["replaced"] is True
    assert copy.read_bytes() == out.read_bytes()


def test_recommend_refuses_what_it_cannot_do(tmp_path):
    spindle = tmp_path / "ra1.json"
    spindle.write_text(json.dumps(ra1(GRID)))
    lib = SAMPLES / "fusion-synthetic" / "synthetic_library.json"
    base = ["library", "recommend", str(lib), "--max-rpm", "24000", "-o", str(tmp_path / "o.json")]
    r = runner.invoke(app, [*base, "--material", "aluminium-7075"])
    assert r.exit_code == 1 and "exactly one of --spindle" in r.stderr
    r = runner.invoke(app, [*base, "--material", "carbon-steel", "--spindle", str(spindle)])
    assert r.exit_code == 1 and r.stderr.startswith("error: tangential_coefficient_n_m2: the table has no citable")
    fctb = SAMPLES / "freecad" / "5mm_Endmill.fctb"
    r = runner.invoke(app, ["library", "recommend", str(fctb), "--material", "7075", "--max-rpm", "24000",
                            "--spindle", str(spindle), "--in-place"])
    assert r.exit_code == 1 and "FreeCAD" in r.stderr and not (tmp_path / "o.json").exists()
    r = runner.invoke(app, ["library", "recommend", str(lib), "--material", "7075", "--max-rpm", "24000",
                            "--library-id", "nope", "--store", str(tmp_path / "store"), "--in-place"])
    assert r.exit_code == 1 and "nope" in r.stderr


def test_recommend_robust_presets_with_uncertainty_and_confidence(tmp_path):
    spindle = tmp_path / "ra1.json"
    spindle.write_text(json.dumps(ra1(GRID)))
    lib = SAMPLES / "fusion-synthetic" / "synthetic_library.json"
    args = ["library", "recommend", str(lib), "--spindle", str(spindle), "--material", "aluminium-7075",
            "--max-rpm", "24000", "--method", "zoa", "-o", str(tmp_path / "robust.json"), "-q",
            "--uncertainty", '{"draws": 12, "seed": 2}', "--confidence", "0.9"]
    r = runner.invoke(app, args)
    assert r.exit_code == 0, r.stderr
    tools = [t for t in json.loads(r.stdout)["tools"] if t["status"] == "written"]
    assert tools and all(t["confidence"] == 0.9 and t["robust_depth_limit_m"] <= t["depth_limit_m"] for t in tools)
    r = runner.invoke(app, [*args[:-4], "--confidence", "0.9"])
    assert r.exit_code == 1 and "confidence: needs uncertainty" in r.stderr

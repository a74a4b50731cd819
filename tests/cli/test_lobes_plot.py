"""``rcsa lobes`` and ``rcsa plot`` on the command line."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

import rcsa
from rcsa.cli import app
from rcsa.reference import ra1

runner = CliRunner()
GRID = {"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 2.0}
LOBES = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
         "milling": "down", "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 120}}


def test_lobes_from_an_assembly_with_a_plot(tmp_path):
    request = tmp_path / "lobes.json"
    request.write_text(json.dumps({"assembly": ra1(GRID), **LOBES}))
    picture = tmp_path / "lobes.png"
    result = runner.invoke(app, ["lobes", str(request), "--plot", str(picture)])
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["frf_y_source"] == "same_as_x"
    assert len(out["depth_limit_m"]) == 120 and out["lobes"]
    assert out["method"] == "semi_discretization" and len(out["resolved"]) == 120  # auto at a/D 0.5, 4 teeth
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_lobes_bad_request_is_one_line(tmp_path):
    request = tmp_path / "lobes.json"
    request.write_text(json.dumps({"assembly": ra1(GRID), **LOBES, "teeth": 0}))
    result = runner.invoke(app, ["lobes", str(request)])
    assert result.exit_code == 1 and result.stderr.startswith("error: teeth")


@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_plot_a_prediction_result(tmp_path, suffix):
    source = tmp_path / "result.json"
    source.write_text(json.dumps(rcsa.predict(ra1(GRID)).to_dict()))
    picture = tmp_path / f"frf{suffix}"
    result = runner.invoke(app, ["plot", str(source), "-o", str(picture)])
    assert result.exit_code == 0, result.stderr
    data = picture.read_bytes()
    assert data.startswith(b"\x89PNG") if suffix == ".png" else b"<svg" in data[:2000]


def test_plot_refuses_unknown_documents_and_formats(tmp_path):
    source = tmp_path / "x.json"
    source.write_text(json.dumps({"hello": 1}))
    result = runner.invoke(app, ["plot", str(source), "-o", str(tmp_path / "x.png")])
    assert result.exit_code == 1 and "not a prediction result" in result.stderr
    result = runner.invoke(app, ["plot", str(source), "-o", str(tmp_path / "x.jpg")])
    assert result.exit_code == 1 and ".png or .svg" in result.stderr


def test_plot_a_lobes_result_as_it_is(tmp_path):
    """`rcsa lobes ... -o out.json` then `rcsa plot out.json`: the result is drawn, not re-solved."""
    request = tmp_path / "lobes.json"
    request.write_text(json.dumps({"assembly": ra1(GRID), **LOBES, "method": "zoa"}))  # drawing, not solving
    out = tmp_path / "result.json"
    assert runner.invoke(app, ["lobes", str(request), "-o", str(out)]).exit_code == 0
    picture = tmp_path / "lobes.svg"
    result = runner.invoke(app, ["plot", str(out), "-o", str(picture)])
    assert result.exit_code == 0, result.stderr
    svg = picture.read_text()
    assert 'id="envelope"' in svg and 'id="lobe-0"' in svg
    # the contract's fields alone (another program's result) are enough
    doc = json.loads(out.read_text())
    minimal = {k: doc[k] for k in ("spindle_speed_rpm", "depth_limit_m", "chatter_frequency_hz", "lobes")}
    source = tmp_path / "minimal.json"
    source.write_text(json.dumps(minimal))
    assert runner.invoke(app, ["plot", str(source), "-o", str(tmp_path / "m.png")]).exit_code == 0
    source.write_text(json.dumps({**minimal, "depth_limit_m": minimal["depth_limit_m"][:-1]}))
    result = runner.invoke(app, ["plot", str(source), "-o", str(tmp_path / "m.png")])
    assert result.exit_code == 1 and result.stderr.startswith("error: depth_limit_m: must have one value per speed")


def test_robust_lobes_on_the_command_line_with_their_plot(tmp_path):
    request = tmp_path / "lobes.json"
    small = {**LOBES, "method": "zoa", "spindle_speed_rpm": {"start": 3000, "stop": 24000, "count": 100}}
    request.write_text(json.dumps({"assembly": ra1(GRID), **small, "uncertainty": {"draws": 4, "seed": 5}}))
    picture = tmp_path / "lobes.svg"
    result = runner.invoke(app, ["lobes", str(request), "--plot", str(picture)])
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)
    assert len(out["depth_limit_robust_m"]) == 100 and out["robust"]["draws"] == 4
    assert 'id="robust' in picture.read_text()
    again = tmp_path / "again.svg"  # rcsa plot draws what rcsa lobes wrote, robust limit included
    (tmp_path / "out.json").write_text(result.stdout)
    assert runner.invoke(app, ["plot", str(tmp_path / "out.json"), "-o", str(again)]).exit_code == 0
    assert 'id="robust' in again.read_text()


def test_plot_a_prediction_with_its_uncertainty_band(tmp_path):
    source = tmp_path / "prediction.json"
    prediction = rcsa.predict({**ra1(GRID), "uncertainty": {"draws": 4}}).to_dict()
    source.write_text(json.dumps(prediction))
    picture = tmp_path / "frf.svg"
    result = runner.invoke(app, ["plot", str(source), "-o", str(picture)])
    assert result.exit_code == 0, result.stderr
    assert 'id="band' in picture.read_text()

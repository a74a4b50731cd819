"""The ``rcsa`` command line: predict, and the one-line failure contract."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from rcsa.cli import app
from rcsa.reference import ra1

runner = CliRunner()


@pytest.fixture
def assembly_file(tmp_path):
    path = tmp_path / "ra1.json"
    path.write_text(json.dumps(ra1({"start_hz": 500.0, "stop_hz": 1500.0, "step_hz": 1.0})))
    return path


def test_predict_prints_the_contract_result(assembly_file):
    result = runner.invoke(app, ["predict", str(assembly_file)])
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)
    assert set(out) >= {"frequency_hz", "tool_point", "natural_frequencies_hz", "peaks",
                        "static_stiffness_n_m", "min_real_m_n"}
    assert [round(f, 2) for f in out["natural_frequencies_hz"]] == [599.85, 921.69, 1115.51, 1383.61, 1444.68]
    assert set(out["tool_point"]) == {"h", "l", "n", "p"}
    assert len(out["tool_point"]["h"]["real"]) == len(out["frequency_hz"]) == 1001


def test_predict_writes_out_file(assembly_file, tmp_path):
    out = tmp_path / "out.json"
    result = runner.invoke(app, ["predict", str(assembly_file), "-o", str(out)])
    assert result.exit_code == 0 and result.stdout == ""
    assert json.loads(out.read_text())["peaks"][0]["frequency_hz"] == 599.0


@pytest.mark.parametrize("content, words", [
    ("{not json", "not valid JSON"),
    (json.dumps({**ra1(), "tool": {**ra1()["tool"], "stickout_m": -1.0}}), "tool.stickout_m: must be > 0"),
])
def test_failure_is_one_line_on_stderr(tmp_path, content, words):
    path = tmp_path / "bad.json"
    path.write_text(content)
    result = runner.invoke(app, ["predict", str(path)])
    assert result.exit_code == 1
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and words in lines[0]


def test_missing_file(tmp_path):
    result = runner.invoke(app, ["predict", str(tmp_path / "nope.json")])
    assert result.exit_code == 1 and "cannot read" in result.stderr


@pytest.mark.parametrize("args", [["--help"], ["predict", "--help"], ["serve", "--help"], ["store", "--help"]])
def test_help(args):
    result = runner.invoke(app, args)
    assert result.exit_code == 0 and "Usage" in result.stdout

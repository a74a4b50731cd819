"""What the CLI prints: JSON for machines (pipes, files, --json), a table for a person at a terminal.

The contract's ``rcsa predict ASSEMBLY.json [-o OUT.json]`` (result on stdout, or in OUT) holds
wherever stdout is not a terminal, which is how every script and test sees it; only a terminal
gets the summary table instead (``rcsa.cli._common.emit``). The terminal is simulated by
``is_terminal``.
"""

from __future__ import annotations

import json
import sys

import pytest
from typer.testing import CliRunner

import rcsa.cli._common as common
from rcsa.cli import app
from rcsa.reference import ra1
from tests.helpers import REPO

runner = CliRunner()
EXAMPLES = REPO / "examples"


@pytest.fixture
def assembly_file(tmp_path):
    path = tmp_path / "ra1.json"
    path.write_text(json.dumps(ra1({"start_hz": 500.0, "stop_hz": 1500.0, "step_hz": 1.0})))
    return path


@pytest.fixture
def terminal(monkeypatch):
    """stdout (and stderr) are terminals."""
    monkeypatch.setattr(common, "is_terminal", lambda stream: stream in (sys.stdout, sys.stderr))


@pytest.fixture
def stderr_terminal(monkeypatch):
    """stdout is a pipe, stderr a terminal."""
    monkeypatch.setattr(common, "is_terminal", lambda stream: stream is sys.stderr)


def test_a_terminal_gets_the_summary_not_2_mb_of_json(assembly_file, terminal):
    r = runner.invoke(app, ["predict", str(assembly_file)])
    assert r.exit_code == 0, r.stderr
    assert "Natural frequencies (exact, undamped)" in r.stdout and "599.85" in r.stdout
    assert "static stiffness" in r.stdout and "most negative real part of h" in r.stdout
    assert "frequency_hz" not in r.stdout  # no JSON on the screen
    assert "--json" in r.stderr  # and how to get it


def test_json_flag_prints_the_json_even_on_a_terminal(assembly_file, terminal):
    r = runner.invoke(app, ["predict", str(assembly_file), "--json"])
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["static_stiffness_n_m"] > 0 and r.stderr == ""


def test_a_pipe_gets_the_json_and_the_terminal_on_stderr_the_table(assembly_file, stderr_terminal):
    r = runner.invoke(app, ["predict", str(assembly_file)])
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["natural_frequencies_hz"][0] == pytest.approx(599.85, abs=0.01)
    assert "static stiffness" in r.stderr


def test_nothing_but_json_without_a_terminal(assembly_file):
    r = runner.invoke(app, ["predict", str(assembly_file)])
    assert r.exit_code == 0 and r.stderr == ""
    json.loads(r.stdout)


def test_with_out_file_the_terminal_still_sees_the_table(assembly_file, tmp_path, terminal):
    out = tmp_path / "out.json"
    r = runner.invoke(app, ["predict", str(assembly_file), "-o", str(out)])
    assert r.exit_code == 0, r.stderr
    assert json.loads(out.read_text())["peaks"][0]["frequency_hz"] == 599.0
    assert "static stiffness" in r.stdout and f"wrote the prediction to {out}" in r.stderr


def test_a_batch_shows_one_row_per_combination(terminal):
    r = runner.invoke(app, ["predict", str(EXAMPLES / "batch.json")])
    assert r.exit_code == 0, r.stderr
    for ident in ("T1-ra1-74mm", "T1-ra1-50mm", "T7-d10"):
        assert ident in r.stdout
    assert "3 ok, 0 with an error" in r.stdout


def test_lobes_shows_the_absolute_limit_and_pockets(terminal):
    r = runner.invoke(app, ["lobes", str(EXAMPLES / "lobes-frf.json")])
    assert r.exit_code == 0, r.stderr
    assert "absolute limit" in r.stdout and "Best pockets" in r.stdout and "stepdown" in r.stdout


@pytest.mark.slow
def test_diagnose_shows_verdict_and_shrink(terminal):
    r = runner.invoke(app, ["diagnose", str(EXAMPLES / "diagnosis.json"), "-q"])
    assert r.exit_code == 0, r.stderr
    assert "holder_tool_joint (identified)" in r.stdout and "shrink on held-out" in r.stdout

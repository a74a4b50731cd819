"""``-o OUT.h5|.parquet`` on ``rcsa predict`` (a batch), ``rcsa library predict|sync|export``."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from rcsa.app.results import json_bytes
from rcsa.cli import app
from rcsa.reference import ra1
from tests.helpers import REPO
from tests.result_files import read_hdf5, read_parquet

GRID = {"start_hz": 100.0, "stop_hz": 3000.0, "step_hz": 50.0}
READERS = {".h5": read_hdf5, ".parquet": read_parquet}
LIBRARY = str(REPO / "examples/fusion-library.json")
runner = CliRunner()


@pytest.fixture
def batch_file(tmp_path):
    doc = ra1(GRID)
    path = tmp_path / "batch.json"
    path.write_text(json.dumps({"frequency": GRID, "spindle": doc["spindle"], "combinations": [
        {"id": "A", "holder": doc["holder"], "tool": doc["tool"], "joints": doc["joints"]},
        {"id": "B", "holder": doc["holder"], "tool": {**doc["tool"], "stickout_m": 0.05}}]}))
    return path


@pytest.mark.parametrize("suffix", [".h5", ".parquet"])
def test_predict_a_batch_to_a_binary_file(batch_file, tmp_path, suffix):
    as_json = runner.invoke(app, ["predict", str(batch_file)])
    assert as_json.exit_code == 0, as_json.stderr
    out = tmp_path / f"result{suffix}"
    r = runner.invoke(app, ["predict", str(batch_file), "-o", str(out)])
    assert r.exit_code == 0 and r.stdout == "", r.stderr
    document = READERS[suffix](out.read_bytes())
    assert json_bytes(document, indent=True) + b"\n" == as_json.stdout_bytes
    assert document["summary"] == {"ok": 2, "error": 0}


def test_one_assembly_is_refused_a_binary_file(tmp_path):
    path = tmp_path / "ra1.json"
    path.write_text(json.dumps(ra1(GRID)))
    r = runner.invoke(app, ["predict", str(path), "-o", str(tmp_path / "x.h5")])
    assert r.exit_code == 1 and "for batches and libraries" in r.stderr and not (tmp_path / "x.h5").exists()


@pytest.mark.parametrize("suffix", [".h5", ".parquet"])
def test_library_predict_sync_and_export_to_binary_files(tmp_path, monkeypatch, suffix):
    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "store"))
    common = ["--spindle", str(REPO / "examples/ra1.json"), "--frequency", "100:3000:50", "-q"]
    as_json = runner.invoke(app, ["library", "predict", LIBRARY, *common])
    out = tmp_path / f"predicted{suffix}"
    r = runner.invoke(app, ["library", "predict", LIBRARY, *common, "-o", str(out)])
    assert r.exit_code == 0, r.stderr
    assert json_bytes(READERS[suffix](out.read_bytes()), indent=True) + b"\n" == as_json.stdout_bytes

    synced = tmp_path / f"synced{suffix}"
    r = runner.invoke(app, ["library", "sync", LIBRARY, *common, "--library-id", "shop", "-o", str(synced)])
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["counts"]["added"]  # the report still goes to stdout
    exported = tmp_path / "exported.json"
    assert runner.invoke(app, ["library", "export", "shop", "-o", str(exported)]).exit_code == 0
    assert json_bytes(READERS[suffix](synced.read_bytes())) == exported.read_bytes()
    again = tmp_path / f"exported{suffix}"
    assert runner.invoke(app, ["library", "export", "shop", "-o", str(again)]).exit_code == 0
    assert json_bytes(READERS[suffix](again.read_bytes())) == exported.read_bytes()


def test_parquet_without_pyarrow_is_a_one_line_error(batch_file, tmp_path, monkeypatch):
    import rcsa.app.results as results

    monkeypatch.setattr(results, "parquet_available", lambda: False)
    r = runner.invoke(app, ["predict", str(batch_file), "-o", str(tmp_path / "x.parquet")])
    assert r.exit_code == 1 and "pip install 'rcsa[parquet]'" in r.stderr
    r = runner.invoke(app, ["library", "predict", LIBRARY, "--spindle", str(REPO / "examples/ra1.json"),
                            "--frequency", "100:3000:50", "-q", "-o", str(tmp_path / "x.parquet")])
    assert r.exit_code == 1 and r.stderr.startswith("error: format: Parquet results need pyarrow")

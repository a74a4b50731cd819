"""Stored libraries: incremental sync, content keys, a killed sync resumed, exports, CLI."""

from __future__ import annotations

import copy
import io
import json
import subprocess
import sys
import threading
import zipfile
from contextlib import closing

import h5py
import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from rcsa.app.measurements import demo_measurement
from rcsa.cli.library_cmd import register
from rcsa.libraries import exports, results_cache
from rcsa.libraries import sync as library_sync
from rcsa.measured.store import MeasurementStore
from rcsa.reference import ra1
from tests.helpers import REPO

SAMPLE = REPO / "tests" / "data" / "tool-libraries" / "fusion-synthetic" / "synthetic_library.json"
GRID = {"start_hz": 5.0, "stop_hz": 1000.0, "step_hz": 5.0}
RA1 = ra1(GRID)
SETTINGS = {"spindle": RA1["spindle"], "frequency": GRID, "joints": RA1["joints"]}


def tool_id(i: int) -> str:
    """The Fusion guid of synthetic tool ``i``."""
    return f"00000000-0000-4000-8000-{i + 1:012d}"


def make_tool(i: int, diameter_mm: float, stickout_mm: float) -> dict:
    """A Fusion tool item (the sample's first tool and holder) with its own guid, DC and LB."""
    t = copy.deepcopy(json.loads(SAMPLE.read_text())["data"][0])
    t["guid"], t["description"] = tool_id(i), f"synthetic {diameter_mm:g} mm, LB {stickout_mm:g} mm"
    t["post-process"]["number"] = i + 1
    flutes = min(2.0 * diameter_mm, stickout_mm - 6.0)
    t["geometry"].update({"DC": diameter_mm, "SFDM": diameter_mm, "LB": stickout_mm, "OAL": stickout_mm + 35.0,
                          "LCF": flutes, "shoulder-length": flutes + 3.0, "shoulder-diameter": diameter_mm,
                          "assemblyGaugeLength": 70.0 + stickout_mm})
    return t


def make_library(n: int) -> dict:
    """A Fusion library of ``n`` distinct tools (diameters 6-16 mm, stickouts 25-60 mm)."""
    return {"data": [make_tool(i, 6.0 + 2.0 * (i % 6), 25.0 + (7 * i) % 36) for i in range(n)], "version": 36}


@pytest.fixture
def libs(tmp_path):
    return library_sync.LibraryStore(tmp_path / "store" / "libraries")


@pytest.fixture
def computed(monkeypatch):
    """Counts the tools handed to the model (``compute_chunk``)."""
    count = {"tools": 0, "calls": 0}
    original = library_sync.compute_chunk

    def counting(batch, **kwargs):
        count["tools"] += len(batch["combinations"])
        count["calls"] += 1
        return original(batch, **kwargs)

    monkeypatch.setattr(library_sync, "compute_chunk", counting)
    return count


def test_same_sync_twice_computes_nothing(libs, computed):
    lib = make_library(5)
    first = library_sync.sync_library(libs, "shop", lib, **SETTINGS)
    assert computed["tools"] == 5 and first.computed == 5 and first.revision == 1
    assert first.added == tuple(tool_id(i) for i in range(5)) and not first.changed + first.unchanged + first.removed
    second = library_sync.sync_library(libs, "shop", lib, **SETTINGS)
    assert computed["tools"] == 5 and computed["calls"] == 1  # nothing new went to the model
    assert second.computed == 0 and second.from_cache == 5 and second.revision == 2
    assert second.unchanged == first.added and not second.added + second.changed + second.removed
    assert second.summary == {"ok": 5, "skipped": 0, "error": 0}


def test_changed_removed_added_are_reported_per_tool_id(libs, computed):
    lib = make_library(6)
    library_sync.sync_library(libs, "shop", lib, **SETTINGS)
    before = libs.get("shop")["tools"]
    computed["tools"] = 0

    lib["data"][2]["geometry"]["LB"] += 4.0                     # one stickout changed
    lib["data"][2]["geometry"]["assemblyGaugeLength"] += 4.0
    lib["data"][3]["description"] = "renamed; same geometry"    # not a result input
    report = library_sync.sync_library(libs, "shop", lib, **SETTINGS)
    assert report.changed == (tool_id(2),) and computed["tools"] == 1 and report.computed == 1
    assert report.unchanged == tuple(tool_id(i) for i in (0, 1, 3, 4, 5))
    after = libs.get("shop")["tools"]
    assert after[3]["description"] == "renamed; same geometry" and after[3]["revision"] == 1
    assert after[2]["revision"] == 2 and after[2]["result_sha256"] != before[2]["result_sha256"]

    del lib["data"][4]
    report = library_sync.sync_library(libs, "shop", lib, **SETTINGS)
    assert report.removed == (tool_id(4),) and not report.changed + report.added and report.computed == 0

    lib["data"].append(make_tool(9, 12.0, 44.0))
    report = library_sync.sync_library(libs, "shop", lib, **SETTINGS)
    assert report.added == (tool_id(9),) and report.computed == 1 and not report.changed + report.removed
    tools = libs.get("shop")["tools"]
    assert [t["id"] for t in tools] == [tool_id(i) for i in (0, 1, 2, 3, 5, 9)]
    assert computed["tools"] == 2


def test_settings_that_change_results_change_every_tool(libs, computed):
    lib = make_library(3)
    library_sync.sync_library(libs, "shop", lib, **SETTINGS)
    stiffer = {**SETTINGS, "joints": {**RA1["joints"], "holder_tool": {**RA1["joints"]["holder_tool"],
                                                                         "stiffness_n_m": 2.0e7}}}
    report = library_sync.sync_library(libs, "shop", lib, **stiffer)
    assert report.changed == tuple(tool_id(i) for i in range(3)) and report.computed == 3
    finer = {**SETTINGS, "frequency": {"start_hz": 5.0, "stop_hz": 1000.0, "step_hz": 2.5}}
    assert library_sync.sync_library(libs, "shop", lib, **finer).computed == 3
    # the old results are still cached: going back computes nothing, but every tool changed again
    back = library_sync.sync_library(libs, "shop", lib, **SETTINGS)
    assert back.computed == 0 and len(back.changed) == 3


def test_result_key_is_content_not_spelling(libs):
    base = library_sync.sync_request("a", make_library(2), **SETTINGS)
    plan = library_sync.plan_sync(libs, base)
    spelled = copy.deepcopy(base)
    spelled["batch"]["frequency"] = {"values_hz": np.arange(5.0, 1000.0 + 1, 5.0).tolist()}
    for combo in spelled["batch"]["combinations"]:
        combo["id"] = "renamed-" + combo["id"]
        combo["tool"]["stickout_m"] = float(combo["tool"]["stickout_m"])
        combo["joints"]["spindle_holder"]["stiffness_n_m"] = int(combo["joints"]["spindle_holder"]["stiffness_n_m"])
    spelled["batch"]["beam_theory"] = "timoshenko"   # the default, written out
    assert library_sync.plan_sync(libs, spelled).keys == plan.keys
    assert results_cache.canonical_json({"x": [1, -0.0]}) == results_cache.canonical_json({"x": [1.0, 0.0]})


def test_keys_made_in_bulk_are_the_keys_made_one_by_one(libs):
    request = library_sync.sync_request("a", make_library(7), **{**SETTINGS, "materials": {"x": {
        "youngs_modulus_pa": 2.1e11, "density_kg_m3": 7850, "poisson_ratio": 0.29}}})
    batch = request["batch"]
    shared = results_cache.shared_part(batch, None)
    fsha = results_cache.frequency_sha256(np.arange(5.0, 1000.0 + 1, 5.0))
    one_by_one = [results_cache.result_key(c, shared, fsha) for c in batch["combinations"]]
    assert results_cache.result_keys(batch["combinations"], shared, fsha) == one_by_one
    assert library_sync.plan_sync(libs, request).keys == tuple(one_by_one)
    assert len(set(one_by_one)) == 7


def test_model_version_is_part_of_the_key(libs, monkeypatch):
    request = library_sync.sync_request("a", make_library(1), **SETTINGS)
    key = library_sync.plan_sync(libs, request).keys[0]
    monkeypatch.setattr(results_cache, "model_fingerprint", lambda root=None: "0" * 64)
    assert library_sync.plan_sync(libs, request).keys[0] != key


def test_measured_spindle_is_keyed_by_its_content_not_its_id(tmp_path, computed):
    store = MeasurementStore(tmp_path / "store")
    first, copy_ = store.put(demo_measurement()), store.put(demo_measurement())
    libs = library_sync.LibraryStore.in_store(store.path)
    lib = make_library(2)
    grid = {"start_hz": 50.0, "stop_hz": 1000.0, "step_hz": 10.0}
    one = library_sync.sync_library(libs, "hyb", lib, store=store, spindle={"measurement_id": first}, frequency=grid)
    assert one.computed == 2 and one.summary["ok"] == 2
    two = library_sync.sync_library(libs, "hyb", lib, store=store, spindle={"measurement_id": copy_}, frequency=grid)
    assert two.computed == 0 and two.unchanged == one.added
    assert libs.get("hyb")["settings"]["spindle"] == {"measurement_id": copy_}


_KILLED_RUN = """
import json, os, signal, sys
from rcsa.libraries import sync as library_sync
request = json.load(open(sys.argv[1]))
libs = library_sync.LibraryStore(sys.argv[2])

def progress(done, total):
    if done >= 2:
        os.kill(os.getpid(), signal.SIGKILL)  # the worker dies between two tools

library_sync.run_sync(libs, request, progress=progress, chunk_tools=1)
"""


def test_killed_sync_resumes_from_the_cache(libs, tmp_path, computed):
    request = library_sync.sync_request("shop", make_library(5), **SETTINGS)
    path = tmp_path / "request.json"
    path.write_text(json.dumps(request))
    run = subprocess.run([sys.executable, "-c", _KILLED_RUN, str(path), str(libs.directory)], cwd=REPO,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == -9, run.stderr
    assert "shop" not in libs  # nothing committed
    report = library_sync.run_sync(libs, request)
    assert computed["tools"] == 3 and report.computed == 3 and report.from_cache == 2
    tools = libs.get("shop")["tools"]
    assert [t["id"] for t in tools] == [tool_id(i) for i in range(5)]  # each tool exactly once
    assert report.added == tuple(tool_id(i) for i in range(5)) and report.revision == 1
    # the cache holds exactly the five complete results under their keys, each readable (a chunk
    # is one transaction of the cache's database: a killed writer leaves all of it or none)
    keys = {t["result_sha256"] for t in tools}
    with closing(libs.cache._connect()) as con:
        stored = sorted(r[0] for r in con.execute("SELECT key FROM results"))
    assert len(keys) == 5 and stored == sorted(keys)
    assert all(libs.cache.get(k)["status"] == "ok" for k in keys)
    assert all(not p.name.endswith(".tmp") for p in libs.directory.rglob("*"))


def test_concurrent_syncs_commit_one_after_the_other(libs):
    lib = make_library(3)
    library_sync.sync_library(libs, "shop", lib, **SETTINGS)
    reports, errors = [], []

    def sync() -> None:
        try:
            reports.append(library_sync.sync_library(libs, "shop", lib, **SETTINGS))
        except Exception as exc:  # pragma: no cover - reported below
            errors.append(exc)

    threads = [threading.Thread(target=sync) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and sorted(r.revision for r in reports) == [2, 3, 4]
    assert len(libs.get("shop")["tools"]) == 3


def test_errors_and_skips_are_kept_and_reported(libs, monkeypatch, computed):
    lib = json.loads(SAMPLE.read_text())
    lib["data"] += [make_tool(7, 10.0, 40.0), make_tool(8, 8.0, 30.0)]
    lib["data"][-2]["geometry"]["OAL"] = 20.0  # shorter than its stickout: the import refuses it
    counting = library_sync.compute_chunk

    def model_refuses_tool_8(batch, **kwargs):  # as predict_batch reports a combination it refuses
        out = counting(batch, **kwargs)
        return [{"id": r["id"], "status": "error", "error": {"field": f"combinations[{k}].tool.stickout_m",
                                                             "detail": "refused"}}
                if r["id"] == tool_id(8) else r for k, r in enumerate(out)]

    monkeypatch.setattr(library_sync, "compute_chunk", model_refuses_tool_8)
    report = library_sync.sync_library(libs, "sample", lib, **SETTINGS)
    assert report.summary == {"ok": 2, "skipped": 2, "error": 2} and report.computed == 3
    assert report.failed == ({"id": tool_id(7), "error": {"field": "geometry.LB", "detail": report.failed[0][
        "error"]["detail"]}}, {"id": tool_id(8), "error": {"field": "tool.stickout_m", "detail": "refused"}})
    again = library_sync.sync_library(libs, "sample", lib, **SETTINGS)  # a refusal is a result too: cached
    assert again.computed == 0 and computed["tools"] == 3 and again.failed == report.failed
    assert len(again.unchanged) == 6
    results = libs.results("sample", ["h"])
    assert [r["status"] for r in results["results"]] == ["ok", "ok", "skipped", "skipped", "error", "error"]
    assert set(results["results"][0]["tool_point"]) == {"h"}
    assert results["results"][5]["error"] == {"field": "tool.stickout_m", "detail": "refused"}


def test_exports_read_back(libs, tmp_path):
    library_sync.sync_library(libs, "shop", make_library(3), **SETTINGS)
    results = libs.results("shop")
    expected = {r["id"]: np.asarray(r["tool_point"]["h"]["real"]) + 1j * np.asarray(r["tool_point"]["h"]["imag"])
                for r in results["results"]}
    f_hz = np.arange(5.0, 1000.0 + 1, 5.0)

    with h5py.File(io.BytesIO(exports.library_hdf5(results)), "r") as f:
        assert f.attrs["schema"] == exports.HDF5_SCHEMA and f.attrs["schema_version"] == 2
        assert f.attrs["library_id"] == "shop" and f.attrs["revision"] == 1
        assert f["frequency_hz"].attrs["units"] == "Hz"
        np.testing.assert_array_equal(f["frequency_hz"][()], f_hz)
        assert list(f["id"].asstr()[()]) == list(expected)
        h = f["tool_point/h"]
        assert h.attrs["units"] == "m/N" and h.dtype == np.complex128
        for row, name in enumerate(expected):
            np.testing.assert_array_equal(h[row], expected[name])  # bit-exact

    import pyuff

    archive = zipfile.ZipFile(io.BytesIO(exports.library_uff_zip(results)))
    index = json.loads(archive.read("index.json"))
    assert [t["id"] for t in index["tools"]] == list(expected)
    for entry in index["tools"]:
        path = tmp_path / entry["file"]
        path.write_bytes(archive.read(entry["file"]))
        uff = pyuff.UFF(str(path))
        assert list(uff.get_set_types()) == [164, 58]
        assert uff.read_sets(0)["units_code"] == 1
        d = uff.read_sets(1)
        assert d["func_type"] == 4 and d["ordinate_spec_data_type"] == 8 and d["orddenom_spec_data_type"] == 13
        np.testing.assert_allclose(d["x"], f_hz, rtol=1e-12)
        h = expected[entry["id"]]
        assert np.max(np.abs(d["data"] - h)) <= 1e-11 * np.max(np.abs(h))  # ASCII UFF: ~12 digits


def _cli():
    app = typer.Typer()

    @app.callback()
    def main() -> None:
        """Test root."""

    register(app)
    return app


def test_cli_sync_show_export(tmp_path, monkeypatch):
    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "store"))
    spindle, lib_path = tmp_path / "ra1.json", tmp_path / "Mill tools.json"
    spindle.write_text(json.dumps(RA1))
    lib = make_library(3)
    lib_path.write_text(json.dumps(lib))
    runner = CliRunner()
    args = ["library", "sync", str(lib_path), "--spindle", str(spindle), "--frequency", "5:1000:5", "-q"]
    r = runner.invoke(_cli(), args)
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["library_id"] == "Mill-tools"
    assert "3 added, 0 changed, 0 unchanged, 0 removed (3 computed" in r.stderr
    r = runner.invoke(_cli(), args)
    assert r.exit_code == 0 and "0 added, 0 changed, 3 unchanged, 0 removed (0 computed, 3 from cache" in r.stderr

    r = runner.invoke(_cli(), ["library", "show", "Mill-tools"])
    assert r.exit_code == 0 and [t["id"] for t in json.loads(r.stdout)["tools"]] == [tool_id(i) for i in range(3)]
    for name in ("out.h5", "out.zip", "out.json"):
        r = runner.invoke(_cli(), ["library", "export", "Mill-tools", "-o", str(tmp_path / name)])
        assert r.exit_code == 0, r.stderr
    with h5py.File(tmp_path / "out.h5", "r") as f:
        assert len(f["id"]) == 3 and f["tool_point/h"].shape[0] == 3
    assert len(zipfile.ZipFile(tmp_path / "out.zip").namelist()) == 4
    assert json.loads((tmp_path / "out.json").read_text())["summary"]["ok"] == 3

    lib["data"][1]["geometry"]["OAL"] = 20.0  # a tool that cannot be mapped: exit 1, named on stderr
    lib_path.write_text(json.dumps(lib))
    r = runner.invoke(_cli(), [*args, "--library-id", "other"])
    assert r.exit_code == 1 and f"error: {tool_id(1)}: geometry.LB: " in r.stderr
    r = runner.invoke(_cli(), ["library", "show", "nope"])
    assert r.exit_code == 1 and r.stderr.startswith("error: ")
    r = runner.invoke(_cli(), ["library", "export", "Mill-tools", "-o", str(tmp_path / "out.csv")])
    assert r.exit_code == 1


def test_cli_library_predict_with_an_uncertainty_band(tmp_path):
    spindle, lib_path = tmp_path / "ra1.json", tmp_path / "tools.json"
    spindle.write_text(json.dumps(RA1))
    lib_path.write_text(json.dumps(make_library(2)))
    args = ["library", "predict", str(lib_path), "--spindle", str(spindle), "--frequency", "5:1000:5", "-q",
            "--uncertainty", '{"draws": 3, "seed": 2}']
    r = CliRunner().invoke(_cli(), args)
    assert r.exit_code == 0, r.stderr
    ok = [item for item in json.loads(r.stdout)["results"] if item["status"] == "ok"]
    assert ok and all(item["uncertainty"]["draws"] == 3 for item in ok)
    r = CliRunner().invoke(_cli(), [*args[:-1], '{"draws": 1}'])
    assert r.exit_code == 1 and "uncertainty.draws" in r.stderr

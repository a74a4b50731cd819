"""``rcsa store check`` and ``rcsa store rebuild`` on a store with a corrupt file."""

from __future__ import annotations

import json
import sqlite3
from contextlib import closing

import numpy as np
from typer.testing import CliRunner

from rcsa.cli.store_cmd import store_app
from rcsa.measured.store import Measurement, MeasurementMeta, MeasurementStore


def _measurement(n: int = 50) -> Measurement:
    f = np.linspace(10.0, 1000.0, n)
    return Measurement(f, {"h": (1e-7 - 2e-7j) / (1 + 1j * f / 500)}, MeasurementMeta("mc1", "x", "spindle_nose",
                                                                                        "direct_frf"))


def _flip_a_data_byte(path) -> None:
    """Corrupt a byte inside the compressed FRF data (Fletcher-32 catches it on read)."""
    raw = bytearray(path.read_bytes())
    i = len(raw) // 2
    raw[i] ^= 0xFF
    path.write_bytes(bytes(raw))


def test_check_reports_a_corrupt_file_and_the_catalogue_and_rebuild_repairs_the_catalogue(tmp_path):
    runner = CliRunner()
    store = MeasurementStore(tmp_path / "store")
    good, bad, gone = store.put(_measurement()), store.put(_measurement(400)), store.put(_measurement())
    assert len(store.list()) == 3  # all in the catalogue
    (store.path / "measurements" / f"{gone}.h5").unlink()  # removed behind the store's back
    _flip_a_data_byte(store.path / "measurements" / f"{bad}.h5")
    (store.path / "measurements" / "m-00000000dead.h5").write_bytes(b"\x89HDF\r\n truncated")  # a truncated file
    with closing(sqlite3.connect(store.path / "index.sqlite")) as con, con:  # a row whose file is gone
        con.execute("DELETE FROM measurements WHERE id = ?", (good,))

    result = runner.invoke(store_app, ["check", "--store", str(store.path)])
    assert result.exit_code == 1, result.output
    report = json.loads(result.stdout)
    assert report["ok"] is False and report["measurements"] == 3 and report["readable"] == 1
    found = {(p["id"], p["problem"]) for p in report["problems"]}
    assert found == {(bad, "damaged"), ("m-00000000dead", "damaged"), (good, "catalogue-missing"),
                     (gone, "catalogue-stale")}, found
    assert store.path.joinpath("index.sqlite").exists()  # check changed nothing: still missing
    with closing(sqlite3.connect(store.path / "index.sqlite")) as con:
        assert con.execute("SELECT COUNT(*) FROM measurements WHERE id = ?", (good,)).fetchone() == (0,)

    result = runner.invoke(store_app, ["rebuild", "--store", str(store.path)])
    assert result.exit_code == 1  # the damaged files are still there
    report = json.loads(result.stdout)
    # the truncated file cannot even be listed; the one with a flipped data byte is listed
    # (its metadata reads) but reported damaged (its checksum fails)
    assert report["measurements"] == 2 and report["damaged"] == sorted([bad, "m-00000000dead"])
    report = json.loads(runner.invoke(store_app, ["check", "--store", str(store.path)]).stdout)
    assert {p["problem"] for p in report["problems"]} == {"damaged"}  # the catalogue is consistent again

    for mid in (bad, "m-00000000dead"):  # the operator removes the damaged files
        (store.path / "measurements" / f"{mid}.h5").unlink()
    report = json.loads(runner.invoke(store_app, ["check", "--store", str(store.path)]).stdout)
    assert [(p["id"], p["problem"]) for p in report["problems"]] == [(bad, "catalogue-stale")]
    result = runner.invoke(store_app, ["rebuild", "--store", str(store.path)])
    assert result.exit_code == 0 and json.loads(result.stdout) == {
        "store": str(store.path), "ok": True, "measurements": 1, "damaged": []}
    assert runner.invoke(store_app, ["check", "--store", str(store.path)]).exit_code == 0

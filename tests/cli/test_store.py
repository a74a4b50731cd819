"""``rcsa store import | list | show | delete`` through typer's CliRunner on a temporary store."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from rcsa.cli.store_cmd import store_app
from rcsa.measured.store import MeasurementStore

F = np.arange(10.0, 1010.0, 10.0)
H = (1e-7 - 2e-7j) / (1 + 1j * F / 500)


@pytest.fixture
def runner():
    return CliRunner()


@pytest.fixture
def csv_um(tmp_path):
    path = tmp_path / "tip.csv"
    path.write_text(
        "f,re,im\n"
        + "".join(
            f"{a:.17g},{b.real * 1e6:.17g},{b.imag * 1e6:.17g}\n" for a, b in zip(F, H, strict=True)
        )
    )
    return path


def _ok(result):
    assert result.exit_code == 0, (result.stdout, result.stderr)
    return (
        json.loads(result.stdout) if result.stdout.strip().startswith(("{", "[")) else result.stdout
    )


def test_import_list_show_delete(runner, tmp_path, csv_um):
    store = tmp_path / "store"
    out = _ok(
        runner.invoke(
            store_app,
            [
                "import",
                str(csv_um),
                "--store",
                str(store),
                "--spindle-id",
                "mc1",
                "--direction",
                "x",
                "--plane",
                "spindle_nose",
                "--units",
                "um/N",
                "--machine",
                "DMU50",
            ],
        )
    )
    mid = out["id"]
    assert (
        out["spindle_id"] == "mc1"
        and out["kind"] == "direct_frf"
        and out["source"]["original_units"] == "um/N"
    )
    np.testing.assert_allclose(MeasurementStore(store).get(mid).frfs["h"], H, rtol=1e-14, atol=0)

    listed = _ok(runner.invoke(store_app, ["list", "--json", "--store", str(store)]))
    assert [i["id"] for i in listed] == [mid]
    assert (
        _ok(
            runner.invoke(
                store_app, ["list", "--json", "--store", str(store), "--spindle-id", "other"]
            )
        )
        == []
    )
    table = _ok(runner.invoke(store_app, ["list", "--store", str(store)]))
    assert mid in table and "DMU50" in table

    shown = _ok(runner.invoke(store_app, ["show", mid, "--store", str(store)]))
    assert shown["id"] == mid and "frequency_hz" not in shown
    assert shown["summary"]["h"]["frequency_at_max_hz"] == 10.0
    full = _ok(runner.invoke(store_app, ["show", mid, "--data", "--store", str(store)]))
    assert full["frequency_hz"] == F.tolist()

    assert _ok(runner.invoke(store_app, ["delete", mid, "--store", str(store)])) == {"deleted": mid}
    assert _ok(runner.invoke(store_app, ["list", "--json", "--store", str(store)])) == []


def test_store_location_from_environment(runner, tmp_path, csv_um, monkeypatch):
    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "env-store"))
    out = _ok(
        runner.invoke(
            store_app,
            [
                "import",
                str(csv_um),
                "--spindle-id",
                "mc1",
                "--direction",
                "y",
                "--plane",
                "holder_tip",
                "--units",
                "um/N",
            ],
        )
    )
    assert (tmp_path / "env-store" / "measurements" / f"{out['id']}.h5").is_file()


def test_import_contract_json_and_export_reimport(runner, tmp_path):
    store = str(tmp_path / "store")
    doc = {
        "spindle_id": "mc1-hsk63",
        "direction": "x",
        "plane": "spindle_nose",
        "kind": "direct_frf",
        "frequency_hz": F.tolist(),
        "h": {"real": H.real.tolist(), "imag": H.imag.tolist()},
    }
    (tmp_path / "m.json").write_text(json.dumps(doc))
    mid = _ok(runner.invoke(store_app, ["import", str(tmp_path / "m.json"), "--store", store]))[
        "id"
    ]
    exported = _ok(runner.invoke(store_app, ["show", mid, "--data", "--store", store]))
    (tmp_path / "e.json").write_text(json.dumps(exported))
    again = _ok(
        runner.invoke(
            store_app, ["import", str(tmp_path / "e.json"), "--format", "json", "--store", store]
        )
    )
    assert again["id"] != mid
    s = MeasurementStore(store)
    assert s.get(again["id"]).frfs["h"].tobytes() == s.get(mid).frfs["h"].tobytes()


def test_import_uff_with_roles(runner, tmp_path):
    from tests.measured.importers._synth import frf58, write_uff

    sets = [
        frf58(F, H, binary=1, rsp=(1, 1), ref=(1, 1)),
        frf58(F, 0.5 * H, binary=1, rsp=(2, 1), ref=(1, 1)),
        frf58(F, 0.7 * H, binary=1, rsp=(2, 1), ref=(2, 1)),
    ]
    path = write_uff(tmp_path / "art.uff", sets, (1, 1.0, 1.0))
    artifact = json.dumps({"diameter_m": 0.016, "stickout_m": 0.06})
    out = _ok(
        runner.invoke(
            store_app,
            [
                "import",
                str(path),
                "--store",
                str(tmp_path / "s"),
                "--spindle-id",
                "mc1",
                "--direction",
                "x",
                "--plane",
                "spindle_nose",
                "--kind",
                "artifact_frfs",
                "--roles",
                "h11=1:1,h21=2:1,h22=2:2",
                "--points-m",
                "0,0.02",
                "--artifact",
                artifact,
            ],
        )
    )
    assert out["frfs"] == ["h11", "h21", "h22"] and out["points_m"] == [0.0, 0.02]
    assert out["artifact"]["diameter_m"] == 0.016


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--units", "furlong/N"], "units: unknown FRF unit"),
        ([], "units: the FRF unit must be declared"),
        (["--units", "um/N", "--format", "xls"], "format"),
        (["--units", "um/N", "--direction", "z"], "direction: must be one of x, y"),
        (
            ["--units", "um/N", "--columns", "f,re,im,coh"],
            "columns: line 2 has 3 values but 4 columns",
        ),
    ],
)
def test_failures_exit_nonzero_with_one_line(runner, tmp_path, csv_um, args, needle):
    base = [
        "import",
        str(csv_um),
        "--store",
        str(tmp_path / "store"),
        "--spindle-id",
        "mc1",
        "--plane",
        "spindle_nose",
    ]
    if "--direction" not in args:
        base += ["--direction", "x"]
    result = runner.invoke(store_app, base + args)
    assert result.exit_code == 1
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and needle in lines[0], result.stderr
    assert "Traceback" not in result.stderr
    assert MeasurementStore(tmp_path / "store").list() == []  # nothing stored


def test_missing_things_fail_cleanly(runner, tmp_path):
    store = ["--store", str(tmp_path / "store")]
    for args, needle in [
        (["show", "m-0123456789ab", *store], "measurement 'm-0123456789ab' not found"),
        (["delete", "nope", *store], "not found"),
        (
            [
                "import",
                str(tmp_path / "absent.csv"),
                "--spindle-id",
                "a",
                "--direction",
                "x",
                "--plane",
                "spindle_nose",
                "--units",
                "m/N",
                *store,
            ],
            "no such file",
        ),
        (["import", str(tmp_path / "x.csv"), "--units", "m/N", *store], "--spindle-id is required"),
    ]:
        result = runner.invoke(store_app, args)
        assert result.exit_code == 1 and needle in result.stderr, (args, result.stderr)
        assert len(result.stderr.strip().splitlines()) == 1


def test_import_tap_and_cutpro(runner, tmp_path):
    from tests.measured.importers.test_import_tap import T, _acceleration, _pulse, _write

    force = _pulse()
    tap = _write(tmp_path / "tap.txt", T, force, _acceleration(force))
    store = [
        "--store",
        str(tmp_path / "s"),
        "--spindle-id",
        "mc1",
        "--direction",
        "x",
        "--plane",
        "holder_tip",
    ]
    out = _ok(
        runner.invoke(
            store_app,
            [
                "import",
                str(tap),
                "--format",
                "tap",
                *store,
                "--force-unit",
                "N",
                "--response-unit",
                "m/s^2",
                "--max-frequency-hz",
                "800",
                "--sensor-mass-kg",
                "0.002",
            ],
        )
    )
    assert out["n_frequencies"] == 800 and out["source"]["sensor_mass_kg"] == 0.002
    frf = tmp_path / "tip.frf"
    frf.write_text(
        "".join(f"{a:.6e}\t{b.real:.6e}\t{b.imag:.6e}\n" for a, b in zip(F, H, strict=True))
    )
    out = _ok(runner.invoke(store_app, ["import", str(frf), *store]))
    assert out["source"]["format"] == "cutpro_frf" and out["n_frequencies"] == F.size

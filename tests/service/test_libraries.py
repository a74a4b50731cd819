"""POST /v1/tool-libraries:predict with the sample Fusion libraries, and `rcsa library predict`."""

from __future__ import annotations

import json
import time

import pytest
import typer
from typer.testing import CliRunner

from rcsa.cli.library_cmd import register
from rcsa.libraries import library_prediction as library_api
from rcsa.reference import ra1
from tests.helpers import REPO

from .conftest import GRID, assert_problem

LIBS = REPO / "tests" / "data" / "tool-libraries" / "fusion-synthetic"
RA1 = ra1(GRID)
FORM = {"spindle": json.dumps(RA1["spindle"]), "frequency": json.dumps(GRID), "joints": json.dumps(RA1["joints"])}


@pytest.mark.parametrize("name", ["synthetic_library.json", "synthetic_library.tools"])
def test_fusion_library_upload(client, name):
    r = client.post("/v1/tool-libraries:predict", files={"library": (name, (LIBS / name).read_bytes())}, data=FORM)
    assert r.status_code == 200, r.text
    out = r.json()
    assert out["summary"] == {"ok": 2, "skipped": 2, "error": 0}
    statuses = [(x["status"], x.get("reason")) for x in out["results"]]
    assert statuses == [("ok", None), ("ok", None), ("skipped", "no holder"),
                        ("skipped", "standalone holder (type: holder), not a tool")]
    assert [x["index"] for x in out["results"]] == [0, 1, 2, 3]
    ok = out["results"][0]
    assert len(ok["frequency_hz"]) == 1000 and ok["natural_frequencies_hz"] and ok["teeth"] == 4
    expected = library_api.predict_library(LIBS / name, spindle=RA1["spindle"], frequency=GRID, joints=RA1["joints"])
    assert out["results"][1]["tool_point"]["h"] == expected["results"][1]["tool_point"]["h"]


def test_library_as_json_body_and_as_a_job(make_client):
    doc = json.loads((LIBS / "synthetic_library.json").read_text())
    with make_client(async_batch_threshold=1) as client:
        body = {"library": doc, "spindle": RA1["spindle"], "frequency": GRID, "options": {"holder_segments_per_cone": 2}}
        r = client.post("/v1/tool-libraries:predict", json=body)
        assert r.status_code == 202, r.text
        location = r.headers["location"]
        for _ in range(6000):  # up to 5 min on a loaded machine; pytest-timeout is the last guard
            job = client.get(location).json()
            if job["status"] in ("succeeded", "failed"):
                break
            time.sleep(0.05)
        assert job["status"] == "succeeded" and job["kind"] == "library"
        result = client.get(job["result_url"]).json()
        assert result["summary"] == {"ok": 2, "skipped": 2, "error": 0}


def test_library_errors(client):
    raw = (LIBS / "synthetic_library.json").read_bytes()
    r = client.post("/v1/tool-libraries:predict", files={"library": ("lib.json", b"{nope")}, data=FORM)
    assert_problem(r, 422, "")
    r = client.post("/v1/tool-libraries:predict", files={"library": ("lib.json", raw)},
                    data={**FORM, "frequency": json.dumps({"start_hz": 0.0, "stop_hz": 1.0, "step_hz": 1.0})})
    assert_problem(r, 422, "frequency.start_hz")
    r = client.post("/v1/tool-libraries:predict", files={"library": ("lib.json", raw)},
                    data={"frequency": FORM["frequency"]})
    assert_problem(r, 422, "spindle")
    r = client.post("/v1/tool-libraries:predict", files={"library": ("lib.json", raw)},
                    data={**FORM, "measurement_id": "m-000000000000"})
    assert_problem(r, 422, "measurement_id")
    r = client.post("/v1/tool-libraries:predict", files={"library": ("lib.json", raw)},
                    data={"frequency": FORM["frequency"], "measurement_id": "m-000000000000"})
    assert_problem(r, 422, "spindle.measurement_id")
    r = client.post("/v1/tool-libraries:predict", files={"library": ("lib.json", raw)},
                    data={**FORM, "options": json.dumps({"holder_segments_per_cone": 0})})
    assert_problem(r, 422, "holder_segments_per_cone")
    r = client.post("/v1/tool-libraries:predict", files={"library": ("lib.json", raw)}, data={**FORM, "spindle": "{"})
    assert_problem(r, 422, "spindle")
    r = client.post("/v1/tool-libraries:predict", json={"library": {"data": []}, "frequency": GRID})
    assert_problem(r, 422, "spindle")
    assert_problem(client.post("/v1/tool-libraries:predict", content=b"x", headers={"content-type": "text/plain"}), 415)


def _cli():
    app = typer.Typer()

    @app.callback()
    def main() -> None:
        """Test root."""

    register(app)
    return app


def test_cli_library_predict(tmp_path, monkeypatch):
    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "store"))
    spindle = tmp_path / "ra1.json"
    spindle.write_text(json.dumps(RA1))
    out = tmp_path / "out.json"
    runner = CliRunner()
    r = runner.invoke(_cli(), ["library", "predict", str(LIBS / "synthetic_library.tools"), "--spindle", str(spindle),
                               "--frequency", "5:5000:5", "-o", str(out)])
    assert r.exit_code == 0, r.stderr
    result = json.loads(out.read_text())
    assert result["summary"] == {"ok": 2, "skipped": 2, "error": 0}
    assert "2 ok, 2 skipped, 0 error" in r.stderr
    bad = tmp_path / "bad.json"
    doc = json.loads((LIBS / "synthetic_library.json").read_text())
    doc["data"][0]["geometry"]["LB"] = -1.0  # a tool that cannot be mapped → status error, exit 1
    bad.write_text(json.dumps(doc))
    r = runner.invoke(_cli(), ["library", "predict", str(bad), "--spindle", str(spindle), "--frequency", "5:5000:5",
                               "-q"])
    assert r.exit_code == 1
    assert json.loads(r.stdout)["summary"]["error"] == 1 and "error: " in r.stderr
    r = runner.invoke(_cli(), ["library", "predict", str(bad), "--frequency", "5:5000:5"])
    assert r.exit_code == 1 and "--spindle" in r.stderr
    r = runner.invoke(_cli(), ["library", "predict", str(LIBS / "synthetic_library.json"), "--spindle", str(spindle),
                               "--frequency", "5-5000"])
    assert r.exit_code == 1 and r.stderr.startswith("error: frequency")


# --------------------------------------------------------------------------- FreeCAD

FREECAD = REPO / "tests" / "data" / "tool-libraries" / "freecad"
FC_BITS = ("5mm_Endmill", "6mm_Ball_End")


def _freecad_zip(with_holder: bool = True) -> bytes:
    import io
    import zipfile

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for name in FC_BITS:
            zf.writestr(f"Bit/{name}.fctb", (FREECAD / f"{name}.fctb").read_bytes())
        if with_holder:
            zf.writestr("Holder/ER32_Standard.fcholder", (FREECAD / "ER32_Standard.fcholder").read_bytes())
    return buf.getvalue()


def test_freecad_zip_upload_has_the_fusion_result_shape(client):
    form = {**FORM, "options": json.dumps({"stickout_m": 0.040})}
    r = client.post("/v1/tool-libraries:predict", files={"library": ("Tools.zip", _freecad_zip(), "application/zip")},
                    data=form)
    assert r.status_code == 200, r.text
    out = r.json()
    assert out["summary"] == {"ok": 2, "skipped": 0, "error": 0}
    assert [x["id"] for x in out["results"]] == ["5mm_Endmill@ER32_Standard", "6mm_Ball_End@ER32_Standard"]
    assert set(out["results"][0]) >= {"id", "index", "status", "warnings", "tool_point", "frequency_hz",
                                      "natural_frequencies_hz", "notes"}
    # one toolbit file and the holder as its own field: the same first result
    r = client.post("/v1/tool-libraries:predict", data=form, files=[
        ("library", ("5mm_Endmill.fctb", (FREECAD / "5mm_Endmill.fctb").read_bytes(), "application/octet-stream")),
        ("holder", ("ER32_Standard.fcholder", (FREECAD / "ER32_Standard.fcholder").read_bytes()))])
    assert r.status_code == 200, r.text
    assert r.json()["results"][0]["tool_point"] == out["results"][0]["tool_point"]


def test_freecad_json_body_and_refusals(client):
    doc = {"format": "freecad", "toolbits": {n: json.loads((FREECAD / f"{n}.fctb").read_text()) for n in FC_BITS},
           "holder": {"ER32": json.loads((FREECAD / "ER32_Standard.fcholder").read_text())}}
    body = {"library": doc, "spindle": RA1["spindle"], "frequency": GRID,
            "options": {"stickout_m": {"5mm_Endmill": 0.04, "6mm_Ball_End": 0.045}}}
    r = client.post("/v1/tool-libraries:predict", json=body)
    assert r.status_code == 200, r.text
    assert [x["status"] for x in r.json()["results"]] == ["ok", "ok"]
    r = client.post("/v1/tool-libraries:predict", json={**body, "options": {}})
    assert_problem(r, 422, "stickout_m")
    r = client.post("/v1/tool-libraries:predict", data=FORM,
                    files={"library": ("renamed.fctb", (LIBS / "synthetic_library.json").read_bytes())})
    assert_problem(r, 422, "library")
    r = client.post("/v1/tool-libraries:predict", data=FORM, files=[
        ("library", ("synthetic_library.json", (LIBS / "synthetic_library.json").read_bytes())),
        ("holder", ("ER32.fcholder", (FREECAD / "ER32_Standard.fcholder").read_bytes()))])
    assert_problem(r, 422, "holder")


def test_freecad_sync_keeps_ids_across_syncs(client):
    from .conftest import WRITE

    form = {**FORM, "options": json.dumps({"stickout_m": 0.040})}
    files = {"library": ("Tools.zip", _freecad_zip())}
    first = client.post("/v1/libraries/fc-shop:sync", files=files, data=form, headers=WRITE)
    assert first.status_code == 201, first.text
    assert first.json()["counts"] == {"added": 2, "changed": 0, "unchanged": 0, "removed": 0}
    again = client.post("/v1/libraries/fc-shop:sync", files={"library": ("Tools.zip", _freecad_zip())}, data=form,
                        headers=WRITE)
    assert again.json()["counts"] == {"added": 0, "changed": 0, "unchanged": 2, "removed": 0}
    assert again.json()["computed"] == 0


def test_cli_freecad_predict_and_sync(tmp_path, monkeypatch):
    import shutil

    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "store"))
    spindle = tmp_path / "ra1.json"
    spindle.write_text(json.dumps(RA1))
    bits = tmp_path / "Tools" / "Bit"
    bits.mkdir(parents=True)
    for name in FC_BITS:
        shutil.copy(FREECAD / f"{name}.fctb", bits)
    (tmp_path / "Tools" / "Library").mkdir()
    fctl = tmp_path / "Tools" / "Library" / "Shop.fctl"
    fctl.write_text(json.dumps({"version": 1, "tools": [{"nr": 4, "path": "5mm_Endmill.fctb"}]}))
    runner = CliRunner()
    common = ["--spindle", str(spindle), "--frequency", "5:2000:5", "--holder", str(FREECAD / "ER32_Standard.fcholder"),
              "--options", '{"stickout_m": 0.04}', "-q"]
    r = runner.invoke(_cli(), ["library", "predict", str(fctl), *common])
    assert r.exit_code == 0, r.stderr
    out = json.loads(r.stdout)
    assert [(x["id"], x["number"], x["status"]) for x in out["results"]] == [("5mm_Endmill@ER32_Standard", 4, "ok")]
    r = runner.invoke(_cli(), ["library", "sync", str(bits), *common])
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["counts"]["added"] == 2
    r = runner.invoke(_cli(), ["library", "predict", str(bits), *common[:-3], "-q"])
    assert r.exit_code == 1 and "stickout_m" in r.stderr


def test_library_upload_with_an_uncertainty_band_form_and_json(client):
    name = "synthetic_library.json"
    option = {"draws": 8, "seed": 4}
    r = client.post("/v1/tool-libraries:predict", files={"library": (name, (LIBS / name).read_bytes())},
                    data={**FORM, "uncertainty": json.dumps(option)})
    assert r.status_code == 200, r.text
    ok = [x for x in r.json()["results"] if x["status"] == "ok"]
    assert len(ok) == 2 and all(x["uncertainty"]["draws"] == 8 for x in ok)
    band = ok[0]["uncertainty"]["h_magnitude_m_n"]
    assert all(a <= b <= c for a, b, c in zip(band["p05"], band["p50"], band["p95"], strict=True))
    body = {"library": json.loads((LIBS / name).read_text()), "spindle": RA1["spindle"], "frequency": GRID,
            "joints": RA1["joints"], "uncertainty": option}
    r = client.post("/v1/tool-libraries:predict", json=body)
    assert r.status_code == 200, r.text
    assert [x.get("uncertainty") for x in r.json()["results"]] == [x["uncertainty"] for x in ok] + [None, None]
    assert_problem(client.post("/v1/tool-libraries:predict", files={"library": (name, (LIBS / name).read_bytes())},
                               data={**FORM, "uncertainty": json.dumps({"draws": 1})}), 422, "uncertainty.draws")

"""A seeded slice of the hostile run: every operation, uploaded files included, in process.

``benchmarks/bench_hostile.py`` sends ~2 000 such cases to a real 2-worker uvicorn; this slice
keeps two of each operation in the suite (same generator, ``tests/service/hostile_cases.py``),
plus the cases the issue named: each must be a 4xx problem naming the field or line — never a
500, never a wrong 2xx.
"""

from __future__ import annotations

import json

import pytest

from rcsa.reference import ra1
from tests.service.hostile_cases import DATA, Case, cases, judge, operations

from .conftest import WRITE, TestClient, assert_problem


@pytest.fixture(scope="module")
def hostile_client(tmp_path_factory):
    from service.main import create_app

    from .conftest import settings_for

    app = create_app(settings_for(tmp_path_factory.mktemp("hostile") / "store"))
    with TestClient(app, raise_server_exceptions=False) as client:
        yield client


def _answer(client, case: Case):
    r = client.post(case.path, **case.request_kwargs())
    return r, judge(case, r.status_code, r.headers.get("content-type", ""), r.content)


def test_the_generator_covers_every_operation_and_each_expectation():
    slice_ = cases(7, 2, write_headers=WRITE)
    assert {c.operation for c in slice_} == set(operations())
    assert len(operations()) >= 29
    assert {c.expect for c in cases(7, 8)} == {"4xx", "item", "any"}
    assert [c.label for c in cases(7, 2)] == [c.label for c in slice_]  # seeded: the same cases


def test_a_seeded_slice_gets_no_500_and_no_wrong_2xx(hostile_client):
    wrong = []
    for case in cases(7, 2, write_headers=WRITE):
        r, verdict = _answer(hostile_client, case)
        if verdict != "ok":
            wrong.append((case.operation, case.label, r.status_code, verdict, r.text[:200]))
    assert wrong == []


def _fusion_text() -> str:
    return (DATA / "tool-libraries" / "fusion-synthetic" / "synthetic_library.json").read_text()


@pytest.mark.parametrize(("label", "text", "field"), [
    ("deep", '{"a":' * 5000 + "1" + "}" * 5000, ""),
    ("400 digits", None, "data[0].geometry.DC"),
    ("1e308", None, "data[0].geometry.DC"),
])
def test_a_fusion_library_file_under_the_number_and_nesting_policy(hostile_client, label, text, field):
    if text is None:
        value = "1" + "0" * 400 if label == "400 digits" else "1e308"
        text = _fusion_text().replace('"DC": 10', f'"DC": {value}', 1)
    r = hostile_client.post("/v1/tool-libraries:entries", files={"library": ("lib.json", text.encode())})
    problem = assert_problem(r, 422)
    assert field in problem["detail"] and ("out of range" in problem["detail"] or "deeper than 32" in problem["detail"])


def test_a_freecad_holder_with_1e308_and_a_uff_units_factor_of_0_are_422(hostile_client):
    fctb = (DATA / "tool-libraries" / "freecad" / "5mm_Endmill.fctb").read_bytes()
    holder = (DATA / "tool-libraries" / "freecad" / "ER32_Standard.fcholder").read_text().replace("23.0", "1e308")
    form = {"spindle": json.dumps(ra1()["spindle"]), "frequency": json.dumps({"start_hz": 5, "stop_hz": 500,
                                                                             "step_hz": 5}),
            "options": json.dumps({"stickout_m": 0.03})}
    r = hostile_client.post("/v1/tool-libraries:predict", data=form,
                            files=[("library", ("a.fctb", fctb)), ("holder", ("h.fcholder", holder.encode()))])
    assert "profile[1][0]: number out of range" in assert_problem(r, 422)["detail"]
    uff = (DATA / "measurements" / "artifact_frfs_accelerance.uff").read_text()
    one = "1.0000000000000000D+00"
    uff = uff.replace(f"{one}   {one}   {one}", f"{one}   0.0000000000000000D+00   {one}", 1)
    r = hostile_client.post("/v1/measurements:read", files={"file": ("a.uff", uff.encode())},
                            data={"kind": "artifact_frfs", "points_m": "0,0.025", "roles": "h11=1:1,h21=2:1,h22=2:2",
                                  "artifact": json.dumps({"diameter_m": 0.0127, "stickout_m": 0.06,
                                                          "material": "carbide"})})
    assert "force factor is 0" in assert_problem(r, 422, "units")["detail"]


def test_a_million_row_csv_and_a_kilotonne_sensor_are_refused(hostile_client):
    rows = "f,re,im\n" + "".join(f"{1 + i},1e-7,-1e-8\n" for i in range(200_001))
    r = hostile_client.post("/v1/measurements:read", files={"file": ("a.csv", rows.encode())}, data={"units": "m/N"})
    assert "at most 200000 rows" in assert_problem(r, 422, "file")["detail"]
    csv = (DATA / "measurements" / "direct_frf_um_per_n.csv").read_bytes()
    r = hostile_client.post("/v1/measurements:read", files={"file": ("a.csv", csv)},
                            data={"units": "um/N", "sensor_mass_kg": "1e30"})
    assert_problem(r, 422, "sensor_mass_kg")


def test_a_22_m_holder_segment_a_tiny_step_and_a_broken_title_are_422(hostile_client):
    asm = ra1({"start_hz": 5.0, "stop_hz": 500.0, "step_hz": 5.0})
    long = json.loads(json.dumps(asm))
    long["holder"]["segments"][0]["length_m"] = 22.0
    assert_problem(hostile_client.post("/v1/tool-point-frf", json=long), 422)
    r = hostile_client.post("/v1/effects", json={"assembly": asm, "relative_step": 1e-300})
    assert_problem(r, 422)
    r = hostile_client.post("/v1/plots/frf", json={"assembly": asm, "title": "$\\frac{$"})
    assert "matplotlib" in assert_problem(r, 422, "title")["detail"]


def test_measured_frfs_in_json_are_bounded_in_rows_like_files(hostile_client):
    from rcsa.model.bounds import MAX_FREQUENCY_LINES

    n = MAX_FREQUENCY_LINES + 1
    doc = {"spindle_id": "s", "direction": "x", "plane": "spindle_nose", "kind": "direct_frf",
           "frequency_hz": [1.0 + i for i in range(n)], "h": {"real": [1e-7] * n, "imag": [-1e-8] * n}}
    r = hostile_client.post("/v1/measurements:read", files={"file": ("tip.json", json.dumps(doc).encode())})
    assert f"at most {MAX_FREQUENCY_LINES} frequency lines" in assert_problem(r, 422, "frequency_hz")["detail"]
    lobes = {"frf_x": {"frequency_hz": doc["frequency_hz"], "h": doc["h"]}, "teeth": 4,
             "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": 0.5, "milling": "down",
             "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 3}}
    assert_problem(hostile_client.post("/v1/stability-lobes", json=lobes), 422)

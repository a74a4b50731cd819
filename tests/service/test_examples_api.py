"""Every example of ``examples/`` through its REST endpoint; each answer fits its typed result model.

The CLI side (and the READMEs' commands) is ``tests/test_examples.py``. Validating the answers
with the response models of :mod:`service.schemas` keeps the OpenAPI honest: a generated
client reading these fields gets what the schema promised.
"""

from __future__ import annotations

import json

import pytest

from service import schemas
from tests.helpers import REPO

from .conftest import WRITE

EXAMPLES = REPO / "examples"


def _example(name: str):
    return json.loads((EXAMPLES / name).read_text())


@pytest.mark.parametrize(("name", "path", "model"), [
    ("ra1.json", "/v1/tool-point-frf", schemas.PredictionResult),
    ("batch.json", "/v1/tool-point-frf/batch", schemas.BatchResult),
    ("ra1-uncertainty.json", "/v1/tool-point-frf", schemas.PredictionResult),
    ("lobes-frf.json", "/v1/stability-lobes", schemas.LobesResult),
    ("lobes-robust.json", "/v1/stability-lobes", schemas.LobesResult),
    ("lobes-sdm.json", "/v1/stability-lobes", schemas.LobesResult),
    ("effects.json", "/v1/effects", schemas.EffectsResult),
    ("identification.json", "/v1/identifications", schemas.IdentificationResult),
    ("diagnosis.json", "/v1/diagnoses", schemas.DiagnosisResult),
])
def test_json_examples(client, name, path, model):
    r = client.post(path, json=_example(name))
    assert r.status_code == 200, r.text[:2000]
    result = model.model_validate(r.json())
    if name == "batch.json":
        assert result.summary.ok == 3 and [i.id for i in result.results][0] == "T1-ra1-74mm"
    if name == "diagnosis.json":
        assert result.verdict.effect == "holder_tool_joint" and result.verdict.status == "identified"
        assert len(result.effects[0].corrected_h) == 3
        # the extensions of issue 31, typed: the model forms weighed and the calibrated model
        assert result.model_form.base_model == "point" and result.model_form.proposed is None
        assert [c.candidate for c in result.model_form.candidates] == ["clamping_model"]
        assert len(result.calibrated.h) == 3 and result.calibrated.effects == ["holder_tool_joint"]
    if name == "identification.json":
        assert result.status == "identified"
        assert result.joints.holder_tool.stiffness_n_m == pytest.approx(5.7e6, rel=0.05)


def test_library_and_lobes_plot_examples(client):
    assembly = _example("ra1.json")
    body = {"library": _example("fusion-library.json"), "spindle": assembly["spindle"],
            "frequency": {"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 5.0}}
    r = client.post("/v1/tool-libraries:predict", json=body)
    assert r.status_code == 200, r.text[:2000]
    assert schemas.LibraryResult.model_validate(r.json()).summary == {"ok": 2, "skipped": 2, "error": 0}
    r = client.post("/v1/plots/lobes?format=svg", json=_example("lobes-assembly.json"))
    assert r.status_code == 200 and 'id="envelope"' in r.text


def test_measurement_examples_upload(client):
    r = client.post("/v1/measurements", json=_example("measurement.json"), headers=WRITE)
    assert r.status_code == 201, r.text
    assert schemas.MeasurementInfo.model_validate(r.json()).kind == "direct_frf"
    with (EXAMPLES / "measurement.csv").open("rb") as f:
        r = client.post("/v1/measurements", headers=WRITE, files={"file": ("measurement.csv", f, "text/csv")},
                        data={"spindle_id": "example-mc1", "direction": "x", "plane": "spindle_nose"})
    assert r.status_code == 201, r.text
    info = schemas.MeasurementInfo.model_validate(r.json())
    assert info.source.format == "csv" and info.source.original_units == "m/N"

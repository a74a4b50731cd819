"""Diagnoses, identifications and effect analyses are typed in the OpenAPI, with the library's bounds.

* the OpenAPI names a request and a response schema for each (generated clients get types,
  not ``Any``);
* the numbers the schemas take from :mod:`rcsa.app.bounds` equal the parsers' own;
* every numeric bound published for the analyses' own fields (options, tolerances, a tap
  test's extras, identification and effect settings) is probed as in
  ``test_schema_bounds.py``: a value just inside it is accepted by both the schema and the
  library's parser, one just outside it is refused by both;
* unknown fields are refused (422, naming the field), as in the other request models.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import pytest
from pydantic import ValidationError

from rcsa.app import bounds
from rcsa.errors import InputError
from rcsa.reference import ra1
from service import schemas

from .conftest import assert_problem
from .test_schema_bounds import _numeric_bounds, _probe

GRID = {"start_hz": 200.0, "stop_hz": 2000.0, "step_hz": 10.0}


def test_the_repeated_numbers_are_the_parsers_own():
    from rcsa.analysis.diagnosis.candidates import CANDIDATE_NAMES
    from rcsa.analysis.diagnosis.discrepancy import DEFAULT_TOLERANCES
    from rcsa.analysis.joint_identification.request import IDENTIFIABLE, MIN_LINES
    from rcsa.analysis.measured_tool_point import MAX_TAP_TESTS, TOOL_OVERRIDES

    assert bounds.DIAGNOSIS_EFFECTS == CANDIDATE_NAMES
    assert set(bounds.DIAGNOSIS_TOLERANCES) == set(DEFAULT_TOLERANCES)
    assert bounds.IDENTIFIABLE_PARAMETERS == IDENTIFIABLE
    assert bounds.IDENTIFICATION_MIN_LINES == MIN_LINES
    assert bounds.ANALYSIS_MAX_MEASUREMENTS == MAX_TAP_TESTS
    assert bounds.TOOL_OVERRIDES == TOOL_OVERRIDES


def test_openapi_types_every_analysis_request_and_response(client):
    spec = client.get("/openapi.json").json()
    components = spec["components"]["schemas"]
    for path, request, response in (("/v1/diagnoses", "DiagnosisRequest", "DiagnosisResult"),
                                    ("/v1/identifications", "IdentificationRequest", "IdentificationResult"),
                                    ("/v1/effects", None, "EffectsResult")):
        op = spec["paths"][path]["post"]
        body = op["requestBody"]["content"]["application/json"]["schema"]
        if request is None:  # effects: an assembly, or {assembly, parameters, relative_step, band_hz}
            refs = {b["$ref"].rsplit("/", 1)[1] for b in body["oneOf"]}
            assert refs == {"Assembly", "EffectAnalysisRequest"}, body
        else:
            assert body == {"$ref": f"#/components/schemas/{request}"}, body
            assert components[request]["additionalProperties"] is False
        assert op["responses"]["200"]["content"]["application/json"]["schema"] == {
            "$ref": f"#/components/schemas/{response}"}
        assert components[response].get("additionalProperties") is True  # results may grow
    tap = components["DiagnosisMeasurement"]["properties"]
    assert tap["h"] == {"$ref": "#/components/schemas/ComplexArrayIn", "description": tap["h"]["description"]}
    assert components["ToolOverrides"]["properties"]["stickout_m"]["maximum"] == bounds.MAX_LENGTH_M
    verdict = components["Verdict"]["properties"]["status"]
    assert verdict["enum"] == ["identified", "ambiguous", "none"]


# --------------------------------------------------------------------------- probing the bounds

def _measurement(stickout_m: float, n: int = 120) -> dict[str, Any]:
    f = [300.0 + 10.0 * i for i in range(n)]
    return {"tool": {"stickout_m": stickout_m}, "frequency_hz": f,
            "h": {"real": [1e-7] * n, "imag": [-1e-8] * n}, "coherence": [0.99] * n}


def _diagnosis() -> dict[str, Any]:
    return {"assembly": ra1(GRID), "measurements": [_measurement(0.06), _measurement(0.074)]}


def _identification() -> dict[str, Any]:
    return {"assembly": ra1(GRID), "measurements": [_measurement(0.074, 40)]}


def _accepts(check: Any, doc: dict[str, Any], errors: tuple[type[Exception], ...]) -> bool:
    try:
        check(copy.deepcopy(doc))
    except errors:
        return False
    return True


def _parse_diagnosis(doc: dict[str, Any]) -> Any:
    from rcsa.analysis.diagnosis.request import parse_request

    return parse_request(doc)


def _parse_identification(doc: dict[str, Any]) -> Any:
    from rcsa.analysis.joint_identification.request import parse_identification_request

    return parse_identification_request(doc)


def _parse_effects(doc: dict[str, Any]) -> Any:
    """The effect request's checks: the request itself, then the step (the band on a tiny run)."""
    from rcsa.analysis.effects.sensitivities import effects_report

    doc = {**doc, "assembly": ra1({"start_hz": 500.0, "stop_hz": 700.0, "step_hz": 100.0}),
           "parameters": ["holder_tool.stiffness_n_m"]}
    doc.setdefault("band_hz", [550.0, 650.0])
    return effects_report(doc)


def _set(doc: dict[str, Any], path: tuple[str | int, ...], value: float) -> dict[str, Any]:
    node: Any = doc
    for key in path[:-1]:
        if isinstance(node, dict):
            node = node.setdefault(key, {} if not isinstance(key, int) else [])
        else:
            node = node[key]
    node[path[-1]] = value
    return doc


def _document_bounds(model: type, prefix: tuple[str | int, ...], skip: tuple[str, ...] = ()
                     ) -> list[tuple[tuple[str | int, ...], str, float]]:
    schema = model.model_json_schema(ref_template="#/components/schemas/{model}")
    components = schema.pop("$defs", {})
    found = []
    for name, sub in schema.get("properties", {}).items():
        if name in skip:
            continue
        for path, keyword, bound in _numeric_bounds(sub, components, (name,)):
            found.append(((*prefix, *path), keyword, bound))
    return found


def _disagreements(model: type, parse: Any, base: dict[str, Any], cases: list[tuple[tuple[str | int, ...], str, float]],
                   adapt: Any = None) -> list[Any]:
    out = []
    for path, keyword, bound in cases:
        inside, outside = _probe(keyword, bound)
        for value, expected in ((inside, True), (outside, False)):
            doc = _set(copy.deepcopy(base), path, value)
            if adapt is not None:
                adapt(doc, path, value)
            got = (_accepts(model.model_validate, doc, (ValidationError,)), _accepts(parse, doc, (InputError,)))
            if got != (expected, expected):
                out.append((".".join(map(str, path)), keyword, bound, value, got))
    return out


def test_diagnosis_options_tolerances_and_tap_extras_bounds_agree_with_the_parser():
    cases = (_document_bounds(schemas.DiagnosisOptions, ("options",), skip=("held_out",))
             + _document_bounds(schemas.DiagnosisTolerances, ("tolerances",))
             + _document_bounds(schemas.DiagnosisMeasurement, ("measurements", 0),
                                skip=("tool", "frequency_hz", "h")))
    fields = {".".join(map(str, p)) for p, _, _ in cases}
    assert {"options.monte_carlo_draws", "options.max_lines", "options.seed", "tolerances.stickout_m",
            "tolerances.bearing_stiffness_log", "measurements.0.n_averages", "measurements.0.sensor_mass_kg",
            "measurements.0.coherence.0"} <= fields, fields

    def adapt(doc: dict[str, Any], path: tuple[str | int, ...], value: float) -> None:
        if path[-1] == "seed":
            doc["options"]["seed"] = int(value) if value >= 0 else -1
        if path[-2:] == ("coherence", 0):
            doc["measurements"][0]["coherence"] = [value] * len(doc["measurements"][0]["frequency_hz"])

    assert not _disagreements(schemas.DiagnosisRequest, _parse_diagnosis, _diagnosis(), cases, adapt)


def test_identification_bounds_agree_with_the_parser():
    cases = _document_bounds(schemas.IdentificationRequest, (), skip=("assembly", "measurements", "bounds"))
    assert [p for p, _, _ in cases] == [("max_residual_to_noise",)]
    assert not _disagreements(schemas.IdentificationRequest, _parse_identification, _identification(), cases)
    # a search range: both numbers > 0 (and the library's rules: low < high, containing the start)
    base = _identification()
    for pair, expected in (([5e-324, 1e12], True), ([0.0, 1e12], False), ([-1.0, 1e12], False)):
        doc = {**base, "bounds": {"holder_tool.stiffness_n_m": pair}}
        got = (_accepts(schemas.IdentificationRequest.model_validate, doc, (ValidationError,)),
               _accepts(_parse_identification, doc, (InputError,)))
        assert got == (expected, expected), (pair, got)
    doc = {**base, "bounds": {"tool.stickout_m": [1.0, 2.0]}}
    assert not _accepts(schemas.IdentificationRequest.model_validate, doc, (ValidationError,))
    assert not _accepts(_parse_identification, doc, (InputError,))


def test_effect_request_bounds_agree_with_the_library():
    cases = _document_bounds(schemas.EffectAnalysisRequest, (), skip=("assembly",))
    assert {p for p, _, _ in cases} == {("relative_step",), ("band_hz", 0)}

    def adapt(doc: dict[str, Any], path: tuple[str | int, ...], value: float) -> None:
        if path[0] == "band_hz":
            doc["band_hz"] = [value, 650.0]

    assert not _disagreements(schemas.EffectAnalysisRequest, _parse_effects, {"assembly": ra1(GRID)}, cases, adapt)


@pytest.mark.parametrize(("path", "doc", "field"), [
    ("/v1/diagnoses", lambda: {**_diagnosis(), "options": {"sample": 1}}, "options.sample"),
    ("/v1/diagnoses", lambda: {**_diagnosis(), "extra": 1}, "extra"),
    ("/v1/identifications", lambda: _set(_identification(), ("measurements", 0, "tool", "holder"), 1.0),
     "measurements[0].tool.holder"),
    ("/v1/effects", lambda: {"assembly": ra1(GRID), "band": [1.0, 2.0]}, "band"),
    ("/v1/effects", lambda: {**ra1(GRID), "parameters": []}, "parameters"),
    ("/v1/effects", lambda: {"assembly": ra1(GRID), "relative_step": 5}, "relative_step"),
    ("/v1/effects", lambda: _set(ra1(GRID), ("tool", "stickout_m"), -1.0), "tool.stickout_m"),
])
def test_refused_fields_are_named_exactly(client, path, doc, field):
    # the name exactly: not prefixed with the name of the union member the body was read as
    assert_problem(client.post(path, json=doc()), 422, field)


def test_a_fractional_count_the_library_accepts_is_accepted():
    doc = _diagnosis()
    doc["options"] = {"monte_carlo_draws": 200.0, "max_effects": 1.0, "max_lines": 250.5}
    schemas.DiagnosisRequest.model_validate(doc)
    assert _parse_diagnosis(doc).options.max_lines == 250
    assert math.isfinite(schemas.DiagnosisRequest.model_validate(doc).options.max_lines)

"""The published OpenAPI says exactly what the library accepts: one source of bounds.

Every numeric bound of the assembly in ``/openapi.json`` (``minimum``, ``maximum``,
``exclusiveMinimum``, ``exclusiveMaximum``) is probed with a value just inside it and one
just outside it. The REST schema (pydantic, ``service.schemas.Assembly``) and rcsa's own
parser (``rcsa.model.contract.parse_assembly``, what the CLI and the Python API use) must
agree on both: the inside value accepted, the outside value refused.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterator
from typing import Any

import pytest
from pydantic import ValidationError
from service.config import Settings
from service.main import create_app
from service.schemas import Assembly, LobesRequest

from rcsa.analysis.lobes.request import parse_lobes_request
from rcsa.analysis.lobes.robust import split_robust_request
from rcsa.errors import InputError
from rcsa.model.bounds import (
    MAX_CONFIDENCE,
    MAX_DIAMETER_M,
    MAX_LENGTH_M,
    MAX_UNCERTAINTY_DRAWS,
    MAX_UNCERTAINTY_SEED,
    MIN_CONFIDENCE,
    MIN_UNCERTAINTY_DRAWS,
)
from rcsa.model.contract import parse_assembly
from rcsa.model.uncertainty import parse_uncertainty
from rcsa.reference import ra1

# JSON-schema keyword -> (the bound is included, the direction "inside" lies in)
_BOUNDS = {"minimum": (True, +1.0), "exclusiveMinimum": (False, +1.0),
           "maximum": (True, -1.0), "exclusiveMaximum": (False, -1.0)}
Path = tuple[str | int, ...]


@pytest.fixture(scope="module")
def openapi(tmp_path_factory) -> dict[str, Any]:
    app = create_app(Settings(store=tmp_path_factory.mktemp("store"), seed_demo=False, access_log=False))
    return app.openapi()


def _numeric_bounds(schema: dict[str, Any], components: dict[str, Any], path: Path = ()
                    ) -> Iterator[tuple[Path, str, float]]:
    """(path, keyword, bound) of every numeric bound under ``schema``; lists at index 0,
    maps (``materials``) under the name ``steel``."""
    if "$ref" in schema:
        yield from _numeric_bounds(components[schema["$ref"].rsplit("/", 1)[1]], components, path)
        return
    for key in ("anyOf", "oneOf", "allOf"):
        for sub in schema.get(key, ()):
            yield from _numeric_bounds(sub, components, path)
    if schema.get("type") in ("number", "integer"):
        for keyword in _BOUNDS:
            if keyword in schema:
                yield path, keyword, float(schema[keyword])
    for name, sub in schema.get("properties", {}).items():
        yield from _numeric_bounds(sub, components, (*path, name))
    if isinstance(schema.get("items"), dict):
        yield from _numeric_bounds(schema["items"], components, (*path, 0))
    if isinstance(schema.get("additionalProperties"), dict):
        yield from _numeric_bounds(schema["additionalProperties"], components, (*path, "steel"))


def _probe(keyword: str, bound: float) -> tuple[float, float]:
    """A value just inside the bound and one just outside it (one ulp away)."""
    included, inward = _BOUNDS[keyword]
    inside = math.nextafter(bound, inward * math.inf)
    outside = math.nextafter(bound, -inward * math.inf) if included else bound
    return inside, outside


def _document(path: Path, value: float) -> dict[str, Any]:
    """RA-1 with ``value`` at ``path``, its neighbours moved so that only this bound is tested
    (the rules between fields — start <= stop, inner < outer diameter, bearings on the
    spindle, flute <= stickout <= overall length — are kept)."""
    doc = ra1({"start_hz": 100.0, "stop_hz": 100.0, "step_hz": 1.0})
    head, field = path[0], path[-1]
    if head == "frequency":
        if "values_hz" in path:
            doc["frequency"] = {"values_hz": [value]}
        elif field == "step_hz":
            doc["frequency"] = {"start_hz": 100.0, "stop_hz": 100.0, "step_hz": value}
        else:
            doc["frequency"] = {"start_hz": value, "stop_hz": value, "step_hz": 1.0}
    elif head == "shear_coefficient":
        doc["shear_coefficient"] = value
    elif head == "materials":
        doc["materials"] = {"steel": {field: value}}
    elif head == "spindle" and field == "effective_length_m":
        doc["spindle"] = {"measurement_id": "m-0123456789ab", "effective_length_m": value}
    elif head in ("spindle", "holder") and path[1] == "segments":
        # a segment of its own at the end: solid, and as thick as allowed
        segment = {"length_m": 0.05, "outer_diameter_m": MAX_DIAMETER_M, "inner_diameter_m": 0.0, "material": "steel"}
        segment[field] = value
        doc[head]["segments"].append(segment)
    elif head == "spindle" and path[1] == "bearings":
        doc["spindle"]["segments"].append({"length_m": MAX_LENGTH_M, "outer_diameter_m": 0.05, "material": "steel"})
        doc["spindle"]["bearings"][0][field] = value
    elif head == "joints" and field in _CLAMPING_PROBES:
        doc["joints"][path[1]] = {**_CLAMPING_PROBES[field], field: value}
    elif head == "joints":
        doc["joints"][path[1]][field] = value
    elif head == "tool" and path[1] == "neck_segments":
        doc["tool"].pop("shoulder_length_m", None)
        doc["tool"].pop("shoulder_diameter_m", None)
        doc["tool"]["neck_segments"] = [{"length_m": 0.001, "diameter_m": 0.01, field: value}]
    elif head == "tool":
        _tool(doc["tool"], field, value)
    else:
        raise AssertionError(f"no document for {path}")
    return doc


#: The holder–tool clamping (contract v1.2) a clamping field is probed on.
_CONTACT = {"model": "contact", "interface_stiffness_n_m3": 1e14}
_CLAMPING_PROBES = {"interface_stiffness_n_m3": {"model": "contact"}, "interface_tangential_ratio": _CONTACT,
                    "interface_loss_factor": _CONTACT, "front_gap_length_m": _CONTACT,
                    "contact_length_m": _CONTACT, "interface_stiffness_scale": _CONTACT, "contact_arc_deg": _CONTACT,
                    "screw_diameter_m": _CONTACT,
                    "contact_pressure_pa": {"model": "contact", "surface_roughness_m": 1e-6},
                    "surface_roughness_m": {"model": "contact", "contact_pressure_pa": 5e7}}
#: Bounds the library tightens by a geometric rule no schema can state: a front gap must leave some
#: of the insertion in contact (the largest one accepted depends on the tool and holder).
_GEOMETRIC = {(("joints", "holder_tool", "front_gap_length_m"), "maximum")}


def _tool(tool: dict[str, Any], field: str, value: float) -> None:
    tool.pop("shoulder_length_m", None)
    tool.pop("shoulder_diameter_m", None)
    flute, stickout, overall = tool["flute_length_m"], tool["stickout_m"], tool["overall_length_m"]
    if field == "overall_length_m":
        tool.update(overall_length_m=value, stickout_m=min(stickout, value), flute_length_m=min(flute, value))
    elif field == "stickout_m":
        tool.update(stickout_m=value, overall_length_m=max(overall, value), flute_length_m=min(flute, value))
    elif field == "flute_length_m":
        tool.update(flute_length_m=value, stickout_m=max(stickout, value), overall_length_m=max(overall, value))
    elif field == "shoulder_length_m":
        tool.update(shoulder_length_m=value, shoulder_diameter_m=tool["diameter_m"], flute_length_m=min(flute, value),
                    stickout_m=max(stickout, value), overall_length_m=max(overall, value))
    elif field == "shoulder_diameter_m":
        tool.update(shoulder_diameter_m=value, shoulder_length_m=stickout)
    else:
        tool[field] = value


def _schema_accepts(model: Any, doc: dict[str, Any]) -> bool:
    try:
        model.model_validate(doc)
    except ValidationError:
        return False
    return True


def _rcsa_accepts(parse: Any, doc: dict[str, Any]) -> bool:
    try:
        parse(copy.deepcopy(doc))
    except InputError:
        return False
    return True


def _assembly_bounds(openapi: dict[str, Any]) -> list[tuple[Path, str, float]]:
    components = openapi["components"]["schemas"]
    return list(_numeric_bounds(components["Assembly"], components))


def test_the_walk_finds_every_bound_of_the_assembly(openapi):
    bounds = _assembly_bounds(openapi)
    fields = {p for p, _, _ in bounds}
    assert len(bounds) >= 60, bounds  # the walk really reached the nested models
    for expected in [("materials", "steel", "youngs_modulus_pa"), ("frequency", "start_hz"),
                     ("spindle", "segments", 0, "length_m"), ("spindle", "bearings", 0, "position_m"),
                     ("spindle", "effective_length_m"), ("holder", "segments", 0, "inner_diameter_m"),
                     ("tool", "stickout_m"), ("joints", "holder_tool", "stiffness_n_m"), ("shear_coefficient",)]:
        assert expected in fields, expected


def test_schema_and_library_agree_on_every_assembly_bound(openapi):
    disagreements = []
    for path, keyword, bound in _assembly_bounds(openapi):
        if (path, keyword) in _GEOMETRIC:
            continue
        inside, outside = _probe(keyword, bound)
        for value, expected in ((inside, True), (outside, False)):
            doc = _document(path, value)
            got = (_schema_accepts(Assembly, doc), _rcsa_accepts(parse_assembly, doc))
            if got != (expected, expected):
                disagreements.append((".".join(map(str, path)), keyword, bound, value, got))
    assert not disagreements, "\n".join(map(str, disagreements))


def test_a_modulus_the_library_refuses_is_refused_by_the_schema_too():
    doc = ra1({"start_hz": 100.0, "stop_hz": 200.0, "step_hz": 10.0})
    doc["materials"] = {"steel": {"youngs_modulus_pa": 5e14}}
    assert not _schema_accepts(Assembly, doc)
    with pytest.raises(InputError) as info:
        parse_assembly(doc)
    assert info.value.field == "materials.steel.youngs_modulus_pa"


_SDM_OPTIONS = ("steps_per_period", "modes_per_direction")
_INTEGERS = ("teeth", "count", *_SDM_OPTIONS)


def _lobes_document(path: Path, value: float) -> dict[str, Any]:
    doc = {"frf_x": {"frequency_hz": [100.0, 200.0], "h": {"real": [1e-7, -1e-7], "imag": [-1e-8, -2e-7]}},
           "teeth": 4, "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
           "milling": "down", "spindle_speed_rpm": {"start": 2000.0, "stop": 30000.0, "count": 3}}
    node = doc
    for key in path[:-1]:
        node = node[key]
    field = path[-1]
    if field not in _SDM_OPTIONS:  # the zero-order bounds (the semi-discretization allows fewer speeds)
        doc["method"] = "zoa"
    if path[0] == "spindle_speed_rpm" and field in ("start", "stop"):
        # start < stop around the probed value
        node.update(start=value, stop=math.nextafter(value, math.inf)) if field == "start" else \
            node.update(start=math.nextafter(value, 0.0), stop=value)
        return doc
    node[field] = int(value) if field in _INTEGERS else value
    if field in _SDM_OPTIONS:  # options of the semi-discretization method only
        doc["method"] = "semi_discretization"
    return doc


def test_schema_and_library_agree_on_the_stability_lobes_bounds(openapi):
    components = openapi["components"]["schemas"]
    schema = {"properties": {k: v for k, v in components["LobesRequest"]["properties"].items()
                             if k not in ("assembly", "frf_x", "frf_y", "uncertainty", "robust", "modal_x",
                                          "modal_y")}}  # the tables: test_modal_table_bounds_agree
    # a speed list's items: tests/analysis/lobes/test_request.py
    bounds = [b for b in _numeric_bounds(schema, components) if not any(isinstance(k, int) for k in b[0])]
    assert {p[0] for p, _, _ in bounds} >= {"teeth", "tangential_coefficient_n_m2", "radial_ratio",
                                            "radial_immersion", "spindle_speed_rpm"}
    disagreements = []
    for path, keyword, bound in bounds:
        inside, outside = _probe(keyword, bound)
        if path[-1] in _INTEGERS:  # integers: one step, not one ulp
            step = 1 if keyword.endswith("inimum") else -1
            inside, outside = bound + (step if keyword.startswith("exclusive") else 0), bound - step
        for value, expected in ((inside, True), (outside, False)):
            doc = _lobes_document(path, value)
            got = (_schema_accepts(LobesRequest, doc), _rcsa_accepts(parse_lobes_request, doc))
            if got != (expected, expected):
                disagreements.append((".".join(map(str, path)), keyword, bound, value, got))
    assert not disagreements, "\n".join(map(str, disagreements))


@pytest.mark.parametrize(("option", "value", "accepted"), [
    ("draws", MIN_UNCERTAINTY_DRAWS, True), ("draws", MIN_UNCERTAINTY_DRAWS - 1, False),
    ("draws", MAX_UNCERTAINTY_DRAWS, True), ("draws", MAX_UNCERTAINTY_DRAWS + 1, False),
    ("seed", 0, True), ("seed", -1, False), ("seed", MAX_UNCERTAINTY_SEED + 1, False),
    ("confidence", MIN_CONFIDENCE, True), ("confidence", math.nextafter(MIN_CONFIDENCE, 0.0), False),
    ("confidence", MAX_CONFIDENCE, True), ("confidence", math.nextafter(MAX_CONFIDENCE, 1.0), False),
])
def test_schema_and_library_agree_on_the_uncertainty_bounds(option, value, accepted):
    doc = {"assembly": ra1({"start_hz": 100.0, "stop_hz": 200.0, "step_hz": 10.0}), "teeth": 4,
           "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": 0.5, "milling": "down",
           "spindle_speed_rpm": {"start": 2000.0, "stop": 30000.0, "count": 3}, "uncertainty": {"draws": 2}}
    if option == "confidence":
        doc["robust"] = {"confidence": value}
    else:
        doc["uncertainty"][option] = value

    def library(d):
        _, robust = split_robust_request(d)
        parse_uncertainty(robust.uncertainty, lines=11)

    assert (_schema_accepts(LobesRequest, doc), _rcsa_accepts(library, doc)) == (accepted, accepted)


def _openapi_bound(openapi: dict[str, Any], model: str, field: str, keyword: str) -> float:
    schema = openapi["components"]["schemas"][model]["properties"][field]
    for option in [schema, *schema.get("anyOf", ())]:
        if keyword in option:
            return float(option[keyword])
    raise AssertionError(f"{model}.{field} states no {keyword}")


def test_the_effects_step_and_the_sensor_mass_are_bounded_alike_in_schema_and_library(openapi, monkeypatch):
    from service.schemas import DiagnosisRequest, EffectAnalysisRequest

    from rcsa.analysis.diagnosis.request import parse_request
    from rcsa.analysis.effects import sensitivities as sensitivity
    from rcsa.measured.importers.sensor import remove_sensor_mass
    from rcsa.model.bounds import MAX_RELATIVE_STEP, MAX_SENSOR_MASS_KG, MIN_RELATIVE_STEP

    assert _openapi_bound(openapi, "EffectAnalysisRequest", "relative_step", "minimum") == MIN_RELATIVE_STEP
    assert _openapi_bound(openapi, "EffectAnalysisRequest", "relative_step", "maximum") == MAX_RELATIVE_STEP
    assert _openapi_bound(openapi, "DiagnosisMeasurement", "sensor_mass_kg", "maximum") == MAX_SENSOR_MASS_KG
    monkeypatch.setattr(sensitivity, "effect_analysis", lambda *a, **k: "ran")  # parse only
    asm = ra1({"start_hz": 100.0, "stop_hz": 200.0, "step_hz": 10.0})
    for keyword, bound in (("minimum", MIN_RELATIVE_STEP), ("maximum", MAX_RELATIVE_STEP)):
        inside, outside = _probe(keyword, bound)
        for value, expected in ((inside, True), (outside, False)):
            doc = {"assembly": asm, "relative_step": value}
            assert _schema_accepts(EffectAnalysisRequest, doc) is expected, (value, expected)
            assert _rcsa_accepts(sensitivity.effects_report, doc) is expected, (value, expected)
    tap = {"tool": {"stickout_m": 0.074}, "frequency_hz": [100.0 + i for i in range(20)],
           "h": {"real": [1e-7] * 20, "imag": [-1e-8] * 20}}
    inside, outside = _probe("maximum", MAX_SENSOR_MASS_KG)
    for value, expected in ((inside, True), (outside, False)):
        doc = {"assembly": {k: v for k, v in asm.items() if k != "frequency"},
               "measurements": [{**tap, "sensor_mass_kg": value}]}
        assert _schema_accepts(DiagnosisRequest, doc) is expected, (value, expected)
        assert _rcsa_accepts(parse_request, doc) is expected, (value, expected)
        try:  # the importers' correction of an uploaded file takes the same bound
            remove_sensor_mass([100.0], [1e-7 + 0j], value)
            imported = True
        except InputError:
            imported = False
        assert imported is expected, (value, expected)


def test_modal_table_bounds_agree():
    """A modal table's row count and fields: the schema refuses what the library refuses."""
    from service.schemas import LobesRequest as LobesSchema

    from rcsa.analysis.lobes.request import parse_lobes_request

    def doc(rows: list[dict[str, float]]) -> dict[str, Any]:
        return {"modal_x": rows, "teeth": 2, "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3,
                "radial_immersion": 0.1, "milling": "down",
                "spindle_speed_rpm": {"start": 2000.0, "stop": 30000.0, "count": 3}}

    row = {"frequency_hz": 800.0, "damping_ratio": 0.03, "stiffness_n_m": 2e7}
    for rows, expected in (([row] * 64, True), ([row] * 65, False), ([{**row, "damping_ratio": -0.1}], False),
                           ([{**row, "frequency_hz": 0.0}], False)):
        got = (_schema_accepts(LobesSchema, doc(rows)), _rcsa_accepts(parse_lobes_request, doc(rows)))
        assert got == (expected, expected), (len(rows), rows[0], got)

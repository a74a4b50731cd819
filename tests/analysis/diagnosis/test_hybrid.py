"""Diagnosis on measured spindles (hybrid): each kind and plane, what is not applicable, refusals, Σ, REST, CLI.

The "measurements" are the rcsa model itself (fast); the stored spindle is the analytical
RA-1 spindle's receptance at its plane (``spindle_nose``), or spindle + holder + tool core +
holder-tool joint at the holder face (``holder_tip``, directly or identified from a blank in
the holder). The benchmark's independent FE truth is in ``test_benchmark_reduced.py``.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from rcsa.analysis.diagnosis import analyse, diagnose
from rcsa.analysis.diagnosis.perturbed_model import Knobs, Solver, config_parts
from rcsa.analysis.diagnosis.report import build_response
from rcsa.errors import InputError
from rcsa.measured.hybrid import base_resolver
from rcsa.measured.store import Measurement, MeasurementMeta, MeasurementStore
from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.chain import Beam
from rcsa.physics.elimination import march
from rcsa.physics.materials import BUILTIN_MATERIALS
from rcsa.physics.sections import tube
from tests.analysis.diagnosis.conftest import model_request
from tests.analysis.diagnosis.truth import base_document

F_HZ = np.arange(60.0, 6000.0 + 1e-9, 8.0)
STICKOUTS_M = (0.055, 0.066, 0.077)
FAST = {"monte_carlo_draws": 50, "max_lines": 300}
NOISE = 0.003
BLANK_M, POINTS_M = 0.060, (0.0, 0.015)


def _spec():
    return parse_assembly({**base_document(), "frequency": {"values_hz": F_HZ.tolist()}})


def _noisy(x, rng, rel=NOISE):
    return x * (1 + rel * (rng.standard_normal(x.size) + 1j * rng.standard_normal(x.size)))


def _coherence(rel):
    return np.full(F_HZ.size, 1.0 / (1.0 + 10.0 * rel**2))  # what ``rel`` means for 5 averages


def nose_receptance() -> np.ndarray:
    """RA-1's spindle at its nose (what a spindle_nose measurement holds)."""
    spec = _spec()
    return inv2(Solver(F_HZ).nose_stiffness(config_parts(spec, spec.tool, Knobs())))


def holder_tip_chain():
    """Spindle, SH joint, holder with RA-1's tool core, HT joint: what a holder_tip measurement holds."""
    spec = _spec()
    model = build_model(spec)
    return model.to_holder_tip() + (model.holder_tool,)


def blank_frfs() -> dict[str, np.ndarray]:
    """h11, h21, h22 of a carbide blank with RA-1's shank in RA-1's holder (exact model)."""
    w = 2 * np.pi * F_HZ
    k_base = march(holder_tip_chain(), w)[0]
    sec = tube(0.0127, 0.0, BUILTIN_MATERIALS["carbide"])
    k_left = march((Beam(sec, BLANK_M - POINTS_M[1]),), w, k_base)[0]
    k_tip = march((Beam(sec, POINTS_M[1]),), w)[0]
    flip = np.diag([1.0, -1.0])
    g22 = inv2(k_left + flip @ k_tip @ flip)
    k_full = march((Beam(sec, POINTS_M[1]),), w, k_left)[0]
    g11 = inv2(k_full)
    from rcsa.physics.segments import dynamic_stiffness
    d = dynamic_stiffness(w, sec, POINTS_M[1])
    u2 = -inv2(k_left + d[:, :2, :2]) @ d[:, :2, 2:] @ g11[:, :, :1]
    return {"h11": g11[:, 0, 0], "h21": u2[:, 0, 0], "h22": g22[:, 0, 0]}


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """A store with a spindle of every kind: ids by (kind, plane)."""
    st = MeasurementStore(tmp_path_factory.mktemp("hybrid") / "store")
    rng = np.random.default_rng(11)
    s = nose_receptance()
    t = inv2(march(holder_tip_chain(), 2 * np.pi * F_HZ)[0])
    ids = {}
    for plane, r in (("spindle_nose", s), ("holder_tip", t)):
        frfs = {n: _noisy(r[:, i, j], rng) for n, (i, j) in zip("hlnp", ((0, 0), (0, 1), (1, 0), (1, 1)), strict=True)}
        ids["point_receptance", plane] = st.put(Measurement(
            F_HZ, frfs, MeasurementMeta("ra1", "x", plane, "point_receptance"),
            coherence={n: _coherence(NOISE) for n in frfs}))
    ids["direct_frf", "spindle_nose"] = st.put(Measurement(
        F_HZ, {"h": _noisy(s[:, 0, 0], rng)}, MeasurementMeta("ra1", "x", "spindle_nose", "direct_frf"),
        coherence={"h": _coherence(NOISE)}))
    blank = {k: _noisy(v, rng, 0.001) for k, v in blank_frfs().items()}
    ids["artifact_frfs", "holder_tip"] = st.put(Measurement(
        F_HZ, blank, MeasurementMeta("ra1", "x", "holder_tip", "artifact_frfs", points_m=POINTS_M,
                                     artifact={"diameter_m": 0.0127, "stickout_m": BLANK_M, "material": "carbide"}),
        coherence={k: _coherence(0.001) for k in blank}))
    return st, ids


def hybrid_request(ids, kind: str, plane: str, knobs: Knobs = Knobs(), seed: int = 0, **spindle) -> dict:  # noqa: B008
    """Model-generated tap tests of RA-1 (with ``knobs``) on the stored spindle of (kind, plane)."""
    req = model_request(knobs, seed=seed, stickouts_m=STICKOUTS_M, frequency_hz=F_HZ)
    a = req["assembly"]
    a["spindle"] = {"measurement_id": ids[kind, plane], **spindle}
    if plane == "holder_tip":  # holder, its clamping and the spindle-holder joint are inside the measurement
        del a["holder"]
        a["joints"] = {}
    req["options"] = dict(FAST)
    return req


CASES = [("point_receptance", "spindle_nose", {}), ("direct_frf", "spindle_nose", {"effective_length_m": 0.23}),
         ("point_receptance", "holder_tip", {}), ("artifact_frfs", "holder_tip", {})]


@pytest.mark.parametrize(("kind", "plane", "spindle"), CASES, ids=[f"{k}-{p}" for k, p, _ in CASES])
def test_a_withheld_sensor_mass_is_recovered_on_every_kind_and_plane(store, kind, plane, spindle):
    st, ids = store
    r = diagnose(hybrid_request(ids, kind, plane, Knobs(tip_mass_kg=0.006), **spindle), base_resolver(st))
    assert r["verdict"]["effect"] == "sensor_mass" and r["verdict"]["status"] == "identified", r["ranking"][:3]
    m = r["effects"][0]["parameters"]["tip_mass_kg"]
    assert abs(m["value"] - 0.006) < max(3 * m["sd"], 0.0025)  # direct_frf: its rotation estimate costs accuracy
    assert r["effects"][0]["confirmed_on_held_out"] is True
    na = {x["effect"]: x["reason"] for x in r["not_applicable"]}
    assert "bearings" in na and "measured" in na["bearings"]
    assert ("spindle_holder_joint" in na) == (plane == "holder_tip")
    ranked = {e["effect"] for e in r["ranking"]}
    assert "bearings" not in ranked and not (ranked & set(na))
    used = r["spindle_measurement"]
    assert used["kind"] == kind and used["plane"] == plane
    assert used["uncertainty_in_expected_scatter"]["noise"]["from_coherence"]
    assert len(r["effects"][0]["corrected_h"][0]["real"]) == F_HZ.size
    json.dumps(r)


def test_a_spindle_holder_joint_softer_than_modelled_is_found_at_the_nose(store):
    st, ids = store
    r = diagnose(hybrid_request(ids, "point_receptance", "spindle_nose",
                                Knobs(sh_translational_scale=0.2, sh_rotational_scale=0.2)), base_resolver(st))
    assert (r["verdict"]["effect"], r["verdict"]["status"]) == ("spindle_holder_joint", "identified")


def test_wrong_estimated_rotations_are_named_for_a_direct_frf_spindle(store):
    """The estimate's length is 4× the spindle's own (≈ 0.23 m): beyond the bounds it claims."""
    st, ids = store
    r = diagnose(hybrid_request(ids, "direct_frf", "spindle_nose", effective_length_m=0.92), base_resolver(st))
    assert (r["verdict"]["effect"], r["verdict"]["status"]) == ("spindle_rotational_receptance", "identified")
    length = r["effects"][0]["physical"]["effective_length_m"]
    assert 0.1 < length < 0.45


def test_a_gap_the_spindle_noise_explains_gives_none(store):
    """Taps of the true assembly; the stored blank FRFs carry 1 % noise, which the identification amplifies.

    With their coherence stored, the noise is drawn through the identification into Σ and the
    gap it causes is expected (none, not significant); the same data declared precise leave a
    significant gap that nothing in the model explains.
    """
    st, _ = store
    rng = np.random.default_rng(1)
    blank = {k: _noisy(v, rng, 0.01) for k, v in blank_frfs().items()}
    meta = MeasurementMeta("ra1", "x", "holder_tip", "artifact_frfs", points_m=POINTS_M,
                           artifact={"diameter_m": 0.0127, "stickout_m": BLANK_M, "material": "carbide"})
    honest = st.put(Measurement(F_HZ, blank, meta, coherence={k: _coherence(0.01) for k in blank}))
    silent = st.put(Measurement(F_HZ, blank, meta))
    out = {}
    for name, mid, tol in (("honest", honest, {}), ("claimed_precise", silent, {"spindle_noise_rel": 1e-4})):
        req = hybrid_request({("artifact_frfs", "holder_tip"): mid}, "artifact_frfs", "holder_tip", seed=2)
        req["tolerances"] = tol
        req["options"]["monte_carlo_draws"] = 200  # the identification's errors are heavy-tailed: 50 draws miss them
        out[name] = diagnose(req, base_resolver(st))
    r = out["honest"]
    assert r["verdict"]["effect"] == "none" and not r["gap"]["significant"]
    noise = r["spindle_measurement"]["uncertainty_in_expected_scatter"]["noise"]
    assert noise["median_relative_sd"]["h11"] == pytest.approx(0.01, rel=1e-6)
    assert noise["condition_number"]["max"] > 10  # the identification amplifies the noise
    precise = out["claimed_precise"]
    assert precise["gap"]["significant"] and precise["gap"]["chi2"] > 2 * r["gap"]["chi2"]
    assert precise["spindle_measurement"]["uncertainty_in_expected_scatter"]["noise"]["default_relative_sd"] == 1e-4


def _edit_spindle(req, **fields):
    doc = copy.deepcopy(req)
    doc["assembly"]["spindle"].update(fields)
    return doc


def test_meaningless_combinations_are_refused_naming_the_field(store):
    st, ids = store
    resolve = base_resolver(st)
    nose = hybrid_request(ids, "point_receptance", "spindle_nose")
    tip = hybrid_request(ids, "artifact_frfs", "holder_tip")
    cases = [
        ({**tip, "options": {**FAST, "effects": ["spindle_holder_joint", "sensor_mass"]}}, "options.effects",
         "spindle-holder joint is inside"),
        ({**nose, "options": {**FAST, "effects": ["bearings"]}}, "options.effects", "bearings are inside"),
        (_edit_spindle(nose, measurement_id="m-missing"), "assembly.spindle.measurement_id", "no stored"),
        ({**tip, "assembly": {**tip["assembly"], "holder": base_document()["holder"]}}, "assembly.holder",
         "left out"),
    ]
    wide = copy.deepcopy(nose)
    m = wide["measurements"][1]
    m["frequency_hz"] = (np.asarray(m["frequency_hz"]) + 30.0).tolist()  # 90-6030 Hz: beyond the spindle's band
    cases.append((wide, "measurements[1].frequency_hz", "outside"))
    fat = copy.deepcopy(tip)
    fat["measurements"][0]["tool"]["shank_diameter_m"] = 0.016
    cases.append((fat, "measurements[0].tool.shank_diameter_m", "must match the shank"))
    for req, field, words in cases:
        with pytest.raises(InputError) as err:
            diagnose(req, resolve)
        assert err.value.field == field, str(err.value)
        assert words in err.value.rule, err.value.rule
    with pytest.raises(InputError) as err:  # the analysis layer never opens a store by itself
        diagnose(nose)
    assert err.value.field == "assembly.spindle"


def test_holder_tip_candidates_act_on_the_tool_only(store):
    """At holder_tip nothing of the holder is modelled: the chain is the tool on the measured receptance."""
    st, ids = store
    a = analyse(hybrid_request(ids, "point_receptance", "holder_tip"), base_resolver(st))
    parts = a.problem.builder.parts(a.problem.tools[0], Knobs(insertion_offset_m=0.004))
    assert parts.spindle == () and parts.middle == ()
    base = a.problem.builder.parts(a.problem.tools[0], Knobs())
    free = sum(getattr(i, "length_m", 0.0) for i in parts.tool) - sum(getattr(i, "length_m", 0.0) for i in base.tool)
    assert free == pytest.approx(0.004)
    r = build_response(a)
    assert r["verdict"]["effect"] == "none"


# ------------------------------------------------------------------------- REST and CLI
def test_rest_diagnosis_on_a_stored_spindle(tmp_path):
    from service.main import create_app

    from tests.service.conftest import WRITE, TestClient, assert_problem, settings_for
    s = nose_receptance()
    rng = np.random.default_rng(3)
    doc = {"spindle_id": "ra1", "direction": "x", "plane": "spindle_nose", "kind": "point_receptance",
           "frequency_hz": F_HZ.tolist()}
    for n, (i, j) in zip("hlnp", ((0, 0), (0, 1), (1, 0), (1, 1)), strict=True):
        v = _noisy(s[:, i, j], rng)
        doc[n] = {"real": v.real.tolist(), "imag": v.imag.tolist()}
    with TestClient(create_app(settings_for(tmp_path / "store"))) as client:
        mid = client.post("/v1/measurements", json=doc, headers=WRITE).json()["id"]
        req = hybrid_request({("point_receptance", "spindle_nose"): mid}, "point_receptance", "spindle_nose",
                             Knobs(tip_mass_kg=0.006))
        r = client.post("/v1/diagnoses", json=req)
        assert r.status_code == 200, r.text
        body = r.json()
        assert body["verdict"]["effect"] == "sensor_mass"
        assert body["spindle_measurement"]["id"] == mid
        assert body["spindle_measurement"]["uncertainty_in_expected_scatter"]["noise"]["default_relative_sd"] == 0.005
        bad = {**req, "options": {**FAST, "effects": ["bearings"]}}
        assert_problem(client.post("/v1/diagnoses", json=bad), 422, "options.effects")


def test_cli_diagnosis_on_a_stored_spindle(store, tmp_path):
    import typer

    from rcsa.cli.diagnose_cmd import register
    st, ids = store
    app = typer.Typer()
    register(app)

    @app.command()
    def _noop() -> None:  # keeps typer from collapsing into a single-command app
        pass

    req = tmp_path / "req.json"
    req.write_text(json.dumps(hybrid_request(ids, "direct_frf", "spindle_nose", Knobs(tip_mass_kg=0.006),
                                             effective_length_m=0.23)))
    out = tmp_path / "out.json"
    result = CliRunner().invoke(app, ["diagnose", str(req), "-o", str(out), "--store", str(st.path)])
    assert result.exit_code == 0, result.output
    body = json.loads(out.read_text())
    assert body["verdict"]["effect"] == "sensor_mass" and body["spindle_measurement"]["kind"] == "direct_frf"
    result = CliRunner().invoke(app, ["diagnose", str(req), "--store", str(tmp_path / "empty")])
    assert result.exit_code == 1 and "measurement_id" in result.output

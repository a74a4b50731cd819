"""The diagnosis as users call it: contract shape, validation errors, CLI."""

from __future__ import annotations

import copy
import json
import re

import numpy as np
import pytest
from typer.testing import CliRunner

from rcsa.analysis.diagnosis import analyse, diagnose, diagnosis_figure
from rcsa.analysis.diagnosis.candidates import CANDIDATE_NAMES
from rcsa.analysis.diagnosis.report import build_response
from rcsa.errors import InputError


@pytest.fixture(scope="module")
def mass_analysis(mass_request):
    return analyse(mass_request)


@pytest.fixture(scope="module")
def mass_response(mass_analysis):
    return build_response(mass_analysis)


def test_response_has_the_contract_shape(mass_response, mass_request):
    r = mass_response
    assert set(r) >= {"gap", "verdict", "effects"}
    assert set(r["gap"]) >= {"bands", "modes"}
    assert set(r["verdict"]) >= {"effect", "status", "ambiguous_with"}
    assert r["verdict"]["status"] in ("identified", "ambiguous", "none")
    assert r["effects"] and r["gap"]["bands"]  # the checks below are not vacuous (a 5 g tip mass is there)
    for e in r["effects"]:
        assert set(e) >= {"effect", "log_bayes_factor", "parameters", "gap_before_db", "gap_after_db",
                          "held_out_gap_before_db", "held_out_gap_after_db", "corrected_h"}
        assert e["effect"] in CANDIDATE_NAMES
        assert len(e["corrected_h"]) == len(mass_request["measurements"])
        for h, m in zip(e["corrected_h"], mass_request["measurements"], strict=True):
            assert len(h["real"]) == len(h["imag"]) == len(m["frequency_hz"])
    assert {m["measurement"] for m in r["gap"]["modes"]} == {0, 1, 2}
    assert all(set(b) >= {"start_hz", "stop_hz", "rms_db", "z"} for b in r["gap"]["bands"])
    assert r["not_observable_at_standstill"] and "standstill" in r["not_observable_sentence"]
    json.dumps(r)  # JSON-ready (no numpy scalars)


def test_a_tip_mass_is_identified_with_its_mass(mass_response):
    r = mass_response
    assert r["verdict"] == {**r["verdict"], "effect": "sensor_mass", "status": "identified", "ambiguous_with": []}
    e = r["effects"][0]
    m = e["parameters"]["tip_mass_kg"]
    assert abs(m["value"] - 0.005) < max(3 * m["sd"], 3e-4)
    assert e["gap_after_db"] < 0.5 * e["gap_before_db"]
    assert e["confirmed_on_held_out"] is True  # three stickouts: leave-one-out
    assert r["held_out"]["method"] == "leave_one_out"
    assert r["gap"]["significant"]


def test_corrected_h_is_the_base_model_plus_the_effect(mass_analysis, mass_response):
    from rcsa.analysis.diagnosis.perturbed_model import Knobs, Solver, config_parts
    a = mass_analysis
    m0 = a.request.measurements[0]
    prm = mass_response["effects"][0]["parameters"]
    knobs = Knobs(tip_mass_kg=prm["tip_mass_kg"]["value"], tip_mass_distance_m=prm["distance_from_tip_m"]["value"])
    h = Solver(m0.frequency_hz).tip_h(config_parts(a.problem.spec, m0.tool, knobs))
    got = mass_response["effects"][0]["corrected_h"][0]
    np.testing.assert_allclose(np.asarray(got["real"]) + 1j * np.asarray(got["imag"]), h, rtol=1e-9)


def test_noise_only_model_data_give_none():
    from tests.analysis.diagnosis.conftest import model_request
    r = diagnose(model_request(seed=4))
    assert r["verdict"]["status"] == "none" and r["verdict"]["effect"] == "none"
    assert r["effects"] == []
    assert not r["gap"]["significant"]


def test_figure_draws_without_pyplot(mass_analysis, mass_response):
    from rcsa.analysis.figures import save_figure
    fig = diagnosis_figure(mass_analysis, mass_response)
    assert save_figure(fig, "png")[:8] == b"\x89PNG\r\n\x1a\n"


def test_figure_is_readable(mass_analysis, mass_response):
    # the measured curve lies under the model's, wider, so it shows where they agree; the
    # frequency axes carry plain, distinct, non-overlapping labels; the gap map has its key
    from rcsa.analysis.diagnosis.report import GAP_MAP_KEY

    fig = diagnosis_figure(mass_analysis, mass_response)
    renderer = fig.canvas.get_renderer()
    frf_axes = [ax for ax in fig.axes if ax.get_xscale() == "log"]
    assert len(frf_axes) == len(mass_analysis.request.measurements)
    for ax in frf_axes:
        lines = {line.get_label(): line for line in ax.get_lines()}
        measured, model = lines["measured"], lines["base model"]
        assert measured.get_zorder() < model.get_zorder() and measured.get_linewidth() > 2 * model.get_linewidth()
        labels = [t for t in ax.get_xticklabels() if t.get_text()]
        assert len(labels) >= 2 and all(re.fullmatch(r"\d+", t.get_text()) for t in labels), \
            [t.get_text() for t in labels]
        boxes = [t.get_window_extent(renderer) for t in labels]
        assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])
        assert not [t for t in ax.get_xticklabels(minor=True) if t.get_text()]
    assert any(t.get_text() == GAP_MAP_KEY for ax in fig.axes for t in ax.texts)
    gap_maps = [ax for ax in fig.axes if ax.get_images()]
    assert gap_maps and all(t.get_text().startswith(("static", "peak", "anti", "band"))
                            for ax in gap_maps for t in ax.get_xticklabels())


# ------------------------------------------------------------------------- validation errors
def _edit(req, path, value):
    doc = copy.deepcopy(req)
    node = doc
    for key in path[:-1]:
        node = node[key]
    if value is _DELETE:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return doc


_DELETE = object()


@pytest.mark.parametrize(("path", "value", "field"), [
    (("measurements", 0, "tool", "stickout_mm"), 50.0, "measurements[0].tool.stickout_mm"),
    (("measurements", 1, "coherence"), [1.5] * 1488, "measurements[1].coherence"),
    (("measurements", 0, "h", "imag"), [0.0] * 10, "measurements[0].h.imag"),
    (("measurements", 0, "frequency_hz"), [100.0, 90.0] + [float(x) for x in range(200, 1686)],
     "measurements[0].frequency_hz"),
    (("measurements", 0, "coherence"), [0.1] * 1488, "measurements[0].coherence"),
    (("tolerances", ), {"tool_youngs_modulus": 0.1}, "tolerances.tool_youngs_modulus"),
    (("options", ), {"effects": ["gyroscopic_coupling"]}, "options.effects"),
    (("options", ), {"held_out": [0, 1, 2]}, "options.held_out"),
    (("assembly", "spindle"), {"measurement_id": "m1"}, "assembly.spindle"),
    (("measurements", ), [], "measurements"),
    (("extra", ), 1, "extra"),
    (("assembly", "tool", "stickout_m"), -1.0, "assembly.tool.stickout_m"),
])
def test_bad_requests_name_the_field(small_request, path, value, field):
    with pytest.raises(InputError) as err:
        diagnose(_edit(small_request, path, value))
    assert err.value.field == field, str(err.value)


def test_too_few_lines_is_refused(small_request):
    m = small_request["measurements"][0]
    for key in ("frequency_hz", "coherence"):
        m[key] = m[key][:60]
    m["h"] = {"real": m["h"]["real"][:60], "imag": m["h"]["imag"][:60]}
    with pytest.raises(InputError, match="at least 100 lines"):
        diagnose(small_request)


# ------------------------------------------------------------------------- CLI
@pytest.mark.slow
def test_cli_diagnose_writes_json_and_png(tmp_path, mass_request):
    import typer

    from rcsa.cli.diagnose_cmd import register
    app = typer.Typer()
    register(app)

    @app.command()
    def _noop() -> None:  # a second command keeps typer from collapsing into a single-command app
        pass

    req = tmp_path / "req.json"
    req.write_text(json.dumps(mass_request))
    out, png = tmp_path / "out.json", tmp_path / "gap.png"
    result = CliRunner().invoke(app, ["diagnose", str(req), "-o", str(out), "--plot", str(png)])
    assert result.exit_code == 0, result.output
    assert json.loads(out.read_text())["verdict"]["effect"] == "sensor_mass"
    assert png.read_bytes()[:4] == b"\x89PNG"
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"assembly": mass_request["assembly"], "measurements": []}))
    result = CliRunner().invoke(app, ["diagnose", str(bad)])
    assert result.exit_code == 1 and "measurements" in result.output


@pytest.mark.slow
def test_one_measurement_and_different_grids_work():
    from rcsa.analysis.diagnosis.perturbed_model import Knobs
    from tests.analysis.diagnosis.conftest import model_request
    one = model_request(Knobs(tip_mass_kg=0.006), stickouts_m=(0.066,))
    r = diagnose(one)
    assert r["held_out"]["method"] == "none"
    assert r["verdict"]["effect"] in ("sensor_mass", "none") or r["verdict"]["status"] == "ambiguous"
    if r["effects"]:
        assert r["effects"][0]["held_out_gap_before_db"] is None
    assert any("nothing can be held out" in n for n in r["notes"])
    two = model_request(Knobs(tip_mass_kg=0.006), stickouts_m=(0.055, 0.077))
    coarse = model_request(Knobs(tip_mass_kg=0.006), stickouts_m=(0.066,), frequency_hz=np.arange(60.0, 6000.0, 5.0),
                           seed=2)
    two["measurements"].append(coarse["measurements"][0])
    r = diagnose({**two, "options": {"effects": ["sensor_mass", "fluted_section", "holder_tool_joint"]}})
    assert r["held_out"]["method"] == "leave_one_out"
    assert {e["effect"] for e in r["ranking"]} == {"sensor_mass", "fluted_section", "holder_tool_joint"}
    assert r["verdict"]["effect"] == "sensor_mass"
    assert len(r["effects"][0]["corrected_h"][2]["real"]) == len(coarse["measurements"][0]["frequency_hz"])

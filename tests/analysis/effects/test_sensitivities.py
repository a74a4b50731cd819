"""Effect analysis: parameter names, finite-difference convergence, symmetry, JSON, figure, CLI."""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from rcsa.analysis.effects.report import FEATURES
from rcsa.analysis.effects.sensitivities import effect_analysis, effects
from rcsa.analysis.figures import effects_figure, save_figure
from rcsa.cli import effects_cmd
from rcsa.errors import InputError
from rcsa.model.contract import parse_assembly
from rcsa.model.parameters import get_parameter, parameter_names, set_parameter
from rcsa.reference import ra1

RA1_NAMES = (
    "bearings[0].stiffness_n_m", "bearings[0].damping_ns_m",
    "bearings[1].stiffness_n_m", "bearings[1].damping_ns_m",
    "bearings[2].stiffness_n_m", "bearings[2].damping_ns_m",
    "bearings[3].stiffness_n_m", "bearings[3].damping_ns_m",
    "spindle_holder.stiffness_n_m", "spindle_holder.damping_ns_m",
    "spindle_holder.rotational_stiffness_nm_rad", "spindle_holder.rotational_damping_nms_rad",
    "holder_tool.stiffness_n_m", "holder_tool.damping_ns_m",
    "holder_tool.rotational_stiffness_nm_rad", "holder_tool.rotational_damping_nms_rad",
    "tool.stickout_m", "tool.fluted_diameter_ratio",
)
#: A small RA-1 band with the first spindle modes and the dominant tool mode.
BAND = {"start_hz": 500.0, "stop_hz": 1500.0, "step_hz": 1.0}


def small_doc():
    return ra1(BAND)


@pytest.fixture(scope="module")
def report():
    return effect_analysis(small_doc())


def test_parameter_names_of_ra1():
    assert parameter_names(parse_assembly(ra1())) == RA1_NAMES


def test_rigid_or_zero_parameters_are_left_out():
    doc = ra1()
    del doc["joints"]["holder_tool"]["rotational_stiffness_nm_rad"]
    doc["joints"]["holder_tool"]["rotational_damping_nms_rad"] = 0.0
    del doc["joints"]["spindle_holder"]
    names = parameter_names(parse_assembly(doc))
    assert not any(n.startswith("spindle_holder.") for n in names)
    assert "holder_tool.rotational_stiffness_nm_rad" not in names
    assert "holder_tool.rotational_damping_nms_rad" not in names
    assert "holder_tool.stiffness_n_m" in names


def test_get_and_set_parameter_round_trip():
    spec = parse_assembly(ra1())
    for name in RA1_NAMES:
        value = get_parameter(spec, name)
        changed = set_parameter(spec, name, 1.5 * value)
        assert get_parameter(changed, name) == pytest.approx(1.5 * value, rel=1e-15)
        assert get_parameter(spec, name) == value  # the original is untouched (frozen)
    moved = set_parameter(spec, "tool.stickout_m", 0.05)
    assert moved.tool.inserted_length_m == pytest.approx(0.175 - 0.05)


@pytest.mark.parametrize("name", ["bearings[9].stiffness_n_m", "bearings[x].stiffness_n_m",
                                  "holder_tool.mass_kg", "tool.diameter_m", "nonsense"])
def test_unknown_parameter_is_an_input_error(name):
    with pytest.raises(InputError, match="parameter"):
        get_parameter(parse_assembly(ra1()), name)


def test_modes_in_band_and_their_features(report):
    np.testing.assert_allclose(report.frequency_hz, [599.85, 921.69, 1115.51, 1383.61, 1444.68], atol=0.01)
    # docs/physics.md §1.5: tip residues 2.02, 0.032, 1.28, 13.6, 0.063; damped peaks 599 / 1103 / 1386 Hz
    np.testing.assert_allclose(report.modes.tip_residue_1_kg, [2.02, 0.032, 1.28, 13.6, 0.063], rtol=0.02)
    peaks = report.modes.peak_frequency_hz
    np.testing.assert_allclose(peaks[[0, 2, 3]], [599.0, 1103.0, 1386.0], atol=1.0)
    assert np.isnan(peaks[[1, 4]]).all()  # hidden at the tool point: no peak, no damping fit
    # docs/physics.md §1.5 peak heights on the 1 Hz grid; the refined maximum is at least as high
    np.testing.assert_allclose(report.modes.peak_magnitude_m_n[[0, 2, 3]], [4.273e-6, 8.27e-7, 5.837e-6],
                               rtol=2e-3)
    zeta = report.modes.damping_ratio[[0, 2, 3]]
    assert np.all((zeta > 0.005) & (zeta < 0.05))


def test_halving_the_step_changes_sensitivities_by_less_than_one_percent(report):
    half = effect_analysis(small_doc(), relative_step=report.relative_step / 2)
    for q in FEATURES:
        a, b = report.sensitivity[q], half.sensitivity[q]
        assert np.array_equal(np.isnan(a), np.isnan(b))
        ok = np.isfinite(a)
        # relative 1 %, with an absolute floor of 1e-4 for sensitivities that are ~0
        np.testing.assert_allclose(a[ok], b[ok], rtol=0.01, atol=1e-4, err_msg=q)


def test_stiffening_never_lowers_a_natural_frequency(report):
    """Rayleigh: adding stiffness raises every undamped natural frequency (S_f >= 0)."""
    stiffnesses = [n for n in report.parameters if n.endswith(("stiffness_n_m", "stiffness_nm_rad"))]
    assert len(stiffnesses) >= 4, report.parameters  # bearings and both joints
    for name in stiffnesses:
        assert np.all(report.column(name) > -1e-6), name


def test_damping_never_moves_an_undamped_frequency(report):
    dampings = [n for n in report.parameters if "damping" in n]
    assert dampings, report.parameters
    for name in dampings:
        assert np.all(report.column(name) == 0.0), name


def test_split_bearing_symmetry():
    """A bearing split into two identical co-located halves: equal sensitivities, each half the whole's.

    ``d ln q / d ln k₁`` with ``k₁ = k/2`` carries the factor k₁/k = 1/2 (chain rule).
    """
    doc = small_doc()
    whole = effect_analysis(doc, parameters=["bearings[0].stiffness_n_m", "bearings[0].damping_ns_m"])
    split = copy.deepcopy(doc)
    b0 = split["spindle"]["bearings"][0]
    half = {**b0, "stiffness_n_m": b0["stiffness_n_m"] / 2, "damping_ns_m": b0["damping_ns_m"] / 2}
    split["spindle"]["bearings"][0:1] = [half, dict(half)]
    names = [f"bearings[{i}].{f}" for i in (0, 1) for f in ("stiffness_n_m", "damping_ns_m")]
    parts = effect_analysis(split, parameters=names)
    np.testing.assert_allclose(parts.frequency_hz, whole.frequency_hz, rtol=1e-10)
    for q in FEATURES:
        for f in ("stiffness_n_m", "damping_ns_m"):
            a = parts.column(f"bearings[0].{f}", q)
            b = parts.column(f"bearings[1].{f}", q)
            w = whole.column(f"bearings[0].{f}", q)
            ok = np.isfinite(w)
            # identical parameters: identical arithmetic up to rounding of the split chain
            np.testing.assert_allclose(a[ok], b[ok], rtol=1e-6, atol=1e-7, err_msg=f"{q} {f}")
            np.testing.assert_allclose(a[ok] + b[ok], w[ok], rtol=1e-3, atol=1e-5, err_msg=f"{q} {f}")


def test_controls_and_controlled_by(report):
    assert report.controls("holder_tool.stiffness_n_m") == pytest.approx(1383.61, abs=0.01)
    assert report.controls("spindle_holder.stiffness_n_m") == pytest.approx(599.85, abs=0.01)
    assert report.controlled_by(3) == "tool.stickout_m"
    assert report.controlled_by(3, among=["holder_tool.stiffness_n_m", "spindle_holder.stiffness_n_m"]) \
        == "holder_tool.stiffness_n_m"


def test_to_dict_is_strict_json_with_stable_names(report):
    doc = report.to_dict()
    text = json.dumps(doc, allow_nan=False)  # NaN became null
    assert [row["parameter"] for row in doc["parameters"]] == list(RA1_NAMES)
    assert set(doc) >= {"band_hz", "relative_step", "modes", "parameters", "features", "notes"}
    mode = doc["modes"][3]
    assert set(mode) >= {"frequency_hz", "tip_participation", "tip_residue_1_kg", "peak_frequency_hz",
                         "peak_magnitude_m_n", "damping_ratio", "controlled_by", "controlled_by_interface"}
    assert mode["controlled_by_interface"]["frequency_hz"] == "holder_tool.stiffness_n_m"
    row = doc["parameters"][RA1_NAMES.index("holder_tool.stiffness_n_m")]
    assert len(row["frequency_hz"]) == len(doc["modes"])
    assert row["controls_frequency_hz"] == pytest.approx(1383.61, abs=0.01)
    assert doc["modes"][1]["peak_magnitude_m_n"] is None and '"damping_ratio": null' in text


def test_effects_request_forms():
    subset = ["holder_tool.stiffness_n_m", "tool.stickout_m"]
    out = effects({"assembly": small_doc(), "parameters": subset, "relative_step": 0.002,
                   "band_hz": [1000.0, 1500.0]})
    assert [r["parameter"] for r in out["parameters"]] == subset
    assert out["relative_step"] == 0.002 and out["band_hz"] == [1000.0, 1500.0]
    assert [round(m["frequency_hz"], 1) for m in out["modes"]] == [1115.5, 1383.6, 1444.7]


@pytest.mark.parametrize("request_doc, field", [
    ({"assembly": {}, "extra": 1}, "extra"),
    ({"assembly": ra1(BAND), "relative_step": 0.5}, "relative_step"),
    ({"assembly": ra1(BAND), "relative_step": "big"}, "relative_step"),
    ({"assembly": ra1(BAND), "parameters": ["holder_tool.mass_kg"]}, "parameters"),
    ({"assembly": ra1(BAND), "parameters": "tool.stickout_m"}, "parameters"),
    ({"assembly": ra1(BAND), "band_hz": [2000.0, 1000.0]}, "band_hz"),
    ({"assembly": {**ra1(BAND), "tool": {**ra1()["tool"], "stickout_m": -1.0}}}, "assembly.tool.stickout_m"),
    ({**ra1(BAND), "spindle": {"measurement_id": "abc"}}, "spindle"),
    ([1, 2], ""),
], ids=["unknown field", "step too big", "step not a number", "unknown parameter", "parameters not a list",
        "band reversed", "bad assembly", "measured spindle", "not an object"])
def test_bad_requests(request_doc, field):
    with pytest.raises(InputError) as err:
        effects(request_doc)
    assert err.value.field == field


def test_zero_parameter_is_refused_by_name():
    doc = small_doc()
    doc["spindle"]["bearings"][0]["damping_ns_m"] = 0.0
    with pytest.raises(InputError, match="zero or rigid"):
        effects({"assembly": doc, "parameters": ["bearings[0].damping_ns_m"]})


def test_figure_is_a_png(report):
    png = save_figure(effects_figure(report), "png")
    assert png[:8] == b"\x89PNG\r\n\x1a\n"


def test_band_without_modes_gives_an_empty_report_and_no_figure():
    report = effect_analysis(ra1({"start_hz": 10.0, "stop_hz": 100.0, "step_hz": 1.0}))
    assert report.frequency_hz.size == 0 and "no natural frequency" in report.notes[0]
    assert report.to_dict()["modes"] == []
    assert report.controls("holder_tool.stiffness_n_m") is None
    with pytest.raises(InputError, match="no mode"):
        effects_figure(report)


def _app() -> typer.Typer:
    app = typer.Typer()
    effects_cmd.register(app)
    app.command("noop")(lambda: None)  # two commands: ``effects`` is a sub-command as in ``rcsa``
    return app


def test_cli_writes_json_and_plot(tmp_path):
    src = tmp_path / "a.json"
    src.write_text(json.dumps({"assembly": small_doc(), "parameters": ["holder_tool.stiffness_n_m"]}))
    out, png = tmp_path / "out.json", tmp_path / "fig.png"
    result = CliRunner().invoke(_app(), ["effects", str(src), "-o", str(out), "--plot", str(png)])
    assert result.exit_code == 0, result.stderr
    doc = json.loads(out.read_text())
    assert doc["parameters"][0]["controls_frequency_hz"] == pytest.approx(1383.61, abs=0.01)
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_cli_failure_is_one_line(tmp_path):
    src = tmp_path / "a.json"
    src.write_text(json.dumps({"assembly": small_doc(), "relative_step": 3}))
    result = CliRunner().invoke(_app(), ["effects", str(src)])
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: relative_step")


def test_sensitivities_are_finite_where_defined(report):
    for q in ("frequency_hz",):
        assert np.all(np.isfinite(report.sensitivity[q]))
    assert math.isfinite(report.column("holder_tool.damping_ns_m", "peak_magnitude_m_n")[3])

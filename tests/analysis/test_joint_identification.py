"""Joint identification on synthetic RA-1 measurements: accuracy, honesty, request checks, CLI.

RA-1 is computed with the seed paper's Table 2 joint values (``docs/physics.md`` §1.1 — they are
RA-1's values), 1 % relative complex noise is added (seeded), and the identification starts
3× off in both joints' k_t and c_t.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from rcsa.analysis.joint_identification.identify import identify
from rcsa.app.predictions import predict
from rcsa.cli import identify_cmd
from rcsa.errors import InputError
from rcsa.reference import ra1

TRUE = {"spindle_holder": {"stiffness_n_m": 3.05e7, "damping_ns_m": 365.0},
        "holder_tool": {"stiffness_n_m": 1.14e7, "damping_ns_m": 34.0}}
NOISE = 0.01
#: 2x what the manual states for these seeded cases (stiffnesses within 1e-4, dampings within
#: 4e-3; measured 4.4e-5 and 3.1e-3) — far inside the brief's acceptance of 5 % and 20 %
RTOL_STIFFNESS, RTOL_DAMPING = 2e-4, 8e-3


def measured(stickout_m: float = 0.074, band_hz=(50.0, 5000.0), seed: int = 0, noise: float = NOISE,
             doc: dict | None = None) -> dict:
    """A synthetic measurement: RA-1 (or ``doc``) with 1 % complex noise, 1 Hz lines."""
    doc = doc or ra1()
    doc = {**doc, "frequency": {"start_hz": band_hz[0], "stop_hz": band_hz[1], "step_hz": 1.0}}
    doc["tool"] = {**doc["tool"], "stickout_m": stickout_m}
    p = predict(doc)
    f, h = p.frequency_hz, p.tool_point.h
    rng = np.random.default_rng(seed)
    noisy = h * (1 + noise * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2))
    return {"tool": {"stickout_m": stickout_m}, "frequency_hz": f.tolist(),
            "h": {"real": noisy.real.tolist(), "imag": noisy.imag.tolist()}}


def start(sh: float, ht: float) -> dict:
    """RA-1 with both joints' k_t and c_t scaled (spindle–holder by ``sh``, holder–tool by ``ht``)."""
    doc = ra1()
    for joint, factor in (("spindle_holder", sh), ("holder_tool", ht)):
        doc["joints"][joint]["stiffness_n_m"] *= factor
        doc["joints"][joint]["damping_ns_m"] *= factor
    return doc


@pytest.fixture(scope="module")
def ra1_measurement():
    return measured(seed=11)


def assert_accurate(out: dict, joints=("spindle_holder", "holder_tool")) -> None:
    assert out["status"] == "identified", out.get("detail")
    for joint in joints:
        got = out["joints"][joint]
        for field, rtol in (("stiffness_n_m", RTOL_STIFFNESS), ("damping_ns_m", RTOL_DAMPING)):
            truth = TRUE[joint][field]
            assert got[field] == pytest.approx(truth, rel=rtol), f"{joint}.{field}"
            sigma = got["uncertainty"][field]
            # the standard uncertainty covers the noise: the error is within 5 σ
            assert 0 < sigma and abs(got[field] - truth) <= 5 * sigma, f"{joint}.{field}: σ {sigma:g}"
        # rotational values are held, as in the seed paper
        assert got["rotational_stiffness_nm_rad"] == 1.5e6 and got["rotational_damping_nms_rad"] == 40.0


def assert_fit_within_noise(out: dict) -> None:
    # complex-log residual per line vs the 1 % relative noise (2 % slack for the p fitted values)
    assert out["residual_rel"] == pytest.approx(NOISE, rel=0.2)
    assert out["residual_rel"] / out["noise_rel"] < 1.3
    # 1 % complex noise: RMS of 20 log10|1 + n| ≈ 8.686·0.01/√2 = 0.061 dB
    assert out["residual_db"] < 0.1


@pytest.mark.parametrize("sh, ht", [(3.0, 3.0), (1 / 3, 1 / 3), (3.0, 1 / 3), (1 / 3, 3.0)],
                         ids=["both 3x high", "both 3x low", "sh high ht low", "sh low ht high"])
def test_identifies_ra1_from_three_times_off(ra1_measurement, sh, ht):
    out = identify({"assembly": start(sh, ht), "measurements": [ra1_measurement]})
    assert_accurate(out)
    assert_fit_within_noise(out)
    used = {(m["controls"], round(m["frequency_hz"])) for m in out["modes_used"]}
    # the effect analysis picks the modes of tests/reference/test_erturk2007_effects.py
    assert ("holder_tool.stiffness_n_m", 1386) in used
    assert ("spindle_holder.stiffness_n_m", 599) in used
    assert out["start"]["holder_tool.stiffness_n_m"] == pytest.approx(1.14e7 * ht)
    assert {f["parameter"] for f in out["flags"]} == {"spindle_holder.rotational_stiffness_nm_rad",
                                                      "holder_tool.rotational_stiffness_nm_rad"}
    json.dumps(out, allow_nan=False)


def test_identified_model_reproduces_the_noise_free_frf(ra1_measurement):
    out = identify({"assembly": start(3.0, 3.0), "measurements": [ra1_measurement]})
    doc = ra1({"start_hz": 50.0, "stop_hz": 5000.0, "step_hz": 1.0})
    truth = predict(doc).tool_point.h
    for joint in TRUE:
        doc["joints"][joint] = {k: v for k, v in out["joints"][joint].items() if k != "uncertainty"}
    model = predict(doc).tool_point.h
    # far inside the 1 % noise everywhere in the band
    assert float(np.max(np.abs(model / truth - 1))) < 0.003


def test_two_stickouts():
    meas = [measured(0.074, seed=1), measured(0.060, seed=2)]
    out = identify({"assembly": start(3.0, 1 / 3), "measurements": meas})
    assert_accurate(out)
    assert_fit_within_noise(out)
    assert {m["measurement"] for m in out["modes_used"]} == {0, 1}
    assert len(out["windows_hz"]) == 2


def test_coherence_weights_are_accepted(ra1_measurement):
    h = np.asarray(ra1_measurement["h"]["real"]) + 1j * np.asarray(ra1_measurement["h"]["imag"])
    coherence = np.clip(1 - (2e-8 / np.abs(h)) ** 2, 0.3, 0.999)  # poor at antiresonances
    out = identify({"assembly": start(3.0, 3.0),
                    "measurements": [{**ra1_measurement, "coherence": coherence.tolist()}]})
    assert_accurate(out)


# ---------------------------------------------------------------------------- honest failures


def test_band_without_any_controlling_mode_is_not_identifiable():
    st = start(3.0, 3.0)
    out = identify({"assembly": st, "measurements": [measured(band_hz=(2000.0, 3500.0))]})
    assert out["status"] == "not_identifiable"
    assert "no resonance peak" in out["detail"]
    for joint in TRUE:  # returned unchanged, never invented
        assert out["joints"][joint]["stiffness_n_m"] == st["joints"][joint]["stiffness_n_m"]
        assert out["joints"][joint]["uncertainty"] == {"stiffness_n_m": None, "damping_ns_m": None}


def test_band_without_the_tool_mode_flags_the_holder_tool_joint():
    doc = start(3.0, 1.0)
    out = identify({"assembly": doc, "measurements": [measured(band_hz=(100.0, 1000.0))]})
    assert_accurate(out, joints=("spindle_holder",))
    ht = out["joints"]["holder_tool"]
    assert ht["stiffness_n_m"] == doc["joints"]["holder_tool"]["stiffness_n_m"]
    assert ht["uncertainty"]["stiffness_n_m"] is None
    flagged = {f["parameter"]: f["reason"] for f in out["flags"]}
    assert "not informed" in flagged["holder_tool.stiffness_n_m"]
    assert "not informed" in flagged["holder_tool.damping_ns_m"]


def test_absurd_start_is_not_identifiable(ra1_measurement):
    st = start(1000.0, 1000.0)
    out = identify({"assembly": st, "measurements": [ra1_measurement]})
    assert out["status"] == "not_identifiable" and out["detail"]
    assert out["joints"]["holder_tool"]["stiffness_n_m"] == st["joints"]["holder_tool"]["stiffness_n_m"]


def test_bounds_that_exclude_the_truth_are_not_identifiable(ra1_measurement):
    out = identify({"assembly": start(3.0, 3.0), "measurements": [ra1_measurement],
                    "bounds": {"holder_tool.stiffness_n_m": [2.5e7, 4.0e7]}})
    assert out["status"] == "not_identifiable"
    assert out["joints"]["holder_tool"]["stiffness_n_m"] == pytest.approx(3 * 1.14e7)


def test_model_form_error_the_joints_cannot_absorb_is_not_identifiable():
    truth = ra1()
    truth["materials"] = {"carbide": {"youngs_modulus_pa": 5.4e11}}  # the real tool is 10 % softer
    out = identify({"assembly": start(3.0, 3.0), "measurements": [measured(doc=truth)]})
    assert out["status"] == "not_identifiable"
    assert "noise" in out["detail"]
    assert out["residual_rel"] > 4 * out["noise_rel"]


# ---------------------------------------------------------------------------- request checks


def _bad(request_update=None, measurement_update=None):
    meas = {"tool": {"stickout_m": 0.074}, "frequency_hz": [100.0 + i for i in range(20)],
            "h": {"real": [1e-7] * 20, "imag": [-1e-8] * 20}}
    meas.update(measurement_update or {})
    req = {"assembly": ra1(), "measurements": [meas]}
    req.update(request_update or {})
    return req


@pytest.mark.parametrize("req, field", [
    (_bad({"extra": 1}), "extra"),
    (_bad({"measurements": []}), "measurements"),
    ({"measurements": []}, "assembly"),
    (_bad(measurement_update={"h": {"real": [1e-7] * 19, "imag": [-1e-8] * 20}}), "measurements[0].h.real"),
    (_bad(measurement_update={"frequency_hz": [100.0 + i for i in range(19)] + [50.0]}), "measurements[0].frequency_hz"),
    (_bad(measurement_update={"frequency_hz": [0.0 + i for i in range(20)]}), "measurements[0].frequency_hz"),
    (_bad(measurement_update={"frequency_hz": [100.0 + i for i in range(10)],
                              "h": {"real": [1e-7] * 10, "imag": [-1e-8] * 10}}), "measurements[0].frequency_hz"),
    (_bad(measurement_update={"coherence": [1.2] * 20}), "measurements[0].coherence"),
    (_bad(measurement_update={"coherence": [1.0] * 3}), "measurements[0].coherence"),
    (_bad(measurement_update={"tool": {"stickout": 0.05}}), "measurements[0].tool.stickout"),
    (_bad(measurement_update={"tool": {"stickout_m": 0.5}}), "measurements[0].tool.stickout_m"),
    (_bad(measurement_update={"h": [1, 2]}), "measurements[0].h"),
    (_bad(measurement_update={"speed": 1}), "measurements[0].speed"),
    (_bad({"assembly": {**ra1(), "joints": {}}}), "assembly.joints"),
    (_bad({"bounds": {"holder_tool.stiffness_n_m": [1e8, 1e9]}}), "bounds.holder_tool.stiffness_n_m"),
    (_bad({"bounds": {"holder_tool.mass_kg": [1, 2]}}), "bounds.holder_tool.mass_kg"),
    (_bad({"max_residual_to_noise": 0.5}), "max_residual_to_noise"),
    (_bad({"assembly": {**ra1(), "spindle": {"measurement_id": "x"}}}), "assembly.spindle"),
], ids=["unknown field", "no measurements", "no assembly", "unequal lengths", "not increasing", "0 Hz",
        "too few lines", "coherence > 1", "coherence length", "unknown tool key", "stickout > OAL",
        "h not complex", "unknown measurement key", "rigid joints", "bounds exclude start",
        "unknown bound", "ratio <= 1", "measured spindle"])
def test_bad_requests_are_input_errors(req, field):
    with pytest.raises(InputError) as err:
        identify(req)
    assert err.value.field == field


def test_zero_starting_damping_is_refused():
    doc = ra1()
    doc["joints"]["holder_tool"]["damping_ns_m"] = 0.0
    with pytest.raises(InputError) as err:
        identify(_bad({"assembly": doc}))
    assert err.value.field == "assembly.joints.holder_tool.damping_ns_m"


# ---------------------------------------------------------------------------- CLI and runtime


def _app() -> typer.Typer:
    app = typer.Typer()
    identify_cmd.register(app)
    app.command("noop")(lambda: None)  # two commands: ``identify`` is a sub-command as in ``rcsa``
    return app


def test_cli_identify(tmp_path, ra1_measurement):
    src, out = tmp_path / "req.json", tmp_path / "out.json"
    src.write_text(json.dumps({"assembly": start(3.0, 3.0), "measurements": [ra1_measurement]}))
    result = CliRunner().invoke(_app(), ["identify", str(src), "-o", str(out)])
    assert result.exit_code == 0, result.stderr
    doc = json.loads(out.read_text())
    assert doc["status"] == "identified"
    assert "runtime_s" in doc  # reported; how long it takes is measured in benchmarks/bench_jointid.py


def test_cli_bad_request_is_one_line(tmp_path):
    src = tmp_path / "req.json"
    src.write_text(json.dumps(_bad({"extra": 1})))
    result = CliRunner().invoke(_app(), ["identify", str(src)])
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: extra")


@pytest.mark.slow
def test_a_clamping_along_the_insertion_has_its_interface_stiffness_identified():
    """A clamped base with a hydraulic sleeve's layer (contact, 6e12 N/m³ as in the 3-D data set),
    tapped on a clamp three times softer (interface stiffness ×0.3): the identification returns it
    as a reusable holder_tool joint, within its stated uncertainty. (A bonded interface, calibrated
    on 3-D elasticity, moves RA-1's tool mode by < 0.05 per e-fold of its scale: below what the
    identification uses, so it is not identified there; a layer this soft is.)"""
    from rcsa.model.assembly import build_model
    from rcsa.model.contract import parse_assembly
    from rcsa.model.parameters import set_parameter
    from rcsa.physics.elimination import tip_receptance

    rng = np.random.default_rng(7)
    base = ra1({"start_hz": 800.0, "stop_hz": 4500.0, "step_hz": 4.0})
    base["joints"]["holder_tool"] = {"model": "contact", "interface_stiffness_n_m3": 6e12}
    measurements = []
    for stickout in (0.060, 0.090):
        doc = json.loads(json.dumps(base))
        doc["tool"]["stickout_m"] = stickout
        spec = set_parameter(parse_assembly(doc), "holder_tool.interface_stiffness_scale", 0.3)
        h = tip_receptance(build_model(spec).chain(), 2 * np.pi * spec.frequency_hz)[:, 0, 0]
        h = h * (1 + 0.01 * (rng.standard_normal(h.size) + 1j * rng.standard_normal(h.size)) / np.sqrt(2))
        measurements.append({"tool": {"stickout_m": stickout}, "frequency_hz": spec.frequency_hz.tolist(),
                             "h": {"real": h.real.tolist(), "imag": h.imag.tolist()}})
    out = identify({"assembly": base, "measurements": measurements})
    assert out["status"] == "identified", out.get("detail")
    got = out["joints"]["holder_tool"]
    assert got["model"] == "contact" and got["interface_stiffness_scale"] == pytest.approx(0.3, rel=2e-3)
    assert abs(got["interface_stiffness_scale"] - 0.3) <= 5 * got["uncertainty"]["interface_stiffness_scale"]
    assert "stiffness_n_m" not in got
    # the identified joint is a valid holder_tool joint of the contract: predicting with it reproduces the tap
    reuse = json.loads(json.dumps(base))
    reuse["joints"]["holder_tool"] = {k: v for k, v in got.items() if k != "uncertainty"}
    assert predict(reuse).tool_point.h.shape == (926,)

"""Unit tests of the diagnosis building blocks (``docs/diagnosis.md`` §7 "Tests")."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rcsa.analysis.diagnosis.attribution import Likelihood, decide, evidence
from rcsa.analysis.diagnosis.candidates import catalogue
from rcsa.analysis.diagnosis.discrepancy import Discrepancy, noise_sd_rel, shrink
from rcsa.analysis.diagnosis.features import design_windows, extract
from rcsa.analysis.diagnosis.perturbed_model import Knobs, Solver, config_parts
from rcsa.model.contract import parse_assembly
from tests.analysis.diagnosis.truth import base_document

F_HZ = np.geomspace(50.0, 8000.0, 1500)


@pytest.fixture(scope="module")
def spec():
    return parse_assembly({**base_document(), "frequency": {"values_hz": F_HZ.tolist()}})


@pytest.fixture(scope="module")
def solver():
    return Solver(F_HZ)


# ------------------------------------------------------------------------- evidence
def _linear_gaussian(x: np.ndarray, y: np.ndarray, sigma: float):
    """ln L(φ) of y = φ x + N(0, σ²) and its closed-form evidence under U(a, b)."""
    def loglik(p: np.ndarray) -> np.ndarray:
        r = y[None, :] - p[:, :1] * x[None, :]
        return -0.5 * np.sum(r**2, axis=1) / sigma**2 - x.size * np.log(np.sqrt(2 * np.pi) * sigma)
    phi_hat = float(x @ y / (x @ x))
    sd = sigma / np.sqrt(x @ x)
    return loglik, phi_hat, sd


@pytest.mark.parametrize("sigma", [0.3, 0.01])  # wide posterior (grid) and narrow one (fine grid)
def test_evidence_equals_closed_form_for_a_linear_gaussian_toy(sigma):
    rng = np.random.default_rng(3)
    x = rng.uniform(0.5, 1.5, 8)
    y = 0.2 * x + sigma * rng.standard_normal(8)
    loglik, phi_hat, sd = _linear_gaussian(x, y, sigma)
    a, b = -1.0, 1.0
    # ln Z = ln L(φ̂) + ln(√(2π) sd) − ln(b − a), exact when the posterior lies inside [a, b]
    expected = float(loglik(np.array([[phi_hat]]))[0]) + np.log(np.sqrt(2 * np.pi) * sd) - np.log(b - a)
    log_z, x_map, post_sd, _, method = evidence(loglik, np.array([a]), np.array([b]))
    assert method == ("grid" if sigma == 0.3 else "fine-grid")
    assert log_z == pytest.approx(expected, abs=2e-3)  # trapezoid on ≥ 25 points per sd-scale
    assert x_map[0] == pytest.approx(phi_hat, abs=0.02 * sd + 1e-9)
    assert post_sd[0] == pytest.approx(sd, rel=0.02)


def test_two_dimensional_laplace_evidence_matches_closed_form():
    rng = np.random.default_rng(5)
    a_mat = rng.standard_normal((12, 2))
    sigma = 0.01
    y = a_mat @ np.array([0.1, -0.2]) + sigma * rng.standard_normal(12)

    def loglik(p):
        r = y[None, :] - p @ a_mat.T
        return -0.5 * np.sum(r**2, axis=1) / sigma**2

    prec = a_mat.T @ a_mat / sigma**2
    p_hat = np.linalg.solve(a_mat.T @ a_mat, a_mat.T @ y)
    expected = float(loglik(p_hat[None, :])[0]) + np.log(2 * np.pi) - 0.5 * np.linalg.slogdet(prec)[1] - np.log(4.0)
    log_z, x_map, _, _, method = evidence(loglik, np.array([-1.0, -1.0]), np.array([1.0, 1.0]))
    assert method == "laplace"
    assert log_z == pytest.approx(expected, abs=1e-3)
    np.testing.assert_allclose(x_map, p_hat, atol=1e-3)


def test_decision_rules():
    class C:
        def __init__(self, name):
            self.name = name

    class F:
        def __init__(self, name, bf):
            self.candidate, self.log_bayes_factor, self.log_evidence = C(name), bf, bf

    assert decide([F("a", 2.9), F("b", 1.0)], 3.0, 2.3).status == "none"
    d = decide([F("a", 9.0), F("b", 7.5), F("c", 1.0)], 3.0, 2.3)
    assert (d.status, d.effect, d.ambiguous_with) == ("ambiguous", "a", ["b"])
    d = decide([F("a", 9.0), F("b", 6.0)], 3.0, 2.3)
    assert (d.status, d.effect) == ("identified", "a")


# ------------------------------------------------------------------------- covariance
def test_shrunk_covariance_is_positive_definite_even_from_too_few_draws():
    rng = np.random.default_rng(0)
    samples = rng.standard_normal((5, 40)) * rng.uniform(0.1, 2.0, 40)  # rank 4 < 40
    cov = np.cov(samples, rowvar=False)
    assert np.linalg.eigvalsh(cov).min() < 1e-10
    assert np.linalg.eigvalsh(shrink(cov)).min() > 0


def test_noise_from_coherence_is_bendat_piersol():
    # γ² = 0.9, n_d = 5: √(0.1) / (√0.9 · √10) = 0.1054
    assert noise_sd_rel(np.array([0.9]), 5)[0] == pytest.approx(np.sqrt(0.1) / (np.sqrt(0.9) * np.sqrt(10)))


def test_whitener_inverts_sigma():
    rng = np.random.default_rng(1)
    a = rng.standard_normal((6, 6))
    sigma = a @ a.T + 0.1 * np.eye(6)
    d = Discrepancy(np.zeros(6), sigma, np.zeros((1, 6)), np.zeros((1, 1)))
    w = d.whitener()
    np.testing.assert_allclose(w @ sigma @ w.T, np.eye(6), atol=1e-10)
    rows = np.array([1, 3, 4])
    w3 = d.whitener(rows)
    np.testing.assert_allclose(w3 @ sigma[np.ix_(rows, rows)] @ w3.T, np.eye(3), atol=1e-10)
    like = Likelihood(np.ones(6), d, np.arange(6), "gaussian")
    assert like.chi2(np.ones(6)) == pytest.approx(0.0)


# ------------------------------------------------------------------------- model and features
def test_tip_mass_leaves_driving_point_antiresonances_and_static_compliance_unchanged(spec, solver):
    """A mass on the pinned DOF cannot change the pinned system: H_m = H / (1 + ω² m H) has H's zeros."""
    h0 = solver.tip_h(config_parts(spec, spec.tool, Knobs()))
    hm = solver.tip_h(config_parts(spec, spec.tool, Knobs(tip_mass_kg=0.006)))
    w = 2 * np.pi * F_HZ
    np.testing.assert_allclose(hm, h0 / (1 - w**2 * 0.006 * h0), rtol=1e-9)  # exact correction (e^{iωt})
    win = design_windows(F_HZ, h0)
    f0, fm = extract(F_HZ, h0, win), extract(F_HZ, hm, win)
    names = np.array(win.names)
    anti = np.char.startswith(names, "antiresonance")
    peaks = np.char.endswith(names, "frequency") & ~anti
    # Antiresonances agree to the parabolic refinement on the analysis lines (0.35 % spacing):
    np.testing.assert_allclose(fm[anti], f0[anti], atol=5e-4)
    # The quasi-static band (50-200 Hz) sees the mass only through ω² m |h| ≤ 0.4 % at 200 Hz:
    assert abs(fm[list(names).index("static")] - f0[list(names).index("static")]) < 2e-3
    assert np.all(fm[peaks] < f0[peaks] - 1e-3)  # every resonance moves down


def test_every_candidate_at_its_null_value_is_the_base_model(spec, solver):
    h0 = solver.tip_h(config_parts(spec, spec.tool, Knobs()))
    cands, notes = catalogue(spec, [spec.tool], solver)
    assert {c.name for c in cands} == {"holder_tool_joint", "spindle_holder_joint", "bearings",
                                      "shear_and_rotary_inertia", "fluted_section", "insertion_depth",
                                      "sensor_mass", "joint_damping", "spindle_rotational_receptance",
                                      "clamping_model"}  # interface_scale: a point base has no interface
    assert notes == ["interface_scale: not a candidate because the base model's holder-tool joint is a point "
                     "joint: there is no clamping interface to scale (clamping_model proposes a clamping "
                     "instead)."]
    for c in cands:
        if c.model_form:  # another model, not an effect at its null value (tests/analysis/diagnosis/test_model_form.py)
            continue
        h = solver.tip_h(config_parts(spec, spec.tool, c.apply(Knobs(), c.null)))
        np.testing.assert_allclose(h, h0, rtol=1e-12, err_msg=c.name)
        assert np.all(c.lo <= c.null) and np.all(c.null <= c.hi), c.name


def test_euler_bernoulli_base_has_null_shear_scale_zero():
    doc = {**base_document("euler_bernoulli"), "frequency": {"values_hz": F_HZ.tolist()}}
    spec_eb = parse_assembly(doc)
    solver = Solver(F_HZ)
    cands, _ = catalogue(spec_eb, [spec_eb.tool], solver, names=["shear_and_rotary_inertia"])
    assert cands[0].null[0] == 0.0
    timo = parse_assembly({**base_document(), "frequency": {"values_hz": F_HZ.tolist()}})
    h_t = solver.tip_h(config_parts(timo, timo.tool, Knobs()))
    h_full = solver.tip_h(config_parts(spec_eb, spec_eb.tool, cands[0].apply(Knobs(), np.array([1.0]))))
    np.testing.assert_allclose(h_full, h_t, rtol=1e-12)


def test_insertion_offset_keeps_the_tip_and_moves_the_clamp(spec, solver):
    """δ inside the holder: the free tool length grows by δ, the holder loses δ, the tip stays."""
    parts = config_parts(spec, spec.tool, Knobs(insertion_offset_m=0.005))
    base = config_parts(spec, spec.tool, Knobs())
    length = sum(getattr(i, "length_m", 0.0) for i in parts.middle + parts.tool)
    assert length == pytest.approx(sum(getattr(i, "length_m", 0.0) for i in base.middle + base.tool), abs=1e-12)
    assert sum(getattr(i, "length_m", 0.0) for i in parts.tool) == pytest.approx(
        sum(getattr(i, "length_m", 0.0) for i in base.tool) + 0.005)


def test_solver_matches_the_engine(spec):
    from rcsa.model.assembly import build_model
    from rcsa.physics.elimination import tip_receptance
    solver = Solver(F_HZ)
    tool = replace(spec.tool, stickout_m=0.06)
    h = solver.tip_h(config_parts(spec, tool, Knobs()))
    exact = tip_receptance(build_model(replace(spec, tool=tool)).chain(), 2 * np.pi * F_HZ)[:, 0, 0]
    np.testing.assert_allclose(h, exact, rtol=1e-10)


def test_added_compliance_is_a_chain_item_adding_to_the_receptance(spec):
    """R → R + [[0, c_wψ], [c_wψ, c_ψψ]], through march and through a measured (compliance) base."""
    from rcsa.analysis.diagnosis.perturbed_model import AddedCompliance
    from rcsa.model.assembly import build_model
    from rcsa.physics.algebra2x2 import inv2
    from rcsa.physics.elimination import march, tip_receptance
    omega = 2 * np.pi * F_HZ[::10]
    chain = build_model(spec).chain()
    added = AddedCompliance(2e-8, 3e-7)
    c = np.array([[0.0, 2e-8], [2e-8, 3e-7]])
    r = tip_receptance(chain, omega)
    np.testing.assert_allclose(tip_receptance((*chain, added), omega), r + c, rtol=1e-9, atol=1e-9 * np.abs(r).max())
    beam = next(i for i in chain if hasattr(i, "section"))
    on_base = inv2(march((added, beam), omega, start_compliance=r)[0])
    np.testing.assert_allclose(on_base, inv2(march((beam,), omega, inv2(r + c))[0]), rtol=1e-8)


def test_the_parabola_stencils_give_the_normal_equations_vertex():
    """The per-line stencil (the least squares solved once per line) and the normal equations
    solved per call give the same vertex; clipped stencils fall back to the latter."""
    from rcsa.analysis.diagnosis.features import _vertex, parabola_stencils

    rng = np.random.default_rng(4)
    x = np.log(np.sort(rng.uniform(100.0, 6000.0, 300)))
    y = -0.5 * ((x[None, :] - x[[80, 150, 220]][:, None]) / 0.02) ** 2 + 0.01 * rng.standard_normal((3, 300))
    i = np.array([80, 150, 221])
    lo, hi = np.array([40, 100, 200]), np.array([120, 200, 260])
    for sign, yy in ((1.0, y), (-1.0, -y)):
        plain = _vertex(x, yy, i, lo, hi, sign)
        fast = _vertex(x, yy, i, lo, hi, sign, stencils=parabola_stencils(x))
        np.testing.assert_allclose(fast[0], plain[0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(fast[1], plain[1], rtol=1e-12)
    assert np.all(np.abs(plain[0] - x[i]) < 0.02)  # a real vertex, not the fallback to the line

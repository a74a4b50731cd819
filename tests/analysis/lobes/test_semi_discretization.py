"""Unit, oracle and convergence tests of the semi-discretization (SDM) stability lobes.

Oracles used here (the published single-mode benchmark is in
tests/reference/test_lobes_insperger_stepan2004.py):

* scipy's ``expm`` of the augmented step matrix (step exponentials);
* a straightforward loop implementation of the SDM map for several modes in x and y, written
  from the equations with the full delay chain of (x, y) samples and unscaled coordinates,
  and dense eigenvalues (the reduced, vectorised map and its Krylov eigenvalue);
* the zero-order solution where it is exact: slotting with an even number N >= 4 of teeth
  makes the cutting-force direction constant in time (the ``sin 2φ``, ``cos 2φ`` terms of two
  teeth π/2 apart cancel), so the delay equation is autonomous and ZOA's characteristic
  equation is exact;
* the order of convergence in the number of steps per period (2 for first-order SDM).
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from scipy.linalg import expm
from typer.testing import CliRunner

import rcsa as rcsa_app
from rcsa.analysis.lobes import monodromy as md
from rcsa.analysis.lobes import semi_discretization as sdm
from rcsa.analysis.lobes.modal_model import (
    MIN_PEAK_FRACTION,
    ModalModel,
    fit_modal_model,
    modal_model_from_assembly,
)
from rcsa.analysis.lobes.options import LobesMethod, parse_method
from rcsa.analysis.lobes.request import parse_lobes_request
from rcsa.analysis.lobes.zoa import (
    LobeResult,
    directional_factors,
    engagement_angles_rad,
    stability_lobes,
)
from rcsa.cli import app as cli_app
from rcsa.errors import InputError
from rcsa.model.contract import parse_assembly
from rcsa.reference import ra1

with warnings.catch_warnings():  # starlette asks for httpx2, which the project does not install
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient
from service.main import create_app

from tests.service.conftest import READ, assert_problem, settings_for

KT, KR = 6e8, 0.3
# Two modes in x and two (different) in y: natural frequency (Hz), damping ratio, residue (1/kg).
XY = ModalModel.of([600.0, 1400.0, 650.0, 1500.0], [0.03, 0.02, 0.035, 0.02], [0.5, 2.0, 0.4, 1.7],
                   [0, 0, 1, 1])
BENCHMARK = ModalModel.of([922.0], [0.011], [1 / 0.03993], [0])  # Insperger & Stépán (2004)
GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
LOBES = {"teeth": 4, "tangential_coefficient_n_m2": KT, "radial_ratio": KR, "radial_immersion": 0.5,
         "milling": "down", "spindle_speed_rpm": {"start": 4000, "stop": 30000, "count": 40}}
SDM = {"method": "semi_discretization"}


def lobes(model=XY, *, teeth=4, immersion=0.5, milling="down", speeds=(12000.0,), **kw):
    return sdm.semi_discretization_lobes(
        model, teeth=teeth, tangential_coefficient_n_m2=KT, radial_ratio=KR, radial_immersion=immersion,
        milling=milling, spindle_speed_rpm=np.asarray(speeds, dtype=float), **kw)


# --------------------------------------------------------------------------- the period map


@pytest.mark.parametrize(("immersion", "milling"), [(0.05, "down"), (0.3, "up"), (0.5, "down"), (1.0, "up")])
@pytest.mark.parametrize("teeth", [1, 2, 3, 5])
def test_step_means_integrate_to_the_zoa_directional_factors(immersion, milling, teeth):
    """Σ_i W_i Δφ over a tooth period = −½ α(φst, φex): every tooth sweeps 2π/N once."""
    st, ex = engagement_angles_rad(immersion, milling)
    plan = md.cutting_plan(teeth, 40, st, ex, KR)
    dphi = 2 * np.pi / (teeth * 40)
    np.testing.assert_allclose(plan.force.sum(axis=0) * dphi, -0.5 * directional_factors(st, ex, KR),
                               rtol=1e-12, atol=1e-14)
    steps = [s for _, start, length in plan.segments for s in range(start, start + length)]
    assert steps == list(range(40))  # the segments cover the period once, in order


def test_low_immersion_keeps_only_the_samples_that_are_read():
    st, ex = engagement_angles_rad(0.05, "down")
    plan = md.cutting_plan(2, 40, st, ex, KR)
    assert plan.cut_step.tolist() == list(range(34, 40)) and plan.n_samples == 6  # 88 → 14 states
    even = md.cutting_plan(4, 40, *engagement_angles_rad(1.0, "down"), KR)
    assert np.allclose(even.force, even.force[0], rtol=1e-12)  # 4-tooth slotting: constant force


@pytest.mark.parametrize("scale", [1e-3, 0.7, 3.0, 40.0])
def test_step_exponentials_match_expm_of_the_augmented_matrix(rng, scale):
    z = rng.standard_normal((6, 5, 5)) * scale
    beta = rng.standard_normal((6, 5, 2))
    e, x, y = md.step_exponentials(z, beta)
    for j in range(6):
        aug = np.zeros((9, 9))
        aug[:5, :5], aug[:5, 5:7], aug[5:7, 7:9] = z[j], beta[j], np.eye(2)
        ref = expm(aug)
        for got, want in ((e[j], ref[:5, :5]), (x[j], ref[:5, 5:7]), (y[j], ref[:5, 7:9])):
            np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


def test_step_exponentials_of_a_mixed_batch_equal_each_alone(rng):
    """Matrices grouped by their squarings and degree, zero ones (padding) set exactly: every
    member of a batch mixing scales and zeros gets what it gets alone."""
    scales = np.array([0.0, 1e-3, 0.1, 0.0, 2.0, 40.0, 0.3])
    z = rng.standard_normal((scales.size, 4, 4)) * scales[:, None, None]
    beta = rng.standard_normal((scales.size, 4, 2)) * (scales > 0)[:, None, None]
    e, x, y = md.step_exponentials(z, beta)
    for j in range(scales.size):
        alone = md.step_exponentials(z[j : j + 1], beta[j : j + 1])
        for got, want in zip((e[j], x[j], y[j]), alone, strict=True):
            np.testing.assert_array_equal(got, want[0])
    np.testing.assert_array_equal(e[0], np.eye(4))


def test_step_exponentials_of_a_batch_larger_than_the_cache_pieces_match_expm(rng):
    """A class of matrices is summed in pieces of ``_CACHE_CHUNK``: members on either side of every
    piece's edge, and in the short last piece, get the augmented matrix's exponential."""
    count = 2 * md._CACHE_CHUNK + 7
    z = rng.standard_normal((count, 4, 4)) * rng.choice([0.05, 0.6, 5.0], size=count)[:, None, None]
    beta = rng.standard_normal((count, 4, 2))
    e, x, y = md.step_exponentials(z, beta)
    for j in sorted({0, md._CACHE_CHUNK - 1, md._CACHE_CHUNK, 2 * md._CACHE_CHUNK, count - 1, *rng.integers(0, count, 8)}):
        aug = np.zeros((8, 8))
        aug[:4, :4], aug[:4, 4:6], aug[4:6, 6:8] = z[j], beta[j], np.eye(2)
        ref = expm(aug)
        for got, want in ((e[j], ref[:4, :4]), (x[j], ref[:4, 4:6]), (y[j], ref[:4, 6:8])):
            np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


def test_a_speeds_chatter_frequency_does_not_depend_on_the_speeds_solved_beside_it():
    """Each member samples its free flight at its own period's count (``displacement_samples``):
    a low speed beside a high one does not change the high one's answer."""
    together = lobes(BENCHMARK, teeth=2, immersion=0.05, speeds=(2500.0, 21000.0))
    for i, n in enumerate((2500.0, 21000.0)):
        alone = lobes(BENCHMARK, teeth=2, immersion=0.05, speeds=(n,))
        assert together.chatter_frequency_hz[i] == pytest.approx(alone.chatter_frequency_hz[0], rel=1e-9)
        assert together.depth_limit_m[i] == pytest.approx(alone.depth_limit_m[0], rel=1e-9)
    system = md.state_space(BENCHMARK)
    periods = 60.0 / (2 * np.array([2500.0, 21000.0]))
    assert md.displacement_samples(system, periods).tolist() == [64 * 2 ** math.ceil(math.log2(4 * 922 * periods[0] / 64)),
                                                                 64]


def test_step_exponentials_of_a_singular_matrix():
    """``A_i`` singular (cutting stiffness cancels a mode): no inverse, φ1(0) = I, φ2(0) = I/2."""
    e, x, y = md.step_exponentials(np.zeros((1, 3, 3)), np.ones((1, 3, 1)))
    np.testing.assert_allclose(e[0], np.eye(3))
    np.testing.assert_allclose(x[0], np.ones((3, 1)))
    np.testing.assert_allclose(y[0], 0.5 * np.ones((3, 1)))


def _loop_monodromy(model, teeth, immersion, milling, rpm, depth, k=40):
    """The SDM map written out: physical modal state [q; q̇], full (x, y) delay chain."""
    st, ex = engagement_angles_rad(immersion, milling)
    w = 2 * np.pi * model.frequency_hz
    d = w.size
    c = np.zeros((2, d))
    c[model.direction, np.arange(d)] = np.sqrt(model.residue_1_kg)  # r = c q, modal force = cᵀ F
    dphi = 2 * np.pi / (teeth * k)
    h = 60.0 / (rpm * teeth) / k
    size = 2 * d + 2 * k
    phi = np.eye(size)
    for i in range(k):
        force = np.zeros((2, 2))  # step mean of W(t), by midpoint-free exact integration
        for j in range(teeth):
            lo = min(max(i * dphi + j * 2 * np.pi / teeth, st), ex)
            hi = min(max((i + 1) * dphi + j * 2 * np.pi / teeth, st), ex)
            if hi > lo:
                force += -0.5 * directional_factors(lo, hi, KR) / dphi
        kf = depth * KT * force
        a = np.zeros((2 * d, 2 * d))
        a[:d, d:] = np.eye(d)
        a[d:, :d] = -np.diag(w**2) - c.T @ kf @ c
        a[d:, d:] = -np.diag(2 * model.damping_ratio * w)
        aug = np.zeros((2 * d + 4, 2 * d + 4))
        aug[: 2 * d, : 2 * d] = a
        aug[d : 2 * d, 2 * d : 2 * d + 2] = c.T @ kf
        aug[2 * d : 2 * d + 2, 2 * d + 2 :] = np.eye(2) / h
        e = expm(aug * h)
        g1, g2 = e[: 2 * d, 2 * d : 2 * d + 2], e[: 2 * d, 2 * d + 2 :]
        step = np.zeros((size, size))
        step[: 2 * d, : 2 * d] = e[: 2 * d, : 2 * d]
        step[: 2 * d, size - 2 :] += g1 - g2  # r_{i−k}: the oldest sample
        step[: 2 * d, size - 4 : size - 2] += g2  # r_{i−k+1}
        step[2 * d : 2 * d + 2, :d] = c  # the new sample r_i
        step[2 * d + 2 :, 2 * d : size - 2] = np.eye(2 * k - 2)
        phi = step @ phi
    ev = np.linalg.eigvals(phi)
    return ev[np.argmax(np.abs(ev))]


CASES = [(XY, 2, 0.05, "down", 18000.0, 3e-3), (XY, 3, 0.3, "up", 9000.0, 2e-3),
         (XY, 4, 0.5, "down", 15000.0, 1e-3), (XY, 2, 1.0, "down", 6000.0, 6e-4)]


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"N{c[1]}-{c[2]}-{c[3]}")
def test_reduced_map_equals_the_loop_oracle(case):
    model, teeth, immersion, milling, rpm, depth = case
    expected = _loop_monodromy(model, teeth, immersion, milling, rpm, depth)
    system = md.state_space(model)
    plan = md.cutting_plan(teeth, 40, *engagement_angles_rad(immersion, milling), KR)
    step = np.array([60.0 / (rpm * teeth) / 40])
    maps = md.period_maps(system, plan, KT, step, np.array([depth]), md.free_maps(system, plan, step))
    mu, vec = md.critical_multipliers(system, plan, maps, vectors=True)
    # Same map in other coordinates: the largest multiplier agrees to rounding (1e-9 of |μ|).
    assert abs(abs(mu[0]) - abs(expected)) < 1e-9 * abs(expected)
    assert abs(mu[0] - (expected if np.sign(expected.imag) == np.sign(mu[0].imag) else np.conj(expected))) < 1e-8
    # Floquet: the next period's state is μ times this one, and the trajectory samples are the
    # delayed samples of the next state.
    assert vec is not None
    z = vec[:, :, None]
    after = md.apply_period(system, plan, maps, z)[:, :, 0]
    np.testing.assert_allclose(after, mu[:, None] * vec, atol=1e-8 * np.abs(vec).max())
    r = md.trajectory(system, plan, maps, vec)
    kept = np.flatnonzero(plan.slot >= 0)
    np.testing.assert_allclose(r[0, kept].ravel(), after[0, system.n :], atol=1e-8 * np.abs(vec).max())


def test_krylov_multipliers_equal_dense_ones():
    system = md.state_space(XY)
    plan = md.cutting_plan(4, 40, *engagement_angles_rad(0.5, "down"), KR)
    rpm = np.linspace(3000, 30000, 60)
    step = 60.0 / (rpm * 4) / 40
    maps = md.period_maps(system, plan, KT, step, np.geomspace(2e-4, 6e-3, 60), md.free_maps(system, plan, step))
    assert system.n + 2 * plan.n_samples > md.DENSE_MAX_SIZE  # the Krylov path is taken
    mu, _ = md.critical_multipliers(system, plan, maps)
    ev = np.linalg.eigvals(md.monodromy_matrix(system, plan, maps))
    dense = ev[np.arange(60), np.argmax(np.abs(ev), axis=1)]
    np.testing.assert_allclose(np.abs(mu), np.abs(dense), rtol=1e-7)


# --------------------------------------------------------------------------- against ZOA


def test_full_immersion_four_teeth_equals_zoa_within_two_percent():
    """Even N >= 4 slotting: the force direction is constant, ZOA exact; the rest is the SDM's
    own discretization error, below 1 % with >= 15 steps per chatter cycle (8 000 rpm and up)."""
    speeds = np.linspace(8000, 30000, 111)
    r = lobes(teeth=4, immersion=1.0, speeds=speeds)
    f = np.arange(200.0, 3000.0, 0.05)  # fine enough for ZOA's grid to stay below 1e-4
    z = stability_lobes(f, XY.receptance(f, 0), XY.receptance(f, 1), teeth=4, tangential_coefficient_n_m2=KT,
                        radial_ratio=KR, radial_immersion=1.0, milling="down", spindle_speed_rpm=speeds)
    assert np.all(r.steps_per_chatter_cycle >= 15)
    np.testing.assert_allclose(r.depth_limit_m, z.depth_limit_m, rtol=0.02,
                               err_msg="SDM vs ZOA, 4-tooth slotting, depth limit")
    np.testing.assert_allclose(r.chatter_frequency_hz, z.chatter_frequency_hz, rtol=0.002)
    assert set(r.instability) == {"hopf"} and np.array_equal(r.governing_lobe, z.governing_lobe)


def test_flip_lobes_at_low_immersion_where_zoa_says_stable():
    speeds = np.linspace(5000, 40000, 351)
    r = lobes(teeth=2, immersion=0.05, speeds=speeds)
    flip = r.instability == "flip"
    assert flip.sum() >= 10
    mu = r.critical_multiplier[flip]  # at the unstable end of a 1e-3-wide depth bracket
    assert np.all(mu.imag == 0) and np.all((mu.real <= -1.0) & (mu.real > -1.01))
    f = np.arange(200.0, 3000.0, 0.1)
    z = stability_lobes(f, XY.receptance(f, 0), XY.receptance(f, 1), teeth=2, tangential_coefficient_n_m2=KT,
                        radial_ratio=KR, radial_immersion=0.05, milling="down", spindle_speed_rpm=speeds)
    assert np.all(z.depth_limit_m[flip] > 1.2 * r.depth_limit_m[flip])  # ZOA: stable at the flip limit


@pytest.mark.parametrize("default_steps", [False, True], ids=["k40", "resolving"])
@pytest.mark.parametrize(("model", "teeth", "immersion", "milling"), [
    (BENCHMARK, 2, 0.05, "down"), (XY, 2, 0.05, "down"), (XY, 3, 0.1, "up")], ids=["1dof", "xy-down", "xy-up"])
def test_the_depth_search_finds_the_first_crossing_of_a_fine_grid(model, teeth, immersion, milling, default_steps):
    """Islands and flip lenses: the scan-and-refine must not step over an unstable band that a
    400-point depth grid (0 … ceiling) sees first (checked with dense eigenvalues of the same map:
    40 steps over the period, or each speed's own cut-window plan)."""
    speeds = np.linspace(5000, 40000, 36)
    r = lobes(model, teeth=teeth, immersion=immersion, milling=milling, speeds=speeds,
              **({} if default_steps else {"steps_per_period": 40}))
    system = md.state_space(model)
    st, ex = engagement_angles_rad(immersion, milling)
    depths = np.linspace(0.0, r.depth_search_max_m, 401)[1:]
    for n, limit, k in zip(speeds, r.depth_limit_m, r.steps, strict=True):  # a loop over speeds (an oracle)
        plan = md.cut_window_plan(teeth, int(k), st, ex, KR) if default_steps else md.cutting_plan(teeth, 40, st, ex, KR)
        h = np.full(depths.size, 60.0 / (n * teeth) * plan.step_fraction)
        maps = md.period_maps(system, plan, KT, h, depths, md.free_maps(system, plan, h))
        rho = np.abs(np.linalg.eigvals(md.monodromy_matrix(system, plan, maps))).max(axis=1)
        unstable = np.flatnonzero(rho >= 1.0)
        assert unstable.size, n
        first = depths[unstable[0]]
        # the limit is a bracket's stable end: at most DEPTH_RTOL below the crossing
        assert (first - (depths[1] - depths[0])) * (1 - sdm.DEPTH_RTOL) <= limit <= first * (1 + 1e-3), (
            n, first, limit)


# --------------------------------------------------------------------------- convergence

CONVERGENCE_SPEEDS = (8500.0, 12000.0, 23000.0)  # Hopf limits of the single-mode benchmark


@pytest.fixture(scope="module")
def convergence():
    depth = {}
    for k in (10, 20, 40, 80, 640):
        r = lobes(BENCHMARK, teeth=2, immersion=0.05, speeds=CONVERGENCE_SPEEDS, steps_per_period=k,
                  depth_rtol=1e-9)
        depth[k] = r.depth_limit_m
    return depth


def test_error_shrinks_as_the_square_of_the_step(convergence):
    """First-order SDM is second-order accurate: each doubling of k divides the error by ~4.

    Measured (k = 640 as reference, relative depth error at 8 500 / 12 000 / 23 000 rpm):
    k = 10: 44 / 17 / 4.3 %, k = 20: 8.6 / 3.1 / 0.99 %, k = 40: 2.1 / 0.68 / 0.22 %,
    k = 80: 0.51 / 0.15 / 0.049 %; observed orders 2.0–2.5.
    """
    ref = convergence[640]
    err = {k: np.abs(convergence[k] / ref - 1) for k in (10, 20, 40, 80)}
    for k in (20, 40):
        order = np.log2(err[k] / err[2 * k])
        assert np.all((order > 1.7) & (order < 2.6)), (k, order)
    assert np.all(err[40] < 0.025)


def test_unresolved_speeds_are_flagged_and_the_default_steps_resolve_them():
    """40 steps over a 15 ms tooth period (22 cycles of the 1.5 kHz mode at 2 000 rpm) are too few:
    the check at 28 steps disagrees by more than 1 %; 2.25 cycles at 20 000 rpm are resolved. The
    default steps resolve both (each checked, refined where needed)."""
    r = lobes(XY, teeth=2, immersion=1.0, speeds=[2000.0, 20000.0], steps_per_period=40)
    assert r.resolved.tolist() == [False, True] and r.under_resolved.tolist() == [True, False]
    assert r.check_steps.tolist() == [28, 28] and r.scheme == "full_period"
    assert "not resolved" in r.to_dict()["notes"][0] and r.to_dict()["resolved"] == [False, True]
    auto = lobes(XY, teeth=2, immersion=1.0, speeds=[2000.0, 20000.0])
    assert auto.resolved.tolist() == [True, True] and auto.steps[0] > 40


# --------------------------------------------------------------------------- the result


def test_result_is_the_contract_response_plus_the_sdm_fields():
    r = lobes(XY, teeth=2, immersion=0.05, speeds=np.linspace(5000, 40000, 71))
    assert isinstance(r, LobeResult)
    d = r.to_dict()
    json.dumps(d, allow_nan=False)
    assert {"spindle_speed_rpm", "depth_limit_m", "chatter_frequency_hz", "lobes"} <= d.keys()
    assert d["method"] == "semi_discretization" and d["frf_y_source"] == "given"
    assert d["modal_model"]["source"] == "given" and len(d["modal_model"]["modes"]) == 4
    # the segments partition the envelope, in speed order, each of one kind and lobe number
    covered = np.concatenate([lobe.spindle_speed_rpm for lobe in r.lobes])
    np.testing.assert_array_equal(covered, r.spindle_speed_rpm[np.isfinite(r.depth_limit_m)])
    for lobe, kind, item in zip(r.lobes, r.lobe_kinds, d["lobes"], strict=True):
        at = np.searchsorted(r.spindle_speed_rpm, lobe.spindle_speed_rpm)
        assert set(r.instability[at]) == {kind} and set(r.governing_lobe[at]) == {lobe.index}
        assert item["kind"] == kind
    assert r.min_depth_limit_m == np.nanmin(r.depth_limit_m)
    assert {"hopf", "flip"} <= set(r.lobe_kinds)


def test_no_limit_below_the_ceiling_is_null(monkeypatch):
    monkeypatch.setattr(sdm, "_SCAN_CEILING", 0.5)  # below every limit
    r = lobes(speeds=[10000.0, 20000.0])
    assert np.all(np.isnan(r.depth_limit_m)) and r.lobes == ()
    d = r.to_dict()
    assert d["depth_limit_m"] == [None, None] and d["instability"] == [None, None]
    assert d["governing_lobe"] == [-1, -1] and d["min_depth_limit_m"] is None


# --------------------------------------------------------------------------- modal models


def test_fit_recovers_different_modes_in_x_and_y():
    f = np.arange(100.0, 3000.0, 1.0)
    fit = fit_modal_model(f, XY.receptance(f, 0), XY.receptance(f, 1), modes_per_direction=2)
    np.testing.assert_allclose(fit.frequency_hz, XY.frequency_hz, rtol=1e-7)
    np.testing.assert_allclose(fit.damping_ratio, XY.damping_ratio, rtol=1e-6)
    np.testing.assert_allclose(fit.residue_1_kg, XY.residue_1_kg, rtol=1e-6)
    assert fit.source == "fit" and not fit.same_in_y and np.all(fit.relative_rms_error < 1e-8)


def test_fit_keeps_the_largest_peaks_and_reports_its_misfit():
    """A weak mode (2 % of the largest peak) is left out; a non-proportionally damped mode
    (complex residue) cannot be matched by a real mode, and the misfit says by how much."""
    f = np.arange(100.0, 3000.0, 1.0)
    w = 2 * np.pi * f
    h = XY.receptance(f, 0)
    weak = ModalModel.of([2500.0], [0.02], [0.2], [0]).receptance(f, 0)
    assert np.abs(weak).max() < 0.05 * np.abs(h).max()
    fit = fit_modal_model(f, h + weak, modes_per_direction=3)
    assert fit.n_modes == 4 and fit.same_in_y  # 2 modes, copied to y
    left = fit.to_dict()["omitted_modes"]
    assert [o["direction"] for o in left] == ["x", "y"]  # its |h| peak, moved by the 1 400 Hz tail
    assert all(abs(o["frequency_hz"] / 2500.0 - 1) < 0.02 for o in left)
    assert 0.01 < left[0]["peak_fraction"] < MIN_PEAK_FRACTION
    one = fit_modal_model(f, h, modes_per_direction=1)  # keeps 1 400 Hz, the larger |h| peak
    assert one.frequency_hz[0] == pytest.approx(1400.0) and one.omitted[0][1] == pytest.approx(600.0, abs=5)
    wn = 2 * np.pi * 600.0
    complex_mode = (0.5 + 0.3j * 0.5 * w / wn) / (wn**2 - w**2 + 2j * 0.03 * wn * w)
    fit = fit_modal_model(f, complex_mode, modes_per_direction=1)
    assert 1e-3 < fit.relative_rms_error[0] < 0.5
    assert fit.to_dict()["relative_rms_error"]["x"] == pytest.approx(fit.relative_rms_error[0])


def test_fit_without_a_peak_is_refused_and_a_rigid_y_has_no_modes():
    f = np.arange(100.0, 3000.0, 1.0)
    with pytest.raises(InputError) as err:
        fit_modal_model(f, np.full(f.size, -1e-9 + 0j))
    assert err.value.field == "frf_x"
    fit = fit_modal_model(f, XY.receptance(f, 0), np.zeros(f.size, dtype=complex))
    assert set(fit.direction.tolist()) == {0} and not fit.same_in_y


@pytest.mark.parametrize(("field", "values"), [
    ("residue_1_kg", ([900.0], [0.02], [-1.0], [0])),
    ("damping_ratio", ([900.0], [1.5], [1.0], [0])),
    ("direction", ([900.0], [0.02], [1.0], [2])),
    ("frequency_hz", ([np.nan], [0.02], [1.0], [0])),
])
def test_modal_model_is_validated(field, values):
    with pytest.raises(InputError) as err:
        ModalModel.of(*values)
    assert err.value.field == f"modal_model.{field}"


def test_exact_modes_of_an_assembly_reproduce_its_frf():
    spec = parse_assembly(ra1(GRID))
    prediction = rcsa_app.predict(spec)
    m = modal_model_from_assembly(spec, modes_per_direction=3, frequency_hz=prediction.frequency_hz,
                                  h=prediction.tool_point.h)
    assert m.source == "exact_modes" and m.same_in_y and m.n_modes == 6
    exact = np.asarray(prediction.natural_frequencies_hz)
    for f in m.frequency_hz:  # each fitted mode sits on an exact one (damping shifts it < 0.5 %)
        assert np.min(np.abs(exact / f - 1)) < 5e-3
    assert np.all(m.peak_relative_error < 0.03) and np.all(m.relative_rms_error < 0.05)
    left = {o["frequency_hz"]: o["peak_fraction"] for o in m.to_dict()["omitted_modes"]}
    assert len(left) == exact.size - 3  # every other exact mode in the band is listed
    assert sum(p is not None for p in left.values()) >= 1  # e.g. 1 115 Hz, 14 % of the largest peak


# --------------------------------------------------------------------------- requests


@pytest.mark.parametrize(("body", "field"), [
    ({"method": "sdm"}, "method"),
    ({"method": 1}, "method"),
    ({"steps_per_period": 40}, "steps_per_period"),  # zoa has no steps
    ({"method": "zoa", "modes_per_direction": 2}, "modes_per_direction"),
    ({**SDM, "steps_per_period": 4}, "steps_per_period"),
    ({**SDM, "steps_per_period": 201}, "steps_per_period"),
    ({**SDM, "steps_per_period": 40.0}, "steps_per_period"),
    ({**SDM, "steps_per_period": True}, "steps_per_period"),
    ({**SDM, "modes_per_direction": 0}, "modes_per_direction"),
    ({**SDM, "modes_per_direction": 9}, "modes_per_direction"),
])
def test_method_options_are_validated(body, field):
    with pytest.raises(InputError) as err:
        parse_method(body, teeth=4, radial_immersion=1.0)  # auto: zero-order (exact for 4-tooth slotting)
    assert err.value.field == field


def test_sdm_speed_grid_is_bounded():
    f = np.arange(100.0, 3000.0, 2.0)
    hx = XY.receptance(f, 0)
    frf = {"frequency_hz": f.tolist(), "h": {"real": hx.real.tolist(), "imag": hx.imag.tolist()}}
    body = {"frf_x": frf, **LOBES, "spindle_speed_rpm": {"start": 4000, "stop": 30000, "count": 5001}}
    parse_lobes_request({**body, "method": "zoa"})  # ZOA takes it
    with pytest.raises(InputError) as err:
        parse_lobes_request({**body, **SDM})
    assert err.value.field == "spindle_speed_rpm.count"


def test_method_defaults():
    """No method is auto; the semi-discretization's default steps resolve the cut (None), every mode
    above the threshold is kept (up to the maximum)."""
    assert parse_method({}, teeth=1, radial_immersion=0.05) == parse_method(
        {"method": None}, teeth=1, radial_immersion=0.05)
    assert parse_method({**SDM}) == LobesMethod()
    assert parse_method({**SDM, "steps_per_period": None}).steps_per_period is None
    assert LobesMethod().modes_per_direction == 8
    with pytest.raises(InputError, match="auto"):
        parse_method({})  # auto needs the cut


def test_inline_request_with_sdm_fits_the_modes():
    f = np.arange(100.0, 3000.0, 2.0)
    hx, hy = XY.receptance(f, 0), XY.receptance(f, 1)
    wire = {"frf_x": {"frequency_hz": f.tolist(), "h": {"real": hx.real.tolist(), "imag": hx.imag.tolist()}},
            "frf_y": {"frequency_hz": f.tolist(), "h": {"real": hy.real.tolist(), "imag": hy.imag.tolist()}},
            **LOBES, **SDM, "modes_per_direction": 2, "steps_per_period": 30}
    request = parse_lobes_request(wire)
    assert request.method == LobesMethod("semi_discretization", 30, 2)
    result = request.solve()
    assert isinstance(result, sdm.SemiDiscretizationResult) and result.steps_per_period == 30
    assert result.modal_model.source == "fit" and not result.same_frf_in_y
    direct = lobes(XY, teeth=4, immersion=0.5, speeds=request.spindle_speed_rpm, steps_per_period=30)
    np.testing.assert_allclose(result.depth_limit_m, direct.depth_limit_m, rtol=2e-3)
    zoa = parse_lobes_request({**{k: v for k, v in wire.items() if k not in SDM and "per" not in k},
                               "method": "zoa"}).solve()
    assert not isinstance(zoa, sdm.SemiDiscretizationResult)


@pytest.fixture(scope="module")
def sdm_response():
    return rcsa_app.stability_lobes({"assembly": ra1(GRID), **LOBES, **SDM, "modes_per_direction": 2})


def test_rest_path(tmp_path, sdm_response):
    body = {"assembly": ra1(GRID), **LOBES, **SDM, "modes_per_direction": 2}
    with TestClient(create_app(settings_for(tmp_path / "store"))) as client:
        r = client.post("/v1/stability-lobes", json=body, headers=READ)
        assert r.status_code == 200, r.text
        assert r.json() == sdm_response
        assert sdm_response["method"] == "semi_discretization"
        assert sdm_response["modal_model"]["source"] == "exact_modes"
        assert sdm_response["frf_y_source"] == "same_as_x" and len(sdm_response["instability"]) == 40
        png = client.post("/v1/plots/lobes", json=body, headers=READ)
        assert png.status_code == 200 and png.content[:4] == b"\x89PNG"
        assert_problem(client.post("/v1/stability-lobes", json={**body, "steps_per_period": 4}, headers=READ),
                       422, "steps_per_period")
        assert_problem(client.post("/v1/stability-lobes", json={**body, "method": "fancy"}, headers=READ), 422,
                       "method")
        zoa_with_steps = {**body, "method": "zoa", "modes_per_direction": None, "steps_per_period": 40}
        assert_problem(client.post("/v1/stability-lobes", json=zoa_with_steps, headers=READ), 422,
                       "steps_per_period")


def test_cli_path(tmp_path, sdm_response):
    request = tmp_path / "lobes.json"
    request.write_text(json.dumps({"assembly": ra1(GRID), **LOBES, **SDM, "modes_per_direction": 2}))
    result = CliRunner().invoke(cli_app, ["lobes", str(request)])
    assert result.exit_code == 0, result.stderr
    assert json.loads(result.stdout) == json.loads(json.dumps(sdm_response))
    request.write_text(json.dumps({"assembly": ra1(GRID), **LOBES, **SDM, "steps_per_period": 1000}))
    result = CliRunner().invoke(cli_app, ["lobes", str(request)])
    assert result.exit_code == 1 and result.stderr.startswith("error: steps_per_period")


def test_depth_search_scale_is_the_zoa_absolute_limit():
    st, ex = engagement_angles_rad(0.5, "down")
    b_ref = sdm._reference_depth(XY, 4, KT, directional_factors(st, ex, KR))
    f = np.arange(200.0, 3000.0, 0.05)
    z = stability_lobes(f, XY.receptance(f, 0), XY.receptance(f, 1), teeth=4, tangential_coefficient_n_m2=KT,
                        radial_ratio=KR, radial_immersion=0.5, milling="down", spindle_speed_rpm=[10000.0])
    assert math.isclose(b_ref, z.min_depth_limit_m, rel_tol=2e-3)


@pytest.mark.parametrize(("change", "field"), [
    ({"teeth": 0}, "teeth"), ({"teeth": 2.0}, "teeth"), ({"steps_per_period": 7}, "steps_per_period"),
    ({"tangential_coefficient_n_m2": -1.0}, "tangential_coefficient_n_m2"), ({"radial_ratio": np.nan}, "radial_ratio"),
    ({"spindle_speed_rpm": [0.0, 1000.0]}, "spindle_speed_rpm"), ({"radial_immersion": 1.5}, "radial_immersion"),
    ({"milling": "climb"}, "milling"),
])
def test_python_api_checks_its_arguments(change, field):
    args = {"teeth": 2, "tangential_coefficient_n_m2": KT, "radial_ratio": KR, "radial_immersion": 0.5,
            "milling": "down", "spindle_speed_rpm": [10000.0], **change}
    with pytest.raises(InputError) as err:
        sdm.semi_discretization_lobes(XY, **args)
    assert err.value.field == field


def test_the_callers_speed_array_stays_writable():
    speeds = np.array([10000.0, 12000.0])
    lobes(speeds=speeds)
    speeds[0] = 1.0

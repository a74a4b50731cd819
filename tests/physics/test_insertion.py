"""The shank inside the holder nose as two beams on a distributed interface (rcsa.physics.insertion).

Oracles: its two limits (no interface: two independent beams, exactly; an ever stiffer one:
the composite section), reciprocity, SciPy's matrix exponential, the exact unit stiffness
behind the interpolant, and the independent Timoshenko finite-element model of
``tests/oracles`` (its ``holder_tool_distributed`` effect: the inserted core a separate beam on
springs per unit length), which converges onto the exact item at second order.
"""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg

import rcsa.model.clamping as clamping
from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.chain import undamped
from rcsa.physics.elimination import tip_receptance
from rcsa.physics.insertion import (
    INTERPOLATION_RTOL,
    Insertion,
    InsertionPiece,
    expm_stack,
    insertion_fit,
    piece_fit,
    piece_stiffness,
    unit_stiffness,
)
from rcsa.physics.materials import BUILTIN_MATERIALS
from rcsa.physics.natural_frequencies import natural_frequencies_hz
from rcsa.physics.sections import composite, tube
from rcsa.physics.segments import dynamic_stiffness
from tests.oracles.fe_assembly import natural_frequencies_hz as fe_natural_frequencies_hz
from tests.oracles.fe_assembly import tool_point_receptance as fe_tool_point_receptance

STEEL, CARBIDE = BUILTIN_MATERIALS["steel"], BUILTIN_MATERIALS["carbide"]
NOSE = tube(0.026, 0.010, STEEL)
SHANK = tube(0.010, 0.0, CARBIDE)
OMEGA = 2 * np.pi * np.array([10.0, 500.0, 2000.0, 6000.0, 15000.0])
HOLDER_DOFS, TOOL_DOFS = [0, 1, 4, 5], [2, 3, 6, 7]


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def test_without_interface_the_two_beams_are_independent():
    d = piece_stiffness(OMEGA, InsertionPiece(NOSE, SHANK, 0.04, 0.0, 0.0))
    assert _rel(d[:, HOLDER_DOFS][:, :, HOLDER_DOFS], dynamic_stiffness(OMEGA, NOSE, 0.04)) < 1e-12
    assert _rel(d[:, TOOL_DOFS][:, :, TOOL_DOFS], dynamic_stiffness(OMEGA, SHANK, 0.04)) < 1e-12
    assert np.max(np.abs(d[:, HOLDER_DOFS][:, :, TOOL_DOFS])) == 0.0


def test_an_ever_stiffer_interface_tends_to_the_composite_section():
    target = dynamic_stiffness(OMEGA, composite(NOSE, SHANK), 0.04)
    errors = [_rel(Insertion((InsertionPiece(NOSE, SHANK, 0.04, k, 1e-4 * k),)).two_port(OMEGA), target)
              for k in (1e12, 1e14, 1e16)]
    assert errors[0] > errors[1] > errors[2] and errors[2] < 0.02, errors


def test_dynamic_stiffness_is_symmetric_and_the_exponential_is_scipys():
    a = np.random.default_rng(1).normal(size=(50, 8, 8)) * 3 + 1j * np.random.default_rng(2).normal(size=(50, 8, 8))
    assert _rel(expm_stack(a), scipy.linalg.expm(a)) < 1e-12
    d = unit_stiffness(OMEGA, InsertionPiece(NOSE, SHANK, 0.05, 3e11 * (1 + 0.01j), 1e7))
    raw = d  # unit_stiffness symmetrises only the pieces: the joined matrix must stay symmetric
    assert _rel(raw, np.swapaxes(raw, -1, -2)) < 1e-10


def test_the_interpolant_reproduces_the_exact_stiffness_between_its_nodes():
    piece = InsertionPiece(NOSE, SHANK, 0.035, 4e11 * (1 + 0.002j), 2e7)
    fit = piece_fit(piece, 2 * np.pi * 8000.0)
    assert fit.interpolant is not None
    w = np.sort(np.random.default_rng(3).uniform(0.0, fit.omega_fit_rad_s, 40))
    exact, approx = unit_stiffness(w, fit.unit), fit.stiffness(w)
    scale = np.abs(exact).reshape(-1, 4, 2, 4, 2).max(axis=(0, 2, 4))
    err = np.abs(approx - exact).reshape(-1, 4, 2, 4, 2).max(axis=(0, 2, 4))
    assert np.all(err <= 10 * INTERPOLATION_RTOL * scale)


def _uniform(model, interface: complex, rotational: complex):
    """The model with the same interface on every piece of its insertion (the FE oracle takes one)."""
    ins = model.holder[-1]
    assert isinstance(ins, Insertion)
    pieces = tuple(replace(p, interface_n_m2=interface, interface_rotational_n=rotational) for p in ins.pieces)
    return replace(model, holder=(*model.holder[:-1], Insertion(pieces)))


#: A short assembly (so the dense FE eigensolver stays cheap): a stub spindle on two bearings, a
#: two-step holder whose nose holds the Ø10 carbide shank over 40 mm, 40 mm of stickout.
COMPACT = {
    "frequency": {"start_hz": 100.0, "stop_hz": 8000.0, "step_hz": 40.0},
    "spindle": {"segments": [{"length_m": 0.08, "outer_diameter_m": 0.06, "material": "steel"}],
                "bearings": [{"position_m": 0.01, "stiffness_n_m": 4e8, "damping_ns_m": 2000.0},
                             {"position_m": 0.07, "stiffness_n_m": 2e8, "damping_ns_m": 1000.0}]},
    "holder": {"segments": [{"length_m": 0.02, "outer_diameter_m": 0.05, "inner_diameter_m": 0.01, "material": "steel"},
                            {"length_m": 0.04, "outer_diameter_m": 0.026, "inner_diameter_m": 0.01,
                             "material": "steel"}]},
    "tool": {"material": "carbide", "diameter_m": 0.01, "shank_diameter_m": 0.01, "overall_length_m": 0.08,
             "flute_length_m": 0.02, "stickout_m": 0.04},
    "joints": {"holder_tool": {"model": "bonded"}},
}


@pytest.fixture
def compact_bonded(monkeypatch):
    """The compact assembly as the FE oracle has it: its holder steps without the stiffness cone, the
    holder's sections with Timoshenko's κGA, and the annulus around the shank shearing as the hollow
    tube it is (the oracle's beams are plain Timoshenko sections)."""
    monkeypatch.setattr(clamping, "BULK_COEFFICIENTS", replace(clamping.BULK_COEFFICIENTS, step_cone=0.0,
                                                                     holder_shear=1.0))
    annulus = clamping._annulus
    monkeypatch.setattr(clamping, "_annulus", lambda *a, filled=False, **k: annulus(*a, **k))
    spec = parse_assembly(COMPACT)
    fe_doc = copy.deepcopy(COMPACT)
    fe_doc["joints"].pop("holder_tool")
    return spec, fe_doc


def test_the_exact_item_is_the_limit_of_the_independent_fe_model(compact_bonded):
    """2nd-order convergence of the FE model onto the exact insertion (uniform interface).

    The error is the largest over the band relative to the peak: lightly damped peaks make it
    large on coarse meshes (a shifted resonance), so the test asks for the rate (×4 per halving)
    and a small error at the finest mesh."""
    spec, fe_doc = compact_bonded
    kw, kr = 3.0e11 * (1 + 0.01j), 1.1e7 * (1 + 0.01j)
    h = tip_receptance(_uniform(build_model(spec), kw, kr).chain(), 2 * np.pi * spec.frequency_hz)[:, 0, 0]
    effect = {"holder_tool_distributed": {"translational_stiffness_n_m2": kw.real, "rotational_stiffness_nm_rad_m":
                                          kr.real, "loss_factor": 0.01}}
    errors = [max(_rel(fe_tool_point_receptance(fe_doc, spec.frequency_hz, effects=effect,
                                                max_element_length_m=h_m)[:, 0, 0], h), 1e-16)
              for h_m in (0.001, 0.0005)]
    assert errors[1] < 1e-2 and 3.0 < errors[0] / errors[1] < 5.0, errors


@pytest.mark.slow
def test_natural_frequencies_count_the_insertions_internal_pivots(compact_bonded):
    """Wittrick–Williams through the condensed insertion = the FE model's eigenvalues (1 mm mesh:
    converged to ~1e-4, second order, so 3e-4 tests the count and the exact roots, not the mesh)."""
    spec, fe_doc = compact_bonded
    kw, kr = 2.5e11, 8.0e6
    chain = undamped(_uniform(build_model(spec), kw, kr).chain())
    exact = natural_frequencies_hz(chain, 100.0, 8000.0)
    effect = {"holder_tool_distributed": {"translational_stiffness_n_m2": kw, "rotational_stiffness_nm_rad_m": kr}}
    fe = fe_natural_frequencies_hz(fe_doc, 8000.0, effects=effect, max_element_length_m=0.001)
    fe = fe[fe >= 100.0]
    assert exact.size == fe.size >= 2 and np.max(np.abs(exact / fe - 1.0)) < 3e-4, (exact, fe)


def test_stacked_insertions_give_each_tools_own_two_port():
    pieces = [InsertionPiece(NOSE, SHANK, length, k, 1e7) for length, k in ((0.03, 2e11), (0.045, 5e11))]
    items = [Insertion((p,)) for p in pieces]
    stacked = items[0].stack(items)
    rows = np.array([0, 1, 1, 0, 1])
    w = 2 * np.pi * np.array([100.0, 700.0, 2500.0, 4000.0, 9000.0])
    got = stacked.take_rows(rows).two_port(w)
    for line, row in enumerate(rows):
        assert _rel(got[line], items[row].two_port(w[line:line + 1])[0]) < 1e-12


def test_the_whole_insertions_interpolant_is_its_exact_condensation(compact_bonded):
    """Below its own clamped modes an insertion is evaluated whole; it equals the line-by-line
    condensation of exact units, at frequencies between the interpolation nodes."""
    spec, _ = compact_bonded
    ins = build_model(spec).holder[-1]
    w = 2 * np.pi * np.sort(np.random.default_rng(4).uniform(1.0, 8000.0, 60))
    assert insertion_fit(ins, float(w.max())) is not None
    exact = ins.condensed(w, exact=True)
    assert _rel(ins.two_port(w), exact) < 1e-8

"""The 3-D reference data set in ``tests/data/solid3d`` is complete, well formed and still what the code computes.

The full computation is ``benchmarks/bench_solid3d.py --write-data``; here the base case is
recomputed on a mesh twice as coarse (a few seconds) and must land within the benchmark's
convergence estimate of the stored tool mode (the 2-level convergence check of the suite).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.oracles.solid3d.dataset import (
    BASES,
    DATA_DIR,
    FREQUENCY_HZ,
    load_case,
    load_reduced,
    reference_cases,
    spindle_base_receptance,
    with_mesh,
)
from tests.oracles.solid3d.reduction import tip_receptance
from tests.oracles.solid3d.solve import build, largest_peak, solve_model


@pytest.fixture(scope="module")
def index() -> dict:
    return json.loads((DATA_DIR / "cases.json").read_text())


def test_every_case_is_stored_with_its_description_and_figures(index):
    assert set(index["cases"]) == set(reference_cases())
    for name, entry in index["cases"].items():
        assert entry["holder"]["segments"] and entry["tool"]["stickout_m"] > 0, name
        # a family's reference case reuses its convergence sequence's model: the stored data set says 0 s
        # for it (bench_solid3d now adds the reused model's build time)
        assert entry["n_dof"] > 1000 and entry["wall_s"] >= 0, name
        for base in BASES:
            figures = entry["bases"][base]
            assert figures["tool_mode"]["frequency_hz"] > 100.0, (name, base)
            assert 0 <= figures["tool_mode"]["convergence"]["frequency_rel"] < 0.02, (name, base)
    assert index["convergence"]["tool_mode_hz"]["remaining_rel"] < 0.01
    for family, conv in index["convergence_by_family"].items():
        assert conv["tool_mode_hz"]["remaining_rel"] < 0.01, family
    total = sum(p.stat().st_size for p in DATA_DIR.iterdir())
    assert total < 5e6, total


@pytest.mark.parametrize("name", sorted(reference_cases()))
def test_stored_frfs_are_passive_and_peak_where_the_index_says(name, index):
    data = load_case(name)
    assert data["frequency_hz"].shape == FREQUENCY_HZ.shape
    for base in BASES:
        h = data[f"h_{base}"]
        assert h.shape == FREQUENCY_HZ.shape and np.all(np.isfinite(h))
        assert np.all(h.imag <= 1e-6 * np.max(np.abs(h)))            # damped driving point (complex64 noise)
        f, m = largest_peak(data["frequency_hz"], h)
        stored = index["cases"][name]["bases"][base]["largest_peak"]
        assert f == pytest.approx(stored["frequency_hz"], rel=1e-4)
        assert m == pytest.approx(stored["magnitude_m_n"], rel=1e-4)


@pytest.mark.parametrize("name", ["base_d10", "sidelock_d16", "collet_d10"])
def test_the_stored_craig_bampton_model_is_the_stored_frf(name):
    """The reduced model (what a diagnosis or a fine peak search evaluates) gives the stored h on both bases."""
    data = load_case(name)
    red = load_reduced(name)
    f = data["frequency_hz"][::50]
    damped, _ = spindle_base_receptance(f)
    for base, stiffness in (("clamped", None), ("spindle", np.linalg.inv(damped))):
        h = tip_receptance(red, 2 * np.pi * f, stiffness)[:, 0, 0]
        stored = data[f"h_{base}"][::50]
        assert np.max(np.abs(h - stored)) <= 1e-6 * np.max(np.abs(stored)), base   # complex64 storage


@pytest.mark.slow
def test_a_coarser_mesh_reproduces_the_stored_base_case_within_its_convergence(index):
    case = reference_cases()["base_d10"][0]
    factor = 2.0
    frf = solve_model(build(with_mesh(case, factor), "clamped", 2.5 * FREQUENCY_HZ[-1]), FREQUENCY_HZ, "clamped")
    f_coarse, _ = largest_peak(FREQUENCY_HZ, frf.h)
    stored = index["cases"]["base_d10"]["bases"]["clamped"]["tool_mode"]
    conv = index["convergence"]["tool_mode_hz"]
    # the error of a mesh `factor` times coarser, by the observed order, plus the stored mesh's own
    expected = stored["frequency_hz"] * conv["remaining_rel"] * (factor ** conv["order"] - 1)
    assert f_coarse >= stored["frequency_hz"]                        # refinement lowers it (stiff P2 error)
    assert f_coarse - stored["frequency_hz"] < 2.0 * expected + 1e-3 * stored["frequency_hz"]

"""The base coupling, the tip loads, the interface and the reduction of the 3-D reference.

* A steel rod on RA-1's spindle (the spindle and its spindle–holder joint condensed to a
  2×2 receptance at the gauge line by rcsa) against rcsa's exact chain on the same base:
  the coupled natural frequencies agree within 0.5 %, and turning the sign of the base's
  rotation (l, n → −l, −n) moves them by far more — the sign convention is checked.
* Tip loads: a unit force, a unit moment, reciprocity, a damped driving point.
* The spring layer's matrix against its closed form for a rigid jump; a stiff layer tends
  to the bonded interface, a soft one lowers the tool mode.
* Craig–Bampton against the direct sparse complex solve.
"""

from __future__ import annotations

import numpy as np
import pytest
from skfem import Basis, ElementTetP2, FacetBasis, MeshTet2

from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.chain import Beam
from rcsa.physics.elimination import tip_receptance as rcsa_tip_receptance
from rcsa.physics.materials import Material
from rcsa.physics.natural_frequencies import natural_frequencies_hz
from rcsa.physics.sections import tube
from rcsa.reference import ra1
from tests.oracles.solid3d.assembly import layer_matrix, tip_loads
from tests.oracles.solid3d.case import (
    STEEL,
    HolderSegment,
    Interface,
    MeshSize,
    SolidCase,
    ToolGeometry,
)
from tests.oracles.solid3d.geometry import Piece, case_pieces, mesh_pieces
from tests.oracles.solid3d.solve import (
    ReceptanceBase,
    build,
    build_body,
    largest_peak,
    solve_model,
    truncation_error,
)

FREQ_HZ = np.arange(100.0, 6001.0, 1.0)
RTOL_THEORY = 5e-3


@pytest.fixture(scope="module")
def spindle_base() -> tuple[np.ndarray, np.ndarray, tuple]:
    chain = build_model(parse_assembly(ra1())).spindle_side()
    omega = 2 * np.pi * FREQ_HZ
    return (rcsa_tip_receptance(chain, omega), rcsa_tip_receptance(tuple(i.undamped() for i in chain), omega),
            chain)


@pytest.fixture(scope="module")
def rod_on_base(spindle_base):
    return build_body((Piece("holder", 0.0, 0.150, 0.040),), (STEEL, STEEL), MeshSize(0.006, 0.006),
                      "elastic", 2.5 * FREQ_HZ[-1])


def test_rod_on_a_spindle_receptance_matches_rcsa_chain_on_the_same_base(spindle_base, rod_on_base):
    damped, undamped, chain = spindle_base
    rod = (Beam(tube(0.040, 0.0, Material(210e9, 0.30, 7850.0, 0.002)), 0.150),)
    exact = natural_frequencies_hz(chain + rod, FREQ_HZ[0], FREQ_HZ[-1])
    frf = solve_model(rod_on_base, FREQ_HZ, ReceptanceBase(FREQ_HZ, damped, undamped))
    assert frf.natural_frequencies_hz is not None and frf.natural_frequencies_hz.size == exact.size
    np.testing.assert_allclose(frf.natural_frequencies_hz, exact, rtol=RTOL_THEORY)
    beam_h = rcsa_tip_receptance(rod, 2 * np.pi * FREQ_HZ, start=np.linalg.inv(damped))[:, 0, 0]
    f3, m3 = largest_peak(FREQ_HZ, frf.h)
    fb, mb = largest_peak(FREQ_HZ, beam_h)
    assert abs(f3 / fb - 1) < RTOL_THEORY and abs(m3 / mb - 1) < 0.03


def test_the_base_rotation_sign_matters(spindle_base, rod_on_base):
    damped, _, _ = spindle_base
    flip = np.diag([1.0, -1.0])
    right = solve_model(rod_on_base, FREQ_HZ, ReceptanceBase(FREQ_HZ, damped)).h
    wrong = solve_model(rod_on_base, FREQ_HZ, ReceptanceBase(FREQ_HZ, flip @ damped @ flip)).h
    assert abs(largest_peak(FREQ_HZ, wrong)[0] / largest_peak(FREQ_HZ, right)[0] - 1) > 0.1


@pytest.fixture(scope="module")
def small_case() -> SolidCase:
    return SolidCase((HolderSegment(0.020, 0.040, 0.010), HolderSegment(0.030, 0.024, 0.010)),
                     ToolGeometry(0.010, 0.010, 0.060, 0.020, 0.035), mesh=MeshSize(0.005, 0.012, 0.8))


@pytest.fixture(scope="module")
def small_model(small_case):
    return build(small_case, "elastic", 2.5 * FREQ_HZ[-1])


def test_tip_loads_are_a_unit_force_and_a_unit_moment(small_case):
    """On rigid motions of the whole face: u_x = 1 reads w = 1, u_z = −θ x reads ψ = θ."""
    mesh = mesh_pieces(case_pieces(small_case), small_case.mesh, True)
    m = MeshTet2(mesh.points_m, mesh.tets)
    loads = tip_loads(m, ElementTetP2(), small_case.tip_z_m, 1e-9, 4)
    xyz = np.repeat(Basis(m, ElementTetP2(), intorder=0).doflocs, 3, axis=1)
    comp = np.arange(loads.shape[0]) % 3
    translation = (comp == 0).astype(float)
    rotation = np.where(comp == 2, -xyz[0], 0.0)
    np.testing.assert_allclose(4 * translation @ loads, [1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(4 * rotation @ loads, [0.0, 1.0], atol=1e-12)


def test_tip_receptance_is_reciprocal_and_damped(small_model):
    frf = solve_model(small_model, FREQ_HZ, "clamped")
    np.testing.assert_allclose(frf.tip[:, 0, 1], frf.tip[:, 1, 0], rtol=1e-9)
    assert np.all(frf.h.imag <= 0)
    assert frf.natural_frequencies_hz is not None and frf.natural_frequencies_hz.size >= 1


@pytest.mark.slow
def test_reduced_model_matches_the_direct_sparse_solve(small_model, spindle_base):
    """Clamped and on the spindle (1e-5 measured on the benchmark's base case)."""
    probe = np.array([900.0, 5900.0])
    assert truncation_error(small_model, probe) < 1e-4
    damped = spindle_base[0][np.searchsorted(FREQ_HZ, probe)]
    assert truncation_error(small_model, probe, ReceptanceBase(probe, damped)) < 1e-4


def test_layer_matrix_of_a_rigid_jump_is_its_closed_form(small_case):
    """Jump [u] = e_x on a quarter cylinder r × l: ∫ k_n n_x² + k_t (1 − n_x²) dA = (k_n + k_t) π r l / 4."""
    kn, kt = 1e14, 0.5e14
    mesh = mesh_pieces(case_pieces(small_case), small_case.mesh, True)
    m = MeshTet2(mesh.points_m, mesh.tets)
    f2t = m.f2t
    between = np.flatnonzero((f2t[1] >= 0) & (mesh.part[f2t[0]] != mesh.part[np.maximum(f2t[1], 0)]))
    lateral = between[np.ptp(m.p[2][m.facets[:, between]], axis=0) > 1e-9]
    n = 3 * Basis(m, ElementTetP2(), intorder=0).N
    a = layer_matrix(FacetBasis(m, ElementTetP2(), facets=lateral, intorder=4), kn, kt, n)
    jump = (np.arange(n) % 3 == 0).astype(float)
    radius, length = small_case.tool.shank_diameter_m / 2, small_case.tool.inserted_length_m
    # the quadratic faces carry the cylinder's area to 4e-4 with 5 mm elements on a Ø10 bore
    assert jump @ (a @ jump) == pytest.approx((kn + kt) * np.pi * radius * length / 4, rel=1e-3)
    assert a.nnz and abs(a - a.T).max() <= 1e-12 * abs(a).max()


@pytest.mark.slow
def test_a_stiff_layer_tends_to_bonding_and_a_soft_one_lowers_the_tool_mode(small_case, small_model):
    bonded = largest_peak(FREQ_HZ, solve_model(small_model, FREQ_HZ).h)[0]
    layer = {}
    for k in (1e13, 1e17):
        case = SolidCase(small_case.holder_segments, small_case.tool, interface=Interface("layer", k),
                         mesh=small_case.mesh)
        layer[k] = largest_peak(FREQ_HZ, solve_model(build(case, "clamped", 2.5 * FREQ_HZ[-1]), FREQ_HZ).h)[0]
    assert layer[1e17] == pytest.approx(bonded, rel=2e-3)
    assert layer[1e13] < 0.97 * bonded
